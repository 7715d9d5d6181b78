//! The `minmax` family (Chen et al. 2011) on wgpu: [`Minmax`] owns the `rectify` (the
//! prefiltered family's kernel, for [`MinmaxVariant::prefiltered`]), `minmax_build` and
//! `minmax_march` pipelines, the rectified map, the min-max tree and output textures and the
//! uniform and slice buffers; an engine calls [`Minmax::prepare`] and [`Minmax::encode`]
//! once per frame with its depth buffer and standard shadow map. [`run_minmax_once`] is the
//! upload-run-readback convenience the conformance tests use.
//!
//! | pass | bindings | dispatch |
//! |---|---|---|
//! | `rectify` | 0 uniform `Frame`, 1 slices, 2 shadow map r32float, 3 rectified r32float (storage, write) | `ceil(Wr/8) x ceil(Hr/8) x 1` |
//! | `minmax_build` | 0 uniform `Frame`, 1 rectified r32float, 2 tree rg32float (storage, write) | `ceil(tree_width(Wr)/64) x Hr x 1` |
//! | `minmax_march` | 0 uniform `Frame`, 1 slices, 2 depth r32float, 3 shadow map r32float, 4 tree rg32float, 5 output rgba16float (storage, write) | `ceil(W/8) x ceil(H/8) x 1` |

use std::time::{Duration, Instant};

use scatter_shaderlib::minmax::{MinmaxVariant, prepare_minmax, tree_width};
use scatter_shaderlib::prefiltered::{
    FrameUniforms, PrefilteredFrame, Resolutions, SliceParams, Storage,
};
use scatter_shaderlib::{Kernel, KernelParams};

use crate::error::{ErrorScopes, check_limit};
use crate::prefiltered::{
    DEPTH_FORMAT, DEPTH_NAMES, FrameInput, OUTPUT_FORMAT, Pipeline, Readback, SHADOW_NAMES,
    buffer_entry, check_dispatch, check_view, create_pipeline, decode_rgba, groups, view_entry,
};
use crate::textures::upload_r32float;
use crate::timer::median_pass_wall_times;
use crate::{Context, GpuTimer, RuntimeError};

const RECTIFY: Kernel = Kernel::Rectify;
const BUILD: Kernel = Kernel::MinmaxBuild;
const MARCH: Kernel = Kernel::MinmaxMarch;

/// Format of the min-max tree (r = min, g = max).
pub const TREE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// GPU time of each pass of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MinmaxTimes {
    /// The `rectify` pass.
    pub rectify: Duration,
    /// The `minmax_build` pass.
    pub build: Duration,
    /// The `minmax_march` pass.
    pub march: Duration,
}

impl MinmaxTimes {
    /// Sum of the passes.
    pub fn total(&self) -> Duration {
        self.rectify + self.build + self.march
    }
}

