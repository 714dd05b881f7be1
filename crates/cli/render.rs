//! `pt render`: one scene, one integrator, an EXR (with variance and a PNG preview when
//! asked), written atomically; Ctrl-C finishes the pass and writes what was rendered.

use crate::{load_scene, thread_pool, variance_path, SceneArgs};
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pt_cluster::part::PartFile;
use pt_image::{ExrMeta, Image};
use pt_integrators::{
    Checkpoint, Integrator, Job, Overrides, Progress, RenderState, Rendered, Run, Share, Strategy,
};
use pt_render::{BvhKind, LightSelection};
use pt_scene::{RadiosityOptions, SceneDesc};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct RenderArgs {
    /// Mitsuba 3 XML scene, or a glTF 2.0 file (.gltf / .glb). Without it, the built-in Cornell
    /// box is rendered.
    pub(crate) scene: Option<PathBuf>,
    /// Render only the K-th of N equal shares of every pixel's samples (sample indices K-1,
    /// K-1+N, K-1+2N ...) into a part file (-o, ending in .ptpart; default
    /// SCENE.partKofN.ptpart) for `pt merge`, which combines the N parts into exactly the image
    /// of the whole render. An unfinished part file of the same render is resumed; a finished
    /// one is left as it is. Every method but sppm and radiosity.
    #[arg(long, value_name = "K/N", value_parser = parse_part)]
    part: Option<(u32, u32)>,
    /// Save the render in progress every SECONDS (between passes): to the part file with
    /// --part, else to --save-state, so that a render that is killed resumes from there
    /// [default with --part: 60].
    #[arg(long, value_name = "SECONDS")]
    checkpoint: Option<u64>,
    /// Save the accumulated per-pixel sums here when the render ends or is interrupted (Ctrl-C),
    /// so that `--resume` can continue it.
    #[arg(long, value_name = "STATE")]
    save_state: Option<PathBuf>,
    /// Continue the render saved in STATE (same scene, options and seed) up to --spp samples per
    /// pixel; the result is bit-identical to an uninterrupted render.
    #[arg(long, value_name = "STATE")]
    resume: Option<PathBuf>,
    /// Output EXR path [default: the scene's file name with .exr, in the current folder].
    #[arg(short, long)]
    pub(crate) output: Option<PathBuf>,
    /// Samples per pixel [default: the scene's sampler sample_count].
    #[arg(long)]
    spp: Option<u32>,
    /// Seed of the random streams [default: the scene's sampler seed].
    #[arg(long)]
    seed: Option<u64>,
    /// Seconds since the lights went out: render the afterglow of phosphorescent materials
    /// (every light and emitter off; see crates/pt-integrators/src/afterglow.rs).
    #[arg(long, value_name = "SECONDS")]
    time: Option<f32>,
    /// Worker threads [default: all cores]. The image does not depend on it.
    #[arg(long)]
    pub(crate) threads: Option<usize>,
    /// Longest path in segments (1: emitters only, 2: direct light, -1: unlimited)
    /// [default: the scene's integrator max_depth].
    #[arg(long, allow_hyphen_values = true)]
    max_depth: Option<i32>,
    /// Image width in pixels [default: the scene's film]. Sets the whole film: the film's crop
    /// window, if any, is dropped.
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels [default: the scene's film].
    #[arg(long)]
    height: Option<u32>,
    /// Also write the per-pixel variance of the mean to OUT_var.exr. Under `splat` (with a
    /// filter wider than a pixel) it is the variance of the pixel's own samples' mean: what the
    /// mean of a region larger than the filter has per pixel (block z-tests such as `pt
    /// compare`'s), above a single splatted pixel's variance.
    #[arg(long)]
    pub(crate) variance: bool,
    /// How samples become pixels: `splat` is Mitsuba's film (each sample placed uniformly in
    /// its pixel and added with the filter's weight to every pixel it reaches: Mitsuba's
    /// per-pixel noise, correlated between neighbours); `importance` draws each sample's offset
    /// from the filter and keeps it in its own pixel (pbrt-v4's filter importance sampling:
    /// independent pixels, more noise per pixel under wide filters). Same expected image; the
    /// box filter gives the same image either way. Radiosity's display always uses
    /// `importance` [default: splat].
    #[arg(long, value_enum)]
    reconstruction: Option<ReconstructionArg>,
    /// Also write a tone-mapped sRGB PNG preview to this path.
    #[arg(long, value_name = "PNG")]
    pub(crate) png: Option<PathBuf>,
    /// Exposure of the PNG preview, in stops.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    exposure: f32,
    /// Direct-light strategy: MIS of light and BSDF sampling, or one of them alone
    /// [default: mis].
    #[arg(long, value_enum)]
    strategy: Option<StrategyArg>,
    /// Clamp each sample's radiance to at most this value (largest RGB channel; hue kept).
    /// Off by default: it removes fireflies but adds bias (darkens caustics and highlights of
    /// small lights); `pt stability` measures how much on a test scene.
    #[arg(long, value_name = "X")]
    clamp: Option<f32>,
    /// How next-event estimation picks a light: `power` gives each distant light
    /// (environment, sun, directional) its uniform share and splits the rest among the other
    /// lights by power; `tree` (the default) keeps the distant lights' shares and chooses among
    /// the others with a light tree, by power, distance and orientation from the shading point
    /// (Conty Estevez and Kulla 2018); `uniform` is Mitsuba's choice.
    #[arg(long, value_enum, default_value_t = SelectionArg::Tree)]
    light_selection: SelectionArg,
    /// Acceleration structure: `auto` tests scenes of at most 32 primitives without a tree
    /// (SIMD, faster at that size) and builds a CWBVH for larger ones; `cwbvh` and `bvh2` are
    /// obvhs's layouts (the CWBVH's tree traversed with uncompressed boxes); `flat` tests every
    /// primitive for every ray (small scenes only).
    #[arg(long, value_enum, default_value_t = BvhArg::Auto)]
    bvh: BvhArg,
    /// Colour transport [default: spectral when the scene has wavelength-dependent inputs
    /// (`pt info` says which), RGB otherwise]. Forcing rgb on a spectral scene projects its
    /// spectra to RGB (an approximation).
    #[arg(long, value_enum)]
    mode: Option<ModeArg>,
    /// Light transport method [default: the scene's integrator]. `radiosity` solves for
    /// diffuse patch radiosities and displays them (see the radiosity options below);
    /// `direct` shades the first hit with light and BSDF samples (Mitsuba's, one of each); `volpath` adds absorbing media;
    /// `ptracer` traces light paths from the lights and splats each vertex the camera sees
    /// (`--spp` light paths per pixel); `sppm` is stochastic progressive photon mapping (`--spp`
    /// iterations); `bdpt` is bidirectional path tracing and `vcm` vertex connection and
    /// merging (`--spp` iterations of one camera and one light subpath per pixel);
    /// `photonmapper` is Jensen's photon mapping (`--spp` iterations, each with its own
    /// photon maps). Naming the
    /// scene's own method keeps its parameters.
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(pt_integrators::METHODS))]
    integrator: Option<String>,
    #[command(flatten)]
    radiosity: RadiosityArgs,
    /// No progress bar or summary on stderr.
    #[arg(short, long)]
    pub(crate) quiet: bool,
    #[command(flatten)]
    scene_args: SceneArgs,
}

