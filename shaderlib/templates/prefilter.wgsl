{%- if moments %}
// prefilter ({{ moment_count }} power moments, {{ regions }} regions, {{ visibility_name }} visibility, {{ light_name }} light, {{ storage }}, {{ rectification_name }}):
// the moment basis (Peters et al. 2016) fused with the weighted running mean along each
// rectified row (Klehm et al. 2014, Sec. 3.3 and 5, Listings 1-3, Table 1's regions).
//
// One invocation per (row, region) (thread is always 0): it filters the {{ moment_count }} power moments
// of z = (2 d - lo - hi) / max(hi - lo, 0.1), (z, z^2, z^3, z^4){% if layers > 1 %} and (z^5, z^6, 0, 0){% endif %}, in {{ layers }} layer{% if layers > 1 %}s{% endif %},
// [lo, hi] the region's whole depth range (a first pass over its depths; `moment_z`).
// Each region restarts the running mean. Stored per texel: the normalised weighted mean
// b_k = sum w_i z_i^k / sum w_i over the region up to the texel, as it is ({{ storage }}).
// The invocation also stores the least and the greatest depth over the region up to the
// texel (`bounds`): where a ray's depth lies outside them, scatter knows the region's
// visibility exactly and skips the moment reconstruction.
{%- else %}
// prefilter ({{ bases }} bases, {{ bases_per_thread }} per thread, {{ regions }} regions, {{ visibility_name }} visibility, {{ light_name }} light, {{ storage }}, {{ rectification_name }}):
// the Fourier basis transform fused with the weighted running mean along each rectified row
// (Klehm et al. 2014, Sec. 3.3 and 5, Listings 1-3, Table 1's regions and bases per thread).
//
// One invocation per (row, region, thread): thread t of a row-region filters the
// {{ bases_per_thread }} bases of layers t * {{ layers_per_thread }} .. (t + 1) * {{ layers_per_thread }}, four bases packed per vec4.
// Each region restarts the running mean. Stored per texel: the normalised weighted mean
// F_k = sum w_i B_k(d_i) / sum w_i over the region up to the texel, mapped to [0, 1] as
// F / 2 + 0.5 in {{ storage }}. Thread 0 of a row-region also stores the least and the
// greatest depth over the region up to the texel (`bounds`): where a ray's depth lies outside
// them, scatter knows the region's visibility exactly and skips the Fourier estimate.
{%- endif %}
{%- if cookie %}
//
// Cookie (scatter_frame::cookie): a cookie is constant along each light ray, so it folds into
// each texel's weight. Texel i's light ray has the cookie C_i (RGB; the ray through the
// texel's centre), and per channel c the filter stores the running mean of C_i^c times the
// basis, {% if moments %}sum w_i C_i^c z_i^k / sum w_i{% else %}F_k^c = sum w_i C_i^c B_k(d_i) / sum w_i (as F / 2 + 0.5){% endif %}, in layers c * {{ layers }} + q,
// and thread 0 the region's mean cookie Cbar^c = sum w_i C_i^c / sum w_i (rgb) in layer {{ cbar_layer }}:
// the lit share sum w_i C_i^c H(d_i - d) / sum w_i then has the same expansion as the
// visibility with Cbar^c in place of 1 (scatter).
{%- endif %}
{%- if projective %}
//
// Projective variant: in a projective frame (frame.proj.x = 1) `rectified` is the engine's
// rasterised map (clip z / w in [0, 1], r32float or depth32float) and the weights follow the
// projective map's texel spans (`proj_texel_weight`); other frames are epipolar as usual.
{%- endif %}
//
// Bindings (group 0):
// | binding | name      | type                                            | access       |
// |---------|-----------|-------------------------------------------------|--------------|
// | 0       | frame     | var<uniform> Frame (432 bytes)                  | uniform      |
// | 1       | slices    | var<storage, read> array<vec4<f32>>             | read         |
// | 2       | rectified | texture_2d<f32> (r32float)                      | textureLoad  |
// | 3       | filtered  | var<storage, read_write> array<{{ filtered_word }}> | write  |
// | 4       | bounds    | var<storage, read_write> array<vec2<f32>>       | write        |
{%- if cookie %}
// | 12      | cookie    | texture_2d<f32> (rgba, linear RGB)              | textureLoad  |
{%- endif %}
// filtered: Wc x Hr texels of {{ filtered_layers }} {{ storage }} layers each{% if !moments %} (bases / 4{% if cookie %} per channel, 3 channels, + 1{% endif %}){% endif %}, Wr x Hr = the rectified
// size (frame.sizes.zw), Wc = Wr / {{ stride }} the stored columns. bounds: Wc x Hr, (min, max) of the region's depths up to the texel (`bounds_index`).
{%- if stride > 1 %}
//
// Coarse filtered columns (filtered_stride = {{ stride }}): the loop filters every rectified texel
// of its row and region, but stores the running means and bounds only at the right edge of
// every {{ stride }}-th column (i % {{ stride }} = {{ stride }} - 1, into stored column i / {{ stride }}); regions start on multiples of {{ stride }}
// (`region_column`), so every stored column belongs to one region. Stored column j holds
// what one texel of a map with {{ stride }} times wider columns would hold had rectify averaged
// its {{ stride }} light rays' bases rather than point-sampled one.
{%- endif %}
//
// Dispatch: (ceil(Hr / 64), {{ regions }}, {{ threads_per_row_region }}) workgroups of (64, 1, 1);
// invocation id x = row, y = region, z = thread.
//
// Mirrors reference/src/kernels/prefilter.rs

