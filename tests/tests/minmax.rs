//! Conformance of the `minmax` family (`depth_columns`, `slice_fit`, `rectify`, `minmax_build`,
//! `minmax_traverse`): the GPU
//! (`scatter_runtime::run_minmax_once`) against the CPU mirrors
//! (`reference/src/kernels/{rectify,minmax_build,minmax_traverse}.rs`) for both variants of
//! `MinmaxVariant::grid()`, directional on `columns`, spot on `spot_grate`, at the
//! `ordinary` and `epipole_on_screen` poses (the latter marches pixels near the epipole), at
//! 67x37 pixels with a 100x60 rectified map (neither a power of two nor a multiple of the
//! workgroups) and a 128^2 shadow map; and two rows wide enough for `minmax_build`'s
//! register groups (700x12: levels 0..3 from each group of 8 texels; 1100x8: level 4 from
//! the map above them; trials `...::map_WxH`). Trials are named
//! `minmax::<variant id>::<scene>::<pose>` (libtest trials: `cargo test -p scatter-conformance
//! -- minmax::` runs this family, `-- --list` lists them); `minmax::errors` checks the error
//! paths.
//!
//! The mirror's `minmax_build` and `minmax_traverse` run on the GPU's rectified map, so that
//! each kernel is compared on the same input. Tolerances: the trees bit for bit (min and max
//! of the same floats); the output `|gpu - cpu| <= 1e-4 * max radiance` plus one f16 step of
//! the mirror's value, except at *ties* (at most 1 % of the pixels): pixels whose ray depth
//! lies within 1e-4 of a stored depth of their row, or whose row coordinate lies within 1e-3
//! of a row boundary, where a few ulps of `acos`/`atan2` legitimately flip one texel or the
//! slice. `rectify` (GPU against its mirror) is reported.

use std::process::ExitCode;
use std::sync::OnceLock;

use scatter_conformance::{Check, Fixture, compare_slices, gpu, run_trials, scene_for};
use scatter_reference::cookie::Cookie;
use scatter_reference::kernels::minmax_traverse::{Pixel, TraverseInputs, pixel_ray};
use scatter_reference::kernels::texture::Tex;
use scatter_reference::kernels::{depth_columns, minmax_from_rectified, rectify, slice_fit};
use scatter_reference::suite::Pose;
use scatter_runtime::{FrameInput, Minmax, RuntimeError, run_minmax_once};
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::prefiltered::{FrameSettings, LightKind, Resolutions};

const SCREEN: [u32; 2] = [67, 37];
const RECTIFIED: [u32; 2] = [100, 60];
const SHADOW_MAP: u32 = 128;
const REL_TOL: f32 = 1e-4;

/// The (light, pose, depth scale, cookie) of every trial: both lights (the grid), at the
/// `ordinary` and `epipole_on_screen` poses, at the `ordinary` pose with the depth buffer at
/// 0.3x, where `slice_fit` narrows the rows (every suite pose here sees the sky, where it
/// does not), and the spot with the `stained_glass` cookie (64^2) at both poses (lit spans
/// and the epipole march).
/// And the rectified map of each (`RECTIFIED`, or a row wider than 4 x 128 texels, where
/// `minmax_build` reduces groups of 8 texels in registers).
const CASES: [(LightKind, Pose, f32, bool, [u32; 2]); 10] = [
    (
        LightKind::Directional,
        Pose::Ordinary,
        1.0,
        false,
        RECTIFIED,
    ),
    (
        LightKind::Directional,
        Pose::EpipoleOnScreen,
        1.0,
        false,
        RECTIFIED,
    ),
    (LightKind::Spot, Pose::Ordinary, 1.0, false, RECTIFIED),
    (
        LightKind::Spot,
        Pose::EpipoleOnScreen,
        1.0,
        false,
        RECTIFIED,
    ),
    (
        LightKind::Directional,
        Pose::Ordinary,
        0.3,
        false,
        RECTIFIED,
    ),
    (LightKind::Spot, Pose::Ordinary, 0.3, false, RECTIFIED),
    (LightKind::Spot, Pose::Ordinary, 1.0, true, RECTIFIED),
    (LightKind::Spot, Pose::EpipoleOnScreen, 1.0, true, RECTIFIED),
    (
        LightKind::Directional,
        Pose::Ordinary,
        1.0,
        false,
        [700, 12],
    ),
    (
        LightKind::Spot,
        Pose::EpipoleOnScreen,
        1.0,
        false,
        [1100, 8],
    ),
];

