//! Scene description: camera, light, participating medium and geometry, loadable from JSON
//! and validated so that every later stage can trust it.
//!
//! Validation rejects NaN/infinite numbers, zero-length directions, a vertical field of view
//! outside (0, 180) degrees, `near >= far`, a negative `sigma_t`, `|g| >= 1` and malformed
//! geometry, each with a message that names the offending field (`camera.fov_y_deg`, ...).

use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Why a scene was rejected.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A field has a value outside its allowed range.
    #[error("invalid scene: {field} {problem}")]
    Invalid {
        /// Path of the offending field, e.g. `camera.fov_y_deg` or `geometry[3].radius`.
        field: String,
        /// What is wrong with it, including the value.
        problem: String,
    },
    /// The JSON could not be parsed.
    #[error("invalid scene JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// The file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
}

fn invalid(field: impl Into<String>, problem: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        field: field.into(),
        problem: problem.into(),
    }
}

/// A complete scene: what the reference renders and what every method gets as input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Scene name (suite name, possibly with pose and medium preset).
    pub name: String,
    /// The viewer.
    pub camera: Camera,
    /// The one light of this pass.
    pub light: Light,
    /// The homogeneous participating medium.
    pub medium: Medium,
    /// Occluders and receivers.
    pub geometry: Vec<Shape>,
    /// Radiance of the sky behind the far plane (RGB), used only for composites.
    #[serde(default = "default_sky")]
    pub sky: [f64; 3],
}

fn default_sky() -> [f64; 3] {
    [0.02, 0.025, 0.035]
}

/// Which way the camera looks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Orientation {
    /// Look at a point, with an approximate up vector.
    LookAt {
        /// Point the view axis passes through.
        target: DVec3,
        /// Approximate up direction (made orthogonal to the view axis).
        up: DVec3,
    },
    /// Look along a direction, with an approximate up vector.
    Forward {
        /// View axis direction (need not be normalised).
        forward: DVec3,
        /// Approximate up direction (made orthogonal to the view axis).
        up: DVec3,
    },
}

/// A pinhole camera. Pixel (0, 0) is the top-left corner of the image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position.
    pub position: DVec3,
    /// View direction.
    pub orientation: Orientation,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f64,
    /// Near plane distance along the view axis (geometry closer than this is clipped).
    pub near: f64,
    /// Far plane distance along the view axis (sky pixels integrate up to it).
    pub far: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// An orthonormal camera frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// View axis.
    pub forward: DVec3,
    /// Image right.
    pub right: DVec3,
    /// Image up.
    pub up: DVec3,
}

impl Camera {
    /// The orthonormal frame (forward, right, up) of a validated camera.
    pub fn frame(&self) -> Frame {
        let (forward, up) = match &self.orientation {
            Orientation::LookAt { target, up } => (*target - self.position, *up),
            Orientation::Forward { forward, up } => (*forward, *up),
        };
        let forward = forward.normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        Frame { forward, right, up }
    }

    /// Width over height.
    pub fn aspect(&self) -> f64 {
        f64::from(self.width) / f64::from(self.height)
    }

    /// tan(fov_y / 2).
    pub fn tan_half_fov(&self) -> f64 {
        (self.fov_y_deg.to_radians() * 0.5).tan()
    }

    /// Unit direction of the ray through image position (`px`, `py`) in pixels, measured
    /// from the top-left corner; pixel centres are at half-integers.
    pub fn ray_dir(&self, frame: &Frame, px: f64, py: f64) -> DVec3 {
        let t = self.tan_half_fov();
        let ndc_x = 2.0 * px / f64::from(self.width) - 1.0;
        let ndc_y = 1.0 - 2.0 * py / f64::from(self.height);
        (frame.forward + frame.right * (ndc_x * t * self.aspect()) + frame.up * (ndc_y * t))
            .normalize()
    }

    /// Where a world direction lands on the image plane, in pixels from the top-left
    /// corner, or `None` if it points behind the camera (or parallel to the image plane).
    pub fn project_direction(&self, frame: &Frame, dir: DVec3) -> Option<(f64, f64)> {
        let z = dir.dot(frame.forward);
        if z <= 1e-12 {
            return None;
        }
        let t = self.tan_half_fov();
        let ndc_x = dir.dot(frame.right) / (z * t * self.aspect());
        let ndc_y = dir.dot(frame.up) / (z * t);
        Some((
            (ndc_x + 1.0) * 0.5 * f64::from(self.width),
            (1.0 - ndc_y) * 0.5 * f64::from(self.height),
        ))
    }

