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

/// A fresh scratch folder under target/ for one test, in a folder named after the test file
/// that asks for it (through `#[track_caller]` helpers), so that equal names in two files of
/// the one test binary, whose tests run at the same time, do not share a folder.
#[track_caller]
pub fn scratch(name: &str) -> PathBuf {
    let file = Path::new(std::panic::Location::caller().file());
    let module = file.file_stem().and_then(|s| s.to_str()).unwrap_or("tests");
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(module)
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch folder");
    dir
}

/// A Mitsuba `<sensor>` element for test scenes: a perspective camera at `origin` looking at
/// the world origin with +y up, `fov` degrees (along x), an independent sampler with `spp`
/// samples and a `width` x `height` box-filtered film.
pub fn sensor_xml(fov: f32, origin: [f32; 3], spp: u32, width: u32, height: u32) -> String {
    let [x, y, z] = origin;
    format!(
        r#"<sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <transform name="to_world"><lookat origin="{x}, {y}, {z}" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/><rfilter type="box"/></film>
    </sensor>"#
    )
}

/// Runs `pt` with the given arguments from the repository root.
pub fn pt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pt"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("run pt")
}

/// Renders `scene` with extra arguments into `dir/name.exr` (+ variance) and reads both back.
pub fn render(scene: &Path, dir: &Path, name: &str, extra: &[&str]) -> (Image, Image) {
    let out = dir.join(format!("{name}.exr"));
    let out_s = out.to_str().expect("utf-8 path");
    let scene_s = scene.to_str().expect("utf-8 path");
    let mut args = vec!["render", scene_s, "-o", out_s, "--variance", "--quiet"];
    args.extend_from_slice(extra);
    let o = pt(&args);
    assert!(
        o.status.success(),
        "pt {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let (img, _) = pt_image::read_exr(&out).expect("read render");
    let (var, _) = pt_image::read_exr(&dir.join(format!("{name}_var.exr"))).expect("read variance");
    (img, var)
}

/// Renders `scene` with extra `args` into `dir/name.exr` and reads every channel back (name,
/// row-major plane), for the channels `render` does not return (alpha, AOVs, moments).
pub fn render_channels(
    scene: &Path,
    dir: &Path,
    name: &str,
    args: &[&str],
) -> Vec<(String, Vec<f32>)> {
    let out = dir.join(format!("{name}.exr"));
    let mut all = vec![
        "render",
        scene.to_str().expect("utf-8 path"),
        "-o",
        out.to_str().expect("utf-8 path"),
        "--quiet",
    ];
    all.extend_from_slice(args);
    let o = pt(&all);
    assert!(
        o.status.success(),
        "pt {all:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    pt_image::read_exr_channels(&out).expect("read render").2
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

/// Block size (pixels) of the reference z-test.
pub const BLOCK: u32 = 16;
/// Family-wise significance of the reference z-test (Sidak-corrected over blocks).
pub const ALPHA: f64 = 0.01;
/// Global mean ratio tolerance. The image mean's standard error is 0.04-0.05% at 256 spp on the
/// Cornell box (measured from the variance images), so 0.5% is over 10 standard errors: noise
/// cannot fail it, while a 2% bias (or any systematic error above 0.5%) does. The block test is
/// the sharper instrument; this one says in one number how far off the image is.
pub const MEAN_RATIO_TOL: f64 = 0.005;

/// Mitsuba 3's spectral film divides by 106.7503 (`1 / MI_CIE_Y_NORMALIZATION`, read from the
/// 3.9.1 Python module) where the integral of the CIE 1931 y-bar over 360-830 nm, which pt uses
/// (a constant spectrum of 1 has Y = 1), is 106.8569. Mitsuba's spectral references are
/// therefore 0.099% brighter than the same radiance in pt; this known convention difference is
/// divided out before comparing, instead of widening any tolerance.
pub const MITSUBA_SPECTRAL_SCALE: f64 = 106.750_259 / 106.856_914_916_767;

/// Whether every emitter of `scene` (a name below scenes/, without `.xml`) is normalised to
/// the D65 white: RGB or constant radiance (both renderers upsample it and multiply by D65),
/// `d65` spectra, bitmap radiance and environment maps, and no display primaries. Both
/// renderers scale D65 to luminance Y = 1 under their own film normalisation (Mitsuba:
/// `MI_CIE_D65_NORMALIZATION` = 1 / 98.9974 gives Y = 0.99993), so such references need no
/// [`MITSUBA_SPECTRAL_SCALE`], which would bias them by 0.1%. Measured on envmap-spectral at
/// 4096 spp (seed 7): pt / Mitsuba = 1.0001, 1.0001, 0.9999 unscaled, block chi2 / dof 0.66;
/// with the scale 1.0009 and more, growing in z with the sample count. The project's other
/// named illuminants are normalised the same way. Tabulated and blackbody spectra are not
/// normalised and keep the scale.
pub fn d65_normalised(scene: &str) -> bool {
    use pt_scene::{LightKind, SpectrumDesc};
    let path = repo().join("scenes").join(format!("{scene}.xml"));
    let desc =
        pt_scene::load_file(&path, &[]).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let white = |s: &SpectrumDesc| match s {
        SpectrumDesc::Constant(_) | SpectrumDesc::Rgb(_) => true,
        SpectrumDesc::Uniform(_) => false,
        // D65 and pt's other named illuminants (A, F1-F12, which Mitsuba reads through
        // references/plugins/cie_illuminants.py) are all scaled to luminance Y = `scale` under
        // each renderer's own film normalisation.
        SpectrumDesc::Illuminant { .. } => true,
        SpectrumDesc::Tabulated(_) | SpectrumDesc::Measured(_) | SpectrumDesc::Blackbody { .. } => {
            false
        }
    };
    let shapes = desc
        .shapes
        .iter()
        .filter_map(|s| s.emitter.as_ref())
        .all(|e| e.primaries.is_none() && e.radiance.spectra().into_iter().all(white));
    let lights = desc.lights.iter().all(|l| match &l.kind {
        LightKind::Point { intensity, .. } => white(intensity),
        LightKind::Spot {
            intensity, texture, ..
        } => white(intensity) && texture.iter().flat_map(|t| t.spectra()).all(white),
        LightKind::Projector { irradiance, .. } => irradiance.spectra().into_iter().all(white),
        LightKind::Directional { irradiance, .. } | LightKind::Sun { irradiance, .. } => {
            white(irradiance)
        }
        LightKind::Constant { radiance } => white(radiance),
        LightKind::EnvMap { .. } => true,
        // Absolute spectral radiance per nm, not a D65 white.
        LightKind::SunSky(_) => false,
    });
    shapes && lights
}

/// The Mitsuba reference of `scene` (mean and variance of the mean), with spectral-variant
/// references rescaled by [`MITSUBA_SPECTRAL_SCALE`] unless their emission is D65-normalised
/// ([`d65_normalised`]).
pub fn reference(scene: &str) -> (Image, Image) {
    let r = repo().join("references");
    let (img, meta) = pt_image::read_exr(&r.join(format!("{scene}.exr")))
        .unwrap_or_else(|e| panic!("reference of {scene}: {e}"));
    let (var, _) = pt_image::read_exr(&r.join(format!("{scene}_var.exr")))
        .unwrap_or_else(|e| panic!("reference variance of {scene}: {e}"));
    let spectral = meta
        .extra
        .iter()
        .any(|(k, v)| k == "variant" && v.contains("spectral"));
    if !spectral || d65_normalised(scene) {
        return (img, var);
    }
    let k = MITSUBA_SPECTRAL_SCALE as f32;
    let scale = |im: Image, f: f32| Image {
        data: im.data.iter().map(|p| p.map(|c| c * f)).collect(),
        ..im
    };
    (scale(img, k), scale(var, k * k))
}

/// The outcome of comparing a render with its reference.
pub struct Verdict {
    /// The block z-test.
    pub z: pt_stats::ZTestReport,
    /// mean(render) / mean(reference) per channel.
    pub ratio: [f64; 3],
}

impl Verdict {
    /// Block z-test passes and every channel's mean ratio is within [`MEAN_RATIO_TOL`] of 1
    /// (channels whose reference mean is 0 must be 0 too).
    pub fn agrees(&self) -> bool {
        self.z.pass
            && self
                .ratio
                .iter()
                .all(|r| (r - 1.0).abs() < MEAN_RATIO_TOL || r.is_nan())
    }
}

/// Compares a render (mean and variance-of-mean images) with the reference of `scene`: block
/// z-test ([`BLOCK`], [`ALPHA`]) with both variances, and the mean ratio. Prints one summary line;
/// on a failed z-test writes the relative error and per-block |z| images under
/// target/tmp/common/diag_<scene>_<label>/ and says where.
pub fn judge_against_reference(img: &Image, var: &Image, scene: &str, label: &str) -> Verdict {
    judge_against_reference_at(img, var, scene, label, ALPHA)
}

/// [`judge_against_reference`] at significance `alpha` for both the block family and the
/// chi-square of all blocks (a suite of many scenes divides [`ALPHA`] among them).
pub fn judge_against_reference_at(
    img: &Image,
    var: &Image,
    scene: &str,
    label: &str,
    alpha: f64,
) -> Verdict {
    let (rimg, rvar) = reference(scene);
    let z = pt_stats::block_ztest(img, var, &rimg, &rvar, BLOCK, alpha)
        .expect("same size as the reference");
    let (m, mr) = (img.mean(), rimg.mean());
    let ratio = std::array::from_fn(|c| {
        if mr[c] == 0.0 && m[c] == 0.0 {
            f64::NAN
        } else {
            m[c] / mr[c]
        }
    });
    eprintln!(
        "{scene} {label}: max |z| {:.2} (per-test p threshold {:.2e}), failed blocks {}/{}, chi2 {:.1} (p {:.3}), mean ratio {:.4} {:.4} {:.4}",
        z.max_abs_z, z.p_threshold, z.failed, z.tests, z.chi2, z.chi2_p, ratio[0], ratio[1], ratio[2]
    );
    if !z.pass {
        write_diagnostics(img, &rimg, &z, &format!("{scene}_{label}"));
    }
    Verdict { z, ratio }
}

fn write_diagnostics(img: &Image, reference: &Image, z: &pt_stats::ZTestReport, name: &str) {
    let dir = scratch(&format!("diag_{name}"));
    let Ok(err) = pt_image::colormap::relative_error_image(img, reference) else {
        return;
    };
    let err_img = pt_image::colormap::false_colour(&err, img.width, img.height, 0.0, 0.2, false);
    let zs: Vec<f32> =
        z.z.iter()
            .map(|b| b.iter().fold(0.0f64, |a, v| a.max(v.abs())) as f32)
            .collect();
    let z_img = pt_image::colormap::false_colour(&zs, z.blocks_x, z.blocks_y, 0.0, 6.0, false);
    let _ = pt_image::write_exr(&dir.join("render.exr"), img, &Default::default());
    let _ = pt_image::write_png_preview(&dir.join("relative_error.png"), &err_img, 0.0);
    let _ = pt_image::write_png_preview(&dir.join("block_abs_z.png"), &z_img, 0.0);
    eprintln!(
        "{name}: render, relative error (0-20%) and per-block |z| (0-6) written to {}",
        dir.display()
    );
}

/// The mean red value of the caustic spot the glass ball focuses on the red wall
/// (scenes/include/cornell-caustic.xml): the 7 x 7 pixels around (19, 86) of the 128 x 128
/// image, where both caustic scenes' Mitsuba references put it.
pub fn caustic_spot(img: &Image) -> f64 {
    let mut sum = 0.0f64;
    for y in 83..90 {
        for x in 16..23 {
            sum += f64::from(img.data[y * img.width as usize + x][0]);
        }
    }
    sum / 49.0
}
