//! From sampled radiance to CIE XYZ (the film's Monte Carlo estimate) and XYZ <-> linear sRGB.
//!
//! Convention (Mitsuba 3 `spectrum_to_xyz`): `X = (1 / int y-bar) * int L(l) x-bar(l) dl` over
//! 360-830 nm, and likewise Y and Z, so a constant spectral radiance of 1 (per nm) has Y = 1.
//! The estimate from one set of four sampled wavelengths is
//! `X ~ (1/4) sum_i L(l_i) x-bar(l_i) / p(l_i) / int y-bar`; lanes with `p = 0` (terminated by
//! [`SampledWavelengths::terminate_secondary`]) contribute nothing.
use crate::cie::{self, CIE_Y_INTEGRAL};
use crate::{SampledSpectrum, SampledWavelengths};
use glam::{Mat3, Vec3, Vec4};

/// XYZ to linear Rec.709 / sRGB (D65 white), the matrix Mitsuba 3 uses (`xyz_to_srgb`), so
/// spectral renders compare with `scalar_spectral` references without a matrix difference.
#[allow(clippy::excessive_precision)] // Mitsuba's digits, kept verbatim.
pub const XYZ_TO_SRGB: Mat3 = Mat3::from_cols_array(&[
    // Column-major: the rows of the usual matrix are read down the columns here.
    3.240479, -0.969256, 0.055648, //
    -1.537150, 1.875991, -0.204043, //
    -0.498535, 0.041556, 1.057311,
]);

/// Linear Rec.709 / sRGB (D65 white) to XYZ, Mitsuba 3's `srgb_to_xyz`. Its middle row is the
/// BT.709 luminance used by [`SampledSpectrum::luminance_rgb`].
pub const SRGB_TO_XYZ: Mat3 = Mat3::from_cols_array(&[
    0.412453, 0.212671, 0.019334, //
    0.357580, 0.715160, 0.119193, //
    0.180423, 0.072169, 0.950227,
]);

/// CIE XYZ to linear sRGB.
#[inline]
pub fn xyz_to_srgb(xyz: [f32; 3]) -> [f32; 3] {
    (XYZ_TO_SRGB * Vec3::from_array(xyz)).to_array()
}

/// Linear sRGB to CIE XYZ.
#[inline]
pub fn srgb_to_xyz(rgb: [f32; 3]) -> [f32; 3] {
    (SRGB_TO_XYZ * Vec3::from_array(rgb)).to_array()
}

/// One-sample Monte Carlo estimate of the XYZ of the spectral radiance `l` (per nm) sampled at
/// `lambda`, normalised so that a constant spectrum of 1 has Y = 1. This is what the film
/// accumulates per camera sample in spectral mode (then averages over samples).
#[cfg_attr(debug_assertions, inline)]
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn spectrum_to_xyz(l: SampledSpectrum, lambda: &SampledWavelengths) -> [f32; 3] {
    let pdf = lambda.pdf();
    // Lanes with pdf 0 are terminated: weight 0 (not NaN).
    let inv_pdf = Vec4::select(pdf.cmpgt(Vec4::ZERO), pdf.recip(), Vec4::ZERO);
    let w = l.0 * inv_pdf * (1.0 / (SampledWavelengths::N as f32 * CIE_Y_INTEGRAL));
    let [x, y, z] = cie::cmf4(lambda.lambda());
    [x.dot(w), y.dot(w), z.dot(w)]
}

