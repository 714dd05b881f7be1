//! `pt converge`: error against render time, for pt's direct-light strategies and for Mitsuba 3.
//!
//! ```text
//! pt converge SCENE --reference REF.exr [--spp 1,2,4,...,1024] [--strategy mis,bsdf,light]
//!            [--modes rgb,spectral] [--mitsuba] [--mitsuba-variant llvm_ad_rgb|scalar_rgb] [--out DIR]
//!            [--threads T] [--max-depth D] [--seed S] [--python PY] [-D name=value]...
//! ```
//!
//! Renders SCENE once per sample count in `--spp` and per strategy in `--strategy` (one curve per
//! strategy; every render uses the same seed, so the renders of one curve share their first
//! samples, as a progressive render would) and, with `--modes`, per colour mode (one curve per
//! mode and strategy, to chart RGB against spectral transport on the same scene), and measures
//! each image against REF.exr: relMSE
//! (`mean((x - r)^2 / (r^2 + 0.01))` over pixels and channels) and RMSE (over pixels and
//! channels). The time of a point is the wall time of the render alone: the scene is loaded and
//! its BVH built once beforehand (that build time is printed separately), and one untimed 1-spp
//! render warms caches first.
//!
//! With `--mitsuba`, Mitsuba 3 renders the same scene file at the same sample counts in the same
//! sitting, before pt does, through `references/mitsuba_converge.py` (run with `.venv/bin/python`
//! of the repository if it exists, else `python3`; `--python` overrides). Only `mi.render` is
//! timed (until the image is evaluated); one untimed warm-up render first traces and JIT-compiles
//! the llvm kernel, so compilation is not counted. Its images are measured against the same
//! reference by the same code. If Mitsuba cannot be imported, the command stops with exit code 2
//! before pt renders anything.
//!
//! Output, in DIR (default `converge-<scene name>`):
//! - `converge.csv`: `series,spp,seconds,relmse,rmse,flip` (FLIP: mean of `pt_image::flip` at
//!   exposure 0, measured after timing), one row per render; series are `pt-mis`, `pt-bsdf`,
//!   `pt-light` (with `--modes`: `pt-rgb-mis`, `pt-spectral-mis`, ...) and `mitsuba-<variant>`;
//! - `converge.svg` and `converge.png`: relMSE against time, log-log, one line per series, points
//!   labelled with their spp (the PNG embeds its font: no system fonts needed);
//! - `summary.txt`: what is printed at the end (build times, and the ratios below);
//! - `pt-<strategy>/spp<N>.exr` and `mitsuba/spp<N>.exr`: every image measured.
//!
//! At the end it prints, for each pt curve against Mitsuba (without `--mitsuba`: each curve
//! against the first), the time each needs to reach the other's final relMSE, interpolated
//! linearly in log(time)-log(relMSE) along its curve (extrapolated with relMSE proportional to
//! 1/time, and marked so, when the target lies outside the curve), and the ratio of that time to
//! the other's final time. A progress line per point goes to stderr.
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

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, ValueEnum};
use plotters::coord::Shift;
use plotters::prelude::*;
use pt_image::{ExrMeta, Image};
use pt_integrators::{RenderSettings, Strategy};
use pt_render::{BvhKind, LightSelection, Scene};
use std::fmt::Write as _;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::Instant;

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
    /// Direct-light strategies of pt, comma separated: one curve each.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "mis")]
    pub strategy: Vec<ConvergeStrategy>,
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

/// pt's direct-light strategy of one curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ConvergeStrategy {
    /// MIS of light and BSDF sampling.
    Mis,
    /// BSDF sampling only.
    Bsdf,
    /// Light sampling only.
    Light,
}

impl ConvergeStrategy {
    fn strategy(self) -> Strategy {
        match self {
            ConvergeStrategy::Mis => Strategy::Mis,
            ConvergeStrategy::Bsdf => Strategy::Bsdf,
            ConvergeStrategy::Light => Strategy::Light,
        }
    }

