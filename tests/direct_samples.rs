//! Mitsuba's `direct` integrator with its sample counts (`emitter_samples`, `bsdf_samples`):
//! light sampling alone, BSDF sampling alone, three of each and unequal counts (one and four,
//! four and one: Veach's count-weighted power heuristic, each strategy's sum divided by its own
//! count; a count left out of either would brighten or darken the image by up to 4x) all render
//! the expected image of `scenes/direct-samples.xml`, whose Mitsuba 3.9.1 reference was made
//! with two of each. Same judge as the reference tests (block z-test with both variances, Sidak-corrected
//! at alpha 0.01, chi-square of the blocks, mean ratio). 256 spp at the scene's seed: the
//! single strategies are the noisy ones (BSDF sampling misses the small light, light sampling
//! the sharp plate), and their variances enter the z-scores, so noise does not fail them; the
//! noisiest of them (BSDF sampling alone) made 2% brighter must fail, which shows the test can
//! see a 2% bias at this noise level.

use crate::common::*;

fn rendered(label: &str, extra: &[&str]) -> (pt_image::Image, pt_image::Image) {
    let dir = scratch(label);
    let mut args = vec!["--spp", "256"];
    args.extend_from_slice(extra);
    render(
        &repo().join("scenes/direct-samples.xml"),
        &dir,
        label,
        &args,
    )
}

#[test]
fn every_choice_of_sample_counts_renders_the_direct_light_image() {
    for (label, e, b) in [
        ("light-only", "1", "0"),
        ("bsdf-only", "0", "1"),
        ("three-each", "3", "3"),
        ("one-light-four-bsdf", "1", "4"),
        ("four-light-one-bsdf", "4", "1"),
    ] {
        let (img, var) = rendered(
            label,
            &[
                "-D",
                &format!("emitter_samples={e}"),
                "-D",
                &format!("bsdf_samples={b}"),
            ],
        );
        let v = judge_against_reference(&img, &var, "direct-samples", label);
        assert!(
            v.agrees(),
            "{label} disagrees with the reference (line above)"
        );
    }
}

#[test]
fn a_two_percent_bias_of_the_noisiest_strategy_is_rejected() {
    let (img, var) = rendered(
        "bsdf-only-biased",
        &["-D", "emitter_samples=0", "-D", "bsdf_samples=1"],
    );
    let brighter = pt_image::Image {
        data: img.data.iter().map(|p| p.map(|c| c * 1.02)).collect(),
        ..img
    };
    let v = judge_against_reference(&brighter, &var, "direct-samples", "bsdf-only x 1.02");
    assert!(!v.agrees(), "BSDF sampling alone, 2% too bright, passed");
}
