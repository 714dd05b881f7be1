//! Mitsuba's film: every sample is placed uniformly in its pixel (its *origin*) and added, with
//! the filter's weight, to every pixel whose filter reaches it; a pixel is its weighted sum
//! divided by its summed weights (Mitsuba 3.9.1's `ImageBlock::put` and the film's
//! normalisation by its weight channel). Neighbouring pixels share samples, so the image's
//! per-pixel noise at equal spp is Mitsuba's (lower than filter importance sampling's under
//! wide filters, and correlated between neighbours).
//!
//! Determinism. Splats cross tile boundaries, so every tile of origin pixels keeps its own
//! accumulator over the pixels its samples can reach (the tile grown by the filter's
//! [`SplatLayout::margin`]). A tile adds the splats of one sample index at a time: the splats of
//! all its origins' sample `k`, in row-major order, into a scratch image of f64 sums, which is
//! then added to the tile's exact sums ([`super::exact`]) and cleared ([`SplatTile::commit`]).
//! Each pixel's sum is then the exact sum over sample indices of numbers that depend on the
//! sample index alone, so it depends on neither the number of threads, nor the passes a render
//! is split into, nor which machine took which sample indices (`--part K/N`): resumed and
//! merged renders are bit-identical to uninterrupted ones. (Rounding once per sample index and
//! tile, not per splat, keeps the exact sums' cost at a few conversions per sample.) The image
//! is the sum of the accumulators ([`SplatFilm::resolve`]). Tiles are aligned to the whole
//! film's grid, so a crop window with `sample_border` adds each of its pixels' splats as the
//! whole film's render does: the same pixels, bit for bit.

use super::exact::{to_fixed, LINEAR_BITS, SQUARE_BITS};
use super::{filter_profile, filter_radius, footprint_weights, MAX_FOOTPRINT};
use pt_math::lanes::lanes;
use pt_math::Vec2;
use pt_scene::FilterDesc;

/// Edge length of a tile of origin pixels. Tiles are aligned to multiples of it in the whole
/// film's coordinates (see the module documentation).
pub const SPLAT_TILE: i32 = 16;

/// The tile grid of a splatting film: which origin pixels each tile holds and which image
/// pixels its accumulator covers. Coordinates are the image's pixels (negative or beyond the
/// image for the border origins of `sample_border`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplatLayout {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// How many pixels beyond its origin a sample can reach: a sample at x in origin pixel X
    /// reaches the pixels whose centre is within the filter's radius r, so up to
    /// ceil(r + 1/2) - 1 pixels away (0 for the box of radius 1/2, 2 for Mitsuba's default
    /// Gaussian of radius 2).
    pub margin: i32,
    /// Origin pixels added around the image on every side: the margin with `sample_border`
    /// (Mitsuba samples that border so that edge pixels see their whole filter), else 0.
    pub border: i32,
    /// Column boundaries of the tiles' origin pixels (`cols[i]..cols[i + 1]` is column i).
    pub cols: Vec<i32>,
    /// Row boundaries of the tiles' origin pixels (as `cols`).
    pub rows: Vec<i32>,
}

impl SplatLayout {
    /// The grid for an image of `width` x `height` pixels whose top-left pixel is the film's
    /// pixel `crop_offset`, under `filter`.
    pub fn new(
        filter: &FilterDesc,
        width: u32,
        height: u32,
        crop_offset: [u32; 2],
        sample_border: bool,
    ) -> SplatLayout {
        let margin = ((filter_radius(filter) + 0.5).ceil() as i32 - 1).max(0);
        let border = if sample_border { margin } else { 0 };
        // Boundaries at the film's multiples of SPLAT_TILE, in image coordinates.
        let cuts = |size: u32, offset: u32| {
            let (lo, hi, off) = (-border, size as i32 + border, offset as i32);
            let mut v = vec![lo];
            let mut x = (lo + off).div_euclid(SPLAT_TILE) * SPLAT_TILE + SPLAT_TILE - off;
            while x < hi {
                v.push(x);
                x += SPLAT_TILE;
            }
            v.push(hi);
            v
        };
        SplatLayout {
            width,
            height,
            margin,
            border,
            cols: cuts(width, crop_offset[0]),
            rows: cuts(height, crop_offset[1]),
        }
    }

    /// Number of tile columns.
    pub fn tile_columns(&self) -> usize {
        self.cols.len() - 1
    }

    /// Number of tile rows.
    pub fn tile_rows(&self) -> usize {
        self.rows.len() - 1
    }

