//! Shapes: OBJ meshes, spheres, disks, rectangles, default BSDFs, media.

use super::*;

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
            frame,
        } => {
            assert!(close(center, Vec3::new(2.0, 3.0, 0.0)));
            assert_eq!((radius, flip_normals), (1.0, true));
            assert!(frame.abs_diff_eq(glam::Mat3::IDENTITY, 1e-6), "{frame}");
        }
        _ => panic!("not a sphere"),
    }
    // A rotation is kept as the sphere's frame (object space z along world y here); a
    // mirroring scale turns the sphere inside out, as in Mitsuba.
    let s = load(&scene(
        r#"<shape type="sphere"><transform name="to_world"><rotate x="1" angle="-90"/><scale x="-3" y="3" z="3"/></transform></shape>"#,
    ))
    .unwrap();
    match s.shapes[0].geometry {
        Geometry::Sphere {
            radius,
            flip_normals,
            frame,
            ..
        } => {
            assert!(
                (radius - 3.0).abs() < 1e-5 && flip_normals,
                "{radius} {flip_normals}"
            );
            assert!(close(frame * Vec3::Z, Vec3::Y), "{frame}");
            assert!(close(frame * Vec3::X, -Vec3::X), "{frame}");
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
    let Geometry::Disk(disk) = &s.shapes[0].geometry else {
        panic!("a disk is analytic");
    };
    assert!(
        (disk.area() - 9.0 * std::f32::consts::PI).abs() < 1e-4,
        "{disk:?}"
    );
    assert!(close(disk.normal, Vec3::Z) && close(disk.axes[1], 3.0 * Vec3::Y));
    // Its triangle fan (for the radiosity solver) has the same area and front side.
    let fan = disk.to_mesh();
    let area: f32 = (0..fan.indices.len())
        .map(|t| {
            let p = fan.indices[t].map(|i| fan.positions[i as usize]);
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
        })
        .sum();
    assert!((area - 9.0 * std::f32::consts::PI).abs() < 1e-3, "{area}");
    assert!(close(face_normal(&fan, 7), Vec3::Z));
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
        matches!(s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: TextureDesc::Constant(SpectrumDesc::Constant(r)) } if r == 0.5)
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
            reflectance: TextureDesc::Constant(SpectrumDesc::Constant(r)),
        } => r,
        ref k => panic!("unexpected {k:?}"),
    };
    assert_eq!((r(0), r(1)), (0.0, 0.5));
}

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
fn media_on_both_sides_the_sensor_and_phase_functions() {
    let s = load(&scene(r#"<integrator type="volpath"/>
<medium type="homogeneous" id="fog"><float name="sigma_t" value="0.5"/><phase type="hg"><float name="g" value="0.3"/></phase></medium>
<sensor type="perspective"><ref id="fog"/></sensor>
<shape type="cube"><bsdf type="null"/><ref name="interior" id="fog"/>
    <medium type="homogeneous" name="exterior"><rgb name="albedo" value="0.2, 0.4, 0.6"/><boolean name="sample_emitters" value="false"/></medium></shape>"#))
    .unwrap();
    let fog = s.camera_medium.as_ref().unwrap();
    // Mitsuba's default albedo, and the phase function given.
    assert_eq!(
        fog.albedo,
        VolumeDesc::Constant(SpectrumDesc::Constant(0.75))
    );
    assert_eq!(fog.phase, PhaseDesc::HenyeyGreenstein { g: 0.3 });
    assert!(fog.sample_emitters);
    assert_eq!(s.shapes[0].interior.as_ref(), Some(fog));
    let outside = s.shapes[0].exterior.as_ref().unwrap();
    assert_eq!(
        outside.albedo,
        VolumeDesc::Constant(SpectrumDesc::Rgb([0.2, 0.4, 0.6]))
    );
    assert_eq!(outside.phase, PhaseDesc::Isotropic);
    assert_eq!(outside.sigma_t, SpectrumDesc::Constant(1.0));
    assert!(!outside.sample_emitters);
    assert!(s.spectral_reason().is_none());
    // A tabulated extinction selects spectral mode, as a tabulated BSDF spectrum does.
    let s = load(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="exterior"><spectrum name="sigma_t" value="400:1, 700:2"/></medium></shape>"#,
    ))
    .unwrap();
    assert!(
        s.spectral_reason()
            .unwrap()
            .contains("spectrum in a medium"),
        "{:?}",
        s.spectral_reason()
    );
}

#[test]
fn bad_media_are_clear_errors() {
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"><float name="albedo" value="1.5"/></medium></shape>"#,
    ));
    assert_error(&e, 2, "float name=\"albedo\"", "albedo must lie in [0, 1]");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"><phase type="hg"><float name="g" value="1"/></phase></medium></shape>"#,
    ));
    assert!(e.message.contains("g must lie in (-1, 1)"), "{e}");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"><phase type="sggx"/></medium></shape>"#,
    ));
    assert!(
        e.message.contains("unsupported plugin phase \"sggx\""),
        "{e}"
    );
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"><phase type="rayleigh"><float name="g" value="0.5"/></phase></medium></shape>"#,
    ));
    assert!(e.message.contains("unused property 'g'"), "{e}");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="exterior"/><medium type="homogeneous" name="exterior"/></shape>"#,
    ));
    assert!(e.message.contains("only one exterior medium"), "{e}");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous"><float name="albedo" value="0"/></medium></shape>"#,
    ));
    assert!(e.message.contains("name=\"interior\""), "{e}");
    let e = fail(&scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"><float name="albedo" value="0"/><float name="sigma_t" value="-1"/></medium></shape>"#,
    ));
    assert!(e.message.contains("sigma_t"), "{e}");
}

