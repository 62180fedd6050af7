//! The sticks' projection: each bone's six sticks solved together, exactly, once per
//! pass (SHAKE, Ryckaert et al. 1977, on the paper's sticks of section 3.1).
//!
//! Six sticks fix a tetrahedron's shape, so the particles that meet them are a rigid
//! pose of the rest tetrahedron, `g_k = c + Q a_k`, with `a_k` the particles about their
//! centre at the start of the substep (rigid then) and `c` their centre now. SHAKE
//! takes each stick's force along the stick as it was at the start of the substep,
//! `Δx_k = w Σ_e λ_e (x_a − x_b)ⁿ`. Forces along the old sticks are exactly the moves
//! with no net force and no torque about the old positions (six of each on a
//! tetrahedron), so the projection is the pose with `Σ (g_k − x_k) = 0` (it keeps the
//! centre) and `Σ a_k × (g_k − x_k) = 0` (`frame::match_turn` solves for `Q`).
//!
//! **Why SHAKE.** Forces central about the old positions keep the discrete angular
//! momentum `Σ m xⁿ⁺¹ × vⁿ⁺½` exactly, and the step is symplectic: a spinning box keeps
//! `|L|` to round-off and its energy without drift. The closest rigid pose (shape
//! matching, Müller et al. 2005, the torque about the current positions) is a
//! projection along the gradients at the end of the step, which drags a spin by
//! `(ω h)² / 2` a substep: a box spinning at 5 rad/s lost 8 % of `|L|` in 10 s, and the
//! Gauss–Seidel passes over single sticks that ran before it lost as much again.

use super::super::bone::Bone;
use super::frame;
use super::particles::{PER_BONE, XParticles};
use glam::{DMat3, DVec3, Vec3A};

/// Moves every moving bone's particles onto their projected rigid pose (module doc),
/// and sets its frame there: the pose is the turn `Q` of the particles at the
/// substep's start, whose frame was read then (`prev_rot`), so the frame is
/// `Q prev_rot` without reading it again (`step` reads it once at the substep's end).
pub(crate) fn project(p: &mut XParticles, bones: &mut [Bone]) {
    for (i, b) in bones.iter_mut().enumerate() {
        if !p.moves(i) {
            continue;
        }
        let f = PER_BONE * i;
        let x = p.bone64(i);
        let c = (x[0] + x[1] + x[2] + x[3]) * 0.25;
        let arms = p.arms_prev(i);
        let off = x.map(|xk| xk - c);
        // The frame turned with every correction (`joints::move_linear`): a guess
        // within the second order of the answer.
        let guess = (b.rot.as_dquat() * b.prev_rot.as_dquat().inverse()).normalize();
        let q = frame::match_turn(&off, &arms, guess);
        let d: [DVec3; 4] = std::array::from_fn(|k| q * arms[k] - off[k]);
        let mean = (d[0] + d[1] + d[2] + d[3]) * 0.25;
        for (xk, dk) in p.x[f..f + PER_BONE].iter_mut().zip(d) {
            *xk += dk - mean;
        }
        b.rot = (q.as_quat() * b.prev_rot).normalize();
        b.com = Vec3A::from(c.as_vec3());
        b.dcom = Vec3A::ZERO;
    }
}

/// The sticks at the velocity level (RATTLE, Andersen 1983): bone `i`'s particle
/// velocities projected onto the rigid ones, `v_k = v̄ + ω × r_k` with `v̄` their mean
/// and `ω = I⁻¹ Σ m r_k × (v_k − v̄)`, the mass-weighted closest rigid velocities.
/// A stick `|x_a − x_b| = l` holds only if `(v_a − v_b) · (x_a − x_b) = 0`; the six
/// of a bone hold together exactly for the rigid velocities. The projection keeps
/// linear and angular momentum and takes only the non-rigid part's energy. Without
/// it a velocity change on barycentric weights (a contact's velocity pass) left a
/// stretching velocity whose mean the position projection then carried on: a box
/// pushed out of the ground at 3 m/s left it at 2.25 m/s.
pub(crate) fn project_velocities(p: &mut XParticles, i: usize) {
    if !p.moves(i) {
        return;
    }
    // In f64, with the inertia of the particles themselves: the projection then gives
    // back rigid velocities unchanged. With the bone's f32 inertia, 4e-7 apart from the
    // particles', each projection turned a spin by that much, and a box spinning for
    // 10 s lost 1-7 % of |L|.
    let f = PER_BONE * i;
    let c = p.centre(i);
    let r: [DVec3; 4] = std::array::from_fn(|k| p.x[f + k] - c);
    let v: [DVec3; 4] = std::array::from_fn(|k| p.v[f + k].as_dvec3());
    let mean = (v[0] + v[1] + v[2] + v[3]) * 0.25;
    let mut l = DVec3::ZERO;
    let mut inertia = DMat3::ZERO;
    for k in 0..PER_BONE {
        l += r[k].cross(v[k] - mean);
        inertia += DMat3::from_diagonal(DVec3::splat(r[k].length_squared()))
            - DMat3::from_cols(r[k] * r[k].x, r[k] * r[k].y, r[k] * r[k].z);
    }
    let det = inertia.determinant();
    if !det.is_finite() || det.abs() <= 1e-300 {
        return;
    }
    let om = inertia.inverse() * l;
    for (vk, rk) in p.v[f..f + PER_BONE].iter_mut().zip(r) {
        *vk = (mean + om.cross(rk)).as_vec3();
    }
}
