//! Contact response of the improved solver (after Müller et al. 2020, "Detailed rigid
//! body simulation with extended position based dynamics", sections 3.5–3.6).
//!
//! Position level, per substep: the normal constraint pushes the shapes apart; then the
//! tangential slip of the contact points during the substep is cancelled entirely when
//! its multiplier stays inside the Coulomb cone, `λ_t ≤ μ λ_n` (static friction), and
//! otherwise only up to `λ_t = μ λ_n` (kinetic friction). Clamping rather than
//! all-or-nothing lets Gauss–Seidel share the tangential load between the points of a
//! manifold — with all-or-nothing each point sees the whole body's slip against a
//! quarter of its normal load and a box creeps down a slope below the friction angle.
//! Static friction also takes back half of a small drift the point made since it became
//! active ([`ANCHOR_PULL`]), which a resting limb otherwise accumulates as a creep.
//!
//! Velocity level: the normal velocity is set to `−e v_n` (the approach speed before
//! the solve) above the restitution threshold and to zero below it, which also removes
//! any velocity the position projection created: pushing out of a penetration must not
//! add energy.

use super::bone::{Bone, Correction, Side, positional_along, side_world};
use super::contacts::{ContactPoint, Manifold};
use glam::{Vec3, Vec3A};

fn side_displacement(bones: &[Bone], s: Side, local: Vec3) -> Vec3A {
    match s {
        Some(i) => bones[i].displacement(local),
        None => Vec3A::ZERO,
    }
}

/// Velocity of a side's material point at world `p`.
#[inline]
pub(crate) fn point_velocity(bones: &[Bone], s: Side, p: Vec3A) -> Vec3A {
    match s {
        Some(i) if !bones[i].is_static() => {
            let b = &bones[i];
            b.lin_vel + b.ang_vel.cross(p - b.center())
        }
        _ => Vec3A::ZERO,
    }
}

/// Normal position pass for one contact: push the shapes apart; an overlap older than
/// the substep by at most `push_out` a substep. Accumulates `lambda_n`.
///
/// The depth at the substep's start is the depth now less the points' approach along
/// the normal during the substep. What the substep's own motion brought in is taken back
/// in full (no tunnelling, however fast), and so is what was pushed in after the
/// point's last solve (by a joint, [`ContactPoint::left_before`]). An older overlap —
/// one a body started in (a file's rest pose, a body added inside another), or one a
/// new collision detection finds that the last one's points did not cover (a capsule
/// rolling off its contact point, a limb turning a corner into the ground between two
/// detections) — is pushed out by at most `push_out` = `Settings::max_push_out_speed` ×
/// h a substep, and the velocity pass takes the push velocity back: in one substep the
/// whole overlap would turn into a velocity of depth / h (25 cm in 1/1200 s is
/// 300 m/s), more than the velocity pass takes back. Pushed out in full, the overlaps a
/// detection found at 1000 substeps of 1/10 s frames threw the capsule human's limbs at
/// up to 30 m/s.
pub(crate) fn solve_normal(bones: &mut [Bone], m: &Manifold, c: &mut ContactPoint, push_out: f32) {
    let pa = bones[m.a].world(c.ra);
    let pb = side_world(bones, m.b, c.rb);
    let depth = (pa - pb).dot(m.n);
    if depth <= 0.0 {
        c.left = 0.0;
        return;
    }
    if c.touched_at.is_none() {
        c.touched_at = Some(Vec3::from(start_offset(bones, m, c, pa, pb)));
    }
    let approach = (bones[m.a].displacement(c.ra) - side_displacement(bones, m.b, c.rb)).dot(m.n);
    let old = (depth - approach).min(c.left_before).max(0.0);
    let left = (old - push_out).max(0.0);
    c.left = left;
    let correction = depth - left;
    if correction > 0.0 {
        c.lambda_n += positional_along(bones, (Some(m.a), pa), (m.b, pb), -m.n, correction);
    }
}

