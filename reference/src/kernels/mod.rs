//! CPU mirrors of the GPU kernels, one module per kernel, named like its template
//! (`shaderlib/templates/<kernel>.wgsl`) and written line by line like the WGSL, so that a
//! GPU result can be compared with its mirror at quantisation-level tolerance. Shared WGSL
//! modules (`templates/common/<name>.wgsl`) are mirrored by `common_<name>.rs`.

pub mod common_cookie;
pub mod common_epipolar;
pub mod common_ivsv;
pub mod common_minmax;
pub mod common_model;
pub mod common_moments;
pub mod common_prefiltered;
pub mod common_prefiltered_projective;
pub mod common_projective;
pub mod common_raymarch;
pub mod common_sampling;
pub mod common_shadow;
pub mod depth_columns;
pub mod family;
pub mod interleave_sum;
pub mod ivsv_gather;
pub mod ivsv_gather_fallback;
pub mod ivsv_gather_unwarp;
pub mod ivsv_interleave_sum;
pub mod ivsv_rectify;
pub mod ivsv_scan;
pub mod minmax_build;
pub mod minmax_traverse;
pub mod minmax_traverse_fallback;
pub mod minmax_traverse_unwarp;
pub mod prefilter;
pub mod pst_sweep;
pub mod pst_sweep_fallback;
pub mod pst_sweep_unwarp;
pub mod raymarch;
pub mod raymarch_fallback;
pub mod raymarch_unwarp;
pub mod rectify;
pub mod row_prefix;
pub mod scatter;
pub mod scatter_fallback;
pub mod scatter_unwarp;
pub mod slice_fit;
pub mod texture;
pub mod volume_bounds;
pub mod volume_march;
pub mod volume_march_fallback;
pub mod volume_march_unwarp;

use crate::buffers::{GBuffer, ShadowMap};
use crate::bvh::Bvh;
use crate::geometry::Aabb;
use crate::image::Image;
use crate::projective::rasterise_rectified;
use crate::scene::Scene;
pub use family::{CpuFamily, CpuFrame, CpuRun, FamilyRun, run_family};
use scatter_shaderlib::area_ivsv::{AreaIvsvFrame, AreaIvsvVariant, VplInput};
use scatter_shaderlib::hybrid_volume::{HybridVolumeVariant, prepare_hybrid_volume};
use scatter_shaderlib::minmax::{MinmaxVariant, prepare_minmax};
use scatter_shaderlib::partial_sum_tree::{
    PartialSumTreeFrame, PartialSumTreeVariant, prepare_partial_sum_tree,
};
use scatter_shaderlib::prefiltered::{
    FrameError, FrameSettings, LightKind, PrefilteredFrame, PrefilteredVariant, Resolutions,
    prepare_frame,
};
use texture::{Tex, TexArray};

/// Every intermediate of one CPU run of the prefiltered family.
#[derive(Clone, Debug)]
pub struct PrefilteredRun {
    /// The frame set-up (uniforms, slices, report).
    pub frame: PrefilteredFrame,
    /// The rectified shadow map.
    pub rectified: Tex,
    /// The filtered-basis array.
    pub filtered: TexArray,
    /// The region-prefix depth bounds `[min, max, 0, 0]` (one layer).
    pub bounds: TexArray,
    /// In-scattered radiance (as stored in rgba16float).
    pub output: Image,
}

