//! The `minmax` family (Chen et al. 2011) in the registry: its knobs (parsed into a
//! shaderlib [`MinmaxVariant`]) and its plan (`scatter_shaderlib::minmax::plan`, which the runtime
//! builds and dispatches from).

use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::prefiltered::LightKind;

use super::{KnobInfo, KnobType};
use crate::GenError;

/// The knobs of [`MinmaxVariant`], defaults from [`MinmaxVariant::default`].
pub fn knobs() -> Vec<KnobInfo> {
    let d = MinmaxVariant::default();
    vec![KnobInfo {
        name: "light",
        value_name: "KIND",
        help: "light type the kernels are compiled for",
        allowed: LightKind::SINGLE_ALLOWED.into(),
        default: d.light.to_string(),
        value_type: KnobType::Name,
    }]
}

/// Parses `(knob, value)` pairs over the default variant and validates the result.
///
/// # Errors
///
/// [`GenError::Knob`] naming the knob, the value and the allowed values.
pub fn parse(knobs: &[(String, String)]) -> Result<MinmaxVariant, GenError> {
    let mut v = MinmaxVariant::default();
    for (name, value) in knobs {
        match name.as_str() {
            "light" => v.light = value.parse()?,
            other => {
                return Err(GenError::Usage(format!(
                    "knob `{}` does not apply to family minmax",
                    scatter_shaderlib::prefiltered::variant::printable(other)
                )));
            }
        }
    }
    v.validate()?;
    Ok(v)
}

pub use scatter_shaderlib::minmax::plan::{pass, plan};
