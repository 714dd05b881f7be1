//! Volumetric path tracing (Mitsuba 3.9.1's `volpath`) through homogeneous participating media
//! ([`pt_render::medium`]): the radiative transfer equation solved by free-flight sampling,
//! phase-function sampling and light sampling with transmittance, under MIS.
//!
//! A path starts in the camera's medium (`Scene::camera_medium`) and changes medium where it
//! crosses a shape that bounds media (`Scene::medium_boundary`): into the shape's interior when
//! it crosses against the geometric normal, its exterior otherwise (vacuum where that side is
//! unset), as Mitsuba does. In each segment through a medium:
//! - *Free flight*: a distance `t` is drawn with density `sigma_t,c exp(-sigma_t,c t)` for a
//!   channel `c` chosen uniformly among the colour channels (RGB) or wavelength lanes
//!   (spectral), and weighted with the density averaged over all channels, `p(t) = mean_k
//!   sigma_t,k exp(-sigma_t,k t)`: one-sample MIS with the balance heuristic over the channels
//!   (Mitsuba's `volpathmis`; Miller, Georgiev & Jarosz 2019, sec. 5.2), where Mitsuba's
//!   `volpath` weights by the chosen channel's density alone (the same expected value, with a
//!   variance that grows without bound as the channels' extinctions part: a red path through a
//!   blue-dense fog). If `t` falls before the next surface, the path scatters there with the
//!   weight `sigma_s T(t) / p(t)`; otherwise it reaches the surface with `T(t_s) / P(t > t_s)`,
//!   P likewise averaged. A medium that only absorbs (albedo 0) is crossed with its
//!   transmittance `T(t_s)` instead: the expected value of the same sampling, without its
//!   variance (Mitsuba's free flight ends such paths at random).
//! - *Scattering in the medium*: light sampling (Mitsuba's `sample_emitters`, on by default)
//!   weighted by the phase function, and phase-function sampling for the next direction; the
//!   two are joined by the power heuristic.
//!
//! Surfaces are shaded as the path tracer shades them (BSDF, light sampling, MIS), but light
//! samples see through *null* interfaces: the transmittance to a light is the product of the
//! media's transmittances along the segment and of the straight-through transmission
//! ([`pt_bsdf::SurfaceBsdf::null_transmission`]) of the surfaces it crosses (a `null` BSDF, a mask's
//! holes, a thin dielectric), where Mitsuba estimates the same product by tracking.
//!
//! Depth follows Mitsuba's `volpath`: `max_depth` counts scattering events, in media and at
//! surfaces, with passes straight through a surface (null events) not counted; Russian roulette
//! starts once the depth exceeds `rr_depth` (q = min(max(throughput) eta^2, 0.95)). A sample
//! covers its pixel (alpha) when the path scatters somewhere (medium or non-null surface
//! event), or when an environment light is visible.

use crate::path::{emission_weight, escaped_radiance, PathSettings, PathState, Strategy};
use crate::ptracer::shading_frame;
use pt_math::{offset_ray_origin, power_heuristic, Ray, Vec3};
use pt_render::light::LightSample;
use pt_render::medium::{transmittance, Medium};
use pt_render::sampler::RandomSource;
use pt_render::scene::SHADOW_RAY_SHORTEN;
use pt_render::Scene;
use pt_spectrum::{ColorMode, SampledSpectrum, SampledWavelengths};

/// Most surfaces a light sample's shadow ray crosses before it is taken as blocked (a guard
/// against rounding loops on coincident surfaces, far above what scenes stack).
const MAX_CROSSINGS: u32 = 256;

/// [`estimate`] compiled for the processor's wider instructions ([`pt_render::isa::best`]),
/// called from the path tracer's loop but kept out of it: inlined there, once per instruction
/// set, it made that already large function much slower to compile.
#[inline(never)]
pub(crate) fn estimate_best<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    path: &mut PathState,
    sampler: &mut S,
) {
    pt_render::isa::best(
        #[inline(always)]
        || estimate(scene, s, path, sampler),
    )
}

