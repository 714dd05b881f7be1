//! The material layer: what a surface is made of, built once from the scene description
//! ([`build`]), and turned into a BSDF by value at each hit (pbrt-v4's `Material::GetBxDF`):
//! every texturable parameter is a [`Texture`] evaluated at the hit's texture point and the
//! path's wavelengths.
//!
//! A [`Material`] is one model with its (textured) parameters; a [`SurfaceMaterial`] adds what
//! wraps a model in the scene description (Mitsuba's `twosided`, `mask`, `normalmap`,
//! `blendbsdf`), as pt-bsdf's [`SurfaceBsdf`] does for BSDFs. In RGB mode, a surface whose
//! parameters are all constant keeps its BSDF, evaluated once at build.

mod build;

pub use build::build_material;

use crate::fluorescence::Fluorescent;
use crate::geometry::Interaction;
use crate::texture::{Texture, TexturePoint};
use pt_bsdf::{
    Bsdf, CoatingTable, Conductor, Dielectric, Distribution, FilmBase, GltfPbr, Hair, Lambert,
    Microfacet, Minnaert, OrenNayar, OrenNayarVariant, PPlastic, Plastic, Polarizer, Principled,
    PrincipledThin, RoughConductor, RoughDielectric, RoughPlastic, RoughThinFilm, SurfaceBsdf,
    ThinDielectric, ThinFilm,
};
use pt_math::{Frame, Vec3};
use pt_spectrum::{ColorMode, SampledSpectrum, SampledWavelengths};
use std::borrow::Cow;

/// The roughness of a rough model: distribution and the two roughness textures (scalars).
#[derive(Clone, Debug)]
pub struct Roughness {
    /// The normal distribution.
    pub distribution: Distribution,
    /// Roughness along dp/du.
    pub alpha_u: Texture,
    /// Roughness along the bitangent.
    pub alpha_v: Texture,
}

impl Roughness {
    /// The microfacet distribution at a point.
    #[inline]
    fn at(&self, at: &TexturePoint) -> Microfacet {
        Microfacet::new(
            self.distribution,
            self.alpha_u.eval_1(at),
            self.alpha_v.eval_1(at),
        )
    }
}

/// What a thin film lies on.
#[derive(Clone, Debug)]
pub enum FilmBaseMaterial {
    /// A dielectric of absolute index `ior`.
    Dielectric {
        /// Index of refraction of the base.
        ior: f32,
    },
    /// A conductor of complex index `eta + i k` (unbounded textures).
    Conductor {
        /// Real part.
        eta: Texture,
        /// Imaginary part.
        k: Texture,
    },
}

/// A thin film's parameters (project extension `thinfilm`, `roughthinfilm`).
#[derive(Clone, Debug)]
pub struct Film {
    /// Thickness, nm (scalar texture).
    pub thickness: Texture,
    /// Index of the film.
    pub film_ior: f32,
    /// Index outside.
    pub ext_ior: f32,
    /// What the film lies on.
    pub base: FilmBaseMaterial,
}

impl Film {
    /// The smooth film at a point: exact Airy reflectance at the path's wavelengths in spectral
    /// mode, Belcour & Barla 2017 in RGB mode.
    #[inline]
    fn at(&self, at: &TexturePoint, lambda: &SampledWavelengths, mode: ColorMode) -> ThinFilm {
        let base = match &self.base {
            FilmBaseMaterial::Dielectric { ior } => FilmBase::Dielectric { ior: *ior },
            FilmBaseMaterial::Conductor { eta, k } => FilmBase::Conductor {
                eta: eta.eval(at, lambda),
                k: k.eval(at, lambda),
            },
        };
        let d = self.thickness.eval_1(at).max(0.0);
        match mode {
            ColorMode::Spectral => {
                ThinFilm::spectral(d, self.film_ior, self.ext_ior, base, lambda.lambda())
            }
            ColorMode::Rgb => ThinFilm::rgb(d, self.film_ior, self.ext_ior, base),
        }
    }
}

