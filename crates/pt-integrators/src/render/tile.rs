//! One pass over the image in tiles (filter importance sampling or the splatting film), and
//! the render loop inside a tile: rows of samples traced together, compiled for x86-64-v3
//! where the processor has it.

use super::{clamp_sample, RenderSettings};
use crate::path::{trace_paths, PathQueue, PathStart, PathState};
use pt_math::Vec2;
use pt_render::film::splat::{SplatFilm, SplatTile};
use pt_render::film::{filter_radius, sample_pixel_offset, PixelStats};
use pt_render::sampler::{RandomSource, Sampler, StructuredSampler};
use pt_render::Scene;
use pt_spectrum::{spectrum_to_srgb, srgb_to_xyz, ColorMode, SampledWavelengths};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// Tile width and largest band height in pixels (see [`super::render_passes`]): small enough to
/// balance many threads, large enough that scheduling overhead is negligible.
const TILE: u32 = 16;

/// One pass of filter importance sampling: samples `samples` of every pixel. `costs` carries
/// the bands' times from pass to pass ([`costliest_first`]).
pub(super) fn importance_pass(
    scene: &Scene,
    settings: &RenderSettings,
    pixels: &mut [PixelStats],
    samples: std::ops::Range<u32>,
    costs: &mut Vec<f32>,
    progress: &(dyn Fn(u64) + Sync),
) {
    let (w, h) = (settings.width, settings.height);
    // The image is rendered in place, in bands of whole rows (contiguous in `pixels`), each
    // band in tiles of TILE columns. Bands are TILE rows high, lower for small images on many
    // threads so that every thread gets about 32 bands (the pass ends at a barrier where a
    // thread may idle for a band). Rendering tiles into copies and writing them back held a
    // second image of sums: 2048x2048 peaked at 467 MB.
    let threads = rayon::current_num_threads().max(1) as u32;
    let rows = (h / (32 * threads)).clamp(1, TILE);
    let bands = pixels.chunks_mut((w * rows) as usize).enumerate().collect();
    costliest_first(bands, costs, |(b, band)| {
        let y0 = b as u32 * rows;
        let y1 = (y0 + rows).min(h);
        for x0 in (0..w).step_by(TILE as usize) {
            let tile = Tile {
                x0: x0 as i32,
                y0: y0 as i32,
                x1: (x0 + TILE).min(w) as i32,
                y1: y1 as i32,
                samples: samples.clone(),
            };
            render_tile(scene, settings, Target::Pixels(band), &tile);
            progress(tile.image_pixels(w, h) * u64::from(samples.len() as u32));
        }
    });
}

/// One pass of the splatting film: samples `samples` of every origin pixel (the image's and,
/// with `sample_border`, its border's), over the film's tiles (each owns its accumulator and
/// the contiguous slice of tile-major statistics of its origins). `costs` carries the tiles'
/// times from pass to pass ([`costliest_first`]).
pub(super) fn splat_pass(
    scene: &Scene,
    settings: &RenderSettings,
    pixels: &mut [PixelStats],
    film: &mut SplatFilm,
    samples: std::ops::Range<u32>,
    costs: &mut Vec<f32>,
    progress: &(dyn Fn(u64) + Sync),
) {
    let layout = &film.layout;
    let columns = layout.tile_columns();
    let mut rest = pixels;
    let mut jobs = Vec::with_capacity(film.tiles.len());
    for (k, acc) in film.tiles.iter_mut().enumerate() {
        let (i, j) = (k % columns, k / columns);
        let (xs, ys) = layout.image_origins(i, j);
        let n = xs.len() * ys.len();
        let (stats, r) = std::mem::take(&mut rest).split_at_mut(n);
        rest = r;
        jobs.push((i, j, stats, acc));
    }
    costliest_first(jobs, costs, |(i, j, stats, acc)| {
        let (xs, ys) = layout.origins(i, j);
        let tile = Tile {
            x0: xs.start,
            y0: ys.start,
            x1: xs.end,
            y1: ys.end,
            samples: samples.clone(),
        };
        let n = stats.len() as u64;
        render_tile(scene, settings, Target::Splat { stats, acc }, &tile);
        progress(n * u64::from(samples.len() as u32));
    });
}

