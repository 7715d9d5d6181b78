//! The family registry: what the generator knows about each kernel family beyond what
//! shaderlib's IR says (its knobs, how a variant is parsed, which textures and buffers the
//! engine allocates and how each pass is dispatched).
//!
//! [`Family`] and [`FamilyVariant`] are the shared ones (`scatter_frame::family`, re-exported
//! by shaderlib with [`KernelFamily`]: kernels and plan); the generator adds the knobs as the
//! CLI shows them ([`FamilyCli`], one module per family like [`prefiltered`]). The CLI, the
//! config file, the manifest and the tests pick a family up from [`Family::ALL`]; see
//! `docs/adding-a-family.md`.

pub mod minmax;
pub mod prefiltered;
pub mod raymarch;

use scatter_shaderlib::Kernel;
use scatter_shaderlib::prefiltered::variant::printable;
use serde::Serialize;

pub use scatter_shaderlib::family::{Family, FamilyVariant, KernelFamily, KnobSet};
pub use scatter_shaderlib::plan::{
    Alternative, BindingSource, BufferDesc, Formula, Parameter, PassPlan, Plan, Resource,
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
                match self {
                    $(Self::$name => $module::knobs(),)*
                }
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
                match self {
                    $(Self::$name => $module::parse(knobs).map(FamilyVariant::$name),)*
                }
            }
        }
    };
}

/// The knobs of a variant as a JSON object (serde names, sorted), as the manifest lists
/// them ([`FamilyVariant::knobs_json`]).
pub fn knobs_json(v: &FamilyVariant) -> serde_json::Value {
    v.knobs_json()
}

cli_families! {
    Minmax => minmax,
    Prefiltered => prefiltered,
    Raymarch => raymarch,
}
