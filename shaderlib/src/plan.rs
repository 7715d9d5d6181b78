//! The plan of a kernel family's variant: everything an engine needs to run it that the
//! compiled shaders do not say (the textures, buffers and samplers to allocate, what each
//! binding of each pass gets, the dispatch sizes as formulas of the resolutions, the
//! per-frame conditions). One description: `scatter-gen` writes it into `manifest.json` and
//! `scatter-runtime`'s plan executor builds its resources, bind groups and dispatches from it.

use serde::Serialize;

use crate::Kernel;

/// Format of the depth buffer, the standard shadow map and the rectified map.
pub const DEPTH_FORMAT: &str = "r32float";
/// Format of every family's output (in-scattered radiance, rgb; alpha 1).
pub const OUTPUT_FORMAT: &str = "rgba16float";
/// Usages of a texture the passes only sample or load.
pub const SAMPLED: &[&str] = &["texture_binding"];
/// Usages of a texture one pass writes and a later one reads.
pub const STORAGE_AND_SAMPLED: &[&str] = &["storage_binding", "texture_binding"];
/// What the engine must know of `slice_fit`, the epipolar families' second pass.
pub const SLICE_FIT_NOTE: &str = "`slice_fit` (after `depth_columns`, one workgroup) rewrites \
                                  the column spacing (x) of every `slices` entry from the \
                                  depth buffer's deepest pixel: upload `slices` anew every \
                                  frame before it, as the frame set-up returns it.";

/// The epipolar families' `column_depth` buffer: one f32 per screen column, written by
/// `depth_columns` and read by `slice_fit`.
pub fn column_depth_buffer() -> Resource {
    Resource {
        kind: "storage_buffer",
        buffer: Some(BufferDesc {
            elements: Some("screen.width".to_owned()),
            usage: vec!["storage"],
        }),
        ..scatter_resource(
            "column_depth",
            "the deepest pixel (view depth clamped to the far plane) of every screen column, \
             written by depth_columns and read by slice_fit",
        )
    }
}
/// The constraint of a parameter that sizes a 2D texture.
pub const TEXTURE_DIMENSION: &str = "1..=max_texture_dimension_2d";

