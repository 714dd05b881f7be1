//! Firefly count: pixels far brighter than their neighbourhood, by a robust outlier rule.
//!
//! **Definition.** For each pixel, with luminance `Y` (Rec.709 weights of linear RGB,
//! `0.2126 R + 0.7152 G + 0.0722 B`), take the luminances of the other pixels in the
//! `(2r+1) x (2r+1)` window around it (clipped at the image border), their median `m` and their
//! median absolute deviation `MAD = median |Y_j - m|`. The robust scale is
//! `s = max(1.4826 MAD, 0.05 |m|, 1e-6)` (1.4826 MAD is the standard deviation for Gaussian
//! data; the floors keep a flat or black neighbourhood, MAD = 0, from making every speck an
//! outlier: a pixel must also stand 5% x k above a flat neighbourhood). The pixel is a **firefly**
//! when `Y > m + k s`. Defaults: `r = 2` (5 x 5 window, 24 neighbours) and `k = 10`: for
//! Gaussian noise a 10-sigma excess has probability ~1e-23, so what is counted is the
//! heavy tail of Monte Carlo noise (rare high-weight paths: caustics through a BSDF-sampled
//! light, a small light hit by BSDF sampling), not ordinary noise. A converged image of a sharp
//! highlight of one or two pixels is counted too: the count is a property of an image, compare it
//! between renders of one scene (and with the reference's own count).
//!
//! Non-finite pixels are not fireflies here (they are counted separately by
//! [`crate::Image::nonfinite_pixels`]) and are left out of the neighbourhood statistics.

use crate::Image;

/// Settings of the firefly rule (see the module doc).
#[derive(Clone, Copy, Debug)]
pub struct FireflyParams {
    /// Window radius in pixels (the window is `2 radius + 1` wide).
    pub radius: u32,
    /// Threshold in robust standard deviations above the neighbourhood median.
    pub k: f32,
}

impl Default for FireflyParams {
    fn default() -> Self {
        FireflyParams { radius: 2, k: 10.0 }
    }
}

/// Rec.709 luminance of a linear RGB pixel.
#[inline]
pub fn luminance(p: [f32; 3]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

fn median(v: &mut [f32]) -> f32 {
    let n = v.len();
    if n == 0 {
        return 0.0;
    }
    let mid = n / 2;
    let (_, &mut hi, _) = v.select_nth_unstable_by(mid, f32::total_cmp);
    if n % 2 == 1 {
        hi
    } else {
        let lo = v[..mid].iter().copied().fold(f32::NEG_INFINITY, f32::max);
        0.5 * (lo + hi)
    }
}

/// Per-pixel firefly mask (row-major, `true` = firefly) under `params`.
pub fn firefly_mask(img: &Image, params: FireflyParams) -> Vec<bool> {
    let (w, h) = (img.width as i64, img.height as i64);
    let r = i64::from(params.radius);
    let y: Vec<f32> = img.data.iter().map(|&p| luminance(p)).collect();
    let mut mask = vec![false; y.len()];
    let mut nb = Vec::with_capacity(((2 * r + 1) * (2 * r + 1)) as usize);
    let mut dev = Vec::with_capacity(nb.capacity());
    for py in 0..h {
        for px in 0..w {
            let c = y[(py * w + px) as usize];
            if !c.is_finite() {
                continue;
            }
            nb.clear();
            for qy in (py - r).max(0)..=(py + r).min(h - 1) {
                for qx in (px - r).max(0)..=(px + r).min(w - 1) {
                    let v = y[(qy * w + qx) as usize];
                    if (qx, qy) != (px, py) && v.is_finite() {
                        nb.push(v);
                    }
                }
            }
            if nb.is_empty() {
                continue;
            }
            let m = median(&mut nb);
            dev.clear();
            dev.extend(nb.iter().map(|v| (v - m).abs()));
            let mad = median(&mut dev);
            let s = (1.4826 * mad).max(0.05 * m.abs()).max(1e-6);
            mask[(py * w + px) as usize] = c > m + params.k * s;
        }
    }
    mask
}

/// Number of fireflies in `img` under `params`.
pub fn count_fireflies(img: &Image, params: FireflyParams) -> usize {
    firefly_mask(img, params).iter().filter(|&&f| f).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-noise in [-0.5, 0.5).
    fn noise(i: u32) -> f32 {
        let x = i
            .wrapping_mul(2_654_435_761)
            .rotate_left(13)
            .wrapping_mul(40_503);
        (x >> 8) as f32 / 16_777_216.0 - 0.5
    }

    #[test]
    fn noisy_flat_image_has_none_and_planted_spikes_are_found() {
        // A flat image with +-10% uniform noise: no pixel is 10 robust sigmas out (uniform
        // noise has no tail), so the count is 0; three planted spikes of 20x the level are
        // found, one in a corner (clipped window) and two adjacent (each is in the other's
        // window, the median ignores one outlier of 24).
        let (w, h) = (40, 30);
        let mut img = Image::filled(w, h, [0.0; 3]);
        for (i, p) in img.data.iter_mut().enumerate() {
            *p = [1.0 + 0.2 * noise(i as u32); 3];
        }
        assert_eq!(count_fireflies(&img, FireflyParams::default()), 0);
        for (x, y) in [(0, 0), (10, 10), (11, 10)] {
            img.set(x, y, [20.0; 3]);
        }
        let mask = firefly_mask(&img, FireflyParams::default());
        assert_eq!(mask.iter().filter(|&&f| f).count(), 3);
        assert!(mask[0] && mask[10 * w as usize + 10] && mask[10 * w as usize + 11]);
    }

    #[test]
    fn edges_and_smooth_gradients_are_not_fireflies() {
        // A step edge (0.1 | 5) and a smooth ramp: the bright side of an edge has at least
        // 9 of 24 bright neighbours in a 5x5 window, so its median stays low only where
        // fewer than half are bright, which a straight edge never gives its own pixels.
        let (w, h) = (32, 16);
        let mut img = Image::filled(w, h, [0.1; 3]);
        for y in 0..h {
            for x in 0..w {
                let v = if x >= 16 { 5.0 } else { 0.1 + 0.05 * x as f32 };
                img.set(x, y, [v; 3]);
            }
        }
        assert_eq!(count_fireflies(&img, FireflyParams::default()), 0);
        // A single bright pixel on black is a firefly (the 1e-6 floor), NaN is not.
        let mut dark = Image::filled(8, 8, [0.0; 3]);
        dark.set(4, 4, [1e-3; 3]);
        dark.set(1, 1, [f32::NAN; 3]);
        assert_eq!(count_fireflies(&dark, FireflyParams::default()), 1);
    }
}
