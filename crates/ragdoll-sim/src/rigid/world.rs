//! [`MultibodyWorld`]: the multibody method built from a `SceneDesc`, behind the
//! [`Method`] trait.

use super::body::{BodyInfo, BodyMotion, BodyNames, BodyStates, FullInertia, Motions};
use super::contact::{Contacts, GroundCollider, may_collide, shape_pose};
use super::impulse::Bodies;
use super::island::Islands;
use super::joint_set::JointSet;
use super::parallel::IslandTasks;
use super::solver;
use super::substeps::SolveBuffers;
use crate::method::{BodyPoseSet, BodyState, Grab, Method, MethodKind, RayHit, Sample};
use crate::metrics::potential_energy;
use crate::motor::JointMotor;
use crate::scene::{
    BodyDesc, BodyId, BodyRef, Pose, SceneDesc, SceneError, Settings, collider, mass_props,
    validate,
};
use crate::snapshot::{BodyInstance, BodyRole, ContactInstance, RenderSnapshot};
use crate::timings::PhaseTimes;
use glam::{Quat, Vec3, Vec3A};
use parry3d::math::Pose as PPose;
use parry3d::query::{self, Ray};
use parry3d::shape::SharedShape;

/// The impulse-based multibody world (right, red).
pub struct MultibodyWorld {
    settings: Settings,
    states: BodyStates,
    info: Vec<BodyInfo>,
    names: BodyNames,
    motion: Vec<BodyMotion>,
    /// The tensors of the bodies whose inertia is not diagonal (see [`BodyMotion`]).
    full_inertia: Vec<FullInertia>,
    joints: JointSet,
    contacts: Contacts,
    islands: Islands,
    awake: Vec<bool>,
    dynamic: Vec<bool>,
    /// Per body: kinematic (moved by the game, fixed to the solver; `kinematic`).
    kinematic: Vec<bool>,
    /// The joint motors in force ([`crate::motor`]).
    motors: Vec<JointMotor>,
    time: f64,
    grab: Option<Grab>,
    /// The last step's phase times, for display only.
    phase_times: PhaseTimes,
    /// The constraint arrays of the step's solve, and the islands' batches of a
    /// parallel one, kept between steps.
    buffers: SolveBuffers,
    island_tasks: IslandTasks,
}

