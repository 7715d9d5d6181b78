//! The rasterising engine (`scatter_examples::raster`, issue 18) against the ray caster that
//! stands in for it everywhere else: on every suite scene at its `ordinary` and `grazing`
//! poses (320x180, 1024^2 shadow map) the rasterised depth buffer and shadow map agree with
//! the ray-cast ones except at silhouettes, and the prefiltered family's GPU output on the
//! rasterised inputs, read by `scatter-runtime` straight from the render targets, meets the
//! `shadow_map` truth as it does on the ray-cast inputs. The projective rectified map
//! agrees with the ray-casting stand-in (`reference/src/projective.rs`) except at
//! silhouettes and where no view ray reaches ([`PROJECTIVE_REACHED_SHARE`] says where the
//! rest is and why).
//!
//! `cargo test --release -p scatter-examples --test raster -- --nocapture` prints the table.

use glam::{DMat4, DVec3, DVec4};
use scatter_conformance::gpu;
use scatter_examples::raster::{Rasteriser, read_r32float};
use scatter_reference::buffers::{GBuffer, SKY, ShadowMap, ShadowProjection};
use scatter_reference::bvh::Bvh;
use scatter_reference::image::Image;
use scatter_reference::kernels::scene_reach;
use scatter_reference::metrics;
use scatter_reference::projective::rasterise_rectified;
use scatter_reference::scene::Scene;
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{self, TruthSettings, Visibility};
use scatter_runtime::prefiltered::{FrameInput, Inputs};
use scatter_runtime::shaderlib::Kernel;
use scatter_runtime::shaderlib::family::FamilyVariant;
use scatter_runtime::shaderlib::prefiltered::{
    FrameSettings, LightDesc, LightKind, PrefilteredVariant, ProjectiveMaps, Rectification,
    Resolutions,
};
use scatter_runtime::textures::{read_rgba16float, upload_r32float};
use scatter_runtime::wgpu;
use scatter_runtime::{Context, FamilyPasses};

const SCREEN: [u32; 2] = [320, 180];
const SHADOW_MAP: u32 = 1024;
const RECTIFIED: [u32; 2] = [512, 512];
/// Relative view-depth difference that counts as disagreement: 50x the tessellation's chord
/// (1.2e-4 of a radius), far below any step between surfaces.
const DEPTH_TOL: f64 = 5e-3;
/// Normalised light-depth difference that counts as disagreement (the bias is 1.5 texels
/// of footprint; this is a few millimetres on the suite's maps).
const SHADOW_TOL: f64 = 5e-4;
/// Share of all pixels (texels) that may disagree away from silhouettes: none should (a
/// centre on a shared triangle edge falls to one of two triangles of one surface, at one
/// depth); 1e-4 (6 of the 57 600 pixels) leaves room for a rasteriser's tie rules.
/// Measured 0 on every pose (lavapipe).
const INTERIOR_SHARE: f64 = 1e-4;
/// Clip-depth (`z / w`) difference that counts as disagreement in the projective map.
const RECTIFIED_TOL: f64 = 5e-4;
/// Share of all texels of the projective map that may disagree with the stand-in away from
/// silhouettes *where it matters*: some point on the texel's light ray whose clip depth lies
/// between the two maps' values (the points the maps shadow differently) is reached by a
/// view ray (inside the camera frustum, not behind the ray-cast depth buffer's surface:
/// [`reachable`]). The same 1e-4 as the other buffers; measured 0 on every pose but
/// `foliage/grazing` (one texel, 0.0004 %; lavapipe).
///
/// Unreached disagreements remain, measured 2026-12-05 and explained, and are only
/// reported (the table's `unreached` column): `spot_grate/grazing` 0.24 % of the texels,
/// a one-texel line along the ground's horizon as the lamp sees it, where the stand-in's
/// analytic (infinite) ground plane is hit 650 m to 30 km from the lamp at clip depth
/// 0.986-0.998 and the rasteriser's ground, a grid `8 x max(far, light reach)` (here about
/// 400 m) around the camera, has ended: no triangle covers the texel. Making the grid 4x
/// and 16x as wide cut the line's texels from 1324 to 333 and 81 (the horizon recedes but
/// never ends); the camera's far plane is 40 m, so no view ray reaches those points.
/// `sphere/grazing` 0.08 %: texels below the ground, where the rasteriser's clamped ground
/// stores 0 and the stand-in's directional rays, which start `scene_reach` before the map,
/// meet the ground before they start (1); the ground hides every point they decide. Neither
/// is a flaw of the rasteriser or of the README's contract, and neither moves the family's
/// output (the rel L1 columns).
const PROJECTIVE_REACHED_SHARE: f64 = 1e-4;

