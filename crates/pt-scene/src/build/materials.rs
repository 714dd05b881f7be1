//! BSDF plugins with physical parameters: Mitsuba's `dielectric`, `thindielectric`,
//! `roughdielectric`, `conductor`, `roughconductor`, and the project's `orennayar`,
//! `minnaert` and `thinfilm` (`thickness` nm 500, `film_ior` 1.33, `ext_ior` 1, and either
//! `int_ior` for a dielectric base or `material` / `eta` + `k` for a conductor base), and
//! `fluorescent` (`reflectance` 0.5, `absorption` 0.5, `emission` required, `yield` 1; see
//! pt-render's `fluorescence.rs`), `phosphorescent` (the same plus `lifetime` in seconds,
//! required; see pt-integrators' `afterglow.rs`). Defaults and named materials follow Mitsuba 3.9.
//!
//! Texturable parameters (Mitsuba's `|spectrum| or |texture|` and `|float| or |texture|`) take
//! a nested texture: reflectances, `specular_reflectance`/`specular_transmittance`, conductor
//! `eta`/`k`, roughness `alpha`/`alpha_u`/`alpha_v` (not of `roughplastic`, whose `alpha` is a
//! float in Mitsuba), and the extensions' `sigma`, `k` and `thickness`.
//!
//! Named indices of refraction and conductors are Mitsuba's, from [`crate::named`].

use super::bsdf::scalar_in;
use super::texture::Nested;
use super::Builder;
use crate::error::Result;
use crate::ir::*;
use crate::named::{conductor_names, ior_names, named_conductor, named_ior};
use crate::props::ObjectView;

/// An index of refraction given as a number or a Mitsuba name.
fn ior(v: &ObjectView<'_>, name: &str, default: f32) -> Result<f32> {
    let value = match v.float_or_string(name)? {
        None => default,
        Some(Ok(x)) => x,
        Some(Err(n)) => named_ior(&n).ok_or_else(|| {
            let known: Vec<&str> = ior_names().collect();
            v.prop_error(
                name,
                format!(
                    "unknown index of refraction '{n}' (known: {})",
                    known.join(", ")
                ),
            )
        })?,
    };
    if !(value > 0.0) {
        return Err(v.prop_error(name, format!("{name} must be positive, got {value}")));
    }
    Ok(value)
}

/// The microfacet distribution (`distribution`, beckmann by default; `sample_visible` is
/// accepted: visible normals are always sampled, which changes variance, not the expectation).
fn distribution(v: &ObjectView<'_>) -> Result<MicrofacetDistribution> {
    v.boolean("sample_visible")?;
    match v
        .string("distribution")?
        .map(|d| d.to_ascii_lowercase())
        .as_deref()
    {
        None | Some("beckmann") => Ok(MicrofacetDistribution::Beckmann),
        Some("ggx") => Ok(MicrofacetDistribution::Ggx),
        Some(other) => Err(v.prop_error(
            "distribution",
            format!("unknown microfacet distribution '{other}' (ggx or beckmann)"),
        )),
    }
}

