//! The model against Mitsuba 3.9.1's `sunsky` (values written by
//! references/make_sunsky_tables.py): six parameter sets (turbidity 1 to 10, albedo 0 to 1,
//! the uniform and the limb-darkened sun, apertures 0.5358 to 3 degrees, scales), 40
//! directions each (random ones, the sun's centre, its limb, its surroundings out to 20
//! degrees, grazing and zenith), RGB and 9 wavelengths.

use super::*;
use serde_json::Value;

const CHECKS: &str = include_str!("../testdata/mitsuba_sunsky.json");

fn f(v: &Value) -> f32 {
    v.as_f64().expect("number") as f32
}

fn vec3(v: &Value) -> Vec3 {
    Vec3::new(f(&v[0]), f(&v[1]), f(&v[2]))
}

fn params(p: &Value) -> (SkyParams, f32) {
    let get = |k: &str, default: f32| p.get(k).map_or(default, f);
    (
        SkyParams {
            turbidity: get("turbidity", 3.0),
            sun_dir: vec3(&p["sun_direction"]),
            sun_half_aperture: (0.5 * get("sun_aperture", 0.5358)).to_radians(),
            complex_sun: p
                .get("complex_sun")
                .and_then(Value::as_bool)
                .unwrap_or(false),
            sun_scale: get("sun_scale", 1.0),
            sky_scale: get("sky_scale", 1.0),
        },
        get("albedo", 0.3),
    )
}

/// The largest magnitude in a table of rows of numbers.
fn largest(rows: &Value) -> f32 {
    rows.as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(f))
        .fold(0.0f32, |m, v| m.max(v.abs()))
}

/// Relative difference, with a floor of 1e-6 of the case's largest value so that values that
/// are zero up to rounding compare absolutely.
fn rel(a: f32, b: f32, scale: f32) -> f32 {
    (a - b).abs() / b.abs().max(1e-6 * scale)
}

/// The bound on the relative difference from Mitsuba in direction `d`: 1e-4 (what the issue
/// asks of the sky; the sky and the uniform sun differ by a few 1e-6, f32 rounding of the
/// interpolations), except on the limb-darkened sun's disc: there Mitsuba sums the polynomial
/// (coefficients of alternating sign up to 1e3) in single precision, which puts its value up to
/// 5e-4 from the double-precision sum pt takes. Measured at turbidity 7.3, blue, 0.2 degrees
/// from the centre: Mitsuba 7090.19, the model in double precision 7090.87, pt 7090.95; red at
/// 0.26 degrees (97% of the radius, where the limb falls steeply): Mitsuba 10276.26, double
/// precision 10281.09, pt 10281.73. Near the rim the value is also steep in gamma: at 97% of
/// the radius cos psi = 0.24 and its relative change is 16 times gamma's, and gamma between two
/// single-precision unit vectors 0.26 degrees apart is itself uncertain by ~1e-5 relative
/// (330 nm there: Mitsuba 236.30, pt 236.58). So 2e-3 on the limb-darkened disc: a wrong
/// coefficient, power or channel is off by far more.
fn tolerance(p: &SkyParams, d: Vec3) -> f32 {
    let on_disc = p.sun_dir.normalize().dot(d) >= p.sun_half_aperture.cos();
    if p.complex_sun && on_disc {
        2e-3
    } else {
        1e-4
    }
}

