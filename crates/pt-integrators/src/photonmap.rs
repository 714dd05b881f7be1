//! Photon mapping as Jensen 1996 describes it ("Global Illumination using Photon Maps",
//! Rendering Techniques '96): a pt extension (`<integrator type="photonmapper">`; Mitsuba 3 has
//! no photon mapper).
//!
//! Two maps, built from paths traced from the lights ([`crate::ptracer::walk_light_path`]:
//! the light tracer's paths, importance transport):
//! - the *global map*: every photon hit on a surface with a non-specular lobe, from
//!   `global_photons` emitted photons;
//! - the *caustic map*: the hits on such surfaces of photons that reached them through specular
//!   surfaces only (light-specular+-diffuse paths), from `caustic_photons` emitted photons.
//!
//! Each map is a balanced kd-tree ([`KdTree`]); the radiance estimate at a point gathers its
//! `lookup` nearest photons within `max_radius` and filters them with Jensen's cone filter
//! (weight 1 - d / (k r), k = 1.1, normalised by 1 - 2 / (3k)): `L = sum f(wo, wi_p) Phi_p w_p
//! / ((1 - 2/(3k)) pi r^2)`, r the distance to the farthest photon gathered (`max_radius` when
//! fewer are found), Phi_p the photon's power (its weight over the emitted count).
//!
//! A camera path goes on through specular lobes; at the first surface with a non-specular lobe
//! the pixel gets (Jensen's split of the rendering equation):
//! - *direct light* by light sampling (exact),
//! - *caustics* from the caustic map,
//! - *indirect diffuse light* by final gathering: one BSDF-sampled ray per camera sample, which
//!   goes on through specular surfaces to a surface with a non-specular lobe, where the global
//!   map's estimate stands for the light it reflects (with `final_gather` false, the global
//!   map's estimate at the first surface replaces all three: Jensen's quick visualisation).
//!
//! Emission counts where the camera sees it directly or through specular surfaces only.
//! **Biased**: the estimates blur light over the photons' radius (caustic edges, shadow edges)
//! and darken corners where the disc leaves the surface; the gathered global estimate one
//! bounce away hides most of its blur. The bias shrinks as the photon counts grow (the radius
//! of `lookup` photons shrinks), not with the number of samples per pixel. Each iteration
//! (`--spp` counts them) traces its own maps at one set of wavelengths (spectral mode; as SPPM
//! does), so the noise of the maps averages out over the iterations while their bias stays.
//! Fluorescence: photons end where they meet a fluorescent surface, and the paths through one
//! are the camera side's, estimated without bias by the path tracer's strategies from the
//! first hit on ([`crate::path::li_through_fluorescence`], which says why); final gathering
//! that reaches a fluorescent surface adds nothing there.

use crate::path::PathSettings;
use crate::ptracer::{shading_frame, to_rgb, walk_light_path, Arrival, AtFluorescence};
use pt_bsdf::SurfaceBsdf;
use pt_math::{offset_ray_origin, Ray, Vec3};
use pt_render::sampler::Sampler;
use pt_render::Scene;
use pt_spectrum::{SampledSpectrum, SampledWavelengths};
use rayon::prelude::*;
use std::collections::BinaryHeap;
use std::sync::atomic::AtomicBool;

/// The photon mapper's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonMapSettings {
    /// Photons emitted for the global map per iteration.
    pub global_photons: u64,
    /// Photons emitted for the caustic map per iteration.
    pub caustic_photons: u64,
    /// Photons per radiance estimate (k nearest).
    pub lookup: usize,
    /// Largest gathering radius, scene units; `None`: 5% of the scene's bounding radius.
    pub max_radius: Option<f32>,
    /// Whether indirect light is gathered (Jensen's final gathering) or read from the global
    /// map at the first surface.
    pub final_gather: bool,
}

impl Default for PhotonMapSettings {
    fn default() -> Self {
        PhotonMapSettings {
            global_photons: 100_000,
            caustic_photons: 100_000,
            lookup: 50,
            max_radius: None,
            final_gather: true,
        }
    }
}

