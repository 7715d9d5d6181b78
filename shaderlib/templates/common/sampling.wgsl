// scatter::sampling: the low-resolution sampling stage every family can use (`sampling =
// lowres`): where sample (i, j) stands, and which samples stand for a screen pixel (the
// four nearest, each only when close to the pixel in view depth). Host side and the
// reasoning: scatter_frame::sampling.
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

// The four samples nearest to a pixel and their weights.
struct LowresTaps {
    // Columns (x0, x1) and rows (y0, y1) of the samples (x0, y0), (x1, y0), (x0, y1),
    // (x1, y1), clamped inside the sample grid.
    cols: vec2<u32>,
    rows: vec2<u32>,
    // Their weights in that order: bilinear, times 0 for a sample not close in depth.
    w: vec4<f32>,
}

// The taps of pixel `p`. The bilinear fractions are multiples of 1 / scale, exact in f32, so
// a weight is exactly 0 only where the pixel lies on a sample's row or column, in every
// module that calls this: `lowres_covered` decides the same for the sampling pass and the
// upsample.
fn lowres_taps(depth: texture_2d<f32>, p: vec2<u32>, screen: vec2<u32>, scale: u32, depth_break: f32) -> LowresTaps {
    let grid = vec2<i32>(lowres_grid(screen, scale));
    let f = (vec2<f32>(p) - vec2<f32>(f32(scale / 2u))) / f32(scale);
    let fl = floor(f);
    let fr = clamp(f - fl, vec2<f32>(0.0), vec2<f32>(1.0));
    let i0 = vec2<i32>(fl);
    let lo = vec2<u32>(clamp(i0, vec2<i32>(0), grid - vec2<i32>(1)));
    let hi = vec2<u32>(clamp(i0 + vec2<i32>(1), vec2<i32>(0), grid - vec2<i32>(1)));
    let d = textureLoad(depth, p, 0).x;
    var t: LowresTaps;
    t.cols = vec2<u32>(lo.x, hi.x);
    t.rows = vec2<u32>(lo.y, hi.y);
    let bx = vec2<f32>(1.0 - fr.x, fr.x);
    let by = vec2<f32>(1.0 - fr.y, fr.y);
    for (var k = 0u; k < 4u; k++) {
        let cx = k % 2u;
        let cy = k / 2u;
        let q = lowres_pixel(vec2<u32>(t.cols[cx], t.rows[cy]), screen, scale);
        var w = 0.0;
        if depth_close(textureLoad(depth, q, 0).x, d, depth_break) {
            w = bx[cx] * by[cy];
        }
        t.w[k] = w;
    }
    return t;
}

// Whether some sample stands for pixel `p` (a positive weight); if not, the family's
// sampling pass evaluates the pixel itself.
fn lowres_covered(t: LowresTaps) -> bool {
    return t.w.x > 0.0 || t.w.y > 0.0 || t.w.z > 0.0 || t.w.w > 0.0;
}
