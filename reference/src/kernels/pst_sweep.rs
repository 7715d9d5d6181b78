//! CPU mirror of `shaderlib/templates/pst_sweep.wgsl`: the partial-sum-tree method of Baran et
//! al. 2010 on the epipolar samples. Per sample slice, its samples are the queries of one
//! sweep through a Fenwick tree over the rectified row the slice lies in (the row of its last
//! sample's pixel): queries ranked by `d`, every column's count `b` of queries that see it lit,
//! its leaf inserted at tree position `V - b` in column order, each query answered (in order
//! of its prefix end) by the prefix below `V - rank`; the columns split over `TREES` trees
//! swept at once, then summed into exclusive prefixes over the trees. Conventions and the derivation:
//! `scatter_frame::partial_sum_tree`. The WGSL's four phases run one after the other here;
//! every value is computed by the same expression in the same order.
//!
//! With a cookie (`cookie = true`, see the WGSL comment) every leaf and tree entry holds three
//! channels of `rank_vecs` vec4s, each query's dot product is per channel, and the last
//! column and the epipole march carry the cookie.

use super::common_cookie::{epipole_march_cookie, frame_cookie, lit_span_cookie};
use super::common_epipolar::{
    edge_t, epipole_march, in_epipole_disc, lit_span, normalised_depth, ray_column, ray_row_coord,
    ray_theta, row_index, row_phi, slice_e,
};
use super::common_model::{clamp, cone_falloff, max, min, phase_hg, select, transmittance_between};
use super::common_sampling::{
    EpipolarCamera, EpipolarSamples, depth_close, epipolar_layout, round_f16_rgb, slice_direction,
    slice_sample_pixel, slice_span,
};
use super::texture::{Tex, TexArray, xyz};
use glam::{Vec3, Vec4};
use scatter_shaderlib::partial_sum_tree::{GL2, GRID, PartialSumTreeVariant, TREES};
use scatter_shaderlib::prefiltered::{FrameUniforms, LightKind, SliceParams};

/// The bindings of `pst_sweep` (and of its fallback, which reads the same but the scratch).
pub struct PstInputs<'a> {
    /// Frame uniforms.
    pub frame: &'a FrameUniforms,
    /// Per-row table (after `slice_fit`).
    pub slices: &'a [SliceParams],
    /// Linear view depth, screen-sized.
    pub depth: &'a Tex,
    /// The standard shadow map.
    pub shadow_map: &'a Tex,
    /// The rectified map (`rectify`).
    pub rectified: &'a Tex,
    /// The factors buffer (`PartialSumTreeFrame::factors`).
    pub factors: &'a [[f32; 4]],
    /// The spot's cookie, for a `cookie` variant (`None`: a white cookie).
    pub cookie: Option<&'a TexArray>,
}

/// What a `cookie` variant's kernels read of the cookie: the texture (a white texel where
/// the inputs hold none) and the rank's vec4s (a leaf entry `h` is channel `h / rank_vecs`).
#[derive(Clone, Copy)]
pub struct Tint<'a> {
    /// The cookie texture.
    pub cookie: &'a TexArray,
    /// `rank_vecs` of the variant.
    pub rank_vecs: u32,
}

/// What the sweep of every slice did (not written by the kernel: counts for reports).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SweepCounts {
    /// Queries answered through the trees.
    pub queries: u64,
    /// Columns inserted (some query sees them lit).
    pub inserted: u64,
    /// Samples marched (near the epipoles) or without a column.
    pub direct: u64,
    /// Samples at a depth break: their pixel's ray (through its centre, to its depth).
    pub edges: u64,
}

fn v4(a: [f32; 4]) -> Vec4 {
    Vec4::from_array(a)
}

/// Factor table `base` at `x` in [0, 1], bases `4h ..`, linear between nodes.
fn factor_at(inp: &PstInputs, base: u32, x: f32, h: u32) -> Vec4 {
    let grid = GRID as u32;
    let p = min(clamp(x, 0.0, 1.0) * (grid - 1) as f32, (grid - 1) as f32);
    let j = (p.floor() as u32).min(grid - 2);
    let t = p - j as f32;
    v4(inp.factors[(base + 2 * j + h) as usize]) * (1.0 - t)
        + v4(inp.factors[(base + 2 * (j + 1) + h) as usize]) * t
}

