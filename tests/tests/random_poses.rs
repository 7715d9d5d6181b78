//! The random-pose suite (issue 12): every family, both visibility modes of the prefiltered
//! method, on seeded random camera and light poses of every suite scene
//! (`scatter_reference::random_poses`: eye inside and outside the scene's bounds, looking
//! toward, across and away from the light, the sun from below the horizon to the zenith,
//! spot lamps on and off screen with the eye in and out of the cone), on the GPU (lavapipe
//! in CI; the CPU mirrors when no GPU is allowed), at 96x54 with a 512^2 shadow map and a
//! 512x512 rectified map, scored against the `shadow_map` truth.
//!
//! Reported (always printed, markdown): per variant, per scene and per pose category, the
//! median / p90 / max rel L1 over the frames whose truth is not near-black, and over the
//! near-black frames (truth max <= 3 % of the scene's lit maximum: the largest truth pixel
//! of the scene's suite `ordinary` pose at the same sizes, a typical lit frame of it) the
//! largest absolute error at any pixel relative to that lit maximum.
//!
//! Asserted, one libtest trial each (`-- --list` lists them):
//! - `random::premises`: every dark pose (a closed room, the sun below the ground's
//!   horizon) has a near-black truth, and every pose's buffers build;
//! - `random::<variant>::finite`: every run succeeds, 0 NaN/Inf pixels;
//! - `random::<variant>::{p90,max,near_black}_bar`: within the variant's row of [`BARS`];
//! - `random::<variant>::p90_vs_raymarch`: p90 no worse than raymarch n64's (per-pixel
//!   variants, and `partial_sum_tree` at 128 x 128 samples, step 1: it has no per-pixel
//!   variant); `random::<variant>::p90_vs_per_pixel`: a sampled variant's (issue 14's
//!   epipolar sampling, 64 x 64 samples, step 8: raymarch; every family with
//!   `SCATTER_FULL=1`) p90 at most half a point above its family's per-pixel variant's.
//!
//! Expected failures are data ([`EXPECTED_FAILURES`]): such a trial must fail, and the run
//! fails when it starts passing.
//!
//! `cargo test -p scatter-conformance --test random_poses` prints the tables.

use std::collections::BTreeMap;
use std::process::ExitCode;
use std::sync::OnceLock;
use std::time::Instant;

use scatter_conformance::{Check, PassCache, gpu, run_trials, run_variant_cached};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::kernels::CpuFrame;
use scatter_reference::metrics;
use scatter_reference::random_poses::{self, Category, RandomPose};
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_runtime::{Context, FrameInput};
use scatter_shaderlib::family::{Family, FamilyVariant};
use scatter_shaderlib::prefiltered::{
    FrameSettings, LightKind, PrefilteredVariant, VisibilityMode,
};
use scatter_shaderlib::sampling::Sampling;

const SCREEN: [u32; 2] = [96, 54];
const RECTIFIED: [u32; 2] = [512, 512];
const SHADOW_MAP: u32 = 512;
/// Poses per suite scene (150 frames in all, as in the first measurement).
const POSES_PER_SCENE: u32 = 25;
/// A frame is near-black when its truth's largest pixel is at most this fraction of the
/// scene's lit maximum. Not lower: under a sun below the horizon the `shadow_map` truth's
/// documented bias (1.5 texels) lights the thin layer of fog next to the ground, up to 2.4 %
/// of the lit maximum (exact visibility: 0); rel L1 against that leak measures nothing.
const NEAR_BLACK: f64 = 3e-2;
/// The bar for closed rooms (`Category::ClosedRoom`: the truth is exactly 0): the
/// largest error at any pixel, relative to the scene's lit maximum, for every variant.
const CLOSED_ROOM: f64 = 1e-3;
/// Frames over this rel L1 are counted in the report.
const HIGH_ERROR: f64 = 0.05;

