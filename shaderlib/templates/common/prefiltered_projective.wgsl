// scatter::prefiltered_projective: the prefiltered family's column layout of a projective
// rectified map (Klehm et al. 2014, Sec. 4.2). Region r maps the column invariant G linearly
// from G_r to G_(r+1) onto its columns (`region_start`), and the prefilter weights its texels
// by their exact spans (`proj_texel_weight`). Reading the map itself belongs to no family:
// `scatter::projective`. A module of its own so that epipolar variants compose none of it.
//
// Composed into kernels by naga_oil (`#import scatter::prefiltered_projective::{...}`); plain
// WGSL, not an askama template. Mirrored line by line by
// reference/src/kernels/common_prefiltered_projective.rs.

#define_import_path scatter::prefiltered_projective

#import scatter::model::{cone_falloff, transmittance_between}
#import scatter::epipolar::{Frame, SliceParams}
#import scatter::projective::{proj_boundary, proj_reach}
#import scatter::prefiltered::{CONE_FLOOR, region_start}

// Column invariant at continuous column `x` of region `r`.
fn proj_region_g(f: Frame, x: f32, r: u32, regions: u32, width: u32, spot: bool) -> f32 {
    let b0 = f32(region_start(r, regions, width, spot));
    let b1 = f32(region_start(r + 1u, regions, width, spot));
    return mix(proj_boundary(f, r), proj_boundary(f, r + 1u), (x - b0) / (b1 - b0));
}

// Continuous column of column invariant `g` (outside the map: extrapolated from the first
// or last region).
fn proj_column(f: Frame, g: f32, regions: u32, width: u32, spot: bool) -> f32 {
    var r = 0u;
    for (; r + 1u < regions; r++) {
        if g > proj_boundary(f, r + 1u) {
            break;
        }
    }
    let g0 = proj_boundary(f, r);
    let g1 = proj_boundary(f, r + 1u);
    let b0 = f32(region_start(r, regions, width, spot));
    let b1 = f32(region_start(r + 1u, regions, width, spot));
    return b0 + (b1 - b0) * (g0 - g) / (g0 - g1);
}

// Projective counterpart of `texel_weight` for column `i` of region `r`: the exact span of
// the row's reference ray (direction e1 + k e2 + m_ref axis) that the texel covers, from the
// projective map itself (Klehm's Eq. 12 assumes a constant growth factor per texel; the
// spans of a perspective map grow hyperbolically, so the exact spans are used instead).
// Column 0 also covers the ray from the eye to the map's first light ray. With coarse
// filtered columns (`stride` > 1) the regions start on multiples of the stride
// (`region_column`): the column invariant is that of column `i / stride` of a map of
// `width / stride` columns (exact: the stride is a power of two).
fn proj_texel_weight(f: Frame, s: SliceParams, i: u32, r: u32, regions: u32, stride: u32, weighted: bool, spot: bool) -> f32 {
    let width = f.sizes[2] / stride;
    let scale = 1.0 / f32(stride);
    let k = s.delta;
    let m = s.theta_ref;
    let len = sqrt(1.0 + k * k + m * m);
    let cap = 4.0 * f.theta[2];
    var t0 = 0.0;
    if i > 0u {
        t0 = proj_reach(f, proj_region_g(f, f32(i) * scale, r, regions, width, spot), m, spot, cap / len) * len;
    }
    let t1 = proj_reach(f, proj_region_g(f, f32(i + 1u) * scale, r, regions, width, spot), m, spot, cap / len) * len;
    if !weighted {
        return t1 - t0;
    }
    var w = transmittance_between(f.medium[0], t0, t1);
    if spot {
        let dir = (f.e1_.xyz + f.e2_.xyz * k + f.axis.xyz * m) / len;
        let to = f.eye.xyz + dir * (0.5 * (t0 + t1)) - f.light_pos.xyz;
        let dl = max(length(to), 1e-4);
        let cone = max(cone_falloff(dot(to / dl, f.light_dir.xyz), f.light_pos[3], f.light_dir[3]), CONE_FLOOR);
        w *= cone * exp(-f.medium[0] * dl) / (dl * dl);
    }
    return w;
}
