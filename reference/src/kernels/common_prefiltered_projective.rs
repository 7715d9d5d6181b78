//! CPU mirror of `shaderlib/templates/common/prefiltered_projective.wgsl`
//! (`scatter::prefiltered_projective`): the prefiltered family's column layout of a projective
//! rectified map (Sec. 4.2): region `r` maps the column invariant linearly from `G_r` to
//! `G_(r+1)` onto its columns, and the prefilter weights its texels by their exact spans.
//! Reading the map itself is [`super::common_projective`].

use super::common_model::{cone_falloff, exp, max, mix, sqrt, transmittance_between};
use super::common_prefiltered::{CONE_FLOOR, region_start};
use super::common_projective::{proj_boundary, proj_reach};
use super::texture::xyz;
use scatter_shaderlib::prefiltered::{FrameUniforms, SliceParams};

/// Column invariant at continuous column `x` of region `r`.
pub fn proj_region_g(
    f: &FrameUniforms,
    x: f32,
    r: u32,
    regions: u32,
    width: u32,
    spot: bool,
) -> f32 {
    let b0 = region_start(r, regions, width, spot) as f32;
    let b1 = region_start(r + 1, regions, width, spot) as f32;
    mix(
        proj_boundary(f, r),
        proj_boundary(f, r + 1),
        (x - b0) / (b1 - b0),
    )
}

/// Continuous column of column invariant `g` (outside the map: extrapolated from the first
/// or last region).
pub fn proj_column(f: &FrameUniforms, g: f32, regions: u32, width: u32, spot: bool) -> f32 {
    let mut r = 0u32;
    while r + 1 < regions {
        if g > proj_boundary(f, r + 1) {
            break;
        }
        r += 1;
    }
    let g0 = proj_boundary(f, r);
    let g1 = proj_boundary(f, r + 1);
    let b0 = region_start(r, regions, width, spot) as f32;
    let b1 = region_start(r + 1, regions, width, spot) as f32;
    b0 + (b1 - b0) * (g0 - g) / (g0 - g1)
}

/// Projective counterpart of [`texel_weight`] for column `i` of region `r`: the exact span
/// of the row's reference ray that the texel covers (column 0 from the eye). With coarse
/// filtered columns (`stride` > 1) the column invariant is that of column `i / stride` of a
/// map of `width / stride` columns (see the WGSL comment).
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn proj_texel_weight(
    f: &FrameUniforms,
    s: &SliceParams,
    i: u32,
    r: u32,
    regions: u32,
    stride: u32,
    weighted: bool,
    spot: bool,
) -> f32 {
    let width = f.sizes[2] / stride;
    let scale = 1.0 / stride as f32;
    let k = s.delta;
    let m = s.theta_ref;
    let len = sqrt(1.0 + k * k + m * m);
    let cap = 4.0 * f.theta[2];
    let mut t0 = 0.0;
    if i > 0 {
        t0 = proj_reach(
            f,
            proj_region_g(f, i as f32 * scale, r, regions, width, spot),
            m,
            spot,
            cap / len,
        ) * len;
    }
    let t1 = proj_reach(
        f,
        proj_region_g(f, (i + 1) as f32 * scale, r, regions, width, spot),
        m,
        spot,
        cap / len,
    ) * len;
    if !weighted {
        return t1 - t0;
    }
    let mut w = transmittance_between(f.medium[0], t0, t1);
    if spot {
        let dir = (xyz(f.e1) + xyz(f.e2) * k + xyz(f.axis) * m) / len;
        let to = xyz(f.eye) + dir * (0.5 * (t0 + t1)) - xyz(f.light_pos);
        let dl = max(to.length(), 1e-4);
        let cone = max(
            cone_falloff(
                (to / dl).dot(xyz(f.light_dir)),
                f.light_pos[3],
                f.light_dir[3],
            ),
            CONE_FLOOR,
        );
        w *= cone * exp(-f.medium[0] * dl) / (dl * dl);
    }
    w
}
