//! Tests of Mitsuba's `principled` and `principledthin` (`Principled`, `PrincipledThin`): values and pdfs against Mitsuba 3.9.1
//! itself, sampling against the pdf (chi-square), finiteness everywhere, and sample weights
//! against the integral of eval (MC vs quadrature).

use crate::common;
use common::*;
use pt_bsdf::principled::{principled_alphas, r0};
use pt_bsdf::{Bsdf, Distribution, Microfacet, Principled, PrincipledThin};
use pt_spectrum::SampledSpectrum;
use pt_testkit::{albedo_mc, albedo_quadrature, dir_deg, Chi2Report};

/// The parameters a scene gives, with Mitsuba's defaults (`specular` 0.5 unless `eta`).
#[derive(Clone, Copy, Default)]
struct P {
    base: [f32; 3],
    roughness: f32,
    anisotropic: f32,
    metallic: f32,
    spec_trans: f32,
    spec_tint: f32,
    sheen: f32,
    sheen_tint: f32,
    flatness: f32,
    clearcoat: f32,
    clearcoat_gloss: f32,
    eta: Option<f32>,
    specular: Option<f32>,
}

/// The model as the loader and material layer build it (RGB mode).
fn build(p: P) -> Bsdf {
    let base = SampledSpectrum::from_rgb(p.base);
    let eta = p.eta.unwrap_or_else(|| {
        let s = p.specular.unwrap_or(0.5);
        2.0 / (1.0 - (0.08 * s).sqrt()) - 1.0
    });
    let (au, av) = principled_alphas(p.roughness, p.anisotropic);
    Bsdf::Principled(Principled {
        base_color: base,
        luminance: base.luminance_rgb(),
        roughness: p.roughness,
        metallic: p.metallic,
        spec_trans: p.spec_trans,
        spec_tint: p.spec_tint,
        sheen: p.sheen,
        sheen_tint: p.sheen_tint,
        flatness: p.flatness,
        clearcoat: p.clearcoat,
        clearcoat_alpha: 0.1 + (0.001 - 0.1) * p.clearcoat_gloss,
        eta,
        mf: Microfacet::new(Distribution::Ggx, au, av),
        transmissive: p.spec_trans > 0.0,
        rates: [1.0; 3],
    })
}

/// The four configurations of the Mitsuba comparison (see `matches_mitsuba`).
fn mitsuba_configs() -> [P; 4] {
    [
        P {
            base: [0.8, 0.4, 0.2],
            roughness: 0.4,
            ..P::default()
        },
        P {
            base: [0.8, 0.4, 0.2],
            roughness: 0.3,
            metallic: 0.7,
            anisotropic: 0.5,
            ..P::default()
        },
        P {
            base: [0.9, 0.9, 0.9],
            roughness: 0.2,
            spec_trans: 0.8,
            eta: Some(1.4),
            ..P::default()
        },
        P {
            base: [0.3, 0.6, 0.9],
            roughness: 0.6,
            clearcoat: 0.8,
            clearcoat_gloss: 0.5,
            sheen: 0.7,
            sheen_tint: 0.5,
            spec_tint: 0.6,
            flatness: 0.4,
            specular: Some(0.8),
            ..P::default()
        },
    ]
}

