//! The scene description IR: what a loader produces and the renderer consumes.
//!
//! Everything here is in **world space** unless said otherwise, lengths in the scene's units
//! (metres by convention), angles in degrees where the Mitsuba format uses degrees (camera fov).
//! Colours are linear Rec.709 RGB. Every element remembers where it came from ([`SourceLoc`]) so
//! that errors found later (in the renderer) can still name the file, line and element.

use glam::{Mat4, Vec2, Vec3};
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
}

/// An emitter that is not attached to a shape, with where it was defined.
#[derive(Clone, Debug)]
pub struct LightDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// Its type and parameters.
    pub kind: LightKind,
}

/// Emitters not attached to shapes. Directions are unit vectors in world space.
#[derive(Clone, Debug)]
pub enum LightKind {
    /// Isotropic point light (Mitsuba `point`): `intensity` in W/sr, inverse-square falloff.
    Point {
        /// Position, world space.
        position: Vec3,
        /// Radiant intensity, W/sr.
        intensity: SpectrumDesc,
    },
    /// Spot light (Mitsuba `spot`): intensity `intensity` (W/sr) on its axis (local +z of
    /// `to_world`), full until `beam_width_deg` off axis, falling linearly in angle to 0 at
    /// `cutoff_deg`.
    Spot {
        /// Light-to-world transform; the light sits at its origin and points along its +z.
        to_world: Mat4,
        /// Radiant intensity on the axis, W/sr.
        intensity: SpectrumDesc,
        /// Angle from the axis beyond which no light leaves, degrees.
        cutoff_deg: f32,
        /// Angle from the axis within which the intensity is full, degrees.
        beam_width_deg: f32,
    },
    /// A distant light from one direction (Mitsuba `directional`).
    Directional {
        /// Direction the light travels in (from the light towards the scene), unit, world.
        direction: Vec3,
        /// Irradiance on a surface facing the light, W/m^2.
        irradiance: SpectrumDesc,
    },
    /// A sun: a distant light of finite angular diameter, uniform radiance over its disk, so that
    /// shadows get a penumbra (project extension `sun`).
    Sun {
        /// Direction the light travels in (from the sun towards the scene), unit, world.
        direction: Vec3,
        /// Irradiance on a surface facing the sun, W/m^2.
        irradiance: SpectrumDesc,
        /// Full angular diameter of the disk, degrees (the Sun's mean is 0.5338).
        angular_diameter_deg: f32,
    },
    /// Uniform radiance from every direction (Mitsuba `constant`).
    Constant {
        /// Radiance, W sr^-1 m^-2.
        radiance: SpectrumDesc,
    },
    /// Environment map (Mitsuba `envmap`): a latitude-longitude image of incident radiance.
    EnvMap {
        /// The image file (EXR), resolved.
        filename: PathBuf,
        /// Map-to-world transform (rotation).
        to_world: Mat4,
        /// Factor applied to the image's values.
        scale: f32,
    },
}

/// Which image axis the field of view spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    /// Horizontal (the default).
    X,
    /// Vertical.
    Y,
    /// The image diagonal.
    Diagonal,
    /// The smaller of the two image axes.
    Smaller,
    /// The larger of the two image axes.
    Larger,
}

/// Camera projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole perspective camera with the full field of view in degrees along `fov_axis`.
    Perspective {
        /// Full field of view in degrees.
        fov_deg: f32,
        /// Which image axis `fov_deg` spans.
        fov_axis: FovAxis,
    },
}

/// A camera. Camera space follows Mitsuba: it looks along +z, +y is up, +x is *left* in the image
/// (so image x grows towards camera -x). `to_world` maps camera space to world space.
#[derive(Clone, Debug)]
pub struct CameraDesc {
    /// Where it was defined (for errors).
    pub loc: SourceLoc,
    /// Projection and its parameters.
    pub projection: Projection,
    /// Camera-to-world transform (may contain scale, e.g. a mirroring `scale x=-1`).
    pub to_world: Mat4,
    /// Near clip distance along the ray, scene units.
    pub near_clip: f32,
    /// Far clip distance along the ray, scene units.
    pub far_clip: f32,
}

