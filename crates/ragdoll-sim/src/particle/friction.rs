//! Contact response of the improved solver (after Müller et al. 2020, "Detailed rigid
//! body simulation with extended position based dynamics", sections 3.5–3.6).
//!
//! Position level, per substep: the normal constraints of a manifold's points push the
//! shapes apart together, one block solved over the manifold's own matrix
//! ([`solve_normals`]: one point at a time, the first point of a face would turn the
//! body and the rest only partly turn it back); then the
//! tangential slip of the contact points during the substep is cancelled entirely when
//! its multiplier stays inside the Coulomb cone, `λ_t ≤ μ λ_n` (static friction), and
//! otherwise only up to `λ_t = μ λ_n` (kinetic friction). Clamping rather than
//! all-or-nothing lets Gauss–Seidel share the tangential load between the points of a
//! manifold — with all-or-nothing each point sees the whole body's slip against a
//! quarter of its normal load and a box creeps down a slope below the friction angle.
//! Static friction also takes back half of a small drift the point made since it became
//! active ([`ANCHOR_PULL`]), which a resting limb otherwise accumulates as a creep.
//!
//! Velocity level: the normal velocity is brought to `−e v_n` (the approach speed before
//! the solve) above the restitution threshold and to zero below it, which also removes
//! the velocity the position projection created: pushing out of a penetration must not
//! add energy. The velocity pass may take back what the position pass pushed, never
//! pull further: over a substep a contact's normal impulse is a push
//! ([`solve_velocities`]).

use super::bone::{Bone, Correction, Side, rotate_local, side_world};
use super::contacts::{ContactPoint, Manifold};
use glam::{Vec3, Vec3A};
use wide::f32x4;

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

/// How far an old overlap may be pushed out ([`normal_target`]) in the substep under
/// way: the same for every point of the contact set, so formed once a substep rather
/// than kept with each point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PushOut {
    /// In the substep, `max_push_out_speed × h` (m).
    pub substep: f32,
    /// In the frame so far, `substep` times the frame's substeps up to and including
    /// this one, `k`: the product `substep × (k as f32)`, formed once. Every point of the
    /// set was detected in the frame and is solved in each of its substeps since (a
    /// detection only makes manifolds with a moving side, and the substeps visit every
    /// such manifold), so `k` counts the substeps its overlap allowance has run for.
    pub frame: f32,
}

impl PushOut {
    /// Substep `k` of the frame (counted from 1) at `max_push_out_speed × h` = `substep`.
    pub fn at(substep: f32, k: u32) -> PushOut {
        PushOut {
            substep,
            frame: substep * k as f32,
        }
    }
}

/// How deep contact point `c` of manifold `m` may still be at the end of this solve, and
/// what it takes to get there: returns the points `pa`, `pb` and the correction along
/// the normal the point needs, `depth − left` (negative for a point not touching: how
/// far it may be pushed in before it touches). Sets `c.left` and, on the first press of
/// a run of touching substeps, `c.touched_at`.
///
/// The depth at the substep's start is the depth now less the points' approach along
/// the normal during the substep. What the substep's own motion brought in is taken back
/// in full (no tunnelling, however fast), and so is what was pushed in after the
/// point's last solve (by a joint, [`ContactPoint::left_before`]). An older overlap —
/// one a body started in (a file's rest pose, a body added inside another), or one a
/// new collision detection finds that the last one's points did not cover (a capsule
/// rolling off its contact point, a limb turning a corner into the ground between two
/// detections) — is pushed out by at most `push.substep` = `Settings::max_push_out_speed`
/// × h a substep, and the velocity pass takes the push velocity back: in one substep the
/// whole overlap would turn into a velocity of depth / h (25 cm in 1/1200 s is
/// 300 m/s), more than the velocity pass takes back. Pushed out in full, the overlaps a
/// detection found at 1000 substeps of 1/10 s frames threw the capsule human's limbs at
/// up to 30 m/s.
///
/// The old overlap also never ends a substep shallower than the frame's allowance,
/// [`ContactPoint::frame_overlap`] less `push.frame` ([`PushOut`]), one product measured
/// from where the bones stood as the frame began. Without it the bound only chains from
/// substep to substep (`old` is the lesser of the depth now and the last target), and that
/// chain keeps every f32 rounding of a bone's centre that lifts it out and corrects every
/// one that leaves it deeper: a 1 m cube rising out of the ground moved up to 12 ulp of its
/// height (3.7e-7 m) a frame more than `max_push_out_speed` × dt. Measured against the
/// frame's start, what is left is the rounding of the frame's last position, which the next
/// frame measures from.
fn normal_target(
    bones: &[Bone],
    m: &Manifold,
    c: &mut ContactPoint,
    push: PushOut,
) -> (Vec3A, Vec3A, f32) {
    let n = m.n();
    let pa = bones[m.a()].world(c.ra);
    let pb = side_world(bones, m.b(), c.rb);
    let depth = (pa - pb).dot(n);
    if depth <= 0.0 {
        c.left = 0.0;
        return (pa, pb, depth);
    }
    if c.touched_at().is_none() {
        c.set_touched_at(Some(Vec3::from(start_offset(bones, m, c, pa, pb))));
    }
    let approach = (bones[m.a()].displacement(c.ra) - side_displacement(bones, m.b(), c.rb)).dot(n);
    let old = (depth - approach).min(c.left_before).max(0.0);
    let frame_left = c.frame_overlap - push.frame;
    let left = (old - push.substep).max(frame_left).max(0.0);
    c.left = left;
    (pa, pb, depth - left)
}

