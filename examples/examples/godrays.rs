//! Renders a suite scene's light shafts to PNG.
//!
//! ```text
//! cargo run --release -p scatter-examples --example godrays -- --scene window --truth exact --out window.png
//! ```
//!
//! Writes `<out>` (composite: surfaces attenuated by the fog plus in-scattering), and beside
//! it `<stem>.inscatter.png` (in-scattered radiance only, tone-mapped) and
//! `<stem>.inscatter.pfm` (the same as linear float RGB).
//!
//! `--method prefiltered` renders with the prefiltered family (Klehm et al. 2014) instead of
//! a ground truth, through the CPU mirror of its kernels (the same arithmetic as the GPU
//! kernels; the conformance suite checks that they agree). `--compare` also renders the
//! `shadow_map` truth from the same shadow map, prints the error and writes
//! `<stem>.compare.png`: truth | prefiltered | 4x difference.

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::kernels::{engine_rectified_map, run_prefiltered};
use scatter_reference::metrics;
use scatter_reference::scene::Scene;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_runtime::{Context, CpuInputs, FrameInput, PrefilteredTimes, run_prefiltered_once};
use scatter_shaderlib::prefiltered::{
    FrameSettings, LightKind, Resolutions, Variant, VariantError, prepare_frame,
};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
enum Method {
    /// A ground truth (see `--truth`).
    Truth,
    /// The prefiltered method (Klehm et al. 2014), CPU mirror of the GPU kernels.
    Prefiltered,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Truth {
    /// Visibility by casting a ray to the light.
    Exact,
    /// Visibility from the standard shadow map (nearest texel, biased).
    ShadowMap,
}

/// Render a scene of the scatter suite (ground truth of the single-scattering model).
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Suite scene: sphere, columns, window, foliage, terrain, spot_grate.
    #[arg(long, value_parser = |s: &str| s.parse::<SceneName>())]
    scene: SceneName,
    /// Camera pose: ordinary, epipole_on_screen, light_behind, grazing.
    #[arg(long, default_value = "ordinary", value_parser = |s: &str| s.parse::<Pose>())]
    pose: Pose,
    /// Medium preset: default, thick, thin.
    #[arg(long, default_value = "default", value_parser = |s: &str| s.parse::<MediumPreset>())]
    medium: MediumPreset,
    /// What renders the in-scattering.
    #[arg(long, value_enum, default_value = "truth")]
    method: Method,
    /// Which ground truth to render (`--method truth`).
    #[arg(long, value_enum, default_value = "exact")]
    truth: Truth,
    /// Prefiltered variant, e.g. `bases=64,regions=8,visibility=average,storage=rgba16float`
    /// (knobs not named keep the paper's defaults; the light follows the scene).
    #[arg(long, default_value = "")]
    variant: String,
    /// Rectified map size for `--method prefiltered`, WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x1024")]
    rectified: String,
    /// With `--method prefiltered`: also render the `shadow_map` truth, print the error and
    /// write `<stem>.compare.png` (truth | prefiltered | 4x difference).
    #[arg(long)]
    compare: bool,
    /// With `--method prefiltered`: run the GPU kernels through `scatter-runtime` (lavapipe
    /// when there is no GPU) instead of the CPU mirror, and print GPU time per pass (the
    /// minimum over `--frames` runs).
    #[arg(long)]
    gpu: bool,
    /// Frames timed with `--gpu` (1..=100).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=100))]
    frames: u32,
    /// With `--gpu`: also time each pass submitted on its own and waited for (median of this
    /// many frames after a warm-up; 0 = off). On lavapipe this wall time is the pass's real
    /// cost, unlike its timestamps.
    #[arg(long, default_value_t = 0)]
    pass_wall_frames: u32,
    /// Image width in pixels (1..=8192).
    #[arg(long, default_value_t = 640, value_parser = clap::value_parser!(u32).range(1..=8192))]
    width: u32,
    /// Image height in pixels (1..=8192).
    #[arg(long, default_value_t = 360, value_parser = clap::value_parser!(u32).range(1..=8192))]
    height: u32,
    /// Shadow-map size for `--truth shadow-map` (1..=16384).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=16384))]
    shadow_map_size: u32,
    /// Quadrature cells per view ray (16..=65536).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(16..=65536))]
    segments: u32,
    /// Output PNG (composite).
    #[arg(long)]
    out: PathBuf,
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

/// Parses `--variant` (`knob=value` pairs separated by commas).
fn parse_variant(text: &str, light: LightKind) -> Result<Variant, String> {
    let mut v = Variant {
        light,
        ..Variant::default()
    };
    for pair in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (k, val) = pair
            .split_once('=')
            .ok_or_else(|| format!("--variant: expected knob=value, got '{pair}'"))?;
        let num = || {
            val.parse::<u32>()
                .map_err(|_| format!("--variant: {k} must be a number, got '{val}'"))
        };
        match k {
            "bases" => v.bases = num()?,
            "bases_per_thread" => v.bases_per_thread = num()?,
            "regions" => v.regions = num()?,
            "visibility" => v.visibility = val.parse().map_err(|e: VariantError| e.to_string())?,
            "storage" => v.storage = val.parse().map_err(|e: VariantError| e.to_string())?,
            "rectification" => {
                v.rectification = val.parse().map_err(|e: VariantError| e.to_string())?
            }
            _ => {
                return Err(format!(
                    "--variant: unknown knob '{k}' (bases, bases_per_thread, regions, visibility, storage, rectification)"
                ));
            }
        }
    }
    v.validate().map_err(|e| format!("--variant: {e}"))?;
    Ok(v)
}

