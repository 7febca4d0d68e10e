//! The shading of SPEC section 3, shared by every method: reads the G-buffer
//! and a method's visibility image, writes linear radiance; and the object
//! id image (`passes/object_ids.wgsl`), which the shading pass writes beside
//! the radiance and [`ObjectIdPass`] alone where no radiance is asked for.

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

/// The object id image's format: one `i32` per pixel.
pub const OBJECT_ID: wgpu::TextureFormat = wgpu::TextureFormat::R32Sint;

const OBJECT_ID_BINDINGS: [LayoutEntry; 2] = [layout::storage_buffer, |b| layout::storage_texture(b, OBJECT_ID)];

/// The per-mesh object ids `passes/object_ids.wgsl` reads, uploaded for the frame.
fn mesh_objects(ctx: &FrameContext<'_>) -> crate::gpu::pool::PooledBuffer {
    let ids: Vec<i32> = ctx.prepared.materials.iter().map(|(_, id)| *id).collect();
    let bytes: &[u8] = bytemuck::cast_slice(&ids);
    let buffer = ctx.buffer("shading::mesh_objects", (bytes.len() as u64).max(4), wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
    ctx.queue.write_buffer(&buffer, 0, bytes);
    buffer
}

/// A frame-sized object id image (`OBJECT_ID`) from the pool.
pub fn object_id_texture(ctx: &FrameContext<'_>) -> PooledTexture {
    ctx.texture("shading::object_ids", ctx.size, OBJECT_ID, wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC)
}

impl ShadingPass {
    pub fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let radiance: LayoutEntry = |b| layout::storage_texture(b, formats::RADIANCE);
        let bindings = [OBJECT_ID_BINDINGS[0], OBJECT_ID_BINDINGS[1], layout::float_texture, layout::storage_buffer, layout::parameters, radiance];
        Self { pass: ScreenPass::per_pixel(device, pool, "shading::pass", crate::shader!("shading.wgsl"), &bindings) }
    }

    /// Radiance of the frame's pixels from the G-buffer and `visibility`,
    /// and their object ids into `object_ids`.
    pub fn record(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        visibility: &PooledTexture,
        (radiance, object_ids): (&PooledTexture, &PooledTexture),
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
        let objects = mesh_objects(ctx);
        self.pass.run(
            ctx,
            encoder,
            &[
                Binding::Buffer(&objects),
                Binding::Texture(object_ids),
                Binding::Texture(visibility),
                Binding::Buffer(&materials),
                Binding::Buffer(&uniforms),
                Binding::Texture(radiance),
            ],
            timestamps,
        );
    }
}

/// The object id image alone (`passes/object_id_pass.wgsl`), for a render
/// that asks for object ids but neither radiance nor normals.
pub struct ObjectIdPass {
    pass: ScreenPass,
}

impl ObjectIdPass {
    pub fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        Self { pass: ScreenPass::per_pixel(device, pool, "object_ids::pass", crate::shader!("object_id_pass.wgsl"), &OBJECT_ID_BINDINGS) }
    }

    pub fn record(&self, ctx: &FrameContext<'_>, encoder: &mut wgpu::CommandEncoder, object_ids: &PooledTexture, timestamps: Option<PassTimestamps<'_>>) {
        let objects = mesh_objects(ctx);
        self.pass.run(ctx, encoder, &[Binding::Buffer(&objects), Binding::Texture(object_ids)], timestamps);
    }
}
