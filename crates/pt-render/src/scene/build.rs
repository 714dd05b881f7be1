//! Building a [`Scene`] from the description: materials and their textures once, meshes into
//! the BVH, lights (area lights in shape order, then the others), the light-selection
//! distribution and the camera.

use super::mesh::{
    add_mesh, bounding_sphere, parallelogram_light, primitive_of, primitive_of_geometry, PrimRef,
};
use super::{
    BuildError, Group, Instance, Instancing, LightSelection, Scene, SceneStats, ShapeData,
};
use crate::accel::top::TopLevel;
use crate::accel::{Accel, BvhKind};
use crate::camera::Camera;
use crate::geometry::Primitive;
use crate::light::{build_light, AreaLight, Light, LightShape, LightTree};
use crate::material::{build_material, SurfaceMaterial};
use crate::medium::{Grid, Lobe, Medium, Phase, TabulatedPhase, VolumeSpectrum};
use crate::texture::{
    constant_spectrum, rgb_of, spectrum_for_role, DisplayPrimaries, Role, Texture, TextureBuilder,
};
use obvhs::aabb::Aabb;
use pt_math::glam::{Affine3A, Mat3, Vec3A};
use pt_math::Distribution1D;
use pt_scene::{AreaEmitterDesc, Geometry, Projection, SceneDesc, ShapeDesc, TextureDesc};
use pt_spectrum::ColorMode;
use std::sync::Arc;

impl Scene {
    /// Builds the BVH and lights in the colour mode the scene needs (spectral when it has
    /// wavelength-dependent inputs, see [`SceneDesc::spectral_reason`]). `selection` chooses how
    /// NEE picks lights.
    pub fn build(
        desc: &SceneDesc,
        bvh: BvhKind,
        selection: LightSelection,
    ) -> Result<Scene, BuildError> {
        Scene::build_with_mode(desc, bvh, selection, None)
    }

    /// [`Scene::build`] with the colour mode forced (`--mode`); `None` chooses automatically.
    pub fn build_with_mode(
        desc: &SceneDesc,
        bvh: BvhKind,
        selection: LightSelection,
        mode: Option<ColorMode>,
    ) -> Result<Scene, BuildError> {
        let mode = mode.unwrap_or(if desc.spectral_reason().is_some() {
            ColorMode::Spectral
        } else {
            ColorMode::Rgb
        });
        let mut textures = TextureBuilder::new(mode);
        let materials: Vec<SurfaceMaterial> = desc
            .bsdfs
            .iter()
            .map(|b| build_material(b, &mut textures))
            .collect::<Result<_, _>>()?;
        let ShapesBuilt {
            prims,
            refs,
            mut shapes,
            mut lights,
            mut stats,
            mut media,
            meter_surface,
        } = build_shapes(desc, &materials, &mut textures, mode)?;
        let instancing = instancing(
            desc,
            &materials,
            &mut shapes,
            &mut stats,
            bvh,
            &mut media,
            mode,
        )?;
        let instance_boxes = instancing
            .iter()
            .flat_map(|i| &i.instances)
            .map(|i| i.bounds);
        let bounds = bounding_sphere(prims.iter().map(Primitive::aabb).chain(instance_boxes));
        // The primitives are made again from the description after the BVH build (less memory).
        let accel = Accel::build_compact(prims, bvh, |i| primitive_of(desc, refs[i]));
        let prim_refs = crate::accel::gathered(refs, &accel.original_index);
        // Vertex data for shading, copied after the BVH build (whose temporaries are the memory
        // peak) rather than before. Shapes of instanced groups follow the scene's own.
        let group_shapes = desc.groups.iter().flat_map(|g| &g.shapes);
        // AOVs of texture coordinates need them on every shape, used or not.
        let keep_uvs = desc.integrator.aov.as_ref().is_some_and(|a| a.needs_uv());
        for (data, shape) in shapes
            .iter_mut()
            .zip(desc.shapes.iter().chain(group_shapes))
        {
            if let Geometry::Mesh(mesh) = &shape.geometry {
                let material = &materials[data.material as usize];
                let light = data.light.map(|i| &lights[i as usize]);
                shading_data(data, mesh, material, light, &textures, mode, keep_uvs).map_err(
                    |message| BuildError {
                        loc: shape.loc.clone(),
                        message,
                    },
                )?;
            }
        }
        for l in &desc.lights {
            lights.push(build_light(l, mode, &mut textures)?);
        }
        let infinite_lights = (0..lights.len())
            .filter(|&i| lights[i].is_infinite())
            .collect();
        let weights: Vec<f32> = match selection {
            LightSelection::Tree | LightSelection::Power => power_selection(&lights, bounds.1),
            LightSelection::Uniform => vec![1.0; lights.len()],
        };
        let light_distr = Distribution1D::new(&weights);
        let light_tree = match selection {
            LightSelection::Tree => LightTree::build(&lights, &weights, bounds.1),
            LightSelection::Power | LightSelection::Uniform => None,
        };
        let camera = build_camera(desc, meter_surface, bounds)?;
        let camera_medium = match &desc.camera_medium {
            Some(m) => Some(add_medium(&mut media, m, mode)?),
            None => None,
        };
        Ok(Scene {
            accel,
            prim_refs,
            instancing: instancing.map(|i| i.scene),
            shapes,
            materials,
            media: media.into_iter().map(|(_, m)| m).collect(),
            camera_medium,
            lights,
            infinite_lights,
            light_distr,
            light_tree,
            bounds,
            camera,
            mode,
            stats,
        })
    }
}

