{%- if sampling.lowres %}

// Samples of the workgroup's 8 x 8 blocks and the one-sample ring around them (the taps of
// the blocks' pixels reach one sample out), and the depths of their pixels.
var<workgroup> tile_light: array<vec3<f32>, 100>;
var<workgroup> tile_depth: array<f32, 100>;

// Sampling pass (`sampling = lowres`, scatter::sampling): workgroup `wid` owns the 8 x 8
// blocks from block 8 wid. Phase 1: its invocations evaluate the 10 x 10 samples of those
// blocks and their ring (sample = the pixel S / 2 into its block) into workgroup memory.
// Phase 2: invocation `lid` fills block 8 wid + lid of `output`, each pixel either the blend
// of its taps (`lowres_blend`) or, where the taps cannot stand for it, its own evaluation.
// Dispatch: (ceil(W / (8 S)), ceil(H / (8 S)), 1) workgroups of (8, 8, 1).
@compute @workgroup_size(8, 8, 1)
fn {{ sampling.entry }}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let screen = vec2<u32>(frame.sizes[0], frame.sizes[1]);
    let grid = lowres_grid(screen, SCALE);
    let origin = vec2<i32>(wid.xy * 8u) - vec2<i32>(1, 1);
    for (var k = li; k < 100u; k += 64u) {
        let i = clamp(origin + vec2<i32>(i32(k % 10u), i32(k / 10u)), vec2<i32>(0, 0), vec2<i32>(grid) - vec2<i32>(1, 1));
        let p = lowres_pixel(vec2<u32>(i), screen, SCALE);
        tile_light[k] = {{ sampling.entry }}_pixel(p.x, p.y);
        tile_depth[k] = textureLoad(depth, p, 0).x;
    }
    workgroupBarrier();
    let b = wid.xy * 8u + lid.xy;
    if b.x >= grid.x || b.y >= grid.y {
        return;
    }
    for (var k = 0u; k < SCALE * SCALE; k++) {
        let q = b * SCALE + vec2<u32>(k % SCALE, k / SCALE);
        if q.x >= screen.x || q.y >= screen.y {
            continue;
        }
        let t = lowres_taps(q, screen, SCALE);
        var depths = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        var light: array<vec3<f32>, 4>;
        for (var j = 0u; j < 4u; j++) {
            let s = vec2<i32>(vec2<u32>(t.cols[j % 2u], t.rows[j / 2u])) - origin;
            let at = u32(s.y) * 10u + u32(s.x);
            depths[j] = tile_depth[at];
            light[j] = tile_light[at];
        }
        var c = lowres_blend(t.w, depths, light, textureLoad(depth, q, 0).x, DEPTH_BREAK, LIGHT_BREAK);
        if c.w == 0.0 {
            let e = {{ sampling.entry }}_pixel(q.x, q.y);
            c = vec4<f32>(e.x, e.y, e.z, 1.0);
        }
        textureStore(output, q, c);
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
