//! Imperfect voxelized shadow volumes (Wyman & Dai 2013) on the CPU: the `area_ivsv` method
//! for area lights, the reference its kernels will mirror (issue 17; no kernel yet).
//!
//! An area light is `N` virtual point lights ([`crate::scene::AreaLight::vpls`]), each a spot
//! with its own standard shadow map ([`ShadowMap::build`]). Per VPL:
//!
//! 1. **Epipolar space.** The axis `a` runs from the eye `E` to the VPL `L` (distance `D`).
//!    An epipolar plane is the angle `theta` about `a`; in it, an eye ray is its angle
//!    `alpha` from `a` at the eye, a light ray its angle `phi` from `-a` at the light. The
//!    grid has `alpha` bins on `[0, pi]` (x), `theta` bins on `[-pi, pi)` (y) and
//!    [`PHI_BITS`] = 128 `phi` bits on `[0, pi]` per texel (a `uvec4`).
//! 2. **Rectify.** Per `(theta, phi)` light ray (bin centres), the shadow map's first occluder
//!    along it (nearest texel, plus the reference's bias) gives the distance `s_occ`, the
//!    occluder point its eye angle `alpha_occ`, and bit `phi` is set in the first texel
//!    along `alpha` whose centre lies beyond it.
//! 3. **Extrude.** An OR prefix scan along `alpha`: along a light ray the eye angle grows
//!    from 0 (at the light) to `pi - phi` (at infinity), so every voxel past the occluder is
//!    shadowed. After the scan the bits are monotone along `alpha` (tested).
//! 4. **Gather.** A pixel's view ray is one `(alpha, theta)`; along it `phi` runs from 0 (the
//!    eye) to `phi_s` (the surface), `t = D sin(phi) / sin(alpha + phi)`. In `phi` the
//!    integrand is `g(phi) = f(t(phi)) dt/dphi`, and `dt/dphi = d^2 / (D sin alpha)` cancels
//!    the point light's `1 / d^2` (Sun et al.'s substitution): for an isotropic light without
//!    extinction or cone `g` is constant, which is why the paper averages the bits uniformly
//!    and multiplies by the analytic airlight ([`Weights::Uniform`]). With phase, extinction
//!    and a spot's cone `g` is not constant but smooth and bounded, and zero outside the
//!    `phi` interval where the ray is inside the cone (closed form: [`cone_support`]). The
//!    gather ([`Weights::Linear`]) evaluates `g` at the ends of `segments` equal pieces of
//!    that interval (clipped to `[0, phi_s]`), weights each bit by the linear interpolant at
//!    its centre times its width (the bit containing `phi_s` by its covered part) and sums
//!    the weights of the bits not set: per piece, `n A + B sum k` over the unset bits, which
//!    the kernel computes with masked popcounts. The two texels nearest in `theta` are both
//!    gathered and interpolated linearly (the paper's `theta` interpolation), never `alpha`.
//!
//! The sum over VPLs is the image; its truth is the `vpl` truth ([`crate::truth::render_vpl`])
//! with the same VPLs and shadow maps.

use crate::buffers::{GBuffer, ShadowMap, ShadowMapError, camera_ray};
use crate::bvh::Bvh;
use crate::image::Image;
use crate::model::RayIntegrand;
use crate::scene::{Light, Scene};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// `phi` bits per texel (a `uvec4`).
pub const PHI_BITS: u32 = 128;

/// How the gather weights the `phi` bits of a texel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weights {
    /// The paper's: every bit the same weight, times the ray's unshadowed integral (exact
    /// only where the integrand is uniform in `phi`: an isotropic point light without
    /// extinction or cone).
    Uniform,
    /// Each bit weighted by the integrand in `phi`, evaluated at the boundaries of this many
    /// equal segments of the 128 bits (a power of two up to 128) and linear between them.
    Linear(u32),
}

