//! The sampling stage every family can use ([`scatter_frame::sampling`]): the askama view
//! the families' per-pixel kernels render their entry point with
//! (`templates/include/sampled_entry.wgsl`, `templates/include/sampled_bindings.wgsl`,
//! shared WGSL `templates/common/sampling.wgsl`), and the dispatch a family's plan gives its
//! per-pixel pass. CPU mirror: `reference/src/kernels/common_sampling.rs`.

pub use scatter_frame::sampling::{Sampling, SamplingKnobs};

use crate::Kernel;

/// What a family's per-pixel template needs of the sampling knobs (its field `sampling`).
#[derive(Clone, Debug)]
pub(crate) struct SamplingView {
    /// Whether the kernel is one of the lowres passes (`sampling = lowres`).
    pub lowres: bool,
    /// Whether the kernel is one of the epipolar passes (`sampling = epipolar`).
    pub epipolar: bool,
    /// Whether the kernel is the unwarp (`<kernel>_unwarp`: the gather of every pixel from
    /// the samples, lowres or epipolar).
    pub unwarp: bool,
    /// Whether the kernel is the fallback (`<kernel>_fallback`).
    pub fallback: bool,
    /// Block side S.
    pub scale: u32,
    /// Pixels per axis per invocation of the `_unwarp` pass ([`unwarp_block`]).
    pub unwarp_block: u32,
    /// The depth break as a WGSL f32 literal (a fraction of the nearer depth).
    pub depth_break: String,
    /// The light break as a WGSL f32 literal (a fraction of the brightest sample).
    pub light_break: String,
    /// Epipolar slices, samples per slice, initial step.
    pub slices: u32,
    pub slice_samples: u32,
    pub step: u32,
    /// Invocations per slice of the epipolar samples pass ([`SLICE_LANES`]).
    pub slice_lanes: u32,
    /// Workgroups per row of the `_fallback` pass's dispatch ([`FALLBACK_ROW_GROUPS`]).
    pub fallback_row_groups: u32,
    /// The kernel's entry point.
    pub entry: &'static str,
    /// The family kernel's entry point (`entry` without `_unwarp` or `_fallback`).
    pub family_entry: &'static str,
    /// The family's per-pixel function, `<family kernel>_pixel`.
    pub pixel: String,
    /// A WGSL expression of type `scatter::sampling::EpipolarCamera` from the kernel's
    /// uniform block.
    pub camera: String,
    /// The family's first free binding B: the samples texture (`lowres_samples` or
    /// `epipolar_samples`) in the unwarp pass; B + 1 is `fallback_count` and B + 2
    /// `fallback_pixels` in the passes that bind them.
    pub binding: u32,
    /// The `#import scatter::sampling::{..}` line the kernel needs (empty for `pixels`).
    pub imports: &'static str,
    /// The format of `output`: rgba32float for the samples pass's samples, else
    /// rgba16float.
    pub output_format: &'static str,
}

