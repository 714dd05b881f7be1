//! Patches: the scene's surfaces cut into small flat triangles, each with a constant radiosity.
//!
//! Every mesh triangle is split regularly into `k^2` sub-triangles, `k = ceil(longest edge / h)`,
//! so that no patch edge is longer than the target size `h` (scene units). Spheres are tessellated
//! as subdivided icosahedra with chords of about `h`. A triangle becomes one patch on its front
//! side (the side `(p1 - p0) x (p2 - p0)` points to); a `twosided` material adds a second patch
//! on the back, with the same reflectance and no emission (area emitters are one-sided). The back
//! of a one-sided surface is not a patch: it reflects and emits nothing (black), as in the path
//! tracer.
//!
//! Regular splitting keeps neighbouring triangles conforming when they share an edge and have the
//! same `k` (rectangles, cubes, regular meshes); elsewhere it leaves T-junctions, which only affect
//! the vertex-smoothed display. Vertices are welded by position (quantised to 1e-6 of the scene
//! diagonal) so that smoothing can find a vertex's patches.

use crate::RadiosityError;
use glam::Vec3;
use pt_render::texture::Role;
use pt_scene::{BsdfDesc, BsdfKind, Geometry, SceneDesc, ShapeDesc, SpectrumDesc};
use std::borrow::Cow;
use std::collections::HashMap;

/// Marks "no patch" (the back of a one-sided surface) in [`Triangle::back`].
pub const NO_PATCH: u32 = u32::MAX;

/// One patch: a flat triangle with constant reflectance, emission and (after solving) radiosity.
#[derive(Clone, Copy, Debug)]
pub struct Patch {
    /// Indices of the three corners in [`PatchMesh::vertices`] (same order as the triangle's).
    pub corners: [u32; 3],
    /// Area, scene units squared.
    pub area: f32,
    /// Unit normal of the side this patch faces (world space): the triangle's front normal for a
    /// front patch, its negation for a back patch.
    pub normal: Vec3,
    /// Centroid, world space.
    pub centroid: Vec3,
    /// Diffuse reflectance (albedo) per linear RGB channel, in [0, 1].
    pub reflectance: [f32; 3],
    /// Emitted radiosity per channel, W m^-2: `pi * Le` for an area emitter of radiance `Le`
    /// on its front side, 0 elsewhere.
    pub emission: [f32; 3],
    /// Index of the scene shape (in `SceneDesc::shapes`) the patch belongs to.
    pub shape: u32,
    /// Index of its geometric triangle in [`PatchMesh::triangles`].
    pub triangle: u32,
}

/// A geometric triangle (one BVH primitive) and the patches on its two sides.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// Vertex indices into [`PatchMesh::vertices`], counter-clockwise seen from the front.
    pub v: [u32; 3],
    /// Unit front normal, world space.
    pub normal: Vec3,
    /// The patch on the front side.
    pub front: u32,
    /// The patch on the back side, or [`NO_PATCH`] for a one-sided material.
    pub back: u32,
}

/// The patches of a scene with their shared vertices.
#[derive(Clone, Debug, Default)]
pub struct PatchMesh {
    /// Welded vertex positions, world space.
    pub vertices: Vec<Vec3>,
    /// Geometric triangles, one per BVH primitive.
    pub triangles: Vec<Triangle>,
    /// Patches (front patches, and back patches of two-sided materials).
    pub patches: Vec<Patch>,
    /// The target patch size used (longest edge, scene units).
    pub patch_size: f32,
    /// Scene bounds (min, max), world space.
    pub bounds: (Vec3, Vec3),
    /// Method failures the user should see (materials that had to be treated as diffuse,
    /// degenerate triangles dropped), each naming the scene element.
    pub warnings: Vec<String>,
}

/// The default patch size as a fraction of the scene's bounding-box diagonal: 1/32 gives about
/// 10,000 patches in the Cornell box (longest edge 0.108 m for its 2 m walls).
pub const DEFAULT_RELATIVE_PATCH_SIZE: f32 = 1.0 / 32.0;

/// Icosahedron chord length / circumradius.
const ICO_EDGE: f32 = 1.051_462_2;
/// Icosahedron inradius / circumradius.
const ICO_INRADIUS: f32 = 0.794_654_5;

/// RGB of a spectral input in a role (tabulated spectra are converted as Mitsuba's RGB
/// variants convert them: the solver works per RGB channel).
fn rgb(s: &SpectrumDesc, role: Role) -> [f32; 3] {
    pt_render::texture::rgb_of(s, role)
}

