//! Light tracing (Mitsuba 3.9.1's `ptracer`, the particle tracer): paths start at the lights
//! and every vertex is connected to the camera, its contribution splatted where it lands on
//! the film (Arvo & Kirk 1990; Veach 1997, ch. 10, the bidirectional strategies with one
//! camera vertex, t = 1).
//!
//! Per light path, as Mitsuba's `ptracer` does:
//! 1. *Emitters seen directly* (unless `hide_emitters`, or `max_depth` 0): a light is chosen
//!    and, for an area light, a point on it by area is connected to the camera; distant lights
//!    (environment, sun) are seen by a camera ray through a film point uniform over the image
//!    (where Mitsuba draws a direction from the light, mostly outside the image: the same
//!    expected image, with far less noise). Delta lights cannot be seen.
//! 2. *A ray from a light* ([`pt_render::light::EmittedRay`]), traced through the scene by
//!    BSDF sampling; at every surface it meets, the vertex is connected to the camera:
//!    `beta f(w_cam, w_light) |cos_s(w_light)| |ng . w_cam| / |ng . w_light| W`, where `f` is the
//!    BSDF the path tracer evaluates for the same path, the cosine factors are the adjoint BSDF
//!    for shading normals (Veach 1997, sec. 5.3) and `W` the camera's weight
//!    ([`pt_render::camera::CameraConnection::weight`]). Sampling a BSDF from the light's side
//!    gives radiance-transport weights; refraction multiplies them by `eta^2` for importance
//!    transport (Veach 1997, sec. 5.2; pbrt-v4's `TransportMode::Importance`). Vertices and
//!    directions where the shading and geometric normals disagree are dropped (light leaks).
//!
//! *Participating media* (Mitsuba's `ptracer` has none; pt's follows its `volpath`): a light
//! path in a medium takes a free flight ([`crate::volpath::free_flight`]: the same sampling
//! and weights, media being reciprocal) and, where it scatters, is connected to the camera with
//! `beta phase(w_cam, w_light) W` and continues in a direction the phase function samples; a
//! path changes medium where it crosses a medium boundary, a pass straight through a surface
//! (a null wall) is not a bounce, and every connection to the camera (surface and medium
//! vertices, emitters and distant lights seen directly) carries the transmittance of the media
//! and null surfaces between ([`crate::volpath::transmittance_to`]). A light path starts in the
//! medium its first medium boundary says it is in ([`light_medium`]).
//!
//! Fluorescent surfaces (a pt extension) scatter light paths by the adjoint of the camera
//! paths' rule (`pt_render::fluorescence`): light arriving at `li` is reflected at `li` or
//! re-emitted at a longer wavelength drawn from the emission spectrum over wavelength, with
//! the weight `r(li) + Q a(li) li int_{li} e(l) / l dl`; the film then weighs each lane at the
//! wavelength it reaches the camera with the density it was drawn with at the light.
//!
//! Depth follows Mitsuba: `max_depth` counts segments including the one to the camera
//! (1: emitters seen directly, 2: direct illumination); Russian roulette after `rr_depth`
//! segments keeps a path with probability min(max(beta) eta^2, 0.95).
//!
//! The image: every pass traces, per sample per pixel, as many light paths as the image has
//! pixels; a splat of contribution `c` adds `c P_film / P_image` times its normalised filter
//! weights ([`pt_render::film::light::LightFilm`]), P the pixel counts of the whole film and of
//! the image (a crop window), so each pixel's value is the measurement of its filter over the
//! film: what the path tracer estimates. Splats are kept per chunk of light paths and added
//! in path order, so the image is the same for any number of threads.
//!
//! Variance: each batch of light paths (one sample per pixel) is an independent estimate of
//! the image. Each pixel keeps the statistics of its value over the batches, taken without the
//! filter (a splat counted in the pixel it lands in): the variance of a region's mean is then
//! the sum of its pixels' variances, what block tests need, where the filtered pixels share
//! splats with their neighbours and would understate it.