impl SamplingView {
    /// The view of `knobs` for kernel `kernel`, whose per-pixel body is the one of
    /// `family_kernel` (the same kernel, or the family kernel of an `_unwarp` or
    /// `_fallback` pass), whose uniform block gives `camera` and whose first free binding is
    /// `binding`.
    pub(crate) fn new(
        knobs: &SamplingKnobs,
        kernel: Kernel,
        family_kernel: Kernel,
        camera: String,
        binding: u32,
    ) -> Self {
        let fallback = kernel != family_kernel && kernel.name().ends_with("_fallback");
        let unwarp = kernel != family_kernel && !fallback;
        let imports = match knobs.sampling {
            Sampling::Pixels => "",
            Sampling::Lowres | Sampling::Epipolar if fallback => "",
            Sampling::Lowres if unwarp => {
                "#import scatter::sampling::{lowres_blend, lowres_grid, lowres_taps}"
            }
            Sampling::Lowres => "#import scatter::sampling::{lowres_grid, lowres_pixel, round_f16}",
            Sampling::Epipolar if unwarp => {
                "#import scatter::sampling::{EpipolarLayout, epipolar_block_slices, epipolar_block_taps, epipolar_block_weights, lowres_blend}"
            }
            Sampling::Epipolar => {
                "#import scatter::sampling::{EpipolarCamera, depth_close, epipolar_layout, round_f16, slice_direction, slice_sample_pixel, slice_span}"
            }
        };
        Self {
            lowres: knobs.sampling == Sampling::Lowres,
            epipolar: knobs.sampling == Sampling::Epipolar,
            unwarp,
            fallback,
            scale: knobs.scale,
            unwarp_block: unwarp_block(knobs),
            depth_break: wgsl_f32(knobs.depth_break_fraction()),
            light_break: wgsl_f32(knobs.light_break_fraction()),
            slices: knobs.slices,
            slice_samples: knobs.slice_samples,
            step: knobs.step,
            slice_lanes: SLICE_LANES,
            fallback_row_groups: FALLBACK_ROW_GROUPS,
            entry: kernel.name(),
            family_entry: family_kernel.name(),
            pixel: format!("{}_pixel", family_kernel.name()),
            camera,
            binding,
            imports,
            output_format: if knobs.is_sampled() && !unwarp && !fallback {
                SAMPLES_FORMAT
            } else {
                "rgba16float"
            },
        }
    }
}

/// The `EpipolarCamera` of a uniform block named `frame` whose fields `cam_forward` (w =
/// tan(fov_y / 2)), `cam_right` (w = aspect) and `cam_up` are the camera's, with `toward`
/// the direction towards the light.
pub(crate) fn camera_expr(toward: &str) -> String {
    format!(
        "EpipolarCamera(frame.cam_forward.xyz, frame.cam_right.xyz, frame.cam_up.xyz, \
         frame.cam_forward.w, frame.cam_right.w, {toward})"
    )
}

