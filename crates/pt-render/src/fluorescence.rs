//! Fluorescent Lambertian surface: a bispectral diffuse BRDF and how a camera path crosses it.
//!
//! # Model
//! The reradiation formulation of Hullin et al. 2010 ("Fluorescent immersion range scanning",
//! sec. 3) and Mojzik et al. 2018 ("Handling fluorescence in a uni-directional spectral path
//! tracer", eq. 1-3), with the reradiation matrix built from a few spectra as in Jung et al. 2018
//! ("Wide gamut spectral upsampling with fluorescence", eq. 4): outgoing radiance at wavelength
//! `lo` (nm) is
//!
//! ```text
//! L_o(lo) = int_{H^2} [ r(lo) L_i(lo) + int_{li < lo} P(li -> lo) L_i(li) dli ] cos / pi  dw_i
//! P(li -> lo) = Q a(li) e(lo) li / lo          (per nm of li)
//! ```
//!
//! - `r`: elastic reflectance (wavelength kept), `a`: fraction of incident photons absorbed by
//!   the fluorophore, `r + a <= 1` at every wavelength (checked at build);
//! - `e`: emission spectrum normalised to unit area over 360-830 nm (per nm);
//! - `Q`: quantum yield, emitted / absorbed photons (DESIGN.md "Fluorescence");
//! - `li / lo`: radiance carries energy, a photon at `l` carries `hc / l`;
//! - Stokes: re-emission only at longer wavelengths than the exciting one, `li < lo`. The part
//!   of `e` below `li` is not renormalised: photons out = `Q int_{lo > li} e` <= `Q` photons in,
//!   with equality when the emission band lies above the exciting wavelength (the usual case of
//!   dye data). Re-emission is Lambertian, like the elastic part.
//!
//! So the directional factor is `cos / pi` for both parts and one cosine-sampled direction
//! serves all four wavelength lanes; only the wavelengths differ.
//!
//! # Transport (camera paths)
//! A lane arriving with emitted wavelength `lo` has the total albedo
//! `A(lo) = r(lo) + F(lo)`, `F(lo) = Q e(lo) / lo  int_{360}^{lo} a(l) l dl`. The lane keeps
//! `lo` with probability `r / A` (elastic) and otherwise moves to an excitation wavelength `li`
//! drawn with density `a(l) l / int_{360}^{lo} a(l) l dl` on `[360, lo)`. Either way its
//! throughput is multiplied by `A(lo)` (times the cosine-sampled direction's weight 1): the
//! estimate `A(lo) L_i(l')` has expectation `r(lo) L_i(lo) + int P(li -> lo) L_i(li) dli`, the
//! bracket above. The integrator makes that choice right after evaluating the BSDF and before
//! next-event estimation, so the light sample is evaluated at the new wavelength `li`, and the
//! path continues at `li`. The four lanes choose independently (with `u + k / 4` rotations of
//! one uniform number); the film still weighs each lane with the wavelength and pdf it was
//! sampled with, since its radiance is what reaches the camera at that wavelength.
//!
//! `a(l) l` is tabulated once on 1 nm bins (bin centres): the sampling density and `F` use the
//! same table, so the estimator is exactly unbiased for the piecewise-constant model, which
//! differs from the continuous one by less than 1e-3 relative for spectra smooth on a 1 nm
//! scale. RGB mode (`--mode rgb` on a fluorescent scene) keeps only the elastic reflectance.
//!
//! # Parameters (Mitsuba-style XML, project extension)
//! | name | type | default | unit |
//! |---|---|---|---|
//! | `reflectance` | spectrum / rgb / float | 0.5 | elastic albedo in [0, 1] |
//! | `absorption` | spectrum / float | 0.5 | absorbed fraction in [0, 1] |
//! | `emission` | spectrum (required) | - | shape only, normalised per nm |
//! | `yield` | float | 1 | photons out / photons absorbed |
//!
//! ```xml
//! <bsdf type="fluorescent">
//!     <spectrum name="reflectance" value="360:0.05, 830:0.05"/>
//!     <spectrum name="absorption" value="360:0.8, 470:0.8, 500:0, 830:0"/>
//!     <spectrum name="emission" value="480:0, 520:1, 600:0"/>
//!     <float name="yield" value="0.9"/>
//! </bsdf>
//! ```
//! Mitsuba has no fluorescence: such scenes have no Mitsuba reference and are checked against
//! closed forms (tests/fluorescence.rs).

