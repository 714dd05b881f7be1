//! Property tests (proptest) of the loaders on hostile input: the XML loader, the OBJ
//! loader and the glTF reader must return `Ok` or `Err`, never panic, whatever the bytes; and
//! what they accept must be usable: every mesh index within its vertex list, every position,
//! normal, sphere and cylinder finite, every normal unit length, every per-vertex array as long as the
//! vertex list. A crasher found would be kept here as a plain regression
//! test (proptest also records failing seeds in `tests/fuzz.proptest-regressions`). None has
//! been found in the XML and OBJ loaders: the OBJ reader checks every index against the lists
//! read before it and every number for finiteness, and the XML loader validates every number
//! it reads. The glTF properties found two panics inside the gltf crate, which the reader now
//! checks for first (the regression tests at the end).
//!
//! Case counts are proptest's default (256 per property), a few seconds in the test profile.

use proptest::prelude::*;
use pt_scene::{Geometry, SceneDesc};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A valid scene exercising most elements, mutated by the properties below.
const SCENE: &str = r#"<scene version="3.0.0">
    <default name="r" value="0.5"/>
    <integrator type="path"><integer name="max_depth" value="5"/></integrator>
    <sensor type="perspective"><float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 1, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
    </sensor>
    <bsdf type="roughconductor" id="gold"><string name="material" value="Au"/><float name="alpha" value="0.2"/></bsdf>
    <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="0" y="0.5" z="0"/><float name="radius" value="$r"/><ref id="gold"/></shape>
    <shape type="cube"><transform name="to_world"><scale x="0.2" y="0.3" z="0.2"/><translate x="1"/></transform>
        <bsdf type="thinfilm"><float name="thickness" value="300"/><float name="int_ior" value="1.5"/></bsdf></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="2"/></transform>
        <emitter type="area"><spectrum name="radiance" value="400:1, 500:2, 600:3"/></emitter></shape>
    <shape type="cylinder"><point name="p0" x="-1" y="0.2" z="0"/><point name="p1" x="-1" y="0.2" z="1"/><float name="radius" value="$r"/>
        <transform name="to_world"><rotate y="1" angle="30"/><scale value="0.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>
    <emitter type="point"><point name="position" x="1" y="2" z="1"/><float name="intensity" value="3"/></emitter>
</scene>"#;

