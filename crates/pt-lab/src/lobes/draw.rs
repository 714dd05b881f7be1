//! The figure of [`Lobes`]: six panels (see the module doc of `lobes`).

use super::{LobePoint, Lobes};
use crate::chart::{palette, viridis, Chart, FONT};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Size of the figure, pixels.
pub(super) const SIZE: (u32, u32) = (1800, 1100);

impl Chart for Lobes {
    fn draw_on<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        draw(root, self).map_err(|e| e.to_string())
    }
}

/// Colour of model `m` at incident angle index `a`: one hue per angle for a single model, one
/// hue per model (darker for larger angles) otherwise.
fn series_colour(d: &Lobes, m: usize, a: usize) -> RGBColor {
    if d.models.len() == 1 {
        return palette(a);
    }
    let RGBColor(r, g, b) = palette(m);
    let k = 1.0 - 0.55 * a as f64 / d.theta_i.len().max(2) as f64;
    RGBColor(
        (r as f64 * k) as u8,
        (g as f64 * k) as u8,
        (b as f64 * k) as u8,
    )
}

type DrawResult = std::result::Result<(), String>;

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, d: &Lobes) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let root = root
        .titled(
            "pt lobes: BSDF lobes, albedo and sampling (luminance of the RGB lanes)",
            (FONT, 26),
        )
        .map_err(e)?;
    let panels = root.split_evenly((2, 3));
    polar(&panels[0], d, true)?;
    polar(&panels[1], d, false)?;
    heat_panel(&panels[2], d)?;
    albedo_panel(&panels[3], d)?;
    hist_panel(&panels[4], d)?;
    legend_panel(&panels[5], d)?;
    Ok(())
}

fn no_data<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    why: &str,
) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let (w, h) = area.dim_in_pixel();
    area.draw(&Text::new(title.to_string(), (20, 10), (FONT, 20)))
        .map_err(e)?;
    area.draw(&Text::new(
        why.to_string(),
        (w as i32 / 6, h as i32 / 2),
        (FONT, 16).into_font().color(&RGBColor(120, 120, 120)),
    ))
    .map_err(e)
}

fn polar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    d: &Lobes,
    with_cos: bool,
) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let title = if with_cos {
        "(1) f * |cos theta_o|, plane of incidence"
    } else {
        "(2) f (no cosine), plane of incidence"
    };
    let raw = |p: &LobePoint| {
        let v = if with_cos {
            p.f * p.angle.to_radians().cos().abs()
        } else {
            p.f
        };
        if v.is_finite() {
            v
        } else {
            0.0
        }
    };
    let curve_max = |pts: &[LobePoint]| pts.iter().map(raw).fold(0.0f64, f64::max);
    let peak = d
        .lobes
        .iter()
        .flatten()
        .map(|c| curve_max(c))
        .fold(0.0f64, f64::max);
    let rmax = if d.normalize { 1.0 } else { peak };
    if peak <= 0.0 {
        return no_data(area, title, "delta lobes only: no density to draw");
    }
    let r = rmax * 1.08;
    let transmissive = d.models.iter().any(|m| m.transmissive && !m.delta);
    let y0 = if transmissive { -r } else { -0.08 * r };
    // Equal scales on both axes (the plot area is about (w - 70) x (h - 75) pixels): widen
    // whichever range is short.
    let (w, h) = area.dim_in_pixel();
    let aspect = (w as f64 - 70.0) / (h as f64 - 75.0);
    let (half_x, r) = if 2.0 * r / (r - y0) > aspect {
        (r, y0 + 2.0 * r / aspect)
    } else {
        ((r - y0) * aspect / 2.0, r)
    };
    let mut chart = ChartBuilder::on(area)
        .caption(
            if d.normalize {
                format!("{title} (each curve / its max)")
            } else {
                format!("{title} (max {rmax:.4})")
            },
            (FONT, 18),
        )
        .margin(8)
        .x_label_area_size(28)
        .y_label_area_size(52)
        .build_cartesian_2d(-half_x..half_x, y0..r)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .label_style((FONT, 12))
        .draw()
        .map_err(e)?;
    let grey = RGBColor(200, 200, 200);
    for k in 1..=4 {
        let rr = rmax * k as f64 / 4.0;
        let lo = if transmissive { -180 } else { -90 };
        let pts: Vec<(f64, f64)> = (lo..=(-lo))
            .map(|a| {
                (
                    rr * (a as f64).to_radians().sin(),
                    rr * (a as f64).to_radians().cos(),
                )
            })
            .collect();
        chart.draw_series(LineSeries::new(pts, &grey)).map_err(e)?;
    }
    chart
        .draw_series(LineSeries::new(
            vec![(-half_x, 0.0), (half_x, 0.0)],
            BLACK.stroke_width(2),
        ))
        .map_err(e)?;
    for (m, per) in d.lobes.iter().enumerate() {
        for (a, pts) in per.iter().enumerate() {
            let c = series_colour(d, m, a);
            let t = d.theta_i[a].to_radians();
            chart
                .draw_series(LineSeries::new(
                    vec![(0.0, 0.0), (-r * t.sin(), r * t.cos())],
                    c.mix(0.5).stroke_width(1),
                ))
                .map_err(e)?;
            let scale = if d.normalize {
                1.0 / curve_max(pts).max(f64::MIN_POSITIVE)
            } else {
                1.0
            };
            let xy: Vec<(f64, f64)> = pts
                .iter()
                .map(|p| {
                    let v = raw(p) * scale;
                    let a = p.angle.to_radians();
                    (v * a.sin(), v * a.cos())
                })
                .collect();
            let label = if d.models.len() == 1 {
                format!("theta_i = {}", d.theta_i[a])
            } else {
                format!("{} @ {}", d.models[m].label, d.theta_i[a])
            };
            chart
                .draw_series(LineSeries::new(xy, c.stroke_width(2)))
                .map_err(e)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
        }
    }
    if with_cos {
        legend(&mut chart, SeriesLabelPosition::UpperLeft).map_err(e)?;
    }
    Ok(())
}

