//! The speed-accuracy bench: every family and variant of a grid on suite scenes and poses,
//! each run through `scatter-runtime` on the GPU (lavapipe when there is none), its error
//! measured against both ground truths, its passes timed; written as CSV, a markdown table
//! with the ratios, and a chart (SVG and PNG) of error against time with the Pareto front.
//!
//! Timing. Each pass is submitted on its own and waited for; the median of `frames` frames
//! after a warm-up is its time ("pass wall time"). The methods compared on one scene are
//! timed interleaved, one frame of each in turn, `frames` rounds: this shared machine's speed
//! drifts by 30 % and more over minutes, and interleaving puts every method of a ratio under
//! the same drift. On a CPU adapter (lavapipe) that is the
//! pass's real cost, and GPU timestamps are not usable (they are not ordered after the
//! compute work: passes read 0.03 ms whatever their size), so the chart uses wall times.
//! The GPU timestamps are recorded too, for real GPUs. Speed is reported as ratios measured
//! in one run, never asserted.

use std::fmt::Write as _;
use std::ops::Not as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::{Image, write_atomic, write_png_rgb8};
use scatter_reference::metrics;
use scatter_reference::scene::Scene;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_runtime::prefiltered::{FrameInput, Inputs};
use scatter_runtime::shaderlib::Kernel;
use scatter_runtime::shaderlib::area_ivsv::AreaIvsvVariant;
use scatter_runtime::shaderlib::family::{Family, FamilyVariant, KernelFamily};
use scatter_runtime::shaderlib::hybrid_volume::HybridVolumeVariant;
use scatter_runtime::shaderlib::minmax::MinmaxVariant;
use scatter_runtime::shaderlib::partial_sum_tree::PartialSumTreeVariant;
use scatter_runtime::shaderlib::prefiltered::{
    Basis, FrameSettings, LightKind, PrefilteredVariant, Resolutions, Storage,
};
use scatter_runtime::shaderlib::raymarch::RaymarchVariant;
use scatter_runtime::shaderlib::sampling::SamplingKnobs;
use scatter_runtime::textures::{read_rgba16float, upload_r32float};
use scatter_runtime::wgpu::TextureView;
use scatter_runtime::{Context, FamilyPasses, Prefiltered, RuntimeError};

/// A variant of any family (the light is set per scene) with, for a family that rectifies,
/// its rectified map when it differs from the run's (`BenchConfig::rectified`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Method {
    /// The variant.
    pub variant: FamilyVariant,
    /// Its rectified map, when it differs from the run's.
    pub rectified: Option<[u32; 2]>,
}

impl<V: Into<FamilyVariant>> From<V> for Method {
    fn from(v: V) -> Self {
        Self::new(v, None)
    }
}

impl Method {
    /// A variant with its own rectified map (`None`: the run's).
    pub fn new(variant: impl Into<FamilyVariant>, rectified: Option<[u32; 2]>) -> Self {
        Self {
            variant: variant.into(),
            rectified,
        }
    }

    /// The family's name.
    pub fn family(&self) -> &'static str {
        self.variant.family().name()
    }

    /// The variant id (light included).
    pub fn id(&self) -> String {
        self.variant.id()
    }

    /// The family's variant (the one enum every tool shares).
    pub fn variant(&self) -> FamilyVariant {
        self.variant
    }

    /// The prefiltered default (the paper's variant) at the run's rectified size.
    pub fn prefiltered_default() -> Self {
        Family::Prefiltered.default_variant().into()
    }

    /// The minmax default at the run's rectified size.
    pub fn minmax_default() -> Self {
        Family::Minmax.default_variant().into()
    }

    /// The partial-sum-tree default (rank 4, 512 slices x 256 samples) at the run's
    /// rectified size.
    pub fn partial_sum_tree_default() -> Self {
        Family::PartialSumTree.default_variant().into()
    }

    /// Whether the family has a rectified map (its plan has the `rectified.width`
    /// parameter).
    pub fn rectifies(&self) -> bool {
        self.variant
            .plan()
            .parameters
            .iter()
            .any(|p| p.name == "rectified.width")
    }

    /// The rectified map this method runs with, given the run's (`None` for a family
    /// without one).
    pub fn rectified(&self, run: [u32; 2]) -> Option<[u32; 2]> {
        self.rectifies().then(|| self.rectified.unwrap_or(run))
    }

    /// The variant's knobs without the light (the chart's marker): its
    /// [`FamilyVariant::marker`] (the family's name when that is empty), then the
    /// rectified map when it is not the run's.
    pub fn knobs(&self) -> String {
        let mut k = self.variant.marker();
        if k.is_empty() {
            k = self.family().to_owned();
        }
        if let Some([w, h]) = self.rectified {
            k += &format!("-{w}x{h}");
        }
        k
    }

    fn with_light(self, light: LightKind) -> Self {
        Self {
            variant: self.variant.with_light(light),
            ..self
        }
    }
}

/// A scene the sweep measures: a suite scene at a pose, or a scene of one's own.
#[derive(Clone, Debug)]
pub enum Case {
    /// `suite::scene(name, pose, MediumPreset::Default, ...)` at the bench's screen.
    Suite(SceneName, Pose),
    /// A scene file's scene (`bench --scene-file`, `tune --scene-file`): its camera is sized
    /// to the bench's screen (the aspect follows the screen); the pose column reads `file`.
    File(Arc<Scene>),
}

impl Case {
    /// The scene at `screen`.
    pub fn scene(&self, [w, h]: [u32; 2]) -> Scene {
        match self {
            Case::Suite(name, pose) => suite::scene(*name, *pose, MediumPreset::Default, w, h),
            Case::File(scene) => {
                let mut scene = Scene::clone(scene);
                scene.camera.width = w;
                scene.camera.height = h;
                scene
            }
        }
    }

    /// The scene's name (the `scene` column).
    pub fn scene_name(&self) -> String {
        match self {
            Case::Suite(name, _) => name.name().to_owned(),
            Case::File(scene) => scene.name.clone(),
        }
    }

    /// The pose's name (the `pose` column): `file` for a scene file.
    pub fn pose_name(&self) -> &'static str {
        match self {
            Case::Suite(_, pose) => pose.name(),
            Case::File(_) => "file",
        }
    }

    /// The scene's light type.
    pub fn light(&self) -> LightKind {
        match self {
            Case::Suite(name, _) => light_of(*name),
            Case::File(scene) => scene.light.kind(),
        }
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// The scenes of the sweep.
    pub cases: Vec<Case>,
    /// Methods (their light is the scene's).
    pub methods: Vec<Method>,
    /// Screen size of the accuracy and timing runs.
    pub screen: [u32; 2],
    /// Rectified map of the prefiltered family.
    pub rectified: [u32; 2],
    /// Standard shadow-map size.
    pub shadow_map: u32,
    /// Timed frames per run (after one warm-up).
    pub frames: u32,
    /// Quadrature cells of the ground truths.
    pub truth_segments: usize,
    /// Also time the prefiltered default at 1280x720 over rectified widths 512..4096 and
    /// screen sizes (no accuracy).
    pub scaling: bool,
    /// Also time the headline configuration (1280x720 screen, 1024x1024 rectified map) for
    /// the prefiltered default, minmax and raymarch N = 64, 128 and (64, 4x4) on
    /// `sphere/ordinary`, `foliage/ordinary` and `terrain/ordinary`.
    pub headline: bool,
    /// With `headline`: also measure each headline run's rel L1 against the `shadow_map`
    /// truth at 1280x720 (the truth costs about a minute per scene on two cores; off for
    /// `bench --headline-only`, which times a kernel change).
    pub headline_error: bool,
    /// Only these families' methods, in the sweep and the headline runs (empty: every
    /// family); `bench --family raymarch --family hybrid_volume`.
    pub families: Vec<Family>,
    /// Only the headline methods with these knobs, as the headline table names them
    /// (`n64-i1-ep512`; empty: every one); `bench --headline-only --knobs n64-i1-ep512`.
    pub headline_knobs: Vec<String>,
    /// The camera pose of the headline's three scenes (`ordinary` in the full bench, whose
    /// ratios are read at it); `bench --headline-only --headline-pose epipole_on_screen`
    /// measures the headline methods at another.
    pub headline_pose: Pose,
    /// Leave out (and list in [`BenchResult::skipped`]) a method whose resources exceed a
    /// device limit, instead of failing the run: `tune`, whose grid spans layouts a small
    /// device cannot hold (a partial-sum tree of rank 8 over 1024 x 512 samples needs a
    /// 151 MB storage buffer; lavapipe binds at most 134 MB).
    pub skip_over_limits: bool,
    /// Measure against the `exact` truth too (`Row::rel_l1_exact`; NaN when off): `tune`
    /// reads only the `shadow_map` column and skips it (an area light's exact truth
    /// integrates 1024 points of the light).
    pub exact_truth: bool,
}

/// The knobs of the prefiltered default (`Method::knobs` of `PrefilteredVariant::default()`),
/// the variant every prefiltered ratio is read against.
pub const PREFILTERED_DEFAULT: &str = "m32-r4";

impl BenchConfig {
    /// The default sweep: every scene at `ordinary` and `epipole_on_screen`, prefiltered
    /// (M, R) in {(16, 4), (32, 1), (32, 3), (32, 4), (32, 8), (64, 4)} and raymarch N in {16, 32,
    /// 64, 128, 256} plus interleaved (64, 4x4) and (256, 4x4), and minmax, at 320x180 with
    /// a 512x512 rectified map (prefiltered and minmax) and a 1024^2 shadow map, 5 frames;
    /// plus the scaling and headline runs.
    pub fn default_sweep() -> BenchConfig {
        let mut methods: Vec<Method> = [(16, 4), (32, 1), (32, 3), (32, 4), (32, 8), (64, 4)]
            .into_iter()
            .map(|(bases, regions)| {
                Method::from(PrefilteredVariant {
                    bases,
                    regions,
                    ..PrefilteredVariant::default()
                })
            })
            .collect();
        for (samples, interleave) in [
            (16, 1),
            (32, 1),
            (64, 1),
            (128, 1),
            (256, 1),
            (64, 4),
            (256, 4),
        ] {
            methods.push(Method::from(RaymarchVariant {
                samples,
                interleave,
                ..RaymarchVariant::default()
            }));
        }
        for moments in PrefilteredVariant::MOMENTS {
            methods.push(Method::from(PrefilteredVariant::with_moments(moments)));
        }
        methods.push(Method::minmax_default());
        methods.push(Method::partial_sum_tree_default());
        // Issue 16: hybrid shadow volumes, the samples in each pixel's interval.
        for samples in [16, 32, 64] {
            methods.push(Method::from(HybridVolumeVariant {
                samples,
                ..HybridVolumeVariant::default()
            }));
        }
        BenchConfig {
            cases: SceneName::ALL
                .iter()
                .flat_map(|&s| {
                    [
                        Case::Suite(s, Pose::Ordinary),
                        Case::Suite(s, Pose::EpipoleOnScreen),
                    ]
                })
                .collect(),
            methods,
            screen: [320, 180],
            rectified: [512, 512],
            shadow_map: 1024,
            frames: 5,
            truth_segments: TruthSettings::default().segments,
            scaling: true,
            headline: true,
            headline_error: true,
            families: Vec::new(),
            headline_knobs: Vec::new(),
            headline_pose: Pose::Ordinary,
            skip_over_limits: false,
            exact_truth: true,
        }
    }

