//! `area_bench`: the `area_ivsv` family (Wyman & Dai 2013) against its brute force, ray
//! marching every VPL's shadow map (the `raymarch` family once per VPL spot, outputs added),
//! both on the GPU (lavapipe here), at the same `N` VPLs and shadow maps.
//!
//! - Error: rel RMSE and rel L1 against the `vpl` truth (the same VPLs and maps) on every
//!   area pose at `--error-size`, mean and worst over the poses.
//! - Time: the median wall time of each pass submitted on its own (`--frames` frames after a
//!   warm-up) at `--time-size` on `area_columns/ordinary`: `ivsv_rectify`, `ivsv_scan`,
//!   `ivsv_gather` (with `sampling = epipolar` its unwarp and fallback); for the brute force
//!   the sum over the VPLs of the `raymarch` pass (the sum of the `N` outputs is not counted:
//!   in the brute force's favour).
//! - Sampled area_ivsv (`--sampling`: lowres 2 and 4, epipolar 512 x 256): the interpolation
//!   error, rel L1 and rel RMSE of the sampled image against the same variant per pixel on
//!   every area pose at `--time-size` (GPU), beside the time; the sweep's 64 x 36 is too
//!   small to sample. Its chart point is at the per-pixel variant's truth error plus that
//!   rel RMSE (a bound on its error against the truth, by the triangle inequality).
//!
//! ```text
//! cargo run --release -p scatter-examples --example area_bench -- --out docs/bench
//! ```
//!
//! Writes `area.csv`, `area.md` and the chart (`area.svg`, `area.png`: error against time,
//! one line per method and VPL count) into `--out`. Speed is a ratio from one run (never a
//! timed test); the machine is shared and noisy.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Duration;

use clap::Parser;
use scatter_examples::bench::{AreaPoint, write_area_chart};
use scatter_reference::area_suite::{self, AreaSceneName};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::kernels::ivsv_inputs;
use scatter_reference::metrics;
use scatter_reference::scene::Scene;
use scatter_reference::suite::{MediumPreset, Pose};
use scatter_reference::truth::{self, TruthSettings};
use scatter_runtime::{
    AreaIvsv, Context, CpuInputs, FamilyPasses, FrameInput, run_area_ivsv_once, run_family_on,
    textures::upload_r32float, upload_vpl_maps,
};
use scatter_shaderlib::Kernel;
use scatter_shaderlib::area_ivsv::AreaIvsvVariant;
use scatter_shaderlib::family::{Family, FamilyVariant};
use scatter_shaderlib::prefiltered::{FrameSettings, LightKind, Resolutions};
use scatter_shaderlib::raymarch::RaymarchVariant;
use scatter_shaderlib::sampling::{Sampling, SamplingKnobs};

/// The command line.
#[derive(Parser, Debug)]
#[command(about = "area_ivsv against per-VPL ray marching: error and time")]
struct Args {
    /// Output folder for area.csv, area.md and the chart (area.svg, area.png).
    #[arg(long, default_value = "docs/bench")]
    out: PathBuf,
    /// Screen size of the error sweep (WxH).
    #[arg(long, default_value = "64x36", value_parser = parse_size)]
    error_size: [u32; 2],
    /// Screen size of the timing (WxH).
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    time_size: [u32; 2],
    /// VPL counts.
    #[arg(long, value_delimiter = ',', default_values_t = [16u32, 64])]
    vpls: Vec<u32>,
    /// Interleaving of area_ivsv's gather (1: none; 2, 4: the paper's interleaved gather).
    #[arg(long, value_delimiter = ',', default_values_t = [1u32, 2, 4])]
    interleave: Vec<u32>,
    /// Sampling of area_ivsv's gather beside per pixel (without interleaving): `lowres2`,
    /// `lowres4`, `epipolar` (512 slices x 256 samples, step 8); `none` for none.
    #[arg(long, value_delimiter = ',', default_values_t = ["lowres2".to_owned(), "lowres4".to_owned(), "epipolar".to_owned()])]
    sampling: Vec<String>,
    /// Samples per view ray of the per-VPL ray march.
    #[arg(long, value_delimiter = ',', default_values_t = [4u32, 8, 16, 32, 64])]
    samples: Vec<u32>,
    /// VPL shadow-map size.
    #[arg(long, default_value_t = 128)]
    map_size: u32,
    /// Frames per timing (median, after one warm-up).
    #[arg(long, default_value_t = 3)]
    frames: u32,
    /// Instead of the bench: write this PNG of `area_grate` (`--image-pose`) lit by its
    /// area light (area_ivsv, 64 VPLs, on the GPU) beside the same scene lit by the light's
    /// point limit (a spot of the same intensity; per-pixel ray marching, 64 samples), one
    /// exposure for both.
    #[arg(long)]
    image: Option<PathBuf>,
    /// The pose of `--image`.
    #[arg(long, default_value = "ordinary")]
    image_pose: Pose,
    /// The size of each half of `--image` (WxH).
    #[arg(long, default_value = "480x270", value_parser = parse_size)]
    image_size: [u32; 2],
}

