//! Analytic scenes, in the style of pbrt-v4's integrator tests: scenes whose exact radiance is
//! known, rendered through the `pt` binary and checked with statistics that fail on bias.
//!
//! The main one is a closed furnace: the camera sits inside a sphere whose inner surface is
//! Lambertian with albedo rho and emits radiance Le. Every path sees the same surroundings, so the
//! radiance along every ray after at most D segments is the geometric series
//! L_D = Le (1 - rho^D) / (1 - rho), and L = Le / (1 - rho) for unlimited depth. This checks NEE,
//! MIS weights, the light pdf's measure conversion, Russian roulette and Mitsuba's depth semantics
//! at once: a missing bounce changes L_D by Le rho^(D-1), a wrong pdf or MIS weight by a constant
//! factor.

use crate::common;

use common::*;

/// Furnace scene: camera at the centre of a unit sphere with inward normals.
fn furnace_xml(albedo: &str, radiance: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <default name="max_depth" value="-1"/>
    <default name="hide" value="false"/>
    <integrator type="path">
        <integer name="max_depth" value="$max_depth"/>
        <boolean name="hide_emitters" value="$hide"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="60"/>
        <transform name="to_world"><lookat origin="0,0,0" target="0.3,0.2,1" up="0,1,0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    </sensor>
    <shape type="sphere">
        <float name="radius" value="1"/>
        <boolean name="flip_normals" value="true"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="{albedo}"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="{radiance}"/></emitter>
    </shape>
</scene>"#
    )
}

/// Per-channel albedo and emission used by the furnace tests (channels differ so that a channel
/// mix-up shows).
const RHO: [f64; 3] = [0.5, 0.8, 0.2];
const LE: [f64; 3] = [1.0, 0.5, 2.0];

fn expected(depth: i32) -> [f64; 3] {
    std::array::from_fn(|c| {
        if depth < 0 {
            LE[c] / (1.0 - RHO[c])
        } else {
            LE[c] * (1.0 - RHO[c].powi(depth)) / (1.0 - RHO[c])
        }
    })
}

/// z-score bound for the furnace means. Each test makes 3 channel comparisons, and the file
/// about 30 in all; a two-sided bound of 4.5 sigma keeps the family-wise false-failure rate
/// below 30 * 6.8e-6 = 2e-4 while a 2% bias is > 10 sigma at these sample counts (the standard
/// error of the image mean is about 0.1% of L here).
const Z_MAX: f64 = 4.5;

/// Systematic floor on the standard error, relative to the exact value. Paths are computed in
/// float32, and secondary rays start a few ULPs off the surface (about 3e-5 at unit scale), which
/// shifts the mean by up to about 1e-5 relative (measured: 1.1e-5 at max_depth 2). Estimators
/// with almost no noise (BSDF sampling in a furnace has zero variance) would otherwise fail on
/// rounding. The floor is three orders of magnitude below the 2% bias the test must catch.
const REL_FLOOR: f64 = 3e-5;

fn check_furnace(name: &str, extra: &[&str], want: [f64; 3]) -> [f64; 3] {
    let dir = scratch(name);
    let scene = dir.join("furnace.xml");
    let rho = RHO.map(|x| x.to_string()).join(", ");
    let le = LE.map(|x| x.to_string()).join(", ");
    std::fs::write(&scene, furnace_xml(&rho, &le)).unwrap();
    let (img, var) = render(&scene, &dir, "out", extra);
    let (mean, se) = mean_and_stderr(&img, &var);
    for c in 0..3 {
        let se_eff = se[c].hypot(REL_FLOOR * want[c].abs());
        let z = (mean[c] - want[c]) / se_eff;
        assert!(
            z.abs() < Z_MAX,
            "{name} channel {c}: mean {} vs exact {} (z = {z:.2}, stderr {:.2e})",
            mean[c],
            want[c],
            se[c]
        );
        // The standard error must be small enough for the test to detect a 2% bias.
        assert!(
            se[c] * Z_MAX < 0.02 * want[c].abs().max(1e-3),
            "{name}: test too noisy to catch 2% bias"
        );
    }
    mean
}

#[test]
fn furnace_unlimited_depth_converges_to_le_over_one_minus_rho() {
    check_furnace("furnace_inf", &[], expected(-1));
}

#[test]
fn furnace_depth_limits_follow_mitsuba_semantics() {
    // max_depth 1: emitters seen directly; noise-free, so exact up to float rounding.
    let dir = scratch("furnace_d1");
    let scene = dir.join("furnace.xml");
    std::fs::write(&scene, furnace_xml("0.5, 0.8, 0.2", "1, 0.5, 2")).unwrap();
    let (img, _) = render(&scene, &dir, "d1", &["--max-depth", "1"]);
    for p in &img.data {
        for c in 0..3 {
            assert!((p[c] as f64 - LE[c]).abs() < 1e-6, "{p:?}");
        }
    }
    // Depths below and above rr_depth (5), so both the plain and the roulette paths are checked.
    for d in [2, 3, 6, 12] {
        check_furnace(
            &format!("furnace_d{d}"),
            &["--max-depth", &d.to_string()],
            expected(d),
        );
    }
}

#[test]
fn furnace_with_each_strategy_has_the_same_mean() {
    // Light sampling only, BSDF sampling only and MIS are three unbiased estimators of one value.
    for s in ["bsdf", "light", "mis"] {
        check_furnace(
            &format!("furnace_{s}"),
            &["--strategy", s, "--max-depth", "4"],
            expected(4),
        );
    }
    // Uniform light selection must agree with power-proportional selection.
    check_furnace(
        "furnace_uniform",
        &["--light-selection", "uniform", "--max-depth", "4"],
        expected(4),
    );
}

#[test]
fn furnace_hide_emitters_removes_only_the_directly_seen_emission() {
    let want: [f64; 3] = std::array::from_fn(|c| expected(-1)[c] - LE[c]);
    check_furnace("furnace_hide", &["-D", "hide=true"], want);
}
