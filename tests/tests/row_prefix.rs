//! Conformance of the `row_prefix` kernel: GPU against the CPU mirror
//! (`reference/src/kernels/row_prefix.rs`) for both modes, on sizes that are and are not
//! multiples of the workgroup size, plus the runtime's input checks.
//!
//! Tolerances (inputs in [-1, 1), f32 throughout):
//! - `sum`: GPU and mirror add in the same order, so results should be identical; we allow
//!   `|gpu - cpu| <= 4 * eps * sum_{i<=x} |in_i|` (a few ulp of the largest partial sum),
//!   which covers a driver that contracts or flushes denormals but fails any wrong index.
//! - `mean`: `mix` may be lowered as `a * (1 - t) + b * t`, `a + t * (b - a)` or with an FMA;
//!   each step differs by a few ulp of max(|F|, |B|) <= 1 and the running mean damps old
//!   errors by `i / (i + 1)` per step, so after n steps the difference is bounded by about
//!   `n/2` steps' worth; we allow `|gpu - cpu| <= 4 * eps * (x + 1)`.

use scatter_conformance::{gpu, mirror_dims, row_prefix_mirror_mode, test_texels, ulp_distance};
use scatter_reference::kernels::row_prefix as mirror;
use scatter_runtime::{ArraySize, RuntimeError, row_prefix};
use scatter_shaderlib::{RowPrefixMode, RowPrefixParams};

const SIZES: &[ArraySize] = &[
    ArraySize::new(1, 1, 1),
    ArraySize::new(37, 5, 2),
    ArraySize::new(64, 64, 1),
    ArraySize::new(3, 65, 3),
    ArraySize::new(1024, 64, 8),
];

/// Largest deviation found in one trial.
#[derive(Default)]
struct Deviation {
    max_abs: f32,
    max_ulp: u32,
    max_ratio: f32,
}

fn run_trial(
    ctx: &scatter_runtime::Context,
    params: RowPrefixParams,
    size: ArraySize,
    seed: u64,
) -> Result<String, String> {
    let trial = format!("common::row_prefix::{}::{size}", params.mode.name());
    let input = test_texels(size.texel_count() as usize, seed);
    let out = row_prefix(ctx, params, size, &input).map_err(|e| format!("{trial}: {e}"))?;
    let cpu = mirror::row_prefix(
        row_prefix_mirror_mode(params.mode),
        mirror_dims(size),
        &input,
    );
    let mut dev = Deviation::default();
    let mut first_failure = None;
    for layer in 0..size.layers {
        for row in 0..size.height {
            let mut abs_sum = [0.0f32; 4];
            for x in 0..size.width {
                let i = size.index(x, row, layer);
                for c in 0..4 {
                    abs_sum[c] += input[i][c].abs();
                    let (g, r) = (out.texels[i][c], cpu[i][c]);
                    let tol = match params.mode {
                        RowPrefixMode::Sum => 4.0 * f32::EPSILON * abs_sum[c],
                        RowPrefixMode::Mean => 4.0 * f32::EPSILON * (x + 1) as f32,
                    };
                    let d = (g - r).abs();
                    dev.max_abs = dev.max_abs.max(d);
                    dev.max_ulp = dev.max_ulp.max(ulp_distance(g, r));
                    dev.max_ratio = dev.max_ratio.max(d / tol);
                    // `d <= tol` is false for NaN, which must fail too.
                    let within = d <= tol;
                    if !within && first_failure.is_none() {
                        first_failure = Some(format!(
                            "texel (x {x}, row {row}, layer {layer}) channel {c}: gpu {g:e} cpu {r:e} |diff| {d:e} > tol {tol:e}"
                        ));
                    }
                }
            }
        }
    }
    let timing = match out.gpu_time {
        Some(t) => format!(
            "gpu {:.3} ms, wall {:.3} ms",
            t.as_secs_f64() * 1e3,
            out.wall_time.as_secs_f64() * 1e3
        ),
        None => format!("gpu n/a, wall {:.3} ms", out.wall_time.as_secs_f64() * 1e3),
    };
    let summary = format!(
        "{trial}: max |diff| {:e}, max {} ulp, max diff/tol {:.3}; {timing}",
        dev.max_abs, dev.max_ulp, dev.max_ratio
    );
    match first_failure {
        None => Ok(summary),
        Some(f) => Err(format!("{summary}\n  FAILED at {f}")),
    }
}

