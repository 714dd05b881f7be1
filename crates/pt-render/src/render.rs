//! The render loop: rayon over tiles, one independent random stream per sample.

use crate::film::{sample_filter, PixelStats};
use crate::integrator::{li, PathSettings};
use crate::sampler::Sampler;
use crate::scene::Scene;
use pt_math::Vec2;
use pt_scene::FilterDesc;
use pt_spectrum::{spectrum_to_srgb, ColorMode, SampledWavelengths};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// What to render.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the random streams.
    pub seed: u64,
    /// Pixel reconstruction filter.
    pub filter: FilterDesc,
    /// Integrator settings.
    pub path: PathSettings,
    /// Optional clamp of each sample's radiance (linear RGB): a sample whose largest channel
    /// exceeds it is scaled down to it (hue kept, as pbrt-v4's `maxcomponentvalue`). Off by
    /// default. It removes fireflies at the cost of **bias** (energy is lost wherever single
    /// samples legitimately exceed it: caustics, small bright lights); `pt stability` reports
    /// the bias on a test scene.
    pub clamp: Option<f32>,
}

/// The rendered image with its per-pixel variance.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixel means, linear RGB radiance, row-major from the top.
    pub mean: Vec<[f32; 3]>,
    /// Variance of each pixel mean (sample variance / spp).
    pub variance: Vec<[f32; 3]>,
    /// Samples per pixel.
    pub spp: u32,
    /// Wall-clock time of the sampling loop.
    pub time: Duration,
    /// Samples whose radiance was NaN or infinite (excluded from the means).
    pub nonfinite_samples: u64,
}

/// Tile edge in pixels: small enough to balance 2-64 threads on 256^2 images, large enough
/// that scheduling overhead is negligible.
const TILE: u32 = 16;

/// Renders the image. `progress` is called after each tile with the number of samples it took
/// (called from worker threads). The result depends only on the scene, settings and seed, not
/// on the number of threads.
pub fn render(scene: &Scene, settings: &RenderSettings, progress: &(dyn Fn(u64) + Sync)) -> RenderOutput {
    let (w, h) = (settings.width, settings.height);
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(TILE)).flat_map(|ty| (0..tiles_x).map(move |tx| (tx, ty))).collect();
    let start = Instant::now();
    let results: Vec<Vec<PixelStats>> = tiles
        .par_iter()
        .map(|&(tx, ty)| {
            let (x0, y0) = (tx * TILE, ty * TILE);
            let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
            let mut out = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
            for y in y0..y1 {
                for x in x0..x1 {
                    out.push(render_pixel(scene, settings, x, y));
                }
            }
            progress(out.len() as u64 * settings.spp as u64);
            out
        })
        .collect();
    let time = start.elapsed();

    let n = (w * h) as usize;
    let mut mean = vec![[0.0; 3]; n];
    let mut variance = vec![[0.0; 3]; n];
    let mut nonfinite = 0u64;
    for (&(tx, ty), tile) in tiles.iter().zip(&results) {
        let (x0, y0) = (tx * TILE, ty * TILE);
        let x1 = (x0 + TILE).min(w);
        for (k, px) in tile.iter().enumerate() {
            let (x, y) = (x0 + k as u32 % (x1 - x0), y0 + k as u32 / (x1 - x0));
            let i = (y * w + x) as usize;
            mean[i] = px.mean();
            variance[i] = px.variance_of_mean();
            nonfinite += px.nonfinite as u64;
        }
    }
    RenderOutput { width: w, height: h, mean, variance, spp: settings.spp, time, nonfinite_samples: nonfinite }
}

/// Scales `rgb` so that its largest channel is at most `max` (non-finite samples pass through,
/// so that they are still counted and left out by the film).
#[inline]
pub fn clamp_sample(rgb: [f32; 3], max: f32) -> [f32; 3] {
    let m = rgb[0].max(rgb[1]).max(rgb[2]);
    if m > max && m.is_finite() {
        let k = max / m;
        [rgb[0] * k, rgb[1] * k, rgb[2] * k]
    } else {
        rgb
    }
}

fn render_pixel(scene: &Scene, settings: &RenderSettings, x: u32, y: u32) -> PixelStats {
    let mut stats = PixelStats::default();
    let pixel = y as u64 * settings.width as u64 + x as u64;
    let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    // RGB mode draws no wavelength sample, so its random sequence is the same as before the
    // spectral mode existed.
    let spectral = scene.mode == ColorMode::Spectral;
    let rgb_lambda = SampledWavelengths::sample_visible(0.5);
    for s in 0..settings.spp {
        let mut sampler = Sampler::new(settings.seed, pixel, s as u64);
        let lambda = if spectral { SampledWavelengths::sample_visible(sampler.next_1d()) } else { rgb_lambda };
        let offset = sample_filter(&settings.filter, &mut sampler);
        let ray = scene.camera.generate_ray(centre + offset);
        let l = li(scene, ray, &settings.path, &mut sampler, &lambda);
        let rgb = if spectral { spectrum_to_srgb(l, &lambda) } else { l.rgb() };
        stats.add(match settings.clamp {
            Some(c) => clamp_sample(rgb, c),
            None => rgb,
        });
    }
    stats
}
