//! The glTF 2.0 metallic-roughness material (glTF 2.0 specification, Appendix B "BRDF
//! Implementation"): a mix, by `metallic`, of a metal and a dielectric, both with a GGX specular
//! lobe of roughness `alpha = roughness^2`.
//!
//! Appendix B writes it as
//! ```text
//! metal      = conductor_fresnel(f0 = base_color, specular_brdf(alpha))
//! dielectric = fresnel_mix(ior = 1.5, base = diffuse_brdf(base_color), layer = specular_brdf(alpha))
//! material   = mix(dielectric, metal, metallic)
//! ```
//! with `specular_brdf = D G / (4 |n.l| |n.v|)` (GGX, Walter et al. 2007 eq. 33), Schlick's
//! Fresnel `F(c) = f0 + (1 - f0)(1 - c)^5` at `c = v.h` (Schlick 1994 eq. 15), `f0 = base_color`
//! for the metal and `f0 = ((ior - 1)/(ior + 1))^2` (0.04 at ior 1.5) for the dielectric.
//!
//! **One deviation, for energy.** Appendix B's `fresnel_mix` weights the diffuse base by
//! `1 - F(v.h)`. That is not energy conserving: at grazing view the specular layer reflects
//! `F` of a small `v.h` (large) while the diffuse base, for most light directions, keeps
//! `1 - F` of a large `v.h` (close to 1), and a white material reflects up to ~1.4 times the
//! incident energy at 85 degrees. Here the diffuse base is coupled to the specular layer as in
//! Kelemen & Szirmay-Kalos 2001 ("A Microfacet Based Coupled Specular-Matte BRDF Model with
//! Importance Sampling", Eurographics short papers, eq. 3):
//!
//! `f_diffuse = base_color / pi * (1 - E(wo)) (1 - E(wi)) / (1 - E_avg)`,
//!
//! where `E(w)` is the directional albedo of the dielectric's Fresnel-weighted specular lobe
//! and `E_avg = 2 int_0^1 E(mu) mu dmu` its cosine-weighted mean. This is reciprocal, and a
//! white dielectric reflects exactly `E(wo) + (1 - E(wo)) = 1`. `E` is linear in `f0`
//! (`E = f0 A + (1 - f0) B` with `A = int D G / (4 cos_o) dwi` and the same with `(1 - v.h)^5`
//! for `B`), so two tables over (cos theta, alpha), computed once by quadrature, cover every
//! index of refraction.
//!
//! Masking-shadowing is the separable Smith G2 of [`Microfacet`] (as the other rough models;
//! Appendix B's `V` uses the height-correlated form, a sub-percent difference).
//!
//! **Sampling.** The specular lobe by GGX visible normals (Heitz 2018) reflected about the
//! sampled normal, with probability `p_s`; the diffuse lobe by cosine-weighted hemisphere
//! sampling otherwise. `p_s = w_s / (w_s + w_d)` with `w_s = metallic + (1 - metallic) E(wo)`
//! and `w_d = (1 - metallic)(1 - E(wo)) max(base_color)`; the pdf is the mixture
//! `p_s pdf_spec + (1 - p_s) cos(theta_i)/pi` (solid angle), which `pdf` returns.
//!
//! | parameter    | type     | default | unit / range                                       |
//! |--------------|----------|---------|----------------------------------------------------|
//! | `base_color` | spectrum | 1       | albedo in [0, 1] (glTF `baseColorFactor`, linear)   |
//! | `metallic`   | float    | 1       | [0, 1] (glTF `metallicFactor`)                      |
//! | `roughness`  | float    | 1       | [0, 1] perceptual; alpha = roughness^2 (>= 1e-3)    |
//! | `ior`        | float    | 1.5     | dielectric index (KHR_materials_ior), >= 1          |
//!
//! One-sided (black when `wo.z <= 0` or `wi.z <= 0`); glTF loaders wrap it two-sided. Read from
//! glTF files by `pt-gltf`; there is no Mitsuba XML form.

use crate::microfacet::{Distribution, Microfacet};
use crate::BsdfSample;
use pt_math::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use pt_math::{Vec2, Vec3, Vec4};
use pt_spectrum::SampledSpectrum;
use std::f32::consts::FRAC_1_PI;
use std::sync::OnceLock;

