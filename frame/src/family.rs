//! Every kernel family as data: [`Family`] names them, the [`KnobSet`] trait is what each
//! family's variant type (its knobs) provides, and [`FamilyVariant`] is the one enum of every
//! family's variant that the generator, the runtime, the bench, `tune` and the tests share
//! instead of keeping their own lists.
//!
//! Adding a family: its variant type implements [`KnobSet`] (in the family's own module) and
//! gets one line in the `families!` table below; see `docs/adding-a-family.md`.

use std::fmt;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::area_ivsv::AreaIvsvVariant;
use crate::hybrid_volume::HybridVolumeVariant;
use crate::minmax::MinmaxVariant;
use crate::partial_sum_tree::PartialSumTreeVariant;
use crate::raymarch::RaymarchVariant;
use crate::sampling::SamplingKnobs;
use crate::variant::{LightKind, PrefilteredVariant, VariantError};

/// The one table of every family: `Name(variant type)`, one line each. It defines [`Family`]
/// (with `ALL`, `name`, `summary`, `default_variant`, `grid`) and [`FamilyVariant`] (with
/// its `From` impls, `family`, `id`, `light`, `validate`), all from the variant types'
/// [`KnobSet`] impls.
macro_rules! families {
    ($($(#[$doc:meta])* $name:ident($ty:ty)),* $(,)?) => {
        /// A kernel family: one published method.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
        #[serde(rename_all = "snake_case")]
        pub enum Family {
            $($(#[$doc])* $name,)*
        }

        impl Family {
            /// Every family, sorted by name.
            pub const ALL: &'static [Family] = &[$(Family::$name),*];

            /// The family's name (`--family`, config key `family`, manifest, trial names).
            pub const fn name(self) -> &'static str {
                match self {
                    $(Self::$name => <$ty as KnobSet>::FAMILY_NAME,)*
                }
            }

            /// One line: the method and its paper.
            pub const fn summary(self) -> &'static str {
                match self {
                    $(Self::$name => <$ty as KnobSet>::SUMMARY,)*
                }
            }

            /// The family's variant with every knob at its default (the paper's choice; the
            /// prefiltered family's 4 regions are measured, `PrefilteredVariant`'s docs).
            pub fn default_variant(self) -> FamilyVariant {
                match self {
                    $(Self::$name => <$ty>::default().into(),)*
                }
            }

            /// The family's conformance grid ([`KnobSet::grid`]).
            pub fn grid(self) -> Vec<FamilyVariant> {
                match self {
                    $(Self::$name => <$ty as KnobSet>::grid().into_iter().map(Into::into).collect(),)*
                }
            }
        }

        /// One variant of some family: the one enum of every family's variant.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum FamilyVariant {
            $($(#[$doc])* $name($ty),)*
        }

        $(impl From<$ty> for FamilyVariant {
            fn from(v: $ty) -> Self {
                Self::$name(v)
            }
        })*

        impl FamilyVariant {
            /// The family.
            pub const fn family(&self) -> Family {
                match self {
                    $(Self::$name(_) => Family::$name,)*
                }
            }

            /// The variant id (`<kernel>.<id>.<ext>` file names, manifest entries).
            pub fn id(&self) -> String {
                match self {
                    $(Self::$name(v) => KnobSet::id(v),)*
                }
            }

            /// `family::id`, the head of every trial name.
            pub fn trial_name(&self) -> String {
                format!("{}::{}", self.family(), self.id())
            }

            /// The light type the kernels are compiled for.
            pub fn light(&self) -> LightKind {
                match self {
                    $(Self::$name(v) => KnobSet::light(v),)*
                }
            }

            /// The knobs as a JSON object (serde names, sorted by name), as the manifest and
            /// the config file spell them.
            pub fn knobs_json(&self) -> serde_json::Value {
                match self {
                    $(Self::$name(v) => serde_json::to_value(v).unwrap_or(serde_json::Value::Null),)*
                }
            }

            /// The knobs as `(name, value)` pairs sorted by name, every knob spelled out
            /// (the light included): `scatter-gen --family F --<name> <value> ...` with `_`
            /// as `-` in the flag emits this variant.
            pub fn knob_values(&self) -> Vec<(String, String)> {
                match self.knobs_json() {
                    serde_json::Value::Object(map) => map
                        .into_iter()
                        .map(|(k, v)| {
                            let value = match v {
                                serde_json::Value::String(s) => s,
                                other => other.to_string(),
                            };
                            (k, value)
                        })
                        .collect(),
                    _ => Vec::new(),
                }
            }

            /// The variant with another light, every other knob kept.
            #[must_use]
            pub fn with_light(self, light: LightKind) -> Self {
                match self {
                    $(Self::$name(v) => Self::$name(KnobSet::with_light(v, light)),)*
                }
            }

            /// Where the family evaluates its per-pixel integral.
            pub fn sampling(&self) -> SamplingKnobs {
                match self {
                    $(Self::$name(v) => KnobSet::sampling(v),)*
                }
            }

            /// The variant with other sampling knobs, every other knob kept.
            #[must_use]
            pub fn with_sampling(self, sampling: SamplingKnobs) -> Self {
                match self {
                    $(Self::$name(v) => Self::$name(KnobSet::with_sampling(v, sampling)),)*
                }
            }

            /// Whether the variant reads a spot light's cookie ([`KnobSet::cookie`]).
            pub fn cookie(&self) -> bool {
                match self {
                    $(Self::$name(v) => KnobSet::cookie(v),)*
                }
            }

            /// The variant with the `cookie` knob set, or `None` for a family without it
            /// ([`KnobSet::with_cookie`]).
            pub fn with_cookie(self, cookie: bool) -> Option<Self> {
                match self {
                    $(Self::$name(v) => KnobSet::with_cookie(v, cookie).map(Self::$name),)*
                }
            }

            /// The knobs without the light, short ([`KnobSet::marker`]); empty for a
            /// family whose only knob is the light.
            pub fn marker(&self) -> String {
                match self {
                    $(Self::$name(v) => KnobSet::marker(v),)*
                }
            }

            /// `family-marker` (or the family's name alone when the marker is empty): a
            /// short name for tables and charts, light excluded.
            pub fn label(&self) -> String {
                let marker = self.marker();
                if marker.is_empty() {
                    self.family().name().to_owned()
                } else {
                    format!("{}-{marker}", self.family())
                }
            }

            /// Checks every knob.
            ///
            /// # Errors
            ///
            /// [`VariantError`] naming the knob, the value and the allowed range.
            pub fn validate(&self) -> Result<(), VariantError> {
                match self {
                    $(Self::$name(v) => KnobSet::validate(v),)*
                }
            }
        }
    };
}

families! {
    /// Wyman & Dai 2013: `ivsv_rectify`, `ivsv_scan`, `ivsv_gather`, `ivsv_interleave_sum`
    /// (interleaved variants); area lights only.
    AreaIvsv(AreaIvsvVariant),
    /// Wyman & Ramsey 2008: `rectify` (the prefiltered family's), `volume_bounds`,
    /// `volume_march`.
    HybridVolume(HybridVolumeVariant),
    /// Chen et al. 2011: `rectify` (the prefiltered family's), `minmax_build`, `minmax_traverse`.
    Minmax(MinmaxVariant),
    /// Baran et al. 2010: `rectify` (the prefiltered family's), `pst_sweep` (epipolar samples
    /// only), its unwarp and fallback.
    PartialSumTree(PartialSumTreeVariant),
    /// Klehm et al. 2014: `rectify`, `prefilter`, `scatter`.
    Prefiltered(PrefilteredVariant),
    /// Tóth & Umenhoffer 2009: `raymarch`, `interleave_sum` (interleaved variants).
    Raymarch(RaymarchVariant),
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
    /// One line: the method and its paper.
    const SUMMARY: &'static str;

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

    /// The variant with another light, every other knob kept.
    #[must_use]
    fn with_light(self, light: LightKind) -> Self;

    /// The knobs without the light, short, for tables and charts (`m32-r4`, `n64-i1`): the
    /// knobs a sweep usually varies always, every other knob only where it differs from
    /// its default; empty when the light is the only knob.
    fn marker(&self) -> String;

    /// The conformance grid: every variant the GPU-against-mirror trials run.
    fn grid() -> Vec<Self>;

    /// Where the family evaluates its per-pixel integral ([`crate::sampling`]).
    fn sampling(&self) -> SamplingKnobs;

    /// The variant with other sampling knobs, every other knob kept (not validated: a
    /// raymarch variant that interleaves rejects sampled evaluation in `validate`).
    #[must_use]
    fn with_sampling(self, sampling: SamplingKnobs) -> Self;

    /// Whether the variant reads a spot light's cookie ([`crate::cookie`]; `false` for a
    /// family without the `cookie` knob).
    fn cookie(&self) -> bool {
        false
    }

    /// The variant with the `cookie` knob set, every other knob kept (not validated), or
    /// `None` for a family without the knob.
    fn with_cookie(self, cookie: bool) -> Option<Self> {
        let _ = cookie;
        None
    }
}

impl fmt::Display for FamilyVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}::{}", self.family(), self.id())
    }
}

