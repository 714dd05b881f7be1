//! Mitsuba's `aov` integrator: for each sample, quantities of the first surface its camera ray
//! hits (depth, position, normals, texture coordinates, albedo, indices; zero where it hits
//! nothing), splatted with the film's filter into extra channels, as Mitsuba 3.9.1 splats them
//! (so that, as its documentation says, integer quantities are fractional where a pixel
//! covers several primitives).
//!
//! The quantities are rendered in a pass of their own over the same film grid, after the
//! image: each sample draws its film position and lens position from the image's random
//! stream for the same pixel and sample index (with an independent sampler these are the
//! image's own camera rays), and the camera ray stops at the first surface it meets, masks
//! and `null` surfaces included (Mitsuba's `aov` intersects once).
//!
//! Mitsuba's `depth` integrator is the `depth` quantity as the image ([`render_depth`]).

use crate::render::RenderSettings;
use pt_math::{Frame, Ray, Vec2, Vec3};
use pt_render::film::splat::{SplatFilm, SplatLayout};
use pt_render::film::{filter_radius, Filter};
use pt_render::geometry::Interaction;
use pt_render::sampler::Sampler;
use pt_render::Scene;
use pt_scene::{AovDesc, AovKind, FilterDesc};
use pt_spectrum::{spectrum_to_srgb, ColorMode, SampledWavelengths};
use rayon::prelude::*;

/// Renders the outputs of `aov` at `settings.spp` samples per pixel: one row-major plane per
/// channel, in the order of [`AovDesc::channel_names`] after the nested integrator's image.
pub fn render_aovs(scene: &Scene, settings: &RenderSettings, aov: &AovDesc) -> Vec<Vec<f32>> {
    let channels: usize = aov.outputs.iter().map(|(_, k)| k.suffixes().len()).sum();
    splat_first_hits(scene, settings, channels, |hit, lambda, values| {
        aov_values(scene, &aov.outputs, hit, lambda, values)
    })
}

/// Mitsuba's `depth` integrator at `settings.spp` samples per pixel: per pixel the
/// filter-weighted mean of the samples' distance to the first hit (0 where a sample hits
/// nothing; measured as the `aov` integrator's `depth`), the variance of that mean, and the
/// alpha (the weighted fraction of samples that hit something). The variance is that of the
/// mean of the pixel's own samples (those whose film position falls in it), as the image film
/// keeps it under every filter: the same samples splatted a second time with a one-pixel box.
pub fn render_depth(scene: &Scene, settings: &RenderSettings) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let depth = |hit: Option<(&Interaction, &Ray)>| hit.map_or(0.0, |(h, ray)| h.t - ray.tmin);
    let planes = splat_first_hits(scene, settings, 2, |hit, _, values| {
        values.copy_from_slice(&[depth(hit), f32::from(u8::from(hit.is_some()))]);
    });
    let [mean, alpha]: [Vec<f32>; 2] = planes.try_into().expect("two planes");
    let own_pixel = RenderSettings {
        filter: Filter::new(FilterDesc::Box { radius: 0.5 }),
        ..settings.clone()
    };
    let planes = splat_first_hits(scene, &own_pixel, 2, |hit, _, values| {
        let t = depth(hit);
        values.copy_from_slice(&[t, t * t]);
    });
    let [own_mean, own_second]: [Vec<f32>; 2] = planes.try_into().expect("two planes");
    let n = settings.spp.max(1) as f32;
    let variance = own_mean
        .iter()
        .zip(&own_second)
        .map(|(m, m2)| (m2 - m * m).max(0.0) / n)
        .collect();
    (mean, variance, alpha)
}

