//! Error metrics of an image against a reference.
//!
//! Everything is accumulated in f64. A pixel where the image or the reference has a non-finite
//! channel (NaN, +-inf) is left out of every mean and counted in [`Metrics::nonfinite_pixels`],
//! so that one NaN cannot silently turn all metrics into NaN, nor disappear: callers must check
//! that count (the CLI and the tests treat any non-finite pixel as a failure).

use crate::{check_same_size, Image, ImageError};

/// Added to `r^2` in the relMSE denominator so that black reference pixels do not divide by zero
/// (the same regularisation as in the denoising literature and Mitsuba's tooling; it makes
/// relMSE behave like absolute MSE/0.01 where the reference is much darker than 0.1).
pub const RELMSE_EPSILON: f64 = 0.01;

/// Error metrics of an image against a reference, per channel (R, G, B).
#[derive(Clone, Debug, PartialEq)]
pub struct Metrics {
    /// Relative mean squared error, mean over pixels of `(x - r)^2 / (r^2 + 0.01)`.
    pub relmse: [f64; 3],
    /// Mean of `relmse` over the three channels.
    pub relmse_all: f64,
    /// Root mean squared error, `sqrt(mean((x - r)^2))`.
    pub rmse: [f64; 3],
    /// Mean absolute error, `mean(|x - r|)`.
    pub mae: [f64; 3],
    /// `mean(img) / mean(reference)`: 1 for an unbiased image (up to noise); NaN or inf where the
    /// reference channel is black.
    pub mean_ratio: [f64; 3],
    /// Pixels left out because the image or the reference has a non-finite channel there.
    pub nonfinite_pixels: usize,
}

/// Compare `img` with `reference` (same size, else [`ImageError::SizeMismatch`]).
///
/// relMSE is the mean over pixels of `(x - r)^2 / (r^2 + 0.01)`; the 0.01 ([`RELMSE_EPSILON`])
/// avoids division by zero in black pixels. Pixels with a non-finite channel in either image are
/// skipped and counted in `nonfinite_pixels`; if every pixel is skipped, the metrics are NaN.
pub fn compare(img: &Image, reference: &Image) -> Result<Metrics, ImageError> {
    check_same_size("image", img, reference, "reference")?;
    let mut sq = [0.0f64; 3];
    let mut rel = [0.0f64; 3];
    let mut abs = [0.0f64; 3];
    let mut sum_x = [0.0f64; 3];
    let mut sum_r = [0.0f64; 3];
    let mut n = 0usize;
    let mut nonfinite = 0usize;
    for (px, pr) in img.data.iter().zip(&reference.data) {
        if !(px.iter().chain(pr).all(|v| v.is_finite())) {
            nonfinite += 1;
            continue;
        }
        n += 1;
        for c in 0..3 {
            let (x, r) = (f64::from(px[c]), f64::from(pr[c]));
            let d = x - r;
            sq[c] += d * d;
            rel[c] += d * d / (r * r + RELMSE_EPSILON);
            abs[c] += d.abs();
            sum_x[c] += x;
            sum_r[c] += r;
        }
    }
    let n = n as f64;
    let relmse = rel.map(|s| s / n);
    Ok(Metrics {
        relmse,
        relmse_all: relmse.iter().sum::<f64>() / 3.0,
        rmse: sq.map(|s| (s / n).sqrt()),
        mae: abs.map(|s| s / n),
        mean_ratio: [0, 1, 2].map(|c| sum_x[c] / sum_r[c]),
        nonfinite_pixels: nonfinite,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1e-300)
    }

    #[test]
    fn hand_computed_values() {
        // reference: (1,0,2) and (3,0,2); image: (2,0,2) and (1,0.1,4).
        let reference = Image {
            width: 2,
            height: 1,
            data: vec![[1.0, 0.0, 2.0], [3.0, 0.0, 2.0]],
        };
        let img = Image {
            width: 2,
            height: 1,
            data: vec![[2.0, 0.0, 2.0], [1.0, 0.1, 4.0]],
        };
        let m = compare(&img, &reference).unwrap();
        // R: d = 1, -2. relMSE = (1/1.01 + 4/9.01)/2; RMSE = sqrt((1+4)/2); MAE = 1.5; ratio 3/4.
        assert!(close(m.relmse[0], (1.0 / 1.01 + 4.0 / 9.01) / 2.0));
        assert!(close(m.rmse[0], 2.5f64.sqrt()));
        assert!(close(m.mae[0], 1.5));
        assert!(close(m.mean_ratio[0], 0.75));
        // G: d = 0, 0.1 (as f32) over a black reference: relMSE = (0.1^2/0.01)/2 = 0.5.
        let d = f64::from(0.1f32);
        assert!(close(m.relmse[1], d * d / 0.01 / 2.0));
        assert!(close(m.mae[1], d / 2.0));
        assert!(m.mean_ratio[1].is_infinite());
        // B: d = 0, 2. relMSE = (4/4.01)/2; RMSE = sqrt(2); ratio 6/4.
        assert!(close(m.relmse[2], 4.0 / 4.01 / 2.0));
        assert!(close(m.rmse[2], 2.0f64.sqrt()));
        assert!(close(m.mean_ratio[2], 1.5));
        assert!(close(m.relmse_all, m.relmse.iter().sum::<f64>() / 3.0));
        assert_eq!(m.nonfinite_pixels, 0);
    }

    #[test]
    fn identical_images_have_zero_error() {
        let a = Image::filled(4, 3, [0.5, 1.0, 2.0]);
        let m = compare(&a, &a).unwrap();
        assert_eq!(m.relmse, [0.0; 3]);
        assert_eq!(m.rmse, [0.0; 3]);
        assert_eq!(m.mean_ratio, [1.0; 3]);
    }

    #[test]
    fn nonfinite_pixels_are_counted_not_averaged() {
        let reference = Image::filled(3, 1, [1.0; 3]);
        let mut img = Image::filled(3, 1, [1.0; 3]);
        img.set(0, 0, [f32::NAN, 1.0, 1.0]);
        img.set(1, 0, [1.0, f32::INFINITY, 1.0]);
        let m = compare(&img, &reference).unwrap();
        assert_eq!(m.nonfinite_pixels, 2);
        assert_eq!(m.rmse, [0.0; 3]);
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let err = compare(&Image::new(3, 2), &Image::new(2, 3)).unwrap_err();
        assert!(matches!(err, ImageError::SizeMismatch { .. }));
        assert!(
            err.to_string().contains("3x2") && err.to_string().contains("2x3"),
            "{err}"
        );
    }
}
