//! Emitters: `area` on shapes, and the lights on their own.

use super::*;
use crate::error::io_message;

impl<'e> Builder<'e> {
    pub(super) fn top_level_emitter(&self, el: &Element) -> SceneError {
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
    /// `envmap` (`filename`, `scale` 1, `to_world`), `projector` (`irradiance` 1 or a nested
    /// texture, `scale` 1, `fov`/`fov_axis`/`focal_length` as a camera's, `to_world`); a spot
    /// may carry a nested `<texture name="texture">`. Photometric lights (pt extensions):
    /// `point` and `spot` take `ies` (an IES file) and `scale`; `goniometric` takes `filename`
    /// (an `.ies` file or an equirectangular EXR of intensity factors), `intensity`, `scale`,
    /// `to_world`.
    pub(super) fn light(&mut self, el: &'e Element) -> Result<LightDesc> {
        let v = ObjectView::parse(el)?;
        let to_world = v.transform("to_world")?;
        let texture = self.light_texture(&v)?;
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
                let profile = self.ies_profile(&v, to_world)?;
                LightKind::Point {
                    position,
                    intensity: light_spectrum(&v, "intensity")?,
                    profile,
                }
            }
            "goniometric" => self.goniometric(&v, to_world)?,
            "spot" => self.spot(&v, to_world, texture)?,
            "projector" => projector(&v, to_world, texture)?,
            "directional" => LightKind::Directional {
                direction: light_direction(&v, to_world)?,
                irradiance: light_spectrum(&v, "irradiance")?,
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
                    direction: light_direction(&v, to_world)?,
                    irradiance: light_spectrum(&v, "irradiance")?,
                    angular_diameter_deg,
                }
            }
            "constant" => LightKind::Constant {
                radiance: light_spectrum(&v, "radiance")?,
            },
            "sunsky" => LightKind::SunSky(Box::new(super::sunsky::sunsky(&v, to_world)?)),
            "envmap" => {
                let name = v
                    .string("filename")?
                    .ok_or_else(|| SceneError::at(&el.loc, "envmap needs a filename"))?;
                let path = self.light_file(&v, "filename", "environment map ", &name)?;
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
        v.finish()?;
        Ok(LightDesc {
            loc: el.loc.clone(),
            kind,
        })
    }

    /// A light's nested texture with the location it was written at: a spot's `texture`, a
    /// projector's `irradiance` (plain textures in Mitsuba 3.9.1, not wrapped in D65); any
    /// other child is an error, and so is a spatially varying `intensity`.
    fn light_texture(
        &mut self,
        v: &ObjectView<'e>,
    ) -> Result<Option<(TextureDesc, &'e SourceLoc)>> {
        let wanted = match v.plugin.as_str() {
            "spot" => Some("texture"),
            "projector" => Some("irradiance"),
            _ => None,
        };
        let mut texture = None;
        for child in &v.children {
            let t = self.resolve(child)?;
            let name = child.written().attr("name").or_else(|| t.attr("name"));
            if t.tag == "texture" && name == Some("intensity") && v.plugin != "projector" {
                // Mitsuba's rule for point and spot lights: no surface to look a texture up on.
                return Err(SceneError::at(
                    &child.written().loc,
                    format!(
                        "the intensity of {} cannot be a texture that varies over space (Mitsuba refuses it too): give a number, <rgb> or <spectrum>",
                        v.what()
                    ),
                ));
            }
            match wanted {
                Some(w) if t.tag == "texture" && name == Some(w) && texture.is_none() => {
                    texture = Some((
                        self.texture(t)?.expect("a texture element gives a texture"),
                        &child.written().loc,
                    ));
                }
                Some(w) if t.tag == "texture" => {
                    return Err(SceneError::at(
                        &child.written().loc,
                        format!(
                            "{} takes one <texture name=\"{w}\">, not name=\"{}\"",
                            v.what(),
                            name.unwrap_or_default()
                        ),
                    ))
                }
                Some(w) => {
                    return Err(misplaced(
                        child,
                        t,
                        v,
                        &format!("one <texture name=\"{w}\">"),
                    ))
                }
                None => no_children(v)?,
            }
        }
        Ok(texture)
    }

