//! Turning the preprocessed element tree into the IR: one function per plugin family, each
//! reading its parameters with Mitsuba 3's names and defaults and rejecting everything else.

use crate::error::{Result, SceneError};
use crate::ir::*;
use crate::obj::{self, ObjOptions};
use crate::props::{Child, ObjectView};
use crate::shapes;
use crate::transform::is_affine;
use crate::xml::{resolve_file, Document, Element};
use glam::{Mat3, Mat4, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Plugins per object tag: (tag, supported, known to Mitsuba 3 but not implemented here).
#[rustfmt::skip]
const PLUGINS: &[(&str, &[&str], &[&str])] = &[
    ("sensor", &["perspective"], &[
        "orthographic", "thinlens", "radiancemeter", "irradiancemeter", "distant", "batch",
    ]),
    ("film", &["hdrfilm"], &["specfilm"]),
    ("sampler", &["independent", "stratified"], &["multijitter", "orthogonal", "ldsampler"]),
    ("rfilter", &["box", "tent", "gaussian"], &["mitchell", "catmullrom", "lanczos"]),
    ("integrator", &["path", "volpath", "direct", "moment", "radiosity"], &[
        "volpathmis", "aov", "prb", "prb_basic", "prb_projective", "direct_projective",
        "ptracer", "depth", "stokes", "prbvolpath",
    ]),
    ("shape", &["obj", "gltf", "rectangle", "cube", "sphere", "disk"], &[
        "ply", "serialized", "cylinder", "shapegroup", "instance", "bsplinecurve", "linearcurve",
        "sdfgrid", "ellipsoids", "ellipsoidsmesh",
    ]),
    ("bsdf", &["diffuse", "twosided", "mask", "normalmap", "blendbsdf", "orennayar", "minnaert", "dielectric", "thindielectric", "roughdielectric", "conductor", "roughconductor", "thinfilm", "roughthinfilm", "roughplastic"], &[
        "plastic", "bumpmap", "null",
        "polarizer", "retarder", "circular", "measured", "pplastic", "principled",
        "principledthin", "hair",
    ]),
    ("emitter", &["area", "point", "spot", "directional", "sun", "constant", "envmap"], &[
        "projector", "directionalarea", "sunsky",
    ]),
    ("texture", &["bitmap", "d65"], &["checkerboard", "mesh_attribute", "volume"]),
    ("medium", &["homogeneous"], &["heterogeneous"]),
    ("phase", &[], &["isotropic", "hg", "rayleigh", "sggx", "tabphase", "blendphase"]),
    ("volume", &[], &["constvolume", "gridvolume"]),
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
    collect_ids(&doc.root, &mut ids)?;
    let mut builder = Builder {
        ids,
        search_paths: &doc.search_paths,
        base_dir,
        bsdfs: Vec::new(),
        bsdf_index: HashMap::new(),
        bsdf_memo: HashMap::new(),
        visiting: Vec::new(),
        default_bsdf: [None, None],
    };
    builder.scene(&doc.root, source)
}

/// Registers every object that has an `id`; ids are global to the scene, like Mitsuba's.
fn collect_ids<'e>(el: &'e Element, ids: &mut HashMap<&'e str, &'e Element>) -> Result<()> {
    for child in &el.children {
        if child.is_object() {
            if let Some(id) = child.attr("id") {
                if id.is_empty() {
                    return Err(SceneError::at(&child.loc, "empty 'id'"));
                }
                if let Some(first) = ids.insert(id, child) {
                    let l = &first.loc;
                    return Err(SceneError::at(
                        &child.loc,
                        format!(
                            "duplicate id \"{id}\" (first used at {}:{}:{})",
                            l.file.display(),
                            l.line,
                            l.col
                        ),
                    ));
                }
            }
        }
        collect_ids(child, ids)?;
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
    /// Ids of BSDFs being built, to report reference cycles instead of recursing forever.
    visiting: Vec<String>,
    /// Indices of the implicit diffuse BSDFs shared by all shapes without one: [0] for shapes
    /// without an emitter (reflectance 0.5), [1] for emitting shapes (reflectance 0).
    default_bsdf: [Option<usize>; 2],
}

impl<'e> Builder<'e> {
    /// The object a nested child stands for (following `<ref>`).
    fn resolve(&self, child: &Child<'e>) -> Result<&'e Element> {
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

    // -----------------------------------------------------------------------------------------
    // Scene

    fn scene(&mut self, root: &'e Element, source: &Path) -> Result<SceneDesc> {
        let view = ObjectView::parse_scene(root)?;
        view.finish()?;
        let mut sensor: Option<(CameraDesc, FilmDesc, SamplerDesc)> = None;
        let mut integrator = None;
        let mut shapes = Vec::new();
        let mut lights = Vec::new();
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
                "sensor" => sensor = Some(self.sensor(el)?),
                "integrator" if integrator.is_some() => {
                    return Err(SceneError::at(
                        &el.loc,
                        "only one <integrator> can be specified",
                    ))
                }
                "integrator" => integrator = Some(self.integrator(el)?),
                "shape" => shapes.push(self.shape(el)?),
                // Validated now; it enters `bsdfs` when a shape uses it.
                "bsdf" => drop(self.bsdf_desc(el)?),
                // Validated now; shapes use it through <ref name="interior" id="..."/>.
                "medium" => drop(medium(el)?),
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
        let (camera, film, sampler) = match sensor {
            Some(s) => s,
            None => (
                default_camera(root, &shapes),
                default_film(),
                default_sampler(),
            ),
        };
        Ok(SceneDesc {
            source: source.to_path_buf(),
            camera,
            film,
            sampler,
            integrator: integrator.unwrap_or_else(default_integrator),
            shapes,
            bsdfs: std::mem::take(&mut self.bsdfs),
            lights,
        })
    }

    fn top_level_emitter(&self, el: &Element) -> SceneError {
        if el.attr("type") == Some("area") {
            SceneError::at(
                &el.loc,
                "an area emitter must be nested in the <shape> that emits",
            )
        } else {
            plugin_error(el)
        }
    }

    /// Emitters outside shapes: `point` (`intensity` 1, `position` or `to_world`), `spot`
    /// (`intensity` 1, `cutoff_angle` 20, `beam_width` 3/4 of the cutoff, `to_world`),
    /// `directional` (`irradiance` 1, `direction` or `to_world` +z), `sun` (project extension:
    /// `irradiance` 1, `direction`, `angular_diameter` 0.5338 degrees), `constant` (`radiance` 1),
    /// `envmap` (`filename`, `scale` 1, `to_world`).
    fn light(&mut self, el: &'e Element) -> Result<LightDesc> {
        let v = ObjectView::parse(el)?;
        let to_world = v.transform("to_world")?;
        let spectrum = |name: &str| -> Result<SpectrumDesc> {
            let s = v.spectrum(name)?.unwrap_or(SpectrumDesc::Constant(1.0));
            let vals = s.values();
            if vals.iter().any(|&x| x < 0.0) {
                return Err(v.prop_error(name, format!("{name} must not be negative")));
            }
            Ok(s)
        };
        // Direction of travel: `direction`, or the +z axis of `to_world`.
        let direction = |v: &ObjectView<'e>, to_world: Option<Mat4>| -> Result<Vec3> {
            let d = match (v.vec3("direction")?, to_world) {
                (Some(_), Some(_)) => {
                    return Err(
                        v.prop_error("direction", "give either direction or to_world, not both")
                    )
                }
                (Some(d), None) => d,
                (None, Some(m)) => m.transform_vector3(Vec3::Z),
                (None, None) => Vec3::Z,
            };
            d.try_normalize()
                .ok_or_else(|| v.prop_error("direction", "direction must not be zero"))
        };
        let kind = match v.plugin.as_str() {
            "point" => {
                let position = match (v.vec3("position")?, to_world) {
                    (Some(_), Some(_)) => {
                        return Err(
                            v.prop_error("position", "give either position or to_world, not both")
                        )
                    }
                    (Some(p), None) => p,
                    (None, Some(m)) => m.transform_point3(Vec3::ZERO),
                    (None, None) => Vec3::ZERO,
                };
                LightKind::Point {
                    position,
                    intensity: spectrum("intensity")?,
                }
            }
            "spot" => {
                let cutoff_deg = v.float("cutoff_angle")?.unwrap_or(20.0);
                if !(cutoff_deg > 0.0 && cutoff_deg <= 180.0) {
                    return Err(
                        v.prop_error("cutoff_angle", "cutoff_angle must be in (0, 180] degrees")
                    );
                }
                let beam_width_deg = v.float("beam_width")?.unwrap_or(cutoff_deg * 0.75);
                if !(beam_width_deg >= 0.0 && beam_width_deg <= cutoff_deg) {
                    return Err(v.prop_error(
                        "beam_width",
                        "beam_width must be in [0, cutoff_angle] degrees",
                    ));
                }
                LightKind::Spot {
                    to_world: to_world.unwrap_or(Mat4::IDENTITY),
                    intensity: spectrum("intensity")?,
                    cutoff_deg,
                    beam_width_deg,
                }
            }
            "directional" => LightKind::Directional {
                direction: direction(&v, to_world)?,
                irradiance: spectrum("irradiance")?,
            },
            "sun" => {
                let angular_diameter_deg = v.float("angular_diameter")?.unwrap_or(0.5338);
                if !(angular_diameter_deg > 0.0 && angular_diameter_deg < 180.0) {
                    return Err(v.prop_error(
                        "angular_diameter",
                        "angular_diameter must be in (0, 180) degrees",
                    ));
                }
                LightKind::Sun {
                    direction: direction(&v, to_world)?,
                    irradiance: spectrum("irradiance")?,
                    angular_diameter_deg,
                }
            }
            "constant" => LightKind::Constant {
                radiance: spectrum("radiance")?,
            },
            "envmap" => {
                let name = v
                    .string("filename")?
                    .ok_or_else(|| SceneError::at(&el.loc, "envmap needs a filename"))?;
                let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
                if !path.is_file() {
                    return Err(v.prop_error(
                        "filename",
                        format!(
                            "cannot open environment map '{name}' (looked for {})",
                            path.display()
                        ),
                    ));
                }
                let scale = v.float("scale")?.unwrap_or(1.0);
                if scale < 0.0 {
                    return Err(v.prop_error("scale", "scale must not be negative"));
                }
                LightKind::EnvMap {
                    filename: path,
                    to_world: to_world.unwrap_or(Mat4::IDENTITY),
                    scale,
                }
            }
            _ => return Err(plugin_error(el)),
        };
        no_children(&v)?;
        v.finish()?;
        Ok(LightDesc {
            loc: el.loc.clone(),
            kind,
        })
    }

    /// `area`: `radiance` (rgb, spectrum or float; Mitsuba's default 1), or a nested
    /// `<texture type="bitmap" name="radiance">` (`filename`, `raw` false, `filter_type`
    /// bilinear or nearest) for an image-emitting surface such as a monitor.
    ///
    /// The bitmap may be wrapped in Mitsuba's `<texture type="d65" name="radiance">` (one nested
    /// bitmap, no `color` or `scale`), which in Mitsuba's spectral variants multiplies it by the
    /// D65 illuminant and in its RGB variants changes nothing. pt multiplies every RGB emission by
    /// D65 in spectral mode anyway (DESIGN.md, Colour), so for pt the wrapper changes nothing; it
    /// makes Mitsuba 3.9.1 agree, which leaves a bare bitmap radiance without D65.
    ///
    /// Display primaries (pt extension, with a radiance texture only): three spectra
    /// `<spectrum name="primary_r" filename="lcd-r.spd"/>`, `primary_g`, `primary_b` (any
    /// spectral form: pairs, a file, blackbody, a named illuminant). In spectral mode a texel of
    /// linear RGB (r, g, b) then emits `r k_r P_r + g k_g P_g + b k_b P_b`, the weights `k`
    /// chosen so that (1, 1, 1) emits the CIE XYZ of D65 at luminance 1 (`spectral_texture.rs`
    /// in pt-render). Mitsuba has no such parameter and rejects these scenes.
    fn area_emitter(&self, el: &'e Element) -> Result<AreaEmitterDesc> {
        let v = ObjectView::parse(el)?;
        if v.plugin != "area" {
            return Err(plugin_error(el));
        }
        let mut texture = None;
        for child in &v.children {
            let t = self.resolve(child)?;
            if t.tag != "texture" || t.attr("name") != Some("radiance") || texture.is_some() {
                return Err(misplaced(child, t, &v, "one <texture name=\"radiance\">"));
            }
            texture = Some(if t.attr("type") == Some("d65") {
                self.d65_bitmap(t)?
            } else {
                self.bitmap(t)?
            });
        }
        if texture.is_some() && v.has("radiance") {
            return Err(v.prop_error(
                "radiance",
                "give either a radiance value or a radiance texture",
            ));
        }
        let radiance = v
            .spectrum("radiance")?
            .unwrap_or(SpectrumDesc::Constant(1.0));
        let names = ["primary_r", "primary_g", "primary_b"];
        let primaries = match names.map(|n| v.spectrum(n)) {
            [Ok(None), Ok(None), Ok(None)] => None,
            [Ok(Some(r)), Ok(Some(g)), Ok(Some(b))] => {
                if texture.is_none() {
                    return Err(v.prop_error("primary_r", "display primaries need a radiance texture (an image whose texels drive them)"));
                }
                for (s, n) in [&r, &g, &b].into_iter().zip(names) {
                    if !s.is_spectral() {
                        return Err(v.prop_error(n, format!("{n} must be a spectrum (wavelength:value pairs, a file, blackbody or a named illuminant), not an RGB value or a constant")));
                    }
                }
                Some(Box::new([r, g, b]))
            }
            [r, g, b] => {
                r?;
                g?;
                b?;
                let missing = names
                    .iter()
                    .zip([v.has(names[0]), v.has(names[1]), v.has(names[2])])
                    .find(|(_, h)| !h)
                    .map_or("", |(n, _)| *n);
                return Err(SceneError::at(&el.loc, format!("display primaries need all three of primary_r, primary_g, primary_b ({missing} is missing)")));
            }
        };
        v.finish()?;
        Ok(AreaEmitterDesc {
            loc: el.loc.clone(),
            radiance,
            texture,
            primaries,
            uv_texture: None,
        })
    }

    /// `<texture type="d65">` around one `<texture type="bitmap">` (see [`Builder::area_emitter`]).
    fn d65_bitmap(&self, el: &'e Element) -> Result<BitmapDesc> {
        let v = ObjectView::parse(el)?;
        let mut bitmap = None;
        for child in &v.children {
            let t = self.resolve(child)?;
            if t.tag != "texture" || t.attr("type") != Some("bitmap") || bitmap.is_some() {
                return Err(misplaced(child, t, &v, "one <texture type=\"bitmap\">"));
            }
            bitmap = Some(self.bitmap(t)?);
        }
        v.finish()?;
        bitmap.ok_or_else(|| SceneError::at(&el.loc, "a d65 radiance texture needs a nested <texture type=\"bitmap\"> (d65 with a color or scale is not yet supported here)"))
    }

    /// `<texture type="bitmap">`.
    fn bitmap(&self, el: &'e Element) -> Result<BitmapDesc> {
        let v = ObjectView::parse(el)?;
        if v.plugin != "bitmap" {
            return Err(plugin_error(el));
        }
        let name = v
            .string("filename")?
            .ok_or_else(|| SceneError::at(&el.loc, "bitmap needs a filename"))?;
        let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
        if !path.is_file() {
            return Err(v.prop_error(
                "filename",
                format!("cannot open image '{name}' (looked for {})", path.display()),
            ));
        }
        let raw = v.boolean("raw")?.unwrap_or(false);
        let filter = v
            .string("filter_type")?
            .unwrap_or_else(|| "bilinear".into());
        if filter != "bilinear" && filter != "nearest" {
            return Err(v.prop_error(
                "filter_type",
                format!("filter_type must be bilinear or nearest, got '{filter}'"),
            ));
        }
        if let Some(w) = v.string("wrap_mode")? {
            if w != "repeat" {
                return Err(v.prop_error(
                    "wrap_mode",
                    format!(
                        "wrap_mode '{w}' is not yet supported (not yet implemented; only repeat)"
                    ),
                ));
            }
        }
        no_children(&v)?;
        v.finish()?;
        Ok(BitmapDesc {
            loc: el.loc.clone(),
            filename: path,
            raw,
            filter,
        })
    }

    // -----------------------------------------------------------------------------------------
    // Sensor, film, sampler

    /// `perspective` (see [`perspective`] for its parameters) with its film and sampler.
    fn sensor(&mut self, el: &'e Element) -> Result<(CameraDesc, FilmDesc, SamplerDesc)> {
        let v = ObjectView::parse(el)?;
        if v.plugin != "perspective" {
            return Err(plugin_error(el));
        }
        let camera = perspective(&v)?;
        let (mut film, mut sampler) = (None, None);
        for child in &v.children {
            let target = self.resolve(child)?;
            match target.tag.as_str() {
                "film" if film.is_none() => film = Some(self.film(target)?),
                "sampler" if sampler.is_none() => sampler = Some(sampler_desc(target)?),
                "film" | "sampler" => {
                    return Err(SceneError::at(
                        &child.written().loc,
                        format!("a sensor takes only one <{}>", target.tag),
                    ))
                }
                _ => return Err(misplaced(child, target, &v, "film or sampler")),
            }
        }
        v.finish()?;
        Ok((
            camera,
            film.unwrap_or_else(default_film),
            sampler.unwrap_or_else(default_sampler),
        ))
    }

    /// `hdrfilm`: `width` (768), `height` (576), nested `rfilter` (gaussian). Output-format
    /// options are accepted when valid and ignored (pt writes its own formats); cropping and
    /// `sample_border` are accepted only at their no-op values.
    fn film(&mut self, el: &'e Element) -> Result<FilmDesc> {
        let v = ObjectView::parse(el)?;
        if v.plugin != "hdrfilm" {
            return Err(plugin_error(el));
        }
        let width = int_in(&v, "width", 768, 1, 1 << 16)? as u32;
        let height = int_in(&v, "height", 576, 1, 1 << 16)? as u32;
        one_of(
            &v,
            "pixel_format",
            &["luminance", "luminance_alpha", "rgb", "rgba", "xyz", "xyza"],
        )?;
        one_of(&v, "component_format", &["float16", "float32", "uint32"])?;
        one_of(&v, "file_format", &["openexr", "exr", "rgbe", "pfm"])?;
        v.boolean("banner")?;
        no_op_crop(&v, width, height)?;
        if v.boolean("sample_border")? == Some(true) {
            return Err(v.prop_error(
                "sample_border",
                "sample_border=true is not yet supported (not yet implemented)",
            ));
        }
        let mut filter = None;
        for child in &v.children {
            let target = self.resolve(child)?;
            match target.tag.as_str() {
                "rfilter" if filter.is_none() => filter = Some(rfilter(target)?),
                "rfilter" => {
                    return Err(SceneError::at(
                        &child.written().loc,
                        "a film takes only one <rfilter>",
                    ))
                }
                _ => return Err(misplaced(child, target, &v, "rfilter")),
            }
        }
        v.finish()?;
        Ok(FilmDesc {
            width,
            height,
            filter: filter.unwrap_or(DEFAULT_FILTER),
        })
    }

    // -----------------------------------------------------------------------------------------
    // Integrator

    /// `path` (`max_depth` -1, `rr_depth` 5, `hide_emitters` false), `direct` (path with
    /// max_depth 2; one emitter and one BSDF sample) and `moment` (wraps one integrator).
    fn integrator(&mut self, el: &'e Element) -> Result<IntegratorDesc> {
        let v = ObjectView::parse(el)?;
        let desc = match v.plugin.as_str() {
            "path" => path_integrator(&v)?,
            "volpath" => IntegratorDesc {
                kind: IntegratorKind::VolPath,
                ..path_integrator(&v)?
            },
            "direct" => direct_integrator(&v)?,
            "moment" => self.moment(&v)?,
            "radiosity" => radiosity_integrator(&v)?,
            _ => return Err(plugin_error(el)),
        };
        let desc = IntegratorDesc {
            loc: el.loc.clone(),
            ..desc
        };
        if v.plugin != "moment" {
            if let Some(child) = v.children.first() {
                let target = self.resolve(child)?;
                return Err(misplaced(child, target, &v, "no nested objects"));
            }
        }
        v.finish()?;
        Ok(desc)
    }

    fn moment(&mut self, v: &ObjectView<'e>) -> Result<IntegratorDesc> {
        let mut inner = None;
        for child in &v.children {
            let target = self.resolve(child)?;
            if target.tag != "integrator" {
                return Err(misplaced(child, target, v, "integrator"));
            }
            if inner.is_some() {
                return Err(SceneError::at(
                    &child.written().loc,
                    "moment with more than one integrator is not yet supported (not yet implemented)",
                ));
            }
            inner = Some(self.integrator(target)?);
        }
        let mut inner = inner
            .ok_or_else(|| SceneError::at(&v.el.loc, "moment needs one nested <integrator>"))?;
        inner.moment = true;
        Ok(inner)
    }

    // -----------------------------------------------------------------------------------------
    // Shapes

    /// A shape with its geometry (see [`crate::shapes`]), BSDF and optional area emitter.
    fn shape(&mut self, el: &'e Element) -> Result<ShapeDesc> {
        let v = ObjectView::parse(el)?;
        let to_world = v.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let flip = v.boolean("flip_normals")?.unwrap_or(false);
        let geometry = match v.plugin.as_str() {
            "rectangle" => self.mesh(&v, shapes::rectangle(), &to_world, flip)?,
            "disk" => self.mesh(&v, shapes::disk(), &to_world, flip)?,
            "cube" => {
                // Mitsuba's cube is a mesh and takes the mesh option; flat faces either way.
                v.boolean("face_normals")?;
                self.mesh(&v, shapes::cube(), &to_world, flip)?
            }
            "sphere" => {
                let center = v.vec3("center")?.unwrap_or(Vec3::ZERO);
                let radius = positive(&v, "radius", 1.0)?;
                shapes::sphere(center, radius, &to_world, flip)
                    .map_err(|m| SceneError::at(&el.loc, m))?
            }
            "obj" => self.obj(&v, &to_world, flip)?,
            "gltf" => self.gltf(&v, &to_world, flip)?,
            _ => return Err(plugin_error(el)),
        };
        let (bsdf, emitter, interior) = self.shape_children(&v)?;
        v.finish()?;
        let bsdf = match bsdf {
            Some(b) => b,
            None => self.default_bsdf(el, emitter.is_some()),
        };
        Ok(ShapeDesc {
            loc: el.loc.clone(),
            plugin: v.plugin.clone(),
            id: el.attr("id").map(str::to_string),
            geometry,
            bsdf,
            emitter,
            interior,
        })
    }

    fn mesh(
        &self,
        v: &ObjectView<'_>,
        local: shapes::LocalMesh,
        m: &Mat4,
        flip: bool,
    ) -> Result<Geometry> {
        shapes::to_world(local, m, flip)
            .map(Geometry::Mesh)
            .map_err(|msg| SceneError::at(&v.el.loc, msg))
    }

    /// `obj`: `filename` (relative to the file naming it, then the main scene's folder, then
    /// `<path>` folders), `face_normals` (false), `flip_tex_coords` (true).
    fn obj(&self, v: &ObjectView<'_>, m: &Mat4, flip: bool) -> Result<Geometry> {
        let err = |msg: String| SceneError::at(&v.el.loc, msg);
        let name = v
            .string("filename")?
            .ok_or_else(|| err("missing <string name=\"filename\" .../>".into()))?;
        let opts = ObjOptions {
            face_normals: v.boolean("face_normals")?.unwrap_or(false),
            flip_tex_coords: v.boolean("flip_tex_coords")?.unwrap_or(true),
        };
        let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
        let local = obj::load_obj(&path, &name, &opts).map_err(err)?;
        let mut mesh =
            shapes::to_world(local, m, flip).map_err(|e| err(format!("mesh '{name}': {e}")))?;
        if mesh.normals.is_none() && !opts.face_normals {
            mesh.normals = Some(shapes::vertex_normals(&mesh.positions, &mesh.indices));
        }
        Ok(Geometry::Mesh(mesh))
    }

    /// `gltf` (project extension): every triangle primitive of a glTF 2.0 file's scene as one
    /// mesh (node transforms applied, then `to_world`), with this shape's BSDF; the file's
    /// materials, cameras and lights are not used. `filename` is resolved as for `obj`.
    fn gltf(&self, v: &ObjectView<'_>, m: &Mat4, flip: bool) -> Result<Geometry> {
        let err = |msg: String| SceneError::at(&v.el.loc, msg);
        let name = v
            .string("filename")?
            .ok_or_else(|| err("missing <string name=\"filename\" .../>".into()))?;
        let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
        let reader = crate::gltf_mesh_reader().ok_or_else(|| {
            err("glTF shapes need the glTF reader, which this program did not install".into())
        })?;
        let mesh = reader(&path).map_err(err)?;
        let local = shapes::LocalMesh {
            positions: mesh.positions,
            normals: mesh.normals,
            uvs: mesh.uvs,
            indices: mesh.indices,
        };
        shapes::to_world(local, m, flip)
            .map(Geometry::Mesh)
            .map_err(|e| err(format!("mesh '{name}': {e}")))
    }

    /// A shape's nested BSDF (or `<ref>` to one), area emitter and interior medium, at most one
    /// of each.
    fn shape_children(
        &mut self,
        v: &ObjectView<'e>,
    ) -> Result<(Option<usize>, Option<AreaEmitterDesc>, Option<MediumDesc>)> {
        let (mut bsdf, mut emitter, mut interior) = (None, None, None);
        for child in &v.children {
            let target = self.resolve(child)?;
            let once = |what: &str| {
                SceneError::at(
                    &child.written().loc,
                    format!("a shape takes only one {what}"),
                )
            };
            match target.tag.as_str() {
                "bsdf" if bsdf.is_some() => return Err(once("BSDF")),
                "bsdf" => bsdf = Some(self.bsdf_for_shape(target)?),
                "emitter" if emitter.is_some() => return Err(once("emitter")),
                "emitter" => emitter = Some(self.area_emitter(target)?),
                "medium" => {
                    let written = child.written();
                    match written.attr("name") {
                        Some("interior") if interior.is_some() => return Err(once("interior medium")),
                        Some("interior") => interior = Some(medium(target)?),
                        Some("exterior") => {
                            return Err(SceneError::at(
                                &written.loc,
                                "exterior media are not yet supported (not yet implemented): the space outside all shapes is vacuum; give the medium to the shape that encloses it as name=\"interior\"",
                            ))
                        }
                        other => {
                            return Err(SceneError::at(
                                &written.loc,
                                format!(
                                    "a shape's <medium> needs name=\"interior\" or name=\"exterior\", got {}",
                                    other.map_or("none".to_string(), |n| format!("\"{n}\""))
                                ),
                            ))
                        }
                    }
                }
                _ => return Err(misplaced(child, target, v, "bsdf, emitter or medium")),
            }
        }
        Ok((bsdf, emitter, interior))
    }

    // -----------------------------------------------------------------------------------------
    // BSDFs

    /// Index in `bsdfs` of the BSDF `el`: shared (id-carrying) BSDFs are added once.
    fn bsdf_for_shape(&mut self, el: &'e Element) -> Result<usize> {
        let id = el.attr("id");
        if let Some(&index) = id.and_then(|id| self.bsdf_index.get(id)) {
            return Ok(index);
        }
        let desc = self.bsdf_desc(el)?;
        self.bsdfs.push(desc);
        let index = self.bsdfs.len() - 1;
        if let Some(id) = id {
            self.bsdf_index.insert(id.to_string(), index);
        }
        Ok(index)
    }

    /// Mitsuba's default for shapes without a BSDF: diffuse with reflectance 0.5, or 0 (black)
    /// when the shape is an emitter (Mitsuba 3.9.1 `Shape`: an area light without a BSDF
    /// reflects nothing); one shared instance of each.
    fn default_bsdf(&mut self, shape: &Element, emitter: bool) -> usize {
        if let Some(index) = self.default_bsdf[usize::from(emitter)] {
            return index;
        }
        self.bsdfs.push(BsdfDesc {
            loc: shape.loc.clone(),
            id: None,
            kind: BsdfKind::Diffuse {
                reflectance: SpectrumDesc::Constant(if emitter { 0.0 } else { 0.5 }),
            },
        });
        let index = self.bsdfs.len() - 1;
        self.default_bsdf[usize::from(emitter)] = Some(index);
        index
    }

    /// Builds the BSDF `el`, once per id.
    fn bsdf_desc(&mut self, el: &'e Element) -> Result<BsdfDesc> {
        let Some(id) = el.attr("id") else {
            return self.build_bsdf(el);
        };
        if let Some(desc) = self.bsdf_memo.get(id) {
            return Ok(desc.clone());
        }
        if self.visiting.iter().any(|v| v == id) {
            return Err(SceneError::at(
                &el.loc,
                format!("BSDF \"{id}\" contains itself"),
            ));
        }
        self.visiting.push(id.to_string());
        let built = self.build_bsdf(el);
        self.visiting.pop();
        let desc = built?;
        self.bsdf_memo.insert(id.to_string(), desc.clone());
        Ok(desc)
    }

    /// `diffuse` (`reflectance`: rgb, spectrum or float; 0.5) and `twosided` (one nested BSDF).
    fn build_bsdf(&mut self, el: &'e Element) -> Result<BsdfDesc> {
        let v = ObjectView::parse(el)?;
        let kind = match v.plugin.as_str() {
            "diffuse" => {
                let reflectance = v
                    .spectrum("reflectance")?
                    .unwrap_or(SpectrumDesc::Constant(0.5));
                if let Some(child) = v.children.first() {
                    let target = self.resolve(child)?;
                    return Err(misplaced(child, target, &v, "no nested objects"));
                }
                BsdfKind::Diffuse { reflectance }
            }
            "twosided" => BsdfKind::TwoSided {
                inner: Box::new(self.twosided_inner(&v)?),
            },
            "mask" => self.mask(&v)?,
            "normalmap" => self.normal_map(&v)?,
            "blendbsdf" => self.blend(&v)?,
            // Project extensions with spectral re-emission (fluorescence.rs, phosphorescence.rs).
            "fluorescent" | "phosphorescent" => {
                no_children(&v)?;
                crate::materials::bsdf_kind(&v)?
            }
            "orennayar" | "minnaert" | "dielectric" | "thindielectric" | "roughdielectric"
            | "conductor" | "roughconductor" | "thinfilm" | "roughthinfilm" | "roughplastic" => {
                no_children(&v)?;
                crate::materials::bsdf_kind(&v)?
            }
            _ => return Err(plugin_error(el)),
        };
        v.finish()?;
        Ok(BsdfDesc {
            loc: el.loc.clone(),
            id: el.attr("id").map(str::to_string),
            kind,
        })
    }

    /// The one nested BSDF of a wrapper (no user at the moment: `mask` and `normalmap` also take
    /// textures).
    #[allow(dead_code)]
    fn single_inner(&mut self, v: &ObjectView<'e>, what: &str) -> Result<BsdfDesc> {
        let mut inner = None;
        for child in &v.children {
            let target = self.resolve(child)?;
            if target.tag != "bsdf" {
                return Err(misplaced(child, target, v, "bsdf"));
            }
            if inner.is_some() {
                return Err(SceneError::at(
                    &child.written().loc,
                    format!("{what} takes one nested <bsdf>"),
                ));
            }
            inner = Some(self.bsdf_desc(target)?);
        }
        inner.ok_or_else(|| {
            SceneError::at(
                &v.el.loc,
                format!("{what} needs one nested <bsdf> or <ref>"),
            )
        })
    }

    /// `mask`: `opacity` a float in [0, 1] (0.5) or `<texture type="bitmap" name="opacity">`
    /// (opacity = the texel's value: Rec. 709 luminance of its linear RGB, as Mitsuba's `eval_1`,
    /// clamped to [0, 1]), and one nested BSDF.
    fn mask(&mut self, v: &ObjectView<'e>) -> Result<BsdfKind> {
        let (mut inner, mut texture) = (None, None);
        for child in &v.children {
            let target = self.resolve(child)?;
            match (target.tag.as_str(), target.attr("name")) {
                ("bsdf", _) if inner.is_none() => inner = Some(self.bsdf_desc(target)?),
                ("bsdf", _) => {
                    return Err(SceneError::at(
                        &child.written().loc,
                        "mask takes one nested <bsdf>",
                    ))
                }
                ("texture", Some("opacity")) if texture.is_none() => {
                    texture = Some(self.bitmap(target)?)
                }
                _ => {
                    return Err(misplaced(
                        child,
                        target,
                        v,
                        "one nested <bsdf> and at most one <texture name=\"opacity\">",
                    ))
                }
            }
        }
        let inner =
            Box::new(inner.ok_or_else(|| {
                SceneError::at(&v.el.loc, "mask needs one nested <bsdf> or <ref>")
            })?);
        if let Some(b) = texture {
            if v.has("opacity") {
                return Err(v.prop_error(
                    "opacity",
                    "give either an opacity value or an opacity texture",
                ));
            }
            let texture = Box::new(UvTexture {
                source: ImageSource::File(b.filename),
                srgb: !b.raw,
                nearest: b.filter == "nearest",
                transform: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            });
            return Ok(BsdfKind::OpacityTexture {
                texture,
                channel: TextureChannel::Luminance,
                factor: 1.0,
                cutoff: None,
                inner,
            });
        }
        let opacity = v.float("opacity")?.unwrap_or(0.5);
        if !(0.0..=1.0).contains(&opacity) {
            return Err(v.prop_error(
                "opacity",
                format!("opacity must be in [0, 1], got {opacity}"),
            ));
        }
        Ok(BsdfKind::Mask { opacity, inner })
    }

    /// `blendbsdf`: `weight` (a float in [0, 1], default 0.5; textured weights are not yet
    /// supported) and exactly two nested BSDFs: `(1 - weight) first + weight second`.
    fn blend(&mut self, v: &ObjectView<'e>) -> Result<BsdfKind> {
        let mut inner = Vec::new();
        for child in &v.children {
            let target = self.resolve(child)?;
            if target.tag != "bsdf" || inner.len() == 2 {
                return Err(misplaced(
                    child,
                    target,
                    v,
                    "exactly two nested <bsdf> (a textured weight is not yet supported)",
                ));
            }
            inner.push(self.bsdf_desc(target)?);
        }
        if inner.len() != 2 {
            return Err(SceneError::at(
                &v.el.loc,
                format!(
                    "blendbsdf needs exactly two nested BSDFs, got {}",
                    inner.len()
                ),
            ));
        }
        let weight = v.float("weight")?.unwrap_or(0.5);
        if !(0.0..=1.0).contains(&weight) {
            return Err(v.prop_error("weight", format!("weight must be in [0, 1], got {weight}")));
        }
        let second = Box::new(inner.pop().expect("two"));
        let first = Box::new(inner.pop().expect("two"));
        Ok(BsdfKind::Blend {
            weight,
            weight_texture: None,
            first,
            second,
        })
    }

    /// `normalmap`: one nested BSDF and `<texture type="bitmap" name="normalmap">` whose RGB
    /// is (n + 1) / 2 in the local shading frame (x along dp/du). As Mitsuba's bitmap, 8-bit
    /// images are sRGB-decoded unless `raw` is true (which normal maps want).
    fn normal_map(&mut self, v: &ObjectView<'e>) -> Result<BsdfKind> {
        let (mut inner, mut texture) = (None, None);
        for child in &v.children {
            let target = self.resolve(child)?;
            match (target.tag.as_str(), target.attr("name")) {
                ("bsdf", _) if inner.is_none() => inner = Some(self.bsdf_desc(target)?),
                ("texture", Some("normalmap")) if texture.is_none() => {
                    texture = Some(self.bitmap(target)?)
                }
                _ => {
                    return Err(misplaced(
                        child,
                        target,
                        v,
                        "one nested <bsdf> and one <texture name=\"normalmap\">",
                    ))
                }
            }
        }
        let inner = inner.ok_or_else(|| {
            SceneError::at(&v.el.loc, "normalmap needs one nested <bsdf> or <ref>")
        })?;
        let b = texture.ok_or_else(|| {
            SceneError::at(
                &v.el.loc,
                "normalmap needs <texture type=\"bitmap\" name=\"normalmap\">",
            )
        })?;
        let texture = Box::new(UvTexture {
            source: ImageSource::File(b.filename),
            srgb: !b.raw,
            nearest: b.filter == "nearest",
            transform: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        });
        Ok(BsdfKind::NormalMap {
            texture,
            scale: 1.0,
            gltf: false,
            inner: Box::new(inner),
        })
    }

    fn twosided_inner(&mut self, v: &ObjectView<'e>) -> Result<BsdfDesc> {
        let mut inner = None;
        for child in &v.children {
            let target = self.resolve(child)?;
            if target.tag != "bsdf" {
                return Err(misplaced(child, target, v, "bsdf"));
            }
            if inner.is_some() {
                return Err(SceneError::at(
                    &child.written().loc,
                    "twosided with a different BSDF per side is not yet supported (not yet implemented)",
                ));
            }
            inner = Some(self.bsdf_desc(target)?);
        }
        inner.ok_or_else(|| SceneError::at(&v.el.loc, "twosided needs one nested <bsdf> or <ref>"))
    }
}

// ---------------------------------------------------------------------------------------------
// Plugins that need no builder state

/// `perspective`: `fov` (degrees, along `fov_axis`: x, y, diagonal, smaller or larger; default
/// x) or `focal_length` ("50mm" style, on a 36 x 24 mm film's diagonal; default 50mm),
/// `near_clip` (1e-2), `far_clip` (1e4), `to_world` (rotation and translation only, as in
/// Mitsuba; a mirroring `scale x="-1"` is allowed), `focus_distance` (accepted, no effect on a
/// pinhole).
fn perspective(v: &ObjectView<'_>) -> Result<CameraDesc> {
    let projection = projection(v)?;
    let near_clip = positive(v, "near_clip", 1e-2)?;
    let far_clip = positive(v, "far_clip", 1e4)?;
    if near_clip >= far_clip {
        return Err(v.prop_error("near_clip", "near_clip must be smaller than far_clip"));
    }
    v.float("focus_distance")?;
    let to_world = v.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
    if !is_affine(&to_world) || has_scale(&to_world) {
        return Err(v.prop_error(
            "to_world",
            "the camera's to_world may only rotate, mirror and translate (Mitsuba rejects scale)",
        ));
    }
    Ok(CameraDesc {
        loc: v.el.loc.clone(),
        projection,
        to_world,
        near_clip,
        far_clip,
    })
}

/// Mitsuba's `has_scale`: some axis changes length.
fn has_scale(m: &Mat4) -> bool {
    let l = Mat3::from_mat4(*m);
    [l.x_axis, l.y_axis, l.z_axis]
        .iter()
        .any(|c| (c.length_squared() - 1.0).abs() > 1e-3)
}

fn projection(v: &ObjectView<'_>) -> Result<Projection> {
    if v.has("fov") && v.has("focal_length") {
        return Err(v.prop_error(
            "focal_length",
            "give either 'fov' or 'focal_length', not both",
        ));
    }
    if let Some(fov) = v.float("fov")? {
        if !(fov > 0.0 && fov < 180.0) {
            return Err(v.prop_error(
                "fov",
                format!("fov must be between 0 and 180 degrees, got {fov}"),
            ));
        }
        let axis = match v
            .string("fov_axis")?
            .map(|s| s.to_ascii_lowercase())
            .as_deref()
        {
            None | Some("x") => FovAxis::X,
            Some("y") => FovAxis::Y,
            Some("diagonal") => FovAxis::Diagonal,
            Some("smaller") => FovAxis::Smaller,
            Some("larger") => FovAxis::Larger,
            Some(other) => {
                return Err(v.prop_error(
                    "fov_axis",
                    format!("fov_axis must be x, y, diagonal, smaller or larger, not \"{other}\""),
                ))
            }
        };
        return Ok(Projection::Perspective {
            fov_deg: fov,
            fov_axis: axis,
        });
    }
    let text = v.string("focal_length")?.unwrap_or_else(|| "50mm".into());
    let mm = text.trim().strip_suffix("mm").unwrap_or(text.trim());
    let f = crate::props::parse_f32(mm)
        .ok()
        .filter(|f| *f > 0.0)
        .ok_or_else(|| {
            v.prop_error(
                "focal_length",
                format!("cannot read focal length \"{text}\" (expected e.g. 50mm)"),
            )
        })?;
    // A 35 mm film is 36 x 24 mm; Mitsuba measures the focal length's view on its diagonal.
    let diagonal = (36.0f32 * 36.0 + 24.0 * 24.0).sqrt();
    let fov_deg = (2.0 * (diagonal / (2.0 * f)).atan()).to_degrees();
    Ok(Projection::Perspective {
        fov_deg,
        fov_axis: FovAxis::Diagonal,
    })
}

/// Mitsuba's default filter: Gaussian, stddev 0.5 pixel.
const DEFAULT_FILTER: FilterDesc = FilterDesc::Gaussian { stddev: 0.5 };

/// `box` (no parameters: radius 0.5), `tent` (`radius`, 1), `gaussian` (`stddev`, 0.5).
fn rfilter(el: &Element) -> Result<FilterDesc> {
    let v = ObjectView::parse(el)?;
    let filter = match v.plugin.as_str() {
        "box" => FilterDesc::Box { radius: 0.5 },
        "tent" => FilterDesc::Tent {
            radius: positive(&v, "radius", 1.0)?,
        },
        "gaussian" => FilterDesc::Gaussian {
            stddev: positive(&v, "stddev", 0.5)?,
        },
        _ => return Err(plugin_error(el)),
    };
    no_children(&v)?;
    v.finish()?;
    Ok(filter)
}

/// `independent` and `stratified` (`sample_count` 4, `seed` 0; stratified also `jitter`).
/// Stratified rounds the sample count up to a square, as Mitsuba does; the IR has no sampler
/// kind, so the renderer samples it independently with that count.
fn sampler_desc(el: &Element) -> Result<SamplerDesc> {
    let v = ObjectView::parse(el)?;
    if !matches!(v.plugin.as_str(), "independent" | "stratified") {
        return Err(plugin_error(el));
    }
    let mut sample_count = int_in(&v, "sample_count", 4, 1, u32::MAX as i64)? as u32;
    let seed = int_in(&v, "seed", 0, 0, i64::MAX)? as u64;
    if v.plugin == "stratified" {
        v.boolean("jitter")?;
        let side = (1u64..).find(|s| s * s >= sample_count as u64).unwrap_or(1);
        sample_count = u32::try_from(side * side).unwrap_or(u32::MAX);
    }
    no_children(&v)?;
    v.finish()?;
    Ok(SamplerDesc { sample_count, seed })
}

fn path_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    Ok(IntegratorDesc {
        kind: IntegratorKind::Path,
        max_depth: int_in(v, "max_depth", -1, -1, i32::MAX as i64)? as i32,
        rr_depth: int_in(v, "rr_depth", 5, 1, u32::MAX as i64)? as u32,
        hide_emitters: v.boolean("hide_emitters")?.unwrap_or(false),
        moment: false,
        radiosity: RadiosityOptions::default(),
        loc: SourceLoc::default(),
    })
}

/// `homogeneous` medium, purely absorbing: `sigma_t` (extinction per scene unit: float, rgb or
/// spectrum; default 1), `scale` (multiplies sigma_t; default 1), `albedo` (must be 0: scattering
/// media are not implemented, and Mitsuba's default albedo is 0.75, so it must be written),
/// `sample_emitters` and `has_spectral_extinction` (accepted; no effect on an absorbing medium).
fn medium(el: &Element) -> Result<MediumDesc> {
    let v = ObjectView::parse(el)?;
    if v.plugin != "homogeneous" {
        return Err(plugin_error(el));
    }
    if let Some(child) = v.children.first() {
        let what = child.written();
        return Err(SceneError::at(
            &what.loc,
            "a phase function or nested object in a medium is not yet supported (not yet implemented): media here only absorb",
        ));
    }
    let sigma_t = v
        .spectrum("sigma_t")?
        .unwrap_or(SpectrumDesc::Constant(1.0));
    let scale = v.float("scale")?.unwrap_or(1.0);
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(v.prop_error(
            "scale",
            format!("scale must be finite and >= 0, got {scale}"),
        ));
    }
    if sigma_t
        .values()
        .iter()
        .any(|x| !(x.is_finite() && *x >= 0.0))
    {
        return Err(v.prop_error("sigma_t", "sigma_t must be finite and >= 0"));
    }
    let albedo = v.spectrum("albedo")?;
    let absorbing = matches!(&albedo, Some(a) if a.values().iter().all(|x| *x == 0.0));
    if !absorbing {
        let message = if albedo.is_none() {
            "a medium without 'albedo' scatters (Mitsuba's default albedo is 0.75); scattering media are not yet supported (not yet implemented): write <float name=\"albedo\" value=\"0\"/> for an absorbing medium"
        } else {
            "scattering media (albedo > 0) are not yet supported (not yet implemented): only albedo 0 (pure absorption, Beer-Lambert)"
        };
        return Err(match albedo {
            Some(_) => v.prop_error("albedo", message),
            None => SceneError::at(&el.loc, message),
        });
    }
    v.boolean("sample_emitters")?;
    v.boolean("has_spectral_extinction")?;
    v.finish()?;
    let sigma_t = match sigma_t {
        SpectrumDesc::Constant(c) => SpectrumDesc::Constant(c * scale),
        SpectrumDesc::Rgb(c) => SpectrumDesc::Rgb(c.map(|x| x * scale)),
        SpectrumDesc::Tabulated(p) => SpectrumDesc::Tabulated(std::sync::Arc::new(
            p.iter().map(|&(w, x)| (w, x * scale)).collect(),
        )),
        s @ (SpectrumDesc::Blackbody { .. } | SpectrumDesc::Illuminant { .. }) => {
            return Err(v.prop_error(
                "sigma_t",
                format!("sigma_t cannot be an emission spectrum ({})", s.form_name()),
            ));
        }
    };
    Ok(MediumDesc {
        loc: el.loc.clone(),
        sigma_t,
    })
}

