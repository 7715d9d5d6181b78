//! What every family's frame set-up shares and no family owns: the engine's scene as plain
//! numbers (camera, light, medium, standard shadow map), the accepted ranges, the frame
//! error, and the validation of those descriptions (`validate_scene`,
//! `validate_shadow_map`, crate-private) that turns them into the validated scene the
//! uniform blocks store. The epipolar set-up ([`crate::frame`]) and the raymarch set-up
//! ([`crate::raymarch`]) both start here; `scatter_frame::frame` re-exports the public items
//! under their old paths.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The type of a scene's light, and the light type a variant is compiled for (every family
/// shares it; its names and parsing are in `crate::variant`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum LightKind {
    /// A distant light (parallel rays).
    #[default]
    Directional,
    /// A spot light (rays from a point, cone falloff, 1/d^2, extinction along the light path).
    Spot,
    /// An area light ([`crate::area_light::AreaLightDesc`]): soft shadows, rendered by the
    /// `area_ivsv` family as virtual point lights. The single-light families refuse it (they
    /// render its point limit, a spot, instead).
    Area,
}

impl LightKind {
    /// The lights one standard shadow map serves: what every single-light family renders.
    pub const SINGLE: &'static [LightKind] = &[LightKind::Directional, LightKind::Spot];

    /// [`Self::SINGLE`]'s names, as the single-light families' `light` knob lists them.
    pub const SINGLE_ALLOWED: &'static str = "directional | spot";
}

/// The camera of one frame (the engine's view).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// Eye position (world).
    pub position: DVec3,
    /// Unit view axis.
    pub forward: DVec3,
    /// Unit image right.
    pub right: DVec3,
    /// Unit image up.
    pub up: DVec3,
    /// tan(vertical fov / 2).
    pub tan_half_fov_y: f64,
    /// Near plane distance (> 0).
    pub near: f64,
    /// Far plane distance (> near).
    pub far: f64,
}

/// The light of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightDesc {
    /// Directional light.
    Directional {
        /// Direction the light travels.
        direction: DVec3,
        /// Irradiance E (RGB).
        color: [f64; 3],
    },
    /// Spot light.
    Spot {
        /// Position.
        position: DVec3,
        /// Cone axis (direction the light travels along the axis).
        direction: DVec3,
        /// Full-intensity half-angle (degrees).
        inner_deg: f64,
        /// Zero-intensity half-angle (degrees).
        outer_deg: f64,
        /// Intensity I (RGB).
        color: [f64; 3],
    },
    /// Area light: the `area_ivsv` family's. With it, the frame's standard shadow map is the
    /// light's point limit's ([`crate::area_light::AreaLightDesc::point_limit`]), the
    /// template of every VPL's map.
    Area(crate::area_light::AreaLightDesc),
}

impl LightDesc {
    /// The light type, as variants are compiled for it.
    pub fn kind(&self) -> LightKind {
        match self {
            LightDesc::Directional { .. } => LightKind::Directional,
            LightDesc::Spot { .. } => LightKind::Spot,
            LightDesc::Area(_) => LightKind::Area,
        }
    }
}

/// The homogeneous medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumDesc {
    /// Extinction (1/m).
    pub sigma_t: f64,
    /// Single-scattering albedo.
    pub albedo: f64,
    /// Henyey-Greenstein g.
    pub g: f64,
}

/// Projection of the engine's standard shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadowProjectionDesc {
    /// Orthographic window in light space.
    Orthographic {
        /// Left.
        x0: f64,
        /// Right.
        x1: f64,
        /// Bottom.
        y0: f64,
        /// Top.
        y1: f64,
    },
    /// Perspective with a square field of view.
    Perspective {
        /// tan(fov / 2).
        tan_half: f64,
    },
}