/// The sampling knobs of a `--sampling` value.
fn parse_sampling(s: &str) -> Result<Option<SamplingKnobs>, String> {
    match s.trim() {
        "none" => Ok(None),
        "lowres2" => Ok(Some(SamplingKnobs::lowres(2))),
        "lowres4" => Ok(Some(SamplingKnobs::lowres(4))),
        "epipolar" => Ok(Some(SamplingKnobs::epipolar(SamplingKnobs::DEFAULT_SLICES))),
        other => Err(format!(
            "--sampling `{other}`: expected lowres2, lowres4, epipolar or none"
        )),
    }
}

fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("size `{s}` must be WxH, e.g. 1280x720"))?;
    let p = |v: &str| {
        v.parse::<u32>()
            .ok()
            .filter(|&n| (1..=16384).contains(&n))
            .ok_or_else(|| format!("size `{s}`: `{v}` must be an integer in 1..=16384"))
    };
    Ok([p(w)?, p(h)?])
}

/// One method: `area_ivsv` with N VPLs (per pixel, interleaved or sampled), or per-VPL ray
/// marching with N VPLs and n samples.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Method {
    Ivsv {
        vpls: u32,
        interleave: u32,
        sampling: SamplingKnobs,
    },
    Raymarch {
        vpls: u32,
        samples: u32,
    },
}

impl Method {
    fn label(self) -> String {
        match self {
            Method::Ivsv {
                vpls,
                interleave: 1,
                sampling,
            } => format!("area_ivsv N={vpls}{}", sampling.marker_suffix()),
            Method::Ivsv {
                vpls, interleave, ..
            } => {
                format!("area_ivsv N={vpls} interleave {interleave}")
            }
            Method::Raymarch { vpls, samples } => format!("raymarch per VPL N={vpls} n={samples}"),
        }
    }
    fn vpls(self) -> u32 {
        match self {
            Method::Ivsv { vpls, .. } | Method::Raymarch { vpls, .. } => vpls,
        }
    }
    /// A sampled area_ivsv method.
    fn sampled(self) -> bool {
        matches!(self, Method::Ivsv { sampling, .. } if sampling.is_sampled())
    }
    /// The same method per pixel.
    fn per_pixel(self) -> Method {
        match self {
            Method::Ivsv {
                vpls, interleave, ..
            } => Method::Ivsv {
                vpls,
                interleave,
                sampling: SamplingKnobs::default(),
            },
            other => other,
        }
    }
}

fn ivsv_variant(vpls: u32, interleave: u32, sampling: SamplingKnobs) -> AreaIvsvVariant {
    AreaIvsvVariant {
        vpls,
        interleave,
        ..AreaIvsvVariant::default()
    }
    .with_sampling_knobs(sampling)
}

