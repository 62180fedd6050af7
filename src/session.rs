//! One scene running in both methods: stepping, snapshots, live numbers and the energy
//! history the panel plots, grabbing and shooting. Used by the window and by capture.

use crate::app_state::SettingsOverride;
use crate::cli::ParticleSolverArg;
use crate::impacts::{MeshImpact, MeshTargets};
use crate::scenes::{LoadedScene, SceneAnimation};
use crate::{AppError, methods};
use glam::{Quat, Vec3};
use ragdoll_sim::scene::{BodyDesc, BodyId, MassSpec, Pose, Settings, Shape};
use ragdoll_sim::snapshot::BodyRole;
use ragdoll_sim::{Grab, Method, RenderSnapshot, Sample};
use std::time::Instant;

/// Samples kept per method for the plots (a minute at 60 Hz).
const HISTORY: usize = 3600;

/// A box shot with B: its edge (m), density (kg/m³) and speed (m/s). The defaults are a
/// 16 cm box of 2 kg at 12 m/s; the panel changes size and speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShotSettings {
    /// Edge length (m).
    pub edge: f32,
    /// Speed along the ray (m/s).
    pub speed: f32,
    /// Density (kg/m³); the mass follows the edge.
    pub density: f32,
}

impl Default for ShotSettings {
    fn default() -> Self {
        ShotSettings {
            edge: 0.16,
            speed: 12.0,
            density: 2.0 / (0.16 * 0.16 * 0.16),
        }
    }
}

impl ShotSettings {
    /// Mass of one box (kg).
    pub fn mass(&self) -> f32 {
        self.density * self.edge.powi(3)
    }
}

/// One frame's measurements of one method, for the plots.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HistoryPoint {
    /// Simulated time (s).
    pub t: f64,
    /// The method's sample then.
    pub sample: Sample,
}

/// Worst values seen since the scene (re)started, per method: what `stats` reports at
/// the end of a run, live.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Worst {
    /// Energy at the start (J).
    pub start_energy: f64,
    /// Largest rise of the energy above its start (J, ≥ 0).
    pub energy_rise: f64,
    /// Largest fall of the energy below its start (J, ≥ 0).
    pub energy_loss: f64,
    /// Deepest penetration (m).
    pub penetration: f32,
    /// Widest joint gap (m).
    pub joint_gap: f32,
    /// Largest limit excess (degrees).
    pub limit_excess_deg: f32,
    /// Largest relative bone stretch (particle method).
    pub stretch: f32,
}

impl Worst {
    fn start(s: &Sample) -> Worst {
        let mut w = Worst {
            start_energy: s.energy,
            ..Default::default()
        };
        w.record(s);
        w
    }

    fn record(&mut self, s: &Sample) {
        let change = s.energy - self.start_energy;
        self.energy_rise = self.energy_rise.max(change);
        self.energy_loss = self.energy_loss.max(-change);
        self.penetration = self.penetration.max(s.max_penetration);
        self.joint_gap = self.joint_gap.max(s.max_joint_gap);
        self.limit_excess_deg = self.limit_excess_deg.max(s.max_limit_violation_deg);
        self.stretch = self.stretch.max(s.max_bone_stretch.unwrap_or(0.0));
    }
}

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
    /// Every frame's sample per method (the last `HISTORY` of them, a minute at 60 Hz).
    pub history: [Vec<HistoryPoint>; 2],
    /// Worst values per method since the start.
    pub worst: [Worst; 2],
    /// Each side's skeleton as its bodies drive it (empty without a skinned mesh).
    pub joint_poses: [Vec<Pose>; 2],
    /// Whether shots hit the skinned mesh (the window ties it to its mesh toggle): a
    /// shot crossing the mesh pushes the body containing the nearest joint (see
    /// [`crate::impacts`]). Without a mesh it has no effect.
    pub mesh_shots: bool,
    /// Every hit of a shot on the mesh since the scene started, in order.
    pub mesh_impacts: Vec<MeshImpact>,
    /// The animation playing in place of the simulation until the ragdoll takes over
    /// (`--anim`; K), with its time (s).
    pub playing: Option<(SceneAnimation, f32)>,
    /// The user's settings over the scene's, kept for the methods the take-over builds.
    overrides: SettingsOverride,
    grab: Option<GrabDrag>,
    shots: u32,
    targets: MeshTargets,
}

impl Session {
    /// Builds both methods from `loaded`.
    pub fn new(loaded: LoadedScene, solver: ParticleSolverArg) -> Result<Session, AppError> {
        Session::configured(loaded, solver, &SettingsOverride::default())
    }

    /// Builds both methods from `loaded` with the user's `overrides` over its settings;
    /// `loaded` keeps the scene's own (the panel shows which are overridden).
    pub fn configured(
        loaded: LoadedScene,
        solver: ParticleSolverArg,
        overrides: &SettingsOverride,
    ) -> Result<Session, AppError> {
        let methods = if overrides.is_empty() {
            [
                methods::build_particle(&loaded.desc, solver)?,
                methods::build_multibody(&loaded.desc)?,
            ]
        } else {
            let mut desc = loaded.desc.clone();
            desc.settings = overrides.apply(&desc.settings);
            [
                methods::build_particle(&desc, solver)?,
                methods::build_multibody(&desc)?,
            ]
        };
        let playing = loaded.animation.clone().map(|a| {
            let start = a.start;
            (a, start)
        });
        let mut session = Session::with_methods(loaded, solver, methods);
        session.overrides = *overrides;
        session.playing = playing;
        session.refresh();
        Ok(session)
    }

