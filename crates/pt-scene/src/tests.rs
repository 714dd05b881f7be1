//! Loader tests: whole scenes in, IR or located errors out.

use crate::*;
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// Loads `xml` as "test.xml" from the current folder.
fn load(xml: &str) -> Result<SceneDesc, SceneError> {
    load_str(xml, Path::new("test.xml"), Path::new("."), &[])
}

/// Wraps `body` in a version 3 scene: line 1 of `body` is line 2 of the file.
fn scene(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")
}

/// Loads a scene that must fail and returns the error.
fn fail(xml: &str) -> SceneError {
    match load(xml) {
        Ok(_) => panic!("scene loaded but should not have:\n{xml}"),
        Err(e) => e,
    }
}

/// Checks that the error is at `line` of test.xml, about `element`, and mentions `text`.
fn assert_error(e: &SceneError, line: u32, element: &str, text: &str) {
    let loc = e
        .loc
        .as_ref()
        .unwrap_or_else(|| panic!("no location in: {e}"));
    assert_eq!(loc.line, line, "wrong line in: {e}");
    assert_eq!(loc.element, element, "wrong element in: {e}");
    assert!(e.message.contains(text), "expected '{text}' in: {e}");
}

/// A fresh folder under the system temp dir, unique to this process and test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pt-scene-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-4
}

fn mesh(shape: &ShapeDesc) -> &TriangleMesh {
    match &shape.geometry {
        Geometry::Mesh(m) => m,
        Geometry::Sphere { .. } => panic!("expected a mesh"),
    }
}

fn face_normal(m: &TriangleMesh, t: usize) -> Vec3 {
    let p = m.indices[t].map(|i| m.positions[i as usize]);
    (p[1] - p[0]).cross(p[2] - p[0]).normalize()
}

fn cornell_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.xml")
}

// -------------------------------------------------------------------------------------------
// The Cornell box

#[test]
fn cornell_box_loads() {
    let s = load_file(&cornell_path(), &[]).unwrap();
    assert_eq!(s.shapes.len(), 8);
    let count = |p: &str| s.shapes.iter().filter(|sh| sh.plugin == p).count();
    assert_eq!((count("rectangle"), count("cube")), (6, 2));
    assert_eq!(s.bsdfs.len(), 4, "white, red, green, black, each once");
    assert_eq!(
        s.bsdfs
            .iter()
            .filter_map(|b| b.id.as_deref())
            .collect::<Vec<_>>(),
        ["white", "red", "green", "black"]
    );

    assert!(close(
        s.camera.to_world.transform_point3(Vec3::ZERO),
        Vec3::new(0.0, 0.0, 4.0)
    ));
    assert!(close(
        s.camera.to_world.transform_vector3(Vec3::Z),
        -Vec3::Z
    ));
    assert_eq!(
        s.camera.projection,
        Projection::Perspective {
            fov_deg: 39.3,
            fov_axis: FovAxis::X
        }
    );
    assert_eq!((s.camera.near_clip, s.camera.far_clip), (0.01, 100.0));
    assert_eq!((s.film.width, s.film.height), (256, 256));
    assert_eq!(s.film.filter, FilterDesc::Box { radius: 0.5 });
    assert_eq!(s.sampler.sample_count, 64);
    assert_eq!(s.integrator.kind, IntegratorKind::Path);
    assert_eq!(
        (
            s.integrator.max_depth,
            s.integrator.rr_depth,
            s.integrator.moment
        ),
        (8, 5, false)
    );

    // Floor faces up, the light faces down and emits.
    assert!(close(face_normal(mesh(&s.shapes[0]), 0), Vec3::Y));
    let light = &s.shapes[7];
    assert!(close(face_normal(mesh(light), 0), -Vec3::Y));
    let emitter = light.emitter.as_ref().expect("light emits");
    assert_eq!(emitter.radiance, SpectrumDesc::Rgb([17.0, 12.0, 4.0]));
    assert_eq!(light.loc.file, cornell_path());
    assert_eq!(light.loc.element, "shape type=\"rectangle\"");
    assert!(s.shapes[..7].iter().all(|sh| sh.emitter.is_none()));
}

#[test]
fn command_line_defaults_override_the_file() {
    let d = [
        ("spp".to_string(), "16".to_string()),
        ("width".to_string(), "32".to_string()),
    ];
    let s = load_file(&cornell_path(), &d).unwrap();
    assert_eq!(s.sampler.sample_count, 16);
    assert_eq!((s.film.width, s.film.height), (32, 256));
}

#[test]
fn missing_scene_file_names_the_file() {
    let e = load_file(Path::new("no/such/scene.xml"), &[]).unwrap_err();
    assert!(e.to_string().contains("no/such/scene.xml"), "{e}");
    assert!(e.to_string().contains("No such file"), "{e}");
}

// -------------------------------------------------------------------------------------------
// Defaults, include, path, ref

