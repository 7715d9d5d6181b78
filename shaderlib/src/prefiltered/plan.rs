//! The plan of a `prefiltered` variant: the textures, buffers and samplers and the three
//! passes (`rectify`, `prefilter`, `scatter`). `scatter-gen` writes it into the manifest;
//! `scatter-runtime` builds and dispatches from it.

use crate::plan::{
    Alternative, BindingSource, BufferDesc, DEPTH_FORMAT, OUTPUT_FORMAT, Parameter, PassPlan, Plan,
    Resource, SamplerDesc, TextureDesc,
};
use crate::prefiltered::{Rectification, Variant};
use crate::{Kernel, KernelParams};

/// The per-frame condition of a projective frame (the frame set-up falls back to epipolar
/// when the epipole is on screen).
pub const PROJECTIVE_FRAME: &str = "frame.proj.x > 0.5 (a projective frame)";
/// The per-frame condition under which `scatter` binds the rasterised rectified map where
/// the standard shadow map goes.
pub const PROJECTIVE_WITHOUT_SHADOW_MAP: &str = "the frame is projective and the engine has no \
                                                 standard shadow map (the binding is not read \
                                                 then)";
/// The per-frame condition under which the slices go round the full circle and `scatter`
/// samples the filtered bases with the wrapping sampler.
pub const WRAPPING_SLICES: &str = "frame.anti_epipole.w > 0.5";
/// The engine's rasterised rectified map of projective variants.
pub const RECTIFIED_RASTER: &str = "rectified_raster";

const SAMPLED: &[&str] = &["texture_binding"];
const STORAGE_AND_SAMPLED: &[&str] = &["storage_binding", "texture_binding"];

