//! The particle (Verlet) ragdoll, left and blue: bones are tetrahedra of four particles
//! and six sticks (Glimberg & Engel 2007, section 3), with two solvers.
//!
//! - [`ParticleSolver::Paper`]: section 3 as written ([`paper`](self) module doc).
//! - [`ParticleSolver::RigidFrames`] (default): particles placed automatically so every bone
//!   has its rigid body's mass, centre of mass and inertia; joints between points in
//!   the bones' frames; generalised-inverse-mass corrections; substeps; contact
//!   manifolds with Coulomb friction and restitution; sleeping.
//!
//! Files, one concept each: `particles` (the paper's storage, Verlet), `bone` (tetrahedron, frame,
//! rigid corrections), `bone_kinds` (what bones share: shape, rest corners and shape
//! frame, materials), `placement` (particulation), `joints`, `joint_kinds` (what joints of a
//! kind share: type, limits, compliance, friction), `limits`, `contacts`
//! (filter, broad and narrow phase), `friction` (contact response), `sleeping`,
//! `rigid_frames` and `paper` (the two solver loops), `islands` (the rigid-frames loop on all
//! cores), `measure` (the metrics).

mod bone;
mod bone_kinds;
mod bone_lanes;
mod contacts;
mod friction;
mod impulse;
mod islands;
mod joint_kinds;
mod joint_lanes;
mod joints;
pub(crate) mod kinematic;
mod limits;
mod measure;
mod motors;
mod paper;
mod particles;
mod placement;
mod rigid_frames;
mod rolling;
mod set_pose;
mod sleeping;
mod xpbd;

/// The XPBD solver's default passes per substep ([`crate::scene::Settings::xpbd_passes`]).
pub(crate) use xpbd::step::PASSES as XPBD_PASSES;

use crate::method::{BodyPoseSet, BodyState, Grab, Method, MethodKind, RayHit, Sample};
use crate::scene::{
    BodyCollider, BodyDesc, BodyId, Pose, SceneDesc, SceneError, Settings, collider, mass_props,
    validate,
};
use crate::snapshot::{
    BodyInstance, BodyRole, ContactInstance, JointInstance, LimitShape, ParticleInstance,
    ParticleRole, RenderSnapshot, StickInstance, StickRole,
};
use crate::timings::{PhaseClock, PhaseTimes};
use bone::{Bone, EDGES};
use bone_kinds::{BoneKind, BoneKinds, Material, Placement};
use contacts::{ContactSet, Filter};
use glam::{Quat, Vec3, Vec3A};
use joint_kinds::JointKinds;
use joints::{Joint, Link, RestFrames};
use parry3d::query::{ContactManifold, Ray};
use parry3d::shape::SharedShape;
use particles::Particles;

/// Which solver the particle method runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ParticleSolver {
    /// The paper's section 3 as written.
    Paper,
    /// Position-based rigid bodies (in the manner of Müller et al. 2020): each bone is
    /// moved as a rigid frame whose four corner particles are evaluated, never stored;
    /// the limit of infinitely stiff sticks. Particulated mass properties, joints between
    /// points in the bones' frames, substeps, contact friction, sleeping.
    #[default]
    RigidFrames,
    /// XPBD on particles with small steps (Macklin et al. 2019): each particle keeps its
    /// own position and velocity; a bone is four particles reproducing its mass, centre
    /// of mass and inertia, held by six sticks; joints, limits and contacts are
    /// constraints on the particles; the bone frame is read from them ([`xpbd`](self)).
    Xpbd,
}

impl ParticleSolver {
    /// Lowercase name as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ParticleSolver::Paper => "paper",
            ParticleSolver::RigidFrames => "rigid-frames",
            ParticleSolver::Xpbd => "xpbd",
        }
    }
}