/// Normal position pass for one contact on its own: push the shapes apart as far as
/// [`normal_target`] asks, or, for a point held in an old overlap that an earlier
/// pass pushed past its allowance, take that push back down to it ([`lowest_push`]).
/// Accumulates `lambda_n`. A manifold of more points than [`BLOCK`] solves them so, in
/// turn. Returns the point's two material points in the world, `(pa, pb)`, when it
/// moved nothing (they are where the bones still stand), `None` when it moved the bones.
pub(crate) fn solve_normal(
    bones: &mut [Bone],
    m: &Manifold,
    c: &mut ContactPoint,
    push: PushOut,
) -> Option<(Vec3A, Vec3A)> {
    let (pa, pb, correction) = normal_target(bones, m, c, push);
    let lowest = lowest_push(c);
    // A correction under 1e-9 m is left: below the f32 rounding of any position read.
    let moves = correction >= 1e-9 || (correction <= -1e-9 && lowest < 0.0);
    if !moves {
        return Some((pa, pb));
    }
    let corr = Correction::along(bones, (Some(m.a()), pa), (m.b(), pb), -m.n());
    if corr.w > 0.0 {
        let lambda = (correction / corr.w).max(lowest);
        corr.apply(bones, lambda);
        c.lambda_n += lambda;
        return None;
    }
    Some((pa, pb))
}

/// The least multiplier a pass may apply at point `c` after [`normal_target`] has set
/// its target: `−lambda_n` (taking back the substep's earlier pushes, never pulling
/// beyond them) for a point held in an old overlap (`c.left > 0`), zero otherwise.
///
/// The allowance of an old overlap ([`normal_target`]) is a bound on both sides: no
/// deeper than `left`, and no shallower either, or the bone is pushed out faster than
/// `max_push_out_speed`. Each pass reads the depth from the bones' f32 frames, and the
/// turns a block applies leave the face tilted by a few 1e-8 rad, so the points'
/// readings scatter by a few 1e-8 m about the target. A push that never comes back
/// (`λ ≥ 0` a pass) keeps every reading that says too deep and ignores every one that
/// says too shallow: pushing corner `A` of a face up by `e` lifts the centre by about
/// `e / 4` (a cube: `K_AA = 1/M + |r × n|² / I = 4/M`) and the opposite corner sinks
/// only by `e / 2`, so each pass after the first lifted the cube a little past its
/// allowance, about 1.2 f32 spacings of its height a frame with five passes. Bounded
/// on the substep's accumulated multiplier (`lambda_n ≥ 0`), a pressed point ends
/// each pass at its target whichever side the reading fell, and the passes no longer
/// add up. A point touching with no old overlap (`left = 0`) keeps `λ ≥ 0` a pass: its
/// only target is "not inside", and a point pulled back to touching would fight its own
/// friction, whose cone is spread by the points' pushes (`ManifoldSolve::pushed`).
fn lowest_push(c: &ContactPoint) -> f32 {
    if c.left > 0.0 { -c.lambda_n } else { 0.0 }
}

