//! The stress suite (issue 6): every family on every configuration of
//! `scatter_reference::stress` (poses where methods break, extreme media, extreme knobs and
//! sizes), on the GPU (lavapipe in CI; the CPU mirrors when no GPU is allowed), at 160x90
//! with a 1024^2 shadow map and a 512x256 rectified map.
//!
//! Asserted:
//! - every case's premise holds (the sun really is on the centre pixel, the eye really is
//!   in shadow, ...);
//! - 0 NaN/Inf pixels in every output of every family on every case;
//! - with no in-scattering (`sigma_t = 0`, albedo 0) and where no light reaches the view
//!   (`closed_room`: the truth is exactly 0, checked) every output is
//!   exactly 0;
//! - prefiltered (M = 32, R = 3, weighted, epipolar and projective) within 5 % rel L1 of the
//!   `shadow_map` truth on every stress pose (the projective variant on `near_cuts_geometry`
//!   excepted, at its measured value: see `PROJECTIVE_EXCEPTIONS`);
//! - bars apply on top of the rgba16float floor (the truth's own rel L1 once rounded to f16);
//! - raymarch converges: N = 256 beats N = 16 on every case, and is within 2 % on every
//!   case of at least 1000 pixels;
//! - minmax within 5 % on every case, and partial_sum_tree (its default: rank 4, 512 x 256
//!   epipolar samples) and hybrid_volume (its default: 32 samples in each pixel's interval)
//!   too;
//! - the moment basis (4 moments with 3 regions, 6 with 8; issue 13) within the same 5 % on
//!   every stress pose, 4 moments excepted on two poses (`MOMENTS4_EXCEPTIONS`). The cases
//!   where moments are known to fail (Peters et al.): light leaking where a region's depths
//!   span a large range (`closed_room`: exactly 0 through the depth bounds;
//!   `closed_room_windows`: walls, ceiling and lit floor in one region; `sky`,
//!   `sky_infinite`: depths at the far plane) and precision loss (`rectified_4096`: the
//!   longest f32 running mean; `sigma_t_1e-6`: radiance among f16's subnormals);
//! - prefiltered with average visibility (3 regions): finite and exact zeros only (it is
//!   11-28 % off on `closed_room_windows` and the spot poses; its accuracy bars, at 8
//!   regions, are in `prefiltered_truth`);
//! - sampled (`sampling = lowres`, scale 4, and `sampling = epipolar` at its defaults:
//!   every family's default): finite and exact zeros as above, and the prefiltered and
//!   minmax bars above (the sampled raymarch N = 64 has no bar of its own, as N = 64 per
//!   pixel);
//! - the safe paths: epipole or anti-epipole on screen -> the neighbourhood is ray-marched
//!   (`FrameReport::marched_radius_px`) and a projective variant falls back to epipolar with
//!   the reason, its output then equal to the epipolar variant's.
//!
//! `cargo test --release -p scatter-conformance --test stress -- --nocapture` prints the
//! table of the closing note.

use scatter_conformance::{gpu, run_variant};
use scatter_reference::buffers::{GBuffer, ShadowMap};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::kernels::CpuFrame;
use scatter_reference::kernels::texture::quantise;
use scatter_reference::metrics;
use scatter_reference::stress::{self, Premise, StressCase, StressGroup};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_runtime::{Context, FrameInput};
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::hybrid_volume::HybridVolumeVariant;
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::partial_sum_tree::PartialSumTreeVariant;
use scatter_shaderlib::prefiltered::{
    Basis, FrameReport, FrameSettings, LightKind, PrefilteredVariant, ProjectiveFallback,
    Rectification, Resolutions, Storage, VisibilityMode,
};
use scatter_shaderlib::raymarch::RaymarchVariant;
use scatter_shaderlib::sampling::SamplingKnobs;

const SCREEN: [u32; 2] = [160, 90];
const RECTIFIED: [u32; 2] = [512, 256];
const SHADOW_MAP: u32 = 1024;

