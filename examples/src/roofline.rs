//! The machine's bounds and every kernel's cost model (issue 13, part 1).
//!
//! **Bounds.** Five probe kernels, each over a 1024x1024 grid of invocations (workgroups of
//! 8x8), timed like the bench's passes (each submitted alone and waited for, the median of
//! `frames` after a warm-up): `copy` (one r32float texel loaded and stored: the cost of a
//! byte written, read and invocation included), `texel_load` (16 `textureLoad`s of an r32float texture per invocation),
//! `filtered_fetch` (16 bilinear `textureSampleLevel`s of an rgba16float texture),
//! `transcendental` (8 rounds of sin, cos, exp and atan2 per invocation: 32) and `fma`
//! (4 independent chains of 64 fused multiply-adds: 256). Each gives this machine's cost of
//! one operation of its kind with the whole device busy (ns per operation, and GB/s or
//! Gop/s).
//!
//! **Cost model.** Per kernel of every family, the count per invocation of each kind of
//! operation and the bytes it writes, read from the template's structure
//! ([`kernel_costs`]; derivation in `docs/roofline.md`), at the headline configuration
//! (1280x720, 1024x1024 rectified map, 1024^2 shadow map, each family's default variant and
//! raymarch N = 64 with 4x4 interleaving for `interleave_sum`). The bound of a kernel is the
//! largest of its per-kind times (count x the probe's cost), the roofline's reading: which
//! resource would hold the kernel if nothing else cost anything. The measured pass time per
//! invocation against it says how far the kernel is from that resource's limit.

use std::time::{Duration, Instant};

use scatter_reference::suite::SceneName;
use scatter_runtime::Context;
use scatter_runtime::shaderlib::minmax::BUILD_LANES;
use scatter_runtime::shaderlib::prefiltered::{PrefilteredVariant, RECTIFY_TEXELS};
use scatter_runtime::shaderlib::raymarch::RaymarchVariant;
use scatter_runtime::shaderlib::sampling::{SLICE_LANES, SamplingKnobs};
use scatter_runtime::wgpu;

use crate::bench::{BoxError, Method, time_methods};

/// Side of the probes' square grid of invocations (and of their textures).
const PROBE_SIDE: u32 = 1024;

/// The kinds of operation the cost model counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpKind {
    /// Bytes written to a storage texture or buffer: the copy probe, whose cost per byte
    /// includes the texel read feeding it and the invocation's overhead.
    Bytes,
    /// One unfiltered texel load (`textureLoad`).
    TexelLoad,
    /// One bilinear fetch through a filtering sampler.
    FilteredFetch,
    /// One sin, cos, exp, acos, atan2 or pow.
    Transcendental,
    /// One fused multiply-add (or a multiply or an add).
    Fma,
}

impl OpKind {
    /// Every kind, in table order.
    pub const ALL: [OpKind; 5] = [
        OpKind::Bytes,
        OpKind::TexelLoad,
        OpKind::FilteredFetch,
        OpKind::Transcendental,
        OpKind::Fma,
    ];

    /// The name used in tables.
    pub const fn name(self) -> &'static str {
        match self {
            OpKind::Bytes => "bytes written",
            OpKind::TexelLoad => "texel loads",
            OpKind::FilteredFetch => "filtered fetches",
            OpKind::Transcendental => "transcendentals",
            OpKind::Fma => "FMAs",
        }
    }

    /// The probe that measures it.
    const fn probe(self) -> &'static str {
        match self {
            OpKind::Bytes => "copy",
            OpKind::TexelLoad => "texel_load",
            OpKind::FilteredFetch => "filtered_fetch",
            OpKind::Transcendental => "transcendental",
            OpKind::Fma => "fma",
        }
    }
}

/// One measured bound: the cost of one operation with the device busy.
#[derive(Clone, Copy, Debug)]
pub struct Bound {
    /// What it bounds.
    pub kind: OpKind,
    /// Median wall time of the probe.
    pub probe_time: Duration,
    /// Nanoseconds per operation (per byte for [`OpKind::Bytes`]).
    pub ns_per_op: f64,
}

impl Bound {
    /// Throughput: GB/s written for bytes, else G operations per second.
    pub fn rate(&self) -> f64 {
        1.0 / self.ns_per_op
    }
}

/// The bindings every probe starts with: its source texture and its output.
const PROBE_BINDINGS: &str = "@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var dst: texture_storage_2d<r32float, write>;
";