/// Pixel reconstruction filter (Mitsuba's `rfilter`). Radii in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterDesc {
    /// Box of the given radius (Mitsuba default radius 0.5: one pixel).
    Box {
        /// Half-width in pixels.
        radius: f32,
    },
    /// Tent (triangle) of the given radius (Mitsuba default 1.0).
    Tent {
        /// Half-width in pixels.
        radius: f32,
    },
    /// Gaussian with standard deviation `stddev` (Mitsuba default 0.5), truncated at 4 stddev.
    Gaussian {
        /// Standard deviation in pixels.
        stddev: f32,
    },
}

/// Film: image size and reconstruction filter.
#[derive(Clone, Debug)]
pub struct FilmDesc {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Reconstruction filter (Mitsuba's default is a Gaussian with stddev 0.5).
    pub filter: FilterDesc,
}

/// Sampler settings.
#[derive(Clone, Debug)]
pub struct SamplerDesc {
    /// Samples per pixel.
    pub sample_count: u32,
    /// Seed of the random streams (Mitsuba default 0).
    pub seed: u64,
}

/// Which integrator the scene asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Unidirectional path tracing with NEE and MIS (Mitsuba `path`).
    Path,
    /// Path tracing through media (Mitsuba `volpath`): as `Path`, and rays inside a shape with an
    /// interior medium are attenuated by it. (`Path` ignores media, as Mitsuba's does.)
    VolPath,
    /// Direct illumination only (Mitsuba `direct`): equivalent to `path` with max_depth 2.
    Direct,
    /// Radiosity (project extension `radiosity`): finite elements for diffuse scenes.
    Radiosity,
}

/// Options of `<integrator type="radiosity">`, as written (validated by the radiosity crate,
/// which reports errors at the integrator's location). `None` means the solver's default.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RadiosityOptions {
    /// Longest patch edge, scene units.
    pub patch_size: Option<f32>,
    /// Form-factor rays per patch.
    pub rays_per_patch: Option<u32>,
    /// Relative residual at which the solver stops.
    pub tolerance: Option<f32>,
    /// Iteration cap.
    pub max_iterations: Option<u32>,
    /// `jacobi`, `gauss_seidel` or `progressive`.
    pub solver: Option<String>,
    /// `constant`, `smoothed` or `final_gather`.
    pub display: Option<String>,
    /// `none`, `average` or `balanced`.
    pub reciprocity: Option<String>,
}

/// Integrator settings with Mitsuba semantics.
#[derive(Clone, Debug)]
pub struct IntegratorDesc {
    /// Which integrator.
    pub kind: IntegratorKind,
    /// Longest path in segments: 1 = emitters seen directly, 2 = direct light, -1 = unlimited.
    pub max_depth: i32,
    /// Depth at which Russian roulette starts (Mitsuba default 5).
    pub rr_depth: u32,
    /// Whether directly visible emitters are hidden (black).
    pub hide_emitters: bool,
    /// Whether the scene wrapped the integrator in `moment` (asks for a variance output).
    pub moment: bool,
    /// Radiosity options (with `IntegratorKind::Radiosity`).
    pub radiosity: RadiosityOptions,
    /// Where the integrator was defined (default location if the scene has none).
    pub loc: SourceLoc,
}

/// A triangle mesh in world space.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    /// Vertex positions, world space.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (unit length, world space), if the mesh has them and
    /// `face_normals` is off. Flipped already when `flip_normals` is set.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates.
    pub uvs: Option<Vec<Vec2>>,
    /// Per-vertex tangents for normal maps (glTF `TANGENT`, or generated from the uvs): xyz the
    /// direction of increasing u, world space; w = +1 or -1, the handedness: the bitangent is
    /// `w (n x t)` (glTF's convention).
    pub tangents: Option<Vec<glam::Vec4>>,
    /// Triangles as vertex index triples, counter-clockwise seen from the front side
    /// (the side the geometric normal `(p1-p0) x (p2-p0)` points to). `flip_normals` has already
    /// reversed the winding where asked.
    pub indices: Vec<[u32; 3]>,
}

