//! Per-sample random numbers: independent streams, or the structured patterns of Mitsuba's
//! samplers.
//!
//! Every camera sample owns a PCG32 stream whose state is a hash of (seed, pixel index, sample
//! index). The image therefore depends only on the seed and the sample count, never on the
//! number of threads, the tile order, or how samples are split into passes.
//!
//! With a structured pattern ([`SamplePattern`], from Mitsuba's `stratified`, `multijitter`,
//! `orthogonal` and `ldsampler`), the numbers of the samples of one pixel are also spread
//! evenly over each dimension: the n samples of a block (n the scene's sample count) are n
//! strata of each dimension, shuffled by a random permutation per pixel and dimension, and
//! jittered within their strata by the sample's PCG stream. A dimension is one request,
//! `next_1d` or `next_2d`, counted from the start of the camera sample (Mitsuba's convention).
//! For a fixed sample, the permutations of different dimensions are independent, so each
//! sample's numbers are independent and uniform: every estimate stays unbiased, however a
//! path uses its numbers (paths that branch differently use the same dimension for different
//! things, which costs stratification, not correctness). Sample k belongs to block k / n; a
//! render of more samples than n uses fresh blocks, so sample k's numbers do not depend on the
//! render's length and progressive or resumed renders stay bit-identical.

use pt_math::Vec2;
use pt_scene::SamplerKind;
use rand::Rng;
use rand_pcg::Pcg32;

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer, used to turn
/// structured (seed, pixel, sample) triples into well-distributed PCG states.
#[inline]
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The largest f32 below 1: stratified values are clamped to it so that `(s + j) / n` never
/// rounds up to 1.
const BELOW_ONE: f32 = 1.0 - 1.0 / (1u32 << 24) as f32;

/// A random permutation of `0..n` (as a function of `seed`) evaluated at `i < n`: a bijection
/// of the `b`-bit integers (`2^b` the least power of two >= n) built from xors with the seed,
/// multiplications by odd constants and xor-shifts, each invertible modulo `2^b`, applied
/// until the value falls below n (cycle walking, Black & Rogaway 2002), which keeps it a
/// bijection of `0..n`. Fewer than two rounds on average.
#[inline]
fn permute(i: u32, n: u32, seed: u32) -> u32 {
    if n <= 1 {
        return 0;
    }
    let bits = 32 - (n - 1).leading_zeros();
    let mask = u32::MAX >> (32 - bits);
    let shift = (bits / 2).max(1);
    let mut x = i;
    loop {
        // Odd multipliers and seed-derived keys (any odd constant keeps the bijection; these
        // are the 32-bit golden ratio and MurmurHash3's finaliser constants).
        x ^= seed & mask;
        x = x.wrapping_mul(0x9E37_79B9) & mask;
        x ^= x >> shift;
        x ^= seed.rotate_right(11) & mask;
        x = x.wrapping_mul(0x85EB_CA6B) & mask;
        x ^= x >> shift;
        x = x.wrapping_add(seed.rotate_right(22)) & mask;
        x = x.wrapping_mul(0xC2B2_AE35) & mask;
        x ^= x >> shift;
        if x < n {
            return x;
        }
    }
}

/// A 32-bit hash of a key and up to two more words (for per-dimension permutation seeds).
#[inline]
fn hash32(key: u64, a: u32, b: u32) -> u32 {
    (splitmix64(key ^ splitmix64(u64::from(a) << 32 | u64::from(b))) >> 32) as u32
}