/// The sky and sun radiance equal Mitsuba's (within [`tolerance`]), in both modes, in every
/// direction, the sun's disc and limb included.
#[test]
fn radiance_matches_mitsuba() {
    let checks: Value = serde_json::from_str(CHECKS).unwrap();
    // Largest differences: off the limb-darkened disc, and on it.
    let (worst, worst_limb) = (std::cell::Cell::new(0.0f32), std::cell::Cell::new(0.0f32));
    let record = |e: f32, tol: f32, what: &dyn Fn() -> String| {
        let w = if tol > 1e-4 { &worst_limb } else { &worst };
        w.set(w.get().max(e));
        assert!(e < tol, "{}", what());
    };
    for case in checks["radiance"].as_array().unwrap() {
        let (p, albedo) = params(&case["params"]);
        let rgb_model = SkyModel::rgb(&p, [albedo; 3]);
        let spec_model = SkyModel::spectral(&p, [albedo; tables::WAVELENGTHS]);
        let lambdas: Vec<f32> = case["wavelengths"]
            .as_array()
            .unwrap()
            .iter()
            .map(f)
            .collect();
        let dirs = case["directions"].as_array().unwrap();
        let (scale_rgb, scale_spec) = (largest(&case["rgb"]), largest(&case["spectral"]));
        for (i, d) in dirs.iter().enumerate() {
            // As Mitsuba receives it: the f32 direction, not renormalised.
            let d = vec3(d);
            let sky = rgb_model.sky_rgb(d);
            let sun = rgb_model.sun_rgb(d);
            for c in 0..3 {
                let want = f(&case["rgb"][i][c]);
                let got = sky[c] + sun[c];
                record(rel(got, want, scale_rgb), tolerance(&p, d), &|| {
                    format!(
                        "{}: dir {i} ({d}) channel {c}: {got} vs Mitsuba {want}",
                        case["params"]
                    )
                });
            }
            for (k, chunk) in lambdas.chunks(4).enumerate() {
                let mut l = [chunk[0]; 4];
                l[..chunk.len()].copy_from_slice(chunk);
                let sky = spec_model.sky_spectral(d, l);
                let sun = spec_model.sun_spectral(d, l);
                for j in 0..chunk.len() {
                    let want = f(&case["spectral"][i][4 * k + j]);
                    let got = sky[j] + sun[j];
                    record(rel(got, want, scale_spec), tolerance(&p, d), &|| {
                        format!(
                            "{}: dir {i} ({d}) {} nm: {got} vs Mitsuba {want}",
                            case["params"], l[j]
                        )
                    });
                }
            }
        }
    }
    let (worst, worst_limb) = (worst.get(), worst_limb.get());
    eprintln!("largest relative difference from Mitsuba: {worst:e}, on the limb-darkened disc {worst_limb:e}");
}

/// The sun's position equals Mitsuba's within 0.05 degrees: the difference is Mitsuba's
/// single-precision Julian date (see `solar`), rounded to quarter days, which moves the sun's
/// ecliptic longitude by up to 0.12 degrees, mostly cancelled in the hour angle by the sidereal
/// time computed from the same date (the cases here and scenes/sunsky.xml's date show up to
/// 0.032 degrees); a wrong time zone sign, longitude or date moves the sun by degrees.
#[test]
fn sun_position_matches_mitsuba() {
    let checks: Value = serde_json::from_str(CHECKS).unwrap();
    for s in checks["sun_positions"].as_array().unwrap() {
        let p = &s["params"];
        let g = |k: &str, d: f64| p.get(k).and_then(Value::as_f64).unwrap_or(d);
        let t = crate::solar::DateTime {
            year: g("year", 2010.0) as i32,
            month: g("month", 7.0) as i32,
            day: g("day", 10.0) as i32,
            hour: g("hour", 15.0),
            minute: g("minute", 0.0),
            second: g("second", 0.0),
        };
        let at = crate::solar::Location {
            latitude: g("latitude", 35.6894),
            longitude: g("longitude", 139.6917),
            timezone: g("timezone", 9.0),
        };
        let ours = crate::solar::sun_direction(&t, &at);
        let theirs = vec3(&s["sun_direction"]);
        let angle = unit_angle(ours, theirs.normalize()).to_degrees();
        assert!(
            angle < 0.05,
            "{p}: {ours} vs Mitsuba {theirs}: {angle} degrees apart"
        );
    }
}