/// Splats `channels` values per sample, written by `values` from the sample's first hit (with
/// the camera ray that found it) and wavelengths, over the film of `settings`: one row-major
/// plane per channel, normalised by the filter weights as the image film is.
fn splat_first_hits(
    scene: &Scene,
    settings: &RenderSettings,
    channels: usize,
    values: impl Fn(Option<(&Interaction, &Ray)>, &SampledWavelengths, &mut [f32]) + Sync,
) -> Vec<Vec<f32>> {
    if channels == 0 {
        return Vec::new();
    }
    let layout = SplatLayout::new(
        &settings.filter.desc,
        settings.width,
        settings.height,
        settings.crop.map_or([0, 0], |c| c.offset),
        settings.sample_border,
    );
    let mut film = SplatFilm::new(layout, channels);
    let layout = film.layout.clone();
    let columns = layout.tile_columns();
    let radius = filter_radius(&settings.filter.desc);
    film.tiles.par_iter_mut().enumerate().for_each(|(t, acc)| {
        let (xs, ys) = layout.origins(t % columns, t / columns);
        let mut out = vec![0.0f32; channels];
        // Sample index first, then origin pixel row by row: a fixed order of additions.
        for k in 0..settings.spp {
            for y in ys.clone() {
                for x in xs.clone() {
                    let (u, ray, hit, lambda) = trace(scene, settings, x, y, k);
                    values(hit.as_ref().map(|h| (h, &ray)), &lambda, &mut out);
                    if out.iter().all(|v| v.is_finite()) {
                        acc.splat(&settings.filter.desc, radius, [x, y], u, &out);
                    }
                }
            }
            acc.commit();
        }
    });
    film.planes()
}

/// Sample `k` of origin pixel (`x`, `y`): its position in the pixel ([0, 1)^2), its camera
/// ray and the ray's first hit, and its wavelengths (drawn as the image's samples draw
/// them).
fn trace(
    scene: &Scene,
    settings: &RenderSettings,
    x: i32,
    y: i32,
    k: u32,
) -> (Vec2, Ray, Option<Interaction>, SampledWavelengths) {
    let mut sampler = Sampler::new(settings.seed, settings.pixel_key(x, y), u64::from(k));
    let lambda = match scene.mode {
        ColorMode::Spectral => SampledWavelengths::sample_visible(sampler.next_1d()),
        ColorMode::Rgb => SampledWavelengths::sample_visible(0.5),
    };
    let u = sampler.next_2d();
    let ray = scene
        .camera
        .sample_ray(x, y, u - Vec2::splat(0.5), || sampler.next_2d());
    (u, ray, scene.intersect(&ray), lambda)
}

/// Writes the quantities `outputs` of `hit` (all zero without one) into `out`, channel after
/// channel. With the hit comes the camera ray that found it.
fn aov_values(
    scene: &Scene,
    outputs: &[(String, AovKind)],
    hit: Option<(&Interaction, &Ray)>,
    lambda: &SampledWavelengths,
    out: &mut [f32],
) {
    let mut i = 0;
    let mut put = |v: &[f32]| {
        out[i..i + v.len()].copy_from_slice(v);
        i += v.len();
    };
    let v3 = |v: Vec3| [v.x, v.y, v.z];
    for (_, kind) in outputs {
        let Some((h, ray)) = hit else {
            put(&[0.0; 3][..kind.suffixes().len()]);
            continue;
        };
        match kind {
            AovKind::Albedo => put(&albedo(scene, h, -ray.dir, lambda)),
            // Mitsuba's camera rays start on the near clip plane, where pt's leave the camera
            // and begin at `tmin`: the distance from there.
            AovKind::Depth => put(&[h.t - ray.tmin]),
            AovKind::Position => put(&v3(h.p)),
            AovKind::Uv => put(&[h.uv.x, h.uv.y]),
            AovKind::GeoNormal => put(&v3(h.ng)),
            AovKind::ShNormal => put(&v3(h.ns)),
            AovKind::DpDu => put(&v3(h.dpdu)),
            AovKind::DpDv => put(&v3(h.dpdv)),
            AovKind::PrimIndex => put(&[scene.primitive_index(h) as f32]),
            // Mitsuba numbers shapes from 1 in the order they were created (0: no shape).
            AovKind::ShapeIndex => put(&[(h.shape + 1) as f32]),
        }
    }
}

/// The hit's diffuse reflectance (`pt_bsdf::SurfaceBsdf::diffuse_reflectance`) seen from
/// `to_camera` (world), linear sRGB (in spectral mode converted as a radiance sample is, as
/// Mitsuba converts it).
fn albedo(
    scene: &Scene,
    h: &Interaction,
    to_camera: Vec3,
    lambda: &SampledWavelengths,
) -> [f32; 3] {
    let frame = if h.dpdu == Vec3::ZERO {
        Frame::from_normal(h.ns)
    } else {
        Frame::from_normal_tangent(h.ns, h.dpdu)
    };
    let wo = frame.to_local(to_camera);
    let a = scene.bsdf(h, lambda).diffuse_reflectance(wo);
    match scene.mode {
        ColorMode::Spectral => spectrum_to_srgb(a, lambda),
        ColorMode::Rgb => a.rgb(),
    }
}
