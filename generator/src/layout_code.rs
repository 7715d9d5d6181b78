//! The uniform structs as host code: a C header (`scatter_uniforms.h`, C11 or C++11) and a
//! Rust module (`scatter_uniforms.rs`), both with explicit padding and static asserts on
//! every offset and on the size, generated from the layouts naga's layouter computed.

use std::fmt::Write as _;

use crate::GenError;
use crate::family::Family;
use crate::reflect::{Shape, StructLayout};

/// A struct of a family, for the host files.
#[derive(Clone, Debug)]
pub struct FamilyStruct {
    /// The family whose kernels use it.
    pub family: Family,
    /// Its layout.
    pub layout: StructLayout,
}

/// The C type name of a family's struct: `ScatterPrefilteredFrame`.
pub fn c_name(family: Family, name: &str) -> String {
    format!("Scatter{}{}", camel(family.name()), camel(name))
}

/// The Rust path of a family's struct inside the module: `prefiltered::Frame`.
pub fn rust_name(family: Family, name: &str) -> String {
    format!("{}::{}", family.name(), camel(name))
}

fn camel(s: &str) -> String {
    s.split('_')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let mut c = p.chars();
            c.next()
                .map(|f| f.to_uppercase().collect::<String>() + c.as_str())
                .unwrap_or_default()
        })
        .collect()
}

const C_KEYWORDS: &[&str] = &[
    "auto",
    "break",
    "case",
    "char",
    "class",
    "const",
    "continue",
    "default",
    "delete",
    "do",
    "double",
    "else",
    "enum",
    "extern",
    "float",
    "for",
    "goto",
    "if",
    "inline",
    "int",
    "long",
    "namespace",
    "new",
    "private",
    "public",
    "register",
    "restrict",
    "return",
    "short",
    "signed",
    "sizeof",
    "static",
    "struct",
    "switch",
    "template",
    "this",
    "typedef",
    "union",
    "unsigned",
    "void",
    "volatile",
    "while",
];

const RUST_KEYWORDS: &[&str] = &[
    "as", "async", "await", "box", "break", "const", "continue", "crate", "dyn", "else", "enum",
    "extern", "false", "fn", "for", "gen", "if", "impl", "in", "let", "loop", "match", "mod",
    "move", "mut", "pub", "ref", "return", "self", "static", "struct", "super", "trait", "true",
    "try", "type", "unsafe", "use", "where", "while", "yield",
];

fn c_field(name: &str) -> String {
    if C_KEYWORDS.contains(&name) {
        format!("{name}_")
    } else {
        name.to_owned()
    }
}

fn rust_field(name: &str) -> String {
    if RUST_KEYWORDS.contains(&name) {
        format!("r#{name}")
    } else {
        name.to_owned()
    }
}

fn c_scalar(s: &str) -> Option<&'static str> {
    Some(match s {
        "f32" => "float",
        "u32" => "uint32_t",
        "i32" => "int32_t",
        "f16" => "uint16_t",
        "f64" => "double",
        "u64" => "uint64_t",
        "i64" => "int64_t",
        _ => return None,
    })
}

fn rust_scalar(s: &str) -> Option<&'static str> {
    Some(match s {
        "f32" => "f32",
        "u32" => "u32",
        "i32" => "i32",
        "f16" => "u16",
        "f64" => "f64",
        "u64" => "u64",
        "i64" => "i64",
        _ => return None,
    })
}

/// A field's host type: base type plus C array suffix (`float`, `[4]`) and the Rust type.
struct HostType {
    c_base: String,
    c_dims: String,
    rust: String,
    size: u32,
}

