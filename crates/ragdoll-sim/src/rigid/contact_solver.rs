//! The contact solve of one step over dense constraint arrays (Box2D v3's
//! `contact_solver.c`, in 3D).
//!
//! [`super::contact`] keeps what must survive between steps — parry's manifold and, per
//! point, its body-space anchors and accumulated impulses. At the start of a step's
//! solve, [`ContactConstraints::build`] turns every touching pair into a
//! `PairConstraint` and its points into `PointConstraint`s laid out one after the
//! other, with everything the iterations only read computed once:
//!
//! - the Jacobian's angular parts `r × n`, `r × t₁`, `r × t₂` (anchors fixed for the
//!   step, as Box2D fixes them), and the effective masses `1 / (J M⁻¹ Jᵀ)`;
//! - per substep ([`ContactConstraints::prepare_substep`], after the world inverse
//!   inertias were refreshed): `I⁻¹ (r × d)` for each row and the separation the biased
//!   iterations share (in the rows of [`super::contact_rows`]).
//!
//! An iteration then reads a row's velocity as `d·(v_b − v_a) + (r_b × d)·ω_b −
//! (r_a × d)·ω_a` and applies an impulse λ as `v ± d λ/m`, `ω ± I⁻¹(r × d) λ`: dot
//! products and scaled additions, no cross product and no 3×3 product in the loop that
//! runs most often (forming them in every iteration would multiply its cost). The
//! arrays are filled anew for every solve (one island on one thread) and kept for the
//! next, so a step allocates nothing once they have grown;
//! [`ContactConstraints::store_impulses`] writes the impulses back to
//! the pairs for the next step's warm start.
//!
//! The rows themselves are [`super::contact_rows`], written once over the lane type:
//! most pairs are solved four at a time (graph colouring, SIMD lanes), the rest one by
//! one, first, in the pairs' order, each pair's points in order. The restitution pass
//! and the position projection run here, over all pairs in order.

use super::body::BodyStates;
use super::contact::{ContactPair, LINEAR_SLOP};
use super::contact_rows::{self, ContactLanes, SLOTS};
use super::project::{CONTACT_CORRECTION, MAX_LINEAR_CORRECTION, POSITION_ITERATIONS};
use super::soft::StepContext;
use crate::lanes::LANES;
use glam::{Vec3, Vec3A};
use wide::f32x4;

/// What bounds the contact projection's push-out in one step (see
/// [`ContactConstraints::project`]).
#[derive(Clone, Copy, Debug)]
pub struct PushOutBudget {
    /// `Settings::max_push_out_speed` (m/s).
    pub max_speed: f32,
    /// The soft contact's bias rate (1/s) the substeps pushed out with.
    pub bias_rate: f32,
    /// The step's length (s).
    pub dt: f32,
}

/// One touching pair's share of the step.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PairConstraint {
    /// Body a (index into the solved states).
    pub(super) a: usize,
    /// Body b, or the static anchor.
    pub(super) b: usize,
    /// Slot of the pair in the array the constraints were built from.
    pub(super) slot: usize,
    /// The pair's points: `points[start..start + count]`.
    pub(super) start: usize,
    pub(super) count: usize,
    /// Normal from a to b (world, fixed for the step).
    pub(super) normal: Vec3,
    /// The friction rows' directions: an orthonormal pair across the normal.
    pub(super) tangents: [Vec3; 2],
    /// Inverse masses as the solver sees them (zero when static or asleep).
    pub(super) inv_mass_a: f32,
    pub(super) inv_mass_b: f32,
    /// Combined Coulomb coefficient.
    pub(super) friction: f32,
    /// Combined restitution.
    pub(super) restitution: f32,
    /// `ρ r` (see [`crate::scene::ROLLING_RESISTANCE`]); zero when neither body rolls.
    pub(super) rolling_arm: f32,
    /// Accumulated rolling-resistance angular impulse on b.
    pub(super) rolling_impulse: Vec3,
}