#[test]
fn include_path_default_and_ref_work_together() {
    let dir = temp_dir("include");
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(
        dir.join("meshes/tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("parts/materials.xml"),
        r#"<scene version="3.0.0">
    <default name="refl" value="0.1"/>
    <bsdf type="diffuse" id="mat"><float name="reflectance" value="$refl"/></bsdf>
</scene>"#,
    )
    .unwrap();
    let main = dir.join("main.xml");
    std::fs::write(
        &main,
        r#"<scene version="3.0.0">
    <default name="refl" value="0.25"/>
    <path value="meshes"/>
    <include filename="parts/materials.xml"/>
    <shape type="obj">
        <string name="filename" value="tri.obj"/>
        <ref id="mat"/>
    </shape>
    <shape type="rectangle"><ref name="bsdf" id="mat"/></shape>
</scene>"#,
    )
    .unwrap();
    let s = load_file(&main, &[]).unwrap();
    assert_eq!(s.shapes.len(), 2);
    assert_eq!(s.bsdfs.len(), 1, "the shared BSDF appears once");
    assert_eq!(s.shapes[0].bsdf, s.shapes[1].bsdf);
    // The main file's <default> came first, so it wins over the included one.
    match &s.bsdfs[0].kind {
        BsdfKind::Diffuse { reflectance } => assert_eq!(*reflectance, SpectrumDesc::Constant(0.25)),
        ref k => panic!("unexpected {k:?}"),
    }
    assert_eq!(s.bsdfs[0].loc.file, dir.join("parts/materials.xml"));
    assert_eq!(s.bsdfs[0].loc.line, 3);
    assert_eq!(mesh(&s.shapes[0]).indices.len(), 1);
}

#[test]
fn errors_in_included_files_point_into_them() {
    let dir = temp_dir("include-error");
    std::fs::write(
        dir.join("bad.xml"),
        "<scene version=\"3.0.0\">\n\n  <bsdf type=\"plasticc\"/>\n</scene>\n",
    )
    .unwrap();
    let main = dir.join("main.xml");
    std::fs::write(
        &main,
        "<scene version=\"3.0.0\">\n<include filename=\"bad.xml\"/>\n</scene>\n",
    )
    .unwrap();
    let e = load_file(&main, &[]).unwrap_err();
    let loc = e.loc.clone().unwrap();
    assert_eq!((loc.file, loc.line, loc.col), (dir.join("bad.xml"), 3, 3));

    let missing = fail(&scene(r#"<include filename="nowhere.xml"/>"#));
    assert_error(
        &missing,
        2,
        "include filename=\"nowhere.xml\"",
        "cannot open included file 'nowhere.xml'",
    );
}

#[test]
fn include_cycles_are_reported() {
    let dir = temp_dir("include-cycle");
    let main = dir.join("main.xml");
    std::fs::write(
        &main,
        "<scene version=\"3.0.0\">\n<include filename=\"main.xml\"/>\n</scene>\n",
    )
    .unwrap();
    let e = load_file(&main, &[]).unwrap_err();
    assert!(e.message.contains("nested <include>"), "{e}");
}

#[test]
fn defaults_substitute_anywhere_in_attribute_values() {
    let s = load(&scene(
        r#"<default name="w" value="100"/>
<default name="axis" value="y"/>
<sensor type="perspective">
    <float name="fov" value="$w.5"/>
    <string name="fov_axis" value="$axis"/>
    <film type="hdrfilm"><integer name="width" value="$w"/></film>
</sensor>"#,
    ))
    .unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Perspective {
            fov_deg: 100.5,
            fov_axis: FovAxis::Y
        }
    );
    assert_eq!(s.film.width, 100);
}

#[test]
fn undefined_parameter_is_an_error() {
    let e = fail(&scene(
        "<sensor type=\"perspective\">\n  <float name=\"fov\" value=\"$fov\"/>\n</sensor>",
    ));
    assert_error(&e, 3, "float name=\"fov\"", "undefined parameter '$fov'");
}

#[test]
fn unknown_and_duplicate_ids_are_errors() {
    let e = fail(&scene(
        "<shape type=\"cube\">\n    <ref id=\"nope\"/>\n</shape>",
    ));
    assert_error(&e, 3, "ref id=\"nope\"", "unknown id \"nope\"");
    let e = fail(&scene(
        "<bsdf type=\"diffuse\" id=\"a\"/>\n<bsdf type=\"diffuse\" id=\"a\"/>",
    ));
    assert_error(&e, 3, "bsdf type=\"diffuse\"", "duplicate id \"a\"");
}

#[test]
fn bsdf_reference_cycles_are_errors() {
    let e = fail(&scene(
        "<bsdf type=\"twosided\" id=\"a\"><ref id=\"a\"/></bsdf>\n<shape type=\"cube\"><ref id=\"a\"/></shape>",
    ));
    assert!(e.message.contains("contains itself"), "{e}");
}

// -------------------------------------------------------------------------------------------
// Error kinds, with locations

#[test]
fn unknown_element_is_an_error() {
    let e = fail(&scene("<bsdf type=\"diffuse\"/>\n<shap type=\"cube\"/>"));
    assert_error(&e, 3, "shap", "unknown element <shap>");
}

#[test]
fn unknown_plugin_is_an_error() {
    let e = fail(&scene("\n<bsdf type=\"plasticc\"/>"));
    assert_error(
        &e,
        3,
        "bsdf type=\"plasticc\"",
        "unknown bsdf plugin \"plasticc\"",
    );
    assert_eq!(e.loc.as_ref().unwrap().col, 1);
}

#[test]
fn unsupported_plugins_say_not_yet_implemented() {
    let cases = [
        "<bsdf type=\"plastic\"/>",
        "<emitter type=\"projector\"/>",
        "<emitter type=\"sunsky\"/>",
        "<sensor type=\"orthographic\"/>",
        "<shape type=\"ply\"/>",
        "<integrator type=\"volpathmis\"/>",
        "<shape type=\"cube\"><bsdf type=\"bumpmap\"/></shape>",
        "<shape type=\"cube\"><bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\"/></bsdf></shape>",
        "<sensor type=\"perspective\"><film type=\"hdrfilm\"><rfilter type=\"mitchell\"/></film></sensor>",
    ];
    for body in cases {
        let e = fail(&scene(body));
        assert!(e.message.contains("not yet implemented"), "{body}: {e}");
        assert_eq!(e.loc.as_ref().unwrap().line, 2, "{body}: {e}");
    }
}

#[test]
fn unused_property_is_an_error() {
    let e = fail(&scene(
        "<sensor type=\"perspective\">\n    <float name=\"fov\" value=\"30\"/>\n    <float name=\"fov2\" value=\"30\"/>\n</sensor>",
    ));
    assert_error(&e, 4, "float name=\"fov2\"", "unused property 'fov2'");
    assert!(e.message.contains("sensor \"perspective\""), "{e}");
    assert_eq!(e.loc.as_ref().unwrap().col, 5);
    assert!(
        e.to_string()
            .starts_with("test.xml:4:5: <float name=\"fov2\">: unused property 'fov2'"),
        "{e}"
    );
}

#[test]
fn wrong_property_type_is_an_error() {
    let e = fail(&scene(
        "<sensor type=\"perspective\">\n  <string name=\"fov\" value=\"30\"/>\n</sensor>",
    ));
    assert_error(&e, 3, "string name=\"fov\"", "must be a float, not string");
    let e = fail(&scene(
        "<integrator type=\"path\">\n  <float name=\"max_depth\" value=\"3\"/>\n</integrator>",
    ));
    assert_error(
        &e,
        3,
        "float name=\"max_depth\"",
        "must be an integer, not float",
    );
}

#[test]
fn misplaced_nested_object_is_an_error() {
    let e = fail(&scene(
        "<shape type=\"cube\">\n  <sensor type=\"perspective\"/>\n</shape>",
    ));
    assert_error(
        &e,
        3,
        "sensor type=\"perspective\"",
        "cannot be nested in shape \"cube\"",
    );
    let e = fail(&scene("<bsdf type=\"diffuse\" id=\"m\"/>\n<sensor type=\"perspective\">\n  <ref id=\"m\"/>\n</sensor>"));
    assert_error(&e, 4, "ref id=\"m\"", "<bsdf> cannot be nested in sensor");
    let e = fail(&scene("<film type=\"hdrfilm\"/>"));
    assert_error(
        &e,
        2,
        "film type=\"hdrfilm\"",
        "must be nested in a <sensor>",
    );
    let e = fail(&scene("<emitter type=\"area\"/>"));
    assert_error(
        &e,
        2,
        "emitter type=\"area\"",
        "must be nested in the <shape>",
    );
}

#[test]
fn bad_numbers_are_errors() {
    for (value, text) in [
        ("nan", "not finite"),
        ("inf", "not finite"),
        ("-Infinity", "not finite"),
        ("1.0x", "cannot parse"),
        ("", "cannot parse"),
    ] {
        let xml = scene(&format!(
            "<sensor type=\"perspective\">\n  <float name=\"fov\" value=\"{value}\"/>\n</sensor>"
        ));
        assert_error(&fail(&xml), 3, "float name=\"fov\"", text);
    }
    let e = fail(&scene(
        "<shape type=\"sphere\">\n  <point name=\"center\" value=\"0, nan, 0\"/>\n</shape>",
    ));
    assert_error(&e, 3, "point name=\"center\"", "not finite");
    let e = fail(&scene("<shape type=\"cube\">\n <emitter type=\"area\"><rgb name=\"radiance\" value=\"1, 2\"/></emitter>\n</shape>"));
    assert_error(&e, 3, "rgb name=\"radiance\"", "one or three numbers");
    let e = fail(&scene(
        "<integrator type=\"path\"><integer name=\"max_depth\" value=\"2.5\"/></integrator>",
    ));
    assert_error(
        &e,
        2,
        "integer name=\"max_depth\"",
        "cannot parse '2.5' as an integer",
    );
    let e = fail(&scene(
        "<integrator type=\"path\"><boolean name=\"hide_emitters\" value=\"yes\"/></integrator>",
    ));
    assert_error(&e, 2, "boolean name=\"hide_emitters\"", "true or false");
}

#[test]
fn transform_errors_name_the_operation() {
    let e = fail(&scene(
        "<shape type=\"cube\">\n  <transform name=\"to_world\">\n    <rotate angle=\"nan\" x=\"1\"/>\n  </transform>\n</shape>",
    ));
    assert_error(&e, 4, "rotate", "not finite");
    let e = fail(&scene(
        "<shape type=\"cube\">\n  <translate value=\"1 2 3\"/>\n</shape>",
    ));
    assert_error(&e, 3, "translate", "can only occur inside a <transform>");
}

#[test]
fn spectrum_pairs_are_tabulated_spectra() {
    let s = load(&scene(
        "<shape type=\"cube\"><bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"400:0.1, 700:0.5\"/>\n</bsdf></shape>",
    ))
    .unwrap();
    assert!(
        matches!(&s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: SpectrumDesc::Tabulated(p) } if p.as_slice() == [(400.0, 0.1), (700.0, 0.5)])
    );
    assert!(s.spectral_reason().unwrap().contains("tabulated spectrum"));
    // Malformed pairs name the element.
    for bad in [
        "400:0.1",
        "500:0.1, 400:0.2",
        "400:x, 500:1",
        "400:0.1; 500:0.2",
    ] {
        let e = fail(&scene(&format!(
            "<shape type=\"cube\"><bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"{bad}\"/>\n</bsdf></shape>"
        )));
        assert_eq!(e.loc.as_ref().unwrap().line, 3, "{bad}: {e}");
    }
    let s = load(&scene(
        "<shape type=\"cube\"><bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"0.3\"/></bsdf></shape>",
    ))
    .unwrap();
    assert!(
        matches!(s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: SpectrumDesc::Constant(r) } if r == 0.3)
    );
}

