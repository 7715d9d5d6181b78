// minmax_build: the 1D min-max binary tree of every rectified row (Chen et al. 2011, Sec. 4):
// node j of level k holds (min, max) of the stored depths of texels [j 2^k, (j + 1) 2^k) of
// its row, all levels packed into one rg32float row (layout: `scatter::minmax`,
// `scatter_frame::minmax`).
//
// One invocation per tree node: it reduces its texel span straight from the rectified map
// (O(Wr log Wr) loads per row, one dispatch, no barriers between levels).
//
// Bindings (group 0):
// | binding | name      | type                                    | access       |
// |---------|-----------|-----------------------------------------|--------------|
// | 0       | frame     | var<uniform> Frame (400 bytes)          | uniform      |
// | 1       | rectified | texture_2d<f32> (r32float, `rectify`'s) | textureLoad  |
// | 2       | tree      | texture_storage_2d<rg32float, write>    | textureStore |
// tree: tree_width(Wr) x Hr, Wr x Hr = the rectified size (frame.sizes.zw).
//
// Dispatch: (ceil(tree_width(Wr) / 64), Hr, 1) workgroups of (64, 1, 1); invocation id x =
// tree column, y = row.
//
// Mirrors reference/src/kernels/minmax_build.rs

#import scatter::epipolar::Frame
#import scatter::minmax::{level_count, tree_width}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var rectified: texture_2d<f32>;
@group(0) @binding(2) var tree: texture_storage_2d<rg32float, write>;

// The kernel body for invocation `id`; stores node (min, max) at tree texel `id.xy` (out of
// range: no store).
@compute @workgroup_size(64, 1, 1)
fn minmax_build(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = frame.sizes[2];
    let c = id.x; let y = id.y;
    if c >= tree_width(width) || y >= frame.sizes[3] {
        return;
    }
    // The level and node of packed column c.
    var level = 0u;
    var off = 0u;
    loop {
        let count = level_count(level, width);
        if c < off + count {
            break;
        }
        off += count;
        level++;
    }
    let first = (c - off) << level;
    let end = min(first + (1u << level), width);
    let d0 = textureLoad(rectified, vec2<u32>(first, y), 0).x;
    var lo = d0;
    var hi = d0;
    for (var i = first + 1u; i < end; i++) {
        let d = textureLoad(rectified, vec2<u32>(i, y), 0).x;
        lo = min(lo, d);
        hi = max(hi, d);
    }
    textureStore(tree, vec2<u32>(c, y), vec4<f32>(lo, hi, 0.0, 0.0));
}
