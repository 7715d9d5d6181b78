//! CPU mirror of `shaderlib/templates/common/ivsv.wgsl` (`scatter::ivsv`): what the
//! `area_ivsv` kernels share (the voxel index, the plane normal, a VPL's shadow-map view).
//! The uniform block and the VPL record are the host structs
//! `scatter_frame::area_ivsv::{IvsvUniforms, VplRecord}`.

use super::common_shadow::ShadowMapView;
use super::texture::xyz;
use glam::Vec3;
use scatter_shaderlib::area_ivsv::{IvsvUniforms, VplRecord};

/// Bits per voxel texel.
pub const PHI_BITS: u32 = 128;

/// The first word of texel `(i, j)` of VPL `v`.
pub fn voxel_word(m: &IvsvUniforms, v: u32, j: u32, i: u32) -> u32 {
    ((v * m.grid[1] + j) * m.grid[0] + i) * 4
}

/// The unit vector in the epipolar plane of angle `theta` normal to the VPL's axis.
pub fn plane_normal(r: &VplRecord, theta: f32) -> Vec3 {
    xyz(r.perp_x) * theta.cos() + xyz(r.perp_y) * theta.sin()
}

/// The VPL's shadow map as `scatter::shadow` reads one.
pub fn vpl_shadow_view(m: &IvsvUniforms, r: &VplRecord) -> ShadowMapView {
    ShadowMapView {
        right: r.sm_right,
        up: r.sm_up,
        forward: r.sm_forward,
        origin: r.sm_origin,
        proj: r.sm_proj,
        size: [m.sizes[2], 0, 0, 0],
    }
}
