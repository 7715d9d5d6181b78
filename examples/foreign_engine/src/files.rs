//! The binary's input and output files, usable without any scatter crate but
//! `scatter-frame`:
//!
//! - `frame.json` ([`FrameFile`]): screen and rectified sizes, camera, light, medium,
//!   standard shadow map and (optional) settings, plain numbers in the units of
//!   [`scatter_frame::frame`];
//! - `depth.pfm`: linear view depth, screen-sized; `shadow_map.pfm`: the standard shadow map
//!   (normalised linear light depth); `rectified.pfm` (projective frames only): the rectified
//!   map rasterised with the frame's matrices. Greyscale PFM (`Pf`), little-endian, rows
//!   bottom to top as PFM stores them (the reader flips them to top-down);
//! - the output: colour PFM (`PF`) of the in-scattered radiance.
//!
//! [`run_dir`] is the whole binary minus argument parsing and device creation.

use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::{Deserialize, Serialize};

use scatter_frame::area_ivsv::{AreaIvsvVariant, prepare_area_light};
use scatter_frame::area_light::{AreaLightDesc, AreaShapeDesc};
use scatter_frame::frame::{
    CameraDesc, FrameSettings, LightDesc, MediumDesc, PrefilteredFrame, Resolutions, ShadowMapDesc,
    ShadowProjectionDesc, prepare_frame,
};
use scatter_frame::hybrid_volume::{HybridVolumeVariant, prepare_hybrid_volume};
use scatter_frame::minmax::{MinmaxVariant, prepare_minmax};
use scatter_frame::partial_sum_tree::{
    PartialSumTreeFrame, PartialSumTreeVariant, prepare_partial_sum_tree,
};
use scatter_frame::raymarch::{RaymarchUniforms, RaymarchVariant, prepare_raymarch};
use scatter_frame::variant::PrefilteredVariant;

use crate::prefiltered::{Inputs, Sizes, run_frame};
use crate::{Engine, EngineError, FrameRun, Target};

/// `frame.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameFile {
    /// Screen width and height (of `depth.pfm` and the output).
    pub screen: [u32; 2],
    /// Rectified map width and height (the engine's choice).
    pub rectified: [u32; 2],
    /// The camera.
    pub camera: CameraFile,
    /// The light.
    pub light: LightFile,
    /// The medium.
    pub medium: MediumFile,
    /// The standard shadow map.
    pub shadow_map: ShadowMapFile,
    /// Frame settings; `FrameSettings::for_screen(screen)` when absent.
    #[serde(default)]
    pub settings: Option<SettingsFile>,
}

/// [`CameraDesc`] as plain numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    /// Eye position.
    pub position: [f64; 3],
    /// Unit view axis.
    pub forward: [f64; 3],
    /// Unit image right.
    pub right: [f64; 3],
    /// Unit image up.
    pub up: [f64; 3],
    /// tan(vertical fov / 2).
    pub tan_half_fov_y: f64,
    /// Near plane.
    pub near: f64,
    /// Far plane.
    pub far: f64,
}

/// [`LightDesc`] as plain numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightFile {
    /// Directional light.
    Directional {
        /// Direction the light travels.
        direction: [f64; 3],
        /// Irradiance (RGB).
        color: [f64; 3],
    },
    /// Spot light.
    Spot {
        /// Position.
        position: [f64; 3],
        /// Cone axis.
        direction: [f64; 3],
        /// Full-intensity half-angle, degrees.
        inner_deg: f64,
        /// Zero-intensity half-angle, degrees.
        outer_deg: f64,
        /// Intensity (RGB).
        color: [f64; 3],
    },
    /// Area light (`scatter_frame::area_light::AreaLightDesc`).
    Area {
        /// Centre.
        position: [f64; 3],
        /// Emitting normal.
        direction: [f64; 3],
        /// The outline's up axis (absent: the light basis's).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        up: Option<[f64; 3]>,
        /// The outline.
        shape: AreaShapeFile,
        /// Full-emission half-angle, degrees.
        inner_deg: f64,
        /// Zero-emission half-angle, degrees.
        outer_deg: f64,
        /// Radiance along the normal (RGB).
        radiance: [f64; 3],
        /// Whether the back face emits too.
        #[serde(default)]
        two_sided: bool,
    },
}