/// The prefiltered bar on stress poses (issue 6).
const PREFILTERED_POSE_BAR: f64 = 0.05;
/// Raymarch N = 256 on every case.
const RAYMARCH_256_BAR: f64 = 0.02;
/// Minmax on every case.
const MINMAX_BAR: f64 = 0.05;
/// Most the partial-sum-tree default (rank 4, 512 x 256 samples) may differ from the truth on
/// any case: minmax's bar (the same rectified map; the rank-4 integrand adds well under 1 %).
const PARTIAL_SUM_TREE_BAR: f64 = 0.05;
/// Most the hybrid_volume default (32 samples in each pixel's interval, 256 bins) may
/// differ from the truth on any case: the bar of every family's default.
const HYBRID_VOLUME_BAR: f64 = 0.05;
/// Cases below this many pixels get no raymarch accuracy bar (only convergence): one ray's
/// error is that ray's quadrature error (a few shadow edges each misplaced by up to half a
/// cell), not a mean over many rays whose signs differ (`screen_1x1`: 5.90 / 1.72 / 2.89 %
/// at N = 16 / 64 / 256).
const RAYMARCH_BAR_MIN_PIXELS: usize = 1000;

/// Stress poses where the projective variant misses the prefiltered bar, with the measured
/// value plus 10 % as its ceiling and the reason. The epipolar default meets the bar there.
const PROJECTIVE_EXCEPTIONS: &[(&str, f64, &str)] = &[(
    "near_cuts_geometry",
    0.082,
    "a projective map starts at the near plane (G = 1/qx is infinite at the eye), so the \
     0.6 m of each view ray in front of it take the first region's visibility; rays that end \
     within 2 m (the column cut by the near plane) carry 5.5 of the 7.4 %",
)];

/// Stress poses where the moment basis with 4 moments and 3 regions misses the prefiltered
/// bar: (case, measured rel L1 plus about 10 %, why). 6 moments with 8 or 16 regions meet
/// the bar on every case (stop 57: 0.49 / 0.30 % on closed_room_windows, 1.83 / 1.27 % on
/// epipole_corner).
const MOMENTS4_EXCEPTIONS: &[(&str, f64, &str)] = &[
    (
        "closed_room_windows",
        0.158,
        "14.3 %: a region's texels hold the room's walls, ceiling and the lit floor behind the \
         windows, and a ray's depth falls inside that range; 4 moments put an atom of up to a \
         third of the weight at the ray's depth, half of it counted wrong (6 moments, 8 \
         regions: 0.49 %, 16 regions: 0.30 %; the Fourier default 1.48 %)",
    ),
    (
        "epipole_corner",
        0.075,
        "6.60 %: the epipole in a corner stretches the slices over the whole screen, so the \
         3 regions span most of the scene's depths (6 moments, 8 regions: 1.83 %, 16 \
         regions: 1.27 %)",
    ),
];

/// Dark cases (the truth exactly 0) where a variant's output is not exactly 0: (case, the
/// prefiltered rectification, the greatest output asserted instead, why). Empty since the
/// default has 4 regions (stop 35): with 3, the projective `closed_room` reached 5.19e-4 on
/// pixels 5.8-6.7 m away (0.30 % of the window scene's lit maximum; the projective map's
/// texel-centre light rays missed the 0.3 m wall there, exactly 0 at a 2048x1024 map); with
/// 4 it measures exactly 0, as the epipolar frame always did (the regions' boundaries moved;
/// not analysed further).
const DARK_EXCEPTIONS: &[(&str, Rectification, f64, &str)] = &[];

