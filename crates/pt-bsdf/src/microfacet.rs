//! Anisotropic microfacet distributions (GGX and Beckmann) with Smith masking-shadowing and
//! visible-normal sampling, shared by the rough conductor and the rough dielectric.
//!
//! - GGX (Trowbridge-Reitz): Walter, Marschner, Li & Torrance 2007, "Microfacet Models for
//!   Refraction through Rough Surfaces", EGSR, eq. 33; anisotropic form
//!   `D(m) = 1 / (pi ax ay (m.x^2/ax^2 + m.y^2/ay^2 + m.z^2)^2)` (Heitz 2014, "Understanding the
//!   Masking-Shadowing Function", JCGT 3(2), eq. 85).
//! - Beckmann: Walter et al. 2007 eq. 25, anisotropic
//!   `D(m) = exp(-(m.x^2/ax^2 + m.y^2/ay^2)/m.z^2) / (pi ax ay m.z^4)` (Heitz 2014 eq. 80).
//! - Smith Lambda (Heitz 2014 eqs. 72 and 86): with `a = 1/(alpha(w) tan theta)`,
//!   `alpha(w)^2 tan^2 = (w.x^2 ax^2 + w.y^2 ay^2)/w.z^2`:
//!   GGX `(-1 + sqrt(1 + 1/a^2))/2`; Beckmann `(erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi))`.
//!   `G1 = 1/(1 + Lambda)`; `G2 = G1(wo) G1(wi)`, the separable (uncorrelated) form of Walter
//!   et al. 2007 eq. 23, which Mitsuba 3 uses: renders must match its references. The
//!   height-correlated `1/(1 + Lambda(wo) + Lambda(wi))` (Heitz 2014 eq. 99) is more accurate
//!   and never darker; with it (and with the anisotropic tangent not following Mitsuba's
//!   `dp_du`), scenes/conductors.xml failed its reference test with region means 0.2-0.5% off.
//! - Visible normals (Heitz & d'Eon 2014, "Importance Sampling Microfacet-Based BSDFs using
//!   the Distribution of Visible Normals", EGSR, eq. 2; Heitz 2018, JCGT 7(4), eq. 1):
//!   `D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z`, the pdf [`Microfacet::pdf_m`] of both
//!   distributions. GGX samples it exactly with Heitz 2018's Listing 1. Beckmann samples it by
//!   Heitz & d'Eon's slope method (stretch `wo` to roughness 1, sample the visible slopes, rotate
//!   and unstretch, their Sec. 4 and Appendix), with the x-slope CDF inverted numerically as in
//!   Jakob 2014 ("An Improved Visible Normal Sampling Routine for the Beckmann Distribution",
//!   tech. report): in `b = erf(x)` the CDF is
//!   `F(b) = (1 + b + tan(theta) e^{-erfinv(b)^2} / sqrt(pi)) / (1 + erf(cot theta) + tan(theta) e^{-cot^2 theta} / sqrt(pi))`,
//!   `dF/db` proportional to `1 - erfinv(b) tan(theta)`; Newton steps safeguarded by bisection.
//!   (Before, Beckmann sampled `D(m) m.z`, Walter et al. eqs. 28-29, and rejected back-facing
//!   normals: at 89 degrees half the samples were lost.)
//!
//! All functions take directions in the local frame with `wo.z >= 0` (callers flip).

use crate::fresnel::fresnel_dielectric;
use pt_math::lanes::{lanes, mask_of, Mask, V3};
use pt_math::{fastmath, Vec2, Vec3};
use std::f32::consts::PI;

/// Which normal distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Distribution {
    /// Trowbridge-Reitz / GGX.
    #[default]
    Ggx,
    /// Beckmann-Spizzichino.
    Beckmann,
}

impl Distribution {
    /// Parses Mitsuba's `distribution` string (`ggx`, `beckmann`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "ggx" => Some(Self::Ggx),
            "beckmann" => Some(Self::Beckmann),
            _ => None,
        }
    }
}

/// Smallest roughness: below it the distributions overflow f32 (use the smooth models).
pub const MIN_ALPHA: f32 = 1e-3;

/// A microfacet distribution with roughness `alpha_u` along x and `alpha_v` along y.
#[derive(Clone, Copy, Debug)]
pub struct Microfacet {
    /// Normal distribution.
    pub dist: Distribution,
    /// Roughness along the tangent x (GGX: slope scale; Beckmann: RMS slope), >= 1e-3.
    pub alpha_u: f32,
    /// Roughness along the bitangent y, >= 1e-3.
    pub alpha_v: f32,
}

