//! BSDF descriptions: Mitsuba's plugins and the project's extensions, with their parameters
//! as written (texturable ones as [`TextureDesc`]).

use super::{SourceLoc, SpectrumDesc, TextureDesc};

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

/// A microfacet normal distribution (Mitsuba's `distribution`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MicrofacetDistribution {
    /// Beckmann (Mitsuba's default).
    #[default]
    Beckmann,
    /// GGX / Trowbridge-Reitz.
    Ggx,
}

/// The microfacet parameters of a rough model: distribution and roughness along the tangent
/// (`alpha_u`, along dp/du) and the bitangent (`alpha_v`); `alpha` sets both.
#[derive(Clone, Debug, PartialEq)]
pub struct MicrofacetDesc {
    /// The normal distribution.
    pub distribution: MicrofacetDistribution,
    /// Roughness along the tangent (scalar texture, > 0).
    pub alpha_u: TextureDesc,
    /// Roughness along the bitangent (scalar texture, > 0).
    pub alpha_v: TextureDesc,
}

/// The Oren-Nayar formulation (project extension `orennayar`, `variant`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum OrenNayarVariant {
    /// The qualitative model of Oren & Nayar 1994 (their eq. 30), the default.
    #[default]
    Qualitative,
    /// The full 1994 model with its interreflection term.
    Full,
    /// Fujii's improved formulation.
    Fujii,
    /// Portsmouth et al.'s energy-preserving Oren-Nayar (EON).
    Eon,
}

/// What a thin film lies on.
#[derive(Clone, Debug, PartialEq)]
pub enum FilmBaseDesc {
    /// A dielectric of index `int_ior`.
    Dielectric {
        /// Index of refraction of the base.
        int_ior: f32,
    },
    /// A conductor of complex index `eta + i k` (unbounded textures).
    Conductor {
        /// Real part.
        eta: TextureDesc,
        /// Imaginary part (extinction coefficient).
        k: TextureDesc,
    },
}

