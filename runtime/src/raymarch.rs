//! The `raymarch` family (Tóth & Umenhoffer 2009) on wgpu: [`Raymarch`] owns the `raymarch`
//! pipeline (and `interleave_sum` for interleaved variants), the partial-sum and output
//! textures and the uniform buffer; an engine calls [`Raymarch::prepare`] and
//! [`Raymarch::encode`] once per frame with its depth buffer and standard shadow map.
//! [`run_raymarch_once`] is the upload-run-readback convenience the conformance tests use.
//!
//! | pass | bindings | dispatch |
//! |---|---|---|
//! | `raymarch` | 0 uniform `RaymarchFrame`, 1 depth r32float, 2 shadow map r32float, 3 output (storage, write: rgba16float radiance, or rgba32float partial sums when interleaved) | `ceil(W/8) x ceil(H/8) x 1` |
//! | `interleave_sum` (interleaved only) | 0 uniform `RaymarchFrame`, 1 partial sums rgba32float, 2 output rgba16float (storage, write) | `ceil(W/8) x ceil(H/8) x 1` |

use std::time::{Duration, Instant};

use scatter_shaderlib::prefiltered::{CameraDesc, LightDesc, MediumDesc, ShadowMapDesc};
use scatter_shaderlib::raymarch::{RaymarchUniforms, RaymarchVariant, prepare_raymarch};
use scatter_shaderlib::{Kernel, KernelParams};

use crate::error::{ErrorScopes, check_limit};
use crate::executor::Executor;
use crate::gpu::{
    DEPTH_NAMES, Readback, SHADOW_NAMES, check_nonempty, check_texture_sides, check_view,
    decode_rgba, upload_inputs,
};
use crate::prefiltered::FrameInput;
use crate::timer::median_pass_wall_times;
use crate::{Context, RuntimeError};

const RAYMARCH: Kernel = Kernel::Raymarch;
const INTERLEAVE_SUM: Kernel = Kernel::InterleaveSum;
const UNWARP: Kernel = Kernel::RaymarchUnwarp;
const FALLBACK: Kernel = Kernel::RaymarchFallback;

/// Format of the partial sums of an interleaved variant
/// (`scatter_shaderlib::raymarch::PARTIAL_FORMAT`).
pub const PARTIAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// One frame's camera, light, medium and standard shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaymarchInput {
    /// The camera.
    pub camera: CameraDesc,
    /// The light (its type must match the variant's).
    pub light: LightDesc,
    /// The homogeneous medium.
    pub medium: MediumDesc,
    /// The standard shadow map's projection and size (must match [`Raymarch::new`]).
    pub shadow_map: ShadowMapDesc,
}

impl From<&FrameInput> for RaymarchInput {
    /// The raymarch family's part of an epipolar family's frame input (it has no settings).
    fn from(f: &FrameInput) -> Self {
        Self {
            camera: f.camera,
            light: f.light,
            medium: f.medium,
            shadow_map: f.shadow_map,
        }
    }
}

/// GPU time of each pass of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RaymarchTimes {
    /// The `raymarch` pass.
    pub raymarch: Duration,
    /// The `interleave_sum` pass (zero without interleaving).
    pub interleave_sum: Duration,
    /// The `raymarch_unwarp` pass (zero per pixel).
    pub unwarp: Duration,
    /// The `raymarch_fallback` pass (zero per pixel).
    pub fallback: Duration,
}

impl RaymarchTimes {
    /// Sum of the passes.
    pub fn total(&self) -> Duration {
        self.raymarch + self.interleave_sum + self.unwarp + self.fallback
    }
}

/// The raymarch family for one [`RaymarchVariant`], sized for one screen and one shadow-map
/// size.
#[derive(Debug)]
pub struct Raymarch {
    variant: RaymarchVariant,
    screen: [u32; 2],
    shadow_map_size: u32,
    /// The plan of the variant, built.
    exec: Executor,
    uniforms: wgpu::Buffer,
    partial: Option<wgpu::Texture>,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    prepared: Option<RaymarchUniforms>,
    /// The spot's cookie ([`Self::set_cookie`]), for a variant with `cookie`.
    cookie: crate::cookie::CookieSlot,
}

