//! The `minmax` family (Chen et al. 2011, "Real-time volumetric shadows using 1D min-max
//! mipmaps"): a 1D min-max binary tree over every row of the prefiltered family's rectified
//! shadow map, and a per-pixel march that steps over tree nodes wholly lit or wholly
//! shadowed for the ray's depth and descends into the others. [`MinmaxVariant`] holds its
//! knobs; [`prepare_minmax`] sets up a frame.
//!
//! # Rectified map
//!
//! `minmax` marches exactly the rectified map of the prefiltered family: its frames come
//! from [`crate::frame::prepare_frame`] with [`MinmaxVariant::prefiltered`] (epipolar
//! rectification, one region; the filter knobs have no effect here), so the uniform block is
//! [`FrameUniforms`](crate::frame::FrameUniforms) (WGSL `struct Frame`) and the first pass is
//! the prefiltered family's `rectify` kernel. Conventions: [`crate::frame`].
//!
//! # Tree layout (`minmax_build`, rg32float, `tree_width(Wr) x Hr`)
//!
//! Row `y` of the tree texture holds the tree of rectified row `y`, levels packed left to
//! right: level `k` has `n_k = ceil(Wr / 2^k)` nodes at columns `off_k .. off_k + n_k`,
//! `off_k = n_0 + ... + n_(k-1)`; node `j` of level `k` covers the texels
//! `[j 2^k, min((j + 1) 2^k, Wr))` and stores `(min, max)` of their stored depths in
//! `(r, g)`. Level 0 is the rectified row itself (`min = max = d_i`); the last level is the
//! single root (`tree_levels(Wr) = ceil(log2 Wr) + 1` levels). The tree is at most
//! `2 Wr + tree_levels(Wr)` columns wide ([`tree_width`]).
//!
//! # The estimate (`minmax_traverse`)
//!
//! A pixel maps to its rectified row (the nearest slice: `floor` of the continuous row
//! coordinate, wrapped or clamped as in `scatter`), its column `x_s` and normalised depth `d`
//! exactly as in `scatter`. Its ray crosses texels `0 .. n`, `n = min(ceil(x_s), Wr)`;
//! column edge `x` lies at ray distance `ray_t(x)` (`scatter`'s), the last texel's span ends
//! at the surface `s`. Texel `i` is lit iff `d <= d_i`. Every maximal run of lit texels
//! `[i0, i1)` contributes the pixel's unshadowed in-scattering over `[ray_t(i0), ray_t(i1)]`:
//! closed form for the sun (`sigma_s p E` applied once per pixel), `spot_quadrature / 4`
//! Gauss-Legendre panels for a spot. The march climbs, at texel `i`, to the largest aligned
//! node that fits inside `[i, n)`, and descends while the node is mixed (`min < d <= max`):
//! a node with `d <= min` is wholly lit, one with `d > max` wholly shadowed, and either is
//! skipped whole. Runs therefore begin and end at the same texel edges as a brute-force
//! march over every texel, which gives the same sum: the hierarchy is exact at texel
//! resolution. Pixels near the epipole or the anti-epipole are ray-marched against the
//! standard shadow map, as `scatter` does.

use crate::family::{Family, KnobSet};
use crate::sampling::{Sampling, SamplingKnobs};
use serde::{Deserialize, Serialize};
use std::fmt;

use crate::frame::{
    CameraDesc, FrameError, FrameSettings, LightDesc, MediumDesc, PrefilteredFrame, Resolutions,
    ShadowMapDesc, prepare_frame,
};
use crate::variant::{LightKind, PrefilteredVariant, Rectification, VariantError};

/// The knobs of the `minmax` family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MinmaxVariant {
    /// Light type.
    pub light: LightKind,
    /// Where `minmax_traverse` runs: every pixel, or a low-resolution grid
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
    /// A spot light's cookie: an RGB texture projected along the cone multiplies each lit
    /// span's quadrature nodes and the epipole march's samples (`light = spot` only; the
    /// engine's `cookie` texture, [`crate::cookie`]).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub cookie: bool,
}

