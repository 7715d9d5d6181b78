//! CPU mirror of `shaderlib/templates/ivsv_gather.wgsl`: per pixel and VPL, the eye ray's
//! integrand in the light angle `phi` at the ends of `segments` pieces of the cone's `phi`
//! interval, linear between them, summed over the unset voxel bits of the two nearest
//! `theta` rows with masked popcounts (the derivation: `scatter_reference::area_ivsv`).

use super::common_ivsv::{PHI_BITS, plane_normal, voxel_word};
use super::common_model::{cone_falloff, phase_hg};
use super::common_sampling::{
    EpipolarCamera, EpipolarSamples, SampledOutput, epipolar_samples, run_sampled,
};
use super::texture::{Tex, xyz};
use glam::Vec3;
use scatter_shaderlib::area_ivsv::{AreaIvsvVariant, IvsvUniforms, VplRecord};
use std::f32::consts::PI;

/// Unit view direction through the centre of pixel `(x, y)`.
pub fn ivsv_pixel_dir(m: &IvsvUniforms, x: u32, y: u32) -> Vec3 {
    let ndc_x = 2.0 * (x as f32 + 0.5) / m.sizes[0] as f32 - 1.0;
    let ndc_y = 1.0 - 2.0 * (y as f32 + 0.5) / m.sizes[1] as f32;
    let t = m.cam_forward[3];
    (xyz(m.cam_forward)
        + xyz(m.cam_right) * (ndc_x * t * m.cam_right[3])
        + xyz(m.cam_up) * (ndc_y * t))
        .normalize()
}

/// The 128 bits of texel `(i, j)` of VPL `v`.
pub fn voxel(m: &IvsvUniforms, volume: &[u32], v: u32, j: u32, i: u32) -> [u32; 4] {
    let at = voxel_word(m, v, j, i) as usize;
    [volume[at], volume[at + 1], volume[at + 2], volume[at + 3]]
}

/// `(count, sum of indices)` of the unset bits `k0 <= k < k1` of `bits`.
pub fn unset_moments(bits: [u32; 4], k0: u32, k1: u32) -> (f32, f32) {
    let mut n = 0u32;
    let mut sum = 0u32;
    for (w, word) in (0u32..).zip(bits) {
        let base = 32 * w;
        let lo = k0.clamp(base, base + 32) - base;
        let hi = k1.clamp(base, base + 32) - base;
        if hi > lo {
            let upper = if hi == 32 { u32::MAX } else { (1u32 << hi) - 1 };
            let x = !word & upper & !((1u32 << lo) - 1);
            let c = x.count_ones();
            n += c;
            sum += base * c
                + (x & 0xaaaa_aaaa).count_ones()
                + 2 * (x & 0xcccc_cccc).count_ones()
                + 4 * (x & 0xf0f0_f0f0).count_ones()
                + 8 * (x & 0xff00_ff00).count_ones()
                + 16 * (x & 0xffff_0000).count_ones();
        }
    }
    (n as f32, sum as f32)
}

/// The integrand in `phi` of a ray of eye angle `alpha` (sine `sa`) in the plane where the
/// spot axis has components `(c, sn)` along `-axis` and the plane normal, at the angle `phi`
/// given by `(cos, sin)` of `phi` (`cs`) and of `alpha + phi` (`cs_ap`).
pub fn density(
    m: &IvsvUniforms,
    r: &VplRecord,
    sa: f32,
    c: f32,
    sn: f32,
    cs: [f32; 2],
    cs_ap: [f32; 2],
) -> f32 {
    let sap = cs_ap[1];
    if sap <= 0.0 {
        return 0.0;
    }
    let cone = cone_falloff(c * cs[0] + sn * cs[1], r.spot_dir[3], r.color[3]);
    let p = phase_hg(m.medium[2], cs_ap[0]);
    let big_d = r.position[3];
    let path = big_d * (sa + cs[1]) / sap;
    m.medium[1] * p * cone * (-m.medium[0] * path).exp() / (big_d * sa)
}

/// `(cos, sin)` of `a + b` from `(cos, sin)` of `a` and of `b`.
pub fn rotate(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0] * b[0] - a[1] * b[1], a[1] * b[0] + a[0] * b[1]]
}

