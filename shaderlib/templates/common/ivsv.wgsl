// scatter::ivsv: what the `area_ivsv` family's kernels (`ivsv_rectify`, `ivsv_scan`,
// `ivsv_gather`) share: the `IvsvFrame` uniform block, the per-VPL record `Vpl`, the voxel
// index, the unit normal of an epipolar plane and a VPL's standard shadow-map view.
// Conventions (Wyman & Dai 2013 in this project's form): `scatter_frame::area_ivsv`; the f64
// method the kernels implement: reference/src/area_ivsv.rs.
//
// Composed into kernels by naga_oil (`#import scatter::ivsv::{...}`); plain WGSL, not an
// askama template. Mirrored line by line by reference/src/kernels/common_ivsv.rs.

#define_import_path scatter::ivsv

#import scatter::shadow::ShadowMapView

// The frame's uniform block (host: `scatter_frame::area_ivsv::IvsvUniforms`, 8 * 16 = 128
// bytes).
struct IvsvFrame {
    // Eye position; w = camera far (depth is clamped to it).
    eye: vec4<f32>,
    // Camera forward; w = tan(fov_y / 2).
    cam_forward: vec4<f32>,
    // Camera right; w = aspect (width / height).
    cam_right: vec4<f32>,
    // Camera up; w unused.
    cam_up: vec4<f32>,
    // x = sigma_t, y = sigma_s, z = g, w unused.
    medium: vec4<f32>,
    // Screen width, height, VPL shadow-map size, VPL count N.
    sizes: vec4<u32>,
    // alpha bins (texels per row), theta bins (rows per VPL), interleave M, unused.
    grid: vec4<u32>,
    // The VPLs' centroid (the light's point of epipolar sampling); w unused.
    centre: vec4<f32>,
}

// One virtual point light (host: `scatter_frame::area_ivsv::VplRecord`, 11 * 16 = 176 bytes;
// the kernels read them as a uniform array: 45 KiB at 256 VPLs):
// a spot with its own perspective shadow map and its epipolar grid about the eye-VPL axis.
struct Vpl {
    // Position; w = D, the eye-VPL distance.
    position: vec4<f32>,
    // Intensity (rgb); w = cos(outer angle).
    color: vec4<f32>,
    // Unit axis from the eye to the VPL; w = alpha_0, the first alpha bin's start.
    axis: vec4<f32>,
    // Unit normal to the axis (theta = 0); w = alpha bin width.
    perp_x: vec4<f32>,
    // axis x perp_x (theta = pi / 2); w = phi_max (the 128 phi bits cover [0, phi_max]).
    perp_y: vec4<f32>,
    // Spot axis (the direction light travels); w = cos(inner angle).
    spot_dir: vec4<f32>,
    // The VPL's shadow map (a perspective `ShadowMapView` without its size: frame.sizes.z).
    sm_right: vec4<f32>,
    sm_up: vec4<f32>,
    sm_forward: vec4<f32>,
    sm_origin: vec4<f32>,
    sm_proj: vec4<f32>,
}

// Bits per voxel texel: 128 phi bits, bit k in word k / 32.
const PHI_BITS: u32 = 128u;

// The first word of texel (i, j) of VPL v (texels: N x theta rows x alpha, 4 words each).
fn voxel_word(m: IvsvFrame, v: u32, j: u32, i: u32) -> u32 {
    return ((v * m.grid[1] + j) * m.grid[0] + i) * 4u;
}

// The unit vector in the epipolar plane of angle `theta` normal to the VPL's axis.
fn plane_normal(r: Vpl, theta: f32) -> vec3<f32> {
    return r.perp_x.xyz * cos(theta) + r.perp_y.xyz * sin(theta);
}

// The VPL's shadow map as `scatter::shadow` reads one.
fn vpl_shadow_view(m: IvsvFrame, r: Vpl) -> ShadowMapView {
    return ShadowMapView(r.sm_right, r.sm_up, r.sm_forward, r.sm_origin, r.sm_proj, vec4<u32>(m.sizes[2], 0u, 0u, 0u));
}
