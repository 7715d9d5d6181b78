//! The area-light suite (issue 17): suite geometry lit by an area light
//! ([`crate::scene::AreaLight`]) instead of the sun or the spot.
//!
//! | scene | geometry | light |
//! |---|---|---|
//! | `area_columns` | `columns` | a disk of radius 1 m, 20 m from the portico |
//! | `area_window` | `window` | a 3 m x 2 m panel 12 m outside the windows |
//! | `area_grate` | `spot_grate` | a 0.8 m x 0.8 m panel where the spot's lamp was |
//!
//! The poses are the suite's ([`Pose`]): the camera of the base scene's pose, and the light
//! where that pose puts its sun (at the scene's distance along the direction towards the sun,
//! aimed at the scene's centre, its cone just covering the scene: the same irradiance at the
//! centre as the sun's) or its spot (the same position, axis and cone, and the spot's
//! intensity as the panel's point limit). So `epipole_on_screen` has the light on screen,
//! `light_behind` behind the camera, and `grazing` low across the scene. Each light has its
//! housing ([`AreaLight::housing`]): a view ray that reaches the light ends at it.

use crate::scene::{AreaLight, AreaShape, Light, Scene};
use crate::suite::{self, MediumPreset, Pose, SceneName};
use glam::DVec3;
use std::fmt;
use std::str::FromStr;

/// The area-light suite's scenes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AreaSceneName {
    /// The portico lit by a distant disk.
    Columns,
    /// The room lit through its windows by a panel outside.
    Window,
    /// The grate under a small panel.
    Grate,
}

impl AreaSceneName {
    /// Every scene, in suite order.
    pub const ALL: &'static [AreaSceneName] = &[
        AreaSceneName::Columns,
        AreaSceneName::Window,
        AreaSceneName::Grate,
    ];

    /// The snake_case name used in trial names, files and the CLI.
    pub fn name(self) -> &'static str {
        match self {
            AreaSceneName::Columns => "area_columns",
            AreaSceneName::Window => "area_window",
            AreaSceneName::Grate => "area_grate",
        }
    }

    /// The suite scene whose geometry and camera poses this scene takes.
    pub fn base(self) -> SceneName {
        match self {
            AreaSceneName::Columns => SceneName::Columns,
            AreaSceneName::Window => SceneName::Window,
            AreaSceneName::Grate => SceneName::SpotGrate,
        }
    }
}

impl fmt::Display for AreaSceneName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for AreaSceneName {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        AreaSceneName::ALL
            .iter()
            .copied()
            .find(|n| n.name() == s)
            .ok_or_else(|| {
                let all: Vec<&str> = AreaSceneName::ALL.iter().map(|n| n.name()).collect();
                format!("area scene must be one of {}, got '{s}'", all.join(", "))
            })
    }
}

/// How far behind the emitting face the suite's lamp housings stand (metres).
pub const HOUSING_BEHIND: f64 = 1e-3;

/// Where a sun-lit base scene's area light stands.
struct Placement {
    /// The point the light aims at.
    centre: DVec3,
    /// Distance from the centre along the direction towards the sun.
    distance: f64,
    /// Radius around the centre the cone must cover.
    reach: f64,
    /// The outline.
    shape: AreaShape,
}

/// Builds an area-light suite scene at the given resolution.
pub fn scene(
    name: AreaSceneName,
    pose: Pose,
    preset: MediumPreset,
    width: u32,
    height: u32,
) -> Scene {
    let mut s = suite::scene(name.base(), pose, preset, width, height);
    let place = |p: Placement, direction: DVec3, irradiance: [f64; 3]| {
        let to_sun = -direction.normalize();
        let outer = (p.reach / p.distance).atan().to_degrees() + 5.0;
        let scale = p.distance * p.distance / p.shape.area();
        AreaLight {
            position: p.centre + to_sun * p.distance,
            direction: -to_sun,
            up: None,
            shape: p.shape,
            inner_angle_deg: outer - 10.0,
            outer_angle_deg: outer,
            radiance: irradiance.map(|e| e * scale),
            two_sided: false,
        }
    };
    let light = match (name, &s.light) {
        (
            AreaSceneName::Columns,
            Light::Directional {
                direction,
                irradiance,
            },
        ) => place(
            Placement {
                centre: DVec3::new(0.0, 3.0, -2.0),
                distance: 20.0,
                reach: 12.0,
                shape: AreaShape::Disk { radius: 1.0 },
            },
            *direction,
            *irradiance,
        ),
        (
            AreaSceneName::Window,
            Light::Directional {
                direction,
                irradiance,
            },
        ) => place(
            Placement {
                centre: DVec3::new(0.0, 2.4, -6.0),
                distance: 12.0,
                reach: 6.5,
                shape: AreaShape::Rect {
                    width: 3.0,
                    height: 2.0,
                },
            },
            *direction,
            *irradiance,
        ),
        (
            _,
            Light::Spot {
                position,
                direction,
                inner_angle_deg,
                outer_angle_deg,
                intensity,
                ..
            },
        ) => {
            let shape = AreaShape::Rect {
                width: 0.8,
                height: 0.8,
            };
            AreaLight {
                position: *position,
                direction: *direction,
                up: None,
                shape,
                inner_angle_deg: *inner_angle_deg,
                outer_angle_deg: *outer_angle_deg,
                radiance: intensity.map(|i| i / shape.area()),
                two_sided: false,
            }
        }
        (_, light) => unreachable!("{name}'s base scene has a sun or a spot, got {light:?}"),
    };
    // The lamp's housing: view rays that reach the light end at it.
    s.geometry
        .extend(light.housing(HOUSING_BEHIND, [0.3, 0.3, 0.3]));
    s.light = Light::Area(light);
    s.name = format!("{name}/{}", s.name.split_once('/').map_or("", |(_, p)| p));
    s
}

