//! Slurm job arrays for split renders: one array task per part (of one or several scenes), a
//! merge job that waits for the whole array (`afterok`), and the state of a run from its
//! files.
//!
//! A run lives in one folder: `manifest.tsv` (one line per array task: task id, scene, part,
//! part file; then one line per scene: its merged image), `parts.sbatch`, `merge.sbatch`,
//! `parts/` (the part files), `logs/` and, once submitted, `jobs.txt` (the job ids). The
//! scripts call `pt` by absolute path from the folder the command was given in, so they run on
//! any node that shares the file system.
//!
//! Retries: a part task that fails (any exit code but 0, and 2, which is bad input and would
//! fail again) requeues itself through `scontrol requeue` until `SLURM_RESTART_COUNT` reaches
//! the retry limit; the array is submitted with `--requeue` so that Slurm also requeues it
//! after a node failure or preemption. A requeued part resumes from its part file: `pt render
//! --part` saves it at every checkpoint and when it is stopped (SIGTERM, which Slurm sends
//! first).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One array task: a part of a scene.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Task {
    /// The scene file (absolute).
    pub scene: PathBuf,
    /// Which part, from 1, and of how many: `--part K/N`.
    pub part: (u32, u32),
    /// Where the part's file goes (absolute).
    pub part_file: PathBuf,
}

/// A merge: the parts of one scene into its image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Merge {
    /// The scene file (absolute).
    pub scene: PathBuf,
    /// Its part files, in part order.
    pub parts: Vec<PathBuf>,
    /// The merged EXR.
    pub output: PathBuf,
}

/// Everything the scripts need.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The `pt` binary (absolute).
    pub pt: PathBuf,
    /// Working folder of the commands.
    pub cwd: PathBuf,
    /// The run's folder (absolute).
    pub dir: PathBuf,
    /// Array tasks, task id = position.
    pub tasks: Vec<Task>,
    /// One merge per scene.
    pub merges: Vec<Merge>,
    /// `pt render` arguments added to every part (`--spp 4096`, `-D ...`).
    pub render_args: Vec<String>,
    /// Slurm partition, or the cluster's default.
    pub partition: Option<String>,
    /// Time limit per task (Slurm's format, `HH:MM:SS` or minutes), or the partition's.
    pub time: Option<String>,
    /// Cores per part (the render's threads).
    pub cpus_per_task: u32,
    /// How often a failed part is requeued.
    pub max_retries: u32,
    /// Seconds between a part's checkpoints.
    pub checkpoint_seconds: u32,
}

/// The files of a run folder.
pub fn manifest_path(dir: &Path) -> PathBuf {
    dir.join("manifest.tsv")
}

/// The array script's path.
pub fn parts_script_path(dir: &Path) -> PathBuf {
    dir.join("parts.sbatch")
}

/// The merge script's path.
pub fn merge_script_path(dir: &Path) -> PathBuf {
    dir.join("merge.sbatch")
}

/// The submitted job ids' file.
pub fn jobs_path(dir: &Path) -> PathBuf {
    dir.join("jobs.txt")
}

/// `s` quoted for bash (single quotes; an embedded quote closed, escaped, reopened).
pub fn quote(s: &str) -> String {
    if !s.is_empty()
        && s.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"/._-=+:,@%".contains(&b))
    {
        return s.to_string();
    }
    format!("'{}'", s.replace('\'', r"'\''"))
}

fn quoted(p: &Path) -> String {
    quote(&p.to_string_lossy())
}

impl Plan {
    /// The `#SBATCH` lines both scripts share: cores, one task, partition and time limit.
    fn resources(&self, s: &mut String) {
        let _ = writeln!(s, "#SBATCH --cpus-per-task={}", self.cpus_per_task);
        let _ = writeln!(s, "#SBATCH --ntasks=1");
        if let Some(p) = &self.partition {
            let _ = writeln!(s, "#SBATCH --partition={p}");
        }
        if let Some(t) = &self.time {
            let _ = writeln!(s, "#SBATCH --time={t}");
        }
    }