impl FamilyVariant {
    /// Whether a rectified map `width` columns wide is wide enough for the variant: a
    /// prefiltered variant needs [`PrefilteredVariant::min_rectified_width`] columns (the
    /// frame set-up refuses fewer with `FrameError::RectifiedTooNarrow`); every other
    /// family takes any width.
    pub fn fits_rectified_width(&self, width: u32) -> bool {
        match self {
            Self::Prefiltered(v) => v.min_rectified_width() <= width,
            _ => true,
        }
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
        // 2016 Fourier variants, 64 of the moment basis, 12 with a cookie, 132 with coarse
        // filtered columns and 30 with `resume`.
        assert_eq!(Family::Prefiltered.grid().len(), 2016 + 64 + 12 + 132 + 30);
    }

    #[test]
    fn marker_and_light_name_the_variant() {
        for &family in Family::ALL {
            let grid = family.grid();
            let mut seen = std::collections::HashSet::new();
            for v in &grid {
                assert!(
                    seen.insert((v.marker(), v.light())),
                    "{v}: marker {}",
                    v.marker()
                );
                assert!(v.label().starts_with(family.name()), "{v}");
                for &light in LightKind::ALL {
                    let w = v.with_light(light);
                    if w.validate().is_err() {
                        continue;
                    }
                    assert_eq!(
                        (w.light(), w.marker(), w.family()),
                        (light, v.marker(), family)
                    );
                }
            }
        }
        assert_eq!(
            Family::Prefiltered.default_variant().label(),
            "prefiltered-m32-r4"
        );
        assert_eq!(
            Family::Raymarch.default_variant().label(),
            "raymarch-n64-i1"
        );
        assert_eq!(Family::Minmax.default_variant().label(), "minmax");
    }

    #[test]
    fn sixteen_regions_need_256_columns() {
        let r16 = FamilyVariant::from(PrefilteredVariant {
            regions: 16,
            ..PrefilteredVariant::default()
        });
        assert!(r16.fits_rectified_width(256));
        assert!(!r16.fits_rectified_width(128));
        assert!(Family::Minmax.default_variant().fits_rectified_width(1));
    }

    #[test]
    fn resume_needs_a_stride_and_names_itself() {
        let v = PrefilteredVariant {
            resume: true,
            ..PrefilteredVariant::default()
        };
        let err = v.validate().expect_err("resume with filtered_stride = 1");
        assert_eq!(err.knob, "resume");
        assert!(err.to_string().contains("filtered_stride"), "{err}");
        let ok = PrefilteredVariant {
            filtered_stride: 8,
            ..v
        };
        assert!(ok.validate().is_ok());
        assert!(ok.id().ends_with("-stride8-resume"), "{}", ok.id());
        // Sized for its stride like the coarse map: 8 x 4^2 columns.
        assert!(FamilyVariant::from(ok).fits_rectified_width(128));
        assert!(!FamilyVariant::from(ok).fits_rectified_width(64));
    }
}