/// The glTF metallic-roughness BRDF at one shading point (see the module doc).
#[derive(Clone, Copy, Debug)]
pub struct GltfPbr {
    /// Base colour, linear albedo per lane.
    pub base_color: SampledSpectrum,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// GGX distribution with alpha = roughness^2.
    pub mf: Microfacet,
    /// Normal-incidence reflectance of the dielectric, ((ior - 1)/(ior + 1))^2.
    pub f0: f32,
    /// `1 - E(wo)` is evaluated per call; `1 / (1 - E_avg)` is fixed per material.
    inv_one_minus_eavg: f32,
}

/// Schlick's weight (1 - c)^5 (Schlick 1994 eq. 15 without f0).
#[inline]
fn schlick_weight(c: f32) -> f32 {
    let m = (1.0 - c).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

impl GltfPbr {
    /// The BRDF of glTF parameters: `roughness` is the perceptual roughness (alpha =
    /// roughness^2), `ior` the dielectric's index (1.5 without KHR_materials_ior).
    pub fn new(base_color: SampledSpectrum, metallic: f32, roughness: f32, ior: f32) -> Self {
        let r = if roughness.is_finite() {
            roughness.clamp(0.0, 1.0)
        } else {
            1.0
        };
        let alpha = r * r;
        let ior = if ior.is_finite() && ior >= 1.0 {
            ior
        } else {
            1.5
        };
        let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        let mf = Microfacet::new(Distribution::Ggx, alpha, alpha);
        let eavg = albedo_tables().e_avg(mf.alpha_u, f0);
        GltfPbr {
            base_color,
            metallic: if metallic.is_finite() {
                metallic.clamp(0.0, 1.0)
            } else {
                1.0
            },
            mf,
            f0,
            inv_one_minus_eavg: 1.0 / (1.0 - eavg).max(1e-4),
        }
    }

    /// Directional albedo E(mu) of the dielectric's specular lobe (the table's value).
    #[inline]
    pub fn specular_albedo(&self, mu: f32) -> f32 {
        albedo_tables().e(mu, self.mf.alpha_u, self.f0)
    }

    /// Probability of sampling the specular lobe for the viewer direction `wo`.
    #[inline]
    fn spec_prob(&self, e_o: f32) -> f32 {
        let ws = self.metallic + (1.0 - self.metallic) * e_o;
        let wd = (1.0 - self.metallic) * (1.0 - e_o) * self.base_color.max_value().max(0.0);
        if ws + wd > 0.0 {
            ws / (ws + wd)
        } else {
            1.0
        }
    }

    /// f(wo, wi) without the cosine, local frame.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        let m = self.metallic;
        // Coupled diffuse (Kelemen & Szirmay-Kalos 2001 eq. 3).
        let k = (1.0 - self.specular_albedo(wo.z))
            * (1.0 - self.specular_albedo(wi.z))
            * self.inv_one_minus_eavg;
        let mut f = self.base_color * ((1.0 - m) * FRAC_1_PI * k);
        let h = (wo + wi).normalize_or_zero();
        // Same support as the specular pdf (wo.h > 0), as in RoughPlastic: at grazing angles the
        // rounded wo.h can be <= 0 next to the mirror direction, where D / (4 cos cos) is huge
        // and the pdf 0 (`pt stability` found albedo 2e10 at roughness 0, 89.99 degrees).
        if h.z > 0.0 && wo.dot(h) > 0.0 {
            let d = self.mf.d(h);
            let v = d * self.mf.g2(wo, wi) / (4.0 * wi.z * wo.z);
            if v.is_finite() && v > 0.0 {
                let s = schlick_weight(wo.dot(h));
                // Per-lane Fresnel: dielectric f0 mixed with the metal's f0 = base colour.
                let fd = self.f0 + (1.0 - self.f0) * s;
                let one = Vec4::ONE;
                let fm = self.base_color.0 + (one - self.base_color.0) * s;
                let fr = SampledSpectrum(fm * m + Vec4::splat(fd * (1.0 - m)));
                f += fr * v;
            }
        }
        f
    }

    /// Specular-lobe solid-angle pdf of `wi`: VNDF pdf of h over 4 wo.h.
    #[inline]
    fn spec_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.mf.reflection_pdf(wo, wi)
    }

    /// Solid-angle pdf of `wi`: `p_s pdf_spec + (1 - p_s) cos(theta_i)/pi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let ps = self.spec_prob(self.specular_albedo(wo.z));
        ps * self.spec_pdf(wo, wi) + (1.0 - ps) * cosine_hemisphere_pdf(wi)
    }

    /// Chooses the specular lobe with `u_lobe < p_s`, else the diffuse lobe; weight
    /// `f cos / pdf` with the mixture pdf.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let ps = self.spec_prob(self.specular_albedo(wo.z));
        let wi = if u_lobe < ps {
            self.mf.sample_reflection(wo, u)?
        } else {
            square_to_cosine_hemisphere(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = ps * self.spec_pdf(wo, wi) + (1.0 - ps) * cosine_hemisphere_pdf(wi);
        if !(pdf > 0.0) {
            return None;
        }
        let weight = self.eval(wo, wi) * (wi.z / pdf);
        if !weight.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}

/// Tables of the dielectric specular lobe's albedo (see the module doc): `A(mu, alpha)` and
/// `B(mu, alpha)` on a regular grid, and their cosine-weighted means over mu.
struct AlbedoTables {
    a: Vec<f32>,
    b: Vec<f32>,
    a_avg: Vec<f32>,
    b_avg: Vec<f32>,
}

/// Grid nodes in x = mu^(1/4), mu = cos(theta_o), over [0, 1] (node 0 evaluated at mu = 1e-9).
/// The fourth root puts nodes close together near grazing incidence, where masking makes E(mu)
/// fall steeply at small roughness (it depends on alpha tan(theta)): with 32 nodes uniform in
/// mu, linear interpolation between mu = 1e-3 and 1/31 underestimated E at 89 degrees, the
/// coupled diffuse term took the difference, and the albedo reached 1.059 (`pt stability`).
const N_MU: usize = 64;
/// Grid nodes in alpha^(1/4) over [1e-3^(1/4), 1] (see [`alpha_coordinate`]): E changes
/// fastest at small alpha, where this grid is densest.
const N_ALPHA: usize = 32;
/// Quadrature points per axis for each node: a midpoint rule over the visible-normal
/// sampler's unit square (48^2 points; its error, measured against 256^2 points, is below 1e-3).
const N_QUAD: usize = 48;

/// sqrt of the smallest alpha the microfacet code uses ([`crate::microfacet::MIN_ALPHA`]): the
/// first node of the roughness axis. (With the axis starting at 0, node 0 was evaluated at the
/// clamped alpha 1e-3 but looked up as alpha 0, so roughness 0 read E at alpha ~0.0016: 2.3%
/// too low at 89.9 degrees, and the coupled diffuse gained that much energy.)
const R_MIN: f32 = 0.031_622_78;

/// Fractional node index of `alpha` on the roughness axis: uniform in alpha^(1/4) (the square
/// root of the perceptual roughness) from sqrt(R_MIN), which puts nodes densely at small
/// roughness, where E at grazing angles changes fastest with alpha (uniform in sqrt(alpha), the
/// interpolation left 1.3% of energy gain at roughness 0.05 and 89 degrees).
#[inline]
fn alpha_coordinate(alpha: f32) -> f32 {
    let s_min = R_MIN.sqrt();
    ((alpha.clamp(0.0, 1.0).sqrt().sqrt() - s_min) / (1.0 - s_min)).clamp(0.0, 1.0)
        * (N_ALPHA - 1) as f32
}

/// The alpha of node `ia` of the roughness axis (inverse of [`alpha_coordinate`]).
fn node_alpha(ia: usize) -> f32 {
    let s_min = R_MIN.sqrt();
    let s = s_min + (1.0 - s_min) * ia as f32 / (N_ALPHA - 1) as f32;
    s.powi(4)
}

fn albedo_tables() -> &'static AlbedoTables {
    static T: OnceLock<AlbedoTables> = OnceLock::new();
    T.get_or_init(AlbedoTables::compute)
}

