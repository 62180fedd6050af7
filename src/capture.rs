//! `ragdoll-lab capture`: offscreen rendering to PNG through the same renderer.

use crate::cli::CaptureArgs;
use crate::AppError;

/// Simulates and renders offscreen, writing PNGs.
pub fn run(args: CaptureArgs) -> Result<(), AppError> {
    let _ = args;
    Err(AppError::Other("capture is not built yet (issue 5)".into()))
}
