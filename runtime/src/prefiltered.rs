//! The `prefiltered` family (Klehm et al. 2014) on wgpu: [`Prefiltered`] owns the five
//! pipelines (`depth_columns`, `slice_fit`, `rectify`, `prefilter`, `scatter`) of one [`PrefilteredVariant`],
//! the intermediate textures and the per-frame buffers; an engine calls
//! [`Prefiltered::prepare`] and [`Prefiltered::encode`] once per frame with its depth buffer
//! and standard shadow map. [`run_prefiltered_once`] is the upload-run-readback convenience
//! the conformance tests use.
//!
//! Pass order and bindings (group 0 of every kernel; built from the variant's plan):
//!
//! | pass | bindings | dispatch |
//! |---|---|---|
//! | `depth_columns` | 0 uniform `Frame`, 1 depth r32float, 2 column_depth (storage, one f32 per screen column) | `ceil(W/64) x 1 x 1` |
//! | `slice_fit` | 0 uniform `Frame`, 1 slices (read_write), 2 column_depth | `1 x 1 x 1` (one workgroup of 256) |
//! | `rectify` | 0 uniform `Frame`, 1 slices, 2 shadow map r32float, 3 rectified r32float (storage, write) | `ceil(Wr/8) x ceil(Hr/8) x 1` |
//! | `prefilter` | 0, 1, 2 rectified r32float, 3 filtered bases (storage buffer, read_write, the variant's format's texel bits), 4 bounds (storage buffer of vec2<f32>, read_write) | `ceil(Hr/64) x regions x bases/bases_per_thread` |
//! | `scatter` | 0, 1, 2 depth r32float, 3 shadow map r32float, 4 filtered bases (storage buffer, read), 5 output rgba16float (storage, write), 6 bounds (storage buffer, read) | `ceil(W/8) x ceil(H/8) x 1` |
//!
//! Projective frames skip `depth_columns`, `slice_fit` and `rectify`.

use std::time::{Duration, Instant};

use scatter_shaderlib::Kernel;
use scatter_shaderlib::family::KernelFamily;
use scatter_shaderlib::prefiltered::plan;
use scatter_shaderlib::prefiltered::{
    CameraDesc, FrameReport, FrameSettings, FrameUniforms, LightDesc, MediumDesc, PrefilteredFrame,
    PrefilteredVariant, Rectification, Resolutions, ShadowMapDesc, SliceParams, Storage,
    filtered_column_major, filtered_word_bytes, prepare_frame,
};

use crate::error::{ErrorScopes, check_limit};
use crate::executor::Executor;
use crate::gpu::{
    DEPTH_NAMES, RECTIFIED_NAMES, Readback, SHADOW_NAMES, check_nonempty, check_texture_sides,
    check_view, decode_rgba, encode_buffer_readback, read_slices, upload_inputs,
};
use crate::timer::{median_pass_wall_times, read_buffer};
use crate::{Context, RuntimeError};

const DEPTH_COLUMNS: Kernel = Kernel::DepthColumns;
const SLICE_FIT: Kernel = Kernel::SliceFit;
const RECTIFY: Kernel = Kernel::Rectify;
const PREFILTER: Kernel = Kernel::Prefilter;
const SCATTER: Kernel = Kernel::Scatter;
const SCATTER_UNWARP: Kernel = Kernel::ScatterUnwarp;
const SCATTER_FALLBACK: Kernel = Kernel::ScatterFallback;

pub use crate::gpu::{DEPTH_FORMAT, OUTPUT_FORMAT};

/// Everything [`Prefiltered::prepare`] needs about one frame besides the textures: the engine's
/// camera, light, medium and standard shadow map, and the runtime settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameInput {
    /// The camera.
    pub camera: CameraDesc,
    /// The light (its type must match the variant's).
    pub light: LightDesc,
    /// The homogeneous medium.
    pub medium: MediumDesc,
    /// The standard shadow map's projection and size (must match [`Prefiltered::new`]).
    pub shadow_map: ShadowMapDesc,
    /// Epipole march radius and steps, spot quadrature.
    pub settings: FrameSettings,
}

