//! Warps from the unit square to sampling domains, each beside its pdf.
//!
//! Inputs are uniform samples in `[0, 1)^2`. Direction pdfs are per unit solid angle, in the
//! local frame (z up); point pdfs per unit area.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};

/// Concentric map from the square to the unit disk (Shirley & Chiu 1997, "A Low Distortion Map
/// Between Disk and Square"), uniform in area. pdf = 1/pi per unit area.
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, 2.0 * FRAC_PI_4 - FRAC_PI_4 * (o.x / o.y))
    };
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// Cosine-weighted hemisphere around +z (Malley's method: lift the uniform disk sample).
/// pdf = cos(theta) / pi, see [`cosine_hemisphere_pdf`].
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Solid-angle pdf of [`square_to_cosine_hemisphere`]: cos(theta)/pi above the horizon, else 0.
#[inline]
pub fn cosine_hemisphere_pdf(v: Vec3) -> f32 {
    if v.z > 0.0 {
        v.z * FRAC_1_PI
    } else {
        0.0
    }
}

/// Uniform direction on the unit sphere. pdf = 1 / (4 pi).
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Solid-angle pdf of [`square_to_uniform_sphere`].
pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * FRAC_1_PI;

/// Barycentric coordinates `(b1, b2)` (weights of vertices 1 and 2) uniform over a triangle,
/// by the square-root parameterisation (Turk 1990; pbrt-v3 eq. 13.12 area measure).
/// pdf = 1 / area per unit area.
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    let su = u.x.sqrt();
    Vec2::new(1.0 - su, u.y * su)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic low-discrepancy points for integration checks (Fibonacci lattice).
    fn lattice(n: usize) -> impl Iterator<Item = Vec2> {
        let g = 0.618_034_f64;
        (0..n).map(move |i| Vec2::new(((i as f64 + 0.5) / n as f64) as f32, ((i as f64 * g).fract()) as f32))
    }

    #[test]
    fn cosine_hemisphere_integrates_cos_over_pdf_to_pi() {
        // E[cos/pdf] = pi exactly when the sampler's density is cos/pi. A wrong pdf (e.g. 1/2pi)
        // would give 2 or another constant; lattice error at 64k points is < 1e-3.
        let n = 1 << 16;
        let mut acc = 0.0f64;
        for u in lattice(n) {
            let v = square_to_cosine_hemisphere(u);
            assert!((v.length() - 1.0).abs() < 1e-5 && v.z >= 0.0);
            acc += (v.z / cosine_hemisphere_pdf(v).max(1e-30)) as f64;
        }
        assert!((acc / n as f64 - PI as f64).abs() < 1e-3);
        // And E[z] = 2/3 under cos-weighting (integral of cos^2 / pi over the hemisphere).
        let mean_z: f64 = lattice(n).map(|u| square_to_cosine_hemisphere(u).z as f64).sum::<f64>() / n as f64;
        assert!((mean_z - 2.0 / 3.0).abs() < 1e-3, "{mean_z}");
    }

    #[test]
    fn uniform_sphere_is_uniform() {
        let n = 1 << 16;
        let mean: Vec3 = lattice(n).map(square_to_uniform_sphere).sum::<Vec3>() / n as f32;
        assert!(mean.length() < 1e-3);
        let mean_z2: f32 = lattice(n).map(|u| square_to_uniform_sphere(u).z.powi(2)).sum::<f32>() / n as f32;
        assert!((mean_z2 - 1.0 / 3.0).abs() < 1e-3);
    }

    #[test]
    fn triangle_barycentrics_are_uniform() {
        // The mean of uniform barycentrics is (1/3, 1/3).
        let n = 1 << 16;
        let mean: Vec2 = lattice(n).map(square_to_uniform_triangle).sum::<Vec2>() / n as f32;
        assert!((mean - Vec2::splat(1.0 / 3.0)).length() < 1e-3, "{mean:?}");
        for u in lattice(1000) {
            let b = square_to_uniform_triangle(u);
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
        }
    }
}

/// Uniform direction in the cone of half-angle `theta_max` around +z, given
/// `one_minus_cos_max = 1 - cos(theta_max)` (pass `2 sin^2(theta_max / 2)`: for the Sun's 0.27
/// degrees, 1 - cos computed in f32 would lose 1% to cancellation).
/// pdf = 1 / (2 pi (1 - cos_max)), see [`uniform_cone_pdf`].
pub fn square_to_uniform_cone(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let omc = u.x * one_minus_cos_max; // 1 - cos(theta), exactly uniform in cos(theta)
    let cos_t = 1.0 - omc;
    let sin_t = (omc * (2.0 - omc)).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Solid-angle pdf of [`square_to_uniform_cone`] (inside the cone).
#[inline]
pub fn uniform_cone_pdf(one_minus_cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}