    fn name(self) -> &'static str {
        match self {
            ConvergeStrategy::Mis => "mis",
            ConvergeStrategy::Bsdf => "bsdf",
            ConvergeStrategy::Light => "light",
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
    fn name(self) -> &'static str {
        match self {
            MitsubaVariant::LlvmAdRgb => "llvm_ad_rgb",
            MitsubaVariant::ScalarRgb => "scalar_rgb",
        }
    }
}

/// One render: its sample count (for radiosity: its patch count), render time and error
/// against the reference.
#[derive(Clone, Debug)]
struct Point {
    spp: u32,
    seconds: f64,
    relmse: f64,
    rmse: f64,
    /// Mean FLIP (Andersson et al. 2020) on the images tone-mapped at exposure 0.
    flip: f32,
}

/// One curve.
struct Series {
    name: String,
    points: Vec<Point>,
}

/// Runs `pt converge`. Errors are bad input (exit code 2 in `main`).
pub fn run(args: ConvergeArgs) -> Result<ExitCode> {
    let mut spp = args.spp.clone();
    if spp.contains(&0) {
        bail!("--spp values must be at least 1");
    }
    spp.sort_unstable();
    spp.dedup();
    if spp.is_empty() {
        bail!("--spp needs at least one sample count");
    }
    let mut strategies: Vec<ConvergeStrategy> = Vec::new();
    for s in &args.strategy {
        if !strategies.contains(s) {
            strategies.push(*s);
        }
    }
    if args.threads == Some(0) {
        bail!("--threads must be at least 1");
    }
    if let Some(d) = args.max_depth {
        if d < -1 {
            bail!("--max-depth must be -1 (unlimited) or >= 0, got {d}");
        }
    }
    let defines = crate::parse_defines(&args.defines)?;
    let out_dir = args.out.clone().unwrap_or_else(|| {
        let stem = args
            .scene
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into());
        PathBuf::from(format!("converge-{stem}"))
    });

    // Everything that can fail fast does so before any render.
    if !args.reference.is_file() {
        bail!("reference '{}' not found", args.reference.display());
    }
    let (reference, _) = pt_image::read_exr(&args.reference)
        .with_context(|| format!("cannot read the reference '{}'", args.reference.display()))?;
    let load_start = Instant::now();
    let desc = pt_scene::load_file(&args.scene, &defines)?;
    if (desc.film.width, desc.film.height) != (reference.width, reference.height) {
        bail!(
            "scene '{}' renders {}x{} but reference '{}' is {}x{} (set the size with -D width=... -D height=... if the scene declares them)",
            args.scene.display(),
            desc.film.width,
            desc.film.height,
            args.reference.display(),
            reference.width,
            reference.height
        );
    }
    if reference.nonfinite_pixels() > 0 {
        eprintln!(
            "warning: the reference has {} non-finite pixels; they are left out of the errors",
            reference.nonfinite_pixels()
        );
    }
    std::fs::create_dir_all(&out_dir)
        .with_context(|| format!("cannot create the output folder '{}'", out_dir.display()))?;
    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(t) = args.threads {
            b = b.num_threads(t);
        }
        b.build().context("cannot start worker threads")?
    };
    let load_s = load_start.elapsed().as_secs_f64();
    let build_start = Instant::now();
    let scene = pool.install(|| Scene::build(&desc, BvhKind::Auto, LightSelection::Power))?;
    let build_s = build_start.elapsed().as_secs_f64();
    // `--modes`: one scene per requested colour mode (None: the automatic one, built above).
    let mut modes: Vec<Option<ConvergeMode>> = Vec::new();
    for m in &args.modes {
        if !modes.contains(&Some(*m)) {
            modes.push(Some(*m));
        }
    }
    if modes.is_empty() {
        modes.push(None);
    }
    // Built before any timing; with `--modes` every entry of `modes` is Some, in this order.
    let mode_scenes: Vec<Scene> = modes
        .iter()
        .flatten()
        .map(|m| {
            pool.install(|| {
                Scene::build_with_mode(&desc, BvhKind::Auto, LightSelection::Power, Some(m.mode()))
            })
        })
        .collect::<Result<_, _>>()?;
    let mut summary = String::new();
    let _ = writeln!(
        summary,
        "scene {} ({}x{}, {} triangles, {} spheres), reference {}, {} pt thread(s)",
        args.scene.display(),
        desc.film.width,
        desc.film.height,
        scene.stats.triangles,
        scene.stats.spheres,
        args.reference.display(),
        pool.current_num_threads()
    );
    let _ = writeln!(
        summary,
        "pt scene load {load_s:.4} s, build (BVH, lights) {build_s:.4} s: not in the render times"
    );
    eprint!("{}", summary);

    let mut all: Vec<Series> = Vec::new();
    if args.mitsuba {
        let (series, info) = run_mitsuba(&args, &spp, &out_dir, &reference)?;
        let _ = writeln!(summary, "{info}");
        all.push(series);
    }

    let mut settings = RenderSettings::from_desc(&desc);
    settings.seed = args.seed;
    if let Some(d) = args.max_depth {
        settings.path.max_depth = d;
    }
    for (k, mode) in modes.iter().enumerate() {
        let scene = if mode.is_some() {
            &mode_scenes[k]
        } else {
            &scene
        };
        // Untimed warm-up (page faults, thread start-up), as Mitsuba gets one.
        pool.install(|| {
            pt_integrators::render(
                scene,
                &RenderSettings {
                    spp: 1,
                    seed: args.seed.wrapping_add(1_000_000),
                    ..settings.clone()
                },
                &|_| {},
            )
        });
        for strategy in &strategies {
            let name = match mode {
                None => format!("pt-{}", strategy.name()),
                Some(m) => format!("pt-{}-{}", m.mode().name(), strategy.name()),
            };
            let dir = out_dir.join(&name);
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("cannot create '{}'", dir.display()))?;
            let mut points = Vec::new();
            for &n in &spp {
                let s = RenderSettings {
                    spp: n,
                    path: pt_integrators::PathSettings {
                        strategy: strategy.strategy(),
                        ..settings.path
                    },
                    ..settings.clone()
                };
                let out = pool.install(|| pt_integrators::render(scene, &s, &|_| {}));
                let image = Image {
                    width: out.width,
                    height: out.height,
                    data: out.mean,
                };
                let meta = ExrMeta {
                    spp: Some(n),
                    mode: Some(scene.mode.name().to_string()),
                    render_time_s: Some(out.time.as_secs_f64()),
                    extra: vec![
                        ("strategy".into(), strategy.name().into()),
                        ("seed".into(), args.seed.to_string()),
                    ],
                };
                pt_image::write_exr(&dir.join(format!("spp{n}.exr")), &image, &meta)?;
                let p = measure(&image, &reference, n, out.time.as_secs_f64(), &name)?;
                if out.nonfinite_samples > 0 {
                    eprintln!(
                        "warning: {name} at {n} spp: {} NaN or infinite samples were left out",
                        out.nonfinite_samples
                    );
                }
                points.push(p);
            }
            all.push(Series { name, points });
        }
    }

    if !args.radiosity_patch_sizes.is_empty() {
        all.push(run_radiosity(
            &args, &desc, &settings, &out_dir, &reference, &pool,
        )?);
    }

    let csv = out_dir.join("converge.csv");
    let mut text = String::from("series,spp,seconds,relmse,rmse,flip\n");
    for s in &all {
        for p in &s.points {
            let _ = writeln!(
                text,
                "{},{},{:.6},{:.6e},{:.6e},{:.6}",
                s.name, p.spp, p.seconds, p.relmse, p.rmse, p.flip
            );
        }
    }
    write_atomic(&csv, text.as_bytes())?;

    let title = format!(
        "{}: relMSE against render time (lower left is better)",
        args.scene
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let svg = out_dir.join("converge.svg");
    let png = out_dir.join("converge.png");
    write_svg(&svg, &title, &all)?;
    write_png(&png, &title, &all)?;

    summary.push_str(&ratios(&all));
    let _ = writeln!(
        summary,
        "wrote {}, {}, {}",
        csv.display(),
        svg.display(),
        png.display()
    );
    write_atomic(&out_dir.join("summary.txt"), summary.as_bytes())?;
    print!("{summary}");
    Ok(ExitCode::SUCCESS)
}