/// An f32 as a WGSL literal that parses back to the same value.
fn wgsl_f32(v: f32) -> String {
    let s = format!("{v:?}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

/// The invocations of a family's per-pixel pass: the screen for `pixels`; for `lowres`,
/// one per sample of the grid ([`lowres_grid_formula`]: one more than the grid along an
/// axis whose size minus one the block side divides; the kernel skips the extra ones); for
/// `epipolar`, one
/// workgroup of [`SLICE_LANES`] invocations per slice: `SLICE_LANES * slices` by 1.
pub fn sampling_invocations(knobs: &SamplingKnobs) -> [String; 3] {
    sampling_invocations_with_lanes(knobs, SLICE_LANES)
}

/// [`sampling_invocations`] with `lanes` invocations per slice for `epipolar` (a family
/// whose samples pass is its own, `pst_sweep`).
pub fn sampling_invocations_with_lanes(knobs: &SamplingKnobs, lanes: u32) -> [String; 3] {
    match knobs.sampling {
        Sampling::Pixels => ["screen.width".into(), "screen.height".into(), "1".into()],
        Sampling::Lowres => {
            let [w, h] = lowres_grid_formula(knobs.scale);
            [w, h, "1".into()]
        }
        Sampling::Epipolar => [(lanes * knobs.slices).to_string(), "1".into(), "1".into()],
    }
}

/// A bound of the lowres sample grid of block side `scale` (`lowres_grid`: ceil((screen -
/// 1) / S) + 1 per axis) as plan formulas: ceil(screen / S) + 1.
pub fn lowres_grid_formula(scale: u32) -> [String; 2] {
    [
        format!("ceil(screen.width / {scale}) + 1"),
        format!("ceil(screen.height / {scale}) + 1"),
    ]
}

/// The texture the samples pass of a sampled plan writes and its `_unwarp` pass reads:
/// `lowres_samples` or `epipolar_samples` (`None` for `pixels`).
pub fn samples_name(knobs: &SamplingKnobs) -> Option<&'static str> {
    match knobs.sampling {
        Sampling::Pixels => None,
        Sampling::Lowres => Some(LOWRES_SAMPLES),
        Sampling::Epipolar => Some(EPIPOLAR_SAMPLES),
    }
}

/// The samples texture of a sampled plan: for `lowres` the grid's samples (at most
/// `(ceil(screen.width / S) + 1) x (ceil(screen.height / S) + 1)`, rgba32float: radiance,
/// the sample pixel's depth in alpha); for `epipolar` (`(slice_samples + 1) x (slices +
/// 1)`, rgba32float: the last column holds each slice's line, the last row the layout);
/// `None` for `pixels`.
pub fn samples_texture(knobs: &SamplingKnobs) -> Option<crate::plan::Resource> {
    match knobs.sampling {
        Sampling::Pixels => None,
        Sampling::Lowres => {
            let [w, h] = lowres_grid_formula(knobs.scale);
            Some(crate::plan::scatter_texture(
                LOWRES_SAMPLES,
                "sampling = lowres: the samples of the low-resolution grid (x, y = sample \
                 column and row; sample (i, j) stands on pixel min((i, j) S, screen - 1)): \
                 radiance rgb rounded to f16, the view depth of the sample's pixel in alpha \
                 (written by the family's per-pixel kernel, read by its _unwarp pass)",
                SAMPLES_FORMAT,
                &w,
                &h,
            ))
        }
        Sampling::Epipolar => Some(crate::plan::scatter_texture(
            EPIPOLAR_SAMPLES,
            "sampling = epipolar: the samples of every slice (x = sample, y = slice): radiance \
             rgb, the view depth of the sample's pixel in alpha; the last column holds the \
             slice's line (direction xy, first distance, distance between samples), the last \
             row's first two texels the layout (origin xy, axis xy; first angle, angle per \
             slice, wrap) (written by the family's per-pixel kernel, read by its _unwarp pass)",
            SAMPLES_FORMAT,
            &(knobs.slice_samples + 1).to_string(),
            &(knobs.slices + 1).to_string(),
        )),
    }
}

/// An error for the `_unwarp` or `_fallback` pass `kernel` of a variant that samples every
/// pixel.
pub(crate) fn unwarp_only(kernel: Kernel, sampling: Sampling) -> Result<(), crate::ShaderError> {
    if sampling != Sampling::Pixels {
        Ok(())
    } else {
        Err(crate::ShaderError::InvalidParameter {
            kernel,
            knob: "sampling",
            value: sampling.to_string(),
            allowed: "lowres or epipolar (only the sampled modes have unwarp and fallback passes)",
        })
    }
}

/// The resource a family's per-pixel kernel writes: `output`, or the samples texture with
/// `lowres` or `epipolar` sampling (its `_unwarp` pass writes `output`).
pub fn sampled_output(knobs: &SamplingKnobs) -> &'static str {
    samples_name(knobs).unwrap_or("output")
}

/// The family kernel's pass `family` as `knobs` sample it: with `lowres` or `epipolar`,
/// `fallback_count` bound at `binding + 1` (the samples pass zeroes it for the unwarp);
/// unchanged otherwise.
pub fn sampled_pass(
    knobs: &SamplingKnobs,
    mut family: crate::plan::PassPlan,
    binding: u32,
) -> crate::plan::PassPlan {
    if knobs.is_sampled() {
        family
            .bindings
            .push(crate::plan::bind(binding + 1, FALLBACK_COUNT));
    }
    family
}

/// The bindings of the family kernel's pass `family` as its `_unwarp` and `_fallback`
/// passes take them: `output` where `family` writes the samples texture, without what
/// [`sampled_pass`] added.
fn family_bindings(family: &crate::plan::PassPlan) -> Vec<crate::plan::BindingSource> {
    family
        .bindings
        .iter()
        .filter(|b| b.resource != FALLBACK_COUNT)
        .cloned()
        .map(|mut b| {
            if [LOWRES_SAMPLES, EPIPOLAR_SAMPLES].contains(&b.resource) {
                b.resource = "output";
            }
            b
        })
        .collect()
}