impl Raymarch {
    /// Validates the variant and the sizes against the device and creates the pipelines,
    /// textures and buffers.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::InvalidRaymarchVariant`] naming the knob; [`RuntimeError::EmptyInput`]
    /// for a zero size; [`RuntimeError::LimitExceeded`] naming the device limit;
    /// [`RuntimeError::Shader`] or [`RuntimeError::Wgpu`] when a kernel or resource fails.
    pub fn new(
        ctx: &Context,
        variant: &RaymarchVariant,
        screen: [u32; 2],
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        variant
            .validate()
            .map_err(|source| RuntimeError::InvalidRaymarchVariant {
                variant: variant.id(),
                source,
            })?;
        let [w, h] = screen;
        check_nonempty(&[
            (RAYMARCH, "screen", screen),
            (RAYMARCH, "shadow map", [shadow_map_size; 2]),
        ])?;
        let device = ctx.device();
        let limits = device.limits();
        check_texture_sides(
            &limits,
            &[
                (RAYMARCH, "screen width", w),
                (RAYMARCH, "screen height", h),
                (RAYMARCH, "shadow map size", shadow_map_size),
            ],
        )?;
        check_limit(
            RAYMARCH,
            "uniform block bytes",
            size_of::<RaymarchUniforms>() as u64,
            "max_uniform_buffer_binding_size",
            limits.max_uniform_buffer_binding_size,
        )?;
        let built: Vec<_> = KernelParams::raymarch(*variant)
            .iter()
            .map(scatter_shaderlib::build)
            .collect::<Result<_, _>>()?;
        let exec = Executor::new(
            ctx,
            scatter_shaderlib::raymarch::plan::plan(variant),
            built,
            &[
                ("screen.width", w.into()),
                ("screen.height", h.into()),
                ("shadow.size", shadow_map_size.into()),
            ],
        )?;
        let uniforms = exec.buffer("frame")?.clone();
        let partial = if variant.interleaved() {
            Some(exec.texture("partial")?.0.clone())
        } else {
            None
        };
        let (output, output_view) = exec.texture("output")?;
        let (output, output_view) = (output.clone(), output_view.clone());
        Ok(Raymarch {
            variant: *variant,
            screen,
            shadow_map_size,
            exec,
            uniforms,
            partial,
            output,
            output_view,
            prepared: None,
            cookie: crate::cookie::CookieSlot::default(),
        })
    }

