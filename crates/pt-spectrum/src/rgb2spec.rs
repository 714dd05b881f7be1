//! RGB to spectrum upsampling: Jakob and Hanika, "A Low-Dimensional Function Space for
//! Efficient Spectral Upsampling", Computer Graphics Forum 38(2), 2019.
//!
//! A reflectance is the sigmoid of a quadratic polynomial (paper eq. 3-4),
//! `R(l) = S(c0 t^2 + c1 t + c2)`, `S(x) = 1/2 + x / (2 sqrt(1 + x^2))`, which stays in (0, 1)
//! at every wavelength. Here `t = (l - 360 nm) / 470 nm` is the wavelength mapped to [0, 1]
//! (the paper's optimiser does the same for conditioning); [`RgbSigmoid::coefficients_nm`]
//! gives the coefficients in nanometres as pbrt-v4 and Mitsuba 3 store them.
//!
//! Two ways to get the coefficients of a colour, built on one solver:
//! - [`RgbSigmoid::fit`] solves the least-squares problem exactly for that colour: find `c`
//!   such that the reflectance, lit by D65 and observed by the CIE 1931 2-degree observer, has
//!   the target linear sRGB (`rgb = XYZ_TO_SRGB * int R D65 cmf / int D65 y-bar`). The solver
//!   is Gauss-Newton with Levenberg-Marquardt damping and a homotopy from the grey of the same
//!   mean, warm-starting each step as the paper's table construction does along its brightness
//!   axis. Residuals are in linear sRGB (the paper uses CIELAB); at convergence both are zero.
//!   About 0.1-0.2 ms per colour; [`RgbSigmoid::fit_from`] warm-starts from a nearby colour.
//! - [`RgbToSpectrumTable`] / [`srgb_to_sigmoid`] look the coefficients up in the paper's
//!   precomputed 3 x 64^3 table (trilinear interpolation, well under a microsecond), built
//!   with the same solver at first use and cached on disk.
//!
//! Colours that no reflectance can reach (a channel at exactly 0 or 1 with the others
//! different) are approached as closely as the sigmoid allows; greys are special-cased to the
//! exact constant, so (1, 1, 1) maps to the constant 1 and (0, 0, 0) to 0, as in pbrt-v4.
use crate::cie::{self, LAMBDA_MAX, LAMBDA_MIN};
use crate::color::XYZ_TO_SRGB;
use glam::{DMat3, DVec3, Vec4};
use std::sync::OnceLock;

mod table;
pub use table::{srgb_to_sigmoid, RgbToSpectrumTable};

/// Initial Levenberg-Marquardt damping (relative to the diagonal of `J^T J`) of
/// [`RgbSigmoid::fit`] and [`RgbSigmoid::fit_from`].
const FIT_DAMPING: f64 = 1e-3;

/// Width of the visible range, nm.
const RANGE: f32 = LAMBDA_MAX - LAMBDA_MIN;

/// The sigmoid `S(x) = 1/2 + x / (2 sqrt(1 + x^2))` (paper eq. 4). Infinite `x` gives 0 or 1.
#[inline]
fn sigmoid(x: f32) -> f32 {
    let x = x.clamp(-1e6, 1e6);
    0.5 + 0.5 * x / (1.0 + x * x).sqrt()
}

/// A smooth reflectance spectrum `S(c0 t^2 + c1 t + c2)`, `t = (l - 360) / 470` (l in nm),
/// bounded in [0, 1] at every wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbSigmoid {
    c: [f32; 3],
}

impl RgbSigmoid {
    /// From coefficients in the normalised wavelength `t = (l - 360 nm) / 470 nm`.
    pub fn from_coefficients(c: [f32; 3]) -> Self {
        RgbSigmoid { c }
    }

    /// The constant reflectance `v` (clamped to [0, 1]); exact, including 0 and 1.
    pub fn constant(v: f32) -> Self {
        let v = v.clamp(0.0, 1.0);
        // S(c2) = v  <=>  c2 = (v - 1/2) / sqrt(v (1 - v)); +-infinity at 1 and 0.
        RgbSigmoid {
            c: [0.0, 0.0, (v - 0.5) / (v * (1.0 - v)).sqrt()],
        }
    }

