{%- if moments %}
// scatter ({{ layers }} layer{% if layers > 1 %}s{% endif %} = {{ moment_count }} power moments, {{ regions }} regions, {{ visibility_name }} visibility, {{ light_name }} light, {{ rectification_name }}): per pixel, the
// prefiltered estimate of in-scattered light (Klehm et al. 2014, Sec. 3, with the moment
// basis of Peters et al. 2016: per region the lit fraction at the pixel's depth reconstructed
// from the filtered moments, `scatter::moments`) and a ray march against the standard shadow
// map for pixels near the epipole or the anti-epipole, where the rectification degenerates
// (Sec. 5, Fig. 8).
{%- else %}
// scatter ({{ layers }} layers = {{ bases }} bases, {{ regions }} regions, {{ visibility_name }} visibility, {{ light_name }} light, {{ rectification_name }}): per pixel, the
// prefiltered estimate of in-scattered light (Klehm et al. 2014, Sec. 3, Listing 4: one dot
// product of the pixel's Fourier coefficients with the filtered bases per region) and a ray
// march against the standard shadow map for pixels near the epipole or the anti-epipole,
// where the rectification degenerates (Sec. 5, Fig. 8).
{%- endif %}
//
// Weighted visibility: L = sum_j U_j Vbar_j over the regions the ray crosses, U_j the
// pixel's own unshadowed integral over its part of the ray inside region j (closed form
// for the sun, Gauss-Legendre for a spot) and Vbar_j the region's prefiltered visibility
// ({% if moments %}from its moments at the ray's depth in the region's moment coordinate, `moment_z`{% else %}clamp(0.5 + a(d) . F_j, 0, 1){% endif %}). Average visibility combines the regions the same way; it
// differs in the prefilter, which weights texels by their length along the reference ray
// instead of its transmittance (with one region: the paper's L_unshadowed * Vbar). Weighting
// the regions by length instead (L_unshadowed * sum_j len_j Vbar_j / s) was 51 % off on
// foliage/epipole_on_screen at every region count (issue 12): along a ray towards the sun
// the shadowed part lies near the eye, where the transmittance is high.
// Where the ray's depth d is at most the least depth of region j's texels that the fetch
// reads (prefilter's `bounds`), the region is wholly lit and Vbar_j = 1 exactly; above the
// greatest, wholly shadowed and Vbar_j = 0: the Fourier series rings only where the answer
// is ambiguous, and no light leaks where no light ray reaches.{% if moments %} (The moment reconstruction
// is also exact outside the depths' range up to the moment bias; the bounds make it exact
// and skip the solve.){% endif %}
{%- if cookie %}
//
// Cookie (scatter_frame::cookie; prefilter folds it into each texel's weight): per channel c
// the region's lit share S_j^c = sum w_i C_i^c H(d_i - d) / sum w_i, with the region's mean
// cookie Cbar_j^c (filtered layer {{ cbar_layer }}) in place of 1: {% if moments %}Cbar^c times the lit fraction of the
// moments divided by Cbar^c (the moments of the cookie-weighted depths){% else %}clamp(0.5 Cbar^c + a(d) . F_j^c, 0, Cbar^c){% endif %};
// Cbar^c where the region is wholly lit, 0 where wholly shadowed. The region contributes
// U_j^c S_j^c / Cbar_j^c, U_j^c the pixel's own unshadowed integral with the cookie over
// its part of the ray (`spot_segment_cookie`): the ratio is the region's cookie-weighted lit
// fraction, so a wholly lit region gives the pixel's exact cookie integral. (U_j S_j^c, the
// cookie averaged along the reference ray instead of the pixel's, was 1.6-4.8 % rel L1 off
// the truth on spot_grate, 0.06-1.9 % without the cookie.) The epipole march carries the
// cookie per sample.
{%- endif %}
//
// Bindings (group 0):
// | binding | name             | type                                     | access             |
// |---------|------------------|------------------------------------------|--------------------|
// | 0       | frame            | var<uniform> Frame (432 bytes)           | uniform            |
// | 1       | slices           | var<storage, read> array<vec4<f32>>      | read               |
// | 2       | depth            | texture_2d<f32> (r32float, view depth)   | textureLoad        |
// | 3       | shadow_map       | texture_2d<f32> (r32float)               | textureLoad        |
// | 4       | filtered         | var<storage, read> array<{{ filtered_word }}> (prefilter's) | read |
// | 5       | output           | texture_storage_2d<rgba16float, write>   | textureStore       |
// | 6       | bounds           | var<storage, read> array<vec2<f32>> (prefilter's) | read      |
{%- if cookie %}
// | 12      | cookie           | texture_2d<f32> (rgba, linear RGB)       | textureLoad        |
{%- endif %}
// filtered: Wc x Hr texels of {{ filtered_layers }} {{ storage }} layers each (below), Wr x Hr = the rectified
// size (frame.sizes.zw), Wc = Wr / {{ stride }} the stored columns, filtered by hand: linearly along each of the pixel's two rows, each row read at its own
// column for the ray (clamp-to-edge in u; in v wrapping round when the slices do,
// frame.anti_epipole.w > 0.5, else clamp-to-edge), and the rows' estimates blended. Texel
// loads instead of a filtering sampler measured 1.9x faster for the whole pass on lavapipe
// (1280x720, sphere) and the weights are exact floats; a storage buffer in place of the
// texture array that followed is faster still (below).
//
{%- if stride > 1 %}
// Coarse filtered columns (filtered_stride = {{ stride }}): prefilter stored every {{ stride }}-th column's
// running means, so the map is read as one of Wc columns, each {{ stride }} rectified columns (an
// angle or a distance of {{ stride }} delta) wide; the linear lookup between the stored right edges
// and the regions (starting on stored columns) are unchanged in those units.
//
{%- endif %}
// Dispatch: (ceil(W / 8), ceil(H / 8), 1) workgroups of (8, 8, 1), W x H = screen size
// (frame.sizes.xy); invocation id x = pixel column, y = pixel row.
//
{%- if projective %}
// Projective variant: in a projective frame (frame.proj.x = 1) the pixel's rectified
// coordinates come from the projective map (row k = qy / qx, depth m = qz / qx, column from
// the invariant G of its surface point); neither epipole is on screen then, so nothing is
// marched.
{%- endif %}
//
// Mirrors reference/src/kernels/scatter.rs

