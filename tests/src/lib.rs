//! `scatter-conformance`: the GPU test harness shared by the conformance tests.
//!
//! [`gpu`] hands every test the same [`Context`], or `None` with a loud skip message, as the
//! `SCATTER_GPU` / `CI` policy says (see [`scatter_runtime::GpuPolicy`]): locally a missing
//! adapter skips GPU trials, under CI it fails them. Trials are named
//! `family::kernel::variant::case` (e.g. `common::row_prefix::mean::37x5x2`) in every message.
//!
//! [`run_trials`] runs a family's conformance as libtest trials (libtest-mimic), one per
//! variant x scene x pose, named `family::variant::scene::pose`: `cargo test -p
//! scatter-conformance -- minmax::` runs one family, `-- --list` lists the trials, and a
//! failure names its trial. Expected failures are data: a trial listed in
//! `expected_failures` must fail, and the run fails when it starts passing or when the list
//! names a trial that does not exist.

use std::io::Write as _;
use std::process::ExitCode;
use std::sync::OnceLock;

use libtest_mimic::{Arguments, Failed, Trial};

use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::kernels::row_prefix as row_prefix_mirror;
use scatter_reference::scene::Scene;
use scatter_reference::suite::{MediumPreset, Pose, SceneName, scene};
use scatter_runtime::{ArraySize, Context, FrameInput, GpuPolicy, RaymarchInput};
use scatter_shaderlib::RowPrefixMode;
use scatter_shaderlib::prefiltered::{FrameSettings, LightKind};

/// The shared GPU context, or `None` when GPU trials must be skipped.
///
/// # Panics
///
/// When the policy is `required` (explicitly, or because `CI` is set) and no context can be
/// created, or when `SCATTER_GPU` is invalid: the test fails with the reason.
pub fn gpu() -> Option<&'static Context> {
    static GPU: OnceLock<Option<Context>> = OnceLock::new();
    let ctx = GPU.get_or_init(|| {
        let policy = GpuPolicy::from_env().unwrap_or_else(|e| panic!("scatter-conformance: {e}"));
        let reason = match policy {
            GpuPolicy::Off => "GPU work switched off".to_owned(),
            GpuPolicy::Auto | GpuPolicy::Required => match Context::new() {
                Ok(ctx) => {
                    loud(&format!(
                        "scatter-conformance: GPU adapter: {}",
                        ctx.report()
                    ));
                    return Some(ctx);
                }
                Err(e) if policy == GpuPolicy::Required => panic!(
                    "scatter-conformance: SCATTER_GPU=required (explicitly or because CI is \
                     set) but no GPU context: {e} (scripts/test.sh installs lavapipe)"
                ),
                Err(e) => e.to_string(),
            },
        };
        loud(&format!(
            "scatter-conformance: !!! GPU TRIALS SKIPPED (SCATTER_GPU={policy}): {reason}; set \
             SCATTER_GPU=required to fail instead !!!"
        ));
        None
    });
    if ctx.is_none() {
        eprintln!("scatter-conformance: GPU trial skipped (no GPU context)");
    }
    ctx.as_ref()
}

/// The suite scene the conformance trials use for a light type: `columns` for the sun,
/// `spot_grate` for the spot lamp and for an area light the base of `area_grate` (which
/// `scatter_reference::area_suite::scene` lights with its area light: the area family's
/// trials build their scenes there).
pub const fn scene_for(light: LightKind) -> SceneName {
    match light {
        LightKind::Directional => SceneName::Columns,
        LightKind::Spot | LightKind::Area => SceneName::SpotGrate,
    }
}

/// A suite scene at one pose with its ray-cast depth buffer and standard shadow map: the
/// inputs every family's trial takes.
pub struct Fixture {
    /// The scene's name.
    pub name: SceneName,
    /// The pose.
    pub pose: Pose,
    /// The scene (default medium).
    pub scene: Scene,
    /// Its BVH (the projective stand-in ray-casts it).
    pub bvh: Bvh,
    /// Depth buffer (and the rest of the G-buffer).
    pub gbuf: GBuffer,
    /// Standard shadow map.
    pub shadow_map: ShadowMap,
}

