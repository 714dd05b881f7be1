//! Shapes and the media on their two sides.

use super::*;

impl<'e> Builder<'e> {
    /// A shape with its geometry (see [`crate::shapes`]), BSDF and optional area emitter.
    pub(super) fn shape(&mut self, el: &'e Element) -> Result<ShapeDesc> {
        let v = ObjectView::parse(el)?;
        let to_world = v.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let flip = v.boolean("flip_normals")?.unwrap_or(false);
        let geometry = match v.plugin.as_str() {
            "rectangle" => self.mesh(&v, shapes::rectangle(), &to_world, flip)?,
            "disk" => {
                shapes::disk_shape(&to_world, flip).map_err(|m| SceneError::at(&el.loc, m))?
            }
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
            "cylinder" => {
                let p0 = v.vec3("p0")?.unwrap_or(Vec3::ZERO);
                let p1 = v.vec3("p1")?.unwrap_or(Vec3::Z);
                let radius = positive(&v, "radius", 1.0)?;
                shapes::cylinder(p0, p1, radius, &to_world, flip)
                    .map_err(|m| SceneError::at(&el.loc, m))?
            }
            "obj" => self.obj(&v, &to_world, flip)?,
            "serialized" => self.serialized(&v, &to_world, flip)?,
            "ply" => self.ply(&v, &to_world, flip)?,
            "gltf" => self.gltf(&v, &to_world, flip)?,
            "sdfgrid" => {
                if v.has("flip_normals") {
                    // Mitsuba's sdfgrid has no such parameter: its outside is where the
                    // function is positive.
                    return Err(v.prop_error(
                        "flip_normals",
                        "an sdfgrid has no flip_normals (its outside is where the distance is positive; negate the grid)",
                    ));
                }
                self.sdfgrid(&v, &to_world)?
            }
            "linearcurve" => self.curves(&v, CurveBasis::Linear, &to_world)?,
            "bsplinecurve" => self.curves(&v, CurveBasis::BSpline, &to_world)?,
            _ => return Err(plugin_error(el)),
        };
        let (bsdf, emitter, [interior, exterior]) = self.shape_children(&v)?;
        if emitter.is_some() && matches!(geometry, Geometry::SdfGrid(_)) {
            return Err(SceneError::at(
                &el.loc,
                "an sdfgrid cannot be an area emitter (as in Mitsuba, which samples no point on it)",
            ));
        }
        if emitter.is_some() && matches!(geometry, Geometry::Curves(_)) {
            return Err(SceneError::at(
                &el.loc,
                format!("a {} cannot be an area emitter (not implemented: no sampling of points on curves)", v.plugin),
            ));
        }
        if (interior.is_some() || exterior.is_some()) && matches!(geometry, Geometry::Curves(_)) {
            return Err(SceneError::at(
                &el.loc,
                format!("a {} cannot bound a medium (its back faces are culled, so rays could not leave it)", v.plugin),
            ));
        }
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
            exterior,
        })
    }

    /// `shapegroup` (Mitsuba's): its nested shapes, built once (the index into
    /// `SceneDesc::groups`). As in Mitsuba 3.9.1, a group holds no emitter and no other group;
    /// instances inside a group and media on its shapes are not implemented.
    pub(super) fn shape_group(&mut self, el: &'e Element) -> Result<usize> {
        let key = el as *const Element;
        if let Some(&i) = self.group_index.get(&key) {
            return Ok(i);
        }
        let v = ObjectView::parse(el)?;
        let mut shapes = Vec::new();
        for child in &v.children {
            let target = self.resolve(child)?;
            if target.tag != "shape" {
                return Err(misplaced(child, target, &v, "shape"));
            }
            let at = |m: &str| Err(SceneError::at(&child.written().loc, m.to_string()));
            match target.attr("type") {
                Some("shapegroup") => {
                    return at("a shapegroup cannot contain another shapegroup (nor can Mitsuba's)")
                }
                Some("instance") => {
                    return at("an instance inside a shapegroup (nested instancing) is not supported (not yet implemented)")
                }
                _ => {}
            }
            let shape = self.shape(target)?;
            if let Some((camera, ..)) = self.shape_sensor.take() {
                return Err(SceneError::at(
                    &camera.loc,
                    "a shape in a shapegroup cannot hold a sensor (Mitsuba's instances cannot either)",
                ));
            }
            if let Some(e) = &shape.emitter {
                return Err(SceneError::at(
                    &e.loc,
                    "a shape in a shapegroup cannot emit (Mitsuba refuses instanced emitters too)",
                ));
            }
            shapes.push(shape);
        }
        v.finish()?;
        let i = self.groups.len();
        self.groups.push(ShapeGroupDesc {
            loc: el.loc.clone(),
            id: el.attr("id").unwrap_or_default().to_string(),
            shapes,
        });
        self.group_index.insert(key, i);
        Ok(i)
    }

    /// `instance` (Mitsuba's): a `<ref>` to a `shapegroup` (or the group written inline) and
    /// `to_world` (any invertible affine transform).
    pub(super) fn instance(&mut self, el: &'e Element) -> Result<InstanceDesc> {
        let v = ObjectView::parse(el)?;
        let to_world = v.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let det = to_world.determinant();
        if !(det.is_finite() && det != 0.0) {
            return Err(SceneError::at(
                &el.loc,
                "the instance's to_world is not invertible (determinant 0)",
            ));
        }
        let mut group = None;
        for child in &v.children {
            let target = self.resolve(child)?;
            if target.tag != "shape" || target.attr("type") != Some("shapegroup") {
                return Err(misplaced(child, target, &v, "a reference to a shapegroup"));
            }
            if group.is_some() {
                return Err(SceneError::at(
                    &child.written().loc,
                    "an instance places exactly one shapegroup",
                ));
            }
            group = Some(self.shape_group(target)?);
        }
        v.finish()?;
        let group = group.ok_or_else(|| {
            SceneError::at(
                &el.loc,
                "an instance needs a shapegroup: <ref id=\"...\"/> to one",
            )
        })?;
        Ok(InstanceDesc {
            loc: el.loc.clone(),
            group,
            to_world,
        })
    }

    pub(super) fn mesh(
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

    /// A mesh read from the file named by `filename` (relative to the file naming it, then the
    /// main scene's folder, then `<path>` folders) by `load(path, name)`: its vertex normals
    /// dropped if `face_normals`, `to_world` and `flip_normals` applied, and, without normals
    /// in the file (and without `face_normals`), vertex normals computed after `to_world`, as
    /// Mitsuba does for every mesh format.
    fn mesh_file(
        &self,
        v: &ObjectView<'_>,
        m: &Mat4,
        flip: bool,
        face_normals: bool,
        load: impl FnOnce(&Path, &str) -> std::result::Result<shapes::LocalMesh, String>,
    ) -> Result<Geometry> {
        let err = |msg: String| SceneError::at(&v.el.loc, msg);
        let name = v
            .string("filename")?
            .ok_or_else(|| err("missing <string name=\"filename\" .../>".into()))?;
        let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
        let mut local = load(&path, &name).map_err(err)?;
        if face_normals {
            local.normals = None;
        }
        let mut mesh =
            shapes::to_world(local, m, flip).map_err(|e| err(format!("mesh '{name}': {e}")))?;
        if mesh.normals.is_none() && !face_normals {
            mesh.normals = Some(shapes::vertex_normals(&mesh.positions, &mesh.indices));
        }
        Ok(Geometry::Mesh(mesh))
    }

    /// `obj` (see [`Self::mesh_file`]): `face_normals` (false), `flip_tex_coords` (true).
    pub(super) fn obj(&self, v: &ObjectView<'_>, m: &Mat4, flip: bool) -> Result<Geometry> {
        let opts = ObjOptions {
            face_normals: v.boolean("face_normals")?.unwrap_or(false),
            flip_tex_coords: v.boolean("flip_tex_coords")?.unwrap_or(true),
        };
        self.mesh_file(v, m, flip, opts.face_normals, |path, name| {
            obj::load_obj(path, name, &opts)
        })
    }

    /// `serialized` (see [`Self::mesh_file`] and [`crate::serialized`]): mesh `shape_index` (0)
    /// of the file, `face_normals` (false).
    pub(super) fn serialized(&self, v: &ObjectView<'_>, m: &Mat4, flip: bool) -> Result<Geometry> {
        let index = match v.integer("shape_index")? {
            None => 0,
            Some(i) => u32::try_from(i).map_err(|_| {
                v.prop_error("shape_index", format!("shape_index must be >= 0, got {i}"))
            })?,
        };
        let face_normals = v.boolean("face_normals")?.unwrap_or(false);
        self.mesh_file(v, m, flip, face_normals, |path, name| {
            serialized::load_serialized(path, name, index)
        })
    }

    /// `ply` (see [`Self::mesh_file`] and [`crate::ply`]): `face_normals` (false),
    /// `flip_tex_coords` (false; v' = 1 - v when set).
    pub(super) fn ply(&self, v: &ObjectView<'_>, m: &Mat4, flip: bool) -> Result<Geometry> {
        let face_normals = v.boolean("face_normals")?.unwrap_or(false);
        let flip_tex_coords = v.boolean("flip_tex_coords")?.unwrap_or(false);
        self.mesh_file(v, m, flip, face_normals, |path, name| {
            let mut local = ply::load_ply(path, name)?;
            if let (true, Some(uvs)) = (flip_tex_coords, &mut local.uvs) {
                uvs.iter_mut().for_each(|uv| uv.y = 1.0 - uv.y);
            }
            Ok(local)
        })
    }

    /// `gltf` (project extension): every triangle primitive of a glTF 2.0 file's scene as one
    /// mesh (node transforms applied, then `to_world`), with this shape's BSDF; the file's
    /// materials, cameras and lights are not used. `filename` is resolved as for `obj`.
    pub(super) fn gltf(&self, v: &ObjectView<'_>, m: &Mat4, flip: bool) -> Result<Geometry> {
        let err = |msg: String| SceneError::at(&v.el.loc, msg);
        let name = v
            .string("filename")?
            .ok_or_else(|| err("missing <string name=\"filename\" .../>".into()))?;
        let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
        let mesh = crate::gltf::load_mesh(&path).map_err(err)?;
        let local = shapes::LocalMesh {
            positions: mesh.positions,
            normals: mesh.normals,
            uvs: mesh.uvs,
            indices: mesh.indices,
            attributes: mesh.attributes,
        };
        shapes::to_world(local, m, flip)
            .map(Geometry::Mesh)
            .map_err(|e| err(format!("mesh '{name}': {e}")))
    }

    /// `sdfgrid` (Mitsuba's): the one-channel grid of the `.vol` file `filename` (resolved as
    /// for `obj`) over the object space's unit cube; `normals` `smooth` (default) or
    /// `analytic`. `to_world` must be scales and a translation: Mitsuba warns against
    /// rotations (and asks for an `instance` instead), and pt refuses them and mirrors.
    /// `linearcurve` and `bsplinecurve`: the curve file `filename` (see [`crate::curves`]),
    /// positions through `to_world`.
    pub(super) fn curves(
        &self,
        v: &ObjectView<'_>,
        basis: CurveBasis,
        m: &Mat4,
    ) -> Result<Geometry> {
        let err = |msg: String| SceneError::at(&v.el.loc, msg);
        if v.has("flip_normals") {
            return Err(v.prop_error(
                "flip_normals",
                format!(
                    "a {} has no flip_normals (as in Mitsuba: its back faces are culled)",
                    v.plugin
                ),
            ));
        }
        let name = v.string("filename")?.ok_or_else(|| {
            err(
                "missing <string name=\"filename\" .../> (the curve file: x y z radius per line)"
                    .into(),
            )
        })?;
        let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
        let curves = crate::curves::load_curves(&path, &name, basis, m).map_err(err)?;
        Ok(Geometry::Curves(std::sync::Arc::new(curves)))
    }

    pub(super) fn sdfgrid(&self, v: &ObjectView<'_>, m: &Mat4) -> Result<Geometry> {
        let err = |msg: String| SceneError::at(&v.el.loc, msg);
        let smooth_normals = match v.string("normals")?.as_deref() {
            None | Some("smooth") => true,
            Some("analytic") => false,
            Some(other) => {
                return Err(v.prop_error(
                    "normals",
                    format!("normals \"{other}\" is not one of: smooth, analytic"),
                ))
            }
        };
        let name = v.string("filename")?.ok_or_else(|| {
            err("missing <string name=\"filename\" .../> (the grid's .vol file)".into())
        })?;
        let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
        let grid = crate::volgrid::load_vol(&path, &name).map_err(err)?;
        if grid.channels != 1 {
            return Err(err(format!(
                "grid '{name}' has {} channels; an sdfgrid needs 1",
                grid.channels
            )));
        }
        if let Some(n) = grid.resolution.iter().find(|&&n| n < 2) {
            return Err(err(format!(
                "grid '{name}' has {n} sample along an axis; an sdfgrid needs at least 2 (one voxel)"
            )));
        }
        if let Some(bad) = grid.values.iter().find(|x| !x.is_finite()) {
            return Err(err(format!("grid '{name}' holds the value {bad}")));
        }
        // Scales and a translation only: the diagonal positive, the rest zero (to rounding).
        let diag = Vec3::new(m.x_axis.x, m.y_axis.y, m.z_axis.z);
        let off = [
            m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.z, m.z_axis.x, m.z_axis.y,
        ];
        let tol = 1e-6 * diag.abs().max_element();
        if !(diag.min_element() > 0.0 && off.iter().all(|o| o.abs() <= tol) && diag.is_finite()) {
            return Err(v.prop_error(
                "to_world",
                "an sdfgrid's to_world must be positive scales and a translation (Mitsuba warns against rotations; place the shape with shapegroup/instance instead)",
            ));
        }
        let sdf = SdfGrid {
            resolution: grid.resolution,
            values: grid.values,
            origin: m.w_axis.truncate(),
            extent: diag,
            smooth_normals,
        };
        if sdf.occupied_voxels().next().is_none() {
            return Err(err(format!(
                "grid '{name}' has no voxel the surface passes through (no value >= 0 beside one <= 0; Mitsuba refuses it too)"
            )));
        }
        Ok(Geometry::SdfGrid(std::sync::Arc::new(sdf)))
    }

    /// A shape's nested BSDF (or `<ref>` to one), area emitter, and interior and exterior
    /// media, at most one of each.
    #[allow(clippy::type_complexity)]
    pub(super) fn shape_children(
        &mut self,
        v: &ObjectView<'e>,
    ) -> Result<(
        Option<usize>,
        Option<AreaEmitterDesc>,
        [Option<MediumDesc>; 2],
    )> {
        let (mut bsdf, mut emitter, mut interior, mut exterior) = (None, None, None, None);
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
                "sensor" if target.attr("type") != Some("irradiancemeter") => {
                    return Err(misplaced(child, target, v, "an irradiancemeter sensor"))
                }
                "sensor" if self.shape_sensor.is_some() => return Err(once("sensor")),
                "sensor" => {
                    let (camera, film, sampler, _) = self.sensor(target, true)?;
                    self.shape_sensor = Some((camera, film, sampler));
                }
                "medium" => {
                    let written = child.written();
                    match written.attr("name") {
                        Some("interior") if interior.is_some() => return Err(once("interior medium")),
                        Some("interior") => interior = Some(self.medium(target)?),
                        Some("exterior") if exterior.is_some() => return Err(once("exterior medium")),
                        Some("exterior") => exterior = Some(self.medium(target)?),
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
                _ => {
                    return Err(misplaced(
                        child,
                        target,
                        v,
                        "bsdf, emitter, medium or sensor",
                    ))
                }
            }
        }
        Ok((bsdf, emitter, [interior, exterior]))
    }
}

