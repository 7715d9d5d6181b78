//! Before/after fingerprints of every family's GPU outputs: the redesign that moved each
//! family onto the one plan-driven executor (issue 11) must not change a single output bit.
//!
//! For a covering set of variants (the whole `raymarch` and `minmax` grids, every 31st
//! variant of the prefiltered conformance grid, which touches every value of every knob) on
//! small suite frames (`columns` for the sun, `spot_grate` for the spot lamp, `ordinary` and
//! `epipole_on_screen` poses; 48x27 pixels, 64x32 rectified map, 128^2 shadow map), the test
//! hashes every texture the runtime reads back (FNV-1a over the f32 bits) and compares the
//! hashes with `tests/data/fingerprints.txt`, which was written by this same file run on the
//! commit before the redesign (45a9458, the hand-wired runtime). Re-blessed once since, for
//! an intended change of outputs (issue 12, equiangular spot marches): only the 60 spot lines
//! of the marches moved (the prefiltered and minmax `output` on `spot_grate/epipole_on_screen`,
//! whose epipole disc is marched, and the raymarch spot `partial` and `output`); every
//! directional line and every intermediate (`rectified`, `filtered`, `tree`) kept its bits.
//!
//! The hashes are those of lavapipe (Mesa 22.3.6, LLVM 15): another driver may round
//! differently, so on any other adapter the test prints a loud skip and asserts nothing;
//! the conformance tests still compare every output with the CPU mirrors there.
//! `SCATTER_BLESS_FINGERPRINTS=1` rewrites the file (only ever from a commit whose outputs
//! are meant to be the reference).

use std::fmt::Write as _;
use std::path::PathBuf;

use scatter_conformance::{Fixture, gpu};
use scatter_reference::kernels::engine_rectified_map;
use scatter_reference::suite::{Pose, SceneName};
use scatter_runtime::{
    CpuInputs, FrameInput, run_minmax_once, run_prefiltered_once, run_raymarch_once,
};
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::prefiltered::{
    FrameSettings, LightKind, PrefilteredVariant, Rectification, Resolutions, prepare_frame,
};
use scatter_shaderlib::raymarch::RaymarchVariant;

const SCREEN: [u32; 2] = [48, 27];
const RECTIFIED: [u32; 2] = [64, 32];
const SHADOW_MAP: u32 = 128;

fn frame_input(f: &Fixture) -> FrameInput {
    f.frame_input(FrameSettings::for_screen(SCREEN[0], SCREEN[1]))
}