impl Fixture {
    /// Builds the scene at `screen` pixels with a `shadow_map_size`^2 shadow map.
    ///
    /// # Panics
    ///
    /// When the suite's shadow map cannot be built (a defect of the suite).
    pub fn new(name: SceneName, pose: Pose, screen: [u32; 2], shadow_map_size: u32) -> Self {
        let scene = scene(name, pose, MediumPreset::Default, screen[0], screen[1]);
        let bvh = Bvh::build(&scene.geometry);
        let gbuf = GBuffer::cast(&scene, &bvh);
        let shadow_map = ShadowMap::build(&scene, &bvh, shadow_map_size)
            .unwrap_or_else(|e| panic!("shadow map of {name}/{pose}: {e}"));
        Self {
            name,
            pose,
            scene,
            bvh,
            gbuf,
            shadow_map,
        }
    }

    /// The area scene `name` (`scatter_reference::area_suite`) at `screen` pixels, its
    /// standard shadow map (its area light's point limit's, the VPL maps' template)
    /// `shadow_map_size`^2; `name` is the scene's base ([`scene_for`] of an area light).
    ///
    /// # Panics
    ///
    /// When the suite's shadow map cannot be built (a defect of the suite).
    pub fn area(
        name: scatter_reference::area_suite::AreaSceneName,
        pose: Pose,
        screen: [u32; 2],
        shadow_map_size: u32,
    ) -> Self {
        let scene = scatter_reference::area_suite::scene(
            name,
            pose,
            MediumPreset::Default,
            screen[0],
            screen[1],
        );
        let bvh = Bvh::build(&scene.geometry);
        let gbuf = GBuffer::cast(&scene, &bvh);
        let shadow_map = ShadowMap::build(&scene, &bvh, shadow_map_size)
            .unwrap_or_else(|e| panic!("shadow map of {name}/{pose}: {e}"));
        Self {
            name: scene_for(LightKind::Area),
            pose,
            scene,
            bvh,
            gbuf,
            shadow_map,
        }
    }

    /// The same fixture with every depth-buffer value times `k` (and the ray lengths with
    /// them): a frame whose deepest pixel lies closer than the far plane, where `slice_fit`
    /// rewrites the slice table (almost every suite pose sees the sky, where it does not).
    pub fn with_depth_scaled(&self, k: f32) -> Self {
        let mut gbuf = self.gbuf.clone();
        for z in &mut gbuf.view_depth {
            *z *= k;
        }
        for s in &mut gbuf.ray_length {
            *s *= f64::from(k);
        }
        Self {
            name: self.name,
            pose: self.pose,
            scene: self.scene.clone(),
            bvh: Bvh::build(&self.scene.geometry),
            gbuf,
            shadow_map: self.shadow_map.clone(),
        }
    }

    /// The same fixture with `cookie` on its spot light (the depth buffer and shadow map do
    /// not depend on it).
    ///
    /// # Panics
    ///
    /// When the fixture's light is not a spot (a defect of the caller).
    pub fn with_cookie(&self, cookie: scatter_reference::cookie::Cookie) -> Self {
        let mut scene = self.scene.clone();
        match &mut scene.light {
            scatter_reference::scene::Light::Spot { cookie: c, .. } => *c = Some(cookie),
            scatter_reference::scene::Light::Directional { .. }
            | scatter_reference::scene::Light::Area(_) => {
                panic!("a cookie needs a spot light")
            }
        }
        Self {
            name: self.name,
            pose: self.pose,
            scene,
            bvh: Bvh::build(&self.scene.geometry),
            gbuf: self.gbuf.clone(),
            shadow_map: self.shadow_map.clone(),
        }
    }

    /// The spot light's cookie as `run_*_once` takes it: its size and RGBA texels.
    pub fn cookie(&self) -> Option<([u32; 2], Vec<[f32; 4]>)> {
        scene_cookie(&self.scene)
    }