/// Inverse error function on (-1, 1) to about 1e-7 relative, f32's precision (+-inf at +-1):
/// Giles 2010 ("Approximating the erfinv function", GPU Computing Gems Jade), his
/// single-precision approximation, one logarithm and a polynomial (his coefficients, written
/// as the f32 values they round to; Mitsuba samples Beckmann slopes with the same
/// approximation).
pub fn erf_inv_giles(y: f32) -> f32 {
    erf_inv_lanes(&[y])[0]
}

/// [`erf_inv_giles`] for `N` lanes at once: Giles' central form for every lane (one logarithm
/// without a library call, and a polynomial), his tail form only when some lane needs it
/// (|y| above about 0.9966), so that the lanes run in SIMD registers and the rare form costs
/// nothing where no lane takes it.
#[inline(always)]
fn erf_inv_lanes<const N: usize>(y: &[f32; N]) -> [f32; N] {
    let w: [f32; N] = lanes(|k| -fastmath::ln((1.0 - y[k]) * (1.0 + y[k])));
    let mut out: [f32; N] = lanes(|k| {
        // Giles' central polynomial in w - 2.5 by Estrin's scheme (a chain of four steps
        // where Horner's has eight: the single-lane callers wait for it).
        let [c0, c1, c2, c3, c4, c5, c6, c7, c8] = [
            1.5014094,
            0.24664073,
            -0.0041776816,
            -0.001253725,
            0.000_218_580_87,
            -4.3915065e-06,
            -3.523_387_7e-06,
            3.4327394e-07,
            2.8102264e-08,
        ];
        let t = w[k] - 2.5;
        let (t2, t4) = (t * t, t * t * t * t);
        let low = (c0 + c1 * t) + t2 * (c2 + c3 * t);
        let high = (c4 + c5 * t) + t2 * (c6 + c7 * t);
        (low + t4 * (high + t4 * c8)) * y[k]
    });
    let tail: [bool; N] = lanes(|k| !(w[k] < 5.0));
    if mask_of(&tail) != 0 {
        for k in 0..N {
            let w = w[k];
            let wt = w.sqrt() - 3.0;
            let mut q = -0.00020021426;
            for c in [
                0.00010095056,
                0.0013493432,
                -0.0036734284,
                0.0057395077,
                -0.007_622_461_3,
                0.0094388705,
                1.001674,
                2.8329768,
            ] {
                q = c + q * wt;
            }
            out[k] = if tail[k] { q * y[k] } else { out[k] };
        }
    }
    lanes(|k| {
        if y[k] <= -1.0 {
            f32::NEG_INFINITY
        } else if y[k] >= 1.0 {
            f32::INFINITY
        } else {
            out[k]
        }
    })
}

/// 1 / sqrt(pi), in the Gaussian slope densities of Beckmann's visible normals.
const INV_SQRT_PI: f32 = 0.564_189_6;

/// Beckmann visible normals for `N` lanes, each with its roughness (`ax`, `ay`), viewer `wo`
/// (local frame, `wo.z > 0`) and uniform numbers (`u0`, `u1`): Heitz & d'Eon 2014's slope
/// method (stretch to roughness 1, sample the visible slopes, rotate to the viewer's azimuth,
/// unstretch), all lanes at once in SIMD registers, the x-slopes solved for the lanes of
/// `active` (the others get some normal); one lane is [`Microfacet::sample_m`]'s Beckmann
/// normal. Away from normal incidence the two slopes are separable: slope_x depends
/// on `u0` and the angle alone ([`beckmann_slopes_x`]), slope_y on `u1` alone
/// ([`beckmann_slope_y`]); at normal incidence every facet is visible and the slopes are the
/// plain Gaussian's. In f32, as the normals they become: the inversions are accurate to a
/// few 1e-7 in probability.
#[inline(always)]
fn beckmann_visible_normals<const N: usize>(
    ax: &[f32; N],
    ay: &[f32; N],
    wo: &V3<N>,
    u0: &[f32; N],
    u1: &[f32; N],
    active: Mask,
) -> V3<N> {
    let ws: V3<N> = V3::from_fn(|k| beckmann_stretched(ax[k], ay[k], wo.get(k)));
    let cos_theta: [f32; N] = lanes(|k| ws.z[k].clamp(0.0, 1.0));
    let mut sx = beckmann_slopes_x(&cos_theta, u0, active);
    let mut sy = erf_inv_lanes::<N>(&lanes(|k| slope_y_argument(u1[k])));
    let normal: [bool; N] = lanes(|k| beckmann_normal_incidence(cos_theta[k]));
    if mask_of(&normal) != 0 {
        for k in 0..N {
            // Normal incidence: the Gaussian's slopes in polar form.
            let u = u0[k].clamp(1e-7, 1.0 - 1e-7);
            let r = (-fastmath::ln(1.0 - u)).sqrt();
            let (sin_phi, cos_phi) = fastmath::sin_cos_turns(u1[k]);
            if normal[k] {
                (sx[k], sy[k]) = (r * cos_phi, r * sin_phi);
            }
        }
    }
    V3::from_fn(|k| beckmann_normal(ax[k], ay[k], ws.get(k), sx[k], sy[k]))
}