/// The minmax family for one [`MinmaxVariant`], sized for one screen, one rectified map and
/// one shadow-map size.
#[derive(Debug)]
pub struct Minmax {
    variant: MinmaxVariant,
    res: Resolutions,
    shadow_map_size: u32,
    rectify: Pipeline,
    build: Pipeline,
    march: Pipeline,
    uniforms: wgpu::Buffer,
    slices: wgpu::Buffer,
    rectified: wgpu::Texture,
    rectified_view: wgpu::TextureView,
    tree: wgpu::Texture,
    tree_view: wgpu::TextureView,
    build_group: wgpu::BindGroup,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    timer: Option<GpuTimer>,
    frame: Option<PrefilteredFrame>,
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
        for (kernel, what, size, empty) in [
            (MARCH, "screen", format!("{w}x{h}"), w == 0 || h == 0),
            (
                RECTIFY,
                "rectified",
                format!("{wr}x{hr}"),
                wr == 0 || hr == 0,
            ),
            (
                RECTIFY,
                "shadow map",
                format!("{shadow_map_size}x{shadow_map_size}"),
                shadow_map_size == 0,
            ),
        ] {
            if empty {
                return Err(RuntimeError::EmptyInput {
                    kernel,
                    size: format!("{what} {size}"),
                });
            }
        }
        let tw = tree_width(wr);
        let device = ctx.device();
        let limits = device.limits();
        let max_2d = u64::from(limits.max_texture_dimension_2d);
        for (kernel, what, value) in [
            (MARCH, "screen width", w),
            (MARCH, "screen height", h),
            (RECTIFY, "rectified width", wr),
            (RECTIFY, "rectified height", hr),
            (RECTIFY, "shadow map size", shadow_map_size),
            (BUILD, "tree width (all levels of a row)", tw),
        ] {
            check_limit(
                kernel,
                what,
                value.into(),
                "max_texture_dimension_2d",
                max_2d,
            )?;
        }
        let slice_bytes = crate::prefiltered::check_frame_buffers(&limits, hr)?;
        let built = KernelParams::minmax(*variant)
            .map(|p| scatter_shaderlib::build(&p))
            .into_iter()
            .collect::<Result<Vec<_>, _>>()?;
        for (b, invocations) in built.iter().zip([[wr, hr, 1], [tw, hr, 1], [w, h, 1]]) {
            check_dispatch(&limits, b, invocations)?;
        }
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty,
            count: None,
        };
        let uniform = wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<FrameUniforms>() as u64),
        };
        let slices_ty = wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<SliceParams>() as u64),
        };
        let texture = wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        };
        let storage = |format| wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        };
        let [b_rectify, b_build, b_march]: [_; 3] = built
            .try_into()
            .map_err(|_| RuntimeError::NotPrepared { kernel: BUILD })?;
        let rectify = create_pipeline(
            device,
            b_rectify,
            &[
                entry(0, uniform),
                entry(1, slices_ty),
                entry(2, texture),
                entry(3, storage(DEPTH_FORMAT)),
            ],
        )?;
        let build = create_pipeline(
            device,
            b_build,
            &[
                entry(0, uniform),
                entry(1, texture),
                entry(2, storage(TREE_FORMAT)),
            ],
        )?;
        let march = create_pipeline(
            device,
            b_march,
            &[
                entry(0, uniform),
                entry(1, slices_ty),
                entry(2, texture),
                entry(3, texture),
                entry(4, texture),
                entry(5, storage(OUTPUT_FORMAT)),
            ],
        )?;
        let scope = ErrorScopes::push(device);
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("minmax frame uniforms"),
            size: size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let slices = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("minmax slice table"),
            size: slice_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let make = |label, [width, height]: [u32; 2], format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let rectified = make("minmax rectified map", res.rectified, DEPTH_FORMAT);
        let tree = make("minmax trees", [tw, hr], TREE_FORMAT);
        let output = make("minmax output", res.screen, OUTPUT_FORMAT);
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let (rectified_view, tree_view, output_view) =
            (view(&rectified), view(&tree), view(&output));
        let build_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("minmax_build"),
            layout: &build.layout,
            entries: &[
                buffer_entry(0, &uniforms),
                view_entry(1, &rectified_view),
                view_entry(2, &tree_view),
            ],
        });
        scope.pop(BUILD, "creating textures and buffers")?;
        Ok(Minmax {
            variant: *variant,
            res,
            shadow_map_size,
            rectify,
            build,
            march,
            uniforms,
            slices,
            rectified,
            rectified_view,
            tree,
            tree_view,
            build_group,
            output,
            output_view,
            timer: GpuTimer::with_passes(ctx, 3),
            frame: None,
        })
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

    /// Records the three passes (with GPU timestamps when the device has them) and returns
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
        let [rectify, build, march] =
            median_pass_wall_times(ctx, [RECTIFY, BUILD, MARCH], frames, |encoder, kernel| {
                self.encode_selected(ctx, encoder, depth, shadow_map, Some(kernel))
                    .map(|_| ())
            })?;
        Ok(MinmaxTimes {
            rectify,
            build,
            march,
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
            return Err(RuntimeError::NotPrepared { kernel: MARCH });
        }
        check_view(MARCH, &DEPTH_NAMES, depth, self.res.screen)?;
        check_view(
            RECTIFY,
            &SHADOW_NAMES,
            shadow_map,
            [self.shadow_map_size; 2],
        )?;
        let device = ctx.device();
        let scope = ErrorScopes::push(device);
        let rectify_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("minmax rectify"),
            layout: &self.rectify.layout,
            entries: &[
                buffer_entry(0, &self.uniforms),
                buffer_entry(1, &self.slices),
                view_entry(2, shadow_map),
                view_entry(3, &self.rectified_view),
            ],
        });
        let march_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("minmax_march"),
            layout: &self.march.layout,
            entries: &[
                buffer_entry(0, &self.uniforms),
                buffer_entry(1, &self.slices),
                view_entry(2, depth),
                view_entry(3, shadow_map),
                view_entry(4, &self.tree_view),
                view_entry(5, &self.output_view),
            ],
        });
        scope.pop(MARCH, "creating the bind groups")?;
        let [w, h] = self.res.screen;
        let [wr, hr] = self.res.rectified;
        let passes = [
            (&self.rectify, &rectify_group, [wr, hr, 1]),
            (&self.build, &self.build_group, [tree_width(wr), hr, 1]),
            (&self.march, &march_group, [w, h, 1]),
        ];
        for (index, (pipeline, group, invocations)) in (0u32..).zip(passes) {
            if only.is_some_and(|k| k != pipeline.kernel) {
                continue;
            }
            let timestamps = if only.is_none() {
                self.timer.as_ref().and_then(|t| t.pass_writes(index))
            } else {
                None
            };
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(pipeline.kernel.name()),
                timestamp_writes: timestamps,
            });
            pass.set_pipeline(&pipeline.pipeline);
            pass.set_bind_group(0, group, &[]);
            let [x, y, z] = groups(invocations, pipeline.workgroup_size);
            pass.dispatch_workgroups(x, y, z);
        }
        if let Some(timer) = self.timer.as_ref().filter(|_| only.is_none()) {
            timer.resolve(encoder);
        }
        Ok(&self.output_view)
    }

    /// GPU time of each pass of the last submitted [`Self::encode`], or `None` without
    /// timestamps. Blocks until the GPU is done.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
    pub fn pass_times(&self, ctx: &Context) -> Result<Option<MinmaxTimes>, RuntimeError> {
        let Some(timer) = &self.timer else {
            return Ok(None);
        };
        let t = timer.read_all(ctx, MARCH)?;
        let at = |i: usize| t.get(i).copied().unwrap_or_default();
        Ok(Some(MinmaxTimes {
            rectify: at(0),
            build: at(1),
            march: at(2),
        }))
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
/// (`input.shadow_map.size` squared) as r32float textures, runs one frame and reads back.
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
) -> Result<MinmaxReadback, RuntimeError> {
    let sm_size = input.shadow_map.size;
    let mut pass = Minmax::new(ctx, variant, res, sm_size)?;
    for (what, [tw, th], data) in [
        ("depth buffer", res.screen, depth),
        ("shadow map", [sm_size; 2], shadow_map),
    ] {
        let expected = u64::from(tw) * u64::from(th);
        if data.len() as u64 != expected {
            return Err(RuntimeError::DataLength {
                kernel: MARCH,
                size: format!("{what} {tw}x{th}"),
                expected,
                actual: data.len() as u64,
            });
        }
    }
    pass.prepare(ctx, input)?;
    let device = ctx.device();
    let depth_texture =
        upload_r32float(ctx, MARCH, "minmax depth (test upload)", res.screen, depth)?;
    let shadow_texture = upload_r32float(
        ctx,
        MARCH,
        "minmax shadow map (test upload)",
        [sm_size; 2],
        shadow_map,
    )?;
    let depth_view = depth_texture.create_view(&wgpu::TextureViewDescriptor::default());
    let shadow_view = shadow_texture.create_view(&wgpu::TextureViewDescriptor::default());
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("minmax run_once"),
    });
    pass.encode(ctx, &mut encoder, &depth_view, &shadow_view)?;
    let scope = ErrorScopes::push(device);
    let rectified = Readback::encode(device, &mut encoder, pass.rectified_texture(), 4, RECTIFY)?;
    let tree = Readback::encode(device, &mut encoder, pass.tree_texture(), 8, BUILD)?;
    let output = Readback::encode(device, &mut encoder, pass.output_texture(), 8, MARCH)?;
    let start = Instant::now();
    ctx.queue().submit([encoder.finish()]);
    scope.pop(MARCH, "dispatch")?;
    let f32s = |bytes: Vec<u8>| -> Vec<f32> {
        bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    };
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
        rectified,
        tree,
        output,
        gpu_times,
        wall_time,
    })
}
