//! `pt lobes`: pictures of a BSDF model drawn from the renderer's own code (issue 4).
//!
//! ```text
//! pt lobes MODEL [--param NAME=VALUE]... [--compare "MODEL NAME=VALUE ..."]...
//!          [--theta-i DEG]... -o lobes.svg|lobes.png [--csv FILE]
//!          [--albedo-samples N] [--hist-samples N] [--seed S]
//! ```
//!
//! MODEL is a BSDF plugin name of the scene format, optionally followed by its parameters in the
//! same string: `diffuse`, `orennayar`, `minnaert`, `roughconductor`, `roughdielectric`, and
//! (albedo panel only, their lobes are deltas) `conductor`, `dielectric`, `thindielectric`.
//! Parameters have their scene-file names and defaults: `reflectance` (one number, or `r,g,b`),
//! `sigma` (radians), `variant` (qualitative, full, fujii, eon), `k` (Minnaert exponent, or a
//! conductor's extinction), `alpha` or `alpha_u` + `alpha_v`, `distribution` (beckmann, ggx),
//! `material` (a conductor name such as `Au`), `eta` + `k` (conductor), `int_ior` / `ext_ior`
//! (a number or a name such as `bk7`), `specular_reflectance`; `eta` on a dielectric is short for
//! `int_ior=eta ext_ior=1`. The model is built exactly as a scene file would build it: the
//! parameters become a `<bsdf>` element read by `pt_scene` and turned into the BSDF by
//! `pt_render`'s material code (RGB mode), so names, defaults, named materials and validation
//! are the scene format's. Each `--compare` adds one more model, drawn on the same charts.
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
//! 6. a legend: the models with their full parameter lists, and the sampling settings.
//!
//! `--csv FILE` writes every plotted value, columns `panel,series,theta_i,theta_o,phi,f,pdf,
//! albedo,albedo_stderr,hist` (angles in degrees): `lobe` rows (phi 0 or 180, f and pdf per
//! solid angle), `albedo` rows, `histogram` rows (`theta_o` the bin centre, `pdf` the integrated
//! pdf of the bin, `hist` the sampled fraction), `hemisphere` rows. The SVG always works; the PNG
//! embeds its font (DejaVu Sans), so it needs no system fonts. Outputs are written atomically.
//!
//! Examples:
//!
//! ```text
//! pt lobes diffuse -o lambert.png
//! pt lobes orennayar --param sigma=0.5 --param variant=full --theta-i 0 --theta-i 60 -o on.svg
//! pt lobes "orennayar sigma=0.3" --compare "orennayar sigma=1.0" --compare diffuse -o on.png
//! pt lobes "roughconductor alpha=0.2 distribution=ggx material=Au" --csv au.csv -o au.png
//! pt lobes "roughdielectric alpha=0.3 int_ior=1.5" --compare "dielectric int_ior=1.5" -o glass.png
//! ```
//!
//! Errors (unknown model or parameter, bad value, unwritable output) exit with code 2.

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use plotters::coord::Shift;
use plotters::prelude::*;
use pt_math::{Vec2, Vec3};
use pt_render::{BvhKind, LightSelection, Scene};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Charts of a BSDF model from the renderer's own code: polar lobes, directional albedo, sampled
/// directions against the pdf, hemisphere map (SVG or PNG, optional CSV).
#[derive(Args, Debug)]
pub struct LobesArgs {
    /// The model: a scene-format BSDF name, optionally with parameters in the same (quoted)
    /// string, e.g. "orennayar sigma=0.3 variant=full". Models: diffuse, orennayar, minnaert,
    /// roughconductor, roughdielectric; conductor, dielectric, thindielectric (albedo only).
    pub model: String,
    /// A parameter of MODEL (repeatable), with its scene-file name: reflectance, sigma, variant,
    /// k, alpha, alpha_u, alpha_v, distribution, material, eta, int_ior, ext_ior,
    /// specular_reflectance.
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// One more model on the same charts (repeatable), written like MODEL with its parameters:
    /// --compare "orennayar sigma=1.0".
    #[arg(long = "compare", value_name = "\"MODEL NAME=VALUE ...\"")]
    pub compare: Vec<String>,
    /// Elevation of the fixed direction in degrees, in [0, 90) (repeatable or comma-separated).
    #[arg(long = "theta-i", value_name = "DEG", value_delimiter = ',', default_values_t = [0.0, 30.0, 60.0, 80.0])]
    pub theta_i: Vec<f64>,
    /// Output figure, .svg or .png.
    #[arg(short = 'o', long = "output", value_name = "FILE.svg|FILE.png")]
    pub output: PathBuf,
    /// Also write the plotted values as CSV.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Samples per point of the albedo curve.
    #[arg(long, default_value_t = 20_000)]
    pub albedo_samples: u32,
    /// Samples of the direction histogram.
    #[arg(long, default_value_t = 1_000_000)]
    pub hist_samples: u32,
    /// Seed of the random numbers (results are deterministic for a seed).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Scale each polar curve to its own maximum (to compare shapes of lobes whose peaks differ
    /// by orders of magnitude); the CSV keeps the absolute values.
    #[arg(long)]
    pub normalize: bool,
}