impl AlbedoTables {
    fn compute() -> AlbedoTables {
        let mut a = vec![0.0; N_MU * N_ALPHA];
        let mut b = vec![0.0; N_MU * N_ALPHA];
        for ia in 0..N_ALPHA {
            let alpha = node_alpha(ia);
            let mf = Microfacet::new(Distribution::Ggx, alpha, alpha);
            for im in 0..N_MU {
                let x = im as f32 / (N_MU - 1) as f32;
                let mu = x.powi(4).max(1e-9);
                let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
                let (mut sa, mut sb) = (0.0f64, 0.0f64);
                for i in 0..N_QUAD {
                    for j in 0..N_QUAD {
                        let u = Vec2::new(
                            (i as f32 + 0.5) / N_QUAD as f32,
                            (j as f32 + 0.5) / N_QUAD as f32,
                        );
                        let m = mf.sample_m(wo, u);
                        let wom = wo.dot(m);
                        if wom <= 0.0 {
                            continue;
                        }
                        let wi = 2.0 * wom * m - wo;
                        if wi.z <= 0.0 {
                            continue;
                        }
                        // VNDF estimator of int D G2 / (4 cos_o) dwi: weight G2 / G1(wo) = G1(wi).
                        let g = f64::from(mf.g1(wi));
                        sa += g;
                        sb += g * f64::from(schlick_weight(wom));
                    }
                }
                let n = (N_QUAD * N_QUAD) as f64;
                a[ia * N_MU + im] = (sa / n) as f32;
                b[ia * N_MU + im] = (sb / n) as f32;
            }
        }
        // E_avg = 2 int_0^1 E(mu) mu dmu = 8 int_0^1 E(x^4) x^7 dx, trapezoidal over the x nodes.
        let avg = |t: &[f32], ia: usize| -> f32 {
            let h = 1.0 / (N_MU - 1) as f32;
            let mut s = 0.0;
            for im in 0..N_MU - 1 {
                let (x0, x1) = (im as f32 * h, (im + 1) as f32 * h);
                s +=
                    0.5 * h * (t[ia * N_MU + im] * x0.powi(7) + t[ia * N_MU + im + 1] * x1.powi(7));
            }
            8.0 * s
        };
        let a_avg = (0..N_ALPHA).map(|ia| avg(&a, ia)).collect();
        let b_avg = (0..N_ALPHA).map(|ia| avg(&b, ia)).collect();
        AlbedoTables { a, b, a_avg, b_avg }
    }