/// The BSDF models the loader knows.
#[derive(Clone, Debug)]
pub enum BsdfKind {
    /// Lambertian reflection (Mitsuba `diffuse`; one-sided: black from the back).
    Diffuse {
        /// Albedo in [0, 1].
        reflectance: TextureDesc,
    },
    /// Makes the inner BSDF act the same on both sides (Mitsuba `twosided`).
    TwoSided {
        /// The wrapped BSDF.
        inner: Box<BsdfDesc>,
    },
    /// Opacity mask (Mitsuba `mask`): with probability `opacity` light meets the inner BSDF,
    /// otherwise it passes straight through.
    Mask {
        /// Opacity in [0, 1] (a scalar texture, clamped).
        opacity: TextureDesc,
        /// glTF `alphaMode` MASK: opacity 1 where the texture is at least this, else 0.
        cutoff: Option<f32>,
        /// The wrapped BSDF.
        inner: Box<BsdfDesc>,
    },
    /// Normal map (Mitsuba `normalmap`; glTF `normalTexture`): the inner BSDF is evaluated in
    /// the shading frame perturbed by the texture's normal (pt-bsdf `normal_map`).
    NormalMap {
        /// The texture: RGB = (n + 1) / 2 (read as data, without spectral upsampling).
        texture: TextureDesc,
        /// glTF `normalTexture.scale`: multiplies the x and y of the decoded normal (1 for
        /// Mitsuba).
        scale: f32,
        /// Whose tangent space: `true` for glTF (frame from the mesh's tangents, y along
        /// `w (n x t)`), `false` for Mitsuba (x along dp/du, y = n x x).
        gltf: bool,
        /// The wrapped BSDF.
        inner: Box<BsdfDesc>,
    },
    /// Bump map (Mitsuba `bumpmap`): the inner BSDF is evaluated in the shading frame whose
    /// normal is that of the surface displaced along its normal by `scale` times the height
    /// texture (only the height's uv gradient matters; pt-render's material layer).
    BumpMap {
        /// The height field, a bitmap read as a scalar (its luminance), per unit of uv.
        height: TextureDesc,
        /// Factor on the height's gradient.
        scale: f32,
        /// The wrapped BSDF.
        inner: Box<BsdfDesc>,
    },
    /// Mixture of two BSDFs (Mitsuba `blendbsdf`): `(1 - weight) first + weight second`.
    Blend {
        /// Share of `second` (a scalar texture, clamped to [0, 1]).
        weight: TextureDesc,
        /// The first nested BSDF.
        first: Box<BsdfDesc>,
        /// The second nested BSDF.
        second: Box<BsdfDesc>,
    },
    /// Oren-Nayar rough diffuse (project extension `orennayar`).
    OrenNayar {
        /// Facet albedo.
        reflectance: TextureDesc,
        /// Standard deviation of the facet slope angle, radians (scalar texture).
        sigma: TextureDesc,
        /// Which formulation.
        variant: OrenNayarVariant,
    },
    /// Minnaert's limb-darkening BRDF (project extension `minnaert`).
    Minnaert {
        /// Albedo scale.
        reflectance: TextureDesc,
        /// Minnaert exponent k, > 0 (1 = Lambert; scalar texture).
        k: TextureDesc,
    },
    /// Smooth dielectric interface (Mitsuba `dielectric`).
    Dielectric {
        /// Interior index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Factor on the reflected part (1 is physical).
        specular_reflectance: TextureDesc,
        /// Factor on the transmitted part (1 is physical).
        specular_transmittance: TextureDesc,
    },
    /// Thin dielectric slab (Mitsuba `thindielectric`).
    ThinDielectric {
        /// Interior index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Factor on the reflected part.
        specular_reflectance: TextureDesc,
        /// Factor on the transmitted part.
        specular_transmittance: TextureDesc,
    },
    /// Rough dielectric interface (Mitsuba `roughdielectric`).
    RoughDielectric {
        /// Interior index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Distribution and roughness.
        microfacet: MicrofacetDesc,
        /// Factor on the reflected part.
        specular_reflectance: TextureDesc,
        /// Factor on the transmitted part.
        specular_transmittance: TextureDesc,
    },
    /// Smooth conductor (Mitsuba `conductor`).
    Conductor {
        /// Real part of the complex index of refraction (n + i k).
        eta: TextureDesc,
        /// Imaginary part (extinction coefficient).
        k: TextureDesc,
        /// Factor on the reflectance (1 is physical).
        specular_reflectance: TextureDesc,
    },
    /// Rough conductor (Mitsuba `roughconductor`).
    RoughConductor {
        /// Real part of the complex index of refraction.
        eta: TextureDesc,
        /// Extinction coefficient.
        k: TextureDesc,
        /// Factor on the reflectance.
        specular_reflectance: TextureDesc,
        /// Distribution and roughness.
        microfacet: MicrofacetDesc,
    },
    /// Thin-film interference (project extension `thinfilm`): a non-absorbing film over a
    /// dielectric or conductor base, smooth.
    ThinFilm {
        /// Film thickness, nm (scalar texture, >= 0).
        thickness: TextureDesc,
        /// Film index of refraction.
        film_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// What the film lies on.
        base: FilmBaseDesc,
    },
    /// Thin film on a rough base (project extension `roughthinfilm`).
    RoughThinFilm {
        /// Film thickness, nm (scalar texture, >= 0).
        thickness: TextureDesc,
        /// Film index of refraction.
        film_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// What the film lies on.
        base: FilmBaseDesc,
        /// Distribution and roughness of the base.
        microfacet: MicrofacetDesc,
    },
    /// Smooth plastic: smooth dielectric coating over a diffuse base (Mitsuba `plastic`).
    Plastic {
        /// Albedo of the diffuse base.
        diffuse_reflectance: TextureDesc,
        /// Factor on the coating's reflection.
        specular_reflectance: TextureDesc,
        /// Coating index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Mitsuba's `nonlinear`: account for the colour shift of inner bounces.
        nonlinear: bool,
    },
    /// Mitsuba's `pplastic` as its unpolarized variants render it: a microfacet reflection
    /// added to a Lambertian base seen through two smooth refractions (Baek et al. 2018).
    PPlastic {
        /// Albedo of the base.
        diffuse_reflectance: TextureDesc,
        /// Factor on the reflection.
        specular_reflectance: TextureDesc,
        /// Interior index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Distribution and roughness of the reflection.
        microfacet: MicrofacetDesc,
    },
    /// Mitsuba's polarizing elements (`polarizer`, `retarder`, `circular`) as its unpolarized
    /// variants render them: light passes straight through, keeping the element's fraction of
    /// unpolarized light ([`PolarizingElement::unpolarized_fraction`]) times `transmittance`.
    Polarizer {
        /// Which element.
        element: PolarizingElement,
        /// Transmittance besides the element's own fraction.
        transmittance: TextureDesc,
    },
    /// Mitsuba's `hair`: Chiang et al. 2016's fibre model (pt-bsdf `hair.rs`), the fibre along
    /// the local frame's second tangent (`n x dp/du`).
    Hair {
        /// Where the absorption comes from.
        absorption: HairAbsorption,
        /// Relative index of refraction, fibre over outside.
        eta: f32,
        /// Longitudinal roughness b_m in [0, 1].
        longitudinal_roughness: f32,
        /// Azimuthal roughness b_n in [0, 1].
        azimuthal_roughness: f32,
        /// Angle of the cuticle scales, degrees.
        scale_tilt_deg: f32,
    },
    /// Rough plastic: rough dielectric coating over a diffuse base (Mitsuba `roughplastic`).
    RoughPlastic {
        /// Albedo of the diffuse base.
        diffuse_reflectance: TextureDesc,
        /// Factor on the coating's reflection.
        specular_reflectance: TextureDesc,
        /// Coating index of refraction.
        int_ior: f32,
        /// Exterior index of refraction.
        ext_ior: f32,
        /// Microfacet distribution.
        distribution: MicrofacetDistribution,
        /// Roughness (isotropic, not texturable, as in Mitsuba).
        alpha: f32,
        /// Mitsuba's `nonlinear`: account for the colour shift of inner bounces.
        nonlinear: bool,
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
    /// pt-integrators' `afterglow.rs`): renders as its elastic reflectance with the lights
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
        base_color: TextureDesc,
        /// Metalness in [0, 1] (scalar texture).
        metallic: TextureDesc,
        /// Perceptual roughness in [0, 1]; GGX alpha = roughness^2 (scalar texture).
        roughness: TextureDesc,
        /// Index of refraction of the dielectric part (1.5 unless KHR_materials_ior).
        ior: f32,
    },
    /// Mitsuba's `principled` (its Disney BSDF; model in pt-bsdf's `principled.rs`).
    Principled(Box<PrincipledDesc>),
    /// Mitsuba's `principledthin` (model in pt-bsdf's `principled_thin.rs`).
    PrincipledThin(Box<PrincipledThinDesc>),
}

