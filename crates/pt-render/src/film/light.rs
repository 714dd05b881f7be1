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
//! Splats are added in the order given into f64 sums of the current batch (one light path per
//! pixel: one sample index), which the caller keeps fixed (light path by light path); at the
//! batch's end [`LightFilm::commit`] adds them to the film's exact sums ([`super::exact`]).
//! The image is then independent of the number of threads and of how batches were split into
//! passes, resumes or the parts of a render split over machines.
//!
//! The bidirectional methods also add their camera samples here, each at its own film
//! position: those are reconstructed as the path tracer's are (Mitsuba's `hdrfilm`): each
//! pixel keeps the sum of the samples' filter weights `w` and of `w L`, and its value is their
//! quotient ([`LightFilm::camera`]). The image is the light splats' sum plus that average.

use super::exact::{to_fixed, LINEAR_BITS};
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
    /// Per pixel (row-major), the exact sum of the splats' weighted values (linear RGB), in
    /// units of 2^-[`LINEAR_BITS`] (committed batches).
    pub sums: Vec<[i128; 3]>,
    /// Per pixel (row-major), the camera samples' filter-weighted sums (linear RGB) and the
    /// sum of their weights (all zero for the light tracer), exact as `sums`.
    pub camera: Vec<[i128; 4]>,
    /// The current batch's splats, not yet committed (zero between commits; not state).
    batch: Vec<[f64; 3]>,
    /// The current batch's camera samples, not yet committed.
    camera_batch: Vec<[f64; 4]>,
}

impl LightFilm {
    /// An empty film of `width` x `height` pixels with the reconstruction filter `filter`.
    pub fn new(filter: FilterDesc, width: u32, height: u32) -> LightFilm {
        LightFilm {
            width,
            height,
            filter,
            radius: filter_radius(&filter),
            sums: vec![[0; 3]; width as usize * height as usize],
            camera: vec![[0; 4]; width as usize * height as usize],
            batch: vec![[0.0; 3]; width as usize * height as usize],
            camera_batch: vec![[0.0; 4]; width as usize * height as usize],
        }
    }

    /// Adds the current batch's splats and camera samples to the exact sums and clears them.
    pub fn commit(&mut self) {
        use rayon::prelude::*;
        // Pixel by pixel, so on all threads (the same sums for any thread count).
        self.sums
            .par_iter_mut()
            .zip(&mut self.batch)
            .for_each(|(e, b)| {
                for c in 0..3 {
                    e[c] = e[c].wrapping_add(to_fixed(b[c], LINEAR_BITS));
                }
                *b = [0.0; 3];
            });
        self.camera
            .par_iter_mut()
            .zip(&mut self.camera_batch)
            .for_each(|(e, b)| {
                if *b != [0.0; 4] {
                    for c in 0..4 {
                        e[c] = e[c].wrapping_add(to_fixed(b[c], LINEAR_BITS));
                    }
                    *b = [0.0; 4];
                }
            });
    }