/// The radiosity curve: one full solve per patch size (mesh, form factors, solve, display),
/// each timed as a whole, measured like the path-traced images. Points carry the patch count.
fn run_radiosity(
    args: &ConvergeArgs,
    desc: &pt_scene::SceneDesc,
    settings: &RenderSettings,
    out_dir: &Path,
    reference: &Image,
    pool: &rayon::ThreadPool,
) -> Result<Series> {
    let name = "radiosity".to_string();
    let dir = out_dir.join(&name);
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create '{}'", dir.display()))?;
    let mut points = Vec::new();
    for &h in &args.radiosity_patch_sizes {
        if !(h > 0.0 && h.is_finite()) {
            bail!("--radiosity-patch-sizes must be positive, got {h}");
        }
        let params = pt_radiosity::RadiosityParams {
            patch_size: Some(h),
            rays_per_patch: args.radiosity_rays,
            spp: 4,
            seed: settings.seed,
            ..Default::default()
        };
        let start = Instant::now();
        let (out, stats) = pool.install(|| pt_radiosity::render(desc, &params, &|_, _| {}))?;
        let seconds = start.elapsed().as_secs_f64();
        let image = Image {
            width: out.width,
            height: out.height,
            data: out.mean,
        };
        let meta = ExrMeta {
            spp: Some(params.spp),
            mode: Some("rgb".into()),
            render_time_s: Some(seconds),
            extra: vec![
                ("patch_size".into(), h.to_string()),
                ("patches".into(), stats.patches.to_string()),
            ],
        };
        pt_image::write_exr(&dir.join(format!("h{h}.exr")), &image, &meta)?;
        let patches = u32::try_from(stats.patches).unwrap_or(u32::MAX);
        points.push(measure(
            &image,
            reference,
            patches,
            seconds,
            &format!("{name} h={h} ({} patches)", stats.patches),
        )?);
    }
    Ok(Series { name, points })
}

