//! Hair and fur: the near-field fibre model of Chiang, Bitterli, Tappan and Burley, "A
//! Practical and Controllable Hair and Fur Model for Production Path Tracing" (Computer Graphics
//! Forum 35(2), 2016), with Mitsuba 3.9.1's `hair` conventions.
//!
//! **Frame.** The fibre runs along local **+y**; the normal plane (its cross-section) is x-z,
//! z the surface normal (Mitsuba's frame for its `hair` plugin). For a direction `w`:
//! the longitudinal angle `theta` has `sin theta = w.y`; the azimuth is
//! `phi = atan2(w.z, w.x)`; and `gamma`, the angle in the normal plane between `w` and the
//! normal, gives the offset across the fibre `h = sin gamma` where the viewer's ray met it
//! (Mitsuba takes `h` from the viewing direction this way, so any surface whose frame has the
//! fibre along y can carry the model). The model is not symmetric: `h` belongs to `wo`.
//!
//! **Model.** The light that leaves towards `wo` after `p` segments inside the fibre
//! (p = 0 reflection, 1 transmission, 2 one internal reflection, 3 all longer paths):
//!
//! `f(wo, wi) |cos_n wi| = sum_{p<3} M_p(theta_o', theta_i) A_p N_p(phi) + M_3 A_3 / (2 pi)`
//!
//! - `M_p`: d'Eon et al. 2011 (eq. 7), `M = csch(1/v) / (2 v) exp(-sin theta_o sin theta_i / v)
//!   I0(cos theta_o cos theta_i / v)`, in log form for `v < 0.1` (Chiang et al. section 4.1);
//!   variances `v_0 = (0.726 b_m + 0.812 b_m^2 + 3.7 b_m^20)^2`, `v_1 = v_0 / 4`,
//!   `v_2 = v_3 = 4 v_0` (Chiang eq. 7). `theta_o'` is `theta_o` tilted by the cuticle scales:
//!   by -2 alpha for p = 0, +alpha for p = 1, +4 alpha for p = 2 (section 4.1.1).
//! - `A_p`: attenuation (Chiang eq. 3-4): Fresnel `f` at `cos theta_o cos gamma_o` (index
//!   `eta`), transmittance `T = exp(-sigma_a 2 cos gamma_t / cos theta_t)` through the fibre
//!   of unit radius; `A_0 = f`, `A_1 = (1-f)^2 T`, `A_2 = A_1 T f`, `A_3 = A_2 T f / (1 - T f)`.
//! - `N_p`: azimuthal, a logistic of scale `s = sqrt(pi/8) (0.265 b_n + 1.194 b_n^2 + 5.372
//!   b_n^22)` (Chiang eq. 8) trimmed to [-pi, pi], centred on the perfect specular deflection
//!   `Phi = 2 p gamma_t - 2 gamma_o + p pi`.
//!
//! **Sampling** (Chiang section 4.3, exact): pick `p` with probability `A_p`'s luminance over the
//! sum; sample the longitudinal lobe exactly (`cos = 1 + v ln(u + (1-u) e^(-2/v))`, d'Eon),
//! then the trimmed logistic (or a uniform azimuth for p = 3). The pdf is the same sum with the
//! luminance weights in place of `A_p`.
//!
//! `f` is returned without the cosine, as pt's BSDFs are (`|cos_n wi|` = `|wi.z|`, the
//! surface normal's, divided out).
//!
//! **Back side.** Both sides scatter alike. One interaction is the whole walk through the fibre,
//! so on a closed shape (a `cylinder` as one fibre) a ray that was transmitted meets the same
//! fibre again from inside and is scattered a second time: Mitsuba 3.9.1 does the same (it
//! declares its back side null but its `sample` and `eval` do not look at the side), and
//! scenes/hair-fibres.xml agrees with its reference only so; a pass-through there made pt's
//! image 8% brighter (30% in the fibres).
//!
//! | parameter | type | default | unit |
//! |---|---|---|---|
//! | `sigma_a` | spectrum | from the pigments | absorption per unit fibre radius |
//! | `eumelanin`, `pheomelanin` | float | 1.3, 0.2 | pigment concentrations (d'Eon et al. 2011) |
//! | `int_ior` / `ext_ior` | float | 1.55 / 1.000277 | fibre (amber) and outside (air) |
//! | `longitudinal_roughness` | float | 0.3 | `b_m` in [0, 1] |
//! | `azimuthal_roughness` | float | 0.3 | `b_n` in [0, 1] |
//! | `scale_tilt` | float | 2 | cuticle scale angle `alpha`, degrees |
//!
//! Mitsuba XML: `<bsdf type="hair"><float name="eumelanin" value="0.3"/></bsdf>`

