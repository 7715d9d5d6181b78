//! The plan of a `prefiltered` variant: the textures and buffers and the five
//! passes (`depth_columns`, `slice_fit`, `rectify`, `prefilter`, `scatter`). `scatter-gen` writes it into the manifest;
//! `scatter-runtime` builds and dispatches from it.

use crate::Kernel;
use crate::family::KernelFamily;
use crate::plan::{
    Alternative, BindingSource, BufferDesc, COOKIE_BINDING, DEPTH_FORMAT, Formula, OUTPUT_FORMAT,
    Parameter, PassPlan, Plan, Resource, SAMPLED, SLICE_FIT_NOTE, TEXTURE_DIMENSION, bind,
    column_depth_buffer, cookie_parameters, cookie_texture, depth_and_shadow_map, frame_buffer,
    scatter_resource, scatter_texture, screen_and_shadow_parameters, texture_2d,
};
use crate::prefiltered::{Basis, PrefilteredVariant, Rectification, Storage};
use crate::sampling::{
    fallback_buffers, fallback_pass, sampled_output, sampled_pass, samples_texture,
    sampling_invocations, unwarp_pass,
};

/// The per-frame condition of a projective frame (the frame set-up falls back to epipolar
/// when the epipole is on screen).
pub const PROJECTIVE_FRAME: &str = "frame.proj.x > 0.5 (a projective frame)";
/// The per-frame condition under which `scatter` binds the rasterised rectified map where
/// the standard shadow map goes.
pub const PROJECTIVE_WITHOUT_SHADOW_MAP: &str = "the frame is projective and the engine has no \
                                                 standard shadow map (the binding is not read \
                                                 then)";
/// Elements of the region-prefix depth bounds written by `prefilter`: one `vec2<f32>` (min,
/// max) per stored column and rectified row ([`stored_width`]), 32-bit so that the bound
/// tests compare the very depths the filter saw.
/// With `resume` a second plane of as many follows: per stored texel `(W, 0)`, the region's
/// weight sum up to the texel, from which `scatter` resumes the running means.
pub fn bounds_elements(v: &PrefilteredVariant) -> Formula {
    if v.resume {
        format!("2 * {} * rectified.height", stored_width(v))
    } else {
        format!("{} * rectified.height", stored_width(v))
    }
}

/// The binding at which `scatter` (and its sampled passes) reads the rectified map with
/// `resume` (the depths of the texels after a stored column).
pub const RESUME_RECTIFIED_BINDING: u32 = 10;

/// The columns `prefilter` stores per row: `rectified.width`, or with coarse filtered
/// columns (`filtered_stride = k > 1`) `ceil(rectified.width / k)` (the width is a multiple
/// of k, so the division is exact).
pub fn stored_width(v: &PrefilteredVariant) -> Formula {
    if v.filtered_stride == 1 {
        "rectified.width".to_owned()
    } else {
        format!("ceil(rectified.width / {})", v.filtered_stride)
    }
}
/// The engine's rasterised rectified map of projective variants.
pub const RECTIFIED_RASTER: &str = "rectified_raster";