/// Mitsuba 3.9.1 `scalar_rgb` (`mi.load_dict({'type': 'principled', ...})`, `eval` and `pdf`
/// with `si.wi` the viewer `wo` here and its `wo` the light `wi` here), read back on
/// 2026-12-02: (config, wo (theta, phi) degrees, wi (theta, phi), eval including |cos wi|,
/// pdf). Back-side and transmission pairs included.
#[rustfmt::skip]
#[allow(clippy::excessive_precision)] // the values as Mitsuba printed them
const MITSUBA: &[MitsubaValue] = &[
    (0, (30.0, 0.0), (40.0, 180.0), [2.8746456e-01, 1.8992607e-01, 1.4115682e-01], 1.1995611e+00),
    (0, (60.0, 10.0), (20.0, 200.0), [2.4801071e-01, 1.2847279e-01, 6.8703830e-02], 2.4751544e-01),
    (0, (10.0, 0.0), (75.0, 90.0), [6.6466570e-02, 3.3498298e-02, 1.7014164e-02], 4.7670282e-02),
    (0, (45.0, 0.0), (45.0, 180.0), [3.9806157e-01, 3.0806875e-01, 2.6307234e-01], 2.2966871e+00),
    (0, (70.0, 0.0), (130.0, 180.0), [0.0, 0.0, 0.0], 0.0),
    (0, (150.0, 0.0), (40.0, 180.0), [0.0, 0.0, 0.0], 0.0),
    (0, (20.0, 0.0), (160.0, 200.0), [0.0, 0.0, 0.0], 0.0),
    (1, (30.0, 0.0), (40.0, 180.0), [2.9050834e+00, 1.4849666e+00, 7.7490860e-01], 3.8879297e+00),
    (1, (60.0, 10.0), (20.0, 200.0), [2.0534408e-01, 1.0432508e-01, 5.3815566e-02], 2.4859603e-01),
    (1, (10.0, 0.0), (75.0, 90.0), [2.0007856e-02, 1.0013171e-02, 5.0158286e-03], 2.0076895e-02),
    (1, (45.0, 0.0), (45.0, 180.0), [7.9897552e+00, 4.1092219e+00, 2.1689556e+00], 1.0700396e+01),
    (2, (30.0, 0.0), (40.0, 180.0), [9.6770518e-02, 9.6770518e-02, 9.6770518e-02], 3.6638319e-01),
    (2, (60.0, 10.0), (20.0, 200.0), [5.3954426e-02, 5.3954426e-02, 5.3954426e-02], 5.3084210e-02),
    (2, (10.0, 0.0), (75.0, 90.0), [1.4030512e-02, 1.4030512e-02, 1.4030512e-02], 1.3894616e-02),
    (2, (45.0, 0.0), (45.0, 180.0), [2.6112378e+00, 2.6112378e+00, 2.6112378e+00], 1.3470234e+01),
    (2, (70.0, 0.0), (130.0, 180.0), [4.6856782e-01, 4.6856782e-01, 4.6856782e-01], 8.0718410e-01),
    (2, (150.0, 0.0), (40.0, 180.0), [1.0340463e+01, 1.0340463e+01, 1.0340463e+01], 6.9533629e+00),
    (2, (20.0, 0.0), (160.0, 200.0), [4.2390715e-02, 4.2390715e-02, 4.2390715e-02], 7.2987311e-02),
    (3, (30.0, 0.0), (40.0, 180.0), [1.2788562e-01, 2.0704938e-01, 2.8621313e-01], 5.4461282e-01),
    (3, (60.0, 10.0), (20.0, 200.0), [1.0559036e-01, 1.9797207e-01, 2.9035380e-01], 3.0473077e-01),
    (3, (10.0, 0.0), (75.0, 90.0), [2.7141789e-02, 5.2992817e-02, 7.8843839e-02], 6.2678143e-02),
    (3, (45.0, 0.0), (45.0, 180.0), [2.2806971e-01, 3.0956075e-01, 3.9105174e-01], 1.1550560e+00),
    (3, (70.0, 0.0), (130.0, 180.0), [0.0, 0.0, 0.0], 0.0),
];

/// eval (times |cos wi|) and pdf equal Mitsuba 3.9.1's to 1e-4 relative (float rounding of
/// the two implementations, measured below 2e-5): every lobe (diffuse with retro-reflection
/// and flatness, sheen and its tint, clearcoat, tinted and metallic specular, anisotropy, rough
/// transmission from both sides) and each side's lobe probabilities.
#[test]
fn matches_mitsuba() {
    check_against_mitsuba("principled", &mitsuba_configs().map(build), MITSUBA);
}

/// A grid over the lobes: each alone and mixed, isotropic and anisotropic, transmissive.
fn models() -> Vec<(String, Bsdf)> {
    let mut v: Vec<(String, Bsdf)> = mitsuba_configs()
        .into_iter()
        .enumerate()
        .map(|(k, p)| (format!("mitsuba config {k}"), build(p)))
        .collect();
    let base = P {
        base: [0.7, 0.7, 0.7],
        roughness: 0.5,
        ..P::default()
    };
    v.push((
        "clearcoat alone".into(),
        build(P {
            base: [0.0; 3],
            metallic: 1.0,
            clearcoat: 1.0,
            clearcoat_gloss: 0.3,
            eta: Some(1.0),
            ..base
        }),
    ));
    v.push((
        "rough glass".into(),
        build(P {
            spec_trans: 1.0,
            roughness: 0.6,
            ..base
        }),
    ));
    v.push((
        "smooth metal".into(),
        build(P {
            metallic: 1.0,
            roughness: 0.1,
            ..base
        }),
    ));
    v
}

