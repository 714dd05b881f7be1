//! Property tests (proptest) of the loaders on hostile input: the XML loader and the OBJ
//! loader must return `Ok` or `Err`, never panic, whatever the bytes; and what they accept must
//! be usable: every mesh index within its vertex list, every position, normal and sphere
//! finite, every normal unit length. A crasher found would be kept here as a plain regression
//! test (proptest also records failing seeds in `tests/fuzz.proptest-regressions`); none has
//! been found so far: the OBJ reader checks every index against the lists read before it and
//! every number for finiteness, and the XML loader validates every number it reads.
//!
//! Case counts are proptest's default (256 per property), a few seconds in the test profile.

use proptest::prelude::*;
use pt_scene::{Geometry, SceneDesc};
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
            }
            Geometry::Sphere { center, radius, .. } => {
                if !center.is_finite() || !radius.is_finite() || *radius <= 0.0 {
                    return Err(format!("shape {k}: sphere at {center:?} radius {radius}"));
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
}
