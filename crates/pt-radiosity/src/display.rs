//! Display of a radiosity solution from the scene camera.
//!
//! A diffuse patch of radiosity `B` leaves radiance `B / pi` in every direction on the side it
//! faces (emitters included: `B = E + R H`, so a black emitter shows exactly `Le`). The back of a
//! one-sided surface is black. Camera samples are placed with the film's reconstruction filter
//! (filter importance sampling, as the path tracer does) with the same random streams
//! (seed, pixel, sample), so the image depends only on the seed and the sample count.
//!
//! - [`Display::Constant`]: each patch shows its own `B / pi` (flat shading; shows the patches).
//! - [`Display::Smoothed`]: `B` at each patch corner is the area-weighted mean of the patches
//!   sharing that vertex whose normals are within 25 degrees and that have the same emitting
//!   status (so creases and light edges stay sharp), interpolated barycentrically (Cohen &
//!   Wallace 1993, ch. 9, "nodal averaging"). Hides the patch structure, not its bias.
//! - [`Display::FinalGather`]: at the visible point `x`, one cosine-distributed ray per sample
//!   reads the radiosity of the patch it hits: `L = Le(x) + R(x) B_hit / pi` (the Lambertian
//!   BRDF `R / pi` times `cos / pdf = pi`). Removes the discretisation of the visible surface
//!   (sharp shadows, no patch edges), at the price of Monte Carlo noise.

use crate::patches::{PatchMesh, NO_PATCH};
use pt_math::warp::square_to_cosine_hemisphere;
use pt_math::{offset_ray_origin, Frame, Ray, Vec2};
use pt_render::accel::Accel;
use pt_render::camera::Camera;
use pt_render::film::{sample_pixel_offset, Filter, PixelStats};
use pt_render::sampler::Sampler;
use pt_render::RenderOutput;
use pt_scene::FilterDesc;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

pub use pt_scene::RadiosityDisplay as Display;

/// Cosine of the largest angle between patch normals that are averaged at a vertex (25 deg).
const SMOOTH_COS: f32 = 0.906;

/// Radiosity at each patch's three corners by area-weighted averaging at shared vertices.
pub fn corner_radiosity(mesh: &PatchMesh, b: &[[f32; 3]]) -> Vec<[[f32; 3]; 3]> {
    // Vertex -> incident patches, compressed rows.
    let nv = mesh.vertices.len();
    let mut start = vec![0usize; nv + 1];
    for p in &mesh.patches {
        for &v in &p.corners {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut adj = vec![0u32; start[nv]];
    for (i, p) in mesh.patches.iter().enumerate() {
        for &v in &p.corners {
            adj[fill[v as usize]] = i as u32;
            fill[v as usize] += 1;
        }
    }
    let emits = |i: usize| mesh.patches[i].emission.iter().any(|&e| e > 0.0);
    mesh.patches
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            p.corners.map(|v| {
                let mut sum = [0.0f32; 3];
                let mut w = 0.0f32;
                for &q in &adj[start[v as usize]..start[v as usize + 1]] {
                    let qp = &mesh.patches[q as usize];
                    if qp.normal.dot(p.normal) >= SMOOTH_COS && emits(q as usize) == emits(i) {
                        for c in 0..3 {
                            sum[c] += qp.area * b[q as usize][c];
                        }
                        w += qp.area;
                    }
                }
                if w > 0.0 {
                    sum.map(|s| s / w)
                } else {
                    b[i]
                }
            })
        })
        .collect()
}

/// What the display needs: the mesh, its BVH, the radiosities and (for smoothing) corner values.
pub struct DisplayInput<'a> {
    /// The patches.
    pub mesh: &'a PatchMesh,
    /// BVH over `mesh.triangles` (as built by [`crate::build_accel`]).
    pub accel: &'a Accel,
    /// Radiosity per patch, W m^-2.
    pub radiosity: &'a [[f32; 3]],
}

