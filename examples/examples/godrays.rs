//! Renders a suite scene's light shafts to PNG: a ground truth, or any kernel family.
//!
//! ```text
//! cargo run --release -p scatter-examples --example godrays -- --scene window --truth exact --out window.png
//! cargo run --release -p scatter-examples --example godrays -- --scene-file reference/scenes/mesh_grate.json --method prefiltered --gpu --out grate.png
//! ```
//!
//! `--scene-file PATH` renders a scene of one's own (JSON, `reference/scenes/README.md`; OBJ
//! meshes by `mesh_file`) instead of a suite scene, at the file's camera size unless
//! `--width`/`--height` are given; its triangle count and BVH build time are printed.
//!
//! Writes `<out>` (composite: surfaces attenuated by the fog plus in-scattering), and beside
//! it `<stem>.inscatter.png` (in-scattered radiance only, tone-mapped) and
//! `<stem>.inscatter.pfm` (the same as linear float RGB).
//!
//! `--method prefiltered | raymarch | minmax` (every family of `Family::ALL`) renders with
//! that family instead of a ground truth, through the CPU mirror of its kernels (the same
//! arithmetic as the GPU kernels; the conformance suite checks that they agree), or with
//! `--gpu` through the kernels themselves on `scatter-runtime` (lavapipe when there is no
//! GPU). `--variant` sets the family's knobs, parsed by `scatter-gen`'s knob parser
//! (`FamilyCli`, the same messages as `scatter-gen --bases ...`); the light follows the
//! scene. `--compare` also renders the `shadow_map` truth from the same shadow map, prints
//! the error and writes `<stem>.compare.png`: truth | family | 4x difference.
//!
//! Options that do not apply to the chosen method (`--gpu`, `--compare`, `--variant`,
//! `--rectified` with `--method truth`; `--truth` with a family; `--rectified` with a
//! family that has no rectified map; `--frames` and `--pass-wall-frames` without `--gpu`)
//! are refused with one line and exit code 2, never ignored.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use scatter_gen::{Family, FamilyCli, FamilyVariant};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::kernels::{CpuFrame, CpuRun, engine_rectified_map};
use scatter_reference::metrics;
use scatter_reference::scene::{Scene, Shape};
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_runtime::textures::upload_r32float;
use scatter_runtime::{
    Context, CpuInputs, FamilyPasses, FrameInput, HybridVolumeTimes, Inputs, MinmaxTimes,
    PartialSumTreeTimes, PrefilteredTimes, RaymarchInput, RaymarchTimes, run_hybrid_volume_once,
    run_minmax_once, run_partial_sum_tree_once, run_prefiltered_once, run_raymarch_once,
};
use scatter_shaderlib::Kernel;
use scatter_shaderlib::family::KernelFamily;
use scatter_shaderlib::prefiltered::variant::printable;
use scatter_shaderlib::prefiltered::{
    FrameReport, FrameSettings, LightKind, Resolutions, prepare_frame,
};

/// The rectified map size when `--rectified` is not given.
const DEFAULT_RECTIFIED: [u32; 2] = [1024, 1024];
/// Frames timed with `--gpu` when `--frames` is not given.
const DEFAULT_FRAMES: u32 = 5;

/// Any error of a run (printed as one line after `godrays: `).
type BoxError = Box<dyn std::error::Error>;

/// The families' names, for help and messages (`minmax | prefiltered | raymarch`).
fn family_names() -> String {
    Family::ALL
        .iter()
        .map(|f| f.name())
        .collect::<Vec<_>>()
        .join(" | ")
}

/// What renders the in-scattering: a ground truth or a kernel family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Method {
    /// A ground truth (see `--truth`).
    Truth,
    /// A kernel family.
    Family(Family),
}

fn parse_method(text: &str) -> Result<Method, String> {
    if text == "truth" {
        return Ok(Method::Truth);
    }
    text.parse().map(Method::Family).map_err(|_| {
        format!(
            "method must be truth | {}, got {}",
            family_names(),
            printable(text)
        )
    })
}

fn method_help() -> String {
    let families: Vec<String> = Family::ALL
        .iter()
        // The summary's head: the paper and the method's name.
        .map(|f| format!("`{f}` ({})", f.summary().split(':').next().unwrap_or("")))
        .collect();
    format!(
        "What renders the in-scattering: `truth` (see --truth), or a kernel family through the \
         CPU mirror of its kernels (with --gpu: the GPU kernels): {} [default: truth]",
        families.join("; ")
    )
}

