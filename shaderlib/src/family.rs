//! What shaderlib adds to every family's variant: its kernels and its plan
//! ([`KernelFamily`]), for the one enum of every family's variant
//! ([`FamilyVariant`], from `scatter-frame`) as for each variant type.

pub use scatter_frame::family::{Family, FamilyVariant, KnobSet, UnknownFamily};

use crate::area_ivsv::AreaIvsvVariant;
use crate::hybrid_volume::HybridVolumeVariant;
use crate::minmax::MinmaxVariant;
use crate::partial_sum_tree::PartialSumTreeVariant;
use crate::plan::Plan;
use crate::prefiltered::PrefilteredVariant;
use crate::raymarch::RaymarchVariant;
use crate::{Kernel, KernelParams};

/// A family's variant as kernels: the kernel parameters in pass order and the plan the
/// generator writes into the manifest and the runtime's executor builds from. Each family
/// implements it for its variant type in its own module (`src/<family>/mod.rs`).
pub trait KernelFamily {
    /// The kernel parameters of every kernel, in pass order.
    fn kernel_params(&self) -> Vec<KernelParams>;

    /// The resources, parameters and passes an engine needs to run the variant.
    fn plan(&self) -> Plan;

    /// The family's variant that has the most passes (every kernel of the family), for
    /// listing its kernels; the default variant unless a knob adds passes.
    fn with_most_passes() -> Self
    where
        Self: Sized;
}

/// Shaderlib's one table of families: `Name(variant type)`, one line each; the names are
/// `FamilyVariant`'s. It implements [`KernelFamily`] for [`FamilyVariant`] and [`kernels`].
macro_rules! kernel_families {
    ($($name:ident($ty:ty)),* $(,)?) => {
        impl KernelFamily for FamilyVariant {
            fn kernel_params(&self) -> Vec<KernelParams> {
                match self {
                    $(Self::$name(v) => v.kernel_params(),)*
                }
            }

            fn plan(&self) -> Plan {
                match self {
                    $(Self::$name(v) => v.plan(),)*
                }
            }

            /// The default family's variant with the most passes.
            fn with_most_passes() -> Self {
                Self::Prefiltered(PrefilteredVariant::with_most_passes())
            }
        }

        /// A family's variant with the most passes ([`KernelFamily::with_most_passes`]).
        pub fn most_passes(family: Family) -> FamilyVariant {
            match family {
                $(Family::$name => FamilyVariant::$name(<$ty as KernelFamily>::with_most_passes()),)*
            }
        }

        /// The kernels of a family in pass order, for its variant with the most passes (read
        /// from the kernel parameters, not listed here).
        pub fn kernels(family: Family) -> Vec<Kernel> {
            most_passes(family)
                .kernel_params()
                .iter()
                .map(KernelParams::kernel)
                .collect()
        }
    };
}

kernel_families! {
    AreaIvsv(AreaIvsvVariant),
    HybridVolume(HybridVolumeVariant),
    Minmax(MinmaxVariant),
    PartialSumTree(PartialSumTreeVariant),
    Prefiltered(PrefilteredVariant),
    Raymarch(RaymarchVariant),
}