/// Runs `depth_columns`, `slice_fit`, `rectify`, `prefilter` and `scatter` on the CPU for a scene, its depth buffer and
/// its standard shadow map. In a projective frame (a `projective` variant whose frame allows
/// it) `rectify` is replaced by the engine's rasterisation of the rectified map
/// ([`crate::projective::rasterise_rectified`], ray cast in `bvh`).
pub fn run_prefiltered(
    variant: &PrefilteredVariant,
    rectified_size: [u32; 2],
    scene: &Scene,
    bvh: &Bvh,
    gbuf: &GBuffer,
    shadow_map: &ShadowMap,
    settings: &FrameSettings,
) -> Result<PrefilteredRun, FrameError> {
    let res = Resolutions {
        screen: [gbuf.width, gbuf.height],
        rectified: rectified_size,
    };
    let mut frame = prepare_frame(
        variant,
        &res,
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &shadow_map.desc(),
        settings,
    )?;
    let spot = variant.light == LightKind::Spot;
    let sm = Tex {
        width: shadow_map.size,
        height: shadow_map.size,
        data: shadow_map.depth.clone(),
    };
    let depth = Tex {
        width: gbuf.width,
        height: gbuf.height,
        data: gbuf.view_depth.clone(),
    };
    let column_depth = depth_columns::depth_columns(&frame.uniforms, &depth);
    slice_fit::slice_fit(&frame.uniforms, &mut frame.slices, &column_depth, spot);
    let rectified = match engine_rectified_map(scene, bvh, &frame) {
        Some(data) => Tex {
            width: rectified_size[0],
            height: rectified_size[1],
            data,
        },
        None => rectify::rectify(&frame.uniforms, &frame.slices, &sm, spot),
    };
    let cookie = variant.cookie.then(|| cookie_texture(scene)).flatten();
    let prefilter::PrefilterOutput { filtered, bounds } = prefilter::prefilter(
        variant,
        &frame.uniforms,
        &frame.slices,
        &rectified,
        cookie.as_ref(),
    );
    let out = scatter::scatter(
        variant,
        &scatter::ScatterInputs {
            frame: &frame.uniforms,
            slices: &frame.slices,
            depth: &depth,
            shadow_map: &sm,
            filtered: &filtered,
            bounds: &bounds,
            rectified: Some(&rectified),
            cookie: cookie.as_ref(),
        },
    );
    let output = Image::from_pixels(
        gbuf.width,
        gbuf.height,
        out.data.iter().map(|c| [c[0], c[1], c[2]]).collect(),
    );
    Ok(PrefilteredRun {
        frame,
        rectified,
        filtered,
        bounds,
        output,
    })
}

/// For a projective frame, the rectified map the engine would rasterise (see
/// [`rasterise_rectified`]); `None` for an epipolar frame.
pub fn engine_rectified_map(
    scene: &Scene,
    bvh: &Bvh,
    frame: &PrefilteredFrame,
) -> Option<Vec<f32>> {
    let maps = frame.report.projective.as_ref()?;
    let [_, _, width, height] = frame.uniforms.sizes;
    Some(rasterise_rectified(
        bvh,
        &scene.light_desc(),
        maps,
        width,
        height,
        scene_reach(scene, bvh),
    ))
}

/// A distance that reaches across the scene's bounded geometry and the camera frustum (the
/// start offset of directional light rays in [`rasterise_rectified`]).
pub fn scene_reach(scene: &Scene, bvh: &Bvh) -> f64 {
    let mut b = bvh.bounds();
    for c in scene.camera.frustum_corners() {
        b = b.grow(c);
    }
    b = b.grow(scene.camera.position);
    if b == Aabb::EMPTY {
        return 1.0;
    }
    2.0 * (b.max - b.min).length() + 1.0
}

/// Every intermediate of one CPU run of the raymarch family.
#[derive(Clone, Debug)]
pub struct RaymarchRun {
    /// The uniform block.
    pub uniforms: scatter_shaderlib::raymarch::RaymarchUniforms,
    /// The partial sums of an interleaved variant (rgba32float), `None` otherwise.
    pub partial: Option<TexArray>,
    /// In-scattered radiance (as stored in rgba16float).
    pub output: Image,
}

/// Runs `raymarch` (and `interleave_sum` when the variant interleaves) on the CPU for a
/// scene, its depth buffer and its standard shadow map.
pub fn run_raymarch(
    variant: &scatter_shaderlib::raymarch::RaymarchVariant,
    scene: &Scene,
    gbuf: &GBuffer,
    shadow_map: &ShadowMap,
) -> Result<RaymarchRun, FrameError> {
    let uniforms = scatter_shaderlib::raymarch::prepare_raymarch(
        variant,
        [gbuf.width, gbuf.height],
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &shadow_map.desc(),
    )?;
    let sm = Tex {
        width: shadow_map.size,
        height: shadow_map.size,
        data: shadow_map.depth.clone(),
    };
    let depth = Tex {
        width: gbuf.width,
        height: gbuf.height,
        data: gbuf.view_depth.clone(),
    };
    let cookie = variant.cookie.then(|| cookie_texture(scene)).flatten();
    let marched = raymarch::raymarch(variant, &uniforms, &depth, &sm, cookie.as_ref());
    let (partial, out) = if variant.interleaved() {
        let out = interleave_sum::interleave_sum(&uniforms, &marched);
        (Some(marched), out)
    } else {
        (None, marched)
    };
    let output = Image::from_pixels(
        gbuf.width,
        gbuf.height,
        out.data.iter().map(|c| [c[0], c[1], c[2]]).collect(),
    );
    Ok(RaymarchRun {
        uniforms,
        partial,
        output,
    })
}

