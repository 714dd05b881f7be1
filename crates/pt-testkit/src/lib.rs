//! Statistical checks for BSDF (and other direction) samplers, written once for every model.
//!
//! - [`chi2_sphere`]: Mitsuba 3's `chi2.py` test of a sampler against its claimed pdf. Sampled
//!   directions are binned over the whole sphere in a grid of cells uniform in (cos theta, phi)
//!   (equal solid angle, since d omega = d(cos theta) d phi); the expected count of a cell is `N`
//!   times the pdf integrated over it by adaptive Simpson quadrature; cells with expected count
//!   below 20 (Mitsuba: 5; see [`Chi2Config::min_expected`]) are pooled in increasing order of
//!   expectation so that Pearson's statistic is close to chi-square distributed; a sampler that fails (returns `None`) is
//!   counted in one extra cell whose expectation is `N (1 - integral of pdf)`, so a sampler that
//!   loses probability the pdf does not account for fails too. [`Chi2Report::check`] applies
//!   a Šidák-corrected level over all tests of a grid.
//! - [`albedo_mc`] and [`albedo_quadrature`]: the white furnace, E[weight] over samples and an
//!   independent quadrature of f |cos theta_i| over the sphere, to cross-check each other and a
//!   closed form.
//! - [`reciprocity_error`]: f(a, b) against f(b, a) over random direction pairs.
//! - [`check_delta`]: deterministic checks of delta lobes (directions, probabilities, weights).
//!
//! Everything takes closures, so any sampler can be tested: `sample(wo, u) -> Option<Sample>`
//! with `u` in [0,1)^3 (`u.x` for the lobe choice, `u.y, u.z` for the direction) and
//! `pdf(wo, wi) -> f32` per unit solid angle. Randomness comes from a fixed-seed PCG32, so every
//! test is deterministic: a statistical test that passes passes every time, and its threshold
//! is a statement about how unlikely a correct sampler would be to fail for a *random* seed.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

use glam::{Vec2, Vec3};
use pt_image::stats::{chi2_sf, sidak_threshold};
use std::f64::consts::PI;

/// What a sampler under test returns (a model-agnostic copy of a BSDF sample).
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// Sampled direction (unit, local frame).
    pub wi: Vec3,
    /// `f |cos theta_i| / pdf` in one spectral lane.
    pub weight: f32,
    /// Solid-angle pdf (discrete probability for a delta lobe).
    pub pdf: f32,
    /// Whether the sample came from a delta lobe.
    pub delta: bool,
}

/// PCG32 (O'Neill 2014, XSH RR 64/32): small, fast, deterministic for a given seed and stream.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// A generator for `seed` on stream `stream`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1) with 24 bits (every value exactly representable, never 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Three uniforms in [0, 1).
    pub fn next_vec3(&mut self) -> Vec3 {
        Vec3::new(self.next_f32(), self.next_f32(), self.next_f32())
    }
}

/// A unit direction from polar coordinates (cos theta, phi).
#[inline]
pub fn spherical(cos_theta: f64, phi: f64) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(
        (sin_theta * phi.cos()) as f32,
        (sin_theta * phi.sin()) as f32,
        cos_theta as f32,
    )
}

/// A unit direction at polar angle `theta_deg` degrees and azimuth `phi_deg` degrees.
pub fn dir_deg(theta_deg: f64, phi_deg: f64) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    spherical(t.cos(), p)
}

/// Settings of the chi-square test. The defaults (200k samples, 32 x 64 cells) detect a pdf
/// wrong by a few percent over a tenth of the sphere and run in about 0.05-0.2 s per test.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Config {
    /// Number of sampler calls.
    pub samples: usize,
    /// Cells in cos theta over [-1, 1] (even, so the horizon is a cell boundary).
    pub res_cos: usize,
    /// Cells in phi over [0, 2 pi).
    pub res_phi: usize,
    /// Cells with smaller expected counts are pooled. Mitsuba uses 5; the default here is 20
    /// because with ~1000 cells near 5 the Pearson statistic's variance exceeds the
    /// chi-square's (by about the sum of 1/E over cells), which inflates the far tail that a
    /// Šidák-corrected level looks at: a correct GGX rough dielectric gave p = 3e-5 at 200k
    /// samples (pooling at 5) and p = 0.6 / 0.24 at 2M samples with two seeds.
    pub min_expected: f64,
    /// Seed of the sample stream.
    pub seed: u64,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Chi2Config {
            samples: 200_000,
            res_cos: 32,
            res_phi: 64,
            min_expected: 20.0,
            seed: 7,
        }
    }
}

