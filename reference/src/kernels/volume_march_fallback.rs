//! CPU mirror of `shaderlib/templates/volume_march_fallback.wgsl`: the epipolar fallback of the
//! volume_march family (`scatter_reference::kernels::common_sampling::epipolar_fallback` with
//! volume_march's per-pixel body).

use super::common_sampling::{EpipolarUnwarp, SampledOutput, epipolar_fallback};
use super::volume_march::{MarchInputs, volume_march_pixel};
use scatter_shaderlib::hybrid_volume::HybridVolumeVariant;

/// The pixels `volume_march_unwarp` listed, marched themselves into its output.
pub fn volume_march_fallback(
    variant: &HybridVolumeVariant,
    inp: &MarchInputs,
    unwarped: EpipolarUnwarp,
) -> SampledOutput {
    epipolar_fallback(unwarped, &|x, y| volume_march_pixel(variant, inp, x, y))
}
