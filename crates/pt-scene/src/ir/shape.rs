//! Shapes in world space: triangle meshes (with their vertex and face attributes) and
//! analytic spheres, disks, cylinders, SDF grids and curves, with their material, emitter and interior medium.

use super::{AreaEmitterDesc, SourceLoc, SpectrumDesc};
use glam::{Mat3, Mat4, Vec2, Vec3};

/// A triangle mesh in world space.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    /// Vertex positions, world space.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (unit length, world space), if the mesh has them and
    /// `face_normals` is off. Flipped already when `flip_normals` is set.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates.
    pub uvs: Option<Vec<Vec2>>,
    /// Per-vertex tangents for normal maps (glTF `TANGENT`, or generated from the uvs): xyz the
    /// direction of increasing u, world space; w = +1 or -1, the handedness: the bitangent is
    /// `w (n x t)` (glTF's convention).
    pub tangents: Option<Vec<glam::Vec4>>,
    /// Triangles as vertex index triples, counter-clockwise seen from the front side
    /// (the side the geometric normal `(p1-p0) x (p2-p0)` points to). `flip_normals` has already
    /// reversed the winding where asked.
    pub indices: Vec<[u32; 3]>,
    /// Named per-vertex or per-face values (Mitsuba's mesh attributes, read by the
    /// `mesh_attribute` texture): `vertex_color` from a PLY file's colours, `COLOR_0` of a
    /// glTF primitive, ...
    pub attributes: Vec<MeshAttribute>,
}

/// Whether a mesh attribute has a value per vertex or per triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AttributeKind {
    /// One value per vertex, interpolated barycentrically (name prefix `vertex_`).
    Vertex,
    /// One value per triangle (name prefix `face_`).
    Face,
}

/// A named mesh attribute: `dims` (1 or 3) numbers per vertex or per triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    /// The full name, with its `vertex_` or `face_` prefix (as `mesh_attribute` names it).
    pub name: String,
    /// Per vertex or per triangle.
    pub kind: AttributeKind,
    /// Numbers per element: 1 (a scalar) or 3 (a colour or vector).
    pub dims: u32,
    /// `dims` numbers per vertex (or triangle), in order; colours are linear.
    pub values: Vec<f32>,
}

impl MeshAttribute {
    /// The kind an attribute's name implies (`vertex_...` or `face_...`), if either.
    pub fn kind_of(name: &str) -> Option<AttributeKind> {
        if name.starts_with("vertex_") {
            Some(AttributeKind::Vertex)
        } else if name.starts_with("face_") {
            Some(AttributeKind::Face)
        } else {
            None
        }
    }
}

/// Geometry of a shape, in world space.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// Triangles (obj, ply, serialized, rectangle and cube are turned into this).
    Mesh(TriangleMesh),
    /// Mitsuba's `disk`, intersected analytically (see [`Disk`]).
    Disk(Disk),
    /// An analytic sphere. `flip_normals` makes its normal point inwards.
    Sphere {
        /// Centre, world space.
        center: Vec3,
        /// Radius, scene units.
        radius: f32,
        /// Whether the normal points inwards.
        flip_normals: bool,
        /// The rotation (orthonormal columns) from the sphere's object space to world space:
        /// texture coordinates and the tangent dp/du follow the object-space z axis, as in
        /// Mitsuba (u = azimuth about z / 2 pi, v = polar angle from +z / pi).
        frame: Mat3,
    },
    /// An analytic open cylinder (no end caps), Mitsuba's `cylinder`: the points
    /// `p0 + frame * (radius cos phi, radius sin phi, z)` for z in [0, `length`]. Its normal
    /// points away from the axis unless `flip_normals`.
    Cylinder {
        /// Centre of the first end circle, world space.
        p0: Vec3,
        /// The rotation (orthonormal columns) from the cylinder's object space to world
        /// space: column 2 is the unit axis from `p0` to the other end; the texture coordinate
        /// u is the azimuth from column 0 towards column 1 over 2 pi, v is z / `length`, as in
        /// Mitsuba.
        frame: Mat3,
        /// Radius, scene units.
        radius: f32,
        /// Length along the axis, scene units.
        length: f32,
        /// Whether the normal points towards the axis.
        flip_normals: bool,
    },
    /// Mitsuba's `sdfgrid` (shared: the shape's primitives are its occupied voxels).
    SdfGrid(std::sync::Arc<SdfGrid>),
    /// Mitsuba's `linearcurve` and `bsplinecurve` (shared: the shape's primitives are its
    /// segments).
    Curves(std::sync::Arc<Curves>),
}

