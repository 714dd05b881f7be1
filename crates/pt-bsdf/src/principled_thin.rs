//! Mitsuba 3.9.1's `principledthin`: the thin-surface variant of its principled BSDF (Burley
//! 2015, "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering", section
//! 5.2 "Thin-surface BSDF"), with the constants, lobe weights and sampling of the code Mitsuba
//! 3.9.1 ships. Two-sided and symmetric: both directions are flipped so that the viewer is
//! above the surface, and light passes through without bending (relative index 1 along every
//! path).
//!
//! With `st = spec_trans`, `dt = diff_trans / 2`, `h` the half vector of the viewer and the
//! light mirrored to the viewer's side, `F` the dielectric Fresnel reflectance at `wo.h`:
//!
//! 1. **Specular reflection**: `st F_thin D_r(h) G_r / (4 cos_o cos_i)`, GGX of the principled
//!    alphas, `F_thin = (1 - spec_tint) F + spec_tint Schlick(c_tint R0(eta))`.
//! 2. **Thin specular transmission**: the same reflection mirrored through the surface,
//!    `st base_color (1 - F) D_t(h) G_t / (4 cos_o |cos_i|)`, with a GGX whose roughness is
//!    scaled by `0.65 eta - 0.35` (Burley 2015, figure 15).
//! 3. **Diffuse reflection**: `(1 - st)(1 - dt) base_color / pi` times the Burley diffuse of
//!    [`crate::principled::burley_diffuse`] (retro-reflection, `flatness`), plus sheen
//!    `(1 - st)(1 - dt) sheen SW(|cos_d|) c_sheen`.
//! 4. **Diffuse transmission**: `(1 - st) dt base_color / pi`.
//!
//! Sampling picks a lobe with constant probabilities proportional to `st rate_sr / 2`, `st
//! rate_st / 2`, `(1 - st)(1 - dt) rate_dr` and `(1 - st) dt rate_dt`; the pdf is their
//! mixture (one-sample MIS).
//!
//! | parameter | type | default | range / unit |
//! |---|---|---|---|
//! | `base_color` | spectrum or texture | 0.5 | albedo in [0, 1] |
//! | `roughness`, `anisotropic` | float or texture | 0.5, 0 | as `principled` |
//! | `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`, `flatness` | float or texture | 0 | [0, 1] |
//! | `diff_trans` | float or texture | 0 | [0, 2] (halved internally) |
//! | `eta` | float or texture | 1.5 | relative index of the sheet |
//! | `specular_reflectance_sampling_rate`, `specular_transmittance_sampling_rate`, `diffuse_reflectance_sampling_rate`, `diffuse_transmittance_sampling_rate` | float | 1 | lobe selection weights |

use crate::fresnel::fresnel_dielectric;
use crate::microfacet::Microfacet;
use crate::principled::{burley_diffuse, r0, schlick_fresnel, schlick_weight, tint_color};
use crate::{map_lanes, BsdfSample};
use pt_math::warp::square_to_cosine_hemisphere;
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use std::f32::consts::FRAC_1_PI;

/// The `principledthin` BSDF at one shading point (see the module doc).
#[derive(Clone, Copy, Debug)]
pub struct PrincipledThin {
    /// Base colour, albedo per lane.
    pub base_color: SampledSpectrum,
    /// Luminance of the base colour, which the tints divide by.
    pub luminance: f32,
    /// Roughness in [0, 1] (the diffuse retro-reflection).
    pub roughness: f32,
    /// Specular transmission weight `st`.
    pub spec_trans: f32,
    /// Tint of the specular reflection towards the base colour.
    pub spec_tint: f32,
    /// Sheen weight.
    pub sheen: f32,
    /// Tint of the sheen.
    pub sheen_tint: f32,
    /// Blend towards the fake subsurface diffuse.
    pub flatness: f32,
    /// Diffuse transmission weight `dt` (Mitsuba's `diff_trans` / 2).
    pub diff_trans: f32,
    /// Relative index of the sheet.
    pub eta: f32,
    /// GGX of the specular reflection.
    pub mf_r: Microfacet,
    /// GGX of the thin transmission (roughness scaled by 0.65 eta - 0.35).
    pub mf_t: Microfacet,
    /// Lobe selection weights: specular reflection, specular transmission, diffuse reflection,
    /// diffuse transmission.
    pub rates: [f32; 4],
}

/// The lobe-selection probabilities (specular reflection, specular transmission, diffuse
/// reflection, diffuse transmission), normalised; constant per shading point.
fn probabilities(b: &PrincipledThin) -> [f32; 4] {
    let [rsr, rst, rdr, rdt] = b.rates;
    let (st, dt) = (b.spec_trans, b.diff_trans);
    let p = [
        st * rsr * 0.5,
        st * rst * 0.5,
        rdr * (1.0 - st) * (1.0 - dt),
        rdt * (1.0 - st) * dt,
    ];
    let sum: f32 = p.iter().sum();
    if sum > 0.0 {
        p.map(|x| x / sum)
    } else {
        [0.0; 4]
    }
}

impl PrincipledThin {
    /// The tint colour of this shading point ([`tint_color`]).
    #[inline]
    fn tint_color(&self) -> SampledSpectrum {
        tint_color(self.base_color, self.luminance)
    }

