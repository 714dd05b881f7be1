//! The error-against-time chart of [`super::run`]: relMSE against render time, log-log, one
//! line per series, points labelled with their sample (or patch) count.

use super::Series;
use crate::chart::{chart_png, chart_svg, log_ticks, tick, Chart, FONT};
use crate::{write_atomic, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Size of the chart, pixels.
const CHART_SIZE: (u32, u32) = (960, 640);

/// The error-against-time chart of `pt converge`.
struct ConvergeChart<'a> {
    title: &'a str,
    all: &'a [Series],
}

impl Chart for ConvergeChart<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        draw_chart(root, self.title, self.all)
    }
}

pub(super) fn write_svg(path: &Path, title: &str, all: &[Series]) -> Result<()> {
    let text = chart_svg(
        &ConvergeChart { title, all },
        CHART_SIZE,
        &format!("'{}'", path.display()),
    )?;
    write_atomic(path, text.as_bytes())
}

pub(super) fn write_png(path: &Path, title: &str, all: &[Series]) -> Result<()> {
    let bytes = chart_png(
        &ConvergeChart { title, all },
        CHART_SIZE,
        &format!("'{}'", path.display()),
    )?;
    write_atomic(path, &bytes)
}

fn draw_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    all: &[Series],
) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("{e:?}");
    root.fill(&WHITE).map_err(err)?;
    let pts = || {
        all.iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.seconds > 0.0 && p.relmse > 0.0)
    };
    let (mut t0, mut t1, mut e0, mut e1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in pts() {
        t0 = t0.min(p.seconds);
        t1 = t1.max(p.seconds);
        e0 = e0.min(p.relmse);
        e1 = e1.max(p.relmse);
    }
    if !(t0 <= t1 && e0 <= e1) {
        (t0, t1, e0, e1) = (0.1, 1.0, 0.01, 0.1);
    }
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 24))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(
            (t0 / 1.6..t1 * 1.6)
                .log_scale()
                .with_key_points(log_ticks(t0 / 1.6, t1 * 1.6)),
            (e0 / 1.6..e1 * 1.6)
                .log_scale()
                .with_key_points(log_ticks(e0 / 1.6, e1 * 1.6)),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("render time (s), log scale")
        .y_desc("relMSE, log scale")
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .light_line_style(TRANSPARENT)
        .draw()
        .map_err(err)?;
    let palette = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(255, 127, 14),
        RGBColor(140, 86, 75),
    ];
    for (k, s) in all.iter().enumerate() {
        let colour = palette[k % palette.len()];
        let xy: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter(|p| p.seconds > 0.0 && p.relmse > 0.0)
            .map(|p| (p.seconds, p.relmse))
            .collect();
        chart
            .draw_series(LineSeries::new(xy.clone(), colour.stroke_width(2)))
            .map_err(err)?
            .label(s.name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3))
            });
        chart
            .draw_series(xy.iter().map(|&p| Circle::new(p, 4, colour.filled())))
            .map_err(err)?;
        chart
            .draw_series(
                s.points
                    .iter()
                    .filter(|p| p.seconds > 0.0 && p.relmse > 0.0)
                    .map(|p| {
                        EmptyElement::at((p.seconds, p.relmse))
                            + Text::new(
                                format!("{}", p.spp),
                                (7, -18),
                                (FONT, 13).into_font().color(&colour),
                            )
                    }),
            )
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 16))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK.mix(0.5))
        .draw()
        .map_err(err)?;
    Ok(())
}
