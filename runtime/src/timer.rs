//! [`GpuTimer`]: GPU timestamps around one or more compute passes, and the readback helper
//! shared by every pass.

use std::sync::mpsc;
use std::time::Duration;

use scatter_shaderlib::Kernel;

use crate::{Context, RuntimeError};

/// Timestamp queries at the start and end of one or more compute passes, with their resolve
/// and readback buffers.
#[derive(Debug)]
pub struct GpuTimer {
    query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    period_ns: f64,
    passes: u32,
}

impl GpuTimer {
    /// A timer for one pass, or `None` when the device has no `TIMESTAMP_QUERY`.
    pub fn new(ctx: &Context) -> Option<Self> {
        Self::with_passes(ctx, 1)
    }

    /// A timer for `passes` passes (at least one), or `None` when the device has no
    /// `TIMESTAMP_QUERY`.
    pub fn with_passes(ctx: &Context, passes: u32) -> Option<Self> {
        if !ctx.has_timestamps() {
            return None;
        }
        let passes = passes.max(1);
        let bytes = Self::bytes(passes);
        let device = ctx.device();
        Some(Self {
            query_set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("scatter timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * passes,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scatter timestamps resolve"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scatter timestamps readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            period_ns: f64::from(ctx.queue().get_timestamp_period()),
            passes,
        })
    }

    fn bytes(passes: u32) -> u64 {
        2 * u64::from(passes) * size_of::<u64>() as u64
    }

    /// Number of passes this timer measures.
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// Timestamp writes at the beginning and end of a compute pass (the first pass).
    pub fn compute_pass_writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    /// Timestamp writes for pass `pass` (0-based), or `None` when `pass >= passes()`.
    pub fn pass_writes(&self, pass: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        (pass < self.passes).then(|| wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(2 * pass),
            end_of_pass_write_index: Some(2 * pass + 1),
        })
    }

    /// Resolves the queries into the readback buffer; encode after the timed passes.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.query_set, 0..2 * self.passes, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(
            &self.resolve,
            0,
            &self.readback,
            0,
            Self::bytes(self.passes),
        );
    }

    /// Reads the elapsed time of the first pass; call after the submission that resolved
    /// the queries.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
    pub fn read(&self, ctx: &Context, kernel: Kernel) -> Result<Duration, RuntimeError> {
        self.read_all(ctx, kernel)?
            .first()
            .copied()
            .ok_or_else(|| RuntimeError::Readback {
                kernel,
                message: "no timestamps".to_owned(),
            })
    }

    /// Reads the elapsed time of every pass, in pass order; call after the submission that
    /// resolved the queries.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
    pub fn read_all(&self, ctx: &Context, kernel: Kernel) -> Result<Vec<Duration>, RuntimeError> {
        let bytes = read_buffer(ctx, kernel, &self.readback)?;
        let ticks: &[u64] =
            bytemuck::try_cast_slice(&bytes).map_err(|e| RuntimeError::Readback {
                kernel,
                message: format!("timestamp buffer: {e}"),
            })?;
        if ticks.len() != 2 * self.passes as usize {
            return Err(RuntimeError::Readback {
                kernel,
                message: format!(
                    "expected {} timestamps, got {}",
                    2 * self.passes,
                    ticks.len()
                ),
            });
        }
        Ok(ticks
            .chunks_exact(2)
            .map(|pair| {
                let ns = pair[1].saturating_sub(pair[0]) as f64 * self.period_ns;
                Duration::from_secs_f64(ns * 1e-9)
            })
            .collect())
    }
}

/// Maps a `MAP_READ` buffer, copies it out and unmaps it (blocking).
pub(crate) fn read_buffer(
    ctx: &Context,
    kernel: Kernel,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u8>, RuntimeError> {
    let (sender, receiver) = mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |result| {
        // The receiver outlives the poll below; a failed send only means it gave up.
        let _ = sender.send(result);
    });
    ctx.device()
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|source| RuntimeError::Poll { kernel, source })?;
    let readback = |message: String| RuntimeError::Readback { kernel, message };
    receiver
        .recv()
        .map_err(|e| readback(format!("map callback never ran: {e}")))?
        .map_err(|e| readback(format!("map_async: {e}")))?;
    let bytes = buffer
        .get_mapped_range(..)
        .map_err(|e| readback(format!("get_mapped_range: {e}")))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// Wall time of each of `kernels` submitted on its own and waited for, the median over
/// `frames` frames after one warm-up frame. `encode` records one kernel's pass (and may
/// record nothing, e.g. a pass the frame skips). On a CPU adapter such as lavapipe this is
/// the pass's real cost; its timestamps are not.
pub(crate) fn median_pass_wall_times<const N: usize>(
    ctx: &Context,
    kernels: [Kernel; N],
    frames: u32,
    mut encode: impl FnMut(&mut wgpu::CommandEncoder, Kernel) -> Result<(), RuntimeError>,
) -> Result<[Duration; N], RuntimeError> {
    let mut samples: [Vec<Duration>; N] = std::array::from_fn(|_| Vec::new());
    for frame in 0..=frames.max(1) {
        for (slot, &kernel) in kernels.iter().enumerate() {
            let mut encoder =
                ctx.device()
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some(kernel.name()),
                    });
            encode(&mut encoder, kernel)?;
            let start = std::time::Instant::now();
            ctx.queue().submit([encoder.finish()]);
            ctx.device()
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|source| RuntimeError::Poll { kernel, source })?;
            if frame > 0 {
                samples[slot].push(start.elapsed());
            }
        }
    }
    Ok(samples.map(|mut v| {
        v.sort();
        v.get(v.len() / 2).copied().unwrap_or_default()
    }))
}

/// `d` when `cond` holds (the pass ran), else zero: the time of a pass only some variants
/// have (the epipolar `_unwarp` and `_fallback` passes).
pub(crate) fn when(cond: bool, d: Duration) -> Duration {
    if cond { d } else { Duration::ZERO }
}
