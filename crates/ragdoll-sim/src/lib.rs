//! # ragdoll-sim
//!
//! The simulation core of ragdoll-lab: a plain-data scene description with a Doom 3
//! articulated-figure reader, two ragdoll methods built from it, and the metrics that
//! compare them. No GPU, no window: glam and parry3d only.
//!
//! ## Start here
//!
//! A [`World`] is one ragdoll method running one scene. Build it from an `.af` file
//! ([`World::from_file`]), from `.af` text ([`World::from_af_str`]) or from a
//! [`SceneDesc`] made in code ([`World::from_scene`]), choosing the [`Solver`]:
//! [`Solver::Multibody`] (impulse-based rigid bodies), [`Solver::RigidFrames`] (the
//! particle method's position-based solver) or [`Solver::Paper`] (the particle method
//! as Glimberg & Engel 2007 write it). Then [`World::step`] or [`World::advance`], and
//! read [`World::body_pose`], [`World::body_state`] and [`World::joint_angles`], bodies
//! and joints found by name. Every failure is an [`Error`]: a file mistake with its
//! `FILE:LINE:COL`, or the body, constraint or setting a method cannot simulate.
//!
//! Drop the 16-bone human of the paper's test 8 for one second and see where its pelvis
//! (the body named `hip`) and its right knee are:
//!
//! ```
//! use ragdoll_sim::{Solver, World};
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/scenes/human.af");
//! let mut world = World::from_file(path, Solver::Multibody)?;
//! let pelvis = world.body("hip").expect("the human has a hip");
//! let start = world.body_pose(pelvis).position;
//! world.advance(1.0);
//! let pelvis_now = world.body_pose(pelvis).position;
//! let knee = world.joint_angles(world.joint("right_knee").expect("a right knee"));
//! println!(
//!     "after {:.2} s the pelvis is at {pelvis_now:.3} m (from {start:.3} m), \
//!      the right knee bent {:.1} degrees",
//!     world.time(),
//!     knee.twist.to_degrees(),
//! );
//! assert!(pelvis_now.y < start.y, "the figure falls");
//! # Ok::<(), ragdoll_sim::Error>(())
//! ```
//!
//! `cargo run --release -p ragdoll-sim --example drop_human` does the same with every
//! solver. The [`Method`] trait behind a `World` ([`World::method`]) is what the app
//! drives: metrics samples, what to draw, ray casts and the mouse grab.
//!
//! ## Acting on a figure
//!
//! What a game does to a ragdoll, as Jolt's ragdoll offers it, on every solver:
//! [`World::apply_impulse`] (a hit), [`World::set_pose`] (a teleport, Jolt's
//! `SetPose`), [`World::set_kinematic`] and [`World::move_kinematic`] (a body moved by
//! the game with infinite mass, an animated character's root or limbs), and
//! [`World::drive_to_pose`] / [`World::drive_joints`] (joint motors toward a pose,
//! `DriveToPoseUsingMotors`; [`motor`] says what they do). Carry the human by its pelvis
//! for half a second with its joints driven to the rest pose, then strike it and let go:
//!
//! ```
//! use ragdoll_sim::glam::Vec3;
//! use ragdoll_sim::scene::Pose;
//! use ragdoll_sim::{MotorDrive, Solver, World};
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/scenes/human.af");
//! let mut world = World::from_file(path, Solver::Multibody)?;
//! let pelvis = world.body("hip").expect("the human has a hip");
//! let rest: Vec<Pose> = world.scene().bodies.iter().map(|b| b.pose).collect();
//! world.set_kinematic(pelvis, true);
//! world.drive_to_pose(&rest, MotorDrive::default())?;
//! let dt = world.scene().settings.timestep;
//! let start = world.body_pose(pelvis).position;
//! for k in 1..=30 {
//!     let target = Pose::from_position(start + Vec3::X * (k as f32 * dt));
//!     world.move_kinematic(pelvis, target, dt);
//!     world.step();
//! }
//! assert!((world.body_pose(pelvis).position.x - (start.x + 0.5)).abs() < 1e-4);
//! let head = world.body("head").expect("a head");
//! let at = world.body_state(head).com;
//! world.apply_impulse(head, Vec3::new(0.0, 0.0, 10.0), at);
//! world.stop_motors();
//! world.set_kinematic(pelvis, false);
//! world.advance(0.5);
//! assert!(world.body_pose(pelvis).position.y < start.y, "let go, it falls");
//! # Ok::<(), ragdoll_sim::Error>(())
//! ```
//!
//! `cargo run --release -p ragdoll-sim --example drive_pose` runs a longer version of
//! this with every solver.
//!
//! ## Modules
//!
//! - [`scene`]: `SceneDesc`, mass properties, the `.af` and `.md5mesh` readers.
//! - [`particle`]: the particle ragdoll, the `paper` (Verlet) and `rigid-frames` solvers.
//! - [`rigid`]: the impulse-based multibody solver.
//! - [`method`]: the trait both methods implement for the app.
//! - [`motor`]: joint motors, the drive toward a pose both methods apply.
//! - [`snapshot`]: what a method shows, the same way for both.
//! - [`metrics`]: energy gain, joint gap, limit violation, penetration.
//! - [`broadphase`]: the overlapping-box pairs both methods collide.
//! - `lanes`: vectors and quaternions four to an instruction, for both solvers.
//! - `batches` and `union_find`: islands found and dealt to threads, for both solvers.
//! - `world` and `error`: [`World`], [`Solver`], [`JointAngles`] and [`Error`], the
//!   entry point above.

#![warn(missing_docs)]

mod batches;
pub mod broadphase;
mod error;
mod lanes;
pub mod method;
pub mod metrics;
pub mod motor;
pub mod particle;
pub mod rigid;
pub mod scene;
pub mod snapshot;
pub mod timings;
mod union_find;
mod world;

pub use error::Error;
pub use glam;
pub use method::{BodyPoseSet, BodyState, BodyVelocity, Grab, Method, MethodKind, RayHit, Sample};
pub use motor::{JointMotor, MotorDrive};
pub use scene::SceneDesc;
pub use snapshot::RenderSnapshot;
pub use timings::PhaseTimes;
pub use world::{JointAngles, JointId, Solver, World};
