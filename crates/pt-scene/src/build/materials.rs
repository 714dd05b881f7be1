//! BSDF plugins with physical parameters: Mitsuba's `dielectric`, `thindielectric`,
//! `roughdielectric`, `conductor`, `roughconductor`, and the project's `orennayar`,
//! `minnaert` and `thinfilm` (`thickness` nm 500, `film_ior` 1.33, `ext_ior` 1, and either
//! `int_ior` for a dielectric base or `material` / `eta` + `k` for a conductor base), and
//! `fluorescent` (`reflectance` 0.5, `absorption` 0.5, `emission` required, `yield` 1; see
//! pt-render's `fluorescence.rs`), `phosphorescent` (the same plus `lifetime` in seconds,
//! required; see pt-render's `phosphorescence.rs`). Defaults and named materials follow Mitsuba 3.9.
//!
//! Texturable parameters (Mitsuba's `|spectrum| or |texture|` and `|float| or |texture|`) take
//! a nested texture: reflectances, `specular_reflectance`/`specular_transmittance`, conductor
//! `eta`/`k`, roughness `alpha`/`alpha_u`/`alpha_v` (not of `roughplastic`, whose `alpha` is a
//! float in Mitsuba), and the extensions' `sigma`, `k` and `thickness`.
//!
//! Named conductors are given by their RGB-mode complex index (eta + i k) exactly as Mitsuba 3.9.1
//! `scalar_rgb` computes it from its spectral tables (read with `mi.traverse` on
//! `{'type': 'conductor', 'material': name}`), so that RGB renders match. The spectral mode will
//! need the spectral tables themselves.

use super::bsdf::scalar_in;
use super::texture::Nested;
use super::Builder;
use crate::error::Result;
use crate::ir::*;
use crate::props::ObjectView;

/// Mitsuba 3's named indices of refraction (its `ior.h` list, values as loaded by 3.9.1).
const IOR_NAMES: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.47),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

/// Mitsuba 3.9.1's RGB-mode complex indices of named conductors: (name, eta, k).
const CONDUCTORS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("none", [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
    (
        "a-C",
        [2.94405, 2.22714, 1.96816],
        [0.887465, 0.799299, 0.81529],
    ),
    (
        "Ag",
        [0.155276, 0.116728, 0.138388],
        [4.82835, 3.12222, 2.1469],
    ),
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    (
        "Au",
        [0.143036, 0.375307, 1.44205],
        [3.983, 2.38556, 1.60336],
    ),
    (
        "Be",
        [4.18501, 3.18503, 2.78406],
        [3.83547, 3.01012, 2.86899],
    ),
    ("Cr", [4.36967, 2.91651, 1.6549], [5.20655, 4.23131, 3.7547]),
    (
        "Cu",
        [0.201005, 0.92375, 1.10222],
        [3.91326, 2.45305, 2.14209],
    ),
    (
        "Hg",
        [2.39894, 1.44003, 0.90957],
        [6.32759, 4.37192, 3.42176],
    ),
    (
        "Ir",
        [3.0863, 2.08219, 1.61791],
        [5.59215, 4.06709, 3.26731],
    ),
    (
        "K",
        [0.0640432, 0.0464098, 0.0381849],
        [2.1042, 1.34894, 0.913126],
    ),
    (
        "Li",
        [0.265791, 0.195618, 0.220949],
        [3.54015, 2.31112, 1.66861],
    ),
    (
        "Mo",
        [4.48397, 3.52513, 2.77631],
        [4.11144, 3.42083, 3.15061],
    ),
    (
        "Na_palik",
        [0.0602694, 0.0561409, 0.0619884],
        [3.17927, 2.11249, 1.57904],
    ),
    (
        "Nb",
        [3.42007, 2.79009, 2.39563],
        [3.44139, 2.73767, 2.57975],
    ),
    (
        "Ni_palik",
        [2.3673, 1.66337, 1.46708],
        [4.49881, 3.05015, 2.34544],
    ),
    (
        "Rh",
        [2.58579, 1.86022, 1.55426],
        [6.78226, 4.70299, 3.97607],
    ),
    (
        "Ta",
        [2.06272, 2.39294, 2.62793],
        [2.40836, 1.74149, 1.94703],
    ),
    (
        "TiN",
        [1.64845, 1.15052, 1.37982],
        [3.36833, 1.9435, 1.10207],
    ),
    (
        "V_palik",
        [4.27758, 3.51295, 2.76107],
        [3.4913, 2.88945, 3.11152],
    ),
    (
        "W",
        [4.37082, 3.30025, 2.99841],
        [3.50064, 2.60487, 2.27323],
    ),
];

/// An index of refraction given as a number or a Mitsuba name.
/// An index of refraction given as a number or a Mitsuba name.
fn ior(v: &ObjectView<'_>, name: &str, default: f32) -> Result<f32> {
    let value = match v.float_or_string(name)? {
        None => default,
        Some(Ok(x)) => x,
        Some(Err(n)) => IOR_NAMES
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(n.trim()))
            .map(|e| e.1)
            .ok_or_else(|| {
                let known: Vec<&str> = IOR_NAMES.iter().map(|e| e.0).collect();
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
                let e = CONDUCTORS
                    .iter()
                    .find(|c| c.0.eq_ignore_ascii_case(&name))
                    .ok_or_else(|| {
                        let known: Vec<&str> = CONDUCTORS.iter().map(|c| c.0).collect();
                        v.prop_error(
                            "material",
                            format!("unknown conductor '{name}' (known: {})", known.join(", ")),
                        )
                    })?;
                Ok((
                    TextureDesc::Constant(SpectrumDesc::Rgb(e.1)),
                    TextureDesc::Constant(SpectrumDesc::Rgb(e.2)),
                ))
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
        "roughplastic" => b.rough_plastic(v, n)?,
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