impl Default for MinmaxVariant {
    /// Directional light, every pixel.
    fn default() -> Self {
        Self {
            light: LightKind::Directional,
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

impl MinmaxVariant {
    /// Checks every knob; the error names the first offending one.
    pub fn validate(&self) -> Result<(), VariantError> {
        crate::variant::validate_single_light(self.light)?;
        self.sampling_knobs().validate()?;
        crate::cookie::validate_cookie(self.cookie, self.light)
    }

    /// A short stable id: `directional`, `spot`, `spot-cookie`, `spot-lowres2-b5`.
    pub fn id(&self) -> String {
        format!(
            "{}{}{}",
            self.light.name(),
            crate::cookie::id_suffix(self.cookie),
            self.sampling_knobs().id_suffix()
        )
    }

    /// The conformance grid: both lights, every pixel, and the spot with its cookie.
    pub fn grid() -> Vec<MinmaxVariant> {
        LightKind::SINGLE
            .iter()
            .map(|&light| MinmaxVariant {
                light,
                ..MinmaxVariant::default()
            })
            .chain([MinmaxVariant {
                light: LightKind::Spot,
                cookie: true,
                ..MinmaxVariant::default()
            }])
            .collect()
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

crate::sampling::sampling_fields!(MinmaxVariant);

impl fmt::Display for MinmaxVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.id())
    }
}

/// Nodes of level `level` of the tree of a row of `width` texels: `ceil(width / 2^level)`
/// (computed in 64 bits: no overflow for any width; 1 for any level past the root of a
/// non-empty row).
pub const fn level_count(level: u32, width: u32) -> u32 {
    if level >= 32 {
        return if width == 0 { 0 } else { 1 };
    }
    ((width as u64 + (1u64 << level) - 1) >> level) as u32
}

/// Levels of the tree of a row of `width` texels (`ceil(log2 width) + 1`; 1 for one texel).
pub const fn tree_levels(width: u32) -> u32 {
    let mut k = 0;
    while level_count(k, width) > 1 {
        k += 1;
    }
    k + 1
}

/// First column of level `level` in the packed tree row (saturating at `u32::MAX`, which
/// only widths beyond any texture limit reach).
pub const fn level_offset(level: u32, width: u32) -> u32 {
    let mut off: u32 = 0;
    let mut k = 0;
    while k < level {
        off = off.saturating_add(level_count(k, width));
        k += 1;
    }
    off
}

/// Width of the tree texture for a rectified width `width`: every level's nodes
/// (saturating at `u32::MAX`).
pub const fn tree_width(width: u32) -> u32 {
    level_offset(tree_levels(width), width)
}

/// Sets up one frame of the `minmax` family: [`prepare_frame`] with
/// [`MinmaxVariant::prefiltered`], so the rectified map is the prefiltered family's.
///
/// # Errors
///
/// As [`prepare_frame`].
pub fn prepare_minmax(
    variant: &MinmaxVariant,
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

impl KnobSet for MinmaxVariant {
    const FAMILY_NAME: &'static str = "minmax";
    const FAMILY: Family = Family::Minmax;
    const SUMMARY: &'static str = "Chen et al. 2011, 1D min-max mipmaps: each pixel marches its rectified row \
         through a min-max binary tree, skipping wholly lit or shadowed spans";

    fn validate(&self) -> Result<(), VariantError> {
        MinmaxVariant::validate(self)
    }

    fn id(&self) -> String {
        MinmaxVariant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    fn with_light(self, light: LightKind) -> Self {
        Self { light, ..self }
    }

    /// Empty (the light is not in markers), `cookie` with a cookie, and the sampling's
    /// (`lr2`).
    fn marker(&self) -> String {
        (crate::cookie::id_suffix(self.cookie).to_owned() + &self.sampling_knobs().marker_suffix())
            .trim_start_matches('-')
            .to_owned()
    }

    fn sampling(&self) -> SamplingKnobs {
        self.sampling_knobs()
    }

    fn with_sampling(self, s: SamplingKnobs) -> Self {
        self.with_sampling_knobs(s)
    }

    fn grid() -> Vec<Self> {
        MinmaxVariant::grid()
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
    fn tree_layout() {
        assert_eq!(tree_levels(1), 1);
        assert_eq!(tree_width(1), 1);
        assert_eq!(tree_levels(2), 2);
        assert_eq!(tree_levels(256), 9);
        assert_eq!(tree_width(256), 511);
        // 5 -> 3 -> 2 -> 1
        assert_eq!(tree_levels(5), 4);
        assert_eq!(level_offset(2, 5), 8);
        assert_eq!(tree_width(5), 11);
        for w in 1..600 {
            assert!(tree_width(w) <= 2 * w + tree_levels(w), "{w}");
            assert_eq!(level_count(tree_levels(w) - 1, w), 1);
        }
    }
}