fn variant_help() -> String {
    let knobs: Vec<String> = Family::ALL
        .iter()
        .map(|&f| {
            let names: Vec<&str> = f
                .knobs()
                .iter()
                .map(|k| k.name)
                .filter(|&k| k != "light")
                .collect();
            if names.is_empty() {
                format!("{f}: none")
            } else {
                format!("{f}: {}", names.join(", "))
            }
        })
        .collect();
    format!(
        "The family's knobs as knob=value pairs, e.g. `bases=64,regions=8` (prefiltered) or \
         `samples=128,interleave=2` (raymarch); knobs not named keep the defaults (the papers', but prefiltered regions = 4), the \
         light follows the scene (`scatter-gen list` shows allowed values). Knobs: {}",
        knobs.join("; ")
    )
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Truth {
    /// Visibility by casting a ray to the light.
    Exact,
    /// Visibility from the standard shadow map (nearest texel, biased).
    ShadowMap,
}

/// The demo's command line (`about` is `--help`'s headline; without it clap would show the
/// crate's description).
#[derive(Parser, Debug)]
#[command(
    name = "godrays",
    version,
    about = "Renders a suite scene's light shafts to PNG: a ground truth, or any kernel family \
             (CPU mirror, or the GPU kernels with --gpu)"
)]
struct Args {
    /// Suite scene: sphere, columns, window, foliage, terrain, spot_grate.
    #[arg(long, value_parser = |s: &str| s.parse::<SceneName>(), required_unless_present = "scene_file")]
    scene: Option<SceneName>,
    /// A scene file instead of a suite scene (JSON, reference/scenes/README.md; OBJ meshes
    /// by `mesh_file`), at its camera's size unless --width/--height are given.
    #[arg(long, value_name = "PATH", conflicts_with_all = ["scene", "pose", "medium"])]
    scene_file: Option<PathBuf>,
    /// Camera pose: ordinary, epipole_on_screen, light_behind, grazing.
    #[arg(long, default_value = "ordinary", value_parser = |s: &str| s.parse::<Pose>())]
    pose: Pose,
    /// Medium preset: default, thick, thin.
    #[arg(long, default_value = "default", value_parser = |s: &str| s.parse::<MediumPreset>())]
    medium: MediumPreset,
    #[arg(long, value_name = "METHOD", help = method_help(), default_value = "truth", hide_default_value = true, value_parser = parse_method)]
    method: Method,
    /// Which ground truth `--method truth` renders [default: exact].
    #[arg(long, value_enum)]
    truth: Option<Truth>,
    #[arg(long, value_name = "KNOBS", help = variant_help())]
    variant: Option<String>,
    /// Rectified map size of a family that has one (prefiltered, minmax), WIDTHxHEIGHT
    /// [default: 1024x1024].
    #[arg(long, value_name = "WxH")]
    rectified: Option<String>,
    /// With a family: also render the `shadow_map` truth from the same shadow map, print the
    /// error and write `<stem>.compare.png` (truth | family | 4x difference).
    #[arg(long)]
    compare: bool,
    /// With a family: run its GPU kernels through `scatter-runtime` (lavapipe when there is
    /// no GPU) instead of the CPU mirror, and print the time per pass.
    #[arg(long)]
    gpu: bool,
    /// With --gpu: frames timed (1..=100); the minimum is printed [default: 5].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100))]
    frames: Option<u32>,
    /// With --gpu: also time each pass submitted on its own and waited for (median of this
    /// many frames after a warm-up; 0 = off). This wall time is a pass's real cost on a CPU
    /// adapter such as lavapipe, whose timestamps are not usable [default: 0 on a GPU,
    /// --frames on a CPU adapter].
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=100))]
    pass_wall_frames: Option<u32>,
    /// Image width in pixels (1..=8192) [default: 640, or a scene file's].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8192))]
    width: Option<u32>,
    /// Image height in pixels (1..=8192) [default: 360, or a scene file's].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=8192))]
    height: Option<u32>,
    /// Shadow-map size for `--truth shadow-map` and every family (1..=16384).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=16384))]
    shadow_map_size: u32,
    /// Quadrature cells per view ray of a truth (--method truth, --compare) (16..=65536).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(16..=65536))]
    segments: u32,
    /// Output PNG (composite).
    #[arg(long)]
    out: PathBuf,
}

/// What to render, from arguments that have been checked against each other.
#[derive(Debug, PartialEq)]
enum Plan {
    /// A ground truth.
    Truth(Truth),
    /// A kernel family.
    Family(FamilyPlan),
}

#[derive(Debug, PartialEq)]
struct FamilyPlan {
    variant: FamilyVariant,
    /// The rectified map size; `None` for a family without a rectified map.
    rectified: Option<[u32; 2]>,
    compare: bool,
    gpu: Option<GpuPlan>,
}

#[derive(Debug, PartialEq)]
struct GpuPlan {
    frames: u32,
    /// `None`: not given (the default depends on the adapter).
    pass_wall_frames: Option<u32>,
}

/// Checks the options against the method and each other, and parses `--variant` with the
/// scene's light. Every refusal is one line naming the option.
fn check(args: &Args, light: LightKind) -> Result<Plan, String> {
    let family = match args.method {
        Method::Truth => {
            let family_only = [
                ("--gpu", args.gpu),
                ("--compare", args.compare),
                ("--variant", args.variant.is_some()),
                ("--rectified", args.rectified.is_some()),
                ("--frames", args.frames.is_some()),
                ("--pass-wall-frames", args.pass_wall_frames.is_some()),
            ];
            if let Some((flag, _)) = family_only.iter().find(|(_, given)| *given) {
                return Err(format!(
                    "{flag} applies to a kernel family (--method {}), not to --method truth",
                    family_names()
                ));
            }
            return Ok(Plan::Truth(args.truth.unwrap_or(Truth::Exact)));
        }
        Method::Family(f) => f,
    };
    if args.truth.is_some() {
        return Err(format!(
            "--truth applies to --method truth, not to --method {family} (--compare always uses \
             the shadow_map truth)"
        ));
    }
    let variant = parse_variant(family, args.variant.as_deref().unwrap_or(""), light)?;
    let has_rectified_map = variant
        .kernel_params()
        .iter()
        .any(|k| k.kernel() == Kernel::Rectify);
    let rectified = match (&args.rectified, has_rectified_map) {
        (Some(text), true) => Some(parse_size(text)?),
        (None, true) => Some(DEFAULT_RECTIFIED),
        (Some(_), false) => {
            return Err(format!(
                "--rectified does not apply to --method {family}: it has no rectified map"
            ));
        }
        (None, false) => None,
    };
    let gpu = if args.gpu {
        Some(GpuPlan {
            frames: args.frames.unwrap_or(DEFAULT_FRAMES),
            pass_wall_frames: args.pass_wall_frames,
        })
    } else {
        if let Some(flag) = [
            ("--frames", args.frames.is_some()),
            ("--pass-wall-frames", args.pass_wall_frames.is_some()),
        ]
        .iter()
        .find_map(|(flag, given)| given.then_some(flag))
        {
            return Err(format!(
                "{flag} applies with --gpu only (the CPU mirror is not timed per pass)"
            ));
        }
        None
    };
    Ok(Plan::Family(FamilyPlan {
        variant,
        rectified,
        compare: args.compare,
        gpu,
    }))
}

/// `variant` reading the scene's spot cookie where the scene has one: an error for a family
/// that reads none.
fn cookie_follows_scene(variant: FamilyVariant, scene: &Scene) -> Result<FamilyVariant, String> {
    if scene.light.cookie().is_none() {
        return Ok(variant);
    }
    variant.with_cookie(true).ok_or_else(|| {
        let with: Vec<&str> = Family::ALL
            .iter()
            .filter(|f| f.default_variant().with_cookie(true).is_some())
            .map(|f| f.name())
            .collect();
        format!(
            "the scene's spot light has a cookie, which the {} family does not read (these \
             do: {})",
            variant.family(),
            with.join(", ")
        )
    })
}

