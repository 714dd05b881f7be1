//! A renderable scene built from the loader's description: BVH, materials, lights, camera.
//! Built once ([`Scene::build`], in `build.rs`), immutable and shared by all render threads.

mod build;
mod interaction;
mod mesh;

use crate::accel::{Accel, AccelHit, BATCH};
use crate::camera::Camera;
use crate::geometry::{Interaction, Primitive};
use crate::light::{AreaLight, Light};
use crate::material::SurfaceMaterial;
use crate::medium::Medium;
use crate::texture::{Attribute, TexturePoint};
use mesh::PrimRef;
use pt_bsdf::SurfaceBsdf;
use pt_math::lanes::{lanes_where, set_lanes, Mask};
use pt_math::{Distribution1D, Mat3, Ray, Vec2, Vec3};
use pt_scene::SourceLoc;
use pt_spectrum::{ColorMode, SampledWavelengths};

/// Shadow rays stop this fraction short of the light point, whose origin is already offset: a
/// relative guard against rounding at the far end, not an absolute epsilon.
pub const SHADOW_RAY_SHORTEN: f32 = 1.0 - 1e-5;

/// Errors found while building a scene (after parsing): each names the element at fault.
#[derive(Debug, thiserror::Error)]
#[error("{loc}: {message}")]
pub struct BuildError {
    /// The offending element.
    pub loc: SourceLoc,
    /// What is wrong.
    pub message: String,
}

/// How lights are chosen for next-event estimation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightSelection {
    /// As [`LightSelection::Power`] for the distant lights' shares and for light paths; from
    /// a shading point, the lights at a finite distance are chosen with a light tree by power,
    /// distance and orientation (Conty Estevez and Kulla 2018; [`crate::light::LightTree`]).
    /// The default.
    #[default]
    Tree,
    /// Each distant light its uniform share, the others the rest in proportion to their
    /// emitted power (see `power_selection` in build.rs), wherever the shading point is.
    Power,
    /// Uniform over lights (Mitsuba 3's choice), for comparison.
    Uniform,
}

/// Per-shape data needed after a hit.
struct ShapeData {
    material: u32,
    light: Option<u32>,
    /// Indices into `Scene::media` of the media inside and outside the shape; a shape with
    /// either is a medium boundary ([`Scene::medium_boundary`]).
    interior: Option<u32>,
    exterior: Option<u32>,
    /// Vertex normals and uvs of meshes, indexed through `indices`.
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    /// Vertex tangents (xyz, handedness w) of meshes that have them (normal maps).
    tangents: Option<Vec<pt_math::Vec4>>,
    indices: Vec<[u32; 3]>,
    /// Mesh attributes by slot (`texture::AttributeSlots`), for `mesh_attribute` textures.
    attributes: Vec<Option<Attribute>>,
    /// Spheres and cylinders: the object-to-world rotation (uv and dp/du follow its z axis);
    /// disks: the two axes and the unit front normal as columns.
    frame: Option<Mat3>,
    /// `sdfgrid` shapes: the grid, for smooth shading normals.
    sdf: Option<std::sync::Arc<pt_scene::SdfGrid>>,
    /// Curves: how many segments the shape has (the texture coordinate along a curve runs
    /// over all of them, as in Mitsuba).
    curve_segments: u32,
    /// The instanced group the shape belongs to (its primitives are in that group's
    /// [`Group::accel`], in the group's space), or `None` for a shape of the scene itself.
    group: Option<u32>,
}

impl ShapeData {
    /// A shape with `material`, in `group` (or the scene's own), its other data still empty.
    fn new(material: u32, group: Option<u32>) -> Self {
        ShapeData {
            material,
            light: None,
            interior: None,
            exterior: None,
            normals: None,
            uvs: None,
            tangents: None,
            indices: Vec::new(),
            attributes: Vec::new(),
            frame: None,
            sdf: None,
            curve_segments: 0,
            group,
        }
    }
}

/// Instancing (Mitsuba's `shapegroup` and `instance`): each group's primitives once, in the
/// group's own space, and a top-level tree over the instances' world boxes.
struct Instancing {
    groups: Vec<Group>,
    /// The instances in the top-level tree's slot order.
    instances: Vec<Instance>,
    top: crate::accel::top::TopLevel,
}

/// One shape group: its BVH (group space) and, per primitive, its shape and face.
struct Group {
    accel: Accel,
    prim_refs: Vec<PrimRef>,
}

