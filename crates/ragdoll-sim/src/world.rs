//! [`World`]: the entry point for a game or a tool — build either method from a file,
//! `.af` text or a [`SceneDesc`], step it, read body poses and joint angles by name.
//!
//! A `World` owns a [`Method`] and the scene it was built from (cold data: names, rest
//! poses, joint axes). The method's body states are copied out once per step into a
//! dense array indexed by [`BodyId`], so every read between steps is a lookup.

use crate::error::Error;
use crate::method::{BodyState, Method, MethodKind};
use crate::particle::{ParticleSolver, ParticleWorld};
use crate::rigid::MultibodyWorld;
use crate::scene::af::{self, AfOptions};
use crate::scene::{BodyDesc, BodyId, BodyRef, JointKind, Pose, SceneDesc, mass_props};
use glam::{Quat, Vec3};
use std::path::Path;

/// The method and solver a [`World`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Solver {
    /// Particle method, the paper's section 3 as written (Verlet, sticks).
    Paper,
    /// Particle method, rigid-frames solver (position-based rigid bones).
    #[default]
    RigidFrames,
    /// Particle method, XPBD on particles with their own state (sticks, joints and
    /// contacts as constraints on particles).
    Xpbd,
    /// Impulse-based multibody method.
    Multibody,
}

impl Solver {
    /// Every solver, in the order the app shows them.
    pub const ALL: [Solver; 4] = [
        Solver::Paper,
        Solver::RigidFrames,
        Solver::Xpbd,
        Solver::Multibody,
    ];

    /// Which of the two methods this solver belongs to.
    pub fn kind(self) -> MethodKind {
        match self {
            Solver::Paper | Solver::RigidFrames | Solver::Xpbd => MethodKind::Particle,
            Solver::Multibody => MethodKind::Multibody,
        }
    }

    /// Lowercase name as on the command line (`paper`, `rigid-frames`, `xpbd`,
    /// `multibody`).
    pub fn name(self) -> &'static str {
        match self {
            Solver::Paper => ParticleSolver::Paper.name(),
            Solver::RigidFrames => ParticleSolver::RigidFrames.name(),
            Solver::Xpbd => ParticleSolver::Xpbd.name(),
            Solver::Multibody => MethodKind::Multibody.name(),
        }
    }

    /// Builds this solver's method for a scene, behind the [`Method`] trait.
    pub fn build(self, scene: &SceneDesc) -> Result<Box<dyn Method>, Error> {
        Ok(match self {
            Solver::Paper => Box::new(ParticleWorld::new(scene, ParticleSolver::Paper)?),
            Solver::RigidFrames => {
                Box::new(ParticleWorld::new(scene, ParticleSolver::RigidFrames)?)
            }
            Solver::Xpbd => Box::new(ParticleWorld::new(scene, ParticleSolver::Xpbd)?),
            Solver::Multibody => Box::new(MultibodyWorld::new(scene)?),
        })
    }
}

/// A typed index into [`SceneDesc::constraints`], the joints of a [`World`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct JointId(pub u32);

