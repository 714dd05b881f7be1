//! The four wavelengths carried by a path in spectral mode (hero wavelength sampling).
//!
//! One wavelength, the *hero*, is drawn from the visible-importance density of Radziszewski,
//! Boryczko and Alda, "An improved technique for full spectral rendering" (Journal of WSCG 17,
//! 2009), in the form used by pbrt-v4 (`SampleVisibleWavelengths` / `VisibleWavelengthsPDF` in
//! `util/spectrum.h`, used by `SampledWavelengths::SampleVisible`) and Mitsuba 3
//! (`sample_rgb_spectrum` / `pdf_rgb_spectrum` in `mitsuba/core/spectrum.h`):
//!
//! `p(l) = A / cosh^2(B (l - 538))` on 360-830 nm, `B = 0.0072 / nm`,
//! `A = B / (tanh(B (830 - 538)) - tanh(B (360 - 538)))`,
//!
//! sampled by its analytic inverse CDF
//! `l(u) = 538 + atanh(tanh(B (360 - 538)) + u (tanh(B (830 - 538)) - tanh(B (360 - 538)))) / B`.
//!
//! The other three lanes use the same mapping with the sample rotated by 1/4, 2/4, 3/4 (mod 1),
//! as pbrt-v4 does (the stratified shifts of Wilkie et al. 2014, "Hero wavelength spectral
//! sampling", applied in sample space): each lane on its own is distributed with density `p`, so
//! the per-lane pdf is `p(l_i)` and the four-lane average of `f(l_i)/p(l_i)` is an unbiased
//! estimate of the integral of `f` over 360-830 nm.
use crate::cie::{LAMBDA_MAX, LAMBDA_MIN};
use glam::Vec4;
use pt_math::fastmath;

/// `B` of the visible density, 1/nm.
const B: f32 = 0.0072;
/// `-tanh(B (360 - 538))` (pbrt-v4: 0.85691062).
const T0: f32 = 0.856_910_6;
/// `tanh(B (830 - 538)) - tanh(B (360 - 538))` (pbrt-v4: 1.82750197).
const T_RANGE: f32 = 1.827_502;
/// `A = B / T_RANGE` (pbrt-v4: 0.0039398042).
const A: f32 = 0.003_939_804;

/// Density, per nm, of [`sample_visible_wavelength`] at `lambda` nm; 0 outside 360-830 nm.
#[inline]
pub fn visible_wavelength_pdf(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    // cosh x = (e^x + e^-x) / 2 without a library call; |x| <= 2.1 on 360-830 nm.
    let x = B * (lambda - 538.0);
    let c = 0.5 * (fastmath::exp(x) + fastmath::exp(-x));
    A / (c * c)
}

/// Map a uniform sample `u` in [0, 1) to a wavelength in 360-830 nm with density
/// [`visible_wavelength_pdf`] (analytic inverse CDF).
#[cfg_attr(debug_assertions, inline)]
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sample_visible_wavelength(u: f32) -> f32 {
    sample_visible_with_pdf(u).0
}

/// [`sample_visible_wavelength`] and its density [`visible_wavelength_pdf`] there, the density
/// from the same `y = tanh(B (l - 538))` the inverse CDF inverts: `A / cosh^2 = A (1 - y^2)`,
/// no exponential needed.
#[cfg_attr(debug_assertions, inline)]
#[cfg_attr(not(debug_assertions), inline(always))]
fn sample_visible_with_pdf(u: f32) -> (f32, f32) {
    // atanh y = ln((1 + y) / (1 - y)) / 2: one logarithm (|y| <= 0.971 here, so 1 - y has
    // no cancellation to speak of).
    let y = -T0 + u * T_RANGE;
    let l = 538.0 + 0.5 * ((1.0 + y) / (1.0 - y)).ln() / B;
    (l.clamp(LAMBDA_MIN, LAMBDA_MAX), A * (1.0 - y * y))
}