/// A variant's bars: `(label, p90 rel L1, max rel L1, near-black max error / lit max)`.
type Bar = (&'static str, f64, f64, f64);

/// Bars per variant (`FamilyVariant::label`): the same for every family. p90 3 %: nine random
/// frames in ten meet the bar the suite holds the sun's poses to; max 7 %: no frame far off
/// (the suite's spot bar plus the lamp rows' margin); near-black 3e-2: a frame the truth
/// calls dark ([`NEAR_BLACK`]) comes out dark by the same measure. Where a variant misses
/// one, the trial is in [`EXPECTED_FAILURES`] with what it measures and why.
///
/// Measured after the fixes of issue 12, `slice_fit`, the occluder depth range and `scatter`
/// reading each row at its own column (lavapipe, 96x54, `DEFAULT_SEED`; before issue 12 in
/// parentheses): minmax p90 1.08 % (1.38), max 5.83 % (6.77), near-black 0.0216 (0.120);
/// prefiltered-m32-r3 (the default until stop 35) 2.27 % (3.73), 6.48 % (27.5), 0.0590
/// (0.616), and with 4 regions, the default since, 1.66 %, 5.94 %, 0.0438; average at 3
/// regions 5.41 % (14.4), 14.7 % (110), 0.0864 (0.617), at 4 3.51 %, 11.8 %, 0.0755;
/// raymarch-n64-i1 2.08 % (2.98), 4.39 % (17.1), 0.0117
/// (0.0117). Closed rooms: every variant 0 (prefiltered 0.0108 and average 0.0115 before the
/// rows' own columns). The moment basis (issue 13, 6 moments, 8 regions): p90 1.64 %, max
/// 6.33 %, near-black 0.0840, closed rooms 0 (0.0256 before); with each region's depth
/// range as the moments' interval (stop 56) 1.50 %, 5.81 %, 0.0377.
const BARS: &[Bar] = &[
    ("minmax", 0.03, 0.07, NEAR_BLACK),
    ("prefiltered-m32-r4", 0.03, 0.07, NEAR_BLACK),
    ("prefiltered-m32-r4-average", 0.03, 0.07, NEAR_BLACK),
    ("prefiltered-moments6-r8", 0.03, 0.07, NEAR_BLACK),
    ("prefiltered-moments6-r16", 0.03, 0.07, NEAR_BLACK),
    ("prefiltered-m32-r4-stride4", 0.03, 0.07, NEAR_BLACK),
    ("raymarch-n64-i1", 0.03, 0.07, NEAR_BLACK),
    ("minmax-ep64x64", 0.03, 0.07, NEAR_BLACK),
    ("prefiltered-m32-r4-ep64x64", 0.03, 0.07, NEAR_BLACK),
    ("raymarch-n64-i1-ep64x64", 0.03, 0.07, NEAR_BLACK),
    ("partial_sum_tree-r4-ep128x128-s1", 0.03, 0.07, NEAR_BLACK),
    ("hybrid_volume-n32", 0.03, 0.07, NEAR_BLACK),
    ("hybrid_volume-n32-ep64x64", 0.03, 0.07, NEAR_BLACK),
];

/// The most a sampled variant's p90 may exceed its per-pixel variant's (issue 14's bar for
/// the suite mean: half a point); sampled variants are compared with their own family per
/// pixel, not with raymarch n64.
const SAMPLED_ADDED: f64 = 0.005;

/// The variant every other per-pixel variant's p90 is compared with.
const REFERENCE: &str = "raymarch-n64-i1";

/// Trials expected to fail today, with the reason: `(trial name, why)`. The run fails when
/// one of them starts passing: remove it then.
const EXPECTED_FAILURES: &[(&str, &str)] = &[
    (
        "random::partial_sum_tree-r4-ep128x128-s1::near_black_bar",
        "3.2e-2 of the lit maximum (3.5e-2 before stop 53's 2 x 2 block unwarp, 4.5e-2 before \
         stop 50's rows on the slices) on \
         random::columns::0 (the sun 13.9 deg below the horizon, \
         looking towards it), minmax's ground tie (2.2e-2 per pixel): view rays ending on the \
         ground, whose own light ray is blocked at the ray's end. The sweep's samples lie on \
         the slice's line, between pixel centres, and end on the ground at the depth their \
         2x2 pixels give; there the tie resolves lit about twice as often as at the pixels' \
         centres (largest sample 6.0e-3, the same pixels' own rays 2.8e-3); 64 x 64 samples \
         give 4.3e-2",
    ),
    (
        "random::minmax-ep64x64::p90_vs_per_pixel",
        "p90 1.78 % against minmax per pixel 1.08 % (+0.70 points; 1.58 % before stop 53's \
         2 x 2 unwarp blocks, +0.55 with slice s on a boundary between two rows, +0.64 before \
         the rows lay on the slices): minmax's exact hard shadows (foliage, the grate) are \
         what an interpolation between slices 3-5 pixels apart at the screen's edge blurs \
         most, and at 96x54 a slice's 64 samples lie 1.5-2 pixels apart, closer than a 2 x 2 \
         block is wide, so a block's pixels are clamped to its two samples along the slice; \
         its suite mean at 320x180 with the defaults is +0.10 points (sampling::accuracy)",
    ),
    (
        "random::prefiltered-m32-r4-ep64x64::p90_vs_per_pixel",
        "p90 2.22 % against prefiltered-m32-r4 per pixel 1.66 % (+0.56 points; +0.43 with 3 \
         regions at stop 49, before stop 53's 2 x 2 unwarp blocks): at 96x54 a slice's 64 \
         samples lie 1.5-2 pixels apart, closer than a block is wide, and a block's pixels \
         take its two samples along the slice (`epipolar_block_weights` clamps them); at \
         1280x720 the 24 suite poses stay within the bars (+0.136 mean, +0.523 worst, 256 \
         slices)",
    ),
    (
        "random::hybrid_volume-n32-ep64x64::p90_vs_per_pixel",
        "p90 2.09 % against hybrid_volume-n32 per pixel 1.48 % (+0.61 points; +0.46 at stop \
         49, before stop 53's 2 x 2 unwarp blocks): the same clamp along slices whose samples \
         lie closer than a block is wide",
    ),
    (
        "random::prefiltered-m32-r4-ep64x64::near_black_bar",
        "the per-pixel prefiltered-m32-r4's near-black failure (random::columns::0, the same \
         ground tie), which epipolar sampling carries over: 4.4e-2 of the lit maximum",
    ),
    (
        "random::prefiltered-m32-r4::near_black_bar",
        "4.4e-2 (3 regions: 5.9e-2) of the lit maximum on random::columns::0 (the sun 13.9 deg below the horizon, \
         looking towards it): view rays ending on the ground, whose own light ray is blocked \
         at the ray's end (a tie the truth's 1.5-texel bias lights a little, raymarch \
         1.2e-2); 32 Fourier bases blur the step over the tie (minmax, exact steps on the \
         same map, 2.2e-2)",
    ),
    (
        "random::prefiltered-m32-r4-average::p90_bar",
        "average visibility, 4 regions: p90 3.51 % (3 regions 5.41 %, 14.4 % before issue 12); \
         the prefilter weights texels by length, not transmittance (window p90 8.23 %, \
         spot_grate 7.51 %); 8 regions meet the suite's bars (prefiltered_truth)",
    ),
    (
        "random::prefiltered-m32-r4-average::max_bar",
        "average visibility, 4 regions: max 11.8 % (3 regions 14.7 %; random::window::22, the eye \
         inside looking away from the sun)",
    ),
    (
        "random::prefiltered-m32-r4-average::near_black_bar",
        "as weighted (7.6e-2 on random::columns::0): the Fourier step at the ground's tie",
    ),
    (
        "random::prefiltered-m32-r4-average::p90_vs_raymarch",
        "average visibility, p90 3.51 % against raymarch n64's 2.08 %",
    ),
    (
        "random::prefiltered-moments6-r8::near_black_bar",
        "3.8e-2 of the lit maximum on random::foliage::13 (8.4e-2 on random::columns::0 before \
         each region's own depth range; the Fourier default: 4.4e-2): the \
         ground's tie, a ray's depth equal to its own light ray's occluder depth, is an atom \
         at the ray's depth, and the midpoint of the bounds counts half of it lit",
    ),
    (
        "random::prefiltered-m32-r4-stride4::max_bar",
        "max 8.69 % (stride 1: 5.94 %) on random::foliage::2 (eye inside, looking toward the sun \
         at 35.7 deg); foliage::1 8.58 %, foliage::15 7.92 % (7.94 % at most before the bounds' \
         lookup stopped one rectified column past the ray's end, which ended the closed-room \
         light and brought p90 from 2.17 to 1.83 %)",
    ),
    (
        "random::prefiltered-m32-r4-stride4::near_black_bar",
        "4.20e-2 of the lit maximum on random::foliage::13 (sun 11.1 deg below the horizon; \
         stride 1: 4.4e-2 on columns::0)",
    ),
];

/// The families of one sun or spot light: the random poses are drawn on the suite's sun and
/// spot scenes (`area_ivsv` renders area lights only; its random-pose suite is not built).
fn single_light_families() -> impl Iterator<Item = &'static Family> {
    Family::ALL.iter().filter(|f| {
        LightKind::SINGLE
            .iter()
            .all(|&l| f.default_variant().with_light(l).validate().is_ok())
    })
}

