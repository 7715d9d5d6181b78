//! Conformance of the `area_ivsv` family (`ivsv_rectify`, `ivsv_scan`, `ivsv_gather`): the GPU
//! (`scatter_runtime::run_area_ivsv_once`) against the CPU mirrors
//! (`reference/src/kernels/ivsv_*.rs`) on every area pose (`area_columns`, `area_window`,
//! `area_grate` x the suite's four poses) for the variants of [`variants`], at 37x21 pixels
//! with 64^2 VPL maps. Trials are named `area_ivsv::<variant id>::<scene>::<pose>`;
//! `area_ivsv::errors` checks the error paths; `area_ivsv::family_table::<scene>::<pose>` the
//! family through the tables every family shares (`FamilyPasses` with the frame's area light
//! and VPL map array, against `run_family`'s mirrors); `area_ivsv::stress::<case>` the stress cases
//! against the truth and `area_ivsv::flicker::area_grate::<path>` temporal stability (both
//! documented at their functions).
//!
//! Each kernel is compared on the same input (the mirror of a pass runs on the GPU's result
//! of the pass before):
//! - `ivsv_rectify`: every marked bit equal, except at *ties*: light rays whose shadow-map
//!   coordinate lies within 1e-3 texels of a texel edge or whose occluder lies within 1e-3
//!   bins of a bin boundary (the mirror's margin), where a few ulps of the GPU's `sin`, `cos`
//!   or `atan2` legitimately move the texel or the bin. At most 0.1 % of the marks may be
//!   ties that differ; every other bit must match.
//! - `ivsv_scan`: bit for bit (integer ORs of the same marks), and `marks` zero afterwards.
//! - `ivsv_gather`: `|gpu - cpu| <= 2e-3 |cpu| + 1e-4 max radiance` (one f16 step and the
//!   transcendentals' ulps) on at least 99.5 % of the pixels; the rest are pixels where one
//!   bit moves between pieces or in and out of the cone's interval at a rounding tie
//!   (reported), and rel L1 over the image <= 1e-3. Interleaved variants: the gather's
//!   partial sums (rgba32float) so, and `ivsv_interleave_sum` on the GPU's partial sums within
//!   1e-3 of the mirror's per channel (one f16 step).

use std::process::ExitCode;

use scatter_conformance::{Check, gpu, run_trials};
use scatter_reference::area_suite::{self, AreaSceneName};
use scatter_reference::buffers::GBuffer;
use scatter_reference::buffers::ShadowMap;
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::kernels::ivsv_rectify::rectify_bit;
use scatter_reference::kernels::texture::Tex;
use scatter_reference::kernels::{
    IvsvInputs, ivsv_gather, ivsv_inputs, ivsv_interleave_sum, ivsv_scan,
};
use scatter_reference::metrics;
use scatter_reference::paths::Path;
use scatter_reference::suite::{MediumPreset, Pose};
use scatter_reference::truth::{self, TruthSettings};
use scatter_runtime::{AreaIvsv, RuntimeError, run_area_ivsv_once};
use scatter_shaderlib::area_ivsv::{AreaIvsvVariant, PHI_BITS};
use scatter_shaderlib::sampling::SamplingKnobs;

const SCREEN: [u32; 2] = [37, 21];
const MAP: u32 = 64;

/// The variants: the family's conformance grid ([`AreaIvsvVariant::grid`]: a small
/// default-like grid, an odd one (3 VPLs, 37 x 19 texels, one segment), many segments, and
/// both interleaves).
fn variants() -> Vec<AreaIvsvVariant> {
    AreaIvsvVariant::grid()
}

struct Case {
    scene: scatter_reference::scene::Scene,
    gbuf: GBuffer,
    inputs: IvsvInputs,
}

fn case(name: AreaSceneName, pose: Pose, v: &AreaIvsvVariant) -> Case {
    let scene = area_suite::scene(name, pose, MediumPreset::Default, SCREEN[0], SCREEN[1]);
    let bvh = Bvh::build(&scene.geometry);
    let gbuf = GBuffer::cast(&scene, &bvh);
    let inputs = ivsv_inputs(&scene, &gbuf, &bvh, v, MAP).expect("inputs");
    Case {
        scene,
        gbuf,
        inputs,
    }
}