    /// The eight corners of the view frustum (near quad then far quad).
    pub fn frustum_corners(&self) -> [DVec3; 8] {
        let f = self.frame();
        let t = self.tan_half_fov();
        let a = self.aspect();
        let mut out = [DVec3::ZERO; 8];
        for (i, d) in [self.near, self.far].into_iter().enumerate() {
            for (j, (sx, sy)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .into_iter()
                .enumerate()
            {
                out[i * 4 + j] = self.position
                    + f.forward * d
                    + f.right * (sx * d * t * a)
                    + f.up * (sy * d * t);
            }
        }
        out
    }
}

/// The light of one pass (several lights are several passes whose results add).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Light {
    /// A distant light (the sun): parallel rays, no extinction along the light path.
    Directional {
        /// Direction the light travels (from the sun into the scene); need not be normalised.
        direction: DVec3,
        /// Irradiance E (RGB) on a surface facing the light, before any shadowing.
        irradiance: [f64; 3],
    },
    /// A spot light: L_in = I * cone(angle) * exp(-sigma_t d) / d^2.
    Spot {
        /// Light position.
        position: DVec3,
        /// Cone axis (direction the light points); need not be normalised.
        direction: DVec3,
        /// Full intensity inside this half-angle (degrees).
        inner_angle_deg: f64,
        /// Zero intensity beyond this half-angle (degrees); 180 means no cone (a point light).
        outer_angle_deg: f64,
        /// Radiant intensity I (RGB) on the axis.
        intensity: [f64; 3],
        /// An RGB texture projected along the cone that multiplies the intensity
        /// ([`crate::cookie`]); needs `outer_angle_deg < 90`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        cookie: Option<crate::cookie::Cookie>,
    },
    /// A rectangular or disk-shaped area light ([`AreaLight`]): soft shadows. The methods
    /// and the `vpl` truth render it as N virtual point lights ([`AreaLight::vpls`]), each a
    /// spot; the `exact` truth integrates over its surface.
    Area(AreaLight),
}

/// The outline of an area light, in its own plane.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum AreaShape {
    /// A rectangle centred on the light's position.
    Rect {
        /// Extent along the light's right axis (> 0, metres).
        width: f64,
        /// Extent along the light's up axis (> 0, metres).
        height: f64,
    },
    /// A disk centred on the light's position.
    Disk {
        /// Radius (> 0, metres).
        radius: f64,
    },
}

impl AreaShape {
    /// The outline as the kernels' set-up takes it.
    pub fn desc(&self) -> scatter_shaderlib::area_ivsv::AreaShapeDesc {
        use scatter_shaderlib::area_ivsv::AreaShapeDesc;
        match *self {
            AreaShape::Rect { width, height } => AreaShapeDesc::Rect { width, height },
            AreaShape::Disk { radius } => AreaShapeDesc::Disk { radius },
        }
    }

    /// Surface area (one side), m^2.
    pub fn area(&self) -> f64 {
        match *self {
            AreaShape::Rect { width, height } => width * height,
            AreaShape::Disk { radius } => std::f64::consts::PI * radius * radius,
        }
    }

    /// The point of the outline for `(u, v)` in the unit square, in the light's plane
    /// coordinates (right, up): a rectangle maps linearly, a disk by Shirley and Chiu's
    /// concentric map; both preserve area, so uniform or low-discrepancy points in the square
    /// stay so on the light.
    pub fn point(&self, u: f64, v: f64) -> (f64, f64) {
        self.desc().point(u, v)
    }

    /// The largest distance of a point of the outline from its centre.
    pub fn radius(&self) -> f64 {
        match *self {
            AreaShape::Rect { width, height } => 0.5 * width.hypot(height),
            AreaShape::Disk { radius } => radius,
        }
    }
}

/// An area light: a flat emitter whose every surface element `dA` is a small spot light of
/// radiant intensity `radiance * cone(angle) * dA` (W/sr), `angle` measured from the
/// emitting normal and `cone` the spot's smoothstep from the outer to the inner half-angle.
///
/// Along the normal `radiance` is the radiance an observer sees. The emission profile is the
/// spot's cone, not Lambert's cosine, so that each virtual point light is exactly a
/// [`Light::Spot`] with a single perspective shadow map (which needs `outer_angle_deg < 80`),
/// and a small light tends to the spot light of intensity `radiance * area`
/// ([`AreaLight::point_limit`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AreaLight {
    /// Centre of the light.
    pub position: DVec3,
    /// The emitting normal (the cone's axis); need not be normalised.
    pub direction: DVec3,
    /// The outline's up axis, made orthogonal to `direction` (need not be normalised); when
    /// absent, the up axis of the light frame ([`crate::buffers::light_basis`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<DVec3>,
    /// The outline (rectangle or disk) in the light's plane.
    pub shape: AreaShape,
    /// Full emission inside this half-angle from the normal (degrees).
    pub inner_angle_deg: f64,
    /// No emission beyond this half-angle from the normal (degrees, in (0, 90]).
    pub outer_angle_deg: f64,
    /// Radiance along the normal (RGB, W sr^-1 m^-2).
    pub radiance: [f64; 3],
    /// Whether the back face emits too (the same cone about the reversed normal); one-sided
    /// when false (the default).
    #[serde(default)]
    pub two_sided: bool,
}

