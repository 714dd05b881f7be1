//! Participating media (Mitsuba 3.9.1's `homogeneous` and `heterogeneous` over a `gridvolume`)
//! and their phase functions (`isotropic`, `hg`).
//!
//! A medium has the extinction `sigma_t` (per scene unit of length) and the single scattering
//! albedo `a`: scattering `sigma_s = a sigma_t`, absorption `sigma_a = (1 - a) sigma_t`. In a
//! heterogeneous medium the extinction is a constant spectrum times an extinction grid's value
//! at the point ([`Grid`]; the medium ends at the grid's box), and the albedo may be a grid too
//! ([`VolumeSpectrum`]). Light travelling a distance `d` keeps the fraction `exp(-sigma_t d)`
//! (Beer-Lambert); at a scattering event it leaves in a direction drawn from the phase function.
//! A medium may also emit (a pt extension, [`Medium::emission`]).
//! The integrators that use them are in `pt-integrators` (`volpath.rs`).
//!
//! Direction convention (Mitsuba's): `wo` points back along the path (towards the camera or the
//! previous vertex, `-ray.dir`), `wi` is the direction the light is exchanged with (the next
//! segment, or towards a light); both unit vectors, world space.

mod grid;

pub use grid::{Grid, VolumeSpectrum};

use crate::texture::ConstantSpectrum;
use pt_math::{Frame, Vec2, Vec3};
use pt_spectrum::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::PI;
use std::sync::Arc;

/// A phase function: the angular distribution of scattered light, normalised over the sphere
/// (its value is its own sampling density per unit solid angle).
#[derive(Clone, Debug, PartialEq)]
pub enum Phase {
    /// One phase function.
    Single(Lobe),
    /// Mitsuba's `blendphase`, nested blends flattened: `sum_i weights[i] lobes[i]` over the
    /// first `count` lobes, weights summing to one. Sampled by choosing a lobe by its weight,
    /// then sampling it exactly; the density of that is the mixture itself.
    Mixture {
        /// Each lobe's share.
        weights: [f32; MAX_PHASE_LOBES],
        /// The lobes.
        lobes: [Lobe; MAX_PHASE_LOBES],
        /// Lobes in use (at least 1).
        count: u8,
    },
}

/// Most lobes a blend of phase functions may have after nested blends are flattened.
pub const MAX_PHASE_LOBES: usize = 4;

/// A phase function of the scattering angle alone, as a density over the sphere at the
/// cosine `mu` between the propagation direction and the scattered one (`mu = 1`: forward).
#[derive(Clone, Debug, PartialEq)]
pub enum Lobe {
    /// Uniform over the sphere: 1 / (4 pi).
    Isotropic,
    /// Henyey & Greenstein 1941 ("Diffuse radiation in the galaxy", ApJ 93, eq. 3), with the
    /// mean cosine `g` of the scattering angle in (-1, 1): `g > 0` scatters forwards.
    HenyeyGreenstein(f32),
    /// Rayleigh scattering by particles much smaller than the wavelength, unpolarised light
    /// (Chandrasekhar 1960, "Radiative Transfer", sec. 17): `3 / (16 pi) (1 + mu^2)`.
    Rayleigh,
    /// Mitsuba's `tabphase`: a table over `mu`, linear between its points.
    Tabulated(Arc<TabulatedPhase>),
}

impl Lobe {
    /// The density over the sphere at the scattering cosine `mu`.
    #[inline]
    fn eval(&self, mu: f32) -> f32 {
        match *self {
            Lobe::Isotropic => 1.0 / (4.0 * PI),
            Lobe::HenyeyGreenstein(g) => hg(g, mu),
            Lobe::Rayleigh => 3.0 / (16.0 * PI) * (1.0 + mu * mu),
            Lobe::Tabulated(ref t) => t.eval(mu),
        }
    }

