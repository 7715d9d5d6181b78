//! The epipolar frame set-up every epipolar family builds on (`prefiltered`, `minmax`): the
//! epipolar (or projective) rectification of the current camera and light, packed into the
//! uniform block ([`FrameUniforms`], WGSL `scatter::epipolar::Frame`) and the per-slice table
//! ([`SliceParams`]) the kernels read. The scene descriptions and their validation live in
//! [`crate::scene`] (re-exported here under their old paths).
//!
//! # Rectified space (epipolar, Klehm et al. 2014 Sec. 4.1 after Baran et al. 2010)
//!
//! The *axis* `A` is the unit direction from the eye towards the light (the sun, or the spot
//! position). Every view ray lies in one half-plane bounded by the axis (an epipolar slice),
//! at angle `phi = atan2(dir . e2, dir . e1)` around it, and makes the angle
//! `theta = acos(dir . A)` with it.
//!
//! - row `y`: slice; `phi = phi0 + (y + 0.5) dphi` at the centre of row `y`, uniform over the
//!   slices that the screen covers (all of them when the epipole or the anti-epipole is on
//!   screen);
//! - column `x`: one light ray of the slice. Directional: the light ray at distance
//!   `v = (x + 0.5) delta` from the axis (light rays are parallel to it). Spot: the ray
//!   leaving the light at angle `psi = (x + 0.5) delta` from the direction light -> eye.
//!   Column 0 passes through the eye, so every view ray is the row segment `[0, x_s]`;
//! - stored depth: the view angle `theta` of the first occluder on that light ray, normalised
//!   to `d = (theta - theta_lo) / (theta_hi - theta_lo)` and clamped to [0, 1]. A point of a
//!   view ray with normalised angle `d_r` is lit iff `d_r <= d` (Klehm's `H(z_i - z_r)`).
//!
//! Per slice the reference ray is the bisectrix of the slice's view-angle range inside the
//! frustum (`theta_ref`), `delta` is chosen so the row spans the slice's far-plane extent.
//! Occluders between the light and the frustum project to `d = 0` (clamped): they shadow
//! the whole light ray, as in the paper.
//!
//! # Rectified space (projective, Sec. 4.2)
//!
//! For a variant with `rectification = projective`, a frame whose slices fan out by at most
//! [`FrameSettings::projective_max_half_angle_deg`] around their bisectrix (so neither
//! epipole is on screen) uses a projective map instead: see [`ProjectiveMaps`] for what the
//! engine rasterises and `projective_frame` (private) for the coordinates. Other frames fall
//! back to the epipolar map above and say why in [`FrameReport::fallback`]; the same
//! kernels handle both (`FrameUniforms::proj[0]` selects).

use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec3, DVec4};
use std::f64::consts::PI;

use crate::sampling::Sampling;
use crate::variant::{LightKind, PrefilteredVariant, Rectification};

pub use crate::scene::{
    BASIS_TOLERANCE, CameraDesc, FrameError, LightDesc, MAX_COLOR, MAX_COORD, MAX_SIGMA_T,
    MIN_NEAR, MediumDesc, ShadowMapDesc, ShadowProjectionDesc, TAN_HALF_RANGE,
};
pub(crate) use crate::scene::{
    ScenePart, finite_fields, require, shadow_projection, validate_scene, validate_shadow_map,
    validate_shadow_projection,
};

/// Texture sizes of one configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resolutions {
    /// Screen (depth buffer and output) width and height.
    pub screen: [u32; 2],
    /// Rectified map width (light rays per slice) and height (slices).
    pub rectified: [u32; 2],
}

/// Runtime parameters that are not part of the compiled variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// Pixels within this radius (pixels) of the epipole or the anti-epipole, when on screen,
    /// are ray-marched against the standard shadow map (Sec. 5, Fig. 8).
    pub epipole_radius_px: f64,
    /// Samples of that ray march.
    pub march_steps: u32,
    /// Gauss-Legendre nodes (a multiple of 4) of the per-pixel unshadowed spot integral.
    pub spot_quadrature: u32,
    /// Projective rectification (variants with `rectification = projective`) is used only
    /// while the screen's slices fan out by at most this half-angle (degrees) around the
    /// bisectrix; wider fans (the epipole near or on the screen) fall back to epipolar
    /// resampling. Rows are uniform in `tan` of the slice angle, so at the fan's edge the
    /// slices are `cos^2(half-angle)` times as dense as in the middle.
    pub projective_max_half_angle_deg: f64,
    /// Where an epipolar frame's rectified rows lie. `None` (the default): on the epipolar
    /// sampling's slices for variants with `sampling = epipolar` (a sample on slice s reads
    /// row s, whose light rays lie in its own plane; `FrameUniforms::fan_angles`; with k
    /// times as many rows as slices, row k s + k / 2), uniform in the angle around the light
    /// axis otherwise. `Some(true)` aligns them for any variant, to a fan of the variant's
    /// `slices` (a per-pixel run whose rows are a sampled run's: the sampling trials compare
    /// the two), `Some(false)` never.
    pub aligned_rows: Option<bool>,
}

impl Default for FrameSettings {
    /// The settings for a 320x180 screen (see [`FrameSettings::for_screen`]).
    fn default() -> Self {
        FrameSettings::for_screen(320, 180)
    }
}

impl FrameSettings {
    /// Defaults for a screen: march radius 7.5 % of the larger screen side (24 pixels at
    /// 320x180, 96 at 1280x720), 128 march steps, 32 spot quadrature nodes, projective
    /// rectification up to a 60 degree half-angle fan.
    pub fn for_screen(width: u32, height: u32) -> FrameSettings {
        FrameSettings {
            epipole_radius_px: 0.075 * f64::from(width.max(height)),
            march_steps: 128,
            spot_quadrature: 32,
            projective_max_half_angle_deg: 60.0,
            aligned_rows: None,
        }
    }
}