/// Options of the radiosity integrator; each overrides the scene's `<integrator type="radiosity">`
/// property of the same name.
#[derive(Args)]
struct RadiosityArgs {
    /// Radiosity: longest patch edge in scene units [default: 1/32 of the scene's diagonal].
    #[arg(long)]
    patch_size: Option<f32>,
    /// Radiosity: form-factor rays per patch [default: 1024].
    #[arg(long)]
    rays_per_patch: Option<u32>,
    /// Radiosity: jacobi, gauss_seidel or progressive [default: gauss_seidel].
    #[arg(long)]
    radiosity_solver: Option<pt_scene::RadiositySolver>,
    /// Radiosity: constant, smoothed or final_gather [default: smoothed].
    #[arg(long)]
    radiosity_display: Option<pt_scene::RadiosityDisplay>,
    /// Radiosity: none, average or balanced form-factor reciprocity [default: balanced].
    #[arg(long)]
    reciprocity: Option<pt_scene::Reciprocity>,
    /// Radiosity: relative residual at which the solver stops [default: 1e-4].
    #[arg(long)]
    tolerance: Option<f32>,
    /// Radiosity: iteration cap [default: 1000].
    #[arg(long)]
    max_iterations: Option<u32>,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ModeArg {
    Rgb,
    Spectral,
}

#[derive(Clone, Copy, ValueEnum)]
enum StrategyArg {
    Mis,
    Bsdf,
    Light,
}

#[derive(Clone, Copy, ValueEnum)]
enum ReconstructionArg {
    Splat,
    Importance,
}

#[derive(Clone, Copy, ValueEnum)]
enum SelectionArg {
    Tree,
    Power,
    Uniform,
}

#[derive(Clone, Copy, ValueEnum)]
enum BvhArg {
    Auto,
    Cwbvh,
    Bvh2,
    Flat,
}

impl RenderArgs {
    /// The command line's changes to the scene's integrator.
    fn overrides(&self) -> Overrides {
        let r = &self.radiosity;
        Overrides {
            // The parser admits only the names of `METHODS`, each of which `method` knows.
            kind: self.integrator.as_deref().and_then(pt_integrators::method),
            max_depth: self.max_depth,
            strategy: self.strategy.map(|s| match s {
                StrategyArg::Mis => Strategy::Mis,
                StrategyArg::Bsdf => Strategy::Bsdf,
                StrategyArg::Light => Strategy::Light,
            }),
            clamp: self.clamp,
            afterglow: self.time,
            radiosity: RadiosityOptions {
                patch_size: r.patch_size,
                rays_per_patch: r.rays_per_patch,
                tolerance: r.tolerance,
                max_iterations: r.max_iterations,
                solver: r.radiosity_solver,
                display: r.radiosity_display,
                reciprocity: r.reciprocity,
            },
        }
    }

