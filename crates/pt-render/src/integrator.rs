//! Unidirectional path tracing with next-event estimation and multiple importance sampling.
//!
//! Estimator: Veach 1997, ch. 9 and 10 (one light sample and one BSDF sample per vertex, each
//! weighted by the power heuristic, beta = 2). Path depth follows Mitsuba 3's `path` integrator:
//! `max_depth` counts path segments (1: emitters seen directly, 2: direct illumination, -1:
//! unlimited); Russian roulette starts once `rr_depth` segments have been traced, continuing with
//! probability min(max throughput, 0.95). Emitters are one-sided.

use crate::geometry::Interaction;
use crate::light::LightSample;
use crate::sampler::Sampler;
use crate::scene::Scene;
use pt_math::{offset_ray_origin, power_heuristic, Frame, Ray, Vec3};
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
        PathSettings { max_depth: -1, rr_depth: 5, hide_emitters: false, strategy: Strategy::Mis, media: false }
    }
}

/// Shadow rays stop this fraction short of the light point, whose origin is already offset: a
/// relative guard against rounding at the far end, not an absolute epsilon.
const SHADOW_RAY_SHORTEN: f32 = 1.0 - 1e-5;

/// Radiance arriving along `ray` (the camera ray), estimated with one path, at the path's
/// wavelengths `lambda` (spectral mode; ignored in RGB mode, whose lanes are R, G, B).
///
/// Always inlined, so that the render loop's x86-64-v3 variant compiles it with those
/// instructions (see `render::render_tile`).
#[inline(always)]
pub fn li(scene: &Scene, mut ray: Ray, s: &PathSettings, sampler: &mut Sampler, lambda: &SampledWavelengths) -> SampledSpectrum {
    let max_depth = if s.max_depth < 0 { u32::MAX } else { s.max_depth as u32 };
    // Lanes may change wavelength at fluorescent vertices; the caller's film keeps the originals.
    let mut lambda = *lambda;
    let lambda = &mut lambda;
    let mut radiance = SampledSpectrum::ZERO;
    let mut throughput = match scene.mode {
        ColorMode::Rgb => SampledSpectrum::from_rgb([1.0; 3]),
        ColorMode::Spectral => SampledSpectrum::splat(1.0),
    };
    // The previous scattering event, for MIS on emitters hit by BSDF sampling.
    let mut prev_p = ray.origin;
    let mut prev_pdf = 0.0f32;
    let mut prev_delta = true; // the camera acts like a delta event: no MIS on directly seen lights
    let use_light = s.strategy != Strategy::Bsdf;
    let mut depth: u32 = 0;
    // Product of the relative indices of refraction crossed so far: radiance carries 1/eta^2 per
    // refraction, which Russian roulette undoes when judging the path's worth (Mitsuba).
    let mut eta_scale: f32 = 1.0;

    loop {
        let Some(hit) = scene.intersect(&ray) else {
            // The ray left the scene: environment and sun.
            for &i in &scene.infinite_lights {
                let light = &scene.lights[i];
                let le = light.escaped_radiance(ray.dir, lambda) * scene.emission(i, lambda);
                if !le.is_black() {
                    let w = emission_weight(s, depth, prev_delta, prev_pdf, || scene.light_pmf(i) * light.escaped_pdf(ray.dir));
                    radiance += throughput * le * w;
                }
            }
            break;
        };
        let wo_world = -ray.dir;

        // Beer-Lambert: a ray that reaches a shape's surface from behind travelled inside it, so
        // it crossed the shape's interior medium over the distance hit.t (the ray's direction is a
        // unit vector). Multiplying by the transmittance exp(-sigma_t t) is the expected value of
        // Mitsuba volpath's free-flight sampling for albedo 0, without its variance.
        if s.media && ray.dir.dot(hit.ng) > 0.0 {
            if let Some(tr) = scene.interior_transmittance(hit.shape, hit.t, lambda) {
                throughput *= tr;
                if throughput.is_black() {
                    break;
                }
            }
        }

        // Emission found by the ray we just traced.
        if let Some((li_idx, light)) = scene.shape_light(hit.shape) {
            let le = light.emitted(hit.ns, wo_world, hit.uv, lambda) * scene.emission(li_idx, lambda);
            if !le.is_black() {
                let w = emission_weight(s, depth, prev_delta, prev_pdf, || scene.light_pmf(li_idx) * light.pdf(prev_p, hit.p, hit.ns));
                radiance += throughput * le * w;
            }
        }

        // Mitsuba: continue only if another segment fits within max_depth.
        if depth.saturating_add(1) >= max_depth {
            break;
        }

        let bsdf = scene.material_at_hit(&hit, lambda);
        // Fluorescence: the BSDF holds each lane's total albedo at its emitted wavelength; now
        // some lanes move to an excitation wavelength, used by NEE and the rest of the path.
        if scene.is_fluorescent(hit.shape) {
            *lambda = scene.fluoresce(hit.shape, lambda, sampler.next_1d());
        }
        let frame = Frame::from_normal_tangent(hit.ns, hit.dpdu);
        let wo = frame.to_local(wo_world);

        // Rays leave the hit offset to one side of the surface; the shadow ray and the next
        // segment of a reflection leave on the side the path came from.
        let spawn = SpawnPoint::new(&hit, ray.dir);

        // Next-event estimation.
        if use_light && bsdf.has_smooth_lobe() {
            if let Some((li_idx, pmf, u_sel)) = scene.sample_light(sampler.next_1d()) {
                let u = sampler.next_2d();
                let light = &scene.lights[li_idx];
                if let Some(ls) = light.sample(hit.p, u_sel, u, lambda) {
                    let wi = frame.to_local(ls.wi);
                    let f = bsdf.eval(wo, wi);
                    if !ls.radiance.is_black() && !f.is_black() && visible(scene, spawn.origin(ls.wi), &ls) {
                        let light_pdf = pmf * ls.pdf;
                        // Delta lights cannot be hit by BSDF sampling: light sampling is the only
                        // strategy, weight 1.
                        let w = if s.strategy != Strategy::Light && !ls.delta { power_heuristic(light_pdf, bsdf.pdf(wo, wi)) } else { 1.0 };
                        radiance += throughput * f * ls.radiance * scene.emission(li_idx, lambda) * (wi.z.abs() * w / light_pdf);
                    }
                }
            } else {
                // Keep the random number sequence aligned whether or not there are lights.
                let _ = sampler.next_2d();
            }
        }

        // BSDF sampling.
        let u_lobe = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u_lobe, sampler.next_2d()) else { break };
        if bs.weight.is_black() {
            break;
        }
        throughput *= bs.weight;
        eta_scale *= bs.eta;
        let wi_world = frame.to_world(bs.wi);
        prev_p = hit.p;
        prev_pdf = bs.pdf;
        prev_delta = bs.delta;
        ray = Ray::new(spawn.origin(wi_world), wi_world);
        depth += 1;

        // Russian roulette (Mitsuba: after rr_depth segments, keep with probability
        // min(max(T) eta^2, 0.95)).
        if depth >= s.rr_depth {
            let q = (throughput.max_value() * eta_scale * eta_scale).min(0.95);
            if !(sampler.next_1d() < q) {
                break;
            }
            throughput *= 1.0 / q;
        }
    }
    radiance
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
        SpawnPoint { p: hit.p, n_out, out: offset_ray_origin(hit.p, n_out) }
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

