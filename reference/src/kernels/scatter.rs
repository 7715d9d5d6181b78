//! CPU mirror of `shaderlib/templates/scatter.wgsl`: per pixel, the prefiltered estimate
//! (Klehm et al. 2014 Listing 4) and a ray march against the standard shadow map for pixels
//! near the epipole or the anti-epipole (Sec. 5, Fig. 8).
//!
//! Weighted visibility: `L = sum_j U_j Vbar_j` over the regions the ray crosses, `U_j` the
//! pixel's own unshadowed integral over its part of the ray inside region `j` (closed form
//! for the sun, Gauss-Legendre for a spot) and `Vbar_j = clamp(0.5 + a(d) . F_j, 0, 1)` the
//! region's prefiltered visibility. With one region this is the paper's `L_unshadowed * Vbar`;
//! with more, each region's visibility is weighted by the true integrand instead of the
//! reference ray's. Average visibility combines the regions the same way and differs in the
//! prefilter's texel weights (length along the reference ray instead of its transmittance);
//! with one region it is the paper's `L_unshadowed * Vbar`. Weighting regions by length
//! (`L_unshadowed * sum_j len_j Vbar_j / s`) was 51 % off on foliage/epipole_on_screen at
//! every region count: along a ray towards the sun the shadowed part lies near the eye.
//! Where the ray's depth `d` is at most the least depth of the texels the fetch reads
//! (`prefilter`'s bounds), `Vbar_j = 1` exactly; above the greatest, `Vbar_j = 0`.
//!
//! With a cookie (see the WGSL comment) each channel's lit share is reconstructed from its
//! own layers with the region's mean cookie `Cbar^c` in place of 1, and the epipole march
//! carries the cookie per sample.

use super::common_cookie::{epipole_march_cookie, spot_segment_cookie};
use super::common_epipolar::{
    epipole_march, in_epipole_disc, normalised_depth, pixel_dir, ray_column, ray_row_coord, ray_t,
    row_index, row_phi, slice_e, spot_segment,
};
use super::common_model::{PI, clamp, max, max_u, min, phase_hg, transmittance_between};
use super::common_moments::{lit_moments4, lit_moments6, moment_layer, moment_z};
use super::common_prefiltered::{coeff4, fourier_step, freq, region_start, texel_weight, turn};
use super::common_prefiltered_projective::{proj_column, proj_texel_weight};
use super::common_projective::{proj_boundary, proj_ray_depth, proj_reach, proj_stored_depth};
use super::common_sampling::{
    EpipolarCamera, EpipolarSamples, SampledOutput, epipolar_samples, run_sampled,
};
use super::texture::{Tex, TexArray, mix4, xyz};
use glam::Vec3;
use scatter_shaderlib::prefiltered::{
    Basis, FrameUniforms, LightKind, PrefilteredVariant, Rectification, SliceParams, VisibilityMode,
};

/// The bindings of `scatter`.
pub struct ScatterInputs<'a> {
    /// Frame uniforms.
    pub frame: &'a FrameUniforms,
    /// Per-slice table.
    pub slices: &'a [SliceParams],
    /// Linear view depth, screen-sized.
    pub depth: &'a Tex,
    /// The standard shadow map.
    pub shadow_map: &'a Tex,
    /// Filtered bases (from `prefilter`).
    pub filtered: &'a TexArray,
    /// Region-prefix depth bounds `[min, max, 0, 0]` (from `prefilter`, layer 0; with
    /// `resume` the weight sums `[W, 0, 0, 0]` in layer 1).
    pub bounds: &'a TexArray,
    /// The rectified map `prefilter` filtered (`rectify`'s, or a projective frame's
    /// rasterised one): read with `resume` only.
    pub rectified: Option<&'a Tex>,
    /// The spot's cookie, for a `cookie` variant (`None`: a white cookie).
    pub cookie: Option<&'a TexArray>,
}

