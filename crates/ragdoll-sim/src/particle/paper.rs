//! The paper's solver, section 3 as written (Glimberg & Engel 2007), so its findings can
//! be reproduced.
//!
//! - Verlet integration of equal-weight particles (2.5; the paper gives particles no
//!   masses, 3.1.1); bones are tetrahedra of 4 particles and 6 sticks (3.1.1).
//! - Joints share particles: one for a ball, two on the axis for a hinge (3.2). A bone
//!   takes a joint's particle as one of its four when that keeps its tetrahedron a
//!   tetrahedron; otherwise (a chest with four coplanar joints) the joint particle is
//!   tied to the bone by sticks to its four particles — the paper's own alternative of
//!   3.2, used only where sharing cannot work. Joints the paper does not have: universal
//!   acts as a ball; fixed and slider tie the two tetrahedra together by sticks; springs
//!   are not simulated.
//! - Hinge limits (3.3.1): two sticks from a reference particle of bone A to the limit
//!   points of a reference particle of bone B, satisfied when the reference particle
//!   leaves the range; the side test is an angle about the axis in A's frame, the same
//!   test as the two half planes plus the third plane through the rest position.
//! - Ball limits (3.3.2): a reach cone around a normal fixed in A; the reference
//!   particle of B must keep `p_dist ≥ c_dist = a cos θ` from the plane; when it does
//!   not, a stick to a particle of A gets rest length `|q − b| + (c_dist − p_dist)`.
//!   Pyramid limits act as their circumscribed cone; twist limits are not in the paper.
//! - Collisions (3.4–3.5): no tests between jointed bones; per pair only the deepest
//!   contact (equal depths averaged); box-mass split `Δa = M_b/(M_a+M_b) n d`; particle
//!   weights `c_i = (1 − |P − p_i| / Σ_j |P − p_j|)/3`, `λ = 1/Σ c_i²`,
//!   `p_i' = p_i + c_i λ Δ`.
//! - Friction (3.6 and appendix C): on every handled collision the old positions of both
//!   bones move towards the current ones by `0.00025 / N · c_i`.
//! - N rounds of relaxation and projection per step. Fixed bones take no correction.

use super::ParticleWorld;
use super::bone::{EDGES, gram_schmidt};
use super::contacts::{broad_phase, ground_pair, shape_pair};
use super::placement::{fill_far_apart, independent, paper_candidates};
use crate::scene::{JointKind, SceneDesc, SwingLimit};
use crate::timings::{PhaseClock, PhaseTimes};
use glam::{Quat, Vec3};

/// The paper's friction constant (appendix C, `m_friction(0.00025)`).
const PAPER_FRICTION: f32 = 0.00025;

/// A distance constraint between two particles (Jakobsen 2001).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stick {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length.
    pub rest: f32,
}

/// A hinge limit (3.3.1).
#[derive(Clone, Copy, Debug)]
pub(crate) struct HingeLimit {
    /// Bone A (body2), `None` for the world.
    pub bone_a: Option<u32>,
    /// The two axis particles; the axis points from `p1` to `p2`.
    pub p1: u32,
    /// Second axis particle.
    pub p2: u32,
    /// Reference particle in A.
    pub ref_a: u32,
    /// Reference particle in B.
    pub ref_b: u32,
    /// B's reference direction at rest, perpendicular to the axis, in A's frame.
    pub rest_dir: Vec3,
    /// Range (rad).
    pub min: f32,
    /// Range (rad).
    pub max: f32,
    /// Stick rest lengths to the limit points at `min` and `max`.
    pub len_min: f32,
    /// See `len_min`.
    pub len_max: f32,
}

/// A ball-joint reach cone (3.3.2).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ConeLimit {
    /// Bone A (body2), `None` for the world.
    pub bone_a: Option<u32>,
    /// The joint particle.
    pub joint: u32,
    /// Reference particle in B.
    pub ref_b: u32,
    /// Particle of A the limit stick pulls against.
    pub other_a: u32,
    /// Cone normal in A's frame.
    pub normal: Vec3,
    /// `c_dist = a cos θ`.
    pub c_dist: f32,
}

