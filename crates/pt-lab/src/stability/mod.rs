//! A numerical stress sweep of every BSDF model (`pt stability`), written as a CSV and a
//! Markdown report with charts.
//!
//! Every variant of [`pt_bsdf::Bsdf`] is built over a grid of its parameters, from 0 through
//! the top of the documented range and beyond it (including NaN, infinite and negative values,
//! which the constructors must sanitise), and probed at incident angles 0 (exactly the normal),
//! 30, 60, 80, 89, 89.9, 89.99 and 90 (exactly the horizon) degrees, from both sides for the
//! transmissive models. Thin films are swept over thicknesses 0-2000 nm (and 1e5 nm beyond),
//! with lane wavelengths covering 360-830 nm in spectral form and the Belcour-Barla RGB form.
//! Where the scene format accepts a configuration, its model is built as a scene file builds
//! it ([`crate::bsdf`]; see [`cases`]).
//!
//! For each (model, parameters, incident direction) the sweep records:
//! - **non-finite values**: NaN or infinite `eval`, `pdf`, sample weights, sample pdfs or sample
//!   directions, over random directions on the whole sphere and special ones (the normal, the
//!   horizon, `wo`, `-wo` and the mirror direction);
//! - **directional albedo** (white furnace): the mean of the sample weight over `--samples`
//!   samples with its standard error, maximum over the spectral lanes; refracted samples are
//!   multiplied by `eta'^2` (energy, not radiance: radiance legitimately grows by `eta^2` on
//!   entering a denser medium). An **energy gain** is an albedo above `1 + ENERGY_TOL + 4 se`;
//! - **pdf mismatches**: a smooth sample whose `pdf` differs from `pdf(wo, wi)` by more than 1e-3
//!   relative (or 1e-6 absolute), or a delta sample whose discrete probability is not in (0, 1],
//!   or a delta model whose `eval`/`pdf` is not 0;
//! - **weight mismatches**: a smooth sample whose weight differs from `eval cos / pdf` by more
//!   than 1e-3 relative;
//! - **chi-square** (smooth models only): Mitsuba's test of the sampled directions against the
//!   integrated pdf ([`pt_stats::chi2_sphere`]); failures are judged at a family-wise level of
//!   1% with Šidák's correction over all chi-square tests of the sweep.
//!
//! It also measures the bias of the optional per-sample clamp (`pt render --clamp`, see
//! [`crate::fireflies`]) on a caustic scene.
//!
//! [`Stability::write`] writes, in a folder (each file atomically): `stability.csv` (one row
//! per case), `report.md`, `albedo.svg`/`.png` and `clamp.svg`/`.png`. The method failure atlas
//! is [`crate::atlas`].

mod cases;
mod report;
#[cfg(test)]
mod tests;

pub use cases::cases;

use crate::bsdf::BsdfSpec;
use crate::fireflies::ClampStudy;
use crate::{LabError, Result};
use pt_bsdf::Bsdf;
use pt_math::{Vec2, Vec3, Vec4};
use pt_spectrum::SampledSpectrum;
use pt_stats::{Chi2Config, Pcg32, Sample};
use rayon::prelude::*;

/// Energy tolerance on the directional albedo, absolute, on top of 4 standard errors of the
/// Monte Carlo estimate: pbrt-v4's white-furnace tests accept 1.01; 1e-3 is tighter, and the
/// f32 arithmetic of the models is far more accurate than that.
pub const ENERGY_TOL: f64 = 1e-3;

/// Family-wise significance of the chi-square tests (Mitsuba's `chi2.py` uses 1%).
pub const CHI2_ALPHA: f64 = 0.01;

/// Incident polar angles, degrees: exactly normal, ordinary, grazing, and exactly at the horizon.
pub const ANGLES_DEG: [f64; 8] = [0.0, 30.0, 60.0, 80.0, 89.0, 89.9, 89.99, 90.0];