/// The engine's textures for one frame ([`Prefiltered::encode`]). All are r32float with
/// `TEXTURE_BINDING` usage.
#[derive(Clone, Copy, Debug)]
pub struct Inputs<'a> {
    /// Linear view depth, screen-sized.
    pub depth: &'a wgpu::TextureView,
    /// The standard shadow map (`shadow_map_size` squared): needed by every epipolar frame
    /// (`rectify` resamples it, `scatter` marches it near the epipole).
    pub shadow_map: Option<&'a wgpu::TextureView>,
    /// The rectified depth map the engine rasterised with [`FrameReport::projective`]'s
    /// matrices (`Wr x Hr`): needed by every projective frame.
    pub rectified: Option<&'a wgpu::TextureView>,
    /// An area light's VPL shadow maps: an r32float 2D-array view of one layer per VPL,
    /// each the standard map's size, rendered with the frames `AreaIvsv::vpls` gives:
    /// needed by the `area_ivsv` family, ignored by the others.
    pub vpl_maps: Option<&'a wgpu::TextureView>,
}

/// GPU time of each pass of one frame (from timestamps at the start and end of each pass).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PrefilteredTimes {
    /// The `depth_columns` pass (zero in a projective frame, where it does not run).
    pub depth_columns: Duration,
    /// The `slice_fit` pass (zero in a projective frame, where it does not run).
    pub slice_fit: Duration,
    /// The `rectify` pass (zero in a projective frame, where it does not run).
    pub rectify: Duration,
    /// The `prefilter` pass.
    pub prefilter: Duration,
    /// The `scatter` pass.
    pub scatter: Duration,
    /// The `scatter_unwarp` pass (zero per pixel).
    pub unwarp: Duration,
    /// The `scatter_fallback` pass (zero per pixel).
    pub fallback: Duration,
}

impl PrefilteredTimes {
    /// Sum of the passes.
    pub fn total(&self) -> Duration {
        self.depth_columns
            + self.slice_fit
            + self.rectify
            + self.prefilter
            + self.scatter
            + self.unwarp
            + self.fallback
    }
}

/// The `prefiltered` method for one [`PrefilteredVariant`], sized for one set of [`Resolutions`] and one
/// shadow-map size.
#[derive(Debug)]
pub struct Prefiltered {
    device: wgpu::Device,
    variant: PrefilteredVariant,
    res: Resolutions,
    shadow_map_size: u32,
    /// The plan of the variant, built.
    exec: Executor,
    uniforms: wgpu::Buffer,
    slices: wgpu::Buffer,
    rectified: wgpu::Texture,
    rectified_view: wgpu::TextureView,
    filtered: wgpu::Buffer,
    bounds: wgpu::Buffer,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    frame: Option<PrefilteredFrame>,
    /// The spot's cookie ([`Self::set_cookie`]), for a variant with `cookie`.
    cookie: crate::cookie::CookieSlot,
}

