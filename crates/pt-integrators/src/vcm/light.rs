//! The light subpaths: the light tracer's walk, keeping each vertex for connections and
//! merging with its partial sums, and splatting each vertex the camera sees (t = 1).

use super::mis::{camera_weight, Factors, SubpathMis};
use super::{LightVertex, VcmSettings, VertexBsdf};
use crate::path::PathSettings;
use crate::ptracer::{seen_by_camera, to_rgb, walk_light_path, Arrival, AtFluorescence, Splat};
use pt_bsdf::SurfaceBsdf;
use pt_math::Vec3;
use pt_render::light::Light;
use pt_render::sampler::Sampler;
use pt_render::Scene;
use pt_spectrum::SampledWavelengths;
use std::borrow::Cow;

/// Traces light subpath `index`: its vertices (non-delta surfaces) appended to `out`, its
/// camera splats (t = 1) to `splats`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn light_subpath<'s>(
    scene: &'s Scene,
    s: &PathSettings,
    vcm: &VcmSettings,
    f: &Factors,
    scale: f32,
    sampler: &mut Sampler,
    lambda: &SampledWavelengths,
    out: &mut Vec<LightVertex<'s>>,
    built: &mut Vec<SurfaceBsdf>,
    splats: &mut Vec<Splat>,
) {
    let mut mis_state = SubpathMis::default();
    let mut prev = Vec3::ZERO;
    walk_light_path::<_, true>(
        scene,
        s,
        sampler,
        lambda,
        AtFluorescence::Absorb,
        #[inline(always)]
        |v, sampler| {
            let cos_in = v.ng_light.abs();
            match v.arrival {
                Arrival::Emitted { light, pmf, ray } => {
                    let l = &scene.lights[light];
                    let emit = pmf * ray.pdf_pos * ray.pdf_dir;
                    let to_light = ray.origin - v.hit.p;
                    let d2 = to_light.length_squared();
                    let (direct, cos_light, dist2) = match l {
                        Light::Area(a) => {
                            let cos_l = ray.normal.dot(ray.ray.dir).abs();
                            // Light sampling's solid-angle density from this vertex, per unit
                            // area at the light.
                            let direct = pmf * a.pdf(v.hit.p, ray.origin, ray.normal) * cos_l / d2;
                            (direct, cos_l, Some(d2))
                        }
                        _ if l.is_infinite() => (pmf * l.escaped_pdf(-ray.ray.dir), 1.0, None),
                        Light::Directional { .. } => (pmf, 1.0, None),
                        _ => (pmf, 1.0, Some(d2)),
                    };
                    mis_state = SubpathMis::light(direct, emit, cos_light, l.is_delta(), f);
                    mis_state.arrive(dist2, cos_in);
                }
                Arrival::Scattered {
                    fwd,
                    rev,
                    cos_out,
                    delta,
                } => {
                    mis_state.scatter(cos_out, fwd, rev, delta, f);
                    mis_state.arrive(Some((v.hit.p - prev).length_squared()), cos_in);
                }
            }
            prev = v.hit.p;
            if !v.bsdf.has_smooth_lobe() {
                return;
            }
            out.push(LightVertex {
                p: v.hit.p,
                ng: v.hit.ng,
                frame: v.frame,
                wl: v.wl,
                w_light: v.w_light,
                ng_light: v.ng_light,
                bsdf: match v.bsdf {
                    Cow::Borrowed(b) => VertexBsdf::Shared(b),
                    Cow::Owned(b) => {
                        built.push(*b);
                        VertexBsdf::Built(built.len() as u32 - 1)
                    }
                },
                beta: v.beta,
                mis: mis_state,
                depth: v.depth,
            });
            if !vcm.connections {
                return;
            }
            // t = 1: the vertex seen by the camera.
            if let Some(seen) = seen_by_camera(scene, v, sampler) {
                let weight = camera_weight(
                    &mis_state,
                    seen.connection.weight * seen.cos * scale,
                    v.bsdf.pdf(seen.wc, v.wl),
                    f,
                );
                splats.push(Splat {
                    film: seen.connection.film,
                    rgb: to_rgb(scene, seen.contribution * weight, &v.lambda),
                    camera: false,
                });
            }
        },
        // Scenes with media are refused before this method runs.
        #[inline(always)]
        |_, _| {},
    );
}