/// The variants measured: every single-light family's default variant, and for a family
/// with a visibility knob (prefiltered) every visibility mode, the moment basis (6
/// moments with 8 regions, and with 16: its configuration that meets the suite's bars on
/// every pose at 1024x1024) and
/// the default with coarse filtered columns (`filtered_stride` 4: 128 stored columns of the
/// 512).
fn variants() -> Vec<FamilyVariant> {
    single_light_families()
        .flat_map(|f| match f.default_variant() {
            FamilyVariant::Prefiltered(v) => VisibilityMode::ALL
                .iter()
                .map(|&visibility| PrefilteredVariant { visibility, ..v }.into())
                .chain([8, 16].map(|regions| {
                    PrefilteredVariant {
                        regions,
                        ..PrefilteredVariant::with_moments(6)
                    }
                    .into()
                }))
                .chain(std::iter::once(
                    PrefilteredVariant {
                        filtered_stride: 4,
                        ..v
                    }
                    .into(),
                ))
                .collect(),
            // Epipolar samples only: 128 slices x 128 samples, every sample answered (the
            // sweep's cost is per slice and column; at 64 x 64 the slices lie 5 pixels apart
            // at the screen's edge and the unwarp spreads the ground tie of
            // random::columns::0 to 4.3e-2 of the lit maximum, against 2.2e-2 per pixel).
            FamilyVariant::PartialSumTree(v) => vec![
                v.with_sampling_knobs(scatter_shaderlib::sampling::SamplingKnobs {
                    slices: 128,
                    slice_samples: 128,
                    step: 1,
                    ..epipolar()
                })
                .into(),
            ],
            other => vec![other],
        })
        .chain(
            single_light_families()
                .filter(|f| f.default_variant().sampling().sampling == Sampling::Pixels)
                .map(|f| f.default_variant().with_sampling(epipolar()))
                .filter(|v| full() || matches!(v, FamilyVariant::Raymarch(_))),
        )
        .collect()
}

