//! Conformance of the `prefiltered` family (`rectify`, `prefilter`, `scatter`): the GPU
//! (`scatter_runtime::run_once`) against the CPU mirrors
//! (`reference/src/kernels/{rectify,prefilter,scatter}.rs`, driven by
//! `scatter_reference::kernels::run_prefiltered`) for every variant of the design card:
//! bases {4, 8, 16, 32, 64, 128} x every valid bases_per_thread x regions {1, 2, 3, 4} x
//! visibility x light x storage x rectification. Directional variants run on
//! `columns/ordinary`, spot variants on `spot_grate/ordinary`, 64x36 pixels, a 128^2 shadow
//! map and a 64x64 rectified map. Trials are named
//! `prefiltered::<variant id>::<scene>::<pose>`. Both poses are projective frames for the
//! projective variants (asserted): their rectified map is the reference's ray-cast stand-in
//! for the engine's rasteriser, uploaded to the GPU, and `rectify` does not run. The
//! fallback to epipolar is tested on `columns/epipole_on_screen`.
//!
//! Tolerances:
//! - rectified map: `|gpu - cpu| <= 1e-4` (a normalised view angle: acos/atan2 differ by a
//!   few ulp between the driver and Rust's libm);
//! - filtered bases (stored as `F / 2 + 0.5`): `1/255 + 1e-6` for rgba8unorm (a value near a
//!   rounding boundary may quantise to the neighbouring step), `1e-3` for the float formats
//!   (f16 keeps 11 bits: half an ulp near 1 is 2.4e-4);
//! - output (in-scattered radiance, rgba16float): `|gpu - cpu| <= 2/255 * max radiance` for
//!   rgba8unorm bases, `1e-3 * max radiance` for float bases, plus one f16 ulp of the
//!   mirror's value: both sides round to rgba16float, so values that differ by less than
//!   the bound before rounding may land one f16 step further apart (near the maximum one
//!   step is up to 2^-10 ~ 1e-3 of it). The summary lines print the raw ratio
//!   `max |diff| / max radiance` without that allowance.
//!
//! `SCATTER_TRIALS=<substring>` runs only the trials whose name contains it.

use std::sync::OnceLock;
use std::time::Instant;

use scatter_conformance::gpu;
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::kernels::{PrefilteredRun, run_prefiltered};
use scatter_reference::scene::Scene;
use scatter_reference::suite::{MediumPreset, Pose, SceneName, scene};
use scatter_runtime::wgpu::TextureView;
use scatter_runtime::{Context, CpuInputs, FrameInput, Inputs, RuntimeError, Scatter, run_once};
use scatter_shaderlib::prefiltered::{
    FrameSettings, LightKind, Rectification, Resolutions, Storage, Variant,
};

const SCREEN: [u32; 2] = [64, 36];
const RECTIFIED: [u32; 2] = [64, 64];
const SHADOW_MAP: u32 = 128;

const RECTIFIED_TOL: f32 = 1e-4;

/// A suite scene with its depth buffer and shadow map, built once.
struct Fixture {
    name: SceneName,
    pose: Pose,
    scene: Scene,
    bvh: Bvh,
    gbuf: GBuffer,
    shadow_map: ShadowMap,
}

