//! Sensor, film, reconstruction filter and sampler.

use super::*;

impl<'e> Builder<'e> {
    /// `perspective`, `thinlens` (see [`perspective`]), `orthographic` (see
    /// [`orthographic`]) or `radiancemeter` at the top level, or `irradiancemeter` nested in a
    /// shape (`in_shape`), with its film, sampler and the medium it sits in.
    pub(super) fn sensor(
        &mut self,
        el: &'e Element,
        in_shape: bool,
    ) -> Result<(CameraDesc, FilmDesc, SamplerDesc, Option<MediumDesc>)> {
        let v = ObjectView::parse(el)?;
        let camera =
            match v.plugin.as_str() {
                "irradiancemeter" if !in_shape => return Err(SceneError::at(
                    &el.loc,
                    "an irradiancemeter must be nested in the <shape> it measures, as in Mitsuba",
                )),
                // The scene numbers the shape, when it knows where the shape goes.
                "irradiancemeter" => CameraDesc {
                    loc: el.loc.clone(),
                    projection: Projection::Irradiancemeter { shape: usize::MAX },
                    to_world: Mat4::IDENTITY,
                    near_clip: 0.0,
                    far_clip: f32::INFINITY,
                    principal_point_offset: [0.0; 2],
                },
                "perspective" | "thinlens" => perspective(&v)?,
                "orthographic" => orthographic(&v)?,
                "radiancemeter" => radiancemeter(&v)?,
                "distant" => distant(&v)?,
                "batch" => CameraDesc {
                    loc: el.loc.clone(),
                    projection: Projection::Batch,
                    to_world: Mat4::IDENTITY,
                    near_clip: 0.0,
                    far_clip: f32::INFINITY,
                    principal_point_offset: [0.0; 2],
                },
                _ => return Err(plugin_error(el)),
            };
        let (mut film, mut sampler, mut medium) = (None, None, None);
        let mut target_shape = None;
        for child in &v.children {
            let target = self.resolve(child)?;
            match target.tag.as_str() {
                "sensor" if v.plugin == "batch" => {
                    // Its film, sampler and medium are not read: the batch's film is split
                    // among its sensors (as in Mitsuba).
                    let (inner, _, _, medium) = self.sensor(target, false)?;
                    let projective = matches!(
                        inner.projection,
                        Projection::Perspective { .. }
                            | Projection::ThinLens { .. }
                            | Projection::Orthographic
                    );
                    if !projective || medium.is_some() {
                        return Err(SceneError::at(
                            &child.written().loc,
                            "a batch holds perspective, thinlens and orthographic sensors without media (not yet implemented otherwise)",
                        ));
                    }
                    self.batch.push(inner);
                }
                "shape" if v.plugin == "distant" && target_shape.is_none() => {
                    if v.has("target") {
                        return Err(SceneError::at(
                            &child.written().loc,
                            "give the distant sensor's target as a point or a shape, not both",
                        ));
                    }
                    target_shape = Some(self.shape(target)?);
                }
                "film" if film.is_none() => film = Some(self.film(target)?),
                "sampler" if sampler.is_none() => sampler = Some(sampler_desc(target)?),
                "medium" if medium.is_none() => medium = Some(self.medium(target)?),
                "film" | "sampler" | "medium" => {
                    return Err(SceneError::at(
                        &child.written().loc,
                        format!("a sensor takes only one <{}>", target.tag),
                    ))
                }
                _ => return Err(misplaced(child, target, &v, "film, sampler or medium")),
            }
        }
        v.finish()?;
        if camera.projection == Projection::Batch {
            let width = film.as_ref().map_or(default_film().width, |f| f.width);
            let n = self.batch.len() as u32;
            if n == 0 {
                return Err(SceneError::at(
                    &el.loc,
                    "a batch sensor needs nested sensors",
                ));
            }
            if width % n != 0 {
                return Err(SceneError::at(
                    &el.loc,
                    format!(
                        "the batch's film width ({width}) must be divisible by its number of sensors ({n}), as in Mitsuba"
                    ),
                ));
            }
            if film.as_ref().is_some_and(|f| f.crop.is_some()) || medium.is_some() {
                return Err(SceneError::at(
                    &el.loc,
                    "a batch sensor with a crop window or a medium is not yet supported (not yet implemented)",
                ));
            }
        }
        let camera = match (camera, target_shape) {
            (c, None) => c,
            (c, Some(shape)) => {
                self.sensor_target = Some(shape);
                CameraDesc {
                    projection: Projection::Distant {
                        target: DistantTarget::Shape,
                    },
                    ..c
                }
            }
        };
        if matches!(
            camera.projection,
            Projection::Radiancemeter
                | Projection::Irradiancemeter { .. }
                | Projection::Distant { .. }
        ) {
            // Mitsuba throws for any other film size.
            match &film {
                Some(f) if f.width == 1 && f.height == 1 => {}
                _ => {
                    return Err(SceneError::at(
                        &el.loc,
                        format!("the {} sensor needs a 1 x 1 film (<film type=\"hdrfilm\"> with width and height 1), as in Mitsuba", v.plugin),
                    ))
                }
            }
        }
        if medium.is_some() && matches!(camera.projection, Projection::Irradiancemeter { .. }) {
            return Err(SceneError::at(
                &el.loc,
                "an irradiancemeter sits on its shape: give the shape an exterior medium instead",
            ));
        }
        Ok((
            camera,
            film.unwrap_or_else(default_film),
            sampler.unwrap_or_else(default_sampler),
            medium,
        ))
    }

