//! The minmax family (Chen et al. 2011) on the CPU mirror: the hierarchical march through
//! the 1D min-max trees equals a brute-force march over every texel of the same rectified
//! map (1e-4 relative per pixel, before the rgba16float rounding) on every suite scene, at
//! the `ordinary` and `epipole_on_screen` poses; the error against the `shadow_map` ground
//! truth is reported (finite, not asserted otherwise: minmax shares the rectified map's
//! resampling error with the prefiltered family).

use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::kernels::run_minmax;
use scatter_reference::metrics;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::prefiltered::{FrameSettings, LightKind};

const SCREEN: (u32, u32) = (80, 45);
const RECTIFIED: [u32; 2] = [256, 256];
const SHADOW_MAP: u32 = 512;
const REL_TOL: f32 = 1e-4;
/// Most tree nodes visited per texel a brute-force march visits (see the module docs).
const MAX_VISIT_RATIO: f64 = 0.5;

fn light_of(name: SceneName) -> LightKind {
    if name == SceneName::SpotGrate {
        LightKind::Spot
    } else {
        LightKind::Directional
    }
}

#[test]
fn hierarchy_equals_brute_force_and_skips_on_every_scene() {
    let mut failures = Vec::new();
    let start = std::time::Instant::now();
    for &name in SceneName::ALL {
        for pose in [Pose::Ordinary, Pose::EpipoleOnScreen] {
            let scene = suite::scene(name, pose, MediumPreset::Default, SCREEN.0, SCREEN.1);
            let bvh = Bvh::build(&scene.geometry);
            let gbuf = GBuffer::cast(&scene, &bvh);
            let sm = ShadowMap::build(&scene, &bvh, SHADOW_MAP).expect("shadow map");
            let variant = MinmaxVariant {
                light: light_of(name),
                ..MinmaxVariant::default()
            };
            let settings = FrameSettings::for_screen(SCREEN.0, SCREEN.1);
            let run = run_minmax(&variant, RECTIFIED, &gbuf, &scene, &sm, &settings)
                .unwrap_or_else(|e| panic!("minmax::{variant}::{name}::{pose}: {e}"));
            let max = run
                .brute
                .exact
                .iter()
                .flat_map(|c| c[..3].iter().copied())
                .fold(0.0f32, f32::max);
            let mut worst_rel = 0.0f32;
            let mut over = 0;
            for (a, b) in run.march.exact.iter().zip(&run.brute.exact) {
                for k in 0..3 {
                    let diff = (a[k] - b[k]).abs();
                    let diff = if diff.is_nan() { f32::INFINITY } else { diff };
                    // Relative to the pixel, with a floor of 1e-6 of the image maximum.
                    let scale = b[k].abs().max(1e-6 * max);
                    let rel = if scale > 0.0 { diff / scale } else { diff };
                    worst_rel = worst_rel.max(rel);
                    if rel > REL_TOL {
                        over += 1;
                    }
                }
            }
            let rows: Vec<(u32, u32)> = run
                .march
                .visits
                .iter()
                .zip(&run.brute.visits)
                .filter(|(_, b)| **b > 0)
                .map(|(a, b)| (*a, *b))
                .collect();
            let (nodes, texels) = rows.iter().fold((0u64, 0u64), |(a, b), (x, y)| {
                (a + u64::from(*x), b + u64::from(*y))
            });
            let marched = run.march.visits.iter().filter(|v| **v == 0).count();
            let ratio = nodes as f64 / texels.max(1) as f64;
            let truth = truth::render(
                &scene,
                &gbuf,
                &Visibility::ShadowMap(&sm),
                &TruthSettings::default(),
                &|| (),
            );
            let report = metrics::compare(&run.output, &truth).expect("same size");
            let trial = format!("minmax::{variant}::{name}::{pose}");
            println!(
                "{trial}: hierarchy vs brute force max rel diff {worst_rel:.2e} ({over} over \
                 {REL_TOL:e}); nodes/texels visited {nodes}/{texels} = {:.3} over {} pixels \
                 ({marched} marched or empty); rel L1 vs shadow_map truth {:.3} %",
                ratio,
                rows.len(),
                100.0 * report.rel_l1
            );
            if texels == 0 || ratio > MAX_VISIT_RATIO {
                failures.push(format!(
                    "{trial}: the hierarchy visited {nodes} nodes for {texels} texels (ratio \
                     {ratio:.3} > {MAX_VISIT_RATIO}): it does not skip"
                ));
            }
            if over > 0 || report.non_finite > 0 || max.is_nan() || max <= 0.0 {
                failures.push(format!(
                    "{trial}: {over} values over tolerance (worst {worst_rel:e}), {} non-finite, max {max}",
                    report.non_finite
                ));
            }
        }
    }
    println!("minmax truth: {:.1} s", start.elapsed().as_secs_f64());
    assert!(failures.is_empty(), "{failures:#?}");
}