/// The particle ragdoll world, built from a [`SceneDesc`].
pub struct ParticleWorld {
    /// The live settings (the scene itself is not kept: a world is built from it).
    settings: Settings,
    /// Bodies of the scene; later ones are projectiles (`add_body`).
    scene_bodies: usize,
    /// Bodies of the scene and projectiles: the next projectile's id.
    bodies: usize,
    solver: ParticleSolver,
    /// The paper's particles. The improved solver keeps none: its particles are the
    /// corners of the bone frames (`Bone::corner`).
    particles: Particles,
    bones: Vec<Bone>,
    /// What bones share: shapes, rest corners and shape frames, materials.
    kinds: BoneKinds,
    joints: Vec<Joint>,
    /// What joints of a kind share: type, limits, compliance, friction.
    joint_kinds: JointKinds,
    /// Each joint's sides, packed ([`Link`]).
    links: Vec<Link>,
    filter: Filter,
    contacts: ContactSet,
    pairs: Vec<(usize, usize)>,
    manifolds: Vec<ContactManifold<(), ()>>,
    paper: Option<paper::PaperState>,
    /// The XPBD solver's particles and constraints.
    xpbd: Option<xpbd::XpbdState>,
    /// Per bone, its motion while it is kinematic (empty until one is).
    kinematic: Vec<Option<kinematic::KinematicBone>>,
    /// The joint motors in force (`motors`).
    motors: Vec<crate::motor::JointMotor>,
    grab: Option<Grab>,
    time: f64,
    /// The last step's phase times, for display only (no step reads them).
    phase_times: PhaseTimes,
}

impl ParticleWorld {
    /// Narrows every joint's slack by what a frame allows ([`Joint::close_slack`] at
    /// `max_push_out_speed`) and returns the figures that had some, sorted, each once:
    /// the figures a solver's start passes move onto their narrowed limits this frame
    /// (`rigid_frames::close_start_slack`, `xpbd::step::close_start_slack`).
    pub(crate) fn close_slack_of_figures(&mut self) -> Vec<u32> {
        let (push_out, dt) = (self.settings.max_push_out_speed, self.settings.timestep);
        let mut figures: Vec<u32> = Vec::new();
        for j in &mut self.joints {
            if j.close_slack(push_out, dt)
                && let Some(i) = j.a().or(j.b())
            {
                figures.push(self.bones[i].figure);
            }
        }
        figures.sort_unstable();
        figures.dedup();
        figures
    }

    /// Builds the world for a scene with the given solver. Fails with a [`SceneError`]
    /// saying what and where when the description cannot be simulated.
    pub fn new(scene: &SceneDesc, solver: ParticleSolver) -> Result<ParticleWorld, SceneError> {
        validate(scene)?;
        let mut w = ParticleWorld {
            settings: scene.settings.clone(),
            scene_bodies: scene.bodies.len(),
            bodies: scene.bodies.len(),
            solver,
            particles: Particles::default(),
            bones: Vec::new(),
            kinds: BoneKinds::building(),
            joints: Vec::new(),
            joint_kinds: JointKinds::building(),
            links: Vec::new(),
            filter: Filter::default(),
            contacts: ContactSet::default(),
            pairs: Vec::new(),
            manifolds: Vec::new(),
            paper: None,
            xpbd: None,
            kinematic: Vec::new(),
            motors: Vec::new(),
            grab: None,
            time: 0.0,
            phase_times: PhaseTimes::default(),
        };
        let mut masses = Vec::with_capacity(scene.bodies.len());
        for b in &scene.bodies {
            masses.push(mass_props(b)?.mass);
        }
        // Shapes first so an unusable hull is reported before anything is built.
        for b in &scene.bodies {
            collider(b)?;
        }
        match solver {
            ParticleSolver::RigidFrames | ParticleSolver::Xpbd => {
                for (i, b) in scene.bodies.iter().enumerate() {
                    let bone = w.particulated_bone(i, b)?;
                    w.bones.push(bone);
                }
            }
            ParticleSolver::Paper => {
                let mut st = paper::build(&mut w, scene, &masses);
                st.shrink_to_fit();
                w.paper = Some(st);
            }
        }
        w.assign_figures(scene);
        let frames: Vec<(Vec3, Quat)> =
            w.bones.iter().map(|b| (Vec3::from(b.com), b.rot)).collect();
        let rf = RestFrames { frames: &frames };
        let mut excluded = Vec::new();
        for c in &scene.constraints {
            let a = Some(c.body1.index());
            let b = c.body2.body().map(|b| b.index());
            let mass_a = w.bones.get(c.body1.index()).map_or(0.0, |b| b.mass);
            let g = w.settings.gravity.length();
            let joint = Joint::new(&rf, (a, b), c, (mass_a, g), &mut w.joint_kinds);
            w.joints.push(joint);
            if let Some(b) = b {
                excluded.push((c.body1.index(), b));
            }
        }
        w.links = w.joints.iter().map(Link::of).collect();
        if matches!(solver, ParticleSolver::RigidFrames | ParticleSolver::Xpbd) {
            // A pose that starts outside a limit is brought in at a bounded speed and
            // by position only (`rigid_frames::close_start_slack`,
            // `xpbd::step::close_start_slack`), not in one substep.
            for j in &mut w.joints {
                j.slack = j.limit_violation(w.joint_kinds.of(j), &w.bones);
            }
        }
        if solver == ParticleSolver::Xpbd {
            w.xpbd = Some(xpbd::XpbdState::new(&mut w.bones, &w.kinds, &w.joints));
        }
        excluded.extend(w.rest_overlaps());
        w.filter = Filter::new(w.bones.len(), &excluded);
        // Built by pushing, these arrays have up to twice the room they use; they keep
        // their size from here on (a projectile is the only thing ever added).
        w.bones.shrink_to_fit();
        w.kinds.seal();
        w.joints.shrink_to_fit();
        w.joint_kinds.seal();
        w.particles.shrink_to_fit();
        Ok(w)
    }

