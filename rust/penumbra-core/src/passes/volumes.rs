//! The raster pass of light-space volumes shared by PVM's penumbra volume map
//! (Cournia 4.1.2) and PVMF's penumbra volume mask (5.1): quadrilaterals seen
//! from the light, both sides drawn, the nearest kept in a depth map with
//! method-specific colour targets beside it.

use crate::error::{Error, Result};
use crate::frame::FrameContext;
use crate::gpu::formats;
use crate::gpu::{layout, PassTimestamps};
use crate::gpu::pool::{Binding, Layout, PooledTexture, ResourcePool};
use crate::light_frustum::{LightFrustum, LightProjection};
use crate::passes::shadow_map::{shadow_uniforms, uniform_buffer, ShadowMapPass};

pub struct VolumePass {
    name: &'static str,
    pipeline: wgpu::RenderPipeline,
    layout: Layout,
    /// What the pass keeps per texel.
    keep: Keep,
}

/// What a [`VolumePass`] keeps per texel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Keep {
    /// The volume nearest the light, in a depth map.
    Nearest,
    /// The volume farthest from the light, in a depth map (cleared to 0 and
    /// tested `Greater`).
    Farthest,
    /// Without a depth map: every volume's fragments reach the colour
    /// targets, which keep the largest value each texel receives (blend
    /// `Max`; the targets' formats must be blendable, and they are cleared
    /// to zero). [`VolumePass::record_uploaded`] records it.
    Max,
}

