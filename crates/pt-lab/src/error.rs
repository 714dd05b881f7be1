//! The error type of every analysis: bad settings, scenes or BSDF parameters that do not
//! load, images that cannot be read, files that cannot be written, a Mitsuba run that fails.

use crate::bsdf::BsdfError;
use std::path::PathBuf;

/// What went wrong in an analysis. The message of each variant is complete on its own; the
/// cause, where there is one, is its [`std::error::Error::source`] (printed after it by
/// `anyhow`'s `{:#}`).
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// A setting outside its domain, or input that does not fit the analysis (a reference of
    /// the wrong size, a study without its scene): the message says which and why.
    #[error("{0}")]
    Invalid(String),
    /// A BSDF specification the builder refuses.
    #[error(transparent)]
    Bsdf(#[from] BsdfError),
    /// A scene that does not load (names the file, line and element).
    #[error(transparent)]
    Scene(#[from] pt_scene::SceneError),
    /// A scene that does not build.
    #[error(transparent)]
    Build(#[from] pt_render::BuildError),
    /// Radiosity refused a scene or its parameters.
    #[error(transparent)]
    Radiosity(#[from] pt_radiosity::RadiosityError),
    /// An image that cannot be read, written or compared.
    #[error(transparent)]
    Image(#[from] pt_image::ImageError),
    /// A file or folder operation that failed: `action` is e.g. "cannot write".
    #[error("{action} '{}'", path.display())]
    Io {
        /// What was being done, e.g. "cannot create the folder".
        action: &'static str,
        /// The file or folder.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// A lower-level error with the analysis' own account of what it was doing.
    #[error("{context}")]
    Context {
        /// What was being done, e.g. "cannot read the reference 'ref.exr'".
        context: String,
        /// Why it failed.
        source: Box<LabError>,
    },
    /// A chart that cannot be drawn or encoded.
    #[error("{0}")]
    Chart(String),
    /// Mitsuba 3 (run for `converge`) failed or answered something unexpected.
    #[error("{0}")]
    Mitsuba(String),
}

impl LabError {
    /// This error with `context` in front, as the cause of a [`LabError::Context`].
    pub fn context(self, context: impl Into<String>) -> LabError {
        LabError::Context {
            context: context.into(),
            source: Box::new(self),
        }
    }

    /// An [`LabError::Io`] for `path`.
    pub fn io(action: &'static str, path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        LabError::Io {
            action,
            path: path.into(),
            source,
        }
    }
}

/// Shorthand for results of the analyses.
pub type Result<T, E = LabError> = std::result::Result<T, E>;

/// Creates `dir` and its parents; the error names it as "cannot create `what` 'dir'".
pub fn create_dir(dir: &std::path::Path, action: &'static str) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| LabError::io(action, dir, e))
}
