//! CPU mirror of `shaderlib/templates/depth_columns.wgsl`: the deepest pixel of every column
//! of the depth buffer (view depth clamped to [0, far] as `scatter` clamps it; NaN reads as
//! 0), for `slice_fit`.

use super::texture::Tex;
use scatter_shaderlib::prefiltered::FrameUniforms;

/// One f32 per screen column.
pub fn depth_columns(frame: &FrameUniforms, depth: &Tex) -> Vec<f32> {
    let far = frame.theta[2];
    (0..depth.width)
        .map(|x| {
            (0..depth.height)
                .map(|y| depth.load(x, y))
                .fold(0.0f32, |z, v| z.max(v.max(0.0).min(far)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_clamp_to_the_far_plane_and_ignore_nan() {
        let frame = FrameUniforms {
            theta: [0.0, 1.0, 40.0, 1.0],
            ..bytemuck::Zeroable::zeroed()
        };
        let depth = Tex {
            width: 3,
            height: 2,
            data: vec![1.0, f32::NAN, 3.0, -2.0, f32::INFINITY, 0.5],
        };
        assert_eq!(depth_columns(&frame, &depth), vec![1.0, 40.0, 3.0]);
    }
}