/// The `_unwarp` pass `kernel` of a family kernel's sampled pass `family`: its `frame` and
/// `depth` bindings, `output` where `family` writes the samples texture, the samples
/// texture read at `binding`, `fallback_count` and `fallback_pixels` at `binding + 1` and
/// `+ 2`; one invocation per block of pixels that share their samples
/// ([`unwarp_block`] per axis: S for `lowres`, 1 for `epipolar`).
pub fn unwarp_pass(
    family: crate::plan::PassPlan,
    kernel: Kernel,
    binding: u32,
    knobs: &SamplingKnobs,
) -> crate::plan::PassPlan {
    let block = unwarp_block(knobs);
    let samples = family
        .bindings
        .iter()
        .map(|b| b.resource)
        .find(|r| [LOWRES_SAMPLES, EPIPOLAR_SAMPLES].contains(r))
        .unwrap_or(EPIPOLAR_SAMPLES);
    // The gather reads only the uniform block, the depth buffer and the samples.
    let mut bindings: Vec<_> = family_bindings(&family)
        .into_iter()
        .filter(|b| ["frame", "depth", "output"].contains(&b.resource))
        .collect();
    bindings.push(crate::plan::bind(binding, samples));
    bindings.push(crate::plan::bind(binding + 1, FALLBACK_COUNT));
    bindings.push(crate::plan::bind(binding + 2, FALLBACK_PIXELS));
    crate::plan::PassPlan {
        kernel,
        invocations: if block == 1 {
            ["screen.width".into(), "screen.height".into(), "1".into()]
        } else {
            [
                format!("ceil(screen.width / {block})"),
                format!("ceil(screen.height / {block})"),
                "1".into(),
            ]
        },
        skip_when: family.skip_when,
        indirect: None,
        bindings,
    }
}

/// Pixels per axis of the blocks the epipolar unwarp gathers: the four samples around a
/// block's centre, loaded once, stand for its pixels, each with its own weights (the centre's
/// fractions moved by their gradients, clamped to the block's samples: at most 0.71 pixel from
/// the pixel's own place), but a pixel whose own slice lies more than half a slice beyond the
/// block's (slices closer than a pixel: near an on-screen epipole, small screens) is listed for
/// the fallback. Measured at 1280x720 (docs/roofline.md, "Stop 53"; minmax, 256 slices, a
/// 1024x256 map, 6 rounds alternated): `minmax_traverse_unwarp` 19.2-19.6 -> 13.3-15.7 ms,
/// the frame's passes 33.6-42.4 -> 27.2-39.1 ms; on the 24 suite poses the mean rel L1
/// against the truth 0.5017 -> 0.5020 %, no pose worse by more than 0.029 points (spot_grate
/// ordinary), 855344 -> 880947 pixels listed in all. One invocation per pixel was the unwarp
/// before;
/// a 2 x 2 quad gathering each pixel's own taps from shared loads of three slices (14 loads
/// for four pixels instead of 32) saved nothing (13.3-14.2 ms against 13.9-14.3 even with
/// the pixels whose taps it had not loaded left wrong, 19.4-22.9 ms with them loading their
/// own: each pixel still computed its own slices, taps and selects; stop 45).
pub const EPIPOLAR_UNWARP_BLOCK: u32 = 2;

/// Pixels per axis one invocation of the `_unwarp` pass gathers: the lowres block side S (a
/// block's pixels share their four samples, loaded once: `raymarch_unwarp` at lowres 4 took
/// 6.4-7.8 ms at 1280x720 against 8.9-9.4 ms with one invocation per pixel; at lowres 2 no
/// change, stop 45), or [`EPIPOLAR_UNWARP_BLOCK`] for `epipolar`.
pub fn unwarp_block(knobs: &SamplingKnobs) -> u32 {
    match knobs.sampling {
        Sampling::Lowres => knobs.scale,
        _ => EPIPOLAR_UNWARP_BLOCK,
    }
}

