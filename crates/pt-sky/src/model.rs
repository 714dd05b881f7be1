//! The sky's and the sun's radiance in a direction (local frame: z up, the sun at `sun_dir`).
//!
//! **Sky** (Hosek and Wilkie 2012, "An analytic model for full spectral sky-dome radiance", ACM
//! TOG 31(4), eq. 9): in a direction at angle `theta` from the zenith and `gamma` from the sun,
//!
//! `L = (1 + A exp(B / (cos theta + 0.01))) (C + D exp(E gamma) + F cos^2 gamma
//!      + G chi(H, gamma) + I sqrt(cos theta)) L_M`,
//! `chi(H, gamma) = (1 + cos^2 gamma) / (1 + H^2 - 2 H cos gamma)^(3/2)`,
//!
//! per channel (RGB, or 11 wavelengths 320-720 nm). The coefficients A..I and the mean
//! radiance `L_M` are interpolated from the tables: linearly in turbidity (levels 1..10) and
//! in ground albedo (levels 0 and 1, per channel), then along the solar elevation `eta` by the
//! quintic Bezier curve of the six control points at `x = (2 eta / pi)^(1/3)` (section 5 of the
//! paper). The tables store the coefficients in the order A B C D E F G I H.
//!
//! **Sun** (Hosek and Wilkie 2013, "Adding a solar-radiance function to the Hosek-Wilkie
//! skylight model", IEEE CG&A 33(3)): a disc of half-angle `alpha` around `sun_dir`. By default
//! (Mitsuba's `complex_sun = false`) its radiance is uniform: the tabulated irradiance of the
//! sun (per turbidity and solar elevation, 2-89 degrees in 3-degree steps, interpolated
//! bilinearly) over the disc's solid angle. With `complex_sun` it is the paper's piecewise
//! polynomial in the viewing elevation (45 segments, breaks at `(pi/2) (k/45)^3`) times the limb
//! darkening, a polynomial in `cos psi = sqrt(1 - sin^2 gamma / sin^2 alpha)` (in RGB mode the
//! two are one table). A disc wider or narrower than the real sun (`sun_aperture`) keeps the
//! real sun's irradiance: its radiance is scaled by the ratio of the solid angles.
//!
//! **Spectral mode** evaluates the 11 channels on either side of a wavelength and interpolates
//! linearly; outside 320-720 nm the radiance is 0. **RGB mode** uses the model's RGB tables
//! (sky) and the sun's irradiance spectrum projected to linear sRGB, scaled as Mitsuba 3.9.1's
//! RGB variants do, so that both modes give Mitsuba's values (checked against it to 1e-4 in
//! this module's tests). Radiance is in W m^-2 sr^-1 nm^-1 (spectral); RGB values are on the
//! scale where a spectral radiance of 1 per nm has luminance 1.
//!
//! Below the horizon (`cos theta < 0`), and everywhere when the sun is below it, the model is 0.

use crate::tables::{self, tables, Tables};
use glam::Vec3;
use pt_math::fastmath;
use pt_math::lanes::lanes;
use std::f64::consts::PI;

/// Mitsuba's `MI_CIE_Y_NORMALIZATION`: 1 / (integral of CIE y-bar over 360-830 nm at 1 nm),
/// the factor by which its RGB variants scale the model's RGB tables.
#[allow(clippy::excessive_precision)] // Mitsuba's digits.
const CIE_Y_NORMALIZATION: f32 = 0.009_367_658_735_689_113;

/// Mitsuba 3.9.1's `SPEC_TO_RGB_SUN_CONV`: with the sRGB projection of the 11-channel
/// irradiance (mean over the channels of CMF times value), the factor that makes its RGB sun
/// agree with the spectral one.
#[allow(clippy::excessive_precision)] // Mitsuba's digits.
const SPEC_TO_RGB_SUN: f32 = 467.069_280_386;