/// Geometry of a shape, in world space.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// Triangles (obj, rectangle, cube, disk are all turned into this).
    Mesh(TriangleMesh),
    /// An analytic sphere. `flip_normals` makes its normal point inwards.
    Sphere {
        /// Centre, world space.
        center: Vec3,
        /// Radius, scene units.
        radius: f32,
        /// Whether the normal points inwards.
        flip_normals: bool,
    },
}

/// An area emitter attached to a shape: emits `radiance` from the shape's front side only
/// (the side its normal points to), as Mitsuba's `area` emitter does.
#[derive(Clone, Debug)]
pub struct AreaEmitterDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// Emitted radiance, W sr^-1 m^-2 (linear RGB); with `texture`, ignored; with
    /// `uv_texture`, a factor multiplying the image.
    pub radiance: SpectrumDesc,
    /// Radiance from an image over the shape's texture coordinates (a screen, a monitor).
    pub texture: Option<BitmapDesc>,
    /// pt extension: spectra of the display's red, green and blue primaries, which the
    /// texture's linear RGB drive in spectral mode (see the loader's `area_emitter`).
    pub primaries: Option<Box<[SpectrumDesc; 3]>>,
    /// Radiance image looked up at the hit's texture coordinates and multiplied by `radiance`
    /// (glTF `emissiveTexture`, sRGB-decoded; its `transform` must be the identity). Exclusive
    /// with `texture`.
    pub uv_texture: Option<Box<UvTexture>>,
}

/// A `<texture type="bitmap">`: an image looked up by texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct BitmapDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// The image file (PNG or EXR), resolved.
    pub filename: PathBuf,
    /// Use the stored values as they are (`raw`): otherwise 8-bit images are sRGB-decoded.
    pub raw: bool,
    /// `bilinear` (default) or `nearest`.
    pub filter: String,
}

/// A shape with its material and optional emitter.
#[derive(Clone, Debug)]
pub struct ShapeDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// The plugin name (`obj`, `rectangle`, `cube`, `sphere`, `disk`), for `pt info`.
    pub plugin: String,
    /// The `id` attribute, if any.
    pub id: Option<String>,
    /// World-space geometry.
    pub geometry: Geometry,
    /// Index into `SceneDesc::bsdfs`. A shape without a BSDF gets Mitsuba's default
    /// (diffuse, reflectance 0.5), which the loader inserts explicitly.
    pub bsdf: usize,
    /// The area emitter, if the shape emits.
    pub emitter: Option<AreaEmitterDesc>,
    /// The medium inside the shape (Mitsuba `<medium name="interior">`), if any. Rays that
    /// refract into the shape are attenuated by it until they leave.
    pub interior: Option<MediumDesc>,
}

/// A homogeneous, purely absorbing medium (Mitsuba `homogeneous` with `albedo` 0): radiance
/// travelling a distance d through it is multiplied by exp(-sigma_t d) (Beer-Lambert).
#[derive(Clone, Debug, PartialEq)]
pub struct MediumDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// Extinction coefficient per scene unit of length, Mitsuba's `sigma_t` already multiplied by
    /// its `scale`. Linear RGB, a constant or a tabulated spectrum, each value >= 0.
    pub sigma_t: SpectrumDesc,
}