/// Pieces inserted by the mutation property: XML syntax, hostile numbers, references.
const TOKENS: &[&str] = &[
    "<",
    ">",
    "/>",
    "\"",
    "'",
    "=",
    "&",
    "&amp;",
    "<!--",
    "-->",
    "<![CDATA[",
    "</scene>",
    "</shape>",
    "<shape type=\"obj\">",
    "<shape type=\"sphere\"/>",
    "<shape type=\"cylinder\"/>",
    "<transform name=\"to_world\">",
    "<ref id=\"gold\"/>",
    "<ref id=\"nothere\"/>",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e39",
    "-1e39",
    "1e-45",
    "0",
    "-0",
    "-1",
    "4294967296",
    "99999999999999999999",
    "$r",
    "$",
    "$$",
    " ",
    ",",
    ",,",
    "0x10",
    "\u{0}",
    "\u{feff}",
    "é",
    "<include filename=\"scene.xml\"/>",
    "<default name=\"r\" value=\"$r\"/>",
    "<lookat origin=\"0,0,0\" target=\"0,0,0\"/>",
    "<scale value=\"0\"/>",
    "<matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 0\"/>",
    "type=\"obj\"",
    "name=\"filename\" value=\"mesh.obj\"",
    "<float name=\"radius\" value=\"-1\"/>",
];

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// What an accepted scene must satisfy for the renderer to use it safely.
fn check_usable(desc: &SceneDesc) -> Result<(), String> {
    for (k, s) in desc.shapes.iter().enumerate() {
        match &s.geometry {
            Geometry::Mesh(m) => {
                let n = m.positions.len();
                if let Some(t) = m
                    .indices
                    .iter()
                    .find(|t| t.iter().any(|&i| i as usize >= n))
                {
                    return Err(format!("shape {k}: index {t:?} out of {n} vertices"));
                }
                if m.positions.iter().any(|p| !p.is_finite()) {
                    return Err(format!("shape {k}: non-finite position"));
                }
                if let Some(ns) = &m.normals {
                    if ns.len() != n
                        || ns
                            .iter()
                            .any(|v| !v.is_finite() || (v.length() - 1.0).abs() > 1e-3)
                    {
                        return Err(format!(
                            "shape {k}: {} normals for {n} vertices, or a non-unit one",
                            ns.len()
                        ));
                    }
                }
                if let Some(uv) = &m.uvs {
                    if uv.len() != n {
                        return Err(format!("shape {k}: {} uvs for {n} vertices", uv.len()));
                    }
                }
                if let Some(t) = &m.tangents {
                    if t.len() != n || t.iter().any(|t| !t.is_finite()) {
                        return Err(format!(
                            "shape {k}: {} tangents for {n} vertices, or a non-finite one",
                            t.len()
                        ));
                    }
                }
                for a in &m.attributes {
                    if a.values.len() != a.dims as usize * n
                        || a.values.iter().any(|x| !x.is_finite())
                    {
                        return Err(format!(
                            "shape {k}: attribute {} has {} values for {n} vertices",
                            a.name,
                            a.values.len()
                        ));
                    }
                }
            }
            Geometry::Curves(c) => {
                let need = c.basis.points_per_segment();
                if c.points.iter().any(|p| !p.is_finite() || p.w < 0.0)
                    || c.segments
                        .iter()
                        .any(|&s| s as usize + need > c.points.len())
                {
                    return Err(format!("shape {k}: curves with bad points or segments"));
                }
            }
            Geometry::SdfGrid(g) => {
                let n: usize = g.resolution.iter().map(|&r| r as usize).product();
                if g.resolution.iter().any(|&r| r < 2)
                    || g.values.len() != n
                    || g.values.iter().any(|v| !v.is_finite())
                    || !(g.extent.min_element() > 0.0 && g.extent.is_finite())
                    || !g.origin.is_finite()
                {
                    return Err(format!(
                        "shape {k}: sdfgrid {:?} with {} values",
                        g.resolution,
                        g.values.len()
                    ));
                }
            }
            Geometry::Sphere { center, radius, .. } => {
                if !center.is_finite() || !radius.is_finite() || *radius <= 0.0 {
                    return Err(format!("shape {k}: sphere at {center:?} radius {radius}"));
                }
            }
            Geometry::Disk(d) => {
                let area = d.area();
                if !(d.center.is_finite() && area > 0.0 && area.is_finite())
                    || (d.normal.length() - 1.0).abs() > 1e-4
                {
                    return Err(format!("shape {k}: disk {d:?}"));
                }
            }
            Geometry::Cylinder {
                p0,
                frame,
                radius,
                length,
                ..
            } => {
                let orthonormal = (frame.transpose() * *frame - glam::Mat3::IDENTITY)
                    .to_cols_array()
                    .iter()
                    .all(|x| x.abs() < 1e-4);
                let sizes = [*radius, *length];
                if !(p0.is_finite()
                    && sizes.iter().all(|s| *s > 0.0 && s.is_finite())
                    && orthonormal)
                {
                    return Err(format!(
                        "shape {k}: cylinder at {p0:?} radius {radius} length {length} frame {frame:?}"
                    ));
                }
            }
        }
    }
    Ok(())
}

fn load(xml: &str, dir: &Path) -> Result<(), String> {
    match pt_scene::load_str(xml, &dir.join("scene.xml"), dir, &[]) {
        Ok(desc) => check_usable(&desc),
        Err(_) => Ok(()),
    }
}

/// One OBJ line drawn from the format's statements with hostile numbers and indices.
fn obj_line() -> impl Strategy<Value = String> {
    let num = prop_oneof![
        (-10.0f32..10.0).prop_map(|v| v.to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-1e39".to_string()),
        Just("1e-42".to_string()),
        Just("".to_string()),
        Just("x".to_string()),
    ];
    let idx = prop_oneof![
        (-6i64..8).prop_map(|v| v.to_string()),
        Just("0".to_string()),
        Just("4294967297".to_string()),
        Just("-99999999999".to_string()),
        (1i64..5, 1i64..5).prop_map(|(a, b)| format!("{a}/{b}")),
        (1i64..5, -3i64..5).prop_map(|(a, b)| format!("{a}//{b}")),
        (1i64..5, 1i64..5, -2i64..5).prop_map(|(a, b, c)| format!("{a}/{b}/{c}")),
        Just("/".to_string()),
    ];
    prop_oneof![
        3 => (num.clone(), num.clone(), num.clone()).prop_map(|(a, b, c)| format!("v {a} {b} {c}")),
        1 => (num.clone(), num.clone(), num.clone()).prop_map(|(a, b, c)| format!("vn {a} {b} {c}")),
        1 => (num.clone(), num.clone()).prop_map(|(a, b)| format!("vt {a} {b}")),
        3 => prop::collection::vec(idx, 0..6).prop_map(|v| format!("f {}", v.join(" "))),
        1 => prop_oneof![Just("o a"), Just("g"), Just("s 1"), Just("mtllib x.mtl"), Just("usemtl m"), Just("l 1 2"), Just("p 1"), Just("#"), Just("\\"), Just("")]
            .prop_map(String::from),
        1 => "[ -~]{0,12}",
    ]
}

fn gltf_asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/gltf")
        .join(name)
}