/// Half the real sun's mean angular diameter, 0.5358 degrees (the model's), radians.
pub const SUN_HALF_APERTURE: f64 = PI * (0.5 * 0.5358) / 180.0;

/// 1 - cos(alpha) as Mitsuba 3.9.1 evaluates it, in single precision: for the real sun
/// 1.0908e-5 against the exact 1.0931e-5 (cos alpha rounded to a float near 1, whose spacing is
/// 6e-8). Mitsuba divides the irradiance by the solid angle of this value, and its disc test
/// (`dot >= cos alpha` in floats) admits the directions within this same solid angle, so its
/// sun delivers exactly the tabulated irradiance. pt takes the same value for both: its disc
/// is the cone of 1 - cos = this value (0.1% narrower in angle than the nominal aperture), so
/// the radiance is Mitsuba's and the irradiance the table's.
fn one_minus_cos_f32(alpha: f32) -> f32 {
    1.0 - alpha.cos()
}

/// Parameters of the model (Mitsuba `sunsky`'s, resolved).
#[derive(Clone, Copy, Debug)]
pub struct SkyParams {
    /// Atmospheric turbidity, 1 (very clear) to 10 (hazy).
    pub turbidity: f32,
    /// Unit direction towards the sun's centre, local frame (z up).
    pub sun_dir: Vec3,
    /// Half the sun's angular diameter, radians (Mitsuba `sun_aperture` / 2).
    pub sun_half_aperture: f32,
    /// Limb darkening and the 2013 radiance function (Mitsuba `complex_sun`).
    pub complex_sun: bool,
    /// Factor on the sun's radiance.
    pub sun_scale: f32,
    /// Factor on the sky's radiance.
    pub sky_scale: f32,
}

/// Per-channel sky coefficients A..I (file order) and mean radiance, coefficient by
/// coefficient (structure of arrays) in `L` lanes, so that one lookup evaluates every channel
/// in SIMD lanes ([`eval_sky`]); lanes beyond the channels hold zeros (radiance 0).
#[derive(Clone, Debug)]
struct SkyChannels<const L: usize> {
    /// `params[p][c]`: coefficient p (file order) of channel c.
    params: [[f32; L]; tables::SKY_PARAMS],
    /// Mean radiance of channel c.
    radiance: [f32; L],
}

/// Lanes of the RGB sky's channels (3, padded to a 4-wide vector).
const RGB_LANES: usize = 4;
/// Lanes of the spectral sky's channels (11, padded to three 4-wide vectors).
const SPECTRAL_LANES: usize = 12;

#[derive(Clone, Debug)]
enum Sun<const C: usize> {
    /// Uniform disc radiance per channel (scales included).
    Disc([f32; C]),
    /// The 2013 function, interpolated in turbidity: per segment, channel and elevation power
    /// (RGB: and cos psi power); spectral mode adds the limb-darkening coefficients.
    Limb {
        poly: Box<[f32]>,
        limb: Option<Box<[[f32; tables::SUN_LD_PARAMS]; C]>>,
        factor: f32,
    },
}

/// The sky's and the sun's data per channel: RGB, or the model's 11 wavelengths (boxed: four
/// times the size).
#[derive(Clone, Debug)]
enum Channels {
    Rgb(SkyChannels<RGB_LANES>, Sun<3>),
    Spectral(Box<(SkyChannels<SPECTRAL_LANES>, Sun<{ tables::WAVELENGTHS }>)>),
}

/// The sun and sky model for one set of parameters, in RGB or spectral mode.
#[derive(Clone, Debug)]
pub struct SkyModel {
    sun_dir: Vec3,
    /// 1 - cos of the disc's half-angle (see [`one_minus_cos_f32`]).
    disc_one_minus_cos: f32,
    /// sin^2 of the disc's half-angle, for the disc test.
    disc_sin2: f32,
    sin_aperture: f32,
    sky_scale: f32,
    sun_up: bool,
    channels: Channels,
}