/// Runs the jobs of a pass on every thread of rayon's pool, each thread taking the next job
/// when it finishes one, the costliest first by `costs` (each job's seconds in the previous
/// pass, by its index; in the given order when the previous pass had other jobs, as the first
/// has none), and records this pass's times in `costs`. Longest processing time first (Graham
/// 1969): a pass ends at a barrier, and the jobs still running when the queue runs dry are its
/// cheapest, so a thread idles there for a short job rather than for a costly one (tiles cost
/// very unequally where geometry or emitters cover part of the image). The image does not
/// depend on the order: every job owns its pixels' sums, which are exact.
fn costliest_first<J: Send>(jobs: Vec<J>, costs: &mut Vec<f32>, work: impl Fn(J) + Sync) {
    let n = jobs.len();
    let mut order: Vec<(usize, J)> = jobs.into_iter().enumerate().collect();
    if costs.len() == n {
        order.sort_by(|a, b| costs[b.0].total_cmp(&costs[a.0]));
    }
    let queue = Mutex::new(order.into_iter());
    let times: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(0)).collect();
    rayon::broadcast(|_| loop {
        // A job's own panic would poison the lock; the queue itself stays consistent.
        let next = queue.lock().unwrap_or_else(|e| e.into_inner()).next();
        let Some((k, job)) = next else {
            break;
        };
        let start = Instant::now();
        work(job);
        times[k].store(start.elapsed().as_secs_f32().to_bits(), Ordering::Relaxed);
    });
    *costs = times
        .into_iter()
        .map(|t| f32::from_bits(t.into_inner()))
        .collect();
}

/// Pixels `x0..x1` by `y0..y1` of the image (origin pixels beyond the image's edge for a
/// splatting film with `sample_border`) and the samples to take in them.
struct Tile {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
    samples: std::ops::Range<u32>,
}

impl Tile {
    /// Number of the tile's pixels inside a `w` x `h` image (for progress: border origins are
    /// not counted).
    fn image_pixels(&self, w: u32, h: u32) -> u64 {
        let span = |a: i32, b: i32, n: u32| (b.min(n as i32) - a.max(0)).max(0) as u64;
        span(self.x0, self.x1, w) * span(self.y0, self.y1, h)
    }
}

/// Where a tile's samples go.
enum Target<'a> {
    /// Importance sampling: the image rows `tile.y0..tile.y1` (full width), each sample
    /// added to its own pixel.
    Pixels(&'a mut [PixelStats]),
    /// Splatting: the tile's accumulator, and the variance statistics of the tile's origins
    /// inside the image (row-major over them).
    Splat {
        stats: &'a mut [PixelStats],
        acc: &'a mut SplatTile,
    },
}

/// Renders one tile: takes its samples and adds them to `target`, compiled for the processor's
/// wider instructions when it has them ([`pt_render::isa::best`]): the path integrator and the
/// BSDF and light routines it calls are inlined into the loop (`#[inline(always)]`), since a
/// function compiled separately keeps the baseline instructions. Cornell box, 256x256, 64 spp,
/// 2 threads: 1.71 -> 2.02 M samples/s (+18%, as much as building everything with
/// `-C target-cpu=x86-64-v3`; AVX-512, `target-cpu=native` on this project's machine, gave
/// only +6%).
fn render_tile(scene: &Scene, settings: &RenderSettings, target: Target, tile: &Tile) {
    pt_render::isa::best(
        #[inline(always)]
        || render_tile_portable(scene, settings, target, tile),
    )
}

