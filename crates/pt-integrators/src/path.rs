//! Unidirectional path tracing with next-event estimation and multiple importance sampling.
//!
//! Estimator: Veach 1997, ch. 9 and 10 (one light sample and one BSDF sample per vertex, each
//! weighted by the power heuristic, beta = 2). Path depth follows Mitsuba 3's `path` integrator:
//! `max_depth` counts path segments (1: emitters seen directly, 2: direct illumination, -1:
//! unlimited); Russian roulette starts once `rr_depth` segments have been traced, continuing with
//! probability min(max throughput, 0.95). Emitters are one-sided.

use pt_math::{offset_ray_origin, power_heuristic, Frame, Ray, Vec3};
use pt_render::geometry::Interaction;
use pt_render::light::LightSample;
use pt_render::sampler::Sampler;
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
    /// Attenuate rays inside shapes with an interior medium (Mitsuba `volpath`); `path` ignores
    /// media, as Mitsuba's does.
    pub media: bool,
}

impl Default for PathSettings {
    fn default() -> Self {
        PathSettings {
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
            strategy: Strategy::Mis,
            media: false,
        }
    }
}

/// Shadow rays stop this fraction short of the light point, whose origin is already offset: a
/// relative guard against rounding at the far end, not an absolute epsilon.
const SHADOW_RAY_SHORTEN: f32 = 1.0 - 1e-5;

/// Radiance arriving along `ray` (the camera ray), estimated with one path, at the path's
/// wavelengths `lambda` (spectral mode; ignored in RGB mode, whose lanes are R, G, B).
///
/// The same computation as [`trace_paths`] for one path (which is how it is done).
#[inline(always)]
pub fn li(
    scene: &Scene,
    ray: Ray,
    s: &PathSettings,
    sampler: &mut Sampler,
    lambda: &SampledWavelengths,
) -> SampledSpectrum {
    let mut first = Some(PathStart {
        path: PathState::new(scene, ray, lambda),
        sampler: sampler.clone(),
        lambda: *lambda,
        tag: 0,
    });
    let mut radiance = SampledSpectrum::ZERO;
    trace_paths(
        scene,
        s,
        || first.take(),
        |done| {
            radiance = done.path.radiance;
            *sampler = done.sampler.clone();
        },
    );
    radiance
}

/// A path as [`trace_paths`] takes it and hands it back: the path, its random numbers, the
/// wavelengths it started with (fluorescence may change the path's own) and a tag of the
/// caller's choosing (which sample it is).
pub struct PathStart {
    /// The path (when handed back, finished: its `radiance` is the estimate).
    pub path: PathState,
    /// The path's random number stream.
    pub sampler: Sampler,
    /// The wavelengths the path started with.
    pub lambda: SampledWavelengths,
    /// The caller's label.
    pub tag: u32,
}

/// One path in flight: what the path loop carries from one segment to the next.
#[derive(Clone, Copy)]
pub struct PathState {
    /// The next segment to trace (world space).
    ray: Ray,
    /// The path's wavelengths (lanes may change at fluorescent vertices).
    lambda: SampledWavelengths,
    /// Radiance gathered so far.
    pub radiance: SampledSpectrum,
    /// Product of the sample weights so far.
    throughput: SampledSpectrum,
    /// The previous scattering event, for MIS on emitters hit by BSDF sampling.
    prev_p: Vec3,
    prev_pdf: f32,
    prev_delta: bool,
    /// Segments traced so far.
    depth: u32,
    /// Product of the relative indices of refraction crossed so far: radiance carries 1/eta^2
    /// per refraction, which Russian roulette undoes when judging the path's worth (Mitsuba).
    eta_scale: f32,
    /// Whether the path goes on (`ray` is its next segment).
    alive: bool,
    /// A light sample's shadow ray waiting for its visibility test, and what it adds to
    /// `radiance` if nothing blocks it.
    shadow: Option<(Ray, SampledSpectrum)>,
}