fn trial(ctx: &scatter_runtime::Context, v: &AreaIvsvVariant, c: &Case) -> Result<String, String> {
    let gpu = run_area_ivsv_once(
        ctx,
        v,
        SCREEN,
        &c.scene.camera_desc(),
        &c.scene.medium_desc(),
        &c.inputs.vpls,
        MAP,
        &c.gbuf.view_depth,
        &c.inputs.map_data,
    )
    .map_err(|e| e.to_string())?;
    if gpu.frame != c.inputs.frame {
        return Err("the runtime's frame set-up differs from the mirror's".into());
    }
    let m = &c.inputs.frame.uniforms;
    let records = &c.inputs.frame.vpls;
    // ivsv_rectify: bit by bit, ties excepted.
    let (mut marked, mut ties, mut wrong) = (0usize, 0usize, Vec::new());
    for vi in 0..v.vpls {
        for j in 0..v.theta {
            for k in 0..PHI_BITS {
                let (word, mask, margin) = match rectify_bit(m, records, &c.inputs.maps, k, j, vi) {
                    Ok(mark) => {
                        marked += 1;
                        (Some(mark.word), mark.mask, mark.margin)
                    }
                    Err(margin) => (None, 1 << (k % 32), margin),
                };
                // The GPU's bit of this light ray, wherever it landed in the row.
                let row = (vi * v.theta + j) * v.alpha * 4 + k / 32;
                let gpu_word = (0..v.alpha)
                    .map(|i| row + 4 * i)
                    .find(|&w| gpu.marks[w as usize] & mask != 0);
                if gpu_word != word {
                    if margin < 1e-3 {
                        ties += 1;
                    } else {
                        wrong.push(format!(
                            "VPL {vi} row {j} bit {k}: gpu word {gpu_word:?}, cpu {word:?} (margin {margin})"
                        ));
                    }
                }
            }
        }
    }
    if !wrong.is_empty() {
        return Err(format!(
            "ivsv_rectify: {} marks differ away from ties: {:?}",
            wrong.len(),
            &wrong[..wrong.len().min(5)]
        ));
    }
    if ties as f64 > 0.001 * (marked.max(1) as f64) {
        return Err(format!(
            "ivsv_rectify: {ties} tied marks differ of {marked}"
        ));
    }
    // ivsv_scan on the GPU's marks.
    let mut marks = gpu.marks.clone();
    let mut volume = vec![0u32; gpu.volume.len()];
    ivsv_scan::ivsv_scan(m, &mut marks, &mut volume);
    if volume != gpu.volume {
        let n = volume
            .iter()
            .zip(&gpu.volume)
            .filter(|(a, b)| a != b)
            .count();
        return Err(format!("ivsv_scan: {n} words differ"));
    }
    if gpu.marks_after_scan.iter().any(|&w| w != 0) {
        return Err("ivsv_scan left marks set".into());
    }
    // ivsv_gather on the GPU's voxels.
    let depth = Tex {
        width: SCREEN[0],
        height: SCREEN[1],
        data: c.gbuf.view_depth.clone(),
    };
    let cpu = ivsv_gather::ivsv_gather(m, records, &gpu.volume, &depth, v.segments, v.interleave);
    // Interleaved: the gather's partial sums, then the window sums of the GPU's partial sums.
    let gathered: Vec<[f32; 4]> = if v.interleave > 1 {
        let partial: Vec<[f32; 3]> = gpu.partial.iter().map(|p| [p[0], p[1], p[2]]).collect();
        let summed = ivsv_interleave_sum::ivsv_interleave_sum(m, &partial, v.interleave);
        for (g, c) in gpu.output.iter().zip(&summed) {
            for ch in 0..3 {
                if (g[ch] - c[ch]).abs() > 1e-3 * c[ch].abs() + 1e-6 {
                    return Err(format!(
                        "ivsv_interleave_sum: {g:?} against the mirror's {c:?}"
                    ));
                }
            }
        }
        gpu.partial.clone()
    } else {
        gpu.output.clone()
    };
    let max = cpu
        .iter()
        .flat_map(|p| p.iter().copied())
        .fold(0.0f32, f32::max);
    let (mut off, mut diff, mut total) = (0usize, 0.0f64, 0.0f64);
    for (g, c) in gathered.iter().zip(&cpu) {
        let mut bad = false;
        for ch in 0..3 {
            if !g[ch].is_finite() {
                return Err(format!("ivsv_gather: non-finite output {g:?}"));
            }
            let d = (g[ch] - c[ch]).abs();
            diff += f64::from(d);
            total += f64::from(c[ch].abs());
            bad |= d > 2e-3 * c[ch].abs() + 1e-4 * max;
        }
        off += usize::from(bad);
    }
    let rel_l1 = diff / total.max(1e-30);
    let pixels = cpu.len();
    if off as f64 > 0.005 * pixels as f64 || rel_l1 > 1e-3 {
        return Err(format!(
            "ivsv_gather: {off} of {pixels} pixels off, rel L1 {rel_l1:.2e}"
        ));
    }
    Ok(format!(
        "{marked} marks, {ties} tied differ; scan exact; gather rel L1 {rel_l1:.2e}, {off} pixels at ties"
    ))
}

