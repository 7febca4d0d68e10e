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

/// `f` of a mapped buffer's bytes; unmaps it.
fn with_mapped<T>(p: &PendingReadback, f: impl FnOnce(&[u8]) -> T) -> Result<T> {
    let view = p.buffer.slice(..).get_mapped_range().map_err(|e| Error::Gpu(format!("mapping a readback buffer failed: {e}")))?;
    let out = f(&view);
    drop(view);
    p.buffer.unmap();
    Ok(out)
}

/// The rows of every mapped buffer, padding stripped, in order; unmaps them.
pub fn read_all(pending: &[PendingReadback]) -> Result<Vec<Vec<u8>>> {
    pending
        .iter()
        .map(|p| {
            with_mapped(p, |view| {
                let mut out = vec![0u8; p.row_bytes as usize * p.height as usize];
                copy_rows(&mut out, view, p.row_bytes as usize, p.padded_row_bytes as usize);
                out
            })
        })
        .collect()
}

/// As [`read_all`], into 4-byte words: every readback here is made of
/// 4-byte texel components, counters or timestamp halves. One copy out of
/// the mapped memory, into memory aligned for `f32`, `u32` and `i32`, so that
/// [`words_as`] reinterprets it without another (a 1920x1080 render reads
/// back about 74 MB: each copy and fresh allocation of it costs
/// milliseconds; docs/gpu_timings.md).
pub fn read_all_words(pending: &[PendingReadback]) -> Result<Vec<Vec<u32>>> {
    pending
        .iter()
        .map(|p| {
            with_mapped(p, |view| {
                let (row, total) = (p.row_bytes as usize, p.row_bytes as usize * p.height as usize);
                let mut out = vec![0u32; total.div_ceil(4)];
                copy_rows(&mut bytemuck::cast_slice_mut(&mut out)[..total], view, row, p.padded_row_bytes as usize);
                out
            })
        })
        .collect()
}

/// Copies the first `row` bytes of each `padded` row of `src` into the
/// tightly packed rows of `dst`.
fn copy_rows(dst: &mut [u8], src: &[u8], row: usize, padded: usize) {
    if row > 0 {
        in_bands(src, padded, dst, row, |s, d| d.copy_from_slice(&s[..row]));
    }
}

/// Maps each group of `group` elements of `src` to `out` outputs with `f`.
pub fn convert<T: Sync, U: Send + Copy + Default>(src: &[T], group: usize, out: usize, f: impl Fn(&[T], &mut [U]) + Sync) -> Vec<U> {
    let mut dst = vec![U::default(); src.len() / group.max(1) * out];
    in_bands(src, group, &mut dst, out, f);
    dst
}

/// `f` of each group of `group` elements of `src` and the `out` elements of
/// `dst` it fills; over 4 MiB of `src`, in bands of groups over up to 8 of
/// the host's threads. One core's pass over a 1920x1080 render's readback
/// (copying rows out of mapped memory, texels into RGB triples or object
/// ids) was most of its wall time on a GPU (docs/gpu_timings.md).
fn in_bands<T: Sync, U: Send>(src: &[T], group: usize, dst: &mut [U], out: usize, f: impl Fn(&[T], &mut [U]) + Sync) {
    let groups = dst.len().checked_div(out).unwrap_or(0);
    if groups == 0 || group == 0 {
        return;
    }
    let run = |s: &[T], d: &mut [U]| {
        for (s, d) in s.chunks(group).zip(d.chunks_exact_mut(out)) {
            f(s, d);
        }
    };
    let threads = if std::mem::size_of_val(src) < 4 << 20 { 1 } else { std::thread::available_parallelism().map_or(1, |n| n.get()).min(8) };
    if threads <= 1 {
        run(src, dst);
        return;
    }
    let band = groups.div_ceil(threads);
    std::thread::scope(|scope| {
        for (s, d) in src.chunks(band * group).zip(dst.chunks_mut(band * out)) {
            let run = &run;
            scope.spawn(move || run(s, d));
        }
    });
}

/// Reinterprets words of [`read_all_words`] as `T` of 4 bytes (`f32`, `u32`,
/// `i32`) in place; any other `T` is copied.
pub fn words_as<T: bytemuck::Pod>(words: Vec<u32>) -> Vec<T> {
    bytemuck::allocation::try_cast_vec(words).unwrap_or_else(|(_, words)| bytemuck::pod_collect_to_vec(&words))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_become_4_byte_texels_in_place_and_other_types_by_copy() {
        let floats = [1.5f32, -2.0, 0.0, f32::MAX];
        let words: Vec<u32> = floats.iter().map(|f| f.to_bits()).collect();
        let at = words.as_ptr() as usize;
        let back: Vec<f32> = words_as(words);
        assert_eq!(back, floats);
        assert_eq!(back.as_ptr() as usize, at, "reinterpreted, not copied");
        // Timestamps: two words a tick, little-endian.
        let ticks: Vec<u64> = words_as(vec![7, 0, 1, 2]);
        assert_eq!(ticks, [7, (2 << 32) | 1]);
    }

    #[test]
    fn rows_are_copied_without_their_padding_in_one_band_or_many() {
        // 3-byte rows padded to 5, small (one thread) and over 4 MiB (bands).
        for rows in [7usize, (4 << 20) / 3 + 11] {
            let src: Vec<u8> = (0..rows * 5).map(|i| (i % 5 + 10 * (i / 5 % 20)) as u8).collect();
            let mut dst = vec![0u8; rows * 3];
            copy_rows(&mut dst, &src, 3, 5);
            let want: Vec<u8> = src.chunks(5).flat_map(|r| r[..3].to_vec()).collect();
            assert!(dst == want, "{rows} rows");
        }
    }

    #[test]
    fn conversions_give_the_same_in_one_band_or_many() {
        for n in [5usize, (1 << 20) + 7] {
            let texels: Vec<f32> = (0..4 * n).map(|i| i as f32).collect();
            let rgb = convert(&texels, 4, 3, |t: &[f32], d: &mut [f32]| d.copy_from_slice(&t[..3]));
            let want: Vec<f32> = texels.chunks(4).flat_map(|t| [t[0], t[1], t[2]]).collect();
            assert!(rgb == want, "{n} texels");
            let w = convert(&texels, 4, 1, |t: &[f32], d: &mut [i32]| d[0] = t[3] as i32);
            assert!(w.iter().enumerate().all(|(i, &x)| x == (4 * i + 3) as i32), "{n} texels");
        }
    }
}
