//! The film's `pixel_format` (issue 20, item 5): the channels written, their conversion from
//! the same samples, and the alpha channel against Mitsuba 3.9.1.

use crate::common;

use common::*;
use std::path::Path;

/// The plane of channel `name`.
fn plane<'a>(channels: &'a [(String, Vec<f32>)], name: &str) -> &'a [f32] {
    &channels
        .iter()
        .find(|c| c.0 == name)
        .unwrap_or_else(|| panic!("no channel {name} in {:?}", names(channels)))
        .1
}

fn names(channels: &[(String, Vec<f32>)]) -> Vec<&str> {
    channels.iter().map(|c| c.0.as_str()).collect()
}

/// A small scene whose film writes `$pf`, optionally with a constant environment.
fn format_scene(dir: &Path, environment: &str, hide: bool) -> std::path::PathBuf {
    let xml = format!(
        r#"<scene version="3.0.0">
    <default name="pf" value="rgb"/>
    <integrator type="path"><boolean name="hide_emitters" value="{hide}"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0.5, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="16"/>
            <string name="pixel_format" value="$pf"/></film>
    </sensor>
    <emitter type="point"><point name="position" x="1" y="2" z="2"/><rgb name="intensity" value="8, 6, 3"/></emitter>
    {environment}
    <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.8"/></bsdf></shape>
</scene>"#
    );
    let path = dir.join("format.xml");
    std::fs::write(&path, xml).expect("write scene");
    path
}

/// Every pixel format writes Mitsuba's channel names, and its channels are the same samples'
/// linear sRGB converted exactly: Y = 0.212671 R + 0.715160 G + 0.072169 B and X, Z by the
/// rows of the sRGB-to-XYZ matrix (Mitsuba's `luminance` and `srgb_to_xyz`). The same seed
/// gives the same samples, so the only difference is float rounding (1e-5 relative).
#[test]
fn formats_are_the_same_samples_converted() {
    let dir = scratch("formats");
    let scene = format_scene(&dir, "", false);
    let rgb = render_channels(&scene, &dir, "rgb", &[]);
    assert_eq!(names(&rgb), ["B", "G", "R"]);
    let (r, g, b) = (plane(&rgb, "R"), plane(&rgb, "G"), plane(&rgb, "B"));
    let rows = [
        ("X", [0.412453f32, 0.357580, 0.180423]),
        ("Y", [0.212671, 0.715160, 0.072169]),
        ("Z", [0.019334, 0.119193, 0.950227]),
    ];
    let close = |got: f32, want: f32| (got - want).abs() <= 1e-5 * want.abs().max(1e-3);
    for (format, expected) in [
        ("luminance", &["Y"][..]),
        ("luminance_alpha", &["A", "Y"]),
        ("xyz", &["X", "Y", "Z"]),
        ("xyza", &["A", "X", "Y", "Z"]),
        ("rgba", &["A", "B", "G", "R"]),
    ] {
        let c = render_channels(&scene, &dir, format, &["-D", &format!("pf={format}")]);
        assert_eq!(names(&c), expected, "{format}");
        for (name, m) in rows {
            if !expected.contains(&name) {
                continue;
            }
            for (i, &v) in plane(&c, name).iter().enumerate() {
                let want = m[0] * r[i] + m[1] * g[i] + m[2] * b[i];
                assert!(close(v, want), "{format} {name} pixel {i}: {v} vs {want}");
            }
        }
        if format == "rgba" {
            assert_eq!(plane(&c, "R"), r);
        }
    }
}

