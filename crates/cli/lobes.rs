//! `pt lobes`: pictures of a BSDF model drawn from the renderer's own code (issue 4); the
//! analysis is `pt_lab::lobes`, whose module doc describes the figure and the CSV.
//!
//! ```text
//! pt lobes MODEL [--param NAME=VALUE]... [--compare "MODEL NAME=VALUE ..."]...
//!          [--theta-i DEG]... -o lobes.svg|lobes.png [--csv FILE]
//!          [--albedo-samples N] [--hist-samples N] [--seed S]
//! ```
//!
//! MODEL is a BSDF plugin name of the scene format, optionally followed by its parameters in the
//! same string: `diffuse`, `orennayar`, `minnaert`, `roughconductor`, `roughdielectric`,
//! `roughplastic`, `roughthinfilm`, and (albedo panel only, their lobes are deltas) `conductor`,
//! `dielectric`, `thindielectric`, `thinfilm`; `twosided MODEL ...` wraps one. Parameters have
//! their scene-file names and defaults (`pt_lab::bsdf::MODELS` lists them): `reflectance` (one
//! number, or `r,g,b`), `sigma` (radians), `variant` (qualitative, full, fujii, eon), `k`
//! (Minnaert exponent, or a conductor's extinction), `alpha` or `alpha_u` + `alpha_v`,
//! `distribution` (beckmann, ggx), `material` (a conductor name such as `Au`), `eta` + `k`
//! (conductor), `int_ior` / `ext_ior` (a number or a name such as `bk7`),
//! `specular_reflectance`; `eta` on a dielectric is short for `int_ior=eta ext_ior=1`. The model
//! is built as a scene file would build it (`pt_lab::bsdf`), so names, defaults, named materials
//! and validation are the scene format's. Each `--compare` adds one more model, drawn on the
//! same charts. Outputs are written atomically.
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

use anyhow::{bail, Context, Result};
use clap::Args;
use pt_lab::bsdf::BsdfSpec;
use pt_lab::lobes::LobesSettings;
use std::path::PathBuf;
use std::process::ExitCode;

/// Charts of a BSDF model from the renderer's own code: polar lobes, directional albedo, sampled
/// directions against the pdf, hemisphere map (SVG or PNG, optional CSV).
#[derive(Args, Debug)]
pub struct LobesArgs {
    /// The model: a scene-format BSDF name, optionally with parameters in the same (quoted)
    /// string, e.g. "orennayar sigma=0.3 variant=full". Models: diffuse, orennayar, minnaert,
    /// roughconductor, roughdielectric, roughplastic, roughthinfilm; conductor, dielectric,
    /// thindielectric, thinfilm (albedo only); "twosided MODEL ..." wraps one.
    pub model: String,
    /// A parameter of MODEL (repeatable), with its scene-file name: reflectance, sigma, variant,
    /// k, alpha, alpha_u, alpha_v, distribution, material, eta, int_ior, ext_ior,
    /// specular_reflectance, ... (each model's list is in the message for an unknown one).
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

/// Runs `pt lobes`.
pub fn run(args: LobesArgs) -> Result<ExitCode> {
    let mut first = BsdfSpec::parse(&args.model)?;
    for p in &args.params {
        first.add_param(p)?;
    }
    let mut models = vec![first];
    for c in &args.compare {
        models.push(BsdfSpec::parse(c).with_context(|| format!("--compare \"{c}\""))?);
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
    let lobes = pt_lab::lobes::compute(&LobesSettings {
        models,
        theta_i: args.theta_i,
        albedo_samples: args.albedo_samples,
        hist_samples: args.hist_samples,
        seed: args.seed,
        normalize: args.normalize,
    })?;
    for line in lobes.sampling_summary() {
        eprintln!("{line}");
    }
    if let Some(csv) = &args.csv {
        pt_lab::write_atomic(csv, lobes.csv().as_bytes())?;
    }
    let bytes = if png {
        lobes.png()?
    } else {
        lobes.svg()?.into_bytes()
    };
    pt_lab::write_atomic(&args.output, &bytes)?;
    Ok(ExitCode::SUCCESS)
}