impl Prefiltered {
    /// Validates the variant and the sizes against the device, builds the three kernels and
    /// creates their pipelines and every texture and buffer they need.
    ///
    /// `res.rectified` is the rectified map (`Wr` light rays per slice by `Hr` slices);
    /// `shadow_map_size` the side of the engine's square standard shadow map.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::InvalidVariant`] naming the knob; [`RuntimeError::EmptyInput`] for a
    /// zero size; [`RuntimeError::TooFewColumns`] when `Wr < regions^2`;
    /// [`RuntimeError::LimitExceeded`] naming the device limit;
    /// [`RuntimeError::Shader`] when a kernel does not build; [`RuntimeError::Wgpu`] when wgpu
    /// rejects a pipeline or resource. Nothing is created on the GPU unless every check
    /// passes.
    pub fn new(
        ctx: &Context,
        variant: &PrefilteredVariant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        variant
            .validate()
            .map_err(|source| RuntimeError::InvalidVariant {
                variant: variant.id(),
                source,
            })?;
        let [w, h] = res.screen;
        let [wr, hr] = res.rectified;
        check_nonempty(&[
            (SCATTER, "screen", res.screen),
            (RECTIFY, "rectified", res.rectified),
            (RECTIFY, "shadow map", [shadow_map_size; 2]),
        ])?;
        // As `prepare_frame` requires: the first of the sun's quadratically split regions has
        // `Wr / (stride regions^2)` stored columns, and the stride divides the width.
        let min_width = variant.min_rectified_width();
        if wr < min_width {
            return Err(RuntimeError::TooFewColumns {
                kernel: PREFILTER,
                regions: variant.regions,
                stride: variant.filtered_stride,
                width: wr,
                min: min_width,
            });
        }
        if !wr.is_multiple_of(variant.filtered_stride) {
            return Err(RuntimeError::StrideMismatch {
                kernel: PREFILTER,
                stride: variant.filtered_stride,
                width: wr,
            });
        }
        let wc = variant.filtered_width(wr);
        let device = ctx.device();
        let limits = device.limits();
        check_texture_sides(
            &limits,
            &[
                (SCATTER, "screen width", w),
                (SCATTER, "screen height", h),
                (RECTIFY, "rectified width", wr),
                (RECTIFY, "rectified height", hr),
                (RECTIFY, "shadow map size", shadow_map_size),
            ],
        )?;
        check_frame_buffers(&limits, hr)?;
        // The filtered bases: one storage-format texel per layer and rectified texel.
        let filtered_bytes = u64::from(wc)
            * u64::from(hr)
            * u64::from(variant.filtered_layers())
            * u64::from(filtered_word_bytes(variant.storage));
        for (name, limit) in [
            (
                "max_storage_buffer_binding_size",
                limits.max_storage_buffer_binding_size,
            ),
            ("max_buffer_size", limits.max_buffer_size),
        ] {
            check_limit(
                PREFILTER,
                "filtered-basis bytes (rectified width / filtered_stride x height x layers x \
                 bytes per layer)",
                filtered_bytes,
                name,
                limit,
            )?;
            check_limit(
                PREFILTER,
                "depth-bounds bytes (8 per stored column and rectified row, 16 with resume)",
                u64::from(wc) * u64::from(hr) * if variant.resume { 16 } else { 8 },
                name,
                limit,
            )?;
        }

        // CPU work only: render, compose and validate the three kernels.
        let built = variant
            .kernel_params()
            .iter()
            .map(scatter_shaderlib::build)
            .collect::<Result<Vec<_>, _>>()?;
        let exec = Executor::new(
            ctx,
            plan::plan(variant),
            built,
            &[
                ("screen.width", w.into()),
                ("screen.height", h.into()),
                ("shadow.size", shadow_map_size.into()),
                ("rectified.width", wr.into()),
                ("rectified.height", hr.into()),
            ],
        )?;
        let (rectified, rectified_view) = exec.texture("rectified")?;
        let filtered = exec.buffer("filtered")?.clone();
        let bounds = exec.buffer("bounds")?.clone();
        let (output, output_view) = exec.texture("output")?;
        Ok(Self {
            device: device.clone(),
            variant: *variant,
            res,
            shadow_map_size,
            uniforms: exec.buffer("frame")?.clone(),
            slices: exec.buffer("slices")?.clone(),
            rectified: rectified.clone(),
            rectified_view: rectified_view.clone(),
            filtered,
            bounds,
            output: output.clone(),
            output_view: output_view.clone(),
            exec,
            frame: None,
            cookie: crate::cookie::CookieSlot::default(),
        })
    }