/// Whether [`beckmann_visible_normals`] takes its normal-incidence form (not separable).
#[inline(always)]
fn beckmann_normal_incidence(cos_theta: f32) -> bool {
    cos_theta > 0.9999
}

/// The visible slope across the viewing plane: the standard Gaussian's, by Giles' inverse
/// error function.
#[inline(always)]
fn beckmann_slope_y(u2: f32) -> f32 {
    erf_inv_giles(slope_y_argument(u2))
}

/// The error function's value whose inverse is [`beckmann_slope_y`] of `u2`.
#[inline(always)]
fn slope_y_argument(u2: f32) -> f32 {
    (2.0 * u2 - 1.0).clamp(-1.0 + 1e-7, 1.0 - 1e-7)
}

/// The viewer direction stretched to roughness 1 (Beckmann sampling).
#[inline(always)]
fn beckmann_stretched(ax: f32, ay: f32, wo: Vec3) -> Vec3 {
    Vec3::new(ax * wo.x, ay * wo.y, wo.z).normalize()
}

/// The microfacet normal of the roughness-1 slopes (`sx`, `sy`) drawn for the stretched
/// viewer `ws`: rotated to the viewer's azimuth, unstretched by (`ax`, `ay`); the normal is
/// (-slope_x, -slope_y, 1), +z where that is not finite.
#[inline(always)]
fn beckmann_normal(ax: f32, ay: f32, ws: Vec3, sx: f32, sy: f32) -> Vec3 {
    // |ws| = 1, so the plain form cannot overflow (`hypot` is a library call).
    let r = (ws.x * ws.x + ws.y * ws.y).sqrt();
    let (cos_phi, sin_phi) = if r > 0.0 {
        (ws.x / r, ws.y / r)
    } else {
        (1.0, 0.0)
    };
    let (rx, ry) = (cos_phi * sx - sin_phi * sy, sin_phi * sx + cos_phi * sy);
    let m = Vec3::new(-rx * ax, -ry * ay, 1.0).normalize();
    if m.is_finite() {
        m
    } else {
        Vec3::Z
    }
}

/// The visible slope in the viewing plane for incidence `cos_theta` (below normal incidence),
/// for each lane: the inverse of its CDF at `u1` by Newton's method in a bracket, in the erf
/// domain b = erf(slope_x) (Heitz & d'Eon 2014, sec. 4 and appendix; the CDF is
/// norm (1 + b + tan(theta) e^{-slope_x^2} / sqrt(pi))). The lanes of `active` iterate
/// together until each has converged; a converged lane keeps its value, so every lane gets
/// what it would alone. The other lanes (their values unused: 0) do not iterate: a lane of
/// no use, with a NaN viewer say, would bisect for twenty steps and hold the others up.
#[inline(always)]
fn beckmann_slopes_x<const N: usize>(
    cos_theta: &[f32; N],
    u1: &[f32; N],
    active: Mask,
) -> [f32; N] {
    let (mut u, mut tan, mut lo, mut hi) = ([0.0; N], [0.0; N], [0.0; N], [0.0; N]);
    let (mut norm, mut b) = ([0.0; N], [0.0; N]);
    for k in 0..N {
        let c = cos_theta[k];
        u[k] = u1[k].clamp(1e-7, 1.0 - 1e-7);
        let sin_theta = (1.0 - c * c).max(0.0).sqrt();
        tan[k] = sin_theta / c;
        let cot = c / sin_theta;
        // Bracket of b: facets with slope_x >= cot(theta) face away from the viewer.
        (lo[k], hi[k]) = (-1.0, 1.0 - fastmath::erfc(cot));
        norm[k] = 1.0 / (1.0 + hi[k] + INV_SQRT_PI * tan[k] * fastmath::exp(-cot * cot));
        // Start from Jakob 2014's fit of the inverse, b0 = c - (1 + c)(1 - u1)^p(theta),
        // which leaves a few Newton steps.
        let theta = fastmath::acos(c);
        let fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
        b[k] = hi[k] - (1.0 + hi[k]) * fastmath::exp(fit * fastmath::ln(1.0 - u[k]));
    }
    let mut x = [0.0; N];
    let mut live: [bool; N] = lanes(|k| active & (1 << k) != 0);
    for _ in 0..32 {
        let bs: [f32; N] = lanes(|k| {
            if b[k] > lo[k] && b[k] < hi[k] {
                b[k]
            } else {
                0.5 * (lo[k] + hi[k])
            }
        });
        let xs = erf_inv_lanes(&bs);
        for k in 0..N {
            let (bk, xk) = (bs[k], xs[k]);
            let value =
                norm[k] * (1.0 + bk + INV_SQRT_PI * tan[k] * fastmath::exp(-xk * xk)) - u[k];
            // 2e-7 in probability: a few roundings of the CDF's f32 terms, below which its
            // sign is noise; a bracket of 1e-6 in b leaves slopes good to f32's own precision.
            let done = value.abs() < 2e-7 || hi[k] - lo[k] < 1e-6;
            x[k] = if live[k] { xk } else { x[k] };
            let step = live[k] & !done;
            // Newton where it stays inside the bracket, bisection otherwise (the check above).
            let derivative = norm[k] * (1.0 - xk * tan[k]);
            hi[k] = if step & (value > 0.0) { bk } else { hi[k] };
            lo[k] = if step & !(value > 0.0) { bk } else { lo[k] };
            b[k] = if step { bk - value / derivative } else { b[k] };
            live[k] = step;
        }
        if mask_of(&live) == 0 {
            break;
        }
    }
    x
}

