//! The scattering step of the path tracer, for every path in flight at once: at each path's
//! hit, the light sample (next-event estimation, whose shadow ray it leaves for the next pass),
//! the BSDF sample that makes the next segment, and Russian roulette.
//!
//! One implementation for every material, texture and light, in lanes (one per path, see
//! `pt_math::lanes`): the geometry (shading frames, ray offsets, local directions, shadow
//! rays, MIS weights) runs for all paths at once in SIMD lanes; each path's BSDF and light are
//! evaluated per lane, except the models written as lane kernels, which run for all paths
//! that have them at once: Lambert's BSDF, the rough conductor, parallelogram area lights and
//! sphere lights (the commonest of real scenes). Those kernels are the models' only
//! implementation (their single-value functions are the kernels with one lane), so lanes and
//! single paths cannot drift apart. Each path draws its random numbers in the same order as
//! it would alone.
//!
//! Three passes over the lanes do what cannot run in SIMD: the draws (gathering each hit,
//! resolving its BSDF, drawing its random numbers and its light), the models without a lane
//! kernel, and the results (shadow rays, next segments). Between them the lane kernels run
//! for all lanes; a lane whose result is not used costs nothing extra in a SIMD register.

use crate::path::{PathSettings, PathStart, PathState, Strategy, MAX_PATHS};
use pt_bsdf::{mirror_side, Bsdf, Distribution, Lambert, RoughConductor, SampleLanes, SurfaceBsdf};
use pt_math::lanes::{lanes, mask_of, offset_ray_origins, set_lanes, Frames, Mask, V3};
use pt_math::{offset_coordinate, power_heuristic, Frame, Ray, Vec2, Vec3};
use pt_render::geometry::Interaction;
use pt_render::light::{
    parallelogram_points, sphere_cone_lanes, to_solid_angle, Light, LightSample, LightShape,
};
use pt_render::sampler::RandomSource;
use pt_render::scene::SHADOW_RAY_SHORTEN;
use pt_render::Scene;
use pt_spectrum::SampledSpectrum;

/// Lanes: one per path in flight.
const N: usize = MAX_PATHS;

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
        self.wi.set(k, s.wi);
        self.p.set(k, s.p);
        self.n.set(k, s.n);
        (self.dist[k], self.radiance[k], self.pdf[k], self.delta[k]) =
            (s.dist, s.radiance, pmf * s.pdf, s.delta);
    }
}

/// What the first pass gathers and draws for each scattering lane: its hit, its BSDF (the
/// material's own when nothing varies over it, not copied; else evaluated into the caller's
/// storage), the uniform numbers of its BSDF sample, and its light choice.
struct Draws<'a> {
    /// Hit points, world space.
    p: V3<N>,
    /// Geometric normals, world space.
    ng: V3<N>,
    /// Shading normals, world space.
    ns: V3<N>,
    /// dp/du, world space (zero without uvs).
    dpdu: V3<N>,
    /// The arriving rays' directions, world space.
    dir: V3<N>,
    /// The lanes' BSDFs when they are their materials' own (nothing varies over them); the
    /// others are in the BSDFs built at the hits.
    fixed: [Option<&'a SurfaceBsdf>; N],
    /// The lanes whose BSDF is a plain Lambertian one (run in lanes), with its albedo and
    /// two-sidedness.
    lambert: Mask,
    albedo: [SampledSpectrum; N],
    /// Whether a lane's plain surface (Lambertian or rough conductor) is two-sided.
    two_sided: [bool; N],
    /// The lanes whose BSDF is a plain rough conductor (run in lanes), and those of them with
    /// a Beckmann distribution (the others are GGX).
    conductor: Mask,
    beckmann: Mask,
    /// Uniform numbers of the BSDF sample: lobe choice, direction (its two coordinates as
    /// two lane arrays, the form the lane kernels read).
    u_lobe: [f32; N],
    ub: [[f32; N]; 2],
    /// The lanes that drew a parallelogram light (sampled in lanes); its index, corner,
    /// edges, area and uniform numbers.
    par: Mask,
    light_index: [usize; N],
    v0: V3<N>,
    e1: V3<N>,
    e2: V3<N>,
    area: [f32; N],
    lu: [[f32; N]; 2],
    /// The radiance of a parallelogram or sphere light that is the same all over it, and the
    /// parallelogram lanes whose light has a texture instead (evaluated once the point is
    /// known).
    light_radiance: [SampledSpectrum; N],
    par_textured: Mask,
    /// The lanes that drew a sphere light without a texture (sampled by solid angle in lanes
    /// where the hit is outside the sphere), its centre, radius and orientation, and the
    /// light selection's reused uniform number (area sampling from inside the sphere needs it).
    sphere: Mask,
    center: V3<N>,
    radius: [f32; N],
    flip: [bool; N],
    u_sel: [f32; N],
    /// Light selection probabilities.
    pmf: [f32; N],
}