/// The body of [`render_tile`], inlined into each instruction-set variant. The rows are traced
/// at one place for both films ([`trace_row`] holds the whole path loop, inlined: a second call
/// site would be a second copy of it to compile).
#[inline(always)]
fn render_tile_portable(scene: &Scene, settings: &RenderSettings, target: Target, tile: &Tile) {
    let splat = matches!(target, Target::Splat { .. });
    let tw = (tile.x1 - tile.x0) as usize;
    let ns = tile.samples.len();
    // Splatting: per origin pixel (row-major) its samples in order: position in the pixel
    // ([0, 1)^2), linear RGB and alpha.
    let mut taken = if splat {
        vec![(Vec2::ZERO, [0.0f32; 3], 0.0f32); tw * (tile.y1 - tile.y0) as usize * ns]
    } else {
        Vec::new()
    };
    let (mut band, mut stats, acc) = match target {
        Target::Pixels(band) => (Some(band), None, None),
        Target::Splat { stats, acc } => (None, Some(stats), Some(acc)),
    };
    for y in tile.y0..tile.y1 {
        let mut sink = match (&mut band, &mut stats) {
            (Some(band), _) => {
                let width = settings.width as usize;
                let row = &mut band[(y - tile.y0) as usize * width..][..width];
                SampleSink::Pixels(row, settings.variance)
            }
            (None, stats) => SampleSink::Splat(splat_row(settings, tile, y, stats, &mut taken)),
        };
        trace_row(scene, settings, y, tile, &mut sink);
    }
    if let Some(acc) = acc {
        splat_taken(settings, tile, &taken, acc);
    }
}

/// Where [`trace_row`] puts row `y`'s samples of a splatting tile: into `taken` (see
/// [`render_tile_portable`]) and the variance statistics of the row's origins inside the image
/// (`stats`: the tile's, row-major over them; none for a border row).
fn splat_row<'a>(
    settings: &RenderSettings,
    tile: &Tile,
    y: i32,
    stats: &'a mut Option<&mut [PixelStats]>,
    taken: &'a mut [(Vec2, [f32; 3], f32)],
) -> SplatRow<'a> {
    let (w, h) = (settings.width as i32, settings.height as i32);
    let (ix0, ix1) = (tile.x0.max(0), tile.x1.min(w));
    let iy0 = tile.y0.max(0);
    let row = match stats {
        Some(stats) if (0..h).contains(&y) && ix0 < ix1 => {
            let start = ((y - iy0) * (ix1 - ix0)) as usize;
            Some(&mut stats[start..start + (ix1 - ix0) as usize])
        }
        _ => None,
    };
    let tw = (tile.x1 - tile.x0) as usize;
    SplatRow {
        taken,
        first: (y - tile.y0) as usize * tw,
        x0: tile.x0,
        samples: tile.samples.start,
        per_origin: tile.samples.len(),
        stats: row,
        inside: ix0..ix1,
        variance: settings.variance,
    }
}

/// Splats a tile's samples `taken` (see [`render_tile_portable`]) into `acc` sample index
/// first, origin pixel (row-major) second, so that the order in which each pixel's sums grow
/// does not depend on how samples were split into passes. Inlined into the render loop's
/// instruction-set variants, as the filter weights' SIMD pass gains from them.
#[inline(always)]
fn splat_taken(
    settings: &RenderSettings,
    tile: &Tile,
    taken: &[(Vec2, [f32; 3], f32)],
    acc: &mut SplatTile,
) {
    let tw = (tile.x1 - tile.x0) as usize;
    let ns = tile.samples.len();
    let radius = filter_radius(&settings.filter.desc);
    let channels = settings.splat_channels();
    for k in 0..ns {
        for q in 0..taken.len() / ns {
            let (u, rgb, alpha) = taken[q * ns + k];
            let origin = [tile.x0 + (q % tw) as i32, tile.y0 + (q / tw) as i32];
            // Samples the film cannot add (non-finite or huge) are counted by the statistics
            // above and left out here.
            if pt_render::film::exact::fits(&rgb) {
                let [r, g, b] = rgb;
                // The squared XYZ only for moment renders (the film reads `channels` values).
                let [x, y, z] = if channels > 4 {
                    srgb_to_xyz(rgb)
                } else {
                    [0.0; 3]
                };
                let values = [r, g, b, alpha, x * x, y * y, z * z];
                acc.splat(
                    &settings.filter.desc,
                    radius,
                    origin,
                    u,
                    &values[..channels],
                );
            }
        }
        // The tile's splats of sample k, summed in a fixed order, join its exact sums.
        acc.commit();
    }
}

