//! BSDF models.
//!
//! Conventions, shared by every model (DESIGN.md):
//! - All directions are unit vectors in the **local shading frame**, z = shading normal.
//! - `wo` points towards the viewer (previous path vertex), `wi` towards the light (next vertex);
//!   both point away from the surface. (Mitsuba calls the viewer direction `si.wi`.)
//! - [`Bsdf::eval`] returns f(wo, wi) **without** the cosine factor.
//! - [`Bsdf::pdf`] is per unit **solid angle** of `wi`.
//! - [`Bsdf::sample`] returns `weight = f * |cos theta_i| / pdf`.
//! - Delta lobes (none yet) will return eval = pdf = 0 and be reached only through `sample`.
//!
//! Models are a closed set behind one enum, held by value at a hit (no allocation per hit).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod lambert;

pub use lambert::Lambert;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;

/// The result of sampling a BSDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled incident direction, local shading frame.
    pub wi: Vec3,
    /// `f(wo, wi) * |cos theta_i| / pdf`: the throughput multiplier.
    pub weight: SampledSpectrum,
    /// Solid-angle pdf of `wi` (for a delta lobe: the discrete probability of choosing it).
    pub pdf: f32,
    /// Whether `wi` came from a delta (specular) lobe: MIS must not weight it.
    pub delta: bool,
}

/// A BSDF model (one-sided unless wrapped by [`SurfaceBsdf`] with `two_sided`).
#[derive(Clone, Copy, Debug)]
pub enum Bsdf {
    /// Lambertian diffuse reflection.
    Lambert(Lambert),
}

impl Bsdf {
    /// f(wo, wi) without the cosine, local frame.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        match self {
            Bsdf::Lambert(m) => m.eval(wo, wi),
        }
    }

    /// Solid-angle pdf of sampling `wi` given `wo`, local frame.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Lambert(m) => m.pdf(wo, wi),
        }
    }

    /// Samples `wi` given `wo` from `u` in [0,1)^2 (and `u_lobe` in [0,1) for lobe choice).
    #[inline]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let _ = u_lobe; // one lobe so far
        match self {
            Bsdf::Lambert(m) => m.sample(wo, u),
        }
    }

    /// Whether the model has a non-delta component, so that light sampling can help.
    #[inline]
    pub fn has_smooth_lobe(&self) -> bool {
        match self {
            Bsdf::Lambert(_) => true,
        }
    }
}

/// A BSDF as attached to a surface: the model, and whether it acts the same from both sides
/// (Mitsuba's `twosided`). A one-sided BSDF is black when `wo` is below the surface.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceBsdf {
    /// The reflectance model.
    pub bsdf: Bsdf,
    /// Mirror the model to the back side.
    pub two_sided: bool,
}

impl SurfaceBsdf {
    /// Flips directions to the front side when two-sided and seen from the back.
    #[inline]
    fn side(&self, wo: Vec3) -> f32 {
        if self.two_sided && wo.z < 0.0 {
            -1.0
        } else {
            1.0
        }
    }

    /// f(wo, wi) without the cosine, local frame.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let s = self.side(wo);
        self.bsdf.eval(flip_z(wo, s), flip_z(wi, s))
    }

    /// Solid-angle pdf of `wi`, local frame.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let s = self.side(wo);
        self.bsdf.pdf(flip_z(wo, s), flip_z(wi, s))
    }

    /// Samples `wi`, local frame.
    #[inline]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let s = self.side(wo);
        let mut bs = self.bsdf.sample(flip_z(wo, s), u_lobe, u)?;
        bs.wi = flip_z(bs.wi, s);
        Some(bs)
    }

    /// Whether light sampling can help (a non-delta lobe exists).
    #[inline]
    pub fn has_smooth_lobe(&self) -> bool {
        self.bsdf.has_smooth_lobe()
    }
}

#[inline]
fn flip_z(v: Vec3, s: f32) -> Vec3 {
    Vec3::new(v.x, v.y, v.z * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sided_is_black_from_behind_two_sided_is_not() {
        let lam = Bsdf::Lambert(Lambert::new(SampledSpectrum::from_rgb([0.5; 3])));
        let wo = Vec3::new(0.0, 0.6, -0.8);
        let wi = Vec3::new(0.6, 0.0, -0.8);
        let one = SurfaceBsdf { bsdf: lam, two_sided: false };
        let two = SurfaceBsdf { bsdf: lam, two_sided: true };
        assert!(one.eval(wo, wi).is_black());
        assert!(one.sample(wo, 0.5, Vec2::splat(0.3)).is_none());
        assert!((two.eval(wo, wi).rgb()[0] - 0.5 / std::f32::consts::PI).abs() < 1e-6);
        let bs = two.sample(wo, 0.5, Vec2::new(0.3, 0.7)).unwrap();
        assert!(bs.wi.z < 0.0, "sampled on the viewer's side");
        assert!((two.pdf(wo, bs.wi) - bs.pdf).abs() < 1e-6);
    }
}