/// `gamma_(4h ..)(v)`.
fn gamma_at(inp: &PstInputs, v: f32, h: u32) -> Vec4 {
    factor_at(inp, 1, v / inp.factors[0][0], h)
}

/// `beta_(4h ..)(theta)`.
fn beta_at(inp: &PstInputs, theta: f32, h: u32) -> Vec4 {
    let head = inp.factors[0];
    factor_at(
        inp,
        1 + 2 * GRID as u32,
        (theta - head[1]) / max(head[2] - head[1], 1e-12),
        h,
    )
}

/// The direction `e` of row `row`'s plane of light rays (`slice_e` of its `row_phi`), which a
/// spot's leaves read: once per row, not per column (WGSL `pst_row_e`); zero for the sun.
pub fn pst_row_e(f: &FrameUniforms, spot: bool, row: u32) -> Vec3 {
    if !spot {
        return Vec3::ZERO;
    }
    slice_e(f, row_phi(f, row))
}

/// Leaf of column `i` of the row whose plane is `e` ([`pst_row_e`]; spacing `delta`), bases
/// `4h ..`; with a cookie (`tint`) entry `h` is channel `h / rank_vecs`'s, bases
/// `4 (h % rank_vecs) ..`.
pub fn pst_leaf(
    inp: &PstInputs,
    spot: bool,
    i: u32,
    e: Vec3,
    delta: f32,
    h: u32,
    tint: Option<Tint>,
) -> Vec4 {
    let f = inp.frame;
    if !spot {
        return gamma_at(inp, i as f32 * delta, h);
    }
    let axis = xyz(f.axis);
    let mut leaf = Vec4::ZERO;
    for g in 0..2u32 {
        let q = if g == 0 { -GL2 } else { GL2 };
        let psi = (i as f32 + 0.5 + 0.5 * q) * delta;
        let l = -axis * psi.cos() + e * psi.sin();
        let cone = cone_falloff(l.dot(xyz(f.light_dir)), f.light_pos[3], f.light_dir[3]);
        if let Some(t) = tint {
            let c = frame_cookie(f, t.cookie, xyz(f.light_pos) + l)[(h / t.rank_vecs) as usize];
            leaf += (0.5 * delta * cone * c) * gamma_at(inp, psi, h % t.rank_vecs);
        } else {
            leaf += (0.5 * delta * cone) * gamma_at(inp, psi, h);
        }
    }
    leaf
}

/// A pixel's ray in rectified space (WGSL `PstRay`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PstRay {
    /// Near the epipoles: `color` holds the marched radiance.
    pub marched: bool,
    /// The marched radiance.
    pub color: Vec3,
    /// Eye position.
    pub eye: Vec3,
    /// Unit view direction.
    pub dir: Vec3,
    /// Distance to the surface.
    pub s: f32,
    /// The pixel's nearest row.
    pub row: u32,
    /// View angle to the axis.
    pub theta: f32,
    /// Normalised rectified depth.
    pub d: f32,
    /// `x_s` times the row's spacing.
    pub xs_num: f32,
}

