//! Conformance of the `partial_sum_tree` family (`depth_columns`, `slice_fit`, `rectify`,
//! `pst_sweep`, `pst_sweep_unwarp`, `pst_sweep_fallback`): the GPU
//! (`scatter_runtime::run_partial_sum_tree_once`) against the CPU mirrors
//! (`reference/src/kernels/{pst_sweep,pst_sweep_unwarp,pst_sweep_fallback}.rs`) for every
//! variant of `PartialSumTreeVariant::grid()` (ranks 1, 4, 8; 64 slices x 64 samples),
//! directional on `columns`, spot on `spot_grate`, at the `ordinary` and `epipole_on_screen`
//! poses and at `ordinary` with the depth buffer at 0.3x (where `slice_fit` narrows the
//! rows), at 67x37 pixels with a 100x60 rectified map and a 128^2 shadow map. Trials are
//! named `partial_sum_tree::<variant id>::<scene>::<pose>`; `partial_sum_tree::errors`
//! checks the error paths.
//!
//! The mirror runs on the GPU's fitted slice table and rectified map, so that the sweep is
//! compared on the same input. Tolerances: every epipolar sample (what `pst_sweep` writes)
//! `|gpu - cpu| <= 1e-4 * max radiance` plus one f16 step of the mirror's value, except at
//! *ties*: samples whose ray depth lies within 1e-4 of a stored depth of the slice's row
//! before its last column, whose column count `x_s` lies within 1e-3 of a whole number,
//! whose slice's row coordinate lies within 1e-3 of a row boundary, or that are marched (a
//! shadow-map texel test), or whose 2 x 2 depth footprint lies within 0.1 % of the depth
//! break (the sample is then its pixel's ray on one side); at most 2 % of the samples may be
//! ties. The sample depths (w)
//! and the slices' lines bit for bit up to the layout's f32 ulps. The screen output (the
//! unwarp's gather and the fallback's pixels) within the same tolerance on all but
//! [`OUTPUT_MISMATCH_SHARE`] of the pixels (a tie sample moves its taps, and the layout's
//! last bits move a pixel's taps, as in `tests/tests/sampling.rs`).

use std::process::ExitCode;
use std::sync::OnceLock;

use scatter_conformance::{Check, Fixture, compare_slices, gpu, run_trials, scene_for};
use scatter_reference::kernels::common_epipolar::ray_row_coord;
use scatter_reference::kernels::common_sampling::{
    EpipolarCamera, epipolar_layout, slice_direction, slice_sample_pixel, slice_span,
};
use scatter_reference::kernels::pst_sweep::{
    PstInputs, pst_columns_crossed, pst_footprint_depth, pst_ray,
};
use scatter_reference::kernels::texture::Tex;
use scatter_reference::kernels::{
    depth_columns, partial_sum_tree_from_rectified, rectify, slice_fit,
};
use scatter_reference::suite::Pose;
use scatter_runtime::{FrameInput, PartialSumTree, RuntimeError, run_partial_sum_tree_once};
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::partial_sum_tree::PartialSumTreeVariant;
use scatter_shaderlib::prefiltered::{FrameSettings, LightKind, Resolutions};

const SCREEN: [u32; 2] = [67, 37];
const RECTIFIED: [u32; 2] = [100, 60];
const SHADOW_MAP: u32 = 128;
const REL_TOL: f32 = 1e-4;
/// The most samples of a trial that may be ties.
const TIE_SHARE: f64 = 0.02;
/// The most output pixels of a trial that may differ beyond the tolerance.
const OUTPUT_MISMATCH_SHARE: f64 = 0.01;

/// The (pose, depth scale) of every trial of a variant.
const POSES: [(Pose, f32); 3] = [
    (Pose::Ordinary, 1.0),
    (Pose::EpipoleOnScreen, 1.0),
    (Pose::Ordinary, 0.3),
];

/// The fixture of (light, pose case) (all built once, on first use).
fn fixture(light: LightKind, i: usize) -> &'static Fixture {
    static ALL: OnceLock<Vec<Fixture>> = OnceLock::new();
    let all = ALL.get_or_init(|| {
        [LightKind::Directional, LightKind::Spot]
            .iter()
            .flat_map(|&light| {
                POSES.iter().map(move |&(pose, scale)| {
                    let f = Fixture::new(scene_for(light), pose, SCREEN, SHADOW_MAP);
                    if scale == 1.0 {
                        f
                    } else {
                        f.with_depth_scaled(scale)
                    }
                })
            })
            .collect()
    });
    let l = usize::from(light == LightKind::Spot);
    &all[l * POSES.len() + i]
}

