//! Conductors: a smooth mirror ([`Conductor`]) and a rough microfacet conductor
//! ([`RoughConductor`]), both with the exact complex Fresnel term.
//!
//! - Smooth: `f = F(cos_o) delta(wi - reflect(wo)) / cos_i`, one delta lobe; the sample weight is
//!   `specular_reflectance * F(cos_o)` with F from [`fresnel_conductor`] (pbrt-v4 eq. 9.6 with
//!   complex eta; sign convention `eta + i k`, `k >= 0`).
//! - Rough: Cook-Torrance (Walter et al. 2007, eq. 20) with the separable Smith
//!   `G2 = G1(wo) G1(wi)` as Mitsuba 3 (see [`crate::microfacet`] for why not the
//!   height-correlated form): `f = F(wo.h) D(h) G2(wo, wi) / (4 cos_i cos_o)`,
//!   `h = normalize(wo + wi)`. Sampling: `h` from the visible normals of either distribution
//!   (GGX: Heitz 2018; Beckmann: Heitz & d'Eon 2014), see [`crate::microfacet`];
//!   `wi = 2 (wo.h) h - wo`; pdf `pdf_m(h) / (4 wo.h)` (Jacobian of the reflection, Walter et
//!   al. 2007 eq. 14), so the weight is `F G1(wi)`. The path tracer runs the model's lane
//!   kernels ([`RoughConductor::eval_pdf_lanes`], [`RoughConductor::sample_lanes`]) for eight
//!   paths at once; `eval_pdf` and `sample` are their one lane.
//!
//! Both are one-sided (black when `wo` or `wi` is below), as Mitsuba's `conductor`. Wrap them
//! in a two-sided [`crate::SurfaceBsdf`] for sheets.
//!
//! | parameter              | type     | default | unit                                  |
//! |------------------------|----------|---------|---------------------------------------|
//! | `eta`                  | spectrum | 0       | real part of the relative index       |
//! | `k`                    | spectrum | 1       | imaginary part (absorption), >= 0     |
//! | `specular_reflectance` | spectrum | 1       | multiplier (not physical), [0, 1]     |
//! | `distribution`         | string   | beckmann (Mitsuba's default) | `ggx`, `beckmann` (rough only) |
//! | `alpha`, `alpha_u`, `alpha_v` | float | 0.1 | roughness, dimensionless (rough only) |
//!
//! (`eta = 0, k = 1` is Mitsuba's `material="none"`: a perfect mirror, F = 1. Named materials
//! such as `Au` are resolved by the loader into `eta`/`k` spectra.)
//!
//! Mitsuba XML:
//! ```xml
//! <bsdf type="conductor">
//!     <rgb name="eta" value="0.2, 0.4, 1.4"/>
//!     <rgb name="k" value="3.4, 2.4, 1.8"/>
//! </bsdf>
//! <bsdf type="roughconductor">
//!     <string name="distribution" value="ggx"/>
//!     <float name="alpha_u" value="0.05"/>
//!     <float name="alpha_v" value="0.3"/>
//!     <string name="material" value="Au"/>
//! </bsdf>
//! ```

use crate::fresnel::{fresnel_conductor4, fresnel_conductor_lanes};
use crate::microfacet::{d_of, g1_of, sample_reflections, Distribution, Microfacet};
use crate::{BsdfSample, SampleLanes};
use pt_math::lanes::{lanes, Mask, V3};
use pt_math::{Vec2, Vec3, Vec4};
use pt_spectrum::SampledSpectrum;

/// Per-lane conductor Fresnel at `cos_i`.
fn fresnel_lanes(cos_i: f32, eta: SampledSpectrum, k: SampledSpectrum) -> SampledSpectrum {
    SampledSpectrum(fresnel_conductor4(cos_i, eta.0, k.0))
}

/// Smooth conductor (perfect specular reflection weighted by the complex Fresnel term).
#[derive(Clone, Copy, Debug)]
pub struct Conductor {
    /// Real part of the index, per lane.
    pub eta: SampledSpectrum,
    /// Imaginary part (absorption coefficient), per lane, >= 0.
    pub k: SampledSpectrum,
    /// Multiplier of the reflectance.
    pub specular_reflectance: SampledSpectrum,
}

