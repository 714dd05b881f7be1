//! Textures that change the BSDF over a surface, end to end: normal maps (the XML `normalmap`
//! against a closed form, glTF `normalTexture` against the XML path on the same mesh and
//! texture) and glTF iridescence thickness textures (against constant-thickness films).
//!
//! 1. **Closed form.** A constant normal map tilting the normal by `a` (40 degrees) towards
//!    local +x (red channel) or +y (green channel) on a Lambertian plane of albedo rho, under a
//!    directional light of irradiance E arriving at 60 degrees from the geometric normal in the
//!    tilt plane, seen from straight above. Mitsuba 3.9.1's `normalmap` (pt-bsdf `normal_map`)
//!    gives the radiance
//!    L = rho / pi * E * cos(theta_l - a) * G,
//!    G = 2 / (1 + sqrt(1 + min(tan^2 a / 8, 1) tan^2 theta_l))  (Conty Estevez et al. 2019),
//!    here with `a` the tilt of the 8-bit texel actually stored (the PNG quantises the normal).
//!    The plane is the only object and the light is a delta light found only by next-event
//!    estimation, so the image is exactly this constant (no noise): the mean must match to 0.2%.
//!    Unperturbed shading (cos 60 = 0.5 vs cos 20 = 0.94), a missing G (6%), or a swapped or
//!    negated channel (the light would be 100 degrees from the normal: black) all fail.
//! 2. **glTF = XML.** The same quad (a glTF file, uvs upright: v = 0 at the top) rendered as
//!    `pt render quad.gltf` with `normalTexture` and as `<shape type="gltf">` inside an XML
//!    `normalmap`, with the committed scenes/textures/bumps-normal.png (stripes tilted in x, a
//!    dome, stripes tilted in y), once with a TANGENT attribute and once with generated tangents.
//!    At a grid of points the world-space shading normal the BSDF sees must agree to 1e-4 (it is
//!    the same computation up to rounding when the tangent is dp/du with w = +1, which holds for
//!    this layout); the maps must also really perturb (some normal tilted by > 30 degrees), so an
//!    ignored map cannot pass. A flipped green channel or handedness breaks the dome's and the
//!    y-stripes' agreement by up to 70 degrees.

use crate::common;

use common::*;
use pt_math::{Frame, Ray, Vec3};
use pt_render::{BvhKind, LightSelection, Scene};
use pt_spectrum::SampledWavelengths;
use std::path::Path;

/// Writes a 2x2 PNG of the normal `n` encoded as (n + 1) / 2 in 8 bits; returns the decoded
/// (quantised) normal, normalised.
fn constant_map(path: &Path, n: [f64; 3]) -> [f64; 3] {
    let c = n.map(|x| ((x + 1.0) * 0.5 * 255.0).round().clamp(0.0, 255.0) as u8);
    image::RgbImage::from_pixel(2, 2, image::Rgb(c))
        .save(path)
        .unwrap();
    let q = c.map(|v| 2.0 * v as f64 / 255.0 - 1.0);
    let l = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
    q.map(|x| x / l)
}

