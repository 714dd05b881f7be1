//! Shape geometry: the built-in shapes (`rectangle`, `cube`, `disk`, `sphere`) and OBJ meshes,
//! turned into world-space [`Geometry`].
//!
//! | shape       | object space                                   | parameters                       |
//! |-------------|------------------------------------------------|----------------------------------|
//! | `rectangle` | [-1, 1]^2 in z = 0, normal +z, uv (0,0)..(1,1) | `to_world`, `flip_normals`       |
//! | `cube`      | [-1, 1]^3, outward normals, uv per face        | `to_world`, `flip_normals`       |
//! | `disk`      | unit disk in z = 0, normal +z (analytic)       | `to_world`, `flip_normals`       |
//! | `sphere`    | `center` (point, 0), `radius` (float, 1)       | `to_world` (similarity only)     |
//! | `obj`       | the file's coordinates                         | `filename`, `face_normals` (false), `flip_tex_coords` (true) |
//!
//! Meshes carry no vertex normals unless the shape is smooth (OBJ), so the renderer shades
//! them flat with the geometric normal `(p1 - p0) x (p2 - p0)`.

use crate::ir::{Disk, Geometry, MeshAttribute, TriangleMesh};
use crate::transform::is_affine;
use glam::{Mat3, Mat4, Vec2, Vec3};

/// Segments of the disk's triangle fan.
pub(crate) const DISK_SEGMENTS: u32 = 1024;

/// A mesh in object space, before `to_world` and `flip_normals`.
#[derive(Debug, Default)]
pub(crate) struct LocalMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
    pub attributes: Vec<MeshAttribute>,
}

/// Mitsuba's `rectangle`: [-1, 1]^2 in the z = 0 plane, facing +z.
pub(crate) fn rectangle() -> LocalMesh {
    LocalMesh {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        normals: None,
        uvs: Some(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ]),
        indices: vec![[0, 1, 2], [0, 2, 3]],
        attributes: Vec::new(),
    }
}

/// Mitsuba's `cube`: [-1, 1]^3 with outward faces, each with its own four vertices and the
/// full (0,0)..(1,1) uv square laid out as Mitsuba 3's cube lays it (its vertex buffers: faces
/// -y, +y, +x, +z, -x, -z; corners with uvs (0,1), (1,1), (1,0), (0,0); triangles (0,1,2) and
/// (3,0,2)). The layout decides where a texture lands on each face and which way dp/du points,
/// so anisotropic materials and normal maps on cubes match Mitsuba too.
pub(crate) fn cube() -> LocalMesh {
    /// Each face's corners in the order of `CORNER_UVS`.
    const FACES: [[[f32; 3]; 4]; 6] = [
        [
            [1., -1., -1.],
            [1., -1., 1.],
            [-1., -1., 1.],
            [-1., -1., -1.],
        ],
        [[1., 1., -1.], [-1., 1., -1.], [-1., 1., 1.], [1., 1., 1.]],
        [[1., -1., -1.], [1., 1., -1.], [1., 1., 1.], [1., -1., 1.]],
        [[1., -1., 1.], [1., 1., 1.], [-1., 1., 1.], [-1., -1., 1.]],
        [
            [-1., -1., 1.],
            [-1., 1., 1.],
            [-1., 1., -1.],
            [-1., -1., -1.],
        ],
        [
            [1., 1., -1.],
            [1., -1., -1.],
            [-1., -1., -1.],
            [-1., 1., -1.],
        ],
    ];
    const CORNER_UVS: [[f32; 2]; 4] = [[0., 1.], [1., 1.], [1., 0.], [0., 0.]];
    let mut mesh = LocalMesh {
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    for face in FACES {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(face.map(Vec3::from_array));
        if let Some(uvs) = mesh.uvs.as_mut() {
            uvs.extend(CORNER_UVS.map(Vec2::from_array));
        }
        mesh.indices.push([base, base + 1, base + 2]);
        mesh.indices.push([base + 3, base, base + 2]);
    }
    mesh
}

/// Mitsuba's `disk` through `to_world` = `m` (any affine map: a non-uniform scale makes an
/// ellipse), its front side turned by `flip`. The normal is Mitsuba's, +z through the inverse
/// transpose: the cofactor identity M^-T e_z = (M e_x x M e_y) / det M gives its direction
/// without inverting.
pub(crate) fn disk_shape(m: &Mat4, flip: bool) -> std::result::Result<Geometry, String> {
    check_affine(m)?;
    let center = m.transform_point3(Vec3::ZERO);
    let axes = [m.transform_vector3(Vec3::X), m.transform_vector3(Vec3::Y)];
    let det = Mat3::from_mat4(*m).determinant();
    let normal = axes[0].cross(axes[1]).normalize_or_zero() * det.signum();
    if !(center.is_finite() && normal != Vec3::ZERO && normal.is_finite() && det != 0.0) {
        return Err("a disk's to_world must be finite and keep the disk a surface (it maps the disk to a point or a line)".into());
    }
    Ok(Geometry::Disk(Disk {
        center,
        axes,
        normal: if flip { -normal } else { normal },
    }))
}

impl Disk {
    /// Surface area, scene units squared: pi |a x b| for the axes a, b.
    pub fn area(&self) -> f32 {
        std::f32::consts::PI * self.axes[0].cross(self.axes[1]).length()
    }

    /// The world-space point at object-space coordinates `local` (x, y), x^2 + y^2 <= 1.
    #[inline]
    pub fn point(&self, local: Vec2) -> Vec3 {
        self.center + self.axes[0] * local.x + self.axes[1] * local.y
    }

    /// Axis-aligned bounds, world space: along each world axis the ellipse reaches
    /// sqrt(a_i^2 + b_i^2) from its centre.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let [a, b] = self.axes;
        let reach = (a * a + b * b).map(f32::sqrt);
        (self.center - reach, self.center + reach)
    }

    /// The disk as a fan of [`DISK_SEGMENTS`] triangles with the same texture coordinates and
    /// front side, for the consumers that need triangles (the radiosity solver's patches).
    pub fn to_mesh(&self) -> TriangleMesh {
        let [a, b] = self.axes;
        let m = Mat4::from_cols(
            a.extend(0.0),
            b.extend(0.0),
            self.normal.extend(0.0),
            self.center.extend(1.0),
        );
        // The fan winds towards a x b; the front side may be the other one.
        let flip = a.cross(b).dot(self.normal) < 0.0;
        to_world(disk(), &m, flip).unwrap_or_default()
    }
}

