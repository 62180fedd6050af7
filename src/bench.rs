//! `ragdoll-lab bench ...`: the paper's performance tests 9-12 and the scale table.

use crate::cli::BenchArgs;
use crate::AppError;

/// Runs one benchmark table.
pub fn run(args: BenchArgs) -> Result<(), AppError> {
    let _ = args;
    Err(AppError::Other("bench is not built yet (issue 6)".into()))
}
