// rectify ({{ light_name }} light): epipolar resampling of the engine's standard shadow map
// into the rectified shadow map of the prefiltered method (Klehm et al. 2014, Sec. 4.1,
// after Baran et al. 2010).
//
// One invocation per rectified texel (column x = light ray, row y = epipolar slice): find the
// light ray's first occluder in the standard shadow map and store its view angle as
// normalised rectified depth (conventions: `scatter_shaderlib::prefiltered::frame`), in
// [0, 1] where view rays use [0.1, 0.9] (`occluder_depth`).
//
// Bindings (group 0):
// | binding | name       | type                                     | access       |
// |---------|------------|------------------------------------------|--------------|
// | 0       | frame      | var<uniform> Frame (336 bytes)           | uniform      |
// | 1       | slices     | var<storage, read> array<vec4<f32>>      | read         |
// | 2       | shadow_map | texture_2d<f32> (r32float)               | textureLoad  |
// | 3       | rectified  | texture_storage_2d<r32float, write>      | textureStore |
// slices: one vec4 per rectified row (x = delta, y = theta_ref, z = theta_lo, w = theta_hi).
//
// Dispatch: (ceil(Wr / 8), ceil(Hr / 8), 1) workgroups of (8, 8, 1), Wr x Hr = rectified
// size (frame.sizes.zw); invocation id x = column, y = row.
//
// Mirrors reference/src/kernels/rectify.rs

#import scatter::model::PI
#import scatter::epipolar::{Frame, occluder_depth, row_phi, slice_e, slice_params, sm_occluder_distance}
#import scatter::shadow::NO_OCCLUDER

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> slices: array<vec4<f32>>;
@group(0) @binding(2) var shadow_map: texture_2d<f32>;
@group(0) @binding(3) var rectified: texture_storage_2d<r32float, write>;

// The kernel body for invocation `id` (`spot` is the template's light switch); stores its
// value at texel `id.xy` (out of range: no store).
@compute @workgroup_size(8, 8, 1)
fn rectify(@builtin(global_invocation_id) id: vec3<u32>) {
    let spot = {{ spot }};
    let x = id.x; let y = id.y;
    if x >= frame.sizes[2] || y >= frame.sizes[3] {
        return;
    }
    let slice = slice_params(slices[y]);
    let e = slice_e(frame, row_phi(frame, y));
    let col = (f32(x) + 0.5) * slice.delta;
    let axis = frame.axis.xyz;
    var theta_occ = PI;
    if spot {
        // The light ray leaving the light at angle psi = col from the direction towards the eye.
        let l = -axis * cos(col) + e * sin(col);
        let s = sm_occluder_distance(frame, shadow_map, frame.light_pos.xyz, l);
        if s < NO_OCCLUDER {
            let dist = frame.axis[3];
            theta_occ = atan2(s * sin(col), dist - s * cos(col));
        }
    } else {
        // The light ray at distance v = col from the axis, travelling along -axis.
        let o = frame.eye.xyz + e * col;
        let s = sm_occluder_distance(frame, shadow_map, o, -axis);
        if s < NO_OCCLUDER {
            theta_occ = atan2(col, -s);
        }
    }
    let d = occluder_depth(theta_occ, frame.theta[0], frame.theta[1]);
    textureStore(rectified, vec2<u32>(x, y), vec4<f32>(d, 0.0, 0.0, 0.0));
}