/// Linear interpolation position in a table of `levels` levels: (lower index, fraction).
fn level(x: f64, levels: usize) -> (usize, f64) {
    let x = x.clamp(0.0, (levels - 1) as f64);
    let i = (x.floor() as usize).min(levels - 2);
    (i, x - i as f64)
}

/// Sky coefficients of `C` channels in `L` >= `C` lanes: turbidity, then albedo, then Bezier
/// over the elevation.
fn sky_channels<const C: usize, const L: usize>(
    params: &[f32],
    radiance: &[f32],
    turbidity: f32,
    albedo: [f32; C],
    eta: f64,
) -> SkyChannels<L> {
    use tables::{ALBEDO_LEVELS, SKY_CONTROL_POINTS as K, SKY_PARAMS as P};
    let (t, ft) = level(turbidity as f64 - 1.0, tables::TURBIDITY_LEVELS);
    // Bernstein weights of the quintic at x = (2 eta / pi)^(1/3), x < 1 as Mitsuba keeps it.
    let x = (2.0 * eta / PI)
        .max(0.0)
        .cbrt()
        .min(1.0 - f32::EPSILON as f64 / 2.0);
    let binom = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    let bern: [f64; K] =
        std::array::from_fn(|k| binom[k] * x.powi(k as i32) * (1.0 - x).powi((K - 1 - k) as i32));
    // Value at (turbidity, albedo level, control point, channel, coefficient) of a table with
    // `n` coefficients per channel.
    let at = |table: &[f32], n: usize, ti: usize, a: usize, k: usize, c: usize, p: usize| {
        table[(((ti * ALBEDO_LEVELS + a) * K + k) * C + c) * n + p] as f64
    };
    let interp = |table: &[f32], n: usize, c: usize, p: usize| -> f32 {
        let alb = albedo[c] as f64;
        let mut sum = 0.0;
        for (k, b) in bern.iter().enumerate() {
            let v =
                |a| at(table, n, t, a, k, c, p) * (1.0 - ft) + at(table, n, t + 1, a, k, c, p) * ft;
            sum += b * (v(0) * (1.0 - alb) + v(1) * alb);
        }
        sum as f32
    };
    // Lanes from C on (padding) hold zeros.
    SkyChannels {
        params: std::array::from_fn(|p| {
            std::array::from_fn(|c| if c < C { interp(params, P, c, p) } else { 0.0 })
        }),
        radiance: std::array::from_fn(|c| {
            if c < C {
                interp(radiance, 1, c, 0)
            } else {
                0.0
            }
        }),
    }
}

/// Irradiance of the sun's disc per wavelength channel, W m^-2 nm^-1, interpolated in
/// turbidity and solar elevation `eta` (radians).
fn sun_irradiance(t: &Tables, turbidity: f32, eta: f64) -> [f32; tables::WAVELENGTHS] {
    use tables::{IRRADIANCE_ELEVATIONS as E, WAVELENGTHS as W};
    let (ti, ft) = level(turbidity as f64 - 1.0, tables::TURBIDITY_LEVELS);
    let (ei, fe) = level((eta.to_degrees() - 2.0) / 3.0, E);
    let v = |ti: usize, ei: usize, c: usize| t.sun_irradiance[(ti * E + ei) * W + c] as f64;
    std::array::from_fn(|c| {
        let a = v(ti, ei, c) * (1.0 - ft) + v(ti + 1, ei, c) * ft;
        let b = v(ti, ei + 1, c) * (1.0 - ft) + v(ti + 1, ei + 1, c) * ft;
        (a * (1.0 - fe) + b * fe) as f32
    })
}

/// A table interpolated in turbidity (its first index).
fn turbidity_slice(table: &[f32], turbidity: f32) -> Box<[f32]> {
    let n = table.len() / tables::TURBIDITY_LEVELS;
    let (t, f) = level(turbidity as f64 - 1.0, tables::TURBIDITY_LEVELS);
    (0..n)
        .map(|i| (table[t * n + i] as f64 * (1.0 - f) + table[(t + 1) * n + i] as f64 * f) as f32)
        .collect()
}

