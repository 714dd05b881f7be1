//! Bidirectional path tracing (`bdpt`; Veach 1997, ch. 10) and vertex connection and merging
//! (`vcm`; Georgiev, Křivánek, Davidovič & Slusallek 2012, "Light Transport Simulation with
//! Vertex Connection and Merging"): pt extensions (Mitsuba 3 has neither).
//!
//! Every iteration (one sample per pixel) traces as many light subpaths as the image has
//! pixels, N, and one camera subpath per pixel; camera subpath k is paired with light
//! subpath k. A full path of `k` segments between a light and the camera is then sampled by
//! every strategy that can make it:
//! - *s = 0*: the camera subpath meets an emitter (or leaves the scene towards an environment);
//! - *s = 1*: light sampling at a camera vertex (next-event estimation);
//! - *s >= 2, t >= 2*: a camera vertex connected to a vertex of its paired light subpath;
//! - *t = 1*: a light vertex connected to the camera and splatted where it lands on the
//!   film (every light subpath, so the camera counts N samples of this strategy per pixel);
//! - *merging* (`vcm` only): a camera vertex gathers the light vertices of all N light
//!   subpaths within the radius `r` of it, a photon-mapping density estimate; its density is
//!   the light subpath's times `pi r^2 N`, which joins it to the connection strategies in one
//!   power heuristic (Georgiev et al. 2012, sec. 4).
//!
//! Each strategy's weight is the power heuristic over all of them, computed from three partial
//! sums carried along each subpath (`dVCM`, `dVC`, `dVM` of Georgiev et al.'s technical report
//! "Implementing Vertex Connection and Merging", 2012, eqs. 31-39; [`SubpathMis`]) instead of
//! walking both subpaths at every connection as pbrt-v4's `MISWeight` does: the same weights
//! (the power heuristic over the same strategies and densities), in constant time per
//! connection. `bdpt` is `vcm` with merging off; with connections off only camera paths meeting
//! emitters and merging remain (a pure photon mapper, [`VcmSettings::connections`]).
//!
//! Densities: solid-angle densities of the BSDFs (forward as sampled, reverse with the
//! directions exchanged), turned into area densities with the geometric normal's cosine;
//! delta lobes leave their factor out (their forward and reverse probabilities cancel). Light
//! emission densities come from [`pt_render::light::Light::emission_pdf`], light sampling's
//! from the light's own `sample`/`pdf` (a sphere light's cone sampling included), the
//! camera's from [`pt_render::camera::Camera::direction_pdf`]. Russian roulette is left out
//! of the weights (it thins every strategy's samples without changing which can make a
//! path, so the weights still sum to one: the estimate stays unbiased).
//!
//! Merging radius: `r_i = r_0 i^((alpha - 1) / 2)` in iteration i (1-based; Georgiev et al.
//! 2012, sec. 5, alpha = 3/4 by default), r_0 = 1% of the scene's bounding radius unless
//! given. Merging is biased at any finite radius (the kernel blurs), consistent as it shrinks.
//! The merged estimate corrects for shading normals (cos_s / cos_g at the camera vertex).
//!
//! Splats: camera subpaths add their estimate at their own film position, light vertices at
//! theirs, in path order, onto the light tracer's film ([`crate::ptracer::add_batches`]):
//! the same image for any number of threads, and per-batch pixel statistics for variance.
//! Spectral mode: light subpath k and camera subpath k share their wavelengths (per path in
//! `bdpt`; per iteration in `vcm`, where any camera path may merge with any light path).
//! Fluorescence: light subpaths end where they meet a fluorescent surface, and a camera
//! subpath that meets one hands the paths through it to the path tracer's strategies
//! ([`crate::path::li_through_fluorescence`], which says why): a partition of path space,
//! so the estimate stays unbiased; paths without fluorescent surfaces keep every strategy.

use crate::grid::PointGrid;
use crate::path::PathSettings;
use crate::ptracer::{
    add_batches, seen_by_camera, shading_frame, to_rgb, walk_light_path, Arrival, AtFluorescence,
    Splat,
};
use pt_bsdf::SurfaceBsdf;
use pt_math::{offset_ray_origin, Frame, Ray, Vec2, Vec3};
use pt_render::light::Light;
use pt_render::sampler::Sampler;
use pt_render::Scene;
use pt_spectrum::{ColorMode, SampledSpectrum, SampledWavelengths};
use rayon::prelude::*;
use std::f32::consts::PI;
use std::sync::atomic::AtomicBool;

/// The key of the light subpaths' random streams (above every pixel key).
const LIGHT_STREAM: u64 = (1 << 63) | 0x5643_4d4c; // "VCML"
/// The key of the camera subpaths' random streams.
const CAMERA_STREAM: u64 = (1 << 63) | 0x5643_4d43; // "VCMC"
/// The key of the subpath pairs' wavelength streams (`bdpt`).
const WAVELENGTH_STREAM: u64 = (1 << 63) | 0x5643_4d57; // "VCMW"

