//! [`PrefilteredVariant`]: the knobs of the prefiltered family (DESIGN.md, "PrefilteredVariant space"), validated
//! with errors that name the knob, the value and the allowed range.

use crate::family::{Family, KnobSet};
use crate::sampling::{Sampling, SamplingKnobs};
use serde::{Deserialize, Serialize};
use std::fmt;

/// How visibility samples along a view ray are weighted (Klehm et al. 2014, Sec. 3.1/3.2).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum VisibilityMode {
    /// Plain average visibility along the ray (Listing 1): each texel weighted by the length
    /// of the reference ray it covers.
    Average,
    /// Transmittance-weighted visibility (Eq. 11, Listing 2): each texel weighted by the
    /// transmittance integral over its span of the slice's reference ray (times the cone
    /// falloff and 1/d^2 for a spot light).
    #[default]
    Weighted,
}

// The light type is the scene's (`crate::scene::LightKind`, shared by every family); its
// names (`ALL`, `name`, parsing) are given below with the prefiltered knobs'.
pub use crate::scene::LightKind;

/// Storage format of the filtered bases (the bits of one texel of this format per layer and
/// rectified texel in the `filtered` storage buffer).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Storage {
    /// 8-bit unsigned normalised (the paper's choice: "no improvement above 8 bit").
    #[default]
    Rgba8unorm,
    /// 16-bit float.
    Rgba16float,
    /// 32-bit float.
    Rgba32float,
}

/// What the prefilter stores of each rectified texel's depth, and what `scatter` reconstructs
/// a region's visibility from.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Basis {
    /// `bases` Fourier bases of the step function (Klehm et al. 2014, Eq. 8): the paper.
    #[default]
    Fourier,
    /// `moments` power moments of the depth (Peters et al. 2016): per pixel the lit fraction
    /// of each region from the moment problem's bounds (4: Hamburger 4MSM, 6: a cubic).
    Moments,
}

/// How the standard shadow map becomes a rectified one.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Rectification {
    /// Epipolar resampling of a standard shadow map (Sec. 4.1, Baran et al.); always valid.
    #[default]
    Epipolar,
    /// One 4x4 matrix the engine rasterises its shadow map with (Sec. 4.2).
    Projective,
}

macro_rules! names {
    ($t:ty, [$($v:ident => $s:literal),* $(,)?]) => {
        impl $t {
            /// Every value, sorted by name.
            pub const ALL: &'static [$t] = &[$(<$t>::$v),*];
            /// The value's name (serde, CLI, variant ids).
            pub const fn name(self) -> &'static str {
                match self { $(<$t>::$v => $s),* }
            }
            /// The allowed names, for error messages.
            pub const ALLOWED: &'static str = concat!($($s, " "),*);
        }
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
        impl std::str::FromStr for $t {
            type Err = VariantError;
            fn from_str(s: &str) -> Result<Self, VariantError> {
                match s {
                    $($s => Ok(<$t>::$v),)*
                    _ => Err(VariantError {
                        knob: stringify_knob::<$t>(),
                        value: s.to_owned(),
                        allowed: Self::ALLOWED.trim_end().replace(' ', " | "),
                    }),
                }
            }
        }
    };
}

fn stringify_knob<T: 'static>() -> &'static str {
    let t = std::any::type_name::<T>();
    if t.ends_with("VisibilityMode") {
        "visibility"
    } else if t.ends_with("LightKind") {
        "light"
    } else if t.ends_with("Storage") {
        "storage"
    } else if t.ends_with("Basis") {
        "basis"
    } else {
        "rectification"
    }
}

