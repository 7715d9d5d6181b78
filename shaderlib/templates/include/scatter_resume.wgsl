
// ---- resume (PrefilteredVariant::resume) ----
// `prefilter` stored the running means, bounds and weight sums (`weight_index`) at every
// STRIDE-th column's right edge only; the lookups count rectified columns, and each resumes
// its row's running mean from the last stored column before it over the rectified texels up
// to it, as `prefilter` filtered them: F(x) = (W_c F_c + sum_i w_i B(d_i)) / (W_c + sum_i w_i),
// the answer of a stride of 1 but for the stored columns' rounding to {{ storage }} (the
// resumed texels are not rounded). Mirrors reference/src/kernels/scatter.rs (`resume_*`).

// The rectified map (`rectify`'s, or in a projective frame the engine's rasterised one),
// whose texels after a stored column the lookups filter themselves.
@group(0) @binding(10) var rectified: texture_2d<f32>;

// Rectified texel (i, row)'s depth as `prefilter` filtered it.
fn resume_depth(i: u32, row: u32, proj: bool) -> f32 {
    var d = textureLoad(rectified, vec2<u32>(i, row), 0).x;
{%- if projective %}
    if proj {
        d = proj_stored_depth(d);
    }
{%- endif %}
    return d;
}

// `prefilter`'s weight of rectified texel i of a row (slice `sp`, slice direction `e`, region
// `region`).
fn resume_weight(sp: SliceParams, e: vec3<f32>, i: u32, region: u32, proj: bool) -> f32 {
{%- if projective %}
    if proj {
        return proj_texel_weight(frame, sp, i, region, REGIONS, STRIDE, {{ weighted }}, {{ spot }});
    }
{%- endif %}
    return texel_weight(frame, sp, e, i, {{ weighted }}, {{ spot }});
}

// The row's slice direction, which only a spot's weights use (`texel_weight`).
fn resume_e(row: u32) -> vec3<f32> {
{%- if spot %}
    return slice_e(frame, row_phi(frame, row));
{%- else %}
    return vec3<f32>(0.0, 0.0, 0.0);
{%- endif %}
}

// Where a row's lookup at rectified column x0 resumes in a region whose first column is
// `start`: (the last stored column whose right edge lies at or before x0, the first texel
// after it); with no stored column of the region there, (0, start), and nothing is read from
// the stored column (weight 0).
fn resume_from(x0: u32, start: u32) -> vec2<u32> {
    let c = (x0 + 1u) / STRIDE * STRIDE;
    return select(vec2<u32>(0u, start), vec2<u32>(c / STRIDE - 1u, c), c > start);
}

// The region's depth bounds (min, max) of row `row` up to rectified column x1, resumed from
// `origin` (`resume_from`).
fn resume_bounds(origin: vec2<u32>, start: u32, x1: u32, row: u32, proj: bool) -> vec2<f32> {
    var lohi = vec2<f32>(1e30, -1e30);
    if origin.y > start {
        lohi = bounds[bounds_index(origin.x, row)];
    }
    for (var i = origin.y; i <= x1; i++) {
        let di = resume_depth(i, row, proj);
        lohi = vec2<f32>(min(lohi.x, di), max(lohi.y, di));
    }
    return lohi;
}

// The stored weight sum at `origin`, 0 where the lookup starts at the region's first column.
fn resume_w(origin: vec2<u32>, start: u32, row: u32) -> f32 {
    var w = 0.0;
    if origin.y > start {
        w = bounds[weight_index(origin.x, row)].x;
    }
    return w;
}
{%- if cookie %}

{% include "include/texel_cookie.wgsl" %}

// With a cookie: a row's mean cookie and its per-channel parts, resumed and blended.
struct ResumedCookie {
    // The region's mean cookie Cbar up to the lookup.
    cbar: vec3<f32>,
{%- if moments %}
    // Per channel c the means of C^c times the moments (layer 0 in `a`, 1 in `b`).
    a: array<vec4<f32>, 3>,
    b: array<vec4<f32>, 3>,
{%- else %}
    // Per channel c, a(d) . F^c (the means of C^c times the bases).
    vis: vec3<f32>,
{%- endif %}
}
{%- endif %}
{%- if !moments %}