    /// `scene::pose`, the tail of trial names.
    pub fn trial_tail(&self) -> String {
        format!("{}::{}", self.name, self.pose)
    }

    /// The CPU mirrors' view of this fixture with a `rectified` map and `settings`.
    pub fn cpu_frame<'a>(
        &'a self,
        rectified: [u32; 2],
        settings: &'a FrameSettings,
    ) -> scatter_reference::kernels::CpuFrame<'a> {
        scatter_reference::kernels::CpuFrame {
            scene: &self.scene,
            bvh: &self.bvh,
            gbuf: &self.gbuf,
            shadow_map: &self.shadow_map,
            rectified,
            settings,
        }
    }

    /// The frame input of the epipolar families with `settings`.
    pub fn frame_input(&self, settings: FrameSettings) -> FrameInput {
        FrameInput {
            camera: self.scene.camera_desc(),
            light: self.scene.light_desc(),
            medium: self.scene.medium_desc(),
            shadow_map: self.shadow_map.desc(),
            settings,
        }
    }

    /// The frame input of the raymarch family.
    pub fn raymarch_input(&self) -> RaymarchInput {
        RaymarchInput {
            camera: self.scene.camera_desc(),
            light: self.scene.light_desc(),
            medium: self.scene.medium_desc(),
            shadow_map: self.shadow_map.desc(),
        }
    }
}

/// A scene's spot cookie as `scatter_runtime::CpuInputs::cookie` takes it: its size and
/// RGBA texels (`None` without one).
pub fn scene_cookie(scene: &Scene) -> Option<([u32; 2], Vec<[f32; 4]>)> {
    match &scene.light {
        scatter_reference::scene::Light::Spot {
            cookie: Some(c), ..
        } => Some(([c.width(), c.height()], c.rgba())),
        _ => None,
    }
}

/// One conformance check: `Err` carries the failure's message (naming the trial).
pub type Check = Box<dyn FnOnce() -> Result<(), String> + Send>;

/// Runs `trials` (name, check) as libtest trials with the command line's filters and
/// options, in parallel. `expected_failures` lists `(trial name, reason)`: such a trial
/// passes when its check fails, and fails when the check passes (remove it from the list)
/// or when no trial has its name.
pub fn run_trials(trials: Vec<(String, Check)>, expected_failures: &[(&str, &str)]) -> ExitCode {
    run_trials_with(&Arguments::from_args(), trials, expected_failures).exit_code()
}

/// [`run_trials`] with explicit arguments, returning libtest-mimic's conclusion.
pub fn run_trials_with(
    args: &Arguments,
    trials: Vec<(String, Check)>,
    expected_failures: &[(&str, &str)],
) -> libtest_mimic::Conclusion {
    let mut stale: Vec<Trial> = expected_failures
        .iter()
        .filter(|(n, _)| !trials.iter().any(|(t, _)| t == n))
        .map(|&(n, why)| {
            let msg =
                format!("expected failure `{n}` ({why}) names no trial: remove it from the list");
            Trial::test(format!("expected_failures::{n}"), move || {
                Err(Failed::from(msg))
            })
        })
        .collect();
    let mut out: Vec<Trial> = trials
        .into_iter()
        .map(|(name, check)| {
            let expected = expected_failures
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, why)| (*why).to_owned());
            let trial_name = name.clone();
            Trial::test(trial_name, move || match (check(), expected) {
                (Ok(()), None) => Ok(()),
                (Err(e), None) => Err(Failed::from(e)),
                (Err(e), Some(why)) => {
                    loud(&format!("expected failure {name} ({why}): {e}"));
                    Ok(())
                }
                (Ok(()), Some(why)) => Err(Failed::from(format!(
                    "{name} is listed as an expected failure ({why}) but passes: remove it \
                     from the list"
                ))),
            })
        })
        .collect();
    out.append(&mut stale);
    libtest_mimic::run(args, out)
}