    /// `hdrfilm`: `width` (768), `height` (576), the crop window ([`crop_window`]), nested
    /// `rfilter` (gaussian), `pixel_format` (rgb), `sample_border` (false). The file and
    /// component formats are accepted when valid and ignored (pt writes float32 OpenEXR).
    pub(super) fn film(&mut self, el: &'e Element) -> Result<FilmDesc> {
        let v = ObjectView::parse(el)?;
        if v.plugin != "hdrfilm" {
            return Err(plugin_error(el));
        }
        let width = int_in(&v, "width", 768, 1, 1 << 16)? as u32;
        let height = int_in(&v, "height", 576, 1, 1 << 16)? as u32;
        let pixel_format = match v.string("pixel_format")? {
            None => PixelFormat::default(),
            Some(s) => PixelFormat::NAMES
                .iter()
                .find(|(n, _)| s.eq_ignore_ascii_case(n))
                .map(|(_, f)| *f)
                .ok_or_else(|| {
                    let names: Vec<&str> = PixelFormat::NAMES.iter().map(|(n, _)| *n).collect();
                    v.prop_error(
                        "pixel_format",
                        format!(
                            "'pixel_format' must be one of {}, not \"{s}\"",
                            names.join(", ")
                        ),
                    )
                })?,
        };
        one_of(&v, "component_format", &["float16", "float32", "uint32"])?;
        one_of(&v, "file_format", &["openexr", "exr", "rgbe", "pfm"])?;
        v.boolean("banner")?;
        let (crop, [width, height]) = crop_window(&v, width, height)?;
        let sample_border = v.boolean("sample_border")?.unwrap_or(false);
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
            crop,
            filter: filter.unwrap_or(DEFAULT_FILTER),
            sample_border,
            reconstruction: Reconstruction::Splat,
            pixel_format,
        })
    }
}