/// Traces `path` (a camera path, not yet traced) through the scene's media and surfaces with
/// Mitsuba's `volpath` rules (see the module documentation); leaves the estimate in
/// `path.radiance` and whether the sample covers its pixel in `path.covered`.
#[inline(always)]
pub fn estimate<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    path: &mut PathState,
    sampler: &mut S,
) {
    let max_depth = s.depth_limit();
    // The channels free-flight sampling chooses among (RGB's fourth lane is unused).
    let channels = match scene.mode {
        ColorMode::Spectral => 4,
        ColorMode::Rgb => 3,
    };
    let mut lambda = path.lambda;
    let mut ray = path.ray;
    let mut throughput = path.throughput;
    let mut radiance = SampledSpectrum::ZERO;
    let mut medium = scene.camera_medium;
    let mut eta = 1.0f32;
    let mut depth = 0u32;
    // The last scattering event (not a null one): where it was, the density of the direction
    // it chose, and whether light sampling could not have made that choice.
    let (mut prev_p, mut prev_pdf, mut prev_delta) = (ray.origin, 0.0f32, true);
    let mut covered = !s.hide_emitters && !scene.infinite_lights.is_empty();
    loop {
        if throughput.is_black() {
            break;
        }
        if depth > s.rr_depth {
            let q = (throughput.max_value() * eta * eta).min(0.95);
            if !(sampler.next_1d() < q) {
                break;
            }
            throughput *= 1.0 / q;
        }
        if depth >= max_depth {
            break;
        }
        let hit = scene.intersect(&ray);
        let t_surface = hit.as_ref().map_or(f32::INFINITY, |h| h.t);

        // The segment through the current medium.
        if let Some(m) = medium.map(|i| &scene.media[i as usize]) {
            let flight = free_flight(m, &ray, t_surface, &lambda, channels, sampler);
            radiance += throughput * flight.emitted;
            throughput *= flight.weight;
            if throughput.is_black() {
                break;
            }
            if let Some(t) = flight.scatter_at {
                let p = ray.origin + ray.dir * t;
                depth += 1;
                covered = true;
                if depth >= max_depth {
                    break;
                }
                let wo = -ray.dir;
                // Light sampling, weighted by the phase function.
                let sample_lights = m.sample_emitters && s.strategy != Strategy::Bsdf;
                if sample_lights {
                    let at = (p, wo, medium);
                    if let Some(c) = medium_nee(scene, s, m, at, &lambda, throughput, sampler) {
                        radiance += c;
                    }
                }
                let ps = m.phase.sample(wo, sampler.next_2d());
                if !(ps.pdf > 0.0) {
                    break;
                }
                (prev_p, prev_pdf, prev_delta) = (p, ps.pdf, !sample_lights);
                ray = Ray::new(p, ps.wi);
                continue;
            }
        }

        // A surface, or the environment.
        let Some(hit) = hit else {
            radiance += escaped_radiance(scene, ray.dir, &lambda, throughput, |i| {
                emission_weight(s, depth, prev_delta, prev_pdf, || {
                    scene.light_pmf_at(prev_p, i) * scene.lights[i].escaped_pdf(ray.dir)
                })
            });
            break;
        };
        let wo_world = -ray.dir;
        let prev = (prev_p, prev_pdf, prev_delta);
        if let Some((le, w)) = emission_met(scene, s, &hit, wo_world, &lambda, depth, prev) {
            radiance += throughput * le * w;
        }
        let frame = shading_frame(&hit);
        let wo = frame.to_local(wo_world);
        let ng_wo = hit.ng.dot(wo_world);
        if ng_wo * wo.z <= 0.0 {
            // The shading and geometric normals disagree about the side: a light leak.
            break;
        }
        let bsdf = scene.bsdf(&hit, &lambda);
        if let Some(f) = scene.material(hit.shape).fluorescent() {
            // The BSDF holds each lane's total albedo at its emitted wavelength; the lanes move
            // to the wavelengths they were excited at (as the path tracer does).
            lambda = f.scatter(&lambda, sampler.next_1d());
        }
        // Light sampling at the surface.
        if bsdf.has_smooth_lobe()
            && depth.saturating_add(1) < max_depth
            && s.strategy != Strategy::Bsdf
        {
            let at = SurfaceVertex {
                hit: &hit,
                frame: &frame,
                bsdf: &bsdf,
                wo,
                medium,
            };
            if let Some(c) = surface_nee(scene, s, &at, &lambda, throughput, sampler) {
                radiance += c;
            }
        }
        // BSDF sampling.
        let u_lobe = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u_lobe, sampler.next_2d()) else {
            break;
        };
        let dir = frame.to_world(bs.wi);
        let ng_next = hit.ng.dot(dir);
        if ng_next * bs.wi.z <= 0.0 {
            break;
        }
        throughput *= bs.weight;
        eta *= bs.eta;
        if !bs.is_pass_through(wo) {
            depth += 1;
            covered = true;
            (prev_p, prev_pdf, prev_delta) = (hit.p, bs.pdf, bs.delta);
        }
        if let Some((inside, outside)) = scene.medium_boundary(hit.shape) {
            medium = if ng_next > 0.0 { outside } else { inside };
        }
        ray = Ray::new(offset_ray_origin(hit.p, hit.ng * ng_next.signum()), dir);
    }
    path.radiance = radiance;
    path.covered = covered;
}