/// The kernel body for pixel `id`; returns the rgba16float texel it stores.
pub fn scatter_main(
    id: [u32; 3],
    variant: &PrefilteredVariant,
    inp: &ScatterInputs,
) -> Option<[f32; 4]> {
    let f = inp.frame;
    let (x, y) = (id[0], id[1]);
    if x >= f.sizes[0] || y >= f.sizes[1] {
        return None;
    }
    let spot = variant.light == LightKind::Spot;
    let eye = xyz(f.eye);
    let dir = pixel_dir(f, x, y);
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s =
        min(max(inp.depth.load(x, y), 0.0), f.theta[2]) / max(dir.dot(xyz(f.cam_forward)), 1e-6);
    let color = xyz(f.light_color);

    // Near the epipole and the anti-epipole the rectification degenerates: march instead.
    let tinted = variant.cookie;
    let white = TexArray::white();
    let cookie = inp.cookie.unwrap_or(&white);
    if in_epipole_disc(f, [x as f32 + 0.5, y as f32 + 0.5]) {
        let l = if tinted {
            epipole_march_cookie(f, inp.shadow_map, cookie, eye, dir, s) * color
        } else {
            epipole_march(f, inp.shadow_map, eye, dir, s, spot) * color
        };
        return Some([l.x, l.y, l.z, 1.0]);
    }

    // Rectified coordinates of the surface point.
    let axis = xyz(f.axis);
    let rows = f.sizes[3];
    // The lookups' columns (Wr / lookup: the stored ones, or with `resume` the rectified
    // ones), which the lookups below count in.
    let stride = variant.filtered_stride;
    let lookup = if variant.resume { 1 } else { stride };
    let width = f.sizes[2] / lookup;
    let regions = variant.regions;
    let wrap = f.anti_epipole[3] > 0.5;
    let yc: f32;
    let d: f32;
    // Projective: the ray's end column, the same in every row.
    let mut xs = 0.0;
    // Epipolar: the ray's end in column units times the row's column spacing (a row's end
    // column is reach / delta), and its view angle.
    let mut reach = 0.0;
    let mut theta = 0.0;
    // Projective: the ray's e1 component and depth m.
    let mut qd = 1.0;
    let mut m = 0.0;
    let proj = variant.rectification == Rectification::Projective && f.proj[0] > 0.5;
    if proj {
        let q = Vec3::new(dir.dot(xyz(f.e1)), dir.dot(xyz(f.e2)), dir.dot(axis));
        qd = max(q.x, 1e-6);
        let k = q.y / qd;
        m = q.z / qd;
        yc = clamp(
            (k + f.proj[1]) / (2.0 * f.proj[1]) * rows as f32,
            0.0,
            rows as f32,
        );
        d = proj_ray_depth(f, m);
        let qs = max(s * qd, 1e-6);
        let mut g = 1.0 / qs;
        if spot {
            g = (f.axis[3] - s * q.z) / qs;
        }
        xs = (stride / lookup) as f32 * proj_column(f, g, regions, f.sizes[2] / stride, spot);
    } else {
        // The view angle from the light axis as atan2(|dir x axis|, dir . axis): acos of the
        // dot product resolves angles near the axis only to sqrt(2 * 6e-8) = 3.5e-4 in f32.
        theta = dir.cross(axis).length().atan2(dir.dot(axis));
        yc = ray_row_coord(f, dir);
        d = normalised_depth(theta, f.theta[0], f.theta[1]);
        reach = ray_column(f, eye, dir, s, theta, spot);
    }

    // The two rectified rows the pixel lies between (the second only with a non-zero weight)
    // and the weight of the second; each row is read at its own column for the ray's points
    // (see the WGSL comment).
    let yb = yc - 0.5;
    let fy = yb - yb.floor();
    let row0 = row_index(yb.floor(), rows, wrap);
    let row1 = if yb > yb.floor() {
        row_index(yb.floor() + 1.0, rows, wrap)
    } else {
        row0
    };
    let w1 = if row1 != row0 { fy } else { 0.0 };

    let cos_theta_l = -xyz(f.light_dir).dot(dir);
    // Every region gets the full spot quadrature (see the WGSL comment).
    let panels = max_u(f.sizes2[2] / 4, 1);
    // The ray's Fourier coefficients depend on its depth only: once per pixel, their angles
    // by angle addition from pi d.
    // (The moment basis: the ray's depth in the region's moment coordinate instead, per
    // region and row below.)
    let moments = variant.basis == Basis::Moments;
    let mut coeffs = Vec::with_capacity(variant.layers() as usize);
    if !moments {
        let mut angle = [(PI * d).sin(), (PI * d).cos()];
        let step = fourier_step(angle);
        for layer in 0..variant.layers() {
            let second = turn(angle, step);
            coeffs.push(coeff4(angle, second, layer));
            angle = turn(second, step);
        }
    }
    // The sun's scattering coefficient times phase, the same for every region.
    let sun_scatter = f.medium[1] * phase_hg(f.medium[2], cos_theta_l);

    // Regions: every region before the surface's, whole, and the surface's up to x_s, each
    // weighted by this pixel's own unshadowed integral over its part [a, b] of the ray; each
    // row places a and b with its own spacing, so the two rows' regions are summed apart in
    // one loop, each row's ending at its own last region (see the WGSL comment).
    let (mut delta0, mut delta1) = (1.0, 1.0);
    let (mut xs0, mut xs1) = (xs, xs);
    if !proj {
        // A lookup column spans `lookup` rectified columns.
        delta0 = lookup as f32 * inp.slices[row0 as usize].delta;
        delta1 = lookup as f32 * inp.slices[row1 as usize].delta;
        xs0 = reach / delta0;
        xs1 = reach / delta1;
    }
    let last0 = min(max(xs0, 0.0), width as f32 - 1.0) as u32;
    let last1 = min(max(xs1, 0.0), width as f32 - 1.0) as u32;
    let (mut total0, mut total1) = (Vec3::ZERO, Vec3::ZERO);
    let (mut done0, mut done1) = (false, false);
    // The furthest stored edge a row's bounds lookup may read in the ray's last region: the
    // last one at most one rectified column past the ray's end (see the WGSL).
    let kf = lookup as f32;
    let cap0 = (((xs0 * kf).floor() + 1.0) / kf).floor();
    let cap1 = (((xs1 * kf).floor() + 1.0) / kf).floor();
    // The previous region's lit fraction per row, for a last region whose first stored edge
    // lies past `cap`.
    let (mut prev0, mut prev1) = (Vec3::ZERO, Vec3::ZERO);
    for r in 0..regions {
        // The region's first and next region's first lookup column (on stored columns).
        let b0 = (stride / lookup * region_start(r, regions, f.sizes[2] / stride, spot)) as f32;
        let b1 = (stride / lookup * region_start(r + 1, regions, f.sizes[2] / stride, spot)) as f32;
        let is_last0 = last0 < b1 as u32 || r + 1 == regions;
        let is_last1 = last1 < b1 as u32 || r + 1 == regions;
        let pos_of = |xs: f32, is_last: bool| {
            if is_last {
                clamp(xs - 0.5, b0 + 0.5, b1 - 0.5)
            } else {
                b1 - 0.5
            }
        };
        let (pos0, pos1) = (pos_of(xs0, is_last0), pos_of(xs1, is_last1));
        // The bounds' lookup stops at `cap` (see the WGSL).
        let (bpos0, bpos1) = (
            pos_of(xs0.min(cap0), is_last0),
            pos_of(xs1.min(cap1), is_last1),
        );
        let before0 = is_last0 && cap0 <= b0 && r > 0;
        let before1 = is_last1 && cap1 <= b0 && r > 0;
        let ((a0, e0), (a1, e1)) = if proj {
            let mut a = 0.0;
            if r > 0 {
                a = min(proj_reach(f, proj_boundary(f, r), m, spot, s * qd) / qd, s);
            }
            let e = if is_last0 {
                s
            } else {
                min(
                    proj_reach(f, proj_boundary(f, r + 1), m, spot, s * qd) / qd,
                    s,
                )
            };
            ((a, e), (a, e))
        } else {
            let span = |delta: f32, is_last: bool| {
                let e = if is_last {
                    s
                } else {
                    ray_t(f, b1, delta, theta, s, spot)
                };
                (ray_t(f, b0, delta, theta, s, spot), e)
            };
            (span(delta0, is_last0), span(delta1, is_last1))
        };
        let weight_of = |a: f32, e: f32| {
            if spot {
                spot_segment(f, eye, dir, a, e, panels)
            } else {
                sun_scatter * transmittance_between(f.medium[0], a, e)
            }
        };
        // With a cookie: the pixel's own unshadowed integral with the cookie (RGB), for the
        // rows not yet done.
        let (weight0, weight1) = if tinted {
            let with_cookie = |done: bool, a: f32, e: f32| {
                if done {
                    Vec3::ZERO
                } else {
                    spot_segment_cookie(f, cookie, eye, dir, a, e, panels)
                }
            };
            (with_cookie(done0, a0, e0), with_cookie(done1, a1, e1))
        } else {
            (
                Vec3::splat(weight_of(a0, e0)),
                Vec3::splat(weight_of(a1, e1)),
            )
        };
        // Per row, the (up to) two texels the linear fetch reads with a non-zero weight:
        // columns x0 <= x1 of the region.
        let texels = |pos: f32| {
            let xb = pos - 0.5;
            let fx = xb - xb.floor();
            let x0 = clamp(xb.floor(), 0.0, width as f32 - 1.0) as u32;
            let x1 = if xb > xb.floor() {
                (x0 + 1).min(width - 1)
            } else {
                x0
            };
            (x0, x1, fx)
        };
        let (x00, x01, fx0) = texels(pos0);
        let (x10, x11, fx1) = texels(pos1);
        // Their depth bounds: a region's prefix bounds only widen along the row, so column
        // x1's cover column x0's; x1 of the lookup stopped at `cap`.
        let resume = Resume {
            inp,
            variant,
            start: b0 as u32,
            region: r,
            proj,
        };
        let (from0, from1) = (resume.origin(x00), resume.origin(x10));
        let (lohi0, lohi1) = if variant.resume {
            // Resumed from each row's last stored column before x0 + 1 in the region (at a
            // lookup of one rectified column the bounds' column is x1).
            (
                resume.bounds(from0, x01, row0),
                resume.bounds(from1, x11, row1),
            )
        } else {
            (
                inp.bounds.load(texels(bpos0).1, row0, 0),
                inp.bounds.load(texels(bpos1).1, row1, 0),
            )
        };
        let ambiguous = |lohi: [f32; 4]| d > lohi[0] && d <= lohi[1];
        // The ray's depth in a row's moment coordinate: the region's whole depth range is its
        // bounds at its last stored column (`moment_z`).
        let zf_of = |row: u32| {
            let range = inp.bounds.load(b1 as u32 * lookup / stride - 1, row, 0);
            moment_z(d, [range[0], range[1]])
        };
        let (add0, add1) = if tinted && variant.resume {
            let range_of = |row: u32| {
                let range = inp.bounds.load(b1 as u32 * lookup / stride - 1, row, 0);
                [range[0], range[1]]
            };
            resume.tinted(
                [from0, from1],
                [(x00, x01, fx0, row0), (x10, x11, fx1, row1)],
                [lohi0, lohi1],
                d,
                [range_of(row0), range_of(row1)],
                &coeffs,
            )
        } else if tinted {
            tinted_region(
                inp,
                variant,
                [(x00, x01, fx0, row0), (x10, x11, fx1, row1)],
                [lohi0, lohi1],
                d,
                if moments {
                    [zf_of(row0), zf_of(row1)]
                } else {
                    [0.0; 2]
                },
                &coeffs,
            )
        } else {
            let (mut vis0, mut vis1) = (0.5, 0.5);
            if moments {
                // The region's moments, filtered linearly along each row.
                let lit = |x0: u32, x1: u32, fx: f32, row: u32, origin: [u32; 2]| {
                    let range = inp.bounds.load(b1 as u32 * lookup / stride - 1, row, 0);
                    let zf = moment_z(d, [range[0], range[1]]);
                    let [m0, m1] = if variant.resume {
                        resume.moments(origin, x0, x1, fx, [range[0], range[1]], row)
                    } else {
                        let fetch = |layer: u32| {
                            let load = |x: u32| inp.filtered.load(x, row, layer);
                            mix4(load(x0), load(x1), fx)
                        };
                        [
                            fetch(0),
                            if variant.moments == 6 {
                                fetch(1)
                            } else {
                                [0.0; 4]
                            },
                        ]
                    };
                    if variant.moments == 6 {
                        lit_moments6(m0, [m1[0], m1[1]], zf)
                    } else {
                        lit_moments4(m0, zf)
                    }
                };
                if ambiguous(lohi0) {
                    vis0 = lit(x00, x01, fx0, row0, from0);
                }
                if ambiguous(lohi1) {
                    vis1 = lit(x10, x11, fx1, row1, from1);
                }
            } else if variant.resume && (ambiguous(lohi0) || ambiguous(lohi1)) {
                // a(d) . F at each row's stored column, then resumed up to x0 and x1.
                let (mut dot0, mut dot1) = (0.0, 0.0);
                for layer in 0..variant.layers() {
                    let coeff = coeffs[layer as usize];
                    let texel0 = inp.filtered.load(from0[0], row0, layer);
                    let texel1 = inp.filtered.load(from1[0], row1, layer);
                    for k in 0..4 {
                        dot0 += coeff[k] * (texel0[k] * 2.0 - 1.0);
                        dot1 += coeff[k] * (texel1[k] * 2.0 - 1.0);
                    }
                }
                vis0 += resume.fourier(from0, x00, x01, fx0, d, dot0, row0);
                vis1 += resume.fourier(from1, x10, x11, fx1, d, dot1, row1);
            } else if ambiguous(lohi0) || ambiguous(lohi1) {
                for layer in 0..variant.layers() {
                    let coeff = coeffs[layer as usize];
                    let load = |x: u32, row: u32| inp.filtered.load(x, row, layer);
                    let texel0 = mix4(load(x00, row0), load(x01, row0), fx0);
                    let texel1 = mix4(load(x10, row1), load(x11, row1), fx1);
                    for k in 0..4 {
                        vis0 += coeff[k] * (texel0[k] * 2.0 - 1.0);
                        vis1 += coeff[k] * (texel1[k] * 2.0 - 1.0);
                    }
                }
            }
            // Outside the row's depth range the region is exactly lit or shadowed.
            let exact = |vis: f32, lohi: [f32; 4]| {
                if d <= lohi[0] {
                    1.0
                } else if d > lohi[1] {
                    0.0
                } else {
                    vis
                }
            };
            vis0 = exact(vis0, lohi0);
            vis1 = exact(vis1, lohi1);
            (
                Vec3::splat(clamp(vis0, 0.0, 1.0)),
                Vec3::splat(clamp(vis1, 0.0, 1.0)),
            )
        };
        // A last region the ray ends under the first coarse column of: the previous region's
        // fraction.
        let add0 = if before0 { prev0 } else { add0 };
        let add1 = if before1 { prev1 } else { add1 };
        prev0 = add0;
        prev1 = add1;
        if !done0 {
            total0 += weight0 * add0;
        }
        if !done1 {
            total1 += weight1 * add1;
        }
        done0 = done0 || is_last0;
        done1 = done1 || is_last1;
        if done0 && done1 {
            break;
        }
    }
    let total = (1.0 - w1) * total0 + w1 * total1;
    let l = total;
    let c = color * l;
    Some([c.x, c.y, c.z, 1.0])
}