/// Errors of one image; prints the progress line.
fn measure(
    image: &Image,
    reference: &Image,
    spp: u32,
    seconds: f64,
    series: &str,
) -> Result<Point> {
    let m = pt_image::metrics::compare(image, reference)?;
    // RMSE over all pixel channels: sqrt of the mean of the per-channel mean squared errors.
    let rmse = (m.rmse.iter().map(|r| r * r).sum::<f64>() / 3.0).sqrt();
    let nonfinite = if m.nonfinite_pixels > 0 {
        format!(" ({} non-finite pixels skipped)", m.nonfinite_pixels)
    } else {
        String::new()
    };
    let unit = if series.starts_with("radiosity") {
        "patches"
    } else {
        "spp"
    };
    // Measured after the timed render, so FLIP's cost does not enter the timings.
    let flip = pt_image::flip::flip(image, reference, 0.0)?.mean;
    eprintln!("{series:<22} {spp:>6} {unit} {seconds:>10.4} s   relMSE {:.4e}   RMSE {rmse:.4e}   FLIP {flip:.4}{nonfinite}", m.relmse_all);
    Ok(Point {
        spp,
        seconds,
        relmse: m.relmse_all,
        rmse,
        flip,
    })
}

/// `references/mitsuba_converge.py`: beside the current folder's `references/`, else in the
/// source tree this binary was built from.
fn mitsuba_script() -> Result<PathBuf> {
    let rel = Path::new("references").join("mitsuba_converge.py");
    let candidates = [
        rel.clone(),
        Path::new(env!("CARGO_MANIFEST_DIR")).join(&rel),
    ];
    candidates
        .iter()
        .find(|p| p.is_file())
        .cloned()
        .ok_or_else(|| {
            anyhow!(
                "--mitsuba needs references/mitsuba_converge.py; looked for {}",
                candidates
                    .map(|p| format!("'{}'", p.display()))
                    .join(" and ")
            )
        })
}