/// The method's knobs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IvsvSettings {
    /// Virtual point lights per face of the light.
    pub vpls: usize,
    /// Shadow map size per VPL (texels per side).
    pub map_size: u32,
    /// `alpha` bins (texels along a row).
    pub alpha: u32,
    /// `theta` bins (rows).
    pub theta: u32,
    /// How the bits are weighted in the gather.
    pub weights: Weights,
}

impl Default for IvsvSettings {
    /// 64 VPLs ("at least 64 VPLs" against banding) with the paper's 128^2 shadow maps and
    /// 128 `phi` bits, 256 x 256 `alpha` x `theta` texels (the paper's 128^2 measured up to
    /// 5.0 % rel RMSE against the `vpl` truth on `area_columns/light_behind`, 256^2 1.8 %),
    /// the integrand in `phi` at 9 knots (8 segments: 0.20-1.94 % rel RMSE against the `vpl`
    /// truth on 11 of the 12 area poses, 16 VPLs, 48x27, where every bit at its own knot,
    /// 128 segments, measured 0.10-1.95 %; 4 segments up to 12.7 %: the `weights_sweep`
    /// test).
    fn default() -> Self {
        IvsvSettings {
            vpls: 64,
            map_size: 128,
            alpha: 256,
            theta: 256,
            weights: Weights::Linear(8),
        }
    }
}

/// Why the method cannot run.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum IvsvError {
    /// A knob out of range.
    #[error("area_ivsv: {0}")]
    Settings(String),
    /// A VPL's shadow map cannot be built.
    #[error("area_ivsv: {0}")]
    ShadowMap(#[from] ShadowMapError),
}

impl IvsvSettings {
    /// Checks every knob; the error names it.
    pub fn validate(&self) -> Result<(), IvsvError> {
        let bad = |m: String| Err(IvsvError::Settings(m));
        if self.vpls == 0 {
            return bad("vpls must be at least 1, got 0".into());
        }
        if self.alpha < 2 || self.theta < 2 {
            return bad(format!(
                "alpha and theta must be at least 2 bins, got {} x {}",
                self.alpha, self.theta
            ));
        }
        if let Weights::Linear(m) = self.weights
            && !(m.is_power_of_two() && m <= PHI_BITS)
        {
            return bad(format!(
                "weights: segments must be a power of two in [1, {PHI_BITS}], got {m}"
            ));
        }
        Ok(())
    }
}

/// One VPL's epipolar voxel grid.
#[derive(Clone, Debug)]
pub struct EpipolarGrid {
    /// The eye.
    pub eye: DVec3,
    /// The VPL.
    pub light: DVec3,
    /// Unit axis from the eye to the light.
    pub axis: DVec3,
    /// Unit vectors spanning the plane normal to the axis (`theta = 0` and `pi / 2`).
    pub basis: [DVec3; 2],
    /// Eye-light distance.
    pub distance: f64,
    /// `alpha` bins.
    pub alpha: u32,
    /// `theta` bins.
    pub theta: u32,
    /// The `alpha` range the bins cover (the screen's: [`EpipolarGrid::fit`]).
    pub alpha_range: (f64, f64),
    /// The `phi` range the bits cover, from 0 (`pi - ` the smallest `alpha` on screen).
    pub phi_max: f64,
    /// Texels, row-major (`theta` rows of `alpha` texels), 128 bits each (bit `k` of word
    /// `k / 32`).
    pub bits: Vec<[u32; 4]>,
}

/// Angle in [0, pi] between two unit vectors, robust near 0 and pi.
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

impl EpipolarGrid {
    /// An empty grid for the eye and a VPL (the caller ensures they differ).
    pub fn new(eye: DVec3, light: DVec3, alpha: u32, theta: u32) -> EpipolarGrid {
        let d = light - eye;
        let distance = d.length().max(1e-12);
        let axis = d / distance;
        let helper = if axis.y.abs() < 0.99 {
            DVec3::Y
        } else {
            DVec3::X
        };
        let b1 = axis.cross(helper).normalize();
        let b2 = axis.cross(b1);
        EpipolarGrid {
            eye,
            light,
            axis,
            basis: [b1, b2],
            distance,
            alpha,
            theta,
            alpha_range: (0.0, PI),
            phi_max: PI,
            bits: vec![[0; 4]; (alpha * theta) as usize],
        }
    }

