//! Primitives (triangles, parallelograms, analytic disks, spheres and cylinders, SDF voxels, curve
//! segments), their ray intersection, and the surface
//! interaction recorded at a hit. Everything in world space.

use obvhs::aabb::Aabb;
use pt_math::{Vec2, Vec3, Vec3A, Vec4};

/// A primitive in the BVH. Triangles store `v0` and two edges, the form Möller-Trumbore wants.
///
/// 64 bytes. A 48-byte layout (`e2` as an unaligned `Vec3`, packed beside the enum tag) saves
/// 16 MB per million triangles but costs 1.4% more instructions and about 2.5% more CPU time on
/// the Cornell box (the conversion to `Vec3A` in every triangle test), so it is not used.
#[derive(Clone, Copy, Debug)]
pub enum Primitive {
    /// A triangle `v0 + b1 e1 + b2 e2`; its front side is the side `e1 x e2` points to.
    Triangle {
        /// First vertex.
        v0: Vec3A,
        /// `v1 - v0`.
        e1: Vec3A,
        /// `v2 - v0`.
        e2: Vec3A,
    },
    /// A parallelogram `v0 + b1 e1 + b2 e2`, `b1` and `b2` in [0, 1]: two triangles of a mesh
    /// that share a diagonal and together form one (rectangles, cube faces, quads), tested
    /// once instead of twice. Front side as for triangles.
    Parallelogram {
        /// The corner the edges start from.
        v0: Vec3A,
        /// First edge.
        e1: Vec3A,
        /// Second edge.
        e2: Vec3A,
    },
    /// A disk (Mitsuba's `disk`, see `pt_scene::Disk`): the points `center + x a + y b` with
    /// x^2 + y^2 <= 1. Its front side is the shape's (kept with the shape, not here: it need
    /// not be the side `a x b` points to).
    Disk {
        /// Centre.
        center: Vec3A,
        /// The image of the object-space x axis.
        a: Vec3A,
        /// The image of the object-space y axis.
        b: Vec3A,
    },
    /// A sphere; `flip` makes the front side (normal) face inwards.
    Sphere {
        /// Centre.
        center: Vec3A,
        /// Radius (> 0).
        radius: f32,
        /// Whether the normal points inwards.
        flip: bool,
    },
    /// An open cylinder (Mitsuba's `cylinder`, no end caps): the points at distance `radius`
    /// from the segment `p0 + z axis`, z in [0, `length`]; `flip` makes the normal face the
    /// axis.
    Cylinder {
        /// Centre of the first end circle.
        p0: Vec3A,
        /// Unit axis direction.
        axis: Vec3A,
        /// Radius (> 0).
        radius: f32,
        /// Length along the axis (> 0).
        length: f32,
        /// Whether the normal points towards the axis.
        flip: bool,
    },
    /// One voxel of Mitsuba's `sdfgrid` that the surface passes through: the zero set of the
    /// trilinear interpolant of its corner values inside the axis-aligned box `lo + [0,
    /// size]` (see [`crate::sdf`]).
    SdfVoxel {
        /// The box's lowest corner.
        lo: Vec3,
        /// The box's size along x, y, z (positive).
        size: Vec3,
        /// The distances at the corners, corner `i` at offset (i & 1, (i >> 1) & 1, i >> 2).
        f: [f32; 8],
    },
    /// One segment of a `linearcurve`: the round cone from the sphere of radius `r0` at `p0`
    /// to the sphere of radius `r1` at `p1` (see [`crate::curve`]); back faces are culled.
    RoundCone {
        /// First control point.
        p0: Vec3A,
        /// Second control point.
        p1: Vec3A,
        /// Radius at `p0` (>= 0).
        r0: f32,
        /// Radius at `p1` (>= 0).
        r1: f32,
    },
    /// A piece of a segment of a `bsplinecurve`: the tube around the uniform cubic B-spline of
    /// the four control points `p` (see [`crate::curve`]), the part `piece` of its segment
    /// (the control points are the piece's own, its parameter runs over [0, 1]); back faces
    /// are culled. The radii are stored as fractions of the largest, `r_max * r[i] / 65535`
    /// (a relative error of at most 8e-6 of the largest radius, exact where the radius is
    /// constant), so that the piece fits the 64 bytes of a primitive.
    BSpline {
        /// The control points.
        p: [Vec3; 4],
        /// The largest of the four radii (>= 0).
        r_max: f32,
        /// The radii as fractions of `r_max`, in units of 1 / 65535.
        r: [u16; 4],
        /// Which part of its segment this is ([`crate::curve::Piece::code`]).
        piece: u8,
    },
}