use crate::path::PathSettings;
use crate::volpath::{free_flight, transmittance_to};
use pt_bsdf::{Bsdf, Lambert, SurfaceBsdf};
use pt_math::{offset_ray_origin, Frame, Ray, Vec2, Vec3};
use pt_render::film::light::LightFilm;
pub(crate) use pt_render::film::light::Splat;
use pt_render::geometry::Interaction;
use pt_render::light::{Light, LightSample};
use pt_render::medium::Phase;
use pt_render::sampler::{RandomSource, Sampler};
use pt_render::Scene;
use pt_spectrum::{spectrum_to_srgb, ColorMode, SampledSpectrum, SampledWavelengths};
use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::atomic::AtomicBool;

/// The key of the light paths' random streams (in the place of a pixel's: above every pixel
/// key, see `RenderSettings::pixel_key`).
const LIGHT_STREAM: u64 = (1 << 63) | 0x4c_4947_4854; // "LIGHT"

/// Light paths per work item: each item's splats are kept in one list.
const CHUNK: u64 = 1024;

/// Most light paths in one pass (their splats are held until the pass ends: about 8 splats of
/// 20 bytes per path, so 40 MB).
const MAX_PASS_PATHS: u64 = 1 << 18;

/// The shading frame of a hit: the same as the path tracer's (oriented by dp/du when the
/// surface has a parameterisation, for anisotropic models).
#[inline(always)]
pub(crate) fn shading_frame(hit: &Interaction) -> Frame {
    if hit.dpdu == Vec3::ZERO {
        Frame::from_normal(hit.ns)
    } else {
        Frame::from_normal_tangent(hit.ns, hit.dpdu)
    }
}

/// The colour of a contribution at the path's wavelengths: linear sRGB.
#[inline(always)]
pub(crate) fn to_rgb(scene: &Scene, c: SampledSpectrum, lambda: &SampledWavelengths) -> [f32; 3] {
    match scene.mode {
        ColorMode::Spectral => spectrum_to_srgb(c, lambda),
        ColorMode::Rgb => c.rgb(),
    }
}

