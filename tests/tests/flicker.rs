//! Temporal stability (issue 6): every suite scene along a 60-frame camera path and a
//! 60-frame light rotation (`scatter_reference::paths`), each frame rendered by every family
//! on the GPU through passes created once (as an engine keeps them), compared with the
//! `shadow_map` truth of that frame. The flicker metric (`scatter_reference::metrics::flicker`)
//! is the mean absolute frame-to-frame change of the error image over the truth's mean.
//!
//! Asserted (the test's name says it): 0 NaN/Inf in every frame; the prefiltered default
//! (M = 32, R = 3) flickers no more than `raymarch` at equal GPU time, except on the
//! sequences listed in `EXCEPTIONS`, where it flickers more and is held under a ceiling. "Equal time" comes from the bench
//! (`cargo run --release -p scatter-examples --example bench`): at the headline
//! configuration (1280x720, 1024^2 rectified map) raymarch N = 64 took 0.68-0.93x the
//! prefiltered default's time and N = 128 1.36-1.94x over two runs on this machine's
//! lavapipe (docs/bench/bench.md), so the equal-time N lies between them. The test compares
//! with N = 64, the cheaper side, and reports minmax too (and N = 32, 128 and 256, context
//! only, with `SCATTER_FULL=1`).
//!
//! Prefiltered flickers less than raymarch N = 64 on `sphere`, `columns`, `foliage`,
//! `spot_grate` (spot: 0.48 against 0.90 %; 2.59 % before raymarch's spot samples became
//! equiangular) and on `window`'s light rotation (3.7 against 4.2 %; with the region depth
//! bounds: 4.9 % before them), more on `terrain` and `window`'s camera path: those three
//! sequences are listed in `EXCEPTIONS` at their measured value plus about 10 %, with the
//! reason. Against N = 128 it flickers less on `foliage`'s camera path (0.19 against 0.20 %)
//! and on `spot_grate` (0.48 against 0.70 %).
//!
//! Two sampled variants (issue 14, raymarch N = 64) are reported and NaN-checked:
//! `sampling = lowres` at scale 4, whose samples stand on fixed pixels, so that what moves
//! is the scene under them, and `sampling = epipolar` (64 x 64, step 8), whose samples move
//! with the epipole. The partial-sum-tree family (issue 15; epipolar samples only, 64 x 64,
//! every sample answered) is reported and NaN-checked too, and so is the hybrid_volume
//! default (issue 16).
//!
//! 64x36 pixels, 256x256 rectified map, 512^2 shadow map, truth with 512 cells per ray:
//! small enough for CI (75 s here in the test profile with a warm Mesa cache).
//! With `SCATTER_FULL=1` the prefiltered and minmax defaults are reported sampled too (lowres
//! 4 and epipolar 64 x 64, NaN-checked; issue 14's flicker rows for its three families).
//! `SCATTER_FLICKER_SCENE=foliage` runs one scene. `cargo test --release -p
//! scatter-conformance --test flicker -- --nocapture` prints the table of the closing note.

use scatter_conformance::gpu;
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::metrics;
use scatter_reference::paths::{self, Path};
use scatter_reference::scene::Scene;
use scatter_reference::suite::SceneName;
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_runtime::prefiltered::Inputs;
use scatter_runtime::shaderlib::Kernel;
use scatter_runtime::textures::{read_rgba16float, upload_r32float};
use scatter_runtime::{Context, FamilyPasses, FrameInput};
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::hybrid_volume::HybridVolumeVariant;
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::partial_sum_tree::PartialSumTreeVariant;
use scatter_shaderlib::prefiltered::{FrameSettings, LightKind, PrefilteredVariant, Resolutions};
use scatter_shaderlib::raymarch::RaymarchVariant;
use scatter_shaderlib::sampling::SamplingKnobs;

