//! `scatter-foreign-engine`: runs one frame of a variant that `scatter-gen` emitted, on raw
//! wgpu, from the shader directory's `manifest.json` and an input directory of plain files
//! (`frame.json`, `depth.pfm`, `shadow_map.pfm`, `rectified.pfm` for projective frames,
//! `vpl_maps.pfm` for an area light; see
//! the library's `files` module), and writes the in-scattered radiance as a colour PFM.
//!
//! Exit codes: 0 success, 1 failure (one line on stderr), 2 bad command line.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use scatter_foreign_engine::files::{RunArgs, run_dir};
use scatter_foreign_engine::{EngineError, Target};

/// Runs scatter-gen's shaders from manifest.json alone, on raw wgpu.
#[derive(Debug, Parser)]
#[command(
    name = "scatter-foreign-engine",
    version,
    after_help = "Example:\n  cargo run -p scatter-gen -- --out /tmp/shaders --target spirv,wgsl\n  \
                  cargo run -p scatter-examples --example foreign_inputs -- --out /tmp/inputs\n  \
                  cargo run -p scatter-foreign-engine -- --shaders /tmp/shaders --inputs /tmp/inputs --out /tmp/inscatter.pfm"
)]
struct Cli {
    /// Directory written by scatter-gen (manifest.json and the shader files).
    #[arg(long, value_name = "DIR")]
    shaders: PathBuf,
    /// PrefilteredVariant id (from the manifest); may be left out when it has only one.
    #[arg(long, value_name = "ID")]
    variant: Option<String>,
    /// Input directory: frame.json, depth.pfm, shadow_map.pfm (rectified.pfm; an area
    /// light's vpl_maps.pfm).
    #[arg(long, value_name = "DIR")]
    inputs: PathBuf,
    /// Output PFM (colour) of the in-scattered radiance.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Which emitted shaders to load: spirv or wgsl.
    #[arg(long, default_value = "spirv")]
    target: Target,
}

fn device() -> Result<(wgpu::Device, wgpu::Queue, String), EngineError> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..wgpu::RequestAdapterOptions::default()
    }))
    .map_err(|e| EngineError::NoDevice(e.to_string()))?;
    let info = adapter.get_info();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("scatter-foreign-engine"),
        required_features: wgpu::Features::empty(),
        required_limits: adapter.limits(),
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    }))
    .map_err(|e| EngineError::NoDevice(e.to_string()))?;
    Ok((device, queue, format!("{} ({:?})", info.name, info.backend)))
}

fn run(cli: Cli) -> Result<(), EngineError> {
    let (device, queue, adapter) = device()?;
    let start = Instant::now();
    let summary = run_dir(
        &device,
        &queue,
        &RunArgs {
            shaders: cli.shaders,
            variant: cli.variant,
            inputs: cli.inputs,
            out: cli.out.clone(),
            target: cli.target,
        },
    )?;
    let max = summary
        .radiance
        .iter()
        .flat_map(|p| &p[..3])
        .fold(0.0f32, |m, &v| m.max(v));
    let [w, h] = summary.screen;
    let frame = summary.frame.as_ref().map_or_else(
        || "per-pixel march".to_owned(),
        |f| {
            format!(
                "{} frame{}",
                f.report.rectification,
                f.report
                    .fallback
                    .map(|f| format!(" (fell back: {f})"))
                    .unwrap_or_default()
            )
        },
    );
    println!(
        "{} ({}) on {adapter} from {}: {w}x{h}, {frame}",
        summary.variant, summary.family, cli.target,
    );
    for (kernel, [x, y, z]) in &summary.run.dispatched {
        println!("  dispatched {kernel} {x}x{y}x{z}");
    }
    for kernel in &summary.run.skipped {
        println!("  skipped {kernel} (skip_when)");
    }
    for alt in &summary.run.alternatives {
        println!("  alternative {alt}");
    }
    println!(
        "  max radiance {max:.4e}; {:.0} ms (load, run, read back){}",
        start.elapsed().as_secs_f64() * 1e3,
        cli.out
            .map(|p| format!("; wrote {}", p.display()))
            .unwrap_or_default()
    );
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("scatter-foreign-engine: {e}");
            ExitCode::FAILURE
        }
    }
}
