//! The plan of a `minmax` variant: its textures and buffers and its passes (`depth_columns`,
//! `slice_fit`, `rectify`, `minmax_build`, `minmax_traverse`). `scatter-gen` writes it into the manifest;
//! `scatter-runtime` builds and dispatches from it.

use crate::Kernel;
use crate::family::KernelFamily;
use crate::minmax::{MinmaxVariant, TREE_FORMAT};
use crate::plan::{
    COOKIE_BINDING, DEPTH_FORMAT, OUTPUT_FORMAT, Parameter, PassPlan, Plan, SLICE_FIT_NOTE,
    TEXTURE_DIMENSION, bind, column_depth_buffer, cookie_parameters, cookie_texture,
    depth_and_shadow_map, frame_buffer, scatter_texture, screen_and_shadow_parameters,
};
use crate::sampling::{
    fallback_buffers, fallback_pass, sampled_output, sampled_pass, samples_texture,
    sampling_invocations, unwarp_pass,
};

/// The resources and passes of a variant, as `runtime/src/minmax.rs` creates them.
pub fn plan(v: &MinmaxVariant) -> Plan {
    let dim = TEXTURE_DIMENSION;
    let mut parameters = screen_and_shadow_parameters();
    parameters.extend([
        Parameter {
            name: "rectified.width",
            description: "light rays per epipolar slice (columns of the rectified map), an \
                          engine choice (tree.width, derived from it, has its own constraint)",
            constraint: dim.into(),
        },
        Parameter {
            name: "rectified.height",
            description: "epipolar slices (rows of the rectified map), an engine choice",
            constraint: dim.into(),
        },
        Parameter {
            name: "tree.width",
            description: "columns of the min-max tree texture, derived: the sum over levels \
                          k = 0, 1, ... of ceil(rectified.width / 2^k) down to the single \
                          root (Rust: scatter_frame::minmax::tree_width; at most \
                          2 rectified.width + log2(rectified.width) + 1)",
            constraint: dim.into(),
        },
    ]);
    let [depth, shadow_map] = depth_and_shadow_map();
    let mut resources = vec![
        frame_buffer(
            "frame",
            "the uniform block of the frame (Rust: scatter_frame::frame::FrameUniforms from \
             scatter_frame::minmax::prepare_minmax), written once per frame",
            None,
        ),
        frame_buffer(
            "slices",
            "one vec4 per rectified row: delta, theta_ref, theta_lo, theta_hi (Rust: \
             SliceParams from prepare_minmax), written once per frame",
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
        scatter_texture(
            "tree",
            "the 1D min-max tree of every rectified row, levels packed left to right (level \
             k: ceil(rectified.width / 2^k) nodes of (min, max)); written by minmax_build",
            TREE_FORMAT,
            "tree.width",
            "rectified.height",
        ),
        scatter_texture(
            "output",
            "in-scattered radiance, rgb, alpha 1 (written by minmax_traverse); add it to the \
             attenuated scene",
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
            "Write `frame` and `slices` once per frame before the first pass; the host code \
             that computes them is scatter_frame::minmax::prepare_minmax (Rust): the \
             prefiltered family's prepare_frame with an epipolar one-region variant of the \
             same light. `depth_columns`, `slice_fit` and `rectify` are the prefiltered family's kernels.",
            SLICE_FIT_NOTE,
            "Group 0 holds every binding; bind by group and binding number, not by name: \
             emitted names may be mangled (naga_oil) or carry a trailing `_` (naga).",
        ],
    }
}

/// The pass of one kernel, or `None` for a kernel that is not in this family.
pub fn pass(v: &MinmaxVariant, kernel: Kernel) -> Option<PassPlan> {
    let f = |s: &str| s.to_owned();
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
        Kernel::MinmaxBuild => Some(PassPlan {
            kernel,
            invocations: [f("128"), f("rectified.height"), f("1")],
            skip_when: None,
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "rectified"), bind(2, "tree")],
        }),
        Kernel::MinmaxTraverse => Some(sampled_pass(
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
                    bind(3, "shadow_map"),
                    bind(4, "tree"),
                    bind(5, sampled_output(&v.sampling_knobs())),
                ]
                .into_iter()
                .chain(v.cookie.then(|| bind(COOKIE_BINDING, "cookie")))
                .collect(),
            },
            6,
        )),
        Kernel::MinmaxTraverseUnwarp => {
            pass(v, Kernel::MinmaxTraverse).map(|p| unwarp_pass(p, kernel, 6, &v.sampling_knobs()))
        }
        Kernel::MinmaxTraverseFallback => {
            pass(v, Kernel::MinmaxTraverse).map(|p| fallback_pass(p, kernel, 6))
        }
        _ => None,
    }
}