/// Most points of a manifold solved as one block ([`solve_normals`],
/// [`solve_velocities`]); parry's face–face manifolds between boxes have at most eight.
pub(crate) const BLOCK: usize = 8;

/// Projected Gauss–Seidel sweeps of a block over its own small matrix, at most: the
/// matrix of a box face's four points has eigenvalues within a factor of a few of each
/// other (and one zero, the twist no rigid motion makes), and a sweep costs `k²`
/// multiply–adds, nothing of the bones.
const BLOCK_SWEEPS: usize = 24;

/// A block's sweeps stop when no multiplier changes the correction of its own point by
/// more than this (m, or m/s in the velocity pass): f32 rounding of the corrections.
const BLOCK_TOLERANCE: f32 = 1e-7;

/// One side of a manifold's block: the bone and, per point, the lever `r × d` in the
/// bone frame and `I⁻¹ (r × d)` (`d` the direction the side is pushed: `−n` for `a`,
/// `n` for `b`).
struct BlockSide {
    bone: usize,
    inv_mass: f32,
    axis: [Vec3A; BLOCK],
    turn: [Vec3A; BLOCK],
}

impl BlockSide {
    /// The side's levers at world points `p[..k]`, or `None` for a static side.
    fn new(bones: &[Bone], s: Side, p: &[Vec3A], d: Vec3A) -> Option<BlockSide> {
        let i = s?;
        let b = &bones[i];
        if b.is_static() {
            return None;
        }
        let mut side = BlockSide {
            bone: i,
            inv_mass: b.inv_mass(),
            axis: [Vec3A::ZERO; BLOCK],
            turn: [Vec3A::ZERO; BLOCK],
        };
        let inv_rot = b.rot.inverse();
        for (k, &p) in p.iter().enumerate() {
            side.axis[k] = inv_rot * (p - b.center()).cross(d);
            side.turn[k] = b.inv_inertia_local * side.axis[k];
        }
        Some(side)
    }

    /// Adds the side's share to the block's matrix: `K_ij += 1/M + (r_i × d)ᵀ I⁻¹
    /// (r_j × d)`, the motion of point `i` along `d` per unit multiplier at point `j`.
    fn add_to(&self, k: usize, matrix: &mut [[f32; BLOCK]; BLOCK]) {
        for (i, row) in matrix.iter_mut().enumerate().take(k) {
            for (j, entry) in row.iter_mut().enumerate().take(k) {
                *entry += self.inv_mass + self.axis[i].dot(self.turn[j]);
            }
        }
    }

    /// The side's motion for multipliers `lambda[..k]` along `d`: the centre by
    /// `d Σλ / M`, the frame by `Σ λ_i I⁻¹ (r_i × d)`, one turn for the whole block.
    fn sums(&self, lambda: &[f32]) -> (f32, Vec3A) {
        let mut total = 0.0;
        let mut turn = Vec3A::ZERO;
        for (l, t) in lambda.iter().zip(&self.turn) {
            total += l;
            turn += *t * *l;
        }
        (total, turn)
    }

    /// Moves the side by multipliers `lambda` along `d` (a position correction).
    fn apply(&self, bones: &mut [Bone], d: Vec3A, lambda: &[f32]) {
        let (total, turn) = self.sums(lambda);
        let b = &mut bones[self.bone];
        b.dcom += d * (total * self.inv_mass);
        b.rot = rotate_local(b.rot, turn);
        b.dturn = rotate_local(b.dturn, turn);
    }

    /// Changes the side's velocities by impulses `lambda` along `d`.
    fn apply_velocity(&self, bones: &mut [Bone], d: Vec3A, lambda: &[f32]) {
        let (total, turn) = self.sums(lambda);
        let b = &mut bones[self.bone];
        b.lin_vel += d * (total * self.inv_mass);
        b.ang_vel += b.rot * turn;
    }
}

