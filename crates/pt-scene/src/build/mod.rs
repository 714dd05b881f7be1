//! Turning the preprocessed element tree into the IR: one function per plugin family, each
//! reading its parameters with Mitsuba 3's names and defaults and rejecting everything else.

mod bsdf;
mod emitter;
mod integrator;
mod materials;
mod sensor;
mod shape;
mod sunsky;
mod texture;

pub(crate) use bsdf::bsdf_from_properties;
use integrator::default_integrator;
use sensor::{default_camera, DEFAULT_FILTER};
use texture::Nested;

use crate::error::{Result, SceneError};
use crate::ir::*;
use crate::obj::{self, ObjOptions};
use crate::props::{Child, ObjectView};
use crate::shapes;
use crate::transform::is_affine;
use crate::xml::{resolve_file, Document, Element};
use crate::{ply, serialized};
use glam::{Mat3, Mat4, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Plugins per object tag: (tag, supported, known to Mitsuba 3 but not implemented here).
#[rustfmt::skip]
const PLUGINS: &[(&str, &[&str], &[&str])] = &[
    ("sensor", &["perspective", "thinlens", "orthographic", "radiancemeter", "irradiancemeter", "distant", "batch"], &[]),
    ("film", &["hdrfilm"], &["specfilm"]),
    ("sampler", &["independent", "stratified", "multijitter", "orthogonal", "ldsampler"], &[]),
    ("rfilter", &["box", "tent", "gaussian", "mitchell", "catmullrom", "lanczos"], &[]),
    ("integrator", &["path", "volpath", "volpathmis", "direct", "moment", "aov", "radiosity", "ptracer", "sppm", "prb", "prb_basic", "prb_projective", "prbvolpath", "depth", "direct_projective"], &[
        "stokes",
    ]),
    ("shape", &["obj", "ply", "serialized", "gltf", "rectangle", "cube", "sphere", "disk", "cylinder", "sdfgrid", "linearcurve", "bsplinecurve", "shapegroup", "instance"], &[
        "ellipsoids", "ellipsoidsmesh",
    ]),
    ("bsdf", &["diffuse", "twosided", "mask", "normalmap", "blendbsdf", "orennayar", "minnaert", "dielectric", "thindielectric", "roughdielectric", "conductor", "roughconductor", "thinfilm", "roughthinfilm", "plastic", "roughplastic", "null", "fluorescent", "phosphorescent", "bumpmap", "principled", "principledthin", "pplastic", "polarizer", "retarder", "circular", "hair"], &[
        "measured",
    ]),
    ("emitter", &["area", "point", "spot", "directional", "sun", "sunsky", "constant", "envmap", "projector", "goniometric"], &[
        "directionalarea",
    ]),
    ("texture", &["bitmap", "checkerboard", "mesh_attribute", "rawconstant", "d65"], &["volume"]),
    ("medium", &["homogeneous", "heterogeneous"], &[]),
    ("phase", &["isotropic", "hg", "rayleigh", "tabphase", "blendphase"], &["sggx"]),
    ("volume", &["constvolume", "gridvolume"], &[]),
];

/// The error for a plugin this loader does not build: "unsupported" for Mitsuba plugins not
/// implemented yet, "unknown" for names Mitsuba does not have either (probably typos).
fn plugin_error(el: &Element) -> SceneError {
    let tag = el.tag.as_str();
    let plugin = el.attr("type").unwrap_or_default();
    let (supported, known) = PLUGINS
        .iter()
        .find(|(t, _, _)| *t == tag)
        .map_or((&[][..], &[][..]), |(_, s, k)| (*s, *k));
    let list = if supported.is_empty() {
        "none yet".to_string()
    } else {
        supported.join(", ")
    };
    let message = if supported.contains(&plugin) {
        format!("{tag} \"{plugin}\" is not yet supported in this position (not yet implemented; it is read only where the docs list it)")
    } else if known.contains(&plugin) {
        format!("unsupported plugin {tag} \"{plugin}\" (not yet implemented; supported: {list})")
    } else {
        format!("unknown {tag} plugin \"{plugin}\" (supported: {list})")
    };
    SceneError::at(&el.loc, message)
}

/// The error for an object nested where it has no meaning. Textures, media and the like are
/// reported as unsupported plugins: they would be meaningful, just not implemented yet.
fn misplaced(
    child: &Child<'_>,
    target: &Element,
    parent: &ObjectView<'_>,
    expected: &str,
) -> SceneError {
    if matches!(
        target.tag.as_str(),
        "texture" | "medium" | "phase" | "volume"
    ) {
        return plugin_error(target);
    }
    SceneError::at(
        &child.written().loc,
        format!(
            "<{}> cannot be nested in {} (expected {expected})",
            target.tag,
            parent.what()
        ),
    )
}

/// Builds a [`SceneDesc`] from a preprocessed document.
pub(crate) fn build(doc: &Document, source: &Path, base_dir: &Path) -> Result<SceneDesc> {
    let mut ids = HashMap::new();
    let mut aliases = Vec::new();
    collect_ids(&doc.root, &mut ids, &mut aliases)?;
    for alias in aliases {
        add_alias(alias, &mut ids)?;
    }
    Builder::new(ids, &doc.search_paths, base_dir).scene(&doc.root, source)
}

/// Mitsuba's `<alias id="A" as="B"/>`: `B` names the object `A` names (the same object, built
/// once). `A` must exist (an object's id or an earlier alias) and `B` must be new.
fn add_alias<'e>(alias: &'e Element, ids: &mut HashMap<&'e str, &'e Element>) -> Result<()> {
    alias.check_attrs(&["id", "as"], &["id", "as"])?;
    if let Some(c) = alias.children.first() {
        return Err(SceneError::at(&c.loc, "<alias> cannot contain elements"));
    }
    let (from, to) = (
        alias.attr("id").unwrap_or_default(),
        alias.attr("as").unwrap_or_default(),
    );
    let target = *ids
        .get(from)
        .ok_or_else(|| SceneError::at(&alias.loc, format!("<alias>: unknown id \"{from}\"")))?;
    if to.is_empty() {
        return Err(SceneError::at(&alias.loc, "<alias>: empty 'as'"));
    }
    match ids.insert(to, target) {
        Some(first) => Err(duplicate_id(alias, to, first)),
        None => Ok(()),
    }
}

