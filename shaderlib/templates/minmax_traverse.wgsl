// minmax_traverse ({{ light_name }} light): per pixel, in-scattered light by marching the pixel's
// rectified row through its 1D min-max tree (Chen et al. 2011, Sec. 4): at each texel the
// march climbs to the largest aligned node that fits in the rest of the ray, skips it whole
// when it is wholly lit (d <= min) or wholly shadowed (d > max) for the ray's depth d, and
// descends otherwise. Every maximal run of lit texels adds the pixel's unshadowed
// in-scattering over its span of the ray (closed form for the sun, Gauss-Legendre for a
// spot), so the result equals a brute-force march over every texel of the row. Pixels near
// the epipole or the anti-epipole are ray-marched against the standard shadow map, as in
// `scatter` (conventions: `scatter_frame::minmax`).
//
// Bindings (group 0):
// | binding | name       | type                                   | access       |
// |---------|------------|----------------------------------------|--------------|
// | 0       | frame      | var<uniform> Frame (432 bytes)         | uniform      |
// | 1       | slices     | var<storage, read> array<vec4<f32>>    | read         |
// | 2       | depth      | texture_2d<f32> (r32float, view depth) | textureLoad  |
// | 3       | shadow_map | texture_2d<f32> (r32float)             | textureLoad  |
// | 4       | tree       | texture_2d<f32> (rg32float, minmax_build's) | textureLoad |
// | 5       | output     | texture_storage_2d<rgba16float, write> | textureStore |
{%- if cookie %}
// | 12      | cookie     | texture_2d<f32> (rgba, linear RGB)     | textureLoad  |
{%- endif %}
// slices: one vec4 per rectified row (x = delta, y = theta_ref, z = theta_lo, w = theta_hi).
//
// Dispatch: (ceil(W / 8), ceil(H / 8), 1) workgroups of (8, 8, 1), W x H = screen size
// (frame.sizes.xy); invocation id x = pixel column, y = pixel row.
//
// Mirrors reference/src/kernels/minmax_traverse.rs

#import scatter::model::{phase_hg}
#import scatter::epipolar::{Frame, in_epipole_disc, edge_t, epipole_march, lit_span, normalised_depth, pixel_dir, ray_column, ray_row_coord, ray_theta, row_index, slice_params}
{%- if cookie %}
#import scatter::cookie::{epipole_march_cookie, lit_span_cookie}
{%- endif %}
#import scatter::minmax::{level_offset, tree_levels}
{%- if !sampling.imports.is_empty() %}
{{ sampling.imports }}
{%- endif %}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> slices: array<vec4<f32>>;
@group(0) @binding(2) var depth: texture_2d<f32>;
@group(0) @binding(3) var shadow_map: texture_2d<f32>;
@group(0) @binding(4) var tree: texture_2d<f32>;
@group(0) @binding(5) var output: texture_storage_2d<{{ sampling.output_format }}, write>;
{%- if cookie %}
// The spot's cookie (scatter_frame::cookie): lit spans and the epipole march carry it per node.
@group(0) @binding(12) var cookie: texture_2d<f32>;
{%- endif %}
{% include "include/sampled_bindings.wgsl" %}

// The in-scattered radiance of pixel (x, y) (the sampling entry point below calls it).
fn minmax_traverse_pixel(x: u32, y: u32) -> vec3<f32> {
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

    // Rectified coordinates of the surface point: the nearest row, its column x_s, depth d.
    let rows = f.sizes[3];
    let width = f.sizes[2];
    let wrap = f.anti_epipole[3] > 0.5;
    let theta = ray_theta(f, dir);
    let yc = ray_row_coord(f, dir);
    let row = row_index(floor(yc), rows, wrap);
    let delta = slice_params(slices[row]).delta;
    let d = normalised_depth(theta, f.theta[0], f.theta[1]);
    let xs = ray_column(f, eye, dir, s, theta, spot) / delta;
    // Texels the ray crosses (NaN or negative x_s: none).
    let n = u32(min(ceil(select(0.0, xs, xs > 0.0)), f32(width)));

    // Walk the tree: climb to the largest aligned node inside [i, n), descend while mixed.
    let levels = tree_levels(width);
    var total = {% if cookie %}vec3<f32>(0.0){% else %}0.0{% endif %};
    var in_run = false;
    var run_a = 0.0;
    var i = 0u;
    while i < n {
        var k = 0u;
        while k + 1u < levels && (i & ((2u << k) - 1u)) == 0u && i + (2u << k) <= n {
            k++;
        }
        var lit = false;
        loop {
            let node = textureLoad(tree, vec2<u32>(level_offset(k, width) + (i >> k), row), 0);
            if d <= node.x {
                lit = true;
                break;
            }
            if d > node.y || k == 0u {
                break;
            }
            k--;
        }
        if lit != in_run {
            let t = edge_t(f, i, n, delta, theta, s, spot);
            if lit {
                run_a = t;
            } else {
{%- if cookie %}
                total += lit_span_cookie(f, cookie, eye, dir, run_a, t);
{%- else %}
                total += lit_span(f, eye, dir, run_a, t, spot);
{%- endif %}
            }
            in_run = lit;
        }
        i += 1u << k;
    }
    if in_run {
{%- if cookie %}
        total += lit_span_cookie(f, cookie, eye, dir, run_a, s);
{%- else %}
        total += lit_span(f, eye, dir, run_a, s, spot);
{%- endif %}
    }
    var l = total;
    if !spot {
        l = f.medium[1] * phase_hg(f.medium[2], -dot(f.light_dir.xyz, dir)) * total;
    }
    let c = color * l;
    return c;
}
{% include "include/sampled_entry.wgsl" %}
