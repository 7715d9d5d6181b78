//! Every kernel family as data: [`Family`] names them, the [`KnobSet`] trait is what each
//! family's variant type (its knobs) provides, and [`FamilyVariant`] is the one enum of every
//! family's variant that the generator, the runtime, the bench, `tune` and the tests share
//! instead of keeping their own lists.
//!
//! Adding a family: its variant type implements [`KnobSet`], and [`Family`] and
//! [`FamilyVariant`] each get one arm (the compiler then names every `match` that needs one);
//! see `docs/adding-a-family.md`.

use std::fmt;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::minmax::MinmaxVariant;
use crate::raymarch::RaymarchVariant;
use crate::variant::{LightKind, Variant, VariantError};

/// A kernel family: one published method.
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

impl Family {
    /// Every family, sorted by name.
    pub const ALL: &'static [Family] = &[Family::Minmax, Family::Prefiltered, Family::Raymarch];

    /// The family's name (`--family`, config key `family`, manifest, trial names).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Minmax => MinmaxVariant::FAMILY_NAME,
            Self::Prefiltered => Variant::FAMILY_NAME,
            Self::Raymarch => RaymarchVariant::FAMILY_NAME,
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

    /// The family's variant with every knob at its default (the paper's choice).
    pub fn default_variant(self) -> FamilyVariant {
        match self {
            Self::Minmax => MinmaxVariant::default().into(),
            Self::Prefiltered => Variant::default().into(),
            Self::Raymarch => RaymarchVariant::default().into(),
        }
    }

    /// The family's conformance grid ([`KnobSet::grid`]).
    pub fn grid(self) -> Vec<FamilyVariant> {
        fn all<V: KnobSet>() -> Vec<FamilyVariant> {
            V::grid().into_iter().map(Into::into).collect()
        }
        match self {
            Self::Minmax => all::<MinmaxVariant>(),
            Self::Prefiltered => all::<Variant>(),
            Self::Raymarch => all::<RaymarchVariant>(),
        }
    }
}

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A family name that is none of [`Family::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("family must be {}, got {}", Family::ALL.iter().map(|f| f.name()).collect::<Vec<_>>().join(" | "), crate::variant::printable(.0))]
pub struct UnknownFamily(pub String);

impl std::str::FromStr for Family {
    type Err = UnknownFamily;

    fn from_str(s: &str) -> Result<Self, UnknownFamily> {
        Self::ALL
            .iter()
            .copied()
            .find(|f| f.name() == s)
            .ok_or_else(|| UnknownFamily(s.to_owned()))
    }
}

/// What each family's variant type (its knobs) provides.
pub trait KnobSet:
    Copy
    + fmt::Debug
    + fmt::Display
    + PartialEq
    + Default
    + Serialize
    + DeserializeOwned
    + Into<FamilyVariant>
{
    /// The family's name (manifest, CLI, trial names).
    const FAMILY_NAME: &'static str;
    /// The family.
    const FAMILY: Family;

    /// Checks every knob, naming the first one out of range.
    ///
    /// # Errors
    ///
    /// [`VariantError`] naming the knob, the value and the allowed range.
    fn validate(&self) -> Result<(), VariantError>;

    /// The variant id used in file names, manifest entries and trial names.
    fn id(&self) -> String;

    /// The light type the kernels are compiled for.
    fn light(&self) -> LightKind;

    /// The conformance grid: every variant the GPU-against-mirror trials run.
    fn grid() -> Vec<Self>;
}

impl KnobSet for Variant {
    const FAMILY_NAME: &'static str = "prefiltered";
    const FAMILY: Family = Family::Prefiltered;

    fn validate(&self) -> Result<(), VariantError> {
        Variant::validate(self)
    }

    fn id(&self) -> String {
        Variant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    /// Regions 1..=4 (every other knob at every value).
    fn grid() -> Vec<Self> {
        Variant::grid(1..=4)
    }
}

impl KnobSet for RaymarchVariant {
    const FAMILY_NAME: &'static str = "raymarch";
    const FAMILY: Family = Family::Raymarch;

    fn validate(&self) -> Result<(), VariantError> {
        RaymarchVariant::validate(self)
    }

    fn id(&self) -> String {
        RaymarchVariant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    fn grid() -> Vec<Self> {
        RaymarchVariant::grid()
    }
}

impl KnobSet for MinmaxVariant {
    const FAMILY_NAME: &'static str = "minmax";
    const FAMILY: Family = Family::Minmax;

    fn validate(&self) -> Result<(), VariantError> {
        MinmaxVariant::validate(self)
    }

    fn id(&self) -> String {
        MinmaxVariant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    fn grid() -> Vec<Self> {
        MinmaxVariant::grid()
    }
}

/// One validated-or-not variant of some family: the one enum of every family's variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FamilyVariant {
    /// A minmax-family variant.
    Minmax(MinmaxVariant),
    /// A prefiltered-family variant.
    Prefiltered(Variant),
    /// A raymarch-family variant.
    Raymarch(RaymarchVariant),
}

impl From<MinmaxVariant> for FamilyVariant {
    fn from(v: MinmaxVariant) -> Self {
        Self::Minmax(v)
    }
}

impl From<Variant> for FamilyVariant {
    fn from(v: Variant) -> Self {
        Self::Prefiltered(v)
    }
}

impl From<RaymarchVariant> for FamilyVariant {
    fn from(v: RaymarchVariant) -> Self {
        Self::Raymarch(v)
    }
}

/// Calls `$body` with `$v` bound to the variant inside any arm.
macro_rules! each {
    ($self:expr, $v:ident => $body:expr) => {
        match $self {
            FamilyVariant::Minmax($v) => $body,
            FamilyVariant::Prefiltered($v) => $body,
            FamilyVariant::Raymarch($v) => $body,
        }
    };
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

    /// The variant id (`<kernel>.<id>.<ext>` file names, manifest entries).
    pub fn id(&self) -> String {
        each!(self, v => KnobSet::id(v))
    }

    /// `family::id`, the head of every trial name.
    pub fn trial_name(&self) -> String {
        format!("{}::{}", self.family(), self.id())
    }

    /// The light type the kernels are compiled for.
    pub fn light(&self) -> LightKind {
        each!(self, v => KnobSet::light(v))
    }

    /// Checks every knob.
    ///
    /// # Errors
    ///
    /// [`VariantError`] naming the knob, the value and the allowed range.
    pub fn validate(&self) -> Result<(), VariantError> {
        each!(self, v => KnobSet::validate(v))
    }
}

impl fmt::Display for FamilyVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}::{}", self.family(), self.id())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_family_round_trips_its_grid() {
        for &family in Family::ALL {
            let grid = family.grid();
            assert!(!grid.is_empty(), "{family}");
            for v in &grid {
                assert_eq!(v.family(), family);
                assert!(v.validate().is_ok(), "{v}");
                assert!(v.trial_name().starts_with(family.name()));
            }
            assert_eq!(family.default_variant().family(), family);
            assert!(family.default_variant().validate().is_ok());
        }
        assert_eq!(Family::Prefiltered.grid().len(), 2016);
    }
}
