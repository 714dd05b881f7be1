//! Directions on the unit sphere and integrals over cells of it.
//!
//! Directions are unit vectors in a local frame with z as the pole (for a BSDF: the shading
//! normal); `theta` is the polar angle from +z, `phi` the azimuth from +x towards +y.

use glam::Vec3;
use std::f64::consts::PI;

/// A unit direction from polar coordinates (cos theta, phi).
#[inline]
pub fn spherical(cos_theta: f64, phi: f64) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(
        (sin_theta * phi.cos()) as f32,
        (sin_theta * phi.sin()) as f32,
        cos_theta as f32,
    )
}

/// A unit direction at polar angle `theta_deg` degrees and azimuth `phi_deg` degrees.
pub fn dir_deg(theta_deg: f64, phi_deg: f64) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    spherical(t.cos(), p)
}

/// Integral over a (theta, phi) rectangle by adaptive Simpson quadrature. The rectangle is
/// split 4x4 (so that a lobe much narrower than the cell is not missed by a first 3x3 rule
/// that would then "converge" on a wrong value); on each part the 3x3 rule is compared with the
/// sum of 3x3 rules on its four quarters, recursing where they differ by more than 15 times the
/// part's tolerance (the Richardson error estimate), to `depth` further levels. The tolerance
/// is `max(abs_tol, rel_tol * |coarse estimate|)` for the rectangle and halves (not quarters)
/// per level, so that refinement along a discontinuity (horizon, total internal reflection)
/// stops instead of running to the depth limit.
fn adaptive_simpson_2d(
    f: &dyn Fn(f64, f64) -> f64,
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    abs_tol: f64,
    rel_tol: f64,
    depth: u32,
) -> f64 {
    fn simpson(f: &dyn Fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        const W: [f64; 3] = [1.0, 4.0, 1.0];
        let (xm, ym) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let xs = [x0, xm, x1];
        let ys = [y0, ym, y1];
        let mut s = 0.0;
        for (i, &x) in xs.iter().enumerate() {
            for (j, &y) in ys.iter().enumerate() {
                s += W[i] * W[j] * f(x, y);
            }
        }
        s * (x1 - x0) * (y1 - y0) / 36.0
    }
    fn rec(
        f: &dyn Fn(f64, f64) -> f64,
        r: (f64, f64, f64, f64),
        whole: f64,
        tol: f64,
        depth: u32,
    ) -> f64 {
        let (x0, x1, y0, y1) = r;
        let (xm, ym) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let q = [
            (x0, xm, y0, ym),
            (xm, x1, y0, ym),
            (x0, xm, ym, y1),
            (xm, x1, ym, y1),
        ];
        let parts = q.map(|(a, b, c, d)| simpson(f, a, b, c, d));
        let sum: f64 = parts.iter().sum();
        if depth == 0 || (sum - whole).abs() <= 15.0 * tol {
            return sum + (sum - whole) / 15.0;
        }
        q.iter()
            .zip(parts)
            .map(|(&qr, p)| rec(f, qr, p, 0.5 * tol, depth - 1))
            .sum()
    }
    let (dx, dy) = ((x1 - x0) / 4.0, (y1 - y0) / 4.0);
    let mut parts = Vec::with_capacity(16);
    for i in 0..4 {
        for j in 0..4 {
            let r = (
                x0 + i as f64 * dx,
                x0 + (i + 1) as f64 * dx,
                y0 + j as f64 * dy,
                y0 + (j + 1) as f64 * dy,
            );
            parts.push((r, simpson(f, r.0, r.1, r.2, r.3)));
        }
    }
    let coarse: f64 = parts.iter().map(|p| p.1).sum();
    let tol = abs_tol.max(rel_tol * coarse.abs()) / 16.0;
    parts
        .into_iter()
        .map(|(r, whole)| rec(f, r, whole, tol, depth))
        .sum()
}

/// Integral of `g(direction)` over each cell of a `res_cos x res_phi` grid in (cos theta, phi)
/// over the sphere, row-major (cos theta outer). Each cell is integrated to an error of about
/// `max(abs_tol, rel_tol * value)` (adaptive Simpson, see the source).
pub fn integrate_cells(
    g: &dyn Fn(Vec3) -> f64,
    res_cos: usize,
    res_phi: usize,
    abs_tol: f64,
    rel_tol: f64,
) -> Vec<f64> {
    // Inside a cell, integrate over (theta, phi) with the Jacobian sin(theta): a lobe at a
    // pole is ~1/(angular width) wider there than in cos(theta), so far easier to resolve.
    let f = |t: f64, p: f64| {
        let (st, ct) = t.sin_cos();
        let v = g(spherical(ct, p)) * st;
        if v.is_finite() {
            v
        } else {
            f64::NAN
        }
    };
    let mut out = Vec::with_capacity(res_cos * res_phi);
    for i in 0..res_cos {
        let c0 = -1.0 + 2.0 * i as f64 / res_cos as f64;
        let c1 = -1.0 + 2.0 * (i + 1) as f64 / res_cos as f64;
        let (t0, t1) = (c1.clamp(-1.0, 1.0).acos(), c0.clamp(-1.0, 1.0).acos());
        // Evaluate strictly inside the cell: a pdf that jumps at a cell boundary (the horizon,
        // where a grazing lobe is cut off) must not leak its value into the neighbour cell
        // through the Simpson end points. The area lost is 1e-6 of the cell.
        let eps = 5e-7 * (t1 - t0);
        let (t0, t1) = (t0 + eps, t1 - eps);
        for j in 0..res_phi {
            let p0 = 2.0 * PI * j as f64 / res_phi as f64;
            let p1 = 2.0 * PI * (j + 1) as f64 / res_phi as f64;
            out.push(adaptive_simpson_2d(
                &f,
                (t0, t1, p0, p1),
                abs_tol,
                rel_tol,
                8,
            ));
        }
    }
    out
}

/// Index of the (cos theta, phi) cell of `wi` in a `res_cos x res_phi` grid, row-major.
pub(crate) fn cell_of(wi: Vec3, res_cos: usize, res_phi: usize) -> usize {
    let c = f64::from(wi.z).clamp(-1.0, 1.0);
    let mut phi = f64::from(wi.y).atan2(f64::from(wi.x));
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let i = (((c + 1.0) * 0.5 * res_cos as f64) as usize).min(res_cos - 1);
    let j = ((phi / (2.0 * PI) * res_phi as f64) as usize).min(res_phi - 1);
    i * res_phi + j
}
