//! The inputs every method gets, produced by ray casting (standing in for an engine's
//! rasteriser): the camera depth buffer and a standard light shadow map.
//!
//! **Depth buffer.** [`GBuffer::view_depth`] holds *linear view depth*: the distance of the
//! first visible surface along the camera's view axis (not along the ray), in metres, as f32.
//! Geometry nearer than `camera.near` is clipped as a rasteriser would; pixels that see no
//! surface before the far plane ("sky") hold exactly `camera.far`, and the scattering
//! integral of such a pixel runs to the far plane. [`ndc_depth`] converts to the standard
//! (non-reversed) wgpu depth `z_ndc = far (z - near) / (z (far - near))` in [0, 1]. The ray
//! length is `s = view_depth / dot(ray_dir, forward)`.
//!
//! **Shadow map.** A square map of *normalised linear light depth* in [0, 1] (f32): for a
//! directional light an orthographic projection along the light, fitted in x/y to the camera
//! frustum including the eye (view rays integrate from the eye) and in depth from the nearest scene occluder towards the light (so occluders
//! between the light and the frustum cast shadows) to the farthest frustum corner; for a spot
//! light a perspective projection from the light along its axis with a field of view of twice
//! the outer cone angle. A texel stores the depth of the first surface along its texel-centre
//! ray, 1.0 where there is none. Lookups are nearest-texel; a point is lit iff its depth is
//! <= the stored depth + [`ShadowMap::bias_world`] (1.5 texel footprints in world units,
//! converted to normalised depth): the "documented bias" of the `shadow_map` truth.
//! Points outside the map's footprint are lit. An infinite plane lit from behind (the ground
//! with the sun below the horizon) stores depth 0 wherever it lies between the sun and the
//! map's near plane, as a depth-clamped caster would: everything in front of it is shadowed.

use crate::bvh::Bvh;
use crate::geometry::{Aabb, Ray};
use crate::scene::{Frame, Light, Scene, Shape};
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;

/// Sentinel shape index of sky pixels.
pub const SKY: u32 = u32::MAX;

/// Per-pixel first-hit information of the camera rays.
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear view depth (see module docs), row-major from the top-left pixel.
    pub view_depth: Vec<f32>,
    /// Ray length `s` to the surface (or to the far plane for sky pixels), f64.
    pub ray_length: Vec<f64>,
    /// Index of the hit shape in `Scene::geometry`, or [`SKY`].
    pub shape: Vec<u32>,
    /// Unit surface normal facing the camera (zero for sky pixels).
    pub normal: Vec<DVec3>,
}

/// Converts a linear view depth to standard wgpu NDC depth in [0, 1].
pub fn ndc_depth(view_depth: f64, near: f64, far: f64) -> f64 {
    far * (view_depth - near) / (view_depth * (far - near))
}

/// Inverse of [`ndc_depth`].
pub fn view_depth_from_ndc(ndc: f64, near: f64, far: f64) -> f64 {
    near * far / (far - ndc * (far - near))
}

/// Camera rays for every pixel: the pixel-centre ray direction.
pub fn camera_ray(scene: &Scene, frame: &Frame, x: u32, y: u32) -> DVec3 {
    scene
        .camera
        .ray_dir(frame, f64::from(x) + 0.5, f64::from(y) + 0.5)
}

impl GBuffer {
    /// Casts one ray per pixel centre (rayon-parallel over rows).
    pub fn cast(scene: &Scene, bvh: &Bvh) -> GBuffer {
        let cam = &scene.camera;
        let frame = cam.frame();
        let (w, h) = (cam.width, cam.height);
        let rows: Vec<Vec<(f32, f64, u32, DVec3)>> = (0..h)
            .into_par_iter()
            .map(|y| {
                (0..w)
                    .map(|x| {
                        let dir = camera_ray(scene, &frame, x, y);
                        let cos = dir.dot(frame.forward);
                        let (tmin, tmax) = (cam.near / cos, cam.far / cos);
                        match bvh.closest(&Ray::new(cam.position, dir), tmin, tmax) {
                            Some(hit) => {
                                let n = if hit.normal.dot(dir) > 0.0 {
                                    -hit.normal
                                } else {
                                    hit.normal
                                };
                                ((hit.t * cos) as f32, hit.t, hit.shape, n)
                            }
                            None => (cam.far as f32, tmax, SKY, DVec3::ZERO),
                        }
                    })
                    .collect()
            })
            .collect();
        let n = (w * h) as usize;
        let mut g = GBuffer {
            width: w,
            height: h,
            view_depth: Vec::with_capacity(n),
            ray_length: Vec::with_capacity(n),
            shape: Vec::with_capacity(n),
            normal: Vec::with_capacity(n),
        };
        for (d, s, sh, nr) in rows.into_iter().flatten() {
            g.view_depth.push(d);
            g.ray_length.push(s);
            g.shape.push(sh);
            g.normal.push(nr);
        }
        g
    }