/// The outcome of one chi-square test.
#[derive(Clone, Debug)]
pub struct Chi2Result {
    /// Label of the test (model, parameters, incident direction).
    pub name: String,
    /// Pearson statistic after pooling.
    pub chi2: f64,
    /// Degrees of freedom (cells after pooling - 1).
    pub dof: usize,
    /// P(X >= chi2) for a chi-square variable with `dof` degrees of freedom.
    pub p_value: f64,
    /// Integral of the pdf over the sphere (1 for a sampler that never fails).
    pub pdf_integral: f64,
    /// A failure that needs no statistics: a sample in a cell of zero expectation, a non-finite
    /// or non-unit direction, a sample's pdf that disagrees with `pdf(wo, wi)`, a delta sample.
    pub hard_failure: Option<String>,
}

/// Integral over a (theta, phi) rectangle by adaptive Simpson quadrature. The rectangle is
/// split 4x4 (so that a lobe much narrower than the cell is not missed by a first 3x3 rule
/// that would then "converge" on a wrong value); on each part the 3x3 rule is compared with the
/// sum of 3x3 rules on its four quarters, recursing where they differ by more than 15 times the
/// part's tolerance (the Richardson error estimate), to `depth` further levels. The tolerance
/// is `max(abs_tol, rel_tol * |coarse estimate|)` for the rectangle and halves (not quarters)
/// per level, so that refinement along a discontinuity (horizon, total internal reflection)
/// stops instead of running to the depth limit.
fn adaptive_simpson_2d(
    f: &dyn Fn(f64, f64) -> f64,
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    abs_tol: f64,
    rel_tol: f64,
    depth: u32,
) -> f64 {
    fn simpson(f: &dyn Fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        const W: [f64; 3] = [1.0, 4.0, 1.0];
        let (xm, ym) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let xs = [x0, xm, x1];
        let ys = [y0, ym, y1];
        let mut s = 0.0;
        for (i, &x) in xs.iter().enumerate() {
            for (j, &y) in ys.iter().enumerate() {
                s += W[i] * W[j] * f(x, y);
            }
        }
        s * (x1 - x0) * (y1 - y0) / 36.0
    }
    fn rec(
        f: &dyn Fn(f64, f64) -> f64,
        r: (f64, f64, f64, f64),
        whole: f64,
        tol: f64,
        depth: u32,
    ) -> f64 {
        let (x0, x1, y0, y1) = r;
        let (xm, ym) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let q = [
            (x0, xm, y0, ym),
            (xm, x1, y0, ym),
            (x0, xm, ym, y1),
            (xm, x1, ym, y1),
        ];
        let parts = q.map(|(a, b, c, d)| simpson(f, a, b, c, d));
        let sum: f64 = parts.iter().sum();
        if depth == 0 || (sum - whole).abs() <= 15.0 * tol {
            return sum + (sum - whole) / 15.0;
        }
        q.iter()
            .zip(parts)
            .map(|(&qr, p)| rec(f, qr, p, 0.5 * tol, depth - 1))
            .sum()
    }
    let (dx, dy) = ((x1 - x0) / 4.0, (y1 - y0) / 4.0);
    let mut parts = Vec::with_capacity(16);
    for i in 0..4 {
        for j in 0..4 {
            let r = (
                x0 + i as f64 * dx,
                x0 + (i + 1) as f64 * dx,
                y0 + j as f64 * dy,
                y0 + (j + 1) as f64 * dy,
            );
            parts.push((r, simpson(f, r.0, r.1, r.2, r.3)));
        }
    }
    let coarse: f64 = parts.iter().map(|p| p.1).sum();
    let tol = abs_tol.max(rel_tol * coarse.abs()) / 16.0;
    parts
        .into_iter()
        .map(|(r, whole)| rec(f, r, whole, tol, depth))
        .sum()
}

