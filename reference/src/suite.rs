//! The named scene suite every method is measured on (DESIGN.md): six scenes, four camera
//! poses each, three medium presets.
//!
//! | scene | what it stresses |
//! |---|---|
//! | `sphere` | minimal: one sphere over a ground plane, one clean shadow volume |
//! | `columns` | a portico: two rows of columns under a roof, parallel shafts between them |
//! | `window` | a closed room lit by the sun through three mullioned windows |
//! | `foliage` | ten trees of ~600 leaf triangles each: thousands of tiny occluders, depth complexity |
//! | `terrain` | a 200 m heightfield with ridges: long smooth shadows (min-max's best case) |
//! | `spot_grate` | a spot light through a raised grate of bars |
//!
//! Poses (directional light; the sun is placed relative to the camera's view direction):
//! - `ordinary`: sun to the side and slightly behind (100 degrees off the view azimuth, 35-40
//!   degrees up): neither the epipole nor the anti-epipole is on screen;
//! - `epipole_on_screen`: the camera looks towards the sun, which projects inside the image;
//! - `light_behind`: the sun is behind the camera; the anti-epipole (where the light travels
//!   to) is on screen;
//! - `grazing`: the sun 4-5 degrees above the horizon and 90 degrees off the view azimuth:
//!   light skims the ground and runs nearly parallel to the image plane.
//!
//! For the spot light every pose makes sense, with these meanings: `ordinary` (lamp above
//! the grate, outside the image), `epipole_on_screen` (the lamp itself projects inside the
//! image), `light_behind` (a distant narrow lamp behind the camera, which stands inside its cone) and
//! `grazing` (the lamp to the side, its axis 18 degrees below the horizontal, so the light
//! crosses the grate's bars at grazing incidence and only thin sheets pass between them).
//!
//! Fog densities are chosen so that the optical depth across the visible scene is about 1:
//! shafts are clearly visible. `thick` multiplies `sigma_t` by 6, `thin` divides it by 20.

use crate::scene::{Camera, Light, Medium, Orientation, Scene, Shape};
use glam::DVec3;
use std::fmt;
use std::str::FromStr;

/// The suite's scenes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SceneName {
    /// One sphere over a plane.
    Sphere,
    /// A portico of columns.
    Columns,
    /// A room lit through windows.
    Window,
    /// Trees with thousands of leaves.
    Foliage,
    /// A heightfield landscape.
    Terrain,
    /// A spot light through a grate.
    SpotGrate,
}

/// Camera poses relative to the light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Pose {
    /// Light off screen, to the side.
    Ordinary,
    /// The light (epipole) projects inside the image.
    EpipoleOnScreen,
    /// The light is behind the camera.
    LightBehind,
    /// The light grazes the scene.
    Grazing,
}

/// Medium presets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub enum MediumPreset {
    /// The scene's own fog.
    #[default]
    Default,
    /// `sigma_t` x 6.
    Thick,
    /// `sigma_t` / 20.
    Thin,
}

macro_rules! named {
    ($t:ty, $what:literal, [$($v:ident => $s:literal),* $(,)?]) => {
        impl $t {
            /// Every value, in suite order.
            pub const ALL: &'static [$t] = &[$(<$t>::$v),*];
            /// The snake_case name used in trial names, files and the CLI.
            pub fn name(self) -> &'static str {
                match self { $(<$t>::$v => $s),* }
            }
        }
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
        impl FromStr for $t {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                match s {
                    $($s => Ok(<$t>::$v),)*
                    _ => Err(format!(
                        concat!($what, " must be one of {}, got '{}'"),
                        [$($s),*].join(", "),
                        s
                    )),
                }
            }
        }
    };
}

named!(SceneName, "scene", [
    Sphere => "sphere", Columns => "columns", Window => "window",
    Foliage => "foliage", Terrain => "terrain", SpotGrate => "spot_grate",
]);
named!(Pose, "pose", [
    Ordinary => "ordinary", EpipoleOnScreen => "epipole_on_screen",
    LightBehind => "light_behind", Grazing => "grazing",
]);
named!(MediumPreset, "medium", [Default => "default", Thick => "thick", Thin => "thin"]);

/// Default suite resolution (the conformance resolution of the issues).
pub const DEFAULT_SIZE: (u32, u32) = (320, 180);