/// One BSDF model with its parameters as textures.
#[derive(Clone, Debug)]
pub enum Material {
    /// RGB mode, nothing varies: the BSDF itself.
    Fixed(Bsdf),
    /// Mitsuba `diffuse`.
    Diffuse {
        /// Albedo.
        reflectance: Texture,
    },
    /// Project extension `orennayar`.
    OrenNayar {
        /// Facet albedo.
        reflectance: Texture,
        /// Facet slope standard deviation, radians (scalar).
        sigma: Texture,
        /// Formulation.
        variant: OrenNayarVariant,
    },
    /// Project extension `minnaert`.
    Minnaert {
        /// Albedo scale.
        reflectance: Texture,
        /// Exponent (scalar).
        k: Texture,
    },
    /// Mitsuba `dielectric`.
    Dielectric {
        /// Relative index inside / outside.
        eta: f32,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
    },
    /// Mitsuba `thindielectric`.
    ThinDielectric {
        /// Relative index.
        eta: f32,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
    },
    /// Mitsuba `roughdielectric`.
    RoughDielectric {
        /// Relative index.
        eta: f32,
        /// Distribution and roughness.
        roughness: Roughness,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
    },
    /// Mitsuba `conductor`.
    Conductor {
        /// Real part of the complex index.
        eta: Texture,
        /// Imaginary part.
        k: Texture,
        /// Factor on reflection.
        specular_reflectance: Texture,
    },
    /// Mitsuba `roughconductor`.
    RoughConductor {
        /// Real part of the complex index.
        eta: Texture,
        /// Imaginary part.
        k: Texture,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Distribution and roughness.
        roughness: Roughness,
    },
    /// Mitsuba `plastic`.
    Plastic {
        /// Albedo of the base.
        diffuse_reflectance: Texture,
        /// Factor on the coating's reflection.
        specular_reflectance: Texture,
        /// Relative index of the coating.
        eta: f32,
        /// Mitsuba's `nonlinear`.
        nonlinear: bool,
        /// Share of specular samples, from the textures' means (Mitsuba).
        specular_sampling_weight: f32,
    },
    /// Mitsuba `pplastic` without polarization.
    PPlastic {
        /// Albedo of the base.
        diffuse_reflectance: Texture,
        /// Factor on the reflection.
        specular_reflectance: Texture,
        /// Relative index, inside / outside.
        eta: f32,
        /// Distribution and roughness of the reflection.
        roughness: Roughness,
        /// Share of specular samples, from the textures' means (Mitsuba).
        specular_sampling_weight: f32,
    },
    /// Mitsuba `polarizer`, `retarder` and `circular` without polarization.
    Polarizer {
        /// The fraction of unpolarized light the element keeps.
        kept: f32,
        /// Transmittance besides that fraction.
        transmittance: Texture,
    },
    /// Mitsuba `hair` (pt-bsdf `hair.rs`).
    Hair {
        /// Absorption per unit fibre radius, or with `from_reflectance` the fibres' colour.
        absorption: Texture,
        /// Whether `absorption` holds a colour to turn into an absorption (Chiang et al. 2016,
        /// eq. 9).
        from_reflectance: bool,
        /// Factor on the absorption (Mitsuba's `scale`).
        scale: f32,
        /// Relative index, fibre over outside.
        eta: f32,
        /// Longitudinal and azimuthal roughness.
        roughness: [f32; 2],
        /// Cuticle scale angle, degrees.
        scale_tilt_deg: f32,
    },
    /// Mitsuba `roughplastic`.
    RoughPlastic {
        /// Albedo of the base.
        diffuse_reflectance: Texture,
        /// Factor on the coating's reflection.
        specular_reflectance: Texture,
        /// Relative index of the coating.
        eta: f32,
        /// Coating roughness (not texturable, as in Mitsuba).
        microfacet: Microfacet,
        /// Mitsuba's `nonlinear`.
        nonlinear: bool,
        /// Share of specular samples, from the textures' means (Mitsuba).
        specular_sampling_weight: f32,
        /// Transmittance table of the coating.
        table: &'static CoatingTable,
    },
    /// Project extension `thinfilm`.
    ThinFilm(Box<Film>),
    /// Project extension `roughthinfilm`.
    RoughThinFilm(Box<(Film, Roughness)>),
    /// glTF metallic-roughness.
    GltfPbr {
        /// Base colour.
        base_color: Texture,
        /// Metalness (scalar).
        metallic: Texture,
        /// Perceptual roughness (scalar).
        roughness: Texture,
        /// Index of the dielectric part.
        ior: f32,
    },
    /// Project extension `fluorescent` in spectral mode: a Lambertian of the total albedo at
    /// each lane's wavelength (the re-emission moves wavelengths: [`SurfaceMaterial::fluorescent`]).
    Fluorescent(Box<Fluorescent>),
    /// Mitsuba `principled`.
    Principled(Box<PrincipledTextures>),
    /// Mitsuba `principledthin`.
    PrincipledThin(Box<PrincipledThinTextures>),
}

