//! Tests of the conductors and dielectrics: chi-square for the rough (non-delta) models over a
//! grid of roughness, anisotropy, index and incident angle (0 and 89 degrees included, and from
//! inside the medium for dielectrics), deterministic checks of the delta lobes, white furnace,
//! reciprocity, closed-form limits and robustness.
//!
//! The chi-square grid is judged at family-wise significance 0.01 (Šidák over the grid).

use crate::common;
use common::*;
use pt_bsdf::fresnel::{fresnel_conductor, fresnel_dielectric};
use pt_bsdf::{
    Bsdf, Conductor, Dielectric, Distribution, Microfacet, RoughConductor, RoughDielectric,
    ThinDielectric,
};
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use pt_testkit::{
    albedo_mc, albedo_quadrature, check_delta, dir_deg, reciprocity_error, upper_hemisphere,
    Chi2Report, DeltaLobe, Sample,
};

fn one() -> SampledSpectrum {
    SampledSpectrum::splat(1.0)
}

fn rough_conductors() -> Vec<(String, Bsdf)> {
    let mut v = Vec::new();
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        for (au, av) in [
            (0.05f32, 0.05f32),
            (0.2, 0.2),
            (0.6, 0.6),
            (1.0, 1.0),
            (0.05, 0.4),
        ] {
            let mf = Microfacet::new(dist, au, av);
            let m = RoughConductor::new(
                SampledSpectrum::splat(0.2),
                SampledSpectrum::splat(3.4),
                one(),
                mf,
            );
            v.push((
                format!("roughconductor {dist:?} a=({au},{av})"),
                Bsdf::RoughConductor(m),
            ));
        }
    }
    v
}

fn rough_dielectrics() -> Vec<(String, Bsdf)> {
    let mut v = Vec::new();
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        for (au, av) in [(0.05f32, 0.05f32), (0.3, 0.3), (1.0, 1.0), (0.1, 0.5)] {
            for eta in [1.5f32, 1.0 / 1.33] {
                let m = RoughDielectric::new(eta, Microfacet::new(dist, au, av));
                v.push((
                    format!("roughdielectric {dist:?} a=({au},{av}) eta={eta}"),
                    Bsdf::RoughDielectric(m),
                ));
            }
        }
    }
    v
}

/// The fast grid keeps, per family, an isotropic, an anisotropic and a Beckmann case at the
/// extremes of roughness; the full grid (ignored by default) runs every model.
fn in_fast_grid(name: &str) -> bool {
    [
        "Ggx a=(0.05,0.05)",
        "Ggx a=(0.05,0.4)",
        "Ggx a=(0.1,0.5) eta=0.75",
        "Ggx a=(0.3,0.3) eta=1.5",
        "Beckmann a=(0.6,0.6)",
        "Beckmann a=(1,1) eta=1.5",
        "Ggx a=(1,1)",
    ]
    .iter()
    .any(|k| name.contains(k))
}

fn chi2_conductor_grid(full: bool) {
    let mut rep = Chi2Report::default();
    for (name, b) in rough_conductors()
        .into_iter()
        .filter(|(n, _)| full || in_fast_grid(n))
    {
        let thetas: &[f64] = if full {
            &[0.0, 30.0, 70.0, 89.0]
        } else {
            &[0.0, 70.0, 89.0]
        };
        for &th in thetas {
            rep.push(chi2_n(
                &format!("{name} theta_o={th}"),
                b,
                dir_deg(th, 35.0),
                full,
            ));
        }
    }
    rep.check(0.01);
}

fn chi2_dielectric_grid(full: bool) {
    let mut rep = Chi2Report::default();
    for (name, b) in rough_dielectrics()
        .into_iter()
        .filter(|(n, _)| full || in_fast_grid(n))
    {
        // 180 - theta: the viewer inside the medium.
        let thetas: &[f64] = if full {
            &[0.0, 45.0, 89.0, 120.0, 179.0]
        } else {
            &[0.0, 89.0, 120.0, 179.0]
        };
        for &th in thetas {
            rep.push(chi2_n(
                &format!("{name} theta_o={th}"),
                b,
                dir_deg(th, 35.0),
                full,
            ));
        }
    }
    rep.check(0.01);
}

