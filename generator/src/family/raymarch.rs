//! The `raymarch` family (Tóth & Umenhoffer 2009) in the registry: its knobs (parsed into a
//! shaderlib [`RaymarchVariant`]) and its plan, exactly as `runtime/src/raymarch.rs`
//! allocates and dispatches it.

use scatter_shaderlib::prefiltered::{LightKind, VariantError};
use scatter_shaderlib::raymarch::RaymarchVariant;
use scatter_shaderlib::{Kernel, KernelParams};

use super::prefiltered::{DEPTH_FORMAT, OUTPUT_FORMAT};
use super::{
    BindingSource, BufferDesc, KnobInfo, Parameter, PassPlan, Plan, Resource, TextureDesc,
};
use crate::GenError;

/// Allowed `samples`.
const SAMPLES_ALLOWED: &str = "in 4..=1024, a multiple of interleave^2";
/// Allowed `interleave`.
const INTERLEAVE_ALLOWED: &str = "in 1..=8";
/// Allowed `jitter`.
const JITTER_ALLOWED: &str = "true | false";
/// Format of the partial sums (`scatter_runtime::raymarch::PARTIAL_FORMAT`).
const PARTIAL_FORMAT: &str = "rgba32float";

/// The knobs of [`RaymarchVariant`], defaults from [`RaymarchVariant::default`].
pub fn knobs() -> Vec<KnobInfo> {
    let d = RaymarchVariant::default();
    vec![
        KnobInfo {
            name: "samples",
            value_name: "N",
            help: "cells per view ray, one shadow-map sample each",
            allowed: SAMPLES_ALLOWED.into(),
            default: d.samples.to_string(),
        },
        KnobInfo {
            name: "interleave",
            value_name: "M",
            help: "interleaved sampling tile side: each pixel of an MxM tile takes N/M^2 of the \
                   samples and a separable sum filter adds them (1 = off)",
            allowed: INTERLEAVE_ALLOWED.into(),
            default: d.interleave.to_string(),
        },
        KnobInfo {
            name: "jitter",
            value_name: "BOOL",
            help: "per-pixel jitter of the sample positions inside their cells",
            allowed: JITTER_ALLOWED.into(),
            default: d.jitter.to_string(),
        },
        KnobInfo {
            name: "light",
            value_name: "KIND",
            help: "light type the kernels are compiled for",
            allowed: LightKind::ALLOWED.trim_end().replace(' ', " | "),
            default: d.light.to_string(),
        },
    ]
}

fn number(knob: &'static str, allowed: &str, value: &str) -> Result<u32, VariantError> {
    value.trim().parse().map_err(|_| VariantError {
        knob,
        value: value.to_owned(),
        allowed: allowed.to_owned(),
    })
}

/// Parses `(knob, value)` pairs over the default variant and validates the result.
///
/// # Errors
///
/// [`GenError::Knob`] naming the knob, the value and the range.
pub fn parse(knobs: &[(String, String)]) -> Result<RaymarchVariant, GenError> {
    let mut v = RaymarchVariant::default();
    for (name, value) in knobs {
        match name.as_str() {
            "samples" => v.samples = number("samples", SAMPLES_ALLOWED, value)?,
            "interleave" => v.interleave = number("interleave", INTERLEAVE_ALLOWED, value)?,
            "jitter" => {
                v.jitter = match value.trim() {
                    "true" | "on" | "1" => true,
                    "false" | "off" | "0" => false,
                    _ => {
                        return Err(VariantError {
                            knob: "jitter",
                            value: value.clone(),
                            allowed: JITTER_ALLOWED.into(),
                        }
                        .into());
                    }
                };
            }
            "light" => v.light = value.parse()?,
            other => {
                return Err(GenError::Usage(format!(
                    "knob `{}` does not apply to family raymarch",
                    scatter_shaderlib::prefiltered::variant::printable(other)
                )));
            }
        }
    }
    v.validate()?;
    Ok(v)
}

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
