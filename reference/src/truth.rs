//! Ground truth of the single-scattering model, accumulated in f64 and parallel over rows.
//!
//! Two truths differ only in the visibility term `V`:
//! - [`Visibility::Exact`]: a ray is cast from the sample point to the light;
//! - [`Visibility::ShadowMap`]: the same standard shadow map the methods get (nearest texel,
//!   biased; see [`crate::buffers`]), which isolates a method's own error from the shadow
//!   map's discretisation.
//!
//! Quadrature. The view ray `[0, s]` is cut into `segments` equal cells and `V` is sampled at
//! the cell centres. Between two centres whose visibility differs, the transition is located
//! by `bisections` halvings, so a lit interval's ends are exact to `s / (segments 2^b)`. The
//! smooth rest of the integrand is integrated exactly over each lit interval (directional:
//! closed form) or by 16-point Gauss-Legendre per 4 cells (spot). A feature thinner than a cell
//! that is crossed twice between two centres can be missed: the convergence test doubles
//! `segments` to show that this changes the result by far less than any method's error.
//!
//! Area lights ([`crate::scene::AreaLight`]). The `exact` truth integrates over the light's
//! surface as well: [`TruthSettings::light_samples`] points of the light (the midpoint rule
//! of [`crate::scene::AreaLight::quadrature`]), each a spot light with exact visibility whose
//! `1 / d^2` is softened to the disk of its cell (`NearField`), summed per view ray; the
//! convergence test (`reference/tests/area.rs`) doubles the points. The `vpl` truth ([`render_vpl`]) sums
//! the spot truths of the N virtual point lights a method uses, each looked up in its own
//! shadow map: it isolates a method's error from the VPL and shadow-map discretisation, as
//! the `shadow_map` truth does for a point light.

use crate::buffers::ShadowMapError;
use crate::buffers::{GBuffer, ShadowMap, camera_ray};
use crate::bvh::Bvh;
use crate::geometry::Ray;
use crate::image::Image;
use crate::model::RayIntegrand;
use crate::scene::{AreaLight, Light, Scene};
use glam::DVec3;
use rayon::prelude::*;

/// How the truth decides whether a point sees the light.
#[derive(Clone, Copy, Debug)]
pub enum Visibility<'a> {
    /// Unshadowed (V = 1): the closed-form part every method shares.
    None,
    /// Cast a ray to the light through the scene.
    Exact(&'a Bvh),
    /// Look up the given shadow map.
    ShadowMap(&'a ShadowMap),
}

/// Quadrature settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSettings {
    /// Equal cells per view ray.
    pub segments: usize,
    /// Bisection steps per visibility transition.
    pub bisections: u32,
    /// Points of an area light the `exact` truth integrates over (unused for other lights).
    pub light_samples: usize,
}

impl Default for TruthSettings {
    /// 1024 cells and 12 bisections: doubling the cells changes every suite image by less
    /// than 0.1 % rel L1 (the convergence test; the worst case is `foliage` looking towards
    /// the sun, whose leaf shadows are thinner than a cell of 256). An area light's
    /// surface: 1024 points, where doubling them changes every area-light suite image by
    /// less than 0.1 % rel L1 over the pixels that do not look at the lamp
    /// (`area_truth_is_converged_in_light_samples`).
    fn default() -> Self {
        TruthSettings {
            segments: 1024,
            bisections: 12,
            light_samples: 1024,
        }
    }
}

/// The point lights whose truths add up to `light`'s: an area light's
/// `settings.light_samples` quadrature points ([`crate::scene::AreaLight::quadrature`]), else
/// the light.
pub fn point_lights(light: &Light, settings: &TruthSettings) -> Vec<Light> {
    match light {
        Light::Area(a) => a.quadrature(settings.light_samples.max(1)),
        _ => vec![light.clone()],
    }
}

/// Distance a shadow ray starts away from its origin (metres).
const SHADOW_EPS: f64 = 1e-5;

