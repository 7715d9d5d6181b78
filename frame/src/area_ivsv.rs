//! The `area_ivsv` family (Wyman & Dai 2013, "Imperfect voxelized shadow volumes"): an area
//! light as `N` virtual point lights (VPLs), each a spot with its own standard shadow map;
//! per VPL an epipolar voxel grid about the eye-VPL axis of `alpha` (eye angle) x `theta`
//! (plane angle) texels of 128 `phi` (light angle) bits, rectified from the VPL's map
//! (`ivsv_rectify`), extruded by an OR scan along `alpha` (`ivsv_scan`) and gathered per pixel
//! with the integrand weighted in `phi` (`ivsv_gather`). The f64 method the kernels implement,
//! with the derivations: `scatter_reference::area_ivsv`. [`AreaIvsvVariant`] holds the knobs;
//! [`prepare_area_ivsv`] sets up a frame from the camera, the medium and the VPLs (each a
//! spot light and its shadow map's description).
//!
//! # Grid
//!
//! Per VPL: the axis `a` from the eye to the VPL (distance `D`), `b1` normal to it (world `y`
//! crossed in, or `x` when `a` is nearly vertical), `b2 = a x b1`. `theta` bins cover
//! `[-pi, pi)`; `alpha` bins cover the eye angles of the screen (`[alpha_0, alpha_0 +
//! alpha d_alpha]`: 0 when the VPL projects inside the screen, `pi` when the point opposite
//! does, else the extremes over 64 points per screen edge, widened by one bin); the 128 bits
//! cover `phi` in `[0, phi_max]`, `phi_max = pi - alpha_0`. Voxel bits: a storage buffer of
//! `4 N theta alpha` `u32`, texel `(i, j)` of VPL `v` at `4 ((v theta + j) alpha + i)`.

use std::fmt;

use crate::family::{Family, KnobSet};
use crate::frame::v4;
use crate::sampling::{Sampling, SamplingKnobs};
use crate::scene::{
    CameraDesc, FrameError, LightDesc, MediumDesc, ShadowMapDesc, ShadowProjectionDesc,
    finite_fields, require, validate_scene, validate_shadow_map,
};
use crate::variant::{LightKind, VariantError};
use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// `phi` bits per voxel texel (a `vec4<u32>`).
pub const PHI_BITS: u32 = 128;
/// The most VPLs (shadow-map layers; WebGPU's `max_texture_array_layers` default is 256).
pub const MAX_VPLS: u32 = 256;
/// The most `alpha` or `theta` bins.
pub const MAX_BINS: u32 = 4096;
/// The most segments of the integrand in `phi`.
pub const MAX_SEGMENTS: u32 = 32;
/// The largest voxel buffer (bytes): WebGPU's default `max_storage_buffer_binding_size`.
pub const MAX_VOXEL_BYTES: u64 = 1 << 27;