    /// A `goniometric` light: a point light whose intensity an IES file or an equirectangular
    /// image of factors shapes.
    fn goniometric(&self, v: &ObjectView<'e>, to_world: Option<Mat4>) -> Result<LightKind> {
        let to_world = to_world.unwrap_or(Mat4::IDENTITY);
        let name = v.string("filename")?.ok_or_else(|| {
            SceneError::at(
                &v.el.loc,
                "goniometric needs a filename (an .ies file or an equirectangular EXR image)",
            )
        })?;
        let scale = self.profile_scale(v)?;
        let path = self.light_file(v, "filename", "", &name)?;
        let source = if is_ies(&name) {
            ProfileSource::Ies(self.read_ies(v, "filename", &name, &path)?)
        } else {
            ProfileSource::Image(path)
        };
        Ok(LightKind::Point {
            position: to_world.transform_point3(Vec3::ZERO),
            intensity: light_spectrum(v, "intensity")?,
            profile: Some(Box::new(IntensityProfile {
                source,
                to_world: profile_rotation(v, &to_world)?,
                scale,
            })),
        })
    }

    /// A `spot` light with its optional `texture` (which must vary) and IES profile.
    fn spot(
        &self,
        v: &ObjectView<'e>,
        to_world: Option<Mat4>,
        texture: Option<(TextureDesc, &SourceLoc)>,
    ) -> Result<LightKind> {
        let cutoff_deg = v.float("cutoff_angle")?.unwrap_or(20.0);
        if !(cutoff_deg > 0.0 && cutoff_deg <= 180.0) {
            return Err(v.prop_error("cutoff_angle", "cutoff_angle must be in (0, 180] degrees"));
        }
        let beam_width_deg = v.float("beam_width")?.unwrap_or(cutoff_deg * 0.75);
        if !(beam_width_deg >= 0.0 && beam_width_deg <= cutoff_deg) {
            return Err(v.prop_error(
                "beam_width",
                "beam_width must be in [0, cutoff_angle] degrees",
            ));
        }
        let texture = match texture {
            Some((TextureDesc::Constant(_), loc)) => {
                return Err(SceneError::at(
                    loc,
                    "a spot's texture must vary over the image (Mitsuba refuses a constant one): give a constant as the intensity",
                ))
            }
            t => t.map(|(t, _)| t),
        };
        Ok(LightKind::Spot {
            to_world: to_world.unwrap_or(Mat4::IDENTITY),
            intensity: light_spectrum(v, "intensity")?,
            cutoff_deg,
            beam_width_deg,
            texture,
            profile: self.ies_profile(v, to_world)?,
        })
    }

    /// A point or spot light's IES profile (pt extension: `<string name="ies" value="lamp.ies"/>`,
    /// with `scale`, default 1), oriented by the light's `to_world`.
    fn ies_profile(
        &self,
        v: &ObjectView<'e>,
        to_world: Option<Mat4>,
    ) -> Result<Option<Box<IntensityProfile>>> {
        let Some(name) = v.string("ies")? else {
            return Ok(None);
        };
        let scale = self.profile_scale(v)?;
        let path = self.light_file(v, "ies", "", &name)?;
        let table = self.read_ies(v, "ies", &name, &path)?;
        Ok(Some(Box::new(IntensityProfile {
            source: ProfileSource::Ies(table),
            to_world: profile_rotation(v, &to_world.unwrap_or(Mat4::IDENTITY))?,
            scale,
        })))
    }

    /// A profile's `scale`: finite, not negative, default 1.
    fn profile_scale(&self, v: &ObjectView<'e>) -> Result<f32> {
        let scale = v.float("scale")?.unwrap_or(1.0);
        if !(scale >= 0.0 && scale.is_finite()) {
            return Err(v.prop_error("scale", "scale must be finite and not negative"));
        }
        Ok(scale)
    }

