//! The prefiltered family (Klehm et al. 2014) on [`Engine`]: the only place that knows what
//! the manifest's resources hold. `frame` gets the bytes of
//! [`scatter_frame::frame::FrameUniforms`] and `slices` those of the
//! [`scatter_frame::frame::SliceParams`] table (both from
//! [`scatter_frame::frame::prepare_frame`]); `depth`, `shadow_map` and, in projective
//! frames, `rectified_raster` are the engine's textures; `output` is read back.
//!
//! Before uploading, [`check_frame_layout`] compares the manifest's `Frame` struct field by
//! field with the host struct this crate was compiled against, so a manifest from another
//! version of the kernels fails with a message instead of garbage.

use std::mem::offset_of;

use scatter_frame::frame::{FrameUniforms, PrefilteredFrame};

use crate::formula::Params;
use crate::{Engine, EngineError, FrameData, FrameRun};

/// Resource of the uniform block.
pub const FRAME: &str = "frame";
/// Resource of the slice table.
pub const SLICES: &str = "slices";
/// The engine's linear view depth.
pub const DEPTH: &str = "depth";
/// The engine's standard shadow map.
pub const SHADOW_MAP: &str = "shadow_map";
/// Resource of a spot's cookie (engine input of a `cookie` variant).
pub const COOKIE: &str = "cookie";
/// The engine's rasterised rectified map (projective variants).
pub const RECTIFIED_RASTER: &str = "rectified_raster";
/// In-scattered radiance.
pub const OUTPUT: &str = "output";

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
    /// The manifest parameters: `screen.width`, `screen.height`, `shadow.size`,
    /// `rectified.width`, `rectified.height`.
    pub fn params(&self) -> Params {
        let mut p = Params::default();
        p.set("screen.width", self.screen[0].into());
        p.set("screen.height", self.screen[1].into());
        p.set("shadow.size", self.shadow_map.into());
        p.set("rectified.width", self.rectified[0].into());
        p.set("rectified.height", self.rectified[1].into());
        p
    }
}

/// The engine's textures for one frame (r32float texels, row-major from the top-left).
#[derive(Clone, Copy, Debug, Default)]
pub struct Inputs<'a> {
    /// Linear view depth, `screen[0] * screen[1]` values.
    pub depth: &'a [f32],
    /// Standard shadow map, `shadow_map^2` values: needed by epipolar frames.
    pub shadow_map: Option<&'a [f32]>,
    /// The rectified map rasterised with the frame's projective matrices (`Wr * Hr` clip
    /// depths): needed by projective frames.
    pub rectified_raster: Option<&'a [f32]>,
    /// A spot's cookie (resource `cookie`, `cookie.width * cookie.height` RGBA texels, linear
    /// RGB): needed by a `cookie` variant.
    pub cookie: Option<&'a [f32]>,
}

/// Radiance of one frame and what ran.
#[derive(Clone, Debug)]
pub struct Output {
    /// In-scattered radiance per pixel, rgba (alpha 1), row-major from the top-left.
    pub radiance: Vec<[f32; 4]>,
    /// Passes dispatched and skipped, alternatives taken.
    pub run: FrameRun,
}

/// Host field names and offsets of [`FrameUniforms`], in the manifest's spelling (naga
/// appends `_` to names ending in a digit).
const HOST_FIELDS: [(&str, usize); 27] = [
    ("eye", offset_of!(FrameUniforms, eye)),
    ("axis", offset_of!(FrameUniforms, axis)),
    ("e1_", offset_of!(FrameUniforms, e1)),
    ("e2_", offset_of!(FrameUniforms, e2)),
    ("cam_forward", offset_of!(FrameUniforms, cam_forward)),
    ("cam_right", offset_of!(FrameUniforms, cam_right)),
    ("cam_up", offset_of!(FrameUniforms, cam_up)),
    ("theta", offset_of!(FrameUniforms, theta)),
    ("medium", offset_of!(FrameUniforms, medium)),
    ("light_color", offset_of!(FrameUniforms, light_color)),
    ("light_pos", offset_of!(FrameUniforms, light_pos)),
    ("light_dir", offset_of!(FrameUniforms, light_dir)),
    ("sm_right", offset_of!(FrameUniforms, sm_right)),
    ("sm_up", offset_of!(FrameUniforms, sm_up)),
    ("sm_forward", offset_of!(FrameUniforms, sm_forward)),
    ("sm_origin", offset_of!(FrameUniforms, sm_origin)),
    ("sm_proj", offset_of!(FrameUniforms, sm_proj)),
    ("epipole", offset_of!(FrameUniforms, epipole)),
    ("anti_epipole", offset_of!(FrameUniforms, anti_epipole)),
    ("sizes", offset_of!(FrameUniforms, sizes)),
    ("sizes2_", offset_of!(FrameUniforms, sizes2)),
    ("proj", offset_of!(FrameUniforms, proj)),
    ("proj_g0_", offset_of!(FrameUniforms, proj_g0)),
    ("proj_g1_", offset_of!(FrameUniforms, proj_g1)),
    ("proj_g2_", offset_of!(FrameUniforms, proj_g2)),
    ("fan_origin", offset_of!(FrameUniforms, fan_origin)),
    ("fan_angles", offset_of!(FrameUniforms, fan_angles)),
];