use pt_spectrum::cie::{LAMBDA_MAX, LAMBDA_MIN};
use pt_spectrum::{SampledSpectrum, SampledWavelengths, Spectrum};

/// Number of 1 nm bins over 360-830 nm.
const BINS: usize = (LAMBDA_MAX - LAMBDA_MIN) as usize;

/// A fluorescent Lambertian material at build time: its spectra and the excitation table.
#[derive(Clone, Debug)]
pub struct Fluorescent {
    /// Elastic reflectance r(l).
    reflectance: Spectrum,
    /// Absorbed fraction a(l).
    absorption: Spectrum,
    /// Emission spectrum e(l), per nm, unit area over 360-830 nm.
    emission: Spectrum,
    /// Quantum yield Q.
    quantum_yield: f32,
    /// `cdf[j]` = int_{360}^{360 + j} a(l) l dl with a(l) l constant on each 1 nm bin (its value
    /// at the bin centre); `BINS + 1` entries, nm^2.
    cdf: Vec<f64>,
    /// `emission_cdf[j]` = int_{360}^{360 + j} e(l) / l dl with e(l) / l constant on each 1 nm
    /// bin (its value at the bin centre); `BINS + 1` entries, 1/nm. For light paths (the
    /// adjoint, see [`Fluorescent::scatter_adjoint`]).
    emission_cdf: Vec<f64>,
}

