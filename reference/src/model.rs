//! The single-scattering model of DESIGN.md, term by term, in f64:
//!
//! ```text
//! L(pixel) = integral_0^s sigma_s p(theta(t)) L_in(x_t) V(x_t) exp(-sigma_t t) dt
//! ```
//!
//! - directional: `L_in = E` (no extinction along the light path);
//! - spot: `L_in = I cone(angle) exp(-sigma_t d) / d^2`, `d` the distance to the light,
//!   `cone` a smoothstep from the outer to the inner half-angle;
//! - `theta` is the scattering angle between the light's travel direction and the direction
//!   towards the eye: `cos theta = -dot(light_travel, view_dir)`, so `g > 0` (forward
//!   scattering) brightens views towards the light.
//!
//! Also the closed forms the ground truth is tested against: the unshadowed directional
//! integral (with its `sigma_t -> 0` limit) and the Sun et al. 2005 airlight integral for an
//! isotropic point light (corrected form, `papers/notes.md`).

use crate::buffers::light_basis;
use crate::cookie::Cookie;
use crate::scene::{Light, Medium};
use glam::DVec3;
use std::f64::consts::PI;

/// Henyey-Greenstein phase function for `cos theta` (isotropic `1/(4 pi)` at `g = 0`).
pub fn phase_hg(g: f64, cos_theta: f64) -> f64 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// `(1 - exp(-sigma_t s)) / sigma_t`, equal to `s` in the limit `sigma_t -> 0` and computed
/// without cancellation or division by zero for small `sigma_t s`.
pub fn transmittance_integral(sigma_t: f64, s: f64) -> f64 {
    let x = sigma_t * s;
    if x.abs() < 1e-300 {
        s
    } else {
        -(-x).exp_m1() / sigma_t
    }
}

/// `integral_a^b exp(-sigma_t t) dt` for `0 <= a <= b`, stable as `sigma_t -> 0`.
pub fn transmittance_integral_between(sigma_t: f64, a: f64, b: f64) -> f64 {
    (-sigma_t * a).exp() * transmittance_integral(sigma_t, b - a)
}

