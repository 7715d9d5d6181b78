// pst_sweep ({{ light_name }} light, rank {{ rank }}): the partial-sum-tree method of Baran et al.
// 2010 on the epipolar samples (`sampling = epipolar`): workgroup s takes epipolar sample
// slice s, whose samples are the queries of one sweep through a Fenwick tree over the
// rectified row the slice lies in (the row of its last sample's pixel: row s where the map
// has as many rows as there are slices, whose rows then lie on the slices). Each query is a view
// ray of the row: normalised view angle d, whole columns 0 .. n - 1 (its last, partial column
// n - 1 is added exactly, as `minmax_traverse` adds it), lit where d <= S_i. The column
// weights are separable, `w_i(theta) ~ a(theta) sum_k leaf_k(i) beta_k(theta)` (the frame's
// rank-r SVD, `pst_factors`; scatter_frame::partial_sum_tree), so a query's sum over its lit
// whole columns is `a(theta) beta(theta) . P` with `P` the sum of the leaves of the lit
// columns before n - 1.
//
// The sweep: the V queries are ranked by d (rank j); column i is lit for the b_i queries of
// lowest rank (b_i = how many d <= S_i). Inserting column i's leaf at tree position V - b_i
// and answering a query, in order of n, after the columns 0 .. n - 2 are in, by the prefix
// over positions below V - j sums exactly its lit whole columns: nothing is removed, no sum
// cancels. The columns are split over TREES trees swept at once (step 4); the slice's 32
// invocations first set up the samples, rank them, and compute every column's b_i and leaf. Samples near the epipole
// and the anti-epipole are ray-marched, as every epipolar family marches them.
{%- if cookie %}
//
// Cookie (scatter_frame::cookie): constant along each light ray, so it multiplies a column's
// leaf. Each column has one leaf per colour channel (its quadrature over the column's light
// rays with the cookie at each node), {{ leaf_vecs }} vec4 per leaf and tree entry (channel c at
// c * {{ rank_vecs }} ..); the trees sum them as before, each query dots every channel's prefix with
// beta(theta), and the last, partial column and the epipole march carry the cookie per node.
{%- endif %}
//
// Bindings (group 0):
// | binding | name        | type                                    | access       |
// |---------|-------------|-----------------------------------------|--------------|
// | 0       | frame       | var<uniform> Frame (432 bytes)          | uniform      |
// | 1       | slices      | var<storage, read> array<vec4<f32>>     | read         |
// | 2       | depth       | texture_2d<f32> (r32float, view depth)  | textureLoad  |
// | 3       | shadow_map  | texture_2d<f32> (r32float)              | textureLoad  |
// | 4       | rectified   | texture_2d<f32> (r32float, rectify's)   | textureLoad  |
// | 5       | pst_factors | var<storage, read> array<vec4<f32>>     | read         |
// | 6       | pst_leaves  | var<storage, read_write> array<vec4<f32>> (SLICES x Wr x {{ leaf_vecs }}) | read_write |
// | 7       | pst_tree    | var<storage, read_write> array<vec4<f32>> (SLICES x (TREES + 1) x SLICE_SAMPLES x {{ leaf_vecs }}) | read_write |
// | 8       | pst_columns | var<storage, read_write> array<u32> (SLICES x Wr) | read_write |
// | 9       | output      | texture_storage_2d<rgba32float, write> (epipolar_samples) | textureStore |
// | 11      | fallback_count | var<storage, read_write> FallbackCount (16 bytes) | read_write |
{%- if cookie %}
// | {{ cookie_binding }}      | cookie      | texture_2d<f32> (rgba, linear RGB)      | textureLoad  |
{%- endif %}
// The unwarp and fallback passes (`pst_sweep_unwarp`, `pst_sweep_fallback`) bind 6-8 not.
//
// Dispatch: (SLICES, 1, 1) workgroups of (32, 1, 1).
//
// Mirrors reference/src/kernels/pst_sweep.rs

