//! The stress configurations (issue 6): where published volumetric-lighting methods break.
//! Every family runs on each of them (`tests/tests/stress.rs`); each case states its premise
//! and [`StressCase::premise`] checks it, so a case that drifts (a scene edit moving the sun
//! off the centre pixel) fails loudly instead of silently testing something easier.
//!
//! | group | case | what |
//! |---|---|---|
//! | pose | `epipole_centre` | the camera looks straight at the sun: view axis anti-parallel to the light's travel |
//! | pose | `epipole_corner` | the sun projects 1.5 pixels from the top-left corner |
//! | pose | `epipole_just_off` | the sun projects 3 % of the height above the top edge |
//! | pose | `anti_epipole_centre` | the light travels along the view axis (exactly behind the camera) |
//! | pose | `light_parallel_image` | the light travels parallel to the image plane |
//! | pose | `camera_in_shadow` | the eye stands under the `columns` roof in its shadow |
//! | pose | `near_cuts_geometry` | a column crosses the near plane (0.6 m) |
//! | pose | `sky` | most pixels see no geometry: depth at the far plane |
//! | pose | `sky_infinite` | as `sky`, with the engine writing +inf depth on sky pixels |
//! | pose | `closed_room` | inside `window` with the sun behind the back wall: no light enters, truth exactly 0 |
//! | pose | `closed_room_windows` | as `closed_room`, looking at the windows from inside (the lit fog outside is seen through them) |
//! | pose | `spot_epipole_centre` | the camera looks straight at a spot lamp |
//! | pose | `spot_cookie_epipole_centre` | as `spot_epipole_centre`, the lamp with the `stained_glass` cookie (64^2): every family's `cookie` variant |
//! | pose | `spot_in_cone` | the eye stands inside the spot's cone |
//! | pose | `spot_outside_cone` | the eye stands outside the spot's cone |
//! | medium | `sigma_t_0` | no medium: every method must output exactly 0 |
//! | medium | `sigma_t_1e-6` | a vanishing medium (radiance near f16's subnormals) |
//! | medium | `optical_depth_10` | `sigma_t * far = 10`: thick fog |
//! | medium | `albedo_0` | absorbing medium: no in-scattering |
//! | medium | `g_-0.95`, `g_0`, `g_0.95` | strongly back-scattering, isotropic, strongly forward |
//! | size | `bases_4`, `bases_128` | few bases (ringing) and many (prefiltered only) |
//! | size | `rectified_64`, `rectified_4096` | rectified maps 64 and 4096 wide (prefiltered, minmax) |
//! | size | `screen_odd` | 101x57: divisible by no workgroup size |
//! | size | `screen_1x1` | a one-pixel screen |
//!
//! Directional cases are built on `columns`, spot cases on `spot_grate`; media and size
//! cases on `columns/ordinary`.

use glam::DVec3;

use crate::buffers::GBuffer;
use crate::bvh::Bvh;
use crate::geometry::Ray;
use crate::scene::{Light, Orientation, Scene};
use crate::suite::{self, MediumPreset, Pose, SceneName};

/// Which part of the stress matrix a case belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StressGroup {
    /// Camera and light geometry.
    Pose,
    /// Medium parameters.
    Medium,
    /// PrefilteredVariant knobs and sizes.
    Size,
}

impl std::fmt::Display for StressGroup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Pose => "pose",
            Self::Medium => "medium",
            Self::Size => "size",
        })
    }
}

/// What a case claims about its geometry, checked by [`StressCase::premise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Premise {
    /// Nothing to check beyond the scene being valid.
    None,
    /// The light (the sun's direction or the spot's position) projects within `tol_px` of
    /// pixel position (`x`, `y`) (which may lie off screen).
    EpipoleAt {
        /// Image x in pixels from the left edge.
        x: f64,
        /// Image y in pixels from the top edge.
        y: f64,
        /// Allowed distance in pixels.
        tol_px: f64,
    },
    /// The light travels along the view axis: the anti-epipole is the image centre.
    AntiEpipoleCentre,
    /// `|light . forward| < 1e-9`.
    LightParallelImage,
    /// The eye is shadowed from the light.
    EyeShadowed,
    /// Geometry lies closer to the eye than the near plane on the view axis.
    NearCutsGeometry,
    /// At least this fraction of the pixels are sky.
    SkyFraction(f64),
    /// The eye is inside (`true`) or outside (`false`) the spot's outer cone.
    EyeInCone(bool),
    /// No light reaches any point the camera sees: the truth is exactly 0 at every pixel,
    /// while the medium scatters. [`StressCase::premise`] checks that the eye is shadowed;
    /// the stress test, which renders the truth, checks the rest.
    Dark,
}