#import scatter::model::{ {%- if !moments %}PI, {% endif %}phase_hg, transmittance_between, transmittance_integral}
#import scatter::epipolar::{Frame, in_epipole_disc, epipole_march, normalised_depth, pixel_dir, ray_column, ray_row_coord, ray_t, row_index, slice_params, spot_segment}
{%- if moments %}
#import scatter::prefiltered::{region_start{% if resume %}, texel_weight{% endif %}}
#import scatter::moments::{lit_moments{{ moment_count }}, moment_z{% if resume %}, moment_layer{% endif %}}
{%- else %}
#import scatter::prefiltered::{coeff4, fourier_step, region_start, turn{% if resume %}, freq, texel_weight{% endif %}}
{%- endif %}
{%- if resume %}
#import scatter::epipolar::{SliceParams, row_phi, slice_e}
{%- if projective %}
#import scatter::projective::proj_stored_depth
#import scatter::prefiltered_projective::{proj_texel_weight{% if cookie %}, proj_region_g{% endif %}}
{%- endif %}
{%- endif %}
{%- if projective %}
#import scatter::projective::{proj_boundary, proj_ray_depth, proj_reach}
#import scatter::prefiltered_projective::proj_column
{%- endif %}
{%- if cookie %}
#import scatter::cookie::{epipole_march_cookie, spot_segment_cookie{% if resume %}, frame_cookie{% endif %}}
{%- endif %}
{%- if !sampling.imports.is_empty() %}
{{ sampling.imports }}
{%- endif %}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> slices: array<vec4<f32>>;
@group(0) @binding(2) var depth: texture_2d<f32>;
@group(0) @binding(3) var shadow_map: texture_2d<f32>;
@group(0) @binding(4) var<storage, read> filtered: array<{{ filtered_word }}>;
@group(0) @binding(5) var output: texture_storage_2d<{{ sampling.output_format }}, write>;
@group(0) @binding(6) var<storage, read> bounds: array<vec2<f32>>;
{%- if cookie %}
// The spot's cookie (scatter_frame::cookie): the epipole march carries it per sample.
@group(0) @binding(12) var cookie: texture_2d<f32>;
{%- endif %}
{% include "include/sampled_bindings.wgsl" %}
{%- include "include/prefiltered_buffers.wgsl" %}

