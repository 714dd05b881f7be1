//! Spectrum-valued inputs: RGB, constants, tabulated spectra, blackbodies, named illuminants.

/// A spectrum-valued parameter: linear Rec.709 RGB, one number for all channels, or a
/// tabulated spectrum (which makes the scene spectral).
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumDesc {
    /// The same value in every channel / at every wavelength (`<float>`, `<integer>`); as an
    /// emission, Mitsuba's D65 white of that luminance.
    Constant(f32),
    /// Mitsuba's `<spectrum value="x"/>`: the value x at every wavelength, an equal-energy
    /// spectrum. As a reflectance the same as a constant; as an emission it is not D65 but
    /// illuminant E (in linear sRGB x (1.205, 0.948, 0.909): Mitsuba 3.9.1 renders it so in
    /// its RGB and spectral variants alike).
    Uniform(f32),
    /// Linear Rec.709 RGB.
    Rgb([f32; 3]),
    /// Piecewise-linear (wavelength nm, value) pairs, increasing wavelengths; zero outside
    /// their range, as Mitsuba's `<spectrum value="400:0.1, 500:0.5"/>`.
    Tabulated(std::sync::Arc<Vec<(f32, f32)>>),
    /// A material's measured spectrum (a named conductor's eta or k: Mitsuba's `data/ior`
    /// tables), piecewise linear and zero outside its range like `Tabulated`, but one that does
    /// not by itself make a scene spectral: RGB mode uses its linear sRGB, converted as Mitsuba's
    /// RGB variants convert these tables (`ior_from_file`: no D65, not clamped).
    Measured(&'static [(f32, f32)]),
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
            SpectrumDesc::Uniform(_) => "uniform".into(),
            SpectrumDesc::Rgb(_) => "RGB".into(),
            SpectrumDesc::Tabulated(_) => "tabulated".into(),
            SpectrumDesc::Measured(_) => "measured".into(),
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
            SpectrumDesc::Constant(c) | SpectrumDesc::Uniform(c) => vec![*c],
            SpectrumDesc::Rgb(c) => c.to_vec(),
            SpectrumDesc::Tabulated(p) => p.iter().map(|e| e.1).collect(),
            SpectrumDesc::Measured(p) => p.iter().map(|e| e.1).collect(),
            SpectrumDesc::Blackbody { .. } => vec![],
            SpectrumDesc::Illuminant { scale, .. } => vec![*scale],
        }
    }
}