/// The `_fallback` pass `kernel` of a family kernel's sampled pass `family`: the same
/// bindings with `output` where `family` writes the samples texture, and `fallback_count`
/// and `fallback_pixels` read at `binding + 1` and `+ 2`; dispatched indirectly from
/// `fallback_count` (byte [`FALLBACK_GROUPS_OFFSET`]: one invocation per listed pixel, in
/// workgroups of 8 x 8, [`FALLBACK_ROW_GROUPS`] per row), its `invocations` the most that can
/// be (every pixel listed) for an engine that dispatches directly.
pub fn fallback_pass(
    family: crate::plan::PassPlan,
    kernel: Kernel,
    binding: u32,
) -> crate::plan::PassPlan {
    let mut bindings = family_bindings(&family);
    bindings.push(crate::plan::bind(binding + 1, FALLBACK_COUNT));
    bindings.push(crate::plan::bind(binding + 2, FALLBACK_PIXELS));
    // Rows of FALLBACK_ROW_GROUPS workgroups of 8 x 8 (65536 entries each) for every pixel.
    crate::plan::PassPlan {
        kernel,
        invocations: [
            (8 * FALLBACK_ROW_GROUPS).to_string(),
            "8 * ceil(screen.width / 256) * ceil(screen.height / 256)".into(),
            "1".into(),
        ],
        skip_when: family.skip_when,
        indirect: Some(crate::plan::Indirect {
            buffer: FALLBACK_COUNT,
            offset_bytes: FALLBACK_GROUPS_OFFSET,
        }),
        bindings,
    }
}

/// The buffers of a sampled plan's fallback list (`fallback_count`, `fallback_pixels`), or
/// none for `pixels`.
pub fn fallback_buffers(knobs: &SamplingKnobs) -> Vec<crate::plan::Resource> {
    if !knobs.is_sampled() {
        return Vec::new();
    }
    let buffer = |name, contents, elements: Option<&str>, usage| crate::plan::Resource {
        kind: "storage_buffer",
        buffer: Some(crate::plan::BufferDesc {
            elements: elements.map(str::to_owned),
            usage,
        }),
        ..crate::plan::scatter_resource(name, contents)
    };
    vec![
        buffer(
            FALLBACK_COUNT,
            "sampling = lowres | epipolar: 4 u32: how many pixels the _unwarp pass listed in \
             fallback_pixels, then the _fallback pass's indirect dispatch (workgroups x, y, z \
             at byte 4) (reset by the family's samples pass, written by the _unwarp pass, \
             read by the _fallback pass; no host upload or clear; copy the first 4 bytes back \
             to report how many pixels fell back)",
            None,
            vec!["storage", "indirect", "copy_src"],
        ),
        buffer(
            FALLBACK_PIXELS,
            "sampling = lowres | epipolar: the pixels no sample stands for, packed x | y << 16, in \
             no particular order (written by the _unwarp pass, evaluated by the _fallback pass)",
            Some("screen.width * screen.height"),
            vec!["storage"],
        ),
    ]
}