/// The radiance emitted by the surface met at `hit` towards `wo_world` (unit, world) and its
/// MIS weight against light sampling from the last scattering event `prev` (its position, the
/// density of the direction it chose, and whether light sampling could not have made that
/// choice) at path depth `depth`; `None` off emitters and for black emission.
#[inline(always)]
fn emission_met(
    scene: &Scene,
    s: &PathSettings,
    hit: &pt_render::geometry::Interaction,
    wo_world: Vec3,
    lambda: &SampledWavelengths,
    depth: u32,
    (prev_p, prev_pdf, prev_delta): (Vec3, f32, bool),
) -> Option<(SampledSpectrum, f32)> {
    let (li, light) = scene.shape_light(hit.shape)?;
    let le = light.emitted(hit.ns, wo_world, hit.uv, lambda);
    if le.is_black() {
        return None;
    }
    let w = emission_weight(s, depth, prev_delta, prev_pdf, || {
        scene.light_pmf_at(prev_p, li) * light.pdf(prev_p, hit.p, hit.ns)
    });
    Some((le, w))
}

/// Light sampling at a scattering event in the medium `m` at `(p, wo, medium)` (position,
/// unit direction back along the path, world; the medium's index), weighted by the phase
/// function and by MIS against phase sampling: the radiance it adds, times `throughput`.
/// Draws the light sample's numbers whether or not a light is found.
#[inline(always)]
fn medium_nee<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    m: &Medium,
    (p, wo, medium): (Vec3, Vec3, Option<u32>),
    lambda: &SampledWavelengths,
    throughput: SampledSpectrum,
    sampler: &mut S,
) -> Option<SampledSpectrum> {
    let (u_light, u_pos) = (sampler.next_1d(), sampler.next_2d());
    let (ls, pmf) = sample_light(scene, p, lambda, u_light, u_pos)?;
    let phase = m.phase.eval(wo, ls.wi);
    let w = nee_weight(s, &ls, pmf, phase);
    if !(w > 0.0 && phase > 0.0) {
        return None;
    }
    let tr = transmittance_to(scene, p, &ls, medium, lambda, sampler);
    Some(throughput * ls.radiance * tr * (phase * w / (pmf * ls.pdf)))
}

/// A surface vertex of a volumetric path as light sampling sees it: the hit, its shading
/// frame and BSDF, `wo` (local frame) and the medium the path arrived in.
struct SurfaceVertex<'a> {
    hit: &'a pt_render::geometry::Interaction,
    frame: &'a pt_math::Frame,
    bsdf: &'a pt_bsdf::SurfaceBsdf,
    wo: Vec3,
    medium: Option<u32>,
}

/// Light sampling at a surface vertex `at`, its shadow ray through media and null surfaces
/// ([`transmittance_to`]), weighted by MIS against BSDF sampling: the radiance it adds, times
/// `throughput`. Draws the light sample's numbers whether or not a light is found.
#[inline(always)]
fn surface_nee<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    at: &SurfaceVertex,
    lambda: &SampledWavelengths,
    throughput: SampledSpectrum,
    sampler: &mut S,
) -> Option<SampledSpectrum> {
    let (hit, bsdf, wo) = (at.hit, at.bsdf, at.wo);
    let (u_light, u_pos) = (sampler.next_1d(), sampler.next_2d());
    let origin_side = |d: Vec3| offset_ray_origin(hit.p, hit.ng * hit.ng.dot(d).signum());
    let (ls, pmf) = sample_light(scene, hit.p, lambda, u_light, u_pos)?;
    let wi = at.frame.to_local(ls.wi);
    let ng_wi = hit.ng.dot(ls.wi);
    if !(ng_wi * wi.z > 0.0) {
        return None;
    }
    let f = bsdf.eval(wo, wi);
    if f.is_black() {
        return None;
    }
    let w = nee_weight(s, &ls, pmf, bsdf.pdf(wo, wi));
    if !(w > 0.0) {
        return None;
    }
    // The shadow ray starts in the medium on the light's side.
    let start = match scene.medium_boundary(hit.shape) {
        Some((_, outside)) if ng_wi > 0.0 => outside,
        Some((inside, _)) => inside,
        None => at.medium,
    };
    let tr = transmittance_to(scene, origin_side(ls.wi), &ls, start, lambda, sampler);
    Some(throughput * f * ls.radiance * tr * (wi.z.abs() * w / (pmf * ls.pdf)))
}

