//! CPU mirror of `shaderlib/templates/common/sampling.wgsl` (`scatter::sampling`): where the
//! samples of `sampling = lowres` stand and which of them stand for a pixel; and of the
//! families' sampling entry point (`shaderlib/templates/include/sampled_entry.wgsl`),
//! [`run_sampled`], which every family's per-pixel mirror calls with its pixel body.
//! Conventions: `scatter_frame::sampling`.

use super::lowres_upsample::lowres_upsample;
use super::texture::{Tex, TexArray, quantise};
use scatter_shaderlib::prefiltered::Storage;
use scatter_shaderlib::sampling::{Sampling, SamplingKnobs};

/// The sample grid of a screen at block side `scale`: ceil(screen / scale).
pub fn lowres_grid(screen: [u32; 2], scale: u32) -> [u32; 2] {
    [
        (screen[0] + scale - 1) / scale,
        (screen[1] + scale - 1) / scale,
    ]
}

/// The pixel sample `i` stands on: the pixel S / 2 into its block (the block's centre, or
/// the last pixel of the screen where the block is cut off).
pub fn lowres_pixel(i: [u32; 2], screen: [u32; 2], scale: u32) -> [u32; 2] {
    let h = scale / 2;
    [
        (i[0] * scale + h).min(screen[0] - 1),
        (i[1] * scale + h).min(screen[1] - 1),
    ]
}

/// Whether two view depths lie on one surface: equal (sky pixels at +inf included), or
/// within `depth_break` (a fraction) of the nearer one.
pub fn depth_close(a: f32, b: f32, depth_break: f32) -> bool {
    a == b || (a - b).abs() <= depth_break * a.min(b)
}

/// The four samples nearest to a pixel and their weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LowresTaps {
    /// Columns (x0, x1) of the samples (x0, y0), (x1, y0), (x0, y1), (x1, y1).
    pub cols: [u32; 2],
    /// Rows (y0, y1).
    pub rows: [u32; 2],
    /// Their weights in that order: bilinear, times 0 for a sample not close in depth.
    pub w: [f32; 4],
}

/// The taps of pixel `p` (bilinear fractions are multiples of 1 / scale, exact in f32).
pub fn lowres_taps(
    depth: &Tex,
    p: [u32; 2],
    screen: [u32; 2],
    scale: u32,
    depth_break: f32,
) -> LowresTaps {
    let grid = lowres_grid(screen, scale).map(|g| g as i32);
    let f = [0, 1].map(|a| (p[a] as f32 - (scale / 2) as f32) / scale as f32);
    let fl = f.map(f32::floor);
    let fr = [0, 1].map(|a| (f[a] - fl[a]).clamp(0.0, 1.0));
    let i0 = fl.map(|v| v as i32);
    let lo = [0, 1].map(|a| i0[a].clamp(0, grid[a] - 1) as u32);
    let hi = [0, 1].map(|a| (i0[a] + 1).clamp(0, grid[a] - 1) as u32);
    let d = depth.load(p[0], p[1]);
    let mut t = LowresTaps {
        cols: [lo[0], hi[0]],
        rows: [lo[1], hi[1]],
        w: [0.0; 4],
    };
    let bx = [1.0 - fr[0], fr[0]];
    let by = [1.0 - fr[1], fr[1]];
    for k in 0..4 {
        let cx = k % 2;
        let cy = k / 2;
        let q = lowres_pixel([t.cols[cx], t.rows[cy]], screen, scale);
        let mut w = 0.0;
        if depth_close(depth.load(q[0], q[1]), d, depth_break) {
            w = bx[cx] * by[cy];
        }
        t.w[k] = w;
    }
    t
}

/// Whether some sample stands for the pixel (a positive weight); if not, the family's
/// sampling pass evaluates the pixel itself.
pub fn lowres_covered(t: &LowresTaps) -> bool {
    t.w.iter().any(|&w| w > 0.0)
}

/// The outputs of a family's per-pixel kernel and, for `lowres`, the upsample.
#[derive(Clone, Debug)]
pub struct SampledOutput {
    /// `lowres`: the samples as stored (rgba16float); `None` for `pixels`.
    pub samples: Option<TexArray>,
    /// The screen-sized output as stored (rgba16float).
    pub output: TexArray,
    /// Pixels the sampling pass evaluated itself (every pixel for `pixels`; for `lowres`
    /// the samples plus the pixels no sample stands for).
    pub evaluated: u64,
    /// `lowres`: the pixels no sample stands for in depth (evaluated per pixel).
    pub fallback: u64,
}

