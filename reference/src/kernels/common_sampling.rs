//! CPU mirror of `shaderlib/templates/common/sampling.wgsl` (`scatter::sampling`): where the
//! samples of `sampling = lowres` stand, which of them stand for a pixel and when a pixel is
//! evaluated itself; and of the families' sampling entry point
//! (`shaderlib/templates/include/sampled_entry.wgsl`), [`run_sampled`], which every family's
//! per-pixel mirror calls with its pixel body.
//! Conventions: `scatter_frame::sampling`.

use super::texture::{Tex, TexArray, quantise, round_f16};
use scatter_shaderlib::prefiltered::Storage;
use scatter_shaderlib::sampling::{Sampling, SamplingKnobs};

/// The sample grid of a screen at block side `scale`: samples at every S-th pixel from the
/// first, and one on the last: ceil((screen - 1) / scale) + 1.
pub fn lowres_grid(screen: [u32; 2], scale: u32) -> [u32; 2] {
    screen.map(|s| (s - 1).div_ceil(scale) + 1)
}

/// The pixel sample `i` stands on: the first pixel of block i, or the screen's last pixel.
pub fn lowres_pixel(i: [u32; 2], screen: [u32; 2], scale: u32) -> [u32; 2] {
    [
        (i[0] * scale).min(screen[0] - 1),
        (i[1] * scale).min(screen[1] - 1),
    ]
}

/// Whether two view depths lie on one surface: equal (sky pixels at +inf included), or
/// within `depth_break` (a fraction) of the nearer one.
pub fn depth_close(a: f32, b: f32, depth_break: f32) -> bool {
    a == b || (a - b).abs() <= depth_break * a.min(b)
}

/// `v` rounded to f16 (to nearest, ties to even) as rgba16float stores it, clamped to f16's
/// largest finite value (WGSL `round_f16`, which does it by bits).
pub fn round_f16_rgb(v: [f32; 3]) -> [f32; 3] {
    v.map(|c| round_f16(c.clamp(-65504.0, 65504.0)))
}

/// The four samples nearest to a pixel and their bilinear weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LowresTaps {
    /// Columns (x0, x1) of the samples (x0, y0), (x1, y0), (x0, y1), (x1, y1), clamped
    /// inside the sample grid.
    pub cols: [u32; 2],
    /// Rows (y0, y1).
    pub rows: [u32; 2],
    /// Their bilinear weights in that order (a weight is exactly 0 where the pixel lies on
    /// the other sample's column or row).
    pub w: [f32; 4],
}

/// The taps of pixel `p` in block p / S: samples p / S and p / S + 1 per axis (the block's
/// first pixel and the next block's), weighted by the pixel's place between their pixels.
pub fn lowres_taps(p: [u32; 2], screen: [u32; 2], scale: u32) -> LowresTaps {
    let grid = lowres_grid(screen, scale);
    let lo = p.map(|v| v / scale);
    let hi = [0, 1].map(|a| (lo[a] + 1).min(grid[a] - 1));
    let p0 = lowres_pixel(lo, screen, scale);
    let p1 = lowres_pixel(hi, screen, scale);
    let fr = [0, 1].map(|a| (p[a] - p0[a]) as f32 / (p1[a] - p0[a]).max(1) as f32);
    LowresTaps {
        cols: [lo[0], hi[0]],
        rows: [lo[1], hi[1]],
        w: [
            (1.0 - fr[0]) * (1.0 - fr[1]),
            fr[0] * (1.0 - fr[1]),
            (1.0 - fr[0]) * fr[1],
            fr[0] * fr[1],
        ],
    }
}

/// The pixel's radiance from its taps (`w` bilinear weights, `depths` of the taps' pixels,
/// `light` their radiance, `d` the pixel's depth): the bilinear blend of the taps with a
/// positive weight that lie within `depth_break` of `d`; `None` where the pixel needs its
/// own evaluation (no such tap, or their spread over `light_break` of the brightest).
pub fn lowres_blend(
    w: [f32; 4],
    depths: [f32; 4],
    light: [[f32; 3]; 4],
    d: f32,
    depth_break: f32,
    light_break: f32,
) -> Option<[f32; 3]> {
    let mut sum = [0.0f32; 3];
    let mut total = 0.0f32;
    let mut lo = [3.4e38f32; 3];
    let mut hi = [0.0f32; 3];
    for k in 0..4 {
        if w[k] > 0.0 && depth_close(depths[k], d, depth_break) {
            for c in 0..3 {
                sum[c] += w[k] * light[k][c];
                lo[c] = lo[c].min(light[k][c]);
                hi[c] = hi[c].max(light[k][c]);
            }
            total += w[k];
        }
    }
    if total <= 0.0 {
        return None;
    }
    let spread = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    if spread[0].max(spread[1].max(spread[2])) > light_break * hi[0].max(hi[1].max(hi[2])) {
        return None;
    }
    Some(sum.map(|v| v / total))
}

