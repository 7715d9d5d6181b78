//! The `hybrid_volume` family (Wyman & Ramsey 2008, "Interactive volumetric shadows in
//! participating media with single-scattering"): per pixel, only the part `[t_f, t_b]` of the
//! view ray between the nearest and the farthest shadow-volume boundary is ray-marched against
//! the standard shadow map; outside it the visibility is constant and the in-scattering is
//! added in closed form. [`HybridVolumeVariant`] holds its knobs; [`prepare_hybrid_volume`]
//! sets up a frame.
//!
//! # Where the shadow volume comes from
//!
//! From the shadow map, on the epipolar layer every rectified family shares (frames from
//! [`crate::frame::prepare_frame`] with [`HybridVolumeVariant::prefiltered`]; kernels
//! `depth_columns`, `slice_fit`, `rectify`): no mesh input, so the inputs contract of every
//! family holds. In an epipolar slice the shadow volume's boundary is the rectified row's
//! occluder depths `S_c` (column `c` = one light ray of the slice) closed by walls between
//! neighbouring columns. A view ray of the slice has one rectified depth `d`; texel `c` is lit
//! iff `d <= S_c`, so the ray crosses the boundary at column edge `c` (between texels `c - 1`
//! and `c`) iff `min(S_(c-1), S_c) < d <= max(S_(c-1), S_c)`.
//!
//! # `volume_bounds` (one workgroup per rectified row)
//!
//! The walls of each row rasterised into [`HybridVolumeVariant::bins`] bins of the ray depth
//! `d` (bin `k`: `d` in `[k / B, (k + 1) / B)`): edge `c` with depth range `(lo, hi]` reaches
//! bins `floor(lo B) ..= floor(hi B)`, and each bin keeps its first and last edge
//! (`atomicMax` in zero-initialised workgroup memory, the first edge as `NO_EDGE - c`;
//! [`NO_EDGE`] when none). This is the
//! paper's rasterisation of shadow-volume faces restricted to one slice, where every view ray
//! of the slice is one point of a 1D "screen" (its `d`): the front-most and back-most boundary
//! crossings for every ray of the slice at once, with no render pipeline. Output: the storage
//! buffer `crossings`, `vec2<u32>` per (row, bin), index `row * B + bin`.
//!
//! # `volume_march` (per pixel)
//!
//! The two rectified rows whose slices bracket the ray (`floor(yc - 0.5)` and the next) each
//! give their first and last edge inside the ray's texels `0 .. n`, padded by
//! [`HybridVolumeVariant::pad`] texels (the rectified texel samples its light ray at the
//! texel's centre; the standard shadow map's boundary lies within half a texel of the edge),
//! mapped to ray distances (`edge_t`). The pixel's interval is the union of the two rows'; a
//! head or tail whose visibility the two rows disagree on is marched too. The head `[0, t_f]`
//! has the visibility of texel 0, the tail `[t_b, s]` that of the row's last edge texel; each
//! adds `lit_span` (the sun's closed form, a spot's Gauss-Legendre panels) times it, and
//! `[t_f, t_b]` is marched with [`HybridVolumeVariant::samples`] samples (`span_march`: uniform
//! cells for the sun, equiangular strata for a spot). Pixels near the epipole or the
//! anti-epipole are marched whole (`epipole_march`), as in every epipolar family.

use crate::family::{Family, KnobSet};
use crate::frame::{
    CameraDesc, FrameError, FrameSettings, LightDesc, MediumDesc, PrefilteredFrame, Resolutions,
    ShadowMapDesc, prepare_frame,
};
use crate::sampling::{Sampling, SamplingKnobs};
use crate::variant::{LightKind, PrefilteredVariant, Rectification, VariantError};
use serde::{Deserialize, Serialize};
use std::fmt;

/// No boundary crossing in a bin (the first edge of an empty bin).
pub const NO_EDGE: u32 = u32::MAX;

/// The default samples in `[t_f, t_b]`.
pub const DEFAULT_SAMPLES: u32 = 32;

/// The most samples.
pub const MAX_SAMPLES: u32 = 1024;

/// The default depth bins per rectified row.
pub const DEFAULT_BINS: u32 = 256;

