//! Mitsuba's `aov` integrator (issue 20, item 8): the channels of `scenes/aov.xml` against
//! Mitsuba 3.9.1's (`references/aov_channels.exr`, every channel of its film at 4096 spp, written
//! by `references/make_references.py aov`); the image itself is judged by tests/references.rs.

use crate::common;

use common::*;
use std::collections::HashMap;
use std::path::Path;

type Channels = HashMap<String, Vec<f32>>;

fn read(path: &Path) -> (usize, usize, Channels) {
    let (w, h, c) =
        pt_image::read_exr_channels(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (w as usize, h as usize, c.into_iter().collect())
}

fn render_aov(dir: &Path, name: &str, scene: &Path, args: &[&str]) -> Channels {
    render_channels(scene, dir, name, args)
        .into_iter()
        .collect()
}

/// The `p`-quantile of `v` (sorted copy).
fn quantile(v: &[f64], p: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((s.len() - 1) as f64 * p).round() as usize]
}

/// Every AOV channel agrees with Mitsuba's, by three statistics per channel, each relative to
/// the channel's scale s (the 95th percentile of |reference|). An AOV is a filter-weighted
/// mean of per-sample values that vary within a pixel only by the quantity's gradient, except
/// where a pixel straddles an edge (a silhouette, a facet or texel boundary), where the
/// samples' split decides it; so at 256 spp most pixels agree to rounding and edge pixels
/// scatter. (1) The median |difference| over the image below 1e-3 s (measured: at most
/// 1.2e-4 s; measuring depth from the camera instead of Mitsuba's near plane gives 1.6e-3 s,
/// a 10% albedo error 3.5e-2 s). (2) The mean signed difference below 1e-3 s: a bias (measured
/// at most 1.3e-4 s; edge noise averages out over 6912 pixels). (3) On interior pixels (the
/// reference's 3x3 neighbourhood on one shape with depth varying less than 10%), the 99th
/// percentile below 1.5e-2 s (measured at most 1.06e-2 s, the torus's facets in the
/// geometric normal; writing the geometric normal as the shading normal gives 2.8e-2 s).
/// `shape_index` is compared as a partition (Mitsuba numbers its objects in an order that
/// differs between its own variants): each of pt's indices maps to one of Mitsuba's.
#[test]
fn aov_channels_agree_with_mitsuba() {
    let dir = scratch("aov_mitsuba");
    let ours = render_aov(
        &dir,
        "aov",
        &repo().join("scenes/aov.xml"),
        &["--spp", "256"],
    );
    let (w, h, reference) = read(&repo().join("references/aov_channels.exr"));
    let mut names: Vec<&String> = reference.keys().collect();
    names.sort();
    let mut ours_names: Vec<&String> = ours.keys().collect();
    ours_names.sort();
    assert_eq!(names, ours_names, "pt writes Mitsuba's channels");

    let (si, depth) = (&reference["si.I"], &reference["dd.y.T"]);
    let interior: Vec<usize> = (1..h - 1)
        .flat_map(|y| (1..w - 1).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let around = |p: &[f32]| -> Vec<f32> {
                (y - 1..=y + 1)
                    .flat_map(|yy| (x - 1..=x + 1).map(move |xx| p[yy * w + xx]))
                    .collect()
            };
            let (s, d) = (around(si), around(depth));
            let centre = s[4];
            centre > 0.5
                && centre.fract() == 0.0
                && s.iter().all(|&v| v == centre)
                && d.iter().cloned().fold(f32::MIN, f32::max)
                    - d.iter().cloned().fold(f32::MAX, f32::min)
                    < 0.1 * d[4]
        })
        .map(|(x, y)| y * w + x)
        .collect();
    assert!(interior.len() > 500, "{} interior pixels", interior.len());

    for name in names {
        if ["R", "G", "B", "si.I"].contains(&name.as_str()) || name.starts_with("my_image.") {
            continue;
        }
        let (a, r) = (&ours[name], &reference[name]);
        let abs_r: Vec<f64> = r.iter().map(|&v| f64::from(v.abs())).collect();
        let s = quantile(&abs_r, 0.95).max(1e-6);
        let d: Vec<f64> = a.iter().zip(r).map(|(&x, &y)| f64::from(x - y)).collect();
        let abs_d: Vec<f64> = d.iter().map(|v| v.abs()).collect();
        let median = quantile(&abs_d, 0.5) / s;
        let mean = (d.iter().sum::<f64>() / d.len() as f64).abs() / s;
        let inner: Vec<f64> = interior.iter().map(|&i| abs_d[i]).collect();
        let p99 = quantile(&inner, 0.99) / s;
        assert!(median < 1e-3, "{name}: median |d| = {median:.2e} s");
        assert!(mean < 1e-3, "{name}: mean d = {mean:.2e} s");
        assert!(p99 < 1.5e-2, "{name}: interior 99th percentile {p99:.2e} s");
    }

    // The image's copy under the nested integrator's name, and its alpha (an environment
    // light is visible: 1 everywhere).
    assert_eq!(ours["my_image.R"], ours["R"]);
    assert!(ours["my_image.A"].iter().all(|&a| a == 1.0));

    // shape_index: a partition of the pixels that hit one shape only, the same as Mitsuba's.
    let mut map: HashMap<(i32, i32), usize> = HashMap::new();
    for (&a, &r) in ours["si.I"].iter().zip(&reference["si.I"]) {
        if a.fract() == 0.0 && r.fract() == 0.0 {
            *map.entry((a as i32, r as i32)).or_default() += 1;
        }
    }
    for pt_index in 0..=4 {
        let counts: Vec<usize> = (0..=4)
            .filter_map(|m| map.get(&(pt_index, m)).copied())
            .collect();
        let total: usize = counts.iter().sum();
        let most = counts.iter().copied().max().unwrap_or(0);
        assert!(total > 100, "shape {pt_index} covers {total} pixels");
        assert!(
            most as f64 > 0.97 * total as f64,
            "shape {pt_index} maps to {counts:?}"
        );
    }
}

/// Without a nested integrator the `aov` integrator renders its outputs alone: the image's
/// channels are zero (Mitsuba's), and the AOVs the same as with one (the same camera rays).
#[test]
fn aovs_alone() {
    let dir = scratch("aovs_alone");
    let xml = std::fs::read_to_string(repo().join("scenes/aov.xml")).expect("scene");
    let start = xml.find("<integrator type=\"path\"").expect("nested");
    let end = xml[start..].find("</integrator>").expect("end") + start + "</integrator>".len();
    // The scene's meshes by absolute path, so that the copy can live in the scratch folder.
    let meshes = repo().join("scenes/meshes/");
    let alone = format!("{}{}", &xml[..start], &xml[end..])
        .replace("value=\"meshes/", &format!("value=\"{}", meshes.display()));
    let path = dir.join("aovs-alone.xml");
    std::fs::write(&path, alone).expect("write");
    let c = render_aov(&dir, "alone", &path, &["--spp", "4"]);
    let full = render_aov(
        &dir,
        "full",
        &repo().join("scenes/aov.xml"),
        &["--spp", "4"],
    );
    assert!(c["R"].iter().chain(&c["G"]).all(|&v| v == 0.0));
    assert!(!c.contains_key("my_image.R"));
    for name in ["dd.y.T", "nn.X", "uv.U", "alb.G", "pi.I"] {
        assert_eq!(c[name], full[name], "{name}");
    }
}
