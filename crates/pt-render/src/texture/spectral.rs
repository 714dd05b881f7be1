//! RGB images in spectral mode: per-texel RGB -> spectrum upsampling (Jakob & Hanika 2019),
//! and display primaries for image-emitting surfaces (monitors).
//!
//! # Upsampling (Jakob & Hanika 2019, eq. 3-4)
//! Every texel's linear sRGB value `rgb` becomes `scale * S(c0 t^2 + c1 t + c2)`,
//! `t = (lambda - 360 nm) / 470 nm`, with the sigmoid polynomial of [`RgbSigmoid`] looked up
//! once per texel at load time in the 64^3 coefficient table of the paper (as Mitsuba 3's
//! `srgb_model_fetch` does; see [`upsample_texels`]): nothing is fitted or allocated per
//! sample.
//! - [`Upsampling::Reflectance`] (bitmap textures: glTF base colour, monitor images): texels with
//!   all components <= 1 get the bounded fit of `rgb` and `scale` 1, as Mitsuba 3's `bitmap` in
//!   its spectral variants (`srgb_model_fetch` per texel). Brighter texels (HDR images) get the
//!   fit of `rgb / (2 max rgb)` and `scale = 2 max rgb` (pbrt-v4's `RGBUnboundedSpectrum`);
//!   Mitsuba clamps them to 1 instead, losing their energy.
//! - [`Upsampling::Emission`] (environment maps): always the fit of `rgb / (2 max rgb)` with
//!   `scale = 2 max rgb`, as Mitsuba 3's `envmap`; black texels have scale 0.
//!
//! Emission is multiplied by the D65 illuminant (normalised to luminance 1) by the caller, as
//! for every RGB emitter in spectral mode (DESIGN.md, Colour), so a white texel (1, 1, 1) emits
//! D65 of luminance 1 and renders as sRGB (1, 1, 1).
//!
//! # Interpolation (checked against Mitsuba 3.9.1)
//! [`SpectralBitmap::eval`] looks up the same texels with the same bilinear weights as
//! [`Bitmap::eval`] (pixel centres at `(x + 0.5) / width`, repeat wrap, or nearest) and
//! interpolates the texels' **spectra** `scale_k S_k(lambda)`, not their coefficients (the
//! sigmoid is not linear in them): for scale-1 texels this is Mitsuba's
//! `BitmapTexture::interpolate_spectral`. Its values then integrate to the bilinear
//! interpolation of the texels' colours, exactly as in RGB mode.
//!
//! Mitsuba's `envmap` instead interpolates the sigmoid values and the scales separately and
//! multiplies the two interpolants (`eval_spectrum`); measured with Mitsuba 3.9.1
//! `scalar_spectral` halfway between texels of rgb (1, 0.5, 0.2) and (10, 10, 10): 3.99998 at
//! 450 nm, equal to the product of interpolants (3.99998) and not to the interpolated products
//! (6.046). The environment map follows that rule (`light.rs`) so references agree.
//!
//! # Display primaries (project extension, issue 5)
//! A monitor emits `L(lambda) = r k_r P_r(lambda) + g k_g P_g(lambda) + b k_b P_b(lambda)`:
//! the texel's linear RGB `(r, g, b)` drives three primary spectra `P_i` (the `.spd` files of
//! `primary_r|g|b`), normalised by weights `k_i` chosen so that `(1, 1, 1)` emits the CIE XYZ
//! of D65 at luminance 1 (`sum_i k_i XYZ(P_i) = XYZ(D65, Y = 1)`, a 3x3 solve; the white an RGB
//! (1, 1, 1) emitter has). Colours other than white and greys take the display's own
//! chromaticities: the image's RGB are the panel's drive values, as on an unmanaged display.
//! In RGB mode the same emission is represented exactly (colorimetrically) by the matrix
//! `rgb -> sum_i k_i rgb_i srgb(P_i)` ([`DisplayPrimaries::to_srgb_matrix`]).

use super::bitmap::{Bitmap, Lookup};
use pt_math::Vec2;
use pt_spectrum::{
    xyz_to_srgb, NamedIlluminant, RgbSigmoid, SampledSpectrum, SampledWavelengths, Spectrum,
};
use rayon::prelude::*;

/// One texel's spectrum, `scale * S(lambda)` (dimensionless reflectance or relative radiance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelSpectrum {
    /// Fitted sigmoid polynomial, values in [0, 1].
    pub sigmoid: RgbSigmoid,
    /// Multiplier (1 for in-gamut reflectances).
    pub scale: f32,
}