    /// The depth buffer as standard NDC depth (see [`ndc_depth`]).
    pub fn ndc_depth(&self, near: f64, far: f64) -> Vec<f32> {
        self.view_depth
            .iter()
            .map(|&z| ndc_depth(f64::from(z), near, far) as f32)
            .collect()
    }
}

/// Projection of a shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadowProjection {
    /// Orthographic along a directional light; light-space x/y window.
    Orthographic {
        /// Left edge (light-space x).
        x0: f64,
        /// Right edge.
        x1: f64,
        /// Bottom edge (light-space y).
        y0: f64,
        /// Top edge.
        y1: f64,
    },
    /// Perspective from a spot light.
    Perspective {
        /// tan of half the field of view (square map).
        tan_half: f64,
    },
}

/// Why a shadow map cannot be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ShadowMapError {
    /// Zero resolution.
    #[error("shadow map size must be at least 1, got {0}")]
    ZeroSize(u32),
    /// Over the texture limit we support.
    #[error("shadow map size must be at most 16384 (the 2D texture limit), got {0}")]
    TooLarge(u32),
    /// A spot cone too wide for one perspective map.
    #[error(
        "light.outer_angle_deg must be below 80 degrees for a single perspective shadow map, got {0}"
    )]
    ConeTooWide(f64),
    /// The VPLs of an area light cannot be placed (`AreaLightDesc::vpl_inputs`).
    #[error("area light VPLs: {0}")]
    Vpl(#[from] scatter_shaderlib::prefiltered::FrameError),
}

/// A standard light shadow map (see the module docs for the exact conventions).
#[derive(Clone, Debug)]
pub struct ShadowMap {
    /// Width and height in texels.
    pub size: u32,
    /// Normalised linear light depth per texel, row-major from the top-left texel.
    pub depth: Vec<f32>,
    /// Light-space origin (world): the spot position, or the world origin for directional.
    pub origin: DVec3,
    /// Light-space basis: right, up, forward (forward = the direction light travels).
    pub basis: [DVec3; 3],
    /// Projection.
    pub projection: ShadowProjection,
    /// Light-space depth of normalised depth 0.
    pub near: f64,
    /// Light-space depth of normalised depth 1.
    pub far: f64,
}

/// Where a world point falls in a shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowCoord {
    /// Horizontal texture coordinate in [0, 1] inside the map (0 = left edge).
    pub u: f64,
    /// Vertical texture coordinate in [0, 1] inside the map (0 = top edge).
    pub v: f64,
    /// Normalised linear depth (0 at `near`, 1 at `far`).
    pub depth: f64,
    /// Light-space depth in world units.
    pub z: f64,
}

/// The light frame (right, up, forward) of a spot or directional light travelling along
/// `forward`: the shadow map's basis, and the frame a spot's cookie is projected in.
pub use scatter_shaderlib::area_ivsv::light_basis;

impl ShadowMap {
    /// A map with `desc`'s frame and no depth yet ([`ShadowMap::cast`] fills it).
    pub fn from_desc(desc: &scatter_shaderlib::prefiltered::ShadowMapDesc) -> ShadowMap {
        use scatter_shaderlib::prefiltered::ShadowProjectionDesc;
        ShadowMap {
            size: desc.size,
            depth: Vec::new(),
            origin: desc.origin,
            basis: desc.basis,
            projection: match desc.projection {
                ShadowProjectionDesc::Orthographic { x0, x1, y0, y1 } => {
                    ShadowProjection::Orthographic { x0, x1, y0, y1 }
                }
                ShadowProjectionDesc::Perspective { tan_half } => {
                    ShadowProjection::Perspective { tan_half }
                }
            },
            near: desc.near,
            far: desc.far,
        }
    }