/// A joint particle that is not among a bone's four, tied to each of the four by a
/// stick (3.2): the stick to the bone's `k`-th particle (`Particles::of_bone`) has rest
/// length `rest[k]`. The four sticks share the two particle indices, 24 bytes in all.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Satellite {
    /// The bone whose particles it is tied to.
    pub bone: u32,
    /// The joint particle.
    pub particle: u32,
    /// Rest lengths of its sticks to the bone's four particles; [`NO_STICK`] where the
    /// two particles coincide and the build makes no stick.
    pub rest: [f32; 4],
}

/// A satellite's rest length where it has no stick: no distance is negative.
const NO_STICK: f32 = -1.0;

/// Runtime state of the paper solver.
///
/// A bone's six sticks join its four particles along `EDGES`, so of each only the rest
/// length is kept, by bone index; the particles are `Particles::of_bone`. A satellite's
/// four sticks name its particle and bone; a tie names its two particles.
/// [`PaperState::relax_sticks`]
/// satisfies them in the order the paper's build makes them: each bone's six, then its
/// satellites, bone after bone, then the ties. (A projectile's six, added after the
/// ties, come before them here: they share no particle with a tie, and a stick moves
/// only its two particles, so the order between them changes no bit.)
#[derive(Clone, Debug, Default)]
pub(crate) struct PaperState {
    /// Per bone, the rest lengths of its six sticks (`EDGES`, in that order).
    pub bone_sticks: Vec<[f32; 6]>,
    /// Satellite joint particles, each tied to a bone's four, ordered by bone.
    pub satellites: Vec<Satellite>,
    /// Sticks of fixed and slider joints between two bones' particles (or a bone's and
    /// fixed anchors).
    pub ties: Vec<Stick>,
    /// Hinge limits.
    pub hinges: Vec<HingeLimit>,
    /// Cone limits.
    pub cones: Vec<ConeLimit>,
}

impl PaperState {
    /// Gives back the room the arrays grew beyond their length.
    pub fn shrink_to_fit(&mut self) {
        self.bone_sticks.shrink_to_fit();
        self.satellites.shrink_to_fit();
        self.ties.shrink_to_fit();
        self.hinges.shrink_to_fit();
        self.cones.shrink_to_fit();
    }

    /// Adds the six sticks (`EDGES`) of the next bone, of rest lengths `rest`.
    pub fn push_bone_sticks(&mut self, rest: [f32; 6]) {
        self.bone_sticks.push(rest);
    }

    /// The rest lengths of bone `i`'s six sticks (`EDGES`).
    pub fn bone_sticks(&self, i: usize) -> [f32; 6] {
        self.bone_sticks[i]
    }

    /// The two particles of each stick that is not a bone's own six: satellites' (the
    /// bones' particles are `of_bone`) and ties'.
    pub fn loose_sticks<'a>(
        &'a self,
        of_bone: &'a [[u32; 4]],
    ) -> impl Iterator<Item = (u32, u32)> + 'a {
        let satellites = self.satellites.iter().flat_map(move |s| {
            let ids = of_bone[s.bone as usize];
            (0..4)
                .filter(move |&k| s.rest[k] != NO_STICK)
                .map(move |k| (s.particle, ids[k]))
        });
        satellites.chain(self.ties.iter().map(|t| (t.a, t.b)))
    }

    /// One relaxation pass over every stick (Jakobsen 2001): bone by bone its six sticks
    /// on the particles `of_bone` names, then its satellites; then the ties.
    pub fn relax_sticks(&self, x: &mut [Vec3], inv: &[f32], of_bone: &[[u32; 4]]) {
        let mut satellites = self.satellites.iter().peekable();
        for (i, (&[p0, p1, p2, p3], r)) in of_bone.iter().zip(&self.bone_sticks).enumerate() {
            // `EDGES`, in its order, spelled out: the four indices stay in registers.
            satisfy(x, inv, p0, p1, r[0]);
            satisfy(x, inv, p0, p2, r[1]);
            satisfy(x, inv, p0, p3, r[2]);
            satisfy(x, inv, p1, p2, r[3]);
            satisfy(x, inv, p1, p3, r[4]);
            satisfy(x, inv, p2, p3, r[5]);
            while let Some(s) = satellites.next_if(|s| s.bone == i as u32) {
                for (p, r) in [p0, p1, p2, p3].into_iter().zip(s.rest) {
                    if r != NO_STICK {
                        satisfy(x, inv, s.particle, p, r);
                    }
                }
            }
        }
        for s in &self.ties {
            satisfy(x, inv, s.a, s.b, s.rest);
        }
    }
}