/// Agreement of a rasterised buffer with the ray-cast one.
struct Agreement {
    /// Share of all pixels that disagree.
    disagree: f64,
    /// Share of all pixels that disagree and are not at a silhouette.
    interior: f64,
    /// Share of all pixels at a silhouette.
    edges: f64,
}

/// Silhouette pixels of a ray-cast buffer: the border, a neighbour (8-connected) on another
/// shape, or a step: the second difference along a row, column or diagonal of
/// `linear(depth)` (a quantity linear in screen space on a plane: 1 / z under a perspective
/// projection, z under an orthographic one), converted to the compared units by
/// `units(depth)`, exceeds `tol`, the tolerance the buffers are compared with. A plane has
/// no such step, a sphere's curvature a negligible one; two surfaces meeting or overlapping
/// (leaves over leaves), a face seen edge-on, do.
fn edges(
    w: usize,
    h: usize,
    depth: &[f32],
    linear: impl Fn(f64) -> f64,
    units: impl Fn(f64) -> f64,
    shape: Option<&[u32]>,
    tol: f64,
) -> Vec<bool> {
    let at = |x: usize, y: usize| linear(f64::from(depth[y * w + x]));
    let mut out = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut edge = x == 0 || y == 0 || x + 1 == w || y + 1 == h;
            if !edge {
                let c = at(x, y);
                let scale = units(f64::from(depth[y * w + x]));
                for (dx, dy) in [(1isize, 0isize), (0, 1), (1, 1), (1, -1)] {
                    let (xa, ya) = ((x as isize + dx) as usize, (y as isize + dy) as usize);
                    let (xb, yb) = ((x as isize - dx) as usize, (y as isize - dy) as usize);
                    let second = at(xa, ya) + at(xb, yb) - 2.0 * c;
                    if second.abs() * scale > tol {
                        edge = true;
                    }
                }
                if let Some(shape) = shape {
                    let s = shape[y * w + x];
                    for (nx, ny) in [
                        (x - 1, y - 1),
                        (x, y - 1),
                        (x + 1, y - 1),
                        (x - 1, y),
                        (x + 1, y),
                        (x - 1, y + 1),
                        (x, y + 1),
                        (x + 1, y + 1),
                    ] {
                        if shape[ny * w + nx] != s {
                            edge = true;
                        }
                    }
                }
            }
            out[y * w + x] = edge;
        }
    }
    out
}

fn agreement(
    raster: &[f32],
    cast: &[f32],
    edge: &[bool],
    differs: impl Fn(f64, f64) -> bool,
) -> Agreement {
    let n = cast.len() as f64;
    let mut disagree = 0usize;
    let mut interior = 0usize;
    for i in 0..cast.len() {
        if differs(f64::from(raster[i]), f64::from(cast[i])) {
            disagree += 1;
            if !edge[i] {
                interior += 1;
            }
        }
    }
    Agreement {
        disagree: disagree as f64 / n,
        interior: interior as f64 / n,
        edges: edge.iter().filter(|e| **e).count() as f64 / n,
    }
}