impl AreaLight {
    /// The light as the kernels' set-up takes it (`LightDesc::Area`): the VPL placement
    /// and the VPLs' maps are its ([`scatter_shaderlib::area_ivsv::AreaLightDesc`]).
    pub fn desc(&self) -> scatter_shaderlib::area_ivsv::AreaLightDesc {
        scatter_shaderlib::area_ivsv::AreaLightDesc {
            position: self.position,
            direction: self.direction,
            up: self.up,
            shape: self.shape.desc(),
            inner_deg: self.inner_angle_deg,
            outer_deg: self.outer_angle_deg,
            radiance: self.radiance,
            two_sided: self.two_sided,
        }
    }

    /// The light's frame: right and up span its plane, `normal` is the emitting normal.
    pub fn frame(&self) -> (DVec3, DVec3, DVec3) {
        let [right, up, n] = self.desc().frame();
        (right, up, n)
    }

    /// The world point of the light for `(u, v)` in the unit square ([`AreaShape::point`]).
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        self.desc().point(u, v)
    }

    /// The spots a point `p` of the light stands for: one per emitting face, along the
    /// face's normal, with the light's cone and the given intensity.
    fn spots_at(&self, p: DVec3, intensity: [f64; 3]) -> impl Iterator<Item = Light> + '_ {
        let normal = self.frame().2;
        [1.0, -1.0]
            .into_iter()
            .take(self.faces())
            .map(move |side| Light::Spot {
                position: p,
                direction: normal * side,
                inner_angle_deg: self.inner_angle_deg,
                outer_angle_deg: self.outer_angle_deg,
                intensity,
                cookie: None,
            })
    }

    /// Emitting faces: 1, or 2 when two-sided.
    pub fn faces(&self) -> usize {
        if self.two_sided { 2 } else { 1 }
    }

    /// `n` virtual point lights on the light (per face: `2 n` when two-sided), each a spot at
    /// the `i`-th point (i = 1..=n) of the Halton sequence in bases 2 and 3 mapped onto the
    /// outline, aimed along the emitting normal with the light's cone, and carrying the
    /// intensity `radiance * area / n`: their sum tends to the light as `n` grows, and
    /// the first `n` of `m > n` points are the same `n` points.
    pub fn vpls(&self, n: usize) -> Vec<Light> {
        self.desc()
            .vpl_lights(n)
            .iter()
            .map(Light::from_spot_desc)
            .collect()
    }

    /// The `exact` truth's `m` points of the light as spots (`2 m` when two-sided), each
    /// with intensity `radiance * area / m`: the midpoint rule on an `a x b` grid of equal-area
    /// cells (`a b = m`, `a` the power of two nearest `sqrt(m)` that divides `m`) of the unit
    /// square, mapped onto the outline (a rectangle linearly; a disk in polar coordinates,
    /// `r = radius sqrt(u)`, `phi = 2 pi v`, which keeps the cells' areas equal and the map
    /// smooth, where the concentric map of [`AreaShape::point`] has kinks). For a smooth
    /// integrand the midpoint rule converges as `1 / m` with first-order terms cancelled per
    /// cell; the Halton set of [`Self::vpls`] converges more slowly.
    pub fn quadrature(&self, m: usize) -> Vec<Light> {
        let m = m.max(1);
        let mut a = 1usize;
        while a * a * 2 <= m && m.is_multiple_of(a * 2) {
            a *= 2;
        }
        let b = m / a;
        let (right, up, _) = self.frame();
        let scale = self.shape.area() / (a * b) as f64;
        let intensity = self.radiance.map(|c| c * scale);
        let mut out = Vec::with_capacity(a * b * self.faces());
        for j in 0..b {
            for i in 0..a {
                let (u, v) = ((i as f64 + 0.5) / a as f64, (j as f64 + 0.5) / b as f64);
                let (x, y) = match self.shape {
                    AreaShape::Rect { .. } => self.shape.point(u, v),
                    AreaShape::Disk { radius } => {
                        let (s, c) = (std::f64::consts::TAU * v).sin_cos();
                        let r = radius * u.sqrt();
                        (r * c, r * s)
                    }
                };
                out.extend(self.spots_at(self.position + right * x + up * y, intensity));
            }
        }
        out
    }

    /// The emitter's housing: its outline as a triangle mesh (a disk as a 48-sided polygon
    /// around it) `behind` metres behind the emitting face, so that view rays that reach the
    /// light end at it, as at any lamp, instead of crossing the emitting surface. It casts no
    /// shadow on its own light (every lit point is in front of the face, and a shadow ray
    /// stops at the emitting point). Two-sided lights have none (both faces emit).
    pub fn housing(&self, behind: f64, albedo: [f64; 3]) -> Option<Shape> {
        if self.two_sided {
            return None;
        }
        let (right, up, normal) = self.frame();
        let centre = self.position - normal * behind;
        let at = |(x, y): (f64, f64)| centre + right * x + up * y;
        let outline: Vec<DVec3> = match self.shape {
            AreaShape::Rect { width, height } => {
                let (w, h) = (0.5 * width, 0.5 * height);
                [(-w, -h), (w, -h), (w, h), (-w, h)].map(at).to_vec()
            }
            AreaShape::Disk { radius } => (0..48)
                .map(|i| {
                    let (s, c) = (std::f64::consts::TAU * f64::from(i) / 48.0).sin_cos();
                    // The polygon circumscribes the disk: it covers every emitting point.
                    let r = radius / (std::f64::consts::PI / 48.0).cos();
                    at((r * c, r * s))
                })
                .collect(),
        };
        let n = outline.len() as u32;
        let mut vertices = vec![centre];
        vertices.extend(outline);
        let triangles = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
        Some(Shape::Mesh {
            vertices,
            triangles,
            albedo,
        })
    }

    /// The spot light the area light tends to as it shrinks: at its centre, intensity
    /// `radiance * area` (front face only: the back face's spot is the same with the
    /// reversed axis).
    pub fn point_limit(&self) -> Light {
        Light::Spot {
            position: self.position,
            direction: self.frame().2,
            inner_angle_deg: self.inner_angle_deg,
            outer_angle_deg: self.outer_angle_deg,
            intensity: self.radiance.map(|c| c * self.shape.area()),
            cookie: None,
        }
    }
}

