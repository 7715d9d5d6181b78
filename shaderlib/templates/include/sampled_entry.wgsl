{%- if sampling.lowres && !sampling.unwarp && !sampling.fallback %}

// Sampling pass 1 (`sampling = lowres`, scatter::sampling): invocation `id` evaluates sample
// `id` of the low-resolution grid (`lowres_pixel`: the first pixel of block `id`, or the
// screen's last pixel) into `output` (`lowres_samples`, rgba32float: the radiance rounded to
// f16 as a per-pixel pass would store it, the sample pixel's view depth in w), and zeroes
// `fallback_count` for the unwarp. Three passes, as with epipolar sampling, not one with the
// blend and the refinement in workgroup memory: there (one workgroup per 8 x 8 blocks) the
// workgroups evaluated their 9 x 9 samples, 27 % more than they own, and llvmpipe runs the
// code between barriers as separately resumed parts; the single pass took 61-76 ms for
// prefiltered m32-r8 at lowres 2 and 1280x720 (eleventh bench run).
// Dispatch: (ceil((ceil(W / S) + 1) / 8), ceil((ceil(H / S) + 1) / 8), 1) workgroups of
// (8, 8, 1); the invocations beyond the grid (ceil((W - 1) / S) + 1 per axis) return.
@compute @workgroup_size(8, 8, 1)
fn {{ sampling.entry }}(@builtin(global_invocation_id) id: vec3<u32>) {
    let screen = vec2<u32>(frame.sizes[0], frame.sizes[1]);
    if id.x == 0u && id.y == 0u {
        // An empty fallback list for the unwarp (no host clear).
        fallback_list_reset();
    }
    let grid = lowres_grid(screen, SCALE);
    if id.x >= grid.x || id.y >= grid.y {
        return;
    }
    let p = lowres_pixel(id.xy, screen, SCALE);
    let c = round_f16({{ sampling.pixel }}(p.x, p.y));
    textureStore(output, id.xy, vec4<f32>(c.x, c.y, c.z, textureLoad(depth, p, 0).x));
}
{%- else if sampling.lowres && sampling.unwarp %}

// Sampling pass 2 (`sampling = lowres`, scatter::sampling): invocation `id` gathers the
// pixels of block `id` (S x S pixels from S id, those on the screen): each the blend of its
// four samples (`lowres_taps`) kept by depth and light spread (`lowres_blend`), or, where they
// cannot stand for it, listed in `fallback_pixels` for pass 3 (0 written), the block's list with one atomic. The pixels of
// a block share their four samples (only their weights differ), so the block loads them once:
// 4 sample loads for S^2 pixels instead of 4 per pixel (llvmpipe pays about 1 ms per texel
// load per 1280x720 pixels; one invocation per pixel took 9-10 ms at 1280x720, stop 45).
// Dispatch: (ceil(ceil(W / S) / 8), ceil(ceil(H / S) / 8), 1) workgroups of (8, 8, 1).
@compute @workgroup_size(8, 8, 1)
fn {{ sampling.entry }}(@builtin(global_invocation_id) id: vec3<u32>) {
    let screen = vec2<u32>(frame.sizes[0], frame.sizes[1]);
    let q0 = id.xy * SCALE;
    if q0.x >= screen.x || q0.y >= screen.y {
        return;
    }
    let t0 = lowres_taps(q0, screen, SCALE);
    var depths = vec4<f32>(0.0, 0.0, 0.0, 0.0);
    var light: array<vec3<f32>, 4>;
    for (var j = 0u; j < 4u; j++) {
        let v = textureLoad(lowres_samples, vec2<u32>(t0.cols[j % 2u], t0.rows[j / 2u]), 0);
        depths[j] = v.w;
        light[j] = v.xyz;
    }
    var listed = 0u;
    for (var i = 0u; i < SCALE * SCALE; i++) {
        let q = q0 + vec2<u32>(i % SCALE, i / SCALE);
        if q.x < screen.x && q.y < screen.y {
            let w = lowres_taps(q, screen, SCALE).w;
            listed |= unwarp_pixel(q, i, w, w, depths, light);
        }
    }
    fallback_list_block(q0, SCALE, listed);
}
{%- else if sampling.epipolar && !sampling.unwarp && !sampling.fallback %}

