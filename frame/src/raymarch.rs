//! The `raymarch` family (Tóth & Umenhoffer 2009): brute-force ray marching through the
//! standard shadow map, optionally with interleaved sampling. [`RaymarchVariant`] holds its
//! knobs; [`prepare_raymarch`] fills its uniform block ([`RaymarchUniforms`], WGSL `struct RaymarchFrame`
//! in `shaderlib/templates/common/raymarch.wgsl`).
//!
//! # The estimate
//!
//! A view ray `[0, s]` is cut into `samples` (N) cells of length `h = s / N`; cell `j` is
//! sampled at `t_j = (j + u) h` with `u = 0.5`, or a per-pixel jitter `u` in [0, 1).
//! Directional light: each cell contributes `V(t_j)` times the exact transmittance integral
//! over the cell (`sigma_s p E` applied once per pixel); spot light: `V(t_j) f(t_j) h`, `f`
//! the shadow-free integrand (cone, `exp(-sigma_t (d + t)) / d^2`, phase).
//!
//! Interleaved sampling with `interleave` M > 1: pixel `(x, y)` belongs to class
//! `c = (x mod Mx) + Mx (y mod My)` with `Mx = min(M, width)`, `My = min(M, height)`, and
//! sums only the cells `j = c, c + Mx My, c + 2 Mx My, ...`; a separable sum filter
//! (`interleave_sum`, M taps along x, then along y, windows clamped inside the screen so each
//! holds every class once) adds the classes of the neighbourhood. With a constant integrand
//! the result is exactly the full-N sum; elsewhere it trades noise for blur across depth
//! edges (the paper's "halos").

use crate::family::{Family, KnobSet};
use crate::sampling::{Sampling, SamplingKnobs};
use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};
use std::fmt;

use crate::frame::{
    CameraDesc, FrameError, LightDesc, MediumDesc, ShadowMapDesc, finite_fields, shadow_projection,
    v4, validate_scene, validate_shadow_map, validate_shadow_projection,
};
use crate::variant::{LightKind, VariantError};

/// The knobs of the `raymarch` family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RaymarchVariant {
    /// Cells per view ray N (4..=1024, a multiple of `interleave^2`).
    pub samples: u32,
    /// Interleaving tile side M (1..=8; 1 = every pixel takes all N samples, no filter).
    pub interleave: u32,
    /// Per-pixel jitter of the sample positions inside their cells.
    pub jitter: bool,
    /// Light type.
    pub light: LightKind,
    /// Where `raymarch` runs: every pixel, or a low-resolution grid ([`crate::sampling`]).
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
    /// A spot light's cookie: an RGB texture projected along the cone multiplies the
    /// light's intensity per sample (`light = spot` only; the kernels bind the engine's
    /// `cookie` texture, [`crate::cookie`]).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub cookie: bool,
}