    /// The scene with the command line's film size.
    pub(crate) fn scene(&self) -> Result<SceneDesc> {
        let mut desc = load_scene(self.scene.as_deref(), &self.scene_args)?;
        if self.width.is_some() || self.height.is_some() {
            // The command line sizes the whole film: a crop window of the file's film no
            // longer fits it.
            if let Some(c) = desc.film.crop.take() {
                [desc.film.width, desc.film.height] = c.film_size;
            }
        }
        if let Some(w) = self.width {
            desc.film.width = w;
        }
        if let Some(h) = self.height {
            desc.film.height = h;
        }
        if let Some(r) = self.reconstruction {
            desc.film.reconstruction = match r {
                ReconstructionArg::Splat => pt_scene::Reconstruction::Splat,
                ReconstructionArg::Importance => pt_scene::Reconstruction::Importance,
            };
        }
        if desc.film.width == 0 || desc.film.height == 0 {
            bail!(
                "image size must be at least 1x1, got {}x{}",
                desc.film.width,
                desc.film.height
            );
        }
        Ok(desc)
    }
}

/// The progress bar on stderr (hidden when not a terminal or with `--quiet`).
struct Bar(ProgressBar);

impl Bar {
    fn new(show: bool) -> Bar {
        let bar = if show {
            ProgressBar::with_draw_target(Some(1), ProgressDrawTarget::stderr())
        } else {
            ProgressBar::hidden()
        };
        Bar(bar)
    }
}

impl Progress for Bar {
    fn start_samples(&self, total: u64, done: u64) {
        self.0.set_length(total);
        self.0.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% {msps} M samples/s, ETA {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .with_key("msps", |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = write!(w, "{:.2}", state.per_sec() / 1e6);
            }),
        );
        self.0.set_position(done);
    }

    fn samples(&self, n: u64) {
        self.0.inc(n);
    }

    fn stage(&self, name: &str, fraction: f32) {
        if self.0.length() != Some(1000) {
            self.0.set_length(1000);
            self.0.set_style(
                ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {msg:<14} {wide_bar} {percent:>3}%",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
        }
        self.0.set_message(name.to_string());
        self.0
            .set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
    }
}

pub(crate) fn run(args: RenderArgs) -> Result<ExitCode> {
    // The arguments after `pt render`, recorded in part files so that `pt merge` can finish
    // the render as this command would.
    let argv: Vec<String> = std::env::args().skip(2).collect();
    execute(args, &argv, None)
}

/// Parses `K/N` (1 <= K <= N).
fn parse_part(s: &str) -> Result<(u32, u32), String> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| format!("expected K/N (such as 2/8), got '{s}'"))?;
    let k: u32 = k
        .trim()
        .parse()
        .map_err(|_| format!("K in K/N must be a whole number, got '{k}'"))?;
    let n: u32 = n
        .trim()
        .parse()
        .map_err(|_| format!("N in K/N must be a whole number, got '{n}'"))?;
    if n == 0 || k == 0 || k > n {
        return Err(format!("K/N needs 1 <= K <= N, got {k}/{n}"));
    }
    Ok((k, n))
}

