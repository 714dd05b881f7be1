//! Method failure atlas: where each direct-lighting strategy fails, by numbers.
//!
//! Scene `scenes/atlas/veach-mis.xml` (embedded; written for this project in the style of
//! Veach 1997, thesis fig. 9.2): four glossy plates of increasing roughness (rows) lit by four
//! spherical lights of increasing size and equal power (columns). It is rendered with BSDF
//! sampling only, light sampling only and MIS (power heuristic) at **equal samples per pixel**
//! (the wall time of each is recorded), and compared with a long MIS render of the same scene
//! by pt itself (the reference; its own noise is `spp / ref_spp` of the tests' variance, 1/64 by
//! default, and shows as a floor of about 1/8 of the MIS error). The error of a region (plate x
//! light) is the relative RMSE of luminance, `sqrt(sum (I - R)^2 / sum R^2)` over its pixels.
//!
//! What it shows (Veach's result, here measured): BSDF sampling fails on rough plates lit by
//! small lights (a sampled direction rarely hits the light), light sampling fails on smooth
//! plates lit by large lights (a point on the light rarely lies in the narrow lobe), MIS is
//! never much worse than the better of the two.

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use pt_image::fireflies::luminance;
use pt_render::{BvhKind, LightSelection, RenderSettings, Scene, Strategy};
use std::fmt::Write as _;
use std::path::Path;

/// The atlas scene (see the module doc).
const VEACH: &str = include_str!("../../scenes/atlas/veach-mis.xml");
/// Plate roughness (GGX alpha), top to bottom, as in the scene file.
const PLATE_ALPHA: [f32; 4] = [0.005, 0.03, 0.1, 0.3];
/// Plate centre heights and tilt angles (degrees), as in the scene file.
const PLATE_Y: [f32; 4] = [1.5, 0.5, -0.5, -1.5];
const PLATE_TILT_DEG: [f32; 4] = [-4.412, -10.383, -16.11, -21.52];
/// Light radii, left to right, as in the scene file.
const LIGHT_RADIUS: [f32; 4] = [0.03, 0.1, 0.3, 0.9];
/// Column bands in world x on the plates: midway between the highlights of neighbouring
/// lights (the mirror image of a light at x_l from the camera at z = 10 with lights at z = 8
/// lies near x = x_l * 10 / 18, so the boundaries are at 0 and +-1.11).
const BANDS_X: [f32; 5] = [-4.0, -1.11, 0.0, 1.11, 4.0];

/// Samples per pixel of the reference (MIS).
pub(crate) const REF_SPP: u32 = 1024;
/// Samples per pixel of each strategy.
pub(crate) const SPP: u32 = 16;

/// The errors of one strategy.
#[derive(Clone, Debug)]
pub(crate) struct StrategyErrors {
    /// Strategy name.
    pub name: &'static str,
    /// Relative RMSE per region, [plate][light].
    pub rel_rmse: [[f64; 4]; 4],
    /// Relative RMSE over the whole image.
    pub whole: f64,
    /// Wall time of the render, seconds.
    pub secs: f64,
}

/// The atlas result.
#[derive(Clone, Debug)]
pub(crate) struct Atlas {
    /// Wall time of the reference, seconds.
    pub ref_secs: f64,
    /// BSDF, light, MIS.
    pub strategies: Vec<StrategyErrors>,
}