/// Mitsuba's `disk` (unit radius, z = 0, facing +z) as a fan of [`DISK_SEGMENTS`] triangles.
///
/// The rim vertices sit on a circle slightly larger than the unit circle, chosen so that the
/// polygon's area is exactly pi: an inscribed polygon would lose area (6e-4 % at 1024 segments),
/// and area is what sets an emitter's power and the form factors between surfaces.
///
/// Texture coordinates are Mitsuba's polar ones, u = r and v = phi / 2 pi (phi from +x towards
/// +y, in [0, 1)): each triangle has its own three vertices, the centre (u = 0, v at the
/// wedge's middle angle) and two rim vertices (u = 1, v = i / n and (i + 1) / n, so the last
/// triangle ends at v = 1 and the seam is not smeared across the disk). Interpolated over a
/// wedge of 2 pi / 1024, u is r to 1e-5 and v the polar angle to within the wedge's half-width
/// times the centre's barycentric weight (at most 1/2048 of a turn, near the centre, where the
/// texture's angular detail shrinks to a point; radial rings would not remove it, since any
/// triangle spanning two radii interpolates the angle with an error of the same order). The
/// tangent dp/du that orients anisotropic BSDFs is then radial, as Mitsuba's.
pub(crate) fn disk() -> LocalMesh {
    let n = DISK_SEGMENTS;
    let step = std::f32::consts::TAU / n as f32;
    // Area of a regular n-gon with circumradius R: n/2 R^2 sin(2 pi / n) = pi.
    let rim = (std::f32::consts::TAU / (n as f32 * step.sin())).sqrt();
    let at = |i: u32| {
        let phi = step * (i % n) as f32;
        Vec3::new(rim * phi.cos(), rim * phi.sin(), 0.0)
    };
    let mut positions = Vec::with_capacity(3 * n as usize);
    let mut uvs = Vec::with_capacity(3 * n as usize);
    for i in 0..n {
        positions.extend([Vec3::ZERO, at(i), at(i + 1)]);
        uvs.extend([
            Vec2::new(0.0, (i as f32 + 0.5) / n as f32),
            Vec2::new(1.0, i as f32 / n as f32),
            Vec2::new(1.0, (i + 1) as f32 / n as f32),
        ]);
    }
    let indices = (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    LocalMesh {
        positions,
        normals: None,
        uvs: Some(uvs),
        indices,
        attributes: Vec::new(),
    }
}

/// Applies `to_world` and `flip_normals` and checks the result is finite.
///
/// Normals are transformed by the inverse transpose (so they stay perpendicular under
/// non-uniform scale) and renormalised. Flipping reverses each triangle's winding and negates
/// the vertex normals, which turns the geometric and the shading normal together.
pub(crate) fn to_world(
    local: LocalMesh,
    m: &Mat4,
    flip: bool,
) -> std::result::Result<TriangleMesh, String> {
    check_affine(m)?;
    let positions: Vec<Vec3> = local
        .positions
        .iter()
        .map(|&p| m.transform_point3(p))
        .collect();
    if positions.iter().any(|p| !p.is_finite()) {
        return Err("mesh has NaN or infinite vertex positions".into());
    }
    let normals = match local.normals {
        Some(ns) => Some(transform_normals(&ns, m, flip)?),
        None => None,
    };
    let mut indices = local.indices;
    if flip {
        for t in &mut indices {
            t.swap(1, 2);
        }
    }
    Ok(TriangleMesh {
        positions,
        normals,
        uvs: local.uvs,
        tangents: None,
        indices,
        attributes: local.attributes,
    })
}

fn transform_normals(ns: &[Vec3], m: &Mat4, flip: bool) -> std::result::Result<Vec<Vec3>, String> {
    let linear = Mat3::from_mat4(*m);
    if linear.determinant() == 0.0 {
        return Err("to_world is singular, so vertex normals cannot be transformed".into());
    }
    let normal_matrix = linear.inverse().transpose();
    let sign = if flip { -1.0 } else { 1.0 };
    ns.iter()
        .map(|&n| {
            (normal_matrix * n)
                .try_normalize()
                .map(|n| n * sign)
                .ok_or_else(|| "mesh has a zero-length, NaN or infinite vertex normal".to_string())
        })
        .collect()
}

fn check_affine(m: &Mat4) -> std::result::Result<(), String> {
    if is_affine(m) {
        Ok(())
    } else {
        Err("to_world must be affine (last matrix row 0, 0, 0, 1)".into())
    }
}

/// A world-space sphere: the centre goes through `to_world`; the radius is multiplied by its
/// scale, which must be uniform (rotation, mirroring and translation are fine).
pub(crate) fn sphere(
    center: Vec3,
    radius: f32,
    m: &Mat4,
    flip: bool,
) -> std::result::Result<Geometry, String> {
    check_affine(m)?;
    let scale = uniform_scale(m).ok_or(
        "a sphere's to_world may only rotate, translate and scale uniformly \
         (non-uniform scale or shear would make an ellipsoid)",
    )?;
    let center = m.transform_point3(center);
    let radius = radius * scale;
    if !(center.is_finite() && radius.is_finite() && radius > 0.0) {
        return Err(format!(
            "sphere has an invalid centre {center} or radius {radius}"
        ));
    }
    // The object-to-world rotation, for texture coordinates and dp/du. A mirroring to_world
    // turns the sphere inside out, as in Mitsuba.
    let frame = Mat3::from_mat4(*m) * (1.0 / scale);
    let mirrored = frame.determinant() < 0.0;
    Ok(Geometry::Sphere {
        center,
        radius,
        flip_normals: flip != mirrored,
        frame,
    })
}

/// A world-space cylinder (Mitsuba's `cylinder`): the object-space cylinder of `radius` around
/// the segment `p0`-`p1` goes through `to_world` = `m`. Mitsuba composes
/// `m * translate(p0) * to_frame(Frame(axis)) * scale(radius, radius, length)` (its frame is
/// Duff et al. 2017's, as [`pt_math::Frame::from_normal`]) and reads the radius and length off
/// the result; the result must keep the cross-section a circle (no shear, the same scale across
/// the axis: Mitsuba only warns there and renders another shape) and must not mirror.
pub(crate) fn cylinder(
    p0: Vec3,
    p1: Vec3,
    radius: f32,
    m: &Mat4,
    flip: bool,
) -> std::result::Result<Geometry, String> {
    check_affine(m)?;
    let axis = p1 - p0;
    let length = axis.length();
    if !(length > 0.0 && length.is_finite()) {
        return Err(format!(
            "cylinder p0 {p0} and p1 {p1} must be distinct and finite"
        ));
    }
    let f = pt_math::Frame::from_normal(axis / length);
    let linear = Mat3::from_mat4(*m);
    let cols = [
        linear * (f.s * radius),
        linear * (f.t * radius),
        linear * (f.n * length),
    ];
    let lengths = cols.map(Vec3::length);
    let tol = 1e-4;
    let circular = (lengths[0] - lengths[1]).abs() <= tol * lengths[0]
        && cols[0].dot(cols[1]).abs() <= tol * lengths[0] * lengths[1]
        && cols[0].dot(cols[2]).abs() <= tol * lengths[0] * lengths[2]
        && cols[1].dot(cols[2]).abs() <= tol * lengths[1] * lengths[2];
    if !circular {
        return Err(
            "a cylinder's to_world may only rotate, translate and scale along its axis \
             and uniformly across it (shear or unequal scale across the axis would make an \
             elliptic cylinder, which Mitsuba renders as a circular one with a warning)"
                .into(),
        );
    }
    let frame = Mat3::from_cols(
        cols[0] / lengths[0],
        cols[1] / lengths[1],
        cols[2] / lengths[2],
    );
    if frame.determinant() < 0.0 {
        return Err("a cylinder's to_world must not mirror (negative determinant)".into());
    }
    let p0 = m.transform_point3(p0);
    let (radius, length) = (lengths[0], lengths[2]);
    if !(p0.is_finite() && radius.is_finite() && radius > 0.0 && length.is_finite()) {
        return Err(format!(
            "cylinder has an invalid start {p0}, radius {radius} or length {length}"
        ));
    }
    Ok(Geometry::Cylinder {
        p0,
        frame,
        radius,
        length,
        flip_normals: flip,
    })
}

/// The bounding box (min, max corners) of the open cylinder around the segment `p0` to
/// `p0 + length axis` (`axis` unit length): the boxes of its end circles, as a circle of radius
/// r around the unit axis a reaches r sqrt(1 - a_i^2) along world axis i.
pub fn cylinder_bounds(p0: Vec3, axis: Vec3, radius: f32, length: f32) -> (Vec3, Vec3) {
    let p1 = p0 + axis * length;
    let reach = (Vec3::ONE - axis * axis).max(Vec3::ZERO).sqrt() * radius;
    (p0.min(p1) - reach, p0.max(p1) + reach)
}

/// The scale factor s if the linear part of `m` is s times an orthogonal matrix.
fn uniform_scale(m: &Mat4) -> Option<f32> {
    let l = Mat3::from_mat4(*m);
    let cols = [l.x_axis, l.y_axis, l.z_axis];
    let s = cols[0].length();
    let tol = 1e-4 * s;
    let lengths_ok = cols.iter().all(|c| (c.length() - s).abs() <= tol);
    let orthogonal = cols[0].dot(cols[1]).abs() <= tol * s
        && cols[1].dot(cols[2]).abs() <= tol * s
        && cols[0].dot(cols[2]).abs() <= tol * s;
    (s > 0.0 && lengths_ok && orthogonal).then_some(s)
}

/// Smooth vertex normals: each triangle adds its unit normal weighted by its angle at the
/// vertex, which does not depend on how the surface around a vertex is triangulated.
/// A vertex touched only by degenerate triangles gets an arbitrary unit normal (+z); it is
/// never shaded through a triangle with non-zero area.
pub(crate) fn vertex_normals(positions: &[Vec3], indices: &[[u32; 3]]) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for tri in indices {
        let [Some(&p0), Some(&p1), Some(&p2)] = tri.map(|i| positions.get(i as usize)) else {
            continue;
        };
        let Some(n) = (p1 - p0).cross(p2 - p0).try_normalize() else {
            continue;
        };
        let corners = [(p0, p1, p2), (p1, p2, p0), (p2, p0, p1)];
        for (&index, (p, a, b)) in tri.iter().zip(corners) {
            let angle = (a - p).angle_between(b - p);
            if let (Some(sum), true) = (sums.get_mut(index as usize), angle.is_finite()) {
                *sum += n * angle;
            }
        }
    }
    sums.into_iter()
        .map(|s| s.try_normalize().unwrap_or(Vec3::Z))
        .collect()
}

