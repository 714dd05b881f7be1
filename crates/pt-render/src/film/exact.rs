//! Exact sums: the film's accumulators in fixed point, so that a pixel's sum does not depend on
//! the order its samples were added in.
//!
//! Floating-point addition is not associative: a pixel whose samples are summed in another order
//! (split over threads, passes, or the machines of a cluster, `--part K/N`) gets another last
//! bit. Every film sum is therefore kept as an integer count of 2^-F units (an `i128`): each
//! added value is rounded once to that grid (the rounding depends on the value alone), and
//! integer addition is associative and commutative, so any partition of the samples, added in
//! any order and merged, gives the same bits. This is the one canonical reduction of the
//! renderer: a render on one machine uses it too, so `pt merge` of N parts equals `pt render`.
//!
//! Two grids: [`LINEAR_BITS`] = 56 fractional bits for values and weights (resolution
//! 1.4e-17, sums up to 2^71 = 2.4e21), [`SQUARE_BITS`] = 40 for squared values (resolution
//! 9.1e-13, sums up to 2^87 = 1.5e26). A sample is added only when every channel is finite and
//! below [`LARGEST_SAMPLE`] = 2^34 (1.7e10) in magnitude ([`fits`]): a pixel's sums then hold
//! 2^37 samples at that bound and its squares 2^19 (and 2^39 samples of radiance 1e7, the sun's
//! order of magnitude in W m^-2 sr^-1). Samples beyond it are counted with the non-finite ones and left
//! out (reported after the render). Additions wrap (two's complement), which keeps them
//! associative even if an intermediate partial sum overflowed: only the final sum has to fit.

/// Fractional bits of sums of values and filter weights.
pub const LINEAR_BITS: u32 = 56;
/// Fractional bits of sums of squared values.
pub const SQUARE_BITS: u32 = 40;
/// Largest magnitude of a sample channel the film adds (2^34; see the module documentation).
pub const LARGEST_SAMPLE: f32 = 17_179_869_184.0;

/// Whether a sample with these channels is added to the film: every channel finite and below
/// [`LARGEST_SAMPLE`] in magnitude.
#[inline]
pub fn fits(values: &[f32]) -> bool {
    values.iter().all(|v| v.abs() < LARGEST_SAMPLE)
}

/// `v` rounded to the nearest multiple of 2^-`frac` (ties away from zero), in those units.
/// Correct for |v| < 2^(63 + 53 - frac) (2^60 for sums of values, 2^76 for squares: far above
/// what the film adds, see the module documentation); NaN and infinities are the caller's to
/// keep out. It runs several times per sample (inlined into the render loop's x86-64-v3
/// variant): the film's usual values, whose count of grid units fits 62 bits (|v| < 64 for
/// sums of values, 2^22 for squares), take two floating-point operations (scaling by 2^frac is
/// exact, and `round` rounds half away from zero, the same rule as [`to_fixed_wide`], which
/// the rest take; same bits either way, by test).
#[inline(always)]
pub fn to_fixed(v: f64, frac: u32) -> i128 {
    /// 2^62: below it a rounded count converts to i64 exactly.
    const FAST_LIMIT: f64 = 4_611_686_018_427_387_904.0;
    // 2^frac built from its exponent bits (frac <= 127, so the power is a normal f64).
    let scaled = v * f64::from_bits(u64::from(1023 + frac) << 52);
    if scaled.abs() < FAST_LIMIT {
        i128::from(scaled.round() as i64)
    } else {
        to_fixed_wide(v, frac)
    }
}

/// [`to_fixed`] for any magnitude below its bound, in integer arithmetic on the bits of `v`
/// (branch-free).
#[inline(always)]
pub fn to_fixed_wide(v: f64, frac: u32) -> i128 {
    let bits = v.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32;
    // v = mantissa * 2^(exponent - 1075), mantissa a 53-bit integer; zero and subnormals (below
    // 2^-1022, far under every grid's resolution) give a zero mantissa.
    let implicit = u64::from(exponent != 0) << 52;
    let mantissa = ((bits & ((1u64 << 52) - 1)) | implicit) * u64::from(exponent != 0);
    // The value in grid units is mantissa * 2^shift. With the mantissa placed 64 bits up, one
    // right shift by 64 - shift (in 1..=127) scales it, and adding half a unit first rounds.
    // Shifts below -63 round to zero anyway (the mantissa is below 2^53).
    let shift = (exponent - 1075 + frac as i32).clamp(-63, 63);
    let right = (64 - shift) as u32;
    let magnitude = (((mantissa as u128) << 64) + (1u128 << (right - 1))) >> right;
    let negative = -((bits >> 63) as i128);
    // Two's complement negation where the sign bit is set: (x ^ -1) - (-1) = -x.
    ((magnitude as i128) ^ negative) - negative
}

/// A sum kept in units of 2^-`F` (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExactSum<const F: u32>(pub i128);

impl<const F: u32> ExactSum<F> {
    /// Adds `v`, rounded to the grid.
    #[inline(always)]
    pub fn add(&mut self, v: f64) {
        self.0 = self.0.wrapping_add(to_fixed(v, F));
    }

    /// Adds another sum (merging partial results: exact).
    #[inline]
    pub fn merge(&mut self, other: ExactSum<F>) {
        self.0 = self.0.wrapping_add(other.0);
    }

    /// The sum as the nearest f64.
    #[inline]
    pub fn value(self) -> f64 {
        // 2^-F is exact in f64; the product only rescales.
        self.0 as f64 * f64::powi(2.0, -(F as i32))
    }