/// The scene's spot cookie as the kernels read it: the `rgba16float` texture the runtime
/// uploads (each channel rounded to f16, alpha 1), or `None` without a cookie.
pub fn cookie_texture(scene: &Scene) -> Option<TexArray> {
    let crate::scene::Light::Spot {
        cookie: Some(cookie),
        ..
    } = &scene.light
    else {
        return None;
    };
    Some(TexArray {
        width: cookie.width(),
        height: cookie.height(),
        layers: 1,
        data: cookie
            .rgba()
            .into_iter()
            .map(|t| t.map(texture::round_f16))
            .collect(),
    })
}

/// The engine's inputs as the mirrors take them: the depth buffer and the standard shadow
/// map.
fn input_textures(gbuf: &GBuffer, shadow_map: &ShadowMap) -> (Tex, Tex) {
    let depth = Tex {
        width: gbuf.width,
        height: gbuf.height,
        data: gbuf.view_depth.clone(),
    };
    let sm = Tex {
        width: shadow_map.size,
        height: shadow_map.size,
        data: shadow_map.depth.clone(),
    };
    (depth, sm)
}

/// The passes every rectified epipolar family starts with, on the CPU: `depth_columns`,
/// `slice_fit` (which rewrites `frame.slices`) and `rectify`; returns the rectified map.
fn rectify_passes(frame: &mut PrefilteredFrame, depth: &Tex, sm: &Tex, light: LightKind) -> Tex {
    let spot = light == LightKind::Spot;
    let column_depth = depth_columns::depth_columns(&frame.uniforms, depth);
    slice_fit::slice_fit(&frame.uniforms, &mut frame.slices, &column_depth, spot);
    rectify::rectify(&frame.uniforms, &frame.slices, sm, spot)
}

/// Every intermediate of one CPU run of the minmax family.
#[derive(Clone, Debug)]
pub struct MinmaxRun {
    /// The frame set-up (the prefiltered family's, for [`MinmaxVariant::prefiltered`]).
    pub frame: PrefilteredFrame,
    /// The rectified shadow map (`rectify`).
    pub rectified: Tex,
    /// The min-max trees (`minmax_build`).
    pub tree: TexArray,
    /// The hierarchical march (`minmax_traverse`): radiance, and nodes visited per pixel.
    pub march: minmax_traverse::TraverseImage,
    /// The brute-force march over every texel of the same rectified rows.
    pub brute: minmax_traverse::TraverseImage,
    /// In-scattered radiance of the hierarchical march (as stored in rgba16float).
    pub output: Image,
}

/// Runs `depth_columns`, `slice_fit`, `rectify`, `minmax_build` and `minmax_traverse` on the CPU for a scene, its depth
/// buffer and its standard shadow map, and the brute-force march over the same rectified
/// map.
pub fn run_minmax(
    variant: &MinmaxVariant,
    rectified_size: [u32; 2],
    gbuf: &GBuffer,
    scene: &Scene,
    shadow_map: &ShadowMap,
    settings: &FrameSettings,
) -> Result<MinmaxRun, FrameError> {
    let res = Resolutions {
        screen: [gbuf.width, gbuf.height],
        rectified: rectified_size,
    };
    let mut frame = prepare_minmax(
        variant,
        &res,
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &shadow_map.desc(),
        settings,
    )?;
    let (depth, sm) = input_textures(gbuf, shadow_map);
    let rectified = rectify_passes(&mut frame, &depth, &sm, variant.light);
    let cookie = variant.cookie.then(|| cookie_texture(scene)).flatten();
    Ok(minmax_from_rectified(
        variant,
        frame,
        rectified,
        &depth,
        &sm,
        cookie.as_ref(),
    ))
}

/// `minmax_build`, `minmax_traverse` and the brute-force march for a given frame and
/// rectified map (the GPU's, in the conformance test); `cookie` for a `cookie` variant.
pub fn minmax_from_rectified(
    variant: &MinmaxVariant,
    frame: PrefilteredFrame,
    rectified: Tex,
    depth: &Tex,
    shadow_map: &Tex,
    cookie: Option<&TexArray>,
) -> MinmaxRun {
    let tree = minmax_build::minmax_build(&frame.uniforms, &rectified);
    let inputs = minmax_traverse::TraverseInputs {
        frame: &frame.uniforms,
        slices: &frame.slices,
        depth,
        shadow_map,
        tree: &tree,
        cookie,
    };
    let march = minmax_traverse::minmax_traverse(variant, &inputs);
    let brute = minmax_traverse::minmax_brute(variant, &inputs, &rectified);
    let output = Image::from_pixels(
        depth.width,
        depth.height,
        march
            .output
            .data
            .iter()
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
    );
    MinmaxRun {
        frame,
        rectified,
        tree,
        march,
        brute,
        output,
    }
}