/// Traces one light path (steps 1 and 2 of the module documentation) and appends its splats.
/// `inv_scale` is P_image / P_film, the inverse of the scale every splat gets (see the module
/// documentation), for contributions sampled uniformly over the image; `rgb_lambda` the
/// (unused) wavelengths of RGB mode, made once.
#[inline(always)]
fn trace_light_path<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    sampler: &mut S,
    inv_scale: f32,
    rgb_lambda: &SampledWavelengths,
    out: &mut Vec<Splat>,
) {
    let lambda = match scene.mode {
        ColorMode::Spectral => SampledWavelengths::sample_visible(sampler.next_1d()),
        ColorMode::Rgb => *rgb_lambda,
    };
    let camera = &scene.camera;
    let one = match scene.mode {
        ColorMode::Spectral => SampledSpectrum::splat(1.0),
        ColorMode::Rgb => SampledSpectrum::from_rgb([1.0; 3]),
    };
    // A contribution at the wavelengths `at` (the path's, moved by fluorescence).
    let mut push = |film: Vec2, c: SampledSpectrum, at: &SampledWavelengths| {
        if !c.is_black() {
            out.push(Splat {
                film,
                rgb: to_rgb(scene, c, at),
                camera: false,
            });
        }
    };
    if s.max_depth != 0 && !s.hide_emitters {
        // Area lights seen directly: a point on one, connected to the camera.
        if let Some((li, pmf, u_sel)) = scene.sample_light(sampler.next_1d()) {
            let (u, u_lens) = (sampler.next_2d(), sampler.next_2d());
            if let Light::Area(a) = &scene.lights[li] {
                let pt = a.sample_position(u_sel, u);
                if let Some(cc) = camera.connect(pt.p, u_lens) {
                    let cos = pt.n.dot(cc.dir);
                    let le = a.emitted(pt.n, cc.dir, pt.uv, &lambda);
                    let origin = offset_ray_origin(pt.p, pt.n);
                    if cos > 0.0 && !le.is_black() {
                        let seen = if scene.has_media() {
                            // Through media and null surfaces, from the medium around the light.
                            let start = light_medium(scene, &Ray::new(origin, cc.dir));
                            camera_transmittance(scene, origin, &cc, start, &lambda, sampler)
                        } else if scene.segment_unoccluded(origin, cc.camera_point) {
                            one
                        } else {
                            SampledSpectrum::ZERO
                        };
                        push(
                            cc.film,
                            le * seen * (cos * cc.weight / (pt.pdf_area * pmf)),
                            &lambda,
                        );
                    }
                }
            }
        }
        // Distant lights seen directly (environment, sun): a camera ray through a film point
        // uniform over the image that leaves the scene. Mitsuba instead draws a direction from
        // the light's own distribution, most of which miss the image; both estimate the same
        // integral of W_e L_e, this one with the path tracer's first-segment noise.
        if !scene.infinite_lights.is_empty() {
            let (u_film, u_lens) = (sampler.next_2d(), sampler.next_2d());
            let film = u_film * camera.image_size();
            let (x, y) = (film.x.floor(), film.y.floor());
            let ray = camera.pixel_ray(
                x as i32,
                y as i32,
                film - Vec2::new(x + 0.5, y + 0.5),
                u_lens,
            );
            // What reaches the camera from beyond the scene: all of it without media when no
            // surface is in the way; with media, through them and through null surfaces.
            let seen = if scene.has_media() {
                let far = LightSample {
                    p: ray.origin,
                    n: Vec3::ZERO,
                    wi: ray.dir,
                    dist: f32::INFINITY,
                    radiance: SampledSpectrum::ZERO,
                    pdf: 1.0,
                    delta: false,
                };
                transmittance_to(
                    scene,
                    ray.origin,
                    &far,
                    scene.camera_medium,
                    &lambda,
                    sampler,
                )
            } else if scene.intersect(&ray).is_none() {
                one
            } else {
                SampledSpectrum::ZERO
            };
            if !seen.is_black() {
                let le = crate::path::escaped_radiance(scene, ray.dir, &lambda, one, |_| 1.0);
                push(film, le * seen * inv_scale, &lambda);
            }
        }
    }

    // A ray from a light, and every surface and medium point it meets connected to the camera
    // (the medium points' splats kept apart while the walk holds `out`).
    let mut in_media = Vec::new();
    walk_light_path::<_, false>(
        scene,
        s,
        sampler,
        &lambda,
        AtFluorescence::Adjoint,
        #[inline(always)]
        |v, sampler| {
            if let Some(seen) = seen_by_camera(scene, v, sampler) {
                out.push(Splat {
                    film: seen.connection.film,
                    rgb: to_rgb(scene, seen.contribution, &v.lambda),
                    camera: false,
                });
            }
        },
        #[inline(always)]
        |v, sampler| {
            if let Some((film, c)) = medium_seen_by_camera(scene, v, sampler) {
                in_media.push(Splat {
                    film,
                    rgb: to_rgb(scene, c, &v.lambda),
                    camera: false,
                });
            }
        },
    );
    out.append(&mut in_media);
}

/// A light path's vertex seen by the camera ([`seen_by_camera`]).
pub(crate) struct CameraSight {
    /// The connection (film position, importance).
    pub connection: pt_render::camera::CameraConnection,
    /// The direction to the camera, the vertex's local frame.
    pub wc: Vec3,
    /// |ng . direction to the camera|.
    pub cos: f32,
    /// `beta f(w_cam, w_light) |cos_s(w_light)| |ng . w_cam| / |ng . w_light| W`: what the vertex
    /// adds to the measurement (see the module documentation).
    pub contribution: SampledSpectrum,
}

/// Connects a light path's vertex to the camera (`u_lens` picks a thin lens's point): `None`
/// when the camera cannot see it, the BSDF sends nothing that way, or the segment is blocked.
#[inline(always)]
pub(crate) fn seen_by_camera<S: RandomSource>(
    scene: &Scene,
    v: &LightVertex,
    sampler: &mut S,
) -> Option<CameraSight> {
    let cc = scene.camera.connect(v.hit.p, sampler.next_2d())?;
    let wc = v.frame.to_local(cc.dir);
    let ng_cam = v.hit.ng.dot(cc.dir);
    if ng_cam * wc.z <= 0.0 {
        return None;
    }
    let f = v.bsdf.eval(wc, v.wl);
    if f.is_black() {
        return None;
    }
    let adjoint = v.wl.z.abs() * ng_cam.abs() / v.ng_light.abs();
    let origin = offset_ray_origin(v.hit.p, v.hit.ng * ng_cam.signum());
    let contribution = v.beta * f * (adjoint * cc.weight);
    let contribution = if scene.has_media() {
        // Through media and null surfaces: starting in the medium on the camera's side.
        let start = match scene.medium_boundary(v.hit.shape) {
            Some((_, outside)) if ng_cam > 0.0 => outside,
            Some((inside, _)) => inside,
            None => v.medium,
        };
        contribution * camera_transmittance(scene, origin, &cc, start, &v.lambda, sampler)
    } else if scene.segment_unoccluded(origin, cc.camera_point) {
        contribution
    } else {
        SampledSpectrum::ZERO
    };
    (!contribution.is_black()).then_some(CameraSight {
        contribution,
        connection: cc,
        wc,
        cos: ng_cam.abs(),
    })
}