const SCREEN: [u32; 2] = [64, 36];
const RECTIFIED: [u32; 2] = [256, 256];
const SHADOW_MAP: u32 = 512;
const FRAMES: usize = 60;
const TRUTH_SEGMENTS: usize = 512;
/// Raymarch samples at equal GPU time with the prefiltered default (see the module docs).
const EQUAL_TIME_SAMPLES: u32 = 64;
/// (scene/path, ceiling in %, why): sequences where the prefiltered default flickers more
/// than raymarch N = 64, held at their measured value plus about 10 %. Each fails the test
/// once it is no longer needed.
const EXCEPTIONS: &[(&str, f64, &str)] = &[
    ("terrain/camera_path", 0.032, SMOOTH),
    ("terrain/light_rotation", 0.092, SMOOTH),
    (
        "window/camera_path",
        5.6,
        "ringing where the depth bounds leave a region ambiguous, and reference-ray weighting: \
         mean error 5.4 % against raymarch's 4.4 % (19.7 % before the bounds); it moves with \
         the casters",
    ),
];

/// Why the smooth scenes are exceptions.
const SMOOTH: &str = "terrain: one clean shadow volume, where a 64-sample march is within \
    0.05 % and the prefiltered error (Fourier truncation, rgba8unorm steps) 0.06-0.08 %; both \
    flicker at the level of their small errors (0.03-0.08 %)";

/// The block side of the sampled variants reported (`sampling = lowres`).
const SAMPLED_SCALE: u32 = 4;

/// Raymarch sample counts reported with `SCATTER_FULL=1`; CI runs the equal-time one
/// only ([`samples`]).
const SAMPLES: [u32; 4] = [32, 64, 128, 256];

/// The raymarch sample counts this run reports: [`EQUAL_TIME_SAMPLES`] (the one asserted
/// against), and with `SCATTER_FULL=1` every [`SAMPLES`]: the other three are context for
/// the table, not asserted (leaving them out saved no measurable time with a cold Mesa cache,
/// 694 s against 713 s for the file; the passes created per scene were that cost, below).
fn samples() -> Vec<u32> {
    if full() {
        SAMPLES.to_vec()
    } else {
        vec![EQUAL_TIME_SAMPLES]
    }
}

/// Whether `SCATTER_FULL=1` asks for the context columns too: raymarch at every
/// [`SAMPLES`], and the prefiltered and minmax defaults sampled (lowres at
/// [`SAMPLED_SCALE`] and [`epipolar_knobs`]; issue 14's flicker rows for each of its three
/// families, reported and NaN-checked; each sampled column costs CI a minute or two of
/// shader compilation with a cold Mesa cache, so CI runs raymarch's only).
fn full() -> bool {
    std::env::var("SCATTER_FULL").is_ok_and(|v| v == "1")
}