impl VolumePass {
    /// A pass that keeps `keep` per texel. `name` labels the pass
    /// (`pvm::volume`); `source` holds the vertex and fragment entry points
    /// `(vs, fs)`, which read the light's `ShadowUniforms` at binding 0; each
    /// vertex is a `V` with `attributes`; one colour target per format.
    #[allow(clippy::too_many_arguments)]
    pub fn new<V>(
        keep: Keep,
        device: &wgpu::Device,
        pool: &ResourcePool,
        name: &'static str,
        source: String,
        entry_points: (&str, &str),
        attributes: &[wgpu::VertexAttribute],
        targets: &[wgpu::TextureFormat],
    ) -> Self {
        let max = wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Max };
        let blend = (keep == Keep::Max).then_some(wgpu::BlendState { color: max, alpha: max });
        let targets: Vec<_> = targets.iter().map(|&format| Some(wgpu::ColorTargetState { format, blend, write_mask: wgpu::ColorWrites::ALL })).collect();
        Self::build::<V>(device, pool, name, source, entry_points, attributes, &targets, keep)
    }

    #[allow(clippy::too_many_arguments)]
    fn build<V>(
        device: &wgpu::Device,
        pool: &ResourcePool,
        name: &'static str,
        source: String,
        (vs, fs): (&str, &str),
        attributes: &[wgpu::VertexAttribute],
        targets: &[Option<wgpu::ColorTargetState>],
        keep: Keep,
    ) -> Self {
        let layout = pool.layout(device, name, &[layout::uniform(0)]);
        let module = crate::shaders::module(device, name, source);
        let buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<V>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes,
        })];
        // Both sides of every quadrilateral: the volume nearest the light (or
        // every volume, without depth), whichever way it faces.
        let primitive = wgpu::PrimitiveState { cull_mode: None, ..Default::default() };
        let depth_stencil = match keep {
            Keep::Nearest => layout::nearest_depth(formats::DEPTH),
            Keep::Farthest => layout::farthest_depth(formats::DEPTH),
            Keep::Max => None,
        };
        let pipeline = layout::render_pipeline(device, name, &layout, &module, (vs, fs), &buffers, primitive, depth_stencil, targets);
        Self { name, pipeline, layout, keep }
    }

    /// Records the pass into a new `map_size` depth map with a layer per
    /// face of `projection`, which it returns; each active face's layer of
    /// the colour `targets` (array textures of as many layers) is cleared to
    /// zero first and drawn into. Draws nothing for no vertices.
    #[allow(clippy::too_many_arguments)]
    pub fn record<V: bytemuck::Pod>(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        projection: &LightProjection,
        vertices: &[V],
        map_size: u32,
        targets: &[&PooledTexture],
        timestamps: Option<PassTimestamps<'_>>,
    ) -> Result<PooledTexture> {
        let vertices = self.upload(ctx, vertices)?;
        let depth = self.record_uploaded(ctx, encoder, projection, &vertices, map_size, targets, timestamps);
        Ok(depth.expect("a depth pass (Keep::Nearest or Farthest) returns its depth map"))
    }

    /// As [`Self::record`], for vertices already on the GPU ([`Self::upload`];
    /// another pass's, with the same vertex layout, will do): the depth map
    /// of a depth pass, or `None` for a [`Keep::Max`] pass, which
    /// draws into its colour `targets` alone.
    #[allow(clippy::too_many_arguments)]
    pub fn record_uploaded(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        projection: &LightProjection,
        vertices: &VolumeVertices,
        map_size: u32,
        targets: &[&PooledTexture],
        timestamps: Option<PassTimestamps<'_>>,
    ) -> Option<PooledTexture> {
        self.record_draws(ctx, encoder, projection, map_size, targets, timestamps, |pass| vertices.draw(pass))
    }

    /// The vertex buffer of `vertices`, for [`Self::record_uploaded`].
    pub fn upload<V: bytemuck::Pod>(&self, ctx: &FrameContext<'_>, vertices: &[V]) -> Result<VolumeVertices> {
        let count = u32::try_from(vertices.len()).map_err(|_| {
            Error::InvalidScene(format!("too many penumbra volumes for one draw: {} vertices, at most {}", vertices.len(), u32::MAX))
        })?;
        let buffer = (count > 0).then(|| {
            let bytes: &[u8] = bytemuck::cast_slice(vertices);
            let buffer = ctx.buffer(self.name, bytes.len() as u64, wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST);
            ctx.queue.write_buffer(&buffer, 0, bytes);
            buffer
        });
        Ok(VolumeVertices { buffer, count })
    }

    /// As [`Self::record`], for a pipeline whose vertices are the light
    /// geometry's positions ([`FrameContext::light_geometry`]): draws each
    /// mesh's triangles as instance `ids[mesh]` (the shader's
    /// `instance_index`), `None` skipping the mesh.
    pub fn record_meshes(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        projection: &LightProjection,
        ids: &[Option<u32>],
        map_size: u32,
        targets: &[&PooledTexture],
        timestamps: Option<PassTimestamps<'_>>,
    ) -> PooledTexture {
        let (positions, indices, _) = ctx.light_geometry();
        let ranges = ctx.light_geometry_meshes();
        let depth = self.record_draws(ctx, encoder, projection, map_size, targets, timestamps, |pass| {
            pass.set_vertex_buffer(0, positions.slice(..));
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            for (range, id) in ranges.iter().zip(ids) {
                // An id of u32::MAX has no instance range: no mesh has it (ids count objects).
                if let Some((id, end)) = id.filter(|_| !range.is_empty()).and_then(|id| Some((id, id.checked_add(1)?))) {
                    pass.draw_indexed(range.clone(), 0, id..end);
                }
            }
        });
        depth.expect("a depth pass (Keep::Nearest or Farthest) returns its depth map")
    }

    #[allow(clippy::too_many_arguments)]
    fn record_draws(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        projection: &LightProjection,
        map_size: u32,
        targets: &[&PooledTexture],
        timestamps: Option<PassTimestamps<'_>>,
        draw: impl Fn(&mut wgpu::RenderPass<'_>),
    ) -> Option<PooledTexture> {
        let depth = (self.keep != Keep::Max).then(|| ShadowMapPass::create_map(ctx, map_size, projection.layers()));
        let cleared_depth = if self.keep == Keep::Farthest { 0.0 } else { 1.0 };
        let faces: Vec<(u32, &LightFrustum)> = projection.active_layers().collect();
        for (k, (layer, frustum)) in faces.iter().enumerate() {
            let layer = *layer as usize;
            let uniforms = uniform_buffer(ctx, self.name, &shadow_uniforms(frustum));
            let bind_group = ctx.pool.bind_group(ctx.device, self.name, &self.layout, &[Binding::Buffer(&uniforms)]);
            let clear = wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT), store: wgpu::StoreOp::Store };
            let attachments: Vec<_> = targets
                .iter()
                .map(|t| {
                    Some(wgpu::RenderPassColorAttachment { view: &t.layer_views[layer], depth_slice: None, resolve_target: None, ops: clear })
                })
                .collect();
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(self.name),
                color_attachments: &attachments,
                depth_stencil_attachment: depth.as_ref().map(|depth| wgpu::RenderPassDepthStencilAttachment {
                    view: &depth.layer_views[layer],
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(cleared_depth), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: timestamps.and_then(|t| t.render_part(k == 0, k + 1 == faces.len())),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            super::shadow_map::keep_border_empty(&mut pass, projection, map_size);
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            draw(&mut pass);
        }
        depth
    }
}

/// Volume vertices on the GPU ([`VolumePass::upload`]); none for an empty list.
pub struct VolumeVertices {
    buffer: Option<crate::gpu::pool::PooledBuffer>,
    count: u32,
}

impl VolumeVertices {
    fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        if let Some(buffer) = &self.buffer {
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..self.count, 0..1);
        }
    }
}
