//! Mitsuba's `pplastic` (polarized plastic) as its unpolarized variants render it: a rough
//! microfacet reflection added to a Lambertian base seen through two smooth refractions, the
//! polarized BRDF of Baek et al. 2018 ("Simultaneous acquisition of polarimetric SVBRDF and
//! normals", eq. 2-4) with its Mueller matrices reduced to their intensity terms. Unlike
//! `plastic` and `roughplastic`, the two terms are simply added (no inner reflections), which
//! loses energy at grazing angles and is not reciprocal in general.
//!
//! With `wo` the viewer and `wi` the light (local frame, both above the surface), h the half
//! vector, F the unpolarized dielectric Fresnel reflectance at relative index `eta`, D and G the
//! microfacet distribution and Smith's separable masking-shadowing:
//!
//! `f(wo, wi) = k_s F(wo.h) D(h) G(wo, wi) / (4 cos_o cos_i) + (1 - F(cos_o)) (1 - F(cos_i)) rho / pi`
//!
//! Sampling (Mitsuba's): the specular lobe with the fixed probability
//! `mean(k_s) / (mean(k_s) + mean(rho))` by visible normals, else the cosine-weighted
//! hemisphere; the pdf is the mixture of both densities. Front side only.
//!
//! | parameter | type | default | unit |
//! |---|---|---|---|
//! | `diffuse_reflectance` | spectrum/texture | 0.5 | albedo of the base |
//! | `specular_reflectance` | spectrum/texture | 1 | factor on the reflection |
//! | `int_ior`, `ext_ior` | float/name | 1.49, 1.000277 | indices |
//! | `distribution` | string | beckmann | or ggx |
//! | `alpha` (`alpha_u`, `alpha_v`) | float | 0.1 | roughness |

use crate::fresnel::fresnel_dielectric;
use crate::microfacet::Microfacet;
use crate::BsdfSample;
use pt_math::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use std::f32::consts::FRAC_1_PI;

/// Polarized plastic rendered without polarization (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct PPlastic {
    /// Albedo of the base per lane.
    pub diffuse_reflectance: SampledSpectrum,
    /// Factor on the microfacet reflection per lane.
    pub specular_reflectance: SampledSpectrum,
    /// Relative index, inside / outside.
    pub eta: f32,
    /// The reflection's roughness.
    pub mf: Microfacet,
    /// Probability of sampling the reflection: Mitsuba's `mean(k_s) / (mean(k_s) +
    /// mean(rho))`, from the whole textures (computed by the caller).
    pub specular_sampling_weight: f32,
}

impl PPlastic {
    /// The model; a sampling weight that is not a number becomes 1/2.
    pub fn new(
        diffuse_reflectance: SampledSpectrum,
        specular_reflectance: SampledSpectrum,
        eta: f32,
        mf: Microfacet,
        sampling_weight: f32,
    ) -> Self {
        PPlastic {
            diffuse_reflectance,
            specular_reflectance,
            eta,
            mf,
            specular_sampling_weight: crate::plastic::sane_sampling_weight(sampling_weight),
        }
    }

    /// f(wo, wi) without the cosine, local frame.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        // Mitsuba evaluates the reflection wherever both directions are above the surface; the
        // shared term also drops where rounding leaves the pdf's support (a 1e9 weight at
        // grazing angles in `pt stability` without it).
        let f = self.specular_reflectance * self.mf.dielectric_reflection(wo, wi, self.eta);
        let t =
            (1.0 - fresnel_dielectric(wo.z, self.eta)) * (1.0 - fresnel_dielectric(wi.z, self.eta));
        f + self.diffuse_reflectance * (t * FRAC_1_PI)
    }

    /// Solid-angle pdf of `wi`: the mixture of the two lobes' densities.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let ps = self.specular_sampling_weight;
        ps * self.mf.reflection_pdf(wo, wi) + (1.0 - ps) * cosine_hemisphere_pdf(wi)
    }

    /// Chooses a lobe with `u_lobe` and samples it with `u`.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.specular_sampling_weight {
            self.mf.sample_reflection(wo, u)?
        } else {
            square_to_cosine_hemisphere(u)
        };
        let pdf = self.pdf(wo, wi);
        if !(pdf > 0.0) || wi.z <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: self.eval(wo, wi) * (wi.z / pdf),
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}