// Every variant fits the 64 bytes the BVH's primitive array is laid out for.
const _: () = assert!(std::mem::size_of::<Primitive>() == 64);

/// obvhs builds directly from the primitives (no separate array of boxes).
impl obvhs::Boundable for Primitive {
    #[inline]
    fn aabb(&self) -> Aabb {
        Primitive::aabb(self)
    }
}

impl Primitive {
    /// Axis-aligned bounds, for the BVH builder.
    pub fn aabb(&self) -> Aabb {
        match *self {
            Primitive::Triangle { v0, e1, e2 } => {
                let (v1, v2) = (v0 + e1, v0 + e2);
                Aabb::new(v0.min(v1).min(v2), v0.max(v1).max(v2))
            }
            Primitive::Parallelogram { v0, e1, e2 } => {
                let (v1, v2, v3) = (v0 + e1, v0 + e2, v0 + e1 + e2);
                Aabb::new(v0.min(v1).min(v2).min(v3), v0.max(v1).max(v2).max(v3))
            }
            Primitive::Disk { center, a, b } => {
                let reach = (a * a + b * b).map(f32::sqrt);
                Aabb::new(center - reach, center + reach)
            }
            Primitive::Sphere { center, radius, .. } => {
                Aabb::new(center - Vec3A::splat(radius), center + Vec3A::splat(radius))
            }
            Primitive::Cylinder {
                p0,
                axis,
                radius,
                length,
                ..
            } => {
                let (lo, hi) = pt_scene::cylinder_bounds(p0.into(), axis.into(), radius, length);
                Aabb::new(lo.into(), hi.into())
            }
            Primitive::SdfVoxel { lo, size, ref f } => {
                let (min, max) = crate::sdf::voxel_bounds(lo, size, f);
                Aabb::new(min.into(), max.into())
            }
            Primitive::RoundCone { p0, p1, r0, r1 } => {
                let (min, max) = crate::curve::round_cone_bounds(p0, p1, r0, r1);
                Aabb::new(min, max)
            }
            Primitive::BSpline { .. } => {
                let (p, r) = self.bspline_segment().unwrap_or_default();
                let (min, max) = crate::curve::bspline_bounds(&p, &r);
                Aabb::new(min, max)
            }
        }
    }

    /// A B-spline segment's `piece` from the piece's own four control points and radii (radii
    /// >= 0).
    pub fn new_bspline(p: [Vec3; 4], radii: [f32; 4], piece: crate::curve::Piece) -> Primitive {
        let r_max = radii.iter().fold(0.0f32, |m, &x| m.max(x));
        let r = radii.map(|x| {
            if r_max > 0.0 {
                (x / r_max * 65535.0).round().clamp(0.0, 65535.0) as u16
            } else {
                0
            }
        });
        Primitive::BSpline {
            p,
            r_max,
            r,
            piece: piece.code(),
        }
    }

    /// A [`Primitive::BSpline`]'s control points and decoded radii; `None` for other
    /// primitives.
    #[inline(always)]
    pub fn bspline_segment(&self) -> Option<([Vec3A; 4], [f32; 4])> {
        match *self {
            Primitive::BSpline { p, r_max, r, .. } => Some((
                p.map(Vec3A::from),
                r.map(|q| r_max * (q as f32 * (1.0 / 65535.0))),
            )),
            _ => None,
        }
    }