/// A one-mip 2D texture of `layers` layers.
pub fn texture_2d(
    format: &str,
    width: &str,
    height: &str,
    layers: &str,
    usage: &[&'static str],
) -> TextureDesc {
    TextureDesc {
        format: format.to_owned(),
        dimension: "2d",
        width: width.to_owned(),
        height: height.to_owned(),
        layers: layers.to_owned(),
        mip_levels: 1,
        usage: usage.to_vec(),
    }
}

/// A binding that always gets `resource`.
pub fn bind(binding: u32, resource: &'static str) -> BindingSource {
    BindingSource {
        binding,
        resource,
        alternative: None,
    }
}

/// `screen.width`, `screen.height` and `shadow.size`: the parameters every family has.
pub fn screen_and_shadow_parameters() -> Vec<Parameter> {
    vec![
        Parameter {
            name: "screen.width",
            description: "screen width in pixels (depth buffer and output)",
            constraint: TEXTURE_DIMENSION.into(),
        },
        Parameter {
            name: "screen.height",
            description: "screen height in pixels (depth buffer and output)",
            constraint: TEXTURE_DIMENSION.into(),
        },
        Parameter {
            name: "shadow.size",
            description: "side of the engine's square standard shadow map in texels",
            constraint: TEXTURE_DIMENSION.into(),
        },
    ]
}

/// A resource scatter allocates.
pub fn scatter_resource(name: &'static str, contents: &'static str) -> Resource {
    Resource {
        name,
        kind: "texture",
        provided_by: "scatter",
        contents,
        texture: None,
        buffer: None,
        sampler: None,
    }
}

/// A per-frame buffer scatter allocates and the host writes: a uniform block, or with
/// `elements` a storage array.
pub fn frame_buffer(
    name: &'static str,
    contents: &'static str,
    elements: Option<&str>,
) -> Resource {
    let (kind, usage) = match elements {
        None => ("uniform_buffer", vec!["uniform", "copy_dst"]),
        // copy_src: a pass may rewrite it (`slice_fit`), and tests read it back.
        Some(_) => ("storage_buffer", vec!["storage", "copy_dst", "copy_src"]),
    };
    Resource {
        kind,
        buffer: Some(BufferDesc {
            elements: elements.map(str::to_owned),
            usage,
        }),
        ..scatter_resource(name, contents)
    }
}

/// A 2D texture scatter allocates (one layer, written by one pass and read by a later one
/// or by the engine).
pub fn scatter_texture(
    name: &'static str,
    contents: &'static str,
    format: &str,
    width: &str,
    height: &str,
) -> Resource {
    Resource {
        texture: Some(texture_2d(format, width, height, "1", STORAGE_AND_SAMPLED)),
        ..scatter_resource(name, contents)
    }
}

/// The engine's inputs every family reads: `depth` (screen-sized) and `shadow_map`.
pub fn depth_and_shadow_map() -> [Resource; 2] {
    let input = |name, contents, width, height| Resource {
        provided_by: "engine",
        texture: Some(texture_2d(DEPTH_FORMAT, width, height, "1", SAMPLED)),
        ..scatter_resource(name, contents)
    };
    [
        input(
            "depth",
            "linear view depth per pixel (far plane distance for sky)",
            "screen.width",
            "screen.height",
        ),
        input(
            "shadow_map",
            "standard shadow map: normalised linear light depth, 1 where nothing was hit, \
             texel (0, 0) top-left; orthographic for a directional light, perspective for a \
             spot (the kernels are generated for one light kind and test only its map kind)",
            "shadow.size",
            "shadow.size",
        ),
    ]
}

/// The binding of the engine's `cookie` texture in every kernel that reads a spot's cookie
/// (above every family's own and sampling bindings), but `partial_sum_tree`'s, whose
/// sampling bindings reach 12: [`crate::partial_sum_tree::COOKIE_BINDING`].
pub const COOKIE_BINDING: u32 = 12;

/// The engine's spot-light cookie ([`scatter_frame::cookie`]): any size, loaded texel by
/// texel, so any float format binds (`rgba16float` declared).
pub fn cookie_texture() -> Resource {
    Resource {
        provided_by: "engine",
        texture: Some(texture_2d(
            scatter_frame::cookie::COOKIE_FORMAT,
            "cookie.width",
            "cookie.height",
            "1",
            SAMPLED,
        )),
        ..scatter_resource(
            "cookie",
            "the spot light's cookie: linear RGB (alpha ignored) projected along the cone, \
             its square circumscribing the outer cone in the shadow map's right/up frame, \
             texel (0, 0) top-left; any size 1..=4096 and any float format \
             (rgba8unorm, rgba8unorm-srgb, rgba16float, rgba32float)",
        )
    }
}

/// The size of the engine's cookie texture, for [`cookie_texture`].
pub fn cookie_parameters() -> Vec<Parameter> {
    vec![
        Parameter {
            name: "cookie.width",
            description: "width of the engine's cookie texture in texels (any; the kernels \
                          filter it themselves)",
            constraint: "1..=4096".into(),
        },
        Parameter {
            name: "cookie.height",
            description: "height of the engine's cookie texture in texels",
            constraint: "1..=4096".into(),
        },
    ]
}

/// A size expression over the [`Plan::parameters`]: an integer, a parameter name
/// (`screen.width`), or a product `16 * rectified.height`.
pub type Formula = String;

/// A symbol that formulas use, with its meaning and constraints.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Parameter {
    /// The symbol, e.g. `rectified.width`.
    pub name: &'static str,
    /// What it is and who chooses it.
    pub description: &'static str,
    /// Allowed values, in words.
    pub constraint: String,
}

