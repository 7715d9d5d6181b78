//! The `partial_sum_tree` family (Baran et al. 2010) on wgpu: [`PartialSumTree`] owns the
//! `depth_columns`, `slice_fit` and `rectify` (the prefiltered family's kernels, for
//! [`PartialSumTreeVariant::prefiltered`]), `pst_sweep`, `pst_sweep_unwarp` and
//! `pst_sweep_fallback` pipelines, the rectified map, the epipolar samples, the sweep's
//! scratch buffers and the output; an engine calls [`PartialSumTree::prepare`] and
//! [`PartialSumTree::encode`] once per frame with its depth buffer and standard shadow map.
//! [`run_partial_sum_tree_once`] is the upload-run-readback convenience the conformance tests
//! use.
//!
//! | pass | bindings | dispatch |
//! |---|---|---|
//! | `depth_columns` | 0 uniform `Frame`, 1 depth, 2 column_depth | `ceil(W/64) x 1 x 1` |
//! | `slice_fit` | 0 uniform `Frame`, 1 slices (read_write), 2 column_depth | `1 x 1 x 1` |
//! | `rectify` | 0 uniform `Frame`, 1 slices, 2 shadow map, 3 rectified (storage, write) | `ceil(Wr/64) x Hr x 1` |
//! | `pst_sweep` | 0 `Frame`, 1 slices, 2 depth, 3 shadow map, 4 rectified, 5 pst_factors, 6-8 scratch, 9 epipolar_samples (rgba32float, write), 11 fallback_count | `slices x 1 x 1` (32 lanes each) |
//! | `pst_sweep_unwarp` | 0 `Frame`, 2 depth, 9 output, 10 epipolar_samples, 11 fallback_count, 12 fallback_pixels | `ceil(W/8) x ceil(H/8) x 1` |
//! | `pst_sweep_fallback` | 0-5, 9 output, 11 fallback_count, 12 fallback_pixels | indirect from `fallback_count` (byte 4): one invocation per listed pixel, workgroups of 64 |

use std::time::{Duration, Instant};

use scatter_shaderlib::Kernel;
use scatter_shaderlib::family::KernelFamily;
use scatter_shaderlib::partial_sum_tree::{
    PartialSumTreeFrame, PartialSumTreeVariant, TREES, prepare_partial_sum_tree,
};
use scatter_shaderlib::prefiltered::{Resolutions, SliceParams, Storage};

use crate::error::{ErrorScopes, check_limit};
use crate::executor::Executor;
use crate::gpu::{
    DEPTH_NAMES, Readback, SHADOW_NAMES, check_nonempty, check_texture_sides, check_view,
    decode_rgba, encode_buffer_readback, read_slices, upload_inputs,
};
use crate::prefiltered::FrameInput;
use crate::timer::median_pass_wall_times;
use crate::{Context, RuntimeError};

const DEPTH_COLUMNS: Kernel = Kernel::DepthColumns;
const SLICE_FIT: Kernel = Kernel::SliceFit;
const RECTIFY: Kernel = Kernel::Rectify;
const SWEEP: Kernel = Kernel::PstSweep;
const UNWARP: Kernel = Kernel::PstSweepUnwarp;
const FALLBACK: Kernel = Kernel::PstSweepFallback;

/// GPU time of each pass of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PartialSumTreeTimes {
    /// The `depth_columns` pass.
    pub depth_columns: Duration,
    /// The `slice_fit` pass.
    pub slice_fit: Duration,
    /// The `rectify` pass.
    pub rectify: Duration,
    /// The `pst_sweep` pass.
    pub sweep: Duration,
    /// The `pst_sweep_unwarp` pass.
    pub unwarp: Duration,
    /// The `pst_sweep_fallback` pass.
    pub fallback: Duration,
}

impl PartialSumTreeTimes {
    /// Sum of the passes.
    pub fn total(&self) -> Duration {
        self.depth_columns
            + self.slice_fit
            + self.rectify
            + self.sweep
            + self.unwarp
            + self.fallback
    }
}

