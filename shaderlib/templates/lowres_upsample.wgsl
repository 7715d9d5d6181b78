// lowres_upsample (block side {{ scale }}, depth break {{ depth_break }}): the depth-aware upsample of
// the low-resolution sampling stage (`sampling = lowres`, scatter::sampling), shared by every
// family. Each screen pixel takes the bilinear blend of its four nearest samples, each kept
// only when its pixel is within the depth break of the pixel's own depth (a joint bilateral
// filter with a box range kernel: no weight across a depth break, so no halo); a pixel no
// sample stands for was evaluated per pixel by the family's sampling pass, and is left as
// it is.
//
// Bindings (group 0):
// | binding | name    | type                                          | access       |
// |---------|---------|-----------------------------------------------|--------------|
// | 0       | depth   | texture_2d<f32> (r32float, view depth)        | textureLoad  |
// | 1       | samples | texture_2d<f32> (rgba16float, the family's)   | textureLoad  |
// | 2       | output  | texture_storage_2d<rgba16float, write>        | textureStore |
// output: in-scattered radiance, screen-sized (rgb, alpha 1).
//
// Dispatch: (ceil(W / 8), ceil(H / 8), 1) workgroups of (8, 8, 1), W x H = screen size (the
// size of `output`).
//
// Mirrors reference/src/kernels/lowres_upsample.rs

#import scatter::sampling::{lowres_covered, lowres_taps}

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var samples: texture_2d<f32>;
@group(0) @binding(2) var output: texture_storage_2d<rgba16float, write>;

// Block side S of the sample grid and the depth break (a fraction of the nearer depth).
const SCALE: u32 = {{ scale }}u;
const DEPTH_BREAK: f32 = {{ depth_break }};

// The kernel body for pixel `id`.
@compute @workgroup_size(8, 8, 1)
fn lowres_upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let screen = textureDimensions(output);
    if id.x >= screen.x || id.y >= screen.y {
        return;
    }
    let t = lowres_taps(depth, id.xy, screen, SCALE, DEPTH_BREAK);
    if !lowres_covered(t) {
        return;
    }
    var c = vec3<f32>(0.0, 0.0, 0.0);
    for (var k = 0u; k < 4u; k++) {
        c += t.w[k] * textureLoad(samples, vec2<u32>(t.cols[k % 2u], t.rows[k / 2u]), 0).xyz;
    }
    c /= t.w.x + t.w.y + t.w.z + t.w.w;
    textureStore(output, id.xy, vec4<f32>(c.x, c.y, c.z, 1.0));
}
