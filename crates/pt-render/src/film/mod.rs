//! The film: pixel filters, per-pixel sample statistics and the two ways samples become
//! pixels ([`pt_scene::Reconstruction`]): Mitsuba's splatting ([`splat`]) and filter importance
//! sampling (here).
//!
//! Filter importance sampling places samples with the pixel filter's shape as the density of
//! sub-pixel offsets, which has the same expectation as Mitsuba's weighted splatting (with its
//! `sample_border` semantics at the image's edges: [`sample_pixel_offset`]) and keeps every
//! pixel independent (so tiles need no locks). Box, tent and Gaussian filters are sampled
//! exactly and every sample has weight 1. Filters with negative lobes (Mitchell-Netravali,
//! Catmull-Rom, Lanczos) are sampled from a table of their absolute value, and each sample
//! carries the weight f(x) / (p(x) integral f), negative where the filter is (pbrt-v4's
//! `FilterSampler`, per axis since these filters are separable as in Mitsuba).

use pt_math::lanes::lanes;
use pt_math::{fastmath, Vec2};
use pt_scene::{FilterDesc, PixelFormat};
use pt_spectrum::srgb_to_xyz;
use std::sync::Arc;

use crate::sampler::RandomSource;

pub mod exact;
pub mod light;
pub mod splat;

/// exp(-8), the Gaussian filter's value at its radius of 4 standard deviations, rounded to f32
/// (equal to `(-8f32).exp()`, by test).
const GAUSSIAN_TAIL: f32 = 3.354_626_3e-4;

/// The 1D profile of a separable filter at offset `x` (pixels), as Mitsuba 3.9.1 evaluates it
/// (`eval`; its Gaussian's exponential to within an ulp, [`pt_math::fastmath::exp`]), even in
/// x; 0 outside the radius. One lane of [`filter_profiles`].
#[inline(always)]
pub fn filter_profile(filter: &FilterDesc, x: f32) -> f32 {
    filter_profiles(filter, &[x])[0]
}

/// [`filter_profile`] at `L` offsets at once: the filter is matched once and each model's
/// formula runs over the lanes, which the compiler vectorises (a footprint's weights in one
/// SIMD pass). Always inlined (as [`splat::SplatTile::splat`], which calls it per sample).
#[inline(always)]
pub fn filter_profiles<const L: usize>(filter: &FilterDesc, x: &[f32; L]) -> [f32; L] {
    let x: [f32; L] = lanes(|k| x[k].abs());
    match *filter {
        FilterDesc::Box { radius } => lanes(|k| f32::from(u8::from(x[k] <= radius))),
        // Mitsuba's form, by the inverse radius (the same values for its default radius 1).
        FilterDesc::Tent { radius } => {
            let inv_radius = 1.0 / radius;
            lanes(|k| (1.0 - x[k] * inv_radius).max(0.0))
        }
        // exp(alpha x^2), alpha = -1 / (2 stddev^2) (Mitsuba's form), cut at radius 4 stddev
        // and lowered by its value there, exp(-4^2 / 2) = exp(-8).
        FilterDesc::Gaussian { stddev } => {
            let alpha = -1.0 / (2.0 * stddev * stddev);
            lanes(|k| (fastmath::exp(alpha * (x[k] * x[k])) - GAUSSIAN_TAIL).max(0.0))
        }
        // Mitchell & Netravali 1988, eq. 8, on radius 2.
        FilterDesc::Mitchell { b, c } => lanes(|k| {
            let x = x[k];
            let (x2, x3) = (x * x, x * x * x);
            let v = if x < 1.0 {
                (12.0 - 9.0 * b - 6.0 * c) * x3
                    + (-18.0 + 12.0 * b + 6.0 * c) * x2
                    + (6.0 - 2.0 * b)
            } else if x < 2.0 {
                (-b - 6.0 * c) * x3
                    + (6.0 * b + 30.0 * c) * x2
                    + (-12.0 * b - 48.0 * c) * x
                    + (8.0 * b + 24.0 * c)
            } else {
                0.0
            };
            v / 6.0
        }),
        FilterDesc::Lanczos { lobes } => lanes(|k| {
            let x = x[k];
            if x >= lobes {
                return 0.0;
            }
            let sinc = |t: f32| {
                if t < 1e-5 {
                    1.0
                } else {
                    let pt = std::f32::consts::PI * t;
                    pt.sin() / pt
                }
            };
            sinc(x) * sinc(x / lobes)
        }),
    }
}

