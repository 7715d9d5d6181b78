//! CPU mirror of `shaderlib/templates/common/epipolar.wgsl` (`scatter::epipolar`): what
//! every family built on the epipolar set-up shares and no family owns: slice angles,
//! rectified depth, the frame's standard shadow-map lookups, the pixel's view ray, the
//! epipole march (equiangular for a spot), the slice-row index and the spot quadrature of a
//! ray span.
//!
//! Conventions are documented in `scatter_frame::frame`.

use super::common_model::{
    PI, clamp, equiangular, equiangular_sample, max, max_u, min, phase_hg, spot_integrand,
    spot_span, transmittance_between,
};
use super::common_shadow::{
    ShadowMapView, shadow_occluder_distance_orthographic, shadow_occluder_distance_perspective,
    shadow_visibility_for,
};
use super::texture::{Tex, xyz};
use glam::Vec3;
use scatter_shaderlib::prefiltered::FrameUniforms;

/// Unit vector of slice angle `phi` (perpendicular to the axis).
pub fn slice_e(f: &FrameUniforms, phi: f32) -> Vec3 {
    xyz(f.e1) * phi.cos() + xyz(f.e2) * phi.sin()
}

/// Slice angle at the centre of row `row`.
pub fn row_phi(f: &FrameUniforms, row: u32) -> f32 {
    if f.fan_angles[2] > 0.5 {
        fan_phi(f, row)
    } else {
        axis_row_phi(f, row)
    }
}

/// Slice angle at the centre of row `row` of rows uniform in the angle around the light
/// axis: [`row_phi`] of a frame whose rows do not follow the sampling's slices.
pub fn axis_row_phi(f: &FrameUniforms, row: u32) -> f32 {
    f.e1[3] + (row as f32 + 0.5) * f.e2[3]
}

/// The screen size in pixels.
fn screen_size(f: &FrameUniforms) -> [f32; 2] {
    [f.sizes[0] as f32, f.sizes[1] as f32]
}

/// Unit view direction through screen position `p` (pixels from the top-left corner).
pub fn screen_dir(f: &FrameUniforms, p: [f32; 2]) -> Vec3 {
    let ndc_x = 2.0 * p[0] / f.sizes[0] as f32 - 1.0;
    let ndc_y = 1.0 - 2.0 * p[1] / f.sizes[1] as f32;
    let t = f.cam_forward[3];
    (xyz(f.cam_forward)
        + xyz(f.cam_right) * (ndc_x * t * f.cam_right[3])
        + xyz(f.cam_up) * (ndc_y * t))
        .normalize()
}

/// Distance from `o` along `u` of the midpoint of the line's part inside the rectangle of
/// pixel centres of a screen of `size` pixels (its nearest point when it misses it). Both
/// axes at once, each kept where the line crosses it, as the kernel computes it (without a
/// loop over the axes: see `fan_line_mid` in common/epipolar.wgsl).
fn fan_line_mid(o: [f32; 2], u: [f32; 2], size: [f32; 2]) -> f32 {
    let axis = |a: usize| {
        let ta = (0.5 - o[a]) / u[a];
        let tb = (size[a] - 0.5 - o[a]) / u[a];
        if u[a].abs() > 1e-12 {
            (ta.min(tb), ta.max(tb))
        } else {
            (0.0, 3.4e38)
        }
    };
    // (enter, leave) along x and along y.
    let (x, y) = (axis(0), axis(1));
    let t_in = max(0.0, max(x.0, y.0));
    let t_out = 3.4e38f32.min(x.1.min(y.1));
    0.5 * (t_in + max(t_out, t_in))
}

/// The slice angle (around the light axis) of aligned row `row` (`FrameUniforms::fan_angles`):
/// that of the view ray through the midpoint of its screen slice.
pub fn fan_phi(f: &FrameUniforms, row: u32) -> f32 {
    let a = f.fan_angles[0] + (row as f32 + 0.5) * f.fan_angles[1];
    let (ax, ay) = (f.fan_origin[2], f.fan_origin[3]);
    let u = [ax * a.cos() - ay * a.sin(), ay * a.cos() + ax * a.sin()];
    let o = [f.fan_origin[0], f.fan_origin[1]];
    let mid = fan_line_mid(o, u, screen_size(f));
    let d = screen_dir(f, [o[0] + u[0] * mid, o[1] + u[1] * mid]);
    d.dot(xyz(f.e2)).atan2(d.dot(xyz(f.e1)))
}

