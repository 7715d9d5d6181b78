//! `scatter-shaderlib`: the WGSL kernels of the scatter library and the pipeline that turns a
//! kernel choice into a validated shader.
//!
//! Every kernel is an askama template (`templates/<kernel>.wgsl`) that may import shared WGSL
//! modules (`templates/common/*.wgsl`, naga_oil `#define_import_path scatter::...`). [`build`]
//! renders the template with the kernel's parameters, composes it with naga_oil, validates it
//! with naga and returns the [`naga::Module`], its [`naga::valid::ModuleInfo`] and WGSL text.
//!
//! Kernels: `row_prefix` ([`RowPrefixParams`]), the prefiltered family (Klehm et al. 2014)
//! `depth_columns`, `slice_fit`, `rectify`, `prefilter`, `scatter`, all five rendered from one
//! [`prefiltered::PrefilteredVariant`] ([`KernelParams::prefiltered`]), and the raymarch family (Tóth &
//! Umenhoffer 2009) `raymarch`, `interleave_sum` from a [`raymarch::RaymarchVariant`]
//! ([`KernelParams::raymarch`]), and the minmax family (Chen et al. 2011) `depth_columns`, `slice_fit`, `rectify`,
//! `minmax_build`, `minmax_traverse` from a [`minmax::MinmaxVariant`] ([`KernelParams::minmax`]).
//!
//! ```
//! use scatter_shaderlib::{build, KernelParams, RowPrefixMode, RowPrefixParams};
//!
//! let built = build(&KernelParams::RowPrefix(RowPrefixParams {
//!     mode: RowPrefixMode::Mean,
//!     ..RowPrefixParams::default()
//! }))?;
//! assert_eq!(built.entry_point, "row_prefix");
//! assert_eq!(built.workgroup_size, [64, 1, 1]);
//! # Ok::<(), scatter_shaderlib::ShaderError>(())
//! ```

pub mod area_ivsv;
mod compose;
mod error;
pub mod family;
pub mod hybrid_volume;
mod kernel;
pub mod minmax;
pub mod partial_sum_tree;
pub mod plan;
pub mod prefiltered;
pub mod raymarch;
pub mod reflect;
pub mod row_prefix;
pub mod sampling;
pub mod uniform_branches;

use area_ivsv::AreaIvsvVariant;
pub use compose::capabilities;
pub use error::ShaderError;
use family::{Family, KernelFamily};
use hybrid_volume::HybridVolumeVariant;
use minmax::MinmaxVariant;
use partial_sum_tree::PartialSumTreeVariant;
use prefiltered::PrefilteredVariant;
use raymarch::RaymarchVariant;
pub use row_prefix::{RowPrefixMode, RowPrefixParams};
pub use scatter_frame::cookie;