    /// Whether this is an analytic primitive (disk, sphere, cylinder, SDF voxel, curve segment), which the flat
    /// SIMD blocks of triangles and parallelograms leave out.
    #[inline]
    pub fn is_analytic(&self) -> bool {
        !matches!(
            self,
            Primitive::Triangle { .. } | Primitive::Parallelogram { .. }
        )
    }

    /// Distance along the ray to the nearest hit in `(tmin, tmax)`, or +inf. `dir` need not be
    /// unit length for triangles; spheres assume it is.
    #[inline(always)]
    pub fn intersect(&self, origin: Vec3A, dir: Vec3A, tmin: f32, tmax: f32) -> f32 {
        match *self {
            Primitive::Triangle { v0, e1, e2 } => {
                intersect_triangle(origin, dir, v0, e1, e2, tmin, tmax)
                    .map_or(f32::INFINITY, |h| h.0)
            }
            Primitive::Parallelogram { v0, e1, e2 } => {
                intersect_parallelogram(origin, dir, v0, e1, e2, tmin, tmax)
                    .map_or(f32::INFINITY, |h| h.0)
            }
            Primitive::Disk { center, a, b } => {
                intersect_disk(origin, dir, center, a, b, tmin, tmax).map_or(f32::INFINITY, |h| h.0)
            }
            Primitive::Sphere { center, radius, .. } => {
                intersect_sphere(origin, dir, center, radius, tmin, tmax)
            }
            Primitive::Cylinder {
                p0,
                axis,
                radius,
                length,
                ..
            } => intersect_cylinder(origin, dir, p0, axis, radius, length, tmin, tmax),
            Primitive::SdfVoxel { lo, size, ref f } => {
                crate::sdf::intersect_voxel(lo, size, f, origin.into(), dir.into(), tmin, tmax)
            }
            Primitive::RoundCone { .. } | Primitive::BSpline { .. } => {
                self.intersect_bary(origin, dir, tmin, tmax).0
            }
        }
    }

    /// [`Primitive::intersect`] with the hit's barycentrics `(t, b1, b2)` (the weights of
    /// `v0 + e1` and `v0 + e2`; for curve segments `b1` is the curve parameter of the hit;
    /// 0 for other primitives); `t` is +inf on a miss.
    #[inline(always)]
    pub fn intersect_bary(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        tmin: f32,
        tmax: f32,
    ) -> (f32, f32, f32) {
        match *self {
            Primitive::Triangle { v0, e1, e2 } => intersect_triangle(
                origin, dir, v0, e1, e2, tmin, tmax,
            )
            .unwrap_or((f32::INFINITY, 0.0, 0.0)),
            Primitive::Parallelogram { v0, e1, e2 } => intersect_parallelogram(
                origin, dir, v0, e1, e2, tmin, tmax,
            )
            .unwrap_or((f32::INFINITY, 0.0, 0.0)),
            Primitive::Disk { center, a, b } => intersect_disk(
                origin, dir, center, a, b, tmin, tmax,
            )
            .unwrap_or((f32::INFINITY, 0.0, 0.0)),
            Primitive::Sphere { .. } | Primitive::Cylinder { .. } | Primitive::SdfVoxel { .. } => {
                (self.intersect(origin, dir, tmin, tmax), 0.0, 0.0)
            }
            Primitive::RoundCone { p0, p1, r0, r1 } => {
                let (t, v) =
                    crate::curve::intersect_round_cone(origin, dir, p0, p1, r0, r1, tmin, tmax);
                (t, v, 0.0)
            }
            Primitive::BSpline { .. } => {
                let (p, r) = self.bspline_segment().unwrap_or_default();
                let (t, u) = crate::curve::intersect_bspline(origin, dir, &p, &r, tmin, tmax);
                (t, u, 0.0)
            }
        }
    }
}