/// A region's cookie-weighted lit fraction per colour channel, for both rows (`texels`: each
/// row's two columns, the second's weight and the row; `lohi`: their depth bounds; `zf`: the
/// ray's depth in each row's moment coordinate, unused with Fourier bases): the lit
/// share clamped to [0, Cbar] over Cbar, 0 where Cbar is (see the WGSL comment).
fn tinted_region(
    inp: &ScatterInputs,
    variant: &PrefilteredVariant,
    texels: [(u32, u32, f32, u32); 2],
    lohi: [[f32; 4]; 2],
    d: f32,
    zf: [f32; 2],
    coeffs: &[[f32; 4]],
) -> (Vec3, Vec3) {
    let layers = variant.layers();
    let fetch = |(x0, x1, fx, row): (u32, u32, f32, u32), layer: u32| {
        mix4(
            inp.filtered.load(x0, row, layer),
            inp.filtered.load(x1, row, layer),
            fx,
        )
    };
    let cbar = texels.map(|t| {
        let c = fetch(t, 3 * layers);
        Vec3::new(c[0], c[1], c[2])
    });
    let mut vis = cbar.map(|c| 0.5 * c);
    let ambiguous = |lohi: [f32; 4]| d > lohi[0] && d <= lohi[1];
    if variant.basis == Basis::Moments {
        // Per channel the moments of the cookie-weighted depths: the stored ones over Cbar.
        for c in 0..3 {
            for row in 0..2 {
                let cb = cbar[row][c];
                if ambiguous(lohi[row]) && cb > 0.0 {
                    let m0 = fetch(texels[row], c as u32 * layers).map(|v| v / cb);
                    vis[row][c] = cb
                        * if variant.moments == 6 {
                            let m1 = fetch(texels[row], c as u32 * layers + 1).map(|v| v / cb);
                            lit_moments6(m0, [m1[0], m1[1]], zf[row])
                        } else {
                            lit_moments4(m0, zf[row])
                        };
                }
            }
        }
    } else if ambiguous(lohi[0]) || ambiguous(lohi[1]) {
        for layer in 0..layers {
            let coeff = coeffs[layer as usize];
            for c in 0..3 {
                let texel = texels.map(|t| fetch(t, c * layers + layer));
                for k in 0..4 {
                    for row in 0..2 {
                        vis[row][c as usize] += coeff[k] * (texel[row][k] * 2.0 - 1.0);
                    }
                }
            }
        }
    }
    cookie_fractions(d, lohi, cbar, vis)
}

