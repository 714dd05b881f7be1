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
mod converge;
mod fireflies;
mod lobes;
mod stability;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pt_image::{ExrMeta, Image};
use pt_render::{BvhKind, LightSelection, RenderSettings, Scene, Strategy};
use pt_scene::{Geometry, SceneDesc};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The Cornell box rendered when no scene is given (scenes/cornell-box.xml, embedded).
const BUILTIN_CORNELL: &str = include_str!("../../scenes/cornell-box.xml");

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
    Render(RenderArgs),
    /// Print what a scene contains: shapes, triangles, lights, materials, camera, colour mode.
    Info(InfoArgs),
    /// Compare an image with a reference: error metrics and, given variances, a block z-test.
    /// Exit code 0 when they agree, 1 when they do not, 2 for bad input.
    Compare(CompareArgs),
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
struct CompareArgs {
    /// The image to judge (EXR from pt or Mitsuba).
    image: PathBuf,
    /// The reference (EXR).
    reference: PathBuf,
    /// Variance of the reference's pixel means [default: REFERENCE_var.exr if it exists].
    #[arg(long, value_name = "REF_VAR.exr")]
    variance: Option<PathBuf>,
    /// Variance of the image's pixel means [default: IMAGE_var.exr if it exists].
    #[arg(long, value_name = "IMG_VAR.exr")]
    image_variance: Option<PathBuf>,
    /// Block size of the z-test, pixels.
    #[arg(long, default_value_t = 16)]
    block: u32,
    /// Family-wise significance of the z-test (Sidak-corrected over blocks).
    #[arg(long, default_value_t = 0.01)]
    alpha: f64,
    /// Write a false-colour relative error image (EXR or PNG).
    #[arg(long, value_name = "OUT")]
    error_image: Option<PathBuf>,
    /// Exposure (stops) of the tone mapping both images get before FLIP (scale by 2^stops, clamp, sRGB).
    #[arg(long, default_value_t = 0.0)]
    flip_exposure: f32,
    /// Write FLIP's per-pixel error (0 to 1, viridis) as a false-colour image (EXR or PNG).
    #[arg(long, value_name = "OUT")]
    flip_image: Option<PathBuf>,
}

#[derive(Args)]
struct SceneArgs {
    /// Set a scene `<default>` parameter, as Mitsuba's `-D name=value` (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    defines: Vec<String>,
    /// glTF scenes: which camera to use (0-based, in node order as `pt info` lists them)
    /// [default: the first perspective camera].
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
}

