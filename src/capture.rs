//! `ragdoll-lab capture`: offscreen rendering to PNG through the same renderer.

use crate::AppError;
use crate::cli::CaptureArgs;

/// Simulates and renders offscreen, writing PNGs.
pub fn run(args: CaptureArgs) -> Result<(), AppError> {
    let _ = args;
    Err(AppError::Other("capture is not built yet (issue 5)".into()))
}
