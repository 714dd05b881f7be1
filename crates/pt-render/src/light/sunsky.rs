//! Mitsuba's `sunsky`: the Hosek-Wilkie sky and the sun's disc (model: crate pt-sky), as an
//! infinite light.
//!
//! Sampling (our own; Mitsuba fits truncated Gaussian mixtures, which only changes the noise):
//! one sample picks the sky with probability `w_sky` = its share of the luminance arriving from
//! the two (the sun's: its radiance at the centre times its solid angle), else the sun.
//! - The sky: a piecewise-constant density over `(phi / 2 pi, cos theta)` of the upper
//!   hemisphere (equal solid angle per unit area, `dw = 2 pi du dv`), each cell's weight the
//!   largest sky luminance at its corners and centre plus 1% of the mean, so the density is
//!   positive wherever the sky is (the model is positive over the whole upper hemisphere).
//! - The sun: uniform over its cone (its radiance varies only by the limb darkening).
//!
//! The pdf of a direction is the mixture `w_sky p_sky + (1 - w_sky) p_sun`, which is what
//! MIS with BSDF sampling weighs against.

use pt_math::warp::{square_to_uniform_cone, uniform_cone_pdf};
use pt_math::{fastmath, Distribution2D, Frame, Mat3, Vec2, Vec3};
use pt_sky::SkyModel;
use pt_spectrum::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::PI;

/// Resolution of the sky's sampling table: azimuth x cos(zenith angle).
const TABLE_PHI: usize = 128;
const TABLE_COS: usize = 64;

/// The sun and sky as a light.
#[derive(Clone, Debug)]
pub struct SunSky {
    /// The model in the scene's colour mode.
    model: SkyModel,
    /// Sky-to-world rotation and its inverse.
    to_world: Mat3,
    to_local: Mat3,
    /// Frame about the direction towards the sun's centre, world.
    sun_frame: Frame,
    /// 1 - cos of the half-angle of the sun's disc.
    one_minus_cos: f32,
    /// Density over (phi / 2 pi, cos theta) of the sky's directions.
    distr: Distribution2D,
    /// Probability of sampling the sky (else the sun).
    w_sky: f32,
    /// Luminance arriving from the sky and the sun together, integrated over solid angle
    /// (W m^-2 in luminance units): the power per unit area of a disk facing the light.
    luminance_integral: f32,
}

/// The local direction at `(phi / 2 pi, cos theta)` of the sky table (upper hemisphere).
#[inline]
fn table_dir(uv: Vec2) -> Vec3 {
    let phi = 2.0 * PI * uv.x;
    let z = uv.y.clamp(0.0, 1.0);
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// Luminance of a linear sRGB colour.
fn luminance(c: [f32; 3]) -> f32 {
    crate::texture::luminance(c)
}

/// The sun's luminance integrated over its disc (half-angle with 1 - cos = `one_minus_cos`):
/// the midpoint rule on 8 rings of equal solid angle x 8 azimuths (the limb-darkened disc
/// falls towards its rim; the uniform one is exact). For light selection only.
fn disc_integral(rgb: &SkyModel, one_minus_cos: f32) -> f32 {
    let frame = Frame::from_normal(rgb.sun_dir());
    let (rings, azimuths) = (8, 8);
    let mut sum = 0.0f32;
    for i in 0..rings {
        let omc = one_minus_cos * (i as f32 + 0.5) / rings as f32;
        let sin = (omc * (2.0 - omc)).sqrt();
        for j in 0..azimuths {
            let phi = 2.0 * PI * (j as f32 + 0.5) / azimuths as f32;
            let d = frame.to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), 1.0 - omc));
            sum += luminance(rgb.sun_rgb(d)).max(0.0);
        }
    }
    sum / (rings * azimuths) as f32 * 2.0 * PI * one_minus_cos
}