#[test]
fn spectrum_files_blackbody_and_named_illuminants() {
    // A file of pairs, relative to the XML file, with comments, blank lines and commas.
    let dir = temp_dir("spectrum-file");
    std::fs::write(
        dir.join("refl.spd"),
        "# wavelength value\n400 0.25\n\n550, 0.5  # mid\n700\t0.75\n",
    )
    .unwrap();
    std::fs::write(dir.join("bad.spd"), "400 0.1\n380 0.2\n").unwrap();
    std::fs::write(dir.join("one.spd"), "400 0.1\n").unwrap();
    std::fs::write(dir.join("text.spd"), "400 0.1\n500 x\n").unwrap();
    let body = |f: &str| {
        scene(&format!("<shape type=\"cube\"><bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" filename=\"{f}\"/>\n</bsdf></shape>"))
    };
    std::fs::write(dir.join("ok.xml"), body("refl.spd")).unwrap();
    let s = load_file(&dir.join("ok.xml"), &[]).unwrap();
    assert!(
        matches!(&s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: SpectrumDesc::Tabulated(p) } if p.as_slice() == [(400.0, 0.25), (550.0, 0.5), (700.0, 0.75)])
    );
    // Bad files: the error names the XML element (line 3) and the data file's line.
    for (f, text) in [
        ("bad.spd", "line 2: wavelengths must increase"),
        ("one.spd", "at least two"),
        ("text.spd", "line 2: cannot parse 'x'"),
        ("missing.spd", "cannot read spectrum file"),
    ] {
        std::fs::write(dir.join("bad.xml"), body(f)).unwrap();
        let e = load_file(&dir.join("bad.xml"), &[]).expect_err(f);
        assert_eq!(e.loc.as_ref().unwrap().line, 3, "{f}: {e}");
        assert!(e.message.contains(text), "{f}: {e}");
    }

    // Blackbody and named illuminants as emitter radiance.
    let emitter = |spec: &str| {
        scene(&format!(
            "<shape type=\"rectangle\"><emitter type=\"area\">\n{spec}\n</emitter></shape>"
        ))
    };
    let radiance = |s: &SceneDesc| s.shapes[0].emitter.as_ref().unwrap().radiance.clone();
    let s = load(&emitter("<spectrum type=\"blackbody\" name=\"radiance\"><float name=\"temperature\" value=\"2500\"/></spectrum>")).unwrap();
    assert_eq!(
        radiance(&s),
        SpectrumDesc::Blackbody {
            temperature: 2500.0
        }
    );
    assert!(
        s.spectral_reason()
            .unwrap()
            .contains("blackbody (2500 K) emission spectrum"),
        "{:?}",
        s.spectral_reason()
    );
    let s = load(&emitter(
        "<spectrum type=\"d65\" name=\"radiance\"><float name=\"scale\" value=\"3\"/></spectrum>",
    ))
    .unwrap();
    assert_eq!(
        radiance(&s),
        SpectrumDesc::Illuminant {
            name: "d65".into(),
            scale: 3.0
        }
    );
    let s = load(&emitter("<spectrum type=\"d65\" name=\"radiance\"/>")).unwrap();
    assert_eq!(
        radiance(&s),
        SpectrumDesc::Illuminant {
            name: "d65".into(),
            scale: 1.0
        }
    );
    for (t, name) in [("A", "a"), ("f1", "f1"), ("F11", "f11"), ("f12", "f12")] {
        let s = load(&emitter(&format!(
            "<spectrum type=\"{t}\" name=\"radiance\"/>"
        )))
        .unwrap();
        assert_eq!(
            radiance(&s),
            SpectrumDesc::Illuminant {
                name: name.into(),
                scale: 1.0
            },
            "{t}"
        );
        assert!(s
            .spectral_reason()
            .unwrap()
            .contains(&format!("CIE {}", name.to_uppercase())));
    }
    // Errors at the element at fault (line 3 is the <spectrum>, line 4 its child).
    for (spec, line, text) in [
        ("<spectrum type=\"blackbody\" name=\"radiance\"/>", 3, "needs <float name=\"temperature\">"),
        ("<spectrum type=\"blackbody\" name=\"radiance\">\n<float name=\"temperature\" value=\"-5\"/></spectrum>", 3, "must be positive"),
        ("<spectrum type=\"blackbody\" name=\"radiance\">\n<float name=\"scale\" value=\"2\"/></spectrum>", 4, "unused property 'scale'"),
        ("<spectrum type=\"d65\" name=\"radiance\">\n<float name=\"scale\" value=\"-1\"/></spectrum>", 3, "must not be negative"),
        ("<spectrum type=\"d65\" name=\"radiance\">\n<rgb name=\"scale\" value=\"1\"/></spectrum>", 4, "must be a float"),
        ("<spectrum type=\"f13\" name=\"radiance\"/>", 3, "unknown spectrum type 'f13'"),
        ("<spectrum type=\"f01\" name=\"radiance\"/>", 3, "unknown spectrum type"),
        ("<spectrum name=\"radiance\" value=\"1\" filename=\"x.spd\"/>", 3, "either 'value' or 'filename'"),
    ] {
        let e = fail(&emitter(spec));
        assert_eq!(e.loc.as_ref().unwrap().line, line, "{spec}: {e}");
        assert!(e.message.contains(text), "{spec}: {e}");
    }
    // An emission spectrum is no reflectance.
    let e = fail(&scene("<shape type=\"cube\"><bsdf type=\"orennayar\">\n<spectrum type=\"d65\" name=\"reflectance\"/>\n</bsdf></shape>"));
    assert!(e.message.contains("not an emission spectrum"), "{e}");
}