/// The method on the GPU over a scene: its image (rgb).
fn gpu_image(
    ctx: &scatter_runtime::Context,
    v: &AreaIvsvVariant,
    scene: &scatter_reference::scene::Scene,
    map: u32,
) -> Result<(Image, GBuffer, Bvh), String> {
    let bvh = Bvh::build(&scene.geometry);
    let gbuf = GBuffer::cast(scene, &bvh);
    let inputs = ivsv_inputs(scene, &gbuf, &bvh, v, map).map_err(|e| e.to_string())?;
    let out = run_area_ivsv_once(
        ctx,
        v,
        [gbuf.width, gbuf.height],
        &scene.camera_desc(),
        &scene.medium_desc(),
        &inputs.vpls,
        map,
        &gbuf.view_depth,
        &inputs.map_data,
    )
    .map_err(|e| e.to_string())?;
    let img = Image::from_pixels(
        gbuf.width,
        gbuf.height,
        out.output.iter().map(|p| [p[0], p[1], p[2]]).collect(),
    );
    Ok((img, gbuf, bvh))
}

/// The stress cases (`area_suite::stress_scenes`) on the GPU, 16 VPLs, the default grid, at
/// 48x27: rel RMSE <= 5 % against the `vpl` truth (the point limit's `shadow_map` truth for
/// the tiny light) and no NaN/Inf; sampled at lowres 4 and along 64 epipolar slices of 64
/// samples, no NaN/Inf either (their rel L1 against the per-pixel image is reported: at
/// 48x27 a sample stands for a large share of the frame).
fn stress(scene: scatter_reference::scene::Scene) -> Result<String, String> {
    let Some(ctx) = gpu() else {
        return Ok(String::new());
    };
    let v = AreaIvsvVariant {
        vpls: 16,
        ..AreaIvsvVariant::default()
    };
    let settings = TruthSettings {
        segments: 256,
        ..TruthSettings::default()
    };
    let (img, gbuf, bvh) = gpu_image(ctx, &v, &scene, 128)?;
    let truth = area_suite::stress_truth(&scene, &gbuf, &bvh, 16, 128, &settings)
        .map_err(|e| e.to_string())?;
    let nan = metrics::non_finite_count(&img);
    let e = metrics::rel_rmse(&img, &truth).map_err(|e| e.to_string())?;
    let l1 = metrics::rel_l1(&img, &truth).map_err(|e| e.to_string())?;
    if nan > 0 || e > 0.05 {
        return Err(format!("rel RMSE {e}, {nan} NaN/Inf"));
    }
    let mut sampled = Vec::new();
    for knobs in [
        SamplingKnobs::lowres(4),
        SamplingKnobs {
            slice_samples: 64,
            ..SamplingKnobs::epipolar(64)
        },
    ] {
        let (s_img, _, _) = gpu_image(ctx, &v.with_sampling_knobs(knobs), &scene, 128)?;
        let nan = metrics::non_finite_count(&s_img);
        if nan > 0 {
            return Err(format!("{}: {nan} NaN/Inf", knobs.marker_suffix()));
        }
        let d = metrics::rel_l1(&s_img, &img).map_err(|e| e.to_string())?;
        sampled.push(format!(
            "{} {:.2} % from per pixel",
            knobs.marker_suffix(),
            100.0 * d
        ));
    }
    Ok(format!(
        "rel RMSE {:.2} % / rel L1 {:.2} %, 0 NaN/Inf; sampled, 0 NaN/Inf: {}",
        100.0 * e,
        100.0 * l1,
        sampled.join(", ")
    ))
}

