//! glTF 2.0 input: the assets of scenes/gltf/ (written by scenes/gltf/make_gltf.py) against
//! closed forms, `pt info`'s listing, and bad input (exit code 2, no output file).

use crate::common;

use common::*;
use pt_bsdf::GltfPbr;
use pt_math::Vec3;
use pt_spectrum::SampledSpectrum;
use std::path::{Path, PathBuf};

fn asset(name: &str) -> PathBuf {
    repo().join("scenes/gltf").join(name)
}

/// scenes/gltf/lights.gltf: a 6 x 6 m plane (y = 0, normal +y, glTF metallic-roughness with
/// base colour 0.6, metallic 0, roughness 0.5) seen from (0, 4, 0) straight down (yfov 50 deg,
/// square image: image right is +x, image top is -z), lit by a KHR_lights_punctual point light
/// (5 cd, colour (1, 0.5, 0.25), at (0.7, 1.5, -0.4)), a spot light (8 cd at (0, 2, 0) pointing
/// down, inner cone 15 deg, outer 30 deg) and a directional light (3 lx travelling along
/// (0.6, -0.8, 0)).
///
/// Each pixel must equal the box-filter footprint average of
/// `L = sum over lights f(wo, wi) E_light(x)` with `E = I cos(theta_i) / d^2` (point, spot
/// times the renderer's falloff: full inside the inner cone, linear in angle to 0 at the outer
/// cone) and `E = E0 cos(theta_i)` (directional), `f` the BRDF evaluated by pt-bsdf (tested on
/// its own in crates/pt-bsdf/tests/gltf_pbr.rs). Photometric units are used 1:1 (pt-gltf's
/// documentation), so a cd is an intensity of 1. This checks the loader's node transforms
/// (light positions and directions, the camera's axes and field of view), the unit mapping and
/// the material mapping at once: a light pointing the wrong way, a factor 683 or 4 pi, or a
/// swapped image axis fails by far more than the tolerance.
///
/// Each light is checked alone (a copy of the file whose scene lists the plane, the camera and
/// that light's node): with several lights, next-event estimation picks one per sample, and a
/// pixel whose 64 samples all picked the same light reports a variance of 0, which a per-pixel
/// z-test cannot use (the sum of lights is the renderer's NEE, tested in tests/lights_analytic.rs
/// and the reference scenes).
///
/// Tolerance as in tests/lights_analytic.rs: 4.5 standard errors per pixel (the larger of the
/// render's own estimate and the one implied by the footprint's variance at 64 spp) plus 2e-4
/// relative for quadrature and float32 rounding, and the image mean within 0.2%.
#[test]
fn punctual_lights_match_closed_form() {
    for which in ["point", "spot", "directional"] {
        check_light(which);
    }
}