    /// The job array's script (`sbatch parts.sbatch`).
    pub fn parts_script(&self) -> String {
        let mut s = String::new();
        let logs = self.dir.join("logs");
        let _ = writeln!(s, "#!/bin/bash");
        let _ = writeln!(s, "# Written by `pt slurm`: one array task per part file.");
        let _ = writeln!(s, "#SBATCH --job-name=pt-parts");
        let _ = writeln!(s, "#SBATCH --array=0-{}", self.tasks.len().max(1) - 1);
        let _ = writeln!(s, "#SBATCH --requeue");
        let _ = writeln!(s, "#SBATCH --open-mode=append");
        let _ = writeln!(s, "#SBATCH --output={}/part-%a.log", logs.display());
        self.resources(&mut s);
        let _ = writeln!(s, "set -u");
        let _ = writeln!(s, "cd {} || exit 1", quoted(&self.cwd));
        let list = |items: Vec<String>| items.join(" ");
        let _ = writeln!(
            s,
            "SCENES=({})",
            list(self.tasks.iter().map(|t| quoted(&t.scene)).collect())
        );
        let _ = writeln!(
            s,
            "PARTS=({})",
            list(
                self.tasks
                    .iter()
                    .map(|t| format!("{}/{}", t.part.0, t.part.1))
                    .collect()
            )
        );
        let _ = writeln!(
            s,
            "OUTS=({})",
            list(self.tasks.iter().map(|t| quoted(&t.part_file)).collect())
        );
        let _ = writeln!(s, "i=${{SLURM_ARRAY_TASK_ID}}");
        let _ = writeln!(
            s,
            "echo \"$(date -u +%FT%TZ) part ${{PARTS[$i]}} of ${{SCENES[$i]}} on $(hostname), attempt $(( ${{SLURM_RESTART_COUNT:-0}} + 1 ))\""
        );
        let extra: Vec<String> = self.render_args.iter().map(|a| quote(a)).collect();
        // `exec` is avoided: the shell must see the exit code to requeue.
        let _ = writeln!(
            s,
            "{} render \"${{SCENES[$i]}}\" --part \"${{PARTS[$i]}}\" -o \"${{OUTS[$i]}}\" --threads \"${{SLURM_CPUS_PER_TASK:-1}}\" --checkpoint {}{}{}",
            quoted(&self.pt),
            self.checkpoint_seconds,
            if extra.is_empty() { "" } else { " " },
            extra.join(" ")
        );
        let _ = writeln!(s, "code=$?");
        let _ = writeln!(
            s,
            "# Exit code 2 is bad input (it would fail again); anything else is retried."
        );
        let _ = writeln!(
            s,
            "if [ $code -ne 0 ] && [ $code -ne 2 ] && [ \"${{SLURM_RESTART_COUNT:-0}}\" -lt {} ]; then",
            self.max_retries
        );
        let _ = writeln!(
            s,
            "  echo \"$(date -u +%FT%TZ) part ${{PARTS[$i]}} failed with exit code $code: requeued, it resumes from its part file\""
        );
        let _ = writeln!(
            s,
            "  scontrol requeue \"${{SLURM_ARRAY_JOB_ID}}_${{SLURM_ARRAY_TASK_ID}}\""
        );
        let _ = writeln!(s, "fi");
        let _ = writeln!(s, "exit $code");
        s
    }

    /// The merge job's script (`sbatch --dependency=afterok:ARRAY merge.sbatch`).
    pub fn merge_script(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "#!/bin/bash");
        let _ = writeln!(
            s,
            "# Written by `pt slurm`: merges each scene's parts once the whole array succeeded."
        );
        let _ = writeln!(s, "#SBATCH --job-name=pt-merge");
        let _ = writeln!(
            s,
            "#SBATCH --output={}/merge.log",
            self.dir.join("logs").display()
        );
        self.resources(&mut s);
        let _ = writeln!(s, "set -eu");
        let _ = writeln!(s, "cd {}", quoted(&self.cwd));
        for m in &self.merges {
            let parts: Vec<String> = m.parts.iter().map(|p| quoted(p)).collect();
            let _ = writeln!(
                s,
                "{} merge {} -o {} --variance --threads \"${{SLURM_CPUS_PER_TASK:-1}}\"",
                quoted(&self.pt),
                parts.join(" "),
                quoted(&m.output)
            );
        }
        s
    }

    /// `manifest.tsv`: `task<TAB>id<TAB>scene<TAB>K/N<TAB>part file` per task, then
    /// `merge<TAB>scene<TAB>output` per scene.
    pub fn manifest(&self) -> String {
        let mut s = String::from("# pt slurm run: tasks of the job array, then merged images\n");
        for (i, t) in self.tasks.iter().enumerate() {
            let _ = writeln!(
                s,
                "task\t{i}\t{}\t{}/{}\t{}",
                t.scene.display(),
                t.part.0,
                t.part.1,
                t.part_file.display()
            );
        }
        for m in &self.merges {
            let _ = writeln!(s, "merge\t{}\t{}", m.scene.display(), m.output.display());
        }
        s
    }
}

/// A run folder's manifest, read back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Manifest {
    /// The array's tasks, task id = position.
    pub tasks: Vec<Task>,
    /// Per scene: the scene file and its merged image.
    pub images: Vec<(PathBuf, PathBuf)>,
}