    /// A bone with everything but its particles (used by both placements): its frame
    /// at the body's pose, its kind, its placement (rest corners `rest`, shape frame
    /// `shape_in_bone` in the bone frame) and materials those of the table
    /// ([`BoneKinds`]).
    fn make_bone(
        &mut self,
        body: usize,
        desc: &BodyDesc,
        mass: f32,
        rest: [Vec3; 4],
        shape_in_bone: Pose,
    ) -> Bone {
        let kind = self.kinds.kind(BoneKind {
            shape: BodyCollider::new(desc)
                .unwrap_or_else(|_| BodyCollider::Shared(SharedShape::ball(0.01))),
            shape_com: mass_props(desc).map(|m| m.local_com).unwrap_or(Vec3::ZERO),
            drawn: desc.shape.clone(),
        });
        let placement = self.kinds.placement_index(Placement {
            rest,
            shape_in_bone,
        });
        let material = self.kinds.material_index(Material {
            friction: desc.friction.contact,
            restitution: desc.restitution,
            air: (desc.friction.linear, desc.friction.angular),
        });
        Bone {
            body: body as u32,
            kind,
            placement,
            material,
            com: desc.pose.position.into(),
            dcom: Vec3A::ZERO,
            rot: desc.pose.rotation,
            prev_rot: desc.pose.rotation,
            dturn: Quat::IDENTITY,
            mass,
            inv_inertia_local: Vec3A::ZERO,
            fixed: desc.is_fixed(),
            asleep: false,
            sleep_time: 0.0,
            still_at: desc.pose.position,
            still_turn: desc.pose.rotation,
            still_time: 0.0,
            lin_vel: desc.linear_velocity.into(),
            ang_vel: desc.angular_velocity.into(),
            figure: body as u32,
            self_collision: desc.self_collision,
        }
    }