/// Integral of `g(direction)` over each cell of a `res_cos x res_phi` grid in (cos theta, phi)
/// over the sphere, row-major (cos theta outer). Each cell is integrated to an error of about
/// `max(abs_tol, rel_tol * value)` (adaptive Simpson, see the source).
pub fn integrate_cells(
    g: &dyn Fn(Vec3) -> f64,
    res_cos: usize,
    res_phi: usize,
    abs_tol: f64,
    rel_tol: f64,
) -> Vec<f64> {
    // Inside a cell, integrate over (theta, phi) with the Jacobian sin(theta): a lobe at a
    // pole is ~1/(angular width) wider there than in cos(theta), so far easier to resolve.
    let f = |t: f64, p: f64| {
        let (st, ct) = t.sin_cos();
        let v = g(spherical(ct, p)) * st;
        if v.is_finite() {
            v
        } else {
            f64::NAN
        }
    };
    let mut out = Vec::with_capacity(res_cos * res_phi);
    for i in 0..res_cos {
        let c0 = -1.0 + 2.0 * i as f64 / res_cos as f64;
        let c1 = -1.0 + 2.0 * (i + 1) as f64 / res_cos as f64;
        let (t0, t1) = (c1.clamp(-1.0, 1.0).acos(), c0.clamp(-1.0, 1.0).acos());
        // Evaluate strictly inside the cell: a pdf that jumps at a cell boundary (the horizon,
        // where a grazing lobe is cut off) must not leak its value into the neighbour cell
        // through the Simpson end points. The area lost is 1e-6 of the cell.
        let eps = 5e-7 * (t1 - t0);
        let (t0, t1) = (t0 + eps, t1 - eps);
        for j in 0..res_phi {
            let p0 = 2.0 * PI * j as f64 / res_phi as f64;
            let p1 = 2.0 * PI * (j + 1) as f64 / res_phi as f64;
            out.push(adaptive_simpson_2d(
                &f,
                (t0, t1, p0, p1),
                abs_tol,
                rel_tol,
                8,
            ));
        }
    }
    out
}

fn cell_of(wi: Vec3, res_cos: usize, res_phi: usize) -> usize {
    let c = f64::from(wi.z).clamp(-1.0, 1.0);
    let mut phi = f64::from(wi.y).atan2(f64::from(wi.x));
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let i = (((c + 1.0) * 0.5 * res_cos as f64) as usize).min(res_cos - 1);
    let j = ((phi / (2.0 * PI) * res_phi as f64) as usize).min(res_phi - 1);
    i * res_phi + j
}