pub use scatter_shaderlib::area_ivsv::halton;

impl Light {
    /// The light type, as variants are compiled for it (an area light's is `area`: the
    /// `area_ivsv` family's; the single-light families render its point limit's scene).
    pub fn kind(&self) -> scatter_shaderlib::prefiltered::LightKind {
        use scatter_shaderlib::prefiltered::LightKind;
        match self {
            Light::Directional { .. } => LightKind::Directional,
            Light::Spot { .. } => LightKind::Spot,
            Light::Area(_) => LightKind::Area,
        }
    }

    /// The light of the kernels' description: a VPL's spot as a spot, a sun as a sun, an
    /// area light as its point limit.
    pub(crate) fn from_spot_desc(desc: &scatter_shaderlib::prefiltered::LightDesc) -> Light {
        use scatter_shaderlib::prefiltered::LightDesc;
        match *desc {
            LightDesc::Spot {
                position,
                direction,
                inner_deg,
                outer_deg,
                color,
            } => Light::Spot {
                position,
                direction,
                inner_angle_deg: inner_deg,
                outer_angle_deg: outer_deg,
                intensity: color,
                cookie: None,
            },
            LightDesc::Directional { direction, color } => Light::Directional {
                direction,
                irradiance: color,
            },
            LightDesc::Area(a) => Light::Spot {
                position: a.position,
                direction: a.direction,
                inner_angle_deg: a.inner_deg,
                outer_angle_deg: a.outer_deg,
                intensity: a.radiance.map(|c| c * a.shape.area()),
                cookie: None,
            },
        }
    }

    /// A spot's cookie (`None` for the sun, an area light and a spot without one).
    pub fn cookie(&self) -> Option<&crate::cookie::Cookie> {
        match self {
            Light::Spot { cookie, .. } => cookie.as_ref(),
            Light::Directional { .. } | Light::Area(_) => None,
        }
    }

    /// RGB scale of the light (irradiance, intensity, or an area light's radiance).
    pub fn color(&self) -> [f64; 3] {
        match self {
            Light::Directional { irradiance, .. } => *irradiance,
            Light::Spot { intensity, .. } => *intensity,
            Light::Area(a) => a.radiance,
        }
    }

    /// The area light, if this is one.
    pub fn area(&self) -> Option<&AreaLight> {
        match self {
            Light::Area(a) => Some(a),
            _ => None,
        }
    }
}

/// A homogeneous participating medium.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Medium {
    /// Extinction coefficient sigma_t (1/m), >= 0.
    pub sigma_t: f64,
    /// Single-scattering albedo in [0, 1]: sigma_s = albedo * sigma_t.
    pub albedo: f64,
    /// Henyey-Greenstein asymmetry g in (-1, 1); 0 is isotropic.
    pub g: f64,
}

