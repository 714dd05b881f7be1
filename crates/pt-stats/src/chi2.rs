//! Mitsuba 3's `chi2.py` test of a direction sampler against its claimed pdf (see the crate doc).

use crate::rng::Pcg32;
use crate::special::{chi2_sf, sidak_threshold};
use crate::sphere::{cell_of, integrate_cells};
use glam::Vec3;

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
                    } else if s.pdf.is_nan()
                        || s.pdf <= 0.0
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
            .filter(|r| r.hard_failure.is_some() || r.p_value.is_nan() || r.p_value < level)
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
}