/// One BSDF configuration of the sweep.
#[derive(Clone, Debug)]
pub struct Case {
    /// Panel / summary group, e.g. `roughconductor-ggx`.
    pub family: &'static str,
    /// The swept parameter's name (`alpha`, `sigma`, `k`, `eta`, `thickness_nm`, ...).
    pub param_name: &'static str,
    /// Its value as given to the constructor (may be NaN, negative or huge).
    pub param: f32,
    /// Other parameters, for the CSV (`eta=1.5 side=...`).
    pub detail: String,
    /// Whether every parameter is inside the model's documented range.
    pub in_range: bool,
    /// Largest directional albedo the model documents for itself (1 for energy-conserving
    /// models; the 1994 Oren-Nayar models are documented as not conserving energy).
    pub energy_bound: f64,
    /// The model.
    pub bsdf: Bsdf,
    /// The scene-format parameters it was built from (see [`cases`]); `None` where its
    /// constructor built it.
    pub spec: Option<BsdfSpec>,
}

/// The result of probing one case at one incident direction.
#[derive(Clone, Debug)]
pub struct Row {
    /// Index into the case list.
    pub case: usize,
    /// Incident polar angle, degrees.
    pub theta_deg: f64,
    /// Whether `wo` is below the surface (inside a transmissive model).
    pub back: bool,
    /// Count of non-finite values seen.
    pub nonfinite: u32,
    /// Directional (energy) albedo, maximum over lanes.
    pub albedo: f64,
    /// Its standard error.
    pub albedo_se: f64,
    /// `albedo > 1 + ENERGY_TOL + 4 se`.
    pub energy_gain: bool,
    /// Count of pdf mismatches.
    pub pdf_mismatch: u32,
    /// Count of weight mismatches.
    pub weight_mismatch: u32,
    /// Chi-square p-value (smooth models, when run).
    pub chi2_p: Option<f64>,
    /// Chi-square hard failure text.
    pub chi2_hard: Option<String>,
    /// Set after the sweep: the chi-square test fails at the family-wise level.
    pub chi2_fail: bool,
}
/// Incident direction at `theta_deg` (azimuth 30 degrees; exactly +z at 0 and z = 0 at 90),
/// mirrored below the surface when `back`.
pub fn incident(theta_deg: f64, back: bool) -> Vec3 {
    let w = if theta_deg == 0.0 {
        Vec3::Z
    } else if theta_deg == 90.0 {
        Vec3::new(30f32.to_radians().cos(), 30f32.to_radians().sin(), 0.0)
    } else {
        pt_stats::dir_deg(theta_deg, 30.0)
    };
    if back {
        Vec3::new(w.x, w.y, -w.z)
    } else {
        w
    }
}

fn finite4(s: SampledSpectrum) -> bool {
    s.0.is_finite()
}

fn rel_diff(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-30)
}

/// Counts of one probe's checks of eval, pdf and samples.
#[derive(Default)]
struct Checks {
    nonfinite: u32,
    pdf_mismatch: u32,
    weight_mismatch: u32,
}

/// eval and pdf of `b` at `wo` over special and random directions on the whole sphere: no
/// non-finite values, and eval = pdf = 0 for a delta model.
fn check_directions(b: &Bsdf, wo: Vec3, rng: &mut Pcg32, c: &mut Checks) {
    let smooth = b.has_smooth_lobe();
    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
    let special = [
        Vec3::Z,
        -Vec3::Z,
        Vec3::X,
        Vec3::Y,
        wo,
        -wo,
        mirror,
        -mirror,
        Vec3::new(1.0, 0.0, 1e-7).normalize(),
    ];
    let random = (0..1000).map(|_| {
        let (u, v) = (rng.next_f32(), rng.next_f32());
        pt_stats::spherical(
            f64::from(2.0 * u - 1.0),
            2.0 * std::f64::consts::PI * f64::from(v),
        )
    });
    let dirs: Vec<Vec3> = special.into_iter().chain(random).collect();
    for &wi in &dirs {
        let f = b.eval(wo, wi);
        let p = b.pdf(wo, wi);
        if !finite4(f) || !p.is_finite() {
            c.nonfinite += 1;
        }
        if !smooth && (!f.is_black() || p != 0.0) {
            c.pdf_mismatch += 1;
        }
    }
}