/// Whether nothing blocks the segment from `origin` (the hit, offset off its surface towards the
/// light) to the light sample, whose end is offset off its surface too (a light without a
/// surface normal, or a distant one, needs no offset there).
#[inline(always)]
fn visible(scene: &Scene, origin: Vec3, ls: &LightSample) -> bool {
    if ls.dist.is_infinite() {
        return !scene.occluded(&Ray::new(origin, ls.wi));
    }
    let target = if ls.n == pt_math::Vec3::ZERO { ls.p } else { offset_ray_origin(ls.p, ls.n * ls.n.dot(-ls.wi).signum()) };
    let seg = target - origin;
    let dist = seg.length();
    if !(dist > 0.0) {
        return false;
    }
    !scene.occluded(&Ray { origin, dir: seg / dist, tmin: 0.0, tmax: dist * SHADOW_RAY_SHORTEN })
}

/// Weight of emission that the traced ray found (an emitter hit or an escaped ray), given the
/// solid-angle pdf with which light sampling would have chosen the same direction (computed
/// only when needed). Seen directly from the camera: 1, or 0 with `hide_emitters`. After a
/// delta bounce: 1 (light sampling cannot produce it). Otherwise the power heuristic against
/// light sampling under MIS, 1 with BSDF sampling alone, and 0 with light sampling alone (NEE
/// already counted it).
#[inline]
fn emission_weight(s: &PathSettings, depth: u32, prev_delta: bool, prev_pdf: f32, light_pdf: impl FnOnce() -> f32) -> f32 {
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