/// `perspective` and `thinlens`: `fov` (degrees, along `fov_axis`: x, y, diagonal, smaller or
/// larger; default x) or `focal_length` ("50mm" style, on a 36 x 24 mm film's diagonal; default
/// 50mm), `near_clip` (1e-2), `far_clip` (1e4), `to_world` (rotation and translation only, as in
/// Mitsuba; a mirroring `scale x="-1"` is allowed), `focus_distance` (accepted, no effect on a
/// pinhole). `thinlens` also: `aperture_radius` (required, >= 0) and `focus_distance` (default
/// `far_clip`, as in Mitsuba).
pub(super) fn perspective(v: &ObjectView<'_>) -> Result<CameraDesc> {
    let projection = projection(v)?;
    let near_clip = positive(v, "near_clip", 1e-2)?;
    let far_clip = positive(v, "far_clip", 1e4)?;
    if near_clip >= far_clip {
        return Err(v.prop_error("near_clip", "near_clip must be smaller than far_clip"));
    }
    let projection = if v.plugin == "thinlens" {
        let Projection::Perspective { fov_deg, fov_axis } = projection else {
            unreachable!("projection() gives a perspective")
        };
        let aperture_radius = v.float("aperture_radius")?.ok_or_else(|| {
            SceneError::at(
                &v.el.loc,
                "thinlens needs <float name=\"aperture_radius\" .../>",
            )
        })?;
        if !(aperture_radius >= 0.0) {
            return Err(v.prop_error(
                "aperture_radius",
                format!("aperture_radius must be >= 0, got {aperture_radius}"),
            ));
        }
        Projection::ThinLens {
            fov_deg,
            fov_axis,
            aperture_radius,
            // Mitsuba's default: in focus at the far clip plane.
            focus_distance: positive(v, "focus_distance", far_clip)?,
        }
    } else {
        // Accepted and ignored on a pinhole, as in Mitsuba.
        v.float("focus_distance")?;
        projection
    };
    // Mitsuba reads the principal point offset in `perspective` only (not `thinlens`).
    let mut principal_point_offset = [0.0f32; 2];
    if v.plugin == "perspective" {
        for (axis, name) in ["principal_point_offset_x", "principal_point_offset_y"]
            .into_iter()
            .enumerate()
        {
            let value = v.float(name)?.unwrap_or(0.0);
            if !value.is_finite() {
                return Err(v.prop_error(name, format!("'{name}' must be finite, got {value}")));
            }
            principal_point_offset[axis] = value;
        }
    }
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
        principal_point_offset,
    })
}

/// `orthographic`: `near_clip` (1e-2), `far_clip` (1e4), `to_world` (affine; its scale sets the
/// film's extent in the scene).
pub(super) fn orthographic(v: &ObjectView<'_>) -> Result<CameraDesc> {
    let near_clip = positive(v, "near_clip", 1e-2)?;
    let far_clip = positive(v, "far_clip", 1e4)?;
    if near_clip >= far_clip {
        return Err(v.prop_error("near_clip", "near_clip must be smaller than far_clip"));
    }
    let to_world = v.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
    if !is_affine(&to_world) || Mat3::from_mat4(to_world).determinant() == 0.0 {
        return Err(v.prop_error(
            "to_world",
            "the camera's to_world must be affine and invertible",
        ));
    }
    Ok(CameraDesc {
        loc: v.el.loc.clone(),
        projection: Projection::Orthographic,
        to_world,
        near_clip,
        far_clip,
        principal_point_offset: [0.0; 2],
    })
}

/// `radiancemeter`: the ray from `origin` along `direction` (points; default the origin and
/// +z), or, instead of them, `to_world` (rotation and translation: the ray is camera +z from its
/// origin), as Mitsuba reads it.
pub(super) fn radiancemeter(v: &ObjectView<'_>) -> Result<CameraDesc> {
    Ok(CameraDesc {
        loc: v.el.loc.clone(),
        projection: Projection::Radiancemeter,
        to_world: ray_frame(v, "a radiancemeter", true)?,
        near_clip: 0.0,
        far_clip: f32::INFINITY,
        principal_point_offset: [0.0; 2],
    })
}

