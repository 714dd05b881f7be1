//! Oren-Nayar rough diffuse reflection, four variants.
//!
//! A surface of V-cavities whose facets are Lambertian, with facet slope angles normally
//! distributed with standard deviation `sigma` (radians). All variants equal [`Lambert`]
//! exactly at `sigma = 0`, are one-sided (black when `wo` or `wi` is below the surface) and are
//! clamped at 0 where their formula goes negative.
//!
//! Notation: `cos_i = wi.z`, `cos_o = wo.z`, `alpha = max(theta_i, theta_o)`,
//! `beta = min(theta_i, theta_o)`, `cos_phi` = cosine of the azimuth difference,
//! `s = wi.wo - cos_i cos_o = sin_i sin_o cos_phi`.
//!
//! - [`OrenNayarVariant::Qualitative`] (default): Oren & Nayar 1994, "Generalization of
//!   Lambert's Reflectance Model", SIGGRAPH '94, the "qualitative model" that closes Sec. 4:
//!   `f = rho/pi (A + B max(0, cos_phi) sin(alpha) tan(beta))`,
//!   `A = 1 - 0.5 sigma^2/(sigma^2 + 0.33)`, `B = 0.45 sigma^2/(sigma^2 + 0.09)`.
//! - [`OrenNayarVariant::Full`]: the same paper's full model (Sec. 4), direct term
//!   `L1 = rho/pi [C1 + cos_phi C2 tan(beta) + (1 - |cos_phi|) C3 tan((alpha+beta)/2)]` with
//!   `C1 = A`, `C2 = 0.45 sigma^2/(sigma^2+0.09) sin(alpha)` for `cos_phi >= 0`, else
//!   `0.45 sigma^2/(sigma^2+0.09) (sin(alpha) - (2 beta/pi)^3)`,
//!   `C3 = 0.125 sigma^2/(sigma^2+0.09) (4 alpha beta/pi^2)^2`, plus the interreflection term
//!   `L2 = 0.17 rho^2/pi sigma^2/(sigma^2+0.13) (1 - cos_phi (2 beta/pi)^2)`; `f = max(0, L1 + L2)`
//!   per lane (it goes negative at forward grazing). The paper's equation numbers are not
//!   quoted here because they were not checked against the printed paper.
//! - [`OrenNayarVariant::Fujii`]: Y. Fujii, "A tiny improvement of Oren-Nayar reflectance
//!   model" (2013, mimosa-pudica.net/improved-oren-nayar.html), "FON":
//!   `f = rho/pi A_F (1 + r s/t)`, `t = max(cos_i, cos_o)` if `s > 0` else 1,
//!   `A_F = 1/(1 + (1/2 - 2/(3 pi)) r)`. Its roughness `r` in [0, 1] is **not** a slope angle.
//!   Conversion used here ([`fujii_roughness`]): `r = B/A` of the qualitative model at the given
//!   `sigma`, which gives FON the same ratio of the `s/t` term to the constant term as the
//!   qualitative model (whose `max(0,cos_phi) sin(alpha) tan(beta)` equals `max(0, s)/t`).
//!   It maps `sigma` in [0, inf) to `r` in [0, 0.9), inside Fujii's range. Fujii gives no
//!   conversion himself. [`OrenNayar::from_fujii_roughness`] takes `r` directly.
//! - [`OrenNayarVariant::Eon`]: energy-preserving Oren-Nayar, J. Portsmouth, P. Kutz, S. Hill,
//!   "EON: A practical energy-preserving rough diffuse BRDF", JCGT 14(1), 2025
//!   (arXiv 2410.18026), Listing 1: FON single scattering plus the multiple-scattering lobe
//!   `f_ms = rho_ms/pi (1 - E_F(cos_o)) (1 - E_F(cos_i)) / (1 - Ebar_F)`,
//!   `rho_ms = rho^2 Ebar_F / (1 - rho (1 - Ebar_F))`, with the exact FON albedo
//!   `E_F(mu) = A_F + B_F/pi G(mu)`,
//!   `G = S (acos(mu) - S mu) + 2/3 (S/mu (1 - S^3) - S)` with `S = sqrt(1 - mu^2)`,
//!   `Ebar_F = A_F (1 + (2/3 - 28/(15 pi)) r)`. Its directional albedo is analytic
//!   ([`OrenNayar::albedo`]): `rho E_F + rho_ms (1 - E_F)`, which is exactly 1 for `rho = 1`.
//!   Same roughness `r` as Fujii, same conversion from `sigma`.
//!
//! Sampling: cosine-weighted hemisphere (pdf `cos_i / pi`) for Qualitative, Full and Fujii;
//! for EON the paper's clipped linearly transformed cosine (CLTC) mixed with a uniform
//! hemisphere (the paper's sampling listings: `ltc_terms`, `cltc_sample`, `cltc_pdf`,
//! `sample_EON`), which follows `f cos` much more closely at high roughness. The CLTC pdf is
//! set to 0 below the horizon, which is exactly the region its clipping removes.
//! Equation and listing numbers of the EON paper are given as found in public copies of its
//! code, not checked against the typeset paper.
//!
//! | parameter     | type     | default       | unit                                   |
//! |---------------|----------|---------------|----------------------------------------|
//! | `reflectance` | spectrum | 0.5           | albedo of the facets, [0, 1]           |
//! | `sigma`       | float    | 0             | radians, std. dev. of facet slope angle |
//! | `variant`     | string   | `qualitative` | `qualitative`, `full`, `fujii`, `eon`  |
//!
//! Mitsuba XML (project extension, also registered as a Mitsuba Python plugin):
//! ```xml
//! <bsdf type="orennayar">
//!     <rgb name="reflectance" value="0.8, 0.6, 0.4"/>
//!     <float name="sigma" value="0.35"/>
//!     <string name="variant" value="eon"/>
//! </bsdf>
//! ```
//!
//! [`Lambert`]: crate::Lambert

