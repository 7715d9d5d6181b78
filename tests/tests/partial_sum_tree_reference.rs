//! The partial-sum-tree method's CPU reference (`scatter_reference::partial_sum_tree`, issue
//! 15) on every suite pose, sun and spot: against the brute-force walk over the same rectified
//! rows (`minmax`'s reference: the same sum with exact per-texel weights, so the difference
//! is the rank-r integrand alone) and against the `shadow_map` truth. CPU only.
//!
//! `cargo test -p scatter-conformance --test partial_sum_tree_reference -- --nocapture` prints the table.

use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::kernels::common_sampling::{EpipolarCamera, run_sampled};
use scatter_reference::kernels::minmax_traverse::TraverseInputs;
use scatter_reference::kernels::texture::Tex;
use scatter_reference::kernels::{MinmaxRun, run_minmax};
use scatter_reference::metrics;
use scatter_reference::partial_sum_tree::{Separable, partial_sum_tree, spot_kernel};
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::prefiltered::FrameSettings;
use scatter_shaderlib::sampling::SamplingKnobs;

const SCREEN: (u32, u32) = (96, 54);
const RECTIFIED: [u32; 2] = [1024, 512];
const SHADOW_MAP: u32 = 512;
/// The paper's rank.
const RANK: usize = 4;
/// The bars against the `shadow_map` truth, away from the marched epipole ring (sun;
/// spot below).
/// Met at 1024 columns x 512 slices; at 256 x 256 window and foliage/epipole_on_screen miss
/// it (2.3-5.3 %) exactly as the brute-force walk (minmax) does: the map's resolution.
const SUN_BAR: f64 = 0.02;
const SPOT_BAR: f64 = 0.03;
/// Most the rank-4 sum may differ from the brute-force walk over the same rows (rel L1 of
/// the image): the paper's 1-2 % reconstruction error of the integrand, at its lower end.
const RANK_BAR: f64 = 0.01;

/// Epipolar sampling at this screen size, as the random-pose suite runs it: 64 slices x 64
/// samples, step 8.
fn epipolar() -> SamplingKnobs {
    SamplingKnobs {
        slice_samples: 64,
        step: 8,
        ..SamplingKnobs::epipolar(64)
    }
}

/// The depth buffer and the shadow map as the mirrors read them.
fn textures(gbuf: &GBuffer, sm: &ShadowMap) -> (Tex, Tex) {
    let depth = Tex {
        width: gbuf.width,
        height: gbuf.height,
        data: gbuf.view_depth.clone(),
    };
    let smt = Tex {
        width: sm.size,
        height: sm.size,
        data: sm.depth.clone(),
    };
    (depth, smt)
}

/// `minmax_traverse`'s inputs of a CPU minmax run (the frame and rows the method shares).
fn inputs<'a>(run: &'a MinmaxRun, depth: &'a Tex, sm: &'a Tex) -> TraverseInputs<'a> {
    TraverseInputs {
        frame: &run.frame.uniforms,
        slices: &run.frame.slices,
        depth,
        shadow_map: sm,
        tree: &run.tree,
        cookie: None,
    }
}

/// Rel L1 of `a` against `b` over the pixels `keep` selects (first three channels).
fn rel_l1(a: &[[f32; 4]], b: &[[f32; 4]], keep: &dyn Fn(usize) -> bool) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        if !keep(i) {
            continue;
        }
        for k in 0..3 {
            num += f64::from((x[k] - y[k]).abs());
            den += f64::from(y[k].abs());
        }
    }
    if den > 0.0 { num / den } else { num }
}