fn host_type(family: Family, shape: &Shape, size: u32, owner: &str) -> Result<HostType, GenError> {
    let unsupported = |what: &str| GenError::Layout {
        name: owner.to_owned(),
        message: format!("a field of type {what} has no C/Rust equivalent here"),
    };
    Ok(match shape {
        Shape::Scalar(s) => HostType {
            c_base: c_scalar(s).ok_or_else(|| unsupported(s))?.into(),
            c_dims: String::new(),
            rust: rust_scalar(s).ok_or_else(|| unsupported(s))?.into(),
            size,
        },
        Shape::Vector(s, n) => HostType {
            c_base: c_scalar(s).ok_or_else(|| unsupported(s))?.into(),
            c_dims: format!("[{n}]"),
            rust: format!("[{}; {n}]", rust_scalar(s).ok_or_else(|| unsupported(s))?),
            size: n * scalar_bytes(s),
        },
        Shape::Matrix {
            scalar,
            columns,
            column_stride,
            ..
        } => {
            // Each column padded to its stride: `columns` arrays of stride / scalar size.
            let per = column_stride / scalar_bytes(scalar);
            HostType {
                c_base: c_scalar(scalar).ok_or_else(|| unsupported(scalar))?.into(),
                c_dims: format!("[{columns}][{per}]"),
                rust: format!(
                    "[[{}; {per}]; {columns}]",
                    rust_scalar(scalar).ok_or_else(|| unsupported(scalar))?
                ),
                size: columns * column_stride,
            }
        }
        Shape::Array {
            element,
            element_size,
            len,
            stride,
        } => {
            let e = host_type(family, element, *element_size, owner)?;
            if e.size != *stride {
                return Err(GenError::Layout {
                    name: owner.to_owned(),
                    message: format!(
                        "an array element of {} bytes has a stride of {stride}: no plain C array has that layout",
                        e.size
                    ),
                });
            }
            HostType {
                c_base: e.c_base,
                c_dims: format!("[{len}]{}", e.c_dims),
                rust: format!("[{}; {len}]", e.rust),
                size: len * stride,
            }
        }
        Shape::Struct(name) => HostType {
            c_base: c_name(family, name),
            c_dims: String::new(),
            rust: camel(name),
            size,
        },
        Shape::Unsupported(what) => return Err(unsupported(what)),
    })
}

fn scalar_bytes(s: &str) -> u32 {
    match s {
        "f16" => 2,
        "f64" | "u64" | "i64" => 8,
        _ => 4,
    }
}

/// One field or padding member, in order.
enum Member {
    Field {
        name: String,
        wgsl: String,
        offset: u32,
        ty: HostType,
    },
    Pad {
        index: u32,
        bytes: u32,
    },
}

fn members(s: &FamilyStruct) -> Result<Vec<Member>, GenError> {
    let mut out = Vec::new();
    let mut at = 0u32;
    let mut pads = 0u32;
    for f in &s.layout.fields {
        if f.offset > at {
            out.push(Member::Pad {
                index: pads,
                bytes: f.offset - at,
            });
            pads += 1;
        }
        let ty = host_type(s.family, &f.shape, f.size, &s.layout.name)?;
        at = f.offset + ty.size;
        out.push(Member::Field {
            name: f.name.clone(),
            wgsl: f.ty.clone(),
            offset: f.offset,
            ty,
        });
    }
    if s.layout.size > at {
        out.push(Member::Pad {
            index: pads,
            bytes: s.layout.size - at,
        });
    }
    Ok(out)
}