/// Image settings of the display.
#[derive(Clone, Copy, Debug)]
pub struct ImageSettings {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Reconstruction filter (the scene film's).
    pub filter: FilterDesc,
    /// The film's `sample_border` (see `pt_render::film::sample_pixel_offset`).
    pub sample_border: bool,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the random streams.
    pub seed: u64,
}

/// Closest hit: (patch, triangle, barycentric weights of vertices 1 and 2). `None` when the ray
/// misses; the patch is [`NO_PATCH`] on the black back of a one-sided surface.
#[inline]
fn hit(mesh: &PatchMesh, accel: &Accel, ray: &Ray) -> Option<(u32, usize, f32, f32)> {
    let h = accel.intersect(ray)?;
    let tri = accel.original_index[h.index] as usize;
    let patch = mesh.patch_hit(tri, ray.dir);
    Some((patch, tri, h.b1, h.b2))
}

/// Renders the solution. `progress` receives the fraction of rows done.
pub fn render_image(
    input: &DisplayInput,
    camera: &Camera,
    settings: &ImageSettings,
    display: Display,
    progress: &(dyn Fn(f32) + Sync),
) -> RenderOutput {
    let DisplayInput {
        mesh,
        accel,
        radiosity: b,
    } = *input;
    let corners = match display {
        Display::Smoothed => corner_radiosity(mesh, b),
        _ => Vec::new(),
    };
    let (w, h) = (settings.width, settings.height);
    let start = Instant::now();
    let done = AtomicUsize::new(0);
    let radiance = |ray: Ray, sampler: &mut Sampler| -> [f32; 3] {
        let Some((p, tri, b1, b2)) = hit(mesh, accel, &ray) else {
            return [0.0; 3];
        };
        if p == NO_PATCH {
            return [0.0; 3];
        }
        let patch = &mesh.patches[p as usize];
        match display {
            Display::Constant => b[p as usize].map(|v| v * FRAC_1_PI),
            Display::Smoothed => {
                let c = &corners[p as usize];
                let b0 = 1.0 - b1 - b2;
                std::array::from_fn(|k| (c[0][k] * b0 + c[1][k] * b1 + c[2][k] * b2) * FRAC_1_PI)
            }
            Display::FinalGather => {
                let t = &mesh.triangles[tri];
                let v = t.v.map(|i| mesh.vertices[i as usize]);
                let x = v[0] * (1.0 - b1 - b2) + v[1] * b1 + v[2] * b2;
                let frame = Frame::from_normal(patch.normal);
                let dir = frame
                    .to_world(square_to_cosine_hemisphere(sampler.next_2d()))
                    .normalize();
                let gray = Ray::new(offset_ray_origin(x, patch.normal), dir);
                let incoming = match hit(mesh, accel, &gray) {
                    Some((q, ..)) if q != NO_PATCH => b[q as usize],
                    _ => [0.0; 3],
                };
                std::array::from_fn(|k| {
                    (patch.emission[k] + patch.reflectance[k] * incoming[k]) * FRAC_1_PI
                })
            }
        }
    };
    let filter = Filter::new(settings.filter);
    let rows: Vec<Vec<PixelStats>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let row: Vec<PixelStats> = (0..w)
                .map(|x| {
                    let mut stats = PixelStats::default();
                    let pixel = y as u64 * w as u64 + x as u64;
                    for s in 0..settings.spp {
                        let mut sampler = Sampler::new(settings.seed, pixel, s as u64);
                        let (offset, weight) = sample_pixel_offset(
                            &filter,
                            &mut sampler,
                            (x, y),
                            (w, h),
                            settings.sample_border,
                        );
                        let u_lens = if camera.needs_lens_sample() {
                            sampler.next_2d()
                        } else {
                            Vec2::splat(0.5)
                        };
                        let ray = camera.pixel_ray(x as i32, y as i32, offset, u_lens);
                        // Radiosity computes no coverage (its output has no alpha).
                        stats.add(radiance(ray, &mut sampler).map(|c| c * weight), 0.0);
                    }
                    stats
                })
                .collect();
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(d as f32 / h as f32);
            row
        })
        .collect();
    let time = start.elapsed();
    let mut mean = Vec::with_capacity((w * h) as usize);
    let mut variance = Vec::with_capacity((w * h) as usize);
    let mut nonfinite = 0u64;
    for px in rows.iter().flatten() {
        mean.push(px.mean());
        variance.push(px.variance_of_mean());
        nonfinite += px.nonfinite as u64;
    }
    RenderOutput {
        width: w,
        height: h,
        mean,
        variance,
        spp: settings.spp,
        time,
        nonfinite_samples: nonfinite,
        alpha: None,
        second_moment: None,
    }
}