impl<'e> Builder<'e> {
    /// `homogeneous` or `heterogeneous` medium (Mitsuba 3.9.1): `sigma_t` (extinction per
    /// scene unit: float, rgb or spectrum, or for `heterogeneous` a nested `gridvolume` (one or
    /// three channels) or `constvolume` named sigma_t; default 1), `scale` (multiplies sigma_t;
    /// default 1), `albedo` (single scattering albedo in [0, 1]: float, rgb, spectrum, or a
    /// `constvolume` or `gridvolume` named albedo; Mitsuba's default 0.75), `sample_emitters`
    /// (default true), `has_spectral_extinction` (accepted: the estimate does not depend on
    /// it), a nested phase function ([`phase`]; isotropic by default), and pt's `emission`
    /// (volume emission, [`MediumDesc::emission`]: a spectrum, or a volume named emission; a
    /// grid only in a heterogeneous medium). A medium with an id is built once (its grids read
    /// once).
    pub(super) fn medium(&mut self, el: &Element) -> Result<MediumDesc> {
        if let Some(m) = el.attr("id").and_then(|id| self.medium_memo.get(id)) {
            return Ok(m.clone());
        }
        let m = self.build_medium(el)?;
        if let Some(id) = el.attr("id") {
            self.medium_memo.insert(id.to_string(), m.clone());
        }
        Ok(m)
    }

