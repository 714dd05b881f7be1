//! `pt compare`: error metrics of an image against a reference, and the z-test when both
//! have variance images.

use crate::variance_path;
use anyhow::{bail, Result};
use clap::Args;
use pt_image::{ExrMeta, Image};
use pt_lab::compare::CompareSettings;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct CompareArgs {
    /// The image to judge (EXR from pt or Mitsuba).
    image: PathBuf,
    /// The reference (EXR).
    reference: PathBuf,
    /// Variance of the reference's pixel means [default: REFERENCE_var.exr if it exists].
    #[arg(long, value_name = "REF_VAR.exr")]
    variance: Option<PathBuf>,
    /// Variance of the image's pixel means [default: IMAGE_var.exr if it exists].
    #[arg(long, value_name = "IMG_VAR.exr")]
    image_variance: Option<PathBuf>,
    /// Block size of the z-test, pixels.
    #[arg(long, default_value_t = 16)]
    block: u32,
    /// Family-wise significance of the z-test (Sidak-corrected over blocks).
    #[arg(long, default_value_t = 0.01)]
    alpha: f64,
    /// Write a false-colour relative error image (EXR or PNG).
    #[arg(long, value_name = "OUT")]
    error_image: Option<PathBuf>,
    /// Exposure (stops) of the tone mapping both images get before FLIP (scale by 2^stops, clamp, sRGB).
    #[arg(long, default_value_t = 0.0)]
    flip_exposure: f32,
    /// Write FLIP's per-pixel error (0 to 1, viridis) as a false-colour image (EXR or PNG).
    #[arg(long, value_name = "OUT")]
    flip_image: Option<PathBuf>,
    /// Only check that the two EXRs hold the same channels with the same values, bit for bit
    /// (headers such as the render time may differ): exit 0 when they do, 1 when not. For
    /// checking that a merged split render equals the render on one machine.
    #[arg(long, conflicts_with_all = ["variance", "image_variance", "error_image", "flip_image"])]
    identical: bool,
}

/// `--identical`: every channel, bit for bit.
fn identical(a: &Path, b: &Path) -> Result<ExitCode> {
    let (wa, ha, ca) = pt_image::read_exr_channels(a)?;
    let (wb, hb, cb) = pt_image::read_exr_channels(b)?;
    if (wa, ha) != (wb, hb) {
        out!("different sizes: {wa}x{ha} and {wb}x{hb}");
        return Ok(ExitCode::from(1));
    }
    let names = |c: &pt_image::NamedChannels| c.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    if names(&ca) != names(&cb) {
        out!("different channels: {:?} and {:?}", names(&ca), names(&cb));
        return Ok(ExitCode::from(1));
    }
    let mut same = true;
    for ((name, x), (_, y)) in ca.iter().zip(&cb) {
        let differ = x
            .iter()
            .zip(y)
            .filter(|(p, q)| p.to_bits() != q.to_bits())
            .count();
        if differ > 0 {
            same = false;
        }
        out!("channel {name}: {differ} of {} values differ", x.len());
    }
    out!("{}", if same { "identical" } else { "NOT identical" });
    Ok(ExitCode::from(u8::from(!same)))
}

/// `a.exr` -> `a_var.exr` if that file exists.
fn sibling_variance(path: &Path) -> Option<PathBuf> {
    let v = variance_path(path);
    v.is_file().then_some(v)
}