/// The sampler draws exactly the mixture `pdf` returns (chi-square over the sphere, Sidak
/// level 0.01 over the grid, fixed seed): a wrong lobe probability, a missing Jacobian or a
/// GTR1 sampler that does not draw its density fails it.
#[test]
fn chi2_sampling_matches_pdf() {
    let mut rep = Chi2Report::default();
    for (name, b) in models() {
        let transmissive = b.is_transmissive();
        for th in [10.0, 50.0, 80.0] {
            rep.push(chi2(&format!("{name} theta_o={th}"), b, dir_deg(th, 20.0)));
            if transmissive {
                rep.push(chi2(
                    &format!("{name} inside theta_o={th}"),
                    b,
                    dir_deg(180.0 - th, 20.0),
                ));
            }
        }
    }
    rep.check(0.01);
}

#[test]
fn no_nan_for_any_direction() {
    for (name, b) in models() {
        assert_finite_everywhere(&name, b);
    }
}

/// Sample weights integrate to the quadrature of f |cos| (`sample` consistent with `eval`):
/// MC over 20k samples within 5 standard errors plus 3e-3 (the quadrature's tolerance), for
/// the reflective configurations (the quadrature covers the upper hemisphere).
#[test]
fn sample_weights_match_eval() {
    for (name, b) in models() {
        if b.is_transmissive() {
            continue;
        }
        for th in [0.0, 45.0, 80.0] {
            let wo = dir_deg(th, 0.0);
            let (mc, se) = albedo_mc(wo, &sampler(b), 20_000, 9);
            let q = albedo_quadrature(wo, &eval_fn(b), 1e-7);
            assert!(
                (mc - q).abs() <= 5.0 * se + 3e-3,
                "{name} theta={th}: MC {mc} +- {se} vs quadrature {q}"
            );
        }
    }
}

/// The derived index: `specular` 0.5 is eta 1.5 (R0 = 0.04 = 0.08 specular).
#[test]
fn specular_half_is_eta_one_and_a_half() {
    let eta = 2.0 / (1.0 - (0.08f32 * 0.5).sqrt()) - 1.0;
    assert!((eta - 1.5).abs() < 1e-6 && (r0(eta) - 0.04).abs() < 1e-7);
}

/// `principledthin` built as the loader and material layer build it (RGB mode).
#[allow(clippy::too_many_arguments)]
fn thin(
    base: [f32; 3],
    roughness: f32,
    anisotropic: f32,
    spec_trans: f32,
    spec_tint: f32,
    (sheen, sheen_tint): (f32, f32),
    flatness: f32,
    diff_trans: f32,
    eta: f32,
) -> Bsdf {
    let base_color = SampledSpectrum::from_rgb(base);
    let mf = |r: f32| Principled::microfacet(r, anisotropic);
    Bsdf::PrincipledThin(PrincipledThin {
        base_color,
        luminance: base_color.luminance_rgb(),
        roughness,
        spec_trans,
        spec_tint,
        sheen,
        sheen_tint,
        flatness,
        diff_trans: 0.5 * diff_trans,
        eta,
        mf_r: mf(roughness),
        mf_t: mf((0.65 * eta - 0.35) * roughness),
        rates: [1.0; 4],
    })
}

/// The three `principledthin` configurations of [`MITSUBA_THIN`].
fn thin_configs() -> [Bsdf; 3] {
    [
        thin(
            [0.8, 0.4, 0.2],
            0.4,
            0.0,
            0.0,
            0.0,
            (0.0, 0.0),
            0.0,
            0.0,
            1.5,
        ),
        thin(
            [0.8, 0.4, 0.2],
            0.3,
            0.5,
            0.7,
            0.4,
            (0.0, 0.0),
            0.0,
            0.0,
            1.3,
        ),
        thin(
            [0.3, 0.6, 0.9],
            0.6,
            0.0,
            0.3,
            0.0,
            (0.7, 0.5),
            0.4,
            1.2,
            1.5,
        ),
    ]
}