/// The textures of a `principledthin` material (pt-bsdf's `principled_thin.rs`).
#[derive(Clone, Debug)]
pub struct PrincipledThinTextures {
    /// Base colour.
    pub base_color: Texture,
    /// Scalars in the order of `pt_scene::PrincipledThinDesc::NAMES`.
    pub scalars: [Texture; 9],
    /// Lobe selection weights.
    pub rates: [f32; 4],
}

impl PrincipledThinTextures {
    /// The BSDF at `at` (the luminance of the tints as for `principled`).
    #[inline]
    fn bsdf(
        &self,
        at: &TexturePoint,
        lambda: &SampledWavelengths,
        mode: ColorMode,
    ) -> PrincipledThin {
        let base_color = self.base_color.eval(at, lambda);
        let [roughness, anisotropic, spec_trans, spec_tint, sheen, sheen_tint, flatness, diff_trans, eta] =
            std::array::from_fn(|k| self.scalars[k].eval_1(at));
        PrincipledThin {
            base_color,
            luminance: base_luminance(base_color, lambda, mode),
            roughness,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            diff_trans: 0.5 * diff_trans,
            eta,
            mf_r: Principled::microfacet(roughness, anisotropic),
            // Burley 2015, figure 15: the thin transmission's roughness.
            mf_t: Principled::microfacet((0.65 * eta - 0.35) * roughness, anisotropic),
            rates: self.rates,
        }
    }
}

/// The luminance the principled tints divide by: Rec. 709 Y of the RGB lanes, or in spectral
/// mode the CIE-y-weighted mean over the path's wavelengths (normalised; Mitsuba 3.9.1's
/// spectral variants leave it unnormalised, so that there the tints change even a white base
/// colour).
#[inline]
fn base_luminance(
    base_color: SampledSpectrum,
    lambda: &SampledWavelengths,
    mode: ColorMode,
) -> f32 {
    match mode {
        ColorMode::Rgb => base_color.luminance_rgb(),
        ColorMode::Spectral => {
            let y = lambda.lambda().to_array().map(pt_spectrum::cie::cmf_y);
            let b = base_color.0.to_array();
            let num: f32 = (0..4).map(|k| y[k] * b[k]).sum();
            let den: f32 = y.iter().sum();
            if den > 0.0 {
                num / den
            } else {
                0.0
            }
        }
    }
}

/// The textures of a `principled` material (pt-bsdf's `principled.rs` for their meaning).
#[derive(Clone, Debug)]
pub struct PrincipledTextures {
    /// Base colour.
    pub base_color: Texture,
    /// Scalar weights, in the order of `pt_scene::PrincipledDesc::NAMES`.
    pub scalars: [Texture; 10],
    /// Relative index of refraction.
    pub eta: f32,
    /// Whether the model transmits.
    pub transmissive: bool,
    /// Lobe selection weights: main specular, clearcoat, diffuse.
    pub rates: [f32; 3],
}

