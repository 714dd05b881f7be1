//! Meshes into BVH primitives: triangles, and pairs of triangles that form a parallelogram
//! tested as one (rectangles, cube faces, quads); the light geometry of emissive meshes.

use super::{BuildError, SceneStats};
use crate::geometry::Primitive;
use crate::light::{LightShape, LightTriangle};
use pt_math::{Vec2, Vec3, Vec3A};
use pt_scene::{Geometry, SceneDesc, SourceLoc, TriangleMesh};

/// Where each BVH primitive came from.
#[derive(Clone, Copy)]
pub(super) struct PrimRef {
    pub(super) shape: u32,
    /// Triangle index within the shape's mesh (0 for spheres); for a parallelogram, the first
    /// of its two triangles (`local + 1` is the other).
    pub(super) local: u32,
    /// Which part of element `local` the primitive is. For a parallelogram: which vertex of
    /// triangle `local` is its corner `v0` (its edges run to the next two vertices in winding
    /// order). For a piece of B-spline segment `local`: which piece
    /// ([`crate::curve::Piece::code`]). `None` for a whole triangle, sphere or segment.
    pub(super) part: Option<u8>,
}

impl PrimRef {
    /// A triangle's or sphere's reference.
    pub(super) fn single(shape: u32, local: u32) -> Self {
        PrimRef {
            shape,
            local,
            part: None,
        }
    }

    /// The vertex indices of triangle `local` of `indices`, rotated so that a parallelogram's
    /// corner comes first: vertex 0 has barycentric weight `1 - b1 - b2`, 1 and 2 have `b1`
    /// and `b2` (over a parallelogram the same affine interpolation, with `1 - b1 - b2` down
    /// to -1 in the second triangle's half).
    #[inline(always)]
    pub(super) fn vertices(&self, indices: &[[u32; 3]]) -> [u32; 3] {
        let t = indices
            .get(self.local as usize)
            .copied()
            .unwrap_or([0, 0, 0]);
        match self.part {
            Some(c) => rotate(t, c),
            None => t,
        }
    }
}

/// `t` rotated so that `t[c]` comes first (winding kept); `c` < 3.
#[inline(always)]
fn rotate(t: [u32; 3], c: u8) -> [u32; 3] {
    const ORDER: [[usize; 3]; 3] = [[0, 1, 2], [1, 2, 0], [2, 0, 1]];
    ORDER[c as usize].map(|k| t[k])
}

/// Adds a mesh's non-degenerate triangles to the BVH list; for an emissive mesh also returns its
/// light triangles and their areas.
#[allow(clippy::type_complexity)]
pub(super) fn add_mesh(
    mesh: &TriangleMesh,
    shape: u32,
    emissive: bool,
    prims: &mut Vec<Primitive>,
    refs: &mut Vec<PrimRef>,
    stats: &mut SceneStats,
    loc: &SourceLoc,
) -> Result<Option<(Vec<LightTriangle>, Vec<f32>)>, BuildError> {
    let n = mesh.positions.len();
    let bad_len = |what: &str, len: usize| BuildError {
        loc: loc.clone(),
        message: format!("mesh has {len} {what} for {n} vertices"),
    };
    if let Some(ns) = &mesh.normals {
        if ns.len() != n {
            return Err(bad_len("normals", ns.len()));
        }
    }
    if let Some(uvs) = &mesh.uvs {
        if uvs.len() != n {
            return Err(bad_len("texture coordinates", uvs.len()));
        }
    }
    let mut tris = Vec::new();
    let mut areas = Vec::new();
    // The triangle that the previous one took in as the second half of its parallelogram.
    let mut merged_with_previous = None;
    for (k, idx) in mesh.indices.iter().enumerate() {
        if idx.iter().any(|&i| i as usize >= n) {
            return Err(BuildError {
                loc: loc.clone(),
                message: format!("triangle {k} has a vertex index out of range ({n} vertices)"),
            });
        }
        let p = idx.map(|i| mesh.positions[i as usize]);
        if !p.iter().all(|v| v.is_finite()) {
            return Err(BuildError {
                loc: loc.clone(),
                message: format!("triangle {k} has a non-finite vertex"),
            });
        }
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        let area = 0.5 * cross.length();
        if !(area > 0.0) {
            stats.degenerate_triangles += 1;
            continue;
        }
        stats.triangles += 1;
        if merged_with_previous == Some(k) {
            // Already in the BVH as the second half of a parallelogram.
        } else if let Some(corner) = mesh
            .attributes
            .is_empty()
            .then(|| parallelogram_corner(mesh, k))
            .flatten()
        {
            // (Meshes with attributes keep their triangles: a face attribute may differ
            // between the two halves, and a vertex attribute need not be affine over the pair.)
            let r = PrimRef {
                shape,
                local: k as u32,
                part: Some(corner),
            };
            prims.push(parallelogram_primitive(mesh, r));
            refs.push(r);
            stats.parallelograms += 1;
            merged_with_previous = Some(k + 1);
        } else {
            prims.push(triangle_primitive(p));
            refs.push(PrimRef::single(shape, k as u32));
        }
        if !emissive {
            continue;
        }
        let ng = cross.normalize();
        let nrm = match &mesh.normals {
            Some(ns) => idx.map(|i| {
                ns.get(i as usize)
                    .copied()
                    .and_then(Vec3::try_normalize)
                    .unwrap_or(ng)
            }),
            None => [ng; 3],
        };
        let uv = match &mesh.uvs {
            Some(uvs) => idx.map(|i| uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO)),
            None => [Vec2::ZERO, Vec2::X, Vec2::Y],
        };
        tris.push(LightTriangle { p, n: nrm, uv });
        areas.push(area);
    }
    Ok((!tris.is_empty()).then_some((tris, areas)))
}