/// The first bit whose centre is at or beyond `phi`.
pub fn first_bit_from(phi: f32, d_phi: f32) -> u32 {
    (phi / d_phi - 0.5).ceil().clamp(0.0, PHI_BITS as f32) as u32
}

/// VPL `v`'s lit in-scattering along the view ray `dir` of length `s` (without its
/// intensity).
pub fn vpl_lit(
    m: &IvsvUniforms,
    r: &VplRecord,
    volume: &[u32],
    v: u32,
    dir: Vec3,
    s: f32,
    segments: u32,
) -> f32 {
    let big_d = r.position[3];
    let axis = xyz(r.axis);
    let alpha = dir
        .cross(axis)
        .length()
        .atan2(dir.dot(axis))
        .clamp(1e-6, PI - 1e-6);
    let sa = alpha.sin();
    let theta = dir.dot(xyz(r.perp_y)).atan2(dir.dot(xyz(r.perp_x)));
    let phi_max = r.perp_y[3];
    let phi_s = (s * sa)
        .atan2(big_d - s * alpha.cos())
        .min(PI - alpha)
        .min(phi_max);
    // The phi interval inside the outer cone.
    let c = -axis.dot(xyz(r.spot_dir));
    let sn = plane_normal(r, theta).dot(xyz(r.spot_dir));
    let rr = (c * c + sn * sn).sqrt();
    let cos_outer = r.color[3];
    if rr <= cos_outer {
        return 0.0;
    }
    let mut phi0 = sn.atan2(c);
    if phi0 < -0.5 * PI {
        phi0 += 2.0 * PI;
    }
    let delta = (cos_outer / rr).clamp(-1.0, 1.0).acos();
    let lo = (phi0 - delta).max(0.0);
    let hi = (phi0 + delta).min(phi_s);
    if lo >= hi {
        return 0.0;
    }
    // The two nearest theta rows and the alpha bin.
    let rows = m.grid[1];
    let xt = (theta + PI) / (2.0 * PI / rows as f32) - 0.5;
    let j0 = xt.floor();
    let tw = xt - j0;
    let ja = ((j0 as i32 + rows as i32) % rows as i32) as u32;
    let jb = (ja + 1) % rows;
    let i = ((alpha - r.axis[3]) / r.perp_x[3])
        .floor()
        .clamp(0.0, (m.grid[0] - 1) as f32) as u32;
    let bits_a = voxel(m, volume, v, ja, i);
    let bits_b = voxel(m, volume, v, jb, i);
    // Bits below phi_s, and the one holding it (covered part `cover`, centre `pc`).
    let d_phi = phi_max / PHI_BITS as f32;
    let xs = phi_s / d_phi;
    let ks = (xs as u32).min(PHI_BITS);
    let cover = xs - ks as f32;
    let pc = (ks as f32 + 0.5 * cover) * d_phi;
    let partial = ks < PHI_BITS && cover > 0.0;
    let (mut set_a, mut set_b) = (false, false);
    if partial {
        set_a = (bits_a[(ks / 32) as usize] >> (ks % 32)) & 1 == 1;
        set_b = (bits_b[(ks / 32) as usize] >> (ks % 32)) & 1 == 1;
    }
    let step = (hi - lo) / segments as f32;
    let (mut lit_a, mut lit_b) = (0.0f32, 0.0f32);
    // The knots' angles by rotation: two sines and cosines per VPL, not four per knot.
    let rot = [step.cos(), step.sin()];
    let mut cs = [lo.cos(), lo.sin()];
    let mut cs_ap = [(alpha + lo).cos(), (alpha + lo).sin()];
    let mut g_hi = density(m, r, sa, c, sn, cs, cs_ap);
    for p in 0..segments {
        let pa = lo + step * p as f32;
        let last = p + 1 == segments;
        let pb = if last { hi } else { lo + step * (p + 1) as f32 };
        cs = rotate(cs, rot);
        cs_ap = rotate(cs_ap, rot);
        let g_lo = g_hi;
        g_hi = density(m, r, sa, c, sn, cs, cs_ap);
        let slope = (g_hi - g_lo) / step;
        // Bits with their centre in [pa, pb) ([pa, hi] in the last piece), below ks.
        let k0 = first_bit_from(pa, d_phi);
        let mut k1 = first_bit_from(pb, d_phi);
        if last {
            k1 = ((hi / d_phi - 0.5).floor() + 1.0).clamp(0.0, PHI_BITS as f32) as u32;
        }
        k1 = k1.min(ks);
        if k1 > k0 {
            let a0 = g_lo + slope * (0.5 * d_phi - pa);
            let b0 = slope * d_phi;
            let ma = unset_moments(bits_a, k0, k1);
            let mb = unset_moments(bits_b, k0, k1);
            lit_a += a0 * ma.0 + b0 * ma.1;
            lit_b += a0 * mb.0 + b0 * mb.1;
        }
        if partial && pc >= pa && (pc < pb || (last && pc <= hi)) {
            let w = cover * (g_lo + slope * (pc - pa));
            lit_a += if set_a { 0.0 } else { w };
            lit_b += if set_b { 0.0 } else { w };
        }
    }
    d_phi * ((1.0 - tw) * lit_a + tw * lit_b)
}

