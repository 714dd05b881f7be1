//! One test per scene in scenes/ that has a Mitsuba reference in references/: render it at a
//! small sample count and compare with the reference (block z-test with both variances plus the
//! mean ratio; see `common::judge_against_reference`). Generated at run time with
//! libtest-mimic, so a new scene with a reference is tested without touching this file;
//! `cargo test --test references -- NAME` runs one.
//!
//! Sample counts: 1024 spp (the scenes here are about 128x96), or for a tiny image (below 768
//! pixels: a 1 x 1 irradiancemeter's) as many samples in all as a 128x96 image takes, so that
//! its pixel is measured as precisely as the mean of a whole image is. The z-scores use variances estimated
//! from the samples themselves; where the per-sample distribution is heavy-tailed (low-noise
//! scenes lit by delta lights, whose variance comes from rare indirect paths and edge pixels)
//! those estimates scatter, and the chi-square of all blocks is then wider than chi-square: at
//! 256 spp the directional-light scene gave chi-square p-values 0.000, 0.998, 0.26, 0.94, 0.99
//! over five seeds. At 1024 spp, twelve seed/scene pairs gave p between 0.025 and 0.997, as a
//! calibrated test should. The seed is the scene's, so CI is deterministic. Scenes with a
//! dedicated test that also checks failure cases (the Cornell box) are skipped here.
//!
//! Multiplicity. Each scene is two tests (the block family and the chi-square of all blocks).
//! At [`ALPHA`] each, a suite of 47 scenes would fail somewhere with probability
//! 1 - 0.99^94 = 61% on correct code whenever the random sequences change (on 2026-12-02 the
//! splatting film re-rolled the Gaussian-filtered scenes' noise and two chi-squares failed: p
//! 0.004 and 0.0002, with 0 of 120 and 126 blocks failing and mean ratios within 0.1%; the
//! disk scene's chi-square per degree of freedom is about 1.13 under either film over nine
//! seeds, its per-sample distribution is heavy-tailed). So the suite divides [`ALPHA`] among
//! its scenes and their two criteria (Bonferroni): the whole suite fails correct code with
//! probability at most 1%. What that costs: a block must be about 5.0 instead of 3.9 standard
//! errors off to fail alone. The mean ratio ([`MEAN_RATIO_TOL`], 0.5%) is unchanged, so a 2%
//! bias anywhere still fails, and so does any error that moves a block by 5 standard errors (a
//! missing bounce, a wrong pdf: tens to hundreds).

mod common;

use common::*;
use libtest_mimic::{Arguments, Failed, Trial};

/// Scenes tested elsewhere, with their own negative checks.
const DEDICATED: &[&str] = &["cornell-box"];
/// Samples per pixel for the comparison renders of the usual image size, [`PIXELS`].
const SPP: u32 = 1024;
/// The usual image size in pixels (128 x 96).
const PIXELS: u32 = 128 * 96;

fn check(scene: String, alpha: f64) -> Result<(), Failed> {
    let dir = scratch(&format!("ref_{scene}"));
    let (reference_img, _) = reference(&scene);
    let pixels = reference_img.width * reference_img.height;
    // Tiny images (a meter's one pixel) get the samples of a usual image; the others 1024 spp.
    let spp = if pixels < PIXELS / 16 {
        SPP * PIXELS / pixels.max(1)
    } else {
        SPP
    };
    let (img, var) = render(
        &repo().join("scenes").join(format!("{scene}.xml")),
        &dir,
        &scene,
        &["--spp", &spp.to_string()],
    );
    if img.nonfinite_pixels() > 0 {
        return Err(format!(
            "{scene}: {} pixels are NaN or infinite",
            img.nonfinite_pixels()
        )
        .into());
    }
    let v = judge_against_reference_at(&img, &var, &scene, &format!("{spp}spp"), alpha);
    if v.agrees() {
        Ok(())
    } else {
        Err(format!(
            "{scene} disagrees with its Mitsuba reference: {} of {} blocks fail (max |z| {:.2}), chi2 p {:.3}, mean ratio {:.4} {:.4} {:.4}",
            v.z.failed, v.z.tests, v.z.max_abs_z, v.z.chi2_p, v.ratio[0], v.ratio[1], v.ratio[2]
        )
        .into())
    }
}

fn main() {
    let args = Arguments::from_args();
    let mut scenes: Vec<String> = std::fs::read_dir(repo().join("scenes"))
        .expect("scenes/")
        .flatten()
        .filter_map(|e| {
            let p = e.path();
            if p.extension()? != "xml" {
                return None;
            }
            Some(p.file_stem()?.to_string_lossy().into_owned())
        })
        .filter(|s| !DEDICATED.contains(&s.as_str()))
        .collect();
    scenes.sort();
    let has_ref = |s: &str| repo().join("references").join(format!("{s}.exr")).is_file();
    // ALPHA shared by every scene's two criteria (see the module doc).
    let tested = scenes.iter().filter(|s| has_ref(s)).count().max(1);
    let alpha = ALPHA / (2 * tested) as f64;
    let trials = scenes
        .into_iter()
        .map(|s| {
            let name = s.clone();
            let ignored = !has_ref(&s);
            // A scene without a reference is listed as ignored, so the gap is visible.
            Trial::test(name, move || check(s, alpha)).with_ignored_flag(ignored)
        })
        .collect();
    libtest_mimic::run(&args, trials).exit();
}