    /// Fits the `alpha` and `phi` ranges to the eye rays of `scene`'s screen (the paper's
    /// remark that an off-screen light uses a small part of epipolar space): `alpha` from its
    /// smallest to its largest value over the screen (0 when the light projects inside it,
    /// `pi` when the point opposite does; else the extremes lie on its border, sampled at 64
    /// points per edge, widened by one bin), and `phi` on `[0, pi - alpha_min]`, the light
    /// angles those rays reach.
    pub fn fit(&mut self, scene: &Scene) {
        let cam = &scene.camera;
        let frame = cam.frame();
        let (w, h) = (f64::from(cam.width), f64::from(cam.height));
        let on_screen = |d: DVec3| {
            cam.project_direction(&frame, d)
                .is_some_and(|(x, y)| (0.0..=w).contains(&x) && (0.0..=h).contains(&y))
        };
        let (mut lo, mut hi) = (PI, 0.0f64);
        for k in 0..=64 {
            let f = f64::from(k) / 64.0;
            for (x, y) in [(f * w, 0.0), (f * w, h), (0.0, f * h), (w, f * h)] {
                let a = angle(cam.ray_dir(&frame, x, y), self.axis);
                lo = lo.min(a);
                hi = hi.max(a);
            }
        }
        if on_screen(self.axis) {
            lo = 0.0;
        }
        if on_screen(-self.axis) {
            hi = PI;
        }
        let pad = (hi - lo) / f64::from(self.alpha);
        self.alpha_range = ((lo - pad).max(0.0), (hi + pad).min(PI));
        self.phi_max = (PI - self.alpha_range.0).max(1e-6);
    }

    /// Width of an `alpha` bin.
    pub fn d_alpha(&self) -> f64 {
        (self.alpha_range.1 - self.alpha_range.0) / f64::from(self.alpha)
    }

    /// Width of a `phi` bit.
    pub fn d_phi(&self) -> f64 {
        self.phi_max / f64::from(PHI_BITS)
    }

    /// The `alpha` bin of an eye angle (clamped to the grid).
    pub fn alpha_bin(&self, alpha: f64) -> u32 {
        let x = (alpha - self.alpha_range.0) / self.d_alpha();
        (x.max(0.0) as u32).min(self.alpha - 1)
    }

    /// The centre of `alpha` bin `i`.
    pub fn alpha_centre(&self, i: u32) -> f64 {
        self.alpha_range.0 + (f64::from(i) + 0.5) * self.d_alpha()
    }

    /// Width of a `theta` bin.
    pub fn d_theta(&self) -> f64 {
        2.0 * PI / f64::from(self.theta)
    }

    /// `(alpha, theta)` of a world direction from the eye.
    pub fn eye_angles(&self, dir: DVec3) -> (f64, f64) {
        let dir = dir.normalize();
        let t = dir.dot(self.basis[1]).atan2(dir.dot(self.basis[0]));
        (angle(dir, self.axis), t)
    }

    /// The unit direction in plane `theta` at angle `angle` from `from` (the axis or its
    /// opposite).
    fn in_plane(&self, from: DVec3, angle: f64, theta: f64) -> DVec3 {
        let (st, ct) = theta.sin_cos();
        let (sa, ca) = angle.sin_cos();
        from * ca + (self.basis[0] * ct + self.basis[1] * st) * sa
    }

    /// The light ray of `(theta, phi)`: its unit direction from the VPL.
    pub fn light_dir(&self, theta: f64, phi: f64) -> DVec3 {
        self.in_plane(-self.axis, phi, theta)
    }