    /// Origin pixels of tile (`i`, `j`): x range and y range.
    pub fn origins(&self, i: usize, j: usize) -> (std::ops::Range<i32>, std::ops::Range<i32>) {
        (
            self.cols[i]..self.cols[i + 1],
            self.rows[j]..self.rows[j + 1],
        )
    }

    /// The origins of tile (`i`, `j`) inside the image: x range and y range (possibly empty).
    pub fn image_origins(
        &self,
        i: usize,
        j: usize,
    ) -> (std::ops::Range<i32>, std::ops::Range<i32>) {
        let (xs, ys) = self.origins(i, j);
        let clip = |r: std::ops::Range<i32>, n: u32| r.start.max(0)..r.end.min(n as i32).max(0);
        (clip(xs, self.width), clip(ys, self.height))
    }

    /// Every image pixel's index (row-major) in tile-major order: tile after tile (row-major
    /// over the grid), each tile's image origins row-major. Statistics kept per origin in this
    /// order give each tile a contiguous slice.
    pub fn tile_major_pixels(&self) -> Vec<usize> {
        let mut order = Vec::with_capacity(self.width as usize * self.height as usize);
        for j in 0..self.tile_rows() {
            for i in 0..self.tile_columns() {
                let (xs, ys) = self.image_origins(i, j);
                for y in ys {
                    for x in xs.clone() {
                        order.push(y as usize * self.width as usize + x as usize);
                    }
                }
            }
        }
        order
    }

    /// The empty accumulator of tile (`i`, `j`) for `channels` values per sample: its origins
    /// grown by the margin, clipped to the image.
    fn tile(&self, i: usize, j: usize, channels: usize, squares_from: usize) -> SplatTile {
        let (xs, ys) = self.origins(i, j);
        let m = self.margin;
        let x0 = (xs.start - m).max(0);
        let y0 = (ys.start - m).max(0);
        let x1 = (xs.end + m).min(self.width as i32);
        let y1 = (ys.end + m).min(self.height as i32);
        let (w, h) = ((x1 - x0).max(0), (y1 - y0).max(0));
        let pitch = w as usize + ROW_LANES - 1;
        SplatTile {
            x0,
            y0,
            w,
            h,
            stride: channels + 1,
            squares_from,
            sums: vec![0; (w * h) as usize * (channels + 1)],
            pitch,
            scratch: vec![0.0; h as usize * pitch * (channels + 1)],
        }
    }
}

/// Fractional bits of the exact sum at position `c` of a pixel's `stride` sums whose values
/// from `squares_from` on (up to the weight, the last) are squares: see
/// [`SplatTile::frac_bits`].
#[inline(always)]
fn grid_bits(squares_from: usize, stride: usize, c: usize) -> u32 {
    if (squares_from..stride - 1).contains(&c) {
        SQUARE_BITS
    } else {
        LINEAR_BITS
    }
}

/// Pixels of a footprint's row that a splat adds at once (a 4-wide f64 vector): the footprints
/// of the usual filters (box, tent, Gaussian, Mitchell: up to 5 pixels) take one or two steps.
const ROW_LANES: usize = 4;

/// The accumulator of one tile: per covered image pixel the weighted sums of each of a
/// sample's values (filter weight times value: linear RGB radiance and alpha for the image,
/// then, in moment renders, the squared X, Y, Z), and the summed weight.
#[derive(Clone, Debug, PartialEq)]
pub struct SplatTile {
    /// Image column of the accumulator's first pixel.
    pub x0: i32,
    /// Image row of the accumulator's first pixel.
    pub y0: i32,
    /// Width, pixels.
    pub w: i32,
    /// Height, pixels.
    pub h: i32,
    /// Sums per pixel: one per value, then the weight.
    pub stride: usize,
    /// The first value that is a square (kept on the finer grid of squares); `stride - 1`
    /// when none is.
    pub squares_from: usize,
    /// Row-major exact sums ([`super::exact`]), `stride` per pixel: weight times each value,
    /// and the weight; in units of 2^-[`SplatTile::frac_bits`] of the value's position.
    pub sums: Vec<i128>,
    /// Length of a row of `scratch`: the width and room for a last step of [`ROW_LANES`]
    /// that starts at the last pixel.
    pitch: usize,
    /// The splats of the current sample index, not yet in `sums` (zero between
    /// [`SplatTile::commit`]s; not part of the film's state): one plane per sum (`stride`
    /// planes of `h` rows of `pitch`), so that a footprint's row of one value is contiguous and
    /// is added in vector steps.
    scratch: Vec<f64>,
}

