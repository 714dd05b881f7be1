//! [`RenderState`]: the sums of a render in progress, merged across shares and saved to and
//! read from a state file.

use super::RenderSettings;
use pt_render::film::exact::ExactSum;
use pt_render::film::light::LightFilm;
use pt_render::film::splat::{SplatFilm, SplatLayout};
use pt_render::film::PixelStats;
use pt_render::RenderOutput;
use std::time::Duration;

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
    /// [`super::Share`]): exact, so that shares merged in any order give the whole render's sums
    /// bit for bit (the light tracer's film is exact too).
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
