//! CPU mirror of `shaderlib/templates/pst_sweep_fallback.wgsl`: the epipolar fallback of the
//! `partial_sum_tree` family (`scatter_reference::kernels::common_sampling::epipolar_fallback`
//! with `pst_sweep_pixel`: the pixel's own row, its lit columns' leaves summed without the
//! tree).

use super::common_sampling::{EpipolarUnwarp, SampledOutput, epipolar_fallback};
use super::pst_sweep::{PstInputs, pst_sweep_pixel};
use scatter_shaderlib::partial_sum_tree::PartialSumTreeVariant;

/// The pixels `pst_sweep_unwarp` listed, evaluated themselves into its output.
pub fn pst_sweep_fallback(
    variant: &PartialSumTreeVariant,
    inp: &PstInputs,
    unwarped: EpipolarUnwarp,
) -> SampledOutput {
    epipolar_fallback(unwarped, &|x, y| pst_sweep_pixel(inp, variant, x, y))
}