/// Sobol's second dimension in base 2 (the upper-triangular Pascal matrix mod 2), which with
/// the van der Corput sequence (bit reversal) makes the (0, 2)-sequence: the first 2^m points
/// form a (0, m, 2)-net.
#[inline]
fn sobol_2(mut i: u32) -> u32 {
    let (mut v, mut x) = (1u32 << 31, 0u32);
    while i != 0 {
        if i & 1 != 0 {
            x ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    x
}

/// A 32-bit fixed-point fraction as a uniform f32 in [0, 1) (its top 24 bits).
#[inline]
fn fraction(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Which structured pattern, with the sizes it needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pattern {
    Stratified { res: u32, jitter: bool },
    MultiJitter { rx: u32, ry: u32, jitter: bool },
    Orthogonal { p: u32, jitter: bool },
    LowDiscrepancy,
}

/// How a render places the samples of a pixel ([`SamplerKind`]), for blocks of `count`
/// samples (the scene's sample count, rounded as Mitsuba rounds it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SamplePattern {
    pattern: Option<Pattern>,
    count: u32,
}

impl SamplePattern {
    /// Independent numbers (Mitsuba's `independent`).
    pub const INDEPENDENT: SamplePattern = SamplePattern {
        pattern: None,
        count: 1,
    };

    /// The pattern of `kind` for blocks of `count` samples (rounded up as
    /// [`SamplerKind::round_count`] says, so any count gives a whole pattern).
    pub fn new(kind: SamplerKind, count: u32) -> Self {
        let count = kind.round_count(count);
        let root = (1u32..).find(|r| u64::from(*r) * u64::from(*r) >= u64::from(count));
        let root = root.unwrap_or(1);
        let pattern = match kind {
            SamplerKind::Independent => None,
            SamplerKind::Stratified { jitter } => Some(Pattern::Stratified { res: root, jitter }),
            SamplerKind::MultiJitter { jitter } => {
                let ry = (1u32..).take_while(|r| r * r <= count).last().unwrap_or(1);
                Some(Pattern::MultiJitter {
                    rx: count / ry,
                    ry,
                    jitter,
                })
            }
            SamplerKind::Orthogonal { jitter } => Some(Pattern::Orthogonal { p: root, jitter }),
            SamplerKind::LowDiscrepancy => Some(Pattern::LowDiscrepancy),
        };
        SamplePattern {
            pattern,
            count: if pattern.is_some() { count } else { 1 },
        }
    }

    /// Samples per block (1 for independent numbers).
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Whether the numbers are independent (no structured pattern).
    pub fn is_independent(&self) -> bool {
        self.pattern.is_none()
    }
}

/// The structured part of a sample's numbers: which sample of which block, and the next
/// dimension.
#[derive(Clone, Copy, Debug)]
struct Strata {
    pattern: Pattern,
    count: u32,
    /// The sample's index in its block.
    index: u32,
    /// Hash of (seed, pixel, block): keys the per-dimension permutations.
    key: u64,
    /// The next dimension.
    dim: u32,
}

impl Strata {
    /// The permutation seed of dimension `dim` (and `salt` for a second permutation).
    #[inline]
    fn seed(&self, dim: u32, salt: u32) -> u32 {
        hash32(self.key, dim, salt)
    }

    /// The sample's stratum of a 1D dimension, of `n` strata.
    #[inline]
    fn stratum(&self, dim: u32, n: u32) -> u32 {
        permute(self.index, n, self.seed(dim, 0))
    }

    #[inline]
    fn next_1d(&mut self, rng: &mut Pcg32) -> f32 {
        let dim = self.dim;
        self.dim += 1;
        let n = self.count;
        match self.pattern {
            Pattern::Stratified { jitter: j, .. } | Pattern::MultiJitter { jitter: j, .. } => {
                let s = self.stratum(dim, n);
                ((s as f32 + jitter(j, rng)) / n as f32).min(BELOW_ONE)
            }
            Pattern::Orthogonal { p, jitter: j } => {
                // Bose's array OA(p^2, p + 1, p, 2): row (a0, a1) has the columns a1 and
                // a0 + k a1 mod p (k = 0..p-1); any two columns take every pair of symbols
                // once. Dimensions use the columns in groups of p + 1 (each group with its own
                // row order); the coarse stratum is the dimension's column, the fine one a
                // second column's symbol, so that each dimension alone is in n strata too.
                let group = dim / (p + 1);
                let column = dim % (p + 1);
                let row = permute(self.index, n, self.seed(group, 1));
                let (a0, a1) = (u64::from(row / p), u64::from(row % p));
                let symbol = |c: u32| -> u32 {
                    if c == 0 {
                        a1 as u32
                    } else {
                        ((a0 + u64::from(c - 1) * a1) % u64::from(p)) as u32
                    }
                };
                let coarse = permute(symbol(column), p, self.seed(dim, 2));
                let fine = permute(symbol((column + 1) % (p + 1)), p, self.seed(dim, 3));
                let x = (coarse as f32 + (fine as f32 + jitter(j, rng)) / p as f32) / p as f32;
                x.min(BELOW_ONE)
            }
            Pattern::LowDiscrepancy => {
                // Van der Corput (bit reversal) of the shuffled index, randomised by a digital
                // shift (xor), which keeps the points a (0, 1)-net.
                let i = self.stratum(dim, n);
                fraction(i.reverse_bits() ^ self.seed(dim, 4))
            }
        }
    }

    #[inline]
    fn next_2d(&mut self, rng: &mut Pcg32) -> Vec2 {
        let n = self.count;
        match self.pattern {
            Pattern::Stratified { res, jitter: j } => {
                let dim = self.dim;
                self.dim += 1;
                let s = self.stratum(dim, n);
                let (x, y) = (s % res, s / res);
                let jx = jitter(j, rng);
                let jy = jitter(j, rng);
                Vec2::new(
                    ((x as f32 + jx) / res as f32).min(BELOW_ONE),
                    ((y as f32 + jy) / res as f32).min(BELOW_ONE),
                )
            }
            Pattern::MultiJitter { rx, ry, jitter: j } => {
                // Chiu, Shirley & Wang 1994, with Kensler 2013's shared shuffles: cell (x, y) of
                // an rx x ry grid; within its column, the sub-column of row y's shuffle, within
                // its row the sub-row of column x's, so that the n samples also fill n columns
                // and n rows.
                let dim = self.dim;
                self.dim += 1;
                let s = self.stratum(dim, n);
                let (x, y) = (s % rx, s / rx);
                let sub_x = permute(y, ry, self.seed(dim, 5));
                let sub_y = permute(x, rx, self.seed(dim, 6));
                let jx = jitter(j, rng);
                let jy = jitter(j, rng);
                Vec2::new(
                    ((x as f32 + (sub_x as f32 + jx) / ry as f32) / rx as f32).min(BELOW_ONE),
                    ((y as f32 + (sub_y as f32 + jy) / rx as f32) / ry as f32).min(BELOW_ONE),
                )
            }
            // Two dimensions of the array, as Mitsuba's orthogonal sampler.
            Pattern::Orthogonal { .. } => {
                let x = self.next_1d(rng);
                Vec2::new(x, self.next_1d(rng))
            }
            Pattern::LowDiscrepancy => {
                let dim = self.dim;
                self.dim += 1;
                let i = self.stratum(dim, n);
                Vec2::new(
                    fraction(i.reverse_bits() ^ self.seed(dim, 4)),
                    fraction(sobol_2(i) ^ self.seed(dim, 7)),
                )
            }
        }
    }
}

/// A stratum's jitter: a uniform number from the stream, or its centre without jitter.
#[inline]
fn jitter(on: bool, rng: &mut Pcg32) -> f32 {
    if on {
        uniform(rng)
    } else {
        0.5
    }
}

/// A uniform f32 in [0, 1) from the stream: its top 24 bits, so the result is exactly
/// representable and < 1.
#[inline(always)]
fn uniform(rng: &mut Pcg32) -> f32 {
    fraction(rng.next_u32())
}

/// What the integrators draw random numbers from: [`Sampler`] (independent numbers) or
/// [`StructuredSampler`] (a structured pattern). The render loop is compiled for each, so the
/// independent case pays nothing for the patterns' bookkeeping.
pub trait RandomSource: Clone {
    /// A uniform number in [0, 1): the next dimension of the pattern.
    fn next_1d(&mut self) -> f32;
    /// Two uniform numbers in [0, 1): the next (2D) dimension of the pattern.
    fn next_2d(&mut self) -> Vec2;
    /// A uniform number from the sample's own stream, outside the pattern (for rejection loops,
    /// which would otherwise use a varying number of dimensions); with independent numbers it
    /// is [`RandomSource::next_1d`].
    fn independent_1d(&mut self) -> f32;
    /// Skips one dimension of the pattern (a request answered from
    /// [`RandomSource::independent_1d`] instead), so that later requests keep their dimensions.
    fn skip_dimension(&mut self);
}

/// Independent random numbers for one camera sample (Mitsuba's `independent`).
#[derive(Clone)]
pub struct Sampler {
    rng: Pcg32,
}

impl Sampler {
    /// Independent numbers for sample `sample` of pixel `pixel` (row-major index) under `seed`.
    #[inline]
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let state = splitmix64(splitmix64(splitmix64(seed) ^ pixel) ^ sample);
        // One fixed stream constant: distinct states on one stream are independent sequences,
        // whereas nearby stream increments of PCG are known to be correlated.
        Sampler {
            rng: Pcg32::new(state, 0x0a02_bdbf_7bb3_c0a7),
        }
    }

    /// A uniform number in [0, 1).
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        uniform(&mut self.rng)
    }

    /// Two uniform numbers in [0, 1).
    #[inline(always)]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = uniform(&mut self.rng);
        Vec2::new(x, uniform(&mut self.rng))
    }
}

