//! Smooth plastic: a smooth dielectric coating over an ideal diffuse base (Mitsuba `plastic`).
//!
//! Model: the coating reflects specularly with the Fresnel reflectance of a smooth dielectric
//! interface ([`fresnel_dielectric`]); what it transmits meets a Lambertian base, bounces inside
//! the layer against the coating's internal diffuse reflectance `r_i`, and leaves through the
//! coating (Weidlich & Wilkie 2007 "Arbitrarily layered micro-facet surfaces", GRAPHITE, for the
//! layering; Mitsuba's `plastic` for the internal-scattering normalisation). With `wo` the
//! viewer and `wi` the light, both above the surface, `eta = int_ior / ext_ior`:
//!
//! ```text
//! f_spec          = k_s F(cos_o, eta) delta(wi - reflect(wo)) / cos_i         (a delta lobe)
//! f_diff(wo, wi)  = rho' / pi / eta^2 (1 - F(cos_o, eta)) (1 - F(cos_i, eta))
//!   rho' = rho / (1 - r_i)                   (linear, Mitsuba's default)
//!   rho' = rho / (1 - rho r_i), per channel  (`nonlinear`: the series of inner bounces)
//! ```
//!
//! `r_i = Fdr(1 / eta)` is the hemispherical average of the Fresnel reflectance seen from inside,
//! by the fit of Egan & Hilgeman 1973 for relative indices below 1 and that of d'Eon & Irving
//! 2011 (eq. 5.27's polynomial in 1/eta) above 1 ([`fresnel_diffuse_reflectance`]).
//!
//! Sampling (Mitsuba): the specular lobe with probability
//! `p_s = F(cos_o) w / (F(cos_o) w + (1 - F(cos_o)) (1 - w))`, `w = mean(k_s) / (mean(k_s) +
//! mean(rho))`, else the cosine-weighted hemisphere. The lobes are sampled as two components,
//! not as a mixture: the specular sample's pdf is the discrete `p_s`, its weight `k_s F / p_s`;
//! `eval` and `pdf` cover the diffuse lobe only (`pdf = (1 - p_s) cos_i / pi`).
//!
//! One-sided: black when `wo` or `wi` is below the surface (wrap in `twosided` for both sides).
//!
//! | parameter              | type     | default               | unit                          |
//! |------------------------|----------|-----------------------|-------------------------------|
//! | `diffuse_reflectance`  | spectrum | 0.5                   | albedo of the base            |
//! | `specular_reflectance` | spectrum | 1                     | multiplier of the coating     |
//! | `int_ior`              | float    | 1.49 (polypropylene)  | coating index                 |
//! | `ext_ior`              | float    | 1.000277 (air)        | outside index                 |
//! | `nonlinear`            | bool     | false                 | colour shift by inner bounces |
//!
//! Mitsuba XML:
//! ```xml
//! <bsdf type="plastic">
//!     <rgb name="diffuse_reflectance" value="0.1, 0.27, 0.36"/>
//!     <float name="int_ior" value="1.9"/>
//! </bsdf>
//! ```

use crate::fresnel::fresnel_dielectric;
use crate::BsdfSample;
use pt_math::warp::square_to_cosine_hemisphere;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use std::f32::consts::FRAC_1_PI;

/// Hemispherical average of the Fresnel reflectance, `Fdr(eta) = 2 int_0^1 F(mu, eta) mu dmu`,
/// for light inside a medium of relative index `eta` (the other side's index over this side's):
/// the fit of Egan & Hilgeman 1973 for `eta < 1` and of d'Eon & Irving 2011 (eq. 5.27) for
/// `eta >= 1`, the two Mitsuba uses.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta
    } else {
        let x = 1.0 / eta;
        // Horner form of 0.919317 - 3.4793 x + 6.75335 x^2 - 7.80989 x^3 + 4.98554 x^4
        // - 1.36881 x^5.
        0.919317 + x * (-3.4793 + x * (6.75335 + x * (-7.80989 + x * (4.98554 - 1.36881 * x))))
    }
}

/// A specular sampling weight in [0, 1] (1/2 for NaN or infinity), for both plastics.
pub(crate) fn sane_sampling_weight(w: f32) -> f32 {
    if w.is_finite() {
        w.clamp(0.0, 1.0)
    } else {
        0.5
    }
}

/// Smooth plastic (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct Plastic {
    /// Diffuse base albedo per lane.
    pub diffuse_reflectance: SampledSpectrum,
    /// Coating reflection multiplier per lane.
    pub specular_reflectance: SampledSpectrum,
    /// Relative index of the coating, inside / outside.
    pub eta: f32,
    /// Mitsuba's `nonlinear` flag.
    pub nonlinear: bool,
    /// Share of samples steered to the specular lobe before the Fresnel adjustment.
    pub specular_sampling_weight: f32,
    /// `Fdr(1 / eta)`, the coating's internal diffuse reflectance.
    pub internal_reflectance: f32,
}

