//! The plan of a `partial_sum_tree` variant: its textures and buffers and its passes
//! (`depth_columns`, `slice_fit`, `rectify`, `pst_sweep`, `pst_sweep_unwarp`,
//! `pst_sweep_fallback`). `scatter-gen` writes it into the manifest; `scatter-runtime` builds
//! and dispatches from it.

use crate::Kernel;
use crate::family::KernelFamily;
use crate::partial_sum_tree::{
    COOKIE_BINDING, FACTOR_VECS, PartialSumTreeVariant, SAMPLED_BINDING, TREES,
};
use crate::plan::{
    BufferDesc, DEPTH_FORMAT, OUTPUT_FORMAT, Parameter, PassPlan, Plan, Resource, SLICE_FIT_NOTE,
    TEXTURE_DIMENSION, bind, column_depth_buffer, cookie_parameters, cookie_texture,
    depth_and_shadow_map, frame_buffer, scatter_resource, scatter_texture,
    screen_and_shadow_parameters,
};
use crate::sampling::{
    fallback_buffers, fallback_pass, sampled_output, sampled_pass, samples_texture,
    sampling_invocations_with_lanes, unwarp_pass,
};

/// The sweep's scratch buffers (bound by `pst_sweep` only).
pub const SCRATCH: [&str; 3] = ["pst_leaves", "pst_tree", "pst_columns"];

/// A storage buffer scatter allocates, of `elements` entries (the stride is the kernel's).
fn scratch(name: &'static str, contents: &'static str, elements: String) -> Resource {
    Resource {
        kind: "storage_buffer",
        buffer: Some(BufferDesc {
            elements: Some(elements),
            usage: vec!["storage"],
        }),
        ..scatter_resource(name, contents)
    }
}