/// The variants run on every case (directional; each case sets the light, and the
/// prefiltered Fourier bases where it stresses them): the prefiltered default, epipolar and
/// projective, and with average visibility; the moment basis with 4 moments (3 regions) and
/// 6 (8 and 16 regions); raymarch N = 16, 64 and 256; minmax; then the sampled ones.
fn methods() -> Vec<FamilyVariant> {
    let raymarch = |samples| {
        FamilyVariant::Raymarch(RaymarchVariant {
            samples,
            ..RaymarchVariant::default()
        })
    };
    vec![
        PrefilteredVariant::default().into(),
        PrefilteredVariant {
            rectification: Rectification::Projective,
            ..PrefilteredVariant::default()
        }
        .into(),
        PrefilteredVariant {
            visibility: VisibilityMode::Average,
            ..PrefilteredVariant::default()
        }
        .into(),
        PrefilteredVariant {
            regions: 3,
            ..PrefilteredVariant::with_moments(4)
        }
        .into(),
        PrefilteredVariant {
            regions: 8,
            ..PrefilteredVariant::with_moments(6)
        }
        .into(),
        // Issue 13: the moment basis's most accurate configuration (its bars on every suite
        // pose at 1024x1024, `prefiltered_truth`), 16 regions of 32 columns on this map.
        PrefilteredVariant {
            regions: 16,
            ..PrefilteredVariant::with_moments(6)
        }
        .into(),
        raymarch(16),
        raymarch(64),
        raymarch(256),
        MinmaxVariant::default().into(),
        // Issue 14: every family's default at a quarter of the screen per axis.
        FamilyVariant::from(PrefilteredVariant::default()).with_sampling(SamplingKnobs::lowres(4)),
        raymarch(64).with_sampling(SamplingKnobs::lowres(4)),
        FamilyVariant::from(MinmaxVariant::default()).with_sampling(SamplingKnobs::lowres(4)),
        // And epipolar at its defaults.
        FamilyVariant::from(PrefilteredVariant::default()).with_sampling(epipolar()),
        // The prefiltered default storing every eighth column and resuming between them
        // (`resume`: the bench's sampled prefiltered frame, docs/roofline.md "Stop 58").
        FamilyVariant::from(PrefilteredVariant {
            filtered_stride: 8,
            resume: true,
            ..PrefilteredVariant::default()
        })
        .with_sampling(epipolar()),
        raymarch(64).with_sampling(epipolar()),
        FamilyVariant::from(MinmaxVariant::default()).with_sampling(epipolar()),
        // Issue 15: partial-sum trees (epipolar samples only, every sample answered).
        PartialSumTreeVariant::default().into(),
        // Issue 16: hybrid shadow volumes (the eye in shadow, wide shadow coverage and
        // foliage are stress poses here).
        HybridVolumeVariant::default().into(),
    ]
}

/// `sampling = epipolar` at its defaults.
fn epipolar() -> SamplingKnobs {
    SamplingKnobs::epipolar(SamplingKnobs::DEFAULT_SLICES)
}

/// The rectification of a weighted prefiltered variant, or `None`.
fn rectification(m: &FamilyVariant) -> Option<Rectification> {
    match m {
        FamilyVariant::Prefiltered(v) if v.visibility == VisibilityMode::Weighted => {
            Some(v.rectification)
        }
        _ => None,
    }
}

/// Raymarch's sample count, or `None`.
fn samples(m: &FamilyVariant) -> Option<u32> {
    match m {
        FamilyVariant::Raymarch(v) => Some(v.samples),
        _ => None,
    }
}

/// A case prepared once: buffers and truth.
struct Prepared {
    case: StressCase,
    bvh: Bvh,
    gbuf: GBuffer,
    sm: ShadowMap,
    truth: Image,
}

impl Prepared {
    fn new(case: StressCase) -> Prepared {
        let scene = &case.scene;
        let bvh = Bvh::build(&scene.geometry);
        let gbuf = GBuffer::cast(scene, &bvh);
        let sm = ShadowMap::build(scene, &bvh, SHADOW_MAP)
            .unwrap_or_else(|e| panic!("stress::{}: shadow map: {e}", case.name));
        let truth = truth::render(
            scene,
            &gbuf,
            &Visibility::ShadowMap(&sm),
            &TruthSettings::default(),
            &|| (),
        );
        Prepared {
            case,
            bvh,
            gbuf,
            sm,
            truth,
        }
    }

    fn light(&self) -> LightKind {
        self.case.scene.light.kind()
    }

    fn screen(&self) -> [u32; 2] {
        [self.gbuf.width, self.gbuf.height]
    }

    fn frame_input(&self) -> FrameInput {
        let s = &self.case.scene;
        FrameInput {
            camera: s.camera_desc(),
            light: s.light_desc(),
            medium: s.medium_desc(),
            shadow_map: self.sm.desc(),
            settings: FrameSettings::for_screen(self.gbuf.width, self.gbuf.height),
        }
    }

    fn resolutions(&self) -> Resolutions {
        Resolutions {
            screen: self.screen(),
            rectified: self.case.rectified.unwrap_or(RECTIFIED),
        }
    }

