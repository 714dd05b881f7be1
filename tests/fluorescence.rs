//! Fluorescence against closed forms (model: crates/pt-render/src/fluorescence.rs).
//!
//! Both tests trace camera paths with the real integrator (`pt_integrators::path::li`) at
//! fixed wavelengths, so they check the spectrum lane by lane, not only its colour: a lane that
//! forgot to change wavelength, NEE evaluated at the emitted instead of the exciting wavelength,
//! a missing li/lo energy factor (10-20% here), a missing Stokes cut or a wrong quantum yield
//! each move some lane by far more than the tolerance.
//!
//! Tolerance: each lane's mean must lie within 4.5 standard errors (estimated from the samples;
//! four lanes per test, so a false alarm has probability about 3e-5) and the standard error
//! must be below 0.4% of the expected value, so that a 2% bias is at least 5 standard errors
//! and cannot pass. The expected values come from an independent fine quadrature of the
//! continuous model; the renderer tabulates a(l) l on 1 nm bins, a difference below 1e-4
//! relative for these piecewise-linear spectra (well inside the noise).

use pt_integrators::path::{li, PathSettings};
use pt_math::{Ray, Vec3};
use pt_render::sampler::Sampler;
use pt_render::{BvhKind, LightSelection, Scene};
use pt_spectrum::{SampledWavelengths, Spectrum};
use std::path::Path;

/// Elastic reflectance, absorption, emission shape and quantum yield used by both tests.
const REFLECTANCE: &str = "360:0.3, 830:0.2";
const ABSORPTION: &str = "360:0.6, 480:0.6, 500:0, 830:0";
const EMISSION: &str = "440:0, 520:1, 600:0";
const YIELD: f32 = 0.8;

fn material_xml() -> String {
    format!(
        r#"<bsdf type="fluorescent">
            <spectrum name="reflectance" value="{REFLECTANCE}"/>
            <spectrum name="absorption" value="{ABSORPTION}"/>
            <spectrum name="emission" value="{EMISSION}"/>
            <float name="yield" value="{YIELD}"/>
        </bsdf>"#
    )
}

fn spec(s: &str) -> Spectrum {
    Spectrum::parse_mitsuba(s).unwrap()
}

fn build(xml: &str) -> Scene {
    let desc = pt_scene::load_str(xml, Path::new("fluorescence-test.xml"), Path::new("."), &[])
        .expect("scene loads");
    assert!(desc.spectral_reason().unwrap().contains("fluorescence"));
    Scene::build(&desc, BvhKind::default(), LightSelection::Power).expect("scene builds")
}

/// Per-lane mean and standard error of `n` estimates of `li` along `ray` at wavelengths `lam`.
fn estimate(
    scene: &Scene,
    ray: Ray,
    settings: &PathSettings,
    lam: [f32; 4],
    n: u64,
) -> ([f64; 4], [f64; 4]) {
    let w = SampledWavelengths::sample_uniform(0.0).with_lambda(lam.into());
    let (mut s1, mut s2) = ([0.0f64; 4], [0.0f64; 4]);
    for k in 0..n {
        let mut sampler = Sampler::new(7, 0, k);
        let v = li(scene, ray, settings, &mut sampler, &w).0.to_array();
        for i in 0..4 {
            s1[i] += v[i] as f64;
            s2[i] += (v[i] as f64).powi(2);
        }
    }
    let nf = n as f64;
    let mean = s1.map(|s| s / nf);
    let se =
        std::array::from_fn(|i| ((s2[i] / nf - mean[i] * mean[i]).max(0.0) / (nf - 1.0)).sqrt());
    (mean, se)
}

fn check(name: &str, lam: [f32; 4], mean: [f64; 4], se: [f64; 4], expect: [f64; 4]) {
    for i in 0..4 {
        let (m, s, e) = (mean[i], se[i], expect[i]);
        println!(
            "{name}: {} nm: {m:.6} +- {s:.6}, expected {e:.6} (ratio {:.4})",
            lam[i],
            m / e
        );
        assert!(
            s < 4e-3 * e,
            "{name} at {} nm: standard error {s} too large for a 2% test (expected {e})",
            lam[i]
        );
        assert!(
            (m - e).abs() < 4.5 * s,
            "{name} at {} nm: {m} +- {s}, expected {e} (ratio {:.4})",
            lam[i],
            m / e
        );
    }
}