/// What the scene's own shapes (not those of instanced groups) give the scene, in shape order.
struct ShapesBuilt {
    /// Their primitives for the BVH, and where each came from.
    prims: Vec<Primitive>,
    refs: Vec<PrimRef>,
    /// Per shape its material, light and media.
    shapes: Vec<ShapeData>,
    /// Their area lights.
    lights: Vec<Light>,
    stats: SceneStats,
    /// The media inside and outside them, each description once.
    media: Vec<(pt_scene::MediumDesc, Medium)>,
    /// The irradiancemeter's shape in its area-sampling form.
    meter_surface: Option<LightShape>,
}

/// Builds the scene's own shapes: their primitives, media and area lights (an emitter or the
/// irradiancemeter on a shape of zero area is an error).
fn build_shapes(
    desc: &SceneDesc,
    materials: &[SurfaceMaterial],
    textures: &mut TextureBuilder,
    mode: ColorMode,
) -> Result<ShapesBuilt, BuildError> {
    let mut out = ShapesBuilt {
        prims: Vec::new(),
        refs: Vec::new(),
        shapes: Vec::new(),
        lights: Vec::new(),
        stats: SceneStats::default(),
        media: Vec::new(),
        meter_surface: None,
    };
    // The irradiancemeter's shape, sampled by area as an emitter's is.
    let meter_shape = match desc.camera.projection {
        Projection::Irradiancemeter { shape } => Some(shape),
        _ => None,
    };
    for (si, shape) in desc.shapes.iter().enumerate() {
        if shape.bsdf >= materials.len() {
            return Err(BuildError {
                loc: shape.loc.clone(),
                message: format!("BSDF index {} out of range", shape.bsdf),
            });
        }
        let mut data = ShapeData::new(shape.bsdf as u32, None);
        let measured = meter_shape == Some(si);
        let light_shape = geometry(
            shape,
            si as u32,
            shape.emitter.is_some() || measured,
            &mut out.prims,
            &mut out.refs,
            &mut out.stats,
            &mut data,
        )?;
        if measured {
            out.meter_surface = match &light_shape {
                Some((surface, area)) if *area > 0.0 => Some(surface.clone()),
                _ => {
                    return Err(BuildError {
                        loc: desc.camera.loc.clone(),
                        message: "an irradiancemeter on a shape with zero area".into(),
                    })
                }
            };
        }
        if let Some(m) = &shape.interior {
            data.interior = Some(add_medium(&mut out.media, m, mode)?);
        }
        if let Some(m) = &shape.exterior {
            data.exterior = Some(add_medium(&mut out.media, m, mode)?);
        }
        if let Some(em) = &shape.emitter {
            let radiance = emission_texture(em, textures)?;
            match light_shape {
                Some((geometry, area)) if area > 0.0 => {
                    data.light = Some(out.lights.len() as u32);
                    out.lights.push(Light::Area(AreaLight {
                        radiance,
                        shape: geometry,
                        area,
                    }));
                }
                _ => {
                    return Err(BuildError {
                        loc: em.loc.clone(),
                        message: "area emitter on a shape with zero area".into(),
                    })
                }
            }
        }
        out.shapes.push(data);
    }
    Ok(out)
}