/// `SCATTER_FULL=1`: also the prefiltered and minmax epipolar rows. CI runs raymarch's only:
/// with a cold Mesa shader cache the three rows took 456 s of this test's 660 s (warm 58 s;
/// llvmpipe compiles the epipolar kernels per pose until its cache holds them), and the
/// sampling stage is one code path for every family (`sampling::accuracy` runs all three).
fn full() -> bool {
    std::env::var("SCATTER_FULL").is_ok_and(|v| v == "1")
}

/// Issue 14's epipolar sampling at this screen size: 64 slices x 64 samples, step 8 (the
/// defaults would place more samples than the 96x54 pixels).
fn epipolar() -> scatter_shaderlib::sampling::SamplingKnobs {
    scatter_shaderlib::sampling::SamplingKnobs {
        slice_samples: 64,
        step: 8,
        ..scatter_shaderlib::sampling::SamplingKnobs::epipolar(64)
    }
}

/// A pose prepared once: buffers and truth.
struct Prepared {
    pose: RandomPose,
    bvh: Bvh,
    gbuf: GBuffer,
    sm: ShadowMap,
    truth: Image,
}

impl Prepared {
    fn new(pose: RandomPose) -> Result<Prepared, String> {
        let scene = &pose.scene;
        let bvh = Bvh::build(&scene.geometry);
        let gbuf = GBuffer::cast(scene, &bvh);
        let sm = ShadowMap::build(scene, &bvh, SHADOW_MAP)
            .map_err(|e| format!("{}: shadow map: {e}", pose.name()))?;
        let truth = truth::render(
            scene,
            &gbuf,
            &Visibility::ShadowMap(&sm),
            &TruthSettings::default(),
            &|| (),
        );
        Ok(Prepared {
            pose,
            bvh,
            gbuf,
            sm,
            truth,
        })
    }

    fn light(&self) -> LightKind {
        self.pose.scene.light.kind()
    }

    fn frame_input(&self) -> FrameInput {
        let s = &self.pose.scene;
        FrameInput {
            camera: s.camera_desc(),
            light: s.light_desc(),
            medium: s.medium_desc(),
            shadow_map: self.sm.desc(),
            settings: FrameSettings::for_screen(self.gbuf.width, self.gbuf.height),
        }
    }

    /// Runs `method` (with the pose's light) on the GPU, or its CPU mirrors without one.
    fn run(
        &self,
        ctx: Option<&Context>,
        cache: &mut PassCache,
        method: &FamilyVariant,
    ) -> Result<Image, String> {
        let settings = self.frame_input().settings;
        run_variant_cached(
            ctx,
            cache,
            &method.with_light(self.light()),
            &CpuFrame {
                scene: &self.pose.scene,
                bvh: &self.bvh,
                gbuf: &self.gbuf,
                shadow_map: &self.sm,
                rectified: RECTIFIED,
                settings: &settings,
            },
        )
        .map(|(image, _)| image)
    }
}

/// One variant on one pose.
#[derive(Clone, Debug)]
struct Score {
    rel_l1: f64,
    non_finite: usize,
    /// Largest absolute error over every finite channel.
    max_abs_err: f64,
}

/// One pose: what the report needs of it.
struct Frame {
    name: String,
    scene: SceneName,
    category: Category,
    /// The generator says no light reaches any view ray.
    dark: bool,
    describe: String,
    truth_max: f64,
    /// Per variant label: the score, or why the run failed.
    scores: BTreeMap<String, Result<Score, String>>,
}

