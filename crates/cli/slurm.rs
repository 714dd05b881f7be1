//! `pt slurm`: a job array of `pt render --part K/N` tasks (one per scene and part) and a
//! merge job that waits for the whole array, written to a run folder and, with `--submit`,
//! submitted through `sbatch`; `--status DIR` reports which parts are done. The scripts and
//! the retry rules are pt-cluster's (`crates/pt-cluster/src/slurm.rs`).

use crate::render;
use anyhow::{bail, Context, Result};
use clap::Args;
use pt_cluster::part::PartFile;
use pt_cluster::slurm::{self, Merge, Plan, Task};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct SlurmArgs {
    /// Scenes to render: each gets --parts array tasks and one merged EXR in the run folder.
    #[arg(value_name = "SCENE", required_unless_present = "status")]
    scenes: Vec<PathBuf>,
    /// Parts per scene (array tasks; each takes every N-th sample of every pixel).
    #[arg(long, default_value_t = 1)]
    parts: u32,
    /// Samples per pixel of each whole render [default: each scene's sampler sample_count].
    #[arg(long)]
    spp: Option<u32>,
    /// Slurm partition [default: the cluster's default].
    #[arg(long)]
    partition: Option<String>,
    /// Time limit of each task, in Slurm's format (minutes, HH:MM:SS, D-HH) [default: the
    /// partition's].
    #[arg(long)]
    time: Option<String>,
    /// Cores per task (the threads of each part's render).
    #[arg(long, default_value_t = 1)]
    cpus_per_task: u32,
    /// The run folder: scripts, manifest, part files, logs and the merged images.
    #[arg(long, default_value = "pt-slurm")]
    out: PathBuf,
    /// Submit the array and the merge job with sbatch (otherwise only write the scripts).
    #[arg(long)]
    submit: bool,
    /// How often a failed part is requeued (it resumes from its last checkpoint).
    #[arg(long, default_value_t = 3)]
    max_retries: u32,
    /// Seconds between a part's checkpoints.
    #[arg(long, default_value_t = 60)]
    checkpoint: u32,
    /// Report the parts and merged images of the run folder DIR, then exit.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["scenes", "submit"])]
    status: Option<PathBuf>,
    /// Further `pt render` arguments for every part, after `--` (`-- -D res=64 --max-depth 8`).
    #[arg(last = true, value_name = "RENDER_ARGS")]
    render_args: Vec<String>,
}

pub(crate) fn run(a: SlurmArgs) -> Result<ExitCode> {
    if let Some(dir) = &a.status {
        return status(dir);
    }
    if a.parts == 0 {
        bail!("--parts must be at least 1");
    }
    if a.cpus_per_task == 0 {
        bail!("--cpus-per-task must be at least 1");
    }
    std::fs::create_dir_all(a.out.join("parts"))
        .and_then(|_| std::fs::create_dir_all(a.out.join("logs")))
        .with_context(|| format!("cannot create the run folder {}", a.out.display()))?;
    let dir = a.out.canonicalize()?;
    let cwd = std::env::current_dir().context("cannot read the current folder")?;
    let mut render_args = a.render_args.clone();
    if let Some(spp) = a.spp {
        render_args.extend(["--spp".to_string(), spp.to_string()]);
    }
    let mut tasks = Vec::new();
    let mut merges: Vec<Merge> = Vec::new();
    for scene in &a.scenes {
        let scene = scene
            .canonicalize()
            .with_context(|| format!("cannot find scene {}", scene.display()))?;
        // The task's command line, checked here (arguments and scene) rather than on the
        // cluster.
        let mut argv = vec![scene.display().to_string()];
        argv.extend(render_args.iter().cloned());
        argv.extend(["--part".to_string(), format!("1/{}", a.parts)]);
        let args = render::stored_arguments(&argv, &cwd)?;
        args.scene()?;
        let stem = scene
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into());
        let output = dir.join(format!("{stem}.exr"));
        if merges.iter().any(|m| m.output == output) {
            bail!(
                "two scenes named {stem}: their images would both be {}",
                output.display()
            );
        }
        let parts: Vec<PathBuf> = (1..=a.parts)
            .map(|k| {
                dir.join("parts")
                    .join(format!("{stem}.part{k}of{}.ptpart", a.parts))
            })
            .collect();
        for (k, file) in parts.iter().enumerate() {
            tasks.push(Task {
                scene: scene.clone(),
                part: (k as u32 + 1, a.parts),
                part_file: file.clone(),
            });
        }
        merges.push(Merge {
            scene,
            parts,
            output,
        });
    }
    let plan = Plan {
        pt: std::env::current_exe()
            .and_then(|p| p.canonicalize())
            .context("cannot find the pt binary")?,
        cwd,
        dir: dir.clone(),
        tasks,
        merges,
        render_args,
        partition: a.partition,
        time: a.time,
        cpus_per_task: a.cpus_per_task,
        max_retries: a.max_retries,
        checkpoint_seconds: a.checkpoint,
    };
    pt_image::write_bytes_atomically(
        &slurm::parts_script_path(&dir),
        plan.parts_script().as_bytes(),
    )?;
    pt_image::write_bytes_atomically(
        &slurm::merge_script_path(&dir),
        plan.merge_script().as_bytes(),
    )?;
    pt_image::write_bytes_atomically(&slurm::manifest_path(&dir), plan.manifest().as_bytes())?;
    out!(
        "wrote {} array tasks ({} scene(s) x {} parts) and a merge job to {}",
        plan.tasks.len(),
        plan.merges.len(),
        a.parts,
        dir.display()
    );
    if a.submit {
        let (array, merge) = slurm::submit(&dir).map_err(|m| anyhow::anyhow!(m))?;
        out!("submitted: array job {array}, merge job {merge} (after the array succeeds)");
        out!("progress: pt slurm --status {}", dir.display());
    } else {
        out!(
            "submit with: pt slurm ... --submit, or sbatch {} then sbatch --dependency=afterok:ARRAY_ID {}",
            slurm::parts_script_path(&dir).display(),
            slurm::merge_script_path(&dir).display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints each task's part (complete, in progress with its samples, or not started) and each
/// merged image.
fn status(dir: &Path) -> Result<ExitCode> {
    let slurm::Manifest {
        tasks,
        images: merges,
    } = slurm::read_manifest(dir).map_err(|m| anyhow::anyhow!(m))?;
    if let Ok(jobs) = std::fs::read_to_string(slurm::jobs_path(dir)) {
        out!("jobs: {}", jobs.trim().replace('\n', ", "));
    }
    let mut complete = 0;
    for (i, t) in tasks.iter().enumerate() {
        let name = t
            .scene
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let state = if t.part_file.exists() {
            match PartFile::read(&t.part_file) {
                Ok(p) if p.complete() => {
                    complete += 1;
                    format!("done ({} spp)", p.done)
                }
                Ok(p) => format!("running or stopped: {} of {} spp", p.done, p.share_spp),
                Err(e) => format!("unreadable: {e}"),
            }
        } else {
            "not started".into()
        };
        out!("task {i}: {name} part {}/{}: {state}", t.part.0, t.part.1);
    }
    let mut merged = 0;
    for (scene, output) in &merges {
        let done = output.exists();
        merged += usize::from(done);
        out!(
            "merge {}: {}",
            scene.display(),
            if done {
                format!("written {}", output.display())
            } else {
                "not yet".into()
            }
        );
    }
    out!(
        "{complete} of {} parts done, {merged} of {} images merged",
        tasks.len(),
        merges.len()
    );
    Ok(ExitCode::SUCCESS)
}