/// The outputs of a family's per-pixel kernel.
#[derive(Clone, Debug)]
pub struct SampledOutput {
    /// The screen-sized output as stored (rgba16float).
    pub output: TexArray,
    /// Pixel evaluations (every pixel for `pixels`; for `lowres` the samples, without the
    /// ring a workgroup evaluates again, plus the pixels evaluated themselves).
    pub evaluated: u64,
    /// `lowres`: the pixels evaluated themselves because no sample is close in depth.
    pub depth_refined: u64,
    /// `lowres`: the pixels evaluated themselves because their samples' light differs.
    pub light_refined: u64,
}

/// The family's sampling entry point (`include/sampled_entry.wgsl`): `pixel(x, y)` is the
/// family's per-pixel body (radiance before rounding), `screen` the screen size.
/// `pixels`: every pixel (rows in parallel). `lowres`: every sample, then every pixel the
/// blend of its taps or its own evaluation. (The GPU evaluates the samples of a workgroup's
/// ring again; the same pixel gives the same value, so the mirror evaluates each once.)
pub fn run_sampled(
    knobs: &SamplingKnobs,
    screen: [u32; 2],
    depth: &Tex,
    pixel: &(dyn Fn(u32, u32) -> [f32; 3] + Sync),
) -> SampledOutput {
    use rayon::prelude::*;
    let [w, h] = screen;
    let store = |c: [f32; 3]| [c[0], c[1], c[2], 1.0].map(|v| quantise(v, Storage::Rgba16float));
    if knobs.sampling == Sampling::Pixels {
        let data = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| (0..w).map(move |x| store(pixel(x, y))))
            .collect();
        return SampledOutput {
            output: TexArray {
                width: w,
                height: h,
                layers: 1,
                data,
            },
            evaluated: u64::from(w) * u64::from(h),
            depth_refined: 0,
            light_refined: 0,
        };
    }
    let scale = knobs.scale;
    let (depth_break, light_break) = (knobs.depth_break_fraction(), knobs.light_break_fraction());
    let grid = lowres_grid(screen, scale);
    // Phase 1: every sample's radiance (rounded to f16) and its pixel's depth.
    let samples: Vec<([f32; 3], f32)> = (0..grid[1])
        .into_par_iter()
        .flat_map_iter(|j| {
            (0..grid[0]).map(move |i| {
                let p = lowres_pixel([i, j], screen, scale);
                (round_f16_rgb(pixel(p[0], p[1])), depth.load(p[0], p[1]))
            })
        })
        .collect();
    // Phase 2: every pixel, blended or evaluated (0 = blended, 1 = no sample close in
    // depth, 2 = the samples' light differs).
    let pixels: Vec<([f32; 4], u8)> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            let samples = &samples;
            (0..w).map(move |x| {
                let t = lowres_taps([x, y], screen, scale);
                let mut depths = [0.0f32; 4];
                let mut light = [[0.0f32; 3]; 4];
                for j in 0..4 {
                    let (c, d) = samples[(t.rows[j / 2] * grid[0] + t.cols[j % 2]) as usize];
                    depths[j] = d;
                    light[j] = c;
                }
                let d = depth.load(x, y);
                match lowres_blend(t.w, depths, light, d, depth_break, light_break) {
                    Some(c) => (store(c), 0),
                    None => {
                        let why = if lowres_blend(t.w, depths, light, d, depth_break, 1.0).is_none()
                        {
                            1
                        } else {
                            2
                        };
                        (store(pixel(x, y)), why)
                    }
                }
            })
        })
        .collect();
    let depth_refined = pixels.iter().filter(|p| p.1 == 1).count() as u64;
    let light_refined = pixels.iter().filter(|p| p.1 == 2).count() as u64;
    SampledOutput {
        output: TexArray {
            width: w,
            height: h,
            layers: 1,
            data: pixels.into_iter().map(|p| p.0).collect(),
        },
        evaluated: u64::from(grid[0]) * u64::from(grid[1]) + depth_refined + light_refined,
        depth_refined,
        light_refined,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_stand_in_their_blocks() {
        assert_eq!(lowres_grid([67, 37], 4), [18, 10]);
        assert_eq!(lowres_grid([65, 37], 4), [17, 10]);
        assert_eq!(lowres_pixel([0, 0], [67, 37], 4), [0, 0]);
        assert_eq!(lowres_pixel([17, 9], [67, 37], 4), [66, 36]);
        assert_eq!(lowres_pixel([1, 1], [67, 37], 2), [2, 2]);
    }

    #[test]
    fn f16_rounding_by_bits_matches() {
        // The WGSL rounds by bits; check that scheme against `round_f16` here.
        let by_bits = |v: f32| {
            let a = v.abs().min(65504.0);
            let u = a.to_bits();
            let normal = f32::from_bits((u + 0xfff + ((u >> 13) & 1)) & 0xffff_e000);
            let sub = (a * 16_777_216.0).round_ties_even() / 16_777_216.0;
            v.signum() * if a < 6.103_515_6e-5 { sub } else { normal }
        };
        let mut x = 1.0e-9f32;
        while x < 7.0e4 {
            for v in [x, x * 1.000_03, x * 0.999_97, -x] {
                assert_eq!(by_bits(v), round_f16_rgb([v; 3])[0], "{v:e}");
            }
            x *= 1.013;
        }
        assert_eq!(round_f16_rgb([1e6, 0.0, -1e6]), [65504.0, 0.0, -65504.0]);
    }

    #[test]
    fn taps_and_blends() {
        // A sample pixel is its own tap with weight 1.
        let t = lowres_taps([2, 2], [8, 8], 2);
        assert_eq!(t.w, [1.0, 0.0, 0.0, 0.0]);
        assert_eq!((t.cols, t.rows), ([1, 2], [1, 2]));
        // Between four samples: a quarter each.
        let t = lowres_taps([3, 3], [8, 8], 2);
        assert_eq!(t.w, [0.25; 4]);
        // The last column: between the sample on column 6 and the one on the last pixel.
        let edge = lowres_taps([7, 3], [8, 8], 2);
        assert_eq!((edge.cols, edge.w), ([3, 4], [0.0, 0.5, 0.0, 0.5]));
        let light = [
            [1.0, 1.0, 1.0],
            [1.1, 1.1, 1.1],
            [0.9, 0.9, 0.9],
            [1.0, 1.0, 1.0],
        ];
        let c = lowres_blend(t.w, [10.0; 4], light, 10.0, 0.05, 0.25).expect("blends");
        assert!((c[0] - 1.0).abs() < 1e-6);
        // A near occluder: no tap is close in depth.
        assert_eq!(lowres_blend(t.w, [10.0; 4], light, 2.0, 0.05, 0.25), None);
        // A shadow edge between the taps: their spread is over the light break.
        assert_eq!(lowres_blend(t.w, [10.0; 4], light, 10.0, 0.05, 0.1), None);
        // Only the taps close in depth count, for the blend and for the spread.
        let c = lowres_blend(
            t.w,
            [10.0, 10.0, 2.0, 2.0],
            [[1.0; 3], [1.0; 3], [9.0; 3], [9.0; 3]],
            10.0,
            0.05,
            0.1,
        );
        assert_eq!(c, Some([1.0; 3]));
        // Infinite depths are equal; a light break of 1 never refines.
        let inf = f32::INFINITY;
        assert!(
            lowres_blend(
                t.w,
                [inf; 4],
                [[0.0; 3], [5.0; 3], [0.0; 3], [0.0; 3]],
                inf,
                0.05,
                1.0
            )
            .is_some()
        );
    }

    #[test]
    fn lowres_of_a_smooth_image_is_close_and_exact_at_breaks() {
        let screen = [13, 9];
        let mut depth = Tex::new(13, 9);
        for y in 0..9 {
            for x in 0..13 {
                depth.store(x, y, if x == 5 { 1.0 } else { 10.0 });
            }
        }
        let body = |x: u32, y: u32| [x as f32 * 0.1, y as f32 * 0.1, 1.0];
        let px = run_sampled(&SamplingKnobs::default(), screen, &depth, &body);
        for scale in [2, 4] {
            let lr = run_sampled(&SamplingKnobs::lowres(scale), screen, &depth, &body);
            assert!(
                lr.depth_refined > 0,
                "the one-pixel column is evaluated per pixel"
            );
            for (a, b) in px.output.data.iter().zip(&lr.output.data) {
                for c in 0..3 {
                    assert!((a[c] - b[c]).abs() <= 0.1 * scale as f32, "{a:?} {b:?}");
                }
            }
            for y in 0..9 {
                assert_eq!(
                    lr.output.load(5, y, 0),
                    px.output.load(5, y, 0),
                    "the occluder column is exact"
                );
            }
        }
    }
}