/// Every (scene, pose) of the area-light suite.
pub fn all() -> Vec<(AreaSceneName, Pose)> {
    AreaSceneName::ALL
        .iter()
        .flat_map(|&n| Pose::ALL.iter().map(move |&p| (n, p)))
        .collect()
}

/// Rebuilds the lamp's housing (the suite scene's last shape) after its light moved or
/// changed size.
pub fn rebuild_housing(scene: &mut Scene) {
    if let Light::Area(a) = &scene.light
        && let Some(h) = a.housing(HOUSING_BEHIND, [0.3, 0.3, 0.3])
        && let Some(last) = scene.geometry.last_mut()
    {
        *last = h;
    }
}

/// Frame `frame` of `frames` of `path` ([`crate::paths`]: the camera dollies, or the light's
/// aim circles) for area scene `name` from its `ordinary` pose, the housing moved with the
/// light.
pub fn animated(
    name: AreaSceneName,
    path: crate::paths::Path,
    frame: usize,
    frames: usize,
    width: u32,
    height: u32,
) -> Scene {
    let mut s = scene(name, Pose::Ordinary, MediumPreset::Default, width, height);
    crate::paths::animate(&mut s, path, frame, frames);
    rebuild_housing(&mut s);
    s
}

/// `area_grate` with its light resized to a `side` x `side` square of the same power.
fn resized(pose: Pose, side: f64, width: u32, height: u32) -> Scene {
    let mut s = scene(
        AreaSceneName::Grate,
        pose,
        MediumPreset::Default,
        width,
        height,
    );
    if let Light::Area(a) = &mut s.light {
        let area = a.shape.area();
        a.shape = AreaShape::Rect {
            width: side,
            height: side,
        };
        // The same power: the radiance scales with 1 / area.
        a.radiance = a.radiance.map(|r| r * area / (side * side));
    }
    rebuild_housing(&mut s);
    s
}

/// Where area lights stress a method (issue 17), each named `area_grate/<pose>/<case>`: a
/// light a millimetre across (`tiny`: all VPLs in one point, which must give its point
/// limit) and a 6 m x 6 m panel over the 4 m grate (`huge`: no umbra left under it), at the
/// `ordinary` and `epipole_on_screen` poses, and the eye inside the penumbra
/// (`eye_in_penumbra`: under the grate, seeing part of the panel between the bars).
pub fn stress_scenes(width: u32, height: u32) -> Vec<Scene> {
    let mut cases = Vec::new();
    for pose in [Pose::Ordinary, Pose::EpipoleOnScreen] {
        let mut tiny = resized(pose, 1e-3, width, height);
        tiny.name = format!("{}/tiny", tiny.name);
        cases.push(tiny);
        let mut huge = resized(pose, 6.0, width, height);
        huge.name = format!("{}/huge", huge.name);
        cases.push(huge);
    }
    let mut inside = scene(
        AreaSceneName::Grate,
        Pose::Ordinary,
        MediumPreset::Default,
        width,
        height,
    );
    inside.camera.position = DVec3::new(0.6, 1.2, 0.3);
    inside.camera.orientation = crate::scene::Orientation::LookAt {
        target: DVec3::new(4.0, 2.0, 2.0),
        up: DVec3::Y,
    };
    inside.name = format!("{}/eye_in_penumbra", inside.name);
    cases.push(inside);
    cases
}

/// The truth a stress case of [`stress_scenes`] is measured against: the `vpl` truth with
/// `vpls` VPLs and `map_size`^2 maps, except for the tiny light, whose VPLs all stand in one
/// point: there the `shadow_map` truth of its point limit (what a shrinking light must tend
/// to).
///
/// # Errors
///
/// A shadow map that cannot be built.
pub fn stress_truth(
    scene: &Scene,
    gbuf: &crate::buffers::GBuffer,
    bvh: &crate::bvh::Bvh,
    vpls: usize,
    map_size: u32,
    settings: &crate::truth::TruthSettings,
) -> Result<crate::image::Image, crate::buffers::ShadowMapError> {
    match &scene.light {
        Light::Area(a) if scene.name.ends_with("/tiny") => {
            let point = Scene {
                light: a.point_limit(),
                ..scene.clone()
            };
            let sm = crate::buffers::ShadowMap::build(&point, bvh, map_size)?;
            Ok(crate::truth::render(
                &point,
                gbuf,
                &crate::truth::Visibility::ShadowMap(&sm),
                settings,
                &|| (),
            ))
        }
        _ => crate::truth::render_vpl(scene, gbuf, bvh, vpls, map_size, settings),
    }
}