/// The knobs of the `area_ivsv` family. `Default`: 64 VPLs, 256 x 256 texels, 8 segments
/// (`scatter_reference::area_ivsv::IvsvSettings`'s measurements).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AreaIvsvVariant {
    /// Must be `area` (the family renders area lights; a spot is the single-light
    /// families').
    pub light: LightKind,
    /// VPLs, 1..=256: the shadow maps (layers of `vpl_maps`) and voxel grids per frame.
    pub vpls: u32,
    /// `alpha` bins (texels per row), 2..=4096.
    pub alpha: u32,
    /// `theta` bins (rows per VPL), 2..=4096.
    pub theta: u32,
    /// Pieces of the cone's `phi` interval the integrand is linear on, a power of two in
    /// 1..=32 (a template constant: the loop of `ivsv_gather`).
    pub segments: u32,
    /// Interleaved gather (the paper's): 1 (every pixel gathers every VPL), 2 or 4: pixel
    /// class `c = (x mod M) + M (y mod M)` gathers the `c`-th of `M^2` runs of consecutive
    /// VPLs and
    /// `ivsv_interleave_sum` adds the `M x M` window around each pixel (`vpls` a multiple
    /// of `M^2`).
    #[serde(skip_serializing_if = "is_one")]
    pub interleave: u32,
    /// Where `ivsv_gather` runs: every pixel, a low-resolution grid or epipolar samples
    /// ([`crate::sampling`]; `interleave` must be 1 when sampled).
    pub sampling: Sampling,
    /// `sampling = lowres`: the block side, 2 or 4.
    pub scale: u32,
    /// `sampling = lowres | epipolar`: the depth break in percent of the nearer depth.
    pub depth_break: u32,
    /// `sampling = lowres | epipolar`: the light break in percent of the brightest sample.
    pub light_break: u32,
    /// `sampling = epipolar`: epipolar slices (radiating from the VPLs' centroid).
    pub slices: u32,
    /// `sampling = epipolar`: samples per slice.
    pub slice_samples: u32,
    /// `sampling = epipolar`: the initial step between evaluated samples of a slice.
    pub step: u32,
}

crate::sampling::sampling_fields!(AreaIvsvVariant);

fn is_one(v: &u32) -> bool {
    *v == 1
}

impl Default for AreaIvsvVariant {
    fn default() -> Self {
        let s = SamplingKnobs::default();
        AreaIvsvVariant {
            light: LightKind::Area,
            vpls: 64,
            alpha: 256,
            theta: 256,
            segments: 8,
            interleave: 1,
            sampling: s.sampling,
            scale: s.scale,
            depth_break: s.depth_break,
            light_break: s.light_break,
            slices: s.slices,
            slice_samples: s.slice_samples,
            step: s.step,
        }
    }
}

impl AreaIvsvVariant {
    /// Checks every knob; the error names the first offending one.
    pub fn validate(&self) -> Result<(), VariantError> {
        if self.light != LightKind::Area {
            return Err(VariantError {
                knob: "light",
                value: self.light.to_string(),
                allowed: "area (directional and spot lights are the single-light families')".into(),
            });
        }
        self.sampling_knobs().validate()?;
        if self.interleave > 1 && self.sampling_knobs().is_sampled() {
            return Err(VariantError {
                knob: "interleave",
                value: self.interleave.to_string(),
                allowed: format!(
                    "1 with sampling = {} (interleaving spreads a pixel's VPLs over its \
                     neighbours, which a sampled variant does not evaluate)",
                    self.sampling
                ),
            });
        }
        let range = |knob: &'static str, value: u32, lo: u32, hi: u32| {
            if (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(VariantError {
                    knob,
                    value: value.to_string(),
                    allowed: format!("in {lo}..={hi}"),
                })
            }
        };
        range("vpls", self.vpls, 1, MAX_VPLS)?;
        range("alpha", self.alpha, 2, MAX_BINS)?;
        range("theta", self.theta, 2, MAX_BINS)?;
        if !(self.segments.is_power_of_two() && self.segments <= MAX_SEGMENTS) {
            return Err(VariantError {
                knob: "segments",
                value: self.segments.to_string(),
                allowed: format!("a power of two in 1..={MAX_SEGMENTS}"),
            });
        }
        if !matches!(self.interleave, 1 | 2 | 4) {
            return Err(VariantError {
                knob: "interleave",
                value: self.interleave.to_string(),
                allowed: "1, 2 or 4".into(),
            });
        }
        let classes = self.interleave * self.interleave;
        if !self.vpls.is_multiple_of(classes) {
            return Err(VariantError {
                knob: "vpls",
                value: self.vpls.to_string(),
                allowed: format!(
                    "a multiple of interleave^2 = {classes} (every pixel class gathers as many VPLs)"
                ),
            });
        }
        if self.voxel_bytes() > MAX_VOXEL_BYTES {
            return Err(VariantError {
                knob: "vpls x alpha x theta",
                value: format!(
                    "{} x {} x {} ({} MiB of voxels)",
                    self.vpls,
                    self.alpha,
                    self.theta,
                    self.voxel_bytes() >> 20
                ),
                allowed: format!(
                    "at most {} MiB of voxels (16 bytes per texel; WebGPU's storage binding limit)",
                    MAX_VOXEL_BYTES >> 20
                ),
            });
        }
        Ok(())
    }

    /// Bytes of one voxel buffer (`marks`, `volume`): 16 per texel.
    pub fn voxel_bytes(&self) -> u64 {
        16 * u64::from(self.vpls) * u64::from(self.alpha) * u64::from(self.theta)
    }

    /// A short stable id: `v64-a256-t256-k8`, `v64-a256-t256-k8-i2`,
    /// `v64-a256-t256-k8-epi512x256-s8-b10-l20`.
    pub fn id(&self) -> String {
        self.label_with(&self.sampling_knobs().id_suffix())
    }

    /// The short label of tables and charts: `v64-a256-t256-k8`, `v64-a256-t256-k8-ep512`.
    pub fn marker(&self) -> String {
        self.label_with(&self.sampling_knobs().marker_suffix())
    }

    /// `v{vpls}-a{alpha}-t{theta}-k{segments}`, `-i{M}` when interleaved, then `sampling`.
    fn label_with(&self, sampling: &str) -> String {
        let interleave = if self.interleave > 1 {
            format!("-i{}", self.interleave)
        } else {
            String::new()
        };
        format!(
            "v{}-a{}-t{}-k{}{interleave}{sampling}",
            self.vpls, self.alpha, self.theta, self.segments
        )
    }
}

