//! From a BSDF description to a [`SurfaceMaterial`]: wrappers become its fields, the model a
//! [`Material`] with a texture per texturable parameter, each built for its role.

use super::{
    Film, FilmBaseMaterial, Material, NormalKind, NormalMap, Opacity, Roughness, SurfaceMaterial,
};
use super::{PrincipledTextures, PrincipledThinTextures};
use crate::fluorescence::Fluorescent;
use crate::scene::BuildError;
use crate::texture::{Role, Texture, TextureBuilder, TexturePoint};
use pt_bsdf::{CoatingTable, Distribution, Microfacet, OrenNayarVariant, SurfaceBsdf};
use pt_scene::{
    BsdfDesc, BsdfKind, FilmBaseDesc, MicrofacetDesc, MicrofacetDistribution,
    OrenNayarVariant as OnDesc, SourceLoc, TextureDesc,
};
use pt_spectrum::{ColorMode, SampledWavelengths};

/// Builds the material of a BSDF description (textures decoded and upsampled once, through
/// `textures`, which shares images between materials).
pub fn build_material(
    desc: &BsdfDesc,
    textures: &mut TextureBuilder,
) -> Result<SurfaceMaterial, BuildError> {
    let mode = textures.mode();
    let mut b = Builder {
        textures,
        loc: &desc.loc,
    };
    let mut surface = SurfaceMaterial {
        material: Material::Fixed(pt_bsdf::Bsdf::Lambert(pt_bsdf::Lambert::new(
            pt_spectrum::SampledSpectrum::ZERO,
        ))),
        blend: None,
        two_sided: false,
        opacity: None,
        normal_map: None,
        fixed: None,
        fixed_lambert: None,
        mode,
    };
    b.wrappers(desc, &mut surface)?;
    surface.fixed = fixed(&surface);
    surface.fixed_lambert = surface.fixed.and_then(|b| b.plain_lambert());
    Ok(surface)
}

/// RGB mode with nothing that varies over the surface: the BSDF, once.
fn fixed(s: &SurfaceMaterial) -> Option<SurfaceBsdf> {
    if s.mode != ColorMode::Rgb || s.normal_map.is_some() {
        return None;
    }
    let constant = |m: &Material| matches!(m, Material::Fixed(_));
    let opacity_fixed = s.opacity.as_ref().is_none_or(|o| o.texture.is_constant());
    let blend_fixed = s
        .blend
        .as_ref()
        .is_none_or(|(w, m)| w.is_constant() && constant(m));
    if !(constant(&s.material) && opacity_fixed && blend_fixed) {
        return None;
    }
    // Constants read the same anywhere: any point and wavelengths give the BSDF.
    let at = crate::texture::TexturePoint::uv(pt_math::Vec2::ZERO);
    let hit = crate::geometry::Interaction::default();
    Some(
        s.bsdf(&hit, &at, &SampledWavelengths::sample_visible(0.5))
            .into_owned(),
    )
}

/// The state of one material's build: the texture builder and where the BSDF was defined.
struct Builder<'a> {
    textures: &'a mut TextureBuilder,
    loc: &'a SourceLoc,
}

