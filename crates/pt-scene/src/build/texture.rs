//! Texturable parameters: a property (`<rgb>`, `<float>`, `<spectrum>`) or a nested texture
//! (`<texture name="..." type="...">` or `<ref name="..." id="..."/>`), and the texture
//! plugins `bitmap`, `checkerboard`, `mesh_attribute` and `rawconstant` with Mitsuba 3.9.1's
//! parameters and defaults.

use super::*;
use std::sync::Arc;

/// A nested texture of a plugin, by the name of the parameter it gives.
struct NamedTexture<'e> {
    /// The parameter (`name` of the texture element or of the `<ref>`).
    name: String,
    /// As written in the plugin (the texture or the `<ref>`).
    written: &'e Element,
    /// The texture element (the `<ref>` followed).
    target: &'e Element,
    /// Whether the plugin read it.
    used: std::cell::Cell<bool>,
}

/// The nested objects of a plugin: its textures by parameter name, and everything else in
/// document order (nested BSDFs, ...). Every texture must be read by the plugin
/// ([`Nested::finish`]), as every property must ([`ObjectView::finish`]).
pub(super) struct Nested<'e> {
    textures: Vec<NamedTexture<'e>>,
    /// The other nested objects: as written, and followed through `<ref>`.
    pub others: Vec<(Child<'e>, &'e Element)>,
}

impl<'e> Nested<'e> {
    /// No nested objects (an object given in code).
    pub(super) fn none() -> Self {
        Nested {
            textures: Vec::new(),
            others: Vec::new(),
        }
    }

    /// Errors on the first nested texture the plugin did not read.
    pub(super) fn finish(&self, v: &ObjectView<'_>) -> Result<()> {
        match self.textures.iter().find(|t| !t.used.get()) {
            Some(t) => Err(SceneError::at(
                &t.written.loc,
                format!(
                    "unused texture '{}': {} does not have a texturable parameter of this name",
                    t.name,
                    v.what()
                ),
            )),
            None => Ok(()),
        }
    }

    /// Errors if the plugin has nested objects other than textures.
    pub(super) fn no_others(&self, v: &ObjectView<'_>) -> Result<()> {
        match self.others.first() {
            Some((child, target)) => Err(misplaced(
                child,
                target,
                v,
                "no nested objects but textures",
            )),
            None => Ok(()),
        }
    }
}

/// Mitsuba's `to_uv` as a 2D affine map: the upper-left 2x2 block and the translation column
/// of the 4x4 matrix (Mitsuba's `Transform4f::extract`).
fn uv_transform(m: &Mat4) -> UvTransform {
    let c = m.to_cols_array_2d();
    [c[0][0], c[1][0], c[3][0], c[0][1], c[1][1], c[3][1]]
}

/// Image files the bitmap texture reads, by extension (lower case).
const IMAGE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "exr", "hdr", "rgbe", "bmp", "tga"];

