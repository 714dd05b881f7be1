//! Elementary functions in plain f32 arithmetic, for hot loops: no library call, no branch and
//! no instruction-set-specific rounding, so that a loop over them vectorises, and the results
//! are the same bits in every compiled variant of the render loop (Rust never fuses a multiply
//! and an add on its own, so the same operations round the same way everywhere). Published
//! coefficients are written as the f32 values they round to.

/// 1.5 * 2^23: added to an f32 of magnitude below 2^22 it leaves the value rounded to the
/// nearest integer (ties to even) in the low mantissa bits, because the sum's unit in the last
/// place is 1. Subtracting it again gives that integer as an f32, exactly.
const ROUNDER: f32 = 12_582_912.0;

/// ln 2 split in two: `LN2_HI` has at most 16 significant bits, so `k * LN2_HI` is exact for the
/// integers |k| < 2^8 that [`exp`] uses; `LN2_LO` is the rest (ln 2 - LN2_HI, to f32).
const LN2_HI: f32 = 0.69314575;
const LN2_LO: f32 = 1.428_606_8e-6;

/// Below this exp(x) is under f32's smallest normal (2^-126 = e^-87.34): [`exp`] returns 0.
const EXP_MIN: f32 = -87.0;
/// Above this exp(x) overflows f32 (e^88.72 = 2^128): [`exp`] clamps its argument to it.
const EXP_MAX: f32 = 88.0;

/// e^x, within 1 ulp of the correctly rounded value on [-87, 88]; 0 below -87 (where the
/// result would be subnormal) and e^88 above 88. NaN stays NaN.
///
/// Range reduction x = k ln 2 + r with integer k and |r| <= ln 2 / 2 (Cody & Waite 1980: ln 2
/// in two parts, so r carries no rounding error from k ln 2), then e^r by its Taylor series to
/// degree 7 (the first term left out, r^8 / 8!, is below 5.2e-9 = 0.09 ulp of 1 on that
/// interval), evaluated by Estrin's scheme, and 2^k placed into the exponent bits.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    let xc = x.clamp(EXP_MIN, EXP_MAX);
    let t = xc * std::f32::consts::LOG2_E + ROUNDER;
    let k = t - ROUNDER;
    let r = (xc - k * LN2_HI) - k * LN2_LO;
    // sum r^j / j!, j = 0..7, by Estrin's scheme: pairs, then pairs of pairs, a dependency
    // chain of three multiply-add steps where Horner's has seven (single values wait for it).
    let (r2, r4) = (r * r, (r * r) * (r * r));
    // The leading 1 added last, to a sum of terms below 0.42 (|r| <= ln 2 / 2): its rounding
    // then stays within the 1 ulp promised (1 + r added first cost a second ulp).
    let low = r + r2 * (0.5 + r * (1.0 / 6.0));
    let high = (1.0 / 24.0 + r * (1.0 / 120.0)) + r2 * (1.0 / 720.0 + r * (1.0 / 5040.0));
    let p = 1.0 + (low + r4 * high);
    // k is an integer in [-126, 127]: 2^k is a normal f32 with biased exponent k + 127. The
    // bits of t are ROUNDER's plus k (t's unit in the last place is 1), so k is an integer
    // difference of bits (a float-to-integer conversion checks for overflow lane by lane).
    let biased = t
        .to_bits()
        .wrapping_sub(ROUNDER.to_bits())
        .wrapping_add(127);
    let scale = f32::from_bits(biased << 23);
    let v = p * scale;
    if x < EXP_MIN {
        0.0
    } else {
        v
    }
}

