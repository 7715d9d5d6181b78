//! The sampling stage every family can use (DESIGN.md, "Sampling"): where a family evaluates
//! its per-pixel integral. `pixels` evaluates it at every screen pixel; `lowres` at one pixel
//! of every `scale x scale` block (a fixed pixel, so that samples do not jump between frames)
//! and fills the screen with a depth- and light-aware upsample, evaluating the pixels no
//! sample can stand for; `epipolar` at samples along epipolar lines, then gathers every
//! pixel from them.
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
//! Three passes, as with `epipolar` below: pass 1, the family's per-pixel kernel, evaluates
//! every sample of the grid (one invocation each) into `lowres_samples` (rgba32float:
//! radiance rounded to f16 as a per-pixel pass stores it, and the view depth of the sample's
//! pixel); pass 2, `<kernel>_unwarp`, blends every pixel from its four samples or lists it in
//! `fallback_pixels`; pass 3, `<kernel>_fallback`, evaluates the listed pixels with the
//! family's per-pixel body. Until stop 41 it was one pass: a workgroup evaluated the samples
//! of its 8 x 8 blocks and of the next column and row (27 % more than it owned) into
//! workgroup memory, blended its pixels or listed them, then evaluated its list, with
//! barriers between the phases. On llvmpipe the three passes are faster (`bench
//! --headline-only`, 1280x720, means over sphere, foliage and terrain): prefiltered m32-r8
//! lowres 2 from 121.2 to 107.9 ms for the frame (its sampled passes 61-76 ms -> 44-56 ms),
//! raymarch n64 lowres 2 from 74.5 to 56.4 ms and lowres 4 from 35.1 to 27.3 ms, with the same
//! images (the sampling trials compare them with the mirror pixel by pixel).

//! # The epipolar passes
//!
//! In-scattered light varies slowly along an epipolar line (the screen image of a plane
//! through the eye and the light) except where the depth buffer breaks (Engelhardt &
//! Dachsbacher 2010). The layout: the epipole `o` (the screen point towards the light, or
//! away from it when the light is behind the camera: every epipolar line passes through it),
//! in pixel coordinates (pixel centres at `x + 0.5`), moved to at most 100 screens from the
//! screen centre along its direction (lines from farther away are parallel to a pixel's
//! width); angles measured from the direction `o -> screen centre`. With `o` on screen the
//! `slices` slices split the full circle; otherwise the angle range of the four screen
//! corners seen from `o`, in equal parts. Slice `s` is the ray from `o` at the centre angle
//! of its part; its `slice_samples` samples are spread evenly from where it enters the
//! rectangle of pixel centres to where it leaves (the first at `o` when `o` is on screen),
//! each standing on the pixel it falls in. Samples are fixed by the camera and the light
//! alone, so they do not move while neither does.
//!
//! Pass 1 is the family's per-pixel kernel on the samples, one workgroup per slice: it
//! evaluates every `step`-th sample, the last, and both samples on either side of a depth
//! break (neighbouring samples whose depths differ by more than `depth_break`); then every
//! sample between two evaluated ones whose values differ by more than `light_break` of the
//! brighter (Yusov 2013's second criterion); and interpolates the rest linearly between the
//! evaluated samples around it (which lie on the same surface: no break between them). It
//! writes `epipolar_samples` (`(slice_samples + 1) x (slices + 1)`, rgba32float: radiance
//! rounded to f16 as a per-pixel pass stores it, and the view depth of the sample's pixel;
//! each slice's line in the last column, the layout in the last row). Each invocation of the
//! pass takes runs of `step` samples from a `step`-th one: it marks them walking forward and
//! notes in each unmarked sample the marked ones around it walking back, so that the light
//! criterion and the interpolation read them instead of searching (searching from every
//! sample cost the raymarch n64 samples pass 4-6 ms of 16 at 1280x720 on llvmpipe).
//!
//! Pass 2, `<kernel>_unwarp`, gathers every screen pixel from the two slices around its
//! angle and the two samples around its distance from `o` on each (bilinear weights), kept
//! by depth and checked for light spread exactly as `lowres` keeps its taps; a pixel no
//! sample stands for is listed in `fallback_pixels`. Pass 3, `<kernel>_fallback`, evaluates
//! the listed pixels with the family's per-pixel body.

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
    /// Samples along epipolar lines (Engelhardt & Dachsbacher 2010, Yusov 2013), evaluated
    /// every `step` samples and on both sides of every depth break, interpolated along the
    /// slice elsewhere; then an unwarp pass gathers every pixel from its two nearest slices
    /// and lists the pixels no sample can stand for, which a fallback pass evaluates.
    Epipolar,
}

