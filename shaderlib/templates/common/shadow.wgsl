// scatter::shadow: the standard shadow-map lookup every family shares: light-space
// coordinates, texel fetch (nearest), depth bias and the biased visibility test of the
// `shadow_map` ground truth, and the distance to the first occluder along a light ray.
//
// Composed into kernels by naga_oil (`#import scatter::shadow::{...}`); plain WGSL, not an
// askama template. Mirrored line by line by reference/src/kernels/common_shadow.rs; functions
// that read the map take it as a parameter (a shared module cannot see the kernel's bindings).
// Conventions: `scatter_shaderlib::prefiltered::ShadowMapDesc` (normalised linear light depth,
// texel (0, 0) top-left, 1 where nothing was hit).

#define_import_path scatter::shadow

// The engine's standard shadow map, as a family's uniform block stores it.
struct ShadowMapView {
    // Light-space right; w = near (light-space depth of stored 0).
    right: vec4<f32>,
    // Light-space up; w = far (light-space depth of stored 1).
    up: vec4<f32>,
    // Light-space forward (the direction light travels); w = bias in texel footprints.
    forward: vec4<f32>,
    // Light-space origin; w = 0 orthographic, 1 perspective.
    origin: vec4<f32>,
    // Orthographic: x0, x1, y0, y1. Perspective: tan_half, 0, 0, 0.
    proj: vec4<f32>,
    // x = texels per side; yzw unused.
    size: vec4<u32>,
}

// Stand-in for "no occluder": a travel distance far beyond any scene.
const NO_OCCLUDER: f32 = 1e30f;

// Light-space coordinates of a world point in the standard shadow map.
fn shadow_light_space(v: ShadowMapView, p: vec3<f32>) -> vec3<f32> {
    let q = p - v.origin.xyz;
    return vec3<f32>(dot(q, v.right.xyz), dot(q, v.up.xyz), dot(q, v.forward.xyz));
}

// Texture coordinates (u, v) in [0, 1] of light-space point `ls` (outside: no coverage).
fn shadow_uv(v: ShadowMapView, ls: vec3<f32>) -> vec2<f32> {
    if v.origin[3] > 0.5 {
        return shadow_uv_perspective(v, ls);
    } else {
        return shadow_uv_orthographic(v, ls);
    }
}

// `shadow_uv` of an orthographic map (the sun) and of a perspective one (a spot). A kernel
// generated for one light kind calls its half directly: llvmpipe runs both sides of a
// branch on the uniform `origin.w` under a mask (`rectify`, 1024x1024 map at 1280x720: 13.5
// ms with the branch, 11.0 ms calling its half).
fn shadow_uv_orthographic(v: ShadowMapView, ls: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(
        (ls.x - v.proj[0]) / (v.proj[1] - v.proj[0]),
        (v.proj[3] - ls.y) / (v.proj[3] - v.proj[2]),
    );
}

fn shadow_uv_perspective(v: ShadowMapView, ls: vec3<f32>) -> vec2<f32> {
    let z = max(ls.z, 1e-6);
    let t = v.proj[0];
    return vec2<f32>(0.5 + 0.5 * ls.x / (z * t), 0.5 - 0.5 * ls.y / (z * t));
}

// Depth bias in world units at light-space depth `z`.
fn shadow_bias(v: ShadowMapView, z: f32) -> f32 {
    if v.origin[3] > 0.5 {
        return shadow_bias_perspective(v, z);
    } else {
        return shadow_bias_orthographic(v);
    }
}

// `shadow_bias` of an orthographic map (the same at every depth) and of a perspective one.
fn shadow_bias_orthographic(v: ShadowMapView) -> f32 {
    let texel = max(v.proj[1] - v.proj[0], v.proj[3] - v.proj[2]) / f32(v.size.x);
    return v.forward[3] * texel;
}

fn shadow_bias_perspective(v: ShadowMapView, z: f32) -> f32 {
    let texel = 2.0 * max(z, 0.0) * v.proj[0] / f32(v.size.x);
    return v.forward[3] * texel;
}

