//! Warps from the unit square to sampling domains, each beside its pdf.
//!
//! Inputs are uniform samples in `[0, 1)^2`. Direction pdfs are per unit solid angle, in the
//! local frame (z up); point pdfs per unit area.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};

/// Concentric map from the square to the unit disk (Shirley & Chiu 1997, "A Low Distortion Map
/// Between Disk and Square"), uniform in area. pdf = 1/pi per unit area. (One lane of
/// [`square_to_disk_concentric_lanes`].)
#[inline(always)]
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    let (x, y) = square_to_disk_concentric_lanes(&[u.x], &[u.y]);
    Vec2::new(x[0], y[0])
}

/// [`square_to_disk_concentric`] in every lane, without branches (the wedge is a coin flip
/// per sample, so a branch on it would be mispredicted half the time): in the wedges
/// |x| > |y|, r = x and the angle is q = pi/4 (y / x); in the others r = y and the angle is
/// pi/2 - q with q = pi/4 (x / y), whose cosine and sine are q's sine and cosine. q lies in
/// [-pi/4, pi/4], where short polynomials are exact to float precision (see
/// `sin_cos_quarter`).
#[inline(always)]
pub fn square_to_disk_concentric_lanes<const N: usize>(
    ux: &[f32; N],
    uy: &[f32; N],
) -> ([f32; N], [f32; N]) {
    let (mut x, mut y) = ([0.0; N], [0.0; N]);
    for k in 0..N {
        let (ox, oy) = (2.0 * ux[k] - 1.0, 2.0 * uy[k] - 1.0);
        let x_wedge = ox.abs() > oy.abs();
        let (r, num) = (select(x_wedge, ox, oy), select(x_wedge, oy, ox));
        // At the centre (0, 0), 0/0 is NaN, which `max` replaces by -1; r = 0 maps it to (0, 0).
        let ratio = (num / r).max(-1.0);
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * ratio);
        let (cos_t, sin_t) = (select(x_wedge, c, s), select(x_wedge, s, c));
        (x[k], y[k]) = (r * cos_t, r * sin_t);
    }
    (x, y)
}

/// `a` if `c`, else `b`, through integer masks, which compile to blends or conditional moves
/// rather than a branch (a branch on a coin flip is mispredicted on every other sample).
#[inline(always)]
fn select(c: bool, a: f32, b: f32) -> f32 {
    let m = (c as u32).wrapping_neg();
    f32::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// `(sin q, cos q)` for `|q| <= pi/4`, by the Taylor polynomials to degree 9 and 10 (Horner's
/// scheme): the first omitted terms, q^11/11! and q^12/12! at q = pi/4, are 1.7e-9 and
/// 1.0e-10, below half an ulp of the results (the largest error over the range is 0.76 ulp
/// relative to the result, from rounding; see the test).
#[inline(always)]
pub fn sin_cos_quarter(q: f32) -> (f32, f32) {
    let q2 = q * q;
    // 1/3!, 1/5!, 1/7!, 1/9! and 1/2!, 1/4!, 1/6!, 1/8!, 1/10!.
    let s = q
        * (1.0
            - q2 * (1.0 / 6.0 - q2 * (1.0 / 120.0 - q2 * (1.0 / 5040.0 - q2 * (1.0 / 362880.0)))));
    let c = 1.0
        - q2 * (0.5
            - q2 * (1.0 / 24.0
                - q2 * (1.0 / 720.0 - q2 * (1.0 / 40320.0 - q2 * (1.0 / 3628800.0)))));
    (s, c)
}

/// Cosine-weighted hemisphere around +z (Malley's method: lift the uniform disk sample).
/// pdf = cos(theta) / pi, see [`cosine_hemisphere_pdf`]. (One lane of
/// [`square_to_cosine_hemisphere_lanes`].)
#[inline(always)]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let v = square_to_cosine_hemisphere_lanes(&[u.x], &[u.y]);
    Vec3::new(v.x[0], v.y[0], v.z[0])
}