/// A manifold's points as one block: the sides' levers and the matrix `K` that maps
/// multipliers at the points to the points' relative motion along the normal.
struct Block {
    k: usize,
    a: Option<BlockSide>,
    b: Option<BlockSide>,
    matrix: [[f32; BLOCK]; BLOCK],
}

impl Block {
    fn new(bones: &[Bone], m: &Manifold, pa: &[Vec3A], pb: &[Vec3A]) -> Block {
        let (k, n) = (pa.len(), m.n());
        let a = BlockSide::new(bones, Some(m.a()), pa, -n);
        let b = BlockSide::new(bones, m.b(), pb, n);
        let mut matrix = [[0.0; BLOCK]; BLOCK];
        for side in a.iter().chain(&b) {
            side.add_to(k, &mut matrix);
        }
        Block { k, a, b, matrix }
    }

    /// Projected Gauss–Seidel on the block's linear complementarity problem, from
    /// `λ = 0`: each `λ_i ≥ lower_i`, `(K λ)_i ≥ rhs_i`, and one of the two an equality
    /// (a point pushes only as far as it must; where it pushes less than it could, it is
    /// left moving apart faster than asked). `lower` all zero is the position pass's
    /// contact problem; the velocity pass solves for the change of an accumulated
    /// impulse whose bound it shifts into `lower`.
    ///
    /// Run for the block's size as a constant ([`Block::solve_k`]): a sweep is a chain
    /// of a few multiply–adds a row, and with `k` known the loops unroll and the rows'
    /// bounds checks go.
    fn solve(&self, rhs: &[f32], lower: &[f32]) -> [f32; BLOCK] {
        match self.k {
            0 => [0.0; BLOCK],
            1 => self.solve_k::<1>(rhs, lower),
            2 => self.solve_k::<2>(rhs, lower),
            3 => self.solve_k::<3>(rhs, lower),
            4 => self.solve_k::<4>(rhs, lower),
            5 => self.solve_k::<5>(rhs, lower),
            6 => self.solve_k::<6>(rhs, lower),
            7 => self.solve_k::<7>(rhs, lower),
            8 => self.solve_k::<8>(rhs, lower),
            k => unreachable!("a block of {k} points, more than {BLOCK}"),
        }
    }

    /// [`Block::solve`] of a block of `K` points (`K == self.k`).
    ///
    /// The multipliers are held in two `f32x4` registers, one lane a point, and row
    /// `i`'s `Σ_j K_ij λ_j` adds its lanes' products in the order `j = 0, 1, …` from
    /// −0, as `Iterator::sum` of the scalar products: the same bits as the scalar
    /// sweep. Held in an array, each row's new `λ_i` was stored as one float and read
    /// back with its neighbours as one vector by the next row, a load the processor
    /// cannot forward from that store and waits for.
    #[inline(always)]
    fn solve_k<const K: usize>(&self, rhs: &[f32], lower: &[f32]) -> [f32; BLOCK] {
        debug_assert_eq!(K, self.k, "a block of {} points", self.k);
        let (rhs, lower) = (&rhs[..K], &lower[..K]);
        let quarter = |row: &[f32; BLOCK], q: usize| {
            f32x4::new([row[4 * q], row[4 * q + 1], row[4 * q + 2], row[4 * q + 3]])
        };
        let rows: [[f32x4; 2]; K] =
            std::array::from_fn(|i| [quarter(&self.matrix[i], 0), quarter(&self.matrix[i], 1)]);
        let mut lambda = [f32x4::ZERO; 2];
        for _ in 0..BLOCK_SWEEPS {
            let mut change = 0.0f32;
            for i in 0..K {
                let kii = self.matrix[i][i];
                if kii <= 0.0 {
                    continue;
                }
                let low = (rows[i][0] * lambda[0]).to_array();
                let high = if K > 4 {
                    (rows[i][1] * lambda[1]).to_array()
                } else {
                    [0.0; 4]
                };
                let mut moved = -0.0f32;
                for j in 0..K {
                    moved += if j < 4 { low[j] } else { high[j - 4] };
                }
                let old = lambda[i / 4].to_array()[i % 4];
                let next = (old + (rhs[i] - moved) / kii).max(lower[i]);
                change = change.max((next - old).abs() * kii);
                lambda[i / 4] = LANE[i % 4].select(f32x4::splat(next), lambda[i / 4]);
            }
            if change <= BLOCK_TOLERANCE {
                break;
            }
        }
        let mut out = [0.0; BLOCK];
        out[..4].copy_from_slice(&lambda[0].to_array());
        out[4..].copy_from_slice(&lambda[1].to_array());
        out
    }
}

