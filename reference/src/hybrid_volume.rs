//! The hybrid shadow-volume method (Wyman & Ramsey 2008, issue 16) on the CPU: the reference
//! its kernels (`volume_bounds`, `volume_march`) will mirror, written before them, as
//! `partial_sum_tree` was.
//!
//! # The method
//!
//! Per pixel, the interval `[t_f, t_b]` of its view ray that can hold a shadow boundary. Outside
//! it the visibility is constant (the head `[0, t_f]` has the visibility of the ray's start,
//! the tail `[t_b, s]` that of its end), so those spans add the unshadowed in-scattering in
//! closed form (`lit_span`: the sun's exact transmittance integral, a spot's Gauss-Legendre
//! panels) times their visibility, and only `[t_f, t_b]` is marched against the standard
//! shadow map, `N` samples (`span_march`: uniform cells for the sun, equiangular strata for a
//! spot, as `raymarch` and the epipole discs).
//!
//! # Where the shadow volume comes from
//!
//! From the shadow map itself, on the epipolar layer every rectified family shares
//! (`depth_columns`, `slice_fit`, `rectify`): no mesh input, the inputs contract unchanged.
//! The shadow volume is the set of points behind the first occluder of their light ray; in an
//! epipolar slice its boundary is the rectified row's occluder depths `S_c` (column `c` = one
//! light ray of the slice) closed by walls between neighbouring columns. A view ray of the
//! slice has one rectified depth `d` for its whole length; texel `c` is lit iff `d <= S_c`, so
//! the ray crosses the boundary at column edge `c` (between texels `c - 1` and `c`) iff
//! `min(S_{c-1}, S_c) < d <= max(S_{c-1}, S_c)`: the wall between the two light rays.
//!
//! `volume_bounds` rasterises these walls, per rectified row, into `B` bins of the ray depth
//! `d` (bin `k` holds `d` in `[k / B, (k + 1) / B)`): every edge `c` is written into each bin
//! its wall's depth range `(min, max]` overlaps, keeping the first and the last edge. That is
//! the shadow-volume rasterisation of the paper restricted to one slice, where every view ray
//! of the slice is one point of a 1D "screen" (its depth `d`): the front-most and the
//! back-most boundary crossing per ray, for every ray of the slice at once, with no render
//! pipeline. A bin is conservative for every depth in it (it holds every edge any of its depths
//! crosses), so the head before the first edge and the tail after the last have one
//! visibility each, for the ray's own `d`.
//!
//! Per pixel (`volume_march`): the two rectified rows around the ray's slice angle (the ray
//! lies between their slices), each giving its first and last edge inside the ray's texels
//! `0 .. n`, padded by one texel on each side (the rectified texel samples the light ray at
//! its centre; the standard shadow map's own boundary lies within half a texel of the edge),
//! mapped to ray distances (`edge_t`). The pixel's interval is the union of the two rows'; a
//! head or tail whose visibility the two rows disagree on is marched too. Pixels near the
//! epipole or the anti-epipole are marched whole (`epipole_march`), as in every epipolar
//! family.

use crate::buffers::{GBuffer, ShadowMap};
use crate::image::Image;
use crate::kernels::common_epipolar::{
    edge_t, epipole_march, lit_span, normalised_depth, pixel_dir, ray_column, ray_row_coord,
    ray_theta, row_index, span_march,
};
use crate::kernels::common_model::phase_hg;
use crate::kernels::texture::{Tex, xyz};
use crate::kernels::{depth_columns, rectify, slice_fit};
use crate::scene::Scene;
use glam::Vec3;
use scatter_shaderlib::minmax::{MinmaxVariant, prepare_minmax};
use scatter_shaderlib::prefiltered::{
    FrameError, FrameSettings, FrameUniforms, LightKind, PrefilteredFrame, Resolutions, SliceParams,
};

/// No boundary crossing in a bin (`first` of an empty bin).
pub const NO_EDGE: u32 = u32::MAX;

/// The method's knobs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HybridSettings {
    /// Samples `N` marched in `[t_f, t_b]`.
    pub samples: u32,
    /// Depth bins `B` per rectified row.
    pub bins: u32,
    /// Texels each bound is padded by.
    pub pad: u32,
}

