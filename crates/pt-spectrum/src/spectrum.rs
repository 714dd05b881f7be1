//! Spectral distributions as functions of wavelength, evaluated at the four sampled wavelengths
//! of a path (spectral mode).
//!
//! | form | constructor | unit | Mitsuba 3 XML |
//! |---|---|---|---|
//! | constant | [`Spectrum::constant`] | as used | `<spectrum name=".." value="0.5"/>` |
//! | piecewise linear | [`Spectrum::tabulated`], [`Spectrum::parse_mitsuba`] | as used | `<spectrum name=".." value="400:0.1, 500:0.5"/>` |
//! | blackbody | [`Spectrum::blackbody`] | W m^-2 sr^-1 nm^-1 | `<spectrum type="blackbody"><float name="temperature" value="5000"/></spectrum>` |
//! | CIE illuminant | [`Spectrum::illuminant`] | radiance per nm, Y = scale | `<spectrum type="d65"/>` (A, F1-F12: project extension) |
//! | RGB albedo | [`Spectrum::rgb_albedo`] | reflectance in [0, 1] | `<rgb name="reflectance" value=".."/>` |
//! | RGB unbounded | [`Spectrum::rgb_unbounded`] | >= 0 | `<rgb>` for unbounded parameters |
//! | RGB illuminant | [`Spectrum::rgb_illuminant`] | radiance per nm | `<rgb name="radiance" value=".."/>` in an emitter |
//!
//! Conventions, checked against Mitsuba 3's sources (`src/spectra/*.cpp`,
//! `include/mitsuba/core/distr_1d.h`, `spectrum.h`):
//! - A piecewise-linear spectrum is **zero outside its first and last wavelength**: Mitsuba's
//!   `regular` and `irregular` spectra (which `value="l:v, .."` becomes) evaluate their
//!   distribution's `eval_pdf`, which masks wavelengths outside the node range to 0. pbrt-v4's
//!   `PiecewiseLinearSpectrum` does the same. Holding the end values instead is available as
//!   [`Outside::Clamp`] for data that should extend flat.
//! - Blackbody: Planck's law in W m^-2 sr^-1 nm^-1 with **no normalisation**, zero outside
//!   360-830 nm, with the constants of Mitsuba 3's `blackbody` plugin (CODATA 2014 h, c, k), so
//!   scenes must be in metres for the radiance to be physical (Mitsuba's note). pbrt-v4
//!   normalises its blackbody to a peak of 1 instead; this crate follows Mitsuba.
//! - Named illuminants and the RGB illuminant form are normalised so that `scale` is their
//!   luminance Y under the film's convention ([`spectrum_to_xyz`](crate::spectrum_to_xyz)):
//!   Mitsuba's `d65` plugin normalises D65 the same way, so `rgb_illuminant([1, 1, 1])` and
//!   `illuminant(D65, 1)` both render as sRGB (1, 1, 1) (to 1e-3).
use crate::cie;
use crate::rgb2spec::RgbSigmoid;
use crate::{SampledSpectrum, SampledWavelengths};
use glam::Vec4;
use std::fmt;

/// What a piecewise-linear spectrum returns outside its tabulated range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Outside {
    /// Zero (Mitsuba 3 `regular`/`irregular`, pbrt-v4 `PiecewiseLinearSpectrum`).
    #[default]
    Zero,
    /// The first value below the range and the last value above it.
    Clamp,
}

/// A spectrum tabulated at increasing wavelengths (nm), linear in between.
#[derive(Clone, Debug, PartialEq)]
pub struct Tabulated {
    lambda: Vec<f32>,
    value: Vec<f32>,
    outside: Outside,
}