/// The uniform block of the epipolar families' kernels (WGSL `struct Frame` in
/// `templates/common/epipolar.wgsl`). Every field is a 16-byte vector, so the WGSL
/// uniform layout is the plain C layout; the asserts below pin it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FrameUniforms {
    /// Eye position; w unused.
    pub eye: [f32; 4],
    /// Axis A (towards the light); w = eye-light distance D (spot), 0 (directional).
    pub axis: [f32; 4],
    /// Slice basis e1 (perpendicular to A); w = phi0.
    pub e1: [f32; 4],
    /// Slice basis e2 = A x e1; w = dphi (radians per row).
    pub e2: [f32; 4],
    /// Camera forward; w = tan(fov_y / 2).
    pub cam_forward: [f32; 4],
    /// Camera right; w = aspect (width / height).
    pub cam_right: [f32; 4],
    /// Camera up; w = near.
    pub cam_up: [f32; 4],
    /// x = theta_lo, y = theta_hi, z = far, w = 1 / (theta_hi - theta_lo).
    pub theta: [f32; 4],
    /// x = sigma_t, y = sigma_s, z = g, w unused.
    pub medium: [f32; 4],
    /// Light colour (E or I); w unused.
    pub light_color: [f32; 4],
    /// Spot position; w = cos(inner angle).
    pub light_pos: [f32; 4],
    /// Direction the light travels (spot axis); w = cos(outer angle).
    pub light_dir: [f32; 4],
    /// Shadow-map right; w = shadow-map near.
    pub sm_right: [f32; 4],
    /// Shadow-map up; w = shadow-map far.
    pub sm_up: [f32; 4],
    /// Shadow-map forward; w = bias in texel footprints.
    pub sm_forward: [f32; 4],
    /// Shadow-map origin; w = 0 orthographic, 1 perspective.
    pub sm_origin: [f32; 4],
    /// Orthographic: x0, x1, y0, y1. Perspective: tan_half, 0, 0, 0.
    pub sm_proj: [f32; 4],
    /// Epipole pixel position x, y; z = 1 if it is on screen; w = march radius (pixels).
    pub epipole: [f32; 4],
    /// Anti-epipole pixel position x, y; z = 1 if on screen; w = 1 if the slices wrap around
    /// (full circle: sample rows with wrap-around).
    pub anti_epipole: [f32; 4],
    /// Screen width, height, rectified width, rectified height.
    pub sizes: [u32; 4],
    /// Shadow-map size, march steps, spot quadrature nodes, unused.
    pub sizes2: [u32; 4],
    /// x = 1 for a projective frame (the rectified map was rasterised with
    /// [`ProjectiveMaps`]), 0 for epipolar; y = `kh` (rows span `k = qy / qx` in
    /// `[-kh, kh]`); z = `m_hi`; w = `1 / (m_hi - m_lo)` (ray depths `m = qz / qx`).
    pub proj: [f32; 4],
    /// Projective column invariants `G_0..G_3` at the region boundaries (see the module docs).
    pub proj_g0: [f32; 4],
    /// `G_4..G_7`.
    pub proj_g1: [f32; 4],
    /// `G_8`; yzw unused.
    pub proj_g2: [f32; 4],
    /// Rows aligned with the epipolar sampling's slices (`fan_angles.z = 1`, variants with
    /// `sampling = epipolar` and epipolar rectification): the slices' origin on screen (the
    /// epipole, or a point far along its direction when it lies near infinity; pixels,
    /// centres at + 0.5) in xy, the unit screen direction of angle 0 in zw
    /// (`scatter::sampling::epipolar_layout`). Zero otherwise.
    pub fan_origin: [f32; 4],
    /// Aligned rows: x = the screen angle where row 0 starts, y = the screen angle per row
    /// (rows uniform in the angle around `fan_origin`, as the slices are), z = 1; all zero
    /// for rows uniform in the angle around the light axis (`e1.w`, `e2.w`).
    pub fan_angles: [f32; 4],
}

/// Per-slice parameters (WGSL `array<vec4<f32>>`): `delta` (world units or radians per
/// column), `theta_ref`, and the slice's view-angle range inside the frustum.
///
/// In a projective frame the same four floats hold the row's `k` (in `delta`), the depth
/// `m_ref` of its reference ray (in `theta_ref`) and the row's depth range `m_lo`, `m_hi`
/// inside the frustum (in `theta_lo`, `theta_hi`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SliceParams {
    /// Column spacing: `v` per column (directional) or `psi` per column (spot).
    pub delta: f32,
    /// View angle of the slice's reference ray.
    pub theta_ref: f32,
    /// Smallest view angle of the slice inside the frustum.
    pub theta_lo: f32,
    /// Largest view angle of the slice inside the frustum.
    pub theta_hi: f32,
}

const _: () = {
    assert!(size_of::<FrameUniforms>() == 27 * 16);
    assert!(std::mem::offset_of!(FrameUniforms, fan_origin) == 25 * 16);
    assert!(std::mem::offset_of!(FrameUniforms, proj) == 21 * 16);
    assert!(std::mem::offset_of!(FrameUniforms, proj_g2) == 24 * 16);
    assert!(std::mem::offset_of!(FrameUniforms, theta) == 7 * 16);
    assert!(std::mem::offset_of!(FrameUniforms, medium) == 8 * 16);
    assert!(std::mem::offset_of!(FrameUniforms, epipole) == 17 * 16);
    assert!(std::mem::offset_of!(FrameUniforms, sizes) == 19 * 16);
    assert!(std::mem::offset_of!(FrameUniforms, sizes2) == 20 * 16);
    assert!(size_of::<SliceParams>() == 16);
};

/// Why a `projective` variant fell back to epipolar resampling this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProjectiveFallback {
    /// The epipole (the direction towards the light) is on screen: some view ray is
    /// parallel to the light.
    EpipoleOnScreen,
    /// The anti-epipole is on screen (light behind the camera).
    AntiEpipoleOnScreen,
    /// The slices fan out wider than `FrameSettings::projective_max_half_angle_deg`.
    WideFan {
        /// The fan's half-angle (degrees).
        half_angle_deg: f64,
        /// The allowed half-angle (degrees).
        max_deg: f64,
    },
}

impl std::fmt::Display for ProjectiveFallback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::EpipoleOnScreen => f.write_str("the epipole is on screen"),
            Self::AntiEpipoleOnScreen => f.write_str("the anti-epipole is on screen"),
            Self::WideFan {
                half_angle_deg,
                max_deg,
            } => write!(
                f,
                "the slices fan out {half_angle_deg:.1} degrees from the bisectrix (more than {max_deg:.1})"
            ),
        }
    }
}

