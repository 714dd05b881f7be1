//! Bidirectional path tracing (`bdpt`; Veach 1997, ch. 10) and vertex connection and merging
//! (`vcm`; Georgiev, Křivánek, Davidovič & Slusallek 2012, "Light Transport Simulation with
//! Vertex Connection and Merging"): pt extensions (Mitsuba 3 has neither).
//!
//! Every iteration (one sample per pixel) traces as many light subpaths as the image has
//! pixels, N, and one camera subpath per pixel; camera subpath k is paired with light
//! subpath k. A full path of `k` segments between a light and the camera is then sampled by
//! every strategy that can make it:
//! - *s = 0*: the camera subpath meets an emitter (or leaves the scene towards an environment);
//! - *s = 1*: light sampling at a camera vertex (next-event estimation);
//! - *s >= 2, t >= 2*: a camera vertex connected to a vertex of its paired light subpath;
//! - *t = 1*: a light vertex connected to the camera and splatted where it lands on the
//!   film (every light subpath, so the camera counts N samples of this strategy per pixel);
//! - *merging* (`vcm` only): a camera vertex gathers the light vertices of all N light
//!   subpaths within the radius `r` of it, a photon-mapping density estimate; its density is
//!   the light subpath's times `pi r^2 N`, which joins it to the connection strategies in one
//!   power heuristic (Georgiev et al. 2012, sec. 4).
//!
//! Each strategy's weight is the power heuristic over all of them, computed from three partial
//! sums carried along each subpath (`dVCM`, `dVC`, `dVM` of Georgiev et al.'s technical report
//! "Implementing Vertex Connection and Merging", 2012, eqs. 31-39; [`SubpathMis`]) instead of
//! walking both subpaths at every connection as pbrt-v4's `MISWeight` does: the same weights
//! (the power heuristic over the same strategies and densities), in constant time per
//! connection. `bdpt` is `vcm` with merging off; with connections off only camera paths meeting
//! emitters and merging remain (a pure photon mapper, [`VcmSettings::connections`]).
//!
//! Densities: solid-angle densities of the BSDFs (forward as sampled, reverse with the
//! directions exchanged), turned into area densities with the geometric normal's cosine;
//! delta lobes leave their factor out (their forward and reverse probabilities cancel). Light
//! emission densities come from [`pt_render::light::Light::emission_pdf`], light sampling's
//! from the light's own `sample`/`pdf` (a sphere light's cone sampling included), the
//! camera's from [`pt_render::camera::Camera::direction_pdf`]. Russian roulette (camera
//! subpaths after `rr_depth` segments as the path tracer, light subpaths from their first
//! bounce, see [`crate::ptracer::walk_light_path`]) is left out
//! of the weights (it thins every strategy's samples without changing which can make a
//! path, so the weights still sum to one: the estimate stays unbiased).
//!
//! Merging radius: `r_i = r_0 i^((alpha - 1) / 2)` in iteration i (1-based; Georgiev et al.
//! 2012, sec. 5, alpha = 3/4 by default), r_0 = 1% of the scene's bounding radius unless
//! given. Merging is biased at any finite radius (the kernel blurs), consistent as it shrinks.
//! The merged estimate corrects for shading normals (cos_s / cos_g at the camera vertex).
//!
//! Splats: camera subpaths add their estimate at their own film position, light vertices at
//! theirs, in path order, onto the light tracer's film ([`crate::ptracer::add_batches`]):
//! the same image for any number of threads, and per-batch pixel statistics for variance.
//! Spectral mode: light subpath k and camera subpath k share their wavelengths (per path in
//! `bdpt`; per iteration in `vcm`, where any camera path may merge with any light path).
//! Fluorescence: light subpaths end where they meet a fluorescent surface, and a camera
//! subpath that meets one hands the paths through it to the path tracer's strategies
//! ([`crate::path::li_through_fluorescence`], which says why): a partition of path space,
//! so the estimate stays unbiased; paths without fluorescent surfaces keep every strategy.

mod camera;
mod light;
mod mis;
#[cfg(test)]
mod tests;

use crate::grid::PointGrid;
use crate::path::PathSettings;
use crate::ptracer::{add_batches, Splat};
use camera::camera_sample;
use light::light_subpath;
use mis::{Factors, SubpathMis};
use pt_bsdf::SurfaceBsdf;
use pt_math::{Frame, Vec3};
use pt_render::sampler::Sampler;
use pt_render::Scene;
use pt_spectrum::{ColorMode, SampledSpectrum, SampledWavelengths};
use rayon::prelude::*;
use std::sync::atomic::AtomicBool;