/// Most pixels per axis whose filter weights a splat computes at once (a filter radius up to
/// 15.5 pixels): the splatting film computes wider footprints pixel by pixel, the light
/// tracer's film refuses them. A multiple of [`WEIGHT_LANES`].
pub(crate) const MAX_FOOTPRINT: usize = 32;

/// Weights computed at once (SIMD lanes): the footprint of every filter Mitsuba users pick by
/// default or name (box, tent, Gaussian, Mitchell, Catmull-Rom: at most 5 pixels; Lanczos
/// with 3 lobes: 7) in one pass.
const WEIGHT_LANES: usize = 8;

/// The filter's weights f(X + 1/2 - frac) along one axis for the `len` pixels X = `first`,
/// `first + 1`, ... (at most [`MAX_FOOTPRINT`]), into `out`, [`WEIGHT_LANES`] at a time (one
/// SIMD pass for the usual filters). `first` and `frac` are in whichever coordinates the
/// caller keeps its sample position: whole pixels relative to the sample's origin pixel and
/// the offset in it (the splatting film), or image pixels and the position (the light
/// tracer's film). Entries from `len` up to the next multiple of [`WEIGHT_LANES`] get the
/// weights of the pixels beyond; callers read the first `len`. A function, not a closure:
/// closures were compiled outside the render loop's instruction sets.
#[inline(always)]
pub(crate) fn footprint_weights(
    filter: &FilterDesc,
    first: i32,
    len: usize,
    frac: f32,
    out: &mut [f32; MAX_FOOTPRINT],
) {
    for c in (0..len).step_by(WEIGHT_LANES) {
        let d: [f32; WEIGHT_LANES] = lanes(|k| (first + (c + k) as i32) as f32 + 0.5 - frac);
        out[c..c + WEIGHT_LANES].copy_from_slice(&filter_profiles(filter, &d));
    }
}

/// Radius of a filter's support, pixels.
pub fn filter_radius(filter: &FilterDesc) -> f32 {
    match *filter {
        FilterDesc::Box { radius } | FilterDesc::Tent { radius } => radius,
        FilterDesc::Gaussian { stddev } => 4.0 * stddev,
        FilterDesc::Mitchell { .. } => 2.0,
        FilterDesc::Lanczos { lobes } => lobes,
    }
}

/// Bins per pixel of the table a signed filter is sampled from. The weight f / p then varies
/// within a bin only by the filter's change over 1/64 pixel (a few per cent on its steepest
/// slopes), which costs a little variance and no bias.
const TABLE_BINS_PER_PIXEL: f32 = 64.0;

/// A signed filter's 1D profile tabulated for sampling: a piecewise-constant density
/// proportional to |f| over [-radius, radius], and the cumulative signed integral for the
/// image-edge normalisation.
#[derive(Debug)]
struct SignedTable {
    radius: f32,
    /// Bin width, pixels.
    h: f32,
    /// Cumulative probability at the bin edges (0 .. 1).
    cdf: Vec<f64>,
    /// Cumulative integral of f at the bin edges (pixels).
    cum_f: Vec<f64>,
    /// Integral of f over the whole support.
    norm: f64,
}

impl SignedTable {
    fn new(filter: &FilterDesc) -> SignedTable {
        let radius = filter_radius(filter);
        let bins = (2.0 * radius * TABLE_BINS_PER_PIXEL).ceil() as usize;
        let h = 2.0 * radius / bins as f32;
        // 16-point midpoint rule per bin for both integrals.
        let sub = 16;
        let (mut cdf, mut cum_f) = (vec![0.0f64], vec![0.0f64]);
        for i in 0..bins {
            let x0 = -radius + i as f32 * h;
            let (mut abs, mut signed) = (0.0f64, 0.0f64);
            for j in 0..sub {
                let x = x0 + (j as f32 + 0.5) * h / sub as f32;
                let f = filter_profile(filter, x) as f64;
                abs += f.abs();
                signed += f;
            }
            let w = h as f64 / sub as f64;
            cdf.push(cdf[i] + abs * w);
            cum_f.push(cum_f[i] + signed * w);
        }
        let total = *cdf.last().expect("bins");
        cdf.iter_mut().for_each(|c| *c /= total);
        let norm = *cum_f.last().expect("bins");
        SignedTable {
            radius,
            h,
            cdf,
            cum_f,
            norm,
        }
    }

