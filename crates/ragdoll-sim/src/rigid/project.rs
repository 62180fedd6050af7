//! The position projection pass: nonlinear Gauss–Seidel on positions after the velocity
//! solve (Box2D v2.4's `SolvePositionConstraints`, Jolt's position iterations, Rapier's
//! position correction; Catto, "Modeling and Solving Constraints", GDC 2009).
//!
//! The soft step keeps joints and contacts as stiff springs: under an impact they give
//! way for a few steps (a falling chain's links part by centimetres), and more velocity
//! iterations do not help, since the softness is what the constraint converges to. After
//! the velocity solve, each constraint is therefore also solved at position level: with
//! the position error `C` measured on the current pose and the effective mass `K` of its
//! Jacobian, the bodies are moved by the position impulse `P = −K⁻¹ C` (`Δx = P/m`,
//! `Δθ = I⁻¹ (r × P)`), one constraint after the other, a few times.
//!
//! It moves positions only, so it adds no kinetic energy; the potential energy it can
//! add is bounded by the errors it removes. Corrections are clamped per iteration
//! ([`MAX_LINEAR_CORRECTION`], [`MAX_ANGULAR_CORRECTION`]) so a large error (bodies
//! started overlapping, a joint torn by a grab) is removed over several steps rather than
//! as a jump, and contacts and limits keep a small slop so resting bodies are not pushed
//! in and out every step.
//!
//! Moving positions at fixed velocities changes momenta: a body moved by `Δx` carries
//! `Δx × m v` more angular momentum, one turned by `Δθ` spins with `R' I R'ᵀ ω`. A
//! joint's correction is internal to its two bodies, so after each joint's update the
//! pair's angular momentum about its common centre of mass is put back
//! ([`keep_pair_momentum`]) when the figure touches nothing; a tumbling figure
//! whose joints open on their arcs would otherwise lose or gain spin at every
//! correction (0.25 % of a hit pair's `L` a step).
//!
//! Bodies at rest (below their sleep speeds) take no part: they are held as if static
//! for the pass. What a resting body's soft constraints still give way is what the
//! velocity solver holds it at; moving it back every step would undo the velocity
//! solve every step, and the island would creep and never sleep.

use super::body::{BodyStates, Motions};
use super::contact_solver::{ContactConstraints, PushOutBudget};
use super::joint_set::{JointSet, ProjectedRows};
use crate::scene::SleepSettings;
use glam::{Mat3, Mat3A, Quat, Vec3};

/// Gauss–Seidel passes over all constraints per step.
pub const POSITION_ITERATIONS: usize = 4;
/// Largest linear correction of one constraint per iteration (m), Box2D's
/// `b2_maxLinearCorrection`.
pub const MAX_LINEAR_CORRECTION: f32 = 0.2;
/// Largest angular correction of one row per iteration (rad), Box2D's
/// `b2_maxAngularCorrection` (8°).
pub const MAX_ANGULAR_CORRECTION: f32 = 8.0 * std::f32::consts::PI / 180.0;
/// Joint gap left to the velocity solver (m): about what a resting figure's soft
/// joints sag under its weight, a quarter of the 2 mm joint-gap bound.
pub const JOINT_SLOP: f32 = 0.0005;
/// Violation of a hard angular limit left alone (rad, 0.25°): the limit rows keep it.
pub const ANGULAR_SLOP: f32 = 0.25 * std::f32::consts::PI / 180.0;
/// Fraction of a contact's penetration removed per iteration (Box2D v2.4's
/// `b2_baumgarte`): full correction of every point of a manifold, one after the other,
/// over-corrects and lifts resting bodies.
pub const CONTACT_CORRECTION: f32 = 0.2;