    /// The ragdoll takes over from the animation playing (K): both methods rebuilt from
    /// the figure where the animation puts it now, with the animation's velocities
    /// ([`LoadedScene::taken_over_at`]). Returns whether an animation was playing.
    pub fn take_over(&mut self) -> Result<bool, AppError> {
        let Some((_, time)) = self.playing else {
            return Ok(false);
        };
        let mut desc = self.loaded.taken_over_at(time).desc;
        desc.settings = self.overrides.apply(&desc.settings);
        // Both built before either replaces its side: a failure keeps the animation.
        self.methods = [
            methods::build_particle(&desc, self.solver)?,
            methods::build_multibody(&desc)?,
        ];
        self.playing = None;
        self.history = [Vec::new(), Vec::new()];
        self.grab = None;
        self.record();
        self.worst = self.samples.map(|s| Worst::start(&s));
        self.refresh();
        Ok(true)
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
            history: [Vec::new(), Vec::new()],
            worst: [Worst::default(); 2],
            joint_poses: [Vec::new(), Vec::new()],
            mesh_shots: true,
            mesh_impacts: Vec::new(),
            playing: None,
            overrides: SettingsOverride::default(),
            grab: None,
            shots: 0,
            targets: MeshTargets::default(),
        };
        session.record();
        session.worst = session.samples.map(|s| Worst::start(&s));
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

    /// One timestep of both methods, timing each. While an animation plays, the
    /// animation advances by one timestep instead, looping over its length. Otherwise,
    /// first, shots that cross the skinned mesh this step push the bodies containing the
    /// joints they hit.
    pub fn step(&mut self) {
        if let Some((a, time)) = &mut self.playing {
            let length = a.takeover.anim().duration();
            *time += self.methods[0].settings().timestep;
            if length > 0.0 && *time > length {
                *time = time.rem_euclid(length);
            } else if length <= 0.0 {
                *time = 0.0;
            }
            return;
        }
        if let Some(skin) = self.loaded.skin.as_ref().filter(|_| self.mesh_shots) {
            let dt = self.methods[0].settings().timestep;
            let n = self.loaded.desc.bodies.len();
            let hits = self.targets.before_step(skin, &mut self.methods, n, dt);
            self.mesh_impacts.extend(hits);
        }
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
            let sample = m.sample();
            self.samples[i] = sample;
            self.worst[i].record(&sample);
            let history = &mut self.history[i];
            if history.len() >= HISTORY {
                history.drain(..HISTORY / 2);
            }
            history.push(HistoryPoint {
                t: m.time(),
                sample,
            });
        }
    }

    /// Refreshes both snapshots. While an animation plays, both show the figure's
    /// bodies where the animation puts them and the mesh on the animation's skeleton.
    pub fn refresh(&mut self) {
        for (m, snap) in self.methods.iter().zip(&mut self.snapshots) {
            m.snapshot(snap);
        }
        if let Some((a, time)) = &self.playing {
            let bodies = a.takeover.body_poses(*time);
            let joints = a.takeover.joint_poses(*time);
            for (snap, skeleton) in self.snapshots.iter_mut().zip(&mut self.joint_poses) {
                for b in snap.bodies.iter_mut() {
                    if let Some(p) = bodies.get(b.body.0 as usize) {
                        b.pose = *p;
                    }
                }
                // The method's own parts (particles, sticks, contacts, joint markers)
                // are at the rest pose: not drawn until it takes over.
                snap.particles.clear();
                snap.sticks.clear();
                snap.contacts.clear();
                snap.joints.clear();
                if self.loaded.skin.is_some() {
                    skeleton.clone_from(&joints);
                }
            }
            return;
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

    /// Shows `body` as selected (lighter, as a grabbed body) in both snapshots. Unless
    /// every joint's limits are shown (`all_limits`), only the joints at the selected
    /// body are kept for drawing: those whose anchor lies within its bounding radius.
    pub fn highlight(&mut self, body: Option<BodyId>, all_limits: bool) {
        let Some(body) = body else { return };
        for snap in &mut self.snapshots {
            let mut reach = None;
            for b in snap.bodies.iter_mut().filter(|b| b.body == body) {
                if b.role != BodyRole::Fixed {
                    b.role = BodyRole::Grabbed;
                }
                reach = Some((b.pose.position, b.shape.local_half_extents().length() * 1.2));
            }
            if !all_limits {
                snap.joints
                    .retain(|j| reach.is_some_and(|(centre, r)| j.anchor.distance(centre) <= r));
            }
        }
    }

    /// Shoots a box of `shot`'s size and speed from `origin` along unit `dir` (the
    /// cursor's ray) into both scenes. It starts 0.3 m and one edge along the ray, clear
    /// of the eye, so it is seen leaving the camera. With a skinned mesh it also hits
    /// the mesh (see [`crate::impacts`]).
    pub fn shoot(&mut self, origin: Vec3, dir: Vec3, shot: &ShotSettings) {
        self.shots += 1;
        let mut body = BodyDesc::new(
            format!("projectile {}", self.shots),
            Shape::Box {
                half_extents: Vec3::splat(shot.edge * 0.5),
            },
            Pose {
                position: origin + dir * (0.3 + shot.edge),
                rotation: Quat::IDENTITY,
            },
            MassSpec::Mass(shot.mass()),
        );
        body.linear_velocity = dir * shot.speed;
        let ids = [
            self.methods[0].add_body(&body),
            self.methods[1].add_body(&body),
        ];
        if self.loaded.skin.is_some() {
            self.targets.add_shot(ids, shot.mass(), shot.edge * 0.5);
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