/// Whether a view ray reaches a point that the projective map's texel at clip `(x, y)`
/// of region matrix `m` decides differently with stored depths `lo < hi`: a point of the
/// texel's light ray (as the stand-in casts it: from the lamp, or from `reach` before the
/// map along a directional light) with clip depth in `(lo, hi]`, inside the camera frustum
/// and not behind the ray-cast surface of its pixel (relative `DEPTH_TOL`). The depth is
/// monotonic along the ray where clip `w > 0` (a ratio of linear functions), so the
/// interval is found by bisection and then sampled for occlusion.
#[allow(clippy::too_many_arguments, reason = "the texel and what decides it")]
fn reachable(
    scene: &Scene,
    gbuf: &GBuffer,
    light: &LightDesc,
    m: &DMat4,
    [x, y]: [f64; 2],
    [lo, hi]: [f64; 2],
    reach: f64,
) -> bool {
    let inv = m.inverse();
    let unproject = |z: f64| {
        let h = inv * DVec4::new(x, y, z, 1.0);
        h.truncate() / h.w
    };
    let (p0, p1) = (unproject(0.0), unproject(1.0));
    let (origin, dir) = match *light {
        LightDesc::Directional { direction, .. } => {
            let l = direction.normalize();
            (p0 - l * reach, l)
        }
        // An area light's projective map is its point limit's.
        LightDesc::Spot { position, .. }
        | LightDesc::Area(scatter_shaderlib::area_ivsv::AreaLightDesc { position, .. }) => {
            let mut v = (p1 - p0).normalize();
            if (*m * v.extend(0.0)).w < 0.0 {
                v = -v;
            }
            (position, v)
        }
    };
    // Clip t >= 0 to the camera frustum: near <= z <= far, |x| <= z t a, |y| <= z t.
    let cam = &scene.camera;
    let f = cam.frame();
    let (ta, tv) = (cam.tan_half_fov() * cam.aspect(), cam.tan_half_fov());
    let view = |p: DVec3| {
        let q = p - cam.position;
        DVec3::new(q.dot(f.right), q.dot(f.up), q.dot(f.forward))
    };
    let (a, b) = (view(origin), view(origin + dir) - view(origin));
    // Each constraint c0 + c1 t >= 0.
    let constraints = [
        (a.z - cam.near, b.z),
        (cam.far - a.z, -b.z),
        (a.z * ta - a.x, b.z * ta - b.x),
        (a.z * ta + a.x, b.z * ta + b.x),
        (a.z * tv - a.y, b.z * tv - b.y),
        (a.z * tv + a.y, b.z * tv + b.y),
    ];
    let (mut t0, mut t1) = (0.0f64, 1e12f64);
    for (c0, c1) in constraints {
        if c1.abs() < 1e-300 {
            if c0 < 0.0 {
                return false;
            }
        } else if c1 > 0.0 {
            t0 = t0.max(-c0 / c1);
        } else {
            t1 = t1.min(-c0 / c1);
        }
    }
    let clip = |t: f64| *m * (origin + dir * t).extend(1.0);
    // Keep clip w > 0 (w is linear in t).
    let (w0, w1) = (clip(t0).w, clip(t1).w);
    if w0 <= 0.0 && w1 <= 0.0 {
        return false;
    }
    if w0 <= 0.0 || w1 <= 0.0 {
        let tz = t0 + (t1 - t0) * w0 / (w0 - w1);
        if w0 <= 0.0 {
            t0 = tz + 1e-9 * (t1 - t0);
        } else {
            t1 = tz - 1e-9 * (t1 - t0);
        }
    }
    if t0 >= t1 {
        return false;
    }
    let depth = |t: f64| {
        let c = clip(t);
        c.z / c.w
    };
    // The t where the monotonic depth crosses `level` inside [t0, t1] (an end if it does
    // not).
    let increasing = depth(t1) >= depth(t0);
    let cross = |level: f64| {
        let (mut l, mut h) = (t0, t1);
        for _ in 0..100 {
            let mid = 0.5 * (l + h);
            if (depth(mid) < level) == increasing {
                l = mid;
            } else {
                h = mid;
            }
        }
        0.5 * (l + h)
    };
    let (mut s0, mut s1) = (cross(lo), cross(hi));
    if s0 > s1 {
        std::mem::swap(&mut s0, &mut s1);
    }
    let (w, h) = (cam.width as usize, cam.height as usize);
    (0..=256).any(|k| {
        let t = s0 + (s1 - s0) * f64::from(k) / 256.0;
        let d = depth(t);
        if !(d > lo && d <= hi) {
            return false;
        }
        let v = view(origin + dir * t);
        let px = ((v.x / (v.z * ta) + 1.0) * 0.5 * w as f64).floor();
        let py = ((1.0 - v.y / (v.z * tv)) * 0.5 * h as f64).floor();
        if !(0.0..w as f64).contains(&px) || !(0.0..h as f64).contains(&py) {
            return false;
        }
        v.z <= f64::from(gbuf.view_depth[py as usize * w + px as usize]) * (1.0 + DEPTH_TOL)
    })
}

