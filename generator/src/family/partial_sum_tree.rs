//! The `partial_sum_tree` family (Baran et al. 2010) in the registry: its knobs (parsed into a
//! shaderlib [`PartialSumTreeVariant`]) and its plan
//! (`scatter_shaderlib::partial_sum_tree::plan`, which the runtime builds and dispatches from).
//! Its sampling knobs are the shared ones with other defaults: `sampling = epipolar` and
//! `step = 1` are the only values it takes (the sweep answers every sample of a slice).

use scatter_shaderlib::partial_sum_tree::{MAX_RANK, PartialSumTreeVariant};
use scatter_shaderlib::prefiltered::LightKind;
use scatter_shaderlib::prefiltered::variant::VariantError;

use super::{KnobInfo, KnobType};
use crate::GenError;

/// The knobs of [`PartialSumTreeVariant`], defaults from [`PartialSumTreeVariant::default`].
pub fn knobs() -> Vec<KnobInfo> {
    let d = PartialSumTreeVariant::default();
    vec![
        KnobInfo {
            name: "light",
            value_name: "KIND",
            help: "light type the kernels are compiled for",
            allowed: LightKind::SINGLE_ALLOWED.into(),
            default: d.light.to_string(),
            value_type: KnobType::Name,
        },
        KnobInfo {
            name: "rank",
            value_name: "R",
            help: "rank of the separable integrand (the frame's SVD; the paper: 4)",
            allowed: format!("in 1..={MAX_RANK}"),
            default: d.rank.to_string(),
            value_type: KnobType::Integer,
        },
    ]
}

/// Parses `(knob, value)` pairs over the default variant and validates the result.
///
/// # Errors
///
/// [`GenError::Knob`] naming the knob, the value and the allowed values.
pub fn parse(knobs: &[(String, String)]) -> Result<PartialSumTreeVariant, GenError> {
    let mut v = PartialSumTreeVariant::default();
    for (name, value) in knobs {
        match name.as_str() {
            "light" => v.light = value.parse()?,
            "rank" => {
                v.rank = value.trim().parse().map_err(|_| VariantError {
                    knob: "rank",
                    value: value.clone(),
                    allowed: format!("in 1..={MAX_RANK}"),
                })?;
            }
            other => {
                return Err(GenError::Usage(format!(
                    "knob `{}` does not apply to family partial_sum_tree",
                    scatter_shaderlib::prefiltered::variant::printable(other)
                )));
            }
        }
    }
    v.validate()?;
    Ok(v)
}

pub use scatter_shaderlib::partial_sum_tree::plan::{pass, plan};