/// Möller & Trumbore 1997, "Fast, Minimum Storage Ray/Triangle Intersection": returns
/// `(t, b1, b2)`. Written so that NaN from degenerate input fails every comparison and misses.
#[inline(always)]
pub fn intersect_triangle(
    o: Vec3A,
    d: Vec3A,
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    moller_trumbore::<TRIANGLE>(o, d, v0, e1, e2, tmin, tmax)
}

/// The parallelogram `v0 + b1 e1 + b2 e2`, `b1, b2` in [0, 1]: Möller-Trumbore's
/// barycentrics are the parallelogram's edge coordinates, so only the last bound changes
/// (`b2 <= 1` in place of `b1 + b2 <= 1`). Returns `(t, b1, b2)`.
#[inline(always)]
pub fn intersect_parallelogram(
    o: Vec3A,
    d: Vec3A,
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    moller_trumbore::<PARALLELOGRAM>(o, d, v0, e1, e2, tmin, tmax)
}

/// The disk `c + x a + y b`, x^2 + y^2 <= 1 (an ellipse when `a` and `b` differ in length or
/// are not orthogonal): Möller-Trumbore's coordinates over the edges `a` and `b` from `c` are
/// the disk's object-space x and y, so the plane test is the triangle's and only the bound
/// changes. Returns `(t, x, y)`.
#[inline(always)]
pub fn intersect_disk(
    o: Vec3A,
    d: Vec3A,
    c: Vec3A,
    a: Vec3A,
    b: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    moller_trumbore::<DISK>(o, d, c, a, b, tmin, tmax)
}

/// The region of the plane `v0 + b1 e1 + b2 e2` that [`moller_trumbore`] accepts.
const TRIANGLE: u8 = 0;
/// See [`TRIANGLE`].
const PARALLELOGRAM: u8 = 1;
/// See [`TRIANGLE`].
const DISK: u8 = 2;

/// Möller & Trumbore's test over the triangle (`REGION` = [`TRIANGLE`]), the parallelogram
/// ([`PARALLELOGRAM`]) spanned by `e1` and `e2` at `v0`, or the disk ([`DISK`]) `v0 + b1 e1 +
/// b2 e2` with b1^2 + b2^2 <= 1.
#[inline(always)]
fn moller_trumbore<const REGION: u8>(
    o: Vec3A,
    d: Vec3A,
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    // Everything is computed and tested once at the end: about half the candidates a ray meets
    // are misses, and early exits on each bound were branches the processor could not predict.
    // A zero determinant gives infinite or NaN coordinates, which fail the bounds.
    let pvec = d.cross(e2);
    let det = e1.dot(pvec);
    let inv_det = 1.0 / det;
    let tvec = o - v0;
    let b1 = tvec.dot(pvec) * inv_det;
    let qvec = tvec.cross(e1);
    let b2 = d.dot(qvec) * inv_det;
    let t = e2.dot(qvec) * inv_det;
    // `&` rather than `&&` (or `contains`, which short-circuits): evaluate every comparison,
    // branch once.
    #[allow(clippy::manual_range_contains)]
    let inside = match REGION {
        TRIANGLE => (b1 >= 0.0) & (b1 <= 1.0) & (b2 >= 0.0) & (b1 + b2 <= 1.0),
        PARALLELOGRAM => (b1 >= 0.0) & (b1 <= 1.0) & (b2 >= 0.0) & (b2 <= 1.0),
        _ => b1 * b1 + b2 * b2 <= 1.0,
    };
    let hit = (det != 0.0) & inside & (t > tmin) & (t < tmax);
    hit.then_some((t, b1, b2))
}