    /// Bilinear lookup of a table at (mu^(1/4), sqrt(alpha)).
    #[inline]
    fn lookup(t: &[f32], mu: f32, alpha: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0).sqrt().sqrt() * (N_MU - 1) as f32;
        let y = alpha_coordinate(alpha);
        let (x0, y0) = ((x as usize).min(N_MU - 2), (y as usize).min(N_ALPHA - 2));
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let at = |i: usize, j: usize| t[j * N_MU + i];
        (at(x0, y0) * (1.0 - fx) + at(x0 + 1, y0) * fx) * (1.0 - fy)
            + (at(x0, y0 + 1) * (1.0 - fx) + at(x0 + 1, y0 + 1) * fx) * fy
    }

    /// E(mu) = f0 A + (1 - f0) B.
    #[inline]
    fn e(&self, mu: f32, alpha: f32, f0: f32) -> f32 {
        (f0 * Self::lookup(&self.a, mu, alpha) + (1.0 - f0) * Self::lookup(&self.b, mu, alpha))
            .clamp(0.0, 1.0)
    }

    /// E_avg = f0 A_avg + (1 - f0) B_avg, linear in sqrt(alpha) between nodes.
    fn e_avg(&self, alpha: f32, f0: f32) -> f32 {
        let y = alpha_coordinate(alpha);
        let y0 = (y as usize).min(N_ALPHA - 2);
        let fy = y - y0 as f32;
        let l = |t: &[f32]| t[y0] * (1.0 - fy) + t[y0 + 1] * fy;
        (f0 * l(&self.a_avg) + (1.0 - f0) * l(&self.b_avg)).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smooth_limit_albedo_is_schlick_fresnel() {
        // At alpha -> 0 the specular lobe is a mirror with G = 1: E(mu) = F(mu) (Schlick).
        let p = GltfPbr::new(SampledSpectrum::from_rgb([0.5; 3]), 0.0, 0.0, 1.5);
        for mu in [1.0f32, 0.5, 0.2] {
            let want = 0.04 + 0.96 * schlick_weight(mu);
            assert!(
                (p.specular_albedo(mu) - want).abs() < 2e-3,
                "mu {mu}: {} vs {want}",
                p.specular_albedo(mu)
            );
        }
    }
}