/// A texture's allocation.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TextureDesc {
    /// WebGPU format name (`r32float`, `rgba8unorm`, ...).
    pub format: String,
    /// Texture dimension (`2d`).
    pub dimension: &'static str,
    /// Width in texels.
    pub width: Formula,
    /// Height in texels.
    pub height: Formula,
    /// Array layers.
    pub layers: Formula,
    /// Mip levels.
    pub mip_levels: u32,
    /// Usages the passes need (`texture_binding`, `storage_binding`).
    pub usage: Vec<&'static str>,
}

/// A buffer's allocation; its size is filled in from the IR layout.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct BufferDesc {
    /// For a runtime-sized array: how many elements (the byte size is this times the
    /// element stride).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub elements: Option<Formula>,
    /// Usages the passes need (`uniform`, `storage`, `copy_dst`).
    pub usage: Vec<&'static str>,
}

/// A sampler's state.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SamplerDesc {
    /// `linear` or `nearest`.
    pub mag_filter: &'static str,
    /// `linear` or `nearest`.
    pub min_filter: &'static str,
    /// `linear` or `nearest`.
    pub mipmap_filter: &'static str,
    /// `clamp_to_edge`, `repeat`, ...
    pub address_mode_u: &'static str,
    /// As `address_mode_u`.
    pub address_mode_v: &'static str,
    /// As `address_mode_u`.
    pub address_mode_w: &'static str,
}

/// Something a pass binds.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Resource {
    /// Its name, used by the passes' bindings.
    pub name: &'static str,
    /// `texture`, `uniform_buffer`, `storage_buffer` or `sampler`.
    pub kind: &'static str,
    /// `engine` (the engine renders it: depth buffer, shadow map) or `scatter` (the engine
    /// allocates it once for the passes).
    pub provided_by: &'static str,
    /// What it holds.
    pub contents: &'static str,
    /// Allocation of a texture.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub texture: Option<TextureDesc>,
    /// Allocation of a buffer.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub buffer: Option<BufferDesc>,
    /// State of a sampler.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampler: Option<SamplerDesc>,
}

/// Which resource a binding gets.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct BindingSource {
    /// The binding number (group 0).
    pub binding: u32,
    /// The resource bound by default.
    pub resource: &'static str,
    /// Another resource bound instead when a per-frame condition holds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alternative: Option<Alternative>,
}

/// A resource bound instead of the default one under a per-frame condition.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Alternative {
    /// The resource.
    pub resource: &'static str,
    /// When (an expression over the uniform block).
    pub when: &'static str,
}

/// One pass: its kernel, its invocation grid and what each binding gets.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PassPlan {
    /// The kernel.
    pub kernel: Kernel,
    /// Invocations along x, y, z (the dispatch is `ceil(invocations / workgroup size)`).
    pub invocations: [Formula; 3],
    /// A per-frame condition under which the pass does not run.
    pub skip_when: Option<&'static str>,
    /// Where the pass is dispatched indirectly: the buffer holding its workgroup counts
    /// (`invocations` then give the most it can be, for an engine that dispatches directly).
    pub indirect: Option<Indirect>,
    /// What each binding of group 0 gets.
    pub bindings: Vec<BindingSource>,
}

/// An indirect dispatch's arguments: three `u32` workgroup counts (x, y, z) written by an
/// earlier pass into `buffer` at byte `offset` (a multiple of 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Indirect {
    /// The buffer resource.
    pub buffer: &'static str,
    /// The arguments' byte offset in it.
    pub offset_bytes: u64,
}

/// Everything about a variant that the IR does not say.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    /// Symbols the formulas use.
    pub parameters: Vec<Parameter>,
    /// Textures, buffers and samplers.
    pub resources: Vec<Resource>,
    /// Passes, one per kernel.
    pub passes: Vec<PassPlan>,
    /// What the engine must know besides the bindings (barriers, per-frame data).
    pub notes: Vec<&'static str>,
}

impl Plan {
    /// The resource named `name`.
    pub fn resource(&self, name: &str) -> Option<&Resource> {
        self.resources.iter().find(|r| r.name == name)
    }

    /// The pass of `kernel`.
    pub fn pass(&self, kernel: Kernel) -> Option<&PassPlan> {
        self.passes.iter().find(|p| p.kernel == kernel)
    }
}