    /// The smoke run (CI): sphere and foliage at `ordinary`, the prefiltered default, two
    /// raymarch variants and minmax, 160x90, 256^2 rectified, 512^2 shadow map, 1 frame, coarse truths.
    pub fn quick() -> BenchConfig {
        BenchConfig {
            cases: vec![
                Case::Suite(SceneName::Sphere, Pose::Ordinary),
                Case::Suite(SceneName::Foliage, Pose::Ordinary),
            ],
            methods: vec![
                Method::prefiltered_default(),
                Method::from(RaymarchVariant {
                    samples: 32,
                    ..RaymarchVariant::default()
                }),
                Method::from(RaymarchVariant {
                    samples: 64,
                    interleave: 4,
                    ..RaymarchVariant::default()
                }),
                Method::minmax_default(),
                Method::partial_sum_tree_default(),
            ],
            screen: [160, 90],
            rectified: [256, 256],
            shadow_map: 512,
            frames: 1,
            truth_segments: 256,
            scaling: false,
            headline: false,
            headline_error: false,
            families: Vec::new(),
            headline_knobs: Vec::new(),
            headline_pose: Pose::Ordinary,
            skip_over_limits: false,
            exact_truth: true,
        }
    }

    /// Keeps only `families`' methods (in the sweep now, in the headline runs when they
    /// run); an empty list keeps every family.
    pub fn only_families(&mut self, families: &[Family]) {
        self.families = families.to_vec();
        if !families.is_empty() {
            self.methods
                .retain(|m| families.contains(&m.variant.family()));
        }
    }
}

/// One measured run.
#[derive(Clone, Debug)]
pub struct Row {
    /// Family.
    pub family: &'static str,
    /// PrefilteredVariant id.
    pub variant: String,
    /// PrefilteredVariant knobs without the light.
    pub knobs: String,
    /// The method (light set to the scene's).
    pub method: Method,
    /// Scene ([`Case::scene_name`]).
    pub scene: String,
    /// Pose ([`Case::pose_name`]: `file` for a scene file).
    pub pose: &'static str,
    /// rel L1 against the `exact` truth.
    pub rel_l1_exact: f64,
    /// rel L1 against the `shadow_map` truth.
    pub rel_l1_shadow_map: f64,
    /// NaN/Inf pixels.
    pub non_finite: usize,
    /// Median wall time of each pass submitted alone: (pass, time).
    pub passes: Vec<(&'static str, Duration)>,
    /// GPU timestamps summed over the passes of one frame, when the adapter has them.
    pub gpu_timestamps: Option<Duration>,
}

impl Row {
    /// Sum of the pass wall times.
    pub fn total(&self) -> Duration {
        self.passes.iter().map(|p| p.1).sum()
    }
}

/// A timing-only run (scaling of the prefiltered method).
#[derive(Clone, Debug)]
pub struct ScalingRow {
    /// Screen size.
    pub screen: [u32; 2],
    /// Rectified size.
    pub rectified: [u32; 2],
    /// Pass wall times: depth_columns, slice_fit, rectify, prefilter, scatter.
    pub passes: [Duration; 5],
}

/// A run at the headline configuration.
#[derive(Clone, Debug)]
pub struct HeadlineRow {
    /// Family.
    pub family: &'static str,
    /// PrefilteredVariant knobs without the light.
    pub knobs: String,
    /// Scene (pose `ordinary`).
    pub scene: SceneName,
    /// Pass wall times.
    pub passes: Vec<(&'static str, Duration)>,
    /// rel L1 against the `shadow_map` truth at the headline size, when measured
    /// ([`BenchConfig::headline_error`]).
    pub rel_l1_shadow_map: Option<f64>,
}

impl HeadlineRow {
    /// Sum of the pass wall times.
    pub fn total(&self) -> Duration {
        self.passes.iter().map(|p| p.1).sum()
    }
}

/// One line per headline run: family, knobs, scene, total and per-pass wall times (ms).
pub fn headline_lines(result: &BenchResult) -> Vec<String> {
    result
        .headline
        .iter()
        .map(|h| {
            let passes = h
                .passes
                .iter()
                .map(|(name, d)| format!("{name} {:.1}", ms(*d)))
                .collect::<Vec<_>>()
                .join(", ");
            let error = h
                .rel_l1_shadow_map
                .map_or(String::new(), |e| format!(", rel L1 {:.3} %", 100.0 * e));
            format!(
                "{} {} {}: {:.1} ms ({passes}){error}",
                h.family,
                h.knobs,
                h.scene,
                ms(h.total())
            )
        })
        .collect()
}

/// Everything a bench run measured.
#[derive(Clone, Debug)]
pub struct BenchResult {
    /// The adapter.
    pub adapter: String,
    /// The configuration.
    pub config: BenchConfig,
    /// Accuracy and timing runs.
    pub rows: Vec<Row>,
    /// Scaling runs.
    pub scaling: Vec<ScalingRow>,
    /// Headline runs (1280x720, 1024x1024 rectified).
    pub headline: Vec<HeadlineRow>,
    /// Methods left out by [`BenchConfig::skip_over_limits`]: (method id, the limit's error),
    /// once per method.
    pub skipped: Vec<(String, String)>,
    /// Wall time of the whole bench.
    pub elapsed: Duration,
    /// The machine's bounds (`roofline::measure_bounds`: copy, texel loads, filtered fetches,
    /// transcendentals, FMAs) measured just before and just after the run. lavapipe on a
    /// shared machine moves between states that weigh these unevenly (docs/roofline.md, "Stop
    /// 54": `prefilter` twice as long, raymarch faster, with the same binary), so a run
    /// carries its own.
    pub probes: [Vec<crate::roofline::Bound>; 2],
}

/// Any error of a bench run.
pub type BoxError = Box<dyn std::error::Error>;

/// A run: its passes, its output (rgba, row-major), its GPU timestamps and, for an area
/// light's family, the VPL map array it reads (uploaded once, kept for the timing).
struct MethodRun {
    pass: FamilyPasses,
    output: Vec<[f32; 4]>,
    gpu_timestamps: Option<Duration>,
    vpl_maps: Option<(scatter_runtime::wgpu::Texture, TextureView)>,
}

/// The VPLs of the `vpl` truth an area case's second error column is measured against:
/// the most a variant takes (`scatter_frame::area_ivsv::MAX_VPLS`), so that every candidate's
/// VPL count is compared with one converged VPL set (with the engine's map size).
pub const AREA_TRUTH_VPLS: usize = 256;

/// Whether `method` renders `light` (the single-light families a sun or a spot, `area_ivsv`
/// an area light): a method of another light is left out of a case, not failed.
fn renders(method: &Method, light: LightKind) -> bool {
    method
        .variant
        .with_light(light)
        .validate()
        .is_err_and(|e| e.knob == "light")
        .not()
}

fn light_of(name: SceneName) -> LightKind {
    if name == SceneName::SpotGrate {
        LightKind::Spot
    } else {
        LightKind::Directional
    }
}

/// Runs the bench.
///
/// # Errors
///
/// Any runtime, reference or I/O error, with context.
pub fn run(ctx: &Context, config: &BenchConfig, progress: bool) -> Result<BenchResult, BoxError> {
    let start = Instant::now();
    let bar = if progress {
        ProgressBar::new((config.cases.len() * (config.methods.len() + 2)) as u64).with_style(
            ProgressStyle::with_template("{msg:40} [{bar:40}] {pos}/{len}, eta {eta}")?
                .progress_chars("=> "),
        )
    } else {
        ProgressBar::hidden()
    };
    bar.set_message("machine probes (before)");
    let probes_before = crate::roofline::measure_bounds(ctx, PROBE_FRAMES)?;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let [w, h] = config.screen;
    for case in &config.cases {
        let (name, pose) = (case.scene_name(), case.pose_name());
        let scene = case.scene([w, h]);
        let bvh = Bvh::build(&scene.geometry);
        let gbuf = GBuffer::cast(&scene, &bvh);
        let sm = ShadowMap::build(&scene, &bvh, config.shadow_map)?;
        let settings = TruthSettings {
            segments: config.truth_segments,
            ..TruthSettings::default()
        };
        bar.set_message(format!("{name}/{pose}: exact truth"));
        let exact = config
            .exact_truth
            .then(|| truth::render(&scene, &gbuf, &Visibility::Exact(&bvh), &settings, &|| ()));
        bar.inc(1);
        bar.set_message(format!("{name}/{pose}: shadow_map truth"));
        // An area light's: the `vpl` truth of the most VPLs, each with its engine map.
        let sm_truth = if scene.light.area().is_some() {
            truth::render_vpl(&scene, &gbuf, &bvh, AREA_TRUTH_VPLS, sm.size, &settings)?
        } else {
            truth::render(
                &scene,
                &gbuf,
                &Visibility::ShadowMap(&sm),
                &settings,
                &|| (),
            )
        };
        bar.inc(1);
        let depth = upload_r32float(
            ctx,
            Kernel::Scatter,
            "bench depth",
            [w, h],
            &gbuf.view_depth,
        )?;
        let shadow = upload_r32float(
            ctx,
            Kernel::Rectify,
            "bench shadow map",
            [sm.size; 2],
            &sm.depth,
        )?;
        let depth_view = depth.create_view(&Default::default());
        let shadow_view = shadow.create_view(&Default::default());
        let methods: Vec<Method> = config
            .methods
            .iter()
            .filter(|m| renders(m, case.light()))
            .map(|m| m.with_light(case.light()))
            .collect();
        let mut runs = Vec::with_capacity(methods.len());
        let mut kept = Vec::with_capacity(methods.len());
        for &method in &methods {
            bar.set_message(format!("{name}/{pose}: {}", method.id()));
            match run_method(
                ctx,
                method,
                (&scene, &bvh, &gbuf),
                &sm,
                &depth_view,
                &shadow_view,
                config.screen,
                config.rectified,
            ) {
                Ok(run) => {
                    runs.push(run);
                    kept.push(method);
                }
                Err(e)
                    if config.skip_over_limits
                        && matches!(
                            e.downcast_ref::<RuntimeError>(),
                            Some(RuntimeError::LimitExceeded { .. })
                        ) =>
                {
                    if !skipped.iter().any(|(id, _)| *id == method.id()) {
                        skipped.push((method.id(), e.to_string()));
                    }
                    bar.inc(1);
                }
                Err(e) => return Err(e),
            }
        }
        let methods = kept;
        bar.set_message(format!("{name}/{pose}: timing, interleaved"));
        let times = time_interleaved(ctx, &runs, &depth_view, &shadow_view, config.frames)?;
        for ((method, run), passes) in methods.into_iter().zip(runs).zip(times) {
            let (output, gpu_timestamps) = (run.output, run.gpu_timestamps);
            let image =
                Image::from_pixels(w, h, output.iter().map(|c| [c[0], c[1], c[2]]).collect());
            let e = match &exact {
                Some(exact) => metrics::compare(&image, exact)?,
                None => metrics::ErrorReport {
                    rel_l1: f64::NAN,
                    ..metrics::compare(&image, &sm_truth)?
                },
            };
            let s = metrics::compare(&image, &sm_truth)?;
            rows.push(Row {
                family: method.family(),
                variant: method.id(),
                knobs: method.knobs(),
                method,
                scene: name.clone(),
                pose,
                rel_l1_exact: e.rel_l1,
                rel_l1_shadow_map: s.rel_l1,
                non_finite: e.non_finite,
                passes,
                gpu_timestamps,
            });
            bar.inc(1);
        }
    }
    let scaling = if config.scaling {
        bar.set_message("prefiltered scaling");
        scaling_runs(ctx, config.frames)?
    } else {
        Vec::new()
    };
    let headline = if config.headline {
        bar.set_message("headline 1280x720");
        headline_runs(ctx, config)?
    } else {
        Vec::new()
    };
    bar.set_message("machine probes (after)");
    let probes_after = crate::roofline::measure_bounds(ctx, PROBE_FRAMES)?;
    bar.finish_and_clear();
    Ok(BenchResult {
        adapter: ctx.report().to_string(),
        config: config.clone(),
        rows,
        scaling,
        headline,
        skipped,
        elapsed: start.elapsed(),
        probes: [probes_before, probes_after],
    })
}

/// Timed frames of each machine probe a run records (about a second for the five).
const PROBE_FRAMES: u32 = 5;

/// Runs `method` once on a prepared scene (the engine's depth buffer `dv` and shadow map
/// `sv` already uploaded; an area light's VPL maps ray-cast and uploaded here, as an engine
/// renders them): its passes (for [`time_interleaved`]), its output, and the GPU timestamps
/// of one frame when the adapter has them.
#[allow(
    clippy::too_many_arguments,
    reason = "the scene's buffers and the sizes"
)]
fn run_method(
    ctx: &Context,
    method: Method,
    (scene, bvh, gbuf): (&Scene, &Bvh, &GBuffer),
    sm: &ShadowMap,
    dv: &TextureView,
    sv: &TextureView,
    screen: [u32; 2],
    rectified: [u32; 2],
) -> Result<MethodRun, BoxError> {
    let res = Resolutions {
        screen,
        rectified: method.rectified(rectified).unwrap_or(rectified),
    };
    let mut pass = FamilyPasses::new(ctx, &method.variant(), res, sm.size)?;
    pass.prepare(
        ctx,
        &FrameInput {
            camera: scene.camera_desc(),
            light: scene.light_desc(),
            medium: scene.medium_desc(),
            shadow_map: sm.desc(),
            settings: FrameSettings::for_screen(screen[0], screen[1]),
        },
    )?;
    let vpl_maps = match method.variant {
        FamilyVariant::AreaIvsv(v) => {
            let inputs = scatter_reference::kernels::ivsv_inputs(scene, gbuf, bvh, &v, sm.size)?;
            Some(scatter_runtime::upload_vpl_maps(
                ctx,
                sm.size,
                v.vpls,
                &inputs.map_data,
            )?)
        }
        _ => None,
    };
    let inputs = Inputs {
        depth: dv,
        shadow_map: Some(sv),
        rectified: None,
        vpl_maps: vpl_maps.as_ref().map(|(_, v)| v),
    };
    let mut encoder = ctx.device().create_command_encoder(&Default::default());
    pass.encode(ctx, &mut encoder, &inputs)?;
    ctx.queue().submit([encoder.finish()]);
    let ts = pass.total_pass_time(ctx)?;
    let output = read_rgba16float(ctx, Kernel::Scatter, pass.output_texture())?;
    Ok(MethodRun {
        pass,
        output,
        gpu_timestamps: ts,
        vpl_maps,
    })
}