/// The fixture of `variant`'s trial `i`: its light's, with the `stained_glass` cookie (64^2)
/// on the spot for a `cookie` variant (built once, on first use).
fn variant_fixture(variant: &PartialSumTreeVariant, i: usize) -> &'static Fixture {
    static COOKIE: OnceLock<Vec<Fixture>> = OnceLock::new();
    if !variant.cookie {
        return fixture(variant.light, i);
    }
    let all = COOKIE.get_or_init(|| {
        (0..POSES.len())
            .map(|i| {
                fixture(LightKind::Spot, i).with_cookie(
                    scatter_reference::cookie::Cookie::pattern("stained_glass", 64)
                        .expect("a built-in pattern"),
                )
            })
            .collect()
    });
    &all[i]
}

fn input(f: &Fixture) -> FrameInput {
    f.frame_input(FrameSettings::for_screen(SCREEN[0], SCREEN[1]))
}

fn res() -> Resolutions {
    Resolutions {
        screen: SCREEN,
        rectified: RECTIFIED,
    }
}

/// Spacing of f16 values at `v`.
fn f16_ulp(v: f32) -> f32 {
    let a = v.abs();
    if !a.is_finite() || a < 2f32.powi(-14) {
        return 2f32.powi(-24);
    }
    2f32.powi(a.log2().floor() as i32 - 10)
}

fn over(g: [f32; 4], c: [f32; 4], max: f32) -> bool {
    (0..3).any(|k| {
        let d = (g[k] - c[k]).abs();
        d.is_nan() || d > REL_TOL * max + f16_ulp(c[k])
    })
}

