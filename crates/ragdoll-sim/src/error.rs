//! [`Error`]: the one error type of the crate's entry points.
//!
//! The readers and the methods keep their own error types, which say what went wrong
//! and where: [`AfError`] is positioned in a file (`FILE:LINE:COL: error: ...`, the
//! `.af`, `.md5mesh`, `.md5anim` and `.def` readers), [`SceneError`] names the body,
//! constraint or setting a method cannot simulate. [`Error`] wraps both so a caller
//! handles one type; its `Display` is the wrapped error's message, unchanged.

use crate::scene::AfError;
use crate::scene::SceneError;
use thiserror::Error;

/// Anything that stops a world from being built — a file that cannot be read or
/// parsed, a scene description that cannot be simulated — or data that does not fit it.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A file could not be read or has a mistake, with its `FILE:LINE:COL` position.
    #[error(transparent)]
    File(#[from] AfError),
    /// A scene description (read or built in code) that a method cannot simulate.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Data handed to a built world that does not fit it (one pose per body, say).
    #[error("{what}")]
    Mismatch {
        /// What does not fit, and how.
        what: String,
    },
}
