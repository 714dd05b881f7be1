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
use pt_math::lanes::{lanes, offset_ray_origins, power_heuristics, Frames, V3};
use pt_math::{Ray, Vec2, Vec3};
use pt_render::geometry::Interaction;
use pt_render::light::{parallelogram_points, to_solid_angle, Light, LightSample, LightShape};
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

impl LightLanes {
    /// No light samples yet.
    #[inline(always)]
    fn empty() -> Self {
        LightLanes {
            have: [false; N],
            wi: V3::splat(Vec3::Z),
            p: V3::default(),
            n: V3::default(),
            dist: [1.0; N],
            radiance: [SampledSpectrum::ZERO; N],
            pdf: [1.0; N],
            delta: [false; N],
        }
    }

    /// Lane `k`'s sample `s` of a light chosen with probability `pmf`.
    #[inline(always)]
    fn set(&mut self, k: usize, s: &LightSample, pmf: f32) {
        self.have[k] = true;
        (self.wi.set(k, s.wi), self.p.set(k, s.p), self.n.set(k, s.n));
        (self.dist[k], self.radiance[k], self.pdf[k], self.delta[k]) =
            (s.dist, s.radiance, pmf * s.pdf, s.delta);
    }
}

/// The hits' geometry, one lane per path: points, geometric normals, shading frames, the
/// directions towards the viewer in those frames, and the spawn points on both sides.
struct Geometry {
    p: V3<N>,
    /// Unit geometric normals flipped to the side each path arrived from.
    n_out: V3<N>,
    frames: Frames<N>,
    /// Towards the viewer, local frames.
    wo: V3<N>,
    /// The hit points offset towards `n_out` (Wächter & Binder 2019).
    out: V3<N>,
    /// The hit points offset away from `n_out` (for transmission).
    back: V3<N>,
}

impl Geometry {
    /// Gathers the hits of the lanes in `todo` (unused lanes keep harmless values).
    #[inline(always)]
    fn gather(
        slots: &[Option<PathStart>; N],
        hits: &[Option<Interaction>; N],
        todo: &[bool; N],
    ) -> Self {
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
        // Rays leave the hit offset to one side of the surface: the side the path came from,
        // or the other one for transmission.
        let ndd = ng.dot(&dir);
        let n_out = ng.scale(&lanes(|k| -ndd[k].signum()));
        let out = offset_ray_origins(&p, &n_out);
        let back = offset_ray_origins(&p, &n_out.neg());
        Geometry {
            p,
            n_out,
            frames,
            wo,
            out,
            back,
        }
    }

    /// Origins for rays leaving in the world directions `dir`: the side each leaves to.
    #[inline(always)]
    fn origins(&self, dir: &V3<N>) -> V3<N> {
        let d = self.n_out.dot(dir);
        V3::select(&lanes(|k| d[k] >= 0.0), &self.out, &self.back)
    }
}

/// What each path draws at its hit: its BSDF (the material's own when nothing varies over it,
/// not copied; else evaluated), the uniform numbers of its BSDF sample, and its light choice.
struct Draws<'a> {
    fixed: [Option<&'a SurfaceBsdf>; N],
    built: [Option<SurfaceBsdf>; N],
    u_lobe: [f32; N],
    ub: [Vec2; N],
    /// Index of a parallelogram light chosen in the lane (sampled in lanes), or `usize::MAX`.
    par: [usize; N],
    /// Its corner, edges, area and uniform numbers.
    v0: V3<N>,
    e1: V3<N>,
    e2: V3<N>,
    area: [f32; N],
    lu: [Vec2; N],
    /// Light selection probabilities.
    pmf: [f32; N],
}