impl<'e> Builder<'e> {
    /// Microfacet parameters: `distribution` and `alpha` or `alpha_u`/`alpha_v` (0.1),
    /// each a positive number or a texture.
    fn microfacet(&mut self, v: &ObjectView<'e>, n: &Nested<'e>) -> Result<MicrofacetDesc> {
        let distribution = distribution(v)?;
        let alpha = self.texture_param(v, n, "alpha")?;
        let (au, av) = (
            self.texture_param(v, n, "alpha_u")?,
            self.texture_param(v, n, "alpha_v")?,
        );
        let (alpha_u, alpha_v) = match (alpha, au, av) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                return Err(v.prop_error("alpha", "give either alpha or alpha_u/alpha_v"))
            }
            (Some(a), None, None) => (a.clone(), a),
            (None, Some(u), Some(w)) => (u, w),
            (None, None, None) => (TextureDesc::constant(0.1), TextureDesc::constant(0.1)),
            (None, u, _) => {
                return Err(v.prop_error(
                    if u.is_some() { "alpha_u" } else { "alpha_v" },
                    "alpha_u and alpha_v go together",
                ))
            }
        };
        for (name, a) in [("alpha_u", &alpha_u), ("alpha_v", &alpha_v)] {
            let name = if v.has("alpha") { "alpha" } else { name };
            positive_scalar(v, name, a, "roughness")?;
        }
        Ok(MicrofacetDesc {
            distribution,
            alpha_u,
            alpha_v,
        })
    }

    /// Complex index of a conductor: `material` (a name, default "none": a perfect mirror) or
    /// `eta` and `k` given directly (numbers, colours, spectra or textures).
    fn conductor_ior(
        &mut self,
        v: &ObjectView<'e>,
        n: &Nested<'e>,
    ) -> Result<(TextureDesc, TextureDesc)> {
        let material = v.string("material")?;
        let (eta, k) = (
            self.texture_param(v, n, "eta")?,
            self.texture_param(v, n, "k")?,
        );
        match (material, eta, k) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                Err(v.prop_error("material", "give either material or eta and k"))
            }
            (m, None, None) => {
                let name = m.unwrap_or_else(|| "none".into());
                let c = named_conductor(&name).ok_or_else(|| {
                    let known: Vec<&str> = conductor_names().collect();
                    v.prop_error(
                        "material",
                        format!("unknown conductor '{name}' (known: {})", known.join(", ")),
                    )
                })?;
                Ok((TextureDesc::Constant(c.eta), TextureDesc::Constant(c.k)))
            }
            (None, Some(e), Some(k)) => Ok((e, k)),
            (None, e, _) => Err(v.prop_error(
                if e.is_some() { "eta" } else { "k" },
                "eta and k go together",
            )),
        }
    }

    /// An albedo-like parameter (default 0.5): a texture, or a constant in [0, 1].
    fn albedo(&mut self, v: &ObjectView<'e>, n: &Nested<'e>, name: &str) -> Result<TextureDesc> {
        let t = self
            .texture_param(v, n, name)?
            .unwrap_or(TextureDesc::constant(0.5));
        for s in t.spectra() {
            check_albedo(v, name, s)?;
        }
        Ok(t)
    }

    /// A non-negative factor (`specular_reflectance`, `specular_transmittance`; default 1).
    fn factor(&mut self, v: &ObjectView<'e>, n: &Nested<'e>, name: &str) -> Result<TextureDesc> {
        let t = self
            .texture_param(v, n, name)?
            .unwrap_or(TextureDesc::constant(1.0));
        for s in t.spectra() {
            if s.is_emission_only() || s.values().iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(
                    v.prop_error(name, format!("{name} must be finite and >= 0, got {s:?}"))
                );
            }
        }
        Ok(t)
    }

    /// A dielectric's interface: (int_ior, ext_ior, specular_reflectance,
    /// specular_transmittance).
    fn dielectric(
        &mut self,
        v: &ObjectView<'e>,
        n: &Nested<'e>,
    ) -> Result<(f32, f32, TextureDesc, TextureDesc)> {
        let int_ior = ior(v, "int_ior", 1.5046)?;
        let ext_ior = ior(v, "ext_ior", 1.000277)?;
        let sr = self.factor(v, n, "specular_reflectance")?;
        let st = self.factor(v, n, "specular_transmittance")?;
        Ok((int_ior, ext_ior, sr, st))
    }

    /// `hair` (Mitsuba 3.9.1's parameters and checks): `eumelanin` 1.3 and `pheomelanin` 0.2,
    /// or `sigma_a` (times `scale`, 1), or pt's `reflectance` (pbrt-v4's), only one of the
    /// three; `int_ior` 1.55 (amber), `ext_ior` 1.000277, different and positive;
    /// `longitudinal_roughness` and `azimuthal_roughness` 0.3 in [0, 1]; `scale_tilt` 2 degrees.
    fn hair(&mut self, v: &ObjectView<'e>, n: &Nested<'e>) -> Result<BsdfKind> {
        let roughness = |name: &str| -> Result<f32> {
            let x = v.float(name)?.unwrap_or(0.3);
            if !(0.0..=1.0).contains(&x) {
                return Err(v.prop_error(name, format!("{name} must be in [0, 1]")));
            }
            Ok(x)
        };
        let longitudinal_roughness = roughness("longitudinal_roughness")?;
        let azimuthal_roughness = roughness("azimuthal_roughness")?;
        let scale_tilt_deg = v.float("scale_tilt")?.unwrap_or(2.0);
        if !(scale_tilt_deg.abs() < 90.0) {
            return Err(v.prop_error("scale_tilt", "scale_tilt must be in (-90, 90) degrees"));
        }
        let int_ior = ior(v, "int_ior", 1.55)?;
        let ext_ior = ior(v, "ext_ior", 1.000277)?;
        if int_ior == ext_ior {
            return Err(v.prop_error(
                "int_ior",
                "the interior and exterior indices of refraction must differ",
            ));
        }
        let pigments = v.has("eumelanin") || v.has("pheomelanin");
        let sigma_a = self.texture_param(v, n, "sigma_a")?;
        let reflectance = self.texture_param(v, n, "reflectance")?;
        let given = [pigments, sigma_a.is_some(), reflectance.is_some()];
        if given.iter().filter(|g| **g).count() > 1 {
            let name = if reflectance.is_some() {
                "reflectance"
            } else {
                "sigma_a"
            };
            return Err(v.prop_error(
                name,
                "give one of the pigments (eumelanin, pheomelanin), sigma_a or reflectance, not several",
            ));
        }
        // Read whatever the absorption, as Mitsuba reads it; it scales only `sigma_a`.
        let scale = v.float("scale")?.unwrap_or(1.0);
        if !(scale >= 0.0) {
            return Err(v.prop_error("scale", "scale must not be negative"));
        }
        let absorption = match (sigma_a, reflectance) {
            (Some(sigma_a), _) => {
                for s in sigma_a.spectra() {
                    if s.values().iter().any(|x| !(*x >= 0.0)) {
                        return Err(v.prop_error("sigma_a", "sigma_a must not be negative"));
                    }
                }
                HairAbsorption::SigmaA { sigma_a, scale }
            }
            (None, Some(r)) => {
                for s in r.spectra() {
                    if s.values().iter().any(|x| !(*x > 0.0 && *x <= 1.0)) {
                        return Err(v.prop_error("reflectance", "reflectance must be in (0, 1]"));
                    }
                }
                HairAbsorption::Reflectance(r)
            }
            (None, None) => {
                let conc = |name: &str, default: f32| -> Result<f32> {
                    let x = v.float(name)?.unwrap_or(default);
                    if !(x >= 0.0) {
                        return Err(v.prop_error(name, format!("{name} must not be negative")));
                    }
                    Ok(x)
                };
                HairAbsorption::Pigments {
                    eumelanin: conc("eumelanin", 1.3)?,
                    pheomelanin: conc("pheomelanin", 0.2)?,
                }
            }
        };
        Ok(BsdfKind::Hair {
            absorption,
            eta: int_ior / ext_ior,
            longitudinal_roughness,
            azimuthal_roughness,
            scale_tilt_deg,
        })
    }

    /// `thinfilm` and `roughthinfilm`: `thickness` (nm, 500), `film_ior` (1.33), `ext_ior` (1),
    /// and `int_ior` (a dielectric base) or `material` / `eta` + `k` (a conductor base).
    fn thin_film(&mut self, v: &ObjectView<'e>, n: &Nested<'e>) -> Result<BsdfKind> {
        let thickness = self
            .texture_param(v, n, "thickness")?
            .unwrap_or(TextureDesc::constant(500.0));
        for s in thickness.spectra() {
            if s.is_spectral() || s.values().iter().any(|x| !(*x >= 0.0)) {
                return Err(v.prop_error(
                    "thickness",
                    format!("thickness (nm) must be >= 0, got {s:?}"),
                ));
            }
        }
        let film_ior = ior(v, "film_ior", 1.33)?;
        let ext_ior = ior(v, "ext_ior", 1.0)?;
        let dielectric = v.has("int_ior");
        if dielectric && (v.has("material") || v.has("eta") || v.has("k")) {
            return Err(v.prop_error(
                "int_ior",
                "give either int_ior (dielectric base) or material / eta and k (conductor base)",
            ));
        }
        let base = if dielectric {
            FilmBaseDesc::Dielectric {
                int_ior: ior(v, "int_ior", 1.5)?,
            }
        } else {
            let (eta, k) = self.conductor_ior(v, n)?;
            FilmBaseDesc::Conductor { eta, k }
        };
        Ok(if v.plugin == "roughthinfilm" {
            let microfacet = self.microfacet(v, n)?;
            BsdfKind::RoughThinFilm {
                thickness,
                film_ior,
                ext_ior,
                base,
                microfacet,
            }
        } else {
            BsdfKind::ThinFilm {
                thickness,
                film_ior,
                ext_ior,
                base,
            }
        })
    }
}

