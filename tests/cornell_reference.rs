//! The Cornell box against its Mitsuba 3 reference (references/cornell-box.exr and _var.exr).
//!
//! Test: a per-block z-test (16x16-pixel blocks, each channel) using the render's and the
//! reference's variance of the mean, Sidak-corrected over all blocks at alpha = 0.01, plus a
//! chi-square test of the sum of squared z-scores (the method of Mitsuba 3's render regression
//! tests, applied per block so a small uniform bias adds up over each block's 256 pixels), and a
//! global mean-ratio check. Both must pass on noise and must fail on a 2% brightness bias and on a
//! render with max_depth 2 instead of the scene's 8; the two negative tests assert that.
//!
//! Why these numbers: the render uses 256 spp (the scene's seed, so CI is deterministic). The
//! relative standard error of a 16x16 block mean is then about 0.3%, so a 2% bias is several
//! sigma in many blocks and ~100 sigma in the chi-square sum; dropping indirect light (max_depth 2)
//! is hundreds of sigma. Noise alone fails with probability about alpha = 1%: measured over 10
//! seeds at 256 spp, 1 chi-square failure (p = 0.009) and no block failure; at 64 spp the
//! per-pixel variance estimates are too noisy for the chi-square to be calibrated (3 of 8 seeds
//! had p ~ 0.03), which is why the test pays for 256.

use crate::common;

use common::*;
use pt_image::Image;

/// Samples per pixel of the test renders (see the module comment).
const SPP: &str = "256";

/// The render at the scene's settings (256x256, max_depth 8) at [`SPP`], cached per test run.
fn nominal() -> &'static (Image, Image) {
    static R: std::sync::OnceLock<(Image, Image)> = std::sync::OnceLock::new();
    R.get_or_init(|| {
        let dir = scratch("cornell_nominal");
        render(
            &repo().join("scenes/cornell-box.xml"),
            &dir,
            "cornell",
            &["--spp", SPP],
        )
    })
}

fn judge(img: &Image, var: &Image, label: &str) -> Verdict {
    judge_against_reference(img, var, "cornell-box", label)
}

#[test]
fn cornell_box_matches_mitsuba_reference() {
    let (img, var) = nominal();
    let v = judge(img, var, "nominal");
    assert!(img.nonfinite_pixels() == 0);
    assert!(
        v.agrees(),
        "the render disagrees with the Mitsuba reference (see the line above)"
    );
}

#[test]
fn a_two_percent_brighter_render_is_rejected() {
    let (img, var) = nominal();
    let scale = 1.02f32;
    let brighter = Image {
        data: img.data.iter().map(|p| p.map(|c| c * scale)).collect(),
        ..img.clone()
    };
    let bvar = Image {
        data: var
            .data
            .iter()
            .map(|p| p.map(|c| c * scale * scale))
            .collect(),
        ..var.clone()
    };
    let v = judge(&brighter, &bvar, "brighter_2pct");
    assert!(!v.z.pass, "the block z-test must detect a 2% bias");
    assert!(!v.agrees());
}

#[test]
fn a_render_without_indirect_light_is_rejected() {
    let dir = scratch("cornell_depth2");
    let (img, var) = render(
        &repo().join("scenes/cornell-box.xml"),
        &dir,
        "cornell_d2",
        &["--max-depth", "2", "--spp", SPP],
    );
    let v = judge(&img, &var, "max_depth_2");
    assert!(
        !v.z.pass,
        "the block z-test must detect missing indirect light"
    );
    assert!(!v.agrees());
}