    fn build_medium(&mut self, el: &Element) -> Result<MediumDesc> {
        let v = ObjectView::parse(el)?;
        let heterogeneous = match v.plugin.as_str() {
            "homogeneous" => false,
            "heterogeneous" => true,
            _ => return Err(plugin_error(el)),
        };
        let nested = self.medium_children(&v, heterogeneous)?;
        let (sigma_t, density) = match nested.sigma_t {
            Some(_) if v.has("sigma_t") => return Err(given_twice(&v, "sigma_t")),
            Some(Volume::Grid(g)) => (SpectrumDesc::Constant(1.0), Some(g)),
            Some(Volume::Constant(c)) => (c, None),
            None => (
                v.spectrum("sigma_t")?
                    .unwrap_or(SpectrumDesc::Constant(1.0)),
                None,
            ),
        };
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
        let albedo = medium_albedo(&v, nested.albedo)?;
        let emission = medium_emission(&v, nested.emission, density.is_some())?;
        let sample_emitters = v.boolean("sample_emitters")?.unwrap_or(true);
        v.boolean("has_spectral_extinction")?;
        v.finish()?;
        Ok(MediumDesc {
            loc: el.loc.clone(),
            sigma_t: scaled_extinction(&v, sigma_t, scale)?,
            albedo,
            phase: nested.phase.unwrap_or(PhaseDesc::Isotropic),
            sample_emitters,
            density,
            emission,
        })
    }

