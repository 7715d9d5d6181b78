//! CPU mirror of `shaderlib/templates/minmax_build.wgsl`: the 1D min-max binary tree of
//! every rectified row (Chen et al. 2011), all levels packed into one rg32float row per
//! rectified row (layout: `scatter_frame::minmax`).

use super::common_minmax::{level_count, tree_width};
use super::texture::{Tex, TexArray};
use scatter_shaderlib::prefiltered::FrameUniforms;

/// The kernel body for invocation `id`; returns the node `(min, max, 0, 0)` it stores at
/// tree texel `id.xy` (None: out of range, no store).
pub fn minmax_build_main(id: [u32; 3], frame: &FrameUniforms, rectified: &Tex) -> Option<[f32; 4]> {
    let width = frame.sizes[2];
    let (c, y) = (id[0], id[1]);
    if c >= tree_width(width) || y >= frame.sizes[3] {
        return None;
    }
    // The level and node of packed column c.
    let mut level = 0u32;
    let mut off = 0u32;
    loop {
        let count = level_count(level, width);
        if c < off + count {
            break;
        }
        off += count;
        level += 1;
    }
    let first = (c - off) << level;
    let end = (first + (1u32 << level)).min(width);
    let d0 = rectified.load(first, y);
    let mut lo = d0;
    let mut hi = d0;
    for i in first + 1..end {
        let d = rectified.load(i, y);
        lo = lo.min(d);
        hi = hi.max(d);
    }
    Some([lo, hi, 0.0, 0.0])
}

/// Runs every invocation (rows in parallel); returns the `tree_width(Wr) x Hr` tree texture
/// (one layer; b and a are 0).
pub fn minmax_build(frame: &FrameUniforms, rectified: &Tex) -> TexArray {
    use rayon::prelude::*;
    let (tw, h) = (tree_width(frame.sizes[2]), frame.sizes[3]);
    let data = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..tw).map(move |c| minmax_build_main([c, y, 0], frame, rectified).unwrap_or([0.0; 4]))
        })
        .collect();
    TexArray {
        width: tw,
        height: h,
        layers: 1,
        data,
    }
}
