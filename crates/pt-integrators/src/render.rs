//! The render loop: passes over the image, rayon over tiles, one independent random stream per
//! sample; a render can be cancelled between passes and resumed from its saved sums.

use crate::path::{trace_paths, PathSettings, PathStart, PathState};
use pt_math::Vec2;
use pt_render::film::exact::ExactSum;
use pt_render::film::light::LightFilm;
use pt_render::film::splat::{SplatFilm, SplatLayout, SplatTile};
use pt_render::film::{filter_radius, sample_pixel_offset, Filter, PixelStats};
use pt_render::sampler::{RandomSource, SamplePattern, Sampler, StructuredSampler};
use pt_render::{RenderOutput, Scene};
use pt_spectrum::{spectrum_to_srgb, srgb_to_xyz, ColorMode, SampledWavelengths};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// What to render.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Where the image lies in a larger film (a crop window), or `None` for the whole film.
    /// Each pixel's random stream is keyed by its position in the whole film, so a cropped
    /// render with `sample_border` is the same pixels, bit for bit, as the whole film's render.
    pub crop: Option<pt_scene::CropWindow>,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the random streams.
    pub seed: u64,
    /// How the samples of a pixel are placed (the scene's sampler, for blocks of its sample
    /// count, whatever `spp` is).
    pub sampler: SamplePattern,
    /// Pixel reconstruction filter.
    pub filter: Filter,
    /// Mitsuba's `sample_border` (see `pt_render::film::sample_pixel_offset`).
    pub sample_border: bool,
    /// How samples become pixels (Mitsuba's splatting or filter importance sampling).
    pub reconstruction: pt_scene::Reconstruction,
    /// Keep the per-pixel mean of the samples' squared XYZ (Mitsuba's `moment`); such renders
    /// always splat, as Mitsuba's film does.
    pub moment: bool,
    /// Integrator settings.
    pub path: PathSettings,
    /// Optional clamp of each sample's radiance (linear RGB): a sample whose largest channel
    /// exceeds it is scaled down to it (hue kept, as pbrt-v4's `maxcomponentvalue`). Off by
    /// default. It removes fireflies at the cost of **bias** (energy is lost wherever single
    /// samples legitimately exceed it: caustics, small bright lights); `pt stability` reports
    /// the bias on a test scene.
    pub clamp: Option<f32>,
    /// Which of the render's sample indices this process takes (all, or one share of a render
    /// split over machines); `spp` counts the share's samples.
    pub share: Share,
}

/// Which of a render's sample indices one process takes: the `index`-th (from 0) of `count`
/// interleaved shares, samples `index`, `index + count`, `index + 2 count` ... of every pixel
/// (`pt render --part K/N` is share K - 1 of N). Interleaving gives every share the same cost
/// however the cost varies with the sample index (structured samplers, progressive passes).
/// Each sample keeps its random stream (keyed by its index in the whole render) and the film's
/// sums are exact ([`pt_render::film::exact`]), so the shares' sums add up to the whole
/// render's, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Share {
    /// Which share, from 0.
    pub index: u32,
    /// Number of shares (at least 1).
    pub count: u32,
}

impl Share {
    /// Every sample: a render on one machine.
    pub const WHOLE: Share = Share { index: 0, count: 1 };

    /// The render's index of the share's `local`-th sample.
    #[inline]
    pub fn sample(&self, local: u32) -> u32 {
        local * self.count + self.index
    }

    /// How many of a render's `spp` samples per pixel the share takes.
    pub fn samples_of(&self, spp: u32) -> u32 {
        if spp > self.index {
            (spp - self.index - 1) / self.count + 1
        } else {
            0
        }
    }
}

impl RenderSettings {
    /// The key of the image's pixel (x, y) for the random streams: its index in the whole
    /// film, row by row. Pixels outside the film (the border a splatting film samples with
    /// `sample_border`) get keys above every film pixel's, from their film coordinates.
    #[inline]
    pub fn pixel_key(&self, x: i32, y: i32) -> u64 {
        let (dx, dy, film) = match &self.crop {
            Some(c) => (c.offset[0], c.offset[1], c.film_size),
            None => (0, 0, [self.width, self.height]),
        };
        let fx = i64::from(x) + i64::from(dx);
        let fy = i64::from(y) + i64::from(dy);
        if (0..i64::from(film[0])).contains(&fx) && (0..i64::from(film[1])).contains(&fy) {
            (fy as u64) * u64::from(film[0]) + fx as u64
        } else {
            // Film coordinates are below 2^16 (the loader's limit) and the border a few
            // pixels: shifted by 2^20 they are non-negative 21-bit numbers.
            let shift = 1i64 << 20;
            (1u64 << 62) | (((fy + shift) as u64) << 24) | ((fx + shift) as u64)
        }
    }