/// Lane `i`'s mask of an `f32x4` (all bits set in lane `i`), for [`Block::solve_k`]'s
/// update of one multiplier.
const LANE: [f32x4; 4] = {
    const ON: f32 = f32::from_bits(u32::MAX);
    [
        f32x4::new([ON, 0.0, 0.0, 0.0]),
        f32x4::new([0.0, ON, 0.0, 0.0]),
        f32x4::new([0.0, 0.0, ON, 0.0]),
        f32x4::new([0.0, 0.0, 0.0, ON]),
    ]
};

/// Normal position pass for one manifold: its points pushed apart as one block, each as
/// far as [`normal_target`] asks and none further (the multipliers of the linear
/// complementarity problem `λ ≥ lowest`, `K λ ≥ c`, complementary, by [`Block::solve`];
/// `lowest` is zero but for a point held in an old overlap, which may take back the
/// substep's earlier pushes, [`lowest_push`]).
/// Accumulates each point's `lambda_n` and returns what each point took, `λ[..k]`, and
/// whether it moved the bones; `points` holds at most [`BLOCK`].
///
/// One point at a time, Gauss–Seidel over a face's four points is not symmetric: the
/// first point takes the whole correction, three quarters of it as a turn of a cube,
/// which the later points undo only in part. What is left is a turn the velocity
/// derivation reads as spin: a cube hitting a wall face-on at 50 m/s came away at
/// 3.5 rad/s and 1.8 m/s sideways, a cube pushed out of the ground tilted as it rose
/// and over-lifted the corners solved last (rising at 3.05 m/s against a push-out of
/// 3 m/s), and a stack of ten cubes leaned over and fell. Solved as a block, a face
/// pressed evenly moves without turning, whatever the order of its points.
pub(crate) fn solve_normals(
    bones: &mut [Bone],
    m: &Manifold,
    points: &mut [ContactPoint],
    push: PushOut,
) -> ([f32; BLOCK], bool) {
    let k = points.len();
    debug_assert!(k <= BLOCK, "a block of {k} points");
    let mut lambda = [0.0; BLOCK];
    if k == 1 {
        let before = points[0].lambda_n;
        let moved = solve_normal(bones, m, &mut points[0], push).is_none();
        lambda[0] = points[0].lambda_n - before;
        return (lambda, moved);
    }
    let (mut pa, mut pb, mut need) = ([Vec3A::ZERO; BLOCK], [Vec3A::ZERO; BLOCK], [0.0; BLOCK]);
    let mut lowest = [0.0; BLOCK];
    let mut pressed = false;
    for (i, c) in points.iter_mut().enumerate() {
        (pa[i], pb[i], need[i]) = normal_target(bones, m, c, push);
        lowest[i] = lowest_push(c);
        pressed |= need[i] > 0.0 || (need[i] < 0.0 && lowest[i] < 0.0);
    }
    // No point needs pushing nor was pushed past its allowance (a speculative
    // manifold): `λ = 0` solves the block.
    if !pressed {
        return (lambda, false);
    }
    let block = Block::new(bones, m, &pa[..k], &pb[..k]);
    lambda = block.solve(&need[..k], &lowest[..k]);
    let n = m.n();
    if let Some(s) = &block.a {
        s.apply(bones, -n, &lambda[..k]);
    }
    if let Some(s) = &block.b {
        s.apply(bones, n, &lambda[..k]);
    }
    for (c, l) in points.iter_mut().zip(lambda) {
        c.lambda_n += l;
    }
    (lambda, true)
}