    /// Adds another film's committed sums (a part of the same render with other batches):
    /// exact. The films must have the same size (checked by the caller).
    pub fn merge(&mut self, other: &LightFilm) {
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for c in 0..3 {
                a[c] = a[c].wrapping_add(b[c]);
            }
        }
        for (a, b) in self.camera.iter_mut().zip(&other.camera) {
            for c in 0..4 {
                a[c] = a[c].wrapping_add(b[c]);
            }
        }
    }

    /// Pixel `i`'s committed splat sum (linear RGB).
    pub fn sum(&self, i: usize) -> [f64; 3] {
        self.sums[i].map(|v| v as f64 * f64::powi(2.0, -(LINEAR_BITS as i32)))
    }

    /// Pixel `i`'s value (row-major): the light splats' sum over `n` plus the camera samples'
    /// weighted average.
    pub fn value(&self, i: usize, n: f64) -> [f32; 3] {
        let unit = f64::powi(2.0, -(LINEAR_BITS as i32));
        let c = self.camera[i].map(|v| v as f64 * unit);
        let avg = if c[3] > 0.0 { 1.0 / c[3] } else { 0.0 };
        let s = self.sum(i);
        [0, 1, 2].map(|k| (s[k] / n + c[k] * avg) as f32)
    }

    /// Whether splats under `filter` fit the footprint this film computes at once.
    pub fn supports(filter: &FilterDesc) -> bool {
        2.0 * filter_radius(filter) + 1.0 < MAX_FOOTPRINT as f32
    }

    /// Adds `value` times `scale` at film position `pos` (pixels from the image's top-left
    /// corner) with the normalised filter weights (see the module documentation), to the
    /// current batch.
    #[inline]
    pub fn splat(&mut self, pos: Vec2, value: [f32; 3], scale: f64) {
        let h = self.height as i32;
        let (filter, radius, w) = (self.filter, self.radius, self.width as i32);
        splat_rows(
            &filter,
            radius,
            (w, h),
            0..h,
            &mut self.batch,
            pos,
            value,
            scale,
        );
    }

    /// Adds the splats `(pos, value)` in order, times `scale`, as [`LightFilm::splat`] one by
    /// one would, bit for bit: the image is cut into bands of rows, each band (on its own
    /// thread) adding in order the parts of the splats that reach it, so every pixel receives
    /// the same additions in the same order.
    pub fn splat_all(&mut self, splats: &[(Vec2, [f32; 3])], scale: f64) {
        let (filter, radius, w, h) = (self.filter, self.radius, self.width, self.height);
        in_bands(
            &mut self.batch,
            (w, h),
            radius,
            splats,
            #[inline(always)]
            |band, rows, pos, value| {
                splat_rows(
                    &filter,
                    radius,
                    (w as i32, h as i32),
                    rows,
                    band,
                    pos,
                    value,
                    scale,
                )
            },
        );
    }

    /// Adds camera samples `(pos, value)` in order (see the module documentation), in bands of
    /// rows on all threads as [`LightFilm::splat_all`] does.
    pub fn add_camera_samples(&mut self, samples: &[(Vec2, [f32; 3])]) {
        let (filter, radius, w, h) = (self.filter, self.radius, self.width, self.height);
        in_bands(
            &mut self.camera_batch,
            (w, h),
            radius,
            samples,
            #[inline(always)]
            |band, rows, pos, value| {
                let Some(fp) = Footprint::new(&filter, radius, (w as i32, h as i32), pos) else {
                    return;
                };
                for (j, y) in fp.ys.clone().enumerate() {
                    if !rows.contains(&y) {
                        continue;
                    }
                    let row = ((y - rows.start) * w as i32) as usize;
                    for (k, x) in fp.xs.clone().enumerate() {
                        let weight = f64::from(fp.wx[k] * fp.wy[j]);
                        let s = &mut band[row + x as usize];
                        for c in 0..3 {
                            s[c] += weight * f64::from(value[c]);
                        }
                        s[3] += weight;
                    }
                }
            },
        );
    }
}

/// Runs `add(band, rows, pos, value)` for every splat on the bands of rows of `pixels` it
/// reaches, the bands on all threads, each adding its splats in order.
fn in_bands<T: Send>(
    pixels: &mut [T],
    (w, h): (u32, u32),
    radius: f32,
    splats: &[(Vec2, [f32; 3])],
    add: impl Fn(&mut [T], std::ops::Range<i32>, Vec2, [f32; 3]) + Sync,
) {
    use rayon::prelude::*;
    let (w, h) = (w as i32, h as i32);
    let threads = rayon::current_num_threads().max(1) as i32;
    let rows = (h / (4 * threads)).max(1);
    // A splat at y reaches rows whose centre is within the radius: y - 1/2 +- radius.
    let reach = radius + 0.5;
    pixels
        .par_chunks_mut((rows * w) as usize)
        .enumerate()
        .for_each(|(b, band)| {
            let y0 = b as i32 * rows;
            let y1 = (y0 + rows).min(h);
            crate::isa::best(
                #[inline(always)]
                || {
                    for &(pos, value) in splats {
                        if pos.y + reach >= y0 as f32 && pos.y - reach < y1 as f32 {
                            add(band, y0..y1, pos, value);
                        }
                    }
                },
            )
        });
}

/// The pixels a sample at `pos` reaches (centres within the filter's radius, clipped to the
/// image; the box of radius 1/2: the pixel it falls in) and their separable filter weights.
struct Footprint {
    xs: std::ops::Range<i32>,
    ys: std::ops::Range<i32>,
    wx: [f32; MAX_FOOTPRINT],
    wy: [f32; MAX_FOOTPRINT],
}