    /// Sets the spot light's cookie a `cookie` variant reads (kept until replaced; any size,
    /// one of [`crate::textures::COOKIE_FORMATS`], projected as `scatter_shaderlib::cookie`
    /// says): `prefilter` folds it into each texel's weight, `scatter` marches with it near
    /// the epipole. [`crate::textures::upload_cookie`] makes one from texels.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::NoCookie`] for a variant without `cookie`;
    /// [`RuntimeError::InputMismatch`] for a view of the wrong format, dimension or usage.
    pub fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
        self.cookie
            .set(self.variant.cookie, self.variant.id(), PREFILTER, cookie)
    }

    /// Sets up one frame ([`prepare_frame`]) and uploads its uniforms and slice table.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::ShadowMapSize`] when `frame.shadow_map.size` differs from the size
    /// given to [`Self::new`]; [`RuntimeError::Frame`] for NaN or degenerate parameters or a
    /// light of the wrong type; [`RuntimeError::Wgpu`] when an upload fails.
    pub fn prepare(
        &mut self,
        ctx: &Context,
        frame: &FrameInput,
    ) -> Result<FrameReport, RuntimeError> {
        if frame.shadow_map.size != self.shadow_map_size {
            return Err(RuntimeError::ShadowMapSize {
                expected: self.shadow_map_size,
                actual: frame.shadow_map.size,
            });
        }
        let prepared = prepare_frame(
            &self.variant,
            &self.res,
            &frame.camera,
            &frame.light,
            &frame.medium,
            &frame.shadow_map,
            &frame.settings,
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
        scope.pop(RECTIFY, "uploading frame parameters")?;
        let report = prepared.report.clone();
        self.frame = Some(prepared);
        Ok(report)
    }

    /// Records the frame's passes (each with GPU timestamps when the device has them; read
    /// them with [`Self::pass_times`] after submitting) and returns the output view:
    /// in-scattered radiance, rgba16float, screen-sized.
    ///
    /// Epipolar frames run `depth_columns`, `slice_fit`, `rectify`, `prefilter` and
    /// `scatter` and need `inputs.shadow_map`; projective frames
    /// ([`FrameReport::rectification`] is `projective`) skip the first three and need
    /// `inputs.rectified`, the map the engine rasterised with the frame's matrices.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::NotPrepared`] before the first [`Self::prepare`];
    /// [`RuntimeError::MissingInput`] when the frame's rectification needs a texture that
    /// is `None`; [`RuntimeError::InputMismatch`] for a view of the wrong format, size or
    /// usage; [`RuntimeError::Wgpu`] when wgpu rejects a bind group.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &Inputs<'_>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        self.encode_selected(encoder, inputs, None)
    }

    /// Records one pass of the frame (`depth_columns`, `slice_fit`, `rectify`, `prefilter`
    /// or `scatter`) without timestamps, for timing passes one submission at a time
    /// ([`Self::measure_pass_wall_times`]). A projective frame records nothing for the first
    /// three. Errors as [`Self::encode`].
    ///
    /// # Errors
    ///
    /// As [`Self::encode`].
    pub fn encode_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &Inputs<'_>,
        kernel: Kernel,
    ) -> Result<(), RuntimeError> {
        self.encode_selected(encoder, inputs, Some(kernel))
            .map(|_| ())
    }

    /// Wall time of each pass submitted on its own and waited for, the median over
    /// `frames` frames after one warm-up frame. On a software rasteriser such as lavapipe,
    /// where the GPU is the CPU, this is the pass's real cost (its GPU timestamps are not:
    /// they are not ordered after the compute work). Includes one submission and one
    /// blocking poll per pass.
    ///
    /// # Errors
    ///
    /// As [`Self::encode`]; [`RuntimeError::Poll`] when waiting fails.
    pub fn measure_pass_wall_times(
        &self,
        ctx: &Context,
        inputs: &Inputs<'_>,
        frames: u32,
    ) -> Result<PrefilteredTimes, RuntimeError> {
        // Per pixel there are no `scatter_unwarp` and `scatter_fallback`
        // passes: their slots record nothing.
        let [
            depth_columns,
            slice_fit,
            rectify,
            prefilter,
            scatter,
            unwarp,
            fallback,
        ] = median_pass_wall_times(
            ctx,
            [
                DEPTH_COLUMNS,
                SLICE_FIT,
                RECTIFY,
                PREFILTER,
                SCATTER,
                SCATTER_UNWARP,
                SCATTER_FALLBACK,
            ],
            frames,
            |encoder, kernel| self.encode_pass(encoder, inputs, kernel),
        )?;
        Ok(PrefilteredTimes {
            depth_columns,
            slice_fit,
            rectify,
            prefilter,
            scatter,
            unwarp: crate::timer::when(self.sampled(), unwarp),
            fallback: crate::timer::when(self.sampled(), fallback),
        })
    }

    fn encode_selected(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &Inputs<'_>,
        only: Option<Kernel>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        let frame = self
            .frame
            .as_ref()
            .ok_or(RuntimeError::NotPrepared { kernel: RECTIFY })?;
        let projective = frame.report.rectification == Rectification::Projective;
        check_view(SCATTER, &DEPTH_NAMES, inputs.depth, self.res.screen)?;
        // A projective frame needs the rasterised rectified map (`prefilter` reads it;
        // `scatter` binds it where the shadow map goes when the engine has none, which it
        // never reads: no epipole on screen); an epipolar frame the standard shadow map.
        if projective {
            let rectified = inputs.rectified.ok_or(RuntimeError::MissingInput {
                kernel: PREFILTER,
                what: "the rasterised rectified map (this frame is projective; render it \
                       with FrameReport::projective)",
            })?;
            check_view(PREFILTER, &RECTIFIED_NAMES, rectified, self.res.rectified)?;
        } else if inputs.shadow_map.is_none() {
            return Err(RuntimeError::MissingInput {
                kernel: RECTIFY,
                what: "the standard shadow map (this frame is epipolar)",
            });
        }
        if let Some(sm) = inputs.shadow_map {
            check_view(RECTIFY, &SHADOW_NAMES, sm, [self.shadow_map_size; 2])?;
        }
        let mut engine = vec![("depth", inputs.depth)];
        engine.extend(inputs.shadow_map.map(|v| ("shadow_map", v)));
        if projective {
            engine.extend(inputs.rectified.map(|v| (plan::RECTIFIED_RASTER, v)));
        }
        self.cookie
            .bind(self.variant.cookie, PREFILTER, &mut engine)?;
        let mut conditions = Vec::new();
        if projective {
            conditions.push(plan::PROJECTIVE_FRAME);
            if inputs.shadow_map.is_none() {
                conditions.push(plan::PROJECTIVE_WITHOUT_SHADOW_MAP);
            }
        }
        self.exec
            .encode(&self.device, encoder, &engine, &conditions, only)?;
        Ok(&self.output_view)
    }

    /// GPU time of each pass of the last submitted [`Self::encode`], or `None` when the
    /// device has no timestamps. Blocks until the GPU is done.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
    pub fn pass_times(&self, ctx: &Context) -> Result<Option<PrefilteredTimes>, RuntimeError> {
        let Some(timer) = self.exec.timer() else {
            return Ok(None);
        };
        let times = timer.read_all(ctx, SCATTER)?;
        let projective = self
            .frame
            .as_ref()
            .is_some_and(|f| f.report.rectification == Rectification::Projective);
        let (times, unwarp, fallback) = match times[..] {
            [ref head @ .., unwarp, fallback] if self.sampled() && times.len() == 7 => {
                (head, unwarp, fallback)
            }
            _ => (&times[..], Duration::ZERO, Duration::ZERO),
        };
        match *times {
            [depth_columns, slice_fit, rectify, prefilter, scatter] => Ok(Some(PrefilteredTimes {
                depth_columns: if projective {
                    Duration::ZERO
                } else {
                    depth_columns
                },
                slice_fit: if projective {
                    Duration::ZERO
                } else {
                    slice_fit
                },
                rectify: if projective { Duration::ZERO } else { rectify },
                prefilter,
                scatter,
                unwarp,
                fallback,
            })),
            _ => Err(RuntimeError::Readback {
                kernel: SCATTER,
                message: format!(
                    "expected {} pass times, got {}",
                    if self.sampled() { 7 } else { 5 },
                    times.len() + 2 * usize::from(self.sampled())
                ),
            }),
        }
    }

    /// Whether the variant samples (lowres or epipolar: it has the unwarp and fallback
    /// passes).
    fn sampled(&self) -> bool {
        self.variant.sampling != scatter_shaderlib::sampling::Sampling::Pixels
    }

    /// The variant the pipelines were built for.
    pub fn variant(&self) -> &PrefilteredVariant {
        &self.variant
    }

    /// The screen and rectified sizes.
    pub fn resolutions(&self) -> Resolutions {
        self.res
    }

    /// Side of the standard shadow map the pass expects.
    pub fn shadow_map_size(&self) -> u32 {
        self.shadow_map_size
    }

    /// The last prepared frame (uniforms, slice table, report).
    pub fn frame(&self) -> Option<&PrefilteredFrame> {
        self.frame.as_ref()
    }

    /// The rectified map: r32float, `Wr x Hr`, normalised rectified depth (written by
    /// `rectify`).
    pub fn rectified_texture(&self) -> &wgpu::Texture {
        &self.rectified
    }

    /// A 2D view of [`Self::rectified_texture`].
    pub fn rectified_view(&self) -> &wgpu::TextureView {
        &self.rectified_view
    }

    /// The filtered bases (written by `prefilter`): a storage buffer of
    /// [`PrefilteredVariant::filtered_layers`] layers of `Wc x Hr` texels (`Wc = Wr /
    /// filtered_stride`), layer `q` of texel
    /// `(x, y)` at element `(q * Wc + x) * Hr + y` (rgba32float: `(q * Hr + y) * Wc + x`,
    /// `scatter_shaderlib::prefiltered::filtered_column_major`), each element the bits of one
    /// texel of the variant's storage format (Fourier bases as `F / 2 + 0.5` in [0, 1]).
    pub fn filtered_buffer(&self) -> &wgpu::Buffer {
        &self.filtered
    }

    /// The region-prefix depth bounds `prefilter` writes beside the filtered bases: a storage
    /// buffer of `Wc x Hr` `vec2<f32>` (min, max), texel `(x, y)` at element `x * Hr + y`.
    pub fn bounds_buffer(&self) -> &wgpu::Buffer {
        &self.bounds
    }

    /// The output: rgba16float, screen-sized, in-scattered radiance (written by `scatter`).
    pub fn output_texture(&self) -> &wgpu::Texture {
        &self.output
    }

    /// A 2D view of [`Self::output_texture`].
    pub fn output_view(&self) -> &wgpu::TextureView {
        &self.output_view
    }
}

