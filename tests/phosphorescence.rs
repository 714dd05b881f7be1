//! Phosphorescence against its closed form (model: crates/pt-integrators/src/afterglow.rs).
//!
//! A phosphorescent plane (a rectangle, two triangles) lit by a narrow-band directional light
//! (a 400-440 nm triangle of peak 10 W m^-2 nm^-1 at normal incidence) at cos = 0.8, nothing
//! else in the scene. After the light goes out, the plane's radiance at wavelength lo and time t
//! is exactly
//!   L(lo, t) = Q e^{-t / tau} e(lo) / (pi lo) * cos * int a(l) E(l) l dl
//! with e normalised to unit area. The first pass estimates the integral per triangle by Monte
//! Carlo over wavelengths (stratified over 1024 samples: error ~1e-4 here) and the afterglow
//! spectrum is tabulated every 2 nm (lanes here lie on nodes), so each lane is compared with a
//! 0.5% tolerance: a missing 1/lo, 1/pi, cos or yield factor, a wrong decay (e^{-t/tau} at
//! t = 3 s, tau = 2 s is 0.22) or a light left on is off by far more.

use pt_integrators::path::{li, PathSettings};
use pt_math::{Ray, Vec3};
use pt_render::sampler::Sampler;
use pt_render::{BvhKind, LightSelection, Scene};
use pt_spectrum::{SampledWavelengths, Spectrum};
use std::path::Path;

const ABSORPTION: &str = "360:0.7, 450:0.7, 470:0, 830:0";
const EMISSION: &str = "480:0, 520:1, 580:0";
const BAND: &str = "400:0, 420:10, 440:0";

fn quad(lo: f64, hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let h = 0.01;
    let n = ((hi - lo) / h).round() as usize;
    (0..n).map(|i| f(lo + (i as f64 + 0.5) * h) * h).sum()
}

#[test]
fn phosphorescent_plane_decays_as_the_closed_form() {
    let xml = format!(
        r#"<scene version="3.0.0">
        <shape type="rectangle">
            <transform name="to_world"><scale value="10, 10, 1"/></transform>
            <bsdf type="phosphorescent">
                <float name="reflectance" value="0.3"/>
                <spectrum name="absorption" value="{ABSORPTION}"/>
                <spectrum name="emission" value="{EMISSION}"/>
                <float name="yield" value="0.5"/>
                <float name="lifetime" value="2"/>
            </bsdf>
        </shape>
        <emitter type="directional">
            <vector name="direction" x="0.6" y="0" z="-0.8"/>
            <spectrum name="irradiance" value="{BAND}"/>
        </emitter>
        </scene>"#
    );
    let desc = pt_scene::load_str(&xml, Path::new("phosphor-test.xml"), Path::new("."), &[])
        .expect("scene loads");
    let (a, e, band) = (
        Spectrum::parse_mitsuba(ABSORPTION).unwrap(),
        Spectrum::parse_mitsuba(EMISSION).unwrap(),
        Spectrum::parse_mitsuba(BAND).unwrap(),
    );
    let phi = 0.8
        * quad(360.0, 830.0, |l| {
            a.eval(l as f32) as f64 * band.eval(l as f32) as f64 * l
        });
    let e_area = quad(360.0, 830.0, |l| e.eval(l as f32) as f64);
    let lam = [500.0f32, 520.0, 540.0, 430.0];
    let ray = Ray::new(Vec3::new(0.3, -0.2, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let settings = PathSettings::default();
    let mut previous: Option<f64> = None;
    for t in [0.0f32, 3.0] {
        let glow = pt_integrators::afterglow::afterglow(&desc, t, 5).expect("afterglow scene");
        assert!(glow.lights.is_empty());
        let scene = Scene::build(&glow, BvhKind::default(), LightSelection::Power).expect("builds");
        let w = SampledWavelengths::sample_uniform(0.0).with_lambda(lam.into());
        let v = li(&scene, ray, &settings, &mut Sampler::new(1, 0, 0), &w)
            .0
            .to_array();
        for i in 0..4 {
            let lo = lam[i] as f64;
            let expect = 0.5 * (-(t as f64) / 2.0).exp() * e.eval(lam[i]) as f64
                / e_area
                / (std::f64::consts::PI * lo)
                * phi;
            println!("t = {t} s, {lo} nm: {} (expected {expect})", v[i]);
            if expect == 0.0 {
                // 430 nm: outside the emission band; the light is off, so nothing at all.
                assert_eq!(v[i], 0.0, "{lo} nm");
            } else {
                assert!(
                    (v[i] as f64 / expect - 1.0).abs() < 5e-3,
                    "t = {t} s, {lo} nm: {} vs {expect}",
                    v[i]
                );
            }
        }
        if let Some(p) = previous {
            let r = v[1] as f64 / p;
            assert!(
                (r - (-1.5f64).exp()).abs() < 1e-4,
                "decay over 3 s with tau 2 s: {r}"
            );
        }
        previous = Some(v[1] as f64);
    }
    // A scene without a phosphor has no afterglow to show: a clear error, not a black image.
    let plain = pt_scene::load_str(
        r#"<scene version="3.0.0"><shape type="rectangle"/></scene>"#,
        Path::new("x.xml"),
        Path::new("."),
        &[],
    )
    .unwrap();
    let e = pt_integrators::afterglow::afterglow(&plain, 1.0, 5).expect_err("error");
    assert!(e.message.contains("phosphorescent"), "{e}");
    assert!(pt_integrators::afterglow::afterglow(&desc, -1.0, 5).is_err());
}
