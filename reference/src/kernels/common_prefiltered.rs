//! CPU mirror of `shaderlib/templates/common/prefiltered.wgsl` (`scatter::prefiltered`): the
//! Fourier basis and coefficients, reference-ray weights, region bounds and the projective
//! mapping; plus the texture operations (loads, stores in the variant's format, bilinear
//! sampling) every mirror uses. The epipolar set-up it builds on is
//! [`super::common_epipolar`].
//!
//! Conventions are documented in `scatter_shaderlib::prefiltered::frame`.

use super::common_epipolar::{DEPTH_MARGIN, row_phi, slice_e};
use super::common_model::{
    PI, clamp, cone_falloff, exp, max, min, mix, sqrt, transmittance_between,
};
pub use super::common_shadow::NO_OCCLUDER;
use glam::Vec3;
use scatter_shaderlib::prefiltered::{FrameUniforms, SliceParams, Storage};

/// Smallest cone factor of a spot texel weight (see the WGSL): a region of the reference ray
/// outside the cone still averages its texels instead of storing an undefined mean.
pub const CONE_FLOOR: f32 = 1e-3;

/// An r32float texture (row-major from the top-left texel).
#[derive(Clone, Debug, PartialEq)]
pub struct Tex {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Texels.
    pub data: Vec<f32>,
}

impl Tex {
    /// A zeroed texture.
    pub fn new(width: u32, height: u32) -> Tex {
        Tex {
            width,
            height,
            data: vec![0.0; width as usize * height as usize],
        }
    }
    /// WGSL `textureLoad` (coordinates must be in range).
    pub fn load(&self, x: u32, y: u32) -> f32 {
        self.data[(y * self.width + x) as usize]
    }
    /// WGSL `textureStore`.
    pub fn store(&mut self, x: u32, y: u32, v: f32) {
        self.data[(y * self.width + x) as usize] = v;
    }
}

/// An rgba texture array (layer-major, then row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct TexArray {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Layers.
    pub layers: u32,
    /// Texels, index `(layer * height + y) * width + x`.
    pub data: Vec<[f32; 4]>,
}

impl TexArray {
    /// A zeroed array.
    pub fn new(width: u32, height: u32, layers: u32) -> TexArray {
        TexArray {
            width,
            height,
            layers,
            data: vec![[0.0; 4]; width as usize * height as usize * layers as usize],
        }
    }
    fn index(&self, x: u32, y: u32, layer: u32) -> usize {
        ((layer * self.height + y) * self.width + x) as usize
    }
    /// WGSL `textureLoad`.
    pub fn load(&self, x: u32, y: u32, layer: u32) -> [f32; 4] {
        self.data[self.index(x, y, layer)]
    }
    /// WGSL `textureStore` into a storage texture of format `storage` (quantised as the
    /// format stores it).
    pub fn store(&mut self, x: u32, y: u32, layer: u32, v: [f32; 4], storage: Storage) {
        let i = self.index(x, y, layer);
        self.data[i] = v.map(|c| quantise(c, storage));
    }
}

/// The value a storage texture of `storage` format keeps for `v`.
pub fn quantise(v: f32, storage: Storage) -> f32 {
    match storage {
        Storage::Rgba8unorm => (v.clamp(0.0, 1.0) * 255.0).round() / 255.0,
        Storage::Rgba16float => round_f16(v),
        Storage::Rgba32float => v,
    }
}

/// Rounds an f32 to the nearest f16 value (ties to even), returned as f32.
pub fn round_f16(v: f32) -> f32 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let e = v.abs().log2().floor() as i32;
    // Spacing of f16 values around v: 2^(e - 10) for normals, 2^-24 for subnormals.
    let q = if e < -14 {
        2f32.powi(-24)
    } else {
        2f32.powi(e - 10)
    };
    let r = (v / q).round_ties_even() * q;
    if r.abs() > 65504.0 {
        v.signum() * f32::INFINITY
    } else {
        r
    }
}