/// One contact point's rows: non-penetration along the normal, friction along the two
/// tangents.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PointConstraint {
    /// Anchors in the bodies' frames, relative to their centres of mass.
    pub(super) local_a: Vec3,
    pub(super) local_b: Vec3,
    /// `s₀ − n·(p_b − p_a)` at build time: the separation now is this plus
    /// `n·(p_b − p_a)` for the anchors' current world positions.
    pub(super) base_separation: f32,
    /// Separation when the step's constraints were built (negative: overlap).
    pub(super) start_separation: f32,
    /// `r_a × n`, `r_b × n`.
    pub(super) ja_n: Vec3,
    pub(super) jb_n: Vec3,
    /// `r_a × t_k`, `r_b × t_k`.
    pub(super) ja_t: [Vec3; 2],
    pub(super) jb_t: [Vec3; 2],
    /// `1 / (n·K·n)`, with the inertia at the start of the step.
    pub(super) normal_mass: f32,
    /// Effective masses of the two tangent rows.
    pub(super) tangent_mass: [f32; 2],
    /// Accumulated normal impulse.
    pub(super) normal_impulse: f32,
    /// Accumulated friction impulse along each tangent.
    pub(super) tangent_impulse: [f32; 2],
    /// Largest normal impulse applied this step (restitution only bounces real contacts).
    pub(super) max_normal_impulse: f32,
    /// Normal velocity at build time (negative = approaching).
    pub(super) relative_velocity: f32,
}

/// A row's velocity `d·(v_b − v_a) + (r_b × d)·ω_b − (r_a × d)·ω_a`, given `dv = v_b − v_a`.
#[inline]
fn row_velocity(d: Vec3, dv: Vec3, ja: Vec3, jb: Vec3, wa: Vec3, wb: Vec3) -> f32 {
    d.dot(dv) + jb.dot(wb) - ja.dot(wa)
}

/// `1/x`, or zero for a row no body can move.
#[inline]
fn inverse_or_zero(x: f32) -> f32 {
    if x > 1e-20 { 1.0 / x } else { 0.0 }
}

/// The contact constraints of one solve (the whole world, or one island).
#[derive(Default)]
pub struct ContactConstraints {
    pairs: Vec<PairConstraint>,
    points: Vec<PointConstraint>,
    /// The pairs solved one by one, first, in array order (see [`super::contact_rows`]).
    single: ContactLanes<f32>,
    /// The other pairs, four at a time, colour by colour.
    bundles: ContactLanes<f32x4>,
}