/// Builds the paper's particles, bones and limits: the joints' shared particles
/// first ([`joint_particles`]), then each bone's tetrahedron of four particles
/// ([`tetrahedron`], [`add_bone`]), then what the paper has no shared particles for —
/// fixed and slider joints tied by sticks — and the limits ([`ties_and_limits`]).
/// Pushes the bones (frames at rest) onto `w` and returns the state.
pub(crate) fn build(w: &mut ParticleWorld, scene: &SceneDesc, masses: &[f32]) -> PaperState {
    let mut st = PaperState::default();
    let (joint_points, joint_particles) = joint_particles(w, scene);
    for (i, body) in scene.bodies.iter().enumerate() {
        let size = scene.bodies[i].shape.local_half_extents().length() * 2.0;
        let (chosen, ids, satellites) = tetrahedron(body, size, &joint_points[i]);
        add_bone(w, &mut st, scene, i, masses[i], &chosen, &ids, &satellites);
    }
    ties_and_limits(w, &mut st, scene, &joint_particles);
    st
}

/// A joint's points as particles, one global particle each, shared by the bones it
/// joins: a ball or universal joint's anchor, a hinge's two points on its axis (half
/// the smaller bone's extent along it either side). Returns, per body, the joint points
/// on it with their particles, and per constraint its particles.
#[allow(clippy::type_complexity)]
fn joint_particles(
    w: &mut ParticleWorld,
    scene: &SceneDesc,
) -> (Vec<Vec<(Vec3, u32)>>, Vec<Vec<u32>>) {
    let dt = scene.settings.timestep;
    let g = scene.settings.gravity;
    let mut joint_points: Vec<Vec<(Vec3, u32)>> = vec![Vec::new(); scene.bodies.len()];
    let mut joint_particles: Vec<Vec<u32>> = Vec::new();
    for c in &scene.constraints {
        let b1 = c.body1.index();
        let b2 = c.body2.body().map(|b| b.index());
        // A joint particle moves only when both bones do (the world and fixed bones
        // hold it).
        let movable =
            !scene.bodies[b1].is_fixed() && b2.is_some_and(|b| !scene.bodies[b].is_fixed());
        let pts: Vec<Vec3> = match &c.kind {
            JointKind::BallAndSocket { anchor, .. } | JointKind::Universal { anchor, .. } => {
                vec![*anchor]
            }
            JointKind::Hinge { anchor, axis, .. } => {
                let ext = |i: usize| {
                    let b = &scene.bodies[i];
                    let local = b.pose.inverse_transform_vector(*axis).abs();
                    local.dot(b.shape.local_half_extents())
                };
                let mut s = ext(b1);
                if let Some(b) = b2 {
                    s = s.min(ext(b));
                }
                let s = (0.5 * s).max(1e-3);
                vec![*anchor - *axis * s, *anchor + *axis * s]
            }
            _ => vec![],
        };
        let mut ids = Vec::new();
        for p in pts {
            let id = w.particles.push(p, Vec3::ZERO, g, dt, 0.0, movable);
            joint_points[b1].push((p, id));
            if let Some(b) = b2 {
                joint_points[b].push((p, id));
            }
            ids.push(id);
        }
        joint_particles.push(ids);
    }
    w.particles.joints = w.particles.len() as u32;
    (joint_points, joint_particles)
}