/// A reflectance must be a reflectance: not an emission spectrum, and within [0, 1].
fn check_albedo(v: &ObjectView<'_>, name: &str, s: &SpectrumDesc) -> Result<()> {
    if s.is_emission_only() {
        return Err(v.prop_error(
            name,
            format!(
                "{name} must be a reflectance in [0, 1], not an emission spectrum ({})",
                s.form_name()
            ),
        ));
    }
    if s.values().iter().any(|&x| !(0.0..=1.0).contains(&x)) {
        return Err(v.prop_error(name, format!("{name} must be in [0, 1], got {s:?}")));
    }
    Ok(())
}

/// A scalar texture whose constants must be positive numbers (roughness, Minnaert k).
fn positive_scalar(v: &ObjectView<'_>, name: &str, t: &TextureDesc, what: &str) -> Result<()> {
    for s in t.spectra() {
        if s.is_spectral() {
            return Err(v.prop_error(
                name,
                format!("{name} is a number, not a spectrum ({})", s.form_name()),
            ));
        }
        if let Some(x) = s.values().into_iter().find(|x| !(*x > 0.0)) {
            return Err(v.prop_error(name, format!("{what} must be positive, got {x}")));
        }
    }
    Ok(())
}

/// A spectrum-valued non-texturable parameter in [0, 1] (fluorescence), default 0.5.
fn fixed_albedo(v: &ObjectView<'_>, name: &str) -> Result<SpectrumDesc> {
    let s = v.spectrum(name)?.unwrap_or(SpectrumDesc::Constant(0.5));
    check_albedo(v, name, &s)?;
    Ok(s)
}