/// Checks a single-light family's `light` knob: one standard shadow map serves a directional
/// or a spot light; an area light is the `area_ivsv` family's.
///
/// # Errors
///
/// A [`VariantError`] naming `light` for [`LightKind::Area`].
pub fn validate_single_light(light: LightKind) -> Result<(), VariantError> {
    if LightKind::SINGLE.contains(&light) {
        Ok(())
    } else {
        Err(VariantError {
            knob: "light",
            value: light.to_string(),
            allowed: format!(
                "{} (an area light is rendered by the area_ivsv family, or as its point limit, a spot)",
                LightKind::SINGLE_ALLOWED
            ),
        })
    }
}

names!(VisibilityMode, [Average => "average", Weighted => "weighted"]);
names!(LightKind, [Directional => "directional", Spot => "spot", Area => "area"]);
names!(Storage, [Rgba16float => "rgba16float", Rgba32float => "rgba32float", Rgba8unorm => "rgba8unorm"]);
names!(Rectification, [Epipolar => "epipolar", Projective => "projective"]);
names!(Basis, [Fourier => "fourier", Moments => "moments"]);

/// `text` with its control characters (newlines, tabs, escape codes) written as Rust
/// escapes (`\n`, `\u{1b}`): user text quoted in an error message keeps the message on
/// one printable line.
pub fn printable(text: &str) -> std::borrow::Cow<'_, str> {
    if text.chars().any(char::is_control) {
        text.chars()
            .map(|c| {
                if c.is_control() {
                    c.escape_default().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect()
    } else {
        text.into()
    }
}

/// A knob outside its allowed range.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{knob} must be {allowed}, got {}", printable(.value))]
pub struct VariantError {
    /// The knob's name (`bases`, `bases_per_thread`, ...).
    pub knob: &'static str,
    /// The rejected value.
    pub value: String,
    /// The allowed range, in words.
    pub allowed: String,
}

/// One compiled configuration of the prefiltered family. `Default` is the design card's
/// choice but for one knob: the Fourier basis, 32 bases, 8 per thread, 4 regions (the card
/// says 3), weighted visibility, rgba8unorm, epipolar, directional. Four regions because of
/// the random poses (issue 12; `cargo test --release -p scatter-conformance --test
/// random_poses`, 150 poses at 96x54): p90 rel L1 2.27 -> 1.66 %, max 6.48 -> 5.94 %,
/// against raymarch n64's 2.08 / 4.39 %, for 1.02-1.05x the time (`scatter` at 1280x720;
/// the bench's 320x180 sweep). [`PrefilteredVariant::with_moments`] is the
/// moment basis.
///
/// Knobs of one basis only: `bases` and `bases_per_thread` belong to the Fourier basis,
/// `moments` to the moment basis; the other basis's knobs must stay at their defaults, so
/// that one configuration has one id.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PrefilteredVariant {
    /// What the prefilter stores: Fourier bases or power moments of the rectified depth.
    pub basis: Basis,
    /// Fourier bases M (M/2 frequencies, sine and cosine): 4..=128, a multiple of 4.
    pub bases: u32,
    /// Bases filtered by one invocation: a multiple of 4 that divides `bases`.
    pub bases_per_thread: u32,
    /// Power moments of the moment basis: 4 or 6.
    pub moments: u32,
    /// Independent prefix regions per rectified row: 1..=8.
    pub regions: u32,
    /// Visibility weighting.
    pub visibility: VisibilityMode,
    /// Light type.
    pub light: LightKind,
    /// Filtered-basis storage format.
    pub storage: Storage,
    /// Rectification scheme.
    pub rectification: Rectification,
    /// Where `scatter` runs: every pixel, or a low-resolution grid ([`crate::sampling`]).
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
    /// A spot light's cookie: an RGB texture projected along the cone ([`crate::cookie`];
    /// `light = spot` only). It is constant along each light ray, so the prefilter folds it
    /// into each rectified texel's weight: per colour channel the weighted means of the
    /// cookie times the basis (three times the layers), plus the region's mean cookie in one
    /// more layer; `scatter` reconstructs each channel's lit share from them.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub cookie: bool,
    /// Rectified columns per stored filtered column (1, 2, 4 or 8): `prefilter` still
    /// filters every rectified texel of its row and region, but stores its running means
    /// (and depth bounds) only at every k-th column's right edge, into a `filtered` map of
    /// `rectified.width / k` columns; regions start on multiples of k. `scatter` reads that
    /// map as one of k times wider columns. 1 (the default) is the paper's layout; the
    /// rectified width must be a multiple of k. See `docs/roofline.md` ("coarse filtered
    /// columns") for what it costs and saves.
    #[serde(skip_serializing_if = "is_one")]
    pub filtered_stride: u32,
    /// With coarse filtered columns (`filtered_stride` above 1): `scatter` resumes each row's
    /// running mean from the last stored column before the ray's end over the rectified
    /// texels up to it (their depths, weights and the ray's truncated step series, Klehm's
    /// sum `a(d) . B(d_i)` = `sum_k 2 / c_k sin(c_k (d_i - d))`), instead of reading a map
    /// `filtered_stride` times coarser: the answer of `filtered_stride = 1` (up to rounding:
    /// the resumed texels are not quantised to `storage`) from a quarter (k = 4) of its
    /// stores, for at most k texels more per lookup. `prefilter` stores each stored column's
    /// weight sum beside its bounds. Meant for sampled frames (`sampling = epipolar |
    /// lowres`), which look up far fewer points than `prefilter` stores; see
    /// `docs/roofline.md` ("Stop 58"). With a cookie the texels' cookies are resumed too.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub resume: bool,
}

fn is_one(v: &u32) -> bool {
    *v == 1
}

impl Default for PrefilteredVariant {
    fn default() -> Self {
        PrefilteredVariant {
            basis: Basis::Fourier,
            bases: 32,
            bases_per_thread: Self::DEFAULT_BASES_PER_THREAD,
            moments: Self::DEFAULT_MOMENTS,
            regions: 4,
            visibility: VisibilityMode::Weighted,
            light: LightKind::Directional,
            storage: Storage::Rgba8unorm,
            rectification: Rectification::Epipolar,
            sampling: Sampling::Pixels,
            scale: SamplingKnobs::DEFAULT_SCALE,
            depth_break: SamplingKnobs::DEFAULT_DEPTH_BREAK,
            light_break: SamplingKnobs::DEFAULT_LIGHT_BREAK,
            slices: SamplingKnobs::DEFAULT_SLICES,
            slice_samples: SamplingKnobs::DEFAULT_SLICE_SAMPLES,
            step: SamplingKnobs::DEFAULT_STEP,
            cookie: false,
            filtered_stride: 1,
            resume: false,
        }
    }
}

impl PrefilteredVariant {
    /// Allowed `bases`.
    pub const BASES: std::ops::RangeInclusive<u32> = 4..=128;
    /// Allowed `regions`. More regions narrow each region's depth range, which the moment
    /// basis needs on `window` (6 moments, 1024x1024 map: 8 regions 4.39 / 5.76 % rel L1 on
    /// window/ordinary and epipole_on_screen, 16 regions 2.19 / 2.61 %).
    pub const REGIONS: std::ops::RangeInclusive<u32> = 1..=16;
    /// The most `regions` a projective variant may have: the projective frame holds the
    /// column invariants of 9 region boundaries (`proj_g0..2` in the `Frame` block).
    pub const MAX_PROJECTIVE_REGIONS: u32 = 8;
    /// Allowed `moments`.
    pub const MOMENTS: [u32; 2] = [4, 6];
    /// Allowed `filtered_stride`: powers of two, so that a rectified column divided by the
    /// stride is exact in `f32`.
    pub const FILTERED_STRIDES: [u32; 4] = [1, 2, 4, 8];
    /// `moments` of [`PrefilteredVariant::with_moments`]'s callers that do not choose.
    pub const DEFAULT_MOMENTS: u32 = 4;
    /// The default `bases_per_thread`: 16 (the paper's Table 1 offers 4 .. 32). Measured on
    /// lavapipe (1280x720, 1024x1024 map, `godrays --gpu --variant bases_per_thread=T`):
    /// `prefilter` 27.4-28.0 ms at 16 against 39.9-40.3 at 8 and 38.7-56.0 at 32 (4 and 8
    /// regions, foliage), spot_grate 40.6 against 65.1, a 512x512 map 7.3 against 10.6:
    /// fewer invocations per texel recompute its weight, and 4 accumulated layers stay in
    /// registers where 8 do not. Knob parsers give a smaller `bases` the largest valid
    /// value below this ([`Self::default_bases_per_thread`]).
    pub const DEFAULT_BASES_PER_THREAD: u32 = 16;

    /// The largest valid `bases_per_thread` for `bases` up to
    /// [`Self::DEFAULT_BASES_PER_THREAD`] (`bases` itself below 16, 4 for `bases = 20`):
    /// what a variant given `bases` and no `bases_per_thread` gets.
    pub fn default_bases_per_thread(bases: u32) -> u32 {
        Self::bases_per_thread_options(bases)
            .into_iter()
            .filter(|&t| t <= Self::DEFAULT_BASES_PER_THREAD)
            .max()
            .unwrap_or(Self::DEFAULT_BASES_PER_THREAD)
    }

    /// The default variant with the moment basis of `moments` power moments (4 or 6) and
    /// its storage, rgba32float (the only one it allows: the moment problem is
    /// ill-conditioned, and 16 bits would need Peters et al.'s quantisation transform).
    pub fn with_moments(moments: u32) -> Self {
        Self {
            basis: Basis::Moments,
            moments,
            storage: Storage::Rgba32float,
            ..Self::default()
        }
    }

    /// Checks every knob; the error names the first offending one.
    pub fn validate(&self) -> Result<(), VariantError> {
        validate_single_light(self.light)?;
        let d = Self::default();
        if self.basis == Basis::Moments {
            if !Self::MOMENTS.contains(&self.moments) {
                return Err(VariantError {
                    knob: "moments",
                    value: self.moments.to_string(),
                    allowed: "4 or 6".into(),
                });
            }
            if self.storage != Storage::Rgba32float {
                return Err(VariantError {
                    knob: "storage",
                    value: self.storage.to_string(),
                    allowed: "rgba32float with basis = moments (power moments need 32-bit floats)"
                        .into(),
                });
            }
            if self.bases != d.bases {
                return Err(VariantError {
                    knob: "bases",
                    value: self.bases.to_string(),
                    allowed: format!(
                        "{} (a Fourier knob; with basis = moments set `moments`)",
                        d.bases
                    ),
                });
            }
            if self.bases_per_thread != d.bases_per_thread {
                return Err(VariantError {
                    knob: "bases_per_thread",
                    value: self.bases_per_thread.to_string(),
                    allowed: format!(
                        "{} (a Fourier knob; basis = moments filters every moment in one thread)",
                        d.bases_per_thread
                    ),
                });
            }
        } else if self.moments != d.moments {
            return Err(VariantError {
                knob: "moments",
                value: self.moments.to_string(),
                allowed: format!(
                    "{} (a moment-basis knob; with basis = fourier set `bases`)",
                    d.moments
                ),
            });
        }
        if !Self::BASES.contains(&self.bases) || !self.bases.is_multiple_of(4) {
            return Err(VariantError {
                knob: "bases",
                value: self.bases.to_string(),
                allowed: "a multiple of 4 in 4..=128".into(),
            });
        }
        if self.bases_per_thread == 0
            || !self.bases_per_thread.is_multiple_of(4)
            || !self.bases.is_multiple_of(self.bases_per_thread)
        {
            return Err(VariantError {
                knob: "bases_per_thread",
                value: self.bases_per_thread.to_string(),
                allowed: format!("a multiple of 4 that divides bases = {}", self.bases),
            });
        }
        if !Self::REGIONS.contains(&self.regions) {
            return Err(VariantError {
                knob: "regions",
                value: self.regions.to_string(),
                allowed: "in 1..=16".into(),
            });
        }
        if self.rectification == Rectification::Projective
            && self.regions > Self::MAX_PROJECTIVE_REGIONS
        {
            return Err(VariantError {
                knob: "regions",
                value: self.regions.to_string(),
                allowed: "in 1..=8 with rectification = projective (its frame holds 9 region \
                          boundaries; up to 16 with epipolar)"
                    .into(),
            });
        }
        if !Self::FILTERED_STRIDES.contains(&self.filtered_stride) {
            return Err(VariantError {
                knob: "filtered_stride",
                value: self.filtered_stride.to_string(),
                allowed: "1, 2, 4 or 8".into(),
            });
        }
        if self.resume && self.filtered_stride == 1 {
            return Err(VariantError {
                knob: "resume",
                value: "true".into(),
                allowed: "false with filtered_stride = 1 (true needs filtered_stride = 2, 4 or 8: \
                          with 1 every column is stored and there is nothing to resume)"
                    .into(),
            });
        }
        self.sampling_knobs().validate()?;
        crate::cookie::validate_cookie(self.cookie, self.light)
    }

    /// Whether `regions` regions are valid with `rectification` (projective: at most
    /// [`Self::MAX_PROJECTIVE_REGIONS`]).
    pub fn regions_fit(regions: u32, rectification: Rectification) -> bool {
        rectification != Rectification::Projective || regions <= Self::MAX_PROJECTIVE_REGIONS
    }

    /// Every valid `bases_per_thread` for `bases`.
    pub fn bases_per_thread_options(bases: u32) -> Vec<u32> {
        (4..=bases)
            .step_by(4)
            .filter(|b| bases.is_multiple_of(*b))
            .collect()
    }

    /// Every valid variant with bases in {4, 8, 16, 32, 64, 128} (the powers of two of the
    /// design card), every `bases_per_thread`, the given `regions`, both visibilities, both
    /// lights, every storage format and both rectifications; sorted by those knobs; then the
    /// moment basis; then the spot with a cookie (each basis, both visibilities and
    /// rectifications, 3 regions where `regions` holds 3), all with `filtered_stride = 1`;
    /// then the coarse-column variants ([`Self::stride_grid`]) and the `resume` ones
    /// ([`Self::resume_grid`]).
    pub fn grid(regions: std::ops::RangeInclusive<u32>) -> Vec<PrefilteredVariant> {
        let mut out = Vec::new();
        for bases in [4, 8, 16, 32, 64, 128] {
            for bases_per_thread in Self::bases_per_thread_options(bases) {
                for r in regions.clone() {
                    for &visibility in VisibilityMode::ALL {
                        for &light in LightKind::SINGLE {
                            for &storage in Storage::ALL {
                                for &rectification in Rectification::ALL {
                                    if !Self::regions_fit(r, rectification) {
                                        continue;
                                    }
                                    out.push(PrefilteredVariant {
                                        bases,
                                        bases_per_thread,
                                        regions: r,
                                        visibility,
                                        light,
                                        storage,
                                        rectification,
                                        ..Self::default()
                                    });
                                }
                            }
                        }
                    }
                }
            }
        }
        for moments in Self::MOMENTS {
            for r in regions.clone() {
                for &visibility in VisibilityMode::ALL {
                    for &light in LightKind::SINGLE {
                        for &rectification in Rectification::ALL {
                            if !Self::regions_fit(r, rectification) {
                                continue;
                            }
                            out.push(PrefilteredVariant {
                                regions: r,
                                visibility,
                                light,
                                rectification,
                                ..Self::with_moments(moments)
                            });
                        }
                    }
                }
            }
        }
        // The spot with its cookie: each basis, both visibilities and both rectifications at
        // the paper's bases (m32) and the default region count where it is in range.
        let r = regions
            .clone()
            .find(|r| *r == 3)
            .unwrap_or(*regions.start());
        for base in [
            Self::default(),
            Self::with_moments(4),
            Self::with_moments(6),
        ] {
            for &visibility in VisibilityMode::ALL {
                for &rectification in Rectification::ALL {
                    out.push(PrefilteredVariant {
                        regions: r,
                        visibility,
                        light: LightKind::Spot,
                        rectification,
                        cookie: true,
                        ..base
                    });
                }
            }
        }
        out.extend(Self::stride_grid(regions.clone()));
        out.extend(Self::resume_grid(regions));
        out
    }

    /// The `resume` variants of [`Self::grid`]: every `filtered_stride` above 1 with every
    /// light, rectification and visibility, the five bases of [`Self::stride_grid`] and the
    /// regions that fit [`Self::STRIDE_GRID_WIDTH`] cycling, then the spot with its cookie
    /// (Fourier and 4 moments) at each stride (30 variants: every knob value meets every
    /// stride).
    fn resume_grid(regions: std::ops::RangeInclusive<u32>) -> Vec<PrefilteredVariant> {
        let bases = Self::stride_grid_bases();
        let mut out = Vec::new();
        let mut n = 0;
        for k in Self::FILTERED_STRIDES.into_iter().filter(|&k| k > 1) {
            let fits: Vec<u32> = regions
                .clone()
                .filter(|r| k * r * r <= Self::STRIDE_GRID_WIDTH)
                .collect();
            if fits.is_empty() {
                continue;
            }
            for &light in LightKind::SINGLE {
                for &rectification in Rectification::ALL {
                    for &visibility in VisibilityMode::ALL {
                        out.push(PrefilteredVariant {
                            regions: fits[n % fits.len()],
                            visibility,
                            light,
                            rectification,
                            filtered_stride: k,
                            resume: true,
                            ..bases[n % bases.len()]
                        });
                        n += 1;
                    }
                }
            }
            // The spot with its cookie: the Fourier basis and 4 moments, one rectification
            // each, alternating with k; 2 regions (within `regions`), whose starts every
            // stride keeps on the conformance map, so that the outputs compare with k = 1.
            for (i, base) in [Self::default(), Self::with_moments(4)]
                .into_iter()
                .enumerate()
            {
                out.push(PrefilteredVariant {
                    regions: if fits.contains(&2) {
                        2
                    } else {
                        fits[n % fits.len()]
                    },
                    light: LightKind::Spot,
                    rectification: Rectification::ALL[(i + k as usize / 2) % 2],
                    cookie: true,
                    filtered_stride: k,
                    resume: true,
                    ..base
                });
                n += 1;
            }
        }
        out
    }

    /// The rectified width the coarse-column variants of [`Self::grid`] are chosen for
    /// (the conformance tests' map): every one has `filtered_stride * regions^2` at most
    /// this.
    pub const STRIDE_GRID_WIDTH: u32 = 64;

    /// The five bases the coarse-column and `resume` grids run: m32-t16 rgba8unorm, m16-t8
    /// rgba16float, m8-t4 rgba32float, 4 and 6 moments.
    fn stride_grid_bases() -> [PrefilteredVariant; 5] {
        [
            Self::default(),
            Self {
                bases: 16,
                bases_per_thread: 8,
                storage: Storage::Rgba16float,
                ..Self::default()
            },
            Self {
                bases: 8,
                bases_per_thread: 4,
                storage: Storage::Rgba32float,
                ..Self::default()
            },
            Self::with_moments(4),
            Self::with_moments(6),
        ]
    }

    /// The coarse-column variants of [`Self::grid`]: every `filtered_stride` above 1 with
    /// every light, rectification and visibility, each with five bases (m32-t16
    /// rgba8unorm, m16-t8 rgba16float, m8-t4 rgba32float, 4 and 6 moments), the regions
    /// cycling through those of `regions` that fit [`Self::STRIDE_GRID_WIDTH`]; then the
    /// spot with its cookie (Fourier and 4 moments, both rectifications). Every knob value
    /// meets every stride.
    fn stride_grid(regions: std::ops::RangeInclusive<u32>) -> Vec<PrefilteredVariant> {
        let bases = Self::stride_grid_bases();
        let mut out = Vec::new();
        for k in Self::FILTERED_STRIDES.into_iter().filter(|&k| k > 1) {
            let fits: Vec<u32> = regions
                .clone()
                .filter(|r| k * r * r <= Self::STRIDE_GRID_WIDTH)
                .collect();
            if fits.is_empty() {
                continue;
            }
            let mut n = 0;
            let mut next_regions = || {
                n += 1;
                fits[(n - 1) % fits.len()]
            };
            for &light in LightKind::SINGLE {
                for &rectification in Rectification::ALL {
                    for &visibility in VisibilityMode::ALL {
                        for base in bases {
                            out.push(PrefilteredVariant {
                                regions: next_regions(),
                                visibility,
                                light,
                                rectification,
                                filtered_stride: k,
                                ..base
                            });
                        }
                    }
                }
            }
            for base in [Self::default(), Self::with_moments(4)] {
                for &rectification in Rectification::ALL {
                    out.push(PrefilteredVariant {
                        regions: next_regions(),
                        light: LightKind::Spot,
                        rectification,
                        cookie: true,
                        filtered_stride: k,
                        ..base
                    });
                }
            }
        }
        out
    }

    /// rgba layers of one colour channel's filtered basis: `bases / 4` (Fourier), or
    /// `ceil(moments / 4)` (moments: `(z, z^2, z^3, z^4)` then `(z^5, z^6, 0, 0)`). The
    /// `filtered` buffer holds [`Self::filtered_layers`].
    pub fn layers(&self) -> u32 {
        match self.basis {
            Basis::Fourier => self.bases / 4,
            Basis::Moments => self.moments.div_ceil(4),
        }
    }

    /// rgba layers of the `filtered` buffer: [`Self::layers`], or with a cookie
    /// `3 * layers + 1` (channel `c`'s layer `q` at `c * layers + q`, then the region's mean
    /// cookie, rgb, in the last layer).
    pub fn filtered_layers(&self) -> u32 {
        if self.cookie {
            3 * self.layers() + 1
        } else {
            self.layers()
        }
    }

    /// Invocations per (row, region): `bases / bases_per_thread` (Fourier), 1 (moments).
    pub fn threads_per_row_region(&self) -> u32 {
        match self.basis {
            Basis::Fourier => self.bases / self.bases_per_thread,
            Basis::Moments => 1,
        }
    }

    /// Bases one prefilter invocation filters: `bases_per_thread` (Fourier), every moment
    /// (moments).
    pub fn per_thread(&self) -> u32 {
        match self.basis {
            Basis::Fourier => self.bases_per_thread,
            Basis::Moments => self.moments,
        }
    }

    /// The basis in a variant id: `m{bases}-t{bases_per_thread}` (Fourier) or
    /// `moments{moments}`.
    fn basis_id(&self) -> String {
        match self.basis {
            Basis::Fourier => format!("m{}-t{}", self.bases, self.bases_per_thread),
            Basis::Moments => format!("moments{}", self.moments),
        }
    }

    /// The smallest rectified width for this variant: every region needs a stored
    /// column, so `filtered_stride * regions^2` (the sun's quadratic region starts give the
    /// first region `width / regions^2` columns).
    pub fn min_rectified_width(&self) -> u32 {
        self.filtered_stride * self.regions * self.regions
    }

    /// Columns of the `filtered` and `bounds` maps for a rectified width:
    /// `width / filtered_stride`.
    pub fn filtered_width(&self, rectified_width: u32) -> u32 {
        rectified_width / self.filtered_stride.max(1)
    }

    /// `-stride{k}` for a `filtered_stride` other than 1 (`-stride{k}-resume` with `resume`),
    /// else empty.
    fn stride_suffix(&self) -> String {
        if self.filtered_stride == 1 {
            String::new()
        } else if self.resume {
            format!("-stride{}-resume", self.filtered_stride)
        } else {
            format!("-stride{}", self.filtered_stride)
        }
    }

    /// A short stable id, used in file names and trial names:
    /// `m32-t16-r3-weighted-directional-rgba8unorm-epipolar`,
    /// `moments4-r3-weighted-directional-rgba32float-epipolar`, with a cookie
    /// `m32-t16-r3-weighted-spot-cookie-rgba8unorm-epipolar`, with coarse filtered columns
    /// `m32-t16-r3-weighted-directional-rgba8unorm-epipolar-stride4`.
    pub fn id(&self) -> String {
        format!(
            "{}-r{}-{}-{}{}-{}-{}{}{}",
            self.basis_id(),
            self.regions,
            self.visibility,
            self.light,
            crate::cookie::id_suffix(self.cookie),
            self.storage,
            self.rectification,
            self.stride_suffix(),
            self.sampling_knobs().id_suffix()
        )
    }
}

crate::sampling::sampling_fields!(PrefilteredVariant);

impl fmt::Display for PrefilteredVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.id())
    }
}

