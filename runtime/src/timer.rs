//! [`GpuTimer`]: a pair of GPU timestamps around a compute pass, and the readback helper
//! shared by every pass.

use std::sync::mpsc;
use std::time::Duration;

use scatter_shaderlib::Kernel;

use crate::{Context, RuntimeError};

/// Two timestamp queries (start and end of one pass) with their resolve and readback
/// buffers.
#[derive(Debug)]
pub struct GpuTimer {
    query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    period_ns: f64,
}

impl GpuTimer {
    const BYTES: u64 = 2 * size_of::<u64>() as u64;

    /// A timer, or `None` when the device has no `TIMESTAMP_QUERY`.
    pub fn new(ctx: &Context) -> Option<Self> {
        if !ctx.has_timestamps() {
            return None;
        }
        let device = ctx.device();
        Some(Self {
            query_set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("scatter timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scatter timestamps resolve"),
                size: Self::BYTES,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scatter timestamps readback"),
                size: Self::BYTES,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            period_ns: f64::from(ctx.queue().get_timestamp_period()),
        })
    }

    /// Timestamp writes at the beginning and end of a compute pass.
    pub fn compute_pass_writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    /// Resolves the queries into the readback buffer; encode after the timed pass.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.query_set, 0..2, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, Self::BYTES);
    }

    /// Reads the elapsed time between the two timestamps; call after the submission that
    /// resolved them.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Poll`] or [`RuntimeError::Readback`].
    pub fn read(&self, ctx: &Context, kernel: Kernel) -> Result<Duration, RuntimeError> {
        let bytes = read_buffer(ctx, kernel, &self.readback)?;
        let ticks: &[u64] =
            bytemuck::try_cast_slice(&bytes).map_err(|e| RuntimeError::Readback {
                kernel,
                message: format!("timestamp buffer: {e}"),
            })?;
        let [start, end] = ticks else {
            return Err(RuntimeError::Readback {
                kernel,
                message: format!("expected 2 timestamps, got {}", ticks.len()),
            });
        };
        let ns = end.saturating_sub(*start) as f64 * self.period_ns;
        Ok(Duration::from_secs_f64(ns * 1e-9))
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
