// raymarch ({{ light_name }} light{% if interleaved %}, interleaved: partial sums{% endif %}): brute-force ray marching of the
// single-scattering integral through the standard shadow map, optionally with interleaved
// sampling (Tóth & Umenhoffer 2009).
//
// Per pixel: the view ray [0, s] (s from the depth buffer) is cut into N = frame.sizes.w
// cells; cell j is sampled at offset u = 0.5 or the pixel's jitter (frame.interleave.z).
// Directional: cells of length h = s / N in t, sampled at (j + u) h; each sample adds V times
// the exact transmittance integral over its cell, scaled once by sigma_s p E. Spot: N
// equiangular strata (`scatter::model::equiangular`: equal angles under which the lamp sees
// the ray, Kulla & Fajardo 2012), sampled at j + u; each adds V f(t) w with f the shadow-free
// integrand (cone, exp(-sigma_t (d + t)) / d^2, phase) and w = 1 / (N pdf(t)), which cancels
// the 1/d^2 peak of a ray passing next to the lamp; times I. With interleaving the pixel of
// class c = (x mod Mx) + Mx (y mod My) takes only the cells j = c (mod Mx My) (for a spot,
// its strata of the same equiangular set) and stores its partial sum for `interleave_sum`.
//
// Bindings (group 0):
// | binding | name       | type                                         | access       |
// |---------|------------|----------------------------------------------|--------------|
// | 0       | frame      | var<uniform> RaymarchFrame (240 bytes)               | uniform      |
// | 1       | depth      | texture_2d<f32> (r32float, view depth)       | textureLoad  |
// | 2       | shadow_map | texture_2d<f32> (r32float)                   | textureLoad  |
// | 3       | output     | texture_storage_2d<{{ output_format }}, write>           | textureStore |
{%- if cookie %}
// | 12      | cookie     | texture_2d<f32> (rgba, linear RGB)           | textureLoad  |
{%- endif %}
// output: screen-sized; {% if interleaved %}the partial sums `interleave_sum` reads{% else %}in-scattered radiance (rgb, alpha 1){% endif %}.
{%- if cookie %}
// cookie: the spot's cookie (scatter_frame::cookie), multiplying each sample's integrand.
{%- endif %}
//
// Dispatch: (ceil(W / 8), ceil(H / 8), 1) workgroups of (8, 8, 1), W x H = screen size
// (frame.sizes.xy); invocation id x = pixel column, y = pixel row.
//
// Mirrors reference/src/kernels/raymarch.rs

#import scatter::model::{equiangular, equiangular_sample, phase_hg, spot_integrand, transmittance_between}
{%- if cookie %}
#import scatter::cookie::spot_cookie
{%- endif %}
#import scatter::shadow::shadow_visibility_for
#import scatter::raymarch::{RaymarchFrame, raymarch_pixel_dir, raymarch_shadow_view, pixel_jitter}
{%- if !sampling.imports.is_empty() %}
{{ sampling.imports }}
{%- endif %}

@group(0) @binding(0) var<uniform> frame: RaymarchFrame;
@group(0) @binding(1) var depth: texture_2d<f32>;
@group(0) @binding(2) var shadow_map: texture_2d<f32>;
@group(0) @binding(3) var output: texture_storage_2d<{{ output_format }}, write>;
{%- if cookie %}
@group(0) @binding(12) var cookie: texture_2d<f32>;
{%- endif %}
{% include "include/sampled_bindings.wgsl" %}

// The in-scattered radiance of pixel (x, y) (the sampling entry point below calls it).
fn raymarch_pixel(x: u32, y: u32) -> vec3<f32> {
    let m = frame;
    let spot = {{ spot }};
    let eye = m.eye.xyz;
    let dir = raymarch_pixel_dir(m, x, y);
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s = min(max(textureLoad(depth, vec2<u32>(x, y), 0).x, 0.0), m.eye.w) / max(dot(dir, m.cam_forward.xyz), 1e-6);
    let n = m.sizes[3];
    let h = s / f32(n);
    let mx = m.interleave[0];
    let my = m.interleave[1];
    let stride = mx * my;
    let pixel_class = (x % mx) + mx * (y % my);
    // Selected, not branched on: lavapipe re-specialises a shader branching on a uniform at
    // every dispatch (`scatter_shaderlib::uniform_branches`; the epipolar samples pass 6.9-7.7
    // ms at 1280x720 with the branch, 3.3-4.2 ms without).
    let u = select(0.5, pixel_jitter(x, y), m.interleave[2] != 0u);
    let view = raymarch_shadow_view(m);
    let strata = equiangular(eye, dir, m.light_pos.xyz, 0.0, s, n);
    var sum = {% if cookie %}vec3<f32>(0.0){% else %}0.0{% endif %};
    for (var j = pixel_class; j < n; j += stride) {
        var t = (f32(j) + u) * h;
        var w = h;
        if spot {
            let tw = equiangular_sample(strata, f32(j) + u);
            t = tw.x;
            w = tw.y;
        }
        let v = shadow_visibility_for(view, shadow_map, eye + dir * t, spot);
        if spot {
{%- if cookie %}
            let x = eye + dir * t;
            sum += v * w * spot_integrand(eye, dir, t, m.light_pos.xyz, m.light_dir.xyz, m.light_pos[3], m.light_dir[3], m.medium) * spot_cookie(cookie, x, m.light_pos.xyz, m.sm_right.xyz, m.sm_up.xyz, m.sm_forward.xyz, m.light_dir[3]);
{%- else %}
            sum += v * w * spot_integrand(eye, dir, t, m.light_pos.xyz, m.light_dir.xyz, m.light_pos[3], m.light_dir[3], m.medium);
{%- endif %}
        } else {
            sum += v * transmittance_between(m.medium[0], f32(j) * h, f32(j + 1u) * h);
        }
    }
    var l = sum;
    if !spot {
        l = m.medium[1] * phase_hg(m.medium[2], -dot(m.light_dir.xyz, dir)) * sum;
    }
    let c = m.light_color.xyz * l;
    return c;
}
{% include "include/sampled_entry.wgsl" %}
