//! The engine's side of projective rectification (Klehm et al. 2014 Sec. 4.2), standing in
//! for its rasteriser: [`rasterise_rectified`] ray casts the rectified depth map through the
//! per-region matrices of [`ProjectiveMaps`] exactly as a rasteriser would sample them
//! (texel centres, depth test LESS, cleared to 1, depth clamping on).
//!
//! Nothing here uses the kernels' own formulas for the map: texel centres are unprojected
//! through the inverse matrices and hit points projected through the matrices, so a
//! kernel that disagrees with the matrices shows up in the conformance tests.

use crate::bvh::Bvh;
use crate::geometry::Ray;
use glam::{DVec3, DVec4};
use rayon::prelude::*;
use scatter_shaderlib::prefiltered::{LightDesc, ProjectiveMaps};

/// Clip-space `z / w` of world point `p` under `m`, or `None` behind the projection centre.
fn clip_depth(m: &glam::DMat4, p: DVec3) -> Option<f64> {
    let c = *m * p.extend(1.0);
    (c.w > 0.0).then(|| c.z / c.w)
}

/// Unprojects clip-space `(x, y, z)` (w = 1) through `inv`.
fn unproject(inv: &glam::DMat4, x: f64, y: f64, z: f64) -> DVec3 {
    let h: DVec4 = *inv * DVec4::new(x, y, z, 1.0);
    h.truncate() / h.w
}

/// The rectified depth map (`width x height`, row-major from the top-left texel) the engine
/// would rasterise with `maps` for the scene in `bvh` lit by `light`: per texel the
/// smallest clip depth of the occluders on its light ray, clamped to [0, 1], 1 where there
/// is none. `reach` bounds the scene (world units): a directional light ray is cast from
/// `reach` beyond the texel's first unprojected point, towards the scene.
pub fn rasterise_rectified(
    bvh: &Bvh,
    light: &LightDesc,
    maps: &ProjectiveMaps,
    width: u32,
    height: u32,
    reach: f64,
) -> Vec<f32> {
    let mut out = vec![1.0f32; width as usize * height as usize];
    for (m, &[first, count]) in maps.matrices.iter().zip(&maps.viewports) {
        let inv = m.inverse();
        let cells: Vec<(u32, u32, f32)> = (0..height)
            .into_par_iter()
            .flat_map_iter(|row| {
                (first..first + count).map(move |col| {
                    let x = -1.0 + 2.0 * (f64::from(col - first) + 0.5) / f64::from(count);
                    let y = 1.0 - 2.0 * (f64::from(row) + 0.5) / f64::from(height);
                    let p0 = unproject(&inv, x, y, 0.0);
                    let p1 = unproject(&inv, x, y, 1.0);
                    let ray = match *light {
                        LightDesc::Directional { direction, .. } => {
                            let l = direction.normalize();
                            Ray::new(p0 - l * reach, l)
                        }
                        // An area light's projective map is its point limit's.
                        LightDesc::Spot { position, .. }
                        | LightDesc::Area(scatter_shaderlib::area_ivsv::AreaLightDesc {
                            position,
                            ..
                        }) => {
                            // Both unprojected points lie on the texel's line through the
                            // lamp (maybe on its far side); the light ray leaves the lamp
                            // towards the frustum's side, where clip w (the distance along
                            // the bisectrix) grows.
                            let mut v = (p1 - p0).normalize();
                            if (*m * v.extend(0.0)).w < 0.0 {
                                v = -v;
                            }
                            Ray::new(position, v)
                        }
                    };
                    let depth = bvh
                        .closest(&ray, 0.0, f64::INFINITY)
                        .and_then(|hit| clip_depth(m, ray.at(hit.t)))
                        .map_or(1.0, |z| z.clamp(0.0, 1.0) as f32);
                    (col, row, depth)
                })
            })
            .collect();
        for (col, row, depth) in cells {
            out[(row * width + col) as usize] = depth;
        }
    }
    out
}