/// Four wavelengths (nm) and their sampling densities (per nm), one per lane of a
/// [`SampledSpectrum`](crate::SampledSpectrum). Lane 0 is the hero wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    lambda: Vec4,
    pdf: Vec4,
}

impl SampledWavelengths {
    /// Number of lanes.
    pub const N: usize = 4;

    /// Hero wavelength from `u` with the visible density, the other lanes from `u + i/4`
    /// (mod 1) (pbrt-v4 `SampledWavelengths::SampleVisible`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sample_visible(u: f32) -> Self {
        let mut lambda = [0.0; 4];
        let mut pdf = [0.0; 4];
        for i in 0..4 {
            let mut up = u + i as f32 / 4.0;
            if up >= 1.0 {
                up -= 1.0;
            }
            (lambda[i], pdf[i]) = sample_visible_with_pdf(up);
        }
        SampledWavelengths {
            lambda: Vec4::from_array(lambda),
            pdf: Vec4::from_array(pdf),
        }
    }

    /// Hero wavelength uniform on 360-830 nm, the other lanes at equal spacing from it
    /// (wrapping around), each with pdf 1/470 per nm. Mostly for tests and comparisons.
    pub fn sample_uniform(u: f32) -> Self {
        let range = LAMBDA_MAX - LAMBDA_MIN;
        let mut lambda = [0.0; 4];
        for (i, l) in lambda.iter_mut().enumerate() {
            let mut up = u + i as f32 / 4.0;
            if up >= 1.0 {
                up -= 1.0;
            }
            *l = (LAMBDA_MIN + up * range).min(LAMBDA_MAX);
        }
        SampledWavelengths {
            lambda: Vec4::from_array(lambda),
            pdf: Vec4::splat(1.0 / range),
        }
    }

    /// The four wavelengths, nm.
    #[inline]
    pub fn lambda(&self) -> Vec4 {
        self.lambda
    }

    /// Per-lane sampling density, per nm; 0 for a terminated lane.
    #[inline]
    pub fn pdf(&self) -> Vec4 {
        self.pdf
    }

    /// The same lanes moved to other wavelengths `lambda` (nm), with the pdfs unchanged: for
    /// fluorescence, where a lane continues at the wavelength that excited what it carries.
    /// The pdfs keep describing how the lanes were first sampled, which is what the film needs;
    /// use the original value, not this one, for the film.
    #[inline]
    pub fn with_lambda(&self, lambda: Vec4) -> Self {
        SampledWavelengths {
            lambda,
            pdf: self.pdf,
        }
    }

    /// The hero wavelength (lane 0), nm.
    #[inline]
    pub fn hero(&self) -> f32 {
        self.lambda.x
    }

    /// Keep only the hero wavelength (pbrt-v4 `TerminateSecondary`): call where the lanes stop
    /// being coherent (wavelength-dependent refraction, fluorescence re-emission). The other
    /// lanes get pdf 0, so the film ignores them, and the hero's pdf is divided by 4 so that
    /// the four-lane average in [`spectrum_to_xyz`](crate::spectrum_to_xyz) stays unbiased.
    /// Idempotent.
    pub fn terminate_secondary(&mut self) {
        if self.secondary_terminated() {
            return;
        }
        self.pdf = Vec4::new(self.pdf.x / Self::N as f32, 0.0, 0.0, 0.0);
    }

    /// Whether [`terminate_secondary`](Self::terminate_secondary) has been called.
    #[inline]
    pub fn secondary_terminated(&self) -> bool {
        self.pdf.y == 0.0 && self.pdf.z == 0.0 && self.pdf.w == 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_match_their_definition() {
        let b = 0.0072f64;
        let t_lo = (b * (360.0 - 538.0)).tanh();
        let t_hi = (b * (830.0 - 538.0)).tanh();
        assert!((T0 as f64 + t_lo).abs() < 1e-6);
        assert!((T_RANGE as f64 - (t_hi - t_lo)).abs() < 1e-6);
        assert!((A as f64 - b / (t_hi - t_lo)).abs() < 1e-9);
    }

    #[test]
    fn pdf_integrates_to_one_and_inverts_the_cdf() {
        let total = crate::cie::integrate_visible(|l| visible_wavelength_pdf(l as f32) as f64);
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        assert!((sample_visible_wavelength(0.0) - 360.0).abs() < 1e-2);
        assert!((sample_visible_wavelength(0.999_999) - 830.0).abs() < 0.5);
        // CDF(l(u)) = u: integrate the pdf numerically up to the sampled wavelength.
        for &u in &[0.1f32, 0.25, 0.5, 0.75, 0.9] {
            let l = sample_visible_wavelength(u) as f64;
            let n = 20_000;
            let h = (l - 360.0) / n as f64;
            let cdf: f64 = (0..n)
                .map(|k| visible_wavelength_pdf((360.0 + (k as f64 + 0.5) * h) as f32) as f64 * h)
                .sum();
            assert!((cdf - u as f64).abs() < 1e-4, "u={u} cdf={cdf}");
        }
        assert_eq!(visible_wavelength_pdf(359.0), 0.0);
        assert_eq!(visible_wavelength_pdf(831.0), 0.0);
    }

    #[test]
    fn histogram_matches_pdf() {
        // Chi-square-style check: 47 bins of 10 nm, many stratified samples of all 4 lanes.
        let mut hist = [0.0f64; 47];
        let n = 100_000;
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            let w = SampledWavelengths::sample_visible(u);
            for l in w.lambda().to_array() {
                hist[(((l - 360.0) / 10.0) as usize).min(46)] += 1.0;
            }
        }
        for (i, &h) in hist.iter().enumerate() {
            let lo = 360.0 + 10.0 * i as f64;
            let expect: f64 = (0..100)
                .map(|j| visible_wavelength_pdf((lo + 0.1 * (j as f64 + 0.5)) as f32) as f64 * 0.1)
                .sum::<f64>()
                * (4 * n) as f64;
            assert!(
                (h - expect).abs() < 0.01 * expect + 5.0,
                "bin {i}: {h} vs {expect}"
            );
        }
    }

    #[test]
    fn lanes_are_stratified_rotations() {
        let w = SampledWavelengths::sample_visible(0.3);
        let l = w.lambda().to_array();
        assert_eq!(l[0], sample_visible_wavelength(0.3));
        assert_eq!(l[1], sample_visible_wavelength(0.55));
        assert!((l[3] - sample_visible_wavelength(0.05)).abs() < 1e-3);
        // The lanes' densities are A (1 - y^2) from the inverse CDF's y = tanh(B (l - 538)),
        // the density at l to within the roundings of y and l: 1 - y^2 >= 0.057 here, so a
        // relative error of y of 1e-7 becomes at most 2 y^2 / (1 - y^2) 1e-7 = 3.3e-6. A wrong
        // A or B would be off by percents.
        for u in [0.0f32, 0.3, 0.61, 0.999_999] {
            let w = SampledWavelengths::sample_visible(u);
            for (p, l) in w.pdf().to_array().into_iter().zip(w.lambda().to_array()) {
                let want = visible_wavelength_pdf(l);
                assert!((p - want).abs() < 5e-6 * want, "{l} nm: {p} vs {want}");
            }
        }
    }

    #[test]
    fn terminate_secondary_keeps_the_hero() {
        let mut w = SampledWavelengths::sample_visible(0.6);
        let before = w;
        assert!(!w.secondary_terminated());
        w.terminate_secondary();
        assert!(w.secondary_terminated());
        assert_eq!(w.hero(), before.hero());
        assert_eq!(w.lambda(), before.lambda());
        assert_eq!(w.pdf(), Vec4::new(before.pdf().x / 4.0, 0.0, 0.0, 0.0));
        w.terminate_secondary();
        assert_eq!(w.pdf().x, before.pdf().x / 4.0);
    }
}