/// Builds a suite scene at the given resolution.
pub fn scene(name: SceneName, pose: Pose, preset: MediumPreset, width: u32, height: u32) -> Scene {
    let def = match name {
        SceneName::Sphere => sphere(pose),
        SceneName::Columns => columns(pose),
        SceneName::Window => window(pose),
        SceneName::Foliage => foliage(pose),
        SceneName::Terrain => terrain(pose),
        SceneName::SpotGrate => spot_grate(pose),
    };
    let mut medium = def.medium;
    match preset {
        MediumPreset::Default => {}
        MediumPreset::Thick => medium.sigma_t *= 6.0,
        MediumPreset::Thin => medium.sigma_t /= 20.0,
    }
    let suffix = match preset {
        MediumPreset::Default => String::new(),
        p => format!("/{p}"),
    };
    Scene {
        name: format!("{name}/{pose}{suffix}"),
        camera: Camera {
            position: def.eye,
            orientation: Orientation::LookAt {
                target: def.target,
                up: DVec3::Y,
            },
            fov_y_deg: 60.0,
            near: 0.1,
            far: def.far,
            width,
            height,
        },
        light: def.light,
        medium,
        geometry: def.geometry,
        sky: [0.02, 0.025, 0.035],
    }
}

struct Def {
    eye: DVec3,
    target: DVec3,
    far: f64,
    light: Light,
    medium: Medium,
    geometry: Vec<Shape>,
}

/// Direction towards the sun: `rel_az_deg` clockwise (towards the camera's right) from the
/// camera's horizontal view direction, `el_deg` above the horizon.
fn to_sun(eye: DVec3, target: DVec3, rel_az_deg: f64, el_deg: f64) -> DVec3 {
    let f = DVec3::new(target.x - eye.x, 0.0, target.z - eye.z).normalize();
    let right = f.cross(DVec3::Y);
    let (sa, ca) = rel_az_deg.to_radians().sin_cos();
    let (se, ce) = el_deg.to_radians().sin_cos();
    (f * ca + right * sa) * ce + DVec3::Y * se
}

fn sun(eye: DVec3, target: DVec3, rel_az_deg: f64, el_deg: f64, e: f64) -> Light {
    Light::Directional {
        direction: -to_sun(eye, target, rel_az_deg, el_deg),
        irradiance: [e, 0.95 * e, 0.85 * e],
    }
}

fn ground(albedo: [f64; 3]) -> Shape {
    Shape::Plane {
        point: DVec3::ZERO,
        normal: DVec3::Y,
        albedo,
    }
}

fn aabb(min: [f64; 3], max: [f64; 3], albedo: [f64; 3]) -> Shape {
    Shape::Box {
        min: DVec3::from_array(min),
        max: DVec3::from_array(max),
        albedo,
    }
}

/// A directional-light pose table: (eye, target, sun rel. azimuth, sun elevation) per pose.
fn directional_pose(
    pose: Pose,
    table: [(DVec3, DVec3, f64, f64); 4],
    e: f64,
) -> (DVec3, DVec3, Light) {
    let (eye, target, az, el) = table[match pose {
        Pose::Ordinary => 0,
        Pose::EpipoleOnScreen => 1,
        Pose::LightBehind => 2,
        Pose::Grazing => 3,
    }];
    (eye, target, sun(eye, target, az, el, e))
}

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

fn sphere(pose: Pose) -> Def {
    let (eye, target, light) = directional_pose(
        pose,
        [
            (v(0.0, 2.5, 12.0), v(0.0, 3.0, 0.0), 100.0, 40.0),
            (v(0.0, 2.0, 12.0), v(0.0, 4.0, 0.0), 6.0, 16.0),
            (v(0.0, 4.0, 13.0), v(0.0, 2.0, 0.0), 200.0, 35.0),
            (v(0.0, 2.5, 12.0), v(0.0, 3.0, 0.0), 90.0, 4.0),
        ],
        1.0,
    );
    Def {
        eye,
        target,
        far: 60.0,
        light,
        medium: Medium {
            sigma_t: 0.05,
            albedo: 0.8,
            g: 0.3,
        },
        geometry: vec![
            ground([0.5, 0.5, 0.5]),
            Shape::Sphere {
                center: v(0.0, 4.0, 0.0),
                radius: 2.0,
                albedo: [0.8, 0.3, 0.2],
            },
        ],
    }
}