/// [`spectrum_to_xyz`] followed by [`xyz_to_srgb`]: the linear sRGB a spectral-mode film adds
/// for one camera sample.
#[inline]
pub fn spectrum_to_srgb(l: SampledSpectrum, lambda: &SampledWavelengths) -> [f32; 3] {
    xyz_to_srgb(spectrum_to_xyz(l, lambda))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrices_are_inverse() {
        let p = XYZ_TO_SRGB * SRGB_TO_XYZ;
        assert!(p.abs_diff_eq(Mat3::IDENTITY, 2e-5), "{p}");
        // Row 0 of XYZ_TO_SRGB as usually printed.
        assert_eq!(XYZ_TO_SRGB.row(0), Vec3::new(3.240479, -1.53715, -0.498535));
        let w = srgb_to_xyz([1.0; 3]);
        assert!((w[1] - 1.0).abs() < 1e-6);
    }

    /// Average of the film estimate over `n` stratified wavelength sets.
    fn estimate(n: usize, f: impl Fn(f32) -> f32) -> [f64; 3] {
        let mut acc = [0.0f64; 3];
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            let w = SampledWavelengths::sample_visible(u);
            let l = SampledSpectrum(Vec4::from_array(w.lambda().to_array().map(&f)));
            let xyz = spectrum_to_xyz(l, &w);
            for c in 0..3 {
                acc[c] += xyz[c] as f64 / n as f64;
            }
        }
        acc
    }

    #[test]
    fn constant_one_has_unit_luminance() {
        let xyz = estimate(20_000, |_| 1.0);
        assert!((xyz[1] - 1.0).abs() < 1e-3, "{xyz:?}");
        // Equal-energy white: X = Y = Z (to the table's precision), sRGB (1.205, 0.948, 0.909).
        assert!(
            (xyz[0] - 1.0).abs() < 2e-3 && (xyz[2] - 1.0).abs() < 2e-3,
            "{xyz:?}"
        );
        let rgb = xyz_to_srgb(xyz.map(|v| v as f32));
        assert!(
            (rgb[0] - 1.2049).abs() < 3e-3 && (rgb[1] - 0.9484).abs() < 3e-3,
            "{rgb:?}"
        );
    }

    #[test]
    fn random_wavelengths_converge() {
        // Independent (not stratified) hero samples: unbiased, converges within noise.
        let mut state = 0x853c_49e6_748f_ea9bu64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        let n = 200_000;
        let mut y = 0.0f64;
        let mut y2 = 0.0f64;
        for _ in 0..n {
            let w = SampledWavelengths::sample_visible(next());
            let v = spectrum_to_xyz(SampledSpectrum::splat(1.0), &w)[1] as f64;
            y += v;
            y2 += v * v;
        }
        let mean = y / n as f64;
        let sigma = ((y2 / n as f64 - mean * mean) / n as f64).sqrt();
        assert!((mean - 1.0).abs() < 4.0 * sigma + 1e-4, "{mean} +- {sigma}");
    }

    #[test]
    fn terminated_lanes_do_not_bias() {
        let n = 20_000;
        let mut y = 0.0f64;
        for k in 0..n {
            let mut w = SampledWavelengths::sample_visible((k as f32 + 0.5) / n as f32);
            w.terminate_secondary();
            y += spectrum_to_xyz(SampledSpectrum::splat(1.0), &w)[1] as f64 / n as f64;
        }
        assert!((y - 1.0).abs() < 1e-3, "{y}");
    }
}

/// How Mitsuba 3's RGB variants read a wavelength-valued spectrum: as a reflectance (weighted
/// by D65 and clamped to [0, 1]), as an emission (unweighted, negatives clamped), or as another
/// quantity that may exceed 1 (conductor indices: weighted by D65, negatives clamped).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RgbRole {
    /// Bounded reflectance.
    Reflectance,
    /// Emitted radiance, irradiance or intensity.
    Emission,
    /// Unbounded non-emissive value.
    Unbounded,
}