/// Normalised rectified depth of view angle `theta`, the frame's view angles spanning
/// [`lo`, `hi`] (`FrameUniforms::theta`).
pub fn normalised_depth(theta: f32, lo: f32, hi: f32) -> f32 {
    DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp((theta - lo) / max(hi - lo, 1e-6), 0.0, 1.0)
}

/// Normalised rectified depth of the first occluder of a light ray at view angle `theta`:
/// the same map as [`normalised_depth`], clamped to [0, 1] instead of the view rays'
/// [`DEPTH_MARGIN`, 1 - `DEPTH_MARGIN`]. An occluder before every view ray of the frame (or
/// none) then lies up to `DEPTH_MARGIN` away from the nearest ray depth, not on it, so the
/// Fourier step does not blur it into half a light (a sun below the horizon lit 6 % of a
/// lit frame's maximum at the frame's low-angle border, issue 12).
pub fn occluder_depth(theta: f32, lo: f32, hi: f32) -> f32 {
    clamp(
        DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * ((theta - lo) / max(hi - lo, 1e-6)),
        0.0,
        1.0,
    )
}

/// View-ray depths use [`DEPTH_MARGIN`, 1 - `DEPTH_MARGIN`], occluder depths [0, 1]: the
/// Fourier series of the step is 2-periodic, so depth differences near +-1 would fall on
/// the periodic copy's discontinuity; the largest difference is 0.9.
pub const DEPTH_MARGIN: f32 = 0.1;

/// The frame's standard shadow map ([`super::common_shadow`]).
pub fn sm_view(f: &FrameUniforms) -> ShadowMapView {
    ShadowMapView {
        right: f.sm_right,
        up: f.sm_up,
        forward: f.sm_forward,
        origin: f.sm_origin,
        proj: f.sm_proj,
        size: [f.sizes2[0], 0, 0, 0],
    }
}

/// Standard shadow-map visibility of world point `p` (1 lit, 0 shadowed); `spot`: the
/// kernel's light switch.
pub fn sm_visibility(f: &FrameUniforms, sm: &Tex, p: Vec3, spot: bool) -> f32 {
    shadow_visibility_for(&sm_view(f), sm, p, spot)
}

/// Travel distance along a light ray to its first occluder, or
/// [`NO_OCCLUDER`](super::common_shadow::NO_OCCLUDER): the sun's light ray from `o` along
/// the light's direction.
pub fn sm_occluder_distance_sun(f: &FrameUniforms, sm: &Tex, o: Vec3) -> f32 {
    shadow_occluder_distance_orthographic(&sm_view(f), sm, o)
}

/// [`sm_occluder_distance_sun`] of a spot: the light ray from the light along `l`.
pub fn sm_occluder_distance_spot(f: &FrameUniforms, sm: &Tex, l: Vec3) -> f32 {
    shadow_occluder_distance_perspective(&sm_view(f), sm, l)
}

/// Unit view direction through the centre of pixel (x, y).
pub fn pixel_dir(f: &FrameUniforms, x: u32, y: u32) -> Vec3 {
    let ndc_x = 2.0 * (x as f32 + 0.5) / f.sizes[0] as f32 - 1.0;
    let ndc_y = 1.0 - 2.0 * (y as f32 + 0.5) / f.sizes[1] as f32;
    let t = f.cam_forward[3];
    (xyz(f.cam_forward)
        + xyz(f.cam_right) * (ndc_x * t * f.cam_right[3])
        + xyz(f.cam_up) * (ndc_y * t))
        .normalize()
}

/// The spot integrand at ray parameter `t` with the light and medium of the frame.
pub fn frame_spot_integrand(f: &FrameUniforms, eye: Vec3, dir: Vec3, t: f32) -> f32 {
    spot_integrand(
        eye,
        dir,
        t,
        xyz(f.light_pos),
        xyz(f.light_dir),
        f.light_pos[3],
        f.light_dir[3],
        f.medium,
    )
}