impl Fixture {
    /// Directional variants run on `columns/ordinary`; spot variants on
    /// `spot_grate/ordinary`, except projective ones on `spot_grate/grazing` (the ordinary
    /// pose's slices fan out too wide for a projective map: it falls back to epipolar).
    fn get(light: LightKind, rectification: Rectification) -> &'static Fixture {
        static COLUMNS: OnceLock<Fixture> = OnceLock::new();
        static SPOT_GRATE: OnceLock<Fixture> = OnceLock::new();
        static SPOT_GRATE_GRAZING: OnceLock<Fixture> = OnceLock::new();
        let (cell, name, pose) = match (light, rectification) {
            (LightKind::Directional, _) => (&COLUMNS, SceneName::Columns, Pose::Ordinary),
            (LightKind::Spot, Rectification::Epipolar) => {
                (&SPOT_GRATE, SceneName::SpotGrate, Pose::Ordinary)
            }
            (LightKind::Spot, Rectification::Projective) => {
                (&SPOT_GRATE_GRAZING, SceneName::SpotGrate, Pose::Grazing)
            }
        };
        cell.get_or_init(|| {
            let scene = scene(name, pose, MediumPreset::Default, SCREEN[0], SCREEN[1]);
            let bvh = Bvh::build(&scene.geometry);
            let gbuf = GBuffer::cast(&scene, &bvh);
            let shadow_map = ShadowMap::build(&scene, &bvh, SHADOW_MAP)
                .unwrap_or_else(|e| panic!("shadow map of {name}: {e}"));
            Fixture {
                name,
                pose,
                scene,
                bvh,
                gbuf,
                shadow_map,
            }
        })
    }

    fn for_light(light: LightKind) -> &'static Fixture {
        Fixture::get(light, Rectification::Epipolar)
    }

    fn frame_input(&self) -> FrameInput {
        FrameInput {
            camera: self.scene.camera_desc(),
            light: self.scene.light_desc(),
            medium: self.scene.medium_desc(),
            shadow_map: self.shadow_map.desc(),
            settings: FrameSettings::default(),
        }
    }

    fn cpu_inputs(&self) -> CpuInputs {
        CpuInputs {
            frame: self.frame_input(),
            depth: self.gbuf.view_depth.clone(),
            shadow_map: self.shadow_map.depth.clone(),
            rectified: None,
            pass_wall_frames: 0,
        }
    }

    fn resolutions(&self) -> Resolutions {
        Resolutions {
            screen: [self.gbuf.width, self.gbuf.height],
            rectified: RECTIFIED,
        }
    }
}

/// Every variant of the design card for one light type, regions 1..=4 as the issue's
/// conformance grid asks.
fn variants(light: LightKind) -> Vec<Variant> {
    Variant::grid(1..=4)
        .into_iter()
        .filter(|v| v.light == light)
        .collect()
}

/// Largest deviations of one trial (and where the worst one was).
#[derive(Default, Clone, Copy)]
struct Worst {
    /// Values over the tolerance.
    over: usize,
    diff: f32,
    tol: f32,
    at: usize,
    gpu: f32,
    cpu: f32,
}

impl Worst {
    fn update(&mut self, at: usize, gpu: f32, cpu: f32, tol: f32) {
        let diff = (gpu - cpu).abs();
        // NaN compares false: count it as infinitely bad.
        let diff = if diff.is_nan() { f32::INFINITY } else { diff };
        if diff > tol {
            self.over += 1;
        }
        if diff / tol > self.diff / self.tol.max(f32::MIN_POSITIVE) || self.tol == 0.0 {
            *self = Worst {
                over: self.over,
                diff,
                tol,
                at,
                gpu,
                cpu,
            };
        }
    }

    fn ok(&self) -> bool {
        self.diff <= self.tol
    }
}

/// Per-trial result: the deviations of the three outputs.
struct TrialResult {
    rectified: Worst,
    filtered: Worst,
    output: Worst,
    max_radiance: f32,
    line: String,
}

fn filtered_tol(storage: Storage) -> f32 {
    match storage {
        Storage::Rgba8unorm => 1.0 / 255.0 + 1e-6,
        Storage::Rgba16float | Storage::Rgba32float => 1e-3,
    }
}

fn output_rel_tol(storage: Storage) -> f32 {
    match storage {
        Storage::Rgba8unorm => 2.0 / 255.0,
        Storage::Rgba16float | Storage::Rgba32float => 1e-3,
    }
}

/// Spacing of f16 values at `v` (2^-24 for subnormals).
fn f16_ulp(v: f32) -> f32 {
    let a = v.abs();
    if !a.is_finite() || a < 2f32.powi(-14) {
        return 2f32.powi(-24);
    }
    2f32.powi(a.log2().floor() as i32 - 10)
}

fn trial_name(variant: &Variant, fixture: &Fixture) -> String {
    format!(
        "prefiltered::{}::{}::{}",
        variant.id(),
        fixture.name,
        fixture.pose
    )
}

