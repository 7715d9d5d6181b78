// volume_march ({{ light_name }} light): per pixel, in-scattered light with only the part
// [t_f, t_b] of the view ray that can hold a shadow boundary ray-marched against the
// standard shadow map (Wyman & Ramsey 2008, Sec. 4-5): {{ samples }} samples there; the head
// [0, t_f] and the tail [t_b, s] have one visibility each and add the unshadowed
// in-scattering in closed form (`closed_form`). The interval comes from `volume_bounds`: the
// two rectified rows whose slices bracket the ray each give their first and last boundary
// crossing for the ray's depth inside its texels 0 .. n, padded by {{ pad }} texel(s); the
// pixel's interval is their union, and a head or tail the two rows disagree on is marched
// too. Pixels near the epipole or the anti-epipole are marched whole (`epipole_march`), as
// in every epipolar family (conventions: `scatter_frame::hybrid_volume`).
//
// Bindings (group 0):
// | binding | name       | type                                   | access       |
// |---------|------------|----------------------------------------|--------------|
// | 0       | frame      | var<uniform> Frame (432 bytes)         | uniform      |
// | 1       | slices     | var<storage, read> array<vec4<f32>>    | read         |
// | 2       | depth      | texture_2d<f32> (r32float, view depth) | textureLoad  |
// | 3       | shadow_map | texture_2d<f32> (r32float)             | textureLoad  |
// | 4       | rectified  | texture_2d<f32> (r32float, `rectify`'s) | textureLoad |
// | 5       | crossings  | var<storage, read> array<u32> (`volume_bounds`'s: first, last per bin) | read |
// | 6       | output     | texture_storage_2d<rgba16float, write> | textureStore |
// slices: one vec4 per rectified row (x = delta, y = theta_ref, z = theta_lo, w = theta_hi).
//
// Dispatch: (ceil(W / 8), ceil(H / 8), 1) workgroups of (8, 8, 1), W x H = screen size
// (frame.sizes.xy); invocation id x = pixel column, y = pixel row.
//
// Mirrors reference/src/kernels/volume_march.rs

#import scatter::model::{phase_hg, transmittance_between}
#import scatter::epipolar::{Frame, in_epipole_disc, edge_t, epipole_march, normalised_depth, pixel_dir, ray_column, ray_row_coord, ray_theta, row_index, slice_params, span_march, spot_segment}
{%- if cookie %}
#import scatter::cookie::{epipole_march_cookie, span_march_cookie, spot_segment_cookie}
{%- endif %}
{%- if !sampling.imports.is_empty() %}
{{ sampling.imports }}
{%- endif %}

const SAMPLES: u32 = {{ samples }}u;
const BINS: u32 = {{ bins }}u;
const PAD: u32 = {{ pad }}u;
const NO_EDGE: u32 = 0xffffffffu;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> slices: array<vec4<f32>>;
@group(0) @binding(2) var depth: texture_2d<f32>;
@group(0) @binding(3) var shadow_map: texture_2d<f32>;
@group(0) @binding(4) var rectified: texture_2d<f32>;
@group(0) @binding(5) var<storage, read> crossings: array<u32>;
@group(0) @binding(6) var output: texture_storage_2d<{{ sampling.output_format }}, write>;
{%- if cookie %}
// The spot's cookie (scatter_frame::cookie): head, tail and march carry it per node.
@group(0) @binding(12) var cookie: texture_2d<f32>;
{%- endif %}
{% include "include/sampled_bindings.wgsl" %}

// What one rectified row says about a ray: the interval (t_f > t_b: no crossing) and the
// visibility before it (head) and after it (tail).
struct RowSpan {
    t_f: f32,
    t_b: f32,
    head: bool,
    tail: bool,
}

// The bin of ray depth `d` (as `volume_bounds`).
fn depth_bin(d: f32) -> u32 {
    return u32(clamp(floor(d * f32(BINS)), 0.0, f32(BINS - 1u)));
}

// Row `row`'s view of a ray of depth `d` (bin `bin`, view angle `theta`, surface at `s`)
// whose surface point has column coordinate `col` (before the row's spacing).
fn row_span(row: u32, col: f32, d: f32, bin: u32, theta: f32, s: f32, spot: bool) -> RowSpan {
    let f = frame;
    let width = f.sizes[2];
    let delta = slice_params(slices[row]).delta;
    let xs = col / delta;
    // Texels the ray crosses (NaN or negative x_s: none).
    let n = u32(min(ceil(select(0.0, xs, xs > 0.0)), f32(width)));
    if n == 0u {
        // No texel: nothing known, march it all.
        return RowSpan(0.0, s, true, true);
    }
    let head = d <= textureLoad(rectified, vec2<u32>(0u, row), 0).x;
    let first_edge = crossings[2u * (row * BINS + bin)];
    if first_edge == NO_EDGE || first_edge >= n {
        return RowSpan(s, 0.0, head, head);
    }
    let last = min(crossings[2u * (row * BINS + bin) + 1u], n - 1u);
    let tail = d <= textureLoad(rectified, vec2<u32>(last, row), 0).x;
    let first = select(first_edge - PAD, 0u, first_edge < PAD);
    return RowSpan(
        edge_t(f, first, n, delta, theta, s, spot),
        edge_t(f, last + PAD, n, delta, theta, s, spot),
        head,
        tail,
    );
}