/// Ray-sphere intersection for a unit-length `d`, using the numerically stable form of
/// Haines et al. 2019 ("Precision Improvements for Ray/Sphere Intersection", Ray Tracing Gems
/// ch. 7, eq. 10): the discriminant is computed from the perpendicular distance, which avoids the
/// cancellation of b^2 - c for far-away origins.
#[inline(always)]
pub fn intersect_sphere(
    o: Vec3A,
    d: Vec3A,
    center: Vec3A,
    radius: f32,
    tmin: f32,
    tmax: f32,
) -> f32 {
    sphere_hit(
        o.to_array(),
        d.to_array(),
        center.to_array(),
        radius,
        tmin,
        tmax,
    )
}

/// [`intersect_sphere`] on plain numbers, for single rays and for loops over rays in SIMD lanes
/// (the flat structure's batches, where the compiler turns the early return into a select);
/// the sums in the order of glam's dot products ((x + y) + z), so single rays through
/// [`intersect_sphere`] give the bits they gave before the lanes shared the routine.
#[inline(always)]
pub fn sphere_hit(
    o: [f32; 3],
    d: [f32; 3],
    center: [f32; 3],
    radius: f32,
    tmin: f32,
    tmax: f32,
) -> f32 {
    let dot = |a: [f32; 3], b: [f32; 3]| (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
    let f = [o[0] - center[0], o[1] - center[1], o[2] - center[2]];
    let b = -dot(f, d); // distance along d to the point closest to the centre
    let perp = [f[0] + d[0] * b, f[1] + d[1] * b, f[2] + d[2] * b]; // its offset from the centre
    let disc = radius * radius - dot(perp, perp);
    // Most rays miss: a single ray returns before the root and the division (written without
    // the branch, single-ray renders without spheres were 18% slower: the larger routine is
    // inlined wherever a primitive is tested, and the code around it compiled worse).
    if !(disc >= 0.0) {
        return f32::INFINITY;
    }
    let sq = disc.sqrt();
    // Stable pair of roots: q has the larger magnitude, the other root is c / q.
    let c = dot(f, f) - radius * radius;
    let q = if b >= 0.0 { b + sq } else { b - sq };
    let (r0, r1) = (c / q, q);
    let (t0, t1) = if r0 > r1 { (r1, r0) } else { (r0, r1) };
    let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (t0, t1) };
    if t0 > tmin && t0 < tmax {
        t0
    } else if t1 > tmin && t1 < tmax {
        t1
    } else {
        f32::INFINITY
    }
}

/// The open cylinder of unit axis `axis` around the segment `p0 + z axis`, z in [0, `length`]:
/// the distance to the nearest hit in `(tmin, tmax)`, or +inf. `d` must be unit length. In the
/// plane across the axis, the ray is the line `f + t d` (`f = o - p0`, both with their axis
/// parts removed), and the roots of `|f + t d|^2 = r^2` are computed as for the sphere: the
/// discriminant from the distance of the line to the axis (no cancellation for distant
/// origins, pbrt-v4 6.8.1), the pair of roots in the stable form. A root counts when its point
/// lies between the end circles; the far root is the hit when the near one misses them (the
/// inside seen through an open end), as in Mitsuba. A ray parallel to the axis never hits.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn intersect_cylinder(
    o: Vec3A,
    d: Vec3A,
    p0: Vec3A,
    axis: Vec3A,
    radius: f32,
    length: f32,
    tmin: f32,
    tmax: f32,
) -> f32 {
    let f = o - p0;
    let (fz, dz) = (f.dot(axis), d.dot(axis));
    let f_across = f - axis * fz;
    let d_across = d - axis * dz;
    let a = d_across.length_squared();
    if !(a > 1e-12) {
        return f32::INFINITY;
    }
    let b = -f_across.dot(d_across) / a; // t of the line's point closest to the axis
    let perp = f_across + d_across * b;
    let disc = radius * radius - perp.length_squared();
    if !(disc >= 0.0) {
        return f32::INFINITY;
    }
    let half_width = (disc / a).sqrt();
    let c = (f_across.length_squared() - radius * radius) / a;
    let q = if b >= 0.0 {
        b + half_width
    } else {
        b - half_width
    };
    let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q) };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let valid = |t: f32| {
        let z = fz + t * dz;
        t > tmin && t < tmax && (0.0..=length).contains(&z)
    };
    if valid(t0) {
        t0
    } else if valid(t1) {
        t1
    } else {
        f32::INFINITY
    }
}

