//! Passes shared by every method: the camera G-buffer, the light's depth
//! map, and the shading of SPEC section 3.

pub mod centre_map;
pub mod gbuffer;
pub mod map_rays;
pub mod object_map;
pub mod samplers;
pub mod screen;
pub mod shading;
pub mod shadow_map;
pub mod shadow_test;
pub mod solid_layers;
pub mod volumes;

/// Vertex layout of [`crate::scene::CornerVertex`]: position, normal, mesh index.
pub const CORNER_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Uint32];

pub fn corner_layout(attributes: &[wgpu::VertexAttribute]) -> wgpu::VertexBufferLayout<'_> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<crate::scene::CornerVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes,
    }
}

/// Row-major arrays of a glam matrix as WGSL's column-major `mat4x4` expects.
pub fn mat4(m: glam::Mat4) -> [[f32; 4]; 4] {
    m.to_cols_array_2d()
}