fn texture(
    format: &str,
    width: &str,
    height: &str,
    layers: String,
    usage: &[&'static str],
) -> TextureDesc {
    TextureDesc {
        format: format.to_owned(),
        dimension: "2d",
        width: width.to_owned(),
        height: height.to_owned(),
        layers,
        mip_levels: 1,
        usage: usage.to_vec(),
    }
}

fn linear_sampler(address_mode_v: &'static str) -> SamplerDesc {
    SamplerDesc {
        mag_filter: "linear",
        min_filter: "linear",
        mipmap_filter: "nearest",
        address_mode_u: "clamp_to_edge",
        address_mode_v,
        address_mode_w: "clamp_to_edge",
    }
}

fn bind(binding: u32, resource: &'static str) -> BindingSource {
    BindingSource {
        binding,
        resource,
        alternative: None,
    }
}

/// The resources and passes of a variant, as `runtime/src/prefiltered.rs` creates them.
pub fn plan(v: &Variant) -> Plan {
    let parameters = vec![
        Parameter {
            name: "screen.width",
            description: "screen width in pixels (depth buffer and output)",
            constraint: "1..=max_texture_dimension_2d".into(),
        },
        Parameter {
            name: "screen.height",
            description: "screen height in pixels (depth buffer and output)",
            constraint: "1..=max_texture_dimension_2d".into(),
        },
        Parameter {
            name: "shadow.size",
            description: "side of the engine's square standard shadow map in texels",
            constraint: "1..=max_texture_dimension_2d".into(),
        },
        Parameter {
            name: "rectified.width",
            description: "light rays per epipolar slice (columns of the rectified map), an \
                          engine choice (the demo uses 1024)",
            constraint: format!(
                "regions^2 = {}..=max_texture_dimension_2d",
                v.regions * v.regions
            ),
        },
        Parameter {
            name: "rectified.height",
            description: "epipolar slices (rows of the rectified map), an engine choice (the \
                          demo uses 1024)",
            constraint: "1..=max_texture_dimension_2d".into(),
        },
    ];
    let mut resources = vec![
        Resource {
            name: "frame",
            kind: "uniform_buffer",
            provided_by: "scatter",
            contents: "the uniform block of the frame (Rust: \
                       scatter_shaderlib::prefiltered::FrameUniforms from prepare_frame), \
                       written once per frame",
            texture: None,
            buffer: Some(BufferDesc {
                elements: None,
                usage: vec!["uniform", "copy_dst"],
            }),
            sampler: None,
        },
        Resource {
            name: "slices",
            kind: "storage_buffer",
            provided_by: "scatter",
            contents: "one vec4 per rectified row: delta, theta_ref, theta_lo, theta_hi (Rust: \
                       SliceParams from prepare_frame), written once per frame",
            texture: None,
            buffer: Some(BufferDesc {
                elements: Some("rectified.height".into()),
                usage: vec!["storage", "copy_dst"],
            }),
            sampler: None,
        },
        Resource {
            name: "depth",
            kind: "texture",
            provided_by: "engine",
            contents: "linear view depth per pixel (far plane distance for sky)",
            texture: Some(texture(
                DEPTH_FORMAT,
                "screen.width",
                "screen.height",
                "1".into(),
                SAMPLED,
            )),
            buffer: None,
            sampler: None,
        },
        Resource {
            name: "shadow_map",
            kind: "texture",
            provided_by: "engine",
            contents: "standard shadow map: normalised linear light depth, 1 where nothing was \
                       hit, texel (0, 0) top-left",
            texture: Some(texture(
                DEPTH_FORMAT,
                "shadow.size",
                "shadow.size",
                "1".into(),
                SAMPLED,
            )),
            buffer: None,
            sampler: None,
        },
        Resource {
            name: "rectified",
            kind: "texture",
            provided_by: "scatter",
            contents: "rectified shadow map: normalised view angle of the first occluder per \
                       light ray (written by rectify)",
            texture: Some(texture(
                DEPTH_FORMAT,
                "rectified.width",
                "rectified.height",
                "1".into(),
                STORAGE_AND_SAMPLED,
            )),
            buffer: None,
            sampler: None,
        },
        Resource {
            name: "filtered",
            kind: "texture",
            provided_by: "scatter",
            contents: "filtered Fourier bases, four per layer, stored as F / 2 + 0.5 (written \
                       by prefilter); view it as a 2d array even with one layer",
            texture: Some(texture(
                v.storage.name(),
                "rectified.width",
                "rectified.height",
                v.layers().to_string(),
                STORAGE_AND_SAMPLED,
            )),
            buffer: None,
            sampler: None,
        },
        Resource {
            name: "output",
            kind: "texture",
            provided_by: "scatter",
            contents: "in-scattered radiance, rgb, alpha 1 (written by scatter); add it to the \
                       attenuated scene",
            texture: Some(texture(
                OUTPUT_FORMAT,
                "screen.width",
                "screen.height",
                "1".into(),
                STORAGE_AND_SAMPLED,
            )),
            buffer: None,
            sampler: None,
        },
        Resource {
            name: "filtered_sampler_clamp",
            kind: "sampler",
            provided_by: "scatter",
            contents: "bilinear sampler of the filtered bases when the slices do not wrap",
            texture: None,
            buffer: None,
            sampler: Some(linear_sampler("clamp_to_edge")),
        },
        Resource {
            name: "filtered_sampler_wrap",
            kind: "sampler",
            provided_by: "scatter",
            contents: "bilinear sampler of the filtered bases when the slices go round the \
                       full circle (repeat across slices)",
            texture: None,
            buffer: None,
            sampler: Some(linear_sampler("repeat")),
        },
    ];
    if v.rectification == Rectification::Projective {
        resources.push(Resource {
            name: RECTIFIED_RASTER,
            kind: "texture",
            provided_by: "engine",
            contents: "projective frames only: the rectified depth map the engine rasterises \
                       with the frame's per-region matrices and viewports (Rust: \
                       FrameReport::projective from prepare_frame), clip depth in [0, 1]",
            texture: Some(texture(
                DEPTH_FORMAT,
                "rectified.width",
                "rectified.height",
                "1".into(),
                SAMPLED,
            )),
            buffer: None,
            sampler: None,
        });
    }
    // One pass per kernel shaderlib lists for the variant, in its order; a kernel this
    // module does not know gets no pass, and generation names it.
    let passes = KernelParams::prefiltered(*v)
        .iter()
        .filter_map(|p| pass(v, p.kernel()))
        .collect();
    let mut notes = vec![
        "Run the passes in order; each reads what the previous ones wrote: put a \
             compute-to-compute memory barrier (and, in Vulkan, the image layout transition \
             from storage to sampled) between them.",
        "Write `frame` and `slices` once per frame before the first pass; the host code \
             that computes them is scatter_shaderlib::prefiltered::prepare_frame (Rust).",
        "Group 0 holds every binding; bind by group and binding number, not by name: \
             emitted names may be mangled (naga_oil) or carry a trailing `_` (naga).",
    ];
    if v.rectification == Rectification::Projective {
        notes.push(
            "Projective variant: the frame set-up decides per frame (FrameReport::rectification) \
             whether the frame is projective or falls back to epipolar (FrameReport::fallback \
             says why: epipole or anti-epipole on screen, slices fanning out too wide). In a \
             projective frame skip `rectify`, rasterise `rectified_raster` with the frame's \
             matrices and bind it where the passes say; epipolar frames run as usual.",
        );
    }
    Plan {
        parameters,
        resources,
        passes,
        notes,
    }
}

/// The pass of one kernel, or `None` for a kernel that is not in this family.
pub fn pass(v: &Variant, kernel: Kernel) -> Option<PassPlan> {
    let f = |s: &str| s.to_owned();
    let projective = v.rectification == Rectification::Projective;
    match kernel {
        Kernel::Rectify => Some(PassPlan {
            kernel,
            invocations: [f("rectified.width"), f("rectified.height"), f("1")],
            skip_when: projective.then_some(PROJECTIVE_FRAME),
            bindings: vec![
                bind(0, "frame"),
                bind(1, "slices"),
                bind(2, "shadow_map"),
                bind(3, "rectified"),
            ],
        }),
        Kernel::Prefilter => Some(PassPlan {
            kernel,
            invocations: [
                f("rectified.height"),
                v.regions.to_string(),
                v.threads_per_row_region().to_string(),
            ],
            skip_when: None,
            bindings: vec![
                bind(0, "frame"),
                bind(1, "slices"),
                BindingSource {
                    binding: 2,
                    resource: "rectified",
                    alternative: projective.then_some(Alternative {
                        resource: RECTIFIED_RASTER,
                        when: PROJECTIVE_FRAME,
                    }),
                },
                bind(3, "filtered"),
            ],
        }),
        Kernel::Scatter => Some(PassPlan {
            kernel,
            invocations: [f("screen.width"), f("screen.height"), f("1")],
            skip_when: None,
            bindings: vec![
                bind(0, "frame"),
                bind(1, "slices"),
                bind(2, "depth"),
                BindingSource {
                    binding: 3,
                    resource: "shadow_map",
                    alternative: projective.then_some(Alternative {
                        resource: RECTIFIED_RASTER,
                        when: PROJECTIVE_WITHOUT_SHADOW_MAP,
                    }),
                },
                bind(4, "filtered"),
                BindingSource {
                    binding: 5,
                    resource: "filtered_sampler_clamp",
                    alternative: Some(Alternative {
                        resource: "filtered_sampler_wrap",
                        when: WRAPPING_SLICES,
                    }),
                },
                bind(6, "output"),
            ],
        }),
        _ => None,
    }
}