/// Parses `--variant` (`knob=value` pairs separated by commas) with `scatter-gen`'s knob
/// parser, the light set from the scene.
fn parse_variant(family: Family, text: &str, light: LightKind) -> Result<FamilyVariant, String> {
    let mut knobs = Vec::new();
    for pair in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (k, v) = pair
            .split_once('=')
            .ok_or_else(|| format!("--variant: expected knob=value, got '{}'", printable(pair)))?;
        let k = k.trim();
        if k == "light" {
            return Err(format!(
                "--variant: the light follows the scene ({light} here); leave `light` out"
            ));
        }
        if k == "cookie" {
            return Err(
                "--variant: the cookie follows the scene (its spot's `cookie` entry); leave \
                 `cookie` out"
                    .to_owned(),
            );
        }
        knobs.push((k.to_owned(), v.trim().to_owned()));
    }
    knobs.push(("light".to_owned(), light.to_string()));
    family
        .variant(&knobs)
        .map_err(|e| format!("--variant: {e}"))
}

fn parse_size(text: &str) -> Result<[u32; 2], String> {
    let err = || {
        format!(
            "--rectified must be WIDTHxHEIGHT with both in 1..=16384, got '{}'",
            printable(text)
        )
    };
    let (w, h) = text.split_once('x').ok_or_else(err)?;
    let w: u32 = w.parse().map_err(|_| err())?;
    let h: u32 = h.parse().map_err(|_| err())?;
    if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
        return Err(err());
    }
    Ok([w, h])
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("godrays: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &Args) -> Result<(), BoxError> {
    if args.out.extension().and_then(|e| e.to_str()) != Some("png") {
        return Err(format!("--out must name a .png file, got {}", args.out.display()).into());
    }
    let scene = match (&args.scene_file, args.scene) {
        (Some(path), _) => {
            let mut scene =
                Scene::load(path).map_err(|e| format!("--scene-file {}: {e}", path.display()))?;
            scene.camera.width = args.width.unwrap_or(scene.camera.width);
            scene.camera.height = args.height.unwrap_or(scene.camera.height);
            scene
        }
        (None, Some(name)) => suite::scene(
            name,
            args.pose,
            args.medium,
            args.width.unwrap_or(640),
            args.height.unwrap_or(360),
        ),
        (None, None) => return Err("give --scene NAME or --scene-file PATH".into()),
    };
    scene.validate()?;
    let light = scene.light.kind();
    let mut plan = check(args, light)?;
    if let Plan::Family(p) = &mut plan {
        p.variant = cookie_follows_scene(p.variant, &scene)?;
    }
    let (width, height) = (scene.camera.width, scene.camera.height);
    let t0 = Instant::now();
    let bvh = Bvh::build(&scene.geometry);
    let bvh_time = t0.elapsed();
    let t0 = Instant::now();
    let gbuf = GBuffer::cast(&scene, &bvh);
    eprintln!(
        "{}: {} occluders ({} triangles), {} primitives, BVH built in {:.2?}; depth buffer {width}x{height} in {:.2?}",
        scene.name,
        scene.occluder_count(),
        scene
            .geometry
            .iter()
            .filter(|s| matches!(s, Shape::Mesh { .. } | Shape::Heightfield { .. }))
            .map(Shape::occluder_count)
            .sum::<usize>(),
        bvh.prim_count(),
        bvh_time,
        t0.elapsed()
    );
    let which = match plan {
        Plan::Family(p) => return run_family(args, &p, &scene, &bvh, &gbuf),
        Plan::Truth(which) => which,
    };
    let sm;
    let vis = match which {
        Truth::Exact => Visibility::Exact(&bvh),
        Truth::ShadowMap => {
            let t = Instant::now();
            sm = ShadowMap::build(&scene, &bvh, args.shadow_map_size)?;
            eprintln!(
                "shadow map {0}x{0} in {1:.2?}",
                args.shadow_map_size,
                t.elapsed()
            );
            Visibility::ShadowMap(&sm)
        }
    };
    let bar = ProgressBar::new(u64::from(scene.camera.height)).with_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows, eta {eta}")?
            .progress_chars("=> "),
    );
    bar.set_message(format!("truth ({which:?})"));
    let settings = TruthSettings {
        segments: args.segments as usize,
        ..TruthSettings::default()
    };
    let t = Instant::now();
    let inscatter = truth::render(&scene, &gbuf, &vis, &settings, &|| bar.inc(1));
    bar.finish_and_clear();
    eprintln!("truth in {:.2?}", t.elapsed());
    let composite = truth::surface_radiance(&scene, &gbuf, &bvh).add(&inscatter)?;

    write_outputs(args, &composite, &inscatter)
}

fn write_outputs(args: &Args, composite: &Image, inscatter: &Image) -> Result<(), BoxError> {
    let stem = args.out.with_extension("");
    let ins_png = stem.with_extension("inscatter.png");
    let ins_pfm = stem.with_extension("inscatter.pfm");
    composite.write_png(&args.out, None)?;
    inscatter.write_png(&ins_png, None)?;
    inscatter.write_pfm(&ins_pfm)?;
    eprintln!(
        "wrote {}, {}, {}",
        args.out.display(),
        ins_png.display(),
        ins_pfm.display()
    );
    Ok(())
}

/// `WxH screen[, WxH rectified]`.
fn sizes(gbuf: &GBuffer, rectified: Option<[u32; 2]>) -> String {
    let mut s = format!("{}x{} screen", gbuf.width, gbuf.height);
    if let Some([w, h]) = rectified {
        s.push_str(&format!(", {w}x{h} rectified"));
    }
    s
}