/// Wavelength of channel `c`, nm.
fn channel_wavelength(c: usize) -> f32 {
    tables::WAVELENGTH_MIN + tables::WAVELENGTH_STEP * c as f32
}

impl SkyModel {
    fn common(p: &SkyParams) -> (Vec3, f64, f32) {
        let sun_dir = p.sun_dir.normalize();
        let eta = std::f64::consts::FRAC_PI_2 - (sun_dir.z as f64).clamp(-1.0, 1.0).acos();
        // Keeps the real sun's irradiance for another aperture (both in Mitsuba's precision).
        let area_ratio =
            one_minus_cos_f32(SUN_HALF_APERTURE as f32) / one_minus_cos_f32(p.sun_half_aperture);
        (sun_dir, eta, area_ratio)
    }

    fn assemble(p: &SkyParams, sun_dir: Vec3, channels: Channels) -> SkyModel {
        let omc = one_minus_cos_f32(p.sun_half_aperture);
        SkyModel {
            sun_dir,
            disc_one_minus_cos: omc,
            disc_sin2: omc * (2.0 - omc),
            sin_aperture: p.sun_half_aperture.sin(),
            sky_scale: p.sky_scale,
            sun_up: sun_dir.z >= 0.0,
            channels,
        }
    }

    /// The model in RGB mode; `albedo` is the ground's linear sRGB reflectance, each in [0, 1].
    pub fn rgb(p: &SkyParams, albedo: [f32; 3]) -> SkyModel {
        let t = tables();
        let (sun_dir, eta, area_ratio) = Self::common(p);
        let sky = sky_channels(&t.sky_params_rgb, &t.sky_rad_rgb, p.turbidity, albedo, eta);
        let factor = p.sun_scale * area_ratio * SPEC_TO_RGB_SUN * CIE_Y_NORMALIZATION;
        let sun = if p.complex_sun {
            Sun::Limb {
                poly: turbidity_slice(&t.sun_rad_rgb, p.turbidity),
                limb: None,
                factor,
            }
        } else {
            // Mitsuba's spectrum_to_srgb of the 11 channels: the mean of CMF x value, then
            // XYZ to linear sRGB.
            let e = sun_irradiance(t, p.turbidity, eta);
            let mut xyz = [0.0f32; 3];
            for (c, v) in e.iter().enumerate() {
                let cmf = pt_spectrum::cie::cmf(channel_wavelength(c));
                for k in 0..3 {
                    xyz[k] += cmf[k] * v / tables::WAVELENGTHS as f32;
                }
            }
            let rgb = pt_spectrum::xyz_to_srgb(xyz);
            let solid = 2.0 * std::f32::consts::PI * one_minus_cos_f32(SUN_HALF_APERTURE as f32);
            Sun::Disc(rgb.map(|v| v / solid * factor))
        };
        Self::assemble(p, sun_dir, Channels::Rgb(sky, sun))
    }

    /// The model in spectral mode; `albedo` is the ground's reflectance at the model's 11
    /// wavelengths (320, 360, ..., 720 nm), each in [0, 1].
    pub fn spectral(p: &SkyParams, albedo: [f32; tables::WAVELENGTHS]) -> SkyModel {
        let t = tables();
        let (sun_dir, eta, area_ratio) = Self::common(p);
        let sky = sky_channels(
            &t.sky_params_spec,
            &t.sky_rad_spec,
            p.turbidity,
            albedo,
            eta,
        );
        let factor = p.sun_scale * area_ratio;
        let sun = if p.complex_sun {
            let mut ld = [[0.0; tables::SUN_LD_PARAMS]; tables::WAVELENGTHS];
            for (c, row) in ld.iter_mut().enumerate() {
                row.copy_from_slice(
                    &t.sun_ld_spec[c * tables::SUN_LD_PARAMS..(c + 1) * tables::SUN_LD_PARAMS],
                );
            }
            Sun::Limb {
                poly: turbidity_slice(&t.sun_rad_spec, p.turbidity),
                limb: Some(Box::new(ld)),
                factor,
            }
        } else {
            let solid = 2.0 * std::f32::consts::PI * one_minus_cos_f32(SUN_HALF_APERTURE as f32);
            let e = sun_irradiance(t, p.turbidity, eta);
            Sun::Disc(e.map(|v| v / solid * factor))
        };
        Self::assemble(p, sun_dir, Channels::Spectral(Box::new((sky, sun))))
    }