impl SplatTile {
    /// Fractional bits of the exact sum at position `c` of a pixel's values: squared values
    /// (positions from [`SplatTile::squares_from`] to the weight) on [`SQUARE_BITS`], the rest
    /// on [`LINEAR_BITS`].
    #[inline]
    pub fn frac_bits(&self, c: usize) -> u32 {
        grid_bits(self.squares_from, self.stride, c)
    }

    /// Adds the splats made since the last commit (one sample index's, see the module
    /// documentation) to the exact sums and clears them. Inlined into the render loop (compiled
    /// for its instruction sets: the conversions' variable shifts are single instructions there).
    #[inline(always)]
    pub fn commit(&mut self) {
        let (stride, w, pitch) = (self.stride, self.w as usize, self.pitch);
        let plane = self.h as usize * pitch;
        if plane == 0 {
            return;
        }
        for (c, scratch) in self.scratch.chunks_exact_mut(plane).enumerate() {
            let bits = grid_bits(self.squares_from, stride, c);
            // Row by row: the padding beyond `w` only ever receives zeros (see `splat`).
            for (r, row) in scratch.chunks_exact_mut(pitch).enumerate() {
                let sums = self.sums[r * w * stride..][..w * stride].chunks_exact_mut(stride);
                for (sum, s) in sums.zip(&mut row[..w]) {
                    if *s != 0.0 {
                        sum[c] = sum[c].wrapping_add(to_fixed(*s, bits));
                        *s = 0.0;
                    }
                }
            }
        }
    }

    /// Adds a sample's `values` (as many as the accumulator's channels) taken at `u` (in [0, 1)^2) within origin
    /// pixel `origin` (image pixels) to every covered pixel whose filter reaches it, with the
    /// separable weight f(X + 1/2 - x) f(Y + 1/2 - y) at the sample's position (x, y)
    /// (Mitsuba's product of 1D profiles), into the scratch sums that [`SplatTile::commit`]
    /// adds to the tile's. The distances are computed from the whole-pixel
    /// difference X - origin and `u`, so they are the same numbers whatever the image's place
    /// in the film (a crop window's pixels splat exactly as the whole film's). Always inlined:
    /// the render loop is compiled for the processor's instruction sets ([`crate::isa::best`]), and
    /// an outlined copy is compiled for the baseline, where `floor` and `ceil` are libm calls.
    #[inline(always)]
    pub fn splat(
        &mut self,
        filter: &FilterDesc,
        radius: f32,
        origin: [i32; 2],
        u: Vec2,
        values: &[f32],
    ) {
        debug_assert_eq!(values.len() + 1, self.stride);
        // Pixels X with |X + 1/2 - (x0 + u)| <= radius, as whole-pixel differences d = X - x0.
        let range = |u: f32, x0: i32, lo: i32, n: i32| {
            let a = (x0 + (u - 0.5 - radius).ceil() as i32).max(lo);
            let b = (x0 + (u - 0.5 + radius).floor() as i32).min(lo + n - 1);
            a..b + 1
        };
        let xs = range(u.x, origin[0], self.x0, self.w);
        let ys = range(u.y, origin[1], self.y0, self.h);
        if xs.is_empty() || ys.is_empty() {
            return;
        }
        let weight = |d: i32, u: f32| filter_profile(filter, d as f32 + 0.5 - u);
        let (mut wx, mut wy) = ([0.0f32; MAX_FOOTPRINT], [0.0f32; MAX_FOOTPRINT]);
        let cached = xs.len() <= MAX_FOOTPRINT && ys.len() <= MAX_FOOTPRINT;
        if cached {
            footprint_weights(filter, xs.start - origin[0], xs.len(), u.x, &mut wx);
            footprint_weights(filter, ys.start - origin[1], ys.len(), u.y, &mut wy);
        }
        let plane = self.h as usize * self.pitch;
        for (j, y) in ys.enumerate() {
            let wy = if cached {
                wy[j]
            } else {
                weight(y - origin[1], u.y)
            };
            if wy == 0.0 {
                continue;
            }
            let row = (y - self.y0) as usize * self.pitch + (xs.start - self.x0) as usize;
            let len = xs.len();
            if !cached {
                // Footprints wider than MAX_FOOTPRINT (huge filters), pixel by pixel.
                for (k, x) in xs.clone().enumerate() {
                    let w = f64::from(wy * weight(x - origin[0], u.x));
                    for (c, v) in values
                        .iter()
                        .map(|&v| f64::from(v))
                        .chain([1.0])
                        .enumerate()
                    {
                        self.scratch[c * plane + row + k] += w * v;
                    }
                }
                continue;
            }
            // ROW_LANES pixels at a time, each value's plane in one vector step; lanes beyond
            // the footprint weigh 0 (and add zeros: the values are finite, `fits`).
            for c0 in (0..len).step_by(ROW_LANES) {
                let w: [f64; ROW_LANES] = lanes(|k| {
                    let x = c0 + k;
                    let w = f64::from(wy * wx[x % MAX_FOOTPRINT]);
                    if x < len {
                        w
                    } else {
                        0.0
                    }
                });
                let mut add = |at: usize, v: f64| {
                    let s: &mut [f64; ROW_LANES] = (&mut self.scratch[at..at + ROW_LANES])
                        .try_into()
                        .expect("a step of ROW_LANES");
                    for (s, w) in s.iter_mut().zip(w) {
                        *s += w * v;
                    }
                };
                let mut at = row + c0;
                for &v in values {
                    add(at, f64::from(v));
                    at += plane;
                }
                // The weight (times 1: the same bits as the weight itself).
                add(at, 1.0);
            }
        }
    }
}