fn trial(
    ctx: &scatter_runtime::Context,
    variant: PartialSumTreeVariant,
    f: &Fixture,
) -> Result<String, String> {
    let spot = variant.light == LightKind::Spot;
    let cookie = f.cookie();
    let cookie_tex = scatter_reference::kernels::cookie_texture(&f.scene);
    let gpu = run_partial_sum_tree_once(
        ctx,
        &variant,
        res(),
        &input(f),
        &f.gbuf.view_depth,
        &f.shadow_map.depth,
        cookie.as_ref().map(|(size, t)| (*size, &t[..])),
    )
    .map_err(|e| format!("GPU run failed: {e}"))?;
    let sm = Tex {
        width: SHADOW_MAP,
        height: SHADOW_MAP,
        data: f.shadow_map.depth.clone(),
    };
    let depth = Tex {
        width: SCREEN[0],
        height: SCREEN[1],
        data: f.gbuf.view_depth.clone(),
    };
    let mut fitted = gpu.frame.frame.slices.clone();
    slice_fit::slice_fit(
        &gpu.frame.frame.uniforms,
        &mut fitted,
        &depth_columns::depth_columns(&gpu.frame.frame.uniforms, &depth),
        spot,
    );
    compare_slices(&gpu.slices, &fitted)?;
    let mut frame = gpu.frame.clone();
    frame.frame.slices = gpu.slices.clone();
    // rectify: reported only (its own conformance lives with the prefiltered family).
    let cpu_rect = rectify::rectify(&frame.frame.uniforms, &frame.frame.slices, &sm, spot);
    let rect_flips = cpu_rect
        .data
        .iter()
        .zip(&gpu.rectified)
        .filter(|(a, b)| (*a - *b).abs() > 1e-4)
        .count();
    let rectified = Tex {
        width: RECTIFIED[0],
        height: RECTIFIED[1],
        data: gpu.rectified.clone(),
    };
    let cpu = partial_sum_tree_from_rectified(
        &variant,
        frame,
        rectified.clone(),
        &depth,
        &sm,
        cookie_tex.as_ref(),
    );
    let inp = PstInputs {
        frame: &cpu.frame.frame.uniforms,
        slices: &cpu.frame.frame.slices,
        depth: &depth,
        shadow_map: &sm,
        rectified: &rectified,
        factors: &cpu.frame.factors,
        cookie: cookie_tex.as_ref(),
    };
    let samples = &cpu.samples.samples;
    if samples.data.len() != gpu.samples.len() {
        return Err("epipolar sample textures differ in size".into());
    }
    let max = samples.data[..]
        .iter()
        .flat_map(|c| c[..3].iter().copied())
        .fold(0.0f32, f32::max);
    if max.is_nan() || max <= 0.0 {
        return Err("the mirror's samples are black".into());
    }
    // The samples, tie-aware.
    let knobs = variant.sampling_knobs();
    let (slices, m) = (knobs.slices, knobs.slice_samples);
    let f = inp.frame;
    let layout = epipolar_layout(&EpipolarCamera::of_frame(f), SCREEN, slices);
    let (mut ties, mut bad, mut worst) = (0usize, Vec::new(), 0.0f32);
    for s in 0..slices {
        let u = slice_direction(&layout, s);
        let span = slice_span(&layout, s, SCREEN, m);
        let at = |k: u32| {
            let t = span[0] + k as f32 * span[1];
            [layout.origin[0] + u[0] * t, layout.origin[1] + u[1] * t]
        };
        let lr = pst_ray(&inp, spot, at(m - 1), 0.0, None);
        let row = lr.row;
        // The slice's row within 0.001 rows of a row boundary either way (with rows on the
        // slices, a map with an even multiple of the slices' count puts every slice there).
        let yc = ray_row_coord(f, lr.dir);
        let row_tie = (yc - yc.round()).abs() < 1e-3;
        let delta = inp.slices[row as usize].delta;
        for k in 0..m {
            let i = (s * (m + 1) + k) as usize;
            let (g, c) = (gpu.samples[i], samples.data[i]);
            let d = (0..3).map(|j| (g[j] - c[j]).abs()).fold(0.0f32, |a, v| {
                if v.is_nan() { f32::INFINITY } else { a.max(v) }
            });
            if !over(g, c, max) {
                worst = worst.max(d);
                continue;
            }
            let p = slice_sample_pixel(&layout, u, span, k, SCREEN);
            let footprint = pst_footprint_depth(&inp, at(k), SCREEN, knobs.depth_break_fraction());
            // A sample at a depth break is its pixel's ray.
            let r = if footprint < 0.0 {
                pst_ray(
                    &inp,
                    spot,
                    [p[0] as f32 + 0.5, p[1] as f32 + 0.5],
                    depth.load(p[0], p[1]),
                    None,
                )
            } else {
                pst_ray(&inp, spot, at(k), footprint, None)
            };
            let n = pst_columns_crossed(f, &r, delta);
            let xs = r.xs_num / delta;
            // The depth-break decision within 0.1 % of the break either way.
            let db = knobs.depth_break_fraction();
            let break_tie = (pst_footprint_depth(&inp, at(k), SCREEN, db * 0.999) < 0.0)
                != (pst_footprint_depth(&inp, at(k), SCREEN, db * 1.001) < 0.0);
            let tie = r.marched
                || row_tie
                || break_tie
                || (xs - xs.round()).abs() < 1e-3
                || (0..n).any(|i| (r.d - rectified.load(i, row)).abs() < 1e-4);
            if tie {
                ties += 1;
            } else {
                bad.push(format!(
                    "slice {s} sample {k} pixel {p:?}: gpu {g:?} cpu {c:?} (n {n}, row {row}, footprint depth {footprint})"
                ));
            }
        }
        // The slice's line.
        let i = (s * (m + 1) + m) as usize;
        let (g, c) = (gpu.samples[i], samples.data[i]);
        if (0..4).any(|j| (g[j] - c[j]).abs() > 1e-3 * c[j].abs().max(1.0)) {
            bad.push(format!("slice {s} line: gpu {g:?} cpu {c:?}"));
        }
    }
    let total = (slices * m) as usize;
    if !bad.is_empty() || ties as f64 > TIE_SHARE * total as f64 {
        return Err(format!(
            "{} samples over tolerance that are not ties, {ties} ties of {total} (at most {} \
             %); first: {}",
            bad.len(),
            100.0 * TIE_SHARE,
            bad.first().cloned().unwrap_or_default()
        ));
    }
    // The screen.
    let out_max = cpu
        .sampled
        .output
        .data
        .iter()
        .flat_map(|c| c[..3].iter().copied())
        .fold(0.0f32, f32::max);
    let out_over = gpu
        .output
        .iter()
        .zip(&cpu.sampled.output.data)
        .filter(|(g, c)| over(**g, **c, out_max))
        .count();
    let pixels = gpu.output.len();
    if out_over as f64 > OUTPUT_MISMATCH_SHARE * pixels as f64 {
        return Err(format!(
            "{out_over} of {pixels} output pixels over tolerance (at most {} %)",
            100.0 * OUTPUT_MISMATCH_SHARE
        ));
    }
    Ok(format!(
        "samples max |diff| {worst:.2e} ({:.2e} of max {max:.3e}) without ties, {ties} ties; \
         {} queries, {} columns inserted, {} marched; output: {out_over} pixels over \
         tolerance, {} evaluated by the fallback; rectify: {rect_flips} texels > 1e-4",
        worst / max,
        cpu.counts.queries,
        cpu.counts.inserted,
        cpu.counts.direct,
        cpu.sampled.evaluated
    ))
}

