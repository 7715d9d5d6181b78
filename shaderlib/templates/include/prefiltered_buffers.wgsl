
// `filtered` is a storage buffer, layer-major and, for 4- and 8-byte elements, column-major
// within a layer: layer q of stored texel (x, row) at (q * Wc + x) * Hr + row (rgba32float:
// row-major, (q * Hr + row) * Wc + x), each element one {{ storage }} texel's bits
{%- if storage == "rgba8unorm" %}
// (pack4x8unorm: the rounding an rgba8unorm texture store does).
{%- elif storage == "rgba16float" %}
// (two pack2x16float: the bits of an rgba16float texel).
{%- else %}
// (four f32).
{%- endif %}
// Measured on lavapipe at 1280x720 with a 1024x1024 map (m32-r4, three scenes): `scatter`
// 74-97 ms against 83-125 ms from an rgba texture array, `prefilter` unchanged (40-41 ms
// against 40-49). Column-major puts the rows `prefilter`'s SIMD lanes filter side by side
// (40-41 ms; row-major 41-42); a texel's layers side by side instead made the invocations
// that filter one texel's other layers share its cache lines (63-113 ms). For 16-byte
// rgba32float elements column-major was the slower one: the moment basis's `prefilter` took
// 19.3-22.1 ms column-major against 9.7-10.6 row-major (its `scatter` 57-61 against 58-65;
// m32-r4's rgba8unorm `scatter` 68-91 column-major against 70-97 row-major).

// Rectified columns per stored column (the variant's `filtered_stride`): `prefilter` stores
// its running means and bounds at the right edge of every {{ stride }}-th rectified column only, so
// `filtered` and `bounds` hold Wc = Wr / STRIDE columns per row, and x below counts those.
const STRIDE: u32 = {{ stride }}u;

// The index in `bounds` of stored texel (x, row): column-major as `filtered`'s layers.
// A storage buffer of vec2<f32> in place of an rg32float texture: `scatter` 68.5-93.5 ms
// against 75.7-99.4 (m32-r4 per pixel, the three scenes, binaries alternated), its lowres 2
// samples pass 25-34 against 30-38 (m32-r8); `prefilter` unchanged.
fn bounds_index(x: u32, row: u32) -> u32 {
    return x * frame.sizes[3] + row;
}

{%- if resume %}

// The index in `bounds` of stored texel (x, row)'s weight sum (resume): the second plane,
// after the Wc x Hr (min, max) pairs.
fn weight_index(x: u32, row: u32) -> u32 {
    return (frame.sizes[2] / STRIDE) * frame.sizes[3] + bounds_index(x, row);
}
{%- endif %}

// The index in `filtered` of layer `layer` of stored texel (x, row).
fn filtered_index(x: u32, row: u32, layer: u32) -> u32 {
{%- if storage == "rgba32float" %}
    return (layer * frame.sizes[3] + row) * (frame.sizes[2] / STRIDE) + x;
{%- else %}
    return (layer * (frame.sizes[2] / STRIDE) + x) * frame.sizes[3] + row;
{%- endif %}
}
{%- if storage == "rgba8unorm" %}

fn encode_layer(v: vec4<f32>) -> u32 {
    return pack4x8unorm(v);
}

fn decode_layer(w: u32) -> vec4<f32> {
    return unpack4x8unorm(w);
}
{%- elif storage == "rgba16float" %}

fn encode_layer(v: vec4<f32>) -> vec2<u32> {
    return vec2<u32>(pack2x16float(v.xy), pack2x16float(v.zw));
}

fn decode_layer(w: vec2<u32>) -> vec4<f32> {
    return vec4<f32>(unpack2x16float(w.x), unpack2x16float(w.y));
}
{%- else %}

fn encode_layer(v: vec4<f32>) -> vec4<f32> {
    return v;
}

fn decode_layer(w: vec4<f32>) -> vec4<f32> {
    return w;
}
{%- endif %}

// Layer `layer` of stored texel (x, row).
fn filtered_load(x: u32, row: u32, layer: u32) -> vec4<f32> {
    return decode_layer(filtered[filtered_index(x, row, layer)]);
}