/// What the integrator needs to know about a hit, world space.
#[derive(Clone, Copy, Debug, Default)]
pub struct Interaction {
    /// Hit point.
    pub p: Vec3,
    /// Unit geometric normal, on the primitive's front side.
    pub ng: Vec3,
    /// Unit shading normal (interpolated vertex normal, or `ng`), on the same side as `ng`.
    pub ns: Vec3,
    /// Surface parameterisation (texture coordinates).
    pub uv: Vec2,
    /// Tangent along increasing u (not normalised; zero when the surface has no
    /// parameterisation). It orients anisotropic BSDFs, as Mitsuba's `dp_du` does.
    pub dpdu: Vec3,
    /// Tangent along increasing v (not normalised; zero without a parameterisation): with
    /// `dpdu`, what a bump map perturbs.
    pub dpdv: Vec3,
    /// Interpolated mesh tangent for normal maps (xyz world, not normalised; w = +-1 the
    /// handedness, bitangent `w (n x t)`); zero when the mesh has no tangents.
    pub tangent: Vec4,
    /// Distance along the ray.
    pub t: f32,
    /// Index of the shape this primitive belongs to.
    pub shape: u32,
    /// Index of the hit primitive in the acceleration structure (for mesh attributes).
    pub prim: u32,
    /// Barycentric coordinates (b1, b2) of the hit on the primitive, as the intersection found
    /// them (a parallelogram's range to 1 over its two triangles).
    pub b: Vec2,
}