/// Subpaths per work item: each item keeps its splats and light vertices in one list.
const CHUNK: u64 = 1024;

/// The bidirectional methods' own settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VcmSettings {
    /// Vertex merging (`vcm`); off: bidirectional path tracing (`bdpt`).
    pub merging: bool,
    /// Vertex connection: light sampling, connections and the light vertices' splats. Off
    /// (with merging on): only camera paths meeting emitters and merging, a pure photon
    /// mapper under the same weights, for checking (no scene parameter).
    pub connections: bool,
    /// Merging radius of the first iteration (scene units); `None`: 1% of the scene's
    /// bounding sphere radius.
    pub initial_radius: Option<f32>,
    /// Exponent of the radius schedule, in (0, 1) (3/4 by default).
    pub alpha: f32,
}

impl VcmSettings {
    /// `bdpt`: connections only.
    pub fn bdpt() -> Self {
        VcmSettings {
            merging: false,
            connections: true,
            initial_radius: None,
            alpha: 0.75,
        }
    }

    /// `vcm` with its defaults.
    pub fn vcm() -> Self {
        VcmSettings {
            merging: true,
            ..VcmSettings::bdpt()
        }
    }

    /// The method's name, as in `<integrator type="...">`.
    pub fn name(&self) -> &'static str {
        if self.merging {
            "vcm"
        } else {
            "bdpt"
        }
    }

    /// The merging radius of iteration `i` (0-based) for a scene of bounding radius
    /// `scene_radius`.
    pub fn radius(&self, i: u32, scene_radius: f32) -> f32 {
        let r0 = self.initial_radius.unwrap_or(0.01 * scene_radius);
        r0 * ((i + 1) as f32).powf(0.5 * (self.alpha - 1.0))
    }
}

/// The power heuristic's exponent applied to one density or ratio of densities.
#[inline(always)]
fn mis(x: f32) -> f32 {
    x * x
}

/// The iteration's constants that join merging to the connections: with
/// `eta = pi r^2 N` (merging's density over a connection's, per light vertex), `vm`
/// = mis(eta) and `vc` = mis(1 / eta) when merging is on (Georgiev et al.'s report, eq. 20);
/// `conn` = 1 with connections, 0 without: then the terms of the connection strategies,
/// which the report's recursion always carries, are dropped, leaving emission and merging.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Factors {
    vm: f32,
    vc: f32,
    conn: f32,
}

impl Factors {
    /// The factors for `light_paths` light subpaths merged within `radius`.
    pub(crate) fn new(settings: &VcmSettings, radius: f32, light_paths: f32) -> Factors {
        let eta = if settings.merging {
            PI * radius * radius * light_paths
        } else {
            1.0
        };
        Factors {
            vm: if settings.merging { mis(eta) } else { 0.0 },
            vc: if settings.merging {
                mis(1.0 / eta)
            } else {
                0.0
            },
            conn: if settings.connections { 1.0 } else { 0.0 },
        }
    }
}

/// The partial sums of density ratios a subpath carries to its last vertex (Georgiev et al.'s
/// report, sec. 4): with them, the weight of any strategy that uses this vertex follows from
/// the densities at the vertex alone.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SubpathMis {
    /// The strategies that sample this vertex from the other side (`dVCM`).
    pub dvcm: f32,
    /// The connection strategies behind it (`dVC`).
    pub dvc: f32,
    /// The merging strategies behind it (`dVM`).
    pub dvm: f32,
}

impl SubpathMis {
    /// A camera subpath's start: `n_over_pdf` is the number of light subpaths over the
    /// solid-angle density of the camera ray for its pixel.
    pub(crate) fn camera(n_over_pdf: f32) -> Self {
        SubpathMis {
            dvcm: mis(n_over_pdf),
            dvc: 0.0,
            dvm: 0.0,
        }
    }

    /// A light subpath's start: the densities of light sampling (`direct`) and of emission
    /// (`emit`, position times direction), both with the light's selection probability, and
    /// the cosine at the light (1 for point-like and distant lights). A delta light can be
    /// neither hit nor merged at (dVC = dVM = 0).
    pub(crate) fn light(direct: f32, emit: f32, cos_light: f32, delta: bool, f: &Factors) -> Self {
        let dvc = if delta { 0.0 } else { mis(cos_light / emit) };
        SubpathMis {
            dvcm: mis(direct / emit),
            dvc,
            dvm: dvc * f.vc,
        }
    }

    /// The subpath reached its next vertex over a segment of squared length `dist2` (`None`
    /// for a distant light's first segment: its density is per unit area already), meeting
    /// the surface at the geometric cosine `cos`.
    pub(crate) fn arrive(&mut self, dist2: Option<f32>, cos: f32) {
        if let Some(d2) = dist2 {
            self.dvcm *= mis(d2);
        }
        let c = 1.0 / mis(cos);
        self.dvcm *= c;
        self.dvc *= c;
        self.dvm *= c;
    }

