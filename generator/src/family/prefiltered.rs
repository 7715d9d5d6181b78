//! The `prefiltered` family (Klehm et al. 2014) in the registry: its knobs (parsed into a
//! shaderlib [`PrefilteredVariant`]) and its plan (`scatter_shaderlib::prefiltered::plan`, which the
//! runtime builds and dispatches from).

use scatter_shaderlib::prefiltered::{
    Basis, LightKind, PrefilteredVariant, Rectification, Storage, VariantError, VisibilityMode,
};

use super::{KnobInfo, KnobType};
use crate::GenError;

/// Allowed `bases`, in the words of [`PrefilteredVariant::validate`].
const BASES_ALLOWED: &str = "a multiple of 4 in 4..=128";
/// Allowed `bases_per_thread`.
const BASES_PER_THREAD_ALLOWED: &str = "a multiple of 4 that divides bases";
/// Allowed `regions`.
const REGIONS_ALLOWED: &str = "in 1..=16 (1..=8 with rectification = projective)";
/// Allowed `moments`.
const MOMENTS_ALLOWED: &str = "4 or 6";
/// Allowed `filtered_stride`.
const FILTERED_STRIDE_ALLOWED: &str = "1, 2, 4 or 8";

fn enum_allowed(allowed: &str) -> String {
    allowed.trim_end().replace(' ', " | ")
}

/// The knobs of [`PrefilteredVariant`], defaults from [`PrefilteredVariant::default`] (the paper's choice).
pub fn knobs() -> Vec<KnobInfo> {
    let d = PrefilteredVariant::default();
    vec![
        KnobInfo {
            name: "basis",
            value_name: "BASIS",
            help: "what the prefilter stores of the rectified depth: Fourier bases (the paper) \
                   or power moments (Peters et al. 2016; storage defaults to rgba32float)",
            allowed: enum_allowed(Basis::ALLOWED),
            default: d.basis.to_string(),
            value_type: KnobType::Name,
        },
        KnobInfo {
            name: "bases",
            value_name: "N",
            help: "Fourier bases M (M/2 frequencies, sine and cosine); basis = fourier only",
            allowed: BASES_ALLOWED.into(),
            default: d.bases.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "bases_per_thread",
            value_name: "N",
            help: "bases filtered by one prefilter invocation (threads per row and region = \
                   bases / bases_per_thread)",
            allowed: BASES_PER_THREAD_ALLOWED.into(),
            default: d.bases_per_thread.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "moments",
            value_name: "N",
            help: "power moments of the moment basis (4: Hamburger 4MSM, 6: a cubic); \
                   basis = moments only",
            allowed: MOMENTS_ALLOWED.into(),
            default: d.moments.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "regions",
            value_name: "N",
            help: "independent prefix regions per rectified row (Table 1)",
            allowed: REGIONS_ALLOWED.into(),
            default: d.regions.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "visibility",
            value_name: "MODE",
            help: "visibility weighting along a view ray: plain average or transmittance-weighted \
                   (Eq. 11/12)",
            allowed: enum_allowed(VisibilityMode::ALLOWED),
            default: d.visibility.to_string(),
            value_type: KnobType::Name,
        },
        KnobInfo {
            name: "light",
            value_name: "KIND",
            help: "light type the kernels are compiled for",
            allowed: LightKind::SINGLE_ALLOWED.into(),
            default: d.light.to_string(),
            value_type: KnobType::Name,
        },
        KnobInfo {
            name: "storage",
            value_name: "FORMAT",
            help: "texture format of the filtered bases (rgba32float needs float32-filterable)",
            allowed: enum_allowed(Storage::ALLOWED),
            default: d.storage.to_string(),
            value_type: KnobType::Name,
        },
        KnobInfo {
            name: "rectification",
            value_name: "SCHEME",
            help: "how the standard shadow map becomes a rectified one (Sec. 4)",
            allowed: enum_allowed(Rectification::ALLOWED),
            default: d.rectification.to_string(),
            value_type: KnobType::Name,
        },
        KnobInfo {
            name: "filtered_stride",
            value_name: "K",
            help: "rectified columns per stored filtered column: prefilter filters every \
                   rectified texel but stores every K-th column's running means (regions start \
                   on multiples of K; the rectified width must be a multiple of K), and scatter \
                   reads a map K times coarser",
            allowed: FILTERED_STRIDE_ALLOWED.into(),
            default: d.filtered_stride.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "resume",
            value_name: "BOOL",
            help: "with filtered_stride > 1: scatter resumes each running mean from the last \
                   stored column before the ray's end over the rectified texels up to it (the \
                   answer of filtered_stride = 1 from 1/K of its stores; for sampled frames)",
            allowed: RESUME_ALLOWED.into(),
            default: d.resume.to_string(),
            value_type: KnobType::Boolean,
        },
    ]
}

