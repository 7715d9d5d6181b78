//! Rows aligned with the epipolar sampling's slices (`FrameUniforms::fan_origin`,
//! `fan_angles`; variants with `sampling = epipolar`): on the 24 suite poses and random ones,
//! sun and spot, with as many rows as slices and with 2 and 3 times as many (k rows per
//! slice), every point of screen slice s that a pixel sees outside the epipole rings
//!
//! - lies on the plane of row r = k s + k / 2 (row s with as many rows as slices; with an
//!   even k the frame moves the rows half a row so that a slice is not on a boundary between
//!   two): its view ray's slice angle around the light axis is
//!   `row_phi(r)` to 2e-3 of the angle between neighbouring rows (a quarter of it where the
//!   layout clamps a near-infinite epipole, whose lines are only nearly epipolar; measured
//!   up to 0.072 on window/grazing, against up to half a row for rows uniform around the
//!   light axis), so `rectify` casts row s's light rays in the plane of the samples that
//!   read it;
//! - has the row coordinate r + 1/2 (`ray_row_coord`, to 2e-3 rows; wrapped when the
//!   slices go around the origin), so `scatter` and `minmax_traverse` read row r alone;
//!
//! and the frame's fan is the sampling's layout (`common_sampling::epipolar_layout`, which the
//! samples pass computes on the GPU): the same origin, axis, range and wrap. The slices are
//! the layout's, not the frame's: the check is that the two agree. CPU only (the kernels'
//! `row_phi` and `ray_row_coord` are these mirrors' WGSL, checked against them by the
//! conformance trials).

use glam::Vec3;
use scatter_reference::buffers::ShadowMap;
use scatter_reference::bvh::Bvh;
use scatter_reference::kernels::common_epipolar::{
    in_epipole_disc, ray_row_coord, row_phi, screen_dir,
};
use scatter_reference::kernels::common_sampling::{
    EPIPOLE_FAR, EpipolarCamera, epipolar_layout, slice_direction, slice_span,
};
use scatter_reference::kernels::texture::xyz;
use scatter_reference::random_poses;
use scatter_reference::scene::Scene;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_shaderlib::prefiltered::{
    FrameSettings, FrameUniforms, PrefilteredVariant, Resolutions, prepare_frame,
};
use scatter_shaderlib::sampling::SamplingKnobs;

const SCREEN: [u32; 2] = [320, 180];
/// Slices of the sampling.
const SLICES: u32 = 64;
/// Rows of the map per slice.
const ROWS_PER_SLICE: [u32; 3] = [1, 2, 3];
/// Random poses per suite scene (on top of the 24 suite poses).
const RANDOM_PER_SCENE: u32 = 4;
/// Points per slice.
const POINTS: u32 = 24;
/// How far, in rows, a slice's point may lie from its row's plane and row coordinate.
const ROW_BAR: f32 = 2e-3;
/// How far, in rows, a slice's point may lie from its row's plane when the layout clamped
/// its origin (the epipole near infinity, `EPIPOLE_FAR` screens away): its lines are then
/// only nearly epipolar, and the row's plane is the one through the line's midpoint
/// (`fan_phi`). Half the unaligned rows' worst case (half a row): every point stays nearer
/// its own row's plane than any other's.
const CLAMPED_ROW_BAR: f32 = 0.25;

/// The frame of `scene` for the prefiltered default with epipolar sampling of SLICES slices
/// and `k` rows per slice.
fn frame(scene: &Scene, k: u32) -> FrameUniforms {
    let bvh = Bvh::build(&scene.geometry);
    let sm = ShadowMap::build(scene, &bvh, 64).expect("shadow map");
    let variant = PrefilteredVariant {
        light: scene.light.kind(),
        ..PrefilteredVariant::default()
    }
    .with_sampling_knobs(SamplingKnobs::epipolar(SLICES));
    let res = Resolutions {
        screen: SCREEN,
        rectified: [256, k * SLICES],
    };
    prepare_frame(
        &variant,
        &res,
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &sm.desc(),
        &FrameSettings::for_screen(SCREEN[0], SCREEN[1]),
    )
    .unwrap_or_else(|e| panic!("{}: {e}", scene.name))
    .uniforms
}

/// The difference of two angles, in (-pi, pi].
fn angle_diff(a: f32, b: f32) -> f32 {
    (a - b).sin().atan2((a - b).cos())
}

