//! The Hosek-Wilkie sun and sky (Mitsuba 3's `sunsky` emitter): the sky's and the sun's
//! radiance in RGB and spectral mode ([`SkyModel`]), and the sun's position at a date and place
//! ([`solar::sun_direction`]). Rendering (sampling, frames, the scene) is pt-render's.
//!
//! The coefficient tables are the authors' published data (BSD-3; `data/`).

mod model;
pub mod solar;
pub mod tables;

pub use model::{SkyModel, SkyParams, SUN_HALF_APERTURE};