/// Allowed values of `resume`.
const RESUME_ALLOWED: &str = "true | false";

fn number(knob: &'static str, allowed: &str, value: &str) -> Result<u32, VariantError> {
    value.trim().parse().map_err(|_| VariantError {
        knob,
        value: value.to_owned(),
        allowed: allowed.to_owned(),
    })
}

/// Parses `(knob, value)` pairs over the default variant and validates the result. With
/// `basis = moments` and no `storage` given, the storage is rgba32float (the only one the
/// moment basis allows); with no `bases_per_thread` given, the largest valid one up to the
/// default (`PrefilteredVariant::default_bases_per_thread`: `bases = 8` gets 8).
///
/// # Errors
///
/// [`GenError::Knob`]: the variant's own message naming the knob, the value and the range.
pub fn parse(knobs: &[(String, String)]) -> Result<PrefilteredVariant, GenError> {
    let mut v = PrefilteredVariant::default();
    let mut storage_given = false;
    let mut per_thread_given = false;
    for (name, value) in knobs {
        match name.as_str() {
            "basis" => v.basis = value.parse()?,
            "moments" => v.moments = number("moments", MOMENTS_ALLOWED, value)?,
            "bases" => v.bases = number("bases", BASES_ALLOWED, value)?,
            "bases_per_thread" => {
                v.bases_per_thread = number("bases_per_thread", BASES_PER_THREAD_ALLOWED, value)?;
                per_thread_given = true;
            }
            "regions" => v.regions = number("regions", REGIONS_ALLOWED, value)?,
            "visibility" => v.visibility = value.parse()?,
            "light" => v.light = value.parse()?,
            "storage" => {
                v.storage = value.parse()?;
                storage_given = true;
            }
            "rectification" => v.rectification = value.parse()?,
            "filtered_stride" => {
                v.filtered_stride = number("filtered_stride", FILTERED_STRIDE_ALLOWED, value)?;
            }
            "resume" => {
                v.resume = match value.trim() {
                    "true" | "on" | "1" => true,
                    "false" | "off" | "0" => false,
                    _ => {
                        return Err(VariantError {
                            knob: "resume",
                            value: value.clone(),
                            allowed: RESUME_ALLOWED.into(),
                        }
                        .into());
                    }
                };
            }
            other => {
                return Err(GenError::Usage(format!(
                    "knob `{}` does not apply to family prefiltered",
                    scatter_shaderlib::prefiltered::variant::printable(other)
                )));
            }
        }
    }
    if v.basis == Basis::Moments && !storage_given {
        v.storage = Storage::Rgba32float;
    }
    if !per_thread_given {
        v.bases_per_thread = PrefilteredVariant::default_bases_per_thread(v.bases);
    }
    v.validate()?;
    Ok(v)
}

pub use scatter_shaderlib::plan::{DEPTH_FORMAT, OUTPUT_FORMAT};
pub use scatter_shaderlib::prefiltered::plan::{pass, plan};