    /// Whether samples are splatted (Mitsuba's film with a filter wider than a pixel). The box
    /// filter's splat is its own pixel with weight 1, which is what importance sampling the box
    /// gives, so it takes the importance-sampling loop under either setting (same image).
    /// Moment renders always splat (their squared XYZ is kept by the splatting film only).
    pub fn splats(&self) -> bool {
        self.moment
            || (self.reconstruction == pt_scene::Reconstruction::Splat
                && !matches!(self.filter.desc, pt_scene::FilterDesc::Box { .. }))
    }

    /// Values the splatting film adds per sample: linear R, G, B and alpha, and with
    /// [`RenderSettings::moment`] the squares of the sample's X, Y, Z.
    fn splat_channels(&self) -> usize {
        if self.moment {
            7
        } else {
            4
        }
    }

    /// The settings a scene file asks for: film size and filter, spp, seed, and its
    /// integrator's ([`PathSettings::from_desc`]).
    pub fn from_desc(desc: &pt_scene::SceneDesc) -> Self {
        RenderSettings {
            width: desc.film.width,
            height: desc.film.height,
            crop: desc.film.crop,
            spp: desc.sampler.sample_count,
            seed: desc.sampler.seed,
            sampler: SamplePattern::new(desc.sampler.kind, desc.sampler.sample_count),
            filter: Filter::new(desc.film.filter),
            sample_border: desc.film.sample_border,
            reconstruction: desc.film.reconstruction,
            moment: desc.integrator.moment.is_some(),
            path: PathSettings::from_desc(&desc.integrator),
            clamp: None,
            share: Share::WHOLE,
        }
    }
}

/// Tile width and largest band height in pixels (see [`render_passes`]): small enough to
/// balance many threads, large enough that scheduling overhead is negligible.
const TILE: u32 = 16;

/// Renders the image. `progress` is called after each tile with the number of samples it took
/// (called from worker threads). The result depends only on the scene, settings and seed, not
/// on the number of threads.
pub fn render(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    let mut state = RenderState::new(settings);
    render_passes(
        scene,
        settings,
        &mut state,
        &AtomicBool::new(false),
        progress,
    );
    state.output()
}

/// The accumulated sums of a render in progress: what `--save-state` writes and `--resume`
/// reads. Sample `s` of pixel `p` always uses the random stream `hash(seed, p, s)` and each
/// pixel adds its samples in order, so continuing a state to N samples gives exactly the image of
/// an uninterrupted N-sample render.
#[derive(Clone, Debug)]
pub struct RenderState {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Seed of the random streams.
    pub seed: u64,
    /// Samples per pixel accumulated so far.
    pub spp_done: u32,
    /// Wall-clock time spent sampling so far (all sessions).
    pub time: Duration,
    /// Per-pixel sums of the samples taken in each pixel: the image under importance sampling
    /// (row-major from the top); under splatting the variance (see [`RenderState::output`]),
    /// in the film's tile-major order ([`SplatLayout::tile_major_pixels`]), so that each tile
    /// owns a contiguous slice.
    pub pixels: Vec<PixelStats>,
    /// The splatting film's accumulators, when the render splats
    /// ([`RenderSettings::splats`]).
    pub splat: Option<SplatFilm>,
    /// The light tracer's film (`ptracer`): the sums of its filtered splats, already scaled
    /// so that their sum over batches divided by `spp_done` is the image. `pixels` then holds
    /// per pixel the statistics of the unfiltered batches (see [`crate::ptracer`]).
    pub light: Option<LightFilm>,
}

/// Bytes per pixel of a state file's statistics: two counts (u32) and seven exact sums (i128).
const PIXEL_BYTES: usize = 8 + 7 * 16;

/// Bytes of one exact sum of the splatting or light film.
const SPLAT_SUM_BYTES: usize = 16;

/// First bytes of a state file (and its format version).
const STATE_MAGIC: &[u8; 8] = b"PTSTATE4";

/// First bytes of a light tracer's state file (its film's sums follow the pixels').
const LIGHT_STATE_MAGIC: &[u8; 8] = b"PTLIGHT3";