/// Tangential offset of a contact's two points at the start of the substep, `pa − pb`
/// less their motion since (`pa`, `pb` the points now; any time in the substep gives
/// the same).
fn start_offset(bones: &[Bone], m: &Manifold, c: &ContactPoint, pa: Vec3A, pb: Vec3A) -> Vec3A {
    let sub = bones[m.a].displacement(c.ra) - side_displacement(bones, m.b, c.rb);
    let d = pa - pb - sub;
    d - m.n * d.dot(m.n)
}

/// Share of a contact point's tangential drift since it came into touch
/// (`ContactPoint::touched_at`) that static friction takes back per substep, on top of
/// the substep's own slip.
///
/// Friction runs before the joints in each pass, so the joints' last corrections leave
/// a slip of a few micrometres a substep that a friction anchored at the substep's
/// start never sees again: at 20 substeps a frame it adds up to a creep of about 1 cm/s
/// on a resting limb, and a pile of humans stays awake for seconds (the 100-human pile
/// slept at 4.8 s). Taking all of the drift back (1), the whole drift comes back in one
/// substep as a velocity of drift / h and the human jitters at
/// 5–14 cm/s, never sleeping. Half a substep's drift (it halves every substep) stops the
/// creep without the jitter. Measured over piles of 4 to 44 humans (`ragdoll-lab stats
/// --scene pile --count N`, 11 distinct piles): they fall asleep at 1.5–2.9 s, mean 2.3,
/// against 2.2–4.9 s, mean 3.6, with the pull at zero. One scene's sleep time alone is
/// chaotic and moves by seconds with the rounding of a single operation (the human,
/// scene 8: 2.9 s with the pull, 2.8 s without), so the test
/// (`resting_piles_stop_creeping_and_sleep_sooner`) averages piles.
const ANCHOR_PULL: f32 = 0.5;

/// Largest drift (m) static friction takes back ([`ANCHOR_PULL`]). The creep it is for
/// is micrometres a substep; a larger drift is motion the drift would misread (a capsule
/// rolling moves its material point off the contact), and pulling it back acts as a
/// spring that can throw a limb: measured on the capsule human without this bound, an
/// arm spun up to 85 rad/s in one frame.
const DRIFT_MAX: f32 = 1e-4;

