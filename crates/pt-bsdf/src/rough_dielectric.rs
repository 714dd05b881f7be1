//! Rough dielectric interface: microfacet reflection and refraction (frosted glass).
//!
//! Model: Walter, Marschner, Li & Torrance 2007, "Microfacet Models for Refraction through
//! Rough Surfaces", EGSR; in the form of pbrt-v4 `DielectricBxDF` (rough branch).
//! With `eta' = 1` for reflection, else the index on `wi`'s side over `wo`'s side (`eta` when
//! `wo.z > 0`, `1/eta` when the viewer is inside), the generalised half vector is
//! `h = normalize(eta' wi + wo)` facing +z (Walter eqs. 13 and 16), and with `F = F(wo.h)`
//! the exact dielectric Fresnel ([`fresnel_dielectric`]; for refraction evaluated from both
//! cosines of the pair, which is symmetric in floating point):
//! - reflection (eq. 20): `f_r = F D(h) G2 / (4 |cos_i cos_o|)`;
//! - refraction (eq. 21): `f_t = (1 - F) D(h) G2 |wi.h wo.h| / (|cos_i cos_o| (wi.h + wo.h/eta')^2)
//!   / eta'^2`, the last factor being radiance transport (pbrt-v4 `TransportMode::Radiance`;
//!   see [`crate::dielectric`]). Not symmetric; it obeys the generalised reciprocity
//!   `f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2`, `n_o`, `n_i` the indices on the sides of `wo` and
//!   `wi` (Veach 1997, Sec. 5.2; tested).
//! - `G2` is the height-correlated Smith term, `D` GGX or Beckmann, anisotropic
//!   ([`crate::microfacet`]). Micro-normals facing away from `wo` or `wi` contribute 0.
//!
//! Sampling: a normal `m` from [`Microfacet::sample_m`] (visible normals for GGX, Heitz 2018),
//! then reflection with probability `F(wo.m)`, else refraction through `m`. Pdfs (Walter eqs.
//! 14 and 17): reflection `pdf_m(h) F / (4 |wo.h|)`, refraction
//! `pdf_m(h) (1 - F) |wi.h| / (wi.h + wo.h/eta')^2`. Samples leaving on the wrong side are
//! rejected (`None`), which the pdf accounts for.
//!
//! Two-sided by nature (`wo.z < 0` is inside): do not wrap it in a two-sided `SurfaceBsdf`.
//!
//! | parameter                | type     | default   | unit                              |
//! |--------------------------|----------|-----------|-----------------------------------|
//! | `int_ior`                | float    | 1.5046    | index inside (BK7)                |
//! | `ext_ior`                | float    | 1.000277  | index outside (air)               |
//! | `distribution`           | string   | beckmann  | `ggx`, `beckmann` (Mitsuba default beckmann) |
//! | `alpha`, `alpha_u`, `alpha_v` | float | 0.1     | roughness, dimensionless, >= 1e-3 |
//! | `specular_reflectance`   | spectrum | 1         | multiplier (not physical)         |
//! | `specular_transmittance` | spectrum | 1         | multiplier (not physical)         |
//!
//! Mitsuba XML:
//! ```xml
//! <bsdf type="roughdielectric">
//!     <string name="distribution" value="ggx"/>
//!     <float name="alpha" value="0.2"/>
//!     <float name="int_ior" value="1.5"/>
//! </bsdf>
//! ```

use crate::dielectric::sane_eta;
use crate::fresnel::{fresnel_dielectric, refract};
use crate::microfacet::Microfacet;
use crate::BsdfSample;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;