/// Temporal stability: `area_grate` along a camera path and a light rotation
/// (`area_suite::animated`, 16 frames at 32x18), area_ivsv (16 VPLs, the default grid) and,
/// for comparison, ray marching every VPL's map with n = 16 (about area_ivsv's time at
/// 1280x720: `docs/bench/area.md`), each frame against its `vpl` truth. Asserted: 0 NaN/Inf
/// in every frame, and area_ivsv flickers no more than the per-VPL ray march. Reported: the
/// flicker of area_ivsv along 64 epipolar slices of 64 samples (0 NaN/Inf asserted).
fn flicker(path: Path) -> Result<String, String> {
    let Some(ctx) = gpu() else {
        return Ok(String::new());
    };
    const FRAMES: usize = 16;
    let v = AreaIvsvVariant {
        vpls: 16,
        ..AreaIvsvVariant::default()
    };
    let settings = TruthSettings {
        segments: 256,
        ..TruthSettings::default()
    };
    let march = scatter_shaderlib::family::FamilyVariant::Raymarch(
        scatter_shaderlib::raymarch::RaymarchVariant {
            light: scatter_shaderlib::prefiltered::LightKind::Spot,
            samples: 16,
            ..Default::default()
        },
    );
    let res = scatter_shaderlib::prefiltered::Resolutions {
        screen: [32, 18],
        rectified: [1, 1],
    };
    let mut pass =
        scatter_runtime::FamilyPasses::new(ctx, &march, res, 128).map_err(|e| e.to_string())?;
    let (mut ivsv, mut marched, mut truths) = (Vec::new(), Vec::new(), Vec::new());
    // Sampled along 64 epipolar slices of 64 samples: its samples move with the epipole;
    // its flicker is reported.
    let sampled_v = v.with_sampling_knobs(SamplingKnobs {
        slice_samples: 64,
        ..SamplingKnobs::epipolar(64)
    });
    let mut sampled = Vec::new();
    for f in 0..FRAMES {
        let s = area_suite::animated(AreaSceneName::Grate, path, f, FRAMES, 32, 18);
        let (img, gbuf, bvh) = gpu_image(ctx, &v, &s, 128)?;
        if metrics::non_finite_count(&img) > 0 {
            return Err(format!("{}: NaN/Inf", s.name));
        }
        let (s_img, _, _) = gpu_image(ctx, &sampled_v, &s, 128)?;
        if metrics::non_finite_count(&s_img) > 0 {
            return Err(format!("{} sampled: NaN/Inf", s.name));
        }
        sampled.push(s_img);
        let mut sum = vec![[0.0f32; 3]; (32 * 18) as usize];
        for vpl in s.point_light_scenes(16) {
            let sm = ShadowMap::build(&vpl, &bvh, 128).map_err(|e| e.to_string())?;
            let inputs = scatter_runtime::CpuInputs {
                frame: scatter_runtime::FrameInput {
                    camera: vpl.camera_desc(),
                    light: vpl.light_desc(),
                    medium: vpl.medium_desc(),
                    shadow_map: sm.desc(),
                    settings: scatter_shaderlib::prefiltered::FrameSettings::default(),
                },
                depth: gbuf.view_depth.clone(),
                shadow_map: sm.depth.clone(),
                rectified: None,
                pass_wall_frames: 0,
                cookie: None,
                vpl_maps: None,
            };
            let out = scatter_runtime::run_family_on(ctx, &mut pass, res, &inputs)
                .map_err(|e| e.to_string())?;
            for (acc, p) in sum.iter_mut().zip(&out.output) {
                for k in 0..3 {
                    acc[k] += p[k];
                }
            }
        }
        marched.push(Image::from_pixels(32, 18, sum));
        truths.push(
            truth::render_vpl(&s, &gbuf, &bvh, 16, 128, &settings).map_err(|e| e.to_string())?,
        );
        ivsv.push(img);
    }
    let fi = metrics::flicker(&ivsv, &truths).map_err(|e| e.to_string())?;
    let fm = metrics::flicker(&marched, &truths).map_err(|e| e.to_string())?;
    let fs = metrics::flicker(&sampled, &truths).map_err(|e| e.to_string())?;
    let line = format!(
        "flicker: area_ivsv {:.2} %, per-VPL raymarch n16 {:.2} %; area_ivsv epipolar 64 x 64 {:.2} % (0 NaN/Inf)",
        100.0 * fi,
        100.0 * fm,
        100.0 * fs
    );
    if fi > fm {
        return Err(line);
    }
    Ok(line)
}