/// Tangential offset of a contact's two points at the start of the substep, `pa − pb`
/// less their motion since (`pa`, `pb` the points now; any time in the substep gives
/// the same).
fn start_offset(bones: &[Bone], m: &Manifold, c: &ContactPoint, pa: Vec3A, pb: Vec3A) -> Vec3A {
    let sub = bones[m.a()].displacement(c.ra) - side_displacement(bones, m.b(), c.rb);
    let (d, n) = (pa - pb - sub, m.n());
    d - n * d.dot(n)
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
/// spent, `None` when it moved nothing. `at` is the point's two material points in the
/// world, `(pa, pb)`, when the caller has just read them from the bones as they stand
/// (the same bits as reading them here).
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
    at: Option<(Vec3A, Vec3A)>,
) -> Option<f32> {
    // Nothing to spend (a manifold not pressed yet, or its cone used up): return before
    // measuring the slip, four rotations of the contact's arms.
    let allowed = m.mu() * group_n - group_t;
    if allowed <= 0.0 {
        return None;
    }
    let a = Some(m.a());
    let (pa, pb) = at.unwrap_or_else(|| (bones[m.a()].world(c.ra), side_world(bones, m.b(), c.rb)));
    let n = m.n();
    let tangential = |d: Vec3A| d - n * d.dot(n);
    // The substep's slip, and the drift since the points came into touch:
    // `pa − pb = touched_at + drift + substep slip` along the tangent.
    let sub = tangential(bones[m.a()].displacement(c.ra) - side_displacement(bones, m.b(), c.rb));
    // A point not pressed itself (its manifold is) has not drifted.
    let drift = c
        .touched_at()
        .map_or(Vec3A::ZERO, |t| tangential(pa - pb) - sub - Vec3A::from(t));
    // Corrections move pa − pb against the slip `d`, along `−d` itself (not normalised:
    // `Correction::along_scaled`, whose `w` is `|d|²` times the unit direction's).
    let against = |d: Vec3A, d2: f32| Correction::along_scaled(bones, (a, pa), (m.b(), pb), -d, d2);
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
        return None;
    }
    // λ = |correction| / w_unit, the correction being the slip or as much as the cone
    // allows: per unit of the slip vector, `len / (len w_unit) = len² / W`, or
    // `allowed / len`.
    let mu = (len2 / corr.w).min(allowed / len);
    corr.apply(bones, mu);
    let lt = mu * len;
    c.lambda_tv += lt;
    Some(lt)
}

/// Radius of the contact patch a point contact stands for (m): the lever arm of its
/// torsional friction. A box resting on one corner otherwise spins about the normal
/// without losing energy, since a point cannot resist twist.
const PATCH_RADIUS: f32 = 0.01;

/// Normal velocity a contact point leaves with: restitution on its relative normal
/// velocity before the substep's solve, `vn_before` (m/s, > 0 approaching; above the
/// threshold), never more; zero otherwise.
fn velocity_target(m: &Manifold, vn_before: f32, restitution_threshold: f32) -> f32 {
    if vn_before > restitution_threshold {
        -m.e * vn_before
    } else {
        0.0
    }
}

/// Point `i`'s relative normal velocity before the substep's solve, of a manifold's
/// `approach` ([`solve_velocities`]): 0 where none was measured (`e = 0`, whose target
/// is zero whatever the approach).
fn approach_of(approach: &[f32], i: usize) -> f32 {
    approach.get(i).copied().unwrap_or(0.0)
}

