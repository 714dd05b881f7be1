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
//! | [`Integrator::PhotonMapper`] | `photonmapper` (pt) | photon mapping as Jensen 1996 describes it: global and caustic maps, k-nearest estimates, final gathering ([`photonmap`]) |
//! | [`Integrator::Vcm`] | `bdpt`, `vcm` (pt) | bidirectional path tracing, and vertex connection and merging, under one power heuristic ([`vcm`]) |
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
// processor was checked for those features (render/tile.rs, `render_tile`).
#![deny(unsafe_code)]

pub mod afterglow;
pub mod aov;
mod config;
pub mod direct;
mod grid;
mod methods;
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
use pt_render::{BuildError, BvhKind, LightSelection, RenderOutput};
use pt_scene::{IntegratorKind, RadiosityOptions, SceneDesc};
use pt_spectrum::ColorMode;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

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
    /// Whether the output's per-pixel variance is wanted: without it, a splatting film skips
    /// the sums it needs ([`RenderSettings::variance`]). A render that saves its state (to
    /// resume or merge it) must keep them.
    pub variance: bool,
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
            variance: true,
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
}
