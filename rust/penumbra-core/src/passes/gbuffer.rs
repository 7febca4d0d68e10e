//! The camera G-buffer (SPEC section 3): world position with view depth, and
//! shading normal with mesh index, in two float32 targets.

use crate::frame::FrameContext;
use crate::gpu::{formats, layout};
use crate::gpu::PassTimestamps;
use crate::gpu::pool::{Binding, Layout, ResourcePool};
use crate::pass_cache::CachedPass;

/// The G-buffer as the pass cache keeps it: two cameras (or image sizes) alternating.
pub const GBUFFER: CachedPass = CachedPass { name: "gbuffer", capacity: 2 };

crate::gpu_type! {
    pub struct CameraUniforms => "CameraUniforms" in "passes/gbuffer.wgsl" {
        pub(crate) view_proj: [[f32; 4]; 4],
        pub(crate) view: [[f32; 4]; 4],
    }
}

pub struct GBufferPass {
    pipeline: wgpu::RenderPipeline,
    layout: Layout,
}

impl GBufferPass {
    pub fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let layout = pool.layout(device, "gbuffer::layout", &[layout::uniform(0)]);
        let module = crate::shaders::module(device, "gbuffer::shader", crate::shader!("gbuffer.wgsl"));
        let buffers = [Some(super::corner_layout(&super::CORNER_ATTRIBUTES))];
        // Back faces are drawn too: they are shaded dark (one-sided surfaces).
        let primitive = wgpu::PrimitiveState { cull_mode: None, ..Default::default() };
        let targets = [Some(formats::POSITION.into()), Some(formats::NORMAL.into())];
        let pipeline = layout::render_pipeline(
            device,
            "gbuffer::pipeline",
            &layout,
            &module,
            ("vs_main", "fs_main"),
            &buffers,
            primitive,
            layout::nearest_depth(formats::DEPTH),
            &targets,
        );
        Self { pipeline, layout }
    }

    /// Draws the scene from the camera into the frame's G-buffer.
    pub fn record(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        view: glam::Mat4,
        projection: glam::Mat4,
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let target = &ctx.gbuffer;
        let uniforms = super::shadow_map::uniform_buffer(
            ctx,
            "gbuffer::uniforms",
            &CameraUniforms { view_proj: super::mat4(projection * view), view: super::mat4(view) },
        );
        let bind_group = ctx.pool.bind_group(ctx.device, "gbuffer::bind_group", &self.layout, &[Binding::Buffer(&uniforms)]);
        let (vertices, indices, count) = ctx.surface();
        let clear = |c: wgpu::Color| wgpu::Operations { load: wgpu::LoadOp::Clear(c), store: wgpu::StoreOp::Store };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer::pass"),
            color_attachments: &[
                Some(wgpu::RenderPassColorAttachment {
                    view: &target.position.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear(wgpu::Color::TRANSPARENT),
                }),
                Some(wgpu::RenderPassColorAttachment {
                    view: &target.normal.view,
                    depth_slice: None,
                    resolve_target: None,
                    // w = -1 marks the background (common.wgsl).
                    ops: clear(wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: -1.0 }),
                }),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &target.depth.view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps.map(|t| t.render()),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..count, 0, 0..1);
    }
}