fn run_trial(ctx: &Context, variant: &Variant, fixture: &Fixture) -> Result<TrialResult, String> {
    let trial = trial_name(variant, fixture);
    let start = Instant::now();
    let cpu: PrefilteredRun = run_prefiltered(
        variant,
        RECTIFIED,
        &fixture.scene,
        &fixture.bvh,
        &fixture.gbuf,
        &fixture.shadow_map,
        &FrameSettings::default(),
    )
    .map_err(|e| format!("{trial}: CPU mirror failed: {e}"))?;
    if cpu.frame.report.rectification != variant.rectification {
        return Err(format!(
            "{trial}: expected a {} frame, got {} ({:?})",
            variant.rectification, cpu.frame.report.rectification, cpu.frame.report.fallback
        ));
    }
    let mut inputs = fixture.cpu_inputs();
    if cpu.frame.report.projective.is_some() {
        inputs.rectified = Some(cpu.rectified.data.clone());
    }
    let gpu_start = Instant::now();
    let gpu = run_once(ctx, variant, fixture.resolutions(), &inputs)
        .map_err(|e| format!("{trial}: GPU run failed: {e}"))?;
    let gpu_wall = gpu_start.elapsed();
    if gpu.frame != cpu.frame {
        return Err(format!(
            "{trial}: the runtime uploaded a different frame set-up than the mirror used"
        ));
    }
    let lengths = [
        ("rectified", gpu.rectified.len(), cpu.rectified.data.len()),
        ("filtered", gpu.filtered.len(), cpu.filtered.data.len()),
        ("output", gpu.output.len(), cpu.output.data.len()),
    ];
    for (what, g, c) in lengths {
        if g != c {
            return Err(format!(
                "{trial}: {what} has {g} texels on the GPU, {c} on the CPU"
            ));
        }
    }

    let mut rectified = Worst::default();
    for (i, (&g, &c)) in gpu.rectified.iter().zip(&cpu.rectified.data).enumerate() {
        rectified.update(i, g, c, RECTIFIED_TOL);
    }
    let mut filtered = Worst::default();
    let ftol = filtered_tol(variant.storage);
    for (i, (g, c)) in gpu.filtered.iter().zip(&cpu.filtered.data).enumerate() {
        for k in 0..4 {
            filtered.update(4 * i + k, g[k], c[k], ftol);
        }
    }
    let max_radiance = cpu
        .output
        .data
        .iter()
        .flatten()
        .fold(0.0f32, |m, &v| m.max(v));
    let otol = output_rel_tol(variant.storage) * max_radiance;
    let mut output = Worst::default();
    for (i, (g, c)) in gpu.output.iter().zip(&cpu.output.data).enumerate() {
        for k in 0..3 {
            output.update(3 * i + k, g[k], c[k], otol + f16_ulp(c[k]));
        }
    }
    let times = gpu.gpu_times.map_or_else(
        || "gpu n/a".to_owned(),
        |t| {
            format!(
                "gpu rectify {:.2} ms prefilter {:.2} ms scatter {:.2} ms",
                t.rectify.as_secs_f64() * 1e3,
                t.prefilter.as_secs_f64() * 1e3,
                t.scatter.as_secs_f64() * 1e3
            )
        },
    );
    let line = format!(
        "{trial}: rectified max |diff| {:.2e}; filtered {:.2e}; output {:.2e} ({:.2e} of max {:.3e}); {times}; run_once {:.0} ms, total {:.0} ms",
        rectified.diff,
        filtered.diff,
        output.diff,
        output.diff / max_radiance.max(f32::MIN_POSITIVE),
        max_radiance,
        gpu_wall.as_secs_f64() * 1e3,
        start.elapsed().as_secs_f64() * 1e3,
    );
    Ok(TrialResult {
        rectified,
        filtered,
        output,
        max_radiance,
        line,
    })
}

/// Describes a failed comparison: where, values, tolerance.
fn describe(what: &str, w: &Worst, layout: impl Fn(usize) -> String) -> String {
    format!(
        "{what}: {} values over tolerance, worst at {}: gpu {:e} cpu {:e} |diff| {:e} > tol {:e}",
        w.over,
        layout(w.at),
        w.gpu,
        w.cpu,
        w.diff,
        w.tol
    )
}

