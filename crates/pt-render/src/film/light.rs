//! The film of methods that splat light paths onto the image (Mitsuba's `ptracer`): a light
//! path's vertex seen by the camera lands at any film position, not at a pixel's own sample.
//!
//! A splat at film position (x, y) adds its value times the separable filter weights
//! f(X + 1/2 - x) f(Y + 1/2 - y) to the pixels (X, Y) whose centre lies within the filter's
//! radius, inside the image; the weights are normalised to sum to 1 over those pixels, so every
//! splat deposits its whole value in the image (Mitsuba 3.9.1's `ImageBlock::put` with
//! `normalize`, as its scalar variants clip the footprint; the box filter of radius 1/2 puts
//! the value in the pixel the position falls in). The image is the sum of the splats, scaled by
//! the caller, with no division by summed weights (a light tracer's pixel is an integral over
//! its footprint, not an average of samples).
//!
//! Splats are added in the order given: the caller keeps that order fixed (light path by light
//! path), which makes the image independent of the number of threads.

use super::{filter_profile, filter_radius};
use pt_math::Vec2;
use pt_scene::FilterDesc;

/// Most pixels per axis a splat reaches (a filter radius up to 15.5 pixels); the light tracer
/// refuses wider filters ([`LightFilm::supports`]).
const MAX_FOOTPRINT: usize = 32;

/// The accumulated splats of a light-path render.
#[derive(Clone, Debug, PartialEq)]
pub struct LightFilm {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    filter: FilterDesc,
    radius: f32,
    /// Per pixel (row-major), the sum of the splats' weighted values (linear RGB).
    pub sums: Vec<[f64; 3]>,
}

impl LightFilm {
    /// An empty film of `width` x `height` pixels with the reconstruction filter `filter`.
    pub fn new(filter: FilterDesc, width: u32, height: u32) -> LightFilm {
        LightFilm {
            width,
            height,
            filter,
            radius: filter_radius(&filter),
            sums: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    /// Whether splats under `filter` fit the footprint this film computes at once.
    pub fn supports(filter: &FilterDesc) -> bool {
        2.0 * filter_radius(filter) + 1.0 < MAX_FOOTPRINT as f32
    }

    /// Adds `value` times `scale` at film position `pos` (pixels from the image's top-left
    /// corner) with the normalised filter weights (see the module documentation).
    #[inline]
    pub fn splat(&mut self, pos: Vec2, value: [f32; 3], scale: f64) {
        let (w, h) = (self.width as i32, self.height as i32);
        if matches!(self.filter, FilterDesc::Box { radius } if radius <= 0.5) {
            let (x, y) = (pos.x.floor() as i32, pos.y.floor() as i32);
            if (0..w).contains(&x) && (0..h).contains(&y) {
                let s = &mut self.sums[(y * w + x) as usize];
                for c in 0..3 {
                    s[c] += scale * f64::from(value[c]);
                }
            }
            return;
        }
        // Pixels X with |X + 1/2 - x| <= radius, clipped to the image.
        let range = |x: f32, n: i32| {
            let a = ((x - 0.5 - self.radius).ceil() as i32).max(0);
            let b = ((x - 0.5 + self.radius).floor() as i32).min(n - 1);
            a..b + 1
        };
        let (xs, ys) = (range(pos.x, w), range(pos.y, h));
        if xs.is_empty() || ys.is_empty() {
            return;
        }
        let mut wx = [0.0f32; MAX_FOOTPRINT];
        let mut wy = [0.0f32; MAX_FOOTPRINT];
        let (mut sx, mut sy) = (0.0f32, 0.0f32);
        for (k, x) in xs.clone().enumerate() {
            wx[k] = filter_profile(&self.filter, x as f32 + 0.5 - pos.x);
            sx += wx[k];
        }
        for (k, y) in ys.clone().enumerate() {
            wy[k] = filter_profile(&self.filter, y as f32 + 0.5 - pos.y);
            sy += wy[k];
        }
        let norm = sx * sy;
        if norm == 0.0 {
            return;
        }
        let v = value.map(|c| scale * f64::from(c) / f64::from(norm));
        for (j, y) in ys.enumerate() {
            let row = (y * w) as usize;
            for (k, x) in xs.clone().enumerate() {
                let weight = f64::from(wx[k] * wy[j]);
                let s = &mut self.sums[row + x as usize];
                for c in 0..3 {
                    s[c] += weight * v[c];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every splat deposits its whole value, at the centre and at the image's edges, for every
    /// filter (the normalisation over the clipped footprint); the box of radius 1/2 puts it in
    /// one pixel.
    #[test]
    fn splats_conserve_their_value() {
        for f in [
            FilterDesc::Box { radius: 0.5 },
            FilterDesc::Gaussian { stddev: 0.5 },
            FilterDesc::Tent { radius: 1.5 },
            FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
            },
            FilterDesc::Lanczos { lobes: 3.0 },
        ] {
            for pos in [
                Vec2::new(5.3, 4.7),
                Vec2::new(0.1, 0.2),
                Vec2::new(9.95, 7.99),
            ] {
                let mut film = LightFilm::new(f, 10, 8);
                film.splat(pos, [1.0, 2.0, 4.0], 0.5);
                for c in 0..3 {
                    let total: f64 = film.sums.iter().map(|s| s[c]).sum();
                    let want = 0.5 * [1.0, 2.0, 4.0][c];
                    assert!((total - want).abs() < 1e-5, "{f:?} at {pos}: {total}");
                }
                if let FilterDesc::Box { .. } = f {
                    let touched = film.sums.iter().filter(|s| s[0] != 0.0).count();
                    assert_eq!(touched, 1);
                }
            }
        }
    }

    /// The weights are the filter's at the pixel centres: the tent of radius 1 at (2.25, 1.5)
    /// reaches pixels 1 and 2 in x (0.25 and 0.75) and pixel 1 in y.
    #[test]
    fn weights_are_the_filter_at_pixel_centres() {
        let mut film = LightFilm::new(FilterDesc::Tent { radius: 1.0 }, 4, 3);
        film.splat(Vec2::new(2.25, 1.5), [1.0, 0.0, 0.0], 1.0);
        assert!((film.sums[4 + 1][0] - 0.25).abs() < 1e-7);
        assert!((film.sums[4 + 2][0] - 0.75).abs() < 1e-7);
        let total: f64 = film.sums.iter().map(|s| s[0]).sum();
        assert!((total - 1.0).abs() < 1e-7);
    }
}