/// The probe kernels: (kind, WGSL after [`PROBE_BINDINGS`], operations per invocation).
/// Every probe writes one value per invocation so that nothing is optimised away.
fn probes() -> [(OpKind, &'static str, f64); 5] {
    [
        (
            OpKind::Bytes,
            r"@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    textureStore(dst, id.xy, textureLoad(src, id.xy, 0));
}",
            // 4 bytes written (with the texel read that feeds them and the invocation's own
            // overhead: the probe prices a store as a kernel pays for it).
            4.0,
        ),
        (
            OpKind::TexelLoad,
            r"@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var sum = 0.0;
    for (var k = 0u; k < 16u; k++) {
        sum += textureLoad(src, vec2<u32>((id.x + 61u * k) % 1024u, id.y), 0).x;
    }
    textureStore(dst, id.xy, vec4<f32>(sum, 0.0, 0.0, 0.0));
}",
            16.0,
        ),
        (
            OpKind::FilteredFetch,
            r"@group(0) @binding(2) var smp: sampler;
@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var sum = 0.0;
    let uv = (vec2<f32>(id.xy) + vec2<f32>(0.3, 0.7)) / 1024.0;
    for (var k = 0u; k < 16u; k++) {
        sum += textureSampleLevel(src, smp, uv + vec2<f32>(f32(k) * 61.0 / 1024.0, 0.0), 0.0).x;
    }
    textureStore(dst, id.xy, vec4<f32>(sum, 0.0, 0.0, 0.0));
}",
            16.0,
        ),
        (
            OpKind::Transcendental,
            r"@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var x = textureLoad(src, id.xy, 0).x;
    for (var k = 0u; k < 8u; k++) {
        x = sin(x) + cos(x * 1.3) + exp(-abs(x)) + atan2(x, 1.7);
    }
    textureStore(dst, id.xy, vec4<f32>(x, 0.0, 0.0, 0.0));
}",
            32.0,
        ),
        (
            OpKind::Fma,
            r"@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = textureLoad(src, id.xy, 0).x;
    var a = x; var b = x + 1.0; var c = x + 2.0; var d = x + 3.0;
    for (var k = 0u; k < 64u; k++) {
        a = fma(a, 0.999, 0.001);
        b = fma(b, 0.998, 0.002);
        c = fma(c, 0.997, 0.003);
        d = fma(d, 0.996, 0.004);
    }
    textureStore(dst, id.xy, vec4<f32>(a + b + c + d, 0.0, 0.0, 0.0));
}",
            256.0,
        ),
    ]
}

/// A source texture for the probes: `PROBE_SIDE`^2 texels of `format`, filled with a ramp.
fn probe_texture(ctx: &Context, format: wgpu::TextureFormat) -> wgpu::Texture {
    let device = ctx.device();
    let size = wgpu::Extent3d {
        width: PROBE_SIDE,
        height: PROBE_SIDE,
        depth_or_array_layers: 1,
    };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("roofline probe source"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let n = (PROBE_SIDE * PROBE_SIDE) as usize;
    let (bytes, texel_bytes): (Vec<u8>, u32) = match format {
        wgpu::TextureFormat::Rgba16Float => (
            (0..n)
                .flat_map(|i| {
                    let h = half_bits((i % 1024) as f32 / 1024.0);
                    [h, h, h, h]
                })
                .flat_map(u16::to_le_bytes)
                .collect(),
            8,
        ),
        _ => (
            (0..n)
                .flat_map(|i| ((i % 1024) as f32 / 1024.0).to_le_bytes())
                .collect(),
            4,
        ),
    };
    ctx.queue().write_texture(
        texture.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(PROBE_SIDE * texel_bytes),
            rows_per_image: Some(PROBE_SIDE),
        },
        size,
    );
    texture
}

/// IEEE half bits of `v` in [0, 1) (enough for a ramp).
fn half_bits(v: f32) -> u16 {
    if v <= 0.0 {
        return 0;
    }
    let bits = v.to_bits();
    let exp = ((bits >> 23) & 0xff) as i32 - 127 + 15;
    if exp <= 0 {
        return 0;
    }
    ((exp as u16) << 10) | ((bits >> 13) & 0x3ff) as u16
}

/// Runs every probe: the machine's cost of one operation of each kind.
///
/// # Errors
///
/// A probe that fails to build or run (the message names it).
pub fn measure_bounds(ctx: &Context, frames: u32) -> Result<Vec<Bound>, BoxError> {
    let device = ctx.device();
    let r32 = probe_texture(ctx, wgpu::TextureFormat::R32Float);
    let rgba16 = probe_texture(ctx, wgpu::TextureFormat::Rgba16Float);
    let dst = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("roofline probe output"),
        size: wgpu::Extent3d {
            width: PROBE_SIDE,
            height: PROBE_SIDE,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    });
    let dst_view = dst.create_view(&Default::default());
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("roofline probe sampler"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        address_mode_u: wgpu::AddressMode::Repeat,
        ..Default::default()
    });
    let mut out = Vec::new();
    for (kind, source, ops) in probes() {
        let filtered = kind == OpKind::FilteredFetch;
        let src_view = if filtered { &rgba16 } else { &r32 }.create_view(&Default::default());
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(kind.probe()),
            source: wgpu::ShaderSource::Wgsl(format!("{PROBE_BINDINGS}{source}").into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(kind.probe()),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&src_view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&dst_view),
            },
        ];
        if filtered {
            entries.push(wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(&sampler),
            });
        }
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(kind.probe()),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut samples = Vec::new();
        for frame in 0..=frames.max(1) {
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(PROBE_SIDE / 8, PROBE_SIDE / 8, 1);
            }
            let start = Instant::now();
            ctx.queue().submit([encoder.finish()]);
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| format!("roofline probe {}: {e}", kind.probe()))?;
            if frame > 0 {
                samples.push(start.elapsed());
            }
        }
        samples.sort();
        let probe_time = samples[samples.len() / 2];
        let total_ops = ops * f64::from(PROBE_SIDE * PROBE_SIDE);
        out.push(Bound {
            kind,
            probe_time,
            ns_per_op: probe_time.as_secs_f64() * 1e9 / total_ops,
        });
    }
    Ok(out)
}

