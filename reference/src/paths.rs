//! Animated sequences for the temporal-stability (flicker) measurements of issue 6: per suite
//! scene, a camera path and a light rotation of any number of frames, both starting from
//! the scene's `ordinary` pose.
//!
//! - camera path: the eye dollies 1.5 m to the right and 1 m forward (in the camera's own
//!   frame at the start) and rises 0.3 m, still looking at the pose's target; a smoothstep
//!   in time, so the speed varies like a real camera's;
//! - light rotation: the sun's direction turns 30 degrees about the vertical; a spot's aim
//!   point circles 1 m around its start on the ground (the cone sweeps the grate).

use glam::{DMat3, DVec3};

use crate::scene::{Light, Orientation, Scene};
use crate::suite::{self, MediumPreset, Pose, SceneName};

/// Which animation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// The camera moves, the light stays.
    Camera,
    /// The light turns, the camera stays.
    Light,
}

impl Path {
    /// Both paths.
    pub const ALL: [Path; 2] = [Path::Camera, Path::Light];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            Path::Camera => "camera_path",
            Path::Light => "light_rotation",
        }
    }
}

impl std::fmt::Display for Path {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Frame `frame` of `frames` (0-based) of `path` for suite scene `name` at `width` x `height`.
///
/// # Panics
///
/// Never for `frames >= 1`; `frame` is clamped to the last frame.
pub fn frame(
    name: SceneName,
    path: Path,
    frame: usize,
    frames: usize,
    width: u32,
    height: u32,
) -> Scene {
    let mut scene = suite::scene(name, Pose::Ordinary, MediumPreset::Default, width, height);
    animate(&mut scene, path, frame, frames);
    scene
}

/// Moves `scene` (at its start) to frame `frame` of `frames` of `path` and appends
/// `/<path>/<frame>` to its name: what [`frame`] does to a suite scene, for any scene.
pub fn animate(scene: &mut Scene, path: Path, frame: usize, frames: usize) {
    let u = if frames > 1 {
        frame.min(frames - 1) as f64 / (frames - 1) as f64
    } else {
        0.0
    };
    let ease = u * u * (3.0 - 2.0 * u);
    match path {
        Path::Camera => {
            let f = scene.camera.frame();
            let horizontal = DVec3::new(f.forward.x, 0.0, f.forward.z).normalize_or_zero();
            let right = DVec3::new(f.right.x, 0.0, f.right.z).normalize_or_zero();
            let start = scene.camera.position;
            scene.camera.position =
                start + ease * (1.5 * right + 1.0 * horizontal + 0.3 * DVec3::Y);
            // Keep looking at the pose's target.
            if let Orientation::Forward { .. } = scene.camera.orientation {
                scene.camera.orientation = Orientation::LookAt {
                    target: start + f.forward * 10.0,
                    up: DVec3::Y,
                };
            }
        }
        Path::Light => {
            let turn = DMat3::from_rotation_y((30.0 * ease).to_radians());
            match &mut scene.light {
                Light::Directional { direction, .. } => *direction = turn * *direction,
                Light::Spot {
                    position,
                    direction,
                    ..
                } => {
                    // The aim point on the ground circles 1 m around its start.
                    let t = -position.y / direction.y.min(-1e-6);
                    let aim = *position + *direction * t;
                    let a = std::f64::consts::TAU * ease;
                    let moved = aim + DVec3::new(a.cos() - 1.0, 0.0, a.sin());
                    *direction = moved - *position;
                }
                Light::Area(area) => {
                    // As a spot: the aim point of the normal circles 1 m around its start.
                    let t = -area.position.y / area.direction.y.min(-1e-6);
                    let aim = area.position + area.direction * t;
                    let a = std::f64::consts::TAU * ease;
                    let moved = aim + DVec3::new(a.cos() - 1.0, 0.0, a.sin());
                    area.direction = moved - area.position;
                }
            }
        }
    }
    scene.name = format!("{}/{path}/{frame}", scene.name);
}