/// One lane of [`beckmann_slopes_x`].
fn beckmann_slope_x(cos_theta: f32, u1: f32) -> f32 {
    beckmann_slopes_x(&[cos_theta], &[u1], 1)[0]
}

/// [`Microfacet::d`] of the GGX (`BECKMANN` false) or the Beckmann distribution of roughness
/// (`ax`, `ay`). Written with selects rather than early returns, and inlined, so that a loop
/// of it over lanes (the path tracer's rough conductors) vectorises; one lane is the
/// single-value function.
#[inline(always)]
pub fn d_of<const BECKMANN: bool>(ax: f32, ay: f32, m: Vec3) -> f32 {
    let (x, y) = (m.x / ax, m.y / ay);
    let z2 = m.z * m.z;
    let v = if BECKMANN {
        fastmath::exp(-(x * x + y * y) / z2) / (PI * ax * ay * z2 * z2)
    } else {
        let k = x * x + y * y + z2;
        1.0 / (PI * ax * ay * k * k)
    };
    if (m.z > 0.0) & v.is_finite() {
        v
    } else {
        0.0
    }
}

/// [`Microfacet::lambda`] of the GGX (`BECKMANN` false) or the Beckmann distribution of
/// roughness (`ax`, `ay`), with selects as [`d_of`].
#[inline(always)]
pub fn lambda_of<const BECKMANN: bool>(ax: f32, ay: f32, w: Vec3) -> f32 {
    let z2 = w.z * w.z;
    let t2 = w.x * w.x * ax * ax + w.y * w.y * ay * ay;
    let v = if BECKMANN {
        let a = (z2 / t2).sqrt();
        // Walter et al. 2007 eq. 27's Lambda, (e^{-a^2} / (a sqrt(pi)) - erfc(a)) / 2, with
        // erfc itself: 1 - erf(a) lost its digits in f32 for a > 2. Lambda is small where the
        // two terms nearly cancel (1.4e-9 at a = 4): their relative errors of a few 1e-6 move
        // G1 by less than 1e-7. From a = 4 on it is taken as 0 (Lambda(4) = 1.4e-9; the
        // difference cancels in f32).
        let l = (0.5 * (fastmath::exp(-a * a) * INV_SQRT_PI / a - fastmath::erfc(a))).max(0.0);
        if a >= 4.0 {
            0.0
        } else {
            l
        }
    } else {
        0.5 * (-1.0 + (1.0 + t2 / z2).sqrt())
    };
    if t2 <= 0.0 {
        0.0
    } else if z2 == 0.0 {
        f32::INFINITY
    } else {
        v
    }
}

/// Smith G1(w) = 1/(1 + Lambda(w)) of [`lambda_of`]'s distribution.
#[inline(always)]
pub fn g1_of<const BECKMANN: bool>(ax: f32, ay: f32, w: Vec3) -> f32 {
    1.0 / (1.0 + lambda_of::<BECKMANN>(ax, ay, w))
}

