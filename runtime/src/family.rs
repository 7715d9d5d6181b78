//! Any family's passes behind one type: [`FamilyPasses`] is built from the one enum of every
//! family's variant ([`FamilyVariant`]) and driven with the same frame input and textures
//! whatever the family, so that tools and tests (the bench, the flicker test, ...) need no
//! list of families of their own.
//!
//! Each family's runtime type implements [`FamilyRuntime`] in its own module (what its
//! `new` / `prepare` / `encode` need from the common inputs); [`FamilyPasses`] comes from
//! one table, one line per family.

use std::time::Duration;

use scatter_shaderlib::Kernel;
use scatter_shaderlib::family::FamilyVariant;
use scatter_shaderlib::prefiltered::{FrameReport, Resolutions};

use crate::gpu::upload_inputs;
use crate::prefiltered::{CpuInputs, FrameInput, Inputs};
use crate::textures::read_rgba16float;
use crate::{
    AreaIvsv, Context, HybridVolume, Minmax, PartialSumTree, Prefiltered, Raymarch, RuntimeError,
};

/// What a family's runtime type offers with the inputs every family takes: the frame input
/// of the epipolar families (a family ignores what it does not use) and the engine's
/// textures as [`Inputs`].
pub trait FamilyRuntime: Sized {
    /// The family's variant type.
    type Variant: Copy + Into<FamilyVariant>;

    /// Validates and builds the variant's passes for `res` and a `shadow_map_size`^2 map.
    ///
    /// # Errors
    ///
    /// As the family's `new`.
    fn create(
        ctx: &Context,
        variant: &Self::Variant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError>;

    /// The variant the passes were built for.
    fn knobs(&self) -> Self::Variant;

    /// Sets up and uploads one frame; the epipolar families return their frame report.
    ///
    /// # Errors
    ///
    /// As the family's `prepare`.
    fn prepare_frame(
        &mut self,
        ctx: &Context,
        input: &FrameInput,
    ) -> Result<Option<FrameReport>, RuntimeError>;

    /// Records the frame's passes and returns the output view.
    ///
    /// # Errors
    ///
    /// As the family's `encode`; [`RuntimeError::MissingInput`] for a texture it needs that
    /// `inputs` lacks.
    fn encode_frame(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &Inputs<'_>,
    ) -> Result<&wgpu::TextureView, RuntimeError>;

    /// The output texture (rgba16float, screen-sized).
    fn output(&self) -> &wgpu::Texture;

    /// GPU time of the last submitted frame's passes added up, or `None` without
    /// timestamps.
    ///
    /// # Errors
    ///
    /// As the family's `pass_times`.
    fn total_pass_time(&self, ctx: &Context) -> Result<Option<Duration>, RuntimeError>;

    /// Wall time of each pass the variant has, submitted on its own, the median over
    /// `frames` frames, in pass order with its kernel.
    ///
    /// # Errors
    ///
    /// As the family's `measure_pass_wall_times`.
    fn pass_wall_times(
        &self,
        ctx: &Context,
        inputs: &Inputs<'_>,
        frames: u32,
    ) -> Result<Vec<(Kernel, Duration)>, RuntimeError>;

    /// How many pixels the last submitted frame's `_unwarp` pass listed for its `_fallback`
    /// pass, or `None` without epipolar sampling. Blocks until the GPU is done.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
    fn fallback_pixels(&self, ctx: &Context) -> Result<Option<u32>, RuntimeError>;

    /// Sets the spot light's cookie a `cookie` variant reads (`scatter_shaderlib::cookie`).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::NoCookie`] for a family or variant without the `cookie` knob;
    /// [`RuntimeError::InputMismatch`] for a view of the wrong format, dimension or usage.
    fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
        let _ = cookie;
        Err(RuntimeError::NoCookie {
            variant: self.knobs().into().to_string(),
        })
    }
}

/// The `fallback_count` buffer of `exec`'s plan read back (`None` when the plan has none:
/// no epipolar sampling); `kernel` is blamed for a failed readback.
pub(crate) fn read_fallback_count(
    ctx: &Context,
    exec: &crate::executor::Executor,
    kernel: Kernel,
) -> Result<Option<u32>, RuntimeError> {
    let Some(buffer) = exec.buffer_if_any(scatter_shaderlib::sampling::FALLBACK_COUNT) else {
        return Ok(None);
    };
    let mut encoder = ctx
        .device()
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("fallback_count readback"),
        });
    let staging = crate::gpu::encode_buffer_readback(ctx.device(), &mut encoder, buffer);
    ctx.queue().submit([encoder.finish()]);
    let bytes = crate::timer::read_buffer(ctx, kernel, &staging)?;
    let count: [u8; 4] = bytes
        .get(..4)
        .and_then(|b| b.try_into().ok())
        .ok_or_else(|| RuntimeError::Readback {
            kernel,
            message: format!("fallback_count holds {} bytes, fewer than 4", bytes.len()),
        })?;
    Ok(Some(u32::from_le_bytes(count)))
}

