//! Per-frame conditions of the manifest (`passes[].skip_when`,
//! `bindings[].alternative.when`), evaluated against the bytes the engine uploads.
//!
//! A condition that names a buffer is machine-readable: `<buffer>.<field>[.<component>] <op>
//! <number>`, optionally followed by a parenthesised remark, e.g. `frame.anti_epipole.w >
//! 0.5` or `frame.proj.x > 0.5 (a projective frame)`. `<buffer>` is a uniform-buffer
//! resource, `<field>` a field of the struct its bindings hold (offset and type from the
//! manifest's `structs`), `<component>` one of `x y z w`, `<op>` one of `> >= < <= == !=`.
//!
//! Any other text is an engine-side condition written for people (`the frame is projective
//! and the engine has no standard shadow map`): this engine takes such an alternative only
//! when the resource it replaces is an engine input that was not supplied this frame, which
//! is what those conditions describe. A `skip_when` must be machine-readable.

use crate::EngineError;
use crate::manifest::{Manifest, VariantEntry};

/// A comparison operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `==`
    Eq,
    /// `!=`
    Ne,
}

impl Op {
    fn apply(self, a: f64, b: f64) -> bool {
        match self {
            Self::Gt => a > b,
            Self::Ge => a >= b,
            Self::Lt => a < b,
            Self::Le => a <= b,
            Self::Eq => a == b,
            Self::Ne => a != b,
        }
    }
}

/// The scalar type of the value a condition reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// `f32`
    F32,
    /// `u32`
    U32,
    /// `i32`
    I32,
}

/// A parsed condition.
#[derive(Clone, Debug, PartialEq)]
pub enum Condition {
    /// Compares one scalar of an uploaded uniform buffer with a constant.
    Buffer {
        /// The buffer resource.
        resource: String,
        /// Byte offset of the scalar in the buffer.
        offset: usize,
        /// Its type.
        scalar: Scalar,
        /// The comparison.
        op: Op,
        /// The constant.
        value: f64,
        /// The manifest's text.
        text: String,
    },
    /// An engine-side condition written for people.
    Engine {
        /// The manifest's text.
        text: String,
    },
}