    /// An offset drawn with density p (proportional to |f|) from `u`, and its weight
    /// f / (p norm).
    fn sample(&self, filter: &FilterDesc, u: f32) -> (f32, f32) {
        let u = u as f64;
        let bin = self
            .cdf
            .partition_point(|&c| c <= u)
            .clamp(1, self.cdf.len() - 1)
            - 1;
        let (c0, c1) = (self.cdf[bin], self.cdf[bin + 1]);
        let t = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.5 };
        let x = -self.radius + (bin as f64 + t) as f32 * self.h;
        let p = (c1 - c0) / self.h as f64;
        let f = filter_profile(filter, x) as f64;
        (x, (f / (p * self.norm)) as f32)
    }

    /// Linear interpolation of a cumulative table at offset `x` (clamped to the support).
    fn at(&self, table: &[f64], x: f32) -> f64 {
        let t = ((x + self.radius) / self.h).clamp(0.0, (table.len() - 1) as f32);
        let i = (t as usize).min(table.len() - 2);
        let f = (t - i as f32) as f64;
        table[i] * (1.0 - f) + table[i + 1] * f
    }

    /// The factor that turns the weights of samples restricted to offsets in [lo, hi] (redrawn
    /// until inside) into Mitsuba's normalisation by the filter's integral over [lo, hi]:
    /// P(lo, hi) norm / F(lo, hi).
    fn edge_factor(&self, lo: f32, hi: f32) -> f32 {
        if lo <= -self.radius && hi >= self.radius {
            return 1.0;
        }
        let p = self.at(&self.cdf, hi) - self.at(&self.cdf, lo);
        let f = self.at(&self.cum_f, hi) - self.at(&self.cum_f, lo);
        (p * self.norm / f) as f32
    }
}

/// A pixel filter ready for sampling (built once per render from its description).
#[derive(Clone, Debug)]
pub struct Filter {
    /// The description.
    pub desc: FilterDesc,
    table: Option<Arc<SignedTable>>,
}

impl Filter {
    /// The filter `desc`, with its sampling table if it has negative lobes.
    pub fn new(desc: FilterDesc) -> Filter {
        let table = matches!(
            desc,
            FilterDesc::Mitchell { .. } | FilterDesc::Lanczos { .. }
        )
        .then(|| Arc::new(SignedTable::new(&desc)));
        Filter { desc, table }
    }
}

/// Samples a film offset (pixels, relative to the pixel centre) distributed as the filter,
/// with its weight (1 except for filters with negative lobes). It takes one (2D) dimension of
/// the sample pattern: the box, the tent and the tabulated filters warp it, the Gaussian's
/// rejection loop skips it and draws from the sample's own stream (a loop would otherwise take
/// a varying number of dimensions and misalign the later ones).
#[inline(always)]
pub fn sample_filter<S: RandomSource>(filter: &Filter, sampler: &mut S) -> (Vec2, f32) {
    sample_filter_in(filter, sampler, true)
}

/// [`sample_filter`], from the pattern's next dimension (`pattern`) or from the sample's own
/// stream (redraws).
#[inline(always)]
fn sample_filter_in<S: RandomSource>(
    filter: &Filter,
    sampler: &mut S,
    pattern: bool,
) -> (Vec2, f32) {
    let u2 = |s: &mut S| {
        if pattern {
            s.next_2d()
        } else {
            let x = s.independent_1d();
            Vec2::new(x, s.independent_1d())
        }
    };
    if let Some(t) = &filter.table {
        let u = u2(sampler);
        let (x, wx) = t.sample(&filter.desc, u.x);
        let (y, wy) = t.sample(&filter.desc, u.y);
        return (Vec2::new(x, y), wx * wy);
    }
    let offset = match filter.desc {
        FilterDesc::Box { radius } => (u2(sampler) * 2.0 - Vec2::ONE) * radius,
        FilterDesc::Tent { radius } => {
            let u = u2(sampler);
            Vec2::new(sample_tent(u.x), sample_tent(u.y)) * radius
        }
        FilterDesc::Gaussian { stddev } => {
            // Mitsuba 3's Gaussian: exp(-x^2 / (2 s^2)) minus its value at the radius 4 s,
            // clamped at 0, separable. Sampled per axis by rejection from the uniform box:
            // exact for any shape, acceptance ~31% per axis.
            let radius = 4.0 * stddev;
            let bias = (-(radius * radius) / (2.0 * stddev * stddev)).exp();
            if pattern {
                sampler.skip_dimension();
            }
            let axis = |sampler: &mut S| loop {
                let x = (2.0 * sampler.independent_1d() - 1.0) * radius;
                // The profile normalised to 1 at the centre: the acceptance probability.
                let f = filter_profile(&filter.desc, x) / (1.0 - bias);
                if sampler.independent_1d() < f {
                    break x;
                }
            };
            let x = axis(sampler);
            Vec2::new(x, axis(sampler))
        }
        FilterDesc::Mitchell { .. } | FilterDesc::Lanczos { .. } => {
            unreachable!("tabulated above")
        }
    };
    (offset, 1.0)
}