/// `n` samples of `b` at `wo`: finiteness, pdf and weight consistency; returns the directional
/// (energy) albedo, maximum over lanes, and its standard error.
fn check_samples(b: &Bsdf, wo: Vec3, n: usize, rng: &mut Pcg32, c: &mut Checks) -> (f64, f64) {
    let (mut sum, mut sum2) = (Vec4::ZERO, Vec4::ZERO);
    for _ in 0..n {
        let u = rng.next_vec3();
        let Some(s) = b.sample(wo, u.x, Vec2::new(u.y, u.z)) else {
            continue;
        };
        if !s.wi.is_finite() || !finite4(s.weight) || !s.pdf.is_finite() || !s.eta.is_finite() {
            c.nonfinite += 1;
            continue;
        }
        if s.delta {
            if !(s.pdf > 0.0 && s.pdf <= 1.0 + 1e-6) {
                c.pdf_mismatch += 1;
            }
        } else {
            let p = b.pdf(wo, s.wi);
            if (p - s.pdf).abs() > 1e-3 * s.pdf.max(p) + 1e-6 {
                c.pdf_mismatch += 1;
            }
            if s.pdf > 0.0 {
                let expect = b.eval(wo, s.wi) * (s.wi.z.abs() / s.pdf);
                let bad = (0..4).any(|l| {
                    let (a, e) = (s.weight.0[l], expect.0[l]);
                    (a - e).abs() > 1e-3 * a.abs().max(e.abs()) + 1e-6 && rel_diff(a, e) > 1e-3
                });
                if bad {
                    c.weight_mismatch += 1;
                }
            }
        }
        let refracted = s.wi.z * wo.z < 0.0;
        let w = s.weight.0 * if refracted { s.eta * s.eta } else { 1.0 };
        sum += w;
        sum2 += w * w;
    }
    let nf = n as f64;
    let mut albedo = 0.0f64;
    let mut albedo_se = 0.0f64;
    for l in 0..4 {
        let m = f64::from(sum[l]) / nf;
        let var = (f64::from(sum2[l]) / nf - m * m).max(0.0);
        if m > albedo || l == 0 {
            albedo = m;
            albedo_se = (var / nf).sqrt();
        }
    }
    (albedo, albedo_se)
}

/// Probes `case` at `theta_deg` (see the module doc) with `n` samples, and a chi-square test
/// with `chi2_samples` samples when the model has a smooth lobe and `chi2_samples > 0`.
pub fn probe(
    ci: usize,
    case: &Case,
    theta_deg: f64,
    back: bool,
    n: usize,
    chi2_samples: usize,
) -> Row {
    let b = case.bsdf;
    let wo = incident(theta_deg, back);
    let seed = (ci as u64) << 16 ^ (theta_deg * 100.0) as u64 ^ (back as u64) << 40;
    let mut rng = Pcg32::new(seed, 0x57ab);
    let mut c = Checks::default();
    check_directions(&b, wo, &mut rng, &mut c);
    let (albedo, albedo_se) = check_samples(&b, wo, n, &mut rng, &mut c);
    let energy_gain = albedo > 1.0 + ENERGY_TOL + 4.0 * albedo_se;
    let (mut chi2_p, mut chi2_hard) = (None, None);
    // The chi-square test needs a pdf that is not identically zero: skip wo exactly on the
    // horizon (one-sided models are black there) and wo below one-sided models.
    if b.has_smooth_lobe()
        && chi2_samples > 0
        && wo.z != 0.0
        && (b.is_transmissive() || !back)
        && chi2_resolvable(&b)
    {
        let sample = |wo: Vec3, u: Vec3| {
            b.sample(wo, u.x, Vec2::new(u.y, u.z)).map(|s| Sample {
                wi: s.wi,
                weight: s.weight.0.x,
                pdf: s.pdf,
                delta: s.delta,
            })
        };
        let pdf = |wo: Vec3, wi: Vec3| b.pdf(wo, wi);
        let cfg = Chi2Config {
            samples: chi2_samples,
            res_cos: 16,
            res_phi: 32,
            min_expected: 20.0,
            seed: 7 + ci as u64,
        };
        let r = pt_stats::chi2_sphere("", wo, &sample, &pdf, &cfg);
        chi2_p = Some(r.p_value);
        chi2_hard = r.hard_failure;
    }
    Row {
        case: ci,
        theta_deg,
        back,
        nonfinite: c.nonfinite,
        albedo,
        albedo_se,
        energy_gain,
        pdf_mismatch: c.pdf_mismatch,
        weight_mismatch: c.weight_mismatch,
        chi2_p,
        chi2_hard,
        chi2_fail: false,
    }
}