/// [`Microfacet::dielectric_reflection_pdf`] of the GGX (`BECKMANN` false) or Beckmann
/// distribution of roughness (`ax`, `ay`), with selects as [`d_of`].
#[inline(always)]
fn dielectric_reflection_pdf_of<const BECKMANN: bool>(
    ax: f32,
    ay: f32,
    wo: Vec3,
    wi: Vec3,
    eta: f32,
) -> (f32, f32) {
    let h = (wo + wi).normalize_or_zero();
    let woh = wo.dot(h);
    let ok = !(wo.z <= 0.0) & !(wi.z <= 0.0) & !(h.z <= 0.0) & !(woh <= 0.0);
    let (d, g1_o) = (d_of::<BECKMANN>(ax, ay, h), g1_of::<BECKMANN>(ax, ay, wo));
    let g2 = g1_o * g1_of::<BECKMANN>(ax, ay, wi);
    let v = fresnel_dielectric(woh, eta) * d * g2 / (4.0 * wo.z * wi.z);
    // As pdf_m(wo, h) / (4 wo.h).
    let p = g1_o * woh.max(0.0) * d / wo.z / (4.0 * woh);
    (
        if ok & v.is_finite() { v } else { 0.0 },
        if ok & p.is_finite() { p } else { 0.0 },
    )
}