/// The median wall time of each pass of each run over `frames` rounds; a round times one
/// frame of every run in turn (after one warm-up frame each), so that the machine's drift
/// falls on every run alike.
fn time_interleaved(
    ctx: &Context,
    runs: &[MethodRun],
    dv: &TextureView,
    sv: &TextureView,
    frames: u32,
) -> Result<Vec<Vec<(&'static str, Duration)>>, BoxError> {
    fn inputs<'a>(run: &'a MethodRun, dv: &'a TextureView, sv: &'a TextureView) -> Inputs<'a> {
        Inputs {
            depth: dv,
            shadow_map: Some(sv),
            rectified: None,
            vpl_maps: run.vpl_maps.as_ref().map(|(_, v)| v),
        }
    }
    let inputs = |run| inputs(run, dv, sv);
    for run in runs {
        run.pass.measure_pass_wall_times(ctx, &inputs(run), 1)?;
    }
    let mut samples: Vec<Vec<(&'static str, Vec<Duration>)>> = vec![Vec::new(); runs.len()];
    for _ in 0..frames.max(1) {
        for (run, s) in runs.iter().zip(&mut samples) {
            let t = run.pass.measure_pass_wall_times(ctx, &inputs(run), 1)?;
            if s.is_empty() {
                *s = t.iter().map(|(k, _)| (k.name(), Vec::new())).collect();
            }
            for ((_, v), (_, d)) in s.iter_mut().zip(t) {
                v.push(d);
            }
        }
    }
    Ok(samples
        .into_iter()
        .map(|s| {
            s.into_iter()
                .map(|(name, mut v)| {
                    v.sort();
                    (name, v[v.len() / 2])
                })
                .collect()
        })
        .collect())
}

/// A timing scene: `name/ordinary` at a screen size, its depth buffer and 1024^2 shadow map,
/// and the engine's depth buffer and shadow map uploaded.
struct BenchScene {
    scene: Scene,
    bvh: Bvh,
    gbuf: GBuffer,
    sm: ShadowMap,
    dv: TextureView,
    sv: TextureView,
}

fn bench_scene(
    ctx: &Context,
    name: SceneName,
    pose: Pose,
    screen: [u32; 2],
) -> Result<BenchScene, BoxError> {
    let scene = suite::scene(name, pose, MediumPreset::Default, screen[0], screen[1]);
    let bvh = Bvh::build(&scene.geometry);
    let gbuf = GBuffer::cast(&scene, &bvh);
    let sm = ShadowMap::build(&scene, &bvh, 1024)?;
    let depth = upload_r32float(
        ctx,
        Kernel::Scatter,
        "bench depth",
        screen,
        &gbuf.view_depth,
    )?;
    let shadow = upload_r32float(
        ctx,
        Kernel::Rectify,
        "bench shadow map",
        [sm.size; 2],
        &sm.depth,
    )?;
    Ok(BenchScene {
        dv: depth.create_view(&Default::default()),
        sv: shadow.create_view(&Default::default()),
        scene,
        bvh,
        gbuf,
        sm,
    })
}

/// Times `methods` (pass wall times, interleaved) on `name/ordinary` at `screen`
/// (prefiltered and minmax: with a `rectified` map).
pub(crate) fn time_methods(
    ctx: &Context,
    methods: &[Method],
    name: SceneName,
    screen: [u32; 2],
    rectified: [u32; 2],
    frames: u32,
) -> Result<Vec<Vec<(&'static str, Duration)>>, BoxError> {
    let bench = bench_scene(ctx, name, Pose::Ordinary, screen)?;
    Ok(
        time_methods_on(ctx, methods, name, &bench, screen, rectified, frames)?
            .into_iter()
            .map(|(times, _)| times)
            .collect(),
    )
}

