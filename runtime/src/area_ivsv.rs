//! The `area_ivsv` family (Wyman & Dai 2013) on the GPU: `ivsv_rectify`, `ivsv_scan` and
//! `ivsv_gather`, built and dispatched from the family's plan
//! (`scatter_shaderlib::area_ivsv::plan`) by the shared executor.
//!
//! Its inputs beyond every family's: an area light (`LightDesc::Area` in the
//! [`FrameInput`]), whose `N` VPLs each have their own shadow map, which the engine renders
//! into the layers of one `r32float` array texture ([`Inputs::vpl_maps`]) with the frames
//! [`AreaIvsv::vpls`] gives after [`AreaIvsv::prepare_light`] (each derived from the frame's
//! standard shadow map, the light's point limit's). It is one of [`crate::FamilyPasses`];
//! [`run_area_ivsv_once`] is its pass-by-pass test convenience.

use std::time::{Duration, Instant};

use scatter_shaderlib::Kernel;
use scatter_shaderlib::area_ivsv::{
    AreaIvsvFrame, AreaIvsvVariant, VplInput, prepare_area_ivsv, prepare_area_light,
};
use scatter_shaderlib::prefiltered::{CameraDesc, MediumDesc, Resolutions, Storage};

use crate::prefiltered::{FrameInput, Inputs};

use crate::error::{ErrorScopes, check_limit};
use crate::executor::Executor;
use crate::gpu::{
    DEPTH_FORMAT, DEPTH_NAMES, Readback, check_nonempty, check_texture_sides, check_view,
    decode_rgba, encode_buffer_readback, upload_inputs,
};
use crate::timer::median_pass_wall_times;
use crate::{Context, RuntimeError};

const RECTIFY: Kernel = Kernel::IvsvRectify;
const SCAN: Kernel = Kernel::IvsvScan;
const GATHER: Kernel = Kernel::IvsvGather;
const INTERLEAVE_SUM: Kernel = Kernel::IvsvInterleaveSum;
const UNWARP: Kernel = Kernel::IvsvGatherUnwarp;
const FALLBACK: Kernel = Kernel::IvsvGatherFallback;

/// GPU (or wall) time of each pass of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AreaIvsvTimes {
    /// `ivsv_rectify`.
    pub rectify: Duration,
    /// `ivsv_scan`.
    pub scan: Duration,
    /// `ivsv_gather`.
    pub gather: Duration,
    /// `ivsv_interleave_sum` (zero without interleaving).
    pub interleave_sum: Duration,
    /// `ivsv_gather_unwarp` (zero per pixel).
    pub unwarp: Duration,
    /// `ivsv_gather_fallback` (zero per pixel).
    pub fallback: Duration,
}

impl AreaIvsvTimes {
    /// Sum of the passes.
    pub fn total(&self) -> Duration {
        self.rectify + self.scan + self.gather + self.interleave_sum + self.unwarp + self.fallback
    }
}

/// The area_ivsv family for one [`AreaIvsvVariant`], sized for one screen and one VPL
/// shadow-map size.
#[derive(Debug)]
pub struct AreaIvsv {
    variant: AreaIvsvVariant,
    screen: [u32; 2],
    map_size: u32,
    exec: Executor,
    uniforms: wgpu::Buffer,
    vpls: wgpu::Buffer,
    marks: wgpu::Buffer,
    volume: wgpu::Buffer,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    /// The interleaved gather's partial sums (rgba32float), when interleaved.
    partial: Option<wgpu::Texture>,
    frame: Option<AreaIvsvFrame>,
    /// The VPLs of the last [`AreaIvsv::prepare_light`] (empty after [`AreaIvsv::prepare`]).
    vpl_inputs: Vec<VplInput>,
}