/// Mitsuba's `disk` in world space: the points `center + x axes[0] + y axes[1]` with
/// x^2 + y^2 <= 1, the image of the unit disk in object space's z = 0 plane under `to_world`
/// (an ellipse under non-uniform scale or shear). Texture coordinates are Mitsuba's polar ones,
/// u = r = sqrt(x^2 + y^2) and v = phi / 2 pi, phi = atan2(y, x) in [0, 2 pi).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Centre, world space (the image of the object-space origin).
    pub center: Vec3,
    /// The images of the object-space x and y unit vectors under `to_world` (scene units;
    /// not necessarily orthogonal nor of equal length).
    pub axes: [Vec3; 2],
    /// Unit normal of the front side, world space: Mitsuba's, the object-space +z normal
    /// through `to_world`'s inverse transpose (so a mirroring `to_world` turns it), negated by
    /// `flip_normals`.
    pub normal: Vec3,
}

/// How a curve's control points make the curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveBasis {
    /// `linearcurve`: straight segments between consecutive control points, joined by spheres
    /// and ended by spheres (round cones).
    Linear,
    /// `bsplinecurve`: uniform cubic B-spline segments over each four consecutive control
    /// points, with open ends.
    BSpline,
}

impl CurveBasis {
    /// Control points per segment (2 or 4); a curve needs at least this many.
    pub fn points_per_segment(self) -> usize {
        match self {
            CurveBasis::Linear => 2,
            CurveBasis::BSpline => 4,
        }
    }
}

/// Curves, world space: tubes around polylines or B-splines, with a radius per control point.
#[derive(Clone, Debug)]
pub struct Curves {
    /// Linear or B-spline.
    pub basis: CurveBasis,
    /// Control points: xyz the position (world space, `to_world` applied), w the radius (scene
    /// units; `to_world` does not scale it, as in Mitsuba).
    pub points: Vec<glam::Vec4>,
    /// For each segment, the index of its first control point (the segment uses that point
    /// and the next one or three).
    pub segments: Vec<u32>,
}

impl Curves {
    /// The control points of segment `i`: two for linear curves, four for B-splines.
    pub fn segment(&self, i: usize) -> &[glam::Vec4] {
        let first = self.segments[i] as usize;
        &self.points[first..first + self.basis.points_per_segment()]
    }

    /// A box (min, max corners, world space) around every tube: the control points grown by
    /// their radii (a B-spline lies in the hull of its control points, its radius is a convex
    /// combination of theirs).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.points.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p.truncate() - p.w), hi.max(p.truncate() + p.w)),
        )
    }
}

/// Mitsuba's `sdfgrid`: a signed distance function sampled at the vertices of a regular grid
/// over the unit cube of the shape's object space, and interpolated trilinearly in each voxel;
/// the surface is its zero set, the outside where it is positive.
#[derive(Clone, Debug)]
pub struct SdfGrid {
    /// Samples along x, y and z (each at least 2: a voxel spans 1 / (resolution - 1)).
    pub resolution: [u32; 3],
    /// The samples (object-space units), x fastest, then y, then z.
    pub values: Vec<f32>,
    /// Where the object space's origin (the grid's corner sample 0) lies, world space.
    pub origin: Vec3,
    /// The world-space size of the object space's unit cube along x, y and z (positive: the
    /// loader accepts a `to_world` of scales and a translation only).
    pub extent: Vec3,
    /// Shading normals: `true` for Mitsuba's `smooth` (continuous across voxels; Hansson-
    /// Söderlund, Evans and Akenine-Möller 2022), `false` for `analytic` (the gradient of the
    /// voxel's interpolant, which the geometric normal always is).
    pub smooth_normals: bool,
}

