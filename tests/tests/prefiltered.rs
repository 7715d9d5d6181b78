//! Conformance of the `prefiltered` family (`rectify`, `prefilter`, `scatter`): the GPU
//! (`scatter_runtime::run_prefiltered_once`) against the CPU mirrors
//! (`reference/src/kernels/{rectify,prefilter,scatter}.rs`, driven by
//! `scatter_reference::kernels::run_prefiltered`) for every variant of the design card:
//! bases {4, 8, 16, 32, 64, 128} x every valid bases_per_thread x regions {1, 2, 3, 4} x
//! visibility x light x storage x rectification, the moment basis (4 or 6 moments,
//! rgba32float) x regions x visibility x light x rectification, and coarse filtered columns
//! (`filtered_stride` 2, 4, 8 x light x rectification x visibility x five bases, and the spot's
//! cookie), and 12 and 16 regions (Fourier m32, 4 and 6 moments x light x visibility, on a
//! 256x32 rectified map: a directional row needs regions^2 columns) (the moments are stored raw,
//! within the float formats' `1e-3`; the output within `1e-3 * max radiance`, as the Fourier
//! float variants, although the reconstruction is a solve). Directional variants run on
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
//! Each variant is one libtest trial (`cargo test -p scatter-conformance --test prefiltered
//! -- m32-t16-r4` runs those whose name contains the filter, `-- --list` lists the 2254);
//! `prefiltered::errors::*` check the error paths.

use std::process::ExitCode;
use std::sync::OnceLock;
use std::time::Instant;

use scatter_conformance::{Check, Fixture, compare_slices, gpu, run_trials};
use scatter_reference::kernels::common_prefiltered::{region_column, region_start};
use scatter_reference::kernels::{PrefilteredRun, run_prefiltered};
use scatter_reference::suite::{Pose, SceneName};
use scatter_runtime::wgpu::TextureView;
use scatter_runtime::{
    Context, CpuInputs, FrameInput, Inputs, Prefiltered, RuntimeError, run_prefiltered_once,
};
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::prefiltered::{
    FrameSettings, LightKind, PrefilteredVariant, Rectification, Resolutions, Storage,
    VisibilityMode,
};

const SCREEN: [u32; 2] = [64, 36];
const RECTIFIED: [u32; 2] = [64, 64];
/// The rectified map of variants with more than 8 regions: a directional row needs
/// `regions^2` columns (quadratic region starts), 256 for 16.
const WIDE_RECTIFIED: [u32; 2] = [256, 32];
/// The region counts above 8 the conformance run adds (epipolar only: a projective frame
/// holds at most 8 regions).
const WIDE_REGIONS: [u32; 2] = [12, 16];

/// The rectified map `variant` runs on: [`WIDE_RECTIFIED`] above 8 regions.
fn rectified_for(variant: &PrefilteredVariant) -> [u32; 2] {
    if variant.regions > 8 {
        WIDE_RECTIFIED
    } else {
        RECTIFIED
    }
}
const SHADOW_MAP: u32 = 128;

const RECTIFIED_TOL: f32 = 1e-4;
/// `resume`'s weight sums (bounds' second plane), relative: f32 sums of the same weights in
/// the same order on both sides, apart by the weights' transcendentals.
const WEIGHT_SUM_REL_TOL: f32 = 1e-4;

/// The scene and pose of a light and rectification (see [`Fixture::get`]).
const fn case(light: LightKind, rectification: Rectification) -> (SceneName, Pose) {
    match (light, rectification) {
        (LightKind::Directional, _) => (SceneName::Columns, Pose::Ordinary),
        // No prefiltered variant has an area light (the variant refuses it).
        (LightKind::Spot | LightKind::Area, Rectification::Epipolar) => {
            (SceneName::SpotGrate, Pose::Ordinary)
        }
        (LightKind::Spot | LightKind::Area, Rectification::Projective) => {
            (SceneName::SpotGrate, Pose::Grazing)
        }
    }
}