/// FNV-1a over the bits of every value.
fn hash(values: impl IntoIterator<Item = f32>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in values {
        for b in v.to_bits().to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

fn flat4(v: &[[f32; 4]]) -> impl Iterator<Item = f32> + '_ {
    v.iter().flatten().copied()
}

fn res() -> Resolutions {
    Resolutions {
        screen: SCREEN,
        rectified: RECTIFIED,
    }
}

/// Every line `<trial> <texture> <hash>` of the current outputs, sorted by trial.
fn fingerprints(ctx: &scatter_runtime::Context) -> String {
    let fixtures: Vec<Fixture> = [SceneName::Columns, SceneName::SpotGrate]
        .into_iter()
        .flat_map(|s| {
            [Pose::Ordinary, Pose::EpipoleOnScreen].map(|p| Fixture::new(s, p, SCREEN, SHADOW_MAP))
        })
        .collect();
    let for_light = |light: LightKind| {
        let want = if light == LightKind::Spot {
            SceneName::SpotGrate
        } else {
            SceneName::Columns
        };
        fixtures.iter().filter(move |f| f.name == want)
    };
    let mut out = String::new();
    let mut line = |trial: &str, texture: &str, h: u64| {
        writeln!(out, "{trial} {texture} {h:016x}").unwrap_or_else(|e| panic!("{e}"));
    };

    let prefiltered: Vec<PrefilteredVariant> = PrefilteredVariant::grid(1..=4)
        .into_iter()
        .step_by(31)
        .collect();
    for v in &prefiltered {
        for f in for_light(v.light) {
            let trial = format!("prefiltered::{}::{}", v.id(), f.trial_tail());
            // A cookie variant reads the `stained_glass` pattern, as the raymarch ones below.
            let f = if v.cookie {
                &f.with_cookie(
                    scatter_reference::cookie::Cookie::pattern("stained_glass", 64)
                        .expect("a built-in pattern"),
                )
            } else {
                f
            };
            let input = frame_input(f);
            let rectified = if v.rectification == Rectification::Projective {
                let frame = prepare_frame(
                    v,
                    &res(),
                    &input.camera,
                    &input.light,
                    &input.medium,
                    &input.shadow_map,
                    &input.settings,
                )
                .unwrap_or_else(|e| panic!("{trial}: frame set-up: {e}"));
                engine_rectified_map(&f.scene, &f.bvh, &frame)
            } else {
                None
            };
            let gpu = run_prefiltered_once(
                ctx,
                v,
                res(),
                &CpuInputs {
                    frame: input,
                    depth: f.gbuf.view_depth.clone(),
                    shadow_map: f.shadow_map.depth.clone(),
                    rectified,
                    pass_wall_frames: 0,
                    cookie: f.cookie(),
                    vpl_maps: None,
                },
            )
            .unwrap_or_else(|e| panic!("{trial}: {e}"));
            line(&trial, "rectified", hash(gpu.rectified.iter().copied()));
            line(&trial, "filtered", hash(flat4(&gpu.filtered)));
            line(&trial, "output", hash(flat4(&gpu.output)));
        }
    }

    for v in RaymarchVariant::grid() {
        for f in for_light(v.light).filter(|f| f.pose == Pose::Ordinary) {
            let trial = format!("raymarch::{}::{}", v.id(), f.trial_tail());
            let f = if v.cookie {
                &f.with_cookie(
                    scatter_reference::cookie::Cookie::pattern("stained_glass", 64)
                        .expect("a built-in pattern"),
                )
            } else {
                f
            };
            let gpu = run_raymarch_once(
                ctx,
                &v,
                SCREEN,
                &f.raymarch_input(),
                &f.gbuf.view_depth,
                &f.shadow_map.depth,
                f.cookie().as_ref().map(|(size, t)| (*size, &t[..])),
            )
            .unwrap_or_else(|e| panic!("{trial}: {e}"));
            if let Some(partial) = &gpu.partial {
                line(&trial, "partial", hash(flat4(partial)));
            }
            line(&trial, "output", hash(flat4(&gpu.output)));
        }
    }

    for v in MinmaxVariant::grid() {
        for f in for_light(v.light) {
            let trial = format!("minmax::{}::{}", v.id(), f.trial_tail());
            let f = if v.cookie {
                &f.with_cookie(
                    scatter_reference::cookie::Cookie::pattern("stained_glass", 64)
                        .expect("a built-in pattern"),
                )
            } else {
                f
            };
            let gpu = run_minmax_once(
                ctx,
                &v,
                res(),
                &frame_input(f),
                &f.gbuf.view_depth,
                &f.shadow_map.depth,
                f.cookie().as_ref().map(|(size, t)| (*size, &t[..])),
            )
            .unwrap_or_else(|e| panic!("{trial}: {e}"));
            line(&trial, "rectified", hash(gpu.rectified.iter().copied()));
            line(&trial, "tree", hash(gpu.tree.iter().flatten().copied()));
            line(&trial, "output", hash(flat4(&gpu.output)));
        }
    }
    out
}

#[test]
fn every_family_outputs_the_pre_redesign_bits() {
    let Some(ctx) = gpu() else { return };
    let adapter = ctx.report().name.clone();
    if !adapter.contains("llvmpipe") {
        eprintln!(
            "fingerprints: !!! SKIPPED: the recorded hashes are lavapipe's, this adapter is \
             {adapter:?} !!!"
        );
        return;
    }
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/fingerprints.txt");
    let now = fingerprints(ctx);
    if std::env::var_os("SCATTER_BLESS_FINGERPRINTS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap_or_else(|| panic!("no parent")))
            .unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(&path, &now).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        eprintln!("fingerprints: blessed {} lines", now.lines().count());
        return;
    }
    let recorded = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (bless it on the reference commit)", path.display()));
    // Keyed by trial and texture (the line without its hash), so that a texture added or
    // removed is reported as such, not as every later line differing.
    let key = |line: &str| {
        line.rsplit_once(' ')
            .map_or(line.to_owned(), |(k, _)| k.to_owned())
    };
    let recorded_keys: std::collections::BTreeMap<String, &str> =
        recorded.lines().map(|l| (key(l), l)).collect();
    let now_keys: std::collections::BTreeMap<String, &str> =
        now.lines().map(|l| (key(l), l)).collect();
    let differ: Vec<_> = recorded_keys
        .iter()
        .filter_map(|(k, a)| {
            now_keys
                .get(k)
                .filter(|b| *b != a)
                .map(|b| format!("  recorded {a}\n  now      {b}"))
        })
        .collect();
    let gone: Vec<_> = recorded_keys
        .keys()
        .filter(|k| !now_keys.contains_key(*k))
        .collect();
    let added: Vec<_> = now_keys
        .keys()
        .filter(|k| !recorded_keys.contains_key(*k))
        .collect();
    eprintln!(
        "fingerprints: {} textures compared, {} differ, {} no longer made, {} new",
        now.lines().count(),
        differ.len(),
        gone.len(),
        added.len()
    );
    assert!(
        gone.is_empty() && added.is_empty(),
        "the set of fingerprinted textures changed (bless on purpose with \
         SCATTER_BLESS_FINGERPRINTS=1): no longer made {gone:#?}, new {added:#?}"
    );
    assert!(
        differ.is_empty(),
        "{} textures differ from the pre-redesign outputs:\n{}",
        differ.len(),
        differ.join("\n")
    );
}