/// Friction position pass for one contact of a manifold whose normal multipliers sum to
/// `group_n` and whose friction has spent `group_t` so far: cancel the contact point's
/// tangential slip during the substep (and half its drift since it came into touch,
/// [`ANCHOR_PULL`]) entirely if that stays inside the Coulomb cone of the whole manifold
/// (static), else as far as the cone allows (kinetic). Returns the tangential multiplier
/// spent.
///
/// The cone is the manifold's, `Σλ_t ≤ μ Σλ_n`, not each point's: Gauss–Seidel does not
/// share the normal load evenly between a face's points within one pass, and a point
/// with little normal load would let the body slide (measured: a box on a 35° slope slid
/// 7 % further than Coulomb allows with per-point cones).
pub(crate) fn solve_friction(
    bones: &mut [Bone],
    m: &Manifold,
    c: &mut ContactPoint,
    group_n: f32,
    group_t: f32,
) -> f32 {
    // Nothing to spend (a manifold not pressed yet, or its cone used up): return before
    // measuring the slip, four rotations of the contact's arms.
    let allowed = m.mu * group_n - group_t;
    if allowed <= 0.0 {
        return 0.0;
    }
    let a = Some(m.a);
    let pa = bones[m.a].world(c.ra);
    let pb = side_world(bones, m.b, c.rb);
    let tangential = |d: Vec3A| d - m.n * d.dot(m.n);
    // The substep's slip, and the drift since the points came into touch:
    // `pa − pb = touched_at + drift + substep slip` along the tangent.
    let sub = tangential(bones[m.a].displacement(c.ra) - side_displacement(bones, m.b, c.rb));
    // A point not pressed itself (its manifold is) has not drifted.
    let drift = c
        .touched_at
        .map_or(Vec3A::ZERO, |t| tangential(pa - pb) - sub - Vec3A::from(t));
    // Corrections move pa − pb against the slip `d`, along `−d` itself (not normalised:
    // `Correction::along_scaled`, whose `w` is `|d|²` times the unit direction's).
    let against = |d: Vec3A, d2: f32| Correction::along_scaled(bones, (a, pa), (m.b, pb), -d, d2);
    // Static friction takes back the slip and a share of the drift when the cone allows
    // both; kinetic friction (or a static one that cannot afford the drift) acts on the
    // substep's slip alone, so it only ever opposes the motion it sees.
    let pulled = if drift.length() <= DRIFT_MAX {
        sub + drift * ANCHOR_PULL
    } else {
        sub
    };
    let pulled2 = pulled.length_squared();
    let corr_pulled = against(pulled, pulled2);
    // Static when the whole slip fits the cone: `|d| / w ≤ allowed`, that is
    // `|d|³ ≤ allowed W` with `W = |d|² w`. No slip at all (a drift taken back that
    // cancels the substep's slip exactly) fits: there is nothing to correct.
    let fits = |d2: f32, w: f32| d2 == 0.0 || (w > 0.0 && d2 * d2.sqrt() <= allowed * w);
    let (len2, corr) = if fits(pulled2, corr_pulled.w) || pulled == sub {
        (pulled2, corr_pulled)
    } else {
        let sub2 = sub.length_squared();
        (sub2, against(sub, sub2))
    };
    let len = len2.sqrt();
    if len < 1e-9 || corr.w <= 0.0 {
        return 0.0;
    }
    // λ = |correction| / w_unit, the correction being the slip or as much as the cone
    // allows: per unit of the slip vector, `len / (len w_unit) = len² / W`, or
    // `allowed / len`.
    let mu = (len2 / corr.w).min(allowed / len);
    corr.apply(bones, mu);
    let lt = mu * len;
    c.lambda_t += lt;
    lt
}

/// Radius of the contact patch a point contact stands for (m): the lever arm of its
/// torsional friction. A box resting on one corner otherwise spins about the normal
/// without losing energy, since a point cannot resist twist.
const PATCH_RADIUS: f32 = 0.01;

/// Velocity pass for one contact that was active this substep.
pub(crate) fn solve_velocity(
    bones: &mut [Bone],
    m: &Manifold,
    c: &ContactPoint,
    h: f32,
    restitution_threshold: f32,
) {
    if c.lambda_n <= 0.0 {
        return;
    }
    let a = Some(m.a);
    let pa = bones[m.a].world(c.ra);
    let pb = side_world(bones, m.b, c.rb);
    let v = point_velocity(bones, a, pa) - point_velocity(bones, m.b, pb);
    let vn = v.dot(m.n);
    // Normal: restitution on the approach speed before the solve, never more.
    let target = if c.vn_before > restitution_threshold {
        -m.e * c.vn_before
    } else {
        0.0
    };
    let corr = Correction::along(bones, (a, pa), (m.b, pb), m.n);
    if corr.w > 0.0 {
        let lambda = (target - vn) / corr.w;
        corr.apply_velocity(bones, lambda);
    }
    // Torsional friction: twist about the normal, capped by μ r λ_n / h.
    let twist = |bones: &[Bone], s: Side| match s {
        Some(i) if !bones[i].is_static() => bones[i].ang_vel.dot(m.n),
        _ => 0.0,
    };
    let spin = twist(bones, a) - twist(bones, m.b);
    if spin != 0.0 {
        // Both levers `I⁻¹ n` formed once, for the inverse mass and the impulse.
        let turn = Correction::turning(bones, a, m.b, m.n);
        if turn.w > 0.0 {
            let cap = m.mu * PATCH_RADIUS * c.lambda_n / h;
            let l = spin.signum() * (spin.abs() / turn.w).min(cap);
            turn.apply_velocity(bones, -l);
        }
    }
}
