//! The method failure atlas (`pt atlas`): where each rendering method fails, by numbers.
//!
//! Four studies, each a scene (or family of scenes) written for this project under
//! `scenes/atlas/` (embedded in `studies.rs`), rendered by competing methods and compared region by region
//! with a Mitsuba 3 reference (`references/atlas/NAME.exr` and `NAME_var.exr`, made by
//! `references/make_references.py scenes/atlas/NAME.xml`). When a reference file is missing, a
//! long MIS render by pt itself (other seed) stands in, and the report says so.
//!
//! 1. **Veach** (`veach-mis.xml`, in the style of Veach 1997, thesis fig. 9.2): four glossy
//!    plates of increasing roughness (rows) lit by four spherical lights of increasing size and
//!    equal power (columns), direct light only; BSDF sampling, light sampling and MIS.
//! 2. **Caustic** (`caustic-r*.xml`): a glass sphere on a diffuse floor under one spherical light
//!    whose radius goes from 0.01 to 1 (two decades) at equal power; regions: the caustic (a fixed
//!    rectangle around the focused spot) and the rest of the image.
//! 3. **Radiosity** (`radiosity-glossy.xml`): a box lit by its whole ceiling whose back wall is a
//!    diffuse strip and five GGX strips of alpha 0.5 to 0.01, each with albedo 0.5 at the camera's
//!    view; `pt-radiosity` (which substitutes grey diffuse 0.5 for every non-diffuse material)
//!    against path tracing.
//! 4. **Transport** (`scenes/caustic-sphere-light.xml`, `scenes/caustic-point-light.xml`): a
//!    glass ball in the Cornell box focuses a small sphere light or a point light onto the red
//!    wall; path tracing (MIS), light tracing (`ptracer`) and photon mapping (`sppm`), against
//!    Mitsuba's `ptracer` references, in the caustic and on the walls (the ball itself, which a
//!    light tracer cannot show, is left out).
//!
//! **Budget.** By default the methods get **equal time**: MIS renders `--spp` samples per pixel
//! and its wall time `T` is the budget of the other strategies, which render in steps (1 spp,
//! then as many samples as the measured time per sample says fit in what is left of `T`, until
//! no further sample fits), so their sample counts come out of the measurement. Seeds are fixed
//! (each sample has its own random stream), so a run is reproducible up to the sample counts
//! that timing gives. In the radiosity study the path tracer gets the radiosity run's wall time
//! (meshing, form factors, solve and display). [`Equal::Spp`] gives every method
//! [`AtlasSettings::spp`] samples instead (deterministic; the times are still reported).
//!
//! **Error.** Per region, the relative RMSE of luminance, `sqrt(sum (I - R)^2 / sum R^2)` over its
//! pixels. The reference's own noise in the same units, `sqrt(sum var(R) / sum R^2)`, is reported
//! beside it (it adds in quadrature to every error: an error near it is at the reference's noise
//! floor). The luminance variance of a reference pixel is bounded by `(sum_c w_c sd_c)^2`
//! (channels fully correlated, as they are for grey materials under a white light).
//!
//! [`study`] runs one study and returns a [`Study`] (errors per method and region), which
//! writes its report section ([`Study::report`]) and its chart ([`Study::write_charts`]).

mod report;
mod studies;
#[cfg(test)]
mod tests;

pub use studies::{caustic, radiosity, transport, veach, CAUSTIC, TRANSPORT};

use crate::{LabError, Result};
use pt_image::fireflies::luminance;
use pt_integrators::{RenderSettings, RenderState, Strategy};
use pt_render::{BvhKind, LightSelection, RenderOutput, Scene};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// Seed of the method renders; the fallback references use another one so that their noise is
/// independent.
const SEED: u64 = 7;
const FALLBACK_SEED: u64 = 1_000_003;

/// What the competing methods get the same of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Equal {
    /// Equal wall time: the time MIS (or radiosity) needed.
    Time,
    /// Equal samples per pixel ([`AtlasSettings::spp`]).
    Spp,
}

/// A study of the atlas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    /// Plates x lights, BSDF / light / MIS (Veach).
    Veach,
    /// Glass sphere under lights of decreasing size.
    Caustic,
    /// Radiosity on glossy strips.
    Radiosity,
    /// A caustic behind glass: path tracing, light tracing and photon mapping.
    Transport,
}

