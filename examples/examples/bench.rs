//! `bench`: speed against accuracy for every family and variant of a grid on the suite
//! (`scatter_examples::bench`): CSV, markdown report with the ratios, chart (SVG, PNG).
//!
//! ```sh
//! cargo run --release -p scatter-examples --example bench -- --out-dir docs/bench
//! cargo run --release -p scatter-examples --example bench -- --quick --out-dir out/bench
//! cargo run --release -p scatter-examples --example bench -- --headline-only
//! cargo run --release -p scatter-examples --example bench -- --headline-only --headline-errors --family prefiltered --family raymarch
//! cargo run --release -p scatter-examples --example bench -- --roofline
//! cargo run --release -p scatter-examples --example bench -- --family raymarch --family hybrid_volume
//! cargo run --release -p scatter-examples --example bench -- --scene-file reference/scenes/mesh_grate.json
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use clap::Parser;
use scatter_examples::bench::{BenchConfig, Case, run, write_outputs};
use scatter_reference::suite::Pose;
use scatter_runtime::Context;
use scatter_runtime::shaderlib::family::Family;

/// Speed against accuracy of every scatter family on the scene suite.
#[derive(Debug, Parser)]
#[command(name = "bench")]
struct Args {
    /// Directory for bench.csv, bench.md, bench.svg and bench.png.
    #[arg(long, default_value = "out/bench")]
    out_dir: PathBuf,
    /// The smoke run: two scenes, three variants, 160x90 (under 2 minutes).
    #[arg(long)]
    quick: bool,
    /// Timed frames per run after the warm-up (1..=20).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=20))]
    frames: Option<u32>,
    /// Skip the prefiltered scaling runs (rectified width 512..4096, screen sizes).
    #[arg(long)]
    no_scaling: bool,
    /// Only the headline runs (1280x720, 1024x1024 rectified map, sphere, foliage and
    /// terrain): per-pass wall times printed, no accuracy, no files written. For measuring
    /// a kernel change before and after.
    #[arg(long, conflicts_with_all = ["quick", "no_scaling"])]
    headline_only: bool,
    /// With `--headline-only`: also each run's rel L1 against the `shadow_map` truth at the
    /// headline size (the truth takes about 10 s per scene on two cores), and then, for
    /// the families run, the ratio lines the full bench reads from the headline.
    #[arg(long, requires = "headline_only")]
    headline_errors: bool,
    /// With `--headline-only`: only the methods with these knobs, as the headline table
    /// names them (repeatable; e.g. `--knobs n64-i1-ep512 --knobs n64-i1`). A name no
    /// headline method has is an error.
    #[arg(long = "knobs", value_name = "KNOBS", requires = "headline_only")]
    knobs: Vec<String>,
    /// With `--headline-only`: the camera pose of the three scenes (ordinary,
    /// epipole_on_screen, light_behind, grazing; the full bench reads its ratios at
    /// ordinary).
    #[arg(long, value_name = "POSE", default_value = "ordinary", requires = "headline_only", value_parser = |s: &str| s.parse::<Pose>())]
    headline_pose: Pose,
    /// Only the machine's bounds (probe kernels: copy bandwidth, texel loads, filtered
    /// fetches, transcendentals, FMAs) and every kernel's cost model against them at the
    /// headline configuration (`scatter_examples::roofline`): two markdown tables printed,
    /// no files written.
    #[arg(long, conflicts_with_all = ["quick", "no_scaling", "headline_only"])]
    roofline: bool,
    /// Only this family's methods, in the sweep and the headline runs (repeatable; e.g.
    /// `--family raymarch --family hybrid_volume` for one family against brute force).
    #[arg(long = "family", value_name = "FAMILY", value_parser = parse_family)]
    families: Vec<Family>,
    /// Sweep a scene of one's own instead of the suite (JSON, `reference/scenes/README.md`;
    /// OBJ meshes by `mesh_file`): its camera at the sweep's 320x180, the default grid of
    /// every family; no scaling or headline runs (they time suite scenes).
    #[arg(long, value_name = "PATH", conflicts_with_all = ["quick", "headline_only", "roofline"])]
    scene_file: Option<PathBuf>,
}

/// A family name, or an error listing the known ones.
fn parse_family(s: &str) -> Result<Family, String> {
    s.parse::<Family>().map_err(|_| {
        let names: Vec<&str> = Family::ALL.iter().map(|f| f.name()).collect();
        format!("unknown family `{s}` (known: {})", names.join(", "))
    })
}

fn main() -> ExitCode {
    let args = Args::parse();
    let mut config = if args.quick {
        BenchConfig::quick()
    } else {
        BenchConfig::default_sweep()
    };
    if let Some(f) = args.frames {
        config.frames = f;
    }
    if args.no_scaling {
        config.scaling = false;
    }
    config.only_families(&args.families);
    if let Some(path) = &args.scene_file {
        match scatter_examples::scene_file::load(path, Some(config.screen)) {
            Ok(loaded) => {
                eprintln!("{}", loaded.report(path));
                config.cases = vec![Case::File(Arc::new(loaded.scene))];
                config.scaling = false;
                config.headline = false;
            }
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        }
    }
    if args.headline_only {
        config.cases.clear();
        config.scaling = false;
        config.headline = true;
        config.headline_error = args.headline_errors;
        config.headline_knobs = args.knobs.clone();
        config.headline_pose = args.headline_pose;
        eprintln!("headline pose: {}", args.headline_pose);
    }
    if args.roofline {
        return roofline(args.frames.unwrap_or(5));
    }
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let result = Context::new()
        .map_err(|e| e.to_string())
        .and_then(|ctx| {
            eprintln!("GPU adapter: {}", ctx.report());
            run(&ctx, &config, true).map_err(|e| e.to_string())
        })
        .and_then(|r| {
            if args.headline_only {
                for line in scatter_examples::bench::headline_lines(&r) {
                    println!("{line}");
                }
                // The machine's state around the timings (probes before, then after).
                for probes in &r.probes {
                    println!("{}", scatter_examples::roofline::bounds_markdown(probes));
                }
                if args.headline_errors {
                    for line in scatter_examples::bench::ratios(&r) {
                        println!("{line}");
                    }
                }
                return Ok((r, Vec::new()));
            }
            write_outputs(&r, &args.out_dir, &command)
                .map(|paths| (r, paths))
                .map_err(|e| e.to_string())
        });
    match result {
        Ok((r, paths)) => {
            if args.headline_only {
                eprintln!("bench done in {:.1} s", r.elapsed.as_secs_f64());
                return ExitCode::SUCCESS;
            }
            for line in scatter_examples::bench::ratios(&r) {
                println!("{line}");
            }
            for p in paths {
                eprintln!("wrote {}", p.display());
            }
            eprintln!("bench done in {:.1} s", r.elapsed.as_secs_f64());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// `--roofline`: the bounds and the cost-model table, printed as markdown.
fn roofline(frames: u32) -> ExitCode {
    use scatter_examples::roofline;
    let result = Context::new().map_err(|e| e.to_string()).and_then(|ctx| {
        eprintln!("GPU adapter: {}", ctx.report());
        let bounds = roofline::measure_bounds(&ctx, frames).map_err(|e| e.to_string())?;
        let rows = roofline::roofline(&ctx, &bounds, frames).map_err(|e| e.to_string())?;
        Ok((bounds, rows))
    });
    match result {
        Ok((bounds, rows)) => {
            println!("{}", roofline::bounds_markdown(&bounds));
            println!("{}", roofline::roofline_markdown(&rows));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