/// Pearson's chi-square of `observed` against `expected` after pooling cells with expectation
/// below `min_expected` (sorted by expectation, merged until each pooled cell reaches it;
/// Mitsuba's `chi2.py` pools all of them into one). Returns (chi2, dof, hard failure).
pub fn pooled_chi2(
    observed: &[f64],
    expected: &[f64],
    min_expected: f64,
) -> (f64, usize, Option<String>) {
    let mut idx: Vec<usize> = (0..expected.len()).collect();
    idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut chi2 = 0.0;
    let mut cells = 0usize;
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    for &k in &idx {
        let (o, e) = (observed[k], expected[k]);
        if e <= 0.0 && o > 0.0 {
            return (
                f64::INFINITY,
                0,
                Some(format!(
                    "{o} samples in cell {k} where the pdf integrates to {e:e}"
                )),
            );
        }
        if e < min_expected {
            pool_obs += o;
            pool_exp += e;
            if pool_exp >= min_expected {
                chi2 += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
                cells += 1;
                pool_obs = 0.0;
                pool_exp = 0.0;
            }
        } else {
            chi2 += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pool_exp > 0.0 {
        // Leftover pool below the minimum: count it as its own cell (conservative in dof).
        chi2 += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        cells += 1;
    } else if pool_obs > 0.0 {
        return (
            f64::INFINITY,
            0,
            Some(format!("{pool_obs} samples where the pdf is 0")),
        );
    }
    (chi2, cells.saturating_sub(1), None)
}

/// Chi-square test of `sample` against `pdf` for the incident direction `wo` (see the crate doc).
///
/// Besides the histogram, each returned sample is checked: unit and finite `wi`, `delta` false,
/// and its `pdf` equal to `pdf(wo, wi)` to 1e-3 relative (a mismatch is a hard failure).
pub fn chi2_sphere(
    name: &str,
    wo: Vec3,
    sample: &dyn Fn(Vec3, Vec3) -> Option<Sample>,
    pdf: &dyn Fn(Vec3, Vec3) -> f32,
    cfg: &Chi2Config,
) -> Chi2Result {
    let ncells = cfg.res_cos * cfg.res_phi;
    let mut observed = vec![0.0f64; ncells + 1]; // last cell: sampler failures
    let mut rng = Pcg32::new(cfg.seed, 0x5eed);
    let mut hard_failure = None;
    for _ in 0..cfg.samples {
        let u = rng.next_vec3();
        match sample(wo, u) {
            None => observed[ncells] += 1.0,
            Some(s) => {
                if hard_failure.is_none() {
                    let p = pdf(wo, s.wi);
                    if !s.wi.is_finite() || (s.wi.length() - 1.0).abs() > 1e-3 {
                        hard_failure = Some(format!("non-unit direction {:?} for u = {u:?}", s.wi));
                    } else if s.delta {
                        hard_failure =
                            Some(format!("delta sample {:?} in a smooth-lobe test", s.wi));
                    } else if !(s.pdf > 0.0)
                        || !s.pdf.is_finite()
                        || !s.weight.is_finite()
                        || s.weight < 0.0
                    {
                        hard_failure = Some(format!(
                            "sample pdf {} weight {} at wi = {:?}",
                            s.pdf, s.weight, s.wi
                        ));
                    } else if (p - s.pdf).abs() > 1e-3 * s.pdf.max(p) + 1e-6 {
                        hard_failure = Some(format!(
                            "sample pdf {} but pdf(wo, wi) = {p} at wi = {:?}",
                            s.pdf, s.wi
                        ));
                    }
                }
                if s.wi.is_finite() {
                    observed[cell_of(s.wi, cfg.res_cos, cfg.res_phi)] += 1.0;
                }
            }
        }
    }
    let n = cfg.samples as f64;
    // Quadrature tolerance per cell: 0.02 expected counts or 1e-4 of the cell's expectation,
    // whichever is larger. An error d in a cell of expectation E adds about d^2/E to the
    // statistic: at most 4e-4 per low cell and 1e-8 E per high cell, far below the chi-square's
    // own spread (sqrt(2 dof) ~ 60 for 2048 cells). (1e-3 was measurably too loose for a GGX
    // lobe of alpha = 0.05 seen from inside glass: integral 0.9983 against a true 0.9975.)
    let g = |wi: Vec3| f64::from(pdf(wo, wi));
    let mut expected: Vec<f64> = integrate_cells(&g, cfg.res_cos, cfg.res_phi, 0.02 / n, 1e-4);
    let pdf_integral: f64 = expected.iter().sum();
    if hard_failure.is_none() && !pdf_integral.is_finite() {
        hard_failure = Some("pdf is not finite somewhere".into());
    }
    for e in &mut expected {
        *e = e.max(0.0) * n;
    }
    // Failure cell: its expectation is the probability the pdf does not account for (clamped
    // at 0, since quadrature may overshoot 1 by its error). When the pdf integrates to 1 within
    // the quadrature's accuracy (1e-4) and at most 1e-4 of the samples failed (samples exactly
    // on the horizon, a measure-zero set), the cell is left out: a loss that small is below
    // what the quadrature can resolve.
    let fails = observed[ncells];
    if (1.0 - pdf_integral).abs() < 1e-4 && fails <= 1e-4 * n {
        observed.pop();
    } else {
        expected.push((1.0 - pdf_integral).max(0.0) * n);
    }
    if pdf_integral > 1.0 + 1e-3 && hard_failure.is_none() {
        hard_failure = Some(format!("pdf integrates to {pdf_integral} > 1"));
    }
    let (chi2, dof, pool_fail) = pooled_chi2(&observed, &expected, cfg.min_expected);
    if hard_failure.is_none() {
        hard_failure = pool_fail;
    }
    let p_value = if dof == 0 {
        if chi2.is_finite() {
            1.0
        } else {
            0.0
        }
    } else {
        chi2_sf(chi2, dof as f64)
    };
    Chi2Result {
        name: name.to_string(),
        chi2,
        dof,
        p_value,
        pdf_integral,
        hard_failure,
    }
}

/// A set of chi-square tests judged together.
#[derive(Clone, Debug, Default)]
pub struct Chi2Report {
    /// Every test run.
    pub results: Vec<Chi2Result>,
}

impl Chi2Report {
    /// Adds one test's result.
    pub fn push(&mut self, r: Chi2Result) {
        self.results.push(r);
    }

    /// The tests that fail at family-wise significance `alpha` (Šidák level
    /// `1 - (1 - alpha)^(1/n)` per test over the `n` tests), plus every hard failure.
    pub fn failures(&self, alpha: f64) -> Vec<&Chi2Result> {
        let level = sidak_threshold(alpha, self.results.len());
        self.results
            .iter()
            .filter(|r| r.hard_failure.is_some() || !(r.p_value >= level))
            .collect()
    }

    /// Panics listing the failed tests at family-wise significance `alpha` (use 0.01, Mitsuba's).
    pub fn check(&self, alpha: f64) {
        let fails = self.failures(alpha);
        if !fails.is_empty() {
            let level = sidak_threshold(alpha, self.results.len());
            let mut msg = format!(
                "{} of {} chi-square tests failed (per-test level {level:.3e}):\n",
                fails.len(),
                self.results.len()
            );
            for r in fails {
                msg += &format!(
                    "  {}: chi2 = {:.1}, dof = {}, p = {:.3e}, pdf integral = {:.5}{}\n",
                    r.name,
                    r.chi2,
                    r.dof,
                    r.p_value,
                    r.pdf_integral,
                    r.hard_failure
                        .as_deref()
                        .map(|s| format!(", {s}"))
                        .unwrap_or_default()
                );
            }
            panic!("{msg}");
        }
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;

    fn cosine_sample(_wo: Vec3, u: Vec3) -> Option<Sample> {
        // Malley: uniform disk lifted to the hemisphere (polar map; the test needs no low distortion).
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
    fn cosine_pdf(_wo: Vec3, wi: Vec3) -> f32 {
        if wi.z > 0.0 {
            wi.z / std::f32::consts::PI
        } else {
            0.0
        }
    }

    #[test]
    fn passes_for_cosine_sampling_against_its_pdf() {
        let r = chi2_sphere(
            "cosine",
            Vec3::Z,
            &cosine_sample,
            &cosine_pdf,
            &Chi2Config::default(),
        );
        assert!(r.hard_failure.is_none(), "{r:?}");
        assert!((r.pdf_integral - 1.0).abs() < 1e-4, "{r:?}");
        // One test at 1%: a correct sampler with this fixed seed passes; a p-value this small
        // for a correct one would need a 1-in-100 seed.
        assert!(r.p_value > 0.01, "{r:?}");
    }

    #[test]
    fn fails_for_cosine_sampling_judged_against_uniform_pdf() {
        // The sampler reports the uniform-hemisphere pdf (so the per-sample pdf check passes)
        // but draws cosine-weighted directions: only the histogram can catch it.
        let wrong = |wo: Vec3, u: Vec3| {
            cosine_sample(wo, u).map(|s| Sample {
                pdf: 0.5 / std::f32::consts::PI,
                ..s
            })
        };
        let uniform = |_wo: Vec3, wi: Vec3| {
            if wi.z > 0.0 {
                0.5 / std::f32::consts::PI
            } else {
                0.0
            }
        };
        let r = chi2_sphere("wrong", Vec3::Z, &wrong, &uniform, &Chi2Config::default());
        assert!(r.hard_failure.is_none() && r.p_value < 1e-12, "{r:?}");
        let mut rep = Chi2Report::default();
        rep.push(r);
        assert_eq!(rep.failures(0.01).len(), 1);
    }

    #[test]
    fn fails_for_slightly_wrong_pdf_and_for_lost_samples() {
        // A 5% tilt of the pdf (it still integrates to 1): cos/pi * (1 + 0.1 (x)).
        let tilted = |_wo: Vec3, wi: Vec3| cosine_pdf(Vec3::Z, wi) * (1.0 + 0.1 * wi.x);
        let lenient = |wo: Vec3, u: Vec3| {
            cosine_sample(wo, u).map(|s| Sample {
                pdf: tilted(wo, s.wi),
                ..s
            })
        };
        let r = chi2_sphere("tilted", Vec3::Z, &lenient, &tilted, &Chi2Config::default());
        assert!(r.p_value < 1e-6, "{r:?}");
        // A sampler that silently drops 3% of its samples while its pdf integrates to 1.
        let lossy = |wo: Vec3, u: Vec3| {
            if u.x < 0.03 {
                None
            } else {
                cosine_sample(wo, u)
            }
        };
        let r = chi2_sphere(
            "lossy",
            Vec3::Z,
            &lossy,
            &cosine_pdf,
            &Chi2Config::default(),
        );
        assert!(r.p_value < 1e-6, "{r:?}");
        // The per-sample pdf check catches a sample pdf that disagrees with pdf().
        let liar = |wo: Vec3, u: Vec3| {
            cosine_sample(wo, u).map(|s| Sample {
                pdf: 2.0 * s.pdf,
                ..s
            })
        };
        let r = chi2_sphere("liar", Vec3::Z, &liar, &cosine_pdf, &Chi2Config::default());
        assert!(r.hard_failure.is_some());
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
