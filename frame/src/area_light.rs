//! An area light as the engine describes it ([`AreaLightDesc`], the payload of
//! [`LightDesc::Area`]) and its virtual point lights (VPLs): the one placement every user
//! shares (the `area_ivsv` family's set-up, the reference's `vpl` truth and its CPU mirrors),
//! and the shadow map of each VPL, derived from one map the engine fits for the light's point
//! limit ([`AreaLightDesc::vpl_inputs`]), so that an engine and the reference render exactly
//! the same maps.
//!
//! # Model
//!
//! A flat emitter whose every surface element `dA` is a small spot light of radiant intensity
//! `radiance * cone(angle) * dA`, `angle` measured from the emitting normal, `cone` the spot's
//! smoothstep from the outer to the inner half-angle (not Lambert's cosine: each VPL is then
//! exactly a spot with one perspective shadow map). `n` VPLs are the points `i = 1..=n` of the
//! Halton sequence in bases 2 and 3 mapped onto the outline (area-preserving: a rectangle
//! linearly, a disk by Shirley and Chiu's concentric map), each a spot of intensity
//! `radiance * area / n` along the normal; a two-sided light adds the same spot along the
//! reversed normal at every point.

use crate::area_ivsv::VplInput;
use crate::scene::{
    FrameError, LightDesc, MAX_COLOR, ShadowMapDesc, ShadowProjectionDesc, in_world, require, show,
    unit,
};
use glam::DVec3;

/// The widest cone an area light may have: every VPL has one perspective shadow map.
pub const MAX_AREA_OUTER_DEG: f64 = 80.0;

/// The outline of an area light, in its own plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShapeDesc {
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

impl AreaShapeDesc {
    /// Surface area (one side), m^2.
    pub fn area(&self) -> f64 {
        match *self {
            AreaShapeDesc::Rect { width, height } => width * height,
            AreaShapeDesc::Disk { radius } => std::f64::consts::PI * radius * radius,
        }
    }

    /// The point of the outline for `(u, v)` in the unit square, in the light's plane
    /// coordinates (right, up): a rectangle maps linearly, a disk by Shirley and Chiu's
    /// concentric map; both preserve area, so uniform or low-discrepancy points in the square
    /// stay so on the light.
    pub fn point(&self, u: f64, v: f64) -> (f64, f64) {
        match *self {
            AreaShapeDesc::Rect { width, height } => ((u - 0.5) * width, (v - 0.5) * height),
            AreaShapeDesc::Disk { radius } => {
                let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
                if a == 0.0 && b == 0.0 {
                    return (0.0, 0.0);
                }
                let q = std::f64::consts::FRAC_PI_4;
                let (r, phi) = if a.abs() > b.abs() {
                    (a, q * (b / a))
                } else {
                    (b, 2.0 * q - q * (a / b))
                };
                (radius * r * phi.cos(), radius * r * phi.sin())
            }
        }
    }

    /// The largest distance of a point of the outline from its centre.
    pub fn radius(&self) -> f64 {
        match *self {
            AreaShapeDesc::Rect { width, height } => 0.5 * width.hypot(height),
            AreaShapeDesc::Disk { radius } => radius,
        }
    }
}

/// An area light (see the module docs for the model).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLightDesc {
    /// Centre of the light.
    pub position: DVec3,
    /// The emitting normal (the cone's axis); need not be normalised.
    pub direction: DVec3,
    /// The outline's up axis, made orthogonal to `direction` (need not be normalised); when
    /// `None`, the up axis of [`light_basis`]`(direction)`.
    pub up: Option<DVec3>,
    /// The outline.
    pub shape: AreaShapeDesc,
    /// Full emission inside this half-angle from the normal (degrees).
    pub inner_deg: f64,
    /// No emission beyond this half-angle from the normal (degrees, below
    /// [`MAX_AREA_OUTER_DEG`]).
    pub outer_deg: f64,
    /// Radiance along the normal (RGB, W sr^-1 m^-2).
    pub radiance: [f64; 3],
    /// Whether the back face emits too (the same cone about the reversed normal).
    pub two_sided: bool,
}

/// The light-space basis of a light travelling along `forward`: `[right, up, forward]`,
/// `right = forward x Y` (or `x X` when `forward` is nearly vertical). Every standard shadow
/// map of a spot and every VPL map uses it.
pub fn light_basis(forward: DVec3) -> [DVec3; 3] {
    let f = forward.normalize();
    let helper = if f.y.abs() < 0.99 { DVec3::Y } else { DVec3::X };
    let right = f.cross(helper).normalize();
    let up = right.cross(f);
    [right, up, f]
}

