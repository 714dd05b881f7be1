//! The error type of this crate.

use std::path::PathBuf;

/// Everything that can go wrong reading, writing or comparing images.
///
/// Every variant that concerns a file names it; comparisons of in-memory images name the roles
/// of the images instead (for example "image" and "reference"), which the caller can map to files.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImageError {
    /// An operating-system I/O error (file missing, directory missing, permission, disk full).
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// What was being done, e.g. "open file" or "rename temporary file over target".
        action: &'static str,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },

    /// The file is not a valid EXR (truncated, corrupt, unsupported).
    #[error("{}: cannot read EXR: {source}", path.display())]
    ExrRead {
        /// The file concerned.
        path: PathBuf,
        /// The error reported by the `exr` crate.
        #[source]
        source: exr::error::Error,
    },

    /// The EXR encoder failed.
    #[error("{}: cannot write EXR: {source}", path.display())]
    ExrWrite {
        /// The file concerned.
        path: PathBuf,
        /// The error reported by the `exr` crate.
        #[source]
        source: exr::error::Error,
    },

    /// The EXR has no layer with R, G and B channels (nor a single luminance channel).
    #[error(
        "{}: no layer with R, G and B channels (or a Y luminance channel); channels present: [{}]",
        path.display(),
        channels.join(", ")
    )]
    MissingChannels {
        /// The file concerned.
        path: PathBuf,
        /// All channel names found in the file, as `layer.channel` where the layer has a name.
        channels: Vec<String>,
    },

    /// The EXR uses a layout this reader does not handle (e.g. subsampled colour channels).
    #[error("{}: unsupported EXR layout: {reason}", path.display())]
    Unsupported {
        /// The file concerned.
        path: PathBuf,
        /// What is unsupported.
        reason: String,
    },

    /// The EXR library panicked on this file (a bug in it, most likely on corrupt input);
    /// the panic was caught and turned into this error.
    #[error("{}: EXR decoder failed on this file (internal panic: {message})", path.display())]
    DecoderPanic {
        /// The file concerned.
        path: PathBuf,
        /// The panic message, if it was a string.
        message: String,
    },

    /// The PNG encoder failed.
    #[error("{}: cannot write PNG: {source}", path.display())]
    Png {
        /// The file concerned.
        path: PathBuf,
        /// The error reported by the `image` crate.
        #[source]
        source: image::ImageError,
    },

    /// Metadata cannot be stored in an EXR header (non-Latin-1 text, reserved attribute name...).
    #[error("{}: invalid metadata: {reason}", path.display())]
    InvalidMeta {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },

    /// An image is malformed (pixel count does not match its size, or it is empty where that is
    /// not allowed). `what` names the file or the image's role.
    #[error("{what}: invalid image: {reason}")]
    InvalidImage {
        /// The file path or the image's role (e.g. "reference variance").
        what: String,
        /// What is wrong.
        reason: String,
    },

    /// Two images that must have the same size do not.
    #[error("{what} is {width}x{height} but {other} is {other_width}x{other_height}")]
    SizeMismatch {
        /// Role of the first image (e.g. "image").
        what: String,
        /// Width of the first image.
        width: u32,
        /// Height of the first image.
        height: u32,
        /// Role of the second image (e.g. "reference").
        other: String,
        /// Width of the second image.
        other_width: u32,
        /// Height of the second image.
        other_height: u32,
    },

    /// A parameter is out of its domain (block size 0, alpha outside (0, 1)...).
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
}

impl ImageError {
    pub(crate) fn io(
        path: impl Into<PathBuf>,
        action: &'static str,
        source: std::io::Error,
    ) -> Self {
        Self::Io {
            path: path.into(),
            action,
            source,
        }
    }
}