/// One method's pass wall times and its output (rgba, row-major).
type TimedOutput = (Vec<(&'static str, Duration)>, Vec<[f32; 4]>);

/// [`time_methods`] on a prepared scene, with each method's output (read back once).
fn time_methods_on(
    ctx: &Context,
    methods: &[Method],
    name: SceneName,
    bench: &BenchScene,
    screen: [u32; 2],
    rectified: [u32; 2],
    frames: u32,
) -> Result<Vec<TimedOutput>, BoxError> {
    let BenchScene {
        scene,
        bvh,
        gbuf,
        sm,
        dv,
        sv,
    } = bench;
    let runs = methods
        .iter()
        .map(|m| {
            run_method(
                ctx,
                m.with_light(light_of(name)),
                (scene, bvh, gbuf),
                sm,
                dv,
                sv,
                screen,
                rectified,
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let times = time_interleaved(ctx, &runs, dv, sv, frames)?;
    Ok(times
        .into_iter()
        .zip(runs)
        .map(|(t, run)| (t, run.output))
        .collect())
}

/// The per-pixel variants the headline also runs sampled: every family's default and the
/// moment basis with 4 moments.
fn sampled_bases() -> Vec<FamilyVariant> {
    // The families with a per-pixel mode and the sampled ones (not partial_sum_tree, which
    // samples epipolar lines only and is timed on its own, nor area_ivsv, which renders
    // area lights, not the headline's sun: `examples/area_bench` measures it, per pixel and
    // sampled).
    let mut out: Vec<FamilyVariant> = Family::ALL
        .iter()
        .map(|f| f.default_variant())
        .filter(|v| v.family() != Family::AreaIvsv)
        .filter(|v| !v.sampling().is_sampled())
        .filter(|v| {
            sampled_configs()
                .iter()
                .all(|k| v.with_sampling(*k).validate().is_ok())
        })
        .collect();
    out.push(PrefilteredVariant::with_moments(4).into());
    out
}

/// The sampling configurations the headline runs every sampled base with: lowres at 1/2
/// and 1/4 of the screen per axis, and epipolar at its defaults (512 slices x 256 samples,
/// step 8).
fn sampled_configs() -> Vec<SamplingKnobs> {
    let mut out: Vec<SamplingKnobs> = SamplingKnobs::SCALES
        .iter()
        .map(|&s| SamplingKnobs::lowres(s))
        .collect();
    out.push(SamplingKnobs::epipolar(SamplingKnobs::DEFAULT_SLICES));
    out
}

/// Epipolar slices that give a 1280x720 screen the slice spacing Yusov 2013's 512 give
/// 2560x1600 (about 16 pixels of the screen's border per slice).
pub const HEADLINE_SLICES: u32 = 256;

/// The rectified map of the headline's epipolar frames at [`HEADLINE_SLICES`]: one row per
/// slice and one column per sample (the epipolar sample grid; Yusov 2013 builds one min/max
/// tree per slice). The per-pixel frame keeps the run's map (1024x1024).
pub const SLICE_GRID_RECTIFIED: [u32; 2] = [256, 256];

/// The rectified map of the headline's epipolar frames at [`HEADLINE_SLICES`] that keeps
/// issue 14's per-pose bars: one row per slice (on the slices' planes: rows aligned) and the
/// per-pixel map's 1024 columns, which thin occluders need (the slice-grid map's 256 columns
/// point-sample `window`'s bars: 2.5 points worse than per pixel on its grazing pose, this
/// map at most 0.72 on the 24 suite poses; docs/roofline.md, "Stop 47").
pub const SLICE_ROWS_RECTIFIED: [u32; 2] = [1024, 256];

/// Every sampled method of the headline with the per-pixel method it is compared with: each
/// base in each configuration; each base at [`HEADLINE_SLICES`] slices, and a base that
/// rectifies also with the [`SLICE_GRID_RECTIFIED`] and [`SLICE_ROWS_RECTIFIED`] maps; and
/// raymarch n256 epipolar (the brute-force anchor sampled: its evaluations are the fewest) at
/// both slice counts.
fn sampled_variants() -> Vec<(Method, Method)> {
    let mut out = Vec::new();
    let n256: FamilyVariant = RaymarchVariant {
        samples: 256,
        ..RaymarchVariant::default()
    }
    .into();
    for base in sampled_bases() {
        for knobs in sampled_configs() {
            out.push((Method::from(base), Method::from(base.with_sampling(knobs))));
        }
    }
    for base in sampled_bases() {
        let sampled = base.with_sampling(SamplingKnobs::epipolar(HEADLINE_SLICES));
        out.push((Method::from(base), Method::from(sampled)));
        for map in [SLICE_GRID_RECTIFIED, SLICE_ROWS_RECTIFIED] {
            let with_map = Method::new(sampled, Some(map));
            if with_map.rectifies() {
                out.push((Method::from(base), with_map));
            }
        }
    }
    // Coarse filtered columns (`filtered_stride` 4): the prefiltered default sampled with
    // [`SLICE_ROWS_RECTIFIED`] against the same variant per pixel and against the default
    // per pixel (its `prefilter` is the stores of every rectified texel: docs/roofline.md,
    // "Stop 54").
    let stride4: FamilyVariant = PrefilteredVariant {
        filtered_stride: 4,
        ..PrefilteredVariant::default()
    }
    .into();
    let stride4_sampled = Method::new(
        stride4.with_sampling(SamplingKnobs::epipolar(HEADLINE_SLICES)),
        Some(SLICE_ROWS_RECTIFIED),
    );
    out.push((Method::from(stride4), stride4_sampled));
    out.push((Method::prefiltered_default(), stride4_sampled));
    // `resume` at filtered_stride 8: the prefiltered default sampled with
    // [`SLICE_ROWS_RECTIFIED`], `prefilter` storing every eighth column and the samples and
    // fallback pixels resuming the running means between them: the default's answer (up to
    // its rgba8 rounding), so compared with the default per pixel; and with itself per pixel,
    // which is slower than the default (every pixel resumes; docs/roofline.md, "Stop 58").
    let resume8: FamilyVariant = PrefilteredVariant {
        filtered_stride: 8,
        resume: true,
        ..PrefilteredVariant::default()
    }
    .into();
    let resume8_sampled = Method::new(
        resume8.with_sampling(SamplingKnobs::epipolar(HEADLINE_SLICES)),
        Some(SLICE_ROWS_RECTIFIED),
    );
    out.push((Method::prefiltered_default(), resume8_sampled));
    out.push((Method::from(resume8), resume8_sampled));
    for slices in [SamplingKnobs::DEFAULT_SLICES, HEADLINE_SLICES] {
        out.push((
            Method::from(n256),
            Method::from(n256.with_sampling(SamplingKnobs::epipolar(slices))),
        ));
    }
    out
}

/// The headline configuration: 1280x720, 1024x1024 rectified, on sphere, foliage and
/// terrain; with `errors`, each run's rel L1 against the `shadow_map` truth at that size.
fn headline_runs(ctx: &Context, config: &BenchConfig) -> Result<Vec<HeadlineRow>, BoxError> {
    let (frames, errors, families) = (config.frames, config.headline_error, &config.families);
    let mut methods = vec![
        Method::prefiltered_default(),
        Method::minmax_default(),
        Method::from(HybridVolumeVariant::default()),
        Method::partial_sum_tree_default(),
        // As many rows as slices: the rows the sweep reads, on the slices (stop 50).
        Method::new(Family::PartialSumTree.default_variant(), Some([1024, 512])),
        Method::new(Family::PartialSumTree.default_variant(), Some([512, 512])),
    ];
    for moments in PrefilteredVariant::MOMENTS {
        methods.push(Method::from(PrefilteredVariant::with_moments(moments)));
    }
    // The moment basis with 8 regions (the random poses' row), and its most accurate
    // configuration, 16 regions (prefiltered_truth: the bars on every pose at 1024x1024).
    for regions in [8, 16] {
        methods.push(Method::from(PrefilteredVariant {
            regions,
            ..PrefilteredVariant::with_moments(6)
        }));
    }
    for (samples, interleave) in [(64, 1), (128, 1), (256, 1), (64, 4)] {
        methods.push(Method::from(RaymarchVariant {
            samples,
            interleave,
            ..RaymarchVariant::default()
        }));
    }
    // The sampling stage (issue 14): each family's default, and the moment basis's
    // cheapest, at 1/2 and 1/4 of the screen per axis and epipolar.
    for (_, sampled) in sampled_variants() {
        // A sampled method may be paired with more than one per-pixel one: run it once.
        if !methods.contains(&sampled) {
            methods.push(sampled);
        }
    }
    // Epipolar sampling with a rectified map of as many rows as slices (512x512): a quarter
    // of the fixed passes' texels, which dominate the sampled prefiltered and minmax frames;
    // and the prefiltered default at lowres 2 and 4 with that map (candidates of issue 13's
    // "best prefiltered configuration").
    for family in [Family::Prefiltered, Family::Minmax] {
        methods.push(Method::new(
            family
                .default_variant()
                .with_sampling(SamplingKnobs::epipolar(SamplingKnobs::DEFAULT_SLICES)),
            Some([512, 512]),
        ));
    }
    for scale in [2, 4] {
        methods.push(Method::new(
            Family::Prefiltered
                .default_variant()
                .with_sampling(SamplingKnobs::lowres(scale)),
            Some([512, 512]),
        ));
    }
    // The sweep's most accurate Fourier configuration, 8 regions (m32-r8: 0.84 % mean rel L1
    // at 320x180 against the default's 1.23 %), per pixel and sampled: candidates of issue
    // 13's targets at raymarch n256's error.
    let r8: FamilyVariant = PrefilteredVariant {
        regions: 8,
        ..PrefilteredVariant::default()
    }
    .into();
    methods.push(Method::from(r8));
    for knobs in sampled_configs() {
        methods.push(Method::from(r8.with_sampling(knobs)));
    }
    // m32-r8 at lowres 2 with smaller maps (candidates of issue 13's target at raymarch
    // n256's error): at 1024x1024 the map's fixed passes are two thirds of that frame
    // (rectify 16 and prefilter 62 of 124 ms, nineteenth run) and scale with its texels,
    // and the error grows as they fall (`godrays --compare`, means of the headline scenes:
    // 0.0620 % at 1024x1024, 0.0628 at 1024x640, 0.0634 at 1024x576, 0.0644 at 1024x512,
    // 0.0633 at 896x640, 0.0646 at 768x640; raymarch n256 0.0640). A grid, so that the
    // ratio line finds the cheapest one at or below n256's error in the run itself.
    for map in [
        [1024, 512],
        [1024, 576],
        [1024, 640],
        [1024, 768],
        [896, 576],
        [896, 640],
    ] {
        methods.push(Method::new(
            r8.with_sampling(SamplingKnobs::lowres(2)),
            Some(map),
        ));
    }
    // Coarse filtered columns: the default per pixel at filtered_stride 2 and 4 (sampled
    // with stride 4 in `sampled_variants`); m32-r8 lowres 2 at stride 4 (issue 13's target
    // at raymarch n256's error); m96 and m128 with 8 regions at lowres 2 and stride 4, whose
    // Fourier error floor on foliage reaches minmax's (issue 13's third target: m128-r8
    // lowres 2 0.0676 % at stride 1, `prefilter` 252 of 368 ms in the nineteenth run's
    // state; 0.0691 % at stride 4).
    for k in [2, 4] {
        methods.push(Method::from(PrefilteredVariant {
            filtered_stride: k,
            ..PrefilteredVariant::default()
        }));
    }
    // `resume` at stride 8 per pixel: the per-pixel frame of the sampled `resume` row, which
    // every pixel pays the resumption in (docs/roofline.md, "Stop 58").
    methods.push(Method::from(PrefilteredVariant {
        filtered_stride: 8,
        resume: true,
        ..PrefilteredVariant::default()
    }));
    for bases in [32, 96, 128] {
        methods.push(Method::from(
            FamilyVariant::from(PrefilteredVariant {
                bases,
                regions: 8,
                filtered_stride: 4,
                ..PrefilteredVariant::default()
            })
            .with_sampling(SamplingKnobs::lowres(2)),
        ));
    }
    if !families.is_empty() {
        methods.retain(|m| families.contains(&m.variant.family()));
    }
    if !config.headline_knobs.is_empty() {
        let known: Vec<String> = methods.iter().map(Method::knobs).collect();
        if let Some(k) = config.headline_knobs.iter().find(|k| !known.contains(k)) {
            return Err(format!(
                "no headline method has the knobs `{k}` (the headline's: {})",
                known.join(", ")
            )
            .into());
        }
        methods.retain(|m| config.headline_knobs.contains(&m.knobs()));
    }
    let screen = [1280, 720];
    let mut out = Vec::new();
    for name in [SceneName::Sphere, SceneName::Foliage, SceneName::Terrain] {
        let bench = bench_scene(ctx, name, config.headline_pose, screen)?;
        let runs = time_methods_on(ctx, &methods, name, &bench, screen, [1024, 1024], frames)?;
        let truth = errors.then(|| {
            truth::render(
                &bench.scene,
                &bench.gbuf,
                &Visibility::ShadowMap(&bench.sm),
                &TruthSettings::default(),
                &|| (),
            )
        });
        for (&m, (passes, output)) in methods.iter().zip(runs) {
            let rel_l1_shadow_map = match &truth {
                Some(t) => {
                    let image = Image::from_pixels(
                        screen[0],
                        screen[1],
                        output.iter().map(|c| [c[0], c[1], c[2]]).collect(),
                    );
                    Some(metrics::compare(&image, t)?.rel_l1)
                }
                None => None,
            };
            out.push(HeadlineRow {
                family: m.family(),
                knobs: m.knobs(),
                scene: name,
                passes,
                rel_l1_shadow_map,
            });
        }
    }
    Ok(out)
}

/// The prefiltered default on sphere/ordinary at 1280x720 with rectified widths 512..4096
/// (1024 rows), and at 320x180 / 640x360 / 1280x720 with a 1024x1024 map.
fn scaling_runs(ctx: &Context, frames: u32) -> Result<Vec<ScalingRow>, BoxError> {
    let mut out = Vec::new();
    let configs = [512, 1024, 2048, 4096]
        .map(|wr| ([1280, 720], [wr, 1024]))
        .into_iter()
        .chain([([320, 180], [1024, 1024]), ([640, 360], [1024, 1024])]);
    for (screen, rectified) in configs {
        let BenchScene {
            scene, sm, dv, sv, ..
        } = bench_scene(ctx, SceneName::Sphere, Pose::Ordinary, screen)?;
        let mut pass = Prefiltered::new(
            ctx,
            &PrefilteredVariant::default(),
            Resolutions { screen, rectified },
            sm.size,
        )?;
        pass.prepare(
            ctx,
            &FrameInput {
                camera: scene.camera_desc(),
                light: scene.light_desc(),
                medium: scene.medium_desc(),
                shadow_map: sm.desc(),
                settings: FrameSettings::for_screen(screen[0], screen[1]),
            },
        )?;
        let t = pass.measure_pass_wall_times(
            ctx,
            &Inputs {
                depth: &dv,
                shadow_map: Some(&sv),
                rectified: None,
                vpl_maps: None,
            },
            frames,
        )?;
        out.push(ScalingRow {
            screen,
            rectified,
            passes: [
                t.depth_columns,
                t.slice_fit,
                t.rectify,
                t.prefilter,
                t.scatter,
            ],
        });
    }
    Ok(out)
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Per-variant means over the runs: (family, knobs, mean total ms, mean rel L1 vs shadow
/// map truth, mean rel L1 vs exact), sorted by family then time.
pub fn per_variant(rows: &[Row]) -> Vec<(&'static str, String, f64, f64, f64)> {
    let mut keys: Vec<(&'static str, String)> = Vec::new();
    for r in rows {
        if !keys.iter().any(|k| k.0 == r.family && k.1 == r.knobs) {
            keys.push((r.family, r.knobs.clone()));
        }
    }
    let mut out: Vec<_> = keys
        .into_iter()
        .map(|(family, knobs)| {
            let sel: Vec<&Row> = rows
                .iter()
                .filter(|r| r.family == family && r.knobs == knobs)
                .collect();
            let n = sel.len().max(1) as f64;
            let t = sel.iter().map(|r| ms(r.total())).sum::<f64>() / n;
            let es = sel.iter().map(|r| r.rel_l1_shadow_map).sum::<f64>() / n;
            let ee = sel.iter().map(|r| r.rel_l1_exact).sum::<f64>() / n;
            (family, knobs, t, es, ee)
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(b.0).then(a.2.total_cmp(&b.2)));
    out
}

/// The Pareto front (cheaper or more accurate than every other point) of (time, error)
/// points, sorted by time.
pub fn pareto(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut sorted: Vec<_> = points.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for p in sorted {
        if front.last().is_none_or(|l| p.1 < l.1) {
            front.push(p);
        }
    }
    front
}

/// The ratio lines of the report.
pub fn ratios(result: &BenchResult) -> Vec<String> {
    let mut out = Vec::new();
    let variants = per_variant(&result.rows);
    let reference = variants
        .iter()
        .find(|v| v.0 == "prefiltered" && v.1 == PREFILTERED_DEFAULT);
    if let Some(p) = reference {
        let matching = variants
            .iter()
            .filter(|v| v.0 == "raymarch" && v.3 <= p.3)
            .min_by(|a, b| a.2.total_cmp(&b.2));
        match matching {
            Some(r) => out.push(format!(
                "prefiltered {PREFILTERED_DEFAULT} ({:.2} ms, mean rel L1 {:.2} %) vs the cheapest raymarch at equal or better error, {} ({:.2} ms, {:.2} %): raymarch takes {:.2}x the time",
                p.2,
                100.0 * p.3,
                r.1,
                r.2,
                100.0 * r.3,
                r.2 / p.2
            )),
            None => {
                let best = variants
                    .iter()
                    .filter(|v| v.0 == "raymarch")
                    .min_by(|a, b| a.3.total_cmp(&b.3));
                out.push(match best {
                    Some(b) => format!(
                        "prefiltered {PREFILTERED_DEFAULT} ({:.2} ms, mean rel L1 {:.2} %): no raymarch variant in the sweep reaches its error; the most accurate, {} ({:.2} ms), has {:.2} % ({:.2}x the time)",
                        p.2,
                        100.0 * p.3,
                        b.1,
                        b.2,
                        100.0 * b.3,
                        b.2 / p.2
                    ),
                    None => "no raymarch variant in the sweep".to_owned(),
                });
            }
        }
    }
    // Issue 16: hybrid shadow volumes against brute-force marching at equal or better error
    // (Wyman & Ramsey report 2.4-7.1x over marching the whole ray).
    for knobs in ["n16", "n32", "n64"] {
        let Some(h) = variants
            .iter()
            .find(|v| v.0 == "hybrid_volume" && v.1 == knobs)
        else {
            continue;
        };
        let matching = variants
            .iter()
            .filter(|v| v.0 == "raymarch" && v.3 <= h.3)
            .min_by(|a, b| a.2.total_cmp(&b.2));
        out.push(match matching {
            Some(r) => format!(
                "hybrid_volume {knobs} ({:.2} ms, mean rel L1 {:.2} %) vs the cheapest raymarch at equal or better error, {} ({:.2} ms, {:.2} %): raymarch takes {:.2}x the time",
                h.2,
                100.0 * h.3,
                r.1,
                r.2,
                100.0 * r.3,
                r.2 / h.2
            ),
            None => format!(
                "hybrid_volume {knobs} ({:.2} ms, mean rel L1 {:.2} %): no raymarch variant in the sweep reaches its error",
                h.2,
                100.0 * h.3
            ),
        });
    }
    // The same comparison at the headline configuration (times; the tag takes the errors
    // from the sweep above).
    let matching = reference.and_then(|p| {
        variants
            .iter()
            .filter(|v| v.0 == "raymarch" && v.3 <= p.3)
            .min_by(|a, b| a.2.total_cmp(&b.2))
            .map(|r| r.1.clone())
    });
    for scene in [SceneName::Sphere, SceneName::Foliage] {
        let time = |family: &str, knobs: &str| {
            result
                .headline
                .iter()
                .find(|r| r.family == family && r.knobs == knobs && r.scene == scene)
                .map(|r| ms(r.total()))
        };
        if let Some(p) = time("prefiltered", PREFILTERED_DEFAULT) {
            for knobs in ["n64-i1", "n128-i1", "n64-i4"] {
                if let Some(r) = time("raymarch", knobs) {
                    let tag = if matching.as_deref() == Some(knobs) {
                        " (the cheapest raymarch at equal or better sweep error)"
                    } else {
                        ""
                    };
                    out.push(format!(
                        "headline 1280x720, 1024x1024 rectified, {scene}/ordinary: raymarch {knobs}{tag} {r:.1} ms / prefiltered {PREFILTERED_DEFAULT} {p:.1} ms = {:.2}",
                        r / p
                    ));
                }
            }
        }
    }
    // Time and error read from the same runs at the headline size: per method, the means
    // over the headline scenes, each against the prefiltered default.
    let headline_mean = |family: &str, knobs: &str| {
        let rows: Vec<&HeadlineRow> = result
            .headline
            .iter()
            .filter(|r| r.family == family && r.knobs == knobs)
            .collect();
        let errors: Option<Vec<f64>> = rows.iter().map(|r| r.rel_l1_shadow_map).collect();
        match errors {
            Some(e) if !rows.is_empty() => Some((
                rows.iter().map(|r| ms(r.total())).sum::<f64>() / rows.len() as f64,
                e.iter().sum::<f64>() / e.len() as f64,
            )),
            _ => None,
        }
    };
    if let Some((pt, pe)) = headline_mean("prefiltered", PREFILTERED_DEFAULT) {
        for (family, knobs) in [
            ("prefiltered", "moments4-r4"),
            ("prefiltered", "moments6-r4"),
            ("prefiltered", "moments6-r8"),
            ("prefiltered", "moments6-r16"),
            ("raymarch", "n64-i1"),
            ("raymarch", "n128-i1"),
            ("raymarch", "n256-i1"),
            ("raymarch", "n64-i4"),
            ("minmax", "minmax"),
            ("partial_sum_tree", "r4-ep512-s1"),
            ("partial_sum_tree", "r4-ep512-s1-512x512"),
            ("hybrid_volume", "n32"),
        ] {
            if let Some((t, e)) = headline_mean(family, knobs) {
                out.push(format!(
                    "headline 1280x720, means over sphere, foliage and terrain (ordinary): {family} {knobs} {t:.1} ms at rel L1 {:.3} % / prefiltered {PREFILTERED_DEFAULT} {pt:.1} ms at {:.3} %: {:.2}x the time, {} error",
                    100.0 * e,
                    100.0 * pe,
                    t / pt,
                    if e <= pe { "equal or lower" } else { "higher" }
                ));
            }
        }
    }
    // Issue 16: hybrid_volume at the headline against brute-force marching, minmax and the
    // prefiltered default (time and error from the same runs).
    if let Some((ht, he)) = headline_mean("hybrid_volume", "n32") {
        for (family, knobs) in [
            ("raymarch", "n64-i1"),
            ("raymarch", "n128-i1"),
            ("raymarch", "n256-i1"),
            ("minmax", "minmax"),
            ("prefiltered", PREFILTERED_DEFAULT),
        ] {
            if let Some((t, e)) = headline_mean(family, knobs) {
                out.push(format!(
                    "headline means (sphere, foliage, terrain): hybrid_volume n32 {ht:.1} ms at rel L1 {:.3} %; {family} {knobs} {t:.1} ms ({:.2}x the time) at {:.3} %",
                    100.0 * he,
                    t / ht,
                    100.0 * e
                ));
            }
        }
    }
    // Issue 13's targets, per prefiltered basis: the brute-force march at about the same
    // error, how much longer it takes, and whether the prefiltered error is at or below it.
    for prefiltered in [
        PREFILTERED_DEFAULT,
        "moments4-r4",
        "moments6-r4",
        "moments6-r8",
        "moments6-r16",
    ] {
        let Some((pt, pe)) = headline_mean("prefiltered", prefiltered) else {
            continue;
        };
        for (family, knobs) in [
            ("raymarch", "n64-i1"),
            ("raymarch", "n256-i1"),
            ("minmax", "minmax"),
            ("partial_sum_tree", "r4-ep512-s1"),
        ] {
            if let Some((t, e)) = headline_mean(family, knobs) {
                out.push(format!(
                    "target check, headline means: {family} {knobs} takes {:.2}x the time of prefiltered {prefiltered} ({t:.1} / {pt:.1} ms); prefiltered error {:.3} % is {} {family} {knobs}'s {:.3} %",
                    t / pt,
                    100.0 * pe,
                    if pe <= e { "at or below" } else { "above" },
                    100.0 * e
                ));
            }
        }
    }
    // Issue 13's targets over every prefiltered configuration the headline ran (either
    // basis, per pixel or sampled, either rectified map): the cheapest one at or below each
    // competitor's error, and how much longer the competitor takes.
    let mut configs: Vec<String> = result
        .headline
        .iter()
        .filter(|r| r.family == "prefiltered")
        .map(|r| r.knobs.clone())
        .collect();
    configs.sort();
    configs.dedup();
    let cheapest_at_or_below = |error: f64, measure: &dyn Fn(&str) -> Option<(f64, f64)>| {
        configs
            .iter()
            .filter_map(|k| measure(k).map(|m| (k.clone(), m)))
            .filter(|(_, m)| m.1 <= error)
            .min_by(|a, b| a.1.0.total_cmp(&b.1.0))
    };
    for (family, knobs, target) in [("raymarch", "n64-i1", 3.0), ("raymarch", "n256-i1", 5.0)] {
        let Some((t, e)) = headline_mean(family, knobs) else {
            continue;
        };
        out.push(
            match cheapest_at_or_below(e, &|k| headline_mean("prefiltered", k)) {
                Some((k, (pt, pe))) => format!(
                    "best prefiltered configuration at or below {family} {knobs}'s error, headline means: prefiltered {k} {pt:.1} ms at rel L1 {:.3} % / {family} {knobs} {t:.1} ms at {:.3} %: {family} takes {:.2}x the time (issue 13's target: {target}x)",
                    100.0 * pe,
                    100.0 * e,
                    t / pt
                ),
                None => format!(
                    "best prefiltered configuration at or below {family} {knobs}'s error, headline means: none of the {} the headline ran reaches {:.3} %",
                    configs.len(),
                    100.0 * e
                ),
            },
        );
    }
    let on_foliage = |family: &str, knobs: &str| {
        result
            .headline
            .iter()
            .find(|r| r.family == family && r.knobs == knobs && r.scene == SceneName::Foliage)
            .and_then(|r| r.rel_l1_shadow_map.map(|e| (ms(r.total()), e)))
    };
    if let Some((t, e)) = on_foliage("minmax", "minmax") {
        out.push(
            match cheapest_at_or_below(e, &|k| on_foliage("prefiltered", k)) {
                Some((k, (pt, pe))) => format!(
                    "best prefiltered configuration at or below minmax's error on foliage/ordinary at 1280x720: prefiltered {k} {pt:.1} ms at rel L1 {:.3} % / minmax {t:.1} ms at {:.3} %: minmax takes {:.2}x the time (issue 13's target: more than 1x)",
                    100.0 * pe,
                    100.0 * e,
                    t / pt
                ),
                None => format!(
                    "best prefiltered configuration at or below minmax's error on foliage/ordinary at 1280x720: none of the {} the headline ran reaches {:.3} %",
                    configs.len(),
                    100.0 * e
                ),
            },
        );
    }
    // The same comparison along minmax's whole speed-error curve on foliage: for every
    // minmax configuration the headline ran (per pixel, sampled, either map), the cheapest
    // prefiltered one at or below its error. Where the prefiltered curve lies below
    // minmax's, and where it stops (the error it cannot reach), read from one run.
    let mut minmax_configs: Vec<(String, (f64, f64))> = result
        .headline
        .iter()
        .filter(|r| r.family == "minmax" && r.scene == SceneName::Foliage)
        .filter_map(|r| on_foliage("minmax", &r.knobs).map(|m| (r.knobs.clone(), m)))
        .collect();
    minmax_configs.sort_by(|a, b| a.1.1.total_cmp(&b.1.1));
    minmax_configs.dedup_by(|a, b| a.0 == b.0);
    for (knobs, (t, e)) in &minmax_configs {
        out.push(
            match cheapest_at_or_below(*e, &|k| on_foliage("prefiltered", k)) {
                Some((k, (pt, pe))) => format!(
                    "foliage/ordinary at 1280x720, minmax {knobs} {t:.1} ms at rel L1 {:.3} %: the cheapest prefiltered configuration at or below its error, {k}, {pt:.1} ms at {:.3} %: {}",
                    100.0 * e,
                    100.0 * pe,
                    if pt < *t {
                        format!("minmax takes {:.2}x the time", t / pt)
                    } else {
                        format!("prefiltered takes {:.2}x the time", pt / t)
                    }
                ),
                None => format!(
                    "foliage/ordinary at 1280x720, minmax {knobs} {t:.1} ms at rel L1 {:.3} %: no prefiltered configuration of the {} reaches its error",
                    100.0 * e,
                    configs.len()
                ),
            },
        );
    }
    // Issue 14: each family sampled against itself per pixel, and the best sampled
    // configuration against brute-force raymarch n256 at equal or lower error.
    let mut best: Option<(String, f64, f64)> = None;
    for (px, m) in sampled_variants() {
        let Some((pt, pe)) = headline_mean(px.family(), &px.knobs()) else {
            continue;
        };
        {
            if let Some((t, e)) = headline_mean(m.family(), &m.knobs()) {
                out.push(format!(
                    "sampled vs per pixel, headline means: {} {} {t:.1} ms at rel L1 {:.3} % / {} {pt:.1} ms at {:.3} %: {:.2}x faster, {:+.3} points",
                    m.family(),
                    m.knobs(),
                    100.0 * e,
                    px.knobs(),
                    100.0 * pe,
                    pt / t,
                    100.0 * (e - pe)
                ));
                if best.as_ref().is_none_or(|b| t < b.1) {
                    best = Some((format!("{} {}", m.family(), m.knobs()), t, e));
                }
            }
        }
    }
    if let (Some((name, _, _)), Some((rt, re))) = (&best, headline_mean("raymarch", "n256-i1")) {
        // The fastest sampled configuration whose error is at or below raymarch n256's.
        let mut at_error: Option<(String, f64, f64)> = None;
        for (_, m) in sampled_variants() {
            if let Some((t, e)) = headline_mean(m.family(), &m.knobs())
                && e <= re
                && at_error.as_ref().is_none_or(|b| t < b.1)
            {
                at_error = Some((format!("{} {}", m.family(), m.knobs()), t, e));
            }
        }
        match at_error {
            Some((n, t, e)) => out.push(format!(
                "best sampled configuration vs brute-force raymarch n256 at equal or lower error, headline means: {n} {t:.1} ms at rel L1 {:.3} % / raymarch n256-i1 {rt:.1} ms at {:.3} %: {:.1}x faster (Yusov 2013: 33x)",
                100.0 * e,
                100.0 * re,
                rt / t
            )),
            None => out.push(format!(
                "best sampled configuration vs brute-force raymarch n256: no sampled configuration reaches its rel L1 {:.3} % (the fastest sampled: {name})",
                100.0 * re
            )),
        }
    }
    for family_knobs in [
        ("prefiltered", PREFILTERED_DEFAULT),
        ("raymarch", "n64-i1"),
        ("minmax", "minmax"),
    ] {
        let t = |scene: SceneName| {
            result
                .headline
                .iter()
                .find(|r| {
                    r.family == family_knobs.0 && r.knobs == family_knobs.1 && r.scene == scene
                })
                .map(|r| ms(r.total()))
        };
        if let (Some(f), Some(s)) = (t(SceneName::Foliage), t(SceneName::Sphere)) {
            out.push(format!(
                "scene independence at 1280x720, {} {}: time(foliage) / time(sphere) = {f:.1} / {s:.1} ms = {:.2}",
                family_knobs.0,
                family_knobs.1,
                f / s
            ));
        }
    }
    for scene in [SceneName::Foliage, SceneName::Terrain] {
        let sweep = |family: &str| {
            result
                .rows
                .iter()
                .find(|r| {
                    r.family == family
                        && (r.knobs == PREFILTERED_DEFAULT || family == "minmax")
                        && r.scene == scene.name()
                        && r.pose == Pose::Ordinary.name()
                })
                .map(|r| (ms(r.total()), r.rel_l1_shadow_map))
        };
        if let (Some(p), Some(m)) = (sweep("prefiltered"), sweep("minmax")) {
            out.push(format!(
                "{scene}/ordinary at the sweep size: minmax {:.1} ms ({:.2} %) / prefiltered {PREFILTERED_DEFAULT} {:.1} ms ({:.2} %) = {:.2}",
                m.0,
                100.0 * m.1,
                p.0,
                100.0 * p.1,
                m.0 / p.0
            ));
        }
        let head = |family: &str, knobs: &str| {
            result
                .headline
                .iter()
                .find(|r| r.family == family && r.knobs == knobs && r.scene == scene)
                .map(|r| ms(r.total()))
        };
        if let (Some(p), Some(m)) = (
            head("prefiltered", PREFILTERED_DEFAULT),
            head("minmax", "minmax"),
        ) {
            out.push(format!(
                "{scene}/ordinary at 1280x720, 1024x1024 rectified: minmax {m:.1} ms / prefiltered {PREFILTERED_DEFAULT} {p:.1} ms = {:.2}",
                m / p
            ));
        }
    }
    for (family, knobs) in [
        ("prefiltered", PREFILTERED_DEFAULT),
        ("raymarch", "n64-i1"),
        ("minmax", "minmax"),
    ] {
        let time = |scene: SceneName| {
            result
                .rows
                .iter()
                .find(|r| {
                    r.family == family
                        && r.knobs == knobs
                        && r.scene == scene.name()
                        && r.pose == Pose::Ordinary.name()
                })
                .map(|r| ms(r.total()))
        };
        if let (Some(f), Some(s)) = (time(SceneName::Foliage), time(SceneName::Sphere)) {
            out.push(format!(
                "scene independence, {family} {knobs}: time(foliage) / time(sphere) = {f:.2} / {s:.2} ms = {:.2}",
                f / s
            ));
        }
    }
    if let Some(base) = result
        .scaling
        .iter()
        .find(|r| r.screen == [1280, 720] && r.rectified == [512, 1024])
    {
        let b: f64 = base.passes.iter().copied().map(ms).sum();
        for r in &result.scaling {
            let t: f64 = r.passes.iter().copied().map(ms).sum();
            out.push(format!(
                "prefiltered {PREFILTERED_DEFAULT} scaling, {}x{} screen, {}x{} rectified: {:.1} ms (depth_columns {:.1}, slice_fit {:.1}, rectify {:.1}, prefilter {:.1}, scatter {:.1}) = {:.2}x the 1280x720 / 512x1024 time",
                r.screen[0],
                r.screen[1],
                r.rectified[0],
                r.rectified[1],
                t,
                ms(r.passes[0]),
                ms(r.passes[1]),
                ms(r.passes[2]),
                ms(r.passes[3]),
                ms(r.passes[4]),
                t / b
            ));
        }
    }
    out
}

/// The CSV: one line per run.
pub fn csv(result: &BenchResult) -> String {
    let mut s = String::from(
        "family,variant,scene,pose,rel_l1_exact,rel_l1_shadow_map,non_finite,total_ms,passes,gpu_timestamps_ms\n",
    );
    for r in &result.rows {
        let passes: Vec<String> = r
            .passes
            .iter()
            .map(|(n, d)| format!("{n}={:.3}", ms(*d)))
            .collect();
        let _ = writeln!(
            s,
            "{},{},{},{},{:.6},{:.6},{},{:.3},{},{}",
            r.family,
            r.variant,
            r.scene,
            r.pose,
            r.rel_l1_exact,
            r.rel_l1_shadow_map,
            r.non_finite,
            ms(r.total()),
            passes.join(";"),
            r.gpu_timestamps
                .map_or_else(String::new, |d| format!("{:.3}", ms(d)))
        );
    }
    s
}

/// The markdown report: configuration, ratios, per-variant means, every run.
pub fn markdown(result: &BenchResult, command: &str) -> String {
    let c = &result.config;
    let mut s = String::new();
    let _ = writeln!(s, "# scatter bench\n");
    let _ = writeln!(
        s,
        "`{command}` on {} in {:.0} s: {} runs, {}x{} screen, {}x{} rectified map (prefiltered), {}^2 shadow map, times = median pass wall time over {} frame(s) (each pass submitted alone).\n",
        result.adapter,
        result.elapsed.as_secs_f64(),
        result.rows.len(),
        c.screen[0],
        c.screen[1],
        c.rectified[0],
        c.rectified[1],
        c.shadow_map,
        c.frames
    );
    if !result.probes[0].is_empty() {
        let _ = writeln!(
            s,
            "## Machine state\n\nThe probes of `bench --roofline` (docs/roofline.md) just before the run:\n\n{}\nand just after it:\n\n{}",
            crate::roofline::bounds_markdown(&result.probes[0]),
            crate::roofline::bounds_markdown(&result.probes[1])
        );
    }
    let _ = writeln!(s, "## Ratios (one run)\n");
    for r in ratios(result) {
        let _ = writeln!(s, "- {r}");
    }
    if !result.headline.is_empty() {
        let _ = writeln!(
            s,
            "\n## Headline configuration (1280x720, 1024x1024 rectified)\n"
        );
        let _ = writeln!(
            s,
            "| family | variant | scene | time (ms) | rel L1 vs shadow_map truth | passes (ms) |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|");
        for r in &result.headline {
            let passes: Vec<String> = r
                .passes
                .iter()
                .map(|(n, d)| format!("{n} {:.1}", ms(*d)))
                .collect();
            let error = r
                .rel_l1_shadow_map
                .map_or("-".to_owned(), |e| format!("{:.2} %", 100.0 * e));
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.1} | {error} | {} |",
                r.family,
                r.knobs,
                r.scene,
                ms(r.total()),
                passes.join(", ")
            );
        }
    }
    let _ = writeln!(s, "\n## Per variant (means over the scenes and poses)\n");
    let _ = writeln!(
        s,
        "| family | variant | time (ms) | rel L1 vs shadow_map truth | rel L1 vs exact truth |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for (family, knobs, t, es, ee) in per_variant(&result.rows) {
        let _ = writeln!(
            s,
            "| {family} | {knobs} | {t:.2} | {:.3} % | {:.3} % |",
            100.0 * es,
            100.0 * ee
        );
    }
    let _ = writeln!(s, "\n## Every run\n");
    let _ = writeln!(
        s,
        "| family | variant | scene | pose | rel L1 shadow_map | rel L1 exact | NaN/Inf | time (ms) | passes (ms) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for r in &result.rows {
        let passes: Vec<String> = r
            .passes
            .iter()
            .map(|(n, d)| format!("{n} {:.2}", ms(*d)))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.3} % | {:.3} % | {} | {:.2} | {} |",
            r.family,
            r.variant,
            r.scene,
            r.pose,
            100.0 * r.rel_l1_shadow_map,
            100.0 * r.rel_l1_exact,
            r.non_finite,
            ms(r.total()),
            passes.join(", ")
        );
    }
    s
}

const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// The chart's colour of a family (an exhaustive match: a new family must pick one).
fn family_colour(family: Family) -> plotters::style::RGBColor {
    use plotters::style::colors::{BLUE, GREEN, MAGENTA, RED};
    match family {
        Family::Prefiltered => RED,
        Family::Raymarch => BLUE,
        Family::Minmax => GREEN,
        Family::PartialSumTree => MAGENTA,
        Family::HybridVolume => plotters::style::RGBColor(230, 140, 0),
        Family::AreaIvsv => plotters::style::RGBColor(0, 150, 150),
    }
}

/// Draws the chart into any plotters backend: x = time (log), y = mean rel L1 vs the
/// `shadow_map` truth (log), one marker per variant, one colour per family, the Pareto
/// front of all variants as a line.
fn draw<DB: plotters::prelude::DrawingBackend>(
    root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    result: &BenchResult,
) -> Result<(), BoxError>
where
    DB::ErrorType: 'static,
{
    use plotters::prelude::*;
    root.fill(&WHITE)?;
    let v = per_variant(&result.rows);
    let pts: Vec<(f64, f64)> = v
        .iter()
        .map(|p| (p.2.max(1e-3), (100.0 * p.3).max(1e-3)))
        .collect();
    let (xmin, xmax) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (ymin, ymax) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "scatter: error vs time ({}x{}, {})",
                result.config.screen[0],
                result.config.screen[1],
                result.adapter.split(" (").next().unwrap_or("")
            ),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (xmin / 1.5..xmax * 1.5).log_scale(),
            (ymin / 1.5..ymax * 1.5).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("time per frame, sum of pass wall times (ms, log)")
        .y_desc("mean rel L1 vs shadow_map truth (%, log)")
        .label_style(("sans-serif", 12))
        .draw()?;
    let front = pareto(&pts);
    chart
        .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1)))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK));
    for &family in Family::ALL {
        let colour = family_colour(family);
        let family = family.name();
        let sel: Vec<_> = v.iter().zip(&pts).filter(|(p, _)| p.0 == family).collect();
        if sel.is_empty() {
            continue;
        }
        chart
            .draw_series(
                sel.iter()
                    .map(|(_, p)| Circle::new(**p, 5, colour.filled())),
            )?
            .label(family)
            .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
        chart.draw_series(
            sel.iter()
                .map(|(v, p)| Text::new(v.1.clone(), **p, ("sans-serif", 11).into_font())),
        )?;
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .draw()?;
    root.present()?;
    Ok(())
}

