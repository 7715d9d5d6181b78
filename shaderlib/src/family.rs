//! What shaderlib adds to every family's variant: its kernels and its plan
//! ([`KernelFamily`]), for the one enum of every family's variant
//! ([`FamilyVariant`], from `scatter-frame`) as for each variant type.

pub use scatter_frame::family::{Family, FamilyVariant, KnobSet, UnknownFamily};

use crate::minmax::MinmaxVariant;
use crate::plan::Plan;
use crate::prefiltered::Variant;
use crate::raymarch::RaymarchVariant;
use crate::{Kernel, KernelParams};

/// A family's variant as kernels: the kernel parameters in pass order and the plan the
/// generator writes into the manifest and the runtime's executor builds from.
pub trait KernelFamily {
    /// The kernel parameters of every kernel, in pass order.
    fn kernel_params(&self) -> Vec<KernelParams>;

    /// The resources, parameters and passes an engine needs to run the variant.
    fn plan(&self) -> Plan;
}

impl KernelFamily for Variant {
    fn kernel_params(&self) -> Vec<KernelParams> {
        KernelParams::prefiltered(*self).to_vec()
    }

    fn plan(&self) -> Plan {
        crate::prefiltered::plan::plan(self)
    }
}

impl KernelFamily for RaymarchVariant {
    fn kernel_params(&self) -> Vec<KernelParams> {
        KernelParams::raymarch(*self)
    }

    fn plan(&self) -> Plan {
        crate::raymarch::plan::plan(self)
    }
}

impl KernelFamily for MinmaxVariant {
    fn kernel_params(&self) -> Vec<KernelParams> {
        KernelParams::minmax(*self).to_vec()
    }

    fn plan(&self) -> Plan {
        crate::minmax::plan::plan(self)
    }
}

impl KernelFamily for FamilyVariant {
    fn kernel_params(&self) -> Vec<KernelParams> {
        match self {
            Self::Minmax(v) => v.kernel_params(),
            Self::Prefiltered(v) => v.kernel_params(),
            Self::Raymarch(v) => v.kernel_params(),
        }
    }

    fn plan(&self) -> Plan {
        match self {
            Self::Minmax(v) => v.plan(),
            Self::Prefiltered(v) => v.plan(),
            Self::Raymarch(v) => v.plan(),
        }
    }
}

/// The kernels of a family in pass order, for its variant with the most passes (read from
/// the kernel parameters, not listed here).
pub fn kernels(family: Family) -> Vec<Kernel> {
    let variant = match family {
        Family::Raymarch => FamilyVariant::Raymarch(RaymarchVariant {
            interleave: 2,
            ..RaymarchVariant::default()
        }),
        _ => family.default_variant(),
    };
    variant
        .kernel_params()
        .iter()
        .map(KernelParams::kernel)
        .collect()
}