impl SunSky {
    /// The light from the model in the scene's colour mode (`model`), its RGB counterpart
    /// (`rgb`, for the sampling densities: the same support, luminance close to the spectral
    /// one) and the sky-to-world rotation. `None` when the sun is below the horizon and so the
    /// model is dark everywhere.
    pub fn new(model: SkyModel, rgb: &SkyModel, to_world: Mat3) -> Option<Self> {
        let sun_local = model.sun_dir();
        if sun_local.z < 0.0 {
            return None;
        }
        // Sky table: corner values on a (TABLE_PHI + 1) x (TABLE_COS + 1) grid, centres.
        let dir = |u: f32, v: f32| table_dir(Vec2::new(u, v));
        let sky = |d: Vec3| luminance(rgb.sky_rgb(d)).max(0.0);
        let corners: Vec<f32> = (0..=TABLE_COS)
            .flat_map(|j| {
                (0..=TABLE_PHI)
                    .map(move |i| (i as f32 / TABLE_PHI as f32, j as f32 / TABLE_COS as f32))
            })
            .map(|(u, v)| sky(dir(u, v)))
            .collect();
        let mut weights = vec![0.0f32; TABLE_PHI * TABLE_COS];
        let mut sum = 0.0f64;
        for j in 0..TABLE_COS {
            for i in 0..TABLE_PHI {
                let c = |di: usize, dj: usize| corners[(j + dj) * (TABLE_PHI + 1) + i + di];
                let centre = sky(dir(
                    (i as f32 + 0.5) / TABLE_PHI as f32,
                    (j as f32 + 0.5) / TABLE_COS as f32,
                ));
                sum += centre as f64;
                weights[j * TABLE_PHI + i] =
                    c(0, 0).max(c(1, 0)).max(c(0, 1)).max(c(1, 1)).max(centre);
            }
        }
        let cells = (TABLE_PHI * TABLE_COS) as f64;
        // The sky's luminance over the hemisphere: the midpoint rule on the table (2 pi per
        // unit area of the table).
        let sky_integral = (2.0 * std::f64::consts::PI * sum / cells) as f32;
        let floor = 0.01 * (sum / cells) as f32;
        for w in &mut weights {
            *w += floor;
        }
        let distr = Distribution2D::new(&weights, TABLE_PHI, TABLE_COS)?;

        // The disc the model tests, so that every sun sample lands in it.
        let one_minus_cos = model.sun_one_minus_cos();
        let sun_integral = disc_integral(rgb, one_minus_cos);
        let total = sky_integral + sun_integral;
        if !(total > 0.0) {
            return None;
        }
        Some(SunSky {
            model,
            to_world,
            to_local: to_world.transpose(),
            sun_frame: Frame::from_normal((to_world * sun_local).normalize()),
            one_minus_cos,
            distr,
            w_sky: sky_integral / total,
            luminance_integral: total,
        })
    }

    /// Luminance arriving from the whole sky and sun per unit area facing them (for light
    /// selection: times the scene's cross-section).
    pub fn luminance_integral(&self) -> f32 {
        self.luminance_integral
    }

    /// Radiance arriving from world direction `dir` (unit, pointing away from the scene).
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn radiance(&self, dir: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        let d = self.to_local * dir;
        if self.model.is_spectral() {
            let l = lambda.lambda().to_array();
            let sky = self.model.sky_spectral(d, l);
            let sun = self.model.sun_spectral(d, l);
            SampledSpectrum(glam::Vec4::from_array(sky) + glam::Vec4::from_array(sun))
        } else {
            let sky = self.model.sky_rgb(d);
            let sun = self.model.sun_rgb(d);
            SampledSpectrum::from_rgb([sky[0] + sun[0], sky[1] + sun[1], sky[2] + sun[2]])
        }
    }