/// One stress configuration.
#[derive(Clone, Debug)]
pub struct StressCase {
    /// Case name (unique, snake_case).
    pub name: &'static str,
    /// Group.
    pub group: StressGroup,
    /// What it stresses.
    pub what: &'static str,
    /// The scene at the case's screen size.
    pub scene: Scene,
    /// Prefiltered bases override (`size` cases); `None`: the variant's own.
    pub bases: Option<u32>,
    /// Rectified map override (`size` cases); `None`: the test's default.
    pub rectified: Option<[u32; 2]>,
    /// The engine writes +inf instead of the far plane into sky pixels of the depth buffer.
    pub sky_depth_infinite: bool,
    /// The claim checked by [`StressCase::premise`].
    pub premise: Premise,
}

impl StressCase {
    /// The depth buffer the engine hands over: the cast's linear view depth, with sky pixels
    /// set to +inf for `sky_depth_infinite`.
    pub fn engine_depth(&self, gbuf: &GBuffer) -> Vec<f32> {
        gbuf.view_depth
            .iter()
            .zip(&gbuf.shape)
            .map(|(&z, &s)| {
                if self.sky_depth_infinite && s == crate::buffers::SKY {
                    f32::INFINITY
                } else {
                    z
                }
            })
            .collect()
    }

    /// Checks the case's premise; the error says what does not hold.
    ///
    /// # Errors
    ///
    /// A message naming the case and the measured quantity.
    pub fn premise(&self, bvh: &Bvh, gbuf: &GBuffer) -> Result<(), String> {
        let cam = &self.scene.camera;
        let frame = cam.frame();
        let to_light = |p: DVec3| -> DVec3 {
            match &self.scene.light {
                Light::Directional { direction, .. } => -direction.normalize(),
                Light::Spot { position, .. } => (*position - p).normalize(),
                Light::Area(a) => (a.position - p).normalize(),
            }
        };
        let fail = |what: String| Err(format!("stress case {}: {what}", self.name));
        match self.premise {
            Premise::None => Ok(()),
            Premise::EpipoleAt { x, y, tol_px } => {
                match cam.project_direction(&frame, to_light(cam.position)) {
                    Some((px, py)) if (px - x).hypot(py - y) <= tol_px => Ok(()),
                    Some((px, py)) => fail(format!(
                        "the light projects to ({px:.2}, {py:.2}), not within {tol_px} px of ({x}, {y})"
                    )),
                    None => fail("the light is behind the camera".into()),
                }
            }
            Premise::AntiEpipoleCentre => {
                let d = (-to_light(cam.position)).dot(frame.forward);
                if d > 1.0 - 1e-12 {
                    Ok(())
                } else {
                    fail(format!("light . forward = {d}, not 1"))
                }
            }
            Premise::LightParallelImage => {
                let d = to_light(cam.position).dot(frame.forward);
                if d.abs() < 1e-9 {
                    Ok(())
                } else {
                    fail(format!("light . forward = {d:e}, not 0"))
                }
            }
            Premise::EyeShadowed | Premise::Dark => {
                let dir = to_light(cam.position);
                let reach = match &self.scene.light {
                    Light::Directional { .. } => 1e6,
                    Light::Spot { position, .. } => (*position - cam.position).length(),
                    Light::Area(a) => (a.position - cam.position).length(),
                };
                if bvh.occluded(&Ray::new(cam.position, dir), 1e-6, reach) {
                    Ok(())
                } else {
                    fail("the eye sees the light".into())
                }
            }
            Premise::NearCutsGeometry => {
                if bvh.occluded(&Ray::new(cam.position, frame.forward), 0.0, cam.near) {
                    Ok(())
                } else {
                    fail(format!(
                        "nothing lies within the near plane ({} m)",
                        cam.near
                    ))
                }
            }
            Premise::SkyFraction(min) => {
                let sky = gbuf
                    .shape
                    .iter()
                    .filter(|&&s| s == crate::buffers::SKY)
                    .count() as f64
                    / gbuf.shape.len() as f64;
                if sky >= min {
                    Ok(())
                } else {
                    fail(format!("sky fraction {sky:.3} < {min}"))
                }
            }
            Premise::EyeInCone(inside) => {
                let Light::Spot {
                    position,
                    direction,
                    outer_angle_deg,
                    ..
                } = &self.scene.light
                else {
                    return fail("not a spot light".into());
                };
                let cos = (cam.position - *position)
                    .normalize()
                    .dot(direction.normalize());
                let is_inside = cos > outer_angle_deg.to_radians().cos();
                if is_inside == inside {
                    Ok(())
                } else {
                    fail(format!(
                        "the eye is {} the cone (angle {:.1} deg, outer {outer_angle_deg} deg)",
                        if is_inside { "inside" } else { "outside" },
                        cos.clamp(-1.0, 1.0).acos().to_degrees()
                    ))
                }
            }
        }
    }
}