/// The four points of `body`'s tetrahedron (world space; `size` its diagonal): its
/// explicit particles, or its joint points while they stay independent, then the
/// candidates of its shape farthest apart. With them, the particle of each point that
/// is a joint's (`u32::MAX`: a new particle), and the joint particles left over
/// (satellites, tied to the four by sticks).
fn tetrahedron(
    body: &crate::scene::BodyDesc,
    size: f32,
    joint_points: &[(Vec3, u32)],
) -> (Vec<Vec3>, Vec<u32>, Vec<u32>) {
    let mut chosen: Vec<Vec3> = Vec::new();
    let mut ids: Vec<u32> = Vec::new();
    let mut satellites: Vec<u32> = Vec::new();
    if let Some(explicit) = body.particles {
        for p in explicit {
            let wp = body.pose.transform_point(p);
            chosen.push(wp);
            let shared = joint_points
                .iter()
                .find(|(q, _)| q.distance(wp) < 1e-3 * size.max(1e-3));
            ids.push(match shared {
                Some(&(_, id)) => id,
                None => u32::MAX,
            });
        }
        for &(q, id) in joint_points {
            if !ids.contains(&id) {
                let _ = q;
                satellites.push(id);
            }
        }
    } else {
        for &(q, id) in joint_points {
            if chosen.len() < 4 && independent(&chosen, q, size) {
                chosen.push(q);
                ids.push(id);
            } else {
                satellites.push(id);
            }
        }
        let cands: Vec<Vec3> = paper_candidates(&body.shape)
            .iter()
            .map(|c| body.pose.transform_point(*c))
            .collect();
        fill_far_apart(&mut chosen, &cands, size);
        // A degenerate leftover cannot happen with eight box corners, but be safe.
        let mut k = 0;
        while chosen.len() < 4 {
            let axis = [Vec3::X, Vec3::Y, Vec3::Z][k % 3] * (0.1 * size * (1 + k / 3) as f32);
            let p = body.pose.position + axis;
            if independent(&chosen, p, size) || k > 20 {
                chosen.push(p);
            }
            k += 1;
        }
        ids.resize(4, u32::MAX);
    }
    (chosen, ids, satellites)
}

/// Bone `i` of `scene` (mass `mass`) on the particles at `chosen` (new ones where
/// `ids` has `u32::MAX`): its frame at rest by Gram–Schmidt on the first three, its six
/// sticks, and sticks from each satellite to its four particles.
#[allow(clippy::too_many_arguments)]
fn add_bone(
    w: &mut ParticleWorld,
    st: &mut PaperState,
    scene: &SceneDesc,
    i: usize,
    mass: f32,
    chosen: &[Vec3],
    ids: &[u32],
    satellites: &[u32],
) {
    let dt = scene.settings.timestep;
    let g = scene.settings.gravity;
    let body = &scene.bodies[i];
    let movable = !body.is_fixed();
    let v0 = body.linear_velocity;
    let mut particles = [0u32; 4];
    for k in 0..4 {
        particles[k] = if ids[k] == u32::MAX {
            let v = v0 + body.angular_velocity.cross(chosen[k] - body.pose.position);
            w.particles.push(chosen[k], v, g, dt, 0.0, movable)
        } else {
            ids[k]
        };
        if movable {
            w.particles.mass[particles[k] as usize] += mass * 0.25;
        } else {
            w.particles.inv_mass[particles[k] as usize] = 0.0;
        }
    }
    let x = &w.particles.x;
    let pos: [Vec3; 4] = particles.map(|p| x[p as usize]);
    let (rot, _) = gram_schmidt(pos[1] - pos[0], pos[2] - pos[0]);
    let frame = crate::scene::Pose {
        position: pos[0],
        rotation: rot,
    };
    let inv = crate::scene::Pose {
        position: -(rot.inverse() * pos[0]),
        rotation: rot.inverse(),
    };
    let rest = pos.map(|p| frame.inverse_transform_point(p));
    let mut bone = w.make_bone(i, body, mass, rest, inv.mul_pose(&body.pose));
    w.particles.of_bone.push(particles);
    bone.com = pos[0].into();
    bone.rot = rot;
    st.push_bone_sticks(EDGES.map(|(a, b)| pos[a].distance(pos[b])));
    let x = &w.particles.x;
    for &s in satellites {
        let rest = particles.map(|p| {
            let rest = x[s as usize].distance(x[p as usize]);
            if rest > 1e-6 { rest } else { NO_STICK }
        });
        st.satellites.push(Satellite {
            bone: i as u32,
            particle: s,
            rest,
        });
    }
    w.bones.push(bone);
}

