//! Joints and limits as constraints on particles.
//!
//! **Points.** A joint's anchor on a bone is the fixed affine combination `Σ β_k x_k`
//! of the bone's particles (`frame`); the ball constraint `C = p_b − p_a = 0` moves
//! particle `k` of side `a` by `β_k w_k Δλ n` with `Δλ = |C| / (Σ_a β² w + Σ_b β² w + α̃)`
//! (XPBD, Macklin et al. 2016, eq. 18, one iteration from `λ = 0` per substep).
//!
//! **Angles.** Hinge axes, universal shafts, a fixed joint's orientation and the
//! limits are functions of the bones' frames, and the frame is read from the particles
//! (`frame::read`). To first order it turns by `δθ = I⁻¹ Σ m r_k × Δx_k`, so an angle
//! `C` with world gradient `n` (per unit turn of the frame) has gradient
//! `∇_k C = m_k (I⁻¹ n) × r_k` on particle `k` and generalised inverse mass
//! `Σ w_k |∇_k C|² = nᵀ I⁻¹ n` — the rigid body's. The XPBD update
//! `Δx_k = w_k ∇_k C Δλ = (I⁻¹ n Δλ) × r_k` turns every particle about the centre of
//! mass; the sticks then take back the second-order stretch of the linear turn.

use super::super::bone::{Bone, Side};
use super::super::joint_kinds::JointKind;
use super::super::joints::{Joint, JointType, hinge_turn_ratio};
use super::super::limits::{Swing, SwingLimit, perpendicular};
use super::frame::combine64;
use super::particles::{PER_BONE, XParticles};
use glam::{DQuat, DVec3, Quat, Vec3};

/// One side of a point constraint: a bone and the point's weights on its particles,
/// or a point fixed in the world.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Anchor {
    /// On bone `.0` with barycentric weights `.1`.
    Bone(u32, [f32; 4]),
    /// Fixed in the world.
    World(Vec3),
}

impl Anchor {
    /// Where the point is now, rounded to f32 (drawing).
    #[inline]
    pub fn point(&self, p: &XParticles) -> Vec3 {
        self.point64(p).as_vec3()
    }

    /// Where the point is now.
    #[inline]
    pub fn point64(&self, p: &XParticles) -> DVec3 {
        match *self {
            Anchor::Bone(i, ref w) => combine64(&p.bone64(i as usize), w),
            Anchor::World(x) => x.as_dvec3(),
        }
    }

    /// Where the point was at the start of the substep.
    #[inline]
    pub fn prev_point64(&self, p: &XParticles) -> DVec3 {
        match *self {
            Anchor::Bone(i, ref w) => combine64(&p.bone_prev(i as usize), w),
            Anchor::World(x) => x.as_dvec3(),
        }
    }

    /// The point's velocity, `Σ β_k v_k` (0 for the world).
    #[inline]
    pub fn velocity(&self, p: &XParticles) -> Vec3 {
        match *self {
            Anchor::Bone(i, ref w) => {
                let f = PER_BONE * i as usize;
                let v = &p.v;
                super::frame::combine(&[v[f], v[f + 1], v[f + 2], v[f + 3]], w)
            }
            Anchor::World(_) => Vec3::ZERO,
        }
    }

    /// Its generalised inverse mass, `Σ β_k² w_k`.
    #[inline]
    pub fn inv_mass(&self, p: &XParticles) -> f32 {
        match *self {
            Anchor::Bone(i, ref w) => {
                let f = PER_BONE * i as usize;
                (0..PER_BONE).map(|k| w[k] * w[k] * p.w[f + k]).sum()
            }
            Anchor::World(_) => 0.0,
        }
    }

    /// Moves the point by `d` times its inverse mass: particle `k` by `β_k w_k d`.
    #[inline]
    pub fn shift(&self, p: &mut XParticles, d: Vec3) {
        if let Anchor::Bone(i, ref w) = *self {
            let f = PER_BONE * i as usize;
            for (k, wk) in w.iter().enumerate() {
                p.x[f + k] += (d * (wk * p.w[f + k])).as_dvec3();
            }
        }
    }
}

