//! Mitsuba's `linearcurve` and `bsplinecurve` shapes, one segment at a time: tubes of varying
//! radius around a polyline or a uniform cubic B-spline. World space throughout.
//!
//! - **Linear segments** are round cones: the union of the spheres whose centre moves linearly
//!   from one control point to the next while the radius moves linearly from one radius to the
//!   other, which is the convex hull of the two end spheres. Consecutive segments share their
//!   joint sphere and every curve ends in a sphere (Mitsuba 3.9.1 renders them so, through
//!   Embree's round linear curves).
//! - **B-spline segments** are the tube swept by the circle of radius `r(u)` around the curve
//!   point `c(u)`, across the tangent `c'(u)`, for `u` in [0, 1]; the ends are open (no caps),
//!   as in Mitsuba 3.9.1. Its normal (Mitsuba's, from the implicit form below) is
//!   `(|c'|^2 - (p - c).c'') (p - c) - r r' c'`: the gradient of `|p - c(u)|^2 - r(u)^2` with
//!   `u(p)` the foot parameter where `(p - c(u)).c'(u) = 0`.
//! - **Back faces are culled** (Mitsuba's documented behaviour for both): a ray from inside a
//!   tube does not hit it, so a fibre's BSDF accounts for the walk through the fibre.
//!
//! The B-spline intersection is the "phantom" iteration of Reshetov and Luebke 2018 ("Phantom
//! Ray-Hair Intersector", Proc. ACM CGIT 1(2), sec. 3): at the current curve parameter `u`, the
//! ray is intersected with the cone tangent to the tube along the circle at `u` (axis `c'`,
//! radius `r`, slope `r' / |c'|`); the hit's offset along the cone's axis, over `|c'|`, moves
//! `u`. At the fixed point the hit lies on the circle at `u`, that is on the tube. The iteration
//! starts from both ends of the segment and its middle and keeps the nearest front-facing hit
//! with `u` in [0, 1]. Two safeguards of ours: a box test in the ray's own frame before any
//! iteration, and a step back (bisection towards the last parameter whose cone the ray met)
//! when the ray misses the cone, which rays grazing a strand along its length do.

use pt_math::{Vec2, Vec3, Vec3A};

/// The uniform cubic B-spline basis at `u` in [0, 1]: weights of the four control points of a
/// segment for the point, the first and the second derivative (with respect to `u`).
#[inline(always)]
pub fn bspline_basis(u: f32) -> [[f32; 4]; 3] {
    let (u2, u3, w) = (u * u, u * u * u, 1.0 - u);
    let sixth = 1.0 / 6.0;
    [
        [
            w * w * w * sixth,
            (3.0 * u3 - 6.0 * u2 + 4.0) * sixth,
            (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) * sixth,
            u3 * sixth,
        ],
        [
            -0.5 * w * w,
            0.5 * (3.0 * u2 - 4.0 * u),
            0.5 * (-3.0 * u2 + 2.0 * u + 1.0),
            0.5 * u2,
        ],
        [w, 3.0 * u - 2.0, 1.0 - 3.0 * u, u],
    ]
}

/// A B-spline segment evaluated at one parameter: centre, first and second derivative of
/// the centre, radius and its first derivative (all with respect to the segment's `u`).
#[derive(Clone, Copy, Debug)]
pub struct CurvePoint {
    /// Centre `c(u)`.
    pub c: Vec3A,
    /// `c'(u)`.
    pub dc: Vec3A,
    /// `c''(u)`.
    pub ddc: Vec3A,
    /// Radius `r(u)`.
    pub r: f32,
    /// `r'(u)`.
    pub dr: f32,
}

/// The segment with control points `p` and radii `r` at `u`.
#[inline(always)]
pub fn bspline_eval(p: &[Vec3A; 4], r: &[f32; 4], u: f32) -> CurvePoint {
    let [b, db, ddb] = bspline_basis(u);
    let sum = |w: [f32; 4]| p[0] * w[0] + p[1] * w[1] + p[2] * w[2] + p[3] * w[3];
    let dot = |w: [f32; 4]| r[0] * w[0] + r[1] * w[1] + r[2] * w[2] + r[3] * w[3];
    CurvePoint {
        c: sum(b),
        dc: sum(db),
        ddc: sum(ddb),
        r: dot(b),
        dr: dot(db),
    }
}

