// scatter::indexing: shared index guards and running-filter weights for the row kernels.
//
// Composed into kernels by naga_oil (`#import scatter::indexing::{...}`); plain WGSL, not an
// askama template. The CPU mirrors reimplement these functions line by line
// (reference/src/kernels/row_prefix.rs).

#define_import_path scatter::indexing

// True when invocation (row, layer) addresses an existing row of a texture array with
// `height` rows and `layers` layers. Dispatches are rounded up to whole workgroups, so the
// trailing invocations of the last workgroup must stay idle.
fn row_in_range(row: u32, layer: u32, height: u32, layers: u32) -> bool {
    return row < height && layer < layers;
}

// Blend weight of sample i (0-based) in a running mean, 1 / (i + 1): mixing the mean of
// samples 0..i-1 towards sample i by this weight gives the mean of samples 0..=i
// (Klehm et al. 2014, Listing 1).
fn running_mean_weight(i: u32) -> f32 {
    return 1.0 / f32(i + 1u);
}