/// `fluorescent` / `phosphorescent`: the parameters they share (reflectance, absorption,
/// emission, yield).
fn luminescent(v: &ObjectView<'_>) -> Result<(SpectrumDesc, SpectrumDesc, SpectrumDesc, f32)> {
    let reflectance = fixed_albedo(v, "reflectance")?;
    let absorption = fixed_albedo(v, "absorption")?;
    let emission = v.spectrum("emission")?.ok_or_else(|| {
        v.prop_error(
            "emission",
            format!(
                "{} needs an emission spectrum (<spectrum name=\"emission\" value=\"...\"/>)",
                v.plugin
            ),
        )
    })?;
    if emission.values().iter().any(|&x| x < 0.0) || emission.values().iter().all(|&x| x == 0.0) {
        return Err(v.prop_error(
            "emission",
            "emission spectrum must be non-negative and not all zero",
        ));
    }
    let quantum_yield = v.float("yield")?.unwrap_or(1.0);
    if !(0.0..=1.0).contains(&quantum_yield) {
        return Err(v.prop_error(
            "yield",
            format!("quantum yield must be in [0, 1], got {quantum_yield}"),
        ));
    }
    Ok((reflectance, absorption, emission, quantum_yield))
}

/// Builds the BSDF kind of a model plugin (see the module doc); unknown plugins are errors.
pub(super) fn bsdf_kind<'e>(
    b: &mut Builder<'e>,
    v: &ObjectView<'e>,
    n: &Nested<'e>,
) -> Result<BsdfKind> {
    Ok(match v.plugin.as_str() {
        // Not range-checked, as Mitsuba's `uniform` is not: radiosity rejects albedos above 1
        // itself, and a path tracer renders them (gaining energy).
        "diffuse" => BsdfKind::Diffuse {
            reflectance: b
                .texture_param(v, n, "reflectance")?
                .unwrap_or(TextureDesc::constant(0.5)),
        },
        "orennayar" => {
            let sigma = b.texture_param(v, n, "sigma")?;
            let sigma = scalar_in(v, "sigma", sigma, 0.0, 0.0..=f32::MAX)?;
            BsdfKind::OrenNayar {
                reflectance: b.albedo(v, n, "reflectance")?,
                sigma,
                variant: oren_nayar_variant(v)?,
            }
        }
        "minnaert" => {
            let k = b
                .texture_param(v, n, "k")?
                .unwrap_or(TextureDesc::constant(1.0));
            positive_scalar(v, "k", &k, "k")?;
            BsdfKind::Minnaert {
                reflectance: b.albedo(v, n, "reflectance")?,
                k,
            }
        }
        "dielectric" => {
            let (int_ior, ext_ior, specular_reflectance, specular_transmittance) =
                b.dielectric(v, n)?;
            BsdfKind::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            }
        }
        "thindielectric" => {
            let (int_ior, ext_ior, specular_reflectance, specular_transmittance) =
                b.dielectric(v, n)?;
            BsdfKind::ThinDielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            }
        }
        "roughdielectric" => {
            let (int_ior, ext_ior, specular_reflectance, specular_transmittance) =
                b.dielectric(v, n)?;
            let microfacet = b.microfacet(v, n)?;
            BsdfKind::RoughDielectric {
                int_ior,
                ext_ior,
                microfacet,
                specular_reflectance,
                specular_transmittance,
            }
        }
        "plastic" => b.plastic(v, n)?,
        "roughplastic" => b.rough_plastic(v, n)?,
        "principled" => b.principled(v, n)?,
        "principledthin" => b.principled_thin(v, n)?,
        "conductor" => {
            let (eta, k) = b.conductor_ior(v, n)?;
            let specular_reflectance = b.factor(v, n, "specular_reflectance")?;
            BsdfKind::Conductor {
                eta,
                k,
                specular_reflectance,
            }
        }
        "roughconductor" => {
            let (eta, k) = b.conductor_ior(v, n)?;
            let specular_reflectance = b.factor(v, n, "specular_reflectance")?;
            let microfacet = b.microfacet(v, n)?;
            BsdfKind::RoughConductor {
                eta,
                k,
                specular_reflectance,
                microfacet,
            }
        }
        "thinfilm" | "roughthinfilm" => b.thin_film(v, n)?,
        "pplastic" => {
            let (int_ior, ext_ior) = (ior(v, "int_ior", 1.49)?, ior(v, "ext_ior", 1.000277)?);
            if int_ior == ext_ior {
                return Err(v.prop_error(
                    "int_ior",
                    "int_ior and ext_ior must differ (as Mitsuba requires)",
                ));
            }
            BsdfKind::PPlastic {
                diffuse_reflectance: b.albedo(v, n, "diffuse_reflectance")?,
                specular_reflectance: b.factor(v, n, "specular_reflectance")?,
                int_ior,
                ext_ior,
                microfacet: b.microfacet(v, n)?,
            }
        }
        // Without polarization an element's orientation, retardance and handedness change
        // nothing.
        "polarizer" => {
            b.texture_param(v, n, "theta")?;
            v.boolean("polarizing")?;
            BsdfKind::Polarizer {
                element: PolarizingElement::LinearPolarizer,
                transmittance: b.factor(v, n, "transmittance")?,
            }
        }
        "retarder" => {
            b.texture_param(v, n, "theta")?;
            b.texture_param(v, n, "delta")?;
            BsdfKind::Polarizer {
                element: PolarizingElement::Retarder,
                transmittance: b.factor(v, n, "transmittance")?,
            }
        }
        "circular" => {
            v.boolean("left_handed")?;
            BsdfKind::Polarizer {
                element: PolarizingElement::CircularPolarizer,
                transmittance: b.factor(v, n, "transmittance")?,
            }
        }
        "hair" => b.hair(v, n)?,
        "fluorescent" => {
            let (reflectance, absorption, emission, quantum_yield) = luminescent(v)?;
            BsdfKind::Fluorescent {
                reflectance,
                absorption,
                emission,
                quantum_yield,
            }
        }
        "phosphorescent" => phosphorescent(v)?,
        _ => return Err(super::plugin_error(v.el)),
    })
}

