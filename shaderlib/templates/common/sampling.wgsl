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
// pixel needs its own evaluation: no such tap, or only one of several (a depth break: a
// thin occluder, a silhouette), or the taps differ by more than `light_break` of the brightest channel of
// the brightest one (a shadow edge, the lamp; Yusov 2013's second criterion).
fn lowres_blend(w: vec4<f32>, depths: vec4<f32>, light: array<vec3<f32>, 4>, d: f32, depth_break: f32, light_break: f32) -> vec4<f32> {
    var sum = vec3<f32>(0.0, 0.0, 0.0);
    var total = 0.0;
    var lo = vec3<f32>(3.4e38, 3.4e38, 3.4e38);
    var hi = vec3<f32>(0.0, 0.0, 0.0);
    var taps = 0u;
    var close = 0u;
    for (var k = 0u; k < 4u; k++) {
        taps += select(0u, 1u, w[k] > 0.0);
        if w[k] > 0.0 && depth_close(depths[k], d, depth_break) {
            close += 1u;
            sum += w[k] * light[k];
            total += w[k];
            lo = min(lo, light[k]);
            hi = max(hi, light[k]);
        }
    }
    // One close tap of several stands for nothing but itself (its light would be spread
    // over the pixels between it and the far taps, and the light criterion has nothing to
    // compare it with): a pixel beside a silhouette is evaluated unless it lies on the tap.
    if total <= 0.0 || close < min(taps, 2u) {
        return vec4<f32>(0.0, 0.0, 0.0, 0.0);
    }
    let spread = hi - lo;
    if max(spread.x, max(spread.y, spread.z)) > light_break * max(hi.x, max(hi.y, hi.z)) {
        return vec4<f32>(0.0, 0.0, 0.0, 0.0);
    }
    let c = sum / total;
    return vec4<f32>(c.x, c.y, c.z, 1.0);
}

// ---- sampling = epipolar (scatter_frame::sampling, "The epipolar passes") ----

// What an epipolar layout is built from: the camera and the direction towards the light.
struct EpipolarCamera {
    forward: vec3<f32>,
    right: vec3<f32>,
    up: vec3<f32>,
    // tan(fov_y / 2) and width / height.
    tan_half: f32,
    aspect: f32,
    // From the eye towards the light (any length).
    toward: vec3<f32>,
}

// A frame's slices: the epipole `origin` (pixel coordinates, pixel centres at + 0.5), the
// unit direction `axis` from it to the screen centre (angle 0), slice 0's first angle `phi_start`
// and the angle per slice `dphi` (radians, counter-clockwise from `axis` towards
// (-axis.y, axis.x)), and whether the origin is on screen (the slices go around it).
struct EpipolarLayout {
    origin: vec2<f32>,
    axis: vec2<f32>,
    phi_start: f32,
    dphi: f32,
    wrap: u32,
}

// The farthest the layout's origin lies from the screen centre, in screens (max(W, H)):
// lines from farther away are parallel to within a pixel's width, and f32 angles stay exact
// to a hundredth of a slice.
const EPIPOLE_FAR: f32 = 100.0;

// Angle of `d` from `axis` (counter-clockwise towards (-axis.y, axis.x)).
fn epipolar_angle(axis: vec2<f32>, d: vec2<f32>) -> f32 {
    return atan2(axis.x * d.y - axis.y * d.x, axis.x * d.x + axis.y * d.y);
}

// The layout of `slices` slices for a camera and a screen.
fn epipolar_layout(cam: EpipolarCamera, screen: vec2<u32>, slices: u32) -> EpipolarLayout {
    let size = vec2<f32>(screen);
    let centre = 0.5 * size;
    // The light direction in camera space; its screen point is centre + q / z.
    let z = dot(cam.toward, cam.forward);
    let q = vec2<f32>(dot(cam.toward, cam.right) * centre.x / (cam.tan_half * cam.aspect), -dot(cam.toward, cam.up) * centre.y / cam.tan_half);
    let far = EPIPOLE_FAR * max(size.x, size.y);
    let lq = length(q);
    var origin = centre;
    if lq >= far * abs(z) {
        // At or near infinity: the direction only (z's sign flips the side, not the lines).
        origin = centre + q * (far / max(lq, 1e-30)) * select(1.0, -1.0, z < 0.0);
    } else if lq > 0.0 {
        origin = centre + q / z;
    }
    var l: EpipolarLayout;
    l.origin = origin;
    let to_centre = centre - origin;
    let lc = length(to_centre);
    l.axis = select(vec2<f32>(1.0, 0.0), to_centre / max(lc, 1e-30), lc > 0.0);
    let lo = vec2<f32>(0.5, 0.5);
    let hi = size - vec2<f32>(0.5, 0.5);
    let inside = origin.x >= lo.x && origin.x <= hi.x && origin.y >= lo.y && origin.y <= hi.y;
    if inside {
        l.wrap = 1u;
        l.phi_start = -PI_SAMPLING;
        l.dphi = 2.0 * PI_SAMPLING / f32(slices);
    } else {
        l.wrap = 0u;
        var a = 0.0;
        var b = 0.0;
        for (var k = 0u; k < 4u; k++) {
            let corner = vec2<f32>(select(lo.x, hi.x, (k & 1u) != 0u), select(lo.y, hi.y, (k & 2u) != 0u));
            let phi = epipolar_angle(l.axis, corner - origin);
            if k == 0u {
                a = phi;
                b = phi;
            } else {
                a = min(a, phi);
                b = max(b, phi);
            }
        }
        l.phi_start = a;
        l.dphi = (b - a) / f32(slices);
    }
    return l;
}