impl Conductor {
    /// A smooth conductor of complex index `eta + i k`.
    pub fn new(
        eta: SampledSpectrum,
        k: SampledSpectrum,
        specular_reflectance: SampledSpectrum,
    ) -> Self {
        Conductor {
            eta,
            k,
            specular_reflectance,
        }
    }

    /// Reflectance at `cos_o`: `specular_reflectance * F(cos_o)`.
    pub fn reflectance(&self, cos_o: f32) -> SampledSpectrum {
        self.specular_reflectance * fresnel_lanes(cos_o, self.eta, self.k)
    }

    /// Delta lobe: 0.
    pub fn eval(&self, _wo: Vec3, _wi: Vec3) -> SampledSpectrum {
        SampledSpectrum::ZERO
    }

    /// Delta lobe: 0.
    pub fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    /// The mirror direction, weight `F(cos_o)`, pdf 1 (discrete), delta.
    pub fn sample(&self, wo: Vec3, _u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = Vec3::new(-wo.x, -wo.y, wo.z);
        Some(BsdfSample {
            wi,
            weight: self.reflectance(wo.z),
            pdf: 1.0,
            delta: true,
            eta: 1.0,
        })
    }
}

/// Rough conductor (microfacet reflection, Walter et al. 2007).
#[derive(Clone, Copy, Debug)]
pub struct RoughConductor {
    /// Real part of the index, per lane.
    pub eta: SampledSpectrum,
    /// Imaginary part, per lane, >= 0.
    pub k: SampledSpectrum,
    /// Multiplier of the reflectance.
    pub specular_reflectance: SampledSpectrum,
    /// Microfacet distribution and roughness.
    pub mf: Microfacet,
}

impl RoughConductor {
    /// A rough conductor of complex index `eta + i k` with the distribution `mf`.
    pub fn new(
        eta: SampledSpectrum,
        k: SampledSpectrum,
        specular_reflectance: SampledSpectrum,
        mf: Microfacet,
    ) -> Self {
        RoughConductor {
            eta,
            k,
            specular_reflectance,
            mf,
        }
    }

