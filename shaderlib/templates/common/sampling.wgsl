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

// The pixel's radiance from its taps (`w` bilinear weights, `support` the weights that
// decide which taps stand around the pixel, `depths` of the taps' pixels, `light` their
// radiance, `d` the pixel's depth): the blend of the taps with a positive weight that lie
// within `depth_break` of `d`, in (rgb, 1); or alpha 0 where the pixel needs its own
// evaluation: no such tap, or only one of several taps with positive support (a depth
// break: a thin occluder, a silhouette), or the close taps with positive support differ by
// more than `light_break` of the brightest channel of the brightest one (a shadow edge, the
// lamp; Yusov 2013's second criterion). A pixel gathered alone passes its weights as
// `support`; a pixel of an epipolar block the block centre's weights (its own are clamped to
// the block's samples, and would hide the samples beyond them from both criteria).
fn lowres_blend(w: vec4<f32>, support: vec4<f32>, depths: vec4<f32>, light: array<vec3<f32>, 4>, d: f32, depth_break: f32, light_break: f32) -> vec4<f32> {
    var sum = vec3<f32>(0.0, 0.0, 0.0);
    var total = 0.0;
    var lo = vec3<f32>(3.4e38, 3.4e38, 3.4e38);
    var hi = vec3<f32>(0.0, 0.0, 0.0);
    var taps = 0u;
    var close = 0u;
    for (var k = 0u; k < 4u; k++) {
        let near = depth_close(depths[k], d, depth_break);
        taps += select(0u, 1u, support[k] > 0.0);
        if support[k] > 0.0 && near {
            close += 1u;
            lo = min(lo, light[k]);
            hi = max(hi, light[k]);
        }
        if w[k] > 0.0 && near {
            sum += w[k] * light[k];
            total += w[k];
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

// The four samples a block of pixels is gathered from (slices `slices.x` and `slices.y`,
// samples (k.x, k.x + 1) on the first and (k.y, k.y + 1) on the second), and how a pixel's
// weights follow from its place in the block: at the block's centre the second slice's
// fraction `fs` and the fractions `fk` along each slice from sample k, unclamped, and their
// changes per pixel (`gs`, `gk_lo`, `gk_hi`): the slice fraction's gradient (the angle's,
// perp(d) / |d|^2, over the angle per slice) and each slice's direction over its sample
// spacing (the distance along a slice is linear in the pixel).
struct EpipolarBlock {
    slices: vec2<u32>,
    k: vec2<u32>,
    fs: f32,
    gs: vec2<f32>,
    fk: vec2<f32>,
    gk_lo: vec2<f32>,
    gk_hi: vec2<f32>,
    // The range a pixel's own slice fraction keeps to (the fan's ends clamp it: -s_lo and
    // slices - 1 - s_lo; unbounded around a full circle), and its own fractions along the
    // slices (the slices' ends: -k and samples - 1 - k).
    fs_range: vec2<f32>,
    fk_min: vec2<f32>,
    fk_max: vec2<f32>,
}

// The slices around point `x` (pixel coordinates; a block's centre) as `epipolar_slices`
// chooses them for a pixel centre there, with the slice fraction and its gradient.
fn epipolar_block_slices(l: EpipolarLayout, x: vec2<f32>, slices: u32) -> EpipolarBlock {
    let d = x - l.origin;
    let f = (epipolar_angle(l.axis, d) - l.phi_start) / l.dphi - 0.5;
    var s_lo = 0u;
    var base = 0.0;
    if l.wrap != 0u {
        let fl = floor(f);
        base = fl;
        s_lo = u32(i32(fl) + i32(slices)) % slices;
    } else {
        let fc = clamp(f, 0.0, f32(slices - 1u));
        s_lo = min(u32(fc), slices - 2u);
        base = f32(s_lo);
    }
    var b: EpipolarBlock;
    b.slices = vec2<u32>(s_lo, (s_lo + 1u) % slices);
    b.fs = f - base;
    b.fs_range = select(vec2<f32>(-base, f32(slices - 1u) - base), vec2<f32>(-3.4e38, 3.4e38), l.wrap != 0u);
    // The gradient with its low 12 mantissa bits cleared: a pixel's offsets (multiples of
    // 1/2) then multiply it exactly, and the weights do not depend on whether a compiler
    // fuses |d|^2 into a multiply-add (the foreign engine compares the emitted SPIR-V with
    // the runtime's own compile to below one f16 step).
    let gs = vec2<f32>(-d.y, d.x) / (max(dot(d, d), 1e-20) * l.dphi);
    b.gs = bitcast<vec2<f32>>(bitcast<vec2<u32>>(gs) & vec2<u32>(0xfffff000u));
    return b;
}

// The samples around point `x` on the block's slices (`epipolar_block_slices`) from the
// slices' lines `line_lo`, `line_hi` (direction xy, first distance z, distance between
// samples w; the last column of `epipolar_samples`), with the fractions along the slices and
// their gradients (a point beyond a slice's end takes its end samples: the depth test decides).
fn epipolar_block_taps(l: EpipolarLayout, x: vec2<f32>, block: EpipolarBlock, line_lo: vec4<f32>, line_hi: vec4<f32>, samples: u32) -> EpipolarBlock {
    let d = x - l.origin;
    var b = block;
    let s0 = max(line_lo.w, 1e-20);
    let s1 = max(line_hi.w, 1e-20);
    let g = vec2<f32>((dot(d, line_lo.xy) - line_lo.z) / s0, (dot(d, line_hi.xy) - line_hi.z) / s1);
    let gc = clamp(g, vec2<f32>(0.0, 0.0), vec2<f32>(f32(samples - 1u)));
    b.k = min(vec2<u32>(gc), vec2<u32>(samples - 2u));
    b.fk = g - vec2<f32>(b.k);
    b.fk_min = -vec2<f32>(b.k);
    b.fk_max = vec2<f32>(f32(samples - 1u)) - vec2<f32>(b.k);
    b.gk_lo = line_lo.xy / s0;
    b.gk_hi = line_hi.xy / s1;
    return b;
}

// The bilinear weights of the block's four samples for the pixel whose centre lies `o`
// from the block's centre: the fractions moved by their gradients (kept to the ranges a
// pixel's own keep to) and clamped to [0, 1]. At the centre, `o` = 0, the weights of a pixel
// there; a pixel whose own slices or samples differ from the block's takes the nearest of
// the block's (at most 0.71 pixel from its own place), except where its own slice fraction
// lies more than half a slice beyond the block's slices (slices closer than a pixel: near
// an on-screen epipole, a small screen), where it gets no weights, which lists it for the
// fallback pass. Samples closer than a pixel along a slice (the short slices at a corner)
// are clamped: listing them too listed 14687 pixels instead of 345 on `sphere` at
// 1280x720 (minmax, 256 slices), and the fallback pass took 2.4 ms instead of 0.4.
fn epipolar_block_weights(b: EpipolarBlock, o: vec2<f32>) -> vec4<f32> {
    let own_s = clamp(b.fs + dot(b.gs, o), b.fs_range.x, b.fs_range.y);
    let own_k = clamp(b.fk + vec2<f32>(dot(b.gk_lo, o), dot(b.gk_hi, o)), b.fk_min, b.fk_max);
    let beyond = own_s < -0.5 || own_s > 1.5;
    let fs = clamp(own_s, 0.0, 1.0);
    let fk = clamp(own_k, vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 1.0));
    let w = vec4<f32>((1.0 - fs) * (1.0 - fk.x), (1.0 - fs) * fk.x, fs * (1.0 - fk.y), fs * fk.y);
    return select(w, vec4<f32>(0.0, 0.0, 0.0, 0.0), beyond);
}
