//! One scene running in both methods: stepping, snapshots, live numbers and the energy
//! history the panel plots, grabbing and shooting. Used by the window and by capture.

use crate::cli::ParticleSolverArg;
use crate::scenes::LoadedScene;
use crate::{AppError, methods};
use glam::{Quat, Vec3};
use ragdoll_sim::scene::{BodyDesc, BodyId, MassSpec, Pose, Settings, Shape};
use ragdoll_sim::{Grab, Method, RenderSnapshot, Sample};
use std::time::Instant;

/// Energy samples kept per method for the plot (a minute at 60 Hz).
const HISTORY: usize = 3600;

/// Edge half-length (m), mass (kg) and speed (m/s) of a box shot with B.
const SHOT_HALF_EXTENT: f32 = 0.08;
const SHOT_MASS: f32 = 2.0;
const SHOT_SPEED: f32 = 12.0;

/// A grab in progress: the body, the point on it, and how far along the ray it was hit.
#[derive(Clone, Copy, Debug)]
struct GrabDrag {
    body: BodyId,
    local_point: Vec3,
    distance: f32,
}

/// The two methods on one scene. Index 0 is the particle method (left), 1 the multibody
/// method (right).
pub struct Session {
    /// The scene as loaded, variant applied.
    pub loaded: LoadedScene,
    /// The particle solver the left side runs.
    pub solver: ParticleSolverArg,
    /// The methods: particle, multibody.
    pub methods: [Box<dyn Method>; 2],
    /// What each shows now.
    pub snapshots: [RenderSnapshot; 2],
    /// Smoothed wall-clock time of one step (ms).
    pub step_ms: [f64; 2],
    /// The latest metrics sample.
    pub samples: [Sample; 2],
    /// (simulated time, energy) per method.
    pub energy: [Vec<[f64; 2]>; 2],
    /// Each side's skeleton as its bodies drive it (empty without a skinned mesh).
    pub joint_poses: [Vec<Pose>; 2],
    grab: Option<GrabDrag>,
    shots: u32,
}

impl Session {
    /// Builds both methods from `loaded`.
    pub fn new(loaded: LoadedScene, solver: ParticleSolverArg) -> Result<Session, AppError> {
        let methods = [
            methods::build_particle(&loaded.desc, solver)?,
            methods::build_multibody(&loaded.desc)?,
        ];
        Ok(Session::with_methods(loaded, solver, methods))
    }

    /// A session around methods built elsewhere (particle first).
    pub fn with_methods(
        loaded: LoadedScene,
        solver: ParticleSolverArg,
        methods: [Box<dyn Method>; 2],
    ) -> Session {
        let mut session = Session {
            loaded,
            solver,
            methods,
            snapshots: Default::default(),
            step_ms: [0.0; 2],
            samples: [Sample::default(); 2],
            energy: [Vec::new(), Vec::new()],
            joint_poses: [Vec::new(), Vec::new()],
            grab: None,
            shots: 0,
        };
        session.record();
        session.refresh();
        session
    }

    /// Settings in force (the particle method's; both get the same).
    pub fn settings(&self) -> Settings {
        self.methods[0].settings().clone()
    }

    /// Applies `settings` to both methods.
    pub fn set_settings(&mut self, settings: &Settings) {
        for m in &mut self.methods {
            m.set_settings(settings);
        }
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.methods[0].time()
    }

    /// One timestep of both methods, timing each.
    pub fn step(&mut self) {
        for (i, m) in self.methods.iter_mut().enumerate() {
            let start = Instant::now();
            m.step();
            let ms = start.elapsed().as_secs_f64() * 1e3;
            // An exponential average over ~20 steps keeps the label readable.
            self.step_ms[i] = if self.step_ms[i] == 0.0 {
                ms
            } else {
                self.step_ms[i] + (ms - self.step_ms[i]) * 0.05
            };
        }
        self.record();
    }

    fn record(&mut self) {
        for (i, m) in self.methods.iter().enumerate() {
            self.samples[i] = m.sample();
            let history = &mut self.energy[i];
            if history.len() >= HISTORY {
                history.drain(..HISTORY / 2);
            }
            history.push([m.time(), self.samples[i].energy]);
        }
    }

    /// Refreshes both snapshots.
    pub fn refresh(&mut self) {
        for (m, snap) in self.methods.iter().zip(&mut self.snapshots) {
            m.snapshot(snap);
        }
        if let Some(skin) = &self.loaded.skin {
            let n = self.loaded.desc.bodies.len();
            for (snap, joints) in self.snapshots.iter().zip(&mut self.joint_poses) {
                let mut bodies = vec![Pose::IDENTITY; n];
                for b in snap.bodies.iter().filter(|b| (b.body.0 as usize) < n) {
                    bodies[b.body.0 as usize] = b.pose;
                }
                *joints = skin.joint_poses(&bodies);
            }
        }
    }

    /// Shoots a small box from `origin` along unit `dir` into both scenes.
    pub fn shoot(&mut self, origin: Vec3, dir: Vec3) {
        self.shots += 1;
        let mut body = BodyDesc::new(
            format!("projectile {}", self.shots),
            Shape::Box {
                half_extents: Vec3::splat(SHOT_HALF_EXTENT),
            },
            Pose {
                position: origin + dir * 0.3,
                rotation: Quat::IDENTITY,
            },
            MassSpec::Mass(SHOT_MASS),
        );
        body.linear_velocity = dir * SHOT_SPEED;
        for m in &mut self.methods {
            m.add_body(&body);
        }
    }

    /// Starts a grab with the ray under the cursor, cast into `side`'s method; the same
    /// body and point are then pulled in both. Returns whether a body was hit.
    pub fn grab_start(&mut self, side: usize, origin: Vec3, dir: Vec3) -> bool {
        let Some(hit) = self.methods[side.min(1)].raycast(origin, dir) else {
            return false;
        };
        self.grab = Some(GrabDrag {
            body: hit.body,
            local_point: hit.local_point,
            distance: hit.distance,
        });
        self.grab_move(origin, dir);
        true
    }

    /// Moves the grab target to the point of the new ray at the grab's distance.
    pub fn grab_move(&mut self, origin: Vec3, dir: Vec3) {
        let Some(g) = self.grab else { return };
        let grab = Grab {
            body: g.body,
            local_point: g.local_point,
            target: origin + dir * g.distance,
        };
        for m in &mut self.methods {
            m.set_grab(Some(grab));
        }
    }

    /// Releases the grab.
    pub fn grab_end(&mut self) {
        if self.grab.take().is_some() {
            for m in &mut self.methods {
                m.set_grab(None);
            }
        }
    }

    /// Whether a body is being dragged.
    pub fn grabbing(&self) -> bool {
        self.grab.is_some()
    }
}
