//! The `area_ivsv` method on the CPU (Wyman & Dai 2013): its epipolar coordinates, the
//! rectified and extruded voxel bits, and its accuracy against the `vpl` truth.

use glam::DVec3;
use scatter_reference::area_ivsv::{
    self, EpipolarGrid, IvsvError, IvsvSettings, PHI_BITS, Weights,
};
use scatter_reference::area_suite::{self, AreaSceneName};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::metrics;
use scatter_reference::scene::Light;
use scatter_reference::suite::{MediumPreset, Pose};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use std::f64::consts::PI;

/// Whether the full (opt-in) grid runs: `SCATTER_FULL=1`.
fn full() -> bool {
    std::env::var("SCATTER_FULL").is_ok_and(|v| v == "1")
}

fn grid_for(name: AreaSceneName, pose: Pose, vpl: usize) -> (EpipolarGrid, ShadowMap) {
    let s = area_suite::scene(name, pose, MediumPreset::Default, 32, 18);
    let bvh = Bvh::build(&s.geometry);
    let v = &s.point_light_scenes(16)[vpl];
    let Light::Spot { position, .. } = v.light else {
        panic!("a VPL is a spot")
    };
    let sm = ShadowMap::build(v, &bvh, 128).unwrap();
    (EpipolarGrid::new(s.camera.position, position, 64, 64), sm)
}

#[test]
fn epipolar_coordinates_round_trip() {
    let (g, _) = grid_for(AreaSceneName::Grate, Pose::Ordinary, 3);
    for k in 0..200 {
        let x = f64::from(k);
        let dir = DVec3::new((x * 0.37).sin(), (x * 0.71).cos(), (x * 1.3).sin() + 0.1).normalize();
        let (alpha, theta) = g.eye_angles(dir);
        assert!((0.0..=PI).contains(&alpha) && (-PI..=PI).contains(&theta));
        assert!((g.eye_dir(alpha, theta) - dir).length() < 1e-9);
        for t in [0.1, 1.0, 7.5, 40.0] {
            let phi = g.phi_at(alpha, t);
            assert!((0.0..PI - alpha + 1e-12).contains(&phi), "{phi}");
            assert!((g.t_at(alpha, phi) - t).abs() < 1e-8 * t.max(1.0), "{t}");
            // The point lies on the light ray of (theta, phi).
            let p = g.eye + dir * t;
            let u = g.light_dir(theta, phi);
            assert!(((p - g.light).normalize() - u).length() < 1e-8);
        }
    }
}

/// After the scan every bit stays set along `alpha` (the shadow is extruded away from the
/// light), and the voxels agree with the VPL's shadow map at their centres except where the
/// map's occluder falls inside the voxel's `alpha` bin.
#[test]
fn extruded_bits_are_monotone_and_match_the_shadow_map() {
    for (name, pose) in [
        (AreaSceneName::Grate, Pose::Ordinary),
        (AreaSceneName::Columns, Pose::EpipoleOnScreen),
        (AreaSceneName::Window, Pose::Grazing),
    ] {
        let (mut g, sm) = grid_for(name, pose, 5);
        g.rectify(&sm);
        let set_before: usize = g
            .bits
            .iter()
            .map(|w| w.iter().map(|x| x.count_ones() as usize).sum::<usize>())
            .sum();
        g.scan();
        let (mut checked, mut mismatched, mut shadowed) = (0usize, 0usize, 0usize);
        let d_phi = PI / f64::from(PHI_BITS);
        for j in 0..g.theta {
            let theta = -PI + (f64::from(j) + 0.5) * g.d_theta();
            for k in 0..PHI_BITS {
                let phi = (f64::from(k) + 0.5) * d_phi;
                for i in 0..g.alpha {
                    let bit = g.bit(i, j, k);
                    if i + 1 < g.alpha {
                        assert!(
                            !bit || g.bit(i + 1, j, k),
                            "{name}/{pose}: bit ({i}, {j}, {k}) not extruded"
                        );
                    }
                    let alpha = g.alpha_centre(i);
                    if alpha + phi >= PI - 1e-9 {
                        continue;
                    }
                    let p = g.eye + g.eye_dir(alpha, theta) * g.t_at(alpha, phi);
                    // Inside the map's footprint and depth range (beyond its far plane the map
                    // says nothing: "shadowed" there is an artefact of the depth compare).
                    if sm.coord(p).is_none_or(|c| c.depth > 1.0) {
                        continue;
                    }
                    checked += 1;
                    let lit = sm.visibility(p) > 0.5;
                    shadowed += usize::from(!lit);
                    if lit == bit {
                        // Disagreement: allowed only next to the occluder's bin.
                        let near = (i > 0 && g.bit(i - 1, j, k) != bit)
                            || (i + 1 < g.alpha && g.bit(i + 1, j, k) != bit);
                        if !near {
                            mismatched += 1;
                        }
                    }
                }
            }
        }
        println!(
            "{name}/{pose}: {set_before} bits rectified, {checked} voxels in the map, {shadowed} shadowed, {mismatched} disagree away from a boundary"
        );
        assert!(
            shadowed > 0 && checked > 1000,
            "{name}/{pose}: nothing checked"
        );
        assert_eq!(
            mismatched, 0,
            "{name}/{pose}: {mismatched} of {checked} voxels disagree with the shadow map"
        );
    }
}

