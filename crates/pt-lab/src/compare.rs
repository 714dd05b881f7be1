//! The figures of `pt compare` (and of the Python module's `compare`): an image against a
//! reference, both linear RGB of the same size.
//!
//! - error metrics per channel (relMSE, RMSE, MAE, mean ratio; [`pt_image::metrics`]);
//! - non-finite pixels of each image;
//! - FLIP (Andersson et al. 2020) after tone mapping both at an exposure;
//! - fireflies of each image ([`pt_image::fireflies`], default rule);
//! - given the variances of both images' pixel means: the block z-test (Šidák-corrected over
//!   blocks, plus a chi-square of every block's z) and the per-pixel z-test
//!   ([`pt_stats::block_ztest`], [`pt_stats::pixel_ztest`]).
//!
//! The two agree when neither has a non-finite pixel and the block z-test passes (or was not
//! run, for lack of variances).

use crate::Result;
use pt_image::fireflies::FireflyParams;
use pt_image::flip::Flip;
use pt_image::metrics::Metrics;
use pt_image::Image;
use pt_stats::{PixelZTest, ZTestReport};

/// Settings of a comparison (`pt compare`'s defaults).
#[derive(Clone, Copy, Debug)]
pub struct CompareSettings {
    /// Block size of the z-test, pixels.
    pub block: u32,
    /// Family-wise significance of the block z-test (Šidák-corrected over blocks); the
    /// per-test level of the pixel z-test.
    pub alpha: f64,
    /// Exposure in stops of the tone mapping both images get before FLIP.
    pub flip_exposure: f32,
}

impl Default for CompareSettings {
    fn default() -> Self {
        CompareSettings {
            block: 16,
            alpha: 0.01,
            flip_exposure: 0.0,
        }
    }
}

/// The z-tests of a comparison with variances.
#[derive(Clone, Debug)]
pub struct ZTests {
    /// The block z-test.
    pub block: ZTestReport,
    /// The per-pixel z-test.
    pub pixel: PixelZTest,
}

/// What [`compare`] found.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Error metrics per channel.
    pub metrics: Metrics,
    /// Non-finite pixels of the image and of the reference.
    pub nonfinite: (usize, usize),
    /// FLIP: the mean and the per-pixel error map.
    pub flip: Flip,
    /// Fireflies of the image and of the reference.
    pub fireflies: (usize, usize),
    /// The firefly rule used.
    pub firefly_rule: FireflyParams,
    /// The z-tests, when both variances were given.
    pub ztests: Option<ZTests>,
    /// Neither image has a non-finite pixel and the block z-test passed (or was not run).
    pub agree: bool,
    /// The settings used.
    pub settings: CompareSettings,
}

/// Compares `img` with `reference`; `variances` are the variances of the pixel means of the
/// image and of the reference, in that order. Errors on size mismatches and settings outside
/// their domain (`block` 0, `alpha` outside (0, 1)).
pub fn compare(
    img: &Image,
    reference: &Image,
    variances: Option<(&Image, &Image)>,
    settings: CompareSettings,
) -> Result<Comparison> {
    pt_image::check_same_size("image", img, reference, "reference")?;
    let metrics = pt_image::metrics::compare(img, reference)?;
    let flip = pt_image::flip::flip(img, reference, settings.flip_exposure)?;
    let rule = FireflyParams::default();
    let ztests = match variances {
        None => None,
        Some((iv, rv)) => Some(ZTests {
            block: pt_stats::block_ztest(img, iv, reference, rv, settings.block, settings.alpha)?,
            pixel: pt_stats::pixel_ztest(img, iv, reference, rv, settings.alpha)?,
        }),
    };
    let nonfinite = (img.nonfinite_pixels(), reference.nonfinite_pixels());
    let agree = nonfinite.0 == 0 && ztests.as_ref().is_none_or(|z| z.block.pass);
    Ok(Comparison {
        metrics,
        nonfinite,
        flip,
        fireflies: (
            pt_image::fireflies::count_fireflies(img, rule),
            pt_image::fireflies::count_fireflies(reference, rule),
        ),
        firefly_rule: rule,
        ztests,
        agree,
        settings,
    })
}
