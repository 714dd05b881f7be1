//! Tone-mapped PNG previews for looking at renders (never for comparisons: they clamp).

use std::io::{BufWriter, Write};
use std::path::Path;

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};

use crate::atomic::write_atomically;
use crate::{Image, ImageError};

/// The sRGB opto-electronic transfer function (IEC 61966-2-1), linear [0, 1] to encoded [0, 1].
pub(crate) fn srgb_oetf(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// One linear channel value to an 8-bit sRGB code: scale, clamp to [0, 1], OETF, round.
/// NaN becomes 0 (black) so that it cannot hide as a plausible colour; +inf becomes 255.
pub(crate) fn to_srgb8(linear: f32, scale: f32) -> u8 {
    let v = linear * scale;
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (srgb_oetf(v) * 255.0).round() as u8
}

/// Tone-mapped 8-bit sRGB PNG preview, written atomically like [`crate::write_exr`].
///
/// Each linear value is multiplied by `2^exposure_stops`, clamped to [0, 1] and encoded with the
/// sRGB OETF. NaN channels become 0.
pub fn write_png_preview(path: &Path, img: &Image, exposure_stops: f32) -> Result<(), ImageError> {
    let what = || path.display().to_string();
    img.check_len().map_err(|reason| ImageError::InvalidImage {
        what: what(),
        reason,
    })?;
    if img.width == 0 || img.height == 0 {
        return Err(ImageError::InvalidImage {
            what: what(),
            reason: format!("cannot write an empty {}x{} image", img.width, img.height),
        });
    }
    let scale = exposure_stops.exp2();
    let bytes: Vec<u8> = img
        .data
        .iter()
        .flat_map(|p| p.map(|v| to_srgb8(v, scale)))
        .collect();
    write_atomically(path, |file| {
        let mut buffered = BufWriter::new(file);
        PngEncoder::new(&mut buffered)
            .write_image(&bytes, img.width, img.height, ExtendedColorType::Rgb8)
            .map_err(|source| ImageError::Png {
                path: path.to_path_buf(),
                source,
            })?;
        buffered
            .flush()
            .map_err(|e| ImageError::io(path, "write temporary file", e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::scratch_dir;

    #[test]
    fn oetf_known_values() {
        assert_eq!(to_srgb8(0.0, 1.0), 0);
        assert_eq!(to_srgb8(1.0, 1.0), 255);
        assert_eq!(to_srgb8(f32::INFINITY, 1.0), 255);
        assert_eq!(to_srgb8(f32::NAN, 1.0), 0);
        assert_eq!(to_srgb8(-3.0, 1.0), 0);
        // 18% grey encodes to 118 (0.4614 * 255 = 117.7), the textbook value.
        assert_eq!(to_srgb8(0.18, 1.0), 118);
        // One stop up from 0.25 is 0.5 -> 0.7354 * 255 = 187.5 -> 188.
        assert_eq!(to_srgb8(0.25, 2.0), 188);
        // Continuity at the linear/power junction.
        assert!((srgb_oetf(0.003_130_8) - 0.040_449_936).abs() < 1e-6);
    }

    #[test]
    fn writes_a_png_of_the_right_size() {
        let dir = scratch_dir("png");
        let path = dir.join("p.png");
        let mut img = Image::new(3, 2);
        img.set(2, 1, [1.0, 0.5, 0.0]);
        write_png_preview(&path, &img, 0.0).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        // IHDR width and height, big-endian, at offsets 16 and 20.
        assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 3);
        assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 2);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        let missing = dir.join("no").join("p.png");
        assert!(write_png_preview(&missing, &img, 0.0).is_err());
        assert!(!missing.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
