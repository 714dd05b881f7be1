//! Mitsuba's `polarizer` (a linear polarizer) as its unpolarized variants render it: a
//! surface that light crosses straight, from either side, keeping half of it times the
//! `transmittance` (unpolarized light loses half its intensity in an ideal linear polarizer,
//! Malus's law averaged over the polarization angle). Its orientation `theta` and
//! `polarizing` change nothing without polarization. It is a null lobe in Mitsuba: shadow rays
//! are blocked by it, and a pixel seen only through it is not covered (alpha).
//!
//! `sample`: `wi = -wo`, weight `transmittance / 2`, discrete probability 1, delta; `eval` and
//! `pdf` are 0.
//!
//! | parameter | type | default | unit |
//! |---|---|---|---|
//! | `transmittance` | spectrum/texture | 1 | fraction kept besides the polarizer's half |
//! | `theta` | float/texture | 0 | degrees; no effect without polarization |
//! | `polarizing` | boolean | true | no effect without polarization |

use crate::BsdfSample;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;

/// An ideal linear polarizer for unpolarized light (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct Polarizer {
    /// Transmittance per lane, besides the polarizer's factor 1/2.
    pub transmittance: SampledSpectrum,
}

impl Polarizer {
    /// f(wo, wi): 0 (a delta lobe only).
    pub fn eval(&self, _wo: Vec3, _wi: Vec3) -> SampledSpectrum {
        SampledSpectrum::ZERO
    }

    /// 0 (a delta lobe only).
    pub fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    /// Straight through, from either side.
    pub fn sample(&self, wo: Vec3, _u: Vec2) -> Option<BsdfSample> {
        Some(BsdfSample {
            wi: -wo,
            weight: self.transmittance * 0.5,
            pdf: 1.0,
            delta: true,
            eta: 1.0,
        })
    }
}
