//! Conformance of the `hybrid_volume` family (`depth_columns`, `slice_fit`, `rectify`,
//! `volume_bounds`, `volume_march`): the GPU (`scatter_runtime::run_hybrid_volume_once`)
//! against the CPU mirrors (`reference/src/kernels/{volume_bounds,volume_march}.rs`) for every
//! variant of `HybridVolumeVariant::grid()`: directional on `columns`, spot on `spot_grate`, at
//! the `ordinary` and `epipole_on_screen` poses (the latter marches pixels near the epipole),
//! and the default directional variant with the depth buffer at 0.3x (`slice_fit` narrows the
//! rows); 67x37 pixels, a 100x60 rectified map (neither a power of two nor a multiple of the
//! workgroups), a 128^2 shadow map. Trials are named
//! `hybrid_volume::<variant id>::<scene>::<pose>`; `hybrid_volume::errors` checks the error
//! paths.
//!
//! The mirrors of `volume_bounds` and `volume_march` run on the GPU's rectified map, so that
//! each kernel is compared on the same input. Tolerances: the crossings bit for bit (integer
//! min and max of the same edges); the output `|gpu - cpu| <= 1e-4 * max radiance` plus one
//! f16 step of the mirror's value, except at *ties* (at most 1 % of the pixels): pixels whose
//! ray depth lies within 1e-4 of a stored depth of one of its two rows or within 1e-3 bins of
//! a bin boundary, whose row coordinate lies within 1e-3 of a row boundary, whose column
//! lies within 1e-3 texels of an edge, or which lie within 1e-3 px of the epipole disc's
//! rim, where a few ulps of `atan2` legitimately move a crossing, the bin, the row pair or the
//! ray's texel count; and pixels whose march moves by more than 1e-3 of itself when the
//! interval's ends move by 1e-5 of their distance (samples on a shadow-map texel border:
//! near the epipole the view ray runs almost along the light rays, and one shift moves
//! several samples across the same border).

use std::process::ExitCode;
use std::sync::OnceLock;

use scatter_conformance::{Check, Fixture, compare_slices, gpu, run_trials, scene_for};
use scatter_reference::kernels::common_epipolar::{
    normalised_depth, pixel_dir, ray_column, ray_row_coord, ray_theta, row_index,
};
use scatter_reference::kernels::texture::{Tex, xyz};
use scatter_reference::kernels::volume_march::{
    MarchInputs, PixelSpan, pixel_span, span_sum, surface_distance,
};
use scatter_reference::kernels::{depth_columns, hybrid_volume_from_rectified, slice_fit};
use scatter_reference::suite::Pose;
use scatter_runtime::{FrameInput, HybridVolume, RuntimeError, run_hybrid_volume_once};
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::hybrid_volume::HybridVolumeVariant;
use scatter_shaderlib::prefiltered::{FrameSettings, LightKind, Resolutions};

const SCREEN: [u32; 2] = [67, 37];
const RECTIFIED: [u32; 2] = [100, 60];
const SHADOW_MAP: u32 = 128;
const REL_TOL: f32 = 1e-4;

/// Every trial: (variant index in the grid, pose, depth scale).
fn cases() -> Vec<(HybridVolumeVariant, Pose, f32)> {
    let mut out = Vec::new();
    for v in HybridVolumeVariant::grid() {
        for pose in [Pose::Ordinary, Pose::EpipoleOnScreen] {
            out.push((v, pose, 1.0));
        }
    }
    out.push((HybridVolumeVariant::default(), Pose::Ordinary, 0.3));
    out
}

/// The fixture of (light, pose, depth scale, cookie), built once per distinct key; a cookie
/// variant's has the `stained_glass` cookie (64^2).
fn fixture(light: LightKind, pose: Pose, scale: f32, cookie: bool) -> &'static Fixture {
    type Key = (LightKind, Pose, u32, bool);
    static ALL: OnceLock<Vec<(Key, Fixture)>> = OnceLock::new();
    let all = ALL.get_or_init(|| {
        let mut keys: Vec<Key> = cases()
            .iter()
            .map(|&(v, pose, scale)| (v.light, pose, scale.to_bits(), v.cookie))
            .chain([(
                LightKind::Directional,
                Pose::Ordinary,
                1f32.to_bits(),
                false,
            )])
            .collect();
        keys.sort();
        keys.dedup();
        keys.into_iter()
            .map(|key @ (light, pose, bits, cookie)| {
                let f = Fixture::new(scene_for(light), pose, SCREEN, SHADOW_MAP);
                let scale = f32::from_bits(bits);
                let f = if scale == 1.0 {
                    f
                } else {
                    f.with_depth_scaled(scale)
                };
                let f = if cookie {
                    f.with_cookie(
                        scatter_reference::cookie::Cookie::pattern("stained_glass", 64)
                            .expect("a built-in pattern"),
                    )
                } else {
                    f
                };
                (key, f)
            })
            .collect()
    });
    let key = (light, pose, scale.to_bits(), cookie);
    &all.iter()
        .find(|(k, _)| *k == key)
        .expect("a fixture for every case")
        .1
}