    /// `method` as this case runs it: the case's light (with its cookie where the spot has
    /// one: every family reads it), and the case's bases for the prefiltered family.
    fn variant(&self, method: &FamilyVariant) -> FamilyVariant {
        let mut v = method.with_light(self.light());
        if self.case.scene.light.cookie().is_some() {
            v = v.with_cookie(true).unwrap_or(v);
        }
        if let (FamilyVariant::Prefiltered(p), Some(bases)) = (&mut v, self.case.bases)
            && p.basis == Basis::Fourier
        {
            p.bases = bases;
            p.bases_per_thread = bases.min(p.bases_per_thread);
        }
        v
    }

    /// Whether the case's rectified map is wide enough for `method` (a prefiltered variant
    /// needs `filtered_stride x regions^2` columns: 16 regions do not fit `rectified_64`).
    fn fits(&self, method: &FamilyVariant) -> bool {
        self.variant(method)
            .fits_rectified_width(self.resolutions().rectified[0])
    }

    /// Runs `method` on the GPU (or its CPU mirrors without one): the output and, for the
    /// families with a frame set-up, the frame report.
    fn run(
        &self,
        ctx: Option<&Context>,
        method: &FamilyVariant,
    ) -> Result<(Image, Option<FrameReport>), String> {
        let gbuf = GBuffer {
            view_depth: self.case.engine_depth(&self.gbuf),
            ..self.gbuf.clone()
        };
        let settings = self.frame_input().settings;
        run_variant(
            ctx,
            &self.variant(method),
            &CpuFrame {
                scene: &self.case.scene,
                bvh: &self.bvh,
                gbuf: &gbuf,
                shadow_map: &self.sm,
                rectified: self.resolutions().rectified,
                settings: &settings,
            },
        )
    }
}

/// One measured cell of the table.
struct Cell {
    method: FamilyVariant,
    rel_l1: f64,
    non_finite: usize,
    max_abs: f32,
}

