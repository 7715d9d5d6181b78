// scatter::cookie: a spot light's cookie (`scatter_frame::cookie`), for the kernels of the
// variants that read one (`cookie = true`): the cookie at a point, the spot quadrature of a
// span with the cookie at every node and as many panels as the cookie's texels need, and the
// epipole march with it. A module of its own so that the kernels without a cookie compose
// none of it.
//
// Composed into kernels by naga_oil (`#import scatter::cookie::{...}`); plain WGSL, not an
// askama template. Mirrored line by line by reference/src/kernels/common_cookie.rs; the
// functions take the kernel's `cookie` binding as a parameter.

#define_import_path scatter::cookie

#import scatter::model::{GL4_W, GL4_X, equiangular, equiangular_sample, spot_integrand}
#import scatter::epipolar::{Frame, frame_spot_integrand, sm_visibility}

// A spot light's cookie (scatter_frame::cookie) for the ray point `x`: the RGB texture
// `cookie` projected along the cone from the lamp at `light_pos` in the light frame `right`,
// `up`, `forward` (the spot's shadow-map basis), its square circumscribing the outer cone
// (`cos_outer`); bilinear between texel centres from four loads, clamped to the edge; black
// behind the lamp. Constant along each light ray.
fn spot_cookie(cookie: texture_2d<f32>, x: vec3<f32>, light_pos: vec3<f32>, right: vec3<f32>, up: vec3<f32>, forward: vec3<f32>, cos_outer: f32) -> vec3<f32> {
    let d = x - light_pos;
    let z = dot(d, forward);
    if z <= 0.0 {
        return vec3<f32>(0.0);
    }
    let tan_outer = sqrt(max(1.0 - cos_outer * cos_outer, 0.0)) / cos_outer;
    let a = dot(d, right) / (z * tan_outer);
    let b = dot(d, up) / (z * tan_outer);
    let size = vec2<i32>(textureDimensions(cookie));
    let p = vec2<f32>(0.5 * (a + 1.0), 0.5 * (1.0 - b)) * vec2<f32>(size) - 0.5;
    let p0 = floor(p);
    let f = p - p0;
    let i0 = clamp(vec2<i32>(p0), vec2<i32>(0), size - 1);
    let i1 = clamp(vec2<i32>(p0) + 1, vec2<i32>(0), size - 1);
    let top = mix(textureLoad(cookie, vec2<i32>(i0.x, i0.y), 0).xyz, textureLoad(cookie, vec2<i32>(i1.x, i0.y), 0).xyz, f.x);
    let bottom = mix(textureLoad(cookie, vec2<i32>(i0.x, i1.y), 0).xyz, textureLoad(cookie, vec2<i32>(i1.x, i1.y), 0).xyz, f.x);
    return mix(top, bottom, f.y);
}

// Most panels `spot_span_cookie` takes over one span.
const MAX_COOKIE_PANELS: u32 = 64u;

// Texture coordinates of world point `x` in the cookie's projection (`spot_cookie`), clamped
// to [0, 1]; (-1, -1) behind the lamp.
fn cookie_uv(x: vec3<f32>, light_pos: vec3<f32>, right: vec3<f32>, up: vec3<f32>, forward: vec3<f32>, cos_outer: f32) -> vec2<f32> {
    let d = x - light_pos;
    let z = dot(d, forward);
    if z <= 0.0 {
        return vec2<f32>(-1.0);
    }
    let tan_outer = sqrt(max(1.0 - cos_outer * cos_outer, 0.0)) / cos_outer;
    let a = dot(d, right) / (z * tan_outer);
    let b = dot(d, up) / (z * tan_outer);
    return clamp(vec2<f32>(0.5 * (a + 1.0), 0.5 * (1.0 - b)), vec2<f32>(0.0), vec2<f32>(1.0));
}

// The panels `spot_span_cookie` takes over `[a, b]` of the ray: at least `panels`, and one per
// cookie texel the span's projection crosses (a segment projects to a segment; counted along
// both axes, clamped to the texture), at most MAX_COOKIE_PANELS; the most where the span
// passes behind the lamp. A cookie's texels vary along the span at their own scale, which
// the spot quadrature's few panels do not follow: with 4 panels minmax was 9.4 % off the
// truth on spot_grate/ordinary with the 64^2 stained glass.
fn cookie_panels(cookie: texture_2d<f32>, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32, panels: u32, light_pos: vec3<f32>, right: vec3<f32>, up: vec3<f32>, forward: vec3<f32>, cos_outer: f32) -> u32 {
    let ua = cookie_uv(eye + dir * a, light_pos, right, up, forward, cos_outer);
    let ub = cookie_uv(eye + dir * b, light_pos, right, up, forward, cos_outer);
    if ua.x < 0.0 || ub.x < 0.0 {
        return max(panels, MAX_COOKIE_PANELS);
    }
    let texels = abs(ub - ua) * vec2<f32>(textureDimensions(cookie));
    return clamp(u32(ceil(texels.x + texels.y)), panels, max(panels, MAX_COOKIE_PANELS));
}

