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
        let z = max(ls.z, 1e-6);
        let t = v.proj[0];
        [0.5 + 0.5 * ls.x / (z * t), 0.5 - 0.5 * ls.y / (z * t)]
    } else {
        [
            (ls.x - v.proj[0]) / (v.proj[1] - v.proj[0]),
            (v.proj[3] - ls.y) / (v.proj[3] - v.proj[2]),
        ]
    }
}

/// Depth bias in world units at light-space depth `z`.
pub fn shadow_bias(v: &ShadowMapView, z: f32) -> f32 {
    let size = v.size[0] as f32;
    let texel = if v.origin[3] > 0.5 {
        2.0 * max(z, 0.0) * v.proj[0] / size
    } else {
        max(v.proj[1] - v.proj[0], v.proj[3] - v.proj[2]) / size
    };
    v.forward[3] * texel
}

/// Stored depth of the nearest texel at (u, v), or 2 (beyond everything) outside the map.
pub fn shadow_fetch(v: &ShadowMapView, sm: &Tex, uv: [f32; 2]) -> f32 {
    if uv[0] < 0.0 || uv[0] > 1.0 || uv[1] < 0.0 || uv[1] > 1.0 {
        return 2.0;
    }
    let n = v.size[0];
    let x = ((uv[0] * n as f32) as u32).min(n - 1);
    let y = ((uv[1] * n as f32) as u32).min(n - 1);
    sm.load(x, y)
}

/// Standard shadow-map visibility of world point `p` (1 lit, 0 shadowed): nearest texel,
/// biased, exactly the test of the `shadow_map` ground truth.
pub fn shadow_visibility(v: &ShadowMapView, sm: &Tex, p: Vec3) -> f32 {
    let ls = shadow_light_space(v, p);
    let (near, far) = (v.right[3], v.up[3]);
    if v.origin[3] > 0.5 && ls.z <= near {
        return 1.0;
    }
    let stored = shadow_fetch(v, sm, shadow_uv(v, ls));
    let depth = (ls.z - near) / (far - near);
    select(
        0.0,
        1.0,
        depth <= stored + shadow_bias(v, ls.z) / (far - near),
    )
}

/// Travel distance from `o` along the light ray `o + s l` to its first occluder, biased as
/// [`shadow_visibility`] biases (points before it are lit), or [`NO_OCCLUDER`]. For a spot the
/// ray must start at the shadow map's origin (the light).
pub fn shadow_occluder_distance(v: &ShadowMapView, sm: &Tex, o: Vec3, l: Vec3) -> f32 {
    let ls = shadow_light_space(v, o);
    let (near, far) = (v.right[3], v.up[3]);
    if v.origin[3] > 0.5 {
        let dir = Vec3::new(l.dot(xyz(v.right)), l.dot(xyz(v.up)), l.dot(xyz(v.forward)));
        if dir.z <= 1e-6 {
            return NO_OCCLUDER;
        }
        let stored = shadow_fetch(v, sm, shadow_uv(v, dir));
        if stored >= 1.0 {
            return NO_OCCLUDER;
        }
        let z = near + stored * (far - near);
        (z + shadow_bias(v, z)) / dir.z
    } else {
        let stored = shadow_fetch(v, sm, shadow_uv(v, ls));
        if stored >= 1.0 {
            return NO_OCCLUDER;
        }
        let z = near + stored * (far - near);
        z + shadow_bias(v, z) - ls.z
    }
}
