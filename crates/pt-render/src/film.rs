//! The film: per-pixel sample statistics.
//!
//! Samples are placed by filter importance sampling (the pixel filter's shape is the density of
//! sub-pixel offsets, each sample weight 1), which has the same expectation as Mitsuba's weighted
//! splatting for non-negative filters (with its `sample_border` semantics at the image's edges:
//! [`sample_pixel_offset`]) and keeps every pixel independent (so tiles need no locks).

use pt_math::Vec2;
use pt_scene::FilterDesc;

use crate::sampler::Sampler;

/// Samples a film offset (pixels, relative to the pixel centre) distributed as the filter.
/// It takes one (2D) dimension of the sample pattern: the box and the tent warp it, the
/// Gaussian's rejection loop skips it and draws from the sample's own stream (a loop would
/// otherwise take a varying number of dimensions and misalign the later ones).
#[inline(always)]
pub fn sample_filter(filter: &FilterDesc, sampler: &mut Sampler) -> Vec2 {
    sample_filter_in(filter, sampler, true)
}

/// [`sample_filter`], from the pattern's next dimension (`pattern`) or from the sample's own
/// stream (redraws).
#[inline(always)]
fn sample_filter_in(filter: &FilterDesc, sampler: &mut Sampler, pattern: bool) -> Vec2 {
    let u2 = |s: &mut Sampler| {
        if pattern {
            s.next_2d()
        } else {
            let x = s.independent_1d();
            Vec2::new(x, s.independent_1d())
        }
    };
    match *filter {
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
            let axis = |sampler: &mut Sampler| loop {
                let x = (2.0 * sampler.independent_1d() - 1.0) * radius;
                let f = ((-(x * x) / (2.0 * stddev * stddev)).exp() - bias) / (1.0 - bias);
                if sampler.independent_1d() < f {
                    break x;
                }
            };
            let x = axis(sampler);
            Vec2::new(x, axis(sampler))
        }
    }
}

/// Most redraws of an offset that leaves the image (see [`sample_pixel_offset`]). A corner pixel
/// keeps at least a quarter of any of the filters' mass inside the image, so 64 redraws all
/// fail with probability below (3/4)^64 = 1e-8; the last offset is then clamped into the image.
const MAX_REDRAWS: u32 = 64;

/// A sample's offset (pixels, from the centre of pixel `(x, y)` of a `width` x `height`
/// image) distributed as `filter`, with Mitsuba's `sample_border` semantics. Mitsuba places
/// samples inside the image only (unless `sample_border`) and makes each pixel the weighted
/// mean of the splats it receives: a border pixel's filter is cut off at the image's edge.
/// Drawing offsets from the filter restricted to the image (redrawing those that leave it) has
/// the same expectation. With `sample_border`, Mitsuba also samples a border around the image,
/// so every pixel sees its whole filter: offsets are kept as drawn.
#[inline(always)]
pub fn sample_pixel_offset(
    filter: &FilterDesc,
    sampler: &mut Sampler,
    pixel: (u32, u32),
    size: (u32, u32),
    sample_border: bool,
) -> Vec2 {
    let centre = Vec2::new(pixel.0 as f32 + 0.5, pixel.1 as f32 + 0.5);
    let size = Vec2::new(size.0 as f32, size.1 as f32);
    let mut offset = sample_filter(filter, sampler);
    if sample_border {
        return offset;
    }
    let inside = |o: Vec2| {
        let p = centre + o;
        p.x >= 0.0 && p.y >= 0.0 && p.x < size.x && p.y < size.y
    };
    let mut redraws = 0;
    while !inside(offset) {
        if redraws == MAX_REDRAWS {
            let p = (centre + offset).clamp(Vec2::ZERO, size - Vec2::splat(1e-3));
            return p - centre;
        }
        offset = sample_filter_in(filter, sampler, false);
        redraws += 1;
    }
    offset
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

/// Running sums of one pixel: count, sum and sum of squares per channel (f64, so that 1e6
/// samples of values up to 1e4 keep full precision).
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelStats {
    /// Number of finite samples.
    pub n: u32,
    /// Samples whose value was NaN or infinite (left out of the sums and reported).
    pub nonfinite: u32,
    /// Sum of sample values per channel.
    pub sum: [f64; 3],
    /// Sum of squared sample values per channel.
    pub sum_sq: [f64; 3],
}

impl PixelStats {
    /// Adds one sample (RGB radiance).
    #[inline]
    pub fn add(&mut self, v: [f32; 3]) {
        if !v.iter().all(|c| c.is_finite()) {
            self.nonfinite += 1;
            return;
        }
        self.n += 1;
        for c in 0..3 {
            let x = v[c] as f64;
            self.sum[c] += x;
            self.sum_sq[c] += x * x;
        }
    }

    /// Mean per channel (the pixel value).
    pub fn mean(&self) -> [f32; 3] {
        let n = self.n.max(1) as f64;
        self.sum.map(|s| (s / n) as f32)
    }

    /// Estimated variance of the mean per channel: unbiased sample variance / n.
    pub fn variance_of_mean(&self) -> [f32; 3] {
        if self.n < 2 {
            return [0.0; 3];
        }
        let n = self.n as f64;
        std::array::from_fn(|c| {
            let m = self.sum[c] / n;
            let var = ((self.sum_sq[c] / n - m * m) * n / (n - 1.0)).max(0.0);
            (var / n) as f32
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
                .map(|_| sample_filter(&f, &mut s).x as f64)
                .map(|x| x * x)
                .sum::<f64>()
                / n as f64;
            assert!(
                (v - want).abs() < 5e-3 * want.max(0.1) * 2.0,
                "{f:?}: {v} vs {want}"
            );
        }
        let g: Vec<f32> = (0..n)
            .map(|_| sample_filter(&FilterDesc::Gaussian { stddev: 0.5 }, &mut s).y)
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
        let tent = FilterDesc::Tent { radius: 1.0 };
        let n = 100_000;
        let mean_x = |pixel: (u32, u32), border: bool| {
            let mut s = Sampler::new(5, 0, 0);
            (0..n)
                .map(|_| sample_pixel_offset(&tent, &mut s, pixel, (8, 8), border))
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

    #[test]
    fn stats_mean_and_variance() {
        let mut p = PixelStats::default();
        for v in [1.0, 2.0, 3.0, 4.0] {
            p.add([v, 0.0, v * 2.0]);
        }
        p.add([f32::NAN, 0.0, 0.0]);
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
}