#[test]
fn malformed_xml_has_a_location() {
    let e = fail("<scene version=\"3.0.0\">\n<shape type=\"cube\">\n</scene>");
    let loc = e.loc.as_ref().unwrap();
    assert_eq!(loc.line, 3, "{e}");
    assert!(e.message.contains("malformed XML"), "{e}");
}

#[test]
fn scene_root_and_version_are_required() {
    assert!(fail("<scene/>")
        .message
        .contains("missing attribute 'version'"));
    assert!(fail("<shape type=\"cube\" version=\"3.0.0\"/>")
        .message
        .contains("root element"));
    assert!(fail("<scene version=\"three\"/>")
        .message
        .contains("cannot parse version"));
    let e = fail(&scene("<shape type=\"cube\" colour=\"red\"/>"));
    assert_error(
        &e,
        2,
        "shape type=\"cube\"",
        "unexpected attribute 'colour'",
    );
}

#[test]
fn missing_obj_names_the_file() {
    let e = fail(&scene(
        "<shape type=\"obj\">\n  <string name=\"filename\" value=\"bunny.obj\"/>\n</shape>",
    ));
    assert_error(
        &e,
        2,
        "shape type=\"obj\"",
        "cannot open mesh 'bunny.obj': No such file or directory",
    );
    assert!(
        e.to_string()
            .starts_with("test.xml:2:1: <shape type=\"obj\">: cannot open mesh"),
        "{e}"
    );
}

#[test]
fn malformed_obj_is_an_error_at_the_shape() {
    let dir = temp_dir("bad-obj");
    let cases = [
        (
            "range.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
            "line 4: face corner '9' refers to vertex 9, but 3 vertices are defined before it",
        ),
        (
            "nan.obj",
            "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
            "line 2: position 'nan' is not finite",
        ),
        (
            "junk.obj",
            "v 0 zero 0\nf 1 2 3\n",
            "line 1: position 'zero' is not a number",
        ),
        (
            "huge.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/9999999999999999999 2/1 3/1\n",
            "line 5: face corner '1/9999999999999999999': '9999999999999999999' is not an index",
        ),
    ];
    for (name, text, expected) in cases {
        std::fs::write(dir.join(name), text).unwrap();
        let xml = scene(&format!(
            "<shape type=\"obj\">\n<string name=\"filename\" value=\"{name}\"/>\n</shape>"
        ));
        let e = load_str(&xml, Path::new("test.xml"), &dir, &[]).unwrap_err();
        assert_error(&e, 2, "shape type=\"obj\"", expected);
        assert!(e.message.contains(name), "{e}");
    }
}

// -------------------------------------------------------------------------------------------
// Shapes

#[test]
fn obj_loads_with_transformed_normals() {
    let dir = temp_dir("obj");
    // A quad in z = 0 facing +z (two triangles after triangulation) and a second object.
    let obj =
        "o quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               f 1/1/1 2/2/1 3/3/1 4/4/1\no tri\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5/1/1 6/2/1 7/4/1\n";
    std::fs::write(dir.join("quad.obj"), obj).unwrap();
    let body = r#"<shape type="obj">
    <string name="filename" value="quad.obj"/>
    <transform name="to_world">
        <scale x="2"/>
        <rotate x="1" angle="90"/>
    </transform>
</shape>
<shape type="obj">
    <string name="filename" value="quad.obj"/>
    <boolean name="face_normals" value="true"/>
    <boolean name="flip_normals" value="true"/>
</shape>"#;
    let s = load_str(&scene(body), Path::new("test.xml"), &dir, &[]).unwrap();
    let m = mesh(&s.shapes[0]);
    assert_eq!(m.indices.len(), 3);
    // Rotating +z by 90 degrees about x gives -y; scaling x does not change a z normal.
    let normals = m.normals.as_ref().expect("file normals kept");
    assert!(normals.iter().all(|n| close(*n, -Vec3::Y)), "{normals:?}");
    assert!(close(face_normal(m, 0), -Vec3::Y));
    assert!(close(m.positions[1], Vec3::new(2.0, 0.0, 0.0)));
    // flip_tex_coords (default true): v' = 1 - v.
    assert_eq!(m.uvs.as_ref().unwrap()[0], Vec2::new(0.0, 1.0));

    let flat = mesh(&s.shapes[1]);
    assert!(flat.normals.is_none(), "face_normals drops vertex normals");
    assert!(
        close(face_normal(flat, 0), -Vec3::Z),
        "flip_normals reverses the winding"
    );
}

#[test]
fn obj_without_normals_gets_smooth_normals() {
    let dir = temp_dir("obj-smooth");
    std::fs::write(dir.join("t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let xml = scene("<shape type=\"obj\"><string name=\"filename\" value=\"t.obj\"/><boolean name=\"flip_normals\" value=\"true\"/></shape>");
    let s = load_str(&xml, Path::new("test.xml"), &dir, &[]).unwrap();
    let m = mesh(&s.shapes[0]);
    assert!(m
        .normals
        .as_ref()
        .unwrap()
        .iter()
        .all(|n| close(*n, -Vec3::Z)));
    assert!(m.uvs.is_none());
}

#[test]
fn sphere_takes_center_radius_and_uniform_scale() {
    let s = load(&scene(
        r#"<shape type="sphere">
    <point name="center" x="1"/>
    <float name="radius" value="0.5"/>
    <boolean name="flip_normals" value="true"/>
    <transform name="to_world"><scale value="2"/><translate y="3"/></transform>
</shape>"#,
    ))
    .unwrap();
    match s.shapes[0].geometry {
        Geometry::Sphere {
            center,
            radius,
            flip_normals,
        } => {
            assert!(close(center, Vec3::new(2.0, 3.0, 0.0)));
            assert_eq!((radius, flip_normals), (1.0, true));
        }
        _ => panic!("not a sphere"),
    }
    let e = fail(&scene("<shape type=\"sphere\">\n<transform name=\"to_world\"><scale x=\"2\"/></transform>\n</shape>"));
    assert_error(&e, 2, "shape type=\"sphere\"", "non-uniform");
}

#[test]
fn disk_and_rectangle_geometry() {
    let s = load(&scene(
        "<shape type=\"disk\"><transform name=\"to_world\"><scale value=\"3\"/></transform></shape>\n<shape type=\"rectangle\"/>",
    ))
    .unwrap();
    let disk = mesh(&s.shapes[0]);
    let area: f32 = (0..disk.indices.len())
        .map(|t| {
            let p = disk.indices[t].map(|i| disk.positions[i as usize]);
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
        })
        .sum();
    assert!((area - 9.0 * std::f32::consts::PI).abs() < 1e-3, "{area}");
    let rect = mesh(&s.shapes[1]);
    assert_eq!(rect.indices.len(), 2);
    assert_eq!(rect.uvs.as_ref().unwrap()[2], Vec2::ONE);
    assert!(close(face_normal(rect, 1), Vec3::Z));
}

// -------------------------------------------------------------------------------------------
// BSDFs

#[test]
fn shapes_without_bsdf_share_one_default_diffuse() {
    let s = load(&scene(
        "<shape type=\"cube\"/>\n<shape type=\"rectangle\"/>",
    ))
    .unwrap();
    assert_eq!(s.bsdfs.len(), 1);
    assert_eq!((s.shapes[0].bsdf, s.shapes[1].bsdf), (0, 0));
    assert!(
        matches!(s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: SpectrumDesc::Constant(r) } if r == 0.5)
    );
}