/// The Bézier control points of the B-spline segment `p` (the same cubic): the curve lies in
/// their convex hull, which is tighter than the B-spline points' hull. Also for radii.
#[inline]
pub fn bspline_to_bezier<T>(p: [T; 4]) -> [T; 4]
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T>,
{
    let third = 1.0 / 3.0;
    let sixth = 1.0 / 6.0;
    [
        (p[0] + p[1] * 4.0 + p[2]) * sixth,
        (p[1] * 2.0 + p[2]) * third,
        (p[1] + p[2] * 2.0) * third,
        (p[1] + p[2] * 4.0 + p[3]) * sixth,
    ]
}

/// The bounds (min, max corners) of a B-spline segment's tube: the box of its Bézier control
/// points grown by the largest radius (a convex combination of the Bézier radii).
pub fn bspline_bounds(p: &[Vec3A; 4], r: &[f32; 4]) -> (Vec3A, Vec3A) {
    let b = bspline_to_bezier(*p);
    let rb = bspline_to_bezier(*r);
    let grow = Vec3A::splat(rb.iter().fold(0.0f32, |m, &x| m.max(x)));
    let lo = b[0].min(b[1]).min(b[2]).min(b[3]);
    let hi = b[0].max(b[1]).max(b[2]).max(b[3]);
    (lo - grow, hi + grow)
}

/// A part of a B-spline segment: piece `index` of `2^log2_count` equal ranges of its
/// parameter. The BVH holds a long segment as several pieces, each with its own four control
/// points (the same cubic over the piece's range), so that each box is tight around its part
/// of a thin strand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Piece {
    /// Which piece, from the segment's start (< `2^log2_count`).
    pub index: u8,
    /// The segment is cut into `2^log2_count` pieces (at most [`Piece::MAX_LOG2`]).
    pub log2_count: u8,
}

/// A segment is cut into pieces about this many radii long (measured along its Bézier
/// control polygon): a piece's box is then a few radii across, whatever its orientation.
const PIECE_LENGTH_IN_RADII: f32 = 8.0;

impl Piece {
    /// A whole segment.
    pub const WHOLE: Piece = Piece {
        index: 0,
        log2_count: 0,
    };
    /// At most 2^4 = 16 pieces per segment.
    pub const MAX_LOG2: u8 = 4;

    /// The piece as one byte (count in the high nibble, index in the low one).
    pub fn code(self) -> u8 {
        (self.log2_count << 4) | self.index
    }

    /// The piece [`Piece::code`] made.
    pub fn from_code(code: u8) -> Piece {
        let log2_count = (code >> 4).min(Piece::MAX_LOG2);
        Piece {
            index: (code & 15) & ((1u8 << log2_count) - 1),
            log2_count,
        }
    }

    /// The piece's range of the segment's parameter.
    pub fn range(self) -> (f32, f32) {
        let n = (1u32 << self.log2_count) as f32;
        (self.index as f32 / n, (self.index as f32 + 1.0) / n)
    }

    /// The pieces a segment (control points xyz, radius w) is cut into: enough (a power of two,
    /// at most 16) that each is about [`PIECE_LENGTH_IN_RADII`] of its largest radius long.
    pub fn split(cp: [pt_math::Vec4; 4]) -> impl Iterator<Item = Piece> {
        let b = bspline_to_bezier(cp.map(|p| p.truncate()));
        let length = (b[1] - b[0]).length() + (b[2] - b[1]).length() + (b[3] - b[2]).length();
        let r_max = bspline_to_bezier(cp.map(|p| p.w))
            .iter()
            .fold(0.0f32, |m, &x| m.max(x));
        let want = length / (PIECE_LENGTH_IN_RADII * r_max);
        let log2_count = if want > 1.0 {
            (want.log2().ceil() as u8).min(Piece::MAX_LOG2)
        } else {
            0
        };
        (0..1u8 << log2_count).map(move |index| Piece { index, log2_count })
    }

