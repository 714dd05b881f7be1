//! Pictures of a BSDF model drawn from the renderer's own code (`pt lobes`, issue 4).
//!
//! Each model is a [`BsdfSpec`] built by [`crate::bsdf::build_bsdf`] exactly as a scene file
//! would build it (RGB mode), with two conveniences of this analysis: `eta` on a dielectric is
//! short for `int_ior=eta ext_ior=1`, and a `reflectance` must be one number or r,g,b in
//! [0, 1] (the scene format lets `diffuse` take any value, as Mitsuba does; a lobe chart of a
//! reflectance above 1 is a typo). [`compute`] evaluates and samples the models, [`Lobes`]
//! holds everything plotted and writes it as CSV ([`Lobes::csv`]) and as a figure
//! ([`Lobes::svg`], [`Lobes::png`]; the PNG embeds its font, DejaVu Sans, so it needs no
//! system fonts).
//!
//! Geometry, in the local frame (z = normal): the fixed direction at elevation `theta_i` is the
//! one the sampler is given (the crate's `wo`, at azimuth 180 degrees, in the x-z plane); the
//! plotted direction at `(theta_o, phi)` is the sampled one (the crate's `wi`), so the specular
//! peak is at `theta_o = +theta_i`. For reciprocal reflection models the two roles are
//! interchangeable. Plotted values are the luminance of the RGB lanes (`0.2126 R + 0.7152 G +
//! 0.0722 B`; equal to every lane for grey parameters).
//!
//! The figure (3 x 2 panels):
//! 1. polar plot, in the plane of incidence, of `f * |cos theta_o|` for each `--theta-i` (default
//!    0, 30, 60, 80 degrees); the lower half is the transmitted lobe; thin lines mark the fixed
//!    direction;
//! 2. the same for `f` alone (a Lambertian lobe is a half circle);
//! 3. directional albedo against `theta_i` from 0 to 89.9 degrees: the mean of the model's own
//!    sample weights `f cos / pdf` (`--albedo-samples` per point, error bars +-2 standard errors;
//!    transmission includes the radiance factor 1/eta^2, as in the renderer);
//! 4. for the first `theta_i`: histogram of sampled `theta_o` (fraction of samples per 2 degree
//!    bin, points) against the pdf integrated over each bin (line), with chi^2 / dof over the
//!    bins expecting at least 5 samples (about 1 when sampling matches `pdf`);
//! 5. hemisphere heat map of `f * |cos theta_o|` over `(theta_o, phi)` for the first model and
//!    the first `theta_i` (whole sphere for transmissive models);
//!
//! The CSV ([`Lobes::csv`]) holds every plotted value, columns `panel,series,theta_i,theta_o,
//! phi,f,pdf,albedo,albedo_stderr,hist` (angles in degrees): `lobe` rows (phi 0 or 180, f and
//! pdf per solid angle), `albedo` rows, `histogram` rows (`theta_o` the bin centre, `pdf` the
//! integrated pdf of the bin, `hist` the sampled fraction), `hemisphere` rows.

mod draw;
#[cfg(test)]
mod tests;

use crate::bsdf::{build_bsdf, BsdfError, BsdfSpec, PropValue};
use crate::{LabError, Result};
use pt_math::{Vec2, Vec3};
use rayon::prelude::*;
use std::fmt::Write as _;

/// What [`compute`] draws and how hard it samples.
#[derive(Clone, Debug, PartialEq)]
pub struct LobesSettings {
    /// The models, drawn on the same charts; the first gets the hemisphere map.
    pub models: Vec<BsdfSpec>,
    /// Elevations of the fixed direction, degrees, each in [0, 90); the first is also that of
    /// the histogram and the hemisphere map.
    pub theta_i: Vec<f64>,
    /// Samples per point of the albedo curve (at least 2).
    pub albedo_samples: u32,
    /// Samples of the direction histogram (at least 1).
    pub hist_samples: u32,
    /// Seed of the random numbers (results are deterministic for a seed).
    pub seed: u64,
    /// Scale each polar curve to its own maximum (the CSV keeps the absolute values).
    pub normalize: bool,
}

impl Default for LobesSettings {
    /// No models yet; `pt lobes`' defaults for the rest.
    fn default() -> Self {
        LobesSettings {
            models: Vec::new(),
            theta_i: vec![0.0, 30.0, 60.0, 80.0],
            albedo_samples: 20_000,
            hist_samples: 1_000_000,
            seed: 1,
            normalize: false,
        }
    }
}