/// The fixture of case `i` of [`CASES`] (all built once, on first use).
fn fixture(i: usize) -> &'static Fixture {
    static ALL: OnceLock<Vec<Fixture>> = OnceLock::new();
    &ALL.get_or_init(|| {
        CASES
            .iter()
            .map(|&(light, pose, scale, cookie, _)| {
                let f = Fixture::new(scene_for(light), pose, SCREEN, SHADOW_MAP);
                let f = if scale == 1.0 {
                    f
                } else {
                    f.with_depth_scaled(scale)
                };
                if cookie {
                    f.with_cookie(Cookie::pattern("stained_glass", 64).expect("a built-in pattern"))
                } else {
                    f
                }
            })
            .collect()
    })[i]
}

/// The variant a fixture is run with: its light, and the cookie where it has one.
fn variant_of(f: &Fixture) -> MinmaxVariant {
    MinmaxVariant {
        light: light_of(f),
        cookie: f.cookie().is_some(),
        ..MinmaxVariant::default()
    }
}

fn light_of(f: &Fixture) -> LightKind {
    if f.name == scene_for(LightKind::Spot) {
        LightKind::Spot
    } else {
        LightKind::Directional
    }
}

fn input(f: &Fixture) -> FrameInput {
    f.frame_input(FrameSettings::for_screen(SCREEN[0], SCREEN[1]))
}

fn trial_name(
    light: LightKind,
    pose: Pose,
    depth_scale: f32,
    cookie: bool,
    rectified: [u32; 2],
) -> String {
    let mut tail = if depth_scale == 1.0 {
        String::new()
    } else {
        format!("::depth_x{depth_scale}")
    };
    if rectified != RECTIFIED {
        tail += &format!("::map_{}x{}", rectified[0], rectified[1]);
    }
    format!(
        "{}::{}::{pose}{tail}",
        FamilyVariant::from(MinmaxVariant {
            light,
            cookie,
            ..MinmaxVariant::default()
        })
        .trial_name(),
        scene_for(light)
    )
}

fn res() -> Resolutions {
    res_with(RECTIFIED)
}