impl MultibodyWorld {
    /// Builds the world from a scene: validates it, computes mass properties, creates the
    /// joints at the rest pose and the contact exclusions (jointed pairs, pairs of the same
    /// figure that overlap at rest).
    pub fn new(scene: &SceneDesc) -> Result<MultibodyWorld, SceneError> {
        validate(scene)?;
        let n = scene.bodies.len();
        // Figures: connected components of the joint graph.
        let mut figure: Vec<u32> = (0..n as u32).collect();
        fn root(f: &mut [u32], mut i: u32) -> u32 {
            while f[i as usize] != i {
                i = f[i as usize];
            }
            i
        }
        for c in &scene.constraints {
            if let BodyRef::Body(b) = c.body2 {
                let (ra, rb) = (root(&mut figure, c.body1.0), root(&mut figure, b.0));
                figure[ra.max(rb) as usize] = ra.min(rb);
            }
        }
        // The bodies and the static anchor.
        let mut states = BodyStates::with_capacity(n + 1);
        let mut info = Vec::with_capacity(n);
        let mut motion = Vec::with_capacity(n);
        let mut full_inertia = Vec::new();
        let mut hulls = Vec::new();
        let mut names =
            BodyNames::with_capacity(n, scene.bodies.iter().map(|b| b.name.len()).sum());
        for (i, b) in scene.bodies.iter().enumerate() {
            let mp = mass_props(b)?;
            let shape = collider(b)?;
            let fig = root(&mut figure, i as u32);
            info.push(BodyInfo::new(b, &mp, shape, fig, &mut hulls));
            names.push(&b.name);
            motion.push(BodyMotion::new(b, &mp, &mut full_inertia));
            let com = b.pose.transform_point(mp.local_com);
            let (v, w) = if b.is_fixed() {
                (Vec3::ZERO, Vec3::ZERO)
            } else {
                (b.linear_velocity, b.angular_velocity)
            };
            states.push(com, b.pose.rotation, v, w);
        }
        // Pushed one hull at a time; their sizes are known now.
        full_inertia.shrink_to_fit();
        hulls.shrink_to_fit();
        // The static anchor: the world and the ground.
        states.push(Vec3::ZERO, Quat::IDENTITY, Vec3::ZERO, Vec3::ZERO);
        let dynamic: Vec<bool> = info.iter().map(|b: &BodyInfo| !b.fixed).collect();
        let g = scene.settings.gravity.length();
        let joints = JointSet::build(&scene.constraints, &states, &info, n, g);

        let mut contacts = Contacts::default();
        contacts.hulls = hulls;
        joints.for_each_pair(|a, b| {
            if b < n {
                contacts.excluded.push((a.min(b) as u32, a.max(b) as u32));
            }
        });
        for a in 0..n {
            for b in a + 1..n {
                if info[a].figure != info[b].figure || !may_collide(&info, a, b) {
                    continue;
                }
                let (pa, pb) = (shape_pose(&states, &info, a), shape_pose(&states, &info, b));
                let hulls = &contacts.hulls;
                let (ca, cb) = (info[a].collider(hulls), info[b].collider(hulls));
                let overlap = query::contact(&pa, ca.shape(), &pb, cb.shape(), 0.0)
                    .ok()
                    .flatten()
                    .is_some_and(|c| c.dist < -1e-3);
                if overlap {
                    contacts.excluded.push((a as u32, b as u32));
                }
            }
        }
        contacts.excluded.sort_unstable();
        contacts.excluded.dedup();
        contacts.ground = scene.settings.ground.map(|gr| {
            let rot = Quat::from_rotation_z(gr.tilt);
            let origin = Vec3::new(0.0, gr.height, 0.0);
            GroundCollider {
                shape: SharedShape::halfspace(Vec3::Y),
                pose: PPose::from_parts(origin, rot),
                normal: gr.normal(),
                origin,
                friction: gr.friction,
                restitution: gr.restitution,
            }
        });
        let islands = Islands::new(&states, n);
        let mut awake = vec![false; n + 1];
        solver::refresh_awake(&mut states, &info, &islands, &mut awake, &dynamic);
        Ok(MultibodyWorld {
            settings: scene.settings.clone(),
            states,
            info,
            names,
            motion,
            full_inertia,
            joints,
            contacts,
            islands,
            awake,
            dynamic,
            kinematic: vec![false; n],
            motors: Vec::new(),
            time: 0.0,
            grab: None,
            phase_times: PhaseTimes::default(),
            buffers: SolveBuffers::default(),
            island_tasks: IslandTasks::default(),
        })
    }

    /// Deepest overlap among colliding pairs and the ground now (m).
    fn max_penetration(&self) -> f32 {
        self.deepest_overlap().map_or(0.0, |d| d.0)
    }

    /// The deepest overlap now and its pair (body names; `"ground"` for the plane), for
    /// diagnostics.
    pub fn deepest_overlap(&self) -> Option<(f32, String, String)> {
        let n = self.info.len();
        let mut deepest = 0.0f32;
        let mut which = None;
        for p in &self.contacts.pairs {
            if !p.touching() {
                continue;
            }
            let (a, b) = (p.a as usize, p.b as usize);
            let pa = shape_pose(&self.states, &self.info, a);
            if b == n {
                // Against the plane: depth of the shape's support point along −n.
                let g = self
                    .contacts
                    .ground
                    .as_ref()
                    .expect("ground pair without ground");
                if let Some(sm) = self.info[a]
                    .collider(&self.contacts.hulls)
                    .shape()
                    .as_support_map()
                {
                    let local = sm.local_support_point(pa.rotation.inverse() * -g.normal);
                    let p = pa.transform_point(local);
                    let depth = -g.normal.dot(p - g.origin);
                    if depth > deepest {
                        deepest = depth;
                        which = Some((a, b));
                    }
                }
                continue;
            }
            let pb = shape_pose(&self.states, &self.info, b);
            if let Ok(Some(c)) = query::contact(
                &pa,
                self.info[a].collider(&self.contacts.hulls).shape(),
                &pb,
                self.info[b].collider(&self.contacts.hulls).shape(),
                0.0,
            ) && -c.dist > deepest
            {
                deepest = -c.dist;
                which = Some((a, b));
            }
        }
        let name = |i: usize| self.names.get(i).unwrap_or("ground").to_string();
        which.map(|(a, b)| (deepest, name(a), name(b)))
    }