/// A model built by the renderer's material code, read through luminance.
pub struct Model {
    /// The model with its parameters, as given ([`BsdfSpec::label`]).
    pub label: String,
    /// The model's BSDF (its parameters are constants: one BSDF everywhere).
    pub bsdf: pt_bsdf::SurfaceBsdf,
    /// Whether it has delta lobes only (no density to draw: albedo only).
    pub delta: bool,
    /// Whether it transmits (the charts then cover the lower hemisphere too).
    pub transmissive: bool,
}

/// One sampled direction: `wi`, the luminance of `f cos / pdf`.
struct Sampled {
    wi: Vec3,
    weight: f32,
    /// Whether it came from a delta lobe.
    delta: bool,
}

impl Model {
    /// Builds `spec` (with this analysis' `eta` shorthand and reflectance check, see the module
    /// doc).
    pub fn new(spec: &BsdfSpec) -> Result<Model> {
        let label = spec.label();
        check_reflectance(spec)?;
        let bsdf = build_bsdf(&eta_shorthand(spec)?)?;
        let (delta, transmissive) = (!bsdf.has_smooth_lobe(), bsdf.bsdf.is_transmissive());
        Ok(Model {
            label,
            bsdf,
            delta,
            transmissive,
        })
    }

    /// Luminance of f(wo, wi), without the cosine.
    pub fn f(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.bsdf.eval(wo, wi).luminance_rgb()
    }

    /// Solid-angle pdf of sampling `wi` given `wo`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.bsdf.pdf(wo, wi)
    }

    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<Sampled> {
        self.bsdf.sample(wo, u_lobe, u).map(|s| Sampled {
            wi: s.wi,
            weight: s.weight.luminance_rgb(),
            delta: s.delta,
        })
    }
}

/// Refuses a `reflectance` that is not one number or r,g,b, each in [0, 1] (of the model or
/// of the model inside `twosided`).
fn check_reflectance(spec: &BsdfSpec) -> Result<(), BsdfError> {
    if let Some(inner) = &spec.inner {
        return check_reflectance(inner);
    }
    let Some(v) = spec.param("reflectance") else {
        return Ok(());
    };
    let unit = |x: f32| (0.0..=1.0).contains(&x);
    let ok = match v {
        PropValue::Float(x) => unit(*x),
        PropValue::Rgb(c) => c.iter().all(|&x| unit(x)),
        _ => false,
    };
    if ok {
        return Ok(());
    }
    Err(BsdfError::Syntax(format!(
        "{}: reflectance must be one number or r,g,b, each in [0, 1], got '{}'",
        spec.model,
        crate::bsdf::value_text(v)
    )))
}

/// `eta` on a dielectric model as `int_ior=eta ext_ior=1`.
fn eta_shorthand(spec: &BsdfSpec) -> Result<BsdfSpec, BsdfError> {
    if let Some(inner) = &spec.inner {
        return Ok(BsdfSpec::two_sided(eta_shorthand(inner)?));
    }
    let Some(eta) = spec
        .param("eta")
        .filter(|_| spec.model.contains("dielectric"))
    else {
        return Ok(spec.clone());
    };
    if spec.param("int_ior").is_some() || spec.param("ext_ior").is_some() {
        return Err(BsdfError::Syntax(format!(
            "{}: give either eta or int_ior/ext_ior",
            spec.model
        )));
    }
    let mut out = BsdfSpec::new(&spec.model).with("ext_ior", 1.0);
    for (n, v) in &spec.params {
        let n = if n == "eta" { "int_ior" } else { n.as_str() };
        out = out.with(
            n,
            if n == "int_ior" {
                eta.clone()
            } else {
                v.clone()
            },
        );
    }
    Ok(out)
}

/// SplitMix64 (Steele, Lea & Flood 2014): small, seedable, good enough for these pictures.
struct Rng(u64);

