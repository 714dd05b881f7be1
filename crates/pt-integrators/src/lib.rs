//! Light transport methods as peers behind one interface: a closed [`Integrator`] enum, each
//! variant configured once from the scene description's `<integrator>` (and the command line's
//! [`Overrides`]), each rendering a [`Job`] into an image with its per-pixel variance.
//!
//! | variant | Mitsuba plugin | method |
//! |---|---|---|
//! | [`Integrator::Path`] | `path`, `volpath` | unidirectional path tracing, NEE + MIS ([`path`]); `volpath` with media: [`volpath`] (free-flight and phase sampling, light sampling through media and null surfaces) |
//! | [`Integrator::Direct`] | `direct` | direct illumination at the camera ray's hit: any numbers of light and BSDF samples, weighted by Veach's count-weighted power heuristic ([`direct`]) |
//! | [`Integrator::PTracer`] | `ptracer` | light tracing: paths from the lights, every vertex connected to the camera and splatted ([`ptracer`]) |
//! | [`Integrator::Sppm`] | `sppm` (pt) | stochastic progressive photon mapping with Knaus & Zwicker's radius schedule ([`sppm`]) |
//! | [`Integrator::Radiosity`] | `radiosity` (pt) | finite-element radiosity (crate `pt-radiosity`) |
//! | [`Integrator::Depth`] | `depth` | the distance to the first hit as the image ([`aov::render_depth`]) |
//! | [`Integrator::Afterglow`] | (pt, `--time`) | phosphorescent afterglow: a first pass with the lights on, then the path tracer in the dark ([`afterglow`]) |
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use pt_integrators::{Integrator, Job, Overrides, Run};
//! let desc = pt_scene::load_file("scenes/cornell-box.xml".as_ref(), &[])?;
//! let integrator = Integrator::from_desc(&desc.integrator, &Overrides::default())?;
//! let job = Job::new(&desc);
//! let rendered = integrator.render(&job, Run::default())?;
//! assert_eq!(rendered.output.spp, desc.sampler.sample_count);
//! # Ok(()) }
//! ```
#![warn(missing_docs)]
// One exception, allowed where it is: calling the render loop's x86-64-v3 variant after the
// processor was checked for those features (render.rs, `render_tile`).
#![deny(unsafe_code)]

pub mod afterglow;
pub mod aov;
pub mod direct;
mod grid;
pub mod path;
pub mod photonmap;
pub mod ptracer;
pub mod render;
mod scatter;
pub mod sppm;
pub mod vcm;
pub mod volpath;

pub use path::{Coverage, PathSettings, Strategy};
pub use render::{
    render, render_passes, render_passes_saving, Checkpoint, RenderSettings, RenderState, Share,
};