fn run_family(
    args: &Args,
    plan: &FamilyPlan,
    scene: &Scene,
    bvh: &Bvh,
    gbuf: &GBuffer,
) -> Result<(), BoxError> {
    let variant = plan.variant;
    let family = variant.family();
    let t = Instant::now();
    let sm = ShadowMap::build(scene, bvh, args.shadow_map_size)?;
    eprintln!(
        "shadow map {0}x{0} in {1:.2?}",
        args.shadow_map_size,
        t.elapsed()
    );
    let t = Instant::now();
    let settings = FrameSettings::for_screen(scene.camera.width, scene.camera.height);
    let rectified = plan.rectified.unwrap_or(DEFAULT_RECTIFIED);
    let output = match &plan.gpu {
        Some(gpu) => run_on_gpu(gpu, plan, scene, bvh, gbuf, &sm, settings)?,
        None => {
            let run = scatter_reference::kernels::run_family(
                &variant,
                &CpuFrame {
                    scene,
                    bvh,
                    gbuf,
                    shadow_map: &sm,
                    rectified,
                    settings: &settings,
                },
            )?;
            let (output, report) = (run.output().clone(), run.report().cloned());
            eprintln!(
                "{family} {} ({}) on the CPU mirror in {:.2?}",
                variant.id(),
                sizes(gbuf, plan.rectified),
                t.elapsed()
            );
            print_report(report.as_ref());
            output
        }
    };
    let composite = truth::surface_radiance(scene, gbuf, bvh).add(&output)?;
    write_outputs(args, &composite, &output)?;
    if plan.compare {
        let bar = ProgressBar::new(u64::from(scene.camera.height)).with_style(
            ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows, eta {eta}")?
                .progress_chars("=> "),
        );
        bar.set_message("shadow_map truth");
        let settings = TruthSettings {
            segments: args.segments as usize,
            ..TruthSettings::default()
        };
        let truth = truth::render(scene, gbuf, &Visibility::ShadowMap(&sm), &settings, &|| {
            bar.inc(1)
        });
        bar.finish_and_clear();
        let report = metrics::compare(&output, &truth)?;
        println!(
            "{}: {family} {} vs shadow_map truth: {report}",
            scene.name,
            variant.id()
        );
        let diff = output.abs_diff(&truth, 4.0)?;
        let strip = Image::hstack(&[&truth, &output, &diff])?;
        let path = args.out.with_extension("").with_extension("compare.png");
        strip.write_png(&path, Some(truth.auto_exposure()))?;
        eprintln!(
            "wrote {} (truth | {family} | 4x difference)",
            path.display()
        );
    }
    Ok(())
}

/// Prints the frame report (epipolar families have one), indented under the run's line.
fn print_report(report: Option<&FrameReport>) {
    for line in report.map(describe_report).unwrap_or_default() {
        eprintln!("  {line}");
    }
}

/// The frame report of an epipolar family as a few readable lines.
fn describe_report(r: &FrameReport) -> Vec<String> {
    let mut lines = Vec::new();
    lines.push(match (&r.projective, &r.fallback) {
        (Some(maps), _) => format!(
            "rectification: projective (the engine rasterises the rectified map with {} \
             region matrices; rectify does not run)",
            maps.matrices.len()
        ),
        (None, Some(why)) => {
            format!("rectification: epipolar, the projective variant fell back: {why}")
        }
        (None, None) => format!("rectification: {}", r.rectification),
    });
    let on_screen = match (r.epipole_on_screen, r.anti_epipole_on_screen) {
        (true, true) => Some("epipole and anti-epipole on screen"),
        (true, false) => Some("epipole on screen"),
        (false, true) => Some("anti-epipole on screen"),
        (false, false) => None,
    };
    lines.push(match (on_screen, r.marched_radius_px) {
        (Some(what), Some(px)) => {
            format!("{what}: pixels within {px:.1} px of it are ray-marched")
        }
        (Some(what), None) => format!("{what}: no pixel is ray-marched"),
        (None, _) => "epipole and anti-epipole off screen: no pixel is ray-marched".to_owned(),
    });
    lines.push(format!(
        "epipolar slices: {}, at most {:.2} px apart along the screen border, {} not on screen",
        if r.full_circle {
            "the full circle around the epipole"
        } else {
            "a fan"
        },
        r.max_slice_gap_px,
        r.empty_slices
    ));
    lines
}