impl Rng {
    fn new(seed: u64, stream: u64) -> Rng {
        let mut r = Rng(seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
        r.next();
        r
    }
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn f32(&mut self) -> f32 {
        (self.next() >> 40) as f32 * (1.0 / 16_777_216.0)
    }
}

/// The fixed direction at elevation `theta_i` (degrees), azimuth 180 degrees.
fn fixed_dir(theta_i: f64) -> Vec3 {
    let t = theta_i.to_radians();
    Vec3::new(-t.sin() as f32, 0.0, t.cos() as f32)
}

/// Direction at elevation `theta` and azimuth `phi` (degrees).
fn dir(theta: f64, phi: f64) -> Vec3 {
    let (t, p) = (theta.to_radians(), phi.to_radians());
    Vec3::new(
        (t.sin() * p.cos()) as f32,
        (t.sin() * p.sin()) as f32,
        t.cos() as f32,
    )
}

/// A point of a lobe in the plane of incidence: `angle` is signed from the normal (positive
/// towards the specular side, beyond 90 degrees: below the surface), degrees.
#[derive(Clone, Copy, Debug)]
pub struct LobePoint {
    /// Signed angle of the plotted direction from the normal, degrees.
    pub angle: f64,
    /// Luminance of f there, per steradian (no cosine).
    pub f: f64,
    /// Solid-angle pdf of sampling that direction.
    pub pdf: f64,
}

/// The lobe in the plane of incidence, every half degree over the whole circle.
pub fn lobe(model: &Model, theta_i: f64) -> Vec<LobePoint> {
    let wo = fixed_dir(theta_i);
    (0..=720)
        .map(|i| {
            let angle = -180.0 + 0.5 * i as f64;
            let wi = dir(angle, 0.0);
            LobePoint {
                angle,
                f: model.f(wo, wi) as f64,
                pdf: model.pdf(wo, wi) as f64,
            }
        })
        .collect()
}

/// A directional albedo estimate: mean of the sample weights and its standard error.
#[derive(Clone, Copy, Debug)]
pub struct Albedo {
    /// Elevation of the fixed direction, degrees.
    pub theta_i: f64,
    /// Mean of `f cos / pdf` over the model's own samples (transmission includes 1/eta^2).
    pub mean: f64,
    /// Standard error of the mean.
    pub stderr: f64,
}

/// Directional albedo at `theta_i` (degrees) from `n` samples of the model's own sampler.
pub fn albedo(model: &Model, theta_i: f64, n: u32, seed: u64) -> Albedo {
    let wo = fixed_dir(theta_i);
    let mut rng = Rng::new(seed, theta_i.to_bits());
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let (ul, u) = (rng.f32(), Vec2::new(rng.f32(), rng.f32()));
        let w = model.sample(wo, ul, u).map_or(0.0, |s| s.weight as f64);
        let w = if w.is_finite() { w } else { 0.0 };
        sum += w;
        sum2 += w * w;
    }
    let n = n.max(1) as f64;
    let mean = sum / n;
    let var = (sum2 / n - mean * mean).max(0.0) * n / (n - 1.0).max(1.0);
    Albedo {
        theta_i,
        mean,
        stderr: (var / n).sqrt(),
    }
}

/// Angles of the albedo curve: 0 to 89.9 degrees.
fn albedo_angles() -> Vec<f64> {
    (0..=60)
        .map(|i| if i == 60 { 89.9 } else { 1.5 * i as f64 })
        .collect()
}

/// Sampled-direction histogram in `theta_o` against the integrated pdf.
#[derive(Clone, Debug)]
pub struct Histogram {
    /// Bin width, degrees; bins start at 0.
    pub width: f64,
    /// Fraction of the samples per bin.
    pub observed: Vec<f64>,
    /// pdf integrated over each bin (a probability).
    pub expected: Vec<f64>,
    /// chi^2 over bins expecting at least 5 samples.
    pub chi2: f64,
    /// Its degrees of freedom (bins used - 1, at least 1).
    pub dof: usize,
}