fn shadow_fetch(v: ShadowMapView, sm: texture_2d<f32>, uv: vec2<f32>) -> f32 {
    // Without a branch: a texel at the clamped coordinates is loaded either way and the
    // outside case selected (as fast on llvmpipe as the early return it replaces, which
    // llvmpipe runs as a mask over the rest anyway).
    let outside = (uv[0] < 0.0) | (uv[0] > 1.0) | (uv[1] < 0.0) | (uv[1] > 1.0);
    let n = v.size.x;
    let x = min(u32(uv[0] * f32(n)), n - 1u);
    let y = min(u32(uv[1] * f32(n)), n - 1u);
    return select(textureLoad(sm, vec2<u32>(x, y), 0).x, 2.0, outside);
}

// Standard shadow-map visibility of world point `p` (1 lit, 0 shadowed): nearest texel,
// biased, exactly the test of the `shadow_map` ground truth.
fn shadow_visibility(v: ShadowMapView, sm: texture_2d<f32>, p: vec3<f32>) -> f32 {
    return shadow_visibility_for(v, sm, p, v.origin[3] > 0.5);
}

// `shadow_visibility` of a perspective map when `perspective`, else of an orthographic one.
// Kernels generated for one light kind pass their template constant: the other half is
// then compiled out, where a branch on the uniform `origin.w` runs both under llvmpipe
// (raymarch N = 64 at 1280x720: 139-140 ms against 142-148 ms with the branch).
fn shadow_visibility_for(v: ShadowMapView, sm: texture_2d<f32>, p: vec3<f32>, perspective: bool) -> f32 {
    let ls = shadow_light_space(v, p);
    let near = v.right[3]; let far = v.up[3];
    if perspective {
        let stored = shadow_fetch(v, sm, shadow_uv_perspective(v, ls));
        let depth = (ls.z - near) / (far - near);
        let lit = depth <= stored + shadow_bias_perspective(v, ls.z) / (far - near);
        // In front of the light's near plane: lit.
        return select(0.0, 1.0, lit | (ls.z <= near));
    }
    let stored = shadow_fetch(v, sm, shadow_uv_orthographic(v, ls));
    let depth = (ls.z - near) / (far - near);
    return select(0.0, 1.0, depth <= stored + shadow_bias_orthographic(v) / (far - near));
}

// Travel distance from `o` along the light ray `o + s l` to its first occluder, biased as
// `shadow_visibility` biases (points before it are lit), or NO_OCCLUDER. For a spot the
// ray must start at the shadow map's origin (the light).
fn shadow_occluder_distance(v: ShadowMapView, sm: texture_2d<f32>, o: vec3<f32>, l: vec3<f32>) -> f32 {
    let perspective = v.origin[3] > 0.5;
    if perspective {
        return shadow_occluder_distance_perspective(v, sm, l);
    } else {
        return shadow_occluder_distance_orthographic(v, sm, o);
    }
}

// `shadow_occluder_distance` of an orthographic map (the ray from `o` travels along the
// light's forward) and of a perspective one (the ray from the light along `l`).
fn shadow_occluder_distance_orthographic(v: ShadowMapView, sm: texture_2d<f32>, o: vec3<f32>) -> f32 {
    let ls = shadow_light_space(v, o);
    let near = v.right[3]; let far = v.up[3];
    let stored = shadow_fetch(v, sm, shadow_uv_orthographic(v, ls));
    let z = near + stored * (far - near);
    return select(z + shadow_bias_orthographic(v) - ls.z, NO_OCCLUDER, stored >= 1.0);
}

fn shadow_occluder_distance_perspective(v: ShadowMapView, sm: texture_2d<f32>, l: vec3<f32>) -> f32 {
    let near = v.right[3]; let far = v.up[3];
    let dir = vec3<f32>(dot(l, v.right.xyz), dot(l, v.up.xyz), dot(l, v.forward.xyz));
    if dir.z <= 1e-6 {
        return NO_OCCLUDER;
    }
    let stored = shadow_fetch(v, sm, shadow_uv_perspective(v, dir));
    if stored >= 1.0 {
        return NO_OCCLUDER;
    }
    let z = near + stored * (far - near);
    return (z + shadow_bias_perspective(v, z)) / dir.z;
}