impl Which {
    /// `pt atlas`' samples per pixel of MIS for the study: 64 for veach and radiosity, 1024 for
    /// caustic, where fewer samples find no caustic at all under the smallest light.
    pub fn default_spp(self) -> u32 {
        match self {
            Which::Caustic => 1024,
            Which::Transport => 256,
            Which::Veach | Which::Radiosity => 64,
        }
    }
}

/// Options of a study run.
#[derive(Clone, Debug)]
pub struct AtlasSettings {
    /// Equal time or equal spp.
    pub equal: Equal,
    /// MIS samples per pixel (with [`Equal::Spp`], every method's; in the radiosity study the
    /// path tracer's).
    pub spp: u32,
    /// Folder of the Mitsuba references (`NAME.exr` and `NAME_var.exr`).
    pub references: PathBuf,
    /// Render size divisor (1: the scene's size; tests use 2).
    pub shrink: u32,
    /// Samples per pixel of a fallback reference (pt MIS), where a Mitsuba one is missing.
    pub fallback_spp: u32,
}

/// The study `which` (on the current rayon pool; the caustic study over all light radii).
pub fn study(which: Which, s: &AtlasSettings) -> Result<Study> {
    match which {
        Which::Veach => veach(s),
        Which::Caustic => caustic(s, &[0, 1, 2, 3, 4]),
        Which::Radiosity => radiosity(s),
        Which::Transport => transport(s),
    }
}

/// Checks the settings (every study does first).
fn check(s: &AtlasSettings) -> Result<()> {
    if s.spp == 0 || s.shrink == 0 || s.fallback_spp == 0 {
        return Err(LabError::Invalid(
            "spp, shrink and fallback_spp must be at least 1".into(),
        ));
    }
    Ok(())
}

/// The title and introduction of `report.md`, before the studies' sections.
pub fn report_header() -> String {
    "# Method failure atlas\n\nWhere each rendering method fails, measured: per-region error against a reference. \
     Made by `pt atlas` (see `crates/pt-lab/src/atlas/`).\n\n"
        .to_string()
}

/// A method's budget.
#[derive(Clone, Copy, Debug)]
pub enum Budget {
    /// This many samples per pixel.
    Spp(u32),
    /// As many samples per pixel as fit in this wall time.
    Time(Duration),
}

/// Renders with `settings` (its `spp` ignored) within `budget`. For a time budget: one sample
/// per pixel, then steps of as many samples as the time per sample measured so far says fit in
/// the rest (at most 4x the samples so far, so one slow estimate cannot overshoot far), until
/// not one more sample fits. The image is that of a plain render at the final sample count.
pub fn render_within(scene: &Scene, settings: &RenderSettings, budget: Budget) -> RenderOutput {
    render_steps(
        settings,
        budget,
        RenderState::new(settings),
        |rs: &RenderSettings, state: &mut RenderState| {
            pt_integrators::render_passes(scene, rs, state, &AtomicBool::new(false), &|_| {});
        },
    )
}

/// [`render_within`] for any method whose renders continue a [`RenderState`]: `advance` takes
/// `state` to `settings.spp` samples (light paths per pixel, iterations).
pub fn render_steps(
    settings: &RenderSettings,
    budget: Budget,
    mut state: RenderState,
    advance: impl Fn(&RenderSettings, &mut RenderState),
) -> RenderOutput {
    let at = |spp: u32| RenderSettings {
        spp,
        ..settings.clone()
    };
    match budget {
        Budget::Spp(n) => advance(&at(n.max(1)), &mut state),
        Budget::Time(t) => {
            let budget = t.as_secs_f64();
            let mut target = 1u32;
            loop {
                advance(&at(target), &mut state);
                let used = state.time.as_secs_f64();
                let per_spp = used / f64::from(state.spp_done);
                let fit = ((budget - used) / per_spp).floor();
                if fit.is_nan() || fit < 1.0 {
                    break;
                }
                target = state.spp_done + (fit as u32).min(4 * state.spp_done);
            }
        }
    }
    state.output()
}

/// A reference image with the variance of its pixel means.
pub struct Reference {
    /// Mean radiance, row-major from the top.
    pub mean: Vec<[f32; 3]>,
    /// Variance of each pixel mean, per channel.
    pub var: Vec<[f32; 3]>,
    /// Where it came from (for the report).
    pub source: String,
}

