//! Rough thin film (`rough_thin_film.rs`): chi-square of sampling against the pdf (conductor and
//! dielectric bases, GGX and Beckmann, spectral lanes and the RGB mode, viewer outside and
//! inside), energy (albedo <= 1 counting transmitted energy), the zero-thickness limit (the bare
//! rough conductor / rough dielectric, to f32 rounding), and robustness.

use crate::common;
use common::*;
use pt_bsdf::{
    Bsdf, Distribution, FilmBase, Microfacet, RoughConductor, RoughDielectric, RoughThinFilm,
    ThinFilm,
};
use pt_math::{Vec2, Vec3, Vec4};
use pt_spectrum::SampledSpectrum;
use pt_testkit::{albedo_mc, dir_deg, Chi2Report, Sample};

const LANES: Vec4 = Vec4::new(420.0, 510.0, 600.0, 730.0);

fn conductor(eta: f32, k: f32) -> FilmBase {
    FilmBase::Conductor {
        eta: SampledSpectrum::splat(eta),
        k: SampledSpectrum::splat(k),
    }
}

fn rough(d: f32, base: FilmBase, dist: Distribution, alpha: f32, rgb: bool) -> Bsdf {
    let film = if rgb {
        ThinFilm::rgb(d, 1.33, 1.0, base)
    } else {
        ThinFilm::spectral(d, 1.33, 1.0, base, LANES)
    };
    Bsdf::RoughThinFilm(RoughThinFilm::new(
        film,
        Microfacet::new(dist, alpha, alpha),
    ))
}

fn grid() -> Vec<(String, Bsdf)> {
    let mut v = Vec::new();
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        for alpha in [0.1f32, 0.5] {
            for (bname, base) in [
                ("conductor", conductor(0.3, 2.6)),
                ("glass", FilmBase::Dielectric { ior: 1.5 }),
            ] {
                for rgb in [false, true] {
                    v.push((
                        format!("roughthinfilm {dist:?} alpha={alpha} {bname} rgb={rgb}"),
                        rough(400.0, base, dist, alpha, rgb),
                    ));
                }
            }
        }
    }
    v
}

#[test]
fn chi2_rough_thin_film() {
    let mut rep = Chi2Report::default();
    // The RGB mode samples with the same code as the spectral one (only the lane values
    // differ), so one RGB case per base is enough; this keeps the test near 30 s.
    for (name, b) in grid()
        .into_iter()
        .filter(|(n, _)| !n.contains("rgb=true") || n.contains("Ggx alpha=0.5"))
    {
        let glass = name.contains("glass");
        for th in [0.0, 60.0, 89.0, 130.0] {
            if th > 90.0 && !glass {
                continue; // a conductor base is one-sided
            }
            // phi 35 as in specular.rs. (At theta 89, phi 25 the Beckmann alpha 0.5 case gives
            // p = 1.6e-5 with 200k samples and 0.05 with 1M, for the plain rough conductor too:
            // the Beckmann sampler near grazing, not this model; see the issue notes.)
            rep.push(chi2(&format!("{name} theta_o={th}"), b, dir_deg(th, 35.0)));
        }
    }
    rep.check(0.01);
}

#[test]
fn energy_albedo_at_most_one() {
    // Every lane: E[weight], transmitted samples times eta'^2 (energy, not radiance), <= 1
    // within 5 standard errors. The film absorbs nothing, so with a dielectric base the loss
    // is only the single-scattering microfacet loss.
    for (name, b) in grid() {
        for lane in 0..3 {
            for th in [0.0, 50.0, 85.0, 140.0] {
                let wo = dir_deg(th, 10.0);
                let s = move |wo: Vec3, u: Vec3| {
                    b.sample(wo, u.x, Vec2::new(u.y, u.z)).map(|s| Sample {
                        wi: s.wi,
                        weight: s.weight.0.to_array()[lane]
                            * if s.wi.z * wo.z < 0.0 {
                                s.eta * s.eta
                            } else {
                                1.0
                            },
                        pdf: s.pdf,
                        delta: s.delta,
                    })
                };
                let (e, se) = albedo_mc(wo, &s, 20_000, 7);
                assert!(
                    e <= 1.0 + 5.0 * se + 1e-6,
                    "{name} lane {lane} theta={th}: energy albedo {e} +- {se}"
                );
            }
        }
    }
}

#[test]
fn zero_thickness_is_the_bare_rough_base() {
    // d = 0: the Airy sum is the bare interface's Fresnel amplitude, so eval and pdf equal the
    // rough conductor / rough dielectric up to f32 rounding. The film's transmission is
    // 1 - R(wo.h) from one cosine while the bare model evaluates it from both cosines of the
    // refraction pair, which in f32 are not exactly Snell-consistent; near total internal
    // reflection that is amplified (measured: 1.6e-3 relative at wo.z = -0.1). A real
    // difference (a thickness or phase error, the wrong side's index) is wrong almost
    // everywhere, by percents: at most 1% of pairs may exceed 1e-4 relative, none 1e-2.
    let mut rng = pt_testkit::Pcg32::new(5, 1);
    let (mut over, mut worst, mut n) = (0usize, 0.0f32, 0usize);
    for dist in [Distribution::Ggx, Distribution::Beckmann] {
        let mf = Microfacet::new(dist, 0.3, 0.3);
        let cond = Bsdf::RoughConductor(RoughConductor::new(
            SampledSpectrum::splat(0.3),
            SampledSpectrum::splat(2.6),
            SampledSpectrum::splat(1.0),
            mf,
        ));
        let diel = Bsdf::RoughDielectric(RoughDielectric::new(1.5, mf));
        let (fc, fd) = (
            rough(0.0, conductor(0.3, 2.6), dist, 0.3, false),
            rough(0.0, FilmBase::Dielectric { ior: 1.5 }, dist, 0.3, false),
        );
        for _ in 0..2000 {
            let a =
                pt_math::warp::square_to_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            let c =
                pt_math::warp::square_to_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            for (film, bare) in [(fc, cond), (fd, diel)] {
                for (x, y) in [
                    (film.eval(a, c).0.x, bare.eval(a, c).0.x),
                    (film.pdf(a, c), bare.pdf(a, c)),
                ] {
                    if x.max(y) < 1e-6 {
                        continue;
                    }
                    let e = (x - y).abs() / x.max(y);
                    worst = worst.max(e);
                    over += usize::from(e > 1e-4);
                    n += 1;
                }
            }
        }
    }
    eprintln!("zero thickness: {over} of {n} values over 1e-4 relative, worst {worst:.2e}");
    assert!(
        over * 100 <= n && worst < 1e-2,
        "{over} of {n} values over 1e-4, worst {worst}"
    );
}

#[test]
fn no_nan_for_any_direction() {
    for (name, b) in grid() {
        assert_finite_everywhere(&name, b);
    }
    assert_finite_everywhere(
        "roughthinfilm thick evanescent",
        rough(
            2000.0,
            FilmBase::Dielectric { ior: 1.0 },
            Distribution::Ggx,
            0.001,
            false,
        ),
    );
}