/// Jensen 1996's cone filter constant k (>= 1).
const CONE_K: f32 = 1.1;

/// The key of the photons' random streams.
const PHOTON_STREAM: u64 = (1 << 63) | 0x4a_504d; // "JPM"

/// Photons per work item.
const CHUNK: u64 = 4096;

/// A stored photon.
#[derive(Clone, Copy, Debug)]
struct Photon {
    /// Geometric normal where it landed, world.
    ng: Vec3,
    /// Unit direction towards where it came from, world.
    w_light: Vec3,
    /// Its power: the path's weight over the photons emitted.
    power: SampledSpectrum,
    /// Segments from the light.
    depth: u32,
}

/// A balanced kd-tree of items at points, stored as an implicit tree in one array: the
/// median of a range is its root, split along the range's longest extent.
pub(crate) struct KdTree<T> {
    items: Vec<(Vec3, T)>,
    axes: Vec<u8>,
}

impl<T: Copy> KdTree<T> {
    /// Builds the tree (deterministic for a given input order).
    pub(crate) fn new(mut items: Vec<(Vec3, T)>) -> Self {
        let mut axes = vec![0u8; items.len()];
        fn build<T>(items: &mut [(Vec3, T)], axes: &mut [u8]) {
            if items.len() <= 1 {
                return;
            }
            let (lo, hi) = items.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), (p, _)| (lo.min(*p), hi.max(*p)),
            );
            let e = hi - lo;
            let axis = if e.x >= e.y && e.x >= e.z {
                0
            } else if e.y >= e.z {
                1
            } else {
                2
            };
            let mid = items.len() / 2;
            items.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
            axes[mid] = axis as u8;
            let (l, r) = items.split_at_mut(mid);
            let (al, ar) = axes.split_at_mut(mid);
            build(l, al);
            build(&mut r[1..], &mut ar[1..]);
        }
        build(&mut items, &mut axes);
        KdTree { items, axes }
    }

    /// The `k` items nearest `p` within `max_r` into `heap` (cleared first; a max-heap of
    /// (squared distance bits, index), so its top is the farthest kept).
    pub(crate) fn nearest(&self, p: Vec3, k: usize, max_r: f32, heap: &mut BinaryHeap<(u32, u32)>) {
        heap.clear();
        let mut r2 = max_r * max_r;
        self.search(0, self.items.len(), p, k, &mut r2, heap);
    }

    fn search(
        &self,
        lo: usize,
        hi: usize,
        p: Vec3,
        k: usize,
        r2: &mut f32,
        heap: &mut BinaryHeap<(u32, u32)>,
    ) {
        if lo >= hi {
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let (q, _) = self.items[mid];
        let axis = self.axes[mid] as usize;
        let d = p[axis] - q[axis];
        let (near, far) = if d <= 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1, p, k, r2, heap);
        let d2 = (q - p).length_squared();
        if d2 <= *r2 {
            // Non-negative floats order as their bits.
            heap.push((d2.to_bits(), mid as u32));
            if heap.len() > k {
                heap.pop();
            }
            if heap.len() == k {
                *r2 = f32::from_bits(heap.peek().expect("k items").0);
            }
        }
        if d * d <= *r2 {
            self.search(far.0, far.1, p, k, r2, heap);
        }
    }

    /// The item of index `i` (as `nearest` reports it).
    pub(crate) fn item(&self, i: u32) -> &(Vec3, T) {
        &self.items[i as usize]
    }
}

/// One iteration's maps and what the estimates need.
struct Maps {
    global: KdTree<Photon>,
    caustic: KdTree<Photon>,
    lookup: usize,
    max_r: f32,
    max_depth: u32,
}