/// Every intermediate of one CPU run of the `hybrid_volume` family.
#[derive(Clone, Debug)]
pub struct HybridVolumeRun {
    /// The frame set-up (the prefiltered family's, for [`HybridVolumeVariant::prefiltered`]).
    pub frame: PrefilteredFrame,
    /// The rectified shadow map (`rectify`).
    pub rectified: Tex,
    /// The binned boundary crossings (`volume_bounds`).
    pub crossings: volume_bounds::VolumeBounds,
    /// Each pixel's interval (`None`: an epipole disc, marched whole), row-major; empty for
    /// a sampled variant (diagnostics, not a pass).
    pub spans: Vec<Option<volume_march::PixelSpan>>,
    /// `volume_march` through its sampling stage.
    pub march: common_sampling::SampledOutput,
    /// In-scattered radiance (as stored in rgba16float).
    pub output: Image,
}

/// Runs `depth_columns`, `slice_fit`, `rectify`, `volume_bounds` and `volume_march` on the
/// CPU for a scene, its depth buffer and its standard shadow map.
///
/// # Errors
///
/// As the frame set-up ([`prepare_hybrid_volume`]).
pub fn run_hybrid_volume(
    variant: &HybridVolumeVariant,
    rectified_size: [u32; 2],
    gbuf: &GBuffer,
    scene: &Scene,
    shadow_map: &ShadowMap,
    settings: &FrameSettings,
) -> Result<HybridVolumeRun, FrameError> {
    let res = Resolutions {
        screen: [gbuf.width, gbuf.height],
        rectified: rectified_size,
    };
    let mut frame = prepare_hybrid_volume(
        variant,
        &res,
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &shadow_map.desc(),
        settings,
    )?;
    let (depth, sm) = input_textures(gbuf, shadow_map);
    let rectified = rectify_passes(&mut frame, &depth, &sm, variant.light);
    let cookie = variant.cookie.then(|| cookie_texture(scene)).flatten();
    Ok(hybrid_volume_from_rectified(
        variant,
        frame,
        rectified,
        &depth,
        &sm,
        cookie.as_ref(),
    ))
}

/// `volume_bounds` and `volume_march` for a given frame (after `slice_fit`) and rectified
/// map (the GPU's, in the conformance test); `cookie` for a `cookie` variant.
pub fn hybrid_volume_from_rectified(
    variant: &HybridVolumeVariant,
    frame: PrefilteredFrame,
    rectified: Tex,
    depth: &Tex,
    shadow_map: &Tex,
    cookie: Option<&TexArray>,
) -> HybridVolumeRun {
    let crossings = volume_bounds::volume_bounds(&frame.uniforms, &rectified, variant.bins);
    let inputs = volume_march::MarchInputs {
        frame: &frame.uniforms,
        slices: &frame.slices,
        depth,
        shadow_map,
        rectified: &rectified,
        crossings: &crossings,
        cookie,
    };
    let march = volume_march::volume_march(variant, &inputs);
    let spans = if variant.sampling_knobs().is_sampled() {
        Vec::new()
    } else {
        volume_march::pixel_spans(variant, &inputs)
    };
    let output = Image::from_pixels(
        depth.width,
        depth.height,
        march
            .output
            .data
            .iter()
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
    );
    HybridVolumeRun {
        frame,
        rectified,
        crossings,
        spans,
        march,
        output,
    }
}

/// Every intermediate of one CPU run of the `partial_sum_tree` family.
#[derive(Clone, Debug)]
pub struct PartialSumTreeRun {
    /// The frame set-up (the shared epipolar frame after `slice_fit`, and the separable
    /// integrand with its factors buffer).
    pub frame: PartialSumTreeFrame,
    /// The rectified shadow map (`rectify`).
    pub rectified: Tex,
    /// What `pst_sweep` wrote to `epipolar_samples`.
    pub samples: common_sampling::EpipolarSamples,
    /// The sweep's counts.
    pub counts: pst_sweep::SweepCounts,
    /// The unwarp and fallback (`output`, the fallback's pixel count).
    pub sampled: common_sampling::SampledOutput,
    /// In-scattered radiance (as stored in rgba16float).
    pub output: Image,
}

