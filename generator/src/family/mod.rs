//! The family registry: what the generator knows about each kernel family beyond what
//! shaderlib's IR says (its knobs, how a variant is parsed, which textures and buffers the
//! engine allocates and how each pass is dispatched).
//!
//! Adding a family (`raymarch`, `minmax`, ...) means adding a [`Family`] value, a
//! [`FamilyVariant`] arm and a module like [`prefiltered`]; the CLI, the config file, the
//! manifest and the tests pick it up from [`Family::ALL`] without changing shape.

pub mod minmax;
pub mod prefiltered;
pub mod raymarch;

use std::fmt;

use scatter_shaderlib::prefiltered::variant::printable;
use scatter_shaderlib::{Kernel, KernelParams};
use serde::Serialize;

pub use scatter_shaderlib::plan::{
    Alternative, BindingSource, BufferDesc, Formula, Parameter, PassPlan, Plan, Resource,
    SamplerDesc, TextureDesc,
};

use crate::GenError;

/// A kernel family the generator can emit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// Chen et al. 2011: `rectify` (the prefiltered family's), `minmax_build`,
    /// `minmax_march`.
    Minmax,
    /// Klehm et al. 2014: `rectify`, `prefilter`, `scatter`.
    Prefiltered,
    /// Tóth & Umenhoffer 2009: `raymarch`, `interleave_sum` (interleaved variants).
    Raymarch,
}

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
}

impl KnobInfo {
    /// The command-line flag: the name with `-` for `_`.
    pub fn flag(&self) -> String {
        self.name.replace('_', "-")
    }
}

impl Family {
    /// Every family, sorted by name.
    pub const ALL: &'static [Family] = &[Family::Minmax, Family::Prefiltered, Family::Raymarch];

    /// The family's name (`--family`, config key `family`, manifest).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Minmax => "minmax",
            Self::Prefiltered => "prefiltered",
            Self::Raymarch => "raymarch",
        }
    }

    /// One line: the method and its paper.
    pub const fn summary(self) -> &'static str {
        match self {
            Self::Minmax => {
                "Chen et al. 2011, 1D min-max mipmaps: each pixel marches its rectified row \
                 through a min-max binary tree, skipping wholly lit or shadowed spans"
            }
            Self::Prefiltered => {
                "Klehm et al. 2014, prefiltered single scattering: Fourier-basis visibility \
                 prefiltered along epipolar rows of a rectified shadow map"
            }
            Self::Raymarch => {
                "Toth & Umenhoffer 2009, ray marching through the standard shadow map, \
                 optionally with interleaved sampling and a separable sum filter"
            }
        }
    }

    /// The knobs, in the order `--help` and `list` show them.
    pub fn knobs(self) -> Vec<KnobInfo> {
        match self {
            Self::Minmax => minmax::knobs(),
            Self::Prefiltered => prefiltered::knobs(),
            Self::Raymarch => raymarch::knobs(),
        }
    }

    /// The variant with every knob at its default (the paper's choice).
    pub fn default_variant(self) -> FamilyVariant {
        match self {
            Self::Minmax => FamilyVariant::Minmax(Default::default()),
            Self::Prefiltered => FamilyVariant::Prefiltered(Default::default()),
            Self::Raymarch => FamilyVariant::Raymarch(Default::default()),
        }
    }

    /// The kernels of a variant, in pass order (read from shaderlib, not listed here), for
    /// the variant that has the most passes.
    pub fn kernels(self) -> Vec<Kernel> {
        let variant = match self {
            Self::Raymarch => {
                FamilyVariant::Raymarch(scatter_shaderlib::raymarch::RaymarchVariant {
                    interleave: 2,
                    ..Default::default()
                })
            }
            _ => self.default_variant(),
        };
        variant
            .kernel_params()
            .iter()
            .map(KernelParams::kernel)
            .collect()
    }

    /// Parses a variant from `(knob, value)` pairs; knobs not named keep their defaults.
    ///
    /// # Errors
    ///
    /// [`GenError::Knob`] naming the knob, the value and the allowed range, or
    /// [`GenError::Usage`] for a knob the family does not have.
    pub fn variant(self, knobs: &[(String, String)]) -> Result<FamilyVariant, GenError> {
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
        match self {
            Self::Minmax => minmax::parse(knobs).map(FamilyVariant::Minmax),
            Self::Prefiltered => prefiltered::parse(knobs).map(FamilyVariant::Prefiltered),
            Self::Raymarch => raymarch::parse(knobs).map(FamilyVariant::Raymarch),
        }
    }
}

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Family {
    type Err = GenError;

    fn from_str(s: &str) -> Result<Self, GenError> {
        Self::ALL
            .iter()
            .copied()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|f| f.name()).collect();
                GenError::Usage(format!(
                    "family must be {}, got {}",
                    names.join(" | "),
                    printable(s)
                ))
            })
    }
}

/// One validated variant of some family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FamilyVariant {
    /// A minmax-family variant.
    Minmax(scatter_shaderlib::minmax::MinmaxVariant),
    /// A prefiltered-family variant.
    Prefiltered(scatter_shaderlib::prefiltered::Variant),
    /// A raymarch-family variant.
    Raymarch(scatter_shaderlib::raymarch::RaymarchVariant),
}

impl FamilyVariant {
    /// The family.
    pub const fn family(&self) -> Family {
        match self {
            Self::Minmax(_) => Family::Minmax,
            Self::Prefiltered(_) => Family::Prefiltered,
            Self::Raymarch(_) => Family::Raymarch,
        }
    }

    /// The variant id used in file names (`<kernel>.<id>.<ext>`).
    pub fn id(&self) -> String {
        match self {
            Self::Minmax(v) => v.id(),
            Self::Prefiltered(v) => v.id(),
            Self::Raymarch(v) => v.id(),
        }
    }

    /// The knobs as a JSON object (serde names, sorted).
    pub fn knobs_json(&self) -> serde_json::Value {
        match self {
            Self::Minmax(v) => serde_json::to_value(v).unwrap_or(serde_json::Value::Null),
            Self::Prefiltered(v) => serde_json::to_value(v).unwrap_or(serde_json::Value::Null),
            Self::Raymarch(v) => serde_json::to_value(v).unwrap_or(serde_json::Value::Null),
        }
    }

    /// The kernel parameters of every kernel, in pass order, as shaderlib defines them.
    pub fn kernel_params(&self) -> Vec<KernelParams> {
        match self {
            Self::Minmax(v) => KernelParams::minmax(*v).to_vec(),
            Self::Prefiltered(v) => KernelParams::prefiltered(*v).to_vec(),
            Self::Raymarch(v) => KernelParams::raymarch(*v),
        }
    }

    /// The resources, parameters and passes an engine needs to run the variant.
    pub fn plan(&self) -> Plan {
        match self {
            Self::Minmax(v) => minmax::plan(v),
            Self::Prefiltered(v) => prefiltered::plan(v),
            Self::Raymarch(v) => raymarch::plan(v),
        }
    }
}
