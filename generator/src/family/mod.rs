//! The family registry: what the generator knows about each kernel family beyond what
//! shaderlib's IR says (its knobs, how a variant is parsed, which textures and buffers the
//! engine allocates and how each pass is dispatched).
//!
//! [`Family`] and [`FamilyVariant`] are the shared ones (`scatter_frame::family`, re-exported
//! by shaderlib with [`KernelFamily`]: kernels and plan); the generator adds the knobs as the
//! CLI shows them ([`FamilyCli`], one module per family like [`prefiltered`]). The CLI, the
//! config file, the manifest and the tests pick a family up from [`Family::ALL`]; see
//! `docs/adding-a-family.md`.

pub mod area_ivsv;
pub mod hybrid_volume;
pub mod minmax;
pub mod partial_sum_tree;
pub mod prefiltered;
pub mod raymarch;

use scatter_shaderlib::Kernel;
use scatter_shaderlib::prefiltered::VariantError;
use scatter_shaderlib::prefiltered::variant::printable;
use scatter_shaderlib::sampling::{Sampling, SamplingKnobs};
use serde::Serialize;

pub use scatter_shaderlib::family::{Family, FamilyVariant, KernelFamily, KnobSet};
pub use scatter_shaderlib::plan::{
    Alternative, BindingSource, BufferDesc, Formula, Indirect, Parameter, PassPlan, Plan, Resource,
    SamplerDesc, TextureDesc,
};

use crate::GenError;

/// One knob of a family, as the CLI, `scatter-gen list` and the config file show it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct KnobInfo {
    /// The knob's name (config key and manifest key), e.g. `bases_per_thread`.
    pub name: &'static str,
    /// Placeholder for its value in `--help`, e.g. `N`.
    pub value_name: &'static str,
    /// What it does, one sentence.
    pub help: &'static str,
    /// The allowed values, in words (`a multiple of 4 in 4..=128`, `average | weighted`).
    pub allowed: String,
    /// The default (the paper's choice).
    pub default: String,
    /// The TOML type of its value in a config file.
    pub value_type: KnobType,
}

/// The TOML type a knob's value must have in a config file (`bases = 32`, `jitter = true`,
/// `light = "spot"`); on the command line every value is text.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum KnobType {
    /// A whole number.
    Integer,
    /// `true` or `false`.
    Boolean,
    /// A name, as a string.
    Name,
}

impl KnobType {
    /// The type in words, as a config error names it (`an integer`).
    pub const fn describe(self) -> &'static str {
        match self {
            Self::Integer => "an integer",
            Self::Boolean => "a boolean",
            Self::Name => "a string",
        }
    }
}

impl KnobInfo {
    /// The command-line flag: the name with `-` for `_`.
    pub fn flag(&self) -> String {
        self.name.replace('_', "-")
    }
}

/// What the generator adds to a [`Family`]: its knobs as the CLI and the config file show
/// them, and parsing a variant from `(knob, value)` pairs.
pub trait FamilyCli: Sized {
    /// The knobs, in the order `--help` and `list` show them.
    fn knobs(self) -> Vec<KnobInfo>;

    /// The kernels of a variant, in pass order, for the variant that has the most passes.
    fn kernels(self) -> Vec<Kernel>;

    /// Parses a variant from `(knob, value)` pairs; knobs not named keep their defaults.
    ///
    /// # Errors
    ///
    /// [`GenError::Knob`] naming the knob, the value and the allowed range, or
    /// [`GenError::Usage`] for a knob the family does not have.
    fn variant(self, knobs: &[(String, String)]) -> Result<FamilyVariant, GenError>;
}