    /// The improved placement of one body: particles reproducing its mass properties.
    fn particulated_bone(&mut self, body: usize, desc: &BodyDesc) -> Result<Bone, SceneError> {
        let mp = mass_props(desc)?;
        let p = placement::particulate(&mp);
        let shape_in_bone = Pose {
            position: -(p.bone_in_shape.rotation.inverse() * p.bone_in_shape.position),
            rotation: p.bone_in_shape.rotation.inverse(),
        };
        let mut bone = self.make_bone(body, desc, mp.mass, p.rest, shape_in_bone);
        let frame = desc.pose.mul_pose(&p.bone_in_shape);
        bone.com = frame.position.into();
        bone.rot = frame.rotation;
        bone.prev_rot = bone.rot;
        bone.inv_inertia_local = p
            .principal_inertia
            .map(|i| if i > 0.0 { 1.0 / i } else { 0.0 })
            .into();
        let s = &self.settings;
        let (dt, g) = (s.timestep, s.gravity);
        let movable = !desc.is_fixed();
        if self.solver == ParticleSolver::RigidFrames {
            // The velocity form of Verlet keeps its velocity half a substep back,
            // `v − ½ g h` (see `Particles::push`), which makes free fall exact.
            let h = dt / rigid_frames::substeps(s) as f32;
            if movable {
                bone.lin_vel -= Vec3A::from(g * (0.5 * h));
            }
            return Ok(bone);
        }
        if self.solver == ParticleSolver::Xpbd {
            // Its particles are made from the frame and velocities (`XpbdState::add_bone`).
            return Ok(bone);
        }
        let ids = std::array::from_fn(|k| {
            let x = Vec3::from(bone.world(p.rest[k]));
            let v = desc.linear_velocity + desc.angular_velocity.cross(x - Vec3::from(bone.com));
            self.particles.push(
                x,
                v,
                g,
                dt,
                if movable { mp.mass * 0.25 } else { 0.0 },
                movable,
            )
        });
        self.particles.of_bone.push(ids);
        Ok(bone)
    }

    /// Where bone `i`'s four particles are now: the paper's particles, or the corners of
    /// the improved bone's frame.
    pub(crate) fn corners(&self, i: usize) -> [Vec3; 4] {
        let b = &self.bones[i];
        match self.solver {
            ParticleSolver::RigidFrames => std::array::from_fn(|k| b.corner(&self.kinds, k)),
            ParticleSolver::Paper => {
                self.particles.of_bone[i].map(|p| self.particles.x[p as usize])
            }
            ParticleSolver::Xpbd => match &self.xpbd {
                Some(st) => st.particles.bone(i),
                None => std::array::from_fn(|k| b.corner(&self.kinds, k)),
            },
        }
    }

    /// The rest lengths of bone `i`'s six sticks (`EDGES`): the paper solver's own
    /// ([`paper::PaperState::bone_sticks`]), else those of its rest particles.
    pub(crate) fn stick_rest(&self, i: usize) -> [f32; 6] {
        match &self.paper {
            Some(st) => st.bone_sticks(i),
            None => self.bones[i].rest_stick_lengths(&self.kinds),
        }
    }

