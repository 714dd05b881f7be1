//! Stochastic progressive photon mapping (Hachisuka & Jensen 2009, "Stochastic Progressive
//! Photon Mapping"), with the radius schedule of Knaus & Zwicker 2011 ("Progressive Photon
//! Mapping: A Probabilistic Approach"): a pt extension (`<integrator type="sppm">`;
//! Mitsuba 3 has no photon mapper).
//!
//! Each iteration (one per sample per pixel):
//! 1. *Camera pass.* Every pixel traces one camera ray (its film position drawn from the
//!    filter, as `--reconstruction importance` does). Along it, emission is counted where the
//!    ray meets an emitter or leaves the scene. At every surface with a non-specular lobe the
//!    path leaves a *visible point* (its position, BSDF, direction to the camera and
//!    throughput) and estimates direct light there by light sampling; it then goes on only
//!    through specular (delta) lobes, so a mirror, glass or a smooth plastic's coating shows
//!    what lies behind, and stops when the BSDF sample is not specular.
//! 2. *Photon pass.* `photons_per_iteration` paths from the lights
//!    ([`crate::ptracer::walk_light_path`]: the light tracer's paths, importance transport).
//!    Every surface a photon meets after its first (direct light is step 1's) adds
//!    `f(wo, wi) beta` to each visible point within the radius `r_i` on a surface facing the
//!    same way, where `wi` is the photon's arriving direction and `beta` its weight.
//! 3. The pixel's estimate of this iteration is its direct light plus, per visible point,
//!    `throughput * sum / (N pi r_i^2)` (N photons): a density estimate with the constant
//!    kernel over the disc of radius r_i (Jensen 1996's radiance estimate, in its SPPM form).
//!
//! The image is the mean of the iterations' estimates. The radius shrinks as
//! `r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1)` (Knaus & Zwicker 2011's radius sequence; alpha in (0, 1),
//! 2/3 by default), so the kernel's bias vanishes while the variance of the mean still falls:
//! the estimate is consistent, with a mean squared error falling as N^-alpha in the number of
//! iterations (their analysis of the sequence). It is biased at any finite count: blurred by the kernel
//! (caustics and shadows spread over r), darkened near edges and corners where the disc leaves
//! the surface. The initial radius defaults to 1% of the scene's bounding sphere radius.
//!
//! `max_depth` counts segments as the path tracer does: a photon deposit at a visible point
//! found after `c` camera segments, by a photon that travelled `p` segments, forms a path of
//! `c + p` segments. Each iteration uses one set of wavelengths for all its camera and photon
//! paths (pbrt-v4's SPPM), so photons and visible points meet at the same wavelengths.
//! Fluorescence: photons end where they meet a fluorescent surface, and the paths through one
//! are the camera side's, estimated by the path tracer's strategies from the first hit on
//! ([`crate::path::li_through_fluorescence`], which says why): consistent as before.
//!
//! Determinism: the camera pass is per pixel, photons are traced in chunks whose deposits are
//! added in photon order, and the grid is built in visible-point order: the image is the same
//! for any number of threads. An iteration's radius, wavelengths and random streams follow
//! from its index, so the pixels' statistics are the whole state: a saved render resumes
//! exactly. Variance: each pixel's estimates over the iterations (not
//! identically distributed while the radius shrinks; the written variance treats them as
//! independent samples).

use crate::grid::PointGrid;
use crate::path::PathSettings;
use crate::ptracer::{shading_frame, to_rgb, walk_light_path, AtFluorescence};
use pt_bsdf::SurfaceBsdf;
use pt_math::{offset_ray_origin, Frame, Ray, Vec3};
use pt_render::film::sample_pixel_offset;
use pt_render::sampler::Sampler;
use pt_render::{RenderOutput, Scene};
use pt_spectrum::{ColorMode, SampledSpectrum, SampledWavelengths};
use rayon::prelude::*;
use std::sync::atomic::AtomicBool;

/// The photon mapper's own settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppmSettings {
    /// Photons traced per iteration; `None`: as many as the image has pixels.
    pub photons: Option<u64>,
    /// Radius of the first iteration (scene units); `None`: 1% of the scene's bounding sphere
    /// radius.
    pub initial_radius: Option<f32>,
    /// Knaus & Zwicker's alpha in (0, 1): the fraction of the previous iteration's density
    /// estimate kept (2/3 by default).
    pub alpha: f32,
}

impl Default for SppmSettings {
    fn default() -> Self {
        SppmSettings {
            photons: None,
            initial_radius: None,
            alpha: 2.0 / 3.0,
        }
    }
}