/// What a segment through a medium did: the throughput factor, where the path scatters (the
/// ray parameter) if it does before `t_surface`, and the medium's emission gathered on the way.
pub(crate) struct Flight {
    /// The throughput factor.
    pub weight: SampledSpectrum,
    /// The ray parameter of the scattering event, if there is one.
    pub scatter_at: Option<f32>,
    /// An estimate of the emitted radiance the segment adds, `int_0^t_s T(t) j(t) dt` up to the
    /// surface (or out of the medium), weighted as the path's throughput before the segment
    /// is (multiply by that throughput, not by `weight`). Zero in a medium that does not glow.
    pub emitted: SampledSpectrum,
}

/// The mean of the first `channels` lanes.
#[inline(always)]
fn mean(x: SampledSpectrum, channels: usize) -> f32 {
    x.0.to_array()[..channels].iter().sum::<f32>() / channels as f32
}

/// `int_0^d exp(-sigma_t t) j dt = j (1 - exp(-sigma_t d)) / sigma_t` per lane: the emission of
/// a homogeneous glowing medium along `d` (`j d` where `sigma_t` is 0; 0 where `j` is, even
/// for an infinite `d`).
#[inline(always)]
fn homogeneous_emission(j: SampledSpectrum, sigma_t: SampledSpectrum, d: f32) -> SampledSpectrum {
    let (j, s) = (j.0.to_array(), sigma_t.0.to_array());
    SampledSpectrum(pt_math::Vec4::from_array(std::array::from_fn(|k| {
        if j[k] == 0.0 {
            0.0
        } else if s[k] > 0.0 {
            // -expm1 keeps the digits of a short or thin segment.
            j[k] * -(-s[k] * d).exp_m1() / s[k]
        } else {
            j[k] * d
        }
    })))
}

/// Free flight along `ray` through the medium `m` up to the surface at `t_surface` (infinite
/// if none), as the module documentation describes. Homogeneous: a distance drawn for a
/// channel chosen uniformly, weighted by the channel-averaged density; the emission integral
/// is exact. Heterogeneous: delta tracking against the majorant `mu = max_k sigma_t,k * max
/// grid value` inside the grid's box (Woodcock et al. 1965; as null-collision MIS by Miller,
/// Georgiev & Jarosz 2019): tentative collisions at rate `mu`, each a scattering with
/// probability `P_s = mean(sigma_s) / (mean(sigma_s) + mean(sigma_n))` (weight `sigma_s / (mu
/// P_s)`) or a null collision (weight `sigma_n / (mu (1 - P_s))`, `sigma_n = mu - sigma_t`),
/// absorption left to the weights; every channel's expected value is the RTE's. Emission is
/// gathered by the collision estimator: `j(x) / mu` at each tentative collision, with the
/// weight so far (its expectation is `int T j dt`, as the collisions have density `mu
/// T_mu(t)` and the weights turn `T_mu` into `T`).
#[inline(always)]
pub(crate) fn free_flight<S: RandomSource>(
    m: &Medium,
    ray: &Ray,
    t_surface: f32,
    lambda: &SampledWavelengths,
    channels: usize,
    sampler: &mut S,
) -> Flight {
    let zero = SampledSpectrum::ZERO;
    let pass = |weight, emitted| Flight {
        weight,
        scatter_at: None,
        emitted,
    };
    let Some(density) = &m.density else {
        let sigma_t = m.sigma_t.at(lambda);
        // Emission is a constant in a homogeneous medium (the loader confines grids to
        // heterogeneous ones).
        let emitted = match m.emission.as_ref().and_then(|e| e.constant()) {
            Some(j) => homogeneous_emission(j.at(lambda), sigma_t, t_surface),
            None => zero,
        };
        if !m.scatters {
            // Absorption only: the transmittance, the expected value of free flight.
            return pass(transmittance(sigma_t, t_surface), emitted);
        }
        let channel = ((sampler.next_1d() * channels as f32) as usize).min(channels - 1);
        let sigma_c = sigma_t.0[channel];
        let u = sampler.next_1d();
        let t = if sigma_c > 0.0 {
            -(1.0 - u).ln() / sigma_c
        } else {
            f32::INFINITY
        };
        if t < t_surface {
            // A scattering event: weight sigma_s T(t) / p(t).
            let tr = transmittance(sigma_t, t);
            let pdf = mean(sigma_t * tr, channels);
            if !(pdf > 0.0) {
                return pass(zero, emitted);
            }
            let albedo = m.albedo_at(ray.origin + ray.dir * t, lambda);
            return Flight {
                weight: sigma_t * albedo * tr * (1.0 / pdf),
                scatter_at: Some(t),
                emitted,
            };
        }
        // Reaching the surface (or leaving the scene): weight T(t_s) / P(t > t_s).
        let tr = transmittance(sigma_t, t_surface);
        let p = mean(tr, channels);
        return pass(if p > 0.0 { tr * (1.0 / p) } else { zero }, emitted);
    };
    let one = SampledSpectrum::splat(1.0);
    let Some((t0, t1)) = density.clip(ray, t_surface) else {
        return pass(one, zero);
    };
    let t0 = t0.max(0.0);
    let sigma_t = m.sigma_t.at(lambda);
    let mu = max_lane(sigma_t, channels) * density.max;
    if !(mu > 0.0) {
        // Nothing attenuates: the emission integral is the length times j, estimated at one
        // uniform point (exact for a constant j).
        let emitted = match &m.emission {
            Some(e) => {
                let t = t0 + (t1 - t0) * sampler.next_1d();
                e.at(ray.origin + ray.dir * t, lambda) * (t1 - t0)
            }
            None => zero,
        };
        return pass(one, emitted);
    }
    // A constant albedo is looked up once, not at every collision.
    let albedo = m.albedo.constant().map(|a| a.at(lambda));
    let mut weight = one;
    let mut emitted = zero;
    let mut t = t0;
    loop {
        t -= (1.0 - sampler.next_1d()).ln() / mu;
        if t >= t1 {
            return pass(weight, emitted);
        }
        let p = ray.origin + ray.dir * t;
        if let Some(e) = &m.emission {
            emitted += weight * e.at(p, lambda) * (1.0 / mu);
        }
        let st = sigma_t * density.at(p, lambda);
        let ss = st * albedo.unwrap_or_else(|| m.albedo_at(p, lambda));
        let sn = SampledSpectrum(SampledSpectrum::splat(mu).0 - st.0);
        let (ms, mn) = (mean(ss, channels), mean(sn, channels).max(0.0));
        if !(ms + mn > 0.0) {
            // Only absorption here, in every channel.
            return pass(zero, emitted);
        }
        let p_s = ms / (ms + mn);
        if sampler.next_1d() < p_s {
            return Flight {
                weight: weight * ss * (1.0 / (mu * p_s)),
                scatter_at: Some(t),
                emitted,
            };
        }
        weight *= sn * (1.0 / (mu * (1.0 - p_s)));
    }
}

