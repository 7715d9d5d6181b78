// volume_bounds: the shadow volume's boundary crossings of every rectified row, binned by ray
// depth (Wyman & Ramsey 2008, Sec. 4, rasterising the shadow volume, restricted to one
// epipolar slice). In a slice, a view ray has one normalised depth d, and texel c of the
// row (one light ray, occluder depth S_c) is lit for it iff d <= S_c; the ray crosses the
// volume's boundary at column edge c (texels c - 1, c) iff min(S_(c-1), S_c) < d <=
// max(S_(c-1), S_c). Edge c is written into every bin k = floor(lo B) ..= floor(hi B) its
// depth range (lo, hi] meets (bin k: d in [k / B, (k + 1) / B)), and each bin keeps its
// first and last edge: for any depth of the bin, every crossing lies in [first, last].
// B = {{ bins }} bins (conventions: `scatter_frame::hybrid_volume`).
//
// One workgroup per rectified row: its 64 invocations set the row's bins to "no edge", then
// take every 64th edge and combine with atomicMin / atomicMax on the row's bins in the
// output buffer (order-free, so the result is exact and deterministic). The bins live in the
// storage buffer, not in workgroup memory: naga zero-initialises workgroup memory with a
// store that its own SPIR-V front-end (wgpu's `ShaderSource::SpirV`) rejects for an array of
// atomics.

// Bindings (group 0):
// | binding | name      | type                                        | access      |
// |---------|-----------|---------------------------------------------|-------------|
// | 0       | frame     | var<uniform> Frame (432 bytes)              | uniform     |
// | 1       | rectified | texture_2d<f32> (r32float, `rectify`'s)     | textureLoad |
// | 2       | crossings | var<storage, read_write> array<atomic<u32>> | atomics     |
// crossings: 2 B Hr u32, bin (row, k) at 2 (row * B + k): the first edge, then the last; first
// = 0xffffffff (and last = 0) where no edge reaches the bin.
//
// Dispatch: (1, Hr, 1) workgroups of (64, 1, 1), Hr = rectified rows (frame.sizes.w);
// workgroup id y = row.
//
// Mirrors reference/src/kernels/volume_bounds.rs

#import scatter::epipolar::Frame

const BINS: u32 = {{ bins }}u;
const NO_EDGE: u32 = 0xffffffffu;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var rectified: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> crossings: array<atomic<u32>>;

// The bin of ray depth `d` (clamped to the bins before the conversion, which is undefined
// out of range).
fn depth_bin(d: f32) -> u32 {
    return u32(clamp(floor(d * f32(BINS)), 0.0, f32(BINS - 1u)));
}

@compute @workgroup_size(64, 1, 1)
fn volume_bounds(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let width = frame.sizes[2];
    let row = wid.y;
    let in_range = row < frame.sizes[3];
    if in_range {
        for (var k = li; k < BINS; k += 64u) {
            atomicStore(&crossings[2u * (row * BINS + k)], NO_EDGE);
            atomicStore(&crossings[2u * (row * BINS + k) + 1u], 0u);
        }
    }
    storageBarrier();
    if in_range {
        for (var c = li + 1u; c < width; c += 64u) {
            let a = textureLoad(rectified, vec2<u32>(c - 1u, row), 0).x;
            let b = textureLoad(rectified, vec2<u32>(c, row), 0).x;
            let lo = min(a, b);
            let hi = max(a, b);
            if lo < hi {
                let k1 = depth_bin(hi);
                for (var k = depth_bin(lo); k <= k1; k++) {
                    atomicMin(&crossings[2u * (row * BINS + k)], c);
                    atomicMax(&crossings[2u * (row * BINS + k) + 1u], c);
                }
            }
        }
    }
}