/// Pixel rectangles (row0, row1, col0, col1; half-open) of the plate x light regions, from the
/// camera of the scene file (at z = 10 looking down -z, horizontal fov 46 degrees, 128 x 96):
/// a world point (x, y, z) projects to column `W/2 + f x / (10 - z)` and row
/// `H/2 - f y / (10 - z)`, `f = (W/2) / tan(23 deg)`. One pixel is trimmed at each edge so that
/// the plate borders (partly background) stay out.
fn regions(w: u32, h: u32) -> [[(u32, u32, u32, u32); 4]; 4] {
    let f = (w as f32 / 2.0) / 23f32.to_radians().tan();
    let row = |y: f32, z: f32| (h as f32 / 2.0 - f * y / (10.0 - z)).round().clamp(0.0, h as f32) as u32;
    let col = |x: f32| (w as f32 / 2.0 + f * x / 10.0).round().clamp(0.0, w as f32) as u32;
    let mut out = [[(0, 0, 0, 0); 4]; 4];
    for p in 0..4 {
        let a = PLATE_TILT_DEG[p].to_radians();
        // Rotation about x by a maps (0, +-0.4, 0) to (0, +-0.4 cos a, +-0.4 sin a).
        let (top, bottom) = (row(PLATE_Y[p] + 0.4 * a.cos(), 0.4 * a.sin()), row(PLATE_Y[p] - 0.4 * a.cos(), -0.4 * a.sin()));
        for l in 0..4 {
            out[p][l] = (top + 1, bottom.saturating_sub(1), col(BANDS_X[l]) + 1, col(BANDS_X[l + 1]).saturating_sub(1));
        }
    }
    out
}

fn rel_rmse(img: &[[f32; 3]], reference: &[[f32; 3]], w: u32, r: (u32, u32, u32, u32)) -> f64 {
    let (mut se, mut s2) = (0.0f64, 0.0f64);
    for y in r.0..r.1 {
        for x in r.2..r.3 {
            let i = (y * w + x) as usize;
            let (a, b) = (f64::from(luminance(img[i])), f64::from(luminance(reference[i])));
            se += (a - b) * (a - b);
            s2 += b * b;
        }
    }
    (se / s2.max(1e-30)).sqrt()
}

/// Renders the atlas (on the current rayon pool).
pub(crate) fn veach_atlas() -> Result<Atlas> {
    let desc = pt_scene::load_str(VEACH, Path::new("scenes/atlas/veach-mis.xml"), Path::new("."), &[])?;
    let scene = Scene::build(&desc, BvhKind::CwBvh, LightSelection::Power)?;
    let base = RenderSettings::from_desc(&desc);
    let with = |strategy: Strategy, spp: u32, seed: u64| {
        let s = RenderSettings { spp, seed, path: pt_render::PathSettings { strategy, ..base.path }, ..base.clone() };
        pt_render::render(&scene, &s, &|_| {})
    };
    // The reference uses another seed than the tests, so its noise is independent of theirs.
    let reference = with(Strategy::Mis, REF_SPP, 1_000_003);
    let (w, h) = (reference.width, reference.height);
    let regs = regions(w, h);
    let mut strategies = Vec::new();
    for (name, st) in [("BSDF sampling", Strategy::Bsdf), ("light sampling", Strategy::Light), ("MIS", Strategy::Mis)] {
        let out = with(st, SPP, 7);
        let mut e = [[0.0; 4]; 4];
        for p in 0..4 {
            for l in 0..4 {
                e[p][l] = rel_rmse(&out.mean, &reference.mean, w, regs[p][l]);
            }
        }
        let whole = rel_rmse(&out.mean, &reference.mean, w, (0, h, 0, w));
        strategies.push(StrategyErrors { name, rel_rmse: e, whole, secs: out.time.as_secs_f64() });
    }
    Ok(Atlas { ref_secs: reference.time.as_secs_f64(), strategies })
}

