//! Textured spot lights (issue 18 part 2): a spot's cookie (`scatter_shaderlib::cookie`, the
//! `stained_glass` pattern at 64^2) through both truths and every family that reads one.
//!
//! Asserted:
//! - the model: a white cookie is no cookie (the truth and the raymarch mirror unchanged to
//!   the last bit) and a uniform grey cookie scales the truth by its value;
//! - the truth converges with the cookie's sharp lead lines: doubling the cells changes the
//!   image by less than 0.1 % rel L1;
//! - the premise: the cookie changes the truth (by more than 10 % rel L1 on every case);
//! - every family's `cookie` variant (GPU on lavapipe; the CPU mirrors without one) within
//!   the plain spot's bars against the `shadow_map` truth with the cookie, 5 % rel L1 and
//!   10 % rel RMSE (`tests/tests/lamp.rs`), 0 NaN/Inf, on `spot_grate` at `ordinary`,
//!   `grazing` and `epipole_on_screen` (the lamp on screen) and on every spot pose of the
//!   random-pose generator's first 4 draws per scene (seed 2026);
//!   (prefiltered with both bases);
//! - every family has the knob, a cookie on the sun names the `cookie` knob, and a variant
//!   without it refuses a cookie (`RuntimeError::NoCookie`).
//!
//! `cargo test --release -p scatter-conformance --test cookie -- --nocapture` prints the
//! table of the closing note.

use scatter_conformance::{gpu, run_variant};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::cookie::Cookie;
use scatter_reference::image::Image;
use scatter_reference::kernels::{CpuFrame, run_raymarch};
use scatter_reference::metrics;
use scatter_reference::random_poses;
use scatter_reference::scene::{Light, Scene};
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_shaderlib::family::{Family, FamilyVariant};
use scatter_shaderlib::prefiltered::PrefilteredVariant;
use scatter_shaderlib::prefiltered::{FrameSettings, LightKind};
use scatter_shaderlib::raymarch::RaymarchVariant;

const SCREEN: [u32; 2] = [96, 54];
const SHADOW_MAP: u32 = 1024;
const RECTIFIED: [u32; 2] = [512, 512];
/// The plain spot's bars (`tests/tests/lamp.rs`).
const REL_L1_BAR: f64 = 0.05;
const REL_RMSE_BAR: f64 = 0.10;
/// The seed of the random spot poses.
const SEED: u64 = 2026;

fn stained_glass() -> Cookie {
    Cookie::pattern("stained_glass", 64).expect("a built-in pattern")
}

/// `scene` with `cookie` on its spot.
fn with_cookie(scene: &Scene, cookie: Option<Cookie>) -> Scene {
    let mut s = scene.clone();
    match &mut s.light {
        Light::Spot { cookie: c, .. } => *c = cookie,
        Light::Directional { .. } | Light::Area(_) => {
            panic!("{}: a cookie needs a spot light", scene.name)
        }
    }
    s
}

/// The cases: `spot_grate` at three poses and the random spot poses.
fn cases() -> Vec<(String, Scene)> {
    let mut out: Vec<(String, Scene)> = [Pose::Ordinary, Pose::Grazing, Pose::EpipoleOnScreen]
        .into_iter()
        .map(|pose| {
            (
                format!("spot_grate/{pose}"),
                suite::scene(
                    SceneName::SpotGrate,
                    pose,
                    MediumPreset::Default,
                    SCREEN[0],
                    SCREEN[1],
                ),
            )
        })
        .collect();
    for p in random_poses::poses(SEED, 4, SCREEN[0], SCREEN[1]) {
        if matches!(p.scene.light, Light::Spot { .. }) && !p.dark {
            out.push((p.name(), p.scene));
        }
    }
    out
}

/// A scene's depth buffer, shadow map and `shadow_map` truth.
struct Prepared {
    bvh: Bvh,
    gbuf: GBuffer,
    sm: ShadowMap,
}

impl Prepared {
    fn new(scene: &Scene) -> Self {
        let bvh = Bvh::build(&scene.geometry);
        let gbuf = GBuffer::cast(scene, &bvh);
        let sm = ShadowMap::build(scene, &bvh, SHADOW_MAP).expect("shadow map");
        Prepared { bvh, gbuf, sm }
    }

    fn truth(&self, scene: &Scene, settings: &TruthSettings) -> Image {
        truth::render(
            scene,
            &self.gbuf,
            &Visibility::ShadowMap(&self.sm),
            settings,
            &|| (),
        )
    }
}

fn max_abs_diff(a: &Image, b: &Image) -> f64 {
    a.data
        .iter()
        .zip(&b.data)
        .flat_map(|(p, q)| (0..3).map(move |k| f64::from((p[k] - q[k]).abs())))
        .fold(0.0, f64::max)
}

