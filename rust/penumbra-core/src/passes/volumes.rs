//! The raster pass of light-space volumes shared by PVM's penumbra volume map
//! (Cournia 4.1.2) and PVMF's penumbra volume mask (5.1): quadrilaterals seen
//! from the light, both sides drawn, the nearest kept in a depth map with
//! method-specific colour targets beside it.

use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::gpu::{layout, PassTimestamps};
use crate::light_frustum::LightFrustum;
use crate::passes::shadow_map::{shadow_uniforms, ShadowMapPass, FORMAT};

pub struct VolumePass {
    name: &'static str,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl VolumePass {
    /// `name` labels the pass (`pvm::volume`); `source` holds the vertex and
    /// fragment entry points `(vs, fs)`, which read the light's
    /// `ShadowUniforms` at binding 0; each vertex is a `V` with `attributes`;
    /// one colour target per format.
    pub fn new<V>(
        device: &wgpu::Device,
        name: &'static str,
        source: String,
        (vs, fs): (&str, &str),
        attributes: &[wgpu::VertexAttribute],
        targets: &[wgpu::TextureFormat],
    ) -> Self {
        let layout = layout::bind_group_layout(device, name, &[layout::uniform(0)]);
        let module = crate::shaders::module(device, name, source);
        let buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<V>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes,
        })];
        let targets: Vec<_> = targets.iter().map(|&f| Some(f.into())).collect();
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(name),
            layout: Some(&layout::pipeline_layout(device, name, &layout)),
            vertex: wgpu::VertexState { module: &module, entry_point: Some(vs), compilation_options: Default::default(), buffers: &buffers },
            // Both sides of every quadrilateral: the volume nearest the light, whichever way it faces.
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: layout::nearest_depth(FORMAT),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState { module: &module, entry_point: Some(fs), compilation_options: Default::default(), targets: &targets }),
            multiview_mask: None,
            cache: None,
        });
        Self { name, pipeline, layout }
    }

    /// Records the pass into a new `map_size` depth map, which it returns;
    /// the colour `targets` are cleared to zero first. `frustum` is the
    /// light's; draws nothing for no vertices.
    #[allow(clippy::too_many_arguments)]
    pub fn record<V: bytemuck::Pod>(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        frustum: &LightFrustum,
        vertices: &[V],
        map_size: u32,
        targets: &[&wgpu::Texture],
        timestamps: Option<PassTimestamps<'_>>,
    ) -> Result<wgpu::Texture> {
        let count = u32::try_from(vertices.len()).map_err(|_| {
            Error::InvalidScene(format!("too many penumbra volumes for one draw: {} vertices, at most {}", vertices.len(), u32::MAX))
        })?;
        let depth = ShadowMapPass::create_map(device, map_size);
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(self.name),
            contents: bytemuck::bytes_of(&shadow_uniforms(frustum)),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = layout::bind_group(device, self.name, &self.layout, &[uniforms.as_entire_binding()]);
        let buffer = (count > 0).then(|| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(self.name),
                contents: bytemuck::cast_slice(vertices),
                usage: wgpu::BufferUsages::VERTEX,
            })
        });
        let depth_view = layout::view(&depth);
        let views: Vec<_> = targets.iter().map(|t| layout::view(t)).collect();
        let clear = wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT), store: wgpu::StoreOp::Store };
        let attachments: Vec<_> = views
            .iter()
            .map(|view| Some(wgpu::RenderPassColorAttachment { view, depth_slice: None, resolve_target: None, ops: clear }))
            .collect();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.name),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps.map(|t| t.render()),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if let Some(buffer) = &buffer {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..count, 0..1);
        }
        drop(pass);
        Ok(depth)
    }
}