/// Joints the paper has no shared particles for — a fixed or slider joint ties every
/// particle of one bone to every particle of the other (or to a fixed particle where
/// it is, for the world) — and the hinge and cone limits on the joints' particles.
fn ties_and_limits(
    w: &mut ParticleWorld,
    st: &mut PaperState,
    scene: &SceneDesc,
    joint_particles: &[Vec<u32>],
) {
    let dt = scene.settings.timestep;
    let g = scene.settings.gravity;
    for (ci, c) in scene.constraints.iter().enumerate() {
        let b1 = c.body1.index();
        let b2 = c.body2.body().map(|b| b.index());
        match &c.kind {
            JointKind::Fixed | JointKind::Slider { .. } => {
                if let Some(b2) = b2 {
                    for p in w.particles.of_bone[b1] {
                        for q in w.particles.of_bone[b2] {
                            let rest =
                                w.particles.x[p as usize].distance(w.particles.x[q as usize]);
                            st.ties.push(Stick { a: p, b: q, rest });
                        }
                    }
                } else {
                    for p in w.particles.of_bone[b1] {
                        let x = w.particles.x[p as usize];
                        let anchor = w.particles.push(x, Vec3::ZERO, g, dt, 0.0, false);
                        st.ties.push(Stick {
                            a: p,
                            b: anchor,
                            rest: 0.0,
                        });
                    }
                }
            }
            JointKind::Hinge { limit: Some(l), .. } => {
                let ids = &joint_particles[ci];
                let (p1, p2) = (ids[0], ids[1]);
                st.hinges
                    .push(hinge_limit(w, b1, b2, p1, p2, l.min, l.max, dt));
            }
            JointKind::BallAndSocket { swing: Some(s), .. }
            | JointKind::Universal { swing: Some(s), .. } => {
                let joint = joint_particles[ci][0];
                st.cones.push(cone_limit(w, b1, b2, joint, s, dt));
            }
            _ => {}
        }
    }
}

/// Orientation of bone `bone`'s frame (identity for the world, `None`).
fn frame_rot(w: &ParticleWorld, bone: Option<u32>) -> Quat {
    bone.map_or(Quat::IDENTITY, |b| w.bones[b as usize].rot)
}

fn farthest_from_line(w: &ParticleWorld, bone: usize, p1: Vec3, axis: Vec3, skip: &[u32]) -> u32 {
    let x = &w.particles.x;
    *w.particles.of_bone[bone]
        .iter()
        .filter(|p| !skip.contains(p))
        .max_by(|&&a, &&b| {
            let da = (x[a as usize] - p1).reject_from(axis).length();
            let db = (x[b as usize] - p1).reject_from(axis).length();
            da.total_cmp(&db)
        })
        .unwrap_or(&w.particles.of_bone[bone][3])
}

#[allow(clippy::too_many_arguments)]
fn hinge_limit(
    w: &mut ParticleWorld,
    b1: usize,
    b2: Option<usize>,
    p1: u32,
    p2: u32,
    min: f32,
    max: f32,
    dt: f32,
) -> HingeLimit {
    let bone_a = b2.map(|b| b as u32);
    let x1 = w.particles.x[p1 as usize];
    let axis = (w.particles.x[p2 as usize] - x1).normalize();
    let ref_b = farthest_from_line(w, b1, x1, axis, &[p1, p2]);
    let xb = w.particles.x[ref_b as usize];
    let radial = (xb - x1).reject_from(axis);
    let ref_a = match b2 {
        Some(b) => farthest_from_line(w, b, x1, axis, &[p1, p2]),
        None => {
            // The world has no particles: a fixed one off the axis, opposite bone B.
            let off =
                -radial.normalize_or(axis.any_orthonormal_vector()) * radial.length().max(0.05);
            w.particles
                .push(x1 + off, Vec3::ZERO, Vec3::ZERO, dt, 0.0, false)
        }
    };
    let xa = w.particles.x[ref_a as usize];
    let on_axis = xb - radial;
    let limit_point = |angle: f32| on_axis + Quat::from_axis_angle(axis, angle) * radial;
    HingeLimit {
        bone_a,
        p1,
        p2,
        ref_a,
        ref_b,
        rest_dir: frame_rot(w, bone_a).inverse() * radial.normalize_or_zero(),
        min,
        max,
        len_min: xa.distance(limit_point(min)),
        len_max: xa.distance(limit_point(max)),
    }
}