/// The resources and passes of a variant, as `runtime/src/prefiltered.rs` creates them.
pub fn plan(v: &PrefilteredVariant) -> Plan {
    let mut parameters = screen_and_shadow_parameters();
    parameters.extend([
        Parameter {
            name: "rectified.width",
            description: "light rays per epipolar slice (columns of the rectified map), an \
                          engine choice (the demo uses 1024)",
            constraint: if v.filtered_stride == 1 {
                format!(
                    "regions^2 = {}..=max_texture_dimension_2d",
                    v.regions * v.regions
                )
            } else {
                format!(
                    "a multiple of filtered_stride = {} in filtered_stride x regions^2 = \
                     {}..=max_texture_dimension_2d",
                    v.filtered_stride,
                    v.min_rectified_width()
                )
            },
        },
        Parameter {
            name: "rectified.height",
            description: "epipolar slices (rows of the rectified map), an engine choice (the \
                          demo uses 1024)",
            constraint: TEXTURE_DIMENSION.into(),
        },
    ]);
    let [depth, shadow_map] = depth_and_shadow_map();
    let mut resources = vec![
        frame_buffer(
            "frame",
            "the uniform block of the frame (Rust: \
             scatter_shaderlib::prefiltered::FrameUniforms from prepare_frame), written once \
             per frame",
            None,
        ),
        frame_buffer(
            "slices",
            "one vec4 per rectified row: delta, theta_ref, theta_lo, theta_hi (Rust: \
             SliceParams from prepare_frame), written once per frame",
            Some("rectified.height"),
        ),
        depth,
        shadow_map,
        column_depth_buffer(),
        scatter_texture(
            "rectified",
            "rectified shadow map: normalised view angle of the first occluder per light ray \
             (written by rectify)",
            DEPTH_FORMAT,
            "rectified.width",
            "rectified.height",
        ),
        Resource {
            kind: "storage_buffer",
            buffer: Some(BufferDesc {
                elements: Some(filtered_elements(v)),
                usage: vec!["storage", "copy_src"],
            }),
            ..scatter_resource("filtered", filtered_description(v))
        },
        Resource {
            kind: "storage_buffer",
            buffer: Some(BufferDesc {
                elements: Some(bounds_elements(v)),
                usage: vec!["storage", "copy_src"],
            }),
            ..scatter_resource(
                "bounds",
                "per texel, the least and the greatest rectified depth over its region's \
                 prefix up to the texel (min, max), written by prefilter beside the filtered \
                 bases: scatter takes a region as wholly lit (ray depth <= min) or wholly \
                 shadowed (> max) without its Fourier estimate, so no light rings where none \
                 can arrive; a storage buffer of vec2<f32>, texel (x, row) at element x * \
                 rectified.height + row (column-major, as filtered's layers)",
            )
        },
        scatter_texture(
            "output",
            "in-scattered radiance, rgb, alpha 1 (written by scatter); add it to the \
             attenuated scene",
            OUTPUT_FORMAT,
            "screen.width",
            "screen.height",
        ),
    ];
    if v.rectification == Rectification::Projective {
        resources.push(Resource {
            provided_by: "engine",
            texture: Some(texture_2d(
                DEPTH_FORMAT,
                "rectified.width",
                "rectified.height",
                "1",
                SAMPLED,
            )),
            ..scatter_resource(
                RECTIFIED_RASTER,
                "projective frames only: the rectified depth map the engine rasterises with the \
                 frame's per-region matrices and viewports (Rust: FrameReport::projective from \
                 prepare_frame), clip depth in [0, 1]",
            )
        });
    }
    if v.cookie {
        parameters.extend(cookie_parameters());
        resources.push(cookie_texture());
    }
    resources.extend(samples_texture(&v.sampling_knobs()));
    resources.extend(fallback_buffers(&v.sampling_knobs()));
    // One pass per kernel shaderlib lists for the variant, in its order; a kernel this
    // module does not know gets no pass, and generation names it.
    let passes = v
        .kernel_params()
        .iter()
        .filter_map(|p| pass(v, p.kernel()))
        .collect();
    let mut notes = vec![
        "Run the passes in order; each reads what the previous ones wrote: put a \
             compute-to-compute memory barrier (and, in Vulkan, the image layout transition \
             from storage to sampled) between them.",
        "Write `frame` and `slices` once per frame before the first pass; the host code \
             that computes them is scatter_shaderlib::prefiltered::prepare_frame (Rust).",
        SLICE_FIT_NOTE,
        "Group 0 holds every binding; bind by group and binding number, not by name: \
             emitted names may be mangled (naga_oil) or carry a trailing `_` (naga).",
    ];
    if v.storage == Storage::Rgba16float {
        notes.push(
            "rgba16float storage: prefilter and scatter pack and unpack the filtered layers with \
             pack2x16float / unpack2x16float, so the device needs them in 32-bit shaders (wgpu: \
             DownlevelFlags::SHADER_F16_IN_F32, naga: SHADER_FLOAT16_IN_FLOAT32; Vulkan, Metal \
             and DX12 have it, GLSL ES 3.0 as packHalf2x16).",
        );
    }
    if v.filtered_stride > 1 {
        notes.push(
            "Coarse filtered columns (filtered_stride = k > 1): rectify still writes every \
             rectified column and prefilter filters every one of them, but filtered and bounds \
             hold only every k-th column's running mean (at its right edge), \
             rectified.width / k columns per row: in their layouts x counts the stored \
             columns and rectified.width reads rectified.width / k; the rectified width must \
             be a multiple of k, and in a projective \
             frame the region viewports (FrameReport::projective) start on multiples of k.",
        );
    }
    if v.resume {
        notes.push(
            "resume: bounds holds two planes of stored_width x rectified.height vec2<f32>: \
             (min, max) as without it, then (W, 0), the region's weight sum up to the texel, \
             at element stored_width * rectified.height + x * rectified.height + row; \
             scatter and its sampled passes also read the rectified map (binding 10) to \
             resume the running means from the stored column before a ray's end.",
        );
    }
    if v.rectification == Rectification::Projective {
        notes.push(
            "Projective variant: the frame set-up decides per frame (FrameReport::rectification) \
             whether the frame is projective or falls back to epipolar (FrameReport::fallback \
             says why: epipole or anti-epipole on screen, slices fanning out too wide). In a \
             projective frame skip `depth_columns`, `slice_fit` and `rectify`, rasterise \
             `rectified_raster` with the frame's \
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

/// The elements of the `filtered` storage buffer: one per layer of every rectified texel.
pub fn filtered_elements(v: &PrefilteredVariant) -> Formula {
    format!(
        "{} * {} * rectified.height",
        v.filtered_layers(),
        stored_width(v)
    )
}

/// The layout every description of `filtered` ends with (a macro, for `concat!`).
macro_rules! filtered_layout {
    () => {
        "; a storage buffer, layer q of rectified texel (x, row) at element (q * \
         rectified.width + x) * rectified.height + row (column-major layers: prefilter's \
         invocations, one per row, store side by side; rgba32float row-major, (q * \
         rectified.height + row) * rectified.width + x), each element the bits of one texel \
         of the storage format (rgba8unorm: a u32 from pack4x8unorm; rgba16float: two u32 from \
         pack2x16float; rgba32float: four f32)"
    };
}

/// What the `filtered` buffer holds for the variant's basis (and cookie), and its layout.
fn filtered_description(v: &PrefilteredVariant) -> &'static str {
    match (v.basis, v.moments, v.cookie) {
        (Basis::Fourier, _, true) => {
            concat!(
                "per colour channel c, the filtered Fourier bases times the spot's cookie, four \
             per layer, in layers c * bases / 4 .., stored as F / 2 + 0.5; the region's mean \
             cookie (rgb) in the last layer (written by prefilter)",
                filtered_layout!()
            )
        }
        (Basis::Moments, _, true) => {
            concat!(
                "per colour channel c, the filtered power moments of z = (2 d - lo - hi) / max(hi - lo, 0.1) ([lo, hi] the region's depth range, \
             bounds at its last stored column) times the spot's \
             cookie in layers c * ceil(moments / 4) .., stored as they are; the region's mean \
             cookie (rgb) in the last layer (written by prefilter)",
                filtered_layout!()
            )
        }
        (Basis::Fourier, _, false) => {
            concat!(
                "filtered Fourier bases, four per layer, stored as F / 2 + 0.5 (written by \
             prefilter)",
                filtered_layout!()
            )
        }
        (Basis::Moments, 6, false) => {
            concat!(
                "filtered power moments of z = (2 d - lo - hi) / max(hi - lo, 0.1) ([lo, hi] the region's depth range, \
             bounds at its last stored column), (z, z^2, z^3, z^4) in layer 0 and \
             (z^5, z^6, 0, 0) in layer 1, stored as they are (written by prefilter)",
                filtered_layout!()
            )
        }
        (Basis::Moments, _, false) => {
            concat!(
                "filtered power moments of z = (2 d - lo - hi) / max(hi - lo, 0.1) ([lo, hi] the region's depth range, \
             bounds at its last stored column), (z, z^2, z^3, z^4), stored as they are \
             (written by prefilter)",
                filtered_layout!()
            )
        }
    }
}

/// The pass of one kernel, or `None` for a kernel that is not in this family.
pub fn pass(v: &PrefilteredVariant, kernel: Kernel) -> Option<PassPlan> {
    let f = |s: &str| s.to_owned();
    let projective = v.rectification == Rectification::Projective;
    match kernel {
        Kernel::DepthColumns => Some(PassPlan {
            kernel,
            invocations: [f("screen.width"), f("1"), f("1")],
            skip_when: projective.then_some(PROJECTIVE_FRAME),
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "depth"), bind(2, "column_depth")],
        }),
        Kernel::SliceFit => Some(PassPlan {
            kernel,
            invocations: [f("256"), f("1"), f("1")],
            skip_when: projective.then_some(PROJECTIVE_FRAME),
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "slices"), bind(2, "column_depth")],
        }),
        Kernel::Rectify => Some(PassPlan {
            kernel,
            invocations: [rectify_columns(), f("rectified.height"), f("1")],
            skip_when: projective.then_some(PROJECTIVE_FRAME),
            indirect: None,
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
            indirect: None,
            bindings: [
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
                bind(4, "bounds"),
            ]
            .into_iter()
            .chain(v.cookie.then(|| bind(COOKIE_BINDING, "cookie")))
            .collect(),
        }),
        Kernel::Scatter => Some(sampled_pass(
            &v.sampling_knobs(),
            PassPlan {
                kernel,
                invocations: sampling_invocations(&v.sampling_knobs()),
                skip_when: None,
                indirect: None,
                bindings: [
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
                    bind(5, sampled_output(&v.sampling_knobs())),
                    bind(6, "bounds"),
                ]
                .into_iter()
                .chain(v.resume.then_some(BindingSource {
                    binding: RESUME_RECTIFIED_BINDING,
                    resource: "rectified",
                    alternative: projective.then_some(Alternative {
                        resource: RECTIFIED_RASTER,
                        when: PROJECTIVE_FRAME,
                    }),
                }))
                .chain(v.cookie.then(|| bind(COOKIE_BINDING, "cookie")))
                .collect(),
            },
            7,
        )),
        Kernel::ScatterUnwarp => {
            pass(v, Kernel::Scatter).map(|p| unwarp_pass(p, kernel, 7, &v.sampling_knobs()))
        }
        Kernel::ScatterFallback => pass(v, Kernel::Scatter).map(|p| fallback_pass(p, kernel, 7)),
        _ => None,
    }
}

/// The `rectify` pass's invocations along x: each stores
/// [`RECTIFY_TEXELS`](super::kernels::RECTIFY_TEXELS) columns of a row.
pub fn rectify_columns() -> Formula {
    format!("ceil(rectified.width / {})", super::kernels::RECTIFY_TEXELS)
}