use crate::fresnel::fresnel_dielectric;
use crate::BsdfSample;
use pt_math::{fastmath, Vec2, Vec3, Vec4};
use pt_spectrum::SampledSpectrum;
use std::f32::consts::{PI, TAU};

/// Absorption of eumelanin per unit concentration, linear sRGB, per unit fibre radius
/// (d'Eon et al. 2011, "An energy-conserving hair reflectance model", section 6).
pub const EUMELANIN_SIGMA_A: [f32; 3] = [0.419, 0.697, 1.37];
/// Absorption of pheomelanin per unit concentration (d'Eon et al. 2011).
pub const PHEOMELANIN_SIGMA_A: [f32; 3] = [0.187, 0.4, 1.05];

/// Segments modelled one by one; longer paths are summed into the last term.
const P_MAX: usize = 3;
/// Smallest longitudinal variance (b_m = 0.014; the v_1 = v_0 / 4 lobe is then 0.3 degrees
/// wide): below it `exp(-1/v)` and `I0` leave single precision.
const MIN_V: f32 = 1e-4;
/// Smallest azimuthal logistic scale (b_n = 0.004).
const MIN_S: f32 = 1e-3;

/// The hair fibre scattering model.
#[derive(Clone, Copy, Debug)]
pub struct Hair {
    /// Absorption coefficient per unit fibre radius, per lane.
    sigma_a: SampledSpectrum,
    /// Weights turning a lane vector into luminance (RGB: Rec. 709; spectral: CIE y-bar at the
    /// lanes' wavelengths), for the choice of `p`.
    luminance: Vec4,
    /// Relative index of refraction, fibre over outside.
    eta: f32,
    /// 1 / v_0, the inverse of the first longitudinal variance (the others are v_0 / 4,
    /// 4 v_0, 4 v_0: [`LOBE_INV_V`]).
    inv_v0: f32,
    /// The longitudinal lobes' normalisations ([`Longitudinal::norm`]): the model is kept
    /// within the [`crate::Bsdf`]'s size by storing only these.
    m_norm: [f32; P_MAX + 1],
    /// The azimuthal lobe: the logistic of scale `s` on [-pi, pi].
    n: TrimmedLogistic,
    /// sin and cos of alpha, 2 alpha, 4 alpha (the scale tilt).
    sin_2k_alpha: [f32; 3],
    cos_2k_alpha: [f32; 3],
}

/// Quantities of the viewing direction `wo` shared by eval, pdf and sample.
struct Setup {
    sin_theta_o: f32,
    cos_theta_o: f32,
    phi_o: f32,
    gamma_o: f32,
    gamma_t: f32,
    /// A_0..A_3 per lane.
    a: [SampledSpectrum; P_MAX + 1],
    /// Probabilities of p = 0..3.
    a_pdf: [f32; P_MAX + 1],
}

impl Hair {
    /// The model from the absorption `sigma_a` (per unit radius, per lane), the luminance
    /// weights of the lanes, the relative index `eta` (> 0, not 1), the longitudinal and
    /// azimuthal roughness (in [0, 1]) and the scale tilt in degrees.
    pub fn new(
        sigma_a: SampledSpectrum,
        luminance: Vec4,
        eta: f32,
        longitudinal_roughness: f32,
        azimuthal_roughness: f32,
        scale_tilt_deg: f32,
    ) -> Self {
        let bm = longitudinal_roughness;
        let bn = azimuthal_roughness;
        // Roughness 0 (allowed, as in Mitsuba) would make the lobes deltas, which the model's
        // densities cannot hold: v and s are kept above MIN_V and MIN_S (b_m 0.014, b_n 0.004),
        // lobes already narrower than a degree.
        let v0 = {
            let x = 0.726 * bm + 0.812 * bm * bm + 3.7 * bm.powi(20);
            (x * x).max(MIN_V)
        };
        let s =
            ((PI / 8.0).sqrt() * (0.265 * bn + 1.194 * bn * bn + 5.372 * bn.powi(22))).max(MIN_S);
        let mut sin_2k_alpha = [0.0; 3];
        let mut cos_2k_alpha = [0.0; 3];
        sin_2k_alpha[0] = scale_tilt_deg.to_radians().sin();
        cos_2k_alpha[0] = (1.0 - sin_2k_alpha[0] * sin_2k_alpha[0]).max(0.0).sqrt();
        for i in 1..3 {
            sin_2k_alpha[i] = 2.0 * cos_2k_alpha[i - 1] * sin_2k_alpha[i - 1];
            cos_2k_alpha[i] = cos_2k_alpha[i - 1] * cos_2k_alpha[i - 1]
                - sin_2k_alpha[i - 1] * sin_2k_alpha[i - 1];
        }
        let v = [v0, 0.25 * v0, 4.0 * v0, 4.0 * v0];
        Hair {
            sigma_a,
            luminance,
            eta,
            inv_v0: 1.0 / v0,
            m_norm: v.map(|v| Longitudinal::new(v).norm),
            n: TrimmedLogistic::new(s),
            sin_2k_alpha,
            cos_2k_alpha,
        }
    }