use pt_radiosity::RadiosityParams;
use pt_render::{BuildError, BvhKind, LightSelection, RenderOutput, Scene};
use pt_scene::{IntegratorDesc, IntegratorKind, RadiosityOptions, SceneDesc};
use pt_spectrum::{srgb_to_xyz, ColorMode};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// Errors of an integrator: bad settings, a scene it cannot render, a bad saved state.
#[derive(Debug, thiserror::Error)]
pub enum IntegratorError {
    /// The scene could not be built (names the element).
    #[error(transparent)]
    Build(#[from] BuildError),
    /// Radiosity refused the scene or its parameters.
    #[error(transparent)]
    Radiosity(#[from] pt_radiosity::RadiosityError),
    /// A setting out of range or one that does not apply to the chosen method.
    #[error("{0}")]
    Settings(String),
}

/// The light transport methods a front end may ask for by name (`pt render --integrator`,
/// the Python module's `integrator=`), as [`method`] reads them.
pub const METHODS: &[&str] = &[
    "path",
    "volpath",
    "direct",
    "ptracer",
    "sppm",
    "bdpt",
    "vcm",
    "photonmapper",
    "radiosity",
    "depth",
];

/// The method named `name` (one of [`METHODS`]) with its default settings, as the scene
/// format's `<integrator type="name">` without properties reads it; `None` for another name.
/// As an [`Overrides::kind`], naming the scene's own method keeps the scene's settings.
pub fn method(name: &str) -> Option<IntegratorKind> {
    Some(match name {
        "path" => IntegratorKind::Path,
        "volpath" => IntegratorKind::VolPath,
        "direct" => IntegratorKind::Direct {
            emitter_samples: 1,
            bsdf_samples: 1,
        },
        "ptracer" => IntegratorKind::PTracer {
            samples_per_pass: None,
        },
        "sppm" => IntegratorKind::Sppm {
            photons_per_iteration: None,
            initial_radius: None,
            alpha: 2.0 / 3.0,
        },
        "bdpt" => IntegratorKind::Bdpt,
        "photonmapper" => IntegratorKind::PhotonMapper {
            global_photons: 100_000,
            caustic_photons: 100_000,
            lookup_size: 50,
            lookup_radius: None,
            final_gather: true,
        },
        "vcm" => IntegratorKind::Vcm {
            initial_radius: None,
            alpha: 0.75,
        },
        "radiosity" => IntegratorKind::Radiosity,
        "depth" => IntegratorKind::Depth,
        _ => return None,
    })
}

/// Settings given on the command line that override the scene's `<integrator>`: each applies
/// to the methods that have it, and is an error for the others.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// Another method than the scene's.
    pub kind: Option<IntegratorKind>,
    /// Longest path in segments (path tracers).
    pub max_depth: Option<i32>,
    /// Direct-light strategy (path tracers).
    pub strategy: Option<Strategy>,
    /// Clamp of each sample's radiance (path tracers; adds bias).
    pub clamp: Option<f32>,
    /// Seconds since the lights went out: the afterglow of phosphorescent materials.
    pub afterglow: Option<f32>,
    /// Radiosity options, each overriding the scene's of the same name.
    pub radiosity: RadiosityOptions,
}

/// The path tracer's settings: the estimator and the optional sample clamp.
#[derive(Clone, Copy, Debug)]
pub struct PathTracer {
    /// Depth, Russian roulette, strategy, media.
    pub settings: PathSettings,
    /// Clamp of each sample's radiance (largest RGB channel; off by default, adds bias).
    pub clamp: Option<f32>,
}

/// A light transport method with its settings.
#[derive(Clone, Debug)]
pub enum Integrator {
    /// Path tracing (Mitsuba `path`, and `volpath` with absorbing media).
    Path(PathTracer),
    /// Direct illumination (Mitsuba `direct`): Mitsuba's numbers of light and BSDF samples at
    /// the camera ray's hit ([`direct`]).
    Direct(PathTracer),
    /// Light tracing (Mitsuba `ptracer`, [`ptracer`]): `max_depth`, `rr_depth` and
    /// `hide_emitters` of the path settings apply.
    PTracer {
        /// Depth, Russian roulette, hidden emitters.
        settings: PathSettings,
        /// Mitsuba's `samples_per_pass`: the sample count must be a multiple of it.
        samples_per_pass: Option<u32>,
    },
    /// Stochastic progressive photon mapping (pt extension, [`sppm`]): `max_depth`,
    /// `rr_depth` and `hide_emitters` of the path settings apply.
    Sppm {
        /// Depth, Russian roulette, hidden emitters.
        settings: PathSettings,
        /// Photons, radius, alpha.
        sppm: sppm::SppmSettings,
    },
    /// Photon mapping as Jensen 1996 describes it (pt extension, [`photonmap`]):
    /// `max_depth`, `rr_depth` and `hide_emitters` of the path settings apply.
    PhotonMapper {
        /// Depth, Russian roulette, hidden emitters.
        settings: PathSettings,
        /// Photon counts, lookups, final gathering.
        photons: photonmap::PhotonMapSettings,
    },
    /// Bidirectional path tracing or vertex connection and merging (pt extensions,
    /// [`vcm`]): `max_depth`, `rr_depth` and `hide_emitters` of the path settings apply.
    Vcm {
        /// Depth, Russian roulette, hidden emitters.
        settings: PathSettings,
        /// Merging on or off, radius schedule.
        vcm: vcm::VcmSettings,
    },
    /// Mitsuba's `depth`: the distance to the first hit ([`aov::render_depth`]).
    Depth,
    /// Radiosity (project extension).
    Radiosity(RadiosityParams),
    /// The afterglow of phosphorescent materials `time` seconds after the lights went out,
    /// rendered by the path tracer.
    Afterglow {
        /// Seconds since the lights went out (>= 0).
        time: f32,
        /// The path tracer of both passes.
        path: PathTracer,
    },
}

/// What to render: the scene, its film and sampler settings, and how the scene is built.
#[derive(Clone, Debug)]
pub struct Job<'a> {
    /// The scene description (its film gives the image size and filter).
    pub desc: &'a SceneDesc,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the random streams.
    pub seed: u64,
    /// Acceleration structure (path tracers).
    pub bvh: BvhKind,
    /// How next-event estimation picks lights (path tracers).
    pub selection: LightSelection,
    /// The colour mode, or `None` for the scene's own (spectral when it needs it).
    pub mode: Option<ColorMode>,
    /// Which of the `spp` samples per pixel to take (all, or one share of a render split over
    /// machines: camera-path methods only).
    pub share: Share,
}

impl<'a> Job<'a> {
    /// The scene as its file describes it: its spp and seed, default build options.
    pub fn new(desc: &'a SceneDesc) -> Self {
        Job {
            desc,
            spp: desc.sampler.sample_count,
            seed: desc.sampler.seed,
            bvh: BvhKind::Auto,
            selection: LightSelection::default(),
            mode: None,
            share: Share::WHOLE,
        }
    }
}

/// Progress reports of a render (called from worker threads).
pub trait Progress: Sync {
    /// The sampling starts: `total` samples in all, `done` of them already taken (resumed).
    fn start_samples(&self, total: u64, done: u64);
    /// `n` more samples taken.
    fn samples(&self, n: u64);
    /// A method with stages (radiosity): the stage's name and how far the whole run is (0-1).
    fn stage(&self, name: &str, fraction: f32);
}

/// Reports nothing.
struct Silent;

impl Progress for Silent {
    fn start_samples(&self, _: u64, _: u64) {}
    fn samples(&self, _: u64) {}
    fn stage(&self, _: &str, _: f32) {}
}

/// How a render runs: progress, cancellation and a saved state to continue.
pub struct Run<'a> {
    /// Where progress goes.
    pub progress: &'a dyn Progress,
    /// Set to stop after the current pass (the image so far is returned).
    pub cancel: &'a AtomicBool,
    /// A saved render to continue (path tracers only; see [`RenderState`]).
    pub resume: Option<RenderState>,
    /// Save the render in progress now and then (camera-path methods; see [`Checkpoint`]).
    pub checkpoint: Option<Checkpoint<'a>>,
}

