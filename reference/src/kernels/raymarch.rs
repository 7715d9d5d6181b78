//! CPU mirror of `shaderlib/templates/raymarch.wgsl`: brute-force ray marching through the
//! standard shadow map, optionally one interleaving class per pixel (Tóth & Umenhoffer
//! 2009); a spot light's samples are equiangular (Kulla & Fajardo 2012). Conventions:
//! `scatter_frame::raymarch`.

use super::common_cookie::spot_cookie;
use super::common_model::{
    equiangular, equiangular_sample, max, min, phase_hg, spot_integrand, transmittance_between,
};
use super::common_raymarch::{pixel_jitter, raymarch_pixel_dir, raymarch_shadow_view};
use super::common_sampling::{
    EpipolarCamera, EpipolarSamples, SampledOutput, epipolar_samples, run_sampled,
};
use super::common_shadow::shadow_visibility_for;
use super::texture::{Tex, TexArray, quantise, xyz};
use glam::Vec3;
use scatter_shaderlib::prefiltered::{LightKind, Storage};
use scatter_shaderlib::raymarch::{RaymarchUniforms, RaymarchVariant};

/// The kernel body for pixel `id`; returns the texel it stores (radiance, or the partial
/// sum of an interleaved variant), before the storage format's rounding.
pub fn raymarch_main(
    id: [u32; 3],
    variant: &RaymarchVariant,
    m: &RaymarchUniforms,
    depth: &Tex,
    shadow_map: &Tex,
    cookie: Option<&TexArray>,
) -> Option<[f32; 4]> {
    let (x, y) = (id[0], id[1]);
    if x >= m.sizes[0] || y >= m.sizes[1] {
        return None;
    }
    let spot = variant.light == LightKind::Spot;
    let eye = xyz(m.eye);
    let dir = raymarch_pixel_dir(m, x, y);
    // Depth is clamped to [0, far]: engines with an infinite far plane write +inf on sky pixels.
    let s = min(max(depth.load(x, y), 0.0), m.eye[3]) / max(dir.dot(xyz(m.cam_forward)), 1e-6);
    let n = m.sizes[3];
    let h = s / n as f32;
    let mx = m.interleave[0];
    let my = m.interleave[1];
    let stride = mx * my;
    let pixel_class = (x % mx) + mx * (y % my);
    let mut u = 0.5;
    if m.interleave[2] != 0 {
        u = pixel_jitter(x, y);
    }
    let view = raymarch_shadow_view(m);
    let strata = equiangular(eye, dir, xyz(m.light_pos), 0.0, s, n);
    let mut sum = Vec3::ZERO;
    let mut j = pixel_class;
    while j < n {
        let mut t = (j as f32 + u) * h;
        let mut w = h;
        if spot {
            let tw = equiangular_sample(&strata, j as f32 + u);
            t = tw.0;
            w = tw.1;
        }
        let v = shadow_visibility_for(&view, shadow_map, eye + dir * t, spot);
        if spot {
            let f = v
                * w
                * spot_integrand(
                    eye,
                    dir,
                    t,
                    xyz(m.light_pos),
                    xyz(m.light_dir),
                    m.light_pos[3],
                    m.light_dir[3],
                    m.medium,
                );
            sum += match cookie {
                Some(cookie) => {
                    f * spot_cookie(
                        cookie,
                        eye + dir * t,
                        xyz(m.light_pos),
                        xyz(m.sm_right),
                        xyz(m.sm_up),
                        xyz(m.sm_forward),
                        m.light_dir[3],
                    )
                }
                None => Vec3::splat(f),
            };
        } else {
            sum += Vec3::splat(
                v * transmittance_between(m.medium[0], j as f32 * h, (j + 1) as f32 * h),
            );
        }
        j += stride;
    }
    let mut l = sum;
    if !spot {
        l = m.medium[1] * phase_hg(m.medium[2], -xyz(m.light_dir).dot(dir)) * sum;
    }
    let c = xyz(m.light_color) * l;
    Some([c.x, c.y, c.z, 1.0])
}

/// Runs every pixel (rows in parallel): radiance as stored in rgba16float, or the partial
/// sums (rgba32float) of an interleaved variant; a sampled variant through
/// [`raymarch_sampled`].
pub fn raymarch(
    variant: &RaymarchVariant,
    m: &RaymarchUniforms,
    depth: &Tex,
    shadow_map: &Tex,
    cookie: Option<&TexArray>,
) -> TexArray {
    use rayon::prelude::*;
    if !variant.interleaved() {
        return raymarch_sampled(variant, m, depth, shadow_map, cookie).output;
    }
    let (w, h) = (m.sizes[0], m.sizes[1]);
    let data = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..w).map(move |x| {
                raymarch_main([x, y, 0], variant, m, depth, shadow_map, cookie)
                    .unwrap_or([0.0; 4])
                    .map(|c| quantise(c, Storage::Rgba32float))
            })
        })
        .collect();
    TexArray {
        width: w,
        height: h,
        layers: 1,
        data,
    }
}

/// A variant without interleaving through its sampling (every pixel, or `lowres` with its
/// upsample): [`run_sampled`] with [`raymarch_main`] as the pixel body.
pub fn raymarch_sampled(
    variant: &RaymarchVariant,
    m: &RaymarchUniforms,
    depth: &Tex,
    shadow_map: &Tex,
    cookie: Option<&TexArray>,
) -> SampledOutput {
    run_sampled(
        &variant.sampling_knobs(),
        [m.sizes[0], m.sizes[1]],
        depth,
        &EpipolarCamera::of_raymarch(m, variant.light),
        &|x, y| {
            let c =
                raymarch_main([x, y, 0], variant, m, depth, shadow_map, cookie).unwrap_or([0.0; 4]);
            [c[0], c[1], c[2]]
        },
    )
}

/// `raymarch` of an `epipolar` variant: the samples of every slice (sampling pass 1).
pub fn raymarch_epipolar_samples(
    variant: &RaymarchVariant,
    m: &RaymarchUniforms,
    depth: &Tex,
    shadow_map: &Tex,
    cookie: Option<&TexArray>,
) -> EpipolarSamples {
    epipolar_samples(
        &variant.sampling_knobs(),
        [m.sizes[0], m.sizes[1]],
        depth,
        &EpipolarCamera::of_raymarch(m, variant.light),
        &|x, y| {
            let c =
                raymarch_main([x, y, 0], variant, m, depth, shadow_map, cookie).unwrap_or([0.0; 4]);
            [c[0], c[1], c[2]]
        },
    )
}