/// Visibility of a world point from the scene's light (an area light: from its centre).
pub fn visibility(vis: &Visibility, light: &Light, p: DVec3) -> bool {
    match vis {
        Visibility::None => true,
        Visibility::ShadowMap(sm) => sm.visibility(p) > 0.5,
        Visibility::Exact(bvh) => match light {
            Light::Directional { direction, .. } => !bvh.occluded(
                &Ray::new(p, -direction.normalize()),
                SHADOW_EPS,
                f64::INFINITY,
            ),
            Light::Spot { position, .. } | Light::Area(AreaLight { position, .. }) => {
                let to = *position - p;
                let d = to.length();
                d <= SHADOW_EPS || !bvh.occluded(&Ray::new(p, to / d), SHADOW_EPS, d - SHADOW_EPS)
            }
        },
    }
}

/// In-scattered radiance along one view ray (`dir` unit) of length `s`, scalar (multiply by
/// `Light::color`; a spot's cookie is left out: [`ray_inscatter_rgb`] has it). An area
/// light's is the sum over its points ([`point_lights`]) per unit radiance.
pub fn ray_inscatter(
    scene: &Scene,
    vis: &Visibility,
    settings: &TruthSettings,
    origin: DVec3,
    dir: DVec3,
    s: f64,
) -> f64 {
    if let Light::Area(a) = &scene.light {
        let lights = point_lights(&scene.light, settings);
        let soft = NearField::of(&scene.light, settings);
        let per_radiance = a.shape.area() / lights.len().max(1) as f64 * a.faces() as f64;
        return per_radiance
            * lights
                .iter()
                .map(|l| ray_inscatter_point(scene, l, &soft, vis, settings, origin, dir, s))
                .sum::<f64>();
    }
    let point = NearField::default();
    ray_inscatter_point(scene, &scene.light, &point, vis, settings, origin, dir, s)
}

/// How the `exact` truth of an area light treats the light's neighbourhood: each quadrature
/// point stands for a disk of its cell's area ([`RayIntegrand::softened`]: the integrand over
/// the surface is bounded, a point's `1 / d^2` is not), and where a view ray passes within
/// twice the light's radius of its centre, the Gauss-Legendre pieces there are 8 disk radii
/// long (nodes half a radius apart). Not enough for the fog next to the emitting face: the
/// pixels whose ray ends on the lamp's housing converge slowly in the light's points (the
/// convergence test reports them apart). Nothing for other lights.
#[derive(Clone, Copy, Debug, Default)]
struct NearField {
    /// Squared disk radius (0: points).
    soft_r2: f64,
    /// The light's centre.
    centre: DVec3,
    /// Twice the light's radius (0: no refinement).
    reach: f64,
}

impl NearField {
    fn of(light: &Light, settings: &TruthSettings) -> NearField {
        match light {
            Light::Area(a) => NearField {
                soft_r2: soft_r2(light, settings),
                centre: a.position,
                reach: 2.0 * a.shape.radius(),
            },
            _ => NearField::default(),
        }
    }

    /// The refined window `[t0, t1]` of the ray and its piece length, if it passes near.
    fn window(&self, origin: DVec3, dir: DVec3, s: f64) -> Option<(f64, f64, f64)> {
        if self.reach <= 0.0 || self.soft_r2 <= 0.0 {
            return None;
        }
        let t = (self.centre - origin).dot(dir).clamp(0.0, s);
        let h = (origin + dir * t - self.centre).length();
        if h >= self.reach {
            return None;
        }
        let (t0, t1) = ((t - self.reach).max(0.0), (t + self.reach).min(s));
        (t1 > t0).then_some((t0, t1, 8.0 * self.soft_r2.sqrt()))
    }
}