impl Draws<'_> {
    /// Nothing drawn yet (harmless values in every lane).
    #[inline(always)]
    fn empty() -> Self {
        Draws {
            p: V3::default(),
            ng: V3::default(),
            ns: V3::splat(Vec3::Z),
            dpdu: V3::default(),
            dir: V3::splat(-Vec3::Z),
            fixed: [None; N],
            lambert: 0,
            albedo: [SampledSpectrum::ZERO; N],
            two_sided: [false; N],
            conductor: 0,
            beckmann: 0,
            u_lobe: [0.5; N],
            ub: [[0.5; N]; 2],
            par: 0,
            light_index: [0; N],
            v0: V3::default(),
            e1: V3::default(),
            e2: V3::default(),
            area: [1.0; N],
            lu: [[0.5; N]; 2],
            light_radiance: [SampledSpectrum::ZERO; N],
            par_textured: 0,
            sphere: 0,
            center: V3::default(),
            radius: [1.0; N],
            flip: [false; N],
            u_sel: [0.5; N],
            pmf: [1.0; N],
        }
    }
}

/// The hits' shading geometry, one lane per path: shading frames, the directions towards the
/// viewer in those frames, and the spawn points on both sides.
struct Geometry {
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
    /// The geometry of the hits in `d`.
    #[inline(always)]
    fn new(d: &Draws) -> Self {
        // Without dp/du in any lane (meshes without uvs), the frames from the normals alone:
        // the same frames, without the projection of the tangents.
        let tangent: [bool; N] =
            lanes(|k| (d.dpdu.x[k] != 0.0) | (d.dpdu.y[k] != 0.0) | (d.dpdu.z[k] != 0.0));
        if mask_of(&tangent) == 0 {
            Geometry::with_frames(d, |k| Frame::from_normal(d.ns.get(k)))
        } else {
            Geometry::with_frames(d, |k| {
                Frame::from_normal_tangent(d.ns.get(k), d.dpdu.get(k))
            })
        }
    }

    /// The geometry of the hits in `d` with the shading frames `frame(lane)`: one loop whose
    /// body is a whole lane, which the compiler vectorises as one piece.
    #[inline(always)]
    fn with_frames(d: &Draws, frame: impl Fn(usize) -> Frame) -> Self {
        let mut g = Geometry {
            n_out: V3::default(),
            frames: Frames::from_fn(|_| Frame::from_normal(Vec3::Z)),
            wo: V3::default(),
            out: V3::default(),
            back: V3::default(),
        };
        for k in 0..N {
            let (ng, dir) = (d.ng.get(k), d.dir.get(k));
            let f = frame(k);
            // Rays leave the hit offset to one side of the surface: the side the path came
            // from, or the other one for transmission.
            let n_out = ng * -ng.dot(dir).signum();
            g.frames.set(k, f);
            g.wo.set(k, f.to_local(-dir));
            g.n_out.set(k, n_out);
        }
        // Coordinate by coordinate in lanes (the single-point form packs one point's three
        // coordinates into one SIMD register instead).
        g.out = offset_ray_origins(&d.p, &g.n_out);
        g.back = offset_ray_origins(&d.p, &g.n_out.neg());
        g
    }

