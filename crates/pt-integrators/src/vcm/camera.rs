//! The camera subpaths and their strategies at each vertex: emission met (s = 0), light
//! sampling (s = 1), connections to the paired light subpath (s, t >= 2) and merging.

use super::mis::{connection_weight, emission_weight, light_sample_weight, merge_weight};
use super::{Iteration, LightVertex, Photon, SubpathMis};
use crate::grid::PointGrid;
use crate::ptracer::{shading_frame, to_rgb, Splat};
use pt_bsdf::SurfaceBsdf;
use pt_math::{offset_ray_origin, Frame, Ray, Vec2, Vec3};
use pt_render::geometry::Interaction;
use pt_render::light::Light;
use pt_render::sampler::Sampler;
use pt_spectrum::{ColorMode, SampledSpectrum, SampledWavelengths};
use std::f32::consts::PI;

/// Traces camera subpath `index` (pixel `index` of the image) and returns its film position
/// and estimate: emission met (s = 0), light sampling (s = 1), connections to the vertices
/// of its light subpath, `light_vertices`, and merging with every light subpath.
#[inline(always)]
fn camera_subpath(
    it: &Iteration,
    sampler: &mut Sampler,
    lambda: &SampledWavelengths,
    index: usize,
    width: u32,
    (light_vertices, built): (&[LightVertex], &[SurfaceBsdf]),
) -> (Vec2, SampledSpectrum) {
    let (scene, s, f) = (it.scene, it.s, &it.f);
    let camera = &scene.camera;
    let (x, y) = ((index as u32 % width) as i32, (index as u32 / width) as i32);
    let u_film = sampler.next_2d();
    let u_lens = sampler.next_2d();
    let film = Vec2::new(x as f32, y as f32) + u_film;
    let mut ray = camera.pixel_ray(x, y, u_film - Vec2::splat(0.5), u_lens);
    let mut beta = match scene.mode {
        ColorMode::Spectral => SampledSpectrum::splat(1.0),
        ColorMode::Rgb => SampledSpectrum::from_rgb([1.0; 3]),
    };
    let mut radiance = SampledSpectrum::ZERO;
    // The camera ray's density for this pixel is P_film times the film-wide one, and
    // N = P_image light subpaths: N / p = 1 / (scale p_film).
    let pdf_film = camera.direction_pdf(ray.dir);
    if !(pdf_film > 0.0) {
        return (film, radiance);
    }
    let mut mis_state = SubpathMis::camera(1.0 / (it.scale * pdf_film));
    let mut prev = ray.origin;
    let max_depth = s.depth_limit();
    let mut eta = 1.0f32;
    let mut depth = 1u32;
    loop {
        let Some(hit) = scene.intersect(&ray) else {
            // Distant lights seen (s = 0).
            add_escaped(it, ray.dir, depth, &mis_state, beta, lambda, &mut radiance);
            break;
        };
        let wo_world = -ray.dir;
        let frame = shading_frame(&hit);
        let wo = frame.to_local(wo_world);
        let ng_wo = hit.ng.dot(wo_world);
        mis_state.arrive(Some((hit.p - prev).length_squared()), ng_wo.abs());
        // Emitters met (s = 0).
        if let Some(c) = emission_met(it, &hit, prev, wo_world, depth, &mis_state, beta, lambda) {
            radiance += c;
        }
        // Paths through a fluorescent surface are the camera side's alone (light subpaths end
        // there): the path tracer's strategies from here on.
        if scene.material(hit.shape).fluorescent().is_some() {
            radiance += crate::path::li_through_fluorescence(
                scene,
                ray,
                beta,
                depth - 1,
                s,
                sampler,
                lambda,
            );
            break;
        }
        if depth >= max_depth || ng_wo * wo.z <= 0.0 {
            break;
        }
        let bsdf = scene.bsdf(&hit, lambda);
        if bsdf.has_smooth_lobe() {
            // s = 1: light sampling.
            let (u_light, u_sel_pos) = (sampler.next_1d(), sampler.next_2d());
            if it.vcm.connections && depth < max_depth {
                radiance += beta
                    * light_sample(
                        it, &hit, &frame, &bsdf, wo, &mis_state, lambda, u_light, u_sel_pos,
                    );
            }
            // s >= 2, t >= 2: connections to the paired light subpath.
            if it.vcm.connections {
                for lv in light_vertices {
                    if lv.depth.saturating_add(depth).saturating_add(1) > max_depth {
                        break;
                    }
                    let lb = lv.bsdf(built);
                    radiance += beta * connect(it, &hit, &frame, &bsdf, wo, &mis_state, lv, lb);
                }
            }
            // Merging with the light vertices of every subpath nearby.
            if let Some(grid) = &it.grid {
                let sum = merged(it, grid, &hit, &frame, &bsdf, wo, &mis_state, depth);
                radiance += beta * sum * (1.0 / (PI * it.radius * it.radius * it.n));
            }
        }
        // Continue the camera subpath.
        let u_lobe = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u_lobe, sampler.next_2d()) else {
            break;
        };
        let dir = frame.to_world(bs.wi);
        let ng_next = hit.ng.dot(dir);
        if ng_next * bs.wi.z <= 0.0 {
            break;
        }
        let rev = if bs.delta {
            bs.pdf
        } else {
            bsdf.pdf(bs.wi, wo)
        };
        mis_state.scatter(ng_next.abs(), bs.pdf, rev, bs.delta, f);
        beta *= bs.weight;
        eta *= bs.eta;
        if beta.is_black() || !beta.is_finite() {
            break;
        }
        prev = hit.p;
        ray = Ray::new(offset_ray_origin(hit.p, hit.ng * ng_next.signum()), dir);
        depth += 1;
        if depth > s.rr_depth {
            let q = (beta.max_value() * eta * eta).min(0.95);
            if !(sampler.next_1d() < q) {
                break;
            }
            beta *= 1.0 / q;
        }
    }
    (film, radiance)
}