#[test]
fn constant_tilt_matches_closed_form() {
    let (a, theta_l, rho, e) = (40f64.to_radians(), 60f64.to_radians(), 0.7, 2.0);
    // (name, map normal, direction towards the light), local frame of the rectangle = world.
    let cases = [
        (
            "x",
            [a.sin(), 0.0, a.cos()],
            [theta_l.sin(), 0.0, theta_l.cos()],
        ),
        (
            "y",
            [0.0, a.sin(), a.cos()],
            [0.0, theta_l.sin(), theta_l.cos()],
        ),
    ];
    for (name, n, l) in cases {
        let dir = scratch(&format!("normal_map_closed_{name}"));
        let nq = constant_map(&dir.join("n.png"), n);
        let sensor = sensor_xml(10.0, [0.0, 0.0, 10.0], 4, 8, 8);
        let xml = format!(
            r#"<scene version="3.0.0">
    <integrator type="path"/>
    {sensor}
    <emitter type="directional"><vector name="direction" value="{}, {}, {}"/><rgb name="irradiance" value="{e}, {e}, {e}"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5, 5, 1"/></transform>
        <bsdf type="normalmap">
            <texture type="bitmap" name="normalmap"><string name="filename" value="n.png"/><boolean name="raw" value="true"/></texture>
            <bsdf type="diffuse"><rgb name="reflectance" value="{rho}, {rho}, {rho}"/></bsdf>
        </bsdf>
    </shape>
</scene>"#,
            -l[0], -l[1], -l[2]
        );
        let path = dir.join("scene.xml");
        std::fs::write(&path, xml).unwrap();
        let (img, var) = render(&path, &dir, "out", &["--spp", "4"]);
        let (m, _) = mean_and_stderr(&img, &var);
        let cos_p = nq[0] * l[0] + nq[1] * l[1] + nq[2] * l[2];
        let tan2_n = (nq[0] * nq[0] + nq[1] * nq[1]) / (nq[2] * nq[2]);
        let alpha2 = (tan2_n / 8.0).min(1.0);
        let g = 2.0 / (1.0 + (1.0 + alpha2 * theta_l.tan().powi(2)).sqrt());
        let want = rho / std::f64::consts::PI * e * cos_p * g;
        eprintln!("{name}: got {m:?}, want {want:.6} (cos' {cos_p:.4}, G {g:.4})");
        for c in m {
            assert!(
                (c - want).abs() <= 2e-3 * want,
                "tilt in {name}: {c} vs closed form {want}"
            );
        }
    }
}

/// The world-space shading normal the BSDF sees at the first hit of a ray straight down at
/// (x, y), or `None` on a miss.
fn shading_normal(scene: &Scene, x: f32, y: f32) -> Option<Vec3> {
    let ray = Ray::new(Vec3::new(x, y, 5.0), Vec3::NEG_Z);
    let hit = scene.intersect(&ray)?;
    let b = scene.bsdf(&hit, &SampledWavelengths::sample_visible(0.5));
    let local = Frame::from_normal_tangent(hit.ns, hit.dpdu);
    let n = b.normal.expect("normal-mapped material");
    Some(local.to_world(pt_bsdf::normal_map::frame(n, local.to_local(-ray.dir)).n))
}

/// A glTF quad (-1..1)^2 in z = 0, normal +z, uv (0, 0) at the top left (x = -1, y = 1), with
/// the normal texture `bumps-normal.png` beside it, optionally a TANGENT attribute (+x, w = 1).
/// Returns the JSON and the binary buffer (`quad.bin`).
fn quad_gltf(with_tangents: bool) -> (String, Vec<u8>) {
    let material = r#"{"normalTexture": {"index": 0}, "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 1}}"#;
    quad_gltf_with(
        with_tangents,
        material,
        r#"[{"source": 0}]"#,
        r#"[{"uri": "bumps-normal.png"}]"#,
        "",
    )
}

/// The quad of [`quad_gltf`] with the given material, textures, images and extra top-level
/// members (JSON text).
fn quad_gltf_with(
    with_tangents: bool,
    material: &str,
    textures: &str,
    images: &str,
    extra: &str,
) -> (String, Vec<u8>) {
    let pos: [[f32; 3]; 4] = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let nrm = [[0.0f32, 0.0, 1.0]; 4];
    let uv: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let tan = [[1.0f32, 0.0, 0.0, 1.0]; 4];
    let idx: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bytes = Vec::new();
    pos.iter()
        .flatten()
        .chain(nrm.iter().flatten())
        .chain(uv.iter().flatten())
        .chain(tan.iter().flatten())
        .for_each(|f| bytes.extend_from_slice(&f.to_le_bytes()));
    idx.iter()
        .for_each(|i| bytes.extend_from_slice(&i.to_le_bytes()));
    let tangent_attr = if with_tangents {
        r#", "TANGENT": 3"#
    } else {
        ""
    };
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2{tangent_attr}}}, "indices": 4, "material": 0}}]}}],
  "materials": [{material}], "textures": {textures}, "images": {images} {extra},
  "buffers": [{{"byteLength": {len}, "uri": "quad.bin"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
                  {{"buffer": 0, "byteOffset": 96, "byteLength": 32}}, {{"buffer": 0, "byteOffset": 128, "byteLength": 64}},
                  {{"buffer": 0, "byteOffset": 192, "byteLength": 12}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]}},
                {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
                {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}},
                {{"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC4"}},
                {{"bufferView": 4, "componentType": 5123, "count": 6, "type": "SCALAR"}}]}}"#,
        len = bytes.len()
    );
    (json, bytes)
}