/// Mitsuba 3 gives an emitting shape without a BSDF a black diffuse one (checked with
/// `mi.load_dict` in 3.9.1: `SmoothDiffuse[reflectance = 0]`), so a large light does not
/// reflect light back into the scene (a radius-1 sphere light made the floor under it 1.8%
/// brighter than Mitsuba's before this).
#[test]
fn emitters_without_bsdf_get_a_black_default() {
    let s = load(&scene(
        "<shape type=\"sphere\"><emitter type=\"area\"/></shape>\n<shape type=\"rectangle\"/>\n<shape type=\"sphere\"><emitter type=\"area\"/></shape>",
    ))
    .unwrap();
    assert_eq!(s.bsdfs.len(), 2);
    assert_eq!(s.shapes[0].bsdf, s.shapes[2].bsdf);
    let r = |i: usize| match s.bsdfs[s.shapes[i].bsdf].kind {
        BsdfKind::Diffuse {
            reflectance: SpectrumDesc::Constant(r),
        } => r,
        ref k => panic!("unexpected {k:?}"),
    };
    assert_eq!((r(0), r(1)), (0.0, 0.5));
}

#[test]
fn twosided_wraps_one_bsdf() {
    let s = load(&scene(
        r#"<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
<bsdf type="twosided" id="both"><ref id="red"/></bsdf>
<shape type="rectangle"><ref id="both"/></shape>
<shape type="rectangle"><ref id="both"/></shape>
<shape type="cube"><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#,
    ))
    .unwrap();
    assert_eq!(s.bsdfs.len(), 2);
    match &s.bsdfs[0].kind {
        BsdfKind::TwoSided { inner } => assert!(matches!(
            inner.kind,
            BsdfKind::Diffuse { reflectance: SpectrumDesc::Rgb([r, _, _]) } if r == 0.8
        )),
        k => panic!("unexpected {k:?}"),
    }
    let e = fail(&scene(
        "<bsdf type=\"twosided\">\n<bsdf type=\"diffuse\"/>\n<bsdf type=\"diffuse\"/>\n</bsdf>",
    ));
    assert_error(&e, 4, "bsdf type=\"diffuse\"", "not yet implemented");
    let e = fail(&scene("<bsdf type=\"twosided\"/>"));
    assert_error(&e, 2, "bsdf type=\"twosided\"", "needs one nested");
}

// -------------------------------------------------------------------------------------------
// Sensor, film, sampler, integrator

#[test]
fn missing_sensor_and_integrator_use_mitsuba_defaults() {
    let s = load(&scene("<shape type=\"cube\"/>")).unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Perspective {
            fov_deg: 45.0,
            fov_axis: FovAxis::X
        }
    );
    assert_eq!((s.film.width, s.film.height), (768, 576));
    assert_eq!(s.film.filter, FilterDesc::Gaussian { stddev: 0.5 });
    assert_eq!((s.sampler.sample_count, s.sampler.seed), (4, 0));
    assert_eq!(s.integrator.kind, IntegratorKind::Path);
    assert_eq!(
        (
            s.integrator.max_depth,
            s.integrator.rr_depth,
            s.integrator.hide_emitters
        ),
        (-1, 5, false)
    );
    // The camera backs off along -z until the whole [-1, 1]^3 cube fits in 45 degrees.
    let eye = s.camera.to_world.transform_point3(Vec3::ZERO);
    let distance = 2.0 / (2.0 * 22.5f32.to_radians().tan());
    assert!(close(eye, Vec3::new(0.0, 0.0, -1.0 - distance)), "{eye}");

    let empty = load(&scene("")).unwrap();
    assert_eq!(empty.camera.to_world, glam::Mat4::IDENTITY);
    assert!(empty.shapes.is_empty());
}

#[test]
fn sensor_parameters() {
    let s = load(&scene(
        r#"<sensor type="perspective">
    <string name="focal_length" value="35mm"/>
    <float name="near_clip" value="0.5"/>
    <sampler type="stratified"><integer name="sample_count" value="10"/><integer name="seed" value="7"/><boolean name="jitter" value="false"/></sampler>
    <film type="hdrfilm">
        <integer name="height" value="100"/>
        <string name="pixel_format" value="RGBA"/>
        <string name="component_format" value="float32"/>
        <boolean name="banner" value="false"/>
        <boolean name="sample_border" value="false"/>
        <integer name="crop_offset_x" value="0"/>
        <integer name="crop_height" value="100"/>
        <rfilter type="tent"><float name="radius" value="1.5"/></rfilter>
    </film>
</sensor>"#,
    ))
    .unwrap();
    let fov = 2.0 * (43.266_615f32 / 70.0).atan().to_degrees();
    match s.camera.projection {
        Projection::Perspective { fov_deg, fov_axis } => {
            assert!((fov_deg - fov).abs() < 1e-3, "{fov_deg} vs {fov}");
            assert_eq!(fov_axis, FovAxis::Diagonal);
        }
    }
    assert_eq!(s.camera.near_clip, 0.5);
    assert_eq!(
        (s.sampler.sample_count, s.sampler.seed),
        (16, 7),
        "stratified rounds up to a square"
    );
    assert_eq!((s.film.width, s.film.height), (768, 100));
    assert_eq!(s.film.filter, FilterDesc::Tent { radius: 1.5 });
}

#[test]
fn sensor_errors() {
    let sensor = |inner: &str| {
        scene(&format!(
            "<sensor type=\"perspective\">\n{inner}\n</sensor>"
        ))
    };
    let cases = [
        ("<string name=\"fov_axis\" value=\"z\"/>\n<float name=\"fov\" value=\"30\"/>", 3, "fov_axis must be"),
        ("<float name=\"fov\" value=\"180\"/>", 3, "between 0 and 180"),
        ("<float name=\"near_clip\" value=\"10\"/><float name=\"far_clip\" value=\"1\"/>", 3, "smaller than far_clip"),
        ("<float name=\"fov\" value=\"30\"/><string name=\"focal_length\" value=\"50mm\"/>", 3, "not both"),
        ("<string name=\"focal_length\" value=\"long\"/>", 3, "focal length"),
        ("<transform name=\"to_world\"><scale value=\"2\"/></transform>", 3, "may only rotate"),
        ("<film type=\"hdrfilm\"><integer name=\"width\" value=\"0\"/></film>", 3, "between 1 and"),
        ("<film type=\"hdrfilm\"><integer name=\"crop_width\" value=\"10\"/></film>", 3, "cropping"),
        ("<film type=\"hdrfilm\"><boolean name=\"sample_border\" value=\"true\"/></film>", 3, "sample_border"),
        ("<film type=\"hdrfilm\"><string name=\"pixel_format\" value=\"cmyk\"/></film>", 3, "pixel_format"),
        ("<film type=\"hdrfilm\"><rfilter type=\"box\"><float name=\"radius\" value=\"1\"/></rfilter></film>", 3, "unused property 'radius'"),
        ("<sampler type=\"independent\"><integer name=\"sample_count\" value=\"0\"/></sampler>", 3, "at least 1"),
        ("<film type=\"hdrfilm\"/>\n<film type=\"hdrfilm\"/>", 4, "only one <film>"),
        ("<string name=\"fov_axis\" value=\"y\"/>", 3, "unused property 'fov_axis'"),
    ];
    for (inner, line, text) in cases {
        let e = fail(&sensor(inner));
        assert_eq!(e.loc.as_ref().map(|l| l.line), Some(line), "{inner}: {e}");
        assert!(
            e.message.contains(text),
            "{inner}: expected '{text}' in {e}"
        );
    }
    assert!(fail(&scene(
        "<sensor type=\"perspective\"/>\n<sensor type=\"perspective\"/>"
    ))
    .message
    .contains("only one <sensor>"));
}