impl RandomSource for Sampler {
    #[inline(always)]
    fn next_1d(&mut self) -> f32 {
        Sampler::next_1d(self)
    }
    #[inline(always)]
    fn next_2d(&mut self) -> Vec2 {
        Sampler::next_2d(self)
    }
    #[inline(always)]
    fn independent_1d(&mut self) -> f32 {
        uniform(&mut self.rng)
    }
    #[inline(always)]
    fn skip_dimension(&mut self) {}
}

/// The numbers of one camera sample in a structured pattern ([`SamplePattern`]): the
/// pattern's value of each dimension, jittered from the sample's own stream.
#[derive(Clone)]
pub struct StructuredSampler {
    rng: Pcg32,
    strata: Strata,
}

impl StructuredSampler {
    /// The numbers of sample `sample` of pixel `pixel` under `seed` in `pattern`; `None` for
    /// the independent pattern (use [`Sampler::new`]).
    #[inline]
    pub fn new(pattern: &SamplePattern, seed: u64, pixel: u64, sample: u64) -> Option<Self> {
        let p = pattern.pattern?;
        let count = u64::from(pattern.count);
        let block = sample / count;
        Some(StructuredSampler {
            rng: Sampler::new(seed, pixel, sample).rng,
            strata: Strata {
                pattern: p,
                count: pattern.count,
                index: (sample % count) as u32,
                key: splitmix64(splitmix64(splitmix64(seed ^ 0x5bd1_e995) ^ pixel) ^ block),
                dim: 0,
            },
        })
    }
}

