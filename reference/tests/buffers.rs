//! Depth-buffer and shadow-map conventions, the BVH against brute force, and the suite's poses.

use glam::{DVec3, DVec4};
use scatter_reference::buffers::{
    GBuffer, SKY, ShadowMap, ShadowMapError, ndc_depth, view_depth_from_ndc,
};
use scatter_reference::bvh::Bvh;
use scatter_reference::geometry::{Ray, lower};
use scatter_reference::scene::{Light, Scene, Shape};
use scatter_reference::suite::{self, MediumPreset, Pose, SceneName};
use scatter_reference::truth::{Visibility, visibility};

/// SplitMix64 for reproducible random tests.
struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn dir(&mut self) -> DVec3 {
        let z = 2.0 * self.f() - 1.0;
        let phi = std::f64::consts::TAU * self.f();
        let r = (1.0 - z * z).sqrt();
        DVec3::new(r * phi.cos(), z, r * phi.sin())
    }
}

fn small(name: SceneName, pose: Pose) -> Scene {
    suite::scene(name, pose, MediumPreset::Default, 64, 36)
}

#[test]
fn ndc_depth_round_trips_and_spans_zero_to_one() {
    let (n, f) = (0.1, 60.0);
    assert!(ndc_depth(n, n, f).abs() < 1e-15);
    assert!((ndc_depth(f, n, f) - 1.0).abs() < 1e-15);
    for z in [0.1, 0.5, 3.0, 17.0, 59.9] {
        assert!((view_depth_from_ndc(ndc_depth(z, n, f), n, f) - z).abs() < 1e-9 * z);
    }
}

#[test]
fn depth_buffer_holds_linear_view_depth_and_far_for_sky() {
    for &name in SceneName::ALL {
        let s = small(name, Pose::Ordinary);
        let bvh = Bvh::build(&s.geometry);
        let g = GBuffer::cast(&s, &bvh);
        let frame = s.camera.frame();
        let mut sky = 0;
        for y in 0..g.height {
            for x in 0..g.width {
                let i = (y * g.width + x) as usize;
                let dir = s
                    .camera
                    .ray_dir(&frame, f64::from(x) + 0.5, f64::from(y) + 0.5);
                let cos = dir.dot(frame.forward);
                let z = f64::from(g.view_depth[i]);
                assert!(
                    (z - g.ray_length[i] * cos).abs() <= 1e-6 * z,
                    "{}: depth vs ray length",
                    s.name
                );
                assert!(z >= s.camera.near * (1.0 - 1e-6) && z <= s.camera.far * (1.0 + 1e-6));
                if g.shape[i] == SKY {
                    sky += 1;
                    assert_eq!(g.view_depth[i], s.camera.far as f32);
                } else {
                    // The reconstructed point lies on the surface: a ray back towards the eye
                    // started just in front of it reaches the eye unobstructed by that surface.
                    let p = s.camera.position + dir * g.ray_length[i];
                    let probe = Ray::new(p - dir * 1e-3, dir);
                    let hit = bvh.closest(&probe, 0.0, 2e-3);
                    assert!(
                        hit.is_some(),
                        "{}: pixel ({x}, {y}) not on a surface",
                        s.name
                    );
                    assert!(g.normal[i].dot(dir) <= 0.0, "normals face the camera");
                }
            }
        }
        if name == SceneName::Window {
            assert!(
                sky < (g.width * g.height / 4) as usize,
                "the room is closed"
            );
        }
    }
}

#[test]
fn near_plane_clips_geometry() {
    let mut s = small(SceneName::Sphere, Pose::Ordinary);
    let frame = s.camera.frame();
    // A small sphere in front of the eye, closer than the near plane.
    s.geometry.push(Shape::Sphere {
        center: s.camera.position + frame.forward * 0.05,
        radius: 0.02,
        albedo: [1.0; 3],
    });
    let bvh = Bvh::build(&s.geometry);
    let g = GBuffer::cast(&s, &bvh);
    let centre = (s.camera.height / 2 * s.camera.width + s.camera.width / 2) as usize;
    assert_ne!(g.shape[centre] as usize, s.geometry.len() - 1);
    assert!(f64::from(g.view_depth[centre]) > s.camera.near);
}