/// Both rows' cookie-weighted lit fractions from their lit shares `vis`, mean cookies `cbar`
/// and depth bounds `lohi`: outside a row's depth range the region is exactly lit (the mean
/// cookie) or shadowed; the share clamped to [0, Cbar] over Cbar, 0 where Cbar is.
fn cookie_fractions(d: f32, lohi: [[f32; 4]; 2], cbar: [Vec3; 2], vis: [Vec3; 2]) -> (Vec3, Vec3) {
    let fraction = |row: usize| {
        let v = if d <= lohi[row][0] {
            cbar[row]
        } else if d > lohi[row][1] {
            Vec3::ZERO
        } else {
            vis[row]
        };
        let c = cbar[row];
        let f = |v: f32, c: f32| if c > 0.0 { clamp(v, 0.0, c) / c } else { 0.0 };
        Vec3::new(f(v.x, c.x), f(v.y, c.y), f(v.z, c.z))
    };
    (fraction(0), fraction(1))
}

/// `resume` (`templates/include/scatter_resume.wgsl`): a region's lookups resumed from the
/// last stored column before them over the rectified texels up to them, as `prefilter`
/// filtered them: `F(x) = (W_c F_c + sum_i w_i B(d_i)) / (W_c + sum_i w_i)`.
struct Resume<'a> {
    inp: &'a ScatterInputs<'a>,
    variant: &'a PrefilteredVariant,
    /// The region's first rectified column.
    start: u32,
    region: u32,
    /// A projective frame.
    proj: bool,
}