/// Diffuse reflectance and two-sidedness of a material. Models radiosity cannot represent are
/// replaced by grey diffuse 0.5 with a warning.
fn material(b: &BsdfDesc, warnings: &mut Vec<String>) -> Result<([f32; 3], bool), RadiosityError> {
    #[allow(unreachable_patterns)] // other BSDF models will be added to the loader
    match &b.kind {
        BsdfKind::Diffuse { reflectance } => {
            let Some(reflectance) = reflectance.as_constant() else {
                warnings.push(format!(
                    "{}: radiosity gives each patch one reflectance; this textured reflectance is treated as 0.5 (not yet implemented: per-patch texture means)",
                    b.loc
                ));
                return Ok(([0.5; 3], false));
            };
            let r = rgb(reflectance, Role::Albedo);
            if !r.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(RadiosityError::scene(
                    &b.loc,
                    format!("diffuse reflectance {r:?} must be finite and non-negative"),
                ));
            }
            if r.iter().any(|&v| v > 1.0) {
                return Err(RadiosityError::scene(
                    &b.loc,
                    format!("diffuse reflectance {r:?} exceeds 1: not energy conserving, the radiosity iteration would diverge"),
                ));
            }
            Ok((r, false))
        }
        BsdfKind::TwoSided { inner } => {
            let (r, _) = material(inner, warnings)?;
            Ok((r, true))
        }
        _ => {
            warnings.push(format!(
                "{}: radiosity represents only diffuse surfaces; this material is treated as diffuse with reflectance 0.5",
                b.loc
            ));
            Ok(([0.5; 3], false))
        }
    }
}

/// Welds vertices by quantised position.
struct Welder {
    map: HashMap<[i64; 3], u32>,
    inv_quantum: f32,
}

impl Welder {
    fn add(&mut self, vertices: &mut Vec<Vec3>, p: Vec3) -> u32 {
        let k = (p * self.inv_quantum).round();
        let key = [k.x as i64, k.y as i64, k.z as i64];
        *self.map.entry(key).or_insert_with(|| {
            vertices.push(p);
            (vertices.len() - 1) as u32
        })
    }
}

/// The geometry with a disk turned into its triangle fan (the solver's patches are triangles),
/// other geometry as it is.
fn meshed(g: &Geometry) -> Cow<'_, Geometry> {
    match g {
        Geometry::Disk(d) => Cow::Owned(Geometry::Mesh(d.to_mesh())),
        _ => Cow::Borrowed(g),
    }
}

