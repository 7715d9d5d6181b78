// scatter::projective: reading a projective rectified map (Klehm et al. 2014, Sec. 4.2), the
// part of it that belongs to no family: the frame's column invariants of the region
// boundaries, where a view ray meets a light ray of a given invariant, and the normalised
// depths of a view ray and of a rasterised texel. Conventions: `ProjectiveMaps` and
// `projective_frame` in scatter_shaderlib::prefiltered::frame. Light space: eye at the
// origin, x = e1 (the fan's bisectrix), y = e2, z = axis. Row k = qy / qx, ray depth
// m = qz / qx, column invariant G = 1 / qx (sun) or (D - qz) / qx (spot).
//
// How a family lays its columns out between the boundaries is the family's (the prefiltered
// family maps G linearly per region: `proj_region_g`, `proj_column` in
// `scatter::prefiltered`).
//
// Composed into kernels by naga_oil (`#import scatter::projective::{...}`); plain WGSL, not an
// askama template. Mirrored line by line by reference/src/kernels/common_projective.rs.

#define_import_path scatter::projective

#import scatter::epipolar::{DEPTH_MARGIN, Frame}

// Column invariant G_r of region boundary `r` (0..=8).
fn proj_boundary(f: Frame, r: u32) -> f32 {
    var v = f.proj_g2_;
    if r < 4u {
        v = f.proj_g0_;
    } else if r < 8u {
        v = f.proj_g1_;
    }
    return v[r % 4u];
}

// qx where a view ray of depth `m` meets the light rays of invariant `g`: 1 / g (sun),
// D / (g + m) (spot); `cap` when it never does or lies beyond `cap`.
fn proj_reach(f: Frame, g: f32, m: f32, spot: bool, cap: f32) -> f32 {
    var num = 1.0;
    var den = g;
    if spot {
        num = f.axis[3];
        den = g + m;
    }
    if den * cap <= num {
        return cap;
    }
    return num / den;
}

// Normalised rectified depth of a view ray of depth `m` (lit iff it is <= the stored depth).
fn proj_ray_depth(f: Frame, m: f32) -> f32 {
    return DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp((f.proj[2] - m) * f.proj[3], 0.0, 1.0);
}

// Normalised rectified depth of a rasterised texel (clip z / w in [0, 1]).
fn proj_stored_depth(raw: f32) -> f32 {
    return DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp(raw, 0.0, 1.0);
}
