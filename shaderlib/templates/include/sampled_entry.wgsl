{%- if sampling.lowres %}

// Sampling pass (`sampling = lowres`, scatter::sampling): invocation `id` evaluates sample
// `id` (the pixel S / 2 into its S x S block) into `samples`, then every pixel of its block
// that no sample stands for in depth into `output`; `lowres_upsample` fills the rest of
// `output`. Dispatch: ceil(W / S) x ceil(H / S) invocations.
@compute @workgroup_size(8, 8, 1)
fn {{ sampling.entry }}(@builtin(global_invocation_id) id: vec3<u32>) {
    let screen = vec2<u32>(frame.sizes[0], frame.sizes[1]);
    let grid = lowres_grid(screen, SCALE);
    if id.x >= grid.x || id.y >= grid.y {
        return;
    }
    let p = lowres_pixel(id.xy, screen, SCALE);
    let c = {{ sampling.entry }}_pixel(p.x, p.y);
    textureStore(samples, id.xy, vec4<f32>(c.x, c.y, c.z, 1.0));
    for (var k = 0u; k < SCALE * SCALE; k++) {
        let q = id.xy * SCALE + vec2<u32>(k % SCALE, k / SCALE);
        if q.x < screen.x && q.y < screen.y && !lowres_covered(lowres_taps(depth, q, screen, SCALE, DEPTH_BREAK)) {
            let cq = {{ sampling.entry }}_pixel(q.x, q.y);
            textureStore(output, q, vec4<f32>(cq.x, cq.y, cq.z, 1.0));
        }
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
