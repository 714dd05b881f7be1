//! The sweep's own checks: no NaN and no energy gain in the documented ranges, detection of
//! a gain and a NaN, the chi-square wiring, and the grid's scene-format models.

use super::*;
use pt_bsdf::Lambert;
use report::fmt_param;

/// The CI check of the issue: over the whole parameter grid (beyond the documented ranges
/// too) no model produces a NaN or infinity anywhere; within each documented range the
/// white-furnace albedo stays below the model's documented bound (1 for every model except
/// the 1994 Oren-Nayar ones and the RGB thin film) + 1e-3 + 4 standard errors; sample pdfs
/// and weights agree with pdf() and eval(). 4000 samples per probe keep it to a few
/// seconds; an albedo 1% too high is still 10 standard errors away for the smooth models,
/// and exact for the delta ones.
#[test]
fn no_nan_and_no_energy_gain_in_documented_ranges() {
    let cases = cases();
    let rows = sweep(&cases, 4000, 0, &|| {});
    let mut msgs = Vec::new();
    for r in &rows {
        let c = &cases[r.case];
        let what = format!(
            "{} {}={} {} theta={} back={}",
            c.family,
            c.param_name,
            fmt_param(c.param),
            c.detail,
            r.theta_deg,
            r.back
        );
        if r.nonfinite > 0 {
            msgs.push(format!("{what}: {} non-finite values", r.nonfinite));
        }
        if c.in_range && r.albedo > c.energy_bound + ENERGY_TOL + 4.0 * r.albedo_se {
            msgs.push(format!(
                "{what}: albedo {} ± {} above {}",
                r.albedo, r.albedo_se, c.energy_bound
            ));
        }
        if c.in_range && (r.pdf_mismatch > 0 || r.weight_mismatch > 0) {
            msgs.push(format!(
                "{what}: {} pdf and {} weight mismatches",
                r.pdf_mismatch, r.weight_mismatch
            ));
        }
    }
    assert!(
        msgs.is_empty(),
        "{} problems:\n{}",
        msgs.len(),
        msgs.join("\n")
    );
}

/// The checks can fail: a Lambertian model built around the constructor with albedo 1.05
/// is an energy gain, one with a NaN albedo is non-finite, and the sweep sees both.
#[test]
fn sweep_detects_gain_and_nan() {
    let hot = Case {
        family: "test",
        param_name: "reflectance",
        param: 1.05,
        detail: String::new(),
        in_range: true,
        energy_bound: 1.0,
        bsdf: Bsdf::Lambert(Lambert {
            reflectance: SampledSpectrum::splat(1.05),
        }),
        spec: None,
    };
    let nan = Case {
        bsdf: Bsdf::Lambert(Lambert {
            reflectance: SampledSpectrum::splat(f32::NAN),
        }),
        ..hot.clone()
    };
    let rows = sweep(&[hot, nan], 2000, 0, &|| {});
    assert!(
        rows.iter()
            .filter(|r| r.case == 0 && r.theta_deg < 90.0)
            .all(|r| r.energy_gain),
        "albedo 1.05 not flagged"
    );
    assert!(
        rows.iter()
            .filter(|r| r.case == 1 && r.theta_deg < 90.0)
            .all(|r| r.nonfinite > 0),
        "NaN albedo not flagged"
    );
}

/// Control of the chi-square wiring: a correct GGX rough conductor (alpha 0.3, 60 degrees)
/// passes with 100k samples (a correct sampler fails p < 1e-4 one time in 10^4). That the
/// test rejects wrong samplers is pt-stats' own test
/// (`fails_for_slightly_wrong_pdf_and_for_lost_samples`).
#[test]
fn chi2_passes_for_a_correct_rough_conductor() {
    let c = cases()
        .into_iter()
        .find(|c| c.family == "roughconductor-ggx" && c.param == 0.3)
        .unwrap();
    let r = probe(0, &c, 60.0, false, 2000, 100_000);
    assert!(r.chi2_hard.is_none() && r.chi2_p.unwrap() > 1e-4, "{r:?}");
}

/// The grid builds from scene-format parameters wherever the scene format accepts them: every
/// case of the families the scene format has, in range, except Minnaert's k = 0 (the scene
/// format needs k > 0) and microfacet alpha = 0, and the spectral-lane films; none of glTF's.
#[test]
fn in_range_cases_of_scene_format_models_are_built_as_scene_files_build_them() {
    for c in cases() {
        let scene_family = !(c.family.starts_with("gltf")
            || c.detail.contains("spectral")
            || c.family == "thinfilm-spectral");
        let refused = c.param == 0.0 && (c.family == "minnaert" || c.param_name == "alpha");
        if c.in_range && scene_family && !refused {
            assert!(
                c.spec.is_some(),
                "{} {}={} {}",
                c.family,
                c.param_name,
                c.param,
                c.detail
            );
        }
        if c.family == "gltfpbr" || c.family == "thinfilm-spectral" {
            assert!(c.spec.is_none());
        }
    }
}
