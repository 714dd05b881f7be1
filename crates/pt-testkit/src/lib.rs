//! Test helpers for BSDF (and other direction) samplers, written once for every model. Not part
//! of the `pt` binary (`publish = false`; only tests depend on it).
//!
//! - [`albedo_mc`] and [`albedo_quadrature`]: the white furnace, E[weight] over samples and an
//!   independent quadrature of f |cos theta_i| over the sphere, to cross-check each other and a
//!   closed form.
//! - [`reciprocity_error`]: f(a, b) against f(b, a) over random direction pairs.
//! - [`check_delta`]: deterministic checks of delta lobes (directions, probabilities, weights).
//! - Re-exported from `pt-stats`, where the binary can use them too: the chi-square test of a
//!   sampler against its pdf ([`chi2_sphere`], [`Chi2Config`], [`Chi2Report`], ...), the PCG32
//!   generator ([`Pcg32`]) and the direction helpers ([`spherical`], [`dir_deg`]).
//!
//! Everything takes closures, so any sampler can be tested: `sample(wo, u) -> Option<Sample>`
//! with `u` in [0,1)^3 (`u.x` for the lobe choice, `u.y, u.z` for the direction) and
//! `pdf(wo, wi) -> f32` per unit solid angle, directions in the local shading frame (z = the
//! normal). Randomness comes from a fixed-seed PCG32, so every test is deterministic: a
//! statistical test that passes passes every time, and its threshold is a statement about how
//! unlikely a correct sampler would be to fail for a *random* seed.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

use glam::{Vec2, Vec3};
use std::f64::consts::PI;

pub use pt_stats::chi2::{chi2_sphere, pooled_chi2, Chi2Config, Chi2Report, Chi2Result, Sample};
pub use pt_stats::rng::Pcg32;
pub use pt_stats::sphere::{dir_deg, integrate_cells, spherical};

/// Monte Carlo directional albedo: mean and standard error of the sample weight over `n`
/// samples (failed samples count as 0). With a white BSDF this is the white-furnace value.
pub fn albedo_mc(
    wo: Vec3,
    sample: &dyn Fn(Vec3, Vec3) -> Option<Sample>,
    n: usize,
    seed: u64,
) -> (f64, f64) {
    let mut rng = Pcg32::new(seed, 0xa1be);
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let w = sample(wo, rng.next_vec3()).map_or(0.0, |s| f64::from(s.weight));
        assert!(
            w.is_finite() && w >= 0.0,
            "non-finite or negative weight {w} at wo = {wo:?}"
        );
        s += w;
        s2 += w * w;
    }
    let mean = s / n as f64;
    let var = (s2 / n as f64 - mean * mean).max(0.0);
    (mean, (var / n as f64).sqrt())
}

/// Directional albedo by quadrature: integral over the sphere of `f(wo, wi) |cos theta_i|`,
/// by adaptive Simpson over a 32 x 64 (cos theta, phi) grid with absolute tolerance `tol` and
/// relative tolerance 1e-4 per cell. Independent of any sampler; accurate for smooth lobes.
pub fn albedo_quadrature(wo: Vec3, f: &dyn Fn(Vec3, Vec3) -> f32, tol: f64) -> f64 {
    let g = |wi: Vec3| f64::from(f(wo, wi)) * f64::from(wi.z).abs();
    integrate_cells(&g, 32, 64, tol, 1e-4).iter().sum()
}