// The kernel table: one line per kernel (name, template stem, parameter type, render
// function), sorted by name. `Kernel`, `KernelParams` and `render` come from it.
kernel::kernels! {
    /// The deepest pixel of every depth-buffer row (the epipolar families' first pass, for
    /// `slice_fit`).
    DepthColumns("depth_columns", PrefilteredVariant, prefiltered::kernels::render_depth_columns),
    /// Separable sum filter of interleaved sampling over the `raymarch` partial sums (Tóth &
    /// Umenhoffer 2009).
    InterleaveSum("interleave_sum", RaymarchVariant, raymarch::render_interleave_sum),
    /// area_ivsv: per pixel, the lit integral of every VPL from its voxel bits (Wyman & Dai
    /// 2013).
    IvsvGather("ivsv_gather", AreaIvsvVariant, area_ivsv::render_gather),
    /// `sampling = epipolar`: the pixels `ivsv_gather_unwarp` listed (no sample stands for
    /// them), gathered themselves.
    IvsvGatherFallback("ivsv_gather_fallback", AreaIvsvVariant, area_ivsv::render_gather_fallback),
    /// `sampling = epipolar`: every pixel gathered from the `ivsv_gather` samples of the two
    /// slices around it, or listed for `ivsv_gather_fallback` where none stands for it.
    IvsvGatherUnwarp("ivsv_gather_unwarp", AreaIvsvVariant, area_ivsv::render_gather_unwarp),
    /// area_ivsv, interleaved gather: the sum of each pixel's window of partial sums.
    IvsvInterleaveSum("ivsv_interleave_sum", AreaIvsvVariant, area_ivsv::render_interleave_sum),
    /// area_ivsv: per VPL and epipolar light ray, the voxel where its shadow starts.
    IvsvRectify("ivsv_rectify", AreaIvsvVariant, area_ivsv::render_rectify),
    /// area_ivsv: the extrusion of the marked voxels, an OR scan along alpha.
    IvsvScan("ivsv_scan", AreaIvsvVariant, area_ivsv::render_scan),
    /// The 1D min-max tree of every rectified row (Chen et al. 2011).
    MinmaxBuild("minmax_build", MinmaxVariant, minmax::render_build),
    /// Per pixel: the rectified row marched through its min-max tree, skipping nodes wholly
    /// lit or shadowed; pixels near the epipole ray-marched (Chen et al. 2011).
    MinmaxTraverse("minmax_traverse", MinmaxVariant, minmax::render_traverse),
    /// `sampling = epipolar`: the pixels `minmax_traverse_unwarp` listed (no sample stands
    /// for them), traversed themselves.
    MinmaxTraverseFallback("minmax_traverse_fallback", MinmaxVariant, minmax::render_traverse_fallback),
    /// `sampling = epipolar`: every pixel gathered from the `minmax_traverse` samples of
    /// the two slices around it, or listed for `minmax_traverse_fallback` where none stands
    /// for it.
    MinmaxTraverseUnwarp("minmax_traverse_unwarp", MinmaxVariant, minmax::render_traverse_unwarp),
    /// Fourier basis transform fused with the weighted running mean along each rectified
    /// row, per region (Klehm et al. 2014, Listings 1-3, Table 1).
    Prefilter("prefilter", PrefilteredVariant, prefiltered::kernels::render_prefilter),
    /// Per epipolar slice: every sample answered by one sweep through a partial-sum
    /// (Fenwick) tree of a rank-r separable integrand over the slice's rectified row;
    /// samples near the epipole ray-marched (Baran et al. 2010).
    PstSweep("pst_sweep", PartialSumTreeVariant, partial_sum_tree::render_sweep),
    /// The pixels `pst_sweep_unwarp` listed (no sample stands for them), each summed over
    /// its own row's lit columns without the tree.
    PstSweepFallback("pst_sweep_fallback", PartialSumTreeVariant, partial_sum_tree::render_sweep_fallback),
    /// Every pixel gathered from the `pst_sweep` samples of the two slices around it, or
    /// listed for `pst_sweep_fallback` where none stands for it.
    PstSweepUnwarp("pst_sweep_unwarp", PartialSumTreeVariant, partial_sum_tree::render_sweep_unwarp),
    /// Brute-force ray marching through the standard shadow map, optionally interleaved
    /// (Tóth & Umenhoffer 2009).
    Raymarch("raymarch", RaymarchVariant, raymarch::render_raymarch),
    /// `sampling = epipolar`: the pixels `raymarch_unwarp` listed (no sample stands for
    /// them), marched themselves.
    RaymarchFallback("raymarch_fallback", RaymarchVariant, raymarch::render_raymarch_fallback),
    /// `sampling = epipolar`: every pixel gathered from the `raymarch` samples of the two
    /// slices around it, or listed for `raymarch_fallback` where none stands for it.
    RaymarchUnwarp("raymarch_unwarp", RaymarchVariant, raymarch::render_raymarch_unwarp),
    /// Epipolar resampling of a standard shadow map into the rectified shadow map (Klehm et
    /// al. 2014, Sec. 4.1, after Baran et al. 2010).
    Rectify("rectify", PrefilteredVariant, prefiltered::kernels::render_rectify),
    /// Per-row running prefix (sum or mean) over an rgba texture array; the filtering step
    /// of the prefiltered method (Klehm et al. 2014, Listing 1).
    RowPrefix("row_prefix", RowPrefixParams, row_prefix::render),
    /// Per pixel: prefiltered visibility times the unshadowed integral, one dot product per
    /// region; pixels near the epipole ray-marched (Klehm et al. 2014, Listing 4, Sec. 5).
    Scatter("scatter", PrefilteredVariant, prefiltered::kernels::render_scatter),
    /// `sampling = epipolar`: the pixels `scatter_unwarp` listed (no sample stands for
    /// them), evaluated themselves.
    ScatterFallback("scatter_fallback", PrefilteredVariant, prefiltered::kernels::render_scatter_fallback),
    /// `sampling = epipolar`: every pixel gathered from the `scatter` samples of the two
    /// slices around it, or listed for `scatter_fallback` where none stands for it.
    ScatterUnwarp("scatter_unwarp", PrefilteredVariant, prefiltered::kernels::render_scatter_unwarp),
    /// Every rectified row's column spacing fitted to the deepest pixel of the depth buffer
    /// (after `depth_columns`; the host spans rows to the far plane).
    SliceFit("slice_fit", PrefilteredVariant, prefiltered::kernels::render_slice_fit),
    /// The shadow volume's boundary crossings of every rectified row, binned by ray depth:
    /// first and last column edge per bin (Wyman & Ramsey 2008, rasterised per slice).
    VolumeBounds("volume_bounds", HybridVolumeVariant, hybrid_volume::render_bounds),
    /// Per pixel: only the interval between the first and last shadow-volume crossing
    /// ray-marched, head and tail in closed form; pixels near the epipole marched whole
    /// (Wyman & Ramsey 2008).
    VolumeMarch("volume_march", HybridVolumeVariant, hybrid_volume::render_march),
    /// `sampling = epipolar`: the pixels `volume_march_unwarp` listed (no sample stands for
    /// them), marched themselves.
    VolumeMarchFallback("volume_march_fallback", HybridVolumeVariant, hybrid_volume::render_march_fallback),
    /// `sampling = epipolar`: every pixel gathered from the `volume_march` samples of the
    /// two slices around it, or listed for `volume_march_fallback` where none stands for it.
    VolumeMarchUnwarp("volume_march_unwarp", HybridVolumeVariant, hybrid_volume::render_march_unwarp),
}

