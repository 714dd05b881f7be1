//! `pt converge`: error against render time, for pt's direct-light strategies and for Mitsuba 3;
//! the analysis is `pt_lab::converge`, whose module doc describes the measurements and files.
//!
//! ```text
//! pt converge SCENE --reference REF.exr [--spp 1,2,4,...,1024] [--strategy mis,bsdf,light]
//!            [--modes rgb,spectral] [--mitsuba] [--mitsuba-variant llvm_ad_rgb|scalar_rgb] [--out DIR]
//!            [--threads T] [--max-depth D] [--seed S] [--python PY] [-D name=value]...
//! ```
//!
//! With `--mitsuba`, `references/mitsuba_converge.py` runs with `.venv/bin/python` of the
//! repository if it exists, else `python3` (`--python` overrides). If Mitsuba cannot be
//! imported, the command stops with exit code 2 before pt renders anything. Output, in DIR
//! (default `converge-<scene name>`): `converge.csv`, `converge.svg`, `converge.png`,
//! `summary.txt` (what is printed at the end) and every image measured. A progress line per
//! point goes to stderr.
//!
//! Threads: pt uses `--threads` workers (default: all cores), Mitsuba the same count (Dr.Jit's
//! thread count). Errors (unreadable scene, missing reference, size mismatch, Mitsuba missing)
//! exit with code 2.
//!
//! Example:
//! ```text
//! pt converge scenes/cornell-box.xml --reference references/cornell-box.exr \
//!     --spp 4,16,64,256 --strategy mis,bsdf --mitsuba --out /tmp/converge-cb
//! ```

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use pt_lab::converge::{ConvergeSettings, MitsubaRun, MitsubaVariant as Variant};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Options of `pt converge`.
#[derive(Args, Debug)]
pub struct ConvergeArgs {
    /// Mitsuba 3 XML scene to render.
    pub scene: PathBuf,
    /// Reference image (EXR) the errors are measured against; same size as the scene's film.
    #[arg(long, value_name = "REF.exr")]
    pub reference: PathBuf,
    /// Sample counts per pixel, comma separated: one render (one point) each.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1,2,4,8,16,32,64,128,256,512,1024"
    )]
    pub spp: Vec<u32>,
    /// Direct-light strategies of pt's path tracer, comma separated: one curve each.
    #[arg(long, value_delimiter = ',', default_value = "mis", value_parser = clap::builder::PossibleValuesParser::new(pt_lab::converge::STRATEGIES))]
    pub strategy: Vec<String>,
    /// Light transport methods of pt, comma separated: `path` (one curve per --strategy),
    /// `ptracer` (light tracing, curve `pt-ptracer`; its spp are light paths per pixel),
    /// `sppm` (photon mapping, curve `pt-sppm`; its spp are iterations), `photonmapper`
    /// (Jensen's, `pt-photonmapper`; spp are iterations), `bdpt`
    /// (bidirectional path tracing, `pt-bdpt`) and `vcm` (vertex connection and merging,
    /// `pt-vcm`; spp are iterations of a camera and a light subpath per pixel).
    #[arg(long, value_delimiter = ',', default_value = "path", value_parser = clap::builder::PossibleValuesParser::new(pt_lab::converge::Method::NAMES))]
    pub integrators: Vec<String>,
    /// Colour modes of pt, comma separated (`rgb,spectral`): one curve per mode and strategy,
    /// named `pt-<mode>-<strategy>`, each timed with its own scene build [default: the scene's
    /// automatic mode only, curves named `pt-<strategy>`]. On a spectral scene, RGB converges
    /// to the spectra projected to RGB, so its error against a spectral reference levels off.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub modes: Vec<ConvergeMode>,
    /// Also render with Mitsuba 3 (references/mitsuba_converge.py) at the same sample counts.
    #[arg(long)]
    pub mitsuba: bool,
    /// Mitsuba variant for --mitsuba.
    #[arg(long, value_enum, default_value_t = MitsubaVariant::LlvmAdRgb)]
    pub mitsuba_variant: MitsubaVariant,
    /// Python interpreter for --mitsuba [default: the repository's .venv/bin/python if present,
    /// else python3].
    #[arg(long, value_name = "PYTHON")]
    pub python: Option<PathBuf>,
    /// Output folder (created if needed) [default: converge-<scene name>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Worker threads of pt and of Mitsuba [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Longest path in segments (1: emitters only, 2: direct light, -1: unlimited) [default: the
    /// scene's]. Mitsuba gets it as the scene parameter $max_depth, which the scene must declare.
    #[arg(long, allow_hyphen_values = true)]
    pub max_depth: Option<i32>,
    /// Seed of pt's random streams; Mitsuba's render i uses seed + i. Keep it away from the
    /// reference's seeds (make_references.py uses 0..63).
    #[arg(long, default_value_t = 1000)]
    pub seed: u64,
    /// Set a scene `<default>` parameter, as Mitsuba's `-D name=value` (repeatable; passed to
    /// Mitsuba too).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub defines: Vec<String>,
    /// Also solve the scene by radiosity at these patch sizes (scene units, comma separated):
    /// one point each, timed from meshing to the displayed image, on the same chart. Points
    /// are labelled with their patch count.
    #[arg(long, value_delimiter = ',', value_name = "SIZES")]
    pub radiosity_patch_sizes: Vec<f32>,
    /// Form-factor rays per patch for the radiosity points.
    #[arg(long, default_value_t = 1024)]
    pub radiosity_rays: u32,
}