// The part of `[a, b]` of the ray inside the cookie's square pyramid (the lamp at its apex,
// `|d.right|, |d.up| <= d.forward tan_outer`), as (start, end); start >= end where the ray
// misses it. The outer cone is inscribed in the pyramid, so the spot's integrand is 0
// outside it: clipping the span to it changes no integral and spends no panel there.
fn cookie_clip(eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32, light_pos: vec3<f32>, right: vec3<f32>, up: vec3<f32>, forward: vec3<f32>, cos_outer: f32) -> vec2<f32> {
    let tan_outer = sqrt(max(1.0 - cos_outer * cos_outer, 0.0)) / cos_outer;
    let o = eye - light_pos;
    let z0 = dot(o, forward) * tan_outer;
    let z1 = dot(dir, forward) * tan_outer;
    var lo = a;
    var hi = b;
    // The four side planes g0 + g1 t >= 0: z tan -+ x >= 0, z tan -+ y >= 0.
    for (var k = 0u; k < 4u; k++) {
        let axis = select(up, right, k < 2u);
        let sign = select(-1.0, 1.0, k % 2u == 0u);
        let g0 = z0 + sign * dot(o, axis);
        let g1 = z1 + sign * dot(dir, axis);
        if g1 > 0.0 {
            lo = max(lo, -g0 / g1);
        } else if g1 < 0.0 {
            hi = min(hi, -g0 / g1);
        } else if g0 < 0.0 {
            hi = lo;
        }
    }
    return vec2<f32>(lo, hi);
}

// `spot_span` with the cookie (`spot_cookie`) at every node and `cookie_panels` panels over
// the part of `[a, b]` inside the cookie's pyramid (`cookie_clip`): the unshadowed RGB
// in-scattering of a spot with a cookie over `[a, b]` (without the light colour). The light
// frame is the shadow map's (`right`, `up`, `forward`). (Unclipped, a ray from behind the
// lamp took the most panels on every span: prefiltered's scatter with the cookie measured
// 481 ms at 320x180 on stained_glass, 10x the pass without it.)
fn spot_span_cookie(
    cookie: texture_2d<f32>,
    eye: vec3<f32>,
    dir: vec3<f32>,
    a: f32,
    b: f32,
    panels: u32,
    light_pos: vec3<f32>,
    light_dir: vec3<f32>,
    cos_inner: f32,
    cos_outer: f32,
    medium: vec4<f32>,
    right: vec3<f32>,
    up: vec3<f32>,
    forward: vec3<f32>,
) -> vec3<f32> {
    let span = cookie_clip(eye, dir, a, b, light_pos, right, up, forward, cos_outer);
    if !(span.x < span.y) {
        return vec3<f32>(0.0);
    }
    let n = cookie_panels(cookie, eye, dir, span.x, span.y, panels, light_pos, right, up, forward, cos_outer);
    let t0 = dot(light_pos - eye, dir);
    let h = max(length(eye + dir * t0 - light_pos), 1e-4 * max(span.y - span.x, 1e-6));
    let g0 = atan((span.x - t0) / h);
    let w = (atan((span.y - t0) / h) - g0) / f32(n);
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < n; k++) {
        let mid = g0 + (f32(k) + 0.5) * w;
        for (var q = 0u; q < 4u; q++) {
            let u = tan(mid + 0.5 * w * GL4_X[q]);
            let t = t0 + h * u;
            sum += GL4_W[q] * spot_integrand(eye, dir, t, light_pos, light_dir, cos_inner, cos_outer, medium) * (1.0 + u * u) * spot_cookie(cookie, eye + dir * t, light_pos, right, up, forward, cos_outer);
        }
    }
    return sum * (0.5 * w * h);
}

// A spot's cookie (`spot_cookie`) at world point `x`, in the frame's shadow-map
// frame. `cookie`: the kernel's `cookie` binding.
fn frame_cookie(f: Frame, cookie: texture_2d<f32>, x: vec3<f32>) -> vec3<f32> {
    return spot_cookie(cookie, x, f.light_pos.xyz, f.sm_right.xyz, f.sm_up.xyz, f.sm_forward.xyz, f.light_dir[3]);
}

// `span_march` of a spot with a cookie: each sample's integrand times the cookie (RGB).
fn span_march_cookie(f: Frame, sm: texture_2d<f32>, cookie: texture_2d<f32>, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32, steps: u32) -> vec3<f32> {
    let strata = equiangular(eye, dir, f.light_pos.xyz, a, b, steps);
    var sum = vec3<f32>(0.0);
    // `k + 1u <= steps`: see `span_march` (scatter::epipolar).
    for (var k = 0u; k + 1u <= steps; k++) {
        let tw = equiangular_sample(strata, f32(k) + 0.5);
        let x = eye + dir * tw.x;
        let v = sm_visibility(f, sm, x, true);
        sum += v * tw.y * frame_spot_integrand(f, eye, dir, tw.x) * frame_cookie(f, cookie, x);
    }
    return sum;
}

// `epipole_march` of a spot with a cookie (RGB, without the light colour).
fn epipole_march_cookie(f: Frame, sm: texture_2d<f32>, cookie: texture_2d<f32>, eye: vec3<f32>, dir: vec3<f32>, s: f32) -> vec3<f32> {
    return span_march_cookie(f, sm, cookie, eye, dir, 0.0, s, f.sizes2_[1]);
}

// `spot_segment` of a spot with a cookie (`spot_span_cookie`: at least
// `panels` panels, one per cookie texel crossed; RGB).
fn spot_segment_cookie(f: Frame, cookie: texture_2d<f32>, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32, panels: u32) -> vec3<f32> {
    return spot_span_cookie(cookie, eye, dir, a, b, panels, f.light_pos.xyz, f.light_dir.xyz, f.light_pos[3], f.light_dir[3], f.medium, f.sm_right.xyz, f.sm_up.xyz, f.sm_forward.xyz);
}

// `lit_span` of a spot with a cookie: `spot_segment_cookie` with `lit_span`'s panels (RGB,
// without the light colour).
fn lit_span_cookie(f: Frame, cookie: texture_2d<f32>, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32) -> vec3<f32> {
    return spot_segment_cookie(f, cookie, eye, dir, a, b, max(f.sizes2_[2] / 4u, 1u));
}