fn parse_size(text: &str) -> Result<[u32; 2], String> {
    let err = || format!("--rectified must be WIDTHxHEIGHT with both in 1..=16384, got '{text}'");
    let (w, h) = text.split_once('x').ok_or_else(err)?;
    let w: u32 = w.parse().map_err(|_| err())?;
    let h: u32 = h.parse().map_err(|_| err())?;
    if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
        return Err(err());
    }
    Ok([w, h])
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    if args.out.extension().and_then(|e| e.to_str()) != Some("png") {
        return Err(format!("--out must name a .png file, got {}", args.out.display()).into());
    }
    let scene = suite::scene(args.scene, args.pose, args.medium, args.width, args.height);
    scene.validate()?;
    let t0 = Instant::now();
    let bvh = Bvh::build(&scene.geometry);
    let gbuf = GBuffer::cast(&scene, &bvh);
    eprintln!(
        "{}: {} occluders, {} primitives; depth buffer {}x{} in {:.2?}",
        scene.name,
        scene.occluder_count(),
        bvh.prim_count(),
        args.width,
        args.height,
        t0.elapsed()
    );
    if args.method == Method::Prefiltered {
        return run_prefiltered_method(args, &scene, &bvh, &gbuf);
    }
    let sm;
    let vis = match args.truth {
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
    let bar = ProgressBar::new(u64::from(args.height)).with_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows, eta {eta}")?
            .progress_chars("=> "),
    );
    bar.set_message(format!("truth ({:?})", args.truth));
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

