//! Smooth dielectric interface (glass, water): specular reflection and refraction.
//!
//! Model: Fresnel's equations for unpolarised light (exact for a real index, [`fresnel_dielectric`];
//! Born & Wolf 1999 Sec. 1.5.2; pbrt-v4 eq. 9.6) and Snell's law ([`crate::fresnel::refract`]).
//! Two delta lobes, chosen with the Fresnel probability `R` (pbrt-v4 `DielectricBxDF`,
//! specular branch; Mitsuba `dielectric`):
//! - reflection `wi = (-wo.x, -wo.y, wo.z)`, pdf `R`, weight `specular_reflectance`;
//! - refraction through the interface, pdf `T = 1 - R`, weight
//!   `specular_transmittance / eta'^2`, where `eta' = BsdfSample::eta` is the index on `wi`'s
//!   side over the index on `wo`'s side.
//!
//! **Radiance transport.** Radiance crossing an interface is scaled by `1/eta'^2` (the solid
//! angle is compressed by refraction; Veach 1997 Sec. 5.2, pbrt-v4 `TransportMode::Radiance`).
//! It is included in the BTDF and hence in the sample weight. Energy is conserved in the
//! `eta^2`-corrected sense: `R * 1 + T * (weight * eta'^2) = 1`.
//!
//! The model is two-sided by nature: `wo.z < 0` means the viewer is inside the medium (index
//! `int_ior`), and the relative index is inverted. Do **not** wrap it in a two-sided
//! `SurfaceBsdf` (that would mirror the inside to the outside). Total internal reflection gives
//! `R = 1`. Both lobes are delta: `eval` and `pdf` return 0.
//!
//! | parameter                | type     | default   | unit                           |
//! |--------------------------|----------|-----------|--------------------------------|
//! | `int_ior`                | float    | 1.5046    | index inside (BK7)             |
//! | `ext_ior`                | float    | 1.000277  | index outside (air)            |
//! | `specular_reflectance`   | spectrum | 1         | multiplier (not physical)      |
//! | `specular_transmittance` | spectrum | 1         | multiplier (not physical)      |
//!
//! (`eta = int_ior / ext_ior`, one real number: no dispersion.)
//!
//! Mitsuba XML:
//! ```xml
//! <bsdf type="dielectric">
//!     <float name="int_ior" value="1.5"/>
//!     <float name="ext_ior" value="1.0"/>
//! </bsdf>
//! ```

use crate::fresnel::{fresnel_dielectric, refract};
use crate::BsdfSample;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;

/// Mitsuba's default interior index (BK7 glass).
pub const DEFAULT_INT_IOR: f32 = 1.5046;
/// Mitsuba's default exterior index (air).
pub const DEFAULT_EXT_IOR: f32 = 1.000277;

/// Sanitises a relative index: finite and positive, else 1.
pub(crate) fn sane_eta(eta: f32) -> f32 {
    if eta.is_finite() && eta > 0.0 {
        eta
    } else {
        1.0
    }
}

/// Smooth dielectric interface.
#[derive(Clone, Copy, Debug)]
pub struct Dielectric {
    /// Relative index inside / outside.
    pub eta: f32,
    /// Reflection multiplier.
    pub specular_reflectance: SampledSpectrum,
    /// Transmission multiplier.
    pub specular_transmittance: SampledSpectrum,
}

impl Dielectric {
    /// A smooth dielectric with relative index `eta = int_ior / ext_ior` and unit multipliers.
    pub fn new(eta: f32) -> Self {
        let one = SampledSpectrum::splat(1.0);
        Dielectric {
            eta: sane_eta(eta),
            specular_reflectance: one,
            specular_transmittance: one,
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

    /// Chooses reflection with probability R (from `u_lobe`), else refraction.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, _u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let r = fresnel_dielectric(wo.z, self.eta);
        let t = 1.0 - r;
        if u_lobe < r || t <= 0.0 {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample {
                wi,
                weight: self.specular_reflectance,
                pdf: r,
                delta: true,
                eta: 1.0,
            });
        }
        let (wi, etap) = refract(wo, Vec3::Z, self.eta)?;
        if wi.z * wo.z >= 0.0 {
            return None;
        }
        let weight = self.specular_transmittance * (1.0 / (etap * etap));
        Some(BsdfSample {
            wi,
            weight,
            pdf: t,
            delta: true,
            eta: etap,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_reflectance() {
        let d = Dielectric::new(1.5);
        let r = d.sample(Vec3::Z, 0.0, Vec2::ZERO).unwrap();
        assert!((r.pdf - 0.04).abs() < 1e-6 && r.wi == Vec3::Z);
        let t = d.sample(Vec3::Z, 0.5, Vec2::ZERO).unwrap();
        assert!((t.pdf - 0.96).abs() < 1e-6 && (t.wi + Vec3::Z).length() < 1e-6);
        assert!((t.eta - 1.5).abs() < 1e-7 && (t.weight.0.x - 1.0 / 2.25).abs() < 1e-6);
    }
}
