//! Instancing (`shapegroup` + `instance`, issue 20 item 2). Agreement with Mitsuba 3.9.1 is
//! tested by the reference scene `scenes/instances.xml` (tests/references.rs). Here:
//! - an instanced group renders as the plain shapes it stands for: a torus whose reflectance is
//!   a `mesh_attribute` (looked up through the instanced triangle, which Mitsuba 3.9.1 gets wrong:
//!   see scenes/README.md) and an anisotropic sphere (dp/du carried into world space), placed by
//!   an instance, against the same shapes with the instance's transform composed into their
//!   own `to_world`: block z-test of the two renders;
//! - a group a scene places nowhere renders nothing (bit for bit the scene without it);
//! - malformed groups and instances are located errors (exit code 2, no output).

use crate::common;

use common::*;

const SENSOR: &str = r#"<sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 2.2, 4" target="0, 0.4, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.6, 0.65, 0.7"/></emitter>
    <shape type="sphere"><point name="center" value="1, 3, 1"/><float name="radius" value="0.4"/>
        <emitter type="area"><rgb name="radiance" value="12"/></emitter></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/></transform></shape>"#;

/// The ornament's shapes, each with `extra` transform steps after its own.
fn ornament(extra: &str) -> String {
    format!(
        r#"<shape type="ply"><string name="filename" value="{}"/>
            <transform name="to_world"><scale value="0.6"/>{extra}</transform>
            <bsdf type="twosided"><bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
                <string name="name" value="vertex_color"/></texture></bsdf></bsdf></shape>
        <shape type="sphere"><float name="radius" value="0.3"/>
            <transform name="to_world">{extra}</transform>
            <bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.4"/></bsdf></shape>"#,
        repo().join("scenes/meshes/torus.ply").display()
    )
}

/// The instance's transform (rotation, uniform scale and translation, which a sphere's own
/// `to_world` can take too).
const PLACE: &str = r#"<rotate x="1" angle="-65"/><rotate y="1" angle="30"/><scale value="1.3"/><translate value="0.2, 0.5, 0"/>"#;

fn write(dir: &std::path::Path, name: &str, body: &str) -> std::path::PathBuf {
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(
        &path,
        format!("<scene version=\"3.0.0\">\n    {SENSOR}\n    {body}\n</scene>\n"),
    )
    .expect("write scene");
    path
}

/// The instanced ornament and its plain copy have the same expected image: block z-test (both
/// renders' variances, 16x16 blocks, family-wise alpha 0.01) and mean ratio within 0.5%, as
/// the reference tests judge. Each render is 1024 spp; the two differ only by rounding in the
/// ray's transform, so a wrong normal transform, a missed dp/du transform (the anisotropic
/// highlight turns) or an attribute read from the wrong triangle (colours scrambled) fails it.
#[test]
fn an_instance_renders_as_its_plain_copy() {
    let dir = scratch("instance_vs_plain");
    let grouped = format!(
        r#"<shape type="shapegroup" id="g">{}</shape>
    <shape type="instance"><ref id="g"/><transform name="to_world">{PLACE}</transform></shape>"#,
        ornament("")
    );
    let a = write(&dir, "instanced", &grouped);
    let b = write(&dir, "plain", &ornament(PLACE));
    let spp = ["--spp", "1024"];
    let (ia, va) = render(&a, &dir, "instanced", &spp);
    let (ib, vb) = render(&b, &dir, "plain", &spp);
    let z = pt_stats::block_ztest(&ia, &va, &ib, &vb, BLOCK, ALPHA).expect("same size");
    let (ma, mb) = (ia.mean(), ib.mean());
    eprintln!(
        "instance vs plain: {} of {} blocks fail, max |z| {:.2}, chi2 p {:.3}, means {ma:?} {mb:?}",
        z.failed, z.tests, z.max_abs_z, z.chi2_p
    );
    assert!(z.pass, "the instanced ornament differs from its plain copy");
    for c in 0..3 {
        assert!((ma[c] / mb[c] - 1.0).abs() < MEAN_RATIO_TOL, "channel {c}");
    }
}