/// Runs Mitsuba at every sample count; returns its curve and a summary line.
fn run_mitsuba(
    args: &ConvergeArgs,
    spp: &[u32],
    out_dir: &Path,
    reference: &Image,
) -> Result<(Series, String)> {
    let script = mitsuba_script()?;
    let python = args.python.clone().unwrap_or_else(|| {
        let venv = script
            .parent()
            .and_then(Path::parent)
            .map(|repo| repo.join(".venv").join("bin").join("python"));
        venv.filter(|p| p.is_file())
            .unwrap_or_else(|| PathBuf::from("python3"))
    });
    let variant = args.mitsuba_variant.name();
    let dir = out_dir.join("mitsuba");
    let mut cmd = Command::new(&python);
    cmd.arg(&script)
        .arg(&args.scene)
        .arg("--variant")
        .arg(variant)
        .arg("--seed")
        .arg(args.seed.to_string())
        .arg("--out")
        .arg(&dir);
    cmd.arg("--spp").args(spp.iter().map(u32::to_string));
    if let Some(t) = args.threads {
        cmd.arg("--threads").arg(t.to_string());
    }
    if let Some(d) = args.max_depth {
        cmd.arg(format!("--max-depth={d}"));
    }
    for d in &args.defines {
        cmd.arg(format!("-D{d}"));
    }
    cmd.stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .stdin(Stdio::null());
    let mut child = cmd.spawn().with_context(|| {
        format!(
            "cannot run '{}' for --mitsuba (give the interpreter with --python)",
            python.display()
        )
    })?;
    let stdout = child.stdout.take().expect("piped stdout");
    let name = format!("mitsuba-{variant}");
    let mut points = Vec::new();
    let mut info: Vec<(String, String)> = Vec::new();
    let mut failure = None;
    for line in BufReader::new(stdout).lines() {
        let line = line.context("cannot read Mitsuba's output")?;
        let mut words = line.split_whitespace();
        match words.next() {
            Some("point") => {
                let parsed = (|| {
                    let n: u32 = words.next()?.parse().ok()?;
                    let secs: f64 = words.next()?.parse().ok()?;
                    Some((n, secs))
                })();
                let Some((n, secs)) = parsed else {
                    failure = Some(anyhow!(
                        "unexpected line from {}: '{line}'",
                        script.display()
                    ));
                    break;
                };
                let path = dir.join(format!("spp{n}.exr"));
                let result = pt_image::read_exr(&path)
                    .map_err(anyhow::Error::from)
                    .and_then(|(img, _)| measure(&img, reference, n, secs, &name));
                match result {
                    Ok(p) => points.push(p),
                    Err(e) => {
                        failure = Some(e.context(format!("Mitsuba's image at {n} spp")));
                        break;
                    }
                }
            }
            Some("info") => {
                if let Some(key) = words.next() {
                    info.push((key.to_string(), words.collect::<Vec<_>>().join(" ")));
                }
            }
            _ => eprintln!("mitsuba: {line}"),
        }
    }
    if failure.is_some() {
        let _ = child.kill();
    }
    let status = child
        .wait()
        .context("cannot wait for the Mitsuba process")?;
    if let Some(e) = failure {
        return Err(e);
    }
    if !status.success() {
        bail!(
            "the Mitsuba run ({} {}) failed with {status}; its message is above",
            python.display(),
            script.display()
        );
    }
    let got: Vec<u32> = points.iter().map(|p| p.spp).collect();
    if got != spp {
        bail!("Mitsuba returned sample counts {got:?}, expected {spp:?}");
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
    eprintln!("{line}");
    Ok((Series { name, points }, line))
}

/// Time for `curve` to reach relMSE `target`: linear interpolation in log-log along the curve at
/// its first downward crossing of `target`; outside the curve, extrapolation with relMSE
/// proportional to 1/time from the nearest end (`true` when extrapolated).
fn time_to_reach(curve: &[Point], target: f64) -> (f64, bool) {
    let first = &curve[0];
    if first.relmse <= target {
        return (first.seconds * first.relmse / target, first.relmse < target);
    }
    for w in curve.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if a.relmse >= target && b.relmse <= target {
            let (la, lb) = (a.relmse.ln(), b.relmse.ln());
            let f = if la == lb {
                0.0
            } else {
                (la - target.ln()) / (la - lb)
            };
            return (
                (a.seconds.ln() + f * (b.seconds.ln() - a.seconds.ln())).exp(),
                false,
            );
        }
    }
    let last = curve.last().expect("non-empty curve");
    (last.seconds * last.relmse / target, true)
}

