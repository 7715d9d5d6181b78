//! CPU mirror of `shaderlib/templates/volume_march.wgsl`: per pixel, the interval `[t_f, t_b]`
//! of the view ray that can hold a shadow boundary (from `volume_bounds`'s bins of the two
//! rectified rows around the ray) marched against the standard shadow map, the head and the
//! tail added in closed form; pixels near the epipole or the anti-epipole marched whole.
//! Conventions: `scatter_frame::hybrid_volume`.
//!
//! The WGSL kernel body is one function; here the interval ([`pixel_span`]) and its sum
//! ([`span_sum`]) are split out, so that the tests can check the interval against a
//! brute-force cast of the shadow map's volume and the march against `span_march` over the
//! whole ray.

use super::common_cookie::{epipole_march_cookie, span_march_cookie, spot_segment_cookie};
use super::common_epipolar::{
    edge_t, epipole_march, in_epipole_disc, normalised_depth, pixel_dir, ray_column, ray_row_coord,
    ray_theta, row_index, span_march, spot_segment,
};
use super::common_model::{max, max_u, min, phase_hg, transmittance_between};
use super::common_sampling::{
    EpipolarCamera, EpipolarSamples, SampledOutput, epipolar_samples, run_sampled,
};
use super::texture::{Tex, TexArray, xyz};
use super::volume_bounds::{VolumeBounds, depth_bin};
use glam::Vec3;
use scatter_shaderlib::hybrid_volume::{HybridVolumeVariant, NO_EDGE};
use scatter_shaderlib::prefiltered::{FrameUniforms, LightKind, SliceParams};

/// The bindings of `volume_march`.
pub struct MarchInputs<'a> {
    /// Frame uniforms.
    pub frame: &'a FrameUniforms,
    /// Per-slice table (after `slice_fit`).
    pub slices: &'a [SliceParams],
    /// Linear view depth, screen-sized.
    pub depth: &'a Tex,
    /// The standard shadow map.
    pub shadow_map: &'a Tex,
    /// The rectified map (`rectify`).
    pub rectified: &'a Tex,
    /// `volume_bounds`'s bins.
    pub crossings: &'a VolumeBounds,
    /// A `cookie` variant's spot cookie (`None` otherwise).
    pub cookie: Option<&'a TexArray>,
}

/// What one rectified row says about a ray: the interval (`t_f > t_b`: no crossing) and the
/// visibility before it (`head`) and after it (`tail`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowSpan {
    /// Start of the row's interval.
    pub t_f: f32,
    /// End of the row's interval.
    pub t_b: f32,
    /// Whether the ray is lit before `t_f`.
    pub head: bool,
    /// Whether the ray is lit after `t_b`.
    pub tail: bool,
}

/// A pixel's interval and the visibility outside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelSpan {
    /// Surface distance.
    pub s: f32,
    /// Start of the marched interval.
    pub t_f: f32,
    /// End of the marched interval (`t_f <= t_b <= s`; equal: nothing marched).
    pub t_b: f32,
    /// Visibility of `[0, t_f]` (0 or 1).
    pub head: f32,
    /// Visibility of `[t_b, s]` (0 or 1).
    pub tail: f32,
}

/// Row `row`'s view of a ray of depth `d` (bin `bin`, view angle `theta`, surface at `s`)
/// whose surface point has column coordinate `col` (before the row's spacing).
#[allow(
    clippy::too_many_arguments,
    reason = "the WGSL helper's parameters, one for one"
)]
pub fn row_span(
    inp: &MarchInputs,
    pad: u32,
    row: u32,
    col: f32,
    d: f32,
    bin: u32,
    theta: f32,
    s: f32,
    spot: bool,
) -> RowSpan {
    let f = inp.frame;
    let width = f.sizes[2];
    let delta = inp.slices[row as usize].delta;
    let xs = col / delta;
    // Texels the ray crosses (NaN or negative x_s: none).
    let n = min((if xs > 0.0 { xs } else { 0.0 }).ceil(), width as f32) as u32;
    if n == 0 {
        // No texel: nothing known, march it all.
        return RowSpan {
            t_f: 0.0,
            t_b: s,
            head: true,
            tail: true,
        };
    }
    let head = d <= inp.rectified.load(0, row);
    let [e0, e1] = inp.crossings.get(row, bin);
    if e0 == NO_EDGE || e0 >= n {
        return RowSpan {
            t_f: s,
            t_b: 0.0,
            head,
            tail: head,
        };
    }
    let last = e1.min(n - 1);
    let tail = d <= inp.rectified.load(last, row);
    let first = e0.saturating_sub(pad);
    RowSpan {
        t_f: edge_t(f, first, n, delta, theta, s, spot),
        t_b: edge_t(f, last + pad, n, delta, theta, s, spot),
        head,
        tail,
    }
}