#[test]
fn bad_settings_are_refused_naming_the_knob() {
    let s = area_suite::scene(
        AreaSceneName::Grate,
        Pose::Ordinary,
        MediumPreset::Default,
        8,
        4,
    );
    let bvh = Bvh::build(&s.geometry);
    let gbuf = GBuffer::cast(&s, &bvh);
    for (settings, knob) in [
        (
            IvsvSettings {
                vpls: 0,
                ..IvsvSettings::default()
            },
            "vpls",
        ),
        (
            IvsvSettings {
                alpha: 1,
                ..IvsvSettings::default()
            },
            "alpha",
        ),
        (
            IvsvSettings {
                weights: Weights::Linear(3),
                ..IvsvSettings::default()
            },
            "segments",
        ),
        (
            IvsvSettings {
                weights: Weights::Linear(256),
                ..IvsvSettings::default()
            },
            "segments",
        ),
    ] {
        let err = area_ivsv::render(&s, &gbuf, &bvh, &settings).unwrap_err();
        assert!(matches!(err, IvsvError::Settings(_)));
        assert!(err.to_string().contains(knob), "{err}");
    }
}

/// Poses where the default misses the 5 % bar: (pose, measured rel RMSE, cause).
/// Poses expected to fail the 5 % bar, with the measured value and the cause: none.
/// (`area_grate/epipole_on_screen` was one at 6.17 %: its lamp pixels' rays pass 2 cm from
/// the VPLs and the truth's Gauss-Legendre pieces missed the `1 / d^2` peak; the truth
/// integrates it equiangularly now, `truth::PointPeak`, and the pose measures 0.37 %.)
const EXPECTED_FAILURES: &[(&str, f64, &str)] = &[];

/// Against the `vpl` truth (the same VPLs and shadow maps): rel RMSE <= 5 % on every
/// area-light pose (the paper's range is 3-5 %) but the listed expected failures, which must
/// still fail (a fixed one is taken off the list). Printed beside the default: the paper's
/// uniform average of the bits times the unshadowed integral (`chunks = 1`) on its 128^2
/// grid. CI: 16 VPLs at 48x27; `SCATTER_FULL=1` also 64 VPLs.
#[test]
fn area_ivsv_matches_the_vpl_truth() {
    let counts: &[usize] = if full() { &[16, 64] } else { &[16] };
    let truth_settings = TruthSettings {
        segments: 256,
        ..TruthSettings::default()
    };
    let mut worst = (0.0, String::new());
    let mut failures = Vec::new();
    for &n in counts {
        for (name, pose) in area_suite::all() {
            let s = area_suite::scene(name, pose, MediumPreset::Default, 48, 27);
            let bvh = Bvh::build(&s.geometry);
            let gbuf = GBuffer::cast(&s, &bvh);
            let settings = IvsvSettings {
                vpls: n,
                ..IvsvSettings::default()
            };
            let truth =
                truth::render_vpl(&s, &gbuf, &bvh, n, settings.map_size, &truth_settings).unwrap();
            let paper = IvsvSettings {
                alpha: 128,
                theta: 128,
                weights: Weights::Uniform,
                ..settings
            };
            let mut line = format!("{} N={n}:", s.name);
            let mut rmse = 0.0;
            for (label, config) in [("default", settings), ("paper (uniform, 128^2)", paper)] {
                let img = area_ivsv::render(&s, &gbuf, &bvh, &config).unwrap();
                assert_eq!(metrics::non_finite_count(&img), 0);
                let e = metrics::rel_rmse(&img, &truth).unwrap();
                let l1 = metrics::rel_l1(&img, &truth).unwrap();
                line += &format!(
                    " {label}: rel RMSE {:.2} % / rel L1 {:.2} %",
                    100.0 * e,
                    100.0 * l1
                );
                if config == settings {
                    rmse = e;
                }
            }
            println!("{line}");
            let expected = EXPECTED_FAILURES.iter().find(|f| f.0 == s.name);
            match (rmse <= 0.05, expected) {
                (true, Some(f)) => failures.push(format!(
                    "{}: now meets the bar ({rmse}); take it off EXPECTED_FAILURES ({})",
                    s.name, f.2
                )),
                (false, None) => failures.push(format!("{} N={n}: rel RMSE {rmse} > 5 %", s.name)),
                _ => {}
            }
            if expected.is_none() && rmse > worst.0 {
                worst = (rmse, format!("{} N={n}", s.name));
            }
        }
    }
    println!(
        "worst outside the expected failures: {} at {:.2} %",
        worst.1,
        100.0 * worst.0
    );
    assert!(failures.is_empty(), "{failures:#?}");
}