impl Default for HybridSettings {
    /// 32 samples, 256 bins, one texel of padding (16 samples miss 5 % on `window/grazing`,
    /// whose intervals hold 40 % of its rays: `tests/tests/hybrid_volume_reference.rs`).
    fn default() -> Self {
        Self {
            samples: 32,
            bins: 256,
            pad: 1,
        }
    }
}

/// The first and last boundary crossing (column edge) per rectified row and depth bin.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VolumeBounds {
    /// Bins per row.
    pub bins: u32,
    /// `[first, last]` edge, index `row * bins + bin`; `first == NO_EDGE`: none.
    pub edges: Vec<[u32; 2]>,
}

impl VolumeBounds {
    /// The edges of bin `bin` of row `row`.
    pub fn get(&self, row: u32, bin: u32) -> [u32; 2] {
        self.edges[(row * self.bins + bin) as usize]
    }
}

/// The bin of ray depth `d` among `bins` (clamped).
pub fn depth_bin(d: f32, bins: u32) -> u32 {
    let k = (d * bins as f32).floor();
    (if k > 0.0 { k } else { 0.0 } as u32).min(bins - 1)
}

/// `volume_bounds`: every rectified row's walls rasterised into `bins` depth bins (module
/// docs). Edge `c` (texels `c - 1`, `c`) with depth range `(lo, hi]` reaches the bins
/// `floor(lo B) ..= floor(hi B)`, exactly those whose depths `[k / B, (k + 1) / B)` meet it.
pub fn volume_bounds(f: &FrameUniforms, rectified: &Tex, bins: u32) -> VolumeBounds {
    let width = f.sizes[2];
    let rows = f.sizes[3];
    let mut edges = vec![[NO_EDGE, 0u32]; (rows * bins) as usize];
    for row in 0..rows {
        let base = (row * bins) as usize;
        let mut prev = rectified.load(0, row);
        for c in 1..width {
            let cur = rectified.load(c, row);
            let lo = prev.min(cur);
            let hi = prev.max(cur);
            prev = cur;
            if lo >= hi {
                continue;
            }
            let k0 = depth_bin(lo, bins);
            let k1 = depth_bin(hi, bins);
            for k in k0..=k1 {
                let e = &mut edges[base + k as usize];
                e[0] = e[0].min(c);
                e[1] = e[1].max(c);
            }
        }
    }
    VolumeBounds { bins, edges }
}

/// What one rectified row says about a ray: the visibility before `t_f` (`head`) and after
/// `t_b` (`tail`); `t_f > t_b` when it sees no crossing.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RowSpan {
    t_f: f32,
    t_b: f32,
    head: bool,
    tail: bool,
}

/// A pixel's interval and the visibility outside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelSpan {
    /// Surface distance.
    pub s: f32,
    /// Start of the marched interval.
    pub t_f: f32,
    /// End of the marched interval (`t_f <= t_b <= s`).
    pub t_b: f32,
    /// Visibility of `[0, t_f]` (0 or 1).
    pub head: f32,
    /// Visibility of `[t_b, s]` (0 or 1).
    pub tail: f32,
}

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
    /// `volume_bounds`'s edges.
    pub bounds: &'a VolumeBounds,
}

/// Row `row`'s view of a ray of depth `d` crossing column coordinate `col` (before the row's
/// spacing).
#[allow(
    clippy::too_many_arguments,
    reason = "the kernel's per-row locals, passed as the WGSL helper will take them"
)]
fn row_span(
    inp: &MarchInputs,
    row: u32,
    col: f32,
    d: f32,
    bin: u32,
    theta: f32,
    s: f32,
    pad: u32,
    spot: bool,
) -> RowSpan {
    let f = inp.frame;
    let width = f.sizes[2];
    let delta = inp.slices[row as usize].delta;
    let xs = col / delta;
    // Texels the ray crosses (NaN or negative x_s: none).
    let n = (if xs > 0.0 { xs } else { 0.0 }).ceil().min(width as f32) as u32;
    if n == 0 {
        // No texel: nothing known, march it all.
        return RowSpan {
            t_f: 0.0,
            t_b: s,
            head: true,
            tail: true,
        };
    }
    let lit = |c: u32| d <= inp.rectified.load(c, row);
    let [first, last] = inp.bounds.get(row, bin);
    if first == NO_EDGE || first >= n {
        let v = lit(0);
        return RowSpan {
            t_f: s,
            t_b: 0.0,
            head: v,
            tail: v,
        };
    }
    let last = last.min(n - 1);
    RowSpan {
        t_f: edge_t(f, first.saturating_sub(pad), n, delta, theta, s, spot),
        t_b: edge_t(f, last + pad, n, delta, theta, s, spot),
        head: lit(0),
        tail: lit(last),
    }
}

