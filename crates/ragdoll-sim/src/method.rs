//! The interface both methods offer to the app, the metrics and the benchmarks.
//!
//! A method is built from a [`SceneDesc`](crate::scene::SceneDesc) only and is driven
//! through this trait; the app never reaches into a method's internals.

use crate::scene::{BodyDesc, BodyId, Settings};
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
    /// Wall time of the last step's phases, for display only (no result depends on it).
    /// Empty for a method that does not time its phases.
    fn phase_times(&self) -> PhaseTimes {
        PhaseTimes::default()
    }
}
