//! `scatter-frame`: what a host needs besides the shaders to drive the scatter kernels, with
//! no shader tooling (no naga, no askama): the prefiltered family's variant knobs
//! ([`variant`]) and its per-frame set-up ([`frame`]: the `Frame` uniform block, the
//! per-row slice table and, for projective rectification, the matrices the engine
//! rasterises with).
//!
//! `scatter-shaderlib` re-exports both modules as `scatter_shaderlib::prefiltered::*`; an
//! engine that only uses shaders emitted by `scatter-gen` links this crate alone (see
//! `examples/foreign_engine`). A C++ engine ports [`frame::prepare_frame`]; its inputs and
//! outputs are plain numbers, documented field by field. The raymarch and minmax families'
//! knobs and set-up are in [`raymarch`] and [`minmax`]. [`family`] lists the families and
//! holds the one enum of every family's variant ([`family::FamilyVariant`]).

pub mod area_ivsv;
pub mod area_light;
pub mod cookie;
pub mod family;
pub mod frame;
pub mod hybrid_volume;
pub mod minmax;
pub mod partial_sum_tree;
pub mod raymarch;
pub mod sampling;
pub mod scene;
pub mod variant;