    /// Unit direction towards the sun's centre, local frame.
    pub fn sun_dir(&self) -> Vec3 {
        self.sun_dir
    }

    /// 1 - cos of the half-angle of the sun's disc: the cone [`SkyModel::in_sun`] accepts.
    pub fn sun_one_minus_cos(&self) -> f32 {
        self.disc_one_minus_cos
    }

    /// Whether the model is in spectral mode.
    pub fn is_spectral(&self) -> bool {
        matches!(self.channels, Channels::Spectral(..))
    }

    /// Whether `d` (local; unit up to rounding) lies in the sun's disc. Tested as
    /// sin^2(angle) = |d x s|^2 / |d|^2 < sin^2(half-angle), which, unlike `d . s >= cos`,
    /// neither cancels near 1 nor depends on how well `d` is normalised (a float `d . s` near 1
    /// is uncertain by 1e-7, 1% of the real sun's 1 - cos).
    #[inline]
    pub fn in_sun(&self, d: Vec3) -> bool {
        self.sun_dir.dot(d) > 0.0
            && self.sun_dir.cross(d).length_squared() < self.disc_sin2 * d.length_squared()
    }

    /// (cos theta, gamma) of a direction, or `None` where the model is 0.
    #[inline]
    fn angles(&self, d: Vec3) -> Option<(f32, f32)> {
        if !(d.z >= 0.0) || !self.sun_up {
            return None;
        }
        Some((d.z, unit_angle(self.sun_dir, d)))
    }