/// The GGX visible normal for the viewer `wo` (`wo.z > 0`) and roughness (`ax`, `ay`) from the
/// uniform number `u1` and the angle `2 pi u2`, given by its sine and cosine (Heitz 2018,
/// Listing 1: stretch, sample the projected hemisphere, unstretch). Selects rather than
/// branches, so that a loop of it over lanes vectorises (the sine and cosine, library calls,
/// are the caller's).
#[inline(always)]
fn ggx_visible_normal(ax: f32, ay: f32, wo: Vec3, u1: f32, sin_phi: f32, cos_phi: f32) -> Vec3 {
    let vh = Vec3::new(ax * wo.x, ay * wo.y, wo.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    let t2v = vh.cross(t1);
    let r = u1.sqrt();
    let p1 = r * cos_phi;
    let p2 = r * sin_phi;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = t1 * p1 + t2v * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    Vec3::new(ax * nh.x, ay * nh.y, nh.z.max(1e-6)).normalize()
}

/// `wo` reflected about the normal `m`, and whether the reflection exists: `wo` faces `m`
/// and the result lies above the surface ([`Microfacet::sample_reflection`]).
#[inline(always)]
fn reflect_about(wo: Vec3, m: Vec3) -> (Vec3, bool) {
    let wom = wo.dot(m);
    let wi = (2.0 * wom * m - wo).normalize();
    (wi, !(wom <= 0.0) & (wi.z > 0.0))
}

/// [`Microfacet::sample_reflection`] for `N` lanes of the GGX (`BECKMANN` false) or Beckmann
/// distribution, each with its roughness (`ax`, `ay`), viewer `wo` (local frame) and uniform
/// numbers (`u0`, `u1`): the reflected directions and which lanes have one, computed for the
/// lanes of `mask` where `wo` is above the surface, all lanes at once in SIMD registers (the
/// Beckmann lanes iterate for their visible slopes together, [`beckmann_slopes_x`]). The same
/// operations as one lane's.
#[inline(always)]
pub fn sample_reflections<const N: usize, const BECKMANN: bool>(
    ax: &[f32; N],
    ay: &[f32; N],
    wo: &V3<N>,
    u0: &[f32; N],
    u1: &[f32; N],
    mask: Mask,
) -> (V3<N>, [bool; N]) {
    let above: [bool; N] = lanes(|k| wo.z[k] > 0.0);
    let mask = mask & mask_of(&above);
    let mut wi = V3::splat(Vec3::Z);
    let mut ok = [false; N];
    if BECKMANN {
        let m = beckmann_visible_normals(ax, ay, wo, u0, u1, mask);
        for k in 0..N {
            let (w, exists) = reflect_about(wo.get(k), m.get(k));
            wi.set(k, w);
            ok[k] = exists & (mask & (1 << k) != 0);
        }
        return (wi, ok);
    }
    let (mut sin_phi, mut cos_phi) = ([0.0; N], [1.0; N]);
    for k in 0..N {
        (sin_phi[k], cos_phi[k]) = pt_math::fastmath::sin_cos_turns(u1[k]);
    }
    for k in 0..N {
        let m = ggx_visible_normal(ax[k], ay[k], wo.get(k), u0[k], sin_phi[k], cos_phi[k]);
        let (w, exists) = reflect_about(wo.get(k), m);
        wi.set(k, w);
        ok[k] = exists & (mask & (1 << k) != 0);
    }
    (wi, ok)
}

impl Microfacet {
    /// A distribution; alphas are clamped to [1e-3, 10] (non-finite taken as 1e-3).
    pub fn new(dist: Distribution, alpha_u: f32, alpha_v: f32) -> Self {
        let c = |a: f32| {
            if a.is_finite() {
                a.clamp(MIN_ALPHA, 10.0)
            } else {
                MIN_ALPHA
            }
        };
        Microfacet {
            dist,
            alpha_u: c(alpha_u),
            alpha_v: c(alpha_v),
        }
    }

    /// D(m) per unit solid angle of m (projected area normalised: int D(m) m.z dm = 1).
    pub fn d(&self, m: Vec3) -> f32 {
        match self.dist {
            Distribution::Ggx => d_of::<false>(self.alpha_u, self.alpha_v, m),
            Distribution::Beckmann => d_of::<true>(self.alpha_u, self.alpha_v, m),
        }
    }

    /// Smith Lambda(w) for the side `w` is on (uses |w.z|).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn lambda(&self, w: Vec3) -> f32 {
        match self.dist {
            Distribution::Ggx => lambda_of::<false>(self.alpha_u, self.alpha_v, w),
            Distribution::Beckmann => lambda_of::<true>(self.alpha_u, self.alpha_v, w),
        }
    }

    /// Smith G1(w) = 1/(1 + Lambda(w)).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Separable masking-shadowing G2(wo, wi) = G1(wo) G1(wi) (Walter et al. 2007 eq. 23, as
    /// Mitsuba 3); see the module doc for why not the height-correlated form.
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.g1(wo) * self.g1(wi)
    }

    /// Density (solid angle of m) of the normals [`Microfacet::sample_m`] draws, for `wo.z > 0`:
    /// the visible normals `D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z` (both distributions).
    pub fn pdf_m(&self, wo: Vec3, m: Vec3) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo.dot(m).max(0.0) * self.d(m) / wo.z
    }

    /// Solid-angle pdf of reflecting `wo` into `wi` about a normal drawn by
    /// [`Microfacet::sample_m`]: `pdf_m(wo, h) / (4 wo.h)` with `h = normalize(wo + wi)` (Walter
    /// et al. 2007 eq. 14); 0 below the surface, for back-facing `h` and where it is not finite.
    /// Shared by every model with a microfacet reflection lobe.
    pub fn reflection_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize_or_zero();
        let woh = wo.dot(h);
        if h.z <= 0.0 || woh <= 0.0 {
            return 0.0;
        }
        let p = self.pdf_m(wo, h) / (4.0 * woh);
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    /// The reflection of a rough dielectric interface of relative index `eta`, without the
    /// cosine: F(wo.h) D(h) G(wo, wi) / (4 cos_o cos_i) (Walter et al. 2007 eq. 20), for `wo`
    /// and `wi` above the surface; 0 outside the support of [`Microfacet::reflection_pdf`] and
    /// where it is not finite. That support matters at grazing angles: wo.h, positive in exact
    /// arithmetic, can round to <= 0 where D / (4 cos cos) is ~1e12 at alpha 1e-3, and a sample
    /// of another lobe landing there got a weight of 1e14 (`pt stability`, Beckmann alpha 1e-3
    /// at 89.99 degrees). The coated models' specular term (`roughplastic`, `pplastic`).
    pub fn dielectric_reflection(&self, wo: Vec3, wi: Vec3, eta: f32) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize_or_zero();
        if h.z <= 0.0 || wo.dot(h) <= 0.0 {
            return 0.0;
        }
        let v =
            fresnel_dielectric(wo.dot(h), eta) * self.d(h) * self.g2(wo, wi) / (4.0 * wo.z * wi.z);
        if v.is_finite() {
            v
        } else {
            0.0
        }
    }

    /// [`Microfacet::dielectric_reflection`] and [`Microfacet::reflection_pdf`] of the same
    /// pair, the same values (the same operations in the same order) with the half vector,
    /// D(h) and G1(wo) computed once. (One lane of [`dielectric_reflection_pdf_of`].)
    pub fn dielectric_reflection_pdf(&self, wo: Vec3, wi: Vec3, eta: f32) -> (f32, f32) {
        let (ax, ay) = (self.alpha_u, self.alpha_v);
        match self.dist {
            Distribution::Ggx => dielectric_reflection_pdf_of::<false>(ax, ay, wo, wi, eta),
            Distribution::Beckmann => dielectric_reflection_pdf_of::<true>(ax, ay, wo, wi, eta),
        }
    }

    /// Draws a normal for `wo` (`wo.z > 0`) and reflects `wo` about it: the direction whose
    /// density is [`Microfacet::reflection_pdf`], or `None` when it falls below the surface.
    pub fn sample_reflection(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        let (wi, ok) = reflect_about(wo, self.sample_m(wo, u));
        ok.then_some(wi)
    }

    /// [`Microfacet::sample_m`] for every pair of a grid of uniform numbers: the normal for
    /// (`us[i]`, `vs[j]`) at `[j * us.len() + i]`, the same normals. A Beckmann distribution
    /// away from normal incidence draws its two slopes from one number each, so each is solved
    /// once per row or column (the Newton iterations for slope_x once per `us[i]`, not per
    /// pair: the coating tables of `roughplastic` integrate over such grids).
    pub fn sample_m_grid(&self, wo: Vec3, us: &[f32], vs: &[f32]) -> Vec<Vec3> {
        let per_pair = || {
            vs.iter()
                .flat_map(|&v| us.iter().map(move |&u| (u, v)))
                .map(|(u, v)| self.sample_m(wo, Vec2::new(u, v)))
                .collect()
        };
        if self.dist != Distribution::Beckmann {
            return per_pair();
        }
        let (ax, ay) = (self.alpha_u, self.alpha_v);
        let ws = beckmann_stretched(ax, ay, wo);
        let cos_theta = ws.z.clamp(0.0, 1.0);
        if beckmann_normal_incidence(cos_theta) {
            return per_pair();
        }
        let sx: Vec<f32> = us.iter().map(|&u| beckmann_slope_x(cos_theta, u)).collect();
        vs.iter()
            .flat_map(|&v| {
                let sy = beckmann_slope_y(v);
                sx.iter()
                    .map(move |&sx| beckmann_normal(ax, ay, ws, sx, sy))
            })
            .collect()
    }

    /// Samples a microfacet normal (upper hemisphere) for the viewer direction `wo` (`wo.z > 0`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sample_m(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let (ax, ay) = (self.alpha_u, self.alpha_v);
        match self.dist {
            Distribution::Ggx => {
                let (sin_phi, cos_phi) = pt_math::fastmath::sin_cos_turns(u.y);
                ggx_visible_normal(ax, ay, wo, u.x, sin_phi, cos_phi)
            }
            Distribution::Beckmann => {
                let wo = V3::splat(wo);
                let m = beckmann_visible_normals(&[ax], &[ay], &wo, &[u.x], &[u.y], 1);
                m.get(0)
            }
        }
    }
}