    /// The piece's own control points and radii, from the segment's: the same cubic over the
    /// piece's range with its parameter running from 0 to 1. Computed in f64 (the conversion
    /// back to B-spline points amplifies rounding tenfold).
    pub fn of(self, p: [Vec3; 4], r: [f32; 4]) -> ([Vec3; 4], [f32; 4]) {
        if self.log2_count == 0 {
            return (p, r);
        }
        let (u0, u1) = self.range();
        let (u0, u1) = (u0 as f64, u1 as f64);
        let xyzr: [[f64; 4]; 4] =
            std::array::from_fn(|i| [p[i].x, p[i].y, p[i].z, r[i]].map(f64::from));
        let out = sub_bspline(xyzr, u0, u1);
        (
            out.map(|q| Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32)),
            out.map(|q| (q[3] as f32).max(0.0)),
        )
    }
}

/// The B-spline control points (per coordinate) of the cubic that the segment `p` traces over
/// [u0, u1], reparameterised to [0, 1]: its Bézier points restricted by blossoming (the
/// sub-curve's Bézier points are the blossom at (u0, u0, u0), (u0, u0, u1), (u0, u1, u1),
/// (u1, u1, u1); de Casteljau with one parameter per level), then converted back to B-spline
/// points (the inverse of [`bspline_to_bezier`]).
fn sub_bspline(p: [[f64; 4]; 4], u0: f64, u1: f64) -> [[f64; 4]; 4] {
    let lerp = |a: [f64; 4], b: [f64; 4], t: f64| std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t);
    let bez: [[f64; 4]; 4] = {
        let (third, sixth) = (1.0 / 3.0, 1.0 / 6.0);
        let f = |w: [f64; 4]| -> [f64; 4] {
            std::array::from_fn(|k| {
                w[0] * p[0][k] + w[1] * p[1][k] + w[2] * p[2][k] + w[3] * p[3][k]
            })
        };
        [
            f([sixth, 4.0 * sixth, sixth, 0.0]),
            f([0.0, 2.0 * third, third, 0.0]),
            f([0.0, third, 2.0 * third, 0.0]),
            f([0.0, sixth, 4.0 * sixth, sixth]),
        ]
    };
    let blossom = |x: f64, y: f64, z: f64| {
        let l1 = [
            lerp(bez[0], bez[1], x),
            lerp(bez[1], bez[2], x),
            lerp(bez[2], bez[3], x),
        ];
        let l2 = [lerp(l1[0], l1[1], y), lerp(l1[1], l1[2], y)];
        lerp(l2[0], l2[1], z)
    };
    let b = [
        blossom(u0, u0, u0),
        blossom(u0, u0, u1),
        blossom(u0, u1, u1),
        blossom(u1, u1, u1),
    ];
    let p1: [f64; 4] = std::array::from_fn(|k| 2.0 * b[1][k] - b[2][k]);
    let p2: [f64; 4] = std::array::from_fn(|k| 2.0 * b[2][k] - b[1][k]);
    let p0 = std::array::from_fn(|k| 6.0 * b[0][k] - 4.0 * p1[k] - p2[k]);
    let p3 = std::array::from_fn(|k| 6.0 * b[3][k] - p1[k] - 4.0 * p2[k]);
    [p0, p1, p2, p3]
}

/// The outward normal (not normalised) of a B-spline tube at `p`, on the circle at the
/// evaluated point `e` (Mitsuba's formula, see the module documentation).
#[inline(always)]
pub fn bspline_normal(e: &CurvePoint, p: Vec3A) -> Vec3A {
    let rad = p - e.c;
    (e.dc.length_squared() - rad.dot(e.ddc)) * rad - (e.r * e.dr) * e.dc
}

/// How far (in the parameter) beyond its range a piece still counts a hit: rounding at the
/// seam between two pieces, far below a radius.
const SEAM: f32 = 1e-5;

/// Most phantom iterations from one starting parameter: the iteration converges in a handful
/// from an end of a hair-like segment; one that has not settled after this many is taken as a
/// miss from that start.
const PHANTOM_ITERATIONS: usize = 24;