/// The standard shadow map of `inputs`, which `kernel`'s family needs in every frame.
pub(crate) fn required_shadow_map<'a>(
    inputs: &Inputs<'a>,
    kernel: Kernel,
) -> Result<&'a wgpu::TextureView, RuntimeError> {
    inputs.shadow_map.ok_or(RuntimeError::MissingInput {
        kernel,
        what: "the standard shadow map",
    })
}

/// The runtime's one table of families: `Name(runtime type)`, one line each; the names are
/// `FamilyVariant`'s.
macro_rules! runtime_families {
    ($($(#[$doc:meta])* $name:ident($ty:ty)),* $(,)?) => {
        /// The passes of one variant of any family, sized for one set of resolutions.
        #[derive(Debug)]
        #[allow(
            clippy::large_enum_variant,
            reason = "created once per set of passes and kept; the variants hold wgpu handles"
        )]
        pub enum FamilyPasses {
            $($(#[$doc])* $name($ty),)*
        }

        impl FamilyPasses {
            /// Builds the variant's passes (the family's `new`).
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
                    $(FamilyVariant::$name(v) => {
                        Self::$name(<$ty>::create(ctx, v, res, shadow_map_size)?)
                    })*
                })
            }

            /// The variant the passes were built for.
            pub fn variant(&self) -> FamilyVariant {
                match self {
                    $(Self::$name(p) => p.knobs().into(),)*
                }
            }

            /// Sets up and uploads one frame; the epipolar families return their frame
            /// report (raymarch has none and ignores `input.settings`).
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
                    $(Self::$name(p) => p.prepare_frame(ctx, input),)*
                }
            }

            /// Records the frame's passes and returns the output view (rgba16float radiance).
            ///
            /// # Errors
            ///
            /// As the family's `encode`; [`RuntimeError::MissingInput`] when raymarch or
            /// minmax get no standard shadow map.
            pub fn encode(
                &self,
                ctx: &Context,
                encoder: &mut wgpu::CommandEncoder,
                inputs: &Inputs<'_>,
            ) -> Result<&wgpu::TextureView, RuntimeError> {
                match self {
                    $(Self::$name(p) => p.encode_frame(ctx, encoder, inputs),)*
                }
            }

            /// The output texture (rgba16float, screen-sized).
            pub fn output_texture(&self) -> &wgpu::Texture {
                match self {
                    $(Self::$name(p) => p.output(),)*
                }
            }

            /// GPU time of the last submitted frame's passes added up, or `None` without
            /// timestamps. Blocks until the GPU is done.
            ///
            /// # Errors
            ///
            /// As the family's `pass_times`.
            pub fn total_pass_time(&self, ctx: &Context) -> Result<Option<Duration>, RuntimeError> {
                match self {
                    $(Self::$name(p) => p.total_pass_time(ctx),)*
                }
            }

            /// Sets the spot light's cookie a `cookie` variant reads.
            ///
            /// # Errors
            ///
            /// As the family's `set_cookie`: [`RuntimeError::NoCookie`] for a variant
            /// without the `cookie` knob.
            pub fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
                match self {
                    $(Self::$name(p) => p.set_cookie(cookie),)*
                }
            }

            /// How many pixels the last submitted frame's `_unwarp` pass listed for its
            /// `_fallback` pass, or `None` without epipolar sampling. Blocks until the GPU is
            /// done.
            ///
            /// # Errors
            ///
            /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
            pub fn fallback_pixels(&self, ctx: &Context) -> Result<Option<u32>, RuntimeError> {
                match self {
                    $(Self::$name(p) => p.fallback_pixels(ctx),)*
                }
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
                match self {
                    $(Self::$name(p) => p.pass_wall_times(ctx, inputs, frames),)*
                }
            }
        }
    };
}

runtime_families! {
    /// The area-light family (imperfect voxelized shadow volumes).
    AreaIvsv(AreaIvsv),
    /// The hybrid shadow-volume family.
    HybridVolume(HybridVolume),
    /// The minmax family.
    Minmax(Minmax),
    /// The partial-sum-tree family.
    PartialSumTree(PartialSumTree),
    /// The prefiltered family.
    Prefiltered(Prefiltered),
    /// The raymarch family (it uses only the screen size of the resolutions).
    Raymarch(Raymarch),
}

