//! The raymarch family (Tóth & Umenhoffer 2009) on [`Engine`]: what its manifest resources
//! hold. `frame` gets the bytes of [`RaymarchUniforms`] (from
//! [`scatter_frame::raymarch::prepare_raymarch`]); `depth` and `shadow_map` are the engine's
//! textures; `output` is read back. Interleaved variants also have `partial`, which the
//! engine allocates from the manifest like any other resource.

use std::mem::offset_of;

use scatter_frame::raymarch::RaymarchUniforms;

use crate::formula::Params;
use crate::prefiltered::{COOKIE, DEPTH, Output, SHADOW_MAP, check_struct_layout, read_output};
use crate::{Engine, EngineError, FrameData};

/// Resource of the uniform block.
pub const FRAME: &str = "frame";

/// Texture sizes of one configuration: the values of the manifest's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sizes {
    /// Screen width and height (depth buffer and output).
    pub screen: [u32; 2],
    /// Side of the standard shadow map.
    pub shadow_map: u32,
}

impl Sizes {
    /// The manifest parameters: `screen.width`, `screen.height`, `shadow.size`.
    pub fn params(&self) -> Params {
        let mut p = Params::default();
        p.set("screen.width", self.screen[0].into());
        p.set("screen.height", self.screen[1].into());
        p.set("shadow.size", self.shadow_map.into());
        p
    }
}

/// Host field names and offsets of [`RaymarchUniforms`], in the manifest's spelling.
const HOST_FIELDS: [(&str, usize); 15] = [
    ("eye", offset_of!(RaymarchUniforms, eye)),
    ("cam_forward", offset_of!(RaymarchUniforms, cam_forward)),
    ("cam_right", offset_of!(RaymarchUniforms, cam_right)),
    ("cam_up", offset_of!(RaymarchUniforms, cam_up)),
    ("medium", offset_of!(RaymarchUniforms, medium)),
    ("light_color", offset_of!(RaymarchUniforms, light_color)),
    ("light_pos", offset_of!(RaymarchUniforms, light_pos)),
    ("light_dir", offset_of!(RaymarchUniforms, light_dir)),
    ("sm_right", offset_of!(RaymarchUniforms, sm_right)),
    ("sm_up", offset_of!(RaymarchUniforms, sm_up)),
    ("sm_forward", offset_of!(RaymarchUniforms, sm_forward)),
    ("sm_origin", offset_of!(RaymarchUniforms, sm_origin)),
    ("sm_proj", offset_of!(RaymarchUniforms, sm_proj)),
    ("sizes", offset_of!(RaymarchUniforms, sizes)),
    ("interleave", offset_of!(RaymarchUniforms, interleave)),
];

/// Checks that the struct the manifest's `frame` bindings hold has exactly the fields,
/// offsets and size of [`RaymarchUniforms`].
///
/// # Errors
///
/// [`EngineError::Inconsistent`] naming the first difference.
pub fn check_raymarch_layout(engine: &Engine) -> Result<(), EngineError> {
    check_struct_layout(
        engine,
        FRAME,
        "scatter-frame's RaymarchUniforms",
        size_of::<RaymarchUniforms>(),
        &HOST_FIELDS,
    )
}

/// Runs one frame: uploads `uniforms` and the engine's depth buffer and standard shadow map
/// (r32float texels, row-major from the top-left), dispatches and reads `output` back.
///
/// # Errors
///
/// [`check_raymarch_layout`]'s; [`Engine::run`]'s (wrong lengths);
/// [`Engine::read_texture`]'s.
pub fn run_frame(
    engine: &mut Engine,
    uniforms: &RaymarchUniforms,
    depth: &[f32],
    shadow_map: &[f32],
    cookie: Option<&[f32]>,
) -> Result<Output, EngineError> {
    check_raymarch_layout(engine)?;
    let mut textures = vec![(DEPTH, depth), (SHADOW_MAP, shadow_map)];
    if let Some(c) = cookie {
        textures.push((COOKIE, c));
    }
    let run = engine.run(&FrameData {
        buffers: &[(FRAME, bytemuck::bytes_of(uniforms))],
        textures: &textures,
    })?;
    let radiance = read_output(engine)?;
    Ok(Output { radiance, run })
}