/// The splatting film of a render: its grid and one accumulator per tile (row-major over the
/// grid, so that the tiles of one row of the grid are contiguous).
#[derive(Clone, Debug, PartialEq)]
pub struct SplatFilm {
    /// The grid.
    pub layout: SplatLayout,
    /// Values per sample.
    pub channels: usize,
    /// The tiles' accumulators.
    pub tiles: Vec<SplatTile>,
}

impl SplatFilm {
    /// An empty film with `layout` for samples of `channels` values.
    pub fn new(layout: SplatLayout, channels: usize) -> SplatFilm {
        SplatFilm::with_squares(layout, channels, channels)
    }

    /// An empty film with `layout` for samples of `channels` values, those from position
    /// `squares_from` on being squares (kept on the grid of squares, [`SQUARE_BITS`]).
    pub fn with_squares(layout: SplatLayout, channels: usize, squares_from: usize) -> SplatFilm {
        let tiles = (0..layout.tile_rows())
            .flat_map(|j| (0..layout.tile_columns()).map(move |i| (i, j)))
            .map(|(i, j)| layout.tile(i, j, channels, squares_from.min(channels)))
            .collect();
        SplatFilm {
            layout,
            channels,
            tiles,
        }
    }

    /// The image's sums (per pixel, row-major: weight times each value, then the weight),
    /// every pixel's accumulators added exactly.
    pub fn resolve(&self) -> Vec<f64> {
        let stride = self.channels + 1;
        let w = self.layout.width as usize;
        let Some(first) = self.tiles.first() else {
            return Vec::new();
        };
        let bits: Vec<u32> = (0..stride).map(|c| first.frac_bits(c)).collect();
        let mut exact = vec![0i128; w * self.layout.height as usize * stride];
        for t in &self.tiles {
            for (r, row) in t
                .sums
                .chunks_exact(t.w.max(1) as usize * stride)
                .enumerate()
            {
                let start = ((t.y0 as usize + r) * w + t.x0 as usize) * stride;
                for (o, s) in exact[start..start + row.len()].iter_mut().zip(row) {
                    *o = o.wrapping_add(*s);
                }
            }
        }
        exact
            .iter()
            .enumerate()
            .map(|(i, &v)| v as f64 * f64::powi(2.0, -(bits[i % stride] as i32)))
            .collect()
    }

    /// Adds another film's sums (a part of the same render with other sample indices): exact.
    /// The films must have the same layout and channels (checked by the caller).
    pub fn merge(&mut self, other: &SplatFilm) {
        for (a, b) in self.tiles.iter_mut().zip(&other.tiles) {
            for (x, y) in a.sums.iter_mut().zip(&b.sums) {
                *x = x.wrapping_add(*y);
            }
        }
    }