/// Most redraws of an offset that leaves the image (see [`sample_pixel_offset`]). A corner pixel
/// keeps at least a quarter of any of the filters' mass inside the image, so 64 redraws all
/// fail with probability below (3/4)^64 = 1e-8; the last offset is then clamped into the image.
const MAX_REDRAWS: u32 = 64;

/// A sample's offset (pixels, from the centre of pixel `(x, y)` of a `width` x `height`
/// image) distributed as `filter`, and its weight, with Mitsuba's `sample_border` semantics.
/// Mitsuba places samples inside the image only (unless `sample_border`) and makes each pixel
/// the weighted mean of the splats it receives: a border pixel's filter is cut off at the
/// image's edge. Drawing offsets from the filter restricted to the image (redrawing those that
/// leave it) has the same expectation for non-negative filters; for filters with negative
/// lobes the weight also carries the factor that renormalises by the filter's integral over
/// the part inside ([`SignedTable::edge_factor`], per axis). With `sample_border`, Mitsuba
/// also samples a border around the image, so every pixel sees its whole filter: offsets are
/// kept as drawn.
#[inline(always)]
pub fn sample_pixel_offset<S: RandomSource>(
    filter: &Filter,
    sampler: &mut S,
    pixel: (u32, u32),
    size: (u32, u32),
    sample_border: bool,
) -> (Vec2, f32) {
    let centre = Vec2::new(pixel.0 as f32 + 0.5, pixel.1 as f32 + 0.5);
    let size = Vec2::new(size.0 as f32, size.1 as f32);
    let (mut offset, mut weight) = sample_filter(filter, sampler);
    if sample_border {
        return (offset, weight);
    }
    let inside = |o: Vec2| {
        let p = centre + o;
        p.x >= 0.0 && p.y >= 0.0 && p.x < size.x && p.y < size.y
    };
    let mut redraws = 0;
    while !inside(offset) {
        if redraws == MAX_REDRAWS {
            let p = (centre + offset).clamp(Vec2::ZERO, size - Vec2::splat(1e-3));
            return (p - centre, weight);
        }
        (offset, weight) = sample_filter_in(filter, sampler, false);
        redraws += 1;
    }
    if let Some(t) = &filter.table {
        // The offsets that stay inside, per axis: [-centre, size - centre].
        weight *= t.edge_factor(-centre.x, size.x - centre.x)
            * t.edge_factor(-centre.y, size.y - centre.y);
    }
    (offset, weight)
}

/// Inverse CDF of the unit tent on [-1, 1].
#[inline]
fn sample_tent(u: f32) -> f32 {
    if u < 0.5 {
        (2.0 * u).sqrt() - 1.0
    } else {
        1.0 - (2.0 - 2.0 * u).sqrt()
    }
}

/// Running sums of one pixel: count, sum and sum of squares per channel, kept exactly
/// ([`exact`]: fixed point, so that the sums do not depend on the order the samples came in and
/// parts of a render merge bit for bit).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelStats {
    /// Number of samples added.
    pub n: u32,
    /// Samples whose value was NaN, infinite or beyond [`exact::LARGEST_SAMPLE`] (left out of
    /// the sums and reported).
    pub nonfinite: u32,
    /// Sum of sample values per channel.
    pub sum: [exact::LinearSum; 3],
    /// Sum of squared sample values per channel.
    pub sum_sq: [exact::SquareSum; 3],
    /// Sum of the samples' alpha (coverage, times the filter weight where samples carry one).
    pub alpha: exact::LinearSum,
}