    /// The widths of the narrowest lobes: the standard deviation of the narrowest longitudinal
    /// lobe (`sqrt(v_1)`, radians) and the azimuthal logistic scale `s` (radians).
    pub fn lobe_widths(&self) -> (f32, f32) {
        (self.lobe(1).v().sqrt(), self.n.s)
    }

    /// `sigma_a` from pigment concentrations in RGB (d'Eon et al. 2011).
    pub fn pigment_sigma_a_rgb(eumelanin: f32, pheomelanin: f32) -> [f32; 3] {
        std::array::from_fn(|c| {
            eumelanin * EUMELANIN_SIGMA_A[c] + pheomelanin * PHEOMELANIN_SIGMA_A[c]
        })
    }

    /// The absorption that gives fibres of azimuthal roughness `b_n` the colour `c` (per lane,
    /// in (0, 1]) after multiple scattering: Chiang et al. 2016, eq. 9,
    /// `sigma_a = (ln c / (5.969 - 0.215 b_n + 2.532 b_n^2 - 10.73 b_n^3 + 5.574 b_n^4 +
    /// 0.245 b_n^5))^2`.
    pub fn sigma_a_from_reflectance(c: SampledSpectrum, b_n: f32) -> SampledSpectrum {
        let d = 5.969 - 0.215 * b_n + 2.532 * b_n.powi(2) - 10.73 * b_n.powi(3)
            + 5.574 * b_n.powi(4)
            + 0.245 * b_n.powi(5);
        SampledSpectrum(c.0.map(|x| {
            let l = x.clamp(1e-4, 1.0).ln() / d;
            l * l
        }))
    }

    /// sin and cos of `theta_o` tilted by the scales for segment count `p`.
    #[inline]
    fn tilt(&self, sin_t: f32, cos_t: f32, p: usize) -> (f32, f32) {
        let (s, c) = match p {
            0 => (
                sin_t * self.cos_2k_alpha[1] - cos_t * self.sin_2k_alpha[1],
                cos_t * self.cos_2k_alpha[1] + sin_t * self.sin_2k_alpha[1],
            ),
            1 => (
                sin_t * self.cos_2k_alpha[0] + cos_t * self.sin_2k_alpha[0],
                cos_t * self.cos_2k_alpha[0] - sin_t * self.sin_2k_alpha[0],
            ),
            2 => (
                sin_t * self.cos_2k_alpha[2] + cos_t * self.sin_2k_alpha[2],
                cos_t * self.cos_2k_alpha[2] - sin_t * self.sin_2k_alpha[2],
            ),
            _ => (sin_t, cos_t),
        };
        (s, c.abs())
    }

