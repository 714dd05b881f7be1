//! One test binary for the workspace's cross-crate and image tests (they run the `pt` binary): each file in this folder is a module of it.
//! One binary instead of one per file, because each binary links the whole renderer (the
//! link steps were a large part of CI's build time), and because the tests of all files then
//! run in parallel with each other instead of file after file.
//!
//! Cargo's automatic test discovery is off for this package (`autotests = false`), so a new
//! file here must be added below; `every_test_file_is_a_module` fails until it is.
//!
//! `tests/references.rs` stays its own binary: it generates one test per referenced scene with
//! libtest-mimic (`harness = false`).

mod common;

mod adversarial;
mod analysis_commands;
mod analytic;
mod aov;
mod bad_input;
mod bdpt;
mod cameras;
mod cluster;
mod cornell_reference;
mod determinism;
mod direct_samples;
mod display_primaries;
mod film;
mod fluorescence;
mod gltf;
mod instances;
mod light_stability;
mod lights_analytic;
mod media;
mod moment;
mod parallelograms;
mod phosphorescence;
mod photonmapper;
mod pixel_format;
mod ptracer;
mod radiosity;
mod resume;
mod samplers;
mod scene_docs;
mod source_size;
mod spectral_textures;
mod sppm;
mod surface_textures;
mod texture_closed_form;

/// A file in this folder that is not declared as a module above would silently never run.
#[test]
fn every_test_file_is_a_module() {
    let tests = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let missing =
        pt_testkit::undeclared_test_files(&tests, "integration", &["references"]).unwrap();
    assert!(
        missing.is_empty(),
        "test files not declared in integration.rs: {missing:?}"
    );
}