    /// The sky's RGB radiance in direction `d` (unit, local), sun excluded.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sky_rgb(&self, d: Vec3) -> [f32; 3] {
        let (Channels::Rgb(sky, _), Some((ct, g))) = (&self.channels, self.angles(d)) else {
            return [0.0; 3];
        };
        let s = self.sky_scale * CIE_Y_NORMALIZATION;
        let v = eval_sky(&SkyAngles::new(ct, g, self.sun_dir.dot(d)), sky);
        std::array::from_fn(|c| s * v[c])
    }

    /// The sun's RGB radiance in direction `d` (unit, local): 0 outside its disc.
    #[inline]
    pub fn sun_rgb(&self, d: Vec3) -> [f32; 3] {
        // The disc test first: it is cheaper than the angles, and most directions miss.
        if !self.in_sun(d) {
            return [0.0; 3];
        }
        let (Channels::Rgb(_, sun), Some((ct, g))) = (&self.channels, self.angles(d)) else {
            return [0.0; 3];
        };
        match sun {
            Sun::Disc(v) => *v,
            Sun::Limb { poly, factor, .. } => {
                use tables::{SUN_CONTROL_POINTS as K, SUN_LD_PARAMS as J};
                let (pos, x) = sun_segment(ct);
                let cos_psi = self.cos_psi(g) as f64;
                // In double precision: the coefficients alternate in sign and reach 1e3, so a
                // single-precision sum loses about 1e-4 of the result near the limb.
                std::array::from_fn(|c| {
                    let base = (pos * 3 + c) * K * J;
                    let mut sum = 0.0f64;
                    let mut xk = 1.0f64;
                    for k in 0..K {
                        let mut cj = 1.0f64;
                        for j in 0..J {
                            sum += xk * cj * poly[base + k * J + j] as f64;
                            cj *= cos_psi;
                        }
                        xk *= x as f64;
                    }
                    sum as f32 * factor
                })
            }
        }
    }

    /// The sky's spectral radiance at four wavelengths `lambda` (nm), sun excluded.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sky_spectral(&self, d: Vec3, lambda: [f32; 4]) -> [f32; 4] {
        let (Channels::Spectral(data), Some((ct, g))) = (&self.channels, self.angles(d)) else {
            return [0.0; 4];
        };
        let sky = &data.0;
        // All 11 channels at once (three vector steps), rather than the up to eight that four
        // wavelengths fall between, one by one.
        let v = eval_sky(&SkyAngles::new(ct, g, self.sun_dir.dot(d)), sky);
        lanes(|k| lerp_channels(lambda[k], &mut |c| v[c]) * self.sky_scale)
    }

    /// The sun's spectral radiance at four wavelengths `lambda` (nm): 0 outside its disc.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sun_spectral(&self, d: Vec3, lambda: [f32; 4]) -> [f32; 4] {
        // The disc test first: it is cheaper than the angles, and most directions miss.
        if !self.in_sun(d) {
            return [0.0; 4];
        }
        let (Channels::Spectral(data), Some((ct, g))) = (&self.channels, self.angles(d)) else {
            return [0.0; 4];
        };
        let sun = &data.1;
        match sun {
            Sun::Disc(v) => lanes(|k| lerp_channels(lambda[k], &mut |c| v[c])),
            Sun::Limb { poly, limb, factor } => {
                use tables::SUN_CONTROL_POINTS as K;
                let (pos, x) = sun_segment(ct);
                let cos_psi = self.cos_psi(g);
                let radiance = |c: usize| {
                    let base = (pos * tables::WAVELENGTHS + c) * K;
                    let mut sum = 0.0f64;
                    let mut xk = 1.0f64;
                    for k in 0..K {
                        sum += xk * poly[base + k] as f64;
                        xk *= x as f64;
                    }
                    sum as f32
                };
                let ld = limb.as_deref().expect("spectral limb darkening");
                lanes(|k| {
                    let l = lambda[k];
                    // Mitsuba interpolates the radiance and the limb-darkening coefficients
                    // across the channels separately, then multiplies.
                    let r = lerp_channels(l, &mut |c| radiance(c));
                    let mut darkening = 0.0f32;
                    let mut cj = 1.0f32;
                    for j in 0..tables::SUN_LD_PARAMS {
                        darkening += cj * lerp_channels(l, &mut |c| ld[c][j]);
                        cj *= cos_psi;
                    }
                    r * darkening * factor
                })
            }
        }
    }

    /// cos psi: the cosine of the angle at the sun's centre between the viewer and the point
    /// of the disc seen at angle `gamma` from it (Hosek and Wilkie 2013, limb darkening).
    #[inline]
    fn cos_psi(&self, gamma: f32) -> f32 {
        let s = gamma.sin() / self.sin_aperture;
        (1.0 - s * s).max(0.0).sqrt()
    }
}

/// The terms of Hosek and Wilkie's sky function (2012, eq. 9) that depend on the direction
/// alone, shared by every channel of one lookup (the cosine, the division and the square root
/// ran once per channel, up to eight times per spectral lookup).
#[derive(Clone, Copy)]
struct SkyAngles {
    /// gamma, the angle to the sun (radians).
    gamma: f32,
    /// cos gamma.
    cos_gamma: f32,
    /// 1 + cos^2 gamma, the numerator of the circumsolar term chi.
    one_plus_cos2: f32,
    /// cos^2 gamma.
    cos2: f32,
    /// 1 / (cos theta + 0.01), the exponent's scale of the horizon term.
    inv_cos_theta: f32,
    /// sqrt(cos theta) (theta the zenith angle; 0 below the horizon).
    sqrt_cos_theta: f32,
}