impl AreaIvsv {
    /// Validates the sizes against the device and creates the pipelines and buffers (two
    /// voxel buffers of [`AreaIvsvVariant::voxel_bytes`] each).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::EmptyInput`] for a zero size; [`RuntimeError::LimitExceeded`] naming
    /// the device limit (the screen or map side, the VPL count against
    /// `max_texture_array_layers`, the VPL records against `max_uniform_buffer_binding_size`,
    /// a voxel buffer against `max_storage_buffer_binding_size`);
    /// [`RuntimeError::Shader`] for a bad knob; [`RuntimeError::Wgpu`] when a resource fails.
    pub fn new(
        ctx: &Context,
        variant: &AreaIvsvVariant,
        screen: [u32; 2],
        map_size: u32,
    ) -> Result<Self, RuntimeError> {
        check_nonempty(&[
            (GATHER, "screen", screen),
            (RECTIFY, "VPL shadow map", [map_size; 2]),
        ])?;
        let limits = ctx.device().limits();
        check_texture_sides(
            &limits,
            &[
                (GATHER, "screen width", screen[0]),
                (GATHER, "screen height", screen[1]),
                (RECTIFY, "VPL shadow map size", map_size),
            ],
        )?;
        check_limit(
            RECTIFY,
            "VPLs (layers of vpl_maps)",
            u64::from(variant.vpls),
            "max_texture_array_layers",
            u64::from(limits.max_texture_array_layers),
        )?;
        check_limit(
            GATHER,
            "VPL record bytes (176 per VPL, one uniform array)",
            176 * u64::from(variant.vpls),
            "max_uniform_buffer_binding_size",
            limits.max_uniform_buffer_binding_size,
        )?;
        for (name, limit) in [
            (
                "max_storage_buffer_binding_size",
                limits.max_storage_buffer_binding_size,
            ),
            ("max_buffer_size", limits.max_buffer_size),
        ] {
            check_limit(
                SCAN,
                "voxel buffer bytes (16 per texel of every VPL's grid)",
                variant.voxel_bytes(),
                name,
                limit,
            )?;
        }
        if screen[0] < variant.interleave || screen[1] < variant.interleave {
            return Err(RuntimeError::EmptyInput {
                kernel: GATHER,
                size: format!(
                    "screen {}x{} (smaller than the interleaving window {})",
                    screen[0], screen[1], variant.interleave
                ),
            });
        }
        let built = scatter_shaderlib::KernelParams::area_ivsv(*variant)
            .iter()
            .map(scatter_shaderlib::build)
            .collect::<Result<Vec<_>, _>>()?;
        let exec = Executor::new(
            ctx,
            scatter_shaderlib::area_ivsv::plan::plan(variant),
            built,
            &[
                ("screen.width", screen[0].into()),
                ("screen.height", screen[1].into()),
                ("shadow.size", map_size.into()),
            ],
        )?;
        let (output, output_view) = exec.texture("output")?;
        let partial = if variant.interleave > 1 {
            Some(exec.texture("partial")?.0.clone())
        } else {
            None
        };
        Ok(AreaIvsv {
            variant: *variant,
            screen,
            map_size,
            uniforms: exec.buffer("frame")?.clone(),
            vpls: exec.buffer("vpls")?.clone(),
            marks: exec.buffer("marks")?.clone(),
            volume: exec.buffer("volume")?.clone(),
            output: output.clone(),
            output_view: output_view.clone(),
            partial,
            exec,
            frame: None,
            vpl_inputs: Vec::new(),
        })
    }