impl ContactConstraints {
    /// Constraints for the touching pairs of `pairs` with at least one awake body, from
    /// the bodies' poses, velocities and inverse inertias now (call after
    /// `update_inertia`, before the substeps), in place of the last step's: the arrays
    /// keep their capacity, so a step allocates nothing once they have grown. Impulses
    /// carried by the pairs warm start.
    pub fn rebuild(&mut self, pairs: &[ContactPair], s: &BodyStates, awake: &[bool]) {
        let active =
            |p: &&ContactPair| p.touching() && (awake[p.a as usize] || awake[p.b as usize]);
        debug_assert!(
            self.single.is_empty() && self.bundles.is_empty(),
            "end_substeps not called"
        );
        let out = self;
        out.pairs.clear();
        out.points.clear();
        for (slot, pair) in pairs.iter().enumerate() {
            if !active(&pair) {
                continue;
            }
            let (a, b) = (pair.a as usize, pair.b as usize);
            let normal = pair.normal(s.rot[a]);
            let dv = Vec3::from(s.lin_vel[b] - s.lin_vel[a]);
            // The relative velocity at the manifold's centre, where the bodies slide.
            let (mut ra_sum, mut rb_sum, mut points) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
            for (c, _) in pair.contact_points() {
                ra_sum += s.rot[a] * c.local_a;
                rb_sum += s.rot[b] * c.local_b;
                points += 1.0;
            }
            let slip = if points > 0.0 {
                dv + Vec3::from(s.ang_vel[b]).cross(rb_sum / points)
                    - Vec3::from(s.ang_vel[a]).cross(ra_sum / points)
            } else {
                dv
            };
            let tangents = friction_tangents(normal, slip);
            let (ma, mb) = (s.inv_mass[a], s.inv_mass[b]);
            let (ia, ib) = (s.inv_inertia[a], s.inv_inertia[b]);
            let mass =
                |ja: Vec3, jb: Vec3| inverse_or_zero(ma + mb + ja.dot(ia * ja) + jb.dot(ib * jb));
            let start = out.points.len();
            for (c, separation) in pair.contact_points() {
                let ra = s.rot[a] * c.local_a;
                let rb = s.rot[b] * c.local_b;
                let (ja_n, jb_n) = (ra.cross(normal), rb.cross(normal));
                let ja_t = tangents.map(|t| ra.cross(t));
                let jb_t = tangents.map(|t| rb.cross(t));
                out.points.push(PointConstraint {
                    local_a: c.local_a,
                    local_b: c.local_b,
                    base_separation: separation - normal.dot((s.com[b] + rb) - (s.com[a] + ra)),
                    start_separation: separation,
                    ja_n,
                    jb_n,
                    ja_t,
                    jb_t,
                    normal_mass: mass(ja_n, jb_n),
                    tangent_mass: [mass(ja_t[0], jb_t[0]), mass(ja_t[1], jb_t[1])],
                    // The friction impulse is kept as a world vector between steps (the
                    // basis follows the normal); its part across the new normal carries over.
                    normal_impulse: c.normal_impulse,
                    tangent_impulse: tangents.map(|t| t.dot(c.tangent_impulse)),
                    relative_velocity: row_velocity(
                        normal,
                        dv,
                        ja_n,
                        jb_n,
                        Vec3::from(s.ang_vel[a]),
                        Vec3::from(s.ang_vel[b]),
                    ),
                    ..Default::default()
                });
            }
            out.pairs.push(PairConstraint {
                a,
                b,
                slot,
                start,
                count: out.points.len() - start,
                normal,
                tangents,
                inv_mass_a: ma,
                inv_mass_b: mb,
                friction: pair.friction,
                restitution: pair.restitution,
                rolling_arm: pair.rolling_arm,
                rolling_impulse: pair.rolling_impulse,
            });
        }
        out.bundle(s.len());
    }

    /// Colours the pairs and loads the groups of four and the pairs solved one by one
    /// (see [`super::contact_rows`]). Rolling pairs (their resistance is a row of the
    /// whole pair) and pairs with more points than a group has room for are solved one
    /// by one.
    fn bundle(&mut self, bodies: usize) {
        let moving = |i: usize, inv_mass: f32| (inv_mass > 0.0).then_some(i);
        let (colors, single) = contact_rows::color(
            bodies,
            self.pairs.iter().map(|p| {
                (
                    moving(p.a, p.inv_mass_a),
                    moving(p.b, p.inv_mass_b),
                    p.count <= SLOTS && p.rolling_arm == 0.0,
                )
            }),
        );
        for &i in &single {
            let i = i as usize;
            self.single.load(&[i], &[&self.pairs[i]], &self.points);
        }
        for color in &colors {
            for chunk in color.chunks(LANES) {
                let index: [usize; LANES] =
                    std::array::from_fn(|k| chunk.get(k).map_or(0, |&i| i as usize));
                let lanes: [&PairConstraint; LANES] = index.map(|i| &self.pairs[i]);
                let n = chunk.len();
                self.bundles.load(&index[..n], &lanes[..n], &self.points);
            }
        }
    }

    /// Writes the accumulated impulses back to the pairs the constraints were built from,
    /// for the next step's warm start (the friction impulse as a world vector).
    pub fn store_impulses(&self, pairs: &mut [ContactPair]) {
        debug_assert!(
            self.single.is_empty() && self.bundles.is_empty(),
            "end_substeps not called"
        );
        for pc in &self.pairs {
            let pair = &mut pairs[pc.slot];
            pair.rolling_impulse = pc.rolling_impulse;
            let points = &self.points[pc.start..pc.start + pc.count];
            for (c, p) in pair.contact_points_mut().zip(points) {
                c.normal_impulse = p.normal_impulse;
                c.tangent_impulse =
                    pc.tangents[0] * p.tangent_impulse[0] + pc.tangents[1] * p.tangent_impulse[1];
            }
        }
    }