impl Fluorescent {
    /// Builds the model from its spectra (spectral-mode forms). Errors (as text) when the
    /// emission has no area, when `r + a > 1` somewhere on 360-830 nm (checked at every
    /// 1 nm, with a 1e-4 allowance for rounding in the input numbers), or `Q` is outside [0, 1].
    pub fn new(
        reflectance: Spectrum,
        absorption: &Spectrum,
        emission: &Spectrum,
        quantum_yield: f32,
    ) -> Result<Self, String> {
        if !(0.0..=1.0).contains(&quantum_yield) {
            return Err(format!(
                "quantum yield must be in [0, 1], got {quantum_yield}"
            ));
        }
        for k in 0..=BINS {
            let l = LAMBDA_MIN + k as f32;
            let (r, a) = (reflectance.eval(l), absorption.eval(l));
            if r < 0.0 || a < 0.0 || r + a > 1.0 + 1e-4 {
                return Err(format!(
                    "reflectance + absorption must be in [0, 1]: at {l} nm they are {r} + {a}"
                ));
            }
        }
        let area = pt_spectrum::cie::integrate_visible(|l| emission.eval(l as f32) as f64);
        if !(area > 0.0) || !area.is_finite() {
            return Err("the emission spectrum has no area over 360-830 nm".into());
        }
        let emission = scaled(emission, (1.0 / area) as f32);
        let mut cdf = Vec::with_capacity(BINS + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for j in 0..BINS {
            let c = LAMBDA_MIN as f64 + j as f64 + 0.5;
            acc += absorption.eval(c as f32) as f64 * c;
            cdf.push(acc);
        }
        let mut emission_cdf = Vec::with_capacity(BINS + 1);
        let mut acc = 0.0f64;
        emission_cdf.push(0.0);
        for j in 0..BINS {
            let c = LAMBDA_MIN as f64 + j as f64 + 0.5;
            acc += emission.eval(c as f32) as f64 / c;
            emission_cdf.push(acc);
        }
        Ok(Fluorescent {
            reflectance,
            absorption: absorption.clone(),
            emission,
            quantum_yield,
            cdf,
            emission_cdf,
        })
    }

    /// The reradiation kernel `P(li -> lo) = Q a(li) e(lo) li / lo` for `li < lo`, else 0
    /// (per nm of li; continuous form, for tests and plots).
    pub fn reradiation(&self, li: f32, lo: f32) -> f32 {
        if li < lo {
            self.quantum_yield * self.absorption.eval(li) * self.emission.eval(lo) * li / lo
        } else {
            0.0
        }
    }

    /// `int_{360}^{l} a(x) x dx` of the tabulated model, nm^2.
    #[inline]
    fn cumulative(&self, l: f32) -> f64 {
        let x = (l - LAMBDA_MIN).clamp(0.0, BINS as f32) as f64;
        let j = (x as usize).min(BINS - 1);
        self.cdf[j] + (self.cdf[j + 1] - self.cdf[j]) * (x - j as f64)
    }

    /// Elastic and fluorescent albedo `(r(lo), F(lo))` at emitted wavelength `lo` (nm), where
    /// `F(lo) = Q e(lo) / lo int_{360}^{lo} a(l) l dl` (module doc).
    #[inline]
    pub fn albedos(&self, lo: f32) -> (f32, f32) {
        let f = self.quantum_yield as f64 * self.emission.eval(lo) as f64 * self.cumulative(lo)
            / lo as f64;
        (self.reflectance.eval(lo), f as f32)
    }

    /// Total albedo `r + F` per lane at the lanes' (emitted) wavelengths: the reflectance of the
    /// Lambertian BSDF the integrator uses at this vertex.
    pub fn albedo(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        SampledSpectrum(
            lambda
                .lambda()
                .to_array()
                .map(|l| {
                    let (r, f) = self.albedos(l);
                    r + f
                })
                .into(),
        )
    }

    /// Excitation wavelength for emitted `lo`, drawn with density `a(l) l / int_{360}^{lo} a x dx`
    /// on [360, lo) by inverting the tabulated cumulative; `None` if nothing below `lo` absorbs.
    /// Returns `(li, pdf per nm)`.
    pub fn sample_excitation(&self, lo: f32, u: f32) -> Option<(f32, f32)> {
        let total = self.cumulative(lo);
        if !(total > 0.0) {
            return None;
        }
        let target = u.clamp(0.0, 1.0) as f64 * total;
        // Last node with cdf <= target (bins of zero width in cdf are skipped by taking the
        // first bin whose upper node exceeds the target).
        let j = self.cdf.partition_point(|&c| c <= target).clamp(1, BINS) - 1;
        let g = self.cdf[j + 1] - self.cdf[j];
        let t = if g > 0.0 {
            (target - self.cdf[j]) / g
        } else {
            0.0
        };
        let li = (LAMBDA_MIN as f64 + j as f64 + t.clamp(0.0, 1.0)).min(lo as f64 - 1e-4) as f32;
        Some((li, (g / total) as f32))
    }

    /// Chooses, per lane, elastic scattering (wavelength kept) or fluorescence (the lane moves to
    /// an excitation wavelength), as described in the module doc. `u` is one uniform number;
    /// lane k uses `u + k / 4` (mod 1). The throughput factor is [`albedo`](Self::albedo) at the
    /// wavelengths before the call, whatever is chosen.
    pub fn scatter(&self, lambda: &SampledWavelengths, u: f32) -> SampledWavelengths {
        let mut out = lambda.lambda().to_array();
        for (k, lo) in out.iter_mut().enumerate() {
            let (r, f) = self.albedos(*lo);
            if !(f > 0.0) {
                continue;
            }
            let uk = (u + k as f32 * 0.25).fract();
            let p_elastic = r / (r + f);
            if uk < p_elastic {
                continue;
            }
            // Re-use the rest of uk (uniform on [0, 1) given fluorescence) for the excitation.
            let v = ((uk - p_elastic) / (1.0 - p_elastic)).min(1.0 - f32::EPSILON);
            if let Some((li, _)) = self.sample_excitation(*lo, v) {
                *lo = li;
            }
        }
        lambda.with_lambda(out.into())
    }
}

impl Fluorescent {
    /// `int_{360}^{l} e(x) / x dx` of the tabulated model, 1/nm.
    #[inline]
    fn emission_cumulative(&self, l: f32) -> f64 {
        let x = (l - LAMBDA_MIN).clamp(0.0, BINS as f32) as f64;
        let j = (x as usize).min(BINS - 1);
        self.emission_cdf[j] + (self.emission_cdf[j + 1] - self.emission_cdf[j]) * (x - j as f64)
    }

    /// Elastic and fluorescent albedo `(r(li), G(li))` of light arriving at `li` (nm), the
    /// adjoint of [`Fluorescent::albedos`]: the power re-emitted at all longer wavelengths per
    /// unit arriving, `G(li) = int_{lo > li} P(li -> lo) dlo = Q a(li) li int_{li}^{830} e(l) /
    /// l dl`.
    #[inline]
    pub fn adjoint_albedos(&self, li: f32) -> (f32, f32) {
        let above = self.emission_cdf[BINS] - self.emission_cumulative(li);
        let g = self.quantum_yield as f64 * self.absorption.eval(li) as f64 * li as f64 * above;
        (self.reflectance.eval(li), g.max(0.0) as f32)
    }

