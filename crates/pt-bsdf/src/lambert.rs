//! Lambertian (ideal diffuse) reflection.
//!
//! Model: f(wo, wi) = R / pi for wo and wi both above the surface (Lambert 1760), else 0
//! (one-sided, as Mitsuba's `diffuse`). Sampled by the cosine-weighted hemisphere, pdf =
//! cos(theta_i) / pi, so the sample weight f cos / pdf = R exactly.
//!
//! | parameter     | type     | default | unit                |
//! |---------------|----------|---------|---------------------|
//! | `reflectance` | spectrum | 0.5     | albedo in [0, 1]    |
//!
//! Mitsuba XML: `<bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.2, 0.2"/></bsdf>`

use crate::BsdfSample;
use pt_math::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use std::f32::consts::FRAC_1_PI;

/// Lambertian BRDF with albedo `reflectance`.
#[derive(Clone, Copy, Debug)]
pub struct Lambert {
    /// Directional albedo, per lane, in [0, 1].
    pub reflectance: SampledSpectrum,
}

impl Lambert {
    /// A Lambertian BRDF with the given albedo.
    pub fn new(reflectance: SampledSpectrum) -> Self {
        Lambert { reflectance }
    }

    /// f = R / pi when both directions are above the surface (local frame).
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wo.z > 0.0 && wi.z > 0.0 {
            self.reflectance * FRAC_1_PI
        } else {
            SampledSpectrum::ZERO
        }
    }

    /// Cosine-weighted pdf of `wi` (solid angle), 0 when either side is below.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z > 0.0 {
            cosine_hemisphere_pdf(wi)
        } else {
            0.0
        }
    }

    /// Cosine-weighted sample; weight = R.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = square_to_cosine_hemisphere(u);
        let pdf = cosine_hemisphere_pdf(wi);
        if pdf <= 0.0 {
            return None; // grazing sample exactly on the horizon carries no energy
        }
        Some(BsdfSample {
            wi,
            weight: self.reflectance,
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    #[test]
    fn closed_form_value_and_weight() {
        let l = Lambert::new(SampledSpectrum::from_rgb([0.2, 0.5, 0.8]));
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let wi = Vec3::new(-0.5, 0.2, 0.4).normalize();
        let f = l.eval(wo, wi).rgb();
        assert!((f[1] - 0.5 / PI).abs() < 1e-7);
        assert!((l.pdf(wo, wi) - wi.z / PI).abs() < 1e-7);
        let bs = l.sample(wo, Vec2::new(0.25, 0.75)).unwrap();
        // weight = f cos / pdf must equal R.
        let w = l.eval(wo, bs.wi) * bs.wi.z / bs.pdf;
        assert!((w.rgb()[2] - 0.8).abs() < 1e-5 && (bs.weight.rgb()[2] - 0.8).abs() < 1e-7);
        assert!(l.eval(wo, -wi).is_black() && l.eval(-wo, wi).is_black());
    }
}
