//! CPU mirror of `shaderlib/templates/lowres_upsample.wgsl`: the depth-aware upsample of
//! `sampling = lowres`. Conventions: `scatter_frame::sampling`.

use super::common_sampling::{lowres_covered, lowres_taps};
use super::texture::{Tex, TexArray, quantise};
use scatter_shaderlib::prefiltered::Storage;
use scatter_shaderlib::sampling::SamplingKnobs;

/// The kernel body for pixel `id`: the blend of its samples close in depth, or `None` where
/// none is (the sampling pass evaluated the pixel itself).
pub fn lowres_upsample_main(
    id: [u32; 2],
    knobs: &SamplingKnobs,
    depth: &Tex,
    samples: &TexArray,
) -> Option<[f32; 4]> {
    let screen = [depth.width, depth.height];
    let t = lowres_taps(depth, id, screen, knobs.scale, knobs.depth_break_fraction());
    if !lowres_covered(&t) {
        return None;
    }
    let mut c = [0.0f32; 3];
    for k in 0..4 {
        let s = samples.load(t.cols[k % 2], t.rows[k / 2], 0);
        for (a, v) in c.iter_mut().zip(s) {
            *a += t.w[k] * v;
        }
    }
    let total = t.w[0] + t.w[1] + t.w[2] + t.w[3];
    Some([c[0] / total, c[1] / total, c[2] / total, 1.0])
}

/// Runs every pixel of `output` (screen-sized, holding the pixels the sampling pass
/// evaluated), storing the blended pixels as rgba16float.
pub fn lowres_upsample(knobs: &SamplingKnobs, depth: &Tex, samples: &TexArray, output: &mut TexArray) {
    use rayon::prelude::*;
    let w = output.width as usize;
    output
        .data
        .par_chunks_mut(w)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, texel) in row.iter_mut().enumerate() {
                if let Some(c) = lowres_upsample_main([x as u32, y as u32], knobs, depth, samples) {
                    *texel = c.map(|v| quantise(v, Storage::Rgba16float));
                }
            }
        });
}