/// `f.integrate_rgb(a, b, pieces)` with the part of `[a, b]` inside `window` (start, end,
/// piece length) integrated on pieces of at most that length.
fn integrate_refined(
    f: &RayIntegrand,
    a: f64,
    b: f64,
    pieces: usize,
    window: Option<(f64, f64, f64)>,
) -> [f64; 3] {
    let Some((t0, t1, len)) = window.filter(|w| w.0 < b && w.1 > a) else {
        return f.integrate_rgb(a, b, pieces);
    };
    let (lo, hi) = (t0.max(a), t1.min(b));
    let share = |x: f64, y: f64| ((pieces as f64 * (y - x) / (b - a)).ceil() as usize).max(1);
    let near = ((hi - lo) / len).ceil().max(1.0) as usize;
    let mut out = f.integrate_rgb(lo, hi, near);
    for (x, y) in [(a, lo), (hi, b)] {
        if y > x {
            let v = f.integrate_rgb(x, y, share(x, y));
            for k in 0..3 {
                out[k] += v[k];
            }
        }
    }
    out
}

/// The squared radius of the disk each quadrature point of an area light stands for
/// ([`RayIntegrand::softened`]): its cell's area over pi; 0 for any other light.
fn soft_r2(light: &Light, settings: &TruthSettings) -> f64 {
    match light {
        Light::Area(a) => {
            a.shape.area() / (settings.light_samples.max(1) as f64 * std::f64::consts::PI)
        }
        _ => 0.0,
    }
}

/// [`ray_inscatter`] for one point (or directional) light of the scene, with the area
/// light's near field `soft` of the point.
#[allow(
    clippy::too_many_arguments,
    reason = "one ray's integral: each argument is needed"
)]
fn ray_inscatter_point(
    scene: &Scene,
    light: &Light,
    soft: &NearField,
    vis: &Visibility,
    settings: &TruthSettings,
    origin: DVec3,
    dir: DVec3,
    s: f64,
) -> f64 {
    let f = RayIntegrand::new(origin, dir, light, &scene.medium).softened(soft.soft_r2);
    let window = soft.window(origin, dir, s);
    let peak = if soft.soft_r2 > 0.0 {
        None
    } else {
        PointPeak::of(light, settings, origin, dir, s)
    };
    let mut total = 0.0;
    lit_intervals(light, vis, settings, origin, dir, s, &mut |a, b, pieces| {
        total += match (window, peak) {
            (Some(_), _) => integrate_refined(&f, a, b, pieces, window)[0],
            (None, Some(p)) => p.integrate(&f, a, b, pieces),
            (None, None) => f.integrate(a, b, pieces),
        };
    });
    total
}

/// A point light's `1 / d^2` peak along a view ray that passes closer to it than the
/// Gauss-Legendre pieces are long: the peak is `h` wide (`d^2 = h^2 + (t - t_c)^2`, `h` the
/// ray's distance from the light at its closest approach `t_c`), and 16 nodes on a piece
/// many times longer miss it (a lamp pixel of `area_grate/epipole_on_screen`, whose rays pass
/// 2 cm from the VPLs, was 10 % off at 256 segments, converged 0.03 % at 16384). Near the
/// peak the integral is taken in the equiangular variable `t = t_c + h tan(u)`, where
/// `dt/du = d^2 / h` cancels the `1 / d^2` and what is left is smooth.
#[derive(Clone, Copy, Debug)]
struct PointPeak {
    /// Closest approach along the ray (unclamped).
    t_c: f64,
    /// Distance of the ray from the light there.
    h: f64,
    /// Half-width of the window integrated equiangularly.
    reach: f64,
}

impl PointPeak {
    /// Pieces of the equiangular window.
    const PIECES: usize = 32;