impl Default for Run<'_> {
    fn default() -> Self {
        static NEVER: AtomicBool = AtomicBool::new(false);
        Run {
            progress: &Silent,
            cancel: &NEVER,
            resume: None,
            checkpoint: None,
        }
    }
}

/// A finished (or cancelled) render.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image and its variance.
    pub output: RenderOutput,
    /// The colour mode it was rendered in.
    pub mode: ColorMode,
    /// Settings worth recording in the image's header (name, value).
    pub header: Vec<(String, String)>,
    /// One line saying what was done and what it cost, for the log.
    pub summary: String,
    /// Warnings for the user (settings ignored, approximations).
    pub warnings: Vec<String>,
    /// Path tracers: the accumulated sums, for `--save-state`.
    pub state: Option<RenderState>,
    /// Whether all samples were taken (false after a cancel).
    pub complete: bool,
    /// Time to build the scene (BVH, materials, lights), before sampling.
    pub build_time: Duration,
    /// Channels written besides the image's own (Mitsuba's `aov`: the nested integrator's
    /// image under its name, then the AOVs), each a row-major plane.
    pub extra_channels: Vec<(String, Vec<f32>)>,
}

impl Rendered {
    /// Every channel of the image in `format` (see [`RenderOutput::channels`]: `R`, `G`, `B`,
    /// or `Y`, or `X`, `Y`, `Z`, then `A`), followed by [`Rendered::extra_channels`]: what
    /// `pt render` writes to its EXR, in that order, each a row-major plane.
    pub fn channels(
        &self,
        format: pt_scene::PixelFormat,
    ) -> Result<Vec<(String, Vec<f32>)>, String> {
        let mut out: Vec<(String, Vec<f32>)> = self
            .output
            .channels(format)?
            .into_iter()
            .map(|(n, p)| (n.to_string(), p))
            .collect();
        out.extend(self.extra_channels.iter().cloned());
        Ok(out)
    }
}

impl Integrator {
    /// The method the scene's `<integrator>` asks for (or `o.kind`), with its settings read
    /// from the description once and the command line's overrides applied. An override that
    /// does not apply to the method is an error.
    pub fn from_desc(d: &IntegratorDesc, o: &Overrides) -> Result<Integrator, IntegratorError> {
        let bad = |m: String| Err(IntegratorError::Settings(m));
        if let Some(depth) = o.max_depth {
            if depth < -1 {
                return bad(format!(
                    "--max-depth must be -1 (unlimited) or >= 0, got {depth}"
                ));
            }
        }
        if let Some(c) = o.clamp {
            if !(c > 0.0 && c.is_finite()) {
                return bad(format!(
                    "--clamp must be a positive finite radiance, got {c}"
                ));
            }
        }
        // Naming the scene's own method keeps the scene's parameters for it.
        let kind = match o.kind {
            Some(k) if std::mem::discriminant(&k) != std::mem::discriminant(&d.kind) => k,
            _ => d.kind,
        };
        let radiosity_options = o.radiosity != RadiosityOptions::default();
        if kind != IntegratorKind::Radiosity && radiosity_options {
            return bad("radiosity options apply to --integrator radiosity only".into());
        }
        // The scene's settings for the method chosen (which may not be the scene's).
        let scene_settings = PathSettings::from_desc(&IntegratorDesc { kind, ..d.clone() });
        let path = |max_depth: i32| PathTracer {
            settings: PathSettings {
                max_depth: o.max_depth.unwrap_or(max_depth),
                strategy: o.strategy.unwrap_or(scene_settings.strategy),
                ..scene_settings
            },
            clamp: o.clamp,
        };
        if let Some(time) = o.afterglow {
            if matches!(
                kind,
                IntegratorKind::Radiosity
                    | IntegratorKind::Depth
                    | IntegratorKind::PTracer { .. }
                    | IntegratorKind::Sppm { .. }
                    | IntegratorKind::Bdpt
                    | IntegratorKind::Vcm { .. }
                    | IntegratorKind::PhotonMapper { .. }
            ) {
                return bad("--time (afterglow) is rendered by the path tracer".into());
            }
            if !(time >= 0.0 && time.is_finite()) {
                return bad(format!(
                    "--time must be a non-negative number of seconds, got {time}"
                ));
            }
            return Ok(Integrator::Afterglow {
                time,
                path: path(d.max_depth),
            });
        }
        Ok(match kind {
            // A radiosity scene rendered by the path tracer keeps its max_depth.
            IntegratorKind::Path | IntegratorKind::VolPath => Integrator::Path(path(d.max_depth)),
            IntegratorKind::Direct {
                emitter_samples,
                bsdf_samples,
            } => {
                if o.max_depth.is_some() {
                    return bad(
                        "--max-depth applies to path and volpath; direct shades the first hit only"
                            .into(),
                    );
                }
                // --strategy keeps one strategy with the larger count, or both.
                let most = emitter_samples.max(bsdf_samples);
                let counts = match o.strategy {
                    None => (emitter_samples, bsdf_samples),
                    Some(Strategy::Mis) => (most, most),
                    Some(Strategy::Light) => (most, 0),
                    Some(Strategy::Bsdf) => (0, most),
                };
                let mut p = path(2);
                p.settings.direct = Some(direct::ShadingSamples {
                    emitter: counts.0,
                    bsdf: counts.1,
                });
                Integrator::Direct(p)
            }
            IntegratorKind::PTracer { samples_per_pass } => {
                if o.clamp.is_some() || o.strategy.is_some() {
                    return bad(
                        "--clamp and --strategy apply to the path tracer, not to ptracer".into(),
                    );
                }
                Integrator::PTracer {
                    settings: path(d.max_depth).settings,
                    samples_per_pass,
                }
            }
            IntegratorKind::Sppm {
                photons_per_iteration,
                initial_radius,
                alpha,
            } => {
                if o.clamp.is_some() || o.strategy.is_some() {
                    return bad(
                        "--clamp and --strategy apply to the path tracer, not to sppm".into(),
                    );
                }
                Integrator::Sppm {
                    settings: path(d.max_depth).settings,
                    sppm: sppm::SppmSettings {
                        photons: photons_per_iteration.map(u64::from),
                        initial_radius,
                        alpha,
                    },
                }
            }
            IntegratorKind::PhotonMapper {
                global_photons,
                caustic_photons,
                lookup_size,
                lookup_radius,
                final_gather,
            } => {
                if o.clamp.is_some() || o.strategy.is_some() {
                    return bad(
                        "--clamp and --strategy apply to the path tracer, not to photonmapper"
                            .into(),
                    );
                }
                Integrator::PhotonMapper {
                    settings: path(d.max_depth).settings,
                    photons: photonmap::PhotonMapSettings {
                        global_photons: u64::from(global_photons),
                        caustic_photons: u64::from(caustic_photons),
                        lookup: lookup_size as usize,
                        max_radius: lookup_radius,
                        final_gather,
                    },
                }
            }
            IntegratorKind::Bdpt | IntegratorKind::Vcm { .. } => {
                let params = match kind {
                    IntegratorKind::Vcm {
                        initial_radius,
                        alpha,
                    } => vcm::VcmSettings {
                        initial_radius,
                        alpha,
                        ..vcm::VcmSettings::vcm()
                    },
                    _ => vcm::VcmSettings::bdpt(),
                };
                if o.clamp.is_some() || o.strategy.is_some() {
                    return bad(format!(
                        "--clamp and --strategy apply to the path tracer, not to {}",
                        params.name()
                    ));
                }
                Integrator::Vcm {
                    settings: path(d.max_depth).settings,
                    vcm: params,
                }
            }
            IntegratorKind::Depth => {
                if o.max_depth.is_some() || o.strategy.is_some() || o.clamp.is_some() {
                    return bad(
                        "--max-depth, --strategy and --clamp apply to the path tracers, not to depth"
                            .into(),
                    );
                }
                Integrator::Depth
            }
            IntegratorKind::Radiosity => {
                if o.max_depth.is_some() || o.clamp.is_some() || o.strategy.is_some() {
                    return bad("--max-depth, --clamp and --strategy apply to the path tracer, not to radiosity".into());
                }
                Integrator::Radiosity(radiosity_params(&d.radiosity, &o.radiosity))
            }
        })
    }

