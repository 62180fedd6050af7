//! The interface both methods offer to the app, the metrics and the benchmarks.
//!
//! A method is built from a [`SceneDesc`](crate::scene::SceneDesc) only and is driven
//! through this trait; the app never reaches into a method's internals.

use crate::motor::JointMotor;
use crate::scene::{BodyDesc, BodyId, Pose, Settings};
use crate::snapshot::RenderSnapshot;
use crate::timings::PhaseTimes;
use glam::{Quat, Vec3};

/// Which of the two methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MethodKind {
    /// The particle (Verlet) method, left, blue.
    Particle,
    /// The impulse-based multibody method, right, red.
    Multibody,
}

impl MethodKind {
    /// Lowercase name as used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            MethodKind::Particle => "particle",
            MethodKind::Multibody => "multibody",
        }
    }
}

/// Kinematic state of one body, as the method sees it. The particle method reports the
/// values its bone frame implies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState {
    /// Centre of mass (world, m).
    pub com: Vec3,
    /// Orientation of the shape frame.
    pub orientation: Quat,
    /// Linear velocity of the centre of mass (m/s).
    pub linear_velocity: Vec3,
    /// Angular velocity (rad/s, world).
    pub angular_velocity: Vec3,
}

/// Per-frame measurements a method reports; [`crate::metrics`] turns a run of these into
/// the `stats` numbers. Definitions: `docs/metrics.md`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample {
    /// Total energy E(t) (J): kinetic + gravitational potential above the ground plane.
    pub energy: f64,
    /// Kinetic part of `energy` (J).
    pub kinetic: f64,
    /// Deepest overlap among colliding pairs and the ground now (m, 0 if none).
    pub max_penetration: f32,
    /// Largest distance between a joint's anchor seen from each body now (m).
    pub max_joint_gap: f32,
    /// Largest excess of a limited joint's angle beyond its limit now (degrees).
    pub max_limit_violation_deg: f32,
    /// Particle method: largest relative stick-length error of a bone now.
    pub max_bone_stretch: Option<f32>,
    /// Every dynamic body is asleep.
    pub all_asleep: bool,
}

/// Linear and angular velocity of a body (world axes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyVelocity {
    /// Velocity of the centre of mass (m/s).
    pub linear: Vec3,
    /// Angular velocity (rad/s).
    pub angular: Vec3,
}

/// A body put somewhere by [`Method::set_body_poses`] (Jolt's `Ragdoll::SetPose`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyPoseSet {
    /// The body moved.
    pub body: BodyId,
    /// Its new shape-frame pose (the frame of [`BodyDesc::pose`]).
    pub pose: Pose,
    /// Its new velocities; `None` keeps the ones it has (world axes).
    pub velocity: Option<BodyVelocity>,
}

/// A ray hit on a body, for grabbing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The body hit.
    pub body: BodyId,
    /// Distance along the (unit) ray.
    pub distance: f32,
    /// Hit point in the body's shape frame.
    pub local_point: Vec3,
}

/// A mouse grab: pull `local_point` of `body` towards `target` with a soft spring.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grab {
    /// Body grabbed.
    pub body: BodyId,
    /// Point on the body, shape frame.
    pub local_point: Vec3,
    /// World target.
    pub target: Vec3,
}

