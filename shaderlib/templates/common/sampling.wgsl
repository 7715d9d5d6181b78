// scatter::sampling: the low-resolution sampling stage every family can use (`sampling =
// lowres`): where sample (i, j) stands, which samples stand for a screen pixel, and when a
// pixel needs its own evaluation instead. Host side and the reasoning:
// scatter_frame::sampling.
//
// Mirrors reference/src/kernels/common_sampling.rs

#define_import_path scatter::sampling

// The sample grid of a screen at block side `scale`: samples at every S-th pixel from the
// first, and one on the last: ceil((screen - 1) / scale) + 1.
fn lowres_grid(screen: vec2<u32>, scale: u32) -> vec2<u32> {
    return (screen - vec2<u32>(1u, 1u) + vec2<u32>(scale - 1u, scale - 1u)) / scale + vec2<u32>(1u, 1u);
}

// The pixel sample `i` stands on: the first pixel of block i, or the screen's last pixel.
fn lowres_pixel(i: vec2<u32>, screen: vec2<u32>, scale: u32) -> vec2<u32> {
    return min(i * scale, screen - vec2<u32>(1u, 1u));
}

// Whether two view depths lie on one surface: equal (sky pixels at +inf included), or
// within `depth_break` (a fraction) of the nearer one.
fn depth_close(a: f32, b: f32, depth_break: f32) -> bool {
    return a == b || abs(a - b) <= depth_break * min(a, b);
}

// `v` rounded to f16 (to nearest, ties to even), as rgba16float stores it, clamped to f16's
// largest finite value. The samples are kept this way, so that a blend and the light
// criterion see a sample as a per-pixel pass would store it. (By bits, not with
// pack2x16float, which naga admits only with the SHADER_FLOAT16_IN_FLOAT32 capability.)
fn round_f16(v: vec3<f32>) -> vec3<f32> {
    let a = min(abs(v), vec3<f32>(65504.0));
    // Normal f16 range: keep 10 of the 23 mantissa bits, rounding to nearest even.
    let u = bitcast<vec3<u32>>(a);
    let normal = bitcast<vec3<f32>>((u + vec3<u32>(0xfffu) + ((u >> vec3<u32>(13u)) & vec3<u32>(1u))) & vec3<u32>(0xffffe000u));
    // Below 2^-14 f16 is subnormal: multiples of 2^-24 (`round` ties to even).
    let subnormal = round(a * 16777216.0) / 16777216.0;
    return sign(v) * select(normal, subnormal, a < vec3<f32>(6.103515625e-5));
}

// The four samples nearest to a pixel and their bilinear weights.
struct LowresTaps {
    // Columns (x0, x1) and rows (y0, y1) of the samples (x0, y0), (x1, y0), (x0, y1),
    // (x1, y1), clamped inside the sample grid.
    cols: vec2<u32>,
    rows: vec2<u32>,
    // Their bilinear weights in that order (a weight is exactly 0 where the pixel lies on
    // the other sample's column or row).
    w: vec4<f32>,
}

// The taps of pixel `p` in block p / S: samples p / S and p / S + 1 per axis (the block's
// first pixel and the next block's), weighted by the pixel's place between their pixels.
fn lowres_taps(p: vec2<u32>, screen: vec2<u32>, scale: u32) -> LowresTaps {
    let grid = lowres_grid(screen, scale);
    let lo = p / scale;
    let hi = min(lo + vec2<u32>(1u, 1u), grid - vec2<u32>(1u, 1u));
    let p0 = lowres_pixel(lo, screen, scale);
    let p1 = lowres_pixel(hi, screen, scale);
    let fr = vec2<f32>(p - p0) / vec2<f32>(max(p1 - p0, vec2<u32>(1u, 1u)));
    var t: LowresTaps;
    t.cols = vec2<u32>(lo.x, hi.x);
    t.rows = vec2<u32>(lo.y, hi.y);
    t.w = vec4<f32>((1.0 - fr.x) * (1.0 - fr.y), fr.x * (1.0 - fr.y), (1.0 - fr.x) * fr.y, fr.x * fr.y);
    return t;
}

// The pixel's radiance from its taps (`w` bilinear weights, `depths` of the taps' pixels,
// `light` their radiance, `d` the pixel's depth): the bilinear blend of the taps with a
// positive weight that lie within `depth_break` of `d`, in (rgb, 1); or alpha 0 where the
// pixel needs its own evaluation: no such tap (a depth break: a thin occluder, a
// silhouette), or the taps differ by more than `light_break` of the brightest channel of
// the brightest one (a shadow edge, the lamp; Yusov 2013's second criterion).
fn lowres_blend(w: vec4<f32>, depths: vec4<f32>, light: array<vec3<f32>, 4>, d: f32, depth_break: f32, light_break: f32) -> vec4<f32> {
    var sum = vec3<f32>(0.0, 0.0, 0.0);
    var total = 0.0;
    var lo = vec3<f32>(3.4e38, 3.4e38, 3.4e38);
    var hi = vec3<f32>(0.0, 0.0, 0.0);
    for (var k = 0u; k < 4u; k++) {
        if w[k] > 0.0 && depth_close(depths[k], d, depth_break) {
            sum += w[k] * light[k];
            total += w[k];
            lo = min(lo, light[k]);
            hi = max(hi, light[k]);
        }
    }
    if total <= 0.0 {
        return vec4<f32>(0.0, 0.0, 0.0, 0.0);
    }
    let spread = hi - lo;
    if max(spread.x, max(spread.y, spread.z)) > light_break * max(hi.x, max(hi.y, hi.z)) {
        return vec4<f32>(0.0, 0.0, 0.0, 0.0);
    }
    let c = sum / total;
    return vec4<f32>(c.x, c.y, c.z, 1.0);
}