impl Sampling {
    /// Every value, sorted by name.
    pub const ALL: &'static [Sampling] = &[Sampling::Epipolar, Sampling::Lowres, Sampling::Pixels];
    /// The allowed names, for error messages.
    pub const ALLOWED: &'static str = "epipolar | lowres | pixels";

    /// The value's name (serde, CLI, variant ids).
    pub const fn name(self) -> &'static str {
        match self {
            Sampling::Pixels => "pixels",
            Sampling::Lowres => "lowres",
            Sampling::Epipolar => "epipolar",
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
            "epipolar" => Ok(Sampling::Epipolar),
            _ => Err(VariantError {
                knob: "sampling",
                value: s.to_owned(),
                allowed: Self::ALLOWED.into(),
            }),
        }
    }
}

/// The sampling knobs every family's variant carries (as the fields `sampling`, `scale`,
/// `depth_break`, `light_break`, `slices`, `slice_samples`, `step`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SamplingKnobs {
    /// Where the family evaluates its integral.
    pub sampling: Sampling,
    /// `lowres`: the block side S, 2 or 4 (1/2 or 1/4 of the screen per axis).
    pub scale: u32,
    /// `lowres`, `epipolar`: the depth difference, in percent of the nearer depth, beyond
    /// which a sample does not stand for a pixel (1..=50); for `epipolar` also where two
    /// neighbouring samples of a slice are both evaluated.
    pub depth_break: u32,
    /// `lowres`, `epipolar`: the spread of a pixel's samples, in percent of the brightest,
    /// beyond which the pixel is evaluated itself (1..=100; 100 never refines: the spread of
    /// non-negative values never exceeds the largest); for `epipolar` also the spread of two
    /// evaluated samples beyond which the samples between them are evaluated too.
    pub light_break: u32,
    /// `epipolar`: the number of epipolar slices (64, 128, 256, 512 or 1024).
    pub slices: u32,
    /// `epipolar`: samples per slice, from where the slice enters the screen to where it
    /// leaves (64, 128, 256 or 512).
    pub slice_samples: u32,
    /// `epipolar`: every `step`-th sample of a slice is evaluated, and the last (1, 2, 4,
    /// 8, 16 or 32, less than `slice_samples`; 1 evaluates every sample; default 8).
    pub step: u32,
}