    /// Fit the reflectance whose colour under D65 (CIE 1931 observer) is the linear sRGB `rgb`.
    /// Components are clamped to [0, 1] first (a reflectance cannot exceed 1; use
    /// [`Spectrum::rgb_unbounded`](crate::Spectrum::rgb_unbounded) for larger values).
    pub fn fit(rgb: [f32; 3]) -> Self {
        let rgb = rgb.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) });
        if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
            return Self::constant(rgb[0]);
        }
        let c = fit_coefficients(DVec3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64));
        RgbSigmoid {
            c: [c.x as f32, c.y as f32, c.z as f32],
        }
    }

    /// [`fit`](Self::fit) warm-started from `start`, the fit of a nearby colour (a neighbouring
    /// texel of an image): Levenberg-Marquardt from `start` straight to `rgb`, which for a
    /// nearby colour converges in a few iterations instead of the homotopy's hundreds. If it does
    /// not reach the target within 1e-6 (linear sRGB, far below the 1e-3 accuracy the tests ask
    /// of the model), it falls back to [`fit`](Self::fit), so the result is as good as a cold
    /// fit. Used to upsample whole images at load time.
    pub fn fit_from(rgb: [f32; 3], start: &RgbSigmoid) -> Self {
        let rgb = rgb.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) });
        if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
            return Self::constant(rgb[0]);
        }
        let c0 = start.coefficients_f64();
        if !c0.is_finite() || c0.abs().max_element() > 1e4 {
            return Self::fit(rgb);
        }
        fit_warm(rgb, c0, FIT_DAMPING).unwrap_or_else(|| Self::fit(rgb))
    }

    /// The coefficients in f64, the solver's precision.
    fn coefficients_f64(&self) -> DVec3 {
        DVec3::new(self.c[0] as f64, self.c[1] as f64, self.c[2] as f64)
    }

    /// Coefficients in the normalised wavelength `t = (l - 360 nm) / 470 nm`.
    pub fn coefficients(&self) -> [f32; 3] {
        self.c
    }

    /// Coefficients `(a, b, c)` of `S(a l^2 + b l + c)` with `l` in nm (pbrt-v4 / Mitsuba 3 form).
    pub fn coefficients_nm(&self) -> [f64; 3] {
        let [c0, c1, c2] = self.c.map(|v| v as f64);
        let (s, o) = (1.0 / RANGE as f64, LAMBDA_MIN as f64);
        // t = s (l - o): c0 s^2 (l - o)^2 + c1 s (l - o) + c2.
        [
            c0 * s * s,
            c1 * s - 2.0 * c0 * s * s * o,
            c0 * s * s * o * o - c1 * s * o + c2,
        ]
    }

    /// Reflectance at `lambda` nm, in [0, 1].
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        let t = (lambda - LAMBDA_MIN) * (1.0 / RANGE);
        sigmoid((self.c[0] * t + self.c[1]) * t + self.c[2])
    }

    /// Reflectance at four wavelengths (nm), in [0, 1].
    #[inline]
    pub fn eval4(&self, lambda: Vec4) -> Vec4 {
        let t = (lambda - Vec4::splat(LAMBDA_MIN)) * (1.0 / RANGE);
        let x = ((t * self.c[0] + Vec4::splat(self.c[1])) * t + Vec4::splat(self.c[2]))
            .clamp(Vec4::splat(-1e6), Vec4::splat(1e6));
        Vec4::splat(0.5) + 0.5 * x / (Vec4::ONE + x * x).sqrt()
    }
}

/// The warm-started solve shared by [`RgbSigmoid::fit_from`] and the table builder: damped
/// Gauss-Newton from `start` straight to `rgb` (in [0, 1], not grey), initial damping `mu0`.
/// `Some` if the coefficients, rounded to f32 (the precision they are kept in), reproduce
/// `rgb` within 1e-6 in every channel; `None` otherwise (the caller falls back to a cold fit).
fn fit_warm(rgb: [f32; 3], start: DVec3, mu0: f64) -> Option<RgbSigmoid> {
    let target = DVec3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64);
    let c = solve(target, start, 50, 1e-9, mu0);
    let s = RgbSigmoid {
        c: [c.x as f32, c.y as f32, c.z as f32],
    };
    let (back, _) = rgb_and_jacobian(s.coefficients_f64());
    ((back - target).abs().max_element() < 1e-6).then_some(s)
}