#[test]
fn a_white_cookie_is_no_cookie_and_a_grey_one_scales() {
    let base = suite::scene(
        SceneName::SpotGrate,
        Pose::Ordinary,
        MediumPreset::Default,
        SCREEN[0],
        SCREEN[1],
    );
    let p = Prepared::new(&base);
    let settings = TruthSettings::default();
    let plain = p.truth(&base, &settings);
    let white = Cookie::from_texels(3, 2, vec![[1.0; 3]; 6]).expect("cookie");
    let grey = Cookie::from_texels(2, 2, vec![[0.25, 0.5, 0.75]; 4]).expect("cookie");
    let lit_white = with_cookie(&base, Some(white));
    let t = p.truth(&lit_white, &settings);
    // Per channel the same Gauss-Legendre sums of the same integrand times 1.0.
    let d = max_abs_diff(&t, &plain);
    let max = plain.data.iter().flatten().fold(0f32, |m, &v| m.max(v));
    assert!(max > 0.0);
    assert!(
        d <= 1e-12 * f64::from(max),
        "white cookie changes the truth by {d:e}"
    );
    let t = p.truth(&with_cookie(&base, Some(grey)), &settings);
    for (q, r) in t.data.iter().zip(&plain.data) {
        for (k, s) in [0.25f32, 0.5, 0.75].into_iter().enumerate() {
            assert!(
                (q[k] - s * r[k]).abs() <= 1e-6 * max,
                "grey cookie: {} vs {s} x {}",
                q[k],
                r[k]
            );
        }
    }
    // The raymarch mirror: the cookie variant with a white cookie is the plain variant.
    let spot = RaymarchVariant {
        light: LightKind::Spot,
        ..RaymarchVariant::default()
    };
    let a = run_raymarch(&spot, &base, &p.gbuf, &p.sm).expect("frame");
    let b = run_raymarch(
        &RaymarchVariant {
            cookie: true,
            ..spot
        },
        &lit_white,
        &p.gbuf,
        &p.sm,
    )
    .expect("frame");
    assert_eq!(
        a.output, b.output,
        "white cookie changes the raymarch mirror"
    );
}

#[test]
fn the_truth_converges_with_a_cookie() {
    for pose in [Pose::Ordinary, Pose::Grazing] {
        let base = suite::scene(
            SceneName::SpotGrate,
            pose,
            MediumPreset::Default,
            SCREEN[0],
            SCREEN[1],
        );
        let scene = with_cookie(&base, Some(stained_glass()));
        let p = Prepared::new(&scene);
        let settings = TruthSettings::default();
        let t = p.truth(&scene, &settings);
        let t2 = p.truth(
            &scene,
            &TruthSettings {
                segments: 2 * settings.segments,
                ..settings
            },
        );
        let e = metrics::compare(&t, &t2).expect("same size").rel_l1;
        println!(
            "cookie truth spot_grate/{pose}: rel L1 of {} vs {} cells = {:.4} %",
            settings.segments,
            2 * settings.segments,
            100.0 * e
        );
        assert!(e < 1e-3, "spot_grate/{pose}: {e}");
    }
}

/// The families' `cookie` variants: each family's default with the knob on, where the family
/// has it, and prefiltered's moment basis (4 moments) beside its Fourier default.
fn cookie_variants() -> Vec<FamilyVariant> {
    Family::ALL
        .iter()
        .map(|f| f.default_variant())
        .chain([FamilyVariant::from(PrefilteredVariant::with_moments(4))])
        .filter_map(|v| v.with_light(LightKind::Spot).with_cookie(true))
        .collect()
}

/// The families that render a spot light (`area_ivsv` renders area lights, which have no
/// cookie: its variant has no `cookie` knob and its passes refuse one).
fn spot_families() -> impl Iterator<Item = &'static Family> {
    Family::ALL.iter().filter(|f| {
        f.default_variant()
            .with_light(LightKind::Spot)
            .validate()
            .is_ok()
    })
}