#[test]
fn gltf_normal_texture_matches_xml_normalmap() {
    for with_tangents in [true, false] {
        let dir = scratch(&format!("normal_map_gltf_{with_tangents}"));
        std::fs::copy(
            repo().join("scenes/textures/bumps-normal.png"),
            dir.join("bumps-normal.png"),
        )
        .unwrap();
        let (json, bin) = quad_gltf(with_tangents);
        std::fs::write(dir.join("quad.gltf"), json).unwrap();
        std::fs::write(dir.join("quad.bin"), bin).unwrap();
        let xml = r#"<scene version="3.0.0">
    <sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>
    <shape type="gltf">
        <string name="filename" value="quad.gltf"/>
        <bsdf type="normalmap">
            <texture type="bitmap" name="normalmap"><string name="filename" value="bumps-normal.png"/><boolean name="raw" value="true"/></texture>
            <bsdf type="diffuse"/>
        </bsdf>
    </shape>
</scene>"#;
        std::fs::write(dir.join("scene.xml"), xml).unwrap();
        let xml_desc = pt_scene::load_file(&dir.join("scene.xml"), &[]).expect("XML scene loads");
        let gltf = pt_scene::gltf::load(
            &dir.join("quad.gltf"),
            &pt_scene::gltf::LoadOptions::default(),
        )
        .expect("glTF loads");
        assert!(
            !gltf.warnings.iter().any(|w| w.contains("normalTexture")),
            "{:?}",
            gltf.warnings
        );
        let a = Scene::build(&xml_desc, BvhKind::default(), LightSelection::Power).unwrap();
        let b = Scene::build(&gltf.desc, BvhKind::default(), LightSelection::Power).unwrap();
        let (mut max_dev, mut max_tilt) = (0.0f32, 0.0f32);
        for i in 0..48 {
            for j in 0..48 {
                let (x, y) = (
                    -0.98 + 1.96 * (i as f32 + 0.5) / 48.0,
                    -0.98 + 1.96 * (j as f32 + 0.5) / 48.0,
                );
                let (na, nb) = (
                    shading_normal(&a, x, y).unwrap(),
                    shading_normal(&b, x, y).unwrap(),
                );
                max_dev = max_dev.max((na - nb).length());
                max_tilt = max_tilt.max(na.angle_between(Vec3::Z));
            }
        }
        eprintln!("tangents given {with_tangents}: max |n_xml - n_gltf| = {max_dev:e}, max tilt {:.1} deg", max_tilt.to_degrees());
        assert!(max_tilt > 30f32.to_radians(), "the map does not perturb");
        assert!(
            max_dev < 1e-4,
            "glTF and XML shading normals differ by {max_dev}"
        );
    }
}

/// The BSDF values at a hit straight down at (x, y) for a few direction pairs (local frame).
fn bsdf_values(scene: &Scene, x: f32, y: f32, lambda: &SampledWavelengths) -> Vec<[f32; 4]> {
    let hit = scene
        .intersect(&Ray::new(Vec3::new(x, y, 5.0), Vec3::NEG_Z))
        .expect("hit");
    let b = scene.bsdf(&hit, lambda);
    let dirs = [
        Vec3::new(0.3, 0.1, 0.9),
        Vec3::new(-0.2, 0.3, 0.9),
        Vec3::new(0.6, -0.2, 0.5),
        Vec3::new(-0.5, -0.4, 0.6),
    ];
    let mut out = Vec::new();
    for wo in dirs {
        for wi in dirs {
            out.push(b.eval(wo.normalize(), wi.normalize()).0.to_array());
        }
    }
    out
}