    /// A scattering cosine drawn from the uniform `u` by the inverse of the lobe's cumulative
    /// distribution in `mu` (increasing in `u`).
    #[inline]
    fn sample_cosine(&self, u: f32) -> f32 {
        match *self {
            Lobe::Isotropic => 1.0 - 2.0 * u,
            Lobe::HenyeyGreenstein(g) => sample_hg_cosine(g, u),
            Lobe::Rayleigh => sample_rayleigh_cosine(u),
            Lobe::Tabulated(ref t) => t.sample_cosine(u),
        }
    }
}

/// A phase function tabulated over the scattering cosine (Mitsuba's `tabphase`): values at
/// `n >= 2` points spaced evenly over [-1, 1] (`mu = 1` forward), linear between them, and
/// normalised, so that the density over the sphere is `f(mu) / (2 pi int f dmu)`. Sampled
/// exactly: the interval by its share of the integral, then the point inside it by inverting
/// the quadratic cumulative distribution of the linear piece.
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedPhase {
    /// The values divided by `2 pi int f dmu`: the density over the sphere at the points.
    density: Vec<f32>,
    /// The cumulative distribution in `mu` at the points (0 first, 1 last).
    cdf: Vec<f32>,
}

impl TabulatedPhase {
    /// The phase function through `values` (non-negative, finite, at least two, not all 0);
    /// `None` otherwise.
    pub fn new(values: &[f32]) -> Option<Self> {
        if values.len() < 2 || values.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return None;
        }
        let step = 2.0 / (values.len() - 1) as f64;
        let mut cdf = vec![0.0f64; values.len()];
        for i in 1..values.len() {
            cdf[i] = cdf[i - 1] + 0.5 * step * f64::from(values[i - 1] + values[i]);
        }
        let total = *cdf.last()?;
        if !(total > 0.0) {
            return None;
        }
        Some(TabulatedPhase {
            density: values
                .iter()
                .map(|&v| (f64::from(v) / (2.0 * std::f64::consts::PI * total)) as f32)
                .collect(),
            cdf: cdf.iter().map(|&c| (c / total) as f32).collect(),
        })
    }

    /// The interval holding `mu` and the position in it, in [0, 1].
    #[inline]
    fn locate(&self, mu: f32) -> (usize, f32) {
        let last = self.density.len() - 1;
        let x = ((mu + 1.0) * 0.5 * last as f32).clamp(0.0, last as f32);
        let i = (x as usize).min(last - 1);
        (i, x - i as f32)
    }

    /// The density over the sphere at the scattering cosine `mu`.
    #[inline]
    fn eval(&self, mu: f32) -> f32 {
        let (i, t) = self.locate(mu);
        self.density[i] + (self.density[i + 1] - self.density[i]) * t
    }

    /// A scattering cosine from the uniform `u`.
    #[inline]
    fn sample_cosine(&self, u: f32) -> f32 {
        let last = self.density.len() - 1;
        // The interval whose cumulative range holds u.
        let i = self.cdf[1..last].partition_point(|&c| c <= u);
        let (d0, d1) = (self.density[i], self.density[i + 1]);
        let width = 2.0 / last as f32;
        // The share of the interval's mass still to cover, as density x width: with the
        // density d0 + (d1 - d0) t across it, the mass up to t is (d0 t + (d1 - d0) t^2 / 2)
        // times the width (and 2 pi, which the cdf's scale absorbs).
        let mass = self.cdf[i + 1] - self.cdf[i];
        let c = ((u - self.cdf[i]) / mass.max(f32::MIN_POSITIVE)).clamp(0.0, 1.0) * (d0 + d1) * 0.5;
        // The root of (d1 - d0) t^2 / 2 + d0 t - c = 0 in [0, 1], written without the
        // cancellation of the textbook form (exact for d1 = d0 too).
        let disc = (d0 * d0 + 2.0 * (d1 - d0) * c).max(0.0);
        let t = if c > 0.0 {
            2.0 * c / (d0 + disc.sqrt())
        } else {
            0.0
        };
        (-1.0 + (i as f32 + t.clamp(0.0, 1.0)) * width).clamp(-1.0, 1.0)
    }
}

