//! CPU mirror of `shaderlib/templates/common/prefiltered.wgsl` (`scatter::prefiltered`): the
//! Fourier basis and coefficients, reference-ray weights and region bounds. It builds on the
//! epipolar set-up ([`super::common_epipolar`]); the family's column layout of a projective
//! map is [`super::common_prefiltered_projective`]; the texture operations every mirror uses
//! are [`super::texture`].
//!
//! Conventions are documented in `scatter_shaderlib::prefiltered::frame`.

use super::common_model::{PI, cone_falloff, exp, max, min, transmittance_between};
use super::texture::xyz;
use glam::Vec3;
use scatter_shaderlib::prefiltered::{FrameUniforms, SliceParams};

/// Smallest cone factor of a spot texel weight (see the WGSL): a region of the reference ray
/// outside the cone still averages its texels instead of storing an undefined mean.
pub const CONE_FLOOR: f32 = 1e-3;

/// Fourier frequency `c_k = pi (2k - 1)`.
pub fn freq(k: u32) -> f32 {
    PI * (2 * k - 1) as f32
}

/// Basis values of a layer from `a` = `(sin, cos)` of `c1 d` and `b` = `(sin, cos)` of
/// `c2 d`: `(sin c1 d, cos c1 d, sin c2 d, cos c2 d)` (Klehm Eq. 8).
pub fn basis4(a: [f32; 2], b: [f32; 2]) -> [f32; 4] {
    [a[0], a[1], b[0], b[1]]
}

/// `(sin, cos)` of `a + b` from `(sin a, cos a)` and `(sin b, cos b)`.
pub fn turn(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0] * b[1] + a[1] * b[0], a[1] * b[1] - a[0] * b[0]]
}

/// The step of the Fourier recurrence, `(sin, cos)` of `2 pi d = c_(k+1) d - c_k d`, from
/// `first` = `(sin, cos)` of `c_1 d = pi d` (double angle).
pub fn fourier_step(first: [f32; 2]) -> [f32; 2] {
    [2.0 * first[0] * first[1], 1.0 - 2.0 * first[0] * first[0]]
}

/// Coefficients of layer `layer` from `a` = `(sin, cos)` of `c1 d` and `b` = `(sin, cos)` of
/// `c2 d`: `(2/c1 cos c1 d, -2/c1 sin c1 d, 2/c2 cos c2 d, -2/c2 sin c2 d)`, so that
/// `V = 0.5 + sum a . B` approximates the step `H(d_i - d)`.
pub fn coeff4(a: [f32; 2], b: [f32; 2], layer: u32) -> [f32; 4] {
    let c1 = freq(2 * layer + 1);
    let c2 = freq(2 * layer + 2);
    [
        2.0 / c1 * a[1],
        -2.0 / c1 * a[0],
        2.0 / c2 * b[1],
        -2.0 / c2 * b[0],
    ]
}

/// Distance from the eye, along the slice's reference ray, of column edge `x` (continuous,
/// in columns), capped at four far-plane distances.
pub fn ref_t(f: &FrameUniforms, s: &SliceParams, x: f32, spot: bool) -> f32 {
    let cap = 4.0 * f.theta[2];
    if spot {
        let psi = x * s.delta;
        let den = (s.theta_ref + psi).sin();
        if den <= 1e-4 || s.theta_ref + psi >= PI {
            return cap;
        }
        min(f.axis[3] * psi.sin() / den, cap)
    } else {
        min(x * s.delta / max(s.theta_ref.sin(), 1e-4), cap)
    }
}

/// Prefilter weight of column `i` of a row (slice parameters `s`, slice direction `e`, which
/// the caller computes once per row): the length of the reference ray it covers (average),
/// or the transmittance integral over that span (weighted), times the cone falloff and
/// `exp(-sigma_t r) / r^2` at the span's middle for a spot light.
pub fn texel_weight(
    f: &FrameUniforms,
    s: &SliceParams,
    e: Vec3,
    i: u32,
    weighted: bool,
    spot: bool,
) -> f32 {
    let t0 = ref_t(f, s, i as f32, spot);
    let t1 = ref_t(f, s, (i + 1) as f32, spot);
    if !weighted {
        return t1 - t0;
    }
    let mut w = transmittance_between(f.medium[0], t0, t1);
    if spot {
        let psi = (i as f32 + 0.5) * s.delta;
        let l = -xyz(f.axis) * psi.cos() + e * psi.sin();
        let den = max((s.theta_ref + psi).sin(), 1e-4);
        let r = max(f.axis[3] * s.theta_ref.sin() / den, 1e-4);
        let cone = max(
            cone_falloff(l.dot(xyz(f.light_dir)), f.light_pos[3], f.light_dir[3]),
            CONE_FLOOR,
        );
        w *= cone * exp(-f.medium[0] * r) / (r * r);
    }
    w
}

/// First column of region `r` of `regions` in a row of `width` columns. Directional lights
/// split rows quadratically (`width r^2 / regions^2`): transmittance concentrates the
/// integrand near the eye (column 0), and finer regions there cut the reference-ray
/// weighting error (measured: foliage/epipole_on_screen 12.9 % -> 4.0 % rel L1 at 3
/// regions). Spot lights split uniformly (`width r / regions`), as in the paper: their
/// integrand peaks near the lamp, not the eye.
pub fn region_start(r: u32, regions: u32, width: u32, spot: bool) -> u32 {
    if spot {
        r * width / regions
    } else {
        r * r * width / (regions * regions)
    }
}

/// First rectified column of region `r` when `prefilter` stores every `stride`-th column
/// (coarse filtered columns): `stride` times the region's start in a row of `width / stride`
/// columns, so regions start on multiples of the stride. `stride = 1` is [`region_start`].
pub fn region_column(r: u32, regions: u32, width: u32, stride: u32, spot: bool) -> u32 {
    stride * region_start(r, regions, width / stride, spot)
}