/// The headline configuration of the cost model.
pub const SCREEN: [u32; 2] = [1280, 720];
/// Rectified map of the headline configuration.
pub const RECTIFIED: [u32; 2] = [1024, 1024];

/// One kernel's cost model at the headline configuration.
#[derive(Clone, Debug)]
pub struct KernelCost {
    /// The method whose pass it is (`prefiltered m32-t16-r4`, `raymarch n64`, ...).
    pub method: &'static str,
    /// The kernel.
    pub kernel: &'static str,
    /// Invocations per frame.
    pub invocations: u64,
    /// Per invocation, the count of each [`OpKind`] (in [`OpKind::ALL`] order); for a
    /// data-dependent kernel the largest.
    pub counts: [f64; 5],
    /// For a data-dependent kernel, the smallest counts (scatter: no region ambiguous).
    pub low: Option<[f64; 5]>,
    /// Loop trips per invocation, in words.
    pub trips: &'static str,
}

/// The cost model of every kernel at the headline configuration (directional light): counts
/// per invocation from the templates' structure, data-dependent branches at their largest
/// (see `docs/roofline.md` for each line's derivation).
pub fn kernel_costs() -> Vec<KernelCost> {
    let [w, h] = SCREEN.map(u64::from);
    let [wr, hr] = RECTIFIED.map(u64::from);
    let pixels = w * h;
    // Default prefiltered variant: 32 bases (8 layers), 16 per thread (4 layers, 2 threads per
    // row and region), its regions (4), rgba8unorm.
    let d = PrefilteredVariant::default();
    let layers = f64::from(d.layers());
    let lpt = f64::from(d.per_thread() / 4);
    let threads = u64::from(d.threads_per_row_region());
    let regions = u64::from(d.regions);
    let region_texels = wr as f64 / regions as f64;
    // minmax_build's block side at the headline's rectified width.
    let build_block = wr as f64 / f64::from(BUILD_LANES);
    let mut out = vec![
        KernelCost {
            method: "prefiltered, minmax",
            kernel: "depth_columns",
            invocations: w,
            // One invocation per screen column: H depth loads (a clamp and a max per load),
            // one 4-byte store.
            counts: [4.0, h as f64, 0.0, 0.0, 3.0 * h as f64],
            low: None,
            trips: "H loads",
        },
        KernelCost {
            method: "prefiltered, minmax",
            kernel: "slice_fit",
            invocations: 256,
            // One workgroup: W/256 column maxima read each (storage loads, counted as texel
            // loads); Hr/256 = 4 rows rewritten (16 bytes each; the sun: one multiply).
            counts: [
                16.0 * hr as f64 / 256.0,
                w as f64 / 256.0,
                0.0,
                0.0,
                4.0 * hr as f64 / 256.0,
            ],
            low: None,
            trips: "W/256 column maxima, then Hr/256 rows",
        },
        KernelCost {
            method: "prefiltered, minmax",
            kernel: "rectify",
            invocations: wr.div_ceil(u64::from(RECTIFY_TEXELS)) * hr,
            // Per column (RECTIFY_TEXELS of a row per invocation): one shadow-map load, an
            // atan2 of the occluder, a 4-byte store; once per invocation cos and sin of the
            // slice angle.
            counts: [
                4.0 * RECTIFY_TEXELS as f64,
                RECTIFY_TEXELS as f64,
                0.0,
                2.0 + RECTIFY_TEXELS as f64,
                30.0 * RECTIFY_TEXELS as f64,
            ],
            low: None,
            trips: "RECTIFY_TEXELS columns",
        },
        KernelCost {
            method: "prefiltered m32-t16-r4",
            kernel: "prefilter",
            invocations: hr * regions * threads,
            // Per texel of its region (Wr/regions on average): one load; sin(theta_ref) twice
            // (ref_t), two exp (transmittance_between), sin and cos of pi d, and threads
            // t > 0 sin and cos of their first frequency; per layer 2 turns, the blend and
            // the store scale (about 28 FMAs); stores of lpt rgba8 texels, and thread 0 the
            // rg32float bounds (8 bytes, 8 / threads per thread).
            counts: [
                region_texels * (4.0 * lpt + 8.0 / threads as f64),
                region_texels,
                0.0,
                region_texels * (6.0 + 2.0 * (threads - 1) as f64 / threads as f64),
                region_texels * (28.0 * lpt + 10.0),
            ],
            low: None,
            trips: "Wr/regions texels x lpt layers",
        },
        KernelCost {
            method: "prefiltered m32-t16-r4",
            kernel: "scatter",
            invocations: pixels,
            // Per pixel: the depth load; acos, atan2, sin and cos of pi d, sin(theta) for x_s
            // (the phase takes a sqrt, not counted); per region (4 at most): 2 bounds loads,
            // 4 loads per layer when the bounds are ambiguous, sin(theta) in each of two
            // ray_t and two exp; the coefficient set-up
            // (8 layers x 2 turns and 4 scales: about 16 FMAs each), per ambiguous region
            // 8 layers x (3 rgba mixes and 4 FMAs: 28); the rgba16float store.
            counts: [
                8.0,
                1.0 + regions as f64 * (2.0 + 4.0 * layers),
                0.0,
                5.0 + regions as f64 * 4.0,
                40.0 + layers * 16.0 + regions as f64 * (30.0 + layers * 28.0),
            ],
            // No region ambiguous: the Fourier loop never runs.
            low: Some([
                8.0,
                1.0 + regions as f64 * 2.0,
                0.0,
                5.0 + regions as f64 * 4.0,
                40.0 + layers * 16.0 + regions as f64 * 30.0,
            ]),
            trips: "regions x layers where ambiguous (none .. all)",
        },
        KernelCost {
            method: "prefiltered moments4-r4",
            kernel: "prefilter",
            invocations: hr * regions,
            // One thread per row and region. Per texel of its region: one load; sin(theta_ref)
            // twice and two exp (the weight, as the Fourier prefilter); z and its powers and
            // the blend of one rgba32float layer (about 12 FMAs) and the weight's arithmetic
            // (10); stores of one rgba32float texel (16 bytes) and the bounds (8 bytes).
            counts: [
                region_texels * 24.0,
                region_texels,
                0.0,
                region_texels * 4.0,
                region_texels * 22.0,
            ],
            low: None,
            trips: "Wr/regions texels x 1 layer",
        },
        KernelCost {
            method: "prefiltered moments4-r4",
            kernel: "scatter",
            invocations: pixels,
            // Scatter's set-up without the Fourier coefficients (acos, atan2, sin(theta) for
            // x_s); per region 2 bounds loads, two ray_t and two exp; per ambiguous region 4
            // loads of one layer, 3 rgba mixes, and the 4MSM solve: about 60 FMAs, a sqrt and
            // 6 divisions (counted as 7 transcendentals).
            counts: [
                8.0,
                1.0 + regions as f64 * (2.0 + 4.0),
                0.0,
                3.0 + regions as f64 * (4.0 + 7.0),
                40.0 + regions as f64 * (30.0 + 12.0 + 60.0),
            ],
            low: Some([
                8.0,
                1.0 + regions as f64 * 2.0,
                0.0,
                3.0 + regions as f64 * 4.0,
                40.0 + regions as f64 * 30.0,
            ]),
            trips: "regions, the solve where ambiguous (none .. all)",
        },
        KernelCost {
            method: "minmax",
            kernel: "minmax_build",
            invocations: u64::from(BUILD_LANES) * hr,
            // One workgroup of BUILD_LANES per row, blocks of B = Wr / BUILD_LANES = 8
            // texels (t = 3): per invocation levels 0..=3 of its block from its B loads,
            // reduced in registers (2B - 1 = 15 nodes stored, 8 bytes each; a select per
            // load, a min and a max per node); then at most one node above t from
            // workgroup memory (counted as texel loads: 2 on average, the root's 128 in one
            // invocation).
            counts: [
                8.0 * 16.0,
                build_block + 2.0,
                0.0,
                0.0,
                2.0 * 2.0 * build_block + 20.0,
            ],
            low: None,
            trips: "B texels, then one node above t",
        },
        KernelCost {
            method: "minmax",
            kernel: "minmax_traverse",
            invocations: pixels,
            // The ray set-up as scatter's (acos, atan2, sin(theta) and two exp per span), then one node
            // load per tree step: at most 2 log2(Wr) = 20 per lit-shadow transition;
            // counted for one transition and two exp per lit span.
            counts: [8.0, 1.0 + 20.0, 0.0, 6.0, 120.0],
            // No tree step: the ray's span is one node.
            low: Some([8.0, 2.0, 0.0, 6.0, 60.0]),
            trips: "tree steps, data-dependent (one transition: 20 .. none)",
        },
        KernelCost {
            method: "hybrid_volume n32",
            kernel: "volume_bounds",
            invocations: 64 * hr,
            // 64 invocations per row, Wr / 64 edges each: two texel loads, the two bins
            // (multiply, floor, clamp) and per covered bin an atomicMin and an atomicMax
            // (counted as two FMAs); then B / 64 bins of 8 bytes stored each. Counted for
            // walls that cover one bin; a wall covers up to B.
            counts: [
                8.0 * 256.0 / 64.0,
                2.0 * wr as f64 / 64.0,
                0.0,
                0.0,
                (wr as f64 / 64.0) * 8.0,
            ],
            low: None,
            trips: "Wr / 64 edges, each over the bins its wall covers (1 .. B)",
        },
        KernelCost {
            method: "hybrid_volume n32",
            kernel: "volume_march",
            invocations: pixels,
            // The ray set-up (two atan2, the depth's normalisation), per row of the two: two
            // rectified loads, one crossings load and two sin (edge_t); head and tail in
            // closed form (two exp each); then N = 32 samples, each a shadow-map load, the
            // sample's light-space transform and test (about 25 FMAs) and its cell's
            // transmittance (two exp). Counted with every sample marched; none marched: the
            // set-up, head and tail.
            counts: [8.0, 6.0 + 32.0, 0.0, 10.0 + 64.0, 80.0 + 32.0 * 25.0],
            low: Some([8.0, 6.0, 0.0, 10.0, 80.0]),
            trips: "samples marched, data-dependent (32 .. none: the interval is empty)",
        },
    ];
    let n = 64.0;
    out.push(KernelCost {
        method: "raymarch n64",
        kernel: "raymarch",
        invocations: pixels,
        // The depth load; per sample: one shadow-map load, two exp (the cell's
        // transmittance), light-space transform and bias (about 25 FMAs); the equiangular
        // set-up's two atan once (computed for the sun too).
        counts: [8.0, n + 1.0, 0.0, 2.0 * n + 2.0, 25.0 * n + 20.0],
        low: None,
        trips: "N samples",
    });
    out.push(KernelCost {
        method: "raymarch n64 i4",
        kernel: "interleave_sum",
        invocations: pixels,
        // The separable 4x4 sum through workgroup memory: one load of the partial sum,
        // 4 + 4 adds (rgba), the store.
        counts: [8.0, 1.0, 0.0, 0.0, 32.0],
        low: None,
        trips: "2 x 4 taps",
    });
    sampled_costs(&mut out, pixels, n);
    // partial_sum_tree, rank 4, 512 slices x 256 samples: one workgroup of 32 lanes per
    // slice; counts per invocation averaged over the slice's lanes (the sweep runs on one
    // of them). Per slice: Q = 256 sample set-ups (depth and tail loads, two atan2, sin,
    // acos, two exp: about 10 transcendentals), Q^2 = 65536 rank comparisons (two per pair),
    // Wr = 1024 columns (a load, an 8-step binary search, the leaf: two factor loads and
    // a lerp, 16 + 4 bytes), then (Wr + Q) log2 Q = 10240 tree steps of one vec4 load and
    // add (inserts also store 16 bytes) and Q answers (beta: two loads).
    let q = 256.0;
    let slices = 512u64;
    let per_lane = |per_slice: f64| per_slice / 32.0;
    out.push(KernelCost {
        method: "partial_sum_tree r4",
        kernel: "pst_sweep",
        invocations: slices * 32,
        counts: [
            per_lane(q * 16.0 + wr as f64 * 20.0 + wr as f64 * 8.0 * 16.0),
            per_lane(3.0 * q + wr as f64 + (wr as f64 + q) * 8.0 + 2.0 * wr as f64),
            0.0,
            per_lane(10.0 * q),
            per_lane(2.0 * q * q + wr as f64 * (24.0 + 8.0) + (wr as f64 + q) * 8.0 * 4.0),
        ],
        low: None,
        trips: "per slice: Q set-ups, Q^2 rank comparisons, Wr columns, (Wr + Q) log2 Q tree steps on one lane",
    });
    out.push(KernelCost {
        method: "partial_sum_tree r4",
        kernel: "pst_sweep_unwarp",
        invocations: w.div_ceil(2) * h.div_ceil(2),
        // The shared epipolar unwarp (`raymarch n64 ep512`'s `raymarch_unwarp` line).
        counts: EPIPOLAR_UNWARP,
        low: None,
        trips: "2 x 2 pixels x 4 taps",
    });
    out.push(KernelCost {
        method: "partial_sum_tree r4",
        kernel: "pst_sweep_fallback",
        // Dispatched indirectly, one invocation per listed pixel: the ray set-up and every
        // column of its row summed without the tree (Wr rectified loads, the leaves' two
        // factor loads each). Counted for one pixel listed per 8 x 8 (1.6 %).
        invocations: pixels.div_ceil(64),
        counts: [8.0, 3.0 + wr as f64 * 3.0, 0.0, 4.0, 40.0 + wr as f64 * 24.0],
        low: None,
        trips: "Wr columns per listed pixel; listed pixels data-dependent (none .. a few per cent of the screen)",
    });
    // area_ivsv at its defaults: 64 VPLs, 256 x 256 texels per VPL, 8 segments (the
    // interleaved sum at M = 2); its passes are measured by `examples/area_bench`, not the
    // headline (an area light, not the suite's sun).
    let (vpls, alpha, theta, segments) = (64.0, 256.0, 256u64, 8.0);
    out.push(KernelCost {
        method: "area_ivsv v64-a256-t256-k8",
        kernel: "ivsv_rectify",
        invocations: 128 * theta * 64,
        // One light ray: its direction (sin, cos of phi; the plane normal's sin and cos of
        // theta), one nearest shadow-map load, the occluder's eye angle (atan2), the bias and
        // the light-space transform (about 60 FMAs), one 4-byte atomicOr.
        counts: [4.0, 1.0, 0.0, 5.0, 60.0],
        low: None,
        trips: "none (one light ray)",
    });
    out.push(KernelCost {
        method: "area_ivsv v64-a256-t256-k8",
        kernel: "ivsv_scan",
        invocations: 4 * theta * 64,
        // One word of a row, scanned along alpha: per texel an atomicExchange of `marks`
        // (a load and a 4-byte store), an OR and a 4-byte store to `volume`.
        counts: [8.0 * alpha, alpha, 0.0, 0.0, 2.0 * alpha],
        low: None,
        trips: "alpha texels",
    });
    out.push(KernelCost {
        method: "area_ivsv v64-a256-t256-k8",
        kernel: "ivsv_gather",
        invocations: pixels,
        // The depth load; per VPL: alpha, theta, phi_s, phi0 (4 atan2), sin and cos of alpha,
        // acos and sqrt of the cone's interval, cos and sin of the step, of lo and of
        // alpha + lo (11), then per knot (segments + 1) an exp and the phase's pow (2);
        // 8 storage loads (two rows' 128 bits); per segment two masked popcount moments
        // (about 60 operations each) and the density (about 25): about 150, plus 80 of set-up.
        counts: [
            8.0,
            1.0 + 8.0 * vpls,
            0.0,
            vpls * (11.0 + 2.0 * (segments + 1.0)),
            vpls * (150.0 * segments + 80.0),
        ],
        low: None,
        trips: "N VPLs x segments pieces",
    });
    out.push(KernelCost {
        method: "area_ivsv v64-a256-t256-k8-i2",
        kernel: "ivsv_interleave_sum",
        invocations: pixels,
        // The 2 x 2 window of partial sums (rgba32float loads), 3 x 3 adds, the store.
        counts: [8.0, 4.0, 0.0, 0.0, 12.0],
        low: None,
        trips: "M x M taps",
    });
    out
}