/// The surface distance of pixel `(x, y)` along `dir`: depth clamped to `[0, far]` (engines
/// with an infinite far plane write +inf on sky pixels).
pub fn surface_distance(f: &FrameUniforms, depth: &Tex, x: u32, y: u32, dir: Vec3) -> f32 {
    min(max(depth.load(x, y), 0.0), f.theta[2]) / max(dir.dot(xyz(f.cam_forward)), 1e-6)
}

/// The interval of pixel `(x, y)` and the visibility outside it, or `None` in the epipole
/// discs (marched whole).
pub fn pixel_span(inp: &MarchInputs, pad: u32, x: u32, y: u32, spot: bool) -> Option<PixelSpan> {
    let f = inp.frame;
    let eye = xyz(f.eye);
    let dir = pixel_dir(f, x, y);
    let s = surface_distance(f, inp.depth, x, y, dir);
    if in_epipole_disc(f, [x as f32 + 0.5, y as f32 + 0.5]) {
        return None;
    }
    // The ray's depth and the two rows whose slices bracket it (row r's centre is r + 0.5).
    let rows = f.sizes[3];
    let wrap = f.anti_epipole[3] > 0.5;
    let theta = ray_theta(f, dir);
    let yc = ray_row_coord(f, dir);
    let d = normalised_depth(theta, f.theta[0], f.theta[1]);
    let bin = depth_bin(d, inp.crossings.bins);
    let col = ray_column(f, eye, dir, s, theta, spot);
    let j = (yc - 0.5).floor();
    let a = row_span(
        inp,
        pad,
        row_index(j, rows, wrap),
        col,
        d,
        bin,
        theta,
        s,
        spot,
    );
    let b = row_span(
        inp,
        pad,
        row_index(j + 1.0, rows, wrap),
        col,
        d,
        bin,
        theta,
        s,
        spot,
    );
    let mut t_f = a.t_f.min(b.t_f);
    let mut t_b = a.t_b.max(b.t_b);
    if a.head != b.head {
        t_f = 0.0;
    }
    if a.tail != b.tail {
        t_b = s;
    }
    if t_b < t_f {
        // Neither row sees a crossing (and they agree): one visibility for the whole ray.
        t_f = s;
        t_b = s;
    }
    let vis = |lit: bool| if lit { 1.0 } else { 0.0 };
    Some(PixelSpan {
        s,
        t_f,
        t_b,
        head: vis(a.head),
        tail: vis(a.tail),
    })
}

/// Unshadowed in-scattering over `[a, b]` (the head or the tail), without `sigma_s p E` for
/// the sun: the sun's closed form; for a spot, Gauss-Legendre panels no coarser than the
/// march, `samples / 4` panels of 4 nodes (at least the frame's spot quadrature), so that the
/// head and tail do not cap the accuracy the samples buy (with the frame's 8 panels,
/// `spot_grate/grazing` stalled at 0.27 % from 64 samples on, raymarch N = 64 0.24 %).
pub fn closed_form(
    f: &FrameUniforms,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    samples: u32,
    spot: bool,
) -> f32 {
    if spot {
        return spot_segment(
            f,
            eye,
            dir,
            a,
            b,
            max_u(max_u(f.sizes2[2] / 4, samples / 4), 1),
        );
    }
    transmittance_between(f.medium[0], a, b)
}

/// [`closed_form`] of a spot with a cookie (RGB): at least as many panels, one per cookie
/// texel crossed.
#[allow(clippy::too_many_arguments, reason = "closed_form's and the cookie")]
pub fn closed_form_cookie(
    f: &FrameUniforms,
    cookie: &TexArray,
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    samples: u32,
) -> Vec3 {
    spot_segment_cookie(
        f,
        cookie,
        eye,
        dir,
        a,
        b,
        max_u(max_u(f.sizes2[2] / 4, samples / 4), 1),
    )
}