    /// Figures: connected components of the joint graph.
    fn assign_figures(&mut self, scene: &SceneDesc) {
        let n = self.bones.len();
        let mut fig: Vec<u32> = (0..n as u32).collect();
        // Few constraints: relax labels to the minimum until stable.
        loop {
            let mut changed = false;
            for c in &scene.constraints {
                if let Some(b) = c.body2.body() {
                    let (i, j) = (c.body1.index(), b.index());
                    let m = fig[i].min(fig[j]);
                    if fig[i] != m || fig[j] != m {
                        fig[i] = m;
                        fig[j] = m;
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        for (b, f) in self.bones.iter_mut().zip(fig) {
            b.figure = f;
        }
    }

    /// The pairs of bones of one figure that overlap in the rest pose: they never collide
    /// with each other (a figure built that way means them to pass through each other).
    /// Bodies of different figures that start inside each other do collide and are
    /// pushed apart, as the multibody method does.
    fn rest_overlaps(&self) -> Vec<(usize, usize)> {
        let margin = vec![0.0; self.bones.len()];
        let mut pairs = Vec::new();
        broad_all(&self.bones, &self.kinds, &margin, &mut pairs);
        let mut manifolds = Vec::new();
        pairs.retain(|&(i, j)| {
            if self.bones[i].figure != self.bones[j].figure {
                return false;
            }
            let mut overlap = false;
            let bones = (&self.bones[..], &self.kinds);
            contacts::shape_pair(bones, i, j, 0.0, &mut manifolds, |_, _, _, d| {
                overlap |= d < -1e-3
            });
            overlap
        });
        pairs
    }

    /// The solver in use.
    pub fn solver(&self) -> ParticleSolver {
        self.solver
    }

    /// Total energy with the integrator's own particle velocities (J): the state's
    /// energy, `Σ ½ m_p |v_p|² + m_p g h_p` with `v_p` the velocity the next step starts
    /// from. [`Method::sample`] reports the same energy.
    pub fn state_energy(&self) -> f64 {
        match &self.xpbd {
            Some(st) => {
                let (k, p) = xpbd::measure::energy(self, st);
                k + p
            }
            None => measure::state_energy(self),
        }
    }
}

/// Broad phase ignoring the filter (used to find rest overlaps).
fn broad_all(bones: &[Bone], kinds: &BoneKinds, margin: &[f32], out: &mut Vec<(usize, usize)>) {
    contacts::broad_phase((bones, kinds), margin, &Filter::default(), out);
}

/// The improved world of a shipped scene, `assets/scenes/{file}`, with `count` figures
/// where the scene takes a count (the pile): the worlds of the particle method's unit
/// tests.
#[cfg(test)]
pub(crate) fn scene_world(file: &str, count: Option<u32>) -> ParticleWorld {
    solver_scene_world(file, count, ParticleSolver::RigidFrames)
}

/// [`scene_world`] with the particle solver `solver`.
#[cfg(test)]
pub(crate) fn solver_scene_world(
    file: &str,
    count: Option<u32>,
    solver: ParticleSolver,
) -> ParticleWorld {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/scenes")
        .join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
    solver_text_world(&text, &path, count, solver)
}

/// The improved solver's world of the `.af` text `text` (`path` names it and anchors
/// its relative paths), `count` figures where the scene repeats one; panics on error.
#[cfg(test)]
pub(crate) fn text_world(text: &str, path: &std::path::Path, count: Option<u32>) -> ParticleWorld {
    solver_text_world(text, path, count, ParticleSolver::RigidFrames)
}

/// [`text_world`] with the particle solver `solver`.
#[cfg(test)]
fn solver_text_world(
    text: &str,
    path: &std::path::Path,
    count: Option<u32>,
    solver: ParticleSolver,
) -> ParticleWorld {
    use crate::scene::af::{AfOptions, parse};
    let opts = AfOptions {
        count,
        ..AfOptions::default()
    };
    let scene = parse(text, path, &opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .desc;
    ParticleWorld::new(&scene, solver).unwrap_or_else(|e| panic!("{e}"))
}

/// Numbers in [0, 1] from a xorshift generator seeded with `seed`: the same every run
/// (the random cases of the particle method's unit tests).
#[cfg(test)]
pub(crate) fn uniform(mut seed: u32) -> impl FnMut() -> f32 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed as f32 / u32::MAX as f32
    }
}

/// The mouse grab in improved mode: a soft XPBD point constraint to the target.
pub(crate) fn grab_improved(bones: &mut [Bone], kinds: &BoneKinds, g: Grab, h: f32) {
    let Some(i) = bones.iter().position(|b| b.body as usize == g.body.index()) else {
        return;
    };
    let local = kinds
        .placement(&bones[i])
        .shape_in_bone
        .transform_point(g.local_point);
    let p = bones[i].world(local);
    let target = Vec3A::from(g.target);
    // A 5 Hz spring on the bone's own mass, like Box2D's mouse joint: compliance
    // α = 1/k with k = m ω², ω = 2π·5 s⁻¹. Scaled by the mass so a light hand and a heavy
    // chest follow the mouse alike; for the human's 15 kg chest k ≈ 15 kN/m, so the rest
    // of the body hanging from it (≈ 400 N) stretches it by about 3 cm.
    let omega = std::f32::consts::TAU * 5.0;
    let compliance = 1.0 / (bones[i].mass.max(1e-3) * omega * omega);
    bone::positional(
        bones,
        Some(i),
        None,
        p,
        target,
        target - p,
        compliance / (h * h),
    );
}

/// The mouse grab in paper mode: pull the bone's particles towards the target.
pub(crate) fn grab_paper(w: &mut ParticleWorld, g: Grab) {
    let Some(i) = w
        .bones
        .iter()
        .position(|b| b.body as usize == g.body.index())
    else {
        return;
    };
    let local = w
        .kinds
        .placement(&w.bones[i])
        .shape_in_bone
        .transform_point(g.local_point);
    let p = Vec3::from(w.bones[i].world(local));
    let d = (g.target - p) * 0.05;
    for &k in &w.particles.of_bone[i] {
        if w.particles.inv_mass[k as usize] > 0.0 {
            w.particles.x[k as usize] += d;
        }
    }
}

impl Method for ParticleWorld {
    fn kind(&self) -> MethodKind {
        MethodKind::Particle
    }

    fn solver_label(&self) -> String {
        let s = &self.settings;
        match self.solver {
            ParticleSolver::Paper => format!("paper, {} iterations", s.iterations),
            // The panel's sliders are substeps and iterations; say how they make the
            // substeps the solver runs (one constraint pass each).
            ParticleSolver::RigidFrames => format!(
                "rigid frames, {} substeps ({} × {} iterations)",
                rigid_frames::substeps(s),
                s.substeps.max(1),
                s.iterations.max(1)
            ),
            ParticleSolver::Xpbd => match s.xpbd_substeps {
                None => format!(
                    "xpbd particles, {} substeps × {} passes ({} × {} iterations)",
                    rigid_frames::substeps(s),
                    s.xpbd_passes,
                    s.substeps.max(1),
                    s.iterations.max(1)
                ),
                Some(n) => format!("xpbd particles, {n} substeps × {} passes", s.xpbd_passes),
            },
        }
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn step(&mut self) {
        self.advance_kinematic();
        self.apply_motors();
        match self.solver {
            ParticleSolver::RigidFrames => rigid_frames::step(self),
            ParticleSolver::Paper => {
                if let Some(st) = self.paper.take() {
                    paper::step(self, &st);
                    self.paper = Some(st);
                }
            }
            ParticleSolver::Xpbd => {
                // Its phases are not split yet: the step's wall time only.
                let clock = PhaseClock::start();
                if let Some(mut st) = self.xpbd.take() {
                    xpbd::step::step(self, &mut st);
                    self.xpbd = Some(st);
                }
                self.phase_times = PhaseTimes::default();
                clock.finish(&mut self.phase_times);
            }
        }
        self.finish_kinematic();
        self.time += self.settings.timestep as f64;
    }

    fn set_settings(&mut self, settings: &Settings) {
        let old = self.settings.timestep;
        if self.solver == ParticleSolver::Paper
            && old != settings.timestep
            && settings.timestep > 0.0
        {
            self.particles.rescale_verlet(old, settings.timestep);
        }
        self.settings = settings.clone();
    }

    fn settings(&self) -> &Settings {
        &self.settings
    }

    fn snapshot(&self, out: &mut RenderSnapshot) {
        out.clear();
        for (bone, b) in self.bones.iter().enumerate() {
            let role = if b.fixed {
                BodyRole::Fixed
            } else if self.grab.is_some_and(|g| g.body.index() == b.body as usize) {
                BodyRole::Grabbed
            } else if b.body as usize >= self.scene_bodies {
                BodyRole::Projectile
            } else if b.asleep {
                BodyRole::Asleep
            } else {
                BodyRole::Dynamic
            };
            out.bodies.push(BodyInstance {
                body: BodyId(b.body),
                shape: self.kinds.of(b).drawn.clone(),
                pose: b.shape_pose(&self.kinds),
                role,
            });
            let corners = self.corners(bone);
            for &(i, j) in &EDGES {
                out.sticks.push(StickInstance {
                    a: corners[i],
                    b: corners[j],
                    role: StickRole::Bone,
                });
            }
            if matches!(
                self.solver,
                ParticleSolver::RigidFrames | ParticleSolver::Xpbd
            ) {
                let role = if b.fixed {
                    ParticleRole::Fixed
                } else {
                    ParticleRole::Internal
                };
                out.particles
                    .extend(corners.map(|position| ParticleInstance { position, role }));
            }
        }
        for i in 0..self.particles.len() {
            out.particles.push(ParticleInstance {
                position: self.particles.x[i],
                role: if self.particles.inv_mass[i] == 0.0 {
                    ParticleRole::Fixed
                } else if self.particles.is_joint(i) {
                    ParticleRole::Joint
                } else {
                    ParticleRole::Internal
                },
            });
        }
        if let Some(st) = &self.xpbd {
            for c in &st.contacts {
                let (pa, pb) = (c.a.point(&st.particles), c.b.point(&st.particles));
                out.contacts.push(ContactInstance {
                    point: pa,
                    normal: c.n,
                    depth: (pa - pb).dot(c.n),
                });
            }
        }
        let (manifolds, points) = (&self.contacts.manifolds, &self.contacts.points);
        for (m, run) in manifolds
            .iter()
            .zip(contacts::ranges(manifolds, points.len()))
        {
            for c in &points[run] {
                let pa = self.bones[m.a()].world(c.ra);
                let pb = bone::side_world(&self.bones, m.b(), c.rb);
                out.contacts.push(ContactInstance {
                    point: Vec3::from(pa),
                    normal: Vec3::from(m.n()),
                    depth: (pa - pb).dot(m.n()),
                });
            }
        }
        for j in &self.joints {
            let k = self.joint_kinds.of(j);
            if !k.has_anchor {
                continue;
            }
            let (a, b) = j.anchors(&self.bones);
            let limit = match k.swing {
                Some(s) => match s.kind {
                    limits::Swing::Cone { half_angle, .. } => LimitShape::Cone {
                        axis: bone::side_rot(&self.bones, j.b()) * s.axis_b,
                        half_angle,
                    },
                    limits::Swing::Pyramid { h1, h2, .. } => LimitShape::Cone {
                        axis: bone::side_rot(&self.bones, j.b()) * s.axis_b,
                        half_angle: h1.max(h2),
                    },
                },
                None => match (k.joint_type, k.angle_limits.first()) {
                    (joints::JointType::Hinge { .. }, Some(l)) => LimitShape::Arc {
                        axis: bone::side_rot(&self.bones, j.a()) * l.axis_a,
                        reference: bone::side_rot(&self.bones, j.b()) * l.ref_b,
                        min: l.min,
                        max: l.max,
                    },
                    _ => LimitShape::None,
                },
            };
            out.joints.push(JointInstance {
                anchor: a,
                anchor2: b,
                limit,
            });
            out.sticks.push(StickInstance {
                a,
                b,
                role: StickRole::Joint,
            });
        }
    }

    fn sample(&self) -> Sample {
        let mut s = measure::sample(self);
        if let Some(st) = &self.xpbd {
            let (kinetic, potential) = xpbd::measure::energy(self, st);
            s.energy = kinetic + potential;
            s.kinetic = kinetic;
        }
        s
    }

    fn body_count(&self) -> usize {
        self.bones.len()
    }

    fn awake_body_count(&self) -> usize {
        self.bones.iter().filter(|b| !b.is_static()).count()
    }

    fn particle_count(&self) -> usize {
        match self.solver {
            ParticleSolver::RigidFrames => 4 * self.bones.len(),
            ParticleSolver::Paper => self.particles.len(),
            ParticleSolver::Xpbd => self.xpbd.as_ref().map_or(0, |st| st.particles.len()),
        }
    }

    fn body_states(&self, out: &mut Vec<BodyState>) {
        match &self.xpbd {
            Some(st) => xpbd::measure::body_states(self, st, out),
            None => measure::body_states(self, out),
        }
    }

    fn particle_positions(&self, out: &mut Vec<Vec3>) {
        out.clear();
        match self.solver {
            ParticleSolver::RigidFrames => {
                out.extend((0..self.bones.len()).flat_map(|i| self.corners(i)))
            }
            ParticleSolver::Paper => out.extend_from_slice(&self.particles.x),
            ParticleSolver::Xpbd => {
                if let Some(st) = &self.xpbd {
                    out.extend(st.particles.x.iter().map(|x| x.as_vec3()))
                }
            }
        }
    }

    fn raycast(&self, origin: Vec3, dir: Vec3) -> Option<RayHit> {
        let ray = Ray::new(origin, dir);
        let mut best: Option<RayHit> = None;
        for b in &self.bones {
            let kind = self.kinds.of(b);
            let pose = b.parry_pose(&self.kinds);
            if let Some(t) = kind
                .shape
                .get()
                .shape()
                .cast_ray(&pose, &ray, f32::MAX, true)
                && best.is_none_or(|h| t < h.distance)
            {
                let local = b
                    .shape_pose(&self.kinds)
                    .inverse_transform_point(origin + dir * t);
                best = Some(RayHit {
                    body: BodyId(b.body),
                    distance: t,
                    local_point: local,
                });
            }
        }
        best
    }

    fn set_grab(&mut self, grab: Option<Grab>) {
        if let Some(g) = grab {
            for b in self.bones.iter_mut() {
                if b.body as usize == g.body.index() {
                    b.wake();
                }
            }
        }
        self.grab = grab;
    }

    fn phase_times(&self) -> PhaseTimes {
        self.phase_times
    }

    fn drop_by_owner(self: Box<Self>, dropped: &mut dyn FnMut(&'static str)) {
        let ParticleWorld {
            particles,
            bones,
            kinds,
            joints,
            joint_kinds,
            links,
            filter,
            contacts,
            pairs,
            manifolds,
            paper,
            xpbd,
            kinematic,
            motors,
            ..
        } = *self;
        drop((bones, kinds));
        dropped("bones");
        drop((joints, joint_kinds, links, filter, motors, kinematic));
        dropped("joints, links, filter");
        drop(contacts);
        dropped("contact points");
        drop((pairs, manifolds));
        dropped("contact pairs");
        drop(particles);
        dropped("particles");
        drop(paper);
        dropped("paper: sticks, limits");
        if let Some(st) = xpbd {
            drop(st.contacts);
            dropped("xpbd: contact points");
            drop(st.scratch);
            dropped("xpbd: detection scratch");
            drop((st.joint_start, st.limit_lambda));
            dropped("xpbd: joint block starts");
            drop((st.particles, st.anchors, st.rest));
            dropped("xpbd: particles");
        }
    }

    fn apply_impulse(&mut self, body: BodyId, impulse: Vec3, point: Vec3) {
        ParticleWorld::apply_impulse(self, body, impulse, point);
    }

    fn set_body_poses(&mut self, poses: &[BodyPoseSet]) {
        ParticleWorld::set_body_poses(self, poses);
    }

    fn set_kinematic(&mut self, body: BodyId, kinematic: bool) {
        ParticleWorld::set_kinematic(self, body, kinematic);
    }

    fn is_kinematic(&self, body: BodyId) -> bool {
        ParticleWorld::is_kinematic(self, body)
    }

    fn move_kinematic(&mut self, body: BodyId, target: Pose, dt: f32) {
        ParticleWorld::move_kinematic(self, body, target, dt);
    }

    fn set_joint_motors(&mut self, motors: &[crate::motor::JointMotor]) {
        ParticleWorld::set_joint_motors(self, motors);
    }

    fn add_body(&mut self, desc: &BodyDesc) -> BodyId {
        let id = self.bodies;
        self.bodies += 1;
        if let Ok(mut bone) = self.particulated_bone(id, desc) {
            bone.figure = id as u32;
            if let Some(st) = self.xpbd.as_mut() {
                st.add_bone(self.bones.len(), &bone, &self.kinds);
            }
            if self.solver == ParticleSolver::Paper {
                // The paper's frame: particle 0 and Gram–Schmidt, shape stored in it
                // (the bone's placement is its own: a projectile's is never shared).
                let x = &self.particles.x;
                let shape_pose = bone.shape_pose(&self.kinds);
                let ids = self.particles.of_bone[self.bones.len()];
                bone.paper_frame(ids, x);
                let frame = Pose {
                    position: Vec3::from(bone.com),
                    rotation: bone.rot,
                };
                // Its sticks are as long as the placement's rest particles are apart.
                let stick_rest = bone.rest_stick_lengths(&self.kinds);
                let placement = self.kinds.placement_mut(&bone);
                placement.rest = ids.map(|p| frame.inverse_transform_point(x[p as usize]));
                placement.shape_in_bone = Pose {
                    position: frame.inverse_transform_point(shape_pose.position),
                    rotation: (frame.rotation.inverse() * shape_pose.rotation).normalize(),
                };
                if let Some(st) = self.paper.as_mut() {
                    st.push_bone_sticks(stick_rest);
                }
            }
            self.bones.push(bone);
        }
        BodyId(id as u32)
    }
}