/// Checks that the struct the manifest's `frame` bindings hold has exactly the fields,
/// offsets and size of [`FrameUniforms`].
///
/// # Errors
///
/// [`EngineError::Inconsistent`] naming the first difference.
pub fn check_frame_layout(engine: &Engine) -> Result<(), EngineError> {
    check_struct_layout(
        engine,
        FRAME,
        "scatter-frame's FrameUniforms",
        size_of::<FrameUniforms>(),
        &HOST_FIELDS,
    )
}

/// Checks that the struct the manifest's bindings of `resource` hold has exactly the
/// fields (manifest spelling, host offset) and size of the host struct `host`.
///
/// # Errors
///
/// [`EngineError::Inconsistent`] naming the first difference.
pub fn check_struct_layout(
    engine: &Engine,
    resource: &str,
    host: &str,
    host_size: usize,
    host_fields: &[(&str, usize)],
) -> Result<(), EngineError> {
    let variant = engine.variant();
    let struct_name = variant
        .passes
        .iter()
        .flat_map(|p| &p.bindings)
        .filter(|b| b.resource == resource)
        .find_map(|b| b.struct_name.as_deref())
        .ok_or_else(|| {
            EngineError::Inconsistent(format!("no binding of `{resource}` names its struct"))
        })?;
    let layout = engine
        .manifest()
        .struct_layout(&variant.family, struct_name)
        .ok_or_else(|| {
            EngineError::Inconsistent(format!("struct {struct_name} is not in `structs`"))
        })?;
    let differs = |what: String| {
        Err(EngineError::Inconsistent(format!(
            "the manifest's {struct_name} differs from {host}: {what}; \
             regenerate the shaders with the scatter-gen of this scatter-frame"
        )))
    };
    if layout.size != host_size as u64 {
        return differs(format!("{} bytes, the host has {host_size}", layout.size));
    }
    for f in &layout.fields {
        match host_fields.iter().find(|(n, _)| *n == f.name) {
            None => return differs(format!("field {} is not on the host", f.name)),
            Some(&(_, offset)) if offset as u64 != f.offset => {
                return differs(format!(
                    "field {} at offset {}, the host has {offset}",
                    f.name, f.offset
                ));
            }
            Some(_) => {}
        }
    }
    if let Some((missing, _)) = host_fields
        .iter()
        .find(|(n, _)| !layout.fields.iter().any(|f| f.name == *n))
    {
        return differs(format!("the host's field {missing} is not in the manifest"));
    }
    Ok(())
}

/// Reads `output` back as rgba radiance.
///
/// # Errors
///
/// [`Engine::read_texture`]'s; [`EngineError::Inconsistent`] when `output` is not rgba.
pub fn read_output(engine: &Engine) -> Result<Vec<[f32; 4]>, EngineError> {
    let (channels, values) = engine.read_texture(OUTPUT)?;
    if channels != 4 {
        return Err(EngineError::Inconsistent(format!(
            "`{OUTPUT}` has {channels} channels, not rgba"
        )));
    }
    Ok(values
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect())
}

/// Runs one frame: uploads `frame.uniforms`, `frame.slices` and the engine's textures,
/// dispatches and reads `output` back.
///
/// # Errors
///
/// [`check_frame_layout`]'s; [`Engine::run`]'s (a projective frame without
/// `rectified_raster`, an epipolar one without `shadow_map`, wrong lengths);
/// [`Engine::read_texture`]'s.
pub fn run_frame(
    engine: &mut Engine,
    frame: &PrefilteredFrame,
    inputs: &Inputs<'_>,
) -> Result<Output, EngineError> {
    check_frame_layout(engine)?;
    let buffers = [
        (FRAME, bytemuck::bytes_of(&frame.uniforms)),
        (SLICES, bytemuck::cast_slice(&frame.slices)),
    ];
    let mut textures = vec![(DEPTH, inputs.depth)];
    if let Some(sm) = inputs.shadow_map {
        textures.push((SHADOW_MAP, sm));
    }
    if let Some(c) = inputs.cookie {
        textures.push((COOKIE, c));
    }
    if let Some(r) = inputs.rectified_raster {
        textures.push((RECTIFIED_RASTER, r));
    }
    let run = engine.run(&FrameData {
        buffers: &buffers,
        textures: &textures,
    })?;
    let radiance = read_output(engine)?;
    Ok(Output { radiance, run })
}