/// The parameters of Mitsuba's `principledthin` (defaults and meaning in pt-bsdf's
/// `principled_thin.rs`). The scalar ones are scalar textures.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledThinDesc {
    /// Base colour (albedo).
    pub base_color: TextureDesc,
    /// `roughness`, `anisotropic`, `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`,
    /// `flatness`, `diff_trans` (in [0, 2]) and `eta`, in this order.
    pub scalars: [TextureDesc; 9],
    /// Lobe selection weights: specular reflection, specular transmission, diffuse
    /// reflection, diffuse transmission.
    pub rates: [f32; 4],
}

impl PrincipledThinDesc {
    /// The names of `scalars`, in order.
    pub const NAMES: [&'static str; 9] = [
        "roughness",
        "anisotropic",
        "spec_trans",
        "spec_tint",
        "sheen",
        "sheen_tint",
        "flatness",
        "diff_trans",
        "eta",
    ];
}

/// The parameters of Mitsuba's `principled` (defaults and meaning in pt-bsdf's
/// `principled.rs`). The scalar ones are scalar textures.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledDesc {
    /// Base colour (albedo).
    pub base_color: TextureDesc,
    /// The scalar weights, in the order of [`PrincipledDesc::NAMES`], each in [0, 1].
    pub scalars: [TextureDesc; 10],
    /// Relative index of refraction (from `eta`, or from `specular`).
    pub eta: f32,
    /// Whether `spec_trans` was given (Mitsuba then adds the transmission lobe).
    pub transmissive: bool,
    /// Lobe selection weights: main specular, clearcoat, diffuse.
    pub rates: [f32; 3],
}

