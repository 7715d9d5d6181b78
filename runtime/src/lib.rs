//! `scatter-runtime`: a thin wgpu driver for the scatter kernels.
//!
//! [`Context`] picks an adapter (a real GPU when there is one, otherwise a CPU adapter such
//! as lavapipe), reports which, and enables GPU timestamps where the adapter has them;
//! [`Context::from_env`] applies the `SCATTER_GPU` policy that tests and tools share. Each
//! kernel has a pass type that builds its pipeline from `scatter-shaderlib` and encodes it
//! ([`RowPrefixPass`]), plus a one-call convenience for tests ([`row_prefix()`]). Kernel
//! families with several passes have one type for the whole family: [`Prefiltered`] runs the
//! `prefiltered` method (`depth_columns`, `slice_fit`, `rectify`, `prefilter`, `scatter`) once
//! per frame,
//! [`run_prefiltered_once`] is its test convenience; [`Raymarch`] runs the `raymarch` family
//! (`raymarch`, then `interleave_sum` when interleaved), [`run_raymarch_once`] its test
//! convenience; [`Minmax`] runs the `minmax` family (`depth_columns`, `slice_fit`, `rectify`,
//! `minmax_build`, `minmax_traverse`), [`run_minmax_once`] its test convenience. [`FamilyPasses`] drives any of
//! them from the one enum of every family's variant.
//!
//! Every family runs on one plan-driven executor (`executor`, crate-private): the family's
//! plan (`scatter_shaderlib::<family>::plan`, the one `scatter-gen` writes into the
//! manifest) and the bindings reflected from its compiled kernels give the layouts,
//! pipelines, resources and dispatches; a family type keeps only its input checks, its
//! per-frame upload and its frame report. [`gpu`] holds the toolkit no family owns.

pub mod area_ivsv;
mod context;
mod cookie;
mod error;
mod executor;
pub mod family;
pub mod gpu;
pub mod hybrid_volume;
pub mod minmax;
pub mod partial_sum_tree;
pub mod prefiltered;
pub mod raymarch;
pub mod row_prefix;
pub mod textures;
mod timer;

pub use area_ivsv::{
    AreaIvsv, AreaIvsvReadback, AreaIvsvTimes, run_area_ivsv_once, upload_vpl_maps,
};
pub use context::{AdapterReport, Context, ContextError, GpuPolicy};
pub use error::RuntimeError;
pub use family::{FamilyPasses, FamilyReadback, FamilyRuntime, run_family_on, run_family_once};

/// The prefiltered family's passes under their name before the redesign.
#[deprecated(note = "renamed `Prefiltered`: `Scatter` is also the crate and a kernel")]
pub type Scatter = Prefiltered;
pub use hybrid_volume::{
    HybridVolume, HybridVolumeReadback, HybridVolumeTimes, run_hybrid_volume_once,
};
pub use minmax::{Minmax, MinmaxReadback, MinmaxTimes, run_minmax_once};
pub use partial_sum_tree::{
    PartialSumTree, PartialSumTreeReadback, PartialSumTreeTimes, run_partial_sum_tree_once,
};
pub use prefiltered::{
    CpuInputs, FrameInput, Inputs, Prefiltered, PrefilteredReadback, PrefilteredTimes,
    run_prefiltered_once,
};
pub use raymarch::{Raymarch, RaymarchInput, RaymarchReadback, RaymarchTimes, run_raymarch_once};
pub use row_prefix::{ArraySize, RowPrefixOutput, RowPrefixPass, row_prefix};
pub use timer::GpuTimer;

pub use scatter_shaderlib as shaderlib;
pub use wgpu;