impl KernelParams {
    /// Every parameter set the conformance suite checks: `row_prefix` in each of its
    /// modes (default workgroup size), then every family's kernels for its variant with the
    /// most passes and its default with epipolar sampling, each kernel once (from the family table: a new family needs no line here).
    pub fn all_modes() -> Vec<Self> {
        let mut out: Vec<Self> = RowPrefixMode::ALL
            .iter()
            .map(|&mode| {
                Self::RowPrefix(RowPrefixParams {
                    mode,
                    ..RowPrefixParams::default()
                })
            })
            .collect();
        for &family in Family::ALL {
            // The variant with the most passes, then the default with epipolar sampling
            // (its `_unwarp` and `_fallback` kernels).
            let epipolar =
                family
                    .default_variant()
                    .with_sampling(sampling::SamplingKnobs::epipolar(
                        sampling::SamplingKnobs::DEFAULT_SLICES,
                    ));
            for params in family::most_passes(family)
                .kernel_params()
                .into_iter()
                .chain(
                    // A family without epipolar sampling would refuse the variant.
                    epipolar
                        .validate()
                        .map(|()| epipolar.kernel_params())
                        .unwrap_or_default(),
                )
            {
                if !out.iter().any(|p| p.kernel() == params.kernel()) {
                    out.push(params);
                }
            }
        }
        out
    }
}

/// A rendered, composed and validated kernel.
#[derive(Debug, Clone)]
pub struct BuiltKernel {
    /// Which kernel this is.
    pub kernel: Kernel,
    /// The parameters it was rendered with.
    pub params: KernelParams,
    /// Name of the compute entry point (the kernel's name).
    pub entry_point: &'static str,
    /// Workgroup size, read back from the naga IR.
    pub workgroup_size: [u32; 3],
    /// The composed module (imported names are mangled by naga_oil).
    pub module: naga::Module,
    /// Validation info for [`Self::module`], needed by naga's back-ends.
    pub info: naga::valid::ModuleInfo,
    /// The module written back as WGSL by naga's WGSL back-end.
    pub wgsl: String,
}

/// Renders, composes and validates one kernel.
///
/// # Errors
///
/// [`ShaderError`] naming the kernel when a parameter is out of range or a stage of the
/// pipeline (render, compose, validate, write WGSL) fails.
pub fn build(params: &KernelParams) -> Result<BuiltKernel, ShaderError> {
    let kernel = params.kernel();
    let source = render(params)?;
    let module = compose::compose(kernel, &source)?;
    let info = compose::validate(kernel, &module)?;
    let wgsl =
        naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty())
            .map_err(|source| ShaderError::WriteWgsl { kernel, source })?;
    let entry_point = kernel.name();
    let workgroup_size = module
        .entry_points
        .iter()
        .find(|ep| ep.name == entry_point)
        .map(|ep| ep.workgroup_size)
        .ok_or(ShaderError::MissingEntryPoint {
            kernel,
            entry_point,
        })?;
    Ok(BuiltKernel {
        kernel,
        params: *params,
        entry_point,
        workgroup_size,
        module,
        info,
        wgsl,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kernel_and_mode_validates() {
        for params in KernelParams::all_modes() {
            let built = build(&params).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(built.entry_point, params.kernel().name());
            let entry = format!("fn {}", params.kernel().name());
            assert!(built.wgsl.contains(&entry), "{}", built.wgsl);
        }
    }

    #[test]
    fn params_round_trip_through_serde_names() {
        assert_eq!(Kernel::RowPrefix.name(), "row_prefix");
        assert_eq!(RowPrefixMode::Sum.name(), "sum");
        assert_eq!(RowPrefixMode::Mean.name(), "mean");
    }
}
