//! CPU mirror of `shaderlib/templates/minmax_build.wgsl`: the 1D min-max binary tree of
//! every rectified row (Chen et al. 2011), all levels packed into one rg32float row per
//! rectified row (layout: `scatter_frame::minmax`). One workgroup of [`BUILD_LANES`]
//! invocations per row: phase 1 writes the levels 0 ..= t of each invocation's block of 2^t
//! texels (levels 0 ..= 3 of each group of 8 texels from its 8 loads where t >= 3, the rest
//! from the map), phase 2 (after the barrier) the levels above t from the blocks' level-t
//! nodes.

use super::common_minmax::{level_count, level_offset, tree_width};
use super::texture::{Tex, TexArray};
use scatter_shaderlib::minmax::BUILD_LANES;
use scatter_shaderlib::prefiltered::FrameUniforms;

/// Texels per group of phase 1's register reduction (levels 0 ..= GROUP_LEVELS).
const GROUP: u32 = 8;
const GROUP_LEVELS: u32 = 3;

/// The (min, max) of no texel: the identity of [`join`].
const EMPTY: [f32; 2] = [3.4e38, -3.4e38];

/// The node of two nodes.
fn join(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0].min(b[0]), a[1].max(b[1])]
}

/// Texel x of row y as a level-0 node, or EMPTY at or beyond `end` (`end` > 0; the load
/// clamped inside [0, end)).
fn leaf(rectified: &Tex, x: u32, end: u32, y: u32) -> [f32; 2] {
    let d = rectified.load(x.min(end - 1), y);
    if x < end { [d, d] } else { EMPTY }
}

/// Stores node j of the level at packed column `off` when the level has it (j < count).
fn store_node(out: &mut Vec<(u32, [f32; 4])>, off: u32, j: u32, count: u32, v: [f32; 2]) {
    if j < count {
        out.push((off + j, [v[0], v[1], 0.0, 0.0]));
    }
}

/// (min, max) of the stored depths of texels [a, b) of row y (a < b).
fn span_min_max(rectified: &Tex, a: u32, b: u32, y: u32) -> [f32; 2] {
    let d0 = rectified.load(a, y);
    let mut v = [d0, d0];
    for x in a + 1..b {
        let d = rectified.load(x, y);
        v = [v[0].min(d), v[1].max(d)];
    }
    v
}

