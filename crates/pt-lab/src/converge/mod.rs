//! Error against render time, for pt's direct-light strategies and for Mitsuba 3 (`pt
//! converge`).
//!
//! [`run`] renders the scene once per sample count in [`ConvergeSettings::spp`] and per
//! strategy (one curve per strategy; every render uses the same seed, so the renders of one
//! curve share their first samples, as a progressive render would) and, with
//! [`ConvergeSettings::modes`], per colour mode (one curve per mode and strategy, to chart RGB
//! against spectral transport on the same scene), and measures each image against the
//! reference: relMSE (`mean((x - r)^2 / (r^2 + 0.01))` over pixels and channels), RMSE (over
//! pixels and channels) and mean FLIP at exposure 0 (measured after timing). The time of a
//! point is the wall time of the render alone: the scene is loaded and its BVH built once
//! beforehand (that build time is reported separately), and one untimed 1-spp render warms
//! caches first.
//!
//! With [`ConvergeSettings::mitsuba`], Mitsuba 3 renders the same scene file at the same sample
//! counts in the same sitting, before pt does, through `references/mitsuba_converge.py`
//! ([`mitsuba`]). Only `mi.render` is timed (until the image is evaluated); one untimed
//! warm-up render first traces and JIT-compiles the llvm kernel, so compilation is not counted.
//! Its images are measured against the same reference by the same code.
//!
//! Files in [`ConvergeSettings::out`]: `converge.csv` (`series,spp,seconds,relmse,rmse,flip`,
//! one row per render; series `pt-mis`, `pt-bsdf`, `pt-light`, with modes `pt-rgb-mis`,
//! `pt-spectral-mis`, ..., `mitsuba-<variant>` and `radiosity`), `converge.svg` and
//! `converge.png` (relMSE against time, log-log, points labelled with their spp; the PNG
//! embeds its font), `summary.txt` (the returned summary) and every image measured,
//! `pt-<strategy>/spp<N>.exr`, `mitsuba/spp<N>.exr`, `radiosity/h<size>.exr`.
//!
//! The summary ends, for each pt curve against Mitsuba (without Mitsuba: each curve against
//! the first), with the time each needs to reach the other's final relMSE, interpolated
//! linearly in log(time)-log(relMSE) along its curve (extrapolated with relMSE proportional to
//! 1/time, and marked so, when the target lies outside the curve), and the ratio of that time
//! to the other's final time ([`ratios`]).

mod chart;
pub mod mitsuba;

use crate::{create_dir, write_atomic, LabError, Result};
use pt_image::{ExrMeta, Image};
use pt_integrators::{RenderSettings, Strategy};
use pt_render::{BvhKind, LightSelection, Scene};
use pt_spectrum::ColorMode;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

pub use mitsuba::{MitsubaRun, MitsubaVariant};

/// What [`run`] renders and measures.
#[derive(Clone, Debug)]
pub struct ConvergeSettings {
    /// Mitsuba 3 XML scene to render.
    pub scene: PathBuf,
    /// `<default>` parameters of the scene (as Mitsuba's `-D name=value`; Mitsuba gets them too).
    pub defines: Vec<(String, String)>,
    /// Reference image (EXR) the errors are measured against; the size of the scene's film.
    pub reference: PathBuf,
    /// Sample counts per pixel, one render (one point) each; sorted and deduplicated by [`run`].
    pub spp: Vec<u32>,
    /// Direct-light strategies of pt's path tracer, one curve each (repeats ignored).
    pub strategies: Vec<Strategy>,
    /// Light transport methods of pt: the path tracer (a curve per strategy) and others, one
    /// curve each, named `pt-<method>` (repeats ignored).
    pub integrators: Vec<Method>,
    /// Colour modes of pt, one curve per mode and strategy, named `pt-<mode>-<strategy>`,
    /// each timed with its own scene build; empty: the scene's automatic mode only, curves
    /// named `pt-<strategy>`.
    pub modes: Vec<ColorMode>,
    /// Output folder (created if needed).
    pub out: PathBuf,
    /// Longest path in segments (1: emitters only, 2: direct light, -1: unlimited), or the
    /// scene's. Mitsuba gets it as the scene parameter `$max_depth`.
    pub max_depth: Option<i32>,
    /// Seed of pt's random streams; Mitsuba's render i uses seed + i.
    pub seed: u64,
    /// Also render with Mitsuba 3 (see [`mitsuba`]).
    pub mitsuba: Option<MitsubaRun>,
    /// Also solve the scene by radiosity at these patch sizes (scene units): one point each,
    /// timed from meshing to the displayed image, labelled with its patch count.
    pub radiosity_patch_sizes: Vec<f32>,
    /// Form-factor rays per patch for the radiosity points.
    pub radiosity_rays: u32,
}