/// The camera of the scene's sensor and film, with the surface it measures (an
/// irradiancemeter's `meter_surface`, a distant sensor's target shape), a batch's sensors, and
/// a distant sensor aimed at the scene's bounding sphere `bounds`.
fn build_camera(
    desc: &SceneDesc,
    meter_surface: Option<LightShape>,
    bounds: (pt_math::Vec3, f32),
) -> Result<Camera, BuildError> {
    let mut camera = Camera::for_film(&desc.camera, &desc.film);
    if let Some(surface) = meter_surface {
        camera.attach_surface(surface);
    }
    if desc.camera.projection == Projection::Batch {
        let n = desc.batch.len().max(1) as u32;
        // The loader checks the file's width; a width set afterwards (--width) here.
        if desc.film.width % n != 0 {
            return Err(BuildError {
                loc: desc.camera.loc.clone(),
                message: format!(
                    "the film width ({}) must be divisible by the batch's number of sensors ({n}), as in Mitsuba",
                    desc.film.width
                ),
            });
        }
        let strip = desc.film.width / n;
        let members = desc
            .batch
            .iter()
            .map(|c| Camera::new(c, strip, desc.film.height))
            .collect();
        camera.set_batch(members, strip);
    }
    if let Projection::Distant { target } = desc.camera.projection {
        if let Some(shape) = &desc.sensor_target {
            // Sampled by area only: its primitives go nowhere.
            let (mut prims, mut refs) = (Vec::new(), Vec::new());
            let mut data = ShapeData::new(0, None);
            let mut scratch_stats = SceneStats::default();
            match geometry(
                shape,
                0,
                true,
                &mut prims,
                &mut refs,
                &mut scratch_stats,
                &mut data,
            )? {
                Some((surface, area)) if area > 0.0 => camera.attach_surface(surface),
                _ => {
                    return Err(BuildError {
                        loc: shape.loc.clone(),
                        message: "a distant sensor's target shape has zero area".into(),
                    })
                }
            }
        }
        camera.aim(target, bounds.0, bounds.1);
    }
    Ok(camera)
}

/// Builds `m` in the colour mode `mode` and appends it to `media`; returns its index. The same
/// description written once and referenced by several shapes becomes one medium.
fn add_medium(
    media: &mut Vec<(pt_scene::MediumDesc, Medium)>,
    m: &pt_scene::MediumDesc,
    mode: ColorMode,
) -> Result<u32, BuildError> {
    if let Some(i) = media.iter().position(|(d, _)| d == m) {
        return Ok(i as u32);
    }
    let err = |message: String| BuildError {
        loc: m.loc.clone(),
        message,
    };
    let sigma_rgb = rgb_of(&m.sigma_t, Role::Unbounded);
    if sigma_rgb.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
        return Err(err("sigma_t must be finite and non-negative".into()));
    }
    let spectral = mode == ColorMode::Spectral;
    let grid = |g: &pt_scene::GridDesc, emission: bool| {
        Grid::new(
            &g.grid.values,
            g.grid.channels,
            g.grid.resolution,
            g.to_world,
            g.nearest,
            spectral,
            emission,
        )
        .ok_or_else(|| {
            err(format!(
                "a grid with {} channels (1 or 3 are read)",
                g.grid.channels
            ))
        })
    };
    let volume = |v: &pt_scene::VolumeDesc, role: Role| -> Result<VolumeSpectrum, BuildError> {
        Ok(match v {
            pt_scene::VolumeDesc::Constant(c) => {
                VolumeSpectrum::Constant(constant_spectrum(c, role, mode))
            }
            pt_scene::VolumeDesc::Grid(g) => VolumeSpectrum::Grid(grid(g, role == Role::Emission)?),
        })
    };
    let density = m.density.as_ref().map(|g| grid(g, false)).transpose()?;
    let albedo = volume(&m.albedo, Role::Albedo)?;
    let extinct =
        sigma_rgb.iter().all(|&x| x == 0.0) || density.as_ref().is_some_and(|d| d.max == 0.0);
    let scatters = !extinct
        && match &m.albedo {
            pt_scene::VolumeDesc::Constant(
                pt_scene::SpectrumDesc::Constant(a) | pt_scene::SpectrumDesc::Uniform(a),
            ) => *a > 0.0,
            pt_scene::VolumeDesc::Constant(a) => rgb_of(a, Role::Albedo).iter().any(|&x| x > 0.0),
            pt_scene::VolumeDesc::Grid(g) => g.grid.values.iter().any(|&x| x > 0.0),
        };
    let emission = m
        .emission
        .as_ref()
        .map(|e| volume(e, Role::Emission))
        .transpose()?;
    let phase = phase_of(&m.phase).map_err(err)?;
    media.push((
        m.clone(),
        Medium {
            loc: m.loc.clone(),
            sigma_t: constant_spectrum(&m.sigma_t, Role::Unbounded, mode),
            albedo,
            phase,
            sample_emitters: m.sample_emitters,
            scatters,
            density,
            emission,
        },
    ));
    Ok((media.len() - 1) as u32)
}