// a(d) . B(di) for the ray's depth d and a texel's di: sum over the {{ bases / 2 }} frequencies c_k of
// 2 / c_k sin(c_k (di - d)) (`coeff4` . `basis4` summed over the layers), by the turns of
// `fourier_step` from (sin, cos)(pi (di - d)).
fn step_series(x: f32) -> f32 {
    var a = vec2<f32>(sin(PI * x), cos(PI * x));
    let step = fourier_step(a);
    var sum = 0.0;
    for (var k = 1u; k <= 2u * LAYERS; k++) {
        sum += 2.0 / freq(k) * a.x;
        a = turn(a, step);
    }
    return sum;
}

// a(d) . F of row `row` (region `region`) blended linearly between rectified columns x0 and x1
// (x1 = x0 or x0 + 1, weight fx): `at_origin` is a(d) . F at the stored column `origin` the lookup resumes from.
fn resume_fourier(origin: vec2<u32>, start: u32, x0: u32, x1: u32, fx: f32, d: f32, at_origin: f32, row: u32, region: u32, proj: bool) -> f32 {
    let sp = slice_params(slices[row]);
    let e = resume_e(row);
    var w = resume_w(origin, start, row);
    var sum = w * at_origin;
    var w0 = w;
    var sum0 = sum;
    for (var i = origin.y; i <= x1; i++) {
        let wi = resume_weight(sp, e, i, region, proj);
        w += wi;
        sum += wi * step_series(resume_depth(i, row, proj) - d);
        if i == x0 {
            w0 = w;
            sum0 = sum;
        }
    }
    return mix(select(0.0, sum0 / w0, w0 > 0.0), select(0.0, sum / w, w > 0.0), fx);
}
{%- else %}

// A row's moments resumed and blended (layer 0 in `a`, layer 1 in `b` with 6 moments).
struct ResumedMoments {
    a: vec4<f32>,
    b: vec4<f32>,
}

// The moments of row `row` (region `region`, depth range `range`: `moment_z`) blended
// linearly between rectified columns x0 and x1 (x1 = x0 or x0 + 1, weight fx), resumed from
// the stored column `origin`.
fn resume_moments(origin: vec2<u32>, start: u32, x0: u32, x1: u32, fx: f32, range: vec2<f32>, row: u32, region: u32, proj: bool) -> ResumedMoments {
    let sp = slice_params(slices[row]);
    let e = resume_e(row);
    var w = resume_w(origin, start, row);
    var sa = w * filtered_load(origin.x, row, 0u);
{%- if moment_count == 6 %}
    var sb = w * filtered_load(origin.x, row, 1u);
{%- else %}
    var sb = vec4<f32>(0.0);
{%- endif %}
    var w0 = w;
    var sa0 = sa;
    var sb0 = sb;
    for (var i = origin.y; i <= x1; i++) {
        let wi = resume_weight(sp, e, i, region, proj);
        let z = moment_z(resume_depth(i, row, proj), range);
        w += wi;
        sa += wi * moment_layer(z, 0u);
{%- if moment_count == 6 %}
        sb += wi * moment_layer(z, 1u);
{%- endif %}
        if i == x0 {
            w0 = w;
            sa0 = sa;
            sb0 = sb;
        }
    }
    let k0 = select(0.0, 1.0 / w0, w0 > 0.0);
    let k1 = select(0.0, 1.0 / w, w > 0.0);
    return ResumedMoments(mix(sa0 * k0, sa * k1, fx), mix(sb0 * k0, sb * k1, fx));
}
{%- endif %}
{%- if cookie && !moments %}