/// Closes `delta` (from `a`'s point towards `b`'s) with compliance `alpha_tilde`
/// (`α / h²`): the XPBD point correction. Returns `Δλ` (its magnitude, m·kg).
pub(crate) fn pull(
    p: &mut XParticles,
    a: &Anchor,
    b: &Anchor,
    delta: Vec3,
    alpha_tilde: f32,
) -> f32 {
    let c = delta.length();
    if c < 1e-9 {
        return 0.0;
    }
    let w = a.inv_mass(p) + b.inv_mass(p);
    if w + alpha_tilde <= 0.0 {
        return 0.0;
    }
    let n = delta / c;
    let dl = c / (w + alpha_tilde);
    a.shift(p, n * dl);
    b.shift(p, -n * dl);
    dl
}

/// Closes `delta` (from `a`'s point towards `b`'s) with compliance `alpha_tilde`,
/// each side's particles moved along the gradient of its point taken as a point of the
/// rigid frame they imply, evaluated at the start of the substep (SHAKE, Ryckaert et
/// al. 1977). The point is `c + R r`; to first order the frame turns by
/// `δθ = I⁻¹ Σ m r_k × Δx_k` (`frame`), so its gradient on particle `k` is
/// `¼ n + m_k (I⁻¹ (r × n)) × r_k` and its generalised inverse mass the rigid body's,
/// `1/m + (r × n)ᵀ I⁻¹ (r × n)`: the XPBD update moves particle `k` by
/// `(n / m + (I⁻¹ (r × n)) × r_k) Δλ`, a translation and a linear turn. Every term
/// (`r`, `r_k`, `I`) is taken at the substep's start, where the particles are rigid:
/// the correction is then a sum of forces along that configuration's sticks and
/// constraint gradients, which keeps the step symplectic; taken at the current
/// positions, the pendulum of the closed forms lost 0.8 % of its swing energy a
/// second, a drag of `(ω₀ h)²` a substep. The linear turn stretches the sticks to
/// second order; the sticks' projection (`shape_match`) takes that back.
fn pull_rigid(
    p: &mut XParticles,
    bones: &mut [Bone],
    a: &Anchor,
    b: &Anchor,
    delta: Vec3,
    alpha_tilde: f32,
) {
    let c = delta.length();
    if c < 1e-9 {
        return;
    }
    let n = delta / c;
    let lever = |p: &XParticles, bones: &[Bone], e: &Anchor| -> Option<(usize, f32, Vec3)> {
        match *e {
            Anchor::Bone(i, _) if p.moves(i as usize) => {
                let i = i as usize;
                let rn = (e.prev_point64(p) - p.centre_prev(i)).as_vec3().cross(n);
                let (wr, turn) = inertia_lever(p, bones, Some(i), rn, |b| b.prev_rot);
                Some((i, 1.0 / bones[i].mass + wr, turn))
            }
            _ => None,
        }
    };
    let la = lever(p, bones, a);
    let lb = lever(p, bones, b);
    let den = la.map_or(0.0, |l| l.1) + lb.map_or(0.0, |l| l.1) + alpha_tilde;
    if den <= 0.0 {
        return;
    }
    let dl = c / den;
    for (side, sign) in [(la, 1.0f32), (lb, -1.0)] {
        if let Some((i, _, turn)) = side {
            let shift = n * (sign * dl / bones[i].mass);
            move_linear(p, bones, i, shift, turn * (sign * dl));
        }
    }
}

/// Moves bone `i`'s particles by `shift + omega × a_k`, `a_k` their arms about their
/// centre at the substep's start (`pull_rigid`), and turns its read frame by `omega`.
/// Inlined: the blocks' passes call it for every side they move.
#[inline(always)]
pub(super) fn move_linear(
    p: &mut XParticles,
    bones: &mut [Bone],
    i: usize,
    shift: Vec3,
    omega: Vec3,
) {
    let f = PER_BONE * i;
    for (k, arm) in (f..f + PER_BONE).zip(p.arms_prev(i)) {
        p.x[k] += (shift + omega.cross(arm.as_vec3())).as_dvec3();
    }
    let b = &mut bones[i];
    b.rot = (Quat::from_scaled_axis(omega) * b.rot).normalize();
}

/// `nᵀ I⁻¹ n` and `I⁻¹ n` (world) of bone `i` for `n`, with the bone's frame `frame`
/// reads (now, or at the substep's start), 0 if it takes no correction.
#[inline]
fn inertia_lever(
    p: &XParticles,
    bones: &[Bone],
    s: Side,
    n: Vec3,
    frame: impl Fn(&Bone) -> Quat,
) -> (f32, Vec3) {
    match s {
        Some(i) if p.moves(i) => {
            let b = &bones[i];
            let rot = frame(b);
            let local = rot.inverse() * n;
            let turn = rot * (Vec3::from(b.inv_inertia_local) * local);
            (n.dot(turn), turn)
        }
        _ => (0.0, Vec3::ZERO),
    }
}