    /// Ray casts the depth of a map whose frame is set (a spot's or a VPL's: no backlit
    /// planes to account for).
    pub fn cast(mut self, bvh: &Bvh) -> ShadowMap {
        let n = self.size as usize;
        self.depth = (0..n * n)
            .into_par_iter()
            .map(|i| {
                let (ix, iy) = (i % n, i / n);
                let u = (ix as f64 + 0.5) / n as f64;
                let v = (iy as f64 + 0.5) / n as f64;
                let (ray, z_of_t) = self.texel_ray(u, v);
                match bvh.closest(&ray, 0.0, f64::INFINITY) {
                    Some(hit) => self.normalise(z_of_t(hit.t)).clamp(0.0, 1.0) as f32,
                    None => 1.0,
                }
            })
            .collect();
        self
    }

    /// The template of an area scene's VPL maps: the standard map [`ShadowMap::fit`] fits
    /// for the light's point limit, as an engine fits it (for any other scene, its own
    /// map's frame).
    ///
    /// # Errors
    ///
    /// As [`ShadowMap::fit`].
    pub fn area_template(
        scene: &Scene,
        bvh: &Bvh,
        size: u32,
    ) -> Result<scatter_shaderlib::prefiltered::ShadowMapDesc, ShadowMapError> {
        Ok(ShadowMap::fit(scene, bvh, size)?.desc())
    }

    /// The `points` VPLs of an area scene (`points * faces`; [`crate::scene::AreaLight::vpls`])
    /// as spot scenes, each with its shadow map: the frames `scatter_frame`'s
    /// `AreaLightDesc::vpl_inputs` derives from the map the point limit's scene fits
    /// ([`ShadowMap::fit`]), which an engine renders too, ray-cast. Any other scene: itself
    /// and its standard map ([`ShadowMap::build`]).
    ///
    /// # Errors
    ///
    /// As [`ShadowMap::build`], and [`ShadowMapError::Vpl`] for VPLs that cannot be placed.
    pub fn vpl_maps(
        scene: &Scene,
        bvh: &Bvh,
        points: usize,
        size: u32,
    ) -> Result<Vec<(Scene, ShadowMap)>, ShadowMapError> {
        let Light::Area(area) = &scene.light else {
            return Ok(vec![(scene.clone(), ShadowMap::build(scene, bvh, size)?)]);
        };
        let template = ShadowMap::area_template(scene, bvh, size)?;
        let desc = area.desc();
        let count = u32::try_from(points * desc.faces()).unwrap_or(u32::MAX);
        let inputs = desc.vpl_inputs(count, &template)?;
        Ok(inputs
            .into_iter()
            .enumerate()
            .map(|(i, vpl)| {
                let light = Light::from_spot_desc(&vpl.light);
                let map = ShadowMap::from_desc(&vpl.shadow_map).cast(bvh);
                let s = Scene {
                    name: format!("{}/vpl{i}", scene.name),
                    light,
                    ..scene.clone()
                };
                (s, map)
            })
            .collect())
    }

    /// Ray casts a `size x size` shadow map for the scene's light (see module docs).
    pub fn build(scene: &Scene, bvh: &Bvh, size: u32) -> Result<ShadowMap, ShadowMapError> {
        let mut sm = ShadowMap::fit(scene, bvh, size)?;
        // Infinite planes the sun shines on from behind (a sun below the ground's horizon):
        // the near plane stops at the bounded geometry, so such a plane may cross a texel's
        // line between the sun and the map. Every point in front of it is then in its
        // shadow, as an engine's depth-clamped ("pancaked") caster would make it: depth 0.
        let backlit: Vec<(DVec3, DVec3)> = match &scene.light {
            Light::Directional { direction, .. } => scene
                .geometry
                .iter()
                .filter_map(|s| match s {
                    Shape::Plane { point, normal, .. }
                        if normal.normalize().dot(direction.normalize()) > 0.0 =>
                    {
                        Some((*point, normal.normalize()))
                    }
                    _ => None,
                })
                .collect(),
            Light::Spot { .. } | Light::Area(_) => Vec::new(),
        };
        let n = size as usize;
        sm.depth = (0..n * n)
            .into_par_iter()
            .map(|i| {
                let (ix, iy) = (i % n, i / n);
                let u = (ix as f64 + 0.5) / n as f64;
                let v = (iy as f64 + 0.5) / n as f64;
                let (ray, z_of_t) = sm.texel_ray(u, v);
                if backlit
                    .iter()
                    .any(|(p, nrm)| (ray.origin - *p).dot(*nrm) > 0.0)
                {
                    return 0.0;
                }
                match bvh.closest(&ray, 0.0, f64::INFINITY) {
                    Some(hit) => sm.normalise(z_of_t(hit.t)).clamp(0.0, 1.0) as f32,
                    None => 1.0,
                }
            })
            .collect();
        Ok(sm)
    }

