//! Seeded random camera and light poses on every suite scene (issue 12): the poses a new user
//! tries, beyond the suite's four fixed ones per scene.
//!
//! Each pose is drawn from a seed, the scene and its index alone ([`pose`]), so `random::
//! window::7` is the same frame on every machine and whatever the number of poses drawn. A
//! draw picks, independently:
//! - the eye **inside** the scene's bounds (among its geometry: in the `window` room, under the
//!   `columns` roof or the `spot_grate` grate, among the trees, low over the terrain) or
//!   **outside** them, never inside a solid;
//! - the view **toward** the light (within 20 degrees of it), **across** it (60-120 degrees
//!   from it, turned towards the scene) or **away** from it (within 20 degrees of the
//!   direction the light travels);
//! - for the sun: an azimuth, and an elevation from the horizon to the zenith (0.5-90
//!   degrees) or, one draw in seven, below the horizon (0.5-30 degrees): then no light
//!   reaches anything above the ground ([`RandomPose::dark`]; `terrain` has no ground
//!   beyond its heightfield, so there the sun lights the fog past its edges from below);
//! - for the spot lamp (`spot_grate`): its position (over the grate, or low at the side),
//!   cone (outer 15-50 degrees) and aim (at the grate, or at the eye so that the eye stands
//!   inside the cone), its intensity scaled with the square of its distance to the aim.
//!
//! A draw whose scene fails [`Scene::validate`] is drawn again from the next sub-seed (a
//! deterministic retry); the eye and the lamp are placed by rejection outside every solid.
//! The [`Category`] of a pose is measured on the final geometry (where the light projects,
//! whether the eye is in the cone), not taken from what was drawn, so a category's label is
//! always true.

use std::fmt;

use glam::DVec3;

use crate::buffers::camera_ray;
use crate::bvh::Bvh;
use crate::geometry::Ray;
use crate::scene::{Light, Orientation, Scene, Shape};
use crate::suite::Rng;
use crate::suite::{self, MediumPreset, Pose, SceneName};

/// The seed of the random-pose suite (`tests/tests/random_poses.rs`).
pub const DEFAULT_SEED: u64 = 0x0012_5CA7_7E12_0001;

/// What a pose shows, measured on its geometry (the report groups by it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Category {
    /// The sun projects inside the image (the epipole is on screen).
    SunOnScreen,
    /// Neither the sun nor the point the light travels to projects inside the image.
    SunAcross,
    /// The sun is behind the camera: the point the light travels to (the anti-epipole)
    /// projects inside the image.
    SunBehind,
    /// The sun is below the horizon: no light reaches anything above an infinite ground.
    SunBelowHorizon,
    /// `window` with the eye in the room, the sun behind the room's back wall and no view
    /// ray leaving through a window: no light enters the room, the truth is 0.
    ClosedRoom,
    /// The spot lamp projects inside the image.
    LampOnScreen,
    /// The lamp is off screen and the eye stands inside its outer cone.
    LampInCone,
    /// The lamp is off screen and the eye stands outside its outer cone.
    LampOffScreen,
}

impl Category {
    /// Every category, in report order.
    pub const ALL: &'static [Category] = &[
        Category::SunOnScreen,
        Category::SunAcross,
        Category::SunBehind,
        Category::SunBelowHorizon,
        Category::ClosedRoom,
        Category::LampOnScreen,
        Category::LampInCone,
        Category::LampOffScreen,
    ];

    /// The snake_case name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Category::SunOnScreen => "sun_on_screen",
            Category::SunAcross => "sun_across",
            Category::SunBehind => "sun_behind",
            Category::SunBelowHorizon => "sun_below_horizon",
            Category::ClosedRoom => "closed_room",
            Category::LampOnScreen => "lamp_on_screen",
            Category::LampInCone => "lamp_in_cone",
            Category::LampOffScreen => "lamp_off_screen",
        }
    }
}

