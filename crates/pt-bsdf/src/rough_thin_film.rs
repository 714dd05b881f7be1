//! Rough thin film: a thin-film coated interface whose micro-facets each carry the film.
//!
//! Model: Belcour & Barla 2017 ("A Practical Extension to Microfacet Theory for the Modeling of
//! Varying Iridescence", ACM TOG 36(4) 65), Sec. 3: in a microfacet BSDF (Walter et al. 2007,
//! eqs. 20 and 21) the Fresnel term of each micro-facet is replaced by the thin film's Airy
//! reflectance `R(wo.h)` at the facet's local incidence angle ([`ThinFilm::reflectance`], per
//! lane: exact per wavelength in spectral mode, Belcour-Barla integration in RGB mode). The film
//! absorbs nothing, so a dielectric base transmits `T = 1 - R`. With `h` the (generalised) half
//! vector, `D`, `G2` from [`Microfacet`] and `eta'` as in [`crate::RoughDielectric`]:
//!
//! - reflection: `f_r = R(wo.h) D(h) G2 / (4 |cos_i cos_o|)`;
//! - refraction (dielectric base): `f_t = (1 - R(wo.h)) D(h) G2 |wi.h wo.h| /
//!   (|cos_i cos_o| (wi.h + wo.h/eta')^2) / eta'^2` (radiance transport).
//!
//! Sampling: a normal from [`Microfacet::sample_m`], then reflection with probability
//! `P(m) = mean of R(wo.m) over the lanes`, else refraction; pdfs as Walter eqs. 14 and 17 with
//! `P` in place of `F`. Thickness 0 gives the bare rough conductor / rough dielectric (tested).
//! A conductor base is one-sided; a dielectric base handles both sides (`wo.z < 0`: inside).
//!
//! | parameter      | type   | default | unit                                          |
//! |----------------|--------|---------|-----------------------------------------------|
//! | (all of `thinfilm`) |   |         | thickness nm, film_ior, ext_ior, base         |
//! | `distribution` | string | beckmann | `ggx` or `beckmann` (Mitsuba's rough* default) |
//! | `alpha`, `alpha_u`, `alpha_v` | float | 0.1 | roughness, dimensionless            |
//!
//! Mitsuba XML (project extension):
//! ```xml
//! <bsdf type="roughthinfilm">
//!     <float name="thickness" value="400"/>
//!     <float name="alpha" value="0.15"/>
//!     <float name="eta" value="0.3"/> <float name="k" value="2.6"/>
//! </bsdf>
//! ```

use crate::fresnel::refract;
use crate::microfacet::Microfacet;
use crate::thin_film::{FilmBase, ThinFilm};
use crate::BsdfSample;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;

/// Thin film on a rough base (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct RoughThinFilm {
    /// The film and its base (its `reflectance` gives R per lane at a facet's incidence cosine).
    pub film: ThinFilm,
    /// The micro-facet distribution of the base (the film follows it).
    pub mf: Microfacet,
}

impl RoughThinFilm {
    /// A rough film from a smooth film description and a distribution.
    pub fn new(film: ThinFilm, mf: Microfacet) -> Self {
        RoughThinFilm { film, mf }
    }

    /// Relative index inside / outside of a dielectric base, `None` for a conductor.
    fn eta(&self) -> Option<f32> {
        match self.film.base {
            FilmBase::Dielectric { ior } => Some(ior / self.film.ext_ior),
            FilmBase::Conductor { .. } => None,
        }
    }

    /// Mean of the meaningful lanes (the lobe-selection probability).
    fn mean(&self, r: SampledSpectrum) -> f32 {
        let n = self.film.lanes();
        (r.0.to_array()[..n].iter().sum::<f32>() / n as f32).clamp(0.0, 1.0)
    }

    /// Half vector, `eta'` and whether the pair is a reflection; `None` when degenerate (and
    /// for anything but a reflection above a conductor base, which is one-sided).
    fn half(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32, bool)> {
        match self.eta() {
            Some(eta) => crate::microfacet::generalized_half(wo, wi, eta),
            None if wo.z > 0.0 && wi.z > 0.0 => crate::microfacet::generalized_half(wo, wi, 1.0),
            None => None,
        }
    }

    /// f(wo, wi) without the cosine (radiance transport), per lane.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let Some((h, etap, reflect)) = self.half(wo, wi) else {
            return SampledSpectrum::ZERO;
        };
        let d = self.mf.d(h);
        if d == 0.0 {
            return SampledSpectrum::ZERO;
        }
        // The film's reflectance at the facet; h faces +z, so wo.h is negative exactly when the
        // viewer is inside a dielectric base, which is what the film's signed cosine means.
        let r = self.film.reflectance(wo.dot(h));
        let g = self.mf.g2(wo, wi);
        let v = if reflect {
            r * (d * g / (4.0 * (wi.z * wo.z).abs()))
        } else {
            let denom = (wi.dot(h) + wo.dot(h) / etap).powi(2) * wi.z * wo.z;
            let t = SampledSpectrum::splat(1.0) + r * -1.0;
            t * (d * g * (wi.dot(h) * wo.dot(h) / denom).abs() / (etap * etap))
        };
        if v.is_finite() {
            v
        } else {
            SampledSpectrum::ZERO
        }
    }

    /// Solid-angle pdf of `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(half) = self.half(wo, wi) else {
            return 0.0;
        };
        let p_r = if self.eta().is_some() {
            self.mean(self.film.reflectance(wo.dot(half.0)))
        } else {
            1.0
        };
        crate::microfacet::interface_pdf(&self.mf, wo, wi, half, p_r)
    }

    /// Samples a micro-normal, then reflection (probability P) or refraction.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() || (self.eta().is_none() && wo.z < 0.0) {
            return None;
        }
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let m = self.mf.sample_m(wo_up, u);
        if wo_up.dot(m) <= 0.0 {
            return None;
        }
        let (wi, eta) = match self.eta() {
            Some(eta) if u_lobe >= self.mean(self.film.reflectance(wo.dot(m))) => {
                let (wi, etap) = refract(wo, m, eta)?;
                if wi.z * wo.z >= 0.0 {
                    return None;
                }
                (wi, etap)
            }
            _ => {
                let wi = (2.0 * wo.dot(m) * m - wo).normalize();
                if wi.z * wo.z <= 0.0 {
                    return None;
                }
                (wi, 1.0)
            }
        };
        let pdf = self.pdf(wo, wi);
        if !(pdf > 0.0) {
            return None;
        }
        let weight = self.eval(wo, wi) * (wi.z.abs() / pdf);
        if !weight.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
            eta,
        })
    }
}
