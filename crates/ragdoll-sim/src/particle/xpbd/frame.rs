//! What a bone's particles imply: its frame (read, never imposed) and the barycentric
//! weights that attach a point of the bone to its particles.
//!
//! **Frame.** The origin is the particles' centre of mass `c = ¼ Σ x_k` (equal masses),
//! the orientation the rotation of shape matching (Müller et al. 2005): the rotational
//! part `R` of `A = Σ m (x_k − c) r_kᵀ`, with `r_k` the rest positions in the bone
//! frame, extracted by Müller et al. 2016's iteration `q ← exp(ω) q`,
//! `ω = Σ_j R a_j × A_j / |Σ_j R a_j · A_j|` (columns `j`), warm-started from the last
//! frame. For a small displacement `Δx_k` the frame so read turns by
//! `δθ = I⁻¹ Σ m r_k × Δx_k`, `I = Σ m (|r|² − r rᵀ)`: the inertia the particulation
//! reproduces. That is what makes a correction `Δx_k = ω × r_k` turn the read frame by
//! exactly `ω` (`joints::turn`).
//!
//! **Barycentric weights.** A point `p` fixed in the bone is the affine combination
//! `p = Σ β_k x_k`, `Σ β_k = 1`, whose weights solve the rest tetrahedron:
//! `(β₁, β₂, β₃) = D⁻¹ (p − r₀)`, `D = [r₁ − r₀, r₂ − r₀, r₃ − r₀]`, `β₀ = 1 − β₁ − β₂ − β₃`
//! (Jakobsen 2001; the paper's section 3.4 for contacts). A correction `Δp` of such a point
//! moves particle `k` by `β_k w_k Δλ` with `Δλ = |Δp| / Σ β_k² w_k`: its generalised
//! inverse mass.

use super::super::bone::Bone;
use glam::{DMat3, DQuat, DVec3, Mat3, Quat, Vec3, Vec3A};

/// Turn (rad) below which the extraction has converged.
const EXTRACT_TOLERANCE: f32 = 1e-7;
/// Most iterations of the fixed-point extraction (the fallback).
const EXTRACT_ITERATIONS: usize = 16;
/// A Newton step of [`match_turn`] (rad) after which the turn has converged: the next
/// would be of the order of its square, 1e-16 rad, where a substep's turn of
/// `ω h` ≈ 1e-3 rad is resolved by f64 to about 1e-19.
const TURN_STEP_DONE: f64 = 1e-8;
/// Most Newton iterations of [`match_rotation`]; warm-started, a substep needs two.
const NEWTON_ITERATIONS: usize = 8;

/// `D⁻¹` of the bone's rest tetrahedron (see the module doc).
pub(crate) fn rest_inverse(rest: &[Vec3; 4]) -> Mat3 {
    Mat3::from_cols(rest[1] - rest[0], rest[2] - rest[0], rest[3] - rest[0]).inverse()
}

/// The barycentric weights of `local` (a point in the bone frame) on the rest
/// tetrahedron `rest`. Its `D⁻¹` ([`rest_inverse`]) is formed here, not kept per bone:
/// weights are taken at a detection, a joint's creation, a grab and a capsule's rolled
/// ground point, never in the passes.
pub(crate) fn weights(rest: &[Vec3; 4], local: Vec3) -> [f32; 4] {
    let b = rest_inverse(rest) * (local - rest[0]);
    [1.0 - b.x - b.y - b.z, b.x, b.y, b.z]
}

/// The point with weights `w` among the four positions `x`.
#[inline]
pub(crate) fn combine(x: &[Vec3; 4], w: &[f32; 4]) -> Vec3 {
    x[0] * w[0] + x[1] * w[1] + x[2] * w[2] + x[3] * w[3]
}

/// [`combine`] on f64 positions.
#[inline]
pub(crate) fn combine64(x: &[DVec3; 4], w: &[f32; 4]) -> DVec3 {
    x[0] * w[0] as f64 + x[1] * w[1] as f64 + x[2] * w[2] as f64 + x[3] * w[3] as f64
}

/// The bone's world inverse inertia `R I⁻¹ Rᵀ` at the substep's start (`prev_rot`),
/// where its particles are rigid: the one the joint and contact blocks move it by.
pub(crate) fn inv_inertia_prev(bone: &Bone) -> DMat3 {
    let r = DMat3::from_quat(bone.prev_rot.as_dquat());
    let inv = DMat3::from_diagonal(Vec3::from(bone.inv_inertia_local).as_dvec3());
    r * inv * r.transpose()
}