    /// The file a light's parameter `prop` names (an environment map, an IES file, a
    /// goniometric image), resolved as meshes are; an error naming the property if it is
    /// missing. `what` (with a trailing space, or empty) says what the file is in the message.
    fn light_file(
        &self,
        v: &ObjectView<'e>,
        prop: &str,
        what: &str,
        name: &str,
    ) -> Result<PathBuf> {
        let path = resolve_file(name, &v.el.dir, &[self.base_dir], self.search_paths);
        if !path.is_file() {
            return Err(v.prop_error(
                prop,
                format!("cannot open {what}'{name}' (looked for {})", path.display()),
            ));
        }
        Ok(path)
    }

    /// Reads and parses an IES file; its errors name the file's line and the property.
    fn read_ies(
        &self,
        v: &ObjectView<'e>,
        prop: &str,
        name: &str,
        path: &Path,
    ) -> Result<IntensityTable> {
        let bytes = std::fs::read(path).map_err(|e| {
            v.prop_error(
                prop,
                format!("cannot read IES file '{name}': {}", io_message(&e)),
            )
        })?;
        // Keyword lines may hold Latin-1 text; the numbers are ASCII either way.
        let text = String::from_utf8_lossy(&bytes);
        crate::ies::parse_ies(&text).map_err(|e| {
            v.prop_error(
                prop,
                format!("IES file '{name}', line {}: {}", e.line, e.message),
            )
        })
    }

    /// `area`: `radiance` (rgb, spectrum or float; Mitsuba's default 1), or a nested
    /// `<texture name="radiance">` (any texture; for an image-emitting surface such as a
    /// monitor, a bitmap), optionally wrapped in Mitsuba's `<texture type="d65">` (see
    /// [`Builder::emission_texture`]).
    ///
    /// Display primaries (pt extension, with a radiance bitmap only): three spectra
    /// `<spectrum name="primary_r" filename="lcd-r.spd"/>`, `primary_g`, `primary_b` (any
    /// spectral form: pairs, a file, blackbody, a named illuminant). In spectral mode a texel of
    /// linear RGB (r, g, b) then emits `r k_r P_r + g k_g P_g + b k_b P_b`, the weights `k`
    /// chosen so that (1, 1, 1) emits the CIE XYZ of D65 at luminance 1 (`spectral_texture.rs`
    /// in pt-render). Mitsuba has no such parameter and rejects these scenes.
    pub(super) fn area_emitter(&mut self, el: &'e Element) -> Result<AreaEmitterDesc> {
        let v = ObjectView::parse(el)?;
        if v.plugin != "area" {
            return Err(plugin_error(el));
        }
        let mut texture = None;
        for child in &v.children {
            let t = self.resolve(child)?;
            let name = child.written().attr("name").or_else(|| t.attr("name"));
            if t.tag != "texture" || name != Some("radiance") || texture.is_some() {
                return Err(misplaced(child, t, &v, "one <texture name=\"radiance\">"));
            }
            texture = Some(self.emission_texture(t)?);
        }
        if texture.is_some() && v.has("radiance") {
            return Err(v.prop_error(
                "radiance",
                "give either a radiance value or a radiance texture",
            ));
        }
        let radiance = match texture {
            Some(t) => t,
            None => {
                let s = v
                    .spectrum("radiance")?
                    .unwrap_or(SpectrumDesc::Constant(1.0));
                if s.values().iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                    return Err(
                        v.prop_error("radiance", "radiance must be finite and non-negative")
                    );
                }
                TextureDesc::Constant(s)
            }
        };
        let bitmap = matches!(radiance, TextureDesc::Bitmap(_));
        let names = ["primary_r", "primary_g", "primary_b"];
        let primaries = match names.map(|n| v.spectrum(n)) {
            [Ok(None), Ok(None), Ok(None)] => None,
            [Ok(Some(r)), Ok(Some(g)), Ok(Some(b))] => {
                if !bitmap {
                    return Err(v.prop_error("primary_r", "display primaries need a radiance bitmap (an image whose texels drive them)"));
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
            primaries,
        })
    }
}