fn errors() -> Result<(), String> {
    let Some(ctx) = gpu() else { return Ok(()) };
    let v = AreaIvsvVariant::default();
    match AreaIvsv::new(ctx, &v, [0, 4], 64) {
        Err(RuntimeError::EmptyInput { .. }) => {}
        other => return Err(format!("empty screen: {other:?}")),
    }
    let bad = AreaIvsvVariant { segments: 3, ..v };
    match AreaIvsv::new(ctx, &bad, [8, 8], 64) {
        Err(e) if e.to_string().contains("segments") => {}
        other => return Err(format!("bad segments: {other:?}")),
    }
    let mut pass = AreaIvsv::new(
        ctx,
        &AreaIvsvVariant {
            vpls: 2,
            alpha: 8,
            theta: 8,
            segments: 1,
            interleave: 1,
            ..AreaIvsvVariant::default()
        },
        [8, 8],
        16,
    )
    .map_err(|e| e.to_string())?;
    let c = case(AreaSceneName::Grate, Pose::Ordinary, &v);
    let camera = c.scene.camera_desc();
    let medium = c.scene.medium_desc();
    match pass.prepare(ctx, &camera, &medium, &[]) {
        Err(e) if e.to_string().contains("VPL count") => {}
        other => return Err(format!("no VPLs: {other:?}")),
    }
    family_errors(ctx, &c.scene)
}

/// The error paths of the family through the shared tables: a spot light, a template of
/// another size, a frame without its VPL map array, each named.
fn family_errors(
    ctx: &scatter_runtime::Context,
    scene: &scatter_reference::scene::Scene,
) -> Result<(), String> {
    use scatter_runtime::{FamilyPasses, FrameInput, Inputs};
    use scatter_shaderlib::family::FamilyVariant;
    use scatter_shaderlib::prefiltered::{FrameSettings, Resolutions};
    let v = FamilyVariant::AreaIvsv(AreaIvsvVariant::grid()[1]);
    let res = Resolutions {
        screen: [8, 8],
        rectified: [64, 64],
    };
    let mut passes = FamilyPasses::new(ctx, &v, res, 16).map_err(|e| e.to_string())?;
    let bvh = Bvh::build(&scene.geometry);
    let template = ShadowMap::build(scene, &bvh, 16).map_err(|e| e.to_string())?;
    let input = FrameInput {
        camera: scene.camera_desc(),
        light: scene.light_desc(),
        medium: scene.medium_desc(),
        shadow_map: template.desc(),
        settings: FrameSettings::for_screen(8, 8),
    };
    let spot = FrameInput {
        light: scene
            .light
            .area()
            .map(|a| a.desc().point_limit())
            .ok_or("the area scene has an area light")?,
        ..input
    };
    match passes.prepare(ctx, &spot) {
        Err(e) if e.to_string().contains("compiled for light = area") => {}
        other => return Err(format!("a spot light: {other:?}")),
    }
    let mut other_size = input;
    other_size.shadow_map.size = 32;
    match passes.prepare(ctx, &other_size) {
        Err(e) if e.to_string().contains("shadow map size") => {}
        other => return Err(format!("a 32^2 template for 16^2 maps: {other:?}")),
    }
    passes.prepare(ctx, &input).map_err(|e| e.to_string())?;
    let depth = scatter_runtime::textures::upload_r32float(
        ctx,
        scatter_shaderlib::Kernel::IvsvGather,
        "depth",
        [8, 8],
        &[1.0; 64],
    )
    .map_err(|e| e.to_string())?;
    let view = depth.create_view(&Default::default());
    let mut encoder = ctx.device().create_command_encoder(&Default::default());
    let inputs = Inputs {
        depth: &view,
        shadow_map: None,
        rectified: None,
        vpl_maps: None,
    };
    match passes.encode(ctx, &mut encoder, &inputs) {
        Err(e) if e.to_string().contains("VPL shadow maps") => Ok(()),
        other => Err(format!("no VPL maps: {:?}", other.map(|_| ()))),
    }
}