impl PrincipledTextures {
    /// The BSDF at `at` (the tints divide by [`base_luminance`]).
    #[inline]
    fn bsdf(&self, at: &TexturePoint, lambda: &SampledWavelengths, mode: ColorMode) -> Principled {
        let base_color = self.base_color.eval(at, lambda);
        let [roughness, anisotropic, metallic, spec_trans, spec_tint, sheen, sheen_tint, flatness, clearcoat, clearcoat_gloss] =
            std::array::from_fn(|k| self.scalars[k].eval_1(at));
        let luminance = base_luminance(base_color, lambda, mode);
        Principled {
            base_color,
            luminance,
            roughness,
            metallic,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_alpha: 0.1 + (0.001 - 0.1) * clearcoat_gloss,
            eta: self.eta,
            mf: Principled::microfacet(roughness, anisotropic),
            transmissive: self.transmissive,
            rates: self.rates,
        }
    }
}

impl Material {
    /// The BSDF at a texture point and the path's wavelengths.
    #[inline(always)]
    pub fn bsdf(&self, at: &TexturePoint, lambda: &SampledWavelengths, mode: ColorMode) -> Bsdf {
        match self {
            Material::Fixed(b) => *b,
            Material::Diffuse { reflectance } => {
                Bsdf::Lambert(Lambert::new(reflectance.eval(at, lambda)))
            }
            Material::OrenNayar {
                reflectance,
                sigma,
                variant,
            } => Bsdf::OrenNayar(OrenNayar::new(
                reflectance.eval(at, lambda),
                sigma.eval_1(at),
                *variant,
            )),
            Material::Minnaert { reflectance, k } => {
                Bsdf::Minnaert(Minnaert::new(reflectance.eval(at, lambda), k.eval_1(at)))
            }
            Material::Dielectric { .. }
            | Material::ThinDielectric { .. }
            | Material::RoughDielectric { .. } => self.dielectric_bsdf(at, lambda),
            Material::Conductor {
                eta,
                k,
                specular_reflectance,
            } => Bsdf::Conductor(Conductor::new(
                eta.eval(at, lambda),
                k.eval(at, lambda),
                specular_reflectance.eval(at, lambda),
            )),
            Material::RoughConductor {
                eta,
                k,
                specular_reflectance,
                roughness,
            } => Bsdf::RoughConductor(RoughConductor::new(
                eta.eval(at, lambda),
                k.eval(at, lambda),
                specular_reflectance.eval(at, lambda),
                roughness.at(at),
            )),
            Material::PPlastic {
                diffuse_reflectance,
                specular_reflectance,
                eta,
                roughness,
                specular_sampling_weight,
            } => Bsdf::PPlastic(PPlastic::new(
                diffuse_reflectance.eval(at, lambda),
                specular_reflectance.eval(at, lambda),
                *eta,
                roughness.at(at),
                *specular_sampling_weight,
            )),
            Material::Polarizer {
                kept,
                transmittance,
            } => Bsdf::Polarizer(Polarizer {
                kept: *kept,
                transmittance: transmittance.eval(at, lambda),
            }),
            Material::Hair { .. } => self.hair_bsdf(at, lambda, mode),
            Material::Plastic {
                diffuse_reflectance,
                specular_reflectance,
                eta,
                nonlinear,
                specular_sampling_weight,
            } => Bsdf::Plastic(Plastic::new(
                diffuse_reflectance.eval(at, lambda),
                specular_reflectance.eval(at, lambda),
                *eta,
                *nonlinear,
                *specular_sampling_weight,
            )),
            Material::RoughPlastic {
                diffuse_reflectance,
                specular_reflectance,
                eta,
                microfacet,
                nonlinear,
                specular_sampling_weight,
                table,
            } => Bsdf::RoughPlastic(RoughPlastic::new(
                diffuse_reflectance.eval(at, lambda),
                specular_reflectance.eval(at, lambda),
                *eta,
                *microfacet,
                *nonlinear,
                *specular_sampling_weight,
                table,
            )),
            Material::ThinFilm(f) => Bsdf::ThinFilm(f.at(at, lambda, mode)),
            Material::Principled(p) => Bsdf::Principled(p.bsdf(at, lambda, mode)),
            Material::PrincipledThin(p) => Bsdf::PrincipledThin(p.bsdf(at, lambda, mode)),
            Material::RoughThinFilm(b) => {
                Bsdf::RoughThinFilm(RoughThinFilm::new(b.0.at(at, lambda, mode), b.1.at(at)))
            }
            Material::GltfPbr {
                base_color,
                metallic,
                roughness,
                ior,
            } => Bsdf::GltfPbr(GltfPbr::new(
                base_color.eval(at, lambda),
                metallic.eval_1(at),
                roughness.eval_1(at),
                *ior,
            )),
            Material::Fluorescent(f) => Bsdf::Lambert(Lambert::new(f.albedo(lambda))),
        }
    }