#[test]
fn bvh_matches_brute_force() {
    let mut rng = Rng(7);
    for name in [
        SceneName::Foliage,
        SceneName::Columns,
        SceneName::Terrain,
        SceneName::SpotGrate,
    ] {
        let s = small(name, Pose::Ordinary);
        let bvh = Bvh::build(&s.geometry);
        let (prims, planes) = lower(&s.geometry);
        assert_eq!(bvh.prim_count(), prims.len());
        let b = bvh.bounds();
        for _ in 0..3000 {
            // Rays from random points in the scene bounds (and from the eye) in random directions.
            let origin = if rng.f() < 0.2 {
                s.camera.position
            } else {
                b.min + (b.max - b.min) * DVec3::new(rng.f(), rng.f(), rng.f())
            };
            let ray = Ray::new(origin, rng.dir());
            let tmax = if rng.f() < 0.5 {
                f64::INFINITY
            } else {
                20.0 * rng.f()
            };
            let mut best = tmax;
            for p in &prims {
                if let Some(t) = p.prim.hit(&ray, 1e-9, best) {
                    best = t;
                }
            }
            for p in &planes {
                if let Some(t) = p.hit(&ray, 1e-9, best) {
                    best = t;
                }
            }
            let got = bvh.closest(&ray, 1e-9, tmax).map_or(tmax, |h| h.t);
            assert!(
                (got - best).abs() <= 1e-9 * best.abs().max(1.0) || got == best,
                "{name}: bvh {got} vs brute force {best}"
            );
            assert_eq!(
                bvh.occluded(&ray, 1e-9, tmax),
                best < tmax,
                "{name}: occluded"
            );
        }
    }
}

#[test]
fn foliage_has_thousands_of_occluders() {
    let s = small(SceneName::Foliage, Pose::Ordinary);
    assert!(s.occluder_count() >= 5000, "{}", s.occluder_count());
}

#[test]
fn shadow_map_rejects_bad_sizes_and_wide_cones() {
    let s = small(SceneName::Sphere, Pose::Ordinary);
    let bvh = Bvh::build(&s.geometry);
    assert_eq!(
        ShadowMap::build(&s, &bvh, 0).unwrap_err(),
        ShadowMapError::ZeroSize(0)
    );
    assert_eq!(
        ShadowMap::build(&s, &bvh, 16385).unwrap_err(),
        ShadowMapError::TooLarge(16385)
    );
    let mut spot = small(SceneName::SpotGrate, Pose::Ordinary);
    if let Light::Spot {
        outer_angle_deg,
        inner_angle_deg,
        ..
    } = &mut spot.light
    {
        *outer_angle_deg = 85.0;
        *inner_angle_deg = 10.0;
    }
    let err = ShadowMap::build(&spot, &bvh, 64).unwrap_err();
    assert_eq!(err, ShadowMapError::ConeTooWide(85.0));
    assert!(err.to_string().contains("light.outer_angle_deg"));
}

#[test]
fn shadow_map_matrix_agrees_with_lookup() {
    let mut rng = Rng(11);
    for name in [SceneName::Columns, SceneName::SpotGrate] {
        let s = small(name, Pose::Ordinary);
        let bvh = Bvh::build(&s.geometry);
        let sm = ShadowMap::build(&s, &bvh, 256).unwrap();
        let m = sm.world_to_clip();
        let corners = s.camera.frustum_corners();
        let mut checked = 0;
        for _ in 0..500 {
            // Random points inside the view frustum.
            let (a, b, c) = (rng.f(), rng.f(), rng.f());
            let near = corners[0]
                .lerp(corners[1], a)
                .lerp(corners[3].lerp(corners[2], a), b);
            let far = corners[4]
                .lerp(corners[5], a)
                .lerp(corners[7].lerp(corners[6], a), b);
            let p = near.lerp(far, c * c);
            let Some(sc) = sm.coord(p) else { continue };
            let clip = m * DVec4::new(p.x, p.y, p.z, 1.0);
            let (x, y) = (clip.x / clip.w, clip.y / clip.w);
            assert!((0.5 * (x + 1.0) - sc.u).abs() < 1e-9 && (0.5 * (1.0 - y) - sc.v).abs() < 1e-9);
            match s.light {
                Light::Directional { .. } => assert!((clip.z - sc.depth).abs() < 1e-9),
                Light::Spot { .. } | Light::Area(_) => {
                    assert!((clip.w - sc.z).abs() < 1e-9 * sc.z.max(1.0))
                }
            }
            checked += 1;
        }
        assert!(
            checked > 50,
            "{name}: only {checked} frustum points inside the map"
        );
    }
}

#[test]
fn directional_shadow_map_covers_the_eye_and_the_frustum() {
    for &name in SceneName::ALL {
        for &pose in Pose::ALL {
            let s = small(name, pose);
            if let Light::Spot { .. } = s.light {
                continue;
            }
            let bvh = Bvh::build(&s.geometry);
            let sm = ShadowMap::build(&s, &bvh, 64).unwrap();
            assert!(
                sm.coord(s.camera.position).is_some(),
                "{}: eye outside the map",
                s.name
            );
            for c in s.camera.frustum_corners() {
                // Corners sit on the footprint's boundary: nudge them inwards.
                let p = c.lerp(s.camera.position, 1e-9);
                assert!(
                    sm.coord(p).is_some(),
                    "{}: frustum corner outside the map",
                    s.name
                );
            }
        }
    }
}