#[test]
fn integrators() {
    let integrator = |xml: &str| load(&scene(xml)).map(|s| s.integrator);
    let i = integrator("<integrator type=\"path\"><integer name=\"max_depth\" value=\"0\"/><boolean name=\"hide_emitters\" value=\"true\"/></integrator>").unwrap();
    assert_eq!((i.max_depth, i.hide_emitters), (0, true));
    let i = integrator(
        "<integrator type=\"direct\"><integer name=\"emitter_samples\" value=\"1\"/></integrator>",
    )
    .unwrap();
    assert_eq!((i.kind, i.max_depth), (IntegratorKind::Direct, 2));
    let i = integrator("<integrator type=\"moment\"><integrator type=\"path\"><integer name=\"max_depth\" value=\"3\"/></integrator></integrator>").unwrap();
    assert_eq!(
        (i.kind, i.max_depth, i.moment),
        (IntegratorKind::Path, 3, true)
    );

    let cases = [
        (
            "<integer name=\"max_depth\" value=\"-2\"/>",
            "path",
            "at least -1",
        ),
        (
            "<integer name=\"rr_depth\" value=\"0\"/>",
            "path",
            "at least 1",
        ),
        (
            "<integer name=\"bsdf_samples\" value=\"4\"/>",
            "direct",
            "not yet supported",
        ),
        (
            "<integer name=\"max_depth\" value=\"3\"/>",
            "direct",
            "unused property 'max_depth'",
        ),
        ("", "moment", "needs one nested"),
        ("<shape type=\"cube\"/>", "path", "cannot be nested"),
    ];
    for (inner, plugin, text) in cases {
        let e = fail(&scene(&format!(
            "<integrator type=\"{plugin}\">\n{inner}\n</integrator>"
        )));
        assert!(
            e.message.contains(text),
            "{inner}: expected '{text}' in {e}"
        );
    }
    assert!(fail(&scene(
        "<integrator type=\"path\"/><integrator type=\"path\"/>"
    ))
    .message
    .contains("only one"));
}

// -------------------------------------------------------------------------------------------
// Transforms through whole scenes, and old scenes

#[test]
fn transforms_compose_like_mitsuba() {
    let s = load(&scene(
        r#"<shape type="rectangle"><transform name="to_world">
    <scale value="2, 1, 1"/>
    <rotate value="0, 0, 1" angle="90"/>
    <matrix value="1 0 0 10  0 1 0 0  0 0 1 0  0 0 0 1"/>
</transform></shape>
<sensor type="perspective"><transform name="to_world">
    <lookat origin="1, 1, 1" target="1, 1, 0" up="0, 1, 0"/>
    <translate z="5"/>
</transform></sensor>"#,
    ))
    .unwrap();
    // (1,-1,0) -> scale (2,-1,0) -> rotate z 90 (1,2,0) -> translate x 10 (11,2,0).
    let m = mesh(&s.shapes[0]);
    assert!(
        close(m.positions[1], Vec3::new(11.0, 2.0, 0.0)),
        "{}",
        m.positions[1]
    );
    let cam = s.camera.to_world;
    assert!(close(
        cam.transform_point3(Vec3::ZERO),
        Vec3::new(1.0, 1.0, 6.0)
    ));
    assert!(close(cam.transform_vector3(Vec3::Z), -Vec3::Z));
    // Mitsuba's "left" axis: up x dir = y x (-z) = -x.
    assert!(close(cam.transform_vector3(Vec3::X), -Vec3::X));
}

const OLD_SCENE: &str = r#"<scene version="0.6.0">
    <default name="sampleCount" value="9"/>
    <integrator type="path"><integer name="maxDepth" value="3"/><integer name="rrDepth" value="2"/><boolean name="hideEmitters" value="true"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="30"/>
        <string name="fovAxis" value="y"/>
        <float name="nearClip" value="0.1"/>
        <transform name="toWorld"><lookAt origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
        <sampler type="independent"><integer name="sampleCount" value="$sampleCount"/></sampler>
    </sensor>
    <shape type="rectangle">
        <boolean name="flipNormals" value="true"/>
        <bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.2"/></bsdf>
    </shape>
</scene>"#;

#[test]
fn camel_case_is_accepted_in_old_scenes() {
    let s = load(OLD_SCENE).unwrap();
    assert_eq!(
        (
            s.integrator.max_depth,
            s.integrator.rr_depth,
            s.integrator.hide_emitters
        ),
        (3, 2, true)
    );
    assert_eq!(
        s.camera.projection,
        Projection::Perspective {
            fov_deg: 30.0,
            fov_axis: FovAxis::Y
        }
    );
    assert_eq!(s.camera.near_clip, 0.1);
    assert!(close(
        s.camera.to_world.transform_point3(Vec3::ZERO),
        Vec3::new(0.0, 0.0, 5.0)
    ));
    assert_eq!(s.sampler.sample_count, 9);
    assert!(close(face_normal(mesh(&s.shapes[0]), 0), -Vec3::Z));
    assert!(
        matches!(s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: SpectrumDesc::Rgb([r, _, _]) } if r == 0.2)
    );
}

#[test]
fn camel_case_is_rejected_in_version_3() {
    let new = OLD_SCENE.replacen("0.6.0", "3.0.0", 1);
    let e = fail(&new);
    assert_error(
        &e,
        3,
        "integer name=\"maxDepth\"",
        "unused property 'maxDepth'",
    );
    let e = fail(&scene("<shape type=\"cube\">\n<transform name=\"to_world\"><lookAt origin=\"0,0,1\" target=\"0,0,0\"/></transform>\n</shape>"));
    assert_error(&e, 3, "lookAt", "<lookat>");
}

// -------------------------------------------------------------------------------------------
// Robustness: no input makes the loader panic

#[test]
fn truncated_and_mutated_scenes_never_panic() {
    let text = std::fs::read_to_string(cornell_path()).unwrap();
    let dir = cornell_path().parent().unwrap().to_path_buf();
    let boundaries: Vec<usize> = (0..text.len())
        .filter(|&i| text.is_char_boundary(i))
        .collect();
    for &cut in boundaries.iter().step_by(3) {
        let _ = load_str(&text[..cut], Path::new("cut.xml"), &dir, &[]);
    }
    // Replace each number-ish token in turn by hostile values.
    let hostile = [
        "nan",
        "-1",
        "0",
        "1e39",
        "-inf",
        "$x",
        "",
        "99999999999999999999",
        "a,b",
    ];
    let quotes: Vec<usize> = text.match_indices('"').map(|(i, _)| i).collect();
    for pair in quotes.chunks_exact(2) {
        for h in hostile {
            let mutated = format!("{}\"{h}\"{}", &text[..pair[0]], &text[pair[1] + 1..]);
            let _ = load_str(&mutated, Path::new("mutated.xml"), &dir, &[]);
        }
    }
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let depth = 5000;
    let xml = format!(
        "<scene version=\"3.0.0\">{}{}</scene>",
        "<bsdf type=\"twosided\">".repeat(depth),
        "</bsdf>".repeat(depth)
    );
    assert!(fail(&xml).message.contains("nested deeper"));
}