/// In-scattering along `[a, b]` of the pixel's ray by marching `steps` samples against the
/// standard shadow map `sm`, without `sigma_s p E` for the sun (as [`lit_span`]). The sun:
/// cell midpoints uniform in `t`; a spot: the midpoints of `steps` equiangular strata of
/// `[a, b]` ([`equiangular`]), so the 1/d^2 peak next to the lamp is sampled by its angle.
#[allow(
    clippy::too_many_arguments,
    reason = "line for line with the WGSL function's parameters"
)]
pub fn span_march(
    f: &FrameUniforms,
    sm: &Tex,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    steps: u32,
    spot: bool,
) -> f32 {
    let h = (b - a) / steps as f32;
    let strata = equiangular(eye, dir, xyz(f.light_pos), a, b, steps);
    let mut sum = 0.0;
    for k in 0..steps {
        let mut t = a + (k as f32 + 0.5) * h;
        let mut w = h;
        if spot {
            let tw = equiangular_sample(&strata, k as f32 + 0.5);
            t = tw.0;
            w = tw.1;
        }
        let v = sm_visibility(f, sm, eye + dir * t, spot);
        if spot {
            sum += v * w * frame_spot_integrand(f, eye, dir, t);
        } else {
            sum += v * transmittance_between(f.medium[0], a + k as f32 * h, a + (k + 1) as f32 * h);
        }
    }
    sum
}

/// In-scattering along `[0, s]` of the pixel's ray by marching `f.sizes2[1]` samples
/// ([`span_march`]): the epipole and anti-epipole discs of every epipolar family; without
/// the light colour.
pub fn epipole_march(f: &FrameUniforms, sm: &Tex, eye: Vec3, dir: Vec3, s: f32, spot: bool) -> f32 {
    let sum = span_march(f, sm, eye, dir, 0.0, s, f.sizes2[1], spot);
    if spot {
        sum
    } else {
        f.medium[1] * phase_hg(f.medium[2], -xyz(f.light_dir).dot(dir)) * sum
    }
}

/// Whether the pixel centred at `pc` lies in the epipole's or the anti-epipole's disc (radius
/// `epipole.w`), where the rectification degenerates and the families march instead
/// (`in_epipole_disc`).
pub fn in_epipole_disc(f: &FrameUniforms, pc: [f32; 2]) -> bool {
    let px = Vec3::new(pc[0], pc[1], 0.0);
    let radius = f.epipole[3];
    let near_epi =
        f.epipole[2] > 0.5 && (px - Vec3::new(f.epipole[0], f.epipole[1], 0.0)).length() < radius;
    let near_anti = f.anti_epipole[2] > 0.5
        && (px - Vec3::new(f.anti_epipole[0], f.anti_epipole[1], 0.0)).length() < radius;
    near_epi || near_anti
}

/// Row of the `slices` table for row coordinate `j` (a whole number): wrapped around when
/// the slices cover the full circle, else clamped.
pub fn row_index(j: f32, rows: u32, wrap: bool) -> u32 {
    let ji = j as i32;
    if wrap {
        (((ji % rows as i32) + rows as i32) % rows as i32) as u32
    } else {
        ji.clamp(0, rows as i32 - 1) as u32
    }
}

/// Distance along the pixel's own ray (angle `theta` to the axis) of column edge `x`, capped
/// at the surface distance `s`.
pub fn ray_t(f: &FrameUniforms, x: f32, delta: f32, theta: f32, s: f32, spot: bool) -> f32 {
    if spot {
        let psi = x * delta;
        let den = (theta + psi).sin();
        if den <= 1e-6 || theta + psi >= PI {
            return s;
        }
        min(f.axis[3] * psi.sin() / den, s)
    } else {
        min(x * delta / max(theta.sin(), 1e-6), s)
    }
}

/// View angle of direction `dir` to the axis (atan2: accurate near the axis, where acos
/// loses digits).
pub fn ray_theta(f: &FrameUniforms, dir: Vec3) -> f32 {
    let axis = xyz(f.axis);
    dir.cross(axis).length().atan2(dir.dot(axis))
}