/// Renders lights.gltf with only the light node `which` (plane and camera kept) and checks
/// every pixel against the closed form of that light.
fn check_light(which: &str) {
    const W: u32 = 24;
    const SPP: f64 = 64.0;
    let h_cam = 4.0f64;
    let tan = (25.0f64).to_radians().tan();
    let f = GltfPbr::new(SampledSpectrum::from_rgb([0.6; 3]), 0.0, 0.5, 1.5);
    // Local shading frame of the plane: normal +y -> z; isotropic, so any tangent will do.
    let local = |v: [f64; 3]| Vec3::new(v[0] as f32, v[2] as f32, v[1] as f32);
    let norm = |v: [f64; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / l, v[1] / l, v[2] / l]
    };
    let radiance = |x: f64, z: f64| -> [f64; 3] {
        let wo = local(norm([-x, h_cam, -z]));
        let mut l = [0.0f64; 3];
        if which == "point" {
            let (px, ph, pz, i) = (0.7, 1.5, -0.4, 5.0);
            let d2 = (px - x) * (px - x) + ph * ph + (pz - z) * (pz - z);
            let fv = f64::from(f.eval(wo, local(norm([px - x, ph, pz - z]))).0.x);
            let e = i * ph / d2.powf(1.5);
            for (c, col) in [1.0, 0.5, 0.25].iter().enumerate() {
                l[c] += fv * e * col;
            }
        }
        if which == "spot" {
            let (sh, si, outer, inner) = (2.0f64, 8.0f64, 30.0f64, 15.0f64);
            let d2 = x * x + sh * sh + z * z;
            let angle = (sh / d2.sqrt()).acos().to_degrees();
            let fall = if angle <= inner {
                1.0
            } else if angle >= outer {
                0.0
            } else {
                (outer - angle) / (outer - inner)
            };
            let fv = f64::from(f.eval(wo, local(norm([-x, sh, -z]))).0.x);
            for lc in &mut l {
                *lc += fv * si * fall * sh / d2.powf(1.5);
            }
        }
        if which == "directional" {
            // Travelling along (0.6, -0.8, 0): wi = (-0.6, 0.8, 0).
            let fv = f64::from(f.eval(wo, local([-0.6, 0.8, 0.0])).0.x);
            for lc in &mut l {
                *lc += fv * 3.0 * 0.8;
            }
        }
        l
    };
    let dir = scratch(&format!("gltf_lights_{which}"));
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(asset("lights.gltf")).unwrap()).unwrap();
    let node = ["point", "spot", "directional"]
        .iter()
        .position(|w| *w == which)
        .unwrap()
        + 2;
    doc["scenes"][0]["nodes"] = serde_json::json!([0, 1, node]);
    let (img, var) = render(
        &write_json(&dir, "one-light.gltf", &doc),
        &dir,
        "out",
        &[
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "64",
            "--max-depth",
            "2",
        ],
    );
    let n = 16;
    let (mut sum_got, mut sum_want) = (0.0, 0.0);
    for py in 0..W {
        for px in 0..W {
            let (mut want, mut want_sq) = ([0.0f64; 3], [0.0f64; 3]);
            for j in 0..n {
                for i in 0..n {
                    let u = (px as f64 + (i as f64 + 0.5) / n as f64) / W as f64;
                    let v = (py as f64 + (j as f64 + 0.5) / n as f64) / W as f64;
                    let (x, z) = (h_cam * (2.0 * u - 1.0) * tan, h_cam * (2.0 * v - 1.0) * tan);
                    let l = if x.abs() <= 3.0 && z.abs() <= 3.0 {
                        radiance(x, z)
                    } else {
                        [0.0; 3]
                    };
                    for c in 0..3 {
                        want[c] += l[c] / (n * n) as f64;
                        want_sq[c] += l[c] * l[c] / (n * n) as f64;
                    }
                }
            }
            let (got, sd) = (img.get(px, py), var.get(px, py));
            for c in 0..3 {
                let footprint_var = (want_sq[c] - want[c] * want[c]).max(0.0) / SPP;
                let tol =
                    4.5 * (sd[c] as f64).max(footprint_var).sqrt() + 2e-4 * want[c].abs() + 1e-7;
                assert!(
                    (got[c] as f64 - want[c]).abs() <= tol,
                    "{which}: pixel ({px}, {py}) channel {c}: got {} want {} (tol {tol:.3e})",
                    got[c],
                    want[c]
                );
                sum_got += got[c] as f64;
                sum_want += want[c];
            }
        }
    }
    assert!(
        (sum_got / sum_want - 1.0).abs() < 2e-3,
        "{which}: mean ratio {}",
        sum_got / sum_want
    );
}

/// The loader's mapping of the glass block (KHR_materials_volume): attenuationColor c reached
/// after attenuationDistance d means exp(-sigma_t d) = c, so sigma_t = -ln(c)/d per channel;
/// transmission with a volume maps to a smooth dielectric of the KHR_materials_ior index.
#[test]
fn volume_maps_to_beer_lambert_sigma_t() {
    let g = pt_scene::gltf::load(&asset("glass-block.glb"), &Default::default())
        .expect("load glass-block.glb");
    let s = &g.desc.shapes[0];
    let m = s
        .interior
        .as_ref()
        .expect("the slab has an interior medium");
    let pt_scene::SpectrumDesc::Rgb(sigma) = m.sigma_t else {
        panic!("sigma_t {:?}", m.sigma_t)
    };
    for (c, col) in [0.8f32, 0.5, 0.2].iter().enumerate() {
        let want = -col.ln() / 0.5;
        assert!(
            (sigma[c] - want).abs() < 1e-5 * want,
            "channel {c}: {} vs {want}",
            sigma[c]
        );
    }
    assert!(
        matches!(g.desc.bsdfs[s.bsdf].kind, pt_scene::BsdfKind::Dielectric { int_ior, ext_ior, .. } if int_ior == 1.5 && ext_ior == 1.0)
    );
    assert!(
        g.warnings.iter().any(|w| w.contains("default environment")),
        "{:?}",
        g.warnings
    );
}

