//! False-colour images for error diagnostics.

use crate::{check_same_size, Image, ImageError};

/// Matplotlib's viridis (van der Walt & Smith 2015) sampled at 9 evenly spaced points, sRGB
/// encoded: #440154 #472d7b #3b528b #2c728e #21918c #28ae80 #5ec962 #addc30 #fde725.
const VIRIDIS: [[u8; 3]; 9] = [
    [0x44, 0x01, 0x54],
    [0x47, 0x2d, 0x7b],
    [0x3b, 0x52, 0x8b],
    [0x2c, 0x72, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x28, 0xae, 0x80],
    [0x5e, 0xc9, 0x62],
    [0xad, 0xdc, 0x30],
    [0xfd, 0xe7, 0x25],
];

/// Colour for NaN values: magenta, which viridis never produces.
pub const NAN_COLOUR: [f32; 3] = [1.0, 0.0, 1.0];

/// sRGB EOTF (IEC 61966-2-1): encoded [0, 1] to linear.
fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Viridis at `t` in [0, 1] (clamped), as *linear* RGB: interpolated between the encoded control
/// points (where viridis is perceptually uniform), then decoded, so that writing the image with
/// [`crate::write_png_preview`] at exposure 0 shows the usual viridis colours.
pub fn viridis(t: f32) -> [f32; 3] {
    let u = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f32;
    let i = (u.floor() as usize).min(VIRIDIS.len() - 2);
    let f = u - i as f32;
    [0, 1, 2].map(|c| {
        let a = f32::from(VIRIDIS[i][c]) / 255.0;
        let b = f32::from(VIRIDIS[i + 1][c]) / 255.0;
        srgb_to_linear(a + (b - a) * f)
    })
}

/// Map `values` (row-major, `width * height` of them) through viridis: `vmin` and below is the
/// dark end, `vmax` and above the bright end; with `log`, the mapping is linear in `log10(v)`
/// (values <= 0 then count as below `vmin`, which must be > 0). NaN is magenta
/// ([`NAN_COLOUR`]), +-inf is clamped like any other value. If `vmax <= vmin` every value maps to
/// one end or the other (`v > vmin` bright, else dark). The result holds linear RGB.
///
/// # Panics
/// If `values.len() != width * height`.
pub fn false_colour(
    values: &[f32],
    width: u32,
    height: u32,
    vmin: f32,
    vmax: f32,
    log: bool,
) -> Image {
    assert_eq!(
        values.len(),
        width as usize * height as usize,
        "false_colour: {} values for a {width}x{height} image",
        values.len()
    );
    let transform = |v: f32| -> f64 {
        if log {
            if v > 0.0 {
                f64::from(v).log10()
            } else {
                f64::NEG_INFINITY
            }
        } else {
            f64::from(v)
        }
    };
    let (lo, hi) = (transform(vmin), transform(vmax));
    let data = values
        .iter()
        .map(|&v| {
            if v.is_nan() {
                return NAN_COLOUR;
            }
            let x = transform(v);
            let t = if hi > lo {
                ((x - lo) / (hi - lo)).clamp(0.0, 1.0)
            } else if x > lo {
                1.0
            } else {
                0.0
            };
            viridis(t as f32)
        })
        .collect();
    Image {
        width,
        height,
        data,
    }
}

/// Per-pixel relative error `|x - r| / (|r| + 0.01)`, averaged over the three channels (the 0.01
/// keeps black reference pixels finite). Row-major like the images; NaN where an input is NaN.
///
/// Returns [`ImageError::SizeMismatch`] when the sizes differ (the brief's signature returned a
/// plain `Vec`; a comparison of mismatched images must be an error, not a panic).
pub fn relative_error_image(img: &Image, reference: &Image) -> Result<Vec<f32>, ImageError> {
    check_same_size("image", img, reference, "reference")?;
    Ok(img
        .data
        .iter()
        .zip(&reference.data)
        .map(|(x, r)| {
            let sum: f64 = (0..3)
                .map(|c| {
                    let (x, r) = (f64::from(x[c]), f64::from(r[c]));
                    (x - r).abs() / (r.abs() + 0.01)
                })
                .sum();
            (sum / 3.0) as f32
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_nan_and_clamping() {
        let img = false_colour(
            &[0.0, 1.0, f32::NAN, -5.0, f32::INFINITY, 0.5],
            3,
            2,
            0.0,
            1.0,
            false,
        );
        assert_eq!(img.data[0], viridis(0.0));
        assert_eq!(img.data[1], viridis(1.0));
        assert_eq!(img.data[2], NAN_COLOUR);
        assert_eq!(img.data[3], viridis(0.0));
        assert_eq!(img.data[4], viridis(1.0));
        // 0.5 is exactly the 5th control point, #21918c.
        let mid = viridis(0.5);
        let expect = [0x21, 0x91, 0x8c].map(|b: u8| srgb_to_linear(f32::from(b) / 255.0));
        for c in 0..3 {
            assert!((img.data[5][c] - expect[c]).abs() < 1e-6 && (mid[c] - expect[c]).abs() < 1e-6);
        }
    }

    #[test]
    fn log_mapping() {
        // 1e-3 .. 1e1 in log: 1e-1 is halfway.
        let img = false_colour(&[1e-1, 0.0, 1e3], 3, 1, 1e-3, 1e1, true);
        let mid = viridis(0.5);
        for (got, want) in img.data[0].iter().zip(mid) {
            assert!((got - want).abs() < 1e-5);
        }
        assert_eq!(img.data[1], viridis(0.0));
        assert_eq!(img.data[2], viridis(1.0));
    }

    #[test]
    fn viridis_is_monotone_in_luminance() {
        // A perceptual map: luminance (Rec.709 Y of the linear colour) increases along it.
        let y = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let mut prev = -1.0;
        for i in 0..=100 {
            let l = y(viridis(i as f32 / 100.0));
            assert!(l > prev, "at {i}");
            prev = l;
        }
    }

    #[test]
    fn relative_error_values() {
        let reference = Image {
            width: 2,
            height: 1,
            data: vec![[1.0, 0.0, 2.0], [0.99; 3]],
        };
        let img = Image {
            width: 2,
            height: 1,
            data: vec![[2.0, 0.01, 2.0], [0.99; 3]],
        };
        let e = relative_error_image(&img, &reference).unwrap();
        // (1/1.01 + 0.01/0.01 + 0) / 3
        let expect = (1.0 / 1.01 + f64::from(0.01f32) / 0.01) / 3.0;
        assert!((f64::from(e[0]) - expect).abs() < 1e-6, "{}", e[0]);
        assert_eq!(e[1], 0.0);
        assert!(relative_error_image(&img, &Image::new(1, 2)).is_err());
    }
}