impl RenderState {
    /// An empty state for `settings` (no samples yet).
    pub fn new(settings: &RenderSettings) -> Self {
        let n = settings.width as usize * settings.height as usize;
        RenderState {
            width: settings.width,
            height: settings.height,
            seed: settings.seed,
            spp_done: 0,
            time: Duration::ZERO,
            pixels: vec![PixelStats::default(); n],
            splat: settings.splats().then(|| {
                // A moment render's squared XYZ follow the image's RGB and alpha.
                SplatFilm::with_squares(
                    SplatLayout::new(
                        &settings.filter.desc,
                        settings.width,
                        settings.height,
                        settings.crop.map_or([0, 0], |c| c.offset),
                        settings.sample_border,
                    ),
                    settings.splat_channels(),
                    4,
                )
            }),
            light: None,
        }
    }

    /// An empty state for the light tracer with `settings` (no batches yet).
    pub fn for_light_paths(settings: &RenderSettings) -> Self {
        RenderState {
            splat: None,
            light: Some(LightFilm::new(
                settings.filter.desc,
                settings.width,
                settings.height,
            )),
            ..RenderState::new(&RenderSettings {
                reconstruction: pt_scene::Reconstruction::Importance,
                moment: false,
                ..settings.clone()
            })
        }
    }

    /// The image so far (its `spp` is `spp_done`). Under splatting the mean is the splatting
    /// film's and the variance is that of each pixel's own samples' mean (sample variance /
    /// spp): the variance per pixel of the mean of a region larger than the filter, which is
    /// what block tests need (a region's splatted mean averages about as many samples as its
    /// pixels took), and more than a single splatted pixel's variance, which shares samples
    /// with its neighbours.
    pub fn output(&self) -> RenderOutput {
        let variance: Vec<[f32; 3]> = self
            .pixels
            .iter()
            .map(PixelStats::variance_of_mean)
            .collect();
        let mut second_moment = None;
        if let Some(light) = &self.light {
            let n = f64::from(self.spp_done.max(1));
            return RenderOutput {
                width: self.width,
                height: self.height,
                mean: (0..light.sums.len()).map(|i| light.value(i, n)).collect(),
                variance,
                spp: self.spp_done,
                time: self.time,
                nonfinite_samples: self.pixels.iter().map(|p| p.nonfinite as u64).sum(),
                alpha: None,
                second_moment: None,
            };
        }
        let (mean, alpha, variance) = match &self.splat {
            Some(film) => {
                let mut row_major = vec![[0.0; 3]; variance.len()];
                for (v, p) in variance.iter().zip(film.layout.tile_major_pixels()) {
                    row_major[p] = *v;
                }
                let planes = film.planes();
                let triple = |c: usize| -> Vec<[f32; 3]> {
                    (0..planes[c].len())
                        .map(|i| [planes[c][i], planes[c + 1][i], planes[c + 2][i]])
                        .collect()
                };
                second_moment = (planes.len() == 7).then(|| triple(4));
                (triple(0), planes[3].clone(), row_major)
            }
            None => (
                self.pixels.iter().map(PixelStats::mean).collect(),
                self.pixels.iter().map(PixelStats::mean_alpha).collect(),
                variance,
            ),
        };
        RenderOutput {
            width: self.width,
            height: self.height,
            mean,
            variance,
            spp: self.spp_done,
            time: self.time,
            nonfinite_samples: self.pixels.iter().map(|p| p.nonfinite as u64).sum(),
            alpha: Some(alpha),
            second_moment,
        }
    }

    /// Adds the sums of `other`, a state of the same render with other sample indices (another
    /// [`Share`]): exact, so that shares merged in any order give the whole render's sums bit
    /// for bit (the light tracer's film is exact too).
    pub fn merge(&mut self, other: &RenderState) -> Result<(), String> {
        if (self.width, self.height, self.seed) != (other.width, other.height, other.seed) {
            return Err(format!(
                "a state of seed {} at {}x{} cannot join one of seed {} at {}x{}",
                other.seed, other.width, other.height, self.seed, self.width, self.height
            ));
        }
        match (&mut self.light, &other.light) {
            (Some(a), Some(b)) if (a.width, a.height) == (b.width, b.height) => a.merge(b),
            (None, None) => {}
            _ => return Err("the states were rendered by different methods".into()),
        }
        match (&mut self.splat, &other.splat) {
            (Some(a), Some(b)) if a.layout == b.layout && a.channels == b.channels => a.merge(b),
            (None, None) => {}
            _ => return Err("the states were rendered with different films".into()),
        }
        for (a, b) in self.pixels.iter_mut().zip(&other.pixels) {
            a.merge(b);
        }
        self.spp_done += other.spp_done;
        self.time += other.time;
        Ok(())
    }

