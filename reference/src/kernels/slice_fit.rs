//! CPU mirror of `shaderlib/templates/slice_fit.wgsl`: every rectified row's column spacing
//! fitted to the deepest pixel of the depth buffer (the host spans rows to the far plane).
//!
//! One workgroup: the largest view depth `z` (the maximum of `depth_columns`' column
//! maxima, each clamped to [0, far] as `scatter` clamps it), then per row the host's extent
//! with the far plane moved to `z`: directional `delta * z / far`, spot the 33-sample maximum
//! of the light angle. The new spacing replaces
//! the old one when it is smaller, positive and finite. Projective frames are left alone.
//! The reduction's order does not matter: `max` is exact.

use super::common_epipolar::{row_phi, slice_e};
use super::texture::xyz;
use scatter_shaderlib::prefiltered::{FrameUniforms, SliceParams};

/// View angles sampled per row for a spot's extent (the host's 32 intervals).
const SPOT_SAMPLES: u32 = 32;

/// A spot's light ray through the point at view depth `z` on the ray of slice angle `phi`
/// and view angle `theta`: its angle at the light from the direction towards the eye.
fn spot_psi(f: &FrameUniforms, phi: f32, theta: f32, z: f32, dist: f32) -> f32 {
    let d = xyz(f.axis) * theta.cos() + slice_e(f, phi) * theta.sin();
    let t = z / d.dot(xyz(f.cam_forward)).max(1e-6);
    (t * theta.sin()).atan2(dist - t * theta.cos())
}

/// Rewrites `slices` in place as the kernel does, from `column_depth` (`depth_columns`).
pub fn slice_fit(
    frame: &FrameUniforms,
    slices: &mut [SliceParams],
    column_depth: &[f32],
    spot: bool,
) {
    let f = frame;
    let far = f.theta[2];
    let z = column_depth.iter().fold(0.0f32, |z, &v| z.max(v));
    #[allow(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "`!(z < far)` as the WGSL writes it: a NaN far leaves the table alone"
    )]
    let keep = f.proj[0] > 0.5 || !(z < far);
    if keep {
        return;
    }
    let cols = f.sizes[2] as f32;
    let dist = f.axis[3];
    for (row, old) in (0u32..).zip(slices.iter_mut()) {
        let mut delta = old.delta * (z / far);
        if spot {
            let phi = row_phi(f, row);
            let mut extent = 0.0f32;
            for k in 0..=SPOT_SAMPLES {
                let theta =
                    old.theta_lo + (old.theta_hi - old.theta_lo) * k as f32 / SPOT_SAMPLES as f32;
                extent = extent.max(spot_psi(f, phi, theta, z, dist));
            }
            delta = extent * 1.001 / cols;
        }
        if delta > 0.0 && delta < old.delta {
            old.delta = delta;
        }
    }
}