#[test]
fn chi2_rough_conductor() {
    chi2_conductor_grid(false);
}

#[test]
fn chi2_rough_dielectric() {
    chi2_dielectric_grid(false);
}

#[test]
#[ignore = "slow (~30 s): full grid, 1M samples per test; run with `cargo test -p pt-bsdf -- --ignored`"]
fn chi2_rough_conductor_full_grid() {
    chi2_conductor_grid(true);
}

#[test]
#[ignore = "slow (~2 min): full grid, 1M samples per test; run with `cargo test -p pt-bsdf -- --ignored`"]
fn chi2_rough_dielectric_full_grid() {
    chi2_dielectric_grid(true);
}

#[test]
fn no_nan_for_any_direction() {
    let mut all = rough_conductors();
    all.extend(rough_dielectrics());
    all.push((
        "conductor".into(),
        Bsdf::Conductor(Conductor::new(
            SampledSpectrum::splat(0.2),
            SampledSpectrum::splat(3.4),
            one(),
        )),
    ));
    all.push((
        "mirror none".into(),
        Bsdf::Conductor(Conductor::new(
            SampledSpectrum::splat(0.0),
            SampledSpectrum::splat(1.0),
            one(),
        )),
    ));
    all.push(("dielectric".into(), Bsdf::Dielectric(Dielectric::new(1.5))));
    all.push((
        "thindielectric".into(),
        Bsdf::ThinDielectric(ThinDielectric::new(1.5)),
    ));
    all.push((
        "roughdielectric min alpha".into(),
        Bsdf::RoughDielectric(RoughDielectric::new(
            1.5,
            Microfacet::new(Distribution::Ggx, 0.0, 0.0),
        )),
    ));
    all.push((
        "roughconductor min alpha".into(),
        Bsdf::RoughConductor(RoughConductor::new(
            one(),
            one(),
            one(),
            Microfacet::new(Distribution::Beckmann, 0.0, 0.0),
        )),
    ));
    for (name, b) in all {
        assert_finite_everywhere(&name, b);
    }
}

/// E[weight], with transmitted samples multiplied by eta'^2: the energy (not radiance) albedo.
fn energy_albedo(b: Bsdf, wo: Vec3, n: usize) -> (f64, f64) {
    let s = move |wo: Vec3, u: Vec3| {
        b.sample(wo, u.x, Vec2::new(u.y, u.z)).map(|s| Sample {
            wi: s.wi,
            weight: s.weight.0.x
                * if s.wi.z * wo.z < 0.0 {
                    s.eta * s.eta
                } else {
                    1.0
                },
            pdf: s.pdf,
            delta: s.delta,
        })
    };
    albedo_mc(wo, &s, n, 5)
}

#[test]
fn white_furnace() {
    // Single-scattering microfacet models lose energy (more with roughness) but never gain it:
    // albedo <= 1 within 5 standard errors (a correct estimator exceeds that with probability
    // 6e-7). MC (E[weight]) and quadrature of f |cos| must agree within 5 standard errors plus
    // 3e-3 for the quadrature, checked where the lobe is wide enough for a 32x64-cell
    // quadrature (alpha >= 0.2).
    let mut all = rough_conductors();
    all.extend(rough_dielectrics());
    for (name, b) in all {
        let wide = match b {
            Bsdf::RoughConductor(m) => m.mf.alpha_u.min(m.mf.alpha_v) >= 0.2,
            Bsdf::RoughDielectric(m) => m.mf.alpha_u.min(m.mf.alpha_v) >= 0.2,
            _ => false,
        };
        for th in [0.0, 45.0, 80.0, 150.0] {
            let wo = dir_deg(th, 10.0);
            if matches!(b, Bsdf::RoughConductor(_)) && wo.z < 0.0 {
                continue;
            }
            let (e, se) = energy_albedo(b, wo, 20_000);
            assert!(
                e <= 1.0 + 5.0 * se + 1e-6,
                "{name} theta={th}: energy albedo {e} +- {se}"
            );
            // Quadrature cross-check on wide lobes at two angles (the quadrature is the slow part).
            if wide && (th == 45.0 || th == 150.0) {
                let (mc, se) = albedo_mc(wo, &sampler(b), 40_000, 8);
                let q = albedo_quadrature(wo, &eval_fn(b), 1e-7);
                assert!(
                    (mc - q).abs() <= 5.0 * se + 3e-3,
                    "{name} theta={th}: MC {mc} +- {se} vs quadrature {q}"
                );
            }
        }
    }
    // A white GGX conductor at low roughness loses almost nothing: albedo > 0.99 at normal
    // incidence (Heitz 2016 multiple-scattering paper, fig. 1: single-scattering loss ~0 at alpha 0.05).
    let m = RoughConductor::new(
        SampledSpectrum::splat(0.0),
        one(),
        one(),
        Microfacet::new(Distribution::Ggx, 0.05, 0.05),
    );
    let (e, _) = albedo_mc(Vec3::Z, &sampler(Bsdf::RoughConductor(m)), 40_000, 1);
    assert!(e > 0.99, "{e}");
}

