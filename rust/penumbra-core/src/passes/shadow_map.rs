//! Depth-only shadow maps from a light point (Williams 1978), one layer per
//! face of its [`LightProjection`]: the fitted frustum, or the cube faces
//! that see geometry. [`MapDepth`] selects the surface stored: the first
//! (every triangle casts), the second (front faces culled: Wang and Molnar
//! 1994; Cournia 5.5) or the mid-point of the two (Woo 1992, which Cournia
//! 5.5 names as future work): both maps, then a full-screen pass averaging
//! them.

use std::sync::Arc;

use crate::frame::FrameContext;
use crate::gpu::{formats, layout, PassTimestamps};
use crate::gpu::pool::{Binding, Layout, PooledTexture, ResourcePool};
use crate::light_frustum::{LightFrustum, LightProjection};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapDepth {
    /// Every triangle is in the map: the first surface seen from the light.
    First,
    /// Front faces culled: the second surface of closed casters.
    Second,
    /// Half-way between the first and the second surface (where there is no
    /// second surface, half-way to the far plane).
    Midpoint,
}

crate::gpu_type! {
    pub struct ShadowUniforms => "ShadowUniforms" in "passes/light_view.wgsl" {
        pub(crate) view_proj: [[f32; 4]; 4],
        pub(crate) view: [[f32; 4]; 4],
        pub(crate) depth: [f32; 4],
    }
}

pub struct ShadowMapPass {
    first_depth: wgpu::RenderPipeline,
    second_depth: wgpu::RenderPipeline,
    layout: Layout,
    midpoint: wgpu::RenderPipeline,
    midpoint_layout: Layout,
}

impl ShadowMapPass {
    /// The pool's one shadow-map pass (its pipelines built on first use),
    /// which every method that renders depth maps from a light point records.
    pub fn shared(device: &wgpu::Device, pool: &ResourcePool) -> Arc<Self> {
        pool.shared(|| Self::new(device, pool))
    }

