//! `scatter-gen`: the code generator that turns kernel variants into drop-in shaders for
//! another engine: every kernel of each variant as WGSL, GLSL, SPIR-V (HLSL and MSL on
//! request), each validated by naga before it is written, plus `manifest.json` (bindings,
//! struct layouts, resources, pass order and dispatch formulas, file hashes) and the uniform
//! structs as a C header and a Rust module.
//!
//! The binary (`src/main.rs`) is a thin clap front-end over this library:
//! [`family`] parses knobs into variants, [`generate::generate`] produces every file in
//! memory, [`output`] writes them atomically (or `--check`s them).
//!
//! ```no_run
//! use scatter_gen::{Family, FamilyCli, Request, Target, generate, output};
//!
//! let variant = Family::Prefiltered.variant(&[("bases".into(), "16".into())])?;
//! let files = generate(&Request { variants: vec![variant], targets: Target::DEFAULT.to_vec() })?;
//! output::write(std::path::Path::new("shaders"), &files, false)?;
//! # Ok::<(), scatter_gen::GenError>(())
//! ```

pub mod config;
mod error;
pub mod family;
pub mod generate;
pub mod layout_code;
pub mod manifest;
pub mod output;
pub use scatter_shaderlib::reflect;
mod spirv_fixup;
pub mod target;

pub use error::GenError;
pub use family::{Family, FamilyCli, FamilyVariant, KernelFamily};
pub use generate::{Generated, Request, generate};
pub use target::Target;