use crate::{map_lanes, BsdfSample};
use pt_math::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use std::f32::consts::{FRAC_1_PI, PI};

/// Which Oren-Nayar formula to evaluate (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum OrenNayarVariant {
    /// Oren & Nayar 1994 qualitative A/B model.
    #[default]
    Qualitative,
    /// Oren & Nayar 1994 full model with C1..C3 and the rho^2 interreflection term.
    Full,
    /// Fujii's improved model (FON).
    Fujii,
    /// Energy-preserving Oren-Nayar (Portsmouth, Kutz & Hill 2025).
    Eon,
}

impl OrenNayarVariant {
    /// Parses the XML `variant` string (`qualitative`, `full`, `fujii`, `eon`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "qualitative" => Some(Self::Qualitative),
            "full" => Some(Self::Full),
            "fujii" => Some(Self::Fujii),
            "eon" => Some(Self::Eon),
            _ => None,
        }
    }
}

/// `1/2 - 2/(3 pi)`: FON's A coefficient is `1/(1 + C1_FON r)` (EON Listing 1).
const C1_FON: f32 = 0.5 - 2.0 / (3.0 * PI);
/// `2/3 - 28/(15 pi)`: FON's hemispherical average albedo is `A_F (1 + C2_FON r)`.
const C2_FON: f32 = 2.0 / 3.0 - 28.0 / (15.0 * PI);

/// Qualitative-model coefficients (A, B) for slope deviation `sigma` (radians).
pub fn qualitative_ab(sigma: f32) -> (f32, f32) {
    let s2 = sigma * sigma;
    (1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09))
}

/// Fujii's roughness `r` in [0, 0.9) for a slope deviation `sigma` in radians: `B/A` of the
/// qualitative model (see the module documentation for why).
pub fn fujii_roughness(sigma: f32) -> f32 {
    let (a, b) = qualitative_ab(sigma.max(0.0));
    b / a
}

