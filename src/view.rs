//! The window: split-screen renderer, egui panel, the paper's keys.

use crate::cli::ViewArgs;
use crate::AppError;

/// Opens the window and runs until the user quits.
pub fn run(args: ViewArgs) -> Result<(), AppError> {
    let _ = args;
    Err(AppError::Other("the viewer is not built yet (issue 5)".into()))
}
