//! Per-sample random streams.
//!
//! Every camera sample owns a PCG32 stream whose state is a hash of (seed, pixel index, sample
//! index). The image therefore depends only on the seed and the sample count, never on the
//! number of threads, the tile order, or how samples are split into passes.

use pt_math::Vec2;
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

/// Independent uniform random numbers for one camera sample.
#[derive(Clone)]
pub struct Sampler {
    rng: Pcg32,
}

impl Sampler {
    /// The stream for sample `sample` of pixel `pixel` (row-major index) under `seed`.
    #[inline]
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let state = splitmix64(splitmix64(splitmix64(seed) ^ pixel) ^ sample);
        // One fixed stream constant: distinct states on one stream are independent sequences,
        // whereas nearby stream increments of PCG are known to be correlated.
        Sampler {
            rng: Pcg32::new(state, 0x0a02_bdbf_7bb3_c0a7),
        }
    }

    /// Uniform in [0, 1): the top 24 bits, so the result is exactly representable and < 1.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        (self.rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Two uniforms in [0, 1).
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
