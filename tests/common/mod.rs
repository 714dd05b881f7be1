//! Helpers shared by the integration tests: run the `pt` binary, make scratch folders, read
//! renders back.
#![allow(dead_code)]

use pt_image::Image;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (where Cargo.toml is).
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh scratch folder under target/ for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch folder");
    dir
}

/// Runs `pt` with the given arguments from the repository root.
pub fn pt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pt")).args(args).current_dir(repo()).output().expect("run pt")
}

/// Renders `scene` with extra arguments into `dir/name.exr` (+ variance) and reads both back.
pub fn render(scene: &Path, dir: &Path, name: &str, extra: &[&str]) -> (Image, Image) {
    let out = dir.join(format!("{name}.exr"));
    let out_s = out.to_str().expect("utf-8 path");
    let scene_s = scene.to_str().expect("utf-8 path");
    let mut args = vec!["render", scene_s, "-o", out_s, "--variance", "--quiet"];
    args.extend_from_slice(extra);
    let o = pt(&args);
    assert!(o.status.success(), "pt {args:?} failed: {}", String::from_utf8_lossy(&o.stderr));
    let (img, _) = pt_image::read_exr(&out).expect("read render");
    let (var, _) = pt_image::read_exr(&dir.join(format!("{name}_var.exr"))).expect("read variance");
    (img, var)
}

/// Mean of an image per channel and the standard error of that mean, from the per-pixel
/// variance-of-the-mean image (pixels are independent, so variances add).
pub fn mean_and_stderr(img: &Image, var: &Image) -> ([f64; 3], [f64; 3]) {
    let n = img.data.len() as f64;
    let mut m = [0.0; 3];
    let mut v = [0.0; 3];
    for (p, q) in img.data.iter().zip(&var.data) {
        for c in 0..3 {
            m[c] += p[c] as f64;
            v[c] += q[c] as f64;
        }
    }
    (m.map(|x| x / n), v.map(|x| x.sqrt() / n))
}