impl SkyAngles {
    /// The terms for a direction at zenith-angle cosine `cos_theta` and angle `gamma` from the
    /// sun; `cos_gamma` is gamma's cosine, which callers have as the dot product of the unit
    /// directions (no cosine of the angle computed again).
    #[inline]
    fn new(cos_theta: f32, gamma: f32, cos_gamma: f32) -> Self {
        let cos_gamma = cos_gamma.clamp(-1.0, 1.0);
        let cos2 = cos_gamma * cos_gamma;
        SkyAngles {
            gamma,
            cos_gamma,
            one_plus_cos2: 1.0 + cos2,
            cos2,
            inv_cos_theta: 1.0 / (cos_theta + 0.01),
            sqrt_cos_theta: cos_theta.max(0.0).sqrt(),
        }
    }
}

/// The sky's radiance of every channel of `sky` (Hosek and Wilkie 2012, eq. 9; coefficients in
/// the file's order A B C D E F G I H), for the direction terms `a`: one formula over the lanes,
/// which the compiler vectorises (the exponentials included, [`fastmath::exp`]).
#[inline(always)]
fn eval_sky<const L: usize>(a: &SkyAngles, sky: &SkyChannels<L>) -> [f32; L] {
    let p = &sky.params;
    lanes(
        #[cfg_attr(not(debug_assertions), inline(always))]
        |c| {
            let h = p[8][c];
            // chi = (1 + cos^2 gamma) / (1 + H^2 - 2 H cos gamma)^(3/2); x^(3/2) as x sqrt(x).
            let base = 1.0 + h * h - 2.0 * h * a.cos_gamma;
            let chi = a.one_plus_cos2 / (base * base.sqrt());
            let c1 = 1.0 + p[0][c] * fastmath::exp(p[1][c] * a.inv_cos_theta);
            let c2 = p[2][c]
                + p[3][c] * fastmath::exp(p[4][c] * a.gamma)
                + p[5][c] * a.cos2
                + p[6][c] * chi
                + p[7][c] * a.sqrt_cos_theta;
            c1 * c2 * sky.radiance[c]
        },
    )
}

/// Segment of the solar radiance function for a direction with cos(zenith angle) `cos_theta`,
/// and the elevation's offset from the segment's start.
#[inline]
fn sun_segment(cos_theta: f32) -> (usize, f32) {
    use std::f32::consts::FRAC_PI_2;
    let elevation = FRAC_PI_2 - cos_theta.clamp(-1.0, 1.0).acos();
    let n = tables::SUN_SEGMENTS;
    let pos =
        (((2.0 * elevation / std::f32::consts::PI).max(0.0).cbrt() * n as f32) as usize).min(n - 1);
    let start = FRAC_PI_2 * (pos as f32 / n as f32).powi(3);
    (pos, elevation - start)
}

/// A value at wavelength `l` (nm) interpolated linearly between the model's channels; 0
/// outside 320-720 nm.
#[inline]
fn lerp_channels(l: f32, value: &mut impl FnMut(usize) -> f32) -> f32 {
    let x = (l - tables::WAVELENGTH_MIN) / tables::WAVELENGTH_STEP;
    let last = (tables::WAVELENGTHS - 1) as f32;
    if !(0.0..=last).contains(&x) {
        return 0.0;
    }
    let lo = (x as usize).min(tables::WAVELENGTHS - 1);
    let f = x - lo as f32;
    let a = value(lo);
    if f == 0.0 {
        return a;
    }
    a * (1.0 - f) + value(lo + 1) * f
}

/// The angle between two unit vectors, accurate for small and large angles.
#[inline]
fn unit_angle(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) >= 0.0 {
        2.0 * (0.5 * (a - b).length()).min(1.0).asin()
    } else {
        std::f32::consts::PI - 2.0 * (0.5 * (a + b).length()).min(1.0).asin()
    }
}

#[cfg(test)]
mod tests;
