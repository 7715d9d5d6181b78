// ivsv_rectify: per VPL, the first occluder of every (theta, phi) light ray of its epipolar
// voxel grid marks the voxel where its shadow starts (Wyman & Dai 2013, Sec. 4.1, with the
// grid resampled from a standard shadow map per VPL instead of splatted points).
//
// Invocation (k, j, v): VPL v, theta row j (bin centre theta = -pi + (j + 0.5) 2 pi / theta
// bins), phi bit k (bin centre phi = (k + 0.5) phi_max / 128). Its light ray from the VPL,
// u = -axis cos(phi) + e sin(phi) (e the plane's unit normal to the axis), meets the first
// occluder of the VPL's shadow map (nearest texel, biased like the `shadow_map` truth:
// `scatter::shadow`) at travel distance s; that point's eye angle, in the triangle eye - VPL
// - point, is alpha_occ = atan2(s sin(phi), D - s cos(phi)). Bit k is set (atomicOr) in the
// first texel of row j whose alpha centre lies beyond alpha_occ; `ivsv_scan` extrudes it.
//
// Bindings (group 0):
// | binding | name     | type                                         | access      |
// |---------|----------|----------------------------------------------|-------------|
// | 0       | frame    | var<uniform> IvsvFrame (112 bytes)           | uniform     |
// | 1       | vpls     | var<uniform> array<Vpl, {{ vpls }}> (176 bytes each) | uniform |
// | 2       | vpl_maps | texture_2d_array<f32> (r32float, N layers)   | textureLoad |
// | 3       | marks    | var<storage, read_write> array<atomic<u32>>  | atomicOr    |
// marks: 4 N theta alpha u32, zero before the pass (`ivsv_scan` zeroes what it reads).
//
// Dispatch: (128 / 64, theta, N) workgroups of (64, 1, 1); invocation id x = phi bit,
// y = theta row, z = VPL.
//
// Mirrors reference/src/kernels/ivsv_rectify.rs

#import scatter::model::PI
#import scatter::shadow::{ShadowMapView, shadow_bias_perspective, shadow_uv_perspective}
#import scatter::ivsv::{IvsvFrame, Vpl, PHI_BITS, plane_normal, voxel_word, vpl_shadow_view}

@group(0) @binding(0) var<uniform> frame: IvsvFrame;
@group(0) @binding(1) var<uniform> vpls: array<Vpl, {{ vpls }}>;
@group(0) @binding(2) var vpl_maps: texture_2d_array<f32>;
@group(0) @binding(3) var<storage, read_write> marks: array<atomic<u32>>;

// `scatter::shadow::shadow_occluder_distance` for a perspective map in layer `layer` of
// `vpl_maps` and a ray from the map's origin: travel distance along the unit `l` to the
// first occluder (biased), or -1 where there is none.
fn vpl_occluder_distance(v: ShadowMapView, layer: u32, l: vec3<f32>) -> f32 {
    let dir = vec3<f32>(dot(l, v.right.xyz), dot(l, v.up.xyz), dot(l, v.forward.xyz));
    if dir.z <= 1e-6 {
        return -1.0;
    }
    let uv = shadow_uv_perspective(v, dir);
    if uv[0] < 0.0 || uv[0] > 1.0 || uv[1] < 0.0 || uv[1] > 1.0 {
        return -1.0;
    }
    let n = v.size.x;
    let x = min(u32(uv[0] * f32(n)), n - 1u);
    let y = min(u32(uv[1] * f32(n)), n - 1u);
    let stored = textureLoad(vpl_maps, vec2<u32>(x, y), layer, 0).x;
    if stored >= 1.0 {
        return -1.0;
    }
    let near = v.right[3];
    let far = v.up[3];
    let z = near + stored * (far - near);
    return (z + shadow_bias_perspective(v, z)) / dir.z;
}

@compute @workgroup_size(64, 1, 1)
fn ivsv_rectify(@builtin(global_invocation_id) id: vec3<u32>) {
    let m = frame;
    let k = id.x;
    let j = id.y;
    let v = id.z;
    if k >= PHI_BITS || j >= m.grid[1] || v >= m.sizes[3] {
        return;
    }
    let r = vpls[v];
    let theta = -PI + (f32(j) + 0.5) * (2.0 * PI / f32(m.grid[1]));
    let phi = (f32(k) + 0.5) * (r.perp_y[3] / f32(PHI_BITS));
    let u = -r.axis.xyz * cos(phi) + plane_normal(r, theta) * sin(phi);
    let s = vpl_occluder_distance(vpl_shadow_view(m, r), v, u);
    if s < 0.0 {
        return;
    }
    let alpha_occ = atan2(s * sin(phi), r.position[3] - s * cos(phi));
    // The first bin whose centre exceeds alpha_occ.
    let x = (alpha_occ - r.axis[3]) / r.perp_x[3];
    let first = floor(x - 0.5) + 1.0;
    if first < f32(m.grid[0]) {
        let i = u32(max(first, 0.0));
        atomicOr(&marks[voxel_word(m, v, j, i) + k / 32u], 1u << (k % 32u));
    }
}