    /// Both directions flipped so that the viewer is above the surface, and the half vector of
    /// the viewer and the light mirrored to its side.
    #[inline]
    fn frame(wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
        if wo.z == 0.0 || wi.z == 0.0 {
            return None;
        }
        let s = wo.z.signum();
        let (wo, wi) = (wo * s, wi * s);
        let mirrored = Vec3::new(wi.x, wi.y, wi.z.abs());
        let h = (wo + mirrored).try_normalize()?;
        Some((wo, wi, h))
    }

    /// f(wo, wi) without the cosine, local frame (Mitsuba's `eval` over |cos theta_i|).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let Some((wo, wi, h)) = Self::frame(wo, wi) else {
            return SampledSpectrum::ZERO;
        };
        let (cos_o, cos_i) = (wo.z, wi.z);
        let reflect = cos_i > 0.0;
        let (st, dt) = (self.spec_trans, self.diff_trans);
        let mut v = SampledSpectrum::ZERO;
        let (oh, ih) = (wo.dot(h), wi.dot(h));
        if st > 0.0 {
            let f = fresnel_dielectric(oh, self.eta);
            if reflect && oh > 0.0 && ih > 0.0 {
                let tinted = map_lanes(self.tint_color() * r0(self.eta), |t| {
                    schlick_fresnel(t, oh, self.eta)
                });
                let f_thin =
                    SampledSpectrum::splat((1.0 - self.spec_tint) * f) + tinted * self.spec_tint;
                let dg = self.mf_r.d(h) * self.mf_r.g1(wo) * self.mf_r.g1(wi);
                v += f_thin * (st * dg / (4.0 * cos_o * cos_i));
            }
            if !reflect && oh > 0.0 && ih < 0.0 {
                let dg = self.mf_t.d(h) * self.mf_t.g1(wo) * self.mf_t.g1(wi);
                v += self.base_color * (st * (1.0 - f) * dg / (4.0 * cos_o * cos_i.abs()));
            }
        }
        if reflect && st < 1.0 && dt < 1.0 {
            let w = (1.0 - st) * (1.0 - dt);
            let d = burley_diffuse(self.roughness, self.flatness, (cos_i, cos_o), ih);
            v += self.base_color * (w * FRAC_1_PI * d);
            if self.sheen > 0.0 {
                let c_sheen = SampledSpectrum::splat(1.0 - self.sheen_tint)
                    + self.tint_color() * self.sheen_tint;
                v += c_sheen * (w * self.sheen * schlick_weight(ih.abs()));
            }
        }
        if !reflect && st < 1.0 && dt > 0.0 {
            v += self.base_color * ((1.0 - st) * dt * FRAC_1_PI);
        }
        if v.is_finite() {
            v
        } else {
            SampledSpectrum::ZERO
        }
    }

    /// Solid-angle pdf of `wi`: the mixture of the lobes' densities.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some((wo, wi, h)) = Self::frame(wo, wi) else {
            return 0.0;
        };
        let [p_sr, p_st, p_dr, p_dt] = probabilities(self);
        let reflect = wi.z > 0.0;
        let (oh, ih) = (wo.dot(h), wi.dot(h));
        let mut pdf = 0.0;
        if self.spec_trans > 0.0 && oh > 0.0 {
            let jacobian = 1.0 / (4.0 * oh);
            if reflect && ih > 0.0 {
                pdf += p_sr * self.mf_r.pdf_m(wo, h) * jacobian;
            }
            if !reflect && ih < 0.0 {
                pdf += p_st * self.mf_t.pdf_m(wo, h) * jacobian;
            }
        }
        pdf += if reflect {
            p_dr * wi.z * FRAC_1_PI
        } else {
            p_dt * -wi.z * FRAC_1_PI
        };
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// Chooses a lobe with `u_lobe` and draws `wi` from it with `u`.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let s = wo.z.signum();
        let wo_up = wo * s;
        let [p_sr, p_st, p_dr, _] = probabilities(self);
        let reflect_about = |m: Vec3| 2.0 * wo_up.dot(m) * m - wo_up;
        let local = if u_lobe < p_sr {
            let m = self.mf_r.sample_m(wo_up, u);
            let wi = reflect_about(m);
            (wo_up.dot(m) > 0.0 && wi.dot(m) > 0.0 && wi.z > 0.0).then_some(wi)?
        } else if u_lobe < p_sr + p_st {
            let m = self.mf_t.sample_m(wo_up, u);
            let r = reflect_about(m);
            let wi = Vec3::new(r.x, r.y, -r.z);
            (wo_up.dot(m) > 0.0 && wi.dot(m) < 0.0 && wi.z < 0.0).then_some(wi)?
        } else if u_lobe < p_sr + p_st + p_dr {
            square_to_cosine_hemisphere(u)
        } else {
            -square_to_cosine_hemisphere(u)
        };
        let wi = local * s;
        let pdf = self.pdf(wo, wi);
        if !(pdf > 0.0) {
            return None;
        }
        let weight = self.eval(wo, wi) * (wi.z.abs() / pdf);
        weight.is_finite().then_some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}
