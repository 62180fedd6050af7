//! # ragdoll-sim
//!
//! The simulation core of ragdoll-lab: a plain-data scene description with a Doom 3
//! articulated-figure reader, two ragdoll methods built from it, and the metrics that
//! compare them. No GPU, no window: glam and parry3d only.
//!
//! - [`scene`]: `SceneDesc`, mass properties, the `.af` and `.md5mesh` readers.
//! - [`particle`]: the particle ragdoll, the `paper` (Verlet) and `rigid-frames` solvers.
//! - [`rigid`]: the impulse-based multibody solver.
//! - [`method`]: the trait both methods implement for the app.
//! - [`snapshot`]: what a method shows, the same way for both.
//! - [`metrics`]: energy gain, joint gap, limit violation, penetration.
//! - [`broadphase`]: the overlapping-box pairs both methods collide.
//! - `lanes`: vectors and quaternions four to an instruction, for both solvers.

#![warn(missing_docs)]

mod batches;
pub mod broadphase;
mod error;
mod lanes;
pub mod method;
pub mod metrics;
pub mod particle;
pub mod rigid;
pub mod scene;
pub mod snapshot;
mod world;

pub use error::Error;
pub use glam;
pub use method::{BodyState, Grab, Method, MethodKind, RayHit, Sample};
pub use scene::SceneDesc;
pub use snapshot::RenderSnapshot;
pub use world::{JointAngles, JointId, Solver, World};
