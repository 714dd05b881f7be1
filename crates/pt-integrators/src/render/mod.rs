//! The render loop: passes over the image, rayon over tiles, one independent random stream per
//! sample; a render can be cancelled between passes and resumed from its saved sums.

mod state;
#[cfg(test)]
mod tests;
mod tile;

pub use state::RenderState;

use crate::path::PathSettings;
use pt_render::film::Filter;
use pt_render::sampler::{SamplePattern, Sampler};
use pt_render::{RenderOutput, Scene};
use pt_spectrum::{ColorMode, SampledWavelengths};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use tile::{importance_pass, splat_pass};

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
    /// Keep the sums of each pixel's own samples' squares (and, under splatting, of the
    /// samples themselves), the variance of [`RenderOutput::variance`] (and what a saved state
    /// or a part file holds). Without them that variance is zero and each sample costs seven
    /// exact additions less under splatting (`PixelStats::add`, where `PixelStats::count`
    /// only counts it), three less under importance sampling (`PixelStats::add_mean`, which
    /// keeps the sums of values: they are its image); the samples are still counted
    /// (`RenderOutput::nonfinite_samples`). The image is the same either way.
    pub variance: bool,
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
            variance: true,
        }
    }
}

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

/// Continues `state` up to `settings.spp` samples per pixel in passes over the whole image,
/// checking `cancel` between passes: when it is set, returns after the current pass, with every
/// pixel holding the same number of samples (`state.spp_done`). Passes start at one sample per
/// pixel and grow fourfold while a pass takes under a quarter of a second, so that a cancel is
/// honoured within about a second. (Each pass ends at a barrier where one core may idle for a
/// tile: doubling from 1 spp, with more passes, cost 3% of the Cornell box's speed at 64 spp.)
/// Splatting renders hold a pass's samples per tile until they are splatted (see
/// `tile::render_tile_portable`), so their passes stop growing at [`MAX_SPLAT_PASS`] samples
/// per pixel.
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
    // Each tile's (or band's) time in the last pass, which orders the next.
    let mut costs = Vec::new();
    in_passes(
        state,
        settings.spp,
        cancel,
        &mut after_pass,
        4,
        most,
        |state, samples| match &mut state.splat {
            Some(film) => splat_pass(
                scene,
                settings,
                &mut state.pixels,
                film,
                samples,
                &mut costs,
                progress,
            ),
            None => importance_pass(
                scene,
                settings,
                &mut state.pixels,
                samples,
                &mut costs,
                progress,
            ),
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