impl PathState {
    /// A path starting with the camera ray `ray` at wavelengths `lambda`.
    #[inline(always)]
    pub fn new(scene: &Scene, ray: Ray, lambda: &SampledWavelengths) -> Self {
        let throughput = match scene.mode {
            ColorMode::Rgb => SampledSpectrum::from_rgb([1.0; 3]),
            ColorMode::Spectral => SampledSpectrum::splat(1.0),
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
            shadow: None,
        }
    }
}

/// Most paths [`trace_paths`] keeps in flight at once.
pub const MAX_PATHS: usize = 8;

/// Traces the paths that `start` gives until it gives `None`, and hands each finished path to
/// `finish`, in the order they finish (not the order they started).
///
/// Up to [`MAX_PATHS`] paths are in flight, and a path that ends makes room for the next at
/// once. The paths advance together, one segment at a time, in two passes over them: the
/// shadow rays left by the previous scattering and the closest hits of the new segments, then
/// the scattering at each hit (emission, light sample, BSDF sample, Russian roulette). The
/// queries of one pass do not depend on each other, so the processor overlaps them, where one
/// path alone is a chain of dependent steps. Each path draws its random
/// numbers and adds its terms in the same order as it would alone, so each result is
/// bit-identical to tracing the path alone.
#[inline(always)]
pub fn trace_paths(
    scene: &Scene,
    s: &PathSettings,
    mut start: impl FnMut() -> Option<PathStart>,
    mut finish: impl FnMut(&PathStart),
) {
    let mut slots: [Option<PathStart>; MAX_PATHS] = [const { None }; MAX_PATHS];
    for slot in slots.iter_mut() {
        *slot = start();
    }
    let mut hits: [Option<Interaction>; MAX_PATHS] = [None; MAX_PATHS];
    loop {
        // The previous scattering's shadow rays; finished paths out and new ones in; the new
        // segments' closest hits. The queries do not depend on each other.
        let mut any = false;
        for (slot, hit) in slots.iter_mut().zip(hits.iter_mut()) {
            if let Some(sl) = slot {
                if let Some((ray, contribution)) = sl.path.shadow.take() {
                    if !scene.occluded(&ray) {
                        sl.path.radiance += contribution;
                    }
                }
                if !sl.path.alive {
                    finish(sl);
                    *slot = start();
                }
            }
            if let Some(sl) = slot {
                *hit = scene.intersect(&sl.path.ray);
                any = true;
            }
        }
        if !any {
            break;
        }
        for (slot, hit) in slots.iter_mut().zip(&hits) {
            let Some(PathStart { path, sampler, .. }) = slot else {
                continue;
            };
            if !arrive(scene, s, path, hit) {
                continue;
            }
            if let Some(hit) = hit {
                scatter_at(scene, s, path, hit, sampler);
            }
        }
    }
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
    let max_depth = if s.max_depth < 0 {
        u32::MAX
    } else {
        s.max_depth as u32
    };
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
        ..
    } = path;
    let (depth_now, prev_delta_now, prev_pdf_now) = (*depth, *prev_delta, *prev_pdf);
    let Some(hit) = hit else {
        // The ray left the scene: environment and sun.
        for &i in &scene.infinite_lights {
            let light = &scene.lights[i];
            let le = light.escaped_radiance(ray.dir, lambda);
            if !le.is_black() {
                let w = emission_weight(s, depth_now, prev_delta_now, prev_pdf_now, || {
                    scene.light_pmf(i) * light.escaped_pdf(ray.dir)
                });
                *radiance += *throughput * le * w;
            }
        }
        *alive = false;
        return false;
    };
    let wo_world = -ray.dir;

    // Beer-Lambert: a ray that reaches a shape's surface from behind travelled inside it, so
    // it crossed the shape's interior medium over the distance hit.t (the ray's direction is a
    // unit vector). Multiplying by the transmittance exp(-sigma_t t) is the expected value of
    // Mitsuba volpath's free-flight sampling for albedo 0, without its variance.
    if s.media && ray.dir.dot(hit.ng) > 0.0 {
        if let Some(tr) = scene.interior_transmittance(hit.shape, hit.t, lambda) {
            *throughput *= tr;
            if throughput.is_black() {
                *alive = false;
                return false;
            }
        }
    }

    // Emission found by the ray just traced.
    if let Some((li_idx, light)) = scene.shape_light(hit.shape) {
        let le = light.emitted(hit.ns, wo_world, hit.uv, lambda);
        if !le.is_black() {
            let prev = *prev_p;
            let w = emission_weight(s, depth_now, prev_delta_now, prev_pdf_now, || {
                scene.light_pmf(li_idx) * light.pdf(prev, hit.p, hit.ns)
            });
            *radiance += *throughput * le * w;
        }
    }

    // Mitsuba: continue only if another segment fits within max_depth.
    if depth.saturating_add(1) >= max_depth {
        *alive = false;
        return false;
    }
    true
}