    /// The map's frame for the scene's light (light-space basis, projection, depth range:
    /// see the module docs) with no depth yet: what an engine rasterising its own map
    /// renders into (`scatter_examples::raster`); [`ShadowMap::build`] ray-casts it.
    ///
    /// # Errors
    ///
    /// As [`ShadowMap::build`].
    pub fn fit(scene: &Scene, bvh: &Bvh, size: u32) -> Result<ShadowMap, ShadowMapError> {
        if size == 0 {
            return Err(ShadowMapError::ZeroSize(size));
        }
        if size > 16384 {
            return Err(ShadowMapError::TooLarge(size));
        }
        let corners = scene.camera.frustum_corners();
        let scene_bounds = bvh.bounds();
        let sm = match &scene.light {
            Light::Directional { direction, .. } => {
                let basis = light_basis(*direction);
                let lc = |p: DVec3| DVec3::new(p.dot(basis[0]), p.dot(basis[1]), p.dot(basis[2]));
                // The eye is included: view rays integrate from the eye, not from the near plane.
                let fr = corners
                    .iter()
                    .fold(Aabb::EMPTY.grow(lc(scene.camera.position)), |b, &p| {
                        b.grow(lc(p))
                    });
                let mut near = fr.min.z;
                if scene_bounds != Aabb::EMPTY {
                    for c in scene_bounds.corners() {
                        near = near.min(lc(c).z);
                    }
                }
                // A small margin so that surfaces exactly at the bounds are still caught.
                let margin = 1e-3 * (fr.max.z - near).max(1e-3);
                ShadowMap {
                    size,
                    depth: Vec::new(),
                    origin: DVec3::ZERO,
                    basis,
                    projection: ShadowProjection::Orthographic {
                        x0: fr.min.x,
                        x1: fr.max.x,
                        y0: fr.min.y,
                        y1: fr.max.y,
                    },
                    near: near - margin,
                    far: fr.max.z + margin,
                }
            }
            Light::Spot {
                position,
                direction,
                outer_angle_deg,
                ..
            } => {
                if *outer_angle_deg >= 80.0 {
                    return Err(ShadowMapError::ConeTooWide(*outer_angle_deg));
                }
                let basis = light_basis(*direction);
                let mut far: f64 = 1e-3;
                for c in corners
                    .iter()
                    .copied()
                    .chain(if scene_bounds == Aabb::EMPTY {
                        Vec::new()
                    } else {
                        scene_bounds.corners().to_vec()
                    })
                {
                    far = far.max((c - *position).length());
                }
                ShadowMap {
                    size,
                    depth: Vec::new(),
                    origin: *position,
                    basis,
                    projection: ShadowProjection::Perspective {
                        tan_half: outer_angle_deg.to_radians().tan(),
                    },
                    near: far * 1e-4,
                    far,
                }
            }
            // The standard map of an area light is its point limit's: the template of its
            // VPLs' maps (`ShadowMap::vpl_maps`).
            Light::Area(area) => {
                let limit = Scene {
                    light: area.point_limit(),
                    ..scene.clone()
                };
                return ShadowMap::fit(&limit, bvh, size);
            }
        };
        Ok(sm)
    }

    /// The ray through texture coordinate (u, v), and the map from its parameter to
    /// light-space depth.
    #[allow(clippy::type_complexity, reason = "a ray and its depth map, used once")]
    fn texel_ray(&self, u: f64, v: f64) -> (Ray, Box<dyn Fn(f64) -> f64>) {
        let [r, up, f] = self.basis;
        match self.projection {
            ShadowProjection::Orthographic { x0, x1, y0, y1 } => {
                let x = x0 + u * (x1 - x0);
                let y = y1 - v * (y1 - y0);
                let near = self.near;
                let o = self.origin + r * x + up * y + f * near;
                (
                    Ray::new(o, f),
                    Box::new(move |t: f64| near + t) as Box<dyn Fn(f64) -> f64>,
                )
            }
            ShadowProjection::Perspective { tan_half } => {
                let d = (f + r * ((2.0 * u - 1.0) * tan_half) + up * ((1.0 - 2.0 * v) * tan_half))
                    .normalize();
                let cos = d.dot(f);
                (
                    Ray::new(self.origin, d),
                    Box::new(move |t: f64| t * cos) as Box<dyn Fn(f64) -> f64>,
                )
            }
        }
    }

