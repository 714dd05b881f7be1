//! Tests of the hair fibre model (`Hair`, Chiang et al. 2016): the white furnace (with no
//! absorption every path leaves the fibre: albedo 1, by quadrature of f |cos| and by the mean
//! sample weight, within 1% as Mitsuba's and pbrt-v4's hair tests ask), sampling against the
//! pdf (chi-square), finite values everywhere, and absorption lowering the albedo.

use crate::common;
use common::*;
use pt_bsdf::{Bsdf, Hair};
use pt_math::{Vec3, Vec4};
use pt_spectrum::SampledSpectrum;
use pt_testkit::{albedo_mc, albedo_quadrature, Chi2Report};

/// RGB luminance weights (the lanes R, G, B).
const RGB: Vec4 = Vec4::new(0.212_671, 0.715_160, 0.072_169, 0.0);

fn hair(sigma_a: [f32; 3], bm: f32, bn: f32, alpha: f32) -> Bsdf {
    Bsdf::Hair(Hair::new(
        SampledSpectrum::from_rgb(sigma_a),
        RGB,
        1.55,
        bm,
        bn,
        alpha,
    ))
}

/// Viewing directions in the fibre's frame (fibre along y, normal z): across the fibre head
/// on, off-centre (h = +-0.7), and tilted along the fibre by 30 and 70 degrees.
fn views() -> Vec<Vec3> {
    let d = |theta_deg: f32, gamma_deg: f32| {
        let (t, g) = (theta_deg.to_radians(), gamma_deg.to_radians());
        Vec3::new(-t.cos() * g.sin(), t.sin(), t.cos() * g.cos())
    };
    vec![
        d(0.0, 0.0),
        d(0.0, 44.4),
        d(30.0, -44.4),
        d(-70.0, 20.0),
        d(10.0, 80.0),
    ]
}

/// With sigma_a = 0 nothing is absorbed: the sum of the A_p is 1 and each lobe is normalised,
/// so the albedo is 1 from every direction. Quadrature of f |cos| over the sphere within 1%
/// (the bound; the quadrature is finer than the lobes at b_m >= 0.2), and the mean
/// sample weight within 1% too (it is exactly 1 per sample but for the p choice and the pdf's
/// cancellation: the check that `sample`'s weights are `eval`'s).
#[test]
fn white_furnace() {
    for (bm, bn, alpha) in [
        (0.2f32, 0.2f32, 2.0f32),
        (0.3, 0.3, 0.0),
        (0.3, 0.3, 8.0),
        (0.6, 0.9, 2.0),
        (1.0, 0.1, 2.0),
    ] {
        {
            let b = hair([0.0; 3], bm, bn, alpha);
            for wo in views() {
                let q = albedo_quadrature(wo, &eval_fn(b), 1e-5);
                assert!(
                    (q - 1.0).abs() < 0.01,
                    "b_m {bm} b_n {bn} alpha {alpha} wo {wo}: quadrature albedo {q}"
                );
                let (mc, se) = albedo_mc(wo, &sampler(b), 20_000, 5);
                assert!(
                    (mc - 1.0).abs() < 0.01 && se < 0.003,
                    "b_m {bm} b_n {bn} alpha {alpha} wo {wo}: MC albedo {mc} +- {se}"
                );
            }
        }
    }
}

/// With absorption the two estimates still agree (5 standard errors + 0.5%) and the albedo is
/// below 1: sample weights are eval |cos| / pdf also where the A_p are not the p choice's
/// probabilities.
#[test]
fn absorbing_albedo_mc_equals_quadrature() {
    let sigma = Hair::pigment_sigma_a_rgb(1.3, 0.2);
    for (bm, bn) in [(0.25f32, 0.3f32), (0.5, 0.6)] {
        let b = hair(sigma, bm, bn, 2.0);
        for wo in views() {
            let q = albedo_quadrature(wo, &eval_fn(b), 1e-5);
            let (mc, se) = albedo_mc(wo, &sampler(b), 40_000, 11);
            assert!(
                (mc - q).abs() <= 5.0 * se + 5e-3,
                "b_m {bm} wo {wo}: MC {mc} +- {se} vs quadrature {q}"
            );
            assert!(q < 1.0 && q > 0.02, "b_m {bm} wo {wo}: albedo {q}");
        }
    }
}

/// The sampler draws from exactly the pdf `pdf` returns (chi-square over the sphere, family-wise
/// level 0.01): a wrong p probability, longitudinal inversion or azimuthal offset fails it.
#[test]
fn chi2_sampling_matches_pdf() {
    let mut rep = Chi2Report::default();
    let sigma = Hair::pigment_sigma_a_rgb(0.4, 0.6);
    for (bm, bn) in [(0.3f32, 0.3f32), (0.2, 0.15)] {
        let b = hair(sigma, bm, bn, 3.0);
        for (k, wo) in views().into_iter().enumerate() {
            rep.push(chi2(&format!("hair b_m {bm} b_n {bn} view {k}"), b, wo));
        }
    }
    rep.check(0.01);
}

#[test]
fn no_nan_for_any_direction() {
    assert_finite_everywhere(
        "hair",
        hair(Hair::pigment_sigma_a_rgb(1.3, 0.2), 0.3, 0.3, 2.0),
    );
    assert_finite_everywhere("smooth hair", hair([0.0; 3], 0.05, 0.05, 0.0));
    assert_finite_everywhere("rough hair", hair([2.0, 1.0, 0.5], 1.0, 1.0, 10.0));
}