/// ln(x) for positive normal x, within 1 ulp of the correctly rounded value where the result is
/// not near 0 and within 2^-24 absolute near x = 1 (where the result's own ulp is smaller);
/// outside that domain (0, subnormals, negative x, infinities, NaN) a finite value of no
/// meaning (about -88 for 0): callers keep to the domain.
///
/// Cephes' `logf` (Moshier 1989, "Methods and Programs for Mathematical Functions"): x = m 2^e
/// with m in [sqrt(1/2), sqrt(2)) taken from the bits, ln(1 + t) for t = m - 1 as
/// t - t^2/2 + t^3 P(t) with their degree-8 polynomial P (evaluated by Estrin's scheme), and e ln 2 added in two parts
/// (`LN2_HI`'s Cephes split, 0.693359375 exact in 10 bits, and the rest) so that the sum keeps
/// the digits of the small terms. No library call and no branch: loops over lanes vectorise
/// (the x86-64 `logf` is a call per value).
#[inline(always)]
pub fn ln(x: f32) -> f32 {
    /// Cephes' split of ln 2: the high part exact in few bits, the low part the rest.
    const LN2_C_HI: f32 = 0.693_359_4;
    const LN2_C_LO: f32 = -2.121_944_4e-4;
    let bits = x.to_bits();
    // The mantissa as m in [1, 2) and the unbiased exponent.
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let e = ((bits >> 23) & 0xff) as i32 - 127;
    // Into [sqrt(1/2), sqrt(2)): halving m is exact.
    let big = m > std::f32::consts::SQRT_2;
    let m = if big { 0.5 * m } else { m };
    let e = (e + i32::from(big)) as f32;
    let t = m - 1.0;
    let z = t * t;
    // P(t) = sum c_i t^i (c_0 = 1/3 ... c_8), by Estrin's scheme: pairs, then pairs of pairs,
    // a dependency chain of four steps where Horner's has eight (the single-lane callers wait
    // for it).
    let [c0, c1, c2, c3, c4, c5, c6, c7, c8] = [
        3.333_333e-1,
        -2.499_999_4e-1,
        2.000_071_4e-1,
        -1.666_805_8e-1,
        1.424_932_3e-1,
        -1.242_014_1e-1,
        1.167_699_9e-1,
        -1.151_461e-1,
        7.037_683_6e-2,
    ];
    let z2 = z * z;
    let low = (c0 + c1 * t) + z * (c2 + c3 * t);
    let high = (c4 + c5 * t) + z * (c6 + c7 * t);
    let p = low + z2 * (high + z2 * c8);
    let y = t * z * p + e * LN2_C_LO - 0.5 * z;
    (t + y) + e * LN2_C_HI
}

/// The complementary error function erfc(x) = 1 - erf(x) for x >= 0, to within
/// 5e-7 + 1.2e-7 x^2 relative (6e-7 at x = 1, 2.4e-6 at x = 4, where erfc = 1.5e-8; 0 once it
/// falls below f32's normal range, x > 9.3). Press et al., Numerical Recipes in C (2nd ed.,
/// 1992), sec. 6.2, `erfcc`: erfc(x) = t exp(-x^2 + P(t)) with t = 1 / (1 + x/2) and P their
/// Chebyshev-fitted polynomial of degree 9 (fractional error below 1.2e-7 in exact
/// arithmetic) and the roundings of P (a few 1e-7); the x^2 term is the rounding of the exponent, about x^2 in magnitude, which
/// the exponential turns into a relative error. No cancellation: accurate in the far tail,
/// where 1 - erf(x) has lost every digit.
#[inline(always)]
pub fn erfc(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.5 * x);
    // P(t) by Horner, highest coefficient first.
    let mut p = 0.170_872_77;
    for c in [
        -0.822_152_23,
        1.4885159,
        -1.135204,
        0.278_868_07,
        -0.186_288_06,
        0.096_784_18,
        0.374_091_96,
        1.0000237,
        -1.2655122,
    ] {
        p = p * t + c;
    }
    t * exp(-x * x + p)
}

/// tan(pi / 8): [`atan2`] reduces ratios above it by atan t = pi/4 + atan((t - 1) / (t + 1)).
const TAN_PI_8: f32 = 0.414_213_57;

