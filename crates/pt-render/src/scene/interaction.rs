//! A hit's surface data ([`Interaction`]): position, normals, texture coordinates and
//! tangents, one function per kind of primitive, all in the space of the accel that was hit
//! (world space, or an instanced group's own). Every function here runs once per ray hit and
//! is inlined into the path loop.

use super::mesh::PrimRef;
use super::{Scene, ShapeData};
use crate::accel::{Accel, AccelHit};
use crate::geometry::{Interaction, Primitive};
use pt_math::{Mat3, Ray, Vec2, Vec3, Vec3A, Vec4};

impl Scene {
    /// The surface data of `hit`, a hit of `ray` on `accel`'s primitive, whose shapes and faces
    /// `prim_refs` gives (in the space of `accel` and `ray`).
    #[inline(always)]
    pub(super) fn interaction(
        &self,
        accel: &Accel,
        prim_refs: &[PrimRef],
        ray: &Ray,
        hit: AccelHit,
    ) -> Interaction {
        let AccelHit {
            index: id,
            t,
            b1,
            b2,
        } = hit;
        let r = prim_refs[id];
        let shape = &self.shapes[r.shape as usize];
        let analytic = |p, n, uv, dp| Interaction::analytic(p, n, uv, dp, t, r.shape, id as u32);
        match accel.prims[id] {
            Primitive::Triangle { v0, e1, e2 } | Primitive::Parallelogram { v0, e1, e2 } => {
                let ng = match accel.unit_normals.get(id) {
                    Some(&n) => n,
                    None => Vec3::from(e1.cross(e2)).normalize(),
                };
                let mut it = mesh_interaction(shape, r, [v0, e1, e2], ng, Vec2::new(b1, b2));
                (it.t, it.prim) = (t, id as u32);
                it
            }
            Primitive::Disk { center, a, b } => {
                // The hit's object-space coordinates are its barycentrics; the shape's frame
                // holds the front normal (column 2).
                let (a, b) = (Vec3::from(a), Vec3::from(b));
                let n = shape
                    .frame
                    .map_or_else(|| a.cross(b).normalize(), |f| f.z_axis);
                let p = Vec3::from(center) + a * b1 + b * b2;
                let (uv, dp) = crate::light::disk_uv(a, b, Vec2::new(b1, b2));
                analytic(p, n, uv, dp)
            }
            Primitive::Sphere {
                center,
                radius,
                flip,
            } => {
                let frame = shape.frame.unwrap_or(Mat3::IDENTITY);
                let (p, n, uv, dp) = sphere_point(frame, center.into(), radius, ray.at(t));
                analytic(p, if flip { -n } else { n }, uv, dp)
            }
            Primitive::Cylinder {
                p0,
                radius,
                length,
                flip,
                ..
            } => {
                let frame = shape.frame.unwrap_or(Mat3::IDENTITY);
                let (p, n, uv, dp) = cylinder_point(frame, p0.into(), radius, length, ray.at(t));
                analytic(p, if flip { -n } else { n }, uv, dp)
            }
            Primitive::SdfVoxel { lo, size, ref f } => {
                // As Mitsuba's sdfgrid: no texture coordinates, no dp/du; the geometric
                // normal is the voxel's gradient, the shading normal the smooth one unless
                // `normals` is `analytic`.
                let p = ray.at(t);
                let ng = crate::sdf::voxel_normal(lo, size, f, p);
                let mut it = analytic(p, ng, Vec2::ZERO, [Vec3::ZERO; 2]);
                if let Some(g) = shape.sdf.as_deref().filter(|g| g.smooth_normals) {
                    let ns = crate::sdf::smooth_normal(g, p);
                    if ns != Vec3::ZERO {
                        it.ns = ns;
                    }
                }
                it
            }
            Primitive::RoundCone { p0, p1, r0, r1 } => {
                let h = crate::curve::round_cone_hit(
                    [p0, p1],
                    [r0, r1],
                    b1,
                    ray.at(t),
                    r.local,
                    shape.curve_segments,
                );
                analytic(h.p, h.n, h.uv, [h.dpdu, h.dpdv])
            }
            Primitive::BSpline { piece, .. } => {
                let (p, radii) = accel.prims[id].bspline_segment().unwrap_or_default();
                let h = crate::curve::bspline_hit(
                    &p,
                    &radii,
                    b1,
                    ray.at(t),
                    crate::curve::Piece::from_code(piece).range(),
                    r.local,
                    shape.curve_segments,
                );
                analytic(h.p, h.n, h.uv, [h.dpdu, h.dpdv])
            }
        }
    }
}

