//! Measures the reference on the whole suite and writes a contact sheet.
//!
//! ```text
//! cargo run --release -p scatter-examples --example suite_report -- --out-dir out/suite
//! ```
//!
//! Per scene and pose: occluder count, time to cast the 1280x720 depth buffer, time of the
//! `exact` truth at the report resolution (default 320x180), and the rel L1 between the
//! `exact` and `shadow_map` truths for shadow maps of 512, 1024 and 2048 texels (the
//! discretisation error every shadow-map method inherits). Prints a Markdown table and writes
//! `contact_sheet.png` (composites, one row per scene, one column per pose) and
//! `contact_sheet_inscatter.png`.

use clap::Parser;
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::metrics;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// Measure the reference on the scene suite.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Report resolution width.
    #[arg(long, default_value_t = 320, value_parser = clap::value_parser!(u32).range(1..=4096))]
    width: u32,
    /// Report resolution height.
    #[arg(long, default_value_t = 180, value_parser = clap::value_parser!(u32).range(1..=4096))]
    height: u32,
    /// Only the `ordinary` pose (faster).
    #[arg(long)]
    ordinary_only: bool,
    /// Medium preset: default, thick, thin.
    #[arg(long, default_value = "default", value_parser = |s: &str| s.parse::<MediumPreset>())]
    medium: MediumPreset,
    /// Where to write the contact sheets.
    #[arg(long)]
    out_dir: PathBuf,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if let Err(e) = run(&args) {
        eprintln!("suite_report: {e}");
        return ExitCode::from(2);
    }
    ExitCode::SUCCESS
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(&args.out_dir)
        .map_err(|e| format!("cannot create {}: {e}", args.out_dir.display()))?;
    let poses: &[Pose] = if args.ordinary_only {
        &[Pose::Ordinary]
    } else {
        Pose::ALL
    };
    println!(
        "| scene/pose | occluders | depth 1280x720 | exact truth {}x{} | rel L1 exact vs shadow_map 512 / 1024 / 2048 |",
        args.width, args.height
    );
    println!("|---|---|---|---|---|");
    let mut rows = Vec::new();
    let mut rows_ins = Vec::new();
    for &name in SceneName::ALL {
        let mut row = Vec::new();
        let mut row_ins = Vec::new();
        for &pose in poses {
            let big = suite::scene(name, pose, args.medium, 1280, 720);
            let bvh = Bvh::build(&big.geometry);
            let t = Instant::now();
            let _ = GBuffer::cast(&big, &bvh);
            let depth_time = t.elapsed();

            let scene = suite::scene(name, pose, args.medium, args.width, args.height);
            let gbuf = GBuffer::cast(&scene, &bvh);
            let settings = TruthSettings::default();
            let t = Instant::now();
            let exact = truth::render(&scene, &gbuf, &Visibility::Exact(&bvh), &settings, &|| ());
            let truth_time = t.elapsed();
            let mut l1 = Vec::new();
            for size in [512, 1024, 2048] {
                let sm = ShadowMap::build(&scene, &bvh, size)?;
                let img = truth::render(
                    &scene,
                    &gbuf,
                    &Visibility::ShadowMap(&sm),
                    &settings,
                    &|| (),
                );
                l1.push(format!("{:.2} %", 100.0 * metrics::rel_l1(&img, &exact)?));
            }
            println!(
                "| {} | {} | {:.2?} | {:.2?} | {} |",
                scene.name,
                scene.occluder_count(),
                depth_time,
                truth_time,
                l1.join(" / ")
            );
            let surf = truth::surface_radiance(&scene, &gbuf, &bvh);
            row.push(surf.add(&exact)?);
            row_ins.push(exact);
        }
        rows.push(row);
        rows_ins.push(row_ins);
    }
    for (rows, file) in [
        (rows, "contact_sheet.png"),
        (rows_ins, "contact_sheet_inscatter.png"),
    ] {
        // Each image is tone-mapped with its own exposure, then the sheet is assembled.
        let tiles: Vec<Image> = rows
            .iter()
            .map(|r| {
                let normalised: Vec<Image> = r
                    .iter()
                    .map(|img| {
                        let e = img.auto_exposure();
                        Image::from_pixels(
                            img.width,
                            img.height,
                            img.data.iter().map(|c| c.map(|x| x * e)).collect(),
                        )
                    })
                    .collect();
                Image::hstack(&normalised.iter().collect::<Vec<_>>())
            })
            .collect::<Result<_, _>>()?;
        let sheet = Image::vstack(&tiles.iter().collect::<Vec<_>>());
        let path = args.out_dir.join(file);
        sheet.write_png(&path, Some(1.0))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