impl PrincipledDesc {
    /// The names of `scalars`, in order.
    pub const NAMES: [&'static str; 10] = [
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
    ];
}

impl BsdfKind {
    /// The BSDFs nested directly inside this one (wrappers and blends).
    pub fn nested(&self) -> Vec<&BsdfDesc> {
        match self {
            BsdfKind::TwoSided { inner }
            | BsdfKind::Mask { inner, .. }
            | BsdfKind::NormalMap { inner, .. }
            | BsdfKind::BumpMap { inner, .. } => vec![inner],
            BsdfKind::Blend { first, second, .. } => vec![first, second],
            _ => Vec::new(),
        }
    }

    /// Every texturable parameter of this model (not of nested BSDFs), with its name.
    pub fn textures(&self) -> Vec<(&'static str, &TextureDesc)> {
        match self {
            BsdfKind::Diffuse { reflectance } => vec![("reflectance", reflectance)],
            BsdfKind::TwoSided { .. } => Vec::new(),
            BsdfKind::Mask { opacity, .. } => vec![("opacity", opacity)],
            BsdfKind::NormalMap { texture, .. } => vec![("normalmap", texture)],
            BsdfKind::BumpMap { height, .. } => vec![("bumpmap", height)],
            BsdfKind::Blend { weight, .. } => vec![("weight", weight)],
            BsdfKind::OrenNayar {
                reflectance, sigma, ..
            } => vec![("reflectance", reflectance), ("sigma", sigma)],
            BsdfKind::Minnaert { reflectance, k } => vec![("reflectance", reflectance), ("k", k)],
            BsdfKind::Dielectric {
                specular_reflectance,
                specular_transmittance,
                ..
            }
            | BsdfKind::ThinDielectric {
                specular_reflectance,
                specular_transmittance,
                ..
            } => vec![
                ("specular_reflectance", specular_reflectance),
                ("specular_transmittance", specular_transmittance),
            ],
            BsdfKind::RoughDielectric {
                microfacet,
                specular_reflectance,
                specular_transmittance,
                ..
            } => vec![
                ("alpha_u", &microfacet.alpha_u),
                ("alpha_v", &microfacet.alpha_v),
                ("specular_reflectance", specular_reflectance),
                ("specular_transmittance", specular_transmittance),
            ],
            BsdfKind::Conductor {
                eta,
                k,
                specular_reflectance,
            } => vec![
                ("eta", eta),
                ("k", k),
                ("specular_reflectance", specular_reflectance),
            ],
            BsdfKind::RoughConductor {
                eta,
                k,
                specular_reflectance,
                microfacet,
            } => vec![
                ("eta", eta),
                ("k", k),
                ("specular_reflectance", specular_reflectance),
                ("alpha_u", &microfacet.alpha_u),
                ("alpha_v", &microfacet.alpha_v),
            ],
            BsdfKind::ThinFilm {
                thickness, base: b, ..
            } => {
                let mut v = vec![("thickness", thickness)];
                v.extend(film_base_textures(b));
                v
            }
            BsdfKind::RoughThinFilm {
                thickness,
                base: b,
                microfacet,
                ..
            } => {
                let mut v = vec![("thickness", thickness)];
                v.extend(film_base_textures(b));
                v.push(("alpha_u", &microfacet.alpha_u));
                v.push(("alpha_v", &microfacet.alpha_v));
                v
            }
            BsdfKind::Plastic {
                diffuse_reflectance,
                specular_reflectance,
                ..
            }
            | BsdfKind::RoughPlastic {
                diffuse_reflectance,
                specular_reflectance,
                ..
            } => vec![
                ("diffuse_reflectance", diffuse_reflectance),
                ("specular_reflectance", specular_reflectance),
            ],
            BsdfKind::PPlastic {
                diffuse_reflectance,
                specular_reflectance,
                microfacet,
                ..
            } => vec![
                ("diffuse_reflectance", diffuse_reflectance),
                ("specular_reflectance", specular_reflectance),
                ("alpha_u", &microfacet.alpha_u),
                ("alpha_v", &microfacet.alpha_v),
            ],
            BsdfKind::Polarizer { transmittance, .. } => vec![("transmittance", transmittance)],
            BsdfKind::Hair { absorption, .. } => match absorption {
                HairAbsorption::Pigments { .. } => Vec::new(),
                HairAbsorption::SigmaA { sigma_a, .. } => vec![("sigma_a", sigma_a)],
                HairAbsorption::Reflectance(r) => vec![("reflectance", r)],
            },
            BsdfKind::Fluorescent { .. } | BsdfKind::Phosphorescent { .. } => Vec::new(),
            BsdfKind::GltfPbr {
                base_color,
                metallic,
                roughness,
                ..
            } => vec![
                ("base_color", base_color),
                ("metallic", metallic),
                ("roughness", roughness),
            ],
            BsdfKind::Principled(p) => std::iter::once(("base_color", &p.base_color))
                .chain(PrincipledDesc::NAMES.into_iter().zip(&p.scalars))
                .collect(),
            BsdfKind::PrincipledThin(p) => std::iter::once(("base_color", &p.base_color))
                .chain(PrincipledThinDesc::NAMES.into_iter().zip(&p.scalars))
                .collect(),
        }
    }

