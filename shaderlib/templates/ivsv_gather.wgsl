// ivsv_gather: per pixel, the in-scattered light of every VPL from its extruded voxel bits
// (Wyman & Dai 2013, Sec. 4.3, with the bits weighted by the integrand instead of averaged).
//
// The pixel's view ray has, for VPL v, the eye angle alpha to the eye-VPL axis and the plane
// angle theta; along it the light angle phi runs from 0 (eye) to phi_s (the surface at
// distance s), t = D sin(phi) / sin(alpha + phi). In phi the integrand is
//   g(phi) = sigma_s p(cos(alpha + phi)) cone(u(phi) . spot) exp(-sigma_t D (sin alpha +
//            sin phi) / sin(alpha + phi)) / (D sin alpha)
// (dt/dphi = d^2 / (D sin alpha) cancels the 1 / d^2), zero outside the phi interval
// [lo, hi] where the ray is inside the VPL's outer cone: u(phi) . spot = c cos(phi) +
// s sin(phi) = R cos(phi - phi0), so the cone is |phi - phi0| <= acos(cos_outer / R),
// clipped to [0, phi_s]. g is evaluated at the ends of {{ segments }} equal pieces of [lo, hi]
// (their angles' sines and cosines by rotation from lo's) and is linear between them; bit k (centre (k + 0.5) d_phi, d_phi = phi_max / 128) weighs
// d_phi times the interpolant at its centre, the bit holding phi_s its covered part. The lit
// integral of a texel is the weight of its unset bits: per piece, with the weight
// d_phi (A + B k), A n + B sum(k) over the unset bits of the piece, from masked popcounts.
// The two rows nearest in theta are gathered and interpolated linearly (the grid wraps);
// alpha is the bin holding the ray. The sum over VPLs, each times its intensity, is the pixel.
{%- if interleave > 1 %}
// Interleaved (M = {{ interleave }}): pixel class c = (x mod M) + M (y mod M) sums only the c-th
// of M^2 consecutive runs of VPLs into `output` (the `partial` resource; a run of consecutive
// Halton points is spread over the whole light; every M^2-th point is not: the base-2 digits
// put them in one strip); `ivsv_interleave_sum` adds the M x M window of each pixel.
{%- endif %}
{%- if sampling.lowres || sampling.epipolar %}
// Sampled ({{ sampling.entry }}): the per-pixel body `ivsv_gather_pixel` runs on the sampling
// stage's samples (scatter::sampling; epipolar slices radiate from the screen point of the
// VPLs' centroid, frame.centre).
{%- endif %}
//
// Bindings (group 0):
// | binding | name   | type                                           | access       |
// |---------|--------|------------------------------------------------|--------------|
// | 0       | frame  | var<uniform> IvsvFrame (128 bytes)             | uniform      |
// | 1       | vpls   | var<uniform> array<Vpl, {{ vpls }}> (176 bytes each) | uniform |
// | 2       | volume | var<storage, read> array<u32> (`ivsv_scan`'s)  | read         |
// | 3       | depth  | texture_2d<f32> (r32float, view depth)         | textureLoad  |
// | 4       | output | texture_storage_2d<{{ output_format }}, write>         | textureStore |
{%- if interleave > 1 %}
// output: the `partial` resource, screen-sized, the pixel's class's share (rgb, alpha 1).
{%- else if sampling.lowres && !sampling.unwarp && !sampling.fallback %}
// output: the `lowres_samples` resource (scatter::sampling).
{%- else if sampling.epipolar && !sampling.unwarp && !sampling.fallback %}
// output: the `epipolar_samples` resource (scatter::sampling).
{%- else %}
// output: screen-sized, in-scattered radiance (rgb, alpha 1).
{%- endif %}
//
// Dispatch: (ceil(W / 8), ceil(H / 8), 1) workgroups of (8, 8, 1), W x H = screen size
// (frame.sizes.xy); invocation id x = pixel column, y = pixel row.
//
// Mirrors reference/src/kernels/ivsv_gather.rs

#import scatter::model::{PI, cone_falloff, phase_hg}
#import scatter::ivsv::{IvsvFrame, Vpl, PHI_BITS, plane_normal, voxel_word}
{%- if !sampling.imports.is_empty() %}
{{ sampling.imports }}
{%- endif %}

const SEGMENTS: u32 = {{ segments }}u;

@group(0) @binding(0) var<uniform> frame: IvsvFrame;
@group(0) @binding(1) var<uniform> vpls: array<Vpl, {{ vpls }}>;
@group(0) @binding(2) var<storage, read> volume: array<u32>;
@group(0) @binding(3) var depth: texture_2d<f32>;
@group(0) @binding(4) var output: texture_storage_2d<{{ output_format }}, write>;
{% include "include/sampled_bindings.wgsl" %}