/// The ray through the continuous pixel position `pc` ending at view depth `z` (WGSL
/// `pst_ray`); `tint` for a `cookie` variant (the march carries the cookie).
pub fn pst_ray(inp: &PstInputs, spot: bool, pc: [f32; 2], z: f32, tint: Option<Tint>) -> PstRay {
    let f = inp.frame;
    let eye = xyz(f.eye);
    let ndc = [
        2.0 * pc[0] / f.sizes[0] as f32 - 1.0,
        1.0 - 2.0 * pc[1] / f.sizes[1] as f32,
    ];
    let t = f.cam_forward[3];
    let dir = (xyz(f.cam_forward)
        + xyz(f.cam_right) * (ndc[0] * t * f.cam_right[3])
        + xyz(f.cam_up) * (ndc[1] * t))
        .normalize();
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s = min(max(z, 0.0), f.theta[2]) / max(dir.dot(xyz(f.cam_forward)), 1e-6);
    let mut r = PstRay {
        marched: false,
        color: Vec3::ZERO,
        eye,
        dir,
        s,
        row: 0,
        theta: 0.0,
        d: 0.0,
        xs_num: 0.0,
    };
    if in_epipole_disc(f, [pc[0], pc[1]]) {
        r.marched = true;
        r.color = match tint {
            Some(t) => epipole_march_cookie(f, inp.shadow_map, t.cookie, eye, dir, s),
            None => Vec3::splat(epipole_march(f, inp.shadow_map, eye, dir, s, spot)),
        } * xyz(f.light_color);
    }
    r.theta = ray_theta(f, dir);
    r.row = row_index(
        ray_row_coord(f, dir).floor(),
        f.sizes[3],
        f.anti_epipole[3] > 0.5,
    );
    r.d = normalised_depth(r.theta, f.theta[0], f.theta[1]);
    r.xs_num = ray_column(f, eye, dir, s, r.theta, spot);
    r
}

/// Texels the ray crosses in a row of spacing `delta` (WGSL `pst_columns_crossed`).
pub fn pst_columns_crossed(f: &FrameUniforms, r: &PstRay, delta: f32) -> u32 {
    let xs = r.xs_num / delta;
    min(select(0.0, xs, xs > 0.0).ceil(), f.sizes[2] as f32) as u32
}

/// A query's factor and term (WGSL `pst_terms`, with a cookie `pst_terms_cookie`): `(a, b)`,
/// `b` per colour channel (the same in each without a cookie).
pub fn pst_terms(
    inp: &PstInputs,
    spot: bool,
    r: &PstRay,
    row: u32,
    delta: f32,
    n: u32,
    tint: Option<Tint>,
) -> (f32, Vec3) {
    let f = inp.frame;
    let sin_theta = max(r.theta.sin(), 1e-6);
    if let Some(t) = tint {
        let mut tail = Vec3::ZERO;
        if r.d <= inp.rectified.load(n - 1, row) {
            let a = edge_t(f, n - 1, n, delta, r.theta, r.s, true);
            tail = lit_span_cookie(f, t.cookie, r.eye, r.dir, a, r.s);
        }
        return (f.medium[1] / (f.axis[3] * sin_theta), tail);
    }
    let mut tail = 0.0;
    if r.d <= inp.rectified.load(n - 1, row) {
        let a = edge_t(f, n - 1, n, delta, r.theta, r.s, spot);
        tail = lit_span(f, r.eye, r.dir, a, r.s, spot);
    }
    if spot {
        return (f.medium[1] / (f.axis[3] * sin_theta), Vec3::splat(tail));
    }
    let sp = f.medium[1] * phase_hg(f.medium[2], -xyz(f.light_dir).dot(r.dir));
    (
        sp * transmittance_between(f.medium[0], 0.0, delta / sin_theta),
        Vec3::splat(sp * tail),
    )
}

/// View depth at the continuous pixel position `pc` from the 2 x 2 pixels around it, `1 / z`
/// interpolated bilinearly; -1 at a depth break (WGSL `pst_footprint_depth`).
pub fn pst_footprint_depth(
    inp: &PstInputs,
    pc: [f32; 2],
    screen: [u32; 2],
    depth_break: f32,
) -> f32 {
    let last = [screen[0] as f32 - 1.0, screen[1] as f32 - 1.0];
    let q = [
        clamp(pc[0] - 0.5, 0.0, last[0]),
        clamp(pc[1] - 0.5, 0.0, last[1]),
    ];
    let i0 = [q[0].floor() as u32, q[1].floor() as u32];
    let i1 = [
        (i0[0] + 1).min(screen[0] - 1),
        (i0[1] + 1).min(screen[1] - 1),
    ];
    let t = [q[0] - q[0].floor(), q[1] - q[1].floor()];
    let z00 = inp.depth.load(i0[0], i0[1]);
    let z10 = inp.depth.load(i1[0], i0[1]);
    let z01 = inp.depth.load(i0[0], i1[1]);
    let z11 = inp.depth.load(i1[0], i1[1]);
    let lo = min(min(z00, z10), min(z01, z11));
    let hi = max(max(z00, z10), max(z01, z11));
    if !depth_close(lo, hi, depth_break) {
        return -1.0;
    }
    if lo == hi {
        return lo;
    }
    let w0 = (1.0 / z00) * (1.0 - t[0]) + (1.0 / z10) * t[0];
    let w1 = (1.0 / z01) * (1.0 - t[0]) + (1.0 / z11) * t[0];
    1.0 / (w0 * (1.0 - t[1]) + w1 * t[1])
}