/// The engine's standard shadow map: a square map of normalised *linear* light depth
/// (`(z - near) / (far - near)`, 1 where nothing was hit), texel (0, 0) top-left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowMapDesc {
    /// Light-space origin.
    pub origin: DVec3,
    /// Light-space right, up, forward (forward = direction light travels).
    pub basis: [DVec3; 3],
    /// Projection.
    pub projection: ShadowProjectionDesc,
    /// Light-space depth of stored 0.
    pub near: f64,
    /// Light-space depth of stored 1.
    pub far: f64,
    /// Texels per side.
    pub size: u32,
    /// Depth bias in texel footprints (the reference uses 1.5).
    pub bias_texels: f64,
}

/// Why a frame cannot be set up.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// The light type differs from the variant's.
    #[error("the variant is compiled for light = {expected} but the frame has light = {got}")]
    LightMismatch {
        /// The variant's light.
        expected: LightKind,
        /// The frame's light.
        got: LightKind,
    },
    /// A size is zero or too large.
    #[error("{what} must be in 1..={max}, got {value}")]
    Size {
        /// Which size.
        what: &'static str,
        /// Its value.
        value: u32,
        /// The largest allowed.
        max: u32,
    },
    /// Too few rectified columns for the variant's regions.
    #[error(
        "rectified width must be at least {min} for {regions} regions and filtered_stride {stride} (every region needs a stored column: filtered_stride x regions^2), got {width}"
    )]
    RectifiedTooNarrow {
        /// The rectified width.
        width: u32,
        /// The variant's regions.
        regions: u32,
        /// The variant's `filtered_stride`.
        stride: u32,
        /// The smallest allowed width.
        min: u32,
    },
    /// A rectified width that the variant's `filtered_stride` does not divide.
    #[error(
        "rectified width must be a multiple of filtered_stride = {stride} (prefilter stores one column in {stride}), got {width}"
    )]
    RectifiedStride {
        /// The rectified width.
        width: u32,
        /// The variant's `filtered_stride`.
        stride: u32,
    },
    /// A variant knob is out of range.
    #[error(transparent)]
    Variant(#[from] crate::variant::VariantError),
    /// The eye sits on the spot light.
    #[error("the camera is at the spot light's position: epipolar rectification is undefined")]
    EyeAtLight,
    /// A number or vector is outside the range the set-up accepts.
    #[error("frame parameter {what} must be {allowed}, got {value}")]
    OutOfRange {
        /// The parameter (`camera near/far`, `medium albedo`, `shadow map basis`, ...).
        what: &'static str,
        /// What is accepted, in words.
        allowed: &'static str,
        /// The rejected value(s).
        value: String,
    },
    /// The inputs passed every check but a uniform came out NaN or infinite in `f32` (a
    /// safety net: the checks above are meant to make this unreachable).
    #[error(
        "frame set-up produced a non-finite {what} from these inputs (the numbers are too extreme for f32)"
    )]
    NotRepresentable {
        /// The uniform field or slice-table entry.
        what: &'static str,
    },
}

/// Largest magnitude of a world coordinate (positions, far planes, orthographic windows)
/// the frame set-up accepts: every uniform then fits in `f32` with room to spare.
pub const MAX_COORD: f64 = 1e9;
/// Range of `tan` of a half field of view (camera and perspective shadow map) the frame
/// set-up accepts: a full angle from about 0.0001 to 179.9999 degrees.
pub const TAN_HALF_RANGE: std::ops::RangeInclusive<f64> = 1e-6..=1e6;
/// Smallest camera near plane distance the frame set-up accepts.
pub const MIN_NEAR: f64 = 1e-9;
/// Largest extinction coefficient sigma_t (1/m) the frame set-up accepts.
pub const MAX_SIGMA_T: f64 = 1e6;
/// Largest light colour channel (irradiance or intensity) the frame set-up accepts.
pub const MAX_COLOR: f64 = 1e30;
/// Tolerance on the length and orthogonality of the camera and shadow-map bases.
pub const BASIS_TOLERANCE: f64 = 1e-3;

/// A vector for messages: `[x, y, z]`, each number as Rust's `{:?}` writes it (`1e300`,
/// `NaN`, `inf`).
pub(crate) fn show(v: DVec3) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