    /// A medium's nested objects: at most one `<phase>` and one `<volume>` each for
    /// `sigma_t`, `albedo` and `emission`; grids of extinction or emission only in a
    /// `heterogeneous` medium.
    fn medium_children(
        &mut self,
        v: &ObjectView<'_>,
        heterogeneous: bool,
    ) -> Result<MediumChildren> {
        let mut nested = MediumChildren::default();
        for child in &v.children {
            let what = child.written();
            match what.tag.as_str() {
                "phase" if nested.phase.is_none() => nested.phase = Some(phase(what)?),
                "phase" => {
                    return Err(SceneError::at(
                        &what.loc,
                        "a medium takes only one phase function",
                    ))
                }
                "volume" => {
                    let (slot, role) = match what.attr("name") {
                        Some("sigma_t") => (&mut nested.sigma_t, GridRole::Extinction),
                        Some("albedo") => (&mut nested.albedo, GridRole::Albedo),
                        Some("emission") => (&mut nested.emission, GridRole::Emission),
                        other => {
                            return Err(SceneError::at(
                                &what.loc,
                                format!(
                                    "a medium's <volume> needs name=\"sigma_t\", name=\"albedo\" or name=\"emission\", got {}",
                                    other.map_or("none".to_string(), |n| format!("\"{n}\""))
                                ),
                            ))
                        }
                    };
                    if slot.is_some() {
                        return Err(SceneError::at(
                            &what.loc,
                            format!("a medium takes only one {}", role.name()),
                        ));
                    }
                    let volume = self.volume(what, role)?;
                    if !heterogeneous && matches!(volume, Volume::Grid(_)) {
                        match role {
                            GridRole::Albedo => {}
                            GridRole::Extinction => {
                                return Err(SceneError::at(
                                    &what.loc,
                                    "a homogeneous medium takes sigma_t as float, rgb, spectrum or constvolume, not a grid (use type=\"heterogeneous\" for grids)",
                                ))
                            }
                            GridRole::Emission => {
                                return Err(SceneError::at(
                                    &what.loc,
                                    "an emission grid needs a heterogeneous medium with an extinction grid (emission is confined to its box)",
                                ))
                            }
                        }
                    }
                    *slot = Some(volume);
                }
                _ => {
                    return Err(SceneError::at(
                        &what.loc,
                        format!("a medium takes a <phase> or <volume>, not <{}>", what.tag),
                    ))
                }
            }
        }
        Ok(nested)
    }

