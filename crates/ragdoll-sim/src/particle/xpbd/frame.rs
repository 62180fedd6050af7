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
use glam::{Mat3, Quat, Vec3, Vec3A};

/// Turn (rad) below which the extraction has converged.
const EXTRACT_TOLERANCE: f32 = 1e-7;
/// Most iterations of the extraction; warm-started, a step needs one or two.
const EXTRACT_ITERATIONS: usize = 16;

/// `D⁻¹` of the bone's rest tetrahedron (see the module doc).
pub(crate) fn rest_inverse(rest: &[Vec3; 4]) -> Mat3 {
    Mat3::from_cols(rest[1] - rest[0], rest[2] - rest[0], rest[3] - rest[0]).inverse()
}

/// The barycentric weights of `local` (a point in the bone frame).
pub(crate) fn weights(rest_inv: &Mat3, rest0: Vec3, local: Vec3) -> [f32; 4] {
    let b = *rest_inv * (local - rest0);
    [1.0 - b.x - b.y - b.z, b.x, b.y, b.z]
}

/// The point with weights `w` among the four positions `x`.
#[inline]
pub(crate) fn combine(x: &[Vec3; 4], w: &[f32; 4]) -> Vec3 {
    x[0] * w[0] + x[1] * w[1] + x[2] * w[2] + x[3] * w[3]
}

/// Reads `bone`'s frame from its particles `x` (module doc), its old orientation the
/// starting guess.
pub(crate) fn read(bone: &mut Bone, x: &[Vec3; 4]) {
    let c = (x[0] + x[1] + x[2] + x[3]) * 0.25;
    let mut a = Mat3::ZERO;
    for (xk, r) in x.iter().zip(&bone.rest) {
        let d = *xk - c;
        a += Mat3::from_cols(d * r.x, d * r.y, d * r.z);
    }
    bone.rot = extract_rotation(&a, bone.rot);
    bone.prev_rot = bone.rot;
    bone.com = Vec3A::from(c);
    bone.dcom = Vec3A::ZERO;
}

/// The rotational part of `a`, starting from `q` (Müller et al. 2016).
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
        let inv = rest_inverse(&rest);
        for p in [
            Vec3::new(0.3, -0.4, 0.2),
            Vec3::ZERO,
            Vec3::new(-1.0, 2.0, 0.5),
        ] {
            let w = weights(&inv, rest[0], p);
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
}