impl fmt::Display for Category {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Where the view was drawn relative to the light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum View {
    /// Within 20 degrees of the direction towards the light.
    Toward,
    /// 60-120 degrees from the direction towards the light.
    Across,
    /// Within 20 degrees of the direction the light travels.
    Away,
}

impl View {
    /// The name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            View::Toward => "toward",
            View::Across => "across",
            View::Away => "away",
        }
    }
}

impl fmt::Display for View {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One random pose: a suite scene with a drawn camera and light.
#[derive(Clone, Debug)]
pub struct RandomPose {
    /// The suite scene it is built on (geometry, medium, light colour, far plane).
    pub scene_name: SceneName,
    /// Index among the scene's poses.
    pub index: u32,
    /// The scene with the drawn camera and light.
    pub scene: Scene,
    /// What the pose shows, measured on its geometry.
    pub category: Category,
    /// No light reaches any view ray (the truth must be black): a closed room, or a sun
    /// below the horizon of an infinite ground plane (`terrain` has none: a sun below its
    /// horizon lights the fog beyond the heightfield's edges).
    pub dark: bool,
    /// The eye lies inside the scene's bounds.
    pub eye_inside: bool,
    /// How the view was drawn relative to the light.
    pub view: View,
    /// Spot lamps: the eye lies inside the outer cone (`false` for the sun).
    pub eye_in_cone: bool,
    /// Sun elevation above the horizon in degrees (`None` for a spot lamp).
    pub sun_elevation_deg: Option<f64>,
    /// Draws rejected by [`Scene::validate`] before this one.
    pub retries: u32,
}

impl RandomPose {
    /// `random::<scene>::<index>`, stable for a seed.
    pub fn name(&self) -> String {
        format!("random::{}::{}", self.scene_name, self.index)
    }

    /// One line: category, eye, view, light.
    pub fn describe(&self) -> String {
        let light = match (&self.scene.light, self.sun_elevation_deg) {
            (Light::Directional { .. }, Some(el)) => format!("sun {el:.1} deg"),
            (
                Light::Spot {
                    outer_angle_deg, ..
                },
                _,
            ) => format!(
                "lamp outer {outer_angle_deg:.0} deg, eye {} the cone",
                if self.eye_in_cone { "in" } else { "outside" }
            ),
            _ => String::new(),
        };
        format!(
            "{}: eye {}, view {}, {light}",
            self.category,
            if self.eye_inside { "inside" } else { "outside" },
            self.view
        )
    }
}

/// What the pose draws need beyond the suite's SplitMix64 ([`Rng`]).
impl Rng {
    /// True with probability `p`.
    fn chance(&mut self, p: f64) -> bool {
        self.f() < p
    }

    /// Uniform in the box [min, max).
    fn in_box(&mut self, min: DVec3, max: DVec3) -> DVec3 {
        DVec3::new(
            self.range(min.x, max.x),
            self.range(min.y, max.y),
            self.range(min.z, max.z),
        )
    }

    /// `d` (unit) turned by `angle_deg` towards a uniformly random perpendicular direction.
    fn tilt(&mut self, d: DVec3, angle_deg: f64) -> DVec3 {
        let (a, b) = d.any_orthonormal_pair();
        let phi = self.range(0.0, std::f64::consts::TAU);
        let p = a * phi.cos() + b * phi.sin();
        let (s, c) = angle_deg.to_radians().sin_cos();
        (d * c + p * s).normalize()
    }

