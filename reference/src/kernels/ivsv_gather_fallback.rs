//! CPU mirror of `shaderlib/templates/ivsv_gather_fallback.wgsl`: the epipolar fallback of
//! the area_ivsv family (`scatter_reference::kernels::common_sampling::epipolar_fallback`
//! with `ivsv_gather`'s per-pixel body).

use super::common_sampling::{EpipolarUnwarp, SampledOutput, epipolar_fallback};
use super::ivsv_gather::gather_pixel;
use super::texture::Tex;
use scatter_shaderlib::area_ivsv::{AreaIvsvVariant, IvsvUniforms, VplRecord};

/// The pixels `ivsv_gather_unwarp` listed, gathered themselves into its output.
pub fn ivsv_gather_fallback(
    variant: &AreaIvsvVariant,
    m: &IvsvUniforms,
    vpls: &[VplRecord],
    volume: &[u32],
    depth: &Tex,
    unwarped: EpipolarUnwarp,
) -> SampledOutput {
    epipolar_fallback(unwarped, &|x, y| {
        gather_pixel(m, vpls, volume, depth, variant.segments, 1, x, y)
    })
}
