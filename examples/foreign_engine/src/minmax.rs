//! The minmax family (Chen et al. 2011) on [`Engine`]: its resources hold what the
//! prefiltered family's of the same names hold (`frame` the [`FrameUniforms`] bytes and
//! `slices` the slice table, both from [`scatter_frame::minmax::prepare_minmax`]; `depth`
//! and `shadow_map` the engine's textures), so a frame runs through
//! [`crate::prefiltered::run_frame`]. Its one extra parameter is `tree.width`, the width of
//! the min-max tree texture ([`scatter_frame::minmax::tree_width`]).
//!
//! [`FrameUniforms`]: scatter_frame::frame::FrameUniforms

use scatter_frame::frame::PrefilteredFrame;
use scatter_frame::minmax::tree_width;

use crate::formula::Params;
use crate::prefiltered::{Inputs, Output, Sizes};
use crate::{Engine, EngineError};

/// The manifest parameters of a minmax variant: the prefiltered family's (same sizes) plus
/// `tree.width`.
pub fn params(sizes: &Sizes) -> Params {
    let mut p = sizes.params();
    p.set("tree.width", tree_width(sizes.rectified[0]).into());
    p
}

/// Runs one frame of a minmax variant: uploads the frame set-up and the engine's depth
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