// Unit view direction through the centre of pixel (x, y).
fn ivsv_pixel_dir(m: IvsvFrame, x: u32, y: u32) -> vec3<f32> {
    let ndc_x = 2.0 * (f32(x) + 0.5) / f32(m.sizes[0]) - 1.0;
    let ndc_y = 1.0 - 2.0 * (f32(y) + 0.5) / f32(m.sizes[1]);
    let t = m.cam_forward[3];
    return normalize(m.cam_forward.xyz + m.cam_right.xyz * (ndc_x * t * m.cam_right[3]) + m.cam_up.xyz * (ndc_y * t));
}

// The 128 bits of texel (i, j) of VPL v.
fn voxel(m: IvsvFrame, v: u32, j: u32, i: u32) -> vec4<u32> {
    let at = voxel_word(m, v, j, i);
    return vec4<u32>(volume[at], volume[at + 1u], volume[at + 2u], volume[at + 3u]);
}

// (count, sum of indices) of the unset bits k0 <= k < k1 of `bits`.
fn unset_moments(bits: vec4<u32>, k0: u32, k1: u32) -> vec2<f32> {
    var n = 0u;
    var sum = 0u;
    for (var w = 0u; w < 4u; w += 1u) {
        let base = 32u * w;
        let lo = clamp(k0, base, base + 32u) - base;
        let hi = clamp(k1, base, base + 32u) - base;
        if hi > lo {
            let upper = select((1u << hi) - 1u, 0xffffffffu, hi == 32u);
            let x = ~bits[w] & upper & ~((1u << lo) - 1u);
            let c = countOneBits(x);
            n += c;
            sum += base * c + countOneBits(x & 0xaaaaaaaau) + 2u * countOneBits(x & 0xccccccccu)
                + 4u * countOneBits(x & 0xf0f0f0f0u) + 8u * countOneBits(x & 0xff00ff00u)
                + 16u * countOneBits(x & 0xffff0000u);
        }
    }
    return vec2<f32>(f32(n), f32(sum));
}

// The integrand in phi of a ray of eye angle alpha (sin: sa) in the plane where the spot
// axis has components (c, sn) along -axis and the plane normal, at the angle phi given by
// (cos, sin) of phi (`cs`) and of alpha + phi (`cs_ap`).
fn density(m: IvsvFrame, r: Vpl, sa: f32, c: f32, sn: f32, cs: vec2<f32>, cs_ap: vec2<f32>) -> f32 {
    let sap = cs_ap.y;
    if sap <= 0.0 {
        return 0.0;
    }
    let cone = cone_falloff(c * cs.x + sn * cs.y, r.spot_dir[3], r.color[3]);
    let p = phase_hg(m.medium[2], cs_ap.x);
    let big_d = r.position[3];
    let path = big_d * (sa + cs.y) / sap;
    return m.medium[1] * p * cone * exp(-m.medium[0] * path) / (big_d * sa);
}

// (cos, sin) of a + b from (cos, sin) of a and of b.
fn rotate(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(a.x * b.x - a.y * b.y, a.y * b.x + a.x * b.y);
}

// The first bit whose centre is at or beyond phi.
fn first_bit_from(phi: f32, d_phi: f32) -> u32 {
    return u32(clamp(ceil(phi / d_phi - 0.5), 0.0, f32(PHI_BITS)));
}

