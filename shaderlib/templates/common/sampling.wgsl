// scatter::sampling: the low-resolution sampling stage every family can use (`sampling =
// lowres`): where sample (i, j) stands, which samples stand for a screen pixel, and when a
// pixel needs its own evaluation instead. Host side and the reasoning:
// scatter_frame::sampling.
//
// Mirrors reference/src/kernels/common_sampling.rs

#define_import_path scatter::sampling

// The sample grid of a screen at block side `scale`: ceil(screen / scale).
fn lowres_grid(screen: vec2<u32>, scale: u32) -> vec2<u32> {
    return (screen + vec2<u32>(scale - 1u, scale - 1u)) / scale;
}

// The pixel sample `i` stands on: the pixel S / 2 into its block (the block's centre, or the
// last pixel of the screen where the block is cut off).
fn lowres_pixel(i: vec2<u32>, screen: vec2<u32>, scale: u32) -> vec2<u32> {
    let h = scale / 2u;
    return min(i * scale + vec2<u32>(h, h), screen - vec2<u32>(1u, 1u));
}

// Whether two view depths lie on one surface: equal (sky pixels at +inf included), or
// within `depth_break` (a fraction) of the nearer one.
fn depth_close(a: f32, b: f32, depth_break: f32) -> bool {
    return a == b || abs(a - b) <= depth_break * min(a, b);
}

// The four samples nearest to a pixel and their bilinear weights.
struct LowresTaps {
    // Columns (x0, x1) and rows (y0, y1) of the samples (x0, y0), (x1, y0), (x0, y1),
    // (x1, y1), clamped inside the sample grid.
    cols: vec2<u32>,
    rows: vec2<u32>,
    // Their bilinear weights in that order: multiples of 1 / scale^2, exact in f32.
    w: vec4<f32>,
}

// The taps of pixel `p`: sample i sits at pixel i S + S / 2.
fn lowres_taps(p: vec2<u32>, screen: vec2<u32>, scale: u32) -> LowresTaps {
    let grid = vec2<i32>(lowres_grid(screen, scale));
    let f = (vec2<f32>(p) - vec2<f32>(f32(scale / 2u))) / f32(scale);
    let fl = floor(f);
    let fr = clamp(f - fl, vec2<f32>(0.0), vec2<f32>(1.0));
    let i0 = vec2<i32>(fl);
    let lo = vec2<u32>(clamp(i0, vec2<i32>(0), grid - vec2<i32>(1)));
    let hi = vec2<u32>(clamp(i0 + vec2<i32>(1), vec2<i32>(0), grid - vec2<i32>(1)));
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