/// A light transport method charted by [`run`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The path tracer, one curve per [`ConvergeSettings::strategies`].
    Path,
    /// Light tracing (`ptracer`): its spp are light paths per pixel.
    PTracer,
    /// Stochastic progressive photon mapping (`sppm`, default settings): its spp are
    /// iterations.
    Sppm,
    /// Jensen's photon mapping (`photonmapper`, default settings): its spp are iterations.
    PhotonMapper,
    /// Bidirectional path tracing (`bdpt`).
    Bdpt,
    /// Vertex connection and merging (`vcm`, default settings): its spp are iterations.
    Vcm,
}

/// One render: its sample count (for radiosity: its patch count), render time and error
/// against the reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Samples per pixel (radiosity: patches).
    pub spp: u32,
    /// Wall time of the render, seconds.
    pub seconds: f64,
    /// Relative MSE, `mean((x - r)^2 / (r^2 + 0.01))` over pixels and channels.
    pub relmse: f64,
    /// RMSE over pixels and channels.
    pub rmse: f64,
    /// Mean FLIP (Andersson et al. 2020) on the images tone-mapped at exposure 0.
    pub flip: f32,
}

/// One curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Its name in the CSV and the chart (`pt-mis`, `mitsuba-llvm_ad_rgb`, `radiosity`, ...).
    pub name: String,
    /// Its points, by increasing sample count.
    pub points: Vec<Point>,
}

/// What [`run`] found.
#[derive(Clone, Debug)]
pub struct Convergence {
    /// Every curve: Mitsuba's first, then pt's, then radiosity.
    pub series: Vec<Series>,
    /// The summary (also in `summary.txt`): scene, build times, time ratios, files written.
    pub summary: String,
}

/// The name of a strategy in series names: `mis`, `bsdf`, `light`.
pub fn strategy_name(s: Strategy) -> &'static str {
    match s {
        Strategy::Mis => "mis",
        Strategy::Bsdf => "bsdf",
        Strategy::Light => "light",
    }
}

/// The strategies by name (`mis`, `bsdf`, `light`), as [`strategy_name`] writes them.
pub const STRATEGIES: &[&str] = &["mis", "bsdf", "light"];

/// The strategy named `name` (one of [`STRATEGIES`]).
pub fn strategy_named(name: &str) -> Option<Strategy> {
    [Strategy::Mis, Strategy::Bsdf, Strategy::Light]
        .into_iter()
        .find(|s| strategy_name(*s) == name)
}

impl Method {
    /// Every method, in the order of [`Method::NAMES`].
    pub const ALL: [Method; 6] = [
        Method::Path,
        Method::PTracer,
        Method::Sppm,
        Method::PhotonMapper,
        Method::Bdpt,
        Method::Vcm,
    ];
    /// The methods' names, as the scene format's `<integrator type>` spells them.
    pub const NAMES: [&'static str; 6] = ["path", "ptracer", "sppm", "photonmapper", "bdpt", "vcm"];

    /// The method named `name` (one of [`Method::NAMES`]).
    pub fn named(name: &str) -> Option<Method> {
        Self::NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| Self::ALL[i])
    }
}