    /// The bodies and their sleep state, for what acts on them from outside.
    fn bodies(&mut self) -> Bodies<'_> {
        Bodies {
            states: &mut self.states,
            info: &mut self.info,
            motion: Motions {
                bodies: &self.motion,
                full: &self.full_inertia,
            },
            islands: &mut self.islands,
            awake: &mut self.awake,
            dynamic: &mut self.dynamic,
            kinematic: &mut self.kinematic,
            hulls: &self.contacts.hulls,
        }
    }

    /// Current pose of body `i`'s shape frame.
    fn pose(&self, i: usize) -> Pose {
        let q = self.states.rot[i];
        Pose {
            position: self.states.com[i] - q * self.info[i].local_com,
            rotation: q,
        }
    }
}

impl Method for MultibodyWorld {
    fn kind(&self) -> MethodKind {
        MethodKind::Multibody
    }

    fn solver_label(&self) -> String {
        let s = &self.settings;
        format!(
            "soft step, {} substeps × ({} iterations + {} relax)",
            s.multibody_substep_count(),
            s.multibody_iteration_count(),
            s.relax_passes
        )
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn step(&mut self) {
        if let Some(g) = self.grab {
            // A stiff, critically damped mouse spring on the grabbed point (velocity level).
            let i = g.body.index();
            if i < self.info.len() && self.dynamic[i] {
                self.islands.asleep[i] = false;
                let q = self.states.rot[i];
                let r = q * (g.local_point - self.info[i].local_com);
                let p = self.states.com[i] + r;
                let dt = self.settings.timestep;
                let v = Vec3::from(self.states.point_velocity(i, r.into()));
                let dv = (g.target - p) * (0.5 / dt) - v;
                self.states.lin_vel[i] += Vec3A::from(dv * 0.5);
            }
        }
        let dt = self.settings.timestep;
        self.bodies().wake_kinematic_sweeps(dt);
        if !self.motors.is_empty() {
            let motors = std::mem::take(&mut self.motors);
            self.bodies().apply_motors(&motors, dt);
            self.motors = motors;
        }
        solver::step(
            &mut self.states,
            &self.info,
            Motions {
                bodies: &self.motion,
                full: &self.full_inertia,
            },
            &mut self.joints,
            &mut self.contacts,
            &mut self.islands,
            &mut self.awake,
            &self.dynamic,
            &self.settings,
            self.time as f32,
            &mut self.buffers,
            &mut self.island_tasks,
            &mut self.phase_times,
        );
        self.bodies().advance_kinematic(dt);
        self.time += self.settings.timestep as f64;
    }

    fn set_settings(&mut self, settings: &Settings) {
        self.settings = settings.clone();
    }

    fn settings(&self) -> &Settings {
        &self.settings
    }

    fn snapshot(&self, out: &mut RenderSnapshot) {
        out.clear();
        for (i, b) in self.info.iter().enumerate() {
            let role = if self.grab.is_some_and(|g| g.body.index() == i) {
                BodyRole::Grabbed
            } else if b.fixed {
                BodyRole::Fixed
            } else if b.projectile {
                BodyRole::Projectile
            } else if self.islands.asleep[i] {
                BodyRole::Asleep
            } else {
                BodyRole::Dynamic
            };
            out.bodies.push(BodyInstance {
                body: BodyId(i as u32),
                shape: b.shape.clone(),
                pose: self.pose(i),
                role,
            });
        }
        for p in &self.contacts.pairs {
            let (a, b) = (p.a as usize, p.b as usize);
            let normal = p.normal(self.states.rot[a]);
            for c in p.points() {
                let pa = self.states.com[a] + self.states.rot[a] * c.local_a;
                let pb = self.states.com[b] + self.states.rot[b] * c.local_b;
                out.contacts.push(ContactInstance {
                    point: (pa + pb) * 0.5,
                    normal,
                    depth: -normal.dot(pb - pa),
                });
            }
        }
        self.joints.draw(&self.states, &mut out.joints);
    }

    fn sample(&self) -> Sample {
        let mut kinetic = 0.0f64;
        let mut potential = 0.0f64;
        for (i, b) in self.info.iter().enumerate() {
            if b.fixed {
                continue;
            }
            let v = Vec3::from(self.states.lin_vel[i]);
            let w = Vec3::from(self.states.ang_vel[i]);
            let q = self.states.rot[i];
            // ½ ωᵀ I ω with I in body space: ω taken into the body frame.
            let wb = q.inverse() * w;
            kinetic += 0.5 * b.mass as f64 * v.length_squared() as f64
                + 0.5 * wb.dot(self.motion[i].inertia(&self.full_inertia) * wb) as f64;
            potential += potential_energy(&self.settings, b.mass, self.states.com[i]);
        }
        Sample {
            energy: kinetic + potential,
            kinetic,
            max_penetration: self.max_penetration(),
            max_joint_gap: self.joints.max_gap(&self.states),
            // Hard limits only; soft (PyODE tutorial) limits are exceeded by design, see
            // `BallJoint::limit_violation`.
            max_limit_violation_deg: self.joints.max_limit_violation(&self.states).to_degrees(),
            max_bone_stretch: None,
            all_asleep: (0..self.info.len()).all(|i| !self.dynamic[i] || self.islands.asleep[i]),
        }
    }

    fn body_count(&self) -> usize {
        self.info.len()
    }

    fn awake_body_count(&self) -> usize {
        (0..self.info.len())
            .filter(|&i| self.dynamic[i] && !self.islands.asleep[i])
            .count()
    }

    fn particle_count(&self) -> usize {
        0
    }

    fn body_states(&self, out: &mut Vec<BodyState>) {
        out.clear();
        for i in 0..self.info.len() {
            out.push(BodyState {
                com: self.states.com[i],
                orientation: self.states.rot[i],
                linear_velocity: self.states.lin_vel[i].into(),
                angular_velocity: self.states.ang_vel[i].into(),
            });
        }
    }

    fn particle_positions(&self, out: &mut Vec<Vec3>) {
        out.clear();
    }

    fn raycast(&self, origin: Vec3, dir: Vec3) -> Option<RayHit> {
        let ray = Ray::new(origin, dir);
        let mut best: Option<RayHit> = None;
        for (i, b) in self.info.iter().enumerate() {
            let pose = shape_pose(&self.states, &self.info, i);
            if let Some(t) =
                b.collider(&self.contacts.hulls)
                    .shape()
                    .cast_ray(&pose, &ray, f32::MAX, true)
                && best.is_none_or(|h| t < h.distance)
            {
                best = Some(RayHit {
                    body: BodyId(i as u32),
                    distance: t,
                    local_point: self.pose(i).inverse_transform_point(origin + dir * t),
                });
            }
        }
        best
    }

    fn set_grab(&mut self, grab: Option<Grab>) {
        self.grab = grab;
    }

    fn phase_times(&self) -> PhaseTimes {
        self.phase_times
    }

    fn drop_by_owner(self: Box<Self>, dropped: &mut dyn FnMut(&'static str)) {
        let MultibodyWorld {
            settings,
            states,
            info,
            names,
            motion,
            full_inertia,
            joints,
            contacts,
            islands,
            awake,
            dynamic,
            kinematic,
            motors,
            buffers,
            island_tasks,
            ..
        } = *self;
        drop(states);
        dropped("body states");
        drop((info, names, motion, full_inertia, awake, dynamic, kinematic));
        dropped("body info, motion, flags");
        joints.drop_by_owner(dropped);
        contacts.drop_by_owner(dropped);
        drop(islands);
        dropped("islands, sleep");
        buffers.drop_by_owner(dropped);
        island_tasks.drop_by_owner(dropped);
        drop((settings, motors));
        dropped("settings, motors");
    }

    fn apply_impulse(&mut self, body: BodyId, impulse: Vec3, point: Vec3) {
        self.bodies().apply_impulse(body.index(), impulse, point);
    }

    fn set_kinematic(&mut self, body: BodyId, kinematic: bool) {
        self.bodies().set_kinematic(body.index(), kinematic);
    }

    fn is_kinematic(&self, body: BodyId) -> bool {
        self.kinematic.get(body.index()).copied().unwrap_or(false)
    }

    fn move_kinematic(&mut self, body: BodyId, target: Pose, dt: f32) {
        self.bodies().move_kinematic(body.index(), target, dt);
    }

    fn set_joint_motors(&mut self, motors: &[JointMotor]) {
        self.motors.clear();
        self.motors.extend_from_slice(motors);
        self.bodies().wake_motored(motors);
    }

    fn set_body_poses(&mut self, poses: &[BodyPoseSet]) {
        let mut bodies = self.bodies();
        for p in poses {
            bodies.set_pose(p.body.index(), p.pose, p.velocity);
        }
    }

    fn add_body(&mut self, desc: &BodyDesc) -> BodyId {
        let i = self.info.len();
        let (Ok(mp), Ok(shape)) = (mass_props(desc), collider(desc)) else {
            // A degenerate projectile is not added; the caller gets the id it would have had.
            return BodyId(i as u32);
        };
        let mut b = BodyInfo::new(
            desc,
            &mp,
            shape,
            u32::MAX - i as u32,
            &mut self.contacts.hulls,
        );
        b.projectile = true;
        self.info.push(b);
        self.names.push(&desc.name);
        self.motion
            .push(BodyMotion::new(desc, &mp, &mut self.full_inertia));
        // Insert before the static anchor, which stays last.
        let com = desc.pose.transform_point(mp.local_com);
        let s = &mut self.states;
        s.com.insert(i, com);
        s.rot.insert(i, desc.pose.rotation);
        s.lin_vel.insert(i, desc.linear_velocity.into());
        s.ang_vel.insert(i, desc.angular_velocity.into());
        s.inv_mass.insert(i, 0.0);
        s.inv_inertia.insert(i, glam::Mat3A::ZERO);
        self.dynamic.push(!desc.is_fixed());
        self.kinematic.push(false);
        self.awake.insert(i, false);
        self.islands.push(&self.states, i);
        // Joints and contact pairs that named the anchor by index follow it.
        let old_anchor = i;
        let new_anchor = i + 1;
        self.joints.retarget_anchor(old_anchor, new_anchor);
        self.contacts.pairs.clear();
        solver::refresh_awake(
            &mut self.states,
            &self.info,
            &self.islands,
            &mut self.awake,
            &self.dynamic,
        );
        BodyId(i as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::af::{AfOptions, parse};
    use crate::scene::{MassSpec, Pose as BodyPose, Shape};

    /// A pile of ten humans solved with its ball joints and hinges in SIMD lanes and solved
    /// one by one gives the same bits, frame after frame — through the fall, the
    /// collisions, limits meeting their bounds, sleep, and a projectile inserted before
    /// the static anchor (the lanes must follow the anchor's index) — and stretches on
    /// two threads, whose islands are solved one by one, hand the impulses back and
    /// forth. Equal masses: no joint tree ([`super::joint_tree`]).
    #[test]
    fn joints_in_lanes_give_the_bits_of_joints_one_by_one() {
        lanes_match_one_by_one(true);
    }

    /// The same with the first figure's first body twenty times heavier than the rest,
    /// which puts that figure's point rows in a joint tree: the lanes solve all other
    /// rows around the tree with the bits of the one-by-one solve.
    #[test]
    fn joints_in_lanes_around_trees_give_the_bits_of_joints_one_by_one() {
        lanes_match_one_by_one(false);
    }

    /// A pile of twenty humans solved in batches of islands gathered into arrays of their
    /// own ([`super::parallel`]) gives the bits of the whole world solved in place, on one
    /// thread and on two, frame after frame through the fall, the landing (islands
    /// merging) and sleep.
    #[test]
    fn batches_of_islands_give_the_bits_of_the_world_in_place() {
        let scene = pile(20);
        let mut states = Vec::new();
        let mut bits = |w: &MultibodyWorld| {
            w.body_states(&mut states);
            let values = states.iter().flat_map(|b| {
                let v = [b.com, b.linear_velocity, b.angular_velocity];
                v.into_iter()
                    .flat_map(|v| v.to_array())
                    .chain(b.orientation.to_array())
            });
            values.map(f32::to_bits).collect::<Vec<_>>()
        };
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap_or_else(|e| panic!("{e}"));
            let mut batched = MultibodyWorld::new(&scene).unwrap_or_else(|e| panic!("{e}"));
            let mut in_place = MultibodyWorld::new(&scene).unwrap_or_else(|e| panic!("{e}"));
            batched.island_tasks.in_place = Some(false);
            in_place.island_tasks.in_place = Some(true);
            pool.install(|| {
                for frame in 0..240 {
                    batched.step();
                    in_place.step();
                    assert!(
                        bits(&batched) == bits(&in_place),
                        "{threads} threads, frame {frame}: the batches' bodies differ"
                    );
                }
            });
            assert!(batched.sample().all_asleep, "the pile did not settle");
        }
    }

    /// A joint tree that does not factor hands its joints back to Gauss–Seidel, whose
    /// rows read `K⁻¹`, which a joint in a tree leaves unweighed: the tree weighs it
    /// then, as a full preparation on the same pose and inertias would have.
    #[test]
    fn a_tree_that_does_not_factor_weighs_its_joints_for_gauss_seidel() {
        use super::super::joint::PointPart;
        use crate::lanes::{M3, V3};
        let mut w = MultibodyWorld::new(&pile(1)).unwrap_or_else(|e| panic!("{e}"));
        w.step();
        let MultibodyWorld {
            states: s,
            joints,
            awake,
            buffers,
            ..
        } = &mut w;
        assert!(
            awake[..s.len() - 1].iter().all(|&a| a),
            "the falling figure is awake"
        );
        // Without world inverse inertias each point row keeps an invertible
        // `K = (m_a⁻¹ + m_b⁻¹) 1`, but an inner body's block of the tree cannot be formed.
        s.inv_inertia
            .iter_mut()
            .for_each(|i| *i = glam::Mat3A::ZERO);
        let trees = buffers.trees_mut();
        trees.rebuild(joints, s, awake);
        joints.prepare(s, awake);
        let nan = V3 {
            x: f32::NAN,
            y: f32::NAN,
            z: f32::NAN,
        };
        let rows = &mut joints.rows;
        let points = (rows.ball.iter_mut().map(|r| &mut r.point))
            .chain(rows.hinge.iter_mut().map(|r| &mut r.point));
        for p in points {
            (p.k_inv, p.on) = (M3 { cols: [nan; 3] }, false);
        }
        trees.factor(joints, s);
        let bits = |m: &M3<f32>| m.lane(0).to_cols_array().map(f32::to_bits);
        let mut checked = 0;
        let balls = (joints.ball.iter()).map(|j| (j.point, j.frame));
        let hinges = (joints.hinge.iter()).map(|j| (j.point, j.frame));
        let rows = (joints.rows.ball.iter().map(|r| r.point))
            .chain(joints.rows.hinge.iter().map(|r| r.point));
        for ((point, frame), got) in balls.chain(hinges).zip(rows) {
            if !point.in_tree {
                continue;
            }
            assert!(!point.direct, "a joint of a tree that did not factor");
            let mut want = got;
            PointPart::weigh_all(&mut want, &frame, s);
            assert!(got.on && want.on);
            assert_eq!(bits(&got.k_inv), bits(&want.k_inv));
            checked += 1;
        }
        assert!(checked > 0, "no joint tree");
    }

    /// The rows a step prepares for the joints live in the arrays being solved: a world
    /// solved in batches holds none of its own (each batch's gathered arrays do), one
    /// solved in place holds one per joint that touches an awake body (fewer as the
    /// pile falls asleep) and gives them back at rest.
    #[test]
    fn joint_rows_live_in_the_arrays_being_solved() {
        let scene = pile(20);
        let mut batched = MultibodyWorld::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let mut in_place = MultibodyWorld::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        batched.island_tasks.in_place = Some(false);
        in_place.island_tasks.in_place = Some(true);
        let held = |w: &MultibodyWorld| {
            let r = &w.joints.rows;
            r.ball.capacity() + r.hinge.capacity() + r.universal.capacity() + r.fixed.capacity()
        };
        for _ in 0..5 {
            batched.step();
            in_place.step();
        }
        assert_eq!(held(&batched), 0, "the batched world holds joint rows");
        let j = &in_place.joints;
        assert!(!j.ball.is_empty() && !j.hinge.is_empty());
        assert_eq!(
            [j.rows.ball.len(), j.rows.hinge.len()],
            [j.ball.len(), j.hinge.len()],
            "in place, one row set per joint"
        );
        let mut frames = 0;
        let mut partly_asleep = false;
        while !in_place.sample().all_asleep {
            let before = in_place.awake.clone();
            in_place.step();
            frames += 1;
            assert!(frames < 600, "the pile did not settle");
            // The step solved with the sleep states it started with unless an island
            // woke or fell asleep during it.
            let (j, awake) = (&in_place.joints, &in_place.awake);
            if *awake != before || !awake.contains(&true) {
                continue;
            }
            let moved = |a: usize, b: usize| awake[a] || awake[b];
            let balls = j.ball.iter().filter(|j| moved(j.frame.a, j.frame.b));
            let hinges = j.hinge.iter().filter(|j| moved(j.frame.a, j.frame.b));
            let (balls, hinges) = (balls.count(), hinges.count());
            assert_eq!(
                [j.rows.ball.len(), j.rows.hinge.len()],
                [balls, hinges],
                "frame {frames}: one row set per joint touching an awake body"
            );
            partly_asleep |= 0 < balls && balls < j.ball.len();
        }
        assert!(
            partly_asleep,
            "no step had some figures asleep and some awake"
        );
        in_place.step();
        assert_eq!(held(&in_place), 0, "a world at rest keeps its joint rows");
    }

    /// The shipped pile scene with `count` humans.
    fn pile(count: u32) -> SceneDesc {
        let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/scenes/pile.af");
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
        let opts = AfOptions {
            count: Some(count),
            ..AfOptions::default()
        };
        parse(&text, &path, &opts)
            .unwrap_or_else(|e| panic!("{e}"))
            .desc
    }

    fn lanes_match_one_by_one(equal_masses: bool) {
        let mut scene = pile(10);
        for b in &mut scene.bodies {
            b.mass = MassSpec::Mass(5.0);
        }
        if !equal_masses {
            scene.bodies[0].mass = MassSpec::Mass(100.0);
        }
        let mut wide = MultibodyWorld::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let mut single = MultibodyWorld::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        single.joints.lanes_to_plan = None;
        let mut shot = BodyDesc::new(
            "shot",
            Shape::Box {
                half_extents: Vec3::splat(0.1),
            },
            BodyPose::from_position(Vec3::new(-3.0, 1.0, 0.0)),
            MassSpec::Mass(5.0),
        );
        shot.linear_velocity = Vec3::new(15.0, 0.0, 0.0);
        let pool = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap_or_else(|e| panic!("{e}"))
        };
        let pools = [pool(1), pool(2)];
        let bits = |w: &MultibodyWorld| {
            let s = &w.states;
            let v3 = |v: &[Vec3]| {
                v.iter()
                    .flat_map(|v| v.to_array())
                    .map(f32::to_bits)
                    .collect::<Vec<_>>()
            };
            let v3a = |v: &[glam::Vec3A]| {
                v.iter()
                    .flat_map(|v| v.to_array())
                    .map(f32::to_bits)
                    .collect::<Vec<_>>()
            };
            let q = s
                .rot
                .iter()
                .flat_map(|q| q.to_array())
                .map(f32::to_bits)
                .collect::<Vec<_>>();
            (v3(&s.com), q, v3a(&s.lin_vel), v3a(&s.ang_vel))
        };
        let mut trees = false;
        for frame in 0..240 {
            // One thread mostly; every fifth stretch of six frames on two.
            pools[usize::from(frame / 6 % 5 == 4)].install(|| {
                if frame == 60 {
                    wide.add_body(&shot);
                    single.add_body(&shot);
                }
                wide.step();
                single.step();
            });
            trees |= wide.joints.direct;
            let lanes = (wide.joints.lanes.as_ref()).expect("a pile's joints go into lanes");
            assert!(lanes.has_balls() && lanes.has_hinges());
            assert!(
                !wide.joints.trees_own_most(),
                "frame {frame}: the lanes stood aside"
            );
            assert!(
                bits(&wide) == bits(&single),
                "frame {frame}: the lanes' bodies differ"
            );
        }
        assert_eq!(trees, !equal_masses, "joint trees formed");
    }
}