impl BindingSource {
    /// The resource bound this frame: the alternative when its condition is among the
    /// conditions that hold, else the default.
    pub fn resource_for(&self, conditions: &[&str]) -> &'static str {
        match &self.alternative {
            Some(a) if conditions.contains(&a.when) => a.resource,
            _ => self.resource,
        }
    }
}

/// Evaluates a plan formula (an integer, a parameter name, `ceil(a / b)` of two of those, a
/// product of those, or a sum of products, e.g. `16 * rectified.height`,
/// `ceil(screen.width / 2) + 1`) with the parameters' values.
///
/// # Errors
///
/// A message naming the formula and the unknown symbol, the malformed term or the overflow.
pub fn eval(formula: &str, params: &[(&str, u64)]) -> Result<u64, String> {
    let mut sum: u64 = 0;
    for product in formula.split('+') {
        sum = sum
            .checked_add(eval_product(formula, product, params)?)
            .ok_or_else(|| format!("formula `{formula}` overflows 64 bits"))?;
    }
    Ok(sum)
}

/// One product of the formula `formula`'s sum.
fn eval_product(formula: &str, product: &str, params: &[(&str, u64)]) -> Result<u64, String> {
    let atom = |term: &str| -> Result<u64, String> {
        if let Ok(n) = term.parse::<u64>() {
            Ok(n)
        } else if let Some(&(_, v)) = params.iter().find(|(name, _)| *name == term) {
            Ok(v)
        } else if term.is_empty() {
            Err(format!("formula `{formula}` has an empty term"))
        } else {
            let names: Vec<_> = params.iter().map(|(n, _)| *n).collect();
            Err(format!(
                "formula `{formula}` names `{term}`, which is not a parameter (known: {})",
                names.join(", ")
            ))
        }
    };
    let mut value: u64 = 1;
    for term in product.split('*') {
        let term = term.trim();
        // `ceil(a / b)`: integer division rounding up (a sample grid of the screen).
        let factor =
            if let Some(inner) = term.strip_prefix("ceil(").and_then(|t| t.strip_suffix(')')) {
                let (a, b) = inner
                    .split_once('/')
                    .ok_or_else(|| format!("formula `{formula}`: `ceil(` takes `a / b`"))?;
                let (a, b) = (atom(a.trim())?, atom(b.trim())?);
                if b == 0 {
                    return Err(format!("formula `{formula}` divides by zero"));
                }
                a.div_ceil(b)
            } else {
                atom(term)?
            };
        value = value
            .checked_mul(factor)
            .ok_or_else(|| format!("formula `{formula}` overflows 64 bits"))?;
    }
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::eval;

    #[test]
    fn formulas_evaluate() {
        let p = [("screen.width", 1280), ("rectified.height", 512)];
        assert_eq!(eval("1", &p), Ok(1));
        assert_eq!(eval("screen.width", &p), Ok(1280));
        assert_eq!(eval("16 * rectified.height", &p), Ok(8192));
        assert_eq!(eval("2 * screen.width * 3", &p), Ok(7680));
        assert!(eval("tree.width", &p).unwrap_err().contains("tree.width"));
        assert!(eval("2 * ", &p).unwrap_err().contains("empty term"));
        assert!(eval("4294967296 * 4294967296", &p).is_err());
        assert_eq!(eval("ceil(screen.width / 3)", &p), Ok(427));
        assert_eq!(eval("2 * ceil(7 / 2)", &p), Ok(8));
        assert!(eval("ceil(7 / 0)", &p).unwrap_err().contains("zero"));
        assert!(eval("ceil(7)", &p).unwrap_err().contains("a / b"));
        assert_eq!(eval("ceil(screen.width / 2) + 1", &p), Ok(641));
        assert_eq!(eval("2 * 3 + rectified.height * 2", &p), Ok(1030));
        assert!(eval("1 + ", &p).unwrap_err().contains("empty term"));
        assert!(eval("18446744073709551615 + 1", &p).is_err());
    }
}
