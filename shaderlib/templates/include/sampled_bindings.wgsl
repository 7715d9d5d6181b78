{%- if sampling.lowres %}

// The low-resolution grid's block side S, and its depth and light breaks (fractions).
const SCALE: u32 = {{ sampling.scale }}u;
const DEPTH_BREAK: f32 = {{ sampling.depth_break }};
const LIGHT_BREAK: f32 = {{ sampling.light_break }};
{%- endif %}
{%- if sampling.epipolar %}

// Epipolar slices, samples per slice, the initial step between evaluated samples, and the
// depth and light breaks (fractions).
const SLICES: u32 = {{ sampling.slices }}u;
const SLICE_SAMPLES: u32 = {{ sampling.slice_samples }}u;
const SLICE_LANES: u32 = {{ sampling.slice_lanes }}u;
{%- if sampling.unwarp %}
// Pixels per axis of the blocks the unwarp gathers from four samples each.
const UNWARP_BLOCK: u32 = {{ sampling.unwarp_block }}u;
{%- endif %}
const STEP: u32 = {{ sampling.step }}u;
// Runs of STEP samples from every STEP-th one (the samples pass's unit of work).
const SLICE_RUNS: u32 = (SLICE_SAMPLES + STEP - 1u) / STEP;
const DEPTH_BREAK: f32 = {{ sampling.depth_break }};
const LIGHT_BREAK: f32 = {{ sampling.light_break }};
{%- endif %}
{%- if sampling.unwarp && sampling.lowres %}
// The samples of the low-resolution grid (written by `{{ sampling.family_entry }}`): radiance, and the
// view depth of the sample's pixel in w.
@group(0) @binding({{ sampling.binding }}) var lowres_samples: texture_2d<f32>;
{%- else if sampling.unwarp %}
// The samples of every slice (written by `{{ sampling.family_entry }}`): radiance, and the view depth
// of the sample's pixel in w.
@group(0) @binding({{ sampling.binding }}) var epipolar_samples: texture_2d<f32>;
{%- endif %}
{%- if sampling.fallback %}
// The pixels no sample stands for (listed by `{{ sampling.family_entry }}_unwarp`, packed
// x | y << 16) and their count (then this pass's indirect dispatch; `FallbackCount` read
// only: the same layout without atomics).
struct FallbackCountRead {
    listed: u32,
    groups_x: u32,
    groups_y: u32,
    groups_z: u32,
}
@group(0) @binding({{ sampling.binding + 1 }}) var<storage, read> fallback_count: FallbackCountRead;
@group(0) @binding({{ sampling.binding + 2 }}) var<storage, read> fallback_pixels: array<u32>;
// Workgroups (of 8 x 8) per row of this pass's dispatch.
const FALLBACK_ROW_GROUPS: u32 = {{ sampling.fallback_row_groups }}u;
{%- else if sampling.lowres || sampling.epipolar %}
// How many pixels `{{ sampling.family_entry }}_unwarp` listed for `{{ sampling.family_entry }}_fallback`, and the
// workgroups of 8 x 8 that `{{ sampling.family_entry }}_fallback` is dispatched with (indirectly, from byte 4:
// `groups_x` up to FALLBACK_ROW_GROUPS, then rows); reset by `{{ sampling.family_entry }}`.
struct FallbackCount {
    listed: atomic<u32>,
    groups_x: atomic<u32>,
    groups_y: atomic<u32>,
    groups_z: u32,
}
@group(0) @binding({{ sampling.binding + 1 }}) var<storage, read_write> fallback_count: FallbackCount;
const FALLBACK_ROW_GROUPS: u32 = {{ sampling.fallback_row_groups }}u;

// An empty list, and no workgroups for the fallback (no host clear).
fn fallback_list_reset() {
    atomicStore(&fallback_count.listed, 0u);
    atomicStore(&fallback_count.groups_x, 0u);
    atomicStore(&fallback_count.groups_y, 0u);
    fallback_count.groups_z = 1u;
}
{%- endif %}
{%- if sampling.unwarp %}
// The pixels no sample stands for, packed x | y << 16, for `{{ sampling.family_entry }}_fallback`.
@group(0) @binding({{ sampling.binding + 2 }}) var<storage, read_write> fallback_pixels: array<u32>;

// The unwarp's end for pixel `q` (both sampled modes): the blend of its taps (`w` their
// weights, `support` the weights that decide which stand around it, `depths` their pixels'
// depths, `light` their radiance) kept by depth and light spread (`lowres_blend`) stored into
// `output`; where they cannot stand for it the texel stored is 0 (alpha 0, which the
// fallback pass overwrites) and the pixel's bit is returned (1u << i, `i` its place in the
// block) for `fallback_list_block`.
fn unwarp_pixel(q: vec2<u32>, i: u32, w: vec4<f32>, support: vec4<f32>, depths: vec4<f32>, light: array<vec3<f32>, 4>) -> u32 {
    let c = lowres_blend(w, support, depths, light, textureLoad(depth, q, 0).x, DEPTH_BREAK, LIGHT_BREAK);
    textureStore(output, q, c);
    return select(0u, 1u << i, c.w == 0.0);
}

// Lists the pixels of the block from `q0` (`side` pixels per row) whose bits `listed` holds
// in `fallback_pixels`, with one atomic for the block, and raises the fallback's workgroup
// counts to cover them. Once per block, not per pixel: llvmpipe runs an `if` body under a
// mask whether or not a lane takes it, and a per-pixel list (an atomic and two more where an
// entry opened a workgroup) cost 1.5-2 ms of the unwarp at 1280x720 (prefiltered, 256 slices;
// docs/roofline.md, "Stop 58").
fn fallback_list_block(q0: vec2<u32>, side: u32, listed: u32) {
    if listed != 0u {
        let n = countOneBits(listed);
        let e0 = atomicAdd(&fallback_count.listed, n);
        var bits = listed;
        for (var j = 0u; j < n; j++) {
            let i = firstTrailingBit(bits);
            bits &= bits - 1u;
            let q = q0 + vec2<u32>(i % side, i / side);
            fallback_pixels[e0 + j] = q.x | (q.y << 16u);
        }
        // The workgroups of 64 entries the list now reaches.
        let g = (e0 + n - 1u) / 64u + 1u;
        atomicMax(&fallback_count.groups_x, min(g, FALLBACK_ROW_GROUPS));
        atomicMax(&fallback_count.groups_y, (g + FALLBACK_ROW_GROUPS - 1u) / FALLBACK_ROW_GROUPS);
    }
}
{%- endif %}