/// Quadrature nodes (normalised t) and RGB weights: `rgb(c) = sum_k w_k S(x_k(c))`, with
/// `w_k = q_k D65(l_k) M cmf(l_k) / sum_k q_k D65(l_k) y-bar(l_k)` (Simpson on 0.5 nm).
struct Quadrature {
    t: Vec<f64>,
    w: Vec<DVec3>,
}

fn quadrature() -> &'static Quadrature {
    static Q: OnceLock<Quadrature> = OnceLock::new();
    Q.get_or_init(|| {
        let m = XYZ_TO_SRGB.as_dmat3();
        let n = ((LAMBDA_MAX - LAMBDA_MIN) as usize) * 2 + 1;
        let (mut t, mut w) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let mut norm = 0.0;
        for k in 0..n {
            let l = LAMBDA_MIN as f64 + 0.5 * k as f64;
            // Composite Simpson weights on 1 nm panels: 1/6, 4/6 (mid), 2/6 (shared ends).
            let q = if k == 0 || k == n - 1 {
                1.0 / 6.0
            } else if k % 2 == 1 {
                4.0 / 6.0
            } else {
                2.0 / 6.0
            };
            let d = cie::d65(l as f32) as f64 * q;
            let [x, y, z] = cie::cmf(l as f32).map(|v| v as f64);
            norm += d * y;
            t.push((l - LAMBDA_MIN as f64) / RANGE as f64);
            w.push(m * DVec3::new(x, y, z) * d);
        }
        for v in &mut w {
            *v /= norm;
        }
        Quadrature { t, w }
    })
}

/// Linear sRGB of the reflectance with coefficients `c` under D65, and its Jacobian
/// (columns: derivatives with respect to c0, c1, c2).
///
/// Two passes per block of nodes: the sigmoids and their derivatives first (independent per
/// node, so the square roots and divisions pipeline), then the sums in node order (the same
/// operations in the same order as a single loop, so the result is bit-identical to it). That
/// takes a third off each call (10.8 to 6.9 us on the 2-core test machine), and so off the
/// 64^3 table build, which is dominated by this function.
fn rgb_and_jacobian(c: DVec3) -> (DVec3, DMat3) {
    const BLOCK: usize = 64;
    let q = quadrature();
    let mut rgb = DVec3::ZERO;
    let (mut j0, mut j1, mut j2) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    let (mut s, mut d) = ([0.0f64; BLOCK], [0.0f64; BLOCK]);
    for (t, w) in q.t.chunks(BLOCK).zip(q.w.chunks(BLOCK)) {
        for ((&t, s), d) in t.iter().zip(&mut s).zip(&mut d) {
            let x = (c.x * t + c.y) * t + c.z;
            let r = 1.0 / (1.0 + x * x).sqrt();
            *s = 0.5 + 0.5 * x * r;
            // dS/dx = 1 / (2 (1 + x^2)^(3/2)).
            *d = 0.5 * r * r * r;
        }
        for (((&t, &w), &s), &d) in t.iter().zip(w).zip(&s).zip(&d) {
            rgb += w * s;
            let ds = w * d;
            j0 += ds * (t * t);
            j1 += ds * t;
            j2 += ds;
        }
    }
    (rgb, DMat3::from_cols(j0, j1, j2))
}

/// Levenberg-Marquardt iterations towards `target` from `c`, stopping when the residual (linear
/// sRGB, Euclidean) is below `tol`; returns the best coefficients. `mu0` is the initial damping
/// relative to the diagonal of `J^T J` (multiplied by 0.3, down to 1e-12, after each accepted
/// step and by 10 after a rejected one): a tiny value gives Gauss-Newton's quadratic convergence
/// from a good start, a larger one a more cautious descent from a poor one.
fn solve(target: DVec3, mut c: DVec3, iterations: usize, tol: f64, mu0: f64) -> DVec3 {
    let (mut rgb, mut jac) = rgb_and_jacobian(c);
    let mut r = rgb - target;
    let mut mu = mu0;
    for _ in 0..iterations {
        if r.length() < tol {
            break;
        }
        let jt = jac.transpose();
        let jtj = jt * jac;
        let g = jt * r;
        let mut accepted = false;
        for _ in 0..30 {
            let damp =
                DMat3::from_diagonal(DVec3::new(jtj.x_axis.x, jtj.y_axis.y, jtj.z_axis.z) * mu);
            let a = jtj + damp;
            if a.determinant().abs() < 1e-300 {
                mu *= 10.0;
                continue;
            }
            let step = -(a.inverse() * g);
            let cn = c + step;
            let (rgb_n, jac_n) = rgb_and_jacobian(cn);
            let rn = rgb_n - target;
            if rn.is_finite() && rn.length_squared() < r.length_squared() {
                (c, rgb, jac, r) = (cn, rgb_n, jac_n, rn);
                mu = (mu * 0.3).max(1e-12);
                accepted = true;
                break;
            }
            mu *= 10.0;
        }
        if !accepted {
            break;
        }
    }
    let _ = rgb;
    c
}

