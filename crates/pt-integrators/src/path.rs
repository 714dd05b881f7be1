//! Unidirectional path tracing with next-event estimation and multiple importance sampling.
//!
//! Estimator: Veach 1997, ch. 9 and 10 (one light sample and one BSDF sample per vertex, each
//! weighted by the power heuristic, beta = 2). Path depth follows Mitsuba 3's `path` integrator:
//! `max_depth` counts path segments (1: emitters seen directly, 2: direct illumination, -1:
//! unlimited); Russian roulette starts once `rr_depth` segments have been traced, continuing with
//! probability min(max throughput, 0.95). Emitters are one-sided.

use crate::direct::ShadingSamples;
use pt_math::{power_heuristic, Ray, Vec3};
use pt_render::geometry::Interaction;
use pt_render::sampler::RandomSource;
use pt_render::Scene;
use pt_spectrum::{ColorMode, SampledSpectrum, SampledWavelengths};

/// Which strategies estimate direct light (for method comparisons; MIS is the default).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Strategy {
    /// Light sampling and BSDF sampling combined with the power heuristic.
    #[default]
    Mis,
    /// Only BSDF sampling (emitters found by hitting them).
    Bsdf,
    /// Only light sampling (emitters hit by BSDF-sampled rays contribute nothing, except when seen
    /// directly from the camera or after a delta bounce).
    Light,
}

/// Integrator settings (Mitsuba semantics).
#[derive(Clone, Copy, Debug)]
pub struct PathSettings {
    /// Longest path in segments; -1 = unlimited.
    pub max_depth: i32,
    /// Segments after which Russian roulette starts.
    pub rr_depth: u32,
    /// Hide directly visible emitters.
    pub hide_emitters: bool,
    /// Direct-light strategy.
    pub strategy: Strategy,
    /// Trace participating media (Mitsuba `volpath`, [`crate::volpath`]); `path` ignores
    /// media, as Mitsuba's does.
    pub media: bool,
    /// When a sample covers its pixel (its alpha) and what an uncovered sample returns.
    pub coverage: Coverage,
    /// Mitsuba's `direct`: the camera ray's hit is shaded with these numbers of light and BSDF
    /// samples ([`crate::direct`]) instead of tracing a path; `max_depth`, `rr_depth`,
    /// `strategy` and `media` do not apply then.
    pub direct: Option<ShadingSamples>,
}

impl PathSettings {
    /// `max_depth` as a count of segments: `u32::MAX` when unlimited (-1).
    #[inline]
    pub fn depth_limit(&self) -> u32 {
        u32::try_from(self.max_depth).unwrap_or(u32::MAX)
    }

    /// The settings a scene's `<integrator>` gives (for `radiosity` scenes, the path tracer's
    /// with its `max_depth`).
    pub fn from_desc(i: &pt_scene::IntegratorDesc) -> Self {
        use pt_scene::IntegratorKind as K;
        PathSettings {
            max_depth: i.max_depth,
            rr_depth: i.rr_depth,
            hide_emitters: i.hide_emitters,
            strategy: if i.light_sampling {
                Strategy::Mis
            } else {
                Strategy::Bsdf
            },
            media: i.kind == K::VolPath,
            coverage: Coverage::of(i.kind),
            direct: match i.kind {
                K::Direct {
                    emitter_samples,
                    bsdf_samples,
                } => Some(ShadingSamples {
                    emitter: emitter_samples,
                    bsdf: bsdf_samples,
                }),
                _ => None,
            },
        }
    }
}

/// When a path covers its pixel (the pixel's alpha, [`PathState::covered`]) and what a path
/// that does not returns: Mitsuba 3.9.1's integrators differ, and these are their rules as
/// measured on it (`llvm_ad_rgb`; a mask of opacity 0.5 over nothing, lit by a point light).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Coverage {
    /// Mitsuba's `path`: a path covers its pixel when it scatters at a surface by anything but
    /// a straight pass-through (Mitsuba's null lobes), or when `max_depth` ends it at a hit.
    /// An uncovered sample returns radiance 0: light gathered at pass-through vertices of a
    /// path that then leaves the scene is dropped (Mitsuba's `path` renders a half-transparent
    /// mask over nothing at opacity^2 of its lit brightness, `volpath` and `direct` at opacity).
    #[default]
    Path,
    /// Mitsuba's `volpath`: covered as `Path`; the radiance is kept.
    VolPath,
    /// Mitsuba's `direct`: a camera ray that hits any surface covers its pixel.
    AnyHit,
}

