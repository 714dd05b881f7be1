//! BSDFs.

use super::*;
use crate::props::PropValue;

/// Plugins that wrap other BSDFs (read from nested `<bsdf>` elements only).
const WRAPPERS: &[&str] = &["twosided", "mask", "blendbsdf", "normalmap"];

/// Reads a BSDF model plugin from properties given in code (see [`crate::bsdf_from_properties`]).
pub(crate) fn bsdf_from_properties(
    plugin: &str,
    props: &[(String, PropValue)],
) -> Result<BsdfDesc> {
    let loc = SourceLoc {
        file: PathBuf::from("<properties>"),
        line: 0,
        col: 0,
        element: format!("bsdf type=\"{plugin}\""),
    };
    let el = Element {
        tag: "bsdf".into(),
        attrs: vec![("type".into(), plugin.to_string())],
        children: Vec::new(),
        loc,
        dir: PathBuf::from("."),
    };
    let v = ObjectView::from_props(&el, props)?;
    if WRAPPERS.contains(&plugin) {
        return Err(SceneError::at(
            &el.loc,
            format!(
                "bsdf \"{plugin}\" wraps other BSDFs: build the inner one and wrap its description"
            ),
        ));
    }
    let mut b = Builder::new(HashMap::new(), &[], Path::new("."));
    let kind = materials::bsdf_kind(&mut b, &v, &Nested::none())?;
    v.finish()?;
    Ok(BsdfDesc {
        loc: el.loc.clone(),
        id: None,
        kind,
    })
}