/// Model names of the scene format and the parameters each accepts.
const MODELS: &[(&str, &[&str])] = &[
    ("diffuse", &["reflectance"]),
    ("orennayar", &["reflectance", "sigma", "variant"]),
    ("minnaert", &["reflectance", "k"]),
    (
        "roughconductor",
        &[
            "material",
            "eta",
            "k",
            "specular_reflectance",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
        ],
    ),
    (
        "roughdielectric",
        &[
            "int_ior",
            "ext_ior",
            "eta",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
        ],
    ),
    (
        "conductor",
        &["material", "eta", "k", "specular_reflectance"],
    ),
    ("dielectric", &["int_ior", "ext_ior", "eta"]),
    ("thindielectric", &["int_ior", "ext_ior", "eta"]),
    (
        "roughplastic",
        &[
            "diffuse_reflectance",
            "specular_reflectance",
            "int_ior",
            "ext_ior",
            "distribution",
            "alpha",
            "nonlinear",
        ],
    ),
    (
        "thinfilm",
        &[
            "thickness",
            "film_ior",
            "ext_ior",
            "int_ior",
            "material",
            "eta",
            "k",
        ],
    ),
    (
        "roughthinfilm",
        &[
            "thickness",
            "film_ior",
            "ext_ior",
            "int_ior",
            "material",
            "eta",
            "k",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
        ],
    ),
];

/// A model and its parameters as written by the user.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Spec {
    model: String,
    params: Vec<(String, String)>,
}

impl Spec {
    /// Parses "MODEL name=value ..." (whitespace-separated).
    pub(crate) fn parse(text: &str) -> Result<Spec> {
        let mut words = text.split_whitespace();
        let Some(model) = words.next() else {
            bail!("empty model specification")
        };
        let mut spec = Spec {
            model: model.to_ascii_lowercase(),
            params: Vec::new(),
        };
        let Some(&(_, known)) = MODELS.iter().find(|(m, _)| *m == spec.model) else {
            let names: Vec<&str> = MODELS.iter().map(|m| m.0).collect();
            bail!("unknown model '{model}' (known: {})", names.join(", "))
        };
        for w in words {
            spec.add_param(w, known)?;
        }
        Ok(spec)
    }

    fn add_param(&mut self, word: &str, known: &[&str]) -> Result<()> {
        let Some((name, value)) = word.split_once('=') else {
            bail!("{}: expected NAME=VALUE, got '{word}'", self.model)
        };
        let (name, value) = (name.trim().to_ascii_lowercase(), value.trim().to_string());
        if !known.contains(&name.as_str()) {
            bail!(
                "{}: unknown parameter '{name}' (parameters: {})",
                self.model,
                known.join(", ")
            )
        }
        if value.is_empty() {
            bail!("{}: parameter '{name}' has no value", self.model)
        }
        if name == "reflectance" {
            // The scene format lets `diffuse` take any value (as Mitsuba does); a lobe chart
            // of a reflectance above 1 is a typo, so it is refused here for every model.
            let parts: Vec<Option<f64>> = value
                .split(',')
                .map(|p| p.trim().parse::<f64>().ok())
                .collect();
            let ok = (parts.len() == 1 || parts.len() == 3)
                && parts
                    .iter()
                    .all(|p| p.is_some_and(|x| (0.0..=1.0).contains(&x)));
            if !ok {
                bail!(
                    "{}: reflectance must be one number or r,g,b, each in [0, 1], got '{value}'",
                    self.model
                )
            }
        }
        if self.params.iter().any(|(n, _)| *n == name) {
            bail!("{}: parameter '{name}' given twice", self.model)
        }
        self.params.push((name, value));
        Ok(())
    }

    /// The label of the model on the charts: "orennayar sigma=0.3".
    pub(crate) fn label(&self) -> String {
        let mut s = self.model.clone();
        for (n, v) in &self.params {
            let _ = write!(s, " {n}={v}");
        }
        s
    }

