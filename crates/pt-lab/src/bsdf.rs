//! BSDFs built on their own from a model name and parameters, without a scene: the parameters
//! have the scene format's names, defaults and checks (Mitsuba 3's, and the project's own for
//! its extensions), because they are read by the XML loader's own reader
//! ([`pt_scene::bsdf_from_properties`]) and turned into a BSDF by the renderer's material layer
//! ([`pt_render::material::build_material`]) in RGB mode. A BSDF built here is therefore the
//! one a scene file with the same `<bsdf>` element renders with (the tests check that bit for
//! bit).
//!
//! Models ([`MODELS`] lists each with its parameters): `diffuse`, `orennayar` (+ `variant`),
//! `minnaert`, `dielectric`, `thindielectric`, `roughdielectric`, `conductor` (`eta` + `k` or a
//! named `material`), `roughconductor`, `roughplastic`, `pplastic`, `polarizer`, `principled`,
//! `principledthin`, `thinfilm`,
//! `roughthinfilm`, and the
//! wrapper `twosided` around one of them. Values are numbers, linear sRGB colours, names
//! (`variant="full"`, `material="Au"`, `int_ior="bk7"`, `distribution="ggx"`) or flags, as
//! [`PropValue`]s; angles in radians (`sigma`), film thickness in nanometres.
//!
//! ```
//! use pt_lab::bsdf::{build_bsdf, BsdfSpec};
//! use pt_math::Vec3;
//!
//! let on = BsdfSpec::new("orennayar").with("sigma", 0.3).with("variant", "full");
//! let bsdf = build_bsdf(&on)?;
//! let f = bsdf.eval(Vec3::Z, Vec3::Z); // normal incidence and exit, local frame
//! assert!(f.0.x > 0.0);
//! let same = build_bsdf(&BsdfSpec::parse("orennayar sigma=0.3 variant=full")?)?;
//! assert_eq!(same.eval(Vec3::Z, Vec3::Z), f);
//! assert!(build_bsdf(&BsdfSpec::new("orennayar").with("sigmaa", 0.3)).is_err());
//! # Ok::<(), pt_lab::bsdf::BsdfError>(())
//! ```

use pt_bsdf::SurfaceBsdf;
pub use pt_scene::PropValue;
use pt_scene::{BsdfDesc, BsdfKind};
use std::fmt::Write as _;

/// A model the builder knows, with the parameters it accepts.
#[derive(Clone, Copy, Debug)]
pub struct ModelInfo {
    /// The plugin name, as in a scene file (`<bsdf type="...">`).
    pub name: &'static str,
    /// Its parameters, with the scene format's names.
    pub params: &'static [&'static str],
}