/// Runs [`POSITION_ITERATIONS`] passes over joints then contacts, then one over the
/// joints' point rows alone, moving only awake bodies faster than the sleep speeds of
/// `sleep`. `touching` is room for a flag per body: whether its figure touches anything
/// this solve ([`mark_grounded`]).
///
/// Why the last pass: a joint's angular rows (a limit, a hinge's alignment, a universal
/// joint's cross row) turn its two bodies about their centres of mass, and a turn moves
/// every other anchor on them. In Gauss–Seidel order the joints solved before it in the
/// pass are left open by that turn: on the lab humanoid landing on a folded knee, the
/// knee's limit is pressed (its shin's tip carries the figure on the ground) and every
/// pass the hip's rows turned the thigh after the knee had been closed, parting the knee
/// by 2.3 mm at the step's end where the velocity solve had left 0.2 mm. A point row
/// closes its gap by an impulse at the anchor itself: one pass of them, after the
/// turns, closes what the turns opened, and what each correction carries the other
/// anchors of its bodies is of the order of the gaps it closes, not of the turns.
/// (Ending with a full joint pass instead leaves the gaps the last turns open, and more
/// passes of both only trade the same error between the joints and the contact under
/// the shin.)
#[allow(clippy::too_many_arguments)]
pub fn project_positions(
    s: &mut BodyStates,
    motion: Motions<'_>,
    joints: &JointSet,
    contacts: &ContactConstraints,
    awake: &[bool],
    sleep: &SleepSettings,
    push: &PushOutBudget,
    touching: &mut Vec<bool>,
) {
    mark_grounded(s, joints, contacts, touching);
    // Resting bodies: static for the pass (zero inverse mass), restored after it.
    let mut held: Vec<(usize, f32, Mat3A)> = Vec::new();
    for (i, &aw) in awake.iter().enumerate() {
        if aw
            && s.lin_vel[i].length() <= sleep.linear_velocity
            && s.ang_vel[i].length() <= sleep.angular_velocity
        {
            held.push((i, s.inv_mass[i], s.inv_inertia[i]));
            s.inv_mass[i] = 0.0;
            s.inv_inertia[i] = Mat3A::ZERO;
        }
    }
    for _ in 0..POSITION_ITERATIONS {
        joints.project(s, motion, awake, touching, ProjectedRows::All);
        contacts.project(s, push);
    }
    joints.project(s, motion, awake, touching, ProjectedRows::Points);
    for (i, m, inv) in held {
        s.inv_mass[i] = m;
        s.inv_inertia[i] = inv;
    }
}

/// Sets `grounded[i]` for every body with a contact this solve, every body jointed to
/// a body that does not move (the static anchor, a fixed or sleeping body), and every
/// body jointed to one of those, through the joints: the figures that exchange momentum
/// with something outside them. Their projection is left as it is; only a figure that
/// touches nothing keeps its momenta through it. (The set is the closure over the
/// joints, whatever their order, so it is the same solved whole or island by island.)
fn mark_grounded(
    s: &BodyStates,
    joints: &JointSet,
    contacts: &ContactConstraints,
    grounded: &mut Vec<bool>,
) {
    grounded.clear();
    grounded.resize(s.len(), false);
    contacts.mark_touching(grounded);
    let mut changed = true;
    while changed {
        changed = false;
        joints.for_each_pair(|a, b| {
            let held = s.inv_mass[a] <= 0.0 || s.inv_mass[b] <= 0.0;
            if (held || grounded[a] || grounded[b]) && !(grounded[a] && grounded[b]) {
                grounded[a] = true;
                grounded[b] = true;
                changed = true;
            }
        });
    }
}

/// Two bodies' positions and orientations before a joint's projection update.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairPose {
    com: [Vec3; 2],
    rot: [Quat; 2],
}

impl PairPose {
    /// The poses of bodies `a` and `b` now.
    #[inline]
    pub fn of(s: &BodyStates, a: usize, b: usize) -> PairPose {
        PairPose {
            com: [s.com[a], s.com[b]],
            rot: [s.rot[a], s.rot[b]],
        }
    }
}