/// CPU-side inputs of [`run_prefiltered_once`]: the frame's parameters plus the two textures an engine
/// would render.
#[derive(Clone, Debug, PartialEq)]
pub struct CpuInputs {
    /// Camera, light, medium, shadow-map description and settings.
    pub frame: FrameInput,
    /// Linear view depth, `screen[0] * screen[1]` values, row-major from the top-left pixel.
    pub depth: Vec<f32>,
    /// Standard shadow map, `frame.shadow_map.size` squared values (normalised linear light
    /// depth), row-major from the top-left texel.
    pub shadow_map: Vec<f32>,
    /// The engine's rasterised rectified map (`Wr * Hr` clip depths, row-major), used when
    /// the frame turns out projective (it must then be present).
    pub rectified: Option<Vec<f32>>,
    /// When non-zero, [`run_prefiltered_once`] also measures each pass on its own
    /// ([`Prefiltered::measure_pass_wall_times`]) over this many frames.
    pub pass_wall_frames: u32,
    /// A spot light's cookie for a `cookie` variant: its size and RGBA texels (linear RGB,
    /// row-major from the top-left), uploaded by [`crate::run_family_once`] with
    /// [`crate::textures::upload_cookie`].
    pub cookie: Option<([u32; 2], Vec<[f32; 4]>)>,
    /// An area light's VPL shadow maps for an `area_ivsv` variant: every layer's
    /// `frame.shadow_map.size` squared values, layer-major then row-major, uploaded by
    /// [`crate::run_family_once`] with [`crate::upload_vpl_maps`].
    pub vpl_maps: Option<Vec<f32>>,
}

