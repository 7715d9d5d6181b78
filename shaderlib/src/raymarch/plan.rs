//! The plan of a `raymarch` variant: its textures and buffers and its passes (`raymarch`,
//! then `interleave_sum` when interleaved). `scatter-gen` writes it into the manifest;
//! `scatter-runtime` builds and dispatches from it.

use crate::plan::{
    BindingSource, BufferDesc, DEPTH_FORMAT, OUTPUT_FORMAT, Parameter, PassPlan, Plan, Resource,
    TextureDesc,
};
use crate::raymarch::{PARTIAL_FORMAT, RaymarchVariant};
use crate::{Kernel, KernelParams};

fn texture(format: &str, usage: &[&'static str]) -> TextureDesc {
    TextureDesc {
        format: format.to_owned(),
        dimension: "2d",
        width: "screen.width".into(),
        height: "screen.height".into(),
        layers: "1".into(),
        mip_levels: 1,
        usage: usage.to_vec(),
    }
}

fn bind(binding: u32, resource: &'static str) -> BindingSource {
    BindingSource {
        binding,
        resource,
        alternative: None,
    }
}

/// The resources and passes of a variant, as `runtime/src/raymarch.rs` creates them.
pub fn plan(v: &RaymarchVariant) -> Plan {
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
    ];
    let mut resources = vec![
        Resource {
            name: "march",
            kind: "uniform_buffer",
            provided_by: "scatter",
            contents: "the uniform block of the frame (Rust: \
                       scatter_frame::raymarch::MarchUniforms from prepare_march), written \
                       once per frame",
            texture: None,
            buffer: Some(BufferDesc {
                elements: None,
                usage: vec!["uniform", "copy_dst"],
            }),
            sampler: None,
        },
        Resource {
            name: "depth",
            kind: "texture",
            provided_by: "engine",
            contents: "linear view depth per pixel (far plane distance for sky)",
            texture: Some(texture(DEPTH_FORMAT, &["texture_binding"])),
            buffer: None,
            sampler: None,
        },
        Resource {
            name: "shadow_map",
            kind: "texture",
            provided_by: "engine",
            contents: "standard shadow map: normalised linear light depth, 1 where nothing was \
                       hit, texel (0, 0) top-left",
            texture: Some(TextureDesc {
                width: "shadow.size".into(),
                height: "shadow.size".into(),
                ..texture(DEPTH_FORMAT, &["texture_binding"])
            }),
            buffer: None,
            sampler: None,
        },
        Resource {
            name: "output",
            kind: "texture",
            provided_by: "scatter",
            contents: "in-scattered radiance, rgb, alpha 1; add it to the attenuated scene",
            texture: Some(texture(
                OUTPUT_FORMAT,
                &["storage_binding", "texture_binding"],
            )),
            buffer: None,
            sampler: None,
        },
    ];
    if v.interleaved() {
        resources.push(Resource {
            name: "partial",
            kind: "texture",
            provided_by: "scatter",
            contents: "each pixel's partial sum over its interleaving class (written by \
                       raymarch, read by interleave_sum)",
            texture: Some(texture(
                PARTIAL_FORMAT,
                &["storage_binding", "texture_binding"],
            )),
            buffer: None,
            sampler: None,
        });
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
            "Write `march` once per frame before the first pass; the host code that computes \
             it is scatter_frame::raymarch::prepare_march (Rust).",
            "Group 0 holds every binding; bind by group and binding number, not by name.",
        ],
    }
}

/// The pass of one kernel, or `None` for a kernel that is not in this family.
pub fn pass(v: &RaymarchVariant, kernel: Kernel) -> Option<PassPlan> {
    let screen = || ["screen.width".into(), "screen.height".into(), "1".into()];
    match kernel {
        Kernel::Raymarch => Some(PassPlan {
            kernel,
            invocations: screen(),
            skip_when: None,
            bindings: vec![
                bind(0, "march"),
                bind(1, "depth"),
                bind(2, "shadow_map"),
                bind(3, if v.interleaved() { "partial" } else { "output" }),
            ],
        }),
        Kernel::InterleaveSum => Some(PassPlan {
            kernel,
            invocations: screen(),
            skip_when: None,
            bindings: vec![bind(0, "march"), bind(1, "partial"), bind(2, "output")],
        }),
        _ => None,
    }
}
