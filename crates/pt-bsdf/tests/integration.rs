//! One test binary for pt-bsdf's model tests (sampling against pdf, energy, reciprocity): each file in this folder is a module of it.
//! One binary instead of one per file, because each binary links the whole renderer (the
//! link steps were a large part of CI's build time), and because the tests of all files then
//! run in parallel with each other instead of file after file.
//!
//! Cargo's automatic test discovery is off for this package (`autotests = false`), so a new
//! file here must be added below; `every_test_file_is_a_module` fails until it is.

mod common;

mod blend;
mod diffuse;
mod gltf_pbr;
mod hair;
mod normal_map;
mod plastic;
mod pplastic;
mod principled;
mod rough_thin_film;
mod specular;
mod thin_film;

/// A file in this folder that is not declared as a module above would silently never run.
#[test]
fn every_test_file_is_a_module() {
    let tests = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let missing = pt_testkit::undeclared_test_files(&tests, "integration", &[]).unwrap();
    assert!(
        missing.is_empty(),
        "test files not declared in integration.rs: {missing:?}"
    );
}