/// Histogram of the polar angle of `n` sampled directions (2-degree bins up to `max_theta`
/// degrees) for the fixed direction at `theta_i`, against the pdf integrated over each bin.
pub fn histogram(model: &Model, theta_i: f64, n: u32, seed: u64, max_theta: f64) -> Histogram {
    let width = 2.0;
    let bins = (max_theta / width).round() as usize;
    let wo = fixed_dir(theta_i);
    let chunks = 64u32;
    let counts: Vec<u64> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut rng = Rng::new(seed, 0xC0FFEE + c as u64);
            let mut counts = vec![0u64; bins];
            let m = n / chunks + u32::from(c < n % chunks);
            for _ in 0..m {
                let (ul, u) = (rng.f32(), Vec2::new(rng.f32(), rng.f32()));
                // A delta lobe's samples have no density: the pdf leaves them out (it
                // integrates to the smooth lobes' share), so the histogram does too.
                if let Some(s) = model.sample(wo, ul, u).filter(|s| !s.delta) {
                    let theta = (s.wi.z.clamp(-1.0, 1.0) as f64).acos().to_degrees();
                    let b = (theta / width) as usize;
                    if b < bins {
                        counts[b] += 1;
                    }
                }
            }
            counts
        })
        .reduce(
            || vec![0u64; bins],
            |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect(),
        );
    // Midpoint rule over each bin: 16 rows in theta, 720 columns in phi.
    let (sub, nphi) = (16usize, 720usize);
    let expected: Vec<f64> = (0..bins)
        .into_par_iter()
        .map(|b| {
            let dt = (width / sub as f64).to_radians();
            let dp = std::f64::consts::TAU / nphi as f64;
            let mut sum = 0.0;
            for i in 0..sub {
                let theta = b as f64 * width + (i as f64 + 0.5) * width / sub as f64;
                let sin = theta.to_radians().sin();
                for j in 0..nphi {
                    let phi = -180.0 + (j as f64 + 0.5) * 360.0 / nphi as f64;
                    sum += model.pdf(wo, dir(theta, phi)) as f64 * sin;
                }
            }
            sum * dt * dp
        })
        .collect();
    let total = n.max(1) as f64;
    let observed: Vec<f64> = counts.iter().map(|&c| c as f64 / total).collect();
    let (mut chi2, mut dof) = (0.0, 0usize);
    for (o, e) in observed.iter().zip(&expected) {
        let (o, e) = (o * total, e * total);
        if e >= 5.0 {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    Histogram {
        width,
        observed,
        expected,
        chi2,
        dof: dof.saturating_sub(1).max(1),
    }
}

/// Everything plotted (see the module doc).
pub struct Lobes {
    /// The models, in the order of the settings.
    pub models: Vec<Model>,
    /// Elevations of the fixed direction, degrees.
    pub theta_i: Vec<f64>,
    /// Per model, per theta_i, the lobe in the plane of incidence (empty for delta models).
    pub lobes: Vec<Vec<Vec<LobePoint>>>,
    /// Per model, the albedo curve from 0 to 89.9 degrees.
    pub albedo: Vec<Vec<Albedo>>,
    /// Per model, the direction histogram at the first theta_i (None for delta models).
    pub hist: Vec<Option<Histogram>>,
    /// Heat map of the first smooth model at the first theta_i.
    pub heat: Option<Heat>,
    /// Largest plotted theta_o, degrees: 90, or 180 with a smooth transmissive model.
    pub max_theta: f64,
    /// The sampling settings, as the legend shows them.
    pub settings: String,
    /// Whether each polar curve is scaled to its own maximum.
    pub normalize: bool,
}

/// Hemisphere (or sphere) map of one model: rows in theta_o, columns in phi.
pub struct Heat {
    /// Index of the model.
    pub model: usize,
    /// Rows in theta_o.
    pub rows: usize,
    /// Columns in phi, over 360 degrees.
    pub cols: usize,
    /// Largest theta_o, degrees (90, or 180 for transmissive models).
    pub max_theta: f64,
    /// (f, pdf) per cell centre, row-major.
    pub cells: Vec<(f64, f64)>,
}

impl Heat {
    /// theta_o of row `r`'s centre, degrees.
    pub fn theta(&self, r: usize) -> f64 {
        (r as f64 + 0.5) * self.max_theta / self.rows as f64
    }
    /// phi of column `c`'s centre, degrees in [-180, 180).
    pub fn phi(&self, c: usize) -> f64 {
        -180.0 + (c as f64 + 0.5) * 360.0 / self.cols as f64
    }
}

/// Checks the settings (messages name the settings' fields).
fn check(s: &LobesSettings) -> Result<()> {
    let invalid = |m: String| Err(LabError::Invalid(m));
    if s.models.is_empty() {
        return invalid("lobes: no model to draw".into());
    }
    if s.theta_i.is_empty() {
        return invalid("theta_i: give at least one angle".into());
    }
    if let Some(t) = s.theta_i.iter().find(|t| !(0.0..90.0).contains(*t)) {
        return invalid(format!("theta_i must be in [0, 90) degrees, got {t}"));
    }
    if s.albedo_samples < 2 || s.hist_samples < 1 {
        return invalid("albedo_samples must be at least 2 and hist_samples at least 1".into());
    }
    Ok(())
}

/// Builds the models and computes everything plotted (in parallel on the current rayon pool).
pub fn compute(s: &LobesSettings) -> Result<Lobes> {
    check(s)?;
    let models: Vec<Model> = s.models.iter().map(Model::new).collect::<Result<_>>()?;
    let theta_i = s.theta_i.clone();
    let lobes = models
        .iter()
        .map(|m| {
            if m.delta {
                Vec::new()
            } else {
                theta_i.iter().map(|&t| lobe(m, t)).collect()
            }
        })
        .collect();
    let angles = albedo_angles();
    let albedo = models
        .iter()
        .enumerate()
        .map(|(k, m)| {
            angles
                .par_iter()
                .map(|&t| albedo(m, t, s.albedo_samples, s.seed.wrapping_add(k as u64)))
                .collect()
        })
        .collect();
    let max_theta = if models.iter().any(|m| m.transmissive && !m.delta) {
        180.0
    } else {
        90.0
    };
    let hist = models
        .iter()
        .enumerate()
        .map(|(k, m)| {
            (!m.delta).then(|| {
                histogram(
                    m,
                    theta_i[0],
                    s.hist_samples,
                    s.seed.wrapping_add(1000 + k as u64),
                    max_theta,
                )
            })
        })
        .collect();
    let heat = heat_map(&models, theta_i[0]);
    let settings = format!(
        "albedo: {} samples per point (error bars +-2 s.e.)\nhistogram: {} samples; seed {}",
        s.albedo_samples, s.hist_samples, s.seed
    );
    Ok(Lobes {
        models,
        theta_i,
        lobes,
        albedo,
        hist,
        heat,
        max_theta,
        settings,
        normalize: s.normalize,
    })
}

/// The hemisphere map of the first smooth model at `theta_i` (degrees).
fn heat_map(models: &[Model], theta_i: f64) -> Option<Heat> {
    models.iter().position(|m| !m.delta).map(|k| {
        let m = &models[k];
        let ht = if m.transmissive { 180.0 } else { 90.0 };
        let (rows, cols) = (if m.transmissive { 120 } else { 60 }, 144);
        let wo = fixed_dir(theta_i);
        let mut heat = Heat {
            model: k,
            rows,
            cols,
            max_theta: ht,
            cells: Vec::new(),
        };
        heat.cells = (0..rows * cols)
            .map(|i| {
                let wi = dir(heat.theta(i / cols), heat.phi(i % cols));
                (m.f(wo, wi) as f64, m.pdf(wo, wi) as f64)
            })
            .collect();
        heat
    })
}

impl Lobes {
    /// One line per smooth model: how its sampling matches its pdf at the first theta_i.
    pub fn sampling_summary(&self) -> Vec<String> {
        self.models
            .iter()
            .zip(&self.hist)
            .filter_map(|(m, h)| {
                h.as_ref().map(|h| {
                    format!(
                        "{}: sampling vs pdf at theta_i = {}: chi2/dof = {:.3} ({} bins)",
                        m.label,
                        self.theta_i[0],
                        h.chi2 / h.dof as f64,
                        h.dof + 1
                    )
                })
            })
            .collect()
    }

    /// Every plotted value as CSV (see the module doc).
    pub fn csv(&self) -> String {
        let d = self;
        let mut s =
            String::from("panel,series,theta_i,theta_o,phi,f,pdf,albedo,albedo_stderr,hist\n");
        let q = |l: &str| format!("\"{}\"", l.replace('"', "\"\""));
        for (m, per) in d.models.iter().zip(&d.lobes) {
            for (t, pts) in d.theta_i.iter().zip(per) {
                for p in pts {
                    let (theta, phi) = if p.angle >= 0.0 {
                        (p.angle, 0.0)
                    } else {
                        (-p.angle, 180.0)
                    };
                    let _ = writeln!(
                        s,
                        "lobe,{},{t},{theta},{phi},{},{},,,",
                        q(&m.label),
                        p.f,
                        p.pdf
                    );
                }
            }
        }
        for (m, al) in d.models.iter().zip(&d.albedo) {
            for a in al {
                let _ = writeln!(
                    s,
                    "albedo,{},{},,,,,{},{},",
                    q(&m.label),
                    a.theta_i,
                    a.mean,
                    a.stderr
                );
            }
        }
        for (m, h) in d.models.iter().zip(&d.hist) {
            if let Some(h) = h {
                for (b, (o, e)) in h.observed.iter().zip(&h.expected).enumerate() {
                    let _ = writeln!(
                        s,
                        "histogram,{},{},{},,,{e},,,{o}",
                        q(&m.label),
                        d.theta_i[0],
                        (b as f64 + 0.5) * h.width
                    );
                }
            }
        }
        if let Some(h) = &d.heat {
            for (i, (f, pdf)) in h.cells.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "hemisphere,{},{},{},{},{f},{pdf},,,",
                    q(&d.models[h.model].label),
                    d.theta_i[0],
                    h.theta(i / h.cols),
                    h.phi(i % h.cols)
                );
            }
        }
        s
    }

    /// The figure as SVG text.
    pub fn svg(&self) -> Result<String> {
        crate::chart::chart_svg(self, draw::SIZE, "the figure")
    }

    /// The figure as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>> {
        crate::chart::chart_png(self, draw::SIZE, "the figure")
    }
}