/// FON directional albedo at `rho = 1`, exact (EON Listing 1, `E_FON_exact`).
/// `(sin/mu)(1 - sin^3)` is rewritten as `sin mu (1 + sin + sin^2)/(1 + sin)` (using
/// `1 - sin = mu^2/(1 + sin)`), which is finite at `mu = 0` where the original is 0/0.
pub fn fon_albedo(mu: f32, r: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    let a_f = 1.0 / (1.0 + C1_FON * r);
    let b_f = r * a_f;
    let si = (1.0 - mu * mu).max(0.0).sqrt();
    let g = si * (mu.acos() - si * mu)
        + (2.0 / 3.0) * (si * mu * (1.0 + si + si * si) / (1.0 + si) - si);
    a_f + b_f * FRAC_1_PI * g
}

/// Oren-Nayar BRDF (one-sided).
#[derive(Clone, Copy, Debug)]
pub struct OrenNayar {
    /// Facet albedo per lane, [0, 1].
    pub reflectance: SampledSpectrum,
    /// Slope deviation in radians; `None` when made from Fujii's roughness directly.
    sigma: Option<f32>,
    /// Formula.
    pub variant: OrenNayarVariant,
    // Precomputed: (A, B) of the qualitative/full model, or (A_F, r) for Fujii/EON.
    a: f32,
    b: f32,
}

impl OrenNayar {
    /// Oren-Nayar with facet albedo `reflectance`, slope deviation `sigma` in radians (negative
    /// values are taken as 0) and the given formula. Fujii and EON convert `sigma` with
    /// [`fujii_roughness`].
    pub fn new(reflectance: SampledSpectrum, sigma: f32, variant: OrenNayarVariant) -> Self {
        let sigma = if sigma.is_finite() {
            sigma.max(0.0)
        } else {
            0.0
        };
        match variant {
            OrenNayarVariant::Qualitative | OrenNayarVariant::Full => {
                let (a, b) = qualitative_ab(sigma);
                OrenNayar {
                    reflectance,
                    sigma: Some(sigma),
                    variant,
                    a,
                    b,
                }
            }
            OrenNayarVariant::Fujii | OrenNayarVariant::Eon => {
                Self::from_fujii_roughness(reflectance, fujii_roughness(sigma), variant)
                    .with_sigma(sigma)
            }
        }
    }

    /// Fujii or EON with Fujii's roughness `r` given directly, clamped to [0, 1]. Any other
    /// variant is treated as Fujii.
    pub fn from_fujii_roughness(
        reflectance: SampledSpectrum,
        r: f32,
        variant: OrenNayarVariant,
    ) -> Self {
        let r = if r.is_finite() {
            r.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let variant = if variant == OrenNayarVariant::Eon {
            variant
        } else {
            OrenNayarVariant::Fujii
        };
        OrenNayar {
            reflectance,
            sigma: None,
            variant,
            a: 1.0 / (1.0 + C1_FON * r),
            b: r,
        }
    }

    fn with_sigma(mut self, sigma: f32) -> Self {
        self.sigma = Some(sigma);
        self
    }

    /// The slope deviation in radians it was made from (`None` if made from a roughness).
    pub fn sigma(&self) -> Option<f32> {
        self.sigma
    }

    /// Fujii's roughness `r` (Fujii and EON only; 0 otherwise).
    pub fn roughness(&self) -> f32 {
        match self.variant {
            OrenNayarVariant::Fujii | OrenNayarVariant::Eon => self.b,
            _ => 0.0,
        }
    }

    /// f(wo, wi) without the cosine.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        let (cos_i, cos_o) = (wi.z.min(1.0), wo.z.min(1.0));
        let s = wi.dot(wo) - cos_i * cos_o;
        let rho = self.reflectance;
        match self.variant {
            OrenNayarVariant::Qualitative => {
                // max(0, cos_phi) sin(alpha) tan(beta) = max(0, s) / max(cos_i, cos_o).
                let t = cos_i.max(cos_o);
                rho * (FRAC_1_PI * (self.a + self.b * s.max(0.0) / t))
            }
            OrenNayarVariant::Full => self.eval_full(wo, wi, s),
            OrenNayarVariant::Fujii => {
                let r = self.b;
                let s_over_t = if s > 0.0 { s / cos_i.max(cos_o) } else { s };
                rho * (FRAC_1_PI * self.a * (1.0 + r * s_over_t).max(0.0))
            }
            OrenNayarVariant::Eon => {
                let r = self.b;
                let s_over_t = if s > 0.0 { s / cos_i.max(cos_o) } else { s };
                let f_ss = rho * (FRAC_1_PI * self.a * (1.0 + r * s_over_t).max(0.0));
                let (e_o, e_i) = (fon_albedo(cos_o, r), fon_albedo(cos_i, r));
                let avg = self.a * (1.0 + C2_FON * r);
                const EPS: f32 = 1e-7;
                let lobe =
                    FRAC_1_PI * (1.0 - e_o).max(EPS) * (1.0 - e_i).max(EPS) / (1.0 - avg).max(EPS);
                f_ss + self.rho_ms(avg) * lobe
            }
        }
    }