/// Scene bounds over meshes and spheres.
fn scene_bounds(desc: &SceneDesc) -> (Vec3, Vec3) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for s in &desc.shapes {
        match &s.geometry {
            Geometry::Mesh(m) => {
                for p in m.positions.iter().filter(|p| p.is_finite()) {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
            }
            Geometry::Disk(d) => {
                let (a, b) = d.bounds();
                lo = lo.min(a);
                hi = hi.max(b);
            }
            &Geometry::Sphere { center, radius, .. } => {
                if center.is_finite() && radius.is_finite() {
                    lo = lo.min(center - Vec3::splat(radius.abs()));
                    hi = hi.max(center + Vec3::splat(radius.abs()));
                }
            }
            &Geometry::Cylinder {
                p0,
                frame,
                radius,
                length,
                ..
            } => {
                let (a, b) = pt_scene::cylinder_bounds(p0, frame.z_axis, radius, length);
                if a.is_finite() && b.is_finite() {
                    lo = lo.min(a);
                    hi = hi.max(b);
                }
            }
            Geometry::SdfGrid(g) => {
                lo = lo.min(g.origin);
                hi = hi.max(g.origin + g.extent);
            }
            Geometry::Curves(c) => {
                let (a, b) = c.bounds();
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
    }
    if lo.x > hi.x {
        (Vec3::ZERO, Vec3::ZERO)
    } else {
        (lo, hi)
    }
}

/// The 12 vertices and 20 counter-clockwise (outward) faces of a unit icosahedron.
fn icosahedron() -> ([Vec3; 12], [[usize; 3]; 20]) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let v = [
        Vec3::new(-1.0, t, 0.0),
        Vec3::new(1.0, t, 0.0),
        Vec3::new(-1.0, -t, 0.0),
        Vec3::new(1.0, -t, 0.0),
        Vec3::new(0.0, -1.0, t),
        Vec3::new(0.0, 1.0, t),
        Vec3::new(0.0, -1.0, -t),
        Vec3::new(0.0, 1.0, -t),
        Vec3::new(t, 0.0, -1.0),
        Vec3::new(t, 0.0, 1.0),
        Vec3::new(-t, 0.0, -1.0),
        Vec3::new(-t, 0.0, 1.0),
    ]
    .map(|p| p.normalize());
    let f = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (v, f)
}

/// Splits the triangle (p0, p1, p2) into k^2 sub-triangles and calls `emit` with each, keeping
/// the winding. `map` is applied to every grid point (identity for meshes, projection onto the
/// sphere for spheres).
fn split(p: [Vec3; 3], k: u32, map: &dyn Fn(Vec3) -> Vec3, emit: &mut dyn FnMut([Vec3; 3])) {
    let kf = k as f32;
    let at = |i: u32, j: u32| {
        let (a, b) = (i as f32 / kf, j as f32 / kf);
        map(p[0] * (1.0 - a - b) + p[1] * a + p[2] * b)
    };
    for i in 0..k {
        for j in 0..k - i {
            emit([at(i, j), at(i + 1, j), at(i, j + 1)]);
            if i + j + 1 < k {
                emit([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
}

/// What every patch of one shape carries: the shape's index, its RGB reflectance, its
/// emitted radiosity (front side only; W m^-2 per channel, see [`Patch::emission`]) and
/// whether it has a back side.
#[derive(Clone, Copy, Debug)]
struct Surface {
    shape: u32,
    reflectance: [f32; 3],
    emission: [f32; 3],
    two_sided: bool,
}

/// A shape's emitted radiosity, pi times its area emitter's radiance (RGB), or zero without
/// one; the radiance must be a finite, non-negative constant.
fn emitted_radiosity(s: &ShapeDesc) -> Result<[f32; 3], RadiosityError> {
    Ok(match &s.emitter {
        Some(em) => {
            let le = match em.radiance.as_constant() {
                Some(s) => rgb(s, Role::Emission),
                None => {
                    return Err(RadiosityError::scene(
                        &em.loc,
                        "radiosity needs a constant radiance (textured emitters are not yet supported by radiosity)",
                    ))
                }
            };
            if !le.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(RadiosityError::scene(
                    &em.loc,
                    "radiance must be finite and non-negative",
                ));
            }
            le.map(|v| std::f32::consts::PI * v)
        }
        None => [0.0; 3],
    })
}

impl PatchMesh {
    /// Cuts the scene into patches of at most `patch_size` (longest edge, scene units; `None`:
    /// [`DEFAULT_RELATIVE_PATCH_SIZE`] of the scene diagonal). Fails, naming the element, on
    /// invalid input (index out of range, non-finite vertex, bad material or emitter) and when
    /// more than `max_patches` patches would be made.
    pub fn build(
        desc: &SceneDesc,
        patch_size: Option<f32>,
        max_patches: usize,
    ) -> Result<PatchMesh, RadiosityError> {
        if let Some(i) = desc.instances.first() {
            return Err(RadiosityError::scene(
                &i.loc,
                "radiosity does not support instances (not yet implemented): render with the path tracer",
            ));
        }
        let bounds = scene_bounds(desc);
        let diag = (bounds.1 - bounds.0).length();
        let h = match patch_size {
            Some(h) if h.is_finite() && h > 0.0 => h,
            Some(h) => {
                return Err(RadiosityError::Params(format!(
                    "patch_size must be positive and finite, got {h}"
                )))
            }
            None => (diag * DEFAULT_RELATIVE_PATCH_SIZE).max(f32::MIN_POSITIVE),
        };
        let mut mesh = PatchMesh {
            patch_size: h,
            bounds,
            ..Default::default()
        };
        let mut welder = Welder {
            map: HashMap::new(),
            inv_quantum: 1.0 / (1e-6 * diag).max(1e-12),
        };

        // First pass: validate and count, so that a tiny patch size fails before allocating.
        let mut count = 0u64;
        for s in &desc.shapes {
            count += Self::count_shape(s, h)?;
        }
        if count > max_patches as u64 {
            return Err(RadiosityError::Params(format!(
                "patch_size {h} would make {count} triangles (limit {max_patches}); use a larger patch_size"
            )));
        }

        for light in &desc.lights {
            mesh.warnings.push(format!(
                "{}: radiosity supports only area emitters on shapes; this light is ignored",
                light.loc
            ));
        }
        for (si, s) in desc.shapes.iter().enumerate() {
            let bsdf = desc.bsdfs.get(s.bsdf).ok_or_else(|| {
                RadiosityError::scene(&s.loc, format!("BSDF index {} out of range", s.bsdf))
            })?;
            let (reflectance, two_sided) = material(bsdf, &mut mesh.warnings)?;
            let surface = Surface {
                shape: si as u32,
                reflectance,
                emission: emitted_radiosity(s)?,
                two_sided,
            };
            let degenerate = mesh.add_shape(&mut welder, &s.geometry, h, &surface);
            if degenerate > 0 {
                mesh.warnings.push(format!(
                    "{}: {degenerate} zero-area triangles were left out",
                    s.loc
                ));
            }
        }
        Ok(mesh)
    }

    /// Cuts `geometry` (a mesh or a sphere: [`Self::count_shape`] refused the others) into
    /// patches of longest edge about `h` with the properties of `surface`, welding their
    /// corners; returns how many zero-area triangles were left out.
    fn add_shape(
        &mut self,
        welder: &mut Welder,
        geometry: &Geometry,
        h: f32,
        surface: &Surface,
    ) -> usize {
        let mut degenerate = 0usize;
        let mut add = |t: [Vec3; 3], mesh: &mut PatchMesh| {
            if !mesh.add_triangle(welder, t, surface) {
                degenerate += 1;
            }
        };
        match &*meshed(geometry) {
            Geometry::Mesh(m) => {
                for idx in &m.indices {
                    let p = idx.map(|i| m.positions[i as usize]);
                    let k = subdivisions(&p, h);
                    split(p, k, &|q| q, &mut |t| add(t, self));
                }
            }
            &Geometry::Sphere {
                center,
                radius,
                flip_normals,
                ..
            } => {
                let (v, faces) = icosahedron();
                let k = sphere_subdivisions(radius, h);
                for f in faces {
                    let mut p = f.map(|i| v[i]);
                    if flip_normals {
                        p.swap(1, 2);
                    }
                    split(p, k, &|q| center + q.normalize() * radius, &mut |t| {
                        add(t, self)
                    });
                }
            }
            Geometry::Disk(_) => unreachable!("meshed"),
            Geometry::Cylinder { .. } | Geometry::SdfGrid(_) | Geometry::Curves(_) => {
                unreachable!("count_shape refuses cylinders, SDF grids and curves")
            }
        }
        degenerate
    }

    /// Adds the triangle `t` as a patch of `surface` (and its back, for a two-sided one) with
    /// welded corners; false, adding nothing, when its area is zero or not finite.
    fn add_triangle(&mut self, welder: &mut Welder, t: [Vec3; 3], surface: &Surface) -> bool {
        let cross = (t[1] - t[0]).cross(t[2] - t[0]);
        let area = 0.5 * cross.length();
        if !(area > 0.0 && area.is_finite()) {
            return false;
        }
        let normal = cross.normalize();
        let v = t.map(|p| welder.add(&mut self.vertices, p));
        let centroid = (t[0] + t[1] + t[2]) / 3.0;
        let tri = self.triangles.len() as u32;
        let front = self.patches.len() as u32;
        self.patches.push(Patch {
            corners: v,
            area,
            normal,
            centroid,
            reflectance: surface.reflectance,
            emission: surface.emission,
            shape: surface.shape,
            triangle: tri,
        });
        let back = if surface.two_sided {
            self.patches.push(Patch {
                corners: v,
                area,
                normal: -normal,
                centroid,
                reflectance: surface.reflectance,
                emission: [0.0; 3],
                shape: surface.shape,
                triangle: tri,
            });
            front + 1
        } else {
            NO_PATCH
        };
        self.triangles.push(Triangle {
            v,
            normal,
            front,
            back,
        });
        true
    }

    /// Checks a shape's geometry and returns how many triangles it will make.
    fn count_shape(s: &ShapeDesc, h: f32) -> Result<u64, RadiosityError> {
        match &*meshed(&s.geometry) {
            Geometry::Mesh(m) => {
                let n = m.positions.len();
                let mut count = 0u64;
                for (k, idx) in m.indices.iter().enumerate() {
                    if idx.iter().any(|&i| i as usize >= n) {
                        return Err(RadiosityError::scene(
                            &s.loc,
                            format!("triangle {k} has a vertex index out of range ({n} vertices)"),
                        ));
                    }
                    let p = idx.map(|i| m.positions[i as usize]);
                    if !p.iter().all(|v| v.is_finite()) {
                        return Err(RadiosityError::scene(
                            &s.loc,
                            format!("triangle {k} has a non-finite vertex"),
                        ));
                    }
                    let k = subdivisions_f(&p, h);
                    count += (k * k).min(u64::MAX as f64 / 4.0) as u64;
                }
                Ok(count)
            }
            &Geometry::Sphere { center, radius, .. } => {
                if !(center.is_finite() && radius.is_finite() && radius > 0.0) {
                    return Err(RadiosityError::scene(
                        &s.loc,
                        format!("sphere radius must be positive and finite, got {radius}"),
                    ));
                }
                let k = sphere_subdivisions_f(radius, h);
                Ok((20.0 * k * k).min(u64::MAX as f64 / 4.0) as u64)
            }
            Geometry::Disk(_) => unreachable!("meshed"),
            Geometry::Cylinder { .. } => Err(RadiosityError::scene(
                &s.loc,
                "the radiosity solver meshes triangles and spheres; a cylinder is not supported \
                 by it yet (the path tracer renders it)"
                    .to_string(),
            )),
            Geometry::SdfGrid(_) => Err(RadiosityError::scene(
                &s.loc,
                "the radiosity solver meshes triangles and spheres; an sdfgrid is not supported \
                 by it (the path tracer renders it)"
                    .to_string(),
            )),
            Geometry::Curves(_) => Err(RadiosityError::scene(
                &s.loc,
                "the radiosity solver meshes triangles and spheres; curves are not supported \
                 by it (fibres scatter, they do not diffuse; the path tracer renders them)"
                    .to_string(),
            )),
        }
    }

    /// Total patch area, scene units squared.
    pub fn total_area(&self) -> f64 {
        self.patches.iter().map(|p| p.area as f64).sum()
    }

    /// The patch seen when a ray with direction `dir` hits triangle `tri`: the front patch if the
    /// ray arrives from the front, else the back patch (or [`NO_PATCH`]).
    #[inline]
    pub fn patch_hit(&self, tri: usize, dir: Vec3) -> u32 {
        let t = &self.triangles[tri];
        if dir.dot(t.normal) < 0.0 {
            t.front
        } else {
            t.back
        }
    }

    /// Memory held by the patch data, bytes (vertices, triangles, patches).
    pub fn memory_bytes(&self) -> usize {
        self.vertices.capacity() * std::mem::size_of::<Vec3>()
            + self.triangles.capacity() * std::mem::size_of::<Triangle>()
            + self.patches.capacity() * std::mem::size_of::<Patch>()
    }
}

fn subdivisions_f(p: &[Vec3; 3], h: f32) -> f64 {
    let longest = (p[1] - p[0])
        .length()
        .max((p[2] - p[1]).length())
        .max((p[0] - p[2]).length());
    ((longest / h) as f64).ceil().max(1.0)
}

fn subdivisions(p: &[Vec3; 3], h: f32) -> u32 {
    subdivisions_f(p, h) as u32
}

/// Subdivisions of each icosahedron face so that chords stay below `h`: projecting the flat grid
/// onto the sphere stretches it by at most 1 / inradius = 1.258 (at the face centres).
fn sphere_subdivisions_f(radius: f32, h: f32) -> f64 {
    ((ICO_EDGE * radius / (ICO_INRADIUS * h)) as f64)
        .ceil()
        .max(1.0)
}

fn sphere_subdivisions(radius: f32, h: f32) -> u32 {
    sphere_subdivisions_f(radius, h) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_keeps_area_and_winding() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        for k in 1..6 {
            let mut area = 0.0;
            let mut n = 0;
            split(p, k, &|q| q, &mut |t| {
                let c = (t[1] - t[0]).cross(t[2] - t[0]);
                assert!(c.z > 0.0, "winding kept");
                area += 0.5 * c.length();
                n += 1;
            });
            assert_eq!(n, k * k);
            assert!((area - 0.5).abs() < 1e-6);
        }
    }

    #[test]
    fn icosahedron_faces_point_outwards() {
        let (v, f) = icosahedron();
        for t in f {
            let c = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);
            assert!(c.dot(v[t[0]] + v[t[1]] + v[t[2]]) > 0.0);
            assert!(((v[t[1]] - v[t[0]]).length() - ICO_EDGE).abs() < 1e-5);
        }
    }
}
