//! Opacity mask: a surface that is partly a hole (leaves, fences, cut-outs).
//!
//! Model: Mitsuba's `mask`. With opacity `a` in [0, 1], the surface is a mixture of its nested BSDF
//! (weight `a`) and a *null* interface (weight `1 - a`) that lets light through unchanged:
//!
//! `f_mask(wo, wi) = a f(wo, wi) + (1 - a) delta(wi + wo) / |cos wi|`
//!
//! The null lobe is a delta distribution: `eval` and `pdf` see only the nested part,
//! `a f` and `a pdf`; `sample` chooses the null lobe with probability `1 - a` (weight 1, `wi = -wo`,
//! `delta`, discrete probability `1 - a`) and the nested BSDF otherwise (weight `f |cos| / pdf`
//! unchanged, since `a` cancels). Shadow rays are blocked by masked surfaces, as in Mitsuba's
//! `path` integrator: light through the holes is found by BSDF sampling (the null lobe).
//!
//! | parameter | type  | default | unit                                   |
//! |-----------|-------|---------|----------------------------------------|
//! | `opacity` | float | 0.5     | fraction of light that meets the BSDF  |
//!
//! Mitsuba XML:
//! ```xml
//! <bsdf type="mask">
//!     <float name="opacity" value="0.3"/>
//!     <bsdf type="diffuse"/>
//! </bsdf>
//! ```
//! A `<texture type="bitmap" name="opacity">` instead of the float gives a per-texel opacity,
//! the Rec. 709 luminance of the texel's linear RGB clamped to [0, 1] (Mitsuba's `eval_1` of an
//! RGB bitmap): the renderer sets [`crate::SurfaceBsdf::opacity`] per hit (pt-render's
//! `Scene::material_at_hit`); shadow rays are blocked by the surface whatever the texel says,
//! as for a constant opacity.

use crate::BsdfSample;
use pt_math::Vec3;
use pt_spectrum::SampledSpectrum;

/// Chooses between the null lobe and the nested BSDF with the lobe number `u_lobe` in [0, 1):
/// `None` = the nested BSDF, with `u_lobe` rescaled to [0, 1) for its own lobe choice;
/// `Some(sample)` = pass straight through.
#[inline]
pub fn choose(opacity: f32, wo: Vec3, u_lobe: f32) -> Result<f32, BsdfSample> {
    // `|`: one branch, always taken for opaque surfaces.
    if (opacity >= 1.0) | (u_lobe < opacity) {
        // Reuse the part of u_lobe below `opacity` for the nested BSDF (stays uniform).
        let u = if opacity >= 1.0 {
            u_lobe
        } else {
            u_lobe / opacity
        };
        Ok(u.min(ONE_MINUS_EPSILON))
    } else {
        Err(BsdfSample {
            wi: -wo,
            weight: SampledSpectrum::splat(1.0),
            pdf: 1.0 - opacity,
            delta: true,
            eta: 1.0,
        })
    }
}

/// The largest f32 below 1, so a rescaled uniform number stays in [0, 1).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn null_lobe_chosen_with_probability_one_minus_opacity() {
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let n = 100_000;
        let mut passes = 0;
        for i in 0..n {
            let u = (i as f32 + 0.5) / n as f32;
            match choose(0.3, wo, u) {
                Err(s) => {
                    passes += 1;
                    assert_eq!(s.wi, -wo);
                    assert!((s.pdf - 0.7).abs() < 1e-6);
                }
                Ok(u2) => assert!((0.0..1.0).contains(&u2)),
            }
        }
        // Stratified u: exactly 70% of the numbers fall in the null part (to rounding).
        assert!((passes as f32 / n as f32 - 0.7).abs() < 1e-4, "{passes}");
        assert!(choose(1.0, wo, 0.999).is_ok());
        assert!(choose(0.0, wo, 0.0).is_err());
    }
}