/// Everything [`run_prefiltered_once`] reads back.
#[derive(Clone, Debug)]
pub struct PrefilteredReadback {
    /// The frame set-up that was uploaded.
    pub frame: PrefilteredFrame,
    /// The slice table after `slice_fit` (read back; the uploaded one in a projective
    /// frame).
    pub slices: Vec<SliceParams>,
    /// In-scattered radiance per pixel (rgba16float converted to f32), row-major.
    pub output: Vec<[f32; 4]>,
    /// Rectified map, `Wr * Hr` values, row-major.
    pub rectified: Vec<f32>,
    /// Filtered bases, `Wc * Hr * filtered_layers` texels indexed `(layer * Hr + y) * Wc + x`
    /// (`Wc = Wr / filtered_stride`, the stored columns),
    /// converted from the storage format to f32 (values in [0, 1]).
    pub filtered: Vec<[f32; 4]>,
    /// Region-prefix depth bounds (min, max) per stored texel (`Wc x Hr`), row-major; with
    /// `resume` a second plane of `(W, 0)` follows (the region's weight sum up to the texel).
    pub bounds: Vec<[f32; 2]>,
    /// GPU time per pass, when the device has timestamps.
    pub gpu_times: Option<PrefilteredTimes>,
    /// Median wall time per pass submitted on its own, when
    /// [`CpuInputs::pass_wall_frames`] is non-zero.
    pub pass_wall_times: Option<PrefilteredTimes>,
    /// Wall time from submission until every result was mapped (includes the copies back).
    pub wall_time: Duration,
}