/// `variant`'s GPU output from `depth` and `shadow` (textures on the GPU) and, for a
/// projective frame, the rectified map `rectified` makes from the frame's matrices; its rel
/// L1 against `truth` and the frame's projective maps (`None`: the frame fell back).
#[allow(clippy::too_many_arguments, reason = "the frame's inputs")]
fn gpu_error(
    ctx: &Context,
    scene: &Scene,
    shadow_map: &ShadowMap,
    variant: PrefilteredVariant,
    depth: &wgpu::Texture,
    shadow: &wgpu::Texture,
    rectified: impl FnOnce(&ProjectiveMaps) -> wgpu::Texture,
    truth: &Image,
) -> (f64, Option<ProjectiveMaps>) {
    let variant = FamilyVariant::Prefiltered(variant);
    let res = Resolutions {
        screen: SCREEN,
        rectified: RECTIFIED,
    };
    let mut pass = FamilyPasses::new(ctx, &variant, res, SHADOW_MAP)
        .unwrap_or_else(|e| panic!("{variant}: {e}"));
    let report = pass
        .prepare(
            ctx,
            &FrameInput {
                camera: scene.camera_desc(),
                light: scene.light_desc(),
                medium: scene.medium_desc(),
                shadow_map: shadow_map.desc(),
                settings: FrameSettings::for_screen(SCREEN[0], SCREEN[1]),
            },
        )
        .unwrap_or_else(|e| panic!("prepare: {e}"));
    let maps = report.and_then(|r| r.projective);
    let rectified = maps.as_ref().map(rectified);
    let rv = rectified
        .as_ref()
        .map(|t| t.create_view(&Default::default()));
    let (dv, sv) = (
        depth.create_view(&Default::default()),
        shadow.create_view(&Default::default()),
    );
    let mut encoder = ctx.device().create_command_encoder(&Default::default());
    pass.encode(
        ctx,
        &mut encoder,
        &Inputs {
            depth: &dv,
            shadow_map: Some(&sv),
            rectified: rv.as_ref(),
            vpl_maps: None,
        },
    )
    .unwrap_or_else(|e| panic!("encode: {e}"));
    ctx.queue().submit([encoder.finish()]);
    let data = read_rgba16float(ctx, Kernel::Scatter, pass.output_texture())
        .unwrap_or_else(|e| panic!("readback: {e}"));
    let image = Image::from_pixels(
        SCREEN[0],
        SCREEN[1],
        data.iter().map(|c| [c[0], c[1], c[2]]).collect(),
    );
    let report = metrics::compare(&image, truth).expect("same size");
    assert_eq!(report.non_finite, 0, "{}: NaN/Inf", scene.name);
    (report.rel_l1, maps)
}

