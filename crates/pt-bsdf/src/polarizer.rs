//! Mitsuba's polarizing elements as its unpolarized variants render them: `polarizer` (a
//! linear polarizer), `circular` (a circular polarizer) and `retarder` (a wave plate). Light
//! crosses the surface straight, from either side, keeping the element's fraction of
//! unpolarized light times the `transmittance`: half for the polarizers (Malus's law averaged
//! over the polarization angle), all for a retarder, which changes only the polarization.
//! Their orientation, retardance and handedness change nothing without polarization. Each is a
//! null lobe in Mitsuba: shadow rays are blocked by it, and a pixel seen only through it is not
//! covered (alpha).
//!
//! `sample`: `wi = -wo`, weight `kept * transmittance`, discrete probability 1, delta; `eval`
//! and `pdf` are 0.
//!
//! | parameter | type | default | unit |
//! |---|---|---|---|
//! | `transmittance` | spectrum/texture | 1 | fraction kept besides the polarizer's half |
//! | `theta` | float/texture | 0 | degrees; no effect without polarization |
//! | `polarizing` | boolean | true | no effect without polarization |

use crate::BsdfSample;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;

/// An ideal polarizing element for unpolarized light (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct Polarizer {
    /// The fraction of unpolarized light the element keeps: 1/2 for linear and circular
    /// polarizers, 1 for a retarder (`pt_scene::PolarizingElement::unpolarized_fraction`).
    pub kept: f32,
    /// Transmittance per lane, besides `kept`.
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
            weight: self.transmittance * self.kept,
            pdf: 1.0,
            delta: true,
            eta: 1.0,
        })
    }
}
