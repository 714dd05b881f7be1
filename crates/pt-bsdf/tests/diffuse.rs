//! Statistical and closed-form tests of the diffuse models (Lambert, Oren-Nayar, Minnaert).
//!
//! Chi-square tests (pt-testkit, Mitsuba's method) run over a grid of parameters and incident
//! angles including theta_o = 0 and 89 degrees; the grid is judged at family-wise significance
//! 0.01 with the Šidák correction, so a correct sampler fails the whole grid with probability
//! 1% for a random seed (the seed is fixed, so the outcome is deterministic).

use crate::common;
use common::*;
use pt_bsdf::{Bsdf, Lambert, Minnaert, OrenNayar, OrenNayarVariant};
use pt_math::Vec3;
use pt_spectrum::SampledSpectrum;
use pt_testkit::{
    albedo_mc, albedo_quadrature, dir_deg, reciprocity_error, upper_hemisphere, Chi2Report,
};

const VARIANTS: [OrenNayarVariant; 4] = [
    OrenNayarVariant::Qualitative,
    OrenNayarVariant::Full,
    OrenNayarVariant::Fujii,
    OrenNayarVariant::Eon,
];
const THETAS: [f64; 5] = [0.0, 30.0, 60.0, 80.0, 89.0];

fn white() -> SampledSpectrum {
    SampledSpectrum::from_rgb([1.0; 3])
}

fn diffuse_models() -> Vec<(String, Bsdf)> {
    let mut v = vec![("lambert".to_string(), Bsdf::Lambert(Lambert::new(white())))];
    for var in VARIANTS {
        for sigma in [0.0f32, 0.3, 1.0, 3.0] {
            v.push((
                format!("oren_nayar {var:?} sigma={sigma}"),
                Bsdf::OrenNayar(OrenNayar::new(white(), sigma, var)),
            ));
        }
    }
    v.push((
        "eon r=1".into(),
        Bsdf::OrenNayar(OrenNayar::from_fujii_roughness(
            white(),
            1.0,
            OrenNayarVariant::Eon,
        )),
    ));
    for k in [0.0f32, 0.5, 1.0, 2.0, 8.0] {
        v.push((
            format!("minnaert k={k}"),
            Bsdf::Minnaert(Minnaert::new(white(), k)),
        ));
    }
    v
}

fn chi2_grid(full: bool) {
    let mut rep = Chi2Report::default();
    for (name, b) in diffuse_models() {
        // Fast grid: the extremes of each parameter (and sigma = 0 is covered by the Lambert
        // equality tests); the full grid runs everything.
        let keep = full
            || !(name.contains("sigma=0.3")
                || name.contains("sigma=1 ")
                || name.contains("sigma=0 ")
                || name.ends_with("sigma=0")
                || name.ends_with("sigma=1")
                || name.contains("k=1")
                || name.contains("k=2"));
        if !keep {
            continue;
        }
        let thetas: &[f64] = if full { &THETAS } else { &[0.0, 60.0, 89.0] };
        for &th in thetas {
            rep.push(chi2_n(
                &format!("{name} theta_o={th}"),
                b,
                dir_deg(th, 20.0),
                full,
            ));
        }
    }
    rep.check(0.01);
}

#[test]
fn chi2_sampling_matches_pdf() {
    chi2_grid(false);
}

#[test]
#[ignore = "slow (~1 min): full grid, 1M samples per test; run with `cargo test -p pt-bsdf -- --ignored`"]
fn chi2_sampling_matches_pdf_full_grid() {
    chi2_grid(true);
}

#[test]
fn no_nan_for_any_direction() {
    for (name, b) in diffuse_models() {
        assert_finite_everywhere(&name, b);
    }
}