    /// f(wo, wi) without the cosine (the value of [`RoughConductor::eval_pdf`], the model's
    /// one implementation).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        self.eval_pdf(wo, wi).0
    }

    /// Solid-angle pdf: `pdf_m(h) / (4 wo.h)` ([`Microfacet::reflection_pdf`]).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.mf.reflection_pdf(wo, wi)
    }

    /// [`RoughConductor::eval`] and [`RoughConductor::pdf`] together, the same numbers (the
    /// same operations in the same order), with the half vector, D(h) and G1(wo) computed
    /// once: for a Beckmann surface each is an exponential or an error function, and light
    /// sampling with MIS needs both values of every light direction. (One lane of
    /// [`RoughConductor::eval_pdf_lanes`].)
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (SampledSpectrum, f32) {
        let (wo, wi) = (V3::<1>::splat(wo), V3::splat(wi));
        let (f, pdf) = match self.mf.dist {
            Distribution::Ggx => Self::eval_pdf_lanes::<1, false>(&[*self], &wo, &wi),
            Distribution::Beckmann => Self::eval_pdf_lanes::<1, true>(&[*self], &wo, &wi),
        };
        (f[0], pdf[0])
    }

    /// [`RoughConductor::eval_pdf`] for `N` lanes of rough conductors `m` whose distribution
    /// is GGX (`BECKMANN` false) or Beckmann, directions in each lane's local frame: the
    /// microfacet terms and the Fresnel factors for all lanes at once in SIMD registers (the
    /// path tracer's eight paths).
    #[inline(always)]
    pub fn eval_pdf_lanes<const N: usize, const BECKMANN: bool>(
        m: &[RoughConductor; N],
        wo: &V3<N>,
        wi: &V3<N>,
    ) -> ([SampledSpectrum; N], [f32; N]) {
        // Each field in its own array: the compiler vectorises a loop whose lanes store to
        // consecutive addresses, not one that fills an array of structures.
        let (mut lit, mut v, mut woh, mut pdf) = ([false; N], [0.0; N], [0.0; N], [0.0; N]);
        for k in 0..N {
            let (ax, ay) = (m[k].mf.alpha_u, m[k].mf.alpha_v);
            let t = terms::<BECKMANN>(ax, ay, wo.get(k), wi.get(k));
            (lit[k], v[k], woh[k], pdf[k]) = (t.lit, t.v, t.woh, t.pdf);
        }
        // The Fresnel factors channel by channel, each for all lanes at once. (A plain loop:
        // `std::array::from_fn` was left as a call, compiled outside the render loop's
        // instruction set.)
        let mut fresnel = [[0.0; N]; 4];
        for (c, fc) in fresnel.iter_mut().enumerate() {
            let (eta, k) = (lanes(|j| m[j].eta.0[c]), lanes(|j| m[j].k.0[c]));
            *fc = fresnel_conductor_lanes(&woh, &eta, &k);
        }
        let f = lanes(|k| {
            if lit[k] {
                let f = Vec4::new(fresnel[0][k], fresnel[1][k], fresnel[2][k], fresnel[3][k]);
                SampledSpectrum(f) * m[k].specular_reflectance * v[k]
            } else {
                SampledSpectrum::ZERO
            }
        });
        (f, pdf)
    }

    /// Samples a microfacet normal and reflects `wo` about it. (One lane of
    /// [`RoughConductor::sample_lanes`].)
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        let wo = V3::<1>::splat(wo);
        let (u0, u1) = ([u.x], [u.y]);
        let s = match self.mf.dist {
            Distribution::Ggx => Self::sample_lanes::<1, false>(&[*self], &wo, &u0, &u1, 1),
            Distribution::Beckmann => Self::sample_lanes::<1, true>(&[*self], &wo, &u0, &u1, 1),
        };
        s.ok[0].then(|| s.get(0))
    }

    /// [`RoughConductor::sample`] for the lanes of `mask` among `N` lanes of rough conductors
    /// `m` whose distribution is GGX (`BECKMANN` false) or Beckmann: the reflections about
    /// normals drawn with (`u0`, `u1`) ([`sample_reflections`]), valued by
    /// [`RoughConductor::eval_pdf_lanes`].
    #[inline(always)]
    pub fn sample_lanes<const N: usize, const BECKMANN: bool>(
        m: &[RoughConductor; N],
        wo: &V3<N>,
        u0: &[f32; N],
        u1: &[f32; N],
        mask: Mask,
    ) -> SampleLanes<N> {
        let (ax, ay) = (lanes(|k| m[k].mf.alpha_u), lanes(|k| m[k].mf.alpha_v));
        let (wi, drawn) = sample_reflections::<N, BECKMANN>(&ax, &ay, wo, u0, u1, mask);
        let (f, pdf) = Self::eval_pdf_lanes::<N, BECKMANN>(m, wo, &wi);
        SampleLanes {
            weight: lanes(|k| f[k] * (wi.z[k] / pdf[k])),
            wi,
            pdf,
            ok: lanes(|k| drawn[k] & (pdf[k] > 0.0)),
        }
    }

    /// A stand-in for the lanes without a rough conductor in the lane kernels (its values
    /// there are not used).
    pub const UNUSED: RoughConductor = RoughConductor {
        eta: SampledSpectrum::ZERO,
        k: SampledSpectrum::ZERO,
        specular_reflectance: SampledSpectrum::ZERO,
        mf: Microfacet {
            dist: Distribution::Ggx,
            alpha_u: 1.0,
            alpha_v: 1.0,
        },
    };
}

