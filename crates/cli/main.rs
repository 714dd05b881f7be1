//! `pt`: the command-line front end of the path tracer.
//!
//! Exit codes: 0 success, 1 a comparison that does not agree (later subcommands), 2 bad input
//! (unreadable or malformed scene, bad argument, unwritable output). Errors name the file, line
//! and element; no partial output file is ever left behind (outputs are written atomically).

/// `println!` that stops quietly when stdout is closed (`pt compare a.exr b.exr | head`)
/// instead of panicking on the broken pipe.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

mod atlas;
mod compare;
mod converge;
mod info;
mod lobes;
mod merge;
mod render;
mod slurm;
mod stability;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use pt_scene::SceneDesc;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "pt",
    version,
    about = "A physically based path tracer checked against Mitsuba 3"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an OpenEXR image (linear float32 RGB).
    Render(render::RenderArgs),
    /// Combine the part files of a render split with `render --part K/N` into its EXR: the
    /// image of the whole render, bit for bit.
    Merge(merge::MergeArgs),
    /// Split renders over a Slurm cluster: write (and with --submit, submit) a job array of
    /// `render --part` tasks and a merge job that waits for it; --status DIR reports progress.
    Slurm(slurm::SlurmArgs),
    /// Print what a scene contains: shapes, triangles, lights, materials, camera, colour mode.
    Info(info::InfoArgs),
    /// Compare an image with a reference: error metrics and, given variances, a block z-test.
    /// Exit code 0 when they agree, 1 when they do not, 2 for bad input.
    Compare(compare::CompareArgs),
    /// Convergence: relMSE against render time per strategy (and Mitsuba 3 with --mitsuba);
    /// writes a CSV and an SVG/PNG chart.
    Converge(converge::ConvergeArgs),
    Lobes(lobes::LobesArgs),
    /// Numerical stress sweep of every BSDF (NaN/Inf, energy gain, pdf mismatches, chi-square)
    /// over angles and parameters beyond their documented ranges: CSV + Markdown report.
    Stability(stability::StabilityArgs),
    /// Method failure atlas: BSDF/light/MIS on Veach-style plates, caustics from small lights,
    /// radiosity on glossy surfaces; per-region error against Mitsuba references, charts.
    Atlas(atlas::AtlasArgs),
}

#[derive(Args)]
pub(crate) struct SceneArgs {
    /// Set a scene `<default>` parameter, as Mitsuba's `-D name=value` (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    defines: Vec<String>,
    /// glTF scenes: which camera to use (0-based, in node order as `pt info` lists them)
    /// [default: the first perspective camera].
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
}

/// Makes glibc serve every allocation of 1 MB or more with its own mapping, returned to the
/// system when freed. By default glibc raises that threshold (up to 32 MB) each time such a
/// block is freed, after which large buffers come from its heap and their pages stay resident
/// after being freed: the BVH build's temporaries then inflated the peak. Measured on the
/// 1M-triangle scene (`references/make_memory_scene.py`): peak 182 -> 156 MB, time unchanged.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn return_large_frees_to_the_os() {
    // SAFETY: mallopt only changes a setting of the allocator; called before any thread starts.
    #[allow(unsafe_code)]
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}

/// Other allocators need no setting.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn return_large_frees_to_the_os() {}

fn main() -> ExitCode {
    return_large_frees_to_the_os();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Slurm(args) => slurm::run(args),
        Command::Info(args) => info::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Converge(args) => converge::run(args),
        Command::Lobes(args) => lobes::run(args),
        Command::Stability(args) => stability::run(args),
        Command::Atlas(args) => atlas::run(args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn parse_defines(defs: &[String]) -> Result<Vec<(String, String)>> {
    defs.iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.to_string())),
            _ => bail!("-D expects NAME=VALUE, got '{d}'"),
        })
        .collect()
}

/// Loads the scene file, or the built-in Cornell box.
pub(crate) fn load_scene(path: Option<&Path>, args: &SceneArgs) -> Result<SceneDesc> {
    Ok(load_scene_with_summary(path, args)?.0)
}

/// [`load_scene`], and for a glTF file (`.gltf`, `.glb`) also its `pt info` listing; the
/// loader's warnings (glTF defaults used or features ignored, media the path tracer skips) go
/// to stderr.
pub(crate) fn load_scene_with_summary(
    path: Option<&Path>,
    args: &SceneArgs,
) -> Result<(SceneDesc, Vec<String>)> {
    let defines = parse_defines(&args.defines)?;
    let opened = pt_scene::open(path, &defines, args.camera)?;
    for w in &opened.warnings {
        eprintln!("warning: {w}");
    }
    Ok((opened.desc, opened.summary))
}

/// The worker threads of a command: `--threads T` (at least 1), or rayon's default (one per
/// core).
pub(crate) fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        if t == 0 {
            bail!("--threads must be at least 1");
        }
        b = b.num_threads(t);
    }
    b.build().context("cannot start worker threads")
}

/// `out.exr` -> `out_var.exr`.
pub(crate) fn variance_path(output: &Path) -> PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    output.with_file_name(format!("{stem}_var.exr"))
}
