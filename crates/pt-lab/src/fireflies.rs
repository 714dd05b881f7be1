//! The bias of `pt render --clamp X`, measured for the stability report ([`crate::stability`]).
//!
//! Scene (embedded below): a glass sphere on a diffuse floor under a small spherical light,
//! 64 x 48 pixels. Its caustic is reached only by BSDF-sampled paths that hit the small light
//! through the glass, so it is made of rare, very bright samples: fireflies. The scene is
//! rendered once without clamp and once per clamp value **with the same seed**, so every sample
//! is the same path and the difference of two image means is exactly the energy the clamp
//! removed from those samples (its expectation is the clamp's bias; no noise of its own beyond
//! which rare paths happened to be drawn). The firefly count ([`pt_image::fireflies`]) of each
//! image shows what the clamp buys.

use crate::chart::{chart_both, Chart};
use crate::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use pt_image::fireflies::{count_fireflies, luminance, FireflyParams};
use pt_image::Image;
use pt_integrators::RenderSettings;
use pt_render::{BvhKind, LightSelection, Scene};
use std::fmt::Write as _;
use std::path::Path;

/// The test scene: glass sphere, floor, small bright spherical light (radius 0.05, radiance 400).
const SCENE: &str = r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="8"/></integrator>
    <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 2.2, 3.2" target="0, 0.3, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="256"/><integer name="seed" value="3"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/><rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="0" y="0.5" z="0"/><float name="radius" value="0.5"/>
        <bsdf type="dielectric"><float name="int_ior" value="1.5"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="0.3" y="2.0" z="-0.3"/><float name="radius" value="0.05"/>
        <emitter type="area"><rgb name="radiance" value="400, 400, 400"/></emitter></shape>
</scene>"#;

/// Clamp values studied (radiance; `None` is the unclamped render).
const CLAMPS: [Option<f32>; 7] = [
    None,
    Some(1000.0),
    Some(100.0),
    Some(30.0),
    Some(10.0),
    Some(3.0),
    Some(1.0),
];

/// One clamp value's outcome.
#[derive(Clone, Debug)]
pub struct ClampRow {
    /// The clamp (None: off).
    pub clamp: Option<f32>,
    /// Image mean luminance.
    pub mean: f64,
    /// Relative bias of the image mean against the unclamped render, same samples.
    pub bias: f64,
    /// Largest relative bias of a 8x8-pixel block's mean (where the clamp bites hardest).
    pub worst_block_bias: f64,
    /// Firefly count.
    pub fireflies: usize,
    /// Brightest pixel luminance.
    pub max_pixel: f64,
}

/// The study's result.
#[derive(Clone, Debug)]
pub struct ClampStudy {
    /// Samples per pixel of each render.
    pub spp: u32,
    /// One row per clamp value, unclamped first.
    pub rows: Vec<ClampRow>,
}

fn block_means(img: &Image, b: u32) -> Vec<f64> {
    let mut out = Vec::new();
    for by in 0..img.height / b {
        for bx in 0..img.width / b {
            let mut s = 0.0f64;
            for y in by * b..(by + 1) * b {
                for x in bx * b..(bx + 1) * b {
                    s += f64::from(luminance(img.data[(y * img.width + x) as usize]));
                }
            }
            out.push(s / f64::from(b * b));
        }
    }
    out
}

/// Renders the scene at each clamp value (on the current rayon pool) and measures the bias.
pub fn clamp_bias_study() -> Result<ClampStudy> {
    let desc = pt_scene::load_str(SCENE, Path::new("<clamp study scene>"), Path::new("."), &[])?;
    let scene = Scene::build(&desc, BvhKind::Auto, LightSelection::Power)?;
    let base = RenderSettings::from_desc(&desc);
    let mut rows = Vec::new();
    let mut reference: Option<(f64, Vec<f64>)> = None;
    for clamp in CLAMPS {
        let out = pt_integrators::render(
            &scene,
            &RenderSettings {
                clamp,
                ..base.clone()
            },
            &|_| {},
        );
        let img = Image {
            width: out.width,
            height: out.height,
            data: out.mean,
        };
        let mean = img
            .data
            .iter()
            .map(|&p| f64::from(luminance(p)))
            .sum::<f64>()
            / img.data.len() as f64;
        let blocks = block_means(&img, 8);
        let (m0, b0) = reference.get_or_insert_with(|| (mean, blocks.clone()));
        let worst_block_bias = blocks
            .iter()
            .zip(b0.iter())
            .filter(|(_, &r)| r > 0.0)
            .map(|(&v, &r)| v / r - 1.0)
            .fold(0.0f64, f64::min);
        rows.push(ClampRow {
            clamp,
            mean,
            bias: mean / *m0 - 1.0,
            worst_block_bias,
            fireflies: count_fireflies(&img, FireflyParams::default()),
            max_pixel: img
                .data
                .iter()
                .map(|&p| f64::from(luminance(p)))
                .fold(0.0, f64::max),
        });
    }
    Ok(ClampStudy {
        spp: base.spp,
        rows,
    })
}

