//! `tune`: "model no more than a scene needs". Measures a grid of variants of every family
//! (`scatter_examples::bench::tune_candidates`: bases, regions, rectified size, ray-march
//! samples and interleaving) on a scene's four poses, then the knobs the grid held fixed
//! (bases per thread, storage, the next rectified sizes) around its Pareto front
//! (`tune_refinements`), and picks the cheapest whose worst rel L1 against the `shadow_map`
//! truth meets each budget; prints the choice, its error and time, and the `scatter-gen`
//! line (plus the runtime's rectified size) that emits it.
//!
//! ```sh
//! cargo run --release -p scatter-examples --example tune -- --scene foliage --max-error 0.02
//! cargo run --release -p scatter-examples --example tune -- --scene-file reference/scenes/mesh_grate.json --max-error 0.02
//! ```
//!
//! With `--scene-file` the scene of one's own is the one view measured (its camera at the
//! sweep's screen size) instead of a suite scene's four poses. A scene lit by an area light
//! (`reference/scenes/area_grate.json`) runs the `area_ivsv` candidates (VPL count, grid,
//! gather), its error measured against the `vpl` truth of 256 VPLs with the engine's map
//! size (the analogue of the `shadow_map` truth: the light's converged VPL set), with 256^2
//! VPL maps, at 160x90 and 256 truth segments (the sum of 256 VPL truths is the cost).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use clap::Parser;
use scatter_examples::bench::{
    BenchConfig, Case, pareto_entries, run, scatter_gen_command, tune_candidates, tune_pick,
    tune_refinements, tune_table,
};
use scatter_reference::suite::{Pose, SceneName};
use scatter_runtime::shaderlib::prefiltered::LightKind;

/// The VPL map size of an area light's scene.
const AREA_SHADOW_MAP: u32 = 256;
use scatter_runtime::Context;

/// Picks the cheapest variant that meets an error budget on a scene.
#[derive(Debug, Parser)]
#[command(name = "tune")]
struct Args {
    /// Suite scene (its four poses).
    #[arg(
        long,
        required_unless_present = "scene_file",
        conflicts_with = "scene_file"
    )]
    scene: Option<SceneName>,
    /// A scene of one's own instead (JSON, `reference/scenes/README.md`; OBJ meshes by
    /// `mesh_file`): its one view.
    #[arg(long, value_name = "PATH")]
    scene_file: Option<PathBuf>,
    /// Error budgets: worst rel L1 over the poses against the shadow_map truth (an area
    /// light: the `vpl` truth of 256 VPLs), as fractions (0.02 = 2 %); several may be given.
    #[arg(long = "max-error", required = true, num_args = 1..)]
    max_error: Vec<f64>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if let Some(bad) = args
        .max_error
        .iter()
        .find(|b| !(b.is_finite() && **b > 0.0 && **b < 1.0))
    {
        eprintln!("error: --max-error must be in (0, 1), got {bad}");
        return ExitCode::from(2);
    }
    let mut config = BenchConfig::default_sweep();
    let scene_name = match (&args.scene_file, args.scene) {
        (Some(path), _) => match scatter_examples::scene_file::load(path, Some(config.screen)) {
            Ok(loaded) => {
                eprintln!("{}", loaded.report(path));
                let name = loaded.scene.name.clone();
                config.cases = vec![Case::File(Arc::new(loaded.scene))];
                name
            }
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        },
        (None, Some(scene)) => {
            config.cases = Pose::ALL.iter().map(|&p| Case::Suite(scene, p)).collect();
            scene.name().to_owned()
        }
        (None, None) => {
            eprintln!("error: give --scene NAME or --scene-file PATH");
            return ExitCode::from(2);
        }
    };
    // An area light's maps are one per VPL (up to 256 layers): 256^2 each, not the sweep's
    // 1024^2 standard map (a 256-layer array of 1024^2 r32float would be 1 GiB).
    // Its truth sums 256 VPLs' truths: at 160x90 and 256 segments (converged at the lamp
    // too: `truth::PointPeak`) it takes minutes, at the sweep's 320x180 and 1024 an hour.
    if config.cases.iter().any(|c| c.light() == LightKind::Area) {
        config.shadow_map = AREA_SHADOW_MAP;
        config.screen = [160, 90];
        config.truth_segments = 256;
    }
    config.rectified = [512, 512];
    config.scaling = false;
    config.headline = false;
    config.skip_over_limits = true;
    config.exact_truth = false;
    let measure = |methods: Vec<scatter_examples::bench::Method>| -> Result<_, String> {
        let config = BenchConfig {
            methods,
            ..config.clone()
        };
        let ctx = Context::new().map_err(|e| e.to_string())?;
        run(&ctx, &config, true).map_err(|e| e.to_string())
    };
    // Stage 1: the grid; stage 2: the knobs it held fixed, around its Pareto front.
    let first = match measure(tune_candidates()) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let refinements = tune_refinements(&tune_table(&first.rows), config.rectified);
    // No refinement (an area light's candidates have none): no second run of the truths.
    let second = if refinements.is_empty() {
        scatter_examples::bench::BenchResult {
            rows: Vec::new(),
            skipped: Vec::new(),
            elapsed: std::time::Duration::ZERO,
            ..first.clone()
        }
    } else {
        match measure(refinements) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        }
    };
    for (id, why) in first.skipped.iter().chain(&second.skipped) {
        eprintln!("skipped {id}: {why}");
    }
    let rows: Vec<_> = first.rows.iter().chain(&second.rows).cloned().collect();
    let table = tune_table(&rows);
    let front = pareto_entries(&table);
    println!(
        "{}: {} candidates ({} refinements) on {} poses ({}x{}, {} s)",
        scene_name,
        table.len(),
        table.len() - tune_table(&first.rows).len(),
        config.cases.len(),
        config.screen[0],
        config.screen[1],
        (first.elapsed + second.elapsed).as_secs()
    );
    for e in &table {
        let on_front = front.iter().any(|f| std::ptr::eq(*f, e));
        println!(
            "  {:<12} {:<28} worst rel L1 {:>7.3} %  mean {:>8.2} ms{}",
            e.family,
            e.knobs,
            100.0 * e.worst_error,
            e.mean_ms,
            if on_front { "  (Pareto)" } else { "" }
        );
    }
    for budget in &args.max_error {
        match tune_pick(&table, *budget) {
            Some(e) => println!(
                "budget {:.1} %: {} {} (worst {:.3} %, {:.2} ms): {}",
                100.0 * budget,
                e.family,
                e.knobs,
                100.0 * e.worst_error,
                e.mean_ms,
                scatter_gen_command(&e.method, config.rectified)
            ),
            None => println!(
                "budget {:.1} %: no candidate meets it (best worst-pose error {:.3} %)",
                100.0 * budget,
                100.0
                    * table
                        .iter()
                        .map(|e| e.worst_error)
                        .fold(f64::INFINITY, f64::min)
            ),
        }
    }
    ExitCode::SUCCESS
}