impl Resume<'_> {
    /// Rectified texel `(i, row)`'s depth as `prefilter` filtered it (`resume_depth`).
    fn depth(&self, i: u32, row: u32) -> f32 {
        let rectified = self
            .inp
            .rectified
            .expect("a resume variant's scatter inputs carry the rectified map");
        let d = rectified.load(i, row);
        if self.proj { proj_stored_depth(d) } else { d }
    }

    /// `prefilter`'s weight of rectified texel `i` of `row` (`resume_weight`, `resume_e`).
    fn weight(&self, i: u32, row: u32) -> f32 {
        let f = self.inp.frame;
        let sp = &self.inp.slices[row as usize];
        let weighted = self.variant.visibility == VisibilityMode::Weighted;
        let spot = self.variant.light == LightKind::Spot;
        if self.proj {
            return proj_texel_weight(
                f,
                sp,
                i,
                self.region,
                self.variant.regions,
                self.variant.filtered_stride,
                weighted,
                spot,
            );
        }
        let e = if spot {
            slice_e(f, row_phi(f, row))
        } else {
            Vec3::ZERO
        };
        texel_weight(f, sp, e, i, weighted, spot)
    }

    /// `resume_from`: (the last stored column whose right edge lies at or before `x0`, the
    /// first texel after it), or `(0, start)` where the region has none there.
    fn origin(&self, x0: u32) -> [u32; 2] {
        let k = self.variant.filtered_stride;
        let c = (x0 + 1) / k * k;
        if c > self.start {
            [c / k - 1, c]
        } else {
            [0, self.start]
        }
    }

    /// `resume_bounds`: the region's (min, max) depth of `row` up to column `x1`.
    fn bounds(&self, origin: [u32; 2], x1: u32, row: u32) -> [f32; 4] {
        let mut lohi = [1e30f32, -1e30f32];
        if origin[1] > self.start {
            let b = self.inp.bounds.load(origin[0], row, 0);
            lohi = [b[0], b[1]];
        }
        for i in origin[1]..=x1 {
            let di = self.depth(i, row);
            lohi = [lohi[0].min(di), lohi[1].max(di)];
        }
        [lohi[0], lohi[1], 0.0, 0.0]
    }

    /// `resume_w`: the stored weight sum at `origin`, 0 at the region's first column.
    fn stored_w(&self, origin: [u32; 2], row: u32) -> f32 {
        if origin[1] > self.start {
            self.inp.bounds.load(origin[0], row, 1)[0]
        } else {
            0.0
        }
    }

    /// `resume_fourier`: `a(d) . F` of `row` blended between columns `x0` and `x1` by `fx`;
    /// `at_origin` is `a(d) . F` at the stored column.
    #[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
    fn fourier(
        &self,
        origin: [u32; 2],
        x0: u32,
        x1: u32,
        fx: f32,
        d: f32,
        at_origin: f32,
        row: u32,
    ) -> f32 {
        let frequencies = 2 * self.variant.layers();
        let mut w = self.stored_w(origin, row);
        let mut sum = w * at_origin;
        let (mut w0, mut sum0) = (w, sum);
        for i in origin[1]..=x1 {
            let wi = self.weight(i, row);
            w += wi;
            sum += wi * step_series(self.depth(i, row) - d, frequencies);
            if i == x0 {
                (w0, sum0) = (w, sum);
            }
        }
        let mean = |s: f32, w: f32| if w > 0.0 { s / w } else { 0.0 };
        let (a, b) = (mean(sum0, w0), mean(sum, w));
        a * (1.0 - fx) + b * fx
    }

    /// `resume_moments`: the moments of `row` (layer 0, and layer 1 with 6 moments) blended
    /// between columns `x0` and `x1` by `fx`, the depths in `range`'s coordinate.
    #[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
    fn moments(
        &self,
        origin: [u32; 2],
        x0: u32,
        x1: u32,
        fx: f32,
        range: [f32; 2],
        row: u32,
    ) -> [[f32; 4]; 2] {
        let six = self.variant.moments == 6;
        let w_origin = self.stored_w(origin, row);
        let mut w = w_origin;
        let scale = |v: [f32; 4], k: f32| v.map(|c| c * k);
        let add = |a: [f32; 4], b: [f32; 4]| [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]];
        let mut sa = scale(self.inp.filtered.load(origin[0], row, 0), w_origin);
        let mut sb = if six {
            scale(self.inp.filtered.load(origin[0], row, 1), w_origin)
        } else {
            [0.0; 4]
        };
        let (mut w0, mut sa0, mut sb0) = (w, sa, sb);
        for i in origin[1]..=x1 {
            let wi = self.weight(i, row);
            let z = moment_z(self.depth(i, row), range);
            w += wi;
            sa = add(sa, scale(moment_layer(z, 0), wi));
            if six {
                sb = add(sb, scale(moment_layer(z, 1), wi));
            }
            if i == x0 {
                (w0, sa0, sb0) = (w, sa, sb);
            }
        }
        let k0 = if w0 > 0.0 { 1.0 / w0 } else { 0.0 };
        let k1 = if w > 0.0 { 1.0 / w } else { 0.0 };
        [
            mix4(scale(sa0, k0), scale(sa, k1), fx),
            mix4(scale(sb0, k0), scale(sb, k1), fx),
        ]
    }

    /// `texel_cookie` of rectified texel `i` of `row` (the white cookie without one).
    fn cookie_of(&self, i: u32, row: u32, e: Vec3) -> Vec3 {
        let white = TexArray::white();
        super::prefilter::texel_cookie(
            self.inp.frame,
            self.inp.cookie.unwrap_or(&white),
            self.variant.regions,
            self.variant.filtered_stride,
            i,
            &self.inp.slices[row as usize],
            e,
            self.region,
            self.proj,
        )
    }

    /// With a cookie (`resume_cookie`): `row`'s mean cookie and per channel either `a(d) .
    /// F^c` (Fourier: `at_origin` at the stored column) or the means of `C^c` times the
    /// moments in `range`'s coordinate (layers 0 and 1), blended between `x0` and `x1` by
    /// `fx`; the series or moments only where `series`.
    #[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
    fn cookie(
        &self,
        origin: [u32; 2],
        (x0, x1, fx): (u32, u32, f32),
        d: f32,
        at_origin: Vec3,
        range: [f32; 2],
        series: bool,
        row: u32,
    ) -> (Vec3, Vec3, [[[f32; 4]; 3]; 2]) {
        let layers = self.variant.layers();
        let moments = self.variant.basis == Basis::Moments;
        let six = self.variant.moments == 6;
        let f = self.inp.frame;
        let e = if self.variant.light == LightKind::Spot {
            slice_e(f, row_phi(f, row))
        } else {
            Vec3::ZERO
        };
        let scale = |v: [f32; 4], k: f32| v.map(|c| c * k);
        let add = |a: [f32; 4], b: [f32; 4]| [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]];
        let mut w = self.stored_w(origin, row);
        let cb = self.inp.filtered.load(origin[0], row, 3 * layers);
        let mut cs = Vec3::new(cb[0], cb[1], cb[2]) * w;
        let mut vs = at_origin * w;
        let mut sm = [[[0.0f32; 4]; 3]; 2];
        if moments {
            for c in 0..3u32 {
                sm[0][c as usize] = scale(self.inp.filtered.load(origin[0], row, c * layers), w);
                if six {
                    sm[1][c as usize] =
                        scale(self.inp.filtered.load(origin[0], row, c * layers + 1), w);
                }
            }
        }
        let (mut w0, mut cs0, mut vs0, mut sm0) = (w, cs, vs, sm);
        for i in origin[1]..=x1 {
            let wi = self.weight(i, row);
            let ci = self.cookie_of(i, row, e) * wi;
            w += wi;
            cs += ci;
            if series {
                if moments {
                    let z = moment_z(self.depth(i, row), range);
                    let (m0, m1) = (moment_layer(z, 0), moment_layer(z, 1));
                    for c in 0..3 {
                        sm[0][c] = add(sm[0][c], scale(m0, ci[c]));
                        if six {
                            sm[1][c] = add(sm[1][c], scale(m1, ci[c]));
                        }
                    }
                } else {
                    vs += ci * step_series(self.depth(i, row) - d, 2 * layers);
                }
            }
            if i == x0 {
                (w0, cs0, vs0, sm0) = (w, cs, vs, sm);
            }
        }
        let k0 = if w0 > 0.0 { 1.0 / w0 } else { 0.0 };
        let k1 = if w > 0.0 { 1.0 / w } else { 0.0 };
        let mixv = |a: Vec3, b: Vec3| a * (1.0 - fx) + b * fx;
        let mut out = [[[0.0f32; 4]; 3]; 2];
        for l in 0..2 {
            for c in 0..3 {
                out[l][c] = mix4(scale(sm0[l][c], k0), scale(sm[l][c], k1), fx);
            }
        }
        (mixv(cs0 * k0, cs * k1), mixv(vs0 * k0, vs * k1), out)
    }

    /// `scatter`'s cookie branch with `resume`: both rows' cookie-weighted lit fractions
    /// (`texels`: each row's two columns, the second's weight and the row; `lohi` their
    /// bounds; `ranges` their regions' depth ranges for the moments).
    fn tinted(
        &self,
        origins: [[u32; 2]; 2],
        texels: [(u32, u32, f32, u32); 2],
        lohi: [[f32; 4]; 2],
        d: f32,
        ranges: [[f32; 2]; 2],
        coeffs: &[[f32; 4]],
    ) -> (Vec3, Vec3) {
        let layers = self.variant.layers();
        let ambiguous = lohi.map(|l| d > l[0] && d <= l[1]);
        let mut vis = [Vec3::ZERO; 2];
        let mut cbar = [Vec3::ZERO; 2];
        if self.variant.basis == Basis::Moments {
            for row in 0..2 {
                let (x0, x1, fx, r) = texels[row];
                let (cb, _, m) = self.cookie(
                    origins[row],
                    (x0, x1, fx),
                    d,
                    Vec3::ZERO,
                    ranges[row],
                    ambiguous[row],
                    r,
                );
                let zf = moment_z(d, ranges[row]);
                cbar[row] = cb;
                vis[row] = cb * 0.5;
                for c in 0..3 {
                    if ambiguous[row] && cb[c] > 0.0 {
                        let m0 = m[0][c].map(|v| v / cb[c]);
                        vis[row][c] = cb[c]
                            * if self.variant.moments == 6 {
                                let m1 = m[1][c].map(|v| v / cb[c]);
                                lit_moments6(m0, [m1[0], m1[1]], zf)
                            } else {
                                lit_moments4(m0, zf)
                            };
                    }
                }
            }
        } else {
            let mut at = [Vec3::ZERO; 2];
            if ambiguous[0] || ambiguous[1] {
                for layer in 0..layers {
                    let coeff = coeffs[layer as usize];
                    for c in 0..3u32 {
                        for row in 0..2 {
                            let t = self.inp.filtered.load(
                                origins[row][0],
                                texels[row].3,
                                c * layers + layer,
                            );
                            for k in 0..4 {
                                at[row][c as usize] += coeff[k] * (t[k] * 2.0 - 1.0);
                            }
                        }
                    }
                }
            }
            for row in 0..2 {
                let (x0, x1, fx, r) = texels[row];
                let (cb, v, _) = self.cookie(
                    origins[row],
                    (x0, x1, fx),
                    d,
                    at[row],
                    ranges[row],
                    ambiguous[row],
                    r,
                );
                cbar[row] = cb;
                vis[row] = cb * 0.5 + v;
            }
        }
        cookie_fractions(d, lohi, cbar, vis)
    }
}