/// The projective rectification of one frame (Klehm et al. 2014 Sec. 4.2, split per region
/// as the paper suggests): what the engine rasterises its rectified shadow map with.
///
/// For region `r`, render the scene's occluders with `matrices[r]` (world to clip, column
/// vectors: `clip = M * vec4(p, 1)`) into the columns `viewports[r][0] ..
/// viewports[r][0] + viewports[r][1]` and every row of the `Wr x Hr` rectified depth target:
/// depth test LESS, cleared to 1.0, depth clamping on (occluders between the light and the
/// frustum must still land in the map), no culling, no bias. Clip `z / w` is in [0, 1]
/// (wgpu / D3D / Metal convention); clip `y = +1` is row 0. The stored depth is what
/// `prefilter` reads (r32float or depth32float).
#[derive(Clone, Debug, PartialEq)]
pub struct ProjectiveMaps {
    /// World-to-clip matrix per region.
    pub matrices: Vec<DMat4>,
    /// First column and column count of each region.
    pub viewports: Vec<[u32; 2]>,
}

/// What the frame setup decided, for the frame report.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameReport {
    /// The rectification actually used this frame: `projective` only for a projective
    /// variant whose frame allows it, else `epipolar`.
    pub rectification: Rectification,
    /// For a projective variant that fell back to epipolar resampling this frame: why.
    pub fallback: Option<ProjectiveFallback>,
    /// For a projective frame: the matrices the engine must rasterise the rectified map
    /// with (then `rectify` is not dispatched).
    pub projective: Option<ProjectiveMaps>,
    /// Whether pixels near the epipole or the anti-epipole are ray-marched this frame (one of
    /// them is on screen), and within which radius (pixels).
    pub marched_radius_px: Option<f64>,
    /// The epipole (direction towards the light) projects inside the screen.
    pub epipole_on_screen: bool,
    /// The anti-epipole projects inside the screen (light behind the camera).
    pub anti_epipole_on_screen: bool,
    /// Slices cover the full circle around the axis.
    pub full_circle: bool,
    /// Largest distance in pixels between neighbouring slice centres along the screen border
    /// (a pixel lies at most half of this away from a slice).
    pub max_slice_gap_px: f64,
    /// Slices that do not meet the screen (given the frame-wide parameters).
    pub empty_slices: u32,
}

/// Everything the kernels need for one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PrefilteredFrame {
    /// The uniform block.
    pub uniforms: FrameUniforms,
    /// One entry per rectified row.
    pub slices: Vec<SliceParams>,
    /// What was decided.
    pub report: FrameReport,
}

pub(crate) fn v4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

/// Wraps an angle into (-pi, pi].
fn wrap(a: f64) -> f64 {
    let mut a = a % (2.0 * PI);
    if a > PI {
        a -= 2.0 * PI;
    } else if a <= -PI {
        a += 2.0 * PI;
    }
    a
}

/// The epipolar sampling's fan of slices on screen ([`Setup::fan`]; WGSL `EpipolarLayout`).
struct Fan {
    origin: (f64, f64),
    axis: (f64, f64),
    start: f64,
    step: f64,
    wrap: bool,
}

/// `scatter::sampling::EPIPOLE_FAR`: the farthest the fan's origin lies from the screen
/// centre, in screens.
const FAN_EPIPOLE_FAR: f64 = 100.0;

/// Angle of `d` from `axis` (counter-clockwise towards (-axis.y, axis.x)).
fn fan_angle(axis: (f64, f64), d: (f64, f64)) -> f64 {
    (axis.0 * d.1 - axis.1 * d.0).atan2(axis.0 * d.0 + axis.1 * d.1)
}

/// Distance from `origin` along `u` of the midpoint of the line's part inside the rectangle
/// of pixel centres of a `w` x `h` screen (its nearest point when it misses the rectangle).
fn fan_line_mid(origin: (f64, f64), u: (f64, f64), w: f64, h: f64) -> f64 {
    let (mut t_in, mut t_out) = (0.0f64, f64::INFINITY);
    for (ua, oa, lo, hi) in [(u.0, origin.0, 0.5, w - 0.5), (u.1, origin.1, 0.5, h - 0.5)] {
        if ua.abs() > 1e-12 {
            let (ta, tb) = ((lo - oa) / ua, (hi - oa) / ua);
            t_in = t_in.max(ta.min(tb));
            t_out = t_out.min(ta.max(tb));
        }
    }
    0.5 * (t_in + t_out.max(t_in))
}

