//! Mitsuba's `sdfgrid` shape, one voxel at a time: a signed distance function sampled at the
//! grid's vertices and interpolated trilinearly inside each voxel; the surface is its zero set.
//!
//! - Intersection: along a ray the trilinear interpolant is a cubic in the ray parameter; its
//!   first root inside the voxel is bracketed by splitting the voxel's span at the roots of
//!   the cubic's derivative, then refined by Newton's method safeguarded by bisection
//!   (Marmitt, Kleer, Wald and Friedrich 2004, "Fast and Accurate Ray-Voxel Intersection
//!   Techniques for Iso-Surface Ray Tracing"; the cubic's form: Hansson-Söderlund, Evans and
//!   Akenine-Möller 2022, "Ray Tracing of Signed Distance Function Grids", JCGT 11(3), sec. 3).
//!   The values where the ray enters and leaves the voxel are taken on the crossed faces
//!   exactly, so that two voxels sharing a face agree on the sign there and a surface close to
//!   the face is found by one of them (Mitsuba 3.9.1 does the same).
//! - Bounds: the box of the corners on the surface and the points where the surface crosses a
//!   voxel edge (Hansson-Söderlund and Akenine-Möller 2023, "Tight Bounding Boxes for Voxels
//!   and Bricks in a Signed Distance Field Ray Tracer"), which is what Mitsuba's BVH holds.
//! - Normals: the geometric normal is the interpolant's gradient; the `smooth` shading normal
//!   blends the gradients of the eight voxels around the grid vertex nearest to the point
//!   (Hansson-Söderlund et al. 2022, sec. 5), which is continuous across voxel faces.
//!
//! Coordinates: a voxel's local coordinates `w` run over [0, 1]^3 from its lowest corner; its
//! corner values are indexed `x + 2y + 4z`. World space is the voxel's box, `lo + w * size`
//! (the loader admits scales and a translation only, so voxels stay axis-aligned boxes).

use pt_math::Vec3;
use pt_scene::SdfGrid;

/// Bilinear interpolation of `f` (indexed u + 2v) at (u, v); exact at 0 and 1.
#[inline(always)]
fn bilerp(f: [f32; 4], u: f32, v: f32) -> f32 {
    let lerp = |a: f32, b: f32, t: f32| a * (1.0 - t) + b * t;
    lerp(lerp(f[0], f[1], u), lerp(f[2], f[3], u), v)
}

/// The trilinear interpolant of the corner values `f` at `w` (voxel-local).
#[inline(always)]
pub fn trilerp(f: &[f32; 8], w: Vec3) -> f32 {
    let lerp = |a: f32, b: f32, t: f32| a * (1.0 - t) + b * t;
    lerp(
        bilerp([f[0], f[1], f[2], f[3]], w.x, w.y),
        bilerp([f[4], f[5], f[6], f[7]], w.x, w.y),
        w.z,
    )
}

/// The gradient of [`trilerp`] with respect to `w`: each partial derivative is the bilinear
/// interpolant of the differences along the four edges parallel to its axis.
#[inline(always)]
pub fn trilerp_grad(f: &[f32; 8], w: Vec3) -> Vec3 {
    Vec3::new(
        bilerp(
            [f[1] - f[0], f[3] - f[2], f[5] - f[4], f[7] - f[6]],
            w.y,
            w.z,
        ),
        bilerp(
            [f[2] - f[0], f[3] - f[1], f[6] - f[4], f[7] - f[5]],
            w.x,
            w.z,
        ),
        bilerp(
            [f[4] - f[0], f[5] - f[1], f[6] - f[2], f[7] - f[3]],
            w.x,
            w.y,
        ),
    )
}

/// The tight box of the surface in a voxel (voxel-local): the corners where the value is 0
/// and the points where the surface crosses an edge (Hansson-Söderlund and Akenine-Möller
/// 2023). Inverted (min > max) if the surface does not pass through.
pub fn tight_bounds(f: &[f32; 8]) -> (Vec3, Vec3) {
    let corner = |i: usize| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32);
    let (mut lo, mut hi) = (Vec3::ONE, Vec3::ZERO);
    for (i, &fi) in f.iter().enumerate() {
        if fi == 0.0 {
            (lo, hi) = (lo.min(corner(i)), hi.max(corner(i)));
        }
    }
    for (i, &fi) in f.iter().enumerate() {
        for axis in 0..3 {
            if i & (1 << axis) != 0 {
                continue;
            }
            let fj = f[i | (1 << axis)];
            if fi * fj <= 0.0 && fi != fj {
                let mut p = corner(i);
                p[axis] = fi / (fi - fj);
                (lo, hi) = (lo.min(p), hi.max(p));
            }
        }
    }
    (lo, hi)
}