/// atan(r) for |r| <= tan(pi/8): Cephes' `atanf` polynomial (Moshier 1989, "Methods and
/// Programs for Mathematical Functions"; relative error about 1e-7 on that interval).
#[inline(always)]
fn atan_reduced(r: f32) -> f32 {
    let z = r * r;
    let p = ((0.080537446 * z - 0.13877685) * z + 0.19977711) * z - 0.3333295;
    p * z * r + r
}

/// atan2(y, x) in [-pi, pi] for finite arguments, within 4e-7 radians of the exact angle;
/// 0 for (0, 0). The ratio of the smaller to the larger magnitude (in [0, 1]) reduced once
/// more at tan(pi/8) ([`atan_reduced`]), then the octant restored by selects: no branch, no
/// library call.
#[inline(always)]
pub fn atan2(y: f32, x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let t = if hi > 0.0 { lo / hi } else { 0.0 };
    let big = t > TAN_PI_8;
    let r = if big { (t - 1.0) / (t + 1.0) } else { t };
    let a = atan_reduced(r) + if big { FRAC_PI_4 } else { 0.0 };
    let a = if ay > ax { FRAC_PI_2 - a } else { a };
    let a = if x < 0.0 { PI - a } else { a };
    if y < 0.0 {
        -a
    } else {
        a
    }
}

/// asin(s) for |s| <= 1/2: Cephes' `asinf` polynomial (Moshier 1989; relative error about
/// 2.5e-7 on that interval).
#[inline(always)]
fn asin_reduced(s: f32) -> f32 {
    let z = s * s;
    let p = (((0.0421632 * z + 0.024181312) * z + 0.045470025) * z + 0.074953005) * z + 0.16666752;
    p * z * s + s
}

/// acos(x) in [0, pi] for x in [-1, 1] (clamped), within 4e-7 radians of the exact angle:
/// pi/2 - asin(x) for |x| <= 1/2, else 2 asin(sqrt((1 - |x|) / 2)) (no cancellation near
/// |x| = 1), mirrored for negative x; both branches computed and one selected.
#[inline(always)]
pub fn acos(x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, PI};
    let x = x.clamp(-1.0, 1.0);
    let ax = x.abs();
    let middle = FRAC_PI_2 - asin_reduced(x);
    let edge = 2.0 * asin_reduced((0.5 * (1.0 - ax)).sqrt());
    let edge = if x < 0.0 { PI - edge } else { edge };
    if ax <= 0.5 {
        middle
    } else {
        edge
    }
}