/// The transmittance from `origin` (in `medium`) to the camera point of `cc`: media and the
/// straight-through transmission of the surfaces between (the volumetric path tracer's shadow
/// rays, [`transmittance_to`]).
#[inline(always)]
fn camera_transmittance<S: RandomSource>(
    scene: &Scene,
    origin: Vec3,
    cc: &pt_render::camera::CameraConnection,
    medium: Option<u32>,
    lambda: &SampledWavelengths,
    sampler: &mut S,
) -> SampledSpectrum {
    let target = LightSample {
        p: cc.camera_point,
        n: Vec3::ZERO,
        wi: cc.dir,
        dist: cc.dist,
        radiance: SampledSpectrum::ZERO,
        pdf: 1.0,
        delta: true,
    };
    transmittance_to(scene, origin, &target, medium, lambda, sampler)
}

/// A medium vertex seen by the camera: its contribution `beta phase(w_cam, w_light) W T` and
/// where it lands, or `None` when nothing arrives.
#[inline(always)]
fn medium_seen_by_camera<S: RandomSource>(
    scene: &Scene,
    v: &MediumVertex,
    sampler: &mut S,
) -> Option<(Vec2, SampledSpectrum)> {
    let cc = scene.camera.connect(v.p, sampler.next_2d())?;
    let phase = v.phase.eval(cc.dir, v.w_light);
    if !(phase > 0.0) {
        return None;
    }
    let tr = camera_transmittance(scene, v.p, &cc, v.medium, &v.lambda, sampler);
    let c = v.beta * tr * (phase * cc.weight);
    (!c.is_black()).then_some((cc.film, c))
}

/// The medium a light's ray starts in, found by the first medium boundary the ray meets: the
/// shape's interior when it meets the boundary from inside, its exterior otherwise; vacuum if
/// it meets none. For a scene whose media agree with its geometry this is the medium around the
/// light (an area light's declared exterior included), and it is the volumetric path tracer's
/// view of a light inside a medium (its shadow rays carry the receiver's media up to the light).
fn light_medium(scene: &Scene, ray: &Ray) -> Option<u32> {
    let mut ray = *ray;
    for _ in 0..MAX_MEDIUM_PROBES {
        let hit = scene.intersect(&ray)?;
        let ng_dir = hit.ng.dot(ray.dir);
        if let Some((inside, outside)) = scene.medium_boundary(hit.shape) {
            return if ng_dir > 0.0 { inside } else { outside };
        }
        ray = Ray::new(offset_ray_origin(hit.p, hit.ng * ng_dir.signum()), ray.dir);
    }
    None
}

/// Most surfaces [`light_medium`] passes on its way to a medium boundary.
const MAX_MEDIUM_PROBES: u32 = 64;

/// A surface a light path meets (see [`walk_light_path`]).
pub(crate) struct LightVertex<'a, 's> {
    /// The hit, world space.
    pub hit: &'a Interaction,
    /// Its BSDF at the path's wavelengths (borrowed from the scene's material when it is the
    /// same all over the surface: the bidirectional methods keep that reference).
    pub bsdf: &'a Cow<'s, SurfaceBsdf>,
    /// Its shading frame (the path tracer's).
    pub frame: Frame,
    /// Unit direction towards the previous vertex (the light's side), local frame.
    pub wl: Vec3,
    /// The same direction, world space.
    pub w_light: Vec3,
    /// The geometric normal's cosine with the direction towards the previous vertex.
    pub ng_light: f32,
    /// The path's weight arriving here: emitted power over the densities, importance
    /// transport (see the module documentation).
    pub beta: SampledSpectrum,
    /// The wavelengths the light leaves this vertex at (a fluorescent surface moves lanes to
    /// longer ones; the pdfs stay those of the light's sampling).
    pub lambda: SampledWavelengths,
    /// Segments from the light to here (1 at the first surface).
    pub depth: u32,
    /// How the path arrived here (what the bidirectional methods weigh strategies with).
    pub arrival: Arrival,
    /// The medium the path arrived through (index into the scene's media; `None`: vacuum).
    pub medium: Option<u32>,
}