#import scatter::epipolar::{Frame, {% if cookie %}SliceParams, {% endif %}row_phi, slice_e, slice_params}
{%- if moments %}
#import scatter::prefiltered::{region_column, texel_weight}
#import scatter::moments::{moment_layer, moment_z}
{%- else %}
#import scatter::model::PI
#import scatter::prefiltered::{basis4, fourier_step, region_column, texel_weight, turn}
{%- endif %}
{%- if projective %}
#import scatter::projective::proj_stored_depth
{%- if cookie %}
#import scatter::prefiltered_projective::{proj_region_g, proj_texel_weight}
{%- else %}
#import scatter::prefiltered_projective::proj_texel_weight
{%- endif %}
{%- endif %}
{%- if cookie %}
#import scatter::cookie::frame_cookie
{%- endif %}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> slices: array<vec4<f32>>;
@group(0) @binding(2) var rectified: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> filtered: array<{{ filtered_word }}>;
@group(0) @binding(4) var<storage, read_write> bounds: array<vec2<f32>>;
{%- if cookie %}
// The spot's cookie (scatter_frame::cookie), folded into each texel's weight.
@group(0) @binding(12) var cookie: texture_2d<f32>;
{%- endif %}
{% include "include/prefiltered_buffers.wgsl" %}

// Independent prefix regions per row.
const REGIONS: u32 = {{ regions }}u;
// Bases filtered by one invocation.
const BASES_PER_THREAD: u32 = {{ bases_per_thread }}u;
// Invocations per (row, region): bases / bases_per_thread.
const THREADS_PER_ROW_REGION: u32 = {{ threads_per_row_region }}u;
{%- if cookie %}
// rgba layers of one colour channel's basis.
const LAYERS: u32 = {{ layers }}u;

{% include "include/texel_cookie.wgsl" %}
{%- endif %}