impl<'e> Builder<'e> {
    /// `roughplastic`: `diffuse_reflectance` (0.5), `specular_reflectance` (1), `int_ior`
    /// (polypropylene, 1.49), `ext_ior` (air), `distribution`, `alpha` (0.1, a float and
    /// isotropic, as in Mitsuba), `nonlinear` (false).
    /// `plastic`: Mitsuba's parameters and defaults (it accepts equal indices, unlike
    /// `roughplastic`: the coating is then invisible).
    fn plastic(&mut self, v: &ObjectView<'e>, n: &Nested<'e>) -> Result<BsdfKind> {
        Ok(BsdfKind::Plastic {
            int_ior: ior(v, "int_ior", 1.49)?,
            ext_ior: ior(v, "ext_ior", 1.000277)?,
            diffuse_reflectance: self.albedo(v, n, "diffuse_reflectance")?,
            specular_reflectance: self.factor(v, n, "specular_reflectance")?,
            nonlinear: v.boolean("nonlinear")?.unwrap_or(false),
        })
    }

    /// `principled` (Mitsuba 3.9.1's parameters and defaults; see pt-bsdf's `principled.rs`):
    /// `base_color` (0.5), the scalar textures `roughness` (0.5), `anisotropic`, `metallic`,
    /// `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`, `flatness`, `clearcoat`,
    /// `clearcoat_gloss` (0, each in [0, 1]), `eta` or `specular` (0.5; not both; eta = 2 /
    /// (1 - sqrt(0.08 specular)) - 1), and the three sampling rates (1).
    fn principled(&mut self, v: &ObjectView<'e>, n: &Nested<'e>) -> Result<BsdfKind> {
        let mut scalars = Vec::with_capacity(PrincipledDesc::NAMES.len());
        for name in PrincipledDesc::NAMES {
            let default = if name == "roughness" { 0.5 } else { 0.0 };
            let t = self.texture_param(v, n, name)?;
            scalars.push(scalar_in(v, name, t, default, 0.0..=1.0)?);
        }
        let scalars: [TextureDesc; 10] = scalars.try_into().expect("ten scalars");
        let spec_trans = &scalars[3];
        // Mitsuba adds the transmission lobe when spec_trans is given and not the float 0.
        let transmissive = *spec_trans != TextureDesc::constant(0.0);
        let eta = match (v.float("eta")?, v.float("specular")?) {
            (Some(_), Some(_)) => {
                return Err(v.prop_error(
                    "specular",
                    "give either eta or specular (as Mitsuba requires)",
                ))
            }
            (Some(eta), None) => {
                if !(eta > 0.0 && eta.is_finite()) {
                    return Err(v.prop_error("eta", format!("eta must be positive, got {eta}")));
                }
                if transmissive && eta == 1.0 {
                    1.001
                } else {
                    eta
                }
            }
            (None, s) => {
                let s = s.unwrap_or(0.5);
                if !(0.0..=1.0).contains(&s) {
                    return Err(
                        v.prop_error("specular", format!("specular must be in [0, 1], got {s}"))
                    );
                }
                let s = if transmissive && s == 0.0 { 1e-3 } else { s };
                2.0 / (1.0 - (0.08 * s).sqrt()) - 1.0
            }
        };
        let rate = |name: &str| sampling_rate(v, name);
        let rates = [
            rate("main_specular_sampling_rate")?,
            rate("clearcoat_sampling_rate")?,
            rate("diffuse_reflectance_sampling_rate")?,
        ];
        Ok(BsdfKind::Principled(Box::new(PrincipledDesc {
            base_color: self.albedo(v, n, "base_color")?,
            scalars,
            eta,
            transmissive,
            rates,
        })))
    }