// One slice's samples: their depths, the evaluated samples around each (`line_ab`: a | b
// << 16, a = b = k for a sample marked for evaluation), their radiance, and lists of samples
// to evaluate with their counts (workgroup memory starts zeroed).
var<workgroup> line_depth: array<f32, {{ sampling.slice_samples }}>;
var<workgroup> line_ab: array<u32, {{ sampling.slice_samples }}>;
var<workgroup> line_light: array<vec3<f32>, {{ sampling.slice_samples }}>;
var<workgroup> line_list: array<u32, {{ sampling.slice_samples }}>;
// (Two scalars, not an array of atomics: naga's SPIR-V front-end reads the zero
// initialisation of an atomic array as a plain store, which its validator rejects.)
var<workgroup> line_count: atomic<u32>;
var<workgroup> line_count_light: atomic<u32>;

// The marked samples around sample k (k itself when it is one; every STEP-th sample and the
// last are marked, so both exist), from `line_ab`.
fn line_bracket(k: u32) -> vec2<u32> {
    let v = line_ab[k];
    return vec2<u32>(v & 0xffffu, v >> 16u);
}

// Whether sample k is marked for evaluation (its own bracket).
fn line_marked(k: u32) -> bool {
    return (line_ab[k] & 0xffffu) == k;
}

// Whether evaluated samples a and b differ by more than LIGHT_BREAK of the brighter (then
// the samples between them are evaluated too).
fn line_spread_over(ab: vec2<u32>) -> bool {
    let la = line_light[ab.x];
    let lb = line_light[ab.y];
    let hi = max(la, lb);
    let spread = abs(la - lb);
    return max(spread.x, max(spread.y, spread.z)) > LIGHT_BREAK * max(hi.x, max(hi.y, hi.z));
}

// Sampling pass 1 (`sampling = epipolar`, scatter::sampling): workgroup `wid.x` takes slice
// wid.x. Its invocations find the slice's samples and their pixels' depths; mark every
// STEP-th sample, the last, and both samples on either side of a depth break; evaluate the
// marked ones (rounded to f16 as a per-pixel pass stores them); then evaluate every sample
// between two marked ones that differ by more than LIGHT_BREAK; and interpolate the rest
// between the marked samples around them. Writes `output` ((SLICE_SAMPLES + 1) x (SLICES + 1),
// rgba32float: radiance and the sample pixel's depth in w; the last column holds the
// slice's line: direction xy, first distance z, distance between samples w; the last row's
// first two texels the layout: origin, axis; first angle, angle per slice, wrap), and
// zeroes `fallback_count` for the unwarp. Dispatch: (SLICES, 1, 1) workgroups of (SLICE_LANES, 1,
// 1): {{ sampling.slice_lanes }}, one of llvmpipe's 8-lane batches, which runs a loop's body at least once for
// every batch (under an empty mask when the list is shorter than the batch): the second
// evaluation loop, usually empty, then idles no batches, and a slice's 256 samples take as
// many batch trips as with more lanes (scatter_shaderlib::sampling::SLICE_LANES: 1-2 ms
// faster than 32 lanes at 1280x720; 64 lanes were 5-8 ms slower).
@compute @workgroup_size({{ sampling.slice_lanes }}, 1, 1)
fn {{ sampling.entry }}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let screen = vec2<u32>(frame.sizes[0], frame.sizes[1]);
    let lines = epipolar_layout({{ sampling.camera }}, screen, SLICES);
    let s = wid.x;
    let u = slice_direction(lines, s);
    let span = slice_span(lines, s, screen, SLICE_SAMPLES);
    if li == 0u {
        // The slice's line, for the unwarp.
        textureStore(output, vec2<u32>(SLICE_SAMPLES, s), vec4<f32>(u.x, u.y, span.x, span.y));
        if s == 0u {
            // An empty fallback list for the unwarp (no host clear), and the layout in the
            // last row, so that the unwarp loads it instead of computing it per pixel.
            fallback_list_reset();
            textureStore(output, vec2<u32>(0u, SLICES), vec4<f32>(lines.origin, lines.axis));
            textureStore(output, vec2<u32>(1u, SLICES), vec4<f32>(lines.phi_start, lines.dphi, f32(lines.wrap), 0.0));
        }
    }
    for (var k = li; k < SLICE_SAMPLES; k += SLICE_LANES) {
        let p = slice_sample_pixel(lines, u, span, k, screen);
        line_depth[k] = textureLoad(depth, p, 0).x;
    }
    workgroupBarrier();
    // Run g (samples g STEP up to the next STEP-th, the last run with the last sample)
    // goes to one invocation, which marks its samples walking forward, noting in each
    // unmarked one the marked sample before it, then walking back the one after it: a fixed
    // trip count per invocation (searching `line_ab` from every sample ran loops of up to
    // STEP trips under llvmpipe's 8-lane masks, 4-6 ms of the pass at 1280x720).
    for (var g = li; g < SLICE_RUNS; g += SLICE_LANES) {
        let s0 = g * STEP;
        let e = min(s0 + STEP, SLICE_SAMPLES);
        var a = s0;
        for (var k = s0; k < e; k++) {
            var marked = k % STEP == 0u || k == SLICE_SAMPLES - 1u;
            if k > 0u && !depth_close(line_depth[k - 1u], line_depth[k], DEPTH_BREAK) {
                marked = true;
            }
            if k + 1u < SLICE_SAMPLES && !depth_close(line_depth[k], line_depth[k + 1u], DEPTH_BREAK) {
                marked = true;
            }
            if marked {
                a = k;
                line_list[atomicAdd(&line_count, 1u)] = k;
            }
            line_ab[k] = a | (select(0xffffu, k, marked) << 16u);
        }
        // The sample after the run is a STEP-th one; the last run ends on the last.
        var b = min(e, SLICE_SAMPLES - 1u);
        for (var k = e; k > s0; k--) {
            let v = line_ab[k - 1u];
            if (v & 0xffffu) == k - 1u {
                b = k - 1u;
            } else {
                line_ab[k - 1u] = (v & 0xffffu) | (b << 16u);
            }
        }
    }
    workgroupBarrier();
    let n = atomicLoad(&line_count);
    for (var e = li; e < n; e += SLICE_LANES) {
        let k = line_list[e];
        let p = slice_sample_pixel(lines, u, span, k, screen);
        line_light[k] = round_f16({{ sampling.pixel }}(p.x, p.y));
    }
    workgroupBarrier();
    for (var k = li; k < SLICE_SAMPLES; k += SLICE_LANES) {
        if !line_marked(k) && line_spread_over(line_bracket(k)) {
            line_list[atomicAdd(&line_count_light, 1u)] = k;
        }
    }
    workgroupBarrier();
    let n2 = atomicLoad(&line_count_light);
    for (var e = li; e < n2; e += SLICE_LANES) {
        let k = line_list[e];
        let p = slice_sample_pixel(lines, u, span, k, screen);
        line_light[k] = round_f16({{ sampling.pixel }}(p.x, p.y));
    }
    workgroupBarrier();
    for (var k = li; k < SLICE_SAMPLES; k += SLICE_LANES) {
        var c = line_light[k];
        if !line_marked(k) {
            let ab = line_bracket(k);
            if !line_spread_over(ab) {
                let t = f32(k - ab.x) / f32(ab.y - ab.x);
                c = line_light[ab.x] * (1.0 - t) + line_light[ab.y] * t;
            }
        }
        textureStore(output, vec2<u32>(k, s), vec4<f32>(c.x, c.y, c.z, line_depth[k]));
    }
}
{%- else if sampling.unwarp %}