impl Medium {
    /// Scattering coefficient sigma_s = albedo * sigma_t.
    pub fn sigma_s(&self) -> f64 {
        self.albedo * self.sigma_t
    }
}

/// A piece of geometry. Every shape both receives light and casts shadows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Shape {
    /// An infinite plane.
    Plane {
        /// A point on the plane.
        point: DVec3,
        /// Normal (need not be normalised).
        normal: DVec3,
        /// Diffuse albedo (RGB) for composites.
        #[serde(default = "default_albedo")]
        albedo: [f64; 3],
    },
    /// An axis-aligned box.
    Box {
        /// Minimum corner.
        min: DVec3,
        /// Maximum corner (every component > `min`).
        max: DVec3,
        /// Diffuse albedo (RGB) for composites.
        #[serde(default = "default_albedo")]
        albedo: [f64; 3],
    },
    /// A sphere.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius (> 0).
        radius: f64,
        /// Diffuse albedo (RGB) for composites.
        #[serde(default = "default_albedo")]
        albedo: [f64; 3],
    },
    /// A capped cylinder between two points.
    Cylinder {
        /// Centre of one cap.
        a: DVec3,
        /// Centre of the other cap (distinct from `a`).
        b: DVec3,
        /// Radius (> 0).
        radius: f64,
        /// Diffuse albedo (RGB) for composites.
        #[serde(default = "default_albedo")]
        albedo: [f64; 3],
    },
    /// A regular-grid heightfield over the xz plane, triangulated.
    Heightfield {
        /// World position of grid sample (0, 0) at height 0.
        origin: DVec3,
        /// Extent in x and z (> 0).
        size: [f64; 2],
        /// Samples in x and z (>= 2 each).
        samples: [u32; 2],
        /// Heights, row-major (`samples[0]` per row, `samples[1]` rows).
        heights: Vec<f64>,
        /// Diffuse albedo (RGB) for composites.
        #[serde(default = "default_albedo")]
        albedo: [f64; 3],
    },
    /// A triangle mesh.
    Mesh {
        /// Vertex positions.
        vertices: Vec<DVec3>,
        /// Triangles as vertex index triples.
        triangles: Vec<[u32; 3]>,
        /// Diffuse albedo (RGB) for composites.
        #[serde(default = "default_albedo")]
        albedo: [f64; 3],
    },
}

fn default_albedo() -> [f64; 3] {
    [0.6, 0.6, 0.6]
}

impl Shape {
    /// Diffuse albedo of the shape.
    pub fn albedo(&self) -> [f64; 3] {
        match self {
            Shape::Plane { albedo, .. }
            | Shape::Box { albedo, .. }
            | Shape::Sphere { albedo, .. }
            | Shape::Cylinder { albedo, .. }
            | Shape::Heightfield { albedo, .. }
            | Shape::Mesh { albedo, .. } => *albedo,
        }
    }

    /// How many occluders this shape counts as: one per analytic shape, one per triangle of
    /// a mesh or heightfield.
    pub fn occluder_count(&self) -> usize {
        match self {
            Shape::Mesh { triangles, .. } => triangles.len(),
            Shape::Heightfield { samples, .. } => {
                2 * (samples[0] as usize - 1) * (samples[1] as usize - 1)
            }
            _ => 1,
        }
    }
}

fn check_finite(field: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(field, format!("must be finite, got {v}")))
    }
}

fn check_vec(field: &str, v: DVec3) -> Result<(), SceneError> {
    for (c, x) in ["x", "y", "z"].iter().zip(v.to_array()) {
        check_finite(&format!("{field}.{c}"), x)?;
    }
    Ok(())
}

fn check_dir(field: &str, v: DVec3) -> Result<(), SceneError> {
    check_vec(field, v)?;
    if v.length() < 1e-9 {
        return Err(invalid(field, format!("must not be zero-length, got {v}")));
    }
    Ok(())
}

fn check_rgb(field: &str, v: [f64; 3]) -> Result<(), SceneError> {
    for (c, x) in ["r", "g", "b"].iter().zip(v) {
        let f = format!("{field}.{c}");
        check_finite(&f, x)?;
        if x < 0.0 {
            return Err(invalid(f, format!("must be >= 0, got {x}")));
        }
    }
    Ok(())
}

fn check_positive(field: &str, v: f64) -> Result<(), SceneError> {
    check_finite(field, v)?;
    if v <= 0.0 {
        return Err(invalid(field, format!("must be > 0, got {v}")));
    }
    Ok(())
}

