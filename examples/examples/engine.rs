//! A small headless engine: tessellates a suite scene or a scene file into triangles, draws
//! the camera depth, the light's shadow map and (in a projective frame) the rectified map
//! with wgpu render pipelines, runs a kernel family's passes through `scatter-runtime` on
//! those render targets, shades the scene in a forward pass and composites the shafts over
//! it, all on the GPU until the final image is read back (`scatter_examples::engine`).
//!
//! ```text
//! cargo run --release -p scatter-examples --example engine -- --scene spot_grate --pose ordinary --out out/
//! cargo run --release -p scatter-examples --example engine -- --scene window --family prefiltered --variant rectification=projective --out out/
//! cargo run --release -p scatter-examples --example engine -- --scene-file reference/scenes/mesh_grate.json --family minmax --out out/
//! ```
//!
//! Writes `engine.png` (the composite), `shafts.png` (the family's in-scattering alone, at
//! the composite's exposure) and `depth.png` (the rasterised view depth) into `--out`, and
//! prints the triangle count and the wall time of each stage (each submitted and waited
//! for). Bad input is refused with one line and exit code 2; no file is half written.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use scatter_examples::engine::{Engine, EngineSettings, write_outputs};
use scatter_examples::scene_file;
use scatter_gen::{Family, FamilyCli, FamilyVariant};
use scatter_reference::bvh::Bvh;
use scatter_reference::scene::Scene;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_runtime::Context;
use scatter_shaderlib::prefiltered::LightKind;
use scatter_shaderlib::prefiltered::variant::printable;

/// The engine's command line.
#[derive(Parser, Debug)]
#[command(
    name = "engine",
    version,
    about = "A small headless wgpu engine: rasterised depth, shadow map and rectified map, a \
             kernel family's shafts on them, composited over a forward-shaded scene (PNG)"
)]
struct Args {
    /// Suite scene: sphere, columns, window, foliage, terrain, spot_grate.
    #[arg(long, value_parser = |s: &str| s.parse::<SceneName>(), required_unless_present = "scene_file")]
    scene: Option<SceneName>,
    /// A scene file instead of a suite scene (JSON, reference/scenes/README.md; OBJ meshes
    /// by `mesh_file`), with its camera, at its size unless --size is given.
    #[arg(long, value_name = "PATH", conflicts_with_all = ["scene", "pose", "medium"])]
    scene_file: Option<PathBuf>,
    /// Camera pose of a suite scene: ordinary, epipole_on_screen, light_behind, grazing.
    #[arg(long, default_value = "ordinary", value_parser = |s: &str| s.parse::<Pose>())]
    pose: Pose,
    /// Medium preset of a suite scene: default, thick, thin.
    #[arg(long, default_value = "default", value_parser = |s: &str| s.parse::<MediumPreset>())]
    medium: MediumPreset,
    /// Kernel family that renders the shafts: hybrid_volume, minmax, partial_sum_tree,
    /// prefiltered, raymarch.
    #[arg(long, default_value = "prefiltered", value_parser = parse_family)]
    family: Family,
    /// The family's knobs as knob=value pairs, e.g. `bases=64,rectification=projective`
    /// (`scatter-gen list` shows them); the light follows the scene.
    #[arg(long, value_name = "KNOBS")]
    variant: Option<String>,
    /// Image size, WIDTHxHEIGHT [default: 640x360, or a scene file's camera].
    #[arg(long, value_name = "WxH", value_parser = |s: &str| parse_size("--size", s))]
    size: Option<[u32; 2]>,
    /// Shadow map size (1..=16384).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=16384))]
    shadow_map: u32,
    /// Rectified map size of a family that has one, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", default_value = "1024x1024", value_parser = |s: &str| parse_size("--rectified", s))]
    rectified: [u32; 2],
    /// A fixed exposure (linear scale before the tone map) instead of one over the 99.5th percentile of luminance.
    #[arg(long, value_parser = parse_exposure)]
    exposure: Option<f32>,
    /// Output folder (created if missing): engine.png, shafts.png, depth.png.
    #[arg(long)]
    out: PathBuf,
}

fn parse_family(text: &str) -> Result<Family, String> {
    text.parse().map_err(|_| {
        let names: Vec<&str> = Family::ALL.iter().map(|f| f.name()).collect();
        format!(
            "family must be {}, got '{}'",
            names.join(" | "),
            printable(text)
        )
    })
}