/// The partial-sum-tree family for one [`PartialSumTreeVariant`], sized for one screen, one
/// rectified map and one shadow-map size.
#[derive(Debug)]
pub struct PartialSumTree {
    variant: PartialSumTreeVariant,
    res: Resolutions,
    shadow_map_size: u32,
    /// The plan of the variant, built.
    exec: Executor,
    uniforms: wgpu::Buffer,
    slices: wgpu::Buffer,
    factors: wgpu::Buffer,
    rectified: wgpu::Texture,
    samples: wgpu::Texture,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    frame: Option<PartialSumTreeFrame>,
    /// The spot's cookie ([`Self::set_cookie`]), for a variant with `cookie`.
    cookie: crate::cookie::CookieSlot,
}

impl PartialSumTree {
    /// Validates the sizes against the device and creates the pipelines, textures and
    /// buffers. `res.rectified` is the rectified map (`Wr` light rays per row by `Hr` rows);
    /// the sweep's scratch holds `slices x Wr x ceil(rank / 4)` leaves (16 bytes each; three
    /// times that with a cookie).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::EmptyInput`] for a zero size; [`RuntimeError::LimitExceeded`] naming
    /// the device limit (a texture side, the scratch buffers' size, the sweep's workgroup
    /// memory); [`RuntimeError::Shader`] or [`RuntimeError::Wgpu`] when a kernel or resource
    /// fails.
    pub fn new(
        ctx: &Context,
        variant: &PartialSumTreeVariant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        let [w, h] = res.screen;
        let [wr, hr] = res.rectified;
        check_nonempty(&[
            (SWEEP, "screen", res.screen),
            (RECTIFY, "rectified", res.rectified),
            (RECTIFY, "shadow map", [shadow_map_size; 2]),
        ])?;
        let device = ctx.device();
        let limits = device.limits();
        check_texture_sides(
            &limits,
            &[
                (SWEEP, "screen width", w),
                (SWEEP, "screen height", h),
                (RECTIFY, "rectified width", wr),
                (RECTIFY, "rectified height", hr),
                (RECTIFY, "shadow map size", shadow_map_size),
            ],
        )?;
        crate::prefiltered::check_frame_buffers(&limits, hr)?;
        let leaves =
            u64::from(variant.slices) * u64::from(wr) * u64::from(variant.leaf_vecs()) * 16;
        let trees = u64::from(variant.slices)
            * u64::from(TREES + 1)
            * u64::from(variant.slice_samples)
            * u64::from(variant.leaf_vecs())
            * 16;
        for (name, limit) in [
            (
                "max_storage_buffer_binding_size",
                limits.max_storage_buffer_binding_size,
            ),
            ("max_buffer_size", limits.max_buffer_size),
        ] {
            check_limit(
                SWEEP,
                "sweep leaves bytes (slices x rectified width x 16 per 4 ranks)",
                leaves,
                name,
                limit,
            )?;
            check_limit(
                SWEEP,
                "sweep trees bytes (slices x 9 x slice samples x 16 per 4 ranks)",
                trees,
                name,
                limit,
            )?;
        }
        // The sweep's seven per-sample arrays of 4 bytes and its live counter.
        check_limit(
            SWEEP,
            "sweep workgroup memory bytes (28 per sample of a slice, and 4)",
            28 * u64::from(variant.slice_samples) + 4,
            "max_compute_workgroup_storage_size",
            limits.max_compute_workgroup_storage_size.into(),
        )?;
        let built = variant
            .kernel_params()
            .iter()
            .map(scatter_shaderlib::build)
            .collect::<Result<Vec<_>, _>>()?;
        let exec = Executor::new(
            ctx,
            scatter_shaderlib::partial_sum_tree::plan::plan(variant),
            built,
            &[
                ("screen.width", w.into()),
                ("screen.height", h.into()),
                ("shadow.size", shadow_map_size.into()),
                ("rectified.width", wr.into()),
                ("rectified.height", hr.into()),
            ],
        )?;
        let (output, output_view) = exec.texture("output")?;
        Ok(PartialSumTree {
            variant: *variant,
            res,
            shadow_map_size,
            uniforms: exec.buffer("frame")?.clone(),
            slices: exec.buffer("slices")?.clone(),
            factors: exec.buffer("pst_factors")?.clone(),
            rectified: exec.texture("rectified")?.0.clone(),
            samples: exec.texture("epipolar_samples")?.0.clone(),
            output: output.clone(),
            output_view: output_view.clone(),
            exec,
            frame: None,
            cookie: crate::cookie::CookieSlot::default(),
        })
    }