    /// The lanes' origins for rays leaving in the world directions `dir`: on the side each
    /// leaves to. A select of whole lanes (a select per lane inside a loop became a choice of
    /// addresses, which kept the loop out of SIMD registers).
    #[inline(always)]
    fn origins(&self, dir: &V3<N>) -> V3<N> {
        let front: [bool; N] = lanes(|k| self.n_out.get(k).dot(dir.get(k)) >= 0.0);
        V3::select(&front, &self.out, &self.back)
    }
}

/// The lanes' BSDF values towards their light samples and their BSDF samples (structure of
/// arrays; see `pt_bsdf::BsdfSample`).
struct Scattering {
    /// The BSDF towards the light sample (zero without one).
    f: [SampledSpectrum; N],
    /// Its pdf of the light sample's direction, where MIS needs it (else 0).
    bsdf_pdf: [f32; N],
    /// The lanes with a BSDF sample (the others are absorbed); the samples follow.
    sampled: Mask,
    /// Sampled directions, local frames.
    wi: V3<N>,
    /// Throughput multipliers.
    weight: [SampledSpectrum; N],
    /// Solid-angle pdfs (a delta lobe's: its discrete probability).
    pdf: [f32; N],
    /// Whether the sample came from a delta lobe.
    delta: [bool; N],
    /// Relative indices of refraction along the sampled directions.
    eta: [f32; N],
    /// The lanes whose sample passes straight through ([`pt_bsdf::BsdfSample::is_pass_through`]).
    pass_through: Mask,
}

impl Scattering {
    /// Nothing evaluated yet.
    #[inline(always)]
    fn empty() -> Self {
        Scattering {
            f: [SampledSpectrum::ZERO; N],
            bsdf_pdf: [0.0; N],
            sampled: 0,
            wi: V3::splat(Vec3::Z),
            weight: [SampledSpectrum::ZERO; N],
            pdf: [0.0; N],
            delta: [false; N],
            eta: [1.0; N],
            pass_through: 0,
        }
    }
}

/// The scattering of the paths in `slots` that scatter at their hits (the lanes of `todo`),
/// all at once.
#[inline(always)]
pub(crate) fn scatter<S: RandomSource>(
    scene: &Scene,
    s: &PathSettings,
    slots: &mut [Option<PathStart<S>>; N],
    hits: &[Option<Interaction>; N],
    todo: Mask,
) {
    // Filled in place, not returned: the BSDFs are large, and returned arrays of them are
    // copied.
    let mut built: [Option<SurfaceBsdf>; N] = [None; N];
    let mut d = Draws::empty();
    let mut l = LightLanes::empty();
    draw(scene, s, slots, hits, todo, &mut built, &mut d, &mut l);
    let g = Geometry::new(&d);
    // The lane kernels run when some lane needs them (one well-predicted branch per scene).
    if d.par != 0 {
        sample_parallelograms(scene, slots, &d, &mut l);
    }
    if d.sphere != 0 {
        sample_spheres(scene, slots, &d, &mut l);
    }
    let wi = g.frames.to_local(&l.wi);
    let mut sc = Scattering::empty();
    if d.lambert != 0 {
        lambert_lanes(&g, &d, &wi, &mut sc);
    }
    if d.conductor != 0 {
        conductor_lanes(&g, &d, &built, &l, &wi, &mut sc);
    }
    let in_lanes = d.lambert | d.conductor;
    other_bsdfs(s, &g, &d, &built, &l, &wi, todo & !in_lanes, &mut sc);
    // The shadow rays leave on the side of the hit the light is on; the next segments on the
    // side each sampled direction leaves to.
    let shadow = ShadowRays::new(s, &g, &l, &sc, &wi);
    let next_dir = g.frames.to_world(&sc.wi);
    let next_origin = g.origins(&next_dir);
    for k in set_lanes(todo) {
        let (Some(h), Some(PathStart { path, sampler, .. })) = (&hits[k], &mut slots[k]) else {
            continue;
        };
        if shadow.traced & (1 << k) != 0 {
            let ray = Ray {
                origin: shadow.origin.get(k),
                dir: shadow.dir.get(k),
                tmin: 0.0,
                tmax: shadow.tmax[k],
            };
            path.shadow = Some((
                ray,
                path.throughput * sc.f[k] * l.radiance[k] * shadow.scale[k],
            ));
        }
        path.covered |= sc.pass_through & (1 << k) == 0;
        if sc.sampled & (1 << k) == 0 || sc.weight[k].is_black() {
            path.alive = false;
            continue;
        }
        path.throughput *= sc.weight[k];
        path.eta_scale *= sc.eta[k];
        path.prev_p = h.p;
        path.prev_pdf = sc.pdf[k];
        path.prev_delta = sc.delta[k];
        path.ray = Ray::new(next_origin.get(k), next_dir.get(k));
        path.depth += 1;
        russian_roulette(s, path, sampler);
    }
}