    /// The `<bsdf>` element of a scene file with these parameters.
    fn xml(&self) -> Result<String> {
        let dielectric = self.model.contains("dielectric");
        let mut props = String::new();
        for (name, value) in &self.params {
            let (name, value) = if dielectric && name == "eta" {
                if self
                    .params
                    .iter()
                    .any(|(n, _)| n == "int_ior" || n == "ext_ior")
                {
                    bail!("{}: give either eta or int_ior/ext_ior", self.model)
                }
                props.push_str(r#"<float name="ext_ior" value="1"/>"#);
                ("int_ior", value.as_str())
            } else {
                (name.as_str(), value.as_str())
            };
            let esc = xml_escape(value);
            let numbers: Vec<Option<f64>> = value
                .split(',')
                .map(|p| p.trim().parse::<f64>().ok())
                .collect();
            if value.parse::<f64>().is_ok() {
                let _ = write!(props, r#"<float name="{name}" value="{esc}"/>"#);
            } else if value == "true" || value == "false" {
                let _ = write!(props, r#"<boolean name="{name}" value="{esc}"/>"#);
            } else if numbers.len() == 3 && numbers.iter().all(Option::is_some) {
                let _ = write!(props, r#"<rgb name="{name}" value="{esc}"/>"#);
            } else {
                let _ = write!(props, r#"<string name="{name}" value="{esc}"/>"#);
            }
        }
        Ok(format!(
            r#"<scene version="3.0.0"><shape type="sphere"><bsdf type="{}">{props}</bsdf></shape></scene>"#,
            self.model
        ))
    }
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A model built by the renderer's material code, read through luminance.
pub(crate) struct Model {
    label: String,
    /// The model's BSDF (its parameters are constants: one BSDF everywhere).
    bsdf: pt_bsdf::SurfaceBsdf,
    delta: bool,
    transmissive: bool,
}

/// One sampled direction: `wi`, the luminance of `f cos / pdf`.
struct Sampled {
    wi: Vec3,
    weight: f32,
}

impl Model {
    pub(crate) fn new(spec: &Spec) -> Result<Model> {
        let label = spec.label();
        let xml = spec.xml()?;
        let desc = pt_scene::load_str(&xml, Path::new("<lobes>"), Path::new("."), &[])
            .map_err(|e| anyhow!("{label}: {}", e.message))?;
        let scene = Scene::build_with_mode(
            &desc,
            BvhKind::default(),
            LightSelection::default(),
            Some(pt_spectrum::ColorMode::Rgb),
        )
        .map_err(|e| anyhow!("{label}: {}", e.message))?;
        let bsdf = scene.materials[0]
            .fixed
            .ok_or_else(|| anyhow!("{label}: the model's parameters must be constants"))?;
        let (delta, transmissive) = (!bsdf.has_smooth_lobe(), bsdf.bsdf.is_transmissive());
        Ok(Model {
            label,
            bsdf,
            delta,
            transmissive,
        })
    }

    /// Luminance of f(wo, wi), without the cosine.
    fn f(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.bsdf.eval(wo, wi).luminance_rgb()
    }

    /// Solid-angle pdf of sampling `wi` given `wo`.
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.bsdf.pdf(wo, wi)
    }

    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<Sampled> {
        self.bsdf.sample(wo, u_lobe, u).map(|s| Sampled {
            wi: s.wi,
            weight: s.weight.luminance_rgb(),
        })
    }
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
/// towards the specular side, beyond 90 degrees: below the surface).
#[derive(Clone, Copy, Debug)]
pub(crate) struct LobePoint {
    angle: f64,
    f: f64,
    pdf: f64,
}

/// The lobe in the plane of incidence, every half degree over the whole circle.
pub(crate) fn lobe(model: &Model, theta_i: f64) -> Vec<LobePoint> {
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
pub(crate) struct Albedo {
    theta_i: f64,
    mean: f64,
    stderr: f64,
}

/// Directional albedo at `theta_i` from `n` samples of the model's own sampler.
pub(crate) fn albedo(model: &Model, theta_i: f64, n: u32, seed: u64) -> Albedo {
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
pub(crate) struct Histogram {
    /// Bin width, degrees; bins start at 0.
    width: f64,
    /// Fraction of the samples per bin.
    observed: Vec<f64>,
    /// pdf integrated over each bin (a probability).
    expected: Vec<f64>,
    /// chi^2 over bins expecting at least 5 samples, and its degrees of freedom.
    chi2: f64,
    dof: usize,
}

pub(crate) fn histogram(
    model: &Model,
    theta_i: f64,
    n: u32,
    seed: u64,
    max_theta: f64,
) -> Histogram {
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
                if let Some(s) = model.sample(wo, ul, u) {
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

/// Everything plotted.
struct Data {
    models: Vec<Model>,
    theta_i: Vec<f64>,
    /// Per model, per theta_i (empty for delta models).
    lobes: Vec<Vec<Vec<LobePoint>>>,
    albedo: Vec<Vec<Albedo>>,
    /// Per model (None for delta models).
    hist: Vec<Option<Histogram>>,
    /// Heat map of the first smooth model: rows theta_o, columns phi, values f cos.
    heat: Option<Heat>,
    max_theta: f64,
    settings: String,
    normalize: bool,
}

struct Heat {
    model: usize,
    rows: usize,
    cols: usize,
    max_theta: f64,
    /// (f, pdf) per cell centre, row-major.
    cells: Vec<(f64, f64)>,
}

impl Heat {
    fn theta(&self, r: usize) -> f64 {
        (r as f64 + 0.5) * self.max_theta / self.rows as f64
    }
    fn phi(&self, c: usize) -> f64 {
        -180.0 + (c as f64 + 0.5) * 360.0 / self.cols as f64
    }
}

/// Runs `pt lobes`.
pub fn run(args: LobesArgs) -> Result<ExitCode> {
    let mut first = Spec::parse(&args.model)?;
    let known = MODELS
        .iter()
        .find(|(m, _)| *m == first.model)
        .map(|m| m.1)
        .unwrap_or(&[]);
    for p in &args.params {
        first.add_param(p, known)?;
    }
    let mut specs = vec![first];
    for c in &args.compare {
        specs.push(Spec::parse(c).with_context(|| format!("--compare \"{c}\""))?);
    }
    for &t in &args.theta_i {
        if !(0.0..90.0).contains(&t) {
            bail!("--theta-i must be in [0, 90) degrees, got {t}")
        }
    }
    if args.albedo_samples < 2 || args.hist_samples < 1 {
        bail!("--albedo-samples must be at least 2 and --hist-samples at least 1")
    }
    let ext = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let png = match ext.as_deref() {
        Some("png") => true,
        Some("svg") => false,
        _ => bail!(
            "-o '{}': the figure must be .svg or .png",
            args.output.display()
        ),
    };
    let models: Vec<Model> = specs.iter().map(Model::new).collect::<Result<_>>()?;
    let data = compute(models, &args);
    for (m, h) in data.models.iter().zip(&data.hist) {
        if let Some(h) = h {
            eprintln!(
                "{}: sampling vs pdf at theta_i = {}: chi2/dof = {:.3} ({} bins)",
                m.label,
                data.theta_i[0],
                h.chi2 / h.dof as f64,
                h.dof + 1
            );
        }
    }
    if let Some(csv) = &args.csv {
        write_atomic(csv, csv_text(&data).as_bytes())?;
    }
    let bytes = if png {
        render_png(&data)?
    } else {
        render_svg(&data)?.into_bytes()
    };
    write_atomic(&args.output, &bytes)?;
    Ok(ExitCode::SUCCESS)
}

fn compute(models: Vec<Model>, args: &LobesArgs) -> Data {
    let theta_i = args.theta_i.clone();
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
                .map(|&t| albedo(m, t, args.albedo_samples, args.seed.wrapping_add(k as u64)))
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
                    args.hist_samples,
                    args.seed.wrapping_add(1000 + k as u64),
                    max_theta,
                )
            })
        })
        .collect();
    let heat = models.iter().position(|m| !m.delta).map(|k| {
        let m = &models[k];
        let ht = if m.transmissive { 180.0 } else { 90.0 };
        let (rows, cols) = (if m.transmissive { 120 } else { 60 }, 144);
        let wo = fixed_dir(theta_i[0]);
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
    });
    let settings = format!(
        "albedo: {} samples per point (error bars +-2 s.e.)\nhistogram: {} samples; seed {}",
        args.albedo_samples, args.hist_samples, args.seed
    );
    Data {
        models,
        theta_i,
        lobes,
        albedo,
        hist,
        heat,
        max_theta,
        settings,
        normalize: args.normalize,
    }
}

fn csv_text(d: &Data) -> String {
    let mut s = String::from("panel,series,theta_i,theta_o,phi,f,pdf,albedo,albedo_stderr,hist\n");
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

const SIZE: (u32, u32) = (1800, 1100);
const FONT: &str = "sans-serif";

use crate::converge::write_atomic;

impl crate::converge::Chart for Data {
    fn draw_on<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        draw(root, self).map_err(|e| e.to_string())
    }
}

fn render_svg(d: &Data) -> Result<String> {
    crate::converge::chart_svg(d, SIZE, "the figure")
}

fn render_png(d: &Data) -> Result<Vec<u8>> {
    crate::converge::chart_png(d, SIZE, "the figure")
}

/// Tableau 10 colours.
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

fn palette(i: usize) -> RGBColor {
    let (r, g, b) = PALETTE[i % PALETTE.len()];
    RGBColor(r, g, b)
}

/// Colour of model `m` at incident angle index `a`: one hue per angle for a single model, one
/// hue per model (darker for larger angles) otherwise.
fn series_colour(d: &Data, m: usize, a: usize) -> RGBColor {
    if d.models.len() == 1 {
        return palette(a);
    }
    let RGBColor(r, g, b) = palette(m);
    let k = 1.0 - 0.55 * a as f64 / d.theta_i.len().max(2) as f64;
    RGBColor(
        (r as f64 * k) as u8,
        (g as f64 * k) as u8,
        (b as f64 * k) as u8,
    )
}

/// Viridis, by linear interpolation between five stops.
fn viridis(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68., 1., 84.),
        (59., 82., 139.),
        (33., 145., 140.),
        (94., 201., 98.),
        (253., 231., 37.),
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(
        (a.0 + (b.0 - a.0) * f) as u8,
        (a.1 + (b.1 - a.1) * f) as u8,
        (a.2 + (b.2 - a.2) * f) as u8,
    )
}

type DrawResult = std::result::Result<(), String>;

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, d: &Data) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let root = root
        .titled(
            "pt lobes: BSDF lobes, albedo and sampling (luminance of the RGB lanes)",
            (FONT, 26),
        )
        .map_err(e)?;
    let panels = root.split_evenly((2, 3));
    polar(&panels[0], d, true)?;
    polar(&panels[1], d, false)?;
    heat_panel(&panels[2], d)?;
    albedo_panel(&panels[3], d)?;
    hist_panel(&panels[4], d)?;
    legend_panel(&panels[5], d)?;
    Ok(())
}

fn no_data<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    why: &str,
) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let (w, h) = area.dim_in_pixel();
    area.draw(&Text::new(title.to_string(), (20, 10), (FONT, 20)))
        .map_err(e)?;
    area.draw(&Text::new(
        why.to_string(),
        (w as i32 / 6, h as i32 / 2),
        (FONT, 16).into_font().color(&RGBColor(120, 120, 120)),
    ))
    .map_err(e)
}

