//! Conformance of the `area_ivsv` family (`ivsv_rectify`, `ivsv_scan`, `ivsv_gather`): the GPU
//! (`scatter_runtime::run_area_ivsv_once`) against the CPU mirrors
//! (`reference/src/kernels/ivsv_*.rs`) on every area pose (`area_columns`, `area_window`,
//! `area_grate` x the suite's four poses) for the variants of [`variants`], at 37x21 pixels
//! with 64^2 VPL maps. Trials are named `area_ivsv::<variant id>::<scene>::<pose>`;
//! `area_ivsv::errors` checks the error paths.
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
//!   (reported), and rel L1 over the image <= 1e-3.

use std::process::ExitCode;

use scatter_conformance::{Check, gpu, run_trials};
use scatter_reference::area_suite::{self, AreaSceneName};
use scatter_reference::buffers::GBuffer;
use scatter_reference::bvh::Bvh;
use scatter_reference::kernels::ivsv_rectify::rectify_bit;
use scatter_reference::kernels::texture::Tex;
use scatter_reference::kernels::{IvsvInputs, ivsv_gather, ivsv_inputs, ivsv_scan};
use scatter_reference::suite::{MediumPreset, Pose};
use scatter_runtime::{AreaIvsv, RuntimeError, run_area_ivsv_once};
use scatter_shaderlib::area_ivsv::{AreaIvsvVariant, PHI_BITS};

const SCREEN: [u32; 2] = [37, 21];
const MAP: u32 = 64;

/// The variants: a small default-like grid, and an odd one (3 VPLs, 37 x 19 texels, one
/// segment), and many segments.
fn variants() -> Vec<AreaIvsvVariant> {
    vec![
        AreaIvsvVariant {
            vpls: 8,
            alpha: 64,
            theta: 64,
            segments: 8,
        },
        AreaIvsvVariant {
            vpls: 3,
            alpha: 37,
            theta: 19,
            segments: 1,
        },
        AreaIvsvVariant {
            vpls: 4,
            alpha: 128,
            theta: 96,
            segments: 32,
        },
    ]
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
    let cpu = ivsv_gather::ivsv_gather(m, records, &gpu.volume, &depth, v.segments);
    let max = cpu
        .iter()
        .flat_map(|p| p.iter().copied())
        .fold(0.0f32, f32::max);
    let (mut off, mut diff, mut total) = (0usize, 0.0f64, 0.0f64);
    for (g, c) in gpu.output.iter().zip(&cpu) {
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
        },
        [8, 8],
        16,
    )
    .map_err(|e| e.to_string())?;
    let c = case(AreaSceneName::Grate, Pose::Ordinary, &v);
    let camera = c.scene.camera_desc();
    let medium = c.scene.medium_desc();
    match pass.prepare(ctx, &camera, &medium, &[]) {
        Err(e) if e.to_string().contains("VPL count") => Ok(()),
        other => Err(format!("no VPLs: {other:?}")),
    }
}

fn main() -> ExitCode {
    let mut trials: Vec<(String, Check)> = Vec::new();
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
    trials.push(("area_ivsv::errors".into(), Box::new(errors)));
    run_trials(trials, &[])
}