    /// The eye ray of `(alpha, theta)`: its unit direction from the eye.
    pub fn eye_dir(&self, alpha: f64, theta: f64) -> DVec3 {
        self.in_plane(self.axis, alpha, theta)
    }

    /// Bit `k` of texel `(i, j)`.
    pub fn bit(&self, i: u32, j: u32, k: u32) -> bool {
        let w = self.bits[(j * self.alpha + i) as usize][(k / 32) as usize];
        (w >> (k % 32)) & 1 == 1
    }

    fn set(&mut self, i: u32, j: u32, k: u32) {
        self.bits[(j * self.alpha + i) as usize][(k / 32) as usize] |= 1 << (k % 32);
    }

    /// Step 2: sets, per `(theta, phi)` light ray, the bit of the first texel along `alpha`
    /// whose centre lies beyond the ray's first occluder in `sm` (the VPL's map).
    pub fn rectify(&mut self, sm: &ShadowMap) {
        let d_phi = self.d_phi();
        let forward = sm.basis[2];
        for j in 0..self.theta {
            let theta = -PI + (f64::from(j) + 0.5) * self.d_theta();
            for k in 0..PHI_BITS {
                let phi = (f64::from(k) + 0.5) * d_phi;
                let u = self.light_dir(theta, phi);
                if let Some(alpha_occ) = self.occluder_alpha(sm, u, forward) {
                    // First bin whose centre exceeds alpha_occ.
                    let x = (alpha_occ - self.alpha_range.0) / self.d_alpha();
                    let first = (x - 0.5).floor() + 1.0;
                    if first < f64::from(self.alpha) {
                        self.set(first.max(0.0) as u32, j, k);
                    }
                }
            }
        }
    }

    /// The eye angle of the first occluder along the light ray `u` (`None` when the ray
    /// leaves the map or meets nothing): the nearest texel's depth plus the reference's
    /// bias, as the `vpl` truth's lookups.
    fn occluder_alpha(&self, sm: &ShadowMap, u: DVec3, forward: DVec3) -> Option<f64> {
        let cos = u.dot(forward);
        if cos <= 1e-9 {
            return None;
        }
        let c = sm.coord(self.light + u)?;
        let stored = f64::from(sm.texel(c.u, c.v));
        if stored >= 1.0 {
            return None;
        }
        let z = sm.near + stored * (sm.far - sm.near);
        let s = (z + sm.bias_world(z)) / cos;
        let p = self.light + u * s;
        Some(angle((p - self.eye).normalize(), self.axis))
    }

    /// Step 3: the OR prefix scan along `alpha`, row by row.
    pub fn scan(&mut self) {
        for j in 0..self.theta {
            let row = (j * self.alpha) as usize;
            for i in 1..self.alpha as usize {
                let prev = self.bits[row + i - 1];
                for (w, p) in self.bits[row + i].iter_mut().zip(prev) {
                    *w |= p;
                }
            }
        }
    }

    /// `phi` of the point at distance `t` along the eye ray of angle `alpha`.
    pub fn phi_at(&self, alpha: f64, t: f64) -> f64 {
        // The triangle eye - light - point: the angle at the light.
        let (sa, ca) = alpha.sin_cos();
        (t * sa).atan2(self.distance - t * ca)
    }

    /// `t` of the eye-ray point of angle `alpha` at light angle `phi < pi - alpha`.
    pub fn t_at(&self, alpha: f64, phi: f64) -> f64 {
        self.distance * phi.sin() / (alpha + phi).sin().max(1e-300)
    }
}