#[test]
fn reciprocity() {
    // Rough conductor: f(a,b) = f(b,a) (F depends on a.h = b.h, G2 and D are symmetric).
    for (name, b) in rough_conductors() {
        let e = reciprocity_error(&eval_fn(b), &upper_hemisphere, 2000, 1e-4);
        assert!(e < 1e-3, "{name}: {e}");
    }
    // Rough dielectric: reflection is reciprocal; the radiance-transport BTDF obeys
    // f(a, b) / n_a^2 = f(b, a) / n_b^2 (Veach 1997, Sec. 5.2), n the index on each direction's
    // side, a = wo (the viewer).
    let mut rng = pt_testkit::Pcg32::new(4, 4);
    for (name, b) in rough_dielectrics() {
        let Bsdf::RoughDielectric(m) = b else {
            unreachable!()
        };
        let n_of = |w: Vec3| if w.z > 0.0 { 1.0 } else { m.eta };
        let (mut worst, mut over) = (0.0f32, 0usize);
        let pairs = 4000;
        for _ in 0..pairs {
            let a =
                pt_math::warp::square_to_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            let c =
                pt_math::warp::square_to_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            let x = m.eval(a, c).0.x / n_of(a).powi(2);
            let y = m.eval(c, a).0.x / n_of(c).powi(2);
            let e = (x - y).abs() / x.max(y).max(1e-4);
            worst = worst.max(e);
            over += usize::from(e > 1e-3);
        }
        // f32 rounding is amplified where (wi.h + wo.h/eta')^2 nears 0 and where a peaked D
        // (alpha = 0.05) is evaluated at a half vector computed in two different ways. A real
        // asymmetry (a wrong eta' power, F at the wrong cosine) is wrong almost everywhere:
        // at most 1% of pairs may exceed 1e-3 relative error, none 1e-2. (Before Fresnel was
        // computed from both cosines, pairs near total internal reflection reached 0.36.)
        assert!(
            over * 100 <= pairs && worst < 1e-2,
            "{name}: {over} of {pairs} pairs over 1e-3, worst {worst}"
        );
    }
}