/// The sampled passes (`scatter::sampling`, shared by every family) at their defaults, for
/// raymarch N = `n` (the family without fixed passes; another family's samples pass is its
/// per-pixel body per sample, its unwarp and fallback the same code): epipolar 512 slices x
/// 256 samples at step 8, and lowres at scale 2.
fn sampled_costs(out: &mut Vec<KernelCost>, pixels: u64, n: f64) {
    let [w, h] = SCREEN.map(u64::from);
    // One raymarch evaluation (the per-pixel line without its depth load), rounded to f16.
    let eval = [0.0, n, 0.0, 2.0 * n + 2.0, 25.0 * n + 30.0];
    let (slices, samples, step) = (
        u64::from(SamplingKnobs::DEFAULT_SLICES),
        f64::from(SamplingKnobs::DEFAULT_SLICE_SAMPLES),
        f64::from(SamplingKnobs::DEFAULT_STEP),
    );
    let lanes = f64::from(SLICE_LANES);
    let per_lane = samples / lanes;
    // Evaluated samples per lane: every STEP-th and the last (none at a break), .. every one.
    let evaluated = |e: f64| {
        std::array::from_fn(|i| {
            // Per lane: its samples' depth loads, marking, interpolation and stores (16 B
            // each); the layout (four atan2 of the corners), the slice's direction and span
            // (two sin/cos pairs) once.
            let fixed = [16.0 * per_lane, per_lane, 0.0, 8.0, 80.0 + per_lane * 22.0];
            fixed[i] + e * eval[i]
        })
    };
    out.push(KernelCost {
        method: "raymarch n64 ep512",
        kernel: "raymarch",
        invocations: slices * u64::from(SLICE_LANES),
        // A workgroup of SLICE_LANES per slice; counts per lane, the evaluations at their
        // largest (every sample: depth breaks everywhere).
        counts: evaluated(per_lane),
        low: Some(evaluated((samples / step + 1.0) / lanes)),
        trips: "per lane: samples / lanes set-ups, evaluations (samples / step + 1 .. samples) / lanes",
    });
    out.push(KernelCost {
        method: "raymarch n64 ep512",
        kernel: "raymarch_unwarp",
        invocations: w.div_ceil(2) * h.div_ceil(2),
        counts: EPIPOLAR_UNWARP,
        low: None,
        trips: "2 x 2 pixels x 4 taps",
    });
    let grid = lowres_grid(w, 2) * lowres_grid(h, 2);
    out.push(KernelCost {
        method: "raymarch n64 lr2",
        kernel: "raymarch",
        invocations: grid,
        // One evaluation per grid sample: the depth load, the march, a 16-byte store.
        counts: [16.0, 1.0 + n, 0.0, eval[3], eval[4] + 10.0],
        low: None,
        trips: "N samples",
    });
    out.push(KernelCost {
        method: "raymarch n64 lr2",
        kernel: "raymarch_unwarp",
        // One invocation per 2 x 2 block (its pixels share their four samples).
        invocations: w.div_ceil(2) * h.div_ceil(2),
        // Four sample loads, then per pixel its depth, the taps' weights (two divisions) and
        // the blend (about 75 FMAs), the rgba16float store (or a 4-byte list entry).
        counts: [32.0, 8.0, 0.0, 8.0, 300.0],
        low: None,
        trips: "S x S pixels x 4 taps",
    });
    for method in ["raymarch n64 ep512", "raymarch n64 lr2"] {
        // Dispatched indirectly, one invocation per listed pixel: the count and the entry,
        // then the per-pixel body. Counted for 5 % of the pixels listed (the headline lists
        // 0.3-4 %).
        out.push(KernelCost {
            method,
            kernel: "raymarch_fallback",
            invocations: (pixels as f64 * 0.05) as u64,
            counts: [8.0, 4.0 + n, 0.0, eval[3], 8.0 + eval[4]],
            low: None,
            trips: "N samples per listed pixel; listed pixels data-dependent (none .. 5 % of the screen)",
        });
    }
}

