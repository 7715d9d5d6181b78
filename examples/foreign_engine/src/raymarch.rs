//! The raymarch family (Tóth & Umenhoffer 2009) on [`Engine`]: what its manifest resources
//! hold. `march` gets the bytes of [`MarchUniforms`] (from
//! [`scatter_frame::raymarch::prepare_march`]); `depth` and `shadow_map` are the engine's
//! textures; `output` is read back. Interleaved variants also have `partial`, which the
//! engine allocates from the manifest like any other resource.

use std::mem::offset_of;

use scatter_frame::raymarch::MarchUniforms;

use crate::formula::Params;
use crate::prefiltered::{DEPTH, Output, SHADOW_MAP, check_struct_layout, read_output};
use crate::{Engine, EngineError, FrameData};

/// Resource of the uniform block.
pub const MARCH: &str = "march";

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

/// Host field names and offsets of [`MarchUniforms`], in the manifest's spelling.
const HOST_FIELDS: [(&str, usize); 15] = [
    ("eye", offset_of!(MarchUniforms, eye)),
    ("cam_forward", offset_of!(MarchUniforms, cam_forward)),
    ("cam_right", offset_of!(MarchUniforms, cam_right)),
    ("cam_up", offset_of!(MarchUniforms, cam_up)),
    ("medium", offset_of!(MarchUniforms, medium)),
    ("light_color", offset_of!(MarchUniforms, light_color)),
    ("light_pos", offset_of!(MarchUniforms, light_pos)),
    ("light_dir", offset_of!(MarchUniforms, light_dir)),
    ("sm_right", offset_of!(MarchUniforms, sm_right)),
    ("sm_up", offset_of!(MarchUniforms, sm_up)),
    ("sm_forward", offset_of!(MarchUniforms, sm_forward)),
    ("sm_origin", offset_of!(MarchUniforms, sm_origin)),
    ("sm_proj", offset_of!(MarchUniforms, sm_proj)),
    ("sizes", offset_of!(MarchUniforms, sizes)),
    ("interleave", offset_of!(MarchUniforms, interleave)),
];

/// Checks that the struct the manifest's `march` bindings hold has exactly the fields,
/// offsets and size of [`MarchUniforms`].
///
/// # Errors
///
/// [`EngineError::Inconsistent`] naming the first difference.
pub fn check_march_layout(engine: &Engine) -> Result<(), EngineError> {
    check_struct_layout(
        engine,
        MARCH,
        "scatter-frame's MarchUniforms",
        size_of::<MarchUniforms>(),
        &HOST_FIELDS,
    )
}

/// Runs one frame: uploads `uniforms` and the engine's depth buffer and standard shadow map
/// (r32float texels, row-major from the top-left), dispatches and reads `output` back.
///
/// # Errors
///
/// [`check_march_layout`]'s; [`Engine::run`]'s (wrong lengths);
/// [`Engine::read_texture`]'s.
pub fn run_frame(
    engine: &mut Engine,
    uniforms: &MarchUniforms,
    depth: &[f32],
    shadow_map: &[f32],
) -> Result<Output, EngineError> {
    check_march_layout(engine)?;
    let run = engine.run(&FrameData {
        buffers: &[(MARCH, bytemuck::bytes_of(uniforms))],
        textures: &[(DEPTH, depth), (SHADOW_MAP, shadow_map)],
    })?;
    let radiance = read_output(engine)?;
    Ok(Output { radiance, run })
}