fn polar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    d: &Data,
    with_cos: bool,
) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let title = if with_cos {
        "(1) f * |cos theta_o|, plane of incidence"
    } else {
        "(2) f (no cosine), plane of incidence"
    };
    let raw = |p: &LobePoint| {
        let v = if with_cos {
            p.f * p.angle.to_radians().cos().abs()
        } else {
            p.f
        };
        if v.is_finite() {
            v
        } else {
            0.0
        }
    };
    let curve_max = |pts: &[LobePoint]| pts.iter().map(raw).fold(0.0f64, f64::max);
    let peak = d
        .lobes
        .iter()
        .flatten()
        .map(|c| curve_max(c))
        .fold(0.0f64, f64::max);
    let rmax = if d.normalize { 1.0 } else { peak };
    if peak <= 0.0 {
        return no_data(area, title, "delta lobes only: no density to draw");
    }
    let r = rmax * 1.08;
    let transmissive = d.models.iter().any(|m| m.transmissive && !m.delta);
    let y0 = if transmissive { -r } else { -0.08 * r };
    // Equal scales on both axes (the plot area is about (w - 70) x (h - 75) pixels): widen
    // whichever range is short.
    let (w, h) = area.dim_in_pixel();
    let aspect = (w as f64 - 70.0) / (h as f64 - 75.0);
    let (half_x, r) = if 2.0 * r / (r - y0) > aspect {
        (r, y0 + 2.0 * r / aspect)
    } else {
        ((r - y0) * aspect / 2.0, r)
    };
    let mut chart = ChartBuilder::on(area)
        .caption(
            if d.normalize {
                format!("{title} (each curve / its max)")
            } else {
                format!("{title} (max {rmax:.4})")
            },
            (FONT, 18),
        )
        .margin(8)
        .x_label_area_size(28)
        .y_label_area_size(52)
        .build_cartesian_2d(-half_x..half_x, y0..r)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .label_style((FONT, 12))
        .draw()
        .map_err(e)?;
    let grey = RGBColor(200, 200, 200);
    for k in 1..=4 {
        let rr = rmax * k as f64 / 4.0;
        let lo = if transmissive { -180 } else { -90 };
        let pts: Vec<(f64, f64)> = (lo..=(-lo))
            .map(|a| {
                (
                    rr * (a as f64).to_radians().sin(),
                    rr * (a as f64).to_radians().cos(),
                )
            })
            .collect();
        chart.draw_series(LineSeries::new(pts, &grey)).map_err(e)?;
    }
    chart
        .draw_series(LineSeries::new(
            vec![(-half_x, 0.0), (half_x, 0.0)],
            BLACK.stroke_width(2),
        ))
        .map_err(e)?;
    for (m, per) in d.lobes.iter().enumerate() {
        for (a, pts) in per.iter().enumerate() {
            let c = series_colour(d, m, a);
            let t = d.theta_i[a].to_radians();
            chart
                .draw_series(LineSeries::new(
                    vec![(0.0, 0.0), (-r * t.sin(), r * t.cos())],
                    c.mix(0.5).stroke_width(1),
                ))
                .map_err(e)?;
            let scale = if d.normalize {
                1.0 / curve_max(pts).max(f64::MIN_POSITIVE)
            } else {
                1.0
            };
            let xy: Vec<(f64, f64)> = pts
                .iter()
                .map(|p| {
                    let v = raw(p) * scale;
                    let a = p.angle.to_radians();
                    (v * a.sin(), v * a.cos())
                })
                .collect();
            let label = if d.models.len() == 1 {
                format!("theta_i = {}", d.theta_i[a])
            } else {
                format!("{} @ {}", d.models[m].label, d.theta_i[a])
            };
            chart
                .draw_series(LineSeries::new(xy, c.stroke_width(2)))
                .map_err(e)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
        }
    }
    if with_cos {
        legend(&mut chart, SeriesLabelPosition::UpperLeft).map_err(e)?;
    }
    Ok(())
}

