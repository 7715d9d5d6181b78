//! CPU mirror of `shaderlib/templates/ivsv_scan.wgsl`: the OR prefix scan of every voxel row
//! along alpha, word by word, zeroing the marks it reads.

use super::common_ivsv::voxel_word;
use scatter_shaderlib::area_ivsv::IvsvUniforms;

/// The invocation `(4 j + w, v)`: word `w` of row `j` of VPL `v`.
pub fn scan_word(m: &IvsvUniforms, marks: &mut [u32], volume: &mut [u32], j: u32, w: u32, v: u32) {
    let mut acc = 0u32;
    for i in 0..m.grid[0] {
        let at = (voxel_word(m, v, j, i) + w) as usize;
        acc |= std::mem::take(&mut marks[at]);
        volume[at] = acc;
    }
}

/// The whole pass.
pub fn ivsv_scan(m: &IvsvUniforms, marks: &mut [u32], volume: &mut [u32]) {
    for v in 0..m.sizes[3] {
        for j in 0..m.grid[1] {
            for w in 0..4 {
                scan_word(m, marks, volume, j, w, v);
            }
        }
    }
}
