//! Tests of Mitsuba's `pplastic` and `polarizer` as its unpolarized variants render them
//! (`PPlastic`, `Polarizer`): values and pdfs against Mitsuba 3.9.1 itself, sampling against
//! the pdf (chi-square), finiteness everywhere, sample weights against the integral of eval.

use crate::common;
use common::*;
use pt_bsdf::{Bsdf, Distribution, Microfacet, PPlastic, Polarizer};
use pt_math::Vec3;
use pt_spectrum::SampledSpectrum;
use pt_testkit::{albedo_mc, albedo_quadrature, dir_deg, Chi2Report};

/// The three configurations of the Mitsuba comparison as the loader and material layer build
/// them (RGB mode): Mitsuba's defaults (Beckmann 0.1, int_ior 1.49 over air, rho 0.5); GGX 0.3
/// with int_ior 1.6 and a coloured base; anisotropic GGX (0.1, 0.4) with a coloured specular
/// factor. The sampling weight is mean(k_s) / (mean(k_s) + mean(rho)).
fn configs() -> [Bsdf; 3] {
    let air = 1.000277f32;
    let make = |rho: [f32; 3], ks: [f32; 3], eta: f32, mf: Microfacet| {
        let mean = |c: [f32; 3]| (c[0] + c[1] + c[2]) / 3.0;
        Bsdf::PPlastic(PPlastic::new(
            SampledSpectrum::from_rgb(rho),
            SampledSpectrum::from_rgb(ks),
            eta,
            mf,
            mean(ks) / (mean(ks) + mean(rho)),
        ))
    };
    [
        make(
            [0.5; 3],
            [1.0; 3],
            1.49 / air,
            Microfacet::new(Distribution::Beckmann, 0.1, 0.1),
        ),
        make(
            [0.8, 0.4, 0.2],
            [1.0; 3],
            1.6 / air,
            Microfacet::new(Distribution::Ggx, 0.3, 0.3),
        ),
        make(
            [0.1, 0.3, 0.6],
            [0.7, 0.6, 0.5],
            1.49 / air,
            Microfacet::new(Distribution::Ggx, 0.1, 0.4),
        ),
    ]
}

/// Mitsuba 3.9.1 `scalar_rgb` (`mi.load_dict({'type': 'pplastic', ...})`, `eval` and `pdf`
/// with `si.wi` the viewer `wo` here), read back on 2026-12-03: (config, wo (theta, phi)
/// degrees, wi (theta, phi), eval including |cos wi|, pdf). A back-side pair included.
#[rustfmt::skip]
#[allow(clippy::excessive_precision)] // the values as Mitsuba printed them
const MITSUBA: &[MitsubaValue] = &[
    (0, (30.0, 0.0), (40.0, 180.0), [2.9274756e-01, 2.9274756e-01, 2.9274756e-01], 2.9744284e+00),
    (0, (60.0, 10.0), (20.0, 200.0), [1.3116491e-01, 1.3116491e-01, 1.3116491e-01], 9.9720158e-02),
    (0, (10.0, 0.0), (75.0, 90.0), [2.9656379e-02, 2.9656379e-02, 2.9656379e-02], 2.7461549e-02),
    (0, (45.0, 0.0), (45.0, 180.0), [6.5087879e-01, 6.5087879e-01, 6.5087879e-01], 7.5776639e+00),
    (0, (70.0, 0.0), (60.0, 170.0), [1.0174267e-01, 1.0174267e-01, 1.0174267e-01], 2.9280797e-01),
    (0, (20.0, 0.0), (160.0, 200.0), [0.0, 0.0, 0.0], 0.0),
    (0, (80.0, 30.0), (5.0, 250.0), [9.3597144e-02, 9.3597144e-02, 9.3597144e-02], 1.0569953e-01),
    (1, (30.0, 0.0), (40.0, 180.0), [2.2208880e-01, 1.3539210e-01, 9.2043750e-02], 6.7350811e-01),
    (1, (60.0, 10.0), (20.0, 200.0), [2.2271122e-01, 1.2137600e-01, 7.0708387e-02], 3.2586703e-01),
    (1, (10.0, 0.0), (75.0, 90.0), [4.7329009e-02, 2.4536844e-02, 1.3140760e-02], 5.1897604e-02),
    (1, (45.0, 0.0), (45.0, 180.0), [2.3468858e-01, 1.5587461e-01, 1.1646762e-01], 9.0582305e-01),
    (1, (70.0, 0.0), (60.0, 170.0), [2.3429406e-01, 1.8803948e-01, 1.6491219e-01], 8.2025588e-01),
    (1, (80.0, 30.0), (5.0, 250.0), [1.5253676e-01, 8.0692403e-02, 4.4770226e-02], 1.9965677e-01),
    (2, (30.0, 0.0), (40.0, 180.0), [4.4149257e-02, 8.5771181e-02, 1.4975995e-01], 5.6778789e-01),
    (2, (60.0, 10.0), (20.0, 200.0), [2.6968077e-02, 7.9328582e-02, 1.5792185e-01], 1.2210340e-01),
    (2, (10.0, 0.0), (75.0, 90.0), [8.4603848e-03, 1.9961637e-02, 3.7394166e-02], 1.0514491e-01),
    (2, (45.0, 0.0), (45.0, 180.0), [1.1597199e-01, 1.4304443e-01, 1.9048214e-01], 1.8845575e+00),
    (2, (70.0, 0.0), (60.0, 170.0), [1.0873333e-01, 1.1906013e-01, 1.4145499e-01], 8.3627272e-01),
    (2, (80.0, 30.0), (5.0, 250.0), [1.9001773e-02, 5.6400299e-02, 1.1251825e-01], 1.1891489e-01),
];