/// A light's spectrum property `name` (default 1), which must not be negative.
fn light_spectrum(v: &ObjectView<'_>, name: &str) -> Result<SpectrumDesc> {
    let s = v.spectrum(name)?.unwrap_or(SpectrumDesc::Constant(1.0));
    let vals = s.values();
    if vals.iter().any(|&x| x < 0.0) {
        return Err(v.prop_error(name, format!("{name} must not be negative")));
    }
    Ok(s)
}

/// A distant light's direction of travel: `direction`, or the +z axis of `to_world`
/// (default +z), normalised.
fn light_direction(v: &ObjectView<'_>, to_world: Option<Mat4>) -> Result<Vec3> {
    let d = match (v.vec3("direction")?, to_world) {
        (Some(_), Some(_)) => {
            return Err(v.prop_error("direction", "give either direction or to_world, not both"))
        }
        (Some(d), None) => d,
        (None, Some(m)) => m.transform_vector3(Vec3::Z),
        (None, None) => Vec3::Z,
    };
    d.try_normalize()
        .ok_or_else(|| v.prop_error("direction", "direction must not be zero"))
}

/// A `projector`: its irradiance a value or a nested texture (not both), `scale`, and a
/// camera's projection.
fn projector(
    v: &ObjectView<'_>,
    to_world: Option<Mat4>,
    texture: Option<(TextureDesc, &SourceLoc)>,
) -> Result<LightKind> {
    let irradiance = match texture {
        Some((t, _)) => {
            if v.has("irradiance") {
                return Err(v.prop_error(
                    "irradiance",
                    "give either an irradiance value or an irradiance texture",
                ));
            }
            t
        }
        None => TextureDesc::Constant(light_spectrum(v, "irradiance")?),
    };
    let scale = v.float("scale")?.unwrap_or(1.0);
    if !(scale >= 0.0 && scale.is_finite()) {
        return Err(v.prop_error("scale", "scale must be finite and not negative"));
    }
    Ok(LightKind::Projector {
        to_world: to_world.unwrap_or(Mat4::IDENTITY),
        irradiance,
        scale,
        projection: super::sensor::projection(v)?,
    })
}

/// Whether a profile's file name is an IES file (by its extension, as photometric files are
/// named).
fn is_ies(name: &str) -> bool {
    Path::new(name)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ies"))
}

/// The rotation of a profile's `to_world`.
fn profile_rotation(v: &ObjectView<'_>, to_world: &Mat4) -> Result<Mat3> {
    rotation_of(v, to_world, "an intensity profile's to_world")
}

/// The rotation of a `to_world` that orients a direction-dependent light (an intensity
/// profile, a sky; `what` names it in the error): its linear part with the columns normalised,
/// which must be orthogonal and of equal lengths (a rotation times a uniform scale), since a
/// sheared or stretched one has no agreed meaning.
pub(super) fn rotation_of(v: &ObjectView<'_>, to_world: &Mat4, what: &str) -> Result<Mat3> {
    let m = Mat3::from_mat4(*to_world);
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let len = cols.map(|c| c.length());
    let bad = || {
        v.prop_error(
            "to_world",
            format!("{what} must be a rotation (with at most a uniform scale) and a translation"),
        )
    };
    if !(len[0] > 0.0 && len[0].is_finite()) {
        return Err(bad());
    }
    let tol = 1e-3 * len[0];
    if (len[1] - len[0]).abs() > tol
        || (len[2] - len[0]).abs() > tol
        || cols[0].dot(cols[1]).abs() > tol * len[0]
        || cols[0].dot(cols[2]).abs() > tol * len[0]
        || cols[1].dot(cols[2]).abs() > tol * len[0]
    {
        return Err(bad());
    }
    let r = m * (1.0 / len[0]);
    if r.determinant() < 0.0 {
        return Err(bad()); // a mirror image
    }
    Ok(r)
}