/// The frame of a sensor that looks along one direction, its +z (Mitsuba's `radiancemeter` and
/// `distant`): `to_world` (rotation and translation only), or instead `direction` (a finite,
/// non-zero vector; default +z) from `origin` (a point; default the origin; read only
/// `with_origin`). `sensor` names it in errors.
fn ray_frame(v: &ObjectView<'_>, sensor: &str, with_origin: bool) -> Result<Mat4> {
    let placed = v.has("direction") || (with_origin && v.has("origin"));
    match v.transform("to_world")? {
        Some(m) => {
            if placed {
                return Err(v.prop_error(
                    "to_world",
                    if with_origin {
                        "give either to_world or origin and direction, not both (Mitsuba refuses both)"
                    } else {
                        "give either to_world or direction, not both (Mitsuba refuses both)"
                    },
                ));
            }
            if !is_affine(&m) || has_scale(&m) || Mat3::from_mat4(m).determinant() == 0.0 {
                return Err(v.prop_error(
                    "to_world",
                    format!("{sensor}'s to_world may only rotate and translate"),
                ));
            }
            Ok(m)
        }
        None => {
            let origin = if with_origin {
                v.vec3("origin")?.unwrap_or(Vec3::ZERO)
            } else {
                Vec3::ZERO
            };
            let dir = v.vec3("direction")?.unwrap_or(Vec3::Z);
            if !(dir.length_squared() > 0.0 && dir.is_finite() && origin.is_finite()) {
                return Err(v.prop_error(
                    "direction",
                    format!("{sensor}'s direction must be a finite, non-zero vector"),
                ));
            }
            let z = dir.normalize();
            // Any frame whose +z is the direction: the sensor's rays depend on it alone.
            let (x, y) = z.any_orthonormal_pair();
            Ok(Mat4::from_cols(
                x.extend(0.0),
                y.extend(0.0),
                z.extend(0.0),
                origin.extend(1.0),
            ))
        }
    }
}

/// Mitsuba's `distant`: parallel rays along `direction` (a vector; default +z), or instead
/// along `to_world`'s +z (rotation and translation only), aimed at `target` (a point; a nested
/// shape is read by the sensor; default the scene's bounding disk, [`DistantTarget`]).
pub(super) fn distant(v: &ObjectView<'_>) -> Result<CameraDesc> {
    let to_world = ray_frame(v, "a distant sensor", false)?;
    let target = match v.vec3("target")? {
        Some(p) if p.is_finite() => DistantTarget::Point(p),
        Some(_) => return Err(v.prop_error("target", "the target must be a finite point")),
        None => DistantTarget::BoundingDisk,
    };
    Ok(CameraDesc {
        loc: v.el.loc.clone(),
        projection: Projection::Distant { target },
        to_world,
        near_clip: 0.0,
        far_clip: f32::INFINITY,
        principal_point_offset: [0.0; 2],
    })
}

/// Mitsuba's `has_scale`: some axis changes length.
pub(super) fn has_scale(m: &Mat4) -> bool {
    let l = Mat3::from_mat4(*m);
    [l.x_axis, l.y_axis, l.z_axis]
        .iter()
        .any(|c| (c.length_squared() - 1.0).abs() > 1e-3)
}