/// `argv` without `--part K/N` and the output path (their forms `--part X`, `--part=X`,
/// `-o X`, `-oX`, `--output X`, `--output=X`): the arguments every part of a render shares.
fn shared_arguments(argv: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    let mut skip_next = false;
    for a in argv {
        if std::mem::take(&mut skip_next) {
            continue;
        }
        match a.as_str() {
            "--part" | "-o" | "--output" => skip_next = true,
            _ if a.starts_with("--part=") || a.starts_with("--output=") => {}
            _ if a.starts_with("-o") && a.len() > 2 && !a.starts_with("--") => {}
            _ => out.push(a.clone()),
        }
    }
    out
}

/// The `pt render` arguments alone (what a part file records), for `pt merge`.
#[derive(clap::Parser)]
#[command(name = "pt render", no_binary_name = true)]
struct StoredRender {
    #[command(flatten)]
    args: RenderArgs,
}

/// Reads the render arguments a part file recorded; relative scene paths are taken from the
/// part's working folder `cwd`.
pub(crate) fn stored_arguments(argv: &[String], cwd: &Path) -> Result<RenderArgs> {
    use clap::Parser as _;
    let mut args = StoredRender::try_parse_from(argv)
        .map_err(|e| anyhow::anyhow!("the part's render arguments do not parse: {e}"))?
        .args;
    if let Some(scene) = args.scene.as_mut() {
        if scene.is_relative() {
            *scene = cwd.join(&*scene);
        }
    }
    Ok(args)
}