/// The models of [`build_bsdf`] and their parameters (Mitsuba 3's names; `sample_visible` is
/// accepted and ignored, as in scene files: visible normals are always sampled).
pub const MODELS: &[ModelInfo] = &[
    ModelInfo {
        name: "diffuse",
        params: &["reflectance"],
    },
    ModelInfo {
        name: "orennayar",
        params: &["reflectance", "sigma", "variant"],
    },
    ModelInfo {
        name: "minnaert",
        params: &["reflectance", "k"],
    },
    ModelInfo {
        name: "roughconductor",
        params: &[
            "material",
            "eta",
            "k",
            "specular_reflectance",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
        ],
    },
    ModelInfo {
        name: "roughdielectric",
        params: &[
            "int_ior",
            "ext_ior",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "specular_reflectance",
            "specular_transmittance",
            "sample_visible",
        ],
    },
    ModelInfo {
        name: "conductor",
        params: &["material", "eta", "k", "specular_reflectance"],
    },
    ModelInfo {
        name: "dielectric",
        params: &[
            "int_ior",
            "ext_ior",
            "specular_reflectance",
            "specular_transmittance",
        ],
    },
    ModelInfo {
        name: "thindielectric",
        params: &[
            "int_ior",
            "ext_ior",
            "specular_reflectance",
            "specular_transmittance",
        ],
    },
    ModelInfo {
        name: "plastic",
        params: &[
            "diffuse_reflectance",
            "specular_reflectance",
            "int_ior",
            "ext_ior",
            "nonlinear",
        ],
    },
    ModelInfo {
        name: "roughplastic",
        params: &[
            "diffuse_reflectance",
            "specular_reflectance",
            "int_ior",
            "ext_ior",
            "distribution",
            "alpha",
            "nonlinear",
            "sample_visible",
        ],
    },
    ModelInfo {
        name: "pplastic",
        params: &[
            "diffuse_reflectance",
            "specular_reflectance",
            "int_ior",
            "ext_ior",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
        ],
    },
    ModelInfo {
        name: "polarizer",
        params: &["transmittance", "theta", "polarizing"],
    },
    ModelInfo {
        name: "hair",
        params: &[
            "eumelanin",
            "pheomelanin",
            "sigma_a",
            "scale",
            "reflectance",
            "int_ior",
            "ext_ior",
            "longitudinal_roughness",
            "azimuthal_roughness",
            "scale_tilt",
        ],
    },
    ModelInfo {
        name: "thinfilm",
        params: &[
            "thickness",
            "film_ior",
            "ext_ior",
            "int_ior",
            "material",
            "eta",
            "k",
        ],
    },
    ModelInfo {
        name: "roughthinfilm",
        params: &[
            "thickness",
            "film_ior",
            "ext_ior",
            "int_ior",
            "material",
            "eta",
            "k",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
        ],
    },
    ModelInfo {
        name: "principled",
        params: &[
            "base_color",
            "roughness",
            "anisotropic",
            "metallic",
            "spec_trans",
            "spec_tint",
            "sheen",
            "sheen_tint",
            "flatness",
            "clearcoat",
            "clearcoat_gloss",
            "eta",
            "specular",
            "main_specular_sampling_rate",
            "clearcoat_sampling_rate",
            "diffuse_reflectance_sampling_rate",
        ],
    },
    ModelInfo {
        name: "principledthin",
        params: &[
            "base_color",
            "roughness",
            "anisotropic",
            "spec_trans",
            "spec_tint",
            "sheen",
            "sheen_tint",
            "flatness",
            "diff_trans",
            "eta",
            "specular_reflectance_sampling_rate",
            "specular_transmittance_sampling_rate",
            "diffuse_reflectance_sampling_rate",
            "diffuse_transmittance_sampling_rate",
        ],
    },
    ModelInfo {
        name: "twosided",
        params: &[],
    },
];

/// The model `name` of [`MODELS`].
pub fn model_info(name: &str) -> Option<&'static ModelInfo> {
    MODELS.iter().find(|m| m.name == name)
}

/// Why a BSDF cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BsdfError {
    /// The model is not one of [`MODELS`].
    #[error("unknown model '{model}' (known: {})", known_models())]
    UnknownModel {
        /// The name given.
        model: String,
    },
    /// A parameter the model does not have.
    #[error(
        "{model}: unknown parameter '{param}' (parameters: {})",
        known_params(model)
    )]
    UnknownParameter {
        /// The model.
        model: String,
        /// The parameter given.
        param: String,
    },
    /// A specification that is not `MODEL NAME=VALUE ...` (see [`BsdfSpec::parse`]).
    #[error("{0}")]
    Syntax(String),
    /// Parameters the scene format refuses (a value out of range, an unknown named material,
    /// conflicting parameters): `label` is the model with its parameters, `message` the scene
    /// format's reason.
    #[error("{label}: {message}")]
    Invalid {
        /// The model and its parameters as [`BsdfSpec::label`] writes them.
        label: String,
        /// What is wrong.
        message: String,
    },
}

fn known_models() -> String {
    let names: Vec<&str> = MODELS.iter().map(|m| m.name).collect();
    names.join(", ")
}

fn known_params(model: &str) -> String {
    model_info(model).map_or(String::new(), |m| m.params.join(", "))
}

/// A model and its parameters, with the scene format's names.
#[derive(Clone, Debug, PartialEq)]
pub struct BsdfSpec {
    /// The model's plugin name (see [`MODELS`]).
    pub model: String,
    /// Its parameters, in the order given.
    pub params: Vec<(String, PropValue)>,
    /// The model `twosided` wraps (`None` for every other model).
    pub inner: Option<Box<BsdfSpec>>,
}