    fn of(
        light: &Light,
        settings: &TruthSettings,
        origin: DVec3,
        dir: DVec3,
        s: f64,
    ) -> Option<PointPeak> {
        let Light::Spot { position, .. } = light else {
            return None;
        };
        // The Gauss-Legendre piece length of `lit_intervals` (one rule per 4 cells).
        let piece = 4.0 * s / settings.segments.max(1) as f64;
        let t_c = (*position - origin).dot(dir);
        let h = (origin + dir * t_c - *position).length();
        (h < piece && h > 0.0).then_some(PointPeak {
            t_c,
            h,
            reach: 8.0 * piece,
        })
    }

    /// `f.integrate(a, b, pieces)`, the part of `[a, b]` within `reach` of `t_c` in the
    /// equiangular variable.
    fn integrate(&self, f: &RayIntegrand, a: f64, b: f64, pieces: usize) -> f64 {
        let (lo, hi) = (a.max(self.t_c - self.reach), b.min(self.t_c + self.reach));
        if hi <= lo {
            return f.integrate(a, b, pieces);
        }
        let share = |x: f64, y: f64| ((pieces as f64 * (y - x) / (b - a)).ceil() as usize).max(1);
        let mut out = 0.0;
        for (x, y) in [(a, lo), (hi, b)] {
            if y > x {
                out += f.integrate(x, y, share(x, y));
            }
        }
        let (u0, u1) = (
            ((lo - self.t_c) / self.h).atan(),
            ((hi - self.t_c) / self.h).atan(),
        );
        let step = (u1 - u0) / Self::PIECES as f64;
        for i in 0..Self::PIECES {
            let (x, y) = (u0 + step * i as f64, u0 + step * (i + 1) as f64);
            out += crate::model::gauss_legendre_16(
                |u| {
                    let t = self.t_c + self.h * u.tan();
                    let d2 = self.h * self.h + (t - self.t_c) * (t - self.t_c);
                    f.eval(t) * d2 / self.h
                },
                x,
                y,
            );
        }
        out
    }
}

/// In-scattered radiance (RGB) along one view ray (`dir` unit) of length `s`: the light's
/// colour and, for a spot with a cookie, the cookie per point (integrated per channel over
/// the same lit intervals as [`ray_inscatter`]). An area light's is the sum over its points
/// ([`point_lights`]).
pub fn ray_inscatter_rgb(
    scene: &Scene,
    vis: &Visibility,
    settings: &TruthSettings,
    origin: DVec3,
    dir: DVec3,
    s: f64,
) -> [f64; 3] {
    let soft = NearField::of(&scene.light, settings);
    if !matches!(scene.light, Light::Area(_)) {
        let one = std::slice::from_ref(&scene.light);
        return ray_inscatter_lights(scene, one, &soft, vis, settings, origin, dir, s);
    }
    let lights = point_lights(&scene.light, settings);
    ray_inscatter_lights(scene, &lights, &soft, vis, settings, origin, dir, s)
}

/// [`ray_inscatter_rgb`] summed over point lights of the scene (each with its own colour),
/// each with the area light's near field `soft`.
#[allow(
    clippy::too_many_arguments,
    reason = "one ray's integral: each argument is needed"
)]
fn ray_inscatter_lights(
    scene: &Scene,
    lights: &[Light],
    soft: &NearField,
    vis: &Visibility,
    settings: &TruthSettings,
    origin: DVec3,
    dir: DVec3,
    s: f64,
) -> [f64; 3] {
    let mut out = [0.0; 3];
    for light in lights {
        let color = light.color();
        let f = RayIntegrand::new(origin, dir, light, &scene.medium).softened(soft.soft_r2);
        if !f.has_cookie() {
            let l = ray_inscatter_point(scene, light, soft, vis, settings, origin, dir, s);
            for k in 0..3 {
                out[k] += color[k] * l;
            }
            continue;
        }
        let mut total = [0.0; 3];
        lit_intervals(light, vis, settings, origin, dir, s, &mut |a, b, pieces| {
            let v = f.integrate_rgb(a, b, pieces);
            for k in 0..3 {
                total[k] += v[k];
            }
        });
        for k in 0..3 {
            out[k] += color[k] * total[k];
        }
    }
    out
}