/// Renders `args` (`argv` being the command line it came from), or with `merge`, writes the
/// outputs of the render whose parts these are (checked to be the whole render by
/// `pt_cluster::part::check_set`): their sums added, no samples taken.
pub(crate) fn execute(
    args: RenderArgs,
    argv: &[String],
    merge: Option<Vec<(PathBuf, PartFile)>>,
) -> Result<ExitCode> {
    let desc = args.scene()?;
    let integrator = Integrator::from_desc(&desc.integrator, &args.overrides())?;
    if args.spp == Some(0) {
        bail!("--spp must be at least 1");
    }
    integrator.check_scene(&desc)?;
    let part = requested_share(&args, merge.is_some(), &integrator)?;
    // A merge takes no samples: the parts' checkpoint setting does not apply.
    let checkpoint = if merge.is_some() {
        None
    } else {
        args.checkpoint
    };
    if checkpoint.is_some() && part.is_none() && args.save_state.is_none() {
        bail!("--checkpoint saves to the part file (--part) or to --save-state: give one of them");
    }
    let job = job_of(&args, &desc, part);
    let output = match (&args.output, part) {
        (Some(o), _) => o.clone(),
        (None, Some(sh)) => default_part_output(args.scene.as_deref(), sh),
        (None, None) => default_output(args.scene.as_deref()),
    };
    check_output_path(&output, if part.is_some() { "ptpart" } else { "exr" })?;
    let pool = thread_pool(args.threads)?;
    let key = state_key(&args, &desc, &job, &integrator);
    let settings = pt_integrators::RenderSettings {
        width: desc.film.width,
        height: desc.film.height,
        spp: job.share.samples_of(job.spp),
        seed: job.seed,
        ..pt_integrators::RenderSettings::from_desc(&desc)
    };
    let read_state = |bytes: &[u8], path: &Path| {
        integrator
            .read_state(bytes, key, &settings)
            .map_err(|m| anyhow::anyhow!("{}: {m}", path.display()))
    };
    // The part file this render writes, with the sums of `state`.
    let part_file = |sh: Share, state: &RenderState| PartFile {
        index: sh.index,
        count: sh.count,
        spp: job.spp,
        share_spp: settings.spp,
        done: state.spp_done,
        key,
        seed: job.seed,
        width: settings.width,
        height: settings.height,
        cwd: std::env::current_dir()
            .map(|d| d.display().to_string())
            .unwrap_or_default(),
        args: shared_arguments(argv),
        state: state.to_bytes(key),
    };
    let resume = match starting_state(&args, merge, part, &output, &job, key, &read_state)? {
        Start::From(state) => state,
        Start::Complete => return Ok(ExitCode::SUCCESS),
    };
    // Ctrl-C or SIGTERM: finish the current pass, then write what was accumulated (image and,
    // with --save-state, the sums; or the part file) and exit with code 130.
    let cancel = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        // Failing to install the handler (one is already installed) only loses Ctrl-C handling.
        let _ =
            ctrlc::set_handler(move || cancel.store(true, std::sync::atomic::Ordering::Relaxed));
    }
    // Where checkpoints and the final state go.
    let save_state = |state: &RenderState| -> Result<()> {
        match (part, &args.save_state) {
            (Some(sh), _) => {
                pt_image::write_bytes_atomically(&output, &part_file(sh, state).to_bytes())?
            }
            (None, Some(path)) => pt_image::write_bytes_atomically(path, &state.to_bytes(key))?,
            (None, None) => {}
        }
        Ok(())
    };
    let save_checkpoint = |state: &RenderState| {
        if let Err(e) = save_state(state) {
            eprintln!("warning: checkpoint not saved: {e:#}");
        }
    };
    let every = checkpoint.or(part.map(|_| 60));
    let bar = Bar::new(!args.quiet && std::io::stderr().is_terminal());
    let run = Run {
        progress: &bar,
        cancel: &cancel,
        resume,
        checkpoint: every.map(|secs| Checkpoint {
            every: std::time::Duration::from_secs(secs),
            save: &save_checkpoint,
        }),
    };
    let rendered = pool.install(|| integrator.render(&job, run))?;
    bar.0.finish_and_clear();
    match (&rendered.state, part.is_some() || args.save_state.is_some()) {
        (Some(state), true) => save_state(state)?,
        (None, true) => bail!(
            "--save-state applies to path, ptracer, sppm, photonmapper, bdpt and vcm, not to {}",
            integrator.name()
        ),
        _ => {}
    }
    finish(&args, &desc, &job, part, &rendered, &output, settings.spp)
}

/// The share of the samples `--part K/N` asks for (`None`: all of them); refused with the
/// options a part cannot have, when `merging` (a part file's own arguments), and for the
/// methods whose samples cannot be split.
fn requested_share(
    args: &RenderArgs,
    merging: bool,
    integrator: &Integrator,
) -> Result<Option<Share>> {
    Ok(match (args.part, merging) {
        (Some(_), true) => bail!("a part file's arguments contain --part"),
        (Some((k, n)), false) => {
            if args.resume.is_some() || args.save_state.is_some() {
                bail!("--part keeps its state in its part file: drop --resume and --save-state");
            }
            if args.variance || args.png.is_some() {
                bail!("--part writes a part file, not an image: --variance and --png belong to `pt merge`");
            }
            if let Some(why) = integrator.unshared_because() {
                bail!(
                    "--part applies to every sampling method but sppm, radiosity and depth, not to {}: {why}",
                    integrator.name(),
                );
            }
            Some(Share {
                index: k - 1,
                count: n,
            })
        }
        (None, _) => None,
    })
}