/// Reads `bone`'s frame from its particles `x` (module doc), its rest corners `rest`,
/// its old orientation the starting guess.
pub(crate) fn read(bone: &mut Bone, rest: &[Vec3; 4], x: &[DVec3; 4]) {
    let c = (x[0] + x[1] + x[2] + x[3]) * 0.25;
    let p = x.map(|xk| (xk - c).as_vec3());
    bone.rot = match_rotation(&p, rest, bone.rot);
    bone.com = Vec3A::from(c.as_vec3());
    bone.dcom = Vec3A::ZERO;
}

/// The shape-matching rotation of the offsets `p_k` (particles about their centre)
/// against the rest positions `r_k`, starting from `q`: the `R` that zeroes the torque
/// `T(R) = Σ p_k × (R r_k − p_k) = Σ p_k × R r_k`, the gradient of `Σ m |R r_k − p_k|²`
/// (the rotational part of `A = Σ p_k r_kᵀ`).
///
/// Solved by Newton's method on the rotation vector: `T(exp(δ) R) ≈ T(R) + J δ`,
/// `J = Σ ((a_k · b_k) 1 − b_k a_kᵀ)`, `a_k = p_k`, `b_k = R r_k` (from
/// `a × (δ × b) = δ (a · b) − b (a · δ)`), so `δ = −J⁻¹ T`. It converges
/// quadratically from the last substep's frame, where the fixed-point iteration of
/// Müller et al. 2016 contracts by only `(C₁ + C₂) / (C₁ + C₂ + C₃)` a step about a
/// short axis (`C` the second moments): a quarter for a long box, whose read frame then
/// lagged its particles.
pub(crate) fn match_rotation(p: &[Vec3; 4], rest: &[Vec3; 4], q: Quat) -> Quat {
    let mut q = q;
    let arms = p;
    for _ in 0..NEWTON_ITERATIONS {
        let r = Mat3::from_quat(q);
        let mut t = Vec3::ZERO;
        let mut j = Mat3::ZERO;
        for k in 0..4 {
            let (a, b) = (arms[k], r * rest[k]);
            t += a.cross(b - p[k]);
            j += Mat3::from_diagonal(Vec3::splat(a.dot(b)))
                - Mat3::from_cols(b * a.x, b * a.y, b * a.z);
        }
        let det = j.determinant();
        if !det.is_finite() || det.abs() <= 1e-30 {
            return extract_rotation(&shape_matrix(p, rest), q);
        }
        let delta = -(j.inverse() * t);
        let angle = delta.length();
        if !angle.is_finite() {
            return extract_rotation(&shape_matrix(p, rest), q);
        }
        // Far from the solution Newton's step can overshoot; a turn of more than a
        // radian is taken a radian at a time.
        let delta = if angle > 1.0 { delta / angle } else { delta };
        q = (Quat::from_scaled_axis(delta) * q).normalize();
        // The last step is taken too: stopping short of it would leave the frame a
        // little behind a spinning body every substep, a steady drag.
        if angle < EXTRACT_TOLERANCE {
            break;
        }
    }
    q
}

/// The turn `Q` (from the identity) that zeroes `T(Q) = Σ a_k × (Q a_k − p_k)`: the
/// torque of the moves from the offsets `p_k` (particles about their centre) onto the
/// rigid pose `Q a_k`, taken about the arms `a_k` (the particles about their centre at
/// the start of the substep, rigid then) — the sticks' SHAKE projection
/// (`shape_match`). Newton's method as [`match_rotation`]. In f64 and relative to the
/// substep's start: `Q` is a turn of `ω h`, a few milliradians, and an absolute f32
/// orientation resolves angles only to 1e-7 rad, a relative error of 3e-5 a substep
/// in the spin, biased enough to drain 3 % of a box's angular momentum in 10 s.
/// Newton starts from `guess` (the turn the corrections so far imply); the answer does
/// not depend on it.
pub(crate) fn match_turn(p: &[DVec3; 4], arms: &[DVec3; 4], guess: DQuat) -> DQuat {
    let mut q = guess;
    for _ in 0..NEWTON_ITERATIONS {
        let mut t = DVec3::ZERO;
        let mut j = DMat3::ZERO;
        for k in 0..4 {
            let (a, b) = (arms[k], q * arms[k]);
            t += a.cross(b - p[k]);
            j += DMat3::from_diagonal(DVec3::splat(a.dot(b)))
                - DMat3::from_cols(b * a.x, b * a.y, b * a.z);
        }
        let det = j.determinant();
        if !det.is_finite() || det.abs() <= 1e-40 {
            break;
        }
        let delta = -(j.inverse() * t);
        let angle = delta.length();
        if !angle.is_finite() {
            break;
        }
        let delta = if angle > 1.0 { delta / angle } else { delta };
        q = (DQuat::from_scaled_axis(delta) * q).normalize();
        // Newton converges quadratically: after a step below [`TURN_STEP_DONE`] the
        // error left is of the order of its square, below f64's resolution of the turn.
        if angle < TURN_STEP_DONE {
            break;
        }
    }
    q
}