impl AreaIvsvVariant {
    /// The conformance grid: small grids that exercise every knob (a VPL count that is not
    /// a power of two, bins that are not, every segment count's loop shape, both interleaves).
    pub fn grid() -> Vec<AreaIvsvVariant> {
        let v = |vpls, alpha, theta, segments, interleave| AreaIvsvVariant {
            vpls,
            alpha,
            theta,
            segments,
            interleave,
            ..AreaIvsvVariant::default()
        };
        vec![
            v(8, 64, 64, 8, 1),
            v(3, 37, 19, 1, 1),
            v(4, 128, 96, 32, 1),
            v(8, 64, 64, 8, 2),
            v(16, 64, 48, 4, 4),
        ]
    }
}

impl fmt::Display for AreaIvsvVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.id())
    }
}

impl KnobSet for AreaIvsvVariant {
    const FAMILY_NAME: &'static str = "area_ivsv";
    const FAMILY: Family = Family::AreaIvsv;
    const SUMMARY: &'static str = "Wyman & Dai 2013, imperfect voxelized shadow volumes: an area \
         light as N virtual point lights, per VPL an epipolar voxel grid of shadow bits, \
         extruded by an OR scan and gathered per pixel";

    fn validate(&self) -> Result<(), VariantError> {
        AreaIvsvVariant::validate(self)
    }

    fn id(&self) -> String {
        AreaIvsvVariant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    fn with_light(self, light: LightKind) -> Self {
        Self { light, ..self }
    }

    /// `v64-a256-t256-k8`, `v64-a256-t256-k8-lr2` (every knob but the light).
    fn marker(&self) -> String {
        AreaIvsvVariant::marker(self)
    }

    fn grid() -> Vec<Self> {
        AreaIvsvVariant::grid()
    }

    fn sampling(&self) -> SamplingKnobs {
        self.sampling_knobs()
    }

    fn with_sampling(self, s: SamplingKnobs) -> Self {
        self.with_sampling_knobs(s)
    }
}

/// The uniform block of the family's kernels (WGSL `struct IvsvFrame`). Every field is a
/// 16-byte vector; the asserts below pin the layout.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct IvsvUniforms {
    /// Eye position; w = camera far (view depths are clamped to it).
    pub eye: [f32; 4],
    /// Camera forward; w = tan(fov_y / 2).
    pub cam_forward: [f32; 4],
    /// Camera right; w = aspect (width / height).
    pub cam_right: [f32; 4],
    /// Camera up; w unused.
    pub cam_up: [f32; 4],
    /// sigma_t, sigma_s, g, unused.
    pub medium: [f32; 4],
    /// Screen width, height, VPL shadow-map size, VPL count.
    pub sizes: [u32; 4],
    /// `alpha` bins, `theta` bins, interleave `M`, unused.
    pub grid: [u32; 4],
    /// The VPLs' centroid (where epipolar sampling puts the light: its slices radiate from
    /// its screen point); w unused.
    pub centre: [f32; 4],
}