/// The fixture of a light and rectification (built once, on first use): directional
/// variants run on `columns/ordinary`; spot variants on `spot_grate/ordinary`, except
/// projective ones on `spot_grate/grazing` (the ordinary pose's slices fan out too wide for
/// a projective map: it falls back to epipolar).
fn fixture(light: LightKind, rectification: Rectification) -> &'static Fixture {
    static COLUMNS: OnceLock<Fixture> = OnceLock::new();
    static SPOT_GRATE: OnceLock<Fixture> = OnceLock::new();
    static SPOT_GRATE_GRAZING: OnceLock<Fixture> = OnceLock::new();
    let cell = match (light, rectification) {
        (LightKind::Directional, _) => &COLUMNS,
        (LightKind::Spot | LightKind::Area, Rectification::Epipolar) => &SPOT_GRATE,
        (LightKind::Spot | LightKind::Area, Rectification::Projective) => &SPOT_GRATE_GRAZING,
    };
    let (name, pose) = case(light, rectification);
    cell.get_or_init(|| Fixture::new(name, pose, SCREEN, SHADOW_MAP))
}

/// The fixture of `variant`: its light's and rectification's, with the `stained_glass`
/// cookie (64^2) on the spot for a `cookie` variant (built once per rectification).
fn variant_fixture(variant: &PrefilteredVariant) -> &'static Fixture {
    static EPIPOLAR: OnceLock<Fixture> = OnceLock::new();
    static PROJECTIVE: OnceLock<Fixture> = OnceLock::new();
    let plain = fixture(variant.light, variant.rectification);
    if !variant.cookie {
        return plain;
    }
    let cell = match variant.rectification {
        Rectification::Epipolar => &EPIPOLAR,
        Rectification::Projective => &PROJECTIVE,
    };
    cell.get_or_init(|| {
        plain.with_cookie(
            scatter_reference::cookie::Cookie::pattern("stained_glass", 64)
                .expect("a built-in pattern"),
        )
    })
}

fn for_light(light: LightKind) -> &'static Fixture {
    fixture(light, Rectification::Epipolar)
}

fn frame_input(f: &Fixture) -> FrameInput {
    f.frame_input(FrameSettings::default())
}

fn cpu_inputs(f: &Fixture) -> CpuInputs {
    CpuInputs {
        frame: frame_input(f),
        depth: f.gbuf.view_depth.clone(),
        shadow_map: f.shadow_map.depth.clone(),
        rectified: None,
        pass_wall_frames: 0,
        cookie: f.cookie(),
        vpl_maps: None,
    }
}