/// The first pass, per path, in the order a path alone draws them: its hit, its BSDF,
/// fluorescence, the light choice and the light's uniform numbers (lights other than
/// parallelograms sampled here, into `l`), the BSDF sample's uniform numbers.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn draw<'a, S: RandomSource>(
    scene: &'a Scene,
    s: &PathSettings,
    slots: &mut [Option<PathStart<S>>; N],
    hits: &[Option<Interaction>; N],
    todo: Mask,
    built: &mut [Option<SurfaceBsdf>; N],
    d: &mut Draws<'a>,
    l: &mut LightLanes,
) {
    let use_light = s.strategy != Strategy::Bsdf;
    for k in set_lanes(todo) {
        let (Some(h), Some(PathStart { path, sampler, .. })) = (&hits[k], &mut slots[k]) else {
            continue;
        };
        d.p.set(k, h.p);
        d.ng.set(k, h.ng);
        d.ns.set(k, h.ns);
        d.dpdu.set(k, h.dpdu);
        d.dir.set(k, path.ray.dir);
        let material = scene.material(h.shape);
        let (bsdf, lambert): (&SurfaceBsdf, _) = match &material.fixed {
            Some(b) => (d.fixed[k].insert(b), material.fixed_lambert),
            None => {
                let b = built[k].insert(scene.bsdf(h, &path.lambda).into_owned());
                (b, b.plain_lambert())
            }
        };
        if let Some((r, two_sided)) = lambert {
            (d.albedo[k], d.two_sided[k]) = (r, two_sided);
            d.lambert |= 1 << k;
        } else if let Some((Bsdf::RoughConductor(c), two_sided)) = bsdf.plain_model() {
            d.two_sided[k] = two_sided;
            d.conductor |= 1 << k;
            d.beckmann |= Mask::from(c.mf.dist == Distribution::Beckmann) << k;
        }
        // Fluorescence: the BSDF holds each lane's total albedo at its emitted wavelength; now
        // some lanes move to an excitation wavelength, used by NEE and the rest of the path.
        if let Some(f) = material.fluorescent() {
            path.lambda = f.scatter(&path.lambda, sampler.next_1d());
            if path.awaits_fluorescence {
                // What the path found before this vertex is the other side's to count.
                path.radiance = SampledSpectrum::ZERO;
                path.awaits_fluorescence = false;
            }
        }
        if use_light && bsdf.has_smooth_lobe() {
            match scene.sample_light_at(h.p, sampler.next_1d()) {
                Some((li, pmf, u_sel)) => {
                    let u = sampler.next_2d();
                    d.pmf[k] = pmf;
                    let light = &scene.lights[li];
                    // Parallelograms, and spheres of constant radiance, are sampled for all lanes
                    // at once after this loop; every other light here, lane by lane.
                    'lane: {
                        if let Light::Area(a) = light {
                            match &a.shape {
                                LightShape::Parallelogram { v0, e1, e2, n, .. } => {
                                    d.v0.set(k, *v0);
                                    d.e1.set(k, *e1);
                                    d.e2.set(k, *e2);
                                    l.n.set(k, *n);
                                    (d.area[k], d.light_index[k]) = (a.area, li);
                                    (d.lu[0][k], d.lu[1][k]) = (u.x, u.y);
                                    d.par |= 1 << k;
                                    match a.constant_radiance(&path.lambda) {
                                        Some(r) => d.light_radiance[k] = r,
                                        None => d.par_textured |= 1 << k,
                                    }
                                    break 'lane;
                                }
                                LightShape::Sphere {
                                    center,
                                    radius,
                                    flip,
                                    ..
                                } => {
                                    if let Some(r) = a.constant_radiance(&path.lambda) {
                                        d.center.set(k, *center);
                                        (d.radius[k], d.flip[k]) = (*radius, *flip);
                                        d.light_radiance[k] = r;
                                        (d.lu[0][k], d.lu[1][k], d.u_sel[k]) = (u.x, u.y, u_sel);
                                        d.light_index[k] = li;
                                        d.sphere |= 1 << k;
                                        break 'lane;
                                    }
                                }
                                _ => {}
                            }
                        }
                        if let Some(s) = light.sample(h.p, u_sel, u, &path.lambda) {
                            l.set(k, &s, pmf);
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
        let ub = sampler.next_2d();
        (d.ub[0][k], d.ub[1][k]) = (ub.x, ub.y);
    }
}

/// The parallelogram lights drawn in `d`, sampled for all lanes at once (by area, then to
/// solid angle; only the lanes of `d.par` take the results), into `l`.
#[inline(always)]
fn sample_parallelograms<S: RandomSource>(
    scene: &Scene,
    slots: &[Option<PathStart<S>>; N],
    d: &Draws,
    l: &mut LightLanes,
) {
    let points = parallelogram_points(&d.v0, &d.e1, &d.e2, &d.lu[0], &d.lu[1]);
    let sa = to_solid_angle(&d.p, &points, &l.n, &d.area);
    let is_par: [bool; N] = lanes(|k| d.par & (1 << k) != 0);
    let taken: [bool; N] = lanes(|k| is_par[k] & sa.ok[k]);
    l.wi = V3::select(&is_par, &sa.wi, &l.wi);
    l.p = V3::select(&is_par, &points, &l.p);
    // Selects, not branches: the lanes that took a parallelogram sample.
    for k in 0..N {
        let t = taken[k];
        l.have[k] |= t;
        l.dist[k] = if t { sa.dist[k] } else { l.dist[k] };
        l.pdf[k] = if t { d.pmf[k] * sa.pdf[k] } else { l.pdf[k] };
        // The back side emits nothing.
        l.radiance[k] = if t & sa.front[k] {
            d.light_radiance[k]
        } else {
            l.radiance[k]
        };
    }
    for k in set_lanes(d.par_textured) {
        if !(taken[k] && sa.front[k]) {
            continue;
        }
        let Light::Area(a) = &scene.lights[d.light_index[k]] else {
            unreachable!("drawn as an area light")
        };
        let LightShape::Parallelogram { uv, .. } = &a.shape else {
            unreachable!("drawn as a parallelogram")
        };
        let u = Vec2::new(d.lu[0][k], d.lu[1][k]);
        let lambda = &slots[k].as_ref().expect("a scattering path").path.lambda;
        l.radiance[k] = a.radiance_at_uv(uv[0] + uv[1] * u.x + uv[2] * u.y, lambda);
    }
}

/// The sphere lights drawn in `d`, sampled by solid angle for all lanes at once
/// ([`sphere_cone_lanes`]), into `l`; a lane whose hit is inside its sphere samples it by area
/// (`Light::sample`), as a path alone does.
#[inline(always)]
fn sample_spheres<S: RandomSource>(
    scene: &Scene,
    slots: &[Option<PathStart<S>>; N],
    d: &Draws,
    l: &mut LightLanes,
) {
    let c = sphere_cone_lanes(&d.center, &d.radius, &d.p, &d.lu[0], &d.lu[1]);
    for k in set_lanes(d.sphere) {
        if !c.outside[k] {
            let lambda = &slots[k].as_ref().expect("a scattering path").path.lambda;
            let u = Vec2::new(d.lu[0][k], d.lu[1][k]);
            let light = &scene.lights[d.light_index[k]];
            if let Some(s) = light.sample(d.p.get(k), d.u_sel[k], u, lambda) {
                l.set(k, &s, d.pmf[k]);
            }
            continue;
        }
        if !c.ok[k] {
            continue;
        }
        let (wi, n_out) = (c.wi.get(k), c.n_out.get(k));
        let n = if d.flip[k] { -n_out } else { n_out };
        // The back side emits nothing.
        let radiance = if n.dot(-wi) > 0.0 {
            d.light_radiance[k]
        } else {
            SampledSpectrum::ZERO
        };
        let sample = LightSample {
            p: c.p.get(k),
            n,
            wi,
            dist: c.dist[k],
            radiance,
            pdf: c.pdf[k],
            delta: false,
        };
        l.set(k, &sample, d.pmf[k]);
    }
}

/// Lambert's BSDF towards the light samples and its samples, for all lanes at once (with
/// `SurfaceBsdf`'s two-sided mirroring), into `out`: the results count in the lanes of
/// `d.lambert`; [`other_bsdfs`] then overwrites the others.
#[inline(always)]
fn lambert_lanes(g: &Geometry, d: &Draws, wi: &V3<N>, out: &mut Scattering) {
    let mirror: [f32; N] = lanes(|k| mirror_side(d.two_sided[k], false, g.wo.z[k]));
    let wo_z: [f32; N] = lanes(|k| g.wo.z[k] * mirror[k]);
    let wi_z: [f32; N] = lanes(|k| wi.z[k] * mirror[k]);
    out.f = Lambert::eval_lanes(&d.albedo, &wo_z, &wi_z);
    out.bsdf_pdf = Lambert::pdf_lanes(&wo_z, &wi_z);
    let (s_wi, s_pdf, s_ok) = Lambert::sample_lanes(&wo_z, &d.ub[0], &d.ub[1]);
    out.wi = V3 {
        z: lanes(|k| s_wi.z[k] * mirror[k]),
        ..s_wi
    };
    (out.weight, out.pdf) = (d.albedo, s_pdf);
    out.sampled = mask_of(&s_ok) & d.lambert;
}

/// The plain rough conductors (the lanes of `d.conductor`), with `SurfaceBsdf`'s two-sided
/// mirroring, into `out`: the values and pdfs towards the light samples and the BSDF samples,
/// from the model's lane kernels, for all lanes of each distribution at once. (The rough
/// plastic run the same way was no faster: its Beckmann sampling and coating tables are lane
/// by lane, and `mesh-100k` took 1.01-1.02 times as long.)
#[inline(always)]
fn conductor_lanes(
    g: &Geometry,
    d: &Draws,
    built: &[Option<SurfaceBsdf>; N],
    l: &LightLanes,
    wi: &V3<N>,
    out: &mut Scattering,
) {
    // The lanes' models side by side (copies: read through references, one per lane, the
    // kernels took 1.035 times as long on `veach-mis`), stand-ins elsewhere.
    let mut m = [RoughConductor::UNUSED; N];
    for k in set_lanes(d.conductor) {
        match d.fixed[k].or(built[k].as_ref()).map(|b| &b.bsdf) {
            Some(Bsdf::RoughConductor(c)) => m[k] = *c,
            _ => unreachable!("drawn as a rough conductor"),
        }
    }
    let mirror: [f32; N] = lanes(|k| mirror_side(d.two_sided[k], false, g.wo.z[k]));
    let wo = V3 {
        z: lanes(|k| g.wo.z[k] * mirror[k]),
        ..g.wo
    };
    let to_light = V3 {
        z: lanes(|k| wi.z[k] * mirror[k]),
        ..*wi
    };
    let (u0, u1) = (&d.ub[0], &d.ub[1]);
    let ggx = d.conductor & !d.beckmann;
    if ggx != 0 {
        let light = RoughConductor::eval_pdf_lanes::<N, false>(&m, &wo, &to_light);
        let sample = RoughConductor::sample_lanes::<N, false>(&m, &wo, u0, u1, ggx);
        lane_results(ggx, &mirror, l, light, &sample, out);
    }
    if d.beckmann != 0 {
        let light = RoughConductor::eval_pdf_lanes::<N, true>(&m, &wo, &to_light);
        let sample = RoughConductor::sample_lanes::<N, true>(&m, &wo, u0, u1, d.beckmann);
        lane_results(d.beckmann, &mirror, l, light, &sample, out);
    }
}

/// [`conductor_lanes`]' results for the lanes of `mask`: the values and pdfs towards the
/// light samples (`f`, `pdf`), and the BSDF samples, mirrored back to the side each path
/// sees.
#[inline(always)]
fn lane_results(
    mask: Mask,
    mirror: &[f32; N],
    l: &LightLanes,
    (f, pdf): ([SampledSpectrum; N], [f32; N]),
    sample: &SampleLanes<N>,
    out: &mut Scattering,
) {
    for k in set_lanes(mask) {
        if l.have[k] {
            (out.f[k], out.bsdf_pdf[k]) = (f[k], pdf[k]);
        }
        if sample.ok[k] {
            let w = sample.wi.get(k);
            out.wi.set(k, Vec3::new(w.x, w.y, w.z * mirror[k]));
            (out.weight[k], out.pdf[k]) = (sample.weight[k], sample.pdf[k]);
            (out.delta[k], out.eta[k]) = (false, 1.0);
            out.sampled |= 1 << k;
        }
    }
}

/// The BSDFs without a lane kernel (the lanes of `todo`), one path at a time: the value
/// towards the light sample (and the pdf where MIS needs it) and the BSDF sample, into `out`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn other_bsdfs(
    s: &PathSettings,
    g: &Geometry,
    d: &Draws,
    built: &[Option<SurfaceBsdf>; N],
    l: &LightLanes,
    wi: &V3<N>,
    todo: Mask,
    out: &mut Scattering,
) {
    for k in set_lanes(todo) {
        let Some(b) = d.fixed[k].or(built[k].as_ref()) else {
            continue;
        };
        let wo = g.wo.get(k);
        let (u_lobe, u) = (d.u_lobe[k], Vec2::new(d.ub[0][k], d.ub[1][k]));
        (out.f[k], out.bsdf_pdf[k]) = (SampledSpectrum::ZERO, 0.0);
        let mut sample = None;
        if l.have[k] {
            let w = wi.get(k);
            // Only MIS needs the BSDF's pdf of the light's direction; with it, both from one
            // call (the models share terms between the two), and the sample from the same
            // call (the hair model's setup for `wo` serves all three).
            if s.strategy != Strategy::Light && !l.delta[k] && !l.radiance[k].is_black() {
                let both = b.eval_pdf_and_sample(wo, w, u_lobe, u);
                ((out.f[k], out.bsdf_pdf[k]), sample) = (both.0, Some(both.1));
            } else {
                out.f[k] = b.eval(wo, w);
            }
        }
        let sample = sample.unwrap_or_else(|| b.sample(wo, u_lobe, u));
        if let Some(bs) = sample {
            out.wi.set(k, bs.wi);
            (out.weight[k], out.pdf[k]) = (bs.weight, bs.pdf);
            (out.delta[k], out.eta[k]) = (bs.delta, bs.eta);
            out.sampled |= 1 << k;
            out.pass_through |= Mask::from(bs.is_pass_through(wo)) << k;
        }
    }
}

/// The lanes' shadow rays (the lanes of `traced`), and the factor of each one's contribution
/// besides the throughput, the BSDF and the radiance: |cos theta_i| times the MIS weight over
/// the light sample's pdf.
struct ShadowRays {
    traced: Mask,
    origin: V3<N>,
    dir: V3<N>,
    tmax: [f32; N],
    scale: [f32; N],
}

impl ShadowRays {
    /// The shadow rays of the light samples `l`: from the hits, on the side the light is on,
    /// to the light points offset off their own surfaces (a light without a surface normal,
    /// or a distant one, needs no offset there), for the lanes where light arrives and the
    /// BSDF passes it.
    #[inline(always)]
    fn new(s: &PathSettings, g: &Geometry, l: &LightLanes, sc: &Scattering, wi: &V3<N>) -> Self {
        // Spectra are four-wide vectors of their own: tested first, so that the loop below is
        // plain numbers, which the compiler vectorises across the lanes.
        let passes: [bool; N] =
            lanes(|k| l.have[k] & !l.radiance[k].is_black() & !sc.f[k].is_black());
        let mis_used = s.strategy != Strategy::Light;
        let mut r = ShadowRays {
            traced: 0,
            origin: V3::default(),
            dir: V3::default(),
            tmax: [0.0; N],
            scale: [0.0; N],
        };
        let mut lit = [false; N];
        let origins = g.origins(&l.wi);
        for k in 0..N {
            let (wi_world, p, n) = (l.wi.get(k), l.p.get(k), l.n.get(k));
            let origin = origins.get(k);
            // Coordinate by coordinate, as the lanes vectorise it.
            let away = n * n.dot(-wi_world).signum();
            let lifted = Vec3::new(
                offset_coordinate(p.x, away.x),
                offset_coordinate(p.y, away.y),
                offset_coordinate(p.z, away.z),
            );
            let no_normal = (n.x == 0.0) & (n.y == 0.0) & (n.z == 0.0);
            let seg = if no_normal { p } else { lifted } - origin;
            let len = seg.dot(seg).sqrt();
            let distant = l.dist[k] == f32::INFINITY;
            let dir = Vec3::new(seg.x / len, seg.y / len, seg.z / len);
            r.origin.set(k, origin);
            r.dir.set(k, if distant { wi_world } else { dir });
            r.tmax[k] = if distant {
                f32::INFINITY
            } else {
                len * SHADOW_RAY_SHORTEN
            };
            lit[k] = passes[k] & (distant | (len > 0.0));
            // Delta lights cannot be hit by BSDF sampling: light sampling is the only
            // strategy, weight 1.
            let mis = power_heuristic(l.pdf[k], sc.bsdf_pdf[k]);
            let w = if mis_used & !l.delta[k] { mis } else { 1.0 };
            r.scale[k] = wi.z[k].abs() * w / l.pdf[k];
        }
        r.traced = mask_of(&lit);
        r
    }
}

/// Russian roulette (Mitsuba: after `rr_depth` segments, keep the path with probability
/// min(max(T) eta^2, 0.95), and divide its throughput by that).
#[inline(always)]
fn russian_roulette<S: RandomSource>(s: &PathSettings, path: &mut PathState, sampler: &mut S) {
    if path.depth >= s.rr_depth {
        let q = (path.throughput.max_value() * path.eta_scale * path.eta_scale).min(0.95);
        if !(sampler.next_1d() < q) {
            path.alive = false;
            return;
        }
        path.throughput *= 1.0 / q;
    }
}
