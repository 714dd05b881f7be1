//! BSDFs, textures, spectra and emitters.

use super::*;

#[test]
fn spectrum_pairs_are_tabulated_spectra() {
    let s = load(&scene(
        "<shape type=\"cube\"><bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"400:0.1, 700:0.5\"/>\n</bsdf></shape>",
    ))
    .unwrap();
    assert!(
        matches!(&s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: TextureDesc::Constant(SpectrumDesc::Tabulated(p)) } if p.as_slice() == [(400.0, 0.1), (700.0, 0.5)])
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
        matches!(s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: TextureDesc::Constant(SpectrumDesc::Uniform(r)) } if r == 0.3),
        "one number in a <spectrum> is Mitsuba's uniform (equal-energy) spectrum"
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
        matches!(&s.bsdfs[0].kind, BsdfKind::Diffuse { reflectance: TextureDesc::Constant(SpectrumDesc::Tabulated(p)) } if p.as_slice() == [(400.0, 0.25), (550.0, 0.5), (700.0, 0.75)])
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
        TextureDesc::Constant(SpectrumDesc::Blackbody {
            temperature: 2500.0
        })
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
        TextureDesc::Constant(SpectrumDesc::Illuminant {
            name: "d65".into(),
            scale: 3.0
        })
    );
    let s = load(&emitter("<spectrum type=\"d65\" name=\"radiance\"/>")).unwrap();
    assert_eq!(
        radiance(&s),
        TextureDesc::Constant(SpectrumDesc::Illuminant {
            name: "d65".into(),
            scale: 1.0
        })
    );
    for (t, name) in [("A", "a"), ("f1", "f1"), ("F11", "f11"), ("f12", "f12")] {
        let s = load(&emitter(&format!(
            "<spectrum type=\"{t}\" name=\"radiance\"/>"
        )))
        .unwrap();
        assert_eq!(
            radiance(&s),
            TextureDesc::Constant(SpectrumDesc::Illuminant {
                name: name.into(),
                scale: 1.0
            }),
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
            BsdfKind::Diffuse { reflectance: TextureDesc::Constant(SpectrumDesc::Rgb([r, _, _])) } if r == 0.8
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
        (
            r#"<emitter type="point"><texture type="checkerboard" name="intensity"/></emitter>"#,
            "cannot be a texture that varies over space",
        ),
        (
            r#"<emitter type="spot"><texture type="checkerboard" name="intensity"/></emitter>"#,
            "cannot be a texture that varies over space",
        ),
    ] {
        let e = fail(&scene(body));
        assert!(e.to_string().contains(what), "{body}: {e}");
    }
}