/// The C header for `structs` (nested structs must come before their users).
///
/// # Errors
///
/// [`GenError::Layout`] for a field C cannot express.
pub fn c_header(banner: &[String], structs: &[FamilyStruct]) -> Result<String, GenError> {
    let mut h = String::new();
    for line in banner {
        let _ = writeln!(h, "// {line}");
    }
    h.push_str(
        "//\n// Offsets and sizes are those of the WGSL uniform/storage layout (naga's layouter);\n\
         // explicit padding members keep them in plain C. Upload the bytes as they are.\n\n\
         #ifndef SCATTER_UNIFORMS_H\n#define SCATTER_UNIFORMS_H\n\n\
         #include <stddef.h>\n#include <stdint.h>\n\n\
         #ifdef __cplusplus\n#define SCATTER_STATIC_ASSERT(cond, msg) static_assert(cond, msg)\n\
         #else\n#define SCATTER_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)\n#endif\n",
    );
    for s in structs {
        let name = c_name(s.family, &s.layout.name);
        let members = members(s)?;
        let _ = writeln!(
            h,
            "\n/* WGSL `{}` of family {} ({}), {} bytes, alignment {}. */",
            s.layout.name,
            s.family,
            s.layout.module.as_deref().unwrap_or("kernel module"),
            s.layout.size,
            s.layout.alignment
        );
        let _ = writeln!(h, "typedef struct {name} {{");
        for m in &members {
            match m {
                Member::Field {
                    name: field,
                    wgsl,
                    offset,
                    ty,
                } => {
                    let _ = writeln!(
                        h,
                        "    {} {}{}; /* {wgsl}, offset {offset} */",
                        ty.c_base,
                        c_field(field),
                        ty.c_dims
                    );
                }
                Member::Pad { index, bytes } => {
                    let _ = writeln!(h, "    uint8_t _pad{index}[{bytes}];");
                }
            }
        }
        let _ = writeln!(h, "}} {name};");
        let _ = writeln!(
            h,
            "SCATTER_STATIC_ASSERT(sizeof({name}) == {}, \"{name} size\");",
            s.layout.size
        );
        for m in &members {
            if let Member::Field {
                name: field,
                offset,
                ..
            } = m
            {
                let field = c_field(field);
                let _ = writeln!(
                    h,
                    "SCATTER_STATIC_ASSERT(offsetof({name}, {field}) == {offset}, \"{name}.{field} offset\");"
                );
            }
        }
    }
    h.push_str("\n#endif /* SCATTER_UNIFORMS_H */\n");
    Ok(h)
}

/// The Rust module for `structs`: one `pub mod <family>` each, `#[repr(C)]` structs with
/// explicit padding and `const` asserts on every offset and the size.
///
/// # Errors
///
/// [`GenError::Layout`] for a field Rust cannot express.
pub fn rust_module(banner: &[String], structs: &[FamilyStruct]) -> Result<String, GenError> {
    let mut r = String::new();
    for line in banner {
        let _ = writeln!(r, "// {line}");
    }
    r.push_str(
        "//\n// Offsets and sizes are those of the WGSL uniform/storage layout (naga's layouter);\n\
         // explicit padding members keep them in `#[repr(C)]`. Use it with `include!` or as a\n\
         // module file; it needs no dependencies.\n",
    );
    for family in Family::ALL {
        let of_family: Vec<_> = structs.iter().filter(|s| s.family == *family).collect();
        if of_family.is_empty() {
            continue;
        }
        let _ = writeln!(
            r,
            "\n/// Uniform structs of the `{}` kernels.\n#[allow(dead_code, reason = \"generated\")]\npub mod {} {{",
            family,
            family.name()
        );
        for s in of_family {
            let name = camel(&s.layout.name);
            let members = members(s)?;
            let _ = writeln!(
                r,
                "    /// WGSL `{}` ({}), {} bytes, alignment {}.",
                s.layout.name,
                s.layout.module.as_deref().unwrap_or("kernel module"),
                s.layout.size,
                s.layout.alignment
            );
            let _ = writeln!(
                r,
                "    #[repr(C)]\n    #[derive(Clone, Copy, Debug, PartialEq)]\n    pub struct {name} {{"
            );
            for m in &members {
                match m {
                    Member::Field {
                        name: field,
                        wgsl,
                        offset,
                        ty,
                    } => {
                        let _ = writeln!(
                            r,
                            "        /// `{wgsl}` at byte {offset}.\n        pub {}: {},",
                            rust_field(field),
                            ty.rust
                        );
                    }
                    Member::Pad { index, bytes } => {
                        let _ = writeln!(
                            r,
                            "        /// Padding.\n        pub _pad{index}: [u8; {bytes}],"
                        );
                    }
                }
            }
            r.push_str("    }\n\n    const _: () = {\n");
            let _ = writeln!(
                r,
                "        assert!(::core::mem::size_of::<{name}>() == {});",
                s.layout.size
            );
            for m in &members {
                if let Member::Field {
                    name: field,
                    offset,
                    ..
                } = m
                {
                    let _ = writeln!(
                        r,
                        "        assert!(::core::mem::offset_of!({name}, {}) == {offset});",
                        rust_field(field)
                    );
                }
            }
            r.push_str("    };\n");
        }
        r.push_str("}\n");
    }
    Ok(r)
}