fn conformance(light: LightKind, rectification: Rectification) {
    let Some(ctx) = gpu() else { return };
    let fixture = Fixture::get(light, rectification);
    let filter = std::env::var("SCATTER_TRIALS").unwrap_or_default();
    let all: Vec<Variant> = variants(light)
        .into_iter()
        .filter(|v| v.rectification == rectification)
        .collect();
    let chosen: Vec<_> = all
        .iter()
        .filter(|v| trial_name(v, fixture).contains(filter.as_str()))
        .collect();
    let start = Instant::now();
    let mut failures = Vec::new();
    // Largest output deviation relative to the max radiance, and largest filtered
    // deviation, per storage format.
    let mut worst_by_storage: Vec<(Storage, f32, f32, f32)> =
        Storage::ALL.iter().map(|&s| (s, 0.0, 0.0, 0.0)).collect();
    let [wr, hr] = RECTIFIED;
    let [w, _] = SCREEN;
    for variant in &chosen {
        match run_trial(ctx, variant, fixture) {
            Err(e) => {
                eprintln!("FAIL {e}");
                failures.push(e);
            }
            Ok(r) => {
                if let Some(entry) = worst_by_storage.iter_mut().find(|e| e.0 == variant.storage) {
                    entry.1 = entry.1.max(r.rectified.diff);
                    entry.2 = entry.2.max(r.filtered.diff);
                    entry.3 = entry
                        .3
                        .max(r.output.diff / r.max_radiance.max(f32::MIN_POSITIVE));
                }
                let mut problems = Vec::new();
                if !r.rectified.ok() {
                    problems.push(describe("rectify", &r.rectified, |i| {
                        format!("(x {}, row {})", i as u32 % wr, i as u32 / wr)
                    }));
                }
                if !r.filtered.ok() {
                    problems.push(describe("prefilter", &r.filtered, |i| {
                        let texel = (i / 4) as u32;
                        format!(
                            "(x {}, row {}, layer {}) channel {}",
                            texel % wr,
                            (texel / wr) % hr,
                            texel / (wr * hr),
                            i % 4
                        )
                    }));
                }
                if !r.output.ok() {
                    problems.push(describe("scatter", &r.output, |i| {
                        let pixel = (i / 3) as u32;
                        format!("pixel ({}, {}) channel {}", pixel % w, pixel / w, i % 3)
                    }));
                }
                if problems.is_empty() {
                    eprintln!("ok   {}", r.line);
                } else {
                    let msg = format!("{}\n    {}", r.line, problems.join("\n    "));
                    eprintln!("FAIL {msg}");
                    failures.push(msg);
                }
            }
        }
    }
    let total = start.elapsed();
    eprintln!(
        "prefiltered::*-{light}-*-{rectification}: {} trials in {:.1} s ({:.0} ms per trial), {} failed",
        chosen.len(),
        total.as_secs_f64(),
        total.as_secs_f64() * 1e3 / chosen.len().max(1) as f64,
        failures.len()
    );
    for (storage, rect, filt, out) in &worst_by_storage {
        eprintln!(
            "prefiltered::*-{light}-{storage}-{rectification}: max rectified |diff| {rect:.3e}, max filtered |diff| {filt:.3e}, max output |diff| / max radiance {out:.3e}"
        );
    }
    assert!(
        failures.is_empty(),
        "{} of {} trial(s) failed:\n{}",
        failures.len(),
        chosen.len(),
        failures.join("\n")
    );
}

#[test]
fn directional_epipolar_variants_match_mirror() {
    conformance(LightKind::Directional, Rectification::Epipolar);
}

#[test]
fn spot_epipolar_variants_match_mirror() {
    conformance(LightKind::Spot, Rectification::Epipolar);
}

#[test]
fn directional_projective_variants_match_mirror() {
    conformance(LightKind::Directional, Rectification::Projective);
}

#[test]
fn spot_projective_variants_match_mirror() {
    conformance(LightKind::Spot, Rectification::Projective);
}

/// The variant the error tests start from.
fn base_variant() -> Variant {
    Variant::default()
}

fn columns_res() -> Resolutions {
    Resolutions {
        screen: SCREEN,
        rectified: RECTIFIED,
    }
}