/// Runs `depth_columns`, `slice_fit`, `rectify`, `pst_sweep`, `pst_sweep_unwarp` and
/// `pst_sweep_fallback` on the CPU for a scene, its depth buffer and its standard shadow
/// map.
///
/// # Errors
///
/// [`FrameError`] when the frame cannot be set up.
pub fn run_partial_sum_tree(
    variant: &PartialSumTreeVariant,
    rectified_size: [u32; 2],
    gbuf: &GBuffer,
    scene: &Scene,
    shadow_map: &ShadowMap,
    settings: &FrameSettings,
) -> Result<PartialSumTreeRun, FrameError> {
    let res = Resolutions {
        screen: [gbuf.width, gbuf.height],
        rectified: rectified_size,
    };
    let mut frame = prepare_partial_sum_tree(
        variant,
        &res,
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &shadow_map.desc(),
        settings,
    )?;
    let (depth, sm) = input_textures(gbuf, shadow_map);
    let rectified = rectify_passes(&mut frame.frame, &depth, &sm, variant.light);
    let cookie = variant.cookie.then(|| cookie_texture(scene)).flatten();
    Ok(partial_sum_tree_from_rectified(
        variant,
        frame,
        rectified,
        &depth,
        &sm,
        cookie.as_ref(),
    ))
}

/// `pst_sweep`, its unwarp and its fallback for a given frame (after `slice_fit`) and
/// rectified map (the GPU's, in the conformance test); `cookie` for a `cookie` variant.
pub fn partial_sum_tree_from_rectified(
    variant: &PartialSumTreeVariant,
    frame: PartialSumTreeFrame,
    rectified: Tex,
    depth: &Tex,
    shadow_map: &Tex,
    cookie: Option<&TexArray>,
) -> PartialSumTreeRun {
    let inputs = pst_sweep::PstInputs {
        frame: &frame.frame.uniforms,
        slices: &frame.frame.slices,
        depth,
        shadow_map,
        rectified: &rectified,
        factors: &frame.factors,
        cookie,
    };
    let (samples, counts) = pst_sweep::pst_sweep(variant, &inputs);
    let unwarped = pst_sweep_unwarp::pst_sweep_unwarp(variant, &inputs, &samples.samples);
    let sampled = pst_sweep_fallback::pst_sweep_fallback(variant, &inputs, unwarped);
    let output = Image::from_pixels(
        depth.width,
        depth.height,
        sampled
            .output
            .data
            .iter()
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
    );
    PartialSumTreeRun {
        frame,
        rectified,
        samples,
        counts,
        sampled,
        output,
    }
}

/// The inputs of the `area_ivsv` kernels for a scene: its VPLs (each a spot scene of
/// [`Scene::point_light_scenes`]) with their ray-cast shadow maps, the frame set-up, and the
/// textures (VPL maps as layers, channel 0; the depth buffer).
#[derive(Clone, Debug)]
pub struct IvsvInputs {
    /// The frame set-up.
    pub frame: AreaIvsvFrame,
    /// The VPLs as the frame set-up takes them (spot light, shadow-map description).
    pub vpls: Vec<VplInput>,
    /// Every VPL's shadow map, one layer each (channel 0).
    pub maps: TexArray,
    /// The same, as the GPU's `vpl_maps` takes them: layer-major, then row-major.
    pub map_data: Vec<f32>,
    /// The depth buffer.
    pub depth: Tex,
}