/// Calls `lit(a, b, pieces)` for every lit interval `[a, b]` of the view ray, in order, with
/// the Gauss-Legendre pieces for its smooth part (one per 4 cells).
fn lit_intervals(
    light: &Light,
    vis: &Visibility,
    settings: &TruthSettings,
    origin: DVec3,
    dir: DVec3,
    s: f64,
    lit: &mut dyn FnMut(f64, f64, usize),
) {
    let n = settings.segments.max(1);
    let h = s / n as f64;
    if let Visibility::None = vis {
        lit(0.0, s, n);
        return;
    }
    let v = |t: f64| visibility(vis, light, origin + dir * t);
    // Gauss-Legendre pieces for the smooth part (spot): one 16-point rule per 4 cells.
    let pieces = |a: f64, b: f64| ((b - a) / (4.0 * h)).ceil().max(1.0) as usize;
    let mut start = 0.0;
    let mut prev_t = 0.5 * h;
    let mut cur = v(prev_t);
    for i in 1..n {
        let t = (i as f64 + 0.5) * h;
        let vi = v(t);
        if vi != cur {
            let (mut lo, mut hi) = (prev_t, t);
            for _ in 0..settings.bisections {
                let mid = 0.5 * (lo + hi);
                if v(mid) == cur {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let b = 0.5 * (lo + hi);
            if cur {
                lit(start, b, pieces(start, b));
            }
            start = b;
            cur = vi;
        }
        prev_t = t;
    }
    if cur {
        lit(start, s, pieces(start, s));
    }
}

/// Renders the in-scattered radiance image (RGB) of a scene with the given visibility;
/// `on_row` is called once per finished row (for progress bars).
pub fn render(
    scene: &Scene,
    gbuf: &GBuffer,
    vis: &Visibility,
    settings: &TruthSettings,
    on_row: &(dyn Fn() + Sync),
) -> Image {
    let cam = &scene.camera;
    let frame = cam.frame();
    let (w, h) = (gbuf.width, gbuf.height);
    let lights = point_lights(&scene.light, settings);
    let soft = NearField::of(&scene.light, settings);
    let rows: Vec<Vec<[f32; 3]>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let row = (0..w)
                .map(|x| {
                    let i = (y * w + x) as usize;
                    let dir = camera_ray(scene, &frame, x, y);
                    let l = ray_inscatter_lights(
                        scene,
                        &lights,
                        &soft,
                        vis,
                        settings,
                        cam.position,
                        dir,
                        gbuf.ray_length[i],
                    );
                    l.map(|c| c as f32)
                })
                .collect();
            on_row();
            row
        })
        .collect();
    Image::from_pixels(w, h, rows.into_iter().flatten().collect())
}

/// The `vpl` truth of an area light: the sum of the spot truths of its `n` virtual point
/// lights ([`crate::scene::AreaLight::vpls`]; `2 n` when two-sided), each looked up in its
/// own `map_size`^2 shadow map ([`ShadowMap::vpl_maps`]: the maps an engine renders). For any other light, the
/// `shadow_map` truth with one map of that size.
///
/// # Errors
///
/// As [`ShadowMap::build`] (a cone of 80 degrees or wider has no single perspective map).
pub fn render_vpl(
    scene: &Scene,
    gbuf: &GBuffer,
    bvh: &Bvh,
    n: usize,
    map_size: u32,
    settings: &TruthSettings,
) -> Result<Image, ShadowMapError> {
    // Summed in f64: 2 n images of similar magnitude.
    let mut sum = vec![[0.0f64; 3]; (gbuf.width * gbuf.height) as usize];
    for (vpl, sm) in ShadowMap::vpl_maps(scene, bvh, n, map_size)? {
        let img = render(&vpl, gbuf, &Visibility::ShadowMap(&sm), settings, &|| ());
        for (acc, px) in sum.iter_mut().zip(&img.data) {
            for k in 0..3 {
                acc[k] += f64::from(px[k]);
            }
        }
    }
    let px = sum.into_iter().map(|c| c.map(|v| v as f32)).collect();
    Ok(Image::from_pixels(gbuf.width, gbuf.height, px))
}