impl BsdfSpec {
    /// `model` with every parameter at its default.
    pub fn new(model: &str) -> BsdfSpec {
        BsdfSpec {
            model: model.to_string(),
            params: Vec::new(),
            inner: None,
        }
    }

    /// `twosided` around `inner`.
    pub fn two_sided(inner: BsdfSpec) -> BsdfSpec {
        BsdfSpec {
            inner: Some(Box::new(inner)),
            ..BsdfSpec::new("twosided")
        }
    }

    /// This specification with one more parameter (not checked until the BSDF is built).
    pub fn with(mut self, name: &str, value: impl Into<PropValue>) -> BsdfSpec {
        self.params.push((name.to_string(), value.into()));
        self
    }

    /// Parses `MODEL NAME=VALUE ...` (whitespace-separated; `twosided MODEL ...` wraps the rest).
    /// The model name is checked and lower-cased, parameter names are lower-cased and must be
    /// unique; each value is a number, `true`/`false`, three comma-separated numbers (a colour)
    /// or else a name. Numbers are read as in scene files (as f64, then rounded to f32).
    pub fn parse(text: &str) -> Result<BsdfSpec, BsdfError> {
        let mut words = text.split_whitespace();
        let Some(model) = words.next() else {
            return Err(BsdfError::Syntax("empty model specification".into()));
        };
        let model = model.to_ascii_lowercase();
        if model_info(&model).is_none() {
            return Err(BsdfError::UnknownModel { model });
        }
        if model == "twosided" {
            let rest: Vec<&str> = words.collect();
            if rest.is_empty() {
                return Err(BsdfError::Syntax(
                    "twosided: give the model it wraps, e.g. \"twosided diffuse\"".into(),
                ));
            }
            return Ok(BsdfSpec::two_sided(BsdfSpec::parse(&rest.join(" "))?));
        }
        let mut spec = BsdfSpec::new(&model);
        for word in words {
            spec.add_param(word)?;
        }
        Ok(spec)
    }

    /// Adds one parameter written `NAME=VALUE` (see [`BsdfSpec::parse`]); for `twosided`, to
    /// the model inside.
    pub fn add_param(&mut self, word: &str) -> Result<(), BsdfError> {
        if let Some(inner) = &mut self.inner {
            return inner.add_param(word);
        }
        let Some((name, value)) = word.split_once('=') else {
            return Err(BsdfError::Syntax(format!(
                "{}: expected NAME=VALUE, got '{word}'",
                self.model
            )));
        };
        let (name, value) = (name.trim().to_ascii_lowercase(), value.trim());
        if value.is_empty() {
            return Err(BsdfError::Syntax(format!(
                "{}: parameter '{name}' has no value",
                self.model
            )));
        }
        if self.params.iter().any(|(n, _)| *n == name) {
            return Err(BsdfError::Syntax(format!(
                "{}: parameter '{name}' given twice",
                self.model
            )));
        }
        self.params.push((name, parse_value(value)));
        Ok(())
    }

    /// The parameter `name`, if given.
    pub fn param(&self, name: &str) -> Option<&PropValue> {
        self.params.iter().find(|(n, _)| n == name).map(|p| &p.1)
    }

    /// The specification as [`BsdfSpec::parse`] reads it: `orennayar sigma=0.3`.
    pub fn label(&self) -> String {
        let mut s = self.model.clone();
        if let Some(inner) = &self.inner {
            let _ = write!(s, " {}", inner.label());
        }
        for (n, v) in &self.params {
            let _ = write!(s, " {n}={}", value_text(v));
        }
        s
    }
}

/// A value as [`BsdfSpec::parse`] reads it.
fn parse_value(text: &str) -> PropValue {
    // As a scene file's <float>: f64, then f32 (keeps values bit-identical to an XML file).
    let number = |t: &str| t.trim().parse::<f64>().ok().map(|x| x as f32);
    let parts: Vec<Option<f32>> = text.split(',').map(number).collect();
    match (text, parts.as_slice()) {
        ("true", _) => PropValue::Boolean(true),
        ("false", _) => PropValue::Boolean(false),
        (_, [Some(x)]) => PropValue::Float(*x),
        (_, [Some(r), Some(g), Some(b)]) => PropValue::Rgb([*r, *g, *b]),
        _ => PropValue::String(text.to_string()),
    }
}