struct Setup {
    cam: CameraDesc,
    aspect: f64,
    width: f64,
    height: f64,
    axis: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl Setup {
    /// Pixel position of a direction, or None if it does not point in front of the camera.
    fn project(&self, d: DVec3) -> Option<(f64, f64)> {
        let z = d.dot(self.cam.forward);
        if z <= 1e-12 {
            return None;
        }
        let t = self.cam.tan_half_fov_y;
        let nx = d.dot(self.cam.right) / (z * t * self.aspect);
        let ny = d.dot(self.cam.up) / (z * t);
        Some((
            (nx + 1.0) * 0.5 * self.width,
            (1.0 - ny) * 0.5 * self.height,
        ))
    }

    fn on_screen(&self, d: DVec3) -> Option<(f64, f64)> {
        self.project(d)
            .filter(|&(x, y)| (0.0..=self.width).contains(&x) && (0.0..=self.height).contains(&y))
    }

    /// Direction through pixel position (x, y) (pixels from the top-left corner).
    fn dir(&self, x: f64, y: f64) -> DVec3 {
        let t = self.cam.tan_half_fov_y;
        let nx = 2.0 * x / self.width - 1.0;
        let ny = 1.0 - 2.0 * y / self.height;
        (self.cam.forward + self.cam.right * (nx * t * self.aspect) + self.cam.up * (ny * t))
            .normalize()
    }

    fn phi(&self, d: DVec3) -> f64 {
        d.dot(self.e2).atan2(d.dot(self.e1))
    }

    /// The epipolar sampling's fan of `rows` slices towards the light direction `toward`
    /// (`scatter::sampling::epipolar_layout` in f64: the same origin, axis, range and wrap),
    /// for a sampling of `slices` slices: where `rows` is an even multiple k of `slices`,
    /// every slice would lie on a boundary between two rows, half a row from the planes of
    /// both, so the rows move half a row back, and row k s + k / 2 lies on slice s (with an
    /// odd multiple row k s + (k - 1) / 2 already does). The last half row of the screen's
    /// fan then reads the last row, half a row beyond its centre.
    fn fan(&self, toward: DVec3, rows: usize, slices: usize) -> Fan {
        let (w, h) = (self.width, self.height);
        let centre = (0.5 * w, 0.5 * h);
        let t = self.cam.tan_half_fov_y;
        let z = toward.dot(self.cam.forward);
        let q = (
            toward.dot(self.cam.right) * centre.0 / (t * self.aspect),
            -toward.dot(self.cam.up) * centre.1 / t,
        );
        let far = FAN_EPIPOLE_FAR * w.max(h);
        let lq = q.0.hypot(q.1);
        let origin = if lq >= far * z.abs() {
            let k = far / lq.max(1e-30) * if z < 0.0 { -1.0 } else { 1.0 };
            (centre.0 + q.0 * k, centre.1 + q.1 * k)
        } else if lq > 0.0 {
            (centre.0 + q.0 / z, centre.1 + q.1 / z)
        } else {
            centre
        };
        let to_centre = (centre.0 - origin.0, centre.1 - origin.1);
        let lc = to_centre.0.hypot(to_centre.1);
        let axis = if lc > 0.0 {
            (to_centre.0 / lc, to_centre.1 / lc)
        } else {
            (1.0, 0.0)
        };
        let (lo, hi) = ((0.5, 0.5), (w - 0.5, h - 0.5));
        let wrap = origin.0 >= lo.0 && origin.0 <= hi.0 && origin.1 >= lo.1 && origin.1 <= hi.1;
        let (start, range) = if wrap {
            (-PI, 2.0 * PI)
        } else {
            let angles = [(lo.0, lo.1), (hi.0, lo.1), (lo.0, hi.1), (hi.0, hi.1)]
                .map(|c| fan_angle(axis, (c.0 - origin.0, c.1 - origin.1)));
            let a = angles.into_iter().fold(f64::INFINITY, f64::min);
            let b = angles.into_iter().fold(f64::NEG_INFINITY, f64::max);
            (a, b - a)
        };
        let step = range / rows as f64;
        let even_multiple =
            slices > 0 && rows.is_multiple_of(slices) && (rows / slices).is_multiple_of(2);
        Fan {
            origin,
            axis,
            start: if even_multiple {
                start - 0.5 * step
            } else {
                start
            },
            step,
            wrap,
        }
    }

    /// The slice angle around the light axis of row `row` of the fan: that of the view ray
    /// through the midpoint of its screen line inside the rectangle of pixel centres (any
    /// point of the line would do when the origin is the epipole; the midpoint keeps a
    /// near-infinite epipole, whose origin is clamped, on the slice's own plane).
    fn fan_phi(&self, f: &Fan, row: usize) -> f64 {
        let (ox, oy) = f.origin;
        let a = f.start + (row as f64 + 0.5) * f.step;
        let u = (
            f.axis.0 * a.cos() - f.axis.1 * a.sin(),
            f.axis.1 * a.cos() + f.axis.0 * a.sin(),
        );
        let mid = fan_line_mid(f.origin, u, self.width, self.height);
        self.phi(self.dir(ox + u.0 * mid, oy + u.1 * mid))
    }

    fn slice_dir(&self, phi: f64, theta: f64) -> DVec3 {
        let e = self.e1 * phi.cos() + self.e2 * phi.sin();
        self.axis * theta.cos() + e * theta.sin()
    }

    fn inside(&self, d: DVec3) -> bool {
        let z = d.dot(self.cam.forward);
        if z <= 1e-9 {
            return false;
        }
        let t = self.cam.tan_half_fov_y;
        let eps = 1e-9;
        (d.dot(self.cam.right) / z).abs() <= t * self.aspect + eps
            && (d.dot(self.cam.up) / z).abs() <= t + eps
    }

    /// The view-angle interval of slice `phi` inside the frustum (None if it misses it).
    fn slice_theta_range(&self, phi: f64) -> Option<(f64, f64)> {
        let e = self.e1 * phi.cos() + self.e2 * phi.sin();
        let (f, r, u) = (self.cam.forward, self.cam.right, self.cam.up);
        let tx = self.cam.tan_half_fov_y * self.aspect;
        let ty = self.cam.tan_half_fov_y;
        let mut cand = vec![0.0, PI];
        // Boundary lines: dot(d, n) = 0 for the four side planes and the image plane.
        let normals = [r - f * tx, r + f * tx, u - f * ty, u + f * ty, f];
        for n in normals {
            let (p, q) = (self.axis.dot(n), e.dot(n));
            // cos(t) p + sin(t) q = 0  ->  t = atan2(-p, q) (mod pi)
            if p.abs() + q.abs() > 1e-15 {
                let mut t = (-p).atan2(q);
                if t < 0.0 {
                    t += PI;
                }
                cand.push(t.clamp(0.0, PI));
            }
        }
        cand.sort_by(f64::total_cmp);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for w in cand.windows(2) {
            if w[1] - w[0] < 1e-12 {
                continue;
            }
            let mid = 0.5 * (w[0] + w[1]);
            if self.inside(self.slice_dir(phi, mid)) {
                lo = lo.min(w[0]);
                hi = hi.max(w[1]);
            }
        }
        (lo <= hi).then_some((lo, hi))
    }
}

/// Sets up one frame of the prefiltered method: epipolar rectification, or projective
/// rectification for a `projective` variant when the frame allows it.
///
/// Every input is checked before use: sizes, settings, camera (a finite position, an
/// orthonormal basis, `tan_half_fov_y` in [`TAN_HALF_RANGE`], `MIN_NEAR <= near < far <=
/// MAX_COORD`), light (finite non-zero direction, position within [`MAX_COORD`], cone
/// angles `0 <= inner <= outer <= 180`, colour in `[0, MAX_COLOR]`), medium (`sigma_t` in
/// `[0, MAX_SIGMA_T]`, albedo in `[0, 1]`, `|g| < 1`) and shadow map (origin, orthonormal
/// basis, projection, near < far, bias). Every float of the result is finite.
///
/// # Errors
///
/// [`FrameError::Variant`] for a variant that does not validate, [`FrameError::Size`] for
/// a zero or oversized size, [`FrameError::RectifiedTooNarrow`],
/// [`FrameError::LightMismatch`], [`FrameError::OutOfRange`] naming the parameter, its
/// value and the accepted range, [`FrameError::EyeAtLight`]; [`FrameError::NotRepresentable`]
/// if a uniform still came out non-finite.
pub fn prepare_frame(
    variant: &PrefilteredVariant,
    res: &Resolutions,
    camera: &CameraDesc,
    light: &LightDesc,
    medium: &MediumDesc,
    shadow: &ShadowMapDesc,
    settings: &FrameSettings,
) -> Result<PrefilteredFrame, FrameError> {
    let frame = prepare_frame_unchecked(variant, res, camera, light, medium, shadow, settings)?;
    let u = &frame.uniforms;
    finite_fields([
        ("eye", u.eye),
        ("axis", u.axis),
        ("e1", u.e1),
        ("e2", u.e2),
        ("cam_forward", u.cam_forward),
        ("cam_right", u.cam_right),
        ("cam_up", u.cam_up),
        ("theta", u.theta),
        ("medium", u.medium),
        ("light_color", u.light_color),
        ("light_pos", u.light_pos),
        ("light_dir", u.light_dir),
        ("sm_right", u.sm_right),
        ("sm_up", u.sm_up),
        ("sm_forward", u.sm_forward),
        ("sm_origin", u.sm_origin),
        ("sm_proj", u.sm_proj),
        ("epipole", u.epipole),
        ("anti_epipole", u.anti_epipole),
        ("proj", u.proj),
        ("proj_g0", u.proj_g0),
        ("proj_g1", u.proj_g1),
        ("proj_g2", u.proj_g2),
    ])?;
    for s in &frame.slices {
        finite_fields([(
            "slice table entry",
            [s.delta, s.theta_ref, s.theta_lo, s.theta_hi],
        )])?;
    }
    if let Some(p) = &frame.report.projective
        && !p.matrices.iter().all(DMat4::is_finite)
    {
        return Err(FrameError::NotRepresentable {
            what: "projective matrix",
        });
    }
    Ok(frame)
}

fn prepare_frame_unchecked(
    variant: &PrefilteredVariant,
    res: &Resolutions,
    camera: &CameraDesc,
    light: &LightDesc,
    medium: &MediumDesc,
    shadow: &ShadowMapDesc,
    settings: &FrameSettings,
) -> Result<PrefilteredFrame, FrameError> {
    // The variant is plain data: an unvalidated one (regions = u32::MAX) would overflow
    // `regions^2` and allocate per region below.
    variant.validate()?;
    for (what, value, max) in [
        ("screen width", res.screen[0], 16384),
        ("screen height", res.screen[1], 16384),
        ("rectified width", res.rectified[0], 16384),
        ("rectified height", res.rectified[1], 16384),
        ("shadow map size", shadow.size, 16384),
        ("march steps", settings.march_steps, 4096),
    ] {
        if value == 0 || value > max {
            return Err(FrameError::Size { what, value, max });
        }
    }
    if settings.spot_quadrature == 0
        || !settings.spot_quadrature.is_multiple_of(4)
        || settings.spot_quadrature > 256
    {
        return Err(FrameError::Size {
            what: "spot quadrature nodes (a multiple of 4)",
            value: settings.spot_quadrature,
            max: 256,
        });
    }
    let max_half = settings.projective_max_half_angle_deg;
    require(
        max_half > 0.0 && max_half <= 89.0,
        "projective_max_half_angle_deg",
        "in (0, 89]",
        || format!("{max_half:?}"),
    )?;
    require(
        (0.0..=1e6).contains(&settings.epipole_radius_px),
        "epipole_radius_px",
        "in [0, 1e6] pixels",
        || format!("{:?}", settings.epipole_radius_px),
    )?;
    let min_width = variant.min_rectified_width();
    if res.rectified[0] < min_width {
        return Err(FrameError::RectifiedTooNarrow {
            width: res.rectified[0],
            regions: variant.regions,
            stride: variant.filtered_stride,
            min: min_width,
        });
    }
    if !res.rectified[0].is_multiple_of(variant.filtered_stride) {
        return Err(FrameError::RectifiedStride {
            width: res.rectified[0],
            stride: variant.filtered_stride,
        });
    }
    let ScenePart {
        cam,
        axis,
        dist,
        light_pos,
        light_dir,
        color,
        cos_in,
        cos_out,
    } = validate_scene(variant.light, camera, light, medium)?;
    validate_shadow_map(shadow)?;
    validate_shadow_projection(variant.light, shadow)?;
    // e1: the view axis made perpendicular to A (so phi = 0 looks ahead), else any.
    let mut e1 = cam.forward - axis * cam.forward.dot(axis);
    if e1.length() < 1e-6 {
        e1 = axis.any_orthonormal_vector();
    }
    let e1 = e1.normalize();
    let e2 = axis.cross(e1);
    let (w, h) = (f64::from(res.screen[0]), f64::from(res.screen[1]));
    let s = Setup {
        cam,
        aspect: w / h,
        width: w,
        height: h,
        axis,
        e1,
        e2,
    };
    let epi = s.on_screen(axis);
    let anti = s.on_screen(-axis);
    let full_circle = epi.is_some() || anti.is_some();

    // Border samples: every pixel edge position along the four sides.
    let mut border = Vec::new();
    let (wi, hi) = (res.screen[0], res.screen[1]);
    for i in 0..=wi {
        border.push((f64::from(i), 0.0));
        border.push((f64::from(i), h));
    }
    for j in 0..=hi {
        border.push((0.0, f64::from(j)));
        border.push((w, f64::from(j)));
    }
    let dirs: Vec<DVec3> = border.iter().map(|&(x, y)| s.dir(x, y)).collect();
    let (mut theta_lo, mut theta_hi) = (PI, 0.0f64);
    for d in &dirs {
        let t = d.dot(axis).clamp(-1.0, 1.0).acos();
        theta_lo = theta_lo.min(t);
        theta_hi = theta_hi.max(t);
    }
    if epi.is_some() {
        theta_lo = 0.0;
    }
    if anti.is_some() {
        theta_hi = PI;
    }
    let (phi0, phi_range) = if full_circle {
        (-PI, 2.0 * PI)
    } else {
        let pc = s.phi(cam.forward);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for d in &dirs {
            let dp = wrap(s.phi(*d) - pc);
            lo = lo.min(dp);
            hi = hi.max(dp);
        }
        (pc + lo, (hi - lo).max(1e-9))
    };
    let rows = res.rectified[1] as usize;
    let cols = f64::from(res.rectified[0]);
    let dphi = phi_range / rows as f64;
    // Rows aligned with the epipolar sampling's slices: row j on the plane of the screen
    // slice at angle `fan.start + (j + 0.5) fan.step` around the layout's origin.
    let aligned = settings
        .aligned_rows
        .unwrap_or(variant.sampling == Sampling::Epipolar);
    let fan = (aligned && variant.rectification == Rectification::Epipolar)
        .then(|| s.fan(axis, rows, variant.slices as usize));
    let full_circle = fan.as_ref().map_or(full_circle, |f| f.wrap);

    // The largest gap between neighbouring slices on the screen border (where they are
    // farthest apart): the image distance between a border point and the point at the same
    // view angle on the next slice.
    let mut max_gap: f64 = 0.0;
    for (&(x, y), d) in border.iter().zip(&dirs) {
        let theta = d.dot(axis).clamp(-1.0, 1.0).acos();
        let next = s.slice_dir(s.phi(*d) + dphi, theta);
        if let Some((nx, ny)) = s.project(next) {
            max_gap = max_gap.max(((nx - x).powi(2) + (ny - y).powi(2)).sqrt());
        }
    }

    // Per-slice parameters.
    let mut slices = Vec::with_capacity(rows);
    let mut empty = 0u32;
    let mut fallback_delta: f64 = 0.0;
    let mut missing = Vec::new();
    for j in 0..rows {
        let phi = match &fan {
            Some(f) => s.fan_phi(f, j),
            None => phi0 + (j as f64 + 0.5) * dphi,
        };
        let range = s.slice_theta_range(phi);
        let (lo, hi) = match range {
            Some(r) => r,
            None => {
                empty += 1;
                missing.push(j);
                (theta_lo, theta_hi)
            }
        };
        let theta_ref = 0.5 * (lo + hi);
        let far_t = |theta: f64| {
            let d = s.slice_dir(phi, theta);
            cam.far / d.dot(cam.forward).max(1e-6)
        };
        let extent = match variant.light {
            LightKind::Directional => [lo, hi]
                .into_iter()
                .map(|t| far_t(t) * t.sin())
                .fold(0.0, f64::max),
            // `Area` never gets here: the variant refuses it (`single_light`).
            LightKind::Spot | LightKind::Area => (0..=32)
                .map(|k| lo + (hi - lo) * f64::from(k) / 32.0)
                .map(|t| {
                    let tf = far_t(t);
                    (tf * t.sin()).atan2(dist - tf * t.cos())
                })
                .fold(0.0, f64::max),
        };
        let delta = extent * 1.001 / cols;
        if range.is_some() {
            fallback_delta = fallback_delta.max(delta);
        }
        slices.push(SliceParams {
            delta: delta as f32,
            theta_ref: theta_ref as f32,
            theta_lo: lo as f32,
            theta_hi: hi as f32,
        });
    }
    for j in missing {
        if slices[j].delta <= 0.0 || !slices[j].delta.is_finite() {
            slices[j].delta = fallback_delta.max(1e-6) as f32;
        }
    }
    let (sm_kind, sm_proj) = shadow_projection(shadow);
    let (ex, ey) = s.project(axis).unwrap_or((-1e9, -1e9));
    let (ax, ay) = s.project(-axis).unwrap_or((-1e9, -1e9));
    let theta_span = (theta_hi - theta_lo).max(1e-9);
    let uniforms = FrameUniforms {
        eye: v4(cam.position, 0.0),
        axis: v4(axis, dist),
        e1: v4(e1, phi0),
        e2: v4(e2, dphi),
        cam_forward: v4(cam.forward, cam.tan_half_fov_y),
        cam_right: v4(cam.right, w / h),
        cam_up: v4(cam.up, cam.near),
        theta: [
            theta_lo as f32,
            theta_hi as f32,
            cam.far as f32,
            (1.0 / theta_span) as f32,
        ],
        medium: [
            medium.sigma_t as f32,
            (medium.sigma_t * medium.albedo) as f32,
            medium.g as f32,
            0.0,
        ],
        light_color: [color[0] as f32, color[1] as f32, color[2] as f32, 0.0],
        light_pos: v4(light_pos, cos_in),
        light_dir: v4(light_dir, cos_out),
        sm_right: v4(shadow.basis[0], shadow.near),
        sm_up: v4(shadow.basis[1], shadow.far),
        sm_forward: v4(shadow.basis[2], shadow.bias_texels),
        sm_origin: v4(shadow.origin, sm_kind),
        sm_proj,
        epipole: [
            ex as f32,
            ey as f32,
            if epi.is_some() { 1.0 } else { 0.0 },
            settings.epipole_radius_px as f32,
        ],
        anti_epipole: [
            ax as f32,
            ay as f32,
            if anti.is_some() { 1.0 } else { 0.0 },
            if full_circle { 1.0 } else { 0.0 },
        ],
        sizes: [
            res.screen[0],
            res.screen[1],
            res.rectified[0],
            res.rectified[1],
        ],
        sizes2: [
            shadow.size,
            settings.march_steps,
            settings.spot_quadrature,
            0,
        ],
        proj: [0.0; 4],
        proj_g0: [0.0; 4],
        proj_g1: [0.0; 4],
        proj_g2: [0.0; 4],
        fan_origin: fan.as_ref().map_or([0.0; 4], |f| {
            [
                f.origin.0 as f32,
                f.origin.1 as f32,
                f.axis.0 as f32,
                f.axis.1 as f32,
            ]
        }),
        fan_angles: fan
            .as_ref()
            .map_or([0.0; 4], |f| [f.start as f32, f.step as f32, 1.0, 0.0]),
    };
    let half_fan = if full_circle { PI } else { 0.5 * phi_range };
    let fallback = if variant.rectification != Rectification::Projective {
        None
    } else if epi.is_some() {
        Some(ProjectiveFallback::EpipoleOnScreen)
    } else if anti.is_some() {
        Some(ProjectiveFallback::AntiEpipoleOnScreen)
    } else if half_fan > max_half.to_radians() {
        Some(ProjectiveFallback::WideFan {
            half_angle_deg: half_fan.to_degrees(),
            max_deg: max_half,
        })
    } else {
        None
    };
    if variant.rectification == Rectification::Projective && fallback.is_none() {
        return Ok(projective_frame(
            variant,
            res,
            &s,
            dist,
            phi0 + 0.5 * phi_range,
            half_fan,
            uniforms,
        ));
    }
    Ok(PrefilteredFrame {
        uniforms,
        slices,
        report: FrameReport {
            rectification: Rectification::Epipolar,
            fallback,
            projective: None,
            marched_radius_px: (epi.is_some() || anti.is_some())
                .then_some(settings.epipole_radius_px),
            epipole_on_screen: epi.is_some(),
            anti_epipole_on_screen: anti.is_some(),
            full_circle,
            max_slice_gap_px: max_gap,
            empty_slices: empty,
        },
    })
}

/// First column of region `r` of `regions` in a row of `width` columns: quadratic for the
/// sun, uniform for a spot (WGSL `region_start` in `templates/common/prefiltered.wgsl`).
pub fn region_start(r: u32, regions: u32, width: u32, spot: bool) -> u32 {
    if spot {
        r * width / regions
    } else {
        r * r * width / (regions * regions)
    }
}

/// First rectified column of region `r` when `prefilter` stores every `stride`-th column:
/// `stride * region_start(r, regions, width / stride, spot)`, so regions start on multiples
/// of the stride (WGSL: the callers of `region_start` in `prefilter.wgsl` and
/// `common/prefiltered_projective.wgsl`). `stride = 1` is [`region_start`].
pub fn region_column(r: u32, regions: u32, width: u32, stride: u32, spot: bool) -> u32 {
    stride * region_start(r, regions, width / stride, spot)
}

/// The projective frame (Sec. 4.2): light space with the eye at the origin, `x` the
/// bisectrix `e1` of the slices' fan, `y = e2`, `z` the axis towards the light. A point
/// `q` maps to row `k = qy / qx`, ray depth `m = qz / qx` (constant along a view ray,
/// stored normalised as `(m_hi - m) / (m_hi - m_lo)`) and the column invariant
/// `G = 1 / qx` (sun) or `G = (D - qz) / qx` (spot at distance `D`), constant along a light
/// ray. Each region `r` maps `G` linearly from `G_r` to `G_(r+1)` onto its columns; the
/// boundaries are geometric in `qx` (sun) between the frustum's extremes, which limits the
/// hyperbolic crowding of columns near the eye that one projective map over the whole
/// depth range would have, and uniform in the light-ray angle `acot G` (spot), like the
/// epipolar spot's uniform regions (geometric angles measured 85.6 % rel L1 on
/// spot_grate/grazing: the last region then spans most of the ray and the per-region
/// unshadowed quadrature misses the cone).
fn projective_frame(
    variant: &PrefilteredVariant,
    res: &Resolutions,
    s: &Setup,
    dist: f64,
    phi_c: f64,
    half_fan: f64,
    mut uniforms: FrameUniforms,
) -> PrefilteredFrame {
    let spot = variant.light == LightKind::Spot;
    let axis = s.axis;
    let e1 = (s.e1 * phi_c.cos() + s.e2 * phi_c.sin()).normalize();
    let e2 = axis.cross(e1);
    let rot = Setup {
        cam: s.cam,
        aspect: s.aspect,
        width: s.width,
        height: s.height,
        axis,
        e1,
        e2,
    };
    let cam = s.cam;
    let kh = half_fan.tan() * (1.0 + 1e-4) + 1e-9;
    // Ray depths over the screen: extremes at the screen corners (m is linear-fractional
    // on the image plane with a positive denominator).
    let (mut m_lo, mut m_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (x, y) in [
        (0.0, 0.0),
        (s.width, 0.0),
        (0.0, s.height),
        (s.width, s.height),
    ] {
        let d = s.dir(x, y);
        let m = d.dot(axis) / d.dot(e1).max(1e-12);
        m_lo = m_lo.min(m);
        m_hi = m_hi.max(m);
    }
    let span = (m_hi - m_lo).max(1e-6);
    m_lo -= 1e-4 * span;
    m_hi += 1e-4 * span;
    // Column invariants at the frustum corners.
    let tx = cam.tan_half_fov_y * s.aspect;
    let ty = cam.tan_half_fov_y;
    let mut corners = Vec::with_capacity(8);
    for dpt in [cam.near, cam.far] {
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            corners.push((cam.forward + cam.right * (sx * tx) + cam.up * (sy * ty)) * dpt);
        }
    }
    let regions = variant.regions;
    let g: Vec<f64> = if spot {
        let gs = corners
            .iter()
            .map(|c| (dist - c.dot(axis)) / c.dot(e1).max(1e-12));
        let (gmin, gmax) = gs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        let psi0 = 1.0f64.atan2(gmax) * (1.0 - 1e-3);
        let psi1 = (1.0f64.atan2(gmin) * (1.0 + 1e-3)).min(PI - 1e-3);
        (0..=regions)
            .map(|r| {
                let psi = psi0 + (psi1 - psi0) * f64::from(r) / f64::from(regions);
                psi.cos() / psi.sin()
            })
            .collect()
    } else {
        let (n, f) = corners
            .iter()
            .map(|c| c.dot(e1))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        let (n, f) = (n.max(1e-9) * (1.0 - 1e-3), f * (1.0 + 1e-3));
        (0..=regions)
            .map(|r| 1.0 / (n * (f / n).powf(f64::from(r) / f64::from(regions))))
            .collect()
    };
    let rows = res.rectified[1];
    let width = res.rectified[0];
    let dk = 2.0 * kh / f64::from(rows);
    let slices = (0..rows)
        .map(|j| {
            let k = -kh + (f64::from(j) + 0.5) * dk;
            let phi = k.atan();
            let (lo, hi) = rot
                .slice_theta_range(phi)
                .unwrap_or((m_hi.recip().atan(), PI / 2.0));
            let m_of = |theta: f64| theta.cos() / (theta.sin().max(1e-12) * phi.cos());
            let theta_ref = 0.5 * (lo + hi);
            SliceParams {
                delta: k as f32,
                theta_ref: m_of(theta_ref).clamp(m_lo, m_hi) as f32,
                theta_lo: m_of(hi).clamp(m_lo, m_hi) as f32,
                theta_hi: m_of(lo).clamp(m_lo, m_hi) as f32,
            }
        })
        .collect();
    // The engine's matrices: light space, then the per-region projection.
    let eye = cam.position;
    let view = DMat4::from_cols(
        DVec4::new(e1.x, e2.x, axis.x, 0.0),
        DVec4::new(e1.y, e2.y, axis.y, 0.0),
        DVec4::new(e1.z, e2.z, axis.z, 0.0),
        DVec4::new(-e1.dot(eye), -e2.dot(eye), -axis.dot(eye), 1.0),
    );
    let inv = 1.0 / (m_hi - m_lo);
    let mut matrices = Vec::with_capacity(regions as usize);
    let mut viewports = Vec::with_capacity(regions as usize);
    for r in 0..regions {
        let dg = g[r as usize] - g[r as usize + 1];
        let gr = g[r as usize];
        // Rows of the projection acting on (qx, qy, qz, 1).
        let px = if spot {
            DVec4::new(2.0 * gr / dg - 1.0, 0.0, 2.0 / dg, -2.0 * dist / dg)
        } else {
            DVec4::new(2.0 * gr / dg - 1.0, 0.0, 0.0, -2.0 / dg)
        };
        let py = DVec4::new(0.0, -1.0 / kh, 0.0, 0.0);
        let pz = DVec4::new(m_hi * inv, 0.0, -inv, 0.0);
        let pw = DVec4::new(1.0, 0.0, 0.0, 0.0);
        let proj = DMat4::from_cols(px, py, pz, pw).transpose();
        matrices.push(proj * view);
        // Regions start on multiples of the filtered stride (`region_column`).
        let k = variant.filtered_stride;
        let b0 = region_column(r, regions, width, k, spot);
        let b1 = region_column(r + 1, regions, width, k, spot);
        viewports.push([b0, b1 - b0]);
    }
    let mut gv = [0.0f32; 12];
    for (i, v) in g.iter().enumerate() {
        gv[i] = *v as f32;
    }
    uniforms.e1 = v4(e1, -half_fan);
    uniforms.e2 = v4(e2, 2.0 * half_fan / f64::from(rows));
    uniforms.proj = [1.0, kh as f32, m_hi as f32, inv as f32];
    uniforms.proj_g0 = [gv[0], gv[1], gv[2], gv[3]];
    uniforms.proj_g1 = [gv[4], gv[5], gv[6], gv[7]];
    uniforms.proj_g2 = [gv[8], gv[9], gv[10], gv[11]];
    // Neither epipole is on screen in a projective frame: nothing is ray-marched and rows
    // never wrap.
    uniforms.epipole[2] = 0.0;
    uniforms.anti_epipole[2] = 0.0;
    uniforms.anti_epipole[3] = 0.0;
    // Largest gap between neighbouring rows on the screen border.
    let mut max_gap: f64 = 0.0;
    let (w, h) = (res.screen[0], res.screen[1]);
    let border = (0..=w)
        .flat_map(|i| [(f64::from(i), 0.0), (f64::from(i), s.height)])
        .chain((0..=h).flat_map(|j| [(0.0, f64::from(j)), (s.width, f64::from(j))]));
    for (x, y) in border {
        let d = s.dir(x, y);
        let (qx, qy, qz) = (d.dot(e1), d.dot(e2), d.dot(axis));
        let next = e1 * qx + e2 * (qy + dk * qx) + axis * qz;
        if let Some((nx, ny)) = s.project(next) {
            max_gap = max_gap.max(((nx - x).powi(2) + (ny - y).powi(2)).sqrt());
        }
    }
    PrefilteredFrame {
        uniforms,
        slices,
        report: FrameReport {
            rectification: Rectification::Projective,
            fallback: None,
            projective: Some(ProjectiveMaps {
                matrices,
                viewports,
            }),
            marched_radius_px: None,
            epipole_on_screen: false,
            anti_epipole_on_screen: false,
            full_circle: false,
            max_slice_gap_px: max_gap,
            empty_slices: 0,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setup(forward: DVec3, axis: DVec3) -> Setup {
        let forward = forward.normalize();
        let right = forward.cross(DVec3::Y).normalize();
        let up = right.cross(forward);
        let axis = axis.normalize();
        let mut e1 = forward - axis * forward.dot(axis);
        if e1.length() < 1e-6 {
            e1 = axis.any_orthonormal_vector();
        }
        let e1 = e1.normalize();
        Setup {
            cam: CameraDesc {
                position: DVec3::ZERO,
                forward,
                right,
                up,
                tan_half_fov_y: (30f64).to_radians().tan(),
                near: 0.1,
                far: 50.0,
            },
            aspect: 16.0 / 9.0,
            width: 320.0,
            height: 180.0,
            axis,
            e1,
            e2: axis.cross(e1),
        }
    }

    /// The analytic slice clipping agrees with dense sampling of the slice.
    #[test]
    fn slice_theta_range_matches_sampling() {
        let cases = [
            (DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.5, 0.6, 0.4)),
            (DVec3::new(0.0, -0.1, -1.0), DVec3::new(0.1, 0.3, -1.0)),
            (DVec3::new(0.3, -0.2, -1.0), DVec3::new(-0.2, -0.5, 1.0)),
            (DVec3::new(1.0, 0.0, 0.2), DVec3::new(0.0, 0.07, -1.0)),
        ];
        for (fwd, axis) in cases {
            let s = setup(fwd, axis);
            for k in 0..64 {
                let phi = -PI + (f64::from(k) + 0.5) * 2.0 * PI / 64.0;
                let n = 20000;
                let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                for i in 0..=n {
                    let t = PI * f64::from(i) / f64::from(n);
                    if s.inside(s.slice_dir(phi, t)) {
                        lo = lo.min(t);
                        hi = hi.max(t);
                    }
                }
                let got = s.slice_theta_range(phi);
                if lo > hi {
                    assert!(
                        got.is_none() || got.is_some_and(|(a, b)| b - a < 1e-3),
                        "phi {phi}: {got:?}"
                    );
                } else {
                    let (a, b) = got.unwrap_or_else(|| panic!("phi {phi}: expected [{lo}, {hi}]"));
                    assert!(
                        (a - lo).abs() < 1e-3 && (b - hi).abs() < 1e-3,
                        "phi {phi}: [{a}, {b}] vs [{lo}, {hi}]"
                    );
                }
            }
        }
    }
}