    /// Solid-angle pdf with which [`SunSky::sample`] draws world direction `dir`.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let d = self.to_local * dir;
        if !(d.z >= 0.0) {
            return 0.0;
        }
        let sky = self.sky_pdf(d);
        let sun = if self.model.in_sun(d) {
            uniform_cone_pdf(self.one_minus_cos)
        } else {
            0.0
        };
        self.w_sky * sky + (1.0 - self.w_sky) * sun
    }

    /// The sky table's solid-angle density at local direction `d` (upper hemisphere).
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sky_pdf(&self, d: Vec3) -> f32 {
        let mut u = fastmath::atan2(d.y, d.x) * (0.5 / PI);
        if u < 0.0 {
            u += 1.0;
        }
        self.distr.pdf(Vec2::new(u, d.z.clamp(0.0, 1.0))) / (2.0 * PI)
    }

    /// Samples a direction towards the sky or the sun: (world direction, radiance, pdf).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sample(
        &self,
        u: Vec2,
        lambda: &SampledWavelengths,
    ) -> Option<(Vec3, SampledSpectrum, f32)> {
        let dir = if u.x < self.w_sky {
            let (uv, _) = self.distr.sample(Vec2::new(u.x / self.w_sky, u.y));
            self.to_world * table_dir(uv)
        } else {
            let v = ((u.x - self.w_sky) / (1.0 - self.w_sky)).min(1.0 - f32::EPSILON / 2.0);
            self.sun_frame.to_world(square_to_uniform_cone(
                Vec2::new(v, u.y),
                self.one_minus_cos,
            ))
        }
        .normalize();
        let pdf = self.pdf(dir);
        (pdf > 0.0).then(|| (dir, self.radiance(dir, lambda), pdf))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_sky::SkyParams;

    /// A tilted sky (to_world a rotation about x and y) with a low sun and the limb-darkened
    /// disc, in RGB mode.
    fn light(complex_sun: bool, turbidity: f32) -> SunSky {
        let p = SkyParams {
            turbidity,
            sun_dir: Vec3::new(0.3, -0.5, 0.4).normalize(),
            sun_half_aperture: (0.5f32 * 0.5358).to_radians(),
            complex_sun,
            sun_scale: 1.0,
            sky_scale: 1.0,
        };
        let rgb = SkyModel::rgb(&p, [0.2, 0.3, 0.4]);
        let to_world = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(-1.2);
        SunSky::new(rgb.clone(), &rgb, to_world).unwrap()
    }

    /// Uniform numbers from PCG-64 (pairs of consecutive outputs of a plain LCG are
    /// correlated enough to bias the 0.01%-level estimates below).
    fn rng(seed: u64) -> impl FnMut() -> f32 {
        use rand::{RngExt, SeedableRng};
        let mut r = rand_pcg::Pcg64::seed_from_u64(seed);
        move || r.random::<f32>()
    }

    fn lum(s: SampledSpectrum) -> f32 {
        s.luminance_rgb()
    }

    /// The sky's density integrates to 1 over the upper hemisphere (midpoint rule on a grid
    /// finer than the table: exact for a piecewise-constant density up to the cells the grid
    /// splits, 1e-3), and the directions `sample` draws carry `pdf`'s value.
    #[test]
    fn densities_are_normalised_and_consistent() {
        let l = light(true, 5.0);
        let (n_phi, n_z) = (1024, 512);
        let mut sum = 0.0f64;
        for j in 0..n_z {
            for i in 0..n_phi {
                let phi = 2.0 * PI * (i as f32 + 0.5) / n_phi as f32;
                let z = (j as f32 + 0.5) / n_z as f32;
                let s = (1.0 - z * z).sqrt();
                sum += l.sky_pdf(Vec3::new(s * phi.cos(), s * phi.sin(), z)) as f64;
            }
        }
        let integral = sum * 2.0 * std::f64::consts::PI / (n_phi * n_z) as f64;
        assert!(
            (integral - 1.0).abs() < 1e-3,
            "sky density integrates to {integral}"
        );
        let lambda = SampledWavelengths::sample_visible(0.3);
        let mut r = rng(7);
        let mut sun_hits = 0;
        for _ in 0..20_000 {
            let (d, radiance, pdf) = l.sample(Vec2::new(r(), r()), &lambda).unwrap();
            let again = l.pdf(d);
            assert!((pdf - again).abs() <= 1e-4 * again, "{pdf} vs {again}");
            assert!(radiance.is_finite());
            if l.model.in_sun(l.to_local * d) {
                sun_hits += 1;
            }
        }
        // The sun is drawn about (1 - w_sky) of the time.
        let expected = (1.0 - l.w_sky) * 20_000.0;
        assert!(
            (sun_hits as f32 - expected).abs() < 5.0 * expected.sqrt() + 20.0,
            "{sun_hits} vs {expected}"
        );
    }

    /// The importance-sampled mean of L / p equals the luminance arriving from the sky and the
    /// sun, integrated by quadrature (sky: a 2048 x 1024 grid over the hemisphere, denser
    /// towards the horizon; sun: a
    /// polar grid over its disc). 5 standard errors, which the test also requires to be under
    /// 1%, so a 2% bias (a wrong mixture weight, a pdf off by a factor) fails.
    #[test]
    fn sampled_mean_equals_the_integrated_radiance() {
        for (complex, turbidity) in [(false, 2.5), (true, 8.0)] {
            let l = light(complex, turbidity);
            let lambda = SampledWavelengths::sample_visible(0.3);
            let world = |local: Vec3| l.to_world * local;
            // Sky, excluding the sun's disc. In t with z = cos theta = t^2 (dz = 2 t dt), which
            // puts more nodes near the horizon, where the model's exp(B / (cos theta + 0.01))
            // is steep.
            let (n_phi, n_t) = (2048, 1024);
            let mut sky = 0.0f64;
            for j in 0..n_t {
                let t = (j as f32 + 0.5) / n_t as f32;
                let z = t * t;
                let s = (1.0 - z * z).sqrt();
                let mut ring = 0.0f64;
                for i in 0..n_phi {
                    let phi = 2.0 * PI * (i as f32 + 0.5) / n_phi as f32;
                    let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
                    if !l.model.in_sun(d) {
                        ring += lum(l.radiance(world(d), &lambda)) as f64;
                    }
                }
                sky += ring * 2.0 * t as f64;
            }
            sky *= 2.0 * std::f64::consts::PI / (n_phi * n_t) as f64;
            // Sun: polar grid in (angle from the centre, azimuth) over the disc.
            let frame = Frame::from_normal(l.model.sun_dir());
            let alpha = (1.0 - l.one_minus_cos).acos();
            let (n_r, n_a) = (400, 64);
            let mut sun = 0.0f64;
            for a in 0..n_r {
                let t = alpha * (a as f32 + 0.5) / n_r as f32;
                for b in 0..n_a {
                    let p = 2.0 * PI * (b as f32 + 0.5) / n_a as f32;
                    let d =
                        frame.to_world(Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos()));
                    let v = l.model.sun_rgb(d);
                    sun += (crate::texture::luminance(v) * t.sin()) as f64;
                }
            }
            sun *= (alpha as f64 / n_r as f64) * (2.0 * std::f64::consts::PI / n_a as f64);
            let truth = sky + sun;

            let mut r = rng(11);
            let n = 400_000;
            let (mut s1, mut s2) = (0.0f64, 0.0f64);
            for _ in 0..n {
                if let Some((_, radiance, pdf)) = l.sample(Vec2::new(r(), r()), &lambda) {
                    let x = (lum(radiance) / pdf) as f64;
                    s1 += x;
                    s2 += x * x;
                }
            }
            let mean = s1 / n as f64;
            let se = ((s2 / n as f64 - mean * mean) / (n as f64 - 1.0)).sqrt();
            assert!(
                5.0 * se < 0.01 * truth,
                "too noisy to judge: se {se} of {truth}"
            );
            assert!(
                (mean - truth).abs() < 5.0 * se,
                "complex {complex}: sampled {mean} vs integral {truth} (sky {sky}, sun {sun}), se {se}"
            );
            // The light's stored integral (for light selection) is close to the truth.
            assert!((l.luminance_integral() as f64 / truth - 1.0).abs() < 0.02);
        }
    }

    /// Below the horizon of the sky's frame there is neither radiance nor density, and a sun
    /// below the horizon gives no light at all.
    #[test]
    fn nothing_below_the_horizon() {
        let l = light(false, 3.0);
        let lambda = SampledWavelengths::sample_visible(0.3);
        let down = l.to_world * Vec3::new(0.2, 0.1, -0.5).normalize();
        assert!(l.radiance(down, &lambda).is_black());
        assert_eq!(l.pdf(down), 0.0);
        let p = SkyParams {
            turbidity: 3.0,
            sun_dir: Vec3::new(0.3, 0.0, -0.1).normalize(),
            sun_half_aperture: 0.005,
            complex_sun: false,
            sun_scale: 1.0,
            sky_scale: 1.0,
        };
        let m = SkyModel::rgb(&p, [0.3; 3]);
        assert!(SunSky::new(m.clone(), &m, Mat3::IDENTITY).is_none());
    }
}
