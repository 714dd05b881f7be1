//! The XML loader: files, includes, defaults, references, errors, old scenes.

use super::*;

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
            s.integrator.moment.is_some()
        ),
        (8, 5, false)
    );

    // Floor faces up, the light faces down and emits.
    assert!(close(face_normal(mesh(&s.shapes[0]), 0), Vec3::Y));
    let light = &s.shapes[7];
    assert!(close(face_normal(mesh(light), 0), -Vec3::Y));
    let emitter = light.emitter.as_ref().expect("light emits");
    assert_eq!(
        emitter.radiance,
        TextureDesc::Constant(SpectrumDesc::Rgb([17.0, 12.0, 4.0]))
    );
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
        BsdfKind::Diffuse { reflectance } => assert_eq!(
            *reflectance,
            TextureDesc::Constant(SpectrumDesc::Constant(0.25))
        ),
        ref k => panic!("unexpected {k:?}"),
    }
    assert_eq!(s.bsdfs[0].loc.file, dir.join("parts/materials.xml"));
    assert_eq!(s.bsdfs[0].loc.line, 3);
    assert_eq!(mesh(&s.shapes[0]).indices.len(), 1);
}

/// The layout of scene packages: an included file in a subfolder includes a file named
/// relative to the main scene's folder (found through the resolver, which starts there), adds a
/// `<path>` relative to itself, and its shape's mesh is found in that folder.
#[test]
fn included_files_resolve_through_the_main_folder_and_their_own_paths() {
    let dir = temp_dir("include-nested");
    for sub in ["parts/geometry", "common"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    std::fs::write(
        dir.join("parts/geometry/tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("common/bsdfs.xml"),
        r#"<scene version="3.0.0"><bsdf type="diffuse" id="grey"/></scene>"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("parts/shapes.xml"),
        r#"<scene version="3.0.0">
    <path value="geometry"/>
    <include filename="common/bsdfs.xml"/>
    <shape type="obj"><string name="filename" value="tri.obj"/><ref id="grey"/></shape>
</scene>"#,
    )
    .unwrap();
    let main = dir.join("main.xml");
    std::fs::write(
        &main,
        r#"<scene version="3.0.0"><include filename="parts/shapes.xml"/></scene>"#,
    )
    .unwrap();
    let s = load_file(&main, &[]).unwrap();
    assert_eq!(mesh(&s.shapes[0]).indices.len(), 1);
    assert_eq!(s.bsdfs[0].loc.file, dir.join("common/bsdfs.xml"));
    // A folder that exists nowhere is a located error.
    std::fs::write(
        &main,
        "<scene version=\"3.0.0\">\n<path value=\"nowhere\"/>\n</scene>",
    )
    .unwrap();
    let e = load_file(&main, &[]).unwrap_err();
    assert_eq!(e.loc.as_ref().map(|l| l.line), Some(2), "{e}");
    assert!(e.message.contains("folder 'nowhere' not found"), "{e}");
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
fn parameters_the_scene_never_uses_are_errors() {
    // Mitsuba 3.9.1 ("Found unused parameters"): a given parameter that no `$name` uses is
    // refused, even when a <default> declares it; one that is used is fine.
    let xml = "<scene version=\"3.0.0\">\n<default name=\"spp\" value=\"4\"/>\n<default name=\"decl\" value=\"1\"/>\n<sensor type=\"perspective\"><sampler type=\"independent\"><integer name=\"sample_count\" value=\"$spp\"/></sampler></sensor>\n</scene>";
    let load = |defs: &[(&str, &str)]| {
        let defs: Vec<(String, String)> = defs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        crate::load_str(xml, Path::new("p.xml"), Path::new("."), &defs)
    };
    assert_eq!(load(&[("spp", "2")]).unwrap().sampler.sample_count, 2);
    let e = load(&[("decl", "2"), ("spq", "3")]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "p.xml: unused parameters $decl=2, $spq=3 (the scene never uses them; Mitsuba 3 refuses them too)"
    );
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

/// Mitsuba's `<alias>`: a second name for the same object (one BSDF shared by both shapes,
/// an alias of an alias too); an unknown source or a taken name is a located error.
#[test]
fn aliases_name_the_same_object() {
    let d = load(&scene(
        "<bsdf type=\"diffuse\" id=\"white\"><rgb name=\"reflectance\" value=\"0.8\"/></bsdf>\n\
         <alias id=\"white\" as=\"paper\"/>\n<alias id=\"paper\" as=\"wall\"/>\n\
         <shape type=\"cube\"><ref id=\"white\"/></shape>\n\
         <shape type=\"sphere\"><ref id=\"paper\"/></shape>\n\
         <shape type=\"sphere\"><ref id=\"wall\"/></shape>",
    ))
    .unwrap();
    assert_eq!(d.shapes.len(), 3);
    assert!(d.shapes.iter().all(|s| s.bsdf == d.shapes[0].bsdf));
    let e = fail(&scene("<alias id=\"nope\" as=\"b\"/>"));
    assert_error(&e, 2, "alias", "unknown id \"nope\"");
    let e = fail(&scene(
        "<bsdf type=\"diffuse\" id=\"a\"/>\n<bsdf type=\"diffuse\" id=\"b\"/>\n<alias id=\"a\" as=\"b\"/>",
    ));
    assert_error(&e, 4, "alias", "duplicate id \"b\"");
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
        "<bsdf type=\"measured\"/>",
        "<emitter type=\"directionalarea\"/>",
        "<sensor type=\"perspective\"><sampler type=\"orthogonal\"><integer name=\"strength\" value=\"3\"/></sampler></sensor>",
        "<integrator type=\"stokes\"/>",
        "<shape type=\"ellipsoids\"/>",
        "<shape type=\"ellipsoidsmesh\"/>",
        "<shape type=\"cube\"><bsdf type=\"measured\"/></shape>",
        "<shape type=\"cube\"><bsdf type=\"diffuse\"><texture type=\"volume\" name=\"reflectance\"/></bsdf></shape>",
        "<sensor type=\"perspective\"><film type=\"specfilm\"/></sensor>",
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
        matches!(s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: TextureDesc::Constant(SpectrumDesc::Rgb([r, _, _])) } if r == 0.2)
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