#[test]
fn photometric_lights_read_ies_files_and_locate_their_errors() {
    let dir = std::env::temp_dir().join(format!("pt-ies-loader-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = "IESNA:LM-63-2002\r\n[TEST] t\r\nTILT=NONE\r\n1 -1 1 3 1 1 2 0 0 0\r\n1 1 10\r\n0 45 90\r\n0\r\n100 50 0\r\n";
    std::fs::write(dir.join("good.ies"), good).unwrap();
    std::fs::write(dir.join("short.ies"), good.replace("100 50 0", "100 50")).unwrap();
    let xml = scene(
        r#"<emitter type="point"><string name="ies" value="good.ies"/><float name="scale" value="2"/>
    <transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, 1"/></transform></emitter>
<emitter type="goniometric"><string name="filename" value="good.ies"/>
    <transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    <float name="scale" value="2"/></emitter>
<emitter type="spot"><string name="ies" value="good.ies"/></emitter>
<emitter type="goniometric"><string name="filename" value="sky.exr"/></emitter>"#,
    );
    std::fs::write(dir.join("sky.exr"), b"not read by the loader").unwrap();
    let s = load_str(&xml, Path::new("t.xml"), &dir, &[]).unwrap();
    // The `ies` parameter of a point light and the goniometric plugin make the same light.
    let (
        LightKind::Point {
            profile: Some(a),
            position: pa,
            ..
        },
        LightKind::Point {
            profile: Some(b),
            position: pb,
            ..
        },
    ) = (&s.lights[0].kind, &s.lights[1].kind)
    else {
        panic!("{:?}", s.lights)
    };
    assert_eq!(pa, pb);
    assert_eq!(a.scale, 2.0);
    assert_eq!(a.to_world, b.to_world);
    // The nadir (local +z) points down.
    assert!((a.to_world * Vec3::Z - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6);
    let (ProfileSource::Ies(ta), ProfileSource::Ies(tb)) = (&a.source, &b.source) else {
        panic!()
    };
    assert_eq!(ta, tb);
    assert_eq!(ta.values, vec![100.0, 50.0, 0.0]);
    assert!(matches!(
        &s.lights[2].kind,
        LightKind::Spot {
            profile: Some(_),
            ..
        }
    ));
    assert!(
        matches!(&s.lights[3].kind, LightKind::Point { profile: Some(p), .. } if matches!(p.source, ProfileSource::Image(_)))
    );
    // Errors name the element, the file and the file's line.
    for (body, line, what) in [
        (
            r#"<emitter type="point"><string name="ies" value="short.ies"/></emitter>"#,
            2,
            "IES file 'short.ies', line 8: the file ends before the 3 candela values",
        ),
        (
            r#"<emitter type="spot"><string name="ies" value="none.ies"/></emitter>"#,
            2,
            "cannot open 'none.ies'",
        ),
        (r#"<emitter type="goniometric"/>"#, 2, "needs a filename"),
        (
            r#"<emitter type="goniometric"><string name="filename" value="good.ies"/>
<transform name="to_world"><scale value="1, 1, 2"/></transform></emitter>"#,
            3,
            "must be a rotation",
        ),
        (
            r#"<emitter type="point"><string name="ies" value="good.ies"/><float name="scale" value="-2"/></emitter>"#,
            2,
            "scale",
        ),
        (
            r#"<emitter type="point"><float name="scale" value="2"/></emitter>"#,
            2,
            "scale",
        ),
    ] {
        let e = load_str(&scene(body), Path::new("t.xml"), &dir, &[]).unwrap_err();
        assert!(e.to_string().contains(what), "{body}: {e}");
        assert_eq!(e.loc.as_ref().map(|l| l.line), Some(line), "{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn projected_images_on_spots_and_projectors() {
    let s = load(&scene(
        r#"<emitter type="spot"><texture type="checkerboard" name="texture"/></emitter>
<emitter type="projector"><texture type="checkerboard" name="irradiance"/><float name="fov" value="30"/></emitter>
<emitter type="projector"><rgb name="irradiance" value="0.5, 0.4, 0.3"/></emitter>"#,
    ))
    .unwrap();
    assert!(matches!(
        &s.lights[0].kind,
        LightKind::Spot {
            texture: Some(TextureDesc::Checkerboard(_)),
            ..
        }
    ));
    assert!(matches!(
        &s.lights[1].kind,
        LightKind::Projector { irradiance: TextureDesc::Checkerboard(_), scale, projection: Projection::Perspective { fov_deg, fov_axis: FovAxis::X }, .. } if *scale == 1.0 && *fov_deg == 30.0
    ));
    // Mitsuba's default: a 50 mm lens on the diagonal of a 36 x 24 mm film.
    assert!(matches!(
        &s.lights[2].kind,
        LightKind::Projector {
            irradiance: TextureDesc::Constant(SpectrumDesc::Rgb(_)),
            projection: Projection::Perspective {
                fov_axis: FovAxis::Diagonal,
                ..
            },
            ..
        }
    ));
    for (body, line, what) in [
        // Mitsuba refuses a spot texture that does not vary.
        (
            r#"<emitter type="spot">
<rgb name="texture" value="0.5"/></emitter>"#,
            3,
            "texture",
        ),
        (
            r#"<emitter type="spot">
<texture type="bitmap" name="irradiance"><string name="filename" value="x.png"/></texture></emitter>"#,
            3,
            "texture name=\"texture\"",
        ),
        (
            r#"<emitter type="projector"><rgb name="irradiance" value="1"/>
<texture type="checkerboard" name="irradiance"/></emitter>"#,
            2,
            "either",
        ),
        (
            r#"<emitter type="projector"><float name="scale" value="-1"/></emitter>"#,
            2,
            "scale",
        ),
    ] {
        let e = fail(&scene(body));
        assert!(e.to_string().contains(what), "{body}: {e}");
        assert!(e.to_string().contains(&format!(":{line}:")), "{body}: {e}");
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
        matches!(s.bsdfs[0].kind, BsdfKind::Dielectric { int_ior, ext_ior, .. } if int_ior == 1.333 && ext_ior == 1.000277)
    );
    assert!(
        matches!(&s.bsdfs[1].kind, BsdfKind::RoughConductor { microfacet, .. }
        if microfacet.distribution == MicrofacetDistribution::Beckmann
            && microfacet.alpha_u == TextureDesc::constant(0.1)
            && microfacet.alpha_v == TextureDesc::constant(0.3))
    );
    assert!(
        matches!(&s.bsdfs[2].kind, BsdfKind::OrenNayar { variant, .. } if *variant == OrenNayarVariant::Eon)
    );
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
fn mask_wraps_one_bsdf_with_opacity_in_unit_range() {
    let s = load(&scene(r#"<shape type="sphere"><bsdf type="mask"><float name="opacity" value="0.25"/><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf></shape>"#)).unwrap();
    match &s.bsdfs[s.shapes[0].bsdf].kind {
        BsdfKind::Mask {
            opacity,
            cutoff: None,
            inner,
        } => {
            assert_eq!(*opacity, TextureDesc::constant(0.25));
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
    assert!(e.message.contains("needs one nested BSDF"), "{e}");
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
    assert!(
        matches!(&em.radiance, TextureDesc::Bitmap(b) if b.source == ImageSource::File(dir.join("img.png")))
            && em.primaries.is_none()
    );
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
    assert!(e.message.contains("need a radiance bitmap"), "{e}");
    let e = load_in(area(&format!(
        r#"{tex}<rgb name="primary_r" value="1, 0, 0"/>{}"#,
        prim(&["primary_g", "primary_b"])
    )))
    .unwrap_err();
    assert!(e.message.contains("primary_r must be a spectrum"), "{e}");
    let e = load_in(area(r#"<texture type="d65" name="radiance"/>"#)).unwrap_err();
    assert!(e.message.contains("needs a nested <texture>"), "{e}");
    let e = load_in(area(&format!(
        r#"<texture type="d65" name="radiance">{bitmap}{bitmap}</texture>"#
    )))
    .unwrap_err();
    assert!(e.message.contains("one nested <texture>"), "{e}");
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
                matches!(texture, TextureDesc::Bitmap(b) if b.raw)
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
    assert!(matches!(
        &d.bsdfs[0].kind,
        BsdfKind::Mask {
            opacity: TextureDesc::Bitmap(_),
            cutoff: None,
            ..
        }
    ));
    let d = load_in(&xml("<shape type=\"cube\"><bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"0.3\"/><bsdf type=\"diffuse\"/><bsdf type=\"conductor\"/></bsdf></shape>")).unwrap();
    match &d.bsdfs[0].kind {
        BsdfKind::Blend {
            weight,
            first,
            second,
            ..
        } => {
            assert!(
                *weight == TextureDesc::constant(0.3)
                    && matches!(first.kind, BsdfKind::Diffuse { .. })
                    && matches!(second.kind, BsdfKind::Conductor { .. })
            );
        }
        k => panic!("{k:?}"),
    }
    for (body, text) in [
        ("<shape type=\"cube\"><bsdf type=\"normalmap\"><bsdf type=\"diffuse\"/></bsdf></shape>".to_string(), "normalmap needs <texture"),
        (format!("<shape type=\"cube\"><bsdf type=\"normalmap\">{}</bsdf></shape>", tex("normalmap")), "needs one nested BSDF"),
        (format!("<shape type=\"cube\"><bsdf type=\"mask\"><float name=\"opacity\" value=\"0.5\"/>{}<bsdf type=\"diffuse\"/></bsdf></shape>", tex("opacity")), "'opacity' is given both as a value and as a texture"),
        ("<shape type=\"cube\"><bsdf type=\"blendbsdf\"><bsdf type=\"diffuse\"/></bsdf></shape>".to_string(), "needs 2 nested BSDFs (<bsdf> or <ref>), got 1"),
        ("<shape type=\"cube\"><bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"1.5\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf></shape>".to_string(), "weight must be in [0, 1]"),
    ] {
        let e = load_in(&xml(&body)).unwrap_err();
        assert!(e.message.contains(text), "{body}: {e}");
        assert_eq!(e.loc.as_ref().unwrap().line, 2, "{body}: {e}");
    }
}

/// `bsdf_from_properties` reads a model as the XML loader reads the same properties: the same
/// description (compared through `Debug`, which prints every number exactly), and the same
/// messages for bad values, unknown names and properties the plugin does not have.
#[test]
fn properties_given_in_code_read_like_xml() {
    let f = |n: &str, x: f32| (n.to_string(), PropValue::Float(x));
    let s = |n: &str, v: &str| (n.to_string(), PropValue::String(v.to_string()));
    // (plugin, properties, expected error fragment or "" for success)
    type Case<'a> = (&'a str, Vec<(String, PropValue)>, &'a str);
    let cases: Vec<Case> = vec![
        ("diffuse", vec![], ""),
        (
            "orennayar",
            vec![f("sigma", 0.3), s("variant", "full")],
            r#"<float name="sigma" value="0.3"/><string name="variant" value="full"/>"#,
        ),
        (
            "roughconductor",
            vec![
                s("material", "Au"),
                f("alpha", 0.2),
                s("distribution", "ggx"),
            ],
            r#"<string name="material" value="Au"/><float name="alpha" value="0.2"/><string name="distribution" value="ggx"/>"#,
        ),
        (
            "roughdielectric",
            vec![s("int_ior", "bk7"), f("alpha_u", 0.1), f("alpha_v", 0.3)],
            r#"<string name="int_ior" value="bk7"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/>"#,
        ),
        (
            "roughplastic",
            vec![
                (
                    "diffuse_reflectance".into(),
                    PropValue::Rgb([0.2, 0.4, 0.6]),
                ),
                ("nonlinear".into(), PropValue::Boolean(true)),
            ],
            r#"<rgb name="diffuse_reflectance" value="0.2, 0.4, 0.6"/><boolean name="nonlinear" value="true"/>"#,
        ),
        (
            "thinfilm",
            vec![f("thickness", 350.0), s("material", "Cu")],
            r#"<float name="thickness" value="350"/><string name="material" value="Cu"/>"#,
        ),
    ];
    for (plugin, props, xml) in cases {
        let from_code = bsdf_from_properties(plugin, &props).unwrap();
        let file = load(&scene(&format!(
            "<shape type=\"cube\"><bsdf type=\"{plugin}\">{xml}</bsdf></shape>"
        )))
        .unwrap();
        assert_eq!(
            format!("{:?}", from_code.kind),
            format!("{:?}", file.bsdfs[0].kind),
            "{plugin}"
        );
    }
    let err = |plugin: &str, props: Vec<(String, PropValue)>| {
        bsdf_from_properties(plugin, &props)
            .unwrap_err()
            .to_string()
    };
    assert!(err("orennayar", vec![f("sigma", -1.0)]).contains("sigma must be in [0, "));
    assert!(err("orennayar", vec![f("sigma", f32::NAN)])
        .contains("property 'sigma': number 'NaN' is not finite"));
    assert!(err("conductor", vec![s("material", "unobtainium")])
        .contains("unknown conductor 'unobtainium'"));
    assert!(err("diffuse", vec![f("sigma", 1.0)]).contains("unused property 'sigma'"));
    assert!(err(
        "diffuse",
        vec![f("reflectance", 0.5), f("reflectance", 0.6)]
    )
    .contains("given twice"));
    assert!(err("velvet", vec![]).contains("velvet"));
    assert!(err("plastic", vec![f("int_ior", -1.5)]).contains("int_ior must be positive"));
    assert!(err("twosided", vec![]).contains("wraps other BSDFs"));
    let e = bsdf_from_properties("minnaert", &[f("k", 0.0)]).unwrap_err();
    assert_eq!(e.loc.unwrap().file, PathBuf::from("<properties>"));
}

/// `sunsky`: Mitsuba's defaults (turbidity 3, albedo 0.3, Tokyo on 10 July 2010 at 15:00,
/// scales 1, aperture 0.5358, uniform disc); a date and place give the same sun as the
/// direction they resolve to, in the sky's frame; `sun_direction` is in world space and
/// `to_world` turns it into the sky's frame.
#[test]
fn sunsky_parameters_and_sun_position() {
    let s = load(&scene(
        r#"<emitter type="sunsky"/>
<emitter type="sunsky">
    <float name="latitude" value="47.37"/><float name="longitude" value="8.54"/>
    <float name="timezone" value="2"/><integer name="year" value="2026"/>
    <integer name="month" value="8"/><integer name="day" value="14"/>
    <float name="hour" value="17"/><integer name="minute" value="30"/>
    <transform name="to_world"><rotate x="1" angle="-90"/></transform>
</emitter>
<emitter type="sunsky">
    <vector name="sun_direction" x="0" y="2" z="0"/><float name="turbidity" value="7.5"/>
    <rgb name="albedo" value="0.1, 0.2, 0.3"/><float name="sun_scale" value="0"/>
    <float name="sky_scale" value="2"/><float name="sun_aperture" value="2"/>
    <boolean name="complex_sun" value="true"/>
    <transform name="to_world"><rotate x="1" angle="-90"/></transform>
</emitter>"#,
    ))
    .unwrap();
    let get = |i: usize| match &s.lights[i].kind {
        LightKind::SunSky(d) => d.clone(),
        k => panic!("{k:?}"),
    };
    let d = get(0);
    assert_eq!(
        (
            d.turbidity,
            d.sun_scale,
            d.sky_scale,
            d.sun_aperture_deg,
            d.complex_sun
        ),
        (3.0, 1.0, 1.0, 0.5358, false)
    );
    assert!(matches!(d.albedo, SpectrumDesc::Constant(a) if a == 0.3));
    let tokyo = pt_sky::solar::sun_direction(
        &pt_sky::solar::DateTime {
            year: 2010,
            month: 7,
            day: 10,
            hour: 15.0,
            minute: 0.0,
            second: 0.0,
        },
        &pt_sky::solar::Location {
            latitude: 35.6894,
            longitude: 139.6917,
            timezone: 9.0,
        },
    );
    assert!(
        (d.sun_local - tokyo).length() < 1e-6,
        "{:?} vs {tokyo}",
        d.sun_local
    );
    // Zurich: the sun's direction in the sky's frame (z up, x south, y west) does not depend
    // on to_world; in the world, z became y.
    let z = get(1);
    assert!(
        (z.sun_local.z.asin().to_degrees() - 30.67).abs() < 0.05,
        "{:?}",
        z.sun_local
    );
    let world = z.to_world * z.sun_local;
    assert!(
        (world - Vec3::new(0.1916, 0.5102, -0.8385)).length() < 1e-3,
        "{world}"
    );
    // A world direction straight up is the sky's zenith once to_world turns z to y.
    let u = get(2);
    assert!((u.sun_local - Vec3::Z).length() < 1e-6, "{:?}", u.sun_local);
    assert_eq!(
        (
            u.turbidity,
            u.sun_scale,
            u.sky_scale,
            u.sun_aperture_deg,
            u.complex_sun
        ),
        (7.5, 0.0, 2.0, 2.0, true)
    );
}

/// Bad `sunsky` parameters are located errors (Mitsuba's checks: turbidity, albedo, scales,
/// aperture, the sun given twice; and pt's: a to_world that is not a rotation, a month 13).
#[test]
fn sunsky_errors() {
    for (body, line, what) in [
        (r#"<emitter type="sunsky"><float name="turbidity" value="0.5"/></emitter>"#, 2, "turbidity must be in [1, 10]"),
        (r#"<emitter type="sunsky"><float name="albedo" value="1.5"/></emitter>"#, 2, "albedo must be in [0, 1]"),
        (r#"<emitter type="sunsky"><float name="sky_scale" value="-1"/></emitter>"#, 2, "sky_scale must not be negative"),
        (r#"<emitter type="sunsky"><float name="sun_aperture" value="0"/></emitter>"#, 2, "sun_aperture must be in (0, 180)"),
        (
            "<emitter type=\"sunsky\">\n<vector name=\"sun_direction\" x=\"0\" y=\"0\" z=\"1\"/>\n<float name=\"hour\" value=\"12\"/></emitter>",
            4,
            "either sun_direction or a date and place",
        ),
        (r#"<emitter type="sunsky"><vector name="sun_direction" x="0" y="0" z="0"/></emitter>"#, 2, "must not be zero"),
        (r#"<emitter type="sunsky"><integer name="month" value="13"/></emitter>"#, 2, "month must be in [1, 12]"),
        (
            "<emitter type=\"sunsky\">\n<transform name=\"to_world\"><scale value=\"1, 2, 1\"/></transform></emitter>",
            3,
            "must be a rotation",
        ),
    ] {
        let e = fail(&scene(body));
        assert!(e.to_string().contains(what), "{body}: {e}");
        assert_eq!(e.loc.as_ref().map(|l| l.line), Some(line), "{body}: {e}");
    }
}

/// `hair`: Mitsuba's defaults (pigments 1.3 and 0.2, amber in air, roughness 0.3, tilt 2),
/// `sigma_a` with `scale`, pt's `reflectance`; and its errors: two absorptions at once,
/// roughness outside [0, 1], equal indices.
#[test]
fn hair_parameters_and_errors() {
    let s = load(&scene(
        r#"<shape type="sphere"><bsdf type="hair"/></shape>
<shape type="sphere"><bsdf type="hair"><rgb name="sigma_a" value="0.2, 0.3, 0.4"/><float name="scale" value="3"/>
    <float name="longitudinal_roughness" value="0.1"/><float name="scale_tilt" value="-3"/></bsdf></shape>
<shape type="sphere"><bsdf type="hair"><rgb name="reflectance" value="0.6, 0.4, 0.2"/><string name="int_ior" value="water"/></bsdf></shape>"#,
    ))
    .unwrap();
    let kind = |i: usize| &s.bsdfs[s.shapes[i].bsdf].kind;
    let BsdfKind::Hair {
        absorption,
        eta,
        longitudinal_roughness,
        azimuthal_roughness,
        scale_tilt_deg,
    } = kind(0).clone()
    else {
        panic!("{:?}", kind(0))
    };
    assert_eq!(
        absorption,
        HairAbsorption::Pigments {
            eumelanin: 1.3,
            pheomelanin: 0.2
        }
    );
    assert!((eta - 1.55 / 1.000277).abs() < 1e-6);
    assert_eq!(
        (longitudinal_roughness, azimuthal_roughness, scale_tilt_deg),
        (0.3, 0.3, 2.0)
    );
    assert!(
        matches!(kind(1), BsdfKind::Hair { absorption: HairAbsorption::SigmaA { scale, .. }, longitudinal_roughness, scale_tilt_deg, .. } if *scale == 3.0 && *longitudinal_roughness == 0.1 && *scale_tilt_deg == -3.0)
    );
    assert!(
        matches!(kind(2), BsdfKind::Hair { absorption: HairAbsorption::Reflectance(_), eta, .. } if (*eta - 1.333 / 1.000277).abs() < 1e-3)
    );
    for (body, what) in [
        (
            r#"<shape type="sphere"><bsdf type="hair"><float name="eumelanin" value="1"/><rgb name="sigma_a" value="1, 1, 1"/></bsdf></shape>"#,
            "not several",
        ),
        (
            r#"<shape type="sphere"><bsdf type="hair"><float name="azimuthal_roughness" value="1.5"/></bsdf></shape>"#,
            "azimuthal_roughness must be in [0, 1]",
        ),
        (
            r#"<shape type="sphere"><bsdf type="hair"><float name="int_ior" value="1.3"/><float name="ext_ior" value="1.3"/></bsdf></shape>"#,
            "must differ",
        ),
        (
            r#"<shape type="sphere"><bsdf type="hair"><float name="pheomelanin" value="-1"/></bsdf></shape>"#,
            "must not be negative",
        ),
    ] {
        let e = fail(&scene(body));
        assert!(e.to_string().contains(what), "{body}: {e}");
        assert_eq!(e.loc.as_ref().map(|l| l.line), Some(2), "{body}: {e}");
    }
}
