//! The sampling stage every family can use (DESIGN.md, "Sampling"): where a family evaluates
//! its per-pixel integral. `pixels` evaluates it at every screen pixel; `lowres` at one pixel
//! of every `scale x scale` block (a fixed pixel, so that samples do not jump between frames)
//! and fills the screen with a depth- and light-aware upsample, evaluating the pixels no
//! sample can stand for.
//!
//! # The lowres pass
//!
//! Sample `(i, j)` stands on pixel `(min(i S, W - 1), min(j S, H - 1))`, `S` the scale: the
//! first pixel of block `(i, j)`, and one more column and row of samples on the screen's last
//! pixels. A pixel of block `(i, j)` takes the bilinear blend (by its place between their
//! pixels) of the samples `(i, j)`, `(i + 1, j)`, `(i, j + 1)`, `(i + 1, j + 1)`, each kept
//! only when its pixel's view depth is within `depth_break` percent of the pixel's own
//! (`|a - b| <= depth_break / 100 * min(a, b)`, equal depths always): a joint bilateral
//! filter with a box range kernel. The box, not a Gaussian, because a sample across a depth
//! break must get no weight at all (no halo), while samples on the same surface keep their
//! bilinear weights (no blur beyond the sample spacing). A pixel is evaluated itself where
//! no sample is close in depth (a thin occluder, a silhouette between samples), or where the
//! samples it would blend differ by more than `light_break` percent of the brightest (a
//! shadow edge crossing the block, the lamp on screen: the second refinement criterion of
//! Yusov 2013).
//!
//! All of it is one pass of the family's per-pixel kernel: a workgroup evaluates the samples
//! of its 8 x 8 blocks and of the next column and row of blocks (the taps of a block's
//! pixels) into workgroup memory, then blends each of its blocks' pixels or puts it on a
//! list, then evaluates the list with every invocation (so that the lanes stay busy where a
//! few blocks hold most of it). The extra column and row cost `(9^2 - 8^2) / 8^2 = 27 %`
//! more sample evaluations, 7 % (scale 2) or 1.7 % (scale 4) of a per-pixel evaluation
//! (samples at block centres would need a ring on every side, 56 %); in exchange no sample
//! texture, no second pass and no list in memory outside the workgroup exist, and the light
//! criterion, which needs the samples' values, costs nothing extra.

use serde::{Deserialize, Serialize};
use std::fmt;

use crate::variant::VariantError;

/// Where a family evaluates its per-pixel integral.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Every screen pixel (the methods as published).
    #[default]
    Pixels,
    /// One pixel of every `scale x scale` block, then a depth- and light-aware upsample;
    /// pixels no sample can stand for are evaluated per pixel.
    Lowres,
}

impl Sampling {
    /// Every value, sorted by name.
    pub const ALL: &'static [Sampling] = &[Sampling::Lowres, Sampling::Pixels];
    /// The allowed names, for error messages.
    pub const ALLOWED: &'static str = "lowres | pixels";

    /// The value's name (serde, CLI, variant ids).
    pub const fn name(self) -> &'static str {
        match self {
            Sampling::Pixels => "pixels",
            Sampling::Lowres => "lowres",
        }
    }
}

impl fmt::Display for Sampling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Sampling {
    type Err = VariantError;
    fn from_str(s: &str) -> Result<Self, VariantError> {
        match s {
            "pixels" => Ok(Sampling::Pixels),
            "lowres" => Ok(Sampling::Lowres),
            _ => Err(VariantError {
                knob: "sampling",
                value: s.to_owned(),
                allowed: Self::ALLOWED.into(),
            }),
        }
    }
}

/// The sampling knobs every family's variant carries (as the fields `sampling`, `scale`,
/// `depth_break`, `light_break`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SamplingKnobs {
    /// Where the family evaluates its integral.
    pub sampling: Sampling,
    /// `lowres`: the block side S, 2 or 4 (1/2 or 1/4 of the screen per axis).
    pub scale: u32,
    /// `lowres`: the depth difference, in percent of the nearer depth, beyond which a
    /// sample does not stand for a pixel (1..=50).
    pub depth_break: u32,
    /// `lowres`: the spread of a pixel's samples, in percent of the brightest, beyond which
    /// the pixel is evaluated itself (1..=100; 100 never refines: the spread of
    /// non-negative values never exceeds the largest).
    pub light_break: u32,
}

