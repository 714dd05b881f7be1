//! Blends (`SurfaceBsdf::blend`, Mitsuba `blendbsdf`): (1 - w) a + w b.
//!
//! 1. Chi-square: sampling the blend of a Lambert and a rough GGX conductor matches the
//!    mixture pdf `pdf` reports (pt-testkit's test over the sphere, Šidák-corrected at 0.01
//!    over the grid); a wrong selection probability moves mass between the lobes and fails the
//!    histogram, and a sample that reported the chosen model's own pdf (Mitsuba's `sample`)
//!    fails the testkit's per-sample check `pdf == pdf(wo, wi)`.
//! 2. Weights: every sample's weight equals `eval |cos| / pdf` of the mixture, to 1e-3.
//! 3. Energy: the blend's directional albedo (Monte Carlo over its own samples) equals
//!    (1 - w) albedo(a) + w albedo(b) by quadrature within 4.5 standard errors (+1e-3
//!    quadrature tolerance), for smooth models; a wrong selection probability (w for 1 - w)
//!    moves it by |1 - 2w| |albedo(a) - albedo(b)|, here >= 0.05, far outside. With a delta
//!    model (smooth conductor), the albedo is checked the same way with its closed-form
//!    Fresnel reflectance.

use crate::common;
use common::surface_sampler;
use pt_bsdf::{Bsdf, Conductor, Distribution, Lambert, Microfacet, RoughConductor, SurfaceBsdf};
use pt_math::Vec3;
use pt_spectrum::SampledSpectrum;
use pt_testkit::{albedo_mc, albedo_quadrature, chi2_sphere, dir_deg, Chi2Config, Chi2Report};

fn lambert(r: f32) -> Bsdf {
    Bsdf::Lambert(Lambert::new(SampledSpectrum::splat(r)))
}

fn rough_gold(alpha: f32) -> Bsdf {
    Bsdf::RoughConductor(RoughConductor::new(
        SampledSpectrum::splat(0.2),
        SampledSpectrum::splat(3.0),
        SampledSpectrum::splat(1.0),
        Microfacet::new(Distribution::Ggx, alpha, alpha),
    ))
}

fn blend(a: Bsdf, w: f32, b: Bsdf, two_sided: bool) -> SurfaceBsdf {
    SurfaceBsdf {
        blend: Some((w, b)),
        ..SurfaceBsdf::new(a, two_sided)
    }
}

#[test]
fn blend_sampling_matches_mixture_pdf_and_weights() {
    let mut report = Chi2Report::default();
    for w in [0.2f32, 0.7] {
        for alpha in [0.05f32, 0.4] {
            for two_sided in [false, true] {
                let s = blend(lambert(0.8), w, rough_gold(alpha), two_sided);
                for wo in [
                    dir_deg(0.0, 0.0),
                    dir_deg(45.0, 30.0),
                    dir_deg(80.0, 200.0),
                    dir_deg(130.0, 10.0),
                ] {
                    if !two_sided && wo.z < 0.0 {
                        continue;
                    }
                    let label =
                        format!("blend w={w} alpha={alpha} two_sided={two_sided} wo={wo:?}");
                    report.push(chi2_sphere(
                        &label,
                        wo,
                        &surface_sampler(s),
                        &|wo, wi| s.pdf(wo, wi),
                        &Chi2Config::default(),
                    ));
                    let mut rng = pt_testkit::Pcg32::new(11, 5);
                    for _ in 0..2000 {
                        let Some(bs) = s.sample(
                            wo,
                            rng.next_f32(),
                            pt_math::Vec2::new(rng.next_f32(), rng.next_f32()),
                        ) else {
                            continue;
                        };
                        let want = s.eval(wo, bs.wi).0.x * bs.wi.z.abs() / s.pdf(wo, bs.wi);
                        assert!(
                            (bs.weight.0.x - want).abs() <= 1e-3 * want.max(1e-3),
                            "{label}: weight {} vs {want}",
                            bs.weight.0.x
                        );
                    }
                }
            }
        }
    }
    report.check(0.01);
}

#[test]
fn blend_albedo_is_the_weighted_sum() {
    let f = |s: SurfaceBsdf| move |wo: Vec3, wi: Vec3| s.eval(wo, wi).0.x;
    for w in [0.25f32, 0.8] {
        let (a, b) = (lambert(0.3), rough_gold(0.3));
        for wo in [dir_deg(10.0, 0.0), dir_deg(60.0, 45.0)] {
            let qa = albedo_quadrature(wo, &f(SurfaceBsdf::new(a, false)), 1e-6);
            let qb = albedo_quadrature(wo, &f(SurfaceBsdf::new(b, false)), 1e-6);
            let want = (1.0 - w as f64) * qa + w as f64 * qb;
            let (m, se) = albedo_mc(wo, &surface_sampler(blend(a, w, b, false)), 400_000, 3);
            assert!(
                ((1.0 - 2.0 * w as f64) * (qa - qb)).abs() > 0.05,
                "test cannot tell w from 1 - w"
            );
            assert!(
                (m - want).abs() <= 4.5 * se + 1e-3,
                "w={w} wo={wo:?}: albedo {m} +- {se} vs {want}"
            );
        }
    }
    // With a delta model: albedo = (1 - w) rho + w F(cos), F the conductor's Fresnel reflectance.
    let (w, rho) = (0.4f32, 0.6f32);
    let mirror = Bsdf::Conductor(Conductor::new(
        SampledSpectrum::splat(0.2),
        SampledSpectrum::splat(3.0),
        SampledSpectrum::splat(1.0),
    ));
    let wo = dir_deg(30.0, 0.0);
    let fresnel = mirror
        .sample(wo, 0.5, pt_math::Vec2::splat(0.5))
        .unwrap()
        .weight
        .0
        .x as f64;
    let (m, se) = albedo_mc(
        wo,
        &surface_sampler(blend(lambert(rho), w, mirror, false)),
        400_000,
        4,
    );
    let want = (1.0 - w as f64) * rho as f64 + w as f64 * fresnel;
    assert!(
        (m - want).abs() <= 4.5 * se + 1e-4,
        "delta blend: albedo {m} +- {se} vs {want}"
    );
}