#import scatter::model::{cone_falloff, phase_hg, transmittance_between}
#import scatter::epipolar::{Frame, in_epipole_disc, edge_t, epipole_march, lit_span, normalised_depth, ray_column, ray_row_coord, ray_theta, row_index, row_phi, slice_e, slice_params}
{%- if cookie %}
#import scatter::cookie::{epipole_march_cookie, frame_cookie, lit_span_cookie}
{%- endif %}
{%- if !sampling.imports.is_empty() %}
{{ sampling.imports }}
{%- endif %}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> slices: array<vec4<f32>>;
@group(0) @binding(2) var depth: texture_2d<f32>;
@group(0) @binding(3) var shadow_map: texture_2d<f32>;
@group(0) @binding(4) var rectified: texture_2d<f32>;
@group(0) @binding(5) var<storage, read> pst_factors: array<vec4<f32>>;
{%- if !sampling.unwarp && !sampling.fallback %}
@group(0) @binding(6) var<storage, read_write> pst_leaves: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> pst_tree: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> pst_columns: array<u32>;
{%- endif %}
@group(0) @binding(9) var output: texture_storage_2d<{{ sampling.output_format }}, write>;
{%- if cookie %}
// The spot's cookie (scatter_frame::cookie): in every leaf, the last column and the march.
@group(0) @binding({{ cookie_binding }}) var cookie: texture_2d<f32>;
{%- endif %}
{% include "include/sampled_bindings.wgsl" %}

// vec4s of the rank's factors (ceil(rank / 4)), vec4s per leaf and tree entry ({% if cookie %}three
// channels of RANK_VECS{% else %}RANK_VECS{% endif %}), grid nodes of the factors, the 2-point Gauss-Legendre node, and the
// sweep's trees per slice.
const RANK_VECS: u32 = {{ rank_vecs }}u;
const LEAF_VECS: u32 = {{ leaf_vecs }}u;
const TREES: u32 = {{ trees }}u;
const GRID: u32 = {{ grid }}u;
const GL2: f32 = 0.57735026f;

// Factor table `base` (1: gamma over v, 1 + 2 GRID: beta over theta) at `x` in [0, 1], bases
// 4h .. 4h + 3, linear between nodes.
fn factor_at(base: u32, x: f32, h: u32) -> vec4<f32> {
    let p = min(clamp(x, 0.0, 1.0) * f32(GRID - 1u), f32(GRID - 1u));
    let j = min(u32(floor(p)), GRID - 2u);
    let t = p - f32(j);
    return pst_factors[base + 2u * j + h] * (1.0 - t) + pst_factors[base + 2u * (j + 1u) + h] * t;
}

// gamma_(4h ..)(v).
fn gamma_at(v: f32, h: u32) -> vec4<f32> {
    return factor_at(1u, v / pst_factors[0].x, h);
}

// beta_(4h ..)(theta).
fn beta_at(theta: f32, h: u32) -> vec4<f32> {
    let head = pst_factors[0];
    return factor_at(1u + 2u * GRID, (theta - head.y) / max(head.z - head.y, 1e-12), h);
}