fn albedo_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &Data) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let top = d
        .albedo
        .iter()
        .flatten()
        .map(|a| a.mean + 2.0 * a.stderr)
        .filter(|v| v.is_finite())
        .fold(1.0f64, f64::max)
        * 1.05;
    let mut chart = ChartBuilder::on(area)
        .caption(
            "(3) directional albedo E[f cos / pdf] (own sampler)",
            (FONT, 18),
        )
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(52)
        .build_cartesian_2d(0.0..90.0, 0.0..top)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("theta_i (degrees)")
        .y_desc("albedo")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    chart
        .draw_series(LineSeries::new(
            vec![(0.0, 1.0), (90.0, 1.0)],
            RGBColor(150, 150, 150),
        ))
        .map_err(e)?;
    for (m, al) in d.albedo.iter().enumerate() {
        let c = palette(m);
        chart
            .draw_series(LineSeries::new(
                al.iter().map(|a| (a.theta_i, a.mean)),
                c.stroke_width(2),
            ))
            .map_err(e)?
            .label(d.models[m].label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        chart
            // plotters' ErrorBar needs its `errorbar` feature: plain vertical segments instead.
            .draw_series(al.iter().map(|a| {
                PathElement::new(
                    vec![
                        (a.theta_i, a.mean - 2.0 * a.stderr),
                        (a.theta_i, a.mean + 2.0 * a.stderr),
                    ],
                    c.stroke_width(1),
                )
            }))
            .map_err(e)?;
    }
    legend(&mut chart, SeriesLabelPosition::LowerLeft).map_err(e)?;
    Ok(())
}