fn cone_limit(
    w: &mut ParticleWorld,
    b1: usize,
    b2: Option<usize>,
    joint: u32,
    s: &SwingLimit,
    dt: f32,
) -> ConeLimit {
    let bone_a = b2.map(|b| b as u32);
    let (axis, theta, shaft) = match *s {
        SwingLimit::Cone {
            axis,
            half_angle,
            shaft,
        } => (axis, half_angle, shaft),
        SwingLimit::Pyramid {
            axis,
            half_angle1,
            half_angle2,
            shaft,
            ..
        } => (axis, half_angle1.max(half_angle2), shaft),
    };
    let xj = w.particles.x[joint as usize];
    let x = &w.particles.x;
    // Reference particle: the particle of B nearest the shaft's line (3.3.2).
    let ref_b = *w.particles.of_bone[b1]
        .iter()
        .filter(|&&p| p != joint)
        .max_by(|&&a, &&b| {
            let ca = (x[a as usize] - xj).normalize_or_zero().dot(shaft);
            let cb = (x[b as usize] - xj).normalize_or_zero().dot(shaft);
            ca.total_cmp(&cb)
        })
        .unwrap_or(&w.particles.of_bone[b1][3]);
    let a_len = x[ref_b as usize].distance(xj);
    let other_a = match b2 {
        Some(b) => *w.particles.of_bone[b]
            .iter()
            .filter(|&&p| p != joint)
            .min_by(|&&a, &&b| {
                (x[a as usize] - xj)
                    .dot(axis)
                    .total_cmp(&(x[b as usize] - xj).dot(axis))
            })
            .unwrap_or(&w.particles.of_bone[b][3]),
        None => w.particles.push(
            xj - axis * a_len.max(0.05),
            Vec3::ZERO,
            Vec3::ZERO,
            dt,
            0.0,
            false,
        ),
    };
    ConeLimit {
        bone_a,
        joint,
        ref_b,
        other_a,
        normal: frame_rot(w, bone_a).inverse() * axis,
        c_dist: a_len * theta.cos(),
    }
}

/// Jakobsen's stick satisfaction, weighted by the particles' inverse masses (0 for
/// fixed bones, 1 otherwise: the paper's particles have no masses).
fn satisfy(x: &mut [Vec3], inv: &[f32], a: u32, b: u32, rest: f32) {
    let (a, b) = (a as usize, b as usize);
    let (wa, wb) = (inv[a], inv[b]);
    if wa + wb == 0.0 {
        return;
    }
    let d = x[b] - x[a];
    let len = d.length();
    if len < 1e-9 {
        return;
    }
    let diff = (len - rest) / (len * (wa + wb));
    x[a] += d * (wa * diff);
    x[b] -= d * (wb * diff);
}

fn update_frames(w: &mut ParticleWorld) {
    for (b, &ids) in w.bones.iter_mut().zip(&w.particles.of_bone) {
        b.paper_frame(ids, &w.particles.x);
    }
}

/// Handles the deepest contact between bone `a` and `b` (or the ground): 3.5.1–3.5.3,
/// then the friction of 3.6.
fn handle(
    w: &mut ParticleWorld,
    a: usize,
    b: Option<usize>,
    p: Vec3,
    n: Vec3,
    d: f32,
    iterations: u32,
) {
    let ma = if w.bones[a].fixed {
        f32::INFINITY
    } else {
        w.bones[a].mass
    };
    let mb = match b {
        Some(b) if !w.bones[b].fixed => w.bones[b].mass,
        _ => f32::INFINITY,
    };
    // Δa = M_b/(M_a+M_b) · n d, with an infinite mass taking all or nothing.
    let (fa, fb) = match (ma.is_finite(), mb.is_finite()) {
        (true, true) => (mb / (ma + mb), ma / (ma + mb)),
        (true, false) => (1.0, 0.0),
        (false, true) => (0.0, 1.0),
        (false, false) => return,
    };
    let friction = PAPER_FRICTION / iterations as f32;
    let apply = |w: &mut ParticleWorld, bone: usize, delta: Vec3| {
        let ids = w.particles.of_bone[bone].map(|q| q as usize);
        let dist = ids.map(|i| p.distance(w.particles.x[i]));
        let total: f32 = dist.iter().sum();
        let c = if total > 1e-9 {
            dist.map(|di| (1.0 - di / total) / 3.0)
        } else {
            [0.25; 4]
        };
        let lambda = 1.0 / c.iter().map(|ci| ci * ci).sum::<f32>();
        for k in 0..4 {
            let i = ids[k];
            if w.particles.inv_mass[i] == 0.0 {
                continue;
            }
            w.particles.x[i] += delta * (c[k] * lambda);
            let (x, old) = (w.particles.x[i], w.particles.x_prev[i]);
            w.particles.x_prev[i] = old + (x - old) * (friction * c[k]);
        }
    };
    if fa > 0.0 {
        apply(w, a, -n * (d * fa));
    }
    if let (Some(b), true) = (b, fb > 0.0) {
        apply(w, b, n * (d * fb));
    }
}