// The direction `e` of row `row`'s plane of light rays (`slice_e` of its `row_phi`), which a
// spot's leaves read: once per row (a slice's sweep, a fallback pixel), not per column and
// channel (`row_phi` with the rows on the slices is a cos, a sin, an atan2 and a normalize).
// The sun's leaves do not read it.
fn pst_row_e(f: Frame, row: u32) -> vec3<f32> {
    if !{{ spot }} {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    return slice_e(f, row_phi(f, row));
}

// Leaf of column i of the row whose plane is `e` (`pst_row_e`; spacing `delta`), bases
// 4h ..: the sun's gamma(i delta); a spot's integral over the column's light-ray angles of
// gamma(psi) cone(psi) (2-point Gauss-Legendre){% if cookie %};
// with the cookie, entry h < LEAF_VECS is channel h / RANK_VECS's: the integrand times that
// channel of the node's light ray's cookie, bases 4 (h % RANK_VECS) ..{% endif %}.
fn pst_leaf(f: Frame, i: u32, e: vec3<f32>, delta: f32, h: u32) -> vec4<f32> {
    if !{{ spot }} {
        return gamma_at(f32(i) * delta, h);
    }
    let axis = f.axis.xyz;
    var leaf = vec4<f32>(0.0, 0.0, 0.0, 0.0);
    for (var g = 0u; g < 2u; g++) {
        let q = select(GL2, -GL2, g == 0u);
        let psi = (f32(i) + 0.5 + 0.5 * q) * delta;
        let l = -axis * cos(psi) + e * sin(psi);
        let cone = cone_falloff(dot(l, f.light_dir.xyz), f.light_pos[3], f.light_dir[3]);
{%- if cookie %}
        let tint = frame_cookie(f, cookie, f.light_pos.xyz + l)[h / RANK_VECS];
        leaf += (0.5 * delta * cone * tint) * gamma_at(psi, h % RANK_VECS);
{%- else %}
        leaf += (0.5 * delta * cone) * gamma_at(psi, h);
{%- endif %}
    }
    return leaf;
}

// A pixel's ray in rectified space (`minmax_traverse`'s set-up): marched (near the epipoles:
// `color` holds the radiance), or its nearest row, view angle, depth d and the numerator of
// its column x_s (x_s = xs_num / delta of the row it is read in).
struct PstRay {
    marched: bool,
    color: vec3<f32>,
    eye: vec3<f32>,
    dir: vec3<f32>,
    s: f32,
    row: u32,
    theta: f32,
    d: f32,
    xs_num: f32,
}

// The ray through the continuous pixel position `pc` (pixel centres at + 0.5) ending at view
// depth `z`: a pixel's ray (the fallback) or an epipolar sample's, on its slice's line.
fn pst_ray(pc: vec2<f32>, z: f32) -> PstRay {
    let f = frame;
    let spot = {{ spot }};
    let eye = f.eye.xyz;
    let ndc = vec2<f32>(2.0 * pc.x / f32(f.sizes[0]) - 1.0, 1.0 - 2.0 * pc.y / f32(f.sizes[1]));
    let t = f.cam_forward[3];
    let dir = normalize(f.cam_forward.xyz + f.cam_right.xyz * (ndc.x * t * f.cam_right[3]) + f.cam_up.xyz * (ndc.y * t));
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s = min(max(z, 0.0), f.theta.z) / max(dot(dir, f.cam_forward.xyz), 1e-6);
    var r = PstRay(false, vec3<f32>(0.0, 0.0, 0.0), eye, dir, s, 0u, 0.0, 0.0, 0.0);

    // Near the epipole and the anti-epipole the rectification degenerates: march instead.
    if in_epipole_disc(f, pc) {
        r.marched = true;
{%- if cookie %}
        r.color = epipole_march_cookie(frame, shadow_map, cookie, eye, dir, s) * f.light_color.xyz;
{%- else %}
        r.color = epipole_march(frame, shadow_map, eye, dir, s, spot) * f.light_color.xyz;
{%- endif %}
    }

    r.theta = ray_theta(f, dir);
    r.row = row_index(floor(ray_row_coord(f, dir)), f.sizes[3], f.anti_epipole[3] > 0.5);
    r.d = normalised_depth(r.theta, f.theta[0], f.theta[1]);
    r.xs_num = ray_column(f, eye, dir, s, r.theta, spot);
    return r;
}

// Texels the ray crosses in a row of spacing `delta` (NaN or negative x_s: none).
fn pst_columns_crossed(r: PstRay, delta: f32) -> u32 {
    let xs = r.xs_num / delta;
    return u32(min(ceil(select(0.0, xs, xs > 0.0)), f32(frame.sizes[2])));
}

// A query's factor and term: radiance = color (max(a dot, 0) + b), `dot` the tree's
// prefix dotted with beta(theta). x: a, y: b. The sun's a = sigma_s p T(delta / sin theta)
// and b = sigma_s p tail; a spot's a = sigma_s / (D sin theta), b = tail (the last column
// exactly).
fn pst_terms(r: PstRay, row: u32, delta: f32, n: u32) -> vec2<f32> {
    let f = frame;
    let spot = {{ spot }};
    let sin_theta = max(sin(r.theta), 1e-6);
    var tail = 0.0;
    if r.d <= textureLoad(rectified, vec2<u32>(n - 1u, row), 0).x {
        let a = edge_t(f, n - 1u, n, delta, r.theta, r.s, spot);
        tail = lit_span(f, r.eye, r.dir, a, r.s, spot);
    }
    if spot {
        return vec2<f32>(f.medium[1] / (f.axis[3] * sin_theta), tail);
    }
    let sp = f.medium[1] * phase_hg(f.medium[2], -dot(f.light_dir.xyz, r.dir));
    return vec2<f32>(sp * transmittance_between(f.medium[0], 0.0, delta / sin_theta), sp * tail);
}
{%- if cookie %}

// `pst_terms` of a spot with the cookie: x = a, yzw = b, the last column with the cookie (RGB).
fn pst_terms_cookie(r: PstRay, row: u32, delta: f32, n: u32) -> vec4<f32> {
    let f = frame;
    let sin_theta = max(sin(r.theta), 1e-6);
    var tail = vec3<f32>(0.0);
    if r.d <= textureLoad(rectified, vec2<u32>(n - 1u, row), 0).x {
        let a = edge_t(f, n - 1u, n, delta, r.theta, r.s, true);
        tail = lit_span_cookie(f, cookie, r.eye, r.dir, a, r.s);
    }
    return vec4<f32>(f.medium[1] / (f.axis[3] * sin_theta), tail);
}
{%- endif %}

// The in-scattered radiance of pixel (x, y) without the tree (the fallback's body): its own
// nearest row, the lit whole columns' leaves summed in column order.
fn pst_sweep_pixel(x: u32, y: u32) -> vec3<f32> {
    let f = frame;
    let r = pst_ray(vec2<f32>(f32(x) + 0.5, f32(y) + 0.5), textureLoad(depth, vec2<u32>(x, y), 0).x);
    if r.marched {
        return r.color;
    }
    let delta = slice_params(slices[r.row]).delta;
    let row_e = pst_row_e(f, r.row);
    let n = pst_columns_crossed(r, delta);
    if n == 0u {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
{%- if cookie %}
    var sum = vec3<f32>(0.0);
    for (var h = 0u; h < LEAF_VECS; h++) {
        var p = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        for (var i = 0u; i + 1u < n; i++) {
            if r.d <= textureLoad(rectified, vec2<u32>(i, r.row), 0).x {
                p += pst_leaf(f, i, row_e, delta, h);
            }
        }
        sum[h / RANK_VECS] += dot(p, beta_at(r.theta, h % RANK_VECS));
    }
    let ab = pst_terms_cookie(r, r.row, delta, n);
    return f.light_color.xyz * (max(ab.x * sum, vec3<f32>(0.0)) + ab.yzw);
{%- else %}
    var sum = 0.0;
    for (var h = 0u; h < RANK_VECS; h++) {
        var p = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        for (var i = 0u; i + 1u < n; i++) {
            if r.d <= textureLoad(rectified, vec2<u32>(i, r.row), 0).x {
                p += pst_leaf(f, i, row_e, delta, h);
            }
        }
        sum += dot(p, beta_at(r.theta, h));
    }
    let ab = pst_terms(r, r.row, delta, n);
    return f.light_color.xyz * (max(ab.x * sum, 0.0) + ab.y);
{%- endif %}
}
{%- if !sampling.unwarp && !sampling.fallback %}

// The slice's queries: prefix end (whole columns n - 1; NONE where the sample is done:
// marched or no column), rank by d, d (then the sorted d), view angle, the terms a and b,
// and the queries in order of their prefix end.
const NONE: u32 = 0xffffffffu;
var<workgroup> q_end: array<u32, {{ sampling.slice_samples }}>;
var<workgroup> q_rank: array<u32, {{ sampling.slice_samples }}>;
var<workgroup> q_d: array<f32, {{ sampling.slice_samples }}>;
var<workgroup> q_theta: array<f32, {{ sampling.slice_samples }}>;
var<workgroup> q_a: array<f32, {{ sampling.slice_samples }}>;
var<workgroup> q_b: array<{% if cookie %}vec3<f32>{% else %}f32{% endif %}, {{ sampling.slice_samples }}>;
var<workgroup> by_end: array<u32, {{ sampling.slice_samples }}>;
// How many queries are not done (V), and how many end in each tree's columns.
var<workgroup> live: atomic<u32>;
var<workgroup> bucket: array<u32, {{ trees }}>;

// View depth at the continuous pixel position `pc` from the 2 x 2 pixels around it, 1 / z
// interpolated bilinearly (exact on a plane); -1 where they are not all within DEPTH_BREAK of
// each other (a depth break).
fn pst_footprint_depth(pc: vec2<f32>, screen: vec2<u32>) -> f32 {
    let last = vec2<f32>(screen) - vec2<f32>(1.0, 1.0);
    let q = clamp(pc - vec2<f32>(0.5, 0.5), vec2<f32>(0.0, 0.0), last);
    let i0 = vec2<u32>(floor(q));
    let i1 = min(i0 + vec2<u32>(1u, 1u), screen - vec2<u32>(1u, 1u));
    let t = q - floor(q);
    let z00 = textureLoad(depth, i0, 0).x;
    let z10 = textureLoad(depth, vec2<u32>(i1.x, i0.y), 0).x;
    let z01 = textureLoad(depth, vec2<u32>(i0.x, i1.y), 0).x;
    let z11 = textureLoad(depth, i1, 0).x;
    let lo = min(min(z00, z10), min(z01, z11));
    let hi = max(max(z00, z10), max(z01, z11));
    if !depth_close(lo, hi, DEPTH_BREAK) {
        return -1.0;
    }
    if lo == hi {
        return lo;
    }
    let w0 = (1.0 / z00) * (1.0 - t.x) + (1.0 / z10) * t.x;
    let w1 = (1.0 / z01) * (1.0 - t.x) + (1.0 / z11) * t.x;
    return 1.0 / (w0 * (1.0 - t.y) + w1 * t.y);
}

// The slice's samples pass (`sampling = epipolar`, scatter::sampling): the layout, the
// slice's line and the zeroed fallback list as every family's samples pass writes them,
// then every sample answered by the sweep. Writes `output` ((SLICE_SAMPLES + 1) x (SLICES
// + 1), rgba32float: radiance and the sample pixel's depth in w; the last column the
// slice's line, the last row the layout).
@compute @workgroup_size({{ sampling.slice_lanes }}, 1, 1)
fn pst_sweep(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let f = frame;
    let screen = vec2<u32>(f.sizes[0], f.sizes[1]);
    let width = f.sizes[2];
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
    // A sample's ray runs through its point on the slice's line (the unwarp places it
    // there), to the depth of the pixel under it: every sample of the slice then lies in
    // the slice's plane through the axis, in one rectified row (the nearest to the line's
    // farthest sample; with the rows on the slices, the slice's own plane where the map has
    // as many rows as slices). Through the pixel's centre instead, 0.5 pixel off the line, it fell
    // in a neighbouring row for 75 % of the samples at 96x54 (512 rows), whose shadow it
    // read (up to 5 % rel L1 from the pixel body on `window`).
    let far_end = lines.origin + u * (span.x + f32(SLICE_SAMPLES - 1u) * span.y);
    let row = pst_ray(far_end, 0.0).row;
    let delta = slice_params(slices[row]).delta;
    let row_e = pst_row_e(f, row);

    // 1. The samples: marched ones and rays without a column are written now. A sample's ray
    // runs through its point on the line to the depth the 2 x 2 pixels around the point give
    // there (1 / z interpolated bilinearly: exact on a plane), not to its pixel's depth, which
    // a ray half a pixel off the pixel's centre overshoots on a slanted wall (it lit closed
    // rooms through their walls); where those pixels differ by more than DEPTH_BREAK (a
    // silhouette) the sample is its pixel's ray, through the pixel's centre to its depth.
    for (var k = li; k < SLICE_SAMPLES; k += SLICE_LANES) {
        let p = slice_sample_pixel(lines, u, span, k, screen);
        let z = textureLoad(depth, p, 0).x;
        let footprint = pst_footprint_depth(lines.origin + u * (span.x + f32(k) * span.y), screen);
        var r: PstRay;
        if footprint < 0.0 {
            r = pst_ray(vec2<f32>(f32(p.x) + 0.5, f32(p.y) + 0.5), z);
        } else {
            r = pst_ray(lines.origin + u * (span.x + f32(k) * span.y), footprint);
        }
        let n = pst_columns_crossed(r, delta);
        q_end[k] = NONE;
        if r.marched || n == 0u {
            let c = round_f16(r.color);
            textureStore(output, vec2<u32>(k, s), vec4<f32>(c.x, c.y, c.z, z));
        } else {
{%- if cookie %}
            let ab = pst_terms_cookie(r, row, delta, n);
            q_b[k] = ab.yzw;
{%- else %}
            let ab = pst_terms(r, row, delta, n);
            q_b[k] = ab.y;
{%- endif %}
            q_end[k] = n - 1u;
            q_d[k] = r.d;
            q_theta[k] = r.theta;
            q_a[k] = ab.x;
            atomicAdd(&live, 1u);
        }
    }
    workgroupBarrier();
    let v = atomicLoad(&live);

    // 2. The queries in order of their prefix end and of d. Invocation c < TREES collects the
    // queries ending in tree c's columns into its part of `by_end` (after the parts of the
    // trees before it), by insertion in order of the end; invocation TREES sorts d in place
    // by insertion: along the slice d runs monotonically (up from the epipole, down from the
    // anti-epipole) but for silhouette samples, so in the direction it runs each insertion
    // shifts little, and the slots it writes lie below the samples it has still to read.
    let cw = (width + TREES - 1u) / TREES;
    if li < TREES {
        var count = 0u;
        for (var k = 0u; k < SLICE_SAMPLES; k++) {
            if q_end[k] != NONE && min(q_end[k] / cw, TREES - 1u) == li {
                count++;
            }
        }
        bucket[li] = count;
    } else if li == TREES && v > 0u {
        var first = 0u;
        while q_end[first] == NONE {
            first++;
        }
        var last = SLICE_SAMPLES - 1u;
        while q_end[last] == NONE {
            last--;
        }
        let up = q_d[first] <= q_d[last];
        var m = 0u;
        for (var k = 0u; k < SLICE_SAMPLES; k++) {
            if q_end[k] != NONE {
                let d = q_d[k];
                var j = m;
                while j > 0u && select(q_d[j - 1u] < d, q_d[j - 1u] > d, up) {
                    q_d[j] = q_d[j - 1u];
                    q_rank[j] = q_rank[j - 1u];
                    j--;
                }
                q_d[j] = d;
                q_rank[j] = k;
                m++;
            }
        }
        if !up {
            for (var j = 0u; j < v / 2u; j++) {
                let d = q_d[j];
                q_d[j] = q_d[v - 1u - j];
                q_d[v - 1u - j] = d;
                let k = q_rank[j];
                q_rank[j] = q_rank[v - 1u - j];
                q_rank[v - 1u - j] = k;
            }
        }
    }
    workgroupBarrier();
    if li < TREES {
        var start = 0u;
        for (var c = 0u; c < li; c++) {
            start += bucket[c];
        }
        var m = 0u;
        for (var k = 0u; k < SLICE_SAMPLES; k++) {
            if q_end[k] != NONE && min(q_end[k] / cw, TREES - 1u) == li {
                var j = m;
                while j > 0u && q_end[by_end[start + j - 1u]] > q_end[k] {
                    by_end[start + j] = by_end[start + j - 1u];
                    j--;
                }
                by_end[start + j] = k;
                m++;
            }
        }
    }
    // The rank of every query from the sorted list (through registers: every invocation
    // reads before any writes).
    var mine: array<u32, {{ per_lane }}>;
    for (var j = li; j < v; j += SLICE_LANES) {
        mine[j / SLICE_LANES] = q_rank[j];
    }
    workgroupBarrier();
    for (var j = li; j < v; j += SLICE_LANES) {
        q_rank[mine[j / SLICE_LANES]] = j;
    }
    workgroupBarrier();

    // 3. Every column: b = how many queries see it lit (d <= S_i, a prefix of the sorted d),
    // and its leaf where some query does.
    let base = s * width;
    for (var i = li; i < width; i += SLICE_LANES) {
        let occluder = textureLoad(rectified, vec2<u32>(i, row), 0).x;
        var lo = 0u;
        var hi = v;
        while lo < hi {
            let mid = (lo + hi) / 2u;
            if q_d[mid] <= occluder {
                lo = mid + 1u;
            } else {
                hi = mid;
            }
        }
        pst_columns[base + i] = lo;
        if lo > 0u {
            for (var h = 0u; h < LEAF_VECS; h++) {
                pst_leaves[(base + i) * LEAF_VECS + h] = pst_leaf(f, i, row_e, delta, h);
            }
        }
    }
    storageBarrier();
    workgroupBarrier();

    // 4. The sweep, split over TREES trees (invocation c < TREES owns the columns
    // [c CW, (c + 1) CW), CW = ceil(Wr / TREES)): each inserts its columns in index order
    // and answers the part of every query ending in its range that lies in its own columns
    // (a query's whole columns end at n - 1; the query belongs to the tree of that column),
    // then the trees are summed into exclusive prefixes over c (a Fenwick tree is linear in
    // its leaves) and every query adds the complete trees before its own: one step per
    // column on TREES invocations at once instead of all columns on one.
    let trees = s * (TREES + 1u) * SLICE_SAMPLES * LEAF_VECS;
    let partials = trees + TREES * SLICE_SAMPLES * LEAF_VECS;
    if li < TREES {
        let tree = trees + li * SLICE_SAMPLES * LEAF_VECS;
        for (var j = 0u; j < v * LEAF_VECS; j++) {
            pst_tree[tree + j] = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        }
        let lo = li * cw;
        let hi = select(min(lo + cw, width), width, li + 1u == TREES);
        // The first query (in order of its end) ending at or after `lo`.
        var next = 0u;
        var top = v;
        while next < top {
            let mid = (next + top) / 2u;
            if q_end[by_end[mid]] < lo {
                next = mid + 1u;
            } else {
                top = mid;
            }
        }
        for (var i = lo; i <= hi; i++) {
            while next < v && q_end[by_end[next]] == i && (i < hi || li + 1u == TREES) {
                let k = by_end[next];
                next++;
                for (var h = 0u; h < LEAF_VECS; h++) {
                    var p = vec4<f32>(0.0, 0.0, 0.0, 0.0);
                    var j = v - q_rank[k];
                    while j > 0u {
                        p += pst_tree[tree + (j - 1u) * LEAF_VECS + h];
                        j -= j & (~j + 1u);
                    }
                    pst_tree[partials + k * LEAF_VECS + h] = p;
                }
            }
            if i == hi {
                break;
            }
            let b = pst_columns[base + i];
            if b > 0u {
                for (var h = 0u; h < LEAF_VECS; h++) {
                    let leaf = pst_leaves[(base + i) * LEAF_VECS + h];
                    var j = v - b + 1u;
                    while j <= v {
                        pst_tree[tree + (j - 1u) * LEAF_VECS + h] += leaf;
                        j += j & (~j + 1u);
                    }
                }
            }
        }
    }
    storageBarrier();
    workgroupBarrier();
    // Exclusive prefix sums over the trees, entry by entry.
    for (var x = li; x < v * LEAF_VECS; x += SLICE_LANES) {
        var running = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        for (var c = 0u; c < TREES; c++) {
            let at = trees + c * SLICE_SAMPLES * LEAF_VECS + x;
            let own = pst_tree[at];
            pst_tree[at] = running;
            running += own;
        }
    }
    storageBarrier();
    workgroupBarrier();
    // Every query: its partial sum plus the complete trees before its own.
    for (var k = li; k < SLICE_SAMPLES; k += SLICE_LANES) {
        if q_end[k] != NONE {
            let tree = trees + min(q_end[k] / cw, TREES - 1u) * SLICE_SAMPLES * LEAF_VECS;
            var dotp = {% if cookie %}vec3<f32>(0.0){% else %}0.0{% endif %};
            for (var h = 0u; h < LEAF_VECS; h++) {
                var p = pst_tree[partials + k * LEAF_VECS + h];
                var j = v - q_rank[k];
                while j > 0u {
                    p += pst_tree[tree + (j - 1u) * LEAF_VECS + h];
                    j -= j & (~j + 1u);
                }
{%- if cookie %}
                dotp[h / RANK_VECS] += dot(p, beta_at(q_theta[k], h % RANK_VECS));
            }
            let c = round_f16(f.light_color.xyz * (max(q_a[k] * dotp, vec3<f32>(0.0)) + q_b[k]));
{%- else %}
                dotp += dot(p, beta_at(q_theta[k], h));
            }
            let c = round_f16(f.light_color.xyz * (max(q_a[k] * dotp, 0.0) + q_b[k]));
{%- endif %}
            let z = textureLoad(depth, slice_sample_pixel(lines, u, span, k, screen), 0).x;
            textureStore(output, vec2<u32>(k, s), vec4<f32>(c.x, c.y, c.z, z));
        }
    }
}
{%- else %}
{% include "include/sampled_entry.wgsl" %}
{%- endif %}