    /// Per substep, once the world inverse inertias are refreshed: each row's
    /// `I⁻¹ (r × d)`, the rolling mass, and the separation the biased iterations share
    /// (between the velocity and the position integration the bodies do not move).
    pub fn prepare_substep(&mut self, s: &BodyStates) {
        self.single.refresh(s, true);
        self.bundles.refresh(s, true);
    }

    /// After the substeps: the groups hand their impulses back to the points, which the
    /// restitution pass, the projection and [`ContactConstraints::store_impulses`] read.
    pub fn end_substeps(&mut self) {
        self.single.write_back(&mut self.points, &mut self.pairs);
        self.bundles.write_back(&mut self.points, &mut self.pairs);
    }

    /// Re-applies the accumulated impulses (last substep's, or last step's carried over).
    pub fn warm_start(&self, s: &mut BodyStates) {
        self.single.warm_start(s);
        self.bundles.warm_start(s);
    }

    /// One Gauss–Seidel pass over the pairs solved one by one, then the groups of four
    /// ([`ContactLanes::solve`]). The biased pass reads the separations of
    /// [`ContactConstraints::prepare_substep`]; the relax pass, after the positions
    /// moved, evaluates them anew first.
    pub fn solve(&mut self, s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        if !use_bias {
            // The relax pass comes after the positions moved. The velocity solve does not
            // move them, so every point's separation is evaluated once, up front.
            self.single.refresh(s, false);
            self.bundles.refresh(s, false);
        }
        self.single.solve(s, ctx, use_bias);
        self.bundles.solve(s, ctx, use_bias);
    }

    /// Box2D's restitution pass, after the substeps: points that were approaching faster
    /// than `threshold` and carried load get the normal velocity `−e · v_before`.
    /// Block-free Gauss–Seidel over a face's points: one pass under-shoots, so the pass
    /// is run a few times (the clamp keeps it from over-shooting).
    pub fn restitution(&mut self, s: &mut BodyStates, threshold: f32) {
        for _ in 0..4 {
            for pc in &self.pairs {
                if pc.restitution == 0.0 {
                    continue;
                }
                let (a, b) = (pc.a, pc.b);
                for p in &mut self.points[pc.start..pc.start + pc.count] {
                    if p.relative_velocity > -threshold || p.max_normal_impulse == 0.0 {
                        continue;
                    }
                    let vn = row_velocity(
                        pc.normal,
                        Vec3::from(s.lin_vel[b] - s.lin_vel[a]),
                        p.ja_n,
                        p.jb_n,
                        Vec3::from(s.ang_vel[a]),
                        Vec3::from(s.ang_vel[b]),
                    );
                    let l = -p.normal_mass * (vn + pc.restitution * p.relative_velocity);
                    let new = (p.normal_impulse + l).max(0.0);
                    let d = new - p.normal_impulse;
                    p.normal_impulse = new;
                    s.lin_vel[a] -= Vec3A::from(pc.normal * (d * pc.inv_mass_a));
                    s.lin_vel[b] += Vec3A::from(pc.normal * (d * pc.inv_mass_b));
                    // The last substep's inertias, still in place (a bundled point's
                    // `I⁻¹ J` lives in its bundle).
                    s.ang_vel[a] -= Vec3A::from((s.inv_inertia[a] * p.ja_n) * d);
                    s.ang_vel[b] += Vec3A::from((s.inv_inertia[b] * p.jb_n) * d);
                }
            }
        }
    }

    /// Sets `touching[i]` for both bodies of every pair of this solve.
    pub fn mark_touching(&self, touching: &mut [bool]) {
        for pc in &self.pairs {
            for i in [pc.a, pc.b] {
                if let Some(t) = touching.get_mut(i) {
                    *t = true;
                }
            }
        }
    }