/// The series legend every panel uses (light background, grey border, 12 px text).
fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(RGBColor(200, 200, 200))
        .label_font((FONT, 12))
        .draw()
}

fn hist_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &Data) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let title = format!(
        "(4) sampled theta_o at theta_i = {}: histogram vs integrated pdf",
        d.theta_i[0]
    );
    let top = d
        .hist
        .iter()
        .flatten()
        .flat_map(|h| h.observed.iter().chain(&h.expected))
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    if top <= 0.0 {
        return no_data(
            area,
            &title,
            "delta lobes only: no density to sample against",
        );
    }
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 18))
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..d.max_theta, 0.0..top * 1.08)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("theta_o (degrees; > 90: transmitted)")
        .y_desc("fraction of samples per 2 degree bin")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    for (m, h) in d.hist.iter().enumerate() {
        let Some(h) = h else { continue };
        let c = palette(m);
        let centre = |b: usize| (b as f64 + 0.5) * h.width;
        chart
            .draw_series(LineSeries::new(
                h.expected.iter().enumerate().map(|(b, &v)| (centre(b), v)),
                c.stroke_width(2),
            ))
            .map_err(e)?
            .label(format!(
                "{}: pdf (line), samples (dots), chi2/dof {:.2}",
                d.models[m].label,
                h.chi2 / h.dof as f64
            ))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        chart
            .draw_series(
                h.observed
                    .iter()
                    .enumerate()
                    .map(|(b, &v)| Circle::new((centre(b), v), 2, c.filled())),
            )
            .map_err(e)?;
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight).map_err(e)?;
    Ok(())
}