/// [`span_sum`] of a spot with a cookie (RGB, without the light colour).
pub fn span_sum_cookie(
    f: &FrameUniforms,
    sm: &Tex,
    cookie: &TexArray,
    dir: Vec3,
    p: &PixelSpan,
    samples: u32,
) -> Vec3 {
    let eye = xyz(f.eye);
    let mut total = Vec3::ZERO;
    if p.head > 0.5 {
        total += closed_form_cookie(f, cookie, eye, dir, 0.0, p.t_f, samples);
    }
    if p.t_b > p.t_f {
        total += span_march_cookie(f, sm, cookie, eye, dir, p.t_f, p.t_b, samples);
    }
    if p.tail > 0.5 {
        total += closed_form_cookie(f, cookie, eye, dir, p.t_b, p.s, samples);
    }
    total
}

/// The sum of a pixel's span: head and tail in closed form ([`closed_form`]), `[t_f, t_b]`
/// marched with `samples` samples (without `sigma_s p E` for the sun).
pub fn span_sum(
    f: &FrameUniforms,
    sm: &Tex,
    dir: Vec3,
    p: &PixelSpan,
    samples: u32,
    spot: bool,
) -> f32 {
    let eye = xyz(f.eye);
    let mut total = 0.0;
    if p.head > 0.5 {
        total += closed_form(f, eye, dir, 0.0, p.t_f, samples, spot);
    }
    if p.t_b > p.t_f {
        total += span_march(f, sm, eye, dir, p.t_f, p.t_b, samples, spot);
    }
    if p.tail > 0.5 {
        total += closed_form(f, eye, dir, p.t_b, p.s, samples, spot);
    }
    total
}

/// The kernel's per-pixel body (`volume_march_pixel`): the radiance of pixel `(x, y)` before
/// rounding.
pub fn volume_march_pixel(
    variant: &HybridVolumeVariant,
    inp: &MarchInputs,
    x: u32,
    y: u32,
) -> [f32; 3] {
    let f = inp.frame;
    let spot = variant.light == LightKind::Spot;
    let eye = xyz(f.eye);
    let dir = pixel_dir(f, x, y);
    let color = xyz(f.light_color);
    let c = match (pixel_span(inp, variant.pad, x, y, spot), inp.cookie) {
        (None, cookie) => {
            // Near the epipole and the anti-epipole the rectification degenerates: march.
            let s = surface_distance(f, inp.depth, x, y, dir);
            match cookie {
                Some(cookie) => {
                    epipole_march_cookie(f, inp.shadow_map, cookie, eye, dir, s) * color
                }
                None => epipole_march(f, inp.shadow_map, eye, dir, s, spot) * color,
            }
        }
        (Some(p), Some(cookie)) => {
            color * span_sum_cookie(f, inp.shadow_map, cookie, dir, &p, variant.samples)
        }
        (Some(p), None) => {
            let total = span_sum(f, inp.shadow_map, dir, &p, variant.samples, spot);
            let mut l = total;
            if !spot {
                l = f.medium[1] * phase_hg(f.medium[2], -xyz(f.light_dir).dot(dir)) * total;
            }
            color * l
        }
    };
    [c.x, c.y, c.z]
}

/// Runs the kernel over the screen through its sampling stage (every pixel, or `lowres` /
/// `epipolar` samples with their upsampling).
pub fn volume_march(variant: &HybridVolumeVariant, inp: &MarchInputs) -> SampledOutput {
    run_sampled(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        &EpipolarCamera::of_frame(inp.frame),
        &|x, y| volume_march_pixel(variant, inp, x, y),
    )
}

/// Every pixel's interval (`None`: an epipole disc), row-major: diagnostics, not a pass.
pub fn pixel_spans(variant: &HybridVolumeVariant, inp: &MarchInputs) -> Vec<Option<PixelSpan>> {
    use rayon::prelude::*;
    let spot = variant.light == LightKind::Spot;
    let (w, h) = (inp.frame.sizes[0], inp.frame.sizes[1]);
    (0..h)
        .into_par_iter()
        .flat_map_iter(|y| (0..w).map(move |x| pixel_span(inp, variant.pad, x, y, spot)))
        .collect()
}

/// `volume_march` of an `epipolar` variant: the samples of every slice (sampling pass 1).
pub fn volume_march_epipolar_samples(
    variant: &HybridVolumeVariant,
    inp: &MarchInputs,
) -> EpipolarSamples {
    epipolar_samples(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        &EpipolarCamera::of_frame(inp.frame),
        &|x, y| volume_march_pixel(variant, inp, x, y),
    )
}