    /// [`Material::bsdf`] of the three dielectrics (smooth, thin, rough): the interface with
    /// its specular factors evaluated at the point.
    #[inline(always)]
    fn dielectric_bsdf(&self, at: &TexturePoint, lambda: &SampledWavelengths) -> Bsdf {
        match self {
            Material::Dielectric {
                eta,
                specular_reflectance,
                specular_transmittance,
            } => {
                let mut d = Dielectric::new(*eta);
                d.specular_reflectance = specular_reflectance.eval(at, lambda);
                d.specular_transmittance = specular_transmittance.eval(at, lambda);
                Bsdf::Dielectric(d)
            }
            Material::ThinDielectric {
                eta,
                specular_reflectance,
                specular_transmittance,
            } => {
                let mut d = ThinDielectric::new(*eta);
                d.specular_reflectance = specular_reflectance.eval(at, lambda);
                d.specular_transmittance = specular_transmittance.eval(at, lambda);
                Bsdf::ThinDielectric(d)
            }
            Material::RoughDielectric {
                eta,
                roughness,
                specular_reflectance,
                specular_transmittance,
            } => {
                let mut d = RoughDielectric::new(*eta, roughness.at(at));
                d.specular_reflectance = specular_reflectance.eval(at, lambda);
                d.specular_transmittance = specular_transmittance.eval(at, lambda);
                Bsdf::RoughDielectric(d)
            }
            _ => unreachable!("dielectric_bsdf is called for dielectrics"),
        }
    }

    /// [`Material::bsdf`] of Mitsuba's `hair`: the absorption from the texture (or from the
    /// fibres' colour, Chiang et al. 2016, eq. 9) and the luminance weights of the path's
    /// channels (RGB's Y row, or the CIE y of each wavelength) for the lobe selection.
    #[inline(always)]
    fn hair_bsdf(&self, at: &TexturePoint, lambda: &SampledWavelengths, mode: ColorMode) -> Bsdf {
        let Material::Hair {
            absorption,
            from_reflectance,
            scale,
            eta,
            roughness,
            scale_tilt_deg,
        } = self
        else {
            unreachable!("hair_bsdf is called for hair")
        };
        let a = absorption.eval(at, lambda);
        let sigma_a = if *from_reflectance {
            Hair::sigma_a_from_reflectance(a, roughness[1])
        } else {
            a * *scale
        };
        let luminance = match mode {
            ColorMode::Rgb => pt_math::Vec4::new(0.212_671, 0.715_160, 0.072_169, 0.0),
            ColorMode::Spectral => {
                pt_math::Vec4::from_array(lambda.lambda().to_array().map(pt_spectrum::cie::cmf_y))
            }
        };
        Bsdf::Hair(Hair::new(
            sigma_a,
            luminance,
            *eta,
            roughness[0],
            roughness[1],
            *scale_tilt_deg,
        ))
    }
}

