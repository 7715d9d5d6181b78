//! CPU mirror of `shaderlib/templates/minmax_traverse.wgsl`: per pixel, the rectified row
//! marched through its 1D min-max tree (Chen et al. 2011), skipping nodes wholly lit or
//! wholly shadowed for the ray's depth; pixels near the epipole or the anti-epipole
//! ray-marched against the standard shadow map, as in `scatter`. Conventions and the
//! estimate: `scatter_frame::minmax`.
//!
//! The WGSL kernel body is one function; here it is split into the pixel set-up
//! ([`pixel_ray`]), the walk ([`walk_tree`]) and the final scaling ([`radiance`]), so that
//! [`minmax_brute_main`], the brute-force march over every texel of the same rectified row
//! (the reference the hierarchy must equal), shares everything but the walk.

use super::common_cookie::{epipole_march_cookie, lit_span_cookie};
use super::common_epipolar::{
    epipole_march, in_epipole_disc, normalised_depth, pixel_dir, ray_column, ray_row_coord,
    ray_theta, row_index,
};
use super::common_minmax::{level_offset, tree_levels};
use super::common_model::{max, min, phase_hg};
use super::common_sampling::{EpipolarCamera, EpipolarSamples, epipolar_samples, run_sampled};
use super::texture::{Tex, TexArray, quantise, xyz};
use glam::Vec3;
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::prefiltered::{FrameUniforms, LightKind, SliceParams, Storage};

/// The bindings of `minmax_traverse`.
pub struct TraverseInputs<'a> {
    /// Frame uniforms.
    pub frame: &'a FrameUniforms,
    /// Per-slice table.
    pub slices: &'a [SliceParams],
    /// Linear view depth, screen-sized.
    pub depth: &'a Tex,
    /// The standard shadow map.
    pub shadow_map: &'a Tex,
    /// The min-max trees (from `minmax_build`).
    pub tree: &'a TexArray,
    /// A `cookie` variant's spot cookie (`None` otherwise).
    pub cookie: Option<&'a TexArray>,
}

pub use super::common_epipolar::{edge_t, lit_span};

/// A pixel's ray in rectified space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowRay {
    /// Eye position.
    pub eye: Vec3,
    /// Unit view direction.
    pub dir: Vec3,
    /// Distance to the surface.
    pub s: f32,
    /// Continuous row coordinate (the row is its `floor`; diagnostics only).
    pub yc: f32,
    /// Rectified row (nearest slice).
    pub row: u32,
    /// The row's column spacing.
    pub delta: f32,
    /// View angle to the axis.
    pub theta: f32,
    /// Normalised rectified depth of the ray.
    pub d: f32,
    /// Texels the ray crosses (`0 .. n`).
    pub n: u32,
}

/// What the set-up of a pixel decided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pixel {
    /// Near the epipole or the anti-epipole: the marched radiance the kernel stores.
    Marched([f32; 4]),
    /// The pixel's ray in its rectified row.
    Row(RowRay),
}

/// The kernel's pixel set-up for pixel `id` (None: out of range).
pub fn pixel_ray(id: [u32; 3], spot: bool, inp: &TraverseInputs) -> Option<Pixel> {
    let f = inp.frame;
    let (x, y) = (id[0], id[1]);
    if x >= f.sizes[0] || y >= f.sizes[1] {
        return None;
    }
    let eye = xyz(f.eye);
    let dir = pixel_dir(f, x, y);
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s =
        min(max(inp.depth.load(x, y), 0.0), f.theta[2]) / max(dir.dot(xyz(f.cam_forward)), 1e-6);
    let color = xyz(f.light_color);

    // Near the epipole and the anti-epipole the rectification degenerates: march instead.
    if in_epipole_disc(f, [x as f32 + 0.5, y as f32 + 0.5]) {
        let l = match inp.cookie {
            Some(cookie) => epipole_march_cookie(f, inp.shadow_map, cookie, eye, dir, s) * color,
            None => epipole_march(f, inp.shadow_map, eye, dir, s, spot) * color,
        };
        return Some(Pixel::Marched([l.x, l.y, l.z, 1.0]));
    }

    // Rectified coordinates of the surface point: the nearest row, its column x_s, depth d.
    let rows = f.sizes[3];
    let width = f.sizes[2];
    let wrap = f.anti_epipole[3] > 0.5;
    let theta = ray_theta(f, dir);
    let yc = ray_row_coord(f, dir);
    let row = row_index(yc.floor(), rows, wrap);
    let delta = inp.slices[row as usize].delta;
    let d = normalised_depth(theta, f.theta[0], f.theta[1]);
    let xs = ray_column(f, eye, dir, s, theta, spot) / delta;
    // Texels the ray crosses (NaN or negative x_s: none).
    let n = min((if xs > 0.0 { xs } else { 0.0 }).ceil(), width as f32) as u32;
    Some(Pixel::Row(RowRay {
        eye,
        dir,
        s,
        yc,
        row,
        delta,
        theta,
        d,
        n,
    }))
}

