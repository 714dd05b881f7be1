//! FLIP, the perceptual difference metric of Andersson et al. 2020 ("FLIP: A Difference
//! Evaluator for Alternating Images", HPG 2020), computed by NVIDIA's implementation through the
//! `nv-flip` crate, on tone-mapped images.
//!
//! `nv-flip` implements LDR-FLIP, which takes display-encoded sRGB images. Both linear HDR images
//! are therefore tone-mapped the same way as the PNG preview: scaled by `2^exposure`, clamped to
//! [0, 1], encoded with the sRGB OETF and quantised to 8 bits. FLIP then compares them as seen
//! at `pixels_per_degree` (67 by default: a 0.7 m wide 4K monitor viewed from 0.7 m). The result
//! is a per-pixel error in [0, 1] (0: indistinguishable) and its mean, the single number the
//! authors recommend. Because of the clamp, differences above the display's white are invisible
//! to FLIP; relMSE (see [`crate::metrics`]) remains the measure of radiometric accuracy.

use crate::png::to_srgb8;
use crate::{check_same_size, Image, ImageError};

/// FLIP's default viewing condition, pixels per degree of visual angle (Andersson et al. 2020,
/// sec. 5: 0.7 m from a 0.7 m wide 3840-pixel monitor).
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// FLIP of an image against a reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Flip {
    /// Mean FLIP error over the pixels, in [0, 1] (0: no visible difference).
    pub mean: f32,
    /// Per-pixel FLIP error in [0, 1], row-major, top row first.
    pub error_map: Vec<f32>,
}

/// The 8-bit sRGB encoding FLIP sees: `linear * 2^exposure_stops`, clamped to [0, 1], sRGB OETF,
/// rounded (NaN becomes 0, as in the PNG preview).
fn tone_map(img: &Image, exposure_stops: f32) -> Vec<u8> {
    let scale = exposure_stops.exp2();
    img.data
        .iter()
        .flat_map(|p| p.map(|v| to_srgb8(v, scale)))
        .collect()
}

/// FLIP between `img` and `reference` (same size, else [`ImageError::SizeMismatch`]), both
/// tone-mapped with the same exposure (stops; 0 keeps radiance 1 at display white).
pub fn flip(img: &Image, reference: &Image, exposure_stops: f32) -> Result<Flip, ImageError> {
    check_same_size("image", img, reference, "reference")?;
    if img.pixel_count() == 0 {
        return Ok(Flip {
            mean: 0.0,
            error_map: Vec::new(),
        });
    }
    let test =
        nv_flip::FlipImageRgb8::with_data(img.width, img.height, &tone_map(img, exposure_stops));
    let refr = nv_flip::FlipImageRgb8::with_data(
        reference.width,
        reference.height,
        &tone_map(reference, exposure_stops),
    );
    let map = nv_flip::flip(refr, test, DEFAULT_PIXELS_PER_DEGREE);
    let mean = nv_flip::FlipPool::from_image(&map).mean();
    Ok(Flip {
        mean,
        error_map: map.to_vec(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth gradient with a few features, so that FLIP's spatial filters see structure.
    fn scene(w: u32, h: u32) -> Image {
        let mut img = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
                let ring = if ((u - 0.5).powi(2) + (v - 0.5).powi(2)).sqrt() < 0.2 {
                    0.5
                } else {
                    0.0
                };
                img.set(x, y, [0.2 + 0.6 * u, 0.1 + 0.5 * v + ring, 0.3 + ring]);
            }
        }
        img
    }

    #[test]
    fn identical_images_have_zero_flip() {
        let a = scene(48, 32);
        let f = flip(&a, &a, 0.0).unwrap();
        assert_eq!(f.error_map.len(), 48 * 32);
        assert_eq!(f.mean, 0.0);
    }

    #[test]
    fn flip_grows_with_the_difference() {
        // Noise of growing amplitude must give a growing mean FLIP; a 0.5 radiance offset on a
        // mid-grey image is clearly visible (FLIP well above 0.05), a 1% change barely (below).
        let a = scene(64, 64);
        let noisy = |amp: f32| {
            let mut b = a.clone();
            let mut s = 1u32;
            for p in &mut b.data {
                for c in p.iter_mut() {
                    s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    *c *= 1.0 + amp * ((s >> 8) as f32 / (1u32 << 24) as f32 - 0.5);
                }
            }
            b
        };
        let small = flip(&noisy(0.02), &a, 0.0).unwrap().mean;
        let mid = flip(&noisy(0.3), &a, 0.0).unwrap().mean;
        let large = flip(&noisy(1.5), &a, 0.0).unwrap().mean;
        assert!(small < mid && mid < large, "{small} {mid} {large}");
        assert!(small < 0.05, "{small}");
        let offset = Image::filled(32, 32, [0.7; 3]);
        let f = flip(&offset, &Image::filled(32, 32, [0.2; 3]), 0.0)
            .unwrap()
            .mean;
        assert!(f > 0.05, "{f}");
    }

    #[test]
    fn size_mismatch_is_an_error() {
        assert!(flip(&Image::new(4, 4), &Image::new(4, 5), 0.0).is_err());
    }
}
