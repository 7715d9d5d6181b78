//! The `area_ivsv` family (Wyman & Dai 2013) in the registry: its knobs (parsed into a
//! shaderlib [`AreaIvsvVariant`]) and its plan (`scatter_shaderlib::area_ivsv::plan`, which
//! the runtime builds and dispatches from).

use scatter_shaderlib::area_ivsv::{AreaIvsvVariant, MAX_SEGMENTS, MAX_VPLS};
use scatter_shaderlib::prefiltered::VariantError;

use super::{KnobInfo, KnobType};
use crate::GenError;

/// Allowed `vpls`.
const VPLS_ALLOWED: &str = "in 1..=256, a multiple of interleave^2 (even for a two-sided light)";
/// Allowed `alpha` and `theta`.
const BINS_ALLOWED: &str = "in 2..=4096 (vpls x alpha x theta x 16 bytes <= 128 MiB)";
/// Allowed `segments`.
const SEGMENTS_ALLOWED: &str = "1 | 2 | 4 | 8 | 16 | 32";
/// Allowed `interleave`.
const INTERLEAVE_ALLOWED: &str = "1 | 2 | 4";

const _: () = assert!(MAX_VPLS == 256 && MAX_SEGMENTS == 32);

/// The knobs of [`AreaIvsvVariant`], defaults from [`AreaIvsvVariant::default`].
pub fn knobs() -> Vec<KnobInfo> {
    let d = AreaIvsvVariant::default();
    vec![
        KnobInfo {
            name: "vpls",
            value_name: "N",
            help: "virtual point lights on the area light (Halton points): shadow-map layers \
                   and voxel grids per frame",
            allowed: VPLS_ALLOWED.into(),
            default: d.vpls.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "alpha",
            value_name: "BINS",
            help: "eye-angle bins of each VPL's voxel grid (texels per row)",
            allowed: BINS_ALLOWED.into(),
            default: d.alpha.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "theta",
            value_name: "BINS",
            help: "plane-angle bins of each VPL's voxel grid (rows per VPL)",
            allowed: BINS_ALLOWED.into(),
            default: d.theta.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "segments",
            value_name: "K",
            help: "pieces of the spot cone's light-angle interval on which the gather \
                   interpolates the integrand linearly",
            allowed: SEGMENTS_ALLOWED.into(),
            default: d.segments.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "interleave",
            value_name: "M",
            help: "interleaved gather: each pixel of an MxM tile gathers 1/M^2 of the VPLs and \
                   a window sum adds them (1 = off)",
            allowed: INTERLEAVE_ALLOWED.into(),
            default: d.interleave.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "light",
            value_name: "KIND",
            help: "light type the kernels are compiled for (area lights only)",
            allowed: "area".into(),
            default: d.light.to_string(),
            value_type: KnobType::Name,
        },
    ]
}

fn number(knob: &'static str, allowed: &str, value: &str) -> Result<u32, VariantError> {
    value.trim().parse().map_err(|_| VariantError {
        knob,
        value: value.to_owned(),
        allowed: allowed.to_owned(),
    })
}

/// Parses `(knob, value)` pairs over the default variant and validates the result.
///
/// # Errors
///
/// [`GenError::Knob`] naming the knob, the value and the range.
pub fn parse(knobs: &[(String, String)]) -> Result<AreaIvsvVariant, GenError> {
    let mut v = AreaIvsvVariant::default();
    for (name, value) in knobs {
        match name.as_str() {
            "vpls" => v.vpls = number("vpls", VPLS_ALLOWED, value)?,
            "alpha" => v.alpha = number("alpha", BINS_ALLOWED, value)?,
            "theta" => v.theta = number("theta", BINS_ALLOWED, value)?,
            "segments" => v.segments = number("segments", SEGMENTS_ALLOWED, value)?,
            "interleave" => v.interleave = number("interleave", INTERLEAVE_ALLOWED, value)?,
            "light" => v.light = value.parse()?,
            other => {
                return Err(GenError::Usage(format!(
                    "knob `{}` does not apply to family area_ivsv",
                    scatter_shaderlib::prefiltered::variant::printable(other)
                )));
            }
        }
    }
    v.validate()?;
    Ok(v)
}

pub use scatter_shaderlib::area_ivsv::plan::{pass, plan};
