//! CPU mirror of `shaderlib/templates/raymarch_fallback.wgsl`: the epipolar fallback of the
//! raymarch family (`scatter_reference::kernels::common_sampling::epipolar_fallback` with
//! raymarch's per-pixel body).

use super::common_sampling::{EpipolarUnwarp, SampledOutput, epipolar_fallback};
use super::raymarch::raymarch_main;
use super::texture::{Tex, TexArray};
use scatter_shaderlib::raymarch::{RaymarchUniforms, RaymarchVariant};

/// The pixels `raymarch_unwarp` listed, marched themselves into its output.
pub fn raymarch_fallback(
    variant: &RaymarchVariant,
    m: &RaymarchUniforms,
    depth: &Tex,
    shadow_map: &Tex,
    cookie: Option<&TexArray>,
    unwarped: EpipolarUnwarp,
) -> SampledOutput {
    epipolar_fallback(unwarped, &|x, y| {
        let c = raymarch_main([x, y, 0], variant, m, depth, shadow_map, cookie).unwrap_or([0.0; 4]);
        [c[0], c[1], c[2]]
    })
}