    /// `d` (unit) turned by an angle uniform in solid angle within `max_deg` of it.
    fn in_cone(&mut self, d: DVec3, max_deg: f64) -> DVec3 {
        let cos = 1.0 - self.f() * (1.0 - max_deg.to_radians().cos());
        self.tilt(d, cos.clamp(-1.0, 1.0).acos().to_degrees())
    }
}

/// One SplitMix64 step as a hash, to derive sub-seeds.
fn mix(x: u64) -> u64 {
    Rng(x).next_u64()
}

/// Where the eye may stand: `inner` is the scene's bounds (its "inside"), `outer` the box
/// an outside eye is drawn in (outside `inner`), `centre` the point an `across` view turns
/// towards.
struct Bounds {
    inner: (DVec3, DVec3),
    outer: (DVec3, DVec3),
    centre: DVec3,
}

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// The bounds of each suite scene (see `suite.rs` for the geometry). Every box starts 0.3 m
/// above the ground plane.
fn bounds(name: SceneName) -> Bounds {
    let b = |inner: ([f64; 3], [f64; 3]), outer: ([f64; 3], [f64; 3]), centre: [f64; 3]| Bounds {
        inner: (DVec3::from(inner.0), DVec3::from(inner.1)),
        outer: (DVec3::from(outer.0), DVec3::from(outer.1)),
        centre: DVec3::from(centre),
    };
    match name {
        // Around and under the sphere (centre (0, 4, 0), radius 2).
        SceneName::Sphere => b(
            ([-4.0, 0.3, -4.0], [4.0, 7.0, 4.0]),
            ([-20.0, 0.3, -20.0], [20.0, 14.0, 20.0]),
            [0.0, 3.0, 0.0],
        ),
        // Under the portico's roof (x in [-3.6, 3.6], z in [-11.5, 11.5], beams at y = 6).
        SceneName::Columns => b(
            ([-3.6, 0.3, -11.5], [3.6, 5.8, 11.5]),
            ([-20.0, 0.3, -26.0], [20.0, 14.0, 26.0]),
            [0.0, 3.0, 0.0],
        ),
        // In the room (x, z in [-6, 6], y in [0, 5]).
        SceneName::Window => b(
            ([-5.8, 0.3, -5.8], [5.8, 4.8, 5.8]),
            ([-20.0, 0.3, -22.0], [20.0, 10.0, 20.0]),
            [0.0, 2.5, 0.0],
        ),
        // Among the trees (a ring of radius <= 8 around (0, -2), crowns up to ~9 m).
        SceneName::Foliage => b(
            ([-10.0, 0.3, -12.0], [10.0, 8.0, 8.0]),
            ([-28.0, 0.3, -30.0], [28.0, 14.0, 26.0]),
            [0.0, 3.0, -2.0],
        ),
        // Low over the 200 m heightfield (heights up to ~26 m; the solid test keeps the eye
        // above the ground).
        SceneName::Terrain => b(
            ([-95.0, 0.3, -95.0], [95.0, 30.0, 95.0]),
            ([-160.0, 0.3, -160.0], [160.0, 80.0, 160.0]),
            [0.0, 10.0, 0.0],
        ),
        // Under the grate (x, z in [-2.1, 2.1], bars at y = 3).
        SceneName::SpotGrate => b(
            ([-2.0, 0.3, -2.0], [2.0, 2.8, 2.0]),
            ([-12.0, 0.3, -12.0], [12.0, 8.0, 12.0]),
            [0.0, 1.5, 0.0],
        ),
    }
}

fn in_box(p: DVec3, (min, max): (DVec3, DVec3)) -> bool {
    p.cmpge(min).all() && p.cmple(max).all()
}

/// Whether `p` lies inside a solid shape, or within `margin` of one (meshes are thin
/// sheets: never).
fn inside_solid(shapes: &[Shape], p: DVec3, margin: f64) -> bool {
    shapes.iter().any(|s| match s {
        Shape::Plane { point, normal, .. } => (p - *point).dot(normal.normalize()) < margin,
        Shape::Box { min, max, .. } => p.cmpgt(*min - margin).all() && p.cmplt(*max + margin).all(),
        Shape::Sphere { center, radius, .. } => (p - *center).length() < radius + margin,
        Shape::Cylinder { a, b, radius, .. } => {
            let axis = *b - *a;
            let len = axis.length();
            let t = (p - *a).dot(axis / len);
            t > -margin && t < len + margin && (p - *a - axis / len * t).length() < radius + margin
        }
        Shape::Heightfield {
            origin,
            size,
            samples,
            heights,
            ..
        } => {
            let u = (p.x - origin.x) / size[0] * f64::from(samples[0] - 1);
            let w = (p.z - origin.z) / size[1] * f64::from(samples[1] - 1);
            let (nx, nz) = (samples[0] as usize, samples[1] as usize);
            if u < 0.0 || w < 0.0 || u > (nx - 1) as f64 || w > (nz - 1) as f64 {
                return false;
            }
            // Bilinear in the cell: within a margin of either triangulation.
            let (ix, iz) = ((u as usize).min(nx - 2), (w as usize).min(nz - 2));
            let (fx, fz) = (u - ix as f64, w - iz as f64);
            let h = |x: usize, z: usize| heights[z * nx + x];
            let top = (h(ix, iz) * (1.0 - fx) + h(ix + 1, iz) * fx) * (1.0 - fz)
                + (h(ix, iz + 1) * (1.0 - fx) + h(ix + 1, iz + 1) * fx) * fz;
            let peak = h(ix, iz)
                .max(h(ix + 1, iz))
                .max(h(ix, iz + 1))
                .max(h(ix + 1, iz + 1));
            p.y < origin.y + top.max(peak) + margin
        }
        Shape::Mesh { .. } => false,
    })
}

/// How far the eye and the lamp stay from every solid (m).
const SOLID_MARGIN: f64 = 0.2;
/// Rejection-sampling attempts for one point before the whole draw is retried.
const POINT_ATTEMPTS: u32 = 1000;
/// Whole-draw retries before [`pose`] gives up (a defect of the generator).
const DRAW_RETRIES: u32 = 64;

/// An eye position inside or outside the scene's bounds, outside every solid.
fn draw_eye(rng: &mut Rng, b: &Bounds, shapes: &[Shape], inside: bool) -> Option<DVec3> {
    (0..POINT_ATTEMPTS).find_map(|_| {
        let p = if inside {
            rng.in_box(b.inner.0, b.inner.1)
        } else {
            rng.in_box(b.outer.0, b.outer.1)
        };
        let ok = in_box(p, b.inner) == inside && !inside_solid(shapes, p, SOLID_MARGIN);
        ok.then_some(p)
    })
}

/// A view direction relative to `to_light` (unit, from the eye towards the light).
fn draw_forward(rng: &mut Rng, view: View, to_light: DVec3, eye: DVec3, centre: DVec3) -> DVec3 {
    match view {
        View::Toward => rng.in_cone(to_light, 20.0),
        View::Away => rng.in_cone(-to_light, 20.0),
        View::Across => {
            // Turned towards the scene's centre about the light's axis, +-60 degrees.
            let c = centre - eye;
            let perp = c - to_light * c.dot(to_light);
            let base = if perp.length() > 1e-3 * c.length().max(1e-9) {
                perp.normalize()
            } else {
                to_light.any_orthonormal_vector()
            };
            let turn = rng.range(-60f64, 60.0).to_radians();
            let side = to_light.cross(base);
            let dir = base * turn.cos() + side * turn.sin();
            let angle = rng.range(60f64, 120.0).to_radians();
            (to_light * angle.cos() + dir * angle.sin()).normalize()
        }
    }
}

/// A camera orientation looking along `forward` with `+y` up, or a horizontal up when the
/// view is (nearly) vertical.
fn orientation(forward: DVec3) -> Orientation {
    let up = if forward.y.abs() > 0.95 {
        let h = v(forward.x, 0.0, forward.z);
        if h.length() > 1e-6 {
            h.normalize()
        } else {
            DVec3::Z
        }
    } else {
        DVec3::Y
    };
    Orientation::Forward { forward, up }
}

/// Whether a world direction from the eye projects inside the image.
fn on_screen(scene: &Scene, dir: DVec3) -> bool {
    let cam = &scene.camera;
    cam.project_direction(&cam.frame(), dir)
        .is_some_and(|(x, y)| {
            (0.0..=f64::from(cam.width)).contains(&x) && (0.0..=f64::from(cam.height)).contains(&y)
        })
}

/// `window`: whether every pixel's ray ends on the room's walls, floor or ceiling (none
/// leaves through a window).
fn sees_only_the_room(scene: &Scene) -> bool {
    let bvh = Bvh::build(&scene.geometry);
    let cam = &scene.camera;
    let frame = cam.frame();
    let room = (v(-6.31, -0.01, -6.31), v(6.31, 5.31, 6.31));
    (0..cam.height).all(|y| {
        (0..cam.width).all(|x| {
            let dir = camera_ray(scene, &frame, x, y);
            bvh.closest(&Ray::new(cam.position, dir), 0.0, f64::INFINITY)
                .is_some_and(|hit| in_box(cam.position + dir * hit.t, room))
        })
    })
}

/// Whether no light reaches the eye's surroundings: a closed room, or a sun behind an
/// infinite plane (the ground) the eye stands in front of.
fn is_dark(scene: &Scene, category: Category) -> bool {
    match (category, &scene.light) {
        (Category::ClosedRoom, _) => true,
        (Category::SunBelowHorizon, Light::Directional { direction, .. }) => {
            scene.geometry.iter().any(|s| match s {
                Shape::Plane { point, normal, .. } => {
                    normal.dot(*direction) > 0.0
                        && (scene.camera.position - *point).dot(*normal) > 0.0
                }
                _ => false,
            })
        }
        _ => false,
    }
}

/// The pose's category, measured on its geometry.
fn classify(name: SceneName, scene: &Scene, b: &Bounds) -> (Category, bool) {
    let eye = scene.camera.position;
    match &scene.light {
        Light::Directional { direction, .. } => {
            let to_sun = -direction.normalize();
            let cat = if to_sun.y < 0.0 {
                Category::SunBelowHorizon
            } else if name == SceneName::Window
                && in_box(eye, b.inner)
                && to_sun.z >= 0.0
                && sees_only_the_room(scene)
            {
                // The windows are in the wall at z = -6: a sun at +z shines on the back wall,
                // and no view ray leaves the room through a window.
                Category::ClosedRoom
            } else if on_screen(scene, to_sun) {
                Category::SunOnScreen
            } else if on_screen(scene, -to_sun) {
                Category::SunBehind
            } else {
                Category::SunAcross
            };
            (cat, false)
        }
        Light::Spot {
            position,
            direction,
            outer_angle_deg,
            ..
        } => {
            let in_cone = (eye - *position).normalize().dot(direction.normalize())
                > outer_angle_deg.to_radians().cos();
            let cat = if on_screen(scene, *position - eye) {
                Category::LampOnScreen
            } else if in_cone {
                Category::LampInCone
            } else {
                Category::LampOffScreen
            };
            (cat, in_cone)
        }
        Light::Area(a) => {
            let in_cone = (eye - a.position).normalize().dot(a.frame().2)
                > a.outer_angle_deg.to_radians().cos();
            let cat = if on_screen(scene, a.position - eye) {
                Category::LampOnScreen
            } else if in_cone {
                Category::LampInCone
            } else {
                Category::LampOffScreen
            };
            (cat, in_cone)
        }
    }
}

/// The light and eye of one draw on `base` (the suite scene's `ordinary` pose), or `None`
/// when rejection sampling found no place for the eye or the lamp.
fn draw(rng: &mut Rng, name: SceneName, base: &Scene) -> Option<(Scene, bool, View, Option<f64>)> {
    let b = bounds(name);
    let shapes = &base.geometry;
    let eye_inside = rng.chance(0.5);
    let view = match rng.next_u64() % 3 {
        0 => View::Toward,
        1 => View::Across,
        _ => View::Away,
    };
    let mut scene = base.clone();
    let (eye, to_light, elevation) = match &base.light {
        Light::Directional { irradiance, .. } => {
            let el = if rng.chance(1.0 / 7.0) {
                -rng.range(0.5, 30.0)
            } else {
                rng.range(0.5, 90.0)
            };
            let az = rng.range(0.0, 360f64).to_radians();
            let (se, ce) = el.to_radians().sin_cos();
            let to_sun = v(ce * az.cos(), se, ce * az.sin());
            scene.light = Light::Directional {
                direction: -to_sun,
                irradiance: *irradiance,
            };
            (draw_eye(rng, &b, shapes, eye_inside)?, to_sun, Some(el))
        }
        Light::Spot { intensity, .. } => {
            // Over the grate three draws in four, else low at the side.
            let lamp = (0..POINT_ATTEMPTS).find_map(|_| {
                let p = if rng.chance(0.75) {
                    rng.in_box(v(-5.0, 3.6, -5.0), v(5.0, 10.0, 5.0))
                } else {
                    let a = rng.range(0.0, std::f64::consts::TAU);
                    let r = rng.range(3.0, 8.0);
                    v(r * a.cos(), rng.range(0.5, 3.5), r * a.sin())
                };
                (!inside_solid(shapes, p, SOLID_MARGIN)).then_some(p)
            })?;
            let eye = (0..POINT_ATTEMPTS).find_map(|_| {
                let e = draw_eye(rng, &b, shapes, eye_inside)?;
                ((e - lamp).length() > 0.5).then_some(e)
            })?;
            let outer = rng.range(15.0, 50.0);
            let inner = outer * rng.range(0.4, 0.9);
            let aim = rng.in_box(v(-2.0, 0.0, -2.0), v(2.0, 3.0, 2.0));
            // Aimed at the grate, or (one draw in two) at the eye, so that it stands in the
            // cone.
            let axis = if rng.chance(0.5) {
                rng.in_cone((eye - lamp).normalize(), 0.7 * outer)
            } else {
                (aim - lamp).normalize()
            };
            let scale = ((aim - lamp).length() / 7.0).powi(2);
            scene.light = Light::Spot {
                position: lamp,
                direction: axis,
                inner_angle_deg: inner,
                outer_angle_deg: outer,
                intensity: intensity.map(|c| c * scale),
                cookie: None,
            };
            (eye, (lamp - eye).normalize(), None)
        }
        // The suite scenes random poses are drawn on have a sun or a spot.
        Light::Area(_) => return None,
    };
    let forward = draw_forward(rng, view, to_light, eye, b.centre);
    scene.camera.position = eye;
    scene.camera.orientation = orientation(forward);
    Some((scene, eye_inside, view, elevation))
}

/// The seed of draw `retry` of pose `index` of `name`.
fn sub_seed(seed: u64, name: SceneName, index: u32, retry: u32) -> u64 {
    let scene = SceneName::ALL
        .iter()
        .position(|&n| n == name)
        .unwrap_or_default() as u64;
    mix(seed ^ mix(scene.wrapping_add(0x100) ^ mix(u64::from(index) ^ mix(u64::from(retry)))))
}

/// Pose `index` of suite scene `name` from `seed`, at `width` x `height` pixels.
///
/// # Panics
///
/// When no valid draw is found in 64 retries (a defect of the generator, not of the seed).
pub fn pose(name: SceneName, index: u32, seed: u64, width: u32, height: u32) -> RandomPose {
    let base = suite::scene(name, Pose::Ordinary, MediumPreset::Default, width, height);
    pose_on(&base, name, index, seed)
}

/// [`pose`] on an already built base scene (`name`'s `ordinary` pose at the final size).
fn pose_on(base: &Scene, name: SceneName, index: u32, seed: u64) -> RandomPose {
    for retry in 0..DRAW_RETRIES {
        let mut rng = Rng(sub_seed(seed, name, index, retry));
        let Some((mut scene, eye_inside, view, sun_elevation_deg)) = draw(&mut rng, name, base)
        else {
            continue;
        };
        scene.name = format!("random/{name}/{index}");
        if scene.validate().is_err() {
            continue;
        }
        let (category, eye_in_cone) = classify(name, &scene, &bounds(name));
        let dark = is_dark(&scene, category);
        return RandomPose {
            scene_name: name,
            index,
            scene,
            category,
            dark,
            eye_inside,
            view,
            eye_in_cone,
            sun_elevation_deg,
            retries: retry,
        };
    }
    panic!("random pose {name}/{index}: no valid draw in {DRAW_RETRIES} retries")
}

/// `per_scene` poses of every suite scene from `seed`, scene by scene, at `width` x
/// `height` pixels.
pub fn poses(seed: u64, per_scene: u32, width: u32, height: u32) -> Vec<RandomPose> {
    SceneName::ALL
        .iter()
        .flat_map(|&name| {
            let base = suite::scene(name, Pose::Ordinary, MediumPreset::Default, width, height);
            (0..per_scene)
                .map(|i| pose_on(&base, name, i, seed))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn poses_are_deterministic_valid_and_named() {
        let a = poses(DEFAULT_SEED, 12, 48, 27);
        let b = poses(DEFAULT_SEED, 12, 48, 27);
        assert_eq!(a.len(), 6 * 12);
        for (p, q) in a.iter().zip(&b) {
            assert_eq!(p.scene, q.scene, "{}", p.name());
            p.scene
                .validate()
                .unwrap_or_else(|e| panic!("{}: {e}", p.name()));
        }
        // A pose does not depend on how many are drawn.
        assert_eq!(
            pose(SceneName::Window, 5, DEFAULT_SEED, 48, 27).scene,
            a[2 * 12 + 5].scene
        );
        assert_ne!(
            pose(SceneName::Window, 5, DEFAULT_SEED ^ 1, 48, 27).scene,
            a[2 * 12 + 5].scene
        );
        let mut names: Vec<String> = a.iter().map(RandomPose::name).collect();
        assert_eq!(names[0], "random::sphere::0");
        names.sort();
        names.dedup();
        assert_eq!(names.len(), a.len());
    }

    #[test]
    fn draws_respect_their_premises() {
        let all = poses(DEFAULT_SEED, 25, 96, 54);
        let mut count: BTreeMap<Category, usize> = BTreeMap::new();
        for p in &all {
            *count.entry(p.category).or_default() += 1;
            let eye = p.scene.camera.position;
            let b = bounds(p.scene_name);
            assert_eq!(in_box(eye, b.inner), p.eye_inside, "{}", p.name());
            assert!(!inside_solid(&p.scene.geometry, eye, 0.1), "{}", p.name());
            let spot = matches!(p.scene.light, Light::Spot { .. });
            assert_eq!(spot, p.scene_name == SceneName::SpotGrate, "{}", p.name());
            if let Light::Spot {
                outer_angle_deg, ..
            } = p.scene.light
            {
                assert!(
                    outer_angle_deg < 80.0,
                    "{}: the shadow map needs < 80",
                    p.name()
                );
            }
            if p.category == Category::SunBelowHorizon {
                assert!(p.sun_elevation_deg.is_some_and(|e| e < 0.0), "{}", p.name());
            }
        }
        // Every category occurs with the suite's seed and count.
        for c in Category::ALL {
            assert!(
                count.get(c).copied().unwrap_or(0) > 0,
                "no {c} pose: {count:?}"
            );
        }
    }

    #[test]
    fn inside_solid_sees_the_suite_shapes() {
        let s = suite::scene(
            SceneName::Sphere,
            Pose::Ordinary,
            MediumPreset::Default,
            8,
            8,
        );
        assert!(inside_solid(&s.geometry, v(0.0, 4.0, 0.0), 0.0));
        assert!(inside_solid(&s.geometry, v(0.0, -1.0, 5.0), 0.0));
        assert!(!inside_solid(&s.geometry, v(0.0, 1.0, 5.0), 0.2));
        let t = suite::scene(
            SceneName::Terrain,
            Pose::Ordinary,
            MediumPreset::Default,
            8,
            8,
        );
        assert!(inside_solid(&t.geometry, v(0.0, 1.0, 0.0), 0.0));
        assert!(!inside_solid(&t.geometry, v(0.0, 60.0, 0.0), 0.0));
    }
}