/// `radiosity` (project extension): `patch_size` (float, scene units), `rays_per_patch`,
/// `tolerance`, `max_iterations`, `solver`, `display`, `reciprocity` (strings; checked by the
/// radiosity crate). Renders diffuse scenes by finite elements; see crates/pt-radiosity.
fn radiosity_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    let count = |name: &str| -> Result<Option<u32>> {
        match v.integer(name)? {
            None => Ok(None),
            Some(n) if n >= 1 && n <= u32::MAX as i64 => Ok(Some(n as u32)),
            Some(n) => Err(v.prop_error(name, format!("{name} must be at least 1, got {n}"))),
        }
    };
    let radiosity = RadiosityOptions {
        patch_size: v.float("patch_size")?,
        rays_per_patch: count("rays_per_patch")?,
        tolerance: v.float("tolerance")?,
        max_iterations: count("max_iterations")?,
        solver: v.string("solver")?,
        display: v.string("display")?,
        reciprocity: v.string("reciprocity")?,
    };
    Ok(IntegratorDesc {
        kind: IntegratorKind::Radiosity,
        max_depth: -1,
        rr_depth: 5,
        hide_emitters: false,
        moment: false,
        radiosity,
        loc: SourceLoc::default(),
    })
}

/// Mitsuba's `direct` takes several emitter and BSDF samples per hit; this renderer draws one
/// of each (the defaults), which is `path` with `max_depth` 2.
fn direct_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    for name in ["shading_samples", "emitter_samples", "bsdf_samples"] {
        if let Some(n) = v.integer(name)? {
            if n != 1 {
                return Err(v.prop_error(
                    name,
                    format!("{name}={n} is not yet supported (not yet implemented; only 1)"),
                ));
            }
        }
    }
    Ok(IntegratorDesc {
        kind: IntegratorKind::Direct,
        max_depth: 2,
        rr_depth: 5,
        hide_emitters: v.boolean("hide_emitters")?.unwrap_or(false),
        moment: false,
        radiosity: RadiosityOptions::default(),
        loc: SourceLoc::default(),
    })
}