    /// Little-endian bytes (16).
    pub fn to_le_bytes(self) -> [u8; 16] {
        self.0.to_le_bytes()
    }

    /// From [`ExactSum::to_le_bytes`].
    pub fn from_le_bytes(b: [u8; 16]) -> Self {
        ExactSum(i128::from_le_bytes(b))
    }
}

/// A sum of values or weights.
pub type LinearSum = ExactSum<LINEAR_BITS>;
/// A sum of squared values.
pub type SquareSum = ExactSum<SQUARE_BITS>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Sampler;

    /// Values on the grid convert exactly, others to the nearest grid point (the error is at
    /// most half a unit), signs are kept, and tiny values vanish.
    #[test]
    fn conversion_rounds_to_the_grid() {
        for v in [1.0, 0.5, -3.25, 1024.0, 2f64.powi(-56), -(2f64.powi(40))] {
            assert_eq!(to_fixed(v, 56) as f64, v * 2f64.powi(56), "{v}");
        }
        let mut s = Sampler::new(1, 2, 3);
        for _ in 0..10_000 {
            let v = (s.next_1d() as f64 - 0.5) * 10f64.powi((s.next_1d() * 30.0) as i32 - 20);
            let back = to_fixed(v, 56) as f64 * 2f64.powi(-56);
            assert!(
                (back - v).abs() <= 2f64.powi(-57) * 1.000001,
                "{v} -> {back}"
            );
            assert_eq!(to_fixed(-v, 56), -to_fixed(v, 56));
        }
        assert_eq!(to_fixed(1e-30, 56), 0);
        assert_eq!(to_fixed(0.0, 56), 0);
        assert_eq!(to_fixed(-0.0, 56), 0);
    }

    /// The two conversions agree bit for bit: on grid points and ties (half a unit off one),
    /// where rounding rules differ, on random values of every magnitude the film adds, and at
    /// the fast path's edge (2^62 units) in both grids.
    #[test]
    fn fast_and_wide_conversions_agree() {
        let mut s = Sampler::new(7, 8, 9);
        for frac in [LINEAR_BITS, SQUARE_BITS] {
            let unit = 2f64.powi(-(frac as i32));
            let edge = 2f64.powi(62) * unit;
            let check = |v: f64| {
                assert_eq!(
                    to_fixed(v, frac),
                    to_fixed_wide(v, frac),
                    "{v:e} at {frac} bits"
                );
                assert_eq!(to_fixed(-v, frac), to_fixed_wide(-v, frac), "{:e}", -v);
            };
            for k in [0.0, 1.0, 2.0, 3.0, 1e6, 2f64.powi(52), 2f64.powi(61)] {
                for off in [-0.5, 0.0, 0.5, 0.25] {
                    check((k + off) * unit);
                }
            }
            for v in [edge, edge * (1.0 - f64::EPSILON), edge * 1.5, 1e-300, 0.0] {
                check(v);
            }
            for _ in 0..100_000 {
                let mantissa = f64::from(s.next_1d()) + f64::from(s.next_1d()) * 2f64.powi(-24);
                let v = mantissa * 2f64.powi((s.next_1d() * 150.0) as i32 - 90);
                check(v);
            }
        }
    }

    /// The point of the type: the same values summed in two orders, or in two halves merged,
    /// give the same bits (plain f64 sums of these values differ in their last bits).
    #[test]
    fn sums_do_not_depend_on_the_order() {
        let mut s = Sampler::new(4, 5, 6);
        let values: Vec<f64> = (0..5000)
            .map(|_| f64::from(s.next_1d()).powi(8) * 1e6 - 1.0)
            .collect();
        let sum = |it: &mut dyn Iterator<Item = &f64>| {
            let mut a = LinearSum::default();
            it.for_each(|v| a.add(*v));
            a
        };
        let forward = sum(&mut values.iter());
        let backward = sum(&mut values.iter().rev());
        let mut halves = sum(&mut values.iter().step_by(2));
        halves.merge(sum(&mut values.iter().skip(1).step_by(2)));
        assert_eq!(forward, backward);
        assert_eq!(forward, halves);
        let plain: f64 = values.iter().sum();
        assert!((forward.value() - plain).abs() < 1e-9 * plain.abs());
        let plain_back: f64 = values.iter().rev().sum();
        assert_ne!(
            plain, plain_back,
            "the test values should expose f64's order dependence"
        );
    }

    /// Samples at the largest accepted magnitude: 2^19 of them (what the module documentation
    /// promises for squares) still sum exactly in both grids, negative values too.
    #[test]
    fn largest_samples_fit() {
        for v in [
            f64::from(LARGEST_SAMPLE) * (1.0 - 1e-6),
            -f64::from(LARGEST_SAMPLE) * 0.75,
        ] {
            let mut a = LinearSum::default();
            let mut b = SquareSum::default();
            for _ in 0..1 << 19 {
                a.add(v);
                b.add(v * v);
            }
            assert!((a.value() / (v * 2f64.powi(19)) - 1.0).abs() < 1e-15, "{v}");
            assert!(
                (b.value() / (v * v * 2f64.powi(19)) - 1.0).abs() < 1e-15,
                "{v}"
            );
        }
        assert!(fits(&[1.0, -1e10, 0.0]) && !fits(&[2e10, 0.0, 0.0]) && !fits(&[f32::NAN]));
    }
}
