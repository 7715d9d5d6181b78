// ivsv_scan: the extrusion of the marked voxels into shadow volumes (Wyman & Dai 2013,
// Sec. 4.2): an OR prefix scan of every row along alpha. Along a light ray (fixed theta and
// phi) the eye angle grows from 0 at the VPL to pi - phi at infinity, so every voxel past the
// first occluder's is in shadow: after the scan a bit stays set along alpha.
//
// Invocation (w, j, v) scans word w (phi bits 32 w .. 32 w + 31) of row j of VPL v
// sequentially, writes the running OR to `volume` and zeroes the `marks` it read
// (atomicExchange), so that the next frame's `ivsv_rectify` starts from zero without a
// clearing pass.
//
// Bindings (group 0):
// | binding | name   | type                                        | access         |
// |---------|--------|---------------------------------------------|----------------|
// | 0       | frame  | var<uniform> IvsvFrame (112 bytes)          | uniform        |
// | 1       | marks  | var<storage, read_write> array<atomic<u32>> | atomicExchange |
// | 2       | volume | var<storage, read_write> array<u32>         | write          |
// volume: 4 N theta alpha u32 (the voxel bits `ivsv_gather` reads), laid out as marks.
//
// Dispatch: (ceil(4 theta / 64), N, 1) workgroups of (64, 1, 1); invocation id x = 4 j + w,
// y = VPL.
//
// Mirrors reference/src/kernels/ivsv_scan.rs

#import scatter::ivsv::{IvsvFrame, voxel_word}

@group(0) @binding(0) var<uniform> frame: IvsvFrame;
@group(0) @binding(1) var<storage, read_write> marks: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> volume: array<u32>;

@compute @workgroup_size(64, 1, 1)
fn ivsv_scan(@builtin(global_invocation_id) id: vec3<u32>) {
    let m = frame;
    let j = id.x / 4u;
    let w = id.x % 4u;
    let v = id.y;
    if j >= m.grid[1] || v >= m.sizes[3] {
        return;
    }
    var acc = 0u;
    // `i + 1u <= n`, not `i < n`: lavapipe re-specialises a shader at every dispatch when a loop
    // compares its counter with a uniform (`scatter_shaderlib::uniform_branches`).
    for (var i = 0u; i + 1u <= m.grid[0]; i += 1u) {
        let at = voxel_word(m, v, j, i) + w;
        acc = acc | atomicExchange(&marks[at], 0u);
        volume[at] = acc;
    }
}
