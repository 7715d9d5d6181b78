//! The plan of an `area_ivsv` variant: its textures and buffers and its passes
//! (`ivsv_rectify`, `ivsv_scan`, `ivsv_gather`, then `ivsv_interleave_sum` when
//! interleaved, or `ivsv_gather_unwarp` and `ivsv_gather_fallback` with `sampling =
//! epipolar`), from which `scatter-runtime` builds and dispatches.

use crate::area_ivsv::AreaIvsvVariant;
use crate::plan::{
    BufferDesc, DEPTH_FORMAT, OUTPUT_FORMAT, PassPlan, Plan, Resource, SAMPLED, bind,
    depth_and_shadow_map, frame_buffer, scatter_resource, scatter_texture,
    screen_and_shadow_parameters, texture_2d,
};
use crate::sampling::{
    fallback_buffers, fallback_pass, sampled_output, sampled_pass, samples_texture,
    sampling_invocations, unwarp_pass,
};
use crate::{Kernel, KernelParams};

/// A voxel buffer (`marks`, `volume`): four `u32` per texel of every VPL's grid.
fn voxel_buffer(v: &AreaIvsvVariant, name: &'static str, contents: &'static str) -> Resource {
    Resource {
        kind: "storage_buffer",
        buffer: Some(BufferDesc {
            elements: Some(format!("{}", 4 * v.vpls * v.alpha * v.theta)),
            usage: vec!["storage", "copy_src"],
        }),
        ..scatter_resource(name, contents)
    }
}

/// The resources and passes of a variant, as `runtime/src/area_ivsv.rs` creates them.
pub fn plan(v: &AreaIvsvVariant) -> Plan {
    // The shared parameters; `shadow.size` is the side of every VPL's map here.
    let mut parameters = screen_and_shadow_parameters();
    for p in &mut parameters {
        if p.name == "shadow.size" {
            p.description = "side of every VPL's square standard shadow map in texels";
        }
    }
    let [depth, _] = depth_and_shadow_map();
    let vpls = v.vpls.to_string();
    let mut resources = vec![
        frame_buffer(
            "frame",
            "the uniform block of the frame (Rust: scatter_frame::area_ivsv::IvsvUniforms from \
             prepare_area_ivsv), written once per frame",
            None,
        ),
        frame_buffer(
            "vpls",
            "one record per VPL (a uniform array of the variant's `vpls`): position, \
             intensity, epipolar grid, cone, shadow map (Rust: VplRecord from \
             prepare_area_ivsv), written once per frame",
            None,
        ),
        depth,
        Resource {
            provided_by: "engine",
            texture: Some(texture_2d(
                DEPTH_FORMAT,
                "shadow.size",
                "shadow.size",
                &vpls,
                SAMPLED,
            )),
            ..scatter_resource(
                "vpl_maps",
                "one standard shadow map per VPL (layer = VPL index): normalised linear light \
                 depth of the VPL's perspective map (1 where nothing was hit)",
            )
        },
        voxel_buffer(
            v,
            "marks",
            "per VPL, theta row and alpha texel, 128 phi bits: where a light ray's shadow \
             starts (written by ivsv_rectify with atomicOr, zeroed by ivsv_scan; zero when \
             created)",
        ),
        voxel_buffer(
            v,
            "volume",
            "the extruded voxel bits (written by ivsv_scan, read by ivsv_gather)",
        ),
        scatter_texture(
            "output",
            "in-scattered radiance, rgb, alpha 1 (written by ivsv_gather, or \
             ivsv_interleave_sum when interleaved); add it to the attenuated scene",
            OUTPUT_FORMAT,
            "screen.width",
            "screen.height",
        ),
    ];
    if v.interleave > 1 {
        resources.push(scatter_texture(
            "partial",
            "per pixel the share of its interleaving class's VPLs (written by ivsv_gather, \
             summed over each pixel's window by ivsv_interleave_sum)",
            "rgba32float",
            "screen.width",
            "screen.height",
        ));
    }
    resources.extend(samples_texture(&v.sampling_knobs()));
    resources.extend(fallback_buffers(&v.sampling_knobs()));
    let passes = KernelParams::area_ivsv(*v)
        .iter()
        .filter_map(|p| pass(v, p.kernel()))
        .collect();
    Plan {
        parameters,
        resources,
        passes,
        notes: vec![
            "Run the passes in order; each reads what the previous ones wrote: put a \
             compute-to-compute memory barrier between them.",
            "Write `frame` and `vpls` once per frame before the first pass (Rust: \
             scatter_frame::area_ivsv::prepare_area_light from the camera, the area light, the \
             medium and the standard shadow map of the light's point limit, a perspective map \
             of `shadow.size` at its centre; it places the VPLs and gives each one's \
             shadow-map frame). Render every VPL's shadow map with its frame into its layer of \
             `vpl_maps` first.",
            "`marks` must be zero when created (WebGPU buffers are); `ivsv_scan` leaves it zero \
             for the next frame.",
            "Group 0 holds every binding; bind by group and binding number, not by name: \
             emitted names may be mangled (naga_oil) or carry a trailing `_` (naga).",
        ],
    }
}

/// The pass of one kernel, or `None` for a kernel that is not in this family.
pub fn pass(v: &AreaIvsvVariant, kernel: Kernel) -> Option<PassPlan> {
    let f = |s: &str| s.to_owned();
    match kernel {
        Kernel::IvsvRectify => Some(PassPlan {
            kernel,
            invocations: [f("128"), v.theta.to_string(), v.vpls.to_string()],
            skip_when: None,
            indirect: None,
            bindings: vec![
                bind(0, "frame"),
                bind(1, "vpls"),
                bind(2, "vpl_maps"),
                bind(3, "marks"),
            ],
        }),
        Kernel::IvsvScan => Some(PassPlan {
            kernel,
            invocations: [(4 * v.theta).to_string(), v.vpls.to_string(), f("1")],
            skip_when: None,
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "marks"), bind(2, "volume")],
        }),
        Kernel::IvsvGather => Some(sampled_pass(
            &v.sampling_knobs(),
            PassPlan {
                kernel,
                invocations: sampling_invocations(&v.sampling_knobs()),
                skip_when: None,
                indirect: None,
                bindings: vec![
                    bind(0, "frame"),
                    bind(1, "vpls"),
                    bind(2, "volume"),
                    bind(3, "depth"),
                    bind(
                        4,
                        if v.interleave > 1 {
                            "partial"
                        } else {
                            sampled_output(&v.sampling_knobs())
                        },
                    ),
                ],
            },
            5,
        )),
        Kernel::IvsvGatherUnwarp => {
            pass(v, Kernel::IvsvGather).map(|p| unwarp_pass(p, kernel, 5, &v.sampling_knobs()))
        }
        Kernel::IvsvGatherFallback => {
            pass(v, Kernel::IvsvGather).map(|p| fallback_pass(p, kernel, 5))
        }
        Kernel::IvsvInterleaveSum if v.interleave > 1 => Some(PassPlan {
            kernel,
            invocations: [f("screen.width"), f("screen.height"), f("1")],
            skip_when: None,
            indirect: None,
            bindings: vec![bind(0, "frame"), bind(1, "partial"), bind(2, "output")],
        }),
        _ => None,
    }
}