/// sin(2 pi u) and cos(2 pi u), the direction at `u` turns (u in [0, 1) covers the circle;
/// any |u| < 2^20 works), within 1.5e-7 of the exact values: no library call and no branch, so
/// that a loop over lanes of azimuths vectorises.
///
/// Range reduction in turns, where it is exact: q = round(4u) by the [`ROUNDER`] sum and
/// r = u - q/4 in [-1/8, 1/8] (exact by Sterbenz's lemma: u and q/4 are within a factor of
/// two), so the angle x = 2 pi r is in [-pi/4, pi/4] with one rounding. There Cephes' `sinf`
/// and `cosf` polynomials (Moshier 1989; about 1 ulp), then the quadrant q mod 4 restored by
/// swapping the two and flipping sign bits: sin(x + q pi/2) is sin x, cos x, -sin x, -cos x.
#[inline(always)]
pub fn sin_cos_turns(u: f32) -> (f32, f32) {
    let t = 4.0 * u + ROUNDER;
    let quarters = t - ROUNDER;
    // q (two's complement, so negative u works too): t's unit in the last place is 1.
    let q = t.to_bits().wrapping_sub(ROUNDER.to_bits());
    let x = (u - 0.25 * quarters) * std::f32::consts::TAU;
    let z = x * x;
    let sin = ((-0.00019515296 * z + 0.008332161) * z - 0.16666655) * z * x + x;
    let cos = ((2.4433157e-5 * z - 0.0013887316) * z + 0.041666646) * z * z - 0.5 * z + 1.0;
    let odd = q & 1 != 0;
    let (s, c) = (if odd { cos } else { sin }, if odd { sin } else { cos });
    // Sign bits: sin is negative in quadrants 2 and 3, cos in 1 and 2.
    let sin_sign = (q & 2) << 30;
    let cos_sign = (q.wrapping_add(1) & 2) << 30;
    (
        f32::from_bits(s.to_bits() ^ sin_sign),
        f32::from_bits(c.to_bits() ^ cos_sign),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place between two positive finite f32.
    fn ulps(a: f32, b: f32) -> u32 {
        a.to_bits().abs_diff(b.to_bits())
    }

    /// Against f64's ln rounded to f32 over every binade of the normal range (a dense grid of
    /// mantissas in each): within 1 ulp where |ln x| >= 2^-6, within 2^-24 absolute nearer 1
    /// (the absolute accuracy there is what a sum with other terms keeps). A wrong
    /// coefficient, a lost ln 2 part or a misplaced mantissa range breaks it by far more.
    #[test]
    fn ln_within_one_ulp_or_2e_24() {
        let (mut worst_ulp, mut worst_abs) = (0u32, 0.0f64);
        for e in -126..128 {
            for i in 0..4096u32 {
                let x = f32::from_bits((((e + 127) as u32) << 23) | (i << 11) | (i & 0x7ff));
                let exact = f64::from(x).ln();
                let got = ln(x);
                if exact.abs() >= 1.0 / 64.0 {
                    worst_ulp = worst_ulp.max(ulps(got.abs(), exact.abs() as f32));
                } else {
                    worst_abs = worst_abs.max((f64::from(got) - exact).abs());
                }
            }
        }
        assert!(worst_ulp <= 1, "{worst_ulp} ulp");
        assert!(worst_abs <= 2f64.powi(-24), "{worst_abs:e}");
        assert_eq!(ln(1.0), 0.0);
    }

    /// Against f64's exp rounded to f32 (the correctly rounded value, all but always), on a
    /// dense grid over the whole range and at the special points: within the 1 ulp promised.
    /// A wrong coefficient breaks this by many ulp, even the last Taylor term left out by 2.
    #[test]
    fn within_one_ulp_of_the_correctly_rounded_value() {
        let mut worst = 0;
        let n = 2_000_000;
        for i in 0..=n {
            let x = EXP_MIN + (EXP_MAX - EXP_MIN) * i as f32 / n as f32;
            let want = f64::from(x).exp() as f32;
            let d = ulps(exp(x), want);
            assert!(d <= 1, "exp({x}) = {} vs {want}: {d} ulp", exp(x));
            worst = worst.max(d);
        }
        assert!(worst >= 1, "the grid should meet some rounding difference");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-0.0), 1.0);
        assert_eq!(exp(-100.0), 0.0);
        assert_eq!(exp(f32::NEG_INFINITY), 0.0);
        assert!(exp(f32::NAN).is_nan());
        assert_eq!(exp(1000.0), exp(EXP_MAX));
    }

    /// Against libm's f64 erfc on a dense grid of [0, 9] (erfc(9) = 4e-37): within the
    /// documented 5e-7 + 1.2e-7 x^2 relative (the book's 1.2e-7, f32's roundings of the
    /// polynomial, and two roundings of the exponent of size x^2, 6e-8 x^2 each). A wrong
    /// coefficient is off by 1e-3 or more.
    #[test]
    fn erfc_within_its_bound() {
        let n = 200_000;
        let mut worst = 0.0f64;
        for i in 0..=n {
            let x = 9.0 * i as f32 / n as f32;
            let want = libm::erfc(f64::from(x));
            let rel = (f64::from(erfc(x)) - want).abs() / want;
            let bound = 5e-7 + 1.2e-7 * f64::from(x * x);
            worst = worst.max(rel / bound);
            assert!(rel < bound, "erfc({x}) = {} vs {want}: {rel:e}", erfc(x));
        }
        assert!(
            worst > 0.3,
            "the bound should be near what the grid meets: {worst}"
        );
        assert_eq!(erfc(0.0), 1.0);
    }

    /// atan2 over the whole circle (directions at 1e5 angles, also scaled by 1e-30 and 1e30)
    /// and on the axes, against f64's: within the 4e-7 radians promised (about 2 ulp of pi;
    /// a wrong coefficient or octant is off by 1e-5 or more).
    #[test]
    fn atan2_within_its_bound() {
        let n = 100_000;
        let mut worst = 0.0f64;
        for i in 0..n {
            let phi = -std::f64::consts::PI + std::f64::consts::TAU * (i as f64 + 0.5) / n as f64;
            for scale in [1.0, 1e-30, 1e30] {
                let (y, x) = ((phi.sin() * scale) as f32, (phi.cos() * scale) as f32);
                let want = f64::from(y).atan2(f64::from(x));
                let err = (f64::from(atan2(y, x)) - want).abs();
                worst = worst.max(err);
                assert!(err < 4e-7, "atan2({y}, {x}) = {} vs {want}", atan2(y, x));
            }
        }
        assert!(worst > 5e-8, "{worst:e}");
        for (y, x) in [
            (0.0, 1.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (-1.0, -1.0),
        ] {
            assert!((f64::from(atan2(y, x)) - f64::from(y).atan2(f64::from(x))).abs() < 4e-7);
        }
        assert_eq!(atan2(0.0, 0.0), 0.0);
    }

    /// The largest `error(x)` over `n + 1` evenly spaced `x` from `lo` to `hi`, each checked to
    /// be below `bound` (the failing `x` named).
    fn worst_on_grid(lo: f32, hi: f32, n: u32, bound: f64, error: impl Fn(f32) -> f64) -> f64 {
        let mut worst = 0.0f64;
        for i in 0..=n {
            let x = lo + (hi - lo) * i as f32 / n as f32;
            let err = error(x);
            assert!(err < bound, "at {x}: error {err:e}, bound {bound:e}");
            worst = worst.max(err);
        }
        worst
    }

    /// acos on a dense grid of [-1, 1] and at its ends, against f64's: within the 4e-7
    /// radians promised; clamped outside.
    #[test]
    fn acos_within_its_bound() {
        let worst = worst_on_grid(-1.0, 1.0, 1_000_000, 4e-7, |x| {
            (f64::from(acos(x)) - f64::from(x).acos()).abs()
        });
        assert!(worst > 5e-8, "{worst:e}");
        assert_eq!(acos(1.0), 0.0);
        assert!((acos(-1.0) - std::f32::consts::PI).abs() < 4e-7);
        assert_eq!(acos(2.0), acos(1.0));
    }

    /// sin(2 pi u) and cos(2 pi u) on a dense grid of [-2, 2] turns and at the quadrant
    /// boundaries, against f64's: within the 1.5e-7 promised (f32's half ulp at 1 is 6e-8;
    /// the angle's rounding and the polynomials' add about as much again). A wrong
    /// coefficient or quadrant is off by 1e-5 or more.
    #[test]
    fn sin_cos_turns_within_its_bound() {
        let worst = worst_on_grid(-2.0, 2.0, 2_000_000, 1.5e-7, |u| {
            let (s, c) = sin_cos_turns(u);
            let (ws, wc) = (std::f64::consts::TAU * f64::from(u)).sin_cos();
            (f64::from(s) - ws).abs().max((f64::from(c) - wc).abs())
        });
        assert!(worst > 3e-8, "{worst:e}");
        for (u, s, c) in [
            (0.0f32, 0.0f32, 1.0f32),
            (0.25, 1.0, 0.0),
            (0.5, 0.0, -1.0),
            (0.75, -1.0, 0.0),
        ] {
            let (gs, gc) = sin_cos_turns(u);
            assert_eq!((gs.abs(), gc.abs()), (s.abs(), c.abs()), "{u}");
            assert!(gs * s >= 0.0 && gc * c >= 0.0, "{u}: ({gs}, {gc})");
        }
    }
}
