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
use crate::prefiltered::{Inputs, Output};
use crate::{Engine, EngineError};

/// Texture sizes of one configuration: the values of the manifest's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sizes {
    /// Screen width and height (depth buffer and output).
    pub screen: [u32; 2],
    /// Rectified map width (light rays per slice) and height (slices).
    pub rectified: [u32; 2],
    /// Side of the standard shadow map.
    pub shadow_map: u32,
}

impl Sizes {
    /// The manifest parameters: the prefiltered family's plus `tree.width`.
    pub fn params(&self) -> Params {
        let mut p = crate::prefiltered::Sizes {
            screen: self.screen,
            rectified: self.rectified,
            shadow_map: self.shadow_map,
        }
        .params();
        p.set("tree.width", tree_width(self.rectified[0]).into());
        p
    }
}

/// Runs one frame of a minmax variant: uploads the frame set-up and the engine's depth
/// buffer and standard shadow map, dispatches and reads `output` back.
///
/// # Errors
///
/// As [`crate::prefiltered::run_frame`].
pub fn run_frame(
    engine: &mut Engine,
    frame: &PrefilteredFrame,
    depth: &[f32],
    shadow_map: &[f32],
) -> Result<Output, EngineError> {
    crate::prefiltered::run_frame(
        engine,
        frame,
        &Inputs {
            depth,
            shadow_map: Some(shadow_map),
            rectified_raster: None,
        },
    )
}