/// `pt info` on each asset lists the materials with the extensions they use and what each maps
/// to, the lights, the cameras and the colour mode (thin film makes the iridescent sphere
/// spectral).
#[test]
fn info_lists_mapping_lights_cameras_and_mode() {
    let text = |name: &str| {
        let o = pt(&["info", asset(name).to_str().unwrap()]);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        (
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (out, _) = text("lights.gltf");
    for want in [
        "point at",
        "spot at",
        "directional towards",
        "gltf metallic-roughness",
        "camera 0: node 1, perspective",
        "mode        rgb",
    ] {
        assert!(
            out.contains(want),
            "lights.gltf info lacks '{want}':\n{out}"
        );
    }
    let (out, err) = text("iridescence.gltf");
    for want in [
        "KHR_materials_iridescence",
        "thinfilm: 450 nm film of ior 1.33",
        "mode        spectral",
    ] {
        assert!(
            out.contains(want),
            "iridescence.gltf info lacks '{want}':\n{out}"
        );
    }
    assert!(
        err.contains("default environment"),
        "no default-light note on stderr: {err}"
    );
    let (out, _) = text("glass-block.glb");
    for want in [
        "KHR_materials_transmission",
        "KHR_materials_volume",
        "sigma_t",
        "dielectric, ior 1.5",
    ] {
        assert!(
            out.contains(want),
            "glass-block.glb info lacks '{want}':\n{out}"
        );
    }
}

/// Writes `doc` (JSON) to `dir/name` and returns the path.
fn write_json(dir: &Path, name: &str, doc: &serde_json::Value) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_vec_pretty(doc).unwrap()).unwrap();
    p
}

