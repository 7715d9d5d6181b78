//! The `minmax` family (Chen et al. 2011) on wgpu: [`Minmax`] owns the `depth_columns`,
//! `slice_fit` and `rectify` (the prefiltered family's kernels, for [`MinmaxVariant::prefiltered`]), `minmax_build` and
//! `minmax_traverse` pipelines, the rectified map, the min-max tree and output textures and the
//! uniform and slice buffers; an engine calls [`Minmax::prepare`] and [`Minmax::encode`]
//! once per frame with its depth buffer and standard shadow map. [`run_minmax_once`] is the
//! upload-run-readback convenience the conformance tests use.
//!
//! | pass | bindings | dispatch |
//! |---|---|---|
//! | `depth_columns` | 0 uniform `Frame`, 1 depth r32float, 2 column_depth (storage, one f32 per screen column) | `ceil(W/64) x 1 x 1` |
//! | `slice_fit` | 0 uniform `Frame`, 1 slices (read_write), 2 column_depth | `1 x 1 x 1` (one workgroup of 256) |
//! | `rectify` | 0 uniform `Frame`, 1 slices, 2 shadow map r32float, 3 rectified r32float (storage, write) | `ceil(Wr/8) x ceil(Hr/8) x 1` |
//! | `minmax_build` | 0 uniform `Frame`, 1 rectified r32float, 2 tree rg32float (storage, write) | `1 x Hr x 1` (128 invocations per row) |
//! | `minmax_traverse` | 0 uniform `Frame`, 1 slices, 2 depth r32float, 3 shadow map r32float, 4 tree rg32float, 5 output rgba16float (storage, write) | `ceil(W/8) x ceil(H/8) x 1` |

use std::time::{Duration, Instant};

use scatter_shaderlib::Kernel;
use scatter_shaderlib::family::KernelFamily;
use scatter_shaderlib::minmax::{MinmaxVariant, prepare_minmax, tree_width};
use scatter_shaderlib::prefiltered::{PrefilteredFrame, Resolutions, SliceParams, Storage};

use crate::error::ErrorScopes;
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
const BUILD: Kernel = Kernel::MinmaxBuild;
const MARCH: Kernel = Kernel::MinmaxTraverse;
const UNWARP: Kernel = Kernel::MinmaxTraverseUnwarp;
const FALLBACK: Kernel = Kernel::MinmaxTraverseFallback;

/// Format of the min-max tree (r = min, g = max).
pub const TREE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// GPU time of each pass of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MinmaxTimes {
    /// The `depth_columns` pass.
    pub depth_columns: Duration,
    /// The `slice_fit` pass.
    pub slice_fit: Duration,
    /// The `rectify` pass.
    pub rectify: Duration,
    /// The `minmax_build` pass.
    pub build: Duration,
    /// The `minmax_traverse` pass.
    pub march: Duration,
    /// The `minmax_traverse_unwarp` pass (zero per pixel).
    pub unwarp: Duration,
    /// The `minmax_traverse_fallback` pass (zero per pixel).
    pub fallback: Duration,
}

impl MinmaxTimes {
    /// Sum of the passes.
    pub fn total(&self) -> Duration {
        self.depth_columns
            + self.slice_fit
            + self.rectify
            + self.build
            + self.march
            + self.unwarp
            + self.fallback
    }
}

/// The minmax family for one [`MinmaxVariant`], sized for one screen, one rectified map and
/// one shadow-map size.
#[derive(Debug)]
pub struct Minmax {
    variant: MinmaxVariant,
    res: Resolutions,
    shadow_map_size: u32,
    /// The plan of the variant, built.
    exec: Executor,
    uniforms: wgpu::Buffer,
    slices: wgpu::Buffer,
    rectified: wgpu::Texture,
    tree: wgpu::Texture,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    frame: Option<PrefilteredFrame>,
    /// The spot's cookie ([`Self::set_cookie`]), for a variant with `cookie`.
    cookie: crate::cookie::CookieSlot,
}

