//! Image files: sRGB-encoded 8-bit PNG and linear float EXR, by extension.

use std::path::Path;

use crate::error::{Error, Result};

/// The sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to [0, 1].
pub fn linear_to_srgb(x: f32) -> f32 {
    // NaN compares false everywhere and lands on 0.
    let x = if x > 0.0 { x.min(1.0) } else { 0.0 };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Writes a linear image of `channels` (1 or 3) floats per pixel, row 0 at the
/// top: `.png` as sRGB 8-bit, `.exr` as linear float32 RGB.
pub fn write_image(path: &Path, data: &[f32], width: u32, height: u32, channels: u32) -> Result<()> {
    if !(channels == 1 || channels == 3) {
        return Err(Error::InvalidParameter(format!("images have 1 or 3 channels, got {channels}")));
    }
    if width == 0 || height == 0 {
        return Err(Error::InvalidParameter(format!("image size must be at least 1x1, got {width}x{height}")));
    }
    if data.len() != width as usize * height as usize * channels as usize {
        return Err(Error::InvalidParameter(format!(
            "{} values do not make a {width}x{height} image of {channels} channels",
            data.len()
        )));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let png = match ext.as_deref() {
        Some("png") => true,
        Some("exr") => false,
        _ => {
            return Err(Error::InvalidParameter(format!(
                "cannot write {}: the extension must be .png or .exr",
                path.display()
            )))
        }
    };
    // NaN or infinity has no 8-bit encoding and no meaning as linear light:
    // refused for every format (a PNG would quietly write NaN as black).
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        let pixel = i / channels as usize;
        return Err(Error::InvalidParameter(format!(
            "image has a non-finite value ({}) at row {}, column {}",
            data[i],
            pixel / width as usize,
            pixel % width as usize
        )));
    }
    let rgb: Vec<f32> = if channels == 3 { data.to_vec() } else { data.iter().flat_map(|&v| [v, v, v]).collect() };
    let io = |e: image::ImageError| Error::Io(format!("writing {}: {e}", path.display()));
    if png {
        let bytes: Vec<u8> = rgb.iter().map(|&v| (linear_to_srgb(v) * 255.0 + 0.5) as u8).collect();
        image::RgbImage::from_raw(width, height, bytes)
            .ok_or_else(|| Error::Io("image buffer has the wrong size".into()))?
            .save(path)
            .map_err(io)
    } else {
        image::Rgb32FImage::from_raw(width, height, rgb)
            .ok_or_else(|| Error::Io("image buffer has the wrong size".into()))?
            .save(path)
            .map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints_and_nan() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.5) - 0.7354).abs() < 1e-3);
        assert_eq!(linear_to_srgb(f32::NAN), 0.0);
        assert_eq!(linear_to_srgb(7.0), linear_to_srgb(1.0));
    }
}
