//! Thin dielectric sheet (a window pane): both faces of a slab of zero thickness.
//!
//! Model: Mitsuba's `thindielectric`. With the single-interface Fresnel reflectance
//! `R = F(|cos_o|, eta)` ([`fresnel_dielectric`]) and `T = 1 - R`, summing the geometric series
//! of internal reflections between the two parallel faces (no absorption) gives the sheet's
//! reflectance `R' = R + T^2 R / (1 - R^2) = 2R / (1 + R)` and transmittance
//! `T' = 1 - R' = (1 - R)/(1 + R)`. Transmission goes straight through (`wi = -wo`: the two
//! refractions cancel), so `eta' = 1` and no `1/eta^2` factor applies.
//! Two delta lobes chosen with probability `R'` and `T'`, weights `specular_reflectance` and
//! `specular_transmittance`. Symmetric: identical from both sides (no two-sided wrapper needed).
//!
//! | parameter                | type     | default   | unit                      |
//! |--------------------------|----------|-----------|---------------------------|
//! | `int_ior`                | float    | 1.5046    | index of the sheet (BK7)  |
//! | `ext_ior`                | float    | 1.000277  | index around it (air)     |
//! | `specular_reflectance`   | spectrum | 1         | multiplier (not physical) |
//! | `specular_transmittance` | spectrum | 1         | multiplier (not physical) |
//!
//! Mitsuba XML:
//! ```xml
//! <bsdf type="thindielectric">
//!     <float name="int_ior" value="1.5"/>
//! </bsdf>
//! ```

use crate::dielectric::sane_eta;
use crate::fresnel::fresnel_dielectric;
use crate::BsdfSample;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;

/// Thin dielectric sheet.
#[derive(Clone, Copy, Debug)]
pub struct ThinDielectric {
    /// Relative index of the sheet over its surroundings.
    pub eta: f32,
    /// Reflection multiplier.
    pub specular_reflectance: SampledSpectrum,
    /// Transmission multiplier.
    pub specular_transmittance: SampledSpectrum,
}

impl ThinDielectric {
    /// A sheet of relative index `eta = int_ior / ext_ior`, unit multipliers.
    pub fn new(eta: f32) -> Self {
        let one = SampledSpectrum::splat(1.0);
        ThinDielectric {
            eta: sane_eta(eta),
            specular_reflectance: one,
            specular_transmittance: one,
        }
    }

    /// Reflectance of the sheet at `|cos_o|`: `R' = 2R/(1+R)`.
    pub fn reflectance(&self, cos_o: f32) -> f32 {
        let r = fresnel_dielectric(cos_o.abs(), self.eta);
        if r < 1.0 {
            2.0 * r / (1.0 + r)
        } else {
            1.0
        }
    }

    /// Delta lobes: 0.
    pub fn eval(&self, _wo: Vec3, _wi: Vec3) -> SampledSpectrum {
        SampledSpectrum::ZERO
    }

    /// Delta lobes: 0.
    pub fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    /// Reflection with probability `R'` (from `u_lobe`), else straight transmission.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, _u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let r = self.reflectance(wo.z);
        if u_lobe < r || r >= 1.0 {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            Some(BsdfSample {
                wi,
                weight: self.specular_reflectance,
                pdf: r,
                delta: true,
                eta: 1.0,
            })
        } else {
            Some(BsdfSample {
                wi: -wo,
                weight: self.specular_transmittance,
                pdf: 1.0 - r,
                delta: true,
                eta: 1.0,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_sheet() {
        // R = 0.04 per face: R' = 0.08/1.04.
        let t = ThinDielectric::new(1.5);
        assert!((t.reflectance(1.0) - 0.08 / 1.04).abs() < 1e-6);
        assert!((t.reflectance(-1.0) - 0.08 / 1.04).abs() < 1e-6);
    }
}