/// A direction drawn from a phase function.
#[derive(Clone, Copy, Debug)]
pub struct PhaseSample {
    /// The new direction, world space, unit.
    pub wi: Vec3,
    /// Its density per unit solid angle (equal to the phase function's value: the sample's
    /// weight is 1).
    pub pdf: f32,
}

impl Phase {
    /// The isotropic phase function (Mitsuba's default).
    pub const ISOTROPIC: Phase = Phase::Single(Lobe::Isotropic);

    /// The blend of `lobes` (each with its share; the shares sum to one), or `None` when there
    /// are none or more than [`MAX_PHASE_LOBES`].
    pub fn mixture(lobes: Vec<(f32, Lobe)>) -> Option<Phase> {
        if lobes.is_empty() || lobes.len() > MAX_PHASE_LOBES {
            return None;
        }
        let count = lobes.len() as u8;
        let mut weights = [0.0; MAX_PHASE_LOBES];
        let mut all: [Lobe; MAX_PHASE_LOBES] = std::array::from_fn(|_| Lobe::Isotropic);
        for (i, (w, l)) in lobes.into_iter().enumerate() {
            weights[i] = w;
            all[i] = l;
        }
        Some(Phase::Mixture {
            weights,
            lobes: all,
            count,
        })
    }

    /// The phase function's value for light scattered between `wo` and `wi` (see the module
    /// doc), per steradian; also the density of [`Phase::sample`] choosing `wi`.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        // mu: the cosine between the propagation direction (-wo) and wi.
        let mu = -wo.dot(wi);
        match *self {
            Phase::Single(ref lobe) => lobe.eval(mu),
            Phase::Mixture {
                ref weights,
                ref lobes,
                count,
            } => (0..count as usize)
                .map(|i| weights[i] * lobes[i].eval(mu))
                .sum(),
        }
    }

    /// Draws `wi` given `wo` from the uniform numbers `u`: exactly by the inverse of the
    /// cumulative distribution of the scattering angle's cosine (uniform azimuth).
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> PhaseSample {
        let forward = -wo;
        let mu = match *self {
            Phase::Single(ref lobe) => lobe.sample_cosine(u.x),
            Phase::Mixture {
                ref weights,
                ref lobes,
                count,
            } => {
                // Pick the lobe whose share of [0, 1) holds u.x and reuse u.x, rescaled
                // within that share, to sample it.
                let mut start = 0.0;
                let last = count as usize - 1;
                let mut mu = 0.0;
                for i in 0..=last {
                    let end = start + weights[i];
                    if u.x < end || i == last {
                        let v = ((u.x - start) / weights[i].max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
                        mu = lobes[i].sample_cosine(v);
                        break;
                    }
                    start = end;
                }
                mu
            }
        };
        let sin = (1.0 - mu * mu).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), mu);
        let wi = Frame::from_normal(forward).to_world(local).normalize();
        PhaseSample {
            wi,
            pdf: self.eval(wo, wi),
        }
    }
}

/// Henyey-Greenstein's density over the sphere at the cosine `mu` between the propagation
/// direction and the scattered one: `(1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^(3/2))`.
#[inline]
fn hg(g: f32, mu: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * mu;
    (1.0 - g * g) / (4.0 * PI * denom * denom.max(0.0).sqrt())
}