/// Everything measured, once per process.
struct Results {
    labels: Vec<String>,
    frames: Vec<Frame>,
    /// Per scene: the largest truth pixel of its suite `ordinary` pose.
    lit_max: BTreeMap<SceneName, f64>,
    /// Poses whose buffers could not be built.
    setup_failures: Vec<String>,
}

impl Results {
    fn near_black(&self, f: &Frame) -> bool {
        f.truth_max <= NEAR_BLACK * self.lit_max[&f.scene]
    }

    /// Rel L1 of `label` over the frames (not near-black) that `keep` selects.
    fn rel_l1s(&self, label: &str, keep: &dyn Fn(&Frame) -> bool) -> Vec<f64> {
        self.frames
            .iter()
            .filter(|f| keep(f) && !self.near_black(f))
            .filter_map(|f| f.scores.get(label)?.as_ref().ok().map(|s| s.rel_l1))
            .collect()
    }

    /// Largest near-black error of `label` relative to the scene's lit maximum, over the
    /// frames `keep` selects (`None` without a near-black frame).
    fn near_black_err(&self, label: &str, keep: &dyn Fn(&Frame) -> bool) -> Option<f64> {
        self.frames
            .iter()
            .filter(|f| keep(f) && self.near_black(f))
            .filter_map(|f| {
                let s = f.scores.get(label)?.as_ref().ok()?;
                Some(s.max_abs_err / self.lit_max[&f.scene])
            })
            .reduce(f64::max)
    }
}

/// Median, p90 and max (nearest rank); NaN is the largest value.
#[derive(Clone, Copy, Debug)]
struct Stats {
    n: usize,
    median: f64,
    p90: f64,
    max: f64,
}

fn stats(values: &[f64]) -> Option<Stats> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    Some(Stats {
        n: v.len(),
        median: rank(0.5),
        p90: rank(0.9),
        max: v[v.len() - 1],
    })
}

fn pct(x: f64) -> String {
    format!("{:.2}", 100.0 * x)
}

fn cell(s: Option<Stats>) -> String {
    s.map_or("-".into(), |s| {
        format!("{} / {} / {}", pct(s.median), pct(s.p90), pct(s.max))
    })
}

