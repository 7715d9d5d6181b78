//! The hybrid_volume family (Wyman & Ramsey 2008) on [`Engine`]: its resources hold what the
//! prefiltered family's of the same names hold (`frame` the [`FrameUniforms`] bytes and
//! `slices` the slice table, both from
//! [`scatter_frame::hybrid_volume::prepare_hybrid_volume`]; `depth` and `shadow_map` the
//! engine's textures), so a frame runs through [`crate::prefiltered::run_frame`]. Its one
//! buffer of its own, `crossings`, is sized by its formula in the manifest (bins times
//! `rectified.height` elements) and needs no extra parameter.
//!
//! [`FrameUniforms`]: scatter_frame::frame::FrameUniforms

use scatter_frame::frame::PrefilteredFrame;

use crate::formula::Params;
use crate::prefiltered::{Inputs, Output, Sizes};
use crate::{Engine, EngineError};

/// The manifest parameters of a hybrid_volume variant: the prefiltered family's (same sizes).
pub fn params(sizes: &Sizes) -> Params {
    sizes.params()
}

/// Runs one frame of a hybrid_volume variant: uploads the frame set-up and the engine's depth
/// buffer, standard shadow map and, for a `cookie` variant, the spot's cookie (RGBA texels),
/// dispatches and reads `output` back.
///
/// # Errors
///
/// As [`crate::prefiltered::run_frame`].
pub fn run_frame(
    engine: &mut Engine,
    frame: &PrefilteredFrame,
    depth: &[f32],
    shadow_map: &[f32],
    cookie: Option<&[f32]>,
) -> Result<Output, EngineError> {
    crate::prefiltered::run_frame(
        engine,
        frame,
        &Inputs {
            depth,
            shadow_map: Some(shadow_map),
            rectified_raster: None,
            cookie,
        },
    )
}