    /// `principledthin` (Mitsuba 3.9.1's parameters and defaults; see pt-bsdf's
    /// `principled_thin.rs`): `base_color` (0.5), the scalar textures `roughness` (0.5),
    /// `anisotropic`, `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`, `flatness` (0, in [0,
    /// 1]), `diff_trans` (0, in [0, 2]), `eta` (1.5, a texture too), and the four sampling
    /// rates (1).
    fn principled_thin(&mut self, v: &ObjectView<'e>, n: &Nested<'e>) -> Result<BsdfKind> {
        let mut scalars = Vec::with_capacity(9);
        for name in PrincipledThinDesc::NAMES {
            let (default, range) = match name {
                "roughness" => (0.5, 0.0..=1.0),
                "diff_trans" => (0.0, 0.0..=2.0),
                "eta" => (1.5, 1e-3..=f32::MAX),
                _ => (0.0, 0.0..=1.0),
            };
            let t = self.texture_param(v, n, name)?;
            scalars.push(scalar_in(v, name, t, default, range)?);
        }
        let rate = |name: &str| sampling_rate(v, name);
        let rates = [
            rate("specular_reflectance_sampling_rate")?,
            rate("specular_transmittance_sampling_rate")?,
            rate("diffuse_reflectance_sampling_rate")?,
            rate("diffuse_transmittance_sampling_rate")?,
        ];
        Ok(BsdfKind::PrincipledThin(Box::new(PrincipledThinDesc {
            base_color: self.albedo(v, n, "base_color")?,
            scalars: scalars.try_into().expect("nine scalars"),
            rates,
        })))
    }

