//! The model's coefficient tables, read once from `data/hosek_wilkie.bin` (written by
//! `references/make_sunsky_tables.py` from the files Mitsuba 3.9.1 ships; the tables are Hosek
//! and Wilkie's published data, BSD-3, licence in `data/LICENSE-hosek-wilkie`).
//!
//! Index order of every table: turbidity level (1..=10), then albedo level (0, 1) where there
//! is one, then the position along the solar elevation (control point or segment), then the
//! channel, then the coefficient.

use std::sync::OnceLock;

/// Turbidity levels 1, 2, ..., 10.
pub const TURBIDITY_LEVELS: usize = 10;
/// Albedo levels 0 and 1.
pub const ALBEDO_LEVELS: usize = 2;
/// Control points of the quintic Bezier curve over the solar elevation (sky model).
pub const SKY_CONTROL_POINTS: usize = 6;
/// Coefficients A..I of the sky's radiance distribution (Hosek and Wilkie 2012, eq. 9).
pub const SKY_PARAMS: usize = 9;
/// Spectral channels of the model: 320, 360, ..., 720 nm.
pub const WAVELENGTHS: usize = 11;
/// First channel's wavelength, nm.
pub const WAVELENGTH_MIN: f32 = 320.0;
/// Spacing of the channels, nm.
pub const WAVELENGTH_STEP: f32 = 40.0;
/// Segments of the piecewise polynomial over the viewing elevation (solar radiance function).
pub const SUN_SEGMENTS: usize = 45;
/// Polynomial degree + 1 of each segment (in the elevation).
pub const SUN_CONTROL_POINTS: usize = 4;
/// Limb-darkening polynomial degree + 1 (in cos psi).
pub const SUN_LD_PARAMS: usize = 6;
/// Solar elevations of the irradiance table: 2, 5, ..., 89 degrees.
pub const IRRADIANCE_ELEVATIONS: usize = 30;

/// All tables, f32 (the precision Mitsuba evaluates them in).
pub struct Tables {
    /// [turbidity][albedo][control point][rgb][A..I].
    pub sky_params_rgb: Vec<f32>,
    /// [turbidity][albedo][control point][rgb]: the mean radiance L_M.
    pub sky_rad_rgb: Vec<f32>,
    /// [turbidity][albedo][control point][wavelength][A..I].
    pub sky_params_spec: Vec<f32>,
    /// [turbidity][albedo][control point][wavelength].
    pub sky_rad_spec: Vec<f32>,
    /// [turbidity][segment][rgb][elevation power][cos psi power]: solar radiance with the limb
    /// darkening folded in (RGB).
    pub sun_rad_rgb: Vec<f32>,
    /// [turbidity][segment][wavelength][elevation power]: solar radiance at the disc's centre.
    pub sun_rad_spec: Vec<f32>,
    /// [wavelength][cos psi power]: limb darkening.
    pub sun_ld_spec: Vec<f32>,
    /// [turbidity][solar elevation][wavelength]: irradiance of the sun's disc, W m^-2 nm^-1.
    pub sun_irradiance: Vec<f32>,
}

/// The shapes, in the file's order.
const SHAPES: [usize; 8] = [
    TURBIDITY_LEVELS * ALBEDO_LEVELS * SKY_CONTROL_POINTS * 3 * SKY_PARAMS,
    TURBIDITY_LEVELS * ALBEDO_LEVELS * SKY_CONTROL_POINTS * 3,
    TURBIDITY_LEVELS * ALBEDO_LEVELS * SKY_CONTROL_POINTS * WAVELENGTHS * SKY_PARAMS,
    TURBIDITY_LEVELS * ALBEDO_LEVELS * SKY_CONTROL_POINTS * WAVELENGTHS,
    TURBIDITY_LEVELS * SUN_SEGMENTS * 3 * SUN_CONTROL_POINTS * SUN_LD_PARAMS,
    TURBIDITY_LEVELS * SUN_SEGMENTS * WAVELENGTHS * SUN_CONTROL_POINTS,
    WAVELENGTHS * SUN_LD_PARAMS,
    TURBIDITY_LEVELS * IRRADIANCE_ELEVATIONS * WAVELENGTHS,
];

static FILE: &[u8] = include_bytes!("../data/hosek_wilkie.bin");

/// The tables (decoded on first use).
pub fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| decode(FILE).expect("data/hosek_wilkie.bin is part of the crate"))
}

fn decode(bytes: &[u8]) -> Result<Tables, String> {
    let mut rest = bytes
        .strip_prefix(b"PTSKY1\0\0")
        .ok_or("not a pt-sky table file")?;
    let mut read = |count: usize| -> Result<Vec<f32>, String> {
        let (head, tail) = rest.split_at_checked(4).ok_or("truncated")?;
        let n = u32::from_le_bytes(head.try_into().unwrap()) as usize;
        if n != count {
            return Err(format!("a table has {n} values, expected {count}"));
        }
        let (data, tail) = tail.split_at_checked(4 * n).ok_or("truncated")?;
        rest = tail;
        Ok(data
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect())
    };
    let t = Tables {
        sky_params_rgb: read(SHAPES[0])?,
        sky_rad_rgb: read(SHAPES[1])?,
        sky_params_spec: read(SHAPES[2])?,
        sky_rad_spec: read(SHAPES[3])?,
        sun_rad_rgb: read(SHAPES[4])?,
        sun_rad_spec: read(SHAPES[5])?,
        sun_ld_spec: read(SHAPES[6])?,
        sun_irradiance: read(SHAPES[7])?,
    };
    if !rest.is_empty() {
        return Err("trailing bytes".into());
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_file_decodes_with_the_expected_shapes() {
        let t = tables();
        assert_eq!(t.sun_irradiance.len(), SHAPES[7]);
        assert!(t.sky_rad_spec.iter().all(|v| v.is_finite()));
        // First values of Mitsuba's tables (printed by the generator's reader).
        assert_eq!(t.sky_params_rgb[0], -1.099459);
        assert_eq!(t.sun_ld_spec[0], 0.087657);
        assert!(decode(&FILE[..100]).is_err());
    }
}
