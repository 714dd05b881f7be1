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
use super::{filter_radius, footprint_weights, MAX_FOOTPRINT};
use pt_math::Vec2;
use pt_scene::FilterDesc;

/// One contribution to the image: where it lands and its linear RGB value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// Film position, pixels from the image's top-left corner.
    pub film: Vec2,
    /// Linear RGB: a light splat's before the batch's scale, a camera sample's radiance.
    pub rgb: [f32; 3],
    /// Whether it is a camera sample (the bidirectional methods': averaged with the filter's
    /// weights, see the module documentation) rather than a light splat.
    pub camera: bool,
}

/// The accumulated splats of a light-path render.
#[derive(Clone, Debug)]
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
    /// Per pixel, the current batch's unfiltered value (zero between batches; not state).
    unfiltered: Vec<[f64; 3]>,
    /// Per list of the current batch and per band of rows, the list's samples that reach the
    /// band, and the pixels of its non-finite samples (scratch kept for its memory; not state).
    listed: Vec<(Vec<Vec<Splat>>, Vec<usize>)>,
}

/// Films are equal when their size, filter and committed sums are (the current batch and the
/// scratch lists are not part of the film).
impl PartialEq for LightFilm {
    fn eq(&self, other: &Self) -> bool {
        (
            self.width,
            self.height,
            self.filter,
            &self.sums,
            &self.camera,
        ) == (
            other.width,
            other.height,
            other.filter,
            &other.sums,
            &other.camera,
        )
    }
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
            unfiltered: vec![[0.0; 3]; width as usize * height as usize],
            listed: Vec::new(),
        }
    }

    /// Adds the current batch's splats and camera samples to the exact sums and clears them.
    pub fn commit(&mut self) {
        commit_rows(
            &mut self.sums,
            &mut self.batch,
            &mut self.camera,
            &mut self.camera_batch,
        );
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

    /// Adds one batch (one light path per pixel, see the module documentation) and commits it:
    /// the samples of `lists` in order, light splats times `scale` through the filter, camera
    /// samples into the pixels' weighted averages; and into `pixels[i]` (row-major) the batch's
    /// unfiltered value of pixel i (the light splats landing in it times `scale`, plus its
    /// camera samples) as one sample of its statistics. Non-finite samples are counted in
    /// their pixel's statistics and dropped. The same sums, bit for bit, as adding the samples
    /// one by one ([`LightFilm::splat`]): the image is cut into bands of rows, the samples of
    /// each list are listed (in order, the lists in parallel) for the bands they reach, and
    /// each band adds what the lists listed for it, list after list, on its own thread, so
    /// every pixel receives the same additions in the same order for any number of threads.
    pub fn add_batch<L: AsRef<[Splat]> + Sync>(
        &mut self,
        lists: &[L],
        scale: f64,
        pixels: &mut [super::PixelStats],
    ) {
        use rayon::prelude::*;
        let (filter, radius) = (self.filter, self.radius);
        let (w, h) = (self.width as i32, self.height as i32);
        let threads = rayon::current_num_threads().max(1) as i32;
        // Two bands per thread: a splat weighs its whole footprint in every band it reaches,
        // so more bands cost more (four per thread: 3-8% slower on the caustic scenes, eight:
        // 15-20%), and one per thread (3% faster there) leaves a thread idle when the light
        // lands in one half of the image.
        let rows = (h / (2 * threads)).max(1);
        let n_bands = (h as u32).div_ceil(rows as u32) as usize;
        // A sample at y reaches the rows whose centre is within the radius, y - 1/2 +- radius
        // (and its own pixel's row: the box of radius 1/2 keeps that one).
        let reach = radius.max(0.5) + 0.5;
        // Listing on one thread left the other idle a quarter of a light-tracing render.
        self.listed.resize_with(lists.len(), Default::default);
        lists
            .par_iter()
            .zip(self.listed.par_iter_mut())
            .for_each(|(list, (bands, nonfinite))| {
                bands.resize_with(n_bands, Vec::new);
                bands.iter_mut().for_each(Vec::clear);
                nonfinite.clear();
                for sp in list.as_ref() {
                    if !sp.rgb.iter().all(|c| c.is_finite()) {
                        nonfinite.push(own_pixel(sp.film, w, h));
                        continue;
                    }
                    let lo = ((sp.film.y - reach).floor() as i32).clamp(0, h - 1) / rows;
                    let hi = ((sp.film.y + reach).floor() as i32).clamp(0, h - 1) / rows;
                    for band in &mut bands[lo as usize..=hi as usize] {
                        band.push(*sp);
                    }
                }
            });
        for (_, nonfinite) in &self.listed[..lists.len()] {
            for &i in nonfinite {
                pixels[i].nonfinite += 1;
            }
        }
        let listed = &self.listed[..lists.len()];
        let band_len = (rows * w) as usize;
        self.batch
            .par_chunks_mut(band_len)
            .zip(self.camera_batch.par_chunks_mut(band_len))
            .zip(self.unfiltered.par_chunks_mut(band_len))
            .zip(self.sums.par_chunks_mut(band_len))
            .zip(self.camera.par_chunks_mut(band_len))
            .zip(pixels.par_chunks_mut(band_len))
            .enumerate()
            .for_each(
                |(b, (((((batch, camera_batch), unfiltered), sums), camera), stats))| {
                    let y0 = b as i32 * rows;
                    let band = y0..(y0 + rows).min(h);
                    let first = (y0 * w) as usize;
                    crate::isa::best(
                        #[inline(always)]
                        || {
                            for sp in listed.iter().flat_map(|(bands, _)| &bands[b]) {
                                let k = if sp.camera {
                                    add_camera_rows(
                                        &filter,
                                        radius,
                                        (w, h),
                                        &band,
                                        camera_batch,
                                        sp,
                                    );
                                    1.0
                                } else {
                                    splat_rows(
                                        &filter,
                                        radius,
                                        (w, h),
                                        band.clone(),
                                        batch,
                                        sp.film,
                                        sp.rgb,
                                        scale,
                                    );
                                    scale
                                };
                                let pixel = own_pixel(sp.film, w, h);
                                if let Some(u) =
                                    pixel.checked_sub(first).and_then(|i| unfiltered.get_mut(i))
                                {
                                    for c in 0..3 {
                                        u[c] += k * f64::from(sp.rgb[c]);
                                    }
                                }
                            }
                        },
                    );
                    for (stat, u) in stats.iter_mut().zip(unfiltered.iter_mut()) {
                        stat.add(u.map(|c| c as f32), 0.0);
                        *u = [0.0; 3];
                    }
                    commit_rows(sums, batch, camera, camera_batch);
                },
            );
    }
}

