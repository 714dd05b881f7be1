//! Spectral quantities carried along a path.
//!
//! The integrator is written once over [`SampledSpectrum`], four lanes of radiance or
//! throughput. What a lane means depends on the [`ColorMode`], chosen per scene:
//! - [`ColorMode::Rgb`]: lanes 0..3 are linear Rec.709 R, G, B; lane 3 is unused and kept at 0.
//! - [`ColorMode::Spectral`]: four wavelengths per path (hero wavelength sampling). Not implemented
//!   yet: scenes that need it are rejected at load time.
//!
//! Mode branches live only in spectrum evaluation, wavelength sampling and the film (DESIGN.md).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

use glam::Vec4;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign};

/// How colour is transported for a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ColorMode {
    /// Linear Rec.709 RGB, three lanes. Exact for scenes whose inputs are all RGB and whose
    /// materials do not depend on wavelength.
    #[default]
    Rgb,
    /// Spectral transport with four wavelengths per path.
    Spectral,
}

impl ColorMode {
    /// The name used on the command line and in EXR headers (`rgb`, `spectral`).
    pub fn name(self) -> &'static str {
        match self {
            ColorMode::Rgb => "rgb",
            ColorMode::Spectral => "spectral",
        }
    }
}

/// Four lanes of a spectral quantity (radiance in W sr^-1 m^-2, or a dimensionless throughput).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct SampledSpectrum(pub Vec4);

impl SampledSpectrum {
    /// All lanes zero.
    pub const ZERO: Self = SampledSpectrum(Vec4::ZERO);

    /// Every lane set to `v`. In RGB mode use [`SampledSpectrum::from_rgb`] for a grey, so the
    /// unused fourth lane stays 0.
    #[inline]
    pub fn splat(v: f32) -> Self {
        SampledSpectrum(Vec4::splat(v))
    }

    /// An RGB-mode value: lanes (r, g, b, 0).
    #[inline]
    pub fn from_rgb(rgb: [f32; 3]) -> Self {
        SampledSpectrum(Vec4::new(rgb[0], rgb[1], rgb[2], 0.0))
    }

    /// The first three lanes (RGB mode).
    #[inline]
    pub fn rgb(self) -> [f32; 3] {
        [self.0.x, self.0.y, self.0.z]
    }

    /// Largest lane (used by Russian roulette).
    #[inline]
    pub fn max_value(self) -> f32 {
        self.0.max_element()
    }

    /// Whether every lane is exactly zero.
    #[inline]
    pub fn is_black(self) -> bool {
        self.0 == Vec4::ZERO
    }

    /// Whether every lane is finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.0.is_finite()
    }

    /// Rec.709 luminance of the RGB lanes (Y of linear sRGB, ITU-R BT.709 coefficients).
    #[inline]
    pub fn luminance_rgb(self) -> f32 {
        0.212_671 * self.0.x + 0.715_160 * self.0.y + 0.072_169 * self.0.z
    }
}

impl Add for SampledSpectrum {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        SampledSpectrum(self.0 + o.0)
    }
}
impl AddAssign for SampledSpectrum {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.0 += o.0;
    }
}
impl Mul for SampledSpectrum {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        SampledSpectrum(self.0 * o.0)
    }
}
impl MulAssign for SampledSpectrum {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        self.0 *= o.0;
    }
}
impl Mul<f32> for SampledSpectrum {
    type Output = Self;
    #[inline]
    fn mul(self, s: f32) -> Self {
        SampledSpectrum(self.0 * s)
    }
}
impl MulAssign<f32> for SampledSpectrum {
    #[inline]
    fn mul_assign(&mut self, s: f32) {
        self.0 *= s;
    }
}
impl Div<f32> for SampledSpectrum {
    type Output = Self;
    #[inline]
    fn div(self, s: f32) -> Self {
        SampledSpectrum(self.0 / s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_lane_layout() {
        let s = SampledSpectrum::from_rgb([1.0, 2.0, 3.0]);
        assert_eq!(s.rgb(), [1.0, 2.0, 3.0]);
        assert_eq!(s.0.w, 0.0);
        assert_eq!((s * 2.0).rgb(), [2.0, 4.0, 6.0]);
        assert_eq!(s.max_value(), 3.0);
        // Luminance of white is 1 (the BT.709 Y coefficients sum to 1).
        assert!((SampledSpectrum::from_rgb([1.0; 3]).luminance_rgb() - 1.0).abs() < 1e-5);
    }
}