/// [`square_to_cosine_hemisphere`] in every lane.
#[inline(always)]
pub fn square_to_cosine_hemisphere_lanes<const N: usize>(
    ux: &[f32; N],
    uy: &[f32; N],
) -> crate::lanes::V3<N> {
    let (x, y) = square_to_disk_concentric_lanes(ux, uy);
    let z = crate::lanes::lanes(|k| (1.0 - (x[k] * x[k] + y[k] * y[k])).max(0.0).sqrt());
    crate::lanes::V3 { x, y, z }
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
    let (sin_phi, cos_phi) = crate::fastmath::sin_cos_turns(u.y);
    Vec3::new(r * cos_phi, r * sin_phi, z)
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

/// Uniform direction in the cone of half-angle `theta_max` around +z, given
/// `one_minus_cos_max = 1 - cos(theta_max)` (pass `2 sin^2(theta_max / 2)`: for the Sun's 0.27
/// degrees, 1 - cos computed in f32 would lose 1% to cancellation).
/// pdf = 1 / (2 pi (1 - cos_max)), see [`uniform_cone_pdf`].
pub fn square_to_uniform_cone(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let omc = u.x * one_minus_cos_max; // 1 - cos(theta), exactly uniform in cos(theta)
    let cos_t = 1.0 - omc;
    let sin_t = (omc * (2.0 - omc)).max(0.0).sqrt();
    let (sin_phi, cos_phi) = crate::fastmath::sin_cos_turns(u.y);
    Vec3::new(sin_t * cos_phi, sin_t * sin_phi, cos_t)
}

/// Solid-angle pdf of [`square_to_uniform_cone`] (inside the cone).
#[inline]
pub fn uniform_cone_pdf(one_minus_cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic low-discrepancy points for integration checks (Fibonacci lattice).
    fn lattice(n: usize) -> impl Iterator<Item = Vec2> {
        let g = 0.618_034_f64;
        (0..n).map(move |i| {
            Vec2::new(
                ((i as f64 + 0.5) / n as f64) as f32,
                ((i as f64 * g).fract()) as f32,
            )
        })
    }

    #[test]
    fn quarter_sin_cos_is_exact_to_float_precision() {
        // Against f64's sin and cos over [-pi/4, pi/4]: within 1 ulp relative to the result
        // (0.76 measured, from rounding the f32 evaluation; without its last term the sine
        // misses by 4.3 ulp and the cosine by 1.003, so a wrong or missing term fails this).
        for k in 0..=100_000 {
            let q = (k as f32 / 50_000.0 - 1.0) * FRAC_PI_4;
            let (s, c) = sin_cos_quarter(q);
            let (es, ec) = (q as f64).sin_cos();
            assert!(
                (s as f64 - es).abs() <= f32::EPSILON as f64 * es.abs().max(1e-30),
                "sin {q}: {s} vs {es}"
            );
            assert!(
                (c as f64 - ec).abs() <= f32::EPSILON as f64 * ec.abs(),
                "cos {q}: {c} vs {ec}"
            );
        }
    }

    #[test]
    fn concentric_map_matches_the_trigonometric_form() {
        // Shirley & Chiu's map with libm's sin and cos, branch per wedge, as the reference.
        let reference = |u: Vec2| {
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
        };
        for i in 0..=200 {
            for j in 0..=200 {
                let u = Vec2::new(i as f32 / 200.0, j as f32 / 200.0);
                let (a, b) = (square_to_disk_concentric(u), reference(u));
                assert!(
                    (a - b).abs().max_element() <= 4.0 * f32::EPSILON,
                    "{u}: {a} vs {b}"
                );
                assert!(a.length() <= 1.0 + f32::EPSILON);
            }
        }
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
        let mean_z: f64 = lattice(n)
            .map(|u| square_to_cosine_hemisphere(u).z as f64)
            .sum::<f64>()
            / n as f64;
        assert!((mean_z - 2.0 / 3.0).abs() < 1e-3, "{mean_z}");
    }

    #[test]
    fn uniform_sphere_is_uniform() {
        let n = 1 << 16;
        let mean: Vec3 = lattice(n).map(square_to_uniform_sphere).sum::<Vec3>() / n as f32;
        assert!(mean.length() < 1e-3);
        let mean_z2: f32 = lattice(n)
            .map(|u| square_to_uniform_sphere(u).z.powi(2))
            .sum::<f32>()
            / n as f32;
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