/// Fresnel transmittance `1 - R` of an interface from both cosines of a refraction pair
/// (`cos_1` on the side of index 1, `cos_2` on the side of index `etap`, related by Snell's
/// law), instead of deriving `cos_2` from `cos_1`: the same value in exact arithmetic, but
/// symmetric under exchanging the sides in floating point too (both amplitude ratios only
/// change sign), and free of the `sqrt(1 - sin^2/eta^2)` cancellation near total internal
/// reflection. This keeps the BTDF's generalised reciprocity to rounding.
fn fresnel_transmittance_pair(cos_1: f32, cos_2: f32, etap: f32) -> f32 {
    let r_parl = (etap * cos_1 - cos_2) / (etap * cos_1 + cos_2);
    let r_perp = (cos_1 - etap * cos_2) / (cos_1 + etap * cos_2);
    let t = 1.0 - 0.5 * (r_parl * r_parl + r_perp * r_perp);
    if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Rough dielectric interface.
#[derive(Clone, Copy, Debug)]
pub struct RoughDielectric {
    /// Relative index inside / outside.
    pub eta: f32,
    /// Microfacet distribution and roughness.
    pub mf: Microfacet,
    /// Reflection multiplier.
    pub specular_reflectance: SampledSpectrum,
    /// Transmission multiplier.
    pub specular_transmittance: SampledSpectrum,
}

/// The generalised half vector and `eta'` of a pair, or `None` for a degenerate or back-facing
/// configuration.
struct Half {
    h: Vec3,
    etap: f32,
    reflect: bool,
}

impl RoughDielectric {
    /// A rough dielectric with relative index `eta = int_ior / ext_ior`, unit multipliers.
    pub fn new(eta: f32, mf: Microfacet) -> Self {
        let one = SampledSpectrum::splat(1.0);
        RoughDielectric {
            eta: sane_eta(eta),
            mf,
            specular_reflectance: one,
            specular_transmittance: one,
        }
    }

    fn half(&self, wo: Vec3, wi: Vec3) -> Option<Half> {
        let (h, etap, reflect) = crate::microfacet::generalized_half(wo, wi, self.eta)?;
        Some(Half { h, etap, reflect })
    }

    /// f(wo, wi) without the cosine (radiance transport).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let Some(Half { h, etap, reflect }) = self.half(wo, wi) else {
            return SampledSpectrum::ZERO;
        };
        let d = self.mf.d(h);
        if d == 0.0 {
            return SampledSpectrum::ZERO;
        }
        let g = self.mf.g2(wo, wi);
        let (v, mult) = if reflect {
            let f = fresnel_dielectric(wo.dot(h), self.eta);
            (
                f * d * g / (4.0 * (wi.z * wo.z).abs()),
                self.specular_reflectance,
            )
        } else {
            let t = fresnel_transmittance_pair(wo.dot(h).abs(), wi.dot(h).abs(), etap);
            let denom = (wi.dot(h) + wo.dot(h) / etap).powi(2) * wi.z * wo.z;
            (
                t * d * g * (wi.dot(h) * wo.dot(h) / denom).abs() / (etap * etap),
                self.specular_transmittance,
            )
        };
        if v.is_finite() {
            mult * v
        } else {
            SampledSpectrum::ZERO
        }
    }

    /// Solid-angle pdf of `wi`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(Half { h, etap, reflect }) = self.half(wo, wi) else {
            return 0.0;
        };
        let r = fresnel_dielectric(wo.dot(h), self.eta);
        crate::microfacet::interface_pdf(&self.mf, wo, wi, (h, etap, reflect), r)
    }

    /// Samples a micro-normal, then reflection (probability F) or refraction.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let m = self.mf.sample_m(wo_up, u);
        if wo_up.dot(m) <= 0.0 {
            return None;
        }
        let r = fresnel_dielectric(wo.dot(m), self.eta);
        let (wi, eta) = if u_lobe < r {
            let wi = (2.0 * wo.dot(m) * m - wo).normalize();
            if wi.z * wo.z <= 0.0 {
                return None;
            }
            (wi, 1.0)
        } else {
            let (wi, etap) = refract(wo, m, self.eta)?;
            if wi.z * wo.z >= 0.0 {
                return None;
            }
            (wi, etap)
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