/// Whether the chi-square test can judge the model: its quadrature of the pdf over a 16 x 32
/// grid resolves lobes of microfacet roughness >= 0.05 (the pt-bsdf tests' smallest), but not
/// narrower ones, nor the refraction lobe of a rough dielectric with eta within 1% of 1, which
/// is nearly a delta (`wi` close to `-wo`) with a Jacobian singular at eta = 1. There the
/// first sweep found "samples in a cell where the pdf integrates to 0" and "pdf integrates to
/// 1.04" for every configuration: failures of the quadrature, not of the model. Such cases
/// are still checked sample by sample (pdf and weight consistency, finiteness, albedo). Hair
/// likewise where its narrowest longitudinal lobe is under 0.08 rad wide or its azimuthal
/// logistic scale under 0.04 (b_m 0.2 and b_n 0.15, the pt-bsdf tests' narrowest): with
/// roughness 0 the first sweep found "pdf integrates to 1.003" and p = 0 for every direction.
pub fn chi2_resolvable(b: &Bsdf) -> bool {
    const MIN_ALPHA: f32 = 0.05;
    match b {
        Bsdf::RoughConductor(m) => m.mf.alpha_u.min(m.mf.alpha_v) >= MIN_ALPHA,
        Bsdf::RoughDielectric(m) => {
            m.mf.alpha_u.min(m.mf.alpha_v) >= MIN_ALPHA && (m.eta - 1.0).abs() >= 0.01
        }
        Bsdf::RoughPlastic(m) => m.mf.alpha_u.min(m.mf.alpha_v) >= MIN_ALPHA,
        Bsdf::RoughThinFilm(m) => m.mf.alpha_u.min(m.mf.alpha_v) >= MIN_ALPHA,
        Bsdf::GltfPbr(m) => m.mf.alpha_u.min(m.mf.alpha_v) >= MIN_ALPHA,
        Bsdf::Principled(m) => {
            m.mf.alpha_u.min(m.mf.alpha_v) >= MIN_ALPHA
                && (m.clearcoat == 0.0 || m.clearcoat_alpha >= MIN_ALPHA)
                && (!m.transmissive || (m.eta - 1.0).abs() >= 0.01)
        }
        Bsdf::PrincipledThin(m) => {
            m.spec_trans == 0.0
                || [m.mf_r, m.mf_t]
                    .iter()
                    .all(|mf| mf.alpha_u.min(mf.alpha_v) >= MIN_ALPHA)
        }
        Bsdf::Hair(m) => {
            let (longitudinal, azimuthal) = m.lobe_widths();
            longitudinal >= 0.08 && azimuthal >= 0.04
        }
        _ => true,
    }
}

/// Runs the whole sweep (in parallel on the current rayon pool) and marks chi-square failures.
pub fn sweep(
    cases: &[Case],
    n: usize,
    chi2_samples: usize,
    progress: &(dyn Fn() + Sync),
) -> Vec<Row> {
    let mut jobs = Vec::new();
    for (ci, c) in cases.iter().enumerate() {
        for &t in &ANGLES_DEG {
            jobs.push((ci, t, false));
            if c.bsdf.is_transmissive() {
                jobs.push((ci, t, true));
            }
        }
    }
    let mut rows: Vec<Row> = jobs
        .par_iter()
        .map(|&(ci, t, back)| {
            let r = probe(ci, &cases[ci], t, back, n, chi2_samples);
            progress();
            r
        })
        .collect();
    let tests = rows.iter().filter(|r| r.chi2_p.is_some()).count();
    let level = pt_stats::sidak_threshold(CHI2_ALPHA, tests);
    for r in &mut rows {
        if let Some(p) = r.chi2_p {
            r.chi2_fail = r.chi2_hard.is_some() || p.is_nan() || p < level;
        }
    }
    rows
}

/// How hard [`run`] probes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StabilitySettings {
    /// Samples per probe for the albedo and the per-sample checks (at least 100).
    pub samples: usize,
    /// Samples per chi-square test (0: no chi-square tests).
    pub chi2_samples: usize,
}