impl Tabulated {
    /// Value at `lambda` nm.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn eval(&self, lambda: f32) -> f32 {
        let (l, v) = (&self.lambda, &self.value);
        let n = l.len();
        if !(lambda >= l[0] && lambda <= l[n - 1]) {
            return match self.outside {
                Outside::Zero => 0.0,
                Outside::Clamp if lambda < l[0] => v[0],
                Outside::Clamp if lambda > l[n - 1] => v[n - 1],
                Outside::Clamp => 0.0, // NaN
            };
        }
        // First node strictly greater than lambda, minus one: the interval [i, i + 1].
        let i = l.partition_point(|&x| x <= lambda).clamp(1, n - 1) - 1;
        let t = (lambda - l[i]) / (l[i + 1] - l[i]);
        v[i] + t * (v[i + 1] - v[i])
    }

    /// The wavelengths (nm) and values.
    pub fn samples(&self) -> (&[f32], &[f32]) {
        (&self.lambda, &self.value)
    }

    /// Integral over the tabulated range (trapezoid, exact for the linear interpolant), in
    /// value x nm. Divide by it to normalise an emission spectrum to unit area per nm
    /// (DESIGN.md, fluorescence).
    pub fn integral(&self) -> f64 {
        let (l, v) = (&self.lambda, &self.value);
        (0..l.len() - 1)
            .map(|i| 0.5 * (l[i + 1] - l[i]) as f64 * (v[i] + v[i + 1]) as f64)
            .sum()
    }

    /// Sample a wavelength (nm) proportionally to the (non-negative) interpolant over its
    /// range, by inverting its piecewise-quadratic CDF; returns the wavelength and its pdf per
    /// nm, or `None` if the integral is not positive. For fluorescence re-emission. O(n).
    pub fn sample(&self, u: f32) -> Option<(f32, f32)> {
        let (l, v) = (&self.lambda, &self.value);
        let total = self.integral();
        if total.is_nan() || total <= 0.0 || v.iter().any(|&x| x < 0.0) {
            return None;
        }
        let target = (u as f64).clamp(0.0, 1.0) * total;
        let mut acc = 0.0;
        let n = l.len();
        for i in 0..n - 1 {
            let (x0, x1) = (l[i] as f64, l[i + 1] as f64);
            let (y0, y1) = (v[i] as f64, v[i + 1] as f64);
            let w = x1 - x0;
            let area = 0.5 * w * (y0 + y1);
            if target <= acc + area && area > 0.0 || i == n - 2 {
                // Solve y0 t + (y1 - y0) t^2 / 2 = r / w for t in [0, 1].
                let r = ((target - acc) / w).max(0.0);
                let t = if (y1 - y0).abs() < 1e-12 * (y0 + y1) {
                    r / y0
                } else {
                    (-y0 + (y0 * y0 + 2.0 * (y1 - y0) * r).max(0.0).sqrt()) / (y1 - y0)
                };
                let t = t.clamp(0.0, 1.0);
                let lambda = x0 + t * w;
                let pdf = (y0 + t * (y1 - y0)) / total;
                return Some((lambda as f32, pdf as f32));
            }
            acc += area;
        }
        None
    }
}

/// The CIE illuminants available by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NamedIlluminant {
    /// CIE standard illuminant D65 (average daylight, 6504 K), 360-830 nm.
    D65,
    /// CIE standard illuminant A (incandescent tungsten, 2856 K), from its defining formula.
    A,
    /// CIE fluorescent illuminant F1..F12 (the field is 1..=12), 380-780 nm, zero outside.
    F(u8),
}

impl NamedIlluminant {
    /// Parse `d65`, `a`, `f1` .. `f12` (case-insensitive).
    pub fn from_name(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_lowercase();
        match n.as_str() {
            "d65" => Some(Self::D65),
            "a" => Some(Self::A),
            _ => {
                let k: u8 = n.strip_prefix('f')?.parse().ok()?;
                (1..=12).contains(&k).then_some(Self::F(k))
            }
        }
    }

    /// Relative spectral power as tabulated by the CIE (100 at 560 nm for D65 and A) at `lambda` nm.
    pub fn relative_spd(self, lambda: f32) -> f32 {
        match self {
            Self::D65 => cie::d65(lambda),
            Self::A if (cie::LAMBDA_MIN..=cie::LAMBDA_MAX).contains(&lambda) => {
                cie::illuminant_a(lambda)
            }
            Self::A => 0.0,
            Self::F(k) => cie::illuminant_f(k as usize, lambda),
        }
    }