    /// Sets up one frame ([`prepare_area_ivsv`]) and uploads the uniforms and VPL records.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Frame`] for a VPL count other than the variant's, a VPL that is not
    /// a spot, a map of another size, NaN or degenerate input; [`RuntimeError::Wgpu`] when an
    /// upload fails.
    pub fn prepare(
        &mut self,
        ctx: &Context,
        camera: &CameraDesc,
        medium: &MediumDesc,
        vpls: &[VplInput],
    ) -> Result<(), RuntimeError> {
        let prepared = prepare_area_ivsv(
            &self.variant,
            self.screen,
            camera,
            medium,
            vpls,
            self.map_size,
        )?;
        let scope = ErrorScopes::push(ctx.device());
        let queue = ctx.queue();
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&prepared.uniforms));
        queue.write_buffer(&self.vpls, 0, bytemuck::cast_slice(&prepared.vpls));
        scope.pop(GATHER, "uploading frame parameters")?;
        self.frame = Some(prepared);
        self.vpl_inputs.clear();
        Ok(())
    }

    /// Sets up and uploads one frame of an area light: `input.light` must be a
    /// `LightDesc::Area`, `input.shadow_map` the standard map of its point limit (a
    /// perspective map of the size [`Self::new`] took), from which each VPL's map is derived
    /// ([`Self::vpls`]: render layer `i` of the VPL map array with `vpls()[i].shadow_map`).
    /// `input.settings` is not used.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Frame`] for another light, a bad area light, a template that is not
    /// a perspective map of the right size, NaN or degenerate input; [`RuntimeError::Wgpu`]
    /// when an upload fails.
    pub fn prepare_light(&mut self, ctx: &Context, input: &FrameInput) -> Result<(), RuntimeError> {
        if input.shadow_map.size != self.map_size {
            return Err(scatter_shaderlib::prefiltered::FrameError::OutOfRange {
                what: "shadow map size",
                allowed: "the VPL map size the passes were built for",
                value: format!("{} (built for {})", input.shadow_map.size, self.map_size),
            }
            .into());
        }
        let (prepared, vpls) = prepare_area_light(
            &self.variant,
            self.screen,
            &input.camera,
            &input.light,
            &input.medium,
            &input.shadow_map,
        )?;
        let scope = ErrorScopes::push(ctx.device());
        let queue = ctx.queue();
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&prepared.uniforms));
        queue.write_buffer(&self.vpls, 0, bytemuck::cast_slice(&prepared.vpls));
        scope.pop(GATHER, "uploading frame parameters")?;
        self.frame = Some(prepared);
        self.vpl_inputs = vpls;
        Ok(())
    }

    /// The VPLs of the last [`Self::prepare_light`], in layer order: each one's spot light
    /// and the shadow map the engine renders into its layer of the VPL map array.
    pub fn vpls(&self) -> &[VplInput] {
        &self.vpl_inputs
    }

    /// Records the passes (with GPU timestamps when the device has them) and returns
    /// the output view: in-scattered radiance, rgba16float, screen-sized. `depth` is linear
    /// view depth (r32float, screen-sized); `vpl_maps` an r32float 2D-array view of one
    /// layer per VPL, each `map_size` squared.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::NotPrepared`] before [`Self::prepare`];
    /// [`RuntimeError::InputMismatch`] for a view of the wrong format, size, layer count,
    /// dimension or usage; [`RuntimeError::Wgpu`] when wgpu rejects a bind group.
    pub fn encode(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::TextureView,
        vpl_maps: &wgpu::TextureView,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        self.encode_selected(ctx, encoder, depth, vpl_maps, None)
    }

    fn check_maps(&self, view: &wgpu::TextureView) -> Result<(), RuntimeError> {
        let texture = view.texture();
        let mismatch = |what, expected: String, actual: String| {
            Err(RuntimeError::InputMismatch {
                kernel: RECTIFY,
                what,
                expected,
                actual,
            })
        };
        let size = texture.size();
        let expected = [self.map_size, self.map_size, self.variant.vpls];
        let actual = [size.width, size.height, size.depth_or_array_layers];
        if texture.format() != DEPTH_FORMAT {
            return mismatch(
                "VPL shadow maps format",
                format!("{DEPTH_FORMAT:?}"),
                format!("{:?}", texture.format()),
            );
        }
        if actual != expected {
            return mismatch(
                "VPL shadow maps size (width x height x layers)",
                format!("{}x{}x{}", expected[0], expected[1], expected[2]),
                format!("{}x{}x{}", actual[0], actual[1], actual[2]),
            );
        }
        if !texture
            .usage()
            .contains(wgpu::TextureUsages::TEXTURE_BINDING)
        {
            return mismatch(
                "VPL shadow maps usage",
                "TEXTURE_BINDING".to_owned(),
                format!("{:?}", texture.usage()),
            );
        }
        Ok(())
    }

    fn encode_selected(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::TextureView,
        vpl_maps: &wgpu::TextureView,
        only: Option<Kernel>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        if self.frame.is_none() {
            return Err(RuntimeError::NotPrepared { kernel: GATHER });
        }
        check_view(GATHER, &DEPTH_NAMES, depth, self.screen)?;
        self.check_maps(vpl_maps)?;
        let engine = [("depth", depth), ("vpl_maps", vpl_maps)];
        self.exec
            .encode(ctx.device(), encoder, &engine, &[], only)?;
        Ok(&self.output_view)
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
        vpl_maps: &wgpu::TextureView,
        frames: u32,
    ) -> Result<AreaIvsvTimes, RuntimeError> {
        let [rectify, scan, gather, interleave_sum, unwarp, fallback] = median_pass_wall_times(
            ctx,
            [RECTIFY, SCAN, GATHER, INTERLEAVE_SUM, UNWARP, FALLBACK],
            frames,
            |encoder, kernel| {
                self.encode_selected(ctx, encoder, depth, vpl_maps, Some(kernel))
                    .map(|_| ())
            },
        )?;
        Ok(AreaIvsvTimes {
            rectify,
            scan,
            gather,
            interleave_sum: crate::timer::when(self.variant.interleave > 1, interleave_sum),
            unwarp: crate::timer::when(self.sampled(), unwarp),
            fallback: crate::timer::when(self.sampled(), fallback),
        })
    }

    /// Whether the variant samples (lowres or epipolar: it has the unwarp and fallback
    /// passes).
    fn sampled(&self) -> bool {
        self.variant.sampling != scatter_shaderlib::sampling::Sampling::Pixels
    }

    /// GPU time of each pass of the last submitted [`Self::encode`], or `None` without
    /// timestamps. Blocks until the GPU is done.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
    pub fn pass_times(&self, ctx: &Context) -> Result<Option<AreaIvsvTimes>, RuntimeError> {
        let Some(timer) = self.exec.timer() else {
            return Ok(None);
        };
        let t = timer.read_all(ctx, GATHER)?;
        let at = |i: usize| t.get(i).copied().unwrap_or_default();
        // The passes in plan order: rectify, scan, gather, then interleave_sum or the
        // unwarp and the fallback.
        let interleaved = self.variant.interleave > 1;
        Ok(Some(AreaIvsvTimes {
            rectify: at(0),
            scan: at(1),
            gather: at(2),
            interleave_sum: crate::timer::when(interleaved, at(3)),
            unwarp: crate::timer::when(self.sampled(), at(3)),
            fallback: crate::timer::when(self.sampled(), at(4)),
        }))
    }

    /// The variant the pipelines were built for.
    pub fn variant(&self) -> &AreaIvsvVariant {
        &self.variant
    }

    /// The frame set-up of the last [`Self::prepare`].
    pub fn frame(&self) -> Option<&AreaIvsvFrame> {
        self.frame.as_ref()
    }

    /// The `volume` buffer (`4 N theta alpha` `u32`: the extruded voxel bits).
    pub fn volume_buffer(&self) -> &wgpu::Buffer {
        &self.volume
    }

    /// The output texture (rgba16float, screen-sized).
    pub fn output_texture(&self) -> &wgpu::Texture {
        &self.output
    }
}