    /// Sets the spot light's cookie a `cookie` variant reads (kept until replaced; any size,
    /// one of [`crate::textures::COOKIE_FORMATS`], projected as `scatter_shaderlib::cookie`
    /// says): every column's leaf, the last column and the march carry it.
    /// [`crate::textures::upload_cookie`] makes one from texels.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::NoCookie`] for a variant without `cookie`;
    /// [`RuntimeError::InputMismatch`] for a view of the wrong format, dimension or usage.
    pub fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
        self.cookie
            .set(self.variant.cookie, self.variant.id(), SWEEP, cookie)
    }

    /// Sets up one frame ([`prepare_partial_sum_tree`]: the epipolar frame and the rank-r
    /// SVD of the integrand) and uploads its uniforms, slice table and factors.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::ShadowMapSize`] when the shadow map's size differs from
    /// [`Self::new`]'s; [`RuntimeError::Frame`] for NaN or degenerate parameters or a light
    /// of the wrong type; [`RuntimeError::Wgpu`] when an upload fails.
    pub fn prepare(&mut self, ctx: &Context, input: &FrameInput) -> Result<(), RuntimeError> {
        if input.shadow_map.size != self.shadow_map_size {
            return Err(RuntimeError::ShadowMapSize {
                expected: self.shadow_map_size,
                actual: input.shadow_map.size,
            });
        }
        let prepared = prepare_partial_sum_tree(
            &self.variant,
            &self.res,
            &input.camera,
            &input.light,
            &input.medium,
            &input.shadow_map,
            &input.settings,
        )?;
        let rows = self.res.rectified[1] as usize;
        if prepared.frame.slices.len() != rows {
            return Err(RuntimeError::DataLength {
                kernel: RECTIFY,
                size: format!("slice table of {rows} rows"),
                expected: rows as u64,
                actual: prepared.frame.slices.len() as u64,
            });
        }
        let scope = ErrorScopes::push(ctx.device());
        let queue = ctx.queue();
        queue.write_buffer(
            &self.uniforms,
            0,
            bytemuck::bytes_of(&prepared.frame.uniforms),
        );
        queue.write_buffer(
            &self.slices,
            0,
            bytemuck::cast_slice(&prepared.frame.slices),
        );
        queue.write_buffer(&self.factors, 0, bytemuck::cast_slice(&prepared.factors));
        scope.pop(SWEEP, "uploading frame parameters")?;
        self.frame = Some(prepared);
        Ok(())
    }

    /// Records the six passes (with GPU timestamps when the device has them) and returns
    /// the output view: in-scattered radiance, rgba16float, screen-sized. `depth` is linear
    /// view depth (r32float, screen-sized), `shadow_map` the standard shadow map (r32float).
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
    /// `frames` frames after one warm-up frame.
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
    ) -> Result<PartialSumTreeTimes, RuntimeError> {
        let [depth_columns, slice_fit, rectify, sweep, unwarp, fallback] = median_pass_wall_times(
            ctx,
            [DEPTH_COLUMNS, SLICE_FIT, RECTIFY, SWEEP, UNWARP, FALLBACK],
            frames,
            |encoder, kernel| {
                self.encode_selected(ctx, encoder, depth, shadow_map, Some(kernel))
                    .map(|_| ())
            },
        )?;
        Ok(PartialSumTreeTimes {
            depth_columns,
            slice_fit,
            rectify,
            sweep,
            unwarp,
            fallback,
        })
    }

    fn encode_selected(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::TextureView,
        shadow_map: &wgpu::TextureView,
        only: Option<Kernel>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        if self.frame.is_none() {
            return Err(RuntimeError::NotPrepared { kernel: SWEEP });
        }
        check_view(SWEEP, &DEPTH_NAMES, depth, self.res.screen)?;
        check_view(
            RECTIFY,
            &SHADOW_NAMES,
            shadow_map,
            [self.shadow_map_size; 2],
        )?;
        let mut engine = vec![("depth", depth), ("shadow_map", shadow_map)];
        self.cookie.bind(self.variant.cookie, SWEEP, &mut engine)?;
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
    pub fn pass_times(&self, ctx: &Context) -> Result<Option<PartialSumTreeTimes>, RuntimeError> {
        let Some(timer) = self.exec.timer() else {
            return Ok(None);
        };
        let t = timer.read_all(ctx, SWEEP)?;
        let at = |i: usize| t.get(i).copied().unwrap_or_default();
        Ok(Some(PartialSumTreeTimes {
            depth_columns: at(0),
            slice_fit: at(1),
            rectify: at(2),
            sweep: at(3),
            unwarp: at(4),
            fallback: at(5),
        }))
    }

    /// The variant the pipelines were built for.
    pub fn variant(&self) -> &PartialSumTreeVariant {
        &self.variant
    }

    /// The frame set-up of the last [`Self::prepare`].
    pub fn frame(&self) -> Option<&PartialSumTreeFrame> {
        self.frame.as_ref()
    }

    /// The rectified map (r32float, `Wr x Hr`).
    pub fn rectified_texture(&self) -> &wgpu::Texture {
        &self.rectified
    }

    /// The epipolar samples (rgba32float, `(slice_samples + 1) x (slices + 1)`).
    pub fn samples_texture(&self) -> &wgpu::Texture {
        &self.samples
    }

    /// The output texture (rgba16float, screen-sized).
    pub fn output_texture(&self) -> &wgpu::Texture {
        &self.output
    }
}