/// Checks the settings (messages name their fields); returns the sorted sample counts.
fn check(s: &ConvergeSettings) -> Result<Vec<u32>> {
    let mut spp = s.spp.clone();
    if spp.contains(&0) {
        return Err(LabError::Invalid("spp values must be at least 1".into()));
    }
    spp.sort_unstable();
    spp.dedup();
    if spp.is_empty() {
        return Err(LabError::Invalid(
            "spp needs at least one sample count".into(),
        ));
    }
    if let Some(d) = s.max_depth.filter(|&d| d < -1) {
        return Err(LabError::Invalid(format!(
            "max_depth must be -1 (unlimited) or >= 0, got {d}"
        )));
    }
    if let Some(h) = s
        .radiosity_patch_sizes
        .iter()
        .find(|h| !(**h > 0.0 && h.is_finite()))
    {
        return Err(LabError::Invalid(format!(
            "radiosity patch sizes must be positive, got {h}"
        )));
    }
    Ok(spp)
}

/// The reference image, read and checked before any work.
fn read_reference(s: &ConvergeSettings) -> Result<Image> {
    if !s.reference.is_file() {
        return Err(LabError::Invalid(format!(
            "reference '{}' not found",
            s.reference.display()
        )));
    }
    let (reference, _) = pt_image::read_exr(&s.reference).map_err(|e| {
        LabError::from(e).context(format!(
            "cannot read the reference '{}'",
            s.reference.display()
        ))
    })?;
    Ok(reference)
}

/// Renders and measures every curve (on the current rayon pool; Mitsuba gets
/// [`MitsubaRun::threads`]) and writes the files (see the module doc). `log` receives the
/// progress lines and warnings as they happen.
pub fn run(s: &ConvergeSettings, log: &(dyn Fn(&str) + Sync)) -> Result<Convergence> {
    let spp = check(s)?;
    // Everything that can fail fast does so before any render.
    let reference = read_reference(s)?;
    let load_start = Instant::now();
    let desc = pt_scene::load_file(&s.scene, &s.defines)?;
    if (desc.film.width, desc.film.height) != (reference.width, reference.height) {
        return Err(LabError::Invalid(format!(
            "scene '{}' renders {}x{} but reference '{}' is {}x{} (set the size with -D width=... -D height=... if the scene declares them)",
            s.scene.display(),
            desc.film.width,
            desc.film.height,
            s.reference.display(),
            reference.width,
            reference.height
        )));
    }
    if reference.nonfinite_pixels() > 0 {
        log(&format!(
            "warning: the reference has {} non-finite pixels; they are left out of the errors",
            reference.nonfinite_pixels()
        ));
    }
    create_dir(&s.out, "cannot create the output folder")?;
    let load_s = load_start.elapsed().as_secs_f64();
    let build_start = Instant::now();
    let scene = Scene::build(&desc, BvhKind::Auto, LightSelection::Power)?;
    let build_s = build_start.elapsed().as_secs_f64();
    let mut summary = String::new();
    let _ = writeln!(
        summary,
        "scene {} ({}x{}, {} triangles, {} spheres), reference {}, {} pt thread(s)",
        s.scene.display(),
        desc.film.width,
        desc.film.height,
        scene.stats.triangles,
        scene.stats.spheres,
        s.reference.display(),
        rayon::current_num_threads()
    );
    let _ = writeln!(
        summary,
        "pt scene load {load_s:.4} s, build (BVH, lights) {build_s:.4} s: not in the render times"
    );
    for line in summary.lines() {
        log(line);
    }
    let mut all: Vec<Series> = Vec::new();
    if let Some(m) = &s.mitsuba {
        let (series, info) = mitsuba::run(m, s, &spp, &reference, log)?;
        let _ = writeln!(summary, "{info}");
        all.push(series);
    }
    let mut settings = RenderSettings::from_desc(&desc);
    settings.seed = s.seed;
    if let Some(d) = s.max_depth {
        settings.path.max_depth = d;
    }
    all.extend(pt_curves(
        s, &desc, scene, &settings, &spp, &reference, log,
    )?);
    if !s.radiosity_patch_sizes.is_empty() {
        all.push(run_radiosity(s, &desc, &settings, &reference, log)?);
    }
    write_outputs(s, &all, &mut summary)?;
    Ok(Convergence {
        series: all,
        summary,
    })
}