/// The world box the BVH holds for a voxel at `lo` of size `size`: its tight box, padded by
/// 1/1000 of the voxel and 8 ULPs of its coordinates so that rounding in the box tests cannot
/// drop a hit on its boundary (Mitsuba pads the same way).
pub fn voxel_bounds(lo: Vec3, size: Vec3, f: &[f32; 8]) -> (Vec3, Vec3) {
    let (a, b) = tight_bounds(f);
    let (min, max) = (lo + a * size, lo + b * size);
    let pad = size.abs() * 1e-3 + min.abs().max(max.abs()) * (8.0 * f32::EPSILON);
    (min - pad, max + pad)
}

/// A polynomial of degree <= 3 in the ray parameter, lowest coefficient first.
type Cubic = [f32; 4];

/// The product of two polynomials whose degrees add up to at most 3.
#[inline(always)]
fn mul(a: Cubic, b: Cubic) -> Cubic {
    let mut out = [0.0; 4];
    for i in 0..4 {
        for j in 0..4 - i {
            out[i + j] += a[i] * b[j];
        }
    }
    out
}

/// The trilinear interpolant along `p + s d` (voxel-local) as a cubic in `s`: with
/// f = k0 + k1 x + k2 y + k3 xy + k4 z + k5 xz + k6 yz + k7 xyz (the monomial form of the
/// corner values), each coordinate a linear polynomial in s.
#[inline(always)]
fn cubic_along(f: &[f32; 8], p: Vec3, d: Vec3) -> Cubic {
    let k = [
        f[0],
        f[1] - f[0],
        f[2] - f[0],
        f[3] - f[2] - f[1] + f[0],
        f[4] - f[0],
        f[5] - f[4] - f[1] + f[0],
        f[6] - f[4] - f[2] + f[0],
        f[7] - f[6] - f[5] + f[4] - f[3] + f[2] + f[1] - f[0],
    ];
    let (x, y, z) = (
        [p.x, d.x, 0.0, 0.0],
        [p.y, d.y, 0.0, 0.0],
        [p.z, d.z, 0.0, 0.0],
    );
    let xy = mul(x, y);
    let terms = [
        [1.0, 0.0, 0.0, 0.0],
        x,
        y,
        xy,
        z,
        mul(x, z),
        mul(y, z),
        mul(xy, z),
    ];
    let mut c = [0.0; 4];
    for (ki, t) in k.iter().zip(terms) {
        for j in 0..4 {
            c[j] += ki * t[j];
        }
    }
    c
}

/// The cubic's value at `s` (Horner).
#[inline(always)]
fn eval(c: &Cubic, s: f32) -> f32 {
    ((c[3] * s + c[2]) * s + c[1]) * s + c[0]
}

/// Iterations of the root refinement at most (each halves the bracket at least; 50 is far
/// more than 32-bit floats can halve a bracket).
const MAX_ITERATIONS: u32 = 50;

/// The first root of `c` in [0, `end`], where the cubic's values at the ends are `f0` and
/// `f1` (taken on the voxel's faces, see the module docs), or `None`.
fn first_root(c: &Cubic, end: f32, f0: f32, f1: f32) -> Option<f32> {
    let (mut near, mut far, mut f_near, mut f_far) = (0.0f32, end, f0, f1);
    // The derivative 3 c3 s^2 + 2 c2 s + c1 vanishes at most twice: splitting there leaves
    // monotonic pieces, the first of which with a change of sign holds the first root.
    let mut roots = quadratic_roots(3.0 * c[3], 2.0 * c[2], c[1]);
    if roots[0] > roots[1] {
        roots.swap(0, 1);
    }
    for r in roots {
        if !(near <= r && r <= far) {
            continue;
        }
        let fr = eval(c, r);
        if f_near * fr <= 0.0 {
            (far, f_far) = (r, fr);
        } else {
            (near, f_near) = (r, fr);
        }
    }
    if !(f_near * f_far <= 0.0) {
        return None;
    }
    // Secant start, then Newton steps; a step that leaves the bracket bisects instead.
    let mut s = near + (far - near) * (-f_near / (f_far - f_near));
    if !(s >= near && s <= far) {
        s = 0.5 * (near + far);
    }
    let tolerance = 1e-7 * end.max(f32::MIN_POSITIVE);
    for _ in 0..MAX_ITERATIONS {
        let fs = eval(c, s);
        if fs == 0.0 {
            return Some(s);
        }
        if fs * f_near <= 0.0 {
            far = s;
        } else {
            near = s;
        }
        let slope = (3.0 * c[3] * s + 2.0 * c[2]) * s + c[1];
        let newton = s - fs / slope;
        let next = if newton > near && newton < far {
            newton
        } else {
            0.5 * (near + far)
        };
        let step = (next - s).abs();
        s = next;
        if !(step > tolerance) {
            break;
        }
    }
    Some(s)
}

