//! The engine example's frame (`scatter_examples::engine`, issue 18 part 1) on three suite
//! poses at 160x90, each with the prefiltered family (one of them projective: its
//! rectified map rasterised), one with raymarch, and `spot_grate` with the `stained_glass`
//! cookie (prefiltered; the shading carries the cookie too):
//! - the 8-bit composite is the tone map of shaded + shafts read back (within one level of
//!   the 255, from the GPU's f32 to the CPU's), at the exposure the GPU's histogram found,
//!   which is the CPU's 99.5th percentile to within its bin;
//! - nothing is NaN or Inf;
//! - the shaded scene matches `truth::surface_radiance` (the same terms with ray-cast
//!   visibility and normals) to a bar, the shafts match the `shadow_map` truth to the
//!   family's accuracy bar;
//! - the PNGs exist, decode, have the frame's size, and `engine.png` holds the composite.
//!
//! `cargo test -p scatter-examples --test engine -- --nocapture` prints the figures.

use scatter_conformance::gpu;
use scatter_examples::engine::{Engine, EngineSettings, OUTPUTS, tonemap, write_outputs};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::cookie::Cookie;
use scatter_reference::image::Image;
use scatter_reference::metrics;
use scatter_reference::scene::Light;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_runtime::shaderlib::family::FamilyVariant;
use scatter_runtime::shaderlib::prefiltered::{LightKind, PrefilteredVariant, Rectification};
use scatter_runtime::shaderlib::raymarch::RaymarchVariant;

const SCREEN: [u32; 2] = [160, 90];
const SHADOW_MAP: u32 = 1024;
const RECTIFIED: [u32; 2] = [512, 512];