/// A spectrum-valued parameter: linear Rec.709 RGB, one number for all channels, or a
/// tabulated spectrum (which makes the scene spectral).
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumDesc {
    /// The same value in every channel / at every wavelength.
    Constant(f32),
    /// Linear Rec.709 RGB.
    Rgb([f32; 3]),
    /// Piecewise-linear (wavelength nm, value) pairs, increasing wavelengths; zero outside
    /// their range, as Mitsuba's `<spectrum value="400:0.1, 500:0.5"/>`.
    Tabulated(std::sync::Arc<Vec<(f32, f32)>>),
    /// Planck's law at `temperature` K in W m^-2 sr^-1 nm^-1, unnormalised and zero outside
    /// 360-830 nm, as Mitsuba 3.9's `<spectrum type="blackbody">` (scene units must be metres).
    Blackbody {
        /// Temperature, K (> 0).
        temperature: f32,
    },
    /// A CIE illuminant by name, scaled to luminance Y = `scale` (a constant 1 has Y = 1):
    /// Mitsuba's `<spectrum type="d65"/>`, and the project extension `type="a"` and
    /// `type="f1"` .. `type="f12"` (the CIE fluorescent-lamp series).
    Illuminant {
        /// `d65`, `a` or `f1` .. `f12` (lower case).
        name: String,
        /// Luminance, >= 0.
        scale: f32,
    },
}

impl SpectrumDesc {
    /// Whether the value depends on wavelength in a way RGB cannot represent exactly.
    pub fn is_spectral(&self) -> bool {
        matches!(
            self,
            SpectrumDesc::Tabulated(_)
                | SpectrumDesc::Blackbody { .. }
                | SpectrumDesc::Illuminant { .. }
        )
    }

    /// How `pt info` names a wavelength-dependent form: `tabulated`, `blackbody`, `CIE F11`, ...
    pub fn form_name(&self) -> String {
        match self {
            SpectrumDesc::Constant(_) => "constant".into(),
            SpectrumDesc::Rgb(_) => "RGB".into(),
            SpectrumDesc::Tabulated(_) => "tabulated".into(),
            SpectrumDesc::Blackbody { temperature } => format!("blackbody ({temperature} K)"),
            SpectrumDesc::Illuminant { name, .. } => format!("CIE {}", name.to_ascii_uppercase()),
        }
    }

    /// Whether this is an emission-only form (blackbody, named illuminant), which makes no
    /// sense as a reflectance.
    pub fn is_emission_only(&self) -> bool {
        matches!(
            self,
            SpectrumDesc::Blackbody { .. } | SpectrumDesc::Illuminant { .. }
        )
    }

    /// Every number in it (channels, tabulated values, an illuminant's scale; none for a
    /// blackbody, whose temperature is checked when parsed), for range checks.
    pub fn values(&self) -> Vec<f32> {
        match self {
            SpectrumDesc::Constant(c) => vec![*c],
            SpectrumDesc::Rgb(c) => c.to_vec(),
            SpectrumDesc::Tabulated(p) => p.iter().map(|e| e.1).collect(),
            SpectrumDesc::Blackbody { .. } => vec![],
            SpectrumDesc::Illuminant { scale, .. } => vec![*scale],
        }
    }
}