/// The fallback list's count.
pub const FALLBACK_COUNT: &str = "fallback_count";
/// The fallback list's pixels.
pub const FALLBACK_PIXELS: &str = "fallback_pixels";
/// The byte offset of the `_fallback` pass's indirect dispatch arguments in `fallback_count`
/// (after the list's count).
pub const FALLBACK_GROUPS_OFFSET: u64 = 4;
/// Workgroups (of 8 x 8 invocations) per row of the `_fallback` pass's indirect dispatch: the
/// unwarp that lists entry `e` raises the dispatch to cover workgroup `e / 64` (x up to this,
/// then rows), so 1024 x 65535 workgroups cover any screen.
///
/// One invocation per listed pixel, not a fixed grid each taking every N-th entry: a fixed
/// grid either runs the family's body once per idle 8-lane batch (llvmpipe runs a loop's
/// body under an empty mask; one invocation per 8 x 8 pixels cost `minmax_traverse_fallback`
/// 2.5 ms on `sphere` with a few hundred pixels listed, stop 46) or, kept small (one per
/// 32 x 32 pixels until stop 53), gives an invocation hundreds of pixels where many are
/// listed, past llvmpipe's 65535 loop trips per invocation (`lp_exec_endloop`: every loop of
/// the inlined shader then exits): minmax's pass at 320x180 with every pixel listed wrote a
/// quarter of them (stop 52, docs/roofline.md).
pub const FALLBACK_ROW_GROUPS: u32 = 1024;

/// Invocations (one workgroup) per slice of the epipolar samples pass: one 8-lane batch of
/// llvmpipe's (256-bit vectors). llvmpipe runs a loop's body at least once for every 8-lane
/// batch, under an empty mask where the batch has nothing to do, and the pass has two
/// evaluation loops, the second usually empty; with one batch per slice no batch idles
/// through them, and the loops over a slice's samples take as many batch trips as with
/// more lanes. Measured (stop 44, `bench --headline-only --knobs ..-ep512`, 1280x720,
/// binaries alternated, medians over 12 runs), the samples pass at 8 / 16 / 32 lanes:
/// raymarch n64 10.6 / 10.6 / 11.4 ms, prefiltered m32-r4 6.3-6.6 / 7.1-7.3 / 8.2-8.6,
/// minmax 7.2 / 6.8 / 8.1, hybrid_volume n32 5.9 / 6.6 / 7.8; at 64 the raymarch pass took
/// 16-19 ms. (`pst_sweep` keeps its own 32, `partial_sum_tree::SWEEP_LANES`: its sweep
/// spreads a slice's columns and tree steps over the lanes.)
pub const SLICE_LANES: u32 = 8;

/// The lowres samples texture.
pub const LOWRES_SAMPLES: &str = "lowres_samples";
/// The epipolar samples texture.
pub const EPIPOLAR_SAMPLES: &str = "epipolar_samples";

/// Format of the samples textures (`lowres_samples`, `epipolar_samples`).
pub const SAMPLES_FORMAT: &str = "rgba32float";

/// Format of `epipolar_samples` (the samples textures' format).
pub const EPIPOLAR_SAMPLES_FORMAT: &str = SAMPLES_FORMAT;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_round_trip() {
        assert_eq!(wgsl_f32(0.05), "0.05");
        assert_eq!(wgsl_f32(1.0), "1.0");
        assert_eq!(wgsl_f32(0.5), "0.5");
    }

    #[test]
    fn every_family_builds_lowres_and_epipolar() {
        use crate::family::KernelFamily;
        let long = SamplingKnobs {
            slice_samples: 512,
            step: 1,
            ..SamplingKnobs::epipolar(1024)
        };
        for k in [
            SamplingKnobs::lowres(2),
            SamplingKnobs::lowres(4),
            SamplingKnobs::epipolar(64),
            long,
        ] {
            for light in [
                crate::prefiltered::LightKind::Directional,
                crate::prefiltered::LightKind::Spot,
            ] {
                let variants: [crate::family::FamilyVariant; 3] = [
                    crate::prefiltered::PrefilteredVariant {
                        light,
                        ..Default::default()
                    }
                    .into(),
                    crate::raymarch::RaymarchVariant {
                        light,
                        ..Default::default()
                    }
                    .into(),
                    crate::minmax::MinmaxVariant {
                        light,
                        ..Default::default()
                    }
                    .into(),
                ];
                for v in variants {
                    for params in v.with_sampling(k).kernel_params() {
                        crate::build(&params).unwrap_or_else(|e| panic!("{e}"));
                    }
                }
            }
        }
    }
}