    /// Reads a render state saved by `--save-state` for this method, scene and `settings`
    /// (the scene's film: the state's layout follows from it and the method).
    pub fn read_state(
        &self,
        bytes: &[u8],
        scene_key: u64,
        settings: &RenderSettings,
    ) -> Result<RenderState, String> {
        match self {
            // The photon mappers keep per-pixel statistics only (no splatting film).
            Integrator::Sppm { .. } | Integrator::PhotonMapper { .. } => RenderState::from_bytes(
                bytes,
                scene_key,
                &RenderSettings {
                    reconstruction: pt_scene::Reconstruction::Importance,
                    moment: false,
                    ..settings.clone()
                },
            ),
            _ => RenderState::from_bytes(bytes, scene_key, settings),
        }
    }

    /// The method's name, as in `<integrator type="...">`.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Path(p) if p.settings.media => "volpath",
            Integrator::Path(_) => "path",
            Integrator::Direct(_) => "direct",
            Integrator::PTracer { .. } => "ptracer",
            Integrator::Sppm { .. } => "sppm",
            Integrator::Vcm { vcm, .. } => vcm.name(),
            Integrator::PhotonMapper { .. } => "photonmapper",
            Integrator::Radiosity(_) => "radiosity",
            Integrator::Depth => "depth",
            Integrator::Afterglow { .. } => "afterglow",
        }
    }

    /// Whether this method can render `desc` as its file asks: a film with an alpha channel
    /// and Mitsuba's `aov` integrator need camera paths. Checked before any work, so that a
    /// front end refuses the scene at once (the error names the scene file).
    pub fn check_scene(&self, desc: &SceneDesc) -> Result<(), IntegratorError> {
        if desc.film.pixel_format.has_alpha() && !self.traces_camera_paths() {
            return Err(IntegratorError::Settings(format!(
                "{}: the film's pixel_format has an alpha channel, which {} does not compute (use rgb, luminance or xyz)",
                desc.source.display(),
                self.name()
            )));
        }
        // The measuring sensors that sample a surface or a target draw their rays in the
        // camera-path loops only; the irradiancemeter's weight (pi) is the image's alone.
        let (meter, by) = match desc.camera.projection {
            pt_scene::Projection::Irradiancemeter { .. } => (
                "an irradiancemeter",
                "path, volpath or direct (without aov or moment)",
            ),
            pt_scene::Projection::Distant { .. } => {
                ("a distant sensor", "path, volpath, direct or depth")
            }
            pt_scene::Projection::Batch => (
                "a batch sensor",
                "path, volpath, direct, depth, sppm or photonmapper",
            ),
            _ => ("", ""),
        };
        if !meter.is_empty() {
            let irradiance = meter == "an irradiancemeter";
            let renders = match self {
                Integrator::Path(_) | Integrator::Direct(_) | Integrator::Afterglow { .. } => {
                    !irradiance
                        || (desc.integrator.aov.is_none() && desc.integrator.moment.is_none())
                }
                Integrator::Depth => !irradiance,
                Integrator::Sppm { .. } | Integrator::PhotonMapper { .. } => {
                    meter == "a batch sensor"
                }
                _ => false,
            };
            if !renders {
                return Err(IntegratorError::Settings(format!(
                    "{}: {meter} is rendered by {by}, not by {}",
                    desc.camera.loc,
                    self.name()
                )));
            }
        }
        if desc.integrator.aov.is_some() && !self.traces_camera_paths() {
            return Err(IntegratorError::Settings(format!(
                "{}: the scene's aov integrator needs a path tracer, not {}",
                desc.source.display(),
                self.name()
            )));
        }
        Ok(())
    }

    /// Whether the method's samples can be split between processes ([`Share`]) and
    /// checkpointed: every method whose sample indices (iterations) are independent of each
    /// other ([`Integrator::unshared_because`] says why the others are not).
    pub fn takes_shares(&self) -> bool {
        self.unshared_because().is_none()
    }

    /// Why the method's samples cannot be split between processes or checkpointed, or `None`
    /// when they can.
    pub fn unshared_because(&self) -> Option<&'static str> {
        match self {
            Integrator::Sppm { .. } => Some(
                "its iterations depend on the ones before (each shrinks the photon radii from the photons gathered so far)",
            ),
            Integrator::Radiosity(_) => Some("it is not sampled per pixel"),
            Integrator::Depth => Some("it renders in one pass"),
            _ => None,
        }
    }

    /// Whether the method traces camera paths: the path tracers do, and compute the alpha
    /// channel and AOVs; radiosity and the light tracer do neither.
    pub fn traces_camera_paths(&self) -> bool {
        !matches!(
            self,
            Integrator::Radiosity(_)
                | Integrator::PTracer { .. }
                | Integrator::Sppm { .. }
                | Integrator::Vcm { .. }
                | Integrator::PhotonMapper { .. }
        )
    }

    /// Renders the job. Path tracers honour `run.cancel` between passes and continue
    /// `run.resume`; radiosity runs to the end.
    pub fn render(&self, job: &Job, run: Run) -> Result<Rendered, IntegratorError> {
        if let (true, Some(why)) = (
            job.share != Share::WHOLE || run.checkpoint.is_some(),
            self.unshared_because(),
        ) {
            return Err(IntegratorError::Settings(format!(
                "{} cannot be split into parts or checkpointed: {why}",
                self.name()
            )));
        }
        match self {
            Integrator::Path(p) => render_path(self.name(), p, job.desc, job, run),
            Integrator::Direct(p) => render_path(self.name(), p, job.desc, job, run),
            Integrator::Afterglow { time, path } => {
                let start = Instant::now();
                let dark = afterglow::afterglow(job.desc, *time, job.seed)?;
                let mut r = render_path("afterglow", path, &dark, job, run)?;
                r.build_time += start.elapsed();
                r.header.push(("afterglow_time_s".into(), time.to_string()));
                Ok(r)
            }
            Integrator::PTracer {
                settings,
                samples_per_pass,
            } => render_ptracer(settings, *samples_per_pass, job, run),
            Integrator::Sppm { settings, sppm } => render_sppm(settings, sppm, job, run),
            Integrator::Vcm { settings, vcm } => render_vcm(settings, vcm, job, run),
            Integrator::PhotonMapper { settings, photons } => {
                render_photonmapper(settings, photons, job, run)
            }
            Integrator::Radiosity(params) => render_radiosity(params, job, run),
            Integrator::Depth => render_depth(job, run),
        }
    }
}

