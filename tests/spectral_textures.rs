//! glTF base colour textures in spectral mode: each texel upsampled once at load (Jakob & Hanika
//! 2019, `crates/pt-render/src/spectral_texture.rs`), looked up through the same texture
//! transform as in RGB mode.

use crate::common;

use common::*;
use std::path::PathBuf;

fn asset(name: &str) -> PathBuf {
    repo().join("scenes/gltf").join(name)
}

/// scenes/gltf/textures.gltf and textures-flat.gltf: a plane with a 1x2 base colour texture
/// (texture transform on one of them, not on the other) and a metallic-roughness texture,
/// under the default white environment.
/// 1. In spectral mode the transformed and the flat file render the same image (same seed, so
///    the same paths and wavelengths; 1e-4 relative): the spectral lookup uses the transform.
/// 2. With the base colour factor set to 1, one bounce (max depth 2) under the white (D65)
///    environment reflects exactly the colour the upsampling inverts (a reflectance under D65),
///    so spectral and RGB images agree: per channel, image means within 4 combined standard
///    errors plus 3e-3 relative (the fit's 1e-3 round trip and D65's 2e-3 white point). The
///    threshold is asserted to be below 2%, so a 2% error fails.
#[test]
fn base_colour_textures_render_in_spectral_mode() {
    let dir = scratch("spectral_textures");
    let spectral = [
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "16",
        "--seed",
        "3",
        "--max-depth",
        "3",
        "--mode",
        "spectral",
    ];
    let (a, _) = render(&asset("textures.gltf"), &dir, "rotated", &spectral);
    let (b, _) = render(&asset("textures-flat.gltf"), &dir, "flat", &spectral);
    for (i, (p, q)) in a.data.iter().zip(&b.data).enumerate() {
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 1e-4 * q[c].abs().max(1e-3),
                "pixel {i} channel {c}: transformed {} vs flat {}",
                p[c],
                q[c]
            );
        }
    }
    let mut d: serde_json::Value =
        serde_json::from_slice(&std::fs::read(asset("textures-flat.gltf")).unwrap()).unwrap();
    d["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] =
        serde_json::json!([1.0, 1.0, 1.0, 1.0]);
    let white = dir.join("white-factor.gltf");
    std::fs::write(&white, serde_json::to_vec_pretty(&d).unwrap()).unwrap();
    let args = |mode: &'static str| {
        [
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "256",
            "--max-depth",
            "2",
            "--mode",
            mode,
        ]
    };
    let (s, sv) = render(&white, &dir, "spectral", &args("spectral"));
    let (r, rv) = render(&white, &dir, "rgb", &args("rgb"));
    let ((ms, ss), (mr, sr)) = (mean_and_stderr(&s, &sv), mean_and_stderr(&r, &rv));
    eprintln!("spectral {ms:?} +- {ss:?}, rgb {mr:?} +- {sr:?}");
    for c in 0..3 {
        let tol = 4.0 * (ss[c] * ss[c] + sr[c] * sr[c]).sqrt() + 3e-3 * mr[c];
        assert!(
            tol < 0.02 * mr[c],
            "channel {c}: threshold {tol} would not detect a 2% error of {}",
            mr[c]
        );
        assert!(
            (ms[c] - mr[c]).abs() <= tol,
            "channel {c}: spectral {} vs rgb {} (threshold {tol})",
            ms[c],
            mr[c]
        );
    }
}
