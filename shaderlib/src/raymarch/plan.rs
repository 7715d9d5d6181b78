//! The plan of a `raymarch` variant: its textures and buffers and its passes (`raymarch`,
//! then `interleave_sum` when interleaved). `scatter-gen` writes it into the manifest;
//! `scatter-runtime` builds and dispatches from it.

use crate::plan::{
    COOKIE_BINDING, OUTPUT_FORMAT, PassPlan, Plan, bind, cookie_parameters, cookie_texture,
    depth_and_shadow_map, frame_buffer, scatter_texture, screen_and_shadow_parameters,
};
use crate::raymarch::{PARTIAL_FORMAT, RaymarchVariant};
use crate::sampling::{
    fallback_buffers, fallback_pass, sampled_output, sampled_pass, samples_texture,
    sampling_invocations, unwarp_pass,
};
use crate::{Kernel, KernelParams};

/// The resources and passes of a variant, as `runtime/src/raymarch.rs` creates them.
pub fn plan(v: &RaymarchVariant) -> Plan {
    let mut parameters = screen_and_shadow_parameters();
    if v.cookie {
        parameters.extend(cookie_parameters());
    }
    let [depth, shadow_map] = depth_and_shadow_map();
    let mut resources = vec![
        frame_buffer(
            "frame",
            "the uniform block of the frame (Rust: scatter_frame::raymarch::RaymarchUniforms from \
             prepare_raymarch), written once per frame",
            None,
        ),
        depth,
        shadow_map,
        scatter_texture(
            "output",
            "in-scattered radiance, rgb, alpha 1; add it to the attenuated scene",
            OUTPUT_FORMAT,
            "screen.width",
            "screen.height",
        ),
    ];
    if v.cookie {
        resources.push(cookie_texture());
    }
    resources.extend(samples_texture(&v.sampling_knobs()));
    resources.extend(fallback_buffers(&v.sampling_knobs()));
    if v.interleaved() {
        resources.push(scatter_texture(
            "partial",
            "each pixel's partial sum over its interleaving class (written by raymarch, read \
             by interleave_sum)",
            PARTIAL_FORMAT,
            "screen.width",
            "screen.height",
        ));
    }
    let passes = KernelParams::raymarch(*v)
        .iter()
        .filter_map(|p| pass(v, p.kernel()))
        .collect();
    Plan {
        parameters,
        resources,
        passes,
        notes: vec![
            "Run the passes in order with a compute-to-compute memory barrier between them.",
            "Write `frame` once per frame before the first pass; the host code that computes \
             it is scatter_frame::raymarch::prepare_raymarch (Rust).",
            "Group 0 holds every binding; bind by group and binding number, not by name.",
        ],
    }
}

/// The pass of one kernel, or `None` for a kernel that is not in this family.
pub fn pass(v: &RaymarchVariant, kernel: Kernel) -> Option<PassPlan> {
    let screen = || ["screen.width".into(), "screen.height".into(), "1".into()];
    match kernel {
        Kernel::Raymarch => Some(sampled_pass(
            &v.sampling_knobs(),
            PassPlan {
                kernel,
                invocations: sampling_invocations(&v.sampling_knobs()),
                skip_when: None,
                indirect: None,
                bindings: [
                    bind(0, "frame"),
                    bind(1, "depth"),
                    bind(2, "shadow_map"),
                    bind(
                        3,
                        if v.interleaved() {
                            "partial"
                        } else {
                            sampled_output(&v.sampling_knobs())
                        },
                    ),
                ]
                .into_iter()
                .chain(v.cookie.then(|| bind(COOKIE_BINDING, "cookie")))
                .collect(),
            },
            4,
        )),
        Kernel::RaymarchUnwarp => {
            pass(v, Kernel::Raymarch).map(|p| unwarp_pass(p, kernel, 4, &v.sampling_knobs()))
        }
        Kernel::RaymarchFallback => pass(v, Kernel::Raymarch).map(|p| fallback_pass(p, kernel, 4)),
        Kernel::InterleaveSum => Some(PassPlan {
            kernel,
            invocations: screen(),
            skip_when: None,
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "partial"), bind(2, "output")],
        }),
        _ => None,
    }
}
