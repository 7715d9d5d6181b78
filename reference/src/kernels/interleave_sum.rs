//! CPU mirror of `shaderlib/templates/interleave_sum.wgsl`: the separable sum filter of
//! interleaved sampling, one 8 x 8 workgroup (tile) at a time: phase 1 fills the tile's
//! horizontal sums (workgroup memory), phase 2 adds `My` of them per pixel.

use super::common_raymarch::window_start;
use super::texture::TexArray;
use glam::Vec3;
use scatter_shaderlib::prefiltered::Storage;
use scatter_shaderlib::raymarch::RaymarchUniforms;

/// Tile side (the workgroup is TILE x TILE).
pub const TILE: u32 = 8;
/// Rows of horizontal sums a tile needs at most.
pub const ROWS: u32 = 15;

/// One workgroup: tile `wid`; stores into `output` (rgba16float).
pub fn interleave_sum_workgroup(
    wid: [u32; 2],
    m: &RaymarchUniforms,
    partial: &TexArray,
    output: &mut TexArray,
) {
    let w = m.sizes[0];
    let h = m.sizes[1];
    let mx = m.interleave[0];
    let my = m.interleave[1];
    let x0 = wid[0] * TILE;
    let y0 = wid[1] * TILE;
    let y_last = (y0 + TILE - 1).min(h - 1);
    let first_row = window_start(y0, my, h);
    let end_row = window_start(y_last, my, h) + my;
    // Phase 1.
    let mut hsum = [[Vec3::ZERO; TILE as usize]; ROWS as usize];
    for k in 0..ROWS * TILE {
        let r = k / TILE;
        let c = k % TILE;
        let row = first_row + r;
        let col = x0 + c;
        let mut acc = Vec3::ZERO;
        if row < end_row && col < w {
            let start = window_start(col, mx, w);
            for i in 0..mx {
                let t = partial.load(start + i, row, 0);
                acc += Vec3::new(t[0], t[1], t[2]);
            }
        }
        hsum[r as usize][c as usize] = acc;
    }
    // Phase 2.
    for ly in 0..TILE {
        for lx in 0..TILE {
            let (x, y) = (x0 + lx, y0 + ly);
            if x >= w || y >= h {
                continue;
            }
            let start = window_start(y, my, h) - first_row;
            let mut total = Vec3::ZERO;
            for i in 0..my {
                total += hsum[(start + i) as usize][(x - x0) as usize];
            }
            output.store(
                x,
                y,
                0,
                [total.x, total.y, total.z, 1.0],
                Storage::Rgba16float,
            );
        }
    }
}

/// Runs every workgroup; returns the filtered radiance (rgba16float).
pub fn interleave_sum(m: &RaymarchUniforms, partial: &TexArray) -> TexArray {
    let (w, h) = (m.sizes[0], m.sizes[1]);
    let mut out = TexArray::new(w, h, 1);
    for ty in 0..h.div_ceil(TILE) {
        for tx in 0..w.div_ceil(TILE) {
            interleave_sum_workgroup([tx, ty], m, partial, &mut out);
        }
    }
    out
}