fn heat_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &Data) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let Some(h) = &d.heat else {
        return no_data(
            area,
            "(5) f * |cos theta_o| over the sphere",
            "delta lobes only",
        );
    };
    let value = |i: usize| {
        let v = h.cells[i].0 * h.theta(i / h.cols).to_radians().cos().abs();
        if v.is_finite() {
            v
        } else {
            0.0
        }
    };
    let vmax = (0..h.cells.len()).map(value).fold(0.0f64, f64::max);
    let title = format!(
        "(5) f*|cos theta_o| of model {} at theta_i = {} (sqrt colour scale)",
        h.model + 1,
        d.theta_i[0]
    );
    let (pw, _) = area.dim_in_pixel();
    let (main, bar) = area.split_horizontally(pw.saturating_sub(70));
    let mut chart = ChartBuilder::on(&main)
        .caption(title, (FONT, 16))
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(52)
        .build_cartesian_2d(-180.0..180.0, 0.0..h.max_theta)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("phi_o (degrees; the fixed direction is at 180)")
        .y_desc("theta_o (degrees)")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(e)?;
    let (dt, dp) = (h.max_theta / h.rows as f64, 360.0 / h.cols as f64);
    chart
        .draw_series((0..h.cells.len()).map(|i| {
            let (t, p) = (h.theta(i / h.cols), h.phi(i % h.cols));
            let c = viridis(if vmax > 0.0 {
                (value(i) / vmax).sqrt()
            } else {
                0.0
            });
            Rectangle::new(
                [(p - dp / 2.0, t - dt / 2.0), (p + dp / 2.0, t + dt / 2.0)],
                c.filled(),
            )
        }))
        .map_err(e)?;
    // Colour bar.
    let steps = 50;
    let bar = bar.margin(40, 44, 10, 20);
    let (_, bh) = bar.dim_in_pixel();
    for s in 0..steps {
        // Drawn on the same sqrt scale as the map: colour t stands for vmax * t^2.
        let y0 = (bh as f64 * (1.0 - (s + 1) as f64 / steps as f64)) as i32;
        let y1 = (bh as f64 * (1.0 - s as f64 / steps as f64)) as i32;
        bar.draw(&Rectangle::new(
            [(0, y0), (16, y1)],
            viridis((s as f64 + 0.5) / steps as f64).filled(),
        ))
        .map_err(e)?;
    }
    bar.draw(&Text::new(format!("{vmax:.3}"), (0, -14), (FONT, 11)))
        .map_err(e)?;
    bar.draw(&Text::new(
        format!("{:.3}", vmax / 4.0),
        (18, bh as i32 / 2 - 6),
        (FONT, 11),
    ))
    .map_err(e)?;
    bar.draw(&Text::new("0", (0, bh as i32 + 2), (FONT, 11)))
        .map_err(e)?;
    Ok(())
}