// The kernel body for invocation `id` = (row, region, thread).
@compute @workgroup_size(64, 1, 1)
fn prefilter(@builtin(global_invocation_id) id: vec3<u32>) {
    let row = id.x; let region = id.y; let thread = id.z;
    let width = frame.sizes[2];
    if row >= frame.sizes[3] || region >= REGIONS || thread >= THREADS_PER_ROW_REGION {
        return;
    }
    let weighted = {{ weighted }};
    let spot = {{ spot }};
{%- if projective %}
    let proj = frame.proj[0] > 0.5;
{%- endif %}
{%- if moments %}
    let layers_per_thread = {{ layers_per_thread }}u;
{%- else %}
    let layers_per_thread = BASES_PER_THREAD / 4u;
{%- endif %}
    let slice = slice_params(slices[row]);
    // The row's slice direction (the spot weights' light rays, the cookie's).
    let e = slice_e(frame, row_phi(frame, row));
    let start = region_column(region, REGIONS, width, STRIDE, spot);
    let end = region_column(region + 1u, REGIONS, width, STRIDE, spot);
{%- if cookie %}
    // Channel c's layer q of this thread at c * layers_per_thread + q.
    var acc: array<vec4<f32>, {{ acc_layers }}>;
    // The region's running mean of the cookie (thread 0 stores it).
    var tint_mean = vec3<f32>(0.0);
{%- if !projective %}
    let proj = false;
{%- endif %}
{%- else %}
    var acc: array<vec4<f32>, {{ layers_per_thread }}>;
{%- endif %}
    var wsum = 0.0;
    var lo = 1e30;
    var hi = -1e30;
{%- if moments %}
    // The region's whole depth range (what `bounds` holds at its last stored column), which
    // `moment_z` maps to [-1, 1]: one pass of depth loads before the moments.
    var depth_range = vec2<f32>(1e30, -1e30);
    for (var i = start; i < end; i++) {
        var d = textureLoad(rectified, vec2<u32>(i, row), 0).x;
{%- if projective %}
        if proj {
            d = proj_stored_depth(d);
        }
{%- endif %}
        depth_range = vec2<f32>(min(depth_range.x, d), max(depth_range.y, d));
    }
{%- endif %}
    for (var i = start; i < end; i++) {
{%- if projective %}
        var d = textureLoad(rectified, vec2<u32>(i, row), 0).x;
        var w: f32;
        if proj {
            d = proj_stored_depth(d);
            w = proj_texel_weight(frame, slice, i, region, REGIONS, STRIDE, weighted, spot);
        } else {
            w = texel_weight(frame, slice, e, i, weighted, spot);
        }
{%- else %}
        let d = textureLoad(rectified, vec2<u32>(i, row), 0).x;
        let w = texel_weight(frame, slice, e, i, weighted, spot);
{%- endif %}
        wsum += w;
        // Whether texel i ends a stored column (every texel with a stride of 1), and which.
        let store = i % STRIDE == STRIDE - 1u;
        let x = i / STRIDE;
        if thread == 0u {
            lo = min(lo, d);
            hi = max(hi, d);
            if store {
                bounds[bounds_index(x, row)] = vec2<f32>(lo, hi);
{%- if resume %}
                // The region's weight sum up to the texel, from which scatter resumes.
                bounds[weight_index(x, row)] = vec2<f32>(wsum, 0.0);
{%- endif %}
            }
        }
        let blend = select(0.0, w / wsum, wsum > 0.0);
{%- if cookie %}
        let tint = texel_cookie(i, slice, e, region, proj);
        if thread == 0u {
            tint_mean = tint_mean * (1.0 - blend) + tint * blend;
            if store {
                filtered[filtered_index(x, row, 3u * LAYERS)] = encode_layer(vec4<f32>(tint_mean, 1.0));
            }
        }
{%- endif %}
{%- if moments %}
        // The power moments of z in the region's range, stored as they are.
        let z = moment_z(d, depth_range);
        for (var q = 0u; q < layers_per_thread; q++) {
{%- if cookie %}
            let b = moment_layer(z, q);
            for (var c = 0u; c < 3u; c++) {
                let slot = c * layers_per_thread + q;
                acc[slot] = acc[slot] * (1.0 - blend) + b * (tint[c] * blend);
                if store {
                    filtered[filtered_index(x, row, c * LAYERS + q)] = encode_layer(acc[slot]);
                }
            }
{%- else %}
            acc[q] = acc[q] * (1.0 - blend) + moment_layer(z, q) * blend;
            if store {
                filtered[filtered_index(x, row, q)] = encode_layer(acc[q]);
            }
{%- endif %}
        }
{%- else %}
        // The basis angles c_k d by angle addition: (sin, cos)(pi d) turned by
        // (sin, cos)(2 pi d) from this thread's first frequency on (two transcendentals per
        // texel, not four per layer). Thread t > 0 starts at its first frequency,
        // c = pi (1 + 4 t L) d with L layers per thread, directly: two more transcendentals
        // in place of 2 t L turns (m128-r8 lowres 2 with filtered_stride 4 on foliage,
        // 1024x1024: `prefilter` 183-189 -> 86-90 ms on lavapipe).
        var angle = vec2<f32>(sin(PI * d), cos(PI * d));
        let step = fourier_step(angle);
        if thread > 0u {
            let c = PI * d * f32(1u + 4u * thread * layers_per_thread);
            angle = vec2<f32>(sin(c), cos(c));
        }
        for (var q = 0u; q < layers_per_thread; q++) {
            let layer = thread * layers_per_thread + q;
            let second = turn(angle, step);
            let b = basis4(angle, second);
            angle = turn(second, step);
{%- if cookie %}
            for (var c = 0u; c < 3u; c++) {
                let slot = c * layers_per_thread + q;
                acc[slot] = acc[slot] * (1.0 - blend) + b * (tint[c] * blend);
                if store {
                    filtered[filtered_index(x, row, c * LAYERS + layer)] = encode_layer(acc[slot] * 0.5 + 0.5);
                }
            }
{%- else %}
            let a = acc[q];
            acc[q] = a * (1.0 - blend) + b * blend;
            let stored = acc[q] * 0.5 + 0.5;
            if store {
                filtered[filtered_index(x, row, layer)] = encode_layer(stored);
            }
{%- endif %}
        }
{%- endif %}
    }
}