fn res_with(rectified: [u32; 2]) -> Resolutions {
    Resolutions {
        screen: SCREEN,
        rectified,
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
    f: &Fixture,
    rectified: [u32; 2],
) -> Result<String, String> {
    let variant = variant_of(f);
    let name = format!("{}::{}", variant.id(), f.pose);
    let cookie = f.cookie();
    let gpu = run_minmax_once(
        ctx,
        &variant,
        res_with(rectified),
        &input(f),
        &f.gbuf.view_depth,
        &f.shadow_map.depth,
        cookie.as_ref().map(|(size, t)| (*size, &t[..])),
    )
    .map_err(|e| format!("{name}: GPU run failed: {e}"))?;
    let [wr, hr] = rectified;
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
        variant.light == LightKind::Spot,
    );
    compare_slices(&gpu.slices, &fitted).map_err(|e| format!("{name}: {e}"))?;
    let mut frame = gpu.frame.clone();
    frame.slices = gpu.slices.clone();
    // rectify: reported only (its own conformance lives with the prefiltered family).
    let cpu_rect = rectify::rectify(
        &frame.uniforms,
        &frame.slices,
        &sm,
        variant.light == LightKind::Spot,
    );
    let rect_diff = cpu_rect
        .data
        .iter()
        .zip(&gpu.rectified)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    let rect_flips = cpu_rect
        .data
        .iter()
        .zip(&gpu.rectified)
        .filter(|(a, b)| (*a - *b).abs() > 1e-4)
        .count();
    let gpu_rect = Tex {
        width: wr,
        height: hr,
        data: gpu.rectified.clone(),
    };
    let cookie_tex = scatter_reference::kernels::cookie_texture(&f.scene);
    let cpu = minmax_from_rectified(&variant, frame, gpu_rect, &depth, &sm, cookie_tex.as_ref());
    // minmax_build: bit for bit.
    if cpu.tree.data.len() != gpu.tree.len() {
        return Err(format!("{name}: tree sizes differ"));
    }
    let tree_bad = cpu
        .tree
        .data
        .iter()
        .zip(&gpu.tree)
        .filter(|(c, g)| c[0].to_bits() != g[0].to_bits() || c[1].to_bits() != g[1].to_bits())
        .count();
    if tree_bad > 0 {
        return Err(format!(
            "{name}: {tree_bad} tree nodes differ from the mirror"
        ));
    }
    // minmax_traverse.
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
    let mut worst: f32 = 0.0;
    let mut worst_untied: f32 = 0.0;
    let mut ties = 0;
    let mut over = 0;
    let inputs = TraverseInputs {
        frame: &cpu.frame.uniforms,
        slices: &cpu.frame.slices,
        depth: &depth,
        shadow_map: &sm,
        tree: &cpu.tree,
        cookie: cookie_tex.as_ref(),
    };
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
        if is_tie(
            &inputs,
            &cpu.rectified,
            [x, y, 0],
            variant.light == LightKind::Spot,
        ) {
            ties += 1;
        } else {
            worst_untied = worst_untied.max(d);
            over += 1;
            if let Some(Pixel::Row(r)) =
                pixel_ray([x, y, 0], variant.light == LightKind::Spot, &inputs)
            {
                let m = (0..r.n)
                    .map(|i| (r.d - cpu.rectified.load(i, r.row)).abs())
                    .fold(f32::INFINITY, f32::min);
                eprintln!(
                    "  untied pixel ({x}, {y}): gpu {g:?} cpu {c:?}; d {} n {} yc {} row {} min |d - d_i| {m:e} s {}",
                    r.d, r.n, r.yc, r.row, r.s
                );
            }
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
    let times = gpu.gpu_times.map_or_else(
        || "gpu n/a".to_owned(),
        |t| {
            format!(
                "gpu rectify {:.2} ms minmax_build {:.2} ms minmax_traverse {:.2} ms",
                t.rectify.as_secs_f64() * 1e3,
                t.build.as_secs_f64() * 1e3,
                t.march.as_secs_f64() * 1e3
            )
        },
    );
    Ok(format!(
        "{name}: output max |diff| {worst_untied:.2e} ({:.2e} of max {max:.3e}) over pixels \
         without ties; {ties} tie pixels (worst {worst:.2e}); tree exact; rectify max |diff| \
         {rect_diff:.2e} ({rect_flips} texels > 1e-4); {times}",
        worst_untied / max
    ))
}

/// Whether the mirror's classification of pixel `id` is within f32 noise of a different
/// one: its ray depth within `1e-4` of a stored depth of its row (a texel flips between lit
/// and shadowed), or its continuous row coordinate within `1e-3` rows of a row boundary (it
/// may fall into the neighbouring slice). GPU and CPU compute `acos`, `atan2` and the
/// rectified depths to a few ulps, so such pixels may legitimately differ by one texel's
/// or one row's worth.
fn is_tie(inp: &TraverseInputs, rectified: &Tex, id: [u32; 3], spot: bool) -> bool {
    match pixel_ray(id, spot, inp) {
        Some(Pixel::Row(r)) => {
            let depth_tie = (0..r.n).any(|i| (r.d - rectified.load(i, r.row)).abs() < 1e-4);
            let row_tie = (r.yc - r.yc.round()).abs() < 1e-3;
            depth_tie || row_tie
        }
        // Marched pixels: a shadow-map texel test or the epipole radius.
        _ => true,
    }
}

fn main() -> ExitCode {
    let mut trials: Vec<(String, Check)> = CASES
        .iter()
        .enumerate()
        .map(|(i, &(light, pose, scale, cookie, rectified))| {
            let check: Check = Box::new(move || {
                let Some(ctx) = gpu() else { return Ok(()) };
                trial(ctx, fixture(i), rectified).map(drop)
            });
            (trial_name(light, pose, scale, cookie, rectified), check)
        })
        .collect();
    trials.push((
        "minmax::errors".to_owned(),
        Box::new(|| {
            bad_input_is_an_error();
            Ok(())
        }),
    ));
    run_trials(trials, &[])
}

fn bad_input_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let v = MinmaxVariant::default();
    let err = Minmax::new(
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
    eprintln!("ok   minmax::errors::zero_size: {err}");
    let limit = ctx.device().limits().max_texture_dimension_2d;
    let err = Minmax::new(
        ctx,
        &v,
        Resolutions {
            screen: SCREEN,
            rectified: [limit / 2 + 1, 4],
        },
        SHADOW_MAP,
    )
    .expect_err("tree too wide");
    assert!(
        matches!(err, RuntimeError::LimitExceeded { what, .. } if what.contains("tree")),
        "{err}"
    );
    eprintln!("ok   minmax::errors::tree_width: {err}");
    let f = fixture(0);
    let mut pass = Minmax::new(ctx, &v, res(), SHADOW_MAP / 2).unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input(f)).expect_err("shadow map size");
    assert!(matches!(err, RuntimeError::ShadowMapSize { .. }), "{err}");
    eprintln!("ok   minmax::errors::shadow_map_size: {err}");
    let mut pass = Minmax::new(
        ctx,
        &MinmaxVariant {
            light: LightKind::Spot,
            ..MinmaxVariant::default()
        },
        res(),
        SHADOW_MAP,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input(f)).expect_err("light mismatch");
    assert!(err.to_string().contains("light"), "{err}");
    eprintln!("ok   minmax::errors::light_mismatch: {err}");
    let mut input = input(f);
    input.camera.forward.y = f64::NAN;
    let mut pass = Minmax::new(ctx, &v, res(), SHADOW_MAP).unwrap_or_else(|e| panic!("{e}"));
    let err = pass.prepare(ctx, &input).expect_err("NaN camera");
    assert!(err.to_string().contains("camera"), "{err}");
    eprintln!("ok   minmax::errors::nan_camera: {err}");
}