fn raymarch_variant(samples: u32) -> FamilyVariant {
    FamilyVariant::Raymarch(RaymarchVariant {
        light: LightKind::Spot,
        samples,
        ..RaymarchVariant::default()
    })
}

/// A VPL scene's inputs for a single-light family.
fn vpl_inputs(vpl: &Scene, gbuf: &GBuffer, sm: &ShadowMap) -> CpuInputs {
    CpuInputs {
        frame: FrameInput {
            camera: vpl.camera_desc(),
            light: vpl.light_desc(),
            medium: vpl.medium_desc(),
            shadow_map: sm.desc(),
            settings: FrameSettings::default(),
        },
        depth: gbuf.view_depth.clone(),
        shadow_map: sm.depth.clone(),
        rectified: None,
        pass_wall_frames: 0,
        cookie: None,
        vpl_maps: None,
    }
}

/// One method's image of `scene` on the GPU.
fn render(
    ctx: &Context,
    method: Method,
    scene: &Scene,
    gbuf: &GBuffer,
    bvh: &Bvh,
    map_size: u32,
) -> Result<Image, String> {
    let (w, h) = (gbuf.width, gbuf.height);
    match method {
        Method::Ivsv {
            vpls,
            interleave,
            sampling,
        } => {
            let v = ivsv_variant(vpls, interleave, sampling);
            let inputs = ivsv_inputs(scene, gbuf, bvh, &v, map_size).map_err(|e| e.to_string())?;
            let out = run_area_ivsv_once(
                ctx,
                &v,
                [w, h],
                &scene.camera_desc(),
                &scene.medium_desc(),
                &inputs.vpls,
                map_size,
                &gbuf.view_depth,
                &inputs.map_data,
            )
            .map_err(|e| e.to_string())?;
            Ok(Image::from_pixels(
                w,
                h,
                out.output.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            ))
        }
        Method::Raymarch { vpls, samples } => {
            let res = Resolutions {
                screen: [w, h],
                rectified: [1, 1],
            };
            let mut pass = FamilyPasses::new(ctx, &raymarch_variant(samples), res, map_size)
                .map_err(|e| e.to_string())?;
            let mut sum = vec![[0.0f32; 3]; (w * h) as usize];
            // The VPL maps area_ivsv and the `vpl` truth read (`ShadowMap::vpl_maps`).
            let maps = ShadowMap::vpl_maps(scene, bvh, vpls as usize, map_size)
                .map_err(|e| e.to_string())?;
            for (vpl, sm) in &maps {
                let out = run_family_on(ctx, &mut pass, res, &vpl_inputs(vpl, gbuf, sm))
                    .map_err(|e| e.to_string())?;
                for (acc, p) in sum.iter_mut().zip(&out.output) {
                    for k in 0..3 {
                        acc[k] += p[k];
                    }
                }
            }
            Ok(Image::from_pixels(w, h, sum))
        }
    }
}