impl RandomSource for StructuredSampler {
    #[inline(always)]
    fn next_1d(&mut self) -> f32 {
        self.strata.next_1d(&mut self.rng)
    }
    #[inline(always)]
    fn next_2d(&mut self) -> Vec2 {
        self.strata.next_2d(&mut self.rng)
    }
    #[inline(always)]
    fn independent_1d(&mut self) -> f32 {
        uniform(&mut self.rng)
    }
    #[inline(always)]
    fn skip_dimension(&mut self) {
        self.strata.dim += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [SamplerKind; 4] = [
        SamplerKind::Stratified { jitter: true },
        SamplerKind::MultiJitter { jitter: true },
        SamplerKind::Orthogonal { jitter: true },
        SamplerKind::LowDiscrepancy,
    ];

    /// The numbers of all samples of pixel `pixel` (one block), `dims` requests each, the
    /// requests of `two` being 2D.
    fn block(
        kind: SamplerKind,
        count: u32,
        pixel: u64,
        dims: usize,
        two: &[usize],
    ) -> Vec<Vec<Vec2>> {
        let pattern = SamplePattern::new(kind, count);
        (0..pattern.count())
            .map(|k| {
                let mut s = StructuredSampler::new(&pattern, 9, pixel, u64::from(k)).unwrap();
                (0..dims)
                    .map(|d| {
                        if two.contains(&d) {
                            s.next_2d()
                        } else {
                            Vec2::new(s.next_1d(), -1.0)
                        }
                    })
                    .collect()
            })
            .collect()
    }

    fn all_distinct(v: impl Iterator<Item = u32>) -> bool {
        let mut v: Vec<u32> = v.collect();
        let n = v.len();
        v.sort_unstable();
        v.dedup();
        v.len() == n
    }

    #[test]
    fn permute_is_a_permutation() {
        for n in 1..70u32 {
            for seed in [0u32, 1, 0xdead_beef, 12345] {
                let v: Vec<u32> = (0..n).map(|i| permute(i, n, seed)).collect();
                assert!(v.iter().all(|&x| x < n), "{n} {seed}");
                assert!(all_distinct(v.into_iter()), "{n} {seed}");
            }
        }
        // Different seeds give different orders.
        let a: Vec<u32> = (0..16).map(|i| permute(i, 16, 1)).collect();
        let b: Vec<u32> = (0..16).map(|i| permute(i, 16, 2)).collect();
        assert_ne!(a, b);
    }

    /// Each structured pattern puts the n samples of a block into n distinct strata of every
    /// 1D request (every dimension of the orthogonal and low-discrepancy patterns, whose 2D
    /// requests are two 1D strata sets or a (0, 2)-net).
    #[test]
    fn every_dimension_is_stratified() {
        for kind in KINDS {
            for count in [16u32, 25, 64] {
                let b = block(kind, count, 3, 12, &[]);
                let n = b.len() as u32;
                for d in 0..12 {
                    let strata = b.iter().map(|s| (s[d].x * n as f32) as u32);
                    assert!(all_distinct(strata), "{kind:?} n {n} dim {d}");
                }
            }
        }
    }

    /// 2D requests: stratified fills its r x r grid; multi-jittered its rx x ry grid and n
    /// columns and n rows; the orthogonal array every pair of dimensions of a group of p + 1 as
    /// a p x p grid; the low-discrepancy pattern is a (0, m, 2)-net (one point in every
    /// elementary interval of area 1/n).
    #[test]
    fn two_dimensional_requests_are_stratified() {
        let cells = |pts: &[Vec2], nx: u32, ny: u32| {
            all_distinct(
                pts.iter()
                    .map(|p| (p.x * nx as f32) as u32 * ny + (p.y * ny as f32) as u32),
            )
        };
        for d in [0usize, 3] {
            let b = block(SamplerKind::Stratified { jitter: true }, 36, 5, 4, &[0, 3]);
            let pts: Vec<Vec2> = b.iter().map(|s| s[d]).collect();
            assert!(cells(&pts, 6, 6), "stratified dim {d}");
            let b = block(SamplerKind::MultiJitter { jitter: true }, 20, 5, 4, &[0, 3]);
            let pts: Vec<Vec2> = b.iter().map(|s| s[d]).collect();
            assert!(
                cells(&pts, 5, 4) && cells(&pts, 20, 1) && cells(&pts, 1, 20),
                "multijitter dim {d}"
            );
        }
        let b = block(SamplerKind::Orthogonal { jitter: true }, 49, 7, 16, &[]);
        for group in [0usize, 8] {
            for i in group..group + 8 {
                for j in i + 1..group + 8 {
                    let pts: Vec<Vec2> = b.iter().map(|s| Vec2::new(s[i].x, s[j].x)).collect();
                    assert!(cells(&pts, 7, 7), "orthogonal dims {i}, {j}");
                }
            }
        }
        let b = block(SamplerKind::LowDiscrepancy, 64, 7, 3, &[1, 2]);
        for d in [1usize, 2] {
            let pts: Vec<Vec2> = b.iter().map(|s| s[d]).collect();
            for a in 0..=6u32 {
                assert!(
                    cells(&pts, 1 << a, 1 << (6 - a)),
                    "(0, 6, 2)-net, dim {d}, 2^{a} x 2^{}",
                    6 - a
                );
            }
        }
    }

    /// Unbiasedness: over many pixels, every number is uniform (mean 1/2, variance 1/12) and
    /// numbers of one sample are independent across dimensions (E[x y] = 1/4, E[x y z] = 1/8,
    /// the orthogonal array's three columns of one group too). 4,096 pixels x 16 to 25 samples:
    /// the standard error of a mean is below 1.5e-3; the threshold is 6e-3 (4 standard
    /// errors). Dimensions sharing one shuffle give E[xy] = 1/3 (checked: it fails), and a
    /// stratum offset error such as s / n for (s + j) / n moves the mean by 1 / (2n) = 0.03.
    #[test]
    fn numbers_are_uniform_and_independent_across_dimensions() {
        for kind in KINDS {
            let (mut m, mut xy, mut xyz, mut v, mut n) = ([0f64; 4], 0f64, 0f64, 0f64, 0f64);
            for pixel in 0..4096u64 {
                for s in block(kind, 16, pixel, 4, &[]) {
                    let x: Vec<f64> = s.iter().map(|p| p.x as f64).collect();
                    for d in 0..4 {
                        m[d] += x[d];
                    }
                    xy += x[0] * x[1];
                    xyz += x[0] * x[1] * x[2];
                    v += (x[3] - 0.5).powi(2);
                    n += 1.0;
                }
            }
            for d in 0..4 {
                assert!(
                    (m[d] / n - 0.5).abs() < 6e-3,
                    "{kind:?} mean of dim {d}: {}",
                    m[d] / n
                );
            }
            assert!((xy / n - 0.25).abs() < 6e-3, "{kind:?} E[xy] {}", xy / n);
            assert!(
                (xyz / n - 0.125).abs() < 6e-3,
                "{kind:?} E[xyz] {}",
                xyz / n
            );
            assert!(
                (v / n - 1.0 / 12.0).abs() < 6e-3,
                "{kind:?} variance {}",
                v / n
            );
        }
    }

    /// The pattern's sizes follow Mitsuba 3.9.1's rounding, and the independent pattern gives
    /// `Sampler::new`'s numbers.
    #[test]
    fn counts_and_the_independent_pattern() {
        let counts = |k: SamplerKind| [1, 5, 10, 17, 64].map(|n| SamplePattern::new(k, n).count());
        assert_eq!(counts(KINDS[0]), [1, 9, 16, 25, 64]);
        assert_eq!(counts(KINDS[1]), [1, 6, 12, 20, 64]);
        assert_eq!(counts(KINDS[2]), [4, 9, 25, 25, 121]);
        assert_eq!(counts(KINDS[3]), [4, 16, 16, 64, 64]);
        assert!(StructuredSampler::new(&SamplePattern::INDEPENDENT, 4, 5, 6).is_none());
        assert!(SamplePattern::INDEPENDENT.is_independent());
        assert!(!SamplePattern::new(KINDS[0], 4).is_independent());
    }

    #[test]
    fn range_and_determinism() {
        let mut a = Sampler::new(7, 123, 4);
        let mut b = Sampler::new(7, 123, 4);
        let mut c = Sampler::new(7, 123, 5);
        let mut same = 0;
        for _ in 0..1000 {
            let x = a.next_1d();
            assert!((0.0..1.0).contains(&x));
            assert_eq!(x, b.next_1d());
            if x == c.next_1d() {
                same += 1;
            }
        }
        assert!(same < 5, "streams of neighbouring samples must differ");
    }

    #[test]
    fn mean_and_variance_of_uniforms() {
        // 1e5 uniforms: mean 1/2 with std error 9e-4, variance 1/12 with std error 2.7e-4;
        // thresholds at about 5 standard errors.
        let n = 100_000;
        let mut s = Sampler::new(1, 2, 3);
        let xs: Vec<f64> = (0..n).map(|_| s.next_1d() as f64).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 4.5e-3, "{mean}");
        assert!((var - 1.0 / 12.0).abs() < 1.4e-3, "{var}");
    }
}