#[test]
fn rasterised_inputs_agree_with_the_ray_cast_ones_and_feed_the_kernels() {
    let Some(ctx) = gpu() else { return };
    let rasteriser = Rasteriser::new(ctx);
    let mut failures = Vec::new();
    let mut table = vec![
        "| scene/pose | triangles | depth: disagree / interior / edge px | shadow map: disagree / interior / edge texels | prefiltered rel L1: ray-cast inputs / rasterised | projective map: disagree / interior / interior reached / edge texels | projective rel L1: stand-in / rasterised |".to_owned(),
        "|---|---|---|---|---|---|---|".to_owned(),
    ];
    for &name in SceneName::ALL {
        for pose in [Pose::Ordinary, Pose::Grazing] {
            let id = format!("{name}/{pose}");
            let scene = suite::scene(name, pose, MediumPreset::Default, SCREEN[0], SCREEN[1]);
            let bvh = Bvh::build(&scene.geometry);
            let gbuf = GBuffer::cast(&scene, &bvh);
            let sm = ShadowMap::build(&scene, &bvh, SHADOW_MAP).expect("suite shadow map");
            let frame = rasteriser
                .render(ctx, &scene, &bvh, SHADOW_MAP)
                .unwrap_or_else(|e| panic!("{id}: {e}"));
            assert_eq!(frame.shadow_frame.desc(), sm.desc(), "{id}: the fitted map");
            let depth = read_r32float(ctx, &frame.depth).unwrap_or_else(|e| panic!("{e}"));
            let shadow = read_r32float(ctx, &frame.shadow_map).unwrap_or_else(|e| panic!("{e}"));
            let (w, h) = (SCREEN[0] as usize, SCREEN[1] as usize);
            // Compared relatively: d(z) / z = d(1 / z) z.
            let depth_edges = edges(
                w,
                h,
                &gbuf.view_depth,
                |z| 1.0 / z,
                |z| z,
                Some(&gbuf.shape),
                DEPTH_TOL,
            );
            let far = scene.camera.far;
            let d = agreement(&depth, &gbuf.view_depth, &depth_edges, |r, c| {
                (r - c).abs() > DEPTH_TOL * c.min(far)
            });
            // Sky pixels hold `far` exactly in both.
            for (i, s) in gbuf.shape.iter().enumerate() {
                if *s == SKY && depth[i] as f64 != far && !depth_edges[i] {
                    failures.push(format!(
                        "{id}: sky pixel {i} holds {} (far {far})",
                        depth[i]
                    ));
                    break;
                }
            }
            let n = SHADOW_MAP as usize;
            let (near, far_l) = (sm.near, sm.far);
            let z = |d: f64| near + d * (far_l - near);
            let sm_edges = match sm.projection {
                ShadowProjection::Orthographic { .. } => {
                    edges(n, n, &sm.depth, |d| d, |_| 1.0, None, SHADOW_TOL)
                }
                // dd = dz / (far - near) = d(1 / z) z^2 / (far - near).
                ShadowProjection::Perspective { .. } => edges(
                    n,
                    n,
                    &sm.depth,
                    |d| 1.0 / z(d),
                    |d| z(d) * z(d) / (far_l - near),
                    None,
                    SHADOW_TOL,
                ),
            };
            let s = agreement(&shadow, &sm.depth, &sm_edges, |r, c| {
                (r - c).abs() > SHADOW_TOL
            });
            let truth = truth::render(
                &scene,
                &gbuf,
                &Visibility::ShadowMap(&sm),
                &TruthSettings::default(),
                &|| (),
            );
            let cast_depth =
                upload_r32float(ctx, Kernel::Scatter, "depth", SCREEN, &gbuf.view_depth)
                    .expect("upload");
            let cast_shadow =
                upload_r32float(ctx, Kernel::Rectify, "shadow", [n as u32; 2], &sm.depth)
                    .expect("upload");
            let epipolar = PrefilteredVariant {
                light: scene.light.kind(),
                ..PrefilteredVariant::default()
            };
            let projective = PrefilteredVariant {
                rectification: Rectification::Projective,
                ..epipolar
            };
            let unused = |_: &ProjectiveMaps| -> wgpu::Texture { unreachable!("epipolar") };
            let (e_cast, _) = gpu_error(
                ctx,
                &scene,
                &sm,
                epipolar,
                &cast_depth,
                &cast_shadow,
                unused,
                &truth,
            );
            let (e_raster, _) = gpu_error(
                ctx,
                &scene,
                &sm,
                epipolar,
                &frame.depth,
                &frame.shadow_map,
                unused,
                &truth,
            );
            // Projective: the stand-in's map (ray cast through the matrices) against the
            // rasterised one, and the family's output from each.
            let [rw, rh] = RECTIFIED;
            let mut stand_in = Vec::new();
            let (p_cast, maps) = gpu_error(
                ctx,
                &scene,
                &sm,
                projective,
                &cast_depth,
                &cast_shadow,
                |maps| {
                    stand_in = rasterise_rectified(
                        &bvh,
                        &scene.light_desc(),
                        maps,
                        rw,
                        rh,
                        scene_reach(&scene, &bvh),
                    );
                    upload_r32float(ctx, Kernel::Rectify, "rectified", RECTIFIED, &stand_in)
                        .expect("upload")
                },
                &truth,
            );
            let mut raster_map = None;
            let (p_raster, _) = gpu_error(
                ctx,
                &scene,
                &sm,
                projective,
                &frame.depth,
                &frame.shadow_map,
                |maps| {
                    let t = rasteriser
                        .rectified(ctx, &frame, maps, RECTIFIED)
                        .unwrap_or_else(|e| panic!("{id}: {e}"));
                    raster_map = Some(read_r32float(ctx, &t).unwrap_or_else(|e| panic!("{e}")));
                    t
                },
                &truth,
            );
            let projective_cells = match (maps, raster_map) {
                (Some(maps), Some(raster_map)) => {
                    let (rw, rh) = (rw as usize, rh as usize);
                    let e = edges(rw, rh, &stand_in, |d| d, |_| 1.0, None, RECTIFIED_TOL);
                    let differs = |r: f64, c: f64| (r - c).abs() > RECTIFIED_TOL;
                    let r = agreement(&raster_map, &stand_in, &e, differs);
                    // The interior disagreements a view ray reaches.
                    let reach = scene_reach(&scene, &bvh);
                    let light = scene.light_desc();
                    let mut reached = 0usize;
                    for (m, &[first, count]) in maps.matrices.iter().zip(&maps.viewports) {
                        for row in 0..rh {
                            for col in first as usize..(first + count) as usize {
                                let i = row * rw + col;
                                let (a, b) = (f64::from(raster_map[i]), f64::from(stand_in[i]));
                                if e[i] || !differs(a, b) {
                                    continue;
                                }
                                let x = -1.0
                                    + 2.0 * ((col - first as usize) as f64 + 0.5)
                                        / f64::from(count);
                                let y = 1.0 - 2.0 * (row as f64 + 0.5) / rh as f64;
                                if reachable(
                                    &scene,
                                    &gbuf,
                                    &light,
                                    m,
                                    [x, y],
                                    [a.min(b), a.max(b)],
                                    reach,
                                ) {
                                    reached += 1;
                                }
                            }
                        }
                    }
                    let reached = reached as f64 / (rw * rh) as f64;
                    if reached > PROJECTIVE_REACHED_SHARE {
                        failures.push(format!(
                            "{id}: {:.4} % of the rectified texels disagree away from \
                             silhouettes where a view ray reaches ({:.4} % in all)",
                            100.0 * reached,
                            100.0 * r.interior
                        ));
                    }
                    let bar: f64 = if scene.light.kind() == LightKind::Spot {
                        0.05
                    } else {
                        0.03
                    };
                    if p_raster > bar.max(p_cast) + 1e-3 {
                        failures.push(format!(
                            "{id}: projective on rasterised inputs {:.2} % (stand-in {:.2} %)",
                            100.0 * p_raster,
                            100.0 * p_cast
                        ));
                    }
                    format!(
                        "{:.3} / {:.4} / {:.4} / {:.2} % | {:.2} / {:.2} %",
                        100.0 * r.disagree,
                        100.0 * r.interior,
                        100.0 * reached,
                        100.0 * r.edges,
                        100.0 * p_cast,
                        100.0 * p_raster
                    )
                }
                _ => "falls back to epipolar | -".to_owned(),
            };
            table.push(format!(
                "| {id} | {} | {:.3} / {:.4} / {:.2} % | {:.3} / {:.4} / {:.2} % | {:.2} / {:.2} % | {projective_cells} |",
                frame.triangles,
                100.0 * d.disagree,
                100.0 * d.interior,
                100.0 * d.edges,
                100.0 * s.disagree,
                100.0 * s.interior,
                100.0 * s.edges,
                100.0 * e_cast,
                100.0 * e_raster,
            ));
            if d.interior > INTERIOR_SHARE {
                failures.push(format!(
                    "{id}: {:.4} % of the pixels disagree in depth away from silhouettes",
                    100.0 * d.interior
                ));
            }
            if s.interior > INTERIOR_SHARE {
                failures.push(format!(
                    "{id}: {:.4} % of the texels disagree in light depth away from silhouettes",
                    100.0 * s.interior
                ));
            }
            // The accuracy bars of the prefiltered family (tests/tests/prefiltered_truth.rs:
            // 3 % for the sun, 5 % for a spot), or the ray-cast inputs' own error where that
            // pose is one of its listed exceptions (window/ordinary), plus 0.1 percentage
            // points for the silhouettes the two rasterisations place differently.
            let bar: f64 = if scene.light.kind() == LightKind::Spot {
                0.05
            } else {
                0.03
            };
            if e_raster > bar.max(e_cast) + 1e-3 {
                failures.push(format!(
                    "{id}: prefiltered on rasterised inputs {:.2} % (ray-cast inputs {:.2} %, bar {:.0} %)",
                    100.0 * e_raster,
                    100.0 * e_cast,
                    100.0 * bar
                ));
            }
        }
    }
    eprintln!("{}", table.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