/// The family through the shared tables: `scatter_runtime::FamilyPasses` (the frame's
/// `LightDesc::Area`, the VPL frames from its standard map, the VPL map array as an input)
/// against `scatter_reference::kernels::run_family`, both as `scatter_conformance::run_variant`
/// drives every family, within the gather's bar (rel L1 <= 1e-3); the frame the runtime set
/// up is the one the mirrors ran. The sampled variants of [`table_variants`] run the
/// sampling stage's passes on both sides (the GPU's samples, unwarp and fallback against
/// `common_sampling::run_sampled` over the gather's mirror).
fn family_table(
    name: AreaSceneName,
    pose: Pose,
    variant: AreaIvsvVariant,
) -> Result<String, String> {
    use scatter_shaderlib::family::FamilyVariant;
    use scatter_shaderlib::prefiltered::FrameSettings;
    let Some(ctx) = gpu() else {
        return Ok(String::new());
    };
    let v = FamilyVariant::AreaIvsv(variant);
    // An area light's standard map is its point limit's: the VPL maps' template.
    let f = scatter_conformance::Fixture::area(name, pose, SCREEN, MAP);
    let settings = FrameSettings::for_screen(SCREEN[0], SCREEN[1]);
    let frame = f.cpu_frame([64, 64], &settings);
    let (gpu_out, report) = scatter_conformance::run_variant(Some(ctx), &v, &frame)?;
    let (cpu_out, _) = scatter_conformance::run_variant(None, &v, &frame)?;
    if report.is_some() {
        return Err("area_ivsv has no epipolar frame report".into());
    }
    let e = metrics::rel_l1(&gpu_out, &cpu_out).map_err(|e| e.to_string())?;
    let peak = cpu_out.data.iter().flatten().fold(0.0f32, |m, &x| m.max(x));
    if e.is_nan() || e > 1e-3 || peak <= 0.0 {
        return Err(format!(
            "GPU vs mirrors through the family tables: rel L1 {e:.2e}, peak {peak}"
        ));
    }
    Ok(format!("rel L1 {e:.2e} (peak {peak:.3e})"))
}

/// The variants of the family-table trials: the grid's first, and it sampled at a
/// quarter of the screen per axis and along 64 epipolar slices of 64 samples (sparser than
/// the pixels at 37 x 21, so the unwarp interpolates and refines).
fn table_variants() -> [AreaIvsvVariant; 3] {
    let v = AreaIvsvVariant::grid()[0];
    [
        v,
        v.with_sampling_knobs(SamplingKnobs::lowres(4)),
        v.with_sampling_knobs(SamplingKnobs {
            slice_samples: 64,
            ..SamplingKnobs::epipolar(64)
        }),
    ]
}

/// Screen of the sampled-accuracy trials: at 320 x 180 a sample stands for too large a
/// share of the lamp and of each VPL's shafts (lowres 4: 0.56 % mean, 1.01 % on
/// `area_window/epipole_on_screen`; epipolar: 0.57 % mean), at 1280 x 720 (`area_bench`)
/// the same bars hold with margin; 640 x 360 is the smallest size measured where they hold.
const SAMPLED_SCREEN: [u32; 2] = [640, 360];
/// Bars of the sampled-accuracy trials (issue 14's, for the interpolation error alone): rel
/// L1 of the sampled image against the same variant per pixel, at most this on the mean
/// over the 12 area poses ...
const SAMPLED_MEAN: f64 = 0.005;
/// ... and on any pose.
const SAMPLED_POSE: f64 = 0.01;