/// A `geometry` entry of type `mesh_file` in a scene file: a Wavefront OBJ file loaded as a
/// [`Shape::Mesh`] (every object and group of the file, faces triangulated as fans;
/// materials, normals and texture coordinates ignored), scaled then translated.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshFile {
    /// Always `mesh_file` (the tag).
    #[serde(rename = "type")]
    _type: String,
    /// The OBJ file; relative paths are relative to the scene file's directory
    /// ([`Scene::load`]) or to the working directory ([`Scene::from_json`]).
    path: String,
    /// Uniform scale applied first (> 0).
    #[serde(default = "unit_scale")]
    scale: f64,
    /// Translation applied after the scale.
    #[serde(default)]
    translate: DVec3,
    /// Diffuse albedo (RGB) for composites.
    #[serde(default = "default_albedo")]
    albedo: [f64; 3],
}

fn unit_scale() -> f64 {
    1.0
}

/// Loads the OBJ file of `geometry[index]`.
fn load_mesh_file(index: usize, file: &MeshFile, base: Option<&Path>) -> Result<Shape, SceneError> {
    let field = |f: &str| format!("geometry[{index}].{f}");
    check_positive(&field("scale"), file.scale)?;
    check_vec(&field("translate"), file.translate)?;
    let path = match base {
        Some(dir) if Path::new(&file.path).is_relative() => dir.join(&file.path),
        _ => Path::new(&file.path).to_path_buf(),
    };
    let is_obj = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if !is_obj {
        return Err(invalid(
            field("path"),
            format!(
                "must name a Wavefront OBJ file (.obj; glTF is not supported), got {}",
                file.path
            ),
        ));
    }
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj(&path, &options).map_err(|e| {
        invalid(
            field("path"),
            format!("cannot load OBJ file {}: {e}", path.display()),
        )
    })?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for model in &models {
        let base = u32::try_from(vertices.len()).map_err(|_| {
            invalid(
                field("path"),
                format!("{}: too many vertices", path.display()),
            )
        })?;
        vertices.extend(model.mesh.positions.chunks_exact(3).map(|p| {
            DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])) * file.scale
                + file.translate
        }));
        triangles.extend(
            model
                .mesh
                .indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if triangles.is_empty() {
        return Err(invalid(
            field("path"),
            format!("{}: the OBJ file has no faces", path.display()),
        ));
    }
    Ok(Shape::Mesh {
        vertices,
        triangles,
        albedo: file.albedo,
    })
}

impl Scene {
    /// Parses and validates a scene from JSON text; `mesh_file` entries load their OBJ files
    /// relative to the working directory.
    pub fn from_json(text: &str) -> Result<Scene, SceneError> {
        Scene::from_json_in(text, None)
    }

    /// Parses and validates a scene from JSON text; `mesh_file` entries load their OBJ files,
    /// relative paths from `base` (the working directory when `None`).
    pub fn from_json_in(text: &str, base: Option<&Path>) -> Result<Scene, SceneError> {
        let mut value: serde_json::Value = serde_json::from_str(text)?;
        // `mesh_file` entries are read here and stand as empty meshes until the scene is
        // parsed: a parsed `Scene` only holds shapes every stage can render.
        let mut meshes = Vec::new();
        if let Some(geometry) = value
            .get_mut("geometry")
            .and_then(serde_json::Value::as_array_mut)
        {
            for (index, entry) in geometry.iter_mut().enumerate() {
                if entry.get("type").and_then(serde_json::Value::as_str) != Some("mesh_file") {
                    continue;
                }
                let file: MeshFile = serde_json::from_value(entry.take())
                    .map_err(|e| invalid(format!("geometry[{index}]"), e.to_string()))?;
                meshes.push((index, load_mesh_file(index, &file, base)?));
                *entry = serde_json::json!({"type": "mesh", "vertices": [], "triangles": []});
            }
        }
        // A spot's cookie file is relative to the scene file's directory.
        if let (Some(dir), Some(file)) = (
            base,
            value
                .pointer_mut("/light/cookie/file")
                .filter(|f| f.as_str().is_some_and(|f| Path::new(f).is_relative())),
        ) {
            let joined = dir.join(file.as_str().unwrap_or_default());
            *file = serde_json::Value::String(joined.display().to_string());
        }
        let mut scene: Scene = serde_json::from_value(value)?;
        for (index, mesh) in meshes {
            scene.geometry[index] = mesh;
        }
        scene.validate()?;
        Ok(scene)
    }