/// Named times, in pass order.
type PassTimes = Vec<(&'static str, Duration)>;

/// In a projective frame `depth_columns`, `slice_fit` and `rectify` do not run and are left
/// out.
fn prefiltered_times(t: PrefilteredTimes, projective: bool) -> PassTimes {
    let mut out = vec![
        (Kernel::DepthColumns.name(), t.depth_columns),
        (Kernel::SliceFit.name(), t.slice_fit),
        (Kernel::Rectify.name(), t.rectify),
        (Kernel::Prefilter.name(), t.prefilter),
        (Kernel::Scatter.name(), t.scatter),
    ];
    if t.unwarp > Duration::ZERO {
        out.push((Kernel::ScatterUnwarp.name(), t.unwarp));
        out.push((Kernel::ScatterFallback.name(), t.fallback));
    }
    if projective {
        out.drain(..3);
    }
    out
}

fn raymarch_times(t: RaymarchTimes, interleaved: bool) -> PassTimes {
    let mut out = vec![(Kernel::Raymarch.name(), t.raymarch)];
    if interleaved {
        out.push((Kernel::InterleaveSum.name(), t.interleave_sum));
    }
    if t.unwarp > Duration::ZERO {
        out.push((Kernel::RaymarchUnwarp.name(), t.unwarp));
        out.push((Kernel::RaymarchFallback.name(), t.fallback));
    }
    out
}

fn minmax_times(t: MinmaxTimes) -> PassTimes {
    let mut out = vec![
        (Kernel::DepthColumns.name(), t.depth_columns),
        (Kernel::SliceFit.name(), t.slice_fit),
        (Kernel::Rectify.name(), t.rectify),
        (Kernel::MinmaxBuild.name(), t.build),
        (Kernel::MinmaxTraverse.name(), t.march),
    ];
    if t.unwarp > Duration::ZERO {
        out.push((Kernel::MinmaxTraverseUnwarp.name(), t.unwarp));
        out.push((Kernel::MinmaxTraverseFallback.name(), t.fallback));
    }
    out
}

fn area_ivsv_times(t: scatter_runtime::AreaIvsvTimes, interleaved: bool) -> PassTimes {
    let mut out = vec![
        (Kernel::IvsvRectify.name(), t.rectify),
        (Kernel::IvsvScan.name(), t.scan),
        (Kernel::IvsvGather.name(), t.gather),
    ];
    if interleaved {
        out.push((Kernel::IvsvInterleaveSum.name(), t.interleave_sum));
    }
    out
}

fn hybrid_volume_times(t: HybridVolumeTimes) -> PassTimes {
    let mut out = vec![
        (Kernel::DepthColumns.name(), t.depth_columns),
        (Kernel::SliceFit.name(), t.slice_fit),
        (Kernel::Rectify.name(), t.rectify),
        (Kernel::VolumeBounds.name(), t.bounds),
        (Kernel::VolumeMarch.name(), t.march),
    ];
    if t.unwarp > Duration::ZERO {
        out.push((Kernel::VolumeMarchUnwarp.name(), t.unwarp));
        out.push((Kernel::VolumeMarchFallback.name(), t.fallback));
    }
    out
}

fn partial_sum_tree_times(t: PartialSumTreeTimes) -> PassTimes {
    vec![
        (Kernel::DepthColumns.name(), t.depth_columns),
        (Kernel::SliceFit.name(), t.slice_fit),
        (Kernel::Rectify.name(), t.rectify),
        (Kernel::PstSweep.name(), t.sweep),
        (Kernel::PstSweepUnwarp.name(), t.unwarp),
        (Kernel::PstSweepFallback.name(), t.fallback),
    ]
}

/// The pass-wise minimum of two frames' times.
fn min_times(a: Option<PassTimes>, b: PassTimes) -> PassTimes {
    match a {
        None => b,
        Some(a) => a
            .into_iter()
            .zip(b)
            .map(|((name, x), (_, y))| (name, x.min(y)))
            .collect(),
    }
}

/// `rectify 0.123 ms, prefilter ..., total ... ms`.
fn format_times(t: &PassTimes) -> String {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mut parts: Vec<String> = t
        .iter()
        .map(|(name, d)| format!("{name} {:.3} ms", ms(*d)))
        .collect();
    parts.push(format!(
        "total {:.3} ms",
        ms(t.iter().map(|(_, d)| *d).sum())
    ));
    parts.join(", ")
}

/// One GPU frame: output, frame report, wall time, GPU timestamps per pass.
struct GpuFrame {
    output: Vec<[f32; 4]>,
    report: Option<FrameReport>,
    wall_time: Duration,
    gpu_times: Option<PassTimes>,
}

/// Runs one GPU frame; `true` for the last one.
type FrameRunner<'a> = Box<dyn FnMut(bool) -> Result<GpuFrame, BoxError> + 'a>;

/// The scene's cookie as the runtime uploads it, for a variant that reads one.
fn cookie_texels(scene: &Scene, variant: FamilyVariant) -> Option<([u32; 2], Vec<[f32; 4]>)> {
    let cookie = scene.light.cookie().filter(|_| variant.cookie())?;
    Some(([cookie.width(), cookie.height()], cookie.rgba()))
}

/// Runs the family's GPU kernels `frames` times; prints the adapter, the frame wall time,
/// the frame report, the GPU time per pass (not on a CPU adapter, whose timestamps are not
/// usable) and the wall time per pass; returns the last output.
#[allow(clippy::too_many_arguments, reason = "the demo's inputs")]
fn run_on_gpu(
    gpu: &GpuPlan,
    plan: &FamilyPlan,
    scene: &Scene,
    bvh: &Bvh,
    gbuf: &GBuffer,
    sm: &ShadowMap,
    settings: FrameSettings,
) -> Result<Image, BoxError> {
    let ctx = Context::new()?;
    let adapter = ctx.report();
    eprintln!("GPU adapter: {adapter}");
    // On a CPU adapter (lavapipe) the per-pass wall time is the only per-pass cost worth
    // printing: measure it unless told not to.
    let pass_wall_frames =
        gpu.pass_wall_frames
            .unwrap_or(if adapter.is_cpu() { gpu.frames } else { 0 });
    let res = Resolutions {
        screen: [gbuf.width, gbuf.height],
        rectified: plan.rectified.unwrap_or(DEFAULT_RECTIFIED),
    };
    let frame = FrameInput {
        camera: scene.camera_desc(),
        light: scene.light_desc(),
        medium: scene.medium_desc(),
        shadow_map: sm.desc(),
        settings,
    };
    let variant = plan.variant;
    let mut pass_walls: Option<PassTimes> = None;
    // An area light's VPL maps (the engine's path: placed and framed by the frame set-up,
    // ray-cast here).
    let area_inputs = match &variant {
        FamilyVariant::AreaIvsv(v) => Some(scatter_reference::kernels::ivsv_inputs(
            scene, gbuf, bvh, v, sm.size,
        )?),
        _ => None,
    };
    let mut run_frame: FrameRunner<'_> = match &variant {
        FamilyVariant::AreaIvsv(v) => {
            let ctx = &ctx;
            let inputs = area_inputs.as_ref().ok_or("no VPL maps")?;
            Box::new(move |_| {
                let rb = scatter_runtime::run_area_ivsv_once(
                    ctx,
                    v,
                    res.screen,
                    &frame.camera,
                    &frame.medium,
                    &inputs.vpls,
                    sm.size,
                    &gbuf.view_depth,
                    &inputs.map_data,
                )?;
                Ok(GpuFrame {
                    output: rb.output,
                    report: None,
                    wall_time: rb.wall_time,
                    gpu_times: rb.gpu_times.map(|t| area_ivsv_times(t, v.interleave > 1)),
                })
            })
        }
        FamilyVariant::Prefiltered(v) => {
            let mut inputs = cpu_inputs(&variant, res, frame, scene, bvh, gbuf, sm, None)?;
            let ctx = &ctx;
            let pass_walls = &mut pass_walls;
            Box::new(move |last| {
                // Pass wall times once, in the last frame.
                inputs.pass_wall_frames = if last { pass_wall_frames } else { 0 };
                let rb = run_prefiltered_once(ctx, v, res, &inputs)?;
                let projective = rb.frame.report.projective.is_some();
                if let Some(t) = rb.pass_wall_times {
                    *pass_walls = Some(prefiltered_times(t, projective));
                }
                Ok(GpuFrame {
                    output: rb.output,
                    report: Some(rb.frame.report),
                    wall_time: rb.wall_time,
                    gpu_times: rb.gpu_times.map(|t| prefiltered_times(t, projective)),
                })
            })
        }
        FamilyVariant::Raymarch(v) => {
            let input = RaymarchInput::from(&frame);
            let ctx = &ctx;
            let cookie = cookie_texels(scene, variant);
            Box::new(move |_| {
                let rb = run_raymarch_once(
                    ctx,
                    v,
                    res.screen,
                    &input,
                    &gbuf.view_depth,
                    &sm.depth,
                    cookie.as_ref().map(|(size, t)| (*size, &t[..])),
                )?;
                Ok(GpuFrame {
                    output: rb.output,
                    report: None,
                    wall_time: rb.wall_time,
                    gpu_times: rb.gpu_times.map(|t| raymarch_times(t, v.interleaved())),
                })
            })
        }
        FamilyVariant::Minmax(v) => {
            let ctx = &ctx;
            let cookie = cookie_texels(scene, variant);
            Box::new(move |_| {
                let rb = run_minmax_once(
                    ctx,
                    v,
                    res,
                    &frame,
                    &gbuf.view_depth,
                    &sm.depth,
                    cookie.as_ref().map(|(size, t)| (*size, &t[..])),
                )?;
                Ok(GpuFrame {
                    output: rb.output,
                    report: Some(rb.frame.report),
                    wall_time: rb.wall_time,
                    gpu_times: rb.gpu_times.map(minmax_times),
                })
            })
        }
        FamilyVariant::HybridVolume(v) => {
            let ctx = &ctx;
            let cookie = cookie_texels(scene, variant);
            Box::new(move |_| {
                let rb = run_hybrid_volume_once(
                    ctx,
                    v,
                    res,
                    &frame,
                    &gbuf.view_depth,
                    &sm.depth,
                    cookie.as_ref().map(|(size, t)| (*size, &t[..])),
                )?;
                Ok(GpuFrame {
                    output: rb.output,
                    report: Some(rb.frame.report),
                    wall_time: rb.wall_time,
                    gpu_times: rb.gpu_times.map(hybrid_volume_times),
                })
            })
        }
        FamilyVariant::PartialSumTree(v) => {
            let ctx = &ctx;
            let cookie = cookie_texels(scene, variant);
            Box::new(move |_| {
                let rb = run_partial_sum_tree_once(
                    ctx,
                    v,
                    res,
                    &frame,
                    &gbuf.view_depth,
                    &sm.depth,
                    cookie.as_ref().map(|(size, t)| (*size, &t[..])),
                )?;
                Ok(GpuFrame {
                    output: rb.output,
                    report: Some(rb.frame.frame.report),
                    wall_time: rb.wall_time,
                    gpu_times: rb.gpu_times.map(partial_sum_tree_times),
                })
            })
        }
    };
    let mut last = None;
    let mut best_wall = Duration::MAX;
    let mut best_gpu: Option<PassTimes> = None;
    for i in 0..gpu.frames {
        let f = run_frame(i + 1 == gpu.frames)?;
        best_wall = best_wall.min(f.wall_time);
        if let Some(t) = f.gpu_times {
            best_gpu = Some(min_times(best_gpu, t));
        }
        last = Some((f.output, f.report));
    }
    drop(run_frame);
    let (output, report) = last.ok_or("no frame ran")?;
    if pass_wall_frames > 0 && pass_walls.is_none() {
        pass_walls = Some(measure_pass_walls(
            &ctx,
            &variant,
            res,
            &frame,
            gbuf,
            sm,
            cookie_texels(scene, variant),
            area_inputs.as_ref().map(|i| &i.map_data[..]),
            pass_wall_frames,
        )?);
    }
    // With lowres or epipolar sampling: the pixels no sample stood for, which the
    // `_fallback` pass evaluated per pixel (one more frame through the generic runtime,
    // which reads the unwarp's count back).
    let fallback = if variant.sampling().is_sampled() {
        let vpl_maps = area_inputs.as_ref().map(|i| i.map_data.clone());
        let inputs = cpu_inputs(&variant, res, frame, scene, bvh, gbuf, sm, vpl_maps)?;
        scatter_runtime::run_family_once(&ctx, &variant, res, &inputs)?.fallback_pixels
    } else {
        None
    };
    let family = variant.family();
    let sizes = sizes(gbuf, plan.rectified);
    eprintln!("{family} {} on the GPU ({sizes})", variant.id());
    print_report(report.as_ref());
    if let Some(n) = fallback {
        let pixels = u64::from(gbuf.width) * u64::from(gbuf.height);
        println!(
            "fallback: {n} of {pixels} pixels ({:.2} %) had no sample close in depth or in light and were evaluated per pixel",
            100.0 * f64::from(n) / pixels.max(1) as f64
        );
    }
    println!(
        "wall time per frame, submission to mapped readback of every texture (min of {} frames): {:.3} ms",
        gpu.frames,
        best_wall.as_secs_f64() * 1e3
    );
    match best_gpu {
        Some(_) if adapter.is_cpu() => println!(
            "GPU time per pass: not shown: {} is a CPU adapter, and its timestamps are not usable \
             (they are not ordered after the compute work); the GPU is the CPU, so pass wall time \
             is the real cost{}",
            adapter.name,
            if pass_wall_frames == 0 {
                " (--pass-wall-frames N measures it)"
            } else {
                ""
            }
        ),
        Some(t) => println!(
            "GPU time per pass (min of {} frames, {sizes}): {}",
            gpu.frames,
            format_times(&t)
        ),
        None => println!("the adapter has no timestamp queries: no GPU times"),
    }
    if let Some(t) = pass_walls {
        let rectification = report
            .as_ref()
            .map(|r| format!(", {}", r.rectification))
            .unwrap_or_default();
        println!(
            "wall time per pass, each submitted alone (median of {pass_wall_frames} frames, {sizes}{rectification}): {}",
            format_times(&t)
        );
    }
    let image = Image::from_pixels(
        gbuf.width,
        gbuf.height,
        output.iter().map(|c| [c[0], c[1], c[2]]).collect(),
    );
    Ok(image)
}