/// The light angles `[lo, hi]` where the eye ray of `(alpha, theta)` is inside the VPL's
/// outer cone (axis `spot_axis`, `cos_outer`), clipped to `[0, phi_s]`; `None` when it never
/// is. Along the ray the light direction is `u(phi) = -a cos(phi) + e sin(phi)` (`a` the
/// eye-light axis, `e` the plane's unit normal to it), so `u . spot_axis = R cos(phi - phi0)`
/// and the cone `u . spot_axis >= cos_outer` is `|phi - phi0| <= acos(cos_outer / R)`.
pub fn cone_support(
    grid: &EpipolarGrid,
    theta: f64,
    spot_axis: DVec3,
    cos_outer: f64,
    phi_s: f64,
) -> Option<(f64, f64)> {
    let e = grid.basis[0] * theta.cos() + grid.basis[1] * theta.sin();
    let (c, s) = (-grid.axis.dot(spot_axis), e.dot(spot_axis));
    let r = c.hypot(s);
    if r <= cos_outer {
        return None;
    }
    let mut phi0 = s.atan2(c);
    if phi0 < -0.5 * PI {
        phi0 += 2.0 * PI;
    }
    let delta = (cos_outer / r).clamp(-1.0, 1.0).acos();
    let (lo, hi) = ((phi0 - delta).max(0.0), (phi0 + delta).min(phi_s));
    (lo < hi).then_some((lo, hi))
}

/// The per-bit weights of one eye ray (step 4): bit `k`'s share of the ray's unshadowed
/// integral, `w_k ~ integral over the bit's phi range (up to phi_s) of g(phi)`, where
/// `g(phi) = f(t(phi)) dt/dphi` is the integrand in the light angle. With
/// `t = D sin(phi) / sin(alpha + phi)` and `d = D sin(alpha) / sin(alpha + phi)` (the law of
/// sines in the triangle eye - light - point), `dt/dphi / d^2 = 1 / (D sin alpha)`: the
/// `1 / d^2` of a point light cancels (Sun et al.'s substitution) and `g` is bounded; what is
/// left is the phase (`cos = cos(alpha + phi)`), the extinction and the cone, which is zero
/// outside `[lo, hi]` ([`cone_support`]). [`Weights::Linear`] evaluates `g` at the ends of
/// `segments` equal pieces of `[lo, hi]`, linear between them, and gives each bit the value
/// at its centre (of its part below `phi_s`) times its width there. [`Weights::Uniform`] is
/// the paper's: every bit the same weight, the total the ray's unshadowed integral (128
/// pieces).
fn bit_weights(
    grid: &EpipolarGrid,
    f: &RayIntegrand,
    alpha: f64,
    support: Option<(f64, f64)>,
    phi_s: f64,
    weights: Weights,
) -> [f64; PHI_BITS as usize] {
    let mut w = [0.0; PHI_BITS as usize];
    let Some((lo, hi)) = support else {
        return w;
    };
    let d_phi = grid.d_phi();
    let (sa, d) = (alpha.sin(), grid.distance);
    let g = |phi: f64| {
        let s = (alpha + phi).sin();
        if s <= 0.0 {
            return 0.0;
        }
        f.eval(grid.t_at(alpha, phi)) * d * sa / (s * s)
    };
    let segments = match weights {
        Weights::Uniform => PHI_BITS,
        Weights::Linear(m) => m,
    };
    let step = (hi - lo) / f64::from(segments);
    let knots: Vec<f64> = (0..=segments)
        .map(|m| g(lo + step * f64::from(m)))
        .collect();
    let g_lin = |phi: f64| {
        if phi < lo || phi > hi || step <= 0.0 {
            return 0.0;
        }
        let x = ((phi - lo) / step).min(f64::from(segments));
        let m = (x.floor() as usize).min(segments as usize - 1);
        let t = x - m as f64;
        knots[m] + (knots[m + 1] - knots[m]) * t
    };
    for (k, wk) in w.iter_mut().enumerate() {
        let a = k as f64 * d_phi;
        if a >= phi_s {
            break;
        }
        let b = (a + d_phi).min(phi_s);
        *wk = (b - a) * g_lin(0.5 * (a + b));
    }
    if weights == Weights::Uniform {
        let total: f64 = w.iter().sum();
        let covered = phi_s / d_phi;
        for (k, wk) in w.iter_mut().enumerate() {
            *wk = total * ((phi_s - k as f64 * d_phi) / d_phi).clamp(0.0, 1.0) / covered;
        }
    }
    w
}

