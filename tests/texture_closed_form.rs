//! A `checkerboard` texture against a closed form: a one-sided Lambertian plane whose
//! reflectance is a checkerboard of two known RGB colours, under a `constant` environment of
//! radiance L, seen from straight above, nothing else in the scene.
//!
//! **Expectation.** From any point of the plane the whole upper hemisphere is the environment, so
//! the irradiance is pi L and the outgoing radiance is rho(uv) L exactly, at every depth (a path
//! leaving the plane escapes). The film filter is a tent of radius 1e-3 pixel (Mitsuba 3's `box`
//! has no radius parameter, so a tiny tent is how an XML scene puts every sample at the pixel
//! centre): each pixel's expectation is rho(uv of its centre) L, with no footprint averaging.
//! Pixel centre (i + 1/2, j + 1/2) of the 64 x 48 film, camera at height 1 with a 90 degree
//! field of view along x, sees the world point x = (i + 1/2) / 32 - 1, y = 0.75 - (j + 1/2) / 32
//! (image right is +x, image top is +y). The rectangle (scale 2) has Mitsuba's uv
//! u = (x / 2 + 1) / 2, v = (y / 2 + 1) / 2, and the checkerboard's to_uv gives
//! (U, V) = (8 u + 0.3, 4 v + 0.1): cells 8 pixels wide and 16 tall (unequal, so that a
//! transposed lookup shows), with every cell edge 0.3 pixel from the nearest pixel centre (the
//! test checks this margin, so a sample never straddles an edge).
//!
//! **Mitsuba's convention** (checkerboard.cpp, `eval`): with mu = frac(U) > 1/2 and
//! mv = frac(V) > 1/2, color0 where mu == mv (both fractional parts <= 1/2 or both > 1/2), color1
//! elsewhere. A reflectance is read with `eval`; the scalar `eval_1` (roughness, opacity) swaps
//! the two, which must *not* happen here.
//!
//! **Checks**, each also run against wrong expectations that must fail (so the test has power):
//! 1. Every pixel and channel is within the Sidak-corrected z threshold of rho L, with the
//!    render's own variance of the mean: family-wise alpha 0.01 over the 64 x 48 x 3 tests, i.e.
//!    |z| < 4.87. The seed is fixed, so this is deterministic; with correct expectations a
//!    calibrated renderer fails it with probability 1%. Over the whole image, the sum over
//!    pixels of z^2 (averaged over the three channels, which are fully correlated here) must
//!    also be plausible under chi-square with one degree of freedom per pixel (p >= 0.001):
//!    this catches a small bias spread over many pixels, and a variance estimate that is off.
//! 2. Per colour region the mean of the pixels divided by rho L is 1 within 4 standard errors
//!    (the standard error from the variance images, 0.04% here): a 1% bias in the
//!    reflectance, the environment or the BSDF fails this even where check 1 would let it pass.
//! 3. The pattern is where Mitsuba puts it: every pixel is closer to its own expected colour
//!    than to the other one.
//!
//! Wrong expectations that must fail: colours swapped (the scalar `eval_1` convention), v
//! flipped (v' = 1 - v), u and v transposed (each off by hundreds of standard deviations in
//! all three checks), and L scaled by 1.01 (within the per-pixel threshold, max |z| 3.5, but
//! caught by the chi-square, p < 1e-3, and by the region means, 25 standard errors). Whether a
//! fractional part of exactly 1/2 counts as low is not tested: the margin keeps every sample
//! away from cell edges.
//!
//! The same scene with `--strategy bsdf` (cosine-weighted sampling only: every sample weighs
//! exactly rho and sees L) must reproduce rho L to float rounding (1e-5 relative) at every pixel.
//!
//! This is a closed form, not a Mitsuba reference, on purpose: Mitsuba splats uniformly placed
//! samples with the filter's weight, so a filter of radius 1e-3 pixel leaves almost every pixel
//! without weight (its 256-spp render of this scene has 0.07% of the expected mean), and so
//! does pt's default splatting film. The test renders with `--reconstruction importance`,
//! which samples offsets from the filter, so the same XML gives pixel-centre values.

use crate::common;

use common::*;
use pt_image::Image;
use pt_stats::{chi2_sf, normal_sf, sidak_threshold};

const W: u32 = 64;
const H: u32 = 48;
const SPP: &str = "256";
/// Environment radiance.
const L: f64 = 1.5;
/// color0 and color1 of the checkerboard.
const C0: [f64; 3] = [0.8, 0.6, 0.3];
const C1: [f64; 3] = [0.1, 0.25, 0.5];
/// to_uv: U = SU u + TU, V = SV v + TV.
const SU: f64 = 8.0;
const TU: f64 = 0.3;
const SV: f64 = 4.0;
const TV: f64 = 0.1;
/// Family-wise significance of the per-pixel test.
const ALPHA: f64 = 0.01;