    /// Sets the spot light's cookie a `cookie` variant reads (kept until replaced; any size,
    /// one of [`crate::textures::COOKIE_FORMATS`], projected as `scatter_shaderlib::cookie`
    /// says). [`crate::textures::upload_cookie`] makes one from texels.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::NoCookie`] for a variant without `cookie`;
    /// [`RuntimeError::InputMismatch`] for a view of the wrong format, dimension or usage.
    pub fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
        self.cookie
            .set(self.variant.cookie, self.variant.id(), RAYMARCH, cookie)
    }

    /// Fills and uploads the uniform block of one frame.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::ShadowMapSize`] when the shadow map's size differs from
    /// [`Self::new`]'s; [`RuntimeError::Frame`] for NaN or degenerate parameters or a light
    /// of the wrong type.
    pub fn prepare(&mut self, ctx: &Context, input: &RaymarchInput) -> Result<(), RuntimeError> {
        if input.shadow_map.size != self.shadow_map_size {
            return Err(RuntimeError::ShadowMapSize {
                expected: self.shadow_map_size,
                actual: input.shadow_map.size,
            });
        }
        let u = prepare_raymarch(
            &self.variant,
            self.screen,
            &input.camera,
            &input.light,
            &input.medium,
            &input.shadow_map,
        )?;
        let scope = ErrorScopes::push(ctx.device());
        ctx.queue()
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        scope.pop(RAYMARCH, "uploading frame parameters")?;
        self.prepared = Some(u);
        Ok(())
    }

    /// Records the passes (with GPU timestamps when the device has them) and returns the
    /// output view: in-scattered radiance, rgba16float, screen-sized. `depth` is linear view
    /// depth (r32float, screen-sized), `shadow_map` the standard shadow map (r32float).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::NotPrepared`] before [`Self::prepare`];
    /// [`RuntimeError::InputMismatch`] for a view of the wrong format, size or usage;
    /// [`RuntimeError::Wgpu`] when wgpu rejects a bind group.
    pub fn encode(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::TextureView,
        shadow_map: &wgpu::TextureView,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        self.encode_selected(ctx, encoder, depth, shadow_map, None)
    }

    /// Wall time of each pass submitted on its own and waited for, the median over
    /// `frames` frames after one warm-up frame (on a CPU adapter such as lavapipe this is
    /// the pass's real cost; its timestamps are not).
    ///
    /// # Errors
    ///
    /// As [`Self::encode`]; [`RuntimeError::Poll`] when waiting fails.
    pub fn measure_pass_wall_times(
        &self,
        ctx: &Context,
        depth: &wgpu::TextureView,
        shadow_map: &wgpu::TextureView,
        frames: u32,
    ) -> Result<RaymarchTimes, RuntimeError> {
        // Without interleaving there is no `interleave_sum` pass: its slot records nothing.
        let [raymarch, interleave_sum, unwarp, fallback] = median_pass_wall_times(
            ctx,
            [RAYMARCH, INTERLEAVE_SUM, UNWARP, FALLBACK],
            frames,
            |encoder, kernel| {
                self.encode_selected(ctx, encoder, depth, shadow_map, Some(kernel))
                    .map(|_| ())
            },
        )?;
        Ok(RaymarchTimes {
            raymarch,
            interleave_sum: if self.partial.is_some() {
                interleave_sum
            } else {
                Duration::ZERO
            },
            unwarp: crate::timer::when(self.sampled(), unwarp),
            fallback: crate::timer::when(self.sampled(), fallback),
        })
    }

    /// Whether the variant samples (lowres or epipolar: it has the unwarp and fallback
    /// passes).
    fn sampled(&self) -> bool {
        self.variant.sampling != scatter_shaderlib::sampling::Sampling::Pixels
    }

    fn encode_selected(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::TextureView,
        shadow_map: &wgpu::TextureView,
        only: Option<Kernel>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        if self.prepared.is_none() {
            return Err(RuntimeError::NotPrepared { kernel: RAYMARCH });
        }
        check_view(RAYMARCH, &DEPTH_NAMES, depth, self.screen)?;
        check_view(
            RAYMARCH,
            &SHADOW_NAMES,
            shadow_map,
            [self.shadow_map_size; 2],
        )?;
        let mut engine = vec![("depth", depth), ("shadow_map", shadow_map)];
        self.cookie
            .bind(self.variant.cookie, RAYMARCH, &mut engine)?;
        self.exec
            .encode(ctx.device(), encoder, &engine, &[], only)?;
        Ok(&self.output_view)
    }

    /// GPU time of each pass of the last submitted [`Self::encode`], or `None` without
    /// timestamps. Blocks until the GPU is done.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
    pub fn pass_times(&self, ctx: &Context) -> Result<Option<RaymarchTimes>, RuntimeError> {
        let Some(timer) = self.exec.timer() else {
            return Ok(None);
        };
        let times = timer.read_all(ctx, RAYMARCH)?;
        Ok(Some(RaymarchTimes {
            raymarch: times.first().copied().unwrap_or_default(),
            interleave_sum: if self.partial.is_some() {
                times.get(1).copied().unwrap_or_default()
            } else {
                Duration::ZERO
            },
            unwarp: crate::timer::when(self.sampled(), times.get(1).copied().unwrap_or_default()),
            fallback: crate::timer::when(self.sampled(), times.get(2).copied().unwrap_or_default()),
        }))
    }

    /// The variant the pipelines were built for.
    pub fn variant(&self) -> &RaymarchVariant {
        &self.variant
    }

    /// The uniform block of the last [`Self::prepare`].
    pub fn uniforms(&self) -> Option<&RaymarchUniforms> {
        self.prepared.as_ref()
    }

    /// The output texture (rgba16float, screen-sized).
    pub fn output_texture(&self) -> &wgpu::Texture {
        &self.output
    }

    /// The partial sums of an interleaved variant (rgba32float).
    pub fn partial_texture(&self) -> Option<&wgpu::Texture> {
        self.partial.as_ref()
    }
}

/// Everything [`run_raymarch_once`] reads back.
#[derive(Clone, Debug)]
pub struct RaymarchReadback {
    /// The uploaded uniform block.
    pub uniforms: RaymarchUniforms,
    /// In-scattered radiance per pixel (rgba16float converted to f32), row-major.
    pub output: Vec<[f32; 4]>,
    /// The partial sums of an interleaved variant, row-major.
    pub partial: Option<Vec<[f32; 4]>>,
    /// GPU time per pass, when the device has timestamps.
    pub gpu_times: Option<RaymarchTimes>,
    /// Wall time from submission until every result was mapped.
    pub wall_time: Duration,
}

