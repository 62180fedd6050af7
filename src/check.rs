//! `ragdoll-lab check FILE.af [--mesh M]`.

use crate::AppError;
use crate::cli::CheckArgs;

/// Prints a summary of the file or its first error.
pub fn run(args: CheckArgs) -> Result<(), AppError> {
    let _ = args;
    Err(AppError::Other("check is not built yet (issue 2)".into()))
}