fn columns(pose: Pose) -> Def {
    let (eye, target, light) = directional_pose(
        pose,
        [
            (v(1.5, 1.8, 14.0), v(0.0, 2.5, -6.0), 100.0, 38.0),
            (v(0.0, 1.7, 13.0), v(0.0, 3.0, -6.0), 12.0, 14.0),
            (v(0.0, 5.0, 15.0), v(0.0, 1.0, -4.0), 195.0, 35.0),
            (v(1.5, 1.8, 14.0), v(0.0, 2.5, -6.0), 90.0, 5.0),
        ],
        1.0,
    );
    let stone = [0.7, 0.68, 0.62];
    let mut g = vec![ground([0.45, 0.45, 0.42])];
    for row in [-3.0, 3.0] {
        for i in 0..8 {
            let z = -10.5 + 3.0 * f64::from(i);
            g.push(Shape::Cylinder {
                a: v(row, 0.0, z),
                b: v(row, 6.0, z),
                radius: 0.4,
                albedo: stone,
            });
        }
    }
    // Architrave beams over each row and a roof slab with a long skylight slot.
    g.push(aabb([-3.6, 6.0, -11.5], [-2.4, 6.6, 11.5], stone));
    g.push(aabb([2.4, 6.0, -11.5], [3.6, 6.6, 11.5], stone));
    g.push(aabb([-3.6, 6.6, -11.5], [-0.6, 6.9, 11.5], stone));
    g.push(aabb([0.6, 6.6, -11.5], [3.6, 6.9, 11.5], stone));
    Def {
        eye,
        target,
        far: 60.0,
        light,
        medium: Medium {
            sigma_t: 0.05,
            albedo: 0.8,
            g: 0.3,
        },
        geometry: g,
    }
}

fn window(pose: Pose) -> Def {
    // Room x in [-6, 6], y in [0, 5], z in [-6, 6]; windows in the wall at z = -6, outside
    // is -z. Every pose keeps the sun outside that wall (to_sun.z < 0).
    let (eye, target, light) = directional_pose(
        pose,
        [
            (v(5.0, 1.6, 3.0), v(-4.0, 1.8, 0.5), 100.0, 35.0),
            (v(1.0, 1.5, 4.5), v(0.0, 3.0, -6.0), 8.0, 18.0),
            (v(0.0, 3.0, -5.0), v(0.0, 0.5, 3.0), 190.0, 30.0),
            (v(5.0, 1.6, 3.0), v(-4.0, 1.8, 0.5), 90.0, 5.0),
        ],
        4.0,
    );
    let wall = [0.75, 0.72, 0.66];
    let (t0, t1) = (-6.3, -6.0);
    let mut g = vec![
        ground([0.5, 0.45, 0.4]),
        // ceiling, back wall, side walls
        aabb([-6.3, 5.0, -6.3], [6.3, 5.3, 6.3], wall),
        aabb([-6.3, 0.0, 6.0], [6.3, 5.0, 6.3], wall),
        aabb([-6.3, 0.0, -6.0], [-6.0, 5.0, 6.0], wall),
        aabb([6.0, 0.0, -6.0], [6.3, 5.0, 6.0], wall),
        // window wall: sill band, lintel band, piers
        aabb([-6.3, 0.0, t0], [6.3, 1.2, t1], wall),
        aabb([-6.3, 3.6, t0], [6.3, 5.0, t1], wall),
        aabb([-6.3, 1.2, t0], [-4.5, 3.6, t1], wall),
        aabb([-2.5, 1.2, t0], [-1.0, 3.6, t1], wall),
        aabb([1.0, 1.2, t0], [2.5, 3.6, t1], wall),
        aabb([4.5, 1.2, t0], [6.3, 3.6, t1], wall),
    ];
    // Mullions: one vertical and one horizontal bar per window.
    for (x0, x1) in [(-4.5, -2.5), (-1.0, 1.0), (2.5, 4.5)] {
        let xm = 0.5 * (x0 + x1);
        g.push(aabb([xm - 0.06, 1.2, t0], [xm + 0.06, 3.6, t1], wall));
        g.push(aabb([x0, 2.34, t0], [x1, 2.46, t1], wall));
    }
    Def {
        eye,
        target,
        far: 40.0,
        light,
        medium: Medium {
            sigma_t: 0.08,
            albedo: 0.9,
            g: 0.4,
        },
        geometry: g,
    }
}