// Unshadowed in-scattering over [a, b] (the head or the tail), without sigma_s p E for the
// sun: the sun's closed form; for a spot, Gauss-Legendre panels no coarser than the march,
// SAMPLES / 4 panels of 4 nodes (at least the frame's spot quadrature), so that the head and
// tail do not cap the accuracy the samples buy.
fn closed_form(f: Frame, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32, spot: bool) -> f32 {
    if spot {
        return spot_segment(f, eye, dir, a, b, max(max(f.sizes2_[2] / 4u, SAMPLES / 4u), 1u));
    }
    return transmittance_between(f.medium[0], a, b);
}
{%- if cookie %}

// `closed_form` of a spot with a cookie (RGB): at least as many panels, one per cookie texel
// crossed (`scatter::model::cookie_panels`).
fn closed_form_cookie(f: Frame, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32) -> vec3<f32> {
    return spot_segment_cookie(f, cookie, eye, dir, a, b, max(max(f.sizes2_[2] / 4u, SAMPLES / 4u), 1u));
}
{%- endif %}

// The in-scattered radiance of pixel (x, y) (the sampling entry point below calls it).
fn volume_march_pixel(x: u32, y: u32) -> vec3<f32> {
    let f = frame;
    let spot = {{ spot }};
    let eye = f.eye.xyz;
    let dir = pixel_dir(f, x, y);
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s = min(max(textureLoad(depth, vec2<u32>(x, y), 0).x, 0.0), f.theta.z) / max(dot(dir, f.cam_forward.xyz), 1e-6);
    let color = f.light_color.xyz;

    // Near the epipole and the anti-epipole the rectification degenerates: march instead.
    if in_epipole_disc(f, vec2<f32>(f32(x) + 0.5, f32(y) + 0.5)) {
{%- if cookie %}
        let l = epipole_march_cookie(frame, shadow_map, cookie, eye, dir, s) * color;
{%- else %}
        let l = epipole_march(frame, shadow_map, eye, dir, s, spot) * color;
{%- endif %}
        return l;
    }

    // The ray's depth and the two rows whose slices bracket it (row r's centre is r + 0.5).
    let rows = f.sizes[3];
    let wrap = f.anti_epipole[3] > 0.5;
    let theta = ray_theta(f, dir);
    let yc = ray_row_coord(f, dir);
    let d = normalised_depth(theta, f.theta[0], f.theta[1]);
    let bin = depth_bin(d);
    let col = ray_column(f, eye, dir, s, theta, spot);
    let j = floor(yc - 0.5);
    let a = row_span(row_index(j, rows, wrap), col, d, bin, theta, s, spot);
    let b = row_span(row_index(j + 1.0, rows, wrap), col, d, bin, theta, s, spot);
    var t_f = min(a.t_f, b.t_f);
    var t_b = max(a.t_b, b.t_b);
    if a.head != b.head {
        t_f = 0.0;
    }
    if a.tail != b.tail {
        t_b = s;
    }
    if t_b < t_f {
        // Neither row sees a crossing (and they agree): one visibility for the whole ray.
        t_f = s;
        t_b = s;
    }

    // Head and tail in closed form, [t_f, t_b] marched.
{%- if cookie %}
    var total = vec3<f32>(0.0);
    if a.head {
        total += closed_form_cookie(f, eye, dir, 0.0, t_f);
    }
    if t_b > t_f {
        total += span_march_cookie(f, shadow_map, cookie, eye, dir, t_f, t_b, SAMPLES);
    }
    if a.tail {
        total += closed_form_cookie(f, eye, dir, t_b, s);
    }
{%- else %}
    var total = 0.0;
    if a.head {
        total += closed_form(f, eye, dir, 0.0, t_f, spot);
    }
    if t_b > t_f {
        total += span_march(f, shadow_map, eye, dir, t_f, t_b, SAMPLES, spot);
    }
    if a.tail {
        total += closed_form(f, eye, dir, t_b, s, spot);
    }
{%- endif %}
    var l = total;
    if !spot {
        l = f.medium[1] * phase_hg(f.medium[2], -dot(f.light_dir.xyz, dir)) * total;
    }
    let c = color * l;
    return c;
}
{% include "include/sampled_entry.wgsl" %}