impl Coverage {
    /// The rule of a scene's integrator.
    pub fn of(kind: pt_scene::IntegratorKind) -> Coverage {
        match kind {
            pt_scene::IntegratorKind::Direct { .. } | pt_scene::IntegratorKind::Depth => {
                Coverage::AnyHit
            }
            pt_scene::IntegratorKind::VolPath => Coverage::VolPath,
            pt_scene::IntegratorKind::Path
            | pt_scene::IntegratorKind::Radiosity
            | pt_scene::IntegratorKind::PTracer { .. }
            | pt_scene::IntegratorKind::Sppm { .. }
            | pt_scene::IntegratorKind::Bdpt
            | pt_scene::IntegratorKind::PhotonMapper { .. }
            | pt_scene::IntegratorKind::Vcm { .. } => Coverage::Path,
        }
    }
}

impl Default for PathSettings {
    fn default() -> Self {
        PathSettings {
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
            strategy: Strategy::Mis,
            media: false,
            coverage: Coverage::Path,
            direct: None,
        }
    }
}

/// Radiance arriving along `ray` (the camera ray), estimated with one path, at the path's
/// wavelengths `lambda` (spectral mode; ignored in RGB mode, whose lanes are R, G, B).
///
/// The same computation as [`trace_paths`] for one path (which is how it is done).
#[inline(always)]
pub fn li<S: RandomSource>(
    scene: &Scene,
    ray: Ray,
    s: &PathSettings,
    sampler: &mut S,
    lambda: &SampledWavelengths,
) -> SampledSpectrum {
    trace_one(
        scene,
        s,
        PathState::new(scene, ray, lambda),
        sampler,
        lambda,
    )
}

/// Traces the one path `path` (drawing from `sampler`, which it leaves where the path ended)
/// and returns its estimate.
#[inline(always)]
fn trace_one<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    path: PathState,
    sampler: &mut S,
    lambda: &SampledWavelengths,
) -> SampledSpectrum {
    /// The one path, and where its result goes.
    struct One<'a, S> {
        first: Option<PathStart<S>>,
        radiance: SampledSpectrum,
        sampler: &'a mut S,
    }
    impl<S: RandomSource> PathQueue<S> for One<'_, S> {
        #[inline(always)]
        fn start(&mut self, slot: &mut Option<PathStart<S>>) {
            *slot = self.first.take();
        }
        #[inline(always)]
        fn finish(&mut self, done: &PathStart<S>) {
            self.radiance = done.path.radiance;
            *self.sampler = done.sampler.clone();
        }
    }
    let mut one = One {
        first: Some(PathStart {
            path,
            sampler: sampler.clone(),
            lambda: *lambda,
            tag: 0,
        }),
        radiance: SampledSpectrum::ZERO,
        sampler,
    };
    trace_paths(scene, s, &mut one);
    one.radiance
}

/// Radiance arriving along `ray` through at least one fluorescent surface (where the path
/// scatters at a fluorescent material, whichever lane choices it makes there), estimated
/// with one path of the path tracer continuing a camera path: `throughput` is the camera
/// path's weight up to `ray` and `segments` the number of segments before it.
///
/// The bidirectional and photon-based methods take such paths from the camera side alone:
/// a light subpath that changed wavelengths at a fluorescent surface cannot be joined to a
/// camera subpath at the film's wavelengths (the two would have to agree on a continuous
/// wavelength: an event of probability zero), so their light subpaths end where they meet a
/// fluorescent surface and the paths through one are left to the path tracer's strategies,
/// light sampling and BSDF sampling under its MIS, with fluorescence as the camera paths do
/// it (`pt_render::fluorescence`). The split is a partition of path space: each path is
/// estimated by one of the two sides.
pub(crate) fn li_through_fluorescence<S: RandomSource>(
    scene: &Scene,
    ray: Ray,
    throughput: SampledSpectrum,
    segments: u32,
    s: &PathSettings,
    sampler: &mut S,
    lambda: &SampledWavelengths,
) -> SampledSpectrum {
    let mut path = PathState::new(scene, ray, lambda);
    path.throughput = throughput;
    path.depth = segments;
    path.awaits_fluorescence = true;
    trace_one(scene, s, path, sampler, lambda)
}