#[test]
fn wrong_shadow_map_size_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let fixture = Fixture::for_light(LightKind::Directional);
    let mut pass = Scatter::new(ctx, &base_variant(), columns_res(), 2 * SHADOW_MAP)
        .unwrap_or_else(|e| panic!("{e}"));
    let err = pass
        .prepare(ctx, &fixture.frame_input())
        .expect_err("a 128 shadow map on a pass made for 256");
    let text = err.to_string();
    assert!(
        matches!(
            err,
            RuntimeError::ShadowMapSize {
                expected: 256,
                actual: 128
            }
        ) && text.contains("shadow map"),
        "{text}"
    );
    eprintln!("ok   prefiltered::errors::shadow_map_size: {text}");

    // A shadow-map view of the wrong size at encode time.
    let mut pass = Scatter::new(ctx, &base_variant(), columns_res(), SHADOW_MAP)
        .unwrap_or_else(|e| panic!("{e}"));
    pass.prepare(ctx, &fixture.frame_input())
        .unwrap_or_else(|e| panic!("{e}"));
    let texture = |size: [u32; 2], format| {
        ctx.device()
            .create_texture(&scatter_runtime::wgpu::TextureDescriptor {
                label: None,
                size: scatter_runtime::wgpu::Extent3d {
                    width: size[0],
                    height: size[1],
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: scatter_runtime::wgpu::TextureDimension::D2,
                format,
                usage: scatter_runtime::wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
            .create_view(&Default::default())
    };
    let r32 = scatter_runtime::wgpu::TextureFormat::R32Float;
    let depth = texture(SCREEN, r32);
    let mut encoder = ctx.device().create_command_encoder(&Default::default());
    let small = texture([SHADOW_MAP / 2; 2], r32);
    let err = pass
        .encode(&mut encoder, &inputs(&depth, &small))
        .expect_err("a 64^2 shadow-map view");
    assert!(err.to_string().contains("shadow map size"), "{err}");
    eprintln!("ok   prefiltered::errors::shadow_map_view_size: {err}");
    let rgba = texture(
        [SHADOW_MAP; 2],
        scatter_runtime::wgpu::TextureFormat::Rgba8Unorm,
    );
    let err = pass
        .encode(&mut encoder, &inputs(&depth, &rgba))
        .expect_err("an rgba8 shadow-map view");
    assert!(err.to_string().contains("shadow map format"), "{err}");
    eprintln!("ok   prefiltered::errors::shadow_map_view_format: {err}");
    let small_depth = texture([SCREEN[0], SCREEN[1] - 1], r32);
    let sm = texture([SHADOW_MAP; 2], r32);
    let err = pass
        .encode(&mut encoder, &inputs(&small_depth, &sm))
        .expect_err("a short depth buffer");
    assert!(err.to_string().contains("depth buffer size"), "{err}");
    eprintln!("ok   prefiltered::errors::depth_view_size: {err}");
    // The right views encode, and the encoder still finishes cleanly.
    let err = pass
        .encode(
            &mut encoder,
            &Inputs {
                depth: &depth,
                shadow_map: None,
                rectified: None,
            },
        )
        .expect_err("an epipolar frame without a shadow map");
    assert!(matches!(err, RuntimeError::MissingInput { .. }), "{err}");
    eprintln!("ok   prefiltered::errors::missing_shadow_map: {err}");
    pass.encode(&mut encoder, &inputs(&depth, &sm))
        .unwrap_or_else(|e| panic!("{e}"));
    ctx.queue().submit([encoder.finish()]);
}

#[test]
fn zero_resolution_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let cases = [
        ([0, 36], RECTIFIED, SHADOW_MAP, "screen 0x36"),
        ([64, 0], RECTIFIED, SHADOW_MAP, "screen 64x0"),
        (SCREEN, [0, 64], SHADOW_MAP, "rectified 0x64"),
        (SCREEN, [64, 0], SHADOW_MAP, "rectified 64x0"),
        (SCREEN, RECTIFIED, 0, "shadow map 0x0"),
    ];
    for (screen, rectified, sm, expected) in cases {
        let res = Resolutions { screen, rectified };
        let err = Scatter::new(ctx, &base_variant(), res, sm).expect_err(expected);
        let text = err.to_string();
        assert!(
            matches!(err, RuntimeError::EmptyInput { .. }) && text.contains(expected),
            "{expected}: {text}"
        );
        eprintln!("ok   prefiltered::errors::zero_size::{expected}: {text}");
    }
    // Too large for the device: names the limit.
    let max_2d = ctx.device().limits().max_texture_dimension_2d;
    let res = Resolutions {
        screen: [max_2d + 1, 4],
        rectified: RECTIFIED,
    };
    let err = Scatter::new(ctx, &base_variant(), res, SHADOW_MAP).expect_err("too wide");
    assert!(
        err.to_string().contains("max_texture_dimension_2d"),
        "{err}"
    );
    eprintln!("ok   prefiltered::errors::too_wide: {err}");
    // Fewer columns than regions^2 (the first of the sun's quadratic regions would be empty).
    let res = Resolutions {
        screen: SCREEN,
        rectified: [8, 64],
    };
    let err =
        Scatter::new(ctx, &base_variant(), res, SHADOW_MAP).expect_err("8 columns, 3 regions");
    assert!(
        matches!(
            err,
            RuntimeError::TooFewColumns {
                regions: 3,
                width: 8,
                min: 9,
                ..
            }
        ),
        "{err}"
    );
    eprintln!("ok   prefiltered::errors::too_few_columns: {err}");
}

#[test]
fn invalid_variant_names_the_knob() {
    let Some(ctx) = gpu() else { return };
    let cases = [
        (
            Variant {
                regions: 9,
                ..base_variant()
            },
            "regions",
            "9",
        ),
        (
            Variant {
                bases: 6,
                ..base_variant()
            },
            "bases",
            "6",
        ),
        (
            Variant {
                bases_per_thread: 12,
                ..base_variant()
            },
            "bases_per_thread",
            "12",
        ),
    ];
    for (variant, knob, value) in cases {
        let err = Scatter::new(ctx, &variant, columns_res(), SHADOW_MAP).expect_err(knob);
        let text = err.to_string();
        assert!(
            matches!(&err, RuntimeError::InvalidVariant { source, .. } if source.knob == knob)
                && text.contains(knob)
                && text.contains(value),
            "{knob}: {text}"
        );
        eprintln!("ok   prefiltered::errors::variant::{knob}: {text}");
    }
}

#[test]
fn bad_frames_are_errors_not_panics() {
    let Some(ctx) = gpu() else { return };
    let fixture = Fixture::for_light(LightKind::Directional);
    let mut pass = Scatter::new(ctx, &base_variant(), columns_res(), SHADOW_MAP)
        .unwrap_or_else(|e| panic!("{e}"));

    // Encoding before any frame was prepared.
    let mut encoder = ctx.device().create_command_encoder(&Default::default());
    let err = pass
        .encode(
            &mut encoder,
            &inputs(pass.rectified_view(), pass.rectified_view()),
        )
        .expect_err("encode before prepare");
    assert!(matches!(err, RuntimeError::NotPrepared { .. }), "{err}");
    eprintln!("ok   prefiltered::errors::not_prepared: {err}");

    let mut nan = fixture.frame_input();
    nan.camera.position.x = f64::NAN;
    let err = pass.prepare(ctx, &nan).expect_err("NaN camera");
    assert!(
        matches!(err, RuntimeError::Frame(_)) && err.to_string().contains("camera"),
        "{err}"
    );
    eprintln!("ok   prefiltered::errors::nan_camera: {err}");

    let spot = Fixture::for_light(LightKind::Spot).frame_input();
    let mut wrong_light = fixture.frame_input();
    wrong_light.light = spot.light;
    let err = pass
        .prepare(ctx, &wrong_light)
        .expect_err("spot light, directional variant");
    assert!(err.to_string().contains("spot"), "{err}");
    eprintln!("ok   prefiltered::errors::light_mismatch: {err}");

    // A short depth buffer in the test helper.
    let mut inputs = fixture.cpu_inputs();
    inputs.depth.pop();
    let err = run_once(ctx, &base_variant(), columns_res(), &inputs).expect_err("short depth");
    assert!(
        matches!(err, RuntimeError::DataLength { .. }) && err.to_string().contains("depth"),
        "{err}"
    );
    eprintln!("ok   prefiltered::errors::short_depth: {err}");

    // After the errors, a good frame still works.
    pass.prepare(ctx, &fixture.frame_input())
        .unwrap_or_else(|e| panic!("{e}"));
}

/// An epipolar frame's inputs: depth and standard shadow map.
fn inputs<'a>(depth: &'a TextureView, shadow_map: &'a TextureView) -> Inputs<'a> {
    Inputs {
        depth,
        shadow_map: Some(shadow_map),
        rectified: None,
    }
}
