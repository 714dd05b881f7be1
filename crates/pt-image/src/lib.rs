//! Images for the `pt` path tracer: a linear RGB float [`Image`], EXR input and output
//! ([`write_exr`], [`read_exr`]), a tone-mapped PNG preview ([`write_png_preview`]), error
//! metrics ([`metrics`]), FLIP ([`flip`]), firefly counts ([`fireflies`]) and false-colour error
//! images ([`colormap`]). The statistical tests that decide whether a render matches its
//! reference (z-tests) are in the `pt-stats` crate.
//!
//! Conventions: pixels hold linear Rec.709 radiance (no gamma, exposure or tone mapping), rows are
//! stored top row first, and every function that touches a file writes it atomically (temporary
//! file in the same directory, fsync, rename) and names the file in its errors.

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod atomic;
pub mod colormap;
mod error;
mod exr_io;
pub mod fireflies;
pub mod flip;
pub mod metrics;
mod png;

pub use error::ImageError;
pub use exr_io::{
    read_exr, read_exr_channels, write_exr, write_exr_channels, ExrMeta, NamedChannels,
};
pub use png::write_png_preview;

/// Linear RGB float image, row-major, top row first. Values are radiance (no gamma).
///
/// `data[y * width + x]` is the pixel in column `x` of row `y`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Number of columns.
    pub width: u32,
    /// Number of rows.
    pub height: u32,
    /// `width * height` pixels, row-major, top row first.
    pub data: Vec<[f32; 3]>,
}

impl Image {
    /// A black image (all zeros) of the given size.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            data: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    /// An image whose every pixel is `value`.
    pub fn filled(width: u32, height: u32, value: [f32; 3]) -> Self {
        Self {
            width,
            height,
            data: vec![value; width as usize * height as usize],
        }
    }

    /// Number of pixels, `width * height`.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside a {}x{} image",
            self.width,
            self.height
        );
        y as usize * self.width as usize + x as usize
    }

    /// The pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    /// If `(x, y)` lies outside the image.
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.data[self.index(x, y)]
    }

    /// Set the pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    /// If `(x, y)` lies outside the image.
    pub fn set(&mut self, x: u32, y: u32, value: [f32; 3]) {
        let i = self.index(x, y);
        self.data[i] = value;
    }

    /// Mean of each channel over all pixels, accumulated in f64. Non-finite pixels are included
    /// (so they make the mean non-finite); an empty image has mean NaN.
    pub fn mean(&self) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for p in &self.data {
            for c in 0..3 {
                sum[c] += f64::from(p[c]);
            }
        }
        let n = self.data.len() as f64;
        sum.map(|s| s / n)
    }

    /// Number of pixels with at least one non-finite (NaN or infinite) channel.
    pub fn nonfinite_pixels(&self) -> usize {
        self.data
            .iter()
            .filter(|p| !p.iter().all(|v| v.is_finite()))
            .count()
    }

    /// Check that `data` holds exactly `width * height` pixels.
    pub(crate) fn check_len(&self) -> Result<(), String> {
        if self.data.len() == self.pixel_count() {
            Ok(())
        } else {
            Err(format!(
                "image is {}x{} but holds {} pixels instead of {}",
                self.width,
                self.height,
                self.data.len(),
                self.pixel_count()
            ))
        }
    }
}

/// Checks that two images have the same size and that each holds `width * height` pixels.
/// `what` and `b_name` name the images in the error (e.g. "image", "reference").
pub fn check_same_size(what: &str, a: &Image, b: &Image, b_name: &str) -> Result<(), ImageError> {
    for (img, name) in [(a, what), (b, b_name)] {
        if let Err(reason) = img.check_len() {
            return Err(ImageError::InvalidImage {
                what: name.to_string(),
                reason,
            });
        }
    }
    if a.width != b.width || a.height != b.height {
        return Err(ImageError::SizeMismatch {
            what: what.to_string(),
            width: a.width,
            height: a.height,
            other: b_name.to_string(),
            other_width: b.width,
            other_height: b.height,
        });
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod test_util {
    use std::path::PathBuf;

    /// A fresh, empty directory for one test (tests run in parallel: one directory each).
    pub(crate) fn scratch_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("pt-image-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn get_set_are_row_major_top_first() {
        let mut img = Image::new(3, 2);
        img.set(2, 1, [1.0, 2.0, 3.0]);
        assert_eq!(img.data[5], [1.0, 2.0, 3.0]);
        assert_eq!(img.get(2, 1), [1.0, 2.0, 3.0]);
        assert_eq!(img.get(1, 1), [0.0; 3]);
    }

    #[test]
    fn mean_is_per_channel() {
        let mut img = Image::new(2, 1);
        img.set(0, 0, [1.0, 2.0, 4.0]);
        img.set(1, 0, [3.0, 2.0, 0.0]);
        assert_eq!(img.mean(), [2.0, 2.0, 2.0]);
    }
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder, fsync, rename): a
/// reader sees the old file or the whole new one, never a partial file.
pub fn write_bytes_atomically(path: &std::path::Path, bytes: &[u8]) -> Result<(), ImageError> {
    atomic::write_atomically(path, |f| {
        use std::io::Write;
        f.write_all(bytes)
            .map_err(|e| ImageError::io(path, "write file", e))
    })
}