impl PixelStats {
    /// Adds one sample: RGB radiance `v` and its alpha (see [`RenderOutput::alpha`]). A sample
    /// the film cannot add ([`exact::fits`]: NaN, infinite, or huge) is counted in `nonfinite`
    /// and left out of every sum. Inlined into the render loop (and so compiled for its
    /// instruction sets, see pt-integrators' `render_tile`).
    #[inline(always)]
    pub fn add(&mut self, v: [f32; 3], alpha: f32) {
        self.add_sums::<true>(v, alpha);
    }

    /// [`PixelStats::add`] without the squares: the mean (the pixel's value) and alpha as
    /// `add` keeps them, bit for bit, and the variance zero; three exact additions fewer per
    /// sample. For renders that need no variance.
    #[inline(always)]
    pub fn add_mean(&mut self, v: [f32; 3], alpha: f32) {
        self.add_sums::<false>(v, alpha);
    }

    /// [`PixelStats::add`], with the squares when `SQUARES`.
    #[inline(always)]
    fn add_sums<const SQUARES: bool>(&mut self, v: [f32; 3], alpha: f32) {
        if !exact::fits(&v) {
            self.nonfinite += 1;
            return;
        }
        self.n += 1;
        for c in 0..3 {
            let x = v[c] as f64;
            self.sum[c].add(x);
            if SQUARES {
                // Exact: the square of an f32 fits an f64's mantissa.
                self.sum_sq[c].add(x * x);
            }
        }
        self.alpha.add(f64::from(alpha));
    }

    /// Counts one sample without adding it to the sums: in `nonfinite` if the film cannot add
    /// it (as [`PixelStats::add`]), else in `n`. For renders that need no variance (a splatting
    /// film's image is its own sums).
    #[inline(always)]
    pub fn count(&mut self, v: &[f32; 3]) {
        if exact::fits(v) {
            self.n += 1;
        } else {
            self.nonfinite += 1;
        }
    }

    /// Adds another pixel's statistics (a part of the same render with other samples): exact,
    /// so the result does not depend on how the samples were split.
    pub fn merge(&mut self, other: &PixelStats) {
        self.n += other.n;
        self.nonfinite += other.nonfinite;
        for c in 0..3 {
            self.sum[c].merge(other.sum[c]);
            self.sum_sq[c].merge(other.sum_sq[c]);
        }
        self.alpha.merge(other.alpha);
    }

    /// Mean per channel (the pixel value).
    pub fn mean(&self) -> [f32; 3] {
        let n = self.n.max(1) as f64;
        self.sum.map(|s| (s.value() / n) as f32)
    }

    /// Mean alpha.
    pub fn mean_alpha(&self) -> f32 {
        (self.alpha.value() / self.n.max(1) as f64) as f32
    }

