//! The scene description IR: what a loader produces and the renderer consumes.
//!
//! Everything here is in **world space** unless said otherwise, lengths in the scene's units
//! (metres by convention), angles in degrees where the Mitsuba format uses degrees (camera fov).
//! Colours are linear Rec.709 RGB. Every element remembers where it came from ([`SourceLoc`]) so
//! that errors found later (in the renderer) can still name the file, line and element.

mod bsdf;
mod light;
mod sensor;
mod shape;
mod spectrum;
mod texture;

pub use bsdf::*;
pub use light::*;
pub use sensor::*;
pub use shape::*;
pub use spectrum::*;
pub use texture::*;

use std::fmt;
use std::path::PathBuf;

/// A position in a scene file: file path, 1-based line and column, and the element's name
/// (for example `shape type="obj"`).
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct SourceLoc {
    /// The file the element was read from (or `<built-in>` for embedded scenes).
    pub file: PathBuf,
    /// 1-based line number.
    pub line: u32,
    /// 1-based column number.
    pub col: u32,
    /// The element as written, e.g. `shape type="rectangle"` or `float name="fov"`.
    pub element: String,
}

impl fmt::Display for SourceLoc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: <{}>",
            self.file.display(),
            self.line,
            self.col,
            self.element
        )
    }
}

/// A complete scene: camera, film, sampler, integrator settings, shapes and their materials.
#[derive(Clone, Debug)]
pub struct SceneDesc {
    /// The scene file (or `<built-in>`).
    pub source: PathBuf,
    /// The (only) camera.
    pub camera: CameraDesc,
    /// The medium the camera sits in (Mitsuba: a `<medium>` or `<ref>` nested in the sensor),
    /// if any.
    pub camera_medium: Option<MediumDesc>,
    /// Image size and reconstruction filter.
    pub film: FilmDesc,
    /// Sample count and seed.
    pub sampler: SamplerDesc,
    /// Light transport settings.
    pub integrator: IntegratorDesc,
    /// All shapes, in file order.
    pub shapes: Vec<ShapeDesc>,
    /// All BSDFs referenced by shapes (shared ones appear once). `ShapeDesc::bsdf` indexes this.
    pub bsdfs: Vec<BsdfDesc>,
    /// Emitters that are not attached to a shape (point, spot, directional, sun, environment).
    pub lights: Vec<LightDesc>,
    /// Mitsuba `shapegroup`s that instances place (not rendered themselves).
    pub groups: Vec<ShapeGroupDesc>,
    /// Mitsuba `instance`s: a group placed by a transform.
    pub instances: Vec<InstanceDesc>,
    /// The shape a `distant` sensor aims its rays at ([`DistantTarget::Shape`]): sampled by
    /// area, not part of the scene.
    pub sensor_target: Option<ShapeDesc>,
    /// The sensors of Mitsuba's `batch` ([`Projection::Batch`]), left to right on the film;
    /// empty otherwise.
    pub batch: Vec<CameraDesc>,
}

impl SceneDesc {
    /// Why the scene needs spectral transport (the first wavelength-dependent input found, with
    /// its location), or `None` when RGB is exact for it.
    pub fn spectral_reason(&self) -> Option<String> {
        /// Every BSDF in `b`, `b` first, then the nested ones depth first.
        fn all(b: &BsdfDesc) -> Vec<&BsdfDesc> {
            let mut v = vec![b];
            for inner in b.kind.nested() {
                v.extend(all(inner));
            }
            v
        }
        let models: Vec<&BsdfDesc> = self.bsdfs.iter().flat_map(all).collect();
        if let Some(b) = models
            .iter()
            .find(|b| matches!(b.kind, BsdfKind::Fluorescent { .. }))
        {
            return Some(format!(
                "{}: fluorescence moves light between wavelengths (RGB mode cannot express it)",
                b.loc
            ));
        }
        if let Some(b) = models.iter().find(|b| {
            matches!(
                b.kind,
                BsdfKind::ThinFilm { .. } | BsdfKind::RoughThinFilm { .. }
            )
        }) {
            return Some(format!(
                "{}: thin-film interference depends on wavelength (RGB mode can only approximate it, with Belcour & Barla 2017)",
                b.loc
            ));
        }
        for b in &models {
            let textured = b.kind.textures().into_iter().flat_map(|(_, t)| t.spectra());
            if let Some(s) = textured
                .chain(b.kind.fixed_spectra())
                .find(|s| s.is_spectral())
            {
                return Some(format!("{}: {} spectrum in a BSDF", b.loc, s.form_name()));
            }
        }
        let media = self
            .shapes
            .iter()
            .flat_map(|s| s.interior.iter().chain(&s.exterior))
            .chain(&self.camera_medium);
        for m in media {
            /// A parameter's spectrum when it is one (grids are RGB data).
            fn constant(v: &VolumeDesc) -> Option<&SpectrumDesc> {
                match v {
                    VolumeDesc::Constant(s) => Some(s),
                    VolumeDesc::Grid(_) => None,
                }
            }
            if let Some(sp) = [Some(&m.sigma_t), constant(&m.albedo)]
                .into_iter()
                .chain([m.emission.as_ref().and_then(constant)])
                .flatten()
                .find(|s| s.is_spectral())
            {
                return Some(format!(
                    "{}: {} spectrum in a medium",
                    m.loc,
                    sp.form_name()
                ));
            }
        }
        for s in &self.shapes {
            if let Some(e) = &s.emitter {
                if let Some(sp) = e.radiance.spectra().into_iter().find(|s| s.is_spectral()) {
                    return Some(format!("{}: {} emission spectrum", e.loc, sp.form_name()));
                }
                if e.primaries.is_some() {
                    return Some(format!(
                        "{}: display primaries (spectra driven by the radiance texture)",
                        e.loc
                    ));
                }
            }
        }
        for l in &self.lights {
            let spectra: Vec<&SpectrumDesc> = match &l.kind {
                LightKind::Point { intensity, .. } => vec![intensity],
                LightKind::Spot {
                    intensity, texture, ..
                } => {
                    let mut v = vec![intensity];
                    v.extend(texture.iter().flat_map(|t| t.spectra()));
                    v
                }
                LightKind::Directional { irradiance, .. } | LightKind::Sun { irradiance, .. } => {
                    vec![irradiance]
                }
                LightKind::Projector { irradiance, .. } => irradiance.spectra(),
                LightKind::Constant { radiance } => vec![radiance],
                LightKind::SunSky(s) => vec![&s.albedo],
                LightKind::EnvMap { .. } => Vec::new(),
            };
            if let Some(s) = spectra.into_iter().find(|s| s.is_spectral()) {
                return Some(format!("{}: {} emission spectrum", l.loc, s.form_name()));
            }
        }
        None
    }
}