/// The deepest contact among manifold points; equal depths (within 1 µm) averaged.
#[derive(Default)]
struct Deepest {
    depth: f32,
    sum_p: Vec3,
    sum_n: Vec3,
    count: u32,
}

impl Deepest {
    fn add(&mut self, pa: Vec3, pb: Vec3, n: Vec3, dist: f32) {
        let depth = -dist;
        if depth <= 0.0 {
            return;
        }
        if self.count == 0 || depth > self.depth + 1e-6 {
            *self = Deepest {
                depth,
                sum_p: (pa + pb) * 0.5,
                sum_n: n,
                count: 1,
            };
        } else if depth >= self.depth - 1e-6 {
            self.sum_p += (pa + pb) * 0.5;
            self.sum_n += n;
            self.count += 1;
        }
    }
}

fn project_collisions(w: &mut ParticleWorld, iterations: u32) {
    update_frames(w);
    let zero = vec![0.0; w.bones.len()];
    let mut pairs = std::mem::take(&mut w.pairs);
    broad_phase((&w.bones, &w.kinds), &zero, &w.filter, &mut pairs);
    let mut manifolds = std::mem::take(&mut w.manifolds);
    for &(i, j) in &pairs {
        let mut deep = Deepest::default();
        let bones = (&w.bones[..], &w.kinds);
        shape_pair(bones, i, j, 0.0, &mut manifolds, |pa, pb, n, d| {
            deep.add(pa, pb, n, d)
        });
        if deep.count > 0 {
            let n = deep.sum_n.normalize_or_zero();
            handle(
                w,
                i,
                Some(j),
                deep.sum_p / deep.count as f32,
                n,
                deep.depth,
                iterations,
            );
            w.bones[i].paper_frame(w.particles.of_bone[i], &w.particles.x);
            w.bones[j].paper_frame(w.particles.of_bone[j], &w.particles.x);
        }
    }
    if let Some(ground) = w.settings.ground {
        for i in 0..w.bones.len() {
            if w.bones[i].fixed {
                continue;
            }
            let mut deep = Deepest::default();
            let bones = (&w.bones[..], &w.kinds);
            ground_pair(bones, i, &ground, 0.0, &mut manifolds, |pa, pb, n, d| {
                deep.add(pa, pb, n, d)
            });
            if deep.count > 0 {
                let n = deep.sum_n.normalize_or_zero();
                handle(
                    w,
                    i,
                    None,
                    deep.sum_p / deep.count as f32,
                    n,
                    deep.depth,
                    iterations,
                );
                w.bones[i].paper_frame(w.particles.of_bone[i], &w.particles.x);
            }
        }
    }
    w.manifolds = manifolds;
    w.pairs = pairs;
}

