//! Builds the two methods from a scene, behind the common `Method` trait.

use crate::AppError;
use crate::cli::ParticleSolverArg;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::{Method, SceneDesc};

/// The particle method (left, blue) with the chosen solver.
pub fn build_particle(
    scene: &SceneDesc,
    solver: ParticleSolverArg,
) -> Result<Box<dyn Method>, AppError> {
    let solver = match solver {
        ParticleSolverArg::Paper => ParticleSolver::Paper,
        ParticleSolverArg::RigidFrames => ParticleSolver::RigidFrames,
        ParticleSolverArg::Xpbd => ParticleSolver::Xpbd,
    };
    Ok(Box::new(ParticleWorld::new(scene, solver)?))
}

/// The multibody method (right, red).
pub fn build_multibody(scene: &SceneDesc) -> Result<Box<dyn Method>, AppError> {
    Ok(Box::new(ragdoll_sim::rigid::MultibodyWorld::new(scene)?))
}