/// Points of an area light the composites light surfaces with.
const SURFACE_LIGHT_SAMPLES: usize = 64;

/// Radiance reaching the eye from surfaces and sky, attenuated by the medium, for
/// composites: diffuse surfaces lit by the light (exact shadows; an area light by 64 of its
/// points) plus a uniform sky ambient.
pub fn surface_radiance(scene: &Scene, gbuf: &GBuffer, bvh: &Bvh) -> Image {
    let cam = &scene.camera;
    let frame = cam.frame();
    let lights = point_lights(
        &scene.light,
        &TruthSettings {
            light_samples: SURFACE_LIGHT_SAMPLES,
            ..TruthSettings::default()
        },
    );
    let sigma_t = scene.medium.sigma_t;
    let (w, h) = (gbuf.width, gbuf.height);
    let exact = Visibility::Exact(bvh);
    let px: Vec<[f32; 3]> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let i = i as usize;
            let s = gbuf.ray_length[i];
            let trans = (-sigma_t * s).exp();
            let shape = gbuf.shape[i];
            if shape == crate::buffers::SKY {
                return scene.sky.map(|c| (c * trans) as f32);
            }
            let dir = camera_ray(scene, &frame, x, y);
            let n = gbuf.normal[i];
            let p = cam.position + dir * s + n * 1e-4;
            let albedo = scene.geometry[shape as usize].albedo();
            let mut direct = [0.0f64; 3];
            for light in &lights {
                let [r, g, b] = direct_irradiance(&exact, light, p, n, sigma_t);
                direct[0] += r;
                direct[1] += g;
                direct[2] += b;
            }
            let mut out = [0f32; 3];
            for k in 0..3 {
                let diffuse = albedo[k] / std::f64::consts::PI * direct[k];
                let ambient = albedo[k] * scene.sky[k];
                out[k] = ((diffuse + ambient) * trans) as f32;
            }
            out
        })
        .collect();
    Image::from_pixels(w, h, px)
}

/// Irradiance (RGB) at surface point `p` with normal `n` from one point or directional light
/// (exact shadows, cone, cookie and extinction along the light path).
fn direct_irradiance(
    vis: &Visibility,
    light: &Light,
    p: DVec3,
    n: DVec3,
    sigma_t: f64,
) -> [f64; 3] {
    let color = light.color();
    let (to_light, l_in, tint) = match light {
        Light::Directional { direction, .. } => (-direction.normalize(), 1.0, [1.0; 3]),
        Light::Spot {
            position,
            direction,
            inner_angle_deg,
            outer_angle_deg,
            cookie,
            ..
        } => {
            let d = *position - p;
            let dist = d.length().max(1e-9);
            let cone = crate::model::cone_falloff(
                (-d / dist).dot(direction.normalize()),
                *inner_angle_deg,
                *outer_angle_deg,
            );
            let tint = cookie.as_ref().map_or([1.0; 3], |c| {
                c.sample_dir(
                    -d / dist,
                    &crate::buffers::light_basis(*direction),
                    outer_angle_deg.to_radians().tan(),
                )
            });
            (
                d / dist,
                cone * (-sigma_t * dist).exp() / (dist * dist),
                tint,
            )
        }
        // The composites' lights are points: an area light arrives as its points.
        Light::Area(_) => return [0.0; 3],
    };
    let cos = n.dot(to_light).max(0.0);
    let lit = if cos > 0.0 && visibility(vis, light, p) {
        1.0
    } else {
        0.0
    };
    [0, 1, 2].map(|k| color[k] * tint[k] * l_in * cos * lit)
}