/// The ray `o + t d` (`d` unit length) against the B-spline segment with control points `p`
/// and radii `r` (world space): `(t, u)` of the nearest front-facing hit with `t` in
/// `(tmin, tmax)` and `u` in [0, 1], or `t` = +inf.
pub fn intersect_bspline(
    o: Vec3A,
    d: Vec3A,
    p: &[Vec3A; 4],
    r: &[f32; 4],
    tmin: f32,
    tmax: f32,
) -> (f32, f32) {
    // Relative to the ray origin: the tube is thin, and its position relative to the ray is
    // what decides a hit.
    let q = p.map(|x| x - o);
    let r_max = r.iter().fold(0.0f32, |m, &x| m.max(x));
    // Converged when the hit is this close (along the axis) to the circle at u: 1e-4 of the
    // radius. The hit is on the cone tangent to the tube there, so its distance along the ray
    // is off by the square of that (times the curvature), far below rounding.
    let tolerance = 1e-4 * r_max;
    let mut best = (f32::INFINITY, 0.0);
    let b = bspline_to_bezier(q);
    if !ray_near_bspline(d, &b, r_max, tmin, tmax) {
        return best;
    }
    // A piece no longer than a few radii (as `Piece::split` makes them) is nearly straight:
    // a ray enters it at most once, so the first hit found is the hit, and where the ray
    // passes closest to it without meeting it, it misses it.
    let polygon = (b[1] - b[0]).length() + (b[2] - b[1]).length() + (b[3] - b[2]).length();
    let short = polygon <= 2.0 * PIECE_LENGTH_IN_RADII * r_max;
    let mut settled_miss = false;
    // From both ends, and from the middle for strongly bent segments that the ray crosses
    // nearly along (from the ends, the iteration can leave the segment before it settles).
    for start in [0.0f32, 1.0, 0.5] {
        // The middle only when the ends found nothing; nothing more once a short piece's hit
        // is found.
        if (start == 0.5 || short) && best.0.is_finite() || short && settled_miss {
            break;
        }
        let mut u = start;
        // The last parameter whose cone the ray met.
        let mut last_hit: Option<f32> = None;
        // Whether the last step was stopped at an end of the piece.
        let mut at_end = false;
        for _ in 0..PHANTOM_ITERATIONS {
            let e = bspline_eval(&q, r, u);
            let len = e.dc.length();
            if !(len > 0.0) {
                break;
            }
            let axis = e.dc / len;
            let (hit, s, dz) = cone_step(d, axis, e.c, e.r, e.dr / len);
            if hit && dz.abs() <= tolerance {
                let front = bspline_normal(&e, d * s).dot(d) < 0.0;
                // Pieces and segments share their end circles; a hit on the seam may come out
                // a rounding error beyond either piece's range, so both accept that margin.
                #[allow(clippy::manual_range_contains)]
                if front && s > tmin && s < tmax.min(best.0) && u >= -SEAM && u <= 1.0 + SEAM {
                    best = (s, u.clamp(0.0, 1.0));
                }
                break;
            }
            // Settled where the ray passes closest to the curve without meeting the cone
            // there, and no cone met before: the ray misses the tube (from this start).
            if !hit && last_hit.is_none() && dz.abs() <= tolerance {
                // A short piece's closest approach is the only one: no other start can hit.
                settled_miss = true;
                break;
            }
            u = match (hit, last_hit) {
                // A ray that grazes the tube can miss the cone one step past a parameter
                // whose cone it met, while it meets the tube in between: bisect back
                // towards that parameter instead of jumping to where the ray passes closest
                // to this cone's axis (far away for a ray along the strand).
                (false, Some(h)) => {
                    if (u - h).abs() <= 1e-6 {
                        break;
                    }
                    0.5 * (u + h)
                }
                // Newton-like step along the curve.
                _ => {
                    if hit {
                        last_hit = Some(u);
                    }
                    u + dz / len
                }
            };
            // Beyond the piece the hit belongs to the neighbour or to nothing: the iteration
            // stops at the end, and gives up when it is pushed out again from there.
            if !(0.0..=1.0).contains(&u) {
                if at_end {
                    break;
                }
                u = u.clamp(0.0, 1.0);
                at_end = true;
            } else {
                at_end = false;
            }
        }
    }
    best
}