/// One instance: which group, and its transforms.
struct Instance {
    group: u32,
    /// Group space to world space.
    to_world: pt_math::glam::Affine3A,
    /// World space to group space.
    to_local: pt_math::glam::Affine3A,
    /// Normals from group space to world space (the inverse transpose of the linear part).
    normal_to_world: Mat3,
}

/// `ray` below `tmax` in the space of instance `i`, with a unit direction, and the factor
/// from world distances to the local ray's (a local distance divided by it is the world's).
#[inline(always)]
fn local_ray(i: &Instance, ray: &Ray, tmax: f32) -> (Ray, f32) {
    let d = i.to_local.transform_vector3(ray.dir);
    let scale = d.length();
    let local = Ray {
        origin: i.to_local.transform_point3(ray.origin),
        dir: d / scale,
        tmin: ray.tmin * scale,
        tmax: tmax * scale,
    };
    (local, scale)
}

/// Counts for `pt info` and logs.
#[derive(Clone, Debug, Default)]
pub struct SceneStats {
    /// Triangles in the BVH, counting those merged into parallelograms.
    pub triangles: usize,
    /// Pairs of mesh triangles tested as one parallelogram (rectangles, cube faces, quads).
    pub parallelograms: usize,
    /// Analytic spheres in the BVH.
    pub spheres: usize,
    /// Analytic cylinders in the BVH.
    pub cylinders: usize,
    /// Analytic disks.
    pub disks: usize,
    /// Voxels of `sdfgrid` shapes that the surface passes through (one primitive each).
    pub sdf_voxels: usize,
    /// Segments of `linearcurve` and `bsplinecurve` shapes (one primitive each).
    pub curve_segments: usize,
    /// Zero-area triangles left out of the BVH (they can neither be hit nor emit).
    pub degenerate_triangles: usize,
}

/// A scene ready for rendering. Immutable and shared by all render threads.
pub struct Scene {
    accel: Accel,
    prim_refs: Vec<PrimRef>,
    /// Instanced groups, if the scene has instances.
    instancing: Option<Instancing>,
    shapes: Vec<ShapeData>,
    /// One material per BSDF of the description (`ShapeDesc::bsdf` indexes it).
    pub materials: Vec<SurfaceMaterial>,
    /// The participating media that shapes bound and the camera may sit in.
    pub media: Vec<Medium>,
    /// Index into `media` of the medium around the camera, if any.
    pub camera_medium: Option<u32>,
    /// All lights: area lights first (in shape order), then the others in file order.
    pub lights: Vec<Light>,
    /// Indices into `lights` of lights that rays leaving the scene can see.
    pub infinite_lights: Vec<usize>,
    /// Light choice by power alone (light paths; NEE without a tree).
    light_distr: Option<Distribution1D>,
    /// Light choice from a shading point ([`LightSelection::Tree`]).
    light_tree: Option<crate::light::LightTree>,
    /// Centre and radius of the scene's bounding sphere.
    pub bounds: (Vec3, f32),
    /// The camera.
    pub camera: Camera,
    /// Colour mode the scene is rendered in.
    pub mode: ColorMode,
    /// Counts.
    pub stats: SceneStats,
}

