//! Depth-only shadow map from the light centre (Williams 1978) over the
//! fitted frustum. Culling selects the map: none (first depth, every triangle
//! casts) or front faces (second-depth map, Wang and Molnar 1994; Cournia 5.5).

use wgpu::util::DeviceExt;

use crate::gpu::{layout, PassTimestamps};
use crate::light_frustum::LightFrustum;

pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Culling {
    /// Every triangle is in the map: the first surface seen from the light.
    None,
    /// Front faces culled: the second surface of closed casters.
    FrontFaces,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowUniforms {
    view_proj: [[f32; 4]; 4],
    view: [[f32; 4]; 4],
    depth: [f32; 4],
}

pub struct ShadowMapPass {
    first_depth: wgpu::RenderPipeline,
    second_depth: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl ShadowMapPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let layout = layout::bind_group_layout(device, "shadow_map::layout", &[layout::uniform(0)]);
        let module = crate::shaders::module(device, "shadow_map::shader", crate::shaders::shadow_map());
        let pipeline_layout = layout::pipeline_layout(device, "shadow_map::pipeline_layout", &layout);
        let position_only = [wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 }];
        let pipeline = |label: &str, cull_mode: Option<wgpu::Face>| {
            let buffers = [Some(super::corner_layout(&position_only))];
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &buffers,
                },
                primitive: wgpu::PrimitiveState { cull_mode, ..Default::default() },
                depth_stencil: layout::nearest_depth(FORMAT),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        Self {
            first_depth: pipeline("shadow_map::first_depth_pipeline", None),
            second_depth: pipeline("shadow_map::second_depth_pipeline", Some(wgpu::Face::Front)),
            layout,
        }
    }

    pub fn create_map(device: &wgpu::Device, map_size: u32) -> wgpu::Texture {
        layout::create_texture(
            device,
            "shadow_map::depth",
            (map_size, map_size),
            FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        )
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        map: &wgpu::Texture,
        frustum: &LightFrustum,
        culling: Culling,
        vertices: &wgpu::Buffer,
        vertex_count: u32,
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        self.record_writes(device, encoder, map, frustum, culling, vertices, vertex_count, timestamps.map(|t| t.render()));
    }

    /// [`Self::record`] with explicit timestamp writes (for parts of a named pass).
    #[allow(clippy::too_many_arguments)]
    pub fn record_writes(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        map: &wgpu::Texture,
        frustum: &LightFrustum,
        culling: Culling,
        vertices: &wgpu::Buffer,
        vertex_count: u32,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shadow_map::uniforms"),
            contents: bytemuck::bytes_of(&shadow_uniforms(frustum)),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = layout::bind_group(device, "shadow_map::bind_group", &self.layout, &[uniforms.as_entire_binding()]);
        let view = layout::view(map);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow_map::pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(match culling {
            Culling::None => &self.first_depth,
            Culling::FrontFaces => &self.second_depth,
        });
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.draw(0..vertex_count, 0..1);
    }
}

/// The light's view for passes that rasterise from it (shadow maps, volumes).
pub fn shadow_uniforms(frustum: &LightFrustum) -> ShadowUniforms {
    ShadowUniforms {
        view_proj: super::mat4(frustum.projection * frustum.view),
        view: super::mat4(frustum.view),
        depth: [frustum.near, frustum.far, 0.0, 0.0],
    }
}

/// Uniform layout of `LightSpace` in `shaders/light_space.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightSpaceUniform {
    pub view: [[f32; 4]; 4],
    pub window: [f32; 4],
    pub depth: [f32; 4],
}

impl LightSpaceUniform {
    pub fn new(frustum: &LightFrustum, map_size: u32) -> Self {
        Self {
            view: super::mat4(frustum.view),
            window: frustum.window.to_array(),
            depth: [frustum.near, frustum.far, map_size as f32, 0.0],
        }
    }
}