const _: () = {
    assert!(size_of::<IvsvUniforms>() == 8 * 16);
    assert!(std::mem::offset_of!(IvsvUniforms, medium) == 4 * 16);
    assert!(std::mem::offset_of!(IvsvUniforms, sizes) == 5 * 16);
    assert!(std::mem::offset_of!(IvsvUniforms, grid) == 6 * 16);
    assert!(std::mem::offset_of!(IvsvUniforms, centre) == 7 * 16);
};

/// One VPL's record (WGSL `struct Vpl`, an element of the `vpls` storage buffer).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct VplRecord {
    /// Position; w = `D`, the eye-VPL distance.
    pub position: [f32; 4],
    /// Intensity (rgb); w = cos(outer angle).
    pub color: [f32; 4],
    /// Unit axis from the eye to the VPL; w = `alpha_0`.
    pub axis: [f32; 4],
    /// `b1` (`theta = 0`); w = `alpha` bin width.
    pub perp_x: [f32; 4],
    /// `b2 = axis x b1` (`theta = pi / 2`); w = `phi_max`.
    pub perp_y: [f32; 4],
    /// Spot axis; w = cos(inner angle).
    pub spot_dir: [f32; 4],
    /// Shadow-map right; w = near.
    pub sm_right: [f32; 4],
    /// Shadow-map up; w = far.
    pub sm_up: [f32; 4],
    /// Shadow-map forward; w = bias in texel footprints.
    pub sm_forward: [f32; 4],
    /// Shadow-map origin; w = 1 (perspective).
    pub sm_origin: [f32; 4],
    /// tan(half field of view), 0, 0, 0.
    pub sm_proj: [f32; 4],
}

const _: () = {
    assert!(size_of::<VplRecord>() == 11 * 16);
    assert!(std::mem::offset_of!(VplRecord, spot_dir) == 5 * 16);
    assert!(std::mem::offset_of!(VplRecord, sm_proj) == 10 * 16);
};

/// One VPL of a frame: a spot light and its standard shadow map (perspective, from the
/// spot's position), the layer of `vpl_maps` at its index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VplInput {
    /// The VPL (a [`LightDesc::Spot`]).
    pub light: LightDesc,
    /// Its shadow map.
    pub shadow_map: ShadowMapDesc,
}

/// One VPL's epipolar grid (f64; what its record stores).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VplGrid {
    /// Unit axis from the eye to the VPL.
    pub axis: DVec3,
    /// `b1`, `b2`.
    pub basis: [DVec3; 2],
    /// Eye-VPL distance.
    pub distance: f64,
    /// The `alpha` range the bins cover.
    pub alpha_range: (f64, f64),
    /// `phi` range of the bits: `[0, phi_max]`.
    pub phi_max: f64,
}

/// A frame's set-up: the uniforms and one record per VPL, with their grids.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaIvsvFrame {
    /// The `frame` uniform block.
    pub uniforms: IvsvUniforms,
    /// The `vpls` buffer.
    pub vpls: Vec<VplRecord>,
    /// Each VPL's grid.
    pub grids: Vec<VplGrid>,
}