/// An area light's outline as plain numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum AreaShapeFile {
    /// A rectangle.
    Rect {
        /// Extent along the light's right axis.
        width: f64,
        /// Extent along its up axis.
        height: f64,
    },
    /// A disk.
    Disk {
        /// Radius.
        radius: f64,
    },
}

/// [`MediumDesc`] as plain numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediumFile {
    /// Extinction (1/m).
    pub sigma_t: f64,
    /// Single-scattering albedo.
    pub albedo: f64,
    /// Henyey-Greenstein g.
    pub g: f64,
}

/// [`ShadowProjectionDesc`] as plain numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ProjectionFile {
    /// Orthographic window.
    Orthographic {
        /// Left.
        x0: f64,
        /// Right.
        x1: f64,
        /// Bottom.
        y0: f64,
        /// Top.
        y1: f64,
    },
    /// Square perspective.
    Perspective {
        /// tan(fov / 2).
        tan_half: f64,
    },
}

/// [`ShadowMapDesc`] as plain numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShadowMapFile {
    /// Light-space origin.
    pub origin: [f64; 3],
    /// Light-space right, up, forward.
    pub basis: [[f64; 3]; 3],
    /// Projection.
    pub projection: ProjectionFile,
    /// Depth of stored 0.
    pub near: f64,
    /// Depth of stored 1.
    pub far: f64,
    /// Texels per side (of `shadow_map.pfm`).
    pub size: u32,
    /// Depth bias in texel footprints.
    pub bias_texels: f64,
}

/// [`FrameSettings`] as plain numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingsFile {
    /// March radius around the epipoles, pixels.
    pub epipole_radius_px: f64,
    /// March samples.
    pub march_steps: u32,
    /// Spot quadrature nodes (a multiple of 4).
    pub spot_quadrature: u32,
    /// Widest slice fan (half-angle, degrees) of a projective frame.
    pub projective_max_half_angle_deg: f64,
}

fn v3(v: [f64; 3]) -> DVec3 {
    DVec3::from_array(v)
}

impl FrameFile {
    /// From the frame set-up's descriptions (what a Rust engine has at hand).
    pub fn new(
        sizes: Sizes,
        camera: &CameraDesc,
        light: &LightDesc,
        medium: &MediumDesc,
        shadow_map: &ShadowMapDesc,
        settings: &FrameSettings,
    ) -> Self {
        Self {
            screen: sizes.screen,
            rectified: sizes.rectified,
            camera: CameraFile {
                position: camera.position.to_array(),
                forward: camera.forward.to_array(),
                right: camera.right.to_array(),
                up: camera.up.to_array(),
                tan_half_fov_y: camera.tan_half_fov_y,
                near: camera.near,
                far: camera.far,
            },
            light: match *light {
                LightDesc::Directional { direction, color } => LightFile::Directional {
                    direction: direction.to_array(),
                    color,
                },
                LightDesc::Spot {
                    position,
                    direction,
                    inner_deg,
                    outer_deg,
                    color,
                } => LightFile::Spot {
                    position: position.to_array(),
                    direction: direction.to_array(),
                    inner_deg,
                    outer_deg,
                    color,
                },
                LightDesc::Area(a) => LightFile::Area {
                    position: a.position.to_array(),
                    direction: a.direction.to_array(),
                    up: a.up.map(|u| u.to_array()),
                    shape: match a.shape {
                        AreaShapeDesc::Rect { width, height } => {
                            AreaShapeFile::Rect { width, height }
                        }
                        AreaShapeDesc::Disk { radius } => AreaShapeFile::Disk { radius },
                    },
                    inner_deg: a.inner_deg,
                    outer_deg: a.outer_deg,
                    radiance: a.radiance,
                    two_sided: a.two_sided,
                },
            },
            medium: MediumFile {
                sigma_t: medium.sigma_t,
                albedo: medium.albedo,
                g: medium.g,
            },
            shadow_map: ShadowMapFile {
                origin: shadow_map.origin.to_array(),
                basis: shadow_map.basis.map(|v| v.to_array()),
                projection: match shadow_map.projection {
                    ShadowProjectionDesc::Orthographic { x0, x1, y0, y1 } => {
                        ProjectionFile::Orthographic { x0, x1, y0, y1 }
                    }
                    ShadowProjectionDesc::Perspective { tan_half } => {
                        ProjectionFile::Perspective { tan_half }
                    }
                },
                near: shadow_map.near,
                far: shadow_map.far,
                size: shadow_map.size,
                bias_texels: shadow_map.bias_texels,
            },
            settings: Some(SettingsFile {
                epipole_radius_px: settings.epipole_radius_px,
                march_steps: settings.march_steps,
                spot_quadrature: settings.spot_quadrature,
                projective_max_half_angle_deg: settings.projective_max_half_angle_deg,
            }),
        }
    }