pub(super) fn projection(v: &ObjectView<'_>) -> Result<Projection> {
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
pub(super) const DEFAULT_FILTER: FilterDesc = FilterDesc::Gaussian { stddev: 0.5 };

/// `box` (no parameters: radius 0.5), `tent` (`radius`, 1), `gaussian` (`stddev`, 0.5),
/// `mitchell` (`B`, `C`, both 1/3), `catmullrom` (no parameters), `lanczos` (`lobes`, 3).
pub(super) fn rfilter(el: &Element) -> Result<FilterDesc> {
    let v = ObjectView::parse(el)?;
    let filter = match v.plugin.as_str() {
        "box" => FilterDesc::Box { radius: 0.5 },
        "tent" => FilterDesc::Tent {
            radius: positive(&v, "radius", 1.0)?,
        },
        "gaussian" => FilterDesc::Gaussian {
            stddev: positive(&v, "stddev", 0.5)?,
        },
        "mitchell" => FilterDesc::Mitchell {
            b: finite(&v, "B", 1.0 / 3.0)?,
            c: finite(&v, "C", 1.0 / 3.0)?,
        },
        "catmullrom" => FilterDesc::Mitchell { b: 0.0, c: 0.5 },
        "lanczos" => FilterDesc::Lanczos {
            lobes: int_in(&v, "lobes", 3, 1, 64)? as f32,
        },
        _ => return Err(plugin_error(el)),
    };
    no_children(&v)?;
    v.finish()?;
    Ok(filter)
}

/// `independent`, `stratified`, `multijitter`, `orthogonal` and `ldsampler` (`sample_count` 4,
/// `seed` 0; `jitter` true for the first three, `strength` 2 for `orthogonal`). The count is
/// rounded as Mitsuba rounds it ([`SamplerKind::round_count`]).
pub(super) fn sampler_desc(el: &Element) -> Result<SamplerDesc> {
    let v = ObjectView::parse(el)?;
    let requested = int_in(&v, "sample_count", 4, 1, u32::MAX as i64)? as u32;
    let seed = int_in(&v, "seed", 0, 0, i64::MAX)? as u64;
    let jitter = |v: &ObjectView<'_>| -> Result<bool> { Ok(v.boolean("jitter")?.unwrap_or(true)) };
    let kind = match v.plugin.as_str() {
        "independent" => SamplerKind::Independent,
        "stratified" => SamplerKind::Stratified {
            jitter: jitter(&v)?,
        },
        "multijitter" => SamplerKind::MultiJitter {
            jitter: jitter(&v)?,
        },
        "orthogonal" => {
            let strength = int_in(&v, "strength", 2, 1, i64::from(u32::MAX))?;
            if strength != 2 {
                return Err(v.prop_error(
                    "strength",
                    format!("orthogonal arrays of strength {strength} (Bush's construction) are not yet supported (not yet implemented): strength 2 is"),
                ));
            }
            SamplerKind::Orthogonal {
                jitter: jitter(&v)?,
            }
        }
        "ldsampler" => SamplerKind::LowDiscrepancy,
        _ => return Err(plugin_error(el)),
    };
    no_children(&v)?;
    v.finish()?;
    Ok(SamplerDesc {
        sample_count: kind.round_count(requested),
        seed,
        kind,
    })
}

/// Mitsuba's camera for scenes without a sensor: 45 degrees on x, looking along +z from in
/// front of the scene's bounding box, far enough to see all of it.
pub(super) fn default_camera(root: &Element, shapes: &[ShapeDesc]) -> CameraDesc {
    let mut camera = CameraDesc {
        loc: root.loc.clone(),
        projection: Projection::Perspective {
            fov_deg: 45.0,
            fov_axis: FovAxis::X,
        },
        to_world: Mat4::IDENTITY,
        near_clip: 1e-2,
        far_clip: 1e4,
        principal_point_offset: [0.0; 2],
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
pub(super) fn bounds(shapes: &[ShapeDesc]) -> Option<(Vec3, Vec3)> {
    let mut acc: Option<(Vec3, Vec3)> = None;
    let mut add = |p: Vec3| {
        acc = Some(acc.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
    };
    for shape in shapes {
        match &shape.geometry {
            Geometry::Mesh(m) => m.positions.iter().for_each(|&p| add(p)),
            Geometry::Disk(d) => {
                let (lo, hi) = d.bounds();
                add(lo);
                add(hi);
            }
            Geometry::Sphere { center, radius, .. } => {
                add(*center - *radius);
                add(*center + *radius);
            }
            &Geometry::Cylinder {
                p0,
                frame,
                radius,
                length,
                ..
            } => {
                let (lo, hi) = crate::shapes::cylinder_bounds(p0, frame.z_axis, radius, length);
                add(lo);
                add(hi);
            }
            Geometry::SdfGrid(g) => {
                add(g.origin);
                add(g.origin + g.extent);
            }
            Geometry::Curves(c) => {
                let (lo, hi) = c.bounds();
                add(lo);
                add(hi);
            }
        }
    }
    acc
}