/// Continuous row coordinate of the slice holding direction `dir`: its slice angle in rows
/// from the first row's start, wrapped into `[0, rows)` when the slices cover the full
/// circle, else clamped to `[0, rows]`. Row `floor(yc)` is the nearest ([`row_index`]).
pub fn ray_row_coord(f: &FrameUniforms, dir: Vec3) -> f32 {
    let rows = f.sizes[3];
    let mut yc = if f.fan_angles[2] > 0.5 {
        // Aligned rows: the screen angle of the ray's screen point around the fan's origin.
        let z = dir.dot(xyz(f.cam_forward));
        let t = f.cam_forward[3];
        let nx = dir.dot(xyz(f.cam_right)) / (z * t * f.cam_right[3]);
        let ny = dir.dot(xyz(f.cam_up)) / (z * t);
        let size = screen_size(f);
        let p = [(nx + 1.0) * 0.5 * size[0], (1.0 - ny) * 0.5 * size[1]];
        let d = [p[0] - f.fan_origin[0], p[1] - f.fan_origin[1]];
        let (ax, ay) = (f.fan_origin[2], f.fan_origin[3]);
        ((ax * d[1] - ay * d[0]).atan2(ax * d[0] + ay * d[1]) - f.fan_angles[0]) / f.fan_angles[1]
    } else {
        let phi = dir.dot(xyz(f.e2)).atan2(dir.dot(xyz(f.e1)));
        (phi - f.e1[3]) / f.e2[3]
    };
    if f.anti_epipole[3] > 0.5 {
        yc -= (yc / rows as f32).floor() * rows as f32;
    } else {
        yc = clamp(yc, 0.0, rows as f32);
    }
    yc
}

/// Column coordinate, before division by a row's spacing, of the point at distance `s`
/// along the view ray `dir` (view angle `theta`): the sun's distance from the axis, the
/// spot's angle at the lamp from the direction towards the eye (atan2, not acos of the
/// normalised cosine: acos loses digits near 0, where a point near the eye-lamp line lies,
/// off by up to 5 % of its distance in the round-trip test). The inverse of [`ray_t`].
pub fn ray_column(f: &FrameUniforms, eye: Vec3, dir: Vec3, s: f32, theta: f32, spot: bool) -> f32 {
    if spot {
        let q = eye + dir * s - xyz(f.light_pos);
        let to_eye = -xyz(f.axis);
        return q.cross(to_eye).length().atan2(q.dot(to_eye));
    }
    s * theta.sin()
}

/// View angle (to the axis) of the point at distance `s` along the light ray of column
/// coordinate `col` in its slice: the sun's ray at distance `v = col` from the axis, leaving
/// `eye + e v` along -axis; the spot's ray leaving the lamp at angle `psi = col` from the
/// direction towards the eye. [`ray_t`] maps it back to a distance along the view ray.
pub fn light_point_theta(f: &FrameUniforms, col: f32, s: f32, spot: bool) -> f32 {
    if spot {
        (s * col.sin()).atan2(f.axis[3] - s * col.cos())
    } else {
        col.atan2(-s)
    }
}

/// Unshadowed spot in-scattering over `[a, b]` of the ray (`common_model::spot_span`).
pub fn spot_segment(f: &FrameUniforms, eye: Vec3, dir: Vec3, a: f32, b: f32, panels: u32) -> f32 {
    spot_span(
        eye,
        dir,
        a,
        b,
        panels,
        xyz(f.light_pos),
        xyz(f.light_dir),
        f.light_pos[3],
        f.light_dir[3],
        f.medium,
    )
}

/// Ray distance of column edge `x` of a ray that crosses texels `0 .. n`: the last texel's
/// span ends at the surface `s` (the texel walks of `minmax_traverse` and `pst_sweep`).
pub fn edge_t(
    f: &FrameUniforms,
    x: u32,
    n: u32,
    delta: f32,
    theta: f32,
    s: f32,
    spot: bool,
) -> f32 {
    if x >= n {
        return s;
    }
    ray_t(f, x as f32, delta, theta, s, spot)
}

/// Unshadowed in-scattering over `[a, b]` of the ray, without `sigma_s p E` for the sun.
pub fn lit_span(f: &FrameUniforms, eye: Vec3, dir: Vec3, a: f32, b: f32, spot: bool) -> f32 {
    if spot {
        return spot_segment(f, eye, dir, a, b, max_u(f.sizes2[2] / 4, 1));
    }
    transmittance_between(f.medium[0], a, b)
}
