//! The partial-sum-tree family (Baran et al. 2010) on [`Engine`]: `frame` and `slices` hold
//! what the prefiltered family's resources of the same names hold, `pst_factors` the bytes of
//! the frame's separable integrand ([`PartialSumTreeFrame::factors`]), all three from
//! [`scatter_frame::partial_sum_tree::prepare_partial_sum_tree`]; `depth` and `shadow_map`
//! are the engine's textures. The sweep's scratch buffers (`pst_leaves`, `pst_tree`,
//! `pst_columns`) are scatter's: the engine sizes them from the manifest's formulas and
//! uploads nothing. Its parameters are the prefiltered family's.

use scatter_frame::partial_sum_tree::PartialSumTreeFrame;

use crate::prefiltered::{
    COOKIE, DEPTH, FRAME, Output, SHADOW_MAP, SLICES, check_frame_layout, read_output,
};
use crate::{Engine, EngineError, FrameData};

/// Resource of the separable integrand's factors.
pub const FACTORS: &str = "pst_factors";

/// Runs one frame: uploads the frame set-up (uniforms, slice table, factors) and the
/// engine's depth buffer, standard shadow map and, for a `cookie` variant, the spot's cookie
/// (RGBA texels), dispatches and reads `output` back.
///
/// # Errors
///
/// As [`crate::prefiltered::run_frame`].
pub fn run_frame(
    engine: &mut Engine,
    frame: &PartialSumTreeFrame,
    depth: &[f32],
    shadow_map: &[f32],
    cookie: Option<&[f32]>,
) -> Result<Output, EngineError> {
    check_frame_layout(engine)?;
    let buffers = [
        (FRAME, bytemuck::bytes_of(&frame.frame.uniforms)),
        (SLICES, bytemuck::cast_slice(&frame.frame.slices)),
        (FACTORS, bytemuck::cast_slice(&frame.factors)),
    ];
    let mut textures = vec![(DEPTH, depth), (SHADOW_MAP, shadow_map)];
    if let Some(c) = cookie {
        textures.push((COOKIE, c));
    }
    let run = engine.run(&FrameData {
        buffers: &buffers,
        textures: &textures,
    })?;
    let radiance = read_output(engine)?;
    Ok(Output { radiance, run })
}
