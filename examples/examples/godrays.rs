//! Renders a suite scene's light shafts to PNG.
//!
//! ```text
//! cargo run --release -p scatter-examples --example godrays -- --scene window --truth exact --out window.png
//! ```
//!
//! Writes `<out>` (composite: surfaces attenuated by the fog plus in-scattering), and beside
//! it `<stem>.inscatter.png` (in-scattered radiance only, tone-mapped) and
//! `<stem>.inscatter.pfm` (the same as linear float RGB).

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

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
    /// Which ground truth to render.
    #[arg(long, value_enum, default_value = "exact")]
    truth: Truth,
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