impl Default for RaymarchVariant {
    /// 64 samples, no interleaving, no jitter, directional light.
    fn default() -> Self {
        RaymarchVariant {
            samples: 64,
            interleave: 1,
            jitter: false,
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

impl RaymarchVariant {
    /// Allowed `samples`.
    pub const SAMPLES: std::ops::RangeInclusive<u32> = 4..=1024;
    /// Allowed `interleave`.
    pub const INTERLEAVE: std::ops::RangeInclusive<u32> = 1..=8;

    /// Checks every knob; the error names the first offending one.
    pub fn validate(&self) -> Result<(), VariantError> {
        crate::variant::validate_single_light(self.light)?;
        if !Self::INTERLEAVE.contains(&self.interleave) {
            return Err(VariantError {
                knob: "interleave",
                value: self.interleave.to_string(),
                allowed: "in 1..=8".into(),
            });
        }
        let m2 = self.interleave * self.interleave;
        if !Self::SAMPLES.contains(&self.samples) || !self.samples.is_multiple_of(m2) {
            return Err(VariantError {
                knob: "samples",
                value: self.samples.to_string(),
                allowed: format!(
                    "in 4..=1024 and a multiple of interleave^2 = {m2} (every pixel class gets the same number of samples)"
                ),
            });
        }
        self.sampling_knobs().validate()?;
        crate::cookie::validate_cookie(self.cookie, self.light)?;
        if self.interleaved() && self.sampling_knobs().is_sampled() {
            return Err(VariantError {
                knob: "interleave",
                value: self.interleave.to_string(),
                allowed: format!(
                    "1 with sampling = {} (interleaving spreads a pixel's samples over its \
                     neighbours, which a sampled variant does not evaluate)",
                    self.sampling
                ),
            });
        }
        Ok(())
    }

    /// Whether the variant has the `interleave_sum` passes.
    pub fn interleaved(&self) -> bool {
        self.interleave > 1
    }

    /// A short stable id: `n64-i4-jitter-directional`, `n128-i1-nojitter-spot`,
    /// `n64-i1-nojitter-spot-cookie`.
    pub fn id(&self) -> String {
        format!(
            "n{}-i{}-{}-{}{}{}",
            self.samples,
            self.interleave,
            if self.jitter { "jitter" } else { "nojitter" },
            self.light,
            crate::cookie::id_suffix(self.cookie),
            self.sampling_knobs().id_suffix()
        )
    }

    /// The conformance grid: samples {8, 32, 128} x interleave {1, 2, 4} x jitter x light
    /// (pairs whose samples are not a multiple of interleave^2 skipped), and the spot's
    /// cookie at 32 samples with interleave 1 and 2, jittered or not.
    pub fn grid() -> Vec<RaymarchVariant> {
        let mut out = Vec::new();
        for samples in [8, 32, 128] {
            for interleave in [1, 2, 4] {
                for jitter in [false, true] {
                    for &light in LightKind::SINGLE {
                        let v = RaymarchVariant {
                            samples,
                            interleave,
                            jitter,
                            light,
                            ..RaymarchVariant::default()
                        };
                        if v.validate().is_ok() {
                            out.push(v);
                        }
                        if samples == 32 && interleave <= 2 && light == LightKind::Spot {
                            out.push(RaymarchVariant { cookie: true, ..v });
                        }
                    }
                }
            }
        }
        out
    }
}

crate::sampling::sampling_fields!(RaymarchVariant);

impl fmt::Display for RaymarchVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.id())
    }
}

/// The uniform block of the `raymarch` and `interleave_sum` kernels (WGSL `struct RaymarchFrame`).
/// Every field is a 16-byte vector; the asserts below pin the layout.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct RaymarchUniforms {
    /// Eye position; w = camera far (view depths are clamped to it).
    pub eye: [f32; 4],
    /// Camera forward; w = tan(fov_y / 2).
    pub cam_forward: [f32; 4],
    /// Camera right; w = aspect (width / height).
    pub cam_right: [f32; 4],
    /// Camera up; w = near.
    pub cam_up: [f32; 4],
    /// x = sigma_t, y = sigma_s, z = g, w unused.
    pub medium: [f32; 4],
    /// Light colour (E or I); w unused.
    pub light_color: [f32; 4],
    /// Spot position; w = cos(inner angle).
    pub light_pos: [f32; 4],
    /// Direction the light travels (spot axis); w = cos(outer angle).
    pub light_dir: [f32; 4],
    /// Shadow-map right; w = shadow-map near.
    pub sm_right: [f32; 4],
    /// Shadow-map up; w = shadow-map far.
    pub sm_up: [f32; 4],
    /// Shadow-map forward; w = bias in texel footprints.
    pub sm_forward: [f32; 4],
    /// Shadow-map origin; w = 0 orthographic, 1 perspective.
    pub sm_origin: [f32; 4],
    /// Orthographic: x0, x1, y0, y1. Perspective: tan_half, 0, 0, 0.
    pub sm_proj: [f32; 4],
    /// Screen width, height, shadow-map size, samples N.
    pub sizes: [u32; 4],
    /// Mx = min(M, width), My = min(M, height), jitter (0 or 1), M.
    pub interleave: [u32; 4],
}

const _: () = {
    assert!(size_of::<RaymarchUniforms>() == 15 * 16);
    assert!(std::mem::offset_of!(RaymarchUniforms, sm_proj) == 12 * 16);
    assert!(std::mem::offset_of!(RaymarchUniforms, sizes) == 13 * 16);
    assert!(std::mem::offset_of!(RaymarchUniforms, interleave) == 14 * 16);
};

