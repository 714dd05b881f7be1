//! Interrupting and resuming renders (issue 8, "under load"):
//! - a render saved after 10 samples per pixel and resumed to 24 is bit-identical (means and
//!   variances) to an uninterrupted 24-sample render, for 1 and 2 threads, with importance
//!   sampling (the box-filtered Cornell box) and with the splatting film (a Gaussian filter):
//!   the sums are saved exactly, sample s of pixel p always uses the same random stream, and
//!   splats are added in an order that does not depend on the passes;
//! - a state is refused (exit 2, no output) for another seed or image size;
//! - Ctrl-C (SIGINT) during a long render writes a valid image of the samples taken so far, with
//!   the sample count in its header, leaves no temporary file, exits with code 130, and the
//!   saved state resumes.

use crate::common;

use common::*;
use std::process::Command;
use std::time::Duration;

fn run(args: &[&str]) -> std::process::Output {
    pt(args)
}

#[test]
fn resumed_render_equals_uninterrupted_render() {
    let dir = scratch("resume_equal");
    let p = |n: &str| dir.join(n).to_str().unwrap().to_string();
    let gaussian = repo().join("scenes/film-gaussian.xml");
    for (scene, threads) in [
        (None, "1"),
        (None, "2"),
        (Some(&gaussian), "1"),
        (Some(&gaussian), "2"),
    ] {
        let name = |n: &str| format!("{n}{threads}{}", if scene.is_some() { "g" } else { "" });
        let mut base = vec!["--width", "32", "--height", "24", "--quiet", "--variance"];
        if let Some(s) = scene {
            base.insert(0, s.to_str().unwrap());
        }
        let full = p(&format!("{}.exr", name("full")));
        let o = run(&[
            &["render", "-o", &full, "--spp", "24", "--threads", threads][..],
            &base,
        ]
        .concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let state = p(&format!("{}.bin", name("state")));
        let part = p(&format!("{}.exr", name("part")));
        let o = run(&[
            &[
                "render",
                "-o",
                &part,
                "--spp",
                "10",
                "--save-state",
                &state,
                "--threads",
                threads,
            ][..],
            &base,
        ]
        .concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let resumed = p(&format!("{}.exr", name("resumed")));
        let o = run(&[
            &[
                "render",
                "-o",
                &resumed,
                "--spp",
                "24",
                "--resume",
                &state,
                "--threads",
                threads,
            ][..],
            &base,
        ]
        .concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (a, ma) = pt_image::read_exr(std::path::Path::new(&full)).unwrap();
        let (b, mb) = pt_image::read_exr(std::path::Path::new(&resumed)).unwrap();
        assert_eq!(ma.spp, Some(24));
        assert_eq!(mb.spp, Some(24));
        assert!(
            a.data == b.data,
            "resumed image differs from the uninterrupted one ({threads} threads)"
        );
        let va = pt_image::read_exr(&dir.join(format!("{}_var.exr", name("full"))))
            .unwrap()
            .0;
        let vb = pt_image::read_exr(&dir.join(format!("{}_var.exr", name("resumed"))))
            .unwrap()
            .0;
        assert!(va.data == vb.data, "variances differ ({threads} threads)");
        // The partial image is a real 10-spp render, not the full one.
        let (c, mc) = pt_image::read_exr(std::path::Path::new(&part)).unwrap();
        assert_eq!(mc.spp, Some(10));
        assert!(c.data != a.data);
    }
}

#[test]
fn state_of_another_render_is_refused() {
    let dir = scratch("resume_refused");
    let p = |n: &str| dir.join(n).to_str().unwrap().to_string();
    let state = p("state.bin");
    let o = run(&[
        "render",
        "-o",
        &p("a.exr"),
        "--spp",
        "4",
        "--width",
        "16",
        "--height",
        "16",
        "--quiet",
        "--save-state",
        &state,
    ]);
    assert!(o.status.success());
    let cases: [&[&str]; 3] = [
        &["--seed", "9", "--width", "16"],
        &["--width", "20"],
        &["-D", "spp=3", "--width", "16"],
    ];
    for extra in cases {
        let out = p("b.exr");
        let args = [
            &[
                "render", "-o", &out, "--spp", "8", "--height", "16", "--quiet", "--resume", &state,
            ][..],
            extra,
        ]
        .concat();
        let o = run(&args);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            !std::path::Path::new(&out).exists(),
            "{extra:?}: output written"
        );
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("state"),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    std::fs::write(&state, b"PTSTATE1 truncated").unwrap();
    let o = run(&[
        "render",
        "-o",
        &p("c.exr"),
        "--spp",
        "8",
        "--width",
        "16",
        "--height",
        "16",
        "--quiet",
        "--resume",
        &state,
    ]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn ctrl_c_writes_the_image_so_far_and_the_state_resumes() {
    let dir = scratch("resume_ctrl_c");
    let out = dir.join("out.exr");
    let state = dir.join("state.bin");
    let mut child = Command::new(env!("CARGO_BIN_EXE_pt"))
        .args([
            "render",
            "-o",
            out.to_str().unwrap(),
            "--spp",
            "1000000",
            "--width",
            "48",
            "--height",
            "48",
            "--quiet",
            "--save-state",
            state.to_str().unwrap(),
        ])
        .current_dir(repo())
        .spawn()
        .expect("start pt");
    std::thread::sleep(Duration::from_millis(2500));
    let k = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(k.success());
    // A pass takes at most about a second once the doubling stops.
    let mut status = None;
    for _ in 0..200 {
        if let Some(s) = child.try_wait().unwrap() {
            status = Some(s);
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let status = status.unwrap_or_else(|| {
        let _ = child.kill();
        panic!("pt did not stop within 20 s of SIGINT")
    });
    assert_eq!(status.code(), Some(130));
    let (img, meta) = pt_image::read_exr(&out).expect("a valid image after Ctrl-C");
    let spp = meta.spp.expect("spp in the header");
    assert!((1..1_000_000).contains(&spp), "spp {spp}");
    assert!(img.data.iter().all(|p| p.iter().all(|c| c.is_finite())));
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n != "out.exr" && n != "state.bin")
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    // The state continues.
    let more = (spp + 3).to_string();
    let out2 = dir.join("more.exr");
    let o = run(&[
        "render",
        "-o",
        out2.to_str().unwrap(),
        "--spp",
        &more,
        "--width",
        "48",
        "--height",
        "48",
        "--quiet",
        "--resume",
        state.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(pt_image::read_exr(&out2).unwrap().1.spp, Some(spp + 3));
}