fn legend_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &Data) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let mut lines: Vec<(String, RGBColor)> = vec![("(6) models".into(), BLACK)];
    for (m, model) in d.models.iter().enumerate() {
        let note = if model.delta {
            "  [delta lobes: albedo only]"
        } else {
            ""
        };
        lines.push((format!("  {}. {}{note}", m + 1, model.label), palette(m)));
    }
    let grey = RGBColor(70, 70, 70);
    for l in [
        String::new(),
        format!(
            "theta_i: {:?} degrees (fixed direction = the wo given to sample(),",
            d.theta_i
        ),
        "  at phi = 180; plotted direction theta_o, phi = the sampled wi)".into(),
        "values: luminance 0.2126 R + 0.7152 G + 0.0722 B of the RGB lanes".into(),
        "f without cosine; pdf per solid angle; transmission carries 1/eta^2".into(),
    ]
    .into_iter()
    .chain(d.settings.lines().map(str::to_string))
    {
        lines.push((l, grey));
    }
    for (i, (text, c)) in lines.iter().enumerate() {
        area.draw(&Text::new(
            text.clone(),
            (20, 20 + 24 * i as i32),
            (FONT, if i == 0 { 20 } else { 15 }).into_font().color(c),
        ))
        .map_err(e)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(text: &str) -> Model {
        Model::new(&Spec::parse(text).unwrap()).unwrap()
    }

    #[test]
    fn lambert_polar_curve_is_rho_over_pi_cos() {
        let m = model("diffuse reflectance=0.6");
        for theta_i in [0.0, 30.0, 80.0] {
            for p in lobe(&m, theta_i) {
                let cos = p.angle.to_radians().cos();
                let want = if cos > 0.0 {
                    0.6 / std::f64::consts::PI * cos
                } else {
                    0.0
                };
                let got = p.f * cos.abs();
                // f32 evaluation and the luminance weights (which sum to 1 up to rounding):
                // a few ulps of f32.
                assert!(
                    (got - want).abs() <= 1e-6 * want.max(1e-3),
                    "angle {}: {got} vs {want}",
                    p.angle
                );
            }
        }
    }

    #[test]
    fn lambert_albedo_is_rho() {
        // Cosine-weighted sampling makes every weight exactly rho (zero variance), so the mean
        // must equal rho up to rounding; the bound is 4 standard errors (false alarm 6e-5 for a
        // noisy estimator) plus 1e-5 for the f32 arithmetic.
        let m = model("diffuse reflectance=0.7");
        for t in [0.0, 45.0, 89.9] {
            let a = albedo(&m, t, 20_000, 7);
            assert!(
                (a.mean - 0.7).abs() <= 4.0 * a.stderr + 1e-5,
                "theta_i {t}: {a:?}"
            );
        }
    }

    #[test]
    fn sampling_matches_pdf_for_a_rough_conductor() {
        let m = model("roughconductor alpha=0.3 distribution=ggx");
        let h = histogram(&m, 30.0, 200_000, 3, 90.0);
        let (sum_e, sum_o): (f64, f64) = (h.expected.iter().sum(), h.observed.iter().sum());
        assert!(
            (sum_e - sum_o).abs() < 0.01,
            "pdf mass {sum_e} vs sampled {sum_o}"
        );
        // chi^2/dof ~ 1 +- sqrt(2/dof); 2 is far outside chance for ~40 bins.
        assert!(
            h.chi2 / (h.dof as f64) < 2.0,
            "chi2/dof {}",
            h.chi2 / h.dof as f64
        );
    }

    #[test]
    fn parse_errors_are_clear() {
        let err = |t: &str| {
            Spec::parse(t)
                .and_then(|s| Model::new(&s).map(|_| ()))
                .unwrap_err()
                .to_string()
        };
        assert!(err("plastic").contains("unknown model 'plastic'"));
        assert!(err("orennayar foo=1").contains("unknown parameter 'foo'"));
        assert!(err("orennayar sigma").contains("expected NAME=VALUE"));
        assert!(err("orennayar sigma=-1").contains("sigma"));
        assert!(err("orennayar variant=bogus").contains("unknown Oren-Nayar variant"));
        assert!(err("diffuse reflectance=2")
            .contains("reflectance must be one number or r,g,b, each in [0, 1]"));
        assert!(err("minnaert k=0").contains("k must be positive"));
        assert!(err("roughconductor material=unobtainium").contains("unknown conductor"));
        assert!(err("dielectric eta=1.5 int_ior=1.3").contains("either eta or int_ior"));
        assert!(err("").contains("empty"));
    }

    #[test]
    fn dielectric_eta_shorthand_and_delta_flag() {
        let m = model("dielectric eta=1.5");
        assert!(m.delta && m.transmissive);
        // Normal incidence: R = ((1.5 - 1) / 2.5)^2 = 0.04, T weight (1 - R) / eta^2.
        let a = albedo(&m, 0.0, 50_000, 1);
        let want = 0.04 + 0.96 / 2.25;
        assert!(
            (a.mean - want).abs() < 4.0 * a.stderr + 1e-4,
            "{a:?} vs {want}"
        );
    }

    #[test]
    fn figure_draws_without_system_fonts() {
        let args = LobesArgs {
            model: "roughdielectric alpha=0.3".into(),
            params: vec![],
            compare: vec!["diffuse".into()],
            theta_i: vec![0.0, 60.0],
            output: "x.png".into(),
            csv: None,
            albedo_samples: 200,
            hist_samples: 2000,
            seed: 1,
            normalize: true,
        };
        let models = [&args.model, &args.compare[0]]
            .iter()
            .map(|t| model(t))
            .collect();
        let d = compute(models, &args);
        assert!(render_png(&d).unwrap().starts_with(b"\x89PNG"));
        assert!(render_svg(&d).unwrap().contains("<svg"));
        let csv = csv_text(&d);
        assert!(
            csv.starts_with("panel,series,theta_i,theta_o,phi,f,pdf,albedo,albedo_stderr,hist\n")
        );
        assert!(csv.lines().any(|l| l.starts_with("histogram,")));
    }
}