impl Maps {
    /// Jensen's radiance estimate from `map` at a surface point (`p`, geometric normal `ng`,
    /// shading frame, direction `wo` to the viewer in it, BSDF), for paths that already have
    /// `depth` segments on the camera side.
    #[allow(clippy::too_many_arguments)]
    fn estimate(
        &self,
        map: &KdTree<Photon>,
        p: Vec3,
        ng: Vec3,
        frame: &pt_math::Frame,
        wo: Vec3,
        bsdf: &SurfaceBsdf,
        depth: u32,
        heap: &mut BinaryHeap<(u32, u32)>,
    ) -> SampledSpectrum {
        map.nearest(p, self.lookup, self.max_r, heap);
        if heap.is_empty() {
            return SampledSpectrum::ZERO;
        }
        let r = if heap.len() == self.lookup {
            f32::from_bits(heap.peek().expect("not empty").0).sqrt()
        } else {
            self.max_r
        };
        if !(r > 0.0) {
            return SampledSpectrum::ZERO;
        }
        let mut sum = SampledSpectrum::ZERO;
        for &(d2, i) in heap.iter() {
            let (_, ph) = map.item(i);
            if ph.ng.dot(ng) <= 0.0 || ph.depth.saturating_add(depth) > self.max_depth {
                continue;
            }
            let wi = frame.to_local(ph.w_light);
            let ng_wi = ng.dot(ph.w_light);
            if ng_wi * wi.z <= 0.0 {
                continue;
            }
            let f = bsdf.eval(wo, wi);
            if f.is_black() {
                continue;
            }
            // Cone filter; the shading normal's correction cos_s / cos_g of the flux.
            let w = 1.0 - f32::from_bits(d2).sqrt() / (CONE_K * r);
            sum += f * ph.power * (w * wi.z.abs() / ng_wi.abs());
        }
        let norm = (1.0 - 2.0 / (3.0 * CONE_K)) * std::f32::consts::PI * r * r;
        sum * (1.0 / norm)
    }
}

/// Traces `count` photons (random streams `stream..stream + count`) at the wavelengths
/// `lambda` and keeps, photon by photon in order, the hits `keep` accepts (given the hit's
/// depth and whether every bounce before it was specular), each with its power.
#[allow(clippy::too_many_arguments)]
fn trace_photons(
    scene: &Scene,
    s: &PathSettings,
    seed: u64,
    stream: u64,
    count: u64,
    lambda: &SampledWavelengths,
    keep: impl Fn(u32, bool) -> bool + Sync,
    progress: &(dyn Fn(u64) + Sync),
) -> Vec<(Vec3, Photon)> {
    let chunks = count.div_ceil(CHUNK);
    let scale = 1.0 / count as f32;
    let lists: Vec<Vec<(Vec3, Photon)>> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut out = Vec::new();
            let (first, end) = (c * CHUNK, ((c + 1) * CHUNK).min(count));
            // Dispatched per chunk: the walk inlined into one function per instruction set
            // (`pt_render::isa`).
            pt_render::isa::best(
                #[inline(always)]
                || {
                    for k in first..end {
                        let mut sampler = Sampler::new(seed, PHOTON_STREAM, stream + k);
                        let mut specular = true;
                        walk_light_path::<_, false>(
                            scene,
                            s,
                            &mut sampler,
                            lambda,
                            AtFluorescence::Absorb,
                            |v, _| {
                                if let Arrival::Scattered { delta, .. } = v.arrival {
                                    specular &= delta;
                                }
                                if v.bsdf.has_smooth_lobe() && keep(v.depth, specular) {
                                    out.push((
                                        v.hit.p,
                                        Photon {
                                            ng: v.hit.ng,
                                            w_light: v.w_light,
                                            power: v.beta * scale,
                                            depth: v.depth,
                                        },
                                    ));
                                }
                            },
                            // Scenes with media are refused before this method runs.
                            |_, _| {},
                        );
                    }
                },
            );
            progress(end - first);
            out
        })
        .collect();
    lists.into_iter().flatten().collect()
}