// With a cookie, row `row`'s mean cookie and per channel a(d) . F^c, blended linearly between
// rectified columns x0 and x1 (weight fx): `at_origin` holds a(d) . F^c at the stored column
// `origin`; the channels' series only where `series` (the region is ambiguous for the row).
fn resume_cookie(origin: vec2<u32>, start: u32, x0: u32, x1: u32, fx: f32, d: f32, at_origin: vec3<f32>, series: bool, row: u32, region: u32, proj: bool) -> ResumedCookie {
    let sp = slice_params(slices[row]);
    let e = resume_e(row);
    var w = resume_w(origin, start, row);
    var cs = w * filtered_load(origin.x, row, CBAR).xyz;
    var vs = w * at_origin;
    var w0 = w;
    var cs0 = cs;
    var vs0 = vs;
    for (var i = origin.y; i <= x1; i++) {
        let wi = resume_weight(sp, e, i, region, proj);
        let ci = wi * texel_cookie(i, sp, e, region, proj);
        w += wi;
        cs += ci;
        if series {
            vs += ci * step_series(resume_depth(i, row, proj) - d);
        }
        if i == x0 {
            w0 = w;
            cs0 = cs;
            vs0 = vs;
        }
    }
    let k0 = select(0.0, 1.0 / w0, w0 > 0.0);
    let k1 = select(0.0, 1.0 / w, w > 0.0);
    return ResumedCookie(mix(cs0 * k0, cs * k1, fx), mix(vs0 * k0, vs * k1, fx));
}
{%- endif %}
{%- if cookie && moments %}

// With a cookie, row `row`'s mean cookie and per channel the means of C^c times the moments
// (depth range `range`: `moment_z`), blended linearly between rectified columns x0 and x1
// (weight fx), resumed from the stored column `origin`; the moments only where `series`.
fn resume_cookie(origin: vec2<u32>, start: u32, x0: u32, x1: u32, fx: f32, range: vec2<f32>, series: bool, row: u32, region: u32, proj: bool) -> ResumedCookie {
    let sp = slice_params(slices[row]);
    let e = resume_e(row);
    var w = resume_w(origin, start, row);
    var cs = w * filtered_load(origin.x, row, CBAR).xyz;
    var sa: array<vec4<f32>, 3>;
    var sb: array<vec4<f32>, 3>;
    for (var c = 0u; c < 3u; c++) {
        sa[c] = w * filtered_load(origin.x, row, c * LAYERS);
{%- if moment_count == 6 %}
        sb[c] = w * filtered_load(origin.x, row, c * LAYERS + 1u);
{%- else %}
        sb[c] = vec4<f32>(0.0);
{%- endif %}
    }
    var w0 = w;
    var cs0 = cs;
    var sa0 = sa;
    var sb0 = sb;
    for (var i = origin.y; i <= x1; i++) {
        let wi = resume_weight(sp, e, i, region, proj);
        let ci = wi * texel_cookie(i, sp, e, region, proj);
        w += wi;
        cs += ci;
        if series {
            let z = moment_z(resume_depth(i, row, proj), range);
            let m0 = moment_layer(z, 0u);
{%- if moment_count == 6 %}
            let m1 = moment_layer(z, 1u);
{%- endif %}
            for (var c = 0u; c < 3u; c++) {
                sa[c] += ci[c] * m0;
{%- if moment_count == 6 %}
                sb[c] += ci[c] * m1;
{%- endif %}
            }
        }
        if i == x0 {
            w0 = w;
            cs0 = cs;
            sa0 = sa;
            sb0 = sb;
        }
    }
    let k0 = select(0.0, 1.0 / w0, w0 > 0.0);
    let k1 = select(0.0, 1.0 / w, w > 0.0);
    var out: ResumedCookie;
    out.cbar = mix(cs0 * k0, cs * k1, fx);
    for (var c = 0u; c < 3u; c++) {
        out.a[c] = mix(sa0[c] * k0, sa[c] * k1, fx);
        out.b[c] = mix(sb0[c] * k0, sb[c] * k1, fx);
    }
    return out;
}
{%- endif %}