/// The error for `el` giving the name `id` that `first` already has.
fn duplicate_id(el: &Element, id: &str, first: &Element) -> SceneError {
    let l = &first.loc;
    SceneError::at(
        &el.loc,
        format!(
            "duplicate id \"{id}\" (first used at {}:{}:{})",
            l.file.display(),
            l.line,
            l.col
        ),
    )
}

/// Registers every object that has an `id`; ids are global to the scene, like Mitsuba's.
/// `<alias>` elements are gathered in document order into `aliases`.
fn collect_ids<'e>(
    el: &'e Element,
    ids: &mut HashMap<&'e str, &'e Element>,
    aliases: &mut Vec<&'e Element>,
) -> Result<()> {
    for child in &el.children {
        if child.tag == "alias" {
            aliases.push(child);
        }
        if child.is_object() {
            if let Some(id) = child.attr("id") {
                if id.is_empty() {
                    return Err(SceneError::at(&child.loc, "empty 'id'"));
                }
                if let Some(first) = ids.insert(id, child) {
                    return Err(duplicate_id(child, id, first));
                }
            }
        }
        collect_ids(child, ids, aliases)?;
    }
    Ok(())
}

struct Builder<'e> {
    ids: HashMap<&'e str, &'e Element>,
    search_paths: &'e [PathBuf],
    base_dir: &'e Path,
    /// BSDFs used by shapes; `ShapeDesc::bsdf` indexes this.
    bsdfs: Vec<BsdfDesc>,
    /// Index in `bsdfs` of each shared (id-carrying) BSDF already used by a shape.
    bsdf_index: HashMap<String, usize>,
    /// Built BSDFs by id, so that each is built (and validated) once.
    bsdf_memo: HashMap<String, BsdfDesc>,
    /// Built textures by id, so that each is built once and shared images stay shared.
    texture_memo: HashMap<String, TextureDesc>,
    /// Built media by id, so that each grid is read once.
    medium_memo: HashMap<String, MediumDesc>,
    /// Ids of BSDFs and textures being built, to report reference cycles instead of
    /// recursing forever.
    visiting: Vec<String>,
    /// Indices of the implicit diffuse BSDFs shared by all shapes without one: [0] for shapes
    /// without an emitter (reflectance 0.5), [1] for emitting shapes (reflectance 0).
    default_bsdf: [Option<usize>; 2],
    /// Shape groups built so far (`SceneDesc::groups`).
    groups: Vec<ShapeGroupDesc>,
    /// Index in `groups` of each group by its element's address, so that each is built once
    /// however many instances name it.
    group_index: HashMap<*const Element, usize>,
    /// The sensor nested in the shape built last (an `irradiancemeter`), for the scene to
    /// take with the shape's number.
    shape_sensor: Option<(CameraDesc, FilmDesc, SamplerDesc)>,
    /// The shape a `distant` sensor aims at ([`SceneDesc::sensor_target`]).
    sensor_target: Option<ShapeDesc>,
    /// The sensors of a `batch` sensor ([`SceneDesc::batch`]).
    batch: Vec<CameraDesc>,
}