/// Fills the `raymarch` uniform block for one frame.
///
/// # Errors
///
/// [`FrameError::Size`] for a zero or oversized screen or shadow map,
/// [`FrameError::LightMismatch`] for a light of the other type, [`FrameError::OutOfRange`]
/// naming the parameter for a NaN, infinite, out-of-range or degenerate camera, light,
/// medium or shadow map, [`FrameError::EyeAtLight`], [`FrameError::NotRepresentable`] if a
/// uniform still came out non-finite; a variant error for bad knobs is reported as
/// [`FrameError::Variant`].
pub fn prepare_raymarch(
    variant: &RaymarchVariant,
    screen: [u32; 2],
    camera: &CameraDesc,
    light: &LightDesc,
    medium: &MediumDesc,
    shadow: &ShadowMapDesc,
) -> Result<RaymarchUniforms, FrameError> {
    variant.validate().map_err(FrameError::Variant)?;
    for (what, value, max) in [
        ("screen width", screen[0], 16384),
        ("screen height", screen[1], 16384),
        ("shadow map size", shadow.size, 16384),
    ] {
        if value == 0 || value > max {
            return Err(FrameError::Size { what, value, max });
        }
    }
    let sc = validate_scene(variant.light, camera, light, medium)?;
    validate_shadow_map(shadow)?;
    validate_shadow_projection(variant.light, shadow)?;
    let (sm_kind, sm_proj) = shadow_projection(shadow);
    let cam = sc.cam;
    let m = variant.interleave;
    let u = RaymarchUniforms {
        eye: v4(cam.position, cam.far),
        cam_forward: v4(cam.forward, cam.tan_half_fov_y),
        cam_right: v4(cam.right, f64::from(screen[0]) / f64::from(screen[1])),
        cam_up: v4(cam.up, cam.near),
        medium: [
            medium.sigma_t as f32,
            (medium.sigma_t * medium.albedo) as f32,
            medium.g as f32,
            0.0,
        ],
        light_color: [
            sc.color[0] as f32,
            sc.color[1] as f32,
            sc.color[2] as f32,
            0.0,
        ],
        light_pos: v4(sc.light_pos, sc.cos_in),
        light_dir: v4(sc.light_dir, sc.cos_out),
        sm_right: v4(shadow.basis[0], shadow.near),
        sm_up: v4(shadow.basis[1], shadow.far),
        sm_forward: v4(shadow.basis[2], shadow.bias_texels),
        sm_origin: v4(shadow.origin, sm_kind),
        sm_proj,
        sizes: [screen[0], screen[1], shadow.size, variant.samples],
        interleave: [
            m.min(screen[0]),
            m.min(screen[1]),
            u32::from(variant.jitter),
            m,
        ],
    };
    finite_fields([
        ("eye", u.eye),
        ("cam_forward", u.cam_forward),
        ("cam_right", u.cam_right),
        ("cam_up", u.cam_up),
        ("medium", u.medium),
        ("light_color", u.light_color),
        ("light_pos", u.light_pos),
        ("light_dir", u.light_dir),
        ("sm_right", u.sm_right),
        ("sm_up", u.sm_up),
        ("sm_forward", u.sm_forward),
        ("sm_origin", u.sm_origin),
        ("sm_proj", u.sm_proj),
    ])?;
    Ok(u)
}

impl KnobSet for RaymarchVariant {
    const FAMILY_NAME: &'static str = "raymarch";
    const FAMILY: Family = Family::Raymarch;
    const SUMMARY: &'static str = "Toth & Umenhoffer 2009, ray marching through the standard shadow map, \
         optionally with interleaved sampling and a separable sum filter";

    fn validate(&self) -> Result<(), VariantError> {
        RaymarchVariant::validate(self)
    }

    fn id(&self) -> String {
        RaymarchVariant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    fn with_light(self, light: LightKind) -> Self {
        Self { light, ..self }
    }

    /// `n{samples}-i{interleave}`, `-nojitter` / `-jitter` where it differs from the
    /// default.
    fn marker(&self) -> String {
        let mut m = format!("n{}-i{}", self.samples, self.interleave);
        if self.jitter != Self::default().jitter {
            m += if self.jitter { "-jitter" } else { "-nojitter" };
        }
        m += crate::cookie::id_suffix(self.cookie);
        m + &self.sampling_knobs().marker_suffix()
    }

    fn sampling(&self) -> SamplingKnobs {
        self.sampling_knobs()
    }

    fn with_sampling(self, s: SamplingKnobs) -> Self {
        self.with_sampling_knobs(s)
    }

    fn cookie(&self) -> bool {
        self.cookie
    }

    fn with_cookie(self, cookie: bool) -> Option<Self> {
        Some(Self { cookie, ..self })
    }

    fn grid() -> Vec<Self> {
        RaymarchVariant::grid()
    }
}
