//! Bad input gets a clear error naming file, line and element, exit code 2, and no output file.

use crate::common;

use common::*;
use std::path::Path;

/// Writes `xml` as a scene, runs `pt render` on it, and checks exit code 2, that stderr contains
/// every `expect` string, and that no output (or temporary) file was left behind.
fn rejects(name: &str, xml: &str, expect: &[&str]) {
    let dir = scratch(&format!("bad_{name}"));
    let scene = dir.join(format!("{name}.xml"));
    std::fs::write(&scene, xml).unwrap();
    let out = dir.join("out.exr");
    let o = pt(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{name}: exit code; stderr: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{name}: panicked: {stderr}");
    for e in expect {
        assert!(
            stderr.contains(e),
            "{name}: stderr should mention '{e}': {stderr}"
        );
    }
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .filter(|f| f != Path::new(&format!("{name}.xml")).as_os_str())
        .collect();
    assert!(left.is_empty(), "{name}: files left behind: {left:?}");
}

const HEAD: &str = r#"<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="40"/>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
"#;

#[test]
fn malformed_xml() {
    rejects(
        "malformed",
        &format!("{HEAD}<shape type=\"cube\">\n</scene>"),
        &["malformed.xml:"],
    );
}

#[test]
fn unknown_plugin() {
    rejects(
        "unknown",
        &format!("{HEAD}<shape type=\"cube\"><bsdf type=\"plasticc\"/></shape>\n</scene>"),
        &["unknown.xml:5:", "plasticc"],
    );
}

#[test]
fn missing_mesh() {
    rejects("missing", &format!("{HEAD}<shape type=\"obj\"><string name=\"filename\" value=\"nothere.obj\"/></shape>\n</scene>"), &["missing.xml:5:", "nothere.obj"]);
}

#[test]
fn malformed_ies_file() {
    // The IES file lives outside the scene's folder, which must stay empty but for the scene.
    let ies = scratch("bad_ies_file").join("short.ies");
    std::fs::write(
        &ies,
        "IESNA:LM-63-2002\r\nTILT=NONE\r\n1 -1 1 3 1 1 2 0 0 0\r\n1 1 10\r\n0 45 90\r\n0\r\n100 -50 0\r\n",
    )
    .unwrap();
    rejects(
        "ies",
        &format!(
            "{HEAD}<emitter type=\"point\">\n<string name=\"ies\" value=\"{}\"/></emitter>\n</scene>",
            ies.display()
        ),
        &["ies.xml:6:", "<string name=\"ies\">", "short.ies', line 7", "must not be negative"],
    );
}

#[test]
fn nan_parameter() {
    rejects(
        "nan",
        &format!(
            "{HEAD}<shape type=\"sphere\"><float name=\"radius\" value=\"nan\"/></shape>\n</scene>"
        ),
        &["nan.xml:5:", "radius"],
    );
}

#[test]
fn malformed_number() {
    rejects("number", &format!("{HEAD}<shape type=\"sphere\"><float name=\"radius\" value=\"1.0.0\"/></shape>\n</scene>"), &["number.xml:5:", "radius"]);
}

#[test]
fn unused_property() {
    rejects(
        "unused",
        &format!(
            "{HEAD}<shape type=\"cube\"><float name=\"radius\" value=\"1\"/></shape>\n</scene>"
        ),
        &["unused.xml:5:", "radius"],
    );
}

#[test]
fn undefined_substitution() {
    rejects(
        "subst",
        &format!(
            "{HEAD}<shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>\n</scene>"
        ),
        &["subst.xml:5:", "$r"],
    );
}

#[test]
fn missing_scene_file_and_bad_arguments() {
    let dir = scratch("bad_args");
    let out = dir.join("out.exr");
    let o = pt(&["render", "does/not/exist.xml", "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("does/not/exist.xml"));
    // An output folder that does not exist is reported before rendering.
    let o = pt(&["render", "-o", "no/such/folder/x.exr", "--spp", "1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no/such/folder"));
    let o = pt(&["render", "-o", out.to_str().unwrap(), "--spp", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
}
