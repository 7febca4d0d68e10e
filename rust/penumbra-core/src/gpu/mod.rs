//! GPU plumbing shared by every pass: context, readback, timing.

pub mod context;
pub mod formats;
pub mod layout;
pub mod pool;
pub mod profiler;
pub mod readback;

pub use context::{adapter_summary, AdapterSummary, GpuContext};
pub use profiler::{PassTimestamps, Profiler, TimingMode, TimingSource, Timings};
