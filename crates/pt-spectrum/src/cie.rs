//! CIE colorimetric data evaluated at a wavelength: the CIE 1931 2-degree colour matching
//! functions, the standard illuminants D65 and A, and the fluorescent illuminants F1-F12.
//!
//! All wavelengths are in nanometres. Tables are interpolated linearly between their samples
//! (CIE 15:2004 recommends linear interpolation for the illuminants) and are zero outside their
//! tabulated range, as Mitsuba 3's `cie1931_xyz` and `d65` are.
//!
//! | quantity | range | step | source |
//! |---|---|---|---|
//! | x-bar, y-bar, z-bar | 360-830 nm | 1 nm | CIE 15:2004 tables via colour-science 0.4.7 |
//! | D65 (100 at 560 nm) | 360-830 nm | 5 nm | CIE 15:2004 tables (785-830 nm from the D-series definition) |
//! | A (100 at 560 nm) | any | formula | CIE 15:2004 eq. for illuminant A (Planck with c2 = 1.435e-2 m K, T = 2848 K) |
//! | F1-F12 | 380-780 nm | 5 nm | CIE 15:2004 tables via colour-science 0.4.7 |

use crate::data::cie_tables as t;
use glam::Vec4;

/// Shortest wavelength of the visible range used for spectral rendering, nm (pbrt-v4 and Mitsuba 3).
pub const LAMBDA_MIN: f32 = t::CMF_LAMBDA_MIN;
/// Longest wavelength of the visible range used for spectral rendering, nm.
pub const LAMBDA_MAX: f32 = t::CMF_LAMBDA_MAX;
/// Spacing, nm, of the CMF samples [`cmf`] interpolates between. The data are the official
/// 1 nm table; Mitsuba 3 uses its 5 nm subset (the same values every 5 nm) with linear
/// interpolation, and so do we, so that spectral renders match its references: with the 1 nm
/// table, scenes/cornell-spectral.xml came out 0.1% (red) to 0.4% (blue) darker than Mitsuba's
/// llvm_ad_spectral reference and failed its z-test.
pub const CMF_STEP: usize = 5;

/// Integral over 360-830 nm, in nm, of y-bar as [`cmf`] interpolates it (trapezoids on the
/// 5 nm samples are exact for piecewise-linear data): the normalisation that gives a constant
/// spectrum of 1 the luminance Y = 1 (Mitsuba's `MI_CIE_Y_NORMALIZATION` is its inverse).
pub const CIE_Y_INTEGRAL: f32 = cie_y_integral_5nm() as f32;

const fn cie_y_integral_5nm() -> f64 {
    let mut sum = 0.0;
    let mut i = 0;
    while i + CMF_STEP < t::CMF_SAMPLES {
        sum += 0.5 * (t::CIE_Y[i] as f64 + t::CIE_Y[i + CMF_STEP] as f64) * CMF_STEP as f64;
        i += CMF_STEP;
    }
    sum
}

/// Linear interpolation in a table sampled every `step` nm from `start`; zero outside.
#[inline]
fn lerp_table(table: &[f32], start: f32, step: f32, lambda: f32) -> f32 {
    let x = (lambda - start) / step;
    let last = (table.len() - 1) as f32;
    // Written so that NaN falls through to 0.
    if !(x >= 0.0 && x <= last) {
        return 0.0;
    }
    let i = (x as usize).min(table.len() - 2);
    let f = x - i as f32;
    table[i] + f * (table[i + 1] - table[i])
}

/// CIE 1931 2-degree colour matching functions (x-bar, y-bar, z-bar) at `lambda` nm; zero outside
/// 360-830 nm. Peak of y-bar is 1 at 555 nm.
#[inline]
pub fn cmf(lambda: f32) -> [f32; 3] {
    let x = (lambda - LAMBDA_MIN) / CMF_STEP as f32;
    // Also rejects NaN.
    if !(0.0..=(LAMBDA_MAX - LAMBDA_MIN) / CMF_STEP as f32).contains(&x) {
        return [0.0; 3];
    }
    let n = (t::CMF_SAMPLES - 1) / CMF_STEP; // intervals at CMF_STEP nm
    let i = (x as usize).min(n - 1);
    let f = x - i as f32;
    let (i0, i1) = (i * CMF_STEP, (i + 1) * CMF_STEP);
    let l = |tab: &[f32; t::CMF_SAMPLES]| tab[i0] + f * (tab[i1] - tab[i0]);
    [l(&t::CIE_X), l(&t::CIE_Y), l(&t::CIE_Z)]
}

/// CIE 1931 y-bar (photopic luminous efficiency) at `lambda` nm; zero outside 360-830 nm.
#[inline]
pub fn cmf_y(lambda: f32) -> f32 {
    cmf(lambda)[1]
}

/// CIE D65 relative spectral power at `lambda` nm (100 at 560 nm); zero outside 360-830 nm.
#[inline]
pub fn d65(lambda: f32) -> f32 {
    lerp_table(&t::D65, LAMBDA_MIN, 5.0, lambda)
}

/// CIE standard illuminant A at `lambda` nm from its defining formula (CIE 15:2004, 100 at
/// 560 nm): `100 (560/l)^5 (exp(c2/(T 560)) - 1) / (exp(c2/(T l)) - 1)` with
/// `c2 = 1.435e7 nm K` and `T = 2848 K` (the 1931 definition, equal to 2856 K on ITS-90).
/// Defined at every positive wavelength; the renderer only samples 360-830 nm.
#[inline]
pub fn illuminant_a(lambda: f32) -> f32 {
    const C2_OVER_T: f64 = 1.435e7 / 2848.0;
    let l = lambda as f64;
    if l.is_nan() || l <= 0.0 {
        return 0.0;
    }
    (100.0 * (560.0 / l).powi(5) * (C2_OVER_T / 560.0).exp_m1() / (C2_OVER_T / l).exp_m1()) as f32
}