/// A point inside a medium where a light path scatters (see [`walk_light_path`]; only the
/// light tracer walks scenes with media).
pub(crate) struct MediumVertex<'a> {
    /// The point, world space.
    pub p: Vec3,
    /// Unit direction towards the previous vertex (the light's side), world space.
    pub w_light: Vec3,
    /// The medium's phase function.
    pub phase: &'a Phase,
    /// The medium (index into the scene's media).
    pub medium: Option<u32>,
    /// The path's weight arriving here, times the free flight's `sigma_s T / p`.
    pub beta: SampledSpectrum,
    /// The wavelengths of the path.
    pub lambda: SampledWavelengths,
}

/// How a light path reached a vertex ([`LightVertex::arrival`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Arrival {
    /// Straight from the light `light` (chosen with probability `pmf`) by the ray `ray`.
    Emitted {
        /// The light's index in the scene.
        light: usize,
        /// Its selection probability.
        pmf: f32,
        /// The ray and its densities.
        ray: pt_render::light::EmittedRay,
    },
    /// Scattered at the previous vertex: the solid-angle densities of the direction taken as
    /// sampled from the light's side (`fwd`) and of the opposite choice (`rev`: sampling the
    /// direction back towards the light from the direction taken; computed only when the
    /// walk is asked for it), the geometric cosine of the direction taken there, and whether
    /// a delta lobe was sampled.
    Scattered {
        /// Forward density, per unit solid angle.
        fwd: f32,
        /// Reverse density, per unit solid angle.
        rev: f32,
        /// |ng . direction taken| at the previous vertex.
        cos_out: f32,
        /// Whether the lobe sampled was a delta lobe.
        delta: bool,
    },
}

/// What a light path does where it meets a fluorescent surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum AtFluorescence {
    /// Scatter by the adjoint of the camera paths' rule (the module documentation): the light
    /// tracer's way.
    Adjoint,
    /// End on arrival, unseen: the methods that leave paths through fluorescent surfaces to
    /// the camera side ([`crate::path::li_through_fluorescence`]).
    Absorb,
}

