//! Normal mapping: a BSDF evaluated in a perturbed shading frame (Mitsuba 3.9's `normalmap`).
//!
//! A normal map gives, per texel, a normal `n` in the local shading frame `(s, t, n)` (s along
//! dp/du, t = n x s). At a hit seen from `wo` (viewer) the model is evaluated in the frame
//! `(s', t', n')`:
//!
//! 1. *Flip* (Schüssler et al. 2017, "Microfacet-based Normal Mapping for Robust Monte Carlo Path
//!    Tracing", sec. 4, as Mitsuba's `flip_invalid_normals`, on by default there): if the viewer
//!    is below the mapped normal, `wo . n <= 0`, the tangential part is mirrored,
//!    `n = (-n.x, -n.y, n.z)`, so that the shading normal faces the viewer.
//! 2. `n' = n / |n|` ((0, 0, 1) if that is not finite), `s'` = local +x made orthogonal to `n'`
//!    (Gram-Schmidt), `t' = n' x s'`.
//! 3. With `P` the map to the perturbed frame and `wi` the light direction (local frame):
//!
//!    `f_nm(wo, wi) |cos wi| = f(P wo, P wi) |cos' wi| G(wi)`  if `cos(wi) cos'(wi) > 0`, else 0,
//!
//!    where `cos' wi = n' . wi` is the cosine of the *perturbed* frame (the one that shades) and
//!    `G` is the bump-terminator shadowing of Conty Estevez, Lecocq & Stein 2019 ("A
//!    Microfacet-Based Shadowing Function to Solve the Bump Terminator Problem", Ray Tracing Gems
//!    ch. 12, eq. 5), a GGX Smith term in the unperturbed frame:
//!
//!    `G(wi) = 2 / (1 + sqrt(1 + alpha^2 tan^2 theta_i))`, `alpha^2 = min(tan^2 theta_n' / 8, 1)`
//!
//!    (`theta_n'` the angle between `n'` and the local normal; Mitsuba's
//!    `use_shadowing_function`, on by default).
//!
//! The renderer's `eval` excludes the cosine and the integrator multiplies by the cosine of the
//! unperturbed frame, so `eval` returns `f(P wo, P wi) |cos' wi| G(wi) / |cos wi|`. `pdf` is
//! the nested pdf at `(P wo, P wi)` (a rotation keeps solid angle; `G` is not in it); `sample`
//! samples the nested model at `P wo`, rotates the result back and multiplies its weight by `G`.
//!
//! **Geometric checks.** A light direction on different sides of the unperturbed and the
//! perturbed normal contributes nothing (eval and pdf 0, a sample there is discarded), which
//! keeps light from leaking through; the viewer side is kept consistent by the flip. Two-sidedness
//! acts first, in the unperturbed frame (Mitsuba's `twosided` around `normalmap`). The
//! integrator's ray offsets and shadow rays use the geometric normal and are unaffected.
//!
//! | parameter   | type    | default | unit                                                   |
//! |-------------|---------|---------|--------------------------------------------------------|
//! | `normalmap` | texture | —       | RGB = (n + 1) / 2 in the local frame (linear data: `raw`) |
//!
//! Mitsuba XML (its `flip_invalid_normals` and `use_shadowing_function` are not read: both are
//! always on here, Mitsuba's defaults):
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

/// The perturbed frame (in the local frame) for the mapped normal `n` (any length) seen from
/// `wo`: steps 1 and 2 of the module doc.
#[inline]
pub fn frame(n: Vec3, wo: Vec3) -> Frame {
    let n = if wo.z * wo.dot(n) <= 0.0 {
        Vec3::new(-n.x, -n.y, n.z)
    } else {
        n
    };
    let n = n.try_normalize().unwrap_or(Vec3::Z);
    Frame::from_normal_tangent(n, Vec3::X)
}

/// Conty Estevez et al. 2019's shadowing `G(wi)` for the perturbed unit normal `np` (both in the
/// local frame; module doc, step 3).
#[inline]
pub fn shadowing(np: Vec3, wi: Vec3) -> f32 {
    let tan2 = |v: Vec3| (1.0 - v.z * v.z).max(0.0) / (v.z * v.z);
    // 1/8: the paper's fit of the GGX roughness to the normal's tilt.
    let alpha2 = (0.125 * tan2(np)).min(1.0);
    let g = 2.0 / (1.0 + (1.0 + alpha2 * tan2(wi)).sqrt());
    if g.is_finite() {
        g
    } else {
        0.0
    }
}

