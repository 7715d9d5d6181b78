//! CPU mirror of `shaderlib/templates/volume_bounds.wgsl`: every rectified row's shadow-volume
//! walls rasterised into depth bins, each bin keeping its first and last column edge
//! (conventions: `scatter_frame::hybrid_volume`). The kernel's 64 invocations of a row combine
//! with `atomicMax` in zero-initialised workgroup memory (the first edge as `NO_EDGE - c`),
//! which does not depend on order: here one loop over the edges, min and max.

use super::texture::Tex;
use scatter_shaderlib::hybrid_volume::NO_EDGE;
use scatter_shaderlib::prefiltered::FrameUniforms;

/// The first and last boundary crossing (column edge) per rectified row and depth bin.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VolumeBounds {
    /// Bins per row.
    pub bins: u32,
    /// `[first, last]` edge, index `row * bins + bin`; `first == NO_EDGE` (and `last == 0`):
    /// none.
    pub edges: Vec<[u32; 2]>,
}

impl VolumeBounds {
    /// The edges of bin `bin` of row `row`.
    pub fn get(&self, row: u32, bin: u32) -> [u32; 2] {
        self.edges[(row * self.bins + bin) as usize]
    }
}

/// The bin of ray depth `d` among `bins` (clamped to the bins before the conversion).
pub fn depth_bin(d: f32, bins: u32) -> u32 {
    (d * bins as f32).floor().clamp(0.0, (bins - 1) as f32) as u32
}

/// The kernel body for the workgroup of row `row`: its `bins` entries.
pub fn volume_bounds_row(
    frame: &FrameUniforms,
    rectified: &Tex,
    bins: u32,
    row: u32,
) -> Vec<[u32; 2]> {
    let width = frame.sizes[2];
    let mut edges = vec![[NO_EDGE, 0u32]; bins as usize];
    for c in 1..width {
        let a = rectified.load(c - 1, row);
        let b = rectified.load(c, row);
        let lo = a.min(b);
        let hi = a.max(b);
        if lo < hi {
            let k1 = depth_bin(hi, bins);
            for k in depth_bin(lo, bins)..=k1 {
                let e = &mut edges[k as usize];
                e[0] = e[0].min(c);
                e[1] = e[1].max(c);
            }
        }
    }
    edges
}

/// Runs every workgroup (rows in parallel): the `crossings` buffer.
pub fn volume_bounds(frame: &FrameUniforms, rectified: &Tex, bins: u32) -> VolumeBounds {
    use rayon::prelude::*;
    let edges = (0..frame.sizes[3])
        .into_par_iter()
        .flat_map_iter(|row| volume_bounds_row(frame, rectified, bins, row))
        .collect();
    VolumeBounds { bins, edges }
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
        // A single bin holds every edge of the row; depths outside [0, 1] clamp.
        let b = volume_bounds(&f, &rectified, 1);
        assert_eq!(b.get(0, 0), [10, 50]);
        assert_eq!(depth_bin(-3.0, 16), 0);
        assert_eq!(depth_bin(7.0, 16), 15);
    }
}