/// Traces a path from a light: a light chosen by the scene's light selection, a ray from it
/// ([`Light::sample_emission`]), then BSDF sampling from the light's side with importance
/// transport weights (refraction's `eta^2`, the adjoint's shading normal correction), Russian
/// roulette after `rr_depth` segments (keeping min(max(beta) eta^2, 0.95)), up to `max_depth`
/// segments counting one more to the eye (Mitsuba's `ptracer`). `visit` sees every surface
/// met, before the path leaves it, with the sampler for its own numbers. Vertices whose
/// arriving or leaving direction lies on different sides of the shading and geometric
/// normals end the path (light leaks). At fluorescent surfaces the walk does what
/// `fluorescence` says. `BIDIR`: the walk of the bidirectional methods:
/// [`Arrival::Scattered`] carries the reverse density (one more BSDF evaluation per bounce),
/// and Russian roulette weighs the throughput relative to the emitted ray's weight, as the
/// camera side weighs its own (where Mitsuba's `ptracer` compares the weight itself, in the
/// light's power units, with 1: a bright light's paths then run until the 0.95 cap stops them,
/// each vertex connecting to every camera vertex), from the first bounce on.
#[inline(always)]
pub(crate) fn walk_light_path<'s, S: RandomSource, const BIDIR: bool>(
    scene: &'s Scene,
    s: &PathSettings,
    sampler: &mut S,
    lambda: &SampledWavelengths,
    fluorescence: AtFluorescence,
    mut visit: impl FnMut(&LightVertex<'_, 's>, &mut S),
    mut visit_medium: impl FnMut(&MediumVertex, &mut S),
) {
    let Some((li, pmf, emitted)) = sample_emitted(scene, lambda, sampler) else {
        return;
    };
    let mut beta = emitted.weight * (1.0 / pmf);
    let rr_norm = if BIDIR { 1.0 / beta.max_value() } else { 1.0 };
    // The bidirectional methods' light subpaths play Russian roulette from their first bounce
    // on, as the reference implementation of Georgiev et al. 2012 (SmallVCM) does: every
    // vertex of a light subpath is connected to every vertex of its camera subpath, so a long
    // one costs many connections, and the throughput relative to the emitted weight says
    // what it can still bring. Measured (`pt converge`, path against bdpt): the time to the
    // path tracer's error on the Cornell box fell from 2.02x to 1.87x, on `cornell-glass`
    // from 0.47x to 0.40x, against Russian roulette after `rr_depth` (5) bounces.
    let rr_depth = if BIDIR { s.rr_depth.min(1) } else { s.rr_depth };
    let mut ray = emitted.ray;
    // The medium the ray starts in (only the light tracer walks scenes with media).
    let mut medium = if scene.has_media() {
        light_medium(scene, &emitted.ray)
    } else {
        None
    };
    let channels = match scene.mode {
        ColorMode::Spectral => 4,
        ColorMode::Rgb => 3,
    };
    let mut arrival = Arrival::Emitted {
        light: li,
        pmf,
        ray: emitted,
    };
    let mut lambda = *lambda;
    let mut eta = 1.0f32;
    let max_depth = s.depth_limit();
    let medium_walk = scene.has_media();
    let mut depth = 1u32;
    while depth < max_depth {
        let hit = scene.intersect(&ray);
        // The segment through the current medium: free flight, as the volumetric path tracer
        // samples it (media are reciprocal: the same weights carry importance).
        if let Some(m) = medium.map(|i| &scene.media[i as usize]) {
            let t_surface = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
            let flight = free_flight(m, &ray, t_surface, &lambda, channels, sampler);
            beta *= flight.weight;
            if beta.is_black() || !beta.is_finite() {
                return;
            }
            if let Some(t) = flight.scatter_at {
                let p = ray.origin + ray.dir * t;
                let w_light = -ray.dir;
                visit_medium(
                    &MediumVertex {
                        p,
                        w_light,
                        phase: &m.phase,
                        medium,
                        beta,
                        lambda,
                    },
                    sampler,
                );
                // Phase sampling is exact: the weight is 1.
                let ps = m.phase.sample(w_light, sampler.next_2d());
                if !(ps.pdf > 0.0) {
                    return;
                }
                ray = Ray::new(p, ps.wi);
                depth += 1;
                if depth > rr_depth && !roulette(&mut beta, rr_norm * eta * eta, sampler) {
                    return;
                }
                continue;
            }
        }
        let Some(hit) = hit else {
            return;
        };
        let mut bsdf = scene.bsdf(&hit, &lambda);
        let frame = shading_frame(&hit);
        let w_light = -ray.dir;
        let wl = frame.to_local(w_light);
        let ng_light = hit.ng.dot(w_light);
        if ng_light * wl.z <= 0.0 {
            return;
        }
        // A fluorescent surface: the Lambertian of the adjoint albedo at the arriving
        // wavelengths, and the lanes move to the wavelengths they leave at (before the vertex
        // is seen: what leaves it, towards the camera too, is at those).
        if let Some(f) = scene.material(hit.shape).fluorescent() {
            if fluorescence == AtFluorescence::Absorb {
                return;
            }
            bsdf.to_mut().bsdf = Bsdf::Lambert(Lambert::new(f.adjoint_albedo(&lambda)));
            lambda = f.scatter_adjoint(&lambda, sampler.next_1d());
        }
        visit(
            &LightVertex {
                hit: &hit,
                bsdf: &bsdf,
                frame,
                wl,
                w_light,
                ng_light,
                beta,
                lambda,
                depth,
                arrival,
                medium,
            },
            sampler,
        );
        let at = (&hit, &*bsdf, &frame);
        let Some(next) = leave_surface::<S, BIDIR>(at, wl, ng_light, &mut beta, &mut eta, sampler)
        else {
            return;
        };
        (ray, arrival) = (next.ray, next.arrival);
        if let Some((inside, outside)) = scene.medium_boundary(hit.shape) {
            medium = if next.ng_next > 0.0 { outside } else { inside };
        }
        // With media, a pass straight through a surface (a null wall) is not a bounce, as in
        // the volumetric path tracer (Mitsuba's volpath).
        if medium_walk && next.pass_through {
            continue;
        }
        depth += 1;
        if depth > rr_depth && !roulette(&mut beta, rr_norm * eta * eta, sampler) {
            return;
        }
    }
}