    /// The subpath leaves its vertex in a direction sampled with the solid-angle density
    /// `fwd` (reverse: `rev`) at the geometric cosine `cos_out`; `delta` when a delta lobe
    /// was chosen (Georgiev et al.'s report, eqs. 34-38).
    pub(crate) fn scatter(&mut self, cos_out: f32, fwd: f32, rev: f32, delta: bool, f: &Factors) {
        if delta {
            self.dvcm = 0.0;
            self.dvc *= mis(cos_out);
            self.dvm *= mis(cos_out);
        } else {
            let k = mis(cos_out / fwd);
            self.dvc = k * (self.dvc * mis(rev) + self.dvcm * f.conn + f.vm);
            self.dvm = k * (self.dvm * mis(rev) + self.dvcm * f.vc * f.conn + 1.0);
            self.dvcm = mis(1.0 / fwd);
        }
    }
}

/// Weight of a camera subpath meeting an emitter (s = 0): `direct` the area density (solid
/// angle for distant lights) of light sampling choosing the point, `emit` the density of
/// the light emitting towards the previous vertex, both with the selection probability.
#[inline]
pub(crate) fn emission_weight(cam: &SubpathMis, direct: f32, emit: f32, f: &Factors) -> f32 {
    1.0 / (1.0 + mis(direct) * cam.dvcm * f.conn + mis(emit) * cam.dvc)
}