/// The invocation of pixel `(x, y)`: its in-scattered radiance (rgb); with `interleave`
/// `M > 1` only its class's VPLs (the `c`-th of `M^2` consecutive runs, `c = (x mod M) +
/// M (y mod M)`), the partial sum.
#[expect(
    clippy::too_many_arguments,
    reason = "line-comparable to the WGSL entry point"
)]
pub fn gather_pixel(
    m: &IvsvUniforms,
    vpls: &[VplRecord],
    volume: &[u32],
    depth: &Tex,
    segments: u32,
    interleave: u32,
    x: u32,
    y: u32,
) -> [f32; 3] {
    let dir = ivsv_pixel_dir(m, x, y);
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s = depth.load(x, y).max(0.0).min(m.eye[3]) / dir.dot(xyz(m.cam_forward)).max(1e-6);
    let mut sum = Vec3::ZERO;
    let mi = interleave;
    let per_class = m.sizes[3] / (mi * mi);
    let first = ((x % mi) + mi * (y % mi)) * per_class;
    for v in first..first + per_class {
        let r = &vpls[v as usize];
        sum += xyz(r.color) * vpl_lit(m, r, volume, v, dir, s, segments);
    }
    sum.to_array()
}

/// The whole pass: the screen's radiance (`interleave = 1`, not yet rounded to
/// `rgba16float`) or partial sums (`rgba32float`), row-major.
pub fn ivsv_gather(
    m: &IvsvUniforms,
    vpls: &[VplRecord],
    volume: &[u32],
    depth: &Tex,
    segments: u32,
    interleave: u32,
) -> Vec<[f32; 3]> {
    use rayon::prelude::*;
    (0..m.sizes[0] * m.sizes[1])
        .into_par_iter()
        .map(|p| {
            gather_pixel(
                m,
                vpls,
                volume,
                depth,
                segments,
                interleave,
                p % m.sizes[0],
                p / m.sizes[0],
            )
        })
        .collect()
}

/// A variant without interleaving through its sampling (every pixel, `lowres` with its
/// upsample, or `epipolar` with `ivsv_gather_unwarp` and `ivsv_gather_fallback`):
/// [`run_sampled`] with [`gather_pixel`] as the pixel body; the slices radiate from the
/// VPLs' centroid.
pub fn ivsv_gather_sampled(
    variant: &AreaIvsvVariant,
    m: &IvsvUniforms,
    vpls: &[VplRecord],
    volume: &[u32],
    depth: &Tex,
) -> SampledOutput {
    run_sampled(
        &variant.sampling_knobs(),
        [m.sizes[0], m.sizes[1]],
        depth,
        &EpipolarCamera::of_ivsv(m),
        &|x, y| gather_pixel(m, vpls, volume, depth, variant.segments, 1, x, y),
    )
}

/// `ivsv_gather` of an `epipolar` variant: the samples of every slice (sampling pass 1).
pub fn ivsv_gather_epipolar_samples(
    variant: &AreaIvsvVariant,
    m: &IvsvUniforms,
    vpls: &[VplRecord],
    volume: &[u32],
    depth: &Tex,
) -> EpipolarSamples {
    epipolar_samples(
        &variant.sampling_knobs(),
        [m.sizes[0], m.sizes[1]],
        depth,
        &EpipolarCamera::of_ivsv(m),
        &|x, y| gather_pixel(m, vpls, volume, depth, variant.segments, 1, x, y),
    )
}