/// The perturbed frame and `(P wo, P wi)` for the mapped normal `n`, when `wi` lies on the same
/// side of the local and the perturbed normal (module doc), else `None`.
#[inline]
pub fn perturb(n: Vec3, wo: Vec3, wi: Vec3) -> Option<(Frame, Vec3, Vec3)> {
    let f = frame(n, wo);
    let pwi = f.to_local(wi);
    (wi.z * pwi.z > 0.0).then(|| (f, f.to_local(wo), pwi))
}

/// Samples `bsdf` in the perturbed frame of the mapped normal `n` and returns the sample in the
/// local frame with its weight times `G`; `None` when the nested model fails or the sampled
/// direction fails the side check.
#[inline]
pub fn sample(n: Vec3, bsdf: &Bsdf, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
    let f = frame(n, wo);
    let mut bs = bsdf.sample(f.to_local(wo), u_lobe, u)?;
    let wi = f.to_world(bs.wi);
    if !(wi.z * bs.wi.z > 0.0) {
        return None;
    }
    bs.wi = wi;
    bs.weight *= shadowing(f.n, wi);
    Some(bs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Lambert, SurfaceBsdf};
    use pt_spectrum::SampledSpectrum;

    fn lambert_nm(n: Vec3) -> SurfaceBsdf {
        SurfaceBsdf {
            normal: Some(n),
            ..SurfaceBsdf::new(
                Bsdf::Lambert(Lambert::new(SampledSpectrum::splat(0.6))),
                false,
            )
        }
    }

    /// Tilting the normal by `a` about local y: f |cos wi| must be
    /// rho/pi cos(theta_i - a) G(theta_i) for light in the x-z plane, with
    /// G = 2 / (1 + sqrt(1 + min(tan^2 a / 8, 1) tan^2 theta_i)), and 0 where the light is below
    /// either normal; values Mitsuba 3.9.1's `normalmap` gives (checked with its Python
    /// bindings: 0.9702 pi/rho at a = 35 deg, wi at 45 deg, viewer along z).
    #[test]
    fn tilted_lambert_shades_with_the_perturbed_cosine() {
        let a = 0.5f32;
        let b = lambert_nm(Vec3::new(a.sin(), 0.0, a.cos()));
        let wo = Vec3::new(0.2, 0.1, 1.0).normalize();
        for deg in [-80.0f32, -40.0, 0.0, 30.0, 60.0, 85.0] {
            let t = deg.to_radians();
            let wi = Vec3::new(t.sin(), 0.0, t.cos());
            let got = b.eval(wo, wi).0.x * wi.z;
            let alpha2 = (a.tan().powi(2) / 8.0).min(1.0);
            let g = 2.0 / (1.0 + (1.0 + alpha2 * t.tan().powi(2)).sqrt());
            let want = if (t - a).cos() > 0.0 {
                0.6 / std::f32::consts::PI * (t - a).cos() * g
            } else {
                0.0
            };
            assert!((got - want).abs() < 1e-5, "theta {deg}: {got} vs {want}");
        }
        let m = lambert_nm(Vec3::new(
            35f32.to_radians().sin(),
            0.0,
            35f32.to_radians().cos(),
        ));
        let wi = Vec3::new(1.0, 0.0, 1.0).normalize();
        assert!(
            (m.eval(Vec3::Z, wi).0.x * wi.z * std::f32::consts::PI / 0.6 - 0.9702).abs() < 1e-4
        );
        // Viewer below the mapped normal: the tangential part is mirrored (Mitsuba's flip).
        let wo_low = Vec3::new(-0.95, 0.0, 0.3122).normalize();
        let mirrored = lambert_nm(Vec3::new(
            -35f32.to_radians().sin(),
            0.0,
            35f32.to_radians().cos(),
        ));
        assert!((m.eval(wo_low, wi).0.x - mirrored.eval(wo_low, wi).0.x).abs() < 1e-6);
        // Below the unperturbed surface but above the perturbed one: no light leaks through.
        let wi = Vec3::new(1.0, 0.0, -0.1).normalize();
        assert!(b.eval(wo, wi).is_black() && b.pdf(wo, wi) == 0.0);
    }

    /// An unperturbed map (0, 0, 1) changes nothing: eval, pdf and samples equal the plain model.
    #[test]
    fn flat_map_is_the_identity() {
        let plain = SurfaceBsdf::new(
            Bsdf::Lambert(Lambert::new(SampledSpectrum::splat(0.6))),
            true,
        );
        let nm = SurfaceBsdf {
            normal: Some(Vec3::Z),
            ..plain
        };
        let mut rng = pt_testkit::Pcg32::new(3, 4);
        for _ in 0..1000 {
            let wo = rng.next_vec3() * 2.0 - Vec3::ONE;
            let wi = rng.next_vec3() * 2.0 - Vec3::ONE;
            let (Some(wo), Some(wi)) = (wo.try_normalize(), wi.try_normalize()) else {
                continue;
            };
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
