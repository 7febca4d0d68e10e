//! The shading of SPEC section 3, shared by every method: reads the G-buffer
//! and a method's visibility image, writes linear radiance.

use crate::frame::FrameContext;
use crate::gpu::{formats, layout, PassTimestamps};
use crate::gpu::pool::{Binding, PooledTexture, ResourcePool};
use crate::passes::screen::{LayoutEntry, ScreenPass};


crate::gpu_type! {
    pub struct ShadingUniforms => "ShadingUniforms" in "passes/shading.wgsl" {
        pub(crate) light: [f32; 4],
        pub(crate) intensity: [f32; 4],
        pub(crate) ambient: [f32; 4],
        pub(crate) eye: [f32; 4],
    }
}

pub struct ShadingPass {
    pass: ScreenPass,
}

impl ShadingPass {
    pub fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let radiance: LayoutEntry = |b| layout::storage_texture(b, formats::RADIANCE);
        let bindings = [layout::float_texture, layout::storage_buffer, layout::parameters, radiance];
        Self { pass: ScreenPass::per_pixel(device, pool, "shading::pass", crate::shader!("shading.wgsl"), &bindings) }
    }

    /// Radiance of the frame's pixels from the G-buffer and `visibility`.
    pub fn record(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        visibility: &PooledTexture,
        radiance: &PooledTexture,
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let materials: Vec<[f32; 4]> = ctx
            .prepared
            .materials
            .iter()
            .map(|(albedo, _)| [albedo[0], albedo[1], albedo[2], 0.0])
            .collect();
        let bytes: &[u8] = bytemuck::cast_slice(&materials);
        let materials = ctx.buffer("shading::materials", (bytes.len() as u64).max(16), wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
        ctx.queue.write_buffer(&materials, 0, bytes);
        let (l, scene, eye) = (&ctx.scene.light, ctx.scene, ctx.camera.eye);
        let uniforms = ctx.parameters(
            "shading::uniforms",
            &ShadingUniforms {
                light: [l.center[0], l.center[1], l.center[2], l.radius],
                intensity: [l.intensity[0], l.intensity[1], l.intensity[2], 0.0],
                ambient: [scene.ambient[0], scene.ambient[1], scene.ambient[2], 0.0],
                eye: [eye[0], eye[1], eye[2], 0.0],
            },
        );
        self.pass.run(
            ctx,
            encoder,
            &[Binding::Texture(visibility), Binding::Buffer(&materials), Binding::Buffer(&uniforms), Binding::Texture(radiance)],
            timestamps,
        );
    }
}