/// Fails with [`FrameError::OutOfRange`] unless `ok`.
pub(crate) fn require(
    ok: bool,
    what: &'static str,
    allowed: &'static str,
    value: impl FnOnce() -> String,
) -> Result<(), FrameError> {
    if ok {
        Ok(())
    } else {
        Err(FrameError::OutOfRange {
            what,
            allowed,
            value: value(),
        })
    }
}

/// Finite and within [`MAX_COORD`] in every coordinate.
pub(crate) fn in_world(v: DVec3) -> bool {
    v.is_finite() && v.abs().max_element() <= MAX_COORD
}

/// The unit vector along `v`, for any finite non-zero `v` (scaled first, so that huge and
/// tiny vectors normalise without overflow or underflow).
pub(crate) fn unit(v: DVec3) -> Option<DVec3> {
    if !v.is_finite() {
        return None;
    }
    let m = v.abs().max_element();
    if m == 0.0 {
        return None;
    }
    (v / m).try_normalize()
}

/// Three finite unit vectors, mutually orthogonal, within [`BASIS_TOLERANCE`].
pub(crate) fn orthonormal(b: [DVec3; 3]) -> bool {
    let t = BASIS_TOLERANCE;
    b.iter()
        .all(|v| v.is_finite() && (v.length() - 1.0).abs() <= t)
        && b[0].dot(b[1]).abs() <= t
        && b[0].dot(b[2]).abs() <= t
        && b[1].dot(b[2]).abs() <= t
}

/// The validated camera, light and medium of a frame, as every family's uniform block
/// stores them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScenePart {
    /// The camera.
    pub(crate) cam: CameraDesc,
    /// Unit direction from the eye towards the light.
    pub(crate) axis: DVec3,
    /// Eye-light distance (spot), 0 (directional).
    pub(crate) dist: f64,
    /// Spot position (zero for the sun).
    pub(crate) light_pos: DVec3,
    /// Unit direction the light travels (spot axis).
    pub(crate) light_dir: DVec3,
    /// Light colour.
    pub(crate) color: [f64; 3],
    /// Cosine of the inner cone angle (1 for the sun).
    pub(crate) cos_in: f64,
    /// Cosine of the outer cone angle (1 for the sun).
    pub(crate) cos_out: f64,
}

