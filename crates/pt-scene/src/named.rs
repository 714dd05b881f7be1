//! Mitsuba 3's named materials: indices of refraction (`int_ior="bk7"`) and conductors
//! (`material="Au"`), in one place for the XML loader and for code that builds BSDFs from
//! parameters.
//!
//! Named conductors are given by their RGB-mode complex index (eta + i k) exactly as Mitsuba 3.9.1
//! `scalar_rgb` computes it from its spectral tables (read with `mi.traverse` on
//! `{'type': 'conductor', 'material': name}`), so that RGB renders match. The spectral mode will
//! need the spectral tables themselves.

/// A named conductor's complex index of refraction in RGB mode, `eta + i k` per linear sRGB
/// channel, relative to vacuum (dimensionless).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NamedConductor {
    /// The name as Mitsuba spells it (`Au`, `Cu`, `Na_palik`, ...).
    pub name: &'static str,
    /// Real part of the index, per RGB channel.
    pub eta: [f32; 3],
    /// Imaginary part (extinction coefficient), per RGB channel.
    pub k: [f32; 3],
}

/// The index of refraction Mitsuba 3 gives the name (its `ior.h` list: `vacuum`, `air`,
/// `water`, `bk7`, `diamond`, ...), compared case-insensitively, surrounding spaces ignored.
pub fn named_ior(name: &str) -> Option<f32> {
    let name = name.trim();
    IOR_NAMES
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name))
        .map(|e| e.1)
}

/// The names [`named_ior`] knows, in Mitsuba's order.
pub fn ior_names() -> impl Iterator<Item = &'static str> {
    IOR_NAMES.iter().map(|e| e.0)
}

/// The conductor Mitsuba 3 gives the name (`none`, a perfect mirror, `Au`, `Ag`, `Cu`, ...),
/// compared case-insensitively.
pub fn named_conductor(name: &str) -> Option<NamedConductor> {
    CONDUCTORS
        .iter()
        .find(|c| c.0.eq_ignore_ascii_case(name))
        .map(|&(name, eta, k)| NamedConductor { name, eta, k })
}

/// The names [`named_conductor`] knows, in Mitsuba's order.
pub fn conductor_names() -> impl Iterator<Item = &'static str> {
    CONDUCTORS.iter().map(|c| c.0)
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_found_in_any_case_and_unknown_names_are_not() {
        assert_eq!(named_ior(" BK7 "), Some(1.5046));
        assert_eq!(named_ior("unobtainium"), None);
        let au = named_conductor("au").unwrap();
        assert_eq!((au.name, au.eta[0], au.k[2]), ("Au", 0.143036, 1.60336));
        assert!(named_conductor("none").is_some_and(|c| c.eta == [0.0; 3] && c.k == [1.0; 3]));
        assert_eq!(ior_names().count(), 23);
        assert_eq!(conductor_names().next(), Some("none"));
    }
}