/// The largest of the first `channels` lanes.
#[inline(always)]
fn max_lane(x: SampledSpectrum, channels: usize) -> f32 {
    x.0.to_array()[..channels]
        .iter()
        .copied()
        .fold(0.0, f32::max)
}

/// The transmittance of `m` along `ray` over `[0, t]`: exact for a homogeneous medium; by
/// ratio tracking (Novák, Selle & Jarosz 2014) inside a heterogeneous medium's box, the
/// product of `1 - sigma_t(x) / mu` over tentative collisions at rate `mu` (unbiased).
#[inline(always)]
fn medium_transmittance<S: RandomSource>(
    m: &Medium,
    ray: &Ray,
    t: f32,
    lambda: &SampledWavelengths,
    sampler: &mut S,
) -> SampledSpectrum {
    let Some(density) = &m.density else {
        return m.transmittance(t, lambda);
    };
    let one = SampledSpectrum::splat(1.0);
    let Some((t0, t1)) = density.clip(ray, t) else {
        return one;
    };
    let sigma_t = m.sigma_t.at(lambda);
    let mu = max_lane(sigma_t, SampledWavelengths::N) * density.max;
    if !(mu > 0.0) {
        return one;
    }
    let mut tr = one;
    let mut x = t0.max(0.0);
    loop {
        x -= (1.0 - sampler.next_1d()).ln() / mu;
        if x >= t1 {
            return tr;
        }
        let st = sigma_t * density.at(ray.origin + ray.dir * x, lambda);
        tr *= SampledSpectrum(one.0 - st.0 * (1.0 / mu));
        if tr.is_black() {
            return tr;
        }
    }
}

/// A light sample for the point `p` (the scene's light selection, then the light's own
/// sampling) and the selection probability, if it carries light.
#[inline(always)]
fn sample_light(
    scene: &Scene,
    p: Vec3,
    lambda: &SampledWavelengths,
    u_light: f32,
    u_pos: pt_math::Vec2,
) -> Option<(LightSample, f32)> {
    let (li, pmf, u_sel) = scene.sample_light_at(p, u_light)?;
    let ls = scene.lights[li].sample(p, u_sel, u_pos, lambda)?;
    (!ls.radiance.is_black() && ls.pdf > 0.0).then_some((ls, pmf))
}

