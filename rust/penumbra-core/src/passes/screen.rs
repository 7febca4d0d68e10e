//! Screen passes: compute passes run once per camera pixel over the
//! G-buffer. Every one binds the G-buffer's position and normal images at
//! bindings 0 and 1 (declared once, in `shaders/receiver.wgsl`) and its own
//! resources after them, in order; bind groups come from the resource pool,
//! so a render that binds the same resources as an earlier one makes none.
//! A pass that works pixel by pixel imports `shaders/per_pixel.wgsl`, whose
//! `main` runs the pass's `shade` for each pixel inside the image.

use crate::frame::FrameContext;
use crate::gpu::layout;
use crate::gpu::pool::{Binding, Layout};

/// A layout entry builder for the binding number it is given.
pub type LayoutEntry = fn(u32) -> wgpu::BindGroupLayoutEntry;

/// A compute pipeline (one or more entry points of one shader) over the
/// G-buffer and the pass's own bindings.
pub struct ScreenPass {
    label: &'static str,
    layout: Layout,
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
}

impl ScreenPass {
    /// `entries` are the pass's own bindings, numbered from 2; `entry_points`
    /// the shader's compute entry points the pass runs.
    pub fn new(
        device: &wgpu::Device,
        pool: &crate::gpu::pool::ResourcePool,
        label: &'static str,
        source: String,
        entries: &[LayoutEntry],
        entry_points: &[&'static str],
    ) -> Self {
        let all: Vec<wgpu::BindGroupLayoutEntry> = [layout::float_texture as LayoutEntry, layout::float_texture]
            .iter()
            .chain(entries)
            .enumerate()
            .map(|(i, entry)| entry(i as u32))
            .collect();
        let layout = pool.layout(device, label, &all);
        let module = crate::shaders::module(device, label, source);
        let pipelines = entry_points
            .iter()
            .map(|&entry| (entry, layout::compute_pipeline_entry(device, label, &module, &layout, entry)))
            .collect();
        Self { label, layout, pipelines }
    }

    /// A pass whose one entry point is `main` (that of
    /// `shaders/per_pixel.wgsl`, or the pass's own).
    pub fn per_pixel(device: &wgpu::Device, pool: &crate::gpu::pool::ResourcePool, label: &'static str, source: String, entries: &[LayoutEntry]) -> Self {
        Self::new(device, pool, label, source, entries, &["main"])
    }

    /// The bind group of the frame's G-buffer and `resources`.
    pub fn bind_group(&self, ctx: &FrameContext<'_>, resources: &[Binding<'_>]) -> wgpu::BindGroup {
        let g = &ctx.gbuffer;
        let mut all = Vec::with_capacity(resources.len() + 2);
        all.push(Binding::Texture(&g.position));
        all.push(Binding::Texture(&g.normal));
        all.extend(resources.iter().map(Binding::reborrow));
        ctx.pool.bind_group(ctx.device, self.label, &self.layout, &all)
    }

    /// Runs entry point `entry` once per pixel of the frame's image.
    pub fn dispatch(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        entry: &str,
        bind_group: &wgpu::BindGroup,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        self.dispatch_size(encoder, entry, bind_group, ctx.size, timestamps);
    }

    /// Runs entry point `entry` once per texel of a `size` image (a pass at
    /// another resolution than the camera's, which maps texels to pixels itself).
    pub fn dispatch_size(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        entry: &str,
        bind_group: &wgpu::BindGroup,
        size: (u32, u32),
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let pipeline = &self.pipelines.iter().find(|(e, _)| *e == entry).unwrap_or_else(|| panic!("{}: no entry point {entry}", self.label)).1;
        layout::dispatch_per_pixel_writes(encoder, self.label, pipeline, bind_group, size, timestamps);
    }

    /// Runs entry point `entry` over `count` workgroups (x, y, z): a pass
    /// whose workgroups are not the per-pixel 8 x 8 (a tile each, say).
    pub fn dispatch_workgroups(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        entry: &str,
        bind_group: &wgpu::BindGroup,
        count: (u32, u32, u32),
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let pipeline = &self.pipelines.iter().find(|(e, _)| *e == entry).unwrap_or_else(|| panic!("{}: no entry point {entry}", self.label)).1;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(self.label), timestamp_writes });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups(count.0, count.1, count.2);
    }

    /// Runs entry point `entry` over the workgroup counts (x, y, z) that an
    /// earlier pass wrote into `indirect` at `offset`: a pass over a list of
    /// pixels rather than the whole image.
    pub fn dispatch_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        entry: &str,
        bind_group: &wgpu::BindGroup,
        indirect: &wgpu::Buffer,
        offset: u64,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let pipeline = &self.pipelines.iter().find(|(e, _)| *e == entry).unwrap_or_else(|| panic!("{}: no entry point {entry}", self.label)).1;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(self.label), timestamp_writes });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups_indirect(indirect, offset);
    }

    /// Binds `resources` and runs the first entry point: the whole of a
    /// one-dispatch pass.
    pub fn run(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        resources: &[Binding<'_>],
        timestamps: Option<crate::gpu::PassTimestamps<'_>>,
    ) {
        let bind_group = self.bind_group(ctx, resources);
        self.dispatch(ctx, encoder, self.pipelines[0].0, &bind_group, timestamps.map(|t| t.compute()));
    }
}