/// Writes a line straight to the process's stderr, past libtest's output capture (which
/// only catches `print!`/`eprint!`), so adapter reports and skips show in every run.
fn loud(line: &str) {
    // Nothing sensible to do if stderr is gone.
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// The mirror's mode for a shaderlib mode. Exhaustive: a new mode needs its mirror.
pub fn row_prefix_mirror_mode(mode: RowPrefixMode) -> row_prefix_mirror::Mode {
    match mode {
        RowPrefixMode::Sum => row_prefix_mirror::Mode::Sum,
        RowPrefixMode::Mean => row_prefix_mirror::Mode::Mean,
    }
}

/// The mirror's dimensions for a runtime array size.
pub fn mirror_dims(size: ArraySize) -> row_prefix_mirror::Dims {
    row_prefix_mirror::Dims {
        width: size.width,
        height: size.height,
        layers: size.layers,
    }
}

/// Deterministic test texels in [-1, 1) (the range of Fourier basis values), from a
/// 64-bit LCG seeded by `seed`: the same inputs on every machine.
pub fn test_texels(count: usize, seed: u64) -> Vec<[f32; 4]> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        // Top 24 bits: exactly representable in f32.
        ((state >> 40) as f32 / (1u32 << 24) as f32) * 2.0 - 1.0
    };
    (0..count)
        .map(|_| [next(), next(), next(), next()])
        .collect()
}

/// Distance between two f32 in units in the last place (0 for equal values, including
/// +0 and -0; `u32::MAX` when either is NaN).
pub fn ulp_distance(a: f32, b: f32) -> u32 {
    if a.is_nan() || b.is_nan() {
        return u32::MAX;
    }
    // Map the sign-magnitude bit patterns onto a monotonic integer line.
    let key = |x: f32| {
        let bits = x.to_bits() as i32;
        if bits < 0 { i32::MIN - bits } else { bits }
    };
    key(a).abs_diff(key(b))
}

/// Runs any family's variant on a scene, as the stress and random-pose suites do: on the GPU
/// through [`scatter_runtime::run_family_once`] (for a prefiltered variant with the engine's
/// rasterised rectified map, which a projective frame needs) or, without a context, through
/// its CPU mirrors ([`scatter_reference::kernels::run_family`]). The depth buffer is
/// `frame.gbuf.view_depth`. Returns the output (rgb) and, for the epipolar families, the frame
/// report.
///
/// # Errors
///
/// The frame set-up's or the runtime's error, as text.
pub fn run_variant(
    ctx: Option<&Context>,
    variant: &scatter_shaderlib::family::FamilyVariant,
    frame: &scatter_reference::kernels::CpuFrame<'_>,
) -> Result<
    (
        scatter_reference::image::Image,
        Option<scatter_shaderlib::prefiltered::FrameReport>,
    ),
    String,
> {
    run_variant_counted(ctx, variant, frame).map(|(image, report, _)| (image, report))
}

/// [`run_variant`], with the pixels the GPU's epipolar `_unwarp` pass listed for its
/// `_fallback` pass (`None` without epipolar sampling or on the CPU).
///
/// # Errors
///
/// As [`run_variant`].
#[allow(
    clippy::type_complexity,
    reason = "the tuple of run_variant plus one count; a struct would name it once"
)]
pub fn run_variant_counted(
    ctx: Option<&Context>,
    variant: &scatter_shaderlib::family::FamilyVariant,
    frame: &scatter_reference::kernels::CpuFrame<'_>,
) -> Result<
    (
        scatter_reference::image::Image,
        Option<scatter_shaderlib::prefiltered::FrameReport>,
        Option<u32>,
    ),
    String,
> {
    run_variant_in(ctx, None, variant, frame)
}

/// Passes kept across the frames of a test, per variant and sizes (as an engine keeps them):
/// on lavapipe with a cold Mesa cache, passes built anew per frame compile their kernels
/// again (the flicker test: 713 s with passes per scene, 480 s kept).
#[derive(Default)]
pub struct PassCache(std::collections::HashMap<String, scatter_runtime::FamilyPasses>);