fn measure() -> Results {
    let start = Instant::now();
    let ctx = gpu();
    let backend = if ctx.is_some() { "GPU" } else { "CPU mirror" };
    let methods = variants();
    let labels: Vec<String> = methods.iter().map(FamilyVariant::label).collect();
    let poses = random_poses::poses(
        random_poses::DEFAULT_SEED,
        POSES_PER_SCENE,
        SCREEN[0],
        SCREEN[1],
    );
    let mut frames = Vec::new();
    let mut setup_failures = Vec::new();
    let t = Instant::now();
    let lit_max: BTreeMap<SceneName, f64> = SceneName::ALL
        .iter()
        .map(|&name| {
            let scene = suite::scene(
                name,
                Pose::Ordinary,
                MediumPreset::Default,
                SCREEN[0],
                SCREEN[1],
            );
            let bvh = Bvh::build(&scene.geometry);
            let gbuf = GBuffer::cast(&scene, &bvh);
            let sm = ShadowMap::build(&scene, &bvh, SHADOW_MAP)
                .unwrap_or_else(|e| panic!("{name}/ordinary: shadow map: {e}"));
            let truth = truth::render(
                &scene,
                &gbuf,
                &Visibility::ShadowMap(&sm),
                &TruthSettings::default(),
                &|| (),
            );
            let max = truth
                .data
                .iter()
                .flat_map(|c| c.iter().copied())
                .fold(0.0f32, f32::max);
            (name, f64::from(max))
        })
        .collect();
    let mut t_setup = t.elapsed().as_secs_f64();
    let mut t_run = vec![0.0; methods.len()];
    // Every variant's passes built once for all poses (see `PassCache`).
    let mut cache = PassCache::default();
    for pose in poses {
        let t = Instant::now();
        let name = pose.name();
        let p = match Prepared::new(pose) {
            Ok(p) => p,
            Err(e) => {
                setup_failures.push(e);
                continue;
            }
        };
        t_setup += t.elapsed().as_secs_f64();
        let truth_max = p
            .truth
            .data
            .iter()
            .flat_map(|c| c.iter().copied())
            .fold(0.0f32, f32::max);
        let mut scores = BTreeMap::new();
        for (i, (method, label)) in methods.iter().zip(&labels).enumerate() {
            let t = Instant::now();
            let score = p.run(ctx, &mut cache, method).and_then(|image| {
                let e = metrics::compare(&image, &p.truth).map_err(|e| e.to_string())?;
                let max_abs_err = image
                    .data
                    .iter()
                    .zip(&p.truth.data)
                    .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| f64::from(x - y).abs()))
                    .filter(|d| d.is_finite())
                    .fold(0.0, f64::max);
                Ok(Score {
                    rel_l1: e.rel_l1,
                    non_finite: e.non_finite,
                    max_abs_err,
                })
            });
            t_run[i] += t.elapsed().as_secs_f64();
            scores.insert(label.clone(), score);
        }
        frames.push(Frame {
            name,
            scene: p.pose.scene_name,
            category: p.pose.category,
            dark: p.pose.dark,
            describe: p.pose.describe(),
            truth_max: f64::from(truth_max),
            scores,
        });
    }
    let results = Results {
        labels,
        frames,
        lit_max,
        setup_failures,
    };
    report(&results, backend);
    println!(
        "\nwall time: {:.1} s (buffers and truths {t_setup:.1} s; {})",
        start.elapsed().as_secs_f64(),
        results
            .labels
            .iter()
            .zip(&t_run)
            .map(|(l, t)| format!("{l} {t:.1} s"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    results
}

/// Prints the markdown report.
fn report(r: &Results, backend: &str) {
    let all = |_: &Frame| true;
    let header = |first: &str| {
        println!("| {first} | {} |", r.labels.join(" | "));
        println!("|---|{}", "---|".repeat(r.labels.len()));
    };
    println!(
        "\n## Random poses ({backend}, {}x{}, shadow map {SHADOW_MAP}^2, rectified {}x{}, \
         seed {:#x}, {} frames)\n",
        SCREEN[0],
        SCREEN[1],
        RECTIFIED[0],
        RECTIFIED[1],
        random_poses::DEFAULT_SEED,
        r.frames.len()
    );
    let dark: Vec<&Frame> = r.frames.iter().filter(|f| r.near_black(f)).collect();
    println!(
        "rel L1 vs the `shadow_map` truth in %, median / p90 / max over the {} frames whose \
         truth is not near-black; near-black: {} frames (truth max <= {NEAR_BLACK:e} of the \
         scene's lit maximum), max |error| at any pixel / the scene's lit maximum.\n",
        r.frames.len() - dark.len(),
        dark.len()
    );
    println!(
        "| variant | frames | median % | p90 % | max % | frames > {:.0} % | near-black frames | near-black max err / lit max | NaN/Inf px | failed runs |",
        100.0 * HIGH_ERROR
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for l in &r.labels {
        let v = r.rel_l1s(l, &all);
        let s = stats(&v);
        let over = v.iter().filter(|&&x| !within(x, HIGH_ERROR)).count();
        let nan: usize = r
            .frames
            .iter()
            .filter_map(|f| f.scores[l].as_ref().ok())
            .map(|s| s.non_finite)
            .sum();
        let failed = r.frames.iter().filter(|f| f.scores[l].is_err()).count();
        println!(
            "| {l} | {} | {} | {} | {} | {over} | {} | {} | {nan} | {failed} |",
            s.map_or(0, |s| s.n),
            s.map_or("-".into(), |s| pct(s.median)),
            s.map_or("-".into(), |s| pct(s.p90)),
            s.map_or("-".into(), |s| pct(s.max)),
            dark.len(),
            r.near_black_err(l, &all)
                .map_or("-".into(), |e| format!("{e:.2e}"))
        );
    }
    println!("\n### Per scene (median / p90 / max %, frames not near-black)\n");
    header("scene (frames, near-black, lit max)");
    for (&scene, &lit) in &r.lit_max {
        let n = r.frames.iter().filter(|f| f.scene == scene).count();
        let nb = dark.iter().filter(|f| f.scene == scene).count();
        let keep = |f: &Frame| f.scene == scene;
        let cells: Vec<String> = r
            .labels
            .iter()
            .map(|l| cell(stats(&r.rel_l1s(l, &keep))))
            .collect();
        println!("| {scene} ({n}, {nb}, {lit:.3e}) | {} |", cells.join(" | "));
    }
    println!("\n### Per pose category (median / p90 / max %, frames not near-black)\n");
    header("category (frames, near-black)");
    for &c in Category::ALL {
        let n = r.frames.iter().filter(|f| f.category == c).count();
        if n == 0 {
            continue;
        }
        let nb = dark.iter().filter(|f| f.category == c).count();
        let keep = |f: &Frame| f.category == c;
        let cells: Vec<String> = r
            .labels
            .iter()
            .map(|l| cell(stats(&r.rel_l1s(l, &keep))))
            .collect();
        println!("| {c} ({n}, {nb}) | {} |", cells.join(" | "));
    }
    println!("\n### Near-black frames: max |error| / the scene's lit maximum\n");
    header("scene / category (near-black frames)");
    let mut groups: BTreeMap<(SceneName, Category), usize> = BTreeMap::new();
    for f in &dark {
        *groups.entry((f.scene, f.category)).or_default() += 1;
    }
    for (&(scene, c), &n) in &groups {
        let keep = |f: &Frame| f.scene == scene && f.category == c;
        let cells: Vec<String> = r
            .labels
            .iter()
            .map(|l| {
                r.near_black_err(l, &keep)
                    .map_or("-".into(), |e| format!("{e:.2e}"))
            })
            .collect();
        println!("| {scene} / {c} ({n}) | {} |", cells.join(" | "));
    }
    println!("\n### Pose categories per scene\n");
    println!(
        "| scene | {} |",
        Category::ALL
            .iter()
            .map(|c| c.name())
            .collect::<Vec<_>>()
            .join(" | ")
    );
    println!("|---|{}", "---|".repeat(Category::ALL.len()));
    for &scene in SceneName::ALL {
        let counts: Vec<String> = Category::ALL
            .iter()
            .map(|&c| {
                r.frames
                    .iter()
                    .filter(|f| f.scene == scene && f.category == c)
                    .count()
                    .to_string()
            })
            .collect();
        println!("| {scene} | {} |", counts.join(" | "));
    }
    println!("\n### Worst frames per variant (rel L1, frames not near-black)\n");
    for l in &r.labels {
        let mut v: Vec<(&Frame, f64)> = r
            .frames
            .iter()
            .filter(|f| !r.near_black(f))
            .filter_map(|f| Some((f, f.scores[l].as_ref().ok()?.rel_l1)))
            .collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1));
        let worst: Vec<String> = v
            .iter()
            .take(5)
            .map(|(f, e)| format!("{} {} % ({})", f.name, pct(*e), f.describe))
            .collect();
        println!("- {l}: {}", worst.join("; "));
    }
    println!("\n### Worst near-black frames per variant (max |error| / the scene's lit maximum)\n");
    for l in &r.labels {
        let mut v: Vec<(&Frame, f64)> = r
            .frames
            .iter()
            .filter(|f| r.near_black(f))
            .filter_map(|f| {
                let s = f.scores[l].as_ref().ok()?;
                Some((f, s.max_abs_err / r.lit_max[&f.scene]))
            })
            .collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1));
        let worst: Vec<String> = v
            .iter()
            .take(3)
            .map(|(f, e)| format!("{} {e:.2e} ({})", f.name, f.describe))
            .collect();
        println!("- {l}: {}", worst.join("; "));
    }
    for e in &r.setup_failures {
        println!("- setup failed: {e}");
    }
}