/// The cosine `mu` of a Henyey-Greenstein scattering angle from a uniform `u`: the inverse of
/// its cumulative distribution in `mu`, `mu = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g u))^2) /
/// (2 g)` (increasing in `u`: u = 0 gives -1, u = 1 gives +1); uniform for |g| < 1e-3, where
/// the formula loses its digits and the function is isotropic within 0.3%.
#[inline]
fn sample_hg_cosine(g: f32, u: f32) -> f32 {
    if g.abs() < 1e-3 {
        return 1.0 - 2.0 * u;
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// The cosine `mu` of a Rayleigh scattering angle from a uniform `u`. The cumulative
/// distribution of the density `3/8 (1 + mu^2)` over [-1, 1] is `(mu^3 + 3 mu + 4) / 8`, so
/// `mu` is the one real root of the depressed cubic `mu^3 + 3 mu + (4 - 8 u) = 0`, by
/// Cardano's formula `mu = cbrt(z + sqrt(z^2 + 1)) + cbrt(z - sqrt(z^2 + 1))`, `z = 4 u - 2`.
#[inline]
fn sample_rayleigh_cosine(u: f32) -> f32 {
    let z = 4.0 * u - 2.0;
    let r = (z * z + 1.0).sqrt();
    ((z + r).cbrt() + (z - r).cbrt()).clamp(-1.0, 1.0)
}

/// A medium in the scene's colour mode: homogeneous (`density` is `None`) or heterogeneous.
#[derive(Clone, Debug)]
pub struct Medium {
    /// Where the scene defines it (for errors that concern the medium).
    pub loc: pt_scene::SourceLoc,
    /// Extinction per scene unit of length; in a heterogeneous medium the factor that scales
    /// the extinction grid's value (Mitsuba's `scale`).
    pub sigma_t: ConstantSpectrum,
    /// Single scattering albedo, in [0, 1]: a constant, or a grid looked up at the point.
    pub albedo: VolumeSpectrum,
    /// The phase function.
    pub phase: Phase,
    /// Whether scattering events sample the lights (Mitsuba's `sample_emitters`).
    pub sample_emitters: bool,
    /// Whether light can scatter in it at all (some albedo and extinction above zero): a medium
    /// that only absorbs is crossed with its transmittance instead of sampled distances.
    pub scatters: bool,
    /// The extinction grid of a heterogeneous medium (one channel, or three: RGB), which
    /// `sigma_t` scales; the medium exists only inside the grid's box. `None`: homogeneous.
    pub density: Option<Grid>,
    /// Volume emission (a pt extension): radiance emitted per scene unit of path length at each
    /// point, the source term `j` of the radiative transfer equation
    /// `dL/ds = -sigma_t L + sigma_s (phase * L) + j`; an infinite homogeneous medium then
    /// glows with `L = j / sigma_a`. Inside a heterogeneous medium's box only. `None`: dark.
    pub emission: Option<VolumeSpectrum>,
}

impl Medium {
    /// The single scattering albedo at the world point `p`.
    #[inline]
    pub fn albedo_at(&self, p: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        self.albedo.at(p, lambda)
    }

    /// Transmittance `exp(-sigma_t d)` over the distance `d` at the path's wavelengths
    /// (homogeneous media).
    #[inline]
    pub fn transmittance(&self, d: f32, lambda: &SampledWavelengths) -> SampledSpectrum {
        transmittance(self.sigma_t.at(lambda), d)
    }
}

/// `exp(-sigma_t d)` per lane; 1 where `sigma_t` is 0 even for an infinite `d`.
#[inline]
pub fn transmittance(sigma_t: SampledSpectrum, d: f32) -> SampledSpectrum {
    let a = sigma_t.0.to_array();
    SampledSpectrum(pt_math::Vec4::from_array(a.map(|s| {
        if s > 0.0 {
            (-s * d).exp()
        } else {
            1.0
        }
    })))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table of the tests' tabulated phase function: strongly forward, with a bump
    /// backwards and a zero in between (an interval of no mass).
    const TABLE: [f32; 7] = [0.6, 0.2, 0.0, 0.0, 0.5, 2.0, 9.0];

    /// The tabulated phase function of [`TABLE`].
    fn tabulated() -> Lobe {
        Lobe::Tabulated(Arc::new(TabulatedPhase::new(&TABLE).unwrap()))
    }

    /// Exact integrals over [-1, x] of the piecewise-linear `values` (evenly spaced over
    /// [-1, 1]) and of mu times it: `(int f, int mu f)`, in f64.
    fn table_integrals(values: &[f32], x: f64) -> (f64, f64) {
        let step = 2.0 / (values.len() - 1) as f64;
        let (mut m0, mut m1) = (0.0, 0.0);
        for i in 0..values.len() - 1 {
            let a = -1.0 + i as f64 * step;
            if a >= x {
                break;
            }
            let (fa, fb) = (f64::from(values[i]), f64::from(values[i + 1]));
            // The piece up to min(x, its end), f linear in between.
            let b = (a + step).min(x);
            let fb = fa + (fb - fa) * (b - a) / step;
            m0 += (fa + fb) * (b - a) / 2.0;
            m1 += (b - a) / 6.0 * (fa * (2.0 * a + b) + fb * (a + 2.0 * b));
        }
        (m0, m1)
    }

    /// The phase functions integrate to one over the sphere (midpoint rule on a fine grid in
    /// mu and phi), and the Henyey-Greenstein mean cosine is g: both to 1e-3, far inside what
    /// a wrong normalisation or a sign error in mu (mean -g) would give.
    #[test]
    fn phase_functions_are_normalised_with_mean_cosine_g() {
        let wo = Vec3::new(0.3, -0.4, 0.866).normalize();
        let forward = -wo;
        let frame = Frame::from_normal(forward);
        for phase in [
            Phase::ISOTROPIC,
            Phase::Single(Lobe::HenyeyGreenstein(0.7)),
            Phase::Single(Lobe::HenyeyGreenstein(-0.4)),
            Phase::Single(Lobe::HenyeyGreenstein(0.0)),
            Phase::Single(Lobe::Rayleigh),
            Phase::Single(tabulated()),
            Phase::mixture(vec![
                (0.25, Lobe::Isotropic),
                (0.75, Lobe::HenyeyGreenstein(0.6)),
            ])
            .unwrap(),
        ] {
            let (n_mu, n_phi) = (6000, 16);
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n_mu {
                let mu = -1.0 + 2.0 * (i as f32 + 0.5) / n_mu as f32;
                for j in 0..n_phi {
                    let phi = 2.0 * PI * (j as f32 + 0.5) / n_phi as f32;
                    let s = (1.0 - mu * mu).sqrt();
                    let wi = frame.to_world(Vec3::new(s * phi.cos(), s * phi.sin(), mu));
                    let w = f64::from(phase.eval(wo, wi))
                        * (2.0 / n_mu as f64)
                        * (2.0 * std::f64::consts::PI / n_phi as f64);
                    total += w;
                    mean += w * f64::from(mu);
                }
            }
            // Rayleigh's is 0 (symmetric), a table's its exact moment ratio; a mixture's the
            // weighted mean of its lobes'.
            let lobe_g = |lobe: &Lobe| match *lobe {
                Lobe::Isotropic | Lobe::Rayleigh => 0.0,
                Lobe::HenyeyGreenstein(g) => f64::from(g),
                Lobe::Tabulated(_) => {
                    let (m0, m1) = table_integrals(&TABLE, 1.0);
                    m1 / m0
                }
            };
            let g = match &phase {
                Phase::Single(lobe) => lobe_g(lobe),
                Phase::Mixture {
                    weights,
                    lobes,
                    count,
                } => (0..*count as usize)
                    .map(|i| f64::from(weights[i]) * lobe_g(&lobes[i]))
                    .sum(),
            };
            assert!((total - 1.0).abs() < 1e-3, "{phase:?}: integral {total}");
            assert!((mean - g).abs() < 1e-3, "{phase:?}: mean cosine {mean}");
        }
    }

    /// Sampling follows the density: a chi-square test of sampled mu against the density's
    /// integral over 20 bins (50 000 samples, 19 degrees of freedom: the 0.1% critical value is
    /// 43.8; a sampler for -g or for the isotropic law gives chi-square in the thousands), and
    /// every sample's pdf equals the phase function's value at it.
    #[test]
    fn sampling_matches_the_density() {
        let wo = Vec3::new(-0.2, 0.5, -0.84).normalize();
        let forward = -wo;
        // A blend of a forward and a backward lobe with an isotropic one: its sampler must
        // pick each lobe in proportion (a blend sampled as its first lobe only, or with its
        // weights swapped, gives chi-square in the thousands too).
        let blend = Phase::mixture(vec![
            (0.5, Lobe::HenyeyGreenstein(0.8)),
            (0.3, Lobe::HenyeyGreenstein(-0.5)),
            (0.2, Lobe::Isotropic),
        ])
        .unwrap();
        // Rayleigh with a forward lobe, as an atmosphere's molecules and aerosols blend.
        let sky = Phase::mixture(vec![
            (0.7, Lobe::Rayleigh),
            (0.3, Lobe::HenyeyGreenstein(0.76)),
        ])
        .unwrap();
        // A table with a blend around it.
        let table_blend = Phase::mixture(vec![
            (0.6, tabulated()),
            (0.4, Lobe::HenyeyGreenstein(-0.2)),
        ])
        .unwrap();
        for phase in [
            Phase::Single(Lobe::HenyeyGreenstein(0.6)),
            Phase::Single(Lobe::HenyeyGreenstein(-0.3)),
            Phase::Single(Lobe::Rayleigh),
            Phase::Single(tabulated()),
            blend,
            sky,
            table_blend,
        ] {
            let bins = 20;
            let n = 50_000;
            let mut counts = vec![0u32; bins];
            let mut rng = 0x2545_f491_4f6c_dd1du64;
            let mut next = || {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng >> 40) as f32 / (1u64 << 24) as f32
            };
            for _ in 0..n {
                let s = phase.sample(wo, Vec2::new(next(), next()));
                assert!((s.pdf - phase.eval(wo, s.wi)).abs() <= 1e-4 * s.pdf);
                let mu = forward.dot(s.wi).clamp(-1.0, 1.0 - 1e-7);
                counts[((mu + 1.0) / 2.0 * bins as f32) as usize] += 1;
            }
            let lobes: Vec<(f64, Lobe)> = match &phase {
                Phase::Single(lobe) => vec![(1.0, lobe.clone())],
                Phase::Mixture {
                    weights,
                    lobes,
                    count,
                } => (0..*count as usize)
                    .map(|i| (f64::from(weights[i]), lobes[i].clone()))
                    .collect(),
            };
            // Cumulative in mu: 2 pi int_{-1}^{mu} p dmu in closed form per lobe (uniform
            // for g = 0; Rayleigh's (mu^3 + 3 mu + 4) / 8), summed by the lobes' weights.
            let cdf = |mu: f64| {
                lobes
                    .iter()
                    .map(|(w, lobe)| {
                        w * match *lobe {
                            Lobe::Rayleigh => (mu * mu * mu + 3.0 * mu + 4.0) / 8.0,
                            Lobe::Tabulated(_) => {
                                table_integrals(&TABLE, mu).0 / table_integrals(&TABLE, 1.0).0
                            }
                            Lobe::HenyeyGreenstein(g) if g != 0.0 => {
                                let g = f64::from(g);
                                (1.0 - g * g) / (2.0 * g)
                                    * (1.0 / (1.0 + g * g - 2.0 * g * mu).sqrt() - 1.0 / (1.0 + g))
                            }
                            _ => (mu + 1.0) / 2.0,
                        }
                    })
                    .sum::<f64>()
            };
            let mut chi2 = 0.0;
            for (b, &c) in counts.iter().enumerate() {
                let lo = -1.0 + 2.0 * b as f64 / bins as f64;
                let hi = lo + 2.0 / bins as f64;
                let expected = n as f64 * (cdf(hi) - cdf(lo));
                if expected < 1e-9 {
                    // Where the density is 0 (the table's gap) no sample may land.
                    assert_eq!(c, 0, "{phase:?}: samples where the density is 0");
                    continue;
                }
                chi2 += (f64::from(c) - expected).powi(2) / expected;
            }
            assert!(chi2 < 43.8, "{phase:?}: chi-square {chi2}");
        }
    }
}