/// Reads a run folder's manifest.
pub fn read_manifest(dir: &Path) -> Result<Manifest, String> {
    let path = manifest_path(dir);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        format!(
            "{}: cannot read ({e}); is {} a folder written by `pt slurm`?",
            path.display(),
            dir.display()
        )
    })?;
    let mut tasks = Vec::new();
    let mut merges = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split('\t').collect();
        let bad = || format!("{}:{}: malformed line '{line}'", path.display(), n + 1);
        match f.as_slice() {
            ["task", _, scene, part, file] => {
                let (k, of) = part.split_once('/').ok_or_else(bad)?;
                tasks.push(Task {
                    scene: PathBuf::from(scene),
                    part: (
                        k.parse().map_err(|_| bad())?,
                        of.parse().map_err(|_| bad())?,
                    ),
                    part_file: PathBuf::from(file),
                });
            }
            ["merge", scene, output] => merges.push((PathBuf::from(scene), PathBuf::from(output))),
            _ => return Err(bad()),
        }
    }
    Ok(Manifest {
        tasks,
        images: merges,
    })
}

/// Submits a written run: the array, then the merge job depending on it (`afterok`). Returns
/// the two job ids (also written to `jobs.txt`).
pub fn submit(dir: &Path) -> Result<(String, String), String> {
    let sbatch = |args: &[&str]| -> Result<String, String> {
        let out = Command::new("sbatch")
            .args(args)
            .output()
            .map_err(|e| format!("cannot run sbatch ({e}): is Slurm installed on this machine?"))?;
        if !out.status.success() {
            return Err(format!(
                "sbatch {} failed: {}",
                args.join(" "),
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
        // `--parsable` prints `id` or `id;cluster`.
        let text = String::from_utf8_lossy(&out.stdout);
        let id = text.trim().split(';').next().unwrap_or("").to_string();
        if id.is_empty() {
            return Err(format!("sbatch printed no job id: '{}'", text.trim()));
        }
        Ok(id)
    };
    let parts = parts_script_path(dir);
    let array = sbatch(&["--parsable", &parts.to_string_lossy()])?;
    let merge = sbatch(&[
        "--parsable",
        &format!("--dependency=afterok:{array}"),
        "--kill-on-invalid-dep=yes",
        &merge_script_path(dir).to_string_lossy(),
    ])?;
    let text = format!("array {array}\nmerge {merge}\n");
    std::fs::write(jobs_path(dir), text)
        .map_err(|e| format!("{}: {e}", jobs_path(dir).display()))?;
    Ok((array, merge))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> Plan {
        let dir = PathBuf::from("/runs/r1");
        let tasks: Vec<Task> = (1..=3)
            .map(|k| Task {
                scene: PathBuf::from("/scenes/my box.xml"),
                part: (k, 3),
                part_file: dir.join(format!("parts/my box.part{k}of3.ptpart")),
            })
            .collect();
        Plan {
            pt: PathBuf::from("/opt/pt/bin/pt"),
            cwd: PathBuf::from("/home/u"),
            dir: dir.clone(),
            merges: vec![Merge {
                scene: tasks[0].scene.clone(),
                parts: tasks.iter().map(|t| t.part_file.clone()).collect(),
                output: dir.join("my box.exr"),
            }],
            tasks,
            render_args: vec!["--spp".into(), "64".into(), "-D".into(), "v=it's".into()],
            partition: Some("gpu".into()),
            time: Some("01:00:00".into()),
            cpus_per_task: 4,
            max_retries: 3,
            checkpoint_seconds: 60,
        }
    }

    /// The array script has one task per part, asks Slurm to requeue, quotes paths with
    /// spaces and quotes, and requeues itself on failure but not on bad input; the manifest
    /// reads back.
    #[test]
    fn scripts_and_manifest() {
        let p = plan();
        let s = p.parts_script();
        assert!(s.contains("#SBATCH --array=0-2\n"), "{s}");
        assert!(s.contains("#SBATCH --requeue\n"));
        assert!(s.contains("#SBATCH --partition=gpu\n") && s.contains("#SBATCH --time=01:00:00\n"));
        assert!(s.contains("'/scenes/my box.xml'"));
        assert!(s.contains(r"'v=it'\''s'"), "{s}");
        assert!(s.contains("PARTS=(1/3 2/3 3/3)"));
        assert!(s.contains("[ $code -ne 2 ]") && s.contains("scontrol requeue"));
        let m = p.merge_script();
        assert!(
            m.contains("merge '/runs/r1/parts/my box.part1of3.ptpart'"),
            "{m}"
        );
        let dir = std::env::temp_dir().join(format!("pt-cluster-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(manifest_path(&dir), p.manifest()).unwrap();
        let m = read_manifest(&dir).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(m.tasks, p.tasks);
        assert_eq!(
            m.images,
            vec![(p.merges[0].scene.clone(), p.merges[0].output.clone())]
        );
    }

    #[test]
    fn quoting() {
        assert_eq!(quote("/a/b.xml"), "/a/b.xml");
        assert_eq!(quote("a b"), "'a b'");
        assert_eq!(quote(""), "''");
        assert_eq!(quote("$(rm)"), "'$(rm)'");
    }
}