/// A light chosen by the scene's light selection and a ray sampled from it
/// ([`Light::sample_emission`]): the light's index, its selection probability and the ray;
/// `None` when the scene has no light to choose or the light emits no ray.
#[inline(always)]
fn sample_emitted<S: RandomSource>(
    scene: &Scene,
    lambda: &SampledWavelengths,
    sampler: &mut S,
) -> Option<(usize, f32, pt_render::light::EmittedRay)> {
    let (li, pmf, u_sel) = scene.sample_light(sampler.next_1d())?;
    let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
    let emitted = scene.lights[li].sample_emission(u_sel, u_pos, u_dir, lambda, scene.bounds)?;
    Some((li, pmf, emitted))
}

/// How a light path left a surface vertex ([`leave_surface`]).
struct Leaving {
    /// The ray to the next vertex, its origin off the surface.
    ray: Ray,
    /// How the path arrives at the next vertex.
    arrival: Arrival,
    /// ng . direction taken (its sign says which side the ray leaves on).
    ng_next: f32,
    /// Whether the sample passed straight through the surface (a null event).
    pass_through: bool,
}

/// The light path leaves the surface vertex `(hit, bsdf, frame)` by BSDF sampling from the
/// light's side (`wl`: the local direction towards the previous vertex, `ng_light` its
/// geometric cosine), with the importance transport weights folded into `beta` and the
/// relative index into `eta`. `None` when the path ends there: no sample, a light leak, or a
/// black or non-finite weight. `BIDIR`: the arrival carries the reverse density.
#[inline(always)]
fn leave_surface<S: RandomSource, const BIDIR: bool>(
    (hit, bsdf, frame): (&Interaction, &SurfaceBsdf, &Frame),
    wl: Vec3,
    ng_light: f32,
    beta: &mut SampledSpectrum,
    eta: &mut f32,
    sampler: &mut S,
) -> Option<Leaving> {
    let u_lobe = sampler.next_1d();
    let bs = bsdf.sample(wl, u_lobe, sampler.next_2d())?;
    let dir = frame.to_world(bs.wi);
    let ng_next = hit.ng.dot(dir);
    if ng_next * bs.wi.z <= 0.0 {
        return None;
    }
    // Importance transport: refraction's 1 / eta^2 undone, and the adjoint's shading
    // normal correction.
    let correction = (wl.z * ng_next).abs() / (bs.wi.z * ng_light).abs();
    *beta *= bs.weight * (bs.eta * bs.eta * correction);
    *eta *= bs.eta;
    let arrival = Arrival::Scattered {
        fwd: bs.pdf,
        rev: if BIDIR && !bs.delta {
            bsdf.pdf(bs.wi, wl)
        } else {
            bs.pdf
        },
        cos_out: ng_next.abs(),
        delta: bs.delta,
    };
    if beta.is_black() || !beta.is_finite() {
        return None;
    }
    Some(Leaving {
        ray: Ray::new(offset_ray_origin(hit.p, hit.ng * ng_next.signum()), dir),
        arrival,
        ng_next,
        pass_through: bs.is_pass_through(wl),
    })
}

/// Russian roulette on a light path: keeps it with probability q = min(max(beta) `scale`, 0.95)
/// (`scale` holds eta^2 and, for the bidirectional walk, the emitted weight's normalisation),
/// dividing `beta` by q; false when the path ends.
#[inline(always)]
fn roulette<S: RandomSource>(beta: &mut SampledSpectrum, scale: f32, sampler: &mut S) -> bool {
    let q = (beta.max_value() * scale).min(0.95);
    if !(sampler.next_1d() < q) {
        return false;
    }
    *beta *= 1.0 / q;
    true
}