impl Minmax {
    /// Validates the sizes against the device and creates the pipelines, textures and
    /// buffers. `res.rectified` is the rectified map (`Wr` light rays per slice by `Hr`
    /// slices); the tree texture is `tree_width(Wr) x Hr` (at most `2 Wr + log2 Wr + 1`
    /// wide).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::EmptyInput`] for a zero size; [`RuntimeError::LimitExceeded`] naming
    /// the device limit (e.g. the tree wider than `max_texture_dimension_2d`);
    /// [`RuntimeError::Shader`] or [`RuntimeError::Wgpu`] when a kernel or resource fails.
    pub fn new(
        ctx: &Context,
        variant: &MinmaxVariant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        let [w, h] = res.screen;
        let [wr, hr] = res.rectified;
        check_nonempty(&[
            (MARCH, "screen", res.screen),
            (RECTIFY, "rectified", res.rectified),
            (RECTIFY, "shadow map", [shadow_map_size; 2]),
        ])?;
        let tw = tree_width(wr);
        let device = ctx.device();
        let limits = device.limits();
        check_texture_sides(
            &limits,
            &[
                (MARCH, "screen width", w),
                (MARCH, "screen height", h),
                (RECTIFY, "rectified width", wr),
                (RECTIFY, "rectified height", hr),
                (RECTIFY, "shadow map size", shadow_map_size),
                (BUILD, "tree width (all levels of a row)", tw),
            ],
        )?;
        crate::prefiltered::check_frame_buffers(&limits, hr)?;
        let built = variant
            .kernel_params()
            .iter()
            .map(scatter_shaderlib::build)
            .collect::<Result<Vec<_>, _>>()?;
        let exec = Executor::new(
            ctx,
            scatter_shaderlib::minmax::plan::plan(variant),
            built,
            &[
                ("screen.width", w.into()),
                ("screen.height", h.into()),
                ("shadow.size", shadow_map_size.into()),
                ("rectified.width", wr.into()),
                ("rectified.height", hr.into()),
                ("tree.width", tw.into()),
            ],
        )?;
        let (output, output_view) = exec.texture("output")?;
        Ok(Minmax {
            variant: *variant,
            res,
            shadow_map_size,
            uniforms: exec.buffer("frame")?.clone(),
            slices: exec.buffer("slices")?.clone(),
            rectified: exec.texture("rectified")?.0.clone(),
            tree: exec.texture("tree")?.0.clone(),
            output: output.clone(),
            output_view: output_view.clone(),
            exec,
            frame: None,
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
            .set(self.variant.cookie, self.variant.id(), MARCH, cookie)
    }

    /// Sets up one frame ([`prepare_minmax`]) and uploads its uniforms and slice table.
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
        let prepared = prepare_minmax(
            &self.variant,
            &self.res,
            &input.camera,
            &input.light,
            &input.medium,
            &input.shadow_map,
            &input.settings,
        )?;
        let rows = self.res.rectified[1] as usize;
        if prepared.slices.len() != rows {
            return Err(RuntimeError::DataLength {
                kernel: RECTIFY,
                size: format!("slice table of {rows} rows"),
                expected: rows as u64,
                actual: prepared.slices.len() as u64,
            });
        }
        let scope = ErrorScopes::push(ctx.device());
        let queue = ctx.queue();
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&prepared.uniforms));
        queue.write_buffer(&self.slices, 0, bytemuck::cast_slice(&prepared.slices));
        scope.pop(MARCH, "uploading frame parameters")?;
        self.frame = Some(prepared);
        Ok(())
    }

    /// Records the five passes (with GPU timestamps when the device has them) and returns
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
    ) -> Result<MinmaxTimes, RuntimeError> {
        // Per pixel there are no unwarp and fallback passes: their slots
        // record nothing.
        let [
            depth_columns,
            slice_fit,
            rectify,
            build,
            march,
            unwarp,
            fallback,
        ] = median_pass_wall_times(
            ctx,
            [
                DEPTH_COLUMNS,
                SLICE_FIT,
                RECTIFY,
                BUILD,
                MARCH,
                UNWARP,
                FALLBACK,
            ],
            frames,
            |encoder, kernel| {
                self.encode_selected(ctx, encoder, depth, shadow_map, Some(kernel))
                    .map(|_| ())
            },
        )?;
        Ok(MinmaxTimes {
            depth_columns,
            slice_fit,
            rectify,
            build,
            march,
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
        if self.frame.is_none() {
            return Err(RuntimeError::NotPrepared { kernel: MARCH });
        }
        check_view(MARCH, &DEPTH_NAMES, depth, self.res.screen)?;
        check_view(
            RECTIFY,
            &SHADOW_NAMES,
            shadow_map,
            [self.shadow_map_size; 2],
        )?;
        let mut engine = vec![("depth", depth), ("shadow_map", shadow_map)];
        self.cookie.bind(self.variant.cookie, MARCH, &mut engine)?;
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
    pub fn pass_times(&self, ctx: &Context) -> Result<Option<MinmaxTimes>, RuntimeError> {
        let Some(timer) = self.exec.timer() else {
            return Ok(None);
        };
        let t = timer.read_all(ctx, MARCH)?;
        let at = |i: usize| t.get(i).copied().unwrap_or_default();
        Ok(Some(MinmaxTimes {
            depth_columns: at(0),
            slice_fit: at(1),
            rectify: at(2),
            build: at(3),
            march: at(4),
            unwarp: at(5),
            fallback: at(6),
        }))
    }

    /// The variant the pipelines were built for.
    pub fn variant(&self) -> &MinmaxVariant {
        &self.variant
    }

    /// The frame set-up of the last [`Self::prepare`].
    pub fn frame(&self) -> Option<&PrefilteredFrame> {
        self.frame.as_ref()
    }

    /// The rectified map (r32float, `Wr x Hr`).
    pub fn rectified_texture(&self) -> &wgpu::Texture {
        &self.rectified
    }

    /// The min-max trees (rg32float, `tree_width(Wr) x Hr`).
    pub fn tree_texture(&self) -> &wgpu::Texture {
        &self.tree
    }

    /// The output texture (rgba16float, screen-sized).
    pub fn output_texture(&self) -> &wgpu::Texture {
        &self.output
    }
}

/// Everything [`run_minmax_once`] reads back.
#[derive(Clone, Debug)]
pub struct MinmaxReadback {
    /// The frame set-up that was uploaded.
    pub frame: PrefilteredFrame,
    /// The slice table after `slice_fit` (read back).
    pub slices: Vec<SliceParams>,
    /// The rectified map, row-major.
    pub rectified: Vec<f32>,
    /// The min-max trees (min, max), row-major over `tree_width(Wr) x Hr`.
    pub tree: Vec<[f32; 2]>,
    /// In-scattered radiance per pixel (rgba16float converted to f32), row-major.
    pub output: Vec<[f32; 4]>,
    /// GPU time per pass, when the device has timestamps.
    pub gpu_times: Option<MinmaxTimes>,
    /// Wall time from submission until every result was mapped.
    pub wall_time: Duration,
}

/// Test helper: creates a [`Minmax`], uploads `depth` (screen-sized) and `shadow_map`
/// (`input.shadow_map.size` squared) as r32float textures and, for a `cookie` variant,
/// `cookie` (its size and RGBA texels), runs one frame and reads back.
///
/// # Errors
///
/// Whatever [`Minmax::new`], [`Minmax::prepare`] or [`Minmax::encode`] fail with;
/// [`RuntimeError::DataLength`] when a buffer does not match its size; GPU errors.
pub fn run_minmax_once(
    ctx: &Context,
    variant: &MinmaxVariant,
    res: Resolutions,
    input: &FrameInput,
    depth: &[f32],
    shadow_map: &[f32],
    cookie: Option<([u32; 2], &[[f32; 4]])>,
) -> Result<MinmaxReadback, RuntimeError> {
    let sm_size = input.shadow_map.size;
    let mut pass = Minmax::new(ctx, variant, res, sm_size)?;
    if let Some((size, texels)) = cookie {
        let texture = crate::textures::upload_cookie(ctx, MARCH, size, texels)?;
        pass.set_cookie(&texture.create_view(&wgpu::TextureViewDescriptor::default()))?;
    }
    let views = upload_inputs(
        ctx,
        &[
            (MARCH, "depth buffer", res.screen, depth),
            (RECTIFY, "shadow map", [sm_size; 2], shadow_map),
        ],
    )?;
    pass.prepare(ctx, input)?;
    let device = ctx.device();
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("minmax run_prefiltered_once"),
    });
    pass.encode(ctx, &mut encoder, &views[0].1, &views[1].1)?;
    let scope = ErrorScopes::push(device);
    let rectified = Readback::encode(device, &mut encoder, pass.rectified_texture(), 4, RECTIFY)?;
    let tree = Readback::encode(device, &mut encoder, pass.tree_texture(), 8, BUILD)?;
    let output = Readback::encode(device, &mut encoder, pass.output_texture(), 8, MARCH)?;
    let slices = encode_buffer_readback(device, &mut encoder, &pass.slices);
    let start = Instant::now();
    ctx.queue().submit([encoder.finish()]);
    scope.pop(MARCH, "dispatch")?;
    let f32s = |bytes: Vec<u8>| -> Vec<f32> {
        bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    };
    let slices = read_slices(ctx, SLICE_FIT, &slices)?;
    let rectified = f32s(rectified.read(ctx, RECTIFY)?);
    let tree = f32s(tree.read(ctx, BUILD)?)
        .chunks_exact(2)
        .map(|c| [c[0], c[1]])
        .collect();
    let output = output
        .read(ctx, MARCH)?
        .chunks_exact(8)
        .map(|t| decode_rgba(t, Storage::Rgba16float))
        .collect();
    let wall_time = start.elapsed();
    let gpu_times = pass.pass_times(ctx)?;
    let frame = pass
        .frame
        .ok_or(RuntimeError::NotPrepared { kernel: MARCH })?;
    Ok(MinmaxReadback {
        frame,
        slices,
        rectified,
        tree,
        output,
        gpu_times,
        wall_time,
    })
}