/// Writes `bench.csv`, `bench.md` and, when a DejaVu Sans font is installed (Debian's
/// fonts-dejavu-core, which `scripts/test.sh` installs), `bench.svg` and `bench.png` into
/// `dir`, each atomically. Returns the paths written.
///
/// # Errors
///
/// I/O or drawing errors.
pub fn write_outputs(
    result: &BenchResult,
    dir: &Path,
    command: &str,
) -> Result<Vec<PathBuf>, BoxError> {
    use plotters::prelude::IntoDrawingArea as _;
    std::fs::create_dir_all(dir)?;
    let mut written = Vec::new();
    let csv_path = dir.join("bench.csv");
    write_atomic(&csv_path, csv(result).as_bytes())?;
    written.push(csv_path);
    let md_path = dir.join("bench.md");
    write_atomic(&md_path, markdown(result, command).as_bytes())?;
    written.push(md_path);
    // plotters lays text out with a TTF font (no system font libraries): without one the
    // chart is skipped, the tables are not.
    if register_chart_font().is_none() {
        eprintln!(
            "bench: no DejaVu Sans font ({}); install Debian's fonts-dejavu-core for the chart",
            FONT_PATHS.join(", ")
        );
        return Ok(written);
    }
    let mut svg = String::new();
    {
        let root =
            plotters::prelude::SVGBackend::with_string(&mut svg, (900, 600)).into_drawing_area();
        draw(root, result)?;
    }
    let svg_path = dir.join("bench.svg");
    write_atomic(&svg_path, svg.as_bytes())?;
    written.push(svg_path);
    let (w, h) = (900u32, 600u32);
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    {
        let root =
            plotters::prelude::BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        draw(root, result)?;
    }
    let png_path = dir.join("bench.png");
    write_png_rgb8(&png_path, w, h, &pixels)?;
    written.push(png_path);
    Ok(written)
}

