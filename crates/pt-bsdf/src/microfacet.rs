//! Anisotropic microfacet distributions (GGX and Beckmann) with Smith masking-shadowing and
//! visible-normal sampling, shared by the rough conductor and the rough dielectric.
//!
//! - GGX (Trowbridge-Reitz): Walter, Marschner, Li & Torrance 2007, "Microfacet Models for
//!   Refraction through Rough Surfaces", EGSR, eq. 33; anisotropic form
//!   `D(m) = 1 / (pi ax ay (m.x^2/ax^2 + m.y^2/ay^2 + m.z^2)^2)` (Heitz 2014, "Understanding the
//!   Masking-Shadowing Function", JCGT 3(2), eq. 85).
//! - Beckmann: Walter et al. 2007 eq. 25, anisotropic
//!   `D(m) = exp(-(m.x^2/ax^2 + m.y^2/ay^2)/m.z^2) / (pi ax ay m.z^4)` (Heitz 2014 eq. 80).
//! - Smith Lambda (Heitz 2014 eqs. 72 and 86): with `a = 1/(alpha(w) tan theta)`,
//!   `alpha(w)^2 tan^2 = (w.x^2 ax^2 + w.y^2 ay^2)/w.z^2`:
//!   GGX `(-1 + sqrt(1 + 1/a^2))/2`; Beckmann `(erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi))`.
//!   `G1 = 1/(1 + Lambda)`; `G2 = G1(wo) G1(wi)`, the separable (uncorrelated) form of Walter
//!   et al. 2007 eq. 23, which Mitsuba 3 uses: renders must match its references. The
//!   height-correlated `1/(1 + Lambda(wo) + Lambda(wi))` (Heitz 2014 eq. 99) is more accurate
//!   and never darker; with it (and with the anisotropic tangent not following Mitsuba's
//!   `dp_du`), scenes/conductors.xml failed its reference test with region means 0.2-0.5% off.
//! - Visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible Normals", JCGT
//!   7(4), eq. 1): `D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z`. GGX samples it exactly with the
//!   paper's Listing 1. Beckmann samples the plain `D(m) m.z` (Walter et al. 2007 eqs. 28-29,
//!   anisotropic as in pbrt-v3), whose pdf is [`Microfacet::pdf_m`]; normals facing away from
//!   `wo` are rejected by the callers, which the pdf accounts for (it integrates to < 1).
//!
//! All functions take directions in the local frame with `wo.z >= 0` (callers flip).

use pt_math::{Vec2, Vec3};
use std::f32::consts::PI;

/// Which normal distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Distribution {
    /// Trowbridge-Reitz / GGX.
    #[default]
    Ggx,
    /// Beckmann-Spizzichino.
    Beckmann,
}

impl Distribution {
    /// Parses Mitsuba's `distribution` string (`ggx`, `beckmann`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "ggx" => Some(Self::Ggx),
            "beckmann" => Some(Self::Beckmann),
            _ => None,
        }
    }
}

/// Smallest roughness: below it the distributions overflow f32 (use the smooth models).
pub const MIN_ALPHA: f32 = 1e-3;

/// A microfacet distribution with roughness `alpha_u` along x and `alpha_v` along y.
#[derive(Clone, Copy, Debug)]
pub struct Microfacet {
    /// Normal distribution.
    pub dist: Distribution,
    /// Roughness along the tangent x (GGX: slope scale; Beckmann: RMS slope), >= 1e-3.
    pub alpha_u: f32,
    /// Roughness along the bitangent y, >= 1e-3.
    pub alpha_v: f32,
}

/// erf to about 1.5e-7 absolute (Abramowitz & Stegun 7.1.26).
fn erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let y = 1.0
        - (((((1.061_405_4 * t - 1.453_152_1) * t) + 1.421_413_7) * t - 0.284_496_74) * t + 0.254_829_6)
            * t
            * (-x * x).exp();
    y.copysign(x)
}

impl Microfacet {
    /// A distribution; alphas are clamped to [1e-3, 10] (non-finite taken as 1e-3).
    pub fn new(dist: Distribution, alpha_u: f32, alpha_v: f32) -> Self {
        let c = |a: f32| if a.is_finite() { a.clamp(MIN_ALPHA, 10.0) } else { MIN_ALPHA };
        Microfacet { dist, alpha_u: c(alpha_u), alpha_v: c(alpha_v) }
    }