impl Default for StabilitySettings {
    /// `pt stability`'s defaults: 20,000 samples per probe, 100,000 per chi-square test.
    fn default() -> Self {
        StabilitySettings {
            samples: 20_000,
            chi2_samples: 100_000,
        }
    }
}

/// The sweep's results and the clamp study.
pub struct Stability {
    /// The settings it ran with.
    pub settings: StabilitySettings,
    /// Every configuration.
    pub cases: Vec<Case>,
    /// Every probe, in the order of [`sweep`].
    pub rows: Vec<Row>,
    /// Wall time of the sweep, seconds (the clamp study not included).
    pub seconds: f64,
    /// The bias of the firefly clamp.
    pub clamp: ClampStudy,
}

/// The number of probes of `cases` ([`ANGLES_DEG`], both sides for transmissive models).
pub fn probe_count(cases: &[Case]) -> usize {
    cases
        .iter()
        .map(|c| ANGLES_DEG.len() * if c.bsdf.is_transmissive() { 2 } else { 1 })
        .sum()
}

/// Runs the sweep and the clamp study on the current rayon pool; `progress(done, total)` is
/// called after each probe.
pub fn run(s: &StabilitySettings, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<Stability> {
    if s.samples < 100 {
        return Err(LabError::Invalid(format!(
            "samples must be at least 100, got {}",
            s.samples
        )));
    }
    let start = std::time::Instant::now();
    let cases = cases();
    let total = probe_count(&cases);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let tick = || {
        progress(
            done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
            total,
        )
    };
    let rows = sweep(&cases, s.samples, s.chi2_samples, &tick);
    let seconds = start.elapsed().as_secs_f64();
    let clamp = crate::fireflies::clamp_bias_study()?;
    Ok(Stability {
        settings: *s,
        cases,
        rows,
        seconds,
        clamp,
    })
}

impl Stability {
    /// Counts over every probe.
    pub fn summary(&self) -> Summary {
        Summary::of(&self.cases, &self.rows, |_| true)
    }
}

/// Counts over a set of rows.
#[derive(Default)]
pub struct Summary {
    /// Configurations.
    pub cases: usize,
    /// Probes (configurations x incident directions).
    pub probes: usize,
    /// Non-finite values seen.
    pub nonfinite: u64,
    /// Energy gains (albedo above 1 + tolerance).
    pub gains: usize,
    /// Energy gains of in-range cases above the model's documented bound.
    pub gains_in_range: usize,
    /// Largest albedo of an in-range case.
    pub worst_albedo_in_range: f64,
    /// Largest albedo of a case beyond the documented range.
    pub worst_albedo_beyond: f64,
    /// Pdf mismatches.
    pub pdf_mismatch: u64,
    /// Weight mismatches.
    pub weight_mismatch: u64,
    /// Chi-square tests run.
    pub chi2_tests: usize,
    /// Chi-square tests failed at the family-wise level.
    pub chi2_fail: usize,
}

impl Summary {
    /// The counts over the rows whose case `keep` accepts.
    pub fn of(cases: &[Case], rows: &[Row], keep: impl Fn(&Case) -> bool) -> Summary {
        let mut s = Summary::default();
        let mut seen = std::collections::HashSet::new();
        for r in rows {
            let c = &cases[r.case];
            if !keep(c) {
                continue;
            }
            seen.insert(r.case);
            s.probes += 1;
            s.nonfinite += u64::from(r.nonfinite);
            s.gains += usize::from(r.energy_gain);
            if c.in_range {
                s.worst_albedo_in_range = s.worst_albedo_in_range.max(r.albedo);
                s.gains_in_range +=
                    usize::from(r.albedo > c.energy_bound + ENERGY_TOL + 4.0 * r.albedo_se);
            } else {
                s.worst_albedo_beyond = s.worst_albedo_beyond.max(r.albedo);
            }
            s.pdf_mismatch += u64::from(r.pdf_mismatch);
            s.weight_mismatch += u64::from(r.weight_mismatch);
            s.chi2_tests += usize::from(r.chi2_p.is_some());
            s.chi2_fail += usize::from(r.chi2_fail);
        }
        s.cases = seen.len();
        s
    }
}
