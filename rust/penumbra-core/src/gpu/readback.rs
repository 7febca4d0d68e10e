//! Texture readback. Rows are padded to `COPY_BYTES_PER_ROW_ALIGNMENT` for the
//! copy and the padding is stripped here, in one place.

use crate::error::{Error, Result};
use crate::gpu::pool::{PooledBuffer, ResourcePool};
use crate::gpu::GpuContext;

const READBACK: wgpu::BufferUsages = wgpu::BufferUsages::COPY_DST.union(wgpu::BufferUsages::MAP_READ);

/// A texture copy recorded into an encoder, waiting to be mapped.
pub struct PendingReadback {
    buffer: PooledBuffer,
    width: u32,
    height: u32,
    row_bytes: u32,
    padded_row_bytes: u32,
}

/// Records a copy of mip 0 of `texture` (all aspects must be one, e.g. a depth
/// texture's depth) into a mappable buffer.
pub fn copy_texture(
    device: &wgpu::Device,
    pool: &ResourcePool,
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
) -> PendingReadback {
    let (width, height, layers) = (texture.width(), texture.height(), texture.depth_or_array_layers());
    let bytes_per_texel = texture
        .format()
        .block_copy_size(Some(aspect))
        .expect("readback of a format without a fixed texel size");
    let row_bytes = width * bytes_per_texel;
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let padded_row_bytes = row_bytes.div_ceil(align) * align;
    let buffer = pool.buffer(device, "penumbra::readback", padded_row_bytes as u64 * height as u64 * layers as u64, READBACK);
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row_bytes),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: layers },
    );
    // Layers follow each other: as many rows again per layer.
    PendingReadback { buffer, width, height: height * layers, row_bytes, padded_row_bytes }
}

/// Records a copy of the first `bytes` (a multiple of 4) of `source` into a mappable buffer.
pub fn copy_buffer(
    device: &wgpu::Device,
    pool: &ResourcePool,
    encoder: &mut wgpu::CommandEncoder,
    source: &wgpu::Buffer,
    bytes: u32,
) -> PendingReadback {
    let buffer = pool.buffer(device, "penumbra::readback_buffer", bytes as u64, READBACK);
    encoder.copy_buffer_to_buffer(source, 0, &buffer, 0, bytes as u64);
    PendingReadback { buffer, width: bytes / 4, height: 1, row_bytes: bytes, padded_row_bytes: bytes }
}

impl PendingReadback {
    pub fn width(&self) -> u32 {
        self.width
    }
    pub fn height(&self) -> u32 {
        self.height
    }
}

/// Maps every pending buffer (one wait for all), then returns each one's
/// rows, padding stripped, in order.
pub fn map_all(ctx: &GpuContext, pending: &[PendingReadback]) -> Result<Vec<Vec<u8>>> {
    wait_mapped(ctx, pending)?;
    read_all(pending)
}

/// Asks for every pending buffer to be mapped and waits for the GPU (all
/// submitted work included).
pub fn wait_mapped(ctx: &GpuContext, pending: &[PendingReadback]) -> Result<()> {
    for p in pending {
        p.buffer.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    }
    ctx.wait()
}

/// The rows of every mapped buffer, padding stripped, in order; unmaps them.
pub fn read_all(pending: &[PendingReadback]) -> Result<Vec<Vec<u8>>> {
    pending
        .iter()
        .map(|p| {
            let view = p
                .buffer
                .slice(..)
                .get_mapped_range()
                .map_err(|e| Error::Gpu(format!("mapping a readback buffer failed: {e}")))?;
            let mut out = Vec::with_capacity(p.row_bytes as usize * p.height as usize);
            for row in view.chunks_exact(p.padded_row_bytes as usize) {
                out.extend_from_slice(&row[..p.row_bytes as usize]);
            }
            drop(view);
            p.buffer.unmap();
            Ok(out)
        })
        .collect()
}

/// Reinterprets tightly packed little-endian texels as `T` (one copy, aligned).
pub fn cast_vec<T: bytemuck::Pod>(bytes: Vec<u8>) -> Vec<T> {
    bytemuck::pod_collect_to_vec(&bytes)
}
