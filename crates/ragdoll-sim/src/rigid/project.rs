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
//! Bodies at rest (below their sleep speeds) take no part: they are held as if static
//! for the pass. What a resting body's soft constraints still give way is what the
//! velocity solver holds it at; moving it back every step would undo the velocity
//! solve every step, and the island would creep and never sleep.

use super::body::BodyStates;
use super::contact_solver::{ContactConstraints, PushOutBudget};
use super::joint_set::JointSet;
use crate::scene::SleepSettings;
use glam::Mat3A;

/// Gauss–Seidel passes over all constraints per step.
pub const POSITION_ITERATIONS: usize = 4;
/// Largest linear correction of one constraint per iteration (m), Box2D's
/// `b2_maxLinearCorrection`.
pub const MAX_LINEAR_CORRECTION: f32 = 0.2;
/// Largest angular correction of one row per iteration (rad), Box2D's
/// `b2_maxAngularCorrection` (8°).
pub const MAX_ANGULAR_CORRECTION: f32 = 8.0 * std::f32::consts::PI / 180.0;
/// Joint gap left to the velocity solver (m): about what a resting figure's soft
/// joints sag under its weight, a quarter of the 2 mm the issue allows.
pub const JOINT_SLOP: f32 = 0.0005;
/// Violation of a hard angular limit left alone (rad, 0.25°): the limit rows keep it.
pub const ANGULAR_SLOP: f32 = 0.25 * std::f32::consts::PI / 180.0;
/// Fraction of a contact's penetration removed per iteration (Box2D v2.4's
/// `b2_baumgarte`): full correction of every point of a manifold, one after the other,
/// over-corrects and lifts resting bodies.
pub const CONTACT_CORRECTION: f32 = 0.2;

/// Runs [`POSITION_ITERATIONS`] passes over joints then contacts, moving only awake
/// bodies faster than the sleep speeds of `sleep`.
pub fn project_positions(
    s: &mut BodyStates,
    joints: &JointSet,
    contacts: &ContactConstraints,
    awake: &[bool],
    sleep: &SleepSettings,
    push: &PushOutBudget,
) {
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
        joints.project(s, awake);
        contacts.project(s, push);
    }
    for (i, m, inv) in held {
        s.inv_mass[i] = m;
        s.inv_inertia[i] = inv;
    }
}