fn albedo_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &Lobes) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let top = d
        .albedo
        .iter()
        .flatten()
        .map(|a| a.mean + 2.0 * a.stderr)
        .filter(|v| v.is_finite())
        .fold(1.0f64, f64::max)
        * 1.05;
    let mut chart = ChartBuilder::on(area)
        .caption(
            "(3) directional albedo E[f cos / pdf] (own sampler)",
            (FONT, 18),
        )
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(52)
        .build_cartesian_2d(0.0..90.0, 0.0..top)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("theta_i (degrees)")
        .y_desc("albedo")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    chart
        .draw_series(LineSeries::new(
            vec![(0.0, 1.0), (90.0, 1.0)],
            RGBColor(150, 150, 150),
        ))
        .map_err(e)?;
    for (m, al) in d.albedo.iter().enumerate() {
        let c = palette(m);
        chart
            .draw_series(LineSeries::new(
                al.iter().map(|a| (a.theta_i, a.mean)),
                c.stroke_width(2),
            ))
            .map_err(e)?
            .label(d.models[m].label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        chart
            // plotters' ErrorBar needs its `errorbar` feature: plain vertical segments instead.
            .draw_series(al.iter().map(|a| {
                PathElement::new(
                    vec![
                        (a.theta_i, a.mean - 2.0 * a.stderr),
                        (a.theta_i, a.mean + 2.0 * a.stderr),
                    ],
                    c.stroke_width(1),
                )
            }))
            .map_err(e)?;
    }
    legend(&mut chart, SeriesLabelPosition::LowerLeft).map_err(e)?;
    Ok(())
}

/// The series legend every panel uses (light background, grey border, 12 px text).
fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(RGBColor(200, 200, 200))
        .label_font((FONT, 12))
        .draw()
}

fn hist_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &Lobes) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let title = format!(
        "(4) sampled theta_o at theta_i = {}: histogram vs integrated pdf",
        d.theta_i[0]
    );
    let top = d
        .hist
        .iter()
        .flatten()
        .flat_map(|h| h.observed.iter().chain(&h.expected))
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    if top <= 0.0 {
        return no_data(
            area,
            &title,
            "delta lobes only: no density to sample against",
        );
    }
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 18))
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..d.max_theta, 0.0..top * 1.08)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("theta_o (degrees; > 90: transmitted)")
        .y_desc("fraction of samples per 2 degree bin")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    for (m, h) in d.hist.iter().enumerate() {
        let Some(h) = h else { continue };
        let c = palette(m);
        let centre = |b: usize| (b as f64 + 0.5) * h.width;
        chart
            .draw_series(LineSeries::new(
                h.expected.iter().enumerate().map(|(b, &v)| (centre(b), v)),
                c.stroke_width(2),
            ))
            .map_err(e)?
            .label(format!(
                "{}: pdf (line), samples (dots), chi2/dof {:.2}",
                d.models[m].label,
                h.chi2 / h.dof as f64
            ))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        chart
            .draw_series(
                h.observed
                    .iter()
                    .enumerate()
                    .map(|(b, &v)| Circle::new((centre(b), v), 2, c.filled())),
            )
            .map_err(e)?;
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight).map_err(e)?;
    Ok(())
}