// Sampling pass 2 (`sampling = epipolar`, scatter::sampling): invocation `id` gathers the
// pixels of block `id` (B x B pixels from B id, B = UNWARP_BLOCK, those on the screen) from
// the four samples around the block's centre (`epipolar_block_slices`, then
// `epipolar_block_taps` with the two slices' lines from the samples' last column: two
// slices, two samples on each), loaded once for the block: each pixel takes them with its
// own weights (`epipolar_block_weights`: the centre's fractions moved by their gradients,
// clamped to the block's samples), kept by depth and light spread as the centre's weights
// would keep them (`lowres_blend`'s support: so that a pixel clamped onto one slice or one
// sample still sees the others for both criteria), or, where they cannot stand for it, is
// listed in `fallback_pixels` for pass 3 (0 written; one atomic per block, `fallback_list_block`) (as is a pixel whose own slice
// lies more than half a slice beyond the block's: slices closer than a pixel). With B = 2
// `minmax_traverse_unwarp` took 13.3-15.7 against 19.2-19.6 ms per pixel at 1280x720
// (llvmpipe pays about 1 ms per texel load and 1 ms per `atan2` over the screen;
// docs/roofline.md, "Stop 53"). Not evaluated here: llvmpipe
// runs an `if` body under a mask for every lane whether or not one takes it, so an inlined
// per-pixel body cost every pixel its set-up (unwarp 32-87 ms at 1280x720 against 25-37 ms
// without it); and not in a workgroup list either: a barrier splits the kernel into
// resumable parts, which cost 20-60 ms more. Dispatch: (ceil(ceil(W / B) / 8),
// ceil(ceil(H / B) / 8), 1) workgroups of (8, 8, 1).
@compute @workgroup_size(8, 8, 1)
fn {{ sampling.entry }}(@builtin(global_invocation_id) id: vec3<u32>) {
    let screen = vec2<u32>(frame.sizes[0], frame.sizes[1]);
    let q0 = id.xy * UNWARP_BLOCK;
    if q0.x >= screen.x || q0.y >= screen.y {
        return;
    }
    // The layout the samples pass computed (the last row of `epipolar_samples`).
    let head = textureLoad(epipolar_samples, vec2<u32>(0u, SLICES), 0);
    let angles = textureLoad(epipolar_samples, vec2<u32>(1u, SLICES), 0);
    let lines = EpipolarLayout(head.xy, head.zw, angles.x, angles.y, u32(angles.z));
    let centre = vec2<f32>(q0) + vec2<f32>(0.5 * f32(UNWARP_BLOCK));
    let pair = epipolar_block_slices(lines, centre, SLICES);
    let line_lo = textureLoad(epipolar_samples, vec2<u32>(SLICE_SAMPLES, pair.slices.x), 0);
    let line_hi = textureLoad(epipolar_samples, vec2<u32>(SLICE_SAMPLES, pair.slices.y), 0);
    let b = epipolar_block_taps(lines, centre, pair, line_lo, line_hi, SLICE_SAMPLES);
    var depths = vec4<f32>(0.0, 0.0, 0.0, 0.0);
    var light: array<vec3<f32>, 4>;
    for (var j = 0u; j < 4u; j++) {
        let v = textureLoad(epipolar_samples, vec2<u32>(b.k[j / 2u] + j % 2u, b.slices[j / 2u]), 0);
        depths[j] = v.w;
        light[j] = v.xyz;
    }
    let support = epipolar_block_weights(b, vec2<f32>(0.0, 0.0));
    var listed = 0u;
    for (var i = 0u; i < UNWARP_BLOCK * UNWARP_BLOCK; i++) {
        let q = q0 + vec2<u32>(i % UNWARP_BLOCK, i / UNWARP_BLOCK);
        if q.x < screen.x && q.y < screen.y {
            let w = epipolar_block_weights(b, vec2<f32>(q) + vec2<f32>(0.5, 0.5) - centre);
            listed |= unwarp_pixel(q, i, w, support, depths, light);
        }
    }
    fallback_list_block(q0, UNWARP_BLOCK, listed);
}
{%- else if sampling.fallback %}