/// One invocation of the epipolar unwarp (every family's `<kernel>_unwarp`), a 2 x 2 block
/// (`scatter_shaderlib::sampling::EPIPOLAR_UNWARP_BLOCK`): the layout (two loads), the two
/// slices' lines, four sample loads and the four pixels' depths; the centre's angle (one
/// atan2) and about six divisions (counted as transcendentals); per pixel its weights from
/// the gradients and the blend by depth and light (about 90 FMAs); four rgba16float stores
/// (or 4-byte list entries).
const EPIPOLAR_UNWARP: [f64; 5] = [32.0, 12.0, 0.0, 7.0, 360.0];

/// `ceil((side - 1) / scale) + 1`: the lowres grid along one axis.
fn lowres_grid(side: u64, scale: u64) -> u64 {
    (side - 1).div_ceil(scale) + 1
}

/// One row of the roofline table: a kernel's model, its bound and its measured time.
#[derive(Clone, Debug)]
pub struct RooflineRow {
    /// The cost model.
    pub cost: KernelCost,
    /// Per kind, the bound's time per invocation in ns (count x the probe's cost).
    pub bound_ns: [f64; 5],
    /// The same for the smallest counts of a data-dependent kernel.
    pub low_bound_ns: Option<[f64; 5]>,
    /// The measured pass wall time per invocation in ns (median over the scenes measured).
    pub measured_ns: Option<f64>,
}