impl TexelSpectrum {
    /// Values at the four sampled wavelengths.
    #[inline]
    pub fn eval(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        SampledSpectrum(self.sigmoid.eval4(lambda.lambda()) * self.scale)
    }
}

/// How texels are turned into spectra (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Upsampling {
    /// Mitsuba's `bitmap`: bounded fit for texels <= 1, scaled fit above (pt extension).
    Reflectance,
    /// Mitsuba's `envmap`: fit of `rgb / (2 max)` with scale `2 max` for every texel.
    Emission,
}

/// The fit target and scale of one texel.
fn target(rgb: [f32; 3], form: Upsampling) -> ([f32; 3], f32) {
    let rgb = rgb.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
    let m = rgb[0].max(rgb[1]).max(rgb[2]);
    if form == Upsampling::Reflectance && m <= 1.0 {
        return (rgb, 1.0);
    }
    if !(m > 0.0) {
        return ([0.0; 3], 0.0);
    }
    let scale = 2.0 * m;
    (rgb.map(|v| v / scale), scale)
}

/// Upsamples every texel of a `width`-wide row-major image (load time), in parallel: each
/// texel's coefficients come from the Jakob & Hanika coefficient table
/// ([`pt_spectrum::srgb_to_sigmoid`]: a trilinear lookup, about 0.1-0.3 us per texel, built
/// once per machine by the crate's own fit and cached), so a 2K photograph upsamples in well
/// under a second; colours agree with the texels to about 2e-4 on average and 2e-3 at worst
/// (1e-2 within 0.02 of white; the exact per-colour fit is kept for constants).
pub fn upsample_texels(texels: &[[f32; 3]], width: usize, form: Upsampling) -> Vec<TexelSpectrum> {
    if width == 0 {
        return Vec::new();
    }
    texels
        .par_iter()
        .map(|&t| {
            let (rgb, scale) = target(t, form);
            TexelSpectrum {
                sigmoid: pt_spectrum::srgb_to_sigmoid(rgb),
                scale,
            }
        })
        .collect()
}

/// A bitmap whose texels are spectra (spectral mode): the spectral form of a [`Bitmap`], with
/// the same lookup.
#[derive(Clone, Debug)]
pub struct SpectralBitmap {
    /// How it is looked up (the RGB bitmap's).
    pub lookup: Lookup,
    texels: Vec<TexelSpectrum>,
}

impl SpectralBitmap {
    /// Upsamples an image's texels in the given form.
    pub fn new(bitmap: &Bitmap, form: Upsampling) -> Self {
        SpectralBitmap {
            lookup: bitmap.lookup,
            texels: upsample_texels(&bitmap.texels, bitmap.lookup.width, form),
        }
    }

    /// The spectrum at texture coordinates `uv`, at the path's wavelengths: the bilinear
    /// interpolation of the four nearest texels' spectra (or the nearest texel's), with the
    /// weights of [`Bitmap::eval`].
    #[inline]
    pub fn eval(&self, uv: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        let f = self.lookup.footprint(uv);
        if f.weights[0] == 1.0 {
            return self.texels[f.texels[0]].eval(lambda);
        }
        let t = f.texels.map(|i| self.texels[i].eval(lambda));
        let w = f.weights;
        (t[0] * w[0] + t[1] * w[1]) + (t[2] * w[2] + t[3] * w[3])
    }
}

/// Three primary spectra of a display, normalised so that RGB (1, 1, 1) emits the XYZ of D65 at
/// luminance 1 (see the module docs).
#[derive(Clone, Debug)]
pub struct DisplayPrimaries {
    /// The primaries' spectra as given (relative spectral radiance, per nm).
    spectra: [Spectrum; 3],
    /// Normalisation weights `k_i` (dimensionless, positive).
    weights: [f32; 3],
    /// CIE XYZ of each given primary (`int P cmf / int y-bar`).
    xyz: [[f32; 3]; 3],
}