/// Largest relative reciprocity error `|f(a,b) - f(b,a)| / max(f(a,b), f(b,a), floor)` over `n`
/// random pairs of directions from `dirs(u)` (`u` uniform in [0,1)^2).
pub fn reciprocity_error(
    f: &dyn Fn(Vec3, Vec3) -> f32,
    dirs: &dyn Fn(Vec2) -> Vec3,
    n: usize,
    floor: f32,
) -> f32 {
    let mut rng = Pcg32::new(3, 0xec1);
    let mut worst = 0.0f32;
    for _ in 0..n {
        let a = dirs(Vec2::new(rng.next_f32(), rng.next_f32()));
        let b = dirs(Vec2::new(rng.next_f32(), rng.next_f32()));
        let (fab, fba) = (f(a, b), f(b, a));
        assert!(
            fab.is_finite() && fba.is_finite(),
            "non-finite f at {a:?}, {b:?}"
        );
        worst = worst.max((fab - fba).abs() / fab.max(fba).max(floor));
    }
    worst
}

/// Uniform direction on the upper hemisphere from `u` (for reciprocity and robustness checks).
pub fn upper_hemisphere(u: Vec2) -> Vec3 {
    spherical(f64::from(u.x), 2.0 * PI * f64::from(u.y))
}

/// One expected outcome of a delta lobe.
#[derive(Clone, Copy, Debug)]
pub struct DeltaLobe {
    /// The lobe's direction.
    pub wi: Vec3,
    /// Probability of choosing it.
    pub prob: f32,
    /// Expected sample weight.
    pub weight: f32,
}

/// Deterministic checks of a sampler made only of delta lobes: over `n` samples, every sample is
/// `delta`, goes in one of the `lobes` directions (to 1e-4), has `pdf` equal to that lobe's
/// probability and the lobe's `weight` (to 1e-4 relative); the frequency of each lobe is within
/// 5 binomial standard deviations of its probability (a correct sampler fails that with
/// probability below 1e-6 per lobe); no sample fails unless the probabilities sum below 1.
/// Panics with a message naming `name` otherwise.
pub fn check_delta(
    name: &str,
    wo: Vec3,
    sample: &dyn Fn(Vec3, Vec3) -> Option<Sample>,
    lobes: &[DeltaLobe],
    n: usize,
) {
    let mut rng = Pcg32::new(11, 0xde17a);
    let mut counts = vec![0usize; lobes.len()];
    let mut failed = 0usize;
    for _ in 0..n {
        let u = rng.next_vec3();
        let Some(s) = sample(wo, u) else {
            failed += 1;
            continue;
        };
        assert!(s.delta, "{name}: non-delta sample {:?}", s.wi);
        let k = lobes
            .iter()
            .position(|l| (l.wi - s.wi).length() < 1e-4)
            .unwrap_or_else(|| {
                panic!(
                    "{name}: sample {:?} matches no expected lobe {lobes:?} (u = {u:?})",
                    s.wi
                )
            });
        let l = lobes[k];
        assert!(
            (s.pdf - l.prob).abs() <= 1e-4 * l.prob.max(1e-3),
            "{name}: pdf {} != {}",
            s.pdf,
            l.prob
        );
        assert!(
            (s.weight - l.weight).abs() <= 1e-4 * l.weight.max(1e-3),
            "{name}: weight {} != {}",
            s.weight,
            l.weight
        );
        counts[k] += 1;
    }
    let total_p: f32 = lobes.iter().map(|l| l.prob).sum();
    for (l, &c) in lobes.iter().zip(&counts).chain(std::iter::once((
        &DeltaLobe {
            wi: Vec3::ZERO,
            prob: 1.0 - total_p,
            weight: 0.0,
        },
        &failed,
    ))) {
        let p = f64::from(l.prob).clamp(0.0, 1.0);
        let sd = (n as f64 * p * (1.0 - p)).sqrt();
        let dev = (c as f64 - n as f64 * p).abs();
        assert!(
            dev <= 5.0 * sd + 1e-9,
            "{name}: lobe {:?} chosen {c} times of {n}, expected probability {p}",
            l.wi
        );
    }
}