/// The fallback's per-pixel body (WGSL `pst_sweep_pixel`): the pixel's own nearest row, its
/// lit whole columns' leaves summed in column order.
pub fn pst_sweep_pixel(
    inp: &PstInputs,
    variant: &PartialSumTreeVariant,
    x: u32,
    y: u32,
) -> [f32; 3] {
    let f = inp.frame;
    let spot = variant.light == LightKind::Spot;
    let white = TexArray::white();
    let tint = variant.cookie.then(|| Tint {
        cookie: inp.cookie.unwrap_or(&white),
        rank_vecs: variant.rank_vecs(),
    });
    let r = pst_ray(
        inp,
        spot,
        [x as f32 + 0.5, y as f32 + 0.5],
        inp.depth.load(x, y),
        tint,
    );
    if r.marched {
        return r.color.to_array();
    }
    let delta = inp.slices[r.row as usize].delta;
    let row_e = pst_row_e(f, spot, r.row);
    let n = pst_columns_crossed(f, &r, delta);
    if n == 0 {
        return [0.0; 3];
    }
    let rv = variant.rank_vecs();
    let mut sum = Vec3::ZERO;
    for h in 0..variant.leaf_vecs() {
        let mut p = Vec4::ZERO;
        for i in 0..n - 1 {
            if r.d <= inp.rectified.load(i, r.row) {
                p += pst_leaf(inp, spot, i, row_e, delta, h, tint);
            }
        }
        sum[(h / rv) as usize] += p.dot(beta_at(inp, r.theta, h % rv));
    }
    if !variant.cookie {
        sum = Vec3::splat(sum.x);
    }
    let (a, b) = pst_terms(inp, spot, &r, r.row, delta, n, tint);
    (xyz(f.light_color) * ((a * sum).max(Vec3::ZERO) + b)).to_array()
}