/// Light sampling at a surface (direct light; no MIS: emission met after a non-specular
/// bounce is never counted).
#[inline(always)]
fn direct_light(
    scene: &Scene,
    hit: &pt_render::geometry::Interaction,
    frame: &pt_math::Frame,
    bsdf: &SurfaceBsdf,
    wo: Vec3,
    lambda: &SampledWavelengths,
    sampler: &mut Sampler,
) -> SampledSpectrum {
    let (u_light, u) = (sampler.next_1d(), sampler.next_2d());
    let Some((li, pmf, u_sel)) = scene.sample_light(u_light) else {
        return SampledSpectrum::ZERO;
    };
    let Some(ls) = scene.lights[li].sample(hit.p, u_sel, u, lambda) else {
        return SampledSpectrum::ZERO;
    };
    let wi = frame.to_local(ls.wi);
    if ls.radiance.is_black() || !(ls.pdf > 0.0) || hit.ng.dot(ls.wi) * wi.z <= 0.0 {
        return SampledSpectrum::ZERO;
    }
    let f = bsdf.eval(wo, wi);
    if f.is_black() {
        return SampledSpectrum::ZERO;
    }
    let origin = offset_ray_origin(hit.p, hit.ng * hit.ng.dot(ls.wi).signum());
    if scene.light_unoccluded(origin, &ls) {
        f * ls.radiance * (wi.z.abs() / (ls.pdf * pmf))
    } else {
        SampledSpectrum::ZERO
    }
}

/// Most specular bounces a camera or gather path follows when `max_depth` is unlimited.
const MAX_SPECULAR_CHAIN: u32 = 64;

/// One camera sample of pixel (x, y): its radiance and filter weight.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn camera_sample(
    scene: &Scene,
    s: &PathSettings,
    settings: &crate::RenderSettings,
    pm: &PhotonMapSettings,
    maps: &Maps,
    lambda: &SampledWavelengths,
    (x, y): (u32, u32),
    iteration: u32,
    heap: &mut BinaryHeap<(u32, u32)>,
) -> (SampledSpectrum, f32) {
    let (mut sampler, mut ray, weight) = crate::sppm::pixel_ray(scene, settings, (x, y), iteration);
    let mut beta = crate::sppm::unit(scene);
    let mut radiance = SampledSpectrum::ZERO;
    let max_segments = maps.max_depth.min(MAX_SPECULAR_CHAIN);
    let mut segments = 1u32;
    // Whether the paths through a fluorescent surface are counted already (photons end at
    // one: from the first hit on, the path tracer takes them).
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
        radiance += crate::path::fluorescence_once(
            scene,
            (ray, beta, segments - 1),
            s,
            &mut sampler,
            lambda,
            &mut fluorescence_counted,
        );
        if scene.material(hit.shape).fluorescent().is_some() {
            // Every path on from here scatters at a fluorescent surface: counted above.
            break;
        }
        let bsdf = scene.bsdf(&hit, lambda);
        let frame = shading_frame(&hit);
        let wo = frame.to_local(w_cam);
        if bsdf.has_smooth_lobe() {
            let estimate = |map: &KdTree<Photon>, heap: &mut BinaryHeap<(u32, u32)>| {
                maps.estimate(map, hit.p, hit.ng, &frame, wo, &bsdf, segments, heap)
            };
            if !pm.final_gather {
                radiance += beta * estimate(&maps.global, heap);
                break;
            }
            radiance += beta * direct_light(scene, &hit, &frame, &bsdf, wo, lambda, &mut sampler);
            radiance += beta * estimate(&maps.caustic, heap);
            radiance += beta
                * gather(
                    scene,
                    maps,
                    &hit,
                    &frame,
                    &bsdf,
                    wo,
                    segments,
                    lambda,
                    &mut sampler,
                    heap,
                );
            break;
        }
        // A specular surface: follow its lobe.
        let u_lobe = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u_lobe, sampler.next_2d()) else {
            break;
        };
        beta *= bs.weight;
        if beta.is_black() || !beta.is_finite() {
            break;
        }
        let dir = frame.to_world(bs.wi);
        ray = Ray::new(
            offset_ray_origin(hit.p, hit.ng * hit.ng.dot(dir).signum()),
            dir,
        );
        segments += 1;
    }
    (radiance, weight)
}