/// The report section (Markdown).
pub(crate) fn atlas_report(a: &Atlas) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "## Method failure atlas: BSDF sampling, light sampling and MIS\n");
    let _ = writeln!(
        md,
        "Scene `scenes/atlas/veach-mis.xml` (Veach-style, written for this project): plates of GGX roughness {:?} \
         (rows, top to bottom) lit by spherical lights of radius {:?} and equal power (columns, left to right), direct \
         light only. Each strategy at {SPP} spp; reference: pt's own MIS render at {REF_SPP} spp with another seed \
         ({:.1} s), not Mitsuba. Error: relative RMSE of luminance per plate x light region (the reference's own noise \
         adds about {:.0}% of the MIS error).\n",
        PLATE_ALPHA,
        LIGHT_RADIUS,
        a.ref_secs,
        100.0 * (f64::from(SPP) / f64::from(REF_SPP)).sqrt()
    );
    for s in &a.strategies {
        let _ = writeln!(md, "**{}** ({} spp in {:.2} s; whole image {:.1}%)\n", s.name, SPP, s.secs, 100.0 * s.whole);
        let _ = writeln!(md, "| plate alpha \\ light radius | {} |", LIGHT_RADIUS.map(|r| r.to_string()).join(" | "));
        let _ = writeln!(md, "|---|---|---|---|---|");
        for p in 0..4 {
            let cells: Vec<String> = (0..4).map(|l| format!("{:.1}%", 100.0 * s.rel_rmse[p][l])).collect();
            let _ = writeln!(md, "| {} | {} |", PLATE_ALPHA[p], cells.join(" | "));
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(md, "![failure atlas](atlas-veach.svg)\n");
    md
}

/// Three heat maps (one per strategy) of log10 relative RMSE, value written in each cell.
pub(crate) fn atlas_charts(a: &Atlas) -> Result<(String, Vec<u8>)> {
    use image::ImageEncoder as _;
    crate::converge::register_font()?;
    const SIZE: (u32, u32) = (1200, 430);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(&root, a).map_err(|e| anyhow!("cannot draw the atlas: {e}"))?;
        root.present().map_err(|e| anyhow!("cannot draw the atlas: {e:?}"))?;
    }
    let mut rgb = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, a).map_err(|e| anyhow!("cannot draw the atlas: {e}"))?;
        root.present().map_err(|e| anyhow!("cannot draw the atlas: {e:?}"))?;
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgb, SIZE.0, SIZE.1, image::ExtendedColorType::Rgb8)
        .map_err(|e| anyhow!("cannot encode the PNG: {e}"))?;
    Ok((svg, png))
}

/// The cell whose centre is at `v` (labels sit at cell centres k + 0.5, none elsewhere).
fn cell_index(v: f64) -> Option<usize> {
    let i = v - 0.5;
    ((i - i.round()).abs() < 1e-6 && i >= -1e-6).then(|| i.round() as usize)
}

/// Colour of a relative RMSE on a log scale from 1% (green) through 10% (yellow) to 100% and
/// beyond (red).
fn heat(e: f64) -> RGBColor {
    let t = ((e.max(1e-3).log10() + 2.0) / 2.0).clamp(0.0, 1.0);
    let (r, g) = if t < 0.5 { (2.0 * t, 1.0) } else { (1.0, 2.0 * (1.0 - t)) };
    RGBColor((60.0 + 195.0 * r) as u8, (60.0 + 170.0 * g) as u8, 70)
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, a: &Atlas) -> std::result::Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let panels = root.split_evenly((1, a.strategies.len()));
    for (s, area) in a.strategies.iter().zip(panels.iter()) {
        let mut c = ChartBuilder::on(area)
            .caption(format!("{} ({} spp, {:.2} s)", s.name, SPP, s.secs), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0f64..4.0, 0.0f64..4.0)?;
        c.configure_mesh()
            .disable_mesh()
            .x_labels(9)
            .y_labels(9)
            .x_label_formatter(&|x| cell_index(*x).and_then(|i| LIGHT_RADIUS.get(i)).map(|r| r.to_string()).unwrap_or_default())
            .y_label_formatter(&|y| cell_index(*y).and_then(|i| PLATE_ALPHA.get(3usize.checked_sub(i)?)).map(|r| r.to_string()).unwrap_or_default())
            .x_desc("light radius")
            .y_desc("plate alpha")
            .label_style(("sans-serif", 13))
            .draw()?;
        for p in 0..4 {
            for l in 0..4 {
                let e = s.rel_rmse[p][l];
                let y0 = (3 - p) as f64;
                c.draw_series(std::iter::once(Rectangle::new([(l as f64, y0), (l as f64 + 1.0, y0 + 1.0)], heat(e).filled())))?;
                c.draw_series(std::iter::once(Text::new(format!("{:.1}%", 100.0 * e), (l as f64 + 0.2, y0 + 0.6), ("sans-serif", 15).into_font())))?;
            }
        }
    }
    Ok(())
}