/// The resources and passes of a variant, as `runtime/src/partial_sum_tree.rs` creates them.
pub fn plan(v: &PartialSumTreeVariant) -> Plan {
    let dim = TEXTURE_DIMENSION;
    let mut parameters = screen_and_shadow_parameters();
    parameters.extend([
        Parameter {
            name: "rectified.width",
            description: "light rays per epipolar slice (columns of the rectified map, the \
                          leaves of each sweep), an engine choice",
            constraint: dim.into(),
        },
        Parameter {
            name: "rectified.height",
            description: "rows of the rectified map (each sample slice sweeps the row its \
                          farthest sample lies in), an engine choice",
            constraint: dim.into(),
        },
    ]);
    let [depth, shadow_map] = depth_and_shadow_map();
    // vec4s per leaf and tree entry (three channels of the rank's with a cookie).
    let rv = v.leaf_vecs();
    let mut resources = vec![
        frame_buffer(
            "frame",
            "the uniform block of the frame (Rust: scatter_frame::frame::FrameUniforms from \
             scatter_frame::partial_sum_tree::prepare_partial_sum_tree), written once per frame",
            None,
        ),
        frame_buffer(
            "slices",
            "one vec4 per rectified row: delta, theta_ref, theta_lo, theta_hi (Rust: \
             SliceParams from prepare_partial_sum_tree), written once per frame",
            Some("rectified.height"),
        ),
        frame_buffer(
            "pst_factors",
            "the rank-r factors of the frame's separable integrand: a header vec4 (v_max, \
             theta_lo, theta_hi, rank), then gamma and beta at 96 grid nodes, two vec4 per \
             node (Rust: PartialSumTreeFrame::factors from prepare_partial_sum_tree), written \
             once per frame",
            Some(&FACTOR_VECS.to_string()),
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
        scratch(
            "pst_leaves",
            "the sweep's scratch: every slice's column leaves (written and read by pst_sweep)",
            format!("{} * rectified.width", v.slices * rv),
        ),
        scratch(
            "pst_tree",
            "the sweep's scratch: every slice's 8 Fenwick trees over its queries and the \
             queries' partial sums (written and read by pst_sweep)",
            (v.slices * (TREES + 1) * v.slice_samples * rv).to_string(),
        ),
        scratch(
            "pst_columns",
            "the sweep's scratch: how many of its slice's queries see each column lit \
             (written and read by pst_sweep)",
            format!("{} * rectified.width", v.slices),
        ),
        scatter_texture(
            "output",
            "in-scattered radiance, rgb, alpha 1 (written by pst_sweep_unwarp and \
             pst_sweep_fallback); add it to the attenuated scene",
            OUTPUT_FORMAT,
            "screen.width",
            "screen.height",
        ),
    ];
    if v.cookie {
        parameters.extend(cookie_parameters());
        resources.push(cookie_texture());
    }
    resources.extend(samples_texture(&v.sampling_knobs()));
    resources.extend(fallback_buffers(&v.sampling_knobs()));
    let passes = v
        .kernel_params()
        .iter()
        .filter_map(|p| pass(v, p.kernel()))
        .collect();
    Plan {
        parameters,
        resources,
        passes,
        notes: vec![
            "Run the passes in order; each reads what the previous ones wrote: put a \
             compute-to-compute memory barrier (and, in Vulkan, the image layout transition \
             from storage to sampled) between them.",
            "Write `frame`, `slices` and `pst_factors` once per frame before the first pass; \
             the host code that computes them is \
             scatter_frame::partial_sum_tree::prepare_partial_sum_tree (Rust): the prefiltered \
             family's prepare_frame with an epipolar one-region variant of the same light, \
             and the rank-r SVD of the integrand over the frame's view angles. \
             `depth_columns`, `slice_fit` and `rectify` are the prefiltered family's kernels.",
            SLICE_FIT_NOTE,
            "Group 0 holds every binding; bind by group and binding number, not by name: \
             emitted names may be mangled (naga_oil) or carry a trailing `_` (naga).",
        ],
    }
}

/// The pass of one kernel, or `None` for a kernel that is not in this family.
pub fn pass(v: &PartialSumTreeVariant, kernel: Kernel) -> Option<PassPlan> {
    let f = |s: &str| s.to_owned();
    let knobs = v.sampling_knobs();
    match kernel {
        Kernel::DepthColumns => Some(PassPlan {
            kernel,
            invocations: [f("screen.width"), f("1"), f("1")],
            skip_when: None,
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "depth"), bind(2, "column_depth")],
        }),
        Kernel::SliceFit => Some(PassPlan {
            kernel,
            invocations: [f("256"), f("1"), f("1")],
            skip_when: None,
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "slices"), bind(2, "column_depth")],
        }),
        Kernel::Rectify => Some(PassPlan {
            kernel,
            invocations: [
                crate::prefiltered::plan::rectify_columns(),
                f("rectified.height"),
                f("1"),
            ],
            skip_when: None,
            indirect: None,
            bindings: vec![
                bind(0, "frame"),
                bind(1, "slices"),
                bind(2, "shadow_map"),
                bind(3, "rectified"),
            ],
        }),
        Kernel::PstSweep => Some(sampled_pass(
            &knobs,
            PassPlan {
                kernel,
                invocations: sampling_invocations_with_lanes(&knobs, super::SWEEP_LANES),
                skip_when: None,
                indirect: None,
                bindings: [
                    bind(0, "frame"),
                    bind(1, "slices"),
                    bind(2, "depth"),
                    bind(3, "shadow_map"),
                    bind(4, "rectified"),
                    bind(5, "pst_factors"),
                    bind(6, "pst_leaves"),
                    bind(7, "pst_tree"),
                    bind(8, "pst_columns"),
                    bind(9, sampled_output(&knobs)),
                ]
                .into_iter()
                .chain(v.cookie.then(|| bind(COOKIE_BINDING, "cookie")))
                .collect(),
            },
            SAMPLED_BINDING,
        )),
        Kernel::PstSweepUnwarp => pass(v, Kernel::PstSweep)
            .map(|p| unwarp_pass(p, kernel, SAMPLED_BINDING, &v.sampling_knobs())),
        Kernel::PstSweepFallback => pass(v, Kernel::PstSweep).map(|p| {
            let mut p = fallback_pass(p, kernel, SAMPLED_BINDING);
            p.bindings.retain(|b| !SCRATCH.contains(&b.resource));
            p
        }),
        _ => None,
    }
}