    #[cfg_attr(not(debug_assertions), inline(always))]
    fn setup(&self, wo: Vec3) -> Setup {
        let sin_theta_o = wo.y.clamp(-1.0, 1.0);
        let cos_theta_o = (1.0 - sin_theta_o * sin_theta_o).max(0.0).sqrt();
        let phi_o = fastmath::atan2(wo.z, wo.x);
        // gamma_o: the angle in the normal plane from the normal (z), signed so that
        // h = sin gamma_o is positive for x < 0 (Mitsuba's orientation).
        let proj = (wo.x * wo.x + wo.z * wo.z).sqrt();
        let (gamma_o, h) = if proj > 0.0 {
            let g = fastmath::acos((wo.z / proj).clamp(-1.0, 1.0));
            // sin gamma_o = -x / proj: sin acos(z / proj) = |x| / proj, signed as gamma_o.
            (if wo.x < 0.0 { g } else { -g }, -wo.x / proj)
        } else {
            (0.0, 0.0)
        };
        // Refraction: longitudinally by eta, azimuthally by the modified index (Bravais).
        let sin_theta_t = sin_theta_o / self.eta;
        let cos_theta_t = (1.0 - sin_theta_t * sin_theta_t).max(0.0).sqrt();
        let eta_p = (self.eta * self.eta - sin_theta_o * sin_theta_o)
            .max(0.0)
            .sqrt()
            / cos_theta_o;
        let sin_gamma_t = (h / eta_p).clamp(-1.0, 1.0);
        let cos_gamma_t = (1.0 - sin_gamma_t * sin_gamma_t).max(0.0).sqrt();
        let gamma_t = fastmath::atan2(sin_gamma_t, cos_gamma_t);
        let transmittance = SampledSpectrum(
            self.sigma_a
                .0
                .map(|s| fastmath::exp(-s * 2.0 * cos_gamma_t / cos_theta_t)),
        );
        let cos_gamma_o = (1.0 - h * h).max(0.0).sqrt();
        let f = fresnel_dielectric(cos_theta_o * cos_gamma_o, self.eta);
        let a0 = SampledSpectrum::splat(f);
        let a1 = transmittance * ((1.0 - f) * (1.0 - f));
        let a2 = a1 * transmittance * f;
        let tf = transmittance * f;
        let a3 = SampledSpectrum(a2.0 * tf.0 / (Vec4::ONE - tf.0));
        let a = [a0, a1, a2, a3];
        let lum = a.map(|x| (x.0 * self.luminance).element_sum().max(0.0));
        let total: f32 = lum.iter().sum();
        let a_pdf = if total > 0.0 && total.is_finite() {
            lum.map(|l| l / total)
        } else {
            [1.0, 0.0, 0.0, 0.0]
        };
        Setup {
            sin_theta_o,
            cos_theta_o,
            phi_o,
            gamma_o,
            gamma_t,
            a,
            a_pdf,
        }
    }