/// The `i`-th point of the van der Corput sequence in `base` (radical inverse), in [0, 1).
pub fn halton(mut i: usize, base: usize) -> f64 {
    let mut f = 1.0;
    let mut r = 0.0;
    let b = base as f64;
    while i > 0 {
        f /= b;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

impl AreaLightDesc {
    /// Checks every field; the error names the first offending one.
    ///
    /// # Errors
    ///
    /// [`FrameError::OutOfRange`] naming the field and the accepted range.
    pub fn validate(&self) -> Result<(), FrameError> {
        require(
            in_world(self.position),
            "area light position",
            "finite, every coordinate within +-1e9",
            || show(self.position),
        )?;
        let n = unit(self.direction).ok_or_else(|| FrameError::OutOfRange {
            what: "area light direction",
            allowed: "a finite non-zero vector",
            value: show(self.direction),
        })?;
        if let Some(up) = self.up {
            require(
                up.is_finite() && (up - n * up.dot(n)).length() > 1e-6 * up.length(),
                "area light up",
                "a finite vector not parallel to the direction",
                || show(up),
            )?;
        }
        let size_ok = |v: f64| v.is_finite() && v > 0.0 && v <= 1e6;
        match self.shape {
            AreaShapeDesc::Rect { width, height } => require(
                size_ok(width) && size_ok(height),
                "area light width/height",
                "in (0, 1e6] metres",
                || format!("width {width:?}, height {height:?}"),
            )?,
            AreaShapeDesc::Disk { radius } => require(
                size_ok(radius),
                "area light radius",
                "in (0, 1e6] metres",
                || format!("{radius:?}"),
            )?,
        }
        require(
            0.0 <= self.inner_deg
                && self.inner_deg <= self.outer_deg
                && self.outer_deg < MAX_AREA_OUTER_DEG,
            "area light cone angles",
            "0 <= inner_deg <= outer_deg < 80 (each VPL has one perspective shadow map)",
            || {
                format!(
                    "inner_deg {:?}, outer_deg {:?}",
                    self.inner_deg, self.outer_deg
                )
            },
        )?;
        require(
            self.radiance.iter().all(|c| (0.0..=MAX_COLOR).contains(c)),
            "area light colour (radiance)",
            "finite and in [0, 1e30] per channel",
            || format!("{:?}", self.radiance),
        )
    }

    /// The light's frame: `[right, up, normal]`, right and up spanning its plane.
    pub fn frame(&self) -> [DVec3; 3] {
        let n = self.direction.normalize();
        let up = match self.up {
            Some(up) => (up - n * up.dot(n)).normalize(),
            None => light_basis(n)[1],
        };
        [up.cross(n), up, n]
    }

    /// The world point of the light for `(u, v)` in the unit square ([`AreaShapeDesc::point`]).
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        let [right, up, _] = self.frame();
        let (x, y) = self.shape.point(u, v);
        self.position + right * x + up * y
    }

    /// Emitting faces: 1, or 2 when two-sided.
    pub fn faces(&self) -> usize {
        if self.two_sided { 2 } else { 1 }
    }

    /// The VPLs of `points` Halton points as `(position, direction)`, a point's faces
    /// consecutive, and their common intensity.
    fn vpl_rays(&self, points: usize) -> (Vec<(DVec3, DVec3)>, [f64; 3]) {
        let scale = self.shape.area() / points.max(1) as f64;
        let normal = self.frame()[2];
        let mut out = Vec::with_capacity(points * self.faces());
        for i in 1..=points {
            let p = self.point(halton(i, 2), halton(i, 3));
            for side in [1.0, -1.0].into_iter().take(self.faces()) {
                out.push((p, normal * side));
            }
        }
        (out, self.radiance.map(|c| c * scale))
    }

    /// A VPL at `position` aimed along `direction` with intensity `color`: a spot with the
    /// light's cone.
    fn spot(&self, position: DVec3, direction: DVec3, color: [f64; 3]) -> LightDesc {
        LightDesc::Spot {
            position,
            direction,
            inner_deg: self.inner_deg,
            outer_deg: self.outer_deg,
            color,
        }
    }

    /// The VPLs of `points` Halton points (`points * faces()` spots, a point's faces
    /// consecutive), each of intensity `radiance * area / points`: their sum tends to the
    /// light as `points` grows, and the first `n` of `m > n` points are the same `n` points.
    pub fn vpl_lights(&self, points: usize) -> Vec<LightDesc> {
        let (rays, color) = self.vpl_rays(points);
        rays.into_iter()
            .map(|(p, d)| self.spot(p, d, color))
            .collect()
    }

    /// The spot light the area light tends to as it shrinks: at its centre, intensity
    /// `radiance * area`, front face only. Its standard shadow map is the template of the
    /// VPLs' maps ([`Self::vpl_inputs`]); a single-light family renders it in place of the
    /// area light (hard shadows).
    pub fn point_limit(&self) -> LightDesc {
        LightDesc::Spot {
            position: self.position,
            direction: self.frame()[2],
            inner_deg: self.inner_deg,
            outer_deg: self.outer_deg,
            color: self.radiance.map(|c| c * self.shape.area()),
        }
    }

    /// Halton points for `vpls` VPLs: `vpls`, or half of it when two-sided.
    ///
    /// # Errors
    ///
    /// [`FrameError::OutOfRange`] for zero VPLs, or an odd count for a two-sided light.
    pub fn vpl_points(&self, vpls: u32) -> Result<usize, FrameError> {
        let faces = self.faces() as u32;
        require(
            vpls > 0 && vpls.is_multiple_of(faces),
            "VPL count",
            "positive, and even for a two-sided area light (both faces of every point)",
            || format!("{vpls} VPLs, {faces} faces"),
        )?;
        Ok((vpls / faces) as usize)
    }

    /// The shadow map of a VPL at `position` aimed along `direction`, from `template`, the
    /// standard shadow map the engine fitted for [`Self::point_limit`] (a perspective map
    /// at the light's centre whose far plane reaches every receiver): origin at the VPL,
    /// basis [`light_basis`]`(direction)`, the template's projection, size, bias and near
    /// plane, its far plane pushed out by the VPL's distance from the centre (so it reaches
    /// every receiver the template reaches).
    pub fn vpl_shadow_map(
        &self,
        template: &ShadowMapDesc,
        position: DVec3,
        direction: DVec3,
    ) -> ShadowMapDesc {
        ShadowMapDesc {
            origin: position,
            basis: light_basis(direction),
            far: template.far + (position - self.position).length(),
            ..*template
        }
    }

    /// The `vpls` VPLs of one frame with their shadow maps: what
    /// [`crate::area_ivsv::prepare_area_ivsv`] takes, layer `i` of the engine's VPL map
    /// array rendered with `out[i].shadow_map`.
    ///
    /// # Errors
    ///
    /// [`FrameError`] for a bad light ([`Self::validate`]), a VPL count the light cannot
    /// take ([`Self::vpl_points`]) or a template that is not a perspective map.
    pub fn vpl_inputs(
        &self,
        vpls: u32,
        template: &ShadowMapDesc,
    ) -> Result<Vec<VplInput>, FrameError> {
        self.validate()?;
        crate::scene::validate_shadow_map(template)?;
        let points = self.vpl_points(vpls)?;
        let ShadowProjectionDesc::Perspective { .. } = template.projection else {
            return Err(FrameError::OutOfRange {
                what: "shadow map projection",
                allowed: "perspective (an area light's template is the map of its point limit, \
                          a spot)",
                value: "orthographic".into(),
            });
        };
        let (rays, color) = self.vpl_rays(points);
        Ok(rays
            .into_iter()
            .map(|(position, direction)| VplInput {
                light: self.spot(position, direction, color),
                shadow_map: self.vpl_shadow_map(template, position, direction),
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light() -> AreaLightDesc {
        AreaLightDesc {
            position: DVec3::new(0.0, 4.0, 0.0),
            direction: DVec3::new(0.0, -1.0, 0.2),
            up: None,
            shape: AreaShapeDesc::Rect {
                width: 1.0,
                height: 0.5,
            },
            inner_deg: 30.0,
            outer_deg: 60.0,
            radiance: [2.0, 2.0, 2.0],
            two_sided: false,
        }
    }

    fn template() -> ShadowMapDesc {
        ShadowMapDesc {
            origin: DVec3::new(0.0, 4.0, 0.0),
            basis: light_basis(DVec3::new(0.0, -1.0, 0.2)),
            projection: ShadowProjectionDesc::Perspective {
                tan_half: 60f64.to_radians().tan(),
            },
            near: 1e-3,
            far: 20.0,
            size: 64,
            bias_texels: 1.5,
        }
    }

    #[test]
    fn vpls_sum_to_the_light_and_lie_on_it() {
        let l = light();
        let v = l.vpl_inputs(16, &template()).unwrap();
        assert_eq!(v.len(), 16);
        let mut total = 0.0;
        for vpl in &v {
            let LightDesc::Spot {
                position, color, ..
            } = vpl.light
            else {
                panic!("a VPL is a spot")
            };
            total += color[0];
            let q = position - l.position;
            let [r, u, n] = l.frame();
            assert!(q.dot(n).abs() < 1e-12);
            assert!(q.dot(r).abs() <= 0.5 + 1e-12 && q.dot(u).abs() <= 0.25 + 1e-12);
            assert_eq!(vpl.shadow_map.origin, position);
            assert!(vpl.shadow_map.far >= 20.0 + q.length() - 1e-12);
        }
        assert!((total - 2.0 * 0.5).abs() < 1e-12);
    }

    #[test]
    fn bad_lights_are_named() {
        let bad = |f: fn(&mut AreaLightDesc), what: &str| {
            let mut l = light();
            f(&mut l);
            match l.validate() {
                Err(FrameError::OutOfRange { what: w, .. }) => assert_eq!(w, what),
                other => panic!("{what}: {other:?}"),
            }
        };
        bad(|l| l.position.x = f64::NAN, "area light position");
        bad(|l| l.direction = DVec3::ZERO, "area light direction");
        bad(|l| l.up = Some(DVec3::new(0.0, -2.0, 0.4)), "area light up");
        bad(
            |l| {
                l.shape = AreaShapeDesc::Disk { radius: 0.0 };
            },
            "area light radius",
        );
        bad(|l| l.outer_deg = 85.0, "area light cone angles");
        bad(|l| l.radiance[1] = -1.0, "area light colour (radiance)");
        let mut two = light();
        two.two_sided = true;
        assert!(two.vpl_inputs(7, &template()).is_err());
        assert_eq!(two.vpl_inputs(8, &template()).unwrap().len(), 8);
    }
}
