//! The image depends only on the seed and sample count, not on the number of threads: with
//! importance sampling (the box-filtered Cornell box) and with the splatting film (a tent
//! filter with `sample_border`, whose splats cross tiles and come from a border outside the
//! image).

use crate::common;

use common::*;

#[test]
fn bit_identical_for_one_and_two_threads() {
    for name in ["cornell-box", "film-tent"] {
        identical_for_one_and_two_threads(name);
    }
}

fn identical_for_one_and_two_threads(name: &str) {
    let dir = scratch(&format!("determinism_{name}"));
    let scene = repo().join(format!("scenes/{name}.xml"));
    let small = ["--spp", "4", "--width", "48", "--height", "40"];
    let (a, va) = render(
        &scene,
        &dir,
        "t1",
        &[&small[..], &["--threads", "1"]].concat(),
    );
    let (b, vb) = render(
        &scene,
        &dir,
        "t2",
        &[&small[..], &["--threads", "2"]].concat(),
    );
    assert!(a
        .data
        .iter()
        .zip(&b.data)
        .all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits)));
    assert!(va
        .data
        .iter()
        .zip(&vb.data)
        .all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits)));
    // A different seed gives a different image (the streams really depend on it).
    let (c, _) = render(
        &scene,
        &dir,
        "seed",
        &[&small[..], &["--seed", "7"]].concat(),
    );
    assert!(a.data != c.data);
}

#[test]
fn builtin_cornell_box_renders_without_a_scene_argument() {
    let dir = scratch("builtin");
    let out = dir.join("builtin.exr");
    let o = pt(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "1",
        "--width",
        "16",
        "--height",
        "16",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (img, meta) = pt_image::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (16, 16));
    assert_eq!(meta.spp, Some(1));
    assert_eq!(meta.mode.as_deref(), Some("rgb"));
    // `pt info` describes the same scene.
    let o = pt(&["info"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("1 area light") && text.contains("mode        rgb"),
        "{text}"
    );
}
