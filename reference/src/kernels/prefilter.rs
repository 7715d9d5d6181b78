//! CPU mirror of `shaderlib/templates/prefilter.wgsl`: the Fourier basis transform (or the
//! power moments of the depth, `basis = moments`: one thread per row-region, stored as they
//! are) fused with the weighted running mean along each rectified row (Klehm et al. 2014
//! Listings 1-3, Table 1's regions and bases per thread).
//!
//! One invocation per (row, region, thread): thread `t` of a row-region filters the
//! `bases_per_thread` bases of layers `t * bpt / 4 ..`. Each region restarts the running mean.
//! Stored per texel: the normalised weighted mean `F_k = sum w_i B_k(d_i) / sum w_i` over the
//! region up to the texel (with `filtered_stride = k > 1` only at every k-th texel's right
//! edge, into stored column `i / k`; regions start on multiples of k), mapped to [0, 1] as `F / 2 + 0.5` in the variant's storage format.
//! `scatter` weights each region by the pixel's own unshadowed integral over the part of its
//! ray inside the region, so no weight sums need to be stored. Thread 0 of a row-region also
//! stores the least and the greatest depth over the region up to the texel (`bounds`,
//! rg32float on the GPU; here a one-layer array of `[min, max, 0, 0]`).
//!
//! The GPU's `filtered` is a storage buffer (`include/prefiltered_buffers.wgsl`: element
//! `(layer * Wr + x) * Hr + row`, rgba32float `(layer * Hr + row) * Wr + x`, each the bits of
//! one storage-format texel, packed with the rounding a texture store of that format does);
//! here it is the layer-major [`TexArray`] the runtime's readback reorders it into, and
//! `store` quantises as the packing does.
//!
//! With a cookie (`cookie = true`, see the WGSL comment) each texel's light ray carries the
//! cookie `C_i` ([`texel_cookie`]): per channel `c` the running means of `C_i^c` times the
//! basis in layers `c * layers + q`, and thread 0 the region's mean cookie in layer
//! `3 * layers`.

use super::common_cookie::frame_cookie;
use super::common_epipolar::{row_phi, slice_e};
use super::common_model::PI;
use super::common_model::select;
use super::common_moments::{moment_layer, moment_z};
use super::common_prefiltered::{basis4, fourier_step, region_column, texel_weight, turn};
use super::common_prefiltered_projective::{proj_region_g, proj_texel_weight};
use super::common_projective::proj_stored_depth;
use super::texture::{Tex, TexArray, xyz};
use glam::Vec3;
use scatter_shaderlib::prefiltered::{
    Basis, FrameUniforms, LightKind, PrefilteredVariant, Rectification, SliceParams, Storage,
    VisibilityMode,
};

/// The cookie of texel `i` of a row (slice `slice`, slice direction `e`; in a projective
/// frame column `i` of region `region`, with `stride` rectified columns per stored one): that
/// of the light ray through the texel's centre (see the WGSL comment).
#[allow(clippy::too_many_arguments, reason = "mirrors the WGSL signature")]
pub fn texel_cookie(
    frame: &FrameUniforms,
    cookie: &TexArray,
    regions: u32,
    stride: u32,
    i: u32,
    slice: &SliceParams,
    e: Vec3,
    region: u32,
    proj: bool,
) -> Vec3 {
    let col = (i as f32 + 0.5) * slice.delta;
    let mut l = -xyz(frame.axis) * col.cos() + e * col.sin();
    if proj {
        // The region layout of a map of Wr / stride columns (`proj_texel_weight`).
        let g = proj_region_g(
            frame,
            (i as f32 + 0.5) / stride as f32,
            region,
            regions,
            frame.sizes[2] / stride,
            true,
        );
        l = xyz(frame.e1) + xyz(frame.e2) * slice.delta - xyz(frame.axis) * g;
    }
    frame_cookie(frame, cookie, xyz(frame.light_pos) + l)
}