impl<'e> Builder<'e> {
    /// A builder that resolves `<ref>`s through `ids` and files through `search_paths`, then
    /// `base_dir`, with nothing built yet.
    pub(super) fn new(
        ids: HashMap<&'e str, &'e Element>,
        search_paths: &'e [PathBuf],
        base_dir: &'e Path,
    ) -> Self {
        Builder {
            ids,
            search_paths,
            base_dir,
            bsdfs: Vec::new(),
            bsdf_index: HashMap::new(),
            bsdf_memo: HashMap::new(),
            texture_memo: HashMap::new(),
            medium_memo: HashMap::new(),
            visiting: Vec::new(),
            default_bsdf: [None, None],
            groups: Vec::new(),
            group_index: HashMap::new(),
            shape_sensor: None,
            sensor_target: None,
            batch: Vec::new(),
        }
    }

    /// The object a nested child stands for (following `<ref>`).
    pub(super) fn resolve(&self, child: &Child<'e>) -> Result<&'e Element> {
        match *child {
            Child::Object(el) => Ok(el),
            Child::Ref(r) => {
                let id = r.attr("id").unwrap_or_default();
                self.ids
                    .get(id)
                    .copied()
                    .ok_or_else(|| SceneError::at(&r.loc, format!("unknown id \"{id}\"")))
            }
        }
    }

    pub(super) fn scene(&mut self, root: &'e Element, source: &Path) -> Result<SceneDesc> {
        let view = ObjectView::parse_scene(root)?;
        view.finish()?;
        #[allow(clippy::type_complexity)]
        let mut sensor: Option<(CameraDesc, FilmDesc, SamplerDesc, Option<MediumDesc>)> = None;
        let mut integrator = None;
        let mut shapes = Vec::new();
        let mut lights = Vec::new();
        let mut instances = Vec::new();
        for child in &view.children {
            let Child::Object(el) = *child else {
                return Err(SceneError::at(
                    &child.written().loc,
                    "a <ref> directly inside <scene> is not supported",
                ));
            };
            match el.tag.as_str() {
                "sensor" if sensor.is_some() => {
                    return Err(SceneError::at(&el.loc, "only one <sensor> is supported"))
                }
                "sensor" => sensor = Some(self.sensor(el, false)?),
                "integrator" if integrator.is_some() => {
                    return Err(SceneError::at(
                        &el.loc,
                        "only one <integrator> can be specified",
                    ))
                }
                "integrator" => integrator = Some(self.integrator(el)?),
                // Built (and validated) where it is written, used by the instances naming it.
                "shape" if el.attr("type") == Some("shapegroup") => drop(self.shape_group(el)?),
                "shape" if el.attr("type") == Some("instance") => {
                    instances.push(self.instance(el)?)
                }
                "shape" => {
                    shapes.push(self.shape(el)?);
                    if let Some((camera, film, sampler)) = self.shape_sensor.take() {
                        if sensor.is_some() {
                            return Err(SceneError::at(
                                &camera.loc,
                                "only one <sensor> is supported",
                            ));
                        }
                        let projection = Projection::Irradiancemeter {
                            shape: shapes.len() - 1,
                        };
                        sensor = Some((
                            CameraDesc {
                                projection,
                                ..camera
                            },
                            film,
                            sampler,
                            None,
                        ));
                    }
                }
                // Validated now; it enters `bsdfs` when a shape uses it.
                "bsdf" => drop(self.bsdf_desc(el)?),
                // Validated now; shapes and the sensor use it through <ref id="..."/>.
                "medium" => drop(self.medium(el)?),
                // Validated now; materials use it through <ref name="..." id="..."/>.
                "texture" => drop(self.texture(el)?),
                "emitter" if el.attr("type") == Some("area") => {
                    return Err(self.top_level_emitter(el))
                }
                "emitter" => lights.push(self.light(el)?),
                "film" | "sampler" => {
                    return Err(SceneError::at(
                        &el.loc,
                        format!("<{}> must be nested in a <sensor>", el.tag),
                    ))
                }
                "rfilter" => {
                    return Err(SceneError::at(
                        &el.loc,
                        "<rfilter> must be nested in a <film>",
                    ))
                }
                _ => return Err(plugin_error(el)),
            }
        }
        let (camera, film, sampler, camera_medium) = match sensor {
            Some(s) => s,
            None => (
                default_camera(root, &shapes),
                default_film(),
                default_sampler(),
                None,
            ),
        };
        Ok(SceneDesc {
            source: source.to_path_buf(),
            camera,
            camera_medium,
            film,
            sampler,
            integrator: integrator.unwrap_or_else(default_integrator),
            shapes,
            bsdfs: std::mem::take(&mut self.bsdfs),
            lights,
            groups: std::mem::take(&mut self.groups),
            instances,
            sensor_target: self.sensor_target.take(),
            batch: std::mem::take(&mut self.batch),
        })
    }
}

/// Mitsuba's film when a scene has no sensor: 768 x 576 pixels, its default Gaussian filter.
pub(super) fn default_film() -> FilmDesc {
    FilmDesc::new(768, 576, DEFAULT_FILTER)
}

pub(super) fn default_sampler() -> SamplerDesc {
    SamplerDesc {
        sample_count: 4,
        seed: 0,
        kind: SamplerKind::Independent,
    }
}

// ---------------------------------------------------------------------------------------------
// Parameter helpers

/// An integer parameter with a default, checked to lie in `min..=max`.
pub(super) fn int_in(
    v: &ObjectView<'_>,
    name: &str,
    default: i64,
    min: i64,
    max: i64,
) -> Result<i64> {
    let value = v.integer(name)?.unwrap_or(default);
    if value < min || value > max {
        let range = if max >= i32::MAX as i64 {
            format!("at least {min}")
        } else {
            format!("between {min} and {max}")
        };
        return Err(v.prop_error(name, format!("'{name}' must be {range}, got {value}")));
    }
    Ok(value)
}

/// A float parameter with a default, checked to be positive.
pub(super) fn positive(v: &ObjectView<'_>, name: &str, default: f32) -> Result<f32> {
    let value = v.float(name)?.unwrap_or(default);
    if value > 0.0 {
        Ok(value)
    } else {
        Err(v.prop_error(name, format!("'{name}' must be positive, got {value}")))
    }
}

/// A float parameter that must be finite (any sign), with a default.
pub(super) fn finite(v: &ObjectView<'_>, name: &str, default: f32) -> Result<f32> {
    let value = v.float(name)?.unwrap_or(default);
    if value.is_finite() {
        Ok(value)
    } else {
        Err(v.prop_error(name, format!("'{name}' must be finite, got {value}")))
    }
}

/// Accepts a string parameter only if it is one of `allowed` (case-insensitive).
pub(super) fn one_of(v: &ObjectView<'_>, name: &str, allowed: &[&str]) -> Result<()> {
    match v.string(name)? {
        Some(s) if !allowed.contains(&s.to_ascii_lowercase().as_str()) => Err(v.prop_error(
            name,
            format!(
                "'{name}' must be one of {}, not \"{s}\"",
                allowed.join(", ")
            ),
        )),
        _ => Ok(()),
    }
}

/// Mitsuba's crop window: `crop_offset_x/y` (0) and `crop_width/height` (the film's width and
/// height), and the size of the image it makes; `None` when it selects the whole film. The
/// window must lie inside the film.
pub(super) fn crop_window(
    v: &ObjectView<'_>,
    width: u32,
    height: u32,
) -> Result<(Option<CropWindow>, [u32; 2])> {
    let mut offset = [0u32; 2];
    let mut size = [width, height];
    for (axis, (o_name, s_name, full)) in [
        ("crop_offset_x", "crop_width", width),
        ("crop_offset_y", "crop_height", height),
    ]
    .into_iter()
    .enumerate()
    {
        let o = int_in(v, o_name, 0, 0, i64::from(full) - 1)? as u32;
        let s = int_in(v, s_name, i64::from(full), 1, i64::from(full))? as u32;
        if o + s > full {
            // As Mitsuba's film: the size defaults to the whole film, even with an offset.
            return Err(v.prop_error(
                s_name,
                format!(
                    "the crop window reaches past the film: {o_name} {o} + {s_name} {s} > {full}"
                ),
            ));
        }
        (offset[axis], size[axis]) = (o, s);
    }
    let crop = (size != [width, height]).then_some(CropWindow {
        offset,
        film_size: [width, height],
    });
    Ok((crop, size))
}

/// Errors if a plugin without nested objects has one.
pub(super) fn no_children(v: &ObjectView<'_>) -> Result<()> {
    match v.children.first() {
        Some(child) => Err(SceneError::at(
            &child.written().loc,
            format!("<{}> cannot be nested in {}", child.written().tag, v.what()),
        )),
        None => Ok(()),
    }
}
