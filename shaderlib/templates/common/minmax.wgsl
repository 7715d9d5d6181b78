// scatter::minmax: the packed layout of the 1D min-max trees of the `minmax` family (Chen et
// al. 2011), shared by `minmax_build` and `minmax_traverse`. Row y of the rg32float tree
// texture holds the tree of rectified row y, levels packed left to right: level k has
// n_k = ceil(Wr / 2^k) nodes at columns off_k .. off_k + n_k (off_k = n_0 + ... + n_(k-1));
// node j of level k covers texels [j 2^k, min((j + 1) 2^k, Wr)) and stores (min, max) of
// their stored depths in (r, g). Conventions: `scatter_frame::minmax`.
//
// Composed into kernels by naga_oil (`#import scatter::minmax::{...}`); plain WGSL, not an
// askama template. Mirrored line by line by reference/src/kernels/common_minmax.rs.

#define_import_path scatter::minmax

// Nodes of level `level` of the tree of a row of `width` texels: ceil(width / 2^level).
fn level_count(level: u32, width: u32) -> u32 {
    return (width + (1u << level) - 1u) >> level;
}

// Levels of the tree of a row of `width` texels (ceil(log2 width) + 1).
fn tree_levels(width: u32) -> u32 {
    var k = 0u;
    while level_count(k, width) > 1u {
        k++;
    }
    return k + 1u;
}

// First column of level `level` in the packed tree row.
fn level_offset(level: u32, width: u32) -> u32 {
    var off = 0u;
    for (var k = 0u; k < level; k++) {
        off += level_count(k, width);
    }
    return off;
}

// Width of the tree texture for a rectified width `width`: every level's nodes.
fn tree_width(width: u32) -> u32 {
    return level_offset(tree_levels(width), width);
}