/// pt's colour mode of one curve (`--modes`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ConvergeMode {
    /// RGB transport (spectra projected to linear sRGB).
    Rgb,
    /// Spectral transport (four wavelengths per path).
    Spectral,
}

impl ConvergeMode {
    fn mode(self) -> pt_spectrum::ColorMode {
        match self {
            ConvergeMode::Rgb => pt_spectrum::ColorMode::Rgb,
            ConvergeMode::Spectral => pt_spectrum::ColorMode::Spectral,
        }
    }
}

/// Mitsuba 3 variant used by `--mitsuba`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MitsubaVariant {
    /// LLVM JIT, vectorised and multi-threaded (needs libLLVM; fast).
    #[value(name = "llvm_ad_rgb")]
    LlvmAdRgb,
    /// Scalar C++, one sample at a time per thread.
    #[value(name = "scalar_rgb")]
    ScalarRgb,
}

impl MitsubaVariant {
    fn variant(self) -> Variant {
        match self {
            MitsubaVariant::LlvmAdRgb => Variant::LlvmAdRgb,
            MitsubaVariant::ScalarRgb => Variant::ScalarRgb,
        }
    }
}

/// Runs `pt converge`. Errors are bad input (exit code 2 in `main`).
pub fn run(args: ConvergeArgs) -> Result<ExitCode> {
    if args.spp.contains(&0) {
        bail!("--spp values must be at least 1");
    }
    if args.spp.is_empty() {
        bail!("--spp needs at least one sample count");
    }
    if args.threads == Some(0) {
        bail!("--threads must be at least 1");
    }
    if let Some(d) = args.max_depth {
        if d < -1 {
            bail!("--max-depth must be -1 (unlimited) or >= 0, got {d}");
        }
    }
    if let Some(h) = args
        .radiosity_patch_sizes
        .iter()
        .find(|h| !(**h > 0.0 && h.is_finite()))
    {
        bail!("--radiosity-patch-sizes must be positive, got {h}");
    }
    let defines = crate::parse_defines(&args.defines)?;
    let out = args.out.clone().unwrap_or_else(|| {
        let stem = args
            .scene
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into());
        PathBuf::from(format!("converge-{stem}"))
    });
    let mitsuba = match args.mitsuba {
        false => None,
        true => {
            let script = pt_lab::converge::mitsuba::script()?;
            let python = args
                .python
                .clone()
                .unwrap_or_else(|| default_python(&script));
            Some(MitsubaRun {
                script,
                python,
                variant: args.mitsuba_variant.variant(),
                threads: args.threads,
            })
        }
    };
    let settings = ConvergeSettings {
        scene: args.scene,
        defines,
        reference: args.reference,
        spp: args.spp,
        // The parsers admit only the names these functions know.
        strategies: args
            .strategy
            .iter()
            .filter_map(|s| pt_lab::converge::strategy_named(s))
            .collect(),
        integrators: args
            .integrators
            .iter()
            .filter_map(|m| pt_lab::converge::Method::named(m))
            .collect(),
        modes: args.modes.iter().map(|m| m.mode()).collect(),
        out,
        max_depth: args.max_depth,
        seed: args.seed,
        mitsuba,
        radiosity_patch_sizes: args.radiosity_patch_sizes,
        radiosity_rays: args.radiosity_rays,
    };
    let pool = crate::thread_pool(args.threads)?;
    let result = pool.install(|| pt_lab::converge::run(&settings, &|line| eprintln!("{line}")))?;
    print!("{}", result.summary);
    Ok(ExitCode::SUCCESS)
}

/// The repository's `.venv/bin/python` beside the script's `references/` if it exists, else
/// `python3`.
fn default_python(script: &Path) -> PathBuf {
    let venv = script
        .parent()
        .and_then(Path::parent)
        .map(|repo| repo.join(".venv").join("bin").join("python"));
    venv.filter(|p| p.is_file())
        .unwrap_or_else(|| PathBuf::from("python3"))
}