/// The light tracer over the image in passes of batches of light paths
/// ([`ptracer::render_light_passes`]).
fn render_ptracer(
    path: &PathSettings,
    samples_per_pass: Option<u32>,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    if let Some(n) = samples_per_pass {
        if job.spp % n.min(job.spp.max(1)) != 0 {
            return Err(IntegratorError::Settings(format!(
                "ptracer: the sample count ({}) must be a multiple of samples_per_pass ({n})",
                job.spp
            )));
        }
    }
    let (scene, settings, build_time, mut state) = prepare(
        job,
        path,
        run.resume,
        |s| s.light.is_some(),
        "the saved state is a path tracer's, not a light tracer's",
        RenderState::for_light_paths,
        |scene, settings| {
            refuse_glowing_media(scene)
                .and_then(|_| refuse_meters("ptracer", scene))
                .and_then(|_| ptracer::check(settings))
        },
    )?;
    let paths_per_batch = u64::from(settings.width) * u64::from(settings.height);
    run.progress.start_samples(
        paths_per_batch * u64::from(settings.spp),
        paths_per_batch * u64::from(state.spp_done),
    );
    let complete = ptracer::render_light_passes(
        &scene,
        &settings,
        &mut state,
        run.cancel,
        run.checkpoint.as_ref(),
        &|n| run.progress.samples(n),
    );
    let output = state.output();
    let (summary, warnings) = report(
        "ptracer",
        "a sample being one light path; ",
        &output,
        build_time,
    );
    let header = vec![
        ("integrator".to_string(), "ptracer".to_string()),
        ("max_depth".to_string(), path.max_depth.to_string()),
    ];
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// The log line every sampling method ends with (size, samples per pixel, time, rate, scene
/// build; `what` says what a sample is where it is not a camera path) and the warning about
/// samples left out as NaN or infinite.
fn report(
    name: &str,
    what: &str,
    output: &RenderOutput,
    build_time: Duration,
) -> (String, Vec<String>) {
    let secs = output.time.as_secs_f64();
    let samples = u64::from(output.width) * u64::from(output.height) * u64::from(output.spp);
    let summary = format!(
        "{name}: {}x{} at {} spp in {:.2} s ({:.2} M samples/s, {what}scene build {:.2} s)",
        output.width,
        output.height,
        output.spp,
        secs,
        samples as f64 / secs.max(1e-9) / 1e6,
        build_time.as_secs_f64()
    );
    let mut warnings = Vec::new();
    if output.nonfinite_samples > 0 {
        warnings.push(format!(
            "{} samples were NaN or infinite and were left out of the image",
            output.nonfinite_samples
        ));
    }
    (summary, warnings)
}

/// The radiosity parameters: the scene's options, each overridden by the command line's.
fn radiosity_params(scene: &RadiosityOptions, cli: &RadiosityOptions) -> RadiosityParams {
    let d = RadiosityParams::default();
    RadiosityParams {
        patch_size: cli.patch_size.or(scene.patch_size).or(d.patch_size),
        rays_per_patch: cli
            .rays_per_patch
            .or(scene.rays_per_patch)
            .unwrap_or(d.rays_per_patch),
        tolerance: cli.tolerance.or(scene.tolerance).unwrap_or(d.tolerance),
        max_iterations: cli
            .max_iterations
            .or(scene.max_iterations)
            .unwrap_or(d.max_iterations),
        solver: cli.solver.or(scene.solver).unwrap_or(d.solver),
        display: cli.display.or(scene.display).unwrap_or(d.display),
        reciprocity: cli
            .reciprocity
            .or(scene.reciprocity)
            .unwrap_or(d.reciprocity),
        ..d
    }
}

/// The path tracer over the image in passes (see [`render_passes`]).
fn render_path(
    name: &str,
    p: &PathTracer,
    desc: &SceneDesc,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    let build_start = Instant::now();
    let scene = Scene::build_with_mode(desc, job.bvh, job.selection, job.mode)?;
    let build_time = build_start.elapsed();
    let settings = RenderSettings {
        spp: job.share.samples_of(job.spp),
        seed: job.seed,
        path: p.settings,
        clamp: p.clamp,
        share: job.share,
        ..RenderSettings::from_desc(desc)
    };
    let mut state = match run.resume {
        Some(s) => s,
        None => RenderState::new(&settings),
    };
    if state.spp_done > settings.spp {
        return Err(IntegratorError::Settings(format!(
            "the saved render already has {} spp, more than --spp {}",
            state.spp_done, settings.spp
        )));
    }
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    let aov = desc.integrator.aov.as_ref();
    // An `aov` integrator without a nested one renders no image (its channels stay zero).
    let complete = if aov.is_some_and(|a| a.image.is_none()) {
        true
    } else {
        run.progress.start_samples(
            pixels * u64::from(settings.spp),
            pixels * u64::from(state.spp_done),
        );
        render_passes_saving(
            &scene,
            &settings,
            &mut state,
            run.cancel,
            run.checkpoint.as_ref(),
            &|n| run.progress.samples(n),
        )
    };
    let output = state.output();
    let mut extra_channels = Vec::new();
    // A share's AOVs are rendered when the shares are merged (their passes are not split).
    if let (Some(aov), true, true) = (aov, complete, job.share == Share::WHOLE) {
        let mut planes: Vec<Vec<f32>> = Vec::new();
        if aov.image.is_some() {
            planes.extend((0..3).map(|c| output.mean.iter().map(|p| p[c]).collect()));
            planes.push(output.alpha.clone().unwrap_or_default());
        }
        planes.extend(aov::render_aovs(&scene, &settings, aov));
        extra_channels = aov.channel_names().into_iter().zip(planes).collect();
    }
    if let (Some(name), Some(m2)) = (&desc.integrator.moment, &output.second_moment) {
        let xyz: Vec<[f32; 3]> = output.mean.iter().map(|&c| srgb_to_xyz(c)).collect();
        for (prefix, values) in [(name.clone(), &xyz), (format!("m2_{name}"), m2)] {
            for (c, axis) in ["X", "Y", "Z"].iter().enumerate() {
                let plane = values.iter().map(|v| v[c]).collect();
                extra_channels.push((format!("{prefix}.{axis}"), plane));
            }
        }
    }
    let (summary, warnings) = report(name, "", &output, build_time);
    let mut header = vec![
        ("integrator".to_string(), name.to_string()),
        ("max_depth".to_string(), p.settings.max_depth.to_string()),
        (
            "strategy".to_string(),
            format!("{:?}", p.settings.strategy).to_lowercase(),
        ),
    ];
    if let Some(c) = p.clamp {
        header.push(("clamp".into(), c.to_string()));
    }
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels,
    })
}