    /// The value `f |wi.z|` (as Mitsuba's eval) and the pdf of `wi`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn value_pdf(&self, st: &Setup, wi: Vec3) -> (SampledSpectrum, f32) {
        let sin_theta_i = wi.y.clamp(-1.0, 1.0);
        let cos_theta_i = (1.0 - sin_theta_i * sin_theta_i).max(0.0).sqrt();
        let phi = fastmath::atan2(wi.z, wi.x) - st.phi_o;
        let mut value = SampledSpectrum::ZERO;
        let mut pdf = 0.0;
        for p in 0..P_MAX {
            let (sin_op, cos_op) = self.tilt(st.sin_theta_o, st.cos_theta_o, p);
            let m = self.lobe(p).eval(sin_op, cos_op, sin_theta_i, cos_theta_i);
            let n = self.azimuthal(phi, p, st.gamma_o, st.gamma_t);
            value += st.a[p] * (m * n);
            pdf += st.a_pdf[p] * m * n;
        }
        let m = self
            .lobe(P_MAX)
            .eval(st.sin_theta_o, st.cos_theta_o, sin_theta_i, cos_theta_i)
            / TAU;
        value += st.a[P_MAX] * m;
        pdf += st.a_pdf[P_MAX] * m;
        if !value.is_finite() {
            value = SampledSpectrum::ZERO;
        }
        (value, if pdf.is_finite() { pdf } else { 0.0 })
    }

    /// The longitudinal lobe of segment count `p`.
    #[inline]
    fn lobe(&self, p: usize) -> Longitudinal {
        Longitudinal {
            inv_v: self.inv_v0 * LOBE_INV_V[p],
            norm: self.m_norm[p],
        }
    }

    /// Trimmed logistic azimuthal lobe of segment count `p` at azimuth difference `phi`.
    #[inline]
    fn azimuthal(&self, phi: f32, p: usize, gamma_o: f32, gamma_t: f32) -> f32 {
        let pf = p as f32;
        let mut x = phi - (2.0 * pf * gamma_t - 2.0 * gamma_o + pf * PI);
        x = (x + PI).rem_euclid(TAU) - PI;
        self.n.density(x)
    }

    /// f(wo, wi) without the cosine (local frame: fibre along y, normal z).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let cos = wi.z.abs();
        if !(cos > 0.0) {
            return SampledSpectrum::ZERO;
        }
        let (value, _) = self.value_pdf(&self.setup(wo), wi);
        value * (1.0 / cos)
    }

    /// Solid-angle pdf of sampling `wi` given `wo`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.value_pdf(&self.setup(wo), wi).1
    }

    /// [`Hair::eval`] and [`Hair::pdf`] from one setup for `wo` and one pass over the lobes
    /// (each call alone does both): the same values.
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (SampledSpectrum, f32) {
        self.eval_pdf_with(&self.setup(wo), wi)
    }

    /// [`Hair::eval_pdf`] of `wi` and [`Hair::sample`] from one setup for `wo` (the setup's
    /// refraction angles, attenuations and lobe weights are a third of the model's cost, and
    /// the path tracer asks for both at every hit): the same values as the two calls.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn eval_pdf_and_sample(
        &self,
        wo: Vec3,
        wi: Vec3,
        u_lobe: f32,
        u: Vec2,
    ) -> ((SampledSpectrum, f32), Option<BsdfSample>) {
        let st = self.setup(wo);
        (
            self.eval_pdf_with(&st, wi),
            self.sample_with(&st, u_lobe, u),
        )
    }

    /// [`Hair::eval_pdf`] given the setup for `wo`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn eval_pdf_with(&self, st: &Setup, wi: Vec3) -> (SampledSpectrum, f32) {
        let (value, pdf) = self.value_pdf(st, wi);
        let cos = wi.z.abs();
        if !(cos > 0.0) {
            return (SampledSpectrum::ZERO, pdf);
        }
        (value * (1.0 / cos), pdf)
    }

    /// Samples `wi`: `u_lobe` picks the segment count (and is reused for the azimuth), `u` the
    /// longitudinal angle and its azimuth about the tilted cone.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        self.sample_with(&self.setup(wo), u_lobe, u)
    }

    /// [`Hair::sample`] given the setup for `wo`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn sample_with(&self, st: &Setup, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        // Pick p; rescale u_lobe within the chosen interval for the azimuth.
        let mut p = P_MAX;
        let mut rest = u_lobe;
        for (k, &q) in st.a_pdf.iter().enumerate() {
            if rest < q || k == P_MAX {
                p = k;
                rest = if q > 0.0 {
                    (rest / q).clamp(0.0, 1.0 - f32::EPSILON / 2.0)
                } else {
                    0.0
                };
                break;
            }
            rest -= q;
        }
        let (sin_op, cos_op) = self.tilt(st.sin_theta_o, st.cos_theta_o, p);
        // Longitudinal (d'Eon et al. 2011): cos of the angle to the reflected cone's axis.
        let v = self.lobe(p).v();
        let u0 = u.x.max(1e-5);
        let cos_t = 1.0 + v * (u0 + (1.0 - u0) * fastmath::exp(-2.0 / v)).ln();
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let cos_phi = fastmath::sin_cos_turns(u.y).1;
        let sin_theta_i = (-cos_t * sin_op + sin_t * cos_phi * cos_op).clamp(-1.0, 1.0);
        let cos_theta_i = (1.0 - sin_theta_i * sin_theta_i).max(0.0).sqrt();
        let dphi = if p < P_MAX {
            let pf = p as f32;
            2.0 * pf * st.gamma_t - 2.0 * st.gamma_o + pf * PI + self.n.sample(rest)
        } else {
            TAU * rest
        };
        let phi_i = st.phi_o + dphi;
        // In radians, not `fastmath::sin_cos_turns(phi_i / TAU)`: that gives sin exactly 0 where
        // phi_i / TAU rounds to a multiple of 1/2, a direction with wi.z = 0 exactly, which
        // `eval` counts as zero (the stability sweep's weight check found one at grazing
        // incidence with roughness 0).
        let (sin_phi_i, cos_phi_i) = phi_i.sin_cos();
        let wi = Vec3::new(
            cos_theta_i * cos_phi_i,
            sin_theta_i,
            cos_theta_i * sin_phi_i,
        );
        let (value, pdf) = self.value_pdf(st, wi);
        if !(pdf > 0.0) {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: value * (1.0 / pdf),
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}

/// The longitudinal lobes' 1 / v relative to the first's: v_p = v_0, v_0 / 4, 4 v_0, 4 v_0
/// (Chiang et al. 2016, section 4.1; powers of two, so 1 / v_p is exactly `1 / v_0` scaled).
const LOBE_INV_V: [f32; P_MAX + 1] = [1.0, 4.0, 0.25, 0.25];