/// The camera side's share of fluorescence for the photon methods' camera paths:
/// [`li_through_fluorescence`] along `ray` (with the path's throughput and the segments before
/// it) the first time it is called on a path, while `*counted` is false; then 0. Called at the
/// first hit, it counts every path through a fluorescent surface once.
pub(crate) fn fluorescence_once<S: RandomSource>(
    scene: &Scene,
    (ray, throughput, segments): (Ray, SampledSpectrum, u32),
    s: &PathSettings,
    sampler: &mut S,
    lambda: &SampledWavelengths,
    counted: &mut bool,
) -> SampledSpectrum {
    if *counted {
        return SampledSpectrum::ZERO;
    }
    *counted = true;
    li_through_fluorescence(scene, ray, throughput, segments, s, sampler, lambda)
}

/// A path as [`trace_paths`] takes it and hands it back: the path, its random numbers, the
/// wavelengths it started with (fluorescence may change the path's own) and a tag of the
/// caller's choosing (which sample it is).
pub struct PathStart<S = pt_render::sampler::Sampler> {
    /// The path (when handed back, finished: its `radiance` is the estimate).
    pub path: PathState,
    /// The path's random number stream.
    pub sampler: S,
    /// The wavelengths the path started with.
    pub lambda: SampledWavelengths,
    /// The caller's label.
    pub tag: u32,
}

/// One path in flight: what the path loop carries from one segment to the next.
#[derive(Clone, Copy)]
pub struct PathState {
    /// The next segment to trace (world space).
    pub(crate) ray: Ray,
    /// The path's wavelengths (lanes may change at fluorescent vertices).
    pub(crate) lambda: SampledWavelengths,
    /// Radiance gathered so far.
    pub radiance: SampledSpectrum,
    /// Product of the sample weights so far.
    pub(crate) throughput: SampledSpectrum,
    /// The previous scattering event, for MIS on emitters hit by BSDF sampling.
    pub(crate) prev_p: Vec3,
    pub(crate) prev_pdf: f32,
    pub(crate) prev_delta: bool,
    /// Segments traced so far.
    pub(crate) depth: u32,
    /// Product of the relative indices of refraction crossed so far: radiance carries 1/eta^2
    /// per refraction, which Russian roulette undoes when judging the path's worth (Mitsuba).
    pub(crate) eta_scale: f32,
    /// Whether the path goes on (`ray` is its next segment).
    pub(crate) alive: bool,
    /// Whether the path met the scene, for the pixel's alpha (Mitsuba's `valid_ray`, measured
    /// on Mitsuba 3.9.1's `llvm_ad_rgb`): set at a hit where the path scatters unless the
    /// sampled event is a straight pass-through (Mitsuba's null lobes: a `mask`'s holes, a
    /// thin sheet's transmission), at a hit where `max_depth` ends the path, and at any hit
    /// with [`Coverage::AnyHit`]. A visible environment light covers every path (set when the
    /// path is handed back by [`trace_paths`]).
    pub covered: bool,
    /// A light sample's shadow ray waiting for its visibility test, and what it adds to
    /// `radiance` if nothing blocks it.
    pub(crate) shadow: Option<(Ray, SampledSpectrum)>,
    /// Whether the path counts only light that reaches it through a fluorescent surface (see
    /// [`li_through_fluorescence`]): its radiance is dropped when it first scatters at one
    /// (the flag then clears), and at its end if it never did.
    pub(crate) awaits_fluorescence: bool,
}

