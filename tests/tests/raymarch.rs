//! Conformance of the `raymarch` family (`raymarch`, `interleave_sum`): the GPU
//! (`scatter_runtime::run_raymarch_once`) against the CPU mirrors
//! (`reference/src/kernels/{raymarch,interleave_sum}.rs`, driven by
//! `scatter_reference::kernels::run_raymarch`) for every variant of
//! `RaymarchVariant::grid()` (samples {8, 32, 128} x interleave {1, 2, 4} x jitter x light),
//! directional on `columns/ordinary`, spot on `spot_grate/ordinary`, at 67x37 pixels (not a
//! multiple of the 8x8 workgroups, nor of the interleaving tiles) with a 128^2 shadow map.
//! Trials are named `raymarch::<variant id>::<scene>::<pose>` (libtest trials: `cargo test -p
//! scatter-conformance --test raymarch -- n32-i2` runs a few, `-- --list` lists them);
//! `raymarch::errors` checks the error paths.
//!
//! Tolerance: `|gpu - cpu| <= 1e-4 * max radiance` plus one f16 step of the mirror's value
//! for the output (both round to rgba16float), `1e-4 * max` for the rgba32float partial sums.

use std::process::ExitCode;
use std::sync::OnceLock;

use scatter_conformance::{Check, Fixture, gpu, run_trials, scene_for};
use scatter_reference::cookie::Cookie;
use scatter_reference::kernels::run_raymarch;
use scatter_reference::suite::Pose;
use scatter_runtime::{Raymarch, RuntimeError, run_raymarch_once};
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::prefiltered::LightKind;
use scatter_shaderlib::raymarch::RaymarchVariant;

const SCREEN: [u32; 2] = [67, 37];
const SHADOW_MAP: u32 = 128;
const REL_TOL: f32 = 1e-4;

/// The fixture of a variant (built once, on first use): its light's scene, with the
/// `stained_glass` cookie (64^2) for a `cookie` variant.
fn fixture(variant: &RaymarchVariant) -> &'static Fixture {
    static COLUMNS: OnceLock<Fixture> = OnceLock::new();
    static SPOT_GRATE: OnceLock<Fixture> = OnceLock::new();
    static SPOT_COOKIE: OnceLock<Fixture> = OnceLock::new();
    let light = variant.light;
    let plain = |cell: &'static OnceLock<Fixture>| {
        cell.get_or_init(|| Fixture::new(scene_for(light), Pose::Ordinary, SCREEN, SHADOW_MAP))
    };
    match light {
        LightKind::Directional => plain(&COLUMNS),
        LightKind::Spot if variant.cookie => SPOT_COOKIE.get_or_init(|| {
            plain(&SPOT_GRATE)
                .with_cookie(Cookie::pattern("stained_glass", 64).expect("a built-in pattern"))
        }),
        // The raymarch grid has no area light (the variant refuses it).
        LightKind::Spot | LightKind::Area => plain(&SPOT_GRATE),
    }
}

fn trial_name(variant: &RaymarchVariant) -> String {
    format!(
        "{}::{}::{}",
        FamilyVariant::from(*variant).trial_name(),
        scene_for(variant.light),
        Pose::Ordinary
    )
}

/// Spacing of f16 values at `v`.
fn f16_ulp(v: f32) -> f32 {
    let a = v.abs();
    if !a.is_finite() || a < 2f32.powi(-14) {
        return 2f32.powi(-24);
    }
    2f32.powi(a.log2().floor() as i32 - 10)
}