/// Weight of light sampling at a camera vertex (s = 1): `bsdf_fwd` the BSDF's density of the
/// light's direction (0 for a delta light), `direct` the light sampling density (solid
/// angle, with selection), `emit` the light's emission density towards the vertex (with
/// selection), `cos_vertex` and `cos_light` the geometric cosines at both ends, `bsdf_rev`
/// the BSDF's density of the camera side's direction from the light's.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn light_sample_weight(
    cam: &SubpathMis,
    bsdf_fwd: f32,
    direct: f32,
    emit: f32,
    cos_vertex: f32,
    cos_light: f32,
    bsdf_rev: f32,
    f: &Factors,
) -> f32 {
    let w_light = mis(bsdf_fwd / direct);
    let w_camera =
        mis(emit * cos_vertex / (direct * cos_light)) * (f.vm + cam.dvcm + cam.dvc * mis(bsdf_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Weight of connecting a camera vertex and a light vertex (s, t >= 2): `cam_area` the
/// camera vertex's BSDF density of the light vertex (per unit area there), `light_area` the
/// light vertex's of the camera vertex, `light_rev` / `cam_rev` each BSDF's reverse
/// solid-angle density of its own subpath's previous direction.
#[inline]
pub(crate) fn connection_weight(
    light: &SubpathMis,
    cam: &SubpathMis,
    cam_area: f32,
    light_area: f32,
    light_rev: f32,
    cam_rev: f32,
    f: &Factors,
) -> f32 {
    let w_light = mis(cam_area) * (f.vm + light.dvcm + light.dvc * mis(light_rev));
    let w_camera = mis(light_area) * (f.vm + cam.dvcm + cam.dvc * mis(cam_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Weight of a light vertex splatted to the camera (t = 1): `cam_area_over_n` the camera's
/// density of the vertex for one pixel sample (per unit area there) over the number of light
/// subpaths, `light_rev` the vertex's BSDF density of its previous direction from the camera's.
#[inline]
pub(crate) fn camera_weight(
    light: &SubpathMis,
    cam_area_over_n: f32,
    light_rev: f32,
    f: &Factors,
) -> f32 {
    1.0 / (mis(cam_area_over_n) * (f.vm + light.dvcm + light.dvc * mis(light_rev)) + 1.0)
}

/// Weight of merging a light vertex at a camera vertex: `cam_fwd` the camera vertex's BSDF
/// density of the light vertex's arriving direction, `cam_rev` of the camera side's from it.
#[inline]
pub(crate) fn merge_weight(
    light: &SubpathMis,
    cam: &SubpathMis,
    cam_fwd: f32,
    cam_rev: f32,
    f: &Factors,
) -> f32 {
    let w_light = light.dvcm * f.vc * f.conn + light.dvm * mis(cam_fwd);
    let w_camera = cam.dvcm * f.vc * f.conn + cam.dvm * mis(cam_rev);
    1.0 / (w_light + 1.0 + w_camera)
}

/// A light subpath's vertex kept for connections and merging.
#[derive(Clone, Copy, Debug)]
struct LightVertex {
    /// Position, world.
    p: Vec3,
    /// Geometric normal, world.
    ng: Vec3,
    /// Shading frame.
    frame: Frame,
    /// Unit direction towards the previous vertex, local frame.
    wl: Vec3,
    /// The same, world.
    w_light: Vec3,
    /// ng . w_light.
    ng_light: f32,
    /// BSDF at the path's wavelengths.
    bsdf: SurfaceBsdf,
    /// Weight arriving here (importance transport, see [`crate::ptracer`]).
    beta: SampledSpectrum,
    /// The subpath's partial sums at this vertex.
    mis: SubpathMis,
    /// Segments from the light.
    depth: u32,
}

/// What merging needs of a light vertex (kept in the grid, in grid order).
#[derive(Clone, Copy, Debug)]
struct Photon {
    /// Geometric normal, world.
    ng: Vec3,
    /// Unit direction towards the previous vertex, world.
    w_light: Vec3,
    /// Weight arriving here.
    beta: SampledSpectrum,
    /// The subpath's partial sums here.
    mis: SubpathMis,
    /// Segments from the light.
    depth: u32,
}

/// The largest path depth of `s` (Mitsuba's max_depth; -1: none).
fn max_depth(s: &PathSettings) -> u32 {
    if s.max_depth < 0 {
        u32::MAX
    } else {
        s.max_depth as u32
    }
}

/// What an iteration shares: the scene, settings, the merging radius and factors, and for
/// merging the light vertices of all light subpaths (in chunks) and their grid.
struct Iteration<'a> {
    scene: &'a Scene,
    s: &'a PathSettings,
    vcm: &'a VcmSettings,
    f: Factors,
    radius: f32,
    /// Light subpaths per iteration (N).
    n: f32,
    /// P_film / P_image (see [`crate::ptracer`]).
    scale: f32,
    /// Merging: the light subpaths' vertices, per chunk of subpaths (chunk c holds subpaths
    /// c CHUNK.., each subpath's vertices in a range ending at its entry of `ends`).
    chunks: &'a [LightChunk],
    /// Merging: every light vertex.
    grid: Option<PointGrid<Photon>>,
}

/// One chunk of light subpaths: their vertices, where each subpath's end, and their camera
/// splats. Kept from iteration to iteration to reuse the memory.
#[derive(Default)]
struct LightChunk {
    vertices: Vec<LightVertex>,
    ends: Vec<u32>,
    splats: Vec<Splat>,
}

impl Iteration<'_> {
    /// The vertices of light subpath `k` (merging: all were traced before the camera pass).
    fn subpath(&self, k: u64) -> &[LightVertex] {
        let chunk = &self.chunks[(k / CHUNK) as usize];
        let j = (k % CHUNK) as usize;
        let start = if j == 0 {
            0
        } else {
            chunk.ends[j - 1] as usize
        };
        &chunk.vertices[start..chunk.ends[j] as usize]
    }
}

/// The wavelengths of subpath pair `index` of iteration `it`.
fn wavelengths(
    scene: &Scene,
    vcm: &VcmSettings,
    seed: u64,
    it: u32,
    index: u64,
) -> SampledWavelengths {
    match scene.mode {
        ColorMode::Rgb => SampledWavelengths::sample_visible(0.5),
        ColorMode::Spectral if vcm.merging => crate::render::iteration_wavelengths(scene, seed, it),
        ColorMode::Spectral => SampledWavelengths::sample_visible(
            Sampler::new(seed, WAVELENGTH_STREAM, (u64::from(it) << 32) | index).next_1d(),
        ),
    }
}

/// Traces light subpath `index`: its vertices (non-delta surfaces) appended to `out`, its
/// camera splats (t = 1) to `splats`.
#[allow(clippy::too_many_arguments)]
fn light_subpath(
    scene: &Scene,
    s: &PathSettings,
    vcm: &VcmSettings,
    f: &Factors,
    scale: f32,
    sampler: &mut Sampler,
    lambda: &SampledWavelengths,
    out: &mut Vec<LightVertex>,
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
                bsdf: *v.bsdf,
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
        |_, _| {},
    );
}

/// Traces camera subpath `index` (pixel `index` of the image) and returns its film position
/// and estimate: emission met (s = 0), light sampling (s = 1), connections to the vertices
/// of its light subpath, `light_vertices`, and merging with every light subpath.
fn camera_subpath(
    it: &Iteration,
    sampler: &mut Sampler,
    lambda: &SampledWavelengths,
    index: usize,
    width: u32,
    light_vertices: &[LightVertex],
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
    let max_depth = max_depth(s);
    let mut eta = 1.0f32;
    let mut depth = 1u32;
    loop {
        let Some(hit) = scene.intersect(&ray) else {
            // Distant lights seen (s = 0).
            if depth == 1 && s.hide_emitters {
                break;
            }
            for &i in &scene.infinite_lights {
                let l = &scene.lights[i];
                let le = l.escaped_radiance(ray.dir, lambda);
                if le.is_black() {
                    continue;
                }
                let w = if depth == 1 {
                    1.0
                } else {
                    let direct = scene.light_pmf(i) * l.escaped_pdf(ray.dir);
                    let emit = direct / (PI * scene.bounds.1 * scene.bounds.1);
                    emission_weight(&mis_state, direct, emit, f)
                };
                radiance += beta * le * w;
            }
            break;
        };
        let wo_world = -ray.dir;
        let frame = shading_frame(&hit);
        let wo = frame.to_local(wo_world);
        let ng_wo = hit.ng.dot(wo_world);
        mis_state.arrive(Some((hit.p - prev).length_squared()), ng_wo.abs());
        // Emitters met (s = 0).
        if let Some((li, light)) = scene.shape_light(hit.shape) {
            let le = light.emitted(hit.ns, wo_world, hit.uv, lambda);
            if !(le.is_black() || depth == 1 && s.hide_emitters) {
                let w = if depth == 1 {
                    1.0
                } else {
                    let pmf = scene.light_pmf(li);
                    let d2 = (hit.p - prev).length_squared();
                    let direct = pmf * light.pdf(prev, hit.p, hit.ns) * ng_wo.abs() / d2;
                    let (pos, dir) = scene.lights[li].emission_pdf(hit.ns, wo_world, scene.bounds);
                    emission_weight(&mis_state, direct, pmf * pos * dir, f)
                };
                radiance += beta * le * w;
            }
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
                    radiance += beta * connect(it, &hit, &frame, &bsdf, wo, &mis_state, lv);
                }
            }
            // Merging with the light vertices of every subpath nearby.
            if let Some(grid) = &it.grid {
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
                    let w =
                        merge_weight(&ph.mis, &mis_state, bsdf.pdf(wo, wi), bsdf.pdf(wi, wo), f);
                    sum += fv * ph.beta * (w * wi.z.abs() / ng_wi.abs());
                });
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

/// Camera subpath `k` as a camera sample for the film (black ones too: their filter weights
/// count in the pixels' averages).
fn camera_sample(
    it: &Iteration,
    sampler: &mut Sampler,
    lambda: &SampledWavelengths,
    k: u64,
    width: u32,
    own: &[LightVertex],
) -> Splat {
    let (film, l) = camera_subpath(it, sampler, lambda, k as usize, width, own);
    Splat {
        film,
        rgb: to_rgb(it.scene, l, lambda),
        camera: true,
    }
}

/// Light sampling at a camera vertex (s = 1), weighted.
#[allow(clippy::too_many_arguments)]
fn light_sample(
    it: &Iteration,
    hit: &pt_render::geometry::Interaction,
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
fn connect(
    it: &Iteration,
    hit: &pt_render::geometry::Interaction,
    frame: &Frame,
    bsdf: &SurfaceBsdf,
    wo: Vec3,
    cam: &SubpathMis,
    lv: &LightVertex,
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
    let f_light = lv.bsdf.eval(wl_cam, lv.wl);
    if f_cam.is_black() || f_light.is_black() {
        return SampledSpectrum::ZERO;
    }
    let cam_area = bsdf.pdf(wo, wi) * ng_l.abs() / dist2;
    let light_area = lv.bsdf.pdf(lv.wl, wl_cam) * ng_c.abs() / dist2;
    let weight = connection_weight(
        &lv.mis,
        cam,
        cam_area,
        light_area,
        lv.bsdf.pdf(wl_cam, lv.wl),
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

/// Renders `settings.spp` iterations into `state` (a light film), checking `cancel` between
/// iterations. Returns whether all were done.
pub fn render_vcm_passes(
    scene: &Scene,
    settings: &crate::RenderSettings,
    vcm: &VcmSettings,
    state: &mut crate::RenderState,
    cancel: &AtomicBool,
    checkpoint: Option<&crate::Checkpoint>,
    progress: &(dyn Fn(u64) + Sync),
) -> bool {
    let (w, h) = (settings.width, settings.height);
    let paths = u64::from(w) * u64::from(h);
    let [fw, fh] = settings.crop.map_or([w, h], |c| c.film_size);
    let scale = (f64::from(fw) * f64::from(fh)) / paths as f64;
    let s = &settings.path;
    let chunks = paths.div_ceil(CHUNK);
    let range = |c: u64| c * CHUNK..((c + 1) * CHUNK).min(paths);
    let mut pool: Vec<LightChunk> = (0..chunks).map(|_| LightChunk::default()).collect();
    crate::render::in_passes(
        state,
        settings.spp,
        cancel,
        &mut crate::render::checkpointer(checkpoint),
        1,
        1,
        |state, its| {
            // This process's iteration its.start is the render's share.sample(its.start).
            let iteration = settings.share.sample(its.start);
            let radius = vcm.radius(iteration, scene.bounds.1);
            let f = Factors::new(vcm, radius, paths as f32);
            let it = Iteration {
                scene,
                s,
                vcm,
                f,
                radius,
                n: paths as f32,
                scale: scale as f32,
                chunks: &[],
                grid: None,
            };
            // Light subpath k: its vertices and camera splats appended; returns its wavelengths.
            let trace_light = |k: u64, vertices: &mut Vec<LightVertex>, splats: &mut Vec<Splat>| {
                let lambda = wavelengths(scene, vcm, settings.seed, iteration, k);
                let index = u64::from(iteration) * paths + k;
                let mut sampler = Sampler::new(settings.seed, LIGHT_STREAM, index);
                light_subpath(
                    scene,
                    s,
                    vcm,
                    &f,
                    scale as f32,
                    &mut sampler,
                    &lambda,
                    vertices,
                    splats,
                );
                lambda
            };
            for c in pool.iter_mut() {
                c.vertices.clear();
                c.ends.clear();
                c.splats.clear();
            }
            if !vcm.merging {
                // Each light subpath is needed by its own camera subpath only: both in turn.
                pool.par_iter_mut().enumerate().for_each(|(c, chunk)| {
                    let mut own = Vec::new();
                    for k in range(c as u64) {
                        own.clear();
                        let lambda = trace_light(k, &mut own, &mut chunk.splats);
                        let index = u64::from(iteration) * paths + k;
                        let mut sampler = Sampler::new(settings.seed, CAMERA_STREAM, index);
                        chunk
                            .splats
                            .push(camera_sample(&it, &mut sampler, &lambda, k, w, &own));
                    }
                    progress(range(c as u64).count() as u64);
                });
            } else {
                // 1. Every light subpath: vertices and t = 1 splats.
                pool.par_iter_mut().enumerate().for_each(|(c, chunk)| {
                    for k in range(c as u64) {
                        trace_light(k, &mut chunk.vertices, &mut chunk.splats);
                        chunk.ends.push(chunk.vertices.len() as u32);
                    }
                    progress(range(c as u64).count() as u64 / 2);
                });
                // 2. The grid of all light vertices, then every camera subpath.
                let photons = pool
                    .iter()
                    .flat_map(|c| &c.vertices)
                    .map(|v| {
                        let ph = Photon {
                            ng: v.ng,
                            w_light: v.w_light,
                            beta: v.beta,
                            mis: v.mis,
                            depth: v.depth,
                        };
                        (v.p, ph)
                    })
                    .collect();
                let grid = PointGrid::new(photons, radius);
                let camera: Vec<Vec<Splat>> = {
                    let it = Iteration {
                        chunks: &pool,
                        grid: Some(grid),
                        ..it
                    };
                    (0..chunks)
                        .into_par_iter()
                        .map(|c| {
                            let mut out = Vec::with_capacity(CHUNK as usize);
                            for k in range(c) {
                                let lambda = wavelengths(scene, vcm, settings.seed, iteration, k);
                                let index = u64::from(iteration) * paths + k;
                                let mut sampler = Sampler::new(settings.seed, CAMERA_STREAM, index);
                                let own = it.subpath(k);
                                out.push(camera_sample(&it, &mut sampler, &lambda, k, w, own));
                            }
                            let n = range(c).count() as u64;
                            progress(n - n / 2);
                            out
                        })
                        .collect()
                };
                for (chunk, cam) in pool.iter_mut().zip(camera) {
                    chunk.splats.extend(cam);
                }
            }
            let lists: Vec<&[Splat]> = pool.iter().map(|c| c.splats.as_slice()).collect();
            add_batches(state, &lists, lists.len(), scale);
        },
    )
}

/// Whether `vcm`/`bdpt` can render `scene` with `settings`; the reason when it cannot.
pub fn check(
    scene: &Scene,
    settings: &crate::RenderSettings,
    vcm: &VcmSettings,
) -> Result<(), String> {
    let name = vcm.name();
    if !(vcm.alpha > 0.0 && vcm.alpha < 1.0) {
        return Err(format!(
            "{name}: alpha must lie in (0, 1), got {}",
            vcm.alpha
        ));
    }
    if let Some(r) = vcm.initial_radius {
        if !(r > 0.0 && r.is_finite()) {
            return Err(format!("{name}: initial_radius must be positive, got {r}"));
        }
    }
    if scene.camera.is_orthographic() {
        return Err(format!(
            "{}: {name}: an orthographic sensor is not yet supported (not yet implemented); use path or ptracer",
            scene.camera.loc()
        ));
    }
    crate::methods::refuse_meters(name, scene)?;
    crate::ptracer::check(settings).map_err(|e| e.replace("ptracer", name))
}

/// Renders the image by `vcm` (or `bdpt`), as [`crate::ptracer::render`] does by light
/// tracing. The caller checks with [`check`] first.
pub fn render(
    scene: &Scene,
    settings: &crate::RenderSettings,
    vcm: &VcmSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> pt_render::RenderOutput {
    let mut state = crate::RenderState::for_light_paths(settings);
    render_vcm_passes(
        scene,
        settings,
        vcm,
        &mut state,
        &AtomicBool::new(false),
        None,
        progress,
    );
    state.output()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path of `k` segments from a light vertex x_0 to the camera x_k with arbitrary
    /// geometry and densities (see `mis_weights_are_the_power_heuristic_over_all_strategies`).
    struct SyntheticPath {
        k: usize,
        /// Squared length of segment (i, i + 1).
        d2: Vec<f32>,
        /// |cos| at vertex i of segment (i, i + 1) and of segment (i - 1, i).
        cos_next: Vec<f32>,
        cos_prev: Vec<f32>,
        /// At interior vertex i: the BSDF's solid-angle density of the direction to x_{i+1}
        /// coming from x_{i-1} (the light's side sampling), and of the direction to x_{i-1}
        /// coming from x_{i+1} (the camera's side).
        p_to_camera: Vec<f32>,
        p_to_light: Vec<f32>,
        pmf: f32,
        p_pos: f32,
        /// Emission's direction density towards x_1, light sampling's density of x_0 seen
        /// from x_1 (solid angle).
        p_dir: f32,
        p_direct: f32,
        /// The camera's solid-angle density of the direction to x_{k-1} (per pixel sample).
        p_cam: f32,
        n: f32,
        eta: f32,
    }

    impl SyntheticPath {
        fn random(k: usize, seed: u64) -> Self {
            let mut state = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let mut u = move |lo: f32, hi: f32| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                lo + (hi - lo) * ((state >> 40) as f32 / (1u64 << 24) as f32)
            };
            let mut v = |m: usize, lo: f32, hi: f32| (0..m).map(|_| u(lo, hi)).collect::<Vec<_>>();
            SyntheticPath {
                k,
                d2: v(k, 0.05, 4.0),
                cos_next: v(k + 1, 0.05, 1.0),
                cos_prev: v(k + 1, 0.05, 1.0),
                p_to_camera: v(k + 1, 0.02, 3.0),
                p_to_light: v(k + 1, 0.02, 3.0),
                pmf: u(0.2, 1.0),
                p_pos: u(0.1, 2.0),
                p_dir: u(0.05, 1.0),
                p_direct: u(0.1, 5.0),
                p_cam: u(0.5, 50.0),
                n: 1000.0,
                eta: u(0.01, 30.0),
            }
        }

        /// The explicit power-heuristic weights, by pbrt-v4's definition: every strategy's
        /// density of the whole path (with its sample count), squared, over their sum.
        /// Returns (connection weights by s = 0..=k, merging weights by vertex 1..k-1).
        fn explicit(&self, connections: bool, merging: bool) -> (Vec<f64>, Vec<f64>) {
            let k = self.k;
            let mut pl = vec![0.0f64; k];
            pl[0] = f64::from(self.pmf * self.p_pos);
            pl[1] = f64::from(self.p_dir * self.cos_prev[1] / self.d2[0]);
            for i in 1..k - 1 {
                pl[i + 1] = f64::from(self.p_to_camera[i] * self.cos_prev[i + 1] / self.d2[i]);
            }
            let mut pe = vec![0.0f64; k];
            pe[k - 1] = f64::from(self.p_cam * self.cos_next[k - 1] / self.d2[k - 1]);
            for i in (1..k).rev() {
                pe[i - 1] = f64::from(self.p_to_light[i] * self.cos_next[i - 1] / self.d2[i - 1]);
            }
            let direct0 = f64::from(self.pmf * self.p_direct * self.cos_next[0] / self.d2[0]);
            let prod = |v: &[f64]| v.iter().product::<f64>();
            let n = f64::from(self.n);
            let mut conn = vec![0.0f64; k + 1];
            conn[0] = prod(&pe);
            if connections {
                conn[1] = direct0 * prod(&pe[1..]);
                for s in 2..k {
                    conn[s] = prod(&pl[..s]) * prod(&pe[s..]);
                }
                conn[k] = n * prod(&pl);
            }
            let mut merge = vec![0.0f64; k];
            if merging {
                for i in 1..k {
                    merge[i] = f64::from(self.eta) * prod(&pl[..=i]) * prod(&pe[i..]);
                }
            }
            let total: f64 = conn.iter().chain(&merge).map(|p| p * p).sum();
            (
                conn.iter().map(|p| p * p / total).collect(),
                merge.iter().map(|p| p * p / total).collect(),
            )
        }

        /// The light subpath's partial sums at x_i (i >= 1), as the integrator carries them.
        fn light_mis(&self, i: usize, f: &Factors) -> SubpathMis {
            let direct = self.pmf * self.p_direct * self.cos_next[0] / self.d2[0];
            let emit = self.pmf * self.p_pos * self.p_dir;
            let mut m = SubpathMis::light(direct, emit, self.cos_next[0], false, f);
            m.arrive(Some(self.d2[0]), self.cos_prev[1]);
            for j in 1..i {
                m.scatter(
                    self.cos_next[j],
                    self.p_to_camera[j],
                    self.p_to_light[j],
                    false,
                    f,
                );
                m.arrive(Some(self.d2[j]), self.cos_prev[j + 1]);
            }
            m
        }

        /// The camera subpath's partial sums at x_i (i <= k - 1; i = 0: arrived at the light).
        fn camera_mis(&self, i: usize, f: &Factors) -> SubpathMis {
            let k = self.k;
            let mut m = SubpathMis::camera(self.n / self.p_cam);
            m.arrive(Some(self.d2[k - 1]), self.cos_next[k - 1]);
            for j in (i + 1..k).rev() {
                m.scatter(
                    self.cos_prev[j],
                    self.p_to_light[j],
                    self.p_to_camera[j],
                    false,
                    f,
                );
                m.arrive(Some(self.d2[j - 1]), self.cos_next[j - 1]);
            }
            m
        }

        /// The integrator's weights for the same strategies.
        fn implemented(&self, connections: bool, merging: bool) -> (Vec<f64>, Vec<f64>) {
            let k = self.k;
            let settings = VcmSettings {
                merging,
                connections,
                ..VcmSettings::vcm()
            };
            // eta = pi r^2 N: the radius that gives this path's eta.
            let r = (self.eta / (PI * self.n)).sqrt();
            let f = Factors::new(&settings, r, self.n);
            let mut conn = vec![0.0f64; k + 1];
            let direct_a = self.pmf * self.p_direct * self.cos_next[0] / self.d2[0];
            let emit = self.pmf * self.p_pos * self.p_dir;
            conn[0] = f64::from(emission_weight(&self.camera_mis(0, &f), direct_a, emit, &f));
            if connections {
                conn[1] = f64::from(light_sample_weight(
                    &self.camera_mis(1, &f),
                    self.p_to_light[1],
                    self.pmf * self.p_direct,
                    emit,
                    self.cos_prev[1],
                    self.cos_next[0],
                    self.p_to_camera[1],
                    &f,
                ));
                for s in 2..k {
                    let (l, c) = (self.light_mis(s - 1, &f), self.camera_mis(s, &f));
                    conn[s] = f64::from(connection_weight(
                        &l,
                        &c,
                        self.p_to_light[s] * self.cos_next[s - 1] / self.d2[s - 1],
                        self.p_to_camera[s - 1] * self.cos_prev[s] / self.d2[s - 1],
                        self.p_to_light[s - 1],
                        self.p_to_camera[s],
                        &f,
                    ));
                }
                conn[k] = f64::from(camera_weight(
                    &self.light_mis(k - 1, &f),
                    self.p_cam * self.cos_next[k - 1] / self.d2[k - 1] / self.n,
                    self.p_to_light[k - 1],
                    &f,
                ));
            }
            let mut merge = vec![0.0f64; k];
            if merging {
                for i in 1..k {
                    merge[i] = f64::from(merge_weight(
                        &self.light_mis(i, &f),
                        &self.camera_mis(i, &f),
                        self.p_to_light[i],
                        self.p_to_camera[i],
                        &f,
                    ));
                }
            }
            (conn, merge)
        }
    }

    /// Every strategy's weight, as the integrator computes it from its partial sums, is the
    /// power heuristic over all strategies computed explicitly from the whole path's densities
    /// (pbrt-v4's definition), and the weights of each path sum to one: for bdpt, vcm and
    /// merging alone, on 200 random paths of 2 to 7 segments with densities spread over three
    /// orders of magnitude. Tolerance 2e-3 absolute: f32 partial sums against f64 products.
    /// A wrong factor anywhere (a cosine at the wrong end, a reverse density swapped, N
    /// missing) moves weights by far more.
    #[test]
    fn mis_weights_are_the_power_heuristic_over_all_strategies() {
        for seed in 0..200u64 {
            let k = 2 + (seed % 6) as usize;
            let path = SyntheticPath::random(k, seed);
            for (connections, merging) in [(true, false), (true, true), (false, true)] {
                let (ce, me) = path.explicit(connections, merging);
                let (ci, mi) = path.implemented(connections, merging);
                let sum: f64 = ci.iter().chain(&mi).sum();

                assert!(
                    (sum - 1.0).abs() < 2e-3,
                    "k {k} seed {seed} ({connections}, {merging}): sum {sum}"
                );
                for (s, (e, i)) in ce.iter().zip(&ci).enumerate() {
                    assert!((e - i).abs() < 2e-3, "k {k} seed {seed}: s {s}: {i} vs {e}");
                }
                for (v, (e, i)) in me.iter().zip(&mi).enumerate() {
                    assert!(
                        (e - i).abs() < 2e-3,
                        "k {k} seed {seed}: merge at {v}: {i} vs {e}"
                    );
                }
            }
        }
    }
}