    pub fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let layout = pool.layout(device, "shadow_map::layout", &[layout::uniform(0)]);
        let module = crate::shaders::module(device, "shadow_map::shader", crate::shader!("shadow_map.wgsl"));
        let position_only = [wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 }];
        let positions = [Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode: wgpu::VertexStepMode::Vertex, attributes: &position_only })];
        let pipeline = |label: &str, cull_mode: Option<wgpu::Face>| {
            let primitive = wgpu::PrimitiveState { cull_mode, ..Default::default() };
            layout::render_pipeline(device, label, &layout, &module, ("vs_main", "fs_main"), &positions, primitive, layout::nearest_depth(formats::DEPTH), &[])
        };
        let midpoint_layout = pool.layout(
            device,
            "shadow_map::midpoint_layout",
            &[layout::depth_texture(0), layout::depth_texture(1)],
        );
        let always = Some(wgpu::DepthStencilState {
            format: formats::DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        });
        let midpoint = layout::render_pipeline(
            device,
            "shadow_map::midpoint_pipeline",
            &midpoint_layout,
            &module,
            ("vs_fullscreen", "fs_midpoint"),
            &[],
            Default::default(),
            always,
            &[],
        );
        Self {
            first_depth: pipeline("shadow_map::first_depth_pipeline", None),
            second_depth: pipeline("shadow_map::second_depth_pipeline", Some(wgpu::Face::Front)),
            layout,
            midpoint,
            midpoint_layout,
        }
    }

    /// A `map_size` depth map of `layers` layers (one per projection face) from the frame's pool.
    pub fn create_map(ctx: &FrameContext<'_>, map_size: u32, layers: u32) -> PooledTexture {
        ctx.light_texture(
            "shadow_map::depth",
            map_size,
            layers,
            formats::DEPTH,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
        )
    }

    /// Renders the scene's depth into each layer of `map` whose projection
    /// face sees geometry, as part of a named pass that may be made of
    /// several wgpu passes: `(first, last)` say whether these maps open or
    /// close it (`(true, true)`: the whole pass).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        map: &PooledTexture,
        projection: &LightProjection,
        depth: MapDepth,
        timestamps: Option<PassTimestamps<'_>>,
        (first, last): (bool, bool),
    ) {
        let faces: Vec<(u32, &LightFrustum)> = projection.active_layers().collect();
        for (k, (layer, frustum)) in faces.iter().enumerate() {
            let (first, last) = (first && k == 0, last && k + 1 == faces.len());
            self.record_face(ctx, encoder, map, projection, *layer, frustum, depth, timestamps, (first, last));
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn record_face(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        map: &PooledTexture,
        projection: &LightProjection,
        layer: u32,
        frustum: &LightFrustum,
        depth: MapDepth,
        timestamps: Option<PassTimestamps<'_>>,
        (first, last): (bool, bool),
    ) {
        let uniforms = uniform_buffer(ctx, "shadow_map::uniforms", &shadow_uniforms(frustum));
        let bind_group = ctx.pool.bind_group(ctx.device, "shadow_map::bind_group", &self.layout, &[Binding::Buffer(&uniforms)]);
        let (positions, indices, range) = ctx.light_geometry_for(projection, layer);
        let side = map.width();
        let draw = |encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView, pipeline, writes| {
            let mut pass = begin_depth_pass(encoder, target, writes);
            keep_border_empty(&mut pass, projection, side);
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.set_vertex_buffer(0, positions.slice(..));
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(range.clone(), 0, 0..1);
        };
        let part = |first: bool, last: bool| timestamps.and_then(|t| t.render_part(first, last));
        let target = &map.layer_views[layer as usize];
        match depth {
            MapDepth::First => draw(encoder, target, &self.first_depth, part(first, last)),
            MapDepth::Second => draw(encoder, target, &self.second_depth, part(first, last)),
            MapDepth::Midpoint => {
                let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
                let size = (map.width(), map.height());
                let near = ctx.texture("shadow_map::first_depth", size, formats::DEPTH, usage);
                let far = ctx.texture("shadow_map::second_depth", size, formats::DEPTH, usage);
                draw(encoder, &near.view, &self.first_depth, part(first, false));
                draw(encoder, &far.view, &self.second_depth, None);
                let bind_group = ctx.pool.bind_group(
                    ctx.device,
                    "shadow_map::midpoint_bind_group",
                    &self.midpoint_layout,
                    &[Binding::Texture(&near), Binding::Texture(&far)],
                );
                let mut pass = begin_depth_pass(encoder, target, part(false, last));
                keep_border_empty(&mut pass, projection, side);
                pass.set_pipeline(&self.midpoint);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.draw(0..3, 0..1);
            }
        }
    }
}

/// A frustum's map keeps its outermost ring of texels clear: the frustum is
/// fitted around what may shadow something (`LightProjection::fit`), so a
/// point projecting outside its window is lit, and reads there clamp to
/// that ring. The 1% pad of the fit leaves the ring empty anyway from 100
/// texels up; the scissor also holds on smaller maps and for volumes that
/// reach past the window. Cube faces keep every texel: their reads cross
/// seams into the neighbouring face (`map_wrap`).
pub fn keep_border_empty(pass: &mut wgpu::RenderPass<'_>, projection: &LightProjection, size: u32) {
    if !projection.is_cube() && size > 2 {
        pass.set_scissor_rect(1, 1, size - 2, size - 2);
    }
}

fn begin_depth_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("shadow_map::pass"),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// A pooled uniform buffer holding `value` (for raster passes, whose
/// shaders do not branch on it: see `layout::parameters`).
pub fn uniform_buffer<T: bytemuck::Pod>(ctx: &FrameContext<'_>, label: &str, value: &T) -> crate::gpu::pool::PooledBuffer {
    let bytes = bytemuck::bytes_of(value);
    let buffer = ctx.buffer(label, bytes.len() as u64, wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST);
    ctx.queue.write_buffer(&buffer, 0, bytes);
    buffer
}

/// The light's view for passes that rasterise from it (shadow maps, volumes).
pub fn shadow_uniforms(frustum: &LightFrustum) -> ShadowUniforms {
    ShadowUniforms {
        view_proj: super::mat4(frustum.projection * frustum.view),
        view: super::mat4(frustum.view),
        depth: [frustum.near, frustum.far, 0.0, 0.0],
    }
}

crate::gpu_type! {
    /// Uniform layout of `LightSpace` in `shaders/light_space.wgsl`.
    pub struct LightSpaceUniform => "LightSpace" in "shaders/light_space.wgsl" {
        pub view: [[f32; 4]; 4],
        pub window: [f32; 4],
        pub depth: [f32; 4],
        pub faces: [u32; 4],
    }
}

impl LightSpaceUniform {
    /// The shaders' view of `projection` for maps of `map_size` texels: a
    /// frustum's view and window; for cube faces, the translation to the
    /// light point (the shader rotates into each face) and the unit window.
    pub fn new(projection: &LightProjection, map_size: u32) -> Self {
        let face = &projection.faces[0];
        let (view, layers, nearest) = if projection.is_cube() {
            (glam::Mat4::from_translation(-projection.origin), 6.0, projection.nearest.to_bits())
        } else {
            (face.view, 1.0, 0)
        };
        Self {
            view: super::mat4(view),
            window: face.window.to_array(),
            depth: [face.near, face.far, map_size as f32, layers],
            faces: [projection.active, nearest, 0, 0],
        }
    }
}