/// The real roots of a s^2 + b s + c (both NaN if there are none; a linear equation's one
/// root twice).
fn quadratic_roots(a: f32, b: f32, c: f32) -> [f32; 2] {
    if a == 0.0 {
        let r = if b != 0.0 { -c / b } else { f32::NAN };
        return [r, r];
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return [f32::NAN; 2];
    }
    // The form without cancellation (Press et al., Numerical Recipes, sec. 5.6).
    let q = -0.5 * (b + disc.sqrt().copysign(b));
    let r0 = q / a;
    let r1 = if q != 0.0 { c / q } else { r0 };
    [r0, r1]
}

/// Distance along the ray `origin + t dir` (world space) to the first point of the surface in
/// the voxel at `lo` of size `size` with corner values `f`, for t in [tmin, tmax]; +inf if
/// there is none.
pub fn intersect_voxel(
    lo: Vec3,
    size: Vec3,
    f: &[f32; 8],
    origin: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
) -> f32 {
    // Voxel-local ray: distances along it are the world's.
    let o = (origin - lo) / size;
    let d = dir / size;
    let inv = d.recip();
    let forward = [d.x >= 0.0, d.y >= 0.0, d.z >= 0.0];
    let mut t_enter = [0.0f32; 3];
    let mut t_leave = [0.0f32; 3];
    for a in 0..3 {
        let (near, far) = if forward[a] { (0.0, 1.0) } else { (1.0, 0.0) };
        let (t0, t1) = ((near - o[a]) * inv[a], (far - o[a]) * inv[a]);
        // Parallel to the slab: +-inf outside it; NaN exactly in its boundary, inside.
        t_enter[a] = if t0.is_nan() { f32::NEG_INFINITY } else { t0 };
        t_leave[a] = if t1.is_nan() { f32::INFINITY } else { t1 };
    }
    let enter = t_enter[0].max(t_enter[1]).max(t_enter[2]);
    let leave = t_leave[0].min(t_leave[1]).min(t_leave[2]);
    let begin = enter.max(tmin);
    if !(begin < leave && begin <= tmax) {
        return f32::INFINITY;
    }
    let (p_begin, p_end) = (o + d * begin, o + d * leave);
    // The crossed faces' coordinates exactly (an origin inside the voxel crosses none).
    let mut at_begin = p_begin.clamp(Vec3::ZERO, Vec3::ONE);
    let mut at_end = p_end.clamp(Vec3::ZERO, Vec3::ONE);
    for a in 0..3 {
        if t_enter[a] == begin {
            at_begin[a] = if forward[a] { 0.0 } else { 1.0 };
        }
        if t_leave[a] == leave {
            at_end[a] = if forward[a] { 1.0 } else { 0.0 };
        }
    }
    let c = cubic_along(f, p_begin, d);
    match first_root(&c, leave - begin, trilerp(f, at_begin), trilerp(f, at_end)) {
        Some(s) if begin + s <= tmax => begin + s,
        _ => f32::INFINITY,
    }
}

/// The geometric normal at world point `p` of the voxel at `lo` of size `size`: the
/// interpolant's gradient (world space, unit; towards positive values, the outside).
pub fn voxel_normal(lo: Vec3, size: Vec3, f: &[f32; 8], p: Vec3) -> Vec3 {
    let w = ((p - lo) / size).clamp(Vec3::ZERO, Vec3::ONE);
    // d/dp = d/dw / size (the chain rule through w = (p - lo) / size).
    (trilerp_grad(f, w) / size).normalize_or_zero()
}

