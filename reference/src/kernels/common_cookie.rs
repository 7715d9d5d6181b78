//! CPU mirror of `shaderlib/templates/common/cookie.wgsl` (`scatter::cookie`): a spot
//! light's cookie at a point, the spot quadrature of a span with the cookie at every node and
//! [`cookie_panels`] panels, and the epipole march with it, in f32 as the kernels evaluate
//! them.

use super::common_epipolar::{frame_spot_integrand, sm_visibility};
use super::common_model::{
    GL4_W, GL4_X, clamp, equiangular, equiangular_sample, max, max_u, min, spot_integrand, sqrt,
};
use super::texture::{Tex, TexArray, xyz};
use glam::Vec3;
use scatter_shaderlib::prefiltered::FrameUniforms;

/// A spot light's cookie for the ray point `x` (see the WGSL comment): bilinear between
/// texel centres of `cookie` (layer 0) from four loads, clamped to the edge; black behind
/// the lamp.
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn spot_cookie(
    cookie: &TexArray,
    x: Vec3,
    light_pos: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    cos_outer: f32,
) -> Vec3 {
    let d = x - light_pos;
    let z = d.dot(forward);
    if z <= 0.0 {
        return Vec3::ZERO;
    }
    let tan_outer = sqrt(max(1.0 - cos_outer * cos_outer, 0.0)) / cos_outer;
    let a = d.dot(right) / (z * tan_outer);
    let b = d.dot(up) / (z * tan_outer);
    let size = [cookie.width as i32, cookie.height as i32];
    let p = [
        0.5 * (a + 1.0) * size[0] as f32 - 0.5,
        0.5 * (1.0 - b) * size[1] as f32 - 0.5,
    ];
    let p0 = [p[0].floor(), p[1].floor()];
    let f = [p[0] - p0[0], p[1] - p0[1]];
    // WGSL's f32 -> i32 conversion saturates, as Rust's `as` does.
    let i0 = [0, 1].map(|k| (p0[k] as i32).clamp(0, size[k] - 1) as u32);
    let i1 = [0, 1].map(|k| (p0[k] as i32).saturating_add(1).clamp(0, size[k] - 1) as u32);
    let texel = |x: u32, y: u32| {
        let t = cookie.load(x, y, 0);
        Vec3::new(t[0], t[1], t[2])
    };
    let mix3 = |a: Vec3, b: Vec3, t: f32| a * (1.0 - t) + b * t;
    let top = mix3(texel(i0[0], i0[1]), texel(i1[0], i0[1]), f[0]);
    let bottom = mix3(texel(i0[0], i1[1]), texel(i1[0], i1[1]), f[0]);
    mix3(top, bottom, f[1])
}

/// Most panels [`spot_span_cookie`] takes over one span.
pub const MAX_COOKIE_PANELS: u32 = 64;

/// Texture coordinates of world point `x` in the cookie's projection, clamped to [0, 1];
/// `(-1, -1)` behind the lamp. See the WGSL comment.
pub fn cookie_uv(x: Vec3, light_pos: Vec3, frame: [Vec3; 3], cos_outer: f32) -> [f32; 2] {
    let d = x - light_pos;
    let z = d.dot(frame[2]);
    if z <= 0.0 {
        return [-1.0, -1.0];
    }
    let tan_outer = sqrt(max(1.0 - cos_outer * cos_outer, 0.0)) / cos_outer;
    let a = d.dot(frame[0]) / (z * tan_outer);
    let b = d.dot(frame[1]) / (z * tan_outer);
    [
        clamp(0.5 * (a + 1.0), 0.0, 1.0),
        clamp(0.5 * (1.0 - b), 0.0, 1.0),
    ]
}

/// The panels [`spot_span_cookie`] takes over `[a, b]`: one per cookie texel the span's
/// projection crosses, within `[panels, max(panels, MAX_COOKIE_PANELS)]`. See the WGSL
/// comment.
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn cookie_panels(
    cookie: &TexArray,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    panels: u32,
    light_pos: Vec3,
    frame: [Vec3; 3],
    cos_outer: f32,
) -> u32 {
    let ua = cookie_uv(eye + dir * a, light_pos, frame, cos_outer);
    let ub = cookie_uv(eye + dir * b, light_pos, frame, cos_outer);
    if ua[0] < 0.0 || ub[0] < 0.0 {
        return panels.max(MAX_COOKIE_PANELS);
    }
    let tx = (ub[0] - ua[0]).abs() * cookie.width as f32;
    let ty = (ub[1] - ua[1]).abs() * cookie.height as f32;
    // WGSL's f32 -> u32 conversion saturates, as Rust's `as` does.
    ((tx + ty).ceil() as u32).clamp(panels, panels.max(MAX_COOKIE_PANELS))
}