/// The generator's one table of families: `Name => module`, one line each (the module has
/// `knobs()` and `parse()`). It implements [`FamilyCli`].
macro_rules! cli_families {
    ($($name:ident => $module:ident),* $(,)?) => {
        impl FamilyCli for Family {
            fn knobs(self) -> Vec<KnobInfo> {
                let mut out = match self {
                    $(Self::$name => $module::knobs(),)*
                };
                if self.default_variant().with_cookie(true).is_some() {
                    out.push(cookie_knob());
                }
                out.extend(sampling_knobs(self.default_variant().sampling()));
                out
            }

            fn kernels(self) -> Vec<Kernel> {
                scatter_shaderlib::family::kernels(self)
            }

            fn variant(self, knobs: &[(String, String)]) -> Result<FamilyVariant, GenError> {
                let known = self.knobs();
                for (name, _) in knobs {
                    if !known.iter().any(|k| k.name == name.as_str()) {
                        let names: Vec<_> = known.iter().map(|k| k.name).collect();
                        return Err(GenError::Usage(format!(
                            "knob `{}` does not apply to family {self} (its knobs: {})",
                            printable(name),
                            names.join(", ")
                        )));
                    }
                }
                let own: Vec<(String, String)> = knobs
                    .iter()
                    .filter(|(name, _)| {
                        !SAMPLING_KNOBS.contains(&name.as_str()) && name.as_str() != "cookie"
                    })
                    .cloned()
                    .collect();
                let variant = match self {
                    $(Self::$name => $module::parse(&own).map(FamilyVariant::$name)?,)*
                };
                apply_sampling(apply_cookie(variant, knobs)?, knobs)
            }
        }
    };
}

/// Allowed `cookie`.
const COOKIE_ALLOWED: &str = "true | false";

/// The `cookie` knob of the families that read a spot's cookie
/// ([`FamilyVariant::with_cookie`]), after the family's own.
fn cookie_knob() -> KnobInfo {
    KnobInfo {
        name: "cookie",
        value_name: "BOOL",
        help: "a spot light's cookie: an RGB texture (the engine's `cookie` input) projected \
               along the cone multiplies the light (light = spot only)",
        allowed: COOKIE_ALLOWED.into(),
        default: "false".into(),
        value_type: KnobType::Boolean,
    }
}

/// `variant` with the `cookie` knob among `knobs` applied (not validated).
fn apply_cookie(
    variant: FamilyVariant,
    knobs: &[(String, String)],
) -> Result<FamilyVariant, GenError> {
    let mut out = variant;
    for (name, value) in knobs.iter().filter(|(n, _)| n == "cookie") {
        let cookie = match value.trim() {
            "true" | "on" | "1" => true,
            "false" | "off" | "0" => false,
            _ => {
                return Err(VariantError {
                    knob: "cookie",
                    value: value.clone(),
                    allowed: COOKIE_ALLOWED.into(),
                }
                .into());
            }
        };
        out = out.with_cookie(cookie).ok_or_else(|| {
            GenError::Usage(format!(
                "knob `{name}` does not apply to family {}",
                out.family()
            ))
        })?;
    }
    Ok(out)
}

/// The names of the sampling knobs every family has.
const SAMPLING_KNOBS: [&str; 7] = [
    "sampling",
    "scale",
    "depth_break",
    "light_break",
    "slices",
    "slice_samples",
    "step",
];