    /// Reads, parses and validates a scene file; `mesh_file` paths are relative to its
    /// directory.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Scene::from_json_in(&text, path.parent())
    }

    /// Serialises the scene as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a validated scene always serialises")
    }

    /// The scene once per point light: for an area light one scene per virtual point light
    /// ([`AreaLight::vpls`] with `n` points, `2 n` scenes when two-sided), named
    /// `{name}/vpl{i}`, whose results add up to the area light's; any other light is one
    /// point light already (the scene itself).
    pub fn point_light_scenes(&self, n: usize) -> Vec<Scene> {
        match &self.light {
            Light::Area(a) => a
                .vpls(n)
                .into_iter()
                .enumerate()
                .map(|(i, light)| Scene {
                    name: format!("{}/vpl{i}", self.name),
                    light,
                    ..self.clone()
                })
                .collect(),
            _ => vec![self.clone()],
        }
    }

    /// Number of occluders (analytic shapes, plus every mesh and heightfield triangle).
    pub fn occluder_count(&self) -> usize {
        self.geometry.iter().map(Shape::occluder_count).sum()
    }

    /// Checks every field; the error names the first offending one.
    pub fn validate(&self) -> Result<(), SceneError> {
        let c = &self.camera;
        check_vec("camera.position", c.position)?;
        match &c.orientation {
            Orientation::LookAt { target, up } => {
                check_vec("camera.orientation.target", *target)?;
                check_dir("camera.orientation.up", *up)?;
                check_dir(
                    "camera.orientation.(target - position)",
                    *target - c.position,
                )?;
                if (*target - c.position)
                    .normalize()
                    .cross(up.normalize())
                    .length()
                    < 1e-6
                {
                    return Err(invalid(
                        "camera.orientation.up",
                        "must not be parallel to the view direction",
                    ));
                }
            }
            Orientation::Forward { forward, up } => {
                check_dir("camera.orientation.forward", *forward)?;
                check_dir("camera.orientation.up", *up)?;
                if forward.normalize().cross(up.normalize()).length() < 1e-6 {
                    return Err(invalid(
                        "camera.orientation.up",
                        "must not be parallel to camera.orientation.forward",
                    ));
                }
            }
        }
        check_finite("camera.fov_y_deg", c.fov_y_deg)?;
        if !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
            return Err(invalid(
                "camera.fov_y_deg",
                format!("must be in (0, 180) degrees, got {}", c.fov_y_deg),
            ));
        }
        check_positive("camera.near", c.near)?;
        check_finite("camera.far", c.far)?;
        if c.near >= c.far {
            return Err(invalid(
                "camera.far",
                format!(
                    "must be greater than camera.near ({}), got {}",
                    c.near, c.far
                ),
            ));
        }
        if c.width == 0 || c.height == 0 {
            return Err(invalid(
                "camera.width/height",
                format!("must be at least 1x1, got {}x{}", c.width, c.height),
            ));
        }
        match &self.light {
            Light::Directional {
                direction,
                irradiance,
            } => {
                check_dir("light.direction", *direction)?;
                check_rgb("light.irradiance", *irradiance)?;
            }
            Light::Spot {
                position,
                direction,
                inner_angle_deg,
                outer_angle_deg,
                intensity,
                cookie,
            } => {
                check_vec("light.position", *position)?;
                check_dir("light.direction", *direction)?;
                check_finite("light.inner_angle_deg", *inner_angle_deg)?;
                check_finite("light.outer_angle_deg", *outer_angle_deg)?;
                if !(*outer_angle_deg > 0.0 && *outer_angle_deg <= 180.0) {
                    return Err(invalid(
                        "light.outer_angle_deg",
                        format!("must be in (0, 180] degrees, got {outer_angle_deg}"),
                    ));
                }
                if !(*inner_angle_deg >= 0.0 && inner_angle_deg <= outer_angle_deg) {
                    return Err(invalid(
                        "light.inner_angle_deg",
                        format!(
                            "must be in [0, light.outer_angle_deg = {outer_angle_deg}], got {inner_angle_deg}"
                        ),
                    ));
                }
                check_rgb("light.intensity", *intensity)?;
                if cookie.is_some() && *outer_angle_deg >= 90.0 {
                    return Err(invalid(
                        "light.cookie",
                        format!(
                            "needs light.outer_angle_deg < 90 (the cookie is projected onto a \
                             plane across the cone), got {outer_angle_deg}"
                        ),
                    ));
                }
            }
            Light::Area(a) => validate_area(a)?,
        }
        let m = &self.medium;
        check_finite("medium.sigma_t", m.sigma_t)?;
        if m.sigma_t < 0.0 {
            return Err(invalid(
                "medium.sigma_t",
                format!("must be >= 0, got {}", m.sigma_t),
            ));
        }
        check_finite("medium.albedo", m.albedo)?;
        if !(0.0..=1.0).contains(&m.albedo) {
            return Err(invalid(
                "medium.albedo",
                format!("must be in [0, 1], got {}", m.albedo),
            ));
        }
        check_finite("medium.g", m.g)?;
        if m.g.abs() >= 1.0 {
            return Err(invalid(
                "medium.g",
                format!("must satisfy |g| < 1, got {}", m.g),
            ));
        }
        check_rgb("sky", self.sky)?;
        for (i, s) in self.geometry.iter().enumerate() {
            validate_shape(&format!("geometry[{i}]"), s)?;
        }
        Ok(())
    }
}