/// The key of the light subpaths' random streams (above every pixel key).
const LIGHT_STREAM: u64 = (1 << 63) | 0x5643_4d4c; // "VCML"
/// The key of the camera subpaths' random streams.
const CAMERA_STREAM: u64 = (1 << 63) | 0x5643_4d43; // "VCMC"
/// The key of the subpath pairs' wavelength streams (`bdpt`).
const WAVELENGTH_STREAM: u64 = (1 << 63) | 0x5643_4d57; // "VCMW"

/// Subpaths per work item: each item keeps its splats and light vertices in one list.
const CHUNK: u64 = 1024;

/// The bidirectional methods' own settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VcmSettings {
    /// Vertex merging (`vcm`); off: bidirectional path tracing (`bdpt`).
    pub merging: bool,
    /// Vertex connection: light sampling, connections and the light vertices' splats. Off
    /// (with merging on): only camera paths meeting emitters and merging, a pure photon
    /// mapper under the same weights, for checking (no scene parameter).
    pub connections: bool,
    /// Merging radius of the first iteration (scene units); `None`: 1% of the scene's
    /// bounding sphere radius.
    pub initial_radius: Option<f32>,
    /// Exponent of the radius schedule, in (0, 1) (3/4 by default).
    pub alpha: f32,
}

impl VcmSettings {
    /// `bdpt`: connections only.
    pub fn bdpt() -> Self {
        VcmSettings {
            merging: false,
            connections: true,
            initial_radius: None,
            alpha: 0.75,
        }
    }

    /// `vcm` with its defaults.
    pub fn vcm() -> Self {
        VcmSettings {
            merging: true,
            ..VcmSettings::bdpt()
        }
    }

    /// The method's name, as in `<integrator type="...">`.
    pub fn name(&self) -> &'static str {
        if self.merging {
            "vcm"
        } else {
            "bdpt"
        }
    }

    /// The merging radius of iteration `i` (0-based) for a scene of bounding radius
    /// `scene_radius`.
    pub fn radius(&self, i: u32, scene_radius: f32) -> f32 {
        let r0 = self.initial_radius.unwrap_or(0.01 * scene_radius);
        r0 * ((i + 1) as f32).powf(0.5 * (self.alpha - 1.0))
    }
}
/// The BSDF of a kept light vertex: the scene material's own when it is the same all over the
/// surface, else one built for the hit, kept beside the vertices (index into that list). The
/// vertices stay small (a copy of the 272-byte BSDF per vertex took 4% of a BDPT profile).
#[derive(Clone, Copy, Debug)]
enum VertexBsdf<'s> {
    /// The material's.
    Shared(&'s SurfaceBsdf),
    /// Built for the hit: index into the subpaths' list of built BSDFs.
    Built(u32),
}

/// A light subpath's vertex kept for connections and merging.
#[derive(Clone, Copy, Debug)]
struct LightVertex<'s> {
    /// Position, world.
    p: Vec3,
    /// Geometric normal, world.
    ng: Vec3,
    /// Shading frame.
    frame: Frame,
    /// Unit direction towards the previous vertex, local frame.
    wl: Vec3,
    /// The same, world.
    w_light: Vec3,
    /// ng . w_light.
    ng_light: f32,
    /// BSDF at the path's wavelengths.
    bsdf: VertexBsdf<'s>,
    /// Weight arriving here (importance transport, see [`crate::ptracer`]).
    beta: SampledSpectrum,
    /// The subpath's partial sums at this vertex.
    mis: SubpathMis,
    /// Segments from the light.
    depth: u32,
}

impl LightVertex<'_> {
    /// What merging needs of the vertex, and where it is.
    fn photon(&self) -> (Vec3, Photon) {
        let ph = Photon {
            ng: self.ng,
            w_light: self.w_light,
            beta: self.beta,
            mis: self.mis,
            depth: self.depth,
        };
        (self.p, ph)
    }

    /// The vertex's BSDF, `built` being the list of BSDFs built for its subpaths' hits.
    #[inline(always)]
    fn bsdf<'x>(&'x self, built: &'x [SurfaceBsdf]) -> &'x SurfaceBsdf {
        match self.bsdf {
            VertexBsdf::Shared(b) => b,
            VertexBsdf::Built(i) => &built[i as usize],
        }
    }
}