/// pt's curves: per colour mode (the automatic one, or each of `s.modes` with its own scene
/// build, all built before any timing) and strategy.
fn pt_curves(
    s: &ConvergeSettings,
    desc: &pt_scene::SceneDesc,
    auto: Scene,
    settings: &RenderSettings,
    spp: &[u32],
    reference: &Image,
    log: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Series>> {
    let mut modes: Vec<ColorMode> = Vec::new();
    for m in &s.modes {
        if !modes.contains(m) {
            modes.push(*m);
        }
    }
    let scenes: Vec<(Option<ColorMode>, Scene)> = if modes.is_empty() {
        vec![(None, auto)]
    } else {
        modes
            .iter()
            .map(|&m| {
                Scene::build_with_mode(desc, BvhKind::Auto, LightSelection::Power, Some(m))
                    .map(|scene| (Some(m), scene))
            })
            .collect::<Result<_, _>>()?
    };
    let mut strategies: Vec<Strategy> = Vec::new();
    if s.integrators.contains(&Method::Path) {
        for st in &s.strategies {
            if !strategies.contains(st) {
                strategies.push(*st);
            }
        }
    }
    let light_tracer = s.integrators.contains(&Method::PTracer);
    let photon_mapper = s.integrators.contains(&Method::Sppm);
    let bidirectional: Vec<pt_integrators::vcm::VcmSettings> = [
        (Method::Bdpt, pt_integrators::vcm::VcmSettings::bdpt()),
        (Method::Vcm, pt_integrators::vcm::VcmSettings::vcm()),
    ]
    .into_iter()
    .filter(|(m, _)| s.integrators.contains(m))
    .map(|(_, v)| v)
    .collect();
    let mut all = Vec::new();
    for (mode, scene) in &scenes {
        // Untimed warm-up (page faults, thread start-up), as Mitsuba gets one.
        pt_integrators::render(
            scene,
            &RenderSettings {
                spp: 1,
                seed: s.seed.wrapping_add(1_000_000),
                ..settings.clone()
            },
            &|_| {},
        );
        for &strategy in &strategies {
            let name = match mode {
                None => format!("pt-{}", strategy_name(strategy)),
                Some(m) => format!("pt-{}-{}", m.name(), strategy_name(strategy)),
            };
            let settings = RenderSettings {
                path: pt_integrators::PathSettings {
                    strategy,
                    ..settings.path
                },
                ..settings.clone()
            };
            let render = |rs: &RenderSettings| pt_integrators::render(scene, rs, &|_| {});
            let extra = ("strategy", strategy_name(strategy));
            let points = pt_curve(
                s, scene, &settings, render, extra, &name, spp, reference, log,
            )?;
            all.push(Series { name, points });
        }
        if light_tracer {
            pt_integrators::ptracer::check(settings).map_err(LabError::Invalid)?;
            let name = match mode {
                None => "pt-ptracer".to_string(),
                Some(m) => format!("pt-{}-ptracer", m.name()),
            };
            let render = |rs: &RenderSettings| pt_integrators::ptracer::render(scene, rs, &|_| {});
            let extra = ("integrator", "ptracer");
            let points = pt_curve(
                s, scene, settings, render, extra, &name, spp, reference, log,
            )?;
            all.push(Series { name, points });
        }
        if photon_mapper {
            let params = pt_integrators::sppm::SppmSettings::default();
            pt_integrators::sppm::check(&params).map_err(LabError::Invalid)?;
            let name = match mode {
                None => "pt-sppm".to_string(),
                Some(m) => format!("pt-{}-sppm", m.name()),
            };
            let render =
                |rs: &RenderSettings| pt_integrators::sppm::render(scene, rs, &params, &|_| {});
            let extra = ("integrator", "sppm");
            let points = pt_curve(
                s, scene, settings, render, extra, &name, spp, reference, log,
            )?;
            all.push(Series { name, points });
        }
        if s.integrators.contains(&Method::PhotonMapper) {
            let params = pt_integrators::photonmap::PhotonMapSettings::default();
            pt_integrators::photonmap::check(&params).map_err(LabError::Invalid)?;
            let name = match mode {
                None => "pt-photonmapper".to_string(),
                Some(m) => format!("pt-{}-photonmapper", m.name()),
            };
            let render = |rs: &RenderSettings| {
                pt_integrators::photonmap::render(scene, rs, &params, &|_| {})
            };
            let extra = ("integrator", "photonmapper");
            let points = pt_curve(
                s, scene, settings, render, extra, &name, spp, reference, log,
            )?;
            all.push(Series { name, points });
        }
        for params in &bidirectional {
            pt_integrators::vcm::check(scene, settings, params).map_err(LabError::Invalid)?;
            let method = params.name();
            let name = match mode {
                None => format!("pt-{method}"),
                Some(m) => format!("pt-{}-{method}", m.name()),
            };
            let render =
                |rs: &RenderSettings| pt_integrators::vcm::render(scene, rs, params, &|_| {});
            let extra = ("integrator", method);
            let points = pt_curve(
                s, scene, settings, render, extra, &name, spp, reference, log,
            )?;
            all.push(Series { name, points });
        }
    }
    Ok(all)
}

/// One pt curve: a render per sample count by `render`, written as `NAME/spp<N>.exr` (with
/// `extra`, a header entry naming what the curve varies) and measured.
#[allow(clippy::too_many_arguments)]
fn pt_curve(
    s: &ConvergeSettings,
    scene: &Scene,
    settings: &RenderSettings,
    render: impl Fn(&RenderSettings) -> pt_render::RenderOutput,
    extra: (&str, &str),
    name: &str,
    spp: &[u32],
    reference: &Image,
    log: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Point>> {
    let dir = s.out.join(name);
    create_dir(&dir, "cannot create")?;
    let mut points = Vec::new();
    for &n in spp {
        let settings = RenderSettings {
            spp: n,
            ..settings.clone()
        };
        let out = render(&settings);
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
                (extra.0.into(), extra.1.into()),
                ("seed".into(), s.seed.to_string()),
            ],
        };
        pt_image::write_exr(&dir.join(format!("spp{n}.exr")), &image, &meta)?;
        let p = measure(&image, reference, n, out.time.as_secs_f64(), name, log)?;
        if out.nonfinite_samples > 0 {
            log(&format!(
                "warning: {name} at {n} spp: {} NaN or infinite samples were left out",
                out.nonfinite_samples
            ));
        }
        points.push(p);
    }
    Ok(points)
}