    /// The sizes of the manifest's parameters.
    pub fn sizes(&self) -> Sizes {
        Sizes {
            screen: self.screen,
            rectified: self.rectified,
            shadow_map: self.shadow_map.size,
        }
    }

    /// Sets up the frame for `variant` ([`prepare_frame`]).
    ///
    /// # Errors
    ///
    /// [`EngineError::Frame`] when the frame set-up rejects the numbers.
    pub fn prepare(&self, variant: &PrefilteredVariant) -> Result<PrefilteredFrame, EngineError> {
        let d = self.descs();
        Ok(prepare_frame(
            variant,
            &self.resolutions(),
            &d.camera,
            &d.light,
            &d.medium,
            &d.shadow_map,
            &d.settings,
        )?)
    }

    /// Sets up the frame of a minmax variant ([`prepare_minmax`]).
    ///
    /// # Errors
    ///
    /// [`EngineError::Frame`] when the frame set-up rejects the numbers.
    pub fn prepare_minmax(&self, variant: &MinmaxVariant) -> Result<PrefilteredFrame, EngineError> {
        let d = self.descs();
        Ok(prepare_minmax(
            variant,
            &self.resolutions(),
            &d.camera,
            &d.light,
            &d.medium,
            &d.shadow_map,
            &d.settings,
        )?)
    }

    /// Sets up the frame of a hybrid_volume variant ([`prepare_hybrid_volume`]).
    ///
    /// # Errors
    ///
    /// [`EngineError::Frame`] when the frame set-up rejects the numbers.
    pub fn prepare_hybrid_volume(
        &self,
        variant: &HybridVolumeVariant,
    ) -> Result<PrefilteredFrame, EngineError> {
        let d = self.descs();
        Ok(prepare_hybrid_volume(
            variant,
            &self.resolutions(),
            &d.camera,
            &d.light,
            &d.medium,
            &d.shadow_map,
            &d.settings,
        )?)
    }

    /// Sets up the frame of a partial-sum-tree variant ([`prepare_partial_sum_tree`]: the
    /// epipolar frame and the separable integrand's factors).
    ///
    /// # Errors
    ///
    /// [`EngineError::Frame`] when the frame set-up rejects the numbers.
    pub fn prepare_partial_sum_tree(
        &self,
        variant: &PartialSumTreeVariant,
    ) -> Result<PartialSumTreeFrame, EngineError> {
        let d = self.descs();
        Ok(prepare_partial_sum_tree(
            variant,
            &self.resolutions(),
            &d.camera,
            &d.light,
            &d.medium,
            &d.shadow_map,
            &d.settings,
        )?)
    }

    /// The uniform block of a raymarch variant ([`prepare_raymarch`]; the rectified size and
    /// the settings do not apply).
    ///
    /// # Errors
    ///
    /// [`EngineError::Frame`] when the frame set-up rejects the numbers.
    pub fn prepare_raymarch(
        &self,
        variant: &RaymarchVariant,
    ) -> Result<RaymarchUniforms, EngineError> {
        let d = self.descs();
        Ok(prepare_raymarch(
            variant,
            self.screen,
            &d.camera,
            &d.light,
            &d.medium,
            &d.shadow_map,
        )?)
    }

    fn resolutions(&self) -> Resolutions {
        Resolutions {
            screen: self.screen,
            rectified: self.rectified,
        }
    }