    /// A medium's `<volume>`: `constvolume` (`value`: float, rgb or spectrum; default 1) or
    /// `gridvolume` (`filename` of a Mitsuba .vol file with one or three channels,
    /// `filter_type` trilinear or nearest, `use_grid_bbox`, `to_world`; `raw` (false) and
    /// `accel` accepted). Values are checked for the parameter's `role`.
    fn volume(&mut self, el: &Element, role: GridRole) -> Result<Volume> {
        let v = ObjectView::parse(el)?;
        let err = |msg: String| SceneError::at(&el.loc, msg);
        let out = match v.plugin.as_str() {
            "constvolume" => {
                Volume::Constant(v.spectrum("value")?.unwrap_or(SpectrumDesc::Constant(1.0)))
            }
            "gridvolume" => {
                let name = v.string("filename")?.ok_or_else(|| {
                    err("missing <string name=\"filename\" .../> (the grid's .vol file)".into())
                })?;
                let path = resolve_file(&name, &el.dir, &[self.base_dir], self.search_paths);
                let grid = crate::volgrid::load_vol(&path, &name).map_err(err)?;
                if !matches!(grid.channels, 1 | 3) {
                    return Err(err(format!(
                        "grid '{name}' has {} channels; a medium's {} grid needs 1 or 3 (RGB)",
                        grid.channels,
                        role.name()
                    )));
                }
                let (lo, hi, range) = role.range();
                if let Some(bad) = grid
                    .values
                    .iter()
                    .find(|x| !(x.is_finite() && **x >= lo && **x <= hi))
                {
                    return Err(err(format!(
                        "grid '{name}' holds {bad}; {} must be {range}",
                        role.name()
                    )));
                }
                let nearest = match v.string("filter_type")?.as_deref() {
                    None | Some("trilinear") => false,
                    Some("nearest") => true,
                    Some(other) => {
                        return Err(v.prop_error(
                            "filter_type",
                            format!("filter_type \"{other}\" is not one of: trilinear, nearest"),
                        ))
                    }
                };
                match v.string("wrap_mode")?.as_deref() {
                    None | Some("clamp") => {}
                    Some(other) => {
                        return Err(v.prop_error(
                            "wrap_mode",
                            format!("wrap_mode \"{other}\" is not supported (only clamp, Mitsuba's default, is implemented)"),
                        ))
                    }
                }
                let mut to_world = v.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
                if v.boolean("use_grid_bbox")?.unwrap_or(false) {
                    let [lo, hi] = grid.bbox;
                    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
                    to_world *= Mat4::from_translation(lo) * Mat4::from_scale(hi - lo);
                }
                if to_world.determinant().abs() < 1e-12 || !to_world.is_finite() {
                    return Err(v.prop_error("to_world", "the grid's to_world is singular"));
                }
                if v.boolean("raw")?.unwrap_or(false) && grid.channels == 3 {
                    return Err(v.prop_error(
                        "raw",
                        "raw=\"true\" keeps three channels as data, which no medium parameter reads (Mitsuba refuses it too)",
                    ));
                }
                v.boolean("accel")?;
                Volume::Grid(std::sync::Arc::new(GridDesc {
                    grid,
                    to_world,
                    nearest,
                }))
            }
            _ => return Err(plugin_error(el)),
        };
        if let Some(child) = v.children.first() {
            return Err(SceneError::at(
                &child.written().loc,
                "a volume takes no nested objects",
            ));
        }
        v.finish()?;
        Ok(out)
    }
}