/// The generalised half vector of a pair at an interface of relative index `eta` (inside /
/// outside): `h = normalize(eta' wi + wo)` turned to face +z, with `eta' = 1` for a reflection
/// (both directions on one side) and the index on `wi`'s side over `wo`'s side for a refraction
/// (Walter et al. 2007 eqs. 13 and 16). Returns `(h, eta', reflect)`, or `None` for grazing
/// directions, a degenerate pair, or a micro-normal facing away from either direction.
pub fn generalized_half(wo: Vec3, wi: Vec3, eta: f32) -> Option<(Vec3, f32, bool)> {
    let (co, ci) = (wo.z, wi.z);
    if co == 0.0 || ci == 0.0 {
        return None;
    }
    let reflect = co * ci > 0.0;
    let etap = if reflect {
        1.0
    } else if co > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let hv = wi * etap + wo;
    if hv.length_squared() == 0.0 {
        return None;
    }
    let mut h = hv.normalize();
    if h.z < 0.0 {
        h = -h;
    }
    if h.z == 0.0 || h.dot(wi) * ci <= 0.0 || h.dot(wo) * co <= 0.0 {
        return None;
    }
    Some((h, etap, reflect))
}

/// Solid-angle pdf of `wi` for an interface sampled by drawing a normal for `wo` (facing up)
/// and reflecting with probability `p_reflect`, else refracting (Walter et al. 2007 eqs. 14 and
/// 17): reflection `pdf_m(h) p / (4 |wo.h|)`, refraction
/// `pdf_m(h) (1 - p) |wi.h| / (wi.h + wo.h/eta')^2`; `h`, `eta'`, `reflect` from
/// [`generalized_half`]. 0 where not finite.
pub fn interface_pdf(
    mf: &Microfacet,
    wo: Vec3,
    wi: Vec3,
    (h, etap, reflect): (Vec3, f32, bool),
    p_reflect: f32,
) -> f32 {
    let wo_up = if wo.z < 0.0 { -wo } else { wo };
    let pm = mf.pdf_m(wo_up, h);
    let p = if reflect {
        pm * p_reflect / (4.0 * wo.dot(h).abs())
    } else {
        pm * (1.0 - p_reflect) * wi.dot(h).abs() / (wi.dot(h) + wo.dot(h) / etap).powi(2)
    };
    if p.is_finite() {
        p
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid sampler draws exactly `sample_m`'s normals (bit for bit: the coating tables
    /// built from it must not change), for both distributions, isotropic and anisotropic, at
    /// grazing, oblique and normal incidence (the Beckmann normal-incidence branch is not
    /// separable and is taken per pair).
    #[test]
    fn grid_sampling_is_sample_m() {
        let us: Vec<f32> = (0..37).map(|k| (k as f32 + 0.5) / 37.0).collect();
        let vs: Vec<f32> = (0..23).map(|k| (k as f32 + 0.25) / 23.0).collect();
        for dist in [Distribution::Beckmann, Distribution::Ggx] {
            for (au, av) in [(0.3, 0.3), (0.05, 0.6)] {
                let mf = Microfacet::new(dist, au, av);
                for wo in [
                    Vec3::new(0.999, 0.0, 0.02),
                    Vec3::new(0.5, 0.3, 0.8),
                    Vec3::new(-0.2, 0.7, 0.4),
                    Vec3::Z,
                ] {
                    let wo = wo.normalize();
                    let grid = mf.sample_m_grid(wo, &us, &vs);
                    for (j, &v) in vs.iter().enumerate() {
                        for (i, &u) in us.iter().enumerate() {
                            let m = mf.sample_m(wo, Vec2::new(u, v));
                            assert_eq!(grid[j * us.len() + i], m, "{dist:?} {wo} {u} {v}");
                        }
                    }
                }
            }
        }
    }

    /// Giles' f32 inverse against the exact inverse (Newton's method on libm's f64 erf, checked
    /// to invert it to 1e-14): within 1e-6 relative over (-1, 1), a few f32 roundings (Giles'
    /// design accuracy is about 1e-7; a wrong coefficient is off by far more).
    #[test]
    fn erf_inv_inverts_erf() {
        let exact = |y: f64| {
            let mut x = f64::from(erf_inv_giles(y as f32));
            for _ in 0..3 {
                let slope = 2.0 / std::f64::consts::PI.sqrt() * (-x * x).exp();
                x -= (libm::erf(x) - y) / slope;
            }
            assert!((libm::erf(x) - y).abs() < 1e-14, "{y}");
            x
        };
        for k in 1..2000 {
            let y = -1.0 + 2.0 * k as f32 / 2000.0;
            let (a, b) = (f64::from(erf_inv_giles(y)), exact(f64::from(y)));
            assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-3), "{y}: {a} vs {b}");
        }
        assert!(erf_inv_giles(1.0).is_infinite() && erf_inv_giles(-1.0).is_infinite());
    }

    #[test]
    fn beckmann_visible_slopes_stay_in_front_of_the_viewer() {
        // Every sampled normal faces the viewer (wo.m > 0), at every incidence.
        let mf = Microfacet::new(Distribution::Beckmann, 0.4, 0.4);
        for th in [0.0f32, 30.0, 70.0, 85.0, 89.0, 89.9] {
            let wo = Vec3::new(th.to_radians().sin(), 0.0, th.to_radians().cos());
            for i in 0..64 {
                for j in 0..64 {
                    let u = Vec2::new((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0);
                    let m = mf.sample_m(wo, u);
                    assert!(
                        m.is_finite() && m.z > 0.0 && wo.dot(m) > -1e-5,
                        "theta {th}: m {m:?}"
                    );
                }
            }
        }
    }

    /// int D(m) m.z dm = 1 and int D_wo(m) dm = 1 (GGX), by quadrature.
    #[test]
    fn normalisation() {
        for dist in [Distribution::Ggx, Distribution::Beckmann] {
            for (ax, ay) in [(0.3f32, 0.3f32), (0.1, 0.5), (0.8, 0.8)] {
                let mf = Microfacet::new(dist, ax, ay);
                let cells = pt_testkit::integrate_cells(
                    &|m: Vec3| f64::from(mf.d(m) * m.z.max(0.0)),
                    32,
                    64,
                    1e-9,
                    1e-5,
                );
                let s: f64 = cells.iter().sum();
                assert!((s - 1.0).abs() < 2e-3, "{dist:?} {ax} {ay}: {s}");
                let wo = pt_testkit::dir_deg(70.0, 30.0);
                // Projected area of visible normals = wo.z: int <wo.m>+ D G1 dm = wo.z (Heitz 2014 eq. 18).
                let cells = pt_testkit::integrate_cells(
                    &|m: Vec3| f64::from(mf.g1(wo) * wo.dot(m).max(0.0) * mf.d(m)),
                    32,
                    64,
                    1e-9,
                    1e-5,
                );
                let s: f64 = cells.iter().sum();
                assert!(
                    (s - f64::from(wo.z)).abs() < 3e-3,
                    "{dist:?} {ax} {ay}: {s} vs {}",
                    wo.z
                );
            }
        }
    }
}