/// A frame's inputs as the runtime's `run_*_once` helpers take them: for a prefiltered
/// variant also the engine's rectified map (ray cast here), which a projective frame needs.
#[allow(clippy::too_many_arguments, reason = "the frame's inputs")]
fn cpu_inputs(
    variant: &FamilyVariant,
    res: Resolutions,
    frame: FrameInput,
    scene: &Scene,
    bvh: &Bvh,
    gbuf: &GBuffer,
    sm: &ShadowMap,
    vpl_maps: Option<Vec<f32>>,
) -> Result<CpuInputs, BoxError> {
    let rectified = match variant {
        FamilyVariant::Prefiltered(v) => {
            let prepared = prepare_frame(
                v,
                &res,
                &frame.camera,
                &frame.light,
                &frame.medium,
                &frame.shadow_map,
                &frame.settings,
            )?;
            engine_rectified_map(scene, bvh, &prepared)
        }
        _ => None,
    };
    Ok(CpuInputs {
        frame,
        depth: gbuf.view_depth.clone(),
        shadow_map: sm.depth.clone(),
        rectified,
        pass_wall_frames: 0,
        cookie: cookie_texels(scene, *variant),
        vpl_maps,
    })
}

/// The wall time of each of the variant's passes submitted on its own (median of `frames`),
/// through [`FamilyPasses`] (any family whose `run_*_once` does not measure it).
#[allow(clippy::too_many_arguments, reason = "the frame's inputs")]
fn measure_pass_walls(
    ctx: &Context,
    variant: &FamilyVariant,
    res: Resolutions,
    frame: &FrameInput,
    gbuf: &GBuffer,
    sm: &ShadowMap,
    cookie: Option<([u32; 2], Vec<[f32; 4]>)>,
    vpl_maps: Option<&[f32]>,
    frames: u32,
) -> Result<PassTimes, BoxError> {
    let mut pass = FamilyPasses::new(ctx, variant, res, sm.size)?;
    if let Some((size, texels)) = cookie {
        let texture =
            scatter_runtime::textures::upload_cookie(ctx, Kernel::Scatter, size, &texels)?;
        pass.set_cookie(&texture.create_view(&Default::default()))?;
    }
    pass.prepare(ctx, frame)?;
    let depth = upload_r32float(
        ctx,
        Kernel::Scatter,
        "godrays depth",
        res.screen,
        &gbuf.view_depth,
    )?;
    let shadow = upload_r32float(
        ctx,
        Kernel::Rectify,
        "godrays shadow map",
        [sm.size; 2],
        &sm.depth,
    )?;
    let (dv, sv) = (
        depth.create_view(&Default::default()),
        shadow.create_view(&Default::default()),
    );
    let vpl_maps = match vpl_maps {
        Some(data) => {
            let layers = u32::try_from(data.len() / (sm.size as usize).pow(2))?;
            Some(scatter_runtime::upload_vpl_maps(
                ctx, sm.size, layers, data,
            )?)
        }
        None => None,
    };
    let inputs = Inputs {
        depth: &dv,
        shadow_map: Some(&sv),
        rectified: None,
        vpl_maps: vpl_maps.as_ref().map(|(_, v)| v),
    };
    Ok(pass
        .measure_pass_wall_times(ctx, &inputs, frames)?
        .into_iter()
        .map(|(kernel, t)| (kernel.name(), t))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    fn args(extra: &[&str]) -> Args {
        let mut all = vec!["godrays", "--scene", "sphere", "--out", "x.png"];
        all.extend_from_slice(extra);
        Args::try_parse_from(all).unwrap_or_else(|e| panic!("{extra:?}: {e}"))
    }

    fn refused(extra: &[&str]) -> String {
        match check(&args(extra), LightKind::Directional) {
            Ok(p) => panic!("{extra:?} accepted: {p:?}"),
            Err(e) => {
                assert!(!e.contains('\n'), "{e}");
                e
            }
        }
    }

    #[test]
    fn a_scene_file_replaces_the_suite_scene_and_its_pose_and_medium() {
        let parse = |a: &[&str]| Args::try_parse_from(a).map_err(|e| e.kind());
        let a = parse(&["godrays", "--scene-file", "s.json", "--out", "x.png"])
            .unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(a.scene_file, Some(PathBuf::from("s.json")));
        assert_eq!(a.scene, None);
        assert_eq!((a.width, a.height), (None, None));
        for extra in [
            ["--scene", "sphere"],
            ["--pose", "grazing"],
            ["--medium", "thick"],
        ] {
            let mut all = vec!["godrays", "--scene-file", "s.json", "--out", "x.png"];
            all.extend_from_slice(&extra);
            assert_eq!(
                parse(&all).err(),
                Some(clap::error::ErrorKind::ArgumentConflict),
                "{extra:?}"
            );
        }
        assert_eq!(
            parse(&["godrays", "--out", "x.png"]).err(),
            Some(clap::error::ErrorKind::MissingRequiredArgument)
        );
    }

    #[test]
    fn help_describes_the_demo() {
        let about = Args::command()
            .get_about()
            .map(ToString::to_string)
            .unwrap_or_default();
        assert!(
            about.starts_with("Renders a suite scene's light shafts"),
            "{about}"
        );
        let help = Args::command().render_help().to_string();
        for f in Family::ALL {
            assert!(help.contains(&format!("`{f}`")), "{f} missing from --help");
        }
    }

    #[test]
    fn every_family_is_a_method() {
        assert_eq!(parse_method("truth"), Ok(Method::Truth));
        for &f in Family::ALL {
            assert_eq!(parse_method(f.name()), Ok(Method::Family(f)));
            // A scene of the family's light: a spot, or an area light for area_ivsv.
            let light = if f == Family::AreaIvsv {
                LightKind::Area
            } else {
                LightKind::Spot
            };
            let Ok(Plan::Family(p)) = check(&args(&["--method", f.name()]), light) else {
                panic!("{f}");
            };
            assert_eq!(p.variant.family(), f);
            assert_eq!(p.variant.light(), light);
            // The family's defaults with the scene's light.
            let expected = f
                .variant(&[("light".into(), light.name().into())])
                .unwrap_or_else(|e| panic!("{f}: {e}"));
            assert_eq!(p.variant, expected);
        }
        let e = parse_method("prefilter").unwrap_err();
        assert_eq!(
            e,
            "method must be truth | area_ivsv | hybrid_volume | minmax | partial_sum_tree | prefiltered | raymarch, got prefilter"
        );
        assert!(
            Args::try_parse_from([
                "godrays", "--scene", "sphere", "--out", "x.png", "--method", "raytrace"
            ])
            .is_err()
        );
    }

    #[test]
    fn truth_refuses_family_options() {
        let to = "applies to a kernel family (--method area_ivsv | hybrid_volume | minmax | partial_sum_tree | prefiltered | raymarch), not to --method truth";
        assert_eq!(refused(&["--gpu"]), format!("--gpu {to}"));
        assert_eq!(refused(&["--compare"]), format!("--compare {to}"));
        assert_eq!(
            refused(&["--variant", "bases=64"]),
            format!("--variant {to}")
        );
        assert_eq!(
            refused(&["--variant", "bases=30"]),
            format!("--variant {to}")
        );
        assert_eq!(
            refused(&["--rectified", "512x512"]),
            format!("--rectified {to}")
        );
        assert_eq!(refused(&["--frames", "2"]), format!("--frames {to}"));
        assert_eq!(
            refused(&["--method", "truth", "--pass-wall-frames", "2"]),
            format!("--pass-wall-frames {to}")
        );
        assert_eq!(
            check(&args(&["--truth", "shadow-map"]), LightKind::Directional),
            Ok(Plan::Truth(Truth::ShadowMap))
        );
        assert_eq!(
            check(&args(&[]), LightKind::Directional),
            Ok(Plan::Truth(Truth::Exact))
        );
    }

    #[test]
    fn families_refuse_what_does_not_apply() {
        let e = refused(&["--method", "raymarch", "--truth", "exact"]);
        assert!(e.starts_with("--truth applies to --method truth"), "{e}");
        assert_eq!(
            refused(&["--method", "raymarch", "--rectified", "512x512"]),
            "--rectified does not apply to --method raymarch: it has no rectified map"
        );
        assert_eq!(
            refused(&["--method", "minmax", "--frames", "3"]),
            "--frames applies with --gpu only (the CPU mirror is not timed per pass)"
        );
        assert_eq!(
            refused(&["--method", "prefiltered", "--rectified", "0x4"]),
            "--rectified must be WIDTHxHEIGHT with both in 1..=16384, got '0x4'"
        );
        let Ok(Plan::Family(p)) = check(
            &args(&[
                "--method",
                "minmax",
                "--gpu",
                "--rectified",
                "256x128",
                "--compare",
            ]),
            LightKind::Directional,
        ) else {
            panic!("minmax --gpu");
        };
        assert_eq!(p.rectified, Some([256, 128]));
        assert!(p.compare);
        assert_eq!(
            p.gpu,
            Some(GpuPlan {
                frames: DEFAULT_FRAMES,
                pass_wall_frames: None
            })
        );
    }

    #[test]
    fn invalid_variants_are_refused_for_every_family() {
        let cases = [
            (
                "prefiltered",
                "bases=30",
                "--variant: bases must be a multiple of 4 in 4..=128, got 30",
            ),
            (
                "prefiltered",
                "regions=17",
                "--variant: regions must be in 1..=16, got 17",
            ),
            (
                "prefiltered",
                "bases",
                "--variant: expected knob=value, got 'bases'",
            ),
            (
                "raymarch",
                "samples=3",
                "--variant: samples must be in 4..=1024 and a multiple of interleave^2 = 1 (every pixel class gets the same number of samples), got 3",
            ),
            (
                "raymarch",
                "jitter=maybe",
                "--variant: jitter must be true | false, got maybe",
            ),
            (
                "minmax",
                "light=spot",
                "--variant: the light follows the scene (directional here); leave `light` out",
            ),
        ];
        for (method, variant, message) in cases {
            assert_eq!(
                refused(&["--method", method, "--variant", variant]),
                message
            );
        }
        // A knob of another family names the family's own knobs.
        let e = refused(&["--method", "minmax", "--variant", "bases=32"]);
        assert!(
            e.starts_with("--variant: knob `bases` does not apply to family minmax"),
            "{e}"
        );
        let e = refused(&["--method", "raymarch", "--variant", "regions=3"]);
        assert!(e.contains("does not apply to family raymarch"), "{e}");
    }

    #[test]
    fn the_prefiltered_variant_is_the_one_the_old_parser_made() {
        let Ok(Plan::Family(p)) = check(
            &args(&[
                "--method",
                "prefiltered",
                "--variant",
                "bases=64, regions=8,visibility=average,storage=rgba16float,rectification=projective",
            ]),
            LightKind::Spot,
        ) else {
            panic!("prefiltered");
        };
        let expected = scatter_shaderlib::prefiltered::PrefilteredVariant {
            bases: 64,
            regions: 8,
            visibility: "average".parse().unwrap_or_else(|e| panic!("{e}")),
            storage: "rgba16float".parse().unwrap_or_else(|e| panic!("{e}")),
            rectification: "projective".parse().unwrap_or_else(|e| panic!("{e}")),
            light: LightKind::Spot,
            ..Default::default()
        };
        assert_eq!(p.variant, FamilyVariant::Prefiltered(expected));
        assert_eq!(p.rectified, Some(DEFAULT_RECTIFIED));
    }
}