#[test]
fn every_family_reads_a_cookie_and_a_variant_without_one_says_so() {
    let with: Vec<Family> = cookie_variants()
        .iter()
        .map(FamilyVariant::family)
        .collect();
    for f in Family::ALL {
        if !spot_families().any(|g| g == f) {
            assert!(f.default_variant().with_cookie(true).is_none(), "{f}");
            continue;
        }
        assert!(with.contains(f), "{f} has no cookie knob");
        let c = f
            .default_variant()
            .with_light(LightKind::Spot)
            .with_cookie(true)
            .expect("the knob");
        assert!(c.validate().is_ok() && c.cookie(), "{c}");
        // A cookie needs a spot: the knob names itself on a directional light.
        let sun = c.with_light(LightKind::Directional);
        let err = sun.validate().expect_err("a cookie on the sun");
        assert_eq!(err.knob, "cookie", "{sun}: {err}");
    }
    let Some(ctx) = gpu() else {
        return;
    };
    // A variant without the knob set refuses a cookie (the runtime's NoCookie), and so do
    // a family without the knob's passes.
    for f in Family::ALL {
        let v = if spot_families().any(|g| g == f) {
            f.default_variant().with_light(LightKind::Spot)
        } else {
            f.default_variant()
        };
        let mut pass = scatter_runtime::FamilyPasses::new(
            ctx,
            &v,
            scatter_shaderlib::prefiltered::Resolutions {
                screen: [8, 8],
                rectified: [64, 64],
            },
            64,
        )
        .unwrap_or_else(|e| panic!("{v}: {e}"));
        let texture = scatter_runtime::textures::upload_cookie(
            ctx,
            scatter_shaderlib::Kernel::Raymarch,
            [1, 1],
            &[[1.0; 4]],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let err = pass
            .set_cookie(&texture.create_view(&Default::default()))
            .expect_err("a variant without a cookie");
        assert!(
            matches!(err, scatter_runtime::RuntimeError::NoCookie { .. }),
            "{v}: {err}"
        );
        println!("{v}: {err}");
    }
}

#[test]
fn every_cookie_family_meets_the_spot_bars() {
    let ctx = gpu();
    let variants = cookie_variants();
    let mut failures = Vec::new();
    let mut table = vec![format!(
        "| case | cookie vs plain truth | {} |",
        variants
            .iter()
            .map(|v| format!("{} (plain)", v.label()))
            .collect::<Vec<_>>()
            .join(" | ")
    )];
    for (name, base) in cases() {
        let scene = with_cookie(&base, Some(stained_glass()));
        let p = Prepared::new(&scene);
        let settings = TruthSettings::default();
        let truth = p.truth(&scene, &settings);
        let plain_truth = p.truth(&base, &settings);
        let premise = metrics::compare(&plain_truth, &truth)
            .expect("same size")
            .rel_l1;
        if premise < 0.1 {
            failures.push(format!(
                "{name}: the cookie changes the truth by only {:.2} %",
                100.0 * premise
            ));
        }
        let frame_settings = FrameSettings::for_screen(SCREEN[0], SCREEN[1]);
        let run = |scene: &Scene, v: &FamilyVariant| {
            run_variant(
                ctx,
                v,
                &CpuFrame {
                    scene,
                    bvh: &p.bvh,
                    gbuf: &p.gbuf,
                    shadow_map: &p.sm,
                    rectified: RECTIFIED,
                    settings: &frame_settings,
                },
            )
            .map(|(image, _)| image)
        };
        let mut row = format!("| {name} | {:.1} % |", 100.0 * premise);
        for v in &variants {
            let trial = format!("{}::{name}", v.trial_name());
            let (cookie, plain) = match (
                run(&scene, v),
                run(&base, &v.with_cookie(false).expect("the knob")),
            ) {
                (Ok(a), Ok(b)) => (a, b),
                (Err(e), _) | (_, Err(e)) => {
                    failures.push(format!("{trial}: {e}"));
                    continue;
                }
            };
            let r = metrics::compare(&cookie, &truth).expect("same size");
            let q = metrics::compare(&plain, &plain_truth).expect("same size");
            row += &format!(
                " {:.2} / {:.2} % ({:.2} / {:.2} %) |",
                100.0 * r.rel_l1,
                100.0 * r.rel_rmse,
                100.0 * q.rel_l1,
                100.0 * q.rel_rmse
            );
            if r.non_finite > 0 || r.rel_l1 > REL_L1_BAR || r.rel_rmse > REL_RMSE_BAR {
                failures.push(format!(
                    "{trial}: rel L1 {:.2} % / rel RMSE {:.2} % ({} NaN/Inf) over the bars \
                     {:.0} % / {:.0} %",
                    100.0 * r.rel_l1,
                    100.0 * r.rel_rmse,
                    r.non_finite,
                    100.0 * REL_L1_BAR,
                    100.0 * REL_RMSE_BAR
                ));
            }
        }
        table.push(row);
    }
    println!(
        "{} ({}x{}, shadow map {SHADOW_MAP}^2, stained_glass 64^2; rel L1 / rel RMSE vs the \
         shadow_map truth with the cookie, in brackets the plain variant vs the plain truth)",
        if ctx.is_some() { "GPU" } else { "CPU mirrors" },
        SCREEN[0],
        SCREEN[1]
    );
    for line in &table {
        println!("{line}");
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