/// Test helper: creates a [`Prefiltered`] for `variant` and `res`, uploads `inputs.depth` and
/// `inputs.shadow_map` as r32float textures, prepares, encodes and submits one frame, and
/// reads back the output, the rectified map, the filtered bases and the pass times.
///
/// Builds the pipelines on every call: an engine keeps a [`Prefiltered`] instead.
///
/// # Errors
///
/// Whatever [`Prefiltered::new`], [`Prefiltered::prepare`] or [`Prefiltered::encode`] fail with;
/// [`RuntimeError::DataLength`] when a buffer does not match its size;
/// [`RuntimeError::Wgpu`], [`RuntimeError::Poll`] or [`RuntimeError::Readback`] when the
/// GPU work or the readback fails.
pub fn run_prefiltered_once(
    ctx: &Context,
    variant: &PrefilteredVariant,
    res: Resolutions,
    inputs: &CpuInputs,
) -> Result<PrefilteredReadback, RuntimeError> {
    let sm_size = inputs.frame.shadow_map.size;
    let mut pass = Prefiltered::new(ctx, variant, res, sm_size)?;
    let mut cpu = vec![
        (SCATTER, "depth buffer", res.screen, &inputs.depth[..]),
        (RECTIFY, "shadow map", [sm_size; 2], &inputs.shadow_map[..]),
    ];
    if let Some(data) = &inputs.rectified {
        cpu.push((
            PREFILTER,
            "rasterised rectified map",
            res.rectified,
            &data[..],
        ));
    }
    let views = upload_inputs(ctx, &cpu)?;
    let engine_rectified = views.get(2).map(|(_, v)| v);
    if let Some((size, texels)) = &inputs.cookie {
        let texture = crate::textures::upload_cookie(ctx, PREFILTER, *size, texels)?;
        pass.set_cookie(&texture.create_view(&wgpu::TextureViewDescriptor::default()))?;
    }
    pass.prepare(ctx, &inputs.frame)?;
    let device = ctx.device();
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("prefiltered run_prefiltered_once"),
    });
    pass.encode(
        &mut encoder,
        &Inputs {
            depth: &views[0].1,
            shadow_map: Some(&views[1].1),
            rectified: engine_rectified,
            vpl_maps: None,
        },
    )?;
    let scope = ErrorScopes::push(device);
    let rectified_texture = match engine_rectified {
        Some(view) if pass.frame().is_some_and(|f| f.report.projective.is_some()) => view.texture(),
        _ => pass.rectified_texture(),
    };
    let rectified = Readback::encode(device, &mut encoder, rectified_texture, 4, RECTIFY)?;
    let filtered = encode_buffer_readback(device, &mut encoder, pass.filtered_buffer());
    let bounds = encode_buffer_readback(device, &mut encoder, pass.bounds_buffer());
    let output = Readback::encode(device, &mut encoder, pass.output_texture(), 8, SCATTER)?;
    let slices = encode_buffer_readback(device, &mut encoder, &pass.slices);
    let start = Instant::now();
    ctx.queue().submit([encoder.finish()]);
    scope.pop(SCATTER, "dispatch")?;

    let slices = read_slices(ctx, SLICE_FIT, &slices)?;
    let rectified = rectified
        .read(ctx, RECTIFY)?
        .chunks_exact(4)
        .map(|t| f32::from_le_bytes([t[0], t[1], t[2], t[3]]))
        .collect();
    // The stored columns: rectified.width / filtered_stride.
    let stored = [variant.filtered_width(res.rectified[0]), res.rectified[1]];
    let filtered = filtered_layer_major(&read_buffer(ctx, PREFILTER, &filtered)?, variant, stored);
    let bounds = bounds_row_major(
        &read_buffer(ctx, PREFILTER, &bounds)?,
        stored,
        if variant.resume { 2 } else { 1 },
    );
    let output = output
        .read(ctx, SCATTER)?
        .chunks_exact(8)
        .map(|t| decode_rgba(t, Storage::Rgba16float))
        .collect();
    let wall_time = start.elapsed();
    let gpu_times = pass.pass_times(ctx)?;
    let pass_wall_times = if inputs.pass_wall_frames > 0 {
        Some(pass.measure_pass_wall_times(
            ctx,
            &Inputs {
                depth: &views[0].1,
                shadow_map: Some(&views[1].1),
                rectified: engine_rectified,
                vpl_maps: None,
            },
            inputs.pass_wall_frames,
        )?)
    } else {
        None
    };
    let frame = pass
        .frame
        .take()
        .ok_or(RuntimeError::NotPrepared { kernel: RECTIFY })?;
    Ok(PrefilteredReadback {
        frame,
        slices,
        output,
        rectified,
        filtered,
        bounds,
        gpu_times,
        pass_wall_times,
        wall_time,
    })
}

/// The `filtered` buffer's bytes (element `(layer * Wr + x) * Hr + y`, column-major layers, or
/// row-major for rgba32float: `filtered_column_major`) decoded and reordered row-major, `(layer * Hr + y) * Wr + x`, as
/// [`PrefilteredReadback::filtered`] documents.
fn filtered_layer_major(
    bytes: &[u8],
    variant: &PrefilteredVariant,
    [wr, hr]: [u32; 2],
) -> Vec<[f32; 4]> {
    let word = filtered_word_bytes(variant.storage) as usize;
    let (wr, hr) = (wr as usize, hr as usize);
    let layers = variant.filtered_layers() as usize;
    let mut out = vec![[0.0; 4]; wr * hr * layers];
    let column_major = filtered_column_major(variant.storage);
    for (i, bits) in bytes.chunks_exact(word).take(out.len()).enumerate() {
        let texel = decode_rgba(bits, variant.storage);
        if column_major {
            // Element (layer * Wr + x) * Hr + y.
            let (layer_x, y) = (i / hr, i % hr);
            let (layer, x) = (layer_x / wr, layer_x % wr);
            out[(layer * hr + y) * wr + x] = texel;
        } else {
            // Row-major already: element (layer * Hr + y) * Wr + x.
            out[i] = texel;
        }
    }
    out
}