fn solve_limits(w: &mut ParticleWorld, st: &PaperState) {
    update_frames(w);
    let inv = &w.particles.inv_mass;
    for h in &st.hinges {
        let x = &w.particles.x;
        let x1 = x[h.p1 as usize];
        let axis = (x[h.p2 as usize] - x1).normalize_or_zero();
        let rb = (x[h.ref_b as usize] - x1).reject_from(axis);
        let rest = frame_rot(w, h.bone_a) * h.rest_dir;
        let rest = rest.reject_from(axis);
        let angle = axis.dot(rest.cross(rb)).atan2(rest.dot(rb));
        if angle > h.max {
            satisfy(&mut w.particles.x, inv, h.ref_a, h.ref_b, h.len_max);
        } else if angle < h.min {
            satisfy(&mut w.particles.x, inv, h.ref_a, h.ref_b, h.len_min);
        }
    }
    for c in &st.cones {
        let x = &w.particles.x;
        let n = frame_rot(w, c.bone_a) * c.normal;
        let p_dist = (x[c.ref_b as usize] - x[c.joint as usize]).dot(n);
        if p_dist < c.c_dist {
            let rest = x[c.other_a as usize].distance(x[c.ref_b as usize]) + (c.c_dist - p_dist);
            satisfy(&mut w.particles.x, inv, c.other_a, c.ref_b, rest);
        }
    }
}

/// One step of the paper's method.
pub(crate) fn step(w: &mut ParticleWorld, st: &PaperState) {
    // Phases as the paper's relaxation runs them (Jakobsen's loop): Verlet integration,
    // then each iteration's sticks, limits, grab and collisions, then the bone frames.
    let mut times = PhaseTimes::default();
    let mut clock = PhaseClock::start();
    let s = &w.settings;
    let (g, dt, n) = (s.gravity, s.timestep, s.iterations.max(1));
    w.particles.frame_start.clone_from(&w.particles.x);
    w.particles.verlet(g, dt);
    clock.lap(&mut times, "integration");
    for _ in 0..n {
        let p = &mut w.particles;
        st.relax_sticks(&mut p.x, &p.inv_mass, &p.of_bone);
        clock.lap(&mut times, "sticks");
        solve_limits(w, st);
        clock.lap(&mut times, "limits");
        if let Some(grab) = w.grab {
            super::grab_paper(w, grab);
            clock.lap(&mut times, "grab");
        }
        project_collisions(w, n);
        clock.lap(&mut times, "collisions");
    }
    update_frames(w);
    clock.lap(&mut times, "frames");
    clock.finish(&mut times);
    w.phase_times = times;
}

#[cfg(test)]
mod tests {
    use super::super::{ParticleSolver, uniform};
    use super::*;

    /// One relaxation pass ([`PaperState::relax_sticks`]) gives the bits of the sticks
    /// satisfied one by one in the build's order — each bone's six along `EDGES`, then its
    /// satellites, then the ties — on two humans of the pile (their chests tie joint
    /// particles as satellites) whose particles are scattered at random.
    #[test]
    fn relaxation_keeps_the_order_of_the_build() {
        let mut w = super::super::solver_scene_world("pile.af", Some(2), ParticleSolver::Paper);
        let st = w.paper.take().unwrap_or_else(|| panic!("no paper state"));
        assert!(!st.satellites.is_empty(), "no satellite sticks to order");
        let mut next = uniform(0x0bad_cafe);
        for x in &mut w.particles.x {
            *x += Vec3::new(next(), next(), next()) * 0.1 - Vec3::splat(0.05);
        }
        let p = &w.particles;
        let mut relaxed = p.x.clone();
        st.relax_sticks(&mut relaxed, &p.inv_mass, &p.of_bone);
        let mut one_by_one = p.x.clone();
        for (i, ids) in p.of_bone.iter().enumerate() {
            for (k, &(a, b)) in EDGES.iter().enumerate() {
                satisfy(
                    &mut one_by_one,
                    &p.inv_mass,
                    ids[a],
                    ids[b],
                    st.bone_sticks[i][k],
                );
            }
            for s in st.satellites.iter().filter(|s| s.bone as usize == i) {
                for (&b, r) in ids.iter().zip(s.rest) {
                    if r != NO_STICK {
                        satisfy(&mut one_by_one, &p.inv_mass, s.particle, b, r);
                    }
                }
            }
        }
        for s in &st.ties {
            satisfy(&mut one_by_one, &p.inv_mass, s.a, s.b, s.rest);
        }
        assert!(relaxed != p.x, "the pass moved nothing");
        assert!(
            relaxed == one_by_one,
            "the pass differs from the sticks in order"
        );
    }
}