    /// `rho_ms = rho^2 Ebar / (1 - rho (1 - Ebar))` per lane (EON Listing 1).
    fn rho_ms(&self, avg: f32) -> SampledSpectrum {
        map_lanes(self.reflectance, |rho| {
            rho * rho * avg / (1.0 - rho * (1.0 - avg)).max(1e-7)
        })
    }

    fn eval_full(&self, wo: Vec3, wi: Vec3, s: f32) -> SampledSpectrum {
        let sigma = self.sigma.unwrap_or(0.0); // Full is always made from sigma
        let sigma2 = sigma * sigma;
        let (theta_i, theta_o) = (wi.z.min(1.0).acos(), wo.z.min(1.0).acos());
        let (alpha, beta) = (theta_i.max(theta_o), theta_i.min(theta_o));
        let sin_i = (1.0 - wi.z * wi.z).max(0.0).sqrt();
        let sin_o = (1.0 - wo.z * wo.z).max(0.0).sqrt();
        let denom = sin_i * sin_o;
        let cos_phi = if denom > 1e-6 {
            (s / denom).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let k = 0.45 * sigma2 / (sigma2 + 0.09);
        let two_beta_pi = 2.0 * beta / PI;
        let c2 = if cos_phi >= 0.0 {
            k * alpha.sin()
        } else {
            k * (alpha.sin() - two_beta_pi.powi(3))
        };
        let c3 = 0.125 * sigma2 / (sigma2 + 0.09) * (4.0 * alpha * beta / (PI * PI)).powi(2);
        // tan of angles < pi/2, guarded where both directions graze (value stays finite).
        let tan_beta = beta.sin() / beta.cos().max(1e-7);
        let half = 0.5 * (alpha + beta);
        let tan_half = half.sin() / half.cos().max(1e-7);
        let l1 =
            FRAC_1_PI * (self.a + cos_phi * c2 * tan_beta + (1.0 - cos_phi.abs()) * c3 * tan_half);
        let l2 = FRAC_1_PI * 0.17 * sigma2 / (sigma2 + 0.13)
            * (1.0 - cos_phi * two_beta_pi * two_beta_pi);
        map_lanes(self.reflectance, |rho| (rho * l1 + rho * rho * l2).max(0.0))
    }

    /// Directional albedo at `wo` where it is analytic: Lambert (`sigma = 0`) and EON
    /// (`rho E_F + rho_ms (1 - E_F)`). `None` for the other variants.
    pub fn albedo(&self, wo: Vec3) -> Option<SampledSpectrum> {
        if wo.z <= 0.0 {
            return Some(SampledSpectrum::ZERO);
        }
        match self.variant {
            OrenNayarVariant::Eon => {
                let r = self.b;
                let e = fon_albedo(wo.z, r);
                let avg = self.a * (1.0 + C2_FON * r);
                Some(self.reflectance * e + self.rho_ms(avg) * (1.0 - e))
            }
            OrenNayarVariant::Fujii if self.b == 0.0 => Some(self.reflectance),
            OrenNayarVariant::Qualitative | OrenNayarVariant::Full if self.sigma == Some(0.0) => {
                Some(self.reflectance)
            }
            _ => None,
        }
    }

    /// Solid-angle pdf of `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        match self.variant {
            OrenNayarVariant::Eon => eon_pdf(wo, wi, self.b),
            _ => cosine_hemisphere_pdf(wi),
        }
    }

    /// Samples `wi` (cosine-weighted, or the EON CLTC mixture).
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let (wi, pdf) = match self.variant {
            OrenNayarVariant::Eon => eon_sample(wo, self.b, u)?,
            _ => {
                let wi = square_to_cosine_hemisphere(u);
                (wi, cosine_hemisphere_pdf(wi))
            }
        };
        if !(pdf > 0.0) || wi.z <= 0.0 {
            return None;
        }
        let weight = self.eval(wo, wi) * (wi.z / pdf);
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}