/// Puts back the angular momentum of bodies `a` and `b` about their common centre of
/// mass `X` that moving them from `before` to their poses now changed at fixed
/// velocities, by a rigid turn of the pair's velocities, `δv_i = δΩ × d_i`,
/// `δω_i = δΩ` (`d_i = x_i − X`).
///
/// With the spins `L_i = R_i I_i R_iᵀ ω_i`, the change is
/// `ΔL = Σ m_i Δx_i × v_i + Σ (L_i' − L_i)` (`X` does not move: a position impulse moves
/// the two centres by `∓P/m`), and the turn adds `K δΩ` with
/// `K = Σ R_i' I_i R_i'ᵀ + m_i (|d_i|² 1 − d_i d_iᵀ)`, the pair's inertia about `X`: so
/// `δΩ = −K⁻¹ ΔL`. The turn keeps the pair's momentum (`Σ m_i d_i = 0`) and the
/// relative velocity of any two points of the pair, so the joint's rows see no change;
/// other joints of either body see it turn by `δΩ`, which is of the order of the
/// correction. A pair with a body that does not move (the static anchor, a body held
/// at rest for the pass) exchanges momentum with it and is left alone, as is a pair the
/// update did not move, and a pair of a figure that touches anything
/// ([`mark_grounded`]): what it touches exchanges momentum with it anyway, and a turn
/// of its velocities would drive it into its contacts (on the lab humanoid landing, a
/// figure gained up to 6 % of its energy scale that way).
pub(crate) fn keep_pair_momentum(
    s: &mut BodyStates,
    motion: Motions<'_>,
    a: usize,
    b: usize,
    before: &PairPose,
) {
    let n = motion.bodies.len();
    if a >= n || b >= n || s.inv_mass[a] <= 0.0 || s.inv_mass[b] <= 0.0 {
        return;
    }
    let now = PairPose::of(s, a, b);
    if now.com == before.com && now.rot == before.rot {
        return;
    }
    let ids = [a, b];
    let mass = [1.0 / s.inv_mass[a], 1.0 / s.inv_mass[b]];
    let x = (now.com[0] * mass[0] + now.com[1] * mass[1]) / (mass[0] + mass[1]);
    let mut change = Vec3::ZERO;
    let mut k = Mat3::ZERO;
    for side in 0..2 {
        let i = ids[side];
        let inertia = motion.bodies[i].inertia(motion.full);
        let world = |q: Quat| {
            let r = Mat3::from_quat(q);
            r * inertia * r.transpose()
        };
        let (v, w) = (Vec3::from(s.lin_vel[i]), Vec3::from(s.ang_vel[i]));
        let turned = world(now.rot[side]);
        change += (now.com[side] - before.com[side]).cross(v) * mass[side] + turned * w
            - world(before.rot[side]) * w;
        let d = now.com[side] - x;
        k += turned
            + (Mat3::from_diagonal(Vec3::splat(d.length_squared()))
                - Mat3::from_cols(d * d.x, d * d.y, d * d.z))
                * mass[side];
    }
    // The turn is taken perpendicular to the line between the centres, `δΩ = B δ` with
    // `B = [u v]` completing `d̂`: there `K` holds the pair's orbital inertia
    // (`Bᵀ K B ≥ μ |d|²`, μ the reduced mass), where along `d̂` it may hold only the roll
    // inertias of two thin limbs, and a turn about it would spin them up.
    let line = now.com[1] - now.com[0];
    if line.length_squared() <= 1e-12 {
        return;
    }
    let (u, v) = line.normalize().any_orthonormal_pair();
    let (ku, kv) = (k * u, k * v);
    let (k11, k12, k22) = (u.dot(ku), u.dot(kv), v.dot(kv));
    let det = k11 * k22 - k12 * k12;
    if !(det.is_finite() && det > 0.0) {
        return;
    }
    let (r1, r2) = (-u.dot(change), -v.dot(change));
    let turn = u * ((k22 * r1 - k12 * r2) / det) + v * ((k11 * r2 - k12 * r1) / det);
    if !turn.is_finite() {
        return;
    }
    for (&i, com) in ids.iter().zip(now.com) {
        s.lin_vel[i] += glam::Vec3A::from(turn.cross(com - x));
        s.ang_vel[i] += glam::Vec3A::from(turn);
    }
}
