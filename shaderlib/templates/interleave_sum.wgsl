// interleave_sum: the separable sum filter of interleaved sampling (Tóth & Umenhoffer 2009):
// every pixel adds the partial sums of the Mx x My window around it (centred, clamped
// inside the screen, so it holds each pixel class exactly once), first along x into
// workgroup memory, then along y.
//
// One workgroup per 8 x 8 tile of pixels. Phase 1: the horizontal sums of the tile's columns
// for every row any window of the tile touches (at most 8 + My - 1 rows), two per
// invocation. Phase 2: each pixel adds My of them.
//
// Bindings (group 0):
// | binding | name    | type                                        | access       |
// |---------|---------|---------------------------------------------|--------------|
// | 0       | frame   | var<uniform> RaymarchFrame (240 bytes)              | uniform      |
// | 1       | partial | texture_2d<f32> (rgba32float, `raymarch`'s) | textureLoad  |
// | 2       | output  | texture_storage_2d<rgba16float, write>      | textureStore |
// output: in-scattered radiance, screen-sized (rgb, alpha 1).
//
// Dispatch: (ceil(W / 8), ceil(H / 8), 1) workgroups of (8, 8, 1), W x H = screen size
// (frame.sizes.xy).
//
// Mirrors reference/src/kernels/interleave_sum.rs

#import scatter::raymarch::{RaymarchFrame, window_start}

@group(0) @binding(0) var<uniform> frame: RaymarchFrame;
@group(0) @binding(1) var partial: texture_2d<f32>;
@group(0) @binding(2) var output: texture_storage_2d<rgba16float, write>;

// Tile side (the workgroup is TILE x TILE).
const TILE: u32 = 8u;
// Rows of horizontal sums a tile needs at most: TILE + 8 - 1 (M <= 8).
const ROWS: u32 = 15u;

// Horizontal sums: [row - first row][column in the tile].
var<workgroup> hsum: array<array<vec3<f32>, 8>, 15>;

// The kernel body for pixel `gid` of tile `wid` (local index `lid`).
@compute @workgroup_size(8, 8, 1)
fn interleave_sum(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let m = frame;
    let w = m.sizes[0];
    let h = m.sizes[1];
    let mx = m.interleave[0];
    let my = m.interleave[1];
    let x0 = wid.x * TILE;
    let y0 = wid.y * TILE;
    // Rows touched by the windows of the tile's rows (clamped to the screen).
    let y_last = min(y0 + TILE - 1u, h - 1u);
    let first_row = window_start(y0, my, h);
    let end_row = window_start(y_last, my, h) + my;
    // Phase 1: two (row, column) horizontal sums per invocation.
    for (var k = lid; k < ROWS * TILE; k += TILE * TILE) {
        let r = k / TILE;
        let c = k % TILE;
        let row = first_row + r;
        let col = x0 + c;
        var acc = vec3<f32>(0.0, 0.0, 0.0);
        if row < end_row && col < w {
            let start = window_start(col, mx, w);
            // `i + 1u <= mx`: see the rows loop below.
            for (var i = 0u; i + 1u <= mx; i++) {
                acc += textureLoad(partial, vec2<u32>(start + i, row), 0).xyz;
            }
        }
        hsum[r][c] = acc;
    }
    workgroupBarrier();
    // Phase 2: the vertical sum of each pixel's window.
    let x = gid.x;
    let y = gid.y;
    if x >= w || y >= h {
        return;
    }
    let start = window_start(y, my, h) - first_row;
    var total = vec3<f32>(0.0, 0.0, 0.0);
    // `i + 1u <= n`, not `i < n`: lavapipe re-specialises a shader at every dispatch when a loop
    // compares its counter with a uniform (`scatter_shaderlib::uniform_branches`).
    for (var i = 0u; i + 1u <= my; i++) {
        total += hsum[start + i][x - x0];
    }
    textureStore(output, vec2<u32>(x, y), vec4<f32>(total.x, total.y, total.z, 1.0));
}
