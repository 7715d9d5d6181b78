// minmax_build: the 1D min-max binary tree of every rectified row (Chen et al. 2011, Sec. 4):
// node j of level k holds (min, max) of the stored depths of texels [j 2^k, (j + 1) 2^k) of
// its row, all levels packed into one rg32float row (layout: `scatter::minmax`,
// `scatter_frame::minmax`).
//
// One workgroup of LANES invocations per row. The row is cut into LANES blocks of B = 2^t
// texels (the smallest power of two with LANES B >= Wr); phase 1: invocation i writes the
// nodes of levels 0 .. t inside block i, each reduced straight from the rectified map ((t +
// 1) B loads per invocation), and keeps its level-t node in workgroup memory; phase 2, after
// one barrier: the levels above t (at most LANES - 1 nodes), one node per invocation, each
// reduced from the level-t nodes. Every invocation does the same work in phase 1. (Before:
// one invocation per node reducing its span from the map, O(Wr log Wr) loads per row with
// the root's Wr loads in one 8-lane batch: 32-36 ms at 1024 x 1024 on llvmpipe, 2.8x its
// store bound.)
//
// Bindings (group 0):
// | binding | name      | type                                    | access       |
// |---------|-----------|-----------------------------------------|--------------|
// | 0       | frame     | var<uniform> Frame (432 bytes)          | uniform      |
// | 1       | rectified | texture_2d<f32> (r32float, `rectify`'s) | textureLoad  |
// | 2       | tree      | texture_storage_2d<rg32float, write>    | textureStore |
// tree: tree_width(Wr) x Hr, Wr x Hr = the rectified size (frame.sizes.zw).
//
// Dispatch: (1, Hr, 1) workgroups of (LANES, 1, 1): invocations (LANES, Hr, 1); workgroup
// y = row.
//
// Mirrors reference/src/kernels/minmax_build.rs

#import scatter::epipolar::Frame
#import scatter::minmax::{level_count, level_offset}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var rectified: texture_2d<f32>;
@group(0) @binding(2) var tree: texture_storage_2d<rg32float, write>;

// Invocations per row (`scatter_shaderlib::minmax::BUILD_WORKGROUP_SIZE`).
const LANES: u32 = 128u;

// The level-t node of every block of the row (phase 1's results, phase 2's input).
var<workgroup> block_nodes: array<vec2<f32>, LANES>;

// (min, max) of the stored depths of texels [a, b) of row y (a < b).
fn span_min_max(a: u32, b: u32, y: u32) -> vec2<f32> {
    let d0 = textureLoad(rectified, vec2<u32>(a, y), 0).x;
    var v = vec2<f32>(d0, d0);
    for (var x = a + 1u; x < b; x++) {
        let d = textureLoad(rectified, vec2<u32>(x, y), 0).x;
        v = vec2<f32>(min(v.x, d), max(v.y, d));
    }
    return v;
}

@compute @workgroup_size(128, 1, 1)
fn minmax_build(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) i: u32) {
    let width = frame.sizes[2];
    let y = wid.y;
    if y >= frame.sizes[3] {
        return;
    }
    // The block side B = 2^t.
    var t = 0u;
    while (LANES << t) < width {
        t++;
    }
    // Phase 1: levels 0 .. t of block i (node j of level k lies in block j >> (t - k)).
    var top = vec2<f32>(0.0, 0.0);
    for (var k = 0u; k <= t; k++) {
        let count = level_count(k, width);
        let off = level_offset(k, width);
        let per_block = 1u << (t - k);
        for (var n = 0u; n < per_block; n++) {
            let j = i * per_block + n;
            if j < count {
                let v = span_min_max(j << k, min((j + 1u) << k, width), y);
                textureStore(tree, vec2<u32>(off + j, y), vec4<f32>(v.x, v.y, 0.0, 0.0));
                top = v;
            }
        }
    }
    // Block i's level-t node (blocks beyond the row are never read).
    block_nodes[i] = top;
    workgroupBarrier();
    // Phase 2: node c of the levels above t, counted across them in order.
    let count_t = level_count(t, width);
    var c = i;
    var k = t + 1u;
    // Level k exists while level k - 1 has more than one node.
    while level_count(k - 1u, width) > 1u {
        let count = level_count(k, width);
        if c < count {
            let a = c << (k - t);
            let b = min((c + 1u) << (k - t), count_t);
            var v = block_nodes[a];
            for (var m = a + 1u; m < b; m++) {
                let w = block_nodes[m];
                v = vec2<f32>(min(v.x, w.x), max(v.y, w.y));
            }
            textureStore(tree, vec2<u32>(level_offset(k, width) + c, y), vec4<f32>(v.x, v.y, 0.0, 0.0));
            break;
        }
        c -= count;
        k++;
    }
}