/// One point of [`write_area_chart`]: a method's mean error (%) and time (ms).
#[derive(Clone, Debug)]
pub struct AreaPoint {
    /// `area_ivsv` or the competitor's family (`raymarch`): the colour.
    pub family: Family,
    /// The VPL count: points of one count and family are joined by a line.
    pub vpls: u32,
    /// The label beside the marker.
    pub label: String,
    /// Time per frame (ms).
    pub ms: f64,
    /// Mean error (%).
    pub error_pct: f64,
}

/// Registers DejaVu Sans as plotters' `sans-serif`, or `None` without one installed.
fn register_chart_font() -> Option<()> {
    let font = FONT_PATHS.iter().find_map(|p| std::fs::read(p).ok())?;
    let font: &'static [u8] = Box::leak(font.into_boxed_slice());
    plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, font).ok()
}

fn draw_area<DB: plotters::prelude::DrawingBackend>(
    root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    y_desc: &str,
    points: &[AreaPoint],
) -> Result<(), BoxError>
where
    DB::ErrorType: 'static,
{
    use plotters::prelude::*;
    root.fill(&WHITE)?;
    let pts: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (p.ms.max(1e-3), p.error_pct.max(1e-3)))
        .collect();
    let (xmin, xmax) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (ymin, ymax) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (xmin / 1.5..xmax * 1.5).log_scale(),
            (ymin / 1.5..ymax * 1.5).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("time per frame, sum of pass wall times (ms, log)")
        .y_desc(y_desc)
        .label_style(("sans-serif", 12))
        .draw()?;
    let mut series: Vec<(Family, u32)> = points.iter().map(|p| (p.family, p.vpls)).collect();
    series.sort();
    series.dedup();
    for (family, vpls) in series {
        let colour = family_colour(family);
        let mut sel: Vec<(&AreaPoint, (f64, f64))> = points
            .iter()
            .zip(pts.iter().copied())
            .filter(|(p, _)| p.family == family && p.vpls == vpls)
            .collect();
        sel.sort_by(|a, b| a.1.0.total_cmp(&b.1.0));
        // A competitor's points are one knob's sweep (joined); area_ivsv's are different
        // gathers of one VPL count (interleaved, sampled), each on its own.
        let joined = if family == Family::AreaIvsv {
            Vec::new()
        } else {
            sel.iter().map(|s| s.1).collect()
        };
        chart
            .draw_series(LineSeries::new(joined, colour.stroke_width(1)))?
            .label(format!("{family} N={vpls}"))
            .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
        chart.draw_series(sel.iter().map(|s| Circle::new(s.1, 5, colour.filled())))?;
        chart.draw_series(
            sel.iter()
                .map(|s| Text::new(s.0.label.clone(), s.1, ("sans-serif", 11).into_font())),
        )?;
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .draw()?;
    root.present()?;
    Ok(())
}