    /// Total adjoint albedo `r + G` per lane at the lanes' arriving wavelengths: the
    /// reflectance of the Lambertian BSDF a light path meets here.
    pub fn adjoint_albedo(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        SampledSpectrum(
            lambda
                .lambda()
                .to_array()
                .map(|l| {
                    let (r, g) = self.adjoint_albedos(l);
                    r + g
                })
                .into(),
        )
    }

    /// A re-emitted wavelength for light absorbed at `li`, drawn with density
    /// `(e(l) / l) / int_{li}^{830} e(x) / x dx` on (li, 830] by inverting the tabulated
    /// cumulative; `None` if nothing above `li` is emitted.
    pub fn sample_reemission(&self, li: f32, u: f32) -> Option<f32> {
        let base = self.emission_cumulative(li);
        let total = self.emission_cdf[BINS] - base;
        if !(total > 0.0) {
            return None;
        }
        let target = base + u.clamp(0.0, 1.0) as f64 * total;
        let j = self
            .emission_cdf
            .partition_point(|&c| c <= target)
            .clamp(1, BINS)
            - 1;
        let g = self.emission_cdf[j + 1] - self.emission_cdf[j];
        let t = if g > 0.0 {
            (target - self.emission_cdf[j]) / g
        } else {
            0.0
        };
        let lo = (LAMBDA_MIN as f64 + j as f64 + t.clamp(0.0, 1.0)).max(li as f64 + 1e-4);
        Some(lo.min(LAMBDA_MAX as f64) as f32)
    }

