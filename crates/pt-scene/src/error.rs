//! The loader's error type: a message plus the place in the scene file it is about.

use crate::ir::SourceLoc;

/// An error found while loading a scene, with the file, line, column and element it is about.
///
/// `Display` reads like a compiler message, for example
/// `scenes/foo.xml:12:5: <shape type="obj">: cannot open mesh 'bunny.obj': No such file or directory`.
/// `loc` is `None` only for errors that belong to no file (a bad `-D` argument, an unreadable
/// top-level file).
#[derive(Debug, thiserror::Error)]
#[error("{}", render(.loc.as_ref(), .message))]
pub struct SceneError {
    /// Where the problem is, if it belongs to a place in a file.
    pub loc: Option<SourceLoc>,
    /// What is wrong, without the location prefix.
    pub message: String,
}

fn render(loc: Option<&SourceLoc>, message: &str) -> String {
    match loc {
        Some(loc) => format!("{loc}: {message}"),
        None => message.to_string(),
    }
}

impl SceneError {
    /// An error about the element at `loc`.
    pub(crate) fn at(loc: &SourceLoc, message: impl Into<String>) -> Self {
        SceneError {
            loc: Some(loc.clone()),
            message: message.into(),
        }
    }

    /// An error that belongs to no place in a file.
    pub(crate) fn global(message: impl Into<String>) -> Self {
        SceneError {
            loc: None,
            message: message.into(),
        }
    }
}

/// Shorthand for results of loader functions.
pub(crate) type Result<T> = std::result::Result<T, SceneError>;

/// Formats an I/O error without Rust's " (os error N)" suffix, so messages read like the C
/// library's `strerror` ("No such file or directory").
pub(crate) fn io_message(err: &std::io::Error) -> String {
    let text = err.to_string();
    match text.find(" (os error") {
        Some(cut) => text[..cut].to_string(),
        None => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn display_has_location_prefix() {
        let loc = SourceLoc {
            file: PathBuf::from("scenes/foo.xml"),
            line: 12,
            col: 5,
            element: "shape type=\"obj\"".into(),
        };
        let e = SceneError::at(
            &loc,
            "cannot open mesh 'bunny.obj': No such file or directory",
        );
        assert_eq!(
            e.to_string(),
            "scenes/foo.xml:12:5: <shape type=\"obj\">: cannot open mesh 'bunny.obj': No such file or directory"
        );
        assert_eq!(SceneError::global("bad").to_string(), "bad");
    }

    #[test]
    fn io_message_drops_os_error_code() {
        let err = std::io::Error::from(std::io::ErrorKind::NotFound);
        assert!(!io_message(&err).contains("os error"));
    }
}
