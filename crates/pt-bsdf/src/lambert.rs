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
use pt_math::lanes::V3;
use pt_math::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere_lanes};
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

    /// f = R / pi when both directions are above the surface (local frame). (One lane of
    /// [`Lambert::eval_lanes`].)
    #[inline(always)]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        Lambert::eval_lanes(&[self.reflectance], &[wo.z], &[wi.z])[0]
    }

    /// Cosine-weighted pdf of `wi` (solid angle), 0 when either side is below. (One lane of
    /// [`Lambert::pdf_lanes`].)
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        Lambert::pdf_lanes(&[wo.z], &[wi.z])[0]
    }

    /// Cosine-weighted sample; weight = R. (One lane of [`Lambert::sample_lanes`].)
    #[inline(always)]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        let (wi, pdf, ok) = Lambert::sample_lanes(&[wo.z], &[u.x], &[u.y]);
        ok[0].then(|| BsdfSample {
            wi: wi.get(0),
            weight: self.reflectance,
            pdf: pdf[0],
            delta: false,
            eta: 1.0,
        })
    }

    /// [`Lambert::eval`] for `N` lanes, from the z components (cosines) of `wo` and `wi` in
    /// each lane's local frame (all the model reads) and each lane's albedo `r`.
    #[inline(always)]
    pub fn eval_lanes<const N: usize>(
        r: &[SampledSpectrum; N],
        wo_z: &[f32; N],
        wi_z: &[f32; N],
    ) -> [SampledSpectrum; N] {
        pt_math::lanes::lanes(|k| {
            if wo_z[k] > 0.0 && wi_z[k] > 0.0 {
                r[k] * FRAC_1_PI
            } else {
                SampledSpectrum::ZERO
            }
        })
    }

    /// [`Lambert::pdf`] for `N` lanes: cos(theta_i) / pi where `wo` is above the surface.
    #[inline(always)]
    pub fn pdf_lanes<const N: usize>(wo_z: &[f32; N], wi_z: &[f32; N]) -> [f32; N] {
        pt_math::lanes::lanes(|k| {
            if wo_z[k] > 0.0 {
                cosine_hemisphere_pdf_z(wi_z[k])
            } else {
                0.0
            }
        })
    }

    /// [`Lambert::sample`] for `N` lanes: the cosine-weighted directions (local frames) for
    /// the uniform numbers `(ux, uy)`, their pdfs, and whether each lane's sample exists
    /// (`wo` above the surface and a non-zero pdf: a grazing sample exactly on the horizon
    /// carries no energy). The weight of an existing sample is the lane's albedo.
    #[inline(always)]
    pub fn sample_lanes<const N: usize>(
        wo_z: &[f32; N],
        ux: &[f32; N],
        uy: &[f32; N],
    ) -> (V3<N>, [f32; N], [bool; N]) {
        let wi = square_to_cosine_hemisphere_lanes(ux, uy);
        let pdf: [f32; N] = pt_math::lanes::lanes(|k| cosine_hemisphere_pdf_z(wi.z[k]));
        let ok = pt_math::lanes::lanes(|k| !(wo_z[k] <= 0.0) & !(pdf[k] <= 0.0));
        (wi, pdf, ok)
    }
}

/// [`cosine_hemisphere_pdf`] of a direction given by its z component.
#[inline(always)]
fn cosine_hemisphere_pdf_z(z: f32) -> f32 {
    cosine_hemisphere_pdf(Vec3::new(0.0, 0.0, z))
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

    /// The lane kernels give every lane what one lane gives, bit for bit, over above, below
    /// and grazing directions (the path tracer runs them for eight paths at once).
    #[test]
    fn eight_lanes_match_one_lane_bit_for_bit() {
        let r: [SampledSpectrum; 8] =
            std::array::from_fn(|k| SampledSpectrum::from_rgb([0.1 * k as f32, 0.5, 0.9]));
        let wo_z = [0.9, -0.3, 0.0, 1e-9, 0.5, -1.0, 0.7, 0.2];
        let wi_z = [0.4, 0.4, 0.3, -0.2, 0.0, 0.8, 1.0, -0.6];
        let ux = [0.1, 0.5, 0.5, 0.99, 0.0, 0.3, 0.77, 0.25];
        let uy = [0.9, 0.5, 0.0, 0.01, 0.0, 0.6, 0.33, 0.75];
        let f = Lambert::eval_lanes(&r, &wo_z, &wi_z);
        let pdf = Lambert::pdf_lanes(&wo_z, &wi_z);
        let (wi, spdf, ok) = Lambert::sample_lanes(&wo_z, &ux, &uy);
        for k in 0..8 {
            let l = Lambert::new(r[k]);
            let (wo, w) = (Vec3::new(0.0, 0.0, wo_z[k]), Vec3::new(0.0, 0.0, wi_z[k]));
            assert_eq!(
                f[k].0.to_array().map(f32::to_bits),
                l.eval(wo, w).0.to_array().map(f32::to_bits)
            );
            assert_eq!(pdf[k].to_bits(), l.pdf(wo, w).to_bits());
            let one = l.sample(wo, Vec2::new(ux[k], uy[k]));
            assert_eq!(ok[k], one.is_some(), "lane {k}");
            if let Some(b) = one {
                assert_eq!(
                    b.wi.to_array().map(f32::to_bits),
                    wi.get(k).to_array().map(f32::to_bits)
                );
                assert_eq!(b.pdf.to_bits(), spdf[k].to_bits());
            }
        }
    }
}