fn validate_area(a: &AreaLight) -> Result<(), SceneError> {
    check_vec("light.position", a.position)?;
    check_dir("light.direction", a.direction)?;
    if let Some(up) = a.up {
        check_dir("light.up", up)?;
        if a.direction.normalize().cross(up.normalize()).length() < 1e-6 {
            return Err(invalid(
                "light.up",
                "must not be parallel to light.direction",
            ));
        }
    }
    match a.shape {
        AreaShape::Rect { width, height } => {
            check_positive("light.shape.width", width)?;
            check_positive("light.shape.height", height)?;
        }
        AreaShape::Disk { radius } => check_positive("light.shape.radius", radius)?,
    }
    check_finite("light.inner_angle_deg", a.inner_angle_deg)?;
    check_finite("light.outer_angle_deg", a.outer_angle_deg)?;
    if !(a.outer_angle_deg > 0.0 && a.outer_angle_deg <= 90.0) {
        return Err(invalid(
            "light.outer_angle_deg",
            format!(
                "must be in (0, 90] degrees (a face emits into its own half-space), got {}",
                a.outer_angle_deg
            ),
        ));
    }
    if !(a.inner_angle_deg >= 0.0 && a.inner_angle_deg <= a.outer_angle_deg) {
        return Err(invalid(
            "light.inner_angle_deg",
            format!(
                "must be in [0, light.outer_angle_deg = {}], got {}",
                a.outer_angle_deg, a.inner_angle_deg
            ),
        ));
    }
    check_rgb("light.radiance", a.radiance)
}

fn validate_shape(p: &str, s: &Shape) -> Result<(), SceneError> {
    check_rgb(&format!("{p}.albedo"), s.albedo())?;
    match s {
        Shape::Plane { point, normal, .. } => {
            check_vec(&format!("{p}.point"), *point)?;
            check_dir(&format!("{p}.normal"), *normal)?;
        }
        Shape::Box { min, max, .. } => {
            check_vec(&format!("{p}.min"), *min)?;
            check_vec(&format!("{p}.max"), *max)?;
            if !(max.cmpgt(*min).all()) {
                return Err(invalid(
                    format!("{p}.max"),
                    format!("must exceed {p}.min = {min} in every component, got {max}"),
                ));
            }
        }
        Shape::Sphere { center, radius, .. } => {
            check_vec(&format!("{p}.center"), *center)?;
            check_positive(&format!("{p}.radius"), *radius)?;
        }
        Shape::Cylinder { a, b, radius, .. } => {
            check_vec(&format!("{p}.a"), *a)?;
            check_vec(&format!("{p}.b"), *b)?;
            check_dir(&format!("{p}.(b - a)"), *b - *a)?;
            check_positive(&format!("{p}.radius"), *radius)?;
        }
        Shape::Heightfield {
            origin,
            size,
            samples,
            heights,
            ..
        } => {
            check_vec(&format!("{p}.origin"), *origin)?;
            check_positive(&format!("{p}.size[0]"), size[0])?;
            check_positive(&format!("{p}.size[1]"), size[1])?;
            if samples[0] < 2 || samples[1] < 2 {
                return Err(invalid(
                    format!("{p}.samples"),
                    format!("must be at least 2x2, got {}x{}", samples[0], samples[1]),
                ));
            }
            let n = samples[0] as usize * samples[1] as usize;
            if heights.len() != n {
                return Err(invalid(
                    format!("{p}.heights"),
                    format!(
                        "must hold samples[0] * samples[1] = {n} values, got {}",
                        heights.len()
                    ),
                ));
            }
            for (i, h) in heights.iter().enumerate() {
                check_finite(&format!("{p}.heights[{i}]"), *h)?;
            }
        }
        Shape::Mesh {
            vertices,
            triangles,
            ..
        } => {
            for (i, v) in vertices.iter().enumerate() {
                check_vec(&format!("{p}.vertices[{i}]"), *v)?;
            }
            for (i, t) in triangles.iter().enumerate() {
                for k in t {
                    if *k as usize >= vertices.len() {
                        return Err(invalid(
                            format!("{p}.triangles[{i}]"),
                            format!("index {k} out of range for {} vertices", vertices.len()),
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}
