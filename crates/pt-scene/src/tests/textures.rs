//! Texturable parameters: textures nested or shared by id, the texture plugins' parameters,
//! and the located errors for textures where none can go.

use super::*;
use std::sync::Arc;

/// A scene file in a fresh folder with one tiny PNG (`t.png`; the loader checks only that
/// the file exists) and the given body; returns the folder and the load result.
fn load_with_image(name: &str, body: &str) -> (PathBuf, Result<SceneDesc, SceneError>) {
    let dir = temp_dir(name);
    std::fs::write(dir.join("t.png"), b"not decoded by the loader").unwrap();
    let path = dir.join("s.xml");
    std::fs::write(&path, scene(body)).unwrap();
    let r = load_file(&path, &[]);
    (dir, r)
}

#[test]
fn bitmap_parameters_and_sharing_by_id() {
    let (dir, r) = load_with_image(
        "tex-bitmap",
        r#"<texture type="bitmap" id="wood">
    <string name="filename" value="t.png"/>
    <string name="filter_type" value="nearest"/>
    <string name="wrap_mode" value="mirror"/>
    <boolean name="raw" value="true"/>
    <transform name="to_uv"><scale x="2" y="3"/><translate x="0.5"/></transform>
</texture>
<shape type="cube"><bsdf type="diffuse"><ref name="reflectance" id="wood"/></bsdf></shape>
<shape type="cube"><bsdf type="roughconductor"><ref name="specular_reflectance" id="wood"/></bsdf></shape>"#,
    );
    let s = r.unwrap();
    let BsdfKind::Diffuse {
        reflectance: TextureDesc::Bitmap(a),
    } = &s.bsdfs[0].kind
    else {
        panic!("{:?}", s.bsdfs[0].kind)
    };
    assert_eq!(a.source, ImageSource::File(dir.join("t.png")));
    assert_eq!(
        (a.filter, a.wrap, a.raw),
        (BitmapFilter::Nearest, WrapMode::Mirror, true)
    );
    // u' = 2 u + 0.5, v' = 3 v: Mitsuba's to_uv, its 2x2 block and translation.
    assert_eq!(a.to_uv, [2.0, 0.0, 0.5, 0.0, 3.0, 0.0]);
    let BsdfKind::RoughConductor {
        specular_reflectance: TextureDesc::Bitmap(b),
        ..
    } = &s.bsdfs[1].kind
    else {
        panic!("{:?}", s.bsdfs[1].kind)
    };
    assert!(
        Arc::ptr_eq(a, b),
        "a texture shared by id is one description"
    );
}

#[test]
fn checkerboard_mesh_attribute_and_rawconstant() {
    let s = load(&scene(
        r#"<shape type="cube"><bsdf type="roughconductor">
    <texture type="checkerboard" name="alpha">
        <float name="color0" value="0.05"/>
        <texture type="checkerboard" name="color1"><transform name="to_uv"><scale value="4"/></transform></texture>
    </texture>
</bsdf></shape>
<shape type="cube"><bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_color"/><float name="scale" value="0.5"/></texture></bsdf></shape>
<shape type="cube"><bsdf type="blendbsdf"><texture type="rawconstant" name="weight"><float name="value" value="0.25"/></texture><bsdf type="diffuse"/><bsdf type="conductor"/></bsdf></shape>"#,
    ))
    .unwrap();
    let BsdfKind::RoughConductor { microfacet, .. } = &s.bsdfs[0].kind else {
        panic!()
    };
    let TextureDesc::Checkerboard(c) = &microfacet.alpha_u else {
        panic!("{:?}", microfacet.alpha_u)
    };
    assert_eq!(c.color0, TextureDesc::constant(0.05));
    let TextureDesc::Checkerboard(inner) = &c.color1 else {
        panic!("{:?}", c.color1)
    };
    // Mitsuba's defaults for the nested checkerboard: 0.4 and 0.2.
    assert_eq!(
        (inner.color0.clone(), inner.color1.clone()),
        (TextureDesc::constant(0.4), TextureDesc::constant(0.2))
    );
    assert_eq!(inner.to_uv, [4.0, 0.0, 0.0, 0.0, 4.0, 0.0]);
    assert_eq!(microfacet.alpha_u, microfacet.alpha_v, "alpha sets both");
    let BsdfKind::Diffuse {
        reflectance: TextureDesc::MeshAttribute(m),
    } = &s.bsdfs[1].kind
    else {
        panic!()
    };
    assert_eq!((m.name.as_str(), m.scale), ("vertex_color", 0.5));
    let BsdfKind::Blend {
        weight: TextureDesc::RawConstant(r),
        ..
    } = &s.bsdfs[2].kind
    else {
        panic!()
    };
    assert_eq!((r.value, r.scalar), ([0.25; 3], true));
}