/// The samples pass: every slice swept (slices in parallel). Returns the
/// `epipolar_samples` texture (layout: `common_sampling::EpipolarSamples`; `evaluated`
/// counts every sample, `depth_refined` and `light_refined` 0: nothing is interpolated) and
/// the sweep's counts.
pub fn pst_sweep(
    variant: &PartialSumTreeVariant,
    inp: &PstInputs,
) -> (EpipolarSamples, SweepCounts) {
    use rayon::prelude::*;
    let f = inp.frame;
    let spot = variant.light == LightKind::Spot;
    let knobs = variant.sampling_knobs();
    let (n_slices, m) = (knobs.slices, knobs.slice_samples);
    let screen = [f.sizes[0], f.sizes[1]];
    let width = f.sizes[2];
    // vec4s per leaf and tree entry; the rank's.
    let rv = variant.leaf_vecs();
    let rank_vecs = variant.rank_vecs();
    let white = TexArray::white();
    let tint = variant.cookie.then(|| Tint {
        cookie: inp.cookie.unwrap_or(&white),
        rank_vecs,
    });
    let layout = epipolar_layout(&EpipolarCamera::of_frame(f), screen, n_slices);
    let depth_break = knobs.depth_break_fraction();
    let lines: Vec<(Vec<[f32; 4]>, SweepCounts)> = (0..n_slices)
        .into_par_iter()
        .map(|s| {
            let u = slice_direction(&layout, s);
            let span = slice_span(&layout, s, screen, m);
            let mut out = vec![[0.0f32; 4]; m as usize + 1];
            out[m as usize] = [u[0], u[1], span[0], span[1]];
            // Samples on the slice's line (see the WGSL): one row per slice.
            let at = |k: u32| {
                let t = span[0] + k as f32 * span[1];
                [layout.origin[0] + u[0] * t, layout.origin[1] + u[1] * t]
            };
            let row = pst_ray(inp, spot, at(m - 1), 0.0, tint).row;
            let delta = inp.slices[row as usize].delta;
            let row_e = pst_row_e(f, spot, row);
            let mut counts = SweepCounts::default();

            // 1. The samples.
            const NONE: u32 = u32::MAX;
            let mut q_end = vec![NONE; m as usize];
            let mut q_d = vec![0.0f32; m as usize];
            let mut q_theta = vec![0.0f32; m as usize];
            let mut q_ab = vec![(0.0f32, Vec3::ZERO); m as usize];
            let mut v = 0u32;
            for k in 0..m {
                let p = slice_sample_pixel(&layout, u, span, k, screen);
                let z = inp.depth.load(p[0], p[1]);
                let footprint = pst_footprint_depth(inp, at(k), screen, depth_break);
                let r = if footprint < 0.0 {
                    counts.edges += 1;
                    pst_ray(inp, spot, [p[0] as f32 + 0.5, p[1] as f32 + 0.5], z, tint)
                } else {
                    pst_ray(inp, spot, at(k), footprint, tint)
                };
                let n = pst_columns_crossed(f, &r, delta);
                let ku = k as usize;
                if r.marched || n == 0 {
                    let c = round_f16_rgb(r.color.to_array());
                    out[ku] = [c[0], c[1], c[2], z];
                    counts.direct += 1;
                } else {
                    q_ab[ku] = pst_terms(inp, spot, &r, row, delta, n, tint);
                    q_end[ku] = n - 1;
                    q_d[ku] = r.d;
                    q_theta[ku] = r.theta;
                    v += 1;
                }
            }

            // 2. The queries in order of their prefix end (ties by sample index: the WGSL's
            // insertion per tree, trees in order), and d sorted by insertion in the direction
            // it runs along the slice (ties: by sample index up, reversed down).
            let mut by_end: Vec<u32> = (0..m).filter(|&k| q_end[k as usize] != NONE).collect();
            by_end.sort_by_key(|&k| q_end[k as usize]);
            let live: Vec<usize> = (0..m as usize).filter(|&k| q_end[k] != NONE).collect();
            let mut sorted: Vec<f32> = Vec::with_capacity(live.len());
            let mut order: Vec<u32> = Vec::with_capacity(live.len());
            if let (Some(&first), Some(&last)) = (live.first(), live.last()) {
                let up = q_d[first] <= q_d[last];
                for &k in &live {
                    let d = q_d[k];
                    let mut j = sorted.len();
                    while j > 0
                        && if up {
                            sorted[j - 1] > d
                        } else {
                            sorted[j - 1] < d
                        }
                    {
                        j -= 1;
                    }
                    sorted.insert(j, d);
                    order.insert(j, k as u32);
                }
                if !up {
                    sorted.reverse();
                    order.reverse();
                }
            }
            let mut q_rank = vec![0u32; m as usize];
            for (j, &k) in order.iter().enumerate() {
                q_rank[k as usize] = j as u32;
            }

            // 3. Every column's count of queries that see it lit, and its leaf.
            let mut columns = vec![0u32; width as usize];
            let mut leaves = vec![Vec4::ZERO; (width * rv) as usize];
            for i in 0..width {
                let occluder = inp.rectified.load(i, row);
                let b = sorted.partition_point(|&d| d <= occluder) as u32;
                columns[i as usize] = b;
                if b > 0 {
                    for h in 0..rv {
                        leaves[(i * rv + h) as usize] =
                            pst_leaf(inp, spot, i, row_e, delta, h, tint);
                    }
                }
            }

            // 4. The sweep over TREES trees of CW columns each, then the exclusive prefixes
            // of the trees, then every query.
            let trees_n = TREES as usize;
            let cw = width.div_ceil(TREES);
            let stride = (m * rv) as usize;
            let mut trees = vec![Vec4::ZERO; trees_n * stride];
            let mut partials = vec![Vec4::ZERO; stride];
            for c in 0..TREES {
                let tree = c as usize * stride;
                let lo = c * cw;
                let hi = if c + 1 == TREES {
                    width
                } else {
                    (lo + cw).min(width)
                };
                let mut next =
                    by_end[..v as usize].partition_point(|&k| q_end[k as usize] < lo) as u32;
                for i in lo..=hi {
                    while next < v
                        && q_end[by_end[next as usize] as usize] == i
                        && (i < hi || c + 1 == TREES)
                    {
                        let k = by_end[next as usize] as usize;
                        next += 1;
                        for h in 0..rv {
                            let mut p = Vec4::ZERO;
                            let mut j = v - q_rank[k];
                            while j > 0 {
                                p += trees[tree + ((j - 1) * rv + h) as usize];
                                j -= j & j.wrapping_neg();
                            }
                            partials[k * rv as usize + h as usize] = p;
                        }
                    }
                    if i == hi {
                        break;
                    }
                    let b = columns[i as usize];
                    if b > 0 {
                        counts.inserted += 1;
                        for h in 0..rv {
                            let leaf = leaves[(i * rv + h) as usize];
                            let mut j = v - b + 1;
                            while j <= v {
                                trees[tree + ((j - 1) * rv + h) as usize] += leaf;
                                j += j & j.wrapping_neg();
                            }
                        }
                    }
                }
            }
            for x in 0..(v * rv) as usize {
                let mut running = Vec4::ZERO;
                for c in 0..trees_n {
                    let own = trees[c * stride + x];
                    trees[c * stride + x] = running;
                    running += own;
                }
            }
            for k in 0..m as usize {
                if q_end[k] == NONE {
                    continue;
                }
                let tree = (q_end[k] / cw).min(TREES - 1) as usize * stride;
                let mut dotp = Vec3::ZERO;
                for h in 0..rv {
                    let mut p = partials[k * rv as usize + h as usize];
                    let mut j = v - q_rank[k];
                    while j > 0 {
                        p += trees[tree + ((j - 1) * rv + h) as usize];
                        j -= j & j.wrapping_neg();
                    }
                    dotp[(h / rank_vecs) as usize] +=
                        p.dot(beta_at(inp, q_theta[k], h % rank_vecs));
                }
                if !variant.cookie {
                    dotp = Vec3::splat(dotp.x);
                }
                let (a, b) = q_ab[k];
                let c = xyz(f.light_color) * ((a * dotp).max(Vec3::ZERO) + b);
                let c = round_f16_rgb(c.to_array());
                let p = slice_sample_pixel(&layout, u, span, k as u32, screen);
                out[k] = [c[0], c[1], c[2], inp.depth.load(p[0], p[1])];
                counts.queries += 1;
            }
            (out, counts)
        })
        .collect();
    let mut counts = SweepCounts::default();
    let mut data = Vec::with_capacity(((n_slices + 1) * (m + 1)) as usize);
    for (line, c) in lines {
        data.extend(line);
        counts.queries += c.queries;
        counts.inserted += c.inserted;
        counts.direct += c.direct;
        counts.edges += c.edges;
    }
    data.push([
        layout.origin[0],
        layout.origin[1],
        layout.axis[0],
        layout.axis[1],
    ]);
    data.push([
        layout.phi_start,
        layout.dphi,
        if layout.wrap { 1.0 } else { 0.0 },
        0.0,
    ]);
    data.resize(((n_slices + 1) * (m + 1)) as usize, [0.0; 4]);
    (
        EpipolarSamples {
            samples: TexArray {
                width: m + 1,
                height: n_slices + 1,
                layers: 1,
                data,
            },
            evaluated: u64::from(n_slices) * u64::from(m),
            depth_refined: 0,
            light_refined: 0,
        },
        counts,
    )
}