/// Adds a shape's primitives to the BVH list; returns the geometry an emitter on it samples
/// and its area.
/// The instancing of a scene under construction, with each instance's world box.
struct BuiltInstancing {
    scene: Instancing,
    /// World boxes of the instances, in the order of `desc.instances`.
    instances: Vec<BuiltInstance>,
}

struct BuiltInstance {
    bounds: Aabb,
}

/// The scene's shape groups (one BVH each, in group space; their shapes appended to `shapes`
/// after the scene's own) and its instances (a top-level tree over their world boxes); `None`
/// when the scene has no instances. Groups no instance uses are built too (validated) but not
/// kept apart from that.
fn instancing(
    desc: &SceneDesc,
    materials: &[SurfaceMaterial],
    shapes: &mut Vec<ShapeData>,
    stats: &mut SceneStats,
    bvh: BvhKind,
    media: &mut Vec<(pt_scene::MediumDesc, Medium)>,
    mode: ColorMode,
) -> Result<Option<BuiltInstancing>, BuildError> {
    let mut groups = Vec::with_capacity(desc.groups.len());
    let mut group_boxes = Vec::with_capacity(desc.groups.len());
    for (gi, group) in desc.groups.iter().enumerate() {
        let (mut prims, mut refs) = (Vec::new(), Vec::new());
        for shape in &group.shapes {
            if shape.bsdf >= materials.len() {
                return Err(BuildError {
                    loc: shape.loc.clone(),
                    message: format!("BSDF index {} out of range", shape.bsdf),
                });
            }
            let si = shapes.len() as u32;
            let mut data = ShapeData::new(shape.bsdf as u32, Some(gi as u32));
            geometry(shape, si, false, &mut prims, &mut refs, stats, &mut data)?;
            // A group shape's media are those of every instance of it (the media themselves
            // stay in world space, as Mitsuba's do).
            if let Some(m) = &shape.interior {
                data.interior = Some(add_medium(media, m, mode)?);
            }
            if let Some(m) = &shape.exterior {
                data.exterior = Some(add_medium(media, m, mode)?);
            }
            shapes.push(data);
        }
        let bounds = prims
            .iter()
            .map(Primitive::aabb)
            .fold(Aabb::empty(), |a, b| a.union(&b));
        let accel = Accel::build(prims, bvh);
        let prim_refs = crate::accel::gathered(refs, &accel.original_index);
        groups.push(Group { accel, prim_refs });
        group_boxes.push(bounds);
    }
    if desc.instances.is_empty() {
        return Ok(None);
    }
    let mut list = Vec::with_capacity(desc.instances.len());
    let mut built = Vec::with_capacity(desc.instances.len());
    for inst in &desc.instances {
        let to_world = Affine3A::from_mat4(inst.to_world);
        let to_local = to_world.inverse();
        let normal_to_world = Mat3::from(to_local.matrix3).transpose();
        if !(to_local.is_finite() && normal_to_world.is_finite()) {
            return Err(BuildError {
                loc: inst.loc.clone(),
                message: "the instance's to_world cannot be inverted".into(),
            });
        }
        let b = group_boxes[inst.group];
        let bounds = if b.min.cmple(b.max).all() {
            (0..8).fold(Aabb::empty(), |acc, k| {
                let corner = Vec3A::new(
                    if k & 1 == 0 { b.min.x } else { b.max.x },
                    if k & 2 == 0 { b.min.y } else { b.max.y },
                    if k & 4 == 0 { b.min.z } else { b.max.z },
                );
                acc.union(&Aabb::from_point(to_world.transform_point3a(corner)))
            })
        } else {
            b
        };
        list.push(Instance {
            group: inst.group as u32,
            to_world,
            to_local,
            normal_to_world,
        });
        built.push(BuiltInstance { bounds });
    }
    let boxes: Vec<Aabb> = built.iter().map(|b| b.bounds).collect();
    let top = TopLevel::build(&boxes);
    // Into the tree's slot order.
    let mut instances: Vec<Option<Instance>> = list.into_iter().map(Some).collect();
    let instances = top
        .order
        .iter()
        .map(|&i| instances[i as usize].take().expect("each instance once"))
        .collect();
    Ok(Some(BuiltInstancing {
        scene: Instancing {
            groups,
            instances,
            top,
        },
        instances: built,
    }))
}