/// The sampling stage's error on area lights: `v` (16 VPLs, the default grid) sampled with
/// `knobs` against `v` per pixel on the GPU, on every area pose at [`SAMPLED_SCREEN`]
/// (128^2 VPL maps). The interpolation error bounds what sampling adds against any truth
/// (|e(s, t) - e(p, t)| <= e(s, p)); `tests/tests/sampling.rs` checks the stage's passes
/// against their mirrors. Reports the pixels evaluated themselves (fallback) per pose.
fn sampled_accuracy(knobs: SamplingKnobs) -> Result<String, String> {
    use scatter_shaderlib::family::FamilyVariant;
    use scatter_shaderlib::prefiltered::FrameSettings;
    let Some(ctx) = gpu() else {
        return Ok(String::new());
    };
    let per_pixel = AreaIvsvVariant {
        vpls: 16,
        ..AreaIvsvVariant::default()
    };
    let sampled = FamilyVariant::AreaIvsv(per_pixel.with_sampling_knobs(knobs));
    let per_pixel = FamilyVariant::AreaIvsv(per_pixel);
    let (mut sum, mut worst, mut rows) = (0.0f64, (0.0f64, String::new()), Vec::new());
    let poses = area_suite::all();
    for &(name, pose) in &poses {
        let [w, h] = SAMPLED_SCREEN;
        let f = scatter_conformance::Fixture::area(name, pose, SAMPLED_SCREEN, 128);
        let settings = FrameSettings::for_screen(w, h);
        let frame = f.cpu_frame([64, 64], &settings);
        let (pixels, _) = scatter_conformance::run_variant(Some(ctx), &per_pixel, &frame)?;
        let (out, _, listed) =
            scatter_conformance::run_variant_counted(Some(ctx), &sampled, &frame)?;
        if out.data.iter().flatten().any(|c| !c.is_finite()) {
            return Err(format!("{name}/{pose}: NaN or Inf in the sampled image"));
        }
        let e = metrics::rel_l1(&out, &pixels).map_err(|e| e.to_string())?;
        if e.is_nan() {
            return Err(format!("{name}/{pose}: rel L1 is NaN"));
        }
        sum += e;
        if e >= worst.0 {
            worst = (e, format!("{name}/{pose}"));
        }
        rows.push(format!(
            "{name}/{pose} {:.3} %{}",
            100.0 * e,
            listed.map_or(String::new(), |n| format!(" ({n} fallback)"))
        ));
    }
    let mean = sum / poses.len() as f64;
    let table = format!(
        "{}: rel L1 against per pixel: mean {:.3} %, worst {:.3} % ({}); {}",
        sampled.label(),
        100.0 * mean,
        100.0 * worst.0,
        worst.1,
        rows.join(", ")
    );
    if mean > SAMPLED_MEAN || worst.0 > SAMPLED_POSE {
        return Err(format!(
            "over the bars (mean {} %, pose {} %): {table}",
            100.0 * SAMPLED_MEAN,
            100.0 * SAMPLED_POSE
        ));
    }
    Ok(table)
}

fn main() -> ExitCode {
    let mut trials: Vec<(String, Check)> = Vec::new();
    for (name, pose) in [
        (AreaSceneName::Grate, Pose::Ordinary),
        (AreaSceneName::Window, Pose::EpipoleOnScreen),
    ] {
        for v in table_variants() {
            let sampled = v.sampling_knobs().marker_suffix();
            trials.push((
                format!("area_ivsv::family_table{sampled}::{name}::{pose}"),
                Box::new(move || family_table(name, pose, v).map(|m| eprintln!("     {m}"))),
            ));
        }
    }
    for knobs in [
        SamplingKnobs::lowres(2),
        SamplingKnobs::lowres(4),
        SamplingKnobs::epipolar(SamplingKnobs::DEFAULT_SLICES),
    ] {
        trials.push((
            format!("area_ivsv::sampled{}", knobs.marker_suffix()),
            Box::new(move || sampled_accuracy(knobs).map(|m| eprintln!("     {m}"))),
        ));
    }
    for v in variants() {
        for (name, pose) in area_suite::all() {
            let trial_name = format!("area_ivsv::{}::{name}::{pose}", v.id());
            let check: Check = Box::new(move || {
                let Some(ctx) = gpu() else { return Ok(()) };
                let c = case(name, pose, &v);
                trial(ctx, &v, &c).map(|m| eprintln!("     {m}"))
            });
            trials.push((trial_name, check));
        }
    }
    for scene in area_suite::stress_scenes(48, 27) {
        let name = format!("area_ivsv::stress::{}", scene.name);
        trials.push((
            name,
            Box::new(move || stress(scene).map(|m| eprintln!("     {m}"))),
        ));
    }
    for path in Path::ALL {
        trials.push((
            format!("area_ivsv::flicker::area_grate::{path}"),
            Box::new(move || flicker(path).map(|m| eprintln!("     {m}"))),
        ));
    }
    trials.push(("area_ivsv::errors".into(), Box::new(errors)));
    run_trials(trials, &[])
}
