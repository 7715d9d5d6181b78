// slice_fit ({{ light_name }} light): fits every rectified row's column spacing to the deepest
// pixel of the frame's depth buffer, before `rectify` reads it.
//
// The host's frame set-up (`prepare_frame`) spans each row to the far plane: the columns
// reach the light rays that the far plane's points lie on. Where the depth buffer ends
// closer (a room, a forest, anything that hides the far plane), most columns lie beyond
// every view ray and the ones the view rays use are few: a view ray 0.25 m long in a room
// with a 40 m far plane crossed 3 of 512 columns, and light leaked through a 0.3 m ceiling
// between them (issue 12). This pass takes the largest view depth z of the depth buffer
// (clamped to [0, far] as `scatter` clamps it; `depth_columns` left each column's maximum in
// `column_depth`) and recomputes every row's extent as the host
// does with the far plane moved to z: directional, `delta * z / far` (the extent is linear
// in the far distance); spot, the host's 33-sample maximum of the light angle psi over the
// row's view angles with the far distance z. The new spacing replaces the host's when it is
// smaller, positive and finite, so the pass is idempotent and never widens a row. Every
// pixel's ray still ends inside its row, as before (its depth is at most z).
//
// Projective frames (frame.proj.x = 1) keep the host's table: their rows are not spans of
// light rays.
//
// Bindings (group 0):
// | binding | name   | type                                   | access      |
// |---------|--------|----------------------------------------|-------------|
// | 0       | frame  | var<uniform> Frame (432 bytes)         | uniform     |
// | 1       | slices | var<storage, read_write> array<vec4<f32>> | read_write |
// | 2       | column_depth | var<storage, read> array<f32>     | read        |
// slices: one vec4 per rectified row (x = delta, y = theta_ref, z = theta_lo, w = theta_hi);
// this pass rewrites x. column_depth: the deepest pixel of every screen column
// (`depth_columns`).
//
// Dispatch: (1, 1, 1): one workgroup of (256, 1, 1) reduces the screen columns' maxima (strided
// over its invocations, then a tree reduction in workgroup memory) and rewrites every
// rectified row (strided likewise; the sun one multiply, a spot 33 samples of a few
// transcendentals).
//
// Mirrors reference/src/kernels/slice_fit.rs

#import scatter::epipolar::{Frame, row_phi, slice_e}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read_write> slices: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> column_depth: array<f32>;

// Invocations of the one workgroup.
const THREADS: u32 = 256u;
// View angles sampled per row for a spot's extent (the host's 32 intervals).
const SPOT_SAMPLES: u32 = 32u;

var<workgroup> deepest: array<f32, THREADS>;

// A spot's light ray through the point at view depth `z` on the ray of slice angle `phi` and
// view angle `theta`: its angle at the light from the direction towards the eye (`dist` =
// eye-light distance), as the host's frame set-up computes it at the far plane.
fn spot_psi(f: Frame, phi: f32, theta: f32, z: f32, dist: f32) -> f32 {
    let d = f.axis.xyz * cos(theta) + slice_e(f, phi) * sin(theta);
    let t = z / max(dot(d, f.cam_forward.xyz), 1e-6);
    return atan2(t * sin(theta), dist - t * cos(theta));
}

@compute @workgroup_size(256, 1, 1)
fn slice_fit(@builtin(local_invocation_index) lid: u32) {
    let spot = {{ spot }};
    let f = frame;
    let far = f.theta.z;
    var z = 0.0;
    for (var x = lid; x < f.sizes[0]; x += THREADS) {
        z = max(z, column_depth[x]);
    }
    deepest[lid] = z;
    for (var half = THREADS / 2u; half > 0u; half /= 2u) {
        workgroupBarrier();
        if lid < half {
            deepest[lid] = max(deepest[lid], deepest[lid + half]);
        }
    }
    workgroupBarrier();
    z = deepest[0];
    if f.proj[0] > 0.5 || !(z < far) {
        return;
    }
    let rows = f.sizes[3];
    let cols = f32(f.sizes[2]);
    let dist = f.axis[3];
    for (var row = lid; row < rows; row += THREADS) {
        let old = slices[row];
        var delta = old.x * (z / far);
        if spot {
            let phi = row_phi(f, row);
            var extent = 0.0;
            for (var k = 0u; k <= SPOT_SAMPLES; k++) {
                let theta = old.z + (old.w - old.z) * f32(k) / f32(SPOT_SAMPLES);
                extent = max(extent, spot_psi(f, phi, theta, z, dist));
            }
            delta = extent * 1.001 / cols;
        }
        if delta > 0.0 && delta < old.x {
            slices[row] = vec4<f32>(delta, old.y, old.z, old.w);
        }
    }
}
