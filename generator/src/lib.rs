//! `scatter-gen`: the code generator that emits every kernel of a variant as WGSL, GLSL and
//! SPIR-V plus `manifest.json`. The CLI lands with the generator issue; this crate is
//! deliberately empty until then.