/// Velocity pass for one manifold: the normal velocity of each point that pressed this
/// substep brought to its target ([`velocity_target`]) by impulses solved as one block
/// ([`Block::solve`], for the reason [`solve_normals`] gives), then each point's
/// torsional friction. Accumulates each point's `λ_v` (`ContactPoint::lambda_tv`) over
/// the velocity passes. `approach` holds each point's relative normal velocity before
/// the substep's solve (m/s, > 0 approaching) for restitution, measured only on
/// manifolds that bounce (`rigid_frames::run_substeps`); empty, it reads as zero.
///
/// A contact only pushes: over the substep, the position pass's impulse `λ_n / h` and
/// the velocity pass's `λ_v` sum to at least zero at each point. The velocity pass may
/// so take back the velocity the position pass's push made (a push-out of an overlap,
/// a corner pushed up harder than the rest of its face) but never pull the shapes
/// together beyond it: the complementarity problem `λ_v ≥ −λ_n / h`, `v_n ≤ target`,
/// one an equality, by projected Gauss–Seidel over the accumulated `λ_v` (a later
/// velocity pass starts from the earlier passes' impulses and may only change them
/// within the bound).
/// Unbounded, two points of a manifold a few centimetres apart (a forearm lying on the
/// ground) have a nearly singular `K`, and the block met their targets with a large push
/// at one and a large pull at the other: a couple that turned the resting limb at
/// 0.1–0.25 rad/s and kept piles awake.
pub(crate) fn solve_velocities(
    bones: &mut [Bone],
    m: &Manifold,
    points: &mut [ContactPoint],
    approach: &[f32],
    h: f32,
    restitution_threshold: f32,
) {
    let mut active = [0usize; BLOCK];
    let mut k = 0;
    for (i, c) in points.iter().enumerate() {
        if c.lambda_n > 0.0 {
            if k == BLOCK {
                k = BLOCK + 1;
                break;
            }
            active[k] = i;
            k += 1;
        }
    }
    // The twist's levers, formed at the first point that twists: they read the bones'
    // frames and inertia, which the velocity pass does not change.
    let mut turn = None;
    if k <= 1 || k > BLOCK {
        for (i, c) in points.iter_mut().enumerate() {
            if c.lambda_n > 0.0 {
                let target = velocity_target(m, approach_of(approach, i), restitution_threshold);
                solve_velocity(bones, m, c, target, h, &mut turn);
            }
        }
        return;
    }
    let (mut pa, mut pb) = ([Vec3A::ZERO; BLOCK], [Vec3A::ZERO; BLOCK]);
    let (mut excess, mut lower) = ([0.0; BLOCK], [0.0; BLOCK]);
    let n = m.n();
    for (slot, &i) in active[..k].iter().enumerate() {
        let c = &points[i];
        pa[slot] = bones[m.a()].world(c.ra);
        pb[slot] = side_world(bones, m.b(), c.rb);
        let v =
            point_velocity(bones, Some(m.a()), pa[slot]) - point_velocity(bones, m.b(), pb[slot]);
        let target = velocity_target(m, approach_of(approach, i), restitution_threshold);
        excess[slot] = v.dot(n) - target;
        lower[slot] = -c.lambda_n / h - c.lambda_tv;
    }
    let block = Block::new(bones, m, &pa[..k], &pb[..k]);
    let lambda = block.solve(&excess[..k], &lower[..k]);
    if let Some(s) = &block.a {
        s.apply_velocity(bones, -n, &lambda[..k]);
    }
    if let Some(s) = &block.b {
        s.apply_velocity(bones, n, &lambda[..k]);
    }
    for (&i, l) in active[..k].iter().zip(lambda) {
        points[i].lambda_tv += l;
        solve_twist(bones, m, &points[i], h, &mut turn);
    }
}

/// Velocity pass for one contact that was active this substep (`λ_n > 0`), on its own:
/// its normal velocity brought to its `target` ([`velocity_target`]) by an impulse
/// bounded as [`solve_velocities`] bounds a block's, `λ_v ≥ −λ_n / h` accumulated.
fn solve_velocity(
    bones: &mut [Bone],
    m: &Manifold,
    c: &mut ContactPoint,
    target: f32,
    h: f32,
    turn: &mut Option<Correction>,
) {
    let (a, n) = (Some(m.a()), m.n());
    let pa = bones[m.a()].world(c.ra);
    let pb = side_world(bones, m.b(), c.rb);
    let v = point_velocity(bones, a, pa) - point_velocity(bones, m.b(), pb);
    let excess = v.dot(n) - target;
    let corr = Correction::along(bones, (a, pa), (m.b(), pb), n);
    if corr.w > 0.0 {
        // The push `λ_v` (along `−n`) that meets the target, within the bound.
        let push = (excess / corr.w).max(-c.lambda_n / h - c.lambda_tv);
        corr.apply_velocity(bones, -push);
        c.lambda_tv += push;
    }
    solve_twist(bones, m, c, h, turn);
}

