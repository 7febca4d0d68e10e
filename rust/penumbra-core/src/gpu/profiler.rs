//! Per-pass timing: GPU timestamp queries where the device has them, else CPU
//! clocks around submit-and-wait of each pass (STYLE habit 6). The result says which.

use std::time::Instant;

use crate::error::{Error, Result};
use crate::gpu::pool::ResourcePool;
use crate::gpu::readback::{self, PendingReadback};
use crate::gpu::GpuContext;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimingSource {
    GpuTimestamps,
    CpuClock,
}

impl TimingSource {
    pub fn as_str(self) -> &'static str {
        match self {
            TimingSource::GpuTimestamps => "gpu_timestamps",
            TimingSource::CpuClock => "cpu_clock",
        }
    }
}

/// How a renderer times its passes, as the caller names it: `"auto"` (GPU
/// timestamps where the adapter has them, else CPU clocks) or `"cpu"` (CPU
/// clocks around each pass).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimingMode {
    Auto,
    Cpu,
}

impl TimingMode {
    /// Whether to use GPU timestamp queries where the adapter has them.
    pub fn uses_timestamps(self) -> bool {
        self == TimingMode::Auto
    }
}

impl std::str::FromStr for TimingMode {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(TimingMode::Auto),
            "cpu" => Ok(TimingMode::Cpu),
            other => Err(Error::InvalidParameter(format!("timing must be 'auto' or 'cpu', got {other:?}"))),
        }
    }
}

/// Milliseconds per named pass, in the order they ran.
#[derive(Debug, Clone, PartialEq)]
pub struct Timings {
    pub source: TimingSource,
    pub passes: Vec<(String, f64)>,
}

/// Where a pass writes its begin and end timestamps.
#[derive(Clone, Copy)]
pub struct PassTimestamps<'q> {
    set: &'q wgpu::QuerySet,
    begin: u32,
}

impl<'q> PassTimestamps<'q> {
    pub fn render(self) -> wgpu::RenderPassTimestampWrites<'q> {
        wgpu::RenderPassTimestampWrites {
            query_set: self.set,
            beginning_of_pass_write_index: Some(self.begin),
            end_of_pass_write_index: Some(self.begin + 1),
        }
    }
    pub fn compute(self) -> wgpu::ComputePassTimestampWrites<'q> {
        wgpu::ComputePassTimestampWrites {
            query_set: self.set,
            beginning_of_pass_write_index: Some(self.begin),
            end_of_pass_write_index: Some(self.begin + 1),
        }
    }

    /// For a named pass made of several wgpu passes: the begin timestamp only
    /// (on the first), or the end only (on the last); None for the others.
    pub fn render_part(self, first: bool, last: bool) -> Option<wgpu::RenderPassTimestampWrites<'q>> {
        (first || last).then_some(wgpu::RenderPassTimestampWrites {
            query_set: self.set,
            beginning_of_pass_write_index: first.then_some(self.begin),
            end_of_pass_write_index: last.then_some(self.begin + 1),
        })
    }

    pub fn compute_part(self, first: bool, last: bool) -> Option<wgpu::ComputePassTimestampWrites<'q>> {
        (first || last).then_some(wgpu::ComputePassTimestampWrites {
            query_set: self.set,
            beginning_of_pass_write_index: first.then_some(self.begin),
            end_of_pass_write_index: last.then_some(self.begin + 1),
        })
    }
}

/// Records named passes. With timestamps, all passes share one encoder and
/// one submission; without, each pass is submitted and waited for alone.
pub struct Profiler<'c> {
    ctx: &'c GpuContext,
    pool: &'c ResourcePool,
    encoder: wgpu::CommandEncoder,
    queries: Option<wgpu::QuerySet>,
    names: Vec<String>,
    cpu_ms: Vec<f64>,
}

/// Most passes one render may time.
const MAX_PASSES: u32 = 32;