/// Receives the samples of [`trace_row`]. One concrete type for both films, so that the path
/// loop is compiled once per kind of random numbers and instruction set, not once more per
/// film (the loop is the bulk of the crate's code and of its build time); `put` is inlined
/// into the render loop and compiled for its instruction sets ([`render_tile`]), where an
/// outlined closure would be compiled for the baseline and the film's exact sums cost more.
enum SampleSink<'a> {
    /// Filter importance sampling: each sample into its own pixel of the row, with the sums
    /// of its squares when true ([`RenderSettings::variance`]).
    Pixels(&'a mut [PixelStats], bool),
    /// Splatting.
    Splat(SplatRow<'a>),
}

impl SampleSink<'_> {
    /// Sample `k` of pixel `x`: linear RGB radiance, alpha (0 or 1), film offset from the
    /// pixel's centre, film weight.
    #[inline(always)]
    fn put(&mut self, x: i32, k: u32, rgb: [f32; 3], alpha: f32, offset: Vec2, w: f32) {
        match self {
            SampleSink::Pixels(row, variance) => {
                let (v, a) = (rgb.map(|c| c * w), alpha * w);
                if *variance {
                    row[x as usize].add(v, a);
                } else {
                    row[x as usize].add_mean(v, a);
                }
            }
            SampleSink::Splat(row) => row.put(x, k, rgb, alpha, offset),
        }
    }
}

/// Splatting: each sample kept (per origin pixel, in sample order) until the tile splats them,
/// and added to its origin's variance statistics.
struct SplatRow<'a> {
    /// The tile's samples: origin pixel (row-major over the tile) times `per_origin`.
    taken: &'a mut [(Vec2, [f32; 3], f32)],
    /// The row's first origin's index in the tile.
    first: usize,
    /// The tile's first column.
    x0: i32,
    /// The pass's first sample index (local).
    samples: u32,
    /// Samples per origin in the pass.
    per_origin: usize,
    /// The row's statistics for the columns `inside` (none for a border row).
    stats: Option<&'a mut [PixelStats]>,
    /// The columns inside the image.
    inside: std::ops::Range<i32>,
    /// Whether `stats` keep the sums for the variance or only count the samples
    /// ([`RenderSettings::variance`]).
    variance: bool,
}

impl SplatRow<'_> {
    /// Sample `k` of pixel `x` (as [`SampleSink::put`]; the film weighs splatted samples).
    #[inline(always)]
    fn put(&mut self, x: i32, k: u32, rgb: [f32; 3], alpha: f32, offset: Vec2) {
        let q = self.first + (x - self.x0) as usize;
        // Exact: the offset is u - 1/2 for u a multiple of 2^-24 in [0, 1).
        self.taken[q * self.per_origin + (k - self.samples) as usize] =
            (offset + Vec2::splat(0.5), rgb, alpha);
        if let Some(r) = self.stats.as_deref_mut() {
            if self.inside.contains(&x) {
                let stats = &mut r[(x - self.inside.start) as usize];
                if self.variance {
                    stats.add(rgb, alpha);
                } else {
                    stats.count(&rgb);
                }
            }
        }
    }
}

/// Traces samples `tile.samples` of pixels `tile.x0..tile.x1` of row `y` and hands each
/// result to `sink`, pixel by pixel, each pixel's in sample order. For a splatting film the
/// sample's position is uniform in its pixel (weight 1; the film weighs it), else it is drawn
/// from the filter ([`sample_pixel_offset`]).
#[inline(always)]
fn trace_row(scene: &Scene, settings: &RenderSettings, y: i32, tile: &Tile, sink: &mut SampleSink) {
    let splat = matches!(sink, SampleSink::Splat(_));
    // RGB mode draws no wavelength sample (its lanes are R, G, B), so its random sequence is the
    // same as before the spectral mode existed; these wavelengths are only carried along.
    let rgb_lambda = SampledWavelengths::sample_visible(0.5);
    let args = (
        y,
        tile.x0..tile.x1,
        tile.samples.clone(),
        &rgb_lambda,
        splat,
    );
    // The loop is compiled once per kind of random numbers: independent numbers (most scenes)
    // pay nothing for the structured patterns' dimension bookkeeping.
    let pattern = &settings.sampler;
    if pattern.is_independent() {
        render_row_samples(scene, settings, args, sink, |pixel, k| {
            Sampler::new(settings.seed, pixel, k)
        });
    } else {
        render_row_samples(scene, settings, args, sink, |pixel, k| {
            StructuredSampler::new(pattern, settings.seed, pixel, k).expect("a structured pattern")
        });
    }
}