/// The radiosity curve: one full solve per patch size (mesh, form factors, solve, display),
/// each timed as a whole, measured like the path-traced images. Points carry the patch count.
fn run_radiosity(
    s: &ConvergeSettings,
    desc: &pt_scene::SceneDesc,
    settings: &RenderSettings,
    reference: &Image,
    log: &(dyn Fn(&str) + Sync),
) -> Result<Series> {
    let name = "radiosity".to_string();
    let dir = s.out.join(&name);
    create_dir(&dir, "cannot create")?;
    let mut points = Vec::new();
    for &h in &s.radiosity_patch_sizes {
        let params = pt_radiosity::RadiosityParams {
            patch_size: Some(h),
            rays_per_patch: s.radiosity_rays,
            spp: 4,
            seed: settings.seed,
            ..Default::default()
        };
        let start = Instant::now();
        let (out, stats) = pt_radiosity::render(desc, &params, &|_, _| {})?;
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
            log,
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
    log: &(dyn Fn(&str) + Sync),
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
    log(&format!("{series:<22} {spp:>6} {unit} {seconds:>10.4} s   relMSE {:.4e}   RMSE {rmse:.4e}   FLIP {flip:.4}{nonfinite}", m.relmse_all));
    Ok(Point {
        spp,
        seconds,
        relmse: m.relmse_all,
        rmse,
        flip,
    })
}
/// Time for `curve` to reach relMSE `target`: linear interpolation in log-log along the curve at
/// its first downward crossing of `target`; outside the curve, extrapolation with relMSE
/// proportional to 1/time from the nearest end (`true` when extrapolated).
pub fn time_to_reach(curve: &[Point], target: f64) -> (f64, bool) {
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
pub fn ratios(all: &[Series]) -> String {
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

/// `converge.csv`, the charts and `summary.txt` (the summary gets the ratios and the list of
/// files first).
fn write_outputs(s: &ConvergeSettings, all: &[Series], summary: &mut String) -> Result<()> {
    let csv = s.out.join("converge.csv");
    write_atomic(&csv, csv_text(all).as_bytes())?;
    let title = format!(
        "{}: relMSE against render time (lower left is better)",
        s.scene
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let svg = s.out.join("converge.svg");
    let png = s.out.join("converge.png");
    chart::write_svg(&svg, &title, all)?;
    chart::write_png(&png, &title, all)?;
    summary.push_str(&ratios(all));
    let _ = writeln!(
        summary,
        "wrote {}, {}, {}",
        csv.display(),
        svg.display(),
        png.display()
    );
    write_atomic(&s.out.join("summary.txt"), summary.as_bytes())
}

/// The CSV of every point: `series,spp,seconds,relmse,rmse,flip`.
pub fn csv_text(all: &[Series]) -> String {
    let mut text = String::from("series,spp,seconds,relmse,rmse,flip\n");
    for s in all {
        for p in &s.points {
            let _ = writeln!(
                text,
                "{},{},{:.6},{:.6e},{:.6e},{:.6}",
                s.name, p.spp, p.seconds, p.relmse, p.rmse, p.flip
            );
        }
    }
    text
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
    fn chart_draws_without_system_fonts() {
        let all = vec![Series {
            name: "a".into(),
            points: vec![p(1, 0.1, 0.5), p(4, 0.4, 0.12)],
        }];
        let dir = std::env::temp_dir().join(format!("pt-converge-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        chart::write_png(&dir.join("c.png"), "t", &all).unwrap();
        chart::write_svg(&dir.join("c.svg"), "t", &all).unwrap();
        assert!(std::fs::read_to_string(dir.join("c.svg"))
            .unwrap()
            .contains("<svg"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn settings_are_checked() {
        let s = ConvergeSettings {
            scene: "none.xml".into(),
            defines: Vec::new(),
            reference: "none.exr".into(),
            spp: vec![4, 1, 4],
            strategies: vec![Strategy::Mis],
            integrators: vec![Method::Path],
            modes: Vec::new(),
            out: "out".into(),
            max_depth: None,
            seed: 1,
            mitsuba: None,
            radiosity_patch_sizes: Vec::new(),
            radiosity_rays: 16,
        };
        assert_eq!(check(&s).unwrap(), [1, 4]);
        let bad = |t: ConvergeSettings| check(&t).unwrap_err().to_string();
        assert!(bad(ConvergeSettings {
            spp: vec![0],
            ..s.clone()
        })
        .contains("at least 1"));
        assert!(bad(ConvergeSettings {
            max_depth: Some(-2),
            ..s.clone()
        })
        .contains("max_depth"));
        assert!(bad(ConvergeSettings {
            radiosity_patch_sizes: vec![-1.0],
            ..s.clone()
        })
        .contains("positive"));
        let e = run(&s, &|_| {}).unwrap_err().to_string();
        assert_eq!(e, "reference 'none.exr' not found");
    }
}