impl RooflineRow {
    /// The largest per-kind time and its kind: the resource that bounds the kernel.
    pub fn bound(&self) -> (OpKind, f64) {
        largest(self.bound_ns)
    }

    /// [`Self::bound`] for the smallest counts of a data-dependent kernel.
    pub fn low_bound(&self) -> Option<(OpKind, f64)> {
        self.low_bound_ns.map(largest)
    }
}

/// The largest per-kind time and its kind.
fn largest(ns: [f64; 5]) -> (OpKind, f64) {
    OpKind::ALL
        .iter()
        .zip(ns)
        .map(|(&k, t)| (k, t))
        .fold((OpKind::Bytes, 0.0), |a, b| if b.1 > a.1 { b } else { a })
}

/// Measured pass wall times (1280x720, 1024x1024 map, sphere/ordinary; raymarch N = 64 with
/// and without 4x4 interleaving) joined with the cost model and the bounds.
///
/// # Errors
///
/// Scene set-up or GPU errors of the timed runs.
pub fn roofline(
    ctx: &Context,
    bounds: &[Bound],
    frames: u32,
) -> Result<Vec<RooflineRow>, BoxError> {
    let methods = [
        Method::prefiltered_default(),
        Method::minmax_default(),
        Method::from(RaymarchVariant {
            samples: 64,
            interleave: 1,
            ..RaymarchVariant::default()
        }),
        Method::from(RaymarchVariant {
            samples: 64,
            interleave: 4,
            ..RaymarchVariant::default()
        }),
        Method::from(PrefilteredVariant::with_moments(4)),
        Method::from(sampled_raymarch(SamplingKnobs::epipolar(
            SamplingKnobs::DEFAULT_SLICES,
        ))),
        Method::from(sampled_raymarch(SamplingKnobs::lowres(2))),
    ];
    let times = time_methods(ctx, &methods, SceneName::Sphere, SCREEN, RECTIFIED, frames)?;
    // (run, kernel, time): raymarch from the plain run, interleave_sum from the interleaved
    // one. The moment basis's prefilter and scatter (method 4) and the sampled runs' passes
    // (methods 5 and 6) go to their own cost lines, keyed by the method (`run_of`); the
    // moment basis's shared first passes are the default's.
    let mut measured: Vec<(Run, &'static str, Duration)> = Vec::new();
    for (i, passes) in times.into_iter().enumerate() {
        let run = match i {
            4 => Run::Moments,
            5 => Run::Epipolar,
            6 => Run::Lowres,
            _ => Run::Default,
        };
        for (name, t) in passes {
            let keep = !matches!(
                (i, name),
                (3, "raymarch") | (1 | 4, "depth_columns" | "slice_fit" | "rectify")
            );
            if keep {
                measured.push((run, name, t));
            }
        }
    }
    let cost_of = |kind: OpKind| {
        bounds
            .iter()
            .find(|b| b.kind == kind)
            .map_or(f64::NAN, |b| b.ns_per_op)
    };
    Ok(kernel_costs()
        .into_iter()
        .map(|cost| {
            let per_kind =
                |counts: [f64; 5]| std::array::from_fn(|i| counts[i] * cost_of(OpKind::ALL[i]));
            let bound_ns = per_kind(cost.counts);
            let low_bound_ns = cost.low.map(per_kind);
            let run = run_of(cost.method);
            let measured_ns = measured
                .iter()
                .find(|(m, n, _)| *m == run && *n == cost.kernel)
                .map(|(_, _, t)| t.as_secs_f64() * 1e9 / cost.invocations as f64);
            RooflineRow {
                cost,
                bound_ns,
                low_bound_ns,
                measured_ns,
            }
        })
        .collect())
}

/// Which timed run measures a cost line's kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Run {
    /// The per-pixel defaults (prefiltered, minmax, raymarch n64 with and without 4x4).
    Default,
    /// Prefiltered with 4 moments.
    Moments,
    /// Raymarch n64, `sampling = epipolar` at its defaults.
    Epipolar,
    /// Raymarch n64, `sampling = lowres`, scale 2.
    Lowres,
}

