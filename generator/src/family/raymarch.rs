//! The `raymarch` family (Tóth & Umenhoffer 2009) in the registry: its knobs (parsed into a
//! shaderlib [`RaymarchVariant`]) and its plan (`scatter_shaderlib::raymarch::plan`, which the runtime
//! builds and dispatches from).

use scatter_shaderlib::prefiltered::{LightKind, VariantError};
use scatter_shaderlib::raymarch::RaymarchVariant;

use super::{KnobInfo, KnobType};
use crate::GenError;

/// Allowed `samples`.
const SAMPLES_ALLOWED: &str = "in 4..=1024, a multiple of interleave^2";
/// Allowed `interleave`.
const INTERLEAVE_ALLOWED: &str = "in 1..=8";
/// Allowed `jitter`.
const JITTER_ALLOWED: &str = "true | false";

/// The knobs of [`RaymarchVariant`], defaults from [`RaymarchVariant::default`].
pub fn knobs() -> Vec<KnobInfo> {
    let d = RaymarchVariant::default();
    vec![
        KnobInfo {
            name: "samples",
            value_name: "N",
            help: "cells per view ray, one shadow-map sample each",
            allowed: SAMPLES_ALLOWED.into(),
            default: d.samples.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "interleave",
            value_name: "M",
            help: "interleaved sampling tile side: each pixel of an MxM tile takes N/M^2 of the \
                   samples and a separable sum filter adds them (1 = off)",
            allowed: INTERLEAVE_ALLOWED.into(),
            default: d.interleave.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "jitter",
            value_name: "BOOL",
            help: "per-pixel jitter of the sample positions inside their cells",
            allowed: JITTER_ALLOWED.into(),
            default: d.jitter.to_string(),
            value_type: KnobType::Boolean,
        },
        KnobInfo {
            name: "light",
            value_name: "KIND",
            help: "light type the kernels are compiled for",
            allowed: LightKind::SINGLE_ALLOWED.into(),
            default: d.light.to_string(),
            value_type: KnobType::Name,
        },
    ]
}

/// A boolean knob's value.
fn boolean(knob: &'static str, value: &str) -> Result<bool, VariantError> {
    match value.trim() {
        "true" | "on" | "1" => Ok(true),
        "false" | "off" | "0" => Ok(false),
        _ => Err(VariantError {
            knob,
            value: value.to_owned(),
            allowed: JITTER_ALLOWED.into(),
        }),
    }
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
pub fn parse(knobs: &[(String, String)]) -> Result<RaymarchVariant, GenError> {
    let mut v = RaymarchVariant::default();
    for (name, value) in knobs {
        match name.as_str() {
            "samples" => v.samples = number("samples", SAMPLES_ALLOWED, value)?,
            "interleave" => v.interleave = number("interleave", INTERLEAVE_ALLOWED, value)?,
            "jitter" => v.jitter = boolean("jitter", value)?,
            "light" => v.light = value.parse()?,
            other => {
                return Err(GenError::Usage(format!(
                    "knob `{}` does not apply to family raymarch",
                    scatter_shaderlib::prefiltered::variant::printable(other)
                )));
            }
        }
    }
    v.validate()?;
    Ok(v)
}

pub use scatter_shaderlib::raymarch::plan::{pass, plan};