/// eval (times |cos wi|) and pdf equal Mitsuba 3.9.1's to 1e-4 relative: both terms, both
/// distributions, anisotropy, the coloured factors and the fixed lobe probability.
#[test]
fn pplastic_matches_mitsuba() {
    check_against_mitsuba("pplastic", &configs(), MITSUBA);
}

/// The sampler draws exactly the mixture `pdf` returns (chi-square over the sphere, Sidak
/// level 0.01 over the grid, fixed seed).
#[test]
fn pplastic_chi2_sampling_matches_pdf() {
    let mut rep = Chi2Report::default();
    for (k, b) in configs().into_iter().enumerate() {
        for th in [10.0, 50.0, 80.0] {
            rep.push(chi2(
                &format!("config {k} theta_o={th}"),
                b,
                dir_deg(th, 20.0),
            ));
        }
    }
    rep.check(0.01);
}

#[test]
fn pplastic_finite_everywhere() {
    for (k, b) in configs().into_iter().enumerate() {
        assert_finite_everywhere(&format!("pplastic config {k}"), b);
    }
}

/// Sample weights integrate to the quadrature of f |cos| (`sample` consistent with `eval`):
/// MC over 20k samples within 5 standard errors plus 3e-3 (the quadrature's tolerance). The
/// model loses energy at grazing angles (its two terms are only added): the albedo at 80
/// degrees is below 1 and below the one at normal incidence.
#[test]
fn pplastic_sample_weights_match_eval() {
    for (k, b) in configs().into_iter().enumerate() {
        let mut albedo = Vec::new();
        for th in [0.0, 45.0, 80.0] {
            let wo = dir_deg(th, 0.0);
            let (mc, se) = albedo_mc(wo, &sampler(b), 20_000, 9);
            let q = albedo_quadrature(wo, &eval_fn(b), 1e-7);
            assert!(
                (mc - q).abs() <= 5.0 * se + 3e-3,
                "config {k} theta={th}: MC {mc} +- {se} vs quadrature {q}"
            );
            albedo.push(q);
        }
        assert!(albedo.iter().all(|&a| a < 1.0), "config {k}: {albedo:?}");
    }
}

/// The polarizer for unpolarized light: straight through from both sides with half the
/// transmittance, a delta event (Mitsuba's null lobe: a pass-through), nothing to evaluate.
#[test]
fn polarizer_passes_half() {
    let p = Bsdf::Polarizer(Polarizer {
        kept: 0.5,
        transmittance: SampledSpectrum::from_rgb([0.8, 0.6, 1.0]),
    });
    for wo in [dir_deg(30.0, 40.0), dir_deg(150.0, 200.0), Vec3::Z] {
        let s = p
            .sample(wo, 0.3, pt_math::Vec2::new(0.2, 0.7))
            .expect("sample");
        assert_eq!(s.wi, -wo);
        assert_eq!(s.weight.rgb(), [0.4, 0.3, 0.5]);
        assert!(s.delta && s.pdf == 1.0 && s.is_pass_through(wo));
        assert!(p.eval(wo, -wo).is_black() && p.pdf(wo, -wo) == 0.0);
    }
    assert!(p.is_transmissive() && !p.has_smooth_lobe());
}