    /// Factor that gives [`relative_spd`](Self::relative_spd) the luminance Y = 1 under the film's
    /// convention: `int y-bar / int S y-bar` over 360-830 nm.
    pub fn unit_luminance_factor(self) -> f32 {
        let y =
            cie::integrate_visible(|l| (self.relative_spd(l as f32) * cie::cmf_y(l as f32)) as f64);
        (cie::CIE_Y_INTEGRAL as f64 / y) as f32
    }
}

/// Error from building a spectrum.
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumError {
    /// Fewer than two `wavelength:value` pairs.
    TooFewSamples,
    /// Wavelengths not strictly increasing (the offending wavelength, nm).
    NotIncreasing(f32),
    /// A non-finite wavelength or value.
    NotFinite,
    /// A token that is neither a number nor a `wavelength:value` pair.
    Parse(String),
    /// A temperature that is not positive and finite (K).
    BadTemperature(f32),
}

impl fmt::Display for SpectrumError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooFewSamples => write!(
                f,
                "a tabulated spectrum needs at least two wavelength:value pairs"
            ),
            Self::NotIncreasing(l) => {
                write!(f, "wavelengths must be strictly increasing (at {l} nm)")
            }
            Self::NotFinite => write!(f, "spectrum wavelengths and values must be finite"),
            Self::Parse(t) => write!(
                f,
                "invalid spectrum value \"{t}\" (expected a number or wavelength:value pairs)"
            ),
            Self::BadTemperature(t) => {
                write!(f, "blackbody temperature must be positive, got {t} K")
            }
        }
    }
}

impl std::error::Error for SpectrumError {}

/// Planck's law: spectral radiance of a blackbody at `temperature` K, W m^-2 sr^-1 nm^-1, at
/// `lambda` nm (all wavelengths, no range mask). Constants as in Mitsuba 3's `blackbody`.
#[inline]
pub fn planck(lambda: f32, temperature: f32) -> f32 {
    const C: f64 = 2.997_924_58e8; // speed of light, m/s
    const H: f64 = 6.626_070_04e-34; // Planck constant, J s
    const K: f64 = 1.380_648_52e-23; // Boltzmann constant, J/K
    let l = lambda as f64 * 1e-9;
    let t = temperature as f64;
    if !(l > 0.0 && t > 0.0) {
        return 0.0;
    }
    // 2 h c^2 / l^5 / (exp(h c / (l k T)) - 1), per metre of wavelength; 1e-9 converts to per nm.
    (1e-9 * 2.0 * H * C * C / (l.powi(5) * (H * C / (l * K * t)).exp_m1())) as f32
}

/// A spectral distribution, evaluated per wavelength. Built at scene load; cheap to evaluate.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength.
    Constant(f32),
    /// Piecewise linear between tabulated wavelengths.
    Tabulated(Tabulated),
    /// Planck radiance (W m^-2 sr^-1 nm^-1) times `scale`, zero outside 360-830 nm.
    Blackbody {
        /// Temperature, K.
        temperature: f32,
        /// Dimensionless multiplier.
        scale: f32,
    },
    /// A CIE illuminant scaled to luminance `scale` (see [`NamedIlluminant::unit_luminance_factor`]).
    Illuminant {
        /// Which illuminant.
        which: NamedIlluminant,
        /// Luminance Y under the film's convention.
        scale: f32,
        /// `scale` times the unit-luminance factor (precomputed).
        factor: f32,
    },
    /// Reflectance in [0, 1] upsampled from linear sRGB (Jakob and Hanika 2019).
    RgbAlbedo {
        /// Fitted sigmoid polynomial.
        sigmoid: RgbSigmoid,
        /// The linear sRGB it was fitted to (RGB mode uses this directly).
        rgb: [f32; 3],
    },
    /// Non-negative, unbounded: `scale * sigmoid(l)` with `scale = 2 max(rgb)` (pbrt-v4
    /// `RGBUnboundedSpectrum`, Mitsuba's `srgb` with `unbounded`).
    RgbUnbounded {
        /// Fitted sigmoid polynomial (of `rgb / scale`).
        sigmoid: RgbSigmoid,
        /// `2 max(rgb)`.
        scale: f32,
        /// The linear sRGB it was built from.
        rgb: [f32; 3],
    },
    /// Emission: `scale * sigmoid(l) * D65(l)`, D65 normalised to Y = 1 (pbrt-v4
    /// `RGBIlluminantSpectrum`, Mitsuba's `srgb_d65`), radiance per nm.
    RgbIlluminant {
        /// Fitted sigmoid polynomial (of `rgb / scale`).
        sigmoid: RgbSigmoid,
        /// `2 max(rgb)` times the D65 unit-luminance factor.
        factor: f32,
        /// The linear sRGB radiance it was built from.
        rgb: [f32; 3],
    },
}