/// Whose perturbation a [`NormalMap`] applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalKind {
    /// Mitsuba's `normalmap`: RGB = (n + 1) / 2 in the shading frame (s along dp/du).
    Mitsuba,
    /// glTF's `normalTexture`: the mesh's tangent space (tangents and handedness).
    Gltf,
    /// Mitsuba's `bumpmap`: the normal of the surface displaced by a height texture.
    Bump,
}

/// A perturbed shading normal: a normal map (Mitsuba `normalmap`, glTF `normalTexture`) or a
/// bump map (Mitsuba `bumpmap`); the BSDF is then evaluated as pt-bsdf `normal_map` says
/// (flip towards the viewer, shadowing of Conty Estevez et al. 2019), as Mitsuba 3.9.1 does
/// for both.
#[derive(Clone, Debug)]
pub struct NormalMap {
    /// Normal maps: RGB data, the texel c decodes to n = 2 c - 1. Bump maps: the height, a
    /// scalar bitmap.
    pub texture: Texture,
    /// glTF `scale` on the decoded x and y (1 for Mitsuba's normal maps); a bump map's `scale`
    /// on the height's gradient.
    pub scale: f32,
    /// Which perturbation.
    pub kind: NormalKind,
}

impl NormalMap {
    /// The mapped normal at a hit (any length), in the integrator's local shading frame
    /// `Frame::from_normal_tangent(hit.ns, hit.dpdu)` (pt-bsdf `normal_map` builds the frame
    /// from it), in the tangent space (s, t, n): Mitsuba: s along dp/du, t = n x s; glTF: s
    /// along the mesh tangent, t = w (n x s).
    ///
    /// A bump map (Mitsuba 3.9.1 `bumpmap.cpp`) displaces the surface by h = `scale` height(uv)
    /// along the shading normal n, neglecting n's own derivatives (Blinn 1978): the tangents
    /// become dp/du + n (dh/du - n . dp/du) and dp/dv + n (dh/dv - n . dp/dv), i.e. their
    /// normal components are replaced by the height's gradient, and the normal is their cross
    /// product, turned to the geometric normal's side.
    #[inline]
    fn normal(&self, hit: &Interaction, at: &TexturePoint) -> Vec3 {
        let local = || Frame::from_normal_tangent(hit.ns, hit.dpdu);
        match self.kind {
            NormalKind::Mitsuba => {
                let c = self.texture.eval_rgb(at);
                Vec3::new(2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0)
            }
            NormalKind::Gltf => {
                let c = self.texture.eval_rgb(at);
                let n = Vec3::new(
                    (2.0 * c[0] - 1.0) * self.scale,
                    (2.0 * c[1] - 1.0) * self.scale,
                    2.0 * c[2] - 1.0,
                );
                // Tangent frame of the mesh; without tangents, dp/du with w = +1.
                let (t, w) = if hit.tangent.truncate() != Vec3::ZERO {
                    (hit.tangent.truncate(), hit.tangent.w)
                } else {
                    (hit.dpdu, 1.0)
                };
                let tf = Frame::from_normal_tangent(hit.ns, t);
                let world = tf.s * n.x + tf.t * (w * n.y) + tf.n * n.z;
                local().to_local(world)
            }
            NormalKind::Bump => {
                let local = local();
                let g = self.texture.gradient_1(at).unwrap_or_default() * self.scale;
                let mut du = local.to_local(hit.dpdu);
                let mut dv = local.to_local(hit.dpdv);
                du.z = g.x;
                dv.z = g.y;
                let n = du.cross(dv);
                // The local frame is right-handed (t = n x s), so the cross product of local
                // coordinates is the local form of the world cross product.
                if local.to_local(hit.ng).dot(n) < 0.0 {
                    -n
                } else {
                    n
                }
            }
        }
    }
}

/// Opacity of a `mask` (scalar texture, clamped to [0, 1]) and glTF's alpha cutoff.
#[derive(Clone, Debug)]
pub struct Opacity {
    /// The opacity.
    pub texture: Texture,
    /// glTF `alphaMode` MASK: opacity 1 where the texture is at least this, else 0.
    pub cutoff: Option<f32>,
}