/// Why the `area_ivsv` inputs cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum IvsvInputError {
    /// A VPL's shadow map.
    #[error(transparent)]
    ShadowMap(#[from] crate::buffers::ShadowMapError),
    /// The frame set-up.
    #[error(transparent)]
    Frame(#[from] FrameError),
}

/// Builds the `area_ivsv` inputs of `scene` (an area light: `variant.vpls` VPLs, which for a
/// two-sided light must be even: half the points, each twice) with `map_size`^2 VPL maps.
///
/// # Errors
///
/// A VPL's shadow map that cannot be built, or the frame set-up's error.
pub fn ivsv_inputs(
    scene: &Scene,
    gbuf: &GBuffer,
    bvh: &Bvh,
    variant: &AreaIvsvVariant,
    map_size: u32,
) -> Result<IvsvInputs, IvsvInputError> {
    // The engine's path: the point limit's standard map is the template, the frame set-up
    // places the VPLs and derives their maps, and each map is ray-cast as an engine
    // rasterises it.
    let template = ShadowMap::area_template(scene, bvh, map_size)?;
    let (frame, vpls) = scatter_shaderlib::area_ivsv::prepare_area_light(
        variant,
        [gbuf.width, gbuf.height],
        &scene.camera_desc(),
        &scene.light_desc(),
        &scene.medium_desc(),
        &template,
    )?;
    let layers = vpls.len() as u32;
    let mut maps = TexArray::new(map_size, map_size, layers);
    let mut map_data = Vec::with_capacity((layers * map_size * map_size) as usize);
    for (layer, vpl) in (0u32..).zip(&vpls) {
        let sm = ShadowMap::from_desc(&vpl.shadow_map).cast(bvh);
        for (k, &d) in sm.depth.iter().enumerate() {
            let k = k as u32;
            maps.data[((layer * map_size + k / map_size) * map_size + k % map_size) as usize] =
                [d, 0.0, 0.0, 0.0];
        }
        map_data.extend_from_slice(&sm.depth);
    }
    let depth = Tex {
        width: gbuf.width,
        height: gbuf.height,
        data: gbuf.view_depth.clone(),
    };
    Ok(IvsvInputs {
        frame,
        vpls,
        maps,
        map_data,
        depth,
    })
}

/// What the `area_ivsv` mirrors compute for one frame.
#[derive(Clone, Debug)]
pub struct IvsvRun {
    /// `marks` after `ivsv_rectify`.
    pub marks: Vec<u32>,
    /// `volume` after `ivsv_scan`.
    pub volume: Vec<u32>,
    /// `ivsv_gather`'s partial sums when interleaved (else empty).
    pub partial: Vec<[f32; 3]>,
    /// The output (rgb, not rounded to `rgba16float`): `ivsv_gather`'s, or
    /// `ivsv_interleave_sum`'s when interleaved; when sampled the stage's output, rounded
    /// (its samples are stored as rgba16float before they are blended).
    pub output: Vec<[f32; 3]>,
    /// The output as stored in `rgba16float`.
    pub image: Image,
}

/// Runs `ivsv_rectify`, `ivsv_scan`, `ivsv_gather` and, when interleaved,
/// `ivsv_interleave_sum`, or when sampled the sampling stage around `ivsv_gather`'s pixel
/// body (`ivsv_gather_unwarp` and `ivsv_gather_fallback` for `epipolar`), on the CPU.
pub fn run_area_ivsv(variant: &AreaIvsvVariant, inputs: &IvsvInputs) -> IvsvRun {
    let m = &inputs.frame.uniforms;
    let words = 4 * (variant.vpls * variant.alpha * variant.theta) as usize;
    let mut marks = vec![0u32; words];
    ivsv_rectify::ivsv_rectify(m, &inputs.frame.vpls, &inputs.maps, &mut marks);
    let rectified = marks.clone();
    let mut volume = vec![0u32; words];
    ivsv_scan::ivsv_scan(m, &mut marks, &mut volume);
    if variant.sampling_knobs().is_sampled() {
        // Sampled (interleave 1): the stage's passes with the gather's pixel body; the
        // output is already rounded to rgba16float.
        let sampled = ivsv_gather::ivsv_gather_sampled(
            variant,
            m,
            &inputs.frame.vpls,
            &volume,
            &inputs.depth,
        );
        let output: Vec<[f32; 3]> = sampled
            .output
            .data
            .iter()
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let image = Image::from_pixels(m.sizes[0], m.sizes[1], output.clone());
        return IvsvRun {
            marks: rectified,
            volume,
            partial: Vec::new(),
            output,
            image,
        };
    }
    let gathered = ivsv_gather::ivsv_gather(
        m,
        &inputs.frame.vpls,
        &volume,
        &inputs.depth,
        variant.segments,
        variant.interleave,
    );
    let (partial, output) = if variant.interleave > 1 {
        let out = ivsv_interleave_sum::ivsv_interleave_sum(m, &gathered, variant.interleave);
        (gathered, out)
    } else {
        (Vec::new(), gathered)
    };
    let image = Image::from_pixels(
        m.sizes[0],
        m.sizes[1],
        output
            .iter()
            .map(|&p| common_sampling::round_f16_rgb(p))
            .collect(),
    );
    IvsvRun {
        marks: rectified,
        volume,
        partial,
        output,
        image,
    }
}