/// The pixel (row-major index) a sample at `pos` falls in, clamped to the image.
#[inline(always)]
fn own_pixel(pos: Vec2, w: i32, h: i32) -> usize {
    let (x, y) = (pos.x as usize, pos.y as usize);
    y.min(h as usize - 1) * w as usize + x.min(w as usize - 1)
}

/// Adds the batch's sums of some pixels, `batch` and `camera_batch`, to the exact sums of the
/// same pixels, `sums` and `camera`, and clears them.
fn commit_rows(
    sums: &mut [[i128; 3]],
    batch: &mut [[f64; 3]],
    camera: &mut [[i128; 4]],
    camera_batch: &mut [[f64; 4]],
) {
    for (e, b) in sums.iter_mut().zip(batch) {
        for c in 0..3 {
            e[c] = e[c].wrapping_add(to_fixed(b[c], LINEAR_BITS));
        }
        *b = [0.0; 3];
    }
    for (e, b) in camera.iter_mut().zip(camera_batch) {
        if *b != [0.0; 4] {
            for c in 0..4 {
                e[c] = e[c].wrapping_add(to_fixed(b[c], LINEAR_BITS));
            }
            *b = [0.0; 4];
        }
    }
}

/// The part of camera sample `sp` that falls in the rows `band`, added to `sums` (which holds
/// exactly those rows): its value and its filter weight, for the weighted average.
#[inline(always)]
fn add_camera_rows(
    filter: &FilterDesc,
    radius: f32,
    (w, h): (i32, i32),
    band: &std::ops::Range<i32>,
    sums: &mut [[f64; 4]],
    sp: &Splat,
) {
    let Some(fp) = Footprint::new(filter, radius, (w, h), sp.film) else {
        return;
    };
    fp.in_rows(band, w, |i, weight| {
        let s = &mut sums[i];
        for c in 0..3 {
            s[c] += weight * f64::from(sp.rgb[c]);
        }
        s[3] += weight;
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
    /// Calls `add(i, weight)` for each pixel of the footprint in the rows `band` of an image
    /// `w` pixels wide: `i` indexes the band's pixels (row-major), `weight` is the pixel's
    /// filter weight, unnormalised.
    #[inline(always)]
    fn in_rows(&self, band: &std::ops::Range<i32>, w: i32, mut add: impl FnMut(usize, f64)) {
        for (j, y) in self.ys.clone().enumerate() {
            if !band.contains(&y) {
                continue;
            }
            let row = ((y - band.start) * w) as usize;
            for (k, x) in self.xs.clone().enumerate() {
                add(row + x as usize, f64::from(self.wx[k] * self.wy[j]));
            }
        }
    }

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
        footprint_weights(filter, fp.xs.start, fp.xs.len(), pos.x, &mut fp.wx);
        footprint_weights(filter, fp.ys.start, fp.ys.len(), pos.y, &mut fp.wy);
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
    fp.in_rows(&band, w, |i, weight| {
        let s = &mut sums[i];
        for c in 0..3 {
            s[c] += weight * v[c];
        }
    });
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

    /// Adding a batch in row bands on several threads, as one list or cut into several, gives
    /// the sequential sums bit for bit
    /// (every pixel receives the same additions in the same order), with splats straddling
    /// bands and the image's edges: the light splats as [`LightFilm::splat`] one by one adds
    /// them, camera samples and pixel statistics the same for one thread and for three.
    #[test]
    fn banded_batches_equal_sequential_splats() {
        let f = FilterDesc::Gaussian { stddev: 0.5 };
        let (w, h) = (23, 41);
        let splats: Vec<Splat> = (0..500)
            .map(|k| {
                let t = k as f32;
                Splat {
                    film: Vec2::new((t * 7.31) % 23.0, (t * 3.17) % 41.0),
                    rgb: [1.0 + t * 0.01, 0.5, 0.25 * (t % 3.0)],
                    camera: k % 5 == 0,
                }
            })
            .collect();
        let lights: Vec<Splat> = splats.iter().filter(|s| !s.camera).copied().collect();
        let mut one = LightFilm::new(f, w, h);
        for s in &lights {
            one.splat(s.film, s.rgb, 0.7);
        }
        one.commit();
        let banded = |threads: usize, lists: &[&[Splat]]| {
            let mut film = LightFilm::new(f, w, h);
            let mut pixels = vec![super::super::PixelStats::default(); (w * h) as usize];
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| film.add_batch(lists, 0.7, &mut pixels));
            (film, pixels)
        };
        assert_eq!(banded(3, &[&lights]).0.sums, one.sums);
        // The same samples cut into lists (listed in parallel): the same sums in list order.
        let cut: Vec<&[Splat]> = lights.chunks(37).collect();
        assert_eq!(banded(3, &cut).0.sums, one.sums);
        let (a, pa) = banded(1, &[&splats]);
        let (b, pb) = banded(3, &[&splats]);
        let cut: Vec<&[Splat]> = splats.chunks(29).collect();
        let (c, pc) = banded(2, &cut);
        assert_eq!(a, b);
        assert_eq!(pa, pb);
        assert_eq!(a, c);
        assert_eq!(pa, pc);
        assert!(a.camera.iter().any(|c| c[3] != 0));
        // Each pixel's statistics got one sample: the unfiltered sum of what landed in it.
        assert!(pa.iter().all(|p| p.n == 1));
        // A non-finite sample is counted in its own pixel, from whichever list it is in.
        let mut bad = splats.clone();
        bad[123].rgb[1] = f32::NAN;
        let cut: Vec<&[Splat]> = bad.chunks(29).collect();
        let (_, pn) = banded(2, &cut);
        let own = own_pixel(bad[123].film, w as i32, h as i32);
        assert_eq!(pn[own].nonfinite, 1);
        assert_eq!(pn.iter().map(|p| p.nonfinite).sum::<u32>(), 1);
    }
}
