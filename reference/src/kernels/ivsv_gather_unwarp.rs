//! CPU mirror of `shaderlib/templates/ivsv_gather_unwarp.wgsl`: the epipolar unwarp of the
//! area_ivsv family (`scatter_reference::kernels::common_sampling::epipolar_unwarp`): every
//! pixel gathered from the samples, or listed for `ivsv_gather_fallback`.

use super::common_sampling::{EpipolarUnwarp, epipolar_unwarp};
use super::texture::{Tex, TexArray};
use scatter_shaderlib::area_ivsv::{AreaIvsvVariant, IvsvUniforms};

/// Every pixel of an `epipolar` variant gathered from `samples` (what `ivsv_gather` wrote
/// to `epipolar_samples`), or listed for `ivsv_gather_fallback` where no sample stands for
/// it.
pub fn ivsv_gather_unwarp(
    variant: &AreaIvsvVariant,
    m: &IvsvUniforms,
    depth: &Tex,
    samples: &TexArray,
) -> EpipolarUnwarp {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [m.sizes[0], m.sizes[1]],
        depth,
        samples,
    )
}