impl Default for SamplingKnobs {
    /// `pixels` (every pixel), with the lowres knobs at their defaults.
    fn default() -> Self {
        Self {
            sampling: Sampling::Pixels,
            scale: Self::DEFAULT_SCALE,
            depth_break: Self::DEFAULT_DEPTH_BREAK,
            light_break: Self::DEFAULT_LIGHT_BREAK,
            slices: Self::DEFAULT_SLICES,
            slice_samples: Self::DEFAULT_SLICE_SAMPLES,
            step: Self::DEFAULT_STEP,
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

    /// Allowed `slices`.
    pub const SLICES: [u32; 5] = [64, 128, 256, 512, 1024];
    /// `slices` when not chosen (Yusov 2013's high-quality setting, for screens up to
    /// 2560x1600: about 16 pixels of the screen's border per slice). At 1280x720 and below 256
    /// give that spacing: measured there (raymarch N = 64, stop 45), 256 slices took 15-17 %
    /// less of the frame than 512 (5.96x against 5.02x faster than per pixel in the sixteenth
    /// bench run) for 0.005 points of rel L1 on the bench's scenes, and on all 24 suite poses
    /// stayed 0.096 points below per pixel on the mean (the worst pose +0.150).
    pub const DEFAULT_SLICES: u32 = 512;
    /// Allowed `slice_samples`.
    pub const SLICE_SAMPLES: [u32; 4] = [64, 128, 256, 512];
    /// `slice_samples` when not chosen (Yusov 2013's high-quality setting).
    pub const DEFAULT_SLICE_SAMPLES: u32 = 256;
    /// Allowed `step`.
    pub const STEPS: [u32; 6] = [1, 2, 4, 8, 16, 32];
    /// `step` when not chosen. Measured (raymarch N = 64, 512 x 256 samples, light break
    /// 20, CPU mirror at 1280x720, `ordinary` poses, interpolation error against the same
    /// variant per pixel): step 16 (Yusov 2013's initial step) 0.144 / 0.328 / 0.178 % on
    /// sphere / foliage / terrain with 18.6k / 24.4k / 16.4k samples evaluated; step 8
    /// 0.093 / 0.265 / 0.094 % with 18.0k / 22.9k / 18.5k (fewer runs between evaluated
    /// samples differ by more than the light break); step 4 (light break 10) 0.063 / 0.219
    /// / 0.058 % with about twice the evaluations.
    pub const DEFAULT_STEP: u32 = 8;

    /// `lowres` at `scale`, the depth break at its default.
    pub fn lowres(scale: u32) -> Self {
        Self {
            sampling: Sampling::Lowres,
            scale,
            ..Self::default()
        }
    }

    /// `epipolar` with `slices` slices, every other knob at its default.
    pub fn epipolar(slices: u32) -> Self {
        Self {
            sampling: Sampling::Epipolar,
            slices,
            ..Self::default()
        }
    }

    /// Whether the family evaluates fewer samples than pixels (and has the upsample pass).
    pub fn is_sampled(&self) -> bool {
        self.sampling != Sampling::Pixels
    }

    /// Checks the knobs; the error names the first offending one. A mode's knobs must stay
    /// at their defaults in the other modes (`scale` outside `lowres`; `slices`,
    /// `slice_samples`, `step` outside `epipolar`; the breaks with `pixels`), so that one
    /// configuration has one id.
    pub fn validate(&self) -> Result<(), VariantError> {
        let d = Self::default();
        let unused = |knob: &'static str, value: u32, default: u32, modes: &str| {
            if value == default {
                Ok(())
            } else {
                Err(VariantError {
                    knob,
                    value: value.to_string(),
                    allowed: format!("{default} (a knob of sampling = {modes})"),
                })
            }
        };
        if self.sampling != Sampling::Lowres {
            unused("scale", self.scale, d.scale, "lowres")?;
        }
        if self.sampling != Sampling::Epipolar {
            unused("slices", self.slices, d.slices, "epipolar")?;
            unused(
                "slice_samples",
                self.slice_samples,
                d.slice_samples,
                "epipolar",
            )?;
            unused("step", self.step, d.step, "epipolar")?;
        }
        if self.sampling == Sampling::Pixels {
            unused(
                "depth_break",
                self.depth_break,
                d.depth_break,
                "lowres | epipolar",
            )?;
            unused(
                "light_break",
                self.light_break,
                d.light_break,
                "lowres | epipolar",
            )?;
            return Ok(());
        }
        if self.sampling == Sampling::Lowres && !Self::SCALES.contains(&self.scale) {
            return Err(VariantError {
                knob: "scale",
                value: self.scale.to_string(),
                allowed: "2 or 4 (samples per axis: 1/2 or 1/4 of the screen)".into(),
            });
        }
        if self.sampling == Sampling::Epipolar {
            if !Self::SLICES.contains(&self.slices) {
                return Err(VariantError {
                    knob: "slices",
                    value: self.slices.to_string(),
                    allowed: "64, 128, 256, 512 or 1024".into(),
                });
            }
            if !Self::SLICE_SAMPLES.contains(&self.slice_samples) {
                return Err(VariantError {
                    knob: "slice_samples",
                    value: self.slice_samples.to_string(),
                    allowed: "64, 128, 256 or 512".into(),
                });
            }
            if !Self::STEPS.contains(&self.step) || self.step >= self.slice_samples {
                return Err(VariantError {
                    knob: "step",
                    value: self.step.to_string(),
                    allowed: format!(
                        "1, 2, 4, 8, 16 or 32, less than slice_samples = {}",
                        self.slice_samples
                    ),
                });
            }
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
                allowed: "in 1..=100 (percent of the brightest sample; 100 never refines)".into(),
            });
        }
        Ok(())
    }

    /// The tail of a variant id: empty for `pixels` (ids of per-pixel variants are those of
    /// before the knob), `-lowres{scale}-b{depth_break}-l{light_break}` for `lowres`,
    /// `-epi{slices}x{slice_samples}-s{step}-b{depth_break}-l{light_break}` for `epipolar`.
    pub fn id_suffix(&self) -> String {
        match self.sampling {
            Sampling::Pixels => String::new(),
            Sampling::Lowres => format!(
                "-lowres{}-b{}-l{}",
                self.scale, self.depth_break, self.light_break
            ),
            Sampling::Epipolar => format!(
                "-epi{}x{}-s{}-b{}-l{}",
                self.slices, self.slice_samples, self.step, self.depth_break, self.light_break
            ),
        }
    }

    /// The tail of a marker: empty for `pixels`, `-lr{scale}` or `-ep{slices}` (and the
    /// other knobs where they differ from the defaults: `x{slice_samples}`, `-s{step}`,
    /// `-b{depth_break}`, `-l{light_break}`) otherwise.
    pub fn marker_suffix(&self) -> String {
        let mut m = match self.sampling {
            Sampling::Pixels => return String::new(),
            Sampling::Lowres => format!("-lr{}", self.scale),
            Sampling::Epipolar => {
                let mut m = format!("-ep{}", self.slices);
                if self.slice_samples != Self::DEFAULT_SLICE_SAMPLES {
                    m += &format!("x{}", self.slice_samples);
                }
                if self.step != Self::DEFAULT_STEP {
                    m += &format!("-s{}", self.step);
                }
                m
            }
        };
        if self.depth_break != Self::DEFAULT_DEPTH_BREAK {
            m += &format!("-b{}", self.depth_break);
        }
        if self.light_break != Self::DEFAULT_LIGHT_BREAK {
            m += &format!("-l{}", self.light_break);
        }
        m
    }

    /// The sample grid for a `screen` (width, height): the screen itself for `pixels`;
    /// for `lowres` a sample on every S-th pixel from the first and one on the last,
    /// `ceil((screen - 1) / scale) + 1`.
    /// For `epipolar`, `[slice_samples, slices]`: the samples texture.
    pub fn grid_size(&self, screen: [u32; 2]) -> [u32; 2] {
        match self.sampling {
            Sampling::Pixels => screen,
            Sampling::Epipolar => [self.slice_samples, self.slices],
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

/// Implements, for a variant type with the fields `sampling`, `scale`, `depth_break`,
/// `light_break`, `slices`, `slice_samples` and `step`, `sampling_knobs` (those fields as [`SamplingKnobs`]) and
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
                    slices: self.slices,
                    slice_samples: self.slice_samples,
                    step: self.step,
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
                    slices: s.slices,
                    slice_samples: s.slice_samples,
                    step: s.step,
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
        assert_eq!("epipolar".parse::<Sampling>(), Ok(Sampling::Epipolar));
        assert!(SamplingKnobs::epipolar(512).validate().is_ok());
        assert_eq!(
            SamplingKnobs::epipolar(300).validate().unwrap_err().knob,
            "slices"
        );
        let epi_scale = SamplingKnobs {
            scale: 4,
            ..SamplingKnobs::epipolar(256)
        };
        assert_eq!(epi_scale.validate().unwrap_err().knob, "scale");
        let lowres_slices = SamplingKnobs {
            slices: 256,
            ..SamplingKnobs::lowres(2)
        };
        assert_eq!(lowres_slices.validate().unwrap_err().knob, "slices");
        let long_step = SamplingKnobs {
            slice_samples: 64,
            step: 64,
            ..SamplingKnobs::epipolar(256)
        };
        assert_eq!(long_step.validate().unwrap_err().knob, "step");
    }

    #[test]
    fn ids_and_grids() {
        assert_eq!(SamplingKnobs::default().id_suffix(), "");
        assert_eq!(SamplingKnobs::lowres(4).id_suffix(), "-lowres4-b10-l20");
        assert_eq!(SamplingKnobs::lowres(2).marker_suffix(), "-lr2");
        assert_eq!(SamplingKnobs::lowres(2).grid_size([67, 37]), [34, 19]);
        assert_eq!(SamplingKnobs::lowres(4).grid_size([67, 37]), [18, 10]);
        assert_eq!(SamplingKnobs::default().grid_size([67, 37]), [67, 37]);
        let e = SamplingKnobs::epipolar(128);
        assert_eq!(e.id_suffix(), "-epi128x256-s8-b10-l20");
        assert_eq!(e.marker_suffix(), "-ep128");
        assert_eq!(e.grid_size([67, 37]), [256, 128]);
    }
}