/// Mitsuba 3.9.1 `scalar_rgb` `principledthin` values, read back as for [`MITSUBA`] on
/// 2026-12-02 (both sides, reflection and transmission pairs).
#[rustfmt::skip]
#[allow(clippy::excessive_precision)] // the values as Mitsuba printed them
const MITSUBA_THIN: &[MitsubaValue] = &[
    (0, (30.0, 0.0), (40.0, 180.0), [1.9507697e-01, 9.7538486e-02, 4.8769243e-02], 2.4383950e-01),
    (0, (60.0, 10.0), (20.0, 200.0), [2.3907584e-01, 1.1953792e-01, 5.9768960e-02], 2.9911345e-01),
    (0, (10.0, 0.0), (75.0, 90.0), [6.5936543e-02, 3.2968272e-02, 1.6484136e-02], 8.2384653e-02),
    (0, (45.0, 0.0), (135.0, 180.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    (0, (70.0, 0.0), (130.0, 180.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    (0, (150.0, 0.0), (40.0, 180.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    (0, (150.0, 0.0), (140.0, 200.0), [1.9507809e-01, 9.7539045e-02, 4.8769522e-02], 2.4383950e-01),
    (0, (20.0, 0.0), (160.0, 200.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    (1, (30.0, 0.0), (40.0, 180.0), [1.3855621e-01, 8.9186028e-02, 6.4500935e-02], 1.8165567e+00),
    (1, (60.0, 10.0), (20.0, 200.0), [7.5416274e-02, 3.8742978e-02, 2.0406326e-02], 1.7143831e-01),
    (1, (10.0, 0.0), (75.0, 90.0), [1.9248480e-02, 9.6299713e-03, 4.8207175e-03], 2.5199996e-02),
    (1, (45.0, 0.0), (135.0, 180.0), [1.2645237e+02, 6.3226185e+01, 3.1613092e+01], 8.0978836e+01),
    (1, (70.0, 0.0), (130.0, 180.0), [2.0576757e-01, 1.0288379e-01, 5.1441893e-02], 1.3590220e-01),
    (1, (150.0, 0.0), (40.0, 180.0), [1.1300123e+00, 5.6500614e-01, 2.8250307e-01], 7.2001338e-01),
    (1, (150.0, 0.0), (140.0, 200.0), [6.5138727e-02, 3.4208801e-02, 1.8743837e-02], 2.1798617e-01),
    (1, (20.0, 0.0), (160.0, 200.0), [3.9591074e-01, 1.9795537e-01, 9.8977685e-02], 2.5177240e-01),
    (2, (30.0, 0.0), (40.0, 180.0), [2.6613481e-02, 4.5188088e-02, 6.3762702e-02], 1.6353516e-01),
    (2, (60.0, 10.0), (20.0, 200.0), [2.8646838e-02, 5.2529871e-02, 7.6412894e-02], 1.3547109e-01),
    (2, (10.0, 0.0), (75.0, 90.0), [7.5212098e-03, 1.4549159e-02, 2.1577103e-02], 3.0368237e-02),
    (2, (45.0, 0.0), (135.0, 180.0), [5.1005691e-01, 1.0201138e+00, 1.5301707e+00], 9.4398755e-01),
    (2, (70.0, 0.0), (130.0, 180.0), [1.7433199e-01, 3.4866399e-01, 5.2299595e-01], 3.5965958e-01),
    (2, (150.0, 0.0), (40.0, 180.0), [2.4084854e-01, 4.8169708e-01, 7.2254556e-01], 4.6964777e-01),
    (2, (150.0, 0.0), (140.0, 200.0), [2.5299976e-02, 4.3873504e-02, 6.2447034e-02], 1.4841169e-01),
    (2, (20.0, 0.0), (160.0, 200.0), [2.9541960e-01, 5.9083921e-01, 8.8625884e-01], 5.7348686e-01),
];

/// `principledthin`'s eval (times |cos wi|) and pdf equal Mitsuba 3.9.1's to 1e-4 relative:
/// specular reflection with tint, the thin transmission with its scaled roughness, diffuse
/// reflection and transmission, sheen and flatness, from both sides.
#[test]
fn thin_matches_mitsuba() {
    check_against_mitsuba("principledthin", &thin_configs(), MITSUBA_THIN);
}

/// The thin model's sampler draws its mixture pdf, from both sides (chi-square as for
/// `principled`), and its values are finite everywhere.
#[test]
fn thin_chi2_and_finite() {
    let mut rep = Chi2Report::default();
    for (k, b) in thin_configs().into_iter().enumerate() {
        assert_finite_everywhere(&format!("thin config {k}"), b);
        for th in [10.0, 50.0, 80.0, 130.0] {
            rep.push(chi2(
                &format!("thin config {k} theta_o={th}"),
                b,
                dir_deg(th, 20.0),
            ));
        }
    }
    rep.check(0.01);
}