/// A value as written in a label (numbers in Rust's shortest round-trip form).
pub(crate) fn value_text(v: &PropValue) -> String {
    match v {
        PropValue::Float(x) => format!("{x}"),
        PropValue::Rgb([r, g, b]) => format!("{r},{g},{b}"),
        PropValue::String(s) => s.clone(),
        PropValue::Boolean(b) => b.to_string(),
    }
}

/// The scene description of `spec`: names checked against [`MODELS`], values read by the
/// XML loader's reader (same defaults, named materials and checks).
pub fn bsdf_desc(spec: &BsdfSpec) -> Result<BsdfDesc, BsdfError> {
    let info = model_info(&spec.model).ok_or_else(|| BsdfError::UnknownModel {
        model: spec.model.clone(),
    })?;
    if let Some((param, _)) = spec
        .params
        .iter()
        .find(|(n, _)| !info.params.contains(&n.as_str()))
    {
        return Err(BsdfError::UnknownParameter {
            model: spec.model.clone(),
            param: param.clone(),
        });
    }
    let invalid = |message: String| BsdfError::Invalid {
        label: spec.label(),
        message,
    };
    match (spec.model.as_str(), &spec.inner) {
        ("twosided", Some(inner)) => {
            let inner = bsdf_desc(inner)?;
            Ok(BsdfDesc {
                loc: inner.loc.clone(),
                id: None,
                kind: BsdfKind::TwoSided {
                    inner: Box::new(inner),
                },
            })
        }
        ("twosided", None) => Err(invalid("twosided needs the model it wraps".into())),
        (model, Some(_)) => Err(invalid(format!("{model} wraps no other model"))),
        (model, None) => {
            pt_scene::bsdf_from_properties(model, &spec.params).map_err(|e| invalid(e.message))
        }
    }
}

/// The BSDF of `spec` (RGB mode: lanes r, g, b and an unused fourth lane), built as a scene
/// file's `<bsdf>` with the same parameters would be (see the module doc).
pub fn build_bsdf(spec: &BsdfSpec) -> Result<SurfaceBsdf, BsdfError> {
    let model = build_model(spec, pt_spectrum::ColorMode::Rgb)?;
    // Parameters given as values are constants, so in RGB mode the material is one BSDF
    // everywhere.
    model.material.fixed.ok_or_else(|| BsdfError::Invalid {
        label: spec.label(),
        message: "the model's parameters must be constants".into(),
    })
}

/// A BSDF model built for a colour mode: in RGB mode one BSDF, in spectral mode one per set of
/// four wavelengths (its colours upsampled to spectra, named materials and indices read at
/// the wavelengths), as a scene renders it in that mode.
#[derive(Clone, Debug)]
pub struct BsdfModel {
    material: pt_render::material::SurfaceMaterial,
}

impl BsdfModel {
    /// The colour mode it was built for.
    pub fn mode(&self) -> pt_spectrum::ColorMode {
        self.material.mode
    }

    /// The BSDF at the wavelengths `lambda` (nm, one per lane; ignored in RGB mode, whose lanes
    /// are r, g, b and an unused fourth).
    pub fn at(&self, lambda: pt_math::Vec4) -> SurfaceBsdf {
        // Constant parameters read the same at any point of the surface.
        let at = pt_render::texture::TexturePoint::uv(pt_math::Vec2::ZERO);
        let hit = pt_render::geometry::Interaction::default();
        let wavelengths = pt_spectrum::SampledWavelengths::sample_visible(0.5).with_lambda(lambda);
        self.material.bsdf(&hit, &at, &wavelengths).into_owned()
    }
}

/// The model of `spec` in `mode` (see [`BsdfModel`]), built as a scene file's `<bsdf>` with the
/// same parameters would be.
pub fn build_model(spec: &BsdfSpec, mode: pt_spectrum::ColorMode) -> Result<BsdfModel, BsdfError> {
    let desc = bsdf_desc(spec)?;
    let mut textures = pt_render::texture::TextureBuilder::new(mode);
    let material = pt_render::material::build_material(&desc, &mut textures).map_err(|e| {
        BsdfError::Invalid {
            label: spec.label(),
            message: e.message,
        }
    })?;
    Ok(BsdfModel { material })
}

#[cfg(test)]
mod tests;