/// A surface's material with its wrappers: the per-hit form of a BSDF description.
#[derive(Clone, Debug)]
pub struct SurfaceMaterial {
    /// The model.
    pub material: Material,
    /// `blendbsdf`: the weight of `second` (scalar texture, clamped) and `second`.
    pub blend: Option<(Texture, Material)>,
    /// `twosided`.
    pub two_sided: bool,
    /// `mask`.
    pub opacity: Option<Opacity>,
    /// `normalmap`.
    pub normal_map: Option<NormalMap>,
    /// RGB mode with nothing textured: the whole surface BSDF, evaluated once.
    pub fixed: Option<SurfaceBsdf>,
    /// `fixed`'s [`SurfaceBsdf::plain_lambert`] (albedo, two-sided), looked up once: the
    /// shading in lanes asks it at every hit.
    pub fixed_lambert: Option<(SampledSpectrum, bool)>,
    /// Colour mode the textures were built for.
    pub mode: ColorMode,
}

impl SurfaceMaterial {
    /// The surface's BSDF at a hit, at the path's wavelengths: borrowed when it is the same
    /// all over the surface (`fixed`: no copy of its 272 bytes per hit, which took 4% of a
    /// BDPT profile), else built for the hit.
    #[inline(always)]
    pub fn bsdf(
        &self,
        hit: &Interaction,
        at: &TexturePoint,
        lambda: &SampledWavelengths,
    ) -> Cow<'_, SurfaceBsdf> {
        if let Some(b) = &self.fixed {
            return Cow::Borrowed(b);
        }
        let opacity = match &self.opacity {
            None => 1.0,
            Some(o) => {
                let v = o.texture.eval_1(at);
                match o.cutoff {
                    Some(c) => f32::from(u8::from(v >= c)),
                    None => v.clamp(0.0, 1.0),
                }
            }
        };
        Cow::Owned(SurfaceBsdf {
            bsdf: self.material.bsdf(at, lambda, self.mode),
            two_sided: self.two_sided,
            opacity,
            normal: self.normal_map.as_ref().map(|n| n.normal(hit, at)),
            blend: self
                .blend
                .as_ref()
                .map(|(w, m)| (w.eval_1(at).clamp(0.0, 1.0), m.bsdf(at, lambda, self.mode))),
        })
    }

    /// The fluorescence model, if the surface is `fluorescent` (spectral mode).
    #[inline]
    pub fn fluorescent(&self) -> Option<&Fluorescent> {
        match &self.material {
            Material::Fluorescent(f) => Some(f),
            _ => None,
        }
    }

    /// Whether the BSDF may depend on the azimuth (anisotropic models, normal maps, textures):
    /// hits then need texture coordinates and dp/du. Isotropic untextured surfaces give the
    /// same values and sampling distribution in any tangent frame, so their hits skip the uv
    /// interpolation and the dp/du solve (4% of the Cornell box's render time).
    pub fn uses_uv(&self) -> bool {
        let textured = |t: &Texture| !t.is_constant();
        self.normal_map.is_some()
            || self.opacity.as_ref().is_some_and(|o| textured(&o.texture))
            || !self.material.is_isotropic_untextured()
            || self
                .blend
                .as_ref()
                .is_some_and(|(w, m)| textured(w) || !m.is_isotropic_untextured())
    }
}