impl JointId {
    /// As a `usize` index.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A joint's relative rotation since the rest pose, split about the joint's axis.
///
/// `rotation` is Δ = R₂⁻¹ R₁ with Rᵢ = qᵢ qᵢ,rest⁻¹ the rotation body i has made since
/// rest (R₂ = 1 for the world): the rotation of body1 relative to body2, expressed in the
/// world axes of the rest pose, identity at rest — the convention of [`AngleRange`] and
/// [`TwistLimit`](crate::scene::TwistLimit). The swing–twist split Δ = S·T about the unit
/// `axis` takes T = (w, (v·a)a)/‖·‖, so `twist` = 2 atan2(v·a, w) with w ≥ 0, in [−π, π],
/// and `swing` is the angle of S = Δ T⁻¹, in [0, π].
///
/// [`AngleRange`]: crate::scene::AngleRange
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointAngles {
    /// Δ, the rotation of body1 relative to body2 since rest (rest-pose world axes).
    pub rotation: Quat,
    /// The axis of the split (unit, rest-pose world axes): the hinge or slider axis, a
    /// ball joint's twist axis (else its swing shaft, else the line from the anchor to
    /// body1's centre), the normal of a universal joint's two shafts; `Vec3::Y` otherwise.
    pub axis: Vec3,
    /// Rotation about `axis` (radians, right-handed): a hinge's angle.
    pub twist: f32,
    /// Rotation away from `axis` (radians, ≥ 0): a ball joint's swing.
    pub swing: f32,
}

impl JointAngles {
    /// The split of `rotation` about the unit `axis`.
    pub fn split(rotation: Quat, axis: Vec3) -> JointAngles {
        // q and −q are the same rotation; w ≥ 0 puts the twist in [−π, π].
        let q = if rotation.w < 0.0 {
            -rotation
        } else {
            rotation
        };
        let along = q.xyz().dot(axis);
        let twist = 2.0 * along.atan2(q.w);
        let swing = (q * Quat::from_axis_angle(axis, -twist)).normalize();
        JointAngles {
            rotation,
            axis,
            twist,
            swing: 2.0 * swing.w.abs().min(1.0).acos(),
        }
    }
}

/// A ragdoll world: one method built from one scene, with lookups by name.
///
/// ```
/// use ragdoll_sim::{Solver, World};
/// let text = r#"
///     settings { units "m" up "y" }
///     body "box" {
///         model box( (-0.1, -0.1, -0.1), (0.1, 0.1, 0.1) )
///         origin (0, 2, 0)
///         mass 1
///     }
/// "#;
/// let mut world = World::from_af_str(text, "box.af", Solver::Multibody)?;
/// world.advance(0.5);
/// let pose = world.body_pose(world.body("box").unwrap());
/// assert!(pose.position.y < 2.0 - 0.5 * 9.81 * 0.25 * 0.95);
/// # Ok::<(), ragdoll_sim::Error>(())
/// ```
pub struct World {
    method: Box<dyn Method>,
    solver: Solver,
    scene: SceneDesc,
    /// Each body's centre of mass in its shape frame, to turn a state into a pose.
    local_com: Vec<Vec3>,
    /// The method's body states after the last step, indexed by `BodyId`.
    states: Vec<BodyState>,
}

impl World {
    /// Builds `solver`'s method for a scene. Fails with [`Error::Scene`] naming the body,
    /// constraint or setting that cannot be simulated.
    pub fn from_scene(scene: SceneDesc, solver: Solver) -> Result<World, Error> {
        let method = solver.build(&scene)?;
        let local_com = scene
            .bodies
            .iter()
            .map(|b| mass_props(b).map(|m| m.local_com))
            .collect::<Result<Vec<_>, _>>()?;
        let mut world = World {
            method,
            solver,
            scene,
            local_com,
            states: Vec::new(),
        };
        world.method.body_states(&mut world.states);
        Ok(world)
    }

    /// Reads `.af` text (variant 1) and builds the world. `file` names the text in
    /// messages and anchors a relative `mesh` path. Fails with [`Error::File`]
    /// (`FILE:LINE:COL: error: ...`) or [`Error::Scene`].
    pub fn from_af_str(text: &str, file: impl AsRef<Path>, solver: Solver) -> Result<World, Error> {
        let scene = af::parse(text, file.as_ref(), &AfOptions::default())?;
        World::from_scene(scene.desc, solver)
    }

    /// Reads an `.af` file (variant 1) and builds the world.
    pub fn from_file(path: impl AsRef<Path>, solver: Solver) -> Result<World, Error> {
        World::from_file_with(path, &AfOptions::default(), solver)
    }

    /// Reads an `.af` file with options (variant, `.md5mesh`, number of copies).
    pub fn from_file_with(
        path: impl AsRef<Path>,
        opts: &AfOptions,
        solver: Solver,
    ) -> Result<World, Error> {
        let scene = af::load(path.as_ref(), opts)?;
        World::from_scene(scene.desc, solver)
    }

    /// Advances by one `settings.timestep`.
    pub fn step(&mut self) {
        self.method.step();
        self.method.body_states(&mut self.states);
    }

    /// Steps until `seconds` more of simulated time have passed (whole timesteps, the
    /// last one reaching or passing the target); returns the number of steps taken.
    pub fn advance(&mut self, seconds: f64) -> u32 {
        let target = self.method.time() + seconds;
        let dt = f64::from(self.method.settings().timestep);
        let mut steps = 0;
        // Half a step of slack so rounding in the accumulated time never adds a step.
        while self.method.time() + 0.5 * dt < target {
            self.method.step();
            steps += 1;
        }
        self.method.body_states(&mut self.states);
        steps
    }