/// The sampling knobs every family has (`scatter_frame::sampling`), after the family's own,
/// with the family's defaults `d` (`partial_sum_tree` samples epipolar lines by default).
pub fn sampling_knobs(d: SamplingKnobs) -> Vec<KnobInfo> {
    vec![
        KnobInfo {
            name: "sampling",
            value_name: "MODE",
            help: "where the per-pixel integral is evaluated: every pixel; one pixel per \
                   scale x scale block with a depth- and light-aware upsample (lowres); or \
                   samples along epipolar lines with an unwarp pass (epipolar); pixels no \
                   sample can stand for are evaluated themselves",
            allowed: Sampling::ALLOWED.into(),
            default: d.sampling.to_string(),
            value_type: KnobType::Name,
        },
        KnobInfo {
            name: "scale",
            value_name: "S",
            help: "sampling = lowres: block side (samples per axis: 1/S of the screen)",
            allowed: SCALE_ALLOWED.into(),
            default: d.scale.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "depth_break",
            value_name: "PERCENT",
            help: "sampling = lowres | epipolar: a sample stands for a pixel only within \
                   this depth difference, in percent of the nearer depth (epipolar: also \
                   where neighbouring samples of a slice are both evaluated)",
            allowed: DEPTH_BREAK_ALLOWED.into(),
            default: d.depth_break.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "light_break",
            value_name: "PERCENT",
            help: "sampling = lowres | epipolar: a pixel whose samples differ by more than \
                   this, in percent of the brightest, is evaluated itself (100: never; \
                   epipolar: also the samples between two evaluated ones that differ so)",
            allowed: LIGHT_BREAK_ALLOWED.into(),
            default: d.light_break.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "slices",
            value_name: "N",
            help: "sampling = epipolar: epipolar slices (lines from the epipole)",
            allowed: SLICES_ALLOWED.into(),
            default: d.slices.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "slice_samples",
            value_name: "M",
            help: "sampling = epipolar: samples per slice, across the screen",
            allowed: SLICE_SAMPLES_ALLOWED.into(),
            default: d.slice_samples.to_string(),
            value_type: KnobType::Integer,
        },
        KnobInfo {
            name: "step",
            value_name: "K",
            help: "sampling = epipolar: every K-th sample of a slice is evaluated (and both \
                   sides of a depth break); the rest are interpolated (1: every sample)",
            allowed: STEP_ALLOWED.into(),
            default: d.step.to_string(),
            value_type: KnobType::Integer,
        },
    ]
}

/// Allowed `scale`.
const SCALE_ALLOWED: &str = "2 | 4";
/// Allowed `depth_break`.
const DEPTH_BREAK_ALLOWED: &str = "in 1..=50";
/// Allowed `light_break`.
const LIGHT_BREAK_ALLOWED: &str = "in 1..=100";
/// Allowed `slices`.
const SLICES_ALLOWED: &str = "64 | 128 | 256 | 512 | 1024";
/// Allowed `slice_samples`.
const SLICE_SAMPLES_ALLOWED: &str = "64 | 128 | 256 | 512";
/// Allowed `step`.
const STEP_ALLOWED: &str = "1 | 2 | 4 | 8 | 16 | 32 (less than slice_samples)";

/// `variant` with the sampling knobs among `knobs` applied, validated.
fn apply_sampling(
    variant: FamilyVariant,
    knobs: &[(String, String)],
) -> Result<FamilyVariant, GenError> {
    let number = |knob: &'static str, allowed: &str, value: &str| {
        value.trim().parse::<u32>().map_err(|_| VariantError {
            knob,
            value: value.to_owned(),
            allowed: allowed.to_owned(),
        })
    };
    let mut s = variant.sampling();
    for (name, value) in knobs {
        match name.as_str() {
            "sampling" => s.sampling = value.trim().parse()?,
            "scale" => s.scale = number("scale", SCALE_ALLOWED, value)?,
            "depth_break" => s.depth_break = number("depth_break", DEPTH_BREAK_ALLOWED, value)?,
            "light_break" => s.light_break = number("light_break", LIGHT_BREAK_ALLOWED, value)?,
            "slices" => s.slices = number("slices", SLICES_ALLOWED, value)?,
            "slice_samples" => {
                s.slice_samples = number("slice_samples", SLICE_SAMPLES_ALLOWED, value)?;
            }
            "step" => s.step = number("step", STEP_ALLOWED, value)?,
            _ => {}
        }
    }
    let variant = variant.with_sampling(s);
    variant.validate()?;
    Ok(variant)
}

/// The knobs of a variant as a JSON object (serde names, sorted), as the manifest lists
/// them ([`FamilyVariant::knobs_json`]).
pub fn knobs_json(v: &FamilyVariant) -> serde_json::Value {
    v.knobs_json()
}

cli_families! {
    AreaIvsv => area_ivsv,
    HybridVolume => hybrid_volume,
    Minmax => minmax,
    PartialSumTree => partial_sum_tree,
    Prefiltered => prefiltered,
    Raymarch => raymarch,
}
