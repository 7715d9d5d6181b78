// ivsv_interleave_sum: the sum filter of `area_ivsv`'s interleaved gather (Wyman & Dai 2013,
// Sec. 5, after Keller & Heidrich's interleaved sampling): every pixel adds the partial sums
// of the M x M window around it (M = {{ interleave }}; centred, clamped inside the screen, so
// that it holds each pixel class, and so each VPL, exactly once).
//
// Bindings (group 0):
// | binding | name    | type                                           | access       |
// |---------|---------|------------------------------------------------|--------------|
// | 0       | frame   | var<uniform> IvsvFrame (112 bytes)             | uniform      |
// | 1       | partial | texture_2d<f32> (rgba32float, `ivsv_gather`'s) | textureLoad  |
// | 2       | output  | texture_storage_2d<rgba16float, write>         | textureStore |
// output: in-scattered radiance, screen-sized (rgb, alpha 1).
//
// Dispatch: (ceil(W / 8), ceil(H / 8), 1) workgroups of (8, 8, 1), W x H = screen size
// (frame.sizes.xy).
//
// Mirrors reference/src/kernels/ivsv_interleave_sum.rs

#import scatter::ivsv::IvsvFrame

const M: u32 = {{ interleave }}u;

@group(0) @binding(0) var<uniform> frame: IvsvFrame;
@group(0) @binding(1) var partial: texture_2d<f32>;
@group(0) @binding(2) var output: texture_storage_2d<rgba16float, write>;

// First of the M consecutive pixels of the window of pixel `pos` in a line of `len >= M`.
fn window_first(pos: u32, len: u32) -> u32 {
    return u32(clamp(i32(pos) - i32(M / 2u), 0, i32(len) - i32(M)));
}

@compute @workgroup_size(8, 8, 1)
fn ivsv_interleave_sum(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = frame.sizes[0];
    let h = frame.sizes[1];
    if id.x >= w || id.y >= h {
        return;
    }
    let x0 = window_first(id.x, w);
    let y0 = window_first(id.y, h);
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < M; j += 1u) {
        for (var i = 0u; i < M; i += 1u) {
            sum += textureLoad(partial, vec2<u32>(x0 + i, y0 + j), 0).xyz;
        }
    }
    textureStore(output, id.xy, vec4<f32>(sum, 1.0));
}