impl Footprint {
    #[inline(always)]
    fn new(filter: &FilterDesc, radius: f32, (w, h): (i32, i32), pos: Vec2) -> Option<Footprint> {
        let mut fp = Footprint {
            xs: 0..0,
            ys: 0..0,
            wx: [0.0; MAX_FOOTPRINT],
            wy: [0.0; MAX_FOOTPRINT],
        };
        if matches!(filter, FilterDesc::Box { radius } if *radius <= 0.5) {
            let (x, y) = (pos.x.floor() as i32, pos.y.floor() as i32);
            if !((0..w).contains(&x) && (0..h).contains(&y)) {
                return None;
            }
            (fp.xs, fp.ys) = (x..x + 1, y..y + 1);
            (fp.wx[0], fp.wy[0]) = (1.0, 1.0);
            return Some(fp);
        }
        // Pixels X with |X + 1/2 - x| <= radius, clipped to the image.
        let range = |x: f32, n: i32| {
            let a = ((x - 0.5 - radius).ceil() as i32).max(0);
            let b = ((x - 0.5 + radius).floor() as i32).min(n - 1);
            a..b + 1
        };
        (fp.xs, fp.ys) = (range(pos.x, w), range(pos.y, h));
        if fp.xs.is_empty() || fp.ys.is_empty() {
            return None;
        }
        for (k, x) in fp.xs.clone().enumerate() {
            fp.wx[k] = filter_profile(filter, x as f32 + 0.5 - pos.x);
        }
        for (k, y) in fp.ys.clone().enumerate() {
            fp.wy[k] = filter_profile(filter, y as f32 + 0.5 - pos.y);
        }
        Some(fp)
    }
}

/// The part of one splat (see [`LightFilm::splat`]) that falls in the rows `band` of a
/// `size` image, added to `sums`, which holds exactly those rows. The weights are normalised
/// over the whole clipped footprint, whatever part of it the band holds.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn splat_rows(
    filter: &FilterDesc,
    radius: f32,
    (w, h): (i32, i32),
    band: std::ops::Range<i32>,
    sums: &mut [[f64; 3]],
    pos: Vec2,
    value: [f32; 3],
    scale: f64,
) {
    let Some(fp) = Footprint::new(filter, radius, (w, h), pos) else {
        return;
    };
    let sx: f32 = fp.wx[..fp.xs.len()].iter().sum();
    let sy: f32 = fp.wy[..fp.ys.len()].iter().sum();
    let norm = sx * sy;
    if norm == 0.0 {
        return;
    }
    let v = value.map(|c| scale * f64::from(c) / f64::from(norm));
    for (j, y) in fp.ys.clone().enumerate() {
        if !band.contains(&y) {
            continue;
        }
        let row = ((y - band.start) * w) as usize;
        for (k, x) in fp.xs.clone().enumerate() {
            let weight = f64::from(fp.wx[k] * fp.wy[j]);
            let s = &mut sums[row + x as usize];
            for c in 0..3 {
                s[c] += weight * v[c];
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
                film.commit();
                for c in 0..3 {
                    let total: f64 = (0..80).map(|i| film.sum(i)[c]).sum();
                    let want = 0.5 * [1.0, 2.0, 4.0][c];
                    assert!((total - want).abs() < 1e-5, "{f:?} at {pos}: {total}");
                }
                if let FilterDesc::Box { .. } = f {
                    let touched = film.sums.iter().filter(|s| s[0] != 0).count();
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
        film.commit();
        assert!((film.sum(4 + 1)[0] - 0.25).abs() < 1e-7);
        assert!((film.sum(4 + 2)[0] - 0.75).abs() < 1e-7);
        let total: f64 = (0..12).map(|i| film.sum(i)[0]).sum();
        assert!((total - 1.0).abs() < 1e-7);
    }

    /// Adding splats in row bands on several threads gives the sequential sums bit for bit
    /// (every pixel receives the same additions in the same order), with splats straddling
    /// bands and the image's edges.
    #[test]
    fn banded_splats_equal_sequential_splats() {
        let f = FilterDesc::Gaussian { stddev: 0.5 };
        let splats: Vec<(Vec2, [f32; 3])> = (0..500)
            .map(|k| {
                let t = k as f32;
                (
                    Vec2::new((t * 7.31) % 23.0, (t * 3.17) % 41.0),
                    [1.0 + t * 0.01, 0.5, 0.25 * (t % 3.0)],
                )
            })
            .collect();
        let mut one = LightFilm::new(f, 23, 41);
        for &(p, v) in &splats {
            one.splat(p, v, 0.7);
        }
        let mut banded = LightFilm::new(f, 23, 41);
        rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| banded.splat_all(&splats, 0.7));
        assert!(one
            .batch
            .iter()
            .zip(&banded.batch)
            .all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits)));
    }
}
