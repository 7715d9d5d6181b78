//! The plan of a `hybrid_volume` variant: its textures and buffers and its passes
//! (`depth_columns`, `slice_fit`, `rectify`, `volume_bounds`, `volume_march`). `scatter-gen`
//! writes it into the manifest; `scatter-runtime` builds and dispatches from it.

use crate::Kernel;
use crate::family::KernelFamily;
use crate::hybrid_volume::HybridVolumeVariant;
use crate::plan::{
    BufferDesc, COOKIE_BINDING, DEPTH_FORMAT, OUTPUT_FORMAT, Parameter, PassPlan, Plan, Resource,
    SLICE_FIT_NOTE, TEXTURE_DIMENSION, bind, column_depth_buffer, cookie_parameters,
    cookie_texture, depth_and_shadow_map, frame_buffer, scatter_resource, scatter_texture,
    screen_and_shadow_parameters,
};
use crate::sampling::{
    fallback_buffers, fallback_pass, sampled_output, sampled_pass, samples_texture,
    sampling_invocations, unwarp_pass,
};

/// The `crossings` buffer: two `u32` per (rectified row, depth bin).
fn crossings_buffer(v: &HybridVolumeVariant) -> Resource {
    Resource {
        kind: "storage_buffer",
        buffer: Some(BufferDesc {
            elements: Some(format!("{} * rectified.height", 2 * v.bins)),
            usage: vec!["storage", "copy_src"],
        }),
        ..scatter_resource(
            "crossings",
            "per rectified row and ray-depth bin (u32 pair at 2 (row * bins + bin)), the \
             first and last column edge where the shadow volume's boundary crosses a ray of \
             that depth (first = 0xffffffff: none); written by volume_bounds, read by \
             volume_march",
        )
    }
}

/// The resources and passes of a variant, as `runtime/src/hybrid_volume.rs` creates them.
pub fn plan(v: &HybridVolumeVariant) -> Plan {
    let dim = TEXTURE_DIMENSION;
    let mut parameters = screen_and_shadow_parameters();
    parameters.extend([
        Parameter {
            name: "rectified.width",
            description: "light rays per epipolar slice (columns of the rectified map), an \
                          engine choice",
            constraint: dim.into(),
        },
        Parameter {
            name: "rectified.height",
            description: "epipolar slices (rows of the rectified map), an engine choice",
            constraint: dim.into(),
        },
    ]);
    let [depth, shadow_map] = depth_and_shadow_map();
    let mut resources = vec![
        frame_buffer(
            "frame",
            "the uniform block of the frame (Rust: scatter_frame::frame::FrameUniforms from \
             scatter_frame::hybrid_volume::prepare_hybrid_volume), written once per frame",
            None,
        ),
        frame_buffer(
            "slices",
            "one vec4 per rectified row: delta, theta_ref, theta_lo, theta_hi (Rust: \
             SliceParams from prepare_hybrid_volume), written once per frame",
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
        crossings_buffer(v),
        scatter_texture(
            "output",
            "in-scattered radiance, rgb, alpha 1 (written by volume_march); add it to the \
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
             that computes them is scatter_frame::hybrid_volume::prepare_hybrid_volume (Rust): \
             the prefiltered family's prepare_frame with an epipolar one-region variant of \
             the same light. `depth_columns`, `slice_fit` and `rectify` are the prefiltered \
             family's kernels.",
            SLICE_FIT_NOTE,
            "Group 0 holds every binding; bind by group and binding number, not by name: \
             emitted names may be mangled (naga_oil) or carry a trailing `_` (naga).",
        ],
    }
}

/// The pass of one kernel, or `None` for a kernel that is not in this family.
pub fn pass(v: &HybridVolumeVariant, kernel: Kernel) -> Option<PassPlan> {
    let f = |s: &str| s.to_owned();
    match kernel {
        Kernel::DepthColumns | Kernel::SliceFit | Kernel::Rectify => {
            crate::minmax::plan::pass(&crate::minmax::MinmaxVariant::default(), kernel)
        }
        Kernel::VolumeBounds => Some(PassPlan {
            kernel,
            invocations: [f("64"), f("rectified.height"), f("1")],
            skip_when: None,
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "rectified"), bind(2, "crossings")],
        }),
        Kernel::VolumeMarch => Some(sampled_pass(
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
                    bind(4, "rectified"),
                    bind(5, "crossings"),
                    bind(6, sampled_output(&v.sampling_knobs())),
                ]
                .into_iter()
                .chain(v.cookie.then(|| bind(COOKIE_BINDING, "cookie")))
                .collect(),
            },
            7,
        )),
        Kernel::VolumeMarchUnwarp => {
            pass(v, Kernel::VolumeMarch).map(|p| unwarp_pass(p, kernel, 7, &v.sampling_knobs()))
        }
        Kernel::VolumeMarchFallback => {
            pass(v, Kernel::VolumeMarch).map(|p| fallback_pass(p, kernel, 7))
        }
        _ => None,
    }
}
