//! Minnaert's lunar-type reflection.
//!
//! Model: M. Minnaert, "The reciprocity principle in lunar photometry", ApJ 93, 403-410 (1941),
//! eq. (1): radiance `L ~ (cos_i cos_o)^(k-1) cos_i`. As a BRDF, normalised so that `k = 1` is
//! Lambert (DESIGN.md):
//!
//! `f(wo, wi) = rho (k+1)/(2 pi) (cos_i cos_o)^(k-1)`      (both directions above, else 0)
//!
//! Its directional albedo is `rho cos_o^(k-1)` (since `int cos_i^k d omega = 2 pi/(k+1)`):
//! exact and <= rho for `k >= 1`, but unbounded at grazing view for `k < 1`.
//!
//! **Rule for `k < 1`** (documented choice): the view factor `cos_o^(k-1)` is clamped to its
//! value at normal view, 1, i.e. `f = rho (k+1)/(2 pi) cos_i^(k-1)`. Albedo is then exactly `rho`
//! for every `wo`. Cost: the model is no longer reciprocal (`f(wo,wi) != f(wi,wo)`), and the
//! limb brightening towards grazing *view* that `k < 1` would produce is removed; the
//! dependence on the light direction (`cos_i^k` after the cosine) is kept. No energy is lost
//! relative to `rho`.
//!
//! Sampling is exact for the `cos_i` part: `cos theta_i = u^(1/(k+1))`, phi uniform, pdf
//! `(k+1)/(2 pi) cos_i^k`; the weight `f cos_i / pdf` is then `rho cos_o^(k-1)` for `k >= 1` and
//! `rho` for `k < 1`, constant over samples.
//!
//! | parameter     | type     | default | unit                                  |
//! |---------------|----------|---------|---------------------------------------|
//! | `reflectance` | spectrum | 0.5     | normal-incidence albedo, [0, 1]       |
//! | `k`           | float    | 1       | Minnaert exponent, >= 0 (1: Lambert)  |
//!
//! Mitsuba XML (project extension):
//! ```xml
//! <bsdf type="minnaert">
//!     <rgb name="reflectance" value="0.5, 0.5, 0.5"/>
//!     <float name="k" value="1.5"/>
//! </bsdf>
//! ```

use crate::BsdfSample;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use std::f32::consts::PI;

/// Smallest cosine used in `cos^(k-1)` for `k < 1`: keeps the value finite at 1e-12^(-1).
const MIN_COS: f32 = 1e-12;

/// Minnaert BRDF (one-sided).
#[derive(Clone, Copy, Debug)]
pub struct Minnaert {
    /// Albedo at normal view, per lane, [0, 1].
    pub reflectance: SampledSpectrum,
    /// Exponent k >= 0.
    pub k: f32,
}

impl Minnaert {
    /// Minnaert with albedo `reflectance` and exponent `k` (negative or non-finite taken as 1).
    pub fn new(reflectance: SampledSpectrum, k: f32) -> Self {
        let k = if k.is_finite() && k >= 0.0 { k } else { 1.0 };
        Minnaert { reflectance, k }
    }

    /// The view factor: `cos_o^(k-1)`, clamped to 1 for `k < 1` (the module's rule).
    #[inline]
    fn view_factor(&self, cos_o: f32) -> f32 {
        if self.k >= 1.0 {
            cos_o.min(1.0).powf(self.k - 1.0)
        } else {
            1.0
        }
    }

    /// f(wo, wi) without the cosine.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        let ci = wi.z.clamp(MIN_COS, 1.0).powf(self.k - 1.0);
        self.reflectance * ((self.k + 1.0) / (2.0 * PI) * ci * self.view_factor(wo.z))
    }

    /// Directional albedo: `rho cos_o^(k-1)` for `k >= 1`, `rho` for `k < 1`.
    pub fn albedo(&self, wo: Vec3) -> SampledSpectrum {
        if wo.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        self.reflectance * self.view_factor(wo.z)
    }

    /// Solid-angle pdf `(k+1)/(2 pi) cos_i^k`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        (self.k + 1.0) / (2.0 * PI) * wi.z.min(1.0).powf(self.k)
    }

    /// Samples `cos theta_i = u.x^(1/(k+1))`, phi = 2 pi u.y; weight is constant.
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let cos = u.x.powf(1.0 / (self.k + 1.0));
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let wi = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
        let pdf = self.pdf(wo, wi);
        if !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: self.albedo(wo),
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Lambert;

    #[test]
    fn k_one_equals_lambert_exactly() {
        let rho = SampledSpectrum::from_rgb([0.3, 0.6, 0.9]);
        let (m, l) = (Minnaert::new(rho, 1.0), Lambert::new(rho));
        let mut rng = pt_testkit::Pcg32::new(5, 1);
        for _ in 0..200 {
            let wo = pt_testkit::upper_hemisphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            let wi = pt_testkit::upper_hemisphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            assert!((m.eval(wo, wi).0 - l.eval(wo, wi).0).abs().max_element() < 1e-7);
            assert!((m.pdf(wo, wi) - l.pdf(wo, wi)).abs() < 1e-6);
        }
    }

    #[test]
    fn weight_is_f_cos_over_pdf() {
        for k in [0.0, 0.5, 1.0, 2.5] {
            let m = Minnaert::new(SampledSpectrum::from_rgb([0.7; 3]), k);
            let wo = pt_testkit::dir_deg(50.0, 0.0);
            let s = m.sample(wo, Vec2::new(0.3, 0.6)).unwrap();
            let w = m.eval(wo, s.wi).0.x * s.wi.z / s.pdf;
            assert!(
                (w - s.weight.0.x).abs() < 1e-5 * w,
                "k = {k}: {w} vs {}",
                s.weight.0.x
            );
        }
    }
}