/// SplitMix64: a tiny deterministic generator, so the suite (and `random_poses`) is the same
/// everywhere.
#[derive(Clone, Debug)]
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub(crate) fn f(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [a, b).
    pub(crate) fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.f()
    }
    /// Uniform unit vector.
    fn dir(&mut self) -> DVec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        v(r * phi.cos(), z, r * phi.sin())
    }
}

/// Leaf triangles per tree crown.
pub const FOLIAGE_LEAVES_PER_TREE: usize = 600;
/// Trees in the `foliage` scene.
pub const FOLIAGE_TREES: usize = 10;

fn foliage(pose: Pose) -> Def {
    let (eye, target, light) = directional_pose(
        pose,
        [
            (v(0.0, 1.7, 16.0), v(0.0, 3.0, 0.0), 100.0, 40.0),
            (v(0.0, 1.7, 16.0), v(0.0, 4.0, 0.0), 10.0, 22.0),
            (v(0.0, 3.0, 17.0), v(0.0, 2.0, 0.0), 195.0, 28.0),
            (v(0.0, 1.7, 16.0), v(0.0, 3.0, 0.0), 90.0, 5.0),
        ],
        1.0,
    );
    let mut rng = Rng(0x5CA7_7E12);
    let mut g = vec![ground([0.3, 0.35, 0.2])];
    for t in 0..FOLIAGE_TREES {
        // Trees on a jittered ring-and-centre layout around the origin.
        let (x, z) = if t == 0 {
            (0.0, 0.0)
        } else {
            let a = std::f64::consts::TAU * (t as f64 - 1.0) / (FOLIAGE_TREES - 1) as f64;
            let r = rng.range(5.5, 8.0);
            (r * a.cos(), r * a.sin() - 2.0)
        };
        let height = rng.range(4.0, 5.5);
        g.push(Shape::Cylinder {
            a: v(x, 0.0, z),
            b: v(x, height, z),
            radius: 0.22,
            albedo: [0.35, 0.25, 0.15],
        });
        let centre = v(x, height + 1.4, z);
        let radii = v(
            rng.range(2.0, 2.6),
            rng.range(1.6, 2.1),
            rng.range(2.0, 2.6),
        );
        let mut vertices = Vec::with_capacity(3 * FOLIAGE_LEAVES_PER_TREE);
        let mut triangles = Vec::with_capacity(FOLIAGE_LEAVES_PER_TREE);
        for i in 0..FOLIAGE_LEAVES_PER_TREE {
            // Rejection-sample a point in the unit ball, scale to the crown ellipsoid.
            let p = loop {
                let q = v(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                );
                if q.length_squared() <= 1.0 {
                    break q;
                }
            };
            let c = centre + p * radii;
            let n = rng.dir();
            let a = n.any_orthonormal_vector();
            let b = n.cross(a);
            let size = rng.range(0.25, 0.45);
            let rot = rng.range(0.0, std::f64::consts::TAU);
            let (s, co) = rot.sin_cos();
            let e1 = (a * co + b * s) * size;
            let e2 = (a * -s + b * co) * size;
            vertices.extend([c + e1, c - 0.5 * e1 + 0.87 * e2, c - 0.5 * e1 - 0.87 * e2]);
            let k = 3 * i as u32;
            triangles.push([k, k + 1, k + 2]);
        }
        g.push(Shape::Mesh {
            vertices,
            triangles,
            albedo: [0.2, 0.45, 0.15],
        });
    }
    Def {
        eye,
        target,
        far: 60.0,
        light,
        medium: Medium {
            sigma_t: 0.06,
            albedo: 0.8,
            g: 0.4,
        },
        geometry: g,
    }
}

/// Heightfield samples per side of the `terrain` scene.
pub const TERRAIN_SAMPLES: u32 = 129;

