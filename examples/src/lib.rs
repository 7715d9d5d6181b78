//! Shared helpers of the scatter examples (see `examples/`).

pub mod bench;
pub mod engine;
pub mod raster;
pub mod roofline;
pub mod scene_file;