/// The variants reported, in column order: the prefiltered default, the moment basis (6
/// moments, 8 regions; reported, its frames checked for NaN/Inf), raymarch at every
/// [`samples`], minmax, then raymarch N = 64 with `sampling = lowres` at [`SAMPLED_SCALE`].
fn variants(light: LightKind) -> Vec<FamilyVariant> {
    let mut v = vec![
        FamilyVariant::Prefiltered(PrefilteredVariant {
            light,
            ..PrefilteredVariant::default()
        }),
        FamilyVariant::Prefiltered(PrefilteredVariant {
            light,
            regions: 8,
            ..PrefilteredVariant::with_moments(6)
        }),
    ];
    v.extend(samples().into_iter().map(|samples| {
        FamilyVariant::Raymarch(RaymarchVariant {
            samples,
            light,
            ..RaymarchVariant::default()
        })
    }));
    v.push(FamilyVariant::Minmax(MinmaxVariant {
        light,
        ..MinmaxVariant::default()
    }));
    // Issue 14: raymarch N = 64 at a quarter of the screen per axis (reported, NaN checked):
    // samples stay on fixed pixels, so the flicker of the upsample shows here. One family
    // only: the sampling stage is the same code in every family, and each column costs this
    // test a minute of shader compilation with a cold Mesa cache (the three families
    // measured 1.07-1.96x their per-pixel flicker, issue 14's note).
    let n64 = FamilyVariant::Raymarch(RaymarchVariant {
        samples: EQUAL_TIME_SAMPLES,
        light,
        ..RaymarchVariant::default()
    });
    v.push(n64.with_sampling(SamplingKnobs::lowres(SAMPLED_SCALE)));
    // And epipolar (64 slices x 64 samples, step 8, at this screen): its samples move with
    // the epipole, so a camera or light that moves moves them (Yusov 2013's flicker).
    v.push(n64.with_sampling(epipolar_knobs()));
    // Issue 15: the partial-sum-tree family (epipolar samples only) at the same layout,
    // every sample answered (reported, NaN checked).
    v.push(FamilyVariant::PartialSumTree(
        PartialSumTreeVariant {
            light,
            ..PartialSumTreeVariant::default()
        }
        .with_sampling_knobs(SamplingKnobs {
            step: 1,
            ..epipolar_knobs()
        }),
    ));
    // Issue 16: hybrid shadow volumes at their defaults (reported, NaN checked): the
    // interval follows the rectified map, which moves with the camera and the light.
    v.push(FamilyVariant::HybridVolume(HybridVolumeVariant {
        light,
        ..HybridVolumeVariant::default()
    }));
    if full() {
        // Issue 13: the moment basis's most accurate configuration (16 regions of 16
        // columns on this map; reported, NaN checked).
        v.push(FamilyVariant::Prefiltered(PrefilteredVariant {
            light,
            regions: 16,
            ..PrefilteredVariant::with_moments(6)
        }));
        let prefiltered = FamilyVariant::Prefiltered(PrefilteredVariant {
            light,
            ..PrefilteredVariant::default()
        });
        let minmax = FamilyVariant::Minmax(MinmaxVariant {
            light,
            ..MinmaxVariant::default()
        });
        for base in [prefiltered, minmax] {
            v.push(base.with_sampling(SamplingKnobs::lowres(SAMPLED_SCALE)));
            v.push(base.with_sampling(epipolar_knobs()));
        }
    }
    v
}

/// The epipolar configuration reported: 64 slices x 64 samples, step 8 (at 64x36 pixels
/// the defaults would place more samples than pixels).
fn epipolar_knobs() -> SamplingKnobs {
    SamplingKnobs {
        slice_samples: 64,
        step: 8,
        ..SamplingKnobs::epipolar(64)
    }
}

fn labels() -> Vec<String> {
    let mut l = vec![
        "prefiltered m32-r4".to_owned(),
        "prefiltered moments6-r8".to_owned(),
    ];
    l.extend(samples().iter().map(|n| format!("raymarch n{n}")));
    l.push("minmax".into());
    l.push(format!("raymarch n64-lr{SAMPLED_SCALE}"));
    l.push("raymarch n64-ep64x64".into());
    l.push("partial_sum_tree r4-ep64x64".into());
    l.push("hybrid_volume n32".into());
    if full() {
        l.push("prefiltered moments6-r16".into());
        for base in ["prefiltered m32-r4", "minmax"] {
            l.push(format!("{base}-lr{SAMPLED_SCALE}"));
            l.push(format!("{base}-ep64x64"));
        }
    }
    l
}

/// `labels()` names `variants()` column by column: a column added to one and not the other
/// would index past the table (it did, stop 31's CI); checked without a GPU.
#[test]
fn every_variant_has_a_label() {
    for light in [LightKind::Directional, LightKind::Spot] {
        assert_eq!(
            variants(light).len(),
            labels().len(),
            "flicker: variants({light:?}) and labels() list different numbers of columns"
        );
    }
}

