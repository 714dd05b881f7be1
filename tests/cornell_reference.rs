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

mod common;

use common::*;
use pt_image::stats::{block_ztest, ZTestReport};
use pt_image::Image;

const BLOCK: u32 = 16;
const ALPHA: f64 = 0.01;
/// Global mean ratio tolerance. The image mean's standard error is 0.04-0.05% at 256 spp
/// (measured from the variance images), so 0.5% is over 10 standard errors: noise cannot fail
/// it, while a 2% bias (or any systematic error above 0.5%) does. The block test above is the
/// sharper instrument; this one says in one number how far off the image is.
const MEAN_RATIO_TOL: f64 = 0.005;

fn reference() -> (Image, Image) {
    let r = repo().join("references");
    let (img, _) = pt_image::read_exr(&r.join("cornell-box.exr")).expect("references/cornell-box.exr");
    let (var, _) = pt_image::read_exr(&r.join("cornell-box_var.exr")).expect("references/cornell-box_var.exr");
    (img, var)
}

/// Samples per pixel of the test renders (see the module comment).
const SPP: &str = "256";

/// The render at the scene's settings (256x256, max_depth 8) at [`SPP`], cached per test run.
fn nominal() -> &'static (Image, Image) {
    static R: std::sync::OnceLock<(Image, Image)> = std::sync::OnceLock::new();
    R.get_or_init(|| {
        let dir = scratch("cornell_nominal");
        render(&repo().join("scenes/cornell-box.xml"), &dir, "cornell", &["--spp", SPP])
    })
}

struct Verdict {
    z: ZTestReport,
    ratio: [f64; 3],
}

impl Verdict {
    fn agrees(&self) -> bool {
        self.z.pass && self.ratio.iter().all(|r| (r - 1.0).abs() < MEAN_RATIO_TOL)
    }
}

fn judge(img: &Image, var: &Image, name: &str) -> Verdict {
    let (rimg, rvar) = reference();
    let z = block_ztest(img, var, &rimg, &rvar, BLOCK, ALPHA).expect("same size as the reference");
    let (m, mr) = (img.mean(), rimg.mean());
    let ratio = std::array::from_fn(|c| m[c] / mr[c]);
    eprintln!(
        "{name}: max |z| {:.2} (threshold p {:.2e}), failed blocks {}/{}, chi2 {:.1} (p {:.3}), mean ratio {:.4} {:.4} {:.4}",
        z.max_abs_z, z.p_threshold, z.failed, z.tests, z.chi2, z.chi2_p, ratio[0], ratio[1], ratio[2]
    );
    if !z.pass {
        write_diagnostics(img, &rimg, &z, name);
    }
    Verdict { z, ratio }
}

/// On failure: the relative error image and the per-block |z| image under target/.
fn write_diagnostics(img: &Image, reference: &Image, z: &ZTestReport, name: &str) {
    let dir = scratch(&format!("cornell_diag_{name}"));
    let Ok(err) = pt_image::colormap::relative_error_image(img, reference) else { return };
    let err_img = pt_image::colormap::false_colour(&err, img.width, img.height, 0.0, 0.2, false);
    let zs: Vec<f32> = z.z.iter().map(|b| b.iter().fold(0.0f64, |a, v| a.max(v.abs())) as f32).collect();
    let z_img = pt_image::colormap::false_colour(&zs, z.blocks_x, z.blocks_y, 0.0, 6.0, false);
    let _ = pt_image::write_exr(&dir.join("relative_error.exr"), &err_img, &Default::default());
    let _ = pt_image::write_png_preview(&dir.join("relative_error.png"), &err_img, 0.0);
    let _ = pt_image::write_png_preview(&dir.join("block_abs_z.png"), &z_img, 0.0);
    eprintln!("{name}: diagnostics written to {}", dir.display());
}

#[test]
fn cornell_box_matches_mitsuba_reference() {
    let (img, var) = nominal();
    let v = judge(img, var, "nominal");
    assert!(img.nonfinite_pixels() == 0);
    assert!(v.agrees(), "the render disagrees with the Mitsuba reference (see the line above)");
}

#[test]
fn a_two_percent_brighter_render_is_rejected() {
    let (img, var) = nominal();
    let scale = 1.02f32;
    let brighter = Image { data: img.data.iter().map(|p| p.map(|c| c * scale)).collect(), ..img.clone() };
    let bvar = Image { data: var.data.iter().map(|p| p.map(|c| c * scale * scale)).collect(), ..var.clone() };
    let v = judge(&brighter, &bvar, "brighter_2pct");
    assert!(!v.z.pass, "the block z-test must detect a 2% bias");
    assert!(!v.agrees());
}

#[test]
fn a_render_without_indirect_light_is_rejected() {
    let dir = scratch("cornell_depth2");
    let (img, var) = render(&repo().join("scenes/cornell-box.xml"), &dir, "cornell_d2", &["--max-depth", "2", "--spp", SPP]);
    let v = judge(&img, &var, "max_depth_2");
    assert!(!v.z.pass, "the block z-test must detect missing indirect light");
    assert!(!v.agrees());
}
