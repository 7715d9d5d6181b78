//! Conversions from the reference's scene types to the engine-facing descriptions of
//! `scatter-shaderlib` (what an engine would hand the runtime every frame).

use crate::buffers::{ShadowMap, ShadowProjection};
use crate::scene::{Light, Scene};
use scatter_shaderlib::prefiltered::{
    CameraDesc, LightDesc, MediumDesc, ShadowMapDesc, ShadowProjectionDesc,
};

/// Bias of the reference shadow-map lookups, in texel footprints.
pub const SHADOW_BIAS_TEXELS: f64 = 1.5;

impl Scene {
    /// The camera as the kernels see it.
    pub fn camera_desc(&self) -> CameraDesc {
        let f = self.camera.frame();
        CameraDesc {
            position: self.camera.position,
            forward: f.forward,
            right: f.right,
            up: f.up,
            tan_half_fov_y: self.camera.tan_half_fov(),
            near: self.camera.near,
            far: self.camera.far,
        }
    }

    /// The light as the kernels see it (an area light as `LightDesc::Area`: the
    /// `area_ivsv` family's; the single-light families refuse it and render its point
    /// limit's scene or its VPL scenes, [`Scene::point_light_scenes`]).
    pub fn light_desc(&self) -> LightDesc {
        light_desc(&self.light)
    }

    /// The medium as the kernels see it.
    pub fn medium_desc(&self) -> MediumDesc {
        MediumDesc {
            sigma_t: self.medium.sigma_t,
            albedo: self.medium.albedo,
            g: self.medium.g,
        }
    }
}

/// [`Scene::light_desc`] of one light.
fn light_desc(light: &Light) -> LightDesc {
    match light {
        Light::Directional {
            direction,
            irradiance,
        } => LightDesc::Directional {
            direction: *direction,
            color: *irradiance,
        },
        Light::Spot {
            position,
            direction,
            inner_angle_deg,
            outer_angle_deg,
            intensity,
            ..
        } => LightDesc::Spot {
            position: *position,
            direction: *direction,
            inner_deg: *inner_angle_deg,
            outer_deg: *outer_angle_deg,
            color: *intensity,
        },
        Light::Area(a) => LightDesc::Area(a.desc()),
    }
}

impl ShadowMap {
    /// The shadow map as the kernels see it.
    pub fn desc(&self) -> ShadowMapDesc {
        ShadowMapDesc {
            origin: self.origin,
            basis: self.basis,
            projection: match self.projection {
                ShadowProjection::Orthographic { x0, x1, y0, y1 } => {
                    ShadowProjectionDesc::Orthographic { x0, x1, y0, y1 }
                }
                ShadowProjection::Perspective { tan_half } => {
                    ShadowProjectionDesc::Perspective { tan_half }
                }
            },
            near: self.near,
            far: self.far,
            size: self.size,
            bias_texels: SHADOW_BIAS_TEXELS,
        }
    }
}