    /// The spectra of the non-texturable spectral parameters (fluorescence, phosphorescence).
    pub fn fixed_spectra(&self) -> Vec<&SpectrumDesc> {
        match self {
            BsdfKind::Fluorescent {
                reflectance,
                absorption,
                emission,
                ..
            } => vec![reflectance, absorption, emission],
            BsdfKind::Phosphorescent { reflectance, .. } => vec![reflectance],
            _ => Vec::new(),
        }
    }
}

/// The texturable parameters of a thin film's base.
fn film_base_textures(b: &FilmBaseDesc) -> Vec<(&'static str, &TextureDesc)> {
    match b {
        FilmBaseDesc::Dielectric { .. } => Vec::new(),
        FilmBaseDesc::Conductor { eta, k } => vec![("eta", eta), ("k", k)],
    }
}

/// The absorption inside a hair fibre (per unit fibre radius).
#[derive(Clone, Debug, PartialEq)]
pub enum HairAbsorption {
    /// Pigment concentrations (Mitsuba's default: eumelanin 1.3, pheomelanin 0.2), with the
    /// absorption spectra of d'Eon et al. 2011.
    Pigments {
        /// Eumelanin concentration.
        eumelanin: f32,
        /// Pheomelanin concentration.
        pheomelanin: f32,
    },
    /// An absorption coefficient `sigma_a` times `scale` (Mitsuba).
    SigmaA {
        /// Absorption coefficient.
        sigma_a: TextureDesc,
        /// Factor on it.
        scale: f32,
    },
    /// The colour the fibres should have, turned into an absorption by Chiang et al. 2016's
    /// eq. 9 (pbrt-v4's `reflectance`; pt extension).
    Reflectance(TextureDesc),
}

/// Mitsuba's ideal polarizing elements, which its unpolarized variants render as straight
/// transmission of a fixed fraction of the light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PolarizingElement {
    /// `polarizer`: a linear polarizer.
    LinearPolarizer,
    /// `retarder`: a linear retarder (wave plate), which changes only the polarization.
    Retarder,
    /// `circular`: a circular polarizer (a linear polarizer and a quarter-wave plate).
    CircularPolarizer,
}

impl PolarizingElement {
    /// The fraction of unpolarized light the ideal element transmits: the first entry of its
    /// Mueller matrix (1/2 for the polarizers: Malus's law averaged over the angle; 1 for a
    /// retarder). Mitsuba 3.9.1's `llvm_ad_rgb` gives 0.5, 1 and 0.5 through each, measured.
    pub fn unpolarized_fraction(self) -> f32 {
        match self {
            PolarizingElement::LinearPolarizer | PolarizingElement::CircularPolarizer => 0.5,
            PolarizingElement::Retarder => 1.0,
        }
    }
}