#[test]
fn every_family_survives_every_stress_case() {
    let ctx = gpu();
    let backend = if ctx.is_some() { "GPU" } else { "CPU mirror" };
    let mut failures: Vec<String> = Vec::new();
    let methods = methods();
    let labels: Vec<String> = methods.iter().map(FamilyVariant::label).collect();
    let mut table = vec![format!(
        "| group | case | truth max | f16 floor | {} | notes |",
        labels.join(" | ")
    )];
    table.push(format!(
        "|---|---|---|---|{}---|",
        "---|".repeat(methods.len())
    ));
    for case in stress::cases(SCREEN[0], SCREEN[1]) {
        let p = Prepared::new(case);
        let name = p.case.name;
        if let Err(e) = p.case.premise(&p.bvh, &p.gbuf) {
            failures.push(e);
        }
        // Every output is stored in rgba16float: the truth rounded to it is as close as any
        // method can get (2.3 % at sigma_t = 1e-6, whose radiance lies among f16's
        // subnormals); bars apply on top of this floor.
        let rounded = Image::from_pixels(
            p.truth.width,
            p.truth.height,
            p.truth
                .data
                .iter()
                .map(|c| c.map(|v| quantise(v, Storage::Rgba16float)))
                .collect(),
        );
        let floor = metrics::compare(&rounded, &p.truth)
            .expect("same size")
            .rel_l1;
        let pixels = p.truth.data.len();
        let truth_max = p
            .truth
            .data
            .iter()
            .flat_map(|c| c.iter().copied())
            .fold(0.0f32, f32::max);
        if p.case.premise == Premise::Dark && truth_max != 0.0 {
            failures.push(format!(
                "stress case {name}: the premise says no light reaches the camera's view, yet the truth reaches {truth_max:e}"
            ));
        }
        let mut cells = Vec::new();
        let mut reports = Vec::new();
        let mut outputs = Vec::new();
        for &method in &methods {
            let trial = format!("stress::{}::{name}", method.label());
            if !p.fits(&method) {
                // A map too narrow for the variant's regions is refused with a clear error
                // (`FrameError::RectifiedTooNarrow`); the table says so instead of a number.
                continue;
            }
            match p.run(ctx, &method) {
                Ok((image, report)) => {
                    let e = metrics::compare(&image, &p.truth).expect("same size");
                    let max_abs = image
                        .data
                        .iter()
                        .flat_map(|c| c.iter().map(|v| v.abs()))
                        .fold(0.0f32, f32::max);
                    cells.push(Cell {
                        method,
                        rel_l1: e.rel_l1,
                        non_finite: e.non_finite,
                        max_abs,
                    });
                    reports.push((method, report));
                    outputs.push((method, image));
                }
                Err(e) => failures.push(format!("{trial}: run failed: {e}")),
            }
        }
        let cell = |m: FamilyVariant| cells.iter().find(|c| c.method == m);
        // The methods the checks below single out.
        let find = |f: &dyn Fn(&FamilyVariant) -> bool| methods.iter().copied().find(|m| f(m));
        let epipolar = find(&|m| rectification(m) == Some(Rectification::Epipolar));
        let projective = find(&|m| rectification(m) == Some(Rectification::Projective));
        let coarse = find(&|m| samples(m) == Some(16));
        let fine = find(&|m| samples(m) == Some(256));
        for c in &cells {
            let trial = format!("stress::{}::{name}", c.method.label());
            if c.non_finite > 0 {
                failures.push(format!("{trial}: {} NaN/Inf pixels", c.non_finite));
            }
            let dark = DARK_EXCEPTIONS
                .iter()
                .find(|e| e.0 == name && rectification(&c.method) == Some(e.1));
            if let Some(e) = dark {
                if c.max_abs == 0.0 {
                    failures.push(format!(
                        "{trial}: outputs exactly 0 now: remove it from DARK_EXCEPTIONS ({})",
                        e.3
                    ));
                } else if !within(f64::from(c.max_abs), e.2) {
                    failures.push(format!(
                        "{trial}: the truth is 0 everywhere, yet the output reaches {:e} (listed in DARK_EXCEPTIONS up to {:e}: {})",
                        c.max_abs, e.2, e.3
                    ));
                }
            } else if truth_max == 0.0 && c.max_abs != 0.0 {
                failures.push(format!(
                    "{trial}: the truth is 0 everywhere (no in-scattering, or no light reaching the view), yet the output reaches {:e}",
                    c.max_abs
                ));
            }
            let exception = PROJECTIVE_EXCEPTIONS.iter().find(|e| {
                e.0 == name && rectification(&c.method) == Some(Rectification::Projective)
            });
            let moments4 = MOMENTS4_EXCEPTIONS.iter().find(|e| {
                e.0 == name
                    && matches!(c.method, FamilyVariant::Prefiltered(v) if v.basis == Basis::Moments && v.moments == 4)
            });
            let bar = match c.method {
                // Average visibility: finite and exact zeros only here (with 3 regions it is
                // 11-28 % off on closed_room_windows and the spot poses); its bars are in
                // prefiltered_truth (`average_visibility_on_every_pose`, 8 regions).
                FamilyVariant::Prefiltered(v) if v.visibility == VisibilityMode::Average => None,
                FamilyVariant::Prefiltered(_) if p.case.group == StressGroup::Pose => {
                    Some(exception.or(moments4).map_or(PREFILTERED_POSE_BAR, |e| e.1))
                }
                FamilyVariant::Raymarch(v)
                    if v.samples == 256 && pixels >= RAYMARCH_BAR_MIN_PIXELS =>
                {
                    Some(RAYMARCH_256_BAR)
                }
                FamilyVariant::Minmax(_) => Some(MINMAX_BAR),
                FamilyVariant::PartialSumTree(_) => Some(PARTIAL_SUM_TREE_BAR),
                FamilyVariant::HybridVolume(_) => Some(HYBRID_VOLUME_BAR),
                _ => None,
            };
            // Where the truth is 0 the checks above hold the output to 0 (rel L1 is undefined).
            if let Some(bar) = bar
                && truth_max > 0.0
                && !within(c.rel_l1, bar + floor)
            {
                failures.push(format!(
                    "{trial}: rel L1 {:.3} % exceeds the bar {:.1} % (+ the f16 floor {:.3} %){}",
                    100.0 * c.rel_l1,
                    100.0 * bar,
                    100.0 * floor,
                    exception.map_or(String::new(), |e| format!(" [exception: {}]", e.2))
                ));
            }
            if let Some(e) = exception
                && c.rel_l1 <= PREFILTERED_POSE_BAR
            {
                failures.push(format!(
                    "{trial}: meets the {:.0} % bar now ({:.3} %): remove it from PROJECTIVE_EXCEPTIONS ({})",
                    100.0 * PREFILTERED_POSE_BAR,
                    100.0 * c.rel_l1,
                    e.2
                ));
            }
            if let Some(e) = moments4
                && c.rel_l1 <= PREFILTERED_POSE_BAR
            {
                failures.push(format!(
                    "{trial}: meets the {:.0} % bar now ({:.3} %): remove it from MOMENTS4_EXCEPTIONS ({})",
                    100.0 * PREFILTERED_POSE_BAR,
                    100.0 * c.rel_l1,
                    e.2
                ));
            }
        }
        if let (Some(a), Some(b)) = (coarse.and_then(cell), fine.and_then(cell))
            && truth_max > 0.0
            && !(b.rel_l1 < a.rel_l1 || b.rel_l1 < 1e-3)
        {
            failures.push(format!(
                "stress::raymarch::{name}: does not converge: N=16 {:.3} %, N=256 {:.3} %",
                100.0 * a.rel_l1,
                100.0 * b.rel_l1
            ));
        }
        // The safe paths, from the epipolar variant's report.
        let report = |m: Option<FamilyVariant>| {
            reports
                .iter()
                .find(|r| Some(r.0) == m)
                .and_then(|r| r.1.clone())
        };
        let mut notes = Vec::new();
        if let Some(r) = report(epipolar) {
            let on_screen = r.epipole_on_screen || r.anti_epipole_on_screen;
            if on_screen != r.marched_radius_px.is_some() {
                failures.push(format!(
                    "stress::prefiltered::{name}: epipole/anti-epipole on screen = {on_screen} but marched radius = {:?}",
                    r.marched_radius_px
                ));
            }
            if let Some(px) = r.marched_radius_px {
                notes.push(format!("marched r={px:.1}px"));
            }
        }
        if let Some(r) = report(projective) {
            match (&r.fallback, r.rectification) {
                (Some(f), Rectification::Epipolar) => {
                    let expected = if r.epipole_on_screen {
                        Some(ProjectiveFallback::EpipoleOnScreen)
                    } else if r.anti_epipole_on_screen {
                        Some(ProjectiveFallback::AntiEpipoleOnScreen)
                    } else {
                        None
                    };
                    if let Some(e) = expected
                        && *f != e
                    {
                        failures.push(format!(
                            "stress::prefiltered-proj::{name}: falls back because {f}, expected {e}"
                        ));
                    }
                    notes.push(format!("proj -> epipolar: {f}"));
                    let image = |m: Option<FamilyVariant>| {
                        outputs.iter().find(|o| Some(o.0) == m).map(|o| &o.1)
                    };
                    if image(projective) != image(epipolar) {
                        failures.push(format!(
                            "stress::prefiltered-proj::{name}: fell back, yet its output differs from the epipolar variant's"
                        ));
                    }
                }
                (None, Rectification::Projective) => notes.push("proj: projective frame".into()),
                other => failures.push(format!(
                    "stress::prefiltered-proj::{name}: inconsistent report {other:?}"
                )),
            }
        }
        let row = methods
            .iter()
            .map(|&m| match cell(m) {
                Some(c) if c.non_finite > 0 => format!("{} NaN", c.non_finite),
                Some(c) if truth_max == 0.0 => format!("max {:e}", c.max_abs),
                Some(c) => format!("{:.2} %", 100.0 * c.rel_l1),
                None if !p.fits(&m) => "map too narrow".into(),
                None => "failed".into(),
            })
            .collect::<Vec<_>>()
            .join(" | ");
        table.push(format!(
            "| {} | {name} | {truth_max:.3e} | {:.3} % | {row} | {} |",
            p.case.group,
            100.0 * floor,
            notes.join("; ")
        ));
    }
    println!(
        "stress suite ({backend}, {}x{}, rectified {}x{} unless the case sets it, shadow map {SHADOW_MAP}^2), rel L1 vs the shadow_map truth:",
        SCREEN[0], SCREEN[1], RECTIFIED[0], RECTIFIED[1]
    );
    for line in &table {
        println!("{line}");
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// `value <= bound`, false when either is NaN (a NaN result must fail, not pass).
fn within(value: f64, bound: f64) -> bool {
    value <= bound
}