/// A folder under the system's temporary one, removed when dropped.
struct TempDir(std::path::PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        let dir =
            std::env::temp_dir().join(format!("scatter-engine-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temporary folder");
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn decode_png(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("frame");
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Bar on the shaded scene against `truth::surface_radiance` (rel L1): they differ where the
/// map's nearest texel and bias shadow a point the exact ray does not (or the reverse), at
/// silhouettes, and by the tessellation.
const SHADED_BAR: f64 = 0.03;

#[test]
fn the_engine_composites_shafts_over_the_shaded_scene() {
    let Some(ctx) = gpu() else { return };
    let engine = Engine::new(ctx);
    let dir = TempDir::new("composite");
    // `None`: raymarch; otherwise prefiltered with that rectification; the last flag puts
    // the `stained_glass` cookie (64^2) on the spot (the shafts and the shading carry it).
    let cases = [
        (
            SceneName::Sphere,
            Pose::Ordinary,
            Some(Rectification::Epipolar),
            false,
        ),
        (
            SceneName::Columns,
            Pose::Ordinary,
            Some(Rectification::Projective),
            false,
        ),
        (
            SceneName::SpotGrate,
            Pose::Ordinary,
            Some(Rectification::Epipolar),
            false,
        ),
        (SceneName::SpotGrate, Pose::Ordinary, None, false),
        (
            SceneName::SpotGrate,
            Pose::Ordinary,
            Some(Rectification::Epipolar),
            true,
        ),
    ];
    let mut failures = Vec::new();
    for (name, pose, rectification, tinted) in cases {
        let mut scene = suite::scene(name, pose, MediumPreset::Default, SCREEN[0], SCREEN[1]);
        if let (true, Light::Spot { cookie, .. }) = (tinted, &mut scene.light) {
            *cookie = Some(Cookie::pattern("stained_glass", 64).expect("a built-in pattern"));
        }
        let light = scene.light.kind();
        let variant = match rectification {
            Some(rectification) => FamilyVariant::Prefiltered(PrefilteredVariant {
                light,
                rectification,
                ..PrefilteredVariant::default()
            }),
            None => FamilyVariant::Raymarch(RaymarchVariant {
                light,
                ..RaymarchVariant::default()
            }),
        };
        let variant = if tinted {
            variant
                .with_cookie(true)
                .expect("every family reads a cookie")
        } else {
            variant
        };
        let id = format!("{name}/{pose} {}", variant.trial_name());
        let bvh = Bvh::build(&scene.geometry);
        let frame = engine
            .render(
                ctx,
                &scene,
                &bvh,
                &EngineSettings {
                    variant,
                    shadow_map: SHADOW_MAP,
                    rectified: RECTIFIED,
                    exposure: None,
                },
            )
            .unwrap_or_else(|e| panic!("{id}: {e}"));
        if let FamilyVariant::Prefiltered(v) = variant
            && v.rectification == Rectification::Projective
        {
            assert!(
                frame.rectified.is_some(),
                "{id}: a projective frame rasterises its rectified map"
            );
        }
        let (w, h) = (SCREEN[0] as usize, SCREEN[1] as usize);
        assert_eq!(frame.image.len(), w * h * 3, "{id}");
        let shaded = frame.read_shaded(ctx).unwrap_or_else(|e| panic!("{e}"));
        let shafts = frame.read_shafts(ctx).unwrap_or_else(|e| panic!("{e}"));
        let rgb = |c: &[f32; 4]| [c[0], c[1], c[2]];
        let bad = shaded
            .iter()
            .chain(&shafts)
            .filter(|c| rgb(c).iter().any(|x| !x.is_finite()))
            .count();
        assert_eq!(bad, 0, "{id}: NaN/Inf in shaded or shafts");

        // The composite is the tone map of shaded + shafts at the GPU's exposure.
        let exposure = frame.exposure(ctx).unwrap_or_else(|e| panic!("{e}"));
        let sum = Image::from_pixels(
            SCREEN[0],
            SCREEN[1],
            shaded
                .iter()
                .zip(&shafts)
                .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
                .collect(),
        );
        let cpu_exposure = sum.auto_exposure();
        // One histogram bin is 1/8 stop; the bin's middle is within 1/16 stop of any of it.
        let ratio = f64::from(exposure / cpu_exposure);
        if (ratio.log2()).abs() > 1.0 / 16.0 + 1e-3 {
            failures.push(format!(
                "{id}: exposure {exposure} on the GPU, {cpu_exposure} on the CPU"
            ));
        }
        let mut worst = 0u8;
        let mut differ = 0usize;
        for (i, c) in sum.data.iter().enumerate() {
            let cpu = tonemap(*c, exposure);
            for (k, level) in cpu.iter().enumerate() {
                let d = level.abs_diff(frame.image[3 * i + k]);
                worst = worst.max(d);
                differ += usize::from(d > 0);
            }
        }
        if worst > 1 {
            failures.push(format!(
                "{id}: the composite differs from tonemap(shaded + shafts) by {worst} levels"
            ));
        }

        // The shaded scene against the reference's surface radiance, the shafts against
        // the shadow_map truth.
        let gbuf = GBuffer::cast(&scene, &bvh);
        let reference_shaded = truth::surface_radiance(&scene, &gbuf, &bvh);
        let shaded_image =
            Image::from_pixels(SCREEN[0], SCREEN[1], shaded.iter().map(rgb).collect());
        let shaded_err = metrics::compare(&shaded_image, &reference_shaded)
            .expect("same size")
            .rel_l1;
        if shaded_err > SHADED_BAR {
            failures.push(format!(
                "{id}: shaded scene {:.2} % from truth::surface_radiance (bar {:.0} %)",
                100.0 * shaded_err,
                100.0 * SHADED_BAR
            ));
        }
        let sm = ShadowMap::build(&scene, &bvh, SHADOW_MAP).expect("suite shadow map");
        let truth = truth::render(
            &scene,
            &gbuf,
            &Visibility::ShadowMap(&sm),
            &TruthSettings::default(),
            &|| (),
        );
        let shafts_image =
            Image::from_pixels(SCREEN[0], SCREEN[1], shafts.iter().map(rgb).collect());
        let shafts_err = metrics::compare(&shafts_image, &truth)
            .expect("same size")
            .rel_l1;
        // The family's accuracy bars (tests/tests/prefiltered_truth.rs, raymarch.rs).
        let bar = if scene.light.kind() == LightKind::Spot {
            0.05
        } else {
            0.03
        };
        if shafts_err > bar {
            failures.push(format!(
                "{id}: shafts {:.2} % from the shadow_map truth (bar {:.0} %)",
                100.0 * shafts_err,
                100.0 * bar
            ));
        }

        // The PNGs.
        let out = dir.0.join(format!("{name}-{}", variant.family()));
        std::fs::create_dir_all(&out).expect("folder");
        let written = write_outputs(ctx, &frame, &scene, &out).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(written.len(), OUTPUTS.len());
        for path in &written {
            let (pw, ph, pixels) = decode_png(path);
            assert_eq!([pw, ph], SCREEN, "{}", path.display());
            if path.ends_with("engine.png") {
                assert!(
                    pixels == frame.image,
                    "{id}: engine.png holds the composite"
                );
            }
        }
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort_unstable();
        assert_eq!(
            names,
            ["depth.png", "engine.png", "shafts.png"],
            "{id}: no temporary file left"
        );
        eprintln!(
            "{id}: {} triangles; exposure {exposure:.4} (CPU {cpu_exposure:.4}); composite vs \
             tonemap(shaded + shafts): {differ} of {} channels differ, by at most {worst}; shaded \
             {:.2} % from surface_radiance; shafts {:.2} % from the shadow_map truth",
            frame.raster.triangles,
            3 * w * h,
            100.0 * shaded_err,
            100.0 * shafts_err
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