/// The kernel body for invocation `id` = (row, region, thread); `cookie` for a `cookie`
/// variant.
#[allow(clippy::too_many_arguments, reason = "bindings of the kernel")]
pub fn prefilter_main(
    id: [u32; 3],
    variant: &PrefilteredVariant,
    frame: &FrameUniforms,
    slices: &[SliceParams],
    rectified: &Tex,
    filtered: &mut TexArray,
    bounds: &mut TexArray,
    cookie: Option<&TexArray>,
) {
    let (row, region, thread) = (id[0], id[1], id[2]);
    let width = frame.sizes[2];
    if row >= frame.sizes[3]
        || region >= variant.regions
        || thread >= variant.threads_per_row_region()
    {
        return;
    }
    let weighted = variant.visibility == VisibilityMode::Weighted;
    let spot = variant.light == LightKind::Spot;
    let proj = variant.rectification == Rectification::Projective && frame.proj[0] > 0.5;
    let moments = variant.basis == Basis::Moments;
    let layers_per_thread = variant.per_thread().div_ceil(4);
    let slice = slices[row as usize];
    let stride = variant.filtered_stride;
    let start = region_column(region, variant.regions, width, stride, spot);
    let end = region_column(region + 1, variant.regions, width, stride, spot);
    let tinted = variant.cookie;
    let layers = variant.layers();
    let e = slice_e(frame, row_phi(frame, row));
    // With a cookie, channel c's layer q of this thread at c * layers_per_thread + q.
    let channels = if tinted { 3 } else { 1 };
    let mut acc = vec![[0.0f32; 4]; (channels * layers_per_thread) as usize];
    let mut tint_mean = Vec3::ZERO;
    let mut wsum = 0.0f32;
    let mut lo = 1e30f32;
    let mut hi = -1e30f32;
    // The region's whole depth range (what `bounds` holds at its last stored column), which
    // `moment_z` maps to [-1, 1]: one pass of depth loads before the moments.
    let mut depth_range = [1e30f32, -1e30f32];
    if moments {
        for i in start..end {
            let mut d = rectified.load(i, row);
            if proj {
                d = proj_stored_depth(d);
            }
            depth_range = [depth_range[0].min(d), depth_range[1].max(d)];
        }
    }
    for i in start..end {
        let mut d = rectified.load(i, row);
        let w;
        if proj {
            d = proj_stored_depth(d);
            w = proj_texel_weight(
                frame,
                &slice,
                i,
                region,
                variant.regions,
                stride,
                weighted,
                spot,
            );
        } else {
            w = texel_weight(frame, &slice, e, i, weighted, spot);
        }
        wsum += w;
        // Whether texel i ends a stored column (every texel with a stride of 1), and which.
        let store = i % stride == stride - 1;
        let x = i / stride;
        if thread == 0 {
            lo = lo.min(d);
            hi = hi.max(d);
            if store {
                bounds.store(x, row, 0, [lo, hi, 0.0, 0.0], Storage::Rgba32float);
                if variant.resume {
                    // The region's weight sum up to the texel, from which scatter resumes.
                    bounds.store(x, row, 1, [wsum, 0.0, 0.0, 0.0], Storage::Rgba32float);
                }
            }
        }
        let blend = select(0.0, w / wsum, wsum > 0.0);
        let mut tint = Vec3::ONE;
        if tinted {
            if let Some(cookie) = cookie {
                tint = texel_cookie(
                    frame,
                    cookie,
                    variant.regions,
                    stride,
                    i,
                    &slice,
                    e,
                    region,
                    proj,
                );
            }
            if thread == 0 {
                tint_mean = tint_mean * (1.0 - blend) + tint * blend;
                let t = [tint_mean.x, tint_mean.y, tint_mean.z, 1.0];
                if store {
                    filtered.store(x, row, 3 * layers, t, variant.storage);
                }
            }
        }
        // The running means of channel `c`'s `b` (the basis times the cookie; without a
        // cookie the basis itself, as `a (1 - blend) + b blend`).
        let mut update = |c: u32, q: u32, b: [f32; 4]| -> [f32; 4] {
            let a = &mut acc[(c * layers_per_thread + q) as usize];
            for k in 0..4 {
                a[k] = if tinted {
                    a[k] * (1.0 - blend) + b[k] * (tint[c as usize] * blend)
                } else {
                    a[k] * (1.0 - blend) + b[k] * blend
                };
            }
            *a
        };
        if moments {
            // The power moments of z in the region's range, stored as they are.
            let z = moment_z(d, depth_range);
            for q in 0..layers_per_thread {
                let b = moment_layer(z, q);
                for c in 0..channels {
                    let a = update(c, q, b);
                    if store {
                        filtered.store(x, row, c * layers + q, a, variant.storage);
                    }
                }
            }
            continue;
        }
        // The basis angles by angle addition; thread t > 0 starts at its first frequency
        // directly (see the WGSL).
        let mut angle = [(PI * d).sin(), (PI * d).cos()];
        let step = fourier_step(angle);
        if thread > 0 {
            let c = PI * d * (1 + 4 * thread * layers_per_thread) as f32;
            angle = [c.sin(), c.cos()];
        }
        for q in 0..layers_per_thread {
            let layer = thread * layers_per_thread + q;
            let second = turn(angle, step);
            let b = basis4(angle, second);
            angle = turn(second, step);
            for c in 0..channels {
                let a = update(c, q, b);
                let stored = [
                    a[0] * 0.5 + 0.5,
                    a[1] * 0.5 + 0.5,
                    a[2] * 0.5 + 0.5,
                    a[3] * 0.5 + 0.5,
                ];
                if store {
                    filtered.store(x, row, c * layers + layer, stored, variant.storage);
                }
            }
        }
    }
}

/// What `prefilter` writes.
#[derive(Clone, Debug, PartialEq)]
pub struct PrefilterOutput {
    /// The filtered bases.
    pub filtered: TexArray,
    /// Per texel `[min, max, 0, 0]` of the region's depths up to the texel (layer 0); with
    /// `resume` `[W, 0, 0, 0]`, the region's weight sum up to the texel (layer 1).
    pub bounds: TexArray,
}

/// Runs every invocation; returns the filtered-basis array and the region-prefix bounds,
/// both `Wr / filtered_stride` stored columns wide.
/// `cookie`: the spot's cookie texture for a `cookie` variant (ignored otherwise; a `cookie`
/// variant without one filters as with a white cookie).
pub fn prefilter(
    variant: &PrefilteredVariant,
    frame: &FrameUniforms,
    slices: &[SliceParams],
    rectified: &Tex,
    cookie: Option<&TexArray>,
) -> PrefilterOutput {
    // The stored columns: Wr / filtered_stride.
    let (w, h) = (variant.filtered_width(frame.sizes[2]), frame.sizes[3]);
    let mut filtered = TexArray::new(w, h, variant.filtered_layers());
    // (min, max), and with `resume` the weight sums in a second layer.
    let mut bounds = TexArray::new(w, h, if variant.resume { 2 } else { 1 });
    for row in 0..h {
        for region in 0..variant.regions {
            for thread in 0..variant.threads_per_row_region() {
                prefilter_main(
                    [row, region, thread],
                    variant,
                    frame,
                    slices,
                    rectified,
                    &mut filtered,
                    &mut bounds,
                    cookie,
                );
            }
        }
    }
    PrefilterOutput { filtered, bounds }
}