/// Whether the ray from the origin along `d` (unit length) may meet the tube of the
/// B-spline segment with Bézier points `b` (relative to the ray origin) whose radius is at most
/// `r_max` within `(tmin, tmax)`. In the ray's own frame (two axes across it, one along it) the
/// ray is the origin of the plane across it; the projected curve lies in the hull of its
/// projected Bézier points, so within `dev` of the projected chord between its ends, `dev`
/// the larger distance of the two inner Bézier points from that chord (distance to a segment
/// is convex: its largest over a hull is at a corner). The ray can meet the tube only if the
/// origin lies within `dev + r_max` of the projected chord, and the segment's extent along the
/// ray overlaps `(tmin, tmax)`. For a thin, nearly straight piece this is a tight capsule, and
/// it rejects most of what the BVH hands over before any iteration.
#[inline(always)]
fn ray_near_bspline(d: Vec3A, b: &[Vec3A; 4], r_max: f32, tmin: f32, tmax: f32) -> bool {
    let f = pt_math::Frame::from_normal(d.into());
    let (x, y) = (Vec3A::from(f.s), Vec3A::from(f.t));
    let flat = b.map(|p| Vec2::new(p.dot(x), p.dot(y)));
    let along = b.map(|p| p.dot(d));
    let lo = along.iter().fold(f32::INFINITY, |m, &z| m.min(z)) - r_max;
    let hi = along.iter().fold(f32::NEG_INFINITY, |m, &z| m.max(z)) + r_max;
    if !(hi > tmin && lo < tmax) {
        return false;
    }
    // Distance of a point from the projected chord flat[0] -> flat[3].
    let chord = flat[3] - flat[0];
    let len2 = chord.length_squared();
    let dist = |p: Vec2| {
        let t = if len2 > 0.0 {
            ((p - flat[0]).dot(chord) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - flat[0] - chord * t).length()
    };
    let dev = dist(flat[1]).max(dist(flat[2]));
    dist(Vec2::ZERO) <= dev + r_max
}

/// One phantom step: the line `s d` (from the origin, `d` unit length) against the cone with
/// unit axis `axis` through `c`, radius `r` at `c` and slope `k` (radius per unit length along
/// the axis). Returns whether the line meets the cone's front side, the line parameter `s` of
/// that entry (or, on a miss, of the line's closest approach to the axis), and the offset
/// `dz` of that point from `c` along the axis.
///
/// The quadratic is solved about the line's point nearest to `c`, `s0 = c.d`: its
/// coefficients are then of the tube's size, not of its distance, which keeps rounding far
/// below the radius (as Haines et al. 2019 do for spheres).
#[inline(always)]
fn cone_step(d: Vec3A, axis: Vec3A, c: Vec3A, r: f32, k: f32) -> (bool, f32, f32) {
    let s0 = c.dot(d);
    let c = c - d * s0; // from the line's point at s0 to the centre: about a radius long
    let (az, ca) = (d.dot(axis), c.dot(axis));
    // Perpendicular parts, computed as vectors.
    let c_perp = c - axis * ca;
    let d_perp = d - axis * az;
    // The radius along the line: r + k (s az - ca) = r0 + k az s (s from s0 now).
    let r0 = r - k * ca;
    let d2 = d_perp.length_squared();
    let a = d2 - k * k * az * az;
    let b = -2.0 * c_perp.dot(d_perp) - 2.0 * r0 * k * az;
    let cc = c_perp.length_squared() - r0 * r0;
    let disc = b * b - 4.0 * a * cc;
    let mut hit = false;
    let mut s = if d2 > 0.0 {
        c_perp.dot(d_perp) / d2
    } else {
        0.0
    };
    // The ray enters the cone where F(s) = a s^2 + b s + cc (the squared distance from the
    // axis minus the squared radius there: positive outside) falls through zero, where
    // F'(s) = 2 a s + b = -sqrt(disc). That root is (-b - sqrt(disc)) / 2a for either sign of
    // a (a < 0 for a ray closer to the axis direction than the cone's half angle), computed
    // in the stable form: q = -(b + sign(b) sqrt(disc)) / 2 gives it as q / a when b >= 0 and
    // as cc / q otherwise.
    if disc >= 0.0 {
        let sq = disc.sqrt();
        let qq = -0.5 * (b + if b >= 0.0 { sq } else { -sq });
        let entry = if b >= 0.0 { qq / a } else { cc / qq };
        // On the nappe whose radius is positive.
        if entry.is_finite() && r0 + k * az * entry >= 0.0 {
            s = entry;
            hit = true;
        }
    }
    (hit, s0 + s, s * az - ca)
}

/// The ray `o + t d` (`d` unit length) against a linear segment, the round cone from the sphere
/// of radius `ra` at `a` to the sphere of radius `rb` at `b`: `(t, v)` of the nearest
/// front-facing hit with `t` in `(tmin, tmax)`, `v` in [0, 1] the parameter of the sphere
/// (centre `a + v (b - a)`) whose surface the hit lies on; `t` = +inf on a miss.
///
/// The round cone is the union of its two spheres and the cone tangent to both between its
/// circles of contact; outside it, the first entry into any of the three is the entry into the
/// union, so the nearest entry of the three is the hit (exits are back faces, culled).
#[allow(clippy::too_many_arguments)]
pub fn intersect_round_cone(
    o: Vec3A,
    d: Vec3A,
    a: Vec3A,
    b: Vec3A,
    ra: f32,
    rb: f32,
    tmin: f32,
    tmax: f32,
) -> (f32, f32) {
    let mut best = (f32::INFINITY, 0.0);
    for (centre, radius, v) in [(a, ra, 0.0), (b, rb, 1.0)] {
        let t = sphere_entry(o, d, centre, radius);
        if t > tmin && t < tmax.min(best.0) {
            best = (t, v);
        }
    }
    let ab = b - a;
    let len = ab.length();
    let sin_a = (ra - rb) / len;
    // One sphere inside the other (or a point): no cone part.
    if !(sin_a.abs() < 1.0) {
        return best;
    }
    let cos2 = 1.0 - sin_a * sin_a;
    let w = ab / len;
    // In the plane through the axis: axial coordinate z from `a`, distance q from the axis;
    // the cone's profile is the line z sin_a + q cos_a = ra, tangent to both circles.
    let y = o - a;
    let (z0, dz) = (y.dot(w), d.dot(w));
    let (y_perp, d_perp) = (y - w * z0, d - w * dz);
    let h0 = ra - sin_a * z0; // q cos_a along the line at s = 0 is h0 - sin_a dz s
    let qa = cos2 * d_perp.length_squared() - sin_a * sin_a * dz * dz;
    let qb = 2.0 * cos2 * y_perp.dot(d_perp) + 2.0 * sin_a * dz * h0;
    let qc = cos2 * y_perp.length_squared() - h0 * h0;
    let disc = qb * qb - 4.0 * qa * qc;
    if !(disc >= 0.0) || qa == 0.0 {
        return best;
    }
    let sq = disc.sqrt();
    let qq = -0.5 * (qb + if qb >= 0.0 { sq } else { -sq });
    let roots = if qq == 0.0 {
        [0.0, 0.0]
    } else {
        [qq / qa, qc / qq]
    };
    for s in roots {
        if !(s > tmin && s < tmax.min(best.0)) {
            continue;
        }
        let h = h0 - sin_a * dz * s; // = q cos_a on the right nappe
        if !(h > 0.0) {
            continue;
        }
        let z = z0 + dz * s;
        let radial = y_perp + d_perp * s;
        let q = radial.length();
        // The contact sphere's centre along the axis: z - r sin_a with r = q / cos_a.
        let cos_a = cos2.sqrt();
        let v = (z - q * sin_a / cos_a) / len;
        if !(0.0..=1.0).contains(&v) || q == 0.0 {
            continue;
        }
        let n = w * sin_a + radial * (cos_a / q);
        if n.dot(d) < 0.0 {
            best = (s, v);
        }
    }
    best
}

/// The distance along `o + t d` (`d` unit length) at which the ray enters the sphere, or
/// -inf when it does not (the exit is a back face).
#[inline(always)]
fn sphere_entry(o: Vec3A, d: Vec3A, centre: Vec3A, radius: f32) -> f32 {
    let f = o - centre;
    let b = -f.dot(d);
    let perp = f + d * b;
    let disc = radius * radius - perp.length_squared();
    if !(disc >= 0.0) {
        return f32::NEG_INFINITY;
    }
    b - disc.sqrt()
}

/// The bounds (min, max corners) of a round cone: the boxes of its two spheres.
pub fn round_cone_bounds(a: Vec3A, b: Vec3A, ra: f32, rb: f32) -> (Vec3A, Vec3A) {
    (
        (a - Vec3A::splat(ra)).min(b - Vec3A::splat(rb)),
        (a + Vec3A::splat(ra)).max(b + Vec3A::splat(rb)),
    )
}

/// Mitsuba's frame across a curve's unit tangent `axis` that the angle around the curve (the
/// texture coordinate) is measured in: `(rot, rad)`, `rot` the world z axis made
/// perpendicular to the tangent (world y where the tangent is along z), `rad = rot x axis`.
/// The angle runs from `rad` towards `rot`.
pub fn curve_frame(axis: Vec3) -> (Vec3, Vec3) {
    let guide = Vec3::Z;
    let rot = if axis.dot(guide).abs() >= 1.0 {
        Vec3::Y
    } else {
        (guide - axis * axis.dot(guide)).normalize()
    };
    (rot, rot.cross(axis))
}

/// The texture coordinate around a curve: the angle of the unit radial direction `radial`
/// in [`curve_frame`] of `axis`, over 2 pi, in [0, 1).
pub fn around(axis: Vec3, radial: Vec3) -> f32 {
    let (rot, rad) = curve_frame(axis);
    let mut a = radial.dot(rot).atan2(radial.dot(rad));
    if a < 0.0 {
        a += std::f32::consts::TAU;
    }
    a / std::f32::consts::TAU
}

/// The surface at a curve hit, world space: what shading needs.
#[derive(Clone, Copy, Debug)]
pub struct CurveHit {
    /// The hit point, put back onto the tube (its distance from the centre made the radius).
    pub p: Vec3,
    /// Unit outward normal.
    pub n: Vec3,
    /// Texture coordinates: u the angle around the curve over 2 pi ([`around`]), v the
    /// position along all of the shape's segments, `(segment + parameter) / segments`
    /// (Mitsuba 3.9.1's parameterisation).
    pub uv: Vec2,
    /// dp/du: around the curve, `2 pi r (tangent x radial)`. With the normal it makes the
    /// shading frame whose second axis (`n x dp/du`) runs along the curve, which is the frame
    /// the `hair` BSDF reads (fibre along local y).
    pub dpdu: Vec3,
    /// dp/dv: along the curve, `segments (c' + r' radial)`.
    pub dpdv: Vec3,
}

/// The surface of a linear segment (`[a, b]`, radii `r`) at `p`, the hit whose contact
/// sphere has parameter `v` (as [`intersect_round_cone`] returns it); `segment` of the shape's
/// `segments`.
pub fn round_cone_hit(
    [a, b]: [Vec3A; 2],
    [ra, rb]: [f32; 2],
    v: f32,
    p: Vec3,
    segment: u32,
    segments: u32,
) -> CurveHit {
    let (a, b) = (Vec3::from(a), Vec3::from(b));
    let c = a + (b - a) * v;
    let r = ra + (rb - ra) * v;
    let axis = (b - a).normalize_or(Vec3::Z);
    let n = (p - c).normalize_or(curve_frame(axis).1);
    CurveHit {
        p: c + n * r,
        n,
        uv: Vec2::new(
            around(axis, n),
            (v + segment as f32) / segments.max(1) as f32,
        ),
        dpdu: std::f32::consts::TAU * r * axis.cross(n),
        dpdv: segments as f32 * ((b - a) + (rb - ra) * n),
    }
}

/// The surface of a B-spline piece (its own control points `cp` and radii `r`) at `p`, the
/// hit at the piece's parameter `u` (as [`intersect_bspline`] returns it); the piece covers
/// `range` of segment `segment` of the shape's `segments`.
pub fn bspline_hit(
    cp: &[Vec3A; 4],
    r: &[f32; 4],
    u: f32,
    p: Vec3,
    range: (f32, f32),
    segment: u32,
    segments: u32,
) -> CurveHit {
    // The piece's derivatives per unit of the segment's parameter, and where u falls in it.
    let per_segment = 1.0 / (range.1 - range.0);
    let u_segment = range.0 + (range.1 - range.0) * u;
    let e = bspline_eval(cp, r, u);
    let c = Vec3::from(e.c);
    let axis = Vec3::from(e.dc).normalize_or(Vec3::Z);
    let radial = (p - c).normalize_or(curve_frame(axis).1);
    let n = Vec3::from(bspline_normal(&e, Vec3A::from(p))).normalize_or(radial);
    CurveHit {
        p: c + radial * e.r,
        n,
        uv: Vec2::new(
            around(axis, radial),
            (u_segment + segment as f32) / segments.max(1) as f32,
        ),
        dpdu: std::f32::consts::TAU * e.r * axis.cross(radial),
        dpdv: segments as f32 * per_segment * (Vec3::from(e.dc) + radial * e.dr),
    }
}

#[cfg(test)]
mod tests;