// VPL v's lit in-scattering along the view ray `dir` of length s (without its intensity).
fn vpl_lit(m: IvsvFrame, r: Vpl, v: u32, dir: vec3<f32>, s: f32) -> f32 {
    let big_d = r.position[3];
    let axis = r.axis.xyz;
    let alpha = clamp(atan2(length(cross(dir, axis)), dot(dir, axis)), 1e-6, PI - 1e-6);
    let sa = sin(alpha);
    let theta = atan2(dot(dir, r.perp_y.xyz), dot(dir, r.perp_x.xyz));
    let phi_max = r.perp_y[3];
    let phi_s = min(min(atan2(s * sa, big_d - s * cos(alpha)), PI - alpha), phi_max);
    // The phi interval inside the outer cone.
    let c = -dot(axis, r.spot_dir.xyz);
    let sn = dot(plane_normal(r, theta), r.spot_dir.xyz);
    let rr = sqrt(c * c + sn * sn);
    let cos_outer = r.color[3];
    if rr <= cos_outer {
        return 0.0;
    }
    var phi0 = atan2(sn, c);
    if phi0 < -0.5 * PI {
        phi0 += 2.0 * PI;
    }
    let delta = acos(clamp(cos_outer / rr, -1.0, 1.0));
    let lo = max(phi0 - delta, 0.0);
    let hi = min(phi0 + delta, phi_s);
    if lo >= hi {
        return 0.0;
    }
    // The two nearest theta rows and the alpha bin.
    let rows = m.grid[1];
    let xt = (theta + PI) / (2.0 * PI / f32(rows)) - 0.5;
    let j0 = floor(xt);
    let tw = xt - j0;
    let ja = u32((i32(j0) + i32(rows)) % i32(rows));
    let jb = (ja + 1u) % rows;
    let i = u32(clamp(floor((alpha - r.axis[3]) / r.perp_x[3]), 0.0, f32(m.grid[0] - 1u)));
    let bits_a = voxel(m, v, ja, i);
    let bits_b = voxel(m, v, jb, i);
    // Bits below phi_s, and the one holding it (covered part `cover`, centre `pc`).
    let d_phi = phi_max / f32(PHI_BITS);
    let xs = phi_s / d_phi;
    let ks = min(u32(xs), PHI_BITS);
    let cover = xs - f32(ks);
    let pc = (f32(ks) + 0.5 * cover) * d_phi;
    let partial = ks < PHI_BITS && cover > 0.0;
    var set_a = false;
    var set_b = false;
    if partial {
        set_a = ((bits_a[ks / 32u] >> (ks % 32u)) & 1u) == 1u;
        set_b = ((bits_b[ks / 32u] >> (ks % 32u)) & 1u) == 1u;
    }
    let step = (hi - lo) / f32(SEGMENTS);
    var lit_a = 0.0;
    var lit_b = 0.0;
    // The knots' angles by rotation: two sines and cosines per VPL, not four per knot.
    let rot = vec2<f32>(cos(step), sin(step));
    var cs = vec2<f32>(cos(lo), sin(lo));
    var cs_ap = vec2<f32>(cos(alpha + lo), sin(alpha + lo));
    var g_hi = density(m, r, sa, c, sn, cs, cs_ap);
    for (var p = 0u; p < SEGMENTS; p += 1u) {
        let pa = lo + step * f32(p);
        let last = p + 1u == SEGMENTS;
        let pb = select(lo + step * f32(p + 1u), hi, last);
        cs = rotate(cs, rot);
        cs_ap = rotate(cs_ap, rot);
        let g_lo = g_hi;
        g_hi = density(m, r, sa, c, sn, cs, cs_ap);
        let slope = (g_hi - g_lo) / step;
        // Bits with their centre in [pa, pb) ([pa, hi] in the last piece), below ks.
        let k0 = first_bit_from(pa, d_phi);
        var k1 = first_bit_from(pb, d_phi);
        if last {
            k1 = u32(clamp(floor(hi / d_phi - 0.5) + 1.0, 0.0, f32(PHI_BITS)));
        }
        k1 = min(k1, ks);
        if k1 > k0 {
            let a0 = g_lo + slope * (0.5 * d_phi - pa);
            let b0 = slope * d_phi;
            let ma = unset_moments(bits_a, k0, k1);
            let mb = unset_moments(bits_b, k0, k1);
            lit_a += a0 * ma.x + b0 * ma.y;
            lit_b += a0 * mb.x + b0 * mb.y;
        }
        if partial && pc >= pa && (pc < pb || (last && pc <= hi)) {
            let w = cover * (g_lo + slope * (pc - pa));
            lit_a += select(w, 0.0, set_a);
            lit_b += select(w, 0.0, set_b);
        }
    }
    return d_phi * ((1.0 - tw) * lit_a + tw * lit_b);
}

// The in-scattered radiance of pixel (x, y){% if interleave > 1 %}, its class's VPLs only{% endif %} (the sampling entry point below calls it).
fn ivsv_gather_pixel(x: u32, y: u32) -> vec3<f32> {
    let m = frame;
    let dir = ivsv_pixel_dir(m, x, y);
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s = min(max(textureLoad(depth, vec2<u32>(x, y), 0).x, 0.0), m.eye.w) / max(dot(dir, m.cam_forward.xyz), 1e-6);
    var sum = vec3<f32>(0.0);
{%- if interleave > 1 %}
    let mi = {{ interleave }}u;
    let per_class = m.sizes[3] / (mi * mi);
    let first = ((x % mi) + mi * (y % mi)) * per_class;
    for (var v = first; v < first + per_class; v += 1u) {
{%- else %}
    // `v + 1u <= n`, not `v < n`: lavapipe re-specialises a shader at every dispatch when a loop
    // compares its counter with a uniform (`scatter_shaderlib::uniform_branches`).
    for (var v = 0u; v + 1u <= m.sizes[3]; v += 1u) {
{%- endif %}
        let r = vpls[v];
        sum += r.color.xyz * vpl_lit(m, r, v, dir, s);
    }
    return sum;
}
{% include "include/sampled_entry.wgsl" %}