/// [`run_variant`] on the GPU through `cache`'s passes for the variant (built on first use).
///
/// # Errors
///
/// As [`run_variant`].
pub fn run_variant_cached(
    ctx: Option<&Context>,
    cache: &mut PassCache,
    variant: &scatter_shaderlib::family::FamilyVariant,
    frame: &scatter_reference::kernels::CpuFrame<'_>,
) -> Result<
    (
        scatter_reference::image::Image,
        Option<scatter_shaderlib::prefiltered::FrameReport>,
    ),
    String,
> {
    run_variant_in(ctx, Some(cache), variant, frame).map(|(image, report, _)| (image, report))
}

#[allow(clippy::type_complexity, reason = "run_variant_counted's tuple")]
fn run_variant_in(
    ctx: Option<&Context>,
    cache: Option<&mut PassCache>,
    variant: &scatter_shaderlib::family::FamilyVariant,
    frame: &scatter_reference::kernels::CpuFrame<'_>,
) -> Result<
    (
        scatter_reference::image::Image,
        Option<scatter_shaderlib::prefiltered::FrameReport>,
        Option<u32>,
    ),
    String,
> {
    use scatter_reference::image::Image;
    use scatter_reference::kernels::{CpuRun, engine_rectified_map, run_family};
    use scatter_shaderlib::family::FamilyVariant;
    use scatter_shaderlib::prefiltered::{Resolutions, prepare_frame};

    let Some(ctx) = ctx else {
        let run = run_family(variant, frame).map_err(|e| e.to_string())?;
        return Ok((run.output().clone(), run.report().cloned(), None));
    };
    let (scene, gbuf) = (frame.scene, frame.gbuf);
    let input = FrameInput {
        camera: scene.camera_desc(),
        light: scene.light_desc(),
        medium: scene.medium_desc(),
        shadow_map: frame.shadow_map.desc(),
        settings: *frame.settings,
    };
    let res = Resolutions {
        screen: [gbuf.width, gbuf.height],
        rectified: frame.rectified,
    };
    // A projective frame needs the engine's rasterised rectified map.
    let rectified = match variant {
        FamilyVariant::Prefiltered(v) => {
            let prepared = prepare_frame(
                v,
                &res,
                &input.camera,
                &input.light,
                &input.medium,
                &input.shadow_map,
                &input.settings,
            )
            .map_err(|e| e.to_string())?;
            engine_rectified_map(scene, frame.bvh, &prepared)
        }
        _ => None,
    };
    let cpu = scatter_runtime::CpuInputs {
        frame: input,
        depth: gbuf.view_depth.clone(),
        shadow_map: frame.shadow_map.depth.clone(),
        rectified,
        pass_wall_frames: 0,
        cookie: if variant.cookie() {
            scene_cookie(scene)
        } else {
            None
        },
        // An area light's VPL maps, as the engine renders them (framed by the set-up).
        vpl_maps: match variant {
            FamilyVariant::AreaIvsv(v) => Some(
                scatter_reference::kernels::ivsv_inputs(
                    scene,
                    gbuf,
                    frame.bvh,
                    v,
                    frame.shadow_map.size,
                )
                .map_err(|e| e.to_string())?
                .map_data,
            ),
            _ => None,
        },
    };
    let out = match cache {
        None => scatter_runtime::run_family_once(ctx, variant, res, &cpu),
        Some(cache) => {
            let sm_size = cpu.frame.shadow_map.size;
            let key = format!("{variant:?} {res:?} {sm_size}");
            let pass = match cache.0.entry(key) {
                std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                std::collections::hash_map::Entry::Vacant(e) => e.insert(
                    scatter_runtime::FamilyPasses::new(ctx, variant, res, sm_size)
                        .map_err(|e| e.to_string())?,
                ),
            };
            scatter_runtime::run_family_on(ctx, pass, res, &cpu)
        }
    }
    .map_err(|e| e.to_string())?;
    let image = Image::from_pixels(
        gbuf.width,
        gbuf.height,
        out.output.iter().map(|c| [c[0], c[1], c[2]]).collect(),
    );
    Ok((image, out.report, out.fallback_pixels))
}

