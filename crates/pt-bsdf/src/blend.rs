//! A mixture of two models (Mitsuba's `blendbsdf`): `f = (1 - w) f_a + w f_b` for a weight
//! `w` in [0, 1], the same in every lane.
//!
//! `eval` and `pdf` are the exact mixtures, `(1 - w) f_a + w f_b` and `(1 - w) p_a + w p_b`
//! (done by [`crate::SurfaceBsdf`], which holds the second model in its `blend` field).
//! `sample` picks model b with probability `w` (else a) using the lobe number, samples it, and
//! then — for a non-delta sample — reports the *mixture's* pdf and weight `f |cos| / pdf` (the
//! one-sample model of Veach 1997, sec. 9.2.4, with the balance heuristic over the two models),
//! so that MIS against light sampling sees the same pdf that `pdf` returns. A delta sample keeps
//! its model's weight and has discrete probability `w_c p_c` (the other model's delta lobes are
//! taken to point elsewhere; where they coincide the estimate is still unbiased, as a one-sample
//! choice between models).
//!
//! Difference from Mitsuba 3.9: its `blendbsdf` returns the chosen model's own weight and pdf
//! from `sample` (while `eval_pdf` gives the mixture), so its MIS weights for BSDF-sampled hits
//! on emitters use a pdf that differs from the one its light sampling uses: slightly biased where
//! the two models' pdfs differ. Images match where that bias is below the noise.
//!
//! | parameter | type  | default | unit                                      |
//! |-----------|-------|---------|-------------------------------------------|
//! | `weight`  | float | 0.5     | share of the second nested BSDF, in [0, 1] |
//!
//! Mitsuba XML:
//! ```xml
//! <bsdf type="blendbsdf">
//!     <float name="weight" value="0.3"/>
//!     <bsdf type="diffuse"/>
//!     <bsdf type="roughconductor"/>
//! </bsdf>
//! ```

use crate::BsdfSample;
use pt_math::Vec3;
use pt_spectrum::SampledSpectrum;

/// The largest f32 below 1, so a rescaled uniform number stays in [0, 1).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Samples the mixture `(1 - w) a + w b`: `sample_a` / `sample_b` sample one model from a
/// rescaled lobe number, `mixture(wi)` gives the mixture's `(f, pdf)` (local frame, no cosine).
#[inline]
pub fn sample(
    w: f32,
    u_lobe: f32,
    sample_a: impl FnOnce(f32) -> Option<BsdfSample>,
    sample_b: impl FnOnce(f32) -> Option<BsdfSample>,
    mixture: impl FnOnce(Vec3) -> (SampledSpectrum, f32),
) -> Option<BsdfSample> {
    let (mut bs, p_sel) = if u_lobe < w {
        (sample_b((u_lobe / w).min(ONE_MINUS_EPSILON))?, w)
    } else {
        (
            sample_a(((u_lobe - w) / (1.0 - w)).min(ONE_MINUS_EPSILON))?,
            1.0 - w,
        )
    };
    if bs.delta {
        bs.pdf *= p_sel;
        return Some(bs);
    }
    let (f, pdf) = mixture(bs.wi);
    if !(pdf > 0.0) {
        return None;
    }
    bs.weight = f * (bs.wi.z.abs() / pdf);
    bs.pdf = pdf;
    Some(bs)
}
