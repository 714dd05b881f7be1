//! `pt atlas`: the method failure atlas, where each rendering method fails, by numbers; the
//! studies are `pt_lab::atlas` (scenes, regions, budgets and errors are described there).
//!
//! ```text
//! pt atlas [--out DIR] [--references references/atlas] [--equal time|spp] [--spp N]
//!          [--only veach,caustic,radiosity] [--threads T] [--quiet]
//! ```
//!
//! Writes `report.md` and `atlas-{veach,caustic,radiosity,transport}.svg/.png` to DIR. Without the
//! Mitsuba references a long pt MIS render stands in, and the report says so.

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use pt_lab::atlas::AtlasSettings;
use std::path::PathBuf;
use std::process::ExitCode;

/// What the competing methods get the same of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Equal {
    /// Equal wall time: the time MIS (or radiosity) needed.
    Time,
    /// Equal samples per pixel (`--spp`).
    Spp,
}

/// Which studies to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Which {
    /// Plates x lights, BSDF / light / MIS (Veach).
    Veach,
    /// Glass sphere under lights of decreasing size.
    Caustic,
    /// Radiosity on glossy strips.
    Radiosity,
    /// A caustic behind glass: path tracing, light tracing (ptracer), photon mapping (sppm), bdpt and vcm.
    Transport,
}

/// Options of `pt atlas`.
#[derive(Args)]
pub struct AtlasArgs {
    /// Output folder for report.md and the charts atlas-*.svg/.png (created if missing).
    #[arg(long, default_value = "atlas-report")]
    out: PathBuf,
    /// Folder of the Mitsuba references of scenes/atlas/ (NAME.exr and NAME_var.exr). A missing
    /// one is replaced by a long pt MIS render, and the report says so. The transport study
    /// reads the scene suite's `ptracer` references from here or the folder above (required:
    /// a path-traced stand-in would lack the caustic).
    #[arg(long, default_value = "references/atlas")]
    references: PathBuf,
    /// What the methods get the same of: wall time (MIS's time at --spp) or samples per pixel.
    #[arg(long, value_enum, default_value_t = Equal::Time)]
    equal: Equal,
    /// Samples per pixel of MIS (equal time: the others get its wall time), and of the path
    /// tracer in the radiosity study with --equal spp; in the transport study, of the path
    /// tracer [default: 64 for veach and radiosity, 1024 for caustic, where fewer samples find
    /// no caustic at all under the smallest light, 256 for transport].
    #[arg(long)]
    spp: Option<u32>,
    /// Studies to run, comma separated.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Which::Veach, Which::Caustic, Which::Radiosity, Which::Transport])]
    only: Vec<Which>,
    /// Worker threads [default: all cores].
    #[arg(long)]
    threads: Option<usize>,
    /// No progress messages.
    #[arg(long)]
    quiet: bool,
}

impl Equal {
    fn equal(self) -> pt_lab::atlas::Equal {
        match self {
            Equal::Time => pt_lab::atlas::Equal::Time,
            Equal::Spp => pt_lab::atlas::Equal::Spp,
        }
    }
}

impl Which {
    fn which(self) -> pt_lab::atlas::Which {
        match self {
            Which::Veach => pt_lab::atlas::Which::Veach,
            Which::Caustic => pt_lab::atlas::Which::Caustic,
            Which::Radiosity => pt_lab::atlas::Which::Radiosity,
            Which::Transport => pt_lab::atlas::Which::Transport,
        }
    }
}

/// `pt atlas`: runs the selected studies, writes `report.md` and `atlas-KEY.svg/.png` to `--out`.
pub fn run(args: AtlasArgs) -> Result<ExitCode> {
    if args.spp == Some(0) {
        bail!("--spp must be at least 1");
    }
    let pool = crate::thread_pool(args.threads)?;
    pt_lab::create_dir(&args.out, "cannot create the folder")?;
    let mut md = pt_lab::atlas::report_header();
    let mut which = args.only.clone();
    which.dedup();
    for w in which {
        let start = std::time::Instant::now();
        if !args.quiet {
            eprintln!("atlas: {w:?} ...");
        }
        let w = w.which();
        let settings = AtlasSettings {
            equal: args.equal.equal(),
            spp: args.spp.unwrap_or(w.default_spp()),
            references: args.references.clone(),
            shrink: 1,
            fallback_spp: 4096,
        };
        let study = pool.install(|| pt_lab::atlas::study(w, &settings))?;
        study.write_charts(&args.out)?;
        md.push_str(&study.report());
        if !args.quiet {
            eprintln!(
                "atlas: {w:?} done in {:.1} s",
                start.elapsed().as_secs_f64()
            );
        }
    }
    pt_lab::write_atomic(&args.out.join("report.md"), md.as_bytes())?;
    if !args.quiet {
        eprintln!("atlas: wrote {}", args.out.join("report.md").display());
    }
    Ok(ExitCode::SUCCESS)
}