/// A medium's `<volume>` as read.
enum Volume {
    Constant(SpectrumDesc),
    Grid(std::sync::Arc<GridDesc>),
}

/// A medium's nested objects as read, before its properties.
#[derive(Default)]
struct MediumChildren {
    phase: Option<PhaseDesc>,
    sigma_t: Option<Volume>,
    albedo: Option<Volume>,
    emission: Option<Volume>,
}

/// The error of a medium parameter `name` given both as a value and as a `<volume>`.
fn given_twice(v: &ObjectView<'_>, name: &str) -> SceneError {
    v.prop_error(
        name,
        format!("{name} is given twice (a value and a <volume>)"),
    )
}

/// A medium's albedo: its `<volume>` or `albedo` property (Mitsuba's default 0.75); a
/// constant must lie in [0, 1] and not be an emission spectrum.
fn medium_albedo(v: &ObjectView<'_>, nested: Option<Volume>) -> Result<VolumeDesc> {
    // Mitsuba's default albedo.
    let albedo = match nested {
        Some(_) if v.has("albedo") => return Err(given_twice(v, "albedo")),
        Some(Volume::Constant(c)) => VolumeDesc::Constant(c),
        Some(Volume::Grid(g)) => VolumeDesc::Grid(g),
        None => VolumeDesc::Constant(
            v.spectrum("albedo")?
                .unwrap_or(SpectrumDesc::Constant(0.75)),
        ),
    };
    if let VolumeDesc::Constant(a) = &albedo {
        if a.values()
            .iter()
            .any(|x| !(x.is_finite() && (0.0..=1.0).contains(x)))
        {
            return Err(v.prop_error("albedo", "albedo must lie in [0, 1]"));
        }
        if let s @ (SpectrumDesc::Blackbody { .. } | SpectrumDesc::Illuminant { .. }) = a {
            return Err(v.prop_error(
                "albedo",
                format!("albedo cannot be an emission spectrum ({})", s.form_name()),
            ));
        }
    }
    Ok(albedo)
}