/// Adds to `radiance` the distant lights seen by a camera ray that left the scene in
/// direction `dir` (s = 0), weighted; `depth` counts the ray's segments, `beta` is the camera
/// subpath's weight.
#[inline(always)]
fn add_escaped(
    it: &Iteration,
    dir: Vec3,
    depth: u32,
    cam: &SubpathMis,
    beta: SampledSpectrum,
    lambda: &SampledWavelengths,
    radiance: &mut SampledSpectrum,
) {
    let scene = it.scene;
    if depth == 1 && it.s.hide_emitters {
        return;
    }
    for &i in &scene.infinite_lights {
        let l = &scene.lights[i];
        let le = l.escaped_radiance(dir, lambda);
        if le.is_black() {
            continue;
        }
        let w = if depth == 1 {
            1.0
        } else {
            let direct = scene.light_pmf(i) * l.escaped_pdf(dir);
            let emit = direct / (PI * scene.bounds.1 * scene.bounds.1);
            emission_weight(cam, direct, emit, &it.f)
        };
        *radiance += beta * le * w;
    }
}

/// The emission of the surface a camera ray from `prev` met at `hit` (s = 0), weighted and
/// times the camera subpath's weight `beta`; `None` off emitters, for black emission and for
/// emitters hidden from the camera. `wo_world` is the unit direction back along the ray.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn emission_met(
    it: &Iteration,
    hit: &Interaction,
    prev: Vec3,
    wo_world: Vec3,
    depth: u32,
    cam: &SubpathMis,
    beta: SampledSpectrum,
    lambda: &SampledWavelengths,
) -> Option<SampledSpectrum> {
    let scene = it.scene;
    let (li, light) = scene.shape_light(hit.shape)?;
    let le = light.emitted(hit.ns, wo_world, hit.uv, lambda);
    if le.is_black() || depth == 1 && it.s.hide_emitters {
        return None;
    }
    let w = if depth == 1 {
        1.0
    } else {
        let pmf = scene.light_pmf(li);
        let d2 = (hit.p - prev).length_squared();
        let ng_wo = hit.ng.dot(wo_world);
        let direct = pmf * light.pdf(prev, hit.p, hit.ns) * ng_wo.abs() / d2;
        let (pos, dir) = scene.lights[li].emission_pdf(hit.ns, wo_world, scene.bounds);
        emission_weight(cam, direct, pmf * pos * dir, &it.f)
    };
    Some(beta * le * w)
}

/// The light vertices of every subpath within the merging radius of camera vertex `hit`
/// (depth `depth`), each times its BSDF value, weight and the shading-normal correction
/// (cos_s / cos_g), summed: merging's estimate before the kernel's 1 / (pi r^2 N).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn merged(
    it: &Iteration,
    grid: &PointGrid<Photon>,
    hit: &Interaction,
    frame: &Frame,
    bsdf: &SurfaceBsdf,
    wo: Vec3,
    cam: &SubpathMis,
    depth: u32,
) -> SampledSpectrum {
    let max_depth = it.s.depth_limit();
    let mut sum = SampledSpectrum::ZERO;
    grid.within(hit.p, |ph| {
        if ph.ng.dot(hit.ng) <= 0.0 || ph.depth.saturating_add(depth) > max_depth {
            return;
        }
        let wi = frame.to_local(ph.w_light);
        let ng_wi = hit.ng.dot(ph.w_light);
        if ng_wi * wi.z <= 0.0 {
            return;
        }
        let fv = bsdf.eval(wo, wi);
        if fv.is_black() {
            return;
        }
        let w = merge_weight(&ph.mis, cam, bsdf.pdf(wo, wi), bsdf.pdf(wi, wo), &it.f);
        sum += fv * ph.beta * (w * wi.z.abs() / ng_wi.abs());
    });
    sum
}

/// Camera subpath `k` as a camera sample for the film (black ones too: their filter weights
/// count in the pixels' averages).
pub(super) fn camera_sample(
    it: &Iteration,
    sampler: &mut Sampler,
    lambda: &SampledWavelengths,
    k: u64,
    width: u32,
    own: (&[LightVertex], &[SurfaceBsdf]),
) -> Splat {
    // The camera subpath and its strategies inlined into one function per instruction set.
    let (film, l) = pt_render::isa::best(
        #[inline(always)]
        || camera_subpath(it, sampler, lambda, k as usize, width, own),
    );
    Splat {
        film,
        rgb: to_rgb(it.scene, l, lambda),
        camera: true,
    }
}