impl Condition {
    /// Parses `text` against the buffers and structs of `variant`; `context` says where it
    /// appears (for messages).
    ///
    /// # Errors
    ///
    /// [`EngineError::Condition`] when the text names a buffer but is not a valid condition
    /// on it (unknown field or component, bad operator or number).
    pub fn parse(
        text: &str,
        manifest: &Manifest,
        variant: &VariantEntry,
        context: &str,
    ) -> Result<Self, EngineError> {
        let error = |reason: String| EngineError::Condition {
            condition: text.to_owned(),
            context: context.to_owned(),
            reason,
        };
        let trimmed = text.trim();
        // Strip a trailing parenthesised remark.
        let core = match trimmed.find(" (") {
            Some(i) if trimmed.ends_with(')') => trimmed[..i].trim(),
            _ => trimmed,
        };
        let mut words = core.split_whitespace();
        let (Some(lhs), Some(op), Some(rhs), None) =
            (words.next(), words.next(), words.next(), words.next())
        else {
            return Self::engine_or_error(text, core, variant, error);
        };
        let mut path = lhs.split('.');
        let Some(resource) = path.next() else {
            return Self::engine_or_error(text, core, variant, error);
        };
        let Some(buffer) = variant
            .resource(resource)
            .filter(|r| r.kind == "uniform_buffer")
        else {
            return Self::engine_or_error(text, core, variant, error);
        };
        let op = match op {
            ">" => Op::Gt,
            ">=" => Op::Ge,
            "<" => Op::Lt,
            "<=" => Op::Le,
            "==" => Op::Eq,
            "!=" => Op::Ne,
            other => return Err(error(format!("unknown operator {other:?}"))),
        };
        let value: f64 = rhs
            .parse()
            .map_err(|_| error(format!("{rhs:?} is not a number")))?;
        let field_name = path
            .next()
            .ok_or_else(|| error(format!("names buffer `{resource}` but no field")))?;
        let component = path.next();
        if path.next().is_some() {
            return Err(error(format!("{lhs:?} has too many parts")));
        }
        // The struct the buffer's bindings hold.
        let struct_name = variant
            .passes
            .iter()
            .flat_map(|p| &p.bindings)
            .filter(|b| b.resource == buffer.name)
            .find_map(|b| b.struct_name.as_deref())
            .ok_or_else(|| error(format!("no binding of `{resource}` names its struct")))?;
        let layout = manifest
            .struct_layout(&variant.family, struct_name)
            .ok_or_else(|| {
                error(format!(
                    "struct {struct_name} of family {} is not in `structs`",
                    variant.family
                ))
            })?;
        let field = layout
            .fields
            .iter()
            .find(|f| f.name == field_name)
            .ok_or_else(|| {
                error(format!(
                    "struct {struct_name} has no field {field_name:?} (fields: {})",
                    layout
                        .fields
                        .iter()
                        .map(|f| f.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })?;
        let (lanes, scalar) = parse_type(&field.ty)
            .ok_or_else(|| error(format!("field {field_name} has type {}", field.ty)))?;
        let lane = match component {
            None if lanes == 1 => 0,
            None => {
                return Err(error(format!(
                    "field {field_name} is a {}: name a component",
                    field.ty
                )));
            }
            Some(c) => ["x", "y", "z", "w"]
                .iter()
                .position(|&n| n == c)
                .filter(|&l| l < lanes)
                .ok_or_else(|| error(format!("{c:?} is not a component of {}", field.ty)))?,
        };
        let offset = field.offset + 4 * lane as u64;
        if offset + 4 > layout.size {
            return Err(error(format!(
                "offset {offset} lies outside struct {struct_name} ({} bytes)",
                layout.size
            )));
        }
        Ok(Self::Buffer {
            resource: buffer.name.clone(),
            offset: offset as usize,
            scalar,
            op,
            value,
            text: text.to_owned(),
        })
    }

    /// Text that does not name a uniform buffer is an engine-side condition; text that does
    /// but does not parse is an error.
    fn engine_or_error(
        text: &str,
        core: &str,
        variant: &VariantEntry,
        error: impl Fn(String) -> EngineError,
    ) -> Result<Self, EngineError> {
        let first = core.split(['.', ' ']).next().unwrap_or_default();
        if variant
            .resource(first)
            .is_some_and(|r| r.kind == "uniform_buffer")
            && core.starts_with(&format!("{first}."))
        {
            return Err(error(
                "names a buffer but is not `<buffer>.<field>[.<component>] <op> <number>`"
                    .to_owned(),
            ));
        }
        Ok(Self::Engine {
            text: text.to_owned(),
        })
    }

    /// Evaluates a buffer condition on the buffer's uploaded bytes (`bytes_of` gives them by
    /// resource name); `None` for an engine-side condition.
    ///
    /// # Errors
    ///
    /// [`EngineError::Condition`] when the buffer was not uploaded or is too short.
    pub fn eval<'a>(
        &self,
        bytes_of: impl Fn(&str) -> Option<&'a [u8]>,
    ) -> Result<Option<bool>, EngineError> {
        let Self::Buffer {
            resource,
            offset,
            scalar,
            op,
            value,
            text,
        } = self
        else {
            return Ok(None);
        };
        let bytes = bytes_of(resource)
            .and_then(|b| b.get(*offset..offset + 4))
            .ok_or_else(|| EngineError::Condition {
                condition: text.clone(),
                context: "evaluating it this frame".to_owned(),
                reason: format!("buffer `{resource}` was not uploaded"),
            })?;
        let raw = [bytes[0], bytes[1], bytes[2], bytes[3]];
        let lhs = match scalar {
            Scalar::F32 => f64::from(f32::from_le_bytes(raw)),
            Scalar::U32 => f64::from(u32::from_le_bytes(raw)),
            Scalar::I32 => f64::from(i32::from_le_bytes(raw)),
        };
        Ok(Some(op.apply(lhs, *value)))
    }

    /// The manifest's text.
    pub fn text(&self) -> &str {
        match self {
            Self::Buffer { text, .. } | Self::Engine { text } => text,
        }
    }
}

/// Lanes and scalar type of a WGSL scalar or vector type.
fn parse_type(ty: &str) -> Option<(usize, Scalar)> {
    let scalar = |s: &str| match s {
        "f32" => Some(Scalar::F32),
        "u32" => Some(Scalar::U32),
        "i32" => Some(Scalar::I32),
        _ => None,
    };
    if let Some(s) = scalar(ty) {
        return Some((1, s));
    }
    let rest = ty.strip_prefix("vec")?;
    let (n, inner) = rest.split_once('<')?;
    let lanes: usize = n.parse().ok().filter(|n| (2..=4).contains(n))?;
    Some((lanes, scalar(inner.strip_suffix('>')?)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn manifest() -> Manifest {
        let json = r#"{
          "schema": "scatter-gen-manifest", "schema_version": 1,
          "structs": [{"family": "f", "name": "Frame", "size": 48, "fields": [
             {"name": "a", "type": "vec4<f32>", "offset": 0, "size": 16},
             {"name": "sizes", "type": "vec4<u32>", "offset": 16, "size": 16},
             {"name": "s", "type": "f32", "offset": 32, "size": 4}]}],
          "variants": [{"family": "f", "id": "v", "parameters": [],
            "resources": [{"name": "frame", "kind": "uniform_buffer", "provided_by": "scatter",
              "buffer": {"size_bytes": "48", "usage": ["uniform"]}}],
            "passes": [{"kernel": "k", "entry_point": "k", "workgroup_size": [1, 1, 1],
              "dispatch": [], "files": {}, "bindings": [{"group": 0, "binding": 0,
              "kind": "uniform_buffer", "access": "read", "struct_name": "Frame",
              "resource": "frame"}]}]}],
          "files": []}"#;
        Manifest::parse(json.as_bytes(), Path::new("test")).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn reads_fields_by_offset() {
        let m = manifest();
        let v = &m.variants[0];
        let mut bytes = [0u8; 48];
        bytes[12..16].copy_from_slice(&0.75f32.to_le_bytes());
        bytes[20..24].copy_from_slice(&7u32.to_le_bytes());
        bytes[32..36].copy_from_slice(&(-1.0f32).to_le_bytes());
        let get = |t: &str| {
            Condition::parse(t, &m, v, "test")
                .unwrap_or_else(|e| panic!("{e}"))
                .eval(|_| Some(&bytes[..]))
                .unwrap_or_else(|e| panic!("{e}"))
        };
        assert_eq!(get("frame.a.w > 0.5"), Some(true));
        assert_eq!(get("frame.a.w > 0.5 (remark, with words)"), Some(true));
        assert_eq!(get("frame.a.x > 0.5"), Some(false));
        assert_eq!(get("frame.sizes.y == 7"), Some(true));
        assert_eq!(get("frame.s < 0"), Some(true));
        assert_eq!(get("the engine has no shadow map"), None);
    }

    #[test]
    fn rejects_bad_buffer_conditions() {
        let m = manifest();
        let v = &m.variants[0];
        for bad in [
            "frame.b.x > 0.5",
            "frame.a.q > 0.5",
            "frame.a > 0.5",
            "frame.a.x ~ 0.5",
            "frame.a.x > half",
            "frame.a.x > 0.5 and more",
        ] {
            let e = Condition::parse(bad, &m, v, "test").unwrap_err();
            assert!(matches!(e, EngineError::Condition { .. }), "{bad}: {e}");
        }
    }
}