/// A sun below the horizon: the ground plane crosses texel lines between the sun and the
/// map's near plane (which stops at the bounded geometry), so the map must store it there
/// (depth 0) for the points above the ground to be shadowed, as exact visibility says.
#[test]
fn sun_below_the_horizon_shadows_everything_above_the_ground() {
    for &name in &[SceneName::Sphere, SceneName::Columns, SceneName::Foliage] {
        let mut s = small(name, Pose::Ordinary);
        let to_sun = DVec3::new(0.6, -0.15, -0.8).normalize();
        s.light = Light::Directional {
            direction: -to_sun,
            irradiance: [1.0; 3],
        };
        let bvh = Bvh::build(&s.geometry);
        let sm = ShadowMap::build(&s, &bvh, 256).unwrap();
        let mut rng = Rng(7);
        let cam = &s.camera;
        for _ in 0..2000 {
            // Points of the view frustum at least 0.5 m above the ground.
            let d = rng.dir();
            let p = cam.position + d * (cam.far * rng.f());
            if p.y < 0.5 || sm.coord(p).is_none() {
                continue;
            }
            assert!(
                !visibility(&Visibility::Exact(&bvh), &s.light, p),
                "{}: {p} sees a sun below the horizon",
                s.name
            );
            assert_eq!(
                sm.visibility(p),
                0.0,
                "{}: {p} lit in the shadow map",
                s.name
            );
        }
    }
}

/// The shadow map is the discretisation of exact visibility: at 2048 texels they agree on
/// nearly every point of the view frustum.
#[test]
fn shadow_map_visibility_agrees_with_exact_visibility() {
    let mut rng = Rng(5);
    for &name in SceneName::ALL {
        let s = small(name, Pose::Ordinary);
        let bvh = Bvh::build(&s.geometry);
        let sm = ShadowMap::build(&s, &bvh, 2048).unwrap();
        let g = GBuffer::cast(&s, &bvh);
        let frame = s.camera.frame();
        let (mut agree, mut total) = (0usize, 0usize);
        for _ in 0..4000 {
            let (x, y) = (rng.f() * f64::from(g.width), rng.f() * f64::from(g.height));
            let i = (y as u32 * g.width + x as u32) as usize;
            let dir = s.camera.ray_dir(&frame, x, y);
            let p = s.camera.position + dir * g.ray_length[i] * rng.f() * 0.98;
            let a = sm.visibility(p) > 0.5;
            let b = visibility(&Visibility::Exact(&bvh), &s.light, p);
            agree += usize::from(a == b);
            total += 1;
        }
        let frac = agree as f64 / total as f64;
        assert!(
            frac > 0.99,
            "{name}: shadow map agrees with exact visibility on {frac}"
        );
    }
}

/// Each pose is what its name says.
#[test]
fn poses_place_the_light_as_named() {
    for &name in SceneName::ALL {
        for &pose in Pose::ALL {
            let s = suite::scene(name, pose, MediumPreset::Default, 320, 180);
            let cam = &s.camera;
            let f = cam.frame();
            let on_screen = |d: DVec3| {
                cam.project_direction(&f, d).is_some_and(|(x, y)| {
                    (0.0..f64::from(cam.width)).contains(&x)
                        && (0.0..f64::from(cam.height)).contains(&y)
                })
            };
            let (to_light, elevation) = match &s.light {
                Light::Directional { direction, .. } => {
                    let t = -direction.normalize();
                    (t, t.y.asin().to_degrees())
                }
                Light::Spot {
                    position,
                    direction,
                    ..
                } => (
                    (*position - cam.position).normalize(),
                    -direction.normalize().y.asin().to_degrees(),
                ),
                Light::Area(a) => (
                    (a.position - cam.position).normalize(),
                    -a.frame().2.y.asin().to_degrees(),
                ),
            };
            let epipole = on_screen(to_light);
            let anti = on_screen(-to_light);
            let ctx = format!(
                "{}: to_light {to_light}, epipole {epipole}, anti {anti}",
                s.name
            );
            match pose {
                Pose::Ordinary => assert!(!epipole && !anti, "{ctx}"),
                Pose::EpipoleOnScreen => assert!(epipole, "{ctx}"),
                Pose::LightBehind => {
                    assert!(to_light.dot(f.forward) < 0.0, "{ctx}");
                    if matches!(s.light, Light::Directional { .. }) {
                        assert!(anti, "{ctx}");
                    }
                }
                Pose::Grazing => {
                    assert!(!epipole, "{ctx}");
                    // The sun 4-5 degrees up; the spot's axis 18 degrees down.
                    assert!(
                        elevation > 0.0 && elevation < 20.0,
                        "{ctx}: elevation {elevation}"
                    );
                }
            }
        }
    }
}