impl PathState {
    /// A path starting with the camera ray `ray` at wavelengths `lambda`.
    #[inline(always)]
    pub fn new(scene: &Scene, ray: Ray, lambda: &SampledWavelengths) -> Self {
        // The camera's weight of its ray (pi for an irradiancemeter, otherwise 1).
        let w = scene.camera.ray_weight();
        let throughput = match scene.mode {
            ColorMode::Rgb => SampledSpectrum::from_rgb([w; 3]),
            ColorMode::Spectral => SampledSpectrum::splat(w),
        };
        PathState {
            ray,
            lambda: *lambda,
            radiance: SampledSpectrum::ZERO,
            throughput,
            prev_p: ray.origin,
            prev_pdf: 0.0,
            // The camera acts like a delta event: no MIS on directly seen lights.
            prev_delta: true,
            depth: 0,
            eta_scale: 1.0,
            alive: true,
            covered: false,
            shadow: None,
            awaits_fluorescence: false,
        }
    }
}

/// Most paths [`trace_paths`] keeps in flight at once: as many as the scene traces rays
/// together.
pub const MAX_PATHS: usize = pt_render::accel::BATCH;

/// Where [`trace_paths`] takes its paths from and hands them back to. A trait rather than two
/// closures: its methods are inlined into the path loop (`#[inline(always)]` on the
/// implementations), and so compiled for the render loop's instruction sets, where an outlined
/// closure is compiled for the baseline (the camera ray, the sampler's set-up and the film
/// sample took 16% of a tent-filtered render's time there).
pub trait PathQueue<S> {
    /// Writes the next path into `slot`, or `None` when there are no more. Into the slot
    /// itself, not returned: a returned path came back through a temporary whose copy stalled
    /// on the stores that built it (1.7% of the Cornell box's profile samples).
    fn start(&mut self, slot: &mut Option<PathStart<S>>);
    /// Takes a finished path.
    fn finish(&mut self, done: &PathStart<S>);
}

/// Traces the paths that `queue` starts until it gives `None`, and hands each finished path
/// back to it, in the order they finish (not the order they started).
///
/// Up to [`MAX_PATHS`] paths are in flight, and a path that ends makes room for the next at
/// once. The paths advance together, one segment at a time, in two passes over them: the
/// shadow rays left by the previous scattering and the closest hits of the new segments, then
/// the emission each new segment finds and the scattering at every hit, for all paths at once
/// (light sample, BSDF sample, Russian roulette; `scatter.rs`). The queries of one pass do not
/// depend on each other, so the processor overlaps them, where one path alone is a chain of
/// dependent steps. Each path draws its random
/// numbers and adds its terms in the same order as it would alone, so each result is
/// bit-identical to tracing the path alone.
#[inline(always)]
pub fn trace_paths<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    queue: &mut impl PathQueue<S>,
) {
    if crate::volpath::applies(scene, s) {
        // Media: one path at a time through `volpath.rs`.
        while let Some(mut sl) = next(queue) {
            crate::volpath::estimate_best(scene, s, &mut sl.path, &mut sl.sampler);
            queue.finish(&sl);
        }
        return;
    }
    if let Some(counts) = s.direct {
        // Mitsuba's `direct` shades one hit per camera ray: nothing to keep in flight.
        while let Some(mut sl) = next(queue) {
            crate::direct::estimate(scene, s, counts, &mut sl.path, &mut sl.sampler);
            queue.finish(&sl);
        }
        return;
    }
    let mut slots: [Option<PathStart<S>>; MAX_PATHS] = [const { None }; MAX_PATHS];
    for slot in slots.iter_mut() {
        queue.start(slot);
    }
    let mut hits: [Option<Interaction>; MAX_PATHS] = [None; MAX_PATHS];
    // A visible environment light covers every pixel (Mitsuba's alpha).
    let environment_seen = !scene.infinite_lights.is_empty() && !s.hide_emitters;
    // The rays of one pass (a lane per slot), traced together: the queries do not depend on
    // each other (`Scene::intersect_batch`: in SIMD lanes through a tiny scene's primitives,
    // one after the other on one traversal stack through a tree).
    let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); MAX_PATHS];
    loop {
        // The previous scattering's shadow rays.
        let mut shadowed: pt_math::lanes::Mask = 0;
        for (k, slot) in slots.iter().enumerate() {
            if let Some((ray, _)) = slot.as_ref().and_then(|sl| sl.path.shadow.as_ref()) {
                rays[k] = *ray;
                shadowed |= 1 << k;
            }
        }
        let blocked = if shadowed != 0 {
            scene.occluded_batch(&rays, shadowed)
        } else {
            0
        };
        // Finished paths out and new ones in; the new segments' closest hits.
        let mut tracing: pt_math::lanes::Mask = 0;
        for (k, slot) in slots.iter_mut().enumerate() {
            if let Some(sl) = slot {
                if let Some((_, contribution)) = sl.path.shadow.take() {
                    if blocked >> k & 1 == 0 {
                        sl.path.radiance += contribution;
                    }
                }
                if !sl.path.alive {
                    sl.path.covered |= environment_seen;
                    if sl.path.awaits_fluorescence
                        || !sl.path.covered && s.coverage == Coverage::Path
                    {
                        sl.path.radiance = SampledSpectrum::ZERO;
                    }
                    queue.finish(sl);
                    queue.start(slot);
                }
            }
            if let Some(sl) = slot {
                rays[k] = sl.path.ray;
                tracing |= 1 << k;
            }
        }
        if tracing == 0 {
            break;
        }
        scene.intersect_batch(&rays, tracing, &mut hits);
        // Emission found by the new segments; the paths that go on scatter together.
        let mut todo: pt_math::lanes::Mask = 0;
        for (k, (slot, hit)) in slots.iter_mut().zip(&hits).enumerate() {
            if let Some(PathStart { path, .. }) = slot {
                todo |= u32::from(arrive(scene, s, path, hit) && hit.is_some()) << k;
            }
        }
        if todo != 0 {
            crate::scatter::scatter(scene, s, &mut slots, &hits, todo);
        }
    }
}

