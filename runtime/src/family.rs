//! Any family's passes behind one type: [`FamilyPasses`] is built from the one enum of every
//! family's variant ([`FamilyVariant`]) and driven with the same frame input and textures
//! whatever the family, so that tools and tests (the flicker test, ...) need no list of
//! families of their own.

use std::time::Duration;

use scatter_shaderlib::Kernel;
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::prefiltered::{FrameReport, Resolutions};

use crate::prefiltered::{FrameInput, Inputs};
use crate::{Context, Minmax, Prefiltered, Raymarch, RuntimeError};

/// The passes of one variant of any family, sized for one set of resolutions.
#[derive(Debug)]
pub enum FamilyPasses {
    /// The prefiltered family.
    Prefiltered(Prefiltered),
    /// The raymarch family (it uses only the screen size of the resolutions).
    Raymarch(Raymarch),
    /// The minmax family.
    Minmax(Minmax),
}

impl FamilyPasses {
    /// Builds the variant's passes ([`Prefiltered::new`], [`Raymarch::new`], [`Minmax::new`]).
    ///
    /// # Errors
    ///
    /// As the family's `new`.
    pub fn new(
        ctx: &Context,
        variant: &FamilyVariant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        Ok(match variant {
            FamilyVariant::Prefiltered(v) => {
                Self::Prefiltered(Prefiltered::new(ctx, v, res, shadow_map_size)?)
            }
            FamilyVariant::Raymarch(v) => {
                Self::Raymarch(Raymarch::new(ctx, v, res.screen, shadow_map_size)?)
            }
            FamilyVariant::Minmax(v) => Self::Minmax(Minmax::new(ctx, v, res, shadow_map_size)?),
        })
    }

    /// The variant the passes were built for.
    pub fn variant(&self) -> FamilyVariant {
        match self {
            Self::Prefiltered(p) => (*p.variant()).into(),
            Self::Raymarch(p) => (*p.variant()).into(),
            Self::Minmax(p) => (*p.variant()).into(),
        }
    }

    /// Sets up and uploads one frame; the epipolar families return their frame report
    /// (raymarch has none and ignores `input.settings`).
    ///
    /// # Errors
    ///
    /// As the family's `prepare`.
    pub fn prepare(
        &mut self,
        ctx: &Context,
        input: &FrameInput,
    ) -> Result<Option<FrameReport>, RuntimeError> {
        match self {
            Self::Prefiltered(p) => p.prepare(ctx, input).map(Some),
            Self::Raymarch(p) => p.prepare(ctx, &input.into()).map(|()| None),
            Self::Minmax(p) => {
                p.prepare(ctx, input)?;
                Ok(p.frame().map(|f| f.report.clone()))
            }
        }
    }

    fn shadow_map<'a>(&self, inputs: &Inputs<'a>) -> Result<&'a wgpu::TextureView, RuntimeError> {
        let kernel = match self {
            Self::Prefiltered(_) => Kernel::Rectify,
            Self::Raymarch(_) => Kernel::Raymarch,
            Self::Minmax(_) => Kernel::Rectify,
        };
        inputs.shadow_map.ok_or(RuntimeError::MissingInput {
            kernel,
            what: "the standard shadow map",
        })
    }

    /// Records the frame's passes and returns the output view (rgba16float radiance).
    ///
    /// # Errors
    ///
    /// As the family's `encode`; [`RuntimeError::MissingInput`] when raymarch or minmax
    /// get no standard shadow map.
    pub fn encode(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &Inputs<'_>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        match self {
            Self::Prefiltered(p) => p.encode(encoder, inputs),
            Self::Raymarch(p) => p.encode(ctx, encoder, inputs.depth, self.shadow_map(inputs)?),
            Self::Minmax(p) => p.encode(ctx, encoder, inputs.depth, self.shadow_map(inputs)?),
        }
    }

    /// The output texture (rgba16float, screen-sized).
    pub fn output_texture(&self) -> &wgpu::Texture {
        match self {
            Self::Prefiltered(p) => p.output_texture(),
            Self::Raymarch(p) => p.output_texture(),
            Self::Minmax(p) => p.output_texture(),
        }
    }

    /// GPU time of the last submitted frame's passes added up, or `None` without
    /// timestamps. Blocks until the GPU is done.
    ///
    /// # Errors
    ///
    /// As the family's `pass_times`.
    pub fn total_pass_time(&self, ctx: &Context) -> Result<Option<Duration>, RuntimeError> {
        Ok(match self {
            Self::Prefiltered(p) => p.pass_times(ctx)?.map(|t| t.total()),
            Self::Raymarch(p) => p.pass_times(ctx)?.map(|t| t.total()),
            Self::Minmax(p) => p.pass_times(ctx)?.map(|t| t.total()),
        })
    }

    /// Wall time of each pass the variant has, submitted on its own, the median over
    /// `frames` frames, in pass order with its kernel.
    ///
    /// # Errors
    ///
    /// As the family's `measure_pass_wall_times`.
    pub fn measure_pass_wall_times(
        &self,
        ctx: &Context,
        inputs: &Inputs<'_>,
        frames: u32,
    ) -> Result<Vec<(Kernel, Duration)>, RuntimeError> {
        Ok(match self {
            Self::Prefiltered(p) => {
                let t = p.measure_pass_wall_times(ctx, inputs, frames)?;
                vec![
                    (Kernel::Rectify, t.rectify),
                    (Kernel::Prefilter, t.prefilter),
                    (Kernel::Scatter, t.scatter),
                ]
            }
            Self::Raymarch(p) => {
                let t =
                    p.measure_pass_wall_times(ctx, inputs.depth, self.shadow_map(inputs)?, frames)?;
                let mut passes = vec![(Kernel::Raymarch, t.raymarch)];
                if p.variant().interleaved() {
                    passes.push((Kernel::InterleaveSum, t.interleave_sum));
                }
                passes
            }
            Self::Minmax(p) => {
                let t =
                    p.measure_pass_wall_times(ctx, inputs.depth, self.shadow_map(inputs)?, frames)?;
                vec![
                    (Kernel::Rectify, t.rectify),
                    (Kernel::MinmaxBuild, t.build),
                    (Kernel::MinmaxMarch, t.march),
                ]
            }
        })
    }
}
