//! Mitsuba 3's curve for [`super::run`]: `references/mitsuba_converge.py` renders the scene at
//! every sample count in one process and prints `point SPP SECONDS` per image (written as
//! `mitsuba/spp<N>.exr` in the output folder) and `info KEY VALUE` lines; anything else it
//! prints is passed on. Only `mi.render` is timed; one untimed warm-up render first traces and
//! JIT-compiles the llvm kernel.

use super::{measure, ConvergeSettings, Point, Series};
use crate::{LabError, Result};
use pt_image::Image;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// How to run Mitsuba 3.
#[derive(Clone, Debug, PartialEq)]
pub struct MitsubaRun {
    /// `references/mitsuba_converge.py`.
    pub script: PathBuf,
    /// The Python interpreter with the `mitsuba` package.
    pub python: PathBuf,
    /// The variant.
    pub variant: MitsubaVariant,
    /// Dr.Jit's thread count (all cores if `None`).
    pub threads: Option<usize>,
}

/// Mitsuba 3 variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MitsubaVariant {
    /// LLVM JIT, vectorised and multi-threaded (needs libLLVM; fast).
    LlvmAdRgb,
    /// Scalar C++, one sample at a time per thread.
    ScalarRgb,
}

impl MitsubaVariant {
    /// Mitsuba's name of the variant.
    pub fn name(self) -> &'static str {
        match self {
            MitsubaVariant::LlvmAdRgb => "llvm_ad_rgb",
            MitsubaVariant::ScalarRgb => "scalar_rgb",
        }
    }
}

/// `references/mitsuba_converge.py`: under the current folder's `references/`, else in the
/// source tree this library was built from.
pub fn script() -> Result<PathBuf> {
    let rel = std::path::Path::new("references").join("mitsuba_converge.py");
    let candidates = [
        rel.clone(),
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(&rel),
    ];
    candidates
        .iter()
        .find(|p| p.is_file())
        .cloned()
        .ok_or_else(|| {
            LabError::Invalid(format!(
                "Mitsuba's curve needs references/mitsuba_converge.py; looked for {}",
                candidates
                    .map(|p| format!("'{}'", p.display()))
                    .join(" and ")
            ))
        })
}

/// Runs Mitsuba at every sample count of `spp`; returns its curve and a summary line.
pub(super) fn run(
    m: &MitsubaRun,
    s: &ConvergeSettings,
    spp: &[u32],
    reference: &Image,
    log: &(dyn Fn(&str) + Sync),
) -> Result<(Series, String)> {
    let (python, script) = (&m.python, &m.script);
    let variant = m.variant.name();
    let dir = s.out.join("mitsuba");
    let mut cmd = Command::new(python);
    cmd.arg(script)
        .arg(&s.scene)
        .arg("--variant")
        .arg(variant)
        .arg("--seed")
        .arg(s.seed.to_string())
        .arg("--out")
        .arg(&dir);
    cmd.arg("--spp").args(spp.iter().map(u32::to_string));
    if let Some(t) = m.threads {
        cmd.arg("--threads").arg(t.to_string());
    }
    if let Some(d) = s.max_depth {
        cmd.arg(format!("--max-depth={d}"));
    }
    for (k, v) in &s.defines {
        cmd.arg(format!("-D{k}={v}"));
    }
    cmd.stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .stdin(Stdio::null());
    let mut child = cmd.spawn().map_err(|e| {
        LabError::Mitsuba(format!(
            "cannot run '{}' for --mitsuba (give the interpreter with --python): {e}",
            python.display()
        ))
    })?;
    let stdout = child.stdout.take().expect("piped stdout");
    let name = format!("mitsuba-{variant}");
    let (points, info, failure) = read_points(stdout, &dir, &name, script, reference, log);
    if failure.is_some() {
        let _ = child.kill();
    }
    let status = child
        .wait()
        .map_err(|e| LabError::Mitsuba(format!("cannot wait for the Mitsuba process: {e}")))?;
    if let Some(e) = failure {
        return Err(e);
    }
    if !status.success() {
        return Err(LabError::Mitsuba(format!(
            "the Mitsuba run ({} {}) failed with {status}; its message is above",
            python.display(),
            script.display()
        )));
    }
    let got: Vec<u32> = points.iter().map(|p| p.spp).collect();
    if got != spp {
        return Err(LabError::Mitsuba(format!(
            "Mitsuba returned sample counts {got:?}, expected {spp:?}"
        )));
    }
    let get = |k: &str| {
        info.iter()
            .find(|(key, _)| key == k)
            .map_or("?", |(_, v)| v.as_str())
            .to_string()
    };
    let line = format!(
        "mitsuba {} {} ({} thread(s)): scene load {} s, untimed warm-up render (llvm tracing + JIT) {} s",
        get("mitsuba_version"),
        variant,
        get("threads"),
        get("load_s"),
        get("warmup_s")
    );
    log(&line);
    Ok((Series { name, points }, line))
}

/// What the script printed: the measured points, its `info` pairs, and the first failure
/// (a line that cannot be read, a malformed `point` line, an image that cannot be measured),
/// after which reading stops.
fn read_points(
    stdout: std::process::ChildStdout,
    dir: &std::path::Path,
    name: &str,
    script: &std::path::Path,
    reference: &Image,
    log: &(dyn Fn(&str) + Sync),
) -> (Vec<Point>, Vec<(String, String)>, Option<LabError>) {
    let mut points = Vec::new();
    let mut info: Vec<(String, String)> = Vec::new();
    for line in BufReader::new(stdout).lines() {
        let line = match line {
            Ok(l) => l,
            Err(e) => {
                let e = LabError::Mitsuba(format!("cannot read Mitsuba's output: {e}"));
                return (points, info, Some(e));
            }
        };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("point") => {
                let parsed = (|| {
                    let n: u32 = words.next()?.parse().ok()?;
                    let secs: f64 = words.next()?.parse().ok()?;
                    Some((n, secs))
                })();
                let Some((n, secs)) = parsed else {
                    let e = LabError::Mitsuba(format!(
                        "unexpected line from {}: '{line}'",
                        script.display()
                    ));
                    return (points, info, Some(e));
                };
                let path = dir.join(format!("spp{n}.exr"));
                let result = pt_image::read_exr(&path)
                    .map_err(LabError::from)
                    .and_then(|(img, _)| measure(&img, reference, n, secs, name, log));
                match result {
                    Ok(p) => points.push(p),
                    Err(e) => {
                        let e = e.context(format!("Mitsuba's image at {n} spp"));
                        return (points, info, Some(e));
                    }
                }
            }
            Some("info") => {
                if let Some(key) = words.next() {
                    info.push((key.to_string(), words.collect::<Vec<_>>().join(" ")));
                }
            }
            _ => log(&format!("mitsuba: {line}")),
        }
    }
    (points, info, None)
}