fn heat_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &Lobes) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let Some(h) = &d.heat else {
        return no_data(
            area,
            "(5) f * |cos theta_o| over the sphere",
            "delta lobes only",
        );
    };
    let value = |i: usize| {
        let v = h.cells[i].0 * h.theta(i / h.cols).to_radians().cos().abs();
        if v.is_finite() {
            v
        } else {
            0.0
        }
    };
    let vmax = (0..h.cells.len()).map(value).fold(0.0f64, f64::max);
    let title = format!(
        "(5) f*|cos theta_o| of model {} at theta_i = {} (sqrt colour scale)",
        h.model + 1,
        d.theta_i[0]
    );
    let (pw, _) = area.dim_in_pixel();
    let (main, bar) = area.split_horizontally(pw.saturating_sub(70));
    let mut chart = ChartBuilder::on(&main)
        .caption(title, (FONT, 16))
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(52)
        .build_cartesian_2d(-180.0..180.0, 0.0..h.max_theta)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("phi_o (degrees; the fixed direction is at 180)")
        .y_desc("theta_o (degrees)")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(e)?;
    let (dt, dp) = (h.max_theta / h.rows as f64, 360.0 / h.cols as f64);
    chart
        .draw_series((0..h.cells.len()).map(|i| {
            let (t, p) = (h.theta(i / h.cols), h.phi(i % h.cols));
            let c = viridis(if vmax > 0.0 {
                (value(i) / vmax).sqrt()
            } else {
                0.0
            });
            Rectangle::new(
                [(p - dp / 2.0, t - dt / 2.0), (p + dp / 2.0, t + dt / 2.0)],
                c.filled(),
            )
        }))
        .map_err(e)?;
    // Colour bar.
    let steps = 50;
    let bar = bar.margin(40, 44, 10, 20);
    let (_, bh) = bar.dim_in_pixel();
    for s in 0..steps {
        // Drawn on the same sqrt scale as the map: colour t stands for vmax * t^2.
        let y0 = (bh as f64 * (1.0 - (s + 1) as f64 / steps as f64)) as i32;
        let y1 = (bh as f64 * (1.0 - s as f64 / steps as f64)) as i32;
        bar.draw(&Rectangle::new(
            [(0, y0), (16, y1)],
            viridis((s as f64 + 0.5) / steps as f64).filled(),
        ))
        .map_err(e)?;
    }
    bar.draw(&Text::new(format!("{vmax:.3}"), (0, -14), (FONT, 11)))
        .map_err(e)?;
    bar.draw(&Text::new(
        format!("{:.3}", vmax / 4.0),
        (18, bh as i32 / 2 - 6),
        (FONT, 11),
    ))
    .map_err(e)?;
    bar.draw(&Text::new("0", (0, bh as i32 + 2), (FONT, 11)))
        .map_err(e)?;
    Ok(())
}

fn legend_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, d: &Lobes) -> DrawResult {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let mut lines: Vec<(String, RGBColor)> = vec![("(6) models".into(), BLACK)];
    for (m, model) in d.models.iter().enumerate() {
        let note = if model.delta {
            "  [delta lobes: albedo only]"
        } else {
            ""
        };
        lines.push((format!("  {}. {}{note}", m + 1, model.label), palette(m)));
    }
    let grey = RGBColor(70, 70, 70);
    for l in [
        String::new(),
        format!(
            "theta_i: {:?} degrees (fixed direction = the wo given to sample(),",
            d.theta_i
        ),
        "  at phi = 180; plotted direction theta_o, phi = the sampled wi)".into(),
        "values: luminance 0.2126 R + 0.7152 G + 0.0722 B of the RGB lanes".into(),
        "f without cosine; pdf per solid angle; transmission carries 1/eta^2".into(),
    ]
    .into_iter()
    .chain(d.settings.lines().map(str::to_string))
    {
        lines.push((l, grey));
    }
    for (i, (text, c)) in lines.iter().enumerate() {
        area.draw(&Text::new(
            text.clone(),
            (20, 20 + 24 * i as i32),
            (FONT, if i == 0 { 20 } else { 15 }).into_font().color(c),
        ))
        .map_err(e)?;
    }
    Ok(())
}