/// d'Eon et al. 2011's longitudinal scattering function (eq. 7) of one variance `v`:
/// `M(theta_o, theta_i) = e^(-b) I0(a) / (2 v sinh(1 / v))` with `a = cos theta_o cos theta_i
/// / v`, `b = sin theta_o sin theta_i / v`; the log form for `v <= 0.1` keeps `I0` and `sinh`
/// finite (Chiang et al. 2016, section 4.1). What depends on `v` alone is computed once.
#[derive(Clone, Copy, Debug)]
struct Longitudinal {
    /// 1 / v; the log form is used for 1 / v >= 10.
    inv_v: f32,
    /// The normalisation 1 / (2 v sinh(1 / v)), or in the log form its logarithm, whose
    /// leading terms are -1/v - ln v (2 sinh(1/v) = e^(1/v) (1 - e^(-2/v)), the last factor
    /// 1 to within f32 for v <= 0.1: e^-20 = 2e-9).
    norm: f32,
}

impl Longitudinal {
    fn new(v: f32) -> Self {
        let inv_v = 1.0 / v;
        let norm = if inv_v >= 10.0 {
            -inv_v - v.ln()
        } else {
            // 2 v sinh(1 / v) = v (e^{1/v} - e^{-1/v}); 1 / v < 10 here, so neither overflows.
            1.0 / (v * (fastmath::exp(inv_v) - fastmath::exp(-inv_v)))
        };
        Longitudinal { inv_v, norm }
    }

    /// The variance v.
    fn v(&self) -> f32 {
        1.0 / self.inv_v
    }

    /// M between directions of longitudinal angles `theta_o` and `theta_i` (their sines and
    /// cosines).
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn eval(&self, sin_o: f32, cos_o: f32, sin_i: f32, cos_i: f32) -> f32 {
        let a = cos_o * cos_i * self.inv_v;
        let b = sin_o * sin_i * self.inv_v;
        if self.inv_v >= 10.0 {
            fastmath::exp(log_i0(a) - b + self.norm)
        } else {
            fastmath::exp(-b) * i0(a) * self.norm
        }
    }
}

/// Modified Bessel function of the first kind, order 0, for x >= 0, by the polynomial
/// approximations of Abramowitz and Stegun (1964) 9.8.1 (x <= 3.75: a polynomial in
/// (x / 3.75)^2, error below 1.6e-7) and 9.8.2 (above: `e^x / sqrt(x)` times a polynomial in
/// 3.75 / x, relative error below 5e-7), their coefficients written as the f32 values they
/// round to. A fixed length and no division per term, where the power series, summed until
/// its terms stopped counting, took a division per term. (Mitsuba and pbrt-v4 sum ten terms
/// of the series, which is 0.6% low at x = 12, and take an asymptotic form above.)
#[inline]
fn i0(x: f32) -> f32 {
    if x <= 3.75 {
        i0_small(x)
    } else {
        fastmath::exp(x) / x.sqrt() * i0_large_scaled(x)
    }
}

/// ln I0(x) for x >= 0, as [`i0`] computes it, without forming `e^x` (finite for any x).
#[inline]
fn log_i0(x: f32) -> f32 {
    if x <= 3.75 {
        i0_small(x).ln()
    } else {
        x - 0.5 * x.ln() + i0_large_scaled(x).ln()
    }
}

/// Abramowitz and Stegun 9.8.1: I0(x) for x <= 3.75.
#[inline(always)]
fn i0_small(x: f32) -> f32 {
    let t = (x * (1.0 / 3.75)) * (x * (1.0 / 3.75));
    1.0 + t
        * (3.515_622_9
            + t * (3.089_942_5
                + t * (1.206_749_2 + t * (0.265_973_2 + t * (0.036_076_8 + t * 0.004_581_3)))))
}

/// Abramowitz and Stegun 9.8.2: `sqrt(x) e^-x I0(x)` for x >= 3.75.
#[inline(always)]
fn i0_large_scaled(x: f32) -> f32 {
    let r = 3.75 / x;
    0.398_942_3
        + r * (0.013_285_92
            + r * (0.002_253_19
                + r * (-0.001_575_65
                    + r * (0.009_162_81
                        + r * (-0.020_577_06
                            + r * (0.026_355_37 + r * (-0.016_476_33 + r * 0.003_923_77)))))))
}

/// The logistic density of scale `s` at `x`.
#[inline]
fn logistic(x: f32, s: f32) -> f32 {
    let e = fastmath::exp(-x.abs() / s);
    e / (s * (1.0 + e) * (1.0 + e))
}

/// The logistic cumulative distribution of scale `s` at `x`.
#[inline]
fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + fastmath::exp(-x / s))
}

