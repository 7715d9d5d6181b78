//! CPU mirror of `shaderlib/templates/ivsv_rectify.wgsl`: per VPL, theta row and phi bit,
//! the first occluder of the light ray in the VPL's shadow map marks the first voxel along
//! alpha whose centre lies beyond it (conventions: `scatter_frame::area_ivsv`).
//! [`rectify_bit`] is the invocation body; it also returns how far the decision is from a
//! tie (the occluder's fractional bin from a bin boundary, the light ray's shadow-map
//! coordinate from a texel edge), so that a GPU-CPU comparison can tell a rounding tie from
//! a defect.

use super::common_ivsv::{PHI_BITS, plane_normal, voxel_word, vpl_shadow_view};
use super::common_model::max;
use super::common_shadow::{ShadowMapView, shadow_bias_perspective, shadow_uv_perspective};
use super::texture::{TexArray, xyz};
use glam::Vec3;
use scatter_shaderlib::area_ivsv::{IvsvUniforms, VplRecord};
use std::f32::consts::PI;

/// `scatter::shadow::shadow_occluder_distance` for a perspective map in layer `layer`
/// (channel 0 of `maps`) and a ray from its origin: the travel distance along `l` to the first
/// occluder (biased), or -1, and the smallest distance of the ray's texel coordinate to a
/// texel edge (in texels).
pub fn vpl_occluder_distance(
    v: &ShadowMapView,
    maps: &TexArray,
    layer: u32,
    l: Vec3,
) -> (f32, f32) {
    let dir = Vec3::new(l.dot(xyz(v.right)), l.dot(xyz(v.up)), l.dot(xyz(v.forward)));
    if dir.z <= 1e-6 {
        return (-1.0, f32::INFINITY);
    }
    let uv = shadow_uv_perspective(v, dir);
    if uv[0] < 0.0 || uv[0] > 1.0 || uv[1] < 0.0 || uv[1] > 1.0 {
        return (-1.0, f32::INFINITY);
    }
    let n = v.size[0];
    let (fx, fy) = (uv[0] * n as f32, uv[1] * n as f32);
    let margin = (fx - fx.round()).abs().min((fy - fy.round()).abs());
    let x = (fx as u32).min(n - 1);
    let y = (fy as u32).min(n - 1);
    let stored = maps.load(x, y, layer)[0];
    if stored >= 1.0 {
        return (-1.0, margin);
    }
    let near = v.right[3];
    let far = v.up[3];
    let z = near + stored * (far - near);
    ((z + shadow_bias_perspective(v, z)) / dir.z, margin)
}

/// One set bit: the word index in `marks` and the bit mask, with the decision's margin (the
/// smaller of the texel-edge distance and the occluder's distance to a bin boundary, in
/// texels and bins).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mark {
    /// Word index in `marks`.
    pub word: u32,
    /// `1 << (k % 32)`.
    pub mask: u32,
    /// Distance from a rounding tie.
    pub margin: f32,
}

/// The invocation `(k, j, v)`: the bit it sets, if any, and the margin of the decision
/// either way (`Err(margin)` when it sets none).
pub fn rectify_bit(
    m: &IvsvUniforms,
    vpls: &[VplRecord],
    maps: &TexArray,
    k: u32,
    j: u32,
    v: u32,
) -> Result<Mark, f32> {
    let r = &vpls[v as usize];
    let theta = -PI + (j as f32 + 0.5) * (2.0 * PI / m.grid[1] as f32);
    let phi = (k as f32 + 0.5) * (r.perp_y[3] / PHI_BITS as f32);
    let u = -xyz(r.axis) * phi.cos() + plane_normal(r, theta) * phi.sin();
    let (s, texel_margin) = vpl_occluder_distance(&vpl_shadow_view(m, r), maps, v, u);
    if s < 0.0 {
        return Err(texel_margin);
    }
    let alpha_occ = (s * phi.sin()).atan2(r.position[3] - s * phi.cos());
    // The first bin whose centre exceeds alpha_occ.
    let x = (alpha_occ - r.axis[3]) / r.perp_x[3];
    let first = (x - 0.5).floor() + 1.0;
    let margin = texel_margin.min(((x - 0.5) - (x - 0.5).round()).abs());
    if first < m.grid[0] as f32 {
        let i = max(first, 0.0) as u32;
        Ok(Mark {
            word: voxel_word(m, v, j, i) + k / 32,
            mask: 1 << (k % 32),
            margin,
        })
    } else {
        Err(margin)
    }
}

/// The whole pass: `marks` (zero on entry, as the GPU's) with every bit set.
pub fn ivsv_rectify(m: &IvsvUniforms, vpls: &[VplRecord], maps: &TexArray, marks: &mut [u32]) {
    for v in 0..m.sizes[3] {
        for j in 0..m.grid[1] {
            for k in 0..PHI_BITS {
                if let Ok(mark) = rectify_bit(m, vpls, maps, k, j, v) {
                    marks[mark.word as usize] |= mark.mask;
                }
            }
        }
    }
}
