//! Normal mapping: a BSDF evaluated in a perturbed shading frame (Mitsuba 3's `normalmap`).
//!
//! A normal map gives, per texel, a unit normal `n'` in the local shading frame `(s, t, n)`
//! (s along dp/du, t = n x s). The nested model is evaluated in the frame `(s', t', n')` with
//! `s'` = s projected onto the plane normal to `n'` (Gram-Schmidt), `t' = n' x s'`. With
//! `wo` (viewer) and `wi` (light) in the local frame and `P` the map to the perturbed frame:
//!
//! `f_nm(wo, wi) |cos wi| = f(P wo, P wi) |cos' wi|`   if `cos(wi) cos'(wi) > 0`, else 0,
//!
//! where `cos' wi = n' . wi` — the cosine of the *perturbed* frame is what shades, as in Mitsuba,
//! whose BSDFs return f times that cosine. Since the renderer's `eval` excludes the cosine and
//! the integrator multiplies by the cosine of the unperturbed local frame, `eval` returns
//! `f(P wo, P wi) |cos' wi| / |cos wi|`; `pdf` is the nested pdf at `(P wo, P wi)` (a rotation
//! keeps solid angle); `sample` samples the nested model at `P wo` and rotates the result back.
//!
//! **Geometric checks.** As Mitsuba's `normalmap`, a light direction `wi` that lies on different
//! sides of the unperturbed and the perturbed shading normal contributes nothing (eval, pdf 0;
//! a sample there is discarded): this removes light leaking through a surface whose mapped
//! normal faces away. The viewer side is judged by the nested model in the perturbed frame (a
//! one-sided model is black when `P wo` is below the perturbed surface, which gives the black
//! facets of extreme normal maps, as in Mitsuba). Two-sidedness acts first, in the unperturbed
//! frame (Mitsuba's `twosided` around `normalmap`). The integrator's offsets and shadow rays use
//! the geometric normal and are unaffected.
//!
//! Difference from Mitsuba 3.9: its `normalmap` orthogonalises the world-space `dp_du` against
//! the local `n'` when it builds `s'` (mixing frames); here `s'` comes from the local `s`. The
//! two agree for isotropic models, which do not depend on `s'`.
//!
//! | parameter   | type    | default | unit                                                   |
//! |-------------|---------|---------|--------------------------------------------------------|
//! | `normalmap` | texture | —       | RGB = (n' + 1) / 2 in the local frame (linear data: `raw`) |
//!
//! Mitsuba XML:
//! ```xml
//! <bsdf type="normalmap">
//!     <texture type="bitmap" name="normalmap">
//!         <string name="filename" value="bumps.png"/>
//!         <boolean name="raw" value="true"/>
//!     </texture>
//!     <bsdf type="diffuse"/>
//! </bsdf>
//! ```

use crate::{Bsdf, BsdfSample};
use pt_math::{Frame, Vec2, Vec3};

/// The perturbed frame for a mapped normal `n` given in the local shading frame (need not be
/// unit length): `n' = n / |n|`, `s'` = local +x (dp/du) made orthogonal to `n'`. `None` for a
/// zero or non-finite `n` (the caller then leaves the frame unperturbed).
#[inline]
pub fn frame(n: Vec3) -> Option<Frame> {
    let n = n.try_normalize()?;
    Some(Frame::from_normal_tangent(n, Vec3::X))
}

/// `(P wo, P wi)` in the perturbed frame `f` when `wi` lies on the same side of the local and
/// the perturbed normal (module doc), else `None`.
#[inline]
pub fn perturb(f: &Frame, wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3)> {
    let pwi = f.to_local(wi);
    (wi.z * pwi.z > 0.0).then(|| (f.to_local(wo), pwi))
}

/// Samples `bsdf` in the perturbed frame `f` and returns the sample in the local frame; `None`
/// when the nested model fails or the sampled direction fails the side check.
#[inline]
pub fn sample(f: &Frame, bsdf: &Bsdf, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
    let mut bs = bsdf.sample(f.to_local(wo), u_lobe, u)?;
    let wi = f.to_world(bs.wi);
    if !(wi.z * bs.wi.z > 0.0) {
        return None;
    }
    bs.wi = wi;
    Some(bs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Lambert, SurfaceBsdf};
    use pt_spectrum::SampledSpectrum;

    fn lambert_nm(n: Vec3) -> SurfaceBsdf {
        SurfaceBsdf { normal: frame(n), ..SurfaceBsdf::new(Bsdf::Lambert(Lambert::new(SampledSpectrum::splat(0.6))), false) }
    }

    /// Tilting the normal by `a` about local y: f |cos wi| must be rho/pi cos(theta_i - a) for
    /// light in the x-z plane (both cosines positive), 0 where the light is below either normal.
    #[test]
    fn tilted_lambert_shades_with_the_perturbed_cosine() {
        let a = 0.5f32;
        let b = lambert_nm(Vec3::new(a.sin(), 0.0, a.cos()));
        let wo = Vec3::new(0.2, 0.1, 1.0).normalize();
        for deg in [-80.0f32, -40.0, 0.0, 30.0, 60.0, 85.0] {
            let t = deg.to_radians();
            let wi = Vec3::new(t.sin(), 0.0, t.cos());
            let got = b.eval(wo, wi).0.x * wi.z;
            let want = 0.6 / std::f32::consts::PI * (t - a).cos().max(0.0);
            let want = if (t - a).cos() > 0.0 { want } else { 0.0 };
            assert!((got - want).abs() < 1e-5, "theta {deg}: {got} vs {want}");
        }
        // Below the unperturbed surface but above the perturbed one: no light leaks through.
        let wi = Vec3::new(1.0, 0.0, -0.1).normalize();
        assert!(b.eval(wo, wi).is_black() && b.pdf(wo, wi) == 0.0);
    }

    /// An unperturbed map (0, 0, 1) changes nothing: eval, pdf and samples equal the plain model.
    #[test]
    fn flat_map_is_the_identity() {
        let plain = SurfaceBsdf::new(Bsdf::Lambert(Lambert::new(SampledSpectrum::splat(0.6))), true);
        let nm = SurfaceBsdf { normal: frame(Vec3::Z), ..plain };
        let mut rng = pt_testkit::Pcg32::new(3, 4);
        for _ in 0..1000 {
            let wo = rng.next_vec3() * 2.0 - Vec3::ONE;
            let wi = rng.next_vec3() * 2.0 - Vec3::ONE;
            let (Some(wo), Some(wi)) = (wo.try_normalize(), wi.try_normalize()) else { continue };
            assert!((plain.eval(wo, wi).0.x - nm.eval(wo, wi).0.x).abs() < 1e-6);
            assert!((plain.pdf(wo, wi) - nm.pdf(wo, wi)).abs() < 1e-6);
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let (a, b) = (plain.sample(wo, 0.5, u), nm.sample(wo, 0.5, u));
            assert_eq!(a.is_some(), b.is_some());
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a.wi - b.wi).length() < 1e-6 && (a.pdf - b.pdf).abs() < 1e-4 * a.pdf);
            }
        }
    }
}