#[derive(Args)]
struct RenderArgs {
    /// Mitsuba 3 XML scene, or a glTF 2.0 file (.gltf / .glb). Without it, the built-in Cornell
    /// box is rendered.
    scene: Option<PathBuf>,
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
    output: Option<PathBuf>,
    /// Samples per pixel [default: the scene's sampler sample_count].
    #[arg(long)]
    spp: Option<u32>,
    /// Seed of the random streams [default: the scene's sampler seed].
    #[arg(long)]
    seed: Option<u64>,
    /// Seconds since the lights went out: render the afterglow of phosphorescent materials
    /// (every light and emitter off; see crates/pt-render/src/phosphorescence.rs).
    #[arg(long, value_name = "SECONDS")]
    time: Option<f32>,
    /// Worker threads [default: all cores]. The image does not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Longest path in segments (1: emitters only, 2: direct light, -1: unlimited)
    /// [default: the scene's integrator max_depth].
    #[arg(long, allow_hyphen_values = true)]
    max_depth: Option<i32>,
    /// Image width in pixels [default: the scene's film].
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels [default: the scene's film].
    #[arg(long)]
    height: Option<u32>,
    /// Also write the per-pixel variance of the mean to OUT_var.exr.
    #[arg(long)]
    variance: bool,
    /// Also write a tone-mapped sRGB PNG preview to this path.
    #[arg(long, value_name = "PNG")]
    png: Option<PathBuf>,
    /// Exposure of the PNG preview, in stops.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    exposure: f32,
    /// Direct-light strategy: MIS of light and BSDF sampling, or one of them alone.
    #[arg(long, value_enum, default_value_t = StrategyArg::Mis)]
    strategy: StrategyArg,
    /// Clamp each sample's radiance to at most this value (largest RGB channel; hue kept).
    /// Off by default: it removes fireflies but adds bias (darkens caustics and highlights of
    /// small lights); `pt stability` measures how much on a test scene.
    #[arg(long, value_name = "X")]
    clamp: Option<f32>,
    /// How next-event estimation picks a light.
    #[arg(long, value_enum, default_value_t = SelectionArg::Power)]
    light_selection: SelectionArg,
    /// Acceleration structure: `auto` tests scenes of at most 32 primitives without a tree
    /// (SIMD, faster at that size) and builds a CWBVH for larger ones; `cwbvh` and `bvh2` are
    /// obvhs's layouts; `flat` tests every primitive for every ray (small scenes only).
    #[arg(long, value_enum, default_value_t = BvhArg::Auto)]
    bvh: BvhArg,
    /// Colour transport [default: spectral when the scene has wavelength-dependent inputs
    /// (`pt info` says which), RGB otherwise]. Forcing rgb on a spectral scene projects its
    /// spectra to RGB (an approximation).
    #[arg(long, value_enum)]
    mode: Option<ModeArg>,
    /// Global-illumination method [default: the scene's integrator]. `radiosity` solves for
    /// diffuse patch radiosities and displays them (see the radiosity options below).
    #[arg(long, value_enum)]
    integrator: Option<IntegratorArg>,
    #[command(flatten)]
    radiosity: RadiosityArgs,
    /// No progress bar or summary on stderr.
    #[arg(short, long)]
    quiet: bool,
    #[command(flatten)]
    scene_args: SceneArgs,
}

#[derive(Args)]
struct InfoArgs {
    /// Mitsuba 3 XML scene or glTF 2.0 file (.gltf / .glb) [default: the built-in Cornell box].
    scene: Option<PathBuf>,
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
    radiosity_solver: Option<String>,
    /// Radiosity: constant, smoothed or final_gather [default: smoothed].
    #[arg(long)]
    radiosity_display: Option<String>,
    /// Radiosity: none, average or balanced form-factor reciprocity [default: balanced].
    #[arg(long)]
    reciprocity: Option<String>,
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

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum IntegratorArg {
    Path,
    Radiosity,
}

#[derive(Clone, Copy, ValueEnum)]
enum StrategyArg {
    Mis,
    Bsdf,
    Light,
}

#[derive(Clone, Copy, ValueEnum)]
enum SelectionArg {
    Power,
    Uniform,
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

#[derive(Clone, Copy, ValueEnum)]
enum BvhArg {
    Auto,
    Cwbvh,
    Bvh2,
    Flat,
}

fn main() -> ExitCode {
    return_large_frees_to_the_os();
    let cli = Cli::parse();
    // `<shape type="gltf">` in XML scenes reads meshes through pt-gltf.
    pt_scene::set_gltf_mesh_reader(pt_gltf::load_mesh);
    let result = match cli.command {
        Command::Render(args) => cmd_render(args),
        Command::Info(args) => cmd_info(args),
        Command::Compare(args) => cmd_compare(args),
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
fn load_scene(path: Option<&Path>, args: &SceneArgs) -> Result<SceneDesc> {
    Ok(load_scene_with_summary(path, args)?.0)
}

/// [`load_scene`], and for a glTF file (`.gltf`, `.glb`) also its `pt info` listing; the glTF
/// reader's warnings (defaults used, features ignored) go to stderr.
fn load_scene_with_summary(
    path: Option<&Path>,
    args: &SceneArgs,
) -> Result<(SceneDesc, Vec<String>)> {
    if let Some(p) = path.filter(|p| pt_gltf::is_gltf_path(p)) {
        if !args.defines.is_empty() {
            bail!("-D applies to Mitsuba XML scenes, not to glTF files");
        }
        let g = pt_gltf::load(
            p,
            &pt_gltf::LoadOptions {
                camera: args.camera,
            },
        )?;
        for w in &g.warnings {
            eprintln!("warning: {w}");
        }
        return Ok((g.desc, g.summary));
    }
    if args.camera.is_some() {
        bail!("--camera applies to glTF files (a Mitsuba XML scene has one sensor)");
    }
    let defines = parse_defines(&args.defines)?;
    let desc = match path {
        Some(p) => pt_scene::load_file(p, &defines)?,
        None => {
            let cwd = std::env::current_dir().context("cannot read the current folder")?;
            pt_scene::load_str(
                BUILTIN_CORNELL,
                Path::new("<built-in cornell-box.xml>"),
                &cwd,
                &defines,
            )?
        }
    };
    if desc.integrator.kind == pt_scene::IntegratorKind::Path {
        if let Some(s) = desc.shapes.iter().find(|s| s.interior.is_some()) {
            eprintln!(
                "warning: {}: the `path` integrator ignores media, as Mitsuba's does; use <integrator type=\"volpath\"> for absorption",
                s.interior.as_ref().map_or(&s.loc, |m| &m.loc)
            );
        }
    }
    Ok((desc, Vec::new()))
}

fn cmd_render(args: RenderArgs) -> Result<ExitCode> {
    let mut desc = load_scene(args.scene.as_deref(), &args.scene_args)?;
    if let Some(w) = args.width {
        desc.film.width = w;
    }
    if let Some(h) = args.height {
        desc.film.height = h;
    }
    if desc.film.width == 0 || desc.film.height == 0 {
        bail!(
            "image size must be at least 1x1, got {}x{}",
            desc.film.width,
            desc.film.height
        );
    }
    let mut settings = RenderSettings::from_desc(&desc);
    if let Some(spp) = args.spp {
        if spp == 0 {
            bail!("--spp must be at least 1");
        }
        settings.spp = spp;
    }
    if let Some(seed) = args.seed {
        settings.seed = seed;
    }
    if let Some(d) = args.max_depth {
        if d < -1 {
            bail!("--max-depth must be -1 (unlimited) or >= 0, got {d}");
        }
        settings.path.max_depth = d;
    }
    if let Some(c) = args.clamp {
        if !(c > 0.0 && c.is_finite()) {
            bail!("--clamp must be a positive finite radiance, got {c}");
        }
        settings.clamp = Some(c);
    }
    settings.path.strategy = match args.strategy {
        StrategyArg::Mis => Strategy::Mis,
        StrategyArg::Bsdf => Strategy::Bsdf,
        StrategyArg::Light => Strategy::Light,
    };
    let selection = match args.light_selection {
        SelectionArg::Power => LightSelection::Power,
        SelectionArg::Uniform => LightSelection::Uniform,
    };
    let bvh = match args.bvh {
        BvhArg::Auto => BvhKind::Auto,
        BvhArg::Cwbvh => BvhKind::CwBvh,
        BvhArg::Bvh2 => BvhKind::Bvh2,
        BvhArg::Flat => BvhKind::Flat,
    };
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(args.scene.as_deref()));
    check_output_path(&output)?;

    let pool = thread_pool(args.threads)?;

    let radiosity = match args.integrator {
        Some(i) => i == IntegratorArg::Radiosity,
        None => desc.integrator.kind == pt_scene::IntegratorKind::Radiosity,
    };
    if radiosity {
        return render_radiosity(&args, &desc, &settings, &output, &pool);
    }

    let build_start = std::time::Instant::now();
    let mode = args.mode.map(|m| match m {
        ModeArg::Rgb => pt_spectrum::ColorMode::Rgb,
        ModeArg::Spectral => pt_spectrum::ColorMode::Spectral,
    });
    let desc = match args.time {
        Some(t) => {
            pool.install(|| pt_render::phosphorescence::afterglow(&desc, t, settings.seed))?
        }
        None => desc,
    };
    let scene = pool.install(|| Scene::build_with_mode(&desc, bvh, selection, mode))?;
    let build_time = build_start.elapsed();

    let total = settings.width as u64 * settings.height as u64 * settings.spp as u64;
    let show = !args.quiet && std::io::stderr().is_terminal();
    let bar = if show {
        ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% {msps} M samples/s, ETA {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .with_key(
            "msps",
            |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = write!(w, "{:.2}", state.per_sec() / 1e6);
            },
        ),
    );
    // Ctrl-C: finish the current pass, then write what was accumulated (image and, with
    // --save-state, the sums) and exit with code 130.
    let cancel = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        // Failing to install the handler (one is already installed) only loses Ctrl-C handling.
        let _ =
            ctrlc::set_handler(move || cancel.store(true, std::sync::atomic::Ordering::Relaxed));
    }
    let key = state_key(&args, &desc, &settings, scene.mode.name());
    let mut state = match &args.resume {
        Some(path) => {
            let bytes = std::fs::read(path)
                .with_context(|| format!("cannot read render state {}", path.display()))?;
            pt_integrators::RenderState::from_bytes(&bytes, key, &settings)
                .map_err(|m| anyhow::anyhow!("{}: {m}", path.display()))?
        }
        None => pt_integrators::RenderState::new(&settings),
    };
    if state.spp_done > settings.spp {
        bail!(
            "the saved render already has {} spp, more than --spp {}",
            state.spp_done,
            settings.spp
        );
    }
    bar.inc(settings.width as u64 * settings.height as u64 * u64::from(state.spp_done));
    let complete = pool.install(|| {
        pt_integrators::render_passes(&scene, &settings, &mut state, &cancel, &|n| bar.inc(n))
    });
    let out = state.output();
    bar.finish_and_clear();
    if let Some(path) = &args.save_state {
        pt_image::write_bytes_atomically(path, &state.to_bytes(key))?;
    }

    let extra: Vec<(String, String)> = vec![
        ("integrator".into(), "path".into()),
        ("max_depth".into(), settings.path.max_depth.to_string()),
        (
            "strategy".into(),
            format!("{:?}", settings.path.strategy).to_lowercase(),
        ),
    ]
    .into_iter()
    .chain(settings.clamp.map(|c| ("clamp".to_string(), c.to_string())))
    .collect();
    write_outputs(
        &args,
        &desc,
        &settings,
        &out,
        scene.mode.name(),
        extra,
        &output,
    )?;
    if !args.quiet {
        let secs = out.time.as_secs_f64();
        eprintln!(
            "rendered {}x{} at {} spp in {:.2} s ({:.2} M samples/s, scene build {:.2} s) -> {}",
            out.width,
            out.height,
            out.spp,
            secs,
            total as f64 / secs.max(1e-9) / 1e6,
            build_time.as_secs_f64(),
            output.display()
        );
        if out.nonfinite_samples > 0 {
            eprintln!(
                "warning: {} samples were NaN or infinite and were left out of their pixels",
                out.nonfinite_samples
            );
        }
    }
    if !complete {
        eprintln!(
            "interrupted: wrote the image of the {} of {} samples per pixel taken so far{}",
            out.spp,
            settings.spp,
            if args.save_state.is_some() {
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
fn state_key(args: &RenderArgs, desc: &SceneDesc, settings: &RenderSettings, mode: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    match std::fs::read(&desc.source) {
        Ok(b) => eat(&b),
        Err(_) => eat(desc.source.to_string_lossy().as_bytes()),
    }
    let text = format!(
        "{:?}|{:?}|{:?}|{:?}|{mode}|{:?}|{}|{:?}",
        args.scene_args.defines,
        settings.filter,
        settings.path,
        settings.clamp,
        args.time,
        args.light_selection as u8,
        args.scene_args.camera
    );
    eat(text.as_bytes());
    h
}

/// Writes the EXR (and variance and PNG preview when asked), each atomically.
fn write_outputs(
    args: &RenderArgs,
    desc: &SceneDesc,
    settings: &RenderSettings,
    out: &pt_render::RenderOutput,
    mode: &str,
    mut extra: Vec<(String, String)>,
    output: &Path,
) -> Result<()> {
    let image = Image {
        width: out.width,
        height: out.height,
        data: out.mean.clone(),
    };
    extra.splice(
        0..0,
        [
            (
                "pt_version".to_string(),
                env!("CARGO_PKG_VERSION").to_string(),
            ),
            ("scene".to_string(), desc.source.display().to_string()),
            ("seed".to_string(), settings.seed.to_string()),
        ],
    );
    let meta = ExrMeta {
        spp: Some(out.spp),
        mode: Some(mode.to_string()),
        render_time_s: Some(out.time.as_secs_f64()),
        extra,
    };
    pt_image::write_exr(output, &image, &meta)?;
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

/// `pt render --integrator radiosity` (or a scene whose integrator is `radiosity`).
fn render_radiosity(
    args: &RenderArgs,
    desc: &SceneDesc,
    settings: &RenderSettings,
    output: &Path,
    pool: &rayon::ThreadPool,
) -> Result<ExitCode> {
    use pt_radiosity::{Display, RadiosityParams, Reciprocity, Solver};
    if args.max_depth.is_some()
        || args.clamp.is_some()
        || !matches!(args.strategy, StrategyArg::Mis)
        || !matches!(args.light_selection, SelectionArg::Power)
    {
        bail!("--max-depth, --clamp, --strategy and --light-selection apply to the path tracer, not to radiosity");
    }
    let o = &desc.integrator.radiosity;
    let r = &args.radiosity;
    let at = |what: &str, e: String| anyhow::anyhow!("{}: {what}: {e}", desc.integrator.loc);
    let mut p = RadiosityParams {
        spp: settings.spp,
        seed: settings.seed,
        ..RadiosityParams::default()
    };
    p.patch_size = r.patch_size.or(o.patch_size).or(p.patch_size);
    p.rays_per_patch = r
        .rays_per_patch
        .or(o.rays_per_patch)
        .unwrap_or(p.rays_per_patch);
    p.tolerance = r.tolerance.or(o.tolerance).unwrap_or(p.tolerance);
    p.max_iterations = r
        .max_iterations
        .or(o.max_iterations)
        .unwrap_or(p.max_iterations);
    if let Some(s) = r.radiosity_solver.as_ref().or(o.solver.as_ref()) {
        p.solver = s
            .parse::<Solver>()
            .map_err(|e| at("solver", e.to_string()))?;
    }
    if let Some(s) = r.radiosity_display.as_ref().or(o.display.as_ref()) {
        p.display = s
            .parse::<Display>()
            .map_err(|e| at("display", e.to_string()))?;
    }
    if let Some(s) = r.reciprocity.as_ref().or(o.reciprocity.as_ref()) {
        p.reciprocity = s
            .parse::<Reciprocity>()
            .map_err(|e| at("reciprocity", e.to_string()))?;
    }
    let show = !args.quiet && std::io::stderr().is_terminal();
    let bar = if show {
        ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {msg:<14} {wide_bar} {percent:>3}%",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let (out, stats) = pool.install(|| {
        pt_radiosity::render(desc, &p, &|stage, f| {
            bar.set_message(stage.to_string());
            bar.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64);
        })
    })?;
    bar.finish_and_clear();
    for w in &stats.warnings {
        eprintln!("warning: {w}");
    }
    let extra = vec![
        ("integrator".into(), "radiosity".into()),
        ("patches".into(), stats.patches.to_string()),
        ("rays_per_patch".into(), p.rays_per_patch.to_string()),
        ("solver".into(), format!("{:?}", p.solver).to_lowercase()),
        ("display".into(), format!("{:?}", p.display).to_lowercase()),
        ("iterations".into(), stats.iterations.to_string()),
    ];
    write_outputs(args, desc, settings, &out, "rgb", extra, output)?;
    if !args.quiet {
        eprintln!(
            "radiosity: {} patches (size {:.4}), {} form factors ({:.1} MB), form factors {:.2} s, solve {:.2} s in {} iterations, total {:.2} s -> {}",
            stats.patches,
            stats.patch_size,
            stats.nnz,
            stats.memory_bytes as f64 / 1e6,
            stats.form_factor_time.as_secs_f64(),
            stats.solve_time.as_secs_f64(),
            stats.iterations,
            out.time.as_secs_f64(),
            output.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `scene.xml` -> `scene.exr` in the current folder; the built-in box -> `cornell-box.exr`.
fn default_output(scene: Option<&Path>) -> PathBuf {
    let stem = scene
        .and_then(|p| p.file_stem())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "cornell-box".into());
    PathBuf::from(format!("{stem}.exr"))
}

/// `out.exr` -> `out_var.exr`.
fn variance_path(output: &Path) -> PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    output.with_file_name(format!("{stem}_var.exr"))
}

/// Fails early (before rendering) when the output cannot be written.
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

fn check_output_path(output: &Path) -> Result<()> {
    if output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.eq_ignore_ascii_case("exr"))
        != Some(true)
    {
        bail!("output '{}' must end in .exr", output.display());
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

/// One line describing a material for `pt info`: wrappers (twosided, mask, normalmap, blend,
/// textured opacity and film thickness) as `name(parameters, inner)`, textures by their file or
/// embedded name, models by their parameters.
fn describe_bsdf(kind: &pt_scene::BsdfKind) -> String {
    use pt_scene::BsdfKind as K;
    let tex = |t: &pt_scene::UvTexture| match &t.source {
        pt_scene::ImageSource::File(p) => p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        ),
        pt_scene::ImageSource::Embedded { name, .. } => name.clone(),
    };
    match kind {
        K::TwoSided { inner } => format!("twosided({})", describe_bsdf(&inner.kind)),
        K::Mask { opacity, inner } => {
            format!("mask(opacity {opacity}, {})", describe_bsdf(&inner.kind))
        }
        K::NormalMap {
            texture,
            scale,
            gltf,
            inner,
        } => {
            format!(
                "normalmap({}, {} tangent space, scale {scale}, {})",
                tex(texture),
                if *gltf { "glTF" } else { "Mitsuba" },
                describe_bsdf(&inner.kind)
            )
        }
        K::Blend {
            weight,
            weight_texture,
            first,
            second,
        } => {
            let w = match weight_texture {
                Some((t, channel)) => format!("weight {weight} x {} {channel:?}", tex(t)),
                None => format!("weight {weight}"),
            };
            format!(
                "blend({w}, {} | {})",
                describe_bsdf(&first.kind),
                describe_bsdf(&second.kind)
            )
        }
        K::OpacityTexture {
            texture,
            channel,
            factor,
            cutoff,
            inner,
        } => {
            let cut = cutoff.map(|c| format!(", cutoff {c}")).unwrap_or_default();
            format!(
                "mask(opacity {factor} x {} {channel:?}{cut}, {})",
                tex(texture),
                describe_bsdf(&inner.kind)
            )
        }
        K::FilmThicknessTexture {
            texture,
            min_nm,
            max_nm,
            inner,
        } => {
            format!(
                "film-thickness({}, {min_nm}..{max_nm} nm, {})",
                tex(texture),
                describe_bsdf(&inner.kind)
            )
        }
        K::GltfPbr {
            base_color,
            metallic,
            roughness,
            ior,
            base_color_texture,
            metallic_roughness_texture,
        } => {
            let t = |o: &Option<Box<pt_scene::UvTexture>>, what: &str| {
                o.as_ref()
                    .map(|t| format!(", {what} x {}", tex(t)))
                    .unwrap_or_default()
            };
            format!(
                "GltfPbr {{ base_color: {base_color:?}{}, metallic: {metallic}, roughness: {roughness}{}, ior: {ior} }}",
                t(base_color_texture, "texture"),
                t(metallic_roughness_texture, "metallic-roughness texture")
            )
        }
        other => format!("{other:?}"),
    }
}

fn cmd_info(args: InfoArgs) -> Result<ExitCode> {
    let (desc, gltf_summary) = load_scene_with_summary(args.scene.as_deref(), &args.scene_args)?;
    let scene = Scene::build(&desc, BvhKind::Auto, LightSelection::Power)?;
    out!("scene       {}", desc.source.display());
    out!(
        "film        {}x{}, filter {:?}",
        desc.film.width,
        desc.film.height,
        desc.film.filter
    );
    out!(
        "sampler     {} spp, seed {}",
        desc.sampler.sample_count,
        desc.sampler.seed
    );
    let i = &desc.integrator;
    out!(
        "integrator  {:?}, max_depth {}, rr_depth {}, hide_emitters {}{}",
        i.kind,
        i.max_depth,
        i.rr_depth,
        i.hide_emitters,
        if i.moment {
            " (moment: variance requested)"
        } else {
            ""
        }
    );
    let c = &desc.camera;
    let pos = c.to_world.transform_point3(pt_math::Vec3::ZERO);
    let dir = c.to_world.transform_vector3(pt_math::Vec3::Z).normalize();
    out!(
        "camera      {:?}, at ({:.3}, {:.3}, {:.3}) looking ({:.3}, {:.3}, {:.3})",
        c.projection,
        pos.x,
        pos.y,
        pos.z,
        dir.x,
        dir.y,
        dir.z
    );
    out!(
        "geometry    {} shapes, {} triangles{}, {} spheres{}",
        desc.shapes.len(),
        scene.stats.triangles,
        if scene.stats.parallelograms > 0 {
            format!(
                " ({} pairs tested as parallelograms)",
                scene.stats.parallelograms
            )
        } else {
            String::new()
        },
        scene.stats.spheres,
        if scene.stats.degenerate_triangles > 0 {
            format!(
                " ({} zero-area triangles skipped)",
                scene.stats.degenerate_triangles
            )
        } else {
            String::new()
        }
    );
    for (k, s) in desc.shapes.iter().enumerate() {
        let geo = match &s.geometry {
            Geometry::Mesh(m) => format!("{} triangles", m.indices.len()),
            Geometry::Sphere { radius, .. } => format!("sphere r={radius}"),
        };
        let bsdf = &desc.bsdfs[s.bsdf];
        out!(
            "  shape {k:<3} {:<10} {:<16} bsdf {:<12} {}{}",
            s.plugin,
            geo,
            bsdf.id.as_deref().unwrap_or("-"),
            s.emitter
                .as_ref()
                .map(|e| format!(
                    "emits {:?}{}",
                    e.radiance,
                    if e.texture.is_some() || e.uv_texture.is_some() {
                        " x texture"
                    } else {
                        ""
                    }
                ))
                .unwrap_or_default()
                + &s.interior
                    .as_ref()
                    .map(|m| format!(" interior medium sigma_t {:?}", m.sigma_t))
                    .unwrap_or_default(),
            s.id.as_deref()
                .map(|id| format!(" id={id}"))
                .unwrap_or_default(),
        );
    }
    out!("materials   {}", desc.bsdfs.len());
    for b in &desc.bsdfs {
        out!(
            "  {:<12} {}",
            b.id.as_deref().unwrap_or("-"),
            describe_bsdf(&b.kind)
        );
    }
    out!("lights      {} area light(s)", scene.lights.len());
    if !gltf_summary.is_empty() {
        out!("glTF        (how the file maps onto the renderer; see pt-gltf's documentation)");
        for line in &gltf_summary {
            out!("  {line}");
        }
    }
    match desc.spectral_reason() {
        Some(why) => out!("mode        spectral, because {why}"),
        None => out!("mode        rgb (every input is RGB and no material depends on wavelength: RGB is exact)"),
    }
    Ok(ExitCode::SUCCESS)
}

/// `a.exr` -> `a_var.exr` if that file exists.
fn sibling_variance(path: &Path) -> Option<PathBuf> {
    let v = variance_path(path);
    v.is_file().then_some(v)
}

fn cmd_compare(args: CompareArgs) -> Result<ExitCode> {
    // Output names are checked before any work, so a bad one fails fast with nothing written.
    for (flag, out) in [
        ("--error-image", &args.error_image),
        ("--flip-image", &args.flip_image),
    ] {
        if let Some(out) = out {
            if !matches!(
                out.extension()
                    .and_then(|e| e.to_str())
                    .map(str::to_ascii_lowercase)
                    .as_deref(),
                Some("png" | "exr")
            ) {
                bail!("{flag} '{}' must end in .png or .exr", out.display());
            }
        }
    }
    let (img, _) = pt_image::read_exr(&args.image)?;
    let (reference, _) = pt_image::read_exr(&args.reference)?;
    if (img.width, img.height) != (reference.width, reference.height) {
        bail!(
            "'{}' is {}x{} but '{}' is {}x{}",
            args.image.display(),
            img.width,
            img.height,
            args.reference.display(),
            reference.width,
            reference.height
        );
    }
    let m = pt_image::metrics::compare(&img, &reference)?;
    let ch = |v: [f64; 3]| format!("{:>12.6e} {:>12.6e} {:>12.6e}", v[0], v[1], v[2]);
    out!("{:<22} {:>12} {:>12} {:>12}", "metric", "R", "G", "B");
    out!(
        "{:<22} {}   (all: {:.6e})",
        "relMSE",
        ch(m.relmse),
        m.relmse_all
    );
    out!("{:<22} {}", "RMSE", ch(m.rmse));
    out!("{:<22} {}", "MAE", ch(m.mae));
    out!("{:<22} {}", "mean ratio", ch(m.mean_ratio));
    out!(
        "{:<22} {} / {}",
        "non-finite pixels",
        img.nonfinite_pixels(),
        reference.nonfinite_pixels()
    );
    let flip = pt_image::flip::flip(&img, &reference, args.flip_exposure)?;
    out!(
        "{:<22} {:>12.6}   (mean, tone-mapped at {:+} stops, {} px/degree)",
        "FLIP",
        flip.mean,
        args.flip_exposure,
        pt_image::flip::DEFAULT_PIXELS_PER_DEGREE
    );
    let ff = pt_image::fireflies::FireflyParams::default();
    out!(
        "{:<22} {} / {}   (image / reference: luminance > median + {} MAD-sigma of the {}x{} neighbourhood)",
        "fireflies",
        pt_image::fireflies::count_fireflies(&img, ff),
        pt_image::fireflies::count_fireflies(&reference, ff),
        ff.k,
        2 * ff.radius + 1,
        2 * ff.radius + 1
    );
    let img_var = args
        .image_variance
        .clone()
        .or_else(|| sibling_variance(&args.image));
    let ref_var = args
        .variance
        .clone()
        .or_else(|| sibling_variance(&args.reference));
    let mut agree = img.nonfinite_pixels() == 0;
    match (img_var, ref_var) {
        (Some(iv), Some(rv)) => {
            let (iv, _) = pt_image::read_exr(&iv)?;
            let (rv, _) = pt_image::read_exr(&rv)?;
            let z =
                pt_image::stats::block_ztest(&img, &iv, &reference, &rv, args.block, args.alpha)?;
            out!(
                "block z-test ({}x{} px, alpha {}): max |z| {:.2}, {} of {} block-channels fail (per-test p < {:.2e}), chi2 {:.1} on {} dof (p {:.3}): {}",
                args.block,
                args.block,
                args.alpha,
                z.max_abs_z,
                z.failed,
                z.tests,
                z.p_threshold,
                z.chi2,
                z.tests,
                z.chi2_p,
                if z.pass { "PASS" } else { "FAIL" }
            );
            let pz = pt_image::stats::pixel_ztest(&img, &iv, &reference, &rv, args.alpha)?;
            out!(
                "pixel z-test: {:.3}% of pixel-channels fail at p < {}",
                100.0 * pz.fraction_failed,
                args.alpha
            );
            agree &= z.pass;
        }
        _ => {
            out!("no variance images: z-test skipped (give --variance and --image-variance, or put NAME_var.exr beside each)");
        }
    }
    if let Some(out) = &args.error_image {
        let err = pt_image::colormap::relative_error_image(&img, &reference)?;
        let e = pt_image::colormap::false_colour(&err, img.width, img.height, 0.0, 0.2, false);
        match out
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => pt_image::write_png_preview(out, &e, 0.0)?,
            Some("exr") => pt_image::write_exr(out, &e, &ExrMeta::default())?,
            _ => bail!("--error-image '{}' must end in .png or .exr", out.display()),
        }
        out!(
            "relative error image (0 to 20%, viridis) -> {}",
            out.display()
        );
    }
    if let Some(out) = &args.flip_image {
        let e = pt_image::colormap::false_colour(
            &flip.error_map,
            img.width,
            img.height,
            0.0,
            1.0,
            false,
        );
        match out
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => pt_image::write_png_preview(out, &e, 0.0)?,
            Some("exr") => pt_image::write_exr(out, &e, &ExrMeta::default())?,
            _ => bail!("--flip-image '{}' must end in .png or .exr", out.display()),
        }
        out!("FLIP error image (0 to 1, viridis) -> {}", out.display());
    }
    Ok(if agree {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
