// depth_columns: the deepest pixel of every column of the depth buffer, for `slice_fit`.
//
// One invocation per screen column walks the column (neighbouring invocations read
// neighbouring texels) and stores the largest view depth it read, clamped to [0, far] as
// `scatter` clamps it. No workgroup memory and no barrier. Two levels (columns here, then
// the columns' maxima in `slice_fit`) spread the depth buffer's reads over every core: one
// workgroup reading all of it ran on one CPU thread on lavapipe (10.6 ms at 1280x720), and a
// workgroup per row reducing through workgroup memory spent most of its 7 ms in barriers.
//
// Bindings (group 0):
// | binding | name         | type                                   | access      |
// |---------|--------------|----------------------------------------|-------------|
// | 0       | frame        | var<uniform> Frame (432 bytes)         | uniform     |
// | 1       | depth        | texture_2d<f32> (r32float, view depth) | textureLoad |
// | 2       | column_depth | var<storage, read_write> array<f32>    | write       |
// column_depth: one f32 per screen column (frame.sizes.x).
//
// Dispatch: (ceil(W / 64), 1, 1) workgroups of (64, 1, 1), W = screen width
// (frame.sizes.x); invocation id x = screen column.
//
// Mirrors reference/src/kernels/depth_columns.rs

#import scatter::epipolar::Frame

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var depth: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> column_depth: array<f32>;

@compute @workgroup_size(64, 1, 1)
fn depth_columns(@builtin(global_invocation_id) id: vec3<u32>) {
    let f = frame;
    let x = id.x;
    if x >= f.sizes[0] {
        return;
    }
    let far = f.theta.z;
    var z = 0.0;
    let rows = f.sizes[1];
    var y = 0u;
    // Four rows per trip, then the rest: llvmpipe pays its loop overhead per trip (the pass
    // 1.5-2.0 ms at 1280x720 against 1.7-2.3 with one row per trip, stop 46). The same
    // maximum (max is exact). Neither exit test is `y < rows` (`scatter_shaderlib::uniform_branches`).
    for (; y + 4u <= rows; y += 4u) {
        let a = min(max(textureLoad(depth, vec2<u32>(x, y), 0).x, 0.0), far);
        let b = min(max(textureLoad(depth, vec2<u32>(x, y + 1u), 0).x, 0.0), far);
        let c = min(max(textureLoad(depth, vec2<u32>(x, y + 2u), 0).x, 0.0), far);
        let d = min(max(textureLoad(depth, vec2<u32>(x, y + 3u), 0).x, 0.0), far);
        z = max(z, max(max(a, b), max(c, d)));
    }
    for (; y + 1u <= rows; y++) {
        let v = textureLoad(depth, vec2<u32>(x, y), 0).x;
        z = max(z, min(max(v, 0.0), far));
    }
    column_depth[x] = z;
}