impl<'e> Builder<'e> {
    /// Splits the nested objects of `v` into named textures and the rest.
    pub(super) fn nested(&self, v: &ObjectView<'e>) -> Result<Nested<'e>> {
        let mut nested = Nested {
            textures: Vec::new(),
            others: Vec::new(),
        };
        for child in &v.children {
            let target = self.resolve(child)?;
            let written = child.written();
            let name = written.attr("name").or_else(|| target.attr("name"));
            match (target.tag.as_str(), name) {
                ("texture", Some(name)) => {
                    if let Some(first) = nested.textures.iter().find(|t| t.name == name) {
                        let l = &first.written.loc;
                        return Err(SceneError::at(
                            &written.loc,
                            format!(
                                "texture '{name}' is given twice (first at line {}, column {})",
                                l.line, l.col
                            ),
                        ));
                    }
                    nested.textures.push(NamedTexture {
                        name: name.to_string(),
                        written,
                        target,
                        used: std::cell::Cell::new(false),
                    });
                }
                // A bump map's one texture may go without a name (Mitsuba reads its only
                // texture child, whatever it is called).
                ("texture", None) if v.plugin == "bumpmap" => {
                    nested.textures.push(NamedTexture {
                        name: String::new(),
                        written,
                        target,
                        used: std::cell::Cell::new(false),
                    });
                }
                ("texture", None) => {
                    return Err(SceneError::at(
                        &written.loc,
                        format!(
                            "a texture nested in {} needs name=\"...\" (the parameter it gives)",
                            v.what()
                        ),
                    ))
                }
                _ => nested.others.push((*child, target)),
            }
        }
        Ok(nested)
    }

    /// A wrapper's only nested texture, whatever its name (Mitsuba's `bumpmap`); more or fewer
    /// than one is an error.
    pub(super) fn only_texture(
        &mut self,
        v: &ObjectView<'e>,
        nested: &Nested<'e>,
    ) -> Result<TextureDesc> {
        match nested.textures.as_slice() {
            [t] => {
                t.used.set(true);
                Ok(self
                    .texture(t.target)?
                    .expect("a texture element gives a texture"))
            }
            [] => Err(SceneError::at(
                &v.el.loc,
                format!("{} needs one nested <texture> (the height map)", v.what()),
            )),
            [_, second, ..] => Err(SceneError::at(
                &second.written.loc,
                format!("{} takes only one nested <texture>", v.what()),
            )),
        }
    }

    /// The texturable parameter `name` of `v`: a nested texture, a property, or `None` when
    /// neither is given. Both at once is an error.
    pub(super) fn texture_param(
        &mut self,
        v: &ObjectView<'e>,
        nested: &Nested<'e>,
        name: &str,
    ) -> Result<Option<TextureDesc>> {
        let Some(t) = nested.textures.iter().find(|t| t.name == name) else {
            return Ok(v.spectrum(name)?.map(TextureDesc::Constant));
        };
        t.used.set(true);
        if v.has(name) {
            return Err(v.prop_error(
                name,
                format!("'{name}' is given both as a value and as a texture"),
            ));
        }
        self.texture(t.target)
    }

    /// A texture element (`bitmap`, `checkerboard`, `mesh_attribute`, `rawconstant`), built
    /// once per id so that shared images stay shared.
    pub(super) fn texture(&mut self, el: &'e Element) -> Result<Option<TextureDesc>> {
        let id = el.attr("id");
        if let Some(t) = id.and_then(|id| self.texture_memo.get(id)) {
            return Ok(Some(t.clone()));
        }
        if let Some(id) = id {
            if self.visiting.iter().any(|v| v == id) {
                return Err(SceneError::at(
                    &el.loc,
                    format!("texture \"{id}\" contains itself"),
                ));
            }
            self.visiting.push(id.to_string());
        }
        let built = self.build_texture(el);
        if id.is_some() {
            self.visiting.pop();
        }
        let t = built?;
        if let Some(id) = id {
            self.texture_memo.insert(id.to_string(), t.clone());
        }
        Ok(Some(t))
    }

    fn build_texture(&mut self, el: &'e Element) -> Result<TextureDesc> {
        let v = ObjectView::parse(el)?;
        let nested = self.nested(&v)?;
        let to_uv = v
            .transform("to_uv")?
            .as_ref()
            .map_or(UV_IDENTITY, uv_transform);
        let t = match v.plugin.as_str() {
            "bitmap" => TextureDesc::Bitmap(Arc::new(self.bitmap(&v, to_uv)?)),
            "checkerboard" => {
                let color0 = self.texture_param(&v, &nested, "color0")?;
                let color1 = self.texture_param(&v, &nested, "color1")?;
                TextureDesc::Checkerboard(Box::new(CheckerboardDesc {
                    loc: el.loc.clone(),
                    color0: color0.unwrap_or(TextureDesc::constant(0.4)),
                    color1: color1.unwrap_or(TextureDesc::constant(0.2)),
                    to_uv,
                }))
            }
            "mesh_attribute" => {
                let name = v.string("name")?.ok_or_else(|| {
                    SceneError::at(&el.loc, "mesh_attribute needs <string name=\"name\" .../>")
                })?;
                if MeshAttribute::kind_of(&name).is_none() {
                    return Err(v.prop_error(
                        "name",
                        format!("mesh attribute names start with vertex_ or face_, got '{name}'"),
                    ));
                }
                let scale = v.float("scale")?.unwrap_or(1.0);
                TextureDesc::MeshAttribute(MeshAttributeDesc {
                    loc: el.loc.clone(),
                    name,
                    scale,
                })
            }
            "rawconstant" => {
                let (value, scalar) = match (v.float("value"), v.vec3("value")) {
                    (Ok(Some(x)), _) => ([x; 3], true),
                    (_, Ok(Some(p))) => (p.to_array(), false),
                    _ => match v.spectrum("value")? {
                        Some(SpectrumDesc::Rgb(c)) => (c, false),
                        _ => {
                            return Err(SceneError::at(
                                &el.loc,
                                "rawconstant needs a value: <float name=\"value\"> or <vector name=\"value\">",
                            ))
                        }
                    },
                };
                TextureDesc::RawConstant(RawConstant { value, scalar })
            }
            _ => return Err(plugin_error(el)),
        };
        if v.plugin != "bitmap" && v.plugin != "checkerboard" && v.has("to_uv") {
            return Err(v.prop_error("to_uv", format!("{} has no to_uv", v.what())));
        }
        nested.no_others(&v)?;
        nested.finish(&v)?;
        v.finish()?;
        Ok(t)
    }

    /// `bitmap`: `filename` (required; PNG, JPEG, BMP, TGA, EXR, HDR), `raw` (false),
    /// `filter_type` (bilinear | nearest), `wrap_mode` (repeat | mirror | clamp), `to_uv`,
    /// and `format` / `accel`, which choose Mitsuba's storage and have no effect here.
    fn bitmap(&self, v: &ObjectView<'e>, to_uv: UvTransform) -> Result<BitmapDesc> {
        let name = v
            .string("filename")?
            .ok_or_else(|| SceneError::at(&v.el.loc, "bitmap needs a filename"))?;
        let path = resolve_file(&name, &v.el.dir, &[self.base_dir], self.search_paths);
        if !path.is_file() {
            return Err(v.prop_error(
                "filename",
                format!("cannot open image '{name}' (looked for {})", path.display()),
            ));
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        if !IMAGE_EXTENSIONS.contains(&ext.as_str()) {
            return Err(v.prop_error(
                "filename",
                format!(
                    "image '{name}': unsupported file type (readable: {})",
                    IMAGE_EXTENSIONS.join(", ")
                ),
            ));
        }
        let filter = match v.string("filter_type")?.as_deref() {
            None | Some("bilinear") => BitmapFilter::Bilinear,
            Some("nearest") => BitmapFilter::Nearest,
            Some(other) => {
                return Err(v.prop_error(
                    "filter_type",
                    format!("filter_type must be bilinear or nearest, got '{other}'"),
                ))
            }
        };
        let wrap = match v.string("wrap_mode")?.as_deref() {
            None | Some("repeat") => WrapMode::Repeat,
            Some("mirror") => WrapMode::Mirror,
            Some("clamp") => WrapMode::Clamp,
            Some(other) => {
                return Err(v.prop_error(
                    "wrap_mode",
                    format!("wrap_mode must be repeat, mirror or clamp, got '{other}'"),
                ))
            }
        };
        one_of(
            v,
            "format",
            &["auto", "variant", "fp16", "float16", "uint8"],
        )?;
        v.boolean("accel")?;
        Ok(BitmapDesc {
            loc: v.el.loc.clone(),
            source: ImageSource::File(path),
            raw: v.boolean("raw")?.unwrap_or(false),
            filter,
            wrap,
            to_uv,
        })
    }

    /// An emitter's `radiance` texture: a texture, or Mitsuba's `<texture type="d65">` around
    /// one (which in Mitsuba's spectral variants multiplies it by D65, and in its RGB variants
    /// changes nothing). pt multiplies every RGB emission by D65 in spectral mode anyway
    /// (DESIGN.md, Colour), so for pt the wrapper changes nothing; it makes Mitsuba agree.
    pub(super) fn emission_texture(&mut self, el: &'e Element) -> Result<TextureDesc> {
        if el.attr("type") != Some("d65") {
            return self
                .texture(el)
                .map(|t| t.expect("a texture element gives a texture"));
        }
        let v = ObjectView::parse(el)?;
        let mut inner = None;
        for child in &v.children {
            let t = self.resolve(child)?;
            if t.tag != "texture" {
                return Err(misplaced(child, t, &v, "one nested <texture>"));
            }
            if inner.is_some() {
                return Err(SceneError::at(
                    &child.written().loc,
                    "a d65 radiance texture takes one nested <texture>",
                ));
            }
            inner = self.texture(t)?;
        }
        v.finish()?;
        inner.ok_or_else(|| {
            SceneError::at(
                &el.loc,
                "a d65 radiance texture needs a nested <texture> (d65 with a color or scale is not yet supported here: give the colour as <rgb name=\"radiance\">)",
            )
        })
    }
}