/// Writes `<stem>.svg` and `<stem>.png` into `dir` (atomically): `points` on log-log axes of
/// time and error, one line per competitor and VPL count, `area_ivsv`'s points unjoined
/// (`examples/area_bench`'s chart). Skipped
/// (an empty list) without a DejaVu Sans font.
///
/// # Errors
///
/// I/O or drawing errors.
pub fn write_area_chart(
    dir: &Path,
    stem: &str,
    title: &str,
    y_desc: &str,
    points: &[AreaPoint],
) -> Result<Vec<PathBuf>, BoxError> {
    use plotters::prelude::IntoDrawingArea as _;
    if points.is_empty() || register_chart_font().is_none() {
        eprintln!(
            "chart skipped: no points, or no DejaVu Sans font ({})",
            FONT_PATHS.join(", ")
        );
        return Ok(Vec::new());
    }
    std::fs::create_dir_all(dir)?;
    let mut svg = String::new();
    {
        let root =
            plotters::prelude::SVGBackend::with_string(&mut svg, (900, 600)).into_drawing_area();
        draw_area(root, title, y_desc, points)?;
    }
    let svg_path = dir.join(format!("{stem}.svg"));
    write_atomic(&svg_path, svg.as_bytes())?;
    let (w, h) = (900u32, 600u32);
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    {
        let root =
            plotters::prelude::BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        draw_area(root, title, y_desc, points)?;
    }
    let png_path = dir.join(format!("{stem}.png"));
    write_png_rgb8(&png_path, w, h, &pixels)?;
    Ok(vec![svg_path, png_path])
}

/// The `tune` first-stage grid: prefiltered (M, R) over {16, 32, 64} x {1, 4, 8, 16} (the
/// default bases per thread, rgba8unorm) and the moment basis with 4 or 6 moments and 4, 8
/// or 16 regions (16: the moment basis's most accurate configuration since stop 56), each
/// with a 512x512 and a 256x256 rectified map (16 regions need 256 columns on a directional
/// row),
/// raymarch N over {16, 32, 64, 128, 256, 512} plus interleaved (64, 4x4) and (256, 4x4),
/// minmax with both maps; for an area light (a case runs only the methods of its light),
/// `area_ivsv` with 16, 64 and 256 VPLs, two grid sizes, the interleaved gather, and 64
/// VPLs at lowres 2 and epipolar; the sampled configurations of every family's default, and
/// of the prefiltered default at `filtered_stride` 8 with `resume`. Run it
/// with `BenchConfig::rectified` = 512x512.
pub fn tune_candidates() -> Vec<Method> {
    let mut out = Vec::new();
    // Issue 17: area lights, the VPL count (how soft a shadow needs), the grid, the gather.
    for (vpls, bins, interleave) in [
        (16, 256, 1),
        (64, 128, 1),
        (64, 256, 1),
        (64, 256, 2),
        (256, 128, 1),
        (256, 128, 4),
    ] {
        out.push(Method::from(AreaIvsvVariant {
            vpls,
            alpha: bins,
            theta: bins,
            interleave,
            ..AreaIvsvVariant::default()
        }));
    }
    // Issue 14 on area lights: the 64-VPL gather sampled (measured at the case's size, where
    // a sample stands for more of the lamp than at 1280x720: `area_bench` measures both).
    for knobs in [
        SamplingKnobs::lowres(2),
        SamplingKnobs::epipolar(SamplingKnobs::DEFAULT_SLICES),
    ] {
        out.push(Method::from(
            AreaIvsvVariant::default().with_sampling_knobs(knobs),
        ));
    }
    for rectified in [None, Some([256, 256])] {
        for bases in [16, 32, 64] {
            for regions in [1, 4, 8, 16] {
                out.push(Method::new(
                    PrefilteredVariant {
                        bases,
                        regions,
                        ..PrefilteredVariant::default()
                    },
                    rectified,
                ));
            }
        }
        for moments in PrefilteredVariant::MOMENTS {
            for regions in [4, 8, 16] {
                out.push(Method::new(
                    PrefilteredVariant {
                        regions,
                        ..PrefilteredVariant::with_moments(moments)
                    },
                    rectified,
                ));
            }
        }
    }
    // Coarse filtered columns: the default storing every 2nd and 4th column's means.
    for filtered_stride in [2, 4] {
        out.push(Method::from(PrefilteredVariant {
            filtered_stride,
            ..PrefilteredVariant::default()
        }));
    }
    for (samples, interleave) in [
        (16, 1),
        (32, 1),
        (64, 1),
        (128, 1),
        (256, 1),
        (512, 1),
        (64, 4),
        (256, 4),
    ] {
        out.push(Method::from(RaymarchVariant {
            samples,
            interleave,
            ..RaymarchVariant::default()
        }));
    }
    out.push(Method::minmax_default());
    out.push(Method::new(MinmaxVariant::default(), Some([256, 256])));
    // Issue 14: fewer samples than pixels, for every family.
    let sampled: Vec<FamilyVariant> = vec![
        PrefilteredVariant::default().into(),
        PrefilteredVariant::with_moments(4).into(),
        RaymarchVariant::default().into(),
        RaymarchVariant {
            samples: 128,
            ..RaymarchVariant::default()
        }
        .into(),
        MinmaxVariant::default().into(),
    ];
    for base in sampled {
        for knobs in sampled_configs() {
            out.push(Method::from(base.with_sampling(knobs)));
        }
    }
    // The prefiltered default storing every eighth column and resuming between them
    // (`resume`: the default's answer from an eighth of `prefilter`'s stores, for frames that
    // look the map up at few points; docs/roofline.md, "Stop 58").
    let resume8: FamilyVariant = PrefilteredVariant {
        filtered_stride: 8,
        resume: true,
        ..PrefilteredVariant::default()
    }
    .into();
    for knobs in sampled_configs() {
        out.push(Method::from(resume8.with_sampling(knobs)));
    }
    // Issue 15: partial-sum trees (epipolar samples only): the rank, and the layout.
    for rank in [2, 4, 8] {
        for (slices, slice_samples) in [(256, 256), (512, 256), (1024, 512)] {
            out.push(Method::from(PartialSumTreeVariant {
                rank,
                slices,
                slice_samples,
                ..PartialSumTreeVariant::default()
            }));
        }
    }
    out.push(Method::new(
        PartialSumTreeVariant::default(),
        Some([512, 512]),
    ));
    // Issue 16: hybrid shadow volumes: the samples in the interval, the bins, and the
    // rectified map the volume is built from.
    for samples in [8, 16, 32, 64, 128] {
        out.push(Method::from(HybridVolumeVariant {
            samples,
            ..HybridVolumeVariant::default()
        }));
    }
    for bins in [64, 1024] {
        out.push(Method::from(HybridVolumeVariant {
            bins,
            ..HybridVolumeVariant::default()
        }));
    }
    out.push(Method::new(
        HybridVolumeVariant::default(),
        Some([256, 256]),
    ));
    out
}