/// The most depth bins (two `u32` each in workgroup memory: 8 KiB at 1024, half of the
/// 16 KiB every WebGPU device offers).
pub const MAX_BINS: u32 = 1024;

/// The most padding texels.
pub const MAX_PAD: u32 = 8;

/// The knobs of the `hybrid_volume` family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HybridVolumeVariant {
    /// Light type.
    pub light: LightKind,
    /// Samples marched in each pixel's `[t_f, t_b]`, 1..=1024.
    pub samples: u32,
    /// Depth bins per rectified row in `volume_bounds`, 1..=1024.
    pub bins: u32,
    /// Texels each bound is padded by, 0..=8.
    pub pad: u32,
    /// Where `volume_march` runs: every pixel, or a low-resolution grid or epipolar samples
    /// ([`crate::sampling`]).
    pub sampling: Sampling,
    /// `sampling = lowres`: the block side, 2 or 4.
    pub scale: u32,
    /// `sampling = lowres | epipolar`: the depth break in percent of the nearer depth.
    pub depth_break: u32,
    /// `sampling = lowres | epipolar`: the light break in percent of the brightest sample.
    pub light_break: u32,
    /// `sampling = epipolar`: epipolar slices.
    pub slices: u32,
    /// `sampling = epipolar`: samples per slice.
    pub slice_samples: u32,
    /// `sampling = epipolar`: the initial step between evaluated samples of a slice.
    pub step: u32,
    /// A spot light's cookie: an RGB texture projected along the cone multiplies the head's,
    /// the tail's and the march's nodes (`light = spot` only; the engine's `cookie`
    /// texture, [`crate::cookie`]).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub cookie: bool,
}

impl Default for HybridVolumeVariant {
    /// Directional light, 32 samples, 256 bins, one texel of padding, every pixel (32: 16
    /// samples miss 5 % on `window/grazing`, whose intervals hold 40 % of its rays;
    /// `docs/hybrid-volume.md`).
    fn default() -> Self {
        Self {
            light: LightKind::Directional,
            samples: DEFAULT_SAMPLES,
            bins: DEFAULT_BINS,
            pad: 1,
            sampling: Sampling::Pixels,
            scale: SamplingKnobs::DEFAULT_SCALE,
            depth_break: SamplingKnobs::DEFAULT_DEPTH_BREAK,
            light_break: SamplingKnobs::DEFAULT_LIGHT_BREAK,
            slices: SamplingKnobs::DEFAULT_SLICES,
            slice_samples: SamplingKnobs::DEFAULT_SLICE_SAMPLES,
            step: SamplingKnobs::DEFAULT_STEP,
            cookie: false,
        }
    }
}

crate::sampling::sampling_fields!(HybridVolumeVariant);

impl HybridVolumeVariant {
    /// Checks every knob; the error names the first offending one.
    pub fn validate(&self) -> Result<(), VariantError> {
        crate::variant::validate_single_light(self.light)?;
        let range = |knob: &'static str, value: u32, lo: u32, hi: u32| {
            if (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(VariantError {
                    knob,
                    value: value.to_string(),
                    allowed: format!("in {lo}..={hi}"),
                })
            }
        };
        range("samples", self.samples, 1, MAX_SAMPLES)?;
        range("bins", self.bins, 1, MAX_BINS)?;
        range("pad", self.pad, 0, MAX_PAD)?;
        self.sampling_knobs().validate()?;
        crate::cookie::validate_cookie(self.cookie, self.light)
    }

    /// A short stable id: `directional-n32-b256-p1`, `spot-n64-b256-p1-lowres2-b5`.
    pub fn id(&self) -> String {
        format!(
            "{}-n{}-b{}-p{}{}{}",
            self.light.name(),
            self.samples,
            self.bins,
            self.pad,
            crate::cookie::id_suffix(self.cookie),
            self.sampling_knobs().id_suffix()
        )
    }

    /// The conformance grid: both lights at the defaults, the directional light with 8
    /// samples, 64 bins and no padding (every code path: few bins put many walls in a bin),
    /// and the spot with its cookie.
    pub fn grid() -> Vec<HybridVolumeVariant> {
        let mut out: Vec<HybridVolumeVariant> = LightKind::SINGLE
            .iter()
            .map(|&light| HybridVolumeVariant {
                light,
                ..HybridVolumeVariant::default()
            })
            .collect();
        out.push(HybridVolumeVariant {
            samples: 8,
            bins: 64,
            pad: 0,
            ..HybridVolumeVariant::default()
        });
        out.push(HybridVolumeVariant {
            light: LightKind::Spot,
            cookie: true,
            ..HybridVolumeVariant::default()
        });
        out
    }

    /// The prefiltered-family variant whose frame set-up and `rectify` kernel this family
    /// uses: the light, epipolar rectification, one region (the other knobs do not matter).
    pub fn prefiltered(&self) -> PrefilteredVariant {
        PrefilteredVariant {
            regions: 1,
            light: self.light,
            rectification: Rectification::Epipolar,
            ..PrefilteredVariant::default()
        }
    }
}