/// Median pass wall times of `method` at `size` on `scene`: `(pass, time)` in order.
fn time(
    ctx: &Context,
    method: Method,
    scene: &Scene,
    bvh: &Bvh,
    map_size: u32,
    frames: u32,
) -> Result<Vec<(String, Duration)>, String> {
    let gbuf = GBuffer::cast(scene, bvh);
    let screen = [gbuf.width, gbuf.height];
    let err = |e: scatter_runtime::RuntimeError| e.to_string();
    match method {
        Method::Ivsv {
            vpls,
            interleave,
            sampling,
        } => {
            let v = ivsv_variant(vpls, interleave, sampling);
            let inputs = ivsv_inputs(scene, &gbuf, bvh, &v, map_size).map_err(|e| e.to_string())?;
            let mut pass = AreaIvsv::new(ctx, &v, screen, map_size).map_err(err)?;
            pass.prepare(
                ctx,
                &scene.camera_desc(),
                &scene.medium_desc(),
                &inputs.vpls,
            )
            .map_err(err)?;
            let depth = upload_r32float(ctx, Kernel::IvsvGather, "depth", screen, &gbuf.view_depth)
                .map_err(err)?;
            let depth_view = depth.create_view(&Default::default());
            let (_maps, maps_view) =
                upload_vpl_maps(ctx, map_size, vpls, &inputs.map_data).map_err(err)?;
            let t = pass
                .measure_pass_wall_times(ctx, &depth_view, &maps_view, frames)
                .map_err(err)?;
            let mut out = vec![
                ("ivsv_rectify".into(), t.rectify),
                ("ivsv_scan".into(), t.scan),
                ("ivsv_gather".into(), t.gather),
            ];
            if interleave > 1 {
                out.push(("ivsv_interleave_sum".into(), t.interleave_sum));
            }
            if sampling.sampling == Sampling::Epipolar {
                out.push(("ivsv_gather_unwarp".into(), t.unwarp));
                out.push(("ivsv_gather_fallback".into(), t.fallback));
            }
            Ok(out)
        }
        Method::Raymarch { vpls, samples } => {
            let res = Resolutions {
                screen,
                rectified: [1, 1],
            };
            let mut pass =
                FamilyPasses::new(ctx, &raymarch_variant(samples), res, map_size).map_err(err)?;
            let mut total = Duration::ZERO;
            let maps = ShadowMap::vpl_maps(scene, bvh, vpls as usize, map_size)
                .map_err(|e| e.to_string())?;
            for (vpl, sm) in &maps {
                let inputs = CpuInputs {
                    pass_wall_frames: frames,
                    ..vpl_inputs(vpl, &gbuf, sm)
                };
                let out = run_family_on(ctx, &mut pass, res, &inputs).map_err(err)?;
                total += out.pass_wall_times.iter().map(|p| p.1).sum::<Duration>();
            }
            Ok(vec![(format!("raymarch x {vpls}"), total)])
        }
    }
}

/// `--image`: soft shafts from the area light beside hard ones from its point limit.
fn image(ctx: &Context, args: &Args, path: &std::path::Path) -> Result<(), String> {
    let [w, h] = args.image_size;
    let area = area_suite::scene(
        AreaSceneName::Grate,
        args.image_pose,
        MediumPreset::Default,
        w,
        h,
    );
    let scatter_reference::scene::Light::Area(light) = &area.light else {
        return Err("area_grate has no area light".into());
    };
    let point = Scene {
        light: light.point_limit(),
        ..area.clone()
    };
    let bvh = Bvh::build(&area.geometry);
    let gbuf = GBuffer::cast(&area, &bvh);
    let soft = render(
        ctx,
        Method::Ivsv {
            vpls: 64,
            interleave: 1,
            sampling: SamplingKnobs::default(),
        },
        &area,
        &gbuf,
        &bvh,
        args.map_size,
    )?;
    let hard = render(
        ctx,
        Method::Raymarch {
            vpls: 1,
            samples: 64,
        },
        &point,
        &gbuf,
        &bvh,
        512,
    )?;
    let e = |x: Result<Image, scatter_reference::image::ImageError>| x.map_err(|e| e.to_string());
    let hard = e(truth::surface_radiance(&point, &gbuf, &bvh).add(&hard))?;
    let soft = e(truth::surface_radiance(&area, &gbuf, &bvh).add(&soft))?;
    let exposure = hard.auto_exposure();
    e(Image::hstack(&[&hard, &soft]))?
        .write_png(path, Some(exposure))
        .map_err(|e| e.to_string())?;
    eprintln!(
        "wrote {} (left: point limit, right: area light)",
        path.display()
    );
    Ok(())
}

