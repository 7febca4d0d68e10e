//! The shading of SPEC section 3, shared by every method: reads the G-buffer
//! and a method's visibility image, writes linear radiance.

use wgpu::util::DeviceExt;

use crate::gpu::{layout, PassTimestamps};
use crate::passes::gbuffer::GBuffer;
use crate::scene::{PreparedScene, Scene};

pub const VISIBILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
pub const RADIANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadingUniforms {
    light: [f32; 4],
    intensity: [f32; 4],
    ambient: [f32; 4],
    eye: [f32; 4],
}

pub struct ShadingPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl ShadingPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let layout = layout::bind_group_layout(
            device,
            "shading::layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::float_texture(2),
                layout::storage_buffer(3),
                layout::parameters(4),
                layout::storage_texture(5, RADIANCE_FORMAT),
            ],
        );
        let pipeline = layout::compute_pipeline(device, "shading::pipeline", crate::shaders::shading(), &layout);
        Self { pipeline, layout }
    }

    /// A visibility image a method writes, readable by the shading pass.
    pub fn create_visibility(device: &wgpu::Device, size: (u32, u32)) -> wgpu::Texture {
        layout::create_texture(
            device,
            "shading::visibility",
            size,
            VISIBILITY_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        )
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        gbuffer: &GBuffer,
        visibility: &wgpu::Texture,
        radiance: &wgpu::Texture,
        scene: &Scene,
        prepared: &PreparedScene,
        eye: [f32; 3],
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let materials: Vec<[f32; 4]> = prepared
            .materials
            .iter()
            .map(|(albedo, _)| [albedo[0], albedo[1], albedo[2], 0.0])
            .collect();
        let materials = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shading::materials"),
            contents: bytemuck::cast_slice(&materials),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let l = &scene.light;
        let uniforms = layout::parameter_buffer(device, "shading::uniforms", &ShadingUniforms {
                light: [l.center[0], l.center[1], l.center[2], l.radius],
                intensity: [l.intensity[0], l.intensity[1], l.intensity[2], 0.0],
                ambient: [scene.ambient[0], scene.ambient[1], scene.ambient[2], 0.0],
                eye: [eye[0], eye[1], eye[2], 0.0],
            });
        let visibility_view = layout::view(visibility);
        let radiance_view = layout::view(radiance);
        let bind_group = layout::bind_group(
            device,
            "shading::bind_group",
            &self.layout,
            &[
                wgpu::BindingResource::TextureView(&gbuffer.position_view),
                wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                wgpu::BindingResource::TextureView(&visibility_view),
                materials.as_entire_binding(),
                uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(&radiance_view),
            ],
        );
        layout::dispatch_per_pixel(encoder, "shading::pass", &self.pipeline, &bind_group, gbuffer.size, timestamps);
    }
}
