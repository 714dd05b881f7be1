//! Normal mapping (`SurfaceBsdf::normal`): sampling matches the pdf (chi-square over the sphere,
//! including the share of samples discarded by the side check), and sample weights equal
//! `eval |cos| / pdf` (so the shadowing term G is in both or neither), for Lambert and a rough GGX conductor under strongly tilted normals.
//! A pdf that forgot the rotation or the side check moves mass by far more than the few percent
//! the chi-square test resolves (see pt-testkit's `Chi2Config`).

use crate::common;

use common::surface_sampler;
use pt_bsdf::{Bsdf, Distribution, Lambert, Microfacet, RoughConductor, SurfaceBsdf};
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use pt_testkit::{chi2_sphere, dir_deg, Chi2Config, Chi2Report};

fn models() -> Vec<(&'static str, Bsdf)> {
    let rho = SampledSpectrum::splat(0.7);
    vec![
        ("lambert", Bsdf::Lambert(Lambert::new(rho))),
        (
            "roughconductor",
            Bsdf::RoughConductor(RoughConductor::new(
                SampledSpectrum::splat(0.2),
                SampledSpectrum::splat(3.0),
                SampledSpectrum::splat(1.0),
                Microfacet::new(Distribution::Ggx, 0.3, 0.3),
            )),
        ),
    ]
}

#[test]
fn sampling_matches_pdf_under_tilted_normals() {
    let mut report = Chi2Report::default();
    for (name, b) in models() {
        for n in [Vec3::new(0.5, 0.0, 0.8), Vec3::new(-0.3, 0.6, 0.5)] {
            for two_sided in [false, true] {
                let s = SurfaceBsdf {
                    normal: Some(n),
                    ..SurfaceBsdf::new(b, two_sided)
                };
                for wo in [
                    dir_deg(10.0, 0.0),
                    dir_deg(60.0, 180.0),
                    dir_deg(80.0, 90.0),
                    dir_deg(120.0, 30.0),
                ] {
                    if !two_sided && wo.z < 0.0 {
                        continue;
                    }
                    let label = format!("{name} n={n:?} two_sided={two_sided} wo={wo:?}");
                    report.push(chi2_sphere(
                        &label,
                        wo,
                        &surface_sampler(s),
                        &|wo, wi| s.pdf(wo, wi),
                        &Chi2Config::default(),
                    ));
                    // Weights: eval |cos| / pdf for every returned sample.
                    let mut rng = pt_testkit::Pcg32::new(9, 2);
                    for _ in 0..2000 {
                        let Some(bs) = s.sample(
                            wo,
                            rng.next_f32(),
                            Vec2::new(rng.next_f32(), rng.next_f32()),
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