/// The lit part of the ray's integral over texel `(i, j)`: the weights of its unset bits.
fn gather_texel(grid: &EpipolarGrid, w: &[f64; PHI_BITS as usize], i: u32, j: u32) -> f64 {
    (0..PHI_BITS)
        .filter(|&k| !grid.bit(i, j, k))
        .map(|k| w[k as usize])
        .sum()
}

/// The method's in-scattered radiance for one VPL scene at one pixel ray.
fn gather(grid: &EpipolarGrid, scene: &Scene, dir: DVec3, s: f64, weights: Weights) -> f64 {
    let (alpha, theta) = grid.eye_angles(dir);
    let alpha = alpha.clamp(1e-9, PI - 1e-9);
    let phi_s = grid.phi_at(alpha, s).min(PI - alpha).min(grid.phi_max);
    let f = RayIntegrand::new(grid.eye, dir, &scene.light, &scene.medium);
    let support = match scene.light {
        Light::Spot {
            direction,
            outer_angle_deg,
            ..
        } => cone_support(
            grid,
            theta,
            direction.normalize(),
            outer_angle_deg.to_radians().cos(),
            phi_s,
        ),
        _ => Some((0.0, phi_s)),
    };
    let w = bit_weights(grid, &f, alpha, support, phi_s, weights);
    let i = grid.alpha_bin(alpha);
    // Linear in theta between the two nearest rows (the grid wraps around).
    let x = (theta + PI) / grid.d_theta() - 0.5;
    let j0 = x.floor();
    let t = x - j0;
    let row = |j: f64| (j.rem_euclid(f64::from(grid.theta))) as u32;
    let (a, b) = (row(j0), row(j0 + 1.0));
    (1.0 - t) * gather_texel(grid, &w, i, a) + t * gather_texel(grid, &w, i, b)
}

/// Renders an area-light scene with the method (RGB: each VPL's colour); a spot is rendered
/// as its one VPL.
///
/// # Errors
///
/// A knob out of range, a directional light, or a VPL whose shadow map cannot be built.
pub fn render(
    scene: &Scene,
    gbuf: &GBuffer,
    bvh: &Bvh,
    settings: &IvsvSettings,
) -> Result<Image, IvsvError> {
    settings.validate()?;
    let cam = &scene.camera;
    let frame = cam.frame();
    let (w, h) = (gbuf.width, gbuf.height);
    let mut sum = vec![[0.0f64; 3]; (w * h) as usize];
    for (vpl, sm) in ShadowMap::vpl_maps(scene, bvh, settings.vpls, settings.map_size)? {
        let Light::Spot {
            position,
            intensity,
            ..
        } = &vpl.light
        else {
            return Err(IvsvError::Settings(format!(
                "{}: the light must be an area light or a spot",
                scene.name
            )));
        };
        let mut grid = EpipolarGrid::new(cam.position, *position, settings.alpha, settings.theta);
        grid.fit(&vpl);
        grid.rectify(&sm);
        grid.scan();
        let px: Vec<f64> = (0..w * h)
            .into_par_iter()
            .map(|p| {
                let dir = camera_ray(&vpl, &frame, p % w, p / w);
                gather(
                    &grid,
                    &vpl,
                    dir,
                    gbuf.ray_length[p as usize],
                    settings.weights,
                )
            })
            .collect();
        for (acc, l) in sum.iter_mut().zip(px) {
            for k in 0..3 {
                acc[k] += intensity[k] * l;
            }
        }
    }
    let data = sum.into_iter().map(|c| c.map(|v| v as f32)).collect();
    Ok(Image::from_pixels(w, h, data))
}