fn scene() -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="-1"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="90"/>
        <transform name="to_world"><lookat origin="0, 0, 1" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="{SPP}"/><integer name="seed" value="3"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="{W}"/><integer name="height" value="{H}"/>
            <rfilter type="tent"><float name="radius" value="0.001"/></rfilter>
        </film>
    </sensor>
    <emitter type="constant"><float name="radiance" value="{L}"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="2, 2, 1"/></transform>
        <bsdf type="diffuse">
            <texture type="checkerboard" name="reflectance">
                <rgb name="color0" value="{}, {}, {}"/>
                <rgb name="color1" value="{}, {}, {}"/>
                <transform name="to_uv"><scale x="{SU}" y="{SV}"/><translate x="{TU}" y="{TV}"/></transform>
            </texture>
        </bsdf>
    </shape>
</scene>"#,
        C0[0], C0[1], C0[2], C1[0], C1[1], C1[2]
    )
}

/// Rectangle uv of the point seen at the centre of pixel (i, j).
fn pixel_uv(i: u32, j: u32) -> (f64, f64) {
    let x = (f64::from(i) + 0.5) / 32.0 - 1.0;
    let y = 0.75 - (f64::from(j) + 0.5) / 32.0;
    ((x / 2.0 + 1.0) / 2.0, (y / 2.0 + 1.0) / 2.0)
}

/// Mitsuba's checkerboard `eval`: colour index 0 where both fractional parts are <= 1/2 or both
/// are > 1/2.
fn mitsuba_index(u: f64, v: f64) -> usize {
    let (uu, vv) = (SU * u + TU, SV * v + TV);
    let mu = uu - uu.floor() > 0.5;
    let mv = vv - vv.floor() > 0.5;
    usize::from(mu != mv)
}

/// A hypothesis about the pattern: the colour index of each pixel, and the radiance scale.
struct Expectation {
    name: &'static str,
    index: Box<dyn Fn(f64, f64) -> usize>,
    scale: f64,
}

fn expected_image(e: &Expectation) -> (Image, Vec<usize>) {
    let mut img = Image::new(W, H);
    let mut idx = Vec::with_capacity((W * H) as usize);
    for j in 0..H {
        for i in 0..W {
            let (u, v) = pixel_uv(i, j);
            let k = (e.index)(u, v);
            let c = if k == 0 { C0 } else { C1 };
            img.data[(j * W + i) as usize] = c.map(|r| (r * L * e.scale) as f32);
            idx.push(k);
        }
    }
    (img, idx)
}

/// The three checks of the module documentation; Err says which failed and by how much.
fn judge(img: &Image, var: &Image, e: &Expectation) -> Result<String, String> {
    let (want, idx) = expected_image(e);
    let n = (W * H * 3) as usize;
    let z_max = {
        // Two-sided per-test level 1 - (1 - ALPHA)^(1/n) as a |z| threshold.
        let p = sidak_threshold(ALPHA, n);
        let (mut lo, mut hi) = (0.0f64, 40.0f64);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if 2.0 * normal_sf(mid) > p {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    };
    // 1. Per-pixel z-test, and the chi-square of the per-pixel mean of z^2 over the channels
    //    (every sample here is rho times one scalar weight, so the three channels' z are
    //    the same number: pooling them as independent would triple the spread of the sum).
    let (mut worst, mut worst_at, mut chi2) = (0.0f64, (0, 0, 0), 0.0f64);
    for (p, ((a, w), s)) in img.data.iter().zip(&want.data).zip(&var.data).enumerate() {
        for c in 0..3 {
            let sd = f64::from(s[c]).sqrt();
            if sd == 0.0 || !sd.is_finite() {
                return Err(format!(
                    "{}: pixel {p} channel {c} has variance {}",
                    e.name, s[c]
                ));
            }
            let z = (f64::from(a[c]) - f64::from(w[c])) / sd;
            chi2 += z * z / 3.0;
            if z.abs() > worst {
                worst = z.abs();
                worst_at = (p as u32 % W, p as u32 / W, c);
            }
        }
    }
    let dof = f64::from(W * H);
    let chi2_p = chi2_sf(chi2, dof);
    // 2. Mean ratio per colour region (pixels are independent, so variances add).
    let mut ratios = String::new();
    let mut region_bad = None;
    for k in 0..2 {
        let (mut m, mut mw, mut v, mut cnt) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3], 0.0);
        for p in (0..idx.len()).filter(|&p| idx[p] == k) {
            for c in 0..3 {
                m[c] += f64::from(img.data[p][c]);
                mw[c] += f64::from(want.data[p][c]);
                v[c] += f64::from(var.data[p][c]);
            }
            cnt += 1.0;
        }
        for c in 0..3 {
            let ratio = m[c] / mw[c];
            let se = v[c].sqrt() / mw[c];
            ratios += &format!(" c{k}[{c}] {ratio:.5} (se {se:.1e})");
            if ((ratio - 1.0) / se).abs() > 4.0 && region_bad.is_none() {
                region_bad = Some(format!(
                    "color{k} channel {c}: mean ratio {ratio:.5}, {:.1} standard errors from 1 ({cnt} pixels)",
                    (ratio - 1.0) / se
                ));
            }
        }
    }
    // 3. Nearest colour.
    let misplaced = img
        .data
        .iter()
        .zip(&idx)
        .filter(|(a, &k)| {
            let d = |c: [f64; 3]| {
                (0..3)
                    .map(|i| (f64::from(a[i]) - c[i] * L).powi(2))
                    .sum::<f64>()
            };
            let (own, other) = if k == 0 { (C0, C1) } else { (C1, C0) };
            d(own) >= d(other)
        })
        .count();
    let summary = format!(
        "{}: max |z| {worst:.2} at {worst_at:?} (threshold {z_max:.2}), chi2 {chi2:.0} on {dof} (p {chi2_p:.3}), misplaced pixels {misplaced};{ratios}",
        e.name
    );
    if worst > z_max || chi2_p < 1e-3 || region_bad.is_some() || misplaced > 0 {
        Err(format!("{summary}; {}", region_bad.unwrap_or_default()))
    } else {
        Ok(summary)
    }
}