/// The family's sampling entry point and, for `lowres`, `lowres_upsample`: `pixel(x, y)` is
/// the family's per-pixel body (radiance before rounding), `screen` the screen size.
/// `pixels`: every pixel (rows in parallel). `lowres`: every sample, then per block the
/// pixels no sample stands for, then the upsample of the rest.
pub fn run_sampled(
    knobs: &SamplingKnobs,
    screen: [u32; 2],
    depth: &Tex,
    pixel: &(dyn Fn(u32, u32) -> [f32; 3] + Sync),
) -> SampledOutput {
    use rayon::prelude::*;
    let [w, h] = screen;
    let store = |c: [f32; 3]| [c[0], c[1], c[2], 1.0].map(|v| quantise(v, Storage::Rgba16float));
    match knobs.sampling {
        Sampling::Pixels => {
            let data = (0..h)
                .into_par_iter()
                .flat_map_iter(|y| (0..w).map(move |x| store(pixel(x, y))))
                .collect();
            SampledOutput {
                samples: None,
                output: TexArray {
                    width: w,
                    height: h,
                    layers: 1,
                    data,
                },
                evaluated: u64::from(w) * u64::from(h),
                fallback: 0,
            }
        }
        Sampling::Lowres => {
            let scale = knobs.scale;
            let depth_break = knobs.depth_break_fraction();
            let grid = lowres_grid(screen, scale);
            // Per sample: its value, then the block's pixels no sample stands for.
            type Block = ([f32; 4], Vec<([u32; 2], [f32; 4])>);
            let blocks: Vec<Block> = (0..grid[1])
                .into_par_iter()
                .flat_map_iter(|j| {
                    (0..grid[0]).map(move |i| {
                        let p = lowres_pixel([i, j], screen, scale);
                        let c = store(pixel(p[0], p[1]));
                        let mut own = Vec::new();
                        for k in 0..scale * scale {
                            let q = [i * scale + k % scale, j * scale + k / scale];
                            if q[0] < w
                                && q[1] < h
                                && !lowres_covered(&lowres_taps(depth, q, screen, scale, depth_break))
                            {
                                own.push((q, store(pixel(q[0], q[1]))));
                            }
                        }
                        (c, own)
                    })
                })
                .collect();
            let mut output = TexArray::new(w, h, 1);
            let mut fallback = 0;
            for (_, own) in &blocks {
                for &(q, c) in own {
                    output.data[(q[1] * w + q[0]) as usize] = c;
                    fallback += 1;
                }
            }
            let samples = TexArray {
                width: grid[0],
                height: grid[1],
                layers: 1,
                data: blocks.iter().map(|(c, _)| *c).collect(),
            };
            lowres_upsample(knobs, depth, &samples, &mut output);
            SampledOutput {
                samples: Some(samples),
                output,
                evaluated: u64::from(grid[0]) * u64::from(grid[1]) + fallback,
                fallback,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_stand_in_their_blocks() {
        assert_eq!(lowres_grid([67, 37], 4), [17, 10]);
        assert_eq!(lowres_pixel([0, 0], [67, 37], 4), [2, 2]);
        assert_eq!(lowres_pixel([16, 9], [67, 37], 4), [66, 36]);
        assert_eq!(lowres_pixel([1, 1], [67, 37], 2), [3, 3]);
    }

    #[test]
    fn taps_follow_depth() {
        let mut depth = Tex::new(8, 8);
        depth.data.iter_mut().for_each(|d| *d = 10.0);
        // A sample pixel is its own tap with weight 1.
        let t = lowres_taps(&depth, [3, 3], [8, 8], 2, 0.05);
        assert_eq!(t.w, [1.0, 0.0, 0.0, 0.0]);
        assert_eq!((t.cols, t.rows), ([1, 2], [1, 2]));
        // Between four samples: a quarter each.
        let t = lowres_taps(&depth, [4, 4], [8, 8], 2, 0.05);
        assert_eq!(t.w, [0.25; 4]);
        // A near occluder on one pixel (no sample stands on column 4): none of the samples stands for it.
        depth.store(4, 4, 2.0);
        let t = lowres_taps(&depth, [4, 4], [8, 8], 2, 0.05);
        assert!(!lowres_covered(&t));
        // Infinite depths are equal.
        depth.data.iter_mut().for_each(|d| *d = f32::INFINITY);
        assert!(lowres_covered(&lowres_taps(&depth, [4, 4], [8, 8], 2, 0.05)));
    }

    #[test]
    fn lowres_of_a_smooth_image_is_close_and_exact_at_breaks() {
        let screen = [13, 9];
        let mut depth = Tex::new(13, 9);
        for y in 0..9 {
            for x in 0..13 {
                depth.store(x, y, if x == 4 { 1.0 } else { 10.0 });
            }
        }
        let body = |x: u32, y: u32| [x as f32 * 0.1, y as f32 * 0.1, 1.0];
        let px = run_sampled(&SamplingKnobs::default(), screen, &depth, &body);
        for scale in [2, 4] {
            let lr = run_sampled(&SamplingKnobs::lowres(scale), screen, &depth, &body);
            assert!(lr.fallback > 0, "the one-pixel column is evaluated per pixel");
            for (a, b) in px.output.data.iter().zip(&lr.output.data) {
                for c in 0..3 {
                    assert!((a[c] - b[c]).abs() <= 0.1 * scale as f32, "{a:?} {b:?}");
                }
            }
            for y in 0..9 {
                assert_eq!(
                    lr.output.load(4, y, 0),
                    px.output.load(4, y, 0),
                    "the occluder column is exact"
                );
            }
        }
    }
}