/// The MIS weight of a light sample against the scattering's density `scatter_pdf` of the
/// same direction (BSDF or phase function): the power heuristic, 1 for a delta light or with
/// light sampling alone.
#[inline(always)]
fn nee_weight(s: &PathSettings, ls: &LightSample, pmf: f32, scatter_pdf: f32) -> f32 {
    if ls.delta || s.strategy == Strategy::Light {
        1.0
    } else {
        power_heuristic(pmf * ls.pdf, scatter_pdf)
    }
}

/// The fraction of the light sample's radiance that reaches `origin` (a ray origin already
/// off its surface, in `medium`): the product of the media's transmittances along the segment
/// and of the straight-through transmission of each surface it crosses; 0 when an opaque
/// surface blocks it.
#[inline(always)]
pub(crate) fn transmittance_to<S: RandomSource>(
    scene: &Scene,
    origin: Vec3,
    ls: &LightSample,
    mut medium: Option<u32>,
    lambda: &SampledWavelengths,
    sampler: &mut S,
) -> SampledSpectrum {
    // The far end: the light's point off its own surface, or infinitely far along `ls.wi`.
    let (dir, mut remaining) = if ls.dist.is_infinite() {
        (ls.wi, f32::INFINITY)
    } else {
        let target = if ls.n == Vec3::ZERO {
            ls.p
        } else {
            offset_ray_origin(ls.p, ls.n * ls.n.dot(-ls.wi).signum())
        };
        let seg = target - origin;
        let d = seg.length();
        if !(d > 0.0) {
            return SampledSpectrum::ZERO;
        }
        (seg / d, d * SHADOW_RAY_SHORTEN)
    };
    let mut tr = SampledSpectrum::splat(1.0);
    let mut o = origin;
    for _ in 0..MAX_CROSSINGS {
        let ray = Ray {
            origin: o,
            dir,
            tmin: 0.0,
            tmax: remaining,
        };
        let hit = scene.intersect(&ray);
        let t = hit.as_ref().map_or(remaining, |h| h.t);
        if let Some(m) = medium {
            tr *= medium_transmittance(&scene.media[m as usize], &ray, t, lambda, sampler);
        }
        let Some(hit) = hit else {
            return tr;
        };
        let frame = shading_frame(&hit);
        let through = scene
            .bsdf(&hit, lambda)
            .null_transmission(frame.to_local(-dir));
        tr *= through;
        if tr.is_black() {
            return tr;
        }
        let ng_dir = hit.ng.dot(dir);
        if let Some((inside, outside)) = scene.medium_boundary(hit.shape) {
            medium = if ng_dir > 0.0 { outside } else { inside };
        }
        o = offset_ray_origin(hit.p, hit.ng * ng_dir.signum());
        remaining = if remaining.is_finite() {
            // What is left of the segment beyond the crossing, measured from the new origin.
            let left = (ray.origin + dir * remaining - o).dot(dir);
            if !(left > 0.0) {
                return tr;
            }
            left
        } else {
            f32::INFINITY
        };
    }
    SampledSpectrum::ZERO
}