/// The `bounds` buffer's bytes (element `x * Hr + y`, column-major) as `(min, max)` pairs
/// row-major, `y * Wr + x`, as [`PrefilteredReadback::bounds`] documents.
fn bounds_row_major(bytes: &[u8], [wr, hr]: [u32; 2], planes: usize) -> Vec<[f32; 2]> {
    let (wr, hr) = (wr as usize, hr as usize);
    let mut out = vec![[0.0; 2]; planes * wr * hr];
    for (i, t) in bytes.chunks_exact(8).take(out.len()).enumerate() {
        let (plane, j) = (i / (wr * hr), i % (wr * hr));
        let (x, y) = (j / hr, j % hr);
        out[(plane * hr + y) * wr + x] = [
            f32::from_le_bytes([t[0], t[1], t[2], t[3]]),
            f32::from_le_bytes([t[4], t[5], t[6], t[7]]),
        ];
    }
    out
}

/// The slice table (16 bytes per rectified row, `hr` rows) and the uniform block of the
/// families built on the prefiltered frame set-up, against the device's buffer limits; the
/// slice table's size in bytes.
pub(crate) fn check_frame_buffers(limits: &wgpu::Limits, hr: u32) -> Result<u64, RuntimeError> {
    let slice_bytes = u64::from(hr) * size_of::<SliceParams>() as u64;
    for (name, limit) in [
        (
            "max_storage_buffer_binding_size",
            limits.max_storage_buffer_binding_size,
        ),
        ("max_buffer_size", limits.max_buffer_size),
    ] {
        check_limit(
            RECTIFY,
            "slice table bytes (16 per rectified row)",
            slice_bytes,
            name,
            limit,
        )?;
    }
    check_limit(
        RECTIFY,
        "uniform block bytes",
        size_of::<FrameUniforms>() as u64,
        "max_uniform_buffer_binding_size",
        limits.max_uniform_buffer_binding_size,
    )?;
    Ok(slice_bytes)
}

impl crate::family::FamilyRuntime for Prefiltered {
    type Variant = PrefilteredVariant;

    fn create(
        ctx: &Context,
        variant: &PrefilteredVariant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        Self::new(ctx, variant, res, shadow_map_size)
    }

    fn knobs(&self) -> PrefilteredVariant {
        self.variant
    }

    fn prepare_frame(
        &mut self,
        ctx: &Context,
        input: &FrameInput,
    ) -> Result<Option<FrameReport>, RuntimeError> {
        self.prepare(ctx, input).map(Some)
    }

    fn encode_frame(
        &self,
        _ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &Inputs<'_>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        self.encode(encoder, inputs)
    }

    fn output(&self) -> &wgpu::Texture {
        &self.output
    }

    fn total_pass_time(&self, ctx: &Context) -> Result<Option<Duration>, RuntimeError> {
        Ok(self.pass_times(ctx)?.map(|t| t.total()))
    }

    fn fallback_pixels(&self, ctx: &Context) -> Result<Option<u32>, RuntimeError> {
        crate::family::read_fallback_count(ctx, &self.exec, SCATTER_UNWARP)
    }

    fn set_cookie(&mut self, cookie: &wgpu::TextureView) -> Result<(), RuntimeError> {
        Prefiltered::set_cookie(self, cookie)
    }

    fn pass_wall_times(
        &self,
        ctx: &Context,
        inputs: &Inputs<'_>,
        frames: u32,
    ) -> Result<Vec<(Kernel, Duration)>, RuntimeError> {
        let t = self.measure_pass_wall_times(ctx, inputs, frames)?;
        let mut passes = vec![
            (DEPTH_COLUMNS, t.depth_columns),
            (SLICE_FIT, t.slice_fit),
            (RECTIFY, t.rectify),
            (PREFILTER, t.prefilter),
            (SCATTER, t.scatter),
        ];
        if self.sampled() {
            passes.push((SCATTER_UNWARP, t.unwarp));
            passes.push((SCATTER_FALLBACK, t.fallback));
        }
        Ok(passes)
    }
}