impl Default for SamplingKnobs {
    /// `pixels` (every pixel), with the lowres knobs at their defaults.
    fn default() -> Self {
        Self {
            sampling: Sampling::Pixels,
            scale: Self::DEFAULT_SCALE,
            depth_break: Self::DEFAULT_DEPTH_BREAK,
            light_break: Self::DEFAULT_LIGHT_BREAK,
        }
    }
}

impl SamplingKnobs {
    /// Allowed `scale`.
    pub const SCALES: [u32; 2] = [2, 4];
    /// `scale` when not chosen.
    pub const DEFAULT_SCALE: u32 = 2;
    /// Allowed `depth_break` (percent).
    pub const DEPTH_BREAK: std::ops::RangeInclusive<u32> = 1..=50;
    /// `depth_break` when not chosen (percent). Measured (raymarch N = 64 at scale 4, the 24
    /// suite poses at 320x180, light break 20): 2 / 5 / 10 % gave a mean rel L1 of 1.17 /
    /// 1.19 / 1.18 % with 19.5 / 5.5 / 1.8 % of the pixels evaluated for depth: 10 % is as
    /// accurate for the fewest evaluations.
    pub const DEFAULT_DEPTH_BREAK: u32 = 10;
    /// Allowed `light_break` (percent).
    pub const LIGHT_BREAK: std::ops::RangeInclusive<u32> = 1..=100;
    /// `light_break` when not chosen (percent). Measured as `depth_break` (depth break 5):
    /// 10 / 20 / 40 / 100 % gave 1.18 / 1.19 / 1.24 / 1.78 % with 7.7 / 4.2 / 2.2 / 0 % of
    /// the pixels evaluated for light; per pixel 1.04 %.
    pub const DEFAULT_LIGHT_BREAK: u32 = 20;

    /// `lowres` at `scale`, the depth break at its default.
    pub fn lowres(scale: u32) -> Self {
        Self {
            sampling: Sampling::Lowres,
            scale,
            ..Self::default()
        }
    }

    /// Whether the family evaluates fewer samples than pixels (and has the upsample pass).
    pub fn is_sampled(&self) -> bool {
        self.sampling != Sampling::Pixels
    }

    /// Checks the knobs; the error names the first offending one. The lowres knobs must stay
    /// at their defaults with `sampling = pixels`, so that one configuration has one id.
    pub fn validate(&self) -> Result<(), VariantError> {
        let d = Self::default();
        match self.sampling {
            Sampling::Pixels => {
                if self.scale != d.scale {
                    return Err(VariantError {
                        knob: "scale",
                        value: self.scale.to_string(),
                        allowed: format!("{} (a lowres knob; set sampling = lowres)", d.scale),
                    });
                }
                if self.depth_break != d.depth_break {
                    return Err(VariantError {
                        knob: "depth_break",
                        value: self.depth_break.to_string(),
                        allowed: format!(
                            "{} (a lowres knob; set sampling = lowres)",
                            d.depth_break
                        ),
                    });
                }
                if self.light_break != d.light_break {
                    return Err(VariantError {
                        knob: "light_break",
                        value: self.light_break.to_string(),
                        allowed: format!(
                            "{} (a lowres knob; set sampling = lowres)",
                            d.light_break
                        ),
                    });
                }
            }
            Sampling::Lowres => {
                if !Self::SCALES.contains(&self.scale) {
                    return Err(VariantError {
                        knob: "scale",
                        value: self.scale.to_string(),
                        allowed: "2 or 4 (samples per axis: 1/2 or 1/4 of the screen)".into(),
                    });
                }
                if !Self::DEPTH_BREAK.contains(&self.depth_break) {
                    return Err(VariantError {
                        knob: "depth_break",
                        value: self.depth_break.to_string(),
                        allowed: "in 1..=50 (percent of the nearer depth)".into(),
                    });
                }
                if !Self::LIGHT_BREAK.contains(&self.light_break) {
                    return Err(VariantError {
                        knob: "light_break",
                        value: self.light_break.to_string(),
                        allowed: "in 1..=100 (percent of the brightest sample; 100 never refines)"
                            .into(),
                    });
                }
            }
        }
        Ok(())
    }

    /// The tail of a variant id: empty for `pixels` (ids of per-pixel variants are those of
    /// before the knob), `-lowres{scale}-b{depth_break}-l{light_break}` otherwise.
    pub fn id_suffix(&self) -> String {
        match self.sampling {
            Sampling::Pixels => String::new(),
            Sampling::Lowres => format!(
                "-lowres{}-b{}-l{}",
                self.scale, self.depth_break, self.light_break
            ),
        }
    }