/// Smooth spot cone falloff: 1 inside the inner half-angle, 0 beyond the outer one, a
/// smoothstep in `cos(angle)` between. `cos_angle` is the cosine to the spot axis.
pub fn cone_falloff(cos_angle: f64, inner_deg: f64, outer_deg: f64) -> f64 {
    let ci = inner_deg.to_radians().cos();
    let co = outer_deg.to_radians().cos();
    if outer_deg >= 180.0 && inner_deg >= 180.0 {
        return 1.0;
    }
    if ci - co <= 1e-12 {
        return if cos_angle >= co { 1.0 } else { 0.0 };
    }
    let x = ((cos_angle - co) / (ci - co)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Per-ray constants of the integrand for one view ray and one light.
#[derive(Clone, Copy, Debug)]
pub struct RayIntegrand<'a> {
    origin: DVec3,
    dir: DVec3,
    medium: Medium,
    kind: LightKind,
    /// A spot's cookie, its light frame (right, up, forward) and `tan(outer angle)`.
    cookie: Option<(&'a Cookie, [DVec3; 3], f64)>,
}

#[derive(Clone, Copy, Debug)]
enum LightKind {
    /// Constant factor `sigma_s p(theta)` (times E, applied by the caller).
    Directional { c: f64 },
    /// Spot light parameters.
    Spot {
        position: DVec3,
        axis: DVec3,
        inner_deg: f64,
        outer_deg: f64,
        /// Intensity per unit `Light::color` (1; an area light's point limit: its area).
        scale: f64,
        /// Squared radius of the disk the point stands for (0: a point; see
        /// [`RayIntegrand::softened`]).
        soft_r2: f64,
    },
}

impl<'a> RayIntegrand<'a> {
    /// Integrand of the ray `origin + t dir` (`dir` unit) for `light` in `medium`. The RGB
    /// light colour is left out: every method multiplies by `Light::color` at the end. A
    /// spot's cookie is left out of [`Self::eval`] and [`Self::integrate`] and in
    /// [`Self::eval_rgb`] and [`Self::integrate_rgb`]. An area light's integrand is its point
    /// limit's ([`crate::scene::AreaLight::point_limit`]): the truth integrates over its
    /// points instead.
    pub fn new(origin: DVec3, dir: DVec3, light: &'a Light, medium: &Medium) -> RayIntegrand<'a> {
        let kind = match light {
            Light::Directional { direction, .. } => {
                let cos_theta = -direction.normalize().dot(dir);
                LightKind::Directional {
                    c: medium.sigma_s() * phase_hg(medium.g, cos_theta),
                }
            }
            Light::Spot {
                position,
                direction,
                inner_angle_deg,
                outer_angle_deg,
                ..
            } => LightKind::Spot {
                position: *position,
                axis: direction.normalize(),
                inner_deg: *inner_angle_deg,
                outer_deg: *outer_angle_deg,
                scale: 1.0,
                soft_r2: 0.0,
            },
            // The point limit (per unit radiance, so times the area); the truth integrates
            // over the light's points instead (`truth::point_lights`).
            Light::Area(a) => LightKind::Spot {
                position: a.position,
                axis: a.frame().2,
                inner_deg: a.inner_angle_deg,
                outer_deg: a.outer_angle_deg,
                scale: a.shape.area(),
                soft_r2: 0.0,
            },
        };
        let cookie = match light {
            Light::Spot {
                direction,
                outer_angle_deg,
                cookie: Some(cookie),
                ..
            } => Some((
                cookie,
                light_basis(*direction),
                outer_angle_deg.to_radians().tan(),
            )),
            _ => None,
        };
        RayIntegrand {
            origin,
            dir,
            medium: *medium,
            kind,
            cookie,
        }
    }

    /// The same integrand with a spot's point replaced by a small disk of squared radius `r2`
    /// facing along the axis, of the same total intensity: `1 / d^2` becomes
    /// `ln(1 + r2 / d^2) / r2`, exact on the disk's axis for a flat emission profile and
    /// `1 / d^2 (1 - r2 / (2 d^2) + ...)` away from it. The `exact` truth of an area light
    /// gives each point of its quadrature the disk of its cell's area, so that a view ray
    /// passing next to a point does not pick up a `1 / d^2` spike the light's surface does
    /// not have (the integral over the surface is bounded). No effect on a directional light.
    pub fn softened(mut self, r2: f64) -> Self {
        if let LightKind::Spot { soft_r2, .. } = &mut self.kind {
            *soft_r2 = r2.max(0.0);
        }
        self
    }

    /// Whether the light carries a cookie (the integrand is then RGB).
    pub fn has_cookie(&self) -> bool {
        self.cookie.is_some()
    }

    /// The cookie's value for the ray point at `t` (white without a cookie).
    pub fn cookie_at(&self, t: f64) -> [f64; 3] {
        match (self.cookie, self.kind) {
            (Some((cookie, basis, tan_outer)), LightKind::Spot { position, .. }) => {
                let travel = self.origin + self.dir * t - position;
                cookie.sample_dir(travel, &basis, tan_outer)
            }
            _ => [1.0; 3],
        }
    }

    /// [`Self::eval`] times the cookie (RGB).
    pub fn eval_rgb(&self, t: f64) -> [f64; 3] {
        let f = self.eval(t);
        if f == 0.0 {
            return [0.0; 3];
        }
        self.cookie_at(t).map(|c| c * f)
    }

    /// `integral_a^b` of [`Self::eval_rgb`]: [`Self::integrate`] per channel without a
    /// cookie, 16-point Gauss-Legendre on `pieces` equal sub-intervals with one.
    pub fn integrate_rgb(&self, a: f64, b: f64, pieces: usize) -> [f64; 3] {
        if self.cookie.is_none() {
            let f = self.integrate(a, b, pieces);
            return [f; 3];
        }
        if b <= a {
            return [0.0; 3];
        }
        let n = pieces.max(1);
        let h = (b - a) / n as f64;
        let mut sum = [0.0; 3];
        for i in 0..n {
            let lo = a + h * i as f64;
            let m = lo + 0.5 * h;
            let r = 0.5 * h;
            for (x, w) in GL16_X.iter().zip(GL16_W) {
                let (p, q) = (self.eval_rgb(m - r * x), self.eval_rgb(m + r * x));
                for k in 0..3 {
                    sum[k] += w * r * (p[k] + q[k]);
                }
            }
        }
        sum
    }

    /// Whether the unshadowed integrand over a segment has a closed form (directional).
    pub fn is_directional(&self) -> bool {
        matches!(self.kind, LightKind::Directional { .. })
    }

    /// The unshadowed integrand `sigma_s p L_in exp(-sigma_t t)` at parameter `t` (scalar,
    /// without the light colour).
    pub fn eval(&self, t: f64) -> f64 {
        let sigma_t = self.medium.sigma_t;
        match self.kind {
            LightKind::Directional { c } => c * (-sigma_t * t).exp(),
            LightKind::Spot {
                position,
                axis,
                inner_deg,
                outer_deg,
                scale,
                soft_r2,
            } => {
                let x = self.origin + self.dir * t;
                let to_x = x - position;
                let d2 = to_x.length_squared();
                if d2 <= 0.0 {
                    return 0.0;
                }
                let d = d2.sqrt();
                let travel = to_x / d;
                let cone = cone_falloff(travel.dot(axis), inner_deg, outer_deg);
                if cone <= 0.0 {
                    return 0.0;
                }
                let p = phase_hg(self.medium.g, -travel.dot(self.dir));
                // 1 / d^2, or a disk of radius^2 soft_r2 seen on its axis.
                let falloff = if soft_r2 > 0.0 {
                    (soft_r2 / d2).ln_1p() / soft_r2
                } else {
                    1.0 / d2
                };
                scale * self.medium.sigma_s() * p * cone * (-sigma_t * (d + t)).exp() * falloff
            }
        }
    }

    /// `integral_a^b` of the unshadowed integrand: closed form for a directional light,
    /// 16-point Gauss-Legendre on `pieces` equal sub-intervals for a spot light.
    pub fn integrate(&self, a: f64, b: f64, pieces: usize) -> f64 {
        if b <= a {
            return 0.0;
        }
        match self.kind {
            LightKind::Directional { c } => {
                c * transmittance_integral_between(self.medium.sigma_t, a, b)
            }
            LightKind::Spot { .. } => {
                let n = pieces.max(1);
                let h = (b - a) / n as f64;
                let mut sum = 0.0;
                for i in 0..n {
                    sum += gauss_legendre_16(
                        |t| self.eval(t),
                        a + h * i as f64,
                        a + h * (i + 1) as f64,
                    );
                }
                sum
            }
        }
    }
}

const GL16_X: [f64; 8] = [
    0.095_012_509_837_637_44,
    0.281_603_550_779_258_9,
    0.458_016_777_657_227_4,
    0.617_876_244_402_643_7,
    0.755_404_408_355_003,
    0.865_631_202_387_831_8,
    0.944_575_023_073_232_6,
    0.989_400_934_991_649_9,
];
const GL16_W: [f64; 8] = [
    0.189_450_610_455_068_5,
    0.182_603_415_044_923_6,
    0.169_156_519_395_002_5,
    0.149_595_988_816_576_7,
    0.124_628_971_255_533_9,
    0.095_158_511_682_492_78,
    0.062_253_523_938_647_89,
    0.027_152_459_411_754_095,
];

/// 16-point Gauss-Legendre quadrature of `f` over [a, b].
pub fn gauss_legendre_16(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let m = 0.5 * (a + b);
    let r = 0.5 * (b - a);
    let mut s = 0.0;
    for (x, w) in GL16_X.iter().zip(GL16_W) {
        s += w * (f(m - r * x) + f(m + r * x));
    }
    s * r
}

/// Unshadowed single scattering along a view ray of length `s` for a directional light, per
/// unit irradiance: `sigma_s p (1 - exp(-sigma_t s)) / sigma_t` (`sigma_s p s` as
/// `sigma_t -> 0`).
pub fn directional_unshadowed(medium: &Medium, cos_theta: f64, s: f64) -> f64 {
    medium.sigma_s() * phase_hg(medium.g, cos_theta) * transmittance_integral(medium.sigma_t, s)
}

/// Sun et al. 2005's special function `F(u, v) = integral_0^v exp(-u tan xi) d xi` for
/// `0 <= v < pi/2`, by composite 16-point Gauss-Legendre (converged to ~1e-13).
pub fn sun_f(u: f64, v: f64) -> f64 {
    let n = 64;
    let h = v / n as f64;
    (0..n)
        .map(|i| gauss_legendre_16(|xi| (-u * xi.tan()).exp(), h * i as f64, h * (i + 1) as f64))
        .sum()
}

/// Sun et al. 2005 closed form (corrected: `sigma_t` in `A0`'s exponent and in `A1`) for the
/// unshadowed in-scattering of an isotropic point light of unit intensity in an isotropic
/// medium, along a view ray of length `x`, with the light at distance `d_l` from the eye and
/// angle `gamma` (radians, in (0, pi)) between the view ray and the direction to the light:
///
/// ```text
/// L = A0 [F(A1, A2(x)) - F(A1, gamma / 2)]
/// A0 = sigma_s exp(-sigma_t d_l cos gamma) / (2 pi d_l sin gamma)
/// A1 = sigma_t d_l sin gamma
/// A2(x) = pi / 4 + atan((x - d_l cos gamma) / (d_l sin gamma)) / 2
/// ```
///
/// (the `1 / (2 pi)` is the isotropic phase `1 / (4 pi)` times the 2 from the substitution).
pub fn sun_airlight(medium: &Medium, d_l: f64, gamma: f64, x: f64) -> f64 {
    let (sg, cg) = gamma.sin_cos();
    let h = d_l * sg;
    let a0 = medium.sigma_s() * (-medium.sigma_t * d_l * cg).exp() / (2.0 * PI * h);
    let a1 = medium.sigma_t * h;
    let a2 = PI / 4.0 + 0.5 * ((x - d_l * cg) / h).atan();
    a0 * (sun_f(a1, a2) - sun_f(a1, gamma / 2.0))
}