/// Turns bone `i`'s particles by the world rotation `omega` about their centre of
/// mass, and its read frame with them. To first order this is `Δx_k = ω × (x_k − c)`
/// (module doc); the rotation itself, `x_k ← c + exp(ω)(x_k − c)`, keeps every stick's
/// length where the linear step would stretch it by `√(1 + |ω|²)`.
fn turn_bone(p: &mut XParticles, bones: &mut [Bone], i: usize, omega: Vec3) {
    let f = PER_BONE * i;
    let x = p.bone64(i);
    let c = (x[0] + x[1] + x[2] + x[3]) * 0.25;
    // The turn in f64: a small `ω` keeps its relative precision there, where an f32
    // quaternion's `w` rounds near 1.
    let q = DQuat::from_scaled_axis(omega.as_dvec3());
    for (k, xk) in x.iter().enumerate() {
        p.x[f + k] = c + q * (*xk - c);
    }
    let b = &mut bones[i];
    b.rot = (q.as_quat() * b.rot).normalize();
}

/// Turns side `a` by `dphi` relative to side `b` (a world rotation vector: the angle
/// `|dphi|` about its direction), split by the sides' inverse inertias, with
/// compliance `alpha_tilde` (module doc).
pub(crate) fn turn(
    p: &mut XParticles,
    bones: &mut [Bone],
    a: Side,
    b: Side,
    dphi: Vec3,
    alpha_tilde: f32,
) {
    let c = dphi.length();
    if c < 1e-9 || !c.is_finite() {
        return;
    }
    let n = dphi / c;
    let (wa, ta) = inertia_lever(p, bones, a, n, |b| b.rot);
    let (wb, tb) = inertia_lever(p, bones, b, n, |b| b.rot);
    let den = wa + wb + alpha_tilde;
    if den <= 0.0 {
        return;
    }
    let dl = c / den;
    if let Some(i) = a.filter(|_| wa > 0.0) {
        turn_bone(p, bones, i, ta * dl);
    }
    if let Some(i) = b.filter(|_| wb > 0.0) {
        turn_bone(p, bones, i, -tb * dl);
    }
}

/// Orientation of a side (identity for the world).
#[inline]
pub(super) fn rot(bones: &[Bone], s: Side) -> Quat {
    s.map_or(Quat::IDENTITY, |i| bones[i].rot)
}

/// The angular parts of joint `j` of kind `kind`, then its limits, on the frames in
/// `bones` (read from the particles this substep and turned with them since).
pub(crate) fn solve_angular(
    p: &mut XParticles,
    bones: &mut [Bone],
    (j, kind): (&Joint, &JointKind),
    h: f32,
) {
    let (a, b) = (j.a(), j.b());
    match kind.joint_type {
        JointType::Hinge { axis_a, axis_b } => {
            // Turn body1's axis onto body2's: by `asin(s)` about `c / s`, `c = t_a × t_b`.
            let ta = rot(bones, a) * axis_a;
            let tb = rot(bones, b) * axis_b;
            let c = ta.cross(tb);
            let s2 = c.length_squared();
            if s2 > 1e-18 {
                turn(p, bones, a, b, c * hinge_turn_ratio(s2), 0.0);
            }
        }
        JointType::Universal { shaft_a, shaft_b } => {
            // Keep the shafts perpendicular: turn by `asin(s₁ · s₂)` about `s₂ × s₁`.
            let s1 = rot(bones, a) * shaft_a;
            let s2 = rot(bones, b) * shaft_b;
            let n = s2.cross(s1);
            let l = n.length();
            if l > 1e-9 {
                turn(
                    p,
                    bones,
                    a,
                    b,
                    n / l * s1.dot(s2).clamp(-1.0, 1.0).asin(),
                    0.0,
                );
            }
        }
        JointType::Fixed | JointType::Slider { .. } => {
            // Body1's rotation onto its rest orientation relative to body2:
            // `e = q_b q_rest q_a⁻¹`, turned by its rotation vector.
            let mut e = rot(bones, b) * kind.rest_rel * rot(bones, a).inverse();
            if e.w < 0.0 {
                e = -e;
            }
            turn(p, bones, a, b, Vec3::new(e.x, e.y, e.z) * 2.0, 0.0);
        }
        JointType::Ball | JointType::Spring { .. } => {}
    }
    let alpha = kind.limit_compliance / (h * h);
    if let Some(s) = &kind.swing
        && let Some(dphi) = swing_correction(s, bones, a, b, j.slack)
    {
        turn(p, bones, a, b, dphi, alpha);
    }
    for l in &kind.angle_limits {
        // `C = φ − clamp(φ)` along its gradient `J` (per unit turn of body1), the range
        // widened by the joint's slack: a turn `J (target − φ) / |J|²` restores it.
        let (phi, grad) = l.angle(bones, a, b);
        let target = phi.clamp(l.min - j.slack, l.max + j.slack);
        let g2 = grad.length_squared();
        if target != phi && g2 > 1e-12 {
            turn(p, bones, a, b, grad * ((target - phi) / g2), alpha);
        }
    }
}