/// Averages `k x k` blocks of a `w x h` image (`k` divides both): a box-filtered pixel of the
/// small image is exactly the mean of the `k^2` box-filtered pixels it covers. Variances of
/// the means of independent pixels: the sum over `k^4`.
fn downsample(v: &[[f32; 3]], w: u32, k: u32, variance: bool) -> Vec<[f32; 3]> {
    let (sw, sh) = (w / k, v.len() as u32 / w / k);
    let norm = if variance {
        (k * k * k * k) as f32
    } else {
        (k * k) as f32
    };
    let mut out = vec![[0.0f32; 3]; (sw * sh) as usize];
    for y in 0..sh * k {
        for x in 0..sw * k {
            let p = v[(y * w + x) as usize];
            let o = &mut out[((y / k) * sw + x / k) as usize];
            for c in 0..3 {
                o[c] += p[c] / norm;
            }
        }
    }
    out
}

/// The Mitsuba reference `dir/name.exr` (+ `_var.exr`) at the size of `settings` (box-downsampled
/// by an integer factor if the reference is larger), or else a pt MIS render at `fallback_spp`.
pub fn reference(
    dir: &Path,
    name: &str,
    scene: &Scene,
    settings: &RenderSettings,
    fallback_spp: u32,
) -> Result<Reference> {
    let (mp, vp) = (
        dir.join(format!("{name}.exr")),
        dir.join(format!("{name}_var.exr")),
    );
    let (w, h) = (settings.width, settings.height);
    if mp.is_file() && vp.is_file() {
        let read = |p: &Path, what: &str| {
            pt_image::read_exr(p).map_err(|e| {
                LabError::from(e).context(format!("cannot read the {what} '{}'", p.display()))
            })
        };
        let (m, _) = read(&mp, "reference")?;
        let (v, _) = read(&vp, "reference variance")?;
        if (v.width, v.height) != (m.width, m.height) {
            return Err(LabError::Invalid(format!(
                "'{}' is {}x{} but '{}' is {}x{}",
                vp.display(),
                v.width,
                v.height,
                mp.display(),
                m.width,
                m.height
            )));
        }
        let k = m.width / w.max(1);
        if k >= 1 && m.width == k * w && m.height == k * h {
            return Ok(Reference {
                mean: downsample(&m.data, m.width, k, false),
                var: downsample(&v.data, m.width, k, true),
                source: format!(
                    "Mitsuba 3 (`{}`{})",
                    mp.display(),
                    if k > 1 {
                        format!(", averaged over {k}x{k} pixels")
                    } else {
                        String::new()
                    }
                ),
            });
        }
        return Err(LabError::Invalid(format!(
            "the reference '{}' is {}x{}, not a multiple of the {w}x{h} render",
            mp.display(),
            m.width,
            m.height
        )));
    }
    let s = RenderSettings {
        seed: FALLBACK_SEED,
        path: pt_integrators::PathSettings {
            strategy: Strategy::Mis,
            ..settings.path
        },
        ..settings.clone()
    };
    let out = render_within(scene, &s, Budget::Spp(fallback_spp));
    Ok(Reference {
        mean: out.mean,
        var: out.variance,
        source: format!(
            "pt's own MIS render at {fallback_spp} spp (no Mitsuba reference `{}`)",
            mp.display()
        ),
    })
}

/// Relative RMSE of luminance of `img` against `r` over `pixels`, and the reference's own noise
/// in the same units (see the module doc).
pub fn region_error(img: &[[f32; 3]], r: &Reference, pixels: &[usize]) -> (f64, f64) {
    const W: [f64; 3] = [0.2126, 0.7152, 0.0722]; // Rec.709 luminance weights, as `luminance`
    let (mut se, mut s2, mut sv) = (0.0f64, 0.0f64, 0.0f64);
    for &i in pixels {
        let (a, b) = (
            f64::from(luminance(img[i])),
            f64::from(luminance(r.mean[i])),
        );
        se += (a - b) * (a - b);
        s2 += b * b;
        let sd: f64 = (0..3)
            .map(|c| W[c] * f64::from(r.var[i][c].max(0.0)).sqrt())
            .sum();
        sv += sd * sd;
    }
    let d = s2.max(1e-30);
    ((se / d).sqrt(), (sv / d).sqrt())
}

/// Mean of `img` over `pixels` divided by the reference's, minus 1 (luminance).
fn mean_bias(img: &[[f32; 3]], r: &Reference, pixels: &[usize]) -> f64 {
    let (a, b) = pixels.iter().fold((0.0f64, 0.0f64), |(a, b), &i| {
        (
            a + f64::from(luminance(img[i])),
            b + f64::from(luminance(r.mean[i])),
        )
    });
    a / b.max(1e-30) - 1.0
}