impl Spectrum {
    /// A constant spectrum.
    pub fn constant(v: f32) -> Self {
        Spectrum::Constant(v)
    }

    /// Piecewise linear through `(wavelength nm, value)` pairs with strictly increasing
    /// wavelengths; zero outside, as Mitsuba 3.
    pub fn tabulated(pairs: &[(f32, f32)]) -> Result<Self, SpectrumError> {
        Self::tabulated_with(pairs, Outside::Zero)
    }

    /// [`tabulated`](Self::tabulated) with a choice of behaviour outside the range.
    pub fn tabulated_with(pairs: &[(f32, f32)], outside: Outside) -> Result<Self, SpectrumError> {
        if pairs.len() < 2 {
            return Err(SpectrumError::TooFewSamples);
        }
        if pairs.iter().any(|&(l, v)| !l.is_finite() || !v.is_finite()) {
            return Err(SpectrumError::NotFinite);
        }
        if let Some(w) = pairs.windows(2).find(|w| w[1].0 <= w[0].0) {
            return Err(SpectrumError::NotIncreasing(w[1].0));
        }
        Ok(Spectrum::Tabulated(Tabulated {
            lambda: pairs.iter().map(|p| p.0).collect(),
            value: pairs.iter().map(|p| p.1).collect(),
            outside,
        }))
    }