/// A medium's emission (pt extension): its `<volume>` (a grid only beside an extinction
/// grid, `has_density`) or `emission` property, none by default; a constant must be finite
/// and >= 0.
fn medium_emission(
    v: &ObjectView<'_>,
    nested: Option<Volume>,
    has_density: bool,
) -> Result<Option<VolumeDesc>> {
    let emission = match nested {
        Some(_) if v.has("emission") => return Err(given_twice(v, "emission")),
        Some(Volume::Constant(c)) => Some(VolumeDesc::Constant(c)),
        Some(Volume::Grid(g)) if has_density => Some(VolumeDesc::Grid(g)),
        Some(Volume::Grid(_)) => {
            return Err(SceneError::at(
                &v.el.loc,
                "an emission grid needs an extinction grid (a <volume type=\"gridvolume\" name=\"sigma_t\">): emission is confined to its box",
            ))
        }
        None => v.spectrum("emission")?.map(VolumeDesc::Constant),
    };
    if let Some(VolumeDesc::Constant(e)) = &emission {
        if e.values().iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(v.prop_error("emission", "emission must be finite and >= 0"));
        }
    }
    Ok(emission)
}

/// A medium's extinction `sigma_t` times its `scale` (measured spectra become tabulated ones);
/// an emission spectrum is refused.
fn scaled_extinction(
    v: &ObjectView<'_>,
    sigma_t: SpectrumDesc,
    scale: f32,
) -> Result<SpectrumDesc> {
    Ok(match sigma_t {
        SpectrumDesc::Constant(c) => SpectrumDesc::Constant(c * scale),
        SpectrumDesc::Uniform(c) => SpectrumDesc::Uniform(c * scale),
        SpectrumDesc::Rgb(c) => SpectrumDesc::Rgb(c.map(|x| x * scale)),
        SpectrumDesc::Tabulated(p) => SpectrumDesc::Tabulated(std::sync::Arc::new(
            p.iter().map(|&(w, x)| (w, x * scale)).collect(),
        )),
        SpectrumDesc::Measured(p) => SpectrumDesc::Tabulated(std::sync::Arc::new(
            p.iter().map(|&(w, x)| (w, x * scale)).collect(),
        )),
        s @ (SpectrumDesc::Blackbody { .. } | SpectrumDesc::Illuminant { .. }) => {
            return Err(v.prop_error(
                "sigma_t",
                format!("sigma_t cannot be an emission spectrum ({})", s.form_name()),
            ));
        }
    })
}