impl KnobSet for PrefilteredVariant {
    const FAMILY_NAME: &'static str = "prefiltered";
    const FAMILY: Family = Family::Prefiltered;
    const SUMMARY: &'static str = "Klehm et al. 2014, prefiltered single scattering: Fourier-basis visibility \
         prefiltered along epipolar rows of a rectified shadow map";

    fn validate(&self) -> Result<(), VariantError> {
        PrefilteredVariant::validate(self)
    }

    fn id(&self) -> String {
        PrefilteredVariant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    fn with_light(self, light: LightKind) -> Self {
        Self { light, ..self }
    }

    /// `m{bases}-r{regions}` (or `moments{moments}-r{regions}`), then
    /// `-t{bases_per_thread}`, the visibility, the storage and the rectification where they
    /// differ from the basis's default.
    fn marker(&self) -> String {
        let d = match self.basis {
            Basis::Fourier => Self::default(),
            Basis::Moments => Self::with_moments(self.moments),
        };
        let mut m = match self.basis {
            Basis::Fourier => format!("m{}-r{}", self.bases, self.regions),
            Basis::Moments => format!("moments{}-r{}", self.moments, self.regions),
        };
        if self.bases_per_thread != d.bases_per_thread {
            m += &format!("-t{}", self.bases_per_thread);
        }
        if self.visibility != d.visibility {
            m += &format!("-{}", self.visibility);
        }
        if self.storage != d.storage {
            m += &format!("-{}", self.storage);
        }
        if self.rectification != d.rectification {
            m += &format!("-{}", self.rectification);
        }
        m += crate::cookie::id_suffix(self.cookie);
        m += &self.stride_suffix();
        m + &self.sampling_knobs().marker_suffix()
    }

    fn sampling(&self) -> SamplingKnobs {
        self.sampling_knobs()
    }

    fn with_sampling(self, s: SamplingKnobs) -> Self {
        self.with_sampling_knobs(s)
    }

    /// Regions 1..=4 (every other knob at every value).
    fn grid() -> Vec<Self> {
        PrefilteredVariant::grid(1..=4)
    }

    fn cookie(&self) -> bool {
        self.cookie
    }

    fn with_cookie(self, cookie: bool) -> Option<Self> {
        Some(Self { cookie, ..self })
    }
}
