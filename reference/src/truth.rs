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

use crate::buffers::{GBuffer, ShadowMap, camera_ray};
use crate::bvh::Bvh;
use crate::geometry::Ray;
use crate::image::Image;
use crate::model::RayIntegrand;
use crate::scene::{Light, Scene};
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
}

impl Default for TruthSettings {
    /// 1024 cells and 12 bisections: doubling the cells changes every suite image by less
    /// than 0.1 % rel L1 (the convergence test; the worst case is `foliage` looking towards
    /// the sun, whose leaf shadows are thinner than a cell of 256).
    fn default() -> Self {
        TruthSettings {
            segments: 1024,
            bisections: 12,
        }
    }
}

/// Distance a shadow ray starts away from its origin (metres).
const SHADOW_EPS: f64 = 1e-5;

/// Visibility of a world point from the scene's light.
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
            Light::Spot { position, .. } => {
                let to = *position - p;
                let d = to.length();
                d <= SHADOW_EPS || !bvh.occluded(&Ray::new(p, to / d), SHADOW_EPS, d - SHADOW_EPS)
            }
        },
    }
}

/// In-scattered radiance along one view ray (`dir` unit) of length `s`, scalar (multiply by
/// `Light::color`; a spot's cookie is left out: [`ray_inscatter_rgb`] has it).
pub fn ray_inscatter(
    scene: &Scene,
    vis: &Visibility,
    settings: &TruthSettings,
    origin: DVec3,
    dir: DVec3,
    s: f64,
) -> f64 {
    let f = RayIntegrand::new(origin, dir, &scene.light, &scene.medium);
    let mut total = 0.0;
    lit_intervals(scene, vis, settings, origin, dir, s, &mut |a, b, pieces| {
        total += f.integrate(a, b, pieces);
    });
    total
}

/// In-scattered radiance (RGB) along one view ray (`dir` unit) of length `s`: the light's
/// colour and, for a spot with a cookie, the cookie per point (integrated per channel over
/// the same lit intervals as [`ray_inscatter`]).
pub fn ray_inscatter_rgb(
    scene: &Scene,
    vis: &Visibility,
    settings: &TruthSettings,
    origin: DVec3,
    dir: DVec3,
    s: f64,
) -> [f64; 3] {
    let color = scene.light.color();
    let f = RayIntegrand::new(origin, dir, &scene.light, &scene.medium);
    if !f.has_cookie() {
        let l = ray_inscatter(scene, vis, settings, origin, dir, s);
        return color.map(|c| c * l);
    }
    let mut total = [0.0; 3];
    lit_intervals(scene, vis, settings, origin, dir, s, &mut |a, b, pieces| {
        let v = f.integrate_rgb(a, b, pieces);
        for k in 0..3 {
            total[k] += v[k];
        }
    });
    [0, 1, 2].map(|k| color[k] * total[k])
}

/// Calls `lit(a, b, pieces)` for every lit interval `[a, b]` of the view ray, in order, with
/// the Gauss-Legendre pieces for its smooth part (one per 4 cells).
fn lit_intervals(
    scene: &Scene,
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
    let v = |t: f64| visibility(vis, &scene.light, origin + dir * t);
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
    let rows: Vec<Vec<[f32; 3]>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let row = (0..w)
                .map(|x| {
                    let i = (y * w + x) as usize;
                    let dir = camera_ray(scene, &frame, x, y);
                    let l = ray_inscatter_rgb(
                        scene,
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

/// Radiance reaching the eye from surfaces and sky, attenuated by the medium, for
/// composites: diffuse surfaces lit by the light (exact shadows) plus a uniform sky ambient.
pub fn surface_radiance(scene: &Scene, gbuf: &GBuffer, bvh: &Bvh) -> Image {
    let cam = &scene.camera;
    let frame = cam.frame();
    let color = scene.light.color();
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
            let (to_light, l_in, tint) = match &scene.light {
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
            };
            let cos = n.dot(to_light).max(0.0);
            let lit = if cos > 0.0 && visibility(&exact, &scene.light, p) {
                1.0
            } else {
                0.0
            };
            let albedo = scene.geometry[shape as usize].albedo();
            let mut out = [0f32; 3];
            for k in 0..3 {
                let direct =
                    albedo[k] / std::f64::consts::PI * color[k] * tint[k] * l_in * cos * lit;
                let ambient = albedo[k] * scene.sky[k];
                out[k] = ((direct + ambient) * trans) as f32;
            }
            out
        })
        .collect();
    Image::from_pixels(w, h, px)
}