impl Builder<'_> {
    fn err(&self, message: impl Into<String>) -> BuildError {
        BuildError {
            loc: self.loc.clone(),
            message: message.into(),
        }
    }

    /// A parameter's texture for a role, errors located at the BSDF.
    fn tex(&mut self, name: &str, t: &TextureDesc, role: Role) -> Result<Texture, BuildError> {
        self.textures.build(t, role).map_err(|m| BuildError {
            loc: self.loc.clone(),
            message: format!("{name}: {m}"),
        })
    }

    /// The wrappers of `desc` into `s`, then its model.
    fn wrappers(&mut self, desc: &BsdfDesc, s: &mut SurfaceMaterial) -> Result<(), BuildError> {
        let loc = &desc.loc;
        let mut b = Builder {
            textures: self.textures,
            loc,
        };
        match &desc.kind {
            BsdfKind::TwoSided { inner } => {
                s.two_sided = true;
                b.wrappers(inner, s)
            }
            BsdfKind::Mask {
                opacity,
                cutoff,
                inner,
            } => {
                if s.opacity.is_some() {
                    return Err(b.err("nested masks are not yet supported (not yet implemented)"));
                }
                s.opacity = Some(Opacity {
                    texture: b.tex("opacity", opacity, Role::Scalar)?,
                    cutoff: *cutoff,
                });
                b.wrappers(inner, s)
            }
            BsdfKind::NormalMap {
                texture,
                scale,
                gltf,
                inner,
            } => {
                if s.normal_map.is_some() {
                    return Err(b.err("nested normal maps are not supported (not yet implemented)"));
                }
                let texture = b.tex("normalmap", texture, Role::Data)?;
                s.normal_map = Some(NormalMap {
                    texture,
                    scale: *scale,
                    kind: if *gltf {
                        NormalKind::Gltf
                    } else {
                        NormalKind::Mitsuba
                    },
                });
                b.wrappers(inner, s)
            }
            BsdfKind::BumpMap {
                height,
                scale,
                inner,
            } => {
                if s.normal_map.is_some() {
                    return Err(b.err(
                        "a bump map inside a normal or bump map is not supported (not yet implemented)",
                    ));
                }
                let texture = b.tex("bumpmap", height, Role::Scalar)?;
                if texture
                    .gradient_1(&TexturePoint::uv(pt_math::Vec2::ZERO))
                    .is_none()
                {
                    return Err(b.err("bumpmap: the height must be a bitmap"));
                }
                s.normal_map = Some(NormalMap {
                    texture,
                    scale: *scale,
                    kind: NormalKind::Bump,
                });
                b.wrappers(inner, s)
            }
            BsdfKind::Blend {
                weight,
                first,
                second,
            } => {
                let (a, a_two) = b.plain(first)?;
                let (c, c_two) = b.plain(second)?;
                // `two_sided` never mirrors a transmissive model, so it may differ there.
                let transmissive = |d: &BsdfDesc| {
                    matches!(
                        plain_model(d).kind,
                        BsdfKind::Dielectric { .. }
                            | BsdfKind::RoughDielectric { .. }
                            | BsdfKind::ThinDielectric { .. }
                    ) || matches!(
                        &plain_model(d).kind,
                        BsdfKind::ThinFilm {
                            base: FilmBaseDesc::Dielectric { .. },
                            ..
                        } | BsdfKind::RoughThinFilm {
                            base: FilmBaseDesc::Dielectric { .. },
                            ..
                        }
                    )
                };
                if a_two != c_two && !transmissive(first) && !transmissive(second) {
                    return Err(b.err("blendbsdf of a one-sided and a two-sided BSDF is not yet supported (not yet implemented): put twosided around the blendbsdf"));
                }
                if matches!(a, Material::Fluorescent(_)) || matches!(c, Material::Fluorescent(_)) {
                    return Err(b.err("a blendbsdf with a fluorescent BSDF is not yet supported (not yet implemented)"));
                }
                s.two_sided |= a_two || c_two;
                s.material = a;
                s.blend = Some((b.tex("weight", weight, Role::Scalar)?, c));
                Ok(())
            }
            _ => {
                s.material = b.model(desc)?;
                if s.opacity.is_some() && matches!(s.material, Material::Fluorescent(_)) {
                    return Err(b.err("a mask around a fluorescent BSDF is not yet supported (not yet implemented)"));
                }
                Ok(())
            }
        }
    }

    /// A BSDF inside a blend: a model, possibly two-sided (blends of masks, normal maps or
    /// blends are not supported).
    fn plain(&mut self, d: &BsdfDesc) -> Result<(Material, bool), BuildError> {
        let mut b = Builder {
            textures: self.textures,
            loc: &d.loc,
        };
        match &d.kind {
            BsdfKind::TwoSided { inner } => Ok((b.plain(inner)?.0, true)),
            BsdfKind::Mask { .. }
            | BsdfKind::NormalMap { .. }
            | BsdfKind::BumpMap { .. }
            | BsdfKind::Blend { .. } => Err(b.err(
                "blendbsdf of masks, normal or bump maps or blends is not yet supported (not yet implemented): put the mask or normal map around the blendbsdf",
            )),
            _ => Ok((b.model(d)?, false)),
        }
    }

    fn roughness(&mut self, m: &MicrofacetDesc) -> Result<Roughness, BuildError> {
        Ok(Roughness {
            distribution: distribution(m.distribution),
            alpha_u: self.tex("alpha_u", &m.alpha_u, Role::Scalar)?,
            alpha_v: self.tex("alpha_v", &m.alpha_v, Role::Scalar)?,
        })
    }

    fn film(
        &mut self,
        thickness: &TextureDesc,
        film_ior: f32,
        ext_ior: f32,
        base: &FilmBaseDesc,
    ) -> Result<Film, BuildError> {
        Ok(Film {
            thickness: self.tex("thickness", thickness, Role::Scalar)?,
            film_ior,
            ext_ior,
            base: match base {
                FilmBaseDesc::Dielectric { int_ior } => {
                    FilmBaseMaterial::Dielectric { ior: *int_ior }
                }
                FilmBaseDesc::Conductor { eta, k } => FilmBaseMaterial::Conductor {
                    eta: self.tex("eta", eta, Role::Unbounded)?,
                    k: self.tex("k", k, Role::Unbounded)?,
                },
            },
        })
    }

    /// The model of a BSDF description (no wrappers).
    fn model(&mut self, d: &BsdfDesc) -> Result<Material, BuildError> {
        let m = self.model_textured(d)?;
        Ok(fix(m, self.textures.mode()))
    }

    /// The model of a BSDF description with its textures as built, before [`fix`].
    fn model_textured(&mut self, d: &BsdfDesc) -> Result<Material, BuildError> {
        Ok(match &d.kind {
            BsdfKind::Diffuse { reflectance } => Material::Diffuse {
                reflectance: self.tex("reflectance", reflectance, Role::Albedo)?,
            },
            // Lights on: the elastic part (the afterglow is rendered by `afterglow`).
            BsdfKind::Phosphorescent { reflectance, .. } => Material::Diffuse {
                reflectance: self.tex(
                    "reflectance",
                    &TextureDesc::Constant(reflectance.clone()),
                    Role::Albedo,
                )?,
            },
            BsdfKind::Fluorescent { .. } => self.fluorescent(&d.kind)?,
            BsdfKind::OrenNayar {
                reflectance,
                sigma,
                variant,
            } => Material::OrenNayar {
                reflectance: self.tex("reflectance", reflectance, Role::Albedo)?,
                sigma: self.tex("sigma", sigma, Role::Scalar)?,
                variant: match variant {
                    OnDesc::Qualitative => OrenNayarVariant::Qualitative,
                    OnDesc::Full => OrenNayarVariant::Full,
                    OnDesc::Fujii => OrenNayarVariant::Fujii,
                    OnDesc::Eon => OrenNayarVariant::Eon,
                },
            },
            BsdfKind::Minnaert { reflectance, k } => Material::Minnaert {
                reflectance: self.tex("reflectance", reflectance, Role::Albedo)?,
                k: self.tex("k", k, Role::Scalar)?,
            },
            BsdfKind::Dielectric { .. }
            | BsdfKind::ThinDielectric { .. }
            | BsdfKind::RoughDielectric { .. } => self.dielectric(&d.kind)?,
            BsdfKind::Conductor { .. } | BsdfKind::RoughConductor { .. } => {
                self.conductor(&d.kind)?
            }
            BsdfKind::Plastic { .. } => self.plastic(&d.kind)?,
            BsdfKind::PPlastic {
                diffuse_reflectance,
                specular_reflectance,
                int_ior,
                ext_ior,
                microfacet,
            } => {
                let (rho, ks, weight) =
                    self.coating_textures(diffuse_reflectance, specular_reflectance)?;
                Material::PPlastic {
                    diffuse_reflectance: rho,
                    specular_reflectance: ks,
                    eta: int_ior / ext_ior,
                    roughness: self.roughness(microfacet)?,
                    specular_sampling_weight: weight,
                }
            }
            BsdfKind::Polarizer {
                element,
                transmittance,
            } => Material::Polarizer {
                kept: element.unpolarized_fraction(),
                transmittance: self.tex("transmittance", transmittance, Role::Albedo)?,
            },
            BsdfKind::Hair { .. } => self.hair(&d.kind)?,
            BsdfKind::RoughPlastic { .. } => self.rough_plastic(&d.kind)?,
            BsdfKind::ThinFilm {
                thickness,
                film_ior,
                ext_ior,
                base,
            } => Material::ThinFilm(Box::new(self.film(thickness, *film_ior, *ext_ior, base)?)),
            BsdfKind::RoughThinFilm {
                thickness,
                film_ior,
                ext_ior,
                base,
                microfacet,
            } => {
                let film = self.film(thickness, *film_ior, *ext_ior, base)?;
                Material::RoughThinFilm(Box::new((film, self.roughness(microfacet)?)))
            }
            BsdfKind::GltfPbr {
                base_color,
                metallic,
                roughness,
                ior,
            } => Material::GltfPbr {
                base_color: self.tex("base_color", base_color, Role::Albedo)?,
                metallic: self.tex("metallic", metallic, Role::Scalar)?,
                roughness: self.tex("roughness", roughness, Role::Scalar)?,
                ior: *ior,
            },
            BsdfKind::Principled(_) | BsdfKind::PrincipledThin(_) => self.principled(&d.kind)?,
            BsdfKind::TwoSided { .. }
            | BsdfKind::Mask { .. }
            | BsdfKind::NormalMap { .. }
            | BsdfKind::BumpMap { .. }
            | BsdfKind::Blend { .. } => {
                return Err(self.err("internal: a wrapper where a model was expected"))
            }
        })
    }

    /// The dielectrics: `dielectric`, `thindielectric` and `roughdielectric`, each with its
    /// relative index and specular factors.
    fn dielectric(&mut self, kind: &BsdfKind) -> Result<Material, BuildError> {
        Ok(match kind {
            BsdfKind::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => {
                let (specular_reflectance, specular_transmittance) =
                    self.factors(specular_reflectance, specular_transmittance)?;
                Material::Dielectric {
                    eta: int_ior / ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                }
            }
            BsdfKind::ThinDielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => {
                let (specular_reflectance, specular_transmittance) =
                    self.factors(specular_reflectance, specular_transmittance)?;
                Material::ThinDielectric {
                    eta: int_ior / ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                }
            }
            BsdfKind::RoughDielectric {
                int_ior,
                ext_ior,
                microfacet,
                specular_reflectance,
                specular_transmittance,
            } => {
                let (specular_reflectance, specular_transmittance) =
                    self.factors(specular_reflectance, specular_transmittance)?;
                Material::RoughDielectric {
                    eta: int_ior / ext_ior,
                    roughness: self.roughness(microfacet)?,
                    specular_reflectance,
                    specular_transmittance,
                }
            }
            _ => return Err(self.err("internal: not a dielectric BSDF")),
        })
    }

    /// The conductors: `conductor` and `roughconductor`.
    fn conductor(&mut self, kind: &BsdfKind) -> Result<Material, BuildError> {
        Ok(match kind {
            BsdfKind::Conductor {
                eta,
                k,
                specular_reflectance,
            } => Material::Conductor {
                eta: self.tex("eta", eta, Role::Unbounded)?,
                k: self.tex("k", k, Role::Unbounded)?,
                specular_reflectance: self.tex(
                    "specular_reflectance",
                    specular_reflectance,
                    Role::Albedo,
                )?,
            },
            BsdfKind::RoughConductor {
                eta,
                k,
                specular_reflectance,
                microfacet,
            } => Material::RoughConductor {
                eta: self.tex("eta", eta, Role::Unbounded)?,
                k: self.tex("k", k, Role::Unbounded)?,
                specular_reflectance: self.tex(
                    "specular_reflectance",
                    specular_reflectance,
                    Role::Albedo,
                )?,
                roughness: self.roughness(microfacet)?,
            },
            _ => return Err(self.err("internal: not a conductor BSDF")),
        })
    }

    /// `hair`: its absorption from pigments, `sigma_a` or a reflectance, and its roughnesses.
    fn hair(&mut self, kind: &BsdfKind) -> Result<Material, BuildError> {
        Ok(match kind {
            BsdfKind::Hair {
                absorption,
                eta,
                longitudinal_roughness,
                azimuthal_roughness,
                scale_tilt_deg,
            } => {
                use pt_scene::HairAbsorption as A;
                // Pigments: their RGB absorptions summed, then (spectral mode) upsampled as one
                // unbounded colour; Mitsuba upsamples each pigment's and adds the two.
                let (absorption, from_reflectance, scale) = match absorption {
                    A::Pigments {
                        eumelanin,
                        pheomelanin,
                    } => {
                        let rgb = pt_bsdf::Hair::pigment_sigma_a_rgb(*eumelanin, *pheomelanin);
                        let t = TextureDesc::Constant(pt_scene::SpectrumDesc::Rgb(rgb));
                        (self.tex("eumelanin", &t, Role::Unbounded)?, false, 1.0)
                    }
                    A::SigmaA { sigma_a, scale } => (
                        self.tex("sigma_a", sigma_a, Role::Unbounded)?,
                        false,
                        *scale,
                    ),
                    A::Reflectance(r) => (self.tex("reflectance", r, Role::Albedo)?, true, 1.0),
                };
                Material::Hair {
                    absorption,
                    from_reflectance,
                    scale,
                    eta: *eta,
                    roughness: [*longitudinal_roughness, *azimuthal_roughness],
                    scale_tilt_deg: *scale_tilt_deg,
                }
            }
            _ => return Err(self.err("internal: not a hair BSDF")),
        })
    }

    /// The principled BSDFs (`principled`, `principledthin`): their scalar textures by name.
    fn principled(&mut self, kind: &BsdfKind) -> Result<Material, BuildError> {
        Ok(match kind {
            BsdfKind::Principled(p) => {
                let mut scalars = Vec::with_capacity(p.scalars.len());
                for (name, t) in pt_scene::PrincipledDesc::NAMES.iter().zip(&p.scalars) {
                    scalars.push(self.tex(name, t, Role::Scalar)?);
                }
                Material::Principled(Box::new(PrincipledTextures {
                    base_color: self.tex("base_color", &p.base_color, Role::Albedo)?,
                    scalars: scalars.try_into().expect("ten scalars"),
                    eta: p.eta,
                    transmissive: p.transmissive,
                    rates: p.rates,
                }))
            }
            BsdfKind::PrincipledThin(p) => {
                let mut scalars = Vec::with_capacity(p.scalars.len());
                for (name, t) in pt_scene::PrincipledThinDesc::NAMES.iter().zip(&p.scalars) {
                    scalars.push(self.tex(name, t, Role::Scalar)?);
                }
                Material::PrincipledThin(Box::new(PrincipledThinTextures {
                    base_color: self.tex("base_color", &p.base_color, Role::Albedo)?,
                    scalars: scalars.try_into().expect("nine scalars"),
                    rates: p.rates,
                }))
            }
            _ => return Err(self.err("internal: not a principled BSDF")),
        })
    }

    /// A dielectric's `specular_reflectance` and `specular_transmittance` factors.
    fn factors(
        &mut self,
        r: &TextureDesc,
        t: &TextureDesc,
    ) -> Result<(Texture, Texture), BuildError> {
        Ok((
            self.tex("specular_reflectance", r, Role::Albedo)?,
            self.tex("specular_transmittance", t, Role::Albedo)?,
        ))
    }

    /// `fluorescent`: in spectral mode a Lambertian of the total albedo with re-emission; RGB
    /// mode cannot move light between wavelengths and keeps the elastic part only.
    fn fluorescent(&mut self, kind: &BsdfKind) -> Result<Material, BuildError> {
        let BsdfKind::Fluorescent {
            reflectance,
            absorption,
            emission,
            quantum_yield,
        } = kind
        else {
            return Err(self.err("internal: not a fluorescent BSDF"));
        };
        Ok(match self.textures.mode() {
            ColorMode::Spectral => {
                use crate::texture::spectrum_for_role as sp;
                let f = Fluorescent::new(
                    sp(reflectance, Role::Albedo),
                    &sp(absorption, Role::Albedo),
                    &sp(emission, Role::Unbounded),
                    *quantum_yield,
                )
                .map_err(|m| self.err(m))?;
                Material::Fluorescent(Box::new(f))
            }
            ColorMode::Rgb => Material::Diffuse {
                reflectance: self.tex(
                    "reflectance",
                    &TextureDesc::Constant(reflectance.clone()),
                    Role::Albedo,
                )?,
            },
        })
    }

    /// `plastic`: the share of specular samples from the textures' means (see
    /// [`Self::coating_textures`]).
    fn plastic(&mut self, kind: &BsdfKind) -> Result<Material, BuildError> {
        let BsdfKind::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
            nonlinear,
        } = kind
        else {
            return Err(self.err("internal: not a plastic BSDF"));
        };
        let (rho, ks, weight) = self.coating_textures(diffuse_reflectance, specular_reflectance)?;
        Ok(Material::Plastic {
            diffuse_reflectance: rho,
            specular_reflectance: ks,
            eta: int_ior / ext_ior,
            nonlinear: *nonlinear,
            specular_sampling_weight: weight,
        })
    }

    /// `roughplastic`: its coating table, and the share of specular samples from the textures'
    /// means (see [`Self::coating_textures`]).
    fn rough_plastic(&mut self, kind: &BsdfKind) -> Result<Material, BuildError> {
        let BsdfKind::RoughPlastic {
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
            distribution: dist,
            alpha,
            nonlinear,
        } = kind
        else {
            return Err(self.err("internal: not a roughplastic BSDF"));
        };
        let eta = int_ior / ext_ior;
        let mf = Microfacet::new(distribution(*dist), *alpha, *alpha);
        let (rho, ks, weight) = self.coating_textures(diffuse_reflectance, specular_reflectance)?;
        Ok(Material::RoughPlastic {
            diffuse_reflectance: rho,
            specular_reflectance: ks,
            eta,
            microfacet: mf,
            nonlinear: *nonlinear,
            specular_sampling_weight: weight,
            table: CoatingTable::get(mf.dist, mf.alpha_u, eta),
        })
    }

    /// A plastic's diffuse and specular textures and Mitsuba's share of specular samples,
    /// `mean(k_s) / (mean(k_s) + mean(rho))` from the textures' RGB means (the same for every
    /// path: it changes the variance, not the expectation).
    fn coating_textures(
        &mut self,
        diffuse_reflectance: &TextureDesc,
        specular_reflectance: &TextureDesc,
    ) -> Result<(Texture, Texture, f32), BuildError> {
        let rho = self.tex("diffuse_reflectance", diffuse_reflectance, Role::Albedo)?;
        let ks = self.tex(
            "specular_reflectance",
            specular_reflectance,
            Role::Unbounded,
        )?;
        let mean = |t: &Texture| t.mean_rgb().iter().sum::<f32>() / 3.0;
        let (d_mean, s_mean) = (mean(&rho), mean(&ks));
        let weight = if d_mean + s_mean > 0.0 {
            s_mean / (d_mean + s_mean)
        } else {
            0.5
        };
        Ok((rho, ks, weight))
    }
}

/// The model inside any `twosided` wrappers.
fn plain_model(d: &BsdfDesc) -> &BsdfDesc {
    match &d.kind {
        BsdfKind::TwoSided { inner } => plain_model(inner),
        _ => d,
    }
}

/// The renderer's microfacet distribution for the description's.
fn distribution(d: MicrofacetDistribution) -> Distribution {
    match d {
        MicrofacetDistribution::Beckmann => Distribution::Beckmann,
        MicrofacetDistribution::Ggx => Distribution::Ggx,
    }
}

/// In RGB mode, a model whose textures are all constant becomes its BSDF ([`Material::Fixed`]).
fn fix(m: Material, mode: ColorMode) -> Material {
    if mode != ColorMode::Rgb || !textures_constant(&m) {
        return m;
    }
    let at = crate::texture::TexturePoint::uv(pt_math::Vec2::ZERO);
    Material::Fixed(m.bsdf(&at, &SampledWavelengths::sample_visible(0.5), mode))
}

/// Whether every texture of a model is a constant.
fn textures_constant(m: &Material) -> bool {
    !matches!(m, Material::Fluorescent(_)) && m.textures().iter().all(|t| t.is_constant())
}