#[test]
fn smooth_dielectric_delta_lobes_and_energy() {
    for eta in [1.5f32, 1.33, 1.0 / 1.5] {
        let d = Dielectric::new(eta);
        for th in [0.0, 30.0, 60.0, 85.0, 120.0, 150.0, 179.0] {
            let wo = dir_deg(th, 40.0);
            let r = fresnel_dielectric(wo.z, eta);
            let refl = Vec3::new(-wo.x, -wo.y, wo.z);
            let mut lobes = vec![DeltaLobe {
                wi: refl,
                prob: r,
                weight: 1.0,
            }];
            if r < 1.0 {
                let (t, etap) = pt_bsdf::fresnel::refract(wo, Vec3::Z, eta).unwrap();
                // Snell: n_o sin_o = n_i sin_i, on opposite sides.
                assert!(t.z * wo.z < 0.0);
                let sin_o = Vec2::new(wo.x, wo.y).length();
                let sin_t = Vec2::new(t.x, t.y).length();
                assert!(
                    (sin_o - etap * sin_t).abs() < 1e-5,
                    "{sin_o} {etap} {sin_t}"
                );
                lobes.push(DeltaLobe {
                    wi: t,
                    prob: 1.0 - r,
                    weight: 1.0 / (etap * etap),
                });
                // Energy in the eta^2-corrected sense: R * 1 + T * (weight eta'^2) = 1.
                assert!((r + (1.0 - r) * (1.0 / (etap * etap)) * etap * etap - 1.0).abs() < 1e-6);
            }
            check_delta(
                &format!("dielectric eta={eta} theta={th}"),
                wo,
                &sampler(Bsdf::Dielectric(d)),
                &lobes,
                20_000,
            );
            let (e, _) = energy_albedo(Bsdf::Dielectric(d), wo, 20_000);
            assert!((e - 1.0).abs() < 1e-5, "eta={eta} theta={th}: energy {e}");
        }
        // Normal incidence: R = ((eta-1)/(eta+1))^2.
        assert!((fresnel_dielectric(1.0, eta) - ((eta - 1.0) / (eta + 1.0)).powi(2)).abs() < 1e-6);
        assert!(d.eval(Vec3::Z, Vec3::Z).is_black() && d.pdf(Vec3::Z, -Vec3::Z) == 0.0);
    }
    // Total internal reflection: from inside beyond the critical angle, always reflected.
    let d = Dielectric::new(1.5);
    let wo = dir_deg(180.0 - 50.0, 0.0);
    check_delta(
        "tir",
        wo,
        &sampler(Bsdf::Dielectric(d)),
        &[DeltaLobe {
            wi: Vec3::new(-wo.x, -wo.y, wo.z),
            prob: 1.0,
            weight: 1.0,
        }],
        1000,
    );
}

#[test]
fn thin_dielectric_delta_lobes() {
    for eta in [1.5f32, 1.33] {
        let t = ThinDielectric::new(eta);
        for th in [0.0, 45.0, 89.0, 135.0] {
            let wo = dir_deg(th, 20.0);
            let r = fresnel_dielectric(wo.z.abs(), eta);
            let rp = if r < 1.0 {
                r + (1.0 - r).powi(2) * r / (1.0 - r * r)
            } else {
                1.0
            };
            assert!((t.reflectance(wo.z) - rp).abs() < 1e-6);
            let lobes = [
                DeltaLobe {
                    wi: Vec3::new(-wo.x, -wo.y, wo.z),
                    prob: rp,
                    weight: 1.0,
                },
                DeltaLobe {
                    wi: -wo,
                    prob: 1.0 - rp,
                    weight: 1.0,
                },
            ];
            check_delta(
                &format!("thin eta={eta} theta={th}"),
                wo,
                &sampler(Bsdf::ThinDielectric(t)),
                &lobes,
                20_000,
            );
        }
    }
}

#[test]
fn smooth_conductor_delta_lobe_and_fresnel() {
    let (n, k) = (0.2f32, 3.4f32);
    let c = Conductor::new(SampledSpectrum::splat(n), SampledSpectrum::splat(k), one());
    for th in [0.0, 40.0, 80.0, 89.0] {
        let wo = dir_deg(th, 70.0);
        let f = fresnel_conductor(wo.z, n, k);
        check_delta(
            "conductor",
            wo,
            &sampler(Bsdf::Conductor(c)),
            &[DeltaLobe {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                prob: 1.0,
                weight: f,
            }],
            100,
        );
    }
    let r0 = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
    assert!((fresnel_conductor(1.0, n, k) - r0).abs() < 1e-6);
    // One-sided: nothing from below.
    assert!(c.sample(-Vec3::Z, Vec2::ZERO).is_none());
}

#[test]
fn rough_conductor_tends_to_fresnel_times_mirror() {
    // At small roughness the albedo tends to F(cos_o) of the smooth conductor.
    let (n, k) = (0.2f32, 3.4f32);
    for th in [0.0, 50.0] {
        let wo = dir_deg(th, 0.0);
        let m = RoughConductor::new(
            SampledSpectrum::splat(n),
            SampledSpectrum::splat(k),
            one(),
            Microfacet::new(Distribution::Ggx, 0.01, 0.01),
        );
        let (e, _) = albedo_mc(wo, &sampler(Bsdf::RoughConductor(m)), 20_000, 2);
        let f = f64::from(fresnel_conductor(wo.z, n, k));
        assert!((e - f).abs() < 2e-3, "theta={th}: {e} vs {f}");
    }
}