impl Interaction {
    /// A hit on an analytic primitive (sphere, cylinder), world space: one normal for geometry
    /// and shading, no tangent, no barycentrics.
    #[inline(always)]
    pub fn analytic(
        p: Vec3,
        n: Vec3,
        uv: Vec2,
        [dpdu, dpdv]: [Vec3; 2],
        t: f32,
        shape: u32,
        prim: u32,
    ) -> Self {
        Interaction {
            p,
            ng: n,
            ns: n,
            uv,
            dpdu,
            dpdv,
            tangent: Vec4::ZERO,
            t,
            shape,
            prim,
            b: Vec2::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_hits_and_misses() {
        // Unit right triangle in z = 0, both windings; rays straight down at interior, edge-adjacent
        // outside and NaN points.
        let (v0, e1, e2) = (Vec3A::ZERO, Vec3A::X, Vec3A::Y);
        let d = Vec3A::NEG_Z;
        for (a, b) in [(e1, e2), (e2, e1)] {
            let hit =
                intersect_triangle(Vec3A::new(0.25, 0.5, 2.0), d, v0, a, b, 0.0, f32::INFINITY)
                    .unwrap();
            assert_eq!(hit.0, 2.0);
            let (b1, b2) = (hit.1, hit.2);
            let p = v0 + a * b1 + b * b2;
            assert!((p - Vec3A::new(0.25, 0.5, 0.0)).length() < 1e-6, "{p}");
            for o in [
                Vec3A::new(0.6, 0.6, 2.0),
                Vec3A::new(-0.01, 0.5, 2.0),
                Vec3A::new(0.5, -0.01, 2.0),
                Vec3A::splat(f32::NAN),
            ] {
                assert!(
                    intersect_triangle(o, d, v0, a, b, 0.0, f32::INFINITY).is_none(),
                    "{o}"
                );
            }
            // Outside (tmin, tmax): no hit.
            assert!(
                intersect_triangle(Vec3A::new(0.25, 0.25, 2.0), d, v0, a, b, 0.0, 1.5).is_none()
            );
            // Parallel ray: det = 0, no hit.
            assert!(
                intersect_triangle(Vec3A::new(0.25, 0.25, 0.0), Vec3A::X, v0, a, b, -1.0, 1.0)
                    .is_none()
            );
        }
    }

    /// The disk test accepts exactly the ellipse: for the disk with axes a = (2, 0.5, 0) and
    /// b = (0, 1, 0.3) (sheared and tilted) at c, rays towards the points c + x a + y b hit at
    /// the right distance with coordinates (x, y) inside the unit circle, and miss just
    /// outside it (by 1e-3 in radius), from either side; a parallel ray and NaN miss.
    #[test]
    fn disk_hits_inside_the_ellipse_only() {
        let (c, a, b) = (
            Vec3A::new(0.3, -0.2, 1.0),
            Vec3A::new(2.0, 0.5, 0.0),
            Vec3A::new(0.0, 1.0, 0.3),
        );
        let n = a.cross(b).normalize();
        let inf = f32::INFINITY;
        for k in 0..64 {
            let phi = k as f32 * 0.37;
            for (r, inside) in [(0.0, true), (0.5, true), (0.999, true), (1.001, false)] {
                let target = c + a * (r * phi.cos()) + b * (r * phi.sin());
                for side in [1.0, -1.0] {
                    let d = (n * -side + Vec3A::new(0.1, -0.2, 0.05)).normalize();
                    let o = target - d * 3.0;
                    match intersect_disk(o, d, c, a, b, 0.0, inf) {
                        Some((t, x, y)) => {
                            assert!(inside, "r {r} phi {phi}: hit");
                            assert!((t - 3.0).abs() < 1e-4, "{t}");
                            let (ex, ey) = (r * phi.cos(), r * phi.sin());
                            assert!((x - ex).abs() < 1e-4 && (y - ey).abs() < 1e-4);
                        }
                        None => assert!(!inside, "r {r} phi {phi} side {side}: miss"),
                    }
                }
            }
        }
        assert!(intersect_disk(c + n, a.normalize(), c, a, b, -inf, inf).is_none());
        let nan = Vec3A::splat(f32::NAN);
        assert!(intersect_disk(nan, -n, c, a, b, 0.0, inf).is_none());
    }

    /// The open cylinder against closed forms: the cylinder of radius 1 around the z axis, z in
    /// [0, 2].
    #[test]
    fn cylinder_hits_closed_forms() {
        let hit = |o: [f32; 3], d: [f32; 3], tmin: f32, tmax: f32| {
            let d = Vec3A::from(d).normalize();
            let (p0, axis) = (Vec3A::ZERO, Vec3A::Z);
            intersect_cylinder(Vec3A::from(o), d, p0, axis, 1.0, 2.0, tmin, tmax)
        };
        let inf = f32::INFINITY;
        // From outside, across the axis: the near side, at distance 5 - 1.
        assert_eq!(hit([5.0, 0.0, 1.0], [-1.0, 0.0, 0.0], 0.0, inf), 4.0);
        // The same ray beyond the end (z = 2.5): misses.
        assert_eq!(hit([5.0, 0.0, 2.5], [-1.0, 0.0, 0.0], 0.0, inf), inf);
        // From inside: the far side only.
        assert_eq!(hit([0.5, 0.0, 1.0], [1.0, 0.0, 0.0], 0.0, inf), 0.5);
        // tmax before the surface: no hit; tmin past the near side: the far side.
        assert_eq!(hit([5.0, 0.0, 1.0], [-1.0, 0.0, 0.0], 0.0, 3.9), inf);
        assert_eq!(hit([5.0, 0.0, 1.0], [-1.0, 0.0, 0.0], 4.5, inf), 6.0);
        // Down through the open top end at 45 degrees: the near root (outside, above the top)
        // is not on the surface; the inside of the far wall is: from (-2, 0, 4) along
        // (1, 0, -1) / sqrt 2 the ray meets x = -1 at z = 3 (above the end) and x = +1 at
        // z = 1, at t = 3 sqrt 2.
        let t = hit([-2.0, 0.0, 4.0], [1.0, 0.0, -1.0], 0.0, inf);
        assert!((t - 3.0 * 2f32.sqrt()).abs() < 1e-5, "{t}");
        // Parallel to the axis, inside or on the wall: never a hit.
        assert_eq!(hit([0.5, 0.0, -1.0], [0.0, 0.0, 1.0], 0.0, inf), inf);
        assert_eq!(hit([1.0, 0.0, -1.0], [0.0, 0.0, 1.0], 0.0, inf), inf);
        // Passing beside it: no hit; grazing it at the tangent point x = 1: t = 3.
        assert_eq!(hit([1.01, -3.0, 1.0], [0.0, 1.0, 0.0], 0.0, inf), inf);
        let t = hit([1.0, -3.0, 1.0], [0.0, 1.0, 0.0], 0.0, inf);
        assert!((t - 3.0).abs() < 1e-3, "{t}");
        // NaN input misses.
        assert_eq!(hit([f32::NAN, 0.0, 1.0], [-1.0, 0.0, 0.0], 0.0, inf), inf);
    }

    /// The world-space cylinder test against the cylinder's object-space equation solved in
    /// f64 (Mitsuba's way: the ray taken into the frame where the axis is z): over random
    /// cylinders and rays from around them, the same hit or miss, the same distance to 1e-4
    /// relative (or both misses within 1e-3 of an end, where rounding decides).
    #[test]
    fn cylinder_matches_object_space_equation() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut u = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f64) / (1u64 << 24) as f64
        };
        let mut disagree = 0;
        let n = 20_000;
        for _ in 0..n {
            let axis = glam::DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
            let p0 = glam::DVec3::new(u() * 4.0 - 2.0, u() * 4.0 - 2.0, u() * 4.0 - 2.0);
            let (radius, length) = (0.2 + u(), 0.5 + 2.0 * u());
            let o = p0 + glam::DVec3::new(u() * 8.0 - 4.0, u() * 8.0 - 4.0, u() * 8.0 - 4.0);
            let target = p0
                + axis * (length * (u() * 1.4 - 0.2))
                + glam::DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5) * (3.0 * radius);
            let d = (target - o).normalize();
            // Object space: axis -> z.
            let f = pt_math::Frame::from_normal(axis.as_vec3());
            let (s_, t_, n_) = (f.s.as_dvec3(), f.t.as_dvec3(), f.n.as_dvec3());
            let lo = o - p0;
            let (ox, oy, oz) = (lo.dot(s_), lo.dot(t_), lo.dot(n_));
            let (dx, dy, dz) = (d.dot(s_), d.dot(t_), d.dot(n_));
            let a = dx * dx + dy * dy;
            let b = 2.0 * (dx * ox + dy * oy);
            let c = ox * ox + oy * oy - radius * radius;
            let disc = b * b - 4.0 * a * c;
            let mut want = f64::INFINITY;
            let mut near_end = false;
            if a > 1e-12 && disc >= 0.0 {
                for t in [
                    (-b - disc.sqrt()) / (2.0 * a),
                    (-b + disc.sqrt()) / (2.0 * a),
                ] {
                    let z = oz + t * dz;
                    near_end |= (z.abs() < 1e-3) || ((z - length).abs() < 1e-3);
                    if t > 0.0 && (0.0..=length).contains(&z) {
                        want = t;
                        break;
                    }
                }
            }
            let got = intersect_cylinder(
                o.as_vec3a(),
                d.as_vec3a(),
                p0.as_vec3a(),
                axis.as_vec3a(),
                radius as f32,
                length as f32,
                0.0,
                f32::INFINITY,
            ) as f64;
            let agree = if want.is_finite() {
                (got - want).abs() <= 1e-4 * want.max(1.0)
            } else {
                got.is_infinite()
            };
            if !agree && !near_end {
                disagree += 1;
            }
        }
        assert_eq!(disagree, 0, "of {n} rays");
    }
}
