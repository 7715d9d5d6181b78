//! CPU mirror of `shaderlib/templates/common/raymarch.wgsl` (`scatter::raymarch`): the
//! `raymarch` family's shadow-map view, pixel rays, jitter hash and interleaving windows.

use super::common_shadow::ShadowMapView;
use super::texture::xyz;
use glam::Vec3;
use scatter_shaderlib::raymarch::RaymarchUniforms;

/// The frame's standard shadow map ([`super::common_shadow`]).
pub fn raymarch_shadow_view(m: &RaymarchUniforms) -> ShadowMapView {
    ShadowMapView {
        right: m.sm_right,
        up: m.sm_up,
        forward: m.sm_forward,
        origin: m.sm_origin,
        proj: m.sm_proj,
        size: [m.sizes[2], 0, 0, 0],
    }
}

/// Unit view direction through the centre of pixel (x, y).
pub fn raymarch_pixel_dir(m: &RaymarchUniforms, x: u32, y: u32) -> Vec3 {
    let ndc_x = 2.0 * (x as f32 + 0.5) / m.sizes[0] as f32 - 1.0;
    let ndc_y = 1.0 - 2.0 * (y as f32 + 0.5) / m.sizes[1] as f32;
    let t = m.cam_forward[3];
    (xyz(m.cam_forward)
        + xyz(m.cam_right) * (ndc_x * t * m.cam_right[3])
        + xyz(m.cam_up) * (ndc_y * t))
        .normalize()
}

/// A per-pixel offset in [0, 1) (integer hash of the pixel coordinates; wrapping u32
/// arithmetic).
pub fn pixel_jitter(x: u32, y: u32) -> f32 {
    let mut h = x
        .wrapping_mul(1973)
        .wrapping_add(y.wrapping_mul(9277))
        .wrapping_add(26699);
    h = (h ^ (h >> 16)).wrapping_mul(0x7feb_352d);
    h = (h ^ (h >> 15)).wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    (h >> 8) as f32 / 16_777_216.0
}

/// First of the `taps` consecutive pixels the sum filter adds for pixel `pos` of a line of
/// `len` pixels (centred, clamped inside the line; `taps <= len`).
pub fn window_start(pos: u32, taps: u32, len: u32) -> u32 {
    (pos as i32 - (taps / 2) as i32).clamp(0, len as i32 - taps as i32) as u32
}