pub(crate) fn run(args: CompareArgs) -> Result<ExitCode> {
    if args.identical {
        return identical(&args.image, &args.reference);
    }
    // Output names are checked before any work, so a bad one fails fast with nothing written.
    for (flag, out) in [
        ("--error-image", &args.error_image),
        ("--flip-image", &args.flip_image),
    ] {
        if let Some(out) = out {
            if !matches!(extension(out).as_deref(), Some("png" | "exr")) {
                bail!("{flag} '{}' must end in .png or .exr", out.display());
            }
        }
    }
    let (img, _) = pt_image::read_exr(&args.image)?;
    let (reference, _) = pt_image::read_exr(&args.reference)?;
    if (img.width, img.height) != (reference.width, reference.height) {
        bail!(
            "'{}' is {}x{} but '{}' is {}x{}",
            args.image.display(),
            img.width,
            img.height,
            args.reference.display(),
            reference.width,
            reference.height
        );
    }
    let variances = variances(&args)?;
    let c = pt_lab::compare::compare(
        &img,
        &reference,
        variances.as_ref().map(|(i, r)| (i, r)),
        CompareSettings {
            block: args.block,
            alpha: args.alpha,
            flip_exposure: args.flip_exposure,
        },
    )?;
    print_report(&args, &c);
    let flip = c.flip;
    let agree = c.agree;
    if let Some(out) = &args.error_image {
        let err = pt_image::colormap::relative_error_image(&img, &reference)?;
        let e = pt_image::colormap::false_colour(&err, img.width, img.height, 0.0, 0.2, false);
        write_false_colour("--error-image", out, &e)?;
        out!(
            "relative error image (0 to 20%, viridis) -> {}",
            out.display()
        );
    }
    if let Some(out) = &args.flip_image {
        let e = pt_image::colormap::false_colour(
            &flip.error_map,
            img.width,
            img.height,
            0.0,
            1.0,
            false,
        );
        write_false_colour("--flip-image", out, &e)?;
        out!("FLIP error image (0 to 1, viridis) -> {}", out.display());
    }
    Ok(if agree {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// Prints the comparison `c`: the metrics per channel, non-finite pixels, FLIP, fireflies and
/// the z-tests (when there were variances).
fn print_report(args: &CompareArgs, c: &pt_lab::compare::Comparison) {
    let m = &c.metrics;
    let ch = |v: [f64; 3]| format!("{:>12.6e} {:>12.6e} {:>12.6e}", v[0], v[1], v[2]);
    out!("{:<22} {:>12} {:>12} {:>12}", "metric", "R", "G", "B");
    out!(
        "{:<22} {}   (all: {:.6e})",
        "relMSE",
        ch(m.relmse),
        m.relmse_all
    );
    out!("{:<22} {}", "RMSE", ch(m.rmse));
    out!("{:<22} {}", "MAE", ch(m.mae));
    out!("{:<22} {}", "mean ratio", ch(m.mean_ratio));
    out!(
        "{:<22} {} / {}",
        "non-finite pixels",
        c.nonfinite.0,
        c.nonfinite.1
    );
    out!(
        "{:<22} {:>12.6}   (mean, tone-mapped at {:+} stops, {} px/degree)",
        "FLIP",
        c.flip.mean,
        args.flip_exposure,
        pt_image::flip::DEFAULT_PIXELS_PER_DEGREE
    );
    let ff = c.firefly_rule;
    out!(
        "{:<22} {} / {}   (image / reference: luminance > median + {} MAD-sigma of the {}x{} neighbourhood)",
        "fireflies",
        c.fireflies.0,
        c.fireflies.1,
        ff.k,
        2 * ff.radius + 1,
        2 * ff.radius + 1
    );
    match &c.ztests {
        Some(z) => {
            let (b, pz) = (&z.block, &z.pixel);
            out!(
                "block z-test ({}x{} px, alpha {}): max |z| {:.2}, {} of {} block-channels fail (per-test p < {:.2e}), chi2 {:.1} on {} dof (p {:.3}): {}",
                args.block,
                args.block,
                args.alpha,
                b.max_abs_z,
                b.failed,
                b.tests,
                b.p_threshold,
                b.chi2,
                b.tests,
                b.chi2_p,
                if b.pass { "PASS" } else { "FAIL" }
            );
            out!(
                "pixel z-test: {:.3}% of pixel-channels fail at p < {}",
                100.0 * pz.fraction_failed,
                args.alpha
            );
        }
        None => out!("no variance images: z-test skipped (give --variance and --image-variance, or put NAME_var.exr beside each)"),
    }
}

/// The lower-case extension of the output path `out`.
fn extension(out: &Path) -> Option<String> {
    out.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// Writes the false-colour image `e` to `out` (given by `flag`) as PNG or EXR, by its
/// extension.
fn write_false_colour(flag: &str, out: &Path, e: &Image) -> Result<()> {
    match extension(out).as_deref() {
        Some("png") => pt_image::write_png_preview(out, e, 0.0)?,
        Some("exr") => pt_image::write_exr(out, e, &ExrMeta::default())?,
        _ => bail!("{flag} '{}' must end in .png or .exr", out.display()),
    }
    Ok(())
}

/// The variance images of the image and the reference, when both exist (given, or beside
/// each image as NAME_var.exr).
fn variances(args: &CompareArgs) -> Result<Option<(Image, Image)>> {
    let img_var = args
        .image_variance
        .clone()
        .or_else(|| sibling_variance(&args.image));
    let ref_var = args
        .variance
        .clone()
        .or_else(|| sibling_variance(&args.reference));
    Ok(match (img_var, ref_var) {
        (Some(iv), Some(rv)) => Some((pt_image::read_exr(&iv)?.0, pt_image::read_exr(&rv)?.0)),
        _ => None,
    })
}