/// Each mistake is an error at the element that makes it, naming what is wrong.
#[test]
fn texture_mistakes_are_located_errors() {
    let bitmap = |extra: &str| {
        format!(
            r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/>{extra}</texture>"#
        )
    };
    let cases: Vec<(String, &str)> = vec![
        // A texture on a parameter that takes none (dielectric int_ior is a float in Mitsuba).
        (
            r#"<shape type="cube"><bsdf type="dielectric"><texture type="bitmap" name="int_ior"><string name="filename" value="t.png"/></texture></bsdf></shape>"#.into(),
            "unused texture 'int_ior'",
        ),
        (
            r#"<shape type="cube"><bsdf type="roughplastic"><texture type="bitmap" name="alpha"><string name="filename" value="t.png"/></texture></bsdf></shape>"#.into(),
            "unused texture 'alpha'",
        ),
        (
            format!(r#"<shape type="cube"><bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/>{}</bsdf></shape>"#, bitmap("")),
            "'reflectance' is given both as a value and as a texture",
        ),
        (
            format!(r#"<shape type="cube"><bsdf type="diffuse">{}</bsdf></shape>"#, bitmap(r#"<string name="wrap_mode" value="wrap"/>"#)),
            "wrap_mode must be repeat, mirror or clamp",
        ),
        (
            format!(r#"<shape type="cube"><bsdf type="diffuse">{}</bsdf></shape>"#, bitmap(r#"<string name="filter_type" value="trilinear"/>"#)),
            "filter_type must be bilinear or nearest",
        ),
        (
            r#"<shape type="cube"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="missing.png"/></texture></bsdf></shape>"#.into(),
            "cannot open image 'missing.png'",
        ),
        (
            r#"<shape type="cube"><bsdf type="diffuse"><texture type="bitmap"><string name="filename" value="t.png"/></texture></bsdf></shape>"#.into(),
            "needs name=",
        ),
        (
            r#"<shape type="cube"><bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="color"/></texture></bsdf></shape>"#.into(),
            "start with vertex_ or face_",
        ),
        (
            r#"<shape type="cube"><bsdf type="diffuse"><texture type="volume" name="reflectance"/></bsdf></shape>"#.into(),
            "not yet implemented",
        ),
        (
            r#"<texture type="checkerboard" id="a"><ref name="color0" id="a"/></texture><shape type="cube"><bsdf type="diffuse"><ref name="reflectance" id="a"/></bsdf></shape>"#.into(),
            "contains itself",
        ),
    ];
    for (body, text) in cases {
        let (_, r) = load_with_image("tex-errors", &body);
        let e = r.expect_err(&body);
        assert!(e.message.contains(text), "{body}: {e}");
        assert!(e.loc.as_ref().is_some_and(|l| l.line >= 2), "{body}: {e}");
    }
    // An image of a type the renderer cannot read is refused when the scene is loaded.
    let dir = temp_dir("tex-tiff");
    std::fs::write(dir.join("t.tiff"), b"").unwrap();
    std::fs::write(
        dir.join("s.xml"),
        scene(r#"<shape type="cube"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="t.tiff"/></texture></bsdf></shape>"#),
    )
    .unwrap();
    let e = load_file(&dir.join("s.xml"), &[]).unwrap_err();
    assert!(e.message.contains("unsupported file type"), "{e}");
}

#[test]
fn bump_maps_take_one_texture_of_any_name() {
    let bitmap = |name: &str| {
        format!(r#"<texture type="bitmap"{name}><string name="filename" value="t.png"/></texture>"#)
    };
    for name in ["", r#" name="arbitrary""#, r#" name="height""#] {
        let body = format!(
            r#"<shape type="cube"><bsdf type="bumpmap">{}<float name="scale" value="0.2"/><bsdf type="diffuse"/></bsdf></shape>"#,
            bitmap(name)
        );
        let s = load_with_image("bump-ok", &body).1.unwrap();
        assert!(
            matches!(&s.bsdfs[0].kind, BsdfKind::BumpMap { height: TextureDesc::Bitmap(_), scale, inner } if *scale == 0.2 && matches!(inner.kind, BsdfKind::Diffuse { .. })),
            "{name}"
        );
    }
    for (body, what) in [
        (
            r#"<shape type="cube"><bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf></shape>"#
                .to_string(),
            "needs one nested <texture>",
        ),
        (
            format!(
                r#"<shape type="cube"><bsdf type="bumpmap">{}{}<bsdf type="diffuse"/></bsdf></shape>"#,
                bitmap(r#" name="a""#),
                bitmap(r#" name="b""#)
            ),
            "only one nested <texture>",
        ),
        (
            r#"<shape type="cube"><bsdf type="bumpmap"><texture type="checkerboard"/><bsdf type="diffuse"/></bsdf></shape>"#
                .to_string(),
            "bitmap",
        ),
        (
            format!(
                r#"<shape type="cube"><bsdf type="bumpmap">{}</bsdf></shape>"#,
                bitmap("")
            ),
            "nested BSDF",
        ),
    ] {
        let e = load_with_image("bump-bad", &body).1.unwrap_err();
        assert!(e.to_string().contains(what), "{body}: {e}");
    }
}