/// The render job of `desc` as the command line asks for it: samples, seed, acceleration
/// structure, light selection, colour mode and share `part`; the per-pixel variance only when
/// it is written (`--variance`) or saved with the sums (a part file, a saved or resumed state).
fn job_of<'a>(args: &RenderArgs, desc: &'a SceneDesc, part: Option<Share>) -> Job<'a> {
    Job {
        spp: args.spp.unwrap_or(desc.sampler.sample_count),
        seed: args.seed.unwrap_or(desc.sampler.seed),
        bvh: match args.bvh {
            BvhArg::Auto => BvhKind::Auto,
            BvhArg::Cwbvh => BvhKind::CwBvh,
            BvhArg::Bvh2 => BvhKind::Bvh2,
            BvhArg::Flat => BvhKind::Flat,
        },
        selection: match args.light_selection {
            SelectionArg::Tree => LightSelection::Tree,
            SelectionArg::Power => LightSelection::Power,
            SelectionArg::Uniform => LightSelection::Uniform,
        },
        mode: args.mode.map(|m| match m {
            ModeArg::Rgb => pt_spectrum::ColorMode::Rgb,
            ModeArg::Spectral => pt_spectrum::ColorMode::Spectral,
        }),
        share: part.unwrap_or(Share::WHOLE),
        variance: args.variance
            || part.is_some()
            || args.save_state.is_some()
            || args.resume.is_some()
            || args.checkpoint.is_some(),
        ..Job::new(desc)
    }
}

/// Where a render starts.
// One value per render: its size is of no consequence.
#[allow(clippy::large_enum_variant)]
enum Start {
    /// From scratch (`None`) or from a saved state.
    From(Option<RenderState>),
    /// Nowhere: its part file is complete.
    Complete,
}

/// The state a render continues: the sum of the `merge` parts, the `--resume` state, or the
/// unfinished part file at `output` of the same render (`key`, `part`, `job`); each read by
/// `read_state`.
fn starting_state(
    args: &RenderArgs,
    merge: Option<Vec<(PathBuf, PartFile)>>,
    part: Option<Share>,
    output: &Path,
    job: &Job,
    key: u64,
    read_state: &dyn Fn(&[u8], &Path) -> Result<RenderState>,
) -> Result<Start> {
    let state = if let Some(parts) = merge {
        // Sums are exact: the order of the additions does not matter (share order is used).
        let mut total: Option<RenderState> = None;
        for (path, p) in &parts {
            if p.key != key {
                bail!(
                    "{}: the scene file or the options changed since the part was rendered (the render's key differs)",
                    path.display()
                );
            }
            let s = read_state(&p.state, path)?;
            match total.as_mut() {
                None => total = Some(s),
                Some(t) => t
                    .merge(&s)
                    .map_err(|m| anyhow::anyhow!("{}: {m}", path.display()))?,
            }
        }
        total
    } else if let Some(path) = &args.resume {
        let bytes = std::fs::read(path)
            .with_context(|| format!("cannot read render state {}", path.display()))?;
        Some(read_state(&bytes, path)?)
    } else if let (Some(sh), true) = (part, output.exists()) {
        let p = PartFile::read(output)?;
        if (p.key, p.index, p.count, p.spp, p.seed) != (key, sh.index, sh.count, job.spp, job.seed)
        {
            bail!(
                "{} exists and holds part {} of another render (scene, options, seed or sample count differ): delete it or write this part elsewhere (-o)",
                output.display(),
                p.label()
            );
        }
        if p.complete() {
            if !args.quiet {
                eprintln!(
                    "part {} is already complete ({} spp) in {}",
                    p.label(),
                    p.done,
                    output.display()
                );
            }
            return Ok(Start::Complete);
        }
        if !args.quiet {
            eprintln!(
                "resuming part {} from {} of {} spp in {}",
                p.label(),
                p.done,
                p.share_spp,
                output.display()
            );
        }
        Some(read_state(&p.state, output)?)
    } else {
        None
    };
    Ok(Start::From(state))
}

/// After the render: the part file's line or the image files with theirs, the warnings, and
/// the exit code (130 when interrupted, with what was written of the `spp` asked for).
fn finish(
    args: &RenderArgs,
    desc: &SceneDesc,
    job: &Job,
    part: Option<Share>,
    rendered: &Rendered,
    output: &Path,
    spp: u32,
) -> Result<ExitCode> {
    if let Some(sh) = part {
        if !args.quiet {
            eprintln!(
                "part {}/{}: {} -> {}",
                sh.index + 1,
                sh.count,
                rendered.summary,
                output.display()
            );
        }
    } else {
        write_outputs(args, desc, job, rendered, output)?;
        if !args.quiet {
            eprintln!("{} -> {}", rendered.summary, output.display());
        }
    }
    for w in &rendered.warnings {
        eprintln!("warning: {w}");
    }
    if !rendered.complete {
        eprintln!(
            "interrupted: wrote the {} of the {} of {} samples per pixel taken so far{}",
            if part.is_some() { "part file" } else { "image" },
            rendered.output.spp,
            spp,
            if part.is_some() {
                " (run the same command again to resume it)"
            } else if args.save_state.is_some() {
                " and the state to continue it with --resume"
            } else {
                " (add --save-state to be able to resume)"
            }
        );
        return Ok(ExitCode::from(130));
    }
    Ok(ExitCode::SUCCESS)
}