/// The BVH primitive of a triangle with vertices `p`.
fn triangle_primitive(p: [Vec3; 3]) -> Primitive {
    Primitive::Triangle {
        v0: Vec3A::from(p[0]),
        e1: Vec3A::from(p[1] - p[0]),
        e2: Vec3A::from(p[2] - p[0]),
    }
}

/// The light shape and area of an emissive mesh of two triangles that went into the BVH as the
/// parallelogram `prim` (source `r`): sampled as one parallelogram. `None` when `prim` is not a
/// parallelogram, or the mesh has no texture coordinates (its triangles then keep the default
/// per-triangle uvs a textured emitter would see).
pub(super) fn parallelogram_light(
    mesh: &TriangleMesh,
    prim: Primitive,
    r: PrimRef,
) -> Option<(LightShape, f32)> {
    let Primitive::Parallelogram { v0, e1, e2 } = prim else {
        return None;
    };
    let uvs = mesh.uvs.as_ref()?;
    let corners = r.vertices(&mesh.indices);
    let [a, b, c] = corners.map(|i| uvs[i as usize]);
    let cross = Vec3::from(e1.cross(e2));
    let n = match &mesh.normals {
        // Equal at all four corners (a condition of the merge).
        Some(ns) => ns[corners[0] as usize].normalize(),
        None => cross.normalize(),
    };
    Some((
        LightShape::Parallelogram {
            v0: v0.into(),
            e1: e1.into(),
            e2: e2.into(),
            n,
            uv: [a, b - a, c - a],
        },
        cross.length(),
    ))
}

/// The parallelogram whose corner and edges are the vertices of triangle `r.local` of `mesh`,
/// rotated by `r.part` (see [`parallelogram_corner`]).
fn parallelogram_primitive(mesh: &TriangleMesh, r: PrimRef) -> Primitive {
    let [v0, v1, v2] = r
        .vertices(&mesh.indices)
        .map(|i| mesh.positions[i as usize]);
    Primitive::Parallelogram {
        v0: Vec3A::from(v0),
        e1: Vec3A::from(v1 - v0),
        e2: Vec3A::from(v2 - v0),
    }
}

/// Whether mesh triangles `k` and `k + 1` together form a parallelogram that can be tested as
/// one primitive, and if so which vertex of triangle `k` is its corner (the vertex that
/// triangle `k + 1` lacks). They must share exactly two vertex indices (the diagonal), be
/// wound the same way, and their four corners `x` (triangle k's own), `y` (triangle k+1's
/// own) and the diagonal's `s1`, `s2` must satisfy `x + y = s1 + s2` (the diagonals bisect
/// each other) to within float rounding of the vertex positions (16 ULPs of the largest
/// coordinate: transformed rectangles and cube faces miss it by a few), and so must their
/// texture coordinates, which are then one affine map over the whole parallelogram. Vertex
/// normals and tangents, where present, must be the same at all four corners (flat faces).
/// Both triangles are known to be valid (indices in range, finite); `k + 1`'s area is checked
/// here.
fn parallelogram_corner(mesh: &TriangleMesh, k: usize) -> Option<u8> {
    let (a, b) = (mesh.indices[k], *mesh.indices.get(k + 1)?);
    let n = mesh.positions.len();
    if b.iter().any(|&i| i as usize >= n) {
        return None;
    }
    let shared = |i: u32| b.contains(&i);
    if a.iter().filter(|&&i| shared(i)).count() != 2 || a[0] == a[1] || a[1] == a[2] || a[0] == a[2]
    {
        return None;
    }
    let c = a.iter().position(|&i| !shared(i))?;
    let [x, s1, s2] = rotate(a, c as u8);
    let y = *b.iter().find(|&&i| !a.contains(&i))?;
    // Consistent winding: triangle k+1 runs along the diagonal from s2 to s1.
    let at = |i: u32| b.iter().position(|&j| j == i).unwrap_or(0);
    if (at(s2) + 1) % 3 != at(s1) {
        return None;
    }
    let p = |i: u32| mesh.positions[i as usize];
    let corners = [p(x), p(y), p(s1), p(s2)];
    if !corners.iter().all(|v| v.is_finite())
        || (p(s1) - p(y)).cross(p(s2) - p(y)).length_squared() <= 0.0
    {
        return None;
    }
    let scale = corners
        .iter()
        .map(|v| v.abs().max_element())
        .fold(0.0f32, f32::max);
    if (p(x) + p(y) - p(s1) - p(s2)).abs().max_element() > 16.0 * f32::EPSILON * scale {
        return None;
    }
    if let Some(uv) = &mesh.uvs {
        let t = |i: u32| uv[i as usize];
        let uv_scale = [t(x), t(y), t(s1), t(s2)]
            .iter()
            .map(|v| v.abs().max_element())
            .fold(1.0f32, f32::max);
        if !((t(x) + t(y) - t(s1) - t(s2)).abs().max_element() <= 16.0 * f32::EPSILON * uv_scale) {
            return None;
        }
    }
    let same = |v: [pt_math::Vec4; 4]| v.iter().all(|&u| u == v[0]);
    if let Some(ns) = &mesh.normals {
        if !same([x, y, s1, s2].map(|i| ns[i as usize].extend(0.0))) {
            return None;
        }
    }
    if let Some(ts) = &mesh.tangents {
        if ts.len() != n || !same([x, y, s1, s2].map(|i| ts[i as usize])) {
            return None;
        }
    }
    Some(c as u8)
}