impl SdfGrid {
    /// The sample at grid vertex (x, y, z).
    #[inline]
    pub fn at(&self, x: u32, y: u32, z: u32) -> f32 {
        let [nx, ny, _] = self.resolution;
        self.values[((z * ny + y) * nx + x) as usize]
    }

    /// The eight samples at the corners of the voxel whose lowest corner is vertex (x, y, z),
    /// corner `i` at offset (i & 1, (i >> 1) & 1, i >> 2).
    #[inline]
    pub fn corners(&self, [x, y, z]: [u32; 3]) -> [f32; 8] {
        std::array::from_fn(|i| {
            let i = i as u32;
            self.at(x + (i & 1), y + ((i >> 1) & 1), z + (i >> 2))
        })
    }

    /// The voxels the surface passes through, by lowest corner vertex, x fastest: those
    /// whose corners include a value >= 0 and one <= 0 (Mitsuba's occupied voxels).
    pub fn occupied_voxels(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        let [nx, ny, nz] = self.resolution.map(|n| n - 1);
        (0..nz).flat_map(move |z| {
            (0..ny).flat_map(move |y| {
                (0..nx).map(move |x| [x, y, z]).filter(|&v| {
                    let f = self.corners(v);
                    f.iter().any(|&c| c >= 0.0) && f.iter().any(|&c| c <= 0.0)
                })
            })
        })
    }

    /// The world-space box of the voxel whose lowest corner is vertex `v`: its low corner and
    /// its size.
    #[inline]
    pub fn voxel_box(&self, v: [u32; 3]) -> (Vec3, Vec3) {
        let cells = Vec3::from(self.resolution.map(|n| (n - 1) as f32));
        let size = self.extent / cells;
        (self.origin + Vec3::from(v.map(|c| c as f32)) * size, size)
    }
}

/// A shape with its material and optional emitter.
#[derive(Clone, Debug)]
pub struct ShapeDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// The plugin name (`obj`, `rectangle`, `cube`, `sphere`, `disk`), for `pt info`.
    pub plugin: String,
    /// The `id` attribute, if any.
    pub id: Option<String>,
    /// World-space geometry.
    pub geometry: Geometry,
    /// Index into `SceneDesc::bsdfs`. A shape without a BSDF gets Mitsuba's default
    /// (diffuse, reflectance 0.5), which the loader inserts explicitly.
    pub bsdf: usize,
    /// The area emitter, if the shape emits.
    pub emitter: Option<AreaEmitterDesc>,
    /// The medium inside the shape (Mitsuba `<medium name="interior">`), if any: a ray that
    /// crosses the surface inwards (against its geometric normal) travels in it.
    pub interior: Option<MediumDesc>,
    /// The medium outside the shape (Mitsuba `<medium name="exterior">`), if any: a ray that
    /// crosses the surface outwards travels in it. A shape with either is a medium boundary;
    /// crossing a boundary that leaves one side unset enters vacuum (Mitsuba).
    pub exterior: Option<MediumDesc>,
}

/// Mitsuba's `shapegroup`: shapes stored once and placed any number of times by
/// [`InstanceDesc`]s. Its shapes' geometry is in the group's own space (each shape's
/// `to_world` applied, no instance's); they have no emitters (Mitsuba refuses emitters in
/// groups). Their media, if any, bound every instance of them and stay in world space.
#[derive(Clone, Debug)]
pub struct ShapeGroupDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// Its `id`.
    pub id: String,
    /// Its shapes, in file order.
    pub shapes: Vec<ShapeDesc>,
}

/// Mitsuba's `instance`: a [`ShapeGroupDesc`] placed in the world.
#[derive(Clone, Debug)]
pub struct InstanceDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// Index into `SceneDesc::groups`.
    pub group: usize,
    /// From the group's space to world space (any invertible affine transform, as in
    /// Mitsuba: a non-uniform scale turns an instanced sphere into an ellipsoid).
    pub to_world: Mat4,
}