fn conformance(mode: RowPrefixMode) {
    let Some(ctx) = gpu() else { return };
    let params = RowPrefixParams {
        mode,
        ..RowPrefixParams::default()
    };
    let mut failures = Vec::new();
    for (seed, &size) in SIZES.iter().enumerate() {
        match run_trial(ctx, params, size, seed as u64) {
            Ok(line) => eprintln!("ok   {line}"),
            Err(line) => {
                eprintln!("FAIL {line}");
                failures.push(line);
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} trial(s) failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn mean_matches_mirror() {
    conformance(RowPrefixMode::Mean);
}

#[test]
fn sum_matches_mirror() {
    conformance(RowPrefixMode::Sum);
}

#[test]
fn odd_workgroup_sizes_match_mirror() {
    let Some(ctx) = gpu() else { return };
    let mut failures = Vec::new();
    for workgroup_size in [1, 7, 256] {
        for &mode in RowPrefixMode::ALL {
            let params = RowPrefixParams {
                mode,
                workgroup_size,
            };
            match run_trial(
                ctx,
                params,
                ArraySize::new(33, 300, 2),
                u64::from(workgroup_size),
            ) {
                Ok(line) => eprintln!("ok   {line} (workgroup {workgroup_size})"),
                Err(line) => failures.push(format!("{line} (workgroup {workgroup_size})")),
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let Some(ctx) = gpu() else { return };
    let params = RowPrefixParams::default();
    for size in [
        ArraySize::new(0, 4, 1),
        ArraySize::new(4, 0, 1),
        ArraySize::new(4, 4, 0),
    ] {
        let err = row_prefix(ctx, params, size, &[]).expect_err("empty input");
        assert!(
            matches!(err, RuntimeError::EmptyInput { .. }),
            "{size}: {err}"
        );
        eprintln!("ok   common::row_prefix::errors::{size}: {err}");
    }
    let max_2d = ctx.device().limits().max_texture_dimension_2d;
    let wide = ArraySize::new(max_2d + 1, 1, 1);
    let err = row_prefix(ctx, params, wide, &[]).expect_err("too wide");
    assert!(
        err.to_string().contains("max_texture_dimension_2d"),
        "{err}"
    );
    eprintln!("ok   common::row_prefix::errors::{wide}: {err}");
    let max_layers = ctx.device().limits().max_texture_array_layers;
    let deep = ArraySize::new(1, 1, max_layers + 1);
    let err = row_prefix(ctx, params, deep, &[]).expect_err("too many layers");
    assert!(
        err.to_string().contains("max_texture_array_layers"),
        "{err}"
    );
    let size = ArraySize::new(3, 2, 1);
    let err = row_prefix(ctx, params, size, &[[0.0; 4]; 5]).expect_err("short data");
    assert!(
        matches!(
            err,
            RuntimeError::DataLength {
                expected: 6,
                actual: 5,
                ..
            }
        ),
        "{err}"
    );
    eprintln!("ok   common::row_prefix::errors::{size}: {err}");
    let huge = RowPrefixParams {
        workgroup_size: 1024,
        ..params
    };
    match scatter_runtime::RowPrefixPass::new(ctx, huge) {
        Ok(_) => assert!(ctx.device().limits().max_compute_invocations_per_workgroup >= 1024),
        Err(err) => assert!(err.to_string().contains("max_compute"), "{err}"),
    }
}
