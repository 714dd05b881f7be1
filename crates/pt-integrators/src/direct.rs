//! Direct illumination with several light and BSDF samples per camera hit (Mitsuba 3's
//! `direct` integrator).
//!
//! At the camera ray's hit, `n_e` light samples and `n_b` BSDF samples are combined with
//! Veach's power heuristic weighted by the sample counts (Veach 1997, eq. 9.13 with the counts
//! of eq. 9.10): a sample of strategy i with pdf p_i weighs
//! `(n_i p_i)^2 / ((n_e p_e)^2 + (n_b p_b)^2)` and is divided by `n_i`. The estimate is
//! unbiased for any two counts (one of them 0 leaves the other strategy alone); delta lights
//! and delta BSDF lobes are found by one strategy only and weigh 1. As in Mitsuba, nothing is
//! traced past the first hit except the BSDF samples' rays, which count the emission they find
//! (through a mirror or a mask's hole too), and media are ignored.

use crate::path::{emitted_radiance, escaped_radiance, PathSettings, PathState};
use pt_math::{offset_ray_origin, power_heuristic, Frame, Ray, Vec3};
use pt_render::sampler::RandomSource;
use pt_render::Scene;
use pt_spectrum::SampledSpectrum;

/// Mitsuba `direct`'s sample counts per camera hit (`emitter_samples`, `bsdf_samples`); at
/// least one is positive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadingSamples {
    /// Light samples (next-event estimation) per hit.
    pub emitter: u32,
    /// BSDF samples per hit.
    pub bsdf: u32,
}

/// Estimates the radiance arriving along `path.ray` (a camera ray, `path` as
/// `PathState::new` makes it) with `counts` samples of each strategy at its hit, into
/// `path.radiance`; sets `path.covered` (any hit covers its pixel, as does a visible
/// environment) and ends the path.
pub(crate) fn estimate<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    counts: ShadingSamples,
    path: &mut PathState,
    sampler: &mut S,
) {
    path.alive = false;
    let environment_seen = !scene.infinite_lights.is_empty() && !s.hide_emitters;
    path.covered = environment_seen;
    let ray = path.ray;
    let Some(hit) = scene.intersect(&ray) else {
        if !s.hide_emitters {
            path.radiance +=
                escaped_radiance(scene, ray.dir, &path.lambda, path.throughput, |_| 1.0);
        }
        return;
    };
    path.covered = true;
    if !s.hide_emitters {
        path.radiance +=
            emitted_radiance(scene, &hit, -ray.dir, &path.lambda, path.throughput, |_| {
                1.0
            })
            .unwrap_or(SampledSpectrum::ZERO);
    }
    let material = scene.material(hit.shape);
    let bsdf = scene.bsdf(&hit, &path.lambda);
    // Fluorescence moves some lanes to an excitation wavelength for everything lit below.
    if let Some(f) = material.fluorescent() {
        path.lambda = f.scatter(&path.lambda, sampler.next_1d());
    }
    let lambda = path.lambda;
    let frame = Frame::from_normal_tangent(hit.ns, hit.dpdu);
    let wo = frame.to_local(-ray.dir);
    // Rays leave offset to the side of the surface they leave to.
    let n_out = hit.ng * -hit.ng.dot(ray.dir).signum();
    let origin = |dir: Vec3| offset_ray_origin(hit.p, n_out * n_out.dot(dir).signum());
    // The counts weigh the pdfs in the power heuristic (Veach's n_i p_i).
    let (n_e, n_b) = (counts.emitter as f32, counts.bsdf as f32);
    let mut sum = SampledSpectrum::ZERO;

    if counts.emitter > 0 && bsdf.has_smooth_lobe() {
        let mut lights = SampledSpectrum::ZERO;
        for _ in 0..counts.emitter {
            let Some((li, pmf, u_sel)) = scene.sample_light_at(hit.p, sampler.next_1d()) else {
                let _ = sampler.next_2d();
                continue;
            };
            let Some(ls) = scene.lights[li].sample(hit.p, u_sel, sampler.next_2d(), &lambda) else {
                continue;
            };
            let wi = frame.to_local(ls.wi);
            let f = bsdf.eval(wo, wi);
            if ls.radiance.is_black() || f.is_black() {
                continue;
            }
            let pdf = pmf * ls.pdf;
            let w = if ls.delta {
                1.0
            } else {
                power_heuristic(n_e * pdf, n_b * bsdf.pdf(wo, wi))
            };
            if scene.light_unoccluded(origin(ls.wi), &ls) {
                lights += f * ls.radiance * (wi.z.abs() * w / pdf);
            }
        }
        sum += lights * (1.0 / n_e);
    }

    if counts.bsdf > 0 {
        let mut found = SampledSpectrum::ZERO;
        for _ in 0..counts.bsdf {
            let u_lobe = sampler.next_1d();
            let Some(bs) = bsdf.sample(wo, u_lobe, sampler.next_2d()) else {
                continue;
            };
            if bs.weight.is_black() {
                continue;
            }
            let dir = frame.to_world(bs.wi);
            let next = Ray::new(origin(dir), dir);
            // The weight of emission found along the sampled ray, given the pdf with which
            // light sampling picks the same direction (a delta lobe: light sampling cannot).
            let weight = |light_pdf: f32| {
                if bs.delta {
                    1.0
                } else {
                    power_heuristic(n_b * bs.pdf, n_e * light_pdf)
                }
            };
            found += match scene.intersect(&next) {
                Some(h) => emitted_radiance(scene, &h, -dir, &lambda, bs.weight, |pdf| {
                    weight(pdf.from(hit.p))
                })
                .unwrap_or(SampledSpectrum::ZERO),
                None => escaped_radiance(scene, dir, &lambda, bs.weight, |i| {
                    weight(scene.light_pmf_at(hit.p, i) * scene.lights[i].escaped_pdf(dir))
                }),
            };
        }
        sum += found * (1.0 / n_b);
    }
    path.radiance += path.throughput * sum;
}