/// The run a cost line's method is measured in.
fn run_of(method: &str) -> Run {
    if method.contains("moments") {
        Run::Moments
    } else if method.ends_with("ep512") {
        Run::Epipolar
    } else if method.ends_with("lr2") {
        Run::Lowres
    } else {
        Run::Default
    }
}

/// Raymarch N = 64 (the headline's) with `sampling`.
fn sampled_raymarch(sampling: SamplingKnobs) -> RaymarchVariant {
    use scatter_runtime::shaderlib::family::KnobSet;
    RaymarchVariant {
        samples: 64,
        interleave: 1,
        ..RaymarchVariant::default()
    }
    .with_sampling(sampling)
}

/// The bounds as a markdown table.
pub fn bounds_markdown(bounds: &[Bound]) -> String {
    let mut s = String::from(
        "| probe | per invocation | median time (1024^2 invocations) | cost per operation | throughput |\n|---|---|---|---|---|\n",
    );
    for b in bounds {
        let (per, unit) = match b.kind {
            OpKind::Bytes => (
                "1 r32float texel loaded and stored (4 B written)",
                "GB/s written",
            ),
            OpKind::TexelLoad => ("16 r32float loads", "G loads/s"),
            OpKind::FilteredFetch => ("16 bilinear rgba16float fetches", "G fetches/s"),
            OpKind::Transcendental => ("32 (sin, cos, exp, atan2)", "G ops/s"),
            OpKind::Fma => ("256 FMAs (4 chains)", "G FMAs/s"),
        };
        s.push_str(&format!(
            "| {} | {per} | {:.2} ms | {:.3} ns | {:.2} {unit} |\n",
            b.kind.probe(),
            b.probe_time.as_secs_f64() * 1e3,
            b.ns_per_op,
            b.rate()
        ));
    }
    s
}

