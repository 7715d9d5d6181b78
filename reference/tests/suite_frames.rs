//! Every scene, pose and medium preset of the suite is accepted by the frame set-up of every
//! family (`prepare_frame`, `prepare_raymarch`, `prepare_minmax`): the set-up's input checks
//! (orthonormal bases, ranges, a valid variant) reject hostile numbers, not the scenes the
//! conformance suite and the bench run.

use scatter_reference::buffers::ShadowMap;
use scatter_reference::bvh::Bvh;
use scatter_reference::suite::{MediumPreset, Pose, SceneName, scene};
use scatter_shaderlib::minmax::{MinmaxVariant, prepare_minmax};
use scatter_shaderlib::prefiltered::{
    FrameSettings, PrefilteredVariant, Rectification, Resolutions, prepare_frame,
};
use scatter_shaderlib::raymarch::{RaymarchVariant, prepare_raymarch};

#[test]
fn every_suite_frame_is_accepted() {
    let (w, h) = (64, 36);
    let res = Resolutions {
        screen: [w, h],
        rectified: [64, 32],
    };
    let mut frames = 0;
    for &name in SceneName::ALL {
        for &pose in Pose::ALL {
            for &preset in MediumPreset::ALL {
                let sc = scene(name, pose, preset, w, h);
                let bvh = Bvh::build(&sc.geometry);
                let sm = ShadowMap::build(&sc, &bvh, 16).unwrap_or_else(|e| panic!("{e}"));
                let light = sc.light_desc().kind();
                let trial = format!("{name:?}/{pose:?}/{preset:?}");
                let (camera, light_desc, medium, shadow) = (
                    sc.camera_desc(),
                    sc.light_desc(),
                    sc.medium_desc(),
                    sm.desc(),
                );
                let settings = FrameSettings::for_screen(w, h);
                for rectification in [Rectification::Epipolar, Rectification::Projective] {
                    let v = PrefilteredVariant {
                        light,
                        rectification,
                        ..PrefilteredVariant::default()
                    };
                    prepare_frame(&v, &res, &camera, &light_desc, &medium, &shadow, &settings)
                        .unwrap_or_else(|e| panic!("{trial}: prefiltered {rectification}: {e}"));
                }
                let r = RaymarchVariant {
                    light,
                    ..RaymarchVariant::default()
                };
                prepare_raymarch(&r, [w, h], &camera, &light_desc, &medium, &shadow)
                    .unwrap_or_else(|e| panic!("{trial}: raymarch: {e}"));
                let m = MinmaxVariant {
                    light,
                    ..MinmaxVariant::default()
                };
                prepare_minmax(&m, &res, &camera, &light_desc, &medium, &shadow, &settings)
                    .unwrap_or_else(|e| panic!("{trial}: minmax: {e}"));
                frames += 1;
            }
        }
    }
    eprintln!("suite_frames: {frames} scene/pose/medium frames accepted by every family");
}