/// The key of the photons' random streams (above every pixel key).
const PHOTON_STREAM: u64 = (1 << 63) | 0x5048_4f54_4f4e; // "PHOTON"
/// Photons per work item (each keeps its deposits in one list).
const CHUNK: u64 = 4096;
/// Most segments of a camera path through specular surfaces when `max_depth` is unlimited.
const MAX_SPECULAR_CHAIN: u32 = 64;

/// One image row's camera pass: per pixel its direct light and filter weight, and the row's
/// visible points.
type CameraRow = (Vec<(SampledSpectrum, f32)>, Vec<VisiblePoint>);

/// A camera path's stop at a surface with a non-specular lobe.
struct VisiblePoint {
    /// The pixel (row-major index in the image).
    pixel: u32,
    /// Position, world space.
    p: Vec3,
    /// Geometric normal, world space.
    ng: Vec3,
    /// Shading frame.
    frame: Frame,
    /// Unit direction towards the camera, local frame.
    wo: Vec3,
    /// The BSDF at the iteration's wavelengths.
    bsdf: SurfaceBsdf,
    /// The camera path's throughput up to here.
    beta: SampledSpectrum,
    /// Segments from the camera to here.
    segments: u32,
}

/// The squared radius of iteration `i` (0-based): r_0^2 prod_{k=1}^{i} (k + alpha) / (k + 1)
/// (Knaus & Zwicker 2011's sequence, counting iterations from 1).
pub fn radius_squared(r0: f32, alpha: f32, i: u32) -> f64 {
    let mut r2 = f64::from(r0) * f64::from(r0);
    for k in 1..=i {
        r2 *= (f64::from(k) + f64::from(alpha)) / (f64::from(k) + 1.0);
    }
    r2
}

/// Step 1 for one pixel: its direct light (emission and light sampling along the camera path)
/// and its visible points, appended to `out`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn camera_path(
    scene: &Scene,
    s: &PathSettings,
    settings: &crate::RenderSettings,
    lambda: &SampledWavelengths,
    (x, y): (u32, u32),
    iteration: u32,
    out: &mut Vec<VisiblePoint>,
) -> (SampledSpectrum, f32) {
    let pixel = y * settings.width + x;
    let (mut sampler, mut ray, weight) = pixel_ray(scene, settings, (x, y), iteration);
    let mut beta = unit(scene);
    let mut radiance = SampledSpectrum::ZERO;
    let max_segments = if s.max_depth < 0 {
        MAX_SPECULAR_CHAIN
    } else {
        s.max_depth as u32
    };
    // Segments traced so far (the camera ray is the first).
    let mut segments = 1u32;
    // Whether the paths through a fluorescent surface are counted already (photons end at
    // one: from the first visible point on, the path tracer takes them).
    let mut fluorescence_counted = !scene.has_fluorescence();
    loop {
        let seen = segments > 1 || !s.hide_emitters;
        let Some(hit) = scene.intersect(&ray) else {
            if seen {
                radiance += crate::path::escaped_radiance(scene, ray.dir, lambda, beta, |_| 1.0);
            }
            break;
        };
        let w_cam = -ray.dir;
        if seen {
            if let Some((_, light)) = scene.shape_light(hit.shape) {
                radiance += beta * light.emitted(hit.ns, w_cam, hit.uv, lambda);
            }
        }
        if segments >= max_segments {
            break;
        }
        let fluorescent = scene.material(hit.shape).fluorescent().is_some();
        radiance += crate::path::fluorescence_once(
            scene,
            (ray, beta, segments - 1),
            s,
            &mut sampler,
            lambda,
            &mut fluorescence_counted,
        );
        if fluorescent {
            // Every path on from here scatters at a fluorescent surface: counted above.
            break;
        }
        let bsdf = scene.bsdf(&hit, lambda);
        let frame = shading_frame(&hit);
        let wo = frame.to_local(w_cam);
        let out_side = hit.ng * hit.ng.dot(w_cam).signum();
        if bsdf.has_smooth_lobe() {
            out.push(VisiblePoint {
                pixel,
                p: hit.p,
                ng: hit.ng,
                frame,
                wo,
                bsdf: *bsdf,
                beta,
                segments,
            });
            // Direct light by light sampling (the camera path does not go on through this
            // lobe, so nothing else finds the light from here).
            if let Some((li, pmf, u_sel)) = scene.sample_light_at(hit.p, sampler.next_1d()) {
                let u = sampler.next_2d();
                if let Some(ls) = scene.lights[li].sample(hit.p, u_sel, u, lambda) {
                    let wi = frame.to_local(ls.wi);
                    let f = bsdf.eval(wo, wi);
                    if !f.is_black() && !ls.radiance.is_black() && ls.pdf > 0.0 {
                        let origin = offset_ray_origin(hit.p, hit.ng * hit.ng.dot(ls.wi).signum());
                        if scene.light_unoccluded(origin, &ls) {
                            radiance += beta * f * ls.radiance * (wi.z.abs() / (ls.pdf * pmf));
                        }
                    }
                }
            } else {
                let _ = sampler.next_2d();
            }
        }
        // Go on through specular lobes only.
        let u_lobe = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u_lobe, sampler.next_2d()) else {
            break;
        };
        if !bs.delta {
            break;
        }
        beta *= bs.weight;
        if beta.is_black() || !beta.is_finite() {
            break;
        }
        let dir = frame.to_world(bs.wi);
        let side = if dir.dot(out_side) >= 0.0 {
            out_side
        } else {
            -out_side
        };
        ray = Ray::new(offset_ray_origin(hit.p, side), dir);
        segments += 1;
    }
    (radiance, weight)
}