/// Mitsuba's `smooth` shading normal at world point `p` (world space, unit): the normalised
/// gradients of the eight voxels around the grid vertex nearest to `p`, blended trilinearly
/// by `p`'s position between those voxels' centres (Hansson-Söderlund et al. 2022, sec. 5).
/// Each voxel's gradient is made of differences of the interpolant across the voxel along
/// each axis, at `p`'s position along the other two; voxels outside the grid take no weight,
/// and beyond the last sample plane a difference is 0 (its samples are clamped to the grid).
pub fn smooth_normal(grid: &SdfGrid, p: Vec3) -> Vec3 {
    let n = grid.resolution.map(|r| r as i32);
    let cells = Vec3::new((n[0] - 1) as f32, (n[1] - 1) as f32, (n[2] - 1) as f32);
    // Grid coordinates: sample index units.
    let g = (p - grid.origin) / grid.extent * cells;
    let nearest = [g.x.round() as i32, g.y.round() as i32, g.z.round() as i32];
    // The lowest of the eight voxels around the nearest vertex, and p relative to their
    // centres.
    let v = nearest.map(|c| c - 1);
    let mut uvw = g - Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32) - Vec3::splat(0.5);
    // The cell holding p, for the interpolation along the other axes.
    let cell: [i32; 3] = std::array::from_fn(|a| (g[a].floor() as i32).clamp(0, n[a] - 2));
    let w = g - Vec3::new(cell[0] as f32, cell[1] as f32, cell[2] as f32);
    let sample = |q: [i32; 3]| {
        let c: [u32; 3] = std::array::from_fn(|a| q[a].clamp(0, n[a] - 1) as u32);
        grid.at(c[0], c[1], c[2])
    };
    // The interpolant on sample plane q along axis a, at p's position along the other two.
    let plane = |a: usize, q: i32| {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let f: [f32; 4] = std::array::from_fn(|i| {
            let mut idx = [0; 3];
            idx[a] = q;
            idx[b] = cell[b] + (i & 1) as i32;
            idx[c] = cell[c] + (i >> 1) as i32;
            sample(idx)
        });
        bilerp(f, w[b], w[c])
    };
    // Per axis, the differences of the lower and the upper voxel: one spans p's cell, the
    // other reaches the next sample plane on its side.
    let (mut d_lower, mut d_upper) = (Vec3::ZERO, Vec3::ZERO);
    for a in 0..3 {
        let upper = cell[a] != v[a];
        let (g0, g1) = (plane(a, cell[a]), plane(a, cell[a] + 1));
        let across_cell = g1 - g0;
        let beyond = if upper {
            g0 - plane(a, cell[a] - 1)
        } else {
            plane(a, cell[a] + 2) - g1
        };
        let (lower_d, upper_d) = if upper {
            (beyond, across_cell)
        } else {
            (across_cell, beyond)
        };
        d_lower[a] = lower_d * cells[a];
        d_upper[a] = upper_d * cells[a];
    }
    let inside = [v[0] >= 0, v[1] >= 0, v[2] >= 0];
    for a in 0..3 {
        if !inside[a] {
            // The lower voxel is outside the grid: all weight to the upper one.
            uvw[a] = 1.0;
        }
    }
    let normal = |i: usize| {
        let hi = [i & 1 != 0, i & 2 != 0, i & 4 != 0];
        if (0..3).all(|a| hi[a] || inside[a]) {
            let d = Vec3::new(
                if hi[0] { d_upper.x } else { d_lower.x },
                if hi[1] { d_upper.y } else { d_lower.y },
                if hi[2] { d_upper.z } else { d_lower.z },
            );
            d.normalize_or_zero()
        } else {
            Vec3::ZERO
        }
    };
    let lerp = |a: Vec3, b: Vec3, t: f32| a * (1.0 - t) + b * t;
    let blended = lerp(
        lerp(
            lerp(normal(0), normal(1), uvw.x),
            lerp(normal(2), normal(3), uvw.x),
            uvw.y,
        ),
        lerp(
            lerp(normal(4), normal(5), uvw.x),
            lerp(normal(6), normal(7), uvw.x),
            uvw.y,
        ),
        uvw.z,
    );
    // Normals from object space to world: the inverse transpose of the scales.
    (blended / grid.extent).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Corner values of the plane x = a (f = x - a).
    fn plane_x(a: f32) -> [f32; 8] {
        std::array::from_fn(|i| (i & 1) as f32 - a)
    }

    #[test]
    fn a_plane_is_hit_where_it_is() {
        let (lo, size) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.5, 0.25, 2.0));
        let f = plane_x(0.3);
        // Along +x through the voxel's middle: the plane is at world x = 1 + 0.3 * 0.5.
        let o = Vec3::new(0.0, 2.1, 4.0);
        let t = intersect_voxel(lo, size, &f, o, Vec3::X, 0.0, f32::INFINITY);
        assert!((t - 1.15).abs() < 1e-5, "{t}");
        // An oblique ray, checked against the hit point's coordinate.
        let d = Vec3::new(1.0, 0.05, 0.2).normalize();
        let t = intersect_voxel(lo, size, &f, o, d, 0.0, f32::INFINITY);
        assert!(((o + d * t).x - 1.15).abs() < 1e-5);
        // Beyond tmax, or pointing away: no hit.
        assert_eq!(
            intersect_voxel(lo, size, &f, o, Vec3::X, 0.0, 1.1),
            f32::INFINITY
        );
        assert_eq!(
            intersect_voxel(lo, size, &f, o, -Vec3::X, 0.0, 9.0),
            f32::INFINITY
        );
        assert_eq!(voxel_normal(lo, size, &f, o + Vec3::X * 1.15), Vec3::X);
    }

    #[test]
    fn the_first_of_several_roots_is_found() {
        // A saddle, f = 4 (x - 0.5)(y - 0.5) (1 - z) - 0.2 + 0.4 z: along the diagonal
        // x = y = s of the face z = 0 it is 4 (s - 0.5)^2 - 0.2, which has two roots; the
        // nearer one must be reported.
        let f: [f32; 8] = std::array::from_fn(|i| {
            let (x, y, z) = ((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32);
            4.0 * (x - 0.5) * (y - 0.5) * (1.0 - z) - 0.2 + 0.4 * z
        });
        let o = Vec3::new(-1.0, -1.0, 0.0);
        let d = Vec3::new(1.0, 1.0, 0.0).normalize();
        let t = intersect_voxel(Vec3::ZERO, Vec3::ONE, &f, o, d, 0.0, f32::INFINITY);
        // On z = 0, f = 4 (s - 0.5)^2 - 0.2: roots at s = 0.5 -+ sqrt(0.05).
        let s = 0.5 - 0.05f32.sqrt();
        let expect = (s + 1.0) * 2f32.sqrt();
        assert!((t - expect).abs() < 1e-5, "{t} vs {expect}");
    }

    #[test]
    fn neighbouring_voxels_agree_on_a_surface_in_their_shared_face() {
        // The surface x = 1 exactly on the face between two voxels along x: exactly one of
        // them (or both, at the same t) reports it.
        let left: [f32; 8] = plane_x(1.0);
        let right: [f32; 8] = plane_x(0.0);
        let o = Vec3::new(-0.5, 0.5, 0.5);
        let tl = intersect_voxel(Vec3::ZERO, Vec3::ONE, &left, o, Vec3::X, 0.0, f32::INFINITY);
        let tr = intersect_voxel(Vec3::X, Vec3::ONE, &right, o, Vec3::X, 0.0, f32::INFINITY);
        assert!(tl.min(tr) == 1.5, "{tl} {tr}");
    }

    #[test]
    fn tight_bounds_hold_the_surface() {
        let f = plane_x(0.3);
        let (lo, hi) = tight_bounds(&f);
        assert_eq!(
            (lo, hi),
            (Vec3::new(0.3, 0.0, 0.0), Vec3::new(0.3, 1.0, 1.0))
        );
        // Every surface point of a random voxel lies in its tight box.
        let mut state = 12345u32;
        let mut rnd = || {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        for _ in 0..200 {
            let f: [f32; 8] = std::array::from_fn(|_| rnd() - 0.5);
            let (lo, hi) = tight_bounds(&f);
            for _ in 0..50 {
                let o = Vec3::new(rnd(), rnd(), -0.5);
                let t = intersect_voxel(Vec3::ZERO, Vec3::ONE, &f, o, Vec3::Z, 0.0, 9.0);
                if t.is_finite() {
                    let p = o + Vec3::Z * t;
                    let slack = Vec3::splat(1e-4);
                    assert!(p.cmpge(lo - slack).all() && p.cmple(hi + slack).all());
                    assert!(trilerp(&f, p).abs() < 1e-4);
                }
            }
        }
    }

    #[test]
    fn smooth_normals_of_a_linear_field_are_its_gradient() {
        // f = x + 2y - 3z + 0.1 on a 5^3 grid over a stretched box: every voxel's gradient
        // is the same, so the smooth normal is the analytic one away from the grid's upper
        // boundary, and at its lower one (voxels outside take no weight there). Within half
        // a voxel of the upper boundary the clamped differences bend it, in Mitsuba 3.9.1 as
        // here (`matches_mitsuba_3_9_1` covers that).
        let n = 5u32;
        let extent = Vec3::new(2.0, 1.0, 4.0);
        let values = (0..n * n * n)
            .map(|i| {
                let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
                let q = Vec3::new(x as f32, y as f32, z as f32) / (n - 1) as f32 * extent;
                q.x + 2.0 * q.y - 3.0 * q.z + 0.1
            })
            .collect();
        let grid = SdfGrid {
            resolution: [n; 3],
            values,
            origin: Vec3::new(-1.0, 0.5, 0.0),
            extent,
            smooth_normals: true,
        };
        let expect = Vec3::new(1.0, 2.0, -3.0).normalize();
        for p in [
            Vec3::new(0.3, 0.4, 0.7),
            Vec3::new(0.01, 0.02, 0.03),
            Vec3::new(0.5, 0.5, 0.5),
        ] {
            let world = grid.origin + p * grid.extent;
            let got = smooth_normal(&grid, world);
            assert!((got - expect).length() < 1e-5, "{p}: {got}");
        }
        // Near the upper boundary, Mitsuba 3.9.1's normal at this surface point (measured
        // with its scalar_rgb variant on the same grid).
        let p = grid.origin + Vec3::new(0.99, 0.98, 0.336_666_66) * grid.extent;
        let got = smooth_normal(&grid, p);
        let mitsuba = Vec3::new(0.164688, 0.353962, -0.920646);
        assert!((got - mitsuba).length() < 1e-4, "{got}");
    }

    /// One ray: origin, direction, t, geometric normal, smooth shading normal.
    type MitsubaHit = ([f32; 3], [f32; 3], f32, [f32; 3], [f32; 3]);

    /// Mitsuba 3.9.1's `t`, geometric normal and smooth shading normal for rays at the grid
    /// of `references/sdfgrid_rays.py` (its output, pasted; nine significant digits, so that
    /// every f32 round-trips exactly).
    #[allow(clippy::excessive_precision)]
    #[rustfmt::skip]
    const MITSUBA: [MitsubaHit; 24] = [
    ([-2.509189606e+00, -1.125684023e+00, -2.644116879e+00], [6.323984861e-01, 3.228562176e-01, 7.041562200e-01], 3.363469839e+00, [-8.075677156e-01, -4.803165495e-01, -3.422430158e-01], [-8.613809943e-01, -4.153031409e-01, -2.924829721e-01]),
    ([-2.256685972e+00, 1.662263155e+00, 1.427144289e+00], [7.153653502e-01, -5.647546053e-01, -4.114664495e-01], 2.680261374e+00, [-6.797485948e-01, 6.692276597e-01, 3.001270592e-01], [-6.840324998e-01, 6.421976089e-01, 3.459506333e-01]),
    ([1.915292263e+00, -4.065598011e+00, -1.367389321e+00], [-4.397684634e-01, 8.501948118e-01, 2.894348502e-01], 4.456944942e+00, [-2.394700199e-01, -9.650794268e-01, -1.061878651e-01], [-2.463964820e-01, -9.668222666e-01, -6.740508229e-02]),
    ([-5.453121066e-01, -3.508963346e+00, 4.721635282e-01], [1.784647107e-01, 9.621565938e-01, -2.059248984e-01], 3.351597071e+00, [7.085172832e-02, -9.898021817e-01, -1.235783547e-01], [-9.005054832e-02, -9.771509171e-01, -1.925279945e-01]),
    ([-1.983966470e+00, -1.365695447e-01, 2.993741930e-01], [9.748101234e-01, 8.776654303e-02, -2.050421387e-01], 1.576719642e+00, [-9.776345491e-01, 1.654953361e-01, -1.297768354e-01], [-9.891508818e-01, -1.448341608e-01, -2.457028814e-02]),
    ([4.135282040e+00, -4.433144093e+00, 2.745808601e+00], [-6.089891791e-01, 6.933898330e-01, -3.851528764e-01], 6.251098156e+00, [7.996308804e-01, -1.086491346e-01, 5.905808210e-01], [8.021126986e-01, -2.647483349e-01, 5.352789164e-01]),
    ([2.343774080e+00, -3.375063181e+00, 5.706555769e-02], [-5.356765389e-01, 8.427979946e-01, -5.236613750e-02], 3.752603531e+00, [6.792749166e-01, -7.133699059e-01, -1.723048985e-01], [6.517319083e-01, -7.374021411e-01, -1.774365306e-01]),
    ([5.263558626e-01, -3.478785753e+00, -1.526164532e+00], [-9.589898586e-02, 8.945719600e-01, 4.365139306e-01], 3.555037022e+00, [7.158909738e-02, -9.898296595e-01, 1.229316220e-01], [1.486131996e-01, -9.885616302e-01, 2.569292486e-02]),
    ([-4.008335114e+00, -2.625904560e+00, 2.502104044e+00], [7.907238603e-01, 4.747484028e-01, -3.864837587e-01], 5.229542732e+00, [2.900638878e-01, -7.318753004e-01, 6.166210175e-01], [2.822145224e-01, -5.992987752e-01, 7.491300702e-01]),
    ([4.157714367e+00, 2.165540457e+00, -1.423701286e+00], [-8.548090458e-01, -4.688159823e-01, 2.225152403e-01], 4.557282925e+00, [6.454052329e-01, 4.855893552e-01, -5.896227360e-01], [6.521992087e-01, 3.620567322e-01, -6.659962535e-01]),
    ([-1.171327591e+00, -1.123765230e+00, 6.887233853e-01], [6.769816875e-01, 4.803132713e-01, -5.576692224e-01], 1.803650022e+00, [-2.357180417e-01, -9.152098298e-01, -3.268451989e-01], [-7.951717079e-02, -9.474839568e-01, -3.097600043e-01]),
    ([-1.385357141e+00, 3.382110357e+00, -5.492242053e-02], [3.073873520e-01, -9.515719414e-01, 4.883510992e-03], 3.348237514e+00, [-6.909394860e-01, 7.154761553e-01, -1.034236103e-01], [-6.100407243e-01, 7.916243076e-01, -3.437110782e-02]),
    ([-2.509771347e+00, -1.857586741e+00, 1.063582897e+00], [7.847633362e-01, 5.887151361e-01, -1.938066483e-01], 2.975929260e+00, [-5.647763610e-01, -5.652185082e-01, 6.012950540e-01], [-3.826514184e-01, -6.968429685e-01, 6.066199541e-01]),
    ([2.027261257e+00, 1.571182013e+00, -2.782730579e+00], [-5.189574957e-01, -3.840913773e-01, 7.636471391e-01], 3.510279894e+00, [3.787274063e-01, 9.134443998e-01, -1.489462107e-01], [4.071269035e-01, 9.054020643e-01, -1.203942224e-01]),
    ([-5.459620476e+00, 2.188091755e+00, -2.921203852e+00], [8.385037184e-01, -3.633980453e-01, 4.060213268e-01], 6.156770706e+00, [-5.841228366e-01, -6.323297620e-01, -5.088807344e-01], [-6.774325371e-01, -5.219887495e-01, -5.182787776e-01]),
    ([3.653507471e+00, 4.188036442e+00, 3.450326622e-01], [-6.544422507e-01, -7.553256154e-01, 3.447588533e-02], 5.475363731e+00, [4.629819095e-01, 4.175480306e-01, 7.818576097e-01], [3.417305946e-01, 4.034144580e-01, 8.488091826e-01]),
    ([3.364809752e+00, -1.390751481e+00, 1.377496570e-01], [-8.957257867e-01, 4.426435232e-01, 4.173777997e-02], 3.434462547e+00, [5.440205336e-01, 7.298893929e-01, 4.138879180e-01], [6.168381572e-01, 6.937340498e-01, 3.718114197e-01]),
    ([-1.854793787e+00, 2.075007856e-01, -9.140350819e-01], [8.307723999e-01, -1.180263050e-02, 5.564870834e-01], 1.800809264e+00, [-6.975384951e-01, 7.087574601e-01, 1.053704470e-01], [-6.316158175e-01, 7.709755898e-01, 8.159752935e-02]),
    ([4.920620441e+00, -2.191952705e+00, -3.701436520e+00], [-7.978824973e-01, 3.237887621e-01, 5.084726214e-01], 6.345114231e+00, [-4.035890400e-01, -8.165139556e-01, -4.128206074e-01], [-3.149372637e-01, -7.712529302e-01, -5.531577468e-01]),
    ([-4.660907745e+00, -5.632981062e-01, -1.921121836e+00], [9.092699885e-01, 1.303985417e-01, 3.952522576e-01], 4.651063442e+00, [-9.757887125e-01, 1.722819805e-01, -1.347417682e-01], [-9.934492111e-01, 7.074669749e-02, -8.974202722e-02]),
    ([-3.677943230e+00, 4.165013790e+00, -1.143047929e+00], [6.482119560e-01, -7.118705511e-01, 2.702989876e-01], 5.533684254e+00, [6.867951155e-02, 9.155459404e-01, 3.963064849e-01], [-2.517171949e-02, 9.355651736e-01, 3.522560596e-01]),
    ([1.659726977e+00, 9.994620085e-01, -1.992430449e+00], [-7.067632675e-01, -3.973599672e-01, 5.853124857e-01], 2.434409857e+00, [1.000303775e-01, 3.785644770e-01, -9.201536775e-01], [5.392726883e-02, 1.917303354e-01, -9.799649119e-01]),
    ([-2.907761037e-01, 1.425258160e+00, 2.557777643e+00], [1.463736296e-01, -5.637012720e-01, -8.129056692e-01], 2.476029158e+00, [4.533849359e-01, 4.117750823e-01, 7.904957533e-01], [3.446452618e-01, 2.778814733e-01, 8.966614008e-01]),
    ([4.629475594e+00, -3.552826643e+00, 2.774800539e+00], [-7.069976330e-01, 5.817518234e-01, -4.021432400e-01], 6.066721916e+00, [8.049010634e-01, -9.721612930e-02, 5.853916407e-01], [8.342396617e-01, 9.473218024e-02, 5.432034135e-01]),
    ];

    #[test]
    fn matches_mitsuba_3_9_1() {
        // The grid of references/sdfgrid_rays.py: a wobbly sphere on 9^3 samples, placed by
        // scales and a translation.
        let n = 9u32;
        let values = (0..n * n * n)
            .map(|i| {
                let q = [i % n, (i / n) % n, i / (n * n)].map(|c| c as f64 / (n - 1) as f64);
                let r = q.iter().map(|c| (c - 0.5) * (c - 0.5)).sum::<f64>().sqrt();
                (r - 0.3 + 0.05 * (7.0 * q[0]).sin() * (5.0 * q[1]).cos()) as f32
            })
            .collect();
        let grid = SdfGrid {
            resolution: [n; 3],
            values,
            origin: Vec3::new(-0.7, -0.5, -1.0),
            extent: Vec3::new(1.5, 1.0, 2.0),
            smooth_normals: true,
        };
        for (o, d, t_want, n_want, sh_want) in MITSUBA {
            let (o, d) = (Vec3::from(o), Vec3::from(d));
            // The closest hit over every occupied voxel.
            let (t, v) = grid
                .occupied_voxels()
                .map(|v| {
                    let (lo, size) = grid.voxel_box(v);
                    (
                        intersect_voxel(lo, size, &grid.corners(v), o, d, 0.0, f32::INFINITY),
                        v,
                    )
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .unwrap();
            // Both refine the root to ~1e-5 of the ray parameter or better.
            assert!(
                (t - t_want).abs() <= 2e-5 * t_want,
                "t {t} vs Mitsuba {t_want}"
            );
            let p = o + d * t;
            let (lo, size) = grid.voxel_box(v);
            let ng = voxel_normal(lo, size, &grid.corners(v), p);
            let sh = smooth_normal(&grid, p);
            // Normals from points that differ by the roots' tolerance: 1e-3.
            assert!(
                (ng - Vec3::from(n_want)).length() < 1e-3,
                "n {ng} vs {n_want:?}"
            );
            assert!(
                (sh - Vec3::from(sh_want)).length() < 1e-3,
                "smooth n {sh} vs {sh_want:?}"
            );
        }
    }
}