/// What [`run_family_once`] reads back: the output and the frame report of any family.
#[derive(Clone, Debug)]
pub struct FamilyReadback {
    /// In-scattered radiance per pixel (rgba16float converted to f32), row-major.
    pub output: Vec<[f32; 4]>,
    /// The frame report of the epipolar families (`None` for raymarch).
    pub report: Option<FrameReport>,
    /// Median wall time of each pass submitted on its own, in pass order, when
    /// [`CpuInputs::pass_wall_frames`] is non-zero (empty otherwise).
    pub pass_wall_times: Vec<(Kernel, Duration)>,
    /// With epipolar sampling, the pixels the `_unwarp` pass listed for the `_fallback`
    /// pass (no sample stands for them); `None` otherwise.
    pub fallback_pixels: Option<u32>,
}

/// Test and tool helper for any family: builds `variant`'s passes, uploads `inputs` (the
/// depth buffer, the standard shadow map and, for a projective frame, the engine's
/// rasterised rectified map) as r32float textures, runs one frame and reads the output back.
///
/// # Errors
///
/// As [`FamilyPasses::new`], `prepare` and `encode`; [`RuntimeError::DataLength`] for an
/// input whose length does not match its size.
pub fn run_family_once(
    ctx: &Context,
    variant: &FamilyVariant,
    res: Resolutions,
    inputs: &CpuInputs,
) -> Result<FamilyReadback, RuntimeError> {
    let mut pass = FamilyPasses::new(ctx, variant, res, inputs.frame.shadow_map.size)?;
    run_family_on(ctx, &mut pass, res, inputs)
}

/// [`run_family_once`] on passes already built, for many frames of one variant (as an engine
/// keeps its passes; on lavapipe with a cold Mesa cache, passes built anew per frame compile
/// their kernels again). `res` and `inputs.frame.shadow_map.size` must be the ones `pass`
/// was built with.
///
/// # Errors
///
/// As [`run_family_once`] but for building the passes.
pub fn run_family_on(
    ctx: &Context,
    pass: &mut FamilyPasses,
    res: Resolutions,
    inputs: &CpuInputs,
) -> Result<FamilyReadback, RuntimeError> {
    let variant = &pass.variant();
    let sm_size = inputs.frame.shadow_map.size;
    let kernels: Vec<Kernel> = scatter_shaderlib::family::KernelFamily::kernel_params(variant)
        .iter()
        .map(scatter_shaderlib::KernelParams::kernel)
        .collect();
    // The kernels to blame for a bad depth buffer (the last pass reads it) and a bad
    // shadow map (the first pass of the epipolar families, the only one of raymarch).
    let first = kernels.first().copied().unwrap_or(Kernel::Scatter);
    let last = kernels.last().copied().unwrap_or(Kernel::Scatter);
    let mut cpu = vec![
        (last, "depth buffer", res.screen, &inputs.depth[..]),
        (first, "shadow map", [sm_size; 2], &inputs.shadow_map[..]),
    ];
    if let Some(data) = &inputs.rectified {
        cpu.push((first, "rasterised rectified map", res.rectified, &data[..]));
    }
    let views = upload_inputs(ctx, &cpu)?;
    let vpl_maps = match &inputs.vpl_maps {
        Some(data) => {
            let per_layer = (sm_size as usize).pow(2);
            if per_layer == 0 || data.len() % per_layer != 0 {
                return Err(RuntimeError::DataLength {
                    kernel: first,
                    size: format!("VPL shadow maps of {sm_size}x{sm_size} per layer"),
                    expected: (data.len().div_ceil(per_layer.max(1)) * per_layer) as u64,
                    actual: data.len() as u64,
                });
            }
            let layers = u32::try_from(data.len() / per_layer).unwrap_or(u32::MAX);
            Some(crate::area_ivsv::upload_vpl_maps(
                ctx, sm_size, layers, data,
            )?)
        }
        None => None,
    };
    if let Some((size, texels)) = &inputs.cookie {
        let texture = crate::textures::upload_cookie(ctx, first, *size, texels)?;
        pass.set_cookie(&texture.create_view(&wgpu::TextureViewDescriptor::default()))?;
    }
    let report = pass.prepare(ctx, &inputs.frame)?;
    let gpu_inputs = Inputs {
        depth: &views[0].1,
        shadow_map: Some(&views[1].1),
        rectified: views.get(2).map(|(_, v)| v),
        vpl_maps: vpl_maps.as_ref().map(|(_, v)| v),
    };
    let mut encoder = ctx
        .device()
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("run_family_once"),
        });
    pass.encode(ctx, &mut encoder, &gpu_inputs)?;
    ctx.queue().submit([encoder.finish()]);
    let output = read_rgba16float(ctx, last, pass.output_texture())?;
    let fallback_pixels = pass.fallback_pixels(ctx)?;
    let pass_wall_times = if inputs.pass_wall_frames > 0 {
        pass.measure_pass_wall_times(ctx, &gpu_inputs, inputs.pass_wall_frames)?
    } else {
        Vec::new()
    };
    Ok(FamilyReadback {
        output,
        report,
        pass_wall_times,
        fallback_pixels,
    })
}