/// LTC coefficients (a, b, c, d) of `M = [[a, 0, b], [0, c, 0], [d, 0, 1]]` fitted to FON's
/// `f cos` at `mu = cos_o` and roughness `r` (EON paper, `ltc_terms`).
fn ltc_terms(mu: f32, r: f32) -> (f32, f32, f32, f32) {
    let a =
        1.0 + r * (0.303392 + (-0.518982 + 0.111709 * mu) * mu + (-0.276266 + 0.335918 * mu) * r);
    let b =
        r * (-1.16407 + 1.15859 * mu + (0.150815 - 0.150105 * mu) * r) / (mu * mu * mu - 1.43545);
    let c = 1.0 + (0.20013 + (-0.506373 + 0.261777 * mu) * mu) * r;
    let d = ((0.540852 + (-1.01625 + 0.475392 * mu) * mu) * r) / (-1.0743 + mu * (0.0725628 + mu));
    (a, b, c, d)
}

/// Frame of the LTC: x along the azimuth of `wo`, z the normal (EON `orthonormal_basis_ltc`).
fn ltc_basis(wo: Vec3) -> (Vec3, Vec3) {
    let len2 = wo.x * wo.x + wo.y * wo.y;
    let x = if len2 > 0.0 {
        Vec3::new(wo.x, wo.y, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    (x, Vec3::new(-x.y, x.x, 0.0))
}

/// Probability of the uniform-hemisphere component of the EON sampler (`sample_EON`).
fn eon_uniform_prob(mu: f32, r: f32) -> f32 {
    (r.powf(0.1) * (0.162925 + mu * (-0.372058 + (0.538233 - 0.290822 * mu) * mu))).clamp(0.0, 1.0)
}

/// CLTC pdf of `wi` (local frame); 0 below the horizon, which is exactly the region that the
/// clipping removes (`d wh.x + wh.z < 0`).
fn cltc_pdf(wo: Vec3, wi: Vec3, r: f32) -> f32 {
    if wi.z <= 0.0 {
        return 0.0;
    }
    let (bx, by) = ltc_basis(wo);
    let w = Vec3::new(wi.dot(bx), wi.dot(by), wi.z);
    let (a, b, c, d) = ltc_terms(wo.z.clamp(0.0, 1.0), r);
    let det = c * (a - b * d);
    // adj(M) w = det(M) M^-1 w.
    let wh = Vec3::new(
        c * (w.x - b * w.z),
        (a - b * d) * w.y,
        -c * (d * w.x - a * w.z),
    );
    let len2 = wh.length_squared();
    let vz = 1.0 / (d * d + 1.0).sqrt();
    let s = 0.5 * (1.0 + vz);
    let p = (det / len2).powi(2) * wh.z.max(0.0) / (PI * s);
    if p.is_finite() {
        p
    } else {
        0.0
    }
}

fn eon_pdf(wo: Vec3, wi: Vec3, r: f32) -> f32 {
    let p_u = eon_uniform_prob(wo.z, r);
    p_u * (0.5 * FRAC_1_PI) + (1.0 - p_u) * cltc_pdf(wo, wi, r)
}

fn eon_sample(wo: Vec3, r: f32, u: Vec2) -> Option<(Vec3, f32)> {
    let p_u = eon_uniform_prob(wo.z, r);
    let wi = if u.x < p_u {
        // Uniform hemisphere, u.x rescaled to [0, 1).
        let z = u.x / p_u;
        let sin = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        Vec3::new(sin * phi.cos(), sin * phi.sin(), z)
    } else {
        let u1 = ((u.x - p_u) / (1.0 - p_u)).min(1.0);
        let (a, b, c, d) = ltc_terms(wo.z.clamp(0.0, 1.0), r);
        let rad = u1.sqrt();
        let phi = 2.0 * PI * u.y;
        let (mut x, y) = (rad * phi.cos(), rad * phi.sin());
        let vz = 1.0 / (d * d + 1.0).sqrt();
        let s = 0.5 * (1.0 + vz);
        // Clip the disk to the projection of the region that M maps above the horizon.
        x = -((1.0 - s) * (1.0 - y * y).max(0.0).sqrt() + s * x);
        let wh = Vec3::new(x, y, (1.0 - (x * x + y * y)).max(0.0).sqrt());
        let m = Vec3::new(a * wh.x + b * wh.z, c * wh.y, d * wh.x + wh.z);
        let (bx, by) = ltc_basis(wo);
        (bx * m.x + by * m.y + Vec3::Z * m.z).normalize_or_zero()
    };
    if wi.z <= 0.0 {
        return None;
    }
    Some((wi, eon_pdf(wo, wi, r)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Lambert;

    const VARIANTS: [OrenNayarVariant; 4] = [
        OrenNayarVariant::Qualitative,
        OrenNayarVariant::Full,
        OrenNayarVariant::Fujii,
        OrenNayarVariant::Eon,
    ];

    #[test]
    fn sigma_zero_equals_lambert_exactly() {
        let rho = SampledSpectrum::from_rgb([0.2, 0.5, 0.9]);
        let lam = Lambert::new(rho);
        for v in VARIANTS {
            let on = OrenNayar::new(rho, 0.0, v);
            let mut rng = pt_testkit::Pcg32::new(1, 2);
            for _ in 0..200 {
                let wo = pt_testkit::upper_hemisphere(Vec2::new(rng.next_f32(), rng.next_f32()));
                let wi = pt_testkit::upper_hemisphere(Vec2::new(rng.next_f32(), rng.next_f32()));
                let (a, b) = (on.eval(wo, wi).0, lam.eval(wo, wi).0);
                // EON at r = 0 adds f_ms = rho_ms/pi * eps^2/eps with eps = 1e-7 (the paper's
                // guard), rho_ms = 0 at r = 0 exactly since Ebar = 1: so exact there too.
                assert!((a - b).abs().max_element() <= 1e-7, "{v:?}: {a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn qualitative_closed_form_at_a_known_configuration() {
        // theta_i = 60 deg, theta_o = 30 deg, same azimuth: f = rho/pi (A + B sin 60 tan 30).
        let sigma = 0.5f32;
        let on = OrenNayar::new(
            SampledSpectrum::from_rgb([1.0; 3]),
            sigma,
            OrenNayarVariant::Qualitative,
        );
        let wi = Vec3::new(60f32.to_radians().sin(), 0.0, 60f32.to_radians().cos());
        let wo = Vec3::new(30f32.to_radians().sin(), 0.0, 30f32.to_radians().cos());
        let (a, b) = qualitative_ab(sigma);
        let expect = (a + b * 60f32.to_radians().sin() * 30f32.to_radians().tan()) / PI;
        assert!((on.eval(wo, wi).0.x - expect).abs() < 1e-6);
        // Fujii at the same point with r = B/A equals the qualitative value times A_F/A.
        let fu = OrenNayar::new(
            SampledSpectrum::from_rgb([1.0; 3]),
            sigma,
            OrenNayarVariant::Fujii,
        );
        let r = b / a;
        let expect_f = (1.0 + r * 60f32.to_radians().sin() * 30f32.to_radians().tan())
            / (1.0 + C1_FON * r)
            / PI;
        assert!((fu.eval(wo, wi).0.x - expect_f).abs() < 1e-6);
    }

    #[test]
    fn fon_albedo_is_continuous_at_grazing_and_one_at_r_zero() {
        assert!((fon_albedo(0.0, 0.7) - fon_albedo(1e-4, 0.7)).abs() < 1e-3);
        assert!((fon_albedo(0.3, 0.0) - 1.0).abs() < 1e-6);
        assert!(fon_albedo(0.0, 1.0).is_finite());
    }
}
