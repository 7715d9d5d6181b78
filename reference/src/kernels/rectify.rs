//! CPU mirror of `shaderlib/templates/rectify.wgsl`: epipolar resampling of the standard
//! shadow map into the rectified map (Klehm et al. 2014 Sec. 4.1, Baran et al. 2010).
//!
//! Per rectified texel (column `x` = light ray, row `y` = slice): find the light ray's first
//! occluder in the standard shadow map and store its view angle as normalised rectified depth
//! (see `scatter_shaderlib::prefiltered::frame`). Each invocation takes `RECTIFY_TEXELS`
//! consecutive columns of a row, its row's constants once.

use super::common_epipolar::{
    light_point_theta, occluder_depth, row_phi, slice_e, sm_occluder_distance_spot,
    sm_occluder_distance_sun,
};
use super::common_model::{PI, select};
use super::common_shadow::NO_OCCLUDER;
use super::texture::{Tex, xyz};
use glam::Vec3;
use scatter_shaderlib::prefiltered::{FrameUniforms, RECTIFY_TEXELS, SliceParams};

/// The value `rectify_texel` stores at texel `x` of a row (`slice` its parameters, `e` its
/// slice direction; `spot` is the template's light switch).
pub fn rectify_texel(
    x: u32,
    frame: &FrameUniforms,
    slice: SliceParams,
    e: Vec3,
    shadow_map: &Tex,
    spot: bool,
) -> f32 {
    let col = (x as f32 + 0.5) * slice.delta;
    let axis = xyz(frame.axis);
    let mut theta_occ = PI;
    if spot {
        // The light ray leaving the light at angle psi = col from the direction towards the eye.
        let l = -axis * col.cos() + e * col.sin();
        let s = sm_occluder_distance_spot(frame, shadow_map, l);
        if s < NO_OCCLUDER {
            theta_occ = light_point_theta(frame, col, s, true);
        }
    } else {
        // The light ray at distance v = col from the axis, travelling along -axis.
        let o = xyz(frame.eye) + e * col;
        let s = sm_occluder_distance_sun(frame, shadow_map, o);
        theta_occ = select(PI, light_point_theta(frame, col, s, false), s < NO_OCCLUDER);
    }
    occluder_depth(theta_occ, frame.theta[0], frame.theta[1])
}

/// The kernel body for invocation `id`: the values it stores at texels `(RECTIFY_TEXELS
/// id.x .., id.y)`, those inside the map (None: out of range, no store).
pub fn rectify_main(
    id: [u32; 3],
    frame: &FrameUniforms,
    slices: &[SliceParams],
    shadow_map: &Tex,
    spot: bool,
) -> Option<Vec<f32>> {
    let first = id[0] * RECTIFY_TEXELS;
    let y = id[1];
    if first >= frame.sizes[2] || y >= frame.sizes[3] {
        return None;
    }
    let slice = slices[y as usize];
    let e = slice_e(frame, row_phi(frame, y));
    let end = (first + RECTIFY_TEXELS).min(frame.sizes[2]);
    Some(
        (first..end)
            .map(|x| rectify_texel(x, frame, slice, e, shadow_map, spot))
            .collect(),
    )
}

/// Runs every invocation (rows in parallel).
pub fn rectify(frame: &FrameUniforms, slices: &[SliceParams], shadow_map: &Tex, spot: bool) -> Tex {
    use rayon::prelude::*;
    let (w, h) = (frame.sizes[2], frame.sizes[3]);
    let data = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..w.div_ceil(RECTIFY_TEXELS)).flat_map(move |i| {
                rectify_main([i, y, 0], frame, slices, shadow_map, spot).unwrap_or_default()
            })
        })
        .collect();
    Tex {
        width: w,
        height: h,
        data,
    }
}
