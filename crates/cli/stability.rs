//! `pt stability`: a numerical stress sweep of every BSDF model, written as a CSV and a
//! Markdown report with charts; the analysis is `pt_lab::stability` (what each probe checks)
//! and `pt_lab::fireflies` (the bias of `pt render --clamp`).
//!
//! ```text
//! pt stability [--out DIR] [--samples N] [--chi2-samples N] [--threads T] [--strict] [--quiet]
//! ```
//!
//! Outputs in `--out DIR` (each written atomically): `stability.csv` (one row per case),
//! `report.md`, `albedo.svg`/`.png` and `clamp.svg`/`.png`. With `--strict` the exit code is 1
//! when a NaN/Inf or an in-range energy gain is found. The method failure atlas is `pt atlas`.

use anyhow::{bail, Result};
use clap::Args;
use pt_lab::stability::StabilitySettings;
use std::path::PathBuf;
use std::process::ExitCode;

/// Options of `pt stability`.
#[derive(Args)]
pub struct StabilityArgs {
    /// Output folder for stability.csv, report.md and the charts (created if missing).
    #[arg(long, default_value = "stability-report")]
    out: PathBuf,
    /// Samples per case for the albedo and the per-sample checks.
    #[arg(long, default_value_t = 20_000)]
    samples: usize,
    /// Samples per chi-square test (0: no chi-square tests).
    #[arg(long, default_value_t = 100_000)]
    chi2_samples: usize,
    /// Worker threads [default: all cores].
    #[arg(long)]
    threads: Option<usize>,
    /// Exit with code 1 when a NaN/Inf or an in-range energy gain is found.
    #[arg(long)]
    strict: bool,
    /// No progress on stderr.
    #[arg(short, long)]
    quiet: bool,
}

/// Runs `pt stability`.
pub fn run(args: StabilityArgs) -> Result<ExitCode> {
    if args.samples < 100 {
        bail!("--samples must be at least 100, got {}", args.samples);
    }
    let pool = crate::thread_pool(args.threads)?;
    pt_lab::create_dir(&args.out, "cannot create the folder")?;
    let settings = StabilitySettings {
        samples: args.samples,
        chi2_samples: args.chi2_samples,
    };
    let show = !args.quiet;
    let progress = |k: usize, total: usize| {
        if show && k % 200 == 0 {
            eprintln!("stability: {k} / {total} cases");
        }
    };
    let st = pool.install(|| pt_lab::stability::run(&settings, &progress))?;
    st.write(&args.out)?;
    let s = st.summary();
    if !args.quiet {
        eprintln!(
            "stability: {} cases x angles = {} probes in {:.1} s: {} non-finite values, {} energy gains ({} in range beyond the documented bound), {} pdf mismatches, {} weight mismatches, {} of {} chi-square tests failed -> {}",
            st.cases.len(),
            st.rows.len(),
            st.seconds,
            s.nonfinite,
            s.gains,
            s.gains_in_range,
            s.pdf_mismatch,
            s.weight_mismatch,
            s.chi2_fail,
            s.chi2_tests,
            args.out.join("report.md").display()
        );
    }
    Ok(
        if args.strict && (s.nonfinite > 0 || s.gains_in_range > 0) {
            ExitCode::from(1)
        } else {
            ExitCode::SUCCESS
        },
    )
}