/// The unit direction of screen point `(x, y)` (continuous, `[0, w] x [0, h]`).
fn screen_dir(cam: &CameraDesc, screen: [u32; 2], x: f64, y: f64) -> DVec3 {
    let (w, h) = (f64::from(screen[0]), f64::from(screen[1]));
    let t = cam.tan_half_fov_y;
    let ndc_x = 2.0 * x / w - 1.0;
    let ndc_y = 1.0 - 2.0 * y / h;
    (cam.forward + cam.right * (ndc_x * t * w / h) + cam.up * (ndc_y * t)).normalize()
}

/// Whether direction `d` from the eye projects inside the screen.
fn on_screen(cam: &CameraDesc, screen: [u32; 2], d: DVec3) -> bool {
    let z = d.dot(cam.forward);
    if z <= 0.0 {
        return false;
    }
    let t = cam.tan_half_fov_y;
    let aspect = f64::from(screen[0]) / f64::from(screen[1]);
    let x = d.dot(cam.right) / (z * t * aspect);
    let y = d.dot(cam.up) / (z * t);
    x.abs() <= 1.0 && y.abs() <= 1.0
}

/// Angle in `[0, pi]` between unit vectors.
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The grid of a VPL at `light` for the eye of `cam`, `alpha` bins fitted to the screen.
pub fn fit_grid(cam: &CameraDesc, screen: [u32; 2], light: DVec3, alpha_bins: u32) -> VplGrid {
    let d = light - cam.position;
    let distance = d.length();
    let axis = d / distance;
    let helper = if axis.y.abs() < 0.99 {
        DVec3::Y
    } else {
        DVec3::X
    };
    let b1 = axis.cross(helper).normalize();
    let b2 = axis.cross(b1);
    let (w, h) = (f64::from(screen[0]), f64::from(screen[1]));
    let (mut lo, mut hi) = (PI, 0.0f64);
    for k in 0..=64 {
        let f = f64::from(k) / 64.0;
        for (x, y) in [(f * w, 0.0), (f * w, h), (0.0, f * h), (w, f * h)] {
            let a = angle(screen_dir(cam, screen, x, y), axis);
            lo = lo.min(a);
            hi = hi.max(a);
        }
    }
    if on_screen(cam, screen, axis) {
        lo = 0.0;
    }
    if on_screen(cam, screen, -axis) {
        hi = PI;
    }
    let pad = (hi - lo) / f64::from(alpha_bins);
    let alpha_range = ((lo - pad).max(0.0), (hi + pad).min(PI));
    VplGrid {
        axis,
        basis: [b1, b2],
        distance,
        alpha_range,
        phi_max: (PI - alpha_range.0).max(1e-6),
    }
}

