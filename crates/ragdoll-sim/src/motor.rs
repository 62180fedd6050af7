//! Joint motors: a figure driven toward a pose (Jolt's
//! `Ragdoll::DriveToPoseUsingMotors`).
//!
//! A motor acts on the two bodies of a joint and targets their relative orientation,
//! `q₂⁻¹ q₁ = T` (body1's shape frame seen from body2's; body2 the world for a joint to
//! the world). The error is the turn body1 still has to make relative to body2,
//! `E = q₂ T q₁⁻¹` (world axes), as a rotation vector `e` (axis × angle, the shorter way
//! round). The motor is a soft angular constraint `C = −e`, `Ċ = ω₁ − ω₂`, with the
//! soft-step coefficients of Box2D v3 (Catto, "Solver2D", 2024) for the spring frequency
//! `f` and damping ratio `ζ` over the step `h`: `ω = 2π f`, `a₁ = 2ζ + hω`,
//! `a₂ = hω a₁`, `a₃ = 1/(1 + a₂)`, bias rate `ω / a₁`, mass scale `a₂ a₃`. Its angular
//! impulse over a step, body1 `+λ` and body2 `−λ` (a couple: no linear momentum, no
//! angular momentum of the pair changed), is
//!
//! `λ = −a₂a₃ K⁻¹ (ω₁ − ω₂ − (ω/a₁) e)`, `K = I₁⁻¹ + I₂⁻¹` (world),
//!
//! clamped to `|λ| ≤ τ_max h`: the torque the motor can give. This is the backward-Euler
//! spring–damper of stiffness `k = K⁻¹ ω²` and damping `2ζ K⁻¹ ω` over one step,
//! unconditionally stable. A load it meets within the step (gravity, the solver's
//! constraints) comes after its impulse, so from rest it gives `λ = h k e / (1 + a₂)`:
//! a joint at rest holding a load torque `τ` sags by `e = (1 + a₂) τ / k` (or gives way,
//! where `τ_max < τ`). As `f` grows the stiffness tends to `K⁻¹ / h²`, the impulse that
//! takes the whole error out in one step. The bodies' own inertia sets the stiffness:
//! a joint carrying a long limb needs a higher frequency to hold it.
//!
//! Every solver applies the impulse once per step, at its start, to the joint's two
//! bodies' angular velocities, before its own substeps (joints, limits, contacts): the
//! multibody body through `I⁻¹ λ`, a particle bone by turning its particles' velocities
//! with the angular part of its rigid response (`particle::impulse`). Motors stay on
//! until replaced or cleared.

use crate::scene::BodyId;
use glam::{DVec3, Mat3, Quat, Vec3};

/// How hard a motor drives: a spring of frequency `frequency` and damping ratio
/// `damping_ratio` on the joint's two bodies, with a bounded torque.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorDrive {
    /// Spring frequency (Hz) against the joint's two bodies' inertia, > 0.
    pub frequency: f32,
    /// Damping ratio (1 = critical).
    pub damping_ratio: f32,
    /// Largest torque the motor gives (N·m); `f32::INFINITY` for no bound.
    pub max_torque: f32,
}

impl Default for MotorDrive {
    /// A stiff, critically damped drive with no torque bound: 10 Hz, ζ = 1.
    fn default() -> Self {
        MotorDrive {
            frequency: 10.0,
            damping_ratio: 1.0,
            max_torque: f32::INFINITY,
        }
    }
}

/// One joint's motor: drives `q₂⁻¹ q₁` toward `target` (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointMotor {
    /// The joint's first body.
    pub body1: BodyId,
    /// The joint's second body; `None` for the world.
    pub body2: Option<BodyId>,
    /// Target orientation of body1's shape frame relative to body2's (`q₂⁻¹ q₁`; in
    /// world axes for a joint to the world).
    pub target: Quat,
    /// Its spring and torque bound.
    pub drive: MotorDrive,
}

/// A body as a motor sees it: orientation, angular velocity, world inverse inertia.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MotorBody {
    pub rotation: Quat,
    pub angular_velocity: Vec3,
    pub inv_inertia: Mat3,
}

impl MotorBody {
    /// The world, or a fixed body: never turns, takes no impulse.
    pub(crate) const STILL: MotorBody = MotorBody {
        rotation: Quat::IDENTITY,
        angular_velocity: Vec3::ZERO,
        inv_inertia: Mat3::ZERO,
    };
}

/// The rotation vector (axis × angle, angle in [0, π]) of `q`.
pub(crate) fn rotation_vector(q: Quat) -> Vec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let (axis, angle) = q.normalize().to_axis_angle();
    if angle.is_finite() && axis.is_finite() {
        axis * angle
    } else {
        Vec3::ZERO
    }
}

/// The motor's angular impulse on body1 over a step of `h` (module doc); body2 takes
/// its opposite. Zero when neither body can turn.
pub(crate) fn motor_impulse(m: &JointMotor, b1: &MotorBody, b2: &MotorBody, h: f32) -> Vec3 {
    let k = b1.inv_inertia.as_dmat3() + b2.inv_inertia.as_dmat3();
    if k.determinant().abs() < 1e-18 || m.drive.frequency <= 0.0 || h <= 0.0 {
        return Vec3::ZERO;
    }
    let error = rotation_vector(b2.rotation * m.target * b1.rotation.inverse()).as_dvec3();
    let omega = std::f64::consts::TAU * m.drive.frequency as f64;
    let h = h as f64;
    let a1 = 2.0 * m.drive.damping_ratio.max(0.0) as f64 + h * omega;
    let a2 = h * omega * a1;
    let a3 = 1.0 / (1.0 + a2);
    let rel = (b1.angular_velocity - b2.angular_velocity).as_dvec3();
    let lambda: DVec3 = -(a2 * a3) * (k.inverse() * (rel - (omega / a1) * error));
    let bound = m.drive.max_torque as f64 * h;
    let size = lambda.length();
    let lambda = if size > bound {
        lambda * (bound / size)
    } else {
        lambda
    };
    lambda.as_vec3()
}