/// The scattering of a path at `hit` (after [`arrive`]): the light sample, whose shadow ray it
/// leaves in `path.shadow`, the BSDF sample that makes the next segment, and Russian roulette.
/// Ends the path (`alive = false`) where Mitsuba's `path` integrator stops.
#[inline(always)]
fn scatter_at(
    scene: &Scene,
    s: &PathSettings,
    path: &mut PathState,
    hit: &Interaction,
    sampler: &mut Sampler,
) {
    let use_light = s.strategy != Strategy::Bsdf;
    let PathState {
        ray,
        lambda,
        throughput,
        prev_p,
        prev_pdf,
        prev_delta,
        depth,
        eta_scale,
        alive,
        shadow,
        ..
    } = path;
    let wo_world = -ray.dir;
    let bsdf = scene.bsdf(hit, lambda);
    // Fluorescence: the BSDF holds each lane's total albedo at its emitted wavelength; now
    // some lanes move to an excitation wavelength, used by NEE and the rest of the path.
    if scene.material(hit.shape).fluorescent().is_some() {
        if let Some(l) = scene.fluoresce(hit.shape, lambda, sampler.next_1d()) {
            *lambda = l;
        }
    }
    let frame = Frame::from_normal_tangent(hit.ns, hit.dpdu);
    let wo = frame.to_local(wo_world);

    // Rays leave the hit offset to one side of the surface; the shadow ray and the next
    // segment of a reflection leave on the side the path came from.
    let spawn = SpawnPoint::new(hit, ray.dir);

    // Next-event estimation: the light sample's contribution, added once its shadow ray is
    // found unblocked.
    if use_light && bsdf.has_smooth_lobe() {
        if let Some((li_idx, pmf, u_sel)) = scene.sample_light(sampler.next_1d()) {
            let u = sampler.next_2d();
            let light = &scene.lights[li_idx];
            if let Some(ls) = light.sample(hit.p, u_sel, u, lambda) {
                let wi = frame.to_local(ls.wi);
                let f = bsdf.eval(wo, wi);
                if !ls.radiance.is_black() && !f.is_black() {
                    if let Some(shadow_ray) = shadow_ray(spawn.origin(ls.wi), &ls) {
                        let light_pdf = pmf * ls.pdf;
                        // Delta lights cannot be hit by BSDF sampling: light sampling is the
                        // only strategy, weight 1.
                        let w = if s.strategy != Strategy::Light && !ls.delta {
                            power_heuristic(light_pdf, bsdf.pdf(wo, wi))
                        } else {
                            1.0
                        };
                        *shadow = Some((
                            shadow_ray,
                            *throughput
                                * f
                                * ls.radiance
                                * (wi.z.abs() * w / light_pdf),
                        ));
                    }
                }
            }
        } else {
            // Keep the random number sequence aligned whether or not there are lights.
            let _ = sampler.next_2d();
        }
    }

    // BSDF sampling.
    let u_lobe = sampler.next_1d();
    let Some(bs) = bsdf.sample(wo, u_lobe, sampler.next_2d()) else {
        *alive = false;
        return;
    };
    if bs.weight.is_black() {
        *alive = false;
        return;
    }
    *throughput *= bs.weight;
    *eta_scale *= bs.eta;
    let wi_world = frame.to_world(bs.wi);
    *prev_p = hit.p;
    *prev_pdf = bs.pdf;
    *prev_delta = bs.delta;
    *ray = Ray::new(spawn.origin(wi_world), wi_world);
    *depth += 1;

    // Russian roulette (Mitsuba: after rr_depth segments, keep with probability
    // min(max(T) eta^2, 0.95)).
    if *depth >= s.rr_depth {
        let q = (throughput.max_value() * *eta_scale * *eta_scale).min(0.95);
        if !(sampler.next_1d() < q) {
            *alive = false;
            return;
        }
        *throughput *= 1.0 / q;
    }
}