/// Alpha's closed forms: without an environment a pixel whose every sample misses the ball
/// has alpha exactly 0 and one whose samples all hit it exactly 1 (the ball's interior); a
/// visible environment covers every pixel (alpha 1 everywhere, Mitsuba's rule), and a hidden
/// one does not.
#[test]
fn alpha_closed_forms() {
    let dir = scratch("alpha_closed_forms");
    let a = |env: &str, hide: bool, name: &str| -> Vec<f32> {
        let scene = format_scene(&dir, env, hide);
        plane(
            &render_channels(&scene, &dir, name, &["-D", "pf=rgba"]),
            "A",
        )
        .to_vec()
    };
    let env = r#"<emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>"#;
    let plain = a("", false, "plain");
    let (w, h) = (24, 16);
    assert_eq!(plain[0], 0.0, "a corner sees nothing");
    assert_eq!(plain[(h / 2) * w + w / 2], 1.0, "the ball's centre");
    assert!(plain.iter().all(|&v| (0.0..=1.0).contains(&v)));
    assert!(a(env, false, "env").iter().all(|&v| v == 1.0));
    let hidden = a(env, true, "hidden");
    assert_eq!(hidden[0], 0.0, "a hidden environment does not cover");
    assert_eq!(hidden, plain, "the same samples cover the same pixels");
}

/// The alpha channel of `alpha.xml` (a masked card, a thin glass pane and a `null` cube over
/// nothing, a ball and a disk) agrees with Mitsuba 3.9.1's (`references/alpha.exr`, 4096 spp,
/// channel A). Alpha is a mean of 0/1 values, so a pixel's variance at 256 spp is at most
/// 1/(4 256); a 4x4 block mean averages about 16 x 256 samples (splats shared between
/// neighbours make it a little less independent), standard error at most 0.5/64 = 0.008 for
/// pt and 0.002 for the reference. The threshold 0.05 is six of them, over 384 blocks.
/// Counting the card's holes as cover (alpha from 0.4 to 1 on the card), the pane's
/// transmission (from 0.09 to 1) or the cube (from 0 to 1) moves whole blocks by 0.5 or more
/// (the first checked: block differences of 1.0). The image itself is judged by
/// tests/references.rs, where keeping the light that uncovered samples gathered (what
/// Mitsuba's `volpath` does, not its `path`) fails 24 of 60 block-channels.
#[test]
fn alpha_agrees_with_mitsuba() {
    let dir = scratch("alpha_mitsuba");
    let ours = render_channels(
        &repo().join("scenes/alpha.xml"),
        &dir,
        "alpha",
        &["--spp", "256"],
    );
    let (w, h, reference) = pt_image::read_exr_channels(&repo().join("references/alpha.exr"))
        .expect("references/alpha.exr");
    let (a, r) = (plane(&ours, "A"), plane(&reference, "A"));
    assert_eq!(a.len(), (w * h) as usize);
    let (bw, bh) = (w as usize / 4, h as usize / 4);
    let mut worst = (0.0f64, 0, 0);
    for by in 0..bh {
        for bx in 0..bw {
            let mut d = 0.0f64;
            for y in 4 * by..4 * by + 4 {
                for x in 4 * bx..4 * bx + 4 {
                    let i = y * w as usize + x;
                    d += f64::from(a[i] - r[i]) / 16.0;
                }
            }
            if d.abs() > worst.0 {
                worst = (d.abs(), bx, by);
            }
        }
    }
    assert!(
        worst.0 < 0.05,
        "alpha block ({}, {}) differs by {:.4}",
        worst.1,
        worst.2,
        worst.0
    );
    let mean = |p: &[f32]| p.iter().map(|&v| f64::from(v)).sum::<f64>() / p.len() as f64;
    // Whole-image mean: standard error below 0.5 / sqrt(6144 x 256) = 4e-4.
    assert!(
        (mean(a) - mean(r)).abs() < 3e-3,
        "{} vs {}",
        mean(a),
        mean(r)
    );
}

/// A method without alpha (radiosity) refuses a film that asks for it before rendering, with
/// the scene named and exit code 2, and writes nothing.
#[test]
fn radiosity_refuses_alpha() {
    let dir = scratch("radiosity_alpha");
    let scene = format_scene(&dir, "", false);
    let out = dir.join("r.exr");
    let o = pt(&[
        "render",
        scene.to_str().expect("utf-8"),
        "-D",
        "pf=rgba",
        "--integrator",
        "radiosity",
        "-o",
        out.to_str().expect("utf-8"),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("format.xml") && err.contains("alpha"), "{err}");
    assert!(!out.exists());
}
