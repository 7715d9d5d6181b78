// rectify ({{ light_name }} light): epipolar resampling of the engine's standard shadow map
// into the rectified shadow map of the prefiltered method (Klehm et al. 2014, Sec. 4.1,
// after Baran et al. 2010).
//
// Per rectified texel (column x = light ray, row y = epipolar slice): find the light ray's
// first occluder in the standard shadow map and store its view angle as normalised rectified
// depth (conventions: `scatter_shaderlib::prefiltered::frame`), in [0, 1] where view rays use
// [0.1, 0.9] (`occluder_depth`). Each invocation takes {{ texels }} consecutive columns of a row.
//
// Bindings (group 0):
// | binding | name       | type                                     | access       |
// |---------|------------|------------------------------------------|--------------|
// | 0       | frame      | var<uniform> Frame (432 bytes)           | uniform      |
// | 1       | slices     | var<storage, read> array<vec4<f32>>      | read         |
// | 2       | shadow_map | texture_2d<f32> (r32float)               | textureLoad  |
// | 3       | rectified  | texture_storage_2d<r32float, write>      | textureStore |
// slices: one vec4 per rectified row (x = delta, y = theta_ref, z = theta_lo, w = theta_hi).
//
// Dispatch: (ceil(ceil(Wr / {{ texels }}) / 8), ceil(Hr / 8), 1) workgroups of (8, 8, 1),
// Wr x Hr = rectified size (frame.sizes.zw); invocation id x = columns {{ texels }} x ..
// {{ texels }} x + {{ texels - 1 }}, y = row.
//
// Mirrors reference/src/kernels/rectify.rs

#import scatter::model::PI
#import scatter::epipolar::{Frame, SliceParams, light_point_theta, occluder_depth, row_phi, slice_e, slice_params, sm_occluder_distance_spot, sm_occluder_distance_sun}
#import scatter::shadow::NO_OCCLUDER

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> slices: array<vec4<f32>>;
@group(0) @binding(2) var shadow_map: texture_2d<f32>;
@group(0) @binding(3) var rectified: texture_storage_2d<r32float, write>;

// Columns per invocation: the row's constants (slice, slice direction) once for all of them,
// and lavapipe's per-invocation cost shared (rectify measured 4.9x its store bound at one
// texel per invocation, issue 13).
const TEXELS: u32 = {{ texels }}u;

// The value stored at texel (x, y): the light ray's first occluder as normalised rectified
// depth (`spot` is the template's light switch; `e` the row's slice direction).
fn rectify_texel(x: u32, slice: SliceParams, e: vec3<f32>, spot: bool) -> f32 {
    let col = (f32(x) + 0.5) * slice.delta;
    let axis = frame.axis.xyz;
    var theta_occ = PI;
    if spot {
        // The light ray leaving the light at angle psi = col from the direction towards the eye.
        let l = -axis * cos(col) + e * sin(col);
        let s = sm_occluder_distance_spot(frame, shadow_map, l);
        if s < NO_OCCLUDER {
            theta_occ = light_point_theta(frame, col, s, true);
        }
    } else {
        // The light ray at distance v = col from the axis, travelling along -axis.
        let o = frame.eye.xyz + e * col;
        let s = sm_occluder_distance_sun(frame, shadow_map, o);
        theta_occ = select(PI, light_point_theta(frame, col, s, false), s < NO_OCCLUDER);
    }
    return occluder_depth(theta_occ, frame.theta[0], frame.theta[1]);
}

// Invocation `id` stores texels (TEXELS id.x .. TEXELS id.x + TEXELS - 1, id.y), those
// inside the map.
@compute @workgroup_size(8, 8, 1)
fn rectify(@builtin(global_invocation_id) id: vec3<u32>) {
    let spot = {{ spot }};
    let first = id.x * TEXELS;
    let y = id.y;
    if first >= frame.sizes[2] || y >= frame.sizes[3] {
        return;
    }
    let slice = slice_params(slices[y]);
    let e = slice_e(frame, row_phi(frame, y));
    let end = min(first + TEXELS, frame.sizes[2]);
    for (var x = first; x < end; x++) {
        textureStore(rectified, vec2<u32>(x, y), vec4<f32>(rectify_texel(x, slice, e, spot), 0.0, 0.0, 0.0));
    }
}