/// The logistic of scale `s` restricted to [-pi, pi] and renormalised (d'Eon et al. 2011's
/// azimuthal lobe, as Chiang et al. 2016 sample it), with its mass on [-pi, pi] computed once.
#[derive(Clone, Copy, Debug)]
struct TrimmedLogistic {
    s: f32,
    /// The logistic's CDF at -pi.
    cdf_lo: f32,
    /// Its mass on [-pi, pi].
    mass: f32,
}

impl TrimmedLogistic {
    fn new(s: f32) -> Self {
        let cdf_lo = logistic_cdf(-PI, s);
        TrimmedLogistic {
            s,
            cdf_lo,
            mass: logistic_cdf(PI, s) - cdf_lo,
        }
    }

    /// The density at `x` in [-pi, pi].
    #[inline]
    fn density(&self, x: f32) -> f32 {
        logistic(x, self.s) / self.mass
    }

    /// The inverse CDF at `u` in [0, 1).
    #[inline]
    fn sample(&self, u: f32) -> f32 {
        let x = -self.s * (1.0 / (u * self.mass + self.cdf_lo) - 1.0).ln();
        x.clamp(-PI, PI)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `eval_pdf` gives exactly `eval` and `pdf` over random directions on both sides.
    #[test]
    fn eval_pdf_is_eval_and_pdf() {
        let rgb = Vec4::new(0.212_671, 0.715_160, 0.072_169, 0.0);
        let sigma_a = SampledSpectrum::from_rgb(Hair::pigment_sigma_a_rgb(1.3, 0.2));
        let h = Hair::new(sigma_a, rgb, 1.55, 0.3, 0.3, 2.0);
        crate::check_eval_pdf(
            31,
            5_000,
            |a, b| h.eval_pdf(a, b),
            |a, b| h.eval(a, b),
            |a, b| h.pdf(a, b),
        );
    }

    /// I0 and ln I0 against the power series summed in f64 to convergence, on [0, 40]
    /// (beyond what the longitudinal term's direct form uses, 10, and into its log form's
    /// range): within 6e-7 relative (Abramowitz and Stegun's bounds, 1.6e-7 and 5e-7, and f32's
    /// roundings), and ln I0 within 6e-7 relative (absolute below 1, where it nears 0). A wrong
    /// coefficient is 1e-5 off or more.
    #[test]
    fn i0_matches_its_series() {
        for i in 0..=40_000 {
            let x = i as f32 / 1000.0;
            let q = 0.25 * f64::from(x) * f64::from(x);
            let (mut sum, mut term, mut k) = (1.0f64, 1.0f64, 1.0f64);
            while term > 1e-18 * sum {
                term *= q / (k * k);
                sum += term;
                k += 1.0;
            }
            let rel = (f64::from(i0(x)) - sum).abs() / sum;
            assert!(rel < 6e-7, "I0({x}) = {} vs {sum}: {rel:e}", i0(x));
            let err = (f64::from(log_i0(x)) - sum.ln()).abs();
            let bound = 6e-7 * sum.ln().max(1.0);
            assert!(
                err < bound,
                "ln I0({x}) = {} vs {}: {err:e}",
                log_i0(x),
                sum.ln()
            );
        }
    }

    /// The trimmed logistic integrates to 1 on [-pi, pi] and its sampler inverts its CDF.
    #[test]
    fn trimmed_logistic_is_normalised_and_inverted() {
        for s in [0.05f32, 0.3, 1.5] {
            let n = 20_000;
            let h = TAU / n as f32;
            let integral: f32 = (0..n)
                .map(|i| TrimmedLogistic::new(s).density(-PI + (i as f32 + 0.5) * h) * h)
                .sum();
            assert!((integral - 1.0).abs() < 1e-3, "s {s}: {integral}");
            let k = logistic_cdf(PI, s) - logistic_cdf(-PI, s);
            for u in [0.1f32, 0.5, 0.93] {
                let x = TrimmedLogistic::new(s).sample(u);
                let cdf = (logistic_cdf(x, s) - logistic_cdf(-PI, s)) / k;
                assert!((cdf - u).abs() < 1e-4, "s {s} u {u}: {cdf}");
            }
        }
    }

    /// M integrates to 1 over the sphere of outgoing directions for any incoming one (d'Eon's
    /// normalisation: over theta_i with cos theta_i dtheta_i, times the azimuth's 2 pi counted
    /// by N), in both the direct and the log form.
    #[test]
    fn longitudinal_is_normalised() {
        for v in [0.02f32, 0.09, 0.11, 0.5, 2.0] {
            for theta_o in [-1.2f32, 0.0, 0.7] {
                let n = 20_000;
                let h = PI / n as f32;
                let integral: f64 = (0..n)
                    .map(|i| {
                        let t = -0.5 * PI + (i as f32 + 0.5) * h;
                        (Longitudinal::new(v).eval(theta_o.sin(), theta_o.cos(), t.sin(), t.cos())
                            * t.cos()
                            * h) as f64
                    })
                    .sum();
                assert!(
                    (integral - 1.0).abs() < 2e-3,
                    "v {v} theta_o {theta_o}: {integral}"
                );
            }
        }
    }

    /// Values of Mitsuba 3.9.1's `hair` (scalar_rgb; `eval` is f |cos| there, and `pdf`) for four
    /// parameter sets and direction pairs, read with the shading frame set to the identity
    /// (fibre along y): the defaults head-on and at h = 0.7 tilted 30 degrees, pigments with
    /// b_m 0.2, b_n 0.5 and a 3-degree tilt, and an RGB `sigma_a` of (0.2, 0.5, 1.1). pt's
    /// f |wi.z| and pdf are Mitsuba's times 1.0035-1.0037, 1.00005, 1.0006 and 1.0004-1.0009:
    /// the differences are Mitsuba's I0, its ten-term series low by up to 0.6% for arguments
    /// 8-12 (case 1: v_0 = 0.085, arguments up to 11.8) and its one-term asymptotic form above
    /// 12 (9 / (128 x^2) low: 4e-4 at 13); the case without such arguments agrees to 5e-5. So
    /// 5e-3: a wrong lobe, attenuation or pdf weight is off by far more.
    #[test]
    #[allow(clippy::excessive_precision)] // Mitsuba's printed values, kept as read.
    fn matches_mitsuba() {
        let n = |v: [f32; 3]| Vec3::from_array(v).normalize();
        let rgb = Vec4::new(0.212_671, 0.715_160, 0.072_169, 0.0);
        let eta = 1.55 / 1.000_277;
        let pig = |e, p| SampledSpectrum::from_rgb(Hair::pigment_sigma_a_rgb(e, p));
        let cases = [
            (
                Hair::new(pig(1.3, 0.2), rgb, eta, 0.3, 0.3, 2.0),
                [0.0, 0.0, 1.0],
                [0.309426, -0.206284, 0.928279],
                [
                    0.021463049575686455,
                    0.020285239443182945,
                    0.01999933086335659,
                ],
                0.1025695651769638,
            ),
            (
                Hair::new(pig(1.3, 0.2), rgb, eta, 0.3, 0.3, 2.0),
                [0.605926, 0.5, 0.618751],
                [-0.620174, -0.744208, 0.248069],
                [
                    0.01213117130100727,
                    0.01211291179060936,
                    0.012110928073525429,
                ],
                0.05371307581663132,
            ),
            (
                Hair::new(pig(0.3, 0.6), rgb, eta, 0.2, 0.5, 3.0),
                [-0.813798, -0.34202, 0.469846],
                [0.116248, 0.348743, -0.929981],
                [1.844742774963379, 1.2806464433670044, 0.46082359552383423],
                2.609203338623047,
            ),
            (
                Hair::new(
                    SampledSpectrum::from_rgb([0.2, 0.5, 1.1]),
                    rgb,
                    eta,
                    0.5,
                    0.3,
                    2.0,
                ),
                [-0.17101, 0.173648, 0.969846],
                [0.980196, -0.140028, 0.140028],
                [
                    6.32695882814005e-05,
                    1.777702163963113e-05,
                    7.694073246966582e-06,
                ],
                6.201711221365258e-05,
            ),
        ];
        for (k, (h, wo, wi, value, pdf)) in cases.into_iter().enumerate() {
            let (wo, wi) = (n(wo), n(wi));
            let f = h.eval(wo, wi) * wi.z.abs();
            for c in 0..3 {
                let got = f.0[c];
                assert!(
                    (got / value[c] - 1.0).abs() < 5e-3,
                    "case {k} channel {c}: {got} vs Mitsuba {}",
                    value[c]
                );
            }
            let p = h.pdf(wo, wi);
            assert!(
                (p / pdf - 1.0).abs() < 5e-3,
                "case {k}: pdf {p} vs Mitsuba {pdf}"
            );
        }
    }
}