/// A ragdoll method: the particle ragdoll or the multibody solver.
pub trait Method: Send {
    /// Which method this is.
    fn kind(&self) -> MethodKind;
    /// A one-line description of the solver configuration ("rigid frames, 20 substeps (4 × 5 iterations)").
    fn solver_label(&self) -> String;
    /// Simulated time so far (s).
    fn time(&self) -> f64;
    /// Advances the simulation by one `settings.timestep`.
    fn step(&mut self);
    /// Applies changed settings live (timestep, iterations, substeps, gravity).
    fn set_settings(&mut self, settings: &Settings);
    /// The settings in force.
    fn settings(&self) -> &Settings;
    /// Fills `out` with what to draw now.
    fn snapshot(&self, out: &mut RenderSnapshot);
    /// The metrics sample for the current state.
    fn sample(&self) -> Sample;
    /// Number of bodies (scene bodies + projectiles).
    fn body_count(&self) -> usize;
    /// Number of dynamic bodies awake now (neither fixed nor asleep): the bodies the next
    /// step moves. A counter for the benchmarks' cost per moving body; one pass over a
    /// flag per body, cheap enough to call every frame.
    fn awake_body_count(&self) -> usize;
    /// Number of particles (0 for the multibody method).
    fn particle_count(&self) -> usize;
    /// Kinematic state of every body, indexed by `BodyId`.
    fn body_states(&self, out: &mut Vec<BodyState>);
    /// Particle positions (empty for the multibody method).
    fn particle_positions(&self, out: &mut Vec<Vec3>);
    /// First body hit by the ray from `origin` along unit `dir`.
    fn raycast(&self, origin: Vec3, dir: Vec3) -> Option<RayHit>;
    /// Sets or clears the mouse grab.
    fn set_grab(&mut self, grab: Option<Grab>);
    /// Adds a dynamic body (a projectile) with its initial velocity; wakes what it hits.
    fn add_body(&mut self, desc: &BodyDesc) -> BodyId;
    /// Applies the impulse `impulse` (N·s, world axes) at the world point `point` to
    /// `body`, at once: the body's momentum changes by `impulse` and its angular
    /// momentum about its centre of mass `c` by `(point − c) × impulse` (a particle bone
    /// shares it among its particles so that both hold for them). Wakes the body's
    /// island first. Does nothing to a fixed body or an id not of this world.
    fn apply_impulse(&mut self, body: BodyId, impulse: Vec3, point: Vec3);
    /// Puts bodies at new poses, with new velocities or their own, at once (a teleport:
    /// no collision is swept on the way). The bodies and their figures wake; a particle
    /// bone's particles are placed rigidly in its new frame. Joints between a moved
    /// body and one left where it was pull them together again in the next steps, and
    /// an overlap the new poses make is pushed out at the scene's push-out speed. Fixed
    /// bodies and ids not of this world are left alone.
    fn set_body_poses(&mut self, poses: &[BodyPoseSet]);
    /// Makes `body` kinematic — moved by the game, infinite mass to the solver, pushing
    /// what it meets (Jolt's `MotionType::Kinematic`) — keeping its velocities, or
    /// dynamic again, moving on with them. Wakes its figure. A fixed body stays fixed.
    fn set_kinematic(&mut self, body: BodyId, kinematic: bool);
    /// Whether `body` is kinematic.
    fn is_kinematic(&self, body: BodyId) -> bool;
    /// Sets a kinematic body's velocities so that it reaches the shape-frame pose
    /// `target` after `dt` seconds (Jolt's `MoveKinematic`): `v = (c* − c)/dt`,
    /// `ω = θ/dt` with `θ` the turn to the target's orientation. A step of `dt` ends
    /// with the body on the target; it keeps moving at that velocity until told
    /// otherwise. Nothing for a body that is not kinematic.
    fn move_kinematic(&mut self, body: BodyId, target: Pose, dt: f32);
    /// Replaces the joint motors in force by `motors` (empty: all off), waking the
    /// figures they act on. Each drives its joint's relative orientation toward its
    /// target with a bounded torque until replaced ([`crate::motor`]).
    fn set_joint_motors(&mut self, motors: &[JointMotor]);
    /// Wall time of the last step's phases, for display only (no result depends on it).
    /// Empty for a method that does not time its phases.
    fn phase_times(&self) -> PhaseTimes {
        PhaseTimes::default()
    }
    /// Drops the method one owner of heap memory at a time (its bodies, joints, contact
    /// cache, ...), calling `dropped(owner)` after each: with a counting allocator, the
    /// bytes freed since the previous call are what `owner` held. For the memory bench's
    /// breakdown; a method that does not name its owners drops itself whole as `"all"`.
    fn drop_by_owner(self: Box<Self>, dropped: &mut dyn FnMut(&'static str)) {
        drop(self);
        dropped("all");
    }
}