/// A medium on a grouped shape bounds every instance of it: a glass ball full of a chromatic
/// scattering medium, instanced, against the same ball placed by its own `to_world`, under
/// `volpath` (the same block z-test and mean ratio as above, 256 spp each). Without the
/// medium the instanced ball is clear glass, a few times brighter in places: far outside the
/// test.
#[test]
fn an_instanced_medium_renders_as_its_plain_copy() {
    let dir = scratch("instanced_medium");
    let ball = |extra: &str| {
        format!(
            r#"<shape type="sphere"><float name="radius" value="0.45"/>
            <transform name="to_world">{extra}</transform>
            <bsdf type="dielectric"/>
            <medium type="homogeneous" name="interior">
                <rgb name="sigma_t" value="2, 4, 7"/><float name="albedo" value="0.8"/>
                <phase type="hg"><float name="g" value="0.4"/></phase>
            </medium></shape>"#
        )
    };
    let volpath =
        r#"<integrator type="volpath"><integer name="max_depth" value="24"/></integrator>"#;
    let grouped = format!(
        r#"{volpath}<shape type="shapegroup" id="g">{}</shape>
    <shape type="instance"><ref id="g"/><transform name="to_world">{PLACE}</transform></shape>"#,
        ball("")
    );
    let a = write(&dir, "instanced", &grouped);
    let b = write(&dir, "plain", &format!("{volpath}{}", ball(PLACE)));
    let spp = ["--spp", "256"];
    let (ia, va) = render(&a, &dir, "instanced", &spp);
    let (ib, vb) = render(&b, &dir, "plain", &spp);
    let z = pt_stats::block_ztest(&ia, &va, &ib, &vb, BLOCK, ALPHA).expect("same size");
    let (ma, mb) = (ia.mean(), ib.mean());
    eprintln!(
        "instanced medium vs plain: {} of {} blocks fail, max |z| {:.2}, means {ma:?} {mb:?}",
        z.failed, z.tests, z.max_abs_z
    );
    assert!(z.pass, "the instanced medium differs from its plain copy");
    for c in 0..3 {
        assert!((ma[c] / mb[c] - 1.0).abs() < MEAN_RATIO_TOL, "channel {c}");
    }
}

/// A group no instance places renders nothing: the image is bit for bit the scene's without it
/// (and differs from the scene with the shapes placed).
#[test]
fn an_unplaced_group_renders_nothing() {
    let dir = scratch("unplaced_group");
    let spp = ["--spp", "4"];
    let plain = write(&dir, "plain", &ornament(""));
    let unplaced = write(
        &dir,
        "unplaced",
        &format!(
            r#"<shape type="shapegroup" id="g">{}</shape>"#,
            ornament("")
        ),
    );
    let empty = write(&dir, "empty", "");
    let (p, _) = render(&plain, &dir, "plain", &spp);
    let (u, _) = render(&unplaced, &dir, "unplaced", &spp);
    let (e, _) = render(&empty, &dir, "empty", &spp);
    assert!(u.data == e.data, "an unplaced group changed the image");
    assert!(p.data != e.data);
}

/// Malformed groups and instances: exit code 2, the file and line, what is wrong.
#[test]
fn bad_groups_and_instances_are_located_errors() {
    let sphere = r#"<shape type="sphere"/>"#;
    for (name, body, expect) in [
        (
            "emitter",
            r#"<shape type="shapegroup" id="g"><shape type="sphere"><emitter type="area"/></shape></shape>"#.to_string(),
            "cannot emit",
        ),
        (
            "nested",
            format!(r#"<shape type="shapegroup" id="g"><shape type="shapegroup" id="h">{sphere}</shape></shape>"#),
            "cannot contain another shapegroup",
        ),
        (
            "no_group",
            r#"<shape type="instance"/>"#.to_string(),
            "needs a shapegroup",
        ),
        (
            "not_a_group",
            r#"<bsdf type="diffuse" id="d"/><shape type="instance"><ref id="d"/></shape>"#.to_string(),
            "shapegroup",
        ),
        (
            "singular",
            format!(r#"<shape type="shapegroup" id="g">{sphere}</shape><shape type="instance"><ref id="g"/><transform name="to_world"><scale value="1, 0, 1"/></transform></shape>"#),
            "not invertible",
        ),
    ] {
        let dir = scratch(&format!("bad_{name}"));
        let path = write(&dir, name, &body);
        let out = dir.join("out.exr");
        let o = pt(&["render", path.to_str().unwrap(), "-o", out.to_str().unwrap(), "--quiet"]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {stderr}");
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
        assert!(stderr.contains(&format!("{name}.xml:")), "{name}: no location: {stderr}");
        assert!(stderr.contains(expect), "{name}: {stderr}");
        assert!(!out.exists(), "{name}: output written");
    }
}