/// A shape's primitives (added to `prims` and `refs`) and, for shapes that are `sampled` by
/// area (emitters, the irradiancemeter's shape) or analytic, its area-sampling form and area.
fn geometry(
    shape: &ShapeDesc,
    si: u32,
    sampled: bool,
    prims: &mut Vec<Primitive>,
    refs: &mut Vec<PrimRef>,
    stats: &mut SceneStats,
    data: &mut ShapeData,
) -> Result<Option<(LightShape, f32)>, BuildError> {
    Ok(match &shape.geometry {
        Geometry::Mesh(mesh) => mesh_geometry(shape, mesh, si, sampled, prims, refs, stats)?,
        Geometry::Disk(d) => {
            prims.push(primitive_of_geometry(
                &shape.geometry,
                PrimRef::single(si, 0),
            ));
            refs.push(PrimRef::single(si, 0));
            stats.disks += 1;
            data.frame = Some(Mat3::from_cols(d.axes[0], d.axes[1], d.normal));
            Some((LightShape::Disk(*d), d.area()))
        }
        &Geometry::Sphere {
            center,
            radius,
            flip_normals,
            frame,
        } => {
            if !(radius > 0.0 && radius.is_finite() && center.is_finite()) {
                return Err(BuildError {
                    loc: shape.loc.clone(),
                    message: format!("sphere radius must be positive and finite, got {radius}"),
                });
            }
            prims.push(Primitive::Sphere {
                center: center.into(),
                radius,
                flip: flip_normals,
            });
            refs.push(PrimRef::single(si, 0));
            stats.spheres += 1;
            data.frame = Some(frame);
            Some((
                LightShape::Sphere {
                    center,
                    radius,
                    flip: flip_normals,
                    frame,
                },
                4.0 * std::f32::consts::PI * radius * radius,
            ))
        }
        &Geometry::Cylinder {
            p0,
            frame,
            radius,
            length,
            flip_normals,
        } => {
            if !(radius > 0.0 && radius.is_finite() && length > 0.0 && length.is_finite()) {
                return Err(BuildError {
                    loc: shape.loc.clone(),
                    message: format!(
                        "cylinder radius and length must be positive and finite, got {radius} and {length}"
                    ),
                });
            }
            prims.push(primitive_of_geometry(
                &shape.geometry,
                PrimRef::single(si, 0),
            ));
            refs.push(PrimRef::single(si, 0));
            stats.cylinders += 1;
            data.frame = Some(frame);
            Some((
                LightShape::Cylinder {
                    p0,
                    frame,
                    radius,
                    length,
                    flip: flip_normals,
                },
                std::f32::consts::TAU * radius * length,
            ))
        }
        Geometry::SdfGrid(g) => {
            // One primitive per voxel the surface passes through, referenced by the grid
            // index of its lowest corner. The loader refuses emitters on it.
            let [nx, ny, _] = g.resolution;
            for [x, y, z] in g.occupied_voxels() {
                let r = PrimRef::single(si, (z * ny + y) * nx + x);
                prims.push(primitive_of_geometry(&shape.geometry, r));
                refs.push(r);
                stats.sdf_voxels += 1;
            }
            data.sdf = Some(g.clone());
            None
        }
        Geometry::Curves(c) => {
            curve_primitives(c, si, prims, refs, stats, &shape.geometry);
            data.curve_segments = c.segments.len() as u32;
            None
        }
    })
}