/// The next path `queue` starts (see [`trace_paths`]).
#[inline(always)]
fn next<S>(queue: &mut impl PathQueue<S>) -> Option<PathStart<S>> {
    let mut slot = None;
    queue.start(&mut slot);
    slot
}

/// What a path does with the result `hit` of tracing its segment before it scatters there:
/// emission from an escaped ray or a hit emitter. Returns whether it scatters at `hit` (see
/// [`scatter_at`]); otherwise the path has ended (`alive = false`) where Mitsuba's `path`
/// integrator stops.
#[inline(always)]
fn arrive(
    scene: &Scene,
    s: &PathSettings,
    path: &mut PathState,
    hit: &Option<Interaction>,
) -> bool {
    let max_depth = s.depth_limit();
    let PathState {
        ray,
        lambda,
        radiance,
        throughput,
        prev_p,
        prev_pdf,
        prev_delta,
        depth,
        alive,
        covered,
        ..
    } = path;
    let (depth_now, prev_delta_now, prev_pdf_now) = (*depth, *prev_delta, *prev_pdf);
    let prev = *prev_p;
    let Some(hit) = hit else {
        // The ray left the scene: environment and sun.
        *radiance += escaped_radiance(
            scene,
            ray.dir,
            lambda,
            *throughput,
            #[cfg_attr(not(debug_assertions), inline(always))]
            |i| {
                emission_weight(
                    s,
                    depth_now,
                    prev_delta_now,
                    prev_pdf_now,
                    #[cfg_attr(not(debug_assertions), inline(always))]
                    || scene.light_pmf_at(prev, i) * scene.lights[i].escaped_pdf(ray.dir),
                )
            },
        );
        *alive = false;
        return false;
    };
    let wo_world = -ray.dir;
    if s.coverage == Coverage::AnyHit {
        *covered = true;
    }

    // Emission found by the ray just traced (written out here rather than through
    // `emitted_radiance`: the call cost 1.4% of the Cornell box's instructions).
    if let Some((li_idx, light)) = scene.shape_light(hit.shape) {
        let le = light.emitted(hit.ns, wo_world, hit.uv, lambda);
        if !le.is_black() {
            let w = emission_weight(s, depth_now, prev_delta_now, prev_pdf_now, || {
                scene.light_pmf_at(prev, li_idx) * light.pdf(prev, hit.p, hit.ns)
            });
            *radiance += *throughput * le * w;
        }
    }

    // Mitsuba: continue only if another segment fits within max_depth.
    if depth.saturating_add(1) >= max_depth {
        *covered = true;
        *alive = false;
        return false;
    }
    true
}