fn trial(ctx: &scatter_runtime::Context, variant: &RaymarchVariant) -> Result<String, String> {
    let f = fixture(variant);
    let name = trial_name(variant);
    let cpu = run_raymarch(variant, &f.scene, &f.gbuf, &f.shadow_map)
        .map_err(|e| format!("{name}: CPU mirror failed: {e}"))?;
    let gpu = run_raymarch_once(
        ctx,
        variant,
        SCREEN,
        &f.raymarch_input(),
        &f.gbuf.view_depth,
        &f.shadow_map.depth,
        f.cookie().as_ref().map(|(size, t)| (*size, &t[..])),
    )
    .map_err(|e| format!("{name}: GPU run failed: {e}"))?;
    if gpu.uniforms != cpu.uniforms {
        return Err(format!("{name}: different uniform blocks"));
    }
    let max = cpu
        .output
        .data
        .iter()
        .flatten()
        .fold(0.0f32, |m, &v| m.max(v));
    if max.is_nan() || max <= 0.0 {
        return Err(format!("{name}: the mirror's image is black"));
    }
    let mut worst: f32 = 0.0;
    let mut over = 0;
    for (g, c) in gpu.output.iter().zip(&cpu.output.data) {
        for k in 0..3 {
            let d = (g[k] - c[k]).abs();
            let d = if d.is_nan() { f32::INFINITY } else { d };
            worst = worst.max(d);
            if d > REL_TOL * max + f16_ulp(c[k]) {
                over += 1;
            }
        }
    }
    let mut worst_partial: f32 = 0.0;
    match (&gpu.partial, &cpu.partial) {
        (Some(g), Some(c)) => {
            let pmax = c.data.iter().flatten().fold(0.0f32, |m, &v| m.max(v));
            for (a, b) in g.iter().zip(&c.data) {
                for k in 0..3 {
                    let d = (a[k] - b[k]).abs();
                    worst_partial = worst_partial.max(if d.is_nan() { f32::INFINITY } else { d });
                }
            }
            if worst_partial > REL_TOL * pmax {
                return Err(format!(
                    "{name}: partial sums differ by {worst_partial:e} > {:e}",
                    REL_TOL * pmax
                ));
            }
        }
        (None, None) => {}
        _ => return Err(format!("{name}: partial sums on one side only")),
    }
    if over > 0 {
        return Err(format!(
            "{name}: {over} output values over tolerance, worst |diff| {worst:e} ({:.2e} of max {max:e})",
            worst / max
        ));
    }
    let times = gpu.gpu_times.map_or_else(
        || "gpu n/a".to_owned(),
        |t| {
            format!(
                "gpu raymarch {:.2} ms interleave_sum {:.2} ms",
                t.raymarch.as_secs_f64() * 1e3,
                t.interleave_sum.as_secs_f64() * 1e3
            )
        },
    );
    Ok(format!(
        "{name}: output max |diff| {worst:.2e} ({:.2e} of max {max:.3e}); partial {worst_partial:.2e}; {times}",
        worst / max
    ))
}

fn main() -> ExitCode {
    let mut trials: Vec<(String, Check)> = RaymarchVariant::grid()
        .into_iter()
        .map(|variant| {
            let check: Check = Box::new(move || {
                let Some(ctx) = gpu() else { return Ok(()) };
                trial(ctx, &variant).map(drop)
            });
            (trial_name(&variant), check)
        })
        .collect();
    trials.push((
        "raymarch::errors".to_owned(),
        Box::new(|| {
            bad_input_is_an_error();
            Ok(())
        }),
    ));
    run_trials(trials, &[])
}

fn bad_input_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let bad = RaymarchVariant {
        samples: 30,
        interleave: 2,
        ..RaymarchVariant::default()
    };
    let err = Raymarch::new(ctx, &bad, SCREEN, SHADOW_MAP).expect_err("30 samples, interleave 2");
    assert!(
        matches!(&err, RuntimeError::InvalidRaymarchVariant { source, .. } if source.knob == "samples")
            && err.to_string().contains("30"),
        "{err}"
    );
    eprintln!("ok   raymarch::errors::samples: {err}");
    let err = Raymarch::new(ctx, &RaymarchVariant::default(), [0, 4], SHADOW_MAP)
        .expect_err("zero width");
    assert!(matches!(err, RuntimeError::EmptyInput { .. }), "{err}");
    eprintln!("ok   raymarch::errors::zero_size: {err}");
    let f = fixture(&RaymarchVariant::default());
    let mut pass = Raymarch::new(ctx, &RaymarchVariant::default(), SCREEN, SHADOW_MAP / 2)
        .unwrap_or_else(|e| panic!("{e}"));
    let err = pass
        .prepare(ctx, &f.raymarch_input())
        .expect_err("shadow map size");
    assert!(matches!(err, RuntimeError::ShadowMapSize { .. }), "{err}");
    eprintln!("ok   raymarch::errors::shadow_map_size: {err}");
    let mut input = f.raymarch_input();
    input.camera.forward.y = f64::NAN;
    let mut pass = Raymarch::new(ctx, &RaymarchVariant::default(), SCREEN, SHADOW_MAP)
        .unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input).expect_err("NaN camera");
    assert!(err.to_string().contains("camera"), "{err}");
    eprintln!("ok   raymarch::errors::nan_camera: {err}");
    // A 1x1 screen with interleaving (windows shrink to the screen) runs.
    let tiny = run_raymarch_once(
        ctx,
        &RaymarchVariant {
            interleave: 4,
            ..RaymarchVariant::default()
        },
        [1, 1],
        &f.raymarch_input(),
        &[5.0],
        &f.shadow_map.depth,
        None,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(tiny.output[0].iter().all(|v| v.is_finite()));
    cookie_errors(ctx);
}

