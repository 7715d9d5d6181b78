// scatter::prefiltered: what the kernels of the prefiltered family (Klehm et al. 2014) share
// beyond the epipolar set-up (`scatter::epipolar`: the `Frame` block, slices, the frame's
// shadow map, the epipole march): the Fourier basis and its coefficients (Sec. 3, Eq. 8),
// the prefilter's reference-ray weights (Eq. 11/12), and region bounds (Table 1).
// The family's column layout of a projective map is `scatter::prefiltered_projective`, so
// that epipolar variants compose none of it.
//
// Composed into kernels by naga_oil (`#import scatter::prefiltered::{...}`); plain WGSL, not
// an askama template. Conventions: `scatter_shaderlib::prefiltered::frame`. Mirrored line by
// line by reference/src/kernels/common_prefiltered.rs; the texture operations
// (`Tex::load`, `TexArray::store`, `mix4`: reference/src/kernels/texture.rs) are
// textureLoad, textureStore and mix in the kernels.

#define_import_path scatter::prefiltered

#import scatter::model::{PI, cone_falloff, transmittance_between}
#import scatter::epipolar::{Frame, SliceParams}


// Smallest cone factor of a spot texel weight: where a region of the reference ray lies
// outside the cone, its texels still average (nearly uniformly) instead of leaving the
// region's mean undefined (all-zero weights store F = 0, i.e. visibility 0.5), because a
// pixel's own ray may cross the cone where the reference ray does not.
const CONE_FLOOR: f32 = 1e-3f;

// Fourier frequency `c_k = pi (2k - 1)`.
fn freq(k: u32) -> f32 {
    return PI * f32(2u * k - 1u);
}

// Basis values of a layer from `a` = (sin, cos) of c1 d and `b` = (sin, cos) of c2 d,
// `k1 = 2 layer + 1`, `k2 = 2 layer + 2`: `(sin c1 d, cos c1 d, sin c2 d, cos c2 d)` (Klehm
// Eq. 8: B_{2k-1} = sin, B_{2k} = cos). The angles come by `turn`ing `(sin, cos)(pi d)` by
// `fourier_step`.
fn basis4(a: vec2<f32>, b: vec2<f32>) -> vec4<f32> {
    return vec4<f32>(a.x, a.y, b.x, b.y);
}

// (sin, cos) of a + b from (sin a, cos a) and (sin b, cos b).
fn turn(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(a.x * b.y + a.y * b.x, a.y * b.y - a.x * b.x);
}

// The step of the Fourier recurrence, (sin, cos) of 2 pi d = c_(k+1) d - c_k d, from
// `first` = (sin, cos) of c_1 d = pi d (double angle: no transcendental).
fn fourier_step(first: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(2.0 * first.x * first.y, 1.0 - 2.0 * first.x * first.x);
}

// Coefficients of layer `layer` from `a` = (sin, cos) of c1 d and `b` = (sin, cos) of c2 d:
// `(2/c1 cos c1 d, -2/c1 sin c1 d, 2/c2 cos c2 d, -2/c2 sin c2 d)`, so that
// `V = 0.5 + sum a . B` approximates the step `H(d_i - d)`. A ray's angles come by
// `turn`ing `(sin, cos)(pi d)` by `fourier_step` (two transcendentals per ray, not four per
// layer).
fn coeff4(a: vec2<f32>, b: vec2<f32>, layer: u32) -> vec4<f32> {
    let c1 = freq(2u * layer + 1u);
    let c2 = freq(2u * layer + 2u);
    return vec4<f32>(2.0 / c1 * a.y, -2.0 / c1 * a.x, 2.0 / c2 * b.y, -2.0 / c2 * b.x);
}

// First column of region `r` of `regions` in a row of `width` columns. Directional lights
// split rows quadratically (`width r^2 / regions^2`): transmittance concentrates the
// integrand near the eye (column 0), and finer regions there cut the reference-ray
// weighting error. Spot lights split uniformly (`width r / regions`), as in the paper.
fn region_start(r: u32, regions: u32, width: u32, spot: bool) -> u32 {
    if spot {
        return r * width / regions;
    }
    return r * r * width / (regions * regions);
}

// First rectified column of region `r` when `prefilter` stores every `stride`-th column
// (coarse filtered columns): regions start on multiples of the stride, at `stride` times the
// region's start in a row of `width / stride` columns. `stride = 1` is `region_start`.
fn region_column(r: u32, regions: u32, width: u32, stride: u32, spot: bool) -> u32 {
    return stride * region_start(r, regions, width / stride, spot);
}

// Distance from the eye, along the slice's reference ray, of column edge `x` (continuous,
// in columns), capped at four far-plane distances.
fn ref_t(f: Frame, s: SliceParams, x: f32, spot: bool) -> f32 {
    let cap = 4.0 * f.theta[2];
    if spot {
        let psi = x * s.delta;
        let den = sin(s.theta_ref + psi);
        if den <= 1e-4 || s.theta_ref + psi >= PI {
            return cap;
        }
        return min(f.axis[3] * sin(psi) / den, cap);
    } else {
        return min(x * s.delta / max(sin(s.theta_ref), 1e-4), cap);
    }
}

// Prefilter weight of column `i` of a row (slice parameters `s`, slice direction `e`, which
// the caller computes once per row): the length of the reference ray it covers (average), or
// the transmittance integral over that span (weighted), times the cone falloff and
// `exp(-sigma_t r) / r^2` at the span's middle for a spot light.
fn texel_weight(f: Frame, s: SliceParams, e: vec3<f32>, i: u32, weighted: bool, spot: bool) -> f32 {
    let t0 = ref_t(f, s, f32(i), spot);
    let t1 = ref_t(f, s, f32(i + 1u), spot);
    if !weighted {
        return t1 - t0;
    }
    var w = transmittance_between(f.medium[0], t0, t1);
    if spot {
        let psi = (f32(i) + 0.5) * s.delta;
        let l = -f.axis.xyz * cos(psi) + e * sin(psi);
        let den = max(sin(s.theta_ref + psi), 1e-4);
        let r = max(f.axis[3] * sin(s.theta_ref) / den, 1e-4);
        let cone = max(cone_falloff(dot(l, f.light_dir.xyz), f.light_pos[3], f.light_dir[3]), CONE_FLOOR);
        w *= cone * exp(-f.medium[0] * r) / (r * r);
    }
    return w;
}