/// Sets up one frame: the uniforms and the VPL records (grids fitted to the screen).
///
/// # Errors
///
/// [`FrameError`] for a bad knob, a size out of range, a VPL count other than the
/// variant's, a VPL that is not a spot light or whose map is not a perspective map of the
/// variant's size, the eye on a VPL, or non-finite input (each check names the number).
pub fn prepare_area_ivsv(
    variant: &AreaIvsvVariant,
    screen: [u32; 2],
    camera: &CameraDesc,
    medium: &MediumDesc,
    vpls: &[VplInput],
    map_size: u32,
) -> Result<AreaIvsvFrame, FrameError> {
    variant.validate().map_err(FrameError::Variant)?;
    for (what, value, max) in [
        ("screen width", screen[0], 16384),
        ("screen height", screen[1], 16384),
        ("VPL shadow map size", map_size, 16384),
    ] {
        if value == 0 || value > max {
            return Err(FrameError::Size { what, value, max });
        }
    }
    require(
        screen[0] >= variant.interleave && screen[1] >= variant.interleave,
        "screen size",
        "at least `interleave` pixels on each side (the interleaving window)",
        || {
            format!(
                "{}x{} for interleave {}",
                screen[0], screen[1], variant.interleave
            )
        },
    )?;
    require(
        vpls.len() == variant.vpls as usize,
        "VPL count",
        "the variant's `vpls`",
        || format!("{} VPLs for a variant of {}", vpls.len(), variant.vpls),
    )?;
    let mut records = Vec::with_capacity(vpls.len());
    let mut grids = Vec::with_capacity(vpls.len());
    let mut cam = *camera;
    let mut centroid = DVec3::ZERO;
    for vpl in vpls {
        let sc = validate_scene(LightKind::Spot, camera, &vpl.light, medium)?;
        centroid += sc.light_pos / vpls.len() as f64;
        cam = sc.cam;
        let sm = &vpl.shadow_map;
        validate_shadow_map(sm)?;
        let ShadowProjectionDesc::Perspective { tan_half } = sm.projection else {
            return Err(FrameError::OutOfRange {
                what: "VPL shadow map projection",
                allowed: "perspective (a VPL is a spot)",
                value: "orthographic".into(),
            });
        };
        require(
            sm.size == map_size,
            "VPL shadow map size",
            "the same for every VPL",
            || format!("{} and {map_size}", sm.size),
        )?;
        if sc.dist <= 1e-9 * sc.light_pos.abs().max_element().max(1.0) {
            return Err(FrameError::EyeAtLight);
        }
        let g = fit_grid(&cam, screen, sc.light_pos, variant.alpha);
        let d_alpha = (g.alpha_range.1 - g.alpha_range.0) / f64::from(variant.alpha);
        let r = VplRecord {
            position: v4(sc.light_pos, g.distance),
            color: [
                sc.color[0] as f32,
                sc.color[1] as f32,
                sc.color[2] as f32,
                sc.cos_out as f32,
            ],
            axis: v4(g.axis, g.alpha_range.0),
            perp_x: v4(g.basis[0], d_alpha),
            perp_y: v4(g.basis[1], g.phi_max),
            spot_dir: v4(sc.light_dir, sc.cos_in),
            sm_right: v4(sm.basis[0], sm.near),
            sm_up: v4(sm.basis[1], sm.far),
            sm_forward: v4(sm.basis[2], sm.bias_texels),
            sm_origin: v4(sm.origin, 1.0),
            sm_proj: [tan_half as f32, 0.0, 0.0, 0.0],
        };
        finite_fields([
            ("VPL position", r.position),
            ("VPL color", r.color),
            ("VPL axis", r.axis),
            ("VPL perp_x", r.perp_x),
            ("VPL perp_y", r.perp_y),
            ("VPL spot_dir", r.spot_dir),
            ("VPL sm_right", r.sm_right),
            ("VPL sm_up", r.sm_up),
            ("VPL sm_forward", r.sm_forward),
            ("VPL sm_origin", r.sm_origin),
            ("VPL sm_proj", r.sm_proj),
        ])?;
        records.push(r);
        grids.push(g);
    }
    let uniforms = IvsvUniforms {
        eye: v4(cam.position, cam.far),
        cam_forward: v4(cam.forward, cam.tan_half_fov_y),
        cam_right: v4(cam.right, f64::from(screen[0]) / f64::from(screen[1])),
        cam_up: v4(cam.up, 0.0),
        medium: [
            medium.sigma_t as f32,
            (medium.sigma_t * medium.albedo) as f32,
            medium.g as f32,
            0.0,
        ],
        sizes: [screen[0], screen[1], map_size, variant.vpls],
        grid: [variant.alpha, variant.theta, variant.interleave, 0],
        centre: v4(centroid, 0.0),
    };
    finite_fields([
        ("eye", uniforms.eye),
        ("cam_forward", uniforms.cam_forward),
        ("cam_right", uniforms.cam_right),
        ("cam_up", uniforms.cam_up),
        ("medium", uniforms.medium),
        ("centre", uniforms.centre),
    ])?;
    Ok(AreaIvsvFrame {
        uniforms,
        vpls: records,
        grids,
    })
}