/// `area`: `radiance` (rgb, spectrum or float; Mitsuba's default 1).
fn default_film() -> FilmDesc {
    FilmDesc {
        width: 768,
        height: 576,
        filter: DEFAULT_FILTER,
    }
}

fn default_sampler() -> SamplerDesc {
    SamplerDesc {
        sample_count: 4,
        seed: 0,
    }
}

fn default_integrator() -> IntegratorDesc {
    IntegratorDesc {
        radiosity: RadiosityOptions::default(),
        loc: SourceLoc::default(),
        kind: IntegratorKind::Path,
        max_depth: -1,
        rr_depth: 5,
        hide_emitters: false,
        moment: false,
    }
}

/// Mitsuba's camera for scenes without a sensor: 45 degrees on x, looking along +z from in
/// front of the scene's bounding box, far enough to see all of it.
fn default_camera(root: &Element, shapes: &[ShapeDesc]) -> CameraDesc {
    let mut camera = CameraDesc {
        loc: root.loc.clone(),
        projection: Projection::Perspective {
            fov_deg: 45.0,
            fov_axis: FovAxis::X,
        },
        to_world: Mat4::IDENTITY,
        near_clip: 1e-2,
        far_clip: 1e4,
    };
    if let Some((min, max)) = bounds(shapes) {
        let extent = (max - min).max_element();
        let distance = extent / (2.0 * (22.5f32).to_radians().tan());
        if distance > 0.0 && distance.is_finite() {
            let center = (min + max) * 0.5;
            camera.to_world =
                Mat4::from_translation(Vec3::new(center.x, center.y, min.z - distance));
            camera.near_clip = distance / 100.0;
            camera.far_clip = extent * 5.0 + distance;
        }
    }
    camera
}