/// What merging needs of a light vertex (kept in the grid, in grid order).
#[derive(Clone, Copy, Debug)]
struct Photon {
    /// Geometric normal, world.
    ng: Vec3,
    /// Unit direction towards the previous vertex, world.
    w_light: Vec3,
    /// Weight arriving here.
    beta: SampledSpectrum,
    /// The subpath's partial sums here.
    mis: SubpathMis,
    /// Segments from the light.
    depth: u32,
}
/// What an iteration shares: the scene, settings, the merging radius and factors, and for
/// merging the light vertices of all light subpaths (in chunks) and their grid.
struct Iteration<'a, 's> {
    scene: &'a Scene,
    s: &'a PathSettings,
    vcm: &'a VcmSettings,
    f: Factors,
    radius: f32,
    /// Light subpaths per iteration (N).
    n: f32,
    /// P_film / P_image (see [`crate::ptracer`]).
    scale: f32,
    /// Merging: the light subpaths' vertices, per chunk of subpaths (chunk c holds subpaths
    /// c CHUNK.., each subpath's vertices in a range ending at its entry of `ends`).
    chunks: &'a [LightChunk<'s>],
    /// Merging: every light vertex.
    grid: Option<PointGrid<Photon>>,
}

/// One chunk of light subpaths: their vertices, where each subpath's end, and their camera
/// splats. Kept from iteration to iteration to reuse the memory.
#[derive(Default)]
struct LightChunk<'s> {
    vertices: Vec<LightVertex<'s>>,
    /// The BSDFs built for the vertices' hits ([`VertexBsdf::Built`]).
    built: Vec<SurfaceBsdf>,
    ends: Vec<u32>,
    splats: Vec<Splat>,
}

impl<'s> Iteration<'_, 's> {
    /// The vertices of light subpath `k` (merging: all were traced before the camera pass) and
    /// the BSDFs built for them.
    fn subpath(&self, k: u64) -> (&[LightVertex<'s>], &[SurfaceBsdf]) {
        let chunk = &self.chunks[(k / CHUNK) as usize];
        let j = (k % CHUNK) as usize;
        let start = if j == 0 {
            0
        } else {
            chunk.ends[j - 1] as usize
        };
        (&chunk.vertices[start..chunk.ends[j] as usize], &chunk.built)
    }
}