    fn normalise(&self, z: f64) -> f64 {
        (z - self.near) / (self.far - self.near)
    }

    /// Projects a world point; `None` if it is outside the map's footprint (or behind a
    /// spot light).
    pub fn coord(&self, p: DVec3) -> Option<ShadowCoord> {
        let q = p - self.origin;
        let [r, up, f] = self.basis;
        let (x, y, z) = (q.dot(r), q.dot(up), q.dot(f));
        let (u, v) = match self.projection {
            ShadowProjection::Orthographic { x0, x1, y0, y1 } => {
                ((x - x0) / (x1 - x0), (y1 - y) / (y1 - y0))
            }
            ShadowProjection::Perspective { tan_half } => {
                if z <= self.near {
                    return None;
                }
                (
                    0.5 + 0.5 * x / (z * tan_half),
                    0.5 - 0.5 * y / (z * tan_half),
                )
            }
        };
        ((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)).then(|| ShadowCoord {
            u,
            v,
            depth: self.normalise(z),
            z,
        })
    }

    /// Depth bias in world units at light-space depth `z`: 1.5 texel footprints.
    pub fn bias_world(&self, z: f64) -> f64 {
        let texel = match self.projection {
            ShadowProjection::Orthographic { x0, x1, y0, y1 } => (x1 - x0).max(y1 - y0),
            ShadowProjection::Perspective { tan_half } => 2.0 * z.max(0.0) * tan_half,
        } / f64::from(self.size);
        crate::desc::SHADOW_BIAS_TEXELS * texel
    }

    /// Nearest-texel stored depth at texture coordinate (u, v) in [0, 1].
    pub fn texel(&self, u: f64, v: f64) -> f32 {
        let n = self.size as usize;
        let ix = ((u * n as f64) as usize).min(n - 1);
        let iy = ((v * n as f64) as usize).min(n - 1);
        self.depth[iy * n + ix]
    }

    /// Shadow-map visibility of a world point: 1 lit, 0 shadowed (nearest texel, biased).
    pub fn visibility(&self, p: DVec3) -> f64 {
        match self.coord(p) {
            None => 1.0,
            Some(c) => {
                let bias = self.bias_world(c.z) / (self.far - self.near);
                if c.depth <= f64::from(self.texel(c.u, c.v)) + bias {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }

    /// World to light clip space as one matrix, for GPU consumers: after the perspective
    /// divide, `x, y` in [-1, 1] map to `u = (x + 1) / 2`, `v = (1 - y) / 2`. For the
    /// orthographic map `z` is the normalised depth itself; for the perspective map use the
    /// light-space depth `w` and normalise it with `near`/`far` (stored depth is linear).
    pub fn world_to_clip(&self) -> DMat4 {
        let [r, up, f] = self.basis;
        // Rows: light-space x, y, z, 1.
        let view = DMat4::from_cols(
            DVec4::new(r.x, up.x, f.x, 0.0),
            DVec4::new(r.y, up.y, f.y, 0.0),
            DVec4::new(r.z, up.z, f.z, 0.0),
            DVec4::new(
                -r.dot(self.origin),
                -up.dot(self.origin),
                -f.dot(self.origin),
                1.0,
            ),
        );
        let (n, fa) = (self.near, self.far);
        let proj = match self.projection {
            ShadowProjection::Orthographic { x0, x1, y0, y1 } => DMat4::from_cols(
                DVec4::new(2.0 / (x1 - x0), 0.0, 0.0, 0.0),
                DVec4::new(0.0, 2.0 / (y1 - y0), 0.0, 0.0),
                DVec4::new(0.0, 0.0, 1.0 / (fa - n), 0.0),
                DVec4::new(
                    -(x1 + x0) / (x1 - x0),
                    -(y1 + y0) / (y1 - y0),
                    -n / (fa - n),
                    1.0,
                ),
            ),
            ShadowProjection::Perspective { tan_half } => DMat4::from_cols(
                DVec4::new(1.0 / tan_half, 0.0, 0.0, 0.0),
                DVec4::new(0.0, 1.0 / tan_half, 0.0, 0.0),
                DVec4::new(0.0, 0.0, fa / (fa - n), 1.0),
                DVec4::new(0.0, 0.0, -n * fa / (fa - n), 0.0),
            ),
        };
        proj * view
    }
}