    /// The tail of a marker: empty for `pixels`, `-lr{scale}` (and `-b{depth_break}`,
    /// `-l{light_break}` where they differ from the defaults) otherwise.
    pub fn marker_suffix(&self) -> String {
        match self.sampling {
            Sampling::Pixels => String::new(),
            Sampling::Lowres => {
                let mut m = format!("-lr{}", self.scale);
                if self.depth_break != Self::DEFAULT_DEPTH_BREAK {
                    m += &format!("-b{}", self.depth_break);
                }
                if self.light_break != Self::DEFAULT_LIGHT_BREAK {
                    m += &format!("-l{}", self.light_break);
                }
                m
            }
        }
    }

    /// The sample grid for a `screen` (width, height): the screen itself for `pixels`;
    /// for `lowres` a sample on every S-th pixel from the first and one on the last,
    /// `ceil((screen - 1) / scale) + 1`.
    pub fn grid_size(&self, screen: [u32; 2]) -> [u32; 2] {
        match self.sampling {
            Sampling::Pixels => screen,
            Sampling::Lowres => screen.map(|s| s.saturating_sub(1).div_ceil(self.scale) + 1),
        }
    }

    /// The depth break as a fraction (`depth_break / 100`), as the kernels compile it in.
    pub fn depth_break_fraction(&self) -> f32 {
        self.depth_break as f32 / 100.0
    }

    /// The light break as a fraction (`light_break / 100`), as the kernels compile it in.
    pub fn light_break_fraction(&self) -> f32 {
        self.light_break as f32 / 100.0
    }
}

/// Implements, for a variant type with the fields `sampling`, `scale`, `depth_break` and
/// `light_break`, `sampling_knobs` (those fields as [`SamplingKnobs`]) and
/// `with_sampling_knobs`.
macro_rules! sampling_fields {
    ($t:ty) => {
        impl $t {
            /// The sampling knobs.
            pub fn sampling_knobs(&self) -> $crate::sampling::SamplingKnobs {
                $crate::sampling::SamplingKnobs {
                    sampling: self.sampling,
                    scale: self.scale,
                    depth_break: self.depth_break,
                    light_break: self.light_break,
                }
            }

            /// The variant with other sampling knobs, every other knob kept (not
            /// validated).
            #[must_use]
            pub fn with_sampling_knobs(self, s: $crate::sampling::SamplingKnobs) -> Self {
                Self {
                    sampling: s.sampling,
                    scale: s.scale,
                    depth_break: s.depth_break,
                    light_break: s.light_break,
                    ..self
                }
            }
        }
    };
}
pub(crate) use sampling_fields;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knobs_validate_and_name_the_knob() {
        assert!(SamplingKnobs::default().validate().is_ok());
        assert!(SamplingKnobs::lowres(2).validate().is_ok());
        assert!(SamplingKnobs::lowres(4).validate().is_ok());
        assert_eq!(
            SamplingKnobs::lowres(3).validate().unwrap_err().knob,
            "scale"
        );
        let pixels_scale = SamplingKnobs {
            scale: 4,
            ..SamplingKnobs::default()
        };
        assert_eq!(pixels_scale.validate().unwrap_err().knob, "scale");
        let bad_break = SamplingKnobs {
            depth_break: 0,
            ..SamplingKnobs::lowres(2)
        };
        assert_eq!(bad_break.validate().unwrap_err().knob, "depth_break");
        assert_eq!("lowres".parse::<Sampling>(), Ok(Sampling::Lowres));
        assert_eq!("epi".parse::<Sampling>().unwrap_err().knob, "sampling");
    }

    #[test]
    fn ids_and_grids() {
        assert_eq!(SamplingKnobs::default().id_suffix(), "");
        assert_eq!(SamplingKnobs::lowres(4).id_suffix(), "-lowres4-b10-l20");
        assert_eq!(SamplingKnobs::lowres(2).marker_suffix(), "-lr2");
        assert_eq!(SamplingKnobs::lowres(2).grid_size([67, 37]), [34, 19]);
        assert_eq!(SamplingKnobs::lowres(4).grid_size([67, 37]), [18, 10]);
        assert_eq!(SamplingKnobs::default().grid_size([67, 37]), [67, 37]);
    }
}