/// `step_series`: `a(d) . B(d_i)` as a function of `x = d_i - d`, the sum over the
/// `frequencies` Fourier frequencies `c_k` of `2 / c_k sin(c_k x)`, by the turns of
/// `fourier_step` from `(sin, cos)(pi x)`.
fn step_series(x: f32, frequencies: u32) -> f32 {
    let mut a = [(PI * x).sin(), (PI * x).cos()];
    let step = fourier_step(a);
    let mut sum = 0.0;
    for k in 1..=frequencies {
        sum += 2.0 / freq(k) * a[0];
        a = turn(a, step);
    }
    sum
}

/// Runs every pixel (rows in parallel), or the samples and the upsample of a sampled
/// variant; returns the screen-sized output as stored in rgba16float.
pub fn scatter(variant: &PrefilteredVariant, inp: &ScatterInputs) -> TexArray {
    scatter_sampled(variant, inp).output
}

/// [`run_sampled`] with [`scatter_main`] as the pixel body.
pub fn scatter_sampled(variant: &PrefilteredVariant, inp: &ScatterInputs) -> SampledOutput {
    run_sampled(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        &EpipolarCamera::of_frame(inp.frame),
        &|x, y| {
            let c = scatter_main([x, y, 0], variant, inp).unwrap_or([0.0; 4]);
            [c[0], c[1], c[2]]
        },
    )
}

/// `scatter` of an `epipolar` variant: the samples of every slice (sampling pass 1).
pub fn scatter_epipolar_samples(
    variant: &PrefilteredVariant,
    inp: &ScatterInputs,
) -> EpipolarSamples {
    epipolar_samples(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        &EpipolarCamera::of_frame(inp.frame),
        &|x, y| {
            let c = scatter_main([x, y, 0], variant, inp).unwrap_or([0.0; 4]);
            [c[0], c[1], c[2]]
        },
    )
}