/// Bilinear sample of layer `layer` at texel-space position (`x`, `y`) (texel `i`'s centre at
/// `i + 0.5`), clamp-to-edge in x, wrap-around in y when `wrap_y`, else clamp-to-edge.
pub fn sample_bilinear(t: &TexArray, layer: u32, x: f32, y: f32, wrap_y: bool) -> [f32; 4] {
    let (x0, fx) = split(x - 0.5);
    let (y0, fy) = split(y - 0.5);
    let cx = |i: i64| i.clamp(0, i64::from(t.width) - 1) as u32;
    let h = i64::from(t.height);
    let cy = |j: i64| {
        if wrap_y {
            j.rem_euclid(h) as u32
        } else {
            j.clamp(0, h - 1) as u32
        }
    };
    let a = t.load(cx(x0), cy(y0), layer);
    let b = t.load(cx(x0 + 1), cy(y0), layer);
    let c = t.load(cx(x0), cy(y0 + 1), layer);
    let d = t.load(cx(x0 + 1), cy(y0 + 1), layer);
    let mut out = [0.0; 4];
    for k in 0..4 {
        let top = a[k] * (1.0 - fx) + b[k] * fx;
        let bottom = c[k] * (1.0 - fx) + d[k] * fx;
        out[k] = top * (1.0 - fy) + bottom * fy;
    }
    out
}

fn split(x: f32) -> (i64, f32) {
    let f = x.floor();
    (f as i64, x - f)
}