/// The kernel's walk of the tree: climb to the largest aligned node inside `[i, n)`, descend
/// while mixed; every maximal lit run adds [`lit_span`] ([`lit_span_cookie`] with a cookie).
/// Returns the sum (RGB) and the number of nodes visited.
pub fn walk_tree(
    f: &FrameUniforms,
    tree: &TexArray,
    r: &RowRay,
    spot: bool,
    cookie: Option<&TexArray>,
) -> (Vec3, u32) {
    let width = f.sizes[2];
    let (eye, dir, s, d, n) = (r.eye, r.dir, r.s, r.d, r.n);
    let levels = tree_levels(width);
    let mut total = Vec3::ZERO;
    let mut in_run = false;
    let mut run_a = 0.0;
    let mut visits = 0;
    let mut i = 0u32;
    while i < n {
        let mut k = 0u32;
        while k + 1 < levels && (i & ((2u32 << k) - 1)) == 0 && i + (2u32 << k) <= n {
            k += 1;
        }
        let mut lit = false;
        loop {
            let node = tree.load(level_offset(k, width) + (i >> k), r.row, 0);
            visits += 1;
            if d <= node[0] {
                lit = true;
                break;
            }
            if d > node[1] || k == 0 {
                break;
            }
            k -= 1;
        }
        if lit != in_run {
            let t = edge_t(f, i, n, r.delta, r.theta, s, spot);
            if lit {
                run_a = t;
            } else {
                total += span(f, cookie, eye, dir, run_a, t, spot);
            }
            in_run = lit;
        }
        i += 1u32 << k;
    }
    if in_run {
        total += span(f, cookie, eye, dir, run_a, s, spot);
    }
    (total, visits)
}

/// The brute-force walk: every texel `0 .. n` of the row, lit iff `d <= d_i` read straight
/// from the rectified map; every maximal lit run adds [`lit_span`] ([`lit_span_cookie`] with a
/// cookie). Returns the sum (RGB) and the number of texels visited (`n`).
pub fn walk_texels(
    f: &FrameUniforms,
    rectified: &Tex,
    r: &RowRay,
    spot: bool,
    cookie: Option<&TexArray>,
) -> (Vec3, u32) {
    let (eye, dir, s, d, n) = (r.eye, r.dir, r.s, r.d, r.n);
    let mut total = Vec3::ZERO;
    let mut in_run = false;
    let mut run_a = 0.0;
    for i in 0..n {
        let lit = d <= rectified.load(i, r.row);
        if lit != in_run {
            let t = edge_t(f, i, n, r.delta, r.theta, s, spot);
            if lit {
                run_a = t;
            } else {
                total += span(f, cookie, eye, dir, run_a, t, spot);
            }
            in_run = lit;
        }
    }
    if in_run {
        total += span(f, cookie, eye, dir, run_a, s, spot);
    }
    (total, n)
}

/// A lit run's unshadowed in-scattering: [`lit_span`] in every channel, or
/// [`lit_span_cookie`] with a cookie.
#[allow(
    clippy::too_many_arguments,
    reason = "the WGSL call's arguments and the cookie"
)]
fn span(
    f: &FrameUniforms,
    cookie: Option<&TexArray>,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    spot: bool,
) -> Vec3 {
    match cookie {
        Some(cookie) => lit_span_cookie(f, cookie, eye, dir, a, b),
        None => Vec3::splat(lit_span(f, eye, dir, a, b, spot)),
    }
}

/// The stored radiance of a walked ray's sum (`sigma_s p E` for the sun, `I` for a spot).
pub fn radiance(f: &FrameUniforms, r: &RowRay, total: f32, spot: bool) -> [f32; 4] {
    radiance_rgb(f, r, Vec3::splat(total), spot)
}

/// [`radiance`] of an RGB sum (a spot's cookie).
pub fn radiance_rgb(f: &FrameUniforms, r: &RowRay, total: Vec3, spot: bool) -> [f32; 4] {
    let mut l = total;
    if !spot {
        l = f.medium[1] * phase_hg(f.medium[2], -xyz(f.light_dir).dot(r.dir)) * total;
    }
    let c = xyz(f.light_color) * l;
    [c.x, c.y, c.z, 1.0]
}