/// Continues `state` (whose `light` film the light tracer fills) up to `settings.spp`
/// batches of light paths, one batch per sample per pixel, checking `cancel` between passes
/// (see [`crate::render_passes`] for the pass sizes). Returns whether all were traced.
pub fn render_light_passes(
    scene: &Scene,
    settings: &crate::RenderSettings,
    state: &mut crate::RenderState,
    cancel: &AtomicBool,
    checkpoint: Option<&crate::Checkpoint>,
    progress: &(dyn Fn(u64) + Sync),
) -> bool {
    let per_batch = u64::from(settings.width) * u64::from(settings.height);
    let [fw, fh] = settings
        .crop
        .map_or([settings.width, settings.height], |c| c.film_size);
    let scale = (f64::from(fw) * f64::from(fh)) / per_batch as f64;
    let most = (MAX_PASS_PATHS / per_batch).max(1) as u32;
    crate::render::in_passes(
        state,
        settings.spp,
        cancel,
        &mut crate::render::checkpointer(checkpoint),
        2,
        most,
        |state, batches| light_pass(scene, settings, state, batches, scale, progress),
    )
}

/// Traces the light paths of `batches` (in parallel, in chunks), then adds their splats in
/// path order: to the filtered film, and per batch to the unfiltered image whose values go
/// into each pixel's statistics.
fn light_pass(
    scene: &Scene,
    settings: &crate::RenderSettings,
    state: &mut crate::RenderState,
    batches: std::ops::Range<u32>,
    scale: f64,
    progress: &(dyn Fn(u64) + Sync),
) {
    let per_batch = u64::from(settings.width) * u64::from(settings.height);
    let chunks_per_batch = per_batch.div_ceil(CHUNK);
    let items: Vec<(u32, u64)> = batches
        .clone()
        .flat_map(|b| (0..chunks_per_batch).map(move |c| (b, c)))
        .collect();
    let s = &settings.path;
    let rgb_lambda = SampledWavelengths::sample_visible(0.5);
    let inv_scale = (1.0 / scale) as f32;
    let lists: Vec<Vec<Splat>> = items
        .par_iter()
        .map(|&(b, c)| {
            // Batch b of this process is the render's batch share.sample(b) (a split render).
            let b = settings.share.sample(b);
            let first = u64::from(b) * per_batch + c * CHUNK;
            let end = (u64::from(b) * per_batch + per_batch).min(first + CHUNK);
            let mut out = Vec::with_capacity(((end - first) * 4) as usize);
            pt_render::isa::best(
                #[inline(always)]
                || {
                    for path in first..end {
                        let mut sampler = Sampler::new(settings.seed, LIGHT_STREAM, path);
                        trace_light_path(scene, s, &mut sampler, inv_scale, &rgb_lambda, &mut out);
                    }
                },
            );
            progress(end - first);
            out
        })
        .collect();
    add_batches(state, &lists, chunks_per_batch as usize, scale);
}

/// Adds a pass's splats in list order: `lists` holds `per_batch` lists per batch of paths
/// (one sample per pixel), each batch going to the filtered film and, without the filter,
/// into the pixels' statistics (see the module documentation on variance). Splats are
/// scaled by `scale`; non-finite ones are counted in the pixel they land in and dropped.
pub(crate) fn add_batches<L: AsRef<[Splat]> + Sync>(
    state: &mut crate::RenderState,
    lists: &[L],
    per_batch: usize,
    scale: f64,
) {
    let light = state
        .light
        .as_mut()
        .expect("a light-path render keeps a light film");
    for per_batch_lists in lists.chunks(per_batch) {
        light.add_batch(per_batch_lists, scale, &mut state.pixels);
    }
}

/// Whether the light tracer can render with `settings`; the reason when it cannot.
pub fn check(settings: &crate::RenderSettings) -> Result<(), String> {
    if !LightFilm::supports(&settings.filter.desc) {
        return Err("ptracer: the reconstruction filter is wider than 15 pixels".into());
    }
    Ok(())
}

/// Renders the image by light tracing (`settings.spp` batches of light paths; the path
/// settings' depth, Russian roulette and hidden emitters apply), as [`crate::render`] does by
/// path tracing. The caller checks the scene with [`check`] first.
pub fn render(
    scene: &Scene,
    settings: &crate::RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> pt_render::RenderOutput {
    let mut state = crate::RenderState::for_light_paths(settings);
    render_light_passes(
        scene,
        settings,
        &mut state,
        &AtomicBool::new(false),
        None,
        progress,
    );
    state.output()
}