/// The workgroup of row `y`: the nodes it stores, `(packed column, (min, max, 0, 0))`.
pub fn minmax_build_row(y: u32, frame: &FrameUniforms, rectified: &Tex) -> Vec<(u32, [f32; 4])> {
    let width = frame.sizes[2];
    let mut out = Vec::new();
    if y >= frame.sizes[3] {
        return out;
    }
    // The block side B = 2^t.
    let mut t = 0u32;
    while (BUILD_LANES << t) < width {
        t += 1;
    }
    // Phase 1, invocation i: levels 0 ..= t of block i.
    let mut block_nodes = vec![[0.0f32; 2]; BUILD_LANES as usize];
    for i in 0..BUILD_LANES {
        let mut top = [0.0f32; 2];
        // Levels from the map: all of them for narrow rows, those above the groups' otherwise.
        let mut k_map = 0;
        if t >= GROUP_LEVELS {
            k_map = GROUP_LEVELS + 1;
            let c0 = level_count(0, width);
            let c1 = level_count(1, width);
            let c2 = level_count(2, width);
            let c3 = level_count(3, width);
            let stop = ((i + 1) << t).min(width);
            let mut base = i << t;
            while base < stop {
                let end = (base + GROUP).min(width);
                let n: [[f32; 2]; 8] =
                    std::array::from_fn(|m| leaf(rectified, base + m as u32, end, y));
                for (m, v) in n.iter().enumerate() {
                    store_node(&mut out, 0, base + m as u32, c0, *v);
                }
                let m: [[f32; 2]; 4] = std::array::from_fn(|a| join(n[2 * a], n[2 * a + 1]));
                for (a, v) in m.iter().enumerate() {
                    store_node(&mut out, c0, (base >> 1) + a as u32, c1, *v);
                }
                let q = [join(m[0], m[1]), join(m[2], m[3])];
                for (a, v) in q.iter().enumerate() {
                    store_node(&mut out, c0 + c1, (base >> 2) + a as u32, c2, *v);
                }
                let r = join(q[0], q[1]);
                store_node(&mut out, c0 + c1 + c2, base >> 3, c3, r);
                top = r;
                base += GROUP;
            }
        }
        for k in k_map..=t {
            let count = level_count(k, width);
            let off = level_offset(k, width);
            let per_block = 1u32 << (t - k);
            for n in 0..per_block {
                let j = i * per_block + n;
                if j < count {
                    let v = span_min_max(rectified, j << k, ((j + 1) << k).min(width), y);
                    out.push((off + j, [v[0], v[1], 0.0, 0.0]));
                    top = v;
                }
            }
        }
        block_nodes[i as usize] = top;
    }
    // Phase 2, invocation i: node i of the levels above t, counted across them in order.
    let count_t = level_count(t, width);
    for i in 0..BUILD_LANES {
        let mut c = i;
        let mut k = t + 1;
        while level_count(k - 1, width) > 1 {
            let count = level_count(k, width);
            if c < count {
                let a = c << (k - t);
                let b = ((c + 1) << (k - t)).min(count_t);
                let mut v = block_nodes[a as usize];
                for m in a + 1..b {
                    let w = block_nodes[m as usize];
                    v = [v[0].min(w[0]), v[1].max(w[1])];
                }
                out.push((level_offset(k, width) + c, [v[0], v[1], 0.0, 0.0]));
                break;
            }
            c -= count;
            k += 1;
        }
    }
    out
}

/// Runs every workgroup (rows in parallel); returns the `tree_width(Wr) x Hr` tree texture
/// (one layer; b and a are 0; a texel no invocation stores stays 0).
pub fn minmax_build(frame: &FrameUniforms, rectified: &Tex) -> TexArray {
    use rayon::prelude::*;
    let (tw, h) = (tree_width(frame.sizes[2]), frame.sizes[3]);
    let data = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            let mut row = vec![[0.0f32; 4]; tw as usize];
            for (c, v) in minmax_build_row(y, frame, rectified) {
                row[c as usize] = v;
            }
            row
        })
        .collect();
    TexArray {
        width: tw,
        height: h,
        layers: 1,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every packed column of the tree is stored exactly once, with the (min, max) of its
    /// node's texels, for widths around the block boundaries.
    #[test]
    fn every_node_once_with_its_span() {
        for width in [
            1u32, 2, 3, 7, 127, 128, 129, 255, 256, 300, 1000, 1024, 1025, 4096,
        ] {
            let mut frame: FrameUniforms = bytemuck::Zeroable::zeroed();
            frame.sizes[2] = width;
            frame.sizes[3] = 1;
            let data: Vec<f32> = (0..width).map(|x| ((x * 7919) % 1009) as f32).collect();
            let mut rectified = Tex::new(width, 1);
            for (x, &d) in data.iter().enumerate() {
                rectified.store(x as u32, 0, d);
            }
            let nodes = minmax_build_row(0, &frame, &rectified);
            let tw = tree_width(width);
            let mut seen = vec![0u32; tw as usize];
            for &(c, _) in &nodes {
                seen[c as usize] += 1;
            }
            assert!(seen.iter().all(|&n| n == 1), "width {width}: {seen:?}");
            for (c, v) in nodes {
                // The node's level and index.
                let mut k = 0;
                while c >= level_offset(k + 1, width) {
                    k += 1;
                }
                let j = c - level_offset(k, width);
                let span = &data[(j << k) as usize..((j + 1) << k).min(width) as usize];
                let lo = span.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = span.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                assert_eq!([v[0], v[1]], [lo, hi], "width {width}, level {k}, node {j}");
            }
        }
    }
}