/// The kernel body for pixel `id`; returns the rgba16float texel it stores (before
/// rounding) and the tree nodes visited (0 for a marched pixel).
pub fn minmax_traverse_main(
    id: [u32; 3],
    variant: &MinmaxVariant,
    inp: &TraverseInputs,
) -> Option<([f32; 4], u32)> {
    let spot = variant.light == LightKind::Spot;
    Some(match pixel_ray(id, spot, inp)? {
        Pixel::Marched(c) => (c, 0),
        Pixel::Row(r) => {
            let (total, visits) = walk_tree(inp.frame, inp.tree, &r, spot, inp.cookie);
            (radiance_rgb(inp.frame, &r, total, spot), visits)
        }
    })
}

/// The brute-force counterpart of [`minmax_traverse_main`]: the same pixel, its row walked
/// texel by texel over `rectified` (not the tree).
pub fn minmax_brute_main(
    id: [u32; 3],
    variant: &MinmaxVariant,
    inp: &TraverseInputs,
    rectified: &Tex,
) -> Option<([f32; 4], u32)> {
    let spot = variant.light == LightKind::Spot;
    Some(match pixel_ray(id, spot, inp)? {
        Pixel::Marched(c) => (c, 0),
        Pixel::Row(r) => {
            let (total, visits) = walk_texels(inp.frame, rectified, &r, spot, inp.cookie);
            (radiance_rgb(inp.frame, &r, total, spot), visits)
        }
    })
}

/// Per-pixel results of a whole-screen march.
#[derive(Clone, Debug)]
pub struct TraverseImage {
    /// Radiance as stored in rgba16float, screen-sized.
    pub output: TexArray,
    /// Radiance before rounding (f32), row-major.
    pub exact: Vec<[f32; 4]>,
    /// Nodes (tree) or texels (brute force) visited per pixel, row-major.
    pub visits: Vec<u32>,
}

fn run_pixels(
    f: &FrameUniforms,
    body: &(dyn Fn([u32; 3]) -> Option<([f32; 4], u32)> + Sync),
) -> TraverseImage {
    use rayon::prelude::*;
    let (w, h) = (f.sizes[0], f.sizes[1]);
    let results: Vec<([f32; 4], u32)> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| (0..w).map(move |x| body([x, y, 0]).unwrap_or(([0.0; 4], 0))))
        .collect();
    TraverseImage {
        output: TexArray {
            width: w,
            height: h,
            layers: 1,
            data: results
                .iter()
                .map(|(c, _)| c.map(|v| quantise(v, Storage::Rgba16float)))
                .collect(),
        },
        exact: results.iter().map(|(c, _)| *c).collect(),
        visits: results.iter().map(|(_, v)| *v).collect(),
    }
}

/// Runs every pixel through the tree (rows in parallel). A sampled variant runs through
/// [`run_sampled`] instead: `output` is then the upsampled image, `exact` its values and
/// `visits` empty.
pub fn minmax_traverse(variant: &MinmaxVariant, inp: &TraverseInputs) -> TraverseImage {
    let knobs = variant.sampling_knobs();
    if !knobs.is_sampled() {
        return run_pixels(inp.frame, &|id| minmax_traverse_main(id, variant, inp));
    }
    let sampled = run_sampled(
        &knobs,
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        &EpipolarCamera::of_frame(inp.frame),
        &|x, y| {
            let c = minmax_traverse_main([x, y, 0], variant, inp).map_or([0.0; 4], |(c, _)| c);
            [c[0], c[1], c[2]]
        },
    );
    TraverseImage {
        exact: sampled.output.data.clone(),
        output: sampled.output,
        visits: Vec::new(),
    }
}

/// Runs every pixel through the brute-force march over `rectified` (rows in parallel).
pub fn minmax_brute(
    variant: &MinmaxVariant,
    inp: &TraverseInputs,
    rectified: &Tex,
) -> TraverseImage {
    run_pixels(inp.frame, &|id| {
        minmax_brute_main(id, variant, inp, rectified)
    })
}

/// `minmax_traverse` of an `epipolar` variant: the samples of every slice (sampling pass 1).
pub fn minmax_traverse_epipolar_samples(
    variant: &MinmaxVariant,
    inp: &TraverseInputs,
) -> EpipolarSamples {
    epipolar_samples(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        &EpipolarCamera::of_frame(inp.frame),
        &|x, y| {
            let c = minmax_traverse_main([x, y, 0], variant, inp).map_or([0.0; 4], |(c, _)| c);
            [c[0], c[1], c[2]]
        },
    )
}