/// How many VPLs a soft shadow needs: against the `exact` truth (the light's surface), the
/// `vpl` truth and the method with N = 16, 64 and 256 VPLs. The `vpl` truth's error is the
/// VPL discretisation alone and falls with N; the method's falls with it towards the floor
/// its grid and shadow maps set. CI: `area_grate/grazing` at 32x18 with N = 16 and 64;
/// `SCATTER_FULL=1` every area pose at 48x27 with N = 16, 64 and 256.
#[test]
fn error_against_the_exact_truth_falls_with_the_vpl_count() {
    let (poses, (w, h), counts): (_, _, &[usize]) = if full() {
        (area_suite::all(), (48, 27), &[16, 64, 256])
    } else {
        (
            vec![(AreaSceneName::Grate, Pose::Grazing)],
            (32, 18),
            &[16, 64],
        )
    };
    let settings = TruthSettings {
        segments: 256,
        ..TruthSettings::default()
    };
    let mut failures = Vec::new();
    for (name, pose) in poses {
        let s = area_suite::scene(name, pose, MediumPreset::Default, w, h);
        let bvh = Bvh::build(&s.geometry);
        let gbuf = GBuffer::cast(&s, &bvh);
        let exact = truth::render(&s, &gbuf, &Visibility::Exact(&bvh), &settings, &|| ());
        let mut line = format!("{}:", s.name);
        let mut prev: Option<(f64, f64)> = None;
        for &n in counts {
            let ivsv = IvsvSettings {
                vpls: n,
                ..IvsvSettings::default()
            };
            let vpl = truth::render_vpl(&s, &gbuf, &bvh, n, ivsv.map_size, &settings).unwrap();
            let img = area_ivsv::render(&s, &gbuf, &bvh, &ivsv).unwrap();
            let (ev, em) = (
                metrics::rel_rmse(&vpl, &exact).unwrap(),
                metrics::rel_rmse(&img, &exact).unwrap(),
            );
            line += &format!(
                " N={n}: vpl {:.2} % / area_ivsv {:.2} %",
                100.0 * ev,
                100.0 * em
            );
            if let Some((pv, _)) = prev
                && n == 64
                && ev >= pv
            {
                failures.push(format!(
                    "{}: the vpl truth's error does not fall from 16 to 64 VPLs ({pv} -> {ev})",
                    s.name
                ));
            }
            prev = Some((ev, em));
        }
        println!("{line}");
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Where area lights stress a method (issue 17): a light a millimetre across (all VPLs in
/// one point: the spot's `shadow_map` truth of its point limit), a huge light (a 6 m x 6 m
/// panel over the 4 m grate: no umbra left under it), and the camera inside the penumbra
/// (under the grate, seeing part of the panel between the bars). Against the `vpl` truth
/// (the point limit's shadow-map truth for the tiny light): rel RMSE <= 5 % and no NaN/Inf.
#[test]
fn stress_cases_stay_within_the_bar() {
    let settings = TruthSettings {
        segments: 256,
        ..TruthSettings::default()
    };
    let ivsv = IvsvSettings {
        vpls: 16,
        ..IvsvSettings::default()
    };
    let mut failures = Vec::new();
    let cases = area_suite::stress_scenes(48, 27);
    let inside = cases
        .iter()
        .find(|s| s.name.ends_with("/eye_in_penumbra"))
        .expect("the penumbra case");
    {
        // Premise: the eye sees some of the VPLs and not others.
        let bvh = Bvh::build(&inside.geometry);
        let eye = inside.camera.position;
        let vpls = inside.light.area().unwrap().vpls(ivsv.vpls);
        let seen = vpls
            .iter()
            .filter(|l| {
                let Light::Spot { position, .. } = l else {
                    return false;
                };
                let d = *position - eye;
                !bvh.occluded(
                    &scatter_reference::geometry::Ray::new(eye, d.normalize()),
                    1e-6,
                    d.length() - 1e-3,
                )
            })
            .count();
        assert!(
            0 < seen && seen < vpls.len(),
            "the eye sees {seen} of {} VPLs: not in the penumbra",
            vpls.len()
        );
    }
    for s in cases {
        s.validate().unwrap();
        let bvh = Bvh::build(&s.geometry);
        let gbuf = GBuffer::cast(&s, &bvh);
        let img = area_ivsv::render(&s, &gbuf, &bvh, &ivsv).unwrap();
        let truth =
            area_suite::stress_truth(&s, &gbuf, &bvh, ivsv.vpls, ivsv.map_size, &settings).unwrap();
        let nan = metrics::non_finite_count(&img);
        let e = metrics::rel_rmse(&img, &truth).unwrap();
        println!(
            "{}: rel RMSE {:.2} % / rel L1 {:.2} %, {nan} NaN/Inf",
            s.name,
            100.0 * e,
            100.0 * metrics::rel_l1(&img, &truth).unwrap()
        );
        if nan > 0 || e > 0.05 {
            failures.push(format!("{}: rel RMSE {e}, {nan} NaN/Inf", s.name));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// How many knots of the integrand in `phi` the gather needs: rel RMSE against the `vpl`
/// truth (16 VPLs, 48x27) for the paper's uniform weights and 1, 2, 4, 8 and 128 linear
/// segments, every area pose. A measurement, not a bar (the bar is
/// `area_ivsv_matches_the_vpl_truth`): `cargo test --release -p scatter-reference --test
/// area_ivsv -- --ignored --nocapture weights`.
#[test]
#[ignore = "a measurement (a table), run on demand"]
fn weights_sweep() {
    let truth_settings = TruthSettings {
        segments: 256,
        ..TruthSettings::default()
    };
    let modes = [
        Weights::Uniform,
        Weights::Linear(1),
        Weights::Linear(2),
        Weights::Linear(4),
        Weights::Linear(8),
        Weights::Linear(16),
        Weights::Linear(128),
    ];
    println!("pose | {modes:?}");
    for (name, pose) in area_suite::all() {
        let s = area_suite::scene(name, pose, MediumPreset::Default, 48, 27);
        let bvh = Bvh::build(&s.geometry);
        let gbuf = GBuffer::cast(&s, &bvh);
        let base = IvsvSettings {
            vpls: 16,
            ..IvsvSettings::default()
        };
        let truth = truth::render_vpl(&s, &gbuf, &bvh, 16, base.map_size, &truth_settings).unwrap();
        let mut line = format!("{} |", s.name);
        for weights in modes {
            let img =
                area_ivsv::render(&s, &gbuf, &bvh, &IvsvSettings { weights, ..base }).unwrap();
            line += &format!(
                " {:.2} / {:.2} % |",
                100.0 * metrics::rel_rmse(&img, &truth).unwrap(),
                100.0 * metrics::rel_l1(&img, &truth).unwrap()
            );
        }
        println!("{line}");
    }
}

/// The kernels' CPU mirrors (f32, `reference/src/kernels/ivsv_*.rs`) implement the f64
/// method: on every area pose (16 VPLs, 48x27, the default grid and segments) their image is
/// within 1e-4 rel L1 of [`area_ivsv::render`]'s (measured 2-3e-7: f32 rounding), and within the 5 % rel RMSE bar of the `vpl`
/// truth but for the method's listed expected failure.
#[test]
fn kernel_mirrors_match_the_f64_method() {
    use scatter_reference::kernels::{ivsv_inputs, run_area_ivsv};
    use scatter_shaderlib::area_ivsv::AreaIvsvVariant;
    let truth_settings = TruthSettings {
        segments: 256,
        ..TruthSettings::default()
    };
    let variant = AreaIvsvVariant {
        vpls: 16,
        ..AreaIvsvVariant::default()
    };
    let mut failures = Vec::new();
    for (name, pose) in area_suite::all() {
        let s = area_suite::scene(name, pose, MediumPreset::Default, 48, 27);
        let bvh = Bvh::build(&s.geometry);
        let gbuf = GBuffer::cast(&s, &bvh);
        let settings = IvsvSettings {
            vpls: 16,
            ..IvsvSettings::default()
        };
        let method = area_ivsv::render(&s, &gbuf, &bvh, &settings).unwrap();
        let inputs = ivsv_inputs(&s, &gbuf, &bvh, &variant, settings.map_size).unwrap();
        let run = run_area_ivsv(&variant, &inputs);
        let mirror = scatter_reference::image::Image::from_pixels(48, 27, run.output.clone());
        assert_eq!(metrics::non_finite_count(&mirror), 0);
        let truth =
            truth::render_vpl(&s, &gbuf, &bvh, 16, settings.map_size, &truth_settings).unwrap();
        let (to_method, rmse) = (
            metrics::rel_l1(&mirror, &method).unwrap(),
            metrics::rel_rmse(&mirror, &truth).unwrap(),
        );
        println!(
            "{}: mirror vs f64 method rel L1 {:.2e}, vs vpl truth rel RMSE {:.2} %",
            s.name,
            to_method,
            100.0 * rmse
        );
        if to_method > 1e-4 {
            failures.push(format!("{}: mirror vs method {to_method}", s.name));
        }
        if rmse > 0.05 && !EXPECTED_FAILURES.iter().any(|f| f.0 == s.name) {
            failures.push(format!("{}: mirror vs truth {rmse}", s.name));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Where the interleaved gather's error lies: the mirrors with `interleave` 2 against 1 on
/// two poses at 256x144 (`SCATTER_INTERLEAVE_WIDTH` sets the width, 16:9), the error split between pixels next to a depth break (a 4-neighbour
/// whose view depth differs by more than 5 %) and the rest. A measurement:
/// `cargo test --release -p scatter-reference --test area_ivsv -- --ignored --nocapture interleave`.
#[test]
#[ignore = "a measurement, run on demand"]
fn interleave_error_split() {
    use scatter_reference::kernels::{ivsv_inputs, run_area_ivsv};
    use scatter_shaderlib::area_ivsv::AreaIvsvVariant;
    for (name, pose) in [
        (AreaSceneName::Columns, Pose::Ordinary),
        (AreaSceneName::Grate, Pose::Ordinary),
    ] {
        // `SCATTER_INTERLEAVE_WIDTH=1280` measures at 1280x720.
        let w: u32 = std::env::var("SCATTER_INTERLEAVE_WIDTH")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(256);
        let h = w * 9 / 16;
        let s = area_suite::scene(name, pose, MediumPreset::Default, w, h);
        let bvh = Bvh::build(&s.geometry);
        let gbuf = GBuffer::cast(&s, &bvh);
        let run = |interleave| {
            let v = AreaIvsvVariant {
                vpls: 16,
                interleave,
                ..AreaIvsvVariant::default()
            };
            run_area_ivsv(&v, &ivsv_inputs(&s, &gbuf, &bvh, &v, 128).unwrap()).output
        };
        let (a, b) = (run(1), run(2));
        let d = &gbuf.view_depth;
        let (mut edge, mut rest, mut total) = (0.0f64, 0.0f64, 0.0f64);
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let here = d[i];
                let mut brk = false;
                for (dx, dy) in [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)] {
                    let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                    if nx >= 0 && ny >= 0 && nx < w as i32 && ny < h as i32 {
                        let o = d[(ny as u32 * w + nx as u32) as usize];
                        brk |= (o - here).abs() > 0.05 * o.min(here);
                    }
                }
                let e: f64 = (0..3).map(|k| f64::from((a[i][k] - b[i][k]).abs())).sum();
                total += (0..3).map(|k| f64::from(a[i][k])).sum::<f64>();
                if brk {
                    edge += e;
                } else {
                    rest += e;
                }
            }
        }
        println!(
            "{}: interleave 2 vs 1 rel L1 {:.2} % at depth breaks, {:.2} % elsewhere",
            s.name,
            100.0 * edge / total,
            100.0 * rest / total
        );
    }
}