/// A cookie on a directional light, a `cookie` variant encoded without one, a cookie for
/// a variant without the knob, and a cookie of the wrong format: each a clear error.
fn cookie_errors(ctx: &scatter_runtime::Context) {
    let cookie = RaymarchVariant {
        light: LightKind::Spot,
        cookie: true,
        ..RaymarchVariant::default()
    };
    let err = Raymarch::new(
        ctx,
        &RaymarchVariant {
            light: LightKind::Directional,
            ..cookie
        },
        SCREEN,
        SHADOW_MAP,
    )
    .expect_err("cookie on a directional light");
    assert!(err.to_string().contains("cookie"), "{err}");
    eprintln!("ok   raymarch::errors::cookie_directional: {err}");
    let f = fixture(&cookie);
    let mut pass =
        Raymarch::new(ctx, &cookie, SCREEN, SHADOW_MAP).unwrap_or_else(|e| panic!("{e}"));
    pass.prepare(ctx, &f.raymarch_input())
        .unwrap_or_else(|e| panic!("{e}"));
    let views: Vec<_> = [
        ("depth buffer", SCREEN, &f.gbuf.view_depth),
        ("shadow map", [SHADOW_MAP; 2], &f.shadow_map.depth),
    ]
    .into_iter()
    .map(|(what, size, data)| {
        let t = scatter_runtime::textures::upload_r32float(
            ctx,
            scatter_runtime::shaderlib::Kernel::Raymarch,
            what,
            size,
            data,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let v = t.create_view(&Default::default());
        (t, v)
    })
    .collect();
    let mut encoder = ctx
        .device()
        .create_command_encoder(&scatter_runtime::wgpu::CommandEncoderDescriptor::default());
    let err = pass
        .encode(ctx, &mut encoder, &views[0].1, &views[1].1)
        .expect_err("no cookie set");
    assert!(matches!(err, RuntimeError::MissingInput { .. }), "{err}");
    assert!(err.to_string().contains("set_cookie"), "{err}");
    eprintln!("ok   raymarch::errors::cookie_missing: {err}");
    // The depth buffer is r32float: not a cookie format.
    let err = pass.set_cookie(&views[0].1).expect_err("r32float cookie");
    assert!(matches!(err, RuntimeError::InputMismatch { .. }), "{err}");
    eprintln!("ok   raymarch::errors::cookie_format: {err}");
    let mut plain = Raymarch::new(
        ctx,
        &RaymarchVariant {
            light: LightKind::Spot,
            ..RaymarchVariant::default()
        },
        SCREEN,
        SHADOW_MAP,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let texture = scatter_runtime::textures::upload_cookie(
        ctx,
        scatter_runtime::shaderlib::Kernel::Raymarch,
        [2, 1],
        &[[1.0; 4], [0.5; 4]],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let err = plain
        .set_cookie(&texture.create_view(&Default::default()))
        .expect_err("cookie without the knob");
    assert!(err.to_string().contains("cookie"), "{err}");
    eprintln!("ok   raymarch::errors::cookie_without_knob: {err}");
}