    /// The descriptions the frame set-ups take.
    pub fn descs(&self) -> Descs {
        let c = &self.camera;
        let camera = CameraDesc {
            position: v3(c.position),
            forward: v3(c.forward),
            right: v3(c.right),
            up: v3(c.up),
            tan_half_fov_y: c.tan_half_fov_y,
            near: c.near,
            far: c.far,
        };
        let light = match self.light {
            LightFile::Directional { direction, color } => LightDesc::Directional {
                direction: v3(direction),
                color,
            },
            LightFile::Spot {
                position,
                direction,
                inner_deg,
                outer_deg,
                color,
            } => LightDesc::Spot {
                position: v3(position),
                direction: v3(direction),
                inner_deg,
                outer_deg,
                color,
            },
            LightFile::Area {
                position,
                direction,
                up,
                shape,
                inner_deg,
                outer_deg,
                radiance,
                two_sided,
            } => LightDesc::Area(AreaLightDesc {
                position: v3(position),
                direction: v3(direction),
                up: up.map(v3),
                shape: match shape {
                    AreaShapeFile::Rect { width, height } => AreaShapeDesc::Rect { width, height },
                    AreaShapeFile::Disk { radius } => AreaShapeDesc::Disk { radius },
                },
                inner_deg,
                outer_deg,
                radiance,
                two_sided,
            }),
        };
        let medium = MediumDesc {
            sigma_t: self.medium.sigma_t,
            albedo: self.medium.albedo,
            g: self.medium.g,
        };
        let s = &self.shadow_map;
        let shadow = ShadowMapDesc {
            origin: v3(s.origin),
            basis: s.basis.map(v3),
            projection: match s.projection {
                ProjectionFile::Orthographic { x0, x1, y0, y1 } => {
                    ShadowProjectionDesc::Orthographic { x0, x1, y0, y1 }
                }
                ProjectionFile::Perspective { tan_half } => {
                    ShadowProjectionDesc::Perspective { tan_half }
                }
            },
            near: s.near,
            far: s.far,
            size: s.size,
            bias_texels: s.bias_texels,
        };
        let settings = match self.settings {
            Some(s) => FrameSettings {
                epipole_radius_px: s.epipole_radius_px,
                march_steps: s.march_steps,
                spot_quadrature: s.spot_quadrature,
                projective_max_half_angle_deg: s.projective_max_half_angle_deg,
                aligned_rows: None,
            },
            None => FrameSettings::for_screen(self.screen[0], self.screen[1]),
        };
        Descs {
            camera,
            light,
            medium,
            shadow_map: shadow,
            settings,
        }
    }
}

/// A [`FrameFile`]'s numbers as the frame set-ups' descriptions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Descs {
    /// The camera.
    pub camera: CameraDesc,
    /// The light.
    pub light: LightDesc,
    /// The medium.
    pub medium: MediumDesc,
    /// The standard shadow map.
    pub shadow_map: ShadowMapDesc,
    /// Frame settings (epipolar families).
    pub settings: FrameSettings,
}