#[test]
fn white_furnace_and_analytic_albedo() {
    // Energy: MC albedo (E[weight], 20k samples) and quadrature of f cos must agree, be <= 1,
    // and equal the closed form where one exists. Tolerances: 5 standard errors of the MC mean
    // (a correct estimator exceeds that with probability 6e-7) plus 2e-3 for the quadrature of
    // kinked integrands (max/min in the formulas).
    for (name, b) in diffuse_models() {
        for th in [0.0, 45.0, 80.0, 89.0] {
            let wo = dir_deg(th, 0.0);
            let (mc, se) = albedo_mc(wo, &sampler(b), 20_000, 9);
            let q = albedo_quadrature(wo, &eval_fn(b), 1e-7);
            assert!(
                (mc - q).abs() <= 5.0 * se + 2e-3,
                "{name} theta={th}: MC {mc} +- {se} vs quadrature {q}"
            );
            let analytic = match b {
                Bsdf::Lambert(_) => Some(1.0),
                Bsdf::OrenNayar(m) => m.albedo(wo).map(|a| f64::from(a.0.x)),
                Bsdf::Minnaert(m) => Some(f64::from(m.albedo(wo).0.x)),
                #[allow(unreachable_patterns)]
                _ => None,
            };
            if let Some(a) = analytic {
                assert!(
                    (q - a).abs() < 2e-3,
                    "{name} theta={th}: quadrature {q} vs analytic {a}"
                );
            }
            // The 1994 models are not energy conserving: the qualitative model exceeds 1 at
            // grazing view (1.004 at sigma = 0.3, 89 degrees; the EON paper's motivation) and the
            // full model's interreflection term adds energy. They are bounded by 1.1 here;
            // Fujii, EON, Lambert and Minnaert must stay <= 1 (+ quadrature tolerance).
            let bound = if name.contains("Full") || name.contains("Qualitative") {
                1.1
            } else {
                1.0 + 2e-3
            };
            assert!(q <= bound, "{name} theta={th}: albedo {q} > {bound}");
        }
    }
}

#[test]
fn eon_albedo_is_one_for_white_and_analytic_for_grey() {
    for r in [0.0f32, 0.25, 0.5, 1.0] {
        for rho in [1.0f32, 0.5] {
            let m = OrenNayar::from_fujii_roughness(
                SampledSpectrum::from_rgb([rho; 3]),
                r,
                OrenNayarVariant::Eon,
            );
            for th in [0.0, 40.0, 75.0, 88.0] {
                let wo = dir_deg(th, 0.0);
                let a = f64::from(m.albedo(wo).unwrap().0.x);
                if rho == 1.0 {
                    assert!(
                        (a - 1.0).abs() < 1e-5,
                        "r={r} theta={th}: analytic albedo {a}"
                    );
                }
                let q = albedo_quadrature(wo, &eval_fn(Bsdf::OrenNayar(m)), 1e-7);
                assert!(
                    (q - a).abs() < 2e-3,
                    "r={r} rho={rho} theta={th}: {q} vs {a}"
                );
            }
        }
    }
}

#[test]
fn reciprocity() {
    // Every diffuse model here is reciprocal except Minnaert with k < 1 (documented rule).
    for (name, b) in diffuse_models() {
        let e = reciprocity_error(&eval_fn(b), &upper_hemisphere, 2000, 1e-6);
        if name.starts_with("minnaert k=0") {
            assert!(e > 1e-3, "{name}: expected non-reciprocal, error {e}");
        } else {
            assert!(e < 1e-4, "{name}: reciprocity error {e}");
        }
    }
}

#[test]
fn limits_equal_lambert() {
    let rho = SampledSpectrum::from_rgb([0.25, 0.5, 0.75]);
    let lam = Lambert::new(rho);
    for (wo, wi) in [
        (Vec3::Z, dir_deg(70.0, 10.0)),
        (dir_deg(89.0, 0.0), dir_deg(89.0, 180.0)),
        (dir_deg(30.0, 0.0), dir_deg(30.0, 0.0)),
    ] {
        for v in VARIANTS {
            let on = OrenNayar::new(rho, 0.0, v);
            assert!(
                (on.eval(wo, wi).0 - lam.eval(wo, wi).0).abs().max_element() < 1e-7,
                "{v:?}"
            );
        }
        let mi = Minnaert::new(rho, 1.0);
        assert!((mi.eval(wo, wi).0 - lam.eval(wo, wi).0).abs().max_element() < 1e-7);
    }
}