/// The passes of every reported variant for one light kind (created once, as an engine keeps
/// them).
fn passes(ctx: &Context, light: LightKind) -> Vec<FamilyPasses> {
    let res = Resolutions {
        screen: SCREEN,
        rectified: RECTIFIED,
    };
    variants(light)
        .iter()
        .map(|v| FamilyPasses::new(ctx, v, res, SHADOW_MAP).unwrap_or_else(|e| panic!("{v}: {e}")))
        .collect()
}

/// Every variant's output for one frame, in `labels()` order.
fn render(
    ctx: &Context,
    passes: &mut [FamilyPasses],
    scene: &Scene,
    gbuf: &GBuffer,
    sm: &ShadowMap,
) -> Vec<Image> {
    let depth = upload_r32float(
        ctx,
        Kernel::Scatter,
        "flicker depth",
        SCREEN,
        &gbuf.view_depth,
    )
    .expect("depth upload");
    let shadow = upload_r32float(
        ctx,
        Kernel::Rectify,
        "flicker shadow map",
        [SHADOW_MAP; 2],
        &sm.depth,
    )
    .expect("shadow-map upload");
    let (dv, sv) = (
        depth.create_view(&Default::default()),
        shadow.create_view(&Default::default()),
    );
    let input = FrameInput {
        camera: scene.camera_desc(),
        light: scene.light_desc(),
        medium: scene.medium_desc(),
        shadow_map: sm.desc(),
        settings: FrameSettings::for_screen(SCREEN[0], SCREEN[1]),
    };
    let inputs = Inputs {
        depth: &dv,
        shadow_map: Some(&sv),
        rectified: None,
        vpl_maps: None,
    };
    passes
        .iter_mut()
        .map(|pass| {
            let v = pass.variant();
            pass.prepare(ctx, &input)
                .unwrap_or_else(|e| panic!("{v}: prepare: {e}"));
            let mut encoder = ctx.device().create_command_encoder(&Default::default());
            pass.encode(ctx, &mut encoder, &inputs)
                .unwrap_or_else(|e| panic!("{v}: encode: {e}"));
            ctx.queue().submit([encoder.finish()]);
            let data = read_rgba16float(ctx, Kernel::Scatter, pass.output_texture())
                .unwrap_or_else(|e| panic!("{v}: readback: {e}"));
            Image::from_pixels(
                SCREEN[0],
                SCREEN[1],
                data.iter().map(|c| [c[0], c[1], c[2]]).collect(),
            )
        })
        .collect()
}

