//! BSDF plugins with physical parameters: Mitsuba's `dielectric`, `thindielectric`,
//! `roughdielectric`, `conductor`, `roughconductor`, and the project's `orennayar`,
//! `minnaert` and `thinfilm` (`thickness` nm 500, `film_ior` 1.33, `ext_ior` 1, and either
//! `int_ior` for a dielectric base or `material` / `eta` + `k` for a conductor base), and
//! `fluorescent` (`reflectance` 0.5, `absorption` 0.5, `emission` required, `yield` 1; see
//! pt-render's `fluorescence.rs`), `phosphorescent` (the same plus `lifetime` in seconds,
//! required; see pt-render's `phosphorescence.rs`). Defaults and named materials follow Mitsuba 3.9.
//!
//! Named conductors are given by their RGB-mode complex index (eta + i k) exactly as Mitsuba 3.9.1
//! `scalar_rgb` computes it from its spectral tables (read with `mi.traverse` on
//! `{'type': 'conductor', 'material': name}`), so that RGB renders match. The spectral mode will
//! need the spectral tables themselves.

use crate::error::{Result, SceneError};
use crate::ir::{BsdfKind, SpectrumDesc};
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

/// Microfacet parameters: `distribution` (beckmann), `alpha` or `alpha_u`/`alpha_v` (0.1).
fn microfacet(v: &ObjectView<'_>) -> Result<(String, f32, f32)> {
    let distribution = v
        .string("distribution")?
        .unwrap_or_else(|| "beckmann".into())
        .to_ascii_lowercase();
    if distribution != "ggx" && distribution != "beckmann" {
        return Err(v.prop_error(
            "distribution",
            format!("unknown microfacet distribution '{distribution}' (ggx or beckmann)"),
        ));
    }
    v.boolean("sample_visible")?; // always on here; it changes variance, not the expectation
    let alpha = v.float("alpha")?;
    let (au, av) = (v.float("alpha_u")?, v.float("alpha_v")?);
    let (alpha_u, alpha_v) = match (alpha, au, av) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            return Err(v.prop_error("alpha", "give either alpha or alpha_u/alpha_v"))
        }
        (Some(a), None, None) => (a, a),
        (None, Some(u), Some(w)) => (u, w),
        (None, None, None) => (0.1, 0.1),
        _ => {
            return Err(v.prop_error(
                if au.is_some() { "alpha_u" } else { "alpha_v" },
                "alpha_u and alpha_v go together",
            ))
        }
    };
    for (n, a) in [("alpha_u", alpha_u), ("alpha_v", alpha_v)] {
        if !(a > 0.0) {
            return Err(v.prop_error(
                if alpha.is_some() { "alpha" } else { n },
                format!("roughness must be positive, got {a}"),
            ));
        }
    }
    Ok((distribution, alpha_u, alpha_v))
}

/// Complex index of a conductor: `material` (a name, default "none": a perfect mirror) or
/// `eta` and `k` given directly.
fn conductor_ior(v: &ObjectView<'_>) -> Result<(SpectrumDesc, SpectrumDesc, SpectrumDesc)> {
    let material = v.string("material")?;
    let (eta, k) = (v.spectrum("eta")?, v.spectrum("k")?);
    let (eta, k) = match (material, eta, k) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            return Err(v.prop_error("material", "give either material or eta and k"))
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
            (SpectrumDesc::Rgb(e.1), SpectrumDesc::Rgb(e.2))
        }
        (None, Some(e), Some(k)) => (e, k),
        (None, e, _) => {
            return Err(v.prop_error(
                if e.is_some() { "eta" } else { "k" },
                "eta and k go together",
            ))
        }
    };
    let sr = v
        .spectrum("specular_reflectance")?
        .unwrap_or(SpectrumDesc::Constant(1.0));
    Ok((eta, k, sr))
}