fn input(f: &Fixture) -> FrameInput {
    f.frame_input(FrameSettings::for_screen(SCREEN[0], SCREEN[1]))
}

fn trial_name(v: &HybridVolumeVariant, pose: Pose, depth_scale: f32) -> String {
    let tail = if depth_scale == 1.0 {
        String::new()
    } else {
        format!("::depth_x{depth_scale}")
    };
    format!(
        "{}::{}::{pose}{tail}",
        FamilyVariant::from(*v).trial_name(),
        scene_for(v.light)
    )
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

fn trial(
    ctx: &scatter_runtime::Context,
    variant: &HybridVolumeVariant,
    f: &Fixture,
) -> Result<String, String> {
    let name = format!("{}::{}", variant.id(), f.pose);
    let spot = variant.light == LightKind::Spot;
    let gpu = run_hybrid_volume_once(
        ctx,
        variant,
        res(),
        &input(f),
        &f.gbuf.view_depth,
        &f.shadow_map.depth,
        f.cookie().as_ref().map(|(size, t)| (*size, &t[..])),
    )
    .map_err(|e| format!("{name}: GPU run failed: {e}"))?;
    let [wr, hr] = RECTIFIED;
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
    // depth_columns and slice_fit: the mirrors on the uploaded table against the GPU's.
    let mut fitted = gpu.frame.slices.clone();
    slice_fit::slice_fit(
        &gpu.frame.uniforms,
        &mut fitted,
        &depth_columns::depth_columns(&gpu.frame.uniforms, &depth),
        spot,
    );
    compare_slices(&gpu.slices, &fitted).map_err(|e| format!("{name}: {e}"))?;
    let mut frame = gpu.frame.clone();
    frame.slices = gpu.slices.clone();
    let gpu_rect = Tex {
        width: wr,
        height: hr,
        data: gpu.rectified.clone(),
    };
    let cookie_tex = scatter_reference::kernels::cookie_texture(&f.scene);
    let cpu =
        hybrid_volume_from_rectified(variant, frame, gpu_rect, &depth, &sm, cookie_tex.as_ref());
    // volume_bounds: bit for bit.
    if cpu.crossings.edges != gpu.crossings {
        let bad = cpu
            .crossings
            .edges
            .iter()
            .zip(&gpu.crossings)
            .filter(|(c, g)| c != g)
            .count();
        return Err(format!(
            "{name}: {bad} of {} crossing bins differ from the mirror (sizes {} and {})",
            cpu.crossings.edges.len(),
            cpu.crossings.edges.len(),
            gpu.crossings.len()
        ));
    }
    let binned = cpu
        .crossings
        .edges
        .iter()
        .filter(|e| e[0] != u32::MAX)
        .count();
    // volume_march.
    let max = cpu
        .march
        .output
        .data
        .iter()
        .flat_map(|c| c[..3].iter().copied())
        .fold(0.0f32, f32::max);
    if max.is_nan() || max <= 0.0 {
        return Err(format!("{name}: the mirror's image is black"));
    }
    let inputs = MarchInputs {
        frame: &cpu.frame.uniforms,
        slices: &cpu.frame.slices,
        depth: &depth,
        shadow_map: &sm,
        rectified: &cpu.rectified,
        crossings: &cpu.crossings,
        cookie: cookie_tex.as_ref(),
    };
    let mut worst: f32 = 0.0;
    let mut worst_untied: f32 = 0.0;
    let mut ties = 0;
    let mut over = 0;
    for (i, (g, c)) in gpu.output.iter().zip(&cpu.march.output.data).enumerate() {
        let pixel_over = (0..3).any(|k| {
            let d = (g[k] - c[k]).abs();
            d.is_nan() || d > REL_TOL * max + f16_ulp(c[k])
        });
        let d = (0..3).map(|k| (g[k] - c[k]).abs()).fold(0.0f32, |m, d| {
            if d.is_nan() { f32::INFINITY } else { m.max(d) }
        });
        worst = worst.max(d);
        if !pixel_over {
            worst_untied = worst_untied.max(d);
            continue;
        }
        let (x, y) = (i as u32 % SCREEN[0], i as u32 / SCREEN[0]);
        if is_tie(&inputs, variant, x, y) {
            ties += 1;
        } else {
            worst_untied = worst_untied.max(d);
            over += 1;
            eprintln!(
                "  untied pixel ({x}, {y}): gpu {g:?} cpu {c:?} span {:?}",
                cpu.spans.get(i)
            );
        }
    }
    let pixels = (SCREEN[0] * SCREEN[1]) as usize;
    if over > 0 || ties * 100 > pixels {
        return Err(format!(
            "{name}: {over} pixels over tolerance that are not ties, {ties} ties (at most 1 % \
             allowed), worst |diff| {worst:e} ({:.2e} of max {max:e})",
            worst / max
        ));
    }
    Ok(format!(
        "{name}: output max |diff| {worst_untied:.2e} ({:.2e} of max {max:.3e}) over pixels \
         without ties; {ties} tie pixels (worst {worst:.2e}); crossings exact ({binned} bins \
         hold an edge)",
        worst_untied / max
    ))
}

/// Whether the mirror's interval of pixel `(x, y)` is within f32 noise of a different one
/// (module docs): GPU and CPU compute `atan2`, `sin` and the rectified depths to a few ulps.
fn is_tie(inp: &MarchInputs, variant: &HybridVolumeVariant, x: u32, y: u32) -> bool {
    let spot = variant.light == LightKind::Spot;
    let f = inp.frame;
    let eye = xyz(f.eye);
    let dir = pixel_dir(f, x, y);
    let s = surface_distance(f, inp.depth, x, y, dir);
    let radius = f.epipole[3];
    let px = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let rim = [f.epipole, f.anti_epipole]
        .iter()
        .any(|e| e[2] > 0.5 && ((px - glam::Vec2::new(e[0], e[1])).length() - radius).abs() < 1e-3);
    let theta = ray_theta(f, dir);
    let yc = ray_row_coord(f, dir);
    let d = normalised_depth(theta, f.theta[0], f.theta[1]);
    let bins = inp.crossings.bins as f32;
    let bin_tie = ((d * bins) - (d * bins).round()).abs() < 1e-3;
    let row_tie = ((yc - 0.5) - (yc - 0.5).round()).abs() < 1e-3;
    let col = ray_column(f, eye, dir, s, theta, spot);
    let j = (yc - 0.5).floor();
    let rows = f.sizes[3];
    let wrap = f.anti_epipole[3] > 0.5;
    let texel_tie = [j, j + 1.0].iter().any(|&jj| {
        let row = row_index(jj, rows, wrap);
        let xs = col / inp.slices[row as usize].delta;
        let n = (xs.max(0.0).ceil() as u32 + 1).min(f.sizes[2]);
        (xs - xs.round()).abs() < 1e-3
            || (0..n).any(|c| (d - inp.rectified.load(c, row)).abs() < 1e-4)
    });
    // The march: a sample within ulps of a shadow-map texel border or of its stored depth.
    // Near the epipole the view ray runs almost along the light rays, so one shift of the
    // interval moves several samples across the same border at once: perturb both ends by
    // 1e-5 of their distance and see whether the sum moves by more than 1e-3 of itself.
    let march_tie = pixel_span(inp, variant.pad, x, y, spot).is_some_and(|p| {
        let sum = |p: &PixelSpan| span_sum(f, inp.shadow_map, dir, p, variant.samples, spot);
        let base = sum(&p);
        [1.0 - 1e-5, 1.0 + 1e-5].iter().any(|&e| {
            let q = PixelSpan {
                t_f: p.t_f * e,
                t_b: (p.t_b * e).min(p.s),
                ..p
            };
            (sum(&q) - base).abs() > 1e-3 * base.abs()
        })
    });
    rim || bin_tie || row_tie || texel_tie || march_tie
}

fn main() -> ExitCode {
    let mut trials: Vec<(String, Check)> = cases()
        .into_iter()
        .map(|(v, pose, scale)| {
            let check: Check = Box::new(move || {
                let Some(ctx) = gpu() else { return Ok(()) };
                trial(ctx, &v, fixture(v.light, pose, scale, v.cookie))
                    .map(|m| eprintln!("     {m}"))
            });
            (trial_name(&v, pose, scale), check)
        })
        .collect();
    trials.push((
        "hybrid_volume::errors".to_owned(),
        Box::new(|| {
            bad_input_is_an_error();
            Ok(())
        }),
    ));
    run_trials(trials, &[])
}

fn bad_input_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let v = HybridVolumeVariant::default();
    let err = HybridVolume::new(
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
    eprintln!("ok   hybrid_volume::errors::zero_size: {err}");
    let err = HybridVolume::new(
        ctx,
        &HybridVolumeVariant {
            bins: 0,
            ..HybridVolumeVariant::default()
        },
        res(),
        SHADOW_MAP,
    )
    .expect_err("zero bins");
    assert!(err.to_string().contains("bins"), "{err}");
    eprintln!("ok   hybrid_volume::errors::zero_bins: {err}");
    let f = fixture(LightKind::Directional, Pose::Ordinary, 1.0, false);
    let mut pass =
        HybridVolume::new(ctx, &v, res(), SHADOW_MAP / 2).unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input(f)).expect_err("shadow map size");
    assert!(matches!(err, RuntimeError::ShadowMapSize { .. }), "{err}");
    eprintln!("ok   hybrid_volume::errors::shadow_map_size: {err}");
    let mut pass = HybridVolume::new(
        ctx,
        &HybridVolumeVariant {
            light: LightKind::Spot,
            ..HybridVolumeVariant::default()
        },
        res(),
        SHADOW_MAP,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input(f)).expect_err("light mismatch");
    assert!(err.to_string().contains("light"), "{err}");
    eprintln!("ok   hybrid_volume::errors::light_mismatch: {err}");
    let mut input = input(f);
    input.camera.forward.y = f64::NAN;
    let mut pass = HybridVolume::new(ctx, &v, res(), SHADOW_MAP).unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input).expect_err("NaN camera");
    assert!(err.to_string().contains("camera"), "{err}");
    eprintln!("ok   hybrid_volume::errors::nan_camera: {err}");
}