#[test]
fn frames_are_finite_and_prefiltered_flicker_is_within_raymarch_or_its_listed_ceiling() {
    let Some(ctx) = gpu() else {
        return;
    };
    let labels = labels();
    let equal = labels
        .iter()
        .position(|l| *l == format!("raymarch n{EQUAL_TIME_SAMPLES}"))
        .expect("equal-time N is reported");
    let mut failures = Vec::new();
    let mut table = vec![
        format!("| scene | path | {} |", labels.join(" | ")),
        format!("|---|---|{}", "---|".repeat(labels.len())),
    ];
    let mut errors_table = table.clone();
    let only = std::env::var("SCATTER_FLICKER_SCENE").ok();
    // One set of passes per light kind for every scene, as an engine keeps them. With a cold
    // Mesa cache, passes created anew per scene cost this file 713 s against 480 s now (about
    // 60 s warm; same outputs, 2026-12-03): llvmpipe compiled kernels again for new passes.
    let mut sun_passes: Option<Vec<FamilyPasses>> = None;
    let mut spot_passes: Option<Vec<FamilyPasses>> = None;
    for &name in SceneName::ALL
        .iter()
        .filter(|n| only.as_deref().is_none_or(|o| o == n.name()))
    {
        let light = if name == SceneName::SpotGrate {
            LightKind::Spot
        } else {
            LightKind::Directional
        };
        let slot = if light == LightKind::Spot {
            &mut spot_passes
        } else {
            &mut sun_passes
        };
        let passes = slot.get_or_insert_with(|| passes(ctx, light));
        for path in Path::ALL {
            let mut outputs: Vec<Vec<Image>> = vec![Vec::new(); labels.len()];
            let mut truths = Vec::new();
            for f in 0..FRAMES {
                let scene = paths::frame(name, path, f, FRAMES, SCREEN[0], SCREEN[1]);
                let bvh = Bvh::build(&scene.geometry);
                let gbuf = GBuffer::cast(&scene, &bvh);
                let sm = ShadowMap::build(&scene, &bvh, SHADOW_MAP).expect("shadow map");
                truths.push(truth::render(
                    &scene,
                    &gbuf,
                    &Visibility::ShadowMap(&sm),
                    &TruthSettings {
                        segments: TRUTH_SEGMENTS,
                        ..TruthSettings::default()
                    },
                    &|| (),
                ));
                for (i, image) in render(ctx, passes, &scene, &gbuf, &sm)
                    .into_iter()
                    .enumerate()
                {
                    outputs[i].push(image);
                }
            }
            let mut flicker = Vec::new();
            let mut mean_error = Vec::new();
            for (label, frames) in labels.iter().zip(&outputs) {
                let nan: usize = frames.iter().map(metrics::non_finite_count).sum();
                if nan > 0 {
                    failures.push(format!(
                        "flicker::{label}::{name}::{path}: {nan} NaN/Inf pixels"
                    ));
                }
                flicker.push(metrics::flicker(frames, &truths).expect("sequences"));
                mean_error.push(
                    frames
                        .iter()
                        .zip(&truths)
                        .map(|(a, t)| metrics::rel_l1(a, t).expect("same size"))
                        .sum::<f64>()
                        / FRAMES as f64,
                );
            }
            let key = format!("{name}/{path}");
            match EXCEPTIONS.iter().find(|e| e.0 == key) {
                None if !within(flicker[0], flicker[equal]) => failures.push(format!(
                    "flicker::{key}: prefiltered flickers {:.4} %, raymarch n{EQUAL_TIME_SAMPLES} (equal time) {:.4} %",
                    100.0 * flicker[0],
                    100.0 * flicker[equal]
                )),
                None => {}
                Some(_) if flicker[0] <= flicker[equal] => failures.push(format!(
                    "flicker::{key}: prefiltered now flickers no more than raymarch n{EQUAL_TIME_SAMPLES} ({:.4} <= {:.4} %): remove it from EXCEPTIONS",
                    100.0 * flicker[0],
                    100.0 * flicker[equal]
                )),
                Some(e) if !within(flicker[0], e.1 / 100.0) => failures.push(format!(
                    "flicker::{key}: prefiltered flickers {:.4} %, above its listed ceiling {} % ({})",
                    100.0 * flicker[0],
                    e.1,
                    e.2
                )),
                Some(_) => {}
            }
            eprintln!("flicker::{key}: done");
            let fmt = |v: &[f64]| {
                v.iter()
                    .map(|x| format!("{:.3} %", 100.0 * x))
                    .collect::<Vec<_>>()
                    .join(" | ")
            };
            table.push(format!("| {name} | {path} | {} |", fmt(&flicker)));
            errors_table.push(format!("| {name} | {path} | {} |", fmt(&mean_error)));
        }
    }
    println!(
        "flicker ({FRAMES} frames, {}x{}, rectified {}x{}, shadow map {SHADOW_MAP}^2), mean |e_t - e_t-1| / mean truth:",
        SCREEN[0], SCREEN[1], RECTIFIED[0], RECTIFIED[1]
    );
    for line in &table {
        println!("{line}");
    }
    println!("mean rel L1 over the frames:");
    for line in &errors_table {
        println!("{line}");
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `value <= bound`, false when either is NaN (a NaN result must fail, not pass).
fn within(value: f64, bound: f64) -> bool {
    value <= bound
}
