//! The scattering step of the path tracer, for every path in flight at once: at each path's
//! hit, the light sample (next-event estimation, whose shadow ray it leaves for the next pass),
//! the BSDF sample that makes the next segment, and Russian roulette.
//!
//! One implementation for every material, texture and light, in lanes (one per path, see
//! `pt_math::lanes`): the geometry (shading frames, ray offsets, local directions, shadow
//! rays, MIS weights) runs for all paths at once in SIMD lanes; each path's BSDF and light are
//! evaluated per lane, except the models written as lane kernels, which run for all paths
//! that have them at once: Lambert's BSDF and parallelogram area lights (the commonest of real
//! scenes). Those kernels are the models' only implementation (their single-value functions
//! are the kernels with one lane), so lanes and single paths cannot drift apart. Each path
//! draws its random numbers in the same order as it would alone.

use crate::path::{PathSettings, PathStart, PathState, Strategy, MAX_PATHS};
use pt_bsdf::{mirror_side, BsdfSample, Lambert, SurfaceBsdf};
use pt_math::lanes::{offset_ray_origins, power_heuristics, Frames, V3};
use pt_math::{Ray, Vec2, Vec3};
use pt_render::geometry::Interaction;
use pt_render::light::{parallelogram_points, to_solid_angle, Light, LightShape};
use pt_render::Scene;
use pt_spectrum::SampledSpectrum;

/// Lanes: one per path in flight.
const N: usize = MAX_PATHS;

/// Shadow rays stop this fraction short of the light point, whose origin is already offset: a
/// relative guard against rounding at the far end, not an absolute epsilon.
pub(crate) const SHADOW_RAY_SHORTEN: f32 = 1.0 - 1e-5;

/// The lanes' light samples (structure of arrays): which lanes have one, and its values (see
/// `pt_render::light::LightSample`).
struct LightLanes {
    /// Whether the lane has a light sample.
    have: [bool; N],
    /// Unit directions towards the light, world space.
    wi: V3<N>,
    /// Points on the lights (unused for distant lights).
    p: V3<N>,
    /// The lights' normals there (zero for point-like and distant lights).
    n: V3<N>,
    /// Distances (infinite for distant lights).
    dist: [f32; N],
    /// Radiance arriving along `-wi`.
    radiance: [SampledSpectrum; N],
    /// Solid-angle pdfs times the light selection probabilities.
    pdf: [f32; N],
    /// Whether the light is a delta light.
    delta: [bool; N],
}