    /// Parse a Mitsuba `<spectrum value=".."/>` attribute: one number (constant) or
    /// `wavelength:value` pairs separated by commas and/or whitespace.
    pub fn parse_mitsuba(value: &str) -> Result<Self, SpectrumError> {
        let tokens: Vec<&str> = value
            .split([',', ' ', '\t', '\n', '\r'])
            .filter(|t| !t.is_empty())
            .collect();
        let num = |s: &str| {
            s.parse::<f32>()
                .map_err(|_| SpectrumError::Parse(s.to_string()))
        };
        if tokens.len() == 1 && !tokens[0].contains(':') {
            return Ok(Spectrum::Constant(num(tokens[0])?));
        }
        let pairs = tokens
            .iter()
            .map(|t| match t.split_once(':') {
                Some((l, v)) => Ok((num(l)?, num(v)?)),
                None => Err(SpectrumError::Parse(t.to_string())),
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::tabulated(&pairs)
    }

    /// Blackbody radiance at `temperature` K (W m^-2 sr^-1 nm^-1, unnormalised, as Mitsuba 3).
    pub fn blackbody(temperature: f32) -> Result<Self, SpectrumError> {
        if !(temperature > 0.0 && temperature.is_finite()) {
            return Err(SpectrumError::BadTemperature(temperature));
        }
        Ok(Spectrum::Blackbody {
            temperature,
            scale: 1.0,
        })
    }

    /// A CIE illuminant with luminance `scale` (Y = scale under the film's convention).
    pub fn illuminant(which: NamedIlluminant, scale: f32) -> Self {
        Spectrum::Illuminant {
            which,
            scale,
            factor: scale * which.unit_luminance_factor(),
        }
    }

    /// Reflectance from linear sRGB in [0, 1] (clamped), fitted at construction.
    pub fn rgb_albedo(rgb: [f32; 3]) -> Self {
        Spectrum::RgbAlbedo {
            sigmoid: RgbSigmoid::fit(rgb),
            rgb,
        }
    }

    /// Unbounded non-negative spectrum from linear sRGB (negative components clamped to 0).
    pub fn rgb_unbounded(rgb: [f32; 3]) -> Self {
        let (sigmoid, scale) = scaled_fit(rgb);
        Spectrum::RgbUnbounded {
            sigmoid,
            scale,
            rgb,
        }
    }

    /// Emitted radiance from linear sRGB: upsampled colour times D65 (DESIGN.md), with
    /// luminance equal to that of `rgb` (an sRGB (1, 1, 1) emitter renders as (1, 1, 1)).
    pub fn rgb_illuminant(rgb: [f32; 3]) -> Self {
        let (sigmoid, scale) = scaled_fit(rgb);
        let factor = scale * NamedIlluminant::D65.unit_luminance_factor();
        Spectrum::RgbIlluminant {
            sigmoid,
            factor,
            rgb,
        }
    }

    /// Value at one wavelength, nm.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn eval(&self, lambda: f32) -> f32 {
        match self {
            Spectrum::Constant(v) => *v,
            Spectrum::Tabulated(t) => t.eval(lambda),
            Spectrum::Blackbody { temperature, scale } => {
                if (cie::LAMBDA_MIN..=cie::LAMBDA_MAX).contains(&lambda) {
                    scale * planck(lambda, *temperature)
                } else {
                    0.0
                }
            }
            Spectrum::Illuminant { which, factor, .. } => factor * which.relative_spd(lambda),
            Spectrum::RgbAlbedo { sigmoid, .. } => sigmoid.eval(lambda),
            Spectrum::RgbUnbounded { sigmoid, scale, .. } => scale * sigmoid.eval(lambda),
            Spectrum::RgbIlluminant {
                sigmoid, factor, ..
            } => factor * sigmoid.eval(lambda) * cie::d65(lambda),
        }
    }

    /// Values at the four sampled wavelengths (spectral mode).
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sample(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        let l = lambda.lambda();
        SampledSpectrum(match self {
            Spectrum::Constant(v) => Vec4::splat(*v),
            Spectrum::RgbAlbedo { sigmoid, .. } => sigmoid.eval4(l),
            Spectrum::RgbUnbounded { sigmoid, scale, .. } => sigmoid.eval4(l) * *scale,
            _ => Vec4::from_array(l.to_array().map(|x| self.eval(x))),
        })
    }

    /// CIE XYZ of this spectrum as emitted radiance, `int S cmf / int y-bar` (the film's
    /// convention: a constant 1 has Y = 1). Exact quadrature; for load time and tests.
    ///
    /// `xyz_to_srgb(s.emission_xyz())` is close to the RGB-mode value Mitsuba gives a tabulated
    /// *emission* (see [`crate::mitsuba_points_to_srgb`], which also does reflectances: those
    /// are weighted by D65 there).
    pub fn emission_xyz(&self) -> [f32; 3] {
        [0, 1, 2].map(|c| {
            (cie::integrate_visible(|l| (self.eval(l as f32) * cie::cmf(l as f32)[c]) as f64)
                / cie::CIE_Y_INTEGRAL as f64) as f32
        })
    }

    /// CIE XYZ of this spectrum as a reflectance lit by D65, normalised so that a white
    /// reflector has Y = 1 (the colorimetry the RGB upsampling inverts).
    pub fn reflectance_xyz_d65(&self) -> [f32; 3] {
        let norm = cie::integrate_visible(|l| (cie::d65(l as f32) * cie::cmf_y(l as f32)) as f64);
        [0, 1, 2].map(|c| {
            (cie::integrate_visible(|l| {
                let l = l as f32;
                (self.eval(l) * cie::d65(l) * cie::cmf(l)[c]) as f64
            }) / norm) as f32
        })
    }
}

/// Fit of `rgb / (2 max(rgb))` and the scale `2 max(rgb)` (pbrt-v4's unbounded/illuminant forms):
/// the fitted reflectance has components <= 1/2, far from the unreachable boundary.
fn scaled_fit(rgb: [f32; 3]) -> (RgbSigmoid, f32) {
    let rgb = rgb.map(|v| if v.is_nan() { 0.0 } else { v.max(0.0) });
    let m = rgb[0].max(rgb[1]).max(rgb[2]);
    let scale = 2.0 * m;
    let sig = if scale > 0.0 {
        RgbSigmoid::fit(rgb.map(|v| v / scale))
    } else {
        RgbSigmoid::constant(0.0)
    };
    (sig, scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{spectrum_to_xyz, xyz_to_srgb};

    fn close3(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
    }

    #[test]
    fn tabulated_interpolates_and_is_zero_outside() {
        let s = Spectrum::parse_mitsuba("400:0.1, 500:0.5 600:0.3").unwrap();
        assert!((s.eval(450.0) - 0.3).abs() < 1e-6);
        assert_eq!(s.eval(400.0), 0.1);
        assert_eq!(s.eval(600.0), 0.3);
        assert!((s.eval(550.0) - 0.4).abs() < 1e-6);
        assert_eq!(s.eval(399.9), 0.0);
        assert_eq!(s.eval(600.1), 0.0);
        let c = Spectrum::tabulated_with(&[(400.0, 0.1), (500.0, 0.5)], Outside::Clamp).unwrap();
        assert_eq!(c.eval(380.0), 0.1);
        assert_eq!(c.eval(700.0), 0.5);
        assert_eq!(
            Spectrum::parse_mitsuba(" 0.25 ").unwrap(),
            Spectrum::Constant(0.25)
        );
        assert_eq!(
            Spectrum::parse_mitsuba("400:0.5"),
            Err(SpectrumError::TooFewSamples)
        );
        assert_eq!(
            Spectrum::parse_mitsuba("500:0.5, 400:0.1"),
            Err(SpectrumError::NotIncreasing(400.0))
        );
        assert!(matches!(
            Spectrum::parse_mitsuba("foo bar"),
            Err(SpectrumError::Parse(_))
        ));
    }

    #[test]
    fn tabulated_sampling_follows_the_interpolant() {
        let Spectrum::Tabulated(t) = Spectrum::parse_mitsuba("450:0, 500:2, 550:1, 600:1").unwrap()
        else {
            unreachable!()
        };
        assert!((t.integral() - (50.0 + 75.0 + 50.0)).abs() < 1e-9);
        // Quantiles: CDF(500) = 50/175, CDF(550) = 125/175.
        let (l, p) = t.sample(50.0 / 175.0).unwrap();
        assert!(
            (l - 500.0).abs() < 1e-3 && (p - 2.0 / 175.0).abs() < 1e-6,
            "{l} {p}"
        );
        assert!((t.sample(125.0 / 175.0).unwrap().0 - 550.0).abs() < 1e-3);
        assert!((t.sample(0.0).unwrap().0 - 450.0).abs() < 1e-3);
        assert!((t.sample(1.0).unwrap().0 - 600.0).abs() < 1e-3);
        // Histogram against the normalised interpolant.
        let n = 100_000;
        let mut hist = [0.0f64; 15];
        for k in 0..n {
            let (l, p) = t.sample((k as f32 + 0.5) / n as f32).unwrap();
            assert!((p - t.eval(l) / 175.0).abs() < 1e-5);
            hist[(((l - 450.0) / 10.0) as usize).min(14)] += 1.0 / n as f64;
        }
        for (i, h) in hist.iter().enumerate() {
            let lo = 450.0 + 10.0 * i as f32;
            let expect = (0..100)
                .map(|j| t.eval(lo + 0.1 * (j as f32 + 0.5)) as f64 * 0.1)
                .sum::<f64>()
                / 175.0;
            assert!((h - expect).abs() < 1e-3, "bin {i}: {h} vs {expect}");
        }
        let Spectrum::Tabulated(z) = Spectrum::parse_mitsuba("400:0, 500:0").unwrap() else {
            unreachable!()
        };
        assert_eq!(z.sample(0.5), None);
    }

    #[test]
    fn sample_matches_eval() {
        let w = SampledWavelengths::sample_visible(0.37);
        for s in [
            Spectrum::constant(0.7),
            Spectrum::parse_mitsuba("400:0.1, 500:0.5, 700:0.2").unwrap(),
            Spectrum::blackbody(3000.0).unwrap(),
            Spectrum::illuminant(NamedIlluminant::F(11), 2.0),
            Spectrum::rgb_albedo([0.2, 0.5, 0.8]),
            Spectrum::rgb_unbounded([2.0, 0.5, 0.1]),
            Spectrum::rgb_illuminant([3.0, 2.0, 1.0]),
        ] {
            let v = s.sample(&w).0.to_array();
            for (i, (v, l)) in v.into_iter().zip(w.lambda().to_array()).enumerate() {
                let e = s.eval(l);
                assert!((v - e).abs() <= 1e-6 * e.abs().max(1.0), "{s:?} lane {i}");
            }
        }
    }

    #[test]
    fn planck_values() {
        // Spectral radiance at 500 nm, 5000 K: 2hc^2/l^5/(exp(hc/lkT)-1) = 1.2106e13 W m^-3 sr^-1.
        let v = planck(500.0, 5000.0);
        assert!((v / 1.2106e4 - 1.0).abs() < 1e-3, "{v}");
        // Wien's displacement law: peak at 2.8978e6 nm K / T.
        let t = 5000.0;
        let peak = 2.897_77e6 / t;
        assert!(planck(peak, t) > planck(peak - 5.0, t) && planck(peak, t) > planck(peak + 5.0, t));
        let bb = Spectrum::blackbody(5000.0).unwrap();
        assert_eq!(bb.eval(359.0), 0.0);
        assert_eq!(bb.eval(500.0), v);
        assert!(Spectrum::blackbody(0.0).is_err());
        // Illuminant A is Planck at 2848 K with c2 = 1.435e-2 m K: compare shapes at ~2856 K on
        // ITS-90 (c2 = 1.4388e-2): ratios agree to < 1e-3.
        let ta = 2848.0 * 1.438_777 / 1.435;
        for l in [400.0f32, 500.0, 700.0] {
            let r = planck(l, ta) / planck(560.0, ta) * 100.0;
            assert!((r / cie::illuminant_a(l) - 1.0).abs() < 1e-3, "{l}: {r}");
        }
    }

    #[test]
    fn named_illuminants() {
        assert_eq!(
            NamedIlluminant::from_name("D65"),
            Some(NamedIlluminant::D65)
        );
        assert_eq!(NamedIlluminant::from_name("a"), Some(NamedIlluminant::A));
        assert_eq!(
            NamedIlluminant::from_name("F12"),
            Some(NamedIlluminant::F(12))
        );
        assert_eq!(NamedIlluminant::from_name("f13"), None);
        assert_eq!(NamedIlluminant::from_name("x"), None);
        for which in [
            NamedIlluminant::D65,
            NamedIlluminant::A,
            NamedIlluminant::F(2),
            NamedIlluminant::F(11),
        ] {
            let y = Spectrum::illuminant(which, 3.0).emission_xyz()[1];
            assert!((y - 3.0).abs() < 1e-4, "{which:?}: {y}");
        }
    }

    #[test]
    fn d65_and_blackbody_match_mitsuba() {
        // Values printed by Mitsuba 3.9.1 (scalar_spectral): `d65` evaluates to 1.01013 at
        // 560 nm, and `blackbody` at 5000 K to 8743.57, 12107.2, 12762.4, 11812 at 400, 500,
        // 600, 700 nm (no normalisation). Our D65 is scaled to Y = 1 exactly under the 1 nm
        // CIE tables, Mitsuba's by a constant for its 5 nm table: the two differ by 0.11%
        // (measured), hence 0.2% for D65; 0.1% covers float32 in Planck's law. Another
        // normalisation (peak 1, or per 100 at 560 nm) is off by orders of magnitude.
        let d65 = Spectrum::illuminant(NamedIlluminant::D65, 1.0).eval(560.0);
        assert!((d65 / 1.01013 - 1.0).abs() < 2e-3, "{d65}");
        let bb = Spectrum::blackbody(5000.0).unwrap();
        for (l, v) in [
            (400.0, 8743.57),
            (500.0, 12107.2),
            (600.0, 12762.4),
            (700.0, 11812.0),
        ] {
            assert!((bb.eval(l) / v - 1.0).abs() < 1e-3, "{l}: {}", bb.eval(l));
        }
    }

    #[test]
    fn d65_is_white_and_a_is_warm() {
        let d65 = xyz_to_srgb(Spectrum::illuminant(NamedIlluminant::D65, 1.0).emission_xyz());
        assert!(close3(d65, [1.0; 3], 2e-3), "{d65:?}");
        let a = xyz_to_srgb(Spectrum::illuminant(NamedIlluminant::A, 1.0).emission_xyz());
        assert!(a[0] > a[1] && a[1] > a[2] && a[2] > 0.0, "{a:?}");
        // Chromaticity of A: (0.44757, 0.40745).
        let xyz = Spectrum::illuminant(NamedIlluminant::A, 1.0).emission_xyz();
        let s = xyz[0] + xyz[1] + xyz[2];
        assert!((xyz[0] / s - 0.44757).abs() < 2e-4 && (xyz[1] / s - 0.40745).abs() < 2e-4);
    }

    #[test]
    fn film_estimate_of_d65_converges_to_white() {
        let s = Spectrum::illuminant(NamedIlluminant::D65, 1.0);
        let n = 50_000;
        let mut acc = [0.0f64; 3];
        for k in 0..n {
            let w = SampledWavelengths::sample_visible((k as f32 + 0.5) / n as f32);
            let xyz = spectrum_to_xyz(s.sample(&w), &w);
            (0..3).for_each(|c| acc[c] += xyz[c] as f64 / n as f64);
        }
        let rgb = xyz_to_srgb(acc.map(|v| v as f32));
        assert!(close3(rgb, [1.0; 3], 3e-3), "{rgb:?}");
    }

    #[test]
    fn rgb_forms_round_trip() {
        // Albedo: reflectance under D65.
        for rgb in [[0.8f32, 0.2, 0.1], [0.1, 0.6, 0.3], [0.5, 0.5, 0.9]] {
            let back = xyz_to_srgb(Spectrum::rgb_albedo(rgb).reflectance_xyz_d65());
            assert!(close3(back, rgb, 1e-3), "{rgb:?} -> {back:?}");
        }
        // Illuminant: emitted radiance through the film's convention.
        for rgb in [[1.0f32, 1.0, 1.0], [5.0, 2.0, 0.5], [0.0, 0.3, 1.5]] {
            let back = xyz_to_srgb(Spectrum::rgb_illuminant(rgb).emission_xyz());
            let tol = 1e-3 * rgb.iter().cloned().fold(1.0, f32::max);
            assert!(close3(back, rgb, tol), "{rgb:?} -> {back:?}");
        }
        // Unbounded: white 1 is the constant 1, and values above 1 are reachable.
        let u = Spectrum::rgb_unbounded([1.0; 3]);
        assert!((u.eval(400.0) - 1.0).abs() < 1e-6 && (u.eval(700.0) - 1.0).abs() < 1e-6);
        let u = Spectrum::rgb_unbounded([3.0, 1.0, 0.5]);
        let back = xyz_to_srgb(u.reflectance_xyz_d65());
        assert!(close3(back, [3.0, 1.0, 0.5], 3e-3), "{back:?}");
        assert_eq!(Spectrum::rgb_illuminant([0.0; 3]).eval(500.0), 0.0);
        assert_eq!(
            Spectrum::rgb_albedo([1.0; 3]),
            Spectrum::RgbAlbedo {
                sigmoid: RgbSigmoid::constant(1.0),
                rgb: [1.0; 3]
            }
        );
    }
}