fn resolutions(f: &Fixture, variant: &PrefilteredVariant) -> Resolutions {
    Resolutions {
        screen: [f.gbuf.width, f.gbuf.height],
        rectified: rectified_for(variant),
    }
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
    bounds: Worst,
    output: Worst,
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

fn trial_name(variant: &PrefilteredVariant) -> String {
    let (name, pose) = case(variant.light, variant.rectification);
    format!(
        "{}::{name}::{pose}",
        FamilyVariant::from(*variant).trial_name()
    )
}

/// The CPU mirrors' run of `variant` on `fixture` (default frame settings).
fn cpu_run(variant: &PrefilteredVariant, fixture: &Fixture) -> Result<PrefilteredRun, String> {
    run_prefiltered(
        variant,
        rectified_for(variant),
        &fixture.scene,
        &fixture.bvh,
        &fixture.gbuf,
        &fixture.shadow_map,
        &FrameSettings::default(),
    )
    .map_err(|e| format!("CPU mirror failed: {e}"))
}

fn run_trial(
    ctx: &Context,
    variant: &PrefilteredVariant,
    fixture: &Fixture,
) -> Result<TrialResult, String> {
    let trial = trial_name(variant);
    let start = Instant::now();
    let cpu = cpu_run(variant, fixture).map_err(|e| format!("{trial}: {e}"))?;
    if cpu.frame.report.rectification != variant.rectification {
        return Err(format!(
            "{trial}: expected a {} frame, got {} ({:?})",
            variant.rectification, cpu.frame.report.rectification, cpu.frame.report.fallback
        ));
    }
    let mut inputs = cpu_inputs(fixture);
    if cpu.frame.report.projective.is_some() {
        inputs.rectified = Some(cpu.rectified.data.clone());
    }
    let gpu_start = Instant::now();
    let gpu = run_prefiltered_once(ctx, variant, resolutions(fixture, variant), &inputs)
        .map_err(|e| format!("{trial}: GPU run failed: {e}"))?;
    let gpu_wall = gpu_start.elapsed();
    if gpu.frame.uniforms != cpu.frame.uniforms || gpu.frame.report != cpu.frame.report {
        return Err(format!(
            "{trial}: the runtime uploaded a different frame set-up than the mirror used"
        ));
    }
    compare_slices(&gpu.slices, &cpu.frame.slices).map_err(|e| format!("{trial}: {e}"))?;
    let lengths = [
        ("rectified", gpu.rectified.len(), cpu.rectified.data.len()),
        ("filtered", gpu.filtered.len(), cpu.filtered.data.len()),
        ("bounds", gpu.bounds.len(), cpu.bounds.data.len()),
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
    // The bounds are minima and maxima of rectified depths: as close as the rectified maps.
    // With `resume` the second plane holds the weight sums (W, 0): sums of the same f32
    // weights in the same order, as close as their transcendentals (relative).
    let mut bounds = Worst::default();
    let plane = cpu.bounds.data.len() / cpu.bounds.layers.max(1) as usize;
    for (i, (g, c)) in gpu.bounds.iter().zip(&cpu.bounds.data).enumerate() {
        for k in 0..2 {
            let tol = if i < plane {
                RECTIFIED_TOL
            } else {
                WEIGHT_SUM_REL_TOL * c[k].abs() + 1e-6
            };
            bounds.update(2 * i + k, g[k], c[k], tol);
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
        "{trial}: rectified max |diff| {:.2e}; filtered {:.2e}; bounds {:.2e}; output {:.2e} ({:.2e} of max {:.3e}); {times}; run_prefiltered_once {:.0} ms, total {:.0} ms",
        rectified.diff,
        filtered.diff,
        bounds.diff,
        output.diff,
        output.diff / max_radiance.max(f32::MIN_POSITIVE),
        max_radiance,
        gpu_wall.as_secs_f64() * 1e3,
        start.elapsed().as_secs_f64() * 1e3,
    );
    Ok(TrialResult {
        rectified,
        filtered,
        bounds,
        output,
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

/// One variant's trial: the GPU against the mirror on its fixture, every output within its
/// tolerance.
/// The most a `resume` variant's output may differ from the same variant's at a stride of
/// 1, relative to the larger's maximum radiance: the stride of 1 rounds every column's means
/// to the storage format and `resume` only the stored ones, so the two differ by that
/// rounding, at most sum_k |a_k| q = 2.97 q for m32 (|a_k| <= 2 / c_k per sine and cosine, q the
/// decoded mean's rounding: 2 / 255 for rgba8unorm, 2^-10 for rgba16float); rgba32float and
/// the moments (rgba32float) by the order of f32 sums, which the moment reconstruction's
/// conditioning amplifies.
fn resume_tol(storage: Storage) -> f32 {
    match storage {
        Storage::Rgba8unorm => 3.0 * 2.0 / 255.0,
        Storage::Rgba16float => 3.0 * 2f32.powi(-10),
        Storage::Rgba32float => 1e-3,
    }
}

/// Whether `variant`'s regions start on the columns a stride of 1 starts them on (on its
/// trial map).
fn same_regions_as_stride_one(variant: &PrefilteredVariant) -> bool {
    let width = rectified_for(variant)[0];
    let spot = variant.light == LightKind::Spot;
    (0..=variant.regions).all(|r| {
        region_column(r, variant.regions, width, variant.filtered_stride, spot)
            == region_start(r, variant.regions, width, spot)
    })
}

/// `resume` gives the answer of a stride of 1 (CPU mirror, the variant's fixture): the
/// outputs within [`resume_tol`], and the stride of 1's bounds at every stored column.
fn resume_matches_stride_one(variant: &PrefilteredVariant) -> Result<(), String> {
    let fixture = variant_fixture(variant);
    let resumed = cpu_run(variant, fixture)?;
    let one = PrefilteredVariant {
        filtered_stride: 1,
        resume: false,
        ..*variant
    };
    let full = cpu_run(&one, fixture)?;
    let max = full
        .output
        .data
        .iter()
        .chain(&resumed.output.data)
        .flatten()
        .fold(0.0f32, |m, &v| m.max(v));
    let mut worst = (0.0f32, 0usize);
    for (i, (a, b)) in resumed
        .output
        .data
        .iter()
        .zip(&full.output.data)
        .enumerate()
    {
        for k in 0..3 {
            let d = (a[k] - b[k]).abs();
            if d > worst.0 {
                worst = (d, i);
            }
        }
    }
    if max <= 0.0 {
        return Err(format!(
            "{}: a black image at both strides: the comparison would assert nothing",
            trial_name(variant)
        ));
    }
    let tol = resume_tol(variant.storage) * max;
    eprintln!(
        "     {}: max |resume - stride 1| {:.3e} ({:.2e} of max {:.3e}; bar {:.1e})",
        trial_name(variant),
        worst.0,
        worst.0 / max.max(1e-30),
        max,
        resume_tol(variant.storage)
    );
    if resumed.output.data.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("{}: NaN or Inf in the output", trial_name(variant)));
    }
    if worst.0 > tol {
        return Err(format!(
            "{}: output differs from filtered_stride = 1 by {:.3e} at pixel {} (> {:.3e} = {:.1e} of max {:.3e})",
            trial_name(variant),
            worst.0,
            worst.1,
            tol,
            resume_tol(variant.storage),
            max
        ));
    }
    Ok(())
}

fn conformance(variant: &PrefilteredVariant) -> Result<(), String> {
    let Some(ctx) = gpu() else { return Ok(()) };
    compare(ctx, variant, variant_fixture(variant))
}

/// `slice_fit` where it changes the slice table: the light's fixture with its depth buffer
/// at 0.3x (the deepest pixel at 0.3 of the far plane), the default variant of the light.
/// Besides the whole comparison, the mirror's fitted table must be narrower than the
/// uploaded one on every row, by exactly the depth's factor for the sun.
fn slice_fit_conformance(light: LightKind) -> Result<(), String> {
    let Some(ctx) = gpu() else { return Ok(()) };
    let fixture = for_light(light).with_depth_scaled(0.3);
    let variant = PrefilteredVariant {
        light,
        ..base_variant()
    };
    let cpu = cpu_run(&variant, &fixture)?;
    let uploaded = scatter_shaderlib::prefiltered::prepare_frame(
        &variant,
        &resolutions(&fixture, &variant),
        &fixture.scene.camera_desc(),
        &fixture.scene.light_desc(),
        &fixture.scene.medium_desc(),
        &fixture.shadow_map.desc(),
        &FrameSettings::default(),
    )
    .map_err(|e| e.to_string())?;
    // The sun's extent is linear in the far distance: every row at exactly 0.3x. A spot's
    // is an angle at the light, which shrinks less (0.76-0.89x here): every row narrower.
    let wrong: Vec<(usize, f32)> = cpu
        .frame
        .slices
        .iter()
        .zip(&uploaded.slices)
        .map(|(c, u)| c.delta / u.delta)
        .enumerate()
        .filter(|&(_, ratio)| match light {
            LightKind::Directional => (ratio - 0.3).abs() > 1e-6,
            LightKind::Spot | LightKind::Area => ratio >= 0.95,
        })
        .collect();
    if !wrong.is_empty() {
        return Err(format!(
            "slice_fit at 0.3x depth: {} of {} rows have an unexpected spacing ratio, first \
             (row, ratio) {:?}",
            wrong.len(),
            uploaded.slices.len(),
            wrong[0]
        ));
    }
    compare(ctx, &variant, &fixture)
}

/// Runs one variant on one fixture, GPU against the mirror; `Err` lists every pass that
/// missed its tolerance.
fn compare(ctx: &Context, variant: &PrefilteredVariant, fixture: &Fixture) -> Result<(), String> {
    let [wr, hr] = rectified_for(variant);
    let [w, _] = SCREEN;
    let r = run_trial(ctx, variant, fixture)?;
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
    if !r.bounds.ok() {
        problems.push(describe("prefilter bounds", &r.bounds, |i| {
            let texel = (i / 2) as u32;
            format!(
                "(x {}, row {}) {}",
                texel % wr,
                texel / wr,
                ["min", "max"][i % 2]
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
        Ok(())
    } else {
        Err(format!("{}\n    {}", r.line, problems.join("\n    ")))
    }
}

fn main() -> ExitCode {
    // The grid, then 12 and 16 regions (on the wide map) for Fourier m32 and both moment
    // counts, every light and visibility.
    let mut variants = PrefilteredVariant::grid(1..=4);
    for regions in WIDE_REGIONS {
        for base in [
            PrefilteredVariant::default(),
            PrefilteredVariant::with_moments(4),
            PrefilteredVariant::with_moments(6),
        ] {
            for &light in LightKind::SINGLE {
                for &visibility in VisibilityMode::ALL {
                    variants.push(PrefilteredVariant {
                        regions,
                        light,
                        visibility,
                        ..base
                    });
                }
            }
        }
    }
    let mut trials: Vec<(String, Check)> = variants
        .into_iter()
        .map(|variant| {
            let check: Check = Box::new(move || conformance(&variant));
            (trial_name(&variant), check)
        })
        .collect();
    // `resume` against the same variant at a stride of 1, both on the mirror: the math, not
    // the GPU's agreement with it (the trials above). Only where both put the regions on the
    // same columns: a stride of k starts them on multiples of k, and where the stride of 1
    // does not (3 regions on the 64-column map: columns 7 and 28) the two are different
    // variants.
    for variant in PrefilteredVariant::grid(1..=4)
        .into_iter()
        .filter(|v| v.resume && same_regions_as_stride_one(v))
    {
        trials.push((
            format!(
                "prefiltered::resume_matches_stride_one::{}",
                trial_name(&variant)
            ),
            Box::new(move || resume_matches_stride_one(&variant)),
        ));
    }
    for light in LightKind::SINGLE.iter().copied() {
        trials.push((
            format!("prefiltered::slice_fit::{light}"),
            Box::new(move || slice_fit_conformance(light)),
        ));
    }
    let errors: [(&str, fn()); 4] = [
        ("wrong_shadow_map_size", wrong_shadow_map_size_is_an_error),
        ("zero_resolution", zero_resolution_is_an_error),
        ("invalid_variant", invalid_variant_names_the_knob),
        ("bad_frames", bad_frames_are_errors_not_panics),
    ];
    for (name, f) in errors {
        trials.push((
            format!("prefiltered::errors::{name}"),
            Box::new(move || {
                f();
                Ok(())
            }),
        ));
    }
    run_trials(trials, &[])
}

/// The variant the error tests start from.
fn base_variant() -> PrefilteredVariant {
    PrefilteredVariant::default()
}

fn columns_res() -> Resolutions {
    Resolutions {
        screen: SCREEN,
        rectified: RECTIFIED,
    }
}

fn wrong_shadow_map_size_is_an_error() {
    let Some(ctx) = gpu() else { return };
    let fixture = for_light(LightKind::Directional);
    let mut pass = Prefiltered::new(ctx, &base_variant(), columns_res(), 2 * SHADOW_MAP)
        .unwrap_or_else(|e| panic!("{e}"));
    let err = pass
        .prepare(ctx, &frame_input(fixture))
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
    let mut pass = Prefiltered::new(ctx, &base_variant(), columns_res(), SHADOW_MAP)
        .unwrap_or_else(|e| panic!("{e}"));
    pass.prepare(ctx, &frame_input(fixture))
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
                vpl_maps: None,
            },
        )
        .expect_err("an epipolar frame without a shadow map");
    assert!(matches!(err, RuntimeError::MissingInput { .. }), "{err}");
    eprintln!("ok   prefiltered::errors::missing_shadow_map: {err}");
    pass.encode(&mut encoder, &inputs(&depth, &sm))
        .unwrap_or_else(|e| panic!("{e}"));
    ctx.queue().submit([encoder.finish()]);
}

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
        let err = Prefiltered::new(ctx, &base_variant(), res, sm).expect_err(expected);
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
    let err = Prefiltered::new(ctx, &base_variant(), res, SHADOW_MAP).expect_err("too wide");
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
        Prefiltered::new(ctx, &base_variant(), res, SHADOW_MAP).expect_err("8 columns, 4 regions");
    assert!(
        matches!(
            err,
            RuntimeError::TooFewColumns {
                regions: 4,
                width: 8,
                min: 16,
                ..
            }
        ),
        "{err}"
    );
    eprintln!("ok   prefiltered::errors::too_few_columns: {err}");
}

fn invalid_variant_names_the_knob() {
    let Some(ctx) = gpu() else { return };
    let cases = [
        (
            PrefilteredVariant {
                regions: 17,
                ..base_variant()
            },
            "regions",
            "17",
        ),
        (
            PrefilteredVariant {
                regions: 9,
                rectification: Rectification::Projective,
                ..base_variant()
            },
            "regions",
            "9",
        ),
        (
            PrefilteredVariant {
                bases: 6,
                ..base_variant()
            },
            "bases",
            "6",
        ),
        (
            PrefilteredVariant {
                bases_per_thread: 12,
                ..base_variant()
            },
            "bases_per_thread",
            "12",
        ),
    ];
    for (variant, knob, value) in cases {
        let err = Prefiltered::new(ctx, &variant, columns_res(), SHADOW_MAP).expect_err(knob);
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

fn bad_frames_are_errors_not_panics() {
    let Some(ctx) = gpu() else { return };
    let fixture = for_light(LightKind::Directional);
    let mut pass = Prefiltered::new(ctx, &base_variant(), columns_res(), SHADOW_MAP)
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

    let mut nan = frame_input(fixture);
    nan.camera.position.x = f64::NAN;
    let err = pass.prepare(ctx, &nan).expect_err("NaN camera");
    assert!(
        matches!(err, RuntimeError::Frame(_)) && err.to_string().contains("camera"),
        "{err}"
    );
    eprintln!("ok   prefiltered::errors::nan_camera: {err}");

    let spot = frame_input(for_light(LightKind::Spot));
    let mut wrong_light = frame_input(fixture);
    wrong_light.light = spot.light;
    let err = pass
        .prepare(ctx, &wrong_light)
        .expect_err("spot light, directional variant");
    assert!(err.to_string().contains("spot"), "{err}");
    eprintln!("ok   prefiltered::errors::light_mismatch: {err}");

    // A short depth buffer in the test helper.
    let mut inputs = cpu_inputs(fixture);
    inputs.depth.pop();
    let err = run_prefiltered_once(ctx, &base_variant(), columns_res(), &inputs)
        .expect_err("short depth");
    assert!(
        matches!(err, RuntimeError::DataLength { .. }) && err.to_string().contains("depth"),
        "{err}"
    );
    eprintln!("ok   prefiltered::errors::short_depth: {err}");

    // After the errors, a good frame still works.
    pass.prepare(ctx, &frame_input(fixture))
        .unwrap_or_else(|e| panic!("{e}"));
}

/// An epipolar frame's inputs: depth and standard shadow map.
fn inputs<'a>(depth: &'a TextureView, shadow_map: &'a TextureView) -> Inputs<'a> {
    Inputs {
        depth,
        shadow_map: Some(shadow_map),
        rectified: None,
        vpl_maps: None,
    }
}