/// Sets one medium parameter (`far` given for `optical_depth_10`).
type SetMedium = fn(&mut crate::scene::Medium, f64);

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// Sets the camera to look along `forward` from `eye`.
fn look(scene: &mut Scene, eye: DVec3, forward: DVec3) {
    scene.camera.position = eye;
    scene.camera.orientation = Orientation::Forward {
        forward: forward.normalize(),
        up: DVec3::Y,
    };
}

/// A sun whose light travels along `direction`, with the scene's irradiance.
fn sun(scene: &mut Scene, direction: DVec3) {
    let irradiance = scene.light.color();
    scene.light = Light::Directional {
        direction: direction.normalize(),
        irradiance,
    };
}

fn case(
    name: &'static str,
    group: StressGroup,
    what: &'static str,
    scene: Scene,
    premise: Premise,
) -> StressCase {
    let mut scene = scene;
    scene.name = format!("stress/{name}");
    StressCase {
        name,
        group,
        what,
        scene,
        bases: None,
        rectified: None,
        sky_depth_infinite: false,
        premise,
    }
}

/// Every stress case at a `width` x `height` screen (the `screen_*` cases use their own).
pub fn cases(width: u32, height: u32) -> Vec<StressCase> {
    use StressGroup::{Medium, Pose as P, Size};
    let columns = |w, h| {
        suite::scene(
            SceneName::Columns,
            Pose::Ordinary,
            MediumPreset::Default,
            w,
            h,
        )
    };
    let base = columns(width, height);
    let eye = v(0.0, 1.7, 13.0);
    let mut out = Vec::new();

    // The camera looks at the sun 14 degrees up: epipole at the image centre.
    let mut s = base.clone();
    let to_sun = v(0.0, 14f64.to_radians().tan(), -1.0).normalize();
    look(&mut s, eye, to_sun);
    sun(&mut s, -to_sun);
    let centre = (f64::from(width) / 2.0, f64::from(height) / 2.0);
    out.push(case(
        "epipole_centre",
        P,
        "camera looks straight at the sun (view axis anti-parallel to the light)",
        s,
        Premise::EpipoleAt {
            x: centre.0,
            y: centre.1,
            tol_px: 1e-6,
        },
    ));

    // The sun on the ray through a pixel near the top-left corner, or just above the top
    // edge, of a camera looking slightly up the portico.
    for (name, what, px, py) in [
        (
            "epipole_corner",
            "the sun projects 1.5 pixels from the top-left corner",
            1.5,
            1.5,
        ),
        (
            "epipole_just_off",
            "the sun projects just above the top edge (3 % of the height)",
            0.5 * f64::from(width),
            -0.03 * f64::from(height),
        ),
    ] {
        let mut s = base.clone();
        look(&mut s, eye, v(0.0, 0.08, -1.0));
        let frame = s.camera.frame();
        let to_sun = s.camera.ray_dir(&frame, px, py);
        sun(&mut s, -to_sun);
        out.push(case(
            name,
            P,
            what,
            s,
            Premise::EpipoleAt {
                x: px,
                y: py,
                tol_px: 1e-6,
            },
        ));
    }

    // The light travels along the view axis: the sun exactly behind the camera.
    let mut s = base.clone();
    let forward = v(0.0, -0.35, -1.0).normalize();
    look(&mut s, v(0.0, 4.0, 14.0), forward);
    sun(&mut s, forward);
    out.push(case(
        "anti_epipole_centre",
        P,
        "the light travels along the view axis (sun exactly behind the camera)",
        s,
        Premise::AntiEpipoleCentre,
    ));

    // Horizontal view axis, sun 35 degrees up in the plane of image right and up.
    let mut s = base.clone();
    look(&mut s, v(1.5, 1.8, 14.0), v(0.0, 0.0, -1.0));
    let f = s.camera.frame();
    let (sn, cs) = 35f64.to_radians().sin_cos();
    sun(&mut s, -(f.right * cs + f.up * sn));
    out.push(case(
        "light_parallel_image",
        P,
        "the light travels parallel to the image plane",
        s,
        Premise::LightParallelImage,
    ));

    // Under the roof slab (x in [-3.6, -0.6], y >= 6.6) with the sun 75 degrees up.
    let mut s = base.clone();
    look(&mut s, v(-2.1, 3.0, 2.0), v(0.2, -0.05, -1.0));
    let (sn, cs) = 75f64.to_radians().sin_cos();
    sun(&mut s, -v(0.3 * cs, sn, 0.95 * cs));
    out.push(case(
        "camera_in_shadow",
        P,
        "the eye stands in the roof's shadow",
        s,
        Premise::EyeShadowed,
    ));

    // A column (x = 3, z = 1.5, r = 0.4) 0.4 m ahead of the eye, the near plane at 0.6 m.
    let mut s = base.clone();
    look(&mut s, v(3.0, 2.0, 2.3), v(0.0, 0.0, -1.0));
    s.camera.near = 0.6;
    out.push(case(
        "near_cuts_geometry",
        P,
        "the near plane (0.6 m) cuts through a column",
        s,
        Premise::NearCutsGeometry,
    ));

    // Looking 40 degrees up: the roof edge and sky.
    for (name, what, infinite) in [
        ("sky", "most pixels are sky (depth at the far plane)", false),
        (
            "sky_infinite",
            "most pixels are sky and the engine writes +inf depth there",
            true,
        ),
    ] {
        let mut s = base.clone();
        look(&mut s, v(6.0, 1.7, 14.0), v(0.0, 0.84, -1.0));
        let mut c = case(name, P, what, s, Premise::SkyFraction(0.5));
        c.sky_depth_infinite = infinite;
        out.push(c);
    }

    // A closed room: inside `window` (room x, z in [-6, 6], y in [0, 5], windows in the wall
    // at z = -6) with the sun behind the back wall (light travelling towards -z), 35 degrees
    // up: every light ray into the room is blocked by the roof or the back wall. The
    // Fourier series of the prefiltered method rang here ("light in closed rooms", issue 12).
    let room = suite::scene(
        SceneName::Window,
        Pose::Ordinary,
        MediumPreset::Default,
        width,
        height,
    );
    let (sn, cs) = 35f64.to_radians().sin_cos();
    let behind = -v(0.3 * cs, sn, 0.95 * cs);
    let mut s = room.clone();
    look(&mut s, v(3.0, 1.6, -2.0), v(-0.6, 0.1, 1.0));
    sun(&mut s, behind);
    out.push(case(
        "closed_room",
        P,
        "inside the window room, the sun behind its back wall: no light enters",
        s,
        Premise::Dark,
    ));
    let mut s = room.clone();
    look(&mut s, v(2.0, 1.8, 3.0), v(-0.2, 0.05, -1.0));
    sun(&mut s, behind);
    out.push(case(
        "closed_room_windows",
        P,
        "inside the dark room, looking out through the windows at the lit fog",
        s,
        Premise::EyeShadowed,
    ));
    // Under the central tree of `foliage` (crown 5.4-6.9 m up, 2.0-2.6 m wide), looking
    // between the trees, the sun 60 degrees up: view rays cross the leaves' shadows of several
    // crowns, so a shadow volume's first and last crossings can span most of a ray (Wyman &
    // Ramsey's degenerate case, where the interval is the whole ray).
    let mut s = suite::scene(
        SceneName::Foliage,
        Pose::Ordinary,
        MediumPreset::Default,
        width,
        height,
    );
    look(&mut s, v(0.8, 1.7, 0.8), v(0.3, 0.15, 1.0));
    let (sn, cs) = 60f64.to_radians().sin_cos();
    sun(&mut s, -v(0.5 * cs, sn, -0.85 * cs));
    out.push(case(
        "foliage_under_canopy",
        P,
        "under a tree's crown among trees: view rays cross the leaves' shadows of several crowns",
        s,
        Premise::None,
    ));
    // Spot light cases on spot_grate.
    let spot = |pose| {
        suite::scene(
            SceneName::SpotGrate,
            pose,
            MediumPreset::Default,
            width,
            height,
        )
    };
    let mut s = spot(Pose::Ordinary);
    let lamp = match s.light {
        Light::Spot { position, .. } => position,
        Light::Directional { .. } | Light::Area(_) => unreachable!("spot_grate has a spot light"),
    };
    let eye = v(6.0, 1.5, 6.0);
    look(&mut s, eye, lamp - eye);
    let mut tinted = s.clone();
    out.push(case(
        "spot_epipole_centre",
        P,
        "the camera looks straight at the spot lamp",
        s,
        Premise::EpipoleAt {
            x: centre.0,
            y: centre.1,
            tol_px: 1e-6,
        },
    ));
    if let Light::Spot { cookie, .. } = &mut tinted.light {
        *cookie = Some(
            crate::cookie::Cookie::pattern("stained_glass", 64)
                .expect("stained_glass is a built-in pattern"),
        );
    }
    out.push(case(
        "spot_cookie_epipole_centre",
        P,
        "the camera looks straight at a spot lamp with the stained_glass cookie (the coloured \
         glow around the lamp is marched per sample, the rest integrated with the cookie)",
        tinted,
        Premise::EpipoleAt {
            x: centre.0,
            y: centre.1,
            tol_px: 1e-6,
        },
    ));
    out.push(case(
        "spot_in_cone",
        P,
        "the eye stands inside the spot's cone",
        spot(Pose::LightBehind),
        Premise::EyeInCone(true),
    ));
    out.push(case(
        "spot_outside_cone",
        P,
        "the eye stands outside the spot's cone",
        spot(Pose::Ordinary),
        Premise::EyeInCone(false),
    ));

    // Media on columns/ordinary.
    let far = base.camera.far;
    let media: [(&'static str, &'static str, SetMedium); 7] = [
        ("sigma_t_0", "no medium (sigma_t = 0)", |m, _| {
            m.sigma_t = 0.0
        }),
        (
            "sigma_t_1e-6",
            "vanishing medium (sigma_t = 1e-6)",
            |m, _| {
                m.sigma_t = 1e-6;
            },
        ),
        (
            "optical_depth_10",
            "thick fog: sigma_t * far = 10",
            |m, far| m.sigma_t = 10.0 / far,
        ),
        ("albedo_0", "absorbing medium (albedo 0)", |m, _| {
            m.albedo = 0.0;
        }),
        ("g_-0.95", "Henyey-Greenstein g = -0.95", |m, _| m.g = -0.95),
        ("g_0", "isotropic phase (g = 0)", |m, _| m.g = 0.0),
        ("g_0.95", "Henyey-Greenstein g = 0.95", |m, _| m.g = 0.95),
    ];
    for (name, what, set) in media {
        let mut s = base.clone();
        set(&mut s.medium, far);
        out.push(case(name, Medium, what, s, Premise::None));
    }

    // Knobs and sizes on columns/ordinary.
    for (name, what, bases) in [
        ("bases_4", "4 Fourier bases (ringing)", 4),
        ("bases_128", "128 Fourier bases", 128),
    ] {
        let mut c = case(name, Size, what, base.clone(), Premise::None);
        c.bases = Some(bases);
        out.push(c);
    }
    for (name, what, wr) in [
        ("rectified_64", "a rectified map 64 texels wide", 64),
        ("rectified_4096", "a rectified map 4096 texels wide", 4096),
    ] {
        let mut c = case(name, Size, what, base.clone(), Premise::None);
        c.rectified = Some([wr, 256]);
        out.push(c);
    }
    out.push(case(
        "screen_odd",
        Size,
        "a 101x57 screen: divisible by no workgroup size",
        columns(101, 57),
        Premise::None,
    ));
    out.push(case(
        "screen_1x1",
        Size,
        "a one-pixel screen",
        columns(1, 1),
        Premise::None,
    ));
    out
}