/// The linear sRGB that Mitsuba 3.9.1's RGB variants give the spectrum through `points`
/// (wavelength nm, value; increasing wavelengths), its `spectrum_list_to_srgb`: the points
/// interpolated linearly and zero outside them, multiplied by the CIE 1931 colour matching
/// functions (and by D65, 100 at 560 nm, over 98.9974, except for emissions), summed at 1000
/// wavelengths from 360 to 830 nm (both ends) with weight 0.47 nm, normalised by that sum's
/// integral of y-bar (106.75026), through [`XYZ_TO_SRGB`], then clamped as `role` says.
/// A flat emission of 1 gives Y = 1; a flat reflectance of 1 gives grey 0.999.
pub fn mitsuba_points_to_srgb(points: &[(f32, f32)], role: RgbRole) -> [f32; 3] {
    // Mitsuba's constants (MI_CIE_Y_NORMALIZATION, MI_CIE_D65_NORMALIZATION); the first is
    // exactly an f32, 106.7502593994140625.
    const Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
    const D65_NORMALIZATION: f64 = 1.0 / 98.997_417_518_762_55;
    const SAMPLES: usize = 1000;
    let (first, last) = match (points.first(), points.last()) {
        (Some(a), Some(b)) if points.len() >= 2 => (a.0 as f64, b.0 as f64),
        _ => return [0.0; 3],
    };
    let mut xyz = [0.0f64; 3];
    let mut k = 0;
    for i in 0..SAMPLES {
        let w = 360.0 + 470.0 * i as f64 / (SAMPLES - 1) as f64;
        if w < first || w > last {
            continue;
        }
        while k + 2 < points.len() && points[k + 1].0 as f64 <= w {
            k += 1;
        }
        let ((l0, v0), (l1, v1)) = (points[k], points[k + 1]);
        let (l0, v0, l1, v1) = (l0 as f64, v0 as f64, l1 as f64, v1 as f64);
        let v = ((w - l1) * v0 + (l0 - w) * v1) / (l0 - l1);
        let mut weight = v;
        if role != RgbRole::Emission {
            weight *= cie::d65(w as f32) as f64 * D65_NORMALIZATION;
        }
        let cmf = cie::cmf(w as f32);
        for c in 0..3 {
            xyz[c] += cmf[c] as f64 * weight;
        }
    }
    let xyz = xyz.map(|x| (x * 0.47 * Y_NORMALIZATION) as f32);
    let rgb = xyz_to_srgb(xyz);
    match role {
        RgbRole::Reflectance => rgb.map(|c| c.clamp(0.0, 1.0)),
        RgbRole::Emission | RgbRole::Unbounded => rgb.map(|c| c.max(0.0)),
    }
}

#[cfg(test)]
mod mitsuba_rgb_tests {
    use super::*;

    /// Test vectors read back from Mitsuba 3.9.1 (`scalar_rgb`, `load_string` then
    /// `mi.traverse`): each spectrum as a `diffuse` reflectance and as an `area` radiance. The
    /// tolerance, 2e-4 relative, covers the colour matching functions' interpolation (ours and
    /// Mitsuba's 5 nm tables); getting D65, the normalisation, the out-of-range zero or the
    /// clamping wrong moves the values by 1% or more (the emission column is the reflectance
    /// column without D65).
    #[test]
    fn spectra_convert_to_rgb_as_mitsuba_converts_them() {
        let ramp = [(400.0, 0.2), (500.0, 0.5), (600.0, 0.8), (700.0, 0.9)];
        // (points, reflectance RGB, emission RGB)
        type Case<'a> = (&'a [(f32, f32)], [f32; 3], [f32; 3]);
        let cases: [Case; 5] = [
            (
                &ramp,
                [0.880859, 0.631925, 0.321874],
                [1.03639, 0.602969, 0.283548],
            ),
            (
                &[(360.0, 1.0), (830.0, 1.0)],
                [0.998985, 0.998874, 0.998802],
                [1.20488, 0.948228, 0.909267],
            ),
            (
                &[(500.0, 0.0), (520.0, 1.0), (540.0, 0.0)],
                [0.0, 0.246295, 0.0],
                [0.0, 0.229273, 0.0],
            ),
            (
                &[(300.0, 0.5), (450.0, 1.0)],
                [0.0587574, 0.0, 0.474338],
                [0.0594464, 0.0, 0.471239],
            ),
            (
                &[(450.0, 0.3), (650.0, 0.7)],
                [0.597898, 0.508968, 0.14701],
                [0.704055, 0.487514, 0.117208],
            ),
        ];
        for (points, refl, emit) in cases {
            for (role, expect) in [(RgbRole::Reflectance, refl), (RgbRole::Emission, emit)] {
                let got = mitsuba_points_to_srgb(points, role);
                for c in 0..3 {
                    let tol = 2e-4 * expect[c].abs().max(0.05);
                    assert!(
                        (got[c] - expect[c]).abs() <= tol,
                        "{points:?} {role:?}: {got:?} vs {expect:?}"
                    );
                }
            }
        }
    }
}
