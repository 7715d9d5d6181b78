//! The raymarch family (Tóth & Umenhoffer 2009) on the CPU mirror: it converges to the
//! `shadow_map` ground truth as the samples grow, and interleaved sampling with its sum
//! filter reproduces the full-N result exactly when the integrand is constant (the check
//! that the filter sums classes rather than averaging them).

use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::kernels::run_raymarch;
use scatter_reference::metrics;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_shaderlib::prefiltered::LightKind;
use scatter_shaderlib::raymarch::RaymarchVariant;

const SCREEN: (u32, u32) = (160, 90);
const SHADOW_MAP: u32 = 1024;

fn light_of(name: SceneName) -> LightKind {
    if name == SceneName::SpotGrate {
        LightKind::Spot
    } else {
        LightKind::Directional
    }
}

/// Directional and spot variants at N = 8, 32, 128, 512 on the `ordinary` and
/// `epipole_on_screen` poses of every scene (160x90, 1024^2 shadow map).
#[test]
fn error_falls_as_samples_grow() {
    let mut failures = Vec::new();
    for &name in SceneName::ALL {
        for pose in [Pose::Ordinary, Pose::EpipoleOnScreen] {
            let scene = suite::scene(name, pose, MediumPreset::Default, SCREEN.0, SCREEN.1);
            let bvh = Bvh::build(&scene.geometry);
            let gbuf = GBuffer::cast(&scene, &bvh);
            let sm = ShadowMap::build(&scene, &bvh, SHADOW_MAP).expect("shadow map");
            let truth = truth::render(
                &scene,
                &gbuf,
                &Visibility::ShadowMap(&sm),
                &TruthSettings::default(),
                &|| (),
            );
            let errors: Vec<f64> = [8, 32, 128, 512]
                .into_iter()
                .map(|samples| {
                    let variant = RaymarchVariant {
                        samples,
                        light: light_of(name),
                        ..RaymarchVariant::default()
                    };
                    let run = run_raymarch(&variant, &scene, &gbuf, &sm).expect("frame");
                    let report = metrics::compare(&run.output, &truth).expect("same size");
                    assert_eq!(report.non_finite, 0, "raymarch::{variant}::{name}::{pose}");
                    report.rel_l1
                })
                .collect();
            println!(
                "raymarch::{name}::{pose}: rel L1 N=8/32/128/512 = {}",
                errors
                    .iter()
                    .map(|e| format!("{:.3} %", 100.0 * e))
                    .collect::<Vec<_>>()
                    .join(" / ")
            );
            if errors.windows(2).any(|w| w[1] > w[0]) {
                failures.push(format!("{name}/{pose}: {errors:?}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "error does not fall with N: {failures:#?}"
    );
}

#[test]
fn interleaving_a_constant_integrand_gives_the_full_sum() {
    // Isotropic phase, nothing shadowed, every view ray 10 long: every pixel has the same
    // integrand, so summing the classes of a window must give the full-N sum.
    let mut scene = suite::scene(
        SceneName::Columns,
        Pose::Ordinary,
        MediumPreset::Default,
        37,
        21,
    );
    scene.medium.sigma_t = 1e-3;
    scene.medium.albedo = 1.0;
    scene.medium.g = 0.0;
    let bvh = Bvh::build(&scene.geometry);
    let mut gbuf = GBuffer::cast(&scene, &bvh);
    let mut sm = ShadowMap::build(&scene, &bvh, 64).expect("shadow map");
    sm.depth.iter_mut().for_each(|d| *d = 1.0);
    let fwd = scene.camera_desc().forward;
    for y in 0..gbuf.height {
        for x in 0..gbuf.width {
            let dir = scatter_reference::buffers::camera_ray(&scene, &scene.camera.frame(), x, y);
            gbuf.view_depth[(y * gbuf.width + x) as usize] = (10.0 * dir.dot(fwd)) as f32;
        }
    }
    for jitter in [false, true] {
        let full = run_raymarch(
            &RaymarchVariant {
                samples: 64,
                interleave: 1,
                jitter,
                light: LightKind::Directional,
                ..RaymarchVariant::default()
            },
            &scene,
            &gbuf,
            &sm,
        )
        .expect("frame");
        let max = full
            .output
            .data
            .iter()
            .flatten()
            .fold(0.0f32, |m, &v| m.max(v));
        assert!(max > 0.0);
        for interleave in [2, 4, 8] {
            let variant = RaymarchVariant {
                samples: 64,
                interleave,
                jitter,
                light: LightKind::Directional,
                ..RaymarchVariant::default()
            };
            let run = run_raymarch(&variant, &scene, &gbuf, &sm).expect("frame");
            // Each pixel's own partial sum holds 1 / interleave^2 of the cells (up to the
            // transmittance's decay across a class's cells, under 1 % here).
            let partial = run
                .partial
                .as_ref()
                .expect("interleaved variants keep partial sums");
            let pmax = partial
                .data
                .iter()
                .map(|t| t[0].max(t[1]).max(t[2]))
                .fold(0.0f32, f32::max);
            let share = (interleave * interleave) as f32;
            assert!(
                (pmax * share - max).abs() <= 0.02 * max,
                "{variant}: partial max {pmax} x {share} vs full max {max}"
            );
            let worst = run
                .output
                .data
                .iter()
                .zip(&full.output.data)
                .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
                .fold(0.0f32, f32::max);
            println!(
                "raymarch::{variant}::constant: max |interleaved - full| / max = {:.2e}",
                worst / max
            );
            // Both are rounded to rgba16float: allow one f16 step (2^-10 relative).
            assert!(worst <= max * 2f32.powi(-10), "{variant}: {worst} of {max}");
        }
    }
}