/// The wavelengths of subpath pair `index` of iteration `it`, whose shared set (RGB mode, and
/// `vcm` in spectral mode) is `shared`: computed once per iteration, as sampling a set costs
/// four `atanh` and four `cosh` (4% of a `bdpt` profile on the Cornell box when done per pair).
fn wavelengths(
    scene: &Scene,
    vcm: &VcmSettings,
    shared: &SampledWavelengths,
    seed: u64,
    it: u32,
    index: u64,
) -> SampledWavelengths {
    match scene.mode {
        ColorMode::Spectral if !vcm.merging => SampledWavelengths::sample_visible(
            Sampler::new(seed, WAVELENGTH_STREAM, (u64::from(it) << 32) | index).next_1d(),
        ),
        _ => *shared,
    }
}
/// Renders `settings.spp` iterations into `state` (a light film), checking `cancel` between
/// iterations. Returns whether all were done.
pub fn render_vcm_passes<'s>(
    scene: &'s Scene,
    settings: &crate::RenderSettings,
    vcm: &VcmSettings,
    state: &mut crate::RenderState,
    cancel: &AtomicBool,
    checkpoint: Option<&crate::Checkpoint>,
    progress: &(dyn Fn(u64) + Sync),
) -> bool {
    let (w, h) = (settings.width, settings.height);
    let paths = u64::from(w) * u64::from(h);
    let [fw, fh] = settings.crop.map_or([w, h], |c| c.film_size);
    let scale = (f64::from(fw) * f64::from(fh)) / paths as f64;
    let s = &settings.path;
    let chunks = paths.div_ceil(CHUNK);
    let range = |c: u64| c * CHUNK..((c + 1) * CHUNK).min(paths);
    let mut pool: Vec<LightChunk> = (0..chunks).map(|_| LightChunk::default()).collect();
    crate::render::in_passes(
        state,
        settings.spp,
        cancel,
        &mut crate::render::checkpointer(checkpoint),
        1,
        1,
        |state, its| {
            // This process's iteration its.start is the render's share.sample(its.start).
            let iteration = settings.share.sample(its.start);
            let radius = vcm.radius(iteration, scene.bounds.1);
            let f = Factors::new(vcm, radius, paths as f32);
            let shared = crate::render::iteration_wavelengths(scene, settings.seed, iteration);
            let it = Iteration {
                scene,
                s,
                vcm,
                f,
                radius,
                n: paths as f32,
                scale: scale as f32,
                chunks: &[],
                grid: None,
            };
            // Light subpath k: its vertices and camera splats appended; returns its wavelengths.
            let trace_light = |k: u64,
                               vertices: &mut Vec<LightVertex<'s>>,
                               built: &mut Vec<SurfaceBsdf>,
                               splats: &mut Vec<Splat>| {
                let lambda = wavelengths(scene, vcm, &shared, settings.seed, iteration, k);
                let index = u64::from(iteration) * paths + k;
                let mut sampler = Sampler::new(settings.seed, LIGHT_STREAM, index);
                // Dispatched per subpath: the hot routines are inlined into one function per
                // instruction set (`pt_render::isa`).
                pt_render::isa::best(
                    #[inline(always)]
                    || {
                        light_subpath(
                            scene,
                            s,
                            vcm,
                            &f,
                            scale as f32,
                            &mut sampler,
                            &lambda,
                            vertices,
                            built,
                            splats,
                        )
                    },
                );
                lambda
            };
            for c in pool.iter_mut() {
                c.vertices.clear();
                c.built.clear();
                c.ends.clear();
                c.splats.clear();
            }
            if !vcm.merging {
                // Each light subpath is needed by its own camera subpath only: both in turn.
                pool.par_iter_mut().enumerate().for_each(|(c, chunk)| {
                    let (mut own, mut own_built) = (Vec::new(), Vec::new());
                    for k in range(c as u64) {
                        own.clear();
                        own_built.clear();
                        let lambda = trace_light(k, &mut own, &mut own_built, &mut chunk.splats);
                        let index = u64::from(iteration) * paths + k;
                        let mut sampler = Sampler::new(settings.seed, CAMERA_STREAM, index);
                        chunk.splats.push(camera_sample(
                            &it,
                            &mut sampler,
                            &lambda,
                            k,
                            w,
                            (&own, &own_built),
                        ));
                    }
                    progress(range(c as u64).count() as u64);
                });
            } else {
                // 1. Every light subpath: vertices and t = 1 splats.
                pool.par_iter_mut().enumerate().for_each(|(c, chunk)| {
                    for k in range(c as u64) {
                        trace_light(k, &mut chunk.vertices, &mut chunk.built, &mut chunk.splats);
                        chunk.ends.push(chunk.vertices.len() as u32);
                    }
                    progress(range(c as u64).count() as u64 / 2);
                });
                // 2. The grid of all light vertices, then every camera subpath.
                let photons = pool.iter().flat_map(|c| &c.vertices);
                let grid = PointGrid::new(photons.map(LightVertex::photon).collect(), radius);
                let camera: Vec<Vec<Splat>> = {
                    let it = Iteration {
                        chunks: &pool,
                        grid: Some(grid),
                        ..it
                    };
                    (0..chunks)
                        .into_par_iter()
                        .map(|c| {
                            let mut out = Vec::with_capacity(CHUNK as usize);
                            for k in range(c) {
                                let lambda =
                                    wavelengths(scene, vcm, &shared, settings.seed, iteration, k);
                                let index = u64::from(iteration) * paths + k;
                                let mut sampler = Sampler::new(settings.seed, CAMERA_STREAM, index);
                                let own = it.subpath(k);
                                out.push(camera_sample(&it, &mut sampler, &lambda, k, w, own));
                            }
                            let n = range(c).count() as u64;
                            progress(n - n / 2);
                            out
                        })
                        .collect()
                };
                for (chunk, cam) in pool.iter_mut().zip(camera) {
                    chunk.splats.extend(cam);
                }
            }
            let lists: Vec<&[Splat]> = pool.iter().map(|c| c.splats.as_slice()).collect();
            add_batches(state, &lists, lists.len(), scale);
        },
    )
}

/// Whether `vcm`/`bdpt` can render `scene` with `settings`; the reason when it cannot.
pub fn check(
    scene: &Scene,
    settings: &crate::RenderSettings,
    vcm: &VcmSettings,
) -> Result<(), String> {
    let name = vcm.name();
    if !(vcm.alpha > 0.0 && vcm.alpha < 1.0) {
        return Err(format!(
            "{name}: alpha must lie in (0, 1), got {}",
            vcm.alpha
        ));
    }
    if let Some(r) = vcm.initial_radius {
        if !(r > 0.0 && r.is_finite()) {
            return Err(format!("{name}: initial_radius must be positive, got {r}"));
        }
    }
    if scene.camera.is_orthographic() {
        return Err(format!(
            "{}: {name}: an orthographic sensor is not yet supported (not yet implemented); use path or ptracer",
            scene.camera.loc()
        ));
    }
    crate::methods::refuse_meters(name, scene)?;
    crate::ptracer::check(settings).map_err(|e| e.replace("ptracer", name))
}

/// Renders the image by `vcm` (or `bdpt`), as [`crate::ptracer::render`] does by light
/// tracing. The caller checks with [`check`] first.
pub fn render(
    scene: &Scene,
    settings: &crate::RenderSettings,
    vcm: &VcmSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> pt_render::RenderOutput {
    let mut state = crate::RenderState::for_light_paths(settings);
    render_vcm_passes(
        scene,
        settings,
        vcm,
        &mut state,
        &AtomicBool::new(false),
        None,
        progress,
    );
    state.output()
}