impl Plastic {
    /// A smooth plastic. `sampling_weight` is Mitsuba's `mean(k_s) / (mean(k_s) + mean(rho))`,
    /// computed by the caller from the full spectra (not from a path's four wavelengths), so
    /// that the sampling does not change per path. An `eta` that is not finite and positive
    /// becomes polypropylene's.
    pub fn new(
        diffuse_reflectance: SampledSpectrum,
        specular_reflectance: SampledSpectrum,
        eta: f32,
        nonlinear: bool,
        sampling_weight: f32,
    ) -> Self {
        let eta = if eta.is_finite() && eta > 0.0 {
            eta
        } else {
            1.49
        };
        Plastic {
            diffuse_reflectance,
            specular_reflectance,
            eta,
            nonlinear,
            specular_sampling_weight: sane_sampling_weight(sampling_weight),
            internal_reflectance: fresnel_diffuse_reflectance(1.0 / eta),
        }
    }

    /// `rho' / eta^2 / pi`: the diffuse term without the two coating transmissions.
    #[inline]
    fn diffuse_base(&self) -> SampledSpectrum {
        let r_i = self.internal_reflectance;
        let rho = self.diffuse_reflectance;
        let scale = FRAC_1_PI / (self.eta * self.eta);
        crate::map_lanes(rho, |x| {
            let denom = if self.nonlinear {
                1.0 - x * r_i
            } else {
                1.0 - r_i
            };
            let v = x / denom * scale;
            if v.is_finite() {
                v
            } else {
                0.0
            }
        })
    }

    /// f(wo, wi) without the cosine, local frame: the diffuse lobe (the specular one is a delta).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        let t =
            (1.0 - fresnel_dielectric(wo.z, self.eta)) * (1.0 - fresnel_dielectric(wi.z, self.eta));
        self.diffuse_base() * t
    }

    /// Probability of choosing the specular lobe for the viewer `wo`, given `F(cos_o)`.
    #[inline]
    fn prob_specular(&self, f_o: f32) -> f32 {
        let w = self.specular_sampling_weight;
        let (ps, pd) = (f_o * w, (1.0 - f_o) * (1.0 - w));
        if ps + pd > 0.0 {
            ps / (ps + pd)
        } else {
            0.5
        }
    }

    /// Solid-angle pdf of `wi`: the diffuse lobe's share of the cosine-weighted hemisphere.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let ps = self.prob_specular(fresnel_dielectric(wo.z, self.eta));
        (1.0 - ps) * wi.z * FRAC_1_PI
    }

    /// Chooses a lobe with `u_lobe`, samples it with `u`.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta);
        let ps = self.prob_specular(f_o);
        if u_lobe < ps {
            return Some(BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: self.specular_reflectance * (f_o / ps),
                pdf: ps,
                delta: true,
                eta: 1.0,
            });
        }
        let wi = square_to_cosine_hemisphere(u);
        if wi.z <= 0.0 {
            return None;
        }
        let pd = 1.0 - ps;
        // f cos / pdf: the cosine and 1/pi of the hemisphere's pdf cancel with the lobe's.
        let t = (1.0 - f_o) * (1.0 - fresnel_dielectric(wi.z, self.eta));
        Some(BsdfSample {
            wi,
            weight: self.diffuse_base() * (std::f32::consts::PI * t / pd),
            pdf: pd * wi.z * FRAC_1_PI,
            delta: false,
            eta: 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fits against the integral they approximate, `2 int F(mu, eta) mu dmu` by a fine
    /// midpoint rule: within 0.005 absolute on both branches (the published accuracy of the
    /// fits is about 1%); a sign or coefficient slip moves them by far more.
    #[test]
    fn diffuse_fresnel_fits_match_the_integral() {
        for eta in [1.0 / 1.9, 1.0 / 1.49, 1.0 / 1.33, 1.33, 1.49, 1.9] {
            let n = 20_000;
            let integral: f64 = (0..n)
                .map(|k| {
                    let mu = (k as f64 + 0.5) / n as f64;
                    2.0 * f64::from(fresnel_dielectric(mu as f32, eta)) * mu / n as f64
                })
                .sum();
            let fit = fresnel_diffuse_reflectance(eta);
            assert!(
                (f64::from(fit) - integral).abs() < 5e-3,
                "eta {eta}: fit {fit}, integral {integral}"
            );
        }
        // Mitsuba's default coating (polypropylene in air) from inside: 0.5905.
        let r_i = fresnel_diffuse_reflectance(1.000277 / 1.49);
        assert!((r_i - 0.5905).abs() < 5e-4, "{r_i}");
    }

    /// Each sample's weight is f cos / pdf of its own lobe: for the diffuse lobe against
    /// `eval` and `pdf`, for the specular one `k_s F / p_s` with pdf `p_s`.
    #[test]
    fn sample_weights_are_the_lobes_own() {
        let p = Plastic::new(
            SampledSpectrum::splat(0.4),
            SampledSpectrum::splat(0.8),
            1.6,
            false,
            0.8 / 1.2,
        );
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let f_o = fresnel_dielectric(0.8, 1.6);
        let s = p.sample(wo, 0.0, Vec2::new(0.3, 0.7)).unwrap();
        assert!(s.delta && (s.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
        assert!((s.weight.0.x - 0.8 * f_o / s.pdf).abs() < 1e-5);
        let d = p.sample(wo, 0.999, Vec2::new(0.3, 0.7)).unwrap();
        assert!(!d.delta);
        let expect = p.eval(wo, d.wi) * (d.wi.z / p.pdf(wo, d.wi));
        assert!((d.weight.0 - expect.0).abs().max_element() < 1e-5);
        assert!((d.pdf - p.pdf(wo, d.wi)).abs() < 1e-6);
    }
}