/// Albedo-like parameter: finite and in [0, 1].
fn albedo(v: &ObjectView<'_>, name: &str) -> Result<SpectrumDesc> {
    let s = v.spectrum(name)?.unwrap_or(SpectrumDesc::Constant(0.5));
    if s.is_emission_only() {
        return Err(v.prop_error(
            name,
            format!(
                "{name} must be a reflectance in [0, 1], not an emission spectrum ({})",
                s.form_name()
            ),
        ));
    }
    let vals = s.values();
    if vals.iter().any(|&x| !(0.0..=1.0).contains(&x)) {
        return Err(v.prop_error(name, format!("{name} must be in [0, 1], got {s:?}")));
    }
    Ok(s)
}

/// Builds the BSDF kind of a physical plugin (see the module doc).
pub(crate) fn bsdf_kind(v: &ObjectView<'_>) -> Result<BsdfKind> {
    let reject_scale = |name: &str| -> Result<()> {
        match v.spectrum(name)? {
            None | Some(SpectrumDesc::Constant(1.0)) => Ok(()),
            Some(_) => Err(v.prop_error(name, format!("{name} other than 1 is not yet supported (not yet implemented; it breaks energy conservation)"))),
        }
    };
    Ok(match v.plugin.as_str() {
        "orennayar" => {
            let sigma = v.float("sigma")?.unwrap_or(0.0);
            if !(sigma >= 0.0) {
                return Err(v.prop_error(
                    "sigma",
                    format!("sigma (radians) must be >= 0, got {sigma}"),
                ));
            }
            let variant = v
                .string("variant")?
                .unwrap_or_else(|| "qualitative".into())
                .to_ascii_lowercase();
            if !["qualitative", "full", "fujii", "eon"].contains(&variant.as_str()) {
                return Err(v.prop_error(
                    "variant",
                    format!(
                        "unknown Oren-Nayar variant '{variant}' (qualitative, full, fujii, eon)"
                    ),
                ));
            }
            BsdfKind::OrenNayar {
                reflectance: albedo(v, "reflectance")?,
                sigma,
                variant,
            }
        }
        "minnaert" => {
            let k = v.float("k")?.unwrap_or(1.0);
            if !(k > 0.0) {
                return Err(v.prop_error("k", format!("k must be positive, got {k}")));
            }
            BsdfKind::Minnaert {
                reflectance: albedo(v, "reflectance")?,
                k,
            }
        }
        "dielectric" | "thindielectric" | "roughdielectric" => {
            reject_scale("specular_reflectance")?;
            reject_scale("specular_transmittance")?;
            let int_ior = ior(v, "int_ior", 1.5046)?;
            let ext_ior = ior(v, "ext_ior", 1.000277)?;
            match v.plugin.as_str() {
                "dielectric" => BsdfKind::Dielectric { int_ior, ext_ior },
                "thindielectric" => BsdfKind::ThinDielectric { int_ior, ext_ior },
                _ => {
                    let (distribution, alpha_u, alpha_v) = microfacet(v)?;
                    BsdfKind::RoughDielectric {
                        int_ior,
                        ext_ior,
                        distribution,
                        alpha_u,
                        alpha_v,
                    }
                }
            }
        }
        "roughplastic" => {
            let int_ior = ior(v, "int_ior", 1.49)?;
            let ext_ior = ior(v, "ext_ior", 1.000277)?;
            if int_ior == ext_ior {
                return Err(v.prop_error(
                    "int_ior",
                    "int_ior and ext_ior must differ (the coating would be invisible)",
                ));
            }
            let (distribution, alpha_u, alpha_v) = microfacet(v)?;
            if alpha_u != alpha_v {
                return Err(v.prop_error(
                    "alpha_u",
                    "roughplastic is isotropic (as in Mitsuba): give one alpha",
                ));
            }
            let specular_reflectance = v
                .spectrum("specular_reflectance")?
                .unwrap_or(SpectrumDesc::Constant(1.0));
            if specular_reflectance
                .values()
                .iter()
                .any(|x| !(x.is_finite() && *x >= 0.0))
            {
                return Err(v.prop_error(
                    "specular_reflectance",
                    "specular_reflectance must be finite and >= 0",
                ));
            }
            BsdfKind::RoughPlastic {
                diffuse_reflectance: albedo(v, "diffuse_reflectance")?,
                specular_reflectance,
                int_ior,
                ext_ior,
                distribution,
                alpha: alpha_u,
                nonlinear: v.boolean("nonlinear")?.unwrap_or(false),
            }
        }
        "conductor" => {
            let (eta, k, specular_reflectance) = conductor_ior(v)?;
            BsdfKind::Conductor {
                eta,
                k,
                specular_reflectance,
            }
        }
        "thinfilm" | "roughthinfilm" => {
            let thickness = v.float("thickness")?.unwrap_or(500.0);
            if !(thickness >= 0.0) {
                return Err(v.prop_error(
                    "thickness",
                    format!("thickness (nm) must be >= 0, got {thickness}"),
                ));
            }
            let film_ior = ior(v, "film_ior", 1.33)?;
            let ext_ior = ior(v, "ext_ior", 1.0)?;
            let dielectric = v.has("int_ior");
            if dielectric && (v.has("material") || v.has("eta") || v.has("k")) {
                return Err(v.prop_error("int_ior", "give either int_ior (dielectric base) or material / eta and k (conductor base)"));
            }
            let smooth = if dielectric {
                let int_ior = ior(v, "int_ior", 1.5)?;
                BsdfKind::ThinFilm {
                    thickness,
                    film_ior,
                    ext_ior,
                    int_ior: Some(int_ior),
                    eta: SpectrumDesc::Constant(0.0),
                    k: SpectrumDesc::Constant(0.0),
                }
            } else {
                let (eta, k, sr) = conductor_ior(v)?;
                if sr != SpectrumDesc::Constant(1.0) {
                    return Err(v.prop_error(
                        "specular_reflectance",
                        "specular_reflectance is not supported on thinfilm",
                    ));
                }
                BsdfKind::ThinFilm {
                    thickness,
                    film_ior,
                    ext_ior,
                    int_ior: None,
                    eta,
                    k,
                }
            };
            match smooth {
                BsdfKind::ThinFilm {
                    thickness,
                    film_ior,
                    ext_ior,
                    int_ior,
                    eta,
                    k,
                } if v.plugin == "roughthinfilm" => {
                    let (distribution, alpha_u, alpha_v) = microfacet(v)?;
                    BsdfKind::RoughThinFilm {
                        thickness,
                        film_ior,
                        ext_ior,
                        int_ior,
                        eta,
                        k,
                        distribution,
                        alpha_u,
                        alpha_v,
                    }
                }
                smooth => smooth,
            }
        }
        "roughconductor" => {
            let (eta, k, specular_reflectance) = conductor_ior(v)?;
            let (distribution, alpha_u, alpha_v) = microfacet(v)?;
            BsdfKind::RoughConductor {
                eta,
                k,
                specular_reflectance,
                distribution,
                alpha_u,
                alpha_v,
            }
        }
        "fluorescent" => {
            let reflectance = albedo(v, "reflectance")?;
            let absorption = albedo(v, "absorption")?;
            let emission = v.spectrum("emission")?.ok_or_else(|| v.prop_error("emission", "fluorescent needs an emission spectrum (<spectrum name=\"emission\" value=\"...\"/>)"))?;
            if emission.values().iter().any(|&x| x < 0.0)
                || emission.values().iter().all(|&x| x == 0.0)
            {
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
            BsdfKind::Fluorescent {
                reflectance,
                absorption,
                emission,
                quantum_yield,
            }
        }
        "phosphorescent" => {
            let reflectance = albedo(v, "reflectance")?;
            let absorption = albedo(v, "absorption")?;
            let emission = v.spectrum("emission")?.ok_or_else(|| v.prop_error("emission", "phosphorescent needs an emission spectrum (<spectrum name=\"emission\" value=\"...\"/>)"))?;
            if emission.values().iter().any(|&x| x < 0.0)
                || emission.values().iter().all(|&x| x == 0.0)
            {
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
            BsdfKind::Phosphorescent {
                reflectance,
                absorption,
                emission,
                quantum_yield,
                lifetime,
            }
        }
        other => {
            return Err(SceneError::at(
                &v.el.loc,
                format!("internal: {other} is not a physical BSDF"),
            ))
        }
    })
}