/// The part of `[a, b]` of the ray inside the cookie's square pyramid, as `(start, end)`;
/// `start >= end` where the ray misses it. See the WGSL comment.
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn cookie_clip(
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    light_pos: Vec3,
    frame: [Vec3; 3],
    cos_outer: f32,
) -> [f32; 2] {
    let tan_outer = sqrt(max(1.0 - cos_outer * cos_outer, 0.0)) / cos_outer;
    let o = eye - light_pos;
    let z0 = o.dot(frame[2]) * tan_outer;
    let z1 = dir.dot(frame[2]) * tan_outer;
    let (mut lo, mut hi) = (a, b);
    for k in 0..4u32 {
        let axis = if k < 2 { frame[0] } else { frame[1] };
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        let g0 = z0 + sign * o.dot(axis);
        let g1 = z1 + sign * dir.dot(axis);
        if g1 > 0.0 {
            lo = max(lo, -g0 / g1);
        } else if g1 < 0.0 {
            hi = min(hi, -g0 / g1);
        } else if g0 < 0.0 {
            hi = lo;
        }
    }
    [lo, hi]
}

/// [`spot_span`] with the cookie ([`spot_cookie`]) at every node and [`cookie_panels`]
/// panels over the part of `[a, b]` inside the cookie's pyramid ([`cookie_clip`]) (RGB). See
/// the WGSL comment.
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn spot_span_cookie(
    cookie: &TexArray,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    panels: u32,
    light_pos: Vec3,
    light_dir: Vec3,
    cos_inner: f32,
    cos_outer: f32,
    medium: [f32; 4],
    frame: [Vec3; 3],
) -> Vec3 {
    let [lo, hi] = cookie_clip(eye, dir, a, b, light_pos, frame, cos_outer);
    // (`!(lo < hi)`, not `lo >= hi`: a NaN bound is a miss, as in the WGSL.)
    #[allow(clippy::neg_cmp_op_on_partial_ord, reason = "NaN is a miss")]
    if !(lo < hi) {
        return Vec3::ZERO;
    }
    let n = cookie_panels(
        cookie, eye, dir, lo, hi, panels, light_pos, frame, cos_outer,
    );
    let t0 = (light_pos - eye).dot(dir);
    let h = max(
        (eye + dir * t0 - light_pos).length(),
        1e-4 * max(hi - lo, 1e-6),
    );
    let g0 = ((lo - t0) / h).atan();
    let w = (((hi - t0) / h).atan() - g0) / n as f32;
    let mut sum = Vec3::ZERO;
    for k in 0..n {
        let mid = g0 + (k as f32 + 0.5) * w;
        for q in 0..4 {
            let u = (mid + 0.5 * w * GL4_X[q]).tan();
            let t = t0 + h * u;
            sum += GL4_W[q]
                * spot_integrand(
                    eye, dir, t, light_pos, light_dir, cos_inner, cos_outer, medium,
                )
                * (1.0 + u * u)
                * spot_cookie(
                    cookie,
                    eye + dir * t,
                    light_pos,
                    frame[0],
                    frame[1],
                    frame[2],
                    cos_outer,
                );
        }
    }
    sum * (0.5 * w * h)
}

/// A spot's cookie at world point `x` in the frame's shadow-map frame
/// ([`spot_cookie`]).
pub fn frame_cookie(f: &FrameUniforms, cookie: &TexArray, x: Vec3) -> Vec3 {
    spot_cookie(
        cookie,
        x,
        xyz(f.light_pos),
        xyz(f.sm_right),
        xyz(f.sm_up),
        xyz(f.sm_forward),
        f.light_dir[3],
    )
}

/// [`span_march`] of a spot with a cookie: each sample's integrand times the cookie (RGB).
#[allow(
    clippy::too_many_arguments,
    reason = "line for line with the WGSL function's parameters"
)]
pub fn span_march_cookie(
    f: &FrameUniforms,
    sm: &Tex,
    cookie: &TexArray,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    steps: u32,
) -> Vec3 {
    let strata = equiangular(eye, dir, xyz(f.light_pos), a, b, steps);
    let mut sum = Vec3::ZERO;
    for k in 0..steps {
        let tw = equiangular_sample(&strata, k as f32 + 0.5);
        let x = eye + dir * tw.0;
        let v = sm_visibility(f, sm, x, true);
        sum += v * tw.1 * frame_spot_integrand(f, eye, dir, tw.0) * frame_cookie(f, cookie, x);
    }
    sum
}

/// [`epipole_march`] of a spot with a cookie (RGB, without the light colour).
pub fn epipole_march_cookie(
    f: &FrameUniforms,
    sm: &Tex,
    cookie: &TexArray,
    eye: Vec3,
    dir: Vec3,
    s: f32,
) -> Vec3 {
    span_march_cookie(f, sm, cookie, eye, dir, 0.0, s, f.sizes2[1])
}

/// [`lit_span`] of a spot with a cookie (RGB, without the light colour).
pub fn lit_span_cookie(
    f: &FrameUniforms,
    cookie: &TexArray,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
) -> Vec3 {
    spot_segment_cookie(f, cookie, eye, dir, a, b, max_u(f.sizes2[2] / 4, 1))
}

/// `spot_segment` of a spot with a cookie
/// ([`spot_span_cookie`], RGB).
#[allow(
    clippy::too_many_arguments,
    reason = "line for line with the WGSL function's parameters"
)]
pub fn spot_segment_cookie(
    f: &FrameUniforms,
    cookie: &TexArray,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    panels: u32,
) -> Vec3 {
    spot_span_cookie(
        cookie,
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
        [xyz(f.sm_right), xyz(f.sm_up), xyz(f.sm_forward)],
    )
}