/// Stochastic progressive photon mapping ([`sppm::render_sppm_passes`]).
fn render_sppm(
    path: &PathSettings,
    params: &sppm::SppmSettings,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    let (scene, settings, build_time, mut state) = prepare(
        job,
        path,
        run.resume,
        |s| s.light.is_none() && s.splat.is_none(),
        "the saved state is not a photon mapper's",
        sppm::new_state,
        |scene, _| refuse_media("sppm", scene).and_then(|_| sppm::check(params)),
    )?;
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    run.progress.start_samples(
        pixels * u64::from(settings.spp),
        pixels * u64::from(state.spp_done),
    );
    let complete =
        sppm::render_sppm_passes(&scene, &settings, params, &mut state, run.cancel, &|n| {
            run.progress.samples(n)
        });
    let mut output = state.output();
    output.alpha = None;
    let photons = params.photons.unwrap_or(pixels);
    let what =
        format!("a sample being an iteration's camera path, {photons} photons per iteration; ");
    let (summary, warnings) = report("sppm", &what, &output, build_time);
    let header = vec![
        ("integrator".to_string(), "sppm".to_string()),
        ("max_depth".to_string(), path.max_depth.to_string()),
        ("photons_per_iteration".to_string(), photons.to_string()),
        ("alpha".to_string(), params.alpha.to_string()),
    ];
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// The refusal of the light-side methods that do not trace participating media (all but
/// `ptracer`).
fn refuse_media(name: &str, scene: &Scene) -> Result<(), String> {
    if let Some(m) = scene.media.first() {
        return Err(format!(
            "{}: {name} does not yet trace participating media (not yet implemented): the scene has {} medium(s); render it with volpath or ptracer",
            m.loc,
            scene.media.len()
        ));
    }
    Ok(())
}

/// The refusal of the methods that connect light paths to the camera when the sensor is a
/// radiancemeter (one ray, which a connection meets with probability zero), an
/// irradiancemeter, a distant sensor or a batch (whose importance pt does not evaluate).
pub(crate) fn refuse_meters(name: &str, scene: &Scene) -> Result<(), String> {
    if scene.camera.refuses_light_paths() {
        return Err(format!(
            "{}: {name} cannot render for a radiancemeter, irradiancemeter, distant or batch sensor (light paths do not connect to them); use path or volpath",
            scene.camera.loc()
        ));
    }
    Ok(())
}

/// The light tracer's refusal of glowing media: it starts paths on the lights only, and a
/// medium's emission (a pt extension) is not one of them.
fn refuse_glowing_media(scene: &Scene) -> Result<(), String> {
    if let Some(m) = scene.media.iter().find(|m| m.emission.is_some()) {
        return Err(format!(
            "{}: ptracer does not start light paths in glowing media (a medium with emission is not yet a light source; not yet implemented): render the scene with volpath",
            m.loc
        ));
    }
    Ok(())
}

/// What every sampling method does before it samples: builds the scene and the render
/// settings (the job's spp and seed, `path`), runs the method's `check`, and takes the saved
/// state to continue (refused with `wrong` unless `accepts` it, or holding more samples than
/// asked for) or a `new` one.
#[allow(clippy::type_complexity)]
#[allow(clippy::too_many_arguments)]
fn prepare(
    job: &Job,
    path: &PathSettings,
    resume: Option<RenderState>,
    accepts: impl Fn(&RenderState) -> bool,
    wrong: &str,
    new: impl Fn(&RenderSettings) -> RenderState,
    check: impl Fn(&Scene, &RenderSettings) -> Result<(), String>,
) -> Result<(Scene, RenderSettings, Duration, RenderState), IntegratorError> {
    let desc = job.desc;
    let build_start = Instant::now();
    let scene = Scene::build_with_mode(desc, job.bvh, job.selection, job.mode)?;
    let build_time = build_start.elapsed();
    let settings = RenderSettings {
        spp: job.share.samples_of(job.spp),
        seed: job.seed,
        path: *path,
        share: job.share,
        ..RenderSettings::from_desc(desc)
    };
    check(&scene, &settings).map_err(IntegratorError::Settings)?;
    let state = match resume {
        Some(s) if accepts(&s) => s,
        Some(_) => return Err(IntegratorError::Settings(wrong.into())),
        None => new(&settings),
    };
    if state.spp_done > settings.spp {
        return Err(IntegratorError::Settings(format!(
            "the saved render already has {} spp, more than --spp {}",
            state.spp_done, settings.spp
        )));
    }
    Ok((scene, settings, build_time, state))
}

/// Photon mapping ([`photonmap::render_photon_passes`]).
fn render_photonmapper(
    path: &PathSettings,
    params: &photonmap::PhotonMapSettings,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    let (scene, settings, build_time, mut state) = prepare(
        job,
        path,
        run.resume,
        |s| s.light.is_none() && s.splat.is_none(),
        "the saved state is not a photon mapper's",
        sppm::new_state,
        |scene, _| refuse_media("photonmapper", scene).and_then(|_| photonmap::check(params)),
    )?;
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    run.progress.start_samples(
        pixels * u64::from(settings.spp),
        pixels * u64::from(state.spp_done),
    );
    let complete = photonmap::render_photon_passes(
        &scene,
        &settings,
        params,
        &mut state,
        run.cancel,
        run.checkpoint.as_ref(),
        &|n| run.progress.samples(n),
    );
    let mut output = state.output();
    output.alpha = None;
    let what = format!(
        "a sample being an iteration's camera path, {} + {} photons per iteration; ",
        params.global_photons, params.caustic_photons
    );
    let (summary, warnings) = report("photonmapper", &what, &output, build_time);
    let header = vec![
        ("integrator".to_string(), "photonmapper".to_string()),
        ("max_depth".to_string(), path.max_depth.to_string()),
        (
            "global_photons".to_string(),
            params.global_photons.to_string(),
        ),
        (
            "caustic_photons".to_string(),
            params.caustic_photons.to_string(),
        ),
        ("lookup_size".to_string(), params.lookup.to_string()),
        ("final_gather".to_string(), params.final_gather.to_string()),
    ];
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// Bidirectional path tracing and vertex connection and merging
/// ([`vcm::render_vcm_passes`]).
fn render_vcm(
    path: &PathSettings,
    params: &vcm::VcmSettings,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    let name = params.name();
    let (scene, settings, build_time, mut state) = prepare(
        job,
        path,
        run.resume,
        |s| s.light.is_some(),
        "the saved state is not a bidirectional render's (a light film)",
        RenderState::for_light_paths,
        |scene, settings| {
            refuse_media(params.name(), scene).and_then(|_| vcm::check(scene, settings, params))
        },
    )?;
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    run.progress.start_samples(
        pixels * u64::from(settings.spp),
        pixels * u64::from(state.spp_done),
    );
    let complete = vcm::render_vcm_passes(
        &scene,
        &settings,
        params,
        &mut state,
        run.cancel,
        run.checkpoint.as_ref(),
        &|n| run.progress.samples(n),
    );
    let output = state.output();
    let what = "a sample being a camera and a light subpath per pixel; ";
    let (summary, warnings) = report(name, what, &output, build_time);
    let mut header = vec![
        ("integrator".to_string(), name.to_string()),
        ("max_depth".to_string(), path.max_depth.to_string()),
    ];
    if params.merging {
        header.push((
            "initial_radius".to_string(),
            params.radius(0, scene.bounds.1).to_string(),
        ));
        header.push(("alpha".to_string(), params.alpha.to_string()));
    }
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// Mitsuba's `depth` integrator ([`aov::render_depth`]): the distance to the first hit as the
/// image, in one pass (not resumable or split into parts).
fn render_depth(job: &Job, run: Run) -> Result<Rendered, IntegratorError> {
    if run.resume.is_some() {
        return Err(IntegratorError::Settings(
            "--resume applies to the path tracers, not to depth".into(),
        ));
    }
    let build_start = Instant::now();
    let scene = Scene::build_with_mode(job.desc, job.bvh, job.selection, job.mode)?;
    let build_time = build_start.elapsed();
    let settings = RenderSettings {
        spp: job.spp,
        seed: job.seed,
        ..RenderSettings::from_desc(job.desc)
    };
    let start = Instant::now();
    run.progress.stage("depth", 0.0);
    let (depth, variance, alpha) = aov::render_depth(&scene, &settings);
    run.progress.stage("depth", 1.0);
    let output = RenderOutput {
        width: settings.width,
        height: settings.height,
        mean: depth.iter().map(|&t| [t; 3]).collect(),
        variance: variance.iter().map(|&v| [v; 3]).collect(),
        spp: settings.spp,
        time: start.elapsed(),
        nonfinite_samples: 0,
        alpha: Some(alpha),
        second_moment: None,
    };
    let (summary, warnings) = report("depth", "", &output, build_time);
    Ok(Rendered {
        output,
        mode: scene.mode,
        header: vec![("integrator".into(), "depth".into())],
        summary,
        warnings,
        state: None,
        complete: true,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// Radiosity: meshing, form factors, solve, display (crate `pt-radiosity`).
fn render_radiosity(
    params: &RadiosityParams,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    if run.resume.is_some() {
        return Err(IntegratorError::Settings(
            "--resume applies to the path tracer, not to radiosity".into(),
        ));
    }
    if job.mode.is_some() || job.selection != LightSelection::default() || job.bvh != BvhKind::Auto
    {
        return Err(IntegratorError::Settings(
            "--mode, --light-selection and --bvh apply to the path tracer, not to radiosity".into(),
        ));
    }
    let p = RadiosityParams {
        spp: job.spp,
        seed: job.seed,
        ..params.clone()
    };
    let (output, stats) =
        pt_radiosity::render(job.desc, &p, &|stage, f| run.progress.stage(stage, f))?;
    let summary = format!(
        "radiosity: {} patches (size {:.4}), {} form factors ({:.1} MB), form factors {:.2} s, solve {:.2} s in {} iterations, total {:.2} s",
        stats.patches,
        stats.patch_size,
        stats.nnz,
        stats.memory_bytes as f64 / 1e6,
        stats.form_factor_time.as_secs_f64(),
        stats.solve_time.as_secs_f64(),
        stats.iterations,
        output.time.as_secs_f64(),
    );
    let header = vec![
        ("integrator".into(), "radiosity".into()),
        ("patches".into(), stats.patches.to_string()),
        ("rays_per_patch".into(), p.rays_per_patch.to_string()),
        ("solver".into(), format!("{:?}", p.solver).to_lowercase()),
        ("display".into(), format!("{:?}", p.display).to_lowercase()),
        ("iterations".into(), stats.iterations.to_string()),
    ];
    let mode = if job.desc.spectral_reason().is_some() {
        ColorMode::Spectral
    } else {
        ColorMode::Rgb
    };
    Ok(Rendered {
        output,
        mode,
        header,
        summary,
        warnings: stats.warnings.clone(),
        state: None,
        complete: true,
        build_time: Duration::ZERO,
        extra_channels: Vec::new(),
    })
}