/// Relative tolerance of `slice_fit`'s column spacing, GPU against its mirror: exact for the
/// sun (one product and one quotient), a few ulp of the driver's `atan2` for a spot.
pub const SLICE_DELTA_REL_TOL: f32 = 1e-5;

/// The slice table `slice_fit` left on the GPU against the mirror's: the view angles equal,
/// the column spacings within [`SLICE_DELTA_REL_TOL`]. `Err` names the first row that is not.
pub fn compare_slices(
    gpu: &[scatter_shaderlib::prefiltered::SliceParams],
    cpu: &[scatter_shaderlib::prefiltered::SliceParams],
) -> Result<(), String> {
    if gpu.len() != cpu.len() {
        return Err(format!(
            "slice table: {} rows on the GPU, {} in the mirror",
            gpu.len(),
            cpu.len()
        ));
    }
    for (row, (g, c)) in gpu.iter().zip(cpu).enumerate() {
        let angles = [g.theta_ref, g.theta_lo, g.theta_hi] == [c.theta_ref, c.theta_lo, c.theta_hi];
        let close = (g.delta - c.delta).abs() <= SLICE_DELTA_REL_TOL * c.delta.abs();
        if !angles || !close {
            return Err(format!(
                "slice table row {row}: gpu {g:?}, mirror {c:?} (slice_fit)"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(ok: bool) -> Check {
        Box::new(move || {
            if ok {
                Ok(())
            } else {
                Err("it failed".to_owned())
            }
        })
    }

    #[test]
    /// Runs nested trial sets: their own "FAILED" summaries in the log are on purpose.
    fn expected_failures_are_data() {
        let args = Arguments {
            test_threads: Some(1),
            quiet: true,
            ..Arguments::default()
        };
        let trials = || {
            vec![
                ("harness_selftest::passes".to_owned(), check(true)),
                (
                    "harness_selftest::fails_on_purpose".to_owned(),
                    check(false),
                ),
            ]
        };
        // A failing trial fails the run; listed as expected, it passes.
        let plain = run_trials_with(&args, trials(), &[]);
        assert_eq!((plain.num_passed, plain.num_failed), (1, 1));
        let listed = run_trials_with(
            &args,
            trials(),
            &[("harness_selftest::fails_on_purpose", "known")],
        );
        assert_eq!((listed.num_passed, listed.num_failed), (2, 0));
        // A listed trial that passes fails, and so does an entry that names no trial.
        let fixed = run_trials_with(
            &args,
            trials(),
            &[("harness_selftest::passes", "was known")],
        );
        assert_eq!((fixed.num_passed, fixed.num_failed), (0, 2));
        let stale = run_trials_with(&args, vec![], &[("harness_selftest::gone", "renamed")]);
        assert_eq!((stale.num_passed, stale.num_failed), (0, 1));
    }

    #[test]
    fn ulp_distance_counts_representable_steps() {
        assert_eq!(ulp_distance(1.0, 1.0), 0);
        assert_eq!(ulp_distance(0.0, -0.0), 0);
        assert_eq!(ulp_distance(1.0, 1.0 + f32::EPSILON), 1);
        assert_eq!(
            ulp_distance(-f32::MIN_POSITIVE, f32::MIN_POSITIVE),
            2 * 0x0080_0000
        );
        assert_eq!(ulp_distance(f32::NAN, 1.0), u32::MAX);
    }

    #[test]
    fn test_texels_are_deterministic_and_in_range() {
        let a = test_texels(100, 7);
        assert_eq!(a, test_texels(100, 7));
        assert_ne!(a, test_texels(100, 8));
        assert!(a.iter().flatten().all(|v| (-1.0..1.0).contains(v)));
    }
}
