//! Any family's CPU mirrors behind one call: [`run_family`] runs the mirrors of every pass
//! of a [`FamilyVariant`] on a scene, its depth buffer and its standard shadow map, so that
//! the stress suite, the random-pose suite and the demo need no list of families of their
//! own.
//!
//! Each family implements [`CpuFamily`] for its variant type (next to its `run_<family>`
//! in [`super`]); [`FamilyRun`] and [`run_family`] come from one table, one line per family.

use scatter_shaderlib::area_ivsv::AreaIvsvVariant;
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::hybrid_volume::HybridVolumeVariant;
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::partial_sum_tree::PartialSumTreeVariant;
use scatter_shaderlib::prefiltered::{FrameError, FrameReport, FrameSettings, PrefilteredVariant};
use scatter_shaderlib::raymarch::RaymarchVariant;

use super::{HybridVolumeRun, MinmaxRun, PartialSumTreeRun, PrefilteredRun, RaymarchRun};
use crate::buffers::{GBuffer, ShadowMap};
use crate::bvh::Bvh;
use crate::image::Image;
use crate::scene::Scene;

/// What every family's CPU run takes: the scene (camera, light, medium, and its geometry
/// for the engine's rasterised maps), the depth buffer, the standard shadow map, the
/// rectified map's size (the families that rectify) and the frame settings (the epipolar
/// families).
#[derive(Clone, Copy, Debug)]
pub struct CpuFrame<'a> {
    /// Camera, light, medium and geometry.
    pub scene: &'a Scene,
    /// The scene's geometry, ray-cast by the engine's stand-ins (projective maps).
    pub bvh: &'a Bvh,
    /// The depth buffer (its size is the screen's).
    pub gbuf: &'a GBuffer,
    /// The standard shadow map.
    pub shadow_map: &'a ShadowMap,
    /// Rectified map size, `[Wr, Hr]` (ignored by families without one).
    pub rectified: [u32; 2],
    /// Epipolar set-up settings (ignored by families without one).
    pub settings: &'a FrameSettings,
}

/// What a family's CPU run gives: every intermediate, of which every family has the
/// output and, for the epipolar families, the frame report.
pub trait CpuRun {
    /// In-scattered radiance (as stored in rgba16float).
    fn output(&self) -> &Image;

    /// The frame report of the epipolar families (`None` for raymarch).
    fn report(&self) -> Option<&FrameReport>;
}

/// A family's variant run by its CPU mirrors.
pub trait CpuFamily {
    /// Every intermediate of one run.
    type Run: CpuRun;

    /// Runs every pass's mirror, in pass order.
    ///
    /// # Errors
    ///
    /// [`FrameError`] when the frame cannot be set up.
    fn run_cpu(&self, frame: &CpuFrame<'_>) -> Result<Self::Run, FrameError>;
}

impl CpuRun for PrefilteredRun {
    fn output(&self) -> &Image {
        &self.output
    }

    fn report(&self) -> Option<&FrameReport> {
        Some(&self.frame.report)
    }
}

impl CpuRun for super::IvsvRun {
    fn output(&self) -> &Image {
        &self.image
    }

    fn report(&self) -> Option<&FrameReport> {
        None
    }
}

impl CpuFamily for AreaIvsvVariant {
    type Run = super::IvsvRun;

    /// Ray-casts the VPLs' maps from the frame's standard map (the area light's point
    /// limit's: `f.shadow_map`'s size is theirs), then runs the mirrors.
    fn run_cpu(&self, f: &CpuFrame<'_>) -> Result<super::IvsvRun, FrameError> {
        let inputs = super::ivsv_inputs(f.scene, f.gbuf, f.bvh, self, f.shadow_map.size).map_err(
            |e| match e {
                super::IvsvInputError::Frame(e)
                | super::IvsvInputError::ShadowMap(crate::buffers::ShadowMapError::Vpl(e)) => e,
                super::IvsvInputError::ShadowMap(e) => FrameError::OutOfRange {
                    what: "VPL shadow map",
                    allowed: "a map the reference can ray-cast",
                    value: e.to_string(),
                },
            },
        )?;
        Ok(super::run_area_ivsv(self, &inputs))
    }
}

impl CpuRun for RaymarchRun {
    fn output(&self) -> &Image {
        &self.output
    }

