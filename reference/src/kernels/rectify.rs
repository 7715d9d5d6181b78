//! CPU mirror of `shaderlib/templates/rectify.wgsl`: epipolar resampling of the standard
//! shadow map into the rectified map (Klehm et al. 2014 Sec. 4.1, Baran et al. 2010).
//!
//! One invocation per rectified texel (column `x` = light ray, row `y` = slice): find the
//! light ray's first occluder in the standard shadow map and store its view angle as
//! normalised rectified depth (see `scatter_shaderlib::prefiltered::frame`).

use super::common_epipolar::{occluder_depth, row_phi, slice_e, sm_occluder_distance};
use super::common_model::PI;
use super::common_shadow::NO_OCCLUDER;
use super::texture::{Tex, xyz};
use scatter_shaderlib::prefiltered::{FrameUniforms, SliceParams};

/// The kernel body for invocation `id` (`spot` is the template's light switch); returns the
/// value it stores at texel `id.xy` (None: out of range, no store).
pub fn rectify_main(
    id: [u32; 3],
    frame: &FrameUniforms,
    slices: &[SliceParams],
    shadow_map: &Tex,
    spot: bool,
) -> Option<f32> {
    let (x, y) = (id[0], id[1]);
    if x >= frame.sizes[2] || y >= frame.sizes[3] {
        return None;
    }
    let slice = slices[y as usize];
    let e = slice_e(frame, row_phi(frame, y));
    let col = (x as f32 + 0.5) * slice.delta;
    let axis = xyz(frame.axis);
    let mut theta_occ = PI;
    if spot {
        // The light ray leaving the light at angle psi = col from the direction towards the eye.
        let l = -axis * col.cos() + e * col.sin();
        let s = sm_occluder_distance(frame, shadow_map, xyz(frame.light_pos), l);
        if s < NO_OCCLUDER {
            let dist = frame.axis[3];
            theta_occ = (s * col.sin()).atan2(dist - s * col.cos());
        }
    } else {
        // The light ray at distance v = col from the axis, travelling along -axis.
        let o = xyz(frame.eye) + e * col;
        let s = sm_occluder_distance(frame, shadow_map, o, -axis);
        if s < NO_OCCLUDER {
            theta_occ = col.atan2(-s);
        }
    }
    let d = occluder_depth(theta_occ, frame.theta[0], frame.theta[1]);
    Some(d)
}

/// Runs every invocation (rows in parallel).
pub fn rectify(frame: &FrameUniforms, slices: &[SliceParams], shadow_map: &Tex, spot: bool) -> Tex {
    use rayon::prelude::*;
    let (w, h) = (frame.sizes[2], frame.sizes[3]);
    let data = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..w).map(move |x| {
                rectify_main([x, y, 0], frame, slices, shadow_map, spot).unwrap_or(0.0)
            })
        })
        .collect();
    Tex {
        width: w,
        height: h,
        data,
    }
}