/// Origins of rays leaving a hit: the hit point offset off its surface (Wächter & Binder 2019,
/// see [`offset_ray_origin`]) to the side a ray's direction points to. The side the path
/// arrived from is computed once, since the shadow ray and the next segment of a reflection
/// both leave there.
struct SpawnPoint {
    /// Hit point, world space.
    p: Vec3,
    /// Unit geometric normal flipped to the side the path arrived from, world space.
    n_out: Vec3,
    /// `p` offset towards `n_out`.
    out: Vec3,
}

impl SpawnPoint {
    /// Spawn point of `hit`, reached by a ray travelling in direction `ray_dir` (world space).
    #[inline(always)]
    fn new(hit: &Interaction, ray_dir: Vec3) -> Self {
        let n_out = hit.ng * -hit.ng.dot(ray_dir).signum();
        SpawnPoint {
            p: hit.p,
            n_out,
            out: offset_ray_origin(hit.p, n_out),
        }
    }

    /// Origin for a ray leaving in direction `dir` (world space).
    #[inline(always)]
    fn origin(&self, dir: Vec3) -> Vec3 {
        if self.n_out.dot(dir) >= 0.0 {
            self.out
        } else {
            offset_ray_origin(self.p, -self.n_out)
        }
    }
}

/// The shadow ray from `origin` (the hit, offset off its surface towards the light) to the
/// light sample, whose end is offset off its surface too (a light without a surface normal, or
/// a distant one, needs no offset there); `None` when the two points coincide (nothing can be
/// seen).
#[inline(always)]
fn shadow_ray(origin: Vec3, ls: &LightSample) -> Option<Ray> {
    if ls.dist.is_infinite() {
        return Some(Ray::new(origin, ls.wi));
    }
    let target = if ls.n == pt_math::Vec3::ZERO {
        ls.p
    } else {
        offset_ray_origin(ls.p, ls.n * ls.n.dot(-ls.wi).signum())
    };
    let seg = target - origin;
    let dist = seg.length();
    if !(dist > 0.0) {
        return None;
    }
    Some(Ray {
        origin,
        dir: seg / dist,
        tmin: 0.0,
        tmax: dist * SHADOW_RAY_SHORTEN,
    })
}

/// Weight of emission that the traced ray found (an emitter hit or an escaped ray), given the
/// solid-angle pdf with which light sampling would have chosen the same direction (computed
/// only when needed). Seen directly from the camera: 1, or 0 with `hide_emitters`. After a
/// delta bounce: 1 (light sampling cannot produce it). Otherwise the power heuristic against
/// light sampling under MIS, 1 with BSDF sampling alone, and 0 with light sampling alone (NEE
/// already counted it).
#[inline]
fn emission_weight(
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
