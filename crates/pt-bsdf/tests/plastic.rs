//! Rough plastic (Mitsuba `roughplastic`): chi-square of sampling against the pdf over a grid of
//! distributions, roughness, albedo and incident angle (0 and 89 degrees included); white
//! furnace; the smooth, black-base limit (pure Fresnel reflection); robustness.
//!
//! Its eval and pdf were also compared point by point with Mitsuba 3.9.1's own plugin through
//! `pt lobes --csv` (GGX alpha 0.2 and 0.05, Beckmann alpha 0.4, in the plane of incidence,
//! theta_o to 89.5 degrees): f and the GGX pdf agree to 0.25% everywhere (the Beckmann pdf
//! differs by design: pt samples D cos, Mitsuba visible normals). That check needs Mitsuba and
//! is not run here; the scene test (scenes/plastic.xml) covers it in CI.

use crate::common;
use common::*;
use pt_bsdf::fresnel::fresnel_dielectric;
use pt_bsdf::{Bsdf, CoatingTable, Distribution, Microfacet, RoughPlastic};
use pt_math::Vec3;
use pt_spectrum::SampledSpectrum;
use pt_testkit::{albedo_mc, albedo_quadrature, dir_deg, Chi2Report};

fn plastic(dist: Distribution, alpha: f32, rho: f32, eta: f32) -> Bsdf {
    let mf = Microfacet::new(dist, alpha, alpha);
    let table = CoatingTable::get(mf.dist, mf.alpha_u, eta);
    Bsdf::RoughPlastic(RoughPlastic::new(
        SampledSpectrum::splat(rho),
        SampledSpectrum::splat(1.0),
        eta,
        mf,
        false,
        1.0 / (1.0 + rho),
        table,
    ))
}

fn grid() -> Vec<(String, Bsdf)> {
    let mut v = Vec::new();
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        for alpha in [0.05f32, 0.3, 1.0] {
            for rho in [0.0f32, 0.5, 1.0] {
                v.push((
                    format!("roughplastic {dist:?} alpha={alpha} rho={rho}"),
                    plastic(dist, alpha, rho, 1.49),
                ));
            }
        }
    }
    v
}

#[test]
fn chi2_rough_plastic() {
    let mut rep = Chi2Report::default();
    for (name, b) in grid() {
        for th in [0.0, 45.0, 89.0] {
            rep.push(chi2(&format!("{name} theta_o={th}"), b, dir_deg(th, 20.0)));
        }
    }
    rep.check(0.01);
}

#[test]
fn white_furnace_and_quadrature() {
    // Energy: with a white base (rho = 1) the albedo R(mu) + (diffuse part) stays <= 1 within
    // 5 standard errors plus 0.5%. The model is approximate: its inner-bounce normalisation uses
    // the 64-node sum for r_i, which is what Mitsuba does, and the tabulated T; over this grid
    // the largest albedo measured is 0.979 (GGX, rho 1), so the margin is not needed today. A
    // missing 1/eta^2 (albedo ~2.2) fails it by far. MC and quadrature of f cos agree within 5 se + 3e-3.
    let mut max_albedo = 0.0f64;
    for (name, b) in grid() {
        for th in [0.0, 60.0, 85.0] {
            let wo = dir_deg(th, 10.0);
            let (e, se) = albedo_mc(wo, &sampler(b), 40_000, 3);
            max_albedo = max_albedo.max(e);
            assert!(
                e <= 1.005 + 5.0 * se,
                "{name} theta={th}: albedo {e} +- {se}"
            );
            if name.contains("alpha=0.3") || name.contains("alpha=1") {
                let q = albedo_quadrature(wo, &eval_fn(b), 1e-7);
                assert!(
                    (e - q).abs() <= 5.0 * se + 3e-3,
                    "{name} theta={th}: MC {e} +- {se} vs quadrature {q}"
                );
            }
        }
    }
    eprintln!("largest directional albedo over the grid: {max_albedo:.5}");
}

#[test]
fn black_base_smooth_coating_is_fresnel() {
    // rho = 0 and alpha -> 0: only the coating's mirror reflection is left, albedo F(cos, eta).
    for th in [0.0f64, 40.0, 70.0] {
        let wo = dir_deg(th, 0.0);
        let b = plastic(Distribution::Ggx, 0.002, 0.0, 1.5);
        let (e, se) = albedo_mc(wo, &sampler(b), 20_000, 9);
        let f = f64::from(fresnel_dielectric(wo.z, 1.5));
        assert!(
            (e - f).abs() <= 5.0 * se + 2e-3 * f,
            "theta {th}: albedo {e} +- {se} vs Fresnel {f}"
        );
    }
}

#[test]
fn white_base_brightens_and_coating_table_is_monotone() {
    // The coating's transmittance falls towards grazing incidence (Fresnel), and a brighter
    // base gives a brighter diffuse term.
    let t = CoatingTable::get(Distribution::Ggx, 0.3, 1.49);
    for k in 1..t.external_transmittance.len() {
        assert!(
            t.external_transmittance[k] + 1e-4 >= t.external_transmittance[k - 1],
            "T not monotone at {k}: {:?}",
            t.external_transmittance
        );
    }
    let (a, b) = (
        plastic(Distribution::Ggx, 0.3, 0.2, 1.49),
        plastic(Distribution::Ggx, 0.3, 0.8, 1.49),
    );
    let (wo, wi) = (dir_deg(30.0, 0.0), dir_deg(50.0, 100.0));
    assert!(b.eval(wo, wi).0.x > a.eval(wo, wi).0.x);
}

#[test]
fn no_nan_for_any_direction() {
    for (name, b) in grid() {
        assert_finite_everywhere(&name, b);
    }
    assert_finite_everywhere(
        "roughplastic min alpha",
        plastic(Distribution::Beckmann, 0.0, 0.5, 1.49),
    );
    let _ = Vec3::Z;
}