/// World-space bounding box of all shapes, if there is any geometry.
fn bounds(shapes: &[ShapeDesc]) -> Option<(Vec3, Vec3)> {
    let mut acc: Option<(Vec3, Vec3)> = None;
    let mut add = |p: Vec3| {
        acc = Some(acc.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
    };
    for shape in shapes {
        match &shape.geometry {
            Geometry::Mesh(m) => m.positions.iter().for_each(|&p| add(p)),
            Geometry::Sphere { center, radius, .. } => {
                add(*center - *radius);
                add(*center + *radius);
            }
        }
    }
    acc
}

// ---------------------------------------------------------------------------------------------
// Parameter helpers

/// An integer parameter with a default, checked to lie in `min..=max`.
fn int_in(v: &ObjectView<'_>, name: &str, default: i64, min: i64, max: i64) -> Result<i64> {
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
fn positive(v: &ObjectView<'_>, name: &str, default: f32) -> Result<f32> {
    let value = v.float(name)?.unwrap_or(default);
    if value > 0.0 {
        Ok(value)
    } else {
        Err(v.prop_error(name, format!("'{name}' must be positive, got {value}")))
    }
}

/// Accepts a string parameter only if it is one of `allowed` (case-insensitive).
fn one_of(v: &ObjectView<'_>, name: &str, allowed: &[&str]) -> Result<()> {
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

/// Crop parameters are accepted only when they select the whole image.
fn no_op_crop(v: &ObjectView<'_>, width: u32, height: u32) -> Result<()> {
    let checks = [
        ("crop_offset_x", 0),
        ("crop_offset_y", 0),
        ("crop_width", width),
        ("crop_height", height),
    ];
    for (name, whole) in checks {
        if let Some(value) = v.integer(name)? {
            if value != whole as i64 {
                return Err(v.prop_error(
                    name,
                    format!("cropping ({name}={value}) is not yet supported (not yet implemented)"),
                ));
            }
        }
    }
    Ok(())
}

/// Errors if a plugin without nested objects has one.
fn no_children(v: &ObjectView<'_>) -> Result<()> {
    match v.children.first() {
        Some(child) => Err(SceneError::at(
            &child.written().loc,
            format!("<{}> cannot be nested in {}", child.written().tag, v.what()),
        )),
        None => Ok(()),
    }
}