impl Scene {
    /// Closest hit along `ray`, with its surface data.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<Interaction> {
        let mut out = None;
        self.intersect_into(ray, &mut out);
        out
    }

    /// [`Scene::intersect`] written into `out`. Each case writes its result there directly: a
    /// result that one of several cases builds in a temporary is copied out of it, and the
    /// copy's wide loads stall on the narrower stores that built it (its first load drew 3% of
    /// the path tracer's profile samples on the Cornell box).
    #[inline(always)]
    pub fn intersect_into(&self, ray: &Ray, out: &mut Option<Interaction>) {
        let hit = self.accel.intersect(ray);
        if let Some(inst) = &self.instancing {
            *out = self.intersect_with_instances(inst, ray, hit);
            return;
        }
        match hit {
            Some(h) => *out = Some(self.interaction(&self.accel, &self.prim_refs, ray, h)),
            None => *out = None,
        }
    }

    /// [`Scene::intersect`] in a scene with instances, given the closest hit `hit` of `ray` on
    /// the scene's own primitives.
    #[inline(never)]
    fn intersect_with_instances(
        &self,
        inst: &Instancing,
        ray: &Ray,
        hit: Option<AccelHit>,
    ) -> Option<Interaction> {
        let tmax = hit.map_or(ray.tmax, |h| h.t);
        if let Some(it) = self.intersect_instances(inst, ray, tmax) {
            return Some(it);
        }
        Some(self.interaction(&self.accel, &self.prim_refs, ray, hit?))
    }

    /// Whether the segment `ray` (tmin..tmax) is blocked.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(ray)
            || self.instancing.as_ref().is_some_and(|inst| {
                inst.top.any(ray, |slot, tmax| {
                    let i = &inst.instances[slot];
                    let (local, _) = local_ray(i, ray, tmax);
                    inst.groups[i.group as usize].accel.occluded(&local)
                })
            })
    }

    /// [`Scene::intersect_into`] of the rays `rays[k]` for each lane `k` in `active`, into
    /// `out[k]` (other entries are left as they are), traced together as
    /// [`Accel::intersect_batch`] does it (in SIMD lanes through a tiny scene's primitives). The
    /// same results as one at a time; a scene with instances takes them one at a time.
    #[inline(always)]
    pub fn intersect_batch(
        &self,
        rays: &[Ray; BATCH],
        active: Mask,
        out: &mut [Option<Interaction>; BATCH],
    ) {
        if self.instancing.is_some() {
            for k in set_lanes(active) {
                self.intersect_into(&rays[k], &mut out[k]);
            }
            return;
        }
        let mut hits = [None; BATCH];
        self.accel.intersect_batch(rays, active, &mut hits);
        for k in set_lanes(active) {
            match hits[k] {
                Some(h) => {
                    out[k] = Some(self.interaction(&self.accel, &self.prim_refs, &rays[k], h))
                }
                None => out[k] = None,
            }
        }
    }

    /// [`Scene::occluded`] of the rays `rays[k]` for each lane `k` in `active`: the mask of
    /// those blocked, the rays traced together as in [`Scene::intersect_batch`].
    #[inline(always)]
    pub fn occluded_batch(&self, rays: &[Ray; BATCH], active: Mask) -> Mask {
        if self.instancing.is_some() {
            return lanes_where(active, |k| self.occluded(&rays[k]));
        }
        self.accel.occluded_batch(rays, active)
    }

    /// The closest hit on an instance below `tmax`, in world space.
    #[inline(never)]
    fn intersect_instances(&self, inst: &Instancing, ray: &Ray, tmax: f32) -> Option<Interaction> {
        let mut best = None;
        let (slot, t) = inst.top.closest(ray, tmax, |slot, tmax| {
            let i = &inst.instances[slot];
            let (local, scale) = local_ray(i, ray, tmax);
            match inst.groups[i.group as usize].accel.intersect(&local) {
                Some(h) if h.t / scale < tmax => {
                    best = Some((h, local));
                    h.t / scale
                }
                _ => f32::INFINITY,
            }
        })?;
        let (h, local) = best?;
        let i = &inst.instances[slot];
        let g = &inst.groups[i.group as usize];
        let mut it = self.interaction(&g.accel, &g.prim_refs, &local, h);
        let n = |v: Vec3| (i.normal_to_world * v).normalize();
        it.p = i.to_world.transform_point3(it.p);
        it.ng = n(it.ng);
        it.ns = n(it.ns);
        it.dpdu = i.to_world.transform_vector3(it.dpdu);
        it.dpdv = i.to_world.transform_vector3(it.dpdv);
        let tangent = i.to_world.transform_vector3(it.tangent.truncate());
        it.tangent = tangent.extend(it.tangent.w);
        it.t = t;
        Some(it)
    }

    /// The primitives the BVH holds (world space, in BVH order): triangles, parallelograms
    /// merged from triangle pairs, spheres, cylinders. For benchmarks and tools.
    pub fn primitives(&self) -> &[Primitive] {
        &self.accel.prims
    }

    /// Whether nothing blocks the segment from `origin` (a ray origin already offset off its
    /// surface) to the light sample `ls`: to the light point offset off the light's own surface
    /// (point-like lights have no normal and need no offset), or along `ls.wi` to infinity for
    /// distant lights. The far end stops a relative fraction short of the point
    /// (`SHADOW_RAY_SHORTEN`), a guard against rounding, not an absolute epsilon.
    #[inline]
    pub fn light_unoccluded(&self, origin: Vec3, ls: &crate::light::LightSample) -> bool {
        if ls.dist.is_infinite() {
            return !self.occluded(&Ray::new(origin, ls.wi));
        }
        let target = if ls.n == Vec3::ZERO {
            ls.p
        } else {
            pt_math::offset_ray_origin(ls.p, ls.n * ls.n.dot(-ls.wi).signum())
        };
        self.segment_unoccluded(origin, target)
    }

    /// Whether nothing blocks the segment from `origin` (a ray origin already offset off its
    /// surface) to `target` (a point off any surface, or already offset): the far end stops a
    /// relative fraction short (`SHADOW_RAY_SHORTEN`). Light samples and connections to the
    /// camera use it.
    #[inline(always)]
    pub fn segment_unoccluded(&self, origin: Vec3, target: Vec3) -> bool {
        let seg = target - origin;
        let dist = seg.length();
        dist > 0.0
            && !self.occluded(&Ray {
                origin,
                dir: seg / dist,
                tmin: 0.0,
                tmax: dist * SHADOW_RAY_SHORTEN,
            })
    }

    /// Whether any surface is `fluorescent` (spectral mode only: RGB mode keeps the elastic
    /// part).
    pub fn has_fluorescence(&self) -> bool {
        self.materials.iter().any(|m| m.fluorescent().is_some())
    }

    /// The material of a hit shape.
    #[inline(always)]
    pub fn material(&self, shape: u32) -> &SurfaceMaterial {
        &self.materials[self.shapes[shape as usize].material as usize]
    }

    /// Where textures are evaluated at a hit: its texture coordinates and, on meshes with
    /// attributes, the hit's triangle and barycentric weights.
    #[inline(always)]
    pub fn texture_point(&self, hit: &Interaction) -> TexturePoint<'_> {
        let shape = &self.shapes[hit.shape as usize];
        if shape.attributes.is_empty() {
            return TexturePoint::uv(hit.uv);
        }
        let refs = match (shape.group, &self.instancing) {
            (Some(g), Some(inst)) => &inst.groups[g as usize].prim_refs,
            _ => &self.prim_refs,
        };
        let r = refs[hit.prim as usize];
        let (b1, b2) = (hit.b.x, hit.b.y);
        TexturePoint {
            uv: hit.uv,
            attributes: &shape.attributes,
            vertices: r.vertices(&shape.indices),
            weights: [1.0 - b1 - b2, b1, b2],
            face: r.local,
        }
    }

    /// The index of the hit triangle within its shape's mesh, as Mitsuba's `prim_index` (0 on
    /// spheres and cylinders; a parallelogram merged from two triangles reports the one hit).
    pub fn primitive_index(&self, hit: &Interaction) -> u32 {
        let shape = &self.shapes[hit.shape as usize];
        let refs = match (shape.group, &self.instancing) {
            (Some(g), Some(inst)) => &inst.groups[g as usize].prim_refs,
            _ => &self.prim_refs,
        };
        let r = refs[hit.prim as usize];
        // A parallelogram's barycentrics span both triangles: beyond b1 + b2 = 1 is the second.
        r.local + u32::from(r.part.is_some() && hit.b.x + hit.b.y > 1.0)
    }

    /// The BSDF at a hit, at the path's wavelengths ([`SurfaceMaterial::bsdf`]: borrowed from
    /// the material when it is the same all over the surface).
    #[inline(always)]
    pub fn bsdf(
        &self,
        hit: &Interaction,
        lambda: &SampledWavelengths,
    ) -> std::borrow::Cow<'_, SurfaceBsdf> {
        self.material(hit.shape)
            .bsdf(hit, &self.texture_point(hit), lambda)
    }

    /// At a fluorescent hit, the wavelengths at which each lane continues (some lanes move to
    /// an excitation wavelength, see `fluorescence.rs`); `None` for other materials. `u` is
    /// uniform.
    #[inline]
    pub fn fluoresce(
        &self,
        shape: u32,
        lambda: &SampledWavelengths,
        u: f32,
    ) -> Option<SampledWavelengths> {
        self.material(shape)
            .fluorescent()
            .map(|f| f.scatter(lambda, u))
    }

    /// The media on the two sides of `shape` (inside, outside) if it is a medium boundary
    /// (has either; Mitsuba's `is_medium_transition`), else `None`: crossing it then keeps
    /// the medium the ray is in.
    #[inline]
    pub fn medium_boundary(&self, shape: u32) -> Option<(Option<u32>, Option<u32>)> {
        let s = &self.shapes[shape as usize];
        (s.interior.is_some() || s.exterior.is_some()).then_some((s.interior, s.exterior))
    }

    /// Whether the scene has any participating medium.
    pub fn has_media(&self) -> bool {
        !self.media.is_empty()
    }

    /// The light attached to a shape, if it emits: `(light index, light)`.
    #[inline]
    pub fn shape_light(&self, shape: u32) -> Option<(usize, &AreaLight)> {
        let i = self.shapes[shape as usize].light? as usize;
        match &self.lights[i] {
            Light::Area(a) => Some((i, a)),
            _ => None,
        }
    }

    /// Chooses a light by power alone, wherever it will be seen from (the start of a light
    /// path): `(index, probability, u rescaled)`.
    #[inline(always)]
    pub fn sample_light(&self, u: f32) -> Option<(usize, f32, f32)> {
        self.light_distr.as_ref().map(|d| d.sample(u))
    }

    /// Probability that [`Scene::sample_light`] chooses light `i`.
    #[inline]
    pub fn light_pmf(&self, i: usize) -> f32 {
        self.light_distr.as_ref().map_or(0.0, |d| d.pmf(i))
    }

    /// Chooses a light for next-event estimation from the point `p` (world space):
    /// `(index, probability, u rescaled)`, by the scene's [`LightSelection`].
    #[inline(always)]
    pub fn sample_light_at(&self, p: Vec3, u: f32) -> Option<(usize, f32, f32)> {
        match &self.light_tree {
            Some(t) => t.sample(p, u),
            None => self.sample_light(u),
        }
    }

    /// Probability that [`Scene::sample_light_at`] chooses light `i` from the point `p` (for
    /// MIS weights of emission that a scattered ray found).
    #[inline]
    pub fn light_pmf_at(&self, p: Vec3, i: usize) -> f32 {
        match &self.light_tree {
            Some(t) => t.pmf(p, i),
            None => self.light_pmf(i),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BvhKind, LightSelection};

    /// The scene description of an XML text (paths relative to the working folder).
    fn desc_of(xml: &str) -> pt_scene::SceneDesc {
        let (file, dir) = (std::path::Path::new("t.xml"), std::path::Path::new("."));
        pt_scene::load_str(xml, file, dir, &[]).unwrap()
    }

    /// The render scene of a description, with the default acceleration and light selection.
    fn built(desc: &pt_scene::SceneDesc) -> Scene {
        Scene::build(desc, BvhKind::Auto, LightSelection::Power).unwrap()
    }

    /// A sphere turned by its `to_world` keeps Mitsuba's parameterisation in its own frame:
    /// u = azimuth about the object's z axis / 2 pi, v = polar angle from +z / pi, and dp/du
    /// along the object's azimuth direction carried to the world (the tangent that orients
    /// anisotropic BSDFs; it was the world's azimuth before, which turned highlights by 90
    /// degrees). Here the object's z axis is the world's +x (rotation about y by 90 degrees),
    /// so a hit on the world's +y axis is at object (0, 1, 0): u = 1/4, v = 1/2, and dp/du
    /// points along the object's -x, which is the world's +z (the world's azimuth about z
    /// would give -x instead).
    #[test]
    fn rotated_sphere_follows_its_object_frame() {
        let xml = r#"<scene version="3.0.0">
            <shape type="sphere">
                <float name="radius" value="2"/>
                <transform name="to_world"><rotate y="1" angle="90"/><translate x="1"/></transform>
            </shape>
        </scene>"#;
        let scene = built(&desc_of(xml));
        // Rotation about y by +90 degrees maps object x -> world -z, y -> y, z -> world +x.
        let frame = Mat3::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let centre = Vec3::new(1.0, 0.0, 0.0);
        for (origin, object_dir) in [
            (Vec3::new(1.0, 5.0, 0.0), Vec3::Y),
            (Vec3::new(1.0, 0.0, -5.0), Vec3::X),
            (Vec3::new(5.0, 0.0, 0.0), Vec3::Z),
            (Vec3::new(1.0, -5.0, 0.0), -Vec3::Y),
        ] {
            let world_dir = frame * object_dir;
            let ray = Ray::new(origin, (centre + world_dir * 2.0 - origin).normalize());
            let hit = scene.intersect(&ray).expect("the ray hits the sphere");
            assert!(
                (hit.p - (centre + world_dir * 2.0)).length() < 1e-4,
                "{}",
                hit.p
            );
            let o = object_dir;
            let mut u = o.y.atan2(o.x) / std::f32::consts::TAU;
            if u < 0.0 {
                u += 1.0;
            }
            let v = o.z.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
            // At the poles (object z) u is arbitrary and dp/du vanishes.
            if o.z.abs() < 0.5 {
                assert!(
                    (hit.uv - Vec2::new(u, v)).abs().max_element() < 1e-5,
                    "{} vs {u} {v}",
                    hit.uv
                );
                let expected = frame * Vec3::new(-o.y, o.x, 0.0) * (std::f32::consts::TAU * 2.0);
                assert!(
                    (hit.dpdu - expected).length() < 1e-3 * expected.length(),
                    "{} vs {expected}",
                    hit.dpdu
                );
            } else {
                assert!(
                    (hit.uv.y - v).abs() < 1e-5 && hit.dpdu.length() < 1e-4,
                    "{} {}",
                    hit.uv,
                    hit.dpdu
                );
            }
        }
    }

    /// `mesh_attribute` reads the hit shape's values: vertex values interpolated with the hit's
    /// barycentric weights, face values constant per triangle; a mesh without the attribute
    /// a material reads is a build error naming the shape.
    #[test]
    fn mesh_attributes_at_hits() {
        let xml = r#"<scene version="3.0.0">
            <shape type="rectangle"><bsdf type="diffuse">
                <texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_color"/></texture>
            </bsdf></shape>
            <shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform><bsdf type="diffuse">
                <texture type="mesh_attribute" name="reflectance"><string name="name" value="face_tint"/><float name="scale" value="0.5"/></texture>
            </bsdf></shape>
        </scene>"#;
        let mut desc = desc_of(xml);
        let e = Scene::build(&desc, BvhKind::Auto, LightSelection::Power)
            .err()
            .expect("no attributes yet");
        assert!(
            e.message.contains("mesh attribute 'vertex_color'") && e.loc.line == 2,
            "{e}"
        );
        use pt_scene::{AttributeKind, Geometry, MeshAttribute};
        // The rectangle's corners are (-1,-1), (1,-1), (1,1), (-1,1); triangles (0,1,2), (0,2,3).
        let corners = [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let faces = [[0.2, 0.4, 0.6], [0.8, 0.6, 0.4]];
        for (i, (name, kind, values)) in [
            ("vertex_color", AttributeKind::Vertex, corners.concat()),
            ("face_tint", AttributeKind::Face, faces.concat()),
        ]
        .into_iter()
        .enumerate()
        {
            let Geometry::Mesh(m) = &mut desc.shapes[i].geometry else {
                panic!()
            };
            m.attributes.push(MeshAttribute {
                name: name.into(),
                kind,
                dims: 3,
                values,
            });
        }
        let scene = Scene::build(&desc, BvhKind::Auto, LightSelection::Power).unwrap();
        let lambda = pt_spectrum::SampledWavelengths::sample_visible(0.5);
        let albedo = |x: f32, y: f32, z: f32| {
            let hit = scene
                .intersect(&Ray::new(Vec3::new(x, y, z), -Vec3::Z))
                .expect("hit");
            match scene.bsdf(&hit, &lambda).bsdf {
                pt_bsdf::Bsdf::Lambert(l) => l.reflectance.rgb(),
                b => panic!("{b:?}"),
            }
        };
        let close = |a: [f32; 3], b: [f32; 3]| (0..3).all(|c| (a[c] - b[c]).abs() < 1e-5);
        // At (0.5, -0.5) in triangle (0, 1, 2): weights 0.25, 0.5, 0.25.
        let a = albedo(0.5, -0.5, 1.0);
        assert!(close(a, [0.25, 0.5, 0.25]), "{a:?}");
        // At (-0.5, 0.5) in triangle (0, 2, 3): weights 0.25, 0.25, 0.5.
        let a = albedo(-0.5, 0.5, 1.0);
        assert!(close(a, [0.75, 0.5, 0.75]), "{a:?}");
        // Face values times the scale, the same anywhere in each triangle.
        for (x, y, want) in [
            (0.5, -0.5, [0.1, 0.2, 0.3]),
            (0.9, -0.8, [0.1, 0.2, 0.3]),
            (-0.5, 0.5, [0.4, 0.3, 0.2]),
        ] {
            let hit = scene
                .intersect(&Ray::new(Vec3::new(x, y, -0.5), -Vec3::Z))
                .expect("hit");
            let b = scene.bsdf(&hit, &lambda).bsdf;
            let pt_bsdf::Bsdf::Lambert(l) = b else {
                panic!("{b:?}")
            };
            assert!(
                close(l.reflectance.rgb(), want),
                "({x}, {y}): {:?}",
                l.reflectance.rgb()
            );
        }
    }

    /// dp/du and dp/dv are the derivatives of the surface's parameterisation (what a bump map
    /// perturbs): between two nearby hits, the change of position is dp/du du + dp/dv dv to
    /// first order, on a turned sphere, a turned cylinder and a uv-mapped rectangle. A swapped
    /// or mis-signed tangent gives errors of the order of the step; the tolerance is 2% of it.
    #[test]
    fn surface_tangents_are_the_derivatives_of_the_uv_parameterisation() {
        let xml = r#"<scene version="3.0.0">
            <shape type="sphere">
                <float name="radius" value="0.7"/>
                <transform name="to_world"><rotate x="1" angle="-70"/><rotate y="1" angle="30"/></transform>
            </shape>
            <shape type="cylinder">
                <float name="radius" value="0.4"/>
                <transform name="to_world"><rotate x="1" angle="35"/><translate x="3"/></transform>
            </shape>
            <shape type="rectangle">
                <transform name="to_world"><scale x="0.6" y="0.9"/><rotate z="1" angle="25"/><rotate x="1" angle="-60"/><translate x="-3"/></transform>
                <bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf>
            </shape>
        </scene>"#;
        // (The rectangle's texture makes its hits carry uvs: untextured isotropic surfaces
        // skip them.)
        let scene = built(&desc_of(xml));
        for (target, toward) in [
            (Vec3::new(0.2, 0.3, 0.5), Vec3::new(0.2, 0.3, 0.5)),
            (Vec3::new(-0.4, 0.1, 0.3), Vec3::new(-0.4, 0.1, 0.3)),
            (Vec3::new(3.0, -0.287, 0.41), Vec3::new(0.3, 0.819, 0.574)),
            (Vec3::new(-3.1, 0.05, -0.1), Vec3::new(0.0, 0.5, 0.9)),
        ] {
            let origin = target + toward.normalize() * 4.0;
            let hit_at = |p: Vec3| {
                scene
                    .intersect(&Ray::new(origin, (p - origin).normalize()))
                    .expect("a hit")
            };
            let a = hit_at(target);
            for step in [Vec3::new(0.01, 0.0, 0.0), Vec3::new(0.0, 0.007, 0.006)] {
                let b = hit_at(target + step);
                let (du, dv) = (b.uv.x - a.uv.x, b.uv.y - a.uv.y);
                let predicted = a.dpdu * du + a.dpdv * dv;
                let moved = b.p - a.p;
                assert!(
                    (predicted - moved).length() < 0.02 * moved.length(),
                    "{target}: moved {moved}, predicted {predicted} (dpdu {}, dpdv {})",
                    a.dpdu,
                    a.dpdv
                );
            }
        }
    }

    /// A cylinder placed by p0/p1 and turned by its `to_world` keeps Mitsuba's
    /// parameterisation: the object frame is Duff et al.'s around the axis p1 - p0 (here +z,
    /// so the identity), carried by the rotation about y by 90 degrees (object x -> world -z,
    /// z -> world +x). At object (r cos phi, r sin phi, z): u = phi / 2 pi, v = z / length,
    /// the normal is the object's (cos phi, sin phi, 0) in the world, and dp/du is
    /// 2 pi (-r sin phi, r cos phi, 0) in the world. Then, with a checkerboard emitter on it:
    /// every light sample that a ray from the sampling point sees has the radiance the hit
    /// gets at its texture coordinates (the sampler's uv and the hit's agree).
    #[test]
    fn rotated_cylinder_follows_mitsuba_parameterisation() {
        let xml = r#"<scene version="3.0.0">
            <shape type="cylinder">
                <point name="p1" value="0, 0, 2"/>
                <float name="radius" value="0.5"/>
                <transform name="to_world"><rotate y="1" angle="90"/><translate x="1"/></transform>
                <emitter type="area">
                    <texture type="checkerboard" name="radiance">
                        <rgb name="color0" value="1, 0, 0"/><rgb name="color1" value="0, 0, 1"/>
                        <transform name="to_uv"><scale x="12" y="5"/></transform>
                    </texture>
                </emitter>
            </shape>
        </scene>"#;
        let scene = built(&desc_of(xml));
        let frame = Mat3::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let p0 = Vec3::new(1.0, 0.0, 0.0);
        for (phi, z) in [(0.3f32, 0.2f32), (1.9, 1.0), (3.5, 1.7), (5.9, 0.6)] {
            let (s, c) = phi.sin_cos();
            let out = frame * Vec3::new(c, s, 0.0);
            let point = p0 + frame * Vec3::new(0.5 * c, 0.5 * s, z);
            let hit = scene
                .intersect(&Ray::new(point + out * 3.0, -out))
                .expect("the ray hits the cylinder");
            assert!((hit.p - point).length() < 1e-5, "{} vs {point}", hit.p);
            assert!((hit.ng - out).length() < 1e-5, "{} vs {out}", hit.ng);
            let uv = Vec2::new(phi / std::f32::consts::TAU, z / 2.0);
            assert!(
                (hit.uv - uv).abs().max_element() < 1e-5,
                "{} vs {uv}",
                hit.uv
            );
            let dpdu = frame * Vec3::new(-0.5 * s, 0.5 * c, 0.0) * std::f32::consts::TAU;
            assert!((hit.dpdu - dpdu).length() < 1e-4, "{} vs {dpdu}", hit.dpdu);
        }
        let crate::light::Light::Area(light) = &scene.lights[0] else {
            panic!("an area light");
        };
        let lambda = SampledWavelengths::sample_visible(0.5);
        let x = Vec3::new(0.3, 2.0, 0.4);
        let (mut seen, mut differ) = (0, 0);
        let n = 20_000;
        for i in 0..n {
            let u = Vec2::new(
                (i as f32 + 0.5) / n as f32,
                ((i * 7919) % n) as f32 / n as f32,
            );
            let Some(ls) = light.sample(x, 0.5, u, &lambda) else {
                continue;
            };
            let Some(hit) = scene.intersect(&Ray::new(x, ls.wi)) else {
                continue;
            };
            if (hit.t - ls.dist).abs() > 1e-4 * ls.dist {
                continue; // the near side hides this point
            }
            seen += 1;
            let at_hit = light.emitted(hit.ng, -ls.wi, hit.uv, &lambda);
            if (at_hit.0 - ls.radiance.0).abs().max_element() > 1e-6 {
                differ += 1;
            }
        }
        // Half the cylinder faces x; points within rounding of a cell edge may land in the
        // neighbouring cell (a few in 1e4).
        assert!(seen > n / 4, "{seen} of {n} samples seen");
        assert!(
            differ * 1000 <= seen,
            "{differ} of {seen} seen samples differ"
        );
    }

    /// Light selection by power: a sky gets the uniform share (1/3 here) whatever its power
    /// over the scene's disk, and the two rectangles split the rest by power (area x radiance:
    /// 1 x 3 against 4 x 3, so 2/3 x 1/5 and 2/3 x 4/5); without the sky they split it all;
    /// uniform selection gives each a third.
    #[test]
    fn power_selection_gives_distant_lights_their_uniform_share() {
        let rect = |scale: &str, y: f32| {
            format!(
                r#"<shape type="rectangle"><transform name="to_world"><scale value="{scale}"/><translate y="{y}"/></transform>
                <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>"#
            )
        };
        let lights = format!("{}{}", rect("0.5", 0.0), rect("1", 3.0));
        let sky = r#"<emitter type="constant"><rgb name="radiance" value="50"/></emitter>"#;
        let xml = |body: &str| format!(r#"<scene version="3.0.0">{body}</scene>"#);
        let pmfs = |scene: &Scene| {
            (0..scene.lights.len())
                .map(|i| scene.light_pmf(i))
                .collect::<Vec<_>>()
        };
        let close = |a: &[f32], b: &[f32]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
        };
        let with_sky = built(&desc_of(&xml(&format!("{lights}{sky}"))));
        let got = pmfs(&with_sky);
        assert!(close(&got, &[2.0 / 15.0, 8.0 / 15.0, 1.0 / 3.0]), "{got:?}");
        let without = built(&desc_of(&xml(&lights)));
        let got = pmfs(&without);
        assert!(close(&got, &[0.2, 0.8]), "{got:?}");
        let uniform = Scene::build(
            &desc_of(&xml(&format!("{lights}{sky}"))),
            BvhKind::Auto,
            LightSelection::Uniform,
        )
        .unwrap();
        let got = pmfs(&uniform);
        assert!(close(&got, &[1.0 / 3.0; 3]), "{got:?}");
    }
}