#[test]
fn emitters_outside_shapes() {
    let s = load_str(
        &scene(
            r#"<emitter type="point"><point name="position" value="1, 2, 3"/><rgb name="intensity" value="4"/></emitter>
<emitter type="spot"><float name="cutoff_angle" value="30"/></emitter>
<emitter type="directional"><vector name="direction" value="0, -2, 0"/></emitter>
<emitter type="sun"><vector name="direction" value="0, -1, 0"/></emitter>
<emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>"#,
        ),
        Path::new("t.xml"),
        Path::new("."),
        &[],
    )
    .unwrap();
    assert_eq!(s.lights.len(), 5);
    assert!(
        matches!(s.lights[0].kind, LightKind::Point { position, .. } if position == Vec3::new(1.0, 2.0, 3.0))
    );
    assert!(
        matches!(s.lights[1].kind, LightKind::Spot { cutoff_deg, beam_width_deg, .. } if cutoff_deg == 30.0 && beam_width_deg == 22.5)
    );
    assert!(
        matches!(s.lights[2].kind, LightKind::Directional { direction, .. } if direction == Vec3::new(0.0, -1.0, 0.0))
    );
    assert!(
        matches!(s.lights[3].kind, LightKind::Sun { angular_diameter_deg, .. } if angular_diameter_deg == 0.5338)
    );
    // Bad values name the property.
    for (body, what) in [
        (
            r#"<emitter type="spot"><float name="beam_width" value="30"/></emitter>"#,
            "beam_width",
        ),
        (
            r#"<emitter type="point"><rgb name="intensity" value="-1"/></emitter>"#,
            "intensity",
        ),
        (
            r#"<emitter type="envmap"><string name="filename" value="nope.exr"/></emitter>"#,
            "nope.exr",
        ),
        (
            r#"<emitter type="directional"><vector name="direction" value="0, 0, 0"/></emitter>"#,
            "direction",
        ),
    ] {
        let e = fail(&scene(body));
        assert!(e.to_string().contains(what), "{body}: {e}");
    }
}

#[test]
fn physical_bsdfs_with_mitsuba_defaults_and_names() {
    let s = load(&scene(
        r#"<bsdf type="dielectric" id="glass"><string name="int_ior" value="water"/></bsdf>
<bsdf type="roughconductor" id="gold"><string name="material" value="Au"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>
<bsdf type="orennayar" id="on"><float name="sigma" value="0.3"/><string name="variant" value="EON"/></bsdf>
<shape type="cube"><ref id="glass"/></shape>
<shape type="cube"><ref id="gold"/></shape>
<shape type="cube"><ref id="on"/></shape>"#,
    ))
    .unwrap();
    assert!(
        matches!(s.bsdfs[0].kind, BsdfKind::Dielectric { int_ior, ext_ior } if int_ior == 1.333 && ext_ior == 1.000277)
    );
    assert!(
        matches!(&s.bsdfs[1].kind, BsdfKind::RoughConductor { distribution, alpha_u, alpha_v, .. }
        if distribution == "beckmann" && *alpha_u == 0.1 && *alpha_v == 0.3)
    );
    assert!(matches!(&s.bsdfs[2].kind, BsdfKind::OrenNayar { variant, .. } if variant == "eon"));
    for (body, what) in [
        (
            r#"<shape type="cube"><bsdf type="conductor"><string name="material" value="Unobtainium"/></bsdf></shape>"#,
            "Unobtainium",
        ),
        (
            r#"<shape type="cube"><bsdf type="dielectric"><string name="int_ior" value="glas"/></bsdf></shape>"#,
            "glas",
        ),
        (
            r#"<shape type="cube"><bsdf type="roughconductor"><float name="alpha" value="0"/></bsdf></shape>"#,
            "roughness",
        ),
        (
            r#"<shape type="cube"><bsdf type="roughconductor"><string name="distribution" value="phong"/></bsdf></shape>"#,
            "phong",
        ),
        (
            r#"<shape type="cube"><bsdf type="orennayar"><string name="variant" value="nope"/></bsdf></shape>"#,
            "nope",
        ),
        (
            r#"<shape type="cube"><bsdf type="minnaert"><float name="k" value="-1"/></bsdf></shape>"#,
            "k must be positive",
        ),
        (
            r#"<shape type="cube"><bsdf type="orennayar"><float name="reflectance" value="1.5"/></bsdf></shape>"#,
            "in [0, 1]",
        ),
    ] {
        let e = fail(&scene(body));
        assert!(e.to_string().contains(what), "{body}: {e}");
    }
}

// -------------------------------------------------------------------------------------------
// Media and masks

#[test]
fn interior_medium_inline_and_by_reference_with_scale() {
    let s = load(&scene(r#"<integrator type="volpath"/>
<medium type="homogeneous" id="m"><rgb name="sigma_t" value="0.5, 0.25, 1"/><float name="scale" value="2"/><float name="albedo" value="0"/></medium>
<shape type="sphere"><bsdf type="dielectric"/><ref name="interior" id="m"/></shape>
<shape type="sphere"><bsdf type="dielectric"/><medium type="homogeneous" name="interior"><float name="sigma_t" value="3"/><rgb name="albedo" value="0,0,0"/></medium></shape>
<shape type="sphere"/>"#))
    .unwrap();
    assert_eq!(s.integrator.kind, IntegratorKind::VolPath);
    assert_eq!(
        s.shapes[0].interior.as_ref().unwrap().sigma_t,
        SpectrumDesc::Rgb([1.0, 0.5, 2.0])
    );
    assert_eq!(
        s.shapes[1].interior.as_ref().unwrap().sigma_t,
        SpectrumDesc::Constant(3.0)
    );
    assert!(s.shapes[2].interior.is_none());
}

#[test]
fn scattering_exterior_and_nameless_media_are_clear_errors() {
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"/></shape>"#,
    ));
    assert_error(
        &e,
        2,
        "medium type=\"homogeneous\"",
        "without 'albedo' scatters",
    );
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"><float name="albedo" value="0.5"/></medium></shape>"#,
    ));
    assert_error(&e, 2, "float name=\"albedo\"", "scattering media");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="exterior"><float name="albedo" value="0"/></medium></shape>"#,
    ));
    assert!(e.message.contains("exterior media"), "{e}");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous"><float name="albedo" value="0"/></medium></shape>"#,
    ));
    assert!(e.message.contains("name=\"interior\""), "{e}");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"><float name="albedo" value="0"/><float name="sigma_t" value="-1"/></medium></shape>"#,
    ));
    assert!(e.message.contains("sigma_t"), "{e}");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="heterogeneous" name="interior"/></shape>"#,
    ));
    assert!(
        e.message
            .contains("unsupported plugin medium \"heterogeneous\""),
        "{e}"
    );
}