    /// D(m) per unit solid angle of m (projected area normalised: int D(m) m.z dm = 1).
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (ax, ay) = (self.alpha_u, self.alpha_v);
        let (x, y) = (m.x / ax, m.y / ay);
        let z2 = m.z * m.z;
        let v = match self.dist {
            Distribution::Ggx => {
                let k = x * x + y * y + z2;
                1.0 / (PI * ax * ay * k * k)
            }
            Distribution::Beckmann => (-(x * x + y * y) / z2).exp() / (PI * ax * ay * z2 * z2),
        };
        if v.is_finite() {
            v
        } else {
            0.0
        }
    }

    /// Smith Lambda(w) for the side `w` is on (uses |w.z|).
    pub fn lambda(&self, w: Vec3) -> f32 {
        let z2 = w.z * w.z;
        let t2 = w.x * w.x * self.alpha_u * self.alpha_u + w.y * w.y * self.alpha_v * self.alpha_v;
        if t2 <= 0.0 {
            return 0.0;
        }
        if z2 == 0.0 {
            return f32::INFINITY;
        }
        match self.dist {
            Distribution::Ggx => 0.5 * (-1.0 + (1.0 + t2 / z2).sqrt()),
            Distribution::Beckmann => {
                let a = (z2 / t2).sqrt();
                if a >= 4.0 {
                    return 0.0; // Lambda(4) = 1.4e-9; the difference below cancels in f32
                }
                (0.5 * (erf(a) - 1.0) + (-a * a).exp() / (2.0 * a * PI.sqrt())).max(0.0)
            }
        }
    }

    /// Smith G1(w) = 1/(1 + Lambda(w)).
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Separable masking-shadowing G2(wo, wi) = G1(wo) G1(wi) (Walter et al. 2007 eq. 23, as
    /// Mitsuba 3); see the module doc for why not the height-correlated form.
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.g1(wo) * self.g1(wi)
    }

    /// Density (solid angle of m) of the normals [`Microfacet::sample_m`] draws, for `wo.z > 0`:
    /// GGX `D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z`; Beckmann `D(m) m.z`.
    pub fn pdf_m(&self, wo: Vec3, m: Vec3) -> f32 {
        match self.dist {
            Distribution::Ggx => {
                if wo.z <= 0.0 {
                    return 0.0;
                }
                self.g1(wo) * wo.dot(m).max(0.0) * self.d(m) / wo.z
            }
            Distribution::Beckmann => self.d(m) * m.z.max(0.0),
        }
    }

    /// Samples a microfacet normal (upper hemisphere) for the viewer direction `wo` (`wo.z > 0`).
    pub fn sample_m(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let (ax, ay) = (self.alpha_u, self.alpha_v);
        match self.dist {
            Distribution::Ggx => {
                // Heitz 2018, Listing 1: stretch, sample the projected hemisphere, unstretch.
                let vh = Vec3::new(ax * wo.x, ay * wo.y, wo.z).normalize();
                let len2 = vh.x * vh.x + vh.y * vh.y;
                let t1 = if len2 > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt() } else { Vec3::X };
                let t2v = vh.cross(t1);
                let r = u.x.sqrt();
                let phi = 2.0 * PI * u.y;
                let p1 = r * phi.cos();
                let mut p2 = r * phi.sin();
                let s = 0.5 * (1.0 + vh.z);
                p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
                let nh = t1 * p1 + t2v * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
                Vec3::new(ax * nh.x, ay * nh.y, nh.z.max(1e-6)).normalize()
            }
            Distribution::Beckmann => {
                // Walter et al. 2007 eqs. 28-29, anisotropic (pbrt-v3 BeckmannDistribution).
                let log_u = (1.0 - u.x).max(1e-30).ln();
                let (sin_phi, cos_phi) = if ax == ay {
                    (2.0 * PI * u.y).sin_cos()
                } else {
                    let mut phi = (ay / ax * (2.0 * PI * u.y + 0.5 * PI).tan()).atan();
                    if u.y > 0.5 {
                        phi += PI;
                    }
                    phi.sin_cos()
                };
                let tan2 = -log_u / (cos_phi * cos_phi / (ax * ax) + sin_phi * sin_phi / (ay * ay));
                let cos_t = 1.0 / (1.0 + tan2).sqrt();
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                Vec3::new(sin_t * cos_phi, sin_t * sin_phi, cos_t.max(1e-6)).normalize()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// int D(m) m.z dm = 1 and int D_wo(m) dm = 1 (GGX), by quadrature.
    #[test]
    fn normalisation() {
        for dist in [Distribution::Ggx, Distribution::Beckmann] {
            for (ax, ay) in [(0.3f32, 0.3f32), (0.1, 0.5), (0.8, 0.8)] {
                let mf = Microfacet::new(dist, ax, ay);
                let cells = pt_testkit::integrate_cells(&|m: Vec3| f64::from(mf.d(m) * m.z.max(0.0)), 32, 64, 1e-9, 1e-5);
                let s: f64 = cells.iter().sum();
                assert!((s - 1.0).abs() < 2e-3, "{dist:?} {ax} {ay}: {s}");
                let wo = pt_testkit::dir_deg(70.0, 30.0);
                // Projected area of visible normals = wo.z: int <wo.m>+ D G1 dm = wo.z (Heitz 2014 eq. 18).
                let cells = pt_testkit::integrate_cells(&|m: Vec3| f64::from(mf.g1(wo) * wo.dot(m).max(0.0) * mf.d(m)), 32, 64, 1e-9, 1e-5);
                let s: f64 = cells.iter().sum();
                assert!((s - f64::from(wo.z)).abs() < 3e-3, "{dist:?} {ax} {ay}: {s} vs {}", wo.z);
            }
        }
    }
}