/// `A = Σ p_k r_kᵀ`, whose rotational part is the shape-matching rotation.
fn shape_matrix(p: &[Vec3; 4], rest: &[Vec3; 4]) -> Mat3 {
    let mut a = Mat3::ZERO;
    for (d, r) in p.iter().zip(rest) {
        a += Mat3::from_cols(*d * r.x, *d * r.y, *d * r.z);
    }
    a
}

/// The rotational part of `a`, starting from `q` (Müller et al. 2016): the fallback of
/// [`match_rotation`] where its Jacobian is singular.
pub(crate) fn extract_rotation(a: &Mat3, mut q: Quat) -> Quat {
    for _ in 0..EXTRACT_ITERATIONS {
        let r = Mat3::from_quat(q);
        let num = r.x_axis.cross(a.x_axis) + r.y_axis.cross(a.y_axis) + r.z_axis.cross(a.z_axis);
        let den = (r.x_axis.dot(a.x_axis) + r.y_axis.dot(a.y_axis) + r.z_axis.dot(a.z_axis)).abs();
        let omega = num / (den + 1e-12);
        let angle = omega.length();
        if !angle.is_finite() || angle < EXTRACT_TOLERANCE {
            break;
        }
        q = (Quat::from_axis_angle(omega / angle, angle) * q).normalize();
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Weights reproduce points of the rest tetrahedron and sum to one; the extraction,
    /// warm-started near it, reads back a rotation applied to the tetrahedron.
    #[test]
    fn weights_and_frames_read_back() {
        let rest = [
            Vec3::new(0.1, 0.2, 0.05),
            Vec3::new(0.1, -0.2, -0.05),
            Vec3::new(-0.1, 0.2, -0.05),
            Vec3::new(-0.1, -0.2, 0.05),
        ];
        for p in [
            Vec3::new(0.3, -0.4, 0.2),
            Vec3::ZERO,
            Vec3::new(-1.0, 2.0, 0.5),
        ] {
            let w = weights(&rest, p);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            assert!((combine(&rest, &w) - p).length() < 1e-5, "{p}");
        }
        let q = Quat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 2.5);
        let a = rest.iter().fold(Mat3::ZERO, |m, r| {
            let d = q * *r;
            m + Mat3::from_cols(d * r.x, d * r.y, d * r.z)
        });
        // Warm-started as the solver is, from the last substep's frame (here 0.2 rad off).
        let guess = Quat::from_axis_angle(Vec3::new(0.3, -1.0, 0.2).normalize(), 0.2) * q;
        let got = extract_rotation(&a, guess);
        assert!(got.dot(q).abs() > 1.0 - 1e-5, "{got} vs {q}");
    }

    /// The sticks' projection of a configuration that is already a rigid turn of the
    /// arms gives that turn back; of a stretched one, moves that exert no torque about
    /// the arms and sum to zero (forces along the old sticks).
    #[test]
    fn match_turn_projects_along_the_old_sticks() {
        let arms = [
            DVec3::new(0.03, 0.06, 0.12),
            DVec3::new(0.03, -0.06, -0.12),
            DVec3::new(-0.03, 0.06, -0.12),
            DVec3::new(-0.03, -0.06, 0.12),
        ];
        let turn = DQuat::from_scaled_axis(DVec3::new(0.002, -0.003, 0.004));
        let rigid = arms.map(|a| turn * a);
        let got = match_turn(&rigid, &arms, DQuat::IDENTITY);
        assert!(got.dot(turn).abs() > 1.0 - 1e-12, "{got} vs {turn}");
        // Stretched: each point pushed out along its arm and sideways.
        let p: [DVec3; 4] =
            std::array::from_fn(|k| rigid[k] * 1.01 + DVec3::new(0.0, 0.001 * k as f64, -0.0005));
        let c = (p[0] + p[1] + p[2] + p[3]) * 0.25;
        let p = p.map(|x| x - c);
        let q = match_turn(&p, &arms, DQuat::IDENTITY);
        let moves: [DVec3; 4] = std::array::from_fn(|k| q * arms[k] - p[k]);
        let torque: DVec3 = (0..4).map(|k| arms[k].cross(moves[k])).sum();
        let sum: DVec3 = moves.iter().sum();
        assert!(torque.length() < 1e-12, "torque {torque}");
        assert!(sum.length() < 1e-12, "net move {sum}");
    }
}