/// Reads a greyscale PFM: `(width, height, values top row first)`.
///
/// # Errors
///
/// [`EngineError::Io`]; [`EngineError::InputFile`] for a malformed file.
pub fn read_pfm(path: &Path) -> Result<(u32, u32, Vec<f32>), EngineError> {
    let bytes = std::fs::read(path).map_err(EngineError::io(path))?;
    let bad = |reason: String| EngineError::InputFile {
        path: path.to_path_buf(),
        reason,
    };
    // Three whitespace-terminated header tokens, then one whitespace byte, then data.
    let mut tokens = Vec::new();
    let mut pos = 0;
    while tokens.len() < 3 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err(bad("truncated PFM header".to_owned()));
        }
        tokens.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    // Tokens: type, width, height; the scale follows.
    let magic = &tokens[0];
    if magic != "Pf" {
        return Err(bad(format!(
            "PFM type {magic:?}: expected a greyscale \"Pf\" file"
        )));
    }
    let width: u32 = tokens[1]
        .parse()
        .map_err(|_| bad(format!("bad width {:?}", tokens[1])))?;
    let height: u32 = tokens[2]
        .parse()
        .map_err(|_| bad(format!("bad height {:?}", tokens[2])))?;
    while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
        pos += 1;
    }
    let start = pos;
    while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
        pos += 1;
    }
    let scale: f32 = String::from_utf8_lossy(&bytes[start..pos])
        .parse()
        .map_err(|_| bad("bad scale".to_owned()))?;
    if scale == 0.0 || !scale.is_finite() {
        return Err(bad(format!(
            "scale {scale}: must be a finite non-zero number (negative for little-endian)"
        )));
    }
    pos += 1; // the single whitespace byte before the data
    let data = bytes.get(pos..).unwrap_or_default();
    // In 64 bits and checked: 4 * width * height overflows even u64 for the largest sizes.
    let needed = u64::from(width)
        .checked_mul(u64::from(height))
        .and_then(|n| n.checked_mul(4));
    if needed != Some(data.len() as u64) {
        return Err(bad(format!(
            "{width}x{height} needs {} data bytes, found {}",
            needed.map_or_else(|| "more than 2^64".to_owned(), |n| n.to_string()),
            data.len()
        )));
    }
    let count = data.len() / 4;
    let little = scale < 0.0;
    let mut values = vec![0.0f32; count];
    for (i, c) in data.chunks_exact(4).enumerate() {
        let b = [c[0], c[1], c[2], c[3]];
        let v = if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        };
        // PFM rows run bottom to top.
        let (x, y) = (i % width as usize, i / width as usize);
        values[(height as usize - 1 - y) * width as usize + x] = v;
    }
    Ok((width, height, values))
}

