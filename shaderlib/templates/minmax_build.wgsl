// minmax_build: the 1D min-max binary tree of every rectified row (Chen et al. 2011, Sec. 4):
// node j of level k holds (min, max) of the stored depths of texels [j 2^k, (j + 1) 2^k) of
// its row, all levels packed into one rg32float row (layout: `scatter::minmax`,
// `scatter_frame::minmax`).
//
// One workgroup of LANES invocations per row. The row is cut into LANES blocks of B = 2^t
// texels (the smallest power of two with LANES B >= Wr); phase 1: invocation i writes the
// nodes of levels 0 .. t inside block i and keeps its level-t node in workgroup memory;
// phase 2, after one barrier: the levels above t (at most LANES - 1 nodes), one node per
// invocation, each reduced from the level-t nodes. Every invocation does the same work in
// phase 1. Where B >= GROUP (rows of more than 4 LANES texels: t >= 3), phase 1 walks its
// block in groups of GROUP texels, loading each texel once and reducing levels 0 .. 3 of the
// group in registers (B loads per invocation), and reduces the levels 4 .. t from the map
// (B loads each); narrower rows reduce every node straight from the map ((t + 1) B loads,
// at most 6 for t <= 2), where a group of 8 would load texels beyond the block. (Before:
// every node from the map, (t + 1) B = 32 loads per invocation at Wr = 1024: minmax_build
// 3.7 ms at 1024 x 256 on llvmpipe; earlier still one invocation per node, O(Wr log Wr)
// loads per row with the root's Wr loads in one 8-lane batch: 32-36 ms at 1024 x 1024, 2.8x
// its store bound.)
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

// Texels per group of phase 1's register reduction (levels 0 .. GROUP_LEVELS).
const GROUP: u32 = 8u;
const GROUP_LEVELS: u32 = 3u;

// The (min, max) of no texel: the identity of `join`.
const EMPTY: vec2<f32> = vec2<f32>(3.4e38, -3.4e38);

// The level-t node of every block of the row (phase 1's results, phase 2's input).
var<workgroup> block_nodes: array<vec2<f32>, LANES>;

// The node of two nodes.
fn join(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(min(a.x, b.x), max(a.y, b.y));
}

// Texel x of row y as a level-0 node, or EMPTY at or beyond `end` (`end` > 0; the load
// clamped inside [0, end)).
fn leaf(x: u32, end: u32, y: u32) -> vec2<f32> {
    let d = textureLoad(rectified, vec2<u32>(min(x, end - 1u), y), 0).x;
    return select(EMPTY, vec2<f32>(d, d), x < end);
}

// Stores node j of the level at packed column `off` of row y when the level has it (j <
// count).
fn store_node(off: u32, j: u32, count: u32, y: u32, v: vec2<f32>) {
    if j < count {
        textureStore(tree, vec2<u32>(off + j, y), vec4<f32>(v.x, v.y, 0.0, 0.0));
    }
}

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
    // Levels from the map: all of them for narrow rows, those above the groups' otherwise.
    // (The row index in the condition keeps it off lavapipe's uniform inlining,
    // `scatter_shaderlib::uniform_branches`; it is uniform in the workgroup, a real branch.)
    var k_map = 0u;
    if (t >= GROUP_LEVELS) & (y < frame.sizes[3]) {
        k_map = GROUP_LEVELS + 1u;
        let c0 = level_count(0u, width);
        let c1 = level_count(1u, width);
        let c2 = level_count(2u, width);
        let c3 = level_count(3u, width);
        let stop = min((i + 1u) << t, width);
        for (var base = i << t; base < stop; base += GROUP) {
            let end = min(base + GROUP, width);
            let n0 = leaf(base, end, y);
            let n1 = leaf(base + 1u, end, y);
            let n2 = leaf(base + 2u, end, y);
            let n3 = leaf(base + 3u, end, y);
            let n4 = leaf(base + 4u, end, y);
            let n5 = leaf(base + 5u, end, y);
            let n6 = leaf(base + 6u, end, y);
            let n7 = leaf(base + 7u, end, y);
            store_node(0u, base, c0, y, n0);
            store_node(0u, base + 1u, c0, y, n1);
            store_node(0u, base + 2u, c0, y, n2);
            store_node(0u, base + 3u, c0, y, n3);
            store_node(0u, base + 4u, c0, y, n4);
            store_node(0u, base + 5u, c0, y, n5);
            store_node(0u, base + 6u, c0, y, n6);
            store_node(0u, base + 7u, c0, y, n7);
            let m0 = join(n0, n1);
            let m1 = join(n2, n3);
            let m2 = join(n4, n5);
            let m3 = join(n6, n7);
            let j1 = base >> 1u;
            store_node(c0, j1, c1, y, m0);
            store_node(c0, j1 + 1u, c1, y, m1);
            store_node(c0, j1 + 2u, c1, y, m2);
            store_node(c0, j1 + 3u, c1, y, m3);
            let q0 = join(m0, m1);
            let q1 = join(m2, m3);
            let j2 = base >> 2u;
            store_node(c0 + c1, j2, c2, y, q0);
            store_node(c0 + c1, j2 + 1u, c2, y, q1);
            let r = join(q0, q1);
            store_node(c0 + c1 + c2, base >> 3u, c3, y, r);
            top = r;
        }
    }
    for (var k = k_map; k <= t; k++) {
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