/// Rectified sizes the refinement steps through (square).
const TUNE_RECTIFIED: [u32; 4] = [128, 256, 512, 1024];

/// The `tune` second stage: around every prefiltered or minmax entry on its family's
/// Pareto front in the first stage (mean time against worst error; per family, so that a
/// family another dominates still gets its fixed knobs explored), the neighbours along the
/// knobs the grid held fixed: every other bases-per-thread (a multiple of 4 dividing M), the other two
/// storage formats, and the next smaller and larger square rectified map (128..1024).
/// Knobs already measured are left out. `run` is the run's rectified map.
pub fn tune_refinements(table: &[TuneEntry], run: [u32; 2]) -> Vec<Method> {
    let front: Vec<&TuneEntry> = ["prefiltered", "minmax"]
        .into_iter()
        .flat_map(|family| {
            let own: Vec<TuneEntry> = table
                .iter()
                .filter(|e| e.family == family)
                .cloned()
                .collect();
            pareto_entries(&own)
                .into_iter()
                .filter_map(|f| {
                    table
                        .iter()
                        .find(|e| e.family == f.family && e.knobs == f.knobs)
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let mut out: Vec<Method> = Vec::new();
    let mut push = |m: Method| {
        let known = |k: &Method| k.knobs() == m.knobs() && k.family() == m.family();
        if !out.iter().any(known) && !table.iter().any(|e| known(&e.method)) {
            out.push(m);
        }
    };
    let rect_steps = |r: [u32; 2]| -> Vec<[u32; 2]> {
        let Some(i) = TUNE_RECTIFIED
            .iter()
            .position(|&w| w == r[0] && r[0] == r[1])
        else {
            return Vec::new();
        };
        [i.checked_sub(1), Some(i + 1)]
            .into_iter()
            .flatten()
            .filter_map(|j| TUNE_RECTIFIED.get(j).map(|&w| [w, w]))
            .collect()
    };
    let rect_knob = |r: [u32; 2]| (r != run).then_some(r);
    for e in front {
        let m = e.method;
        // The knobs only the prefiltered family has.
        if let FamilyVariant::Prefiltered(v) = m.variant
            && v.basis == Basis::Fourier
        {
            for bpt in (4..=v.bases).step_by(4) {
                if bpt != v.bases_per_thread && v.bases.is_multiple_of(bpt) {
                    push(Method::new(
                        PrefilteredVariant {
                            bases_per_thread: bpt,
                            ..v
                        },
                        m.rectified,
                    ));
                }
            }
            for &storage in Storage::ALL {
                if storage != v.storage {
                    push(Method::new(
                        PrefilteredVariant { storage, ..v },
                        m.rectified,
                    ));
                }
            }
        }
        // Every family with a rectified map: the next sizes, those wide enough for the
        // variant (a prefiltered variant needs `filtered_stride x regions^2` columns: 16
        // regions have no 128-column neighbour, which the frame set-up would refuse).
        if let Some(rect) = m.rectified(run) {
            for step in rect_steps(rect) {
                if m.variant.fits_rectified_width(step[0]) {
                    push(Method::new(m.variant, rect_knob(step)));
                }
            }
        }
    }
    out
}

/// The entries on the Pareto front of (mean time, worst error), cheapest first.
pub fn pareto_entries(table: &[TuneEntry]) -> Vec<&TuneEntry> {
    let mut sorted: Vec<&TuneEntry> = table.iter().collect();
    sorted.sort_by(|a, b| {
        a.mean_ms
            .total_cmp(&b.mean_ms)
            .then(a.worst_error.total_cmp(&b.worst_error))
    });
    let mut front: Vec<&TuneEntry> = Vec::new();
    for e in sorted {
        if front.last().is_none_or(|l| e.worst_error < l.worst_error) {
            front.push(e);
        }
    }
    front
}

/// One `tune` candidate's measurements over a scene's poses.
#[derive(Clone, Debug, PartialEq)]
pub struct TuneEntry {
    /// Family.
    pub family: &'static str,
    /// Knobs without the light.
    pub knobs: String,
    /// The method (with the scene's light).
    pub method: Method,
    /// Worst rel L1 against the `shadow_map` truth over the poses.
    pub worst_error: f64,
    /// Mean time over the poses (ms).
    pub mean_ms: f64,
}

/// Per candidate: the worst error and the mean time over the runs of `rows`, sorted by time.
pub fn tune_table(rows: &[Row]) -> Vec<TuneEntry> {
    let mut out: Vec<(TuneEntry, usize)> = Vec::new();
    for r in rows {
        let t = ms(r.total());
        match out
            .iter_mut()
            .find(|(e, _)| e.family == r.family && e.knobs == r.knobs)
        {
            Some((e, n)) => {
                e.worst_error = e.worst_error.max(r.rel_l1_shadow_map);
                e.mean_ms += t;
                *n += 1;
            }
            None => out.push((
                TuneEntry {
                    family: r.family,
                    knobs: r.knobs.clone(),
                    method: r.method,
                    worst_error: r.rel_l1_shadow_map,
                    mean_ms: t,
                },
                1,
            )),
        }
    }
    let mut out: Vec<TuneEntry> = out
        .into_iter()
        .map(|(mut e, n)| {
            e.mean_ms /= n as f64;
            e
        })
        .collect();
    out.sort_by(|a, b| a.mean_ms.total_cmp(&b.mean_ms));
    out
}

/// The cheapest entry whose worst error is within `budget` (a fraction, 0.02 = 2 %).
pub fn tune_pick(table: &[TuneEntry], budget: f64) -> Option<&TuneEntry> {
    table
        .iter()
        .filter(|e| e.worst_error <= budget)
        .min_by(|a, b| a.mean_ms.total_cmp(&b.mean_ms))
}

/// The `scatter-gen` command line that emits a tune choice (every knob spelled out, the
/// light included), followed for the families with a rectified map by the size to give
/// the runtime (`Resolutions::rectified`; it is not a shader knob). `run` is the run's
/// rectified map.
pub fn scatter_gen_command(method: &Method, run: [u32; 2]) -> String {
    let rect = method
        .rectified(run)
        .map(|[w, h]| format!("  # runtime: rectified map {w}x{h}"))
        .unwrap_or_default();
    let knobs: String = method
        .variant
        .knob_values()
        .iter()
        .map(|(k, v)| format!(" --{} {v}", k.replace('_', "-")))
        .collect();
    format!(
        "scatter-gen --family {}{knobs} --out shaders/{rect}",
        method.family()
    )
}

/// The light of a suite scene.
pub fn scene_light(name: SceneName) -> LightKind {
    light_of(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefiltered_default_names_the_default_variant() {
        assert_eq!(
            Method::from(PrefilteredVariant::default()).knobs(),
            PREFILTERED_DEFAULT
        );
    }

    fn entry(method: Method, worst_error: f64, mean_ms: f64) -> TuneEntry {
        TuneEntry {
            family: method.family(),
            knobs: method.knobs(),
            method,
            worst_error,
            mean_ms,
        }
    }

    fn march(samples: u32) -> Method {
        Method::from(RaymarchVariant {
            samples,
            ..RaymarchVariant::default()
        })
    }

    #[test]
    fn tune_picks_the_cheapest_within_budget() {
        let spot = Method::new(
            PrefilteredVariant {
                light: LightKind::Spot,
                ..PrefilteredVariant::default()
            },
            Some([256, 256]),
        );
        let table = vec![
            entry(march(16), 0.10, 5.0),
            entry(march(64), 0.03, 20.0),
            entry(spot, 0.019, 60.0),
            entry(march(256), 0.006, 80.0),
        ];
        assert_eq!(
            tune_pick(&table, 0.05).map(|e| e.knobs.as_str()),
            Some("n64-i1")
        );
        assert_eq!(
            tune_pick(&table, 0.02).map(|e| e.knobs.as_str()),
            Some("m32-r4-256x256")
        );
        assert_eq!(
            tune_pick(&table, 0.01).map(|e| e.knobs.as_str()),
            Some("n256-i1")
        );
        assert_eq!(tune_pick(&table, 0.001), None);
        assert_eq!(
            scatter_gen_command(&table[2].method, [512, 512]),
            "scatter-gen --family prefiltered --bases 32 --bases-per-thread 16 --basis fourier --depth-break 10 --light spot --light-break 20 --moments 4 --rectification epipolar --regions 4 --sampling pixels --scale 2 --slice-samples 256 --slices 512 --step 8 --storage rgba8unorm --visibility weighted --out shaders/  # runtime: rectified map 256x256"
        );
        assert_eq!(
            scatter_gen_command(&table[1].method, [512, 512]),
            "scatter-gen --family raymarch --depth-break 10 --interleave 1 --jitter false --light directional --light-break 20 --samples 64 --sampling pixels --scale 2 --slice-samples 256 --slices 512 --step 8 --out shaders/"
        );
        // Every knob of every family's grid: the command's flags parse back to the variant.
        use scatter_gen::FamilyCli;
        for &family in Family::ALL {
            for v in family.grid() {
                let cmd = scatter_gen_command(&Method::from(v), [512, 512]);
                let words: Vec<&str> = cmd.split_whitespace().collect();
                assert_eq!(
                    words[..3],
                    ["scatter-gen", "--family", family.name()],
                    "{cmd}"
                );
                let knobs: Vec<(String, String)> = words[3..]
                    .chunks_exact(2)
                    .take_while(|kv| kv[0] != "--out")
                    .map(|kv| (kv[0][2..].replace('-', "_"), kv[1].to_owned()))
                    .collect();
                assert_eq!(family.variant(&knobs).ok(), Some(v), "{cmd}");
            }
        }
    }

    #[test]
    fn refinements_step_the_fixed_knobs_around_the_front() {
        let p = |bases, r| {
            Method::new(
                PrefilteredVariant {
                    bases,
                    ..PrefilteredVariant::default()
                },
                r,
            )
        };
        // m16 at 256^2 and m32 at 512^2 are on the prefiltered front (m32 despite the
        // cheaper, better raymarch); m64 is dominated by m32.
        let table = vec![
            entry(p(16, Some([256, 256])), 0.05, 10.0),
            entry(p(32, None), 0.02, 30.0),
            entry(march(128), 0.01, 25.0),
            entry(p(64, None), 0.025, 90.0),
        ];
        let knobs: Vec<String> = tune_refinements(&table, [512, 512])
            .iter()
            .map(Method::knobs)
            .collect();
        assert_eq!(
            knobs,
            [
                "m16-r4-t4-256x256",
                "m16-r4-t8-256x256",
                "m16-r4-rgba16float-256x256",
                "m16-r4-rgba32float-256x256",
                "m16-r4-128x128",
                "m16-r4", // 512x512 is the run's map
                "m32-r4-t4",
                "m32-r4-t8",
                "m32-r4-t32",
                "m32-r4-rgba16float",
                "m32-r4-rgba32float",
                "m32-r4-256x256",
                "m32-r4-1024x1024",
            ]
        );
        assert_eq!(
            pareto_entries(&table)
                .iter()
                .map(|e| e.knobs.as_str())
                .collect::<Vec<_>>(),
            ["m16-r4-256x256", "n128-i1"]
        );
    }

    #[test]
    fn refinements_skip_maps_too_narrow_for_the_regions() {
        // The moment basis with 16 regions at 256^2 on the front: its smaller neighbour
        // (128 columns, fewer than 16^2) is not a candidate; the larger one is.
        let m16 = Method::new(
            PrefilteredVariant {
                regions: 16,
                ..PrefilteredVariant::with_moments(6)
            },
            Some([256, 256]),
        );
        let table = vec![entry(m16, 0.01, 10.0)];
        let knobs: Vec<String> = tune_refinements(&table, [512, 512])
            .iter()
            .map(Method::knobs)
            .collect();
        assert_eq!(knobs, ["moments6-r16"]); // 512x512 is the run's map
    }
}