impl fmt::Display for HybridVolumeVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.id())
    }
}

/// Sets up one frame of the `hybrid_volume` family: [`prepare_frame`] with
/// [`HybridVolumeVariant::prefiltered`], so the rectified map is the prefiltered family's.
///
/// # Errors
///
/// A knob out of range, or as [`prepare_frame`].
pub fn prepare_hybrid_volume(
    variant: &HybridVolumeVariant,
    res: &Resolutions,
    camera: &CameraDesc,
    light: &LightDesc,
    medium: &MediumDesc,
    shadow: &ShadowMapDesc,
    settings: &FrameSettings,
) -> Result<PrefilteredFrame, FrameError> {
    variant.validate()?;
    // With the sampling knobs: epipolar sampling aligns the rows with its slices.
    prepare_frame(
        &variant
            .prefiltered()
            .with_sampling_knobs(variant.sampling_knobs()),
        res,
        camera,
        light,
        medium,
        shadow,
        settings,
    )
}

impl KnobSet for HybridVolumeVariant {
    const FAMILY_NAME: &'static str = "hybrid_volume";
    const FAMILY: Family = Family::HybridVolume;
    const SUMMARY: &'static str = "Wyman & Ramsey 2008, hybrid shadow volumes: each pixel marches only \
         the part of its ray between the shadow volume's first and last boundary, built per \
         epipolar slice from the rectified shadow map; the rest in closed form";

    fn validate(&self) -> Result<(), VariantError> {
        HybridVolumeVariant::validate(self)
    }

    fn id(&self) -> String {
        HybridVolumeVariant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    fn with_light(self, light: LightKind) -> Self {
        Self { light, ..self }
    }

    /// `n32` (the samples, `-cookie` with a cookie, then the sampling's marker).
    fn marker(&self) -> String {
        format!(
            "n{}{}{}",
            self.samples,
            crate::cookie::id_suffix(self.cookie),
            self.sampling_knobs().marker_suffix()
        )
    }

    fn sampling(&self) -> SamplingKnobs {
        self.sampling_knobs()
    }

    fn with_sampling(self, s: SamplingKnobs) -> Self {
        self.with_sampling_knobs(s)
    }

    fn grid() -> Vec<Self> {
        HybridVolumeVariant::grid()
    }

    fn cookie(&self) -> bool {
        self.cookie
    }

    fn with_cookie(self, cookie: bool) -> Option<Self> {
        Some(Self { cookie, ..self })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knobs_are_checked_by_name() {
        assert!(HybridVolumeVariant::default().validate().is_ok());
        for (v, knob) in [
            (
                HybridVolumeVariant {
                    samples: 0,
                    ..Default::default()
                },
                "samples",
            ),
            (
                HybridVolumeVariant {
                    bins: MAX_BINS + 1,
                    ..Default::default()
                },
                "bins",
            ),
            (
                HybridVolumeVariant {
                    pad: MAX_PAD + 1,
                    ..Default::default()
                },
                "pad",
            ),
        ] {
            assert_eq!(v.validate().unwrap_err().knob, knob);
        }
        assert_eq!(
            HybridVolumeVariant::default().id(),
            "directional-n32-b256-p1"
        );
    }
}