/// The scattering of the paths in `slots` that scatter at their hits (`todo`), all at once.
#[inline(always)]
pub(crate) fn scatter(
    scene: &Scene,
    s: &PathSettings,
    slots: &mut [Option<PathStart>; N],
    hits: &[Option<Interaction>; N],
    todo: &[bool; N],
) {
    let use_light = s.strategy != Strategy::Bsdf;
    // The hits' geometry, one lane per path (unused lanes keep harmless values).
    let (mut p, mut ng, mut ns, mut dpdu) = (
        V3::<N>::default(),
        V3::default(),
        V3::splat(Vec3::Z),
        V3::default(),
    );
    let mut dir = V3::splat(-Vec3::Z);
    for k in 0..N {
        if let (true, Some(h), Some(sl)) = (todo[k], &hits[k], &slots[k]) {
            p.set(k, h.p);
            ng.set(k, h.ng);
            ns.set(k, h.ns);
            dpdu.set(k, h.dpdu);
            dir.set(k, sl.path.ray.dir);
        }
    }
    let frames = Frames::from_normal_tangent(&ns, &dpdu);
    let wo = frames.to_local(&dir.neg());
    // Rays leave the hit offset to one side of the surface (Wächter & Binder 2019): the side
    // the path came from (`n_out`), or the other one for transmission.
    let ndd = ng.dot(&dir);
    let side: [f32; N] = pt_math::lanes::lanes(|k| -ndd[k].signum());
    let n_out = ng.scale(&side);
    let out = offset_ray_origins(&p, &n_out);
    let back = offset_ray_origins(&p, &n_out.neg());

    // Per path: its BSDF (the material's own when nothing varies over it, not copied; else
    // evaluated), fluorescence, its random numbers, its light choice.
    let mut fixed: [Option<&SurfaceBsdf>; N] = [None; N];
    let mut built: [Option<SurfaceBsdf>; N] = [None; N];
    // Lights: parallelogram area lights in lanes (below), the others on their own here.
    let mut par = [usize::MAX; N];
    let mut pmf = [1.0f32; N];
    let mut l = LightLanes {
        have: [false; N],
        wi: V3::splat(Vec3::Z),
        p: V3::default(),
        n: V3::default(),
        dist: [1.0; N],
        radiance: [SampledSpectrum::ZERO; N],
        pdf: [1.0; N],
        delta: [false; N],
    };
    let (mut u_lobe, mut ub) = ([0.5f32; N], [Vec2::splat(0.5); N]);
    let (mut lv0, mut le1, mut le2) = (V3::<N>::default(), V3::default(), V3::default());
    let (mut larea, mut lu) = ([1.0f32; N], [Vec2::splat(0.5); N]);
    for k in 0..N {
        let (true, Some(h), Some(PathStart { path, sampler, .. })) =
            (todo[k], &hits[k], &mut slots[k])
        else {
            continue;
        };
        let material = scene.material(h.shape);
        let bsdf: &SurfaceBsdf = match &material.fixed {
            Some(b) => {
                fixed[k] = Some(b);
                b
            }
            None => built[k].insert(scene.bsdf(h, &path.lambda)),
        };
        // Fluorescence: the BSDF holds each lane's total albedo at its emitted wavelength; now
        // some lanes move to an excitation wavelength, used by NEE and the rest of the path.
        if let Some(f) = material.fluorescent() {
            path.lambda = f.scatter(&path.lambda, sampler.next_1d());
        }
        if use_light && bsdf.has_smooth_lobe() {
            match scene.sample_light(sampler.next_1d()) {
                Some((li, p_sel, u_sel)) => {
                    let u = sampler.next_2d();
                    pmf[k] = p_sel;
                    let light = &scene.lights[li];
                    match light {
                        Light::Area(a) if matches!(a.shape, LightShape::Parallelogram { .. }) => {
                            let LightShape::Parallelogram { v0, e1, e2, n, .. } = a.shape else {
                                unreachable!()
                            };
                            (
                                lv0.set(k, v0),
                                le1.set(k, e1),
                                le2.set(k, e2),
                                l.n.set(k, n),
                            );
                            (larea[k], lu[k], par[k]) = (a.area, u, li);
                        }
                        _ => {
                            if let Some(s) = light.sample(h.p, u_sel, u, &path.lambda) {
                                l.have[k] = true;
                                (l.wi.set(k, s.wi), l.p.set(k, s.p), l.n.set(k, s.n));
                                (l.dist[k], l.radiance[k], l.pdf[k], l.delta[k]) =
                                    (s.dist, s.radiance, p_sel * s.pdf, s.delta);
                            }
                        }
                    }
                }
                // Keep the random number sequence aligned whether or not there are lights.
                None => {
                    let _ = sampler.next_2d();
                }
            }
        }
        u_lobe[k] = sampler.next_1d();
        ub[k] = sampler.next_2d();
    }
    let bsdf_of = |k: usize| -> Option<&SurfaceBsdf> { fixed[k].or(built[k].as_ref()) };

    // Parallelogram lights, all lanes at once (the other lanes' results are not used).
    let is_par: [bool; N] = pt_math::lanes::lanes(|k| par[k] != usize::MAX);
    let points = parallelogram_points(
        &lv0,
        &le1,
        &le2,
        &pt_math::lanes::lanes(|k| lu[k].x),
        &pt_math::lanes::lanes(|k| lu[k].y),
    );
    let sa = to_solid_angle(&p, &points, &l.n, &larea);
    l.wi = V3::select(&is_par, &sa.wi, &l.wi);
    l.p = V3::select(&is_par, &points, &l.p);
    for k in 0..N {
        if !(is_par[k] && sa.ok[k]) {
            continue;
        }
        let Light::Area(a) = &scene.lights[par[k]] else {
            unreachable!("drawn as an area light")
        };
        let LightShape::Parallelogram { uv, .. } = a.shape else {
            unreachable!("drawn as a parallelogram")
        };
        if sa.front[k] {
            let u = lu[k];
            let lambda = &slots[k].as_ref().expect("a scattering path").path.lambda;
            l.radiance[k] = a.radiance_at_uv(uv[0] + uv[1] * u.x + uv[2] * u.y, lambda);
        }
        (l.have[k], l.dist[k], l.pdf[k]) = (true, sa.dist[k], pmf[k] * sa.pdf[k]);
    }
    let wi_world = l.wi;
    let wi = frames.to_local(&wi_world);

    // The BSDFs: f and pdf towards the light sample, and the BSDF sample; plain Lambertian
    // surfaces in lanes (their two-sided mirroring as `SurfaceBsdf` does it), others per path.
    let mut albedo = [SampledSpectrum::ZERO; N];
    let mut lane_lambert = [false; N];
    let mut mirror = [1.0f32; N];
    for k in 0..N {
        if let Some((r, two_sided)) = bsdf_of(k).and_then(|b| b.plain_lambert()) {
            (albedo[k], lane_lambert[k]) = (r, true);
            mirror[k] = mirror_side(two_sided, false, wo.z[k]);
        }
    }
    let wo_z: [f32; N] = pt_math::lanes::lanes(|k| wo.z[k] * mirror[k]);
    let wi_z: [f32; N] = pt_math::lanes::lanes(|k| wi.z[k] * mirror[k]);
    let lambert_f = Lambert::eval_lanes(&albedo, &wo_z, &wi_z);
    let lambert_pdf = Lambert::pdf_lanes(&wo_z, &wi_z);
    let (lambert_wi, lambert_spdf, lambert_ok) = Lambert::sample_lanes(
        &wo_z,
        &pt_math::lanes::lanes(|k| ub[k].x),
        &pt_math::lanes::lanes(|k| ub[k].y),
    );
    let mut f = [SampledSpectrum::ZERO; N];
    let mut bsdf_pdf = [0.0f32; N];
    let mut bs: [Option<BsdfSample>; N] = [None; N];
    for k in 0..N {
        let Some(b) = bsdf_of(k) else { continue };
        if lane_lambert[k] {
            (f[k], bsdf_pdf[k]) = (lambert_f[k], lambert_pdf[k]);
            bs[k] = lambert_ok[k].then(|| BsdfSample {
                wi: Vec3::new(
                    lambert_wi.x[k],
                    lambert_wi.y[k],
                    lambert_wi.z[k] * mirror[k],
                ),
                weight: albedo[k],
                pdf: lambert_spdf[k],
                delta: false,
                eta: 1.0,
            });
            continue;
        }
        if l.have[k] {
            let w = wi.get(k);
            f[k] = b.eval(wo.get(k), w);
            // Only MIS needs the BSDF's pdf of the light's direction.
            if s.strategy != Strategy::Light
                && !l.delta[k]
                && !l.radiance[k].is_black()
                && !f[k].is_black()
            {
                bsdf_pdf[k] = b.pdf(wo.get(k), w);
            }
        }
        bs[k] = b.sample(wo.get(k), u_lobe[k], ub[k]);
    }

    // Shadow rays and MIS weights, all lanes at once: from the side of the hit the light is
    // on, to the light point offset off its own surface (a light without a surface normal, or
    // a distant one, needs no offset there).
    let nwi = n_out.dot(&wi_world);
    let towards: [bool; N] = pt_math::lanes::lanes(|k| nwi[k] >= 0.0);
    let origin = V3::select(&towards, &out, &back);
    let nwd = l.n.dot(&wi_world.neg());
    let facing: [f32; N] = pt_math::lanes::lanes(|k| nwd[k].signum());
    let lifted = offset_ray_origins(&l.p, &l.n.scale(&facing));
    let no_normal: [bool; N] = pt_math::lanes::lanes(|k| l.n.get(k) == Vec3::ZERO);
    let target = V3::select(&no_normal, &l.p, &lifted);
    let seg = target.sub(&origin);
    let seg2 = seg.dot(&seg);
    let seg_len: [f32; N] = pt_math::lanes::lanes(|k| seg2[k].sqrt());
    let light_pdf = l.pdf;
    let mis = power_heuristics(&light_pdf, &bsdf_pdf);
    // The next segments' origins, on the side each sampled direction leaves to.
    let next_dir = frames.to_world(&V3::from_fn(|k| bs[k].map_or(Vec3::Z, |b| b.wi)));
    let nnd = n_out.dot(&next_dir);
    let next_origin = V3::select(&pt_math::lanes::lanes(|k| nnd[k] >= 0.0), &out, &back);

    for k in 0..N {
        let (true, Some(h), Some(PathStart { path, sampler, .. })) =
            (todo[k], &hits[k], &mut slots[k])
        else {
            continue;
        };
        if l.have[k] {
            if !l.radiance[k].is_black() && !f[k].is_black() {
                let ray = if l.dist[k].is_infinite() {
                    Some(Ray::new(origin.get(k), wi_world.get(k)))
                } else {
                    (seg_len[k] > 0.0).then(|| Ray {
                        origin: origin.get(k),
                        dir: seg.get(k) / seg_len[k],
                        tmin: 0.0,
                        tmax: seg_len[k] * SHADOW_RAY_SHORTEN,
                    })
                };
                if let Some(ray) = ray {
                    // Delta lights cannot be hit by BSDF sampling: light sampling is the only
                    // strategy, weight 1.
                    let w = if s.strategy != Strategy::Light && !l.delta[k] {
                        mis[k]
                    } else {
                        1.0
                    };
                    let c =
                        path.throughput * f[k] * l.radiance[k] * (wi.z[k].abs() * w / light_pdf[k]);
                    path.shadow = Some((ray, c));
                }
            }
        }
        continue_path(
            s,
            path,
            sampler,
            h,
            bs[k],
            next_origin.get(k),
            next_dir.get(k),
        );
    }
}

/// The next segment of a path from its BSDF sample (or its end), and Russian roulette
/// (Mitsuba: after `rr_depth` segments, keep with probability min(max(T) eta^2, 0.95)).
#[inline(always)]
fn continue_path(
    s: &PathSettings,
    path: &mut PathState,
    sampler: &mut pt_render::sampler::Sampler,
    hit: &Interaction,
    bs: Option<BsdfSample>,
    origin: Vec3,
    dir: Vec3,
) {
    let Some(bs) = bs.filter(|b| !b.weight.is_black()) else {
        path.alive = false;
        return;
    };
    path.throughput *= bs.weight;
    path.eta_scale *= bs.eta;
    path.prev_p = hit.p;
    path.prev_pdf = bs.pdf;
    path.prev_delta = bs.delta;
    path.ray = Ray::new(origin, dir);
    path.depth += 1;
    if path.depth >= s.rr_depth {
        let q = (path.throughput.max_value() * path.eta_scale * path.eta_scale).min(0.95);
        if !(sampler.next_1d() < q) {
            path.alive = false;
            return;
        }
        path.throughput *= 1.0 / q;
    }
}