/// The "time to reach the other's final error" table.
fn ratios(all: &[Series]) -> String {
    let mut s = String::new();
    let pairs: Vec<(usize, usize)> = match all.iter().position(|c| c.name.starts_with("mitsuba")) {
        Some(m) => (0..all.len()).filter(|&i| i != m).map(|i| (i, m)).collect(),
        None => (1..all.len()).map(|i| (i, 0)).collect(),
    };
    if pairs.is_empty() {
        return s;
    }
    let _ = writeln!(s, "time to reach the other's final relMSE (log-log interpolation along the curve; * = extrapolated as relMSE ~ 1/time):");
    for (a, b) in pairs {
        for (x, y) in [(a, b), (b, a)] {
            let (cx, cy) = (&all[x], &all[y]);
            let fy = cy.points.last().expect("non-empty");
            let (t, extrapolated) = time_to_reach(&cx.points, fy.relmse);
            if extrapolated && cx.name.starts_with("radiosity") {
                // Radiosity's error is discretisation bias, not noise: it does not fall as
                // 1/time, so no extrapolation is honest.
                let best = cx
                    .points
                    .iter()
                    .map(|p| p.relmse)
                    .fold(f64::INFINITY, f64::min);
                let _ = writeln!(
                    s,
                    "  {:<20} does not reach {}'s final relMSE {:.3e} on its curve (best {:.3e}; its error is bias, not extrapolated)",
                    cx.name, cy.name, fy.relmse, best
                );
                continue;
            }
            let _ = writeln!(
                s,
                "  {:<20} reaches {:<20} final relMSE {:.3e} ({} {}, {:.3} s) in {:.3} s{}: time ratio {} / {} = {:.3}",
                cx.name,
                format!("{}'s", cy.name),
                fy.relmse,
                fy.spp,
                if cy.name.starts_with("radiosity") { "patches" } else { "spp" },
                fy.seconds,
                t,
                if extrapolated { "*" } else { "" },
                cx.name,
                cy.name,
                t / fy.seconds
            );
        }
    }
    s
}

/// Writes `bytes` to a temporary file beside `path`, then renames it over `path`.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            anyhow!("cannot write '{}': {e}", path.display())
        })
}

const CHART_SIZE: (u32, u32) = (960, 640);
const FONT: &str = "sans-serif";