fn main() -> Result<(), String> {
    let args = Args::parse();
    let ctx = Context::new().map_err(|e| e.to_string())?;
    eprintln!("area_bench: adapter {}", ctx.report());
    if let Some(path) = &args.image {
        return image(&ctx, &args, path);
    }
    let samplings = args
        .sampling
        .iter()
        .map(|s| parse_sampling(s))
        .collect::<Result<Vec<_>, _>>()?;
    let mut methods = Vec::new();
    for &n in &args.vpls {
        for &i in &args.interleave {
            if n.is_multiple_of(i * i) {
                methods.push(Method::Ivsv {
                    vpls: n,
                    interleave: i,
                    sampling: SamplingKnobs::default(),
                });
            }
        }
        for &sampling in samplings.iter().flatten() {
            methods.push(Method::Ivsv {
                vpls: n,
                interleave: 1,
                sampling,
            });
        }
        for &s in &args.samples {
            methods.push(Method::Raymarch {
                vpls: n,
                samples: s,
            });
        }
    }
    let truth_settings = TruthSettings {
        segments: 256,
        ..TruthSettings::default()
    };
    // Errors: per method, per pose.
    let mut errors: Vec<Vec<(String, f64, f64)>> = vec![Vec::new(); methods.len()];
    let [ew, eh] = args.error_size;
    for (name, pose) in area_suite::all() {
        let s = area_suite::scene(name, pose, MediumPreset::Default, ew, eh);
        let bvh = Bvh::build(&s.geometry);
        let gbuf = GBuffer::cast(&s, &bvh);
        for &n in &args.vpls {
            let truth =
                truth::render_vpl(&s, &gbuf, &bvh, n as usize, args.map_size, &truth_settings)
                    .map_err(|e| e.to_string())?;
            for (i, &m) in methods.iter().enumerate() {
                if m.vpls() != n || m.sampled() {
                    continue;
                }
                let img = render(&ctx, m, &s, &gbuf, &bvh, args.map_size)?;
                let rmse = metrics::rel_rmse(&img, &truth).map_err(|e| e.to_string())?;
                let l1 = metrics::rel_l1(&img, &truth).map_err(|e| e.to_string())?;
                eprintln!(
                    "{} {}: rel RMSE {:.2} %, rel L1 {:.2} %",
                    s.name,
                    m.label(),
                    100.0 * rmse,
                    100.0 * l1
                );
                errors[i].push((s.name.clone(), rmse, l1));
            }
        }
    }
    // Sampled: the interpolation error against the same variant per pixel at the time size.
    let [tw, th] = args.time_size;
    let mut interpolation: Vec<Vec<(String, f64, f64)>> = vec![Vec::new(); methods.len()];
    if methods.iter().any(|m| m.sampled()) {
        for (name, pose) in area_suite::all() {
            let s = area_suite::scene(name, pose, MediumPreset::Default, tw, th);
            let bvh = Bvh::build(&s.geometry);
            let gbuf = GBuffer::cast(&s, &bvh);
            for &n in &args.vpls {
                let mut per_pixel: Option<Image> = None;
                for (i, &m) in methods.iter().enumerate() {
                    if m.vpls() != n || !m.sampled() {
                        continue;
                    }
                    let reference = match &per_pixel {
                        Some(img) => img,
                        None => per_pixel.insert(render(
                            &ctx,
                            m.per_pixel(),
                            &s,
                            &gbuf,
                            &bvh,
                            args.map_size,
                        )?),
                    };
                    let img = render(&ctx, m, &s, &gbuf, &bvh, args.map_size)?;
                    if metrics::non_finite_count(&img) > 0 {
                        return Err(format!("{} {}: NaN or Inf", s.name, m.label()));
                    }
                    let rmse = metrics::rel_rmse(&img, reference).map_err(|e| e.to_string())?;
                    let l1 = metrics::rel_l1(&img, reference).map_err(|e| e.to_string())?;
                    eprintln!(
                        "{} {} against per pixel at {tw}x{th}: rel RMSE {:.2} %, rel L1 {:.2} %",
                        s.name,
                        m.label(),
                        100.0 * rmse,
                        100.0 * l1
                    );
                    interpolation[i].push((s.name.clone(), rmse, l1));
                }
            }
        }
        // A sampled row's error against the truth is bounded by its per-pixel variant's
        // plus the interpolation error; the chart places it there.
        for (i, &m) in methods.iter().enumerate() {
            if m.sampled() {
                let p = methods
                    .iter()
                    .position(|&q| q == m.per_pixel())
                    .ok_or_else(|| format!("{}: its per-pixel variant was not run", m.label()))?;
                errors[i] = errors[p]
                    .iter()
                    .zip(&interpolation[i])
                    .map(|(t, s)| (t.0.clone(), t.1 + s.1, t.2 + s.2))
                    .collect();
            }
        }
    }
    // Times.
    let scene = area_suite::scene(
        AreaSceneName::Columns,
        Pose::Ordinary,
        MediumPreset::Default,
        tw,
        th,
    );
    let bvh = Bvh::build(&scene.geometry);
    let mut rows = Vec::new();
    let mut csv = String::from(
        "method,vpls,samples,mean_rel_rmse,worst_rel_rmse,mean_rel_l1,passes,time_ms\n",
    );
    for (i, &m) in methods.iter().enumerate() {
        let passes = time(&ctx, m, &scene, &bvh, args.map_size, args.frames)?;
        let total: Duration = passes.iter().map(|p| p.1).sum();
        let e = &errors[i];
        let mean = |k: usize| {
            e.iter()
                .map(|x| if k == 0 { x.1 } else { x.2 })
                .sum::<f64>()
                / e.len().max(1) as f64
        };
        let worst = e.iter().map(|x| x.1).fold(0.0, f64::max);
        let split = passes
            .iter()
            .map(|(p, t)| format!("{p} {:.1}", t.as_secs_f64() * 1e3))
            .collect::<Vec<_>>()
            .join(", ");
        eprintln!(
            "{}: {:.1} ms ({split}); mean rel RMSE {:.2} %",
            m.label(),
            total.as_secs_f64() * 1e3,
            100.0 * mean(0)
        );
        let samples = match m {
            Method::Raymarch { samples, .. } => samples.to_string(),
            Method::Ivsv {
                interleave,
                sampling,
                ..
            } => format!("i{interleave}{}", sampling.marker_suffix()),
        };
        let _ = writeln!(
            csv,
            "{},{},{samples},{:.6},{:.6},{:.6},\"{split}\",{:.3}",
            m.label(),
            m.vpls(),
            mean(0),
            worst,
            mean(1),
            total.as_secs_f64() * 1e3
        );
        rows.push((m, mean(0), worst, mean(1), total, split));
    }
    let mut md = format!(
        "# area_ivsv against per-VPL ray marching\n\n`cargo run --release -p scatter-examples --example area_bench` (adapter: {}). Error: against the `vpl` truth on the 12 area poses at {ew}x{eh} (mean and worst rel RMSE, mean rel L1); time: median pass wall times on `area_columns/ordinary` at {tw}x{th}, {} frames after a warm-up, {}^2 VPL maps.\n\n| method | mean rel RMSE | worst rel RMSE | mean rel L1 | time (ms) | passes (ms) |\n|---|---|---|---|---|---|\n",
        ctx.report(),
        args.frames,
        args.map_size
    );
    for (m, rmse, worst, l1, total, split) in &rows {
        let _ = writeln!(
            md,
            "| {} | {:.2} % | {:.2} % | {:.2} % | {:.1} | {split} |",
            m.label(),
            100.0 * rmse,
            100.0 * worst,
            100.0 * l1,
            total.as_secs_f64() * 1e3
        );
    }
    // Ratio at equal or lower error: per area_ivsv row, the fastest ray march with the same
    // VPLs at or below its mean error.
    md += "\n";
    for ivsv in rows.iter().filter(|r| matches!(r.0, Method::Ivsv { .. })) {
        let n = ivsv.0.vpls();
        let competitor = rows
            .iter()
            .filter(|r| matches!(r.0, Method::Raymarch { vpls, .. } if vpls == n) && r.1 <= ivsv.1)
            .min_by_key(|r| r.4);
        match competitor {
            Some(c) => {
                let _ = writeln!(
                    md,
                    "- {}: the fastest per-VPL ray march at or below its mean error ({}, {:.2} %) takes {:.2}x its time.",
                    ivsv.0.label(),
                    c.0.label(),
                    100.0 * c.1,
                    c.4.as_secs_f64() / ivsv.4.as_secs_f64()
                );
            }
            None => {
                let _ = writeln!(
                    md,
                    "- {}: no per-VPL ray march measured with N = {n} reaches its mean error ({:.2} %).",
                    ivsv.0.label(),
                    100.0 * ivsv.1
                );
            }
        }
    }
    // Sampled rows: speed against the same variant per pixel, and the interpolation error.
    if rows.iter().any(|r| r.0.sampled()) {
        let _ = write!(
            md,
            "\nSampled area_ivsv (a sampled row's errors above are its per-pixel variant's plus the interpolation error below: a bound on its error against the truth): the sampled image against the same variant per pixel on the 12 area poses at {tw}x{th}, and the time against per pixel.\n\n| method | time (ms) | faster than per pixel | interpolation rel L1, mean / worst | interpolation rel RMSE, mean / worst |\n|---|---|---|---|---|\n"
        );
        for (i, r) in rows.iter().enumerate() {
            if !r.0.sampled() {
                continue;
            }
            let Some(p) = rows.iter().find(|q| q.0 == r.0.per_pixel()) else {
                continue;
            };
            let e = &interpolation[i];
            let mean = |f: fn(&(String, f64, f64)) -> f64| {
                e.iter().map(f).sum::<f64>() / e.len().max(1) as f64
            };
            let worst = |f: fn(&(String, f64, f64)) -> f64| e.iter().map(f).fold(0.0, f64::max);
            let _ = writeln!(
                md,
                "| {} | {:.1} | {:.2}x | {:.2} / {:.2} % | {:.2} / {:.2} % |",
                r.0.label(),
                r.4.as_secs_f64() * 1e3,
                p.4.as_secs_f64() / r.4.as_secs_f64(),
                100.0 * mean(|x| x.2),
                100.0 * worst(|x| x.2),
                100.0 * mean(|x| x.1),
                100.0 * worst(|x| x.1),
            );
        }
    }
    std::fs::create_dir_all(&args.out).map_err(|e| e.to_string())?;
    let points: Vec<AreaPoint> = rows
        .iter()
        .map(|(m, rmse, _, _, total, _)| AreaPoint {
            family: match m {
                Method::Ivsv { .. } => Family::AreaIvsv,
                Method::Raymarch { .. } => Family::Raymarch,
            },
            vpls: m.vpls(),
            label: match m {
                Method::Ivsv {
                    vpls,
                    interleave: 1,
                    sampling,
                } => format!("N{vpls}{}", sampling.marker_suffix().replace('-', " ")),
                Method::Ivsv {
                    vpls, interleave, ..
                } => format!("N{vpls} i{interleave}"),
                Method::Raymarch { samples, .. } => format!("n{samples}"),
            },
            ms: total.as_secs_f64() * 1e3,
            error_pct: 100.0 * rmse,
        })
        .collect();
    let chart = write_area_chart(
        &args.out,
        "area",
        &format!(
            "area_ivsv vs per-VPL ray marching ({tw}x{th}, {})",
            ctx.report().driver.split(" (").next().unwrap_or("")
        ),
        "mean rel RMSE vs the vpl truth, 12 area poses (%, log)",
        &points,
    )
    .map_err(|e| e.to_string())?;
    if !chart.is_empty() {
        md += "\n![area_ivsv and per-VPL ray marching: error against time](area.png)\n";
    }
    for (file, text) in [("area.csv", &csv), ("area.md", &md)] {
        let path = args.out.join(file);
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, text).map_err(|e| format!("{}: {e}", tmp.display()))?;
        std::fs::rename(&tmp, &path).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    println!("{md}");
    Ok(())
}