    /// One position-projection pass (see [`super::project`]): each point deeper than
    /// [`LINEAR_SLOP`] is pushed apart along its normal by a fraction of its depth,
    /// `P = −K⁻¹ C` with `C = β (s + slop)` clamped to `[−MAX_LINEAR_CORRECTION, 0]`
    /// (Box2D v2.4's `b2ContactSolver::SolvePositionConstraints`). The Jacobian is
    /// formed anew on the moved pose, with the inverse masses the projection holds
    /// (`s`, where resting bodies count as static).
    ///
    /// Together with the velocity solve, a point is pushed out no faster than
    /// `max_push_out_speed`: the biased iterations already pushed it at
    /// `v = min(bias_rate · depth₀, max)` this step (depth₀ at the step's start; the
    /// depth only shrinks while it is pushed out), so the projection may move it by at
    /// most `(max − v) dt` in all, a share of that per iteration. A body that starts
    /// 25 cm in the ground rose at 10 m/s through the projection alone.
    pub fn project(&self, s: &mut BodyStates, push: &PushOutBudget) {
        let per_iteration = push.dt / POSITION_ITERATIONS as f32;
        for pc in &self.pairs {
            let (a, b) = (pc.a, pc.b);
            // Both bodies held still (see `JointSet::project`): nothing can move.
            if !(s.is_mobile(a) || s.is_mobile(b)) {
                continue;
            }
            let n = pc.normal;
            for p in &self.points[pc.start..pc.start + pc.count] {
                let sep = current_separation(pc, p, s);
                let pushed = (-push.bias_rate * p.start_separation).clamp(0.0, push.max_speed);
                let room = ((push.max_speed - pushed) * per_iteration).min(MAX_LINEAR_CORRECTION);
                let c = (CONTACT_CORRECTION * (sep + LINEAR_SLOP)).clamp(-room, 0.0);
                if c == 0.0 {
                    continue;
                }
                let (ra, rb) = (s.rot[a] * p.local_a, s.rot[b] * p.local_b);
                let (ja, jb) = (ra.cross(n), rb.cross(n));
                let k = s.inv_mass[a]
                    + s.inv_mass[b]
                    + ja.dot(s.inv_inertia[a] * ja)
                    + jb.dot(s.inv_inertia[b] * jb);
                if k <= 1e-20 {
                    continue;
                }
                let impulse = n * (-c / k);
                s.apply_position_impulse(a, ra, -impulse);
                s.apply_position_impulse(b, rb, impulse);
            }
        }
    }
}

/// Sliding speed (m/s) above which the first friction row follows the sliding direction:
/// twice Doom 3's default `suspendSpeed`. Slower, the contact is sticking or about to,
/// the slip direction is noise, and a basis turning with it every step kept resting
/// figures (the human's feet) from settling.
const SLIDING_SPEED: f32 = 0.1;

/// The friction rows' directions across `normal`: the first along the relative sliding
/// velocity `slip` at the contact when the bodies slide, else any pair.
///
/// Each row has its own effective mass, so a disk-clamped impulse `(−m₀v₀, −m₁v₁)` is
/// not opposite the sliding velocity unless one row carries all of it: with an
/// arbitrary basis, a box sliding down a slope is held by less than μ λₙ along its path
/// (it slid 13 % too far at 35°) and pushed sideways at its corners, turning about the
/// normal. With the first row along the slide, Coulomb's maximal dissipation holds: the
/// friction at each point is −μ λₙ along the slide.
fn friction_tangents(normal: Vec3, dv: Vec3) -> [Vec3; 2] {
    let slide = dv - normal * normal.dot(dv);
    let speed = slide.length();
    if speed > SLIDING_SPEED {
        let t0 = slide / speed;
        [t0, normal.cross(t0)]
    } else {
        let (t0, t1) = normal.any_orthonormal_pair();
        [t0, t1]
    }
}

/// Separation of a point now, from its anchors' current world positions.
#[inline]
fn current_separation(pc: &PairConstraint, p: &PointConstraint, s: &BodyStates) -> f32 {
    let pa = s.com[pc.a] + s.rot[pc.a] * p.local_a;
    let pb = s.com[pc.b] + s.rot[pc.b] * p.local_b;
    p.base_separation + pc.normal.dot(pb - pa)
}
