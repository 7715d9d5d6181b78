//! `scatter-foreign-engine`: a stand-in for an engine that has none of scatter's Rust
//! crates but its per-frame set-up. It reads a directory written by `scatter-gen` (SPIR-V
//! or WGSL files plus `manifest.json`) and builds everything from the manifest alone: bind
//! group layouts from the reflected bindings, compute pipelines from the shader files
//! (hash-checked), textures, buffers and samplers from the resource list and its size
//! formulas, and per frame the passes in order with their `skip_when` conditions,
//! `alternative` bindings and dispatch formulas. It links `scatter-frame` (the uniform
//! block and slice table of each frame, what a C++ engine would port) and raw `wgpu`, and
//! neither `scatter-shaderlib` nor `scatter-runtime`.
//!
//! - [`manifest`]: the engine's own reader of `manifest.json`;
//! - [`formula`]: size and dispatch formulas, parameter constraints;
//! - [`condition`]: per-frame conditions (`skip_when`, `alternative.when`);
//! - [`engine`]: [`Engine`], family-agnostic;
//! - [`prefiltered`], [`raymarch`], [`minmax`], [`partial_sum_tree`], [`hybrid_volume`],
//!   [`area_ivsv`]: what each family's
//!   resources hold, one
//!   frame end to end (the only family-specific code: which host struct goes into which
//!   buffer, which engine texture into which resource, the family's size parameters);
//! - [`files`]: the binary's `frame.json` and PFM files.
//!
//! ```no_run
//! # fn demo(device: &wgpu::Device, queue: &wgpu::Queue,
//! #         frame: &scatter_frame::frame::PrefilteredFrame, depth: &[f32], shadow: &[f32])
//! #         -> Result<(), scatter_foreign_engine::EngineError> {
//! use scatter_foreign_engine::prefiltered::{Inputs, Sizes, run_frame};
//! use scatter_foreign_engine::{Engine, Target};
//!
//! let sizes = Sizes { screen: [1280, 720], rectified: [1024, 1024], shadow_map: 2048 };
//! let mut engine = Engine::load(device, queue, "shaders".as_ref(),
//!     "m32-t16-r4-weighted-directional-rgba8unorm-epipolar", Target::Spirv, &sizes.params())?;
//! let out = run_frame(&mut engine, frame,
//!     &Inputs { depth, shadow_map: Some(shadow), rectified_raster: None, cookie: None })?;
//! # let _ = out; Ok(()) }
//! ```

pub mod area_ivsv;
pub mod condition;
pub mod engine;
mod error;
pub mod files;
pub mod formula;
pub mod hybrid_volume;
pub mod manifest;
pub mod minmax;
pub mod partial_sum_tree;
pub mod prefiltered;
pub mod raymarch;

pub use engine::{Engine, FrameData, FrameRun, Target};
pub use error::EngineError;
pub use manifest::Manifest;