fn terrain(pose: Pose) -> Def {
    let (eye, target, light) = directional_pose(
        pose,
        [
            (v(0.0, 14.0, 85.0), v(0.0, 10.0, 0.0), 100.0, 25.0),
            (v(0.0, 12.0, 85.0), v(0.0, 20.0, 0.0), 8.0, 12.0),
            (v(0.0, 30.0, 90.0), v(0.0, 5.0, 0.0), 190.0, 30.0),
            (v(0.0, 14.0, 85.0), v(0.0, 10.0, 0.0), 90.0, 5.0),
        ],
        1.0,
    );
    let n = TERRAIN_SAMPLES as usize;
    let size = 200.0;
    let mut heights = Vec::with_capacity(n * n);
    for iz in 0..n {
        for ix in 0..n {
            let x = ix as f64 / (n - 1) as f64 * size - 100.0;
            let z = iz as f64 / (n - 1) as f64 * size - 100.0;
            // Ridges across the view, rolling hills, and a valley where the camera stands.
            let ridge = 14.0 * (0.5 + 0.5 * (0.045 * z + 0.6 * (0.03 * x).sin()).sin()).powi(2);
            let hills = 4.0 * (0.11 * x + 0.7).sin() * (0.09 * z - 0.4).cos()
                + 2.0 * (0.23 * x - 0.13 * z).sin();
            let valley = (1.0 - (-(x * x) / 900.0).exp() * 0.7).max(0.0);
            heights.push(((ridge + hills) * valley + 6.0).max(0.0));
        }
    }
    let geometry = vec![Shape::Heightfield {
        origin: v(-100.0, 0.0, -100.0),
        size: [size, size],
        samples: [TERRAIN_SAMPLES, TERRAIN_SAMPLES],
        heights,
        albedo: [0.4, 0.38, 0.3],
    }];
    Def {
        eye,
        target,
        far: 260.0,
        light,
        medium: Medium {
            sigma_t: 0.008,
            albedo: 0.9,
            g: 0.5,
        },
        geometry,
    }
}

fn spot_grate(pose: Pose) -> Def {
    let (eye, target, position, aim) = match pose {
        Pose::Ordinary => (
            v(7.0, 2.2, 7.0),
            v(0.0, 0.5, 0.0),
            v(0.0, 7.0, 0.0),
            v(0.0, 0.0, 0.0),
        ),
        Pose::EpipoleOnScreen => (
            v(6.0, 1.0, 6.0),
            v(0.0, 4.0, 0.0),
            v(0.0, 7.0, 0.0),
            v(0.0, 0.0, 0.0),
        ),
        Pose::LightBehind => (
            v(0.0, 3.5, 6.0),
            v(0.0, 0.5, -1.0),
            v(0.0, 14.0, 16.0),
            v(0.0, 0.0, -0.5),
        ),
        Pose::Grazing => (
            v(-4.0, 2.5, 7.0),
            v(2.5, 1.0, -1.0),
            v(-6.0, 4.6, 0.0),
            v(2.0, 2.0, 0.0),
        ),
    };
    // In `light_behind` the lamp is a distant, narrow stage light: the camera stands inside its
    // cone, and a near lamp would flood the foreground with 1/d^2 in-scattering.
    let far_lamp = pose == Pose::LightBehind;
    let metal = [0.35, 0.35, 0.38];
    let mut g = vec![ground([0.55, 0.55, 0.55])];
    // A 4 m x 4 m grate at y = 3: bars along z, 0.12 m wide with 0.25 m gaps, a frame and posts.
    let mut x = -2.0;
    while x + 0.12 <= 2.0 + 1e-9 {
        g.push(aabb([x, 2.95, -2.0], [x + 0.12, 3.05, 2.0], metal));
        x += 0.37;
    }
    g.push(aabb([-2.1, 2.95, -2.1], [2.1, 3.05, -2.0], metal));
    g.push(aabb([-2.1, 2.95, 2.0], [2.1, 3.05, 2.1], metal));
    g.push(aabb([-2.1, 2.95, -0.05], [2.1, 3.05, 0.05], metal));
    for (px, pz) in [(-2.1, -2.1), (2.0, -2.1), (-2.1, 2.0), (2.0, 2.0)] {
        g.push(aabb([px, 0.0, pz], [px + 0.1, 2.95, pz + 0.1], metal));
    }
    Def {
        eye,
        target,
        far: 40.0,
        light: Light::Spot {
            position,
            direction: aim - position,
            inner_angle_deg: if far_lamp { 14.0 } else { 24.0 },
            outer_angle_deg: if far_lamp { 18.0 } else { 32.0 },
            intensity: if far_lamp {
                [1200.0, 1140.0, 1020.0]
            } else {
                [200.0, 190.0, 170.0]
            },
            cookie: None,
        },
        medium: Medium {
            sigma_t: 0.08,
            albedo: 0.9,
            g: 0.2,
        },
        geometry: g,
    }
}