/// The cost model and the roofline as a markdown table. A data-dependent kernel shows its
/// smallest .. largest counts and bounds.
pub fn roofline_markdown(rows: &[RooflineRow]) -> String {
    let mut s = String::from(
        "| method | kernel | invocations | bytes written | texel loads | filtered fetches | transcendentals | FMAs | loop trips | bound (ns/inv) | held by | measured (ns/inv) | measured / bound |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let c = &r.cost;
        let count = |i: usize| match c.low {
            Some(low) if low[i] != c.counts[i] => format!("{:.0} .. {:.0}", low[i], c.counts[i]),
            _ => format!("{:.0}", c.counts[i]),
        };
        let (kind, bound) = r.bound();
        let (bound_text, held_by) = match r.low_bound() {
            Some((low_kind, low)) if low_kind != kind => (
                format!("{low:.1} .. {bound:.1}"),
                format!("{} .. {}", low_kind.name(), kind.name()),
            ),
            Some((_, low)) => (format!("{low:.1} .. {bound:.1}"), kind.name().to_owned()),
            None => (format!("{bound:.1}"), kind.name().to_owned()),
        };
        let measured = r.measured_ns.map_or("-".to_owned(), |m| format!("{m:.1}"));
        let ratio = match (r.measured_ns, r.low_bound()) {
            (None, _) => "-".to_owned(),
            (Some(m), Some((_, low))) => format!("{:.1}x .. {:.1}x", m / bound, m / low),
            (Some(m), None) => format!("{:.1}x", m / bound),
        };
        s.push_str(&format!(
            "| {} | `{}` | {} | {} | {} | {} | {} | {} | {} | {bound_text} | {held_by} | {measured} | {ratio} |\n",
            c.method,
            c.kernel,
            c.invocations,
            count(0),
            count(1),
            count(2),
            count(3),
            count(4),
            c.trips,
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kernel_of_every_family_has_a_cost_line() {
        use scatter_runtime::shaderlib::family::{Family, kernels};
        let costs = kernel_costs();
        for &family in Family::ALL {
            for kernel in kernels(family) {
                assert!(
                    costs.iter().any(|c| c.kernel == kernel.name()),
                    "{} has no cost line",
                    kernel.name()
                );
            }
        }
        for c in &costs {
            assert!(c.invocations > 0 && c.counts.iter().all(|n| n.is_finite() && *n >= 0.0));
        }
    }

    #[test]
    fn half_bits_of_a_ramp() {
        assert_eq!(half_bits(0.5), 0x3800);
        assert_eq!(half_bits(0.25), 0x3400);
        assert_eq!(half_bits(0.0), 0);
    }
}