/// The worst deviations of one frame with `per` rows per slice: (row angle, row coordinate,
/// points checked), and its failures.
fn check(name: &str, f: &FrameUniforms, per: u32) -> (f32, f32, u32, Vec<String>) {
    let mut failures = Vec::new();
    let rows = per * SLICES;
    let layout = epipolar_layout(&EpipolarCamera::of_frame(f), SCREEN, SLICES);
    if f.fan_angles[2] <= 0.5 {
        failures.push(format!("{name}: rows not aligned"));
        return (0.0, 0.0, 0, failures);
    }
    let o = [f.fan_origin[0], f.fan_origin[1]];
    let scale = SCREEN[0].max(SCREEN[1]) as f32;
    let origin_off = (o[0] - layout.origin[0]).hypot(o[1] - layout.origin[1]);
    let axis_off = (f.fan_origin[2] - layout.axis[0]).hypot(f.fan_origin[3] - layout.axis[1]);
    // The fan's rows: k per slice, half a row back for an even k.
    let step = layout.dphi / per as f32;
    let start = layout.phi_start
        - if per.is_multiple_of(2) {
            0.5 * step
        } else {
            0.0
        };
    let range_off = (f.fan_angles[0] - start)
        .abs()
        .max((f.fan_angles[1] - step).abs() * rows as f32);
    if origin_off > 1e-5 * scale.max(o[0].abs()).max(o[1].abs())
        || axis_off > 1e-5
        || range_off > 1e-4
        || (f.anti_epipole[3] > 0.5) != layout.wrap
    {
        failures.push(format!(
            "{name}: the frame's fan is not the layout's (origin {origin_off:.2e} px, axis \
             {axis_off:.2e}, range {range_off:.2e}, wrap {} against {})",
            f.anti_epipole[3] > 0.5,
            layout.wrap
        ));
    }
    let centre = [0.5 * SCREEN[0] as f32, 0.5 * SCREEN[1] as f32];
    let clamped = (layout.origin[0] - centre[0]).hypot(layout.origin[1] - centre[1])
        >= 0.999 * EPIPOLE_FAR * scale;
    let plane_bar = if clamped { CLAMPED_ROW_BAR } else { ROW_BAR };
    let (mut worst_phi, mut worst_row, mut points) = (0.0f32, 0.0f32, 0);
    for s in 0..SLICES {
        let r = per * s + per / 2;
        let u = slice_direction(&layout, s);
        let span = slice_span(&layout, s, SCREEN, POINTS);
        for k in 0..POINTS {
            let t = span[0] + k as f32 * span[1];
            let p = [layout.origin[0] + u[0] * t, layout.origin[1] + u[1] * t];
            if in_epipole_disc(f, p) {
                continue;
            }
            let dir: Vec3 = screen_dir(f, p);
            let phi = dir.dot(xyz(f.e2)).atan2(dir.dot(xyz(f.e1)));
            // In rows: the angle between the point's plane and the row's, over the angle
            // between the row's plane and its neighbour's.
            let next = if r + 1 < rows { r + 1 } else { r - 1 };
            let spacing = angle_diff(row_phi(f, next), row_phi(f, r)).abs();
            let dphi = angle_diff(phi, row_phi(f, r)).abs() / spacing;
            let yc = ray_row_coord(f, dir);
            let mut dy = (yc - (r as f32 + 0.5)).abs();
            if f.anti_epipole[3] > 0.5 {
                dy = dy.min(rows as f32 - dy);
            }
            worst_phi = worst_phi.max(dphi);
            worst_row = worst_row.max(dy);
            points += 1;
            if dphi > plane_bar || dy > ROW_BAR {
                failures.push(format!(
                    "{name}: slice {s} point {k} ({:.1}, {:.1}): plane off by {dphi:.2e} rows, \
                     row coordinate {yc:.4} for row {r} of {rows}",
                    p[0], p[1]
                ));
            }
        }
    }
    (worst_phi, worst_row, points, failures)
}

#[test]
fn sampled_rows_lie_on_their_slices() {
    let mut scenes: Vec<Scene> = Vec::new();
    for &name in SceneName::ALL {
        for &pose in Pose::ALL {
            scenes.push(suite::scene(
                name,
                pose,
                MediumPreset::Default,
                SCREEN[0],
                SCREEN[1],
            ));
        }
    }
    scenes.extend(
        random_poses::poses(0xa119_0ed5, RANDOM_PER_SCENE, SCREEN[0], SCREEN[1])
            .into_iter()
            .map(|p| p.scene),
    );
    let mut failures = Vec::new();
    let mut total = 0;
    for scene in &scenes {
        for k in ROWS_PER_SLICE {
            let f = frame(scene, k);
            let (phi, row, points, fails) = check(&scene.name, &f, k);
            println!(
                "{} ({k} rows per slice): plane {phi:.2e} rows, row coordinate {row:.2e} rows \
                 ({points} points)",
                scene.name
            );
            total += points;
            failures.extend(fails);
        }
    }
    assert!(total > 0, "no point checked");
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures[..failures.len().min(20)].join("\n")
    );
}

/// Per-pixel variants keep rows uniform in the angle around the light axis (no fan).
#[test]
fn per_pixel_rows_are_not_aligned() {
    let scene = suite::scene(
        SceneName::ALL[0],
        Pose::ALL[0],
        MediumPreset::Default,
        SCREEN[0],
        SCREEN[1],
    );
    let bvh = Bvh::build(&scene.geometry);
    let sm = ShadowMap::build(&scene, &bvh, 64).expect("shadow map");
    let f = prepare_frame(
        &PrefilteredVariant::default(),
        &Resolutions {
            screen: SCREEN,
            rectified: [256, SLICES],
        },
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &sm.desc(),
        &FrameSettings::for_screen(SCREEN[0], SCREEN[1]),
    )
    .expect("frame")
    .uniforms;
    assert_eq!(f.fan_angles, [0.0; 4]);
    assert_eq!(f.fan_origin, [0.0; 4]);
}