/// `.xyz` of a vec4.
pub fn xyz(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// Fourier frequency `c_k = pi (2k - 1)`.
pub fn freq(k: u32) -> f32 {
    PI * (2 * k - 1) as f32
}

/// Basis values of layer `layer` at depth `d`: `(sin c1 d, cos c1 d, sin c2 d, cos c2 d)`
/// with `k1 = 2 layer + 1`, `k2 = 2 layer + 2` (Klehm Eq. 8: B_{2k-1} = sin, B_{2k} = cos).
pub fn basis4(d: f32, layer: u32) -> [f32; 4] {
    let c1 = freq(2 * layer + 1);
    let c2 = freq(2 * layer + 2);
    [
        (c1 * d).sin(),
        (c1 * d).cos(),
        (c2 * d).sin(),
        (c2 * d).cos(),
    ]
}

/// Coefficients of layer `layer` for a ray of depth `d`:
/// `(2/c1 cos c1 d, -2/c1 sin c1 d, 2/c2 cos c2 d, -2/c2 sin c2 d)`, so that
/// `V = 0.5 + sum a . B` approximates the step `H(d_i - d)`.
pub fn coeff4(d: f32, layer: u32) -> [f32; 4] {
    let c1 = freq(2 * layer + 1);
    let c2 = freq(2 * layer + 2);
    [
        2.0 / c1 * (c1 * d).cos(),
        -2.0 / c1 * (c1 * d).sin(),
        2.0 / c2 * (c2 * d).cos(),
        -2.0 / c2 * (c2 * d).sin(),
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

/// Prefilter weight of column `i` of row `row`: the length of the reference ray it covers
/// (average), or the transmittance integral over that span (weighted), times the cone
/// falloff and `exp(-sigma_t r) / r^2` at the span's middle for a spot light.
pub fn texel_weight(
    f: &FrameUniforms,
    s: &SliceParams,
    row: u32,
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
        let e = slice_e(f, row_phi(f, row));
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

// ---- Projective rectification (Sec. 4.2), mirroring the WGSL section of the same name.

/// Column invariant `G_r` of region boundary `r` (0..=8).
pub fn proj_boundary(f: &FrameUniforms, r: u32) -> f32 {
    let mut v = f.proj_g2;
    if r < 4 {
        v = f.proj_g0;
    } else if r < 8 {
        v = f.proj_g1;
    }
    v[(r % 4) as usize]
}

/// Column invariant at continuous column `x` of region `r`.
pub fn proj_region_g(
    f: &FrameUniforms,
    x: f32,
    r: u32,
    regions: u32,
    width: u32,
    spot: bool,
) -> f32 {
    let b0 = region_start(r, regions, width, spot) as f32;
    let b1 = region_start(r + 1, regions, width, spot) as f32;
    mix(
        proj_boundary(f, r),
        proj_boundary(f, r + 1),
        (x - b0) / (b1 - b0),
    )
}

/// Continuous column of column invariant `g` (outside the map: extrapolated from the first
/// or last region).
pub fn proj_column(f: &FrameUniforms, g: f32, regions: u32, width: u32, spot: bool) -> f32 {
    let mut r = 0u32;
    while r + 1 < regions {
        if g > proj_boundary(f, r + 1) {
            break;
        }
        r += 1;
    }
    let g0 = proj_boundary(f, r);
    let g1 = proj_boundary(f, r + 1);
    let b0 = region_start(r, regions, width, spot) as f32;
    let b1 = region_start(r + 1, regions, width, spot) as f32;
    b0 + (b1 - b0) * (g0 - g) / (g0 - g1)
}

/// `qx` where a view ray of depth `m` meets the light rays of invariant `g`: `1 / g` (sun),
/// `D / (g + m)` (spot); `cap` when it never does or lies beyond `cap`.
pub fn proj_reach(f: &FrameUniforms, g: f32, m: f32, spot: bool, cap: f32) -> f32 {
    let mut num = 1.0;
    let mut den = g;
    if spot {
        num = f.axis[3];
        den = g + m;
    }
    if den * cap <= num {
        return cap;
    }
    num / den
}

/// Normalised rectified depth of a view ray of depth `m`.
pub fn proj_ray_depth(f: &FrameUniforms, m: f32) -> f32 {
    DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp((f.proj[2] - m) * f.proj[3], 0.0, 1.0)
}

/// Normalised rectified depth of a rasterised texel (clip `z / w` in [0, 1]).
pub fn proj_stored_depth(raw: f32) -> f32 {
    DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp(raw, 0.0, 1.0)
}

/// Projective counterpart of [`texel_weight`] for column `i` of region `r`: the exact span
/// of the row's reference ray that the texel covers (column 0 from the eye).
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn proj_texel_weight(
    f: &FrameUniforms,
    s: &SliceParams,
    i: u32,
    r: u32,
    regions: u32,
    weighted: bool,
    spot: bool,
) -> f32 {
    let width = f.sizes[2];
    let k = s.delta;
    let m = s.theta_ref;
    let len = sqrt(1.0 + k * k + m * m);
    let cap = 4.0 * f.theta[2];
    let mut t0 = 0.0;
    if i > 0 {
        t0 = proj_reach(
            f,
            proj_region_g(f, i as f32, r, regions, width, spot),
            m,
            spot,
            cap / len,
        ) * len;
    }
    let t1 = proj_reach(
        f,
        proj_region_g(f, (i + 1) as f32, r, regions, width, spot),
        m,
        spot,
        cap / len,
    ) * len;
    if !weighted {
        return t1 - t0;
    }
    let mut w = transmittance_between(f.medium[0], t0, t1);
    if spot {
        let dir = (xyz(f.e1) + xyz(f.e2) * k + xyz(f.axis) * m) / len;
        let to = xyz(f.eye) + dir * (0.5 * (t0 + t1)) - xyz(f.light_pos);
        let dl = max(to.length(), 1e-4);
        let cone = max(
            cone_falloff(
                (to / dl).dot(xyz(f.light_dir)),
                f.light_pos[3],
                f.light_dir[3],
            ),
            CONE_FLOOR,
        );
        w *= cone * exp(-f.medium[0] * dl) / (dl * dl);
    }
    w
}
