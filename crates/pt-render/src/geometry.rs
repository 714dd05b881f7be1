//! Primitives (triangles and analytic spheres), their ray intersection, and the surface
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
    /// A sphere; `flip` makes the front side (normal) face inwards.
    Sphere {
        /// Centre.
        center: Vec3A,
        /// Radius (> 0).
        radius: f32,
        /// Whether the normal points inwards.
        flip: bool,
    },
}

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
            Primitive::Sphere { center, radius, .. } => {
                Aabb::new(center - Vec3A::splat(radius), center + Vec3A::splat(radius))
            }
        }
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
            Primitive::Sphere { center, radius, .. } => {
                intersect_sphere(origin, dir, center, radius, tmin, tmax)
            }
        }
    }

    /// [`Primitive::intersect`] with the hit's barycentrics `(t, b1, b2)` (the weights of
    /// `v0 + e1` and `v0 + e2`; 0 for spheres); `t` is +inf on a miss.
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
            Primitive::Sphere { center, radius, .. } => (
                intersect_sphere(origin, dir, center, radius, tmin, tmax),
                0.0,
                0.0,
            ),
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
    moller_trumbore::<false>(o, d, v0, e1, e2, tmin, tmax)
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
    moller_trumbore::<true>(o, d, v0, e1, e2, tmin, tmax)
}

/// Möller & Trumbore's test over the triangle (`PARALLELOGRAM` false) or the parallelogram
/// spanned by `e1` and `e2` at `v0`.
#[inline(always)]
fn moller_trumbore<const PARALLELOGRAM: bool>(
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
    let inside = if PARALLELOGRAM {
        b2 <= 1.0
    } else {
        b1 + b2 <= 1.0
    };
    // `&` rather than `&&` (or `contains`, which short-circuits): evaluate every comparison,
    // branch once.
    #[allow(clippy::manual_range_contains)]
    let hit =
        (det != 0.0) & (b1 >= 0.0) & (b1 <= 1.0) & (b2 >= 0.0) & inside & (t > tmin) & (t < tmax);
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
    let f = o - center;
    let b = -f.dot(d); // distance along d to the point closest to the centre
    let perp = f + d * b; // offset of that point from the centre
    let disc = radius * radius - perp.length_squared();
    if !(disc >= 0.0) {
        return f32::INFINITY;
    }
    let sq = disc.sqrt();
    // Stable pair of roots: q has the larger magnitude, the other root is c / q.
    let c = f.length_squared() - radius * radius;
    let q = if b >= 0.0 { b + sq } else { b - sq };
    let (mut t0, mut t1) = (c / q, q);
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if q == 0.0 {
        t0 = 0.0;
        t1 = 0.0;
    }
    if t0 > tmin && t0 < tmax {
        t0
    } else if t1 > tmin && t1 < tmax {
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
}