/// A mesh's triangles (added to `prims` and `refs`) and, when it is `sampled` by area, its
/// area-sampling form (one parallelogram for a rectangle light) and area.
fn mesh_geometry(
    shape: &ShapeDesc,
    mesh: &pt_scene::TriangleMesh,
    si: u32,
    sampled: bool,
    prims: &mut Vec<Primitive>,
    refs: &mut Vec<PrimRef>,
    stats: &mut SceneStats,
) -> Result<Option<(LightShape, f32)>, BuildError> {
    let tris = add_mesh(mesh, si, sampled, prims, refs, stats, &shape.loc)?;
    if let Some(ts) = &mesh.tangents {
        if ts.len() != mesh.positions.len() {
            return Err(BuildError {
                loc: shape.loc.clone(),
                message: format!(
                    "mesh has {} tangents for {} vertices",
                    ts.len(),
                    mesh.positions.len()
                ),
            });
        }
    }
    // An emitter that is one parallelogram (a rectangle light) samples it as one.
    let single = match (prims.last(), refs.last(), &tris) {
        (Some(&prim), Some(r), Some((t, _))) if r.shape == si && t.len() == 2 => {
            parallelogram_light(mesh, prim, *r)
        }
        _ => None,
    };
    Ok(single.or_else(|| {
        tris.map(|(tris, areas)| {
            (
                LightShape::Mesh {
                    distr: Distribution1D::new(&areas).expect("non-empty"),
                    tris,
                },
                areas.iter().sum::<f32>(),
            )
        })
    }))
}

/// The primitives of curves `c` (shape `si`, whose geometry `shape_geometry` they are made
/// from): one per segment, B-spline segments in pieces; added to `prims` and `refs`.
fn curve_primitives(
    c: &pt_scene::Curves,
    si: u32,
    prims: &mut Vec<Primitive>,
    refs: &mut Vec<PrimRef>,
    stats: &mut SceneStats,
    shape_geometry: &Geometry,
) {
    // One primitive per segment, referenced by its index. The loader refuses
    // emitters on curves.
    for i in 0..c.segments.len() as u32 {
        // B-spline segments in pieces short enough for tight boxes.
        let pieces = match c.basis {
            pt_scene::CurveBasis::Linear => vec![None],
            pt_scene::CurveBasis::BSpline => {
                let cp = c.segment(i as usize);
                crate::curve::Piece::split(std::array::from_fn(|k| cp[k]))
                    .map(|p| Some(p.code()))
                    .collect()
            }
        };
        for part in pieces {
            let r = PrimRef {
                shape: si,
                local: i,
                part,
            };
            prims.push(primitive_of_geometry(shape_geometry, r));
            refs.push(r);
        }
    }
    stats.curve_segments += c.segments.len();
}