impl SceneDesc {
    /// Why the scene needs spectral transport (the first wavelength-dependent input found, with
    /// its location), or `None` when RGB is exact for it.
    pub fn spectral_reason(&self) -> Option<String> {
        fn bsdf_spectra(k: &BsdfKind) -> Vec<&SpectrumDesc> {
            match k {
                BsdfKind::Diffuse { reflectance }
                | BsdfKind::OrenNayar { reflectance, .. }
                | BsdfKind::Minnaert { reflectance, .. } => vec![reflectance],
                BsdfKind::TwoSided { inner }
                | BsdfKind::Mask { inner, .. }
                | BsdfKind::NormalMap { inner, .. }
                | BsdfKind::FilmThicknessTexture { inner, .. }
                | BsdfKind::OpacityTexture { inner, .. } => bsdf_spectra(&inner.kind),
                BsdfKind::Conductor {
                    eta,
                    k,
                    specular_reflectance,
                }
                | BsdfKind::RoughConductor {
                    eta,
                    k,
                    specular_reflectance,
                    ..
                } => {
                    vec![eta, k, specular_reflectance]
                }
                BsdfKind::Dielectric { .. }
                | BsdfKind::ThinDielectric { .. }
                | BsdfKind::RoughDielectric { .. } => vec![],
                BsdfKind::ThinFilm { eta, k, .. } | BsdfKind::RoughThinFilm { eta, k, .. } => {
                    vec![eta, k]
                }
                BsdfKind::GltfPbr { base_color, .. } => vec![base_color],
                BsdfKind::RoughPlastic {
                    diffuse_reflectance,
                    specular_reflectance,
                    ..
                } => vec![diffuse_reflectance, specular_reflectance],
                BsdfKind::Fluorescent {
                    reflectance,
                    absorption,
                    emission,
                    ..
                } => vec![reflectance, absorption, emission],
                BsdfKind::Blend { first, second, .. } => bsdf_spectra(&first.kind)
                    .into_iter()
                    .chain(bsdf_spectra(&second.kind))
                    .collect(),
                BsdfKind::Phosphorescent { reflectance, .. } => vec![reflectance],
            }
        }
        fn has_thin_film(k: &BsdfKind) -> bool {
            match k {
                BsdfKind::ThinFilm { .. } | BsdfKind::RoughThinFilm { .. } => true,
                BsdfKind::Blend { first, second, .. } => {
                    has_thin_film(&first.kind) || has_thin_film(&second.kind)
                }
                BsdfKind::TwoSided { inner }
                | BsdfKind::Mask { inner, .. }
                | BsdfKind::NormalMap { inner, .. }
                | BsdfKind::FilmThicknessTexture { inner, .. }
                | BsdfKind::OpacityTexture { inner, .. } => has_thin_film(&inner.kind),
                _ => false,
            }
        }
        fn is_fluorescent(k: &BsdfKind) -> bool {
            match k {
                BsdfKind::Fluorescent { .. } => true,
                BsdfKind::Blend { first, second, .. } => {
                    is_fluorescent(&first.kind) || is_fluorescent(&second.kind)
                }
                BsdfKind::TwoSided { inner }
                | BsdfKind::Mask { inner, .. }
                | BsdfKind::NormalMap { inner, .. }
                | BsdfKind::FilmThicknessTexture { inner, .. }
                | BsdfKind::OpacityTexture { inner, .. } => is_fluorescent(&inner.kind),
                _ => false,
            }
        }
        for b in &self.bsdfs {
            if is_fluorescent(&b.kind) {
                return Some(format!(
                    "{}: fluorescence moves light between wavelengths (RGB mode cannot express it)",
                    b.loc
                ));
            }
        }
        for b in &self.bsdfs {
            if has_thin_film(&b.kind) {
                return Some(format!("{}: thin-film interference depends on wavelength (RGB mode can only approximate it, with Belcour & Barla 2017)", b.loc));
            }
        }
        for b in &self.bsdfs {
            if let Some(s) = bsdf_spectra(&b.kind).into_iter().find(|s| s.is_spectral()) {
                return Some(format!("{}: {} spectrum in a BSDF", b.loc, s.form_name()));
            }
        }
        for s in &self.shapes {
            if let Some(e) = &s.emitter {
                if e.radiance.is_spectral() {
                    return Some(format!(
                        "{}: {} emission spectrum",
                        e.loc,
                        e.radiance.form_name()
                    ));
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
            let spectrum = match &l.kind {
                LightKind::Point { intensity, .. } | LightKind::Spot { intensity, .. } => {
                    Some(intensity)
                }
                LightKind::Directional { irradiance, .. } | LightKind::Sun { irradiance, .. } => {
                    Some(irradiance)
                }
                LightKind::Constant { radiance } => Some(radiance),
                LightKind::EnvMap { .. } => None,
            };
            if let Some(s) = spectrum.filter(|s| s.is_spectral()) {
                return Some(format!("{}: {} emission spectrum", l.loc, s.form_name()));
            }
        }
        None
    }
}

/// A BSDF as described in the scene.
#[derive(Clone, Debug)]
pub struct BsdfDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// The `id` attribute, if any.
    pub id: Option<String>,
    /// The model and its parameters.
    pub kind: BsdfKind,
}

/// The BSDF models the loader knows.
#[derive(Clone, Debug)]
pub enum BsdfKind {
    /// Lambertian reflection with the given albedo (one-sided: black from the back).
    Diffuse {
        /// Albedo in [0, 1] per channel.
        reflectance: SpectrumDesc,
    },
    /// Makes the inner BSDF act the same on both sides (Mitsuba `twosided`).
    TwoSided {
        /// The wrapped BSDF.
        inner: Box<BsdfDesc>,
    },
    /// Opacity mask (Mitsuba `mask`): with probability `opacity` light meets the inner BSDF,
    /// otherwise it passes straight through.
    Mask {
        /// Opacity in [0, 1].
        opacity: f32,
        /// The wrapped BSDF.
        inner: Box<BsdfDesc>,
    },
    /// Normal map (Mitsuba `normalmap`; glTF `normalTexture`): the inner BSDF is evaluated in
    /// the shading frame perturbed by the texture's normal (pt-bsdf `normal_map`).
    NormalMap {
        /// The texture: RGB = (n + 1) / 2, linear data unless `srgb` (Mitsuba's bitmap without
        /// `raw`).
        texture: Box<UvTexture>,
        /// glTF `normalTexture.scale`: multiplies the x and y of the decoded normal (1 for
        /// Mitsuba).
        scale: f32,
        /// Whose tangent space: `true` for glTF (frame from the mesh's tangents, y along
        /// `w (n x t)`), `false` for Mitsuba (x along dp/du, y = n x x).
        gltf: bool,
        /// The wrapped BSDF.
        inner: Box<BsdfDesc>,
    },
    /// Mixture of two BSDFs (Mitsuba `blendbsdf`): `(1 - weight) first + weight second`
    /// (pt-bsdf `blend`).
    Blend {
        /// Share of `second`, in [0, 1].
        weight: f32,
        /// A texture whose value (in the given channel) multiplies `weight` at the hit (glTF
        /// `iridescenceTexture`: red).
        weight_texture: Option<(Box<UvTexture>, TextureChannel)>,
        /// The first nested BSDF.
        first: Box<BsdfDesc>,
        /// The second nested BSDF.
        second: Box<BsdfDesc>,
    },
    /// Opacity mask whose opacity varies over the surface (Mitsuba `mask` with a bitmap
    /// `opacity`; glTF alpha from the base colour texture): as [`BsdfKind::Mask`] with the
    /// opacity of the hit's texel.
    OpacityTexture {
        /// The texture.
        texture: Box<UvTexture>,
        /// Which value of the texel is the opacity.
        channel: TextureChannel,
        /// Multiplies the texel's value (glTF `baseColorFactor` alpha; 1 for Mitsuba).
        factor: f32,
        /// glTF `alphaMode` MASK: opacity 1 where `factor x value >= cutoff`, else 0.
        cutoff: Option<f32>,
        /// The wrapped BSDF.
        inner: Box<BsdfDesc>,
    },
    /// A thin film (`inner`: `ThinFilm` or `RoughThinFilm`, possibly inside `TwoSided`) whose
    /// thickness varies over the surface (glTF `iridescenceThicknessTexture`): thickness =
    /// `min_nm + (max_nm - min_nm) g` with g the texture's green channel (linear data) at the
    /// hit's uv; the inner film's own thickness is not used.
    FilmThicknessTexture {
        /// The texture (green channel used).
        texture: Box<UvTexture>,
        /// Thickness where green is 0, nm.
        min_nm: f32,
        /// Thickness where green is 1, nm.
        max_nm: f32,
        /// The film.
        inner: Box<BsdfDesc>,
    },
    /// Oren-Nayar rough diffuse (project extension `orennayar`).
    OrenNayar {
        /// Facet albedo.
        reflectance: SpectrumDesc,
        /// Standard deviation of the facet slope angle, radians.
        sigma: f32,
        /// `qualitative`, `full`, `fujii` or `eon`.
        variant: String,
    },
    /// Minnaert's limb-darkening BRDF (project extension `minnaert`).
    Minnaert {
        /// Albedo scale.
        reflectance: SpectrumDesc,
        /// Minnaert exponent k (1 = Lambert).
        k: f32,
    },
    /// Smooth dielectric interface (Mitsuba `dielectric`).
    Dielectric {
        /// Interior index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
    },
    /// Thin dielectric slab (Mitsuba `thindielectric`).
    ThinDielectric {
        /// Interior index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
    },
    /// Rough dielectric interface (Mitsuba `roughdielectric`).
    RoughDielectric {
        /// Interior index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Microfacet distribution: `ggx` or `beckmann`.
        distribution: String,
        /// Roughness along the tangent.
        alpha_u: f32,
        /// Roughness along the bitangent.
        alpha_v: f32,
    },
    /// Smooth conductor (Mitsuba `conductor`).
    Conductor {
        /// Real part of the complex index of refraction (n + i k).
        eta: SpectrumDesc,
        /// Imaginary part (extinction coefficient).
        k: SpectrumDesc,
        /// Scale factor on the reflectance (1 is physical).
        specular_reflectance: SpectrumDesc,
    },
    /// Thin-film interference (project extension `thinfilm`): a non-absorbing film over a
    /// dielectric or conductor base, smooth.
    ThinFilm {
        /// Film thickness, nm.
        thickness: f32,
        /// Film index of refraction.
        film_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Dielectric base index (`int_ior`), or None for a conductor base.
        int_ior: Option<f32>,
        /// Conductor base real index (with `int_ior` None).
        eta: SpectrumDesc,
        /// Conductor base extinction coefficient (with `int_ior` None).
        k: SpectrumDesc,
    },
    /// Thin film on a rough base (project extension `roughthinfilm`): the smooth film's
    /// parameters plus a microfacet distribution.
    RoughThinFilm {
        /// Film thickness, nm.
        thickness: f32,
        /// Film index of refraction.
        film_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Dielectric base index (`int_ior`), or None for a conductor base.
        int_ior: Option<f32>,
        /// Conductor base real index (with `int_ior` None).
        eta: SpectrumDesc,
        /// Conductor base extinction coefficient (with `int_ior` None).
        k: SpectrumDesc,
        /// Microfacet distribution: `ggx` or `beckmann`.
        distribution: String,
        /// Roughness along the tangent.
        alpha_u: f32,
        /// Roughness along the bitangent.
        alpha_v: f32,
    },
    /// Rough plastic: rough dielectric coating over a diffuse base (Mitsuba `roughplastic`).
    RoughPlastic {
        /// Albedo of the diffuse base.
        diffuse_reflectance: SpectrumDesc,
        /// Multiplier of the coating's reflection.
        specular_reflectance: SpectrumDesc,
        /// Coating index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Microfacet distribution: `ggx` or `beckmann`.
        distribution: String,
        /// Roughness (isotropic).
        alpha: f32,
        /// Mitsuba's `nonlinear`: account for the colour shift of inner bounces.
        nonlinear: bool,
    },
    /// Rough conductor (Mitsuba `roughconductor`).
    RoughConductor {
        /// Real part of the complex index of refraction.
        eta: SpectrumDesc,
        /// Extinction coefficient.
        k: SpectrumDesc,
        /// Scale factor on the reflectance.
        specular_reflectance: SpectrumDesc,
        /// Microfacet distribution: `ggx` or `beckmann`.
        distribution: String,
        /// Roughness along the tangent.
        alpha_u: f32,
        /// Roughness along the bitangent.
        alpha_v: f32,
    },
    /// Fluorescent Lambertian surface (project extension `fluorescent`; model and transport in
    /// pt-render's `fluorescence.rs`): elastic diffuse reflectance plus absorption re-emitted at
    /// longer wavelengths with the given emission spectrum and quantum yield.
    Fluorescent {
        /// Elastic (wavelength-preserving) diffuse reflectance, in [0, 1].
        reflectance: SpectrumDesc,
        /// Fraction of incident photons absorbed by the fluorophore, in [0, 1], with
        /// reflectance + absorption <= 1 at every wavelength.
        absorption: SpectrumDesc,
        /// Emission spectrum (shape only: normalised to unit area over 360-830 nm when built).
        emission: SpectrumDesc,
        /// Quantum yield, emitted / absorbed photons, in [0, 1].
        quantum_yield: f32,
    },
    /// Phosphorescent Lambertian surface (project extension `phosphorescent`; model in
    /// pt-render's `phosphorescence.rs`): renders as its elastic reflectance with the lights
    /// on; with `pt render --time T` it glows with exponentially decaying afterglow.
    Phosphorescent {
        /// Elastic diffuse reflectance, in [0, 1].
        reflectance: SpectrumDesc,
        /// Fraction of incident photons stored, in [0, 1].
        absorption: SpectrumDesc,
        /// Afterglow emission spectrum (shape only, normalised per nm when used).
        emission: SpectrumDesc,
        /// Quantum yield, emitted / stored photons, in [0, 1].
        quantum_yield: f32,
        /// Lifetime tau of the stored state, seconds (> 0).
        lifetime: f32,
    },
    /// glTF 2.0 metallic-roughness material (read from glTF files; pt-bsdf `GltfPbr`).
    GltfPbr {
        /// Base colour (linear albedo): the diffuse colour of the dielectric and F0 of the metal.
        base_color: SpectrumDesc,
        /// Metalness in [0, 1].
        metallic: f32,
        /// Perceptual roughness in [0, 1]; GGX alpha = roughness^2.
        roughness: f32,
        /// Index of refraction of the dielectric part (1.5 unless KHR_materials_ior).
        ior: f32,
        /// Base colour texture (sRGB-decoded), multiplying `base_color` at the hit's uv.
        base_color_texture: Option<Box<UvTexture>>,
        /// Metallic-roughness texture (linear): blue multiplies `metallic`, green `roughness`.
        metallic_roughness_texture: Option<Box<UvTexture>>,
    },
}

/// Which value of a texel a scalar texture (opacity, blend weight) reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureChannel {
    /// Rec. 709 luminance of the linear RGB (Mitsuba's `eval_1` of an RGB bitmap; the value
    /// itself for a grey image).
    Luminance,
    /// The alpha channel, stored linearly (glTF: 1 where the image has no alpha).
    Alpha,
    /// The red channel (glTF `iridescenceTexture`).
    Red,
}