/// Registers DejaVu Sans (embedded from the `dejavu` crate) as plotters' "sans-serif", once:
/// with the `ab_glyph` feature plotters draws text only with registered fonts.
pub(crate) fn register_font() -> Result<()> {
    static OK: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    if *OK.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
    }) {
        Ok(())
    } else {
        bail!("the embedded chart font is not a valid TrueType font")
    }
}

/// A chart that draws itself on any plotters backend (SVG text or an RGB bitmap).
pub(crate) trait Chart {
    /// Draws the whole chart on `root`; the error is a message.
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static;
}

/// `chart` drawn at `size` pixels as SVG text; `what` names it in errors.
pub(crate) fn chart_svg(chart: &impl Chart, size: (u32, u32), what: &str) -> Result<String> {
    register_font()?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        chart
            .draw_on(&root)
            .map_err(|e| anyhow!("cannot draw {what}: {e}"))?;
        root.present()
            .map_err(|e| anyhow!("cannot draw {what}: {e:?}"))?;
    }
    Ok(text)
}

/// `chart` drawn at `size` pixels as PNG bytes (8-bit RGB); `what` names it in errors.
pub(crate) fn chart_png(chart: &impl Chart, size: (u32, u32), what: &str) -> Result<Vec<u8>> {
    use image::ImageEncoder as _;
    register_font()?;
    let (w, h) = size;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        chart
            .draw_on(&root)
            .map_err(|e| anyhow!("cannot draw {what}: {e}"))?;
        root.present()
            .map_err(|e| anyhow!("cannot draw {what}: {e:?}"))?;
    }
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(&rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| anyhow!("cannot encode {what} as PNG: {e}"))?;
    Ok(bytes)
}

/// The error-against-time chart of `pt converge`.
struct ConvergeChart<'a> {
    title: &'a str,
    all: &'a [Series],
}

impl Chart for ConvergeChart<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        draw_chart(root, self.title, self.all)
    }
}

fn write_svg(path: &Path, title: &str, all: &[Series]) -> Result<()> {
    let text = chart_svg(
        &ConvergeChart { title, all },
        CHART_SIZE,
        &format!("'{}'", path.display()),
    )?;
    write_atomic(path, text.as_bytes())
}

fn write_png(path: &Path, title: &str, all: &[Series]) -> Result<()> {
    let bytes = chart_png(
        &ConvergeChart { title, all },
        CHART_SIZE,
        &format!("'{}'", path.display()),
    )?;
    write_atomic(path, &bytes)
}

/// Short tick labels for a log axis: 0.05, 2, 300, 1e-4.
fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.0e}")
    }
}

/// Tick positions for a log axis over `[lo, hi]`: decades, or 1-2-5, 1-2-3-5-7 or every integer
/// mantissa per decade, the first of these that gives at least four ticks.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let sets: [&[f64]; 4] = [
        &[1.0],
        &[1.0, 2.0, 5.0],
        &[1.0, 2.0, 3.0, 5.0, 7.0],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ];
    let mut ticks = Vec::new();
    for set in sets {
        ticks.clear();
        for k in lo.log10().floor() as i32..=hi.log10().ceil() as i32 {
            let decade = 10f64.powi(k);
            ticks.extend(
                set.iter()
                    .map(|m| m * decade)
                    .filter(|v| (lo..=hi).contains(v)),
            );
        }
        if ticks.len() >= 4 {
            break;
        }
    }
    ticks
}

