//! Builds the two methods from a scene, behind the common `Method` trait.

use crate::cli::ParticleSolverArg;
use crate::AppError;
use ragdoll_sim::{Method, SceneDesc};

/// The particle method (left, blue) with the chosen solver.
pub fn build_particle(
    scene: &SceneDesc,
    solver: ParticleSolverArg,
) -> Result<Box<dyn Method>, AppError> {
    let _ = (scene, solver);
    Err(AppError::Other("the particle method is not built yet (issue 3)".into()))
}

/// The multibody method (right, red).
pub fn build_multibody(scene: &SceneDesc) -> Result<Box<dyn Method>, AppError> {
    Ok(Box::new(ragdoll_sim::rigid::MultibodyWorld::new(scene)?))
}
