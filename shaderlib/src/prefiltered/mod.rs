//! The `prefiltered` family (Klehm et al. 2014): variant knobs, per-frame parameters and the
//! five kernels `depth_columns`, `slice_fit`, `rectify`, `prefilter` and `scatter`.
//!
//! CPU mirrors: `reference/src/kernels/{common_model,common_prefiltered,depth_columns,slice_fit,rectify,prefilter,scatter}.rs`.

pub mod kernels;
pub mod plan;

pub use scatter_frame::{frame, variant};

pub use frame::{
    CameraDesc, FrameError, FrameReport, FrameSettings, FrameUniforms, LightDesc, MediumDesc,
    PrefilteredFrame, ProjectiveFallback, ProjectiveMaps, Resolutions, ShadowMapDesc,
    ShadowProjectionDesc, SliceParams, prepare_frame, region_start,
};
pub use kernels::{
    DEPTH_COLUMNS_WORKGROUP_SIZE, PREFILTER_WORKGROUP_SIZE, RECTIFY_TEXELS, RECTIFY_WORKGROUP_SIZE,
    SCATTER_WORKGROUP_SIZE, SLICE_FIT_WORKGROUP_SIZE, filtered_column_major, filtered_word,
    filtered_word_bytes,
};
pub use variant::{
    Basis, LightKind, PrefilteredVariant, Rectification, Storage, VariantError, VisibilityMode,
};

impl crate::KernelParams {
    /// The five kernels of a prefiltered-family variant, in pass order: `depth_columns`,
    /// `slice_fit`, `rectify`, `prefilter`, `scatter`.
    pub const fn prefiltered(variant: PrefilteredVariant) -> [Self; 5] {
        [
            Self::DepthColumns(variant),
            Self::SliceFit(variant),
            Self::Rectify(variant),
            Self::Prefilter(variant),
            Self::Scatter(variant),
        ]
    }
}

impl crate::family::KernelFamily for PrefilteredVariant {
    fn kernel_params(&self) -> Vec<crate::KernelParams> {
        let mut out = crate::KernelParams::prefiltered(*self).to_vec();
        if self.sampling != crate::sampling::Sampling::Pixels {
            out.push(crate::KernelParams::ScatterUnwarp(*self));
            out.push(crate::KernelParams::ScatterFallback(*self));
        }
        out
    }

    fn plan(&self) -> crate::plan::Plan {
        plan::plan(self)
    }

    fn with_most_passes() -> Self {
        Self::default()
    }
}
