//! The builder against the scene path, its parameter table against the scene format's reader,
//! and its messages.

use super::*;
use pt_math::Vec3;
use pt_render::{BvhKind, LightSelection, Scene};
use std::path::Path;

/// The BSDF a one-sphere scene with `<bsdf>` element `bsdf_xml` gets (RGB mode), the way
/// `pt lobes` used to build its models.
fn from_scene(bsdf_xml: &str) -> SurfaceBsdf {
    let xml = format!(r#"<scene version="3.0.0"><shape type="sphere">{bsdf_xml}</shape></scene>"#);
    let desc = pt_scene::load_str(&xml, Path::new("<test>"), Path::new("."), &[]).unwrap();
    let scene = Scene::build_with_mode(
        &desc,
        BvhKind::default(),
        LightSelection::default(),
        Some(pt_spectrum::ColorMode::Rgb),
    )
    .unwrap();
    scene.materials[0].fixed.unwrap()
}

/// Directions in the local frame (z = normal) at polar angle `theta` and azimuth `phi`,
/// degrees, over the whole sphere.
fn dirs() -> Vec<Vec3> {
    let mut v = Vec::new();
    for theta in [0.0, 10.0, 35.0, 60.0, 85.0, 95.0, 130.0, 170.0, 180.0] {
        for phi in [0.0, 70.0, 180.0, 250.0] {
            v.push(pt_stats::dir_deg(theta, phi));
        }
    }
    v
}

/// For each parameter set, the builder's BSDF is the scene's: the same value in every field
/// (`Debug` prints every float exactly) and bit-identical eval and pdf for pairs of fixed
/// directions over the whole sphere.
#[test]
fn builder_gives_the_bsdf_a_scene_file_gives() {
    let cases: &[(&str, &str)] = &[
        ("diffuse", r#"<bsdf type="diffuse"/>"#),
        (
            "diffuse reflectance=0.2,0.5,0.7",
            r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.7"/></bsdf>"#,
        ),
        (
            "orennayar sigma=0.5 variant=full reflectance=0.8",
            r#"<bsdf type="orennayar"><float name="sigma" value="0.5"/><string name="variant" value="full"/><float name="reflectance" value="0.8"/></bsdf>"#,
        ),
        (
            "orennayar sigma=1.2 variant=eon",
            r#"<bsdf type="orennayar"><float name="sigma" value="1.2"/><string name="variant" value="eon"/></bsdf>"#,
        ),
        (
            "minnaert k=2",
            r#"<bsdf type="minnaert"><float name="k" value="2"/></bsdf>"#,
        ),
        (
            "dielectric int_ior=bk7",
            r#"<bsdf type="dielectric"><string name="int_ior" value="bk7"/></bsdf>"#,
        ),
        (
            "thindielectric int_ior=1.4 ext_ior=1.1",
            r#"<bsdf type="thindielectric"><float name="int_ior" value="1.4"/><float name="ext_ior" value="1.1"/></bsdf>"#,
        ),
        (
            "roughdielectric alpha=0.3 distribution=ggx",
            r#"<bsdf type="roughdielectric"><float name="alpha" value="0.3"/><string name="distribution" value="ggx"/></bsdf>"#,
        ),
        (
            "roughdielectric alpha_u=0.1 alpha_v=0.4 int_ior=1.33",
            r#"<bsdf type="roughdielectric"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.4"/><float name="int_ior" value="1.33"/></bsdf>"#,
        ),
        (
            "conductor material=Au",
            r#"<bsdf type="conductor"><string name="material" value="Au"/></bsdf>"#,
        ),
        (
            "roughconductor eta=0.2,0.9,1.1 k=3.9,2.4,2.1 alpha=0.2 distribution=ggx",
            r#"<bsdf type="roughconductor"><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.1"/><float name="alpha" value="0.2"/><string name="distribution" value="ggx"/></bsdf>"#,
        ),
        (
            "roughplastic diffuse_reflectance=0.1,0.3,0.6 alpha=0.15 nonlinear=true",
            r#"<bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.1, 0.3, 0.6"/><float name="alpha" value="0.15"/><boolean name="nonlinear" value="true"/></bsdf>"#,
        ),
        (
            "thinfilm thickness=300 material=Cu",
            r#"<bsdf type="thinfilm"><float name="thickness" value="300"/><string name="material" value="Cu"/></bsdf>"#,
        ),
        (
            "roughthinfilm thickness=450 int_ior=1.5 alpha=0.25",
            r#"<bsdf type="roughthinfilm"><float name="thickness" value="450"/><float name="int_ior" value="1.5"/><float name="alpha" value="0.25"/></bsdf>"#,
        ),
        (
            "twosided roughconductor material=Al alpha=0.1",
            r#"<bsdf type="twosided"><bsdf type="roughconductor"><string name="material" value="Al"/><float name="alpha" value="0.1"/></bsdf></bsdf>"#,
        ),
    ];
    let dirs = dirs();
    for (text, xml) in cases {
        let built = build_bsdf(&BsdfSpec::parse(text).unwrap()).unwrap();
        let scene = from_scene(xml);
        assert_eq!(format!("{built:?}"), format!("{scene:?}"), "{text}");
        for &wo in &dirs {
            for &wi in &dirs {
                let (a, b) = (
                    built.eval(wo, wi).0.to_array(),
                    scene.eval(wo, wi).0.to_array(),
                );
                assert_eq!(
                    a.map(f32::to_bits),
                    b.map(f32::to_bits),
                    "{text}: eval at {wo} {wi}"
                );
                let (p, q) = (built.pdf(wo, wi), scene.pdf(wo, wi));
                assert_eq!(p.to_bits(), q.to_bits(), "{text}: pdf at {wo} {wi}");
            }
        }
    }
}

/// Named materials come from pt-scene's tables: `material=Au` is Au's index from
/// `named_conductor` (in RGB mode its measured spectra's sRGB), `int_ior=bk7` the number
/// `named_ior` gives.
#[test]
fn named_materials_are_the_scene_formats() {
    let au = pt_scene::named_conductor("Au").unwrap();
    let rgb = |s| pt_render::texture::rgb_of(s, pt_render::texture::Role::Unbounded);
    let named = build_bsdf(&BsdfSpec::new("conductor").with("material", "Au")).unwrap();
    let given = build_bsdf(
        &BsdfSpec::new("conductor")
            .with("eta", rgb(&au.eta))
            .with("k", rgb(&au.k)),
    )
    .unwrap();
    assert_eq!(format!("{named:?}"), format!("{given:?}"));
    let bk7 = pt_scene::named_ior("bk7").unwrap();
    let named = build_bsdf(&BsdfSpec::new("dielectric").with("int_ior", "bk7")).unwrap();
    let given = build_bsdf(&BsdfSpec::new("dielectric").with("int_ior", bk7)).unwrap();
    assert_eq!(format!("{named:?}"), format!("{given:?}"));
}

/// Parameter `name` with a value the scene format accepts, and the partner it needs.
fn sample_params(model: &str, name: &str) -> Vec<(String, PropValue)> {
    let v = |n: &str, v: PropValue| (n.to_string(), v);
    let (f, s) = (PropValue::Float, |t: &str| PropValue::String(t.into()));
    match name {
        "variant" => vec![v(name, s("fujii"))],
        "distribution" => vec![v(name, s("ggx"))],
        "material" => vec![v(name, s("Cu"))],
        "sample_visible" | "nonlinear" | "polarizing" => vec![v(name, PropValue::Boolean(true))],
        "reflectance" | "diffuse_reflectance" => vec![v(name, PropValue::Rgb([0.2, 0.3, 0.4]))],
        "alpha_u" | "alpha_v" => vec![v("alpha_u", f(0.1)), v("alpha_v", f(0.2))],
        "k" if model == "minnaert" => vec![v(name, f(2.0))],
        "eta" if model.starts_with("principled") => vec![v(name, f(1.4))],
        "base_color" => vec![v(name, PropValue::Rgb([0.2, 0.3, 0.4]))],
        "eta" | "k" => vec![v("eta", f(0.5)), v("k", f(2.0))],
        "thickness" => vec![v(name, f(250.0))],
        _ => vec![v(name, f(0.7))],
    }
}

/// Every parameter [`MODELS`] lists is one the scene format's reader reads (it would refuse
/// an unread one as "unused property"), and a name it does not list is refused.
#[test]
fn every_listed_parameter_is_read_and_others_are_refused() {
    for m in MODELS.iter().filter(|m| m.name != "twosided") {
        for p in m.params {
            let mut spec = BsdfSpec::new(m.name);
            for (n, v) in sample_params(m.name, p) {
                spec = spec.with(&n, v);
            }
            if let Err(e) = build_bsdf(&spec) {
                panic!("{} {p}: {e}", m.name);
            }
        }
        let e = build_bsdf(&BsdfSpec::new(m.name).with("bogus", 1.0)).unwrap_err();
        assert!(matches!(e, BsdfError::UnknownParameter { .. }), "{e}");
        // The reader refuses it too: the table is not the only guard.
        let e = pt_scene::bsdf_from_properties(m.name, &[("bogus".into(), PropValue::Float(1.0))])
            .unwrap_err();
        assert!(e.message.contains("unused property 'bogus'"), "{e}");
    }
}

#[test]
fn errors_are_clear() {
    let err = |t: &str| {
        BsdfSpec::parse(t)
            .and_then(|s| build_bsdf(&s).map(|_| ()))
            .unwrap_err()
            .to_string()
    };
    assert!(err("velvet").starts_with("unknown model 'velvet' (known: diffuse, orennayar"));
    assert_eq!(
        err("orennayar foo=1"),
        "orennayar: unknown parameter 'foo' (parameters: reflectance, sigma, variant)"
    );
    assert_eq!(
        err("orennayar sigma"),
        "orennayar: expected NAME=VALUE, got 'sigma'"
    );
    assert_eq!(
        err("orennayar sigma="),
        "orennayar: parameter 'sigma' has no value"
    );
    assert_eq!(
        err("orennayar sigma=1 SIGMA=2"),
        "orennayar: parameter 'sigma' given twice"
    );
    assert!(err("orennayar sigma=-1").starts_with("orennayar sigma=-1: sigma must be in [0, "));
    assert_eq!(err("orennayar variant=bogus"), "orennayar variant=bogus: unknown Oren-Nayar variant 'bogus' (qualitative, full, fujii, eon)");
    assert_eq!(
        err("minnaert k=0"),
        "minnaert k=0: k must be positive, got 0"
    );
    assert!(err("roughconductor material=unobtainium")
        .contains("unknown conductor 'unobtainium' (known: none, Ag, Al"));
    assert!(
        err("dielectric int_ior=unobtainium").contains("unknown index of refraction 'unobtainium'")
    );
    assert!(err("roughconductor alpha=0.1 alpha_u=0.2")
        .ends_with("give either alpha or alpha_u/alpha_v"));
    assert!(err("roughplastic nonlinear=maybe").contains("must be a boolean, not string"));
    assert!(err("orennayar sigma=nan").contains("not finite"));
    assert_eq!(err(""), "empty model specification");
    assert!(err("twosided").starts_with("twosided: give the model it wraps"));
    assert_eq!(
        err("twosided diffuse foo=1"),
        "diffuse: unknown parameter 'foo' (parameters: reflectance)"
    );
    let lonely = BsdfSpec::new("twosided");
    assert_eq!(
        build_bsdf(&lonely).unwrap_err().to_string(),
        "twosided: twosided needs the model it wraps"
    );
}

#[test]
fn parse_reads_values_as_scene_files_do_and_labels_round_trip() {
    let s = BsdfSpec::parse(
        "RoughPlastic Alpha=0.3 diffuse_reflectance=0.1,0.2,0.3 nonlinear=true distribution=ggx",
    )
    .unwrap();
    assert_eq!(s.model, "roughplastic");
    assert_eq!(s.param("alpha"), Some(&PropValue::Float(0.3)));
    assert_eq!(
        s.param("diffuse_reflectance"),
        Some(&PropValue::Rgb([0.1, 0.2, 0.3]))
    );
    assert_eq!(s.param("nonlinear"), Some(&PropValue::Boolean(true)));
    assert_eq!(
        s.param("distribution"),
        Some(&PropValue::String("ggx".into()))
    );
    assert_eq!(BsdfSpec::parse(&s.label()).unwrap(), s);
    let t = BsdfSpec::parse("twosided diffuse reflectance=0.4").unwrap();
    assert_eq!(
        t,
        BsdfSpec::two_sided(BsdfSpec::new("diffuse").with("reflectance", 0.4))
    );
    assert_eq!(t.label(), "twosided diffuse reflectance=0.4");
    assert!(build_bsdf(&t).unwrap().two_sided);
}
