//! The particle (Verlet) ragdoll — being written (issue 3).