/// Samples traced together before their results are handed on: paths finish out of order, and
/// each pixel's results are handed on in sample order (so that the image does not depend on
/// it).
const SAMPLE_CHUNK: u32 = 64;

/// The body of [`trace_row`] for one kind of random numbers. The samples are taken pixel after
/// pixel (all of a pixel's, then the next pixel's) and traced up to `MAX_PATHS` at a time (see
/// [`trace_paths`]), so that passes of few samples per pixel still keep the paths in flight;
/// each sample is the same as traced alone.
#[inline(always)]
fn render_row_samples<S: RandomSource>(
    scene: &Scene,
    settings: &RenderSettings,
    (y, xs, samples, rgb_lambda, splat): (
        i32,
        std::ops::Range<i32>,
        std::ops::Range<u32>,
        &SampledWavelengths,
        bool,
    ),
    sink: &mut SampleSink,
    new_sampler: impl Fn(u64, u64) -> S,
) {
    if samples.is_empty() || xs.is_empty() {
        return;
    }
    let mut chunk = RowChunk {
        scene,
        settings,
        y,
        xs: xs.clone(),
        samples: samples.clone(),
        rgb_lambda: *rgb_lambda,
        splat,
        new_sampler,
        x: xs.start,
        k: samples.start,
        taken: 0,
        results: [([0.0f32; 3], 0.0f32); SAMPLE_CHUNK as usize],
        offsets: [(Vec2::ZERO, 1.0f32); SAMPLE_CHUNK as usize],
    };
    while chunk.x < xs.end {
        let (chunk_x, chunk_k) = (chunk.x, chunk.k);
        chunk.taken = 0;
        trace_paths(scene, &settings.path, &mut chunk);
        // The chunk's results, in the order they were started: pixel by pixel, each in sample
        // order.
        let (mut px, mut pk) = (chunk_x, chunk_k);
        let taken = chunk.taken as usize;
        for ((rgb, alpha), (offset, w)) in chunk.results[..taken].iter().zip(&chunk.offsets) {
            sink.put(px, pk, *rgb, *alpha, *offset, *w);
            pk += 1;
            if pk == samples.end {
                (px, pk) = (px + 1, samples.start);
            }
        }
    }
}

/// One chunk of [`render_row_samples`]: the camera paths of up to [`SAMPLE_CHUNK`] samples of
/// a row's pixels, started for [`trace_paths`] and their results taken back.
struct RowChunk<'a, F> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    /// The row, its pixels and the samples of each pixel.
    y: i32,
    xs: std::ops::Range<i32>,
    samples: std::ops::Range<u32>,
    /// The wavelengths of an RGB render (a spectral one samples its own per path).
    rgb_lambda: SampledWavelengths,
    /// Whether the film splats (the sample's film offset is uniform over the pixel).
    splat: bool,
    /// A sample's random numbers from its pixel key and sample index.
    new_sampler: F,
    /// The next sample to start, as (pixel x, sample index); `x == xs.end` when all are
    /// started.
    x: i32,
    k: u32,
    /// Samples started in this chunk.
    taken: u32,
    /// Each started sample's colour and alpha, by the order it started in.
    results: [([f32; 3], f32); SAMPLE_CHUNK as usize],
    /// Each sample's film offset and weight (1 but for filters with negative lobes).
    offsets: [(Vec2, f32); SAMPLE_CHUNK as usize],
}