/// Image data of a texture: a file, or bytes embedded in the scene file (a glTF buffer view or
/// `data:` URI).
#[derive(Clone, PartialEq)]
pub enum ImageSource {
    /// An image file (PNG or JPEG), resolved.
    File(PathBuf),
    /// Encoded image bytes (PNG or JPEG) and a name for messages.
    Embedded {
        /// Where the bytes came from, e.g. `images[0]`.
        name: String,
        /// The encoded image.
        bytes: std::sync::Arc<Vec<u8>>,
    },
}

/// Names the image instead of listing its bytes (`pt info` prints materials with `{:?}`).
impl std::fmt::Debug for ImageSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ImageSource::File(p) => write!(f, "File({p:?})"),
            ImageSource::Embedded { name, bytes } => {
                write!(f, "Embedded({name}, {} bytes)", bytes.len())
            }
        }
    }
}

/// A texture looked up at the hit's texture coordinates (glTF `textureInfo`): the image is
/// repeated outside [0, 1]^2, row 0 at v = 0 (the image's top row), as glTF and Mitsuba.
#[derive(Clone, Debug, PartialEq)]
pub struct UvTexture {
    /// The image.
    pub source: ImageSource,
    /// sRGB-decode the stored values (colour data); false: use them as they are (linear data).
    pub srgb: bool,
    /// Nearest-texel lookup (glTF sampler `magFilter` NEAREST); otherwise bilinear.
    pub nearest: bool,
    /// Affine map of the texture coordinates applied before the lookup (KHR_texture_transform),
    /// rows `[a, b, c, d, e, f]`: `u' = a u + b v + c`, `v' = d u + e v + f`.
    pub transform: [f32; 6],
}