impl Material {
    /// Every texture of the model.
    pub fn textures(&self) -> Vec<&Texture> {
        fn film(f: &Film) -> Vec<&Texture> {
            let mut v: Vec<&Texture> = vec![&f.thickness];
            if let FilmBaseMaterial::Conductor { eta, k } = &f.base {
                v.extend([eta, k]);
            }
            v
        }
        match self {
            Material::Fixed(_) | Material::Fluorescent(_) => Vec::new(),
            Material::Diffuse { reflectance } => vec![reflectance],
            Material::OrenNayar {
                reflectance, sigma, ..
            } => vec![reflectance, sigma],
            Material::Minnaert { reflectance, k } => vec![reflectance, k],
            Material::Dielectric {
                specular_reflectance,
                specular_transmittance,
                ..
            }
            | Material::ThinDielectric {
                specular_reflectance,
                specular_transmittance,
                ..
            } => vec![specular_reflectance, specular_transmittance],
            Material::RoughDielectric {
                roughness,
                specular_reflectance,
                specular_transmittance,
                ..
            } => vec![
                &roughness.alpha_u,
                &roughness.alpha_v,
                specular_reflectance,
                specular_transmittance,
            ],
            Material::Conductor {
                eta,
                k,
                specular_reflectance,
            } => vec![eta, k, specular_reflectance],
            Material::RoughConductor {
                eta,
                k,
                specular_reflectance,
                roughness,
            } => vec![
                eta,
                k,
                specular_reflectance,
                &roughness.alpha_u,
                &roughness.alpha_v,
            ],
            Material::Plastic {
                diffuse_reflectance,
                specular_reflectance,
                ..
            }
            | Material::RoughPlastic {
                diffuse_reflectance,
                specular_reflectance,
                ..
            } => vec![diffuse_reflectance, specular_reflectance],
            Material::PPlastic {
                diffuse_reflectance,
                specular_reflectance,
                roughness,
                ..
            } => vec![
                diffuse_reflectance,
                specular_reflectance,
                &roughness.alpha_u,
                &roughness.alpha_v,
            ],
            Material::Polarizer { transmittance, .. } => vec![transmittance],
            Material::Hair { absorption, .. } => vec![absorption],
            Material::ThinFilm(f) => film(f),
            Material::RoughThinFilm(b) => {
                let mut v = film(&b.0);
                v.extend([&b.1.alpha_u, &b.1.alpha_v]);
                v
            }
            Material::GltfPbr {
                base_color,
                metallic,
                roughness,
                ..
            } => vec![base_color, metallic, roughness],
            Material::Principled(p) => std::iter::once(&p.base_color).chain(&p.scalars).collect(),
            Material::PrincipledThin(p) => {
                std::iter::once(&p.base_color).chain(&p.scalars).collect()
            }
        }
    }

    /// Whether the model is the same in every tangent frame and none of its parameters varies.
    fn is_isotropic_untextured(&self) -> bool {
        let isotropic_model = match self {
            Material::Fixed(b) => isotropic(b),
            Material::RoughDielectric { .. }
            | Material::RoughConductor { .. }
            | Material::RoughPlastic { .. }
            | Material::PPlastic { .. }
            | Material::RoughThinFilm(_)
            | Material::GltfPbr { .. }
            | Material::Principled(_)
            | Material::PrincipledThin(_) => false,
            _ => true,
        };
        isotropic_model && self.textures().iter().all(|t| t.is_constant())
    }
}

impl SurfaceMaterial {
    /// Every texture of the surface: its model's, the blend's, the mask's, the normal map's.
    pub fn textures(&self) -> Vec<&Texture> {
        let mut v = self.material.textures();
        if let Some((w, m)) = &self.blend {
            v.push(w);
            v.extend(m.textures());
        }
        v.extend(self.opacity.as_ref().map(|o| &o.texture));
        v.extend(self.normal_map.as_ref().map(|n| &n.texture));
        v
    }

    /// Whether some texture of the surface reads mesh attribute `slot`.
    pub fn reads_attribute(&self, slot: u32) -> bool {
        self.textures().iter().any(|t| t.reads_attribute(slot))
    }
}

/// Whether a BSDF is the same in every tangent frame.
fn isotropic(b: &Bsdf) -> bool {
    matches!(
        b,
        Bsdf::Lambert(_)
            | Bsdf::OrenNayar(_)
            | Bsdf::Minnaert(_)
            | Bsdf::Conductor(_)
            | Bsdf::Dielectric(_)
            | Bsdf::ThinDielectric(_)
            | Bsdf::ThinFilm(_)
            | Bsdf::Polarizer(_)
    )
}