impl DisplayPrimaries {
    /// Normalises three primaries. Errors (as text) when a primary is negative somewhere, when
    /// they are linearly dependent, or when D65 lies outside their gamut (a weight would be
    /// negative or zero).
    pub fn new(spectra: [Spectrum; 3]) -> Result<Self, String> {
        const NAMES: [&str; 3] = ["primary_r", "primary_g", "primary_b"];
        for (s, name) in spectra.iter().zip(NAMES) {
            // Tabulated data is linear between its nodes: check the nodes; other forms on 1 nm.
            let negative = match s {
                Spectrum::Tabulated(t) => t.samples().1.iter().any(|&v| v < 0.0),
                _ => (360..=830).any(|l| s.eval(l as f32) < 0.0),
            };
            if negative {
                return Err(format!(
                    "{name} has negative values (a spectral radiance cannot be negative)"
                ));
            }
        }
        let xyz = [0, 1, 2].map(|i| spectra[i].emission_xyz());
        let white = Spectrum::illuminant(NamedIlluminant::D65, 1.0).emission_xyz();
        // Solve sum_i k_i xyz_i = white by Cramer's rule in f64 (columns are the primaries).
        let m = glam::DMat3::from_cols_array_2d(&xyz.map(|c| c.map(|v| v as f64)));
        let det = m.determinant();
        let scale = xyz
            .iter()
            .flatten()
            .fold(0.0f64, |a, &v| a.max(v.abs() as f64));
        if !(det.abs() > 1e-9 * scale * scale * scale) {
            return Err(
                "the three primaries are linearly dependent (their colours lie on a line)".into(),
            );
        }
        let k = m.inverse() * glam::DVec3::new(white[0] as f64, white[1] as f64, white[2] as f64);
        if !(k.min_element() > 0.0 && k.is_finite()) {
            return Err(format!("D65 white lies outside the primaries' gamut (weights {:.4}, {:.4}, {:.4}: each must be positive)", k.x, k.y, k.z));
        }
        Ok(DisplayPrimaries {
            spectra,
            weights: [k.x as f32, k.y as f32, k.z as f32],
            xyz,
        })
    }

    /// The normalisation weights `k_r, k_g, k_b`.
    pub fn weights(&self) -> [f32; 3] {
        self.weights
    }

    /// Emitted spectral radiance for drive values `rgb` at the path's wavelengths:
    /// `sum_i rgb_i k_i P_i(lambda)`.
    #[inline]
    pub fn eval(&self, rgb: [f32; 3], lambda: &SampledWavelengths) -> SampledSpectrum {
        let mut out = SampledSpectrum::ZERO;
        for ((&c, s), &k) in rgb.iter().zip(&self.spectra).zip(&self.weights) {
            if c != 0.0 {
                out += s.sample(lambda) * (c * k);
            }
        }
        out
    }

    /// CIE XYZ emitted for drive values `rgb` (exact quadrature; film convention, Y of a
    /// constant 1 is 1).
    pub fn xyz(&self, rgb: [f32; 3]) -> [f32; 3] {
        std::array::from_fn(|c| {
            (0..3)
                .map(|i| rgb[i] * self.weights[i] * self.xyz[i][c])
                .sum()
        })
    }