/// Torsional friction of one contact point: twist about the normal, capped by
/// `μ r λ_n / h` ([`PATCH_RADIUS`]). `turn` holds the manifold's turning levers
/// ([`Correction::turning`]) once a point has formed them: the same for each of its
/// points while only velocities change.
fn solve_twist(
    bones: &mut [Bone],
    m: &Manifold,
    c: &ContactPoint,
    h: f32,
    turn: &mut Option<Correction>,
) {
    let (a, n) = (Some(m.a()), m.n());
    let twist = |bones: &[Bone], s: Side| match s {
        Some(i) if !bones[i].is_static() => bones[i].ang_vel.dot(n),
        _ => 0.0,
    };
    let spin = twist(bones, a) - twist(bones, m.b());
    if spin != 0.0 {
        // Both levers `I⁻¹ n` formed once, for the inverse mass and the impulse.
        let turn = *turn.get_or_insert_with(|| Correction::turning(bones, a, m.b(), n));
        if turn.w > 0.0 {
            let cap = m.mu() * PATCH_RADIUS * c.lambda_n / h;
            let l = spin.signum() * (spin.abs() / turn.w).min(cap);
            turn.apply_velocity(bones, -l);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sweep as written over plain arrays: `Σ_j K_ij λ_j` by `Iterator::sum`.
    fn scalar_solve(block: &Block, rhs: &[f32], lower: &[f32]) -> [f32; BLOCK] {
        let k = block.k;
        let mut lambda = [0.0f32; BLOCK];
        for _ in 0..BLOCK_SWEEPS {
            let mut change = 0.0f32;
            for i in 0..k {
                let kii = block.matrix[i][i];
                if kii <= 0.0 {
                    continue;
                }
                let moved: f32 = (0..k).map(|j| block.matrix[i][j] * lambda[j]).sum();
                let next = (lambda[i] + (rhs[i] - moved) / kii).max(lower[i]);
                change = change.max((next - lambda[i]).abs() * kii);
                lambda[i] = next;
            }
            if change <= BLOCK_TOLERANCE {
                break;
            }
        }
        lambda
    }

    /// The block sweep in SIMD lanes gives the scalar sweep's bits, block sizes 1 to
    /// [`BLOCK`], on contact matrices `K_ij = 1/M + (r_i × n) · I⁻¹ (r_j × n)` of random
    /// points, targets and bounds (some negative, as the velocity pass's), including
    /// a zero multiplier's sign.
    #[test]
    fn lane_sweep_is_the_scalar_sweep_bit_for_bit() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let n = Vec3A::Y;
        for trial in 0..2000 {
            let k = 1 + trial % BLOCK;
            let inv_mass = 0.5 + uniform().abs() * 4.0;
            let inv_inertia = Vec3A::new(
                1.0 + uniform().abs() * 30.0,
                1.0 + uniform().abs() * 30.0,
                1.0 + uniform().abs() * 30.0,
            );
            let arms: Vec<Vec3A> = (0..k)
                .map(|_| Vec3A::new(uniform(), uniform() * 0.1, uniform()) * 0.3)
                .collect();
            let mut matrix = [[0.0f32; BLOCK]; BLOCK];
            for i in 0..k {
                for j in 0..k {
                    let (ai, aj) = (arms[i].cross(n), arms[j].cross(n));
                    matrix[i][j] = inv_mass + ai.dot(inv_inertia * aj);
                }
            }
            let block = Block {
                k,
                a: None,
                b: None,
                matrix,
            };
            let rhs: Vec<f32> = (0..k).map(|_| uniform() * 1e-3).collect();
            let lower: Vec<f32> = (0..k)
                .map(|_| {
                    if trial % 3 == 0 {
                        uniform().min(0.0)
                    } else {
                        0.0
                    }
                })
                .collect();
            let lanes = block.solve(&rhs, &lower).map(f32::to_bits);
            let scalar = scalar_solve(&block, &rhs, &lower).map(f32::to_bits);
            assert_eq!(lanes, scalar, "block of {k} points, trial {trial}");
        }
    }
}
