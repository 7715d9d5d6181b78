// scatter::raymarch: what the `raymarch` family's kernels (`raymarch`, `interleave_sum`)
// share: the `RaymarchFrame` uniform block, the pixel's view ray, the per-pixel jitter hash and the
// interleaving window.
//
// Composed into kernels by naga_oil (`#import scatter::raymarch::{...}`); plain WGSL, not an
// askama template. Conventions: `scatter_frame::raymarch`. Mirrored line by line by
// reference/src/kernels/common_raymarch.rs.

#define_import_path scatter::raymarch

#import scatter::shadow::ShadowMapView

// The uniform block (host: `scatter_frame::raymarch::RaymarchUniforms`, field by field; every
// member is 16 bytes, 15 * 16 = 240 bytes in all).
struct RaymarchFrame {
    // Eye position; w unused.
    eye: vec4<f32>,
    // Camera forward; w = tan(fov_y / 2).
    cam_forward: vec4<f32>,
    // Camera right; w = aspect (width / height).
    cam_right: vec4<f32>,
    // Camera up; w = near.
    cam_up: vec4<f32>,
    // x = sigma_t, y = sigma_s, z = g, w unused.
    medium: vec4<f32>,
    // Light colour (E or I); w unused.
    light_color: vec4<f32>,
    // Spot position; w = cos(inner angle).
    light_pos: vec4<f32>,
    // Direction the light travels (spot axis); w = cos(outer angle).
    light_dir: vec4<f32>,
    // Shadow-map right; w = shadow-map near.
    sm_right: vec4<f32>,
    // Shadow-map up; w = shadow-map far.
    sm_up: vec4<f32>,
    // Shadow-map forward; w = bias in texel footprints.
    sm_forward: vec4<f32>,
    // Shadow-map origin; w = 0 orthographic, 1 perspective.
    sm_origin: vec4<f32>,
    // Orthographic: x0, x1, y0, y1. Perspective: tan_half, 0, 0, 0.
    sm_proj: vec4<f32>,
    // Screen width, height, shadow-map size, samples N.
    sizes: vec4<u32>,
    // Mx = min(M, width), My = min(M, height), jitter (0 or 1), M.
    interleave: vec4<u32>,
}

// The frame's standard shadow map (`scatter::shadow`).
fn raymarch_shadow_view(m: RaymarchFrame) -> ShadowMapView {
    return ShadowMapView(m.sm_right, m.sm_up, m.sm_forward, m.sm_origin, m.sm_proj, vec4<u32>(m.sizes[2], 0u, 0u, 0u));
}

// Unit view direction through the centre of pixel (x, y).
fn raymarch_pixel_dir(m: RaymarchFrame, x: u32, y: u32) -> vec3<f32> {
    let ndc_x = 2.0 * (f32(x) + 0.5) / f32(m.sizes[0]) - 1.0;
    let ndc_y = 1.0 - 2.0 * (f32(y) + 0.5) / f32(m.sizes[1]);
    let t = m.cam_forward[3];
    return normalize(m.cam_forward.xyz + m.cam_right.xyz * (ndc_x * t * m.cam_right[3]) + m.cam_up.xyz * (ndc_y * t));
}

// A per-pixel offset in [0, 1) (integer hash of the pixel coordinates; wrapping u32
// arithmetic).
fn pixel_jitter(x: u32, y: u32) -> f32 {
    var h = x * 1973u + y * 9277u + 26699u;
    h = (h ^ (h >> 16u)) * 0x7feb352du;
    h = (h ^ (h >> 15u)) * 0x846ca68bu;
    h = h ^ (h >> 16u);
    return f32(h >> 8u) / 16777216.0;
}

// First of the `taps` consecutive pixels the sum filter adds for pixel `pos` of a line of
// `len` pixels: centred, clamped inside the line so the window always holds `taps`
// distinct classes (`taps <= len`).
fn window_start(pos: u32, taps: u32, len: u32) -> u32 {
    return u32(clamp(i32(pos) - i32(taps / 2u), 0, i32(len) - i32(taps)));
}