impl ClampStudy {
    /// The report section (Markdown).
    pub fn report(&self) -> String {
        clamp_report(self)
    }

    /// Chart: bias (%) and firefly count against the clamp value (log scale), as SVG and PNG.
    pub fn charts(&self) -> Result<(String, Vec<u8>)> {
        const SIZE: (u32, u32) = (1000, 420);
        chart_both(self, SIZE, "the clamp chart")
    }
}

fn clamp_report(s: &ClampStudy) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "## Firefly clamp: bias against fireflies\n");
    let _ = writeln!(
        md,
        "`pt render --clamp X` (off by default) scales each sample whose largest RGB channel exceeds X down to X. \
         Scene: a glass sphere on a diffuse floor under a small spherical light (radius 0.05, radiance 400), 64x48 px, \
         {} spp, max_depth 8 (embedded in `crates/pt-lab/src/fireflies.rs`). Every render uses the same seed, so each \
         row differs from the unclamped one only by what the clamp removed from the same samples: the bias column is \
         the clamp's bias (relative, image mean luminance), the worst block is the 8x8-pixel block that lost most \
         (the caustic). Fireflies: pixels whose luminance exceeds the median of their 5x5 neighbourhood by 10 \
         robust standard deviations (1.4826 MAD, floored at 5% of the median; `pt_image::fireflies`), the same \
         count `pt compare` prints.\n",
        s.spp
    );
    let _ = writeln!(md, "| clamp | mean luminance | bias of the mean | worst 8x8 block bias | fireflies | brightest pixel |");
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for r in &s.rows {
        let _ = writeln!(
            md,
            "| {} | {:.5} | {:+.2}% | {:+.1}% | {} | {:.2} |",
            r.clamp.map_or("off".to_string(), |c| c.to_string()),
            r.mean,
            100.0 * r.bias,
            100.0 * r.worst_block_bias,
            r.fireflies,
            r.max_pixel
        );
    }
    let _ = writeln!(md, "\n![clamp bias and fireflies](clamp.svg)\n");
    md
}

impl Chart for ClampStudy {
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

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    s: &ClampStudy,
) -> std::result::Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(SIZE_HALF);
    let pts: Vec<(f64, &ClampRow)> = s
        .rows
        .iter()
        .filter_map(|r| r.clamp.map(|c| (f64::from(c), r)))
        .collect();
    let (x0, x1) = (0.5f64, 2000.0f64);
    let ymin = pts
        .iter()
        .map(|(_, r)| 100.0 * r.worst_block_bias)
        .fold(-1.0f64, f64::min)
        * 1.1;
    let mut c = ChartBuilder::on(&left)
        .caption("bias of --clamp (same samples)", ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d((x0..x1).log_scale(), ymin..1.0f64)?;
    c.configure_mesh()
        .x_desc("clamp (radiance)")
        .y_desc("bias, %")
        .label_style(("sans-serif", 12))
        .draw()?;
    c.draw_series(LineSeries::new(
        pts.iter().map(|(x, r)| (*x, 100.0 * r.bias)),
        BLUE.stroke_width(2),
    ))?
    .label("image mean")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLUE.stroke_width(2)));
    c.draw_series(LineSeries::new(
        pts.iter().map(|(x, r)| (*x, 100.0 * r.worst_block_bias)),
        RED.stroke_width(2),
    ))?
    .label("worst 8x8 block")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], RED.stroke_width(2)));
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .position(SeriesLabelPosition::LowerRight)
        .draw()?;
    let off = s.rows.first().map_or(0, |r| r.fireflies);
    let ymax = s.rows.iter().map(|r| r.fireflies).max().unwrap_or(1).max(1) as f64 * 1.15;
    let mut c = ChartBuilder::on(&right)
        .caption(format!("fireflies (unclamped: {off})"), ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d((x0..x1).log_scale(), 0.0..ymax)?;
    c.configure_mesh()
        .x_desc("clamp (radiance)")
        .y_desc("pixels")
        .label_style(("sans-serif", 12))
        .draw()?;
    c.draw_series(LineSeries::new(
        pts.iter().map(|(x, r)| (*x, r.fireflies as f64)),
        BLACK.stroke_width(2),
    ))?;
    c.draw_series(
        pts.iter()
            .map(|(x, r)| Circle::new((*x, r.fireflies as f64), 4, BLACK.filled())),
    )?;
    Ok(())
}

const SIZE_HALF: u32 = 500;
