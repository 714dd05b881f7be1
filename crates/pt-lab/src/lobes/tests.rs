//! Closed forms and sampling checks of the lobes analysis, and its messages.

use super::*;

fn model(text: &str) -> Model {
    Model::new(&BsdfSpec::parse(text).unwrap()).unwrap()
}

#[test]
fn lambert_polar_curve_is_rho_over_pi_cos() {
    let m = model("diffuse reflectance=0.6");
    for theta_i in [0.0, 30.0, 80.0] {
        for p in lobe(&m, theta_i) {
            let cos = p.angle.to_radians().cos();
            let want = if cos > 0.0 {
                0.6 / std::f64::consts::PI * cos
            } else {
                0.0
            };
            let got = p.f * cos.abs();
            // f32 evaluation and the luminance weights (which sum to 1 up to rounding):
            // a few ulps of f32.
            assert!(
                (got - want).abs() <= 1e-6 * want.max(1e-3),
                "angle {}: {got} vs {want}",
                p.angle
            );
        }
    }
}

#[test]
fn lambert_albedo_is_rho() {
    // Cosine-weighted sampling makes every weight exactly rho (zero variance), so the mean
    // must equal rho up to rounding; the bound is 4 standard errors (false alarm 6e-5 for a
    // noisy estimator) plus 1e-5 for the f32 arithmetic.
    let m = model("diffuse reflectance=0.7");
    for t in [0.0, 45.0, 89.9] {
        let a = albedo(&m, t, 20_000, 7);
        assert!(
            (a.mean - 0.7).abs() <= 4.0 * a.stderr + 1e-5,
            "theta_i {t}: {a:?}"
        );
    }
}

#[test]
fn sampling_matches_pdf_for_a_rough_conductor() {
    let m = model("roughconductor alpha=0.3 distribution=ggx");
    let h = histogram(&m, 30.0, 200_000, 3, 90.0);
    let (sum_e, sum_o): (f64, f64) = (h.expected.iter().sum(), h.observed.iter().sum());
    assert!(
        (sum_e - sum_o).abs() < 0.01,
        "pdf mass {sum_e} vs sampled {sum_o}"
    );
    // chi^2/dof ~ 1 +- sqrt(2/dof); 2 is far outside chance for ~40 bins.
    assert!(
        h.chi2 / (h.dof as f64) < 2.0,
        "chi2/dof {}",
        h.chi2 / h.dof as f64
    );
}

#[test]
fn parse_errors_are_clear() {
    let err = |t: &str| {
        BsdfSpec::parse(t)
            .map_err(LabError::from)
            .and_then(|s| Model::new(&s).map(|_| ()))
            .unwrap_err()
            .to_string()
    };
    assert!(err("velvet").contains("unknown model 'velvet'"));
    assert!(err("orennayar foo=1").contains("unknown parameter 'foo'"));
    assert!(err("orennayar sigma").contains("expected NAME=VALUE"));
    assert!(err("orennayar sigma=-1").contains("sigma"));
    assert!(err("orennayar variant=bogus").contains("unknown Oren-Nayar variant"));
    assert!(err("diffuse reflectance=2")
        .contains("reflectance must be one number or r,g,b, each in [0, 1]"));
    assert!(err("minnaert k=0").contains("k must be positive"));
    assert!(err("roughconductor material=unobtainium").contains("unknown conductor"));
    assert!(err("dielectric eta=1.5 int_ior=1.3").contains("either eta or int_ior"));
    assert!(err("").contains("empty"));
}

#[test]
fn dielectric_eta_shorthand_and_delta_flag() {
    let m = model("dielectric eta=1.5");
    assert!(m.delta && m.transmissive);
    // Normal incidence: R = ((1.5 - 1) / 2.5)^2 = 0.04, T weight (1 - R) / eta^2.
    let a = albedo(&m, 0.0, 50_000, 1);
    let want = 0.04 + 0.96 / 2.25;
    assert!(
        (a.mean - want).abs() < 4.0 * a.stderr + 1e-4,
        "{a:?} vs {want}"
    );
}

#[test]
fn figure_draws_without_system_fonts() {
    let settings = LobesSettings {
        models: ["roughdielectric alpha=0.3", "diffuse"]
            .iter()
            .map(|t| BsdfSpec::parse(t).unwrap())
            .collect(),
        theta_i: vec![0.0, 60.0],
        albedo_samples: 200,
        hist_samples: 2000,
        seed: 1,
        normalize: true,
    };
    let d = compute(&settings).unwrap();
    assert!(d.png().unwrap().starts_with(b"\x89PNG"));
    assert!(d.svg().unwrap().contains("<svg"));
    let csv = d.csv();
    assert!(csv.starts_with("panel,series,theta_i,theta_o,phi,f,pdf,albedo,albedo_stderr,hist\n"));
    assert!(csv.lines().any(|l| l.starts_with("histogram,")));
    assert_eq!(d.sampling_summary().len(), 2);
}

#[test]
fn settings_are_checked() {
    let base = LobesSettings {
        models: vec![BsdfSpec::new("diffuse")],
        ..LobesSettings::default()
    };
    let err = |s: LobesSettings| compute(&s).err().unwrap().to_string();
    assert!(err(LobesSettings {
        theta_i: vec![90.0],
        ..base.clone()
    })
    .contains("theta_i must be in [0, 90)"));
    assert!(err(LobesSettings {
        albedo_samples: 1,
        ..base.clone()
    })
    .contains("albedo_samples"));
    assert!(err(LobesSettings {
        models: vec![],
        ..base
    })
    .contains("no model"));
}