/// Radiance the environment and sun send along `dir` (a ray that left the scene), summed over
/// those lights as `scale * radiance * weight(light index)`; the weight (its MIS weight) is
/// asked only of lights that send some. The one implementation for the path tracer and
/// `direct`.
#[inline(always)]
pub(crate) fn escaped_radiance(
    scene: &Scene,
    dir: Vec3,
    lambda: &SampledWavelengths,
    scale: SampledSpectrum,
    mut weight: impl FnMut(usize) -> f32,
) -> SampledSpectrum {
    let mut sum = SampledSpectrum::ZERO;
    for &i in &scene.infinite_lights {
        let le = scene.lights[i].escaped_radiance(dir, lambda);
        if !le.is_black() {
            sum += scale * le * weight(i);
        }
    }
    sum
}

/// Radiance the area light of `hit`'s shape (if any) sends towards `wo` (world space), as
/// `scale * radiance * weight(pdf)`, where [`HitLightPdf::from`] gives the density with which
/// light sampling picks `hit`, for the weight to evaluate if it needs it; `None` if it sends
/// nothing (most hits: the caller adds nothing then). Used by `direct`; the path tracer's
/// `arrive` writes the same steps out (see there).
#[inline(always)]
pub(crate) fn emitted_radiance(
    scene: &Scene,
    hit: &Interaction,
    wo: Vec3,
    lambda: &SampledWavelengths,
    scale: SampledSpectrum,
    weight: impl FnOnce(HitLightPdf<'_>) -> f32,
) -> Option<SampledSpectrum> {
    let (index, light) = scene.shape_light(hit.shape)?;
    let le = light.emitted(hit.ns, wo, hit.uv, lambda);
    if le.is_black() {
        return None;
    }
    Some(
        scale
            * le
            * weight(HitLightPdf {
                scene,
                index,
                light,
                hit,
            }),
    )
}

/// The light sampling density of an emitter hit, computed on demand (MIS needs it, other
/// weights do not).
pub(crate) struct HitLightPdf<'a> {
    scene: &'a Scene,
    index: usize,
    light: &'a pt_render::light::AreaLight,
    hit: &'a Interaction,
}

impl HitLightPdf<'_> {
    /// The solid-angle density, light selection included, with which light sampling from the
    /// point `x` (world space) picks the hit point.
    #[inline(always)]
    pub(crate) fn from(&self, x: Vec3) -> f32 {
        self.scene.light_pmf_at(x, self.index) * self.light.pdf(x, self.hit.p, self.hit.ns)
    }
}

/// Weight of emission that the traced ray found (an emitter hit or an escaped ray), given the
/// solid-angle pdf with which light sampling would have chosen the same direction (computed
/// only when needed). Seen directly from the camera: 1, or 0 with `hide_emitters`. After a
/// delta bounce: 1 (light sampling cannot produce it). Otherwise the power heuristic against
/// light sampling under MIS, 1 with BSDF sampling alone, and 0 with light sampling alone (NEE
/// already counted it).
#[cfg_attr(debug_assertions, inline)]
#[cfg_attr(not(debug_assertions), inline(always))]
pub(crate) fn emission_weight(
    s: &PathSettings,
    depth: u32,
    prev_delta: bool,
    prev_pdf: f32,
    light_pdf: impl FnOnce() -> f32,
) -> f32 {
    if depth == 0 {
        return if s.hide_emitters { 0.0 } else { 1.0 };
    }
    if prev_delta {
        return 1.0;
    }
    match s.strategy {
        Strategy::Mis => power_heuristic(prev_pdf, light_pdf()),
        Strategy::Bsdf => 1.0,
        Strategy::Light => 0.0,
    }
}