/// glTF `iridescenceThicknessTexture` (2 x 1 texels, nearest: green 0 on the left half of the
/// quad, 1 on the right) with thickness range 200..600 nm: at every point of each half the BSDF
/// must equal, lane for lane, that of the same material without the texture and
/// `iridescenceThicknessMaximum` 200 (left) or 600 (right), i.e. each half renders as the
/// constant-thickness film of its thickness. The halves must differ from each other (so a
/// texture that is ignored or read from the wrong channel fails); tolerance 1e-5 relative, the
/// same computation up to rounding.
#[test]
fn iridescence_thickness_texture_gives_constant_films_per_texel() {
    let dir = scratch("iridescence_thickness_texture");
    image::RgbImage::from_fn(2, 1, |x, _| {
        image::Rgb([128, if x == 0 { 0 } else { 255 }, 30])
    })
    .save(dir.join("thickness.png"))
    .unwrap();
    let iridescence = |thickness_max: f32, texture: bool| {
        let tex = if texture {
            r#", "iridescenceThicknessTexture": {"index": 0}"#
        } else {
            ""
        };
        format!(
            r#"{{"pbrMetallicRoughness": {{"baseColorFactor": [0.9, 0.8, 0.7, 1], "metallicFactor": 1, "roughnessFactor": 0.5}},
               "extensions": {{"KHR_materials_iridescence": {{"iridescenceFactor": 1, "iridescenceIor": 1.3,
               "iridescenceThicknessMinimum": 200, "iridescenceThicknessMaximum": {thickness_max}{tex}}}}}}}"#
        )
    };
    let extra = r#", "samplers": [{"magFilter": 9728, "minFilter": 9728}], "extensionsUsed": ["KHR_materials_iridescence"]"#;
    let load = |name: &str, material: String| {
        let (json, bin) = quad_gltf_with(
            false,
            &material,
            r#"[{"source": 0, "sampler": 0}]"#,
            r#"[{"uri": "thickness.png"}]"#,
            extra,
        );
        std::fs::write(dir.join(format!("{name}.gltf")), json).unwrap();
        std::fs::write(dir.join("quad.bin"), bin).unwrap();
        let g = pt_scene::gltf::load(
            &dir.join(format!("{name}.gltf")),
            &pt_scene::gltf::LoadOptions::default(),
        )
        .expect("glTF loads");
        assert!(
            !g.warnings.iter().any(|w| w.contains("iridescence")),
            "{:?}",
            g.warnings
        );
        Scene::build(&g.desc, BvhKind::default(), LightSelection::Power).unwrap()
    };
    let textured = load("textured", iridescence(600.0, true));
    let (thin, thick) = (
        load("thin", iridescence(200.0, false)),
        load("thick", iridescence(600.0, false)),
    );
    let lambda = SampledWavelengths::sample_visible(0.37);
    let close = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| (x - y).abs() <= 1e-5 * x.abs().max(y.abs()) + 1e-9)
    };
    for (x, y) in [(-0.7, 0.3), (-0.2, -0.8), (0.2, 0.5), (0.9, -0.9)] {
        let got = bsdf_values(&textured, x, y, &lambda);
        let want = bsdf_values(if x < 0.0 { &thin } else { &thick }, x, y, &lambda);
        let other = bsdf_values(if x < 0.0 { &thick } else { &thin }, x, y, &lambda);
        assert!(close(&got, &want), "at ({x}, {y}): {got:?} vs {want:?}");
        assert!(
            !close(&got, &other),
            "at ({x}, {y}) the two thicknesses give the same BSDF: the test cannot tell them apart"
        );
    }
}

/// Mean of the left and right image halves per channel, with their standard errors.
fn half_means(img: &pt_image::Image, var: &pt_image::Image) -> [([f64; 3], [f64; 3]); 2] {
    let w = img.width as usize;
    std::array::from_fn(|half| {
        let (mut m, mut v, mut n) = ([0.0f64; 3], [0.0f64; 3], 0.0);
        for (i, (p, q)) in img.data.iter().zip(&var.data).enumerate() {
            if ((i % w) < w / 2) == (half == 0) {
                n += 1.0;
                for c in 0..3 {
                    m[c] += p[c] as f64;
                    v[c] += q[c] as f64;
                }
            }
        }
        (m.map(|x| x / n), v.map(|x| x.sqrt() / n))
    })
}

