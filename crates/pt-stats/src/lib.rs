//! Statistical tests of the `pt` renderer, used by the command line (`pt compare`, `pt
//! stability`), the analysis library (`pt-lab`) and the tests (`pt-testkit`, `tests/`):
//!
//! - [`special`]: erfc, ln Gamma, the regularized incomplete gamma function and the normal and
//!   chi-square tails they give, and Šidák's per-test level ([`sidak_threshold`]).
//! - [`ztest`]: whether a render matches its reference given the variance of both images'
//!   pixel means: [`block_ztest`] (per block, the pass/fail test) and [`pixel_ztest`] (per
//!   pixel, a diagnostic).
//! - [`chi2`]: Mitsuba 3's `chi2.py` test of a direction sampler against its claimed pdf
//!   ([`chi2_sphere`]). Sampled directions are binned over the whole sphere in a grid of cells
//!   uniform in (cos theta, phi) (equal solid angle, since d omega = d(cos theta) d phi); the
//!   expected count of a cell is `N` times the pdf integrated over it by adaptive Simpson
//!   quadrature ([`integrate_cells`]); cells with expected count below 20 (Mitsuba: 5; see
//!   [`Chi2Config::min_expected`]) are pooled in increasing order of expectation so that
//!   Pearson's statistic is close to chi-square distributed ([`pooled_chi2`]); a sampler that
//!   fails (returns `None`) is counted in one extra cell whose expectation is
//!   `N (1 - integral of pdf)`, so a sampler that loses probability the pdf does not account for
//!   fails too. [`Chi2Report::check`] applies a Šidák-corrected level over all tests of a grid.
//! - [`sphere`] and [`rng`]: directions from polar angles, integrals over cells of the sphere,
//!   and the fixed-seed PCG32 every test draws from.
//!
//! The sampler tests take closures, so any sampler can be tested: `sample(wo, u) ->
//! Option<Sample>` with `u` in [0,1)^3 (`u.x` for the lobe choice, `u.y, u.z` for the
//! direction) and `pdf(wo, wi) -> f32` per unit solid angle, directions in the sampler's local
//! frame (z = the normal). Randomness comes from a fixed-seed PCG32, so every test is
//! deterministic: a statistical test that passes passes every time, and its threshold is a
//! statement about how unlikely a correct sampler would be to fail for a *random* seed.
//!
//! The BSDF test helpers built on this (white furnace, reciprocity, delta lobes) are in
//! `pt-testkit`, which is for tests only; this crate is part of the `pt` binary.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod chi2;
pub mod rng;
pub mod special;
pub mod sphere;
pub mod ztest;

pub use chi2::{chi2_sphere, pooled_chi2, Chi2Config, Chi2Report, Chi2Result, Sample};
pub use rng::Pcg32;
pub use special::{chi2_sf, erf, erfc, gamma_q, ln_gamma, normal_sf, sidak_threshold};
pub use sphere::{dir_deg, integrate_cells, spherical};
pub use ztest::{block_ztest, pixel_ztest, PixelZTest, ZTestReport, ROUNDING_REL};