/// Final gathering from a surface: one BSDF-sampled ray, through specular surfaces, to a
/// surface whose global-map estimate stands for the light it sends back.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn gather(
    scene: &Scene,
    maps: &Maps,
    hit: &pt_render::geometry::Interaction,
    frame: &pt_math::Frame,
    bsdf: &SurfaceBsdf,
    wo: Vec3,
    segments: u32,
    lambda: &SampledWavelengths,
    sampler: &mut Sampler,
    heap: &mut BinaryHeap<(u32, u32)>,
) -> SampledSpectrum {
    let u_lobe = sampler.next_1d();
    let Some(bs) = bsdf.sample(wo, u_lobe, sampler.next_2d()) else {
        return SampledSpectrum::ZERO;
    };
    // The delta lobes of a mixed surface (a plastic's coating) lead to caustic light and
    // direct light, both counted already: only the non-specular lobes gather.
    if bs.delta {
        return SampledSpectrum::ZERO;
    }
    let mut beta = bs.weight;
    let mut dir = frame.to_world(bs.wi);
    if hit.ng.dot(dir) * bs.wi.z <= 0.0 {
        return SampledSpectrum::ZERO;
    }
    let mut at = *hit;
    // Segments on the camera side of the gathered point.
    let mut segments = segments + 1;
    let mut chain = 0;
    while segments < maps.max_depth && chain < MAX_SPECULAR_CHAIN {
        chain += 1;
        let ray = Ray::new(
            offset_ray_origin(at.p, at.ng * at.ng.dot(dir).signum()),
            dir,
        );
        let Some(next) = scene.intersect(&ray) else {
            return SampledSpectrum::ZERO;
        };
        if scene.material(next.shape).fluorescent().is_some() {
            // What a fluorescent surface sends is the camera side's to count.
            return SampledSpectrum::ZERO;
        }
        let b = scene.bsdf(&next, lambda);
        let f = shading_frame(&next);
        let w = f.to_local(-dir);
        if b.has_smooth_lobe() {
            return beta * maps.estimate(&maps.global, next.p, next.ng, &f, w, &b, segments, heap);
        }
        let u_lobe = sampler.next_1d();
        let Some(bs) = b.sample(w, u_lobe, sampler.next_2d()) else {
            return SampledSpectrum::ZERO;
        };
        beta *= bs.weight;
        if beta.is_black() || !beta.is_finite() {
            return SampledSpectrum::ZERO;
        }
        dir = f.to_world(bs.wi);
        at = next;
        segments += 1;
    }
    SampledSpectrum::ZERO
}