/// Test helper: creates a [`Raymarch`], uploads `depth` (screen-sized) and `shadow_map`
/// (`input.shadow_map.size` squared) as r32float textures and, for a `cookie` variant,
/// `cookie` (its size and RGBA texels) with [`crate::textures::upload_cookie`], runs one
/// frame and reads back.
///
/// # Errors
///
/// Whatever [`Raymarch::new`], [`Raymarch::prepare`] or [`Raymarch::encode`] fail with;
/// [`RuntimeError::DataLength`] when a buffer does not match its size; GPU errors.
pub fn run_raymarch_once(
    ctx: &Context,
    variant: &RaymarchVariant,
    screen: [u32; 2],
    input: &RaymarchInput,
    depth: &[f32],
    shadow_map: &[f32],
    cookie: Option<([u32; 2], &[[f32; 4]])>,
) -> Result<RaymarchReadback, RuntimeError> {
    let sm_size = input.shadow_map.size;
    let mut pass = Raymarch::new(ctx, variant, screen, sm_size)?;
    if let Some((size, texels)) = cookie {
        let texture = crate::textures::upload_cookie(ctx, RAYMARCH, size, texels)?;
        pass.set_cookie(&texture.create_view(&wgpu::TextureViewDescriptor::default()))?;
    }
    let views = upload_inputs(
        ctx,
        &[
            (RAYMARCH, "depth buffer", screen, depth),
            (RAYMARCH, "shadow map", [sm_size; 2], shadow_map),
        ],
    )?;
    pass.prepare(ctx, input)?;
    let device = ctx.device();
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("raymarch run_prefiltered_once"),
    });
    pass.encode(ctx, &mut encoder, &views[0].1, &views[1].1)?;
    let scope = ErrorScopes::push(device);
    let partial = pass
        .partial_texture()
        .map(|t| Readback::encode(device, &mut encoder, t, 16, RAYMARCH))
        .transpose()?;
    let output = Readback::encode(device, &mut encoder, pass.output_texture(), 8, RAYMARCH)?;
    let start = Instant::now();
    ctx.queue().submit([encoder.finish()]);
    scope.pop(RAYMARCH, "dispatch")?;
    let partial = match partial {
        Some(r) => Some(
            r.read(ctx, RAYMARCH)?
                .chunks_exact(16)
                .map(|t| decode_rgba(t, scatter_shaderlib::prefiltered::Storage::Rgba32float))
                .collect(),
        ),
        None => None,
    };
    let output = output
        .read(ctx, RAYMARCH)?
        .chunks_exact(8)
        .map(|t| decode_rgba(t, scatter_shaderlib::prefiltered::Storage::Rgba16float))
        .collect();
    let wall_time = start.elapsed();
    let gpu_times = pass.pass_times(ctx)?;
    let uniforms = pass
        .prepared
        .ok_or(RuntimeError::NotPrepared { kernel: RAYMARCH })?;
    Ok(RaymarchReadback {
        uniforms,
        output,
        partial,
        gpu_times,
        wall_time,
    })
}

impl crate::family::FamilyRuntime for Raymarch {
    type Variant = RaymarchVariant;

    /// Uses only `res.screen`.
    fn create(
        ctx: &Context,
        variant: &RaymarchVariant,
        res: scatter_shaderlib::prefiltered::Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        Self::new(ctx, variant, res.screen, shadow_map_size)
    }

    fn knobs(&self) -> RaymarchVariant {
        self.variant
    }

    /// Ignores `input.settings`; raymarch has no frame report.
    fn prepare_frame(
        &mut self,
        ctx: &Context,
        input: &FrameInput,
    ) -> Result<Option<scatter_shaderlib::prefiltered::FrameReport>, RuntimeError> {
        self.prepare(ctx, &input.into()).map(|()| None)
    }

    fn encode_frame(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &crate::prefiltered::Inputs<'_>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        let shadow_map = crate::family::required_shadow_map(inputs, RAYMARCH)?;
        self.encode(ctx, encoder, inputs.depth, shadow_map)
    }

    fn output(&self) -> &wgpu::Texture {
        &self.output
    }

    fn total_pass_time(&self, ctx: &Context) -> Result<Option<Duration>, RuntimeError> {
        Ok(self.pass_times(ctx)?.map(|t| t.total()))
    }

    fn fallback_pixels(&self, ctx: &Context) -> Result<Option<u32>, RuntimeError> {
        crate::family::read_fallback_count(ctx, &self.exec, UNWARP)
    }

    fn pass_wall_times(
        &self,
        ctx: &Context,
        inputs: &crate::prefiltered::Inputs<'_>,
        frames: u32,
    ) -> Result<Vec<(Kernel, Duration)>, RuntimeError> {
        let shadow_map = crate::family::required_shadow_map(inputs, RAYMARCH)?;
        let t = self.measure_pass_wall_times(ctx, inputs.depth, shadow_map, frames)?;
        let mut passes = vec![(RAYMARCH, t.raymarch)];
        if self.variant.interleaved() {
            passes.push((INTERLEAVE_SUM, t.interleave_sum));
        }
        if self.sampled() {
            passes.push((UNWARP, t.unwarp));
            passes.push((FALLBACK, t.fallback));
        }
        Ok(passes)
    }

    fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
        Raymarch::set_cookie(self, cookie)
    }
}
