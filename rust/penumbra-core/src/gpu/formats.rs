//! Texture formats shared across layers: the frame's visibility and radiance
//! images, the camera's G-buffer and the light's depth maps. A method's own
//! images keep their formats in its module.

/// Visibility images: what a method writes and shading reads (one channel).
pub const VISIBILITY: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// The shaded image.
pub const RADIANCE: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// G-buffer: world position (xyz) and view depth (w).
pub const POSITION: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// G-buffer: shading normal (xyz) and mesh index (w).
pub const NORMAL: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Depth attachments: the G-buffer's and the light's shadow maps.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