/// Sum of triangle areas (used by tests and to sanity-check tessellation).
#[cfg(test)]
pub(crate) fn area(mesh: &TriangleMesh) -> f32 {
    mesh.indices
        .iter()
        .map(|t| {
            let p = t.map(|i| mesh.positions[i as usize]);
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face_normal(mesh: &TriangleMesh, t: usize) -> Vec3 {
        let p = mesh.indices[t].map(|i| mesh.positions[i as usize]);
        (p[1] - p[0]).cross(p[2] - p[0]).normalize()
    }

    #[test]
    fn rectangle_faces_plus_z() {
        let m = to_world(rectangle(), &Mat4::IDENTITY, false).unwrap();
        assert_eq!(m.indices.len(), 2);
        for t in 0..2 {
            assert!((face_normal(&m, t) - Vec3::Z).length() < 1e-6);
        }
        assert!((area(&m) - 4.0).abs() < 1e-6);
        let flipped = to_world(rectangle(), &Mat4::IDENTITY, true).unwrap();
        assert!((face_normal(&flipped, 0) + Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn cube_normals_point_outwards() {
        let m = to_world(cube(), &Mat4::IDENTITY, false).unwrap();
        assert_eq!(m.indices.len(), 12);
        assert!(m.normals.is_none());
        for (t, tri) in m.indices.iter().enumerate() {
            let centroid = tri.iter().map(|&i| m.positions[i as usize]).sum::<Vec3>() / 3.0;
            let n = face_normal(&m, t);
            // The centroid lies on the face, so it points the same way as the outward normal.
            assert!(
                n.dot(centroid) > 0.9,
                "triangle {t}: n {n} centroid {centroid}"
            );
        }
        assert!((area(&m) - 24.0).abs() < 1e-4);
    }

    /// Mitsuba 3.9.1's cube uvs as functions of the position on each face (read from its
    /// vertex buffers): a texture on a pt cube lands where it lands in Mitsuba.
    #[test]
    fn cube_uvs_follow_mitsuba() {
        let m = cube();
        let uvs = m.uvs.as_ref().unwrap();
        let half = |t: f32| (t + 1.0) * 0.5;
        // Per face (its outward normal tells which), each corner's uv follows the face's rule.
        let mesh = to_world(cube(), &Mat4::IDENTITY, false).unwrap();
        for (f, quad) in m.positions.chunks(4).enumerate() {
            let n = face_normal(&mesh, 2 * f);
            let rule = |p: Vec3| {
                let (x, y, z) = (p.x, p.y, p.z);
                match (n.x.round() as i32, n.y.round() as i32, n.z.round() as i32) {
                    (-1, 0, 0) => Vec2::new(half(y), half(z)),
                    (1, 0, 0) => Vec2::new(half(y), half(-z)),
                    (0, -1, 0) => Vec2::new(half(z), half(x)),
                    (0, 1, 0) => Vec2::new(half(-x), half(-z)),
                    (0, 0, -1) => Vec2::new(half(-y), half(x)),
                    (0, 0, 1) => Vec2::new(half(y), half(x)),
                    other => panic!("face {f}: normal {other:?} is not an axis"),
                }
            };
            for (c, p) in quad.iter().enumerate() {
                assert_eq!(uvs[4 * f + c], rule(*p), "face {f} corner {p}");
            }
        }
    }

    /// The fan's interpolated uvs are Mitsuba's polar ones, u = r and v = phi / 2 pi: u to
    /// 2e-4 (the rim is a polygon), v to within the wedge's half-width times the centre's
    /// weight (doc of `disk`), over a grid of points in every wedge.
    #[test]
    fn disk_uvs_are_polar() {
        let d = disk();
        let uvs = d.uvs.as_ref().unwrap();
        let half_wedge = 0.5 / DISK_SEGMENTS as f32;
        for tri in &d.indices {
            for (b1, b2) in [
                (0.1, 0.1),
                (0.45, 0.45),
                (0.8, 0.15),
                (0.05, 0.9),
                (0.3, 0.6),
            ] {
                let b0 = 1.0 - b1 - b2;
                let w = [b0, b1, b2];
                let p: Vec3 = (0..3).map(|k| d.positions[tri[k] as usize] * w[k]).sum();
                let uv: Vec2 = (0..3).map(|k| uvs[tri[k] as usize] * w[k]).sum();
                let r = p.truncate().length();
                let mut v = p.y.atan2(p.x) / std::f32::consts::TAU;
                if v < 0.0 {
                    v += 1.0;
                }
                // The last wedge ends at v = 1 rather than 0.
                if uv.y > 0.5 && v < 0.25 {
                    v += 1.0;
                }
                assert!((uv.x - r).abs() < 2e-4, "u {} vs r {r}", uv.x);
                assert!(
                    (uv.y - v).abs() <= b0 * half_wedge + 1e-5,
                    "v {} vs {v}",
                    uv.y
                );
            }
        }
    }

    #[test]
    fn disk_area_is_exactly_pi() {
        let m = to_world(disk(), &Mat4::from_scale(Vec3::splat(2.0)), false).unwrap();
        assert_eq!(m.indices.len(), DISK_SEGMENTS as usize);
        let expected = std::f32::consts::PI * 4.0;
        assert!(
            (area(&m) - expected).abs() < 1e-5 * expected,
            "{}",
            area(&m)
        );
        assert!((face_normal(&m, 0) - Vec3::Z).length() < 1e-5);
    }

    /// The disk's front normal is Mitsuba's: +z through the inverse transpose, so a mirror in z
    /// turns it (a x b does not turn), a mirror in x turns a x b but not the normal, and
    /// `flip_normals` negates it; a non-uniform scale makes an ellipse of area pi s_x s_y whose
    /// bounds reach s_x and s_y; a singular to_world is an error.
    #[test]
    fn disk_normal_is_mitsubas() {
        let normal = |m: Mat4, flip: bool| match disk_shape(&m, flip).unwrap() {
            Geometry::Disk(d) => d.normal,
            _ => panic!("not a disk"),
        };
        let s = |x: f32, y: f32, z: f32| Mat4::from_scale(Vec3::new(x, y, z));
        assert_eq!(normal(Mat4::IDENTITY, false), Vec3::Z);
        assert_eq!(normal(Mat4::IDENTITY, true), -Vec3::Z);
        assert_eq!(normal(s(1.0, 1.0, -1.0), false), -Vec3::Z);
        assert_eq!(normal(s(-1.0, 1.0, 1.0), false), Vec3::Z);
        let r = Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2);
        assert!((normal(r, false) - Vec3::Y).length() < 1e-6);
        let Geometry::Disk(d) = disk_shape(&s(3.0, 0.5, 1.0), false).unwrap() else {
            panic!("not a disk")
        };
        assert!((d.area() - 1.5 * std::f32::consts::PI).abs() < 1e-5);
        assert_eq!(
            d.bounds(),
            (Vec3::new(-3.0, -0.5, 0.0), Vec3::new(3.0, 0.5, 0.0))
        );
        assert!(disk_shape(&s(1.0, 0.0, 1.0), false).is_err());
    }

    #[test]
    fn sphere_scale_must_be_uniform() {
        let m = Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            glam::Quat::from_rotation_y(0.3),
            Vec3::new(1.0, 2.0, 3.0),
        );
        match sphere(Vec3::X, 0.5, &m, false).unwrap() {
            Geometry::Sphere { center, radius, .. } => {
                assert!((radius - 1.0).abs() < 1e-6);
                assert!((center - m.transform_point3(Vec3::X)).length() < 1e-6);
            }
            _ => panic!("not a sphere"),
        }
        assert!(sphere(
            Vec3::ZERO,
            1.0,
            &Mat4::from_scale(Vec3::new(1.0, 2.0, 1.0)),
            false
        )
        .is_err());
        assert!(sphere(
            Vec3::ZERO,
            1.0,
            &Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)),
            false
        )
        .is_ok());
    }

    #[test]
    fn normals_use_inverse_transpose() {
        let mut local = rectangle();
        local.normals = Some(vec![Vec3::new(1.0, 1.0, 0.0).normalize(); 4]);
        let m = to_world(local, &Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0)), false).unwrap();
        let n = m.normals.unwrap()[0];
        assert!((n - Vec3::new(0.5, 1.0, 0.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn angle_weighted_normals_of_a_flat_fan_are_the_plane_normal() {
        let d = disk();
        let n = vertex_normals(&d.positions, &d.indices);
        assert!(n.iter().all(|n| (*n - Vec3::Z).length() < 1e-5));
    }
}