/// XML `mask` with `<texture name="opacity">` (2 x 1 texels, nearest, raw): the left texel is
/// pure red, opacity = its Rec. 709 luminance 0.212671 (Mitsuba's `eval_1`, checked with its
/// Python bindings), the right one grey 128/255. A two-sided diffuse plane of albedo rho under a
/// constant environment of radiance 1, seen straight on, has L = a rho + (1 - a) per half (the
/// closed form of tests/media.rs per texel). Threshold as there: 4.5 standard errors plus 2e-4,
/// standard error below 0.25% of the value, so a 2% bias (an opacity from the red channel, 1.0,
/// or the mean of the channels, 0.333, instead of the luminance) fails.
#[test]
fn mask_opacity_texture_is_luminance_per_texel() {
    let dir = scratch("mask_opacity_texture");
    image::RgbImage::from_fn(2, 1, |x, _| {
        if x == 0 {
            image::Rgb([255, 0, 0])
        } else {
            image::Rgb([128, 128, 128])
        }
    })
    .save(dir.join("opacity.png"))
    .unwrap();
    let rho = 0.4;
    let sensor = sensor_xml(20.0, [0.0, 0.0, 10.0], 16, 16, 16);
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"/>
    {sensor}
    <emitter type="constant"><float name="radiance" value="1"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5, 5, 1"/></transform>
        <bsdf type="mask">
            <texture type="bitmap" name="opacity">
                <string name="filename" value="opacity.png"/><boolean name="raw" value="true"/><string name="filter_type" value="nearest"/>
            </texture>
            <bsdf type="twosided"><bsdf type="diffuse"><float name="reflectance" value="{rho}"/></bsdf></bsdf>
        </bsdf>
    </shape>
</scene>"#
    );
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let (img, var) = render(&path, &dir, "out", &["--spp", "1024"]);
    // Image left = world -x (camera +x is image left, Mitsuba's convention) = u < 1/2 = texel 0.
    let opacity = [0.212671f64, 128.0 / 255.0];
    for (half, (m, se)) in half_means(&img, &var).into_iter().enumerate() {
        let want = opacity[half] * rho + (1.0 - opacity[half]);
        for c in 0..3 {
            eprintln!(
                "half {half} channel {c}: got {:.5} want {want:.5} (stderr {:.2e})",
                m[c], se[c]
            );
            assert!(
                se[c] < 0.0025 * want,
                "standard error {} too large to detect a 2% bias",
                se[c]
            );
            assert!(
                (m[c] - want).abs() <= 4.5 * se[c] + 2e-4,
                "half {half} channel {c}: {} vs closed form {want}",
                m[c]
            );
        }
    }
}

/// glTF base colour texture alpha (2 x 1 texels, nearest: alpha 77/255 left, 1 right) times
/// `baseColorFactor` alpha 0.8: BLEND gives opacity 0.8 x alpha per texel, MASK (cutoff 0.5)
/// 0 left (0.24 < 0.5) and 1 right (0.8 >= 0.5), exactly (the opacity the BSDF carries at the
/// hit); the texture's colour still reaches the base colour (the BSDFs of the halves differ).
#[test]
fn gltf_base_colour_alpha_is_opacity_per_texel() {
    let dir = scratch("gltf_alpha_texture");
    image::RgbaImage::from_fn(2, 1, |x, _| {
        if x == 0 {
            image::Rgba([200, 50, 50, 77])
        } else {
            image::Rgba([50, 50, 200, 255])
        }
    })
    .save(dir.join("base.png"))
    .unwrap();
    let extra = r#", "samplers": [{"magFilter": 9728, "minFilter": 9728}]"#;
    for (mode, want) in [
        ("BLEND", [0.8 * 77.0 / 255.0, 0.8f32]),
        ("MASK", [0.0, 1.0]),
    ] {
        let material = format!(
            r#"{{"alphaMode": "{mode}", "pbrMetallicRoughness": {{"baseColorFactor": [1, 1, 1, 0.8], "baseColorTexture": {{"index": 0}}, "metallicFactor": 0, "roughnessFactor": 0.6}}}}"#
        );
        let (json, bin) = quad_gltf_with(
            false,
            &material,
            r#"[{"source": 0, "sampler": 0}]"#,
            r#"[{"uri": "base.png"}]"#,
            extra,
        );
        std::fs::write(dir.join("quad.gltf"), json).unwrap();
        std::fs::write(dir.join("quad.bin"), bin).unwrap();
        let g = pt_scene::gltf::load(
            &dir.join("quad.gltf"),
            &pt_scene::gltf::LoadOptions::default(),
        )
        .expect("glTF loads");
        assert!(
            !g.warnings.iter().any(|w| w.contains("alpha")),
            "{:?}",
            g.warnings
        );
        let scene = Scene::build(&g.desc, BvhKind::default(), LightSelection::Power).unwrap();
        let lambda = SampledWavelengths::sample_visible(0.5);
        let at = |x: f32| {
            scene.bsdf(
                &scene
                    .intersect(&Ray::new(Vec3::new(x, 0.3, 5.0), Vec3::NEG_Z))
                    .unwrap(),
                &lambda,
            )
        };
        let (l, r) = (at(-0.5), at(0.5));
        assert!(
            (l.opacity - want[0]).abs() < 1e-5 && (r.opacity - want[1]).abs() < 1e-5,
            "{mode}: opacity {} / {}, want {want:?}",
            l.opacity,
            r.opacity
        );
        let (wo, wi) = (
            Vec3::new(0.1, 0.2, 0.9).normalize(),
            Vec3::new(-0.3, 0.1, 0.8).normalize(),
        );
        let (fl, fr) = (l.bsdf.eval(wo, wi).0, r.bsdf.eval(wo, wi).0);
        assert!(
            fl.x > 1.5 * fl.z && fr.z > 1.5 * fr.x,
            "{mode}: base colour texture not applied: {fl} / {fr}"
        );
    }
}