/// The camera ray of pixel (x, y) in iteration `iteration` (its film position drawn from the
/// filter, as `--reconstruction importance` does), the pixel's sampler for what follows, and
/// the sample's filter weight.
pub(crate) fn pixel_ray(
    scene: &Scene,
    settings: &crate::RenderSettings,
    (x, y): (u32, u32),
    iteration: u32,
) -> (Sampler, Ray, f32) {
    let key = settings.pixel_key(x as i32, y as i32);
    let mut sampler = Sampler::new(settings.seed, key, u64::from(iteration));
    let (offset, weight) = sample_pixel_offset(
        &settings.filter,
        &mut sampler,
        (x, y),
        (settings.width, settings.height),
        settings.sample_border,
    );
    let u_lens = sampler.next_2d();
    let ray = scene.camera.pixel_ray(x as i32, y as i32, offset, u_lens);
    (sampler, ray, weight)
}

/// A path's initial throughput, 1 in the scene's colour mode.
pub(crate) fn unit(scene: &Scene) -> SampledSpectrum {
    match scene.mode {
        ColorMode::Spectral => SampledSpectrum::splat(1.0),
        ColorMode::Rgb => SampledSpectrum::from_rgb([1.0; 3]),
    }
}

/// Renders `settings.spp` iterations of SPPM into `state` (its pixels' statistics), checking
/// `cancel` between iterations. Returns whether all were done.
pub fn render_sppm_passes(
    scene: &Scene,
    settings: &crate::RenderSettings,
    sppm: &SppmSettings,
    state: &mut crate::RenderState,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> bool {
    let (w, h) = (settings.width, settings.height);
    let pixels = u64::from(w) * u64::from(h);
    let photons = sppm.photons.unwrap_or(pixels).max(1);
    let r0 = sppm.initial_radius.unwrap_or(0.01 * scene.bounds.1);
    let s = &settings.path;
    // One iteration per pass: each builds its own grid of visible points.
    crate::render::in_passes(
        state,
        settings.spp,
        cancel,
        &mut |_| {},
        1,
        1,
        |state, its| {
            let it = its.start;
            let r2 = radius_squared(r0, sppm.alpha, it);
            let r = r2.sqrt() as f32;
            let lambda = crate::render::iteration_wavelengths(scene, settings.seed, it);
            // 1. Camera pass, row by row.
            let rows: Vec<CameraRow> = (0..h)
                .into_par_iter()
                .map(|y| {
                    let mut points = Vec::new();
                    // Dispatched per row: the camera paths inlined into one function per
                    // instruction set (`pt_render::isa`).
                    let direct = pt_render::isa::best(
                        #[inline(always)]
                        || {
                            (0..w)
                                .map(|x| {
                                    camera_path(
                                        scene,
                                        s,
                                        settings,
                                        &lambda,
                                        (x, y),
                                        it,
                                        &mut points,
                                    )
                                })
                                .collect()
                        },
                    );
                    progress(u64::from(w) / 2);
                    (direct, points)
                })
                .collect();
            let mut direct = Vec::with_capacity(pixels as usize);
            let mut points = Vec::new();
            for (d, p) in rows {
                direct.extend(d);
                points.extend(p);
            }
            // 2. Photon pass.
            let grid = PointGrid::new(
                points
                    .iter()
                    .enumerate()
                    .map(|(i, vp)| (vp.p, i as u32))
                    .collect(),
                r,
            );
            let chunks = photons.div_ceil(CHUNK);
            let max_depth = s.depth_limit();
            let deposits: Vec<Vec<(u32, SampledSpectrum)>> = (0..chunks)
                .into_par_iter()
                .map(|c| {
                    let mut out = Vec::new();
                    let first = c * CHUNK;
                    let end = (first + CHUNK).min(photons);
                    // Dispatched per chunk, as the camera pass.
                    pt_render::isa::best(
                        #[inline(always)]
                        || {
                            for k in first..end {
                                let index = u64::from(it) * photons + k;
                                let mut sampler = Sampler::new(settings.seed, PHOTON_STREAM, index);
                                walk_light_path::<_, false>(
                                    scene,
                                    s,
                                    &mut sampler,
                                    &lambda,
                                    AtFluorescence::Absorb,
                                    |v, _| {
                                        if v.depth < 2 {
                                            return;
                                        }
                                        grid.within(v.hit.p, |&i| {
                                            let vp = &points[i as usize];
                                            if vp.ng.dot(v.hit.ng) <= 0.0
                                                || vp.segments.saturating_add(v.depth) > max_depth
                                            {
                                                return;
                                            }
                                            let f =
                                                vp.bsdf.eval(vp.wo, vp.frame.to_local(v.w_light));
                                            if !f.is_black() {
                                                out.push((i, f * v.beta));
                                            }
                                        });
                                    },
                                    // Scenes with media are refused before this method runs.
                                    |_, _| {},
                                );
                            }
                        },
                    );
                    progress(((end - first) * pixels / photons) / 2);
                    out
                })
                .collect();
            // 3. The iteration's estimate per pixel.
            let mut gathered = vec![SampledSpectrum::ZERO; points.len()];
            for (i, phi) in deposits.iter().flatten() {
                gathered[*i as usize] += *phi;
            }
            let norm = (1.0 / (photons as f64 * std::f64::consts::PI * r2)) as f32;
            let mut indirect = vec![SampledSpectrum::ZERO; pixels as usize];
            for (vp, g) in points.iter().zip(&gathered) {
                indirect[vp.pixel as usize] += vp.beta * *g * norm;
            }
            for ((stats, (d, weight)), ind) in state.pixels.iter_mut().zip(&direct).zip(&indirect) {
                let rgb = to_rgb(scene, *d + *ind, &lambda).map(|c| c * weight);
                stats.add(rgb, 1.0);
            }
        },
    )
}

/// Whether `sppm` settings are valid; the reason when they are not.
pub fn check(sppm: &SppmSettings) -> Result<(), String> {
    if !(sppm.alpha > 0.0 && sppm.alpha < 1.0) {
        return Err(format!(
            "sppm: alpha must lie in (0, 1), got {}",
            sppm.alpha
        ));
    }
    if let Some(r) = sppm.initial_radius {
        if !(r > 0.0 && r.is_finite()) {
            return Err(format!("sppm: initial_radius must be positive, got {r}"));
        }
    }
    Ok(())
}

/// An empty state for SPPM with `settings`: per-pixel statistics of the iterations' estimates
/// (no splatting film: each camera path's film position is drawn from the filter).
pub fn new_state(settings: &crate::RenderSettings) -> crate::RenderState {
    crate::RenderState::new(&crate::RenderSettings {
        reconstruction: pt_scene::Reconstruction::Importance,
        moment: false,
        ..settings.clone()
    })
}

/// Renders the image by SPPM (`settings.spp` iterations) into a new state's statistics.
pub fn render(
    scene: &Scene,
    settings: &crate::RenderSettings,
    sppm: &SppmSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    let mut state = new_state(settings);
    render_sppm_passes(
        scene,
        settings,
        sppm,
        &mut state,
        &AtomicBool::new(false),
        progress,
    );
    let mut out = state.output();
    out.alpha = None;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Knaus & Zwicker's schedule: r_2^2 = r_1^2 (1 + alpha) / 2, and the product telescopes
    /// towards r^2 ~ i^(alpha - 1): over i from 1000 to 8000 the squared radius
    /// falls by 8^(alpha - 1) within 0.5%.
    #[test]
    fn radius_follows_knaus_zwicker() {
        let a = 2.0 / 3.0;
        assert!((radius_squared(1.0, a, 1) - (1.0 + f64::from(a)) / 2.0).abs() < 1e-12);
        let ratio = radius_squared(1.0, a, 8000) / radius_squared(1.0, a, 1000);
        let want = 8f64.powf(f64::from(a) - 1.0);
        assert!((ratio / want - 1.0).abs() < 5e-3, "{ratio} vs {want}");
    }
}