impl Draws<'_> {
    /// Lane `k`'s BSDF, if the lane scatters.
    #[inline(always)]
    fn bsdf(&self, k: usize) -> Option<&SurfaceBsdf> {
        self.fixed[k].or(self.built[k].as_ref())
    }
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
    let g = Geometry::gather(slots, hits, todo);
    let mut l = LightLanes::empty();
    let d = draw(scene, s, slots, hits, todo, &mut l);
    sample_parallelograms(scene, slots, &g, &d, &mut l);
    let wi = g.frames.to_local(&l.wi);
    let (f, bsdf_pdf, bs) = bsdfs(s, &g, &d, &l, &wi);
    // The shadow rays leave on the side of the hit the light is on; the next segments on the
    // side each sampled direction leaves to.
    let origin = g.origins(&l.wi);
    let (seg, seg_len) = shadow_segments(&origin, &l);
    let mis = power_heuristics(&l.pdf, &bsdf_pdf);
    let next_dir = g
        .frames
        .to_world(&V3::from_fn(|k| bs[k].map_or(Vec3::Z, |b| b.wi)));
    let next_origin = g.origins(&next_dir);
    for k in 0..N {
        let (true, Some(h), Some(PathStart { path, sampler, .. })) =
            (todo[k], &hits[k], &mut slots[k])
        else {
            continue;
        };
        if l.have[k] && !l.radiance[k].is_black() && !f[k].is_black() {
            let ray = if l.dist[k].is_infinite() {
                Some(Ray::new(origin.get(k), l.wi.get(k)))
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
                let c = path.throughput * f[k] * l.radiance[k] * (wi.z[k].abs() * w / l.pdf[k]);
                path.shadow = Some((ray, c));
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

/// Per path, in the order a path alone draws them: its BSDF, fluorescence, the light choice
/// and the light's uniform numbers (lights other than parallelograms sampled here, into `l`),
/// the BSDF sample's uniform numbers.
#[inline(always)]
fn draw<'a>(
    scene: &'a Scene,
    s: &PathSettings,
    slots: &mut [Option<PathStart>; N],
    hits: &[Option<Interaction>; N],
    todo: &[bool; N],
    l: &mut LightLanes,
) -> Draws<'a> {
    let use_light = s.strategy != Strategy::Bsdf;
    let mut d = Draws {
        fixed: [None; N],
        built: [None; N],
        u_lobe: [0.5; N],
        ub: [Vec2::splat(0.5); N],
        par: [usize::MAX; N],
        v0: V3::default(),
        e1: V3::default(),
        e2: V3::default(),
        area: [1.0; N],
        lu: [Vec2::splat(0.5); N],
        pmf: [1.0; N],
    };
    for k in 0..N {
        let (true, Some(h), Some(PathStart { path, sampler, .. })) =
            (todo[k], &hits[k], &mut slots[k])
        else {
            continue;
        };
        let material = scene.material(h.shape);
        let bsdf: &SurfaceBsdf = match &material.fixed {
            Some(b) => {
                d.fixed[k] = Some(b);
                b
            }
            None => d.built[k].insert(scene.bsdf(h, &path.lambda)),
        };
        // Fluorescence: the BSDF holds each lane's total albedo at its emitted wavelength; now
        // some lanes move to an excitation wavelength, used by NEE and the rest of the path.
        if let Some(f) = material.fluorescent() {
            path.lambda = f.scatter(&path.lambda, sampler.next_1d());
        }
        if use_light && bsdf.has_smooth_lobe() {
            match scene.sample_light(sampler.next_1d()) {
                Some((li, pmf, u_sel)) => {
                    let u = sampler.next_2d();
                    d.pmf[k] = pmf;
                    match &scene.lights[li] {
                        Light::Area(a) if matches!(a.shape, LightShape::Parallelogram { .. }) => {
                            let LightShape::Parallelogram { v0, e1, e2, n, .. } = a.shape else {
                                unreachable!()
                            };
                            (
                                d.v0.set(k, v0),
                                d.e1.set(k, e1),
                                d.e2.set(k, e2),
                                l.n.set(k, n),
                            );
                            (d.area[k], d.lu[k], d.par[k]) = (a.area, u, li);
                        }
                        light => {
                            if let Some(s) = light.sample(h.p, u_sel, u, &path.lambda) {
                                l.set(k, &s, pmf);
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
        d.u_lobe[k] = sampler.next_1d();
        d.ub[k] = sampler.next_2d();
    }
    d
}

/// The parallelogram lights drawn in `d`, sampled for all their lanes at once (by area, then
/// to solid angle; the other lanes' results are not used), into `l`.
#[inline(always)]
fn sample_parallelograms(
    scene: &Scene,
    slots: &[Option<PathStart>; N],
    g: &Geometry,
    d: &Draws,
    l: &mut LightLanes,
) {
    let is_par: [bool; N] = lanes(|k| d.par[k] != usize::MAX);
    let points = parallelogram_points(
        &d.v0,
        &d.e1,
        &d.e2,
        &lanes(|k| d.lu[k].x),
        &lanes(|k| d.lu[k].y),
    );
    let sa = to_solid_angle(&g.p, &points, &l.n, &d.area);
    l.wi = V3::select(&is_par, &sa.wi, &l.wi);
    l.p = V3::select(&is_par, &points, &l.p);
    for k in 0..N {
        if !(is_par[k] && sa.ok[k]) {
            continue;
        }
        let Light::Area(a) = &scene.lights[d.par[k]] else {
            unreachable!("drawn as an area light")
        };
        let LightShape::Parallelogram { uv, .. } = a.shape else {
            unreachable!("drawn as a parallelogram")
        };
        if sa.front[k] {
            let u = d.lu[k];
            let lambda = &slots[k].as_ref().expect("a scattering path").path.lambda;
            l.radiance[k] = a.radiance_at_uv(uv[0] + uv[1] * u.x + uv[2] * u.y, lambda);
        }
        (l.have[k], l.dist[k], l.pdf[k]) = (true, sa.dist[k], d.pmf[k] * sa.pdf[k]);
    }
}

/// Each lane's BSDF towards its light sample (`f`, and the pdf where MIS needs it) and its
/// BSDF sample: plain Lambertian surfaces in lanes (with `SurfaceBsdf`'s two-sided mirroring),
/// the others per path.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn bsdfs(
    s: &PathSettings,
    g: &Geometry,
    d: &Draws,
    l: &LightLanes,
    wi: &V3<N>,
) -> ([SampledSpectrum; N], [f32; N], [Option<BsdfSample>; N]) {
    let wo = &g.wo;
    let mut albedo = [SampledSpectrum::ZERO; N];
    let mut lane_lambert = [false; N];
    let mut mirror = [1.0f32; N];
    for k in 0..N {
        if let Some((r, two_sided)) = d.bsdf(k).and_then(|b| b.plain_lambert()) {
            (albedo[k], lane_lambert[k]) = (r, true);
            mirror[k] = mirror_side(two_sided, false, wo.z[k]);
        }
    }
    let wo_z: [f32; N] = lanes(|k| wo.z[k] * mirror[k]);
    let wi_z: [f32; N] = lanes(|k| wi.z[k] * mirror[k]);
    let lambert_f = Lambert::eval_lanes(&albedo, &wo_z, &wi_z);
    let lambert_pdf = Lambert::pdf_lanes(&wo_z, &wi_z);
    let (lambert_wi, lambert_spdf, lambert_ok) =
        Lambert::sample_lanes(&wo_z, &lanes(|k| d.ub[k].x), &lanes(|k| d.ub[k].y));
    let mut f = [SampledSpectrum::ZERO; N];
    let mut bsdf_pdf = [0.0f32; N];
    let mut bs: [Option<BsdfSample>; N] = [None; N];
    for k in 0..N {
        let Some(b) = d.bsdf(k) else { continue };
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
        bs[k] = b.sample(wo.get(k), d.u_lobe[k], d.ub[k]);
    }
    (f, bsdf_pdf, bs)
}

/// The shadow rays' segments from `origin` to the light points offset off their own surfaces
/// (a light without a surface normal, or a distant one, needs no offset there), and their
/// lengths.
#[inline(always)]
fn shadow_segments(origin: &V3<N>, l: &LightLanes) -> (V3<N>, [f32; N]) {
    let nwd = l.n.dot(&l.wi.neg());
    let lifted = offset_ray_origins(&l.p, &l.n.scale(&lanes(|k| nwd[k].signum())));
    let no_normal: [bool; N] = lanes(|k| l.n.get(k) == Vec3::ZERO);
    let target = V3::select(&no_normal, &l.p, &lifted);
    let seg = target.sub(origin);
    let seg2 = seg.dot(&seg);
    (seg, lanes(|k| seg2[k].sqrt()))
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
