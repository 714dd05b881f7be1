//! Area lights: emissive shapes, sampled by area and converted to solid angle.
//!
//! An area emitter radiates `radiance` from its front side only (the side its shading normal
//! faces), as Mitsuba's `area` emitter. Points are sampled uniformly by area over the whole
//! shape (triangles chosen by area, then uniform barycentrics; spheres uniformly over their
//! surface), so `pdf_area = 1 / total area`, and the solid-angle pdf seen from a point `x` is
//! `pdf_area * |x - y|^2 / |cos theta_y|` (pbrt-v4 eq. 4.15; Veach 1997 eq. 8.10).

use pt_math::warp::{square_to_uniform_sphere, square_to_uniform_triangle};
use pt_math::{Distribution1D, Vec2, Vec3};
use pt_spectrum::SampledSpectrum;

/// Shape data a mesh light samples from (world space).
#[derive(Clone, Debug)]
pub struct LightTriangle {
    /// Vertices.
    pub p: [Vec3; 3],
    /// Per-vertex shading normals, or the geometric normal three times.
    pub n: [Vec3; 3],
}

/// The geometry of an area light.
#[derive(Clone, Debug)]
pub enum LightShape {
    /// Triangles with an area distribution.
    Mesh {
        /// The emitting triangles (zero-area ones removed).
        tris: Vec<LightTriangle>,
        /// Triangle choice proportional to area.
        distr: Distribution1D,
    },
    /// A sphere (normal inwards when `flip`).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
        /// Whether the front side faces inwards.
        flip: bool,
    },
}

/// An area light attached to one shape.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// Emitted radiance (W sr^-1 m^-2), constant over the surface.
    pub radiance: SampledSpectrum,
    /// The emitting geometry.
    pub shape: LightShape,
    /// Total surface area, scene units squared.
    pub area: f32,
}

/// A point sampled on a light, as seen from a reference point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// The point on the light, world space.
    pub p: Vec3,
    /// The light's shading normal there (front side).
    pub n: Vec3,
    /// Unit direction from the reference point towards `p`.
    pub wi: Vec3,
    /// Distance from the reference point to `p`.
    pub dist: f32,
    /// Radiance arriving along `-wi` (zero if `p` shows its back).
    pub radiance: SampledSpectrum,
    /// Solid-angle pdf of `wi` for this light alone (not including light selection).
    pub pdf: f32,
}

impl AreaLight {
    /// Total emitted power estimate (for light selection): pi * area * luminance.
    pub fn power(&self) -> f32 {
        std::f32::consts::PI * self.area * self.radiance.luminance_rgb().max(0.0)
    }

    /// Samples a point uniformly by area and converts to solid angle as seen from `x`.
    /// Returns `None` when the pdf is not finite (the point coincides with `x` or is seen
    /// exactly edge-on).
    pub fn sample(&self, x: Vec3, u_sel: f32, u: Vec2) -> Option<LightSample> {
        let (p, n) = match &self.shape {
            LightShape::Mesh { tris, distr } => {
                let (i, _, _) = distr.sample(u_sel);
                let t = &tris[i];
                let b = square_to_uniform_triangle(u);
                let b0 = 1.0 - b.x - b.y;
                let p = t.p[0] * b0 + t.p[1] * b.x + t.p[2] * b.y;
                let n = (t.n[0] * b0 + t.n[1] * b.x + t.n[2] * b.y).normalize_or_zero();
                (p, n)
            }
            LightShape::Sphere { center, radius, flip } => {
                let d = square_to_uniform_sphere(u);
                (*center + d * *radius, if *flip { -d } else { d })
            }
        };
        let to = p - x;
        let dist2 = to.length_squared();
        let dist = dist2.sqrt();
        if !(dist > 0.0) {
            return None;
        }
        let wi = to / dist;
        let cos_l = n.dot(-wi);
        let pdf = dist2 / (cos_l.abs() * self.area);
        if !pdf.is_finite() {
            return None;
        }
        let radiance = if cos_l > 0.0 { self.radiance } else { SampledSpectrum::ZERO };
        Some(LightSample { p, n, wi, dist, radiance, pdf })
    }

    /// Solid-angle pdf, from `x`, of having sampled the point `p` with normal `n` on this light
    /// (for MIS when a BSDF-sampled ray hits the light).
    #[inline]
    pub fn pdf(&self, x: Vec3, p: Vec3, n: Vec3) -> f32 {
        let to = p - x;
        let dist2 = to.length_squared();
        let cos_l = n.dot(to).abs() / dist2.sqrt();
        let pdf = dist2 / (cos_l * self.area);
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// Radiance leaving the light at a point with normal `n` towards direction `w` (unit,
    /// pointing away from the light).
    #[inline]
    pub fn emitted(&self, n: Vec3, w: Vec3) -> SampledSpectrum {
        if n.dot(w) > 0.0 { self.radiance } else { SampledSpectrum::ZERO }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_pdf_matches_pdf_query() {
        let tri = |a: Vec3, b: Vec3, c: Vec3| {
            let n = (b - a).cross(c - a).normalize();
            LightTriangle { p: [a, b, c], n: [n; 3] }
        };
        // A 2 x 1 rectangle at y = 1 facing down, split into two triangles of equal area.
        let tris = vec![
            tri(Vec3::new(-1.0, 1.0, -0.5), Vec3::new(1.0, 1.0, -0.5), Vec3::new(1.0, 1.0, 0.5)),
            tri(Vec3::new(-1.0, 1.0, -0.5), Vec3::new(1.0, 1.0, 0.5), Vec3::new(-1.0, 1.0, 0.5)),
        ];
        assert!(tris[0].n.iter().all(|n| (n.y + 1.0).abs() < 1e-6), "faces down");
        let light = AreaLight {
            radiance: SampledSpectrum::from_rgb([1.0; 3]),
            shape: LightShape::Mesh { tris, distr: Distribution1D::new(&[1.0, 1.0]).unwrap() },
            area: 2.0,
        };
        let x = Vec3::new(0.2, 0.0, 0.1);
        // Estimate the solid angle subtended: E[1/pdf] = solid angle. Compare with the value from
        // dense midpoint quadrature of cos/d^2 over the rectangle.
        let n = 200_000;
        let mut s = 99u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32
        };
        let mut est = 0.0f64;
        for _ in 0..n {
            let ls = light.sample(x, rnd(), Vec2::new(rnd(), rnd())).unwrap();
            assert!((light.pdf(x, ls.p, ls.n) - ls.pdf).abs() <= 1e-4 * ls.pdf);
            assert!(!ls.radiance.is_black(), "front side faces x");
            est += 1.0 / ls.pdf as f64;
        }
        est /= n as f64;
        let m = 400;
        let mut quad = 0.0f64;
        for i in 0..m {
            for j in 0..m {
                let p = Vec3::new(-1.0 + 2.0 * (i as f32 + 0.5) / m as f32, 1.0, -0.5 + (j as f32 + 0.5) / m as f32);
                let d = p - x;
                let cos = d.y / d.length();
                quad += (cos / d.length_squared()) as f64 * (2.0 / (m * m) as f64);
            }
        }
        // Monte Carlo relative error of 1/pdf here is ~0.3 / sqrt(2e5) < 1e-3; 5e-3 is 5 sigma.
        assert!((est - quad).abs() / quad < 5e-3, "{est} vs {quad}");
    }
}