fn results() -> &'static Results {
    static RESULTS: OnceLock<Results> = OnceLock::new();
    RESULTS.get_or_init(measure)
}

fn bar(label: &str) -> Result<&'static Bar, String> {
    BARS.iter()
        .find(|b| b.0 == label)
        .ok_or_else(|| format!("random::{label}: no row in BARS: add one"))
}

fn check(f: impl FnOnce() -> Result<(), String> + Send + 'static) -> Check {
    Box::new(f)
}

/// `value <= bound`, false when either is NaN.
fn within(value: f64, bound: f64) -> bool {
    value <= bound
}

fn main() -> ExitCode {
    let labels: Vec<String> = variants().iter().map(FamilyVariant::label).collect();
    // Each sampled variant's per-pixel variant (issue 14's bars are against it).
    // A sampled variant's per-pixel variant, where its family has one (not
    // `partial_sum_tree`, which is compared with raymarch n64 instead).
    let per_pixel: Vec<Option<String>> = variants()
        .iter()
        .map(|v| {
            let pixels = v.with_sampling(Default::default());
            (v.sampling().is_sampled() && pixels.validate().is_ok()).then(|| pixels.label())
        })
        .collect();
    let mut trials: Vec<(String, Check)> = Vec::new();
    trials.push((
        "random::premises".into(),
        check(|| {
            let r = results();
            let mut bad: Vec<String> = r.setup_failures.clone();
            for f in &r.frames {
                if f.dark && !r.near_black(f) {
                    bad.push(format!(
                        "{} ({}): the truth reaches {:.3e} = {:.2e} of the scene's lit maximum, \
                         not near-black",
                        f.name,
                        f.describe,
                        f.truth_max,
                        f.truth_max / r.lit_max[&f.scene]
                    ));
                }
            }
            if bad.is_empty() {
                Ok(())
            } else {
                Err(bad.join("\n"))
            }
        }),
    ));
    trials.push((
        "random::bars_name_variants".into(),
        check({
            let labels = labels.clone();
            move || {
                // Rows of variants left out without SCATTER_FULL are not stale.
                let optional: Vec<String> = single_light_families()
                    .map(|f| f.default_variant().with_sampling(epipolar()).label())
                    .collect();
                let stale: Vec<&str> = BARS
                    .iter()
                    .map(|b| b.0)
                    .filter(|b| !labels.iter().any(|l| l == b) && !optional.iter().any(|l| l == b))
                    .collect();
                if stale.is_empty() {
                    Ok(())
                } else {
                    Err(format!("BARS rows name no measured variant: {stale:?}"))
                }
            }
        }),
    ));
    for (index, label) in labels.iter().enumerate() {
        let l = label.clone();
        trials.push((
            format!("random::{label}::finite"),
            check(move || {
                let r = results();
                let mut bad = Vec::new();
                for f in &r.frames {
                    match &f.scores[&l] {
                        Err(e) => bad.push(format!("{}: run failed: {e}", f.name)),
                        Ok(s) if s.non_finite > 0 => {
                            bad.push(format!("{}: {} NaN/Inf pixels", f.name, s.non_finite));
                        }
                        Ok(_) => {}
                    }
                }
                if bad.is_empty() {
                    Ok(())
                } else {
                    Err(format!("random::{l}:\n{}", bad.join("\n")))
                }
            }),
        ));
        type Pick = fn(&Bar) -> f64;
        let kinds: [(&str, Pick); 3] = [
            ("p90_bar", |b| b.1),
            ("max_bar", |b| b.2),
            ("near_black_bar", |b| b.3),
        ];
        for (kind, pick) in kinds {
            let l = label.clone();
            trials.push((
                format!("random::{label}::{kind}"),
                check(move || {
                    let r = results();
                    let bound = pick(bar(&l)?);
                    let all = |_: &Frame| true;
                    let value = match kind {
                        "near_black_bar" => r.near_black_err(&l, &all).unwrap_or(0.0),
                        _ => {
                            let s = stats(&r.rel_l1s(&l, &all))
                                .ok_or_else(|| format!("random::{l}: no lit frame scored"))?;
                            if kind == "p90_bar" { s.p90 } else { s.max }
                        }
                    };
                    if within(value, bound) {
                        Ok(())
                    } else {
                        Err(format!(
                            "random::{l}::{kind}: {value:.4e} exceeds the bar {bound:.4e} \
                             (BARS)"
                        ))
                    }
                }),
            ));
        }
        let l = label.clone();
        trials.push((
            format!("random::{label}::closed_room_bar"),
            check(move || {
                let r = results();
                let closed = |f: &Frame| f.category == Category::ClosedRoom;
                let value = r.near_black_err(&l, &closed).unwrap_or(0.0);
                if within(value, CLOSED_ROOM) {
                    Ok(())
                } else {
                    Err(format!(
                        "random::{l}::closed_room_bar: {value:.4e} of the lit maximum in a \
                         closed room exceeds {CLOSED_ROOM:e}"
                    ))
                }
            }),
        ));
        if let Some(base) = per_pixel[index].clone() {
            let l = label.clone();
            trials.push((
                format!("random::{label}::p90_vs_per_pixel"),
                check(move || {
                    let r = results();
                    let all = |_: &Frame| true;
                    let p90 = |l: &str| stats(&r.rel_l1s(l, &all)).map_or(f64::NAN, |s| s.p90);
                    let (mine, theirs) = (p90(&l), p90(&base));
                    if within(mine, theirs + SAMPLED_ADDED) {
                        Ok(())
                    } else {
                        Err(format!(
                            "random::{l}: p90 rel L1 {} % is more than {} points above {base}'s {} %",
                            pct(mine),
                            pct(SAMPLED_ADDED),
                            pct(theirs)
                        ))
                    }
                }),
            ));
        } else if label != REFERENCE {
            let l = label.clone();
            trials.push((
                format!("random::{label}::p90_vs_raymarch"),
                check(move || {
                    let r = results();
                    let all = |_: &Frame| true;
                    let p90 = |l: &str| stats(&r.rel_l1s(l, &all)).map_or(f64::NAN, |s| s.p90);
                    let (mine, theirs) = (p90(&l), p90(REFERENCE));
                    if within(mine, theirs) {
                        Ok(())
                    } else {
                        Err(format!(
                            "random::{l}: p90 rel L1 {} % is worse than {REFERENCE}'s {} %",
                            pct(mine),
                            pct(theirs)
                        ))
                    }
                }),
            ));
        }
    }
    // Expected failures of rows this run leaves out (`SCATTER_FULL`) name no trial here.
    let expected: Vec<(&str, &str)> = EXPECTED_FAILURES
        .iter()
        .copied()
        .filter(|(name, _)| {
            labels.iter().any(|l| {
                name.strip_prefix("random::")
                    .is_some_and(|n| n.starts_with(&format!("{l}::")))
            })
        })
        .collect();
    run_trials(trials, &expected)
}
