//! CPU mirror of `shaderlib/templates/common/shadow.wgsl` (`scatter::shadow`): the standard
//! shadow-map lookup every family shares (light-space coordinates, nearest texel fetch, depth
//! bias, the biased visibility test of the `shadow_map` ground truth, the distance to the
//! first occluder along a light ray).

use super::common_model::{max, select};
use super::texture::{Tex, xyz};
use glam::Vec3;

/// Stand-in for "no occluder": a travel distance far beyond any scene.
pub const NO_OCCLUDER: f32 = 1e30;

/// The engine's standard shadow map, as a family's uniform block stores it (WGSL
/// `ShadowMapView`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowMapView {
    /// Light-space right; w = near.
    pub right: [f32; 4],
    /// Light-space up; w = far.
    pub up: [f32; 4],
    /// Light-space forward; w = bias in texel footprints.
    pub forward: [f32; 4],
    /// Light-space origin; w = 0 orthographic, 1 perspective.
    pub origin: [f32; 4],
    /// Orthographic: x0, x1, y0, y1. Perspective: tan_half, 0, 0, 0.
    pub proj: [f32; 4],
    /// x = texels per side.
    pub size: [u32; 4],
}

/// Light-space coordinates of a world point in the standard shadow map.
pub fn shadow_light_space(v: &ShadowMapView, p: Vec3) -> Vec3 {
    let q = p - xyz(v.origin);
    Vec3::new(q.dot(xyz(v.right)), q.dot(xyz(v.up)), q.dot(xyz(v.forward)))
}

/// Texture coordinates (u, v) in [0, 1] of light-space point `ls` (outside: no coverage).
pub fn shadow_uv(v: &ShadowMapView, ls: Vec3) -> [f32; 2] {
    if v.origin[3] > 0.5 {
        shadow_uv_perspective(v, ls)
    } else {
        shadow_uv_orthographic(v, ls)
    }
}

/// [`shadow_uv`] of an orthographic map (the sun).
pub fn shadow_uv_orthographic(v: &ShadowMapView, ls: Vec3) -> [f32; 2] {
    [
        (ls.x - v.proj[0]) / (v.proj[1] - v.proj[0]),
        (v.proj[3] - ls.y) / (v.proj[3] - v.proj[2]),
    ]
}

/// [`shadow_uv`] of a perspective map (a spot).
pub fn shadow_uv_perspective(v: &ShadowMapView, ls: Vec3) -> [f32; 2] {
    let z = max(ls.z, 1e-6);
    let t = v.proj[0];
    [0.5 + 0.5 * ls.x / (z * t), 0.5 - 0.5 * ls.y / (z * t)]
}

/// Depth bias in world units at light-space depth `z`.
pub fn shadow_bias(v: &ShadowMapView, z: f32) -> f32 {
    if v.origin[3] > 0.5 {
        shadow_bias_perspective(v, z)
    } else {
        shadow_bias_orthographic(v)
    }
}

/// [`shadow_bias`] of an orthographic map (the same at every depth).
pub fn shadow_bias_orthographic(v: &ShadowMapView) -> f32 {
    let texel = max(v.proj[1] - v.proj[0], v.proj[3] - v.proj[2]) / v.size[0] as f32;
    v.forward[3] * texel
}

/// [`shadow_bias`] of a perspective map.
pub fn shadow_bias_perspective(v: &ShadowMapView, z: f32) -> f32 {
    let texel = 2.0 * max(z, 0.0) * v.proj[0] / v.size[0] as f32;
    v.forward[3] * texel
}

/// Stored depth of the nearest texel at (u, v), or 2 (beyond everything) outside the map.
pub fn shadow_fetch(v: &ShadowMapView, sm: &Tex, uv: [f32; 2]) -> f32 {
    let outside = uv[0] < 0.0 || uv[0] > 1.0 || uv[1] < 0.0 || uv[1] > 1.0;
    let n = v.size[0];
    let x = ((uv[0] * n as f32) as u32).min(n - 1);
    let y = ((uv[1] * n as f32) as u32).min(n - 1);
    select(sm.load(x, y), 2.0, outside)
}

/// Standard shadow-map visibility of world point `p` (1 lit, 0 shadowed): nearest texel,
/// biased, exactly the test of the `shadow_map` ground truth.
pub fn shadow_visibility(v: &ShadowMapView, sm: &Tex, p: Vec3) -> f32 {
    shadow_visibility_for(v, sm, p, v.origin[3] > 0.5)
}

/// [`shadow_visibility`] of a perspective map when `perspective`, else of an orthographic
/// one (the kernels pass their light kind, a template constant).
pub fn shadow_visibility_for(v: &ShadowMapView, sm: &Tex, p: Vec3, perspective: bool) -> f32 {
    let ls = shadow_light_space(v, p);
    let (near, far) = (v.right[3], v.up[3]);
    if perspective {
        let stored = shadow_fetch(v, sm, shadow_uv_perspective(v, ls));
        let depth = (ls.z - near) / (far - near);
        let lit = depth <= stored + shadow_bias_perspective(v, ls.z) / (far - near);
        // In front of the light's near plane: lit.
        return select(0.0, 1.0, lit | (ls.z <= near));
    }
    let stored = shadow_fetch(v, sm, shadow_uv_orthographic(v, ls));
    let depth = (ls.z - near) / (far - near);
    select(
        0.0,
        1.0,
        depth <= stored + shadow_bias_orthographic(v) / (far - near),
    )
}

/// Travel distance from `o` along the light ray `o + s l` to its first occluder, biased as
/// [`shadow_visibility`] biases (points before it are lit), or [`NO_OCCLUDER`]. For a spot the
/// ray must start at the shadow map's origin (the light).
pub fn shadow_occluder_distance(v: &ShadowMapView, sm: &Tex, o: Vec3, l: Vec3) -> f32 {
    let perspective = v.origin[3] > 0.5;
    if perspective {
        shadow_occluder_distance_perspective(v, sm, l)
    } else {
        shadow_occluder_distance_orthographic(v, sm, o)
    }
}

/// [`shadow_occluder_distance`] of an orthographic map: the ray from `o` travels along the
/// light's forward.
pub fn shadow_occluder_distance_orthographic(v: &ShadowMapView, sm: &Tex, o: Vec3) -> f32 {
    let ls = shadow_light_space(v, o);
    let (near, far) = (v.right[3], v.up[3]);
    let stored = shadow_fetch(v, sm, shadow_uv_orthographic(v, ls));
    let z = near + stored * (far - near);
    select(
        z + shadow_bias_orthographic(v) - ls.z,
        NO_OCCLUDER,
        stored >= 1.0,
    )
}

/// [`shadow_occluder_distance`] of a perspective map: the ray from the light along `l`.
pub fn shadow_occluder_distance_perspective(v: &ShadowMapView, sm: &Tex, l: Vec3) -> f32 {
    let (near, far) = (v.right[3], v.up[3]);
    let dir = Vec3::new(l.dot(xyz(v.right)), l.dot(xyz(v.up)), l.dot(xyz(v.forward)));
    if dir.z <= 1e-6 {
        return NO_OCCLUDER;
    }
    let stored = shadow_fetch(v, sm, shadow_uv_perspective(v, dir));
    if stored >= 1.0 {
        return NO_OCCLUDER;
    }
    let z = near + stored * (far - near);
    (z + shadow_bias_perspective(v, z)) / dir.z
}