/// Writes a PFM: greyscale (`channels == 1`) or colour (`channels == 3`, from rgb or rgba
/// texels when `stride` is 4), values given top row first.
///
/// # Errors
///
/// [`EngineError::Io`].
pub fn write_pfm(
    path: &Path,
    width: u32,
    height: u32,
    values: &[f32],
    channels: usize,
    stride: usize,
) -> Result<(), EngineError> {
    let magic = if channels == 1 { "Pf" } else { "PF" };
    let mut out = format!("{magic}\n{width} {height}\n-1.0\n").into_bytes();
    for y in (0..height as usize).rev() {
        for x in 0..width as usize {
            let base = (y * width as usize + x) * stride;
            for c in 0..channels {
                let v = values.get(base + c).copied().unwrap_or(0.0);
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, out).map_err(EngineError::io(path))
}

/// Writes an input directory the binary reads: `frame.json`, `depth.pfm`, `shadow_map.pfm`
/// and, when given, `rectified.pfm`.
///
/// # Errors
///
/// [`EngineError::Io`].
pub fn write_inputs(
    dir: &Path,
    frame: &FrameFile,
    depth: &[f32],
    shadow_map: &[f32],
    rectified: Option<&[f32]>,
) -> Result<(), EngineError> {
    std::fs::create_dir_all(dir).map_err(EngineError::io(dir))?;
    let json = serde_json::to_string_pretty(frame).map_err(|e| EngineError::InputFile {
        path: dir.join(FRAME_FILE),
        reason: e.to_string(),
    })?;
    let path = dir.join(FRAME_FILE);
    std::fs::write(&path, json).map_err(EngineError::io(&path))?;
    let [w, h] = frame.screen;
    write_pfm(&dir.join(DEPTH_FILE), w, h, depth, 1, 1)?;
    let s = frame.shadow_map.size;
    write_pfm(&dir.join(SHADOW_MAP_FILE), s, s, shadow_map, 1, 1)?;
    if let Some(r) = rectified {
        let [wr, hr] = frame.rectified;
        write_pfm(&dir.join(RECTIFIED_FILE), wr, hr, r, 1, 1)?;
    }
    Ok(())
}

/// The frame description in an input directory.
pub const FRAME_FILE: &str = "frame.json";
/// The depth buffer.
pub const DEPTH_FILE: &str = "depth.pfm";
/// The standard shadow map.
pub const SHADOW_MAP_FILE: &str = "shadow_map.pfm";
/// The rasterised rectified map of a projective frame.
pub const RECTIFIED_FILE: &str = "rectified.pfm";
/// An area light's VPL shadow maps: one `size x size` map per VPL stacked top to bottom in
/// VPL order (`size` wide, `size * VPLs` tall), each rendered with the frame the set-up
/// gives its VPL (`scatter_frame::area_ivsv::prepare_area_light`).
pub const VPL_MAPS_FILE: &str = "vpl_maps.pfm";

/// Writes an area light's VPL shadow maps ([`VPL_MAPS_FILE`]) beside [`write_inputs`]'s files:
/// `maps` holds `layers` maps of `size` squared texels, layer after layer.
///
/// # Errors
///
/// [`EngineError::Io`] when a file cannot be written; [`EngineError::InputFile`] when `maps`
/// does not hold `layers` maps.
pub fn write_vpl_maps(dir: &Path, size: u32, layers: u32, maps: &[f32]) -> Result<(), EngineError> {
    let path = dir.join(VPL_MAPS_FILE);
    if maps.len() as u64 != u64::from(size) * u64::from(size) * u64::from(layers) {
        return Err(EngineError::InputFile {
            path,
            reason: format!("{} texels for {layers} maps of {size}x{size}", maps.len()),
        });
    }
    write_pfm(&path, size, size * layers, maps, 1, 1)
}

/// What [`run_dir`] needs.
#[derive(Clone, Debug)]
pub struct RunArgs {
    /// The scatter-gen directory.
    pub shaders: PathBuf,
    /// The variant id; `None` when the manifest has exactly one variant.
    pub variant: Option<String>,
    /// The input directory.
    pub inputs: PathBuf,
    /// Where to write the radiance (PFM); `None` writes nothing.
    pub out: Option<PathBuf>,
    /// SPIR-V or WGSL.
    pub target: Target,
}

/// What [`run_dir`] did.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// The variant id.
    pub variant: String,
    /// The variant's family (`prefiltered`, `raymarch`, `minmax`, `partial_sum_tree`,
    /// `hybrid_volume`).
    pub family: String,
    /// The epipolar frame set-up (prefiltered, minmax, partial_sum_tree and hybrid_volume; `None` for
    /// raymarch).
    pub frame: Option<PrefilteredFrame>,
    /// Passes run and skipped.
    pub run: FrameRun,
    /// Radiance, rgba per pixel.
    pub radiance: Vec<[f32; 4]>,
    /// Screen size.
    pub screen: [u32; 2],
}

fn read_sized(path: &Path, expected: [u32; 2]) -> Result<Vec<f32>, EngineError> {
    let (w, h, v) = read_pfm(path)?;
    if [w, h] != expected {
        return Err(EngineError::InputFile {
            path: path.to_path_buf(),
            reason: format!("{w}x{h}, frame.json says {}x{}", expected[0], expected[1]),
        });
    }
    Ok(v)
}

/// Reads the input directory, loads the variant, runs one frame and writes the output.
///
/// The variant's knobs come from the manifest (`knobs`), so the frame is set up for the
/// variant the shaders were generated for.
///
/// # Errors
///
/// Every [`EngineError`] of loading, reading inputs and running.
pub fn run_dir(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    args: &RunArgs,
) -> Result<RunSummary, EngineError> {
    let manifest = crate::Manifest::load(&args.shaders)?;
    let id = match &args.variant {
        Some(id) => id.clone(),
        None => match &manifest.variants[..] {
            [only] => only.id.clone(),
            _ => {
                return Err(EngineError::VariantRequired {
                    available: manifest
                        .variants
                        .iter()
                        .map(|v| v.id.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                });
            }
        },
    };
    let knobs = knobs_of(&manifest, &id)?;
    let frame_path = args.inputs.join(FRAME_FILE);
    let text = std::fs::read_to_string(&frame_path).map_err(EngineError::io(&frame_path))?;
    let file: FrameFile = serde_json::from_str(&text).map_err(|e| EngineError::InputFile {
        path: frame_path.clone(),
        reason: e.to_string(),
    })?;
    let depth = read_sized(&args.inputs.join(DEPTH_FILE), file.screen)?;
    let shadow = read_sized(
        &args.inputs.join(SHADOW_MAP_FILE),
        [file.shadow_map.size; 2],
    )?;
    let load = |params: &crate::formula::Params| {
        Engine::load(device, queue, &args.shaders, &id, args.target, params)
    };
    if knobs.cookie() {
        return Err(EngineError::Unsupported {
            context: format!("variant {id}"),
            what: "knob of the file runner (the spot's cookie has no input file; drive it \
                   through the library's run_frame with the cookie's texels)",
            value: "cookie = true".to_owned(),
        });
    }
    let (frame, out) = match &knobs {
        Knobs::Prefiltered(variant) => {
            let frame = file.prepare(variant)?;
            let rectified_path = args.inputs.join(RECTIFIED_FILE);
            let rectified = if frame.report.projective.is_some() {
                if !rectified_path.exists() {
                    return Err(EngineError::InputFile {
                        path: rectified_path,
                        reason: "this frame is projective: rasterise the rectified map with \
                                 the frame's per-region matrices (FrameReport::projective) and \
                                 store it here"
                            .to_owned(),
                    });
                }
                Some(read_sized(&rectified_path, file.rectified)?)
            } else {
                None
            };
            let mut engine = load(&file.sizes().params())?;
            let out = run_frame(
                &mut engine,
                &frame,
                &Inputs {
                    depth: &depth,
                    shadow_map: Some(&shadow),
                    rectified_raster: rectified.as_deref(),
                    cookie: None,
                },
            )?;
            (Some(frame), out)
        }
        Knobs::HybridVolume(variant) => {
            let frame = file.prepare_hybrid_volume(variant)?;
            let mut engine = load(&crate::hybrid_volume::params(&file.sizes()))?;
            let out = crate::hybrid_volume::run_frame(&mut engine, &frame, &depth, &shadow, None)?;
            (Some(frame), out)
        }
        Knobs::Minmax(variant) => {
            let frame = file.prepare_minmax(variant)?;
            let mut engine = load(&crate::minmax::params(&file.sizes()))?;
            let out = crate::minmax::run_frame(&mut engine, &frame, &depth, &shadow, None)?;
            (Some(frame), out)
        }
        Knobs::PartialSumTree(variant) => {
            let frame = file.prepare_partial_sum_tree(variant)?;
            let mut engine = load(&file.sizes().params())?;
            let out =
                crate::partial_sum_tree::run_frame(&mut engine, &frame, &depth, &shadow, None)?;
            (Some(frame.frame), out)
        }
        Knobs::AreaIvsv(variant) => {
            let d = file.descs();
            let (frame, _) = prepare_area_light(
                variant,
                file.screen,
                &d.camera,
                &d.light,
                &d.medium,
                &d.shadow_map,
            )
            .map_err(EngineError::Frame)?;
            let size = file.shadow_map.size;
            let maps = read_sized(
                &args.inputs.join(VPL_MAPS_FILE),
                [size, size.saturating_mul(variant.vpls)],
            )?;
            let sizes = crate::area_ivsv::Sizes {
                screen: file.screen,
                shadow_map: size,
            };
            let mut engine = load(&sizes.params())?;
            let out = crate::area_ivsv::run_frame(&mut engine, &frame, &depth, &maps)?;
            (None, out)
        }
        Knobs::Raymarch(variant) => {
            let uniforms = file.prepare_raymarch(variant)?;
            let sizes = crate::raymarch::Sizes {
                screen: file.screen,
                shadow_map: file.shadow_map.size,
            };
            let mut engine = load(&sizes.params())?;
            let out = crate::raymarch::run_frame(&mut engine, &uniforms, &depth, &shadow, None)?;
            (None, out)
        }
    };
    if let Some(path) = &args.out {
        let flat: Vec<f32> = out.radiance.iter().flatten().copied().collect();
        write_pfm(path, file.screen[0], file.screen[1], &flat, 3, 4)?;
    }
    Ok(RunSummary {
        variant: id,
        family: knobs.family().to_owned(),
        frame,
        run: out.run,
        radiance: out.radiance,
        screen: file.screen,
    })
}

/// The validated knobs of a manifest variant, by family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Knobs {
    /// A `prefiltered` variant.
    Prefiltered(PrefilteredVariant),
    /// A `raymarch` variant.
    Raymarch(RaymarchVariant),
    /// A `minmax` variant.
    Minmax(MinmaxVariant),
    /// A `hybrid_volume` variant.
    HybridVolume(HybridVolumeVariant),
    /// A `partial_sum_tree` variant.
    PartialSumTree(PartialSumTreeVariant),
    /// An `area_ivsv` variant.
    AreaIvsv(AreaIvsvVariant),
}

impl Knobs {
    /// Whether the variant reads a spot's cookie.
    pub fn cookie(&self) -> bool {
        match self {
            Knobs::Raymarch(v) => v.cookie,
            Knobs::Minmax(v) => v.cookie,
            Knobs::HybridVolume(v) => v.cookie,
            Knobs::Prefiltered(v) => v.cookie,
            Knobs::PartialSumTree(v) => v.cookie,
            Knobs::AreaIvsv(_) => false,
        }
    }
}

impl Knobs {
    /// The family's name as the manifest spells it.
    pub const fn family(&self) -> &'static str {
        match self {
            Self::Prefiltered(_) => "prefiltered",
            Self::Raymarch(_) => "raymarch",
            Self::Minmax(_) => "minmax",
            Self::HybridVolume(_) => "hybrid_volume",
            Self::PartialSumTree(_) => "partial_sum_tree",
            Self::AreaIvsv(_) => "area_ivsv",
        }
    }
}