/// Which medium parameter a `<volume>` gives.
#[derive(Clone, Copy)]
enum GridRole {
    Extinction,
    Albedo,
    Emission,
}

impl GridRole {
    /// The parameter's name.
    fn name(self) -> &'static str {
        match self {
            GridRole::Extinction => "sigma_t",
            GridRole::Albedo => "albedo",
            GridRole::Emission => "emission",
        }
    }

    /// The values a grid may hold, and how an error says it.
    fn range(self) -> (f32, f32, &'static str) {
        match self {
            GridRole::Albedo => (0.0, 1.0, "in [0, 1]"),
            GridRole::Extinction | GridRole::Emission => (0.0, f32::INFINITY, "finite and >= 0"),
        }
    }
}

/// A phase function: `isotropic`, `hg` with `g` (default 0.8, Mitsuba's) in (-1, 1),
/// `rayleigh` (no parameters), `tabphase` (`values`: a string of numbers), or `blendphase` of
/// two nested ones with a constant `weight` (default 0.5) in [0, 1].
fn phase(el: &Element) -> Result<PhaseDesc> {
    let v = ObjectView::parse(el)?;
    let p = match v.plugin.as_str() {
        "isotropic" => PhaseDesc::Isotropic,
        "rayleigh" => PhaseDesc::Rayleigh,
        "tabphase" => {
            let text = v
                .string("values")?
                .ok_or_else(|| SceneError::at(&el.loc, "a tabphase needs <string name=\"values\" value=\"...\"/> (the phase function at evenly spaced cosines from -1 to 1)"))?;
            let values = text
                .split([',', ' ', '\t', '\n', '\r'])
                .filter(|t| !t.is_empty())
                .map(|t| t.parse::<f32>().map_err(|_| t.to_string()))
                .collect::<std::result::Result<Vec<f32>, String>>()
                .map_err(|t| v.prop_error("values", format!("'{t}' is not a number")))?;
            if values.len() < 2 {
                return Err(v.prop_error(
                    "values",
                    format!("a tabphase needs at least two values, got {}", values.len()),
                ));
            }
            if let Some(bad) = values.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                return Err(v.prop_error(
                    "values",
                    format!("values must be finite and >= 0, got {bad}"),
                ));
            }
            if values.iter().all(|&x| x == 0.0) {
                return Err(v.prop_error("values", "values are all 0: no phase function"));
            }
            PhaseDesc::Tabulated(values)
        }
        "hg" => {
            let g = v.float("g")?.unwrap_or(0.8);
            if !(g > -1.0 && g < 1.0) {
                return Err(v.prop_error("g", format!("g must lie in (-1, 1), got {g}")));
            }
            PhaseDesc::HenyeyGreenstein { g }
        }
        "blendphase" => {
            let weight = v.float("weight")?.unwrap_or(0.5);
            if !(0.0..=1.0).contains(&weight) {
                return Err(
                    v.prop_error("weight", format!("weight must lie in [0, 1], got {weight}"))
                );
            }
            let [first, second] = v.children.as_slice() else {
                return Err(SceneError::at(
                    &el.loc,
                    format!(
                        "a blendphase needs exactly two nested phase functions, found {} (a textured weight is not supported: give a float)",
                        v.children.len()
                    ),
                ));
            };
            let nested = |c: &Child<'_>| -> Result<PhaseDesc> {
                match *c {
                    Child::Object(e) if e.tag == "phase" => phase(e),
                    Child::Object(e) => Err(SceneError::at(
                        &e.loc,
                        format!("a blendphase nests phase functions, not <{}>", e.tag),
                    )),
                    Child::Ref(e) => Err(SceneError::at(
                        &e.loc,
                        "a blendphase's phase functions are written inside it (a <ref> to one is not supported)",
                    )),
                }
            };
            let (first, second) = (nested(first)?, nested(second)?);
            v.finish()?;
            return Ok(PhaseDesc::Blend {
                weight,
                first: Box::new(first),
                second: Box::new(second),
            });
        }
        _ => return Err(plugin_error(el)),
    };
    if let Some(child) = v.children.first() {
        return Err(SceneError::at(
            &child.written().loc,
            "a phase function takes no nested objects",
        ));
    }
    v.finish()?;
    Ok(p)
}