impl crate::family::FamilyRuntime for AreaIvsv {
    type Variant = AreaIvsvVariant;

    /// `shadow_map_size` is the VPL maps' size (the standard map's: the template's).
    fn create(
        ctx: &Context,
        variant: &AreaIvsvVariant,
        res: Resolutions,
        shadow_map_size: u32,
    ) -> Result<Self, RuntimeError> {
        Self::new(ctx, variant, res.screen, shadow_map_size)
    }

    fn knobs(&self) -> AreaIvsvVariant {
        self.variant
    }

    fn prepare_frame(
        &mut self,
        ctx: &Context,
        input: &FrameInput,
    ) -> Result<Option<scatter_shaderlib::prefiltered::FrameReport>, RuntimeError> {
        self.prepare_light(ctx, input)?;
        Ok(None)
    }

    fn encode_frame(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &Inputs<'_>,
    ) -> Result<&wgpu::TextureView, RuntimeError> {
        self.encode(ctx, encoder, inputs.depth, required_vpl_maps(inputs)?)
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
        inputs: &Inputs<'_>,
        frames: u32,
    ) -> Result<Vec<(Kernel, Duration)>, RuntimeError> {
        let t =
            self.measure_pass_wall_times(ctx, inputs.depth, required_vpl_maps(inputs)?, frames)?;
        let mut passes = vec![(RECTIFY, t.rectify), (SCAN, t.scan), (GATHER, t.gather)];
        if self.variant.interleave > 1 {
            passes.push((INTERLEAVE_SUM, t.interleave_sum));
        }
        if self.sampled() {
            passes.push((UNWARP, t.unwarp));
            passes.push((FALLBACK, t.fallback));
        }
        Ok(passes)
    }
}

