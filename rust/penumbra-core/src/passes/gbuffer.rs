//! The camera G-buffer (SPEC section 3): world position with view depth, and
//! shading normal with mesh index, in two float32 targets.

use wgpu::util::DeviceExt;

use crate::gpu::layout;
use crate::gpu::PassTimestamps;

pub const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CameraUniforms {
    view_proj: [[f32; 4]; 4],
    view: [[f32; 4]; 4],
}

pub struct GBufferPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// The G-buffer of one frame.
pub struct GBuffer {
    pub position: wgpu::Texture,
    pub normal: wgpu::Texture,
    pub position_view: wgpu::TextureView,
    pub normal_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    pub size: (u32, u32),
}

impl GBuffer {
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let position = layout::create_texture(device, "gbuffer::position", size, POSITION_FORMAT, usage);
        let normal = layout::create_texture(device, "gbuffer::normal", size, NORMAL_FORMAT, usage);
        let depth = layout::create_texture(
            device,
            "gbuffer::depth",
            size,
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        Self {
            position_view: layout::view(&position),
            normal_view: layout::view(&normal),
            depth_view: layout::view(&depth),
            position,
            normal,
            size,
        }
    }
}

impl GBufferPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let layout = layout::bind_group_layout(device, "gbuffer::layout", &[layout::uniform(0)]);
        let module = crate::shaders::module(device, "gbuffer::shader", crate::shaders::gbuffer());
        let buffers = [Some(super::corner_layout(&super::CORNER_ATTRIBUTES))];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("gbuffer::pipeline"),
            layout: Some(&layout::pipeline_layout(device, "gbuffer::pipeline_layout", &layout)),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &buffers,
            },
            primitive: wgpu::PrimitiveState {
                // Back faces are drawn too: they are shaded dark (one-sided surfaces).
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: layout::nearest_depth(DEPTH_FORMAT),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(POSITION_FORMAT.into()), Some(NORMAL_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self { pipeline, layout }
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        target: &GBuffer,
        vertices: &wgpu::Buffer,
        vertex_count: u32,
        view: glam::Mat4,
        projection: glam::Mat4,
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("gbuffer::uniforms"),
            contents: bytemuck::bytes_of(&CameraUniforms {
                view_proj: super::mat4(projection * view),
                view: super::mat4(view),
            }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = layout::bind_group(
            device,
            "gbuffer::bind_group",
            &self.layout,
            &[uniforms.as_entire_binding()],
        );
        let clear = |c: wgpu::Color| wgpu::Operations { load: wgpu::LoadOp::Clear(c), store: wgpu::StoreOp::Store };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer::pass"),
            color_attachments: &[
                Some(wgpu::RenderPassColorAttachment {
                    view: &target.position_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear(wgpu::Color::TRANSPARENT),
                }),
                Some(wgpu::RenderPassColorAttachment {
                    view: &target.normal_view,
                    depth_slice: None,
                    resolve_target: None,
                    // w = -1 marks the background (common.wgsl).
                    ops: clear(wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: -1.0 }),
                }),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &target.depth_view,
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
        pass.draw(0..vertex_count, 0..1);
    }
}