    /// Estimated variance of the mean per channel: unbiased sample variance / n. The mean
    /// square is known to half a unit of the squares' grid (each square is rounded once:
    /// 2^-(SQUARE_BITS + 1)), so a spread below that (plus the f64 rounding of the squared
    /// mean) cannot be told from none and reads as 0: samples that are all equal have variance
    /// exactly 0, as they would with exact squares.
    pub fn variance_of_mean(&self) -> [f32; 3] {
        if self.n < 2 {
            return [0.0; 3];
        }
        let n = self.n as f64;
        let resolution = f64::powi(2.0, -(exact::SQUARE_BITS as i32 + 1));
        std::array::from_fn(|c| {
            let m = self.sum[c].value() / n;
            let spread = self.sum_sq[c].value() / n - m * m;
            if spread <= resolution + m * m * f64::EPSILON * 4.0 {
                return 0.0;
            }
            ((spread * n / (n - 1.0)) / n) as f32
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Sampler;

    /// The Gaussian's tail constant is exp(-8) in f32, and the profile vanishes at its radius
    /// (4 standard deviations) and is positive just inside it.
    #[test]
    fn gaussian_tail_is_its_value_at_the_radius() {
        assert_eq!(GAUSSIAN_TAIL, (-8f32).exp());
        assert_eq!(GAUSSIAN_TAIL, fastmath::exp(-8.0));
        for stddev in [0.5f32, 0.3, 1.0] {
            let f = FilterDesc::Gaussian { stddev };
            assert_eq!(filter_profile(&f, 4.0 * stddev), 0.0);
            assert!(filter_profile(&f, 3.9 * stddev) > 0.0);
        }
    }

    #[test]
    fn filter_samples_have_the_filter_moments() {
        // Variance of the box of radius r is r^2/3, of the tent r^2/6; of Mitsuba's truncated,
        // bias-shifted Gaussian with s = 0.5 it is slightly below s^2 = 0.25. 1e5 samples give a
        // standard error of about 1e-3 on these variances; the threshold is 5 standard errors.
        let n = 100_000;
        let mut s = Sampler::new(3, 0, 0);
        for (f, want) in [
            (FilterDesc::Box { radius: 0.5 }, 0.25 / 3.0),
            (FilterDesc::Tent { radius: 1.0 }, 1.0 / 6.0),
        ] {
            let v: f64 = (0..n)
                .map(|_| sample_filter(&Filter::new(f), &mut s).0.x as f64)
                .map(|x| x * x)
                .sum::<f64>()
                / n as f64;
            assert!(
                (v - want).abs() < 5e-3 * want.max(0.1) * 2.0,
                "{f:?}: {v} vs {want}"
            );
        }
        let g: Vec<f32> = (0..n)
            .map(|_| {
                sample_filter(&Filter::new(FilterDesc::Gaussian { stddev: 0.5 }), &mut s)
                    .0
                    .y
            })
            .collect();
        assert!(g.iter().all(|x| x.abs() <= 2.0));
        let v: f64 = g.iter().map(|&x| (x as f64).powi(2)).sum::<f64>() / n as f64;
        assert!(v > 0.2 && v < 0.25, "{v}");
    }

    /// Without `sample_border`, a corner pixel's offsets are the filter restricted to the
    /// image: for the tent of radius 1 at pixel (0, 0), the x offset has the tent's density cut
    /// at -0.5 and renormalised, whose mean is 2/21 (below); interior pixels, and any pixel with
    /// `sample_border`, keep the whole tent (mean 0). 1e5 samples: standard error of the mean
    /// 1.3e-3 (the tent's sd 0.41 / sqrt(1e5)); 6e-3 is over 4 of them, and the shift tested is
    /// 0.095.
    #[test]
    fn border_pixels_draw_the_filter_restricted_to_the_image() {
        let tent = Filter::new(FilterDesc::Tent { radius: 1.0 });
        let n = 100_000;
        let mean_x = |pixel: (u32, u32), border: bool| {
            let mut s = Sampler::new(5, 0, 0);
            (0..n)
                .map(|_| sample_pixel_offset(&tent, &mut s, pixel, (8, 8), border).0)
                .inspect(|o| {
                    let p = Vec2::new(pixel.0 as f32 + 0.5, pixel.1 as f32 + 0.5) + *o;
                    assert!(border || (p.x >= 0.0 && p.y >= 0.0 && p.x < 8.0 && p.y < 8.0));
                })
                .map(|o| o.x as f64)
                .sum::<f64>()
                / n as f64
        };
        // Tent t(x) = 1 - |x| on [-1, 1], cut at x = -0.5: mass 1 - 1/8 = 7/8; first moment
        // int_{-0.5}^0 x (1 + x) dx + int_0^1 x (1 - x) dx = -1/12 + 1/6 = 1/12; the mean is
        // (1/12) / (7/8) = 2/21.
        let want = 2.0 / 21.0;
        let corner = mean_x((0, 0), false);
        assert!((corner - want).abs() < 6e-3, "{corner} vs {want}");
        for (pixel, border) in [((4, 4), false), ((0, 0), true)] {
            let m = mean_x(pixel, border);
            assert!(m.abs() < 6e-3, "{pixel:?} border {border}: {m}");
        }
    }

    /// The signed filters' 1D profiles are Mitsuba 3.9.1's (`rfilter.eval`, read back from
    /// `mi.load_dict` in scalar_rgb at x = 0, 0.5, 1, 1.5, 1.9, 2.5 pixels). (Its Gaussian's
    /// `eval` differs from exp(-x^2 / 2 s^2) - bias by up to 7e-4, an approximate exp; the
    /// Gaussian is sampled exactly here and tested by its moments above.)
    #[test]
    fn profiles_match_mitsuba() {
        let xs = [0.0, 0.5, 1.0, 1.5, 1.9, 2.5];
        for (f, want) in [
            (
                FilterDesc::Mitchell {
                    b: 1.0 / 3.0,
                    c: 1.0 / 3.0,
                },
                [0.88889, 0.53472, 0.05556, -0.03472, -0.00294, 0.0],
            ),
            (
                FilterDesc::Mitchell { b: 0.0, c: 0.5 },
                [1.0, 0.5625, 0.0, -0.0625, -0.0045, 0.0],
            ),
            (
                FilterDesc::Mitchell { b: 0.5, c: 0.25 },
                [0.83333, 0.52083, 0.08333, -0.02083, -0.00217, 0.0],
            ),
            (
                FilterDesc::Lanczos { lobes: 3.0 },
                [1.0, 0.60793, 0.0, -0.13509, -0.02377, 0.02432],
            ),
            (
                FilterDesc::Lanczos { lobes: 2.0 },
                [1.0, 0.57316, 0.0, -0.06368, -0.00271, 0.0],
            ),
        ] {
            for (x, w) in xs.iter().zip(want) {
                let v = filter_profile(&f, *x);
                assert!((v - w).abs() < 2e-5, "{f:?} at {x}: {v} vs {w}");
                assert_eq!(filter_profile(&f, -x), v);
            }
        }
    }

    /// The integral of f g over the normalised filter, by the midpoint rule (reference values).
    fn quadrature(f: &FilterDesc, lo: f32, hi: f32, g: impl Fn(f32) -> f64) -> f64 {
        let n = 20_000;
        let h = (hi - lo) / n as f32;
        (0..n)
            .map(|i| {
                let x = lo + (i as f32 + 0.5) * h;
                filter_profile(f, x) as f64 * g(x) * h as f64
            })
            .sum()
    }

    /// Filters with negative lobes: the weighted samples estimate the normalised filter's
    /// integrals, E[w g(x)] = int f g / int f, for g = 1, x^2 and a function that the negative
    /// lobes change the sign of (cos(pi x / 2)), and at a corner pixel the edge factor makes
    /// them estimate the filter cut at the image's edge, int_in f g / int_in f (Mitsuba's
    /// normalisation by the weights a border pixel receives). 4e5 samples: the standard errors
    /// are below 2e-3 (weights scatter about 1 by the table's bin-wise mismatch and the
    /// lobes' sign); the threshold is 8e-3; dropping the edge factor moves the corner's mean
    /// weight by 6% (Mitchell), dropping the lobes' negative sign the interior's by 14% (both
    /// checked: they fail).
    #[test]
    fn signed_filters_estimate_the_normalised_filter() {
        let n = 400_000;
        for f in [
            FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
            },
            FilterDesc::Mitchell { b: 0.0, c: 0.5 },
            FilterDesc::Lanczos { lobes: 3.0 },
        ] {
            let filter = Filter::new(f);
            let r = filter_radius(&f);
            let gs: [&dyn Fn(f32) -> f64; 3] = [&|_| 1.0, &|x| (x * x) as f64, &|x| {
                (std::f64::consts::FRAC_PI_2 * x as f64).cos()
            }];
            // Whole filter (an interior pixel).
            let mut s = Sampler::new(11, 0, 0);
            let mut sums = [0.0f64; 3];
            for _ in 0..n {
                let (o, w) = sample_pixel_offset(&filter, &mut s, (4, 4), (16, 16), false);
                for (sum, g) in sums.iter_mut().zip(&gs) {
                    // The y axis integrates against the whole normalised filter: 1.
                    *sum += w as f64 * g(o.x);
                }
            }
            let norm = quadrature(&f, -r, r, |_| 1.0);
            for (k, g) in gs.iter().enumerate() {
                let want = quadrature(&f, -r, r, g) / norm;
                let got = sums[k] / n as f64;
                assert!((got - want).abs() < 8e-3, "{f:?} g{k}: {got} vs {want}");
            }
            // Corner pixel (0, 0): offsets x >= -0.5 and y >= -0.5 stay inside.
            let mut s = Sampler::new(12, 0, 0);
            let mut sums = [0.0f64; 3];
            for _ in 0..n {
                let (o, w) = sample_pixel_offset(&filter, &mut s, (0, 0), (16, 16), false);
                assert!(o.x >= -0.5 && o.y >= -0.5);
                for (sum, g) in sums.iter_mut().zip(&gs) {
                    *sum += w as f64 * g(o.x);
                }
            }
            let norm = quadrature(&f, -0.5, r, |_| 1.0);
            for (k, g) in gs.iter().enumerate() {
                let want = quadrature(&f, -0.5, r, g) / norm;
                let got = sums[k] / n as f64;
                assert!(
                    (got - want).abs() < 8e-3,
                    "corner {f:?} g{k}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn stats_mean_and_variance() {
        let mut p = PixelStats::default();
        for v in [1.0, 2.0, 3.0, 4.0] {
            p.add([v, 0.0, v * 2.0], f32::from(u8::from(v > 1.0)));
        }
        p.add([f32::NAN, 0.0, 0.0], 1.0);
        assert_eq!(p.mean_alpha(), 0.75);
        assert_eq!(p.n, 4);
        assert_eq!(p.nonfinite, 1);
        assert_eq!(p.mean(), [2.5, 0.0, 5.0]);
        // Sample variance of 1..4 is 5/3; of the mean, 5/12.
        assert!((p.variance_of_mean()[0] - 5.0 / 12.0).abs() < 1e-6);
        assert!((p.variance_of_mean()[2] - 4.0 * 5.0 / 12.0).abs() < 1e-5);
    }
}

/// The rendered image with its per-pixel variance.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixel means, linear RGB radiance, row-major from the top.
    pub mean: Vec<[f32; 3]>,
    /// Variance of each pixel mean (sample variance / spp).
    pub variance: Vec<[f32; 3]>,
    /// Samples per pixel.
    pub spp: u32,
    /// Wall-clock time of the sampling loop.
    pub time: std::time::Duration,
    /// Samples whose radiance was NaN or infinite (excluded from the means).
    pub nonfinite_samples: u64,
    /// Per pixel, the filter-weighted fraction of samples whose camera path met the scene
    /// (Mitsuba's alpha: 1 everywhere when an environment light is visible), row-major; `None`
    /// for methods that do not compute it.
    pub alpha: Option<Vec<f32>>,
    /// Per pixel, the filter-weighted mean of the samples' squared CIE XYZ (Mitsuba's
    /// `moment`), row-major; `None` unless asked for.
    pub second_moment: Option<Vec<[f32; 3]>>,
}

impl RenderOutput {
    /// The image's channels in `format`, named as Mitsuba names them, each a row-major plane:
    /// `R`, `G`, `B` the linear sRGB means; `X`, `Y`, `Z` their CIE 1931 tristimulus values
    /// (`Y` is the luminance; the sRGB-to-XYZ matrix, so a spectral render's XYZ is that of
    /// its sRGB, a linear map of the same expectation); `A` the alpha. An error when the format
    /// has alpha and the method computed none.
    pub fn channels(&self, format: PixelFormat) -> Result<Vec<(&'static str, Vec<f32>)>, String> {
        let xyz = || -> Vec<[f32; 3]> { self.mean.iter().map(|&c| srgb_to_xyz(c)).collect() };
        let plane = |v: &[[f32; 3]], c: usize| v.iter().map(|p| p[c]).collect::<Vec<f32>>();
        let colour = match format {
            PixelFormat::Rgb | PixelFormat::Rgba => vec![
                ("R", plane(&self.mean, 0)),
                ("G", plane(&self.mean, 1)),
                ("B", plane(&self.mean, 2)),
            ],
            PixelFormat::Luminance | PixelFormat::LuminanceAlpha => vec![("Y", plane(&xyz(), 1))],
            PixelFormat::Xyz | PixelFormat::Xyza => {
                let xyz = xyz();
                vec![
                    ("X", plane(&xyz, 0)),
                    ("Y", plane(&xyz, 1)),
                    ("Z", plane(&xyz, 2)),
                ]
            }
        };
        let mut out = colour;
        if format.has_alpha() {
            let alpha = self.alpha.clone().ok_or_else(|| {
                "this method computes no alpha: use a pixel_format without it (rgb, luminance, xyz)"
                    .to_string()
            })?;
            out.push(("A", alpha));
        }
        debug_assert!(out
            .iter()
            .map(|c| c.0)
            .eq(format.channels().iter().copied()));
        Ok(out)
    }
}