/// Identifies the scene and every option that changes the samples, so that `--resume` refuses a
/// state made with anything else (FNV-1a over the scene file's bytes and the settings).
fn state_key(args: &RenderArgs, desc: &SceneDesc, job: &Job, integrator: &Integrator) -> u64 {
    let mut bytes = std::fs::read(&desc.source)
        .unwrap_or_else(|_| desc.source.to_string_lossy().as_bytes().to_vec());
    let text = format!(
        "{:?}|{:?}|{:?}|{:?}|{integrator:?}|{:?}|{:?}|{:?}",
        job.bvh,
        args.scene_args.defines,
        desc.film.filter,
        desc.film.reconstruction,
        job.mode,
        job.selection,
        args.scene_args.camera
    );
    bytes.extend_from_slice(text.as_bytes());
    pt_cluster::part::fnv1a(&bytes)
}

/// Writes the EXR (and variance and PNG preview when asked), each atomically.
fn write_outputs(
    args: &RenderArgs,
    desc: &SceneDesc,
    job: &Job,
    r: &Rendered,
    output: &Path,
) -> Result<()> {
    let out = &r.output;
    let image = Image {
        width: out.width,
        height: out.height,
        data: out.mean.clone(),
    };
    let mut extra = vec![
        (
            "pt_version".to_string(),
            env!("CARGO_PKG_VERSION").to_string(),
        ),
        ("scene".to_string(), desc.source.display().to_string()),
        ("seed".to_string(), job.seed.to_string()),
    ];
    extra.extend(r.header.iter().cloned());
    let meta = ExrMeta {
        spp: Some(out.spp),
        mode: Some(r.mode.name().to_string()),
        render_time_s: Some(out.time.as_secs_f64()),
        extra,
    };
    let channels = r
        .channels(desc.film.pixel_format)
        .map_err(|m| anyhow::anyhow!("{}: {m}", desc.source.display()))?;
    let planes: Vec<(&str, &[f32])> = channels.iter().map(|(n, p)| (n.as_str(), &p[..])).collect();
    pt_image::write_exr_channels(output, out.width, out.height, &planes, &meta)?;
    if args.variance {
        let var = Image {
            width: out.width,
            height: out.height,
            data: out.variance.clone(),
        };
        pt_image::write_exr(&variance_path(output), &var, &meta)?;
    }
    if let Some(png) = &args.png {
        pt_image::write_png_preview(png, &image, args.exposure)?;
    }
    Ok(())
}

/// `scene.xml` -> `scene`; the built-in box -> `cornell-box`.
fn scene_stem(scene: Option<&Path>) -> String {
    scene
        .and_then(|p| p.file_stem())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "cornell-box".into())
}

/// `scene.xml` -> `scene.exr` in the current folder; the built-in box -> `cornell-box.exr`.
fn default_output(scene: Option<&Path>) -> PathBuf {
    PathBuf::from(format!("{}.exr", scene_stem(scene)))
}

/// `scene.xml`, part 2 of 8 -> `scene.part2of8.ptpart` in the current folder.
pub(crate) fn default_part_output(scene: Option<&Path>, share: Share) -> PathBuf {
    PathBuf::from(format!(
        "{}.part{}of{}.ptpart",
        scene_stem(scene),
        share.index + 1,
        share.count
    ))
}

/// Fails early (before rendering) when the output cannot be written: it must end in
/// `.extension` and its folder must exist.
pub(crate) fn check_output_path(output: &Path, extension: &str) -> Result<()> {
    if output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.eq_ignore_ascii_case(extension))
        != Some(true)
    {
        bail!("output '{}' must end in .{extension}", output.display());
    }
    let dir = output
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        bail!(
            "cannot write '{}': folder '{}' does not exist",
            output.display(),
            dir.display()
        );
    }
    Ok(())
}