/// Bad glTF input fails cleanly: exit code 2, a message naming the file and what is wrong, and
/// no output file. An unsupported *optional* extension only warns, naming it.
#[test]
fn bad_gltf_exits_2_without_output() {
    let dir = scratch("gltf_bad");
    let good: serde_json::Value =
        serde_json::from_slice(&std::fs::read(asset("lights.gltf")).unwrap()).unwrap();
    let mut cases: Vec<(PathBuf, &str)> = Vec::new();

    let p = dir.join("malformed.gltf");
    std::fs::write(&p, b"{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ ").unwrap();
    cases.push((p, "malformed glTF"));

    let glb = std::fs::read(asset("glass-block.glb")).unwrap();
    let p = dir.join("truncated.glb");
    std::fs::write(&p, &glb[..glb.len() * 2 / 3]).unwrap();
    cases.push((p, "malformed glTF"));

    // A buffer shorter than its byteLength (truncated data URI).
    let mut d = good.clone();
    let uri = d["buffers"][0]["uri"].as_str().unwrap().to_string();
    d["buffers"][0]["uri"] = serde_json::Value::String(uri[..uri.len() - 40].to_string());
    cases.push((write_json(&dir, "short-buffer.gltf", &d), "buffers[0]"));

    // An index to an accessor that does not exist.
    let mut d = good.clone();
    d["meshes"][0]["primitives"][0]["indices"] = 99.into();
    cases.push((
        write_json(&dir, "bad-accessor-index.gltf", &d),
        "Index out of bounds",
    ));

    // An accessor that claims more elements than its buffer view holds.
    let mut d = good.clone();
    d["accessors"][0]["count"] = 1000.into();
    cases.push((
        write_json(&dir, "accessor-overrun.gltf", &d),
        "need more than",
    ));

    // Vertex indices beyond the vertex count (POSITION says 3 vertices, the triangles use 4).
    let mut d = good.clone();
    for a in [0, 1, 2] {
        d["accessors"][a]["count"] = 3.into();
    }
    d["accessors"][0]["min"] = serde_json::json!([-3.0, 0.0, -3.0]);
    cases.push((
        write_json(&dir, "vertex-index.gltf", &d),
        "out of range for 3 vertices",
    ));

    let mut d = good.clone();
    d["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual", "KHR_draco_mesh_compression"]);
    d["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
    cases.push((
        write_json(&dir, "required-ext.gltf", &d),
        "KHR_draco_mesh_compression",
    ));

    let mut d = good.clone();
    d["buffers"][0]["uri"] = "missing.bin".into();
    cases.push((write_json(&dir, "missing-buffer.gltf", &d), "missing.bin"));

    for (path, want) in &cases {
        let out = dir.join("out.exr");
        let o = pt(&[
            "render",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--spp",
            "1",
            "--quiet",
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{}: exit {:?}, stderr {err}",
            path.display(),
            o.status.code()
        );
        assert!(
            err.contains(want),
            "{}: stderr lacks '{want}': {err}",
            path.display()
        );
        assert!(
            err.contains(path.file_name().unwrap().to_str().unwrap()),
            "{}: message does not name the file: {err}",
            path.display()
        );
        assert!(
            !out.exists(),
            "{}: an output file was written",
            path.display()
        );
        let o = pt(&["info", path.to_str().unwrap()]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "info {}: exit {:?}",
            path.display(),
            o.status.code()
        );
    }

    // Optional unsupported extension: rendered, with a warning naming it.
    let mut d = good.clone();
    d["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual", "KHR_materials_sheen"]);
    let p = write_json(&dir, "optional-ext.gltf", &d);
    let out = dir.join("optional.exr");
    let o = pt(&[
        "render",
        p.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "1",
        "--width",
        "8",
        "--height",
        "8",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("KHR_materials_sheen"),
        "no warning naming the extension"
    );
    assert!(out.exists());

    // --camera out of range is bad input too.
    let o = pt(&[
        "render",
        asset("lights.gltf").to_str().unwrap(),
        "-o",
        dir.join("c.exr").to_str().unwrap(),
        "--camera",
        "3",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!dir.join("c.exr").exists());
}

/// scenes/gltf/iridescence.gltf: a unit sphere (a 24 x 48 UV mesh with exact vertex normals)
/// with KHR_materials_iridescence (450 nm film of index 1.33 on a dielectric base, metallic 0,
/// ior 1.5, roughness 0), seen from (0, 0, 4) (yfov 32 deg) and lit only by the default environment
/// (constant radiance 1). The film is smooth and its base opaque, so a camera ray that hits the
/// sphere at cos(theta) sees exactly the film's reflectance R(cos theta) times the environment
/// (the mirror ray leaves the convex sphere). With `--mode rgb`, R is the thin-film model's
/// Belcour-Barla RGB reflectance; the base is the loader's documented mapping for a
/// non-metal: an opaque base of index n = ior = 1.5, k = 0 (the diffuse base is dropped).
///
/// Compared per pixel on pixels whose whole footprint hits the sphere at cos(theta) > 0.5, with
/// the footprint average of R at the analytic sphere; tolerance 4.5 standard errors (render and
/// footprint) plus 0.3% relative for the mesh: the flat triangles move the hit point by at most
/// the sagitta 1 - cos(3.75 deg) = 2e-3 of the radius, which changes cos(theta) by about that
/// much. A film thickness or index taken from the wrong field, the angle outside instead of inside
/// the film, or a wrong base index changes R by far more (R oscillates between about 0.02 and
/// 0.2 with angle and wavelength here).
#[test]
fn iridescent_sphere_reflects_thin_film_r() {
    use pt_bsdf::{FilmBase, ThinFilm};
    const W: u32 = 32;
    let n_base = 1.5f32;
    let film = ThinFilm::rgb(
        450.0,
        1.33,
        1.0,
        FilmBase::Conductor {
            eta: SampledSpectrum::from_rgb([n_base; 3]),
            k: SampledSpectrum::from_rgb([0.0; 3]),
        },
    );
    let tan = 16.0f64.to_radians().tan();
    // cos(theta) at the analytic unit sphere for film position (u, v), or None on a miss.
    let cos_at = |u: f64, v: f64| -> Option<f64> {
        let d = [(2.0 * u - 1.0) * tan, (1.0 - 2.0 * v) * tan, -1.0];
        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let d = [d[0] / l, d[1] / l, d[2] / l];
        let b = 4.0 * d[2]; // o.d with o = (0, 0, 4)
        let disc = b * b - 15.0;
        if disc < 0.0 {
            return None;
        }
        let t = -b - disc.sqrt();
        let p = [t * d[0], t * d[1], 4.0 + t * d[2]];
        Some(-(d[0] * p[0] + d[1] * p[1] + d[2] * p[2]))
    };
    let dir = scratch("gltf_iridescence");
    let (img, var) = render(
        &asset("iridescence.gltf"),
        &dir,
        "out",
        &[
            "--width", "32", "--height", "32", "--spp", "64", "--mode", "rgb",
        ],
    );
    let n = 8;
    let mut checked = 0;
    for py in 0..W {
        'px: for px in 0..W {
            let (mut want, mut want_sq) = ([0.0f64; 3], [0.0f64; 3]);
            for j in 0..n {
                for i in 0..n {
                    let u = (px as f64 + (i as f64 + 0.5) / n as f64) / W as f64;
                    let v = (py as f64 + (j as f64 + 0.5) / n as f64) / W as f64;
                    let Some(c) = cos_at(u, v).filter(|c| *c > 0.5) else {
                        continue 'px;
                    };
                    let r = film.reflectance(c as f32).rgb();
                    for k in 0..3 {
                        want[k] += f64::from(r[k]) / (n * n) as f64;
                        want_sq[k] += f64::from(r[k]).powi(2) / (n * n) as f64;
                    }
                }
            }
            let (got, sd) = (img.get(px, py), var.get(px, py));
            for k in 0..3 {
                let footprint_var = (want_sq[k] - want[k] * want[k]).max(0.0) / 64.0;
                let tol = 4.5 * (sd[k] as f64).max(footprint_var).sqrt() + 3e-3 * want[k];
                assert!(
                    (got[k] as f64 - want[k]).abs() <= tol,
                    "pixel ({px}, {py}) channel {k}: got {} want {} (tol {tol:.2e})",
                    got[k],
                    want[k]
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 200, "only {checked} pixels checked");
}

/// Textures (scenes/gltf/textures*.gltf, under the default white environment, same seed):
/// 1. textures.gltf (a 2 x 1 base colour texture rotated 90 degrees by KHR_texture_transform)
///    and textures-flat.gltf (the 1 x 2 texture that rotation should produce, no transform)
///    render the same image: nearest lookups of the same texels along the same paths, so the
///    images agree to float rounding (1e-4 relative allowed per pixel). A rotation applied
///    the other way, or offset/scale ignored, swaps the two colours (a 5x difference).
/// 2. The top half of the image (v < 1/2, texel sRGB (20, 60, 240)) equals a plane without
///    textures whose factors are the glTF factors times the decoded texels: base colour
///    factor x sRGB-decoded texel, roughness x green/255, metallic x blue/255 of the linear
///    metallic-roughness texture. This checks the sRGB decoding (IEC 61966-2-1; no decoding
///    would be 2-10x off), the channel assignment and that factors multiply.
#[test]
fn textures_follow_uv_transform_srgb_and_factors() {
    let dir = scratch("gltf_textures");
    let args = [
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
    ];
    let (a, _) = render(&asset("textures.gltf"), &dir, "rotated", &args);
    let (b, _) = render(&asset("textures-flat.gltf"), &dir, "flat", &args);
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
    let srgb = |c: f64| {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let mut d: serde_json::Value =
        serde_json::from_slice(&std::fs::read(asset("textures-flat.gltf")).unwrap()).unwrap();
    let pbr = &mut d["materials"][0]["pbrMetallicRoughness"];
    let factor = [0.8, 1.0, 0.9];
    let texel = [20.0, 60.0, 240.0];
    pbr["baseColorFactor"] = serde_json::json!([
        factor[0] * srgb(texel[0] / 255.0),
        factor[1] * srgb(texel[1] / 255.0),
        factor[2] * srgb(texel[2] / 255.0),
        1.0
    ]);
    pbr["metallicFactor"] = serde_json::json!(0.5 * 255.0 / 255.0);
    pbr["roughnessFactor"] = serde_json::json!(0.9 * 128.0 / 255.0);
    let obj = pbr.as_object_mut().unwrap();
    obj.remove("baseColorTexture");
    obj.remove("metallicRoughnessTexture");
    let plain = write_json(&dir, "plain.gltf", &d);
    let (c, _) = render(&plain, &dir, "plain", &args);
    for y in 0..7 {
        for x in 0..16 {
            let (p, q) = (a.get(x, y), c.get(x, y));
            for k in 0..3 {
                assert!(
                    (p[k] - q[k]).abs() <= 1e-4 * q[k].abs().max(1e-3),
                    "pixel ({x}, {y}) channel {k}: textured {} vs factors {}",
                    p[k],
                    q[k]
                );
            }
        }
    }
}

/// `<shape type="gltf">` in a Mitsuba XML scene: the plane of lights.gltf placed with a diffuse
/// BSDF renders the same image (to float rounding, 1e-5 relative; same seed, so the same paths)
/// as Mitsuba's `rectangle` covering the same square, under a point light. A glTF shape whose
/// file is bad fails the XML scene with exit code 2, naming the glTF file.
#[test]
fn xml_gltf_shape_places_the_mesh() {
    let dir = scratch("gltf_xml_shape");
    let scene = |shape: &str| {
        format!(
            r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0, 4, 0" target="0, 0, 0" up="0, 0, -1"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film>
    </sensor>
    {shape}
    <emitter type="point"><point name="position" value="0.7, 1.5, -0.4"/><rgb name="intensity" value="5"/></emitter>
</scene>"#
        )
    };
    let bsdf = r#"<bsdf type="diffuse"><float name="reflectance" value="0.6"/></bsdf>"#;
    let rect = dir.join("rect.xml");
    std::fs::write(&rect, scene(&format!(r#"<shape type="rectangle"><transform name="to_world"><scale value="3, 3, 1"/><rotate x="1" angle="-90"/></transform>{bsdf}</shape>"#))).unwrap();
    let gl = dir.join("gltf.xml");
    let file = asset("lights.gltf");
    std::fs::write(
        &gl,
        scene(&format!(
            r#"<shape type="gltf"><string name="filename" value="{}"/>{bsdf}</shape>"#,
            file.display()
        )),
    )
    .unwrap();
    let (a, _) = render(&rect, &dir, "rect", &[]);
    let (b, _) = render(&gl, &dir, "gltf", &[]);
    for (i, (p, q)) in a.data.iter().zip(&b.data).enumerate() {
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 1e-5 * p[c].abs().max(1e-3),
                "pixel {i}: rectangle {} vs glTF {}",
                p[c],
                q[c]
            );
        }
    }
    assert!(a.data.iter().map(|p| p[0]).sum::<f32>() > 1.0, "lit");
    let bad = dir.join("bad.gltf");
    std::fs::write(&bad, b"{ not json").unwrap();
    let badxml = dir.join("bad.xml");
    std::fs::write(
        &badxml,
        scene(&format!(
            r#"<shape type="gltf"><string name="filename" value="{}"/></shape>"#,
            bad.display()
        )),
    )
    .unwrap();
    let out = dir.join("bad.exr");
    let o = pt(&[
        "render",
        badxml.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bad.gltf") && err.contains("shape type=\"gltf\""),
        "{err}"
    );
    assert!(!out.exists());
}

/// scenes/gltf/glass-block.glb (binary glTF): a 1 m thick slab (4 x 4 m faces) of glass
/// (KHR_materials_transmission + KHR_materials_ior 1.5 + KHR_materials_volume with
/// attenuationColor (0.8, 0.5, 0.2) at attenuationDistance 0.5 m) between the camera (yfov 10
/// deg, 3 m away) and the default white environment (radiance 1, seen on both sides).
///
/// Closed form (an infinite slab; the sides are 2 m off axis and never reached at these angles):
/// a ray at incidence theta is reflected with the Fresnel factor R = F(cos theta, 1.5), and light
/// crossing the slab is attenuated by a = exp(-sigma_t d / cos theta_t) per crossing with
/// sigma_t = -ln(c)/0.5 (Beer-Lambert). Summing the front reflection and every exit after k
/// internal crossings (each side sees the same environment):
/// `L = R + (1 - R)^2 a / (1 - R a)`.
/// Compared on 4 x 4-pixel blocks (the mean of the 4 x 4 sub-pixel averages of that), within 4.5
/// standard errors (from the render's variance at 256 spp) plus 1e-3 relative, and on the image
/// mean per channel within 4.5 standard errors plus 0.1%. Not per pixel: a pixel's 256 samples
/// are a few discrete reflect/refract events with Russian roulette, heavy-tailed enough that 1%
/// of correct pixels exceed 3 standard errors (measured), while block means of 4096 samples are
/// close to normal. Without the medium the image would be 1 (R + T = 1); a sigma_t
/// from ln(c) d instead of -ln(c)/d, a missing cos theta_t or a missing Fresnel term each move the
/// channels by 2-60%.
#[test]
fn glass_block_transmits_fresnel_times_beer_lambert() {
    const W: u32 = 16;
    let dir = scratch("gltf_glass");
    let (img, var) = render(
        &asset("glass-block.glb"),
        &dir,
        "out",
        &["--width", "16", "--height", "16", "--spp", "256"],
    );
    let tan = 5.0f64.to_radians().tan();
    let sigma = [0.8f64, 0.5, 0.2].map(|c| -c.ln() / 0.5);
    let fresnel = |cos_i: f64| {
        // Unpolarised Fresnel reflectance of a dielectric interface, eta = 1.5.
        let eta = 1.5;
        let sin_t = (1.0 - cos_i * cos_i).max(0.0).sqrt() / eta;
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
        let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
        (0.5 * (rs * rs + rp * rp), cos_t)
    };
    let n = 4;
    let (mut got_sum, mut want_sum, mut var_sum) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
    const B: u32 = 4;
    let mut blocks = vec![[[0.0f64; 3]; 3]; ((W / B) * (W / B)) as usize]; // got, want, var
    for py in 0..W {
        for px in 0..W {
            let mut want = [0.0f64; 3];
            for j in 0..n {
                for i in 0..n {
                    let u = (px as f64 + (i as f64 + 0.5) / n as f64) / W as f64;
                    let v = (py as f64 + (j as f64 + 0.5) / n as f64) / W as f64;
                    let (x, y) = ((2.0 * u - 1.0) * tan, (1.0 - 2.0 * v) * tan);
                    let cos_i = 1.0 / (1.0 + x * x + y * y).sqrt();
                    let (r, cos_t) = fresnel(cos_i);
                    for c in 0..3 {
                        let a = (-sigma[c] * 1.0 / cos_t).exp();
                        want[c] += (r + (1.0 - r) * (1.0 - r) * a / (1.0 - r * a)) / (n * n) as f64;
                    }
                }
            }
            let (g, s) = (img.get(px, py), var.get(px, py));
            let b = &mut blocks[((py / B) * (W / B) + px / B) as usize];
            for c in 0..3 {
                b[0][c] += g[c] as f64;
                b[1][c] += want[c];
                b[2][c] += s[c] as f64;
                got_sum[c] += g[c] as f64;
                want_sum[c] += want[c];
                var_sum[c] += s[c] as f64;
            }
        }
    }
    for (k, b) in blocks.iter().enumerate() {
        for c in 0..3 {
            let tol = 4.5 * b[2][c].sqrt() + 1e-3 * b[1][c];
            assert!(
                (b[0][c] - b[1][c]).abs() <= tol,
                "block {k} channel {c}: got {} want {} (tol {tol:.2e}, sums of 16 pixels)",
                b[0][c],
                b[1][c]
            );
        }
    }
    for c in 0..3 {
        let se = var_sum[c].sqrt();
        assert!(
            (got_sum[c] - want_sum[c]).abs() <= 4.5 * se + 1e-3 * want_sum[c],
            "channel {c}: mean {} vs {} (se {})",
            got_sum[c] / 256.0,
            want_sum[c] / 256.0,
            se / 256.0
        );
    }
}

/// lights.gltf's plane with its lights removed and made emissive: emissiveFactor (1, 0.5, 0.25)
/// times KHR_materials_emissive_strength 4. With an emissive surface the file has a light, so
/// no default environment is added; the camera sees the plane's front side everywhere, so every
/// pixel is exactly the emitted radiance (4, 2, 1) (up to float rounding): a strength ignored
/// or applied twice fails by 4x.
#[test]
fn emissive_strength_scales_emitted_radiance() {
    let dir = scratch("gltf_emissive");
    let mut d: serde_json::Value =
        serde_json::from_slice(&std::fs::read(asset("lights.gltf")).unwrap()).unwrap();
    d["scenes"][0]["nodes"] = serde_json::json!([0, 1]);
    d["materials"][0]["emissiveFactor"] = serde_json::json!([1.0, 0.5, 0.25]);
    d["materials"][0]["extensions"] =
        serde_json::json!({"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}});
    d["extensionsUsed"] =
        serde_json::json!(["KHR_lights_punctual", "KHR_materials_emissive_strength"]);
    let p = write_json(&dir, "emissive.gltf", &d);
    let (img, _) = render(
        &p,
        &dir,
        "out",
        &["--width", "8", "--height", "8", "--spp", "4"],
    );
    for px in &img.data {
        for (c, want) in [4.0f32, 2.0, 1.0].iter().enumerate() {
            assert!((px[c] - want).abs() < 1e-4 * want, "{px:?}");
        }
    }
}

/// alphaMode BLEND as opacity: lights.gltf's plane without its lights (so the default white
/// environment lights it and is seen through it), once opaque and once with baseColorFactor
/// alpha 0.25. A camera ray meets the surface with probability 0.25 and otherwise continues to
/// the environment (radiance 1), so the blended image's mean must equal 0.25 x opaque + 0.75,
/// within 4.5 standard errors of the two means (from the variance images) plus 1e-3 relative.
/// Alpha ignored gives the opaque mean (checked to be below 0.9), alpha inverted
/// 0.25 + 0.75 x opaque.
#[test]
fn alpha_blend_is_opacity() {
    let dir = scratch("gltf_alpha");
    let mut d: serde_json::Value =
        serde_json::from_slice(&std::fs::read(asset("lights.gltf")).unwrap()).unwrap();
    d["scenes"][0]["nodes"] = serde_json::json!([0, 1]);
    let opaque = write_json(&dir, "opaque.gltf", &d);
    d["materials"][0]["alphaMode"] = "BLEND".into();
    d["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] =
        serde_json::json!([0.6, 0.6, 0.6, 0.25]);
    let blend = write_json(&dir, "blend.gltf", &d);
    let args = ["--width", "16", "--height", "16", "--spp", "256"];
    let (a, va) = render(&opaque, &dir, "opaque", &args);
    let (b, vb) = render(&blend, &dir, "blend", &args);
    let (ma, sa) = mean_and_stderr(&a, &va);
    let (mb, sb) = mean_and_stderr(&b, &vb);
    for c in 0..3 {
        let want = 0.25 * ma[c] + 0.75;
        let se = ((0.25 * sa[c]).powi(2) + sb[c].powi(2)).sqrt();
        assert!(
            (mb[c] - want).abs() <= 4.5 * se + 1e-3 * want,
            "channel {c}: blend mean {} vs 0.25 x {} + 0.75 = {want} (se {se})",
            mb[c],
            ma[c]
        );
        assert!(
            ma[c] < 0.9,
            "the opaque plane must differ from the environment: {}",
            ma[c]
        );
    }
}

/// emissiveTexture (scenes/gltf/textures-flat.gltf's 1 x 2 image, nearest: sRGB (20, 60, 240)
/// for v < 1/2, (200, 100, 50) below) times emissiveFactor (1, 0.5, 2) x
/// KHR_materials_emissive_strength 3. The plane is the only light and cannot see itself, so
/// every pixel that sees its front is exactly factor x strength x decoded texel (float rounding:
/// 1e-4 relative). Checked on the top rows (the first texel) and the bottom rows (the second):
/// a texture ignored is off by the texel (2-50x), sRGB not decoded by 2-10x, a factor or
/// strength ignored by 2-3x. In spectral mode (factor x texel in RGB, as glTF defines it, then
/// upsampled per texel) the means of the top and bottom rows must agree with RGB mode within 3%
/// of their largest channel (the top texel, (0.021, 0.067, 5.2), is a saturated blue whose small
/// channels are differences of large XYZ terms: both the round trip of its sigmoid fit and the
/// hero-wavelength noise scale with the largest channel). Multiplying the factor's and the
/// texel's spectra instead gives a red mean of 0.29 there (off by 5% of the blue); the texture
/// ignored is off by more than 50%.
#[test]
fn emissive_texture_multiplies_factor() {
    let dir = scratch("gltf_emissive_texture");
    let mut d: serde_json::Value =
        serde_json::from_slice(&std::fs::read(asset("textures-flat.gltf")).unwrap()).unwrap();
    let factor = [1.0f64, 0.5, 2.0];
    let strength = 3.0;
    d["materials"][0]["emissiveTexture"] = serde_json::json!({"index": 0});
    d["materials"][0]["emissiveFactor"] = serde_json::json!(factor);
    d["materials"][0]["extensions"] =
        serde_json::json!({"KHR_materials_emissive_strength": {"emissiveStrength": strength}});
    let used = d["extensionsUsed"].as_array().cloned().unwrap_or_default();
    let mut used: Vec<serde_json::Value> = used
        .into_iter()
        .filter(|e| e != "KHR_materials_emissive_strength")
        .collect();
    used.push("KHR_materials_emissive_strength".into());
    d["extensionsUsed"] = serde_json::Value::Array(used);
    let p = write_json(&dir, "emissive-texture.gltf", &d);
    let args = [
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "4",
        "--max-depth",
        "3",
    ];
    let (img, _) = render(&p, &dir, "rgb", &args);
    let srgb = |c: f64| {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let want = |texel: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|k| factor[k] * strength * srgb(texel[k] / 255.0))
    };
    for (rows, texel) in [(0..7, [20.0, 60.0, 240.0]), (9..16, [200.0, 100.0, 50.0])] {
        let w = want(texel);
        for y in rows {
            for x in 0..16 {
                let px = img.get(x, y);
                for k in 0..3 {
                    assert!(
                        (px[k] as f64 - w[k]).abs() <= 1e-4 * w[k],
                        "pixel ({x}, {y}) channel {k}: {} vs factor x strength x texel {}",
                        px[k],
                        w[k]
                    );
                }
            }
        }
    }
    let args_spectral = [
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "16",
        "--max-depth",
        "3",
        "--mode",
        "spectral",
    ];
    let (spec, _) = render(&p, &dir, "spectral", &args_spectral);
    for (rows, texel) in [(0..7, [20.0, 60.0, 240.0]), (9..16, [200.0, 100.0, 50.0])] {
        let w = want(texel);
        for k in 0..3 {
            let mean: f64 = rows
                .clone()
                .flat_map(|y| (0..16).map(move |x| (x, y)))
                .map(|(x, y)| spec.get(x, y)[k] as f64)
                .sum::<f64>()
                / (7.0 * 16.0);
            let scale = w.iter().cloned().fold(0.0, f64::max);
            assert!(
                (mean - w[k]).abs() < 0.03 * scale,
                "spectral rows {rows:?} channel {k}: {mean} vs {} (largest channel {scale})",
                w[k]
            );
        }
    }
}
