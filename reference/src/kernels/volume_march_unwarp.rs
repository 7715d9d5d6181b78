//! CPU mirror of `shaderlib/templates/volume_march_unwarp.wgsl`: the epipolar unwarp of the
//! volume_march family (`scatter_reference::kernels::common_sampling::epipolar_unwarp`): every pixel
//! gathered from the samples, or listed for `volume_march_fallback`.

use super::common_sampling::{EpipolarUnwarp, epipolar_unwarp};
use super::texture::TexArray;
use super::volume_march::MarchInputs;
use scatter_shaderlib::hybrid_volume::HybridVolumeVariant;

/// Every pixel of an `epipolar` variant gathered from `samples` (what `volume_march` wrote to
/// `epipolar_samples`), or listed for `volume_march_fallback` where no sample stands for it.
pub fn volume_march_unwarp(
    variant: &HybridVolumeVariant,
    inp: &MarchInputs,
    samples: &TexArray,
) -> EpipolarUnwarp {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        samples,
    )
}