#[test]
fn rank4_sweep_matches_the_brute_force_walk_and_the_truth_on_every_pose() {
    let mut failures = Vec::new();
    let start = std::time::Instant::now();
    println!(
        "| scene/pose | kernel rank-{RANK} max error | vs brute-force walk | ranks 1 / 2 / 8 vs brute-force walk | vs truth (ring excluded) | vs truth | epipolar 64 x 64 vs truth | minmax vs truth | updates / queries |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for &name in SceneName::ALL {
        let spot = name == SceneName::SpotGrate;
        let bar = if spot { SPOT_BAR } else { SUN_BAR };
        for &pose in Pose::ALL {
            let scene = suite::scene(name, pose, MediumPreset::Default, SCREEN.0, SCREEN.1);
            let bvh = Bvh::build(&scene.geometry);
            let gbuf = GBuffer::cast(&scene, &bvh);
            let sm = ShadowMap::build(&scene, &bvh, SHADOW_MAP).expect("shadow map");
            let settings = FrameSettings::for_screen(SCREEN.0, SCREEN.1);
            let variant = MinmaxVariant {
                light: if spot {
                    scatter_shaderlib::prefiltered::LightKind::Spot
                } else {
                    scatter_shaderlib::prefiltered::LightKind::Directional
                },
                ..MinmaxVariant::default()
            };
            let run = run_minmax(&variant, RECTIFIED, &gbuf, &scene, &sm, &settings)
                .unwrap_or_else(|e| panic!("{name}/{pose}: {e}"));
            let (depth, smt) = textures(&gbuf, &sm);
            let inputs = inputs(&run, &depth, &smt);
            let pst = partial_sum_tree(&inputs, &run.rectified, spot, RANK)
                .unwrap_or_else(|e| panic!("{name}/{pose}: {e}"));
            // The integrand's own error: the rank-4 kernel against exp(-sigma v / sin theta)
            // on a grid finer than the SVD's, off its nodes.
            let kernel_err = kernel_error(&pst.separable, &run.frame.uniforms, spot);
            let marched: Vec<bool> = run.brute.visits.iter().map(|&v| v == 0).collect();
            let all = |_: usize| true;
            let away = |i: usize| !marched[i];
            let vs_brute = rel_l1(&pst.exact, &run.brute.exact, &away);
            let other_ranks: Vec<String> = [1, 2, 8]
                .iter()
                .map(|&rank| {
                    let other = partial_sum_tree(&inputs, &run.rectified, spot, rank)
                        .unwrap_or_else(|e| panic!("{name}/{pose}: {e}"));
                    format!(
                        "{:.3}",
                        100.0 * rel_l1(&other.exact, &run.brute.exact, &away)
                    )
                })
                .collect();
            let truth = truth::render(
                &scene,
                &gbuf,
                &Visibility::ShadowMap(&sm),
                &TruthSettings::default(),
                &|| (),
            );
            let t4: Vec<[f32; 4]> = truth.data.iter().map(|c| [c[0], c[1], c[2], 1.0]).collect();
            let vs_truth_away = rel_l1(&pst.exact, &t4, &away);
            let vs_truth = rel_l1(&pst.exact, &t4, &all);
            let image = Image::from_pixels(
                gbuf.width,
                gbuf.height,
                pst.exact.iter().map(|c| [c[0], c[1], c[2]]).collect(),
            );
            let report = metrics::compare(&image, &truth).expect("same size");
            // The configuration the kernels are planned for (docs/partial-sum-tree.md): the
            // sweep's results at epipolar samples only, gathered back by the sampling stage's
            // unwarp (a sample's value is its pixel's: the sweep evaluates any pixel's ray).
            let sampled = run_sampled(
                &epipolar(),
                [gbuf.width, gbuf.height],
                &depth,
                &EpipolarCamera::of_frame(&run.frame.uniforms),
                &|x, y| {
                    let c = pst.exact[(y * gbuf.width + x) as usize];
                    [c[0], c[1], c[2]]
                },
            );
            let sampled_image = Image::from_pixels(
                gbuf.width,
                gbuf.height,
                sampled
                    .output
                    .data
                    .iter()
                    .map(|c| [c[0], c[1], c[2]])
                    .collect(),
            );
            let sampled_report = metrics::compare(&sampled_image, &truth).expect("same size");
            let minmax = metrics::compare(&run.output, &truth).expect("same size");
            println!(
                "| {name}/{pose} | {:.2e} | {:.3} % | {} % | {:.3} % | {:.3} % | {:.3} % | {:.3} % | {} / {} |",
                kernel_err,
                100.0 * vs_brute,
                other_ranks.join(" / "),
                100.0 * vs_truth_away,
                100.0 * vs_truth,
                100.0 * sampled_report.rel_l1,
                100.0 * minmax.rel_l1,
                pst.updates,
                pst.queries
            );
            if report.non_finite > 0 || sampled_report.non_finite > 0 {
                failures.push(format!(
                    "{name}/{pose}: {} / {} non-finite pixels (per pixel / epipolar)",
                    report.non_finite, sampled_report.non_finite
                ));
            }
            if vs_brute.is_nan() || vs_brute > RANK_BAR {
                failures.push(format!(
                    "{name}/{pose}: rank-{RANK} sweep {:.3} % from the brute-force walk (bar {:.1} %)",
                    100.0 * vs_brute,
                    100.0 * RANK_BAR
                ));
            }
            if vs_truth_away.is_nan() || vs_truth_away > bar {
                failures.push(format!(
                    "{name}/{pose}: {:.3} % from the shadow_map truth away from the ring (bar {:.1} %)",
                    100.0 * vs_truth_away,
                    100.0 * bar
                ));
            }
        }
    }
    println!("partial_sum_tree: {:.1} s", start.elapsed().as_secs_f64());
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Largest error of the separable kernel against the exact one at 4x the SVD grid's
/// resolution per axis, relative to the kernel's largest value there (the sun's lies in
/// (0, 1]; a spot's carries the phase function).
fn kernel_error(
    sep: &Separable,
    f: &scatter_shaderlib::prefiltered::FrameUniforms,
    spot: bool,
) -> f64 {
    let n = 4 * scatter_reference::partial_sum_tree::GRID;
    let (mut worst, mut top) = (0.0f64, 0.0f64);
    for i in 0..n {
        let v = sep.v_max * i as f32 / (n - 1) as f32;
        for j in 0..n {
            let t = sep.theta_lo + (sep.theta_hi - sep.theta_lo) * j as f32 / (n - 1) as f32;
            let exact = if spot {
                spot_kernel(
                    f64::from(f.medium[0]),
                    f64::from(f.medium[2]),
                    f64::from(f.axis[3]),
                    f64::from(v),
                    f64::from(t),
                )
            } else {
                (-f64::from(f.medium[0]) * f64::from(v) / f64::from(t).sin()).exp()
            };
            top = top.max(exact.abs());
            worst = worst.max((f64::from(sep.eval(v, t)) - exact).abs());
        }
    }
    worst / top.max(1e-300)
}

#[test]
fn ranks_outside_the_range_are_refused_with_a_reason() {
    let scene = suite::scene(
        SceneName::Sphere,
        Pose::Ordinary,
        MediumPreset::Default,
        16,
        9,
    );
    let bvh = Bvh::build(&scene.geometry);
    let gbuf = GBuffer::cast(&scene, &bvh);
    let sm = ShadowMap::build(&scene, &bvh, 64).expect("shadow map");
    let variant = MinmaxVariant::default();
    let run = run_minmax(
        &variant,
        [64, 64],
        &gbuf,
        &scene,
        &sm,
        &FrameSettings::for_screen(16, 9),
    )
    .expect("minmax");
    let (depth, smt) = textures(&gbuf, &sm);
    let inputs = inputs(&run, &depth, &smt);
    for rank in [0, scatter_reference::partial_sum_tree::MAX_RANK + 1] {
        let err = partial_sum_tree(&inputs, &run.rectified, false, rank).unwrap_err();
        assert!(err.to_string().contains("rank must be in 1..="), "{err}");
    }
}