/// glTF partial factors become blends (pt-gltf's "Partial factors"): transmissionFactor 0.4 on
/// a material of metallic 0.25 (thin-walled) gives `(1 - w) metallic-roughness + w thin
/// dielectric` with w = 0.4 x 0.75 = 0.3; iridescenceFactor 0.6 gives `0.4 material + 0.6 film`.
/// Checked on the BSDF the hit carries: the blend weight and the second model's type, and the
/// blend's value equals the weighted sum of the two models' values (so the weight is used the
/// right way round).
#[test]
fn gltf_partial_factors_are_blends() {
    let dir = scratch("gltf_partial_factors");
    image::RgbImage::from_pixel(1, 1, image::Rgb([255, 255, 255]))
        .save(dir.join("white.png"))
        .unwrap();
    let cases = [
        (
            r#"{"pbrMetallicRoughness": {"metallicFactor": 0.25, "roughnessFactor": 0.5}, "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.4}}}"#,
            "KHR_materials_transmission",
            0.3f32,
        ),
        (
            r#"{"pbrMetallicRoughness": {"metallicFactor": 1, "roughnessFactor": 0.5}, "extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 0.6, "iridescenceThicknessMaximum": 350}}}"#,
            "KHR_materials_iridescence",
            0.6,
        ),
    ];
    for (material, ext, w) in cases {
        let extra = format!(r#", "extensionsUsed": ["{ext}"]"#);
        let (json, bin) = quad_gltf_with(
            false,
            material,
            r#"[{"source": 0}]"#,
            r#"[{"uri": "white.png"}]"#,
            &extra,
        );
        std::fs::write(dir.join("quad.gltf"), json).unwrap();
        std::fs::write(dir.join("quad.bin"), bin).unwrap();
        let g = pt_scene::gltf::load(
            &dir.join("quad.gltf"),
            &pt_scene::gltf::LoadOptions::default(),
        )
        .expect("glTF loads");
        let scene = Scene::build_with_mode(
            &g.desc,
            BvhKind::default(),
            LightSelection::Power,
            Some(pt_spectrum::ColorMode::Rgb),
        )
        .unwrap();
        let b = scene.bsdf(
            &scene
                .intersect(&Ray::new(Vec3::new(0.1, 0.2, 5.0), Vec3::NEG_Z))
                .unwrap(),
            &SampledWavelengths::sample_visible(0.5),
        );
        let (weight, second) = b.blend.unwrap_or_else(|| panic!("{ext}: no blend: {b:?}"));
        assert!(
            (weight - w).abs() < 1e-6,
            "{ext}: weight {weight}, want {w}"
        );
        match ext {
            "KHR_materials_transmission" => assert!(
                matches!(second, pt_bsdf::Bsdf::ThinDielectric(_)),
                "{second:?}"
            ),
            _ => assert!(
                matches!(second, pt_bsdf::Bsdf::RoughThinFilm(_)),
                "{second:?}"
            ),
        }
        let (wo, wi) = (
            Vec3::new(0.2, 0.1, 0.9).normalize(),
            Vec3::new(-0.3, 0.2, 0.8).normalize(),
        );
        let first = pt_bsdf::SurfaceBsdf { blend: None, ..*b };
        let only_second = pt_bsdf::SurfaceBsdf {
            bsdf: second,
            blend: None,
            ..*b
        };
        let want = first.eval(wo, wi).0 * (1.0 - w) + only_second.eval(wo, wi).0 * w;
        assert!(
            (b.eval(wo, wi).0 - want).abs().max_element() < 1e-6 * want.max_element().max(1.0),
            "{ext}"
        );
    }
}

/// glTF `iridescenceTexture` (2 x 1 texels, nearest: red 0 left, 1 right) with factor 0.8: the
/// blend weight of the film is 0 on the left half and 0.8 on the right, exactly.
#[test]
fn gltf_iridescence_texture_scales_the_blend_weight_per_texel() {
    let dir = scratch("gltf_iridescence_factor_texture");
    image::RgbImage::from_fn(2, 1, |x, _| {
        image::Rgb([if x == 0 { 0 } else { 255 }, 90, 40])
    })
    .save(dir.join("factor.png"))
    .unwrap();
    let material = r#"{"pbrMetallicRoughness": {"metallicFactor": 1, "roughnessFactor": 0.5}, "extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 0.8, "iridescenceTexture": {"index": 0}}}}"#;
    let extra = r#", "samplers": [{"magFilter": 9728, "minFilter": 9728}], "extensionsUsed": ["KHR_materials_iridescence"]"#;
    let (json, bin) = quad_gltf_with(
        false,
        material,
        r#"[{"source": 0, "sampler": 0}]"#,
        r#"[{"uri": "factor.png"}]"#,
        extra,
    );
    std::fs::write(dir.join("quad.gltf"), json).unwrap();
    std::fs::write(dir.join("quad.bin"), bin).unwrap();
    let g = pt_scene::gltf::load(
        &dir.join("quad.gltf"),
        &pt_scene::gltf::LoadOptions::default(),
    )
    .expect("glTF loads");
    assert!(
        !g.warnings.iter().any(|w| w.contains("iridescence")),
        "{:?}",
        g.warnings
    );
    let scene = Scene::build(&g.desc, BvhKind::default(), LightSelection::Power).unwrap();
    let lambda = SampledWavelengths::sample_visible(0.5);
    for (x, want) in [(-0.5f32, 0.0f32), (0.5, 0.8)] {
        let b = scene.bsdf(
            &scene
                .intersect(&Ray::new(Vec3::new(x, -0.2, 5.0), Vec3::NEG_Z))
                .unwrap(),
            &lambda,
        );
        let (w, second) = b.blend.expect("a blend");
        assert!(
            (w - want).abs() < 1e-6 && matches!(second, pt_bsdf::Bsdf::RoughThinFilm(_)),
            "x {x}: weight {w}, want {want}"
        );
    }
}

/// `pt info` describes wrapper materials in one readable line each (the wrapper, its texture's
/// file name, the inner model), not as nested debug dumps with source locations.
#[test]
fn info_describes_wrapper_materials() {
    let o = pt(&[
        "info",
        repo().join("scenes/normal-map.xml").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains(
            "normalmap(bitmap(bumps-normal.png, raw), Mitsuba tangent space, scale 1, Diffuse"
        ),
        "{out}"
    );
    assert!(
        out.contains("normalmap(bitmap(bumps-normal.png, raw), Mitsuba tangent space, scale 1, RoughConductor"),
        "{out}"
    );
    assert!(!out.contains("SourceLoc"), "{out}");
    let o = pt(&[
        "info",
        repo().join("scenes/mask-texture.xml").to_str().unwrap(),
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("mask(opacity bitmap("), "{out}");
    assert!(!out.contains("SourceLoc"), "{out}");
}