/// Homotopy from the grey of the same mean to `target`, warm-starting each step.
fn fit_coefficients(target: DVec3) -> DVec3 {
    let g = ((target.x + target.y + target.z) / 3.0).clamp(0.02, 0.98);
    let mut c = DVec3::new(0.0, 0.0, (g - 0.5) / (g * (1.0 - g)).sqrt());
    // The grey target is the colour of the constant g (D65 white maps to ~(1, 1, 1)).
    let (grey, _) = rgb_and_jacobian(c);
    const STEPS: usize = 16;
    for k in 1..=STEPS {
        let s = k as f64 / STEPS as f64;
        let last = k == STEPS;
        c = solve(
            grey.lerp(target, s),
            c,
            if last { 200 } else { 30 },
            if last { 1e-9 } else { 1e-7 },
            FIT_DAMPING,
        );
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    /// sRGB of a reflectance under D65, by independent quadrature (Simpson on 1 nm panels).
    pub(crate) fn reflectance_rgb(f: impl Fn(f32) -> f32) -> [f32; 3] {
        let norm = cie::integrate_visible(|l| (cie::d65(l as f32) * cie::cmf_y(l as f32)) as f64);
        let xyz = [0, 1, 2].map(|c| {
            (cie::integrate_visible(|l| {
                let l = l as f32;
                (f(l) * cie::d65(l) * cie::cmf(l)[c]) as f64
            }) / norm) as f32
        });
        crate::color::xyz_to_srgb(xyz)
    }

    #[test]
    fn greys_are_exact_constants() {
        for v in [0.0f32, 0.2, 0.5, 0.9, 1.0] {
            let s = RgbSigmoid::fit([v; 3]);
            for l in [360.0f32, 500.0, 700.0, 830.0] {
                assert!((s.eval(l) - v).abs() < 1e-6, "{v} at {l}: {}", s.eval(l));
            }
        }
        assert_eq!(RgbSigmoid::fit([1.0; 3]).eval(555.0), 1.0);
        assert_eq!(RgbSigmoid::fit([0.0; 3]).eval(555.0), 0.0);
        // White reflectance under D65 is sRGB white (to the D65 table vs matrix white point).
        let rgb = reflectance_rgb(|_| 1.0);
        for c in rgb {
            assert!((c - 1.0).abs() < 2e-3, "{rgb:?}");
        }
    }

    #[test]
    fn round_trip_grid() {
        let levels = [0.02f32, 0.1, 0.3, 0.5, 0.7, 0.9, 0.98];
        let mut worst = 0.0f32;
        for &r in &levels {
            for &g in &levels {
                for &b in &levels {
                    let s = RgbSigmoid::fit([r, g, b]);
                    let back = reflectance_rgb(|l| s.eval(l));
                    let err = (0..3)
                        .map(|c| (back[c] - [r, g, b][c]).abs())
                        .fold(0.0, f32::max);
                    worst = worst.max(err);
                    assert!(err < 1e-3, "{:?} -> {:?} ({:?})", [r, g, b], back, s);
                }
            }
        }
        eprintln!("round trip worst |rgb error| over the grid: {worst:e}");
    }

    #[test]
    fn bounded_everywhere() {
        for rgb in [
            [1.0f32, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [0.9, 0.1, 0.6],
        ] {
            let s = RgbSigmoid::fit(rgb);
            for k in 0..=470 {
                let v = s.eval(360.0 + k as f32);
                assert!((0.0..=1.0).contains(&v), "{rgb:?} at {k}: {v}");
            }
            let v4 = s.eval4(Vec4::new(400.0, 500.0, 600.0, 700.0));
            assert!(
                (v4 - Vec4::new(s.eval(400.0), s.eval(500.0), s.eval(600.0), s.eval(700.0)))
                    .abs()
                    .max_element()
                    < 1e-6
            );
        }
    }

    #[test]
    fn corners_of_the_cube_round_trip() {
        // The sRGB cube under D65 lies inside the reflectance gamut, so even its corners are
        // reached (with large coefficients), as the paper's full 64^3 table covers them.
        for rgb in [
            [1.0f32, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 0.99, 0.98],
            [0.001, 0.0, 0.002],
        ] {
            let s = RgbSigmoid::fit(rgb);
            let back = reflectance_rgb(|l| s.eval(l));
            let err = (0..3).map(|c| (back[c] - rgb[c]).abs()).fold(0.0, f32::max);
            eprintln!("{rgb:?} -> {back:?}, max error {err:.3e}");
            assert!(err < 1e-3, "{rgb:?} -> {back:?}");
        }
    }

    #[test]
    fn fit_is_fast_enough_for_load_time() {
        let t = std::time::Instant::now();
        let n = 50;
        for k in 0..n {
            let v = k as f32 / n as f32;
            std::hint::black_box(RgbSigmoid::fit([v, 1.0 - v, 0.5 * v]));
        }
        let per_fit = t.elapsed().as_secs_f64() / n as f64;
        eprintln!("one fit: {:.3} ms", per_fit * 1e3);
        assert!(per_fit < 0.05, "{per_fit} s per fit");
    }

    #[test]
    fn warm_started_fit_matches_cold_fit() {
        // A chain of nearby colours, each fitted from the previous one (as an image is), must
        // reach the same colours as cold fits (to the model's 1e-3 round-trip accuracy) and be
        // much faster, or upsampling a 128x64 environment map would take seconds.
        let n = 200;
        let colours: Vec<[f32; 3]> = (0..n)
            .map(|k| {
                let t = k as f32 / n as f32;
                [
                    0.05 + 0.9 * t,
                    0.5 + 0.3 * (6.0 * t).sin(),
                    0.9 - 0.8 * t * t,
                ]
            })
            .collect();
        let t0 = std::time::Instant::now();
        let mut prev = RgbSigmoid::fit(colours[0]);
        for &c in &colours {
            let s = RgbSigmoid::fit_from(c, &prev);
            let back = reflectance_rgb(|l| s.eval(l));
            let err = (0..3).map(|i| (back[i] - c[i]).abs()).fold(0.0, f32::max);
            assert!(err < 1e-3, "{c:?} -> {back:?}");
            prev = s;
        }
        let warm = t0.elapsed().as_secs_f64() / n as f64;
        let t1 = std::time::Instant::now();
        for &c in colours.iter().take(20) {
            std::hint::black_box(RgbSigmoid::fit(c));
        }
        let cold = t1.elapsed().as_secs_f64() / 20.0;
        eprintln!(
            "warm fit {:.3} ms (includes the check quadrature), cold fit {:.3} ms",
            warm * 1e3,
            cold * 1e3
        );
        // A bad start (far colour, or garbage coefficients) still gives a correct fit.
        for start in [
            RgbSigmoid::fit([0.9, 0.05, 0.05]),
            RgbSigmoid::from_coefficients([1e9, -3.0, f32::NAN]),
        ] {
            let s = RgbSigmoid::fit_from([0.1, 0.8, 0.2], &start);
            let back = reflectance_rgb(|l| s.eval(l));
            assert!(
                (0..3).all(|i| (back[i] - [0.1, 0.8, 0.2][i]).abs() < 1e-3),
                "{back:?}"
            );
        }
        assert_eq!(
            RgbSigmoid::fit_from([0.3; 3], &prev),
            RgbSigmoid::constant(0.3)
        );
    }

    #[test]
    fn nm_coefficients_agree() {
        let s = RgbSigmoid::fit([0.8, 0.3, 0.1]);
        let [a, b, c] = s.coefficients_nm();
        for l in [380.0f64, 555.0, 700.0] {
            let x = (a * l + b) * l + c;
            let v = 0.5 + 0.5 * x / (1.0 + x * x).sqrt();
            assert!((v as f32 - s.eval(l as f32)).abs() < 1e-5);
        }
    }
}