fn render_scene(name: &str, extra: &[&str]) -> (Image, Image) {
    let dir = scratch(name);
    let path = dir.join("scene.xml");
    std::fs::write(&path, scene()).unwrap();
    // Filter importance sampling: every sample at its pixel's centre (see the module doc).
    let args = [&["--reconstruction", "importance"][..], extra].concat();
    render(&path, &dir, name, &args)
}

#[test]
fn setup_keeps_pixel_centres_away_from_cell_edges() {
    // Cell edges are where U or V is a multiple of 1/2; pixel centres must be at least 0.25
    // pixel from them (pixels are 1/32 world units; du/dx = 1/4, dv/dy = 1/4).
    let mut margin = f64::INFINITY;
    for j in 0..H {
        for i in 0..W {
            let (u, v) = pixel_uv(i, j);
            let (uu, vv) = (SU * u + TU, SV * v + TV);
            let du = ((uu * 2.0).round() - uu * 2.0).abs() / 2.0; // in U units
            let dv = ((vv * 2.0).round() - vv * 2.0).abs() / 2.0;
            margin = margin.min(du / SU * 4.0 * 32.0).min(dv / SV * 4.0 * 32.0);
        }
    }
    assert!(
        margin > 0.25,
        "a pixel centre is {margin:.3} px from a cell edge"
    );
}

#[test]
fn checkerboard_reflectance_is_rho_times_l_where_mitsuba_puts_it() {
    let (img, var) = render_scene("texture_closed_form", &["--spp", SPP]);
    let right = Expectation {
        name: "Mitsuba eval",
        index: Box::new(mitsuba_index),
        scale: 1.0,
    };
    let verdict = judge(&img, &var, &right);
    eprintln!("{}", verdict.as_ref().unwrap_or_else(|e| e));
    assert!(verdict.is_ok(), "{}", verdict.unwrap_err());

    let wrong = [
        Expectation {
            name: "colours swapped (eval_1 convention)",
            index: Box::new(|u, v| 1 - mitsuba_index(u, v)),
            scale: 1.0,
        },
        Expectation {
            name: "v flipped",
            index: Box::new(|u, v| mitsuba_index(u, 1.0 - v)),
            scale: 1.0,
        },
        Expectation {
            name: "u and v transposed",
            index: Box::new(|u, v| mitsuba_index(v, u)),
            scale: 1.0,
        },
        Expectation {
            name: "L * 1.01",
            index: Box::new(mitsuba_index),
            scale: 1.01,
        },
    ];
    for e in &wrong {
        match judge(&img, &var, e) {
            Err(msg) => eprintln!("fails as it should: {msg}"),
            Ok(msg) => panic!("the check cannot tell '{}' from the render: {msg}", e.name),
        }
    }
}

#[test]
fn bsdf_sampling_alone_gives_rho_times_l_exactly() {
    // Cosine-weighted sampling of a Lambertian BSDF weighs every sample by exactly rho, and every
    // sampled direction sees L: no noise, so every pixel is rho L to float rounding.
    let (img, _) = render_scene(
        "texture_closed_form_bsdf",
        &["--spp", "16", "--strategy", "bsdf"],
    );
    let right = Expectation {
        name: "Mitsuba eval",
        index: Box::new(mitsuba_index),
        scale: 1.0,
    };
    let (want, _) = expected_image(&right);
    let worst = img
        .data
        .iter()
        .zip(&want.data)
        .flat_map(|(a, w)| (0..3).map(move |c| (f64::from(a[c]) / f64::from(w[c]) - 1.0).abs()))
        .fold(0.0f64, f64::max);
    assert!(
        worst < 1e-5,
        "largest relative deviation from rho L: {worst:.2e}"
    );
}