/// A mesh's shading data: normals, texture coordinates (only where something reads them),
/// tangents and mesh attributes; every attribute the material reads must exist.
/// `keep_uvs` keeps texture coordinates that nothing in the scene reads (for AOVs).
fn shading_data(
    data: &mut ShapeData,
    mesh: &pt_scene::TriangleMesh,
    material: &SurfaceMaterial,
    light: Option<&Light>,
    textures: &TextureBuilder,
    mode: ColorMode,
    keep_uvs: bool,
) -> Result<(), String> {
    data.normals = mesh.normals.clone();
    let textured_light = matches!(light, Some(Light::Area(a)) if !a.radiance.is_constant());
    if material.uses_uv() || textured_light || keep_uvs {
        data.uvs = mesh.uvs.clone();
    }
    data.tangents = mesh.tangents.clone();
    if !textures.slots.names.is_empty() {
        data.attributes = textures.slots.of_mesh(&mesh.attributes, mode);
        for (slot, a) in data.attributes.iter().enumerate() {
            let name = &textures.slots.names[slot];
            if a.is_none() && material.reads_attribute(slot as u32) {
                return Err(format!(
                    "the material reads mesh attribute '{name}', which this mesh does not have (it has: {})",
                    if mesh.attributes.is_empty() {
                        "none".to_string()
                    } else {
                        mesh.attributes.iter().map(|a| a.name.as_str()).collect::<Vec<_>>().join(", ")
                    }
                ));
            }
        }
        if data.attributes.iter().all(Option::is_none) {
            data.attributes.clear();
        }
    }
    // Indices serve only to interpolate normals, uvs, tangents and attributes: without them,
    // no copy.
    if data.normals.is_some()
        || data.uvs.is_some()
        || data.tangents.is_some()
        || !data.attributes.is_empty()
    {
        data.indices = mesh.indices.clone();
    }
    Ok(())
}

/// An area emitter's radiance texture in the scene's mode. With display primaries (pt
/// extension), RGB mode shows the image's colours through the display's matrix
/// ([`DisplayPrimaries::to_srgb_matrix`]), and spectral mode drives the primaries with it.
fn emission_texture(
    em: &AreaEmitterDesc,
    textures: &mut TextureBuilder,
) -> Result<Texture, BuildError> {
    let err = |message: String| BuildError {
        loc: em.loc.clone(),
        message,
    };
    let Some(p) = &em.primaries else {
        let t = textures
            .build(&em.radiance, Role::Emission)
            .map_err(|m| err(format!("radiance: {m}")))?;
        // (RGB projections of spectra may leave the gamut: check the values as given.)
        let negative = em
            .radiance
            .spectra()
            .into_iter()
            .any(|s| s.values().iter().any(|x| !(x.is_finite() && *x >= 0.0)));
        if negative {
            return Err(err("radiance must be finite and non-negative".into()));
        }
        return Ok(t);
    };
    let TextureDesc::Bitmap(b) = &em.radiance else {
        return Err(err("display primaries need a radiance bitmap".into()));
    };
    let image = textures.rgb_bitmap(b).map_err(err)?;
    let spectra = [0, 1, 2].map(|i| spectrum_for_role(&p[i], Role::Unbounded));
    let display =
        DisplayPrimaries::new(spectra).map_err(|m| err(format!("display primaries: {m}")))?;
    Ok(match textures.mode() {
        ColorMode::Spectral => Texture::Primaries(Arc::new((image, display))),
        // The colours the display shows, in linear sRGB: exact for the film by linearity;
        // saturated primaries give components below 0 (outside the sRGB gamut), kept so.
        ColorMode::Rgb => {
            let m = display.to_srgb_matrix();
            Texture::Bitmap(Arc::new(image.map_texels(|t| {
                std::array::from_fn(|r| m[r][0] * t[0] + m[r][1] * t[1] + m[r][2] * t[2])
            })))
        }
    })
}

/// Selection weights of [`LightSelection::Power`]: each distant light (environment, sun,
/// directional) gets the share uniform selection gives it, 1 / (number of lights), and the
/// lights at a finite distance split the rest in proportion to their power. A distant light's
/// power is what crosses the whole scene's bounding disk, most of which never reaches a point
/// inside a room or under a lamp: weighed by power it took 83% of the samples from the area
/// light of `scenes/texture-bitmap.xml` (5.5x the noise of uniform selection); given the share
/// of all finite lights together (pbrt-v4's BVH light sampler's choice) it took half of the
/// staircase's samples for a dim sky (1.2x the noise of uniform selection). With finite lights
/// of equal power this is Mitsuba's uniform selection.
fn power_selection(lights: &[Light], scene_radius: f32) -> Vec<f32> {
    let distant = |l: &Light| l.is_infinite() || matches!(l, Light::Directional { .. });
    let n_distant = lights.iter().filter(|l| distant(l)).count();
    let finite_power: f32 = lights
        .iter()
        .filter(|l| !distant(l))
        .map(|l| l.power(scene_radius))
        .sum();
    if n_distant == 0 || n_distant == lights.len() || !(finite_power > 0.0) {
        return lights.iter().map(|l| l.power(scene_radius)).collect();
    }
    let n = lights.len() as f32;
    let finite_share = (n - n_distant as f32) / n;
    lights
        .iter()
        .map(|l| {
            if distant(l) {
                1.0 / n
            } else {
                finite_share * l.power(scene_radius) / finite_power
            }
        })
        .collect()
}