    fn rough_plastic(&mut self, v: &ObjectView<'e>, n: &Nested<'e>) -> Result<BsdfKind> {
        let int_ior = ior(v, "int_ior", 1.49)?;
        let ext_ior = ior(v, "ext_ior", 1.000277)?;
        if int_ior == ext_ior {
            return Err(v.prop_error(
                "int_ior",
                "int_ior and ext_ior must differ (the coating would be invisible)",
            ));
        }
        let distribution = distribution(v)?;
        if v.has("alpha_u") || v.has("alpha_v") {
            return Err(v.prop_error(
                if v.has("alpha_u") {
                    "alpha_u"
                } else {
                    "alpha_v"
                },
                "roughplastic is isotropic (as in Mitsuba): give one alpha",
            ));
        }
        let alpha = v.float("alpha")?.unwrap_or(0.1);
        if !(alpha > 0.0) {
            return Err(v.prop_error("alpha", format!("roughness must be positive, got {alpha}")));
        }
        Ok(BsdfKind::RoughPlastic {
            diffuse_reflectance: self.albedo(v, n, "diffuse_reflectance")?,
            specular_reflectance: self.factor(v, n, "specular_reflectance")?,
            int_ior,
            ext_ior,
            distribution,
            alpha,
            nonlinear: v.boolean("nonlinear")?.unwrap_or(false),
        })
    }
}

/// A lobe-selection weight of the principled models (`..._sampling_rate`; default 1, >= 0).
fn sampling_rate(v: &ObjectView<'_>, name: &str) -> Result<f32> {
    let r = v.float(name)?.unwrap_or(1.0);
    if !(r >= 0.0 && r.is_finite()) {
        return Err(v.prop_error(name, format!("{name} must be >= 0, got {r}")));
    }
    Ok(r)
}

/// The Oren-Nayar `variant` (qualitative by default).
fn oren_nayar_variant(v: &ObjectView<'_>) -> Result<OrenNayarVariant> {
    match v
        .string("variant")?
        .map(|s| s.to_ascii_lowercase())
        .as_deref()
    {
        None | Some("qualitative") => Ok(OrenNayarVariant::Qualitative),
        Some("full") => Ok(OrenNayarVariant::Full),
        Some("fujii") => Ok(OrenNayarVariant::Fujii),
        Some("eon") => Ok(OrenNayarVariant::Eon),
        Some(other) => Err(v.prop_error(
            "variant",
            format!("unknown Oren-Nayar variant '{other}' (qualitative, full, fujii, eon)"),
        )),
    }
}

/// `phosphorescent`: the luminescent parameters and `lifetime` (seconds, required).
fn phosphorescent(v: &ObjectView<'_>) -> Result<BsdfKind> {
    let (reflectance, absorption, emission, quantum_yield) = luminescent(v)?;
    let lifetime = v.float("lifetime")?.ok_or_else(|| {
        v.prop_error(
            "lifetime",
            "phosphorescent needs <float name=\"lifetime\"> (seconds)",
        )
    })?;
    if !(lifetime > 0.0) {
        return Err(v.prop_error(
            "lifetime",
            format!("lifetime must be positive (seconds), got {lifetime}"),
        ));
    }
    Ok(BsdfKind::Phosphorescent {
        reflectance,
        absorption,
        emission,
        quantum_yield,
        lifetime,
    })
}