/// The BVH primitive `r` refers to, made from the description as the shape loop made it.
pub(super) fn primitive_of(desc: &SceneDesc, r: PrimRef) -> Primitive {
    primitive_of_geometry(&desc.shapes[r.shape as usize].geometry, r)
}

/// The BVH primitive `r` refers to in the shape `geometry`.
pub(super) fn primitive_of_geometry(geometry: &Geometry, r: PrimRef) -> Primitive {
    match geometry {
        Geometry::Mesh(m) if r.part.is_some() => parallelogram_primitive(m, r),
        Geometry::Mesh(m) => {
            triangle_primitive(m.indices[r.local as usize].map(|i| m.positions[i as usize]))
        }
        Geometry::Disk(d) => Primitive::Disk {
            center: d.center.into(),
            a: d.axes[0].into(),
            b: d.axes[1].into(),
        },
        &Geometry::Sphere {
            center,
            radius,
            flip_normals,
            ..
        } => Primitive::Sphere {
            center: center.into(),
            radius,
            flip: flip_normals,
        },
        &Geometry::Cylinder {
            p0,
            frame,
            radius,
            length,
            flip_normals,
        } => Primitive::Cylinder {
            p0: p0.into(),
            axis: frame.z_axis.into(),
            radius,
            length,
            flip: flip_normals,
        },
        Geometry::SdfGrid(g) => sdf_voxel(g, r.local),
        Geometry::Curves(c) => {
            let cp = c.segment(r.local as usize);
            match c.basis {
                pt_scene::CurveBasis::Linear => Primitive::RoundCone {
                    p0: cp[0].truncate().into(),
                    p1: cp[1].truncate().into(),
                    r0: cp[0].w,
                    r1: cp[1].w,
                },
                pt_scene::CurveBasis::BSpline => {
                    let piece = crate::curve::Piece::from_code(r.part.unwrap_or(0));
                    let (p, radii) = piece.of(
                        [0, 1, 2, 3].map(|i| cp[i].truncate()),
                        [0, 1, 2, 3].map(|i| cp[i].w),
                    );
                    Primitive::new_bspline(p, radii, piece)
                }
            }
        }
    }
}

/// The BVH primitive of the voxel of `grid` whose lowest corner is grid vertex `index`.
pub(super) fn sdf_voxel(grid: &pt_scene::SdfGrid, index: u32) -> Primitive {
    let [nx, ny, _] = grid.resolution;
    let v = [index % nx, (index / nx) % ny, index / (nx * ny)];
    let (lo, size) = grid.voxel_box(v);
    Primitive::SdfVoxel {
        lo,
        size,
        f: grid.corners(v),
    }
}

/// Bounding sphere (centre, radius) of all primitives; a unit sphere at the origin if empty.
pub(super) fn bounding_sphere(boxes: impl Iterator<Item = obvhs::aabb::Aabb>) -> (Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for b in boxes {
        lo = lo.min(b.min.into());
        hi = hi.max(b.max.into());
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (Vec3::ZERO, 1.0);
    }
    let c = 0.5 * (lo + hi);
    (c, (0.5 * (hi - lo).length()).max(1e-6))
}
