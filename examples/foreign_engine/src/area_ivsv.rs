//! The area_ivsv family (Wyman & Dai 2013) on [`Engine`]: what its manifest resources hold.
//! `frame` gets the bytes of [`IvsvUniforms`] and `vpls` those of the [`VplRecord`] array
//! (both from [`scatter_frame::area_ivsv::prepare_area_light`], which also gives each VPL's
//! shadow-map frame); `depth` is the engine's depth buffer and `vpl_maps` its VPL shadow maps,
//! one layer per VPL, rendered with those frames; `marks`, `volume` and (interleaved) `partial`
//! are allocated from the manifest like any other resource; `output` is read back.

use std::mem::offset_of;

use scatter_frame::area_ivsv::{AreaIvsvFrame, IvsvUniforms, VplRecord};

use crate::prefiltered::{DEPTH, Output, check_struct_layout, read_output};
use crate::{Engine, EngineError, FrameData};

/// Resource of the uniform block.
pub const FRAME: &str = "frame";
/// Resource of the VPL records.
pub const VPLS: &str = "vpls";
/// The engine's VPL shadow maps (an array texture, one layer per VPL).
pub const VPL_MAPS: &str = "vpl_maps";

/// Texture sizes of one configuration: the screen and the VPL maps' side (`shadow.size`),
/// the same parameters as the raymarch family's.
pub use crate::raymarch::Sizes;

/// Host field names and offsets of [`IvsvUniforms`], in the manifest's spelling.
const FRAME_FIELDS: [(&str, usize); 8] = [
    ("eye", offset_of!(IvsvUniforms, eye)),
    ("cam_forward", offset_of!(IvsvUniforms, cam_forward)),
    ("cam_right", offset_of!(IvsvUniforms, cam_right)),
    ("cam_up", offset_of!(IvsvUniforms, cam_up)),
    ("medium", offset_of!(IvsvUniforms, medium)),
    ("sizes", offset_of!(IvsvUniforms, sizes)),
    ("grid", offset_of!(IvsvUniforms, grid)),
    ("centre", offset_of!(IvsvUniforms, centre)),
];

/// Host field names and offsets of [`VplRecord`].
const VPL_FIELDS: [(&str, usize); 11] = [
    ("position", offset_of!(VplRecord, position)),
    ("color", offset_of!(VplRecord, color)),
    ("axis", offset_of!(VplRecord, axis)),
    ("perp_x", offset_of!(VplRecord, perp_x)),
    ("perp_y", offset_of!(VplRecord, perp_y)),
    ("spot_dir", offset_of!(VplRecord, spot_dir)),
    ("sm_right", offset_of!(VplRecord, sm_right)),
    ("sm_up", offset_of!(VplRecord, sm_up)),
    ("sm_forward", offset_of!(VplRecord, sm_forward)),
    ("sm_origin", offset_of!(VplRecord, sm_origin)),
    ("sm_proj", offset_of!(VplRecord, sm_proj)),
];

/// Checks that the structs the manifest's `frame` and `vpls` bindings hold have exactly
/// the fields, offsets and sizes of [`IvsvUniforms`] and [`VplRecord`].
///
/// # Errors
///
/// [`EngineError::Inconsistent`] naming the first difference.
pub fn check_area_ivsv_layout(engine: &Engine) -> Result<(), EngineError> {
    check_struct_layout(
        engine,
        FRAME,
        "scatter-frame's IvsvUniforms",
        size_of::<IvsvUniforms>(),
        &FRAME_FIELDS,
    )?;
    check_struct_layout(
        engine,
        VPLS,
        "scatter-frame's VplRecord",
        size_of::<VplRecord>(),
        &VPL_FIELDS,
    )
}

/// Runs one frame: uploads the frame set-up, the engine's depth buffer and its VPL shadow
/// maps (r32float texels, row-major from the top-left, layer after layer in VPL order),
/// dispatches and reads `output` back.
///
/// # Errors
///
/// [`check_area_ivsv_layout`]'s; [`Engine::run`]'s (wrong lengths, a VPL count other than
/// the variant's); [`Engine::read_texture`]'s.
pub fn run_frame(
    engine: &mut Engine,
    frame: &AreaIvsvFrame,
    depth: &[f32],
    vpl_maps: &[f32],
) -> Result<Output, EngineError> {
    check_area_ivsv_layout(engine)?;
    let run = engine.run(&FrameData {
        buffers: &[
            (FRAME, bytemuck::bytes_of(&frame.uniforms)),
            (VPLS, bytemuck::cast_slice(&frame.vpls)),
        ],
        textures: &[(DEPTH, depth), (VPL_MAPS, vpl_maps)],
    })?;
    let radiance = read_output(engine)?;
    Ok(Output { radiance, run })
}
