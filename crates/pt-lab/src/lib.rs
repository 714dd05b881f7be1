//! The analyses behind the `pt` command line, as a library: each takes a plain settings struct
//! and returns its results (data for charts, CSV and Markdown), or writes its files given
//! paths. The command line (`crates/cli`) only turns arguments into settings, calls these,
//! prints and maps errors to exit codes.
//!
//! - [`bsdf`]: a BSDF built from a model name and parameters with the scene format's names and
//!   defaults, without a scene.
//! - [`lobes`]: pictures of a BSDF model (`pt lobes`): polar lobes, albedo, sampling
//!   histogram, hemisphere map.
//! - [`stability`]: the numerical stress sweep of every BSDF model (`pt stability`), with
//!   [`fireflies`], the bias of the firefly clamp.
//! - [`atlas`]: the method failure atlas (`pt atlas`).
//! - [`compare`]: the figures of an image against a reference (`pt compare`).
//! - [`converge`]: error against render time per strategy, and Mitsuba 3 (`pt converge`).
//! - [`chart`]: what the charts share (embedded font, SVG and PNG output, palettes, log ticks).
//!
//! Analyses that render run on the current rayon thread pool (`pool.install(|| ...)` chooses
//! the threads). Every file is written atomically ([`write_atomic`]).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod atlas;
pub mod bsdf;
pub mod chart;
pub mod compare;
pub mod converge;
mod error;
pub mod fireflies;
pub mod lobes;
pub mod stability;

pub use error::{create_dir, LabError, Result};

use std::path::Path;

/// Writes `bytes` to a temporary file beside `path`, then renames it over `path`: readers never
/// see a partial file, and a failed write leaves nothing behind.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            LabError::io("cannot write", path, e)
        })
}