    fn report(&self) -> Option<&FrameReport> {
        None
    }
}

impl CpuRun for HybridVolumeRun {
    fn output(&self) -> &Image {
        &self.output
    }

    fn report(&self) -> Option<&FrameReport> {
        Some(&self.frame.report)
    }
}

impl CpuFamily for HybridVolumeVariant {
    type Run = HybridVolumeRun;

    fn run_cpu(&self, f: &CpuFrame<'_>) -> Result<HybridVolumeRun, FrameError> {
        super::run_hybrid_volume(self, f.rectified, f.gbuf, f.scene, f.shadow_map, f.settings)
    }
}

impl CpuRun for MinmaxRun {
    fn output(&self) -> &Image {
        &self.output
    }

    fn report(&self) -> Option<&FrameReport> {
        Some(&self.frame.report)
    }
}

impl CpuRun for PartialSumTreeRun {
    fn output(&self) -> &Image {
        &self.output
    }

    fn report(&self) -> Option<&FrameReport> {
        Some(&self.frame.frame.report)
    }
}

impl CpuFamily for PartialSumTreeVariant {
    type Run = PartialSumTreeRun;

    fn run_cpu(&self, f: &CpuFrame<'_>) -> Result<PartialSumTreeRun, FrameError> {
        super::run_partial_sum_tree(self, f.rectified, f.gbuf, f.scene, f.shadow_map, f.settings)
    }
}

impl CpuFamily for PrefilteredVariant {
    type Run = PrefilteredRun;

    fn run_cpu(&self, f: &CpuFrame<'_>) -> Result<PrefilteredRun, FrameError> {
        super::run_prefiltered(
            self,
            f.rectified,
            f.scene,
            f.bvh,
            f.gbuf,
            f.shadow_map,
            f.settings,
        )
    }
}

impl CpuFamily for RaymarchVariant {
    type Run = RaymarchRun;

    fn run_cpu(&self, f: &CpuFrame<'_>) -> Result<RaymarchRun, FrameError> {
        super::run_raymarch(self, f.scene, f.gbuf, f.shadow_map)
    }
}

impl CpuFamily for MinmaxVariant {
    type Run = MinmaxRun;

    fn run_cpu(&self, f: &CpuFrame<'_>) -> Result<MinmaxRun, FrameError> {
        super::run_minmax(self, f.rectified, f.gbuf, f.scene, f.shadow_map, f.settings)
    }
}

/// The reference's one table of families: `Name(variant type)`, one line each; the names
/// are `FamilyVariant`'s.
macro_rules! cpu_families {
    ($($name:ident($ty:ty)),* $(,)?) => {
        /// Every intermediate of one CPU run of any family.
        #[derive(Clone, Debug)]
        pub enum FamilyRun {
            $(#[doc = concat!("A `", stringify!($name), "` run.")] $name(<$ty as CpuFamily>::Run),)*
        }

        impl CpuRun for FamilyRun {
            fn output(&self) -> &Image {
                match self {
                    $(Self::$name(r) => r.output(),)*
                }
            }

            fn report(&self) -> Option<&FrameReport> {
                match self {
                    $(Self::$name(r) => r.report(),)*
                }
            }
        }

        /// Runs the mirrors of every pass of `variant`, in pass order.
        ///
        /// # Errors
        ///
        /// [`FrameError`] when the frame cannot be set up.
        pub fn run_family(variant: &FamilyVariant, frame: &CpuFrame<'_>) -> Result<FamilyRun, FrameError> {
            Ok(match variant {
                $(FamilyVariant::$name(v) => FamilyRun::$name(v.run_cpu(frame)?),)*
            })
        }
    };
}

cpu_families! {
    AreaIvsv(AreaIvsvVariant),
    HybridVolume(HybridVolumeVariant),
    Minmax(MinmaxVariant),
    PartialSumTree(PartialSumTreeVariant),
    Prefiltered(PrefilteredVariant),
    Raymarch(RaymarchVariant),
}