/// Everything [`run_partial_sum_tree_once`] reads back.
#[derive(Clone, Debug)]
pub struct PartialSumTreeReadback {
    /// The frame set-up that was uploaded.
    pub frame: PartialSumTreeFrame,
    /// The slice table after `slice_fit` (read back).
    pub slices: Vec<SliceParams>,
    /// The rectified map, row-major.
    pub rectified: Vec<f32>,
    /// The epipolar samples `pst_sweep` wrote, row-major over `(slice_samples + 1) x
    /// (slices + 1)`.
    pub samples: Vec<[f32; 4]>,
    /// In-scattered radiance per pixel (rgba16float converted to f32), row-major.
    pub output: Vec<[f32; 4]>,
    /// GPU time per pass, when the device has timestamps.
    pub gpu_times: Option<PartialSumTreeTimes>,
    /// Wall time from submission until every result was mapped.
    pub wall_time: Duration,
}

/// Test helper: creates a [`PartialSumTree`], uploads `depth` (screen-sized) and
/// `shadow_map` (`input.shadow_map.size` squared) as r32float textures and, for a `cookie`
/// variant, `cookie` (its size and RGBA texels), runs one frame and reads back.
///
/// # Errors
///
/// Whatever [`PartialSumTree::new`], [`PartialSumTree::prepare`] or
/// [`PartialSumTree::encode`] fail with; [`RuntimeError::DataLength`] when a buffer does not
/// match its size; GPU errors.
pub fn run_partial_sum_tree_once(
    ctx: &Context,
    variant: &PartialSumTreeVariant,
    res: Resolutions,
    input: &FrameInput,
    depth: &[f32],
    shadow_map: &[f32],
    cookie: Option<([u32; 2], &[[f32; 4]])>,
) -> Result<PartialSumTreeReadback, RuntimeError> {
    let sm_size = input.shadow_map.size;
    let mut pass = PartialSumTree::new(ctx, variant, res, sm_size)?;
    if let Some((size, texels)) = cookie {
        let texture = crate::textures::upload_cookie(ctx, SWEEP, size, texels)?;
        pass.set_cookie(&texture.create_view(&wgpu::TextureViewDescriptor::default()))?;
    }
    let views = upload_inputs(
        ctx,
        &[
            (SWEEP, "depth buffer", res.screen, depth),
            (RECTIFY, "shadow map", [sm_size; 2], shadow_map),
        ],
    )?;
    pass.prepare(ctx, input)?;
    let device = ctx.device();
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("run_partial_sum_tree_once"),
    });
    pass.encode(ctx, &mut encoder, &views[0].1, &views[1].1)?;
    let scope = ErrorScopes::push(device);
    let rectified = Readback::encode(device, &mut encoder, pass.rectified_texture(), 4, RECTIFY)?;
    let samples = Readback::encode(device, &mut encoder, pass.samples_texture(), 16, SWEEP)?;
    let output = Readback::encode(device, &mut encoder, pass.output_texture(), 8, UNWARP)?;
    let slices = encode_buffer_readback(device, &mut encoder, &pass.slices);
    let start = Instant::now();
    ctx.queue().submit([encoder.finish()]);
    scope.pop(SWEEP, "dispatch")?;
    let f32s = |bytes: Vec<u8>| -> Vec<f32> {
        bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    };
    let slices = read_slices(ctx, SLICE_FIT, &slices)?;
    let rectified = f32s(rectified.read(ctx, RECTIFY)?);
    let samples = f32s(samples.read(ctx, SWEEP)?)
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    let output = output
        .read(ctx, UNWARP)?
        .chunks_exact(8)
        .map(|t| decode_rgba(t, Storage::Rgba16float))
        .collect();
    let wall_time = start.elapsed();
    let gpu_times = pass.pass_times(ctx)?;
    let frame = pass
        .frame
        .ok_or(RuntimeError::NotPrepared { kernel: SWEEP })?;
    Ok(PartialSumTreeReadback {
        frame,
        slices,
        rectified,
        samples,
        output,
        gpu_times,
        wall_time,
    })
}