/// Pixel indices of a rectangle (row0, row1, col0, col1; half-open) in a `w`-wide image.
fn rect(w: u32, r: (u32, u32, u32, u32)) -> Vec<usize> {
    (r.0..r.1)
        .flat_map(|y| (r.2..r.3).map(move |x| (y * w + x) as usize))
        .collect()
}

/// One method's panel of a study: its error per region.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Method name.
    pub name: String,
    /// Error per region, [row][column] (relative, 0.1 = 10%).
    pub cells: Vec<Vec<f64>>,
    /// Samples per pixel per column (one render per column, or the same for all).
    pub spp: Vec<u32>,
    /// Wall time per column, seconds.
    pub secs: Vec<f64>,
}

impl Panel {
    /// Panels named `names` with `rows` empty rows each, for studies that fill them a column
    /// (a scene) at a time.
    fn empty<'a>(names: impl Iterator<Item = &'a str>, rows: usize) -> Vec<Panel> {
        names
            .map(|n| Panel {
                name: n.to_string(),
                cells: vec![Vec::new(); rows],
                spp: Vec::new(),
                secs: Vec::new(),
            })
            .collect()
    }
}

/// A study: methods x regions, with the reference's own noise per region.
#[derive(Clone, Debug)]
pub struct Study {
    /// File stem of the figure (`atlas-KEY.svg`).
    pub key: &'static str,
    /// Section title.
    pub title: String,
    /// What the rows are (e.g. "plate alpha").
    pub row_label: String,
    /// What the columns are (e.g. "light radius").
    pub col_label: String,
    /// Row labels, top to bottom.
    pub rows: Vec<String>,
    /// Column labels, left to right.
    pub cols: Vec<String>,
    /// One panel per method.
    pub panels: Vec<Panel>,
    /// The reference's own relative noise per region, [row][column] (NaN where not meaningful).
    pub ref_noise: Vec<Vec<f64>>,
    /// Markdown paragraph: scene, budget, reference, reading.
    pub text: String,
}

/// Loads an embedded atlas scene with its film size divided by `shrink` (the camera is built
/// for the film size, so this happens before the scene is built).
fn load(
    xml: &str,
    name: &str,
    shrink: u32,
) -> Result<(Scene, RenderSettings, pt_scene::SceneDesc)> {
    let mut desc = pt_scene::load_str(
        xml,
        Path::new(&format!("scenes/atlas/{name}.xml")),
        Path::new("."),
        &[],
    )?;
    desc.film.width /= shrink;
    desc.film.height /= shrink;
    let scene = Scene::build(&desc, BvhKind::Auto, LightSelection::Power)?;
    let base = RenderSettings::from_desc(&desc);
    Ok((scene, base, desc))
}

fn with_strategy(base: &RenderSettings, strategy: Strategy) -> RenderSettings {
    RenderSettings {
        seed: SEED,
        path: pt_integrators::PathSettings {
            strategy,
            ..base.path
        },
        ..base.clone()
    }
}

const STRATEGIES: [(&str, Strategy); 3] = [
    ("BSDF sampling", Strategy::Bsdf),
    ("light sampling", Strategy::Light),
    ("MIS", Strategy::Mis),
];

/// Renders MIS at `o.spp`, then BSDF and light sampling at its time (or spp); returns the three
/// outputs in the order of [`STRATEGIES`].
fn three_strategies(scene: &Scene, base: &RenderSettings, o: &AtlasSettings) -> [RenderOutput; 3] {
    let mis = render_within(
        scene,
        &with_strategy(base, Strategy::Mis),
        Budget::Spp(o.spp),
    );
    let budget = match o.equal {
        Equal::Time => Budget::Time(mis.time),
        Equal::Spp => Budget::Spp(o.spp),
    };
    let bsdf = render_within(scene, &with_strategy(base, Strategy::Bsdf), budget);
    let light = render_within(scene, &with_strategy(base, Strategy::Light), budget);
    [bsdf, light, mis]
}

fn budget_words(o: &AtlasSettings) -> String {
    match o.equal {
        Equal::Time => format!(
            "equal time: MIS renders {} spp and the other strategies get its wall time",
            o.spp
        ),
        Equal::Spp => format!("equal samples: {} spp each", o.spp),
    }
}