    /// Applies the impulse `impulse` (N·s, world axes) at the world point `point` to
    /// `body`, at once, waking its island: its momentum changes by `impulse` and its
    /// angular momentum about its centre of mass `c` by `(point − c) × impulse`
    /// ([`Method::apply_impulse`]). The body states read back at once show it. Does
    /// nothing to a fixed body.
    pub fn apply_impulse(&mut self, body: BodyId, impulse: Vec3, point: Vec3) {
        self.method.apply_impulse(body, impulse, point);
        self.method.body_states(&mut self.states);
    }

    /// Simulated time so far (s).
    pub fn time(&self) -> f64 {
        self.method.time()
    }

    /// The solver this world runs.
    pub fn solver(&self) -> Solver {
        self.solver
    }

    /// The scene the world was built from (rest poses, joints, settings at build time).
    pub fn scene(&self) -> &SceneDesc {
        &self.scene
    }

    /// The method, for everything the [`Method`] trait offers (metrics samples, drawing).
    pub fn method(&self) -> &dyn Method {
        self.method.as_ref()
    }

    /// Gives up the lookups and keeps the method.
    pub fn into_method(self) -> Box<dyn Method> {
        self.method
    }

    /// The body named `name`.
    pub fn body(&self, name: &str) -> Option<BodyId> {
        self.scene.body_id(name)
    }

    /// The joint (constraint) named `name`.
    pub fn joint(&self, name: &str) -> Option<JointId> {
        self.scene
            .constraints
            .iter()
            .position(|c| c.name == name)
            .map(|i| JointId(i as u32))
    }

    /// Every body's state after the last step, indexed by `BodyId`.
    pub fn body_states(&self) -> &[BodyState] {
        &self.states
    }

    /// One body's state: centre of mass, orientation, velocities. Panics on an id not
    /// from this world.
    pub fn body_state(&self, body: BodyId) -> BodyState {
        self.states[body.index()]
    }

    /// One body's shape-frame pose, the frame of [`BodyDesc::pose`]: the state's
    /// orientation q and position c − q·c_local (c the centre of mass).
    pub fn body_pose(&self, body: BodyId) -> Pose {
        let s = self.states[body.index()];
        Pose {
            position: s.com - s.orientation * self.local_com[body.index()],
            rotation: s.orientation,
        }
    }

    /// Adds a dynamic body (a projectile) with its initial velocity; its pose and state
    /// are readable from the next step on, by the returned id.
    pub fn add_body(&mut self, desc: &BodyDesc) -> Result<BodyId, Error> {
        let local_com = mass_props(desc)?.local_com;
        let id = self.method.add_body(desc);
        debug_assert_eq!(id.index(), self.local_com.len());
        self.local_com.push(local_com);
        self.method.body_states(&mut self.states);
        Ok(id)
    }

    /// A joint's rotation since rest, split about its axis ([`JointAngles`]). Panics on
    /// an id not from this world.
    pub fn joint_angles(&self, joint: JointId) -> JointAngles {
        let c = &self.scene.constraints[joint.index()];
        let since_rest = |b: BodyId| {
            self.states[b.index()].orientation * self.scene.body(b).pose.rotation.inverse()
        };
        let r1 = since_rest(c.body1);
        let r2 = match c.body2 {
            BodyRef::Body(b) => since_rest(b),
            BodyRef::World => Quat::IDENTITY,
        };
        let delta = (r2.inverse() * r1).normalize();
        JointAngles::split(delta, self.joint_axis(joint))
    }

    /// The axis [`JointAngles`] splits a joint's rotation about (rest-pose world axes).
    fn joint_axis(&self, joint: JointId) -> Vec3 {
        let c = &self.scene.constraints[joint.index()];
        let axis = match &c.kind {
            JointKind::Hinge { axis, .. } | JointKind::Slider { axis } => *axis,
            JointKind::BallAndSocket {
                anchor,
                swing,
                twist,
                ..
            } => match (twist, swing) {
                (Some(t), _) => t.axis,
                (None, Some(crate::scene::SwingLimit::Cone { shaft, .. }))
                | (None, Some(crate::scene::SwingLimit::Pyramid { shaft, .. })) => *shaft,
                (None, None) => {
                    let b1 = self.scene.body(c.body1);
                    let com = b1.pose.transform_point(self.local_com[c.body1.index()]);
                    com - *anchor
                }
            },
            JointKind::Universal { shaft1, shaft2, .. } => shaft1.cross(*shaft2),
            JointKind::Fixed | JointKind::Spring { .. } => Vec3::Y,
        };
        axis.try_normalize().unwrap_or(Vec3::Y)
    }
}