    /// For a light path (the adjoint of [`Fluorescent::scatter`]): per lane, light arriving at
    /// `li` is reflected elastically (wavelength kept) with probability `r / (r + G)`, or
    /// absorbed and re-emitted at a longer wavelength drawn by
    /// [`Fluorescent::sample_reemission`]. The throughput factor is
    /// [`Fluorescent::adjoint_albedo`] at the wavelengths before the call, whatever is chosen:
    /// the estimate `(r + G)(li)` of the re-emitted light at the chosen wavelength has the
    /// expectation of `r(li)` at `li` plus `int P(li -> lo)` spread over `lo`. Lane k uses
    /// `u + k / 4` (mod 1). The pdfs of the wavelengths are kept (the film weighs each lane by
    /// how its light was sampled, at the light).
    pub fn scatter_adjoint(&self, lambda: &SampledWavelengths, u: f32) -> SampledWavelengths {
        let mut out = lambda.lambda().to_array();
        for (k, l) in out.iter_mut().enumerate() {
            let (r, g) = self.adjoint_albedos(*l);
            if !(g > 0.0) {
                continue;
            }
            let uk = (u + k as f32 * 0.25).fract();
            let p_elastic = r / (r + g);
            if uk < p_elastic {
                continue;
            }
            let v = ((uk - p_elastic) / (1.0 - p_elastic)).min(1.0 - f32::EPSILON);
            if let Some(lo) = self.sample_reemission(*l, v) {
                *l = lo;
            }
        }
        lambda.with_lambda(out.into())
    }
}

/// `s` times `k` as a spectrum (tabulated spectra are rescaled node by node; others are
/// evaluated on a 1 nm table, exact for the piecewise-linear forms and within interpolation
/// error for smooth ones).
fn scaled(s: &Spectrum, k: f32) -> Spectrum {
    let pairs: Vec<(f32, f32)> = match s {
        Spectrum::Tabulated(t) => {
            let (l, v) = t.samples();
            l.iter().zip(v).map(|(&l, &v)| (l, v * k)).collect()
        }
        _ => (0..=BINS)
            .map(|j| {
                let l = LAMBDA_MIN + j as f32;
                (l, s.eval(l) * k)
            })
            .collect(),
    };
    Spectrum::tabulated(&pairs).unwrap_or(Spectrum::constant(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(q: f32) -> Fluorescent {
        let r = Spectrum::parse_mitsuba("360:0.1, 830:0.3").unwrap();
        let a = Spectrum::parse_mitsuba("360:0.8, 470:0.6, 500:0, 830:0").unwrap();
        let e = Spectrum::parse_mitsuba("440:0, 520:2, 600:0").unwrap();
        Fluorescent::new(r, &a, &e, q).unwrap()
    }

    /// The emission is normalised and the albedo follows its closed form: F(lo) by an
    /// independent fine quadrature of Q e(lo)/lo int_{360}^{lo} a(l) l dl (0.01 nm midpoint
    /// rule); the 1 nm table may differ by < 1e-3 relative (module doc), far below a missing
    /// factor (li / lo is 0.8-0.95 here, Q is 0.7).
    #[test]
    fn albedo_matches_quadrature() {
        let m = model(0.7);
        let area = pt_spectrum::cie::integrate_visible(|l| m.emission.eval(l as f32) as f64);
        assert!((area - 1.0).abs() < 1e-5, "{area}");
        let a = Spectrum::parse_mitsuba("360:0.8, 470:0.6, 500:0, 830:0").unwrap();
        for lo in [450.0f32, 480.0, 520.0, 560.0, 599.0, 700.0] {
            let n = ((lo - 360.0) * 100.0) as usize;
            let h = (lo - 360.0) as f64 / n as f64;
            let int: f64 = (0..n)
                .map(|i| {
                    let l = 360.0 + (i as f64 + 0.5) * h;
                    a.eval(l as f32) as f64 * l * h
                })
                .sum();
            let expect = 0.7 * m.emission.eval(lo) as f64 * int / lo as f64;
            let (r, f) = m.albedos(lo);
            assert!(
                (f as f64 - expect).abs() <= 1e-3 * expect + 1e-9,
                "{lo}: {f} vs {expect}"
            );
            assert!((r - (0.1 + 0.2 * (lo - 360.0) / 470.0)).abs() < 1e-6);
        }
        // Stokes: nothing is emitted where the emission spectrum is zero.
        assert_eq!(m.albedos(430.0).1, 0.0);
    }

    /// Photon balance from the kernel: photons re-emitted per absorbed photon at li,
    /// int P(li -> lo) lo / li dlo / a(li), must be Q int_{lo > li} e <= Q. At li = 450 nm the
    /// emission (440-600 nm) lies 0.78% below li, so the Stokes cut must show (a kernel without
    /// it gives exactly Q); at li = 430 nm nothing is cut. Also the kernel integrated over li
    /// must give the albedo F(lo) that the sampler uses (< 1e-3 relative: the 1 nm table).
    #[test]
    fn photons_out_do_not_exceed_photons_in() {
        let q = 0.8;
        let m = model(q);
        for (li, cut) in [(450.0f32, (10.0f64 / 80.0).powi(2) * 0.5), (430.0, 0.0)] {
            let a_li = m.absorption.eval(li) as f64;
            let h = 0.01f64;
            let photons: f64 = (0..((830.0 - 360.0) / h) as usize)
                .map(|i| {
                    let lo = 360.0 + (i as f64 + 0.5) * h;
                    m.reradiation(li, lo as f32) as f64 * lo / li as f64 * h
                })
                .sum::<f64>()
                / a_li;
            let expect = q as f64 * (1.0 - cut);
            assert!(
                (photons - expect).abs() < 2e-4,
                "li {li}: {photons} vs {expect}"
            );
            assert!(photons <= q as f64 + 1e-6);
        }
        for lo in [480.0f32, 520.0, 580.0] {
            let h = 0.01f64;
            let f: f64 = (0..((lo as f64 - 360.0) / h) as usize)
                .map(|i| m.reradiation((360.0 + (i as f64 + 0.5) * h) as f32, lo) as f64 * h)
                .sum();
            let (_, f_model) = m.albedos(lo);
            assert!(
                (f_model as f64 / f - 1.0).abs() < 1e-3,
                "lo {lo}: {f_model} vs {f}"
            );
        }
    }

    /// Excitation sampling: samples lie below lo, and their histogram follows a(l) l on
    /// [360, lo) (5 nm bins, 200k stratified samples: each bin's expected share is known to
    /// 1e-6, the stratified estimate is off by < 1e-4; a wrong density is off by > 1e-3).
    #[test]
    fn excitation_sampling_follows_its_density() {
        let m = model(1.0);
        let a = Spectrum::parse_mitsuba("360:0.8, 470:0.6, 500:0, 830:0").unwrap();
        let lo = 520.0f32;
        let n = 200_000;
        let nb = 32; // 360..520 in 5 nm bins
        let mut hist = vec![0.0f64; nb];
        for k in 0..n {
            let (li, pdf) = m
                .sample_excitation(lo, (k as f32 + 0.5) / n as f32)
                .unwrap();
            assert!(li < lo && li >= 360.0 && pdf > 0.0, "{li}");
            hist[(((li - 360.0) / 5.0) as usize).min(nb - 1)] += 1.0 / n as f64;
        }
        let total = m.cumulative(lo);
        for (b, h) in hist.iter().enumerate() {
            let expect: f64 = (0..5)
                .map(|i| {
                    let c = 360.0 + 5.0 * b as f64 + i as f64 + 0.5;
                    a.eval(c as f32) as f64 * c
                })
                .sum::<f64>()
                / total;
            assert!((h - expect).abs() < 1e-4, "bin {b}: {h} vs {expect}");
        }
        assert!(m.sample_excitation(360.0, 0.5).is_none());
    }

    /// `scatter` keeps each lane with probability r / (r + F), else moves it below its
    /// wavelength; over many u the fraction kept matches (binomial noise < 0.005 at 40k samples).
    #[test]
    fn scatter_chooses_lanes_with_the_right_odds() {
        let m = model(0.9);
        let w = SampledWavelengths::sample_uniform(0.0)
            .with_lambda([520.0, 560.0, 450.0, 700.0].into());
        let n = 40_000;
        let mut kept = [0.0f64; 4];
        for k in 0..n {
            let out = m
                .scatter(&w, (k as f32 + 0.5) / n as f32)
                .lambda()
                .to_array();
            for (i, (&o, &l)) in out.iter().zip(w.lambda().to_array().iter()).enumerate() {
                assert!(o <= l);
                if o == l {
                    kept[i] += 1.0 / n as f64;
                }
            }
        }
        for (i, &l) in w.lambda().to_array().iter().enumerate() {
            let (r, f) = m.albedos(l);
            let p = (r / (r + f)) as f64;
            assert!(
                (kept[i] - p).abs() < 5e-3,
                "lane {i} at {l}: {} vs {p}",
                kept[i]
            );
        }
    }

    #[test]
    fn rejects_unphysical_parameters() {
        let e = Spectrum::parse_mitsuba("440:0, 520:2, 600:0").unwrap();
        assert!(
            Fluorescent::new(Spectrum::constant(0.6), &Spectrum::constant(0.5), &e, 1.0)
                .unwrap_err()
                .contains("reflectance + absorption")
        );
        assert!(
            Fluorescent::new(Spectrum::constant(0.2), &Spectrum::constant(0.5), &e, 1.2).is_err()
        );
        assert!(Fluorescent::new(
            Spectrum::constant(0.2),
            &Spectrum::constant(0.5),
            &Spectrum::constant(0.0),
            1.0
        )
        .is_err());
    }

    /// The adjoint (light paths): G(li) is the power re-emitted at all longer wavelengths,
    /// `int_{li}^{830} P(li -> lo) dlo` by an independent quadrature of the kernel (0.01 nm
    /// midpoint rule; the 1 nm table differs by < 1e-3 relative), and re-emitted wavelengths
    /// are drawn in proportion to `e(lo) / lo` above li: their mean matches the quadrature of
    /// that density within 0.5 nm (2^15 stratified draws: the inverse cumulative evaluated on
    /// a fine grid, exact to the 1 nm table's interpolation). A missing li factor or a Stokes cut in the wrong
    /// direction moves G by 10% or more; drawing by e alone shifts the mean by about 1 nm.
    #[test]
    fn adjoint_albedo_and_reemission_follow_the_kernel() {
        let m = model(0.7);
        for li in [400.0f32, 450.0, 480.0] {
            let steps = 43_000;
            let h = (830.0 - f64::from(li)) / steps as f64;
            let (mut g, mut w_sum, mut wl_sum) = (0.0f64, 0.0f64, 0.0f64);
            for k in 0..steps {
                let lo = f64::from(li) + (k as f64 + 0.5) * h;
                g += f64::from(m.reradiation(li, lo as f32)) * h;
                let w = f64::from(m.emission.eval(lo as f32)) / lo;
                w_sum += w * h;
                wl_sum += w * lo * h;
            }
            let (_, got) = m.adjoint_albedos(li);
            assert!(
                (f64::from(got) / g - 1.0).abs() < 1e-3,
                "G({li}) = {got}, quadrature {g}"
            );
            let want_mean = wl_sum / w_sum;
            let n = 1 << 15;
            let mean = (0..n)
                .map(|k| {
                    f64::from(
                        m.sample_reemission(li, (k as f32 + 0.5) / n as f32)
                            .unwrap(),
                    )
                })
                .sum::<f64>()
                / f64::from(n);
            assert!(
                (mean - want_mean).abs() < 0.5,
                "li {li}: mean re-emitted {mean}, want {want_mean}"
            );
            assert!(m.sample_reemission(li, 0.0).unwrap() > li);
        }
    }
}