fn write_outputs(
    args: &Args,
    composite: &Image,
    inscatter: &Image,
) -> Result<(), Box<dyn std::error::Error>> {
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

fn run_prefiltered_method(
    args: &Args,
    scene: &Scene,
    bvh: &Bvh,
    gbuf: &GBuffer,
) -> Result<(), Box<dyn std::error::Error>> {
    let light = match scene.light {
        scatter_reference::scene::Light::Directional { .. } => LightKind::Directional,
        scatter_reference::scene::Light::Spot { .. } => LightKind::Spot,
    };
    let variant = parse_variant(&args.variant, light)?;
    let rectified = parse_size(&args.rectified)?;
    let t = Instant::now();
    let sm = ShadowMap::build(scene, bvh, args.shadow_map_size)?;
    eprintln!(
        "shadow map {0}x{0} in {1:.2?}",
        args.shadow_map_size,
        t.elapsed()
    );
    let t = Instant::now();
    let settings = FrameSettings::for_screen(args.width, args.height);
    let output = if args.gpu {
        run_on_gpu(args, &variant, rectified, scene, bvh, gbuf, &sm, settings)?
    } else {
        let run = run_prefiltered(&variant, rectified, scene, bvh, gbuf, &sm, &settings)?;
        eprintln!(
            "prefiltered {variant} ({}x{} rectified) on the CPU mirror in {:.2?}; {:?}",
            rectified[0],
            rectified[1],
            t.elapsed(),
            run.frame.report
        );
        run.output
    };
    let composite = truth::surface_radiance(scene, gbuf, bvh).add(&output)?;
    write_outputs(args, &composite, &output)?;
    if args.compare {
        let bar = ProgressBar::new(u64::from(args.height)).with_style(
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
            "{}: prefiltered {variant} vs shadow_map truth: {report}",
            scene.name
        );
        let diff = output.abs_diff(&truth, 4.0)?;
        let strip = Image::hstack(&[&truth, &output, &diff])?;
        let path = args.out.with_extension("").with_extension("compare.png");
        strip.write_png(&path, Some(truth.auto_exposure()))?;
        eprintln!(
            "wrote {} (truth | prefiltered | 4x difference)",
            path.display()
        );
    }
    Ok(())
}

/// Runs the prefiltered kernels on the GPU `--frames` times; prints the adapter and the
/// fastest GPU time per pass, returns the last output.
#[allow(clippy::too_many_arguments, reason = "the demo's inputs")]
fn run_on_gpu(
    args: &Args,
    variant: &Variant,
    rectified: [u32; 2],
    scene: &Scene,
    bvh: &Bvh,
    gbuf: &GBuffer,
    sm: &ShadowMap,
    settings: FrameSettings,
) -> Result<Image, Box<dyn std::error::Error>> {
    let ctx = Context::new()?;
    eprintln!("GPU adapter: {}", ctx.report());
    let res = Resolutions {
        screen: [gbuf.width, gbuf.height],
        rectified,
    };
    let frame = FrameInput {
        camera: scene.camera_desc(),
        light: scene.light_desc(),
        medium: scene.medium_desc(),
        shadow_map: sm.desc(),
        settings,
    };
    // A projective frame needs the engine's rasterised rectified map (ray cast here).
    let prepared = prepare_frame(
        variant,
        &res,
        &frame.camera,
        &frame.light,
        &frame.medium,
        &frame.shadow_map,
        &frame.settings,
    )?;
    let inputs = CpuInputs {
        frame,
        depth: gbuf.view_depth.clone(),
        shadow_map: sm.depth.clone(),
        rectified: engine_rectified_map(scene, bvh, &prepared),
        pass_wall_frames: args.pass_wall_frames,
    };
    let mut best: Option<PrefilteredTimes> = None;
    let mut last = None;
    let mut best_wall = std::time::Duration::MAX;
    for _ in 0..args.frames {
        let rb = run_prefiltered_once(&ctx, variant, res, &inputs)?;
        best_wall = best_wall.min(rb.wall_time);
        if let Some(t) = rb.gpu_times {
            best = Some(match best {
                None => t,
                Some(b) => PrefilteredTimes {
                    rectify: b.rectify.min(t.rectify),
                    prefilter: b.prefilter.min(t.prefilter),
                    scatter: b.scatter.min(t.scatter),
                },
            });
        }
        last = Some(rb);
    }
    let rb = last.ok_or("no frame ran")?;
    eprintln!("prefiltered {variant} on the GPU; {:?}", rb.frame.report);
    println!(
        "wall time per frame, submission to mapped readback of every texture (min of {} frames): {:.3} ms",
        args.frames,
        best_wall.as_secs_f64() * 1e3
    );
    match best {
        Some(t) => println!(
            "GPU time per pass (min of {} frames, {}x{} screen, {}x{} rectified): rectify {:.3} ms, prefilter {:.3} ms, scatter {:.3} ms, total {:.3} ms",
            args.frames,
            gbuf.width,
            gbuf.height,
            rectified[0],
            rectified[1],
            t.rectify.as_secs_f64() * 1e3,
            t.prefilter.as_secs_f64() * 1e3,
            t.scatter.as_secs_f64() * 1e3,
            t.total().as_secs_f64() * 1e3
        ),
        None => println!("the adapter has no timestamp queries: no GPU times"),
    }
    if let Some(t) = rb.pass_wall_times {
        println!(
            "wall time per pass, each submitted alone (median of {} frames, {}x{} screen, {}x{} rectified, {}): rectify {:.3} ms, prefilter {:.3} ms, scatter {:.3} ms, total {:.3} ms",
            args.pass_wall_frames,
            gbuf.width,
            gbuf.height,
            rectified[0],
            rectified[1],
            rb.frame.report.rectification,
            t.rectify.as_secs_f64() * 1e3,
            t.prefilter.as_secs_f64() * 1e3,
            t.scatter.as_secs_f64() * 1e3,
            t.total().as_secs_f64() * 1e3
        );
    }
    Ok(Image::from_pixels(
        gbuf.width,
        gbuf.height,
        rb.output.iter().map(|c| [c[0], c[1], c[2]]).collect(),
    ))
}
