//! The app's error type: every failure a user can cause ends here, printed once,
//! exit status 1.

use thiserror::Error;

/// An app-level failure, printed as-is to stderr by `main`.
#[derive(Debug, Error)]
pub enum AppError {
    /// A scene file could not be read or parsed; the message is already
    /// `FILE:LINE:COL: error: ...`.
    #[error("{0}")]
    Scene(String),
    /// A scene description cannot be simulated.
    #[error("error: {0}")]
    Build(#[from] ragdoll_sim::scene::SceneError),
    /// Bad command-line usage the parser could not catch.
    #[error("error: {0}")]
    Usage(String),
    /// File system trouble, with the path.
    #[error("error: {path}: {source}")]
    Io {
        /// The path involved.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// No GPU adapter, surface or device trouble.
    #[error("error: graphics: {0}")]
    Gpu(String),
    /// Anything else, with its message.
    #[error("error: {0}")]
    Other(String),
}