/// The turn of body1 that brings a swing limit's shaft back onto its cone or pyramid
/// widened by `slack` (rad, [`Joint::slack`]), if it is outside: about `s × t` by the
/// angle between the shaft `s` and the nearest allowed direction `t`.
pub(super) fn swing_correction(
    s: &SwingLimit,
    bones: &[Bone],
    a: Side,
    b: Side,
    slack: f32,
) -> Option<Vec3> {
    let qb = rot(bones, b);
    let shaft = rot(bones, a) * s.shaft_a;
    let axis = qb * s.axis_b;
    let t = match s.kind {
        Swing::Cone { half_angle, .. } => {
            let half_angle = half_angle + slack;
            let phi = shaft.dot(axis).clamp(-1.0, 1.0).acos();
            if phi <= half_angle {
                return None;
            }
            // The nearest direction on the cone lies in the plane of shaft and axis.
            let mut n = axis.cross(shaft);
            if n.length_squared() < 1e-12 {
                n = perpendicular(axis);
            }
            Quat::from_axis_angle(n.normalize(), half_angle) * axis
        }
        Swing::Pyramid { h1, h2, u, v } => {
            let (h1, h2) = (h1 + slack, h2 + slack);
            // Angles in the planes (axis, u) and (axis, v), each clamped to its range;
            // the allowed direction with the clamped angles.
            let (u, v) = (qb * u, qb * v);
            let (x, y, z) = (shaft.dot(u), shaft.dot(v), shaft.dot(axis));
            let (a1, a2) = (x.atan2(z), y.atan2(z));
            if a1.abs() <= h1 && a2.abs() <= h2 {
                return None;
            }
            let most = 89f32.to_radians();
            let c1 = a1.clamp(-h1.min(most), h1.min(most));
            let c2 = a2.clamp(-h2.min(most), h2.min(most));
            (axis + u * c1.tan() + v * c2.tan()).normalize()
        }
    };
    let mut n = shaft.cross(t);
    if n.length_squared() < 1e-12 {
        n = perpendicular(shaft);
    }
    Some(n.normalize() * shaft.dot(t).clamp(-1.0, 1.0).acos())
}

/// The point part of joint `j` of kind `kind` between its anchors `ends`, with `h` the
/// substep, moving each bone rigidly (`pull_rigid`).
pub(crate) fn solve_point(
    p: &mut XParticles,
    bones: &mut [Bone],
    (j, kind): (&Joint, &JointKind),
    ends: &[Anchor; 2],
    h: f32,
) {
    let [a, b] = ends;
    let d = (b.point64(p) - a.point64(p)).as_vec3();
    match kind.joint_type {
        JointType::Spring {
            stretch,
            compress,
            rest,
            min,
            max,
        } => {
            let len = d.length();
            if len < 1e-9 {
                return;
            }
            let n = d / len;
            let target = if max > 0.0 && len > max {
                Some((max, 0.0))
            } else if min > 0.0 && len < min {
                Some((min, 0.0))
            } else {
                let k = if len > rest { stretch } else { compress };
                (k > 0.0).then(|| (rest, 1.0 / (k * h * h)))
            };
            if let Some((l0, alpha)) = target {
                pull_rigid(p, bones, a, b, n * (len - l0), alpha);
            }
        }
        JointType::Slider { axis_b } => {
            let axis = rot(bones, j.b()) * axis_b;
            pull_rigid(p, bones, a, b, d - axis * axis.dot(d), 0.0);
        }
        _ => {
            pull_rigid(p, bones, a, b, d, 0.0);
        }
    }
}