/// `int_{360}^{hi} f(l) dl` by the midpoint rule with 0.01 nm steps.
fn quad(hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let h = 0.01;
    let n = ((hi - 360.0) / h).round() as usize;
    (0..n).map(|i| f(360.0 + (i as f64 + 0.5) * h) * h).sum()
}

/// A fluorescent Lambertian plane lit by a narrow-band directional source (a 430-470 nm
/// triangle, peak 10 W m^-2 nm^-1 at normal incidence), incident at cos = 0.8, seen from
/// above with direct light only. Exact outgoing spectrum:
/// L(lo) = cos / pi [ r(lo) E(lo) + Q e(lo) / lo int_{li < lo} a(li) E(li) li dli ]
/// with e normalised to unit area. Lanes: 455 nm (elastic plus fluorescence excited only by
/// the part of the band below 455 nm: the Stokes cut), 465 nm, 520 nm and 580 nm (pure
/// fluorescence).
#[test]
fn fluorescent_plane_under_a_narrow_band_source() {
    let xml = format!(
        r#"<scene version="3.0.0">
        <shape type="rectangle">
            <transform name="to_world"><scale value="10, 10, 1"/></transform>
            {}
        </shape>
        <emitter type="directional">
            <vector name="direction" x="0.6" y="0" z="-0.8"/>
            <spectrum name="irradiance" value="430:0, 450:10, 470:0"/>
        </emitter>
        </scene>"#,
        material_xml()
    );
    let scene = build(&xml);
    let settings = PathSettings {
        max_depth: 2,
        ..PathSettings::default()
    };
    let ray = Ray::new(Vec3::new(0.1, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let lam = [455.0f32, 465.0, 520.0, 580.0];
    let (mean, se) = estimate(&scene, ray, &settings, lam, 1_200_000);

    let (r, a, e, band) = (
        spec(REFLECTANCE),
        spec(ABSORPTION),
        spec(EMISSION),
        spec("430:0, 450:10, 470:0"),
    );
    let e_area = quad(830.0, |l| e.eval(l as f32) as f64);
    let cos = 0.8;
    let expect = lam.map(|lo| {
        let lo64 = lo as f64;
        let excite = quad(lo64, |l| {
            a.eval(l as f32) as f64 * band.eval(l as f32) as f64 * l
        });
        cos / std::f64::consts::PI
            * (r.eval(lo) as f64 * band.eval(lo) as f64
                + YIELD as f64 * e.eval(lo) as f64 / e_area / lo64 * excite)
    });
    check("plane", lam, mean, se, expect);
}

/// A closed fluorescent furnace: the inside of a sphere whose surface is the fluorescent
/// material and also emits Le = 0.5 W m^-2 sr^-1 nm^-1 at every wavelength. Radiance is then
/// uniform and solves L = Le + M L, M = r(lo) delta + Q e(lo) a(li) li / lo [li < lo]. Binned at
/// h = 0.05 nm, M is lower-triangular (Stokes: light only moves to longer wavelengths), so
/// L = (I - M)^-1 Le is solved by forward substitution. Unlimited depth with Russian roulette.
#[test]
fn closed_fluorescent_furnace() {
    let xml = format!(
        r#"<scene version="3.0.0">
        <shape type="sphere">
            <float name="radius" value="1"/>
            <boolean name="flip_normals" value="true"/>
            {}
            <emitter type="area"><spectrum name="radiance" value="360:0.5, 830:0.5"/></emitter>
        </shape>
        </scene>"#,
        material_xml()
    );
    let scene = build(&xml);
    let settings = PathSettings::default();
    let ray = Ray::new(
        Vec3::new(0.05, -0.1, 0.02),
        Vec3::new(0.3, 0.4, -0.866).normalize(),
    );
    let lam = [430.0f32, 470.0, 520.0, 560.0];
    let (mean, se) = estimate(&scene, ray, &settings, lam, 200_000);

    let (r, a, e) = (spec(REFLECTANCE), spec(ABSORPTION), spec(EMISSION));
    let e_area = quad(830.0, |l| e.eval(l as f32) as f64);
    let le = 0.5f64;
    let h = 0.05f64;
    let n = ((600.0 - 360.0) / h) as usize + 1;
    let grid: Vec<f64> = (0..n).map(|j| 360.0 + j as f64 * h).collect();
    // Forward substitution: L_i (1 - r_i) = Le + sum_{j < i} M_ij L_j, with trapezoid weights
    // h (h/2 at the ends) for the integral over li in [360, lo].
    let mut big_l = vec![0.0f64; n];
    let mut g = vec![0.0f64; n]; // a(l) l L(l) at the nodes
    let mut acc = 0.0f64; // h sum_{j < i} g_j
    for i in 0..n {
        let lo = grid[i];
        let emit = YIELD as f64 * e.eval(lo as f32) as f64 / e_area / lo;
        // Trapezoid over [360, lo_i] with g_i (unknown yet) replaced by g_{i-1}: O(h^2).
        let integral = if i == 0 {
            0.0
        } else {
            acc + 0.5 * h * g[i - 1] - 0.5 * h * g[0]
        };
        big_l[i] = (le + emit * integral) / (1.0 - r.eval(lo as f32) as f64);
        g[i] = a.eval(lo as f32) as f64 * lo * big_l[i];
        acc += h * g[i];
    }
    let expect = lam.map(|lo| big_l[((lo as f64 - 360.0) / h).round() as usize]);
    // Without fluorescence the furnace gives Le / (1 - r): the test must see the difference.
    assert!(
        expect[2] > 1.5 * le / (1.0 - r.eval(520.0) as f64),
        "{expect:?}"
    );
    check("furnace", lam, mean, se, expect);
}

/// XYZ (mean, standard error of Y) of the radiance along `ray`, with wavelengths sampled as the
/// film samples them.
fn xyz_along(scene: &Scene, ray: Ray, n: u64) -> ([f64; 3], f64) {
    let settings = PathSettings {
        max_depth: 8,
        ..PathSettings::default()
    };
    let (mut sum, mut sum_y2) = ([0.0f64; 3], 0.0f64);
    for k in 0..n {
        let mut sampler = Sampler::new(11, 1, k);
        let w = SampledWavelengths::sample_visible(sampler.next_1d());
        let xyz = pt_spectrum::spectrum_to_xyz(li(scene, ray, &settings, &mut sampler, &w), &w);
        for c in 0..3 {
            sum[c] += xyz[c] as f64;
        }
        sum_y2 += (xyz[1] as f64).powi(2);
    }
    let nf = n as f64;
    let mean = sum.map(|s| s / nf);
    (
        mean,
        ((sum_y2 / nf - mean[1] * mean[1]).max(0.0) / (nf - 1.0)).sqrt(),
    )
}

/// scenes/fluorescence.xml makes two claims, checked here at the front-top of each sphere:
/// under D65 the fluorescent sphere and its plain twin have the same colour (the twin's
/// reflectance is the paint's effective reflectance under D65 for direct light; interreflected
/// light differs only slightly, so 2% in X, Y, Z plus 4 standard errors); under the blue lamp
/// the paint is several times brighter than the twin (it re-emits green, the twin only reflects
/// the little blue its reflectance of 0.06 allows) and greener (y chromaticity).
#[test]
fn fluorescence_scene_twins_match_in_daylight_only() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/fluorescence.xml");
    let load = |defaults: &[(&str, &str)]| {
        let d: Vec<(String, String)> = defaults
            .iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect();
        let desc = pt_scene::load_file(&path, &d).expect("scene loads");
        Scene::build(&desc, BvhKind::default(), LightSelection::Power).expect("scene builds")
    };
    let eye = Vec3::new(0.0, 0.9, 3.2);
    let ray_to = |x: f32| Ray::new(eye, (Vec3::new(x, 0.6, 0.3) - eye).normalize());
    let n = 60_000;

    let day = load(&[("daylight", "30"), ("blue", "0")]);
    let (paint, se_p) = xyz_along(&day, ray_to(-0.55), n);
    let (twin, se_t) = xyz_along(&day, ray_to(0.55), n);
    println!("daylight: paint XYZ {paint:?} (se Y {se_p:.2e}), twin {twin:?} (se Y {se_t:.2e})");
    let se_rel = (se_p / paint[1]).hypot(se_t / twin[1]);
    assert!(se_rel < 5e-3, "too noisy: {se_rel}");
    for c in 0..3 {
        let r = paint[c] / twin[c];
        assert!(
            (r - 1.0).abs() < 0.02 + 4.0 * se_rel,
            "channel {c}: paint / twin = {r}"
        );
    }

    let blue = load(&[]);
    let (paint, _) = xyz_along(&blue, ray_to(-0.55), n);
    let (twin, _) = xyz_along(&blue, ray_to(0.55), n);
    println!("blue lamp: paint XYZ {paint:?}, twin {twin:?}");
    assert!(
        paint[1] > 5.0 * twin[1],
        "paint Y {} vs twin Y {}",
        paint[1],
        twin[1]
    );
    let y_chroma = |v: [f64; 3]| v[1] / (v[0] + v[1] + v[2]);
    assert!(
        y_chroma(paint) > y_chroma(twin) + 0.2,
        "paint y {} twin y {}",
        y_chroma(paint),
        y_chroma(twin)
    );
}

/// Fluorescence in every integrator, on scenes/fluorescence.xml under its blue lamp (the
/// paint's green glow is all re-emitted light) at 64 x 40 pixels: each integrator's image
/// agrees with the path tracer's, whose fluorescence the closed-form tests above check lane
/// by lane. The light tracer traces fluorescence on light paths (the adjoint rule); bdpt, vcm,
/// sppm and the photon mapper leave the paths through a fluorescent surface to their camera
/// side (`pt_integrators::path::li_through_fluorescence`).
///
/// Two judges, both on the statistics of the two renders: the fluorescent sphere's region
/// (pixels 8..26 x 8..26), each channel's mean within 4.5 standard errors of the difference
/// (green's is 0.7-1.9% of its mean at these sample counts), and the block z-test over the
/// whole image (8-pixel blocks, the suite's ALPHA). The biased methods need no allowance
/// here: their kernels' blur on this smooth glow is below the noise (measured: vcm +0.07%,
/// sppm +0.22%, photon mapper +1.5% in green, |z| < 1). Measured mutations: bdpt or vcm
/// carrying light subpaths on through the paint at other wavelengths gives +18-22% green
/// (z > 24); sppm counting paths through the paint only where its visible point lies on the
/// paint (the floor's reflection of the glow lost) fails 36 of 120 blocks (max |z| 25);
/// dropping the camera side's fluorescent paths loses the whole glow (z < -300); a light
/// tracer's path that keeps its wavelength at the paint (the adjoint albedo without the move)
/// fails most blocks.
#[test]
fn every_integrator_traces_fluorescence() {
    use crate::common::*;
    let scene = repo().join("scenes/fluorescence.xml");
    let dir = scratch("fluorescence_integrators");
    let size = ["-D", "width=64", "-D", "height=40"];
    let args =
        |more: &[&'static str]| -> Vec<&'static str> { size.iter().chain(more).copied().collect() };
    let (camera, cvar) = render(
        &scene,
        &dir,
        "path",
        &args(&["--spp", "2048", "--seed", "9"]),
    );
    let region = |img: &pt_image::Image, c: usize| -> f64 {
        let mut sum = 0.0;
        for y in 8..26 {
            for x in 8..26 {
                sum += f64::from(img.data[y * img.width as usize + x][c]);
            }
        }
        sum / (18.0 * 18.0)
    };
    let mut failed = Vec::new();
    for (name, spp) in [
        ("ptracer", "1024"),
        ("bdpt", "512"),
        ("vcm", "512"),
        ("sppm", "512"),
        ("photonmapper", "64"),
    ] {
        let (img, var) = render(
            &scene,
            &dir,
            name,
            &args(&["--integrator", name, "--spp", spp]),
        );
        for c in 0..3 {
            let (m, mc) = (region(&img, c), region(&camera, c));
            let se = ((region(&var, c) + region(&cvar, c)) / (18.0 * 18.0)).sqrt();
            eprintln!(
                "{name} channel {c}: {m:.5} vs path {mc:.5} ({:+.2}%), se {:.2}%, z {:.2}",
                100.0 * (m / mc - 1.0),
                100.0 * se / mc.abs(),
                (m - mc) / se
            );
            if (m - mc).abs() >= 4.5 * se {
                failed.push(format!("{name} channel {c}: {m} vs {mc} (se {se})"));
            }
        }
        let z = pt_stats::block_ztest(&img, &var, &camera, &cvar, 8, ALPHA).unwrap();
        eprintln!(
            "{name}: {} of {} blocks fail, max |z| {:.2}",
            z.failed, z.tests, z.max_abs_z
        );
        if z.failed > 0 {
            failed.push(format!("{name}: {} of {} blocks fail", z.failed, z.tests));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}