/// Checks the camera, light and medium of a frame for a variant compiled for `expected`
/// lights.
pub(crate) fn validate_scene(
    expected: LightKind,
    camera: &CameraDesc,
    light: &LightDesc,
    medium: &MediumDesc,
) -> Result<ScenePart, FrameError> {
    let got = light.kind();
    if got != expected {
        return Err(FrameError::LightMismatch { expected, got });
    }
    let cam = *camera;
    require(
        in_world(cam.position),
        "camera position",
        "finite, every coordinate within +-1e9",
        || show(cam.position),
    )?;
    require(
        orthonormal([cam.forward, cam.right, cam.up]),
        "camera forward/right/up",
        "finite unit vectors, mutually orthogonal (within 1e-3)",
        || {
            format!(
                "forward {}, right {}, up {}",
                show(cam.forward),
                show(cam.right),
                show(cam.up)
            )
        },
    )?;
    require(
        TAN_HALF_RANGE.contains(&cam.tan_half_fov_y),
        "camera fov (tan_half_fov_y)",
        "in [1e-6, 1e6] (a vertical fov between about 0.0001 and 179.9999 degrees)",
        || format!("{:?}", cam.tan_half_fov_y),
    )?;
    require(
        cam.near >= MIN_NEAR && cam.far > cam.near && cam.far <= MAX_COORD,
        "camera near/far",
        "1e-9 <= near < far <= 1e9",
        || format!("near {:?}, far {:?}", cam.near, cam.far),
    )?;
    require(
        (0.0..=MAX_SIGMA_T).contains(&medium.sigma_t),
        "medium sigma_t",
        "in [0, 1e6] (1/m)",
        || format!("{:?}", medium.sigma_t),
    )?;
    require(
        (0.0..=1.0).contains(&medium.albedo),
        "medium albedo",
        "in [0, 1]",
        || format!("{:?}", medium.albedo),
    )?;
    require(
        medium.g.abs() < 1.0,
        "medium g (Henyey-Greenstein g)",
        "in (-1, 1)",
        || format!("{:?}", medium.g),
    )?;
    let light_direction = |direction: DVec3| {
        unit(direction).ok_or_else(|| FrameError::OutOfRange {
            what: "light direction",
            allowed: "a finite non-zero vector",
            value: show(direction),
        })
    };
    let (axis, dist, light_pos, light_dir, color, cos_in, cos_out) = match *light {
        LightDesc::Directional { direction, color } => {
            let l = light_direction(direction)?;
            (-l, 0.0, DVec3::ZERO, l, color, 1.0, 1.0)
        }
        LightDesc::Spot {
            position,
            direction,
            inner_deg,
            outer_deg,
            color,
        } => {
            require(
                in_world(position),
                "light position",
                "finite, every coordinate within +-1e9",
                || show(position),
            )?;
            let l = light_direction(direction)?;
            require(
                0.0 <= inner_deg && inner_deg <= outer_deg && outer_deg <= 180.0,
                "light cone angles",
                "0 <= inner_deg <= outer_deg <= 180",
                || format!("inner_deg {inner_deg:?}, outer_deg {outer_deg:?}"),
            )?;
            let to = position - cam.position;
            let d = to.length();
            // Relative to the coordinates' magnitude (their rounding), not to the far plane:
            // a far plane of 1e9 must not put a light 12 m away "at the eye".
            if d <= 1e-9 * (1.0 + cam.position.length().max(position.length())) {
                return Err(FrameError::EyeAtLight);
            }
            (
                to / d,
                d,
                position,
                l,
                color,
                inner_deg.to_radians().cos(),
                outer_deg.to_radians().cos(),
            )
        }
        LightDesc::Area(_) => {
            return Err(FrameError::OutOfRange {
                what: "light",
                allowed: "a directional or spot light (an area light's VPLs are spots)",
                value: "an area light".into(),
            });
        }
    };
    require(
        color.iter().all(|c| (0.0..=MAX_COLOR).contains(c)),
        "light colour",
        "finite and in [0, 1e30] per channel",
        || format!("{color:?}"),
    )?;
    Ok(ScenePart {
        cam,
        axis,
        dist,
        light_pos,
        light_dir,
        color,
        cos_in,
        cos_out,
    })
}

/// Checks the engine's standard shadow map description (its `size` is checked with the
/// other sizes).
pub(crate) fn validate_shadow_map(shadow: &ShadowMapDesc) -> Result<(), FrameError> {
    require(
        in_world(shadow.origin),
        "shadow map origin",
        "finite, every coordinate within +-1e9",
        || show(shadow.origin),
    )?;
    let [r, u, f] = shadow.basis;
    require(
        orthonormal(shadow.basis),
        "shadow map basis",
        "three finite unit vectors (right, up, forward), mutually orthogonal (within 1e-3)",
        || format!("right {}, up {}, forward {}", show(r), show(u), show(f)),
    )?;
    match shadow.projection {
        ShadowProjectionDesc::Orthographic { x0, x1, y0, y1 } => require(
            [x0, x1, y0, y1].iter().all(|v| v.abs() <= MAX_COORD) && x0 < x1 && y0 < y1,
            "shadow map projection (orthographic)",
            "finite, within +-1e9, x0 < x1 and y0 < y1",
            || format!("x0 {x0:?}, x1 {x1:?}, y0 {y0:?}, y1 {y1:?}"),
        )?,
        ShadowProjectionDesc::Perspective { tan_half } => require(
            TAN_HALF_RANGE.contains(&tan_half),
            "shadow map projection (perspective tan_half)",
            "in [1e-6, 1e6]",
            || format!("{tan_half:?}"),
        )?,
    }
    require(
        shadow.near.abs() <= MAX_COORD && shadow.far.abs() <= MAX_COORD && shadow.near < shadow.far,
        "shadow map near/far",
        "finite, within +-1e9, near < far",
        || format!("near {:?}, far {:?}", shadow.near, shadow.far),
    )?;
    require(
        (0.0..=1e3).contains(&shadow.bias_texels),
        "shadow map bias_texels",
        "in [0, 1000]",
        || format!("{:?}", shadow.bias_texels),
    )
}