    /// The image, one row-major plane per value: each pixel's weighted sum over its summed
    /// weight (0 where no weight arrived).
    pub fn planes(&self) -> Vec<Vec<f32>> {
        let stride = self.channels + 1;
        let sums = self.resolve();
        (0..self.channels)
            .map(|c| {
                sums.chunks_exact(stride)
                    .map(|s| match s[stride - 1] {
                        0.0 => 0.0,
                        w => (s[c] / w) as f32,
                    })
                    .collect()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid's boundaries fall on the film's multiples of the tile size, cover the origins
    /// (with the border), and the margin is ceil(r + 1/2) - 1.
    #[test]
    fn layout_is_aligned_to_the_film() {
        let g = FilterDesc::Gaussian { stddev: 0.5 };
        let l = SplatLayout::new(&g, 40, 20, [7, 0], true);
        assert_eq!((l.margin, l.border), (2, 2));
        assert_eq!(l.cols, vec![-2, 9, 25, 41, 42]);
        assert_eq!(l.rows, vec![-2, 0, 16, 22]);
        let b = SplatLayout::new(&FilterDesc::Box { radius: 0.5 }, 40, 20, [0, 0], true);
        assert_eq!((b.margin, b.border), (0, 0));
        assert_eq!(b.cols, vec![0, 16, 32, 40]);
        let t = SplatLayout::new(&FilterDesc::Tent { radius: 1.0 }, 40, 20, [0, 0], false);
        assert_eq!((t.margin, t.border), (1, 0));
    }

    /// A sample's weights are the filter's at the covered pixels' centres: the tent of radius
    /// 1 at (2.25, 1.5) reaches pixels 1 and 2 in x (weights 0.25, 0.75) and only pixel 1 in
    /// y (weight 1; pixels 0 and 2 have centres exactly 1 away, weight 0).
    #[test]
    fn splat_weights_are_the_filter_at_pixel_centres() {
        let tent = FilterDesc::Tent { radius: 1.0 };
        let mut film = SplatFilm::new(SplatLayout::new(&tent, 4, 3, [0, 0], false), 4);
        film.tiles[0].splat(
            &tent,
            1.0,
            [2, 1],
            Vec2::new(0.25, 0.5),
            &[2.0, 0.0, 0.0, 1.0],
        );
        film.tiles[0].commit();
        let s = film.resolve();
        let at = |x: usize, y: usize, c: usize| s[(y * 4 + x) * 5 + c];
        assert!((at(1, 1, 4) - 0.25).abs() < 1e-7 && (at(2, 1, 4) - 0.75).abs() < 1e-7);
        assert!((at(2, 1, 0) - 1.5).abs() < 1e-6);
        assert!((at(2, 1, 3) - 0.75).abs() < 1e-6);
        let total: f64 = s.chunks_exact(5).map(|p| p[4]).sum();
        assert!((total - 1.0).abs() < 1e-6, "{total}");
    }

    /// A constant image stays constant to rounding, border pixels included, with and without
    /// `sample_border`, for every filter (the closed form): each pixel's weighted sum
    /// over its weights of a constant is the constant whatever weights arrive. Samples on a
    /// jittered grid over the origins, as the renderer places them.
    #[test]
    fn constant_image_stays_constant() {
        for f in [
            FilterDesc::Gaussian { stddev: 0.5 },
            FilterDesc::Tent { radius: 1.5 },
            FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
            },
            FilterDesc::Lanczos { lobes: 3.0 },
        ] {
            for border in [false, true] {
                let layout = SplatLayout::new(&f, 21, 18, [3, 5], border);
                let mut film = SplatFilm::new(layout.clone(), 4);
                let r = filter_radius(&f);
                for j in 0..layout.tile_rows() {
                    for i in 0..layout.tile_columns() {
                        let (xs, ys) = layout.origins(i, j);
                        let t = &mut film.tiles[j * layout.tile_columns() + i];
                        for y in ys.clone() {
                            for x in xs.clone() {
                                for k in 0..4 {
                                    let u = Vec2::new(
                                        0.25 + 0.5 * (k % 2) as f32,
                                        0.25 + 0.5 * (k / 2) as f32,
                                    );
                                    t.splat(&f, r, [x, y], u, &[0.7, 0.2, 3.0, 0.6]);
                                    t.commit();
                                }
                            }
                        }
                    }
                }
                let planes = film.planes();
                for (c, want) in [0.7f32, 0.2, 3.0, 0.6].iter().enumerate() {
                    for (k, v) in planes[c].iter().enumerate() {
                        assert!(
                            (v - want).abs() < 1e-5 * want,
                            "{f:?} border {border} channel {c} pixel {k}: {v}"
                        );
                    }
                }
            }
        }
    }
}