    /// Linear sRGB matrix (rows: output channel) giving the display's colour for drive values
    /// in RGB mode: `M rgb = xyz_to_srgb(sum_i rgb_i k_i XYZ(P_i))`, exact by linearity.
    pub fn to_srgb_matrix(&self) -> [[f32; 3]; 3] {
        let cols = [0, 1, 2].map(|i| xyz_to_srgb(self.xyz[i].map(|v| v * self.weights[i])));
        [0, 1, 2].map(|r| [cols[0][r], cols[1][r], cols[2][r]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_spectrum::spectrum_to_xyz;

    /// sRGB of a spectrum as a reflectance under D65 (the colour the upsampling inverts), by
    /// quadrature on 1 nm.
    fn reflectance_rgb(f: impl Fn(f32) -> f32) -> [f32; 3] {
        let d65 = Spectrum::illuminant(NamedIlluminant::D65, 1.0);
        let s = Spectrum::tabulated(
            &(360..=830)
                .map(|l| (l as f32, f(l as f32) * d65.eval(l as f32)))
                .collect::<Vec<_>>(),
        )
        .unwrap();
        xyz_to_srgb(s.emission_xyz())
    }

    fn texel_rgb(t: &TexelSpectrum) -> [f32; 3] {
        reflectance_rgb(|l| t.scale * t.sigmoid.eval(l))
    }

    #[test]
    fn texels_round_trip_to_their_rgb() {
        // Each texel's spectrum, seen as a reflectance under D65 (equivalently: times D65 as an
        // emitter), must give back its RGB to the model's accuracy: 1e-3 relative to the
        // texel's largest component (the fit's own round-trip tolerance in pt-spectrum, plus the
        // 1 nm tabulation here). Includes HDR texels (scaled form) and black.
        let texels: Vec<[f32; 3]> = vec![
            [0.8, 0.2, 0.1],
            [0.1, 0.6, 0.3],
            [0.5, 0.5, 0.9],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [0.02, 0.9, 0.98],
            [3.0, 1.0, 0.5],
            [60.0, 50.0, 35.0],
            [0.25, 0.2, 0.15],
        ];
        for form in [Upsampling::Reflectance, Upsampling::Emission] {
            let up = upsample_texels(&texels, 3, form);
            for (rgb, t) in texels.iter().zip(&up) {
                let back = texel_rgb(t);
                let tol = 1e-3 * rgb.iter().cloned().fold(1.0, f32::max);
                assert!(
                    (0..3).all(|c| (back[c] - rgb[c]).abs() <= tol),
                    "{form:?}: {rgb:?} -> {back:?} ({t:?})"
                );
                let m = rgb.iter().cloned().fold(0.0, f32::max);
                match form {
                    Upsampling::Reflectance if m <= 1.0 => {
                        assert_eq!(t.scale, 1.0, "Mitsuba bitmap: in-gamut texels unscaled")
                    }
                    _ => assert_eq!(t.scale, 2.0 * m, "scaled form: 2 max"),
                }
            }
        }
    }

    #[test]
    fn lookup_matches_the_rgb_bitmap() {
        // Greys upsample to exact constants, so the spectral lookup of a grey image must equal
        // the RGB lookup at every uv: this checks that both use the same texels and weights
        // (pixel centres, wrap, nearest). A half-texel shift would fail by up to 0.5 here.
        let dir = std::env::temp_dir().join(format!("pt_spectex_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("grey.png");
        let mut img = image::GrayImage::new(5, 3);
        for (i, p) in img.pixels_mut().enumerate() {
            p.0 = [(i * 53 % 256) as u8];
        }
        img.save(&path).unwrap();
        let lambda = SampledWavelengths::sample_visible(0.3);
        let image =
            super::super::bitmap::Image::load(&pt_scene::ImageSource::File(path.clone()), false)
                .unwrap();
        for (filter, wrap) in [
            (pt_scene::BitmapFilter::Bilinear, pt_scene::WrapMode::Repeat),
            (pt_scene::BitmapFilter::Nearest, pt_scene::WrapMode::Mirror),
            (pt_scene::BitmapFilter::Bilinear, pt_scene::WrapMode::Clamp),
        ] {
            let b = Bitmap {
                lookup: Lookup {
                    width: image.width,
                    height: image.height,
                    filter,
                    wrap,
                    to_uv: [1.3, 0.2, 0.1, -0.1, 0.9, 0.05],
                },
                texels: image.texels.clone(),
            };
            let s = SpectralBitmap::new(&b, Upsampling::Reflectance);
            for k in 0..200 {
                let uv = Vec2::new(
                    -0.3 + 1.7 * ((k * 37 % 200) as f32 / 200.0),
                    -0.2 + 1.5 * (k as f32 / 200.0),
                );
                let rgb = b.eval(uv)[0];
                let v = s.eval(uv, &lambda).0;
                assert!(
                    (v - pt_math::Vec4::splat(rgb)).abs().max_element() < 1e-5,
                    "{filter:?} {wrap:?} {uv}: {v} vs {rgb}"
                );
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn interpolates_spectra_not_coefficients() {
        // Halfway between a red and a blue texel the value is the mean of the two spectra
        // (Mitsuba's interpolate_spectral), which integrates to the mean colour; interpolated
        // coefficients would give another curve.
        let texels = [[0.9f32, 0.1, 0.1], [0.1, 0.1, 0.9]];
        let up = upsample_texels(&texels, 2, Upsampling::Reflectance);
        let b = SpectralBitmap {
            lookup: Lookup {
                width: 2,
                height: 1,
                filter: pt_scene::BitmapFilter::Bilinear,
                wrap: pt_scene::WrapMode::Repeat,
                to_uv: pt_scene::UV_IDENTITY,
            },
            texels: up.clone(),
        };
        for u in [0.1f32, 0.37, 0.8] {
            let lambda = SampledWavelengths::sample_visible(u);
            let mid = b.eval(Vec2::new(0.5, 0.5), &lambda).0;
            let mean = (up[0].eval(&lambda).0 + up[1].eval(&lambda).0) * 0.5;
            assert!((mid - mean).abs().max_element() < 1e-6);
        }
    }

    fn lcd() -> [Spectrum; 3] {
        // Gaussian-like primaries (centre, width in nm), as in scenes/spectra/lcd-*.spd.
        let g = |c: f32, w: f32| {
            Spectrum::tabulated(
                &(360..=830)
                    .map(|l| (l as f32, (-0.5 * ((l as f32 - c) / w).powi(2)).exp()))
                    .collect::<Vec<_>>(),
            )
            .unwrap()
        };
        [g(615.0, 18.0), g(535.0, 16.0), g(455.0, 10.0)]
    }

    #[test]
    fn primaries_emit_d65_for_white_and_are_linear() {
        let d = DisplayPrimaries::new(lcd()).unwrap();
        let white = Spectrum::illuminant(NamedIlluminant::D65, 1.0).emission_xyz();
        let w = d.xyz([1.0; 3]);
        assert!(
            (0..3).all(|c| (w[c] - white[c]).abs() < 1e-5),
            "{w:?} vs {white:?}"
        );
        // RGB-mode matrix: white maps to (1, 1, 1) up to D65's table-vs-matrix white (2e-3).
        let m = d.to_srgb_matrix();
        for r in m {
            assert!((r.iter().sum::<f32>() - 1.0).abs() < 2e-3, "{m:?}");
        }
        // The per-wavelength estimate through the film converges to the quadrature XYZ.
        let rgb = [0.7f32, 0.2, 0.4];
        let n = 20_000;
        let mut acc = [0.0f64; 3];
        for k in 0..n {
            let l = SampledWavelengths::sample_visible((k as f32 + 0.5) / n as f32);
            let xyz = spectrum_to_xyz(d.eval(rgb, &l), &l);
            (0..3).for_each(|c| acc[c] += xyz[c] as f64 / n as f64);
        }
        let exact = d.xyz(rgb);
        assert!(
            (0..3).all(|c| (acc[c] as f32 - exact[c]).abs() < 3e-3 * exact[1]),
            "{acc:?} vs {exact:?}"
        );
        // sRGB-chromaticity primaries would reproduce sRGB; these narrow ones are more saturated:
        // pure red drive gives a red outside the sRGB gamut (negative green or blue).
        let red = xyz_to_srgb(d.xyz([1.0, 0.0, 0.0]));
        assert!(red[0] > 0.0 && (red[1] < 0.0 || red[2] < 0.0), "{red:?}");
    }

    #[test]
    fn bad_primaries_are_rejected() {
        let [r, g, b] = lcd();
        assert!(DisplayPrimaries::new([r.clone(), r.clone(), b.clone()])
            .unwrap_err()
            .contains("linearly dependent"));
        // Without a short-wavelength primary, D65 (which has blue) needs a negative weight.
        let yellow = Spectrum::tabulated(&[(560.0, 0.0), (580.0, 1.0), (600.0, 0.0)]).unwrap();
        assert!(DisplayPrimaries::new([r.clone(), g.clone(), yellow])
            .unwrap_err()
            .contains("gamut"));
        let neg = Spectrum::tabulated(&[(400.0, -0.1), (500.0, 1.0)]).unwrap();
        assert!(DisplayPrimaries::new([r, g, neg])
            .unwrap_err()
            .contains("negative"));
    }
}

#[cfg(test)]
mod timing_probe {
    #[test]
    #[ignore = "slow: load-time cost of upsampling a 256x256 image of distinct noisy colours (prints it)"]
    fn upsample_time_of_a_noisy_image() {
        let (w, h) = (256usize, 256usize);
        let mut s = 1u64;
        let texels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let n = ((s >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 0.1;
                let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
                [
                    (0.2 + 0.6 * x + n).clamp(0.0, 1.0),
                    (0.7 - 0.5 * y + n).clamp(0.0, 1.0),
                    (0.3 + 0.4 * x * y).clamp(0.0, 1.0),
                ]
            })
            .map(|t: [f32; 3]| t.map(|v| (v * 255.0).round() / 255.0))
            .collect();
        let t = std::time::Instant::now();
        let up = super::upsample_texels(&texels, w, super::Upsampling::Reflectance);
        let distinct = texels
            .iter()
            .map(|t| t.map(f32::to_bits))
            .collect::<std::collections::HashSet<_>>()
            .len();
        eprintln!(
            "{} texels ({distinct} distinct colours) in {:.2} s",
            up.len(),
            t.elapsed().as_secs_f64()
        );
    }
}
