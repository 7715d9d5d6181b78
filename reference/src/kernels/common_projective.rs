//! CPU mirror of `shaderlib/templates/common/projective.wgsl` (`scatter::projective`): reading
//! a projective rectified map (Sec. 4.2), the part that belongs to no family: the frame's
//! column invariants of the region boundaries, where a view ray meets the light rays of an
//! invariant, and the normalised depths of a view ray and of a rasterised texel.
//!
//! Conventions are documented in `scatter_shaderlib::prefiltered::frame`.

use super::common_epipolar::DEPTH_MARGIN;
use super::common_model::clamp;
use scatter_shaderlib::prefiltered::FrameUniforms;

/// Column invariant `G_r` of region boundary `r` (0..=8).
pub fn proj_boundary(f: &FrameUniforms, r: u32) -> f32 {
    let mut v = f.proj_g2;
    if r < 4 {
        v = f.proj_g0;
    } else if r < 8 {
        v = f.proj_g1;
    }
    v[(r % 4) as usize]
}

/// `qx` where a view ray of depth `m` meets the light rays of invariant `g`: `1 / g` (sun),
/// `D / (g + m)` (spot); `cap` when it never does or lies beyond `cap`.
pub fn proj_reach(f: &FrameUniforms, g: f32, m: f32, spot: bool, cap: f32) -> f32 {
    let mut num = 1.0;
    let mut den = g;
    if spot {
        num = f.axis[3];
        den = g + m;
    }
    if den * cap <= num {
        return cap;
    }
    num / den
}

/// Normalised rectified depth of a view ray of depth `m`.
pub fn proj_ray_depth(f: &FrameUniforms, m: f32) -> f32 {
    DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp((f.proj[2] - m) * f.proj[3], 0.0, 1.0)
}

/// Normalised rectified depth of a rasterised texel (clip `z / w` in [0, 1]).
pub fn proj_stored_depth(raw: f32) -> f32 {
    DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp(raw, 0.0, 1.0)
}