fn draw_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    all: &[Series],
) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("{e:?}");
    root.fill(&WHITE).map_err(err)?;
    let pts = || {
        all.iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.seconds > 0.0 && p.relmse > 0.0)
    };
    let (mut t0, mut t1, mut e0, mut e1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in pts() {
        t0 = t0.min(p.seconds);
        t1 = t1.max(p.seconds);
        e0 = e0.min(p.relmse);
        e1 = e1.max(p.relmse);
    }
    if !(t0 <= t1 && e0 <= e1) {
        (t0, t1, e0, e1) = (0.1, 1.0, 0.01, 0.1);
    }
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 24))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(
            (t0 / 1.6..t1 * 1.6)
                .log_scale()
                .with_key_points(log_ticks(t0 / 1.6, t1 * 1.6)),
            (e0 / 1.6..e1 * 1.6)
                .log_scale()
                .with_key_points(log_ticks(e0 / 1.6, e1 * 1.6)),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("render time (s), log scale")
        .y_desc("relMSE, log scale")
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .light_line_style(TRANSPARENT)
        .draw()
        .map_err(err)?;
    let palette = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(255, 127, 14),
        RGBColor(140, 86, 75),
    ];
    for (k, s) in all.iter().enumerate() {
        let colour = palette[k % palette.len()];
        let xy: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter(|p| p.seconds > 0.0 && p.relmse > 0.0)
            .map(|p| (p.seconds, p.relmse))
            .collect();
        chart
            .draw_series(LineSeries::new(xy.clone(), colour.stroke_width(2)))
            .map_err(err)?
            .label(s.name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3))
            });
        chart
            .draw_series(xy.iter().map(|&p| Circle::new(p, 4, colour.filled())))
            .map_err(err)?;
        chart
            .draw_series(
                s.points
                    .iter()
                    .filter(|p| p.seconds > 0.0 && p.relmse > 0.0)
                    .map(|p| {
                        EmptyElement::at((p.seconds, p.relmse))
                            + Text::new(
                                format!("{}", p.spp),
                                (7, -18),
                                (FONT, 13).into_font().color(&colour),
                            )
                    }),
            )
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 16))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK.mix(0.5))
        .draw()
        .map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(spp: u32, seconds: f64, relmse: f64) -> Point {
        Point {
            spp,
            seconds,
            relmse,
            rmse: 0.0,
            flip: 0.0,
        }
    }

    #[test]
    fn time_to_reach_interpolates_in_log_log() {
        let c = [p(1, 1.0, 1.0), p(4, 4.0, 0.25), p(16, 16.0, 0.0625)];
        let (t, ex) = time_to_reach(&c, 0.5);
        assert!(!ex && (t - 2.0).abs() < 1e-12, "{t}");
        let (t, ex) = time_to_reach(&c, 0.0625);
        assert!(!ex && (t - 16.0).abs() < 1e-12, "{t}");
        // Beyond the curve: relMSE ~ 1/time from the nearest end.
        let (t, ex) = time_to_reach(&c, 0.03125);
        assert!(ex && (t - 32.0).abs() < 1e-9, "{t}");
        let (t, ex) = time_to_reach(&c, 2.0);
        assert!(ex && (t - 0.5).abs() < 1e-12, "{t}");
    }

    #[test]
    fn log_ticks_are_readable() {
        let t = log_ticks(0.03, 20.0);
        assert_eq!(t.len(), 9, "{t:?}"); // 0.05 0.1 0.2 0.5 1 2 5 10 20
        assert!(t.iter().any(|v| (v - 1.0).abs() < 1e-12), "{t:?}");
        let t = log_ticks(0.0005, 20.0);
        assert_eq!(t.len(), 5, "{t:?}");
        let t = log_ticks(0.06, 0.5);
        assert!(
            t.len() >= 4 && t.iter().all(|v| (0.06..=0.5).contains(v)),
            "{t:?}"
        );
    }

    #[test]
    fn chart_draws_without_system_fonts() {
        let all = vec![Series {
            name: "a".into(),
            points: vec![p(1, 0.1, 0.5), p(4, 0.4, 0.12)],
        }];
        let dir = std::env::temp_dir().join(format!("pt-converge-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        write_png(&dir.join("c.png"), "t", &all).unwrap();
        write_svg(&dir.join("c.svg"), "t", &all).unwrap();
        assert!(std::fs::read_to_string(dir.join("c.svg"))
            .unwrap()
            .contains("<svg"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