/// The interval of pixel `(x, y)` and the visibility outside it, or `None` in the epipole
/// discs (marched whole).
pub fn pixel_span(inp: &MarchInputs, x: u32, y: u32, pad: u32, spot: bool) -> Option<PixelSpan> {
    let f = inp.frame;
    let eye = xyz(f.eye);
    let dir = pixel_dir(f, x, y);
    let s = inp.depth.load(x, y).max(0.0).min(f.theta[2]) / dir.dot(xyz(f.cam_forward)).max(1e-6);
    if in_epipole_disc(f, x, y) {
        return None;
    }
    let rows = f.sizes[3];
    let wrap = f.anti_epipole[3] > 0.5;
    let theta = ray_theta(f, dir);
    let yc = ray_row_coord(f, dir);
    let d = normalised_depth(theta, f.theta[0], f.theta[1]);
    let bin = depth_bin(d, inp.bounds.bins);
    let col = ray_column(f, eye, dir, s, theta, spot);
    // The two rows whose slices bracket the ray (row r's centre is at r + 0.5).
    let j = (yc - 0.5).floor();
    let a = row_span(
        inp,
        row_index(j, rows, wrap),
        col,
        d,
        bin,
        theta,
        s,
        pad,
        spot,
    );
    let b = row_span(
        inp,
        row_index(j + 1.0, rows, wrap),
        col,
        d,
        bin,
        theta,
        s,
        pad,
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
    Some(PixelSpan {
        s,
        t_f,
        t_b,
        head: if a.head { 1.0 } else { 0.0 },
        tail: if a.tail { 1.0 } else { 0.0 },
    })
}

/// Whether pixel `(x, y)` lies in the epipole's or the anti-epipole's marched disc.
fn in_epipole_disc(f: &FrameUniforms, x: u32, y: u32) -> bool {
    let px = Vec3::new(x as f32 + 0.5, y as f32 + 0.5, 0.0);
    let radius = f.epipole[3];
    let near_epi =
        f.epipole[2] > 0.5 && (px - Vec3::new(f.epipole[0], f.epipole[1], 0.0)).length() < radius;
    let near_anti = f.anti_epipole[2] > 0.5
        && (px - Vec3::new(f.anti_epipole[0], f.anti_epipole[1], 0.0)).length() < radius;
    near_epi || near_anti
}

/// The sum of a pixel's span: head and tail in closed form, `[t_f, t_b]` marched with
/// `samples` samples (without `sigma_s p E` for the sun, as `lit_span`).
pub fn span_sum(
    f: &FrameUniforms,
    sm: &Tex,
    eye: Vec3,
    dir: Vec3,
    p: &PixelSpan,
    samples: u32,
    spot: bool,
) -> f32 {
    let mut total = p.head * lit_span(f, eye, dir, 0.0, p.t_f, spot);
    if p.t_b > p.t_f {
        total += span_march(f, sm, eye, dir, p.t_f, p.t_b, samples, spot);
    }
    total + p.tail * lit_span(f, eye, dir, p.t_b, p.s, spot)
}

/// One frame of the method.
#[derive(Clone, Debug)]
pub struct HybridRun {
    /// The frame set-up (the epipolar one every rectified family shares).
    pub frame: PrefilteredFrame,
    /// The rectified map.
    pub rectified: Tex,
    /// The bins.
    pub bounds: VolumeBounds,
    /// Each pixel's interval (`None`: an epipole disc, marched whole), row-major.
    pub spans: Vec<Option<PixelSpan>>,
    /// In-scattered radiance (f32, not quantised).
    pub output: Image,
}

/// Runs the method for one frame: the shared epipolar set-up and `rectify` (as `minmax`),
/// `volume_bounds`, then per pixel its interval and sum.
///
/// # Errors
///
/// As the frame set-up (`prepare_minmax`).
pub fn run_hybrid_volume(
    light: LightKind,
    knobs: &HybridSettings,
    rectified_size: [u32; 2],
    gbuf: &GBuffer,
    scene: &Scene,
    shadow_map: &ShadowMap,
    settings: &FrameSettings,
) -> Result<HybridRun, FrameError> {
    let res = Resolutions {
        screen: [gbuf.width, gbuf.height],
        rectified: rectified_size,
    };
    let variant = MinmaxVariant {
        light,
        ..MinmaxVariant::default()
    };
    let mut frame = prepare_minmax(
        &variant,
        &res,
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &shadow_map.desc(),
        settings,
    )?;
    let sm = Tex {
        width: shadow_map.size,
        height: shadow_map.size,
        data: shadow_map.depth.clone(),
    };
    let spot = light == LightKind::Spot;
    let depth = Tex {
        width: gbuf.width,
        height: gbuf.height,
        data: gbuf.view_depth.clone(),
    };
    let column_depth = depth_columns::depth_columns(&frame.uniforms, &depth);
    slice_fit::slice_fit(&frame.uniforms, &mut frame.slices, &column_depth, spot);
    let rectified = rectify::rectify(&frame.uniforms, &frame.slices, &sm, spot);
    let bounds = volume_bounds(&frame.uniforms, &rectified, knobs.bins);
    let inp = MarchInputs {
        frame: &frame.uniforms,
        slices: &frame.slices,
        depth: &depth,
        shadow_map: &sm,
        rectified: &rectified,
        bounds: &bounds,
    };
    let f = &frame.uniforms;
    let eye = xyz(f.eye);
    let color = xyz(f.light_color);
    let mut spans = Vec::with_capacity((gbuf.width * gbuf.height) as usize);
    let mut data = Vec::with_capacity(spans.capacity());
    for y in 0..gbuf.height {
        for x in 0..gbuf.width {
            let dir = pixel_dir(f, x, y);
            let span = pixel_span(&inp, x, y, knobs.pad, spot);
            let l = match &span {
                None => {
                    let s = depth.load(x, y).max(0.0).min(f.theta[2])
                        / dir.dot(xyz(f.cam_forward)).max(1e-6);
                    epipole_march(f, &sm, eye, dir, s, spot)
                }
                Some(p) => {
                    let total = span_sum(f, &sm, eye, dir, p, knobs.samples, spot);
                    if spot {
                        total
                    } else {
                        f.medium[1] * phase_hg(f.medium[2], -xyz(f.light_dir).dot(dir)) * total
                    }
                }
            };
            let c = color * l;
            spans.push(span);
            data.push([c.x, c.y, c.z]);
        }
    }
    let output = Image {
        width: gbuf.width,
        height: gbuf.height,
        data,
    };
    Ok(HybridRun {
        frame,
        rectified,
        bounds,
        spans,
        output,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_hold_every_edge_their_depths_cross() {
        // One row of 64 texels with steps and ramps; every depth of every bin checked against
        // a walk of the row.
        let width = 64u32;
        let data: Vec<f32> = (0..width)
            .map(|c| match c {
                0..=9 => 0.9,
                10..=19 => 0.3,
                20..=39 => 0.3 + 0.02 * (c - 20) as f32,
                40..=49 => 1.0,
                _ => 0.05,
            })
            .collect();
        let rectified = Tex {
            width,
            height: 1,
            data,
        };
        let mut f: FrameUniforms = bytemuck::Zeroable::zeroed();
        f.sizes = [1, 1, width, 1];
        for bins in [1u32, 7, 64, 256] {
            let b = volume_bounds(&f, &rectified, bins);
            for i in 0..4000 {
                let d = (i as f32 + 0.5) / 4000.0;
                let crossings: Vec<u32> = (1..width)
                    .filter(|&c| (d <= rectified.load(c - 1, 0)) != (d <= rectified.load(c, 0)))
                    .collect();
                let [first, last] = b.get(0, depth_bin(d, bins));
                if let (Some(&lo), Some(&hi)) = (crossings.first(), crossings.last()) {
                    assert!(
                        first <= lo && last >= hi,
                        "bins {bins}, d {d}: {first}..{last} misses {lo}..{hi}"
                    );
                }
            }
        }
        // A single bin holds every edge of the row.
        let b = volume_bounds(&f, &rectified, 1);
        assert_eq!(b.get(0, 0), [10, 50]);
    }
}