fn parse_size(flag: &str, text: &str) -> Result<[u32; 2], String> {
    let err = || {
        format!(
            "{flag} must be WIDTHxHEIGHT with both in 1..=8192, got '{}'",
            printable(text)
        )
    };
    let (w, h) = text.split_once('x').ok_or_else(err)?;
    let w: u32 = w.parse().map_err(|_| err())?;
    let h: u32 = h.parse().map_err(|_| err())?;
    if !(1..=8192).contains(&w) || !(1..=8192).contains(&h) {
        return Err(err());
    }
    Ok([w, h])
}

fn parse_exposure(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(e) if e.is_finite() && e > 0.0 => Ok(e),
        _ => Err(format!(
            "--exposure must be a positive number, got '{}'",
            printable(text)
        )),
    }
}

/// Parses `--variant` with `scatter-gen`'s knob parser, the light set from the scene.
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
        knobs.push((k.to_owned(), v.trim().to_owned()));
    }
    knobs.push(("light".to_owned(), light.to_string()));
    family
        .variant(&knobs)
        .map_err(|e| format!("--variant: {e}"))
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("engine: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &Args) -> Result<(), String> {
    if args.out.exists() && !args.out.is_dir() {
        return Err(format!(
            "--out {} exists and is not a folder",
            args.out.display()
        ));
    }
    let (scene, id): (Scene, String) = match (&args.scene_file, args.scene) {
        (Some(path), _) => {
            let loaded = scene_file::load(path, args.size)?;
            eprintln!("{}", loaded.report(path));
            let name = loaded.scene.name.clone();
            (loaded.scene, name)
        }
        (None, Some(name)) => {
            let [w, h] = args.size.unwrap_or([640, 360]);
            (
                suite::scene(name, args.pose, args.medium, w, h),
                format!("{name}/{}", args.pose),
            )
        }
        (None, None) => return Err("give --scene NAME or --scene-file PATH".into()),
    };
    scene.validate().map_err(|e| e.to_string())?;
    let variant = parse_variant(
        args.family,
        args.variant.as_deref().unwrap_or(""),
        scene.light.kind(),
    )?;
    let ctx = Context::new().map_err(|e| e.to_string())?;
    eprintln!("GPU adapter: {}", ctx.report());
    let t = Instant::now();
    let engine = Engine::new(&ctx);
    let pipelines = t.elapsed();
    let bvh = Bvh::build(&scene.geometry);
    let frame = engine.render(
        &ctx,
        &scene,
        &bvh,
        &EngineSettings {
            variant,
            shadow_map: args.shadow_map,
            rectified: args.rectified,
            exposure: args.exposure,
        },
    )?;
    let [w, h] = [scene.camera.width, scene.camera.height];
    eprintln!(
        "{id}: {w}x{h}, {} triangles, {}x{} shadow map, {} {}",
        frame.raster.triangles,
        args.shadow_map,
        args.shadow_map,
        variant.family(),
        variant.id()
    );
    if let Some(report) = &frame.report {
        match (&report.projective, &report.fallback) {
            (Some(maps), _) => eprintln!(
                "  rectification: projective ({} regions rasterised into a {}x{} map)",
                maps.matrices.len(),
                args.rectified[0],
                args.rectified[1]
            ),
            (None, Some(why)) => eprintln!("  rectification: epipolar (fell back: {why})"),
            (None, None) => eprintln!("  rectification: {}", report.rectification),
        }
    }
    eprintln!("  engine pipelines {:.1} ms", pipelines.as_secs_f64() * 1e3);
    for (stage, time) in &frame.times {
        eprintln!("  {stage} {:.1} ms", time.as_secs_f64() * 1e3);
    }
    eprintln!(
        "  exposure {:.4}{}",
        frame.exposure(&ctx)?,
        if args.exposure.is_some() {
            " (fixed)"
        } else {
            " (99.5th percentile)"
        }
    );
    std::fs::create_dir_all(&args.out).map_err(|e| format!("--out {}: {e}", args.out.display()))?;
    let written = write_outputs(&ctx, &frame, &scene, &args.out)?;
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    eprintln!("wrote {}", names.join(", "));
    Ok(())
}