impl<'e> Builder<'e> {
    /// Index in `bsdfs` of the BSDF `el`: shared (id-carrying) BSDFs are added once.
    pub(super) fn bsdf_for_shape(&mut self, el: &'e Element) -> Result<usize> {
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
    pub(super) fn default_bsdf(&mut self, shape: &Element, emitter: bool) -> usize {
        if let Some(index) = self.default_bsdf[usize::from(emitter)] {
            return index;
        }
        self.bsdfs.push(BsdfDesc {
            loc: shape.loc.clone(),
            id: None,
            kind: BsdfKind::Diffuse {
                reflectance: TextureDesc::constant(if emitter { 0.0 } else { 0.5 }),
            },
        });
        let index = self.bsdfs.len() - 1;
        self.default_bsdf[usize::from(emitter)] = Some(index);
        index
    }

    /// Builds the BSDF `el`, once per id.
    pub(super) fn bsdf_desc(&mut self, el: &'e Element) -> Result<BsdfDesc> {
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

    /// Builds one BSDF element: the wrappers here (`twosided`, `mask`, `normalmap`, `bumpmap`,
    /// `blendbsdf`) and `null`, the models in `materials.rs`. Textures may stand for any texturable
    /// parameter; nested objects that are neither textures nor BSDFs a wrapper takes are errors.
    pub(super) fn build_bsdf(&mut self, el: &'e Element) -> Result<BsdfDesc> {
        let v = ObjectView::parse(el)?;
        let nested = self.nested(&v)?;
        let kind = match v.plugin.as_str() {
            "twosided" => BsdfKind::TwoSided {
                inner: Box::new(self.inner_bsdfs(&v, &nested, 1, 1)?.remove(0)),
            },
            "mask" => {
                let opacity = self.texture_param(&v, &nested, "opacity")?;
                let opacity = scalar_in(&v, "opacity", opacity, 0.5, 0.0..=1.0)?;
                let inner = Box::new(self.inner_bsdfs(&v, &nested, 1, 1)?.remove(0));
                BsdfKind::Mask {
                    opacity,
                    cutoff: None,
                    inner,
                }
            }
            // Mitsuba's `null`: light passes straight through, and the path integrator treats
            // the crossing as a delta bounce (it counts towards max_depth, shadow rays are
            // blocked). That is a mask of opacity 0: its pass-through is the same event.
            "null" => BsdfKind::Mask {
                opacity: TextureDesc::constant(0.0),
                cutoff: None,
                inner: Box::new(BsdfDesc {
                    loc: el.loc.clone(),
                    id: None,
                    kind: BsdfKind::Diffuse {
                        reflectance: TextureDesc::constant(0.0),
                    },
                }),
            },
            "blendbsdf" => {
                let weight = self.texture_param(&v, &nested, "weight")?;
                let weight = scalar_in(&v, "weight", weight, 0.5, 0.0..=1.0)?;
                let mut two = self.inner_bsdfs(&v, &nested, 2, 2)?;
                let second = Box::new(two.pop().expect("two"));
                let first = Box::new(two.pop().expect("two"));
                BsdfKind::Blend {
                    weight,
                    first,
                    second,
                }
            }
            "normalmap" => {
                let texture = self.texture_param(&v, &nested, "normalmap")?;
                let texture = match texture {
                    Some(t @ TextureDesc::Bitmap(_)) => t,
                    _ => {
                        return Err(SceneError::at(
                            &v.el.loc,
                            "normalmap needs <texture type=\"bitmap\" name=\"normalmap\">",
                        ))
                    }
                };
                let inner = Box::new(self.inner_bsdfs(&v, &nested, 1, 1)?.remove(0));
                BsdfKind::NormalMap {
                    texture,
                    scale: 1.0,
                    gltf: false,
                    inner,
                }
            }
            "bumpmap" => {
                let height = match self.only_texture(&v, &nested)? {
                    t @ TextureDesc::Bitmap(_) => t,
                    _ => {
                        return Err(SceneError::at(
                            &v.el.loc,
                            "bumpmap needs a bitmap height texture (Mitsuba differentiates only bitmaps)",
                        ))
                    }
                };
                let scale = v.float("scale")?.unwrap_or(1.0);
                if !scale.is_finite() {
                    return Err(v.prop_error("scale", "scale must be finite"));
                }
                let inner = Box::new(self.inner_bsdfs(&v, &nested, 1, 1)?.remove(0));
                BsdfKind::BumpMap {
                    height,
                    scale,
                    inner,
                }
            }
            _ => {
                nested.no_others(&v)?;
                materials::bsdf_kind(self, &v, &nested)?
            }
        };
        nested.finish(&v)?;
        v.finish()?;
        Ok(BsdfDesc {
            loc: el.loc.clone(),
            id: el.attr("id").map(str::to_string),
            kind,
        })
    }

    /// The nested BSDFs of a wrapper, `min..=max` of them, in document order; any other nested
    /// object (but textures) is an error.
    fn inner_bsdfs(
        &mut self,
        v: &ObjectView<'e>,
        nested: &Nested<'e>,
        min: usize,
        max: usize,
    ) -> Result<Vec<BsdfDesc>> {
        let mut inner = Vec::new();
        for (child, target) in &nested.others {
            if target.tag != "bsdf" {
                return Err(misplaced(child, target, v, "bsdf"));
            }
            if inner.len() == max {
                let what = if v.plugin == "twosided" {
                    "twosided with a different BSDF per side is not yet supported (not yet implemented)".to_string()
                } else {
                    format!("{} takes {max} nested <bsdf>", v.what())
                };
                return Err(SceneError::at(&child.written().loc, what));
            }
            inner.push(self.bsdf_desc(target)?);
        }
        if inner.len() < min {
            let n = if min == 1 {
                "one nested BSDF".to_string()
            } else {
                format!("{min} nested BSDFs")
            };
            return Err(SceneError::at(
                &v.el.loc,
                format!(
                    "{} needs {n} (<bsdf> or <ref>), got {}",
                    v.what(),
                    inner.len()
                ),
            ));
        }
        Ok(inner)
    }
}

/// A scalar texturable parameter with a default whose constant value must lie in `range`
/// (a texture is read as given and clamped where it is used).
pub(super) fn scalar_in(
    v: &ObjectView<'_>,
    name: &str,
    t: Option<TextureDesc>,
    default: f32,
    range: std::ops::RangeInclusive<f32>,
) -> Result<TextureDesc> {
    let t = t.unwrap_or(TextureDesc::constant(default));
    for s in t.spectra() {
        if s.is_spectral() {
            return Err(v.prop_error(
                name,
                format!("{name} is a number, not a spectrum ({})", s.form_name()),
            ));
        }
        if let Some(x) = s.values().into_iter().find(|x| !range.contains(x)) {
            return Err(v.prop_error(
                name,
                format!(
                    "{name} must be in [{}, {}], got {x}",
                    range.start(),
                    range.end()
                ),
            ));
        }
    }
    Ok(t)
}
