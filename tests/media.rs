//! Transparency against closed forms: Beer-Lambert absorption inside glass, and opacity masks.
//!
//! 1. A glass slab (ior 1.5 in vacuum, thickness d, filled with a purely absorbing medium of
//!    extinction sigma) under a constant environment of radiance 1, seen along its normal through
//!    a 2-degree field of view. Along the normal every path stays on one line, so the radiance is
//!    the slab's total reflectance plus total transmittance (the geometric series of internal
//!    reflections, e.g. Born & Wolf ch. 1.6 / any optics text), with R = ((n-1)/(n+1))^2 and the
//!    single-pass transmittance tau = exp(-sigma d):
//!    R_tot = R + (1-R)^2 R tau^2 / (1 - R^2 tau^2),   T_tot = (1-R)^2 tau / (1 - R^2 tau^2).
//!    Off-axis rays (at most 1 degree outside, 0.67 degrees inside the glass) lengthen the path by
//!    under 7e-5 relative: far below the tolerance.
//! 2. `path` ignores the medium (as Mitsuba's does): the same slab gives exactly R_tot + T_tot at
//!    tau = 1, which is 1.
//! 3. A mask of opacity a over a two-sided diffuse plane of albedo rho, under the same
//!    environment: L = a rho + (1 - a) (the null lobe lets the environment behind through).
//!
//! Threshold: the image mean (16x16 pixels, 1024 spp: 262144 paths) must lie within 4.5 of its
//! standard errors (from the variance image) plus 2e-4 (float32 accumulation) of the closed form,
//! and the standard error must be below 0.25% of the value, so that a 2% bias (say, sigma used
//! as exp(-sigma d / 2), a missing internal reflection, a mask weight of a instead of 1) fails.

use crate::common;

use common::*;

const SPP: &str = "1024";

fn slab_scene(integrator: &str, sigma: [f64; 3], d: f64) -> String {
    let sensor = sensor_xml(2.0, [0.0, 0.0, 10.0], 16, 16, 16);
    format!(
        r#"<scene version="3.0.0">
    <integrator type="{integrator}"/>
    {sensor}
    <emitter type="constant"><float name="radiance" value="1"/></emitter>
    <shape type="cube">
        <transform name="to_world"><scale value="5, 5, {half}"/></transform>
        <bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>
        <medium type="homogeneous" name="interior">
            <rgb name="sigma_t" value="{s0}, {s1}, {s2}"/>
            <float name="albedo" value="0"/>
        </medium>
    </shape>
</scene>"#,
        half = d / 2.0,
        s0 = sigma[0],
        s1 = sigma[1],
        s2 = sigma[2]
    )
}

/// Checks the image mean against `want` (see the module doc for the threshold).
fn check_mean(name: &str, xml: &str, want: [f64; 3]) {
    let dir = scratch(&format!("media_{name}"));
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let (img, var) = render(&path, &dir, "out", &["--spp", SPP]);
    let (m, se) = mean_and_stderr(&img, &var);
    for c in 0..3 {
        let z = (m[c] - want[c]).abs() / se[c].max(1e-12);
        eprintln!(
            "{name} channel {c}: got {:.5} want {:.5} (stderr {:.2e}, z {z:.2})",
            m[c], want[c], se[c]
        );
        assert!(
            se[c] < 0.0025 * want[c],
            "{name}: standard error {} too large to detect a 2% bias",
            se[c]
        );
        assert!(
            (m[c] - want[c]).abs() <= 4.5 * se[c] + 2e-4,
            "{name} channel {c}: {} vs closed form {} (z = {z:.1})",
            m[c],
            want[c]
        );
    }
}

/// R_tot + T_tot of an absorbing slab at normal incidence (module doc).
fn slab_radiance(n: f64, tau: f64) -> f64 {
    let r = ((n - 1.0) / (n + 1.0)).powi(2);
    let denom = 1.0 - r * r * tau * tau;
    r + (1.0 - r).powi(2) * r * tau * tau / denom + (1.0 - r).powi(2) * tau / denom
}

#[test]
fn absorbing_slab_matches_beer_lambert_series() {
    let (sigma, d) = ([0.2, 0.5, 1.0], 2.0f64);
    let want = sigma.map(|s| slab_radiance(1.5, (-s * d).exp()));
    check_mean("slab_volpath", &slab_scene("volpath", sigma, d), want);
}

#[test]
fn path_integrator_ignores_media_like_mitsuba() {
    let want = [slab_radiance(1.5, 1.0); 3];
    assert!((want[0] - 1.0).abs() < 1e-12);
    check_mean("slab_path", &slab_scene("path", [0.2, 0.5, 1.0], 2.0), want);
}

#[test]
fn mask_lets_the_background_through_its_holes() {
    let (a, rho) = (0.3, [0.8, 0.5, 0.1]);
    let sensor = sensor_xml(20.0, [0.0, 0.0, 10.0], 16, 16, 16);
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"/>
    {sensor}
    <emitter type="constant"><float name="radiance" value="1"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5, 5, 1"/></transform>
        <bsdf type="mask"><float name="opacity" value="{a}"/>
            <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="{}, {}, {}"/></bsdf></bsdf>
        </bsdf>
    </shape>
</scene>"#,
        rho[0], rho[1], rho[2]
    );
    check_mean("mask", &xml, rho.map(|r| a * r + (1.0 - a)));
}