impl<S: RandomSource, F: Fn(u64, u64) -> S> PathQueue<S> for RowChunk<'_, F> {
    #[inline(always)]
    fn start(&mut self, slot: &mut Option<PathStart<S>>) {
        let (x, y, settings) = (self.x, self.y, self.settings);
        if self.taken == SAMPLE_CHUNK || x >= self.xs.end {
            *slot = None;
            return;
        }
        let pixel = settings.pixel_key(x, y);
        let mut sampler = (self.new_sampler)(pixel, u64::from(settings.share.sample(self.k)));
        let lambda = if self.scene.mode == ColorMode::Spectral {
            SampledWavelengths::sample_visible(sampler.next_1d())
        } else {
            self.rgb_lambda
        };
        let (offset, weight) = if self.splat {
            (sampler.next_2d() - Vec2::splat(0.5), 1.0)
        } else {
            sample_pixel_offset(
                &settings.filter,
                &mut sampler,
                (x as u32, y as u32),
                (settings.width, settings.height),
                settings.sample_border,
            )
        };
        let ray = self
            .scene
            .camera
            .sample_ray(x, y, offset, || sampler.next_2d());
        let path = PathState::new(self.scene, ray, &lambda);
        let tag = self.taken;
        self.offsets[tag as usize] = (offset, weight);
        self.taken += 1;
        self.k += 1;
        if self.k == self.samples.end {
            (self.x, self.k) = (x + 1, self.samples.start);
        }
        *slot = Some(PathStart {
            path,
            sampler,
            lambda,
            tag,
        });
    }

    #[inline(always)]
    fn finish(&mut self, done: &PathStart<S>) {
        let l = done.path.radiance;
        let rgb = if self.scene.mode == ColorMode::Spectral {
            spectrum_to_srgb(l, &done.lambda)
        } else {
            l.rgb()
        };
        let rgb = match self.settings.clamp {
            Some(c) => clamp_sample(rgb, c),
            None => rgb,
        };
        let alpha = f32::from(u8::from(done.path.covered));
        self.results[done.tag as usize] = (rgb, alpha);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_render::{BvhKind, LightSelection};

    /// The x86-64-v3 variants ([`pt_render::isa::best`]) must give exactly the portable
    /// variants' results (the same arithmetic compiled with other instructions): the path
    /// tracer's pixel sums on scenes that together use every BSDF family, textures, spectral
    /// mode, fluorescence and media, and the images of the methods that trace from the lights
    /// (light tracing, BDPT, VCM, which splat). A difference in any bit fails it (what fused
    /// multiply-adds or a different libm path would cause). One test, because the switch to
    /// the portable variants is process-wide.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn v3_variants_match_portable_bit_for_bit() {
        if !pt_render::has_x86_64_v3() {
            eprintln!(
                "skipped: this processor lacks x86-64-v3 (the portable variant is the only one)"
            );
            return;
        }
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let scenes = [
            "cornell-box.xml",
            "conductors.xml",
            "dielectrics.xml",
            "plastic.xml",
            "rough-thin-film.xml",
            "diffuse-models.xml",
            "fluorescence.xml",
            "coloured-glass.xml",
            "normal-map.xml",
            "envmap-spectral.xml",
            "fog-spot.xml",
        ];
        for name in scenes {
            let desc =
                pt_scene::load_file(&dir.join(name), &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
            let scene = Scene::build(&desc, BvhKind::CwBvh, LightSelection::Power)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let mut settings = RenderSettings::from_desc(&desc);
            settings.path.media = true;
            // A 16 x 16 tile across the image centre, 4 samples per pixel, in its band of rows.
            let (x0, y0) = (settings.width / 2 - 8, settings.height / 2 - 8);
            let tile = Tile {
                x0: x0 as i32,
                y0: y0 as i32,
                x1: x0 as i32 + 16,
                y1: y0 as i32 + 16,
                samples: 0..4,
            };
            let mut portable = vec![PixelStats::default(); (settings.width * 16) as usize];
            let mut v3 = portable.clone();
            pt_render::isa::force_baseline(true);
            render_tile(&scene, &settings, Target::Pixels(&mut portable), &tile);
            pt_render::isa::force_baseline(false);
            render_tile(&scene, &settings, Target::Pixels(&mut v3), &tile);
            // The exact sums hold every f32 sample above 2^-33 to its last bit.
            assert!(portable == v3, "{name}: the x86-64-v3 variant differs");
            assert!(
                portable.iter().any(|p| p.sum.iter().any(|s| s.0 > 0)),
                "{name}: the tile is black, the test checks nothing"
            );
        }
        let methods = [
            ("caustic-sphere-light.xml", "ptracer"),
            ("caustic-point-light.xml", "bdpt"),
            ("cornell-box.xml", "vcm"),
        ];
        for (name, method) in methods {
            let mut desc =
                pt_scene::load_file(&dir.join(name), &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
            (desc.film.width, desc.film.height) = (24, 24);
            let overrides = crate::Overrides {
                kind: Some(crate::method(method).expect("a method name")),
                ..Default::default()
            };
            let integrator = crate::Integrator::from_desc(&desc.integrator, &overrides).unwrap();
            let job = crate::Job {
                spp: 2,
                ..crate::Job::new(&desc)
            };
            let image = |baseline: bool| {
                pt_render::isa::force_baseline(baseline);
                let r = integrator.render(&job, crate::Run::default()).unwrap();
                pt_render::isa::force_baseline(false);
                r.output
            };
            let (portable, v3) = (image(true), image(false));
            let bits = |v: &[[f32; 3]]| v.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
            assert!(
                bits(&portable.mean) == bits(&v3.mean)
                    && bits(&portable.variance) == bits(&v3.variance),
                "{method} on {name}: the x86-64-v3 variant differs"
            );
            assert!(
                portable.mean.iter().flatten().any(|&c| c > 0.0),
                "{method} on {name}: the image is black, the test checks nothing"
            );
        }
    }

    /// A render without the variance (`RenderSettings::variance` off, as `pt render` runs
    /// without `--variance`) is the same image, bit for bit, with the same alpha and sample
    /// counts; only its variance is zero. Under both films: splatting on the tent-filtered film
    /// scene, whose splats cross tiles, and importance sampling on the box-filtered Cornell box.
    #[test]
    fn image_does_not_depend_on_the_variance() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        for (name, splats) in [("film-tent.xml", true), ("cornell-box.xml", false)] {
            let mut desc = pt_scene::load_file(&dir.join(name), &[]).expect(name);
            (desc.film.width, desc.film.height) = (48, 36);
            let scene = Scene::build(&desc, BvhKind::Auto, LightSelection::default()).unwrap();
            let with = RenderSettings {
                spp: 5,
                ..RenderSettings::from_desc(&desc)
            };
            assert!(
                with.splats() == splats && with.variance,
                "{name}: the test needs this film"
            );
            let without = RenderSettings {
                variance: false,
                ..with.clone()
            };
            let (a, b) = (
                crate::render::render(&scene, &with, &|_| {}),
                crate::render::render(&scene, &without, &|_| {}),
            );
            let bits = |v: &[[f32; 3]]| v.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
            assert!(bits(&a.mean) == bits(&b.mean), "{name}: the image changed");
            assert_eq!(a.alpha, b.alpha, "{name}");
            assert_eq!(a.nonfinite_samples, b.nonfinite_samples, "{name}");
            assert!(
                a.variance.iter().flatten().any(|&v| v > 0.0),
                "{name}: no variance to leave out"
            );
            assert!(b.variance.iter().flatten().all(|&v| v == 0.0), "{name}");
        }
    }

    /// The pass scheduler runs every job exactly once, records one time per job, and with the
    /// previous pass's times takes the costliest first: on one thread the jobs then run in
    /// decreasing order of their recorded costs.
    #[test]
    fn costliest_first_runs_each_job_once_costliest_first() {
        let mut counts = vec![0u32; 40];
        let mut costs = Vec::new();
        let jobs: Vec<(usize, &mut u32)> = counts.iter_mut().enumerate().collect();
        costliest_first(jobs, &mut costs, |(_, c)| *c += 1);
        assert!(counts.iter().all(|&c| c == 1), "{counts:?}");
        assert_eq!(costs.len(), 40);
        assert!(costs.iter().all(|t| t.is_finite() && *t >= 0.0));
        // Made-up costs: job k cost (k * 7) % 40. On a pool of one thread the order is theirs.
        let mut costs: Vec<f32> = (0..40).map(|k| ((k * 7) % 40) as f32).collect();
        let before = costs.clone();
        let order = Mutex::new(Vec::new());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        pool.install(|| {
            costliest_first((0..40).collect(), &mut costs, |k: usize| {
                order.lock().unwrap().push(k)
            })
        });
        let order = order.into_inner().unwrap();
        assert_eq!(order.len(), 40);
        assert!(
            order.windows(2).all(|w| before[w[0]] >= before[w[1]]),
            "{order:?}"
        );
    }
}
