//! The `partial_sum_tree` family (Baran et al. 2010): the askama views of
//! `templates/pst_sweep.wgsl` (and its `_unwarp` and `_fallback` renderings) from a
//! [`PartialSumTreeVariant`]. The family's first passes are the shared `depth_columns`,
//! `slice_fit` and `rectify` ([`crate::KernelParams::partial_sum_tree`] lists them with
//! [`PartialSumTreeVariant::prefiltered`]). CPU mirrors:
//! `reference/src/kernels/{pst_sweep,pst_sweep_unwarp,pst_sweep_fallback}.rs`. Host-side knobs,
//! the separable integrand and the frame set-up: [`scatter_frame::partial_sum_tree`]
//! (re-exported here).

pub mod plan;

use askama::Template;

use crate::sampling::{SamplingView, camera_expr};

pub use scatter_frame::partial_sum_tree::{
    DEFAULT_RANK, FACTOR_VECS, GL2, GRID, MAX_RANK, PartialSumTreeFrame, PartialSumTreeVariant,
    PstError, Separable, TREES, frame_separable, prepare_partial_sum_tree, query_theta_range,
    spot_kernel, svd_jacobi,
};

use crate::compose::template_path;
use crate::prefiltered::LightKind;
use crate::{Kernel, ShaderError};

/// Invocations per slice of `pst_sweep` (the sampling stage's samples pass of the other
/// families takes [`crate::sampling::SLICE_LANES`]): its sweep spreads a slice's columns,
/// ranks and tree steps over them.
pub const SWEEP_LANES: u32 = 32;

/// Workgroup size of `pst_sweep`: one workgroup per epipolar slice.
pub const SWEEP_WORKGROUP_SIZE: [u32; 3] = [SWEEP_LANES, 1, 1];

/// The first binding after the family's own (the sampling stage's `epipolar_samples` in the
/// unwarp; `fallback_count` and `fallback_pixels` at the next two).
pub const SAMPLED_BINDING: u32 = 10;

/// The binding of the engine's `cookie` texture in a `cookie` variant's sweep and fallback:
/// after the sampling stage's (`fallback_pixels` at 12), where the other families bind it at
/// [`crate::plan::COOKIE_BINDING`].
pub const COOKIE_BINDING: u32 = SAMPLED_BINDING + 3;

/// `pst_sweep` and its unwarp and fallback renderings: one view, three templates.
macro_rules! sweep_template {
    ($name:ident, $path:literal) => {
        #[derive(Template)]
        #[template(path = $path)]
        struct $name {
            light_name: &'static str,
            spot: bool,
            rank: u32,
            rank_vecs: u32,
            leaf_vecs: u32,
            cookie: bool,
            cookie_binding: u32,
            grid: usize,
            per_lane: u32,
            trees: u32,
            sampling: SamplingView,
        }
    };
}

sweep_template!(SweepTemplate, "pst_sweep.wgsl");
sweep_template!(SweepUnwarpTemplate, "pst_sweep_unwarp.wgsl");
sweep_template!(SweepFallbackTemplate, "pst_sweep_fallback.wgsl");

fn validate(kernel: Kernel, variant: &PartialSumTreeVariant) -> Result<(), ShaderError> {
    variant
        .validate()
        .map_err(|source| ShaderError::Variant { kernel, source })
}

/// Renders `kernel`'s template for `variant`.
fn render(kernel: Kernel, variant: &PartialSumTreeVariant) -> Result<String, ShaderError> {
    // (The variant's sampling is epipolar: `validate` refuses the others.)
    validate(kernel, variant)?;
    let sampling = SamplingView {
        slice_lanes: SWEEP_LANES,
        ..SamplingView::new(
            &variant.sampling_knobs(),
            kernel,
            Kernel::PstSweep,
            camera_expr("frame.axis.xyz"),
            SAMPLED_BINDING,
        )
    };
    let light_name = variant.light.name();
    let spot = variant.light == LightKind::Spot;
    let (rank, rank_vecs, grid) = (variant.rank, variant.rank_vecs(), GRID);
    let per_lane = variant.slice_samples.div_ceil(SWEEP_LANES);
    let rendered = match kernel {
        Kernel::PstSweepUnwarp => SweepUnwarpTemplate {
            light_name,
            spot,
            rank,
            rank_vecs,
            leaf_vecs: variant.leaf_vecs(),
            cookie: variant.cookie,
            cookie_binding: COOKIE_BINDING,
            grid,
            per_lane,
            trees: TREES,
            sampling,
        }
        .render(),
        Kernel::PstSweepFallback => SweepFallbackTemplate {
            light_name,
            spot,
            rank,
            rank_vecs,
            leaf_vecs: variant.leaf_vecs(),
            cookie: variant.cookie,
            cookie_binding: COOKIE_BINDING,
            grid,
            per_lane,
            trees: TREES,
            sampling,
        }
        .render(),
        _ => SweepTemplate {
            light_name,
            spot,
            rank,
            rank_vecs,
            leaf_vecs: variant.leaf_vecs(),
            cookie: variant.cookie,
            cookie_binding: COOKIE_BINDING,
            grid,
            per_lane,
            trees: TREES,
            sampling,
        }
        .render(),
    };
    rendered.map_err(|source| ShaderError::Render {
        kernel,
        template: template_path(kernel),
        source,
    })
}

/// Renders `templates/pst_sweep.wgsl` for `variant`.
pub(crate) fn render_sweep(variant: &PartialSumTreeVariant) -> Result<String, ShaderError> {
    render(Kernel::PstSweep, variant)
}

/// Renders `templates/pst_sweep_unwarp.wgsl` for `variant`.
pub(crate) fn render_sweep_unwarp(variant: &PartialSumTreeVariant) -> Result<String, ShaderError> {
    render(Kernel::PstSweepUnwarp, variant)
}

/// Renders `templates/pst_sweep_fallback.wgsl` for `variant`.
pub(crate) fn render_sweep_fallback(
    variant: &PartialSumTreeVariant,
) -> Result<String, ShaderError> {
    render(Kernel::PstSweepFallback, variant)
}

impl crate::KernelParams {
    /// The kernels of a partial-sum-tree variant, in pass order: the shared
    /// `depth_columns`, `slice_fit` and `rectify` (of [`PartialSumTreeVariant::prefiltered`]),
    /// `pst_sweep`, `pst_sweep_unwarp`, `pst_sweep_fallback`.
    pub fn partial_sum_tree(variant: PartialSumTreeVariant) -> [Self; 6] {
        [
            Self::DepthColumns(variant.prefiltered()),
            Self::SliceFit(variant.prefiltered()),
            Self::Rectify(variant.prefiltered()),
            Self::PstSweep(variant),
            Self::PstSweepUnwarp(variant),
            Self::PstSweepFallback(variant),
        ]
    }
}

impl crate::family::KernelFamily for PartialSumTreeVariant {
    fn kernel_params(&self) -> Vec<crate::KernelParams> {
        crate::KernelParams::partial_sum_tree(*self).to_vec()
    }

    fn plan(&self) -> crate::plan::Plan {
        plan::plan(self)
    }

    fn with_most_passes() -> Self {
        Self::default()
    }
}