    /// Serialises the state (little-endian; the sums as f64 bit patterns, so a resumed render
    /// continues from exactly these values). `scene_key` identifies the scene and settings the
    /// state belongs to (checked by [`RenderState::from_bytes`]).
    pub fn to_bytes(&self, scene_key: u64) -> Vec<u8> {
        let mut b = Vec::with_capacity(48 + self.pixels.len() * PIXEL_BYTES);
        b.extend_from_slice(if self.light.is_some() {
            LIGHT_STATE_MAGIC
        } else {
            STATE_MAGIC
        });
        for v in [
            scene_key,
            self.seed,
            u64::from(self.width),
            u64::from(self.height),
            u64::from(self.spp_done),
            self.time.as_nanos() as u64,
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for p in &self.pixels {
            b.extend_from_slice(&p.n.to_le_bytes());
            b.extend_from_slice(&p.nonfinite.to_le_bytes());
            for v in p.sum {
                b.extend_from_slice(&v.to_le_bytes());
            }
            for v in p.sum_sq {
                b.extend_from_slice(&v.to_le_bytes());
            }
            b.extend_from_slice(&p.alpha.to_le_bytes());
        }
        for t in self.splat.iter().flat_map(|f| &f.tiles) {
            for v in &t.sums {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        if let Some(f) = &self.light {
            for v in f.sums.iter().flatten().chain(f.camera.iter().flatten()) {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        b
    }

    /// Reads a state written by [`RenderState::to_bytes`] for the same `scene_key`, seed and
    /// image size; a message saying what does not match otherwise.
    pub fn from_bytes(
        bytes: &[u8],
        scene_key: u64,
        settings: &RenderSettings,
    ) -> Result<RenderState, String> {
        let header = 8 + 6 * 8;
        if bytes.len() < header || (&bytes[..8] != STATE_MAGIC && &bytes[..8] != LIGHT_STATE_MAGIC)
        {
            return Err("not a pt render state (wrong magic number or truncated header)".into());
        }
        let light_paths = &bytes[..8] == LIGHT_STATE_MAGIC;
        let u = |i: usize| {
            u64::from_le_bytes(bytes[8 + 8 * i..16 + 8 * i].try_into().expect("8 bytes"))
        };
        let (key, seed, w, h, spp_done, nanos) = (u(0), u(1), u(2), u(3), u(4), u(5));
        if key != scene_key {
            return Err(
                "the state belongs to a different scene or different render settings".into(),
            );
        }
        if seed != settings.seed
            || w != u64::from(settings.width)
            || h != u64::from(settings.height)
        {
            return Err(format!(
                "the state is for seed {seed} at {w}x{h}, this render is seed {} at {}x{}",
                settings.seed, settings.width, settings.height
            ));
        }
        let n = (w * h) as usize;
        // The splatting film's layout follows from the settings (filter, crop, border).
        let empty = if light_paths {
            RenderState::for_light_paths(settings)
        } else {
            RenderState::new(settings)
        };
        let (mut splat, mut light) = (empty.splat, empty.light);
        let splat_sums: usize = splat
            .iter()
            .flat_map(|f| &f.tiles)
            .map(|t| t.sums.len())
            .sum();
        let light_sums = light
            .as_ref()
            .map_or(0, |f| f.sums.len() * 3 + f.camera.len() * 4);
        let expected = header + n * PIXEL_BYTES + (splat_sums + light_sums) * SPLAT_SUM_BYTES;
        if bytes.len() != expected {
            return Err(format!(
                "the state has {} bytes, a {w}x{h} render with this film needs {expected} (truncated, or saved with another reconstruction or filter)",
                bytes.len(),
            ));
        }
        let mut pixels = Vec::with_capacity(n);
        for k in 0..n {
            let o = header + k * PIXEL_BYTES;
            let u32_at =
                |i: usize| u32::from_le_bytes(bytes[o + i..o + i + 4].try_into().expect("4 bytes"));
            let f = |i: usize| {
                i128::from_le_bytes(
                    bytes[o + 8 + 16 * i..o + 24 + 16 * i]
                        .try_into()
                        .expect("16 bytes"),
                )
            };
            pixels.push(PixelStats {
                n: u32_at(0),
                nonfinite: u32_at(4),
                sum: [f(0), f(1), f(2)].map(ExactSum),
                sum_sq: [f(3), f(4), f(5)].map(ExactSum),
                alpha: ExactSum(f(6)),
            });
        }
        let mut o = header + n * PIXEL_BYTES;
        for t in splat.iter_mut().flat_map(|f| &mut f.tiles) {
            for v in t.sums.iter_mut() {
                let b16 = bytes[o..o + 16].try_into().expect("16 bytes");
                *v = i128::from_le_bytes(b16);
                o += 16;
            }
        }
        for f in light.iter_mut() {
            for v in f
                .sums
                .iter_mut()
                .flatten()
                .chain(f.camera.iter_mut().flatten())
            {
                let b16 = bytes[o..o + 16].try_into().expect("16 bytes");
                *v = i128::from_le_bytes(b16);
                o += 16;
            }
        }
        Ok(RenderState {
            width: w as u32,
            height: h as u32,
            seed,
            spp_done: spp_done as u32,
            time: Duration::from_nanos(nanos),
            pixels,
            splat,
            light,
        })
    }
}

/// Continues `state` up to `settings.spp` samples per pixel in passes over the whole image,
/// checking `cancel` between passes: when it is set, returns after the current pass, with every
/// pixel holding the same number of samples (`state.spp_done`). Passes start at one sample per
/// pixel and grow fourfold while a pass takes under a quarter of a second, so that a cancel is
/// honoured within about a second. (Each pass ends at a barrier where one core may idle for a
/// tile: doubling from 1 spp, with more passes, cost 3% of the Cornell box's speed at 64 spp.)
/// Splatting renders hold a pass's samples per tile until they are splatted (see
/// [`render_splat_tile`]), so their passes stop growing at [`MAX_SPLAT_PASS`] samples per pixel.
/// Returns whether all samples were taken.
pub fn render_passes(
    scene: &Scene,
    settings: &RenderSettings,
    state: &mut RenderState,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> bool {
    render_passes_saving(scene, settings, state, cancel, None, progress)
}

/// Saves a render in progress every so often (a checkpoint, so that a render killed on a
/// cluster resumes from it instead of starting over).
pub struct Checkpoint<'a> {
    /// Least time between two saves.
    pub every: Duration,
    /// Saves the state (called between passes, so every pixel has `spp_done` samples).
    pub save: &'a (dyn Fn(&RenderState) + Sync),
}

/// The `after_pass` of [`in_passes`] that calls `checkpoint.save` at most every
/// `checkpoint.every` (nothing without a checkpoint).
pub(crate) fn checkpointer<'a>(
    checkpoint: Option<&'a Checkpoint<'a>>,
) -> impl FnMut(&RenderState) + 'a {
    let mut last_save = Instant::now();
    move |state: &RenderState| {
        if let Some(c) = checkpoint {
            if last_save.elapsed() >= c.every {
                (c.save)(state);
                last_save = Instant::now();
            }
        }
    }
}

/// [`render_passes`], calling `checkpoint.save` between passes at most every
/// `checkpoint.every`.
pub fn render_passes_saving(
    scene: &Scene,
    settings: &RenderSettings,
    state: &mut RenderState,
    cancel: &AtomicBool,
    checkpoint: Option<&Checkpoint>,
    progress: &(dyn Fn(u64) + Sync),
) -> bool {
    let mut after_pass = checkpointer(checkpoint);
    let most = if state.splat.is_some() {
        MAX_SPLAT_PASS
    } else {
        u32::MAX
    };
    in_passes(
        state,
        settings.spp,
        cancel,
        &mut after_pass,
        4,
        most,
        |state, samples| match &mut state.splat {
            Some(film) => splat_pass(scene, settings, &mut state.pixels, film, samples, progress),
            None => importance_pass(scene, settings, &mut state.pixels, samples, progress),
        },
    )
}

/// Continues `state` up to `spp` samples per pixel in passes: `pass(state, samples)` takes
/// the samples `samples` of every pixel; `cancel` is checked between passes (returns false
/// when it was set, with every pixel at `state.spp_done`). Passes start at one sample per
/// pixel and grow by `growth` while a pass takes under a quarter of a second, up to `most`,
/// so that a cancel is honoured within about a second; `after_pass(state)` is called after
/// each pass but the last. The one pass schedule of every sampling method.
pub(crate) fn in_passes(
    state: &mut RenderState,
    spp: u32,
    cancel: &AtomicBool,
    after_pass: &mut dyn FnMut(&RenderState),
    growth: u32,
    most: u32,
    mut pass: impl FnMut(&mut RenderState, std::ops::Range<u32>),
) -> bool {
    let mut size = 1u32;
    while state.spp_done < spp {
        if cancel.load(Ordering::Relaxed) {
            return false;
        }
        let samples = state.spp_done..state.spp_done.saturating_add(size).min(spp);
        let start = Instant::now();
        let end = samples.end;
        pass(state, samples);
        let took = start.elapsed();
        state.time += took;
        state.spp_done = end;
        if end < spp {
            after_pass(state);
        }
        if took < Duration::from_millis(250) {
            size = size.saturating_mul(growth).min(most.max(1));
        }
    }
    true
}

/// The wavelengths shared by every path of iteration `it` (the photon mappers and `vcm`,
/// whose paths from the camera and from the lights must meet at the same wavelengths; RGB
/// mode: the fixed set). The hero's uniform number is the base-2 radical inverse of `it`
/// rotated by a number drawn from `seed` (Cranley-Patterson): uniform in every iteration, so
/// the image stays unbiased, and spread evenly over the first iterations, so that the few
/// wavelength sets a render of N iterations gets cover the spectrum as N stratified draws
/// would, where independent draws left the colour of a whole image off by several percent
/// at 32 iterations.
pub(crate) fn iteration_wavelengths(scene: &Scene, seed: u64, it: u32) -> SampledWavelengths {
    match scene.mode {
        ColorMode::Rgb => SampledWavelengths::sample_visible(0.5),
        ColorMode::Spectral => {
            /// The key of the rotation's random stream.
            const ROTATION: u64 = (1 << 63) | 0x5741_5645; // "WAVE"
            let rotation = Sampler::new(seed, ROTATION, 0).next_1d();
            let inverse = (it.reverse_bits() as f64 / 4_294_967_296.0) as f32;
            let u = (inverse + rotation).fract();
            SampledWavelengths::sample_visible(u.min(1.0 - f32::EPSILON))
        }
    }
}

/// Largest pass of a splatting render, samples per pixel: a tile then holds at most
/// 16 x 16 x 256 samples of 24 bytes (1.6 MB) per thread.
const MAX_SPLAT_PASS: u32 = 256;

/// One pass of filter importance sampling: samples `samples` of every pixel.
fn importance_pass(
    scene: &Scene,
    settings: &RenderSettings,
    pixels: &mut [PixelStats],
    samples: std::ops::Range<u32>,
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
    pixels
        .par_chunks_mut((w * rows) as usize)
        .enumerate()
        .for_each(|(b, band)| {
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
/// with `sample_border`, its border's), rayon over the film's tiles (each owns its
/// accumulator and the contiguous slice of tile-major statistics of its origins).
fn splat_pass(
    scene: &Scene,
    settings: &RenderSettings,
    pixels: &mut [PixelStats],
    film: &mut SplatFilm,
    samples: std::ops::Range<u32>,
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
    jobs.into_par_iter().for_each(|(i, j, stats, acc)| {
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

/// Renders one tile: takes its samples and adds them to `target`.
///
/// On x86-64 processors with AVX2, FMA and BMI (x86-64-v3: Intel since 2013, AMD since 2015)
/// the same code runs compiled for those instructions, chosen at run time so that the binary
/// still runs on any x86-64: [`render_tile_v3`]. The path integrator and the BSDF and light
/// routines it calls are inlined into it (`#[inline(always)]`), since a function compiled
/// separately keeps the baseline instructions. Images are bit-identical either way: Rust never
/// fuses a multiply and an add on its own, and glam and libm pick their code paths the same way
/// in both. Cornell box, 256x256, 64 spp, 2 threads: 1.71 -> 2.02 M samples/s (+18%, as much
/// as building everything with `-C target-cpu=x86-64-v3`; AVX-512, `target-cpu=native` on this
/// project's machine, gave only +6%).
fn render_tile(scene: &Scene, settings: &RenderSettings, target: Target, tile: &Tile) {
    #[cfg(target_arch = "x86_64")]
    if pt_render::has_x86_64_v3() {
        // SAFETY: the processor supports every feature `render_tile_v3` is compiled for.
        #[allow(unsafe_code)]
        return unsafe { render_tile_v3(scene, settings, target, tile) };
    }
    render_tile_portable(scene, settings, target, tile)
}

/// [`render_tile_portable`] compiled for x86-64-v3 (AVX2, FMA, BMI1/2, LZCNT, POPCNT, MOVBE).
/// Callers must check [`pt_render::has_x86_64_v3`] first (calling it is `unsafe` for that reason).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,movbe")]
fn render_tile_v3(scene: &Scene, settings: &RenderSettings, target: Target, tile: &Tile) {
    render_tile_portable(scene, settings, target, tile)
}

/// The body of [`render_tile`], inlined into each instruction-set variant.
#[inline(always)]
fn render_tile_portable(scene: &Scene, settings: &RenderSettings, target: Target, tile: &Tile) {
    match target {
        Target::Pixels(band) => {
            for y in tile.y0..tile.y1 {
                let row = &mut band[((y - tile.y0) as u32 * settings.width) as usize..]
                    [..settings.width as usize];
                trace_row(scene, settings, y, tile, false, &mut PixelRow(row));
            }
        }
        Target::Splat { stats, acc } => render_splat_tile(scene, settings, tile, stats, acc),
    }
}

/// A splatting tile: traces the samples of every origin pixel of `tile` (adding them to the
/// variance statistics of the origins inside the image), then splats them into `acc` sample
/// index first, origin pixel (row-major) second, so that the order in which each pixel's sums
/// grow does not depend on how samples were split into passes.
#[inline(always)]
fn render_splat_tile(
    scene: &Scene,
    settings: &RenderSettings,
    tile: &Tile,
    stats: &mut [PixelStats],
    acc: &mut SplatTile,
) {
    let (w, h) = (settings.width as i32, settings.height as i32);
    let tw = (tile.x1 - tile.x0) as usize;
    let ns = tile.samples.len();
    let s0 = tile.samples.start;
    // Per origin pixel (row-major) its samples in order: position in the pixel ([0, 1)^2),
    // linear RGB and alpha.
    let mut taken = vec![(Vec2::ZERO, [0.0f32; 3], 0.0f32); tw * (tile.y1 - tile.y0) as usize * ns];
    for y in tile.y0..tile.y1 {
        // The row's statistics (the tile's origins inside the image, from column ix0).
        let (ix0, ix1) = (tile.x0.max(0), tile.x1.min(w));
        let iy0 = tile.y0.max(0);
        let row = ((0..h).contains(&y) && ix0 < ix1).then(|| {
            let start = ((y - iy0) * (ix1 - ix0)) as usize;
            &mut stats[start..start + (ix1 - ix0) as usize]
        });
        let mut sink = SplatRow {
            taken: &mut taken,
            first: (y - tile.y0) as usize * tw,
            x0: tile.x0,
            samples: s0,
            per_origin: ns,
            stats: row,
            inside: ix0..ix1,
        };
        trace_row(scene, settings, y, tile, true, &mut sink);
    }
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

/// Receives the samples of [`trace_row`]. A trait rather than a closure so that `put` is
/// inlined into the render loop and compiled for its instruction sets ([`render_tile`]): an
/// outlined closure is compiled for the baseline, where the film's exact sums cost more.
trait SampleSink {
    /// Sample `k` of pixel `x`: linear RGB radiance, alpha (0 or 1), film offset from the
    /// pixel's centre, film weight.
    fn put(&mut self, x: i32, k: u32, rgb: [f32; 3], alpha: f32, offset: Vec2, weight: f32);
}

/// Filter importance sampling: each sample into its own pixel of the row.
struct PixelRow<'a>(&'a mut [PixelStats]);

impl SampleSink for PixelRow<'_> {
    #[inline(always)]
    fn put(&mut self, x: i32, _: u32, rgb: [f32; 3], alpha: f32, _: Vec2, w: f32) {
        self.0[x as usize].add(rgb.map(|c| c * w), alpha * w);
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
}

impl SampleSink for SplatRow<'_> {
    #[inline(always)]
    fn put(&mut self, x: i32, k: u32, rgb: [f32; 3], alpha: f32, offset: Vec2, _: f32) {
        let q = self.first + (x - self.x0) as usize;
        // Exact: the offset is u - 1/2 for u a multiple of 2^-24 in [0, 1).
        self.taken[q * self.per_origin + (k - self.samples) as usize] =
            (offset + Vec2::splat(0.5), rgb, alpha);
        if let Some(r) = self.stats.as_deref_mut() {
            if self.inside.contains(&x) {
                r[(x - self.inside.start) as usize].add(rgb, alpha);
            }
        }
    }
}

/// Traces samples `tile.samples` of pixels `tile.x0..tile.x1` of row `y` and hands each
/// result to `sink`, pixel by pixel, each pixel's in sample order.
/// `splat`: the sample's position is uniform in its pixel (weight 1; the film weighs it),
/// else it is drawn from the filter ([`sample_pixel_offset`]).
#[inline(always)]
fn trace_row(
    scene: &Scene,
    settings: &RenderSettings,
    y: i32,
    tile: &Tile,
    splat: bool,
    sink: &mut impl SampleSink,
) {
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
    sink: &mut impl SampleSink,
    new_sampler: impl Fn(u64, u64) -> S,
) {
    if samples.is_empty() || xs.is_empty() {
        return;
    }
    let spectral = scene.mode == ColorMode::Spectral;
    let rgb_lambda = *rgb_lambda;
    // The next sample to start, as (pixel x, sample index); `x == xs.end` when all are started.
    let (mut x, mut k) = (xs.start, samples.start);
    while x < xs.end {
        let (chunk_x, chunk_k) = (x, k);
        let mut results = [([0.0f32; 3], 0.0f32); SAMPLE_CHUNK as usize];
        // Each sample's film offset and weight (1 but for filters with negative lobes).
        let mut offsets = [(Vec2::ZERO, 1.0f32); SAMPLE_CHUNK as usize];
        let mut taken = 0u32;
        let start = || {
            if taken == SAMPLE_CHUNK || x >= xs.end {
                return None;
            }
            let pixel = settings.pixel_key(x, y);
            let mut sampler = new_sampler(pixel, u64::from(settings.share.sample(k)));
            let lambda = if spectral {
                SampledWavelengths::sample_visible(sampler.next_1d())
            } else {
                rgb_lambda
            };
            let (offset, weight) = if splat {
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
            let ray = scene.camera.sample_ray(x, y, offset, || sampler.next_2d());
            let path = PathState::new(scene, ray, &lambda);
            let tag = taken;
            offsets[tag as usize] = (offset, weight);
            taken += 1;
            k += 1;
            if k == samples.end {
                (x, k) = (x + 1, samples.start);
            }
            Some(PathStart {
                path,
                sampler,
                lambda,
                tag,
            })
        };
        let finish = |done: &PathStart<S>| {
            let l = done.path.radiance;
            let rgb = if spectral {
                spectrum_to_srgb(l, &done.lambda)
            } else {
                l.rgb()
            };
            let rgb = match settings.clamp {
                Some(c) => clamp_sample(rgb, c),
                None => rgb,
            };
            let alpha = f32::from(u8::from(done.path.covered));
            results[done.tag as usize] = (rgb, alpha);
        };
        trace_paths(scene, &settings.path, start, finish);
        // The chunk's results, in the order they were started: pixel by pixel, each in sample
        // order.
        let (mut px, mut pk) = (chunk_x, chunk_k);
        for ((rgb, alpha), (offset, w)) in results[..taken as usize].iter().zip(&offsets) {
            sink.put(px, pk, *rgb, *alpha, *offset, *w);
            pk += 1;
            if pk == samples.end {
                (px, pk) = (px + 1, samples.start);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_render::{BvhKind, LightSelection};

    /// The shares of a split render take every sample index exactly once, interleaved, and
    /// their sample counts are what `samples_of` says.
    #[test]
    fn shares_take_every_sample_once() {
        for spp in [1, 2, 7, 64, 1000] {
            for count in [1, 2, 3, 4, 8, 13] {
                let mut seen = vec![0u32; spp as usize];
                for index in 0..count {
                    let share = Share { index, count };
                    for local in 0..share.samples_of(spp) {
                        seen[share.sample(local) as usize] += 1;
                    }
                }
                assert!(seen.iter().all(|&n| n == 1), "spp {spp}, {count} shares");
            }
        }
        assert_eq!(Share::WHOLE.samples_of(5), 5);
        assert_eq!(Share { index: 2, count: 4 }.sample(3), 14);
    }

    /// The x86-64-v3 variant of the render loop must give exactly the portable variant's pixel
    /// sums (the same arithmetic compiled with other instructions), on scenes that together use
    /// every BSDF family, textures, spectral mode, fluorescence and media. A difference in any
    /// bit of any sum fails it (what fused multiply-adds or a different libm path would cause).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn v3_variant_matches_portable_bit_for_bit() {
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
            render_tile_portable(&scene, &settings, Target::Pixels(&mut portable), &tile);
            #[allow(unsafe_code)]
            // SAFETY: checked above that the processor has the features.
            unsafe {
                render_tile_v3(&scene, &settings, Target::Pixels(&mut v3), &tile)
            };
            // The exact sums hold every f32 sample above 2^-33 to its last bit.
            assert!(portable == v3, "{name}: the x86-64-v3 variant differs");
            assert!(
                portable.iter().any(|p| p.sum.iter().any(|s| s.0 > 0)),
                "{name}: the tile is black, the test checks nothing"
            );
        }
    }
}
