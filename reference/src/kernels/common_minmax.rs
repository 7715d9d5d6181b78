//! CPU mirror of `shaderlib/templates/common/minmax.wgsl` (`scatter::minmax`): the packed
//! layout of the 1D min-max trees (conventions: `scatter_frame::minmax`, whose `const fn`s
//! compute the same numbers on the host).

/// Nodes of level `level` of the tree of a row of `width` texels: `ceil(width / 2^level)`.
pub fn level_count(level: u32, width: u32) -> u32 {
    (width + (1u32 << level) - 1) >> level
}

/// Levels of the tree of a row of `width` texels (`ceil(log2 width) + 1`).
pub fn tree_levels(width: u32) -> u32 {
    let mut k = 0u32;
    while level_count(k, width) > 1 {
        k += 1;
    }
    k + 1
}

/// First column of level `level` in the packed tree row.
pub fn level_offset(level: u32, width: u32) -> u32 {
    let mut off = 0u32;
    for k in 0..level {
        off += level_count(k, width);
    }
    off
}

/// Width of the tree texture for a rectified width `width`: every level's nodes.
pub fn tree_width(width: u32) -> u32 {
    level_offset(tree_levels(width), width)
}
