// row_prefix ({{ mode_name }} mode): per-row running prefix over an rgba texture array.
//
// One invocation per (row, layer) walks its row from x = 0 to width - 1 and writes at every x
{%- if mean %}
// the running mean of texels 0..=x, blended exactly as Klehm et al. 2014, Sec. 3.3,
// Listing 1 ("basis-texture filtering"): F = mix(F, B, 1 / (i + 1)). This is the
// normalised prefix that the prefiltered method stores per Fourier basis.
{%- else %}
// the inclusive prefix sum of texels 0..=x (the unnormalised form of Klehm et al. 2014,
// Sec. 3.3, Listing 1).
{%- endif %}
//
// Bindings (group 0):
// | binding | name   | type                                         | access       |
// |---------|--------|----------------------------------------------|--------------|
// | 0       | input  | texture_2d_array<f32>, float, non-filterable | textureLoad  |
// | 1       | output | texture_storage_2d_array<rgba32float, write> | textureStore |
// Input and output have the same size (width x height x layers).
//
// Dispatch: (ceil(height / {{ workgroup_size }}), layers, 1) workgroups of ({{ workgroup_size }}, 1, 1);
// invocation id x = row, y = layer. Dimensions come from textureDimensions, so no uniforms.
//
// Mirrors reference/src/kernels/row_prefix.rs

#import scatter::indexing::{row_in_range, running_mean_weight}

@group(0) @binding(0) var input: texture_2d_array<f32>;
@group(0) @binding(1) var output: texture_storage_2d_array<rgba32float, write>;

@compute @workgroup_size({{ workgroup_size }}, 1, 1)
fn row_prefix(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(input);
    let layers = textureNumLayers(input);
    let row = id.x;
    let layer = id.y;
    if !row_in_range(row, layer, size.y, layers) {
        return;
    }
    var acc = vec4<f32>(0.0);
    for (var x = 0u; x < size.x; x += 1u) {
        let texel = textureLoad(input, vec2<u32>(x, row), layer, 0);
{%- if mean %}
        acc = mix(acc, texel, vec4<f32>(running_mean_weight(x)));
{%- else %}
        acc = acc + texel;
{%- endif %}
        textureStore(output, vec2<u32>(x, row), layer, acc);
    }
}