/// CIE fluorescent illuminant F`n` (n in 1..=12) at `lambda` nm as tabulated (380-780 nm at
/// 5 nm); zero outside the table.
///
/// # Panics
/// If `n` is not in 1..=12.
#[inline]
pub fn illuminant_f(n: usize, lambda: f32) -> f32 {
    assert!(
        (1..=12).contains(&n),
        "CIE fluorescent illuminants are F1..F12, got F{n}"
    );
    lerp_table(&t::F_SERIES[n - 1], 380.0, 5.0, lambda)
}

/// Integrate `f` over 360-830 nm exactly for any product of two functions that are linear
/// between whole nanometres (Simpson's rule on each 1 nm interval), e.g. a CMF times a
/// tabulated spectrum. Used at load time (normalisations, RGB fitting, tests), never per sample.
pub fn integrate_visible(f: impl Fn(f64) -> f64) -> f64 {
    let (a, b) = (LAMBDA_MIN as i32, LAMBDA_MAX as i32);
    let mut sum = 0.0;
    for k in a..b {
        let l = k as f64;
        sum += (f(l) + 4.0 * f(l + 0.5) + f(l + 1.0)) / 6.0;
    }
    sum
}

/// [`cmf`] for four wavelengths at once: returns (x-bar, y-bar, z-bar), each per lane.
#[cfg_attr(debug_assertions, inline)]
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn cmf4(lambda: Vec4) -> [Vec4; 3] {
    let a: [[f32; 3]; 4] = pt_math::lanes::lanes(|k| cmf(lambda[k]));
    [
        Vec4::new(a[0][0], a[1][0], a[2][0], a[3][0]),
        Vec4::new(a[0][1], a[1][1], a[2][1], a[3][1]),
        Vec4::new(a[0][2], a[1][2], a[2][2], a[3][2]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cmf_table_values() {
        // Spot values of the CIE 1931 table.
        let c = cmf(555.0);
        assert_eq!(c[1], 1.0);
        assert!((c[0] - 0.5120501).abs() < 1e-7);
        assert!((cmf(600.0)[0] - 1.0622).abs() < 1e-6);
        assert_eq!(cmf(359.9), [0.0; 3]);
        assert_eq!(cmf(830.1), [0.0; 3]);
        assert!(cmf(830.0)[1] > 0.0);
        // Linear interpolation half-way between 5 nm samples.
        let mid = cmf_y(557.5);
        assert!((mid - 0.5 * (cmf_y(555.0) + cmf_y(560.0))).abs() < 1e-7);
        assert_eq!(cmf_y(f32::NAN), 0.0);
    }

    #[test]
    fn y_integral_matches_quadrature() {
        let q = integrate_visible(|l| cmf_y(l as f32) as f64);
        assert!(
            (q - CIE_Y_INTEGRAL as f64).abs() < 1e-3,
            "{q} vs {CIE_Y_INTEGRAL}"
        );
        // The 5 nm and 1 nm piecewise-linear integrals agree to 1e-4 relative.
        assert!((CIE_Y_INTEGRAL as f64 / t::CIE_Y_INTEGRAL - 1.0).abs() < 1e-4);
        // The three CMFs have equal integrals by construction of the 1931 observer (white E).
        let qx = integrate_visible(|l| cmf(l as f32)[0] as f64);
        let qz = integrate_visible(|l| cmf(l as f32)[2] as f64);
        assert!(
            (qx / q - 1.0).abs() < 1e-3 && (qz / q - 1.0).abs() < 1e-3,
            "{qx} {q} {qz}"
        );
    }

    #[test]
    fn d65_table_values() {
        assert_eq!(d65(560.0), 100.0);
        assert!((d65(830.0) - 60.3125).abs() < 1e-4);
        assert!((d65(360.0) - 46.6383).abs() < 1e-4);
        assert!((d65(562.5) - 0.5 * (100.0 + 98.1671)).abs() < 1e-3);
        // Chromaticity of D65 under the 1931 observer: (0.3127, 0.3290).
        let xyz: Vec<f64> = (0..3)
            .map(|c| integrate_visible(|l| (d65(l as f32) * cmf(l as f32)[c]) as f64))
            .collect();
        let s = xyz[0] + xyz[1] + xyz[2];
        assert!((xyz[0] / s - 0.3127).abs() < 2e-4 && (xyz[1] / s - 0.3290).abs() < 2e-4);
    }

    #[test]
    fn illuminant_a_formula_matches_cie_table() {
        assert!((illuminant_a(560.0) - 100.0).abs() < 1e-4);
        let mut worst = 0.0f32;
        for (i, &v) in t::A_TABLE.iter().enumerate() {
            let l = t::A_TABLE_LAMBDA_MIN + 5.0 * i as f32;
            worst = worst.max((illuminant_a(l) - v).abs() / v);
        }
        // The table is printed to 5-6 significant digits.
        assert!(worst < 5e-5, "worst relative error {worst}");
    }

    #[test]
    fn fluorescent_tables() {
        // F1..F12 are tabulated 380-780 nm; spot-check F2's mercury line region and F11's peak.
        assert_eq!(illuminant_f(1, 379.0), 0.0);
        assert!(illuminant_f(2, 435.0) > illuminant_f(2, 430.0));
        for n in 1..=12 {
            let y = integrate_visible(|l| (illuminant_f(n, l as f32) * cmf_y(l as f32)) as f64);
            assert!(y > 0.0);
        }
        assert!((illuminant_f(1, 380.0) - 1.87).abs() < 1e-5);
    }
}
