//! Loader tests: whole scenes in, IR or located errors out.

use crate::*;

mod loader;
mod materials;
mod sensor;
mod shapes;
mod textures;

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
        _ => panic!("expected a mesh"),
    }
}

fn face_normal(m: &TriangleMesh, t: usize) -> Vec3 {
    let p = m.indices[t].map(|i| m.positions[i as usize]);
    (p[1] - p[0]).cross(p[2] - p[0]).normalize()
}

fn cornell_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.xml")
}