impl crate::family::FamilyRuntime for PartialSumTree {
    type Variant = PartialSumTreeVariant;

    fn create(
        ctx: &Context,
        variant: &PartialSumTreeVariant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        Self::new(ctx, variant, res, shadow_map_size)
    }

    fn knobs(&self) -> PartialSumTreeVariant {
        self.variant
    }

    fn prepare_frame(
        &mut self,
        ctx: &Context,
        input: &FrameInput,
    ) -> Result<Option<scatter_shaderlib::prefiltered::FrameReport>, RuntimeError> {
        self.prepare(ctx, input)?;
        Ok(self.frame.as_ref().map(|f| f.frame.report.clone()))
    }

    fn encode_frame(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &crate::prefiltered::Inputs<'_>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        let shadow_map = crate::family::required_shadow_map(inputs, RECTIFY)?;
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

    fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
        PartialSumTree::set_cookie(self, cookie)
    }

    fn pass_wall_times(
        &self,
        ctx: &Context,
        inputs: &crate::prefiltered::Inputs<'_>,
        frames: u32,
    ) -> Result<Vec<(Kernel, Duration)>, RuntimeError> {
        let shadow_map = crate::family::required_shadow_map(inputs, RECTIFY)?;
        let t = self.measure_pass_wall_times(ctx, inputs.depth, shadow_map, frames)?;
        Ok(vec![
            (DEPTH_COLUMNS, t.depth_columns),
            (SLICE_FIT, t.slice_fit),
            (RECTIFY, t.rectify),
            (SWEEP, t.sweep),
            (UNWARP, t.unwarp),
            (FALLBACK, t.fallback),
        ])
    }
}
