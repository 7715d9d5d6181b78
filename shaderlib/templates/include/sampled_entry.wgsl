{%- if sampling.lowres %}

// Samples of the workgroup's 8 x 8 blocks and of the next column and row of blocks (the
// taps of a block's pixels are its own sample and its right and lower neighbours'), and
// the depths of their pixels.
var<workgroup> tile_light: array<vec3<f32>, 81>;
var<workgroup> tile_depth: array<f32, 81>;
// The blocks' pixels to evaluate themselves, packed x | y << 16, and their count (workgroup
// memory starts zeroed).
var<workgroup> refine: array<u32, {{ 64 * sampling.scale * sampling.scale }}>;
var<workgroup> refine_count: atomic<u32>;

// Sampling pass (`sampling = lowres`, scatter::sampling): workgroup `wid` owns the 8 x 8
// blocks from block 8 wid. Phase 1: its invocations evaluate the 9 x 9 samples of those
// blocks and the next ones (sample = the block's first pixel) into workgroup memory,
// rounded to f16 as a per-pixel pass would store them.
// Phase 2: the invocations take the workgroup's 8 S x 8 S pixels, 64 neighbouring ones at a
// time: each gets the blend of its taps (`lowres_blend`), or goes on the workgroup's list
// where the taps cannot stand for it.
// Phase 3: the invocations evaluate the listed pixels, 64 at a time (lanes stay busy where
// a few blocks hold most of the list: an edge, the lamp). Dispatch: (ceil(W / (8 S)),
// ceil(H / (8 S)), 1) workgroups of (8, 8, 1).
@compute @workgroup_size(8, 8, 1)
fn {{ sampling.entry }}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let screen = vec2<u32>(frame.sizes[0], frame.sizes[1]);
    let grid = lowres_grid(screen, SCALE);
    let origin = wid.xy * 8u;
    for (var k = li; k < 81u; k += 64u) {
        let i = min(origin + vec2<u32>(k % 9u, k / 9u), grid - vec2<u32>(1u, 1u));
        let p = lowres_pixel(i, screen, SCALE);
        tile_light[k] = round_f16({{ sampling.entry }}_pixel(p.x, p.y));
        tile_depth[k] = textureLoad(depth, p, 0).x;
    }
    workgroupBarrier();
    // Pixel e of the workgroup's 8 S x 8 S pixels goes to invocation e mod 64: neighbouring
    // invocations take neighbouring pixels.
    for (var k = 0u; k < SCALE * SCALE; k++) {
        let e = li + 64u * k;
        let q = origin * SCALE + vec2<u32>(e % (8u * SCALE), e / (8u * SCALE));
        if q.x < screen.x && q.y < screen.y {
            let t = lowres_taps(q, screen, SCALE);
            var depths = vec4<f32>(0.0, 0.0, 0.0, 0.0);
            var light: array<vec3<f32>, 4>;
            for (var j = 0u; j < 4u; j++) {
                let s = vec2<u32>(t.cols[j % 2u], t.rows[j / 2u]) - origin;
                let at = s.y * 9u + s.x;
                depths[j] = tile_depth[at];
                light[j] = tile_light[at];
            }
            let c = lowres_blend(t.w, depths, light, textureLoad(depth, q, 0).x, DEPTH_BREAK, LIGHT_BREAK);
            if c.w == 0.0 {
                refine[atomicAdd(&refine_count, 1u)] = q.x | (q.y << 16u);
            } else {
                textureStore(output, q, c);
            }
        }
    }
    workgroupBarrier();
    let n = atomicLoad(&refine_count);
    for (var e = li; e < n; e += 64u) {
        let q = vec2<u32>(refine[e] & 0xffffu, refine[e] >> 16u);
        let c = {{ sampling.entry }}_pixel(q.x, q.y);
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
    let c = {{ sampling.entry }}_pixel(id.x, id.y);
    textureStore(output, id.xy, vec4<f32>(c.x, c.y, c.z, 1.0));
}
{%- endif %}