#[test]
fn mask_wraps_one_bsdf_with_opacity_in_unit_range() {
    let s = load(&scene(r#"<shape type="sphere"><bsdf type="mask"><float name="opacity" value="0.25"/><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf></shape>"#)).unwrap();
    match &s.bsdfs[s.shapes[0].bsdf].kind {
        BsdfKind::Mask { opacity, inner } => {
            assert_eq!(*opacity, 0.25);
            assert!(matches!(inner.kind, BsdfKind::TwoSided { .. }));
        }
        k => panic!("expected a mask, got {k:?}"),
    }
    let e = fail(&scene(
        r#"<shape type="sphere"><bsdf type="mask"><float name="opacity" value="1.5"/><bsdf type="diffuse"/></bsdf></shape>"#,
    ));
    assert!(e.message.contains("opacity must be in [0, 1]"), "{e}");
    let e = fail(&scene(
        r#"<shape type="sphere"><bsdf type="mask"/></shape>"#,
    ));
    assert!(e.message.contains("mask needs one nested <bsdf>"), "{e}");
}

#[test]
fn emitter_bitmap_in_d65_and_display_primaries() {
    // The loader only needs the image to exist (pt-render decodes it).
    let dir = temp_dir("emitter-texture");
    std::fs::write(dir.join("img.png"), b"not decoded here").unwrap();
    std::fs::write(dir.join("p.spd"), "400 0.1\n700 0.2\n").unwrap();
    let area = |inner: &str| {
        scene(&format!(
            "<shape type=\"rectangle\">\n<emitter type=\"area\">\n{inner}\n</emitter></shape>"
        ))
    };
    let bitmap = r#"<texture type="bitmap" name="nested"><string name="filename" value="img.png"/></texture>"#;
    let load_in = |xml: String| {
        std::fs::write(dir.join("s.xml"), xml).unwrap();
        load_file(&dir.join("s.xml"), &[])
    };
    // Mitsuba's d65 texture around a bitmap: the same image, no primaries; RGB mode suffices.
    let s = load_in(area(&format!(
        r#"<texture type="d65" name="radiance">{bitmap}</texture>"#
    )))
    .unwrap();
    let em = s.shapes[0].emitter.as_ref().unwrap();
    assert!(em.texture.as_ref().unwrap().filename.ends_with("img.png") && em.primaries.is_none());
    assert!(s.spectral_reason().is_none());
    // Display primaries: three spectra, which make the scene spectral.
    let tex = r#"<texture type="bitmap" name="radiance"><string name="filename" value="img.png"/></texture>"#;
    let prim = |names: &[&str]| {
        names
            .iter()
            .map(|n| format!(r#"<spectrum name="{n}" filename="p.spd"/>"#))
            .collect::<String>()
    };
    let s = load_in(area(&format!(
        "{tex}{}",
        prim(&["primary_r", "primary_g", "primary_b"])
    )))
    .unwrap();
    let p = s.shapes[0]
        .emitter
        .as_ref()
        .unwrap()
        .primaries
        .as_ref()
        .expect("primaries");
    assert!(p.iter().all(
        |s| matches!(s, SpectrumDesc::Tabulated(t) if t.as_slice() == [(400.0, 0.1), (700.0, 0.2)])
    ));
    assert!(
        s.spectral_reason().unwrap().contains("display primaries"),
        "{:?}",
        s.spectral_reason()
    );
    // Errors: a missing primary, primaries without an image, an RGB primary, d65 without or
    // with two images, a d65 colour.
    let e = load_in(area(&format!("{tex}{}", prim(&["primary_r", "primary_b"])))).unwrap_err();
    assert!(e.message.contains("primary_g is missing"), "{e}");
    let e = load_in(area(&prim(&["primary_r", "primary_g", "primary_b"]))).unwrap_err();
    assert!(e.message.contains("need a radiance texture"), "{e}");
    let e = load_in(area(&format!(
        r#"{tex}<rgb name="primary_r" value="1, 0, 0"/>{}"#,
        prim(&["primary_g", "primary_b"])
    )))
    .unwrap_err();
    assert!(e.message.contains("primary_r must be a spectrum"), "{e}");
    let e = load_in(area(r#"<texture type="d65" name="radiance"/>"#)).unwrap_err();
    assert!(
        e.message
            .contains("needs a nested <texture type=\"bitmap\">"),
        "{e}"
    );
    let e = load_in(area(&format!(
        r#"<texture type="d65" name="radiance">{bitmap}{bitmap}</texture>"#
    )))
    .unwrap_err();
    assert!(
        e.message
            .contains("texture \"bitmap\" is not yet supported in this position"),
        "{e}"
    );
    let e = load_in(area(&format!(r#"<texture type="d65" name="radiance"><rgb name="color" value="1, 1, 1"/>{bitmap}</texture>"#))).unwrap_err();
    assert!(e.message.contains("unused property 'color'"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `normalmap`, textured `mask` and `blendbsdf` read into the IR; their mistakes are located.
#[test]
fn normalmap_mask_texture_and_blend() {
    let dir = temp_dir("surftex");
    std::fs::write(dir.join("n.png"), b"not read by the loader").unwrap();
    let xml = |body: &str| format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n");
    let load_in = |x: &str| load_str(x, &dir.join("test.xml"), &dir, &[]);
    let tex = |name: &str| {
        format!("<texture type=\"bitmap\" name=\"{name}\"><string name=\"filename\" value=\"n.png\"/><boolean name=\"raw\" value=\"true\"/></texture>")
    };
    let d = load_in(&xml(&format!(
        "<shape type=\"cube\"><bsdf type=\"normalmap\">{}<bsdf type=\"diffuse\"/></bsdf></shape>",
        tex("normalmap")
    )))
    .unwrap();
    match &d.bsdfs[0].kind {
        BsdfKind::NormalMap {
            texture,
            scale,
            gltf,
            inner,
        } => {
            assert!(
                !texture.srgb
                    && *scale == 1.0
                    && !gltf
                    && matches!(inner.kind, BsdfKind::Diffuse { .. })
            );
        }
        k => panic!("{k:?}"),
    }
    let d = load_in(&xml(&format!(
        "<shape type=\"cube\"><bsdf type=\"mask\">{}<bsdf type=\"diffuse\"/></bsdf></shape>",
        tex("opacity")
    )))
    .unwrap();
    assert!(
        matches!(&d.bsdfs[0].kind, BsdfKind::OpacityTexture { channel: TextureChannel::Luminance, factor, cutoff: None, .. } if *factor == 1.0)
    );
    let d = load_in(&xml("<shape type=\"cube\"><bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"0.3\"/><bsdf type=\"diffuse\"/><bsdf type=\"conductor\"/></bsdf></shape>")).unwrap();
    match &d.bsdfs[0].kind {
        BsdfKind::Blend {
            weight,
            first,
            second,
            ..
        } => {
            assert!(
                *weight == 0.3
                    && matches!(first.kind, BsdfKind::Diffuse { .. })
                    && matches!(second.kind, BsdfKind::Conductor { .. })
            );
        }
        k => panic!("{k:?}"),
    }
    for (body, text) in [
        ("<shape type=\"cube\"><bsdf type=\"normalmap\"><bsdf type=\"diffuse\"/></bsdf></shape>".to_string(), "normalmap needs <texture"),
        (format!("<shape type=\"cube\"><bsdf type=\"normalmap\">{}</bsdf></shape>", tex("normalmap")), "normalmap needs one nested"),
        (format!("<shape type=\"cube\"><bsdf type=\"mask\"><float name=\"opacity\" value=\"0.5\"/>{}<bsdf type=\"diffuse\"/></bsdf></shape>", tex("opacity")), "either an opacity value or an opacity texture"),
        ("<shape type=\"cube\"><bsdf type=\"blendbsdf\"><bsdf type=\"diffuse\"/></bsdf></shape>".to_string(), "exactly two nested BSDFs, got 1"),
        ("<shape type=\"cube\"><bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"1.5\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf></shape>".to_string(), "weight must be in [0, 1]"),
    ] {
        let e = load_in(&xml(&body)).unwrap_err();
        assert!(e.message.contains(text), "{body}: {e}");
        assert_eq!(e.loc.as_ref().unwrap().line, 2, "{body}: {e}");
    }
}