/// The VPL map array of `inputs`, which every area_ivsv frame needs.
fn required_vpl_maps<'a>(inputs: &Inputs<'a>) -> Result<&'a wgpu::TextureView, RuntimeError> {
    inputs.vpl_maps.ok_or(RuntimeError::MissingInput {
        kernel: RECTIFY,
        what: "the VPL shadow maps (an r32float array, one layer per VPL)",
    })
}

/// Everything [`run_area_ivsv_once`] reads back.
#[derive(Clone, Debug)]
pub struct AreaIvsvReadback {
    /// The frame set-up that was uploaded.
    pub frame: AreaIvsvFrame,
    /// `marks` after `ivsv_rectify`.
    pub marks: Vec<u32>,
    /// `volume` after `ivsv_scan`.
    pub volume: Vec<u32>,
    /// `marks` after `ivsv_scan` (zero: the scan clears what it read).
    pub marks_after_scan: Vec<u32>,
    /// The interleaved gather's partial sums (rgba32float), row-major; empty without
    /// interleaving.
    pub partial: Vec<[f32; 4]>,
    /// In-scattered radiance per pixel (rgba16float converted to f32), row-major.
    pub output: Vec<[f32; 4]>,
    /// GPU time per pass, when the device has timestamps.
    pub gpu_times: Option<AreaIvsvTimes>,
    /// Wall time from submission until every result was mapped.
    pub wall_time: Duration,
}

fn u32s(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// Uploads `layers` VPL shadow maps of `map_size` squared values each (layer-major, then
/// row-major from the top-left texel) as an r32float array texture, and its 2D-array view
/// (the view [`AreaIvsv::encode`] takes).
///
/// # Errors
///
/// [`RuntimeError::DataLength`] when `data` does not hold every texel; GPU errors.
pub fn upload_vpl_maps(
    ctx: &Context,
    map_size: u32,
    layers: u32,
    data: &[f32],
) -> Result<(wgpu::Texture, wgpu::TextureView), RuntimeError> {
    let expected = u64::from(map_size) * u64::from(map_size) * u64::from(layers);
    if data.len() as u64 != expected {
        return Err(RuntimeError::DataLength {
            kernel: RECTIFY,
            size: format!("VPL shadow maps {map_size}x{map_size}x{layers}"),
            expected,
            actual: data.len() as u64,
        });
    }
    let device = ctx.device();
    let scope = ErrorScopes::push(device);
    let extent = wgpu::Extent3d {
        width: map_size,
        height: map_size,
        depth_or_array_layers: layers,
    };
    let maps = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("vpl_maps"),
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: DEPTH_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    ctx.queue().write_texture(
        maps.as_image_copy(),
        bytemuck::cast_slice(data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(map_size * 4),
            rows_per_image: Some(map_size),
        },
        extent,
    );
    let view = maps.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..wgpu::TextureViewDescriptor::default()
    });
    scope.pop(RECTIFY, "uploading the VPL shadow maps")?;
    Ok((maps, view))
}

