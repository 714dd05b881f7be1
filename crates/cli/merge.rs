//! `pt merge`: the part files of a render split with `pt render --part K/N` into its image,
//! bit-identical to the render on one machine (the film's sums are exact integers; see
//! crates/pt-cluster/README.md).

use crate::render;
use anyhow::Result;
use clap::Args;
use pt_cluster::part::{check_set, PartFile};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct MergeArgs {
    /// The part files of one render (all N of them, any order), as `pt render --part K/N`
    /// wrote them.
    #[arg(required = true, value_name = "PART")]
    parts: Vec<PathBuf>,
    /// The merged EXR.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the per-pixel variance of the mean to OUT_var.exr (as `pt render --variance`).
    #[arg(long)]
    variance: bool,
    /// Also write a tone-mapped sRGB PNG preview to this path.
    #[arg(long, value_name = "PNG")]
    png: Option<PathBuf>,
    /// Worker threads for loading the scene (no samples are taken) [default: all cores].
    #[arg(long)]
    threads: Option<usize>,
    /// No summary on stderr.
    #[arg(short, long)]
    quiet: bool,
}

pub(crate) fn run(m: MergeArgs) -> Result<ExitCode> {
    let parts = m
        .parts
        .iter()
        .map(|p| Ok((p.clone(), PartFile::read(p)?)))
        .collect::<Result<Vec<_>>>()?;
    let parts = check_set(parts)?;
    let first = &parts[0].1;
    // The render's own command: its scene, options and film; the parts' sums instead of
    // samples. The scene is loaded again (not rendered) so that the outputs are the ones
    // `pt render` writes.
    let mut args = render::stored_arguments(&first.args, Path::new(&first.cwd))?;
    args.output = Some(m.output);
    args.variance = m.variance;
    args.png = m.png;
    args.threads = m.threads;
    args.quiet = m.quiet;
    let argv = first.args.clone();
    render::execute(args, &argv, Some(parts))
}