fn main() -> ExitCode {
    let mut trials: Vec<(String, Check)> = Vec::new();
    for variant in PartialSumTreeVariant::grid() {
        for (i, &(pose, scale)) in POSES.iter().enumerate() {
            let tail = if scale == 1.0 {
                String::new()
            } else {
                format!("::depth_x{scale}")
            };
            let name = format!(
                "{}::{}::{pose}{tail}",
                FamilyVariant::from(variant).trial_name(),
                scene_for(variant.light)
            );
            let check: Check = Box::new(move || {
                let Some(ctx) = gpu() else { return Ok(()) };
                let report = trial(ctx, variant, variant_fixture(&variant, i))?;
                eprintln!("ok   {report}");
                Ok(())
            });
            trials.push((name, check));
        }
    }
    trials.push((
        "partial_sum_tree::errors".to_owned(),
        Box::new(|| {
            bad_input_is_an_error();
            Ok(())
        }),
    ));
    run_trials(trials, &[])
}

fn bad_input_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let v = PartialSumTreeVariant::grid()[1];
    let err = PartialSumTree::new(
        ctx,
        &v,
        Resolutions {
            screen: [0, 4],
            rectified: RECTIFIED,
        },
        SHADOW_MAP,
    )
    .expect_err("zero width");
    assert!(matches!(err, RuntimeError::EmptyInput { .. }), "{err}");
    eprintln!("ok   partial_sum_tree::errors::zero_size: {err}");
    let limits = ctx.device().limits();
    let wide = limits.max_storage_buffer_binding_size / 16 / 1024 + 1;
    let big = PartialSumTreeVariant { slices: 1024, ..v };
    if let Ok(wide) = u32::try_from(wide)
        && wide <= limits.max_texture_dimension_2d
    {
        let err = PartialSumTree::new(
            ctx,
            &big,
            Resolutions {
                screen: SCREEN,
                rectified: [wide, 4],
            },
            SHADOW_MAP,
        )
        .expect_err("scratch too large");
        assert!(
            matches!(err, RuntimeError::LimitExceeded { what, .. } if what.contains("leaves")),
            "{err}"
        );
        eprintln!("ok   partial_sum_tree::errors::scratch: {err}");
    }
    let f = fixture(LightKind::Directional, 0);
    let mut pass =
        PartialSumTree::new(ctx, &v, res(), SHADOW_MAP / 2).unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input(f)).expect_err("shadow map size");
    assert!(matches!(err, RuntimeError::ShadowMapSize { .. }), "{err}");
    eprintln!("ok   partial_sum_tree::errors::shadow_map_size: {err}");
    let mut pass = PartialSumTree::new(
        ctx,
        &PartialSumTreeVariant {
            light: LightKind::Spot,
            ..v
        },
        res(),
        SHADOW_MAP,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input(f)).expect_err("light mismatch");
    assert!(err.to_string().contains("light"), "{err}");
    eprintln!("ok   partial_sum_tree::errors::light_mismatch: {err}");
    let mut input = input(f);
    input.camera.forward.y = f64::NAN;
    let mut pass =
        PartialSumTree::new(ctx, &v, res(), SHADOW_MAP).unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input).expect_err("NaN camera");
    assert!(err.to_string().contains("camera"), "{err}");
    eprintln!("ok   partial_sum_tree::errors::nan_camera: {err}");
}