/// The wavelength-independent part of [`RoughConductor::eval_pdf`] for one pair (`wo`, `wi`)
/// in the local frame: the value is `F(wo.h) k_s v` where `lit`, else black
/// ([`RoughConductor::eval_pdf_lanes`]).
#[derive(Clone, Copy)]
struct Terms {
    /// Whether the value is not black: both directions above, a facing half vector, D(h) > 0
    /// and a finite `v`.
    lit: bool,
    /// `D(h) G1(wo) G1(wi) / (4 cos_i cos_o)`.
    v: f32,
    /// wo.h, the Fresnel term's cosine.
    woh: f32,
    /// The solid-angle pdf, `pdf_m(h) / (4 wo.h)` (0 where not finite).
    pdf: f32,
}

/// [`Terms`] of the GGX (`BECKMANN` false) or Beckmann distribution of roughness (`ax`, `ay`):
/// the operations of [`RoughConductor::eval`] and [`RoughConductor::pdf`] in their order, with
/// selects where those return early (so that a loop of it over lanes vectorises).
#[inline(always)]
fn terms<const BECKMANN: bool>(ax: f32, ay: f32, wo: Vec3, wi: Vec3) -> Terms {
    let h = (wo + wi).normalize_or_zero();
    let d = d_of::<BECKMANN>(ax, ay, h);
    let above = !(wo.z <= 0.0) & !(wi.z <= 0.0) & !(h.z <= 0.0) & (d != 0.0);
    let woh = wo.dot(h);
    let g1_o = g1_of::<BECKMANN>(ax, ay, wo);
    // As Microfacet::reflection_pdf through pdf_m.
    let p = g1_o * woh.max(0.0) * d / wo.z / (4.0 * woh);
    let pdf = if above & !(woh <= 0.0) & p.is_finite() {
        p
    } else {
        0.0
    };
    // As eval, with G2 = G1(wo) G1(wi).
    let v = d * (g1_o * g1_of::<BECKMANN>(ax, ay, wi)) / (4.0 * wi.z * wo.z);
    Terms {
        lit: above & v.is_finite(),
        v,
        woh,
        pdf,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane kernels give every lane what that lane's model gives alone, bit for bit: eight
    /// conductors of different roughness, index and tint, each distribution, directions above,
    /// below and grazing (the path tracer runs them for eight paths at once; a lane mixed up
    /// with another, or a channel with another, fails).
    #[test]
    fn eight_lanes_match_one_lane_bit_for_bit() {
        let bits = |s: SampledSpectrum| s.0.to_array().map(f32::to_bits);
        for dist in [Distribution::Ggx, Distribution::Beckmann] {
            let m: [RoughConductor; 8] = std::array::from_fn(|k| {
                let x = k as f32;
                RoughConductor::new(
                    SampledSpectrum(Vec4::new(0.2 + 0.1 * x, 0.5, 1.1, 0.05 * x)),
                    SampledSpectrum(Vec4::new(3.4, 2.0 + 0.2 * x, 0.0, 4.0)),
                    SampledSpectrum(Vec4::new(1.0, 0.9, 0.8 - 0.05 * x, 1.0)),
                    Microfacet::new(dist, 0.02 + 0.1 * x, 0.3 - 0.03 * x),
                )
            });
            let dir = |x: f32, y: f32, z: f32| Vec3::new(x, y, z).normalize();
            let wo = V3::<8>::from_fn(|k| {
                [
                    dir(0.3, 0.1, 0.9),
                    dir(-0.5, 0.2, 0.4),
                    dir(0.0, 0.0, 1.0),
                    dir(0.9, -0.1, 1e-4),
                    dir(0.2, 0.2, -0.5),
                    dir(-0.1, 0.7, 0.3),
                    dir(0.6, 0.6, 0.2),
                    dir(0.01, -0.02, 0.99),
                ][k]
            });
            let wi = V3::<8>::from_fn(|k| {
                [
                    dir(-0.3, -0.1, 0.9),
                    dir(0.4, -0.3, 0.5),
                    dir(0.1, 0.0, 0.99),
                    dir(-0.9, 0.1, 0.05),
                    dir(0.2, -0.2, 0.6),
                    dir(0.0, -0.7, -0.3),
                    dir(-0.5, -0.6, 0.3),
                    dir(0.0, 0.02, 0.99),
                ][k]
            });
            let u0 = [0.1, 0.5, 0.9, 0.3, 0.7, 0.2, 0.99, 0.0];
            // 0.9995: a slope in the inverse error function's tail form, which the lanes take only
            // when one of them needs it.
            let u1 = [0.8, 0.25, 0.6, 0.1, 0.4, 0.95, 0.5, 0.9995];
            let (f, pdf) = match dist {
                Distribution::Ggx => RoughConductor::eval_pdf_lanes::<8, false>(&m, &wo, &wi),
                Distribution::Beckmann => RoughConductor::eval_pdf_lanes::<8, true>(&m, &wo, &wi),
            };
            let s = match dist {
                Distribution::Ggx => {
                    RoughConductor::sample_lanes::<8, false>(&m, &wo, &u0, &u1, 0xff)
                }
                Distribution::Beckmann => {
                    RoughConductor::sample_lanes::<8, true>(&m, &wo, &u0, &u1, 0xff)
                }
            };
            for k in 0..8 {
                let (f1, pdf1) = m[k].eval_pdf(wo.get(k), wi.get(k));
                assert_eq!(bits(f[k]), bits(f1), "{dist:?} lane {k}");
                assert_eq!(pdf[k].to_bits(), pdf1.to_bits(), "{dist:?} lane {k}");
                let s1 = m[k].sample(wo.get(k), Vec2::new(u0[k], u1[k]));
                assert_eq!(s.ok[k], s1.is_some(), "{dist:?} lane {k}");
                if let Some(s1) = s1 {
                    let s8 = s.get(k);
                    assert_eq!(
                        s8.wi.to_array().map(f32::to_bits),
                        s1.wi.to_array().map(f32::to_bits)
                    );
                    assert_eq!(bits(s8.weight), bits(s1.weight), "{dist:?} lane {k}");
                    assert_eq!(s8.pdf.to_bits(), s1.pdf.to_bits(), "{dist:?} lane {k}");
                }
                assert!(
                    f1.0.is_finite() && (k != 4 || f1.is_black()),
                    "{dist:?} lane {k}"
                );
            }
            // Lanes with a sample exist (the test is not vacuous).
            assert!(s.ok.iter().filter(|&&o| o).count() >= 5, "{dist:?}");
        }
    }

    /// `eval_pdf`'s pdf is exactly `pdf` ([`Microfacet::reflection_pdf`], written separately,
    /// whose operations the kernel repeats in their order), for both distributions,
    /// anisotropic. (`eval` is `eval_pdf`'s value, so that half holds by construction; the
    /// value itself is checked by the chi-square and Fresnel-limit tests in `tests/specular.rs`
    /// and by the reference images.)
    #[test]
    fn eval_pdf_is_eval_and_pdf() {
        use crate::microfacet::Distribution;
        for (k, dist) in [Distribution::Beckmann, Distribution::Ggx]
            .into_iter()
            .enumerate()
        {
            let c = RoughConductor::new(
                SampledSpectrum::splat(0.2),
                SampledSpectrum::splat(3.4),
                SampledSpectrum::splat(0.9),
                Microfacet::new(dist, 0.12, 0.3),
            );
            crate::check_eval_pdf(
                11 + k as u64,
                20_000,
                |a, b| c.eval_pdf(a, b),
                |a, b| c.eval(a, b),
                |a, b| c.pdf(a, b),
            );
        }
    }

    #[test]
    fn gold_like_normal_incidence() {
        // eta = 0.2, k = 3.4: R = ((n-1)^2 + k^2)/((n+1)^2 + k^2) = 12.2/13.0 = 0.93846.
        let c = Conductor::new(
            SampledSpectrum::splat(0.2),
            SampledSpectrum::splat(3.4),
            SampledSpectrum::splat(1.0),
        );
        let s = c.sample(Vec3::Z, Vec2::ZERO).unwrap();
        assert!(s.delta && s.wi == Vec3::Z && s.pdf == 1.0);
        assert!(
            (s.weight.0.x - 12.2 / 13.0).abs() < 1e-6,
            "{}",
            s.weight.0.x
        );
    }
}
