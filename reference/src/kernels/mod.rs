//! CPU mirrors of the GPU kernels, one module per kernel, named like its template
//! (`shaderlib/templates/<kernel>.wgsl`) and written line by line like the WGSL, so that a
//! GPU result can be compared with its mirror at quantisation-level tolerance.

pub mod row_prefix;
