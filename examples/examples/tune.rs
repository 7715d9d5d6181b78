//! `tune`: "model no more than a scene needs". Measures every candidate variant of every
//! family (`scatter_examples::bench::tune_candidates`) on a scene's four poses and picks the
//! cheapest whose worst rel L1 against the `shadow_map` truth meets the budget; prints the
//! choice, its error and time, and the `scatter-gen` line that emits it.
//!
//! ```sh
//! cargo run --release -p scatter-examples --example tune -- --scene foliage --max-error 0.02
//! ```

use std::process::ExitCode;

use clap::Parser;
use scatter_examples::bench::{
    BenchConfig, run, scatter_gen_command, scene_light, tune_candidates, tune_pick, tune_table,
};
use scatter_reference::suite::{Pose, SceneName};
use scatter_runtime::Context;

/// Picks the cheapest variant that meets an error budget on a scene.
#[derive(Debug, Parser)]
#[command(name = "tune")]
struct Args {
    /// Suite scene.
    #[arg(long)]
    scene: SceneName,
    /// Error budgets: worst rel L1 over the poses against the shadow_map truth, as fractions
    /// (0.02 = 2 %); several may be given.
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
    config.cases = Pose::ALL.iter().map(|&p| (args.scene, p)).collect();
    config.methods = tune_candidates();
    config.scaling = false;
    config.headline = false;
    let result = Context::new()
        .map_err(|e| e.to_string())
        .and_then(|ctx| run(&ctx, &config, true).map_err(|e| e.to_string()));
    let result = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let table = tune_table(&result.rows);
    println!(
        "{}: {} candidates on {} poses ({}x{}, {} s)",
        args.scene,
        table.len(),
        config.cases.len(),
        config.screen[0],
        config.screen[1],
        result.elapsed.as_secs()
    );
    for e in &table {
        println!(
            "  {:<12} {:<8} worst rel L1 {:>7.3} %  mean {:>8.2} ms",
            e.family,
            e.knobs,
            100.0 * e.worst_error,
            e.mean_ms
        );
    }
    let light = scene_light(args.scene);
    for budget in &args.max_error {
        match tune_pick(&table, *budget) {
            Some(e) => println!(
                "budget {:.1} %: {} {} (worst {:.3} %, {:.2} ms): {}",
                100.0 * budget,
                e.family,
                e.knobs,
                100.0 * e.worst_error,
                e.mean_ms,
                scatter_gen_command(e, light)
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