/// Whether the volumetric path tracer renders `scene` with the path settings `s`: a `volpath`
/// scene that has media (without media it is the path tracer's image, which the faster path
/// tracer renders).
pub fn applies(scene: &Scene, s: &PathSettings) -> bool {
    s.media && scene.has_media()
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_math::Mat4;
    use pt_render::medium::{Grid, Phase, VolumeSpectrum};
    use pt_render::sampler::Sampler;
    use pt_render::texture::ConstantSpectrum;

    /// A 4 x 3 x 5 grid with a ramp and a bump, stretched over [-1, 3] x [0, 1] x [0, 2] in
    /// world space, in a grey medium of extinction factor `sigma` and albedo `albedo`.
    fn grid_medium(sigma: f32, albedo: f32) -> Medium {
        let res = [4u32, 3, 5];
        let values: Vec<f32> = (0..60)
            .map(|i| {
                let (x, y, z) = (i % 4, (i / 4) % 3, i / 12);
                0.2 + 0.3 * x as f32 + if (y, z) == (1, 2) { 1.5 } else { 0.0 }
            })
            .collect();
        let to_world = Mat4::from_translation(pt_math::Vec3::new(-1.0, 0.0, 0.0))
            * Mat4::from_scale(pt_math::Vec3::new(4.0, 1.0, 2.0));
        let grey = |v| ConstantSpectrum::Rgb(SampledSpectrum::from_rgb([v; 3]));
        Medium {
            loc: Default::default(),
            sigma_t: grey(sigma),
            albedo: VolumeSpectrum::Constant(grey(albedo)),
            phase: Phase::ISOTROPIC,
            sample_emitters: true,
            scatters: albedo > 0.0,
            density: Grid::new(&values, 1, res, to_world, false, false, false),
            emission: None,
        }
    }

    /// A one-channel grid's value at `p`.
    fn density_at(d: &Grid, p: Vec3) -> f32 {
        d.at(p, &SampledWavelengths::sample_visible(0.5)).0.x
    }

    fn ray() -> Ray {
        // Diagonally through the box from a point on its face x = -1: inside it for t < 4.3.
        Ray::new(
            Vec3::new(-1.0, 0.1, 0.2),
            Vec3::new(1.0, 0.15, 0.35).normalize(),
        )
    }

    /// The optical depth along `ray` over [0, t] by the midpoint rule on 200 000 steps (the
    /// trilinear density is continuous: error far below 1e-4).
    fn optical_depth(m: &Medium, ray: &Ray, t: f32) -> f64 {
        let d = m.density.as_ref().unwrap();
        let n = 200_000;
        let h = f64::from(t) / n as f64;
        let sigma = f64::from(m.sigma_t.at(&SampledWavelengths::sample_visible(0.5)).0.x);
        (0..n)
            .map(|i| {
                let x = ((i as f64 + 0.5) * h) as f32;
                sigma * f64::from(density_at(d, ray.origin + ray.dir * x)) * h
            })
            .sum()
    }

    /// Ratio tracking's transmittance through the grid averages to exp(-optical depth): the
    /// mean of 200 000 estimates within 4.5 standard errors (estimated from the same samples)
    /// of the quadrature, the standard error under 0.3% of the value so that a 2% error (say,
    /// tracking against a majorant below the grid's maximum) fails.
    #[test]
    fn ratio_tracking_matches_the_line_integral() {
        // Optical depth about 1.1 over the 4 units.
        let m = grid_medium(0.4, 0.0);
        let r = ray();
        let t = 4.0;
        let want = (-optical_depth(&m, &r, t)).exp();
        let lambda = SampledWavelengths::sample_visible(0.5);
        let mut sampler = Sampler::new(7, 1, 0);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let tr = f64::from(medium_transmittance(&m, &r, t, &lambda, &mut sampler).0.x);
            sum += tr;
            sum2 += tr * tr;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        eprintln!("ratio tracking {mean:.5} vs exp(-tau) {want:.5}, se {se:.2e}");
        assert!(se < 0.003 * want, "too noisy: {se}");
        assert!((mean - want).abs() < 4.5 * se, "{mean} vs {want}");
    }

    /// Delta tracking in a grey medium of albedo 1 scatters at distances with the density
    /// `sigma(t) exp(-int_0^t sigma)` (every weight is exactly 1 there): a chi-square test of
    /// 100 000 free flights over 24 bins of the ray's first 4 units and one for "beyond", the
    /// expected counts from the quadrature (24 degrees of freedom: the 0.1% critical value is
    /// 51.2). A flight that scatters at every tentative collision (null collisions ignored)
    /// fails it.
    #[test]
    fn delta_tracking_distances_follow_the_density() {
        let m = grid_medium(1.3, 1.0);
        let r = ray();
        let t_end = 4.0f32;
        let lambda = SampledWavelengths::sample_visible(0.5);
        let mut sampler = Sampler::new(11, 2, 0);
        let bins = 24;
        let n = 100_000;
        let mut counts = vec![0u32; bins + 1];
        for _ in 0..n {
            let f = free_flight(&m, &r, t_end, &lambda, 3, &mut sampler);
            match f.scatter_at {
                Some(t) => {
                    assert!((f.weight.0.x - 1.0).abs() < 1e-5, "weight {:?}", f.weight);
                    counts[((t / t_end * bins as f32) as usize).min(bins - 1)] += 1;
                }
                None => counts[bins] += 1,
            }
        }
        let cdf = |t: f32| 1.0 - (-optical_depth(&m, &r, t)).exp();
        let mut chi2 = 0.0;
        for (b, &c) in counts.iter().enumerate() {
            let p = if b == bins {
                1.0 - cdf(t_end)
            } else {
                let (lo, hi) = (
                    t_end * b as f32 / bins as f32,
                    t_end * (b + 1) as f32 / bins as f32,
                );
                cdf(hi) - cdf(lo)
            };
            let e = n as f64 * p;
            chi2 += (f64::from(c) - e).powi(2) / e;
        }
        eprintln!("delta tracking chi-square {chi2:.1} (24 dof)");
        assert!(chi2 < 51.2, "chi-square {chi2}");
    }

    /// The density's lookups: cell centres give the cells' values, trilinear between them,
    /// clamped to the outermost values up to the faces and beyond (Mitsuba's clamp; the
    /// medium itself ends at the box, where tracking stops).
    #[test]
    fn density_lookups_are_cell_centred() {
        let m = grid_medium(1.0, 0.0);
        let d = m.density.as_ref().unwrap();
        // Cell (x, y, z) centre in world space: x -1 + 4 (i + 0.5) / 4, y (j + 0.5) / 3,
        // z 2 (k + 0.5) / 5.
        let centre = |i: f32, j: f32, k: f32| {
            Vec3::new(-1.0 + (i + 0.5), (j + 0.5) / 3.0, 2.0 * (k + 0.5) / 5.0)
        };
        assert!((density_at(d, centre(2.0, 0.0, 0.0)) - 0.8).abs() < 1e-5);
        assert!((density_at(d, centre(1.0, 1.0, 2.0)) - 2.0).abs() < 1e-5);
        // Halfway between x cells 0 and 1 (values 0.2 and 0.5).
        assert!((density_at(d, centre(0.5, 0.0, 0.0)) - 0.35).abs() < 1e-5);
        // Clamped between the first centre and the face, and outside the box.
        assert!((density_at(d, Vec3::new(-0.9, 0.05, 0.1)) - 0.2).abs() < 1e-5);
        assert!((density_at(d, Vec3::new(-1.5, 0.5, 0.5)) - 0.2).abs() < 1e-5);
        assert_eq!(d.max, 0.2 + 0.9 + 1.5);
    }

    /// The collision estimator of a glowing grid medium: the emission a free flight gathers
    /// averages to `int_0^t j T(t) dt` (quadrature of the transmittance), whatever the flight
    /// then does (albedo 0.5: half the flights end at a scattering event, whose emission before
    /// it still counts). 200 000 flights; mean within 4.5 standard errors of the integral, the
    /// error under 0.5% of it so that a 2% bias (j not divided by the majorant at each
    /// collision, or emission counted only on flights that do not scatter) fails.
    #[test]
    fn collision_estimator_gathers_the_emission_integral() {
        let mut m = grid_medium(0.4, 0.5);
        let j = 0.7f32;
        m.emission = Some(VolumeSpectrum::Constant(ConstantSpectrum::Rgb(
            SampledSpectrum::from_rgb([j; 3]),
        )));
        let r = ray();
        let t_end = 4.0f32;
        // One march: the optical depth accumulated by the midpoint rule, the integrand taken
        // at each step's middle (200 000 steps: error far below the test's 0.5%).
        let d = m.density.as_ref().unwrap();
        let sigma = f64::from(m.sigma_t.at(&SampledWavelengths::sample_visible(0.5)).0.x);
        let n_quad = 200_000;
        let h = f64::from(t_end) / n_quad as f64;
        let (mut tau, mut want) = (0.0f64, 0.0f64);
        for i in 0..n_quad {
            let x = ((i as f64 + 0.5) * h) as f32;
            let step = sigma * f64::from(density_at(d, r.origin + r.dir * x)) * h;
            want += f64::from(j) * (-(tau + 0.5 * step)).exp() * h;
            tau += step;
        }
        let lambda = SampledWavelengths::sample_visible(0.5);
        let mut sampler = Sampler::new(5, 3, 0);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let e = f64::from(
                free_flight(&m, &r, t_end, &lambda, 3, &mut sampler)
                    .emitted
                    .0
                    .x,
            );
            sum += e;
            sum2 += e * e;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        eprintln!("emission {mean:.5} vs integral {want:.5}, se {se:.2e}");
        assert!(se < 0.005 * want, "too noisy: {se}");
        assert!((mean - want).abs() < 4.5 * se, "{mean} vs {want}");
    }

    /// The homogeneous emission integral in closed form: `j (1 - exp(-sigma d)) / sigma`,
    /// `j d` without extinction, `j / sigma` over an infinite path, and 0 (not NaN) for a dark
    /// lane over an infinite path without extinction.
    #[test]
    fn homogeneous_emission_closed_forms() {
        let j = SampledSpectrum(pt_math::Vec4::new(2.0, 2.0, 0.0, 1.0));
        let s = SampledSpectrum(pt_math::Vec4::new(0.5, 0.0, 0.0, 1e-12));
        let e = homogeneous_emission(j, s, 3.0).0.to_array();
        assert!((e[0] - 2.0 * (1.0 - (-1.5f32).exp()) / 0.5).abs() < 1e-5);
        assert!((e[1] - 6.0).abs() < 1e-5);
        assert_eq!(e[2], 0.0);
        assert!(
            (e[3] - 3.0).abs() < 1e-4,
            "thin lane keeps its digits: {}",
            e[3]
        );
        let inf = homogeneous_emission(j, s, f32::INFINITY).0.to_array();
        assert!((inf[0] - 4.0).abs() < 1e-5);
        assert!(inf[1].is_infinite() && inf[2] == 0.0);
    }
}