// Sampling pass 3 (`sampling = lowres | epipolar`, scatter::sampling): the pixels the unwarp listed
// in `fallback_pixels`, evaluated with the family's per-pixel body, one per invocation.
// Dispatched indirectly from `fallback_count` (byte 4: the unwarp raised its workgroup
// counts to cover the list, `groups_x` up to FALLBACK_ROW_GROUPS, then rows;
// `scatter_shaderlib::sampling::FALLBACK_ROW_GROUPS`): invocation (x, y) of the
// (8 groups_x, 8 groups_y) grid takes entry y 8 groups_x + x. One pixel per invocation keeps
// each within llvmpipe's 65535 loop trips per invocation, and nothing listed dispatches
// nothing. Written as a loop striding over the grid (it takes one trip): with the body
// after an early `return` instead, llvmpipe re-specialised the pass at every dispatch (2.2
// ms for `minmax_traverse_fallback` with no workgroup dispatched, 0.2 ms as a loop; not a
// uniform-only branch that `uniform_branches` finds). An engine without indirect dispatch
// may dispatch the manifest's bound instead: the invocations outside the grid take nothing.
@compute @workgroup_size(8, 8, 1)
fn {{ sampling.entry }}(@builtin(global_invocation_id) id: vec3<u32>) {
    let screen = vec2<u32>(frame.sizes[0], frame.sizes[1]);
    let lanes = 8u * vec2<u32>(fallback_count.groups_x, fallback_count.groups_y);
    let inside = id.x < lanes.x && id.y < lanes.y;
    let n = select(0u, min(fallback_count.listed, screen.x * screen.y), inside);
    for (var e = id.y * lanes.x + id.x; e < n; e += lanes.x * lanes.y) {
        let q = vec2<u32>(fallback_pixels[e] & 0xffffu, fallback_pixels[e] >> 16u);
        let c = {{ sampling.pixel }}(q.x, q.y);
        textureStore(output, q, vec4<f32>(c.x, c.y, c.z, 1.0));
    }
}
{%- else %}

// Every pixel (`sampling = pixels`): invocation `id` evaluates pixel `id` into `output`.
@compute @workgroup_size(8, 8, 1)
fn {{ sampling.entry }}(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.sizes[0] || id.y >= frame.sizes[1] {
        return;
    }
    let c = {{ sampling.pixel }}(id.x, id.y);
    textureStore(output, id.xy, vec4<f32>(c.x, c.y, c.z, 1.0));
}
{%- endif %}
