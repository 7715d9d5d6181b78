//! The `prefiltered` family (Klehm et al. 2014): variant knobs, per-frame parameters and the
//! three kernels `rectify`, `prefilter` and `scatter`.
//!
//! CPU mirrors: `reference/src/kernels/{prefiltered_common,rectify,prefilter,scatter}.rs`.

pub mod frame;
pub mod variant;

pub use frame::{
    CameraDesc, FrameError, FrameReport, FrameSettings, FrameUniforms, LightDesc, MediumDesc,
    PrefilteredFrame, Resolutions, ShadowMapDesc, ShadowProjectionDesc, SliceParams, prepare_frame,
};
pub use variant::{LightKind, Rectification, Storage, Variant, VariantError, VisibilityMode};