/// The glTF documents the mutation property starts from: two of the repository's assets, and
/// one of them with every material feature and vertex attribute the reader maps.
fn gltf_bases() -> Vec<Value> {
    let read = |name: &str| -> Value {
        serde_json::from_slice(&std::fs::read(gltf_asset(name)).unwrap()).unwrap()
    };
    let mut rich = read("textures.gltf");
    let m = &mut rich["materials"][0];
    m["normalTexture"] = json!({"index": 1, "scale": 0.5});
    m["alphaMode"] = json!("MASK");
    m["emissiveFactor"] = json!([1, 1, 1]);
    m["emissiveTexture"] =
        json!({"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0]}}});
    m["extensions"] = json!({
        "KHR_materials_iridescence": {"iridescenceFactor": 0.5, "iridescenceTexture": {"index": 0},
                                      "iridescenceThicknessTexture": {"index": 1}},
        "KHR_materials_transmission": {"transmissionFactor": 0.5},
        "KHR_materials_volume": {"thicknessFactor": 1, "attenuationDistance": 1,
                                 "attenuationColor": [0.5, 0.5, 0.5]}
    });
    rich["samplers"][0]["wrapS"] = json!(33071);
    rich["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = json!(1);
    vec![read("textures.gltf"), read("lights.gltf"), rich]
}

/// Values the glTF mutation property writes into documents: indices in and out of range,
/// component and element types glTF allows elsewhere, hostile numbers, other JSON types.
fn hostile_json() -> Vec<Value> {
    vec![
        json!(-1),
        json!(0),
        json!(1),
        json!(2),
        json!(3),
        json!(7),
        json!(5120),
        json!(5121),
        json!(5123),
        json!(5125),
        json!(5126),
        json!(33648),
        json!(4294967295u64),
        json!(1e39),
        json!(-0.5),
        json!(null),
        json!(true),
        json!("VEC2"),
        json!("VEC4"),
        json!("SCALAR"),
        json!("MAT4"),
        json!("data:,"),
        json!([]),
        json!({}),
        json!([0, 0]),
    ]
}

/// The number of leaves of a JSON value (scalars, empty arrays and objects).
fn leaves(v: &Value) -> usize {
    match v {
        Value::Object(m) if !m.is_empty() => m.values().map(leaves).sum(),
        Value::Array(a) if !a.is_empty() => a.iter().map(leaves).sum(),
        _ => 1,
    }
}

/// Replaces the `k`-th leaf (depth first) of `v` by `new`, or removes it from its object or
/// array; true once done.
fn edit_leaf(v: &mut Value, k: &mut usize, new: &Value, remove: bool) -> bool {
    let is_leaf = |c: &Value| match c {
        Value::Object(m) => m.is_empty(),
        Value::Array(a) => a.is_empty(),
        _ => true,
    };
    match v {
        Value::Object(m) => {
            let keys: Vec<String> = m.keys().cloned().collect();
            for key in keys {
                if is_leaf(&m[&key]) {
                    if *k == 0 {
                        if remove {
                            m.remove(&key);
                        } else {
                            m[&key] = new.clone();
                        }
                        return true;
                    }
                    *k -= 1;
                } else if edit_leaf(m.get_mut(&key).unwrap(), k, new, remove) {
                    return true;
                }
            }
            false
        }
        Value::Array(a) => {
            for i in 0..a.len() {
                if is_leaf(&a[i]) {
                    if *k == 0 {
                        if remove {
                            a.remove(i);
                        } else {
                            a[i] = new.clone();
                        }
                        return true;
                    }
                    *k -= 1;
                } else if edit_leaf(&mut a[i], k, new, remove) {
                    return true;
                }
            }
            false
        }
        _ => false,
    }
}

/// Reads glTF bytes: Ok or Err, and what is accepted is usable.
fn load_gltf(bytes: &[u8], dir: &Path) -> Result<(), String> {
    match pt_scene::gltf::load_slice(bytes, &dir.join("m.gltf"), &Default::default()) {
        Ok(g) => check_usable(&g.desc),
        Err(_) => Ok(()),
    }
}

proptest! {
    /// Arbitrary text: the XML loader returns Ok or Err, never panics.
    #[test]
    fn xml_loader_never_panics_on_arbitrary_text(text in "(?s).{0,400}") {
        let dir = scratch("fuzz_xml_text");
        prop_assert_eq!(load(&text, &dir), Ok(()));
    }

    /// A valid scene with random deletions, insertions of hostile tokens and swaps: never a
    /// panic, and what is accepted is usable.
    #[test]
    fn xml_loader_never_panics_on_mutated_scenes(edits in prop::collection::vec((0usize..SCENE.len(), 0usize..TOKENS.len(), 0u8..3, 0usize..40), 1..8)) {
        let dir = scratch("fuzz_xml_mut");
        std::fs::write(dir.join("mesh.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let mut s = SCENE.to_string();
        for (pos, tok, kind, len) in edits {
            let mut p = pos.min(s.len());
            while !s.is_char_boundary(p) { p -= 1; }
            match kind {
                0 => s.insert_str(p, TOKENS[tok]),
                1 => {
                    let mut e = (p + len).min(s.len());
                    while !s.is_char_boundary(e) { e -= 1; }
                    s.replace_range(p..e, "");
                }
                _ => {
                    let mut e = (p + len).min(s.len());
                    while !s.is_char_boundary(e) { e -= 1; }
                    s.replace_range(p..e, TOKENS[tok]);
                }
            }
        }
        prop_assert_eq!(load(&s, &dir), Ok(()));
    }

    /// Random OBJ files (format statements with hostile numbers and indices, random bytes):
    /// the loader returns Ok or Err, and an accepted mesh has in-range indices, finite
    /// positions and unit normals.
    #[test]
    fn obj_loader_never_panics_and_accepts_only_usable_meshes(lines in prop::collection::vec(obj_line(), 0..24), face_normals in any::<bool>()) {
        let dir = scratch("fuzz_obj");
        std::fs::write(dir.join("m.obj"), lines.join("\n")).unwrap();
        let xml = format!(
            r#"<scene version="3.0.0"><shape type="obj"><string name="filename" value="m.obj"/><boolean name="face_normals" value="{face_normals}"/></shape></scene>"#
        );
        prop_assert_eq!(load(&xml, &dir), Ok(()));
    }

    /// Raw bytes as an OBJ file (invalid UTF-8 included).
    #[test]
    fn obj_loader_never_panics_on_raw_bytes(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        let dir = scratch("fuzz_obj_bytes");
        std::fs::write(dir.join("m.obj"), &bytes).unwrap();
        let xml = r#"<scene version="3.0.0"><shape type="obj"><string name="filename" value="m.obj"/></shape></scene>"#;
        prop_assert_eq!(load(xml, &dir), Ok(()));
    }

    /// glTF documents with leaves replaced by hostile values or removed (indices, component
    /// types, counts, offsets, factors, URIs): the reader returns Ok or Err, never panics, and
    /// what it accepts is usable.
    #[test]
    fn gltf_reader_never_panics_on_mutated_documents(base in 0usize..3, edits in prop::collection::vec((any::<usize>(), 0usize..25, 0u8..4), 1..6)) {
        let dir = scratch("fuzz_gltf_json");
        let mut doc = gltf_bases().swap_remove(base);
        let hostile = hostile_json();
        for (leaf, value, op) in edits {
            let mut k = leaf % leaves(&doc);
            edit_leaf(&mut doc, &mut k, &hostile[value % hostile.len()], op == 0);
        }
        prop_assert_eq!(load_gltf(&serde_json::to_vec(&doc).unwrap(), &dir), Ok(()));
    }

    /// A GLB file with random bytes overwritten (header, JSON chunk, binary chunk).
    #[test]
    fn gltf_reader_never_panics_on_mutated_glb(edits in prop::collection::vec((any::<usize>(), any::<u8>()), 1..8)) {
        let dir = scratch("fuzz_gltf_glb");
        let mut bytes = std::fs::read(gltf_asset("glass-block.glb")).unwrap();
        for (pos, b) in edits {
            let n = bytes.len();
            bytes[pos % n] = b;
        }
        prop_assert_eq!(load_gltf(&bytes, &dir), Ok(()));
    }
}

/// Crasher found by `gltf_reader_never_panics_on_mutated_documents`: an image with neither
/// `uri` nor `bufferView` (the gltf crate's `Image::source` unwraps the uri).
#[test]
fn gltf_image_without_uri_is_an_error() {
    let mut doc = gltf_bases().swap_remove(0);
    doc["images"][0].as_object_mut().unwrap().remove("uri");
    let bytes = serde_json::to_vec(&doc).unwrap();
    let e =
        pt_scene::gltf::load_slice(&bytes, Path::new("m.gltf"), &Default::default()).unwrap_err();
    assert!(
        e.message.contains("images[0]: needs a uri or a bufferView"),
        "{e}"
    );
}

/// Crasher found by both glTF properties: a `POSITION` naming an accessor that does not
/// exist (the gltf crate's own validation indexes the accessor list with it).
#[test]
fn gltf_position_out_of_range_is_an_error() {
    let mut doc = gltf_bases().swap_remove(0);
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7);
    let bytes = serde_json::to_vec(&doc).unwrap();
    let e =
        pt_scene::gltf::load_slice(&bytes, Path::new("m.gltf"), &Default::default()).unwrap_err();
    assert!(
        e.message
            .contains("POSITION is accessors[7], which does not exist"),
        "{e}"
    );
}