/// The surface data at barycentrics `b` = (b1, b2) of the triangle (or parallelogram) with
/// corner `v0` and edges `e1`, `e2` of mesh `shape`, face `r`, whose unit geometric normal is
/// `ng`: position, vertex attributes interpolated (shading normal, uv with dp/du and dp/dv,
/// tangent), barycentric uv without uvs. `t` and `prim` are left 0 for the caller.
#[inline(always)]
fn mesh_interaction(
    shape: &ShapeData,
    r: PrimRef,
    [v0, e1, e2]: [Vec3A; 3],
    ng: Vec3,
    b: Vec2,
) -> Interaction {
    let (b1, b2) = (b.x, b.y);
    let b0 = 1.0 - b1 - b2;
    let p = Vec3::from(v0 + e1 * b1 + e2 * b2);
    // The vertex indices only for shapes with vertex attributes (a flat shape without uvs,
    // such as most walls, never reads them: one memory access less).
    let idx = || r.vertices(&shape.indices);
    let ns = match &shape.normals {
        Some(n) => {
            let idx = idx();
            let v = n[idx[0] as usize] * b0 + n[idx[1] as usize] * b1 + n[idx[2] as usize] * b2;
            v.try_normalize().unwrap_or(ng)
        }
        None => ng,
    };
    let (uv, dpdu, dpdv) = match &shape.uvs {
        Some(uv) => {
            let idx = idx();
            let t = [0, 1, 2].map(|k| uv[idx[k] as usize]);
            let (dpdu, dpdv) = uv_derivatives(t, Vec3::from(e1), Vec3::from(e2));
            (t[0] * b0 + t[1] * b1 + t[2] * b2, dpdu, dpdv)
        }
        None => (Vec2::new(b1, b2), Vec3::ZERO, Vec3::ZERO),
    };
    let tangent = match &shape.tangents {
        Some(ts) => {
            let idx = idx();
            let (a, b, c) = (
                ts[idx[0] as usize],
                ts[idx[1] as usize],
                ts[idx[2] as usize],
            );
            // Handedness is constant over a triangle in well-formed data; take vertex 0's.
            let handedness = if a.w < 0.0 { -1.0 } else { 1.0 };
            (a * b0 + b * b1 + c * b2).truncate().extend(handedness)
        }
        None => Vec4::ZERO,
    };
    Interaction {
        p,
        ng,
        ns,
        uv,
        dpdu,
        dpdv,
        tangent,
        t: 0.0,
        shape: r.shape,
        prim: 0,
        b,
    }
}

/// dp/du and dp/dv of a triangle with edges `e1`, `e2` and vertex uvs `t` (pbrt-v4 eq. 6.7):
/// the solution of [e1 e2] = [dpdu dpdv] [du1 du2; dv1 dv2]; zero where the uvs are degenerate.
#[inline(always)]
fn uv_derivatives(t: [Vec2; 3], e1: Vec3, e2: Vec3) -> (Vec3, Vec3) {
    let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
    let det = d1.x * d2.y - d1.y * d2.x;
    let finite = |d: Vec3| if d.is_finite() { d } else { Vec3::ZERO };
    if det != 0.0 {
        (
            finite((e1 * d2.y - e2 * d1.y) / det),
            finite((e2 * d1.x - e1 * d2.x) / det),
        )
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    }
}

/// Position, outward normal, uv and [dp/du, dp/dv] at `hit` on the sphere of `center` and
/// `radius` whose object-to-world rotation is `frame` (world space).
#[inline(always)]
fn sphere_point(
    frame: Mat3,
    center: Vec3,
    radius: f32,
    hit: Vec3,
) -> (Vec3, Vec3, Vec2, [Vec3; 2]) {
    let local = (hit - center).normalize();
    // Re-project onto the surface: removes the error of o + t d (pbrt-v4 6.8.5).
    let p = center + local * radius;
    // Mitsuba's sphere: u = azimuth about the object's z axis / 2 pi, v = polar angle / pi;
    // dp/du = 2 pi r R (-y, x, 0) in object coordinates (R the rotation), whose direction
    // orients anisotropic BSDFs.
    let uv = crate::light::sphere_uv(frame, local);
    let o = frame.transpose() * local;
    let dpdu = frame * Vec3::new(-o.y, o.x, 0.0) * (std::f32::consts::TAU * radius);
    // v = polar angle / pi: dp/dv = pi r (cos(theta) cos(phi), cos(theta) sin(phi),
    // -sin(theta)) with the object-space direction (sin(theta) cos(phi), ...).
    let rho = Vec2::new(o.x, o.y).length();
    let (cos_phi, sin_phi) = if rho > 0.0 {
        (o.x / rho, o.y / rho)
    } else {
        (1.0, 0.0)
    };
    let dpdv =
        frame * Vec3::new(o.z * cos_phi, o.z * sin_phi, -rho) * (std::f32::consts::PI * radius);
    (p, local, uv, [dpdu, dpdv])
}

/// Position, outward normal, uv and [dp/du, dp/dv] at `hit` on the cylinder from `p0` of
/// `radius` and `length` along the z axis of its object-to-world rotation `frame` (world
/// space).
#[inline(always)]
fn cylinder_point(
    frame: Mat3,
    p0: Vec3,
    radius: f32,
    length: f32,
    hit: Vec3,
) -> (Vec3, Vec3, Vec2, [Vec3; 2]) {
    // Mitsuba's cylinder: u = azimuth about the object's z axis / 2 pi (from its x axis
    // towards y), v = z / length; dp/du = 2 pi R (-y, x, 0) in object coordinates (R the
    // rotation).
    let local = frame.transpose() * (hit - p0);
    let across = Vec2::new(local.x, local.y);
    let rho = across.length();
    let dir = if rho > 0.0 { across / rho } else { Vec2::X };
    // Re-projected onto the surface, as for the sphere.
    let on = dir * radius;
    let p = p0 + frame * Vec3::new(on.x, on.y, local.z);
    let outward = frame * Vec3::new(dir.x, dir.y, 0.0);
    let mut phi = pt_math::fastmath::atan2(dir.y, dir.x);
    if phi < 0.0 {
        phi += std::f32::consts::TAU;
    }
    let uv = Vec2::new(phi / std::f32::consts::TAU, local.z / length);
    let dpdu = frame * Vec3::new(-on.y, on.x, 0.0) * std::f32::consts::TAU;
    (p, outward, uv, [dpdu, frame * Vec3::new(0.0, 0.0, length)])
}