impl<'c> Profiler<'c> {
    pub fn new(ctx: &'c GpuContext, pool: &'c ResourcePool, use_timestamps: bool) -> Self {
        let queries = (use_timestamps && ctx.has_timestamps()).then(|| {
            ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("penumbra::timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * MAX_PASSES,
            })
        });
        Self {
            ctx,
            pool,
            encoder: Self::new_encoder(ctx),
            queries,
            names: Vec::new(),
            cpu_ms: Vec::new(),
        }
    }

    fn new_encoder(ctx: &GpuContext) -> wgpu::CommandEncoder {
        ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("penumbra::frame"),
        })
    }

    pub fn source(&self) -> TimingSource {
        if self.queries.is_some() {
            TimingSource::GpuTimestamps
        } else {
            TimingSource::CpuClock
        }
    }

    /// Records one named pass. `record` gets the encoder and, with timestamps,
    /// where its wgpu pass (or first and last of several) writes them.
    pub fn pass(
        &mut self,
        name: &str,
        record: impl FnOnce(&mut wgpu::CommandEncoder, Option<PassTimestamps<'_>>),
    ) -> Result<()> {
        let index = self.names.len() as u32;
        if index >= MAX_PASSES {
            return Err(Error::Gpu(format!("more than {MAX_PASSES} timed passes")));
        }
        self.names.push(name.to_owned());
        match &self.queries {
            Some(set) => {
                record(&mut self.encoder, Some(PassTimestamps { set, begin: 2 * index }));
            }
            None => {
                // Submit what came before so it is not counted in this pass.
                self.flush()?;
                let start = Instant::now();
                record(&mut self.encoder, None);
                self.flush()?;
                self.cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
        Ok(())
    }

    /// The encoder for untimed work (readback copies).
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        &mut self.encoder
    }

    fn flush(&mut self) -> Result<()> {
        let encoder = std::mem::replace(&mut self.encoder, Self::new_encoder(self.ctx));
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.wait()
    }

    /// Ends the recording. Returns what the timings are made of, the
    /// encoder (unsubmitted: the caller adds its read-back copies and
    /// submits everything once), and, with timestamps, the copy of the
    /// resolved queries to map with the rest.
    pub fn finish(mut self) -> Result<(Profile, wgpu::CommandEncoder, Option<PendingReadback>)> {
        let source = self.source();
        let mut pending = None;
        if let Some(set) = self.queries.take() {
            let count = 2 * self.names.len() as u32;
            if count > 0 {
                let bytes = count as u64 * wgpu::QUERY_SIZE as u64;
                let usage = wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC;
                let resolve = self.pool.buffer(&self.ctx.device, "penumbra::timestamps_resolve", bytes, usage);
                self.encoder.resolve_query_set(&set, 0..count, &resolve, 0);
                pending = Some(readback::copy_buffer(&self.ctx.device, self.pool, &mut self.encoder, &resolve, bytes as u32));
            }
        }
        let profile = Profile {
            source,
            names: std::mem::take(&mut self.names),
            cpu_ms: std::mem::take(&mut self.cpu_ms),
            period_ns: self.ctx.queue.get_timestamp_period() as f64,
        };
        let encoder = std::mem::replace(&mut self.encoder, Self::new_encoder(self.ctx));
        Ok((profile, encoder, pending))
    }
}

/// The timings of a finished recording, once its work is done.
pub struct Profile {
    source: TimingSource,
    names: Vec<String>,
    cpu_ms: Vec<f64>,
    period_ns: f64,
}

impl Profile {
    /// The pass timings, from CPU clocks or from the mapped timestamps
    /// (`ticks`: the bytes of the read-back [`Profiler::finish`] returned).
    pub fn timings(self, ticks: Option<Vec<u8>>) -> Timings {
        let passes = match self.source {
            TimingSource::CpuClock => self.names.into_iter().zip(self.cpu_ms).collect(),
            TimingSource::GpuTimestamps => {
                let ticks: Vec<u64> = ticks.map(|b| bytemuck::pod_collect_to_vec(&b)).unwrap_or_default();
                self.names
                    .into_iter()
                    .enumerate()
                    .map(|(i, name)| {
                        let (a, b) = (ticks.get(2 * i).copied().unwrap_or(0), ticks.get(2 * i + 1).copied().unwrap_or(0));
                        (name, b.saturating_sub(a) as f64 * self.period_ns * 1e-6)
                    })
                    .collect()
            }
        };
        Timings { source: self.source, passes }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timing_modes_parse_by_name() {
        assert_eq!("auto".parse::<TimingMode>(), Ok(TimingMode::Auto));
        assert_eq!("cpu".parse::<TimingMode>(), Ok(TimingMode::Cpu));
        assert!(TimingMode::Auto.uses_timestamps() && !TimingMode::Cpu.uses_timestamps());
        let err = "sometimes".parse::<TimingMode>().unwrap_err();
        assert!(matches!(&err, Error::InvalidParameter(m) if m.contains("'auto' or 'cpu'")), "{err}");
    }
}