impl crate::family::FamilyRuntime for Minmax {
    type Variant = MinmaxVariant;

    fn create(
        ctx: &Context,
        variant: &MinmaxVariant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        Self::new(ctx, variant, res, shadow_map_size)
    }

    fn knobs(&self) -> MinmaxVariant {
        self.variant
    }

    fn prepare_frame(
        &mut self,
        ctx: &Context,
        input: &FrameInput,
    ) -> Result<Option<scatter_shaderlib::prefiltered::FrameReport>, RuntimeError> {
        self.prepare(ctx, input)?;
        Ok(self.frame.as_ref().map(|f| f.report.clone()))
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

    fn pass_wall_times(
        &self,
        ctx: &Context,
        inputs: &crate::prefiltered::Inputs<'_>,
        frames: u32,
    ) -> Result<Vec<(Kernel, Duration)>, RuntimeError> {
        let shadow_map = crate::family::required_shadow_map(inputs, RECTIFY)?;
        let t = self.measure_pass_wall_times(ctx, inputs.depth, shadow_map, frames)?;
        let mut passes = vec![
            (DEPTH_COLUMNS, t.depth_columns),
            (SLICE_FIT, t.slice_fit),
            (RECTIFY, t.rectify),
            (BUILD, t.build),
            (MARCH, t.march),
        ];
        if self.sampled() {
            passes.push((UNWARP, t.unwarp));
            passes.push((FALLBACK, t.fallback));
        }
        Ok(passes)
    }

    fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
        Minmax::set_cookie(self, cookie)
    }
}