/// Parses and validates one family's knobs and checks they describe variant `id`.
fn parse_knobs<V: serde::de::DeserializeOwned>(
    entry: &crate::manifest::VariantEntry,
    validate: impl Fn(&V) -> Result<(), String>,
    variant_id: impl Fn(&V) -> String,
) -> Result<V, EngineError> {
    let id = &entry.id;
    let variant: V = serde_json::from_value(entry.knobs.clone())
        .map_err(|e| EngineError::Inconsistent(format!("knobs of variant {id}: {e}")))?;
    validate(&variant)
        .map_err(|e| EngineError::Inconsistent(format!("knobs of variant {id}: {e}")))?;
    if variant_id(&variant) != *id {
        return Err(EngineError::Inconsistent(format!(
            "the knobs of variant {id} describe variant {}",
            variant_id(&variant)
        )));
    }
    Ok(variant)
}

/// The knobs of manifest entry `id`, by its family.
///
/// # Errors
///
/// [`EngineError::UnknownVariant`]; [`EngineError::Unsupported`] for a family this engine
/// does not know; [`EngineError::Inconsistent`] when the knobs do not describe a valid
/// variant of the family, or another variant than `id`.
pub fn knobs_of(manifest: &crate::Manifest, id: &str) -> Result<Knobs, EngineError> {
    let entry = manifest.variant(id)?;
    match entry.family.as_str() {
        "prefiltered" => parse_knobs(
            entry,
            |v: &PrefilteredVariant| v.validate().map_err(|e| e.to_string()),
            PrefilteredVariant::id,
        )
        .map(Knobs::Prefiltered),
        "raymarch" => parse_knobs(
            entry,
            |v: &RaymarchVariant| v.validate().map_err(|e| e.to_string()),
            RaymarchVariant::id,
        )
        .map(Knobs::Raymarch),
        "minmax" => parse_knobs(
            entry,
            |v: &MinmaxVariant| v.validate().map_err(|e| e.to_string()),
            MinmaxVariant::id,
        )
        .map(Knobs::Minmax),
        "hybrid_volume" => parse_knobs(
            entry,
            |v: &HybridVolumeVariant| v.validate().map_err(|e| e.to_string()),
            HybridVolumeVariant::id,
        )
        .map(Knobs::HybridVolume),
        "partial_sum_tree" => parse_knobs(
            entry,
            |v: &PartialSumTreeVariant| v.validate().map_err(|e| e.to_string()),
            PartialSumTreeVariant::id,
        )
        .map(Knobs::PartialSumTree),
        "area_ivsv" => parse_knobs(
            entry,
            |v: &AreaIvsvVariant| v.validate().map_err(|e| e.to_string()),
            AreaIvsvVariant::id,
        )
        .map(Knobs::AreaIvsv),
        _ => Err(EngineError::Unsupported {
            context: format!("variant {id}"),
            what: "family",
            value: entry.family.clone(),
        }),
    }
}