// Independent prefix regions per rectified row.
const REGIONS: u32 = {{ regions }}u;
// Rectified columns per column of the lookups below: STRIDE when they read the coarse map as
// it is, 1 when they resume the running means between its stored columns (`resume`).
const LOOKUP: u32 = {% if resume %}1u{% else %}STRIDE{% endif %};
{%- if resume %}
{% include "include/scatter_resume.wgsl" %}
{%- endif %}
{%- if !moments %}
// rgba layers of `filtered` (bases / 4){% if cookie %} per colour channel{% endif %}.
const LAYERS: u32 = {{ layers }}u;
{%- endif %}
{%- if cookie %}
{%- if moments %}
// rgba layers of one colour channel's moments.
const LAYERS: u32 = {{ layers }}u;
{%- endif %}
// The layer of the region's mean cookie.
const CBAR: u32 = {{ cbar_layer }}u;
{%- endif %}

// The in-scattered radiance of pixel (x, y) (the sampling entry point below calls it).
fn scatter_pixel(x: u32, y: u32) -> vec3<f32> {
    let f = frame;
    let spot = {{ spot }};
    let eye = f.eye.xyz;
    let dir = pixel_dir(f, x, y);
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s = min(max(textureLoad(depth, vec2<u32>(x, y), 0).x, 0.0), f.theta.z) / max(dot(dir, f.cam_forward.xyz), 1e-6);
    let color = f.light_color.xyz;

    // Near the epipole and the anti-epipole the rectification degenerates: march instead.
    if in_epipole_disc(f, vec2<f32>(f32(x) + 0.5, f32(y) + 0.5)) {
{%- if cookie %}
        let l = epipole_march_cookie(frame, shadow_map, cookie, eye, dir, s) * color;
{%- else %}
        let l = epipole_march(frame, shadow_map, eye, dir, s, spot) * color;
{%- endif %}
        return l;
    }

    // Rectified coordinates of the surface point.
    let axis = f.axis.xyz;
    let rows = f.sizes[3];
    // The lookups' columns (Wr / LOOKUP: the stored ones, or with `resume` the rectified
    // ones), which the lookups below count in.
    let width = f.sizes[2] / LOOKUP;
    let regions = REGIONS;
    let wrap = f.anti_epipole[3] > 0.5;
    var yc: f32;
    var d: f32;
    // Projective: the ray's end column, the same in every row.
    var xs = 0.0;
    // Epipolar: the ray's end in column units times the row's column spacing (v for the
    // sun, psi for a spot; a row's end column is reach / delta), and its view angle.
    var reach = 0.0;
    var theta = 0.0;
{%- if projective %}
    // Projective: the ray's e1 component and depth m.
    var qd = 1.0;
    var m = 0.0;
    let proj = f.proj[0] > 0.5;
    if proj {
        let q = vec3<f32>(dot(dir, f.e1_.xyz), dot(dir, f.e2_.xyz), dot(dir, axis));
        qd = max(q.x, 1e-6);
        let k = q.y / qd;
        m = q.z / qd;
        yc = clamp((k + f.proj[1]) / (2.0 * f.proj[1]) * f32(rows), 0.0, f32(rows));
        d = proj_ray_depth(f, m);
        let qs = max(s * qd, 1e-6);
        var g = 1.0 / qs;
        if spot {
            g = (f.axis[3] - s * q.z) / qs;
        }
        // (The coarse map's column times the stored columns' width in lookup columns.)
        xs = f32(STRIDE / LOOKUP) * proj_column(f, g, regions, f.sizes[2] / STRIDE, spot);
    } else {
{%- else %}
    {
{%- endif %}
        // The view angle from the light axis as atan2(|dir x axis|, dir . axis): acos of the
        // dot product resolves angles near the axis only to sqrt(2 * 6e-8) = 3.5e-4 in f32.
        theta = atan2(length(cross(dir, axis)), dot(dir, axis));
        yc = ray_row_coord(f, dir);
        d = normalised_depth(theta, f.theta[0], f.theta[1]);
        reach = ray_column(f, eye, dir, s, theta, spot);
    }

    // The two rectified rows the pixel lies between (the second only with a non-zero weight)
    // and the weight of the second. Each row is read at its own column for the ray's points:
    // `slice_fit` gives every slice its own column spacing, and reading both rows at one
    // interpolated spacing read a neighbouring slice's light rays beyond the ray's end (light
    // in closed rooms, 1.1e-2 of the lit maximum, issue 12). The filtering is linear, so for
    // rows of equal spacing this is the bilinear fetch it replaces.
    let yb = yc - 0.5;
    let fy = yb - floor(yb);
    let row0 = row_index(floor(yb), rows, wrap);
    let row1 = select(row0, row_index(floor(yb) + 1.0, rows, wrap), yb > floor(yb));
    let w1 = select(0.0, fy, row1 != row0);

    let cos_theta_l = -dot(f.light_dir.xyz, dir);
    // Every region gets the full spot quadrature: its weight must be as accurate as the
    // whole ray's (dividing the panels among the regions cost 2.5 % rel L1 on a thick-fog
    // grazing spot, spot_grate/grazing/thick).
    let panels = max(f.sizes2_[2] / 4u, 1u);
{%- if moments %}
    // (The ray's depth in the moments' coordinate depends on the region's depth range: per
    // region and row below.)
{%- else %}
    // The ray's Fourier coefficients depend on its depth only: once per pixel, not per
    // region, their angles c_k d by angle addition from pi d (two transcendentals per pixel).
    var coeffs: array<vec4<f32>, LAYERS>;
    var angle = vec2<f32>(sin(PI * d), cos(PI * d));
    let step = fourier_step(angle);
    for (var layer = 0u; layer < LAYERS; layer++) {
        let second = turn(angle, step);
        coeffs[layer] = coeff4(angle, second, layer);
        angle = turn(second, step);
    }
{%- endif %}
    // The sun's scattering coefficient times phase, the same for every region.
    let sun_scatter = f.medium[1] * phase_hg(f.medium[2], cos_theta_l);

    // Regions: every region before the surface's, whole, and the surface's up to x_s. Each
    // is weighted by this pixel's own unshadowed integral over its part of the ray [a, b];
    // each row places a and b with its own spacing, so the two rows' regions are summed
    // apart (total0, total1) in one loop, each row's ending at its own last region. One
    // loop and no per-region arrays: lavapipe keeps dynamically indexed private arrays in
    // memory (a loop per row measured 1.2-1.7x the whole pass).
    var delta0 = 1.0;
    var delta1 = 1.0;
    var xs0 = xs;
    var xs1 = xs;
{%- if projective %}
    if !proj {
{%- else %}
    {
{%- endif %}
        // A lookup column spans LOOKUP rectified columns.
        delta0 = f32(LOOKUP) * slice_params(slices[row0]).delta;
        delta1 = f32(LOOKUP) * slice_params(slices[row1]).delta;
        xs0 = reach / delta0;
        xs1 = reach / delta1;
    }
    let last0 = u32(min(max(xs0, 0.0), f32(width) - 1.0));
    let last1 = u32(min(max(xs1, 0.0), f32(width) - 1.0));
    var total0 = {% if cookie %}vec3<f32>(0.0){% else %}0.0{% endif %};
    var total1 = {% if cookie %}vec3<f32>(0.0){% else %}0.0{% endif %};
    var done0 = false;
    var done1 = false;
    // The furthest stored edge a row's bounds lookup may read in the ray's last region: the
    // last one at most one rectified column past the ray's end (at a stride of 1 never before
    // the end, so nothing changes). A coarse column past the end holds light rays beyond the
    // ray's surface: bounds read through to its edge made wholly shadowed regions ambiguous
    // and lit closed rooms (window, 2.2e-2 of the lit maximum at filtered_stride 4, random
    // poses). The means still read the partial column (stopping them too cost 0.06 points
    // on the 24 poses' mean at stride 4).
    let cap0 = floor((floor(xs0 * f32(LOOKUP)) + 1.0) / f32(LOOKUP));
    let cap1 = floor((floor(xs1 * f32(LOOKUP)) + 1.0) / f32(LOOKUP));
    // The previous region's lit fraction per row: a last region whose first stored edge lies
    // past `cap` has no column the ray reaches through, and its part of the ray (under one
    // coarse column) takes the fraction of the region before it.
    var prev0 = {% if cookie %}vec3<f32>(0.0){% else %}0.0{% endif %};
    var prev1 = {% if cookie %}vec3<f32>(0.0){% else %}0.0{% endif %};
{%- if resume %}
    let proj_frame = {% if projective %}proj{% else %}false{% endif %};
{%- endif %}
    for (var r = 0u; r < regions; r++) {
        // The region's first and next region's first lookup column (on stored columns).
        let b0 = f32(STRIDE / LOOKUP * region_start(r, regions, f.sizes[2] / STRIDE, spot));
        let b1 = f32(STRIDE / LOOKUP * region_start(r + 1u, regions, f.sizes[2] / STRIDE, spot));
        let is_last0 = last0 < u32(b1) || r + 1u == regions;
        let is_last1 = last1 < u32(b1) || r + 1u == regions;
        let pos0 = select(b1 - 0.5, clamp(xs0 - 0.5, b0 + 0.5, b1 - 0.5), is_last0);
        let pos1 = select(b1 - 0.5, clamp(xs1 - 0.5, b0 + 0.5, b1 - 0.5), is_last1);
        // The bounds' lookup, stopped at `cap`.
        let bb0 = select(b1 - 0.5, clamp(min(xs0, cap0) - 0.5, b0 + 0.5, b1 - 0.5), is_last0) - 0.5;
        let bb1 = select(b1 - 0.5, clamp(min(xs1, cap1) - 0.5, b0 + 0.5, b1 - 0.5), is_last1) - 0.5;
        let before0 = is_last0 && cap0 <= b0 && r > 0u;
        let before1 = is_last1 && cap1 <= b0 && r > 0u;
        var a0: f32;
        var e0: f32;
        var a1: f32;
        var e1: f32;
{%- if projective %}
        if proj {
            a0 = 0.0;
            if r > 0u {
                a0 = min(proj_reach(f, proj_boundary(f, r), m, spot, s * qd) / qd, s);
            }
            e0 = select(min(proj_reach(f, proj_boundary(f, r + 1u), m, spot, s * qd) / qd, s), s, is_last0);
            a1 = a0;
            e1 = e0;
        } else {
            a0 = ray_t(f, b0, delta0, theta, s, spot);
            e0 = select(ray_t(f, b1, delta0, theta, s, spot), s, is_last0);
            a1 = ray_t(f, b0, delta1, theta, s, spot);
            e1 = select(ray_t(f, b1, delta1, theta, s, spot), s, is_last1);
        }
{%- else %}
        a0 = ray_t(f, b0, delta0, theta, s, spot);
        e0 = select(ray_t(f, b1, delta0, theta, s, spot), s, is_last0);
        a1 = ray_t(f, b0, delta1, theta, s, spot);
        e1 = select(ray_t(f, b1, delta1, theta, s, spot), s, is_last1);
{%- endif %}
{%- if cookie %}
        // The pixel's own unshadowed integral with the cookie over its part of the ray (RGB;
        // one quadrature panel per cookie texel crossed), for the rows not yet done.
        var weight0 = vec3<f32>(0.0);
        var weight1 = vec3<f32>(0.0);
        if !done0 {
            weight0 = spot_segment_cookie(f, cookie, eye, dir, a0, e0, panels);
        }
        if !done1 {
            weight1 = spot_segment_cookie(f, cookie, eye, dir, a1, e1, panels);
        }
{%- else %}
        var weight0: f32;
        var weight1: f32;
        if spot {
            weight0 = spot_segment(f, eye, dir, a0, e0, panels);
            weight1 = spot_segment(f, eye, dir, a1, e1, panels);
        } else {
            weight0 = sun_scatter * transmittance_between(f.medium[0], a0, e0);
            weight1 = sun_scatter * transmittance_between(f.medium[0], a1, e1);
        }
{%- endif %}
        // Per row, the (up to) two texels the linear fetch reads with a non-zero weight:
        // columns x0 <= x1 of the region (pos lies inside it).
        let xb0 = pos0 - 0.5;
        let fx0 = xb0 - floor(xb0);
        let x00 = u32(clamp(floor(xb0), 0.0, f32(width) - 1.0));
        let x01 = select(x00, min(x00 + 1u, width - 1u), xb0 > floor(xb0));
        let xb1 = pos1 - 0.5;
        let fx1 = xb1 - floor(xb1);
        let x10 = u32(clamp(floor(xb1), 0.0, f32(width) - 1.0));
        let x11 = select(x10, min(x10 + 1u, width - 1u), xb1 > floor(xb1));
        // Their depth bounds. A region's prefix bounds only widen along the row, so column
        // x1's cover column x0's: one load per row, at x1 of the lookup stopped at `cap`.
        let xb00 = u32(clamp(floor(bb0), 0.0, f32(width) - 1.0));
        let xb10 = u32(clamp(floor(bb1), 0.0, f32(width) - 1.0));
{%- if resume %}
        // Resumed from each row's last stored column before x0 + 1 in the region (at a
        // lookup of one rectified column the bounds' column is x1).
        let from0 = resume_from(x00, u32(b0));
        let from1 = resume_from(x10, u32(b0));
        let lohi0 = resume_bounds(from0, u32(b0), x01, row0, proj_frame);
        let lohi1 = resume_bounds(from1, u32(b0), x11, row1, proj_frame);
{%- else %}
        let lohi0 = bounds[bounds_index(select(xb00, min(xb00 + 1u, width - 1u), bb0 > floor(bb0)), row0)];
        let lohi1 = bounds[bounds_index(select(xb10, min(xb10 + 1u, width - 1u), bb1 > floor(bb1)), row1)];
{%- endif %}
{%- if cookie %}
{%- if resume %}
        let amb0 = d > lohi0.x && d <= lohi0.y;
        let amb1 = d > lohi1.x && d <= lohi1.y;
{%- if moments %}
        // The region's whole depth range per row (`moment_z`), the mean cookie and the
        // channels' moments of the cookie-weighted depths, resumed; the lit share per channel
        // from the moments over Cbar.
        let range0 = bounds[bounds_index(u32(b1) * LOOKUP / STRIDE - 1u, row0)];
        let range1 = bounds[bounds_index(u32(b1) * LOOKUP / STRIDE - 1u, row1)];
        let zf0 = moment_z(d, range0);
        let zf1 = moment_z(d, range1);
        let rc0 = resume_cookie(from0, u32(b0), x00, x01, fx0, range0, amb0, row0, r, proj_frame);
        let rc1 = resume_cookie(from1, u32(b0), x10, x11, fx1, range1, amb1, row1, r, proj_frame);
        let cbar0 = rc0.cbar;
        let cbar1 = rc1.cbar;
        var vis0 = 0.5 * cbar0;
        var vis1 = 0.5 * cbar1;
        for (var c = 0u; c < 3u; c++) {
            if amb0 && cbar0[c] > 0.0 {
{%- if moment_count == 6 %}
                vis0[c] = cbar0[c] * lit_moments6(rc0.a[c] / cbar0[c], (rc0.b[c] / cbar0[c]).xy, zf0);
{%- else %}
                vis0[c] = cbar0[c] * lit_moments4(rc0.a[c] / cbar0[c], zf0);
{%- endif %}
            }
            if amb1 && cbar1[c] > 0.0 {
{%- if moment_count == 6 %}
                vis1[c] = cbar1[c] * lit_moments6(rc1.a[c] / cbar1[c], (rc1.b[c] / cbar1[c]).xy, zf1);
{%- else %}
                vis1[c] = cbar1[c] * lit_moments4(rc1.a[c] / cbar1[c], zf1);
{%- endif %}
            }
        }
{%- else %}
        // Per channel a(d) . F^c at each row's stored column (where the row is ambiguous),
        // then the mean cookie and the channels' series resumed up to x0 and x1.
        var at0 = vec3<f32>(0.0);
        var at1 = vec3<f32>(0.0);
        if amb0 || amb1 {
            for (var layer = 0u; layer < LAYERS; layer++) {
                let coeff = coeffs[layer];
                for (var c = 0u; c < 3u; c++) {
                    let texel0 = filtered_load(from0.x, row0, c * LAYERS + layer);
                    let texel1 = filtered_load(from1.x, row1, c * LAYERS + layer);
                    for (var k = 0u; k < 4u; k++) {
                        at0[c] += coeff[k] * (texel0[k] * 2.0 - 1.0);
                        at1[c] += coeff[k] * (texel1[k] * 2.0 - 1.0);
                    }
                }
            }
        }
        let rc0 = resume_cookie(from0, u32(b0), x00, x01, fx0, d, at0, amb0, row0, r, proj_frame);
        let rc1 = resume_cookie(from1, u32(b0), x10, x11, fx1, d, at1, amb1, row1, r, proj_frame);
        let cbar0 = rc0.cbar;
        let cbar1 = rc1.cbar;
        var vis0 = 0.5 * cbar0 + rc0.vis;
        var vis1 = 0.5 * cbar1 + rc1.vis;
{%- endif %}
{%- else %}
        // The region's mean cookie up to the ray's end, per row: the channel's lit share
        // lies in [0, Cbar].
        let cbar0 = mix(filtered_load(x00, row0, CBAR), filtered_load(x01, row0, CBAR), fx0).xyz;
        let cbar1 = mix(filtered_load(x10, row1, CBAR), filtered_load(x11, row1, CBAR), fx1).xyz;
        var vis0 = 0.5 * cbar0;
        var vis1 = 0.5 * cbar1;
{%- if moments %}
        // The ray's depth in each row's moment coordinate: the region's whole depth range is
        // its bounds at its last stored column (`moment_z`).
        let zf0 = moment_z(d, bounds[bounds_index(u32(b1) * LOOKUP / STRIDE - 1u, row0)]);
        let zf1 = moment_z(d, bounds[bounds_index(u32(b1) * LOOKUP / STRIDE - 1u, row1)]);
        // Per channel the moments of the cookie-weighted depths: the stored ones over Cbar.
        for (var c = 0u; c < 3u; c++) {
            if d > lohi0.x && d <= lohi0.y && cbar0[c] > 0.0 {
                let m0 = mix(filtered_load(x00, row0, c * LAYERS), filtered_load(x01, row0, c * LAYERS), fx0) / cbar0[c];
{%- if moment_count == 6 %}
                let m1 = mix(filtered_load(x00, row0, c * LAYERS + 1u), filtered_load(x01, row0, c * LAYERS + 1u), fx0) / cbar0[c];
                vis0[c] = cbar0[c] * lit_moments6(m0, m1.xy, zf0);
{%- else %}
                vis0[c] = cbar0[c] * lit_moments4(m0, zf0);
{%- endif %}
            }
            if d > lohi1.x && d <= lohi1.y && cbar1[c] > 0.0 {
                let m0 = mix(filtered_load(x10, row1, c * LAYERS), filtered_load(x11, row1, c * LAYERS), fx1) / cbar1[c];
{%- if moment_count == 6 %}
                let m1 = mix(filtered_load(x10, row1, c * LAYERS + 1u), filtered_load(x11, row1, c * LAYERS + 1u), fx1) / cbar1[c];
                vis1[c] = cbar1[c] * lit_moments6(m0, m1.xy, zf1);
{%- else %}
                vis1[c] = cbar1[c] * lit_moments4(m0, zf1);
{%- endif %}
            }
        }
{%- else %}
        if (d > lohi0.x && d <= lohi0.y) || (d > lohi1.x && d <= lohi1.y) {
            for (var layer = 0u; layer < LAYERS; layer++) {
                let coeff = coeffs[layer];
                for (var c = 0u; c < 3u; c++) {
                    let texel0 = mix(filtered_load(x00, row0, c * LAYERS + layer), filtered_load(x01, row0, c * LAYERS + layer), fx0);
                    let texel1 = mix(filtered_load(x10, row1, c * LAYERS + layer), filtered_load(x11, row1, c * LAYERS + layer), fx1);
                    for (var k = 0u; k < 4u; k++) {
                        vis0[c] += coeff[k] * (texel0[k] * 2.0 - 1.0);
                        vis1[c] += coeff[k] * (texel1[k] * 2.0 - 1.0);
                    }
                }
            }
        }
{%- endif %}
{%- endif %}
        // Outside the row's depth range the region is exactly lit (the mean cookie) or
        // shadowed.
        vis0 = select(select(vis0, vec3<f32>(0.0), d > lohi0.y), cbar0, d <= lohi0.x);
        vis1 = select(select(vis1, vec3<f32>(0.0), d > lohi1.y), cbar1, d <= lohi1.x);
        // The region's cookie-weighted lit fraction (the lit share over the mean cookie)
        // times the pixel's own integral with the cookie: exact where the region is wholly
        // lit or shadowed, whatever the cookie does along the ray.
        var frac0 = select(vec3<f32>(0.0), clamp(vis0, vec3<f32>(0.0), cbar0) / cbar0, cbar0 > vec3<f32>(0.0));
        var frac1 = select(vec3<f32>(0.0), clamp(vis1, vec3<f32>(0.0), cbar1) / cbar1, cbar1 > vec3<f32>(0.0));
        if before0 {
            frac0 = prev0;
        }
        if before1 {
            frac1 = prev1;
        }
        prev0 = frac0;
        prev1 = frac1;
        if !done0 {
            total0 += weight0 * frac0;
        }
        if !done1 {
            total1 += weight1 * frac1;
        }
{%- else %}
        var vis0 = 0.5;
        var vis1 = 0.5;
{%- if moments %}
        // The region's moments, filtered linearly along each row (a mix of moments is the
        // moments of the mixed depths: still a valid moment vector).
        if d > lohi0.x && d <= lohi0.y {
            // The ray's depth in the row's moment coordinate: the region's whole depth range
            // is its bounds at its last stored column (`moment_z`).
            let range0 = bounds[bounds_index(u32(b1) * LOOKUP / STRIDE - 1u, row0)];
            let zf0 = moment_z(d, range0);
{%- if resume %}
            let mm0 = resume_moments(from0, u32(b0), x00, x01, fx0, range0, row0, r, proj_frame);
            let m0 = mm0.a;
            let m1 = mm0.b;
{%- else %}
            let m0 = mix(filtered_load(x00, row0, 0), filtered_load(x01, row0, 0), fx0);
{%- if moment_count == 6 %}
            let m1 = mix(filtered_load(x00, row0, 1), filtered_load(x01, row0, 1), fx0);
{%- endif %}
{%- endif %}
{%- if moment_count == 6 %}
            vis0 = lit_moments6(m0, m1.xy, zf0);
{%- else %}
            vis0 = lit_moments4(m0, zf0);
{%- endif %}
        }
        if d > lohi1.x && d <= lohi1.y {
            let range1 = bounds[bounds_index(u32(b1) * LOOKUP / STRIDE - 1u, row1)];
            let zf1 = moment_z(d, range1);
{%- if resume %}
            let mm1 = resume_moments(from1, u32(b0), x10, x11, fx1, range1, row1, r, proj_frame);
            let m0 = mm1.a;
            let m1 = mm1.b;
{%- else %}
            let m0 = mix(filtered_load(x10, row1, 0), filtered_load(x11, row1, 0), fx1);
{%- if moment_count == 6 %}
            let m1 = mix(filtered_load(x10, row1, 1), filtered_load(x11, row1, 1), fx1);
{%- endif %}
{%- endif %}
{%- if moment_count == 6 %}
            vis1 = lit_moments6(m0, m1.xy, zf1);
{%- else %}
            vis1 = lit_moments4(m0, zf1);
{%- endif %}
        }
{%- else %}
        if (d > lohi0.x && d <= lohi0.y) || (d > lohi1.x && d <= lohi1.y) {
{%- if resume %}
            // a(d) . F at each row's stored column, then resumed up to x0 and x1.
            var dot0 = 0.0;
            var dot1 = 0.0;
            for (var layer = 0u; layer < LAYERS; layer++) {
                let coeff = coeffs[layer];
                let texel0 = filtered_load(from0.x, row0, layer);
                let texel1 = filtered_load(from1.x, row1, layer);
                for (var k = 0u; k < 4u; k++) {
                    dot0 += coeff[k] * (texel0[k] * 2.0 - 1.0);
                    dot1 += coeff[k] * (texel1[k] * 2.0 - 1.0);
                }
            }
            vis0 += resume_fourier(from0, u32(b0), x00, x01, fx0, d, dot0, row0, r, proj_frame);
            vis1 += resume_fourier(from1, u32(b0), x10, x11, fx1, d, dot1, row1, r, proj_frame);
{%- else %}
            for (var layer = 0u; layer < LAYERS; layer++) {
                let coeff = coeffs[layer];
                let texel0 = mix(filtered_load(x00, row0, layer), filtered_load(x01, row0, layer), fx0);
                let texel1 = mix(filtered_load(x10, row1, layer), filtered_load(x11, row1, layer), fx1);
                for (var k = 0u; k < 4u; k++) {
                    vis0 += coeff[k] * (texel0[k] * 2.0 - 1.0);
                    vis1 += coeff[k] * (texel1[k] * 2.0 - 1.0);
                }
            }
{%- endif %}
        }
{%- endif %}
        // Outside the row's depth range the region is exactly lit or shadowed.
        vis0 = select(select(vis0, 0.0, d > lohi0.y), 1.0, d <= lohi0.x);
        vis1 = select(select(vis1, 0.0, d > lohi1.y), 1.0, d <= lohi1.x);
        vis0 = select(clamp(vis0, 0.0, 1.0), prev0, before0);
        vis1 = select(clamp(vis1, 0.0, 1.0), prev1, before1);
        prev0 = vis0;
        prev1 = vis1;
        if !done0 {
            total0 += weight0 * vis0;
        }
        if !done1 {
            total1 += weight1 * vis1;
        }
{%- endif %}
        done0 = done0 || is_last0;
        done1 = done1 || is_last1;
        if done0 && done1 {
            break;
        }
    }
    let total = (1.0 - w1) * total0 + w1 * total1;
    let l = total;
    let c = color * l;
    return c;
}
{% include "include/sampled_entry.wgsl" %}