/// The render-side phase function of `desc`: a `blendphase` (nested ones too) becomes the
/// mixture of its lobes (isotropic, Henyey-Greenstein, Rayleigh, tabulated).
fn phase_of(desc: &pt_scene::PhaseDesc) -> Result<Phase, String> {
    use pt_scene::PhaseDesc;
    /// Appends the lobes of `desc` with their shares of the whole (`share` for `desc`).
    fn lobes(desc: &PhaseDesc, share: f32, out: &mut Vec<(f32, Lobe)>) -> Result<(), String> {
        let lobe = match desc {
            PhaseDesc::Blend {
                weight,
                first,
                second,
            } => {
                lobes(first, share * (1.0 - weight), out)?;
                return lobes(second, share * weight, out);
            }
            PhaseDesc::Isotropic => Lobe::Isotropic,
            &PhaseDesc::HenyeyGreenstein { g } => Lobe::HenyeyGreenstein(g),
            PhaseDesc::Rayleigh => Lobe::Rayleigh,
            PhaseDesc::Tabulated(values) => {
                Lobe::Tabulated(Arc::new(TabulatedPhase::new(values).ok_or_else(|| {
                    "a tabphase needs at least two finite values >= 0, not all 0".to_string()
                })?))
            }
        };
        out.push((share, lobe));
        Ok(())
    }
    let mut all = Vec::new();
    lobes(desc, 1.0, &mut all)?;
    Ok(match desc {
        PhaseDesc::Blend { .. } => {
            all.retain(|&(w, _)| w > 0.0);
            let n = all.len();
            Phase::mixture(all).ok_or_else(|| {
                format!(
                    "a blendphase of {n} phase functions (after nested blends) is more than the {} supported",
                    crate::medium::MAX_PHASE_LOBES
                )
            })?
        }
        // One phase function: one lobe of share 1.
        _ => Phase::Single(all.pop().map_or(Lobe::Isotropic, |(_, l)| l)),
    })
}

#[cfg(test)]
mod phase_tests {
    use super::*;
    use pt_scene::PhaseDesc;

    /// A blend of a Rayleigh phase (share 1 - 0.25) and a blend of two lobes (0.25, split
    /// evenly) flattens to the three lobes with shares 0.75, 0.125, 0.125 (the second
    /// function gets `weight`, as in Mitsuba); five lobes are refused.
    #[test]
    fn nested_blends_flatten_to_weighted_lobes() {
        let hg = |g| Box::new(PhaseDesc::HenyeyGreenstein { g });
        let blend = |weight, first, second| PhaseDesc::Blend {
            weight,
            first,
            second,
        };
        let desc = blend(
            0.25,
            Box::new(PhaseDesc::Rayleigh),
            Box::new(blend(0.5, hg(0.5), hg(-0.5))),
        );
        assert_eq!(
            phase_of(&desc).unwrap(),
            Phase::Mixture {
                weights: [0.75, 0.125, 0.125, 0.0],
                lobes: [
                    Lobe::Rayleigh,
                    Lobe::HenyeyGreenstein(0.5),
                    Lobe::HenyeyGreenstein(-0.5),
                    Lobe::Isotropic
                ],
                count: 3,
            }
        );
        let four = blend(0.5, Box::new(desc.clone()), hg(0.1));
        assert!(phase_of(&four).is_ok());
        let five = blend(0.5, Box::new(four), hg(0.2));
        assert!(phase_of(&five).unwrap_err().contains("more than the 4"));
    }
}