/// A participating medium (Mitsuba `homogeneous` or `heterogeneous`): extinction `sigma_t`,
/// single scattering albedo `albedo` (sigma_s = albedo sigma_t, sigma_a = (1 - albedo)
/// sigma_t), a phase function, and (a pt extension) volume emission.
#[derive(Clone, Debug, PartialEq)]
pub struct MediumDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// Extinction coefficient per scene unit of length, Mitsuba's `sigma_t` already multiplied by
    /// its `scale` (with an extinction grid: `scale` alone, the factor of the grid's values).
    /// Linear RGB, a constant or a tabulated spectrum, each value >= 0.
    pub sigma_t: SpectrumDesc,
    /// Single scattering albedo, each value in [0, 1] (Mitsuba's default 0.75): a spectrum or
    /// (Mitsuba's `<volume name="albedo">`) a grid.
    pub albedo: VolumeDesc,
    /// The phase function (Mitsuba's default: isotropic).
    pub phase: PhaseDesc,
    /// Mitsuba's `sample_emitters` (default true): whether scattering in the medium samples
    /// the lights (next-event estimation); without it only phase sampling finds them.
    pub sample_emitters: bool,
    /// `heterogeneous` with a `gridvolume` extinction: the extinction at a point is `sigma_t`
    /// (which then holds Mitsuba's `scale`) times the grid's value there (one channel, or
    /// three: RGB); the medium ends at the grid's box. `None`: homogeneous.
    pub density: Option<std::sync::Arc<GridDesc>>,
    /// pt's `emission` (not in Mitsuba 3.9.1): radiance emitted per scene unit of path length,
    /// the source term of the transfer equation (W m^-3 sr^-1 for scenes in metres); a spectrum
    /// (an emission: times D65 in spectral mode) or, in a heterogeneous medium, a grid. `None`:
    /// the medium does not glow.
    pub emission: Option<VolumeDesc>,
}

/// A medium parameter that may vary in space: Mitsuba's spectrum or `constvolume` (the same
/// everywhere), or a `gridvolume`.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeDesc {
    /// The same value everywhere.
    Constant(SpectrumDesc),
    /// A grid's value at the point (clamped to the grid's border outside its box, as Mitsuba's
    /// default wrap mode does).
    Grid(std::sync::Arc<GridDesc>),
}

/// A `gridvolume`: one or three (RGB) values per cell, in the grid's unit cube.
#[derive(Clone, Debug, PartialEq)]
pub struct GridDesc {
    /// The values (one channel or three, each finite and >= 0).
    pub grid: crate::volgrid::VolumeGrid,
    /// From the grid's unit cube [0, 1]^3 to world space (Mitsuba: the volume's `to_world`,
    /// after the file's bounding box when `use_grid_bbox` is true).
    pub to_world: Mat4,
    /// Nearest-cell lookups (Mitsuba's `filter_type` "nearest") instead of trilinear ones.
    pub nearest: bool,
}

/// A phase function (Mitsuba's `<phase>`).
#[derive(Clone, Debug, PartialEq)]
pub enum PhaseDesc {
    /// `isotropic`: 1 / (4 pi).
    Isotropic,
    /// `hg`: Henyey-Greenstein with mean cosine `g` in (-1, 1) (positive: forward).
    HenyeyGreenstein {
        /// Mean cosine of the scattering angle.
        g: f32,
    },
    /// `rayleigh`: `3 / (16 pi) (1 + cos^2 theta)` (Rayleigh scattering, unpolarised).
    Rayleigh,
    /// `tabphase`: values at points spaced evenly over the scattering cosine's [-1, 1] (1:
    /// forward), linear between them, normalised when built (at least two, each >= 0).
    Tabulated(Vec<f32>),
    /// `blendphase`: `(1 - weight) first + weight second`.
    Blend {
        /// The second phase function's share, in [0, 1].
        weight: f32,
        /// The first nested phase function.
        first: Box<PhaseDesc>,
        /// The second nested phase function.
        second: Box<PhaseDesc>,
    },
}
