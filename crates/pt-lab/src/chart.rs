//! Charts shared by the analyses: one drawing function per chart, rendered as SVG text or as a
//! PNG (8-bit RGB) through plotters, with the font embedded (DejaVu Sans from the `dejavu`
//! crate, registered as plotters' "sans-serif"), so PNGs work on machines without system fonts.
//! Sizes are in pixels; colours are sRGB.

use crate::{LabError, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

/// The font family every chart uses (registered by [`register_font`]).
pub const FONT: &str = "sans-serif";

/// Tableau 10, the categorical palette of the charts (sRGB).
pub const TABLEAU10: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Colour `i` of [`TABLEAU10`], cycling.
pub fn palette(i: usize) -> RGBColor {
    TABLEAU10[i % TABLEAU10.len()]
}

/// Viridis at `t` in [0, 1] (clamped), by linear interpolation between five stops.
pub fn viridis(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68., 1., 84.),
        (59., 82., 139.),
        (33., 145., 140.),
        (94., 201., 98.),
        (253., 231., 37.),
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(
        (a.0 + (b.0 - a.0) * f) as u8,
        (a.1 + (b.1 - a.1) * f) as u8,
        (a.2 + (b.2 - a.2) * f) as u8,
    )
}

/// Registers DejaVu Sans (embedded from the `dejavu` crate) as plotters' "sans-serif", once:
/// with the `ab_glyph` feature plotters draws text only with registered fonts.
pub fn register_font() -> Result<()> {
    static OK: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    if *OK.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
    }) {
        Ok(())
    } else {
        Err(LabError::Chart(
            "the embedded chart font is not a valid TrueType font".into(),
        ))
    }
}

/// A chart that draws itself on any plotters backend (SVG text or an RGB bitmap).
pub trait Chart {
    /// Draws the whole chart on `root`; the error is a message.
    fn draw_on<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String>
    where
        DB::ErrorType: 'static;
}

/// `chart` drawn at `size` pixels as SVG text; `what` names it in errors.
pub fn chart_svg(chart: &impl Chart, size: (u32, u32), what: &str) -> Result<String> {
    register_font()?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        chart
            .draw_on(&root)
            .map_err(|e| LabError::Chart(format!("cannot draw {what}: {e}")))?;
        root.present()
            .map_err(|e| LabError::Chart(format!("cannot draw {what}: {e:?}")))?;
    }
    Ok(text)
}

/// `chart` drawn at `size` pixels as PNG bytes (8-bit RGB); `what` names it in errors.
pub fn chart_png(chart: &impl Chart, size: (u32, u32), what: &str) -> Result<Vec<u8>> {
    use image::ImageEncoder as _;
    register_font()?;
    let (w, h) = size;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        chart
            .draw_on(&root)
            .map_err(|e| LabError::Chart(format!("cannot draw {what}: {e}")))?;
        root.present()
            .map_err(|e| LabError::Chart(format!("cannot draw {what}: {e:?}")))?;
    }
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(&rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| LabError::Chart(format!("cannot encode {what} as PNG: {e}")))?;
    Ok(bytes)
}

/// `chart` as both SVG text and PNG bytes.
pub fn chart_both(chart: &impl Chart, size: (u32, u32), what: &str) -> Result<(String, Vec<u8>)> {
    Ok((chart_svg(chart, size, what)?, chart_png(chart, size, what)?))
}

/// Short tick labels for a log axis: 0.05, 2, 300, 1e-4.
pub fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.0e}")
    }
}

/// Tick positions for a log axis over `[lo, hi]`: decades, or 1-2-5, 1-2-3-5-7 or every integer
/// mantissa per decade, the first of these that gives at least four ticks.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let sets: [&[f64]; 4] = [
        &[1.0],
        &[1.0, 2.0, 5.0],
        &[1.0, 2.0, 3.0, 5.0, 7.0],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ];
    let mut ticks = Vec::new();
    for set in sets {
        ticks.clear();
        for k in lo.log10().floor() as i32..=hi.log10().ceil() as i32 {
            let decade = 10f64.powi(k);
            ticks.extend(
                set.iter()
                    .map(|m| m * decade)
                    .filter(|v| (lo..=hi).contains(v)),
            );
        }
        if ticks.len() >= 4 {
            break;
        }
    }
    ticks
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_readable() {
        let t = log_ticks(0.03, 20.0);
        assert_eq!(t.len(), 9, "{t:?}"); // 0.05 0.1 0.2 0.5 1 2 5 10 20
        assert!(t.iter().any(|v| (v - 1.0).abs() < 1e-12), "{t:?}");
        let t = log_ticks(0.0005, 20.0);
        assert_eq!(t.len(), 5, "{t:?}");
        let t = log_ticks(0.06, 0.5);
        assert!(
            t.len() >= 4 && t.iter().all(|v| (0.06..=0.5).contains(v)),
            "{t:?}"
        );
        assert_eq!(
            (tick(0.05), tick(300.0), tick(1e-4)),
            ("0.05".into(), "300".into(), "1e-4".into())
        );
    }
}