const PI_SAMPLING: f32 = 3.14159265358979;

// Unit direction of slice `s`.
fn slice_direction(l: EpipolarLayout, s: u32) -> vec2<f32> {
    let phi = l.phi_start + (f32(s) + 0.5) * l.dphi;
    let c = cos(phi);
    let sn = sin(phi);
    return vec2<f32>(l.axis.x * c - l.axis.y * sn, l.axis.y * c + l.axis.x * sn);
}

// Where slice `s` runs inside the rectangle of pixel centres: (first distance from the
// origin, distance between samples); distances along `slice_direction`.
fn slice_span(l: EpipolarLayout, s: u32, screen: vec2<u32>, samples: u32) -> vec2<f32> {
    let u = slice_direction(l, s);
    let lo = vec2<f32>(0.5, 0.5);
    let hi = vec2<f32>(screen) - vec2<f32>(0.5, 0.5);
    var t_in = 0.0;
    var t_out = 3.4e38;
    for (var a = 0u; a < 2u; a++) {
        if abs(u[a]) > 1e-12 {
            let ta = (lo[a] - l.origin[a]) / u[a];
            let tb = (hi[a] - l.origin[a]) / u[a];
            t_in = max(t_in, min(ta, tb));
            t_out = min(t_out, max(ta, tb));
        }
    }
    // A slice that misses the rectangle (rounding at the outermost angles) keeps its samples
    // at its nearest point.
    t_out = max(t_out, t_in);
    return vec2<f32>(t_in, (t_out - t_in) / f32(samples - 1u));
}

// The pixel sample `k` of a slice (direction `u`, span `span`) stands on.
fn slice_sample_pixel(l: EpipolarLayout, u: vec2<f32>, span: vec2<f32>, k: u32, screen: vec2<u32>) -> vec2<u32> {
    let p = l.origin + u * (span.x + f32(k) * span.y);
    let last = vec2<f32>(screen) - vec2<f32>(1.0, 1.0);
    return vec2<u32>(clamp(floor(p), vec2<f32>(0.0, 0.0), last));
}

// The four samples a pixel is gathered from: slices `slices.x` and `slices.y`, samples
// (k.x, k.x + 1) on the first and (k.y, k.y + 1) on the second, and their bilinear weights
// in that order (a pixel beyond a slice's end takes its end sample: the depth test decides).
struct EpipolarTaps {
    slices: vec2<u32>,
    k: vec2<u32>,
    w: vec4<f32>,
}

// The slices on either side of pixel `p`'s angle (`t.slices`), the second one's weight in
// `t.w.y` (the rest of `t` is filled by `epipolar_taps`).
fn epipolar_slices(l: EpipolarLayout, p: vec2<u32>, slices: u32) -> EpipolarTaps {
    let d = vec2<f32>(p) + vec2<f32>(0.5, 0.5) - l.origin;
    let f = (epipolar_angle(l.axis, d) - l.phi_start) / l.dphi - 0.5;
    var s_lo = 0u;
    var fs = 0.0;
    if l.wrap != 0u {
        let fl = floor(f);
        fs = f - fl;
        s_lo = u32(i32(fl) + i32(slices)) % slices;
    } else {
        let fc = clamp(f, 0.0, f32(slices - 1u));
        s_lo = min(u32(fc), slices - 2u);
        fs = fc - f32(s_lo);
    }
    var t: EpipolarTaps;
    t.slices = vec2<u32>(s_lo, (s_lo + 1u) % slices);
    t.w = vec4<f32>(1.0 - fs, fs, 0.0, 0.0);
    return t;
}

// The taps of pixel `p` from its slices `pair` (`epipolar_slices`) and their lines
// `line_lo`, `line_hi` (direction xy, first distance z, distance between samples w; the last
// column of `epipolar_samples`): on each slice the samples on either side of the pixel's
// distance along it.
fn epipolar_taps(l: EpipolarLayout, p: vec2<u32>, pair: EpipolarTaps, line_lo: vec4<f32>, line_hi: vec4<f32>, samples: u32) -> EpipolarTaps {
    let d = vec2<f32>(p) + vec2<f32>(0.5, 0.5) - l.origin;
    var t = pair;
    let ws = pair.w.xy;
    for (var j = 0u; j < 2u; j++) {
        let line = select(line_lo, line_hi, j == 1u);
        let g = (dot(d, line.xy) - line.z) / max(line.w, 1e-20);
        let gc = clamp(g, 0.0, f32(samples - 1u));
        let k_lo = min(u32(gc), samples - 2u);
        let fk = gc - f32(k_lo);
        t.k[j] = k_lo;
        t.w[2u * j] = ws[j] * (1.0 - fk);
        t.w[2u * j + 1u] = ws[j] * fk;
    }
    return t;
}