/// The `.rs` files directly in `tests_dir` that the test binary whose root file is `root` (a
/// file in that folder) does not declare as modules (`mod NAME;` on a line of its own), other
/// than `root` itself and the files named in `standalone` (test targets of their own). For
/// packages with `autotests = false`, where an undeclared file would silently never run.
pub fn undeclared_test_files(
    tests_dir: &std::path::Path,
    root: &str,
    standalone: &[&str],
) -> std::io::Result<Vec<String>> {
    let source = std::fs::read_to_string(tests_dir.join(format!("{root}.rs")))?;
    let declared: Vec<&str> = source
        .lines()
        .filter_map(|l| l.strip_prefix("mod ")?.strip_suffix(';'))
        .collect();
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(tests_dir)? {
        let path = entry?.path();
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if stem != root && !standalone.contains(&stem) && !declared.contains(&stem) {
            missing.push(stem.to_owned());
        }
    }
    missing.sort();
    Ok(missing)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cosine-weighted hemisphere sampling (Malley's method with the polar disk map).
    fn cosine_sample(_wo: Vec3, u: Vec3) -> Option<Sample> {
        let r = u.y.sqrt();
        let phi = 2.0 * std::f32::consts::PI * u.z;
        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.y).max(0.0).sqrt());
        (wi.z > 0.0).then_some(Sample {
            wi,
            weight: 1.0,
            pdf: wi.z / std::f32::consts::PI,
            delta: false,
        })
    }

    #[test]
    fn quadrature_and_furnace_of_lambert() {
        let f = |_wo: Vec3, wi: Vec3| {
            if wi.z > 0.0 {
                0.8 / std::f32::consts::PI
            } else {
                0.0
            }
        };
        let a = albedo_quadrature(Vec3::Z, &f, 1e-7);
        assert!((a - 0.8).abs() < 1e-4, "{a}");
        let s = |wo: Vec3, u: Vec3| cosine_sample(wo, u).map(|s| Sample { weight: 0.8, ..s });
        let (m, se) = albedo_mc(Vec3::Z, &s, 1000, 1);
        assert!((m - 0.8).abs() < 1e-6 && se < 1e-6);
    }

    #[test]
    fn delta_checker_accepts_a_mirror_and_rejects_a_wrong_probability() {
        let wo = dir_deg(30.0, 10.0);
        let mirror = |wo: Vec3, _u: Vec3| {
            Some(Sample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: 0.9,
                pdf: 1.0,
                delta: true,
            })
        };
        let refl = Vec3::new(-wo.x, -wo.y, wo.z);
        check_delta(
            "mirror",
            wo,
            &mirror,
            &[DeltaLobe {
                wi: refl,
                prob: 1.0,
                weight: 0.9,
            }],
            1000,
        );
        let coin = |wo: Vec3, u: Vec3| {
            let (wi, p) = if u.x < 0.7 {
                (Vec3::new(-wo.x, -wo.y, wo.z), 0.5)
            } else {
                (-wo, 0.5)
            };
            Some(Sample {
                wi,
                weight: 1.0,
                pdf: p,
                delta: true,
            })
        };
        let lobes = [
            DeltaLobe {
                wi: refl,
                prob: 0.5,
                weight: 1.0,
            },
            DeltaLobe {
                wi: -wo,
                prob: 0.5,
                weight: 1.0,
            },
        ];
        let r = std::panic::catch_unwind(|| check_delta("coin", wo, &coin, &lobes, 10_000));
        assert!(r.is_err(), "a 70/30 choice passed as 50/50");
    }

    #[test]
    fn reciprocity_of_a_symmetric_and_an_asymmetric_function() {
        let sym = |a: Vec3, b: Vec3| 1.0 + a.z * b.z;
        assert!(reciprocity_error(&sym, &upper_hemisphere, 1000, 1e-6) < 1e-6);
        let asym = |a: Vec3, b: Vec3| 1.0 + a.z * b.z * b.z;
        assert!(reciprocity_error(&asym, &upper_hemisphere, 1000, 1e-6) > 1e-2);
    }
}
