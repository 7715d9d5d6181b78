//! The `hybrid_volume` family (Wyman & Ramsey 2008) in the registry: its knobs (parsed into a
//! shaderlib [`HybridVolumeVariant`]) and its plan (`scatter_shaderlib::hybrid_volume::plan`,
//! which the runtime builds and dispatches from).

use scatter_shaderlib::hybrid_volume::{HybridVolumeVariant, MAX_BINS, MAX_PAD, MAX_SAMPLES};
use scatter_shaderlib::prefiltered::LightKind;
use scatter_shaderlib::prefiltered::variant::VariantError;

use super::{KnobInfo, KnobType};
use crate::GenError;

/// The knobs of [`HybridVolumeVariant`], defaults from [`HybridVolumeVariant::default`].
pub fn knobs() -> Vec<KnobInfo> {
    let d = HybridVolumeVariant::default();
    let integer = |name, value_name, help, hi: u32, lo: u32, default: u32| KnobInfo {
        name,
        value_name,
        help,
        allowed: format!("in {lo}..={hi}"),
        default: default.to_string(),
        value_type: KnobType::Integer,
    };
    vec![
        KnobInfo {
            name: "light",
            value_name: "KIND",
            help: "light type the kernels are compiled for",
            allowed: LightKind::SINGLE_ALLOWED.into(),
            default: d.light.to_string(),
            value_type: KnobType::Name,
        },
        integer(
            "samples",
            "N",
            "samples marched in each pixel's interval between the shadow volume's first and \
             last boundary",
            MAX_SAMPLES,
            1,
            d.samples,
        ),
        integer(
            "bins",
            "B",
            "ray-depth bins per rectified row in volume_bounds",
            MAX_BINS,
            1,
            d.bins,
        ),
        integer(
            "pad",
            "TEXELS",
            "texels each bound of the interval is widened by",
            MAX_PAD,
            0,
            d.pad,
        ),
    ]
}

/// Parses `(knob, value)` pairs over the default variant and validates the result.
///
/// # Errors
///
/// [`GenError::Knob`] naming the knob, the value and the allowed values.
pub fn parse(knobs: &[(String, String)]) -> Result<HybridVolumeVariant, GenError> {
    let mut v = HybridVolumeVariant::default();
    let number = |knob: &'static str, value: &String, hi: u32, lo: u32| {
        value.trim().parse::<u32>().map_err(|_| VariantError {
            knob,
            value: value.clone(),
            allowed: format!("in {lo}..={hi}"),
        })
    };
    for (name, value) in knobs {
        match name.as_str() {
            "light" => v.light = value.parse()?,
            "samples" => v.samples = number("samples", value, MAX_SAMPLES, 1)?,
            "bins" => v.bins = number("bins", value, MAX_BINS, 1)?,
            "pad" => v.pad = number("pad", value, MAX_PAD, 0)?,
            other => {
                return Err(GenError::Usage(format!(
                    "knob `{}` does not apply to family hybrid_volume",
                    scatter_shaderlib::prefiltered::variant::printable(other)
                )));
            }
        }
    }
    v.validate()?;
    Ok(v)
}

pub use scatter_shaderlib::hybrid_volume::plan::{pass, plan};