/// Sets up one frame of an area light ([`LightDesc::Area`]): its `variant.vpls` VPLs and
/// their shadow maps ([`crate::area_light::AreaLightDesc::vpl_inputs`], from `template`, the
/// standard shadow map of the light's point limit), then [`prepare_area_ivsv`]. Returns the
/// frame and the VPLs: layer `i` of the engine's VPL map array is rendered with
/// `vpls[i].shadow_map`.
///
/// # Errors
///
/// [`FrameError::LightMismatch`] for a light that is not an area light; the errors of
/// [`crate::area_light::AreaLightDesc::vpl_inputs`] and [`prepare_area_ivsv`].
pub fn prepare_area_light(
    variant: &AreaIvsvVariant,
    screen: [u32; 2],
    camera: &CameraDesc,
    light: &LightDesc,
    medium: &MediumDesc,
    template: &ShadowMapDesc,
) -> Result<(AreaIvsvFrame, Vec<VplInput>), FrameError> {
    let LightDesc::Area(area) = light else {
        return Err(FrameError::LightMismatch {
            expected: LightKind::Area,
            got: light.kind(),
        });
    };
    variant.validate().map_err(FrameError::Variant)?;
    let vpls = area.vpl_inputs(variant.vpls, template)?;
    let frame = prepare_area_ivsv(variant, screen, camera, medium, &vpls, template.size)?;
    Ok((frame, vpls))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_knobs_are_named() {
        for (v, knob) in [
            (
                AreaIvsvVariant {
                    vpls: 0,
                    ..AreaIvsvVariant::default()
                },
                "vpls",
            ),
            (
                AreaIvsvVariant {
                    alpha: 1,
                    ..AreaIvsvVariant::default()
                },
                "alpha",
            ),
            (
                AreaIvsvVariant {
                    segments: 3,
                    ..AreaIvsvVariant::default()
                },
                "segments",
            ),
            (
                AreaIvsvVariant {
                    vpls: 256,
                    ..AreaIvsvVariant::default()
                },
                "vpls x alpha x theta",
            ),
        ] {
            assert_eq!(v.validate().unwrap_err().knob, knob);
        }
        for (v, knob) in [
            (
                AreaIvsvVariant {
                    interleave: 3,
                    ..AreaIvsvVariant::default()
                },
                "interleave",
            ),
            (
                AreaIvsvVariant {
                    vpls: 6,
                    interleave: 2,
                    ..AreaIvsvVariant::default()
                },
                "vpls",
            ),
        ] {
            assert_eq!(v.validate().unwrap_err().knob, knob);
        }
        AreaIvsvVariant::default().validate().unwrap();
        assert_eq!(AreaIvsvVariant::default().id(), "v64-a256-t256-k8");
    }

    #[test]
    fn sampling_knobs_are_the_stage_s() {
        let epipolar = AreaIvsvVariant::default()
            .with_sampling_knobs(SamplingKnobs::epipolar(SamplingKnobs::DEFAULT_SLICES));
        epipolar.validate().unwrap();
        assert_eq!(epipolar.id(), "v64-a256-t256-k8-epi512x256-s8-b10-l20");
        assert_eq!(epipolar.marker(), "v64-a256-t256-k8-ep512");
        let lowres = AreaIvsvVariant::default().with_sampling_knobs(SamplingKnobs::lowres(4));
        lowres.validate().unwrap();
        assert_eq!(lowres.marker(), "v64-a256-t256-k8-lr4");
        // Interleaving spreads a pixel's VPLs over neighbours a sampled variant does not
        // evaluate.
        let both = AreaIvsvVariant {
            interleave: 2,
            ..lowres
        };
        assert_eq!(both.validate().unwrap_err().knob, "interleave");
        // The stage's own checks name its knobs.
        let bad = AreaIvsvVariant { scale: 3, ..lowres };
        assert_eq!(bad.validate().unwrap_err().knob, "scale");
    }
}