/// Renders `settings.spp` iterations into `state` (pixel statistics), each with its own maps.
pub fn render_photon_passes(
    scene: &Scene,
    settings: &crate::RenderSettings,
    pm: &PhotonMapSettings,
    state: &mut crate::RenderState,
    cancel: &AtomicBool,
    checkpoint: Option<&crate::Checkpoint>,
    progress: &(dyn Fn(u64) + Sync),
) -> bool {
    let (w, h) = (settings.width, settings.height);
    let pixels = u64::from(w) * u64::from(h);
    let s = &settings.path;
    let max_depth = s.depth_limit();
    let photons = pm.global_photons + pm.caustic_photons;
    // Progress counts pixels: the photons of an iteration as one half of them.
    let photon_progress = |n: u64| progress(n * pixels / (2 * photons.max(1)));
    crate::render::in_passes(
        state,
        settings.spp,
        cancel,
        &mut crate::render::checkpointer(checkpoint),
        1,
        1,
        |state, its| {
            // This process's iteration its.start is the render's share.sample(its.start).
            let it = settings.share.sample(its.start);
            let lambda = crate::render::iteration_wavelengths(scene, settings.seed, it);
            let base = u64::from(it) * photons;
            let global = trace_photons(
                scene,
                s,
                settings.seed,
                base,
                pm.global_photons,
                &lambda,
                |_, _| true,
                &photon_progress,
            );
            let caustic = trace_photons(
                scene,
                s,
                settings.seed,
                base + pm.global_photons,
                pm.caustic_photons,
                &lambda,
                |depth, specular| depth >= 2 && specular,
                &photon_progress,
            );
            let maps = Maps {
                global: KdTree::new(global),
                caustic: KdTree::new(caustic),
                lookup: pm.lookup.max(1),
                max_r: pm.max_radius.unwrap_or(0.05 * scene.bounds.1),
                max_depth,
            };
            let rows: Vec<Vec<(SampledSpectrum, f32)>> = (0..h)
                .into_par_iter()
                .map(|y| {
                    let mut heap = BinaryHeap::with_capacity(maps.lookup + 1);
                    // Dispatched per row, as the photon pass.
                    let row = pt_render::isa::best(
                        #[inline(always)]
                        || {
                            (0..w)
                                .map(|x| {
                                    camera_sample(
                                        scene,
                                        s,
                                        settings,
                                        pm,
                                        &maps,
                                        &lambda,
                                        (x, y),
                                        it,
                                        &mut heap,
                                    )
                                })
                                .collect()
                        },
                    );
                    progress(u64::from(w) - u64::from(w) / 2);
                    row
                })
                .collect();
            for (stats, (l, weight)) in state.pixels.iter_mut().zip(rows.into_iter().flatten()) {
                let rgb = to_rgb(scene, l, &lambda).map(|c| c * weight);
                stats.add(rgb, 1.0);
            }
        },
    )
}

/// Whether the photon mapper's settings are valid; the reason when they are not.
pub fn check(pm: &PhotonMapSettings) -> Result<(), String> {
    if pm.global_photons == 0 && pm.caustic_photons == 0 {
        return Err(
            "photonmapper: no photons to trace (global_photons and caustic_photons are 0)".into(),
        );
    }
    if let Some(r) = pm.max_radius {
        if !(r > 0.0 && r.is_finite()) {
            return Err(format!(
                "photonmapper: max_radius must be positive, got {r}"
            ));
        }
    }
    Ok(())
}

/// Renders the image by photon mapping into a new state (see [`crate::sppm::new_state`]).
pub fn render(
    scene: &Scene,
    settings: &crate::RenderSettings,
    pm: &PhotonMapSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> pt_render::RenderOutput {
    let mut state = crate::sppm::new_state(settings);
    render_photon_passes(
        scene,
        settings,
        pm,
        &mut state,
        &AtomicBool::new(false),
        None,
        progress,
    );
    let mut out = state.output();
    out.alpha = None;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kd-tree's k nearest are the k nearest by brute force, for random points and
    /// queries, k below and above the count within the radius.
    #[test]
    fn kd_tree_finds_the_k_nearest() {
        let mut s = 12345u64;
        let mut u = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        let points: Vec<(Vec3, u32)> = (0..2000)
            .map(|i| (Vec3::new(u(), u(), u() * 0.1), i))
            .collect();
        let tree = KdTree::new(points.clone());
        let mut heap = BinaryHeap::new();
        for _ in 0..200 {
            let p = Vec3::new(u(), u(), 0.05);
            for (k, r) in [(1, 1.0), (10, 0.2), (50, 0.05), (30, 2.0)] {
                tree.nearest(p, k, r, &mut heap);
                let mut got: Vec<u32> = heap.iter().map(|&(_, i)| tree.item(i).1).collect();
                got.sort_unstable();
                let mut all: Vec<(f32, u32)> = points
                    .iter()
                    .map(|(q, i)| ((*q - p).length_squared(), *i))
                    .filter(|(d2, _)| *d2 <= r * r)
                    .collect();
                all.sort_by(|a, b| a.0.total_cmp(&b.0));
                let mut want: Vec<u32> = all.iter().take(k).map(|x| x.1).collect();
                want.sort_unstable();
                assert_eq!(got, want, "k {k} r {r}");
            }
        }
    }
}