/// `tabphase` reads its values (commas or spaces) and refuses tables it cannot normalise.
#[test]
fn tabphase_reads_its_table() {
    let phase = |inner: &str| {
        load(&scene(&format!(
            "<shape type=\"sphere\"><medium type=\"homogeneous\" name=\"interior\"><phase type=\"tabphase\">{inner}</phase></medium></shape>"
        )))
        .map(|s| s.shapes[0].interior.as_ref().unwrap().phase.clone())
    };
    assert_eq!(
        phase(r#"<string name="values" value="0.5, 1 2,3"/>"#).unwrap(),
        PhaseDesc::Tabulated(vec![0.5, 1.0, 2.0, 3.0])
    );
    for (inner, want) in [
        ("", "a tabphase needs <string name=\"values\""),
        (
            r#"<string name="values" value="1"/>"#,
            "at least two values",
        ),
        (
            r#"<string name="values" value="1, x"/>"#,
            "'x' is not a number",
        ),
        (
            r#"<string name="values" value="1, -2"/>"#,
            "finite and >= 0, got -2",
        ),
        (r#"<string name="values" value="0 0 0"/>"#, "all 0"),
    ] {
        let e = phase(inner).unwrap_err();
        assert!(e.message.contains(want), "{inner}: {e}");
    }
}

/// A folder `name` in the temporary directory with the grids the medium tests read: one and
/// three channels of 0.5, a negative one, six channels, and an albedo of 1.5.
fn medium_grids(name: &str) -> PathBuf {
    use crate::volgrid::{write_vol, VolumeGrid};
    let dir = temp_dir(name);
    let grid = |channels: u32, value: f32| VolumeGrid {
        resolution: [2, 3, 2],
        channels,
        bbox: [[1.0, 2.0, 3.0], [2.0, 4.0, 7.0]],
        values: vec![value; 12 * channels as usize],
    };
    for (name, g) in [
        ("one.vol", grid(1, 0.5)),
        ("rgb.vol", grid(3, 0.5)),
        ("neg.vol", grid(1, -1.0)),
        ("six.vol", grid(6, 0.5)),
        ("bright.vol", grid(3, 1.5)),
    ] {
        std::fs::write(dir.join(name), write_vol(&g)).unwrap();
    }
    dir
}

/// Loads the scene `xml` with files relative to `dir`.
fn load_in(dir: &Path, xml: &str) -> Result<SceneDesc, SceneError> {
    load_str(xml, Path::new("test.xml"), dir, &[])
}

/// A scene of a cube holding a heterogeneous medium with the children `inner`.
fn heterogeneous(inner: &str) -> String {
    scene(&format!(
        "<shape type=\"cube\"><bsdf type=\"null\"/><medium type=\"heterogeneous\" name=\"interior\">{inner}</medium></shape>"
    ))
}

#[test]
fn heterogeneous_medium_reads_its_grid() {
    let dir = medium_grids("heterogeneous");
    let s = load_in(&dir, &heterogeneous(
        r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="one.vol"/>
           <transform name="to_world"><scale value="2"/></transform></volume>
           <float name="scale" value="4"/>
           <volume type="constvolume" name="albedo"><rgb name="value" value="0.5, 0.6, 0.7"/></volume>"#,
    ))
    .unwrap();
    let m = s.shapes[0].interior.as_ref().unwrap();
    // sigma_t holds the scale; the grid its spatial factor.
    assert_eq!(m.sigma_t, SpectrumDesc::Constant(4.0));
    assert_eq!(
        m.albedo,
        VolumeDesc::Constant(SpectrumDesc::Rgb([0.5, 0.6, 0.7]))
    );
    let d = m.density.as_ref().unwrap();
    assert_eq!(d.grid.resolution, [2, 3, 2]);
    assert_eq!(d.to_world, glam::Mat4::from_scale(Vec3::splat(2.0)));
    assert!(!d.nearest);
    // use_grid_bbox: the file's box, then to_world.
    let s = load_in(&dir, &heterogeneous(
        r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="one.vol"/>
           <boolean name="use_grid_bbox" value="true"/><string name="filter_type" value="nearest"/></volume>"#,
    ))
    .unwrap();
    let d = s.shapes[0]
        .interior
        .as_ref()
        .unwrap()
        .density
        .clone()
        .unwrap();
    assert!(d.nearest);
    assert_eq!(
        d.to_world.transform_point3(Vec3::ONE),
        Vec3::new(2.0, 4.0, 7.0)
    );
}

#[test]
fn heterogeneous_medium_reads_rgb_grids_and_emission() {
    let dir = medium_grids("heterogeneous-rgb");
    // Three-channel (RGB) grids for extinction, albedo and emission, each with its own
    // transform; a constant emission.
    let s = load_in(&dir, &heterogeneous(
        r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="rgb.vol"/></volume>
           <volume type="gridvolume" name="albedo"><string name="filename" value="rgb.vol"/>
               <transform name="to_world"><translate value="1, 0, 0"/></transform></volume>
           <volume type="gridvolume" name="emission"><string name="filename" value="one.vol"/></volume>"#,
    ))
    .unwrap();
    let m = s.shapes[0].interior.as_ref().unwrap();
    assert_eq!(m.density.as_ref().unwrap().grid.channels, 3);
    let VolumeDesc::Grid(albedo) = &m.albedo else {
        panic!("albedo grid: {:?}", m.albedo)
    };
    assert_eq!(albedo.grid.channels, 3);
    assert_eq!(
        albedo.to_world,
        glam::Mat4::from_translation(Vec3::new(1.0, 0.0, 0.0))
    );
    assert!(matches!(m.emission, Some(VolumeDesc::Grid(_))));
    let s = load_in(&dir, &scene(
        r#"<shape type="sphere"><medium type="homogeneous" name="interior"><rgb name="emission" value="1, 2, 3"/>
           <volume type="gridvolume" name="albedo"><string name="filename" value="one.vol"/></volume></medium></shape>"#,
    ))
    .unwrap();
    let m = s.shapes[0].interior.as_ref().unwrap();
    assert_eq!(
        m.emission,
        Some(VolumeDesc::Constant(SpectrumDesc::Rgb([1.0, 2.0, 3.0])))
    );
    assert!(matches!(m.albedo, VolumeDesc::Grid(_)));
}

#[test]
fn heterogeneous_medium_refuses_what_it_cannot_trace() {
    let dir = medium_grids("heterogeneous-refused");
    for (inner, want) in [
        (
            r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="six.vol"/></volume>"#,
            "has 6 channels; a medium's sigma_t grid needs 1 or 3",
        ),
        (
            r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="neg.vol"/></volume>"#,
            "finite and >= 0",
        ),
        (
            r#"<volume type="gridvolume" name="sigma_t"/>"#,
            "missing <string name=\"filename\"",
        ),
        (
            r#"<volume type="gridvolume" name="albedo"><string name="filename" value="bright.vol"/></volume>"#,
            "holds 1.5; albedo must be in [0, 1]",
        ),
        (
            r#"<volume type="gridvolume" name="emission"><string name="filename" value="one.vol"/></volume>"#,
            "an emission grid needs an extinction grid",
        ),
        (
            r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="rgb.vol"/><boolean name="raw" value="true"/></volume>"#,
            "raw",
        ),
        (
            r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="one.vol"/><string name="wrap_mode" value="repeat"/></volume>"#,
            "wrap_mode \"repeat\" is not supported",
        ),
        (
            r#"<float name="emission" value="-1"/>"#,
            "emission must be finite and >= 0",
        ),
        (
            r#"<float name="albedo" value="0.5"/><volume type="constvolume" name="albedo"/>"#,
            "albedo is given twice",
        ),
        (
            r#"<volume type="constvolume" name="density"/>"#,
            "name=\"sigma_t\", name=\"albedo\" or name=\"emission\"",
        ),
    ] {
        let e = load_in(&dir, &heterogeneous(inner)).unwrap_err();
        assert!(e.message.contains(want), "{inner}: {e}");
    }
}

#[test]
fn homogeneous_medium_refuses_extinction_and_emission_grids() {
    let dir = medium_grids("homogeneous-grids");
    // A homogeneous medium reads constant volumes, and refuses extinction and emission grids.
    let homogeneous = |inner: &str| {
        load_in(&dir, &scene(&format!(
            "<shape type=\"sphere\"><medium type=\"homogeneous\" name=\"interior\">{inner}</medium></shape>"
        )))
    };
    homogeneous(r#"<volume type="constvolume" name="sigma_t"/>"#).unwrap();
    for (inner, want) in [
        (
            r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="one.vol"/></volume>"#,
            "use type=\"heterogeneous\" for grids",
        ),
        (
            r#"<volume type="gridvolume" name="emission"><string name="filename" value="one.vol"/></volume>"#,
            "an emission grid needs a heterogeneous medium",
        ),
    ] {
        let e = homogeneous(inner).unwrap_err();
        assert!(e.message.contains(want), "{inner}: {e}");
    }
}

#[test]
fn sdfgrid_loads_its_grid_and_refuses_what_it_cannot_render() {
    use crate::volgrid::{write_vol, VolumeGrid};
    let dir = temp_dir("sdfgrid");
    // A 3 x 2 x 2 grid: the plane x = 0.5 (object space).
    let plane = |channels: u32, res: [u32; 3], f: &dyn Fn(u32) -> f32| VolumeGrid {
        resolution: res,
        channels,
        bbox: [[0.0; 3], [1.0; 3]],
        values: (0..res.iter().product::<u32>() * channels).map(f).collect(),
    };
    let files = [
        (
            "plane.vol",
            plane(1, [3, 2, 2], &|i| (i % 3) as f32 * 0.5 - 0.5),
        ),
        ("two.vol", plane(2, [3, 2, 2], &|_| 0.0)),
        ("thin.vol", plane(1, [3, 1, 2], &|_| 0.0)),
        ("empty.vol", plane(1, [3, 2, 2], &|_| 1.0)),
    ];
    for (name, g) in &files {
        std::fs::write(dir.join(name), write_vol(g)).unwrap();
    }
    let shape = |file: &str, inner: &str| {
        scene(&format!(
            "<shape type=\"sdfgrid\">\n<string name=\"filename\" value=\"{file}\"/>\n{inner}</shape>"
        ))
    };
    let load_in = |xml: &str| load_str(xml, Path::new("test.xml"), &dir, &[]);
    let s = load_in(&shape(
        "plane.vol",
        "<transform name=\"to_world\"><scale value=\"2, 3, 4\"/><translate value=\"1, 0, 0\"/></transform>\n",
    ))
    .unwrap();
    let Geometry::SdfGrid(g) = &s.shapes[0].geometry else {
        panic!("not an sdfgrid")
    };
    assert_eq!(g.resolution, [3, 2, 2]);
    assert_eq!((g.origin, g.extent), (Vec3::X, Vec3::new(2.0, 3.0, 4.0)));
    assert!(g.smooth_normals);
    // The two voxels along x both touch the plane (its samples are 0 on the middle layer).
    assert_eq!(g.occupied_voxels().count(), 2);
    let s = load_in(&shape(
        "plane.vol",
        "<string name=\"normals\" value=\"analytic\"/>\n",
    ))
    .unwrap();
    assert!(matches!(&s.shapes[0].geometry, Geometry::SdfGrid(g) if !g.smooth_normals));

    let cases = [
        (shape("missing.vol", ""), "cannot open grid 'missing.vol'"),
        (shape("two.vol", ""), "has 2 channels; an sdfgrid needs 1"),
        (shape("thin.vol", ""), "needs at least 2"),
        (
            shape("empty.vol", ""),
            "no voxel the surface passes through",
        ),
        (
            shape("plane.vol", "<string name=\"normals\" value=\"flat\"/>\n"),
            "not one of: smooth, analytic",
        ),
        (
            shape(
                "plane.vol",
                "<transform name=\"to_world\"><rotate y=\"1\" angle=\"30\"/></transform>\n",
            ),
            "positive scales and a translation",
        ),
        (
            shape(
                "plane.vol",
                "<transform name=\"to_world\"><scale value=\"-1, 1, 1\"/></transform>\n",
            ),
            "positive scales and a translation",
        ),
        (
            shape(
                "plane.vol",
                "<boolean name=\"flip_normals\" value=\"true\"/>\n",
            ),
            "has no flip_normals",
        ),
        (
            shape("plane.vol", "<emitter type=\"area\"/>\n"),
            "cannot be an area emitter",
        ),
        (
            scene("<shape type=\"sdfgrid\">\n</shape>"),
            "missing <string name=\"filename\"",
        ),
    ];
    for (xml, want) in cases {
        let e = load_in(&xml).unwrap_err();
        // At the shape, or at the property at fault inside it.
        let loc = e.loc.as_ref().expect("located");
        assert!(loc.line >= 2 && !loc.element.is_empty(), "{e}");
        assert!(e.message.contains(want), "{want}: {e}");
    }
}

/// `linearcurve` and `bsplinecurve` read their curve files (positions through `to_world`,
/// radii not), and refuse what they cannot be: bad files with the file's line, emitters,
/// media, `flip_normals`.
#[test]
fn curves_load_their_files_and_refuse_what_they_cannot_render() {
    let dir = temp_dir("curves");
    std::fs::write(
        dir.join("strands.txt"),
        "0 0 0 0.1\n0 1 0 0.1\n0 2 0 0.05\n0 3 0 0.05\n\n1 0 0 0.1\n1 1 0 0.1\n1 2 0 0.1\n1 3 0 0.1\n1 4 0 0.1\n",
    )
    .unwrap();
    std::fs::write(dir.join("bad.txt"), "0 0 0 0.1\n0 1 0 0.1\n0 2 0\n").unwrap();
    let shape = |plugin: &str, file: &str, inner: &str| {
        scene(&format!(
            "<shape type=\"{plugin}\">\n<string name=\"filename\" value=\"{file}\"/>\n{inner}</shape>"
        ))
    };
    let load_in = |xml: &str| load_str(xml, Path::new("test.xml"), &dir, &[]);
    let moved =
        "<transform name=\"to_world\"><scale value=\"2\"/><translate x=\"1\"/></transform>\n";
    let s = load_in(&shape("linearcurve", "strands.txt", moved)).unwrap();
    let Geometry::Curves(c) = &s.shapes[0].geometry else {
        panic!("not curves")
    };
    assert_eq!(c.basis, CurveBasis::Linear);
    assert_eq!(c.segments, vec![0, 1, 2, 4, 5, 6, 7]);
    assert_eq!(c.points[2], glam::Vec4::new(1.0, 4.0, 0.0, 0.05));
    let s = load_in(&shape("bsplinecurve", "strands.txt", "")).unwrap();
    let Geometry::Curves(c) = &s.shapes[0].geometry else {
        panic!("not curves")
    };
    assert_eq!(
        (c.basis, c.segments.clone()),
        (CurveBasis::BSpline, vec![0, 4, 5])
    );
    let cases = [
        (
            shape("linearcurve", "missing.txt", ""),
            "cannot open curve file 'missing.txt'",
            2,
        ),
        (
            shape("linearcurve", "bad.txt", ""),
            "curve file 'bad.txt', line 3: expected four numbers",
            2,
        ),
        (
            shape("bsplinecurve", "strands.txt", "<emitter type=\"area\"/>\n"),
            "cannot be an area emitter",
            2,
        ),
        (
            shape(
                "linearcurve",
                "strands.txt",
                "<boolean name=\"flip_normals\" value=\"true\"/>\n",
            ),
            "has no flip_normals",
            4,
        ),
        (
            shape(
                "linearcurve",
                "strands.txt",
                "<medium type=\"homogeneous\" name=\"interior\"/>\n",
            ),
            "cannot bound a medium",
            2,
        ),
    ];
    for (xml, want, line) in cases {
        let e = load_in(&xml).expect_err(&xml);
        let loc = e.loc.as_ref().expect("located");
        assert_eq!(loc.line, line, "{e}");
        assert!(e.message.contains(want), "expected '{want}' in: {e}");
    }
}

/// `blendphase` nests two phase functions (blends of blends too) with a constant weight, the
/// second's share as in Mitsuba; a missing or third phase, a texture, a `<ref>`, a weight out
/// of [0, 1] are located errors.
#[test]
fn blendphase_nests_two_phase_functions() {
    let medium = |phase: &str| {
        scene(&format!(
            "<integrator type=\"volpath\"/>\n<sensor type=\"perspective\"><medium type=\"homogeneous\">\n{phase}\n</medium></sensor>"
        ))
    };
    let s = load(&medium(
        r#"<phase type="blendphase"><float name="weight" value="0.25"/><phase type="isotropic"/><phase type="blendphase"><phase type="hg"><float name="g" value="0.5"/></phase><phase type="hg"><float name="g" value="-0.5"/></phase></phase></phase>"#,
    ))
    .unwrap();
    let hg = |g| Box::new(PhaseDesc::HenyeyGreenstein { g });
    assert_eq!(
        s.camera_medium.as_ref().unwrap().phase,
        PhaseDesc::Blend {
            weight: 0.25,
            first: Box::new(PhaseDesc::Isotropic),
            second: Box::new(PhaseDesc::Blend {
                weight: 0.5,
                first: hg(0.5),
                second: hg(-0.5),
            }),
        }
    );
    for (phase, want) in [
        (
            r#"<phase type="blendphase"><phase type="isotropic"/></phase>"#,
            "exactly two nested phase functions, found 1",
        ),
        (
            r#"<phase type="blendphase"><float name="weight" value="1.5"/><phase type="isotropic"/><phase type="isotropic"/></phase>"#,
            "weight must lie in [0, 1]",
        ),
        (
            r#"<phase type="blendphase"><texture type="bitmap" name="weight"/><phase type="isotropic"/><phase type="isotropic"/></phase>"#,
            "blendphase",
        ),
        (
            r#"<phase type="blendphase"><phase type="isotropic"/><bsdf type="diffuse"/></phase>"#,
            "nests phase functions, not <bsdf>",
        ),
    ] {
        let e = fail(&medium(phase));
        assert!(e.loc.is_some() && e.message.contains(want), "{phase}: {e}");
    }
}
