//! CPU mirror of `shaderlib/templates/common/model.wgsl` (`scatter::model`): the
//! single-scattering model's terms in f32, as the kernels evaluate them (phase, transmittance,
//! cone, spot integrand, the spot quadrature of a span, equiangular sampling).

use glam::Vec3;

/// `PI` as in the WGSL module.
pub const PI: f32 = std::f32::consts::PI;

/// Henyey-Greenstein phase function of `cos_theta`.
pub fn phase_hg(g: f32, cos_theta: f32) -> f32 {
    let denom = max(1.0 + g * g - 2.0 * g * cos_theta, 1e-8);
    (1.0 - g * g) / (4.0 * PI * denom * sqrt(denom))
}

/// `(1 - exp(-sigma_t len)) / sigma_t`, and `len` as `sigma_t len -> 0` (series below 1e-4).
pub fn transmittance_integral(sigma_t: f32, len: f32) -> f32 {
    let x = sigma_t * len;
    if x < 1e-4 {
        return len * (1.0 - 0.5 * x);
    }
    (1.0 - exp(-x)) / sigma_t
}

/// `integral_a^b exp(-sigma_t t) dt`.
pub fn transmittance_between(sigma_t: f32, a: f32, b: f32) -> f32 {
    exp(-sigma_t * a) * transmittance_integral(sigma_t, b - a)
}

/// Smoothstep cone falloff from the cosines of the outer and inner half-angles.
pub fn cone_falloff(cos_angle: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_inner - cos_outer <= 1e-6 {
        return select(0.0, 1.0, cos_angle >= cos_outer);
    }
    let x = clamp((cos_angle - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Spot-light integrand `sigma_s p I_cone exp(-sigma_t (d + t)) / d^2` at ray parameter
/// `t` (without the light colour), for the view ray `eye + t dir`.
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn spot_integrand(
    eye: Vec3,
    dir: Vec3,
    t: f32,
    light_pos: Vec3,
    light_dir: Vec3,
    cos_inner: f32,
    cos_outer: f32,
    medium: [f32; 4],
) -> f32 {
    let x = eye + dir * t;
    let to_x = x - light_pos;
    let d2 = max(to_x.dot(to_x), 1e-12);
    let d = sqrt(d2);
    let travel = to_x / d;
    let cone = cone_falloff(travel.dot(light_dir), cos_inner, cos_outer);
    let p = phase_hg(medium[2], -travel.dot(dir));
    medium[1] * p * cone * exp(-medium[0] * (d + t)) / d2
}

/// Unshadowed spot in-scattering over `[a, b]` of the view ray `eye + t dir` (without the
/// light colour): `panels` 4-point Gauss-Legendre panels in the angle `gamma` under which the
/// lamp sees the ray point (`t = t0 + h tan(gamma)`, `dt / d^2 = dgamma / h`), so the 1/d^2
/// peak of a ray passing near the lamp is integrated exactly. See the WGSL comment.
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn spot_span(
    eye: Vec3,
    dir: Vec3,
    a: f32,
    b: f32,
    panels: u32,
    light_pos: Vec3,
    light_dir: Vec3,
    cos_inner: f32,
    cos_outer: f32,
    medium: [f32; 4],
) -> f32 {
    let t0 = (light_pos - eye).dot(dir);
    let h = max(
        (eye + dir * t0 - light_pos).length(),
        1e-4 * max(b - a, 1e-6),
    );
    let g0 = ((a - t0) / h).atan();
    let w = (((b - t0) / h).atan() - g0) / panels as f32;
    let mut sum = 0.0;
    for k in 0..panels {
        let mid = g0 + (k as f32 + 0.5) * w;
        for q in 0..4 {
            let u = (mid + 0.5 * w * GL4_X[q]).tan();
            sum += GL4_W[q]
                * spot_integrand(
                    eye,
                    dir,
                    t0 + h * u,
                    light_pos,
                    light_dir,
                    cos_inner,
                    cos_outer,
                    medium,
                )
                * (1.0 + u * u);
        }
    }
    sum * 0.5 * w * h
}

/// Equiangular sampling (Kulla & Fajardo 2012) of `[a, b]` of the view ray `eye + t dir` for a
/// point light at `light_pos`, cut into `n` strata of equal angle (`t = t0 + h tan(theta)`;
/// the pdf cancels the 1/d^2 peak of the spot integrand). See the WGSL comment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equiangular {
    /// Closest approach `t0` of the ray to the lamp.
    pub t_close: f32,
    /// Distance `h` of the lamp from the ray (kept above 1e-4 of the span, as in `spot_span`).
    pub dist: f32,
    /// `theta_a = atan((a - t0) / h)`.
    pub theta_a: f32,
    /// Angle per stratum, `(theta_b - theta_a) / n`.
    pub dtheta: f32,
}

/// The equiangular strata of `[a, b]` (see [`Equiangular`]).
pub fn equiangular(eye: Vec3, dir: Vec3, light_pos: Vec3, a: f32, b: f32, n: u32) -> Equiangular {
    let t0 = (light_pos - eye).dot(dir);
    let h = max(
        (eye + dir * t0 - light_pos).length(),
        1e-4 * max(b - a, 1e-6),
    );
    let theta_a = ((a - t0) / h).atan();
    Equiangular {
        t_close: t0,
        dist: h,
        theta_a,
        dtheta: (((b - t0) / h).atan() - theta_a) / n as f32,
    }
}

/// The sample at stratum position `x` (`x = k + u`): (the ray parameter `t`, its weight
/// `1 / (n pdf(t)) = dtheta h (1 + tan^2 theta)`).
pub fn equiangular_sample(e: &Equiangular, x: f32) -> (f32, f32) {
    let tau = (e.theta_a + x * e.dtheta).tan();
    (
        e.t_close + e.dist * tau,
        e.dtheta * e.dist * (1.0 + tau * tau),
    )
}

/// 4-point Gauss-Legendre abscissae on [-1, 1] (ascending).
pub const GL4_X: [f32; 4] = [-0.861_136_3, -0.339_981_04, 0.339_981_04, 0.861_136_3];
/// 4-point Gauss-Legendre weights.
pub const GL4_W: [f32; 4] = [0.347_854_85, 0.652_145_15, 0.652_145_15, 0.347_854_85];

// WGSL built-ins, so the mirrors read like the shaders.

/// WGSL `max` on f32.
pub fn max(a: f32, b: f32) -> f32 {
    a.max(b)
}
/// WGSL `min` on f32.
pub fn min(a: f32, b: f32) -> f32 {
    a.min(b)
}
/// WGSL `max` on u32.
pub fn max_u(a: u32, b: u32) -> u32 {
    a.max(b)
}
/// WGSL `min` on u32.
pub fn min_u(a: u32, b: u32) -> u32 {
    a.min(b)
}
/// WGSL `clamp` on f32.
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    x.max(lo).min(hi)
}
/// WGSL `sqrt`.
pub fn sqrt(x: f32) -> f32 {
    x.sqrt()
}
/// WGSL `exp`.
pub fn exp(x: f32) -> f32 {
    x.exp()
}
/// WGSL `select(f, t, cond)`.
pub fn select(f: f32, t: f32, cond: bool) -> f32 {
    if cond { t } else { f }
}
/// WGSL `mix` on f32.
pub fn mix(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}
