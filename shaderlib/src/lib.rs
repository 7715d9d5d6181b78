//! `scatter-shaderlib`: the WGSL kernels of the scatter library and the pipeline that turns a
//! kernel choice into a validated shader.
//!
//! Every kernel is an askama template (`templates/<kernel>.wgsl`) that may import shared WGSL
//! modules (`templates/common/*.wgsl`, naga_oil `#define_import_path scatter::...`). [`build`]
//! renders the template with the kernel's parameters, composes it with naga_oil, validates it
//! with naga and returns the [`naga::Module`], its [`naga::valid::ModuleInfo`] and WGSL text.
//!
//! Kernels: `row_prefix` ([`RowPrefixParams`]), the prefiltered family (Klehm et al. 2014)
//! `rectify`, `prefilter`, `scatter`, all three rendered from one
//! [`prefiltered::PrefilteredVariant`] ([`KernelParams::prefiltered`]), and the raymarch family (Tóth &
//! Umenhoffer 2009) `raymarch`, `interleave_sum` from a [`raymarch::RaymarchVariant`]
//! ([`KernelParams::raymarch`]), and the minmax family (Chen et al. 2011) `rectify`,
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

mod compose;
mod error;
pub mod family;
mod kernel;
pub mod minmax;
pub mod plan;
pub mod prefiltered;
pub mod raymarch;
pub mod reflect;
pub mod row_prefix;

pub use error::ShaderError;
pub use kernel::Kernel;
use minmax::MinmaxVariant;
use prefiltered::PrefilteredVariant;
use raymarch::RaymarchVariant;
pub use row_prefix::{RowPrefixMode, RowPrefixParams};

/// A kernel together with the template parameters it is rendered with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kernel", rename_all = "snake_case")]
pub enum KernelParams {
    /// [`Kernel::InterleaveSum`] of an interleaved raymarch-family variant (the code does
    /// not depend on the variant).
    InterleaveSum(RaymarchVariant),
    /// [`Kernel::MinmaxBuild`] of a minmax-family variant (the code does not depend on it).
    MinmaxBuild(MinmaxVariant),
    /// [`Kernel::MinmaxTraverse`] of a minmax-family variant (only `light` changes the code).
    MinmaxTraverse(MinmaxVariant),
    /// [`Kernel::Prefilter`] of a prefiltered-family variant.
    Prefilter(PrefilteredVariant),
    /// [`Kernel::Raymarch`] of a raymarch-family variant (only `light` and whether it
    /// interleaves change the code).
    Raymarch(RaymarchVariant),
    /// [`Kernel::Rectify`] of a prefiltered-family variant (only `light` changes the code).
    Rectify(PrefilteredVariant),
    /// [`Kernel::RowPrefix`]: per-row running sum or mean.
    RowPrefix(RowPrefixParams),
    /// [`Kernel::Scatter`] of a prefiltered-family variant (`bases_per_thread` and `storage`
    /// do not change the code).
    Scatter(PrefilteredVariant),
}

impl KernelParams {
    /// The kernel these parameters belong to.
    pub fn kernel(&self) -> Kernel {
        match self {
            Self::InterleaveSum(_) => Kernel::InterleaveSum,
            Self::MinmaxBuild(_) => Kernel::MinmaxBuild,
            Self::MinmaxTraverse(_) => Kernel::MinmaxTraverse,
            Self::Prefilter(_) => Kernel::Prefilter,
            Self::Raymarch(_) => Kernel::Raymarch,
            Self::Rectify(_) => Kernel::Rectify,
            Self::RowPrefix(_) => Kernel::RowPrefix,
            Self::Scatter(_) => Kernel::Scatter,
        }
    }

    /// The three kernels of a prefiltered-family variant, in pass order: `rectify`,
    /// `prefilter`, `scatter`.
    pub const fn prefiltered(variant: PrefilteredVariant) -> [Self; 3] {
        [
            Self::Rectify(variant),
            Self::Prefilter(variant),
            Self::Scatter(variant),
        ]
    }

    /// The kernels of a raymarch-family variant, in pass order: `raymarch`, then
    /// `interleave_sum` when it interleaves.
    pub fn raymarch(variant: RaymarchVariant) -> Vec<Self> {
        let mut out = vec![Self::Raymarch(variant)];
        if variant.interleaved() {
            out.push(Self::InterleaveSum(variant));
        }
        out
    }

    /// The kernels of a minmax-family variant, in pass order: the prefiltered family's
    /// `rectify` (of [`MinmaxVariant::prefiltered`]), `minmax_build`, `minmax_traverse`.
    pub fn minmax(variant: MinmaxVariant) -> [Self; 3] {
        [
            Self::Rectify(variant.prefiltered()),
            Self::MinmaxBuild(variant),
            Self::MinmaxTraverse(variant),
        ]
    }

    /// Every parameter set the conformance suite checks: each kernel in each of its modes,
    /// with default workgroup sizes, then the prefiltered kernels of the default
    /// [`PrefilteredVariant`].
    pub fn all_modes() -> Vec<Self> {
        RowPrefixMode::ALL
            .iter()
            .map(|&mode| {
                Self::RowPrefix(RowPrefixParams {
                    mode,
                    ..RowPrefixParams::default()
                })
            })
            .chain(Self::prefiltered(PrefilteredVariant::default()))
            .chain(Self::raymarch(RaymarchVariant {
                interleave: 2,
                ..RaymarchVariant::default()
            }))
            .chain(Self::minmax(MinmaxVariant::default()).into_iter().skip(1))
            .collect()
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

/// Renders a kernel's askama template to WGSL source that still contains naga_oil
/// `#import` directives (the input of composition).
///
/// # Errors
///
/// [`ShaderError::InvalidParameter`] or [`ShaderError::Variant`] for out-of-range
/// parameters, [`ShaderError::Render`] when askama fails.
pub fn render(params: &KernelParams) -> Result<String, ShaderError> {
    match params {
        KernelParams::InterleaveSum(v) => raymarch::render_interleave_sum(v),
        KernelParams::MinmaxBuild(v) => minmax::render_build(v),
        KernelParams::MinmaxTraverse(v) => minmax::render_traverse(v),
        KernelParams::Prefilter(v) => prefiltered::kernels::render_prefilter(v),
        KernelParams::Raymarch(v) => raymarch::render_raymarch(v),
        KernelParams::Rectify(v) => prefiltered::kernels::render_rectify(v),
        KernelParams::RowPrefix(p) => row_prefix::render(p),
        KernelParams::Scatter(v) => prefiltered::kernels::render_scatter(v),
    }
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
