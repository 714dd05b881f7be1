//! A study's report section and chart.

use super::Study;
use crate::chart::{chart_both, Chart};
use crate::{write_atomic, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

impl Study {
    /// The report section (Markdown): the text, a table per method, the reference's noise and
    /// the chart (`atlas-KEY.svg`).
    pub fn report(&self) -> String {
        study_report(self)
    }

    /// Heat maps (one panel per method) of the errors, value written in each cell; SVG and
    /// PNG.
    pub fn charts(&self) -> Result<(String, Vec<u8>)> {
        let (_, lines) = panel_grid(self.panels.len());
        let size: (u32, u32) = (1200, lines * (110 + 80 * self.rows.len() as u32));
        chart_both(self, size, "the atlas")
    }

    /// Writes the charts as `atlas-KEY.svg` and `atlas-KEY.png` into `dir`, atomically.
    pub fn write_charts(&self, dir: &Path) -> Result<()> {
        let (svg, png) = self.charts()?;
        write_atomic(&dir.join(format!("atlas-{}.svg", self.key)), svg.as_bytes())?;
        write_atomic(&dir.join(format!("atlas-{}.png", self.key)), &png)
    }
}

/// The report section of a study (Markdown).
fn study_report(s: &Study) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "## {}\n\n{}\n", s.title, s.text);
    let header = |md: &mut String| {
        let _ = writeln!(
            md,
            "| {} \\ {} | {} |",
            s.row_label,
            s.col_label,
            s.cols.join(" | ")
        );
        let _ = writeln!(md, "|---|{}", "---|".repeat(s.cols.len()));
    };
    for p in &s.panels {
        let same = p.spp.windows(2).all(|w| w[0] == w[1])
            && p.secs.windows(2).all(|w| (w[0] - w[1]).abs() < 1e-9);
        if same {
            let _ = writeln!(
                md,
                "**{}** ({} spp in {:.2} s)\n",
                p.name, p.spp[0], p.secs[0]
            );
        } else {
            let cols: Vec<String> = p
                .spp
                .iter()
                .zip(&p.secs)
                .map(|(n, t)| format!("{n} spp / {t:.2} s"))
                .collect();
            let _ = writeln!(md, "**{}** (per column: {})\n", p.name, cols.join(", "));
        }
        header(&mut md);
        for (r, row) in s.rows.iter().enumerate() {
            let cells: Vec<String> = p.cells[r]
                .iter()
                .map(|e| format!("{:.1}%", 100.0 * e))
                .collect();
            let _ = writeln!(md, "| {} | {} |", row, cells.join(" | "));
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(md, "**Reference's own noise** (relative, same units as the first row's error; adds in quadrature)\n");
    header(&mut md);
    for (r, row) in s.rows.iter().enumerate() {
        if s.ref_noise[r].iter().all(|v| v.is_nan()) {
            continue;
        }
        let cells: Vec<String> = s.ref_noise[r]
            .iter()
            .map(|e| {
                if e.is_nan() {
                    "-".to_string()
                } else {
                    format!("{:.2}%", 100.0 * e)
                }
            })
            .collect();
        let _ = writeln!(md, "| {} | {} |", row, cells.join(" | "));
    }
    let _ = writeln!(md, "\n![{}](atlas-{}.svg)\n", s.title, s.key);
    md
}

impl Chart for Study {
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

/// The cell whose centre is at `v` (labels sit at cell centres k + 0.5, none elsewhere).
fn cell_index(v: f64) -> Option<usize> {
    let i = v - 0.5;
    ((i - i.round()).abs() < 1e-6 && i >= -1e-6).then(|| i.round() as usize)
}

/// Colour of a relative error on a log scale from 1% (green) through 10% (yellow) to 100% and
/// beyond (red).
fn heat(e: f64) -> RGBColor {
    let t = ((e.max(1e-3).log10() + 2.0) / 2.0).clamp(0.0, 1.0);
    let (r, g) = if t < 0.5 {
        (2.0 * t, 1.0)
    } else {
        (1.0, 2.0 * (1.0 - t))
    };
    RGBColor((60.0 + 195.0 * r) as u8, (60.0 + 170.0 * g) as u8, 70)
}

fn fmt_pct(e: f64) -> String {
    if e >= 1.0 {
        format!("{:.0}%", 100.0 * e)
    } else {
        format!("{:.1}%", 100.0 * e)
    }
}

/// Panels per line and lines of a chart of `n` panels: up to four on one line (their captions
/// fit 1200 pixels), more in lines of three.
fn panel_grid(n: usize) -> (u32, u32) {
    let per_line = if n <= 4 { n.max(1) } else { 3 };
    (per_line as u32, n.div_ceil(per_line) as u32)
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    s: &Study,
) -> std::result::Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (nr, nc) = (s.rows.len(), s.cols.len());
    let (per_line, lines) = panel_grid(s.panels.len());
    let panels = root.split_evenly((lines as usize, per_line as usize));
    for (p, area) in s.panels.iter().zip(panels.iter()) {
        let (s0, s1) = (
            p.spp.iter().min().copied().unwrap_or(0),
            p.spp.iter().max().copied().unwrap_or(0),
        );
        let (t0, t1) = (
            p.secs.iter().copied().fold(f64::INFINITY, f64::min),
            p.secs.iter().copied().fold(0.0, f64::max),
        );
        let spp = if s0 == s1 {
            s0.to_string()
        } else {
            format!("{s0}-{s1}")
        };
        let secs = if t1 - t0 < 0.005 {
            format!("{t0:.2}")
        } else {
            format!("{t0:.2}-{t1:.2}")
        };
        let caption = format!("{} ({spp} spp, {secs} s)", p.name);
        let mut c = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 17))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(95)
            .build_cartesian_2d(0.0f64..nc as f64, 0.0f64..nr as f64)?;
        c.configure_mesh()
            .disable_mesh()
            .x_labels(2 * nc + 1)
            .y_labels(2 * nr + 1)
            .x_label_formatter(&|x| {
                cell_index(*x)
                    .and_then(|i| s.cols.get(i))
                    .cloned()
                    .unwrap_or_default()
            })
            .y_label_formatter(&|y| {
                cell_index(*y)
                    .and_then(|i| s.rows.get((nr - 1).checked_sub(i)?))
                    .cloned()
                    .unwrap_or_default()
            })
            .x_desc(s.col_label.as_str())
            .y_desc(s.row_label.as_str())
            .label_style(("sans-serif", 12))
            .draw()?;
        let font = if nc > 5 { 11 } else { 14 };
        for r in 0..nr {
            for k in 0..nc {
                let e = p.cells[r][k];
                let y0 = (nr - 1 - r) as f64;
                c.draw_series(std::iter::once(Rectangle::new(
                    [(k as f64, y0), (k as f64 + 1.0, y0 + 1.0)],
                    heat(e).filled(),
                )))?;
                c.draw_series(std::iter::once(Text::new(
                    fmt_pct(e),
                    (k as f64 + 0.12, y0 + 0.6),
                    ("sans-serif", font).into_font(),
                )))?;
            }
        }
    }
    Ok(())
}