/// The shadow-map kind (0 orthographic, 1 perspective) and projection vector of the
/// uniform blocks.
/// Fails unless the shadow map's projection is the light's: orthographic for a
/// directional light (parallel rays), perspective for a spot (rays from the light). The
/// kernels are generated for one light kind and test only that kind's map (llvmpipe runs
/// both halves of a branch on the map's kind, so they do not branch on it).
pub(crate) fn validate_shadow_projection(
    light: LightKind,
    shadow: &ShadowMapDesc,
) -> Result<(), FrameError> {
    let orthographic = matches!(shadow.projection, ShadowProjectionDesc::Orthographic { .. });
    let (ok, allowed) = match light {
        LightKind::Directional => (orthographic, "orthographic (a directional light's map)"),
        LightKind::Spot | LightKind::Area => (!orthographic, "perspective (a spot's map)"),
    };
    require(ok, "shadow map projection", allowed, || {
        if orthographic {
            "orthographic".to_owned()
        } else {
            "perspective".to_owned()
        }
    })
}

pub(crate) fn shadow_projection(shadow: &ShadowMapDesc) -> (f64, [f32; 4]) {
    match shadow.projection {
        ShadowProjectionDesc::Orthographic { x0, x1, y0, y1 } => {
            (0.0, [x0 as f32, x1 as f32, y0 as f32, y1 as f32])
        }
        ShadowProjectionDesc::Perspective { tan_half } => (1.0, [tan_half as f32, 0.0, 0.0, 0.0]),
    }
}

/// Fails with [`FrameError::NotRepresentable`] naming the first uniform field that is not
/// finite.
pub(crate) fn finite_fields<const N: usize>(
    fields: [(&'static str, [f32; 4]); N],
) -> Result<(), FrameError> {
    match fields
        .iter()
        .find(|(_, v)| v.iter().any(|x| !x.is_finite()))
    {
        Some(&(what, _)) => Err(FrameError::NotRepresentable { what }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sun takes an orthographic map and a spot a perspective one; the error names the
    /// projection the light needs.
    #[test]
    fn shadow_projection_matches_the_light() {
        let map = |projection| ShadowMapDesc {
            origin: DVec3::ZERO,
            basis: [DVec3::X, DVec3::Y, DVec3::Z],
            projection,
            near: 0.1,
            far: 10.0,
            size: 1024,
            bias_texels: 1.5,
        };
        let ortho = map(ShadowProjectionDesc::Orthographic {
            x0: -1.0,
            x1: 1.0,
            y0: -1.0,
            y1: 1.0,
        });
        let persp = map(ShadowProjectionDesc::Perspective { tan_half: 0.5 });
        assert!(validate_shadow_projection(LightKind::Directional, &ortho).is_ok());
        assert!(validate_shadow_projection(LightKind::Spot, &persp).is_ok());
        let e = validate_shadow_projection(LightKind::Directional, &persp)
            .expect_err("a sun with a perspective map")
            .to_string();
        assert!(
            e.contains("shadow map projection") && e.contains("orthographic"),
            "{e}"
        );
        let e = validate_shadow_projection(LightKind::Spot, &ortho)
            .expect_err("a spot with an orthographic map")
            .to_string();
        assert!(
            e.contains("shadow map projection") && e.contains("perspective"),
            "{e}"
        );
    }
}