/// Light sampling at a camera vertex (s = 1), weighted.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn light_sample(
    it: &Iteration,
    hit: &Interaction,
    frame: &Frame,
    bsdf: &SurfaceBsdf,
    wo: Vec3,
    cam: &SubpathMis,
    lambda: &SampledWavelengths,
    u_light: f32,
    u: Vec2,
) -> SampledSpectrum {
    let scene = it.scene;
    let Some((li, pmf, u_sel)) = scene.sample_light(u_light) else {
        return SampledSpectrum::ZERO;
    };
    let light = &scene.lights[li];
    let Some(ls) = light.sample(hit.p, u_sel, u, lambda) else {
        return SampledSpectrum::ZERO;
    };
    if ls.radiance.is_black() || !(ls.pdf > 0.0) {
        return SampledSpectrum::ZERO;
    }
    let wi = frame.to_local(ls.wi);
    let ng_wi = hit.ng.dot(ls.wi);
    if ng_wi * wi.z <= 0.0 {
        return SampledSpectrum::ZERO;
    }
    let fv = bsdf.eval(wo, wi);
    if fv.is_black() {
        return SampledSpectrum::ZERO;
    }
    let (pos, dir) = light.emission_pdf(ls.n, -ls.wi, scene.bounds);
    let cos_light = match light {
        Light::Area(_) => ls.n.dot(ls.wi).abs(),
        _ => 1.0,
    };
    let bsdf_fwd = if ls.delta { 0.0 } else { bsdf.pdf(wo, wi) };
    // Light sampling's density per unit solid angle at the vertex: a point-like light's point
    // has density 1 per unit area, d^2 per unit solid angle (its `pdf` of 1 goes with the
    // radiance I / d^2 it returns).
    let direct = match light {
        Light::Point { .. } | Light::Spot { .. } | Light::Projector(_) => ls.dist * ls.dist,
        _ => ls.pdf,
    };
    let w = light_sample_weight(
        cam,
        bsdf_fwd,
        pmf * direct,
        pmf * pos * dir,
        ng_wi.abs(),
        cos_light,
        bsdf.pdf(wi, wo),
        &it.f,
    );
    let c = fv * ls.radiance * (w * wi.z.abs() / (pmf * ls.pdf));
    let origin = offset_ray_origin(hit.p, hit.ng * ng_wi.signum());
    if scene.light_unoccluded(origin, &ls) {
        c
    } else {
        SampledSpectrum::ZERO
    }
}

/// A camera vertex connected to a light vertex (s, t >= 2), weighted; the camera subpath's
/// weight not included.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn connect(
    it: &Iteration,
    hit: &Interaction,
    frame: &Frame,
    bsdf: &SurfaceBsdf,
    wo: Vec3,
    cam: &SubpathMis,
    lv: &LightVertex,
    lb: &SurfaceBsdf,
) -> SampledSpectrum {
    let d = lv.p - hit.p;
    let dist2 = d.length_squared();
    if !(dist2 > 0.0) {
        return SampledSpectrum::ZERO;
    }
    let w = d / dist2.sqrt();
    let wi = frame.to_local(w);
    let ng_c = hit.ng.dot(w);
    let wl_cam = lv.frame.to_local(-w);
    let ng_l = lv.ng.dot(-w);
    if ng_c * wi.z <= 0.0 || ng_l * wl_cam.z <= 0.0 {
        return SampledSpectrum::ZERO;
    }
    let f_cam = bsdf.eval(wo, wi);
    let f_light = lb.eval(wl_cam, lv.wl);
    if f_cam.is_black() || f_light.is_black() {
        return SampledSpectrum::ZERO;
    }
    let cam_area = bsdf.pdf(wo, wi) * ng_l.abs() / dist2;
    let light_area = lb.pdf(lv.wl, wl_cam) * ng_c.abs() / dist2;
    let weight = connection_weight(
        &lv.mis,
        cam,
        cam_area,
        light_area,
        lb.pdf(wl_cam, lv.wl),
        bsdf.pdf(wi, wo),
        &it.f,
    );
    // The light vertex's adjoint (Veach's shading-normal correction, with its geometric
    // cosine), the camera vertex's shading cosine, and 1 / d^2.
    let adjoint = lv.wl.z.abs() * ng_l.abs() / lv.ng_light.abs();
    let c = f_cam * f_light * lv.beta * (weight * wi.z.abs() * adjoint / dist2);
    if c.is_black() {
        return c;
    }
    let origin = offset_ray_origin(hit.p, hit.ng * ng_c.signum());
    let target = offset_ray_origin(lv.p, lv.ng * ng_l.signum());
    if it.scene.segment_unoccluded(origin, target) {
        c
    } else {
        SampledSpectrum::ZERO
    }
}