/// Test helper: creates an [`AreaIvsv`], uploads `depth` (screen-sized) and `vpl_maps`
/// (`vpls.len()` layers of `map_size` squared values, layer-major), runs one frame pass by
/// pass and reads back the marks after `ivsv_rectify`, the voxels and the marks after
/// `ivsv_scan`, and the output.
///
/// # Errors
///
/// Whatever [`AreaIvsv::new`], [`AreaIvsv::prepare`] or [`AreaIvsv::encode`] fail with;
/// [`RuntimeError::DataLength`] when an input does not match its size; GPU errors.
#[expect(
    clippy::too_many_arguments,
    reason = "one frame's inputs, as a test passes them"
)]
pub fn run_area_ivsv_once(
    ctx: &Context,
    variant: &AreaIvsvVariant,
    screen: [u32; 2],
    camera: &CameraDesc,
    medium: &MediumDesc,
    vpls: &[VplInput],
    map_size: u32,
    depth: &[f32],
    vpl_maps: &[f32],
) -> Result<AreaIvsvReadback, RuntimeError> {
    let mut pass = AreaIvsv::new(ctx, variant, screen, map_size)?;
    let layers = variant.vpls;
    let views = upload_inputs(ctx, &[(GATHER, "depth buffer", screen, depth)])?;
    let (_maps, maps_view) = upload_vpl_maps(ctx, map_size, layers, vpl_maps)?;
    let device = ctx.device();
    pass.prepare(ctx, camera, medium, vpls)?;
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("run_area_ivsv_once"),
    });
    let scope = ErrorScopes::push(device);
    pass.encode_selected(ctx, &mut encoder, &views[0].1, &maps_view, Some(RECTIFY))?;
    let marks = encode_buffer_readback(device, &mut encoder, &pass.marks);
    pass.encode_selected(ctx, &mut encoder, &views[0].1, &maps_view, Some(SCAN))?;
    let volume = encode_buffer_readback(device, &mut encoder, &pass.volume);
    let marks_after = encode_buffer_readback(device, &mut encoder, &pass.marks);
    pass.encode_selected(ctx, &mut encoder, &views[0].1, &maps_view, Some(GATHER))?;
    let partial = match &pass.partial {
        Some(t) => Some(Readback::encode(device, &mut encoder, t, 16, GATHER)?),
        None => None,
    };
    for kernel in [INTERLEAVE_SUM, UNWARP, FALLBACK] {
        pass.encode_selected(ctx, &mut encoder, &views[0].1, &maps_view, Some(kernel))?;
    }
    let output = Readback::encode(device, &mut encoder, pass.output_texture(), 8, GATHER)?;
    let start = Instant::now();
    ctx.queue().submit([encoder.finish()]);
    scope.pop(GATHER, "dispatch")?;
    let marks = u32s(&crate::timer::read_buffer(ctx, RECTIFY, &marks)?);
    let volume = u32s(&crate::timer::read_buffer(ctx, SCAN, &volume)?);
    let marks_after_scan = u32s(&crate::timer::read_buffer(ctx, SCAN, &marks_after)?);
    let partial = match partial {
        Some(p) => p
            .read(ctx, GATHER)?
            .chunks_exact(16)
            .map(|t| decode_rgba(t, Storage::Rgba32float))
            .collect(),
        None => Vec::new(),
    };
    let output = output
        .read(ctx, GATHER)?
        .chunks_exact(8)
        .map(|t| decode_rgba(t, Storage::Rgba16float))
        .collect();
    let wall_time = start.elapsed();
    let gpu_times = pass.pass_times(ctx)?;
    let frame = pass
        .frame
        .ok_or(RuntimeError::NotPrepared { kernel: GATHER })?;
    Ok(AreaIvsvReadback {
        frame,
        marks,
        volume,
        marks_after_scan,
        partial,
        output,
        gpu_times,
        wall_time,
    })
}
