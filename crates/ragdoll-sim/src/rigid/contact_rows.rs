//! The contact rows of a step, written once over a lane type (`R = f32`: one pair;
//! `R = f32x4`: four pairs side by side), and the graph colouring that deals pairs into
//! groups of four (Box2D v3's `contact_solver.c` and `constraint_graph.c`, in 3D).
//!
//! Gauss–Seidel solves one constraint after another because each reads the velocities
//! the previous ones wrote. Two pairs that share no moving body do not read each other's
//! writes, so they can be solved at once. [`color`] deals the step's pairs into colours
//! in which no moving body appears twice (static and sleeping bodies are never written,
//! so they may appear in every pair of a colour: the ground does), and each colour is
//! cut into groups of four pairs, one per lane of an `f32x4`. The pairs no colour could
//! take (a body in more than [`COLORS`] pairs), the rolling pairs and the pairs with more
//! than [`SLOTS`] points are solved one by one first, then the colours in turn.
//!
//! Both are the same code, [`PairRows`], instantiated twice: every operation is lane by
//! lane ([`crate::lanes`]), so a pair gets the same bits whether it is solved alone or
//! in any lane of a group, and the order the pairs are solved in is all the lane width
//! changes. Every order is deterministic: the colouring is a greedy pass over the pairs
//! in their array order.
//!
//! A group holds its pairs' accumulated impulses during the substeps; they are written
//! back to the step's points once the substeps are done ([`ContactLanes::write_back`]).

use super::body::BodyStates;
use super::contact_solver::{PairConstraint, PointConstraint};
use super::soft::StepContext;
use crate::lanes::{LANES, M3, Q, Real, V3};
use glam::{Mat3, Vec3, Vec3A};

/// Points per pair a group of four has room for (a box face on a face or on the ground
/// has 4); a pair with more is solved alone.
pub const SLOTS: usize = 4;
/// Colours tried before a pair is left to the one-by-one solve. A body of a pile touches
/// up to about a dozen others.
pub const COLORS: usize = 16;
/// Largest change (m/s) of any of a pair's normal row velocities over a sweep of its
/// points at which [`PairRows::solve_normals`] holds the pair's block solved: a spin
/// error of the order of `tolerance / lever` (a millirad per second on a 20 cm face),
/// and some 25 ulp of an f32 velocity of 50 m/s, so rounding does not keep it sweeping.
const BLOCK_TOLERANCE: f32 = 1e-4;
/// Sweeps [`PairRows::solve_normals`] makes at most. In the pile of 100 humans 91 % of
/// the pair solves stop after one sweep, under 0.01 % reach this cap.
const BLOCK_SWEEPS: usize = 32;

/// One point's rows in each lane: non-penetration along the normal, friction along the
/// two tangents (see [`PointConstraint`] for each field's meaning). What the block
/// solve's sweeps read comes first, so a sweep, made two or three times per pass, reads
/// the leading cache lines of each row; the friction rows follow. What only
/// [`ContactLanes::refresh`] reads is apart, in [`PointAnchors`].
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PointRows<R> {
    /// `r_a × n`, `r_b × n`.
    ja_n: V3<R>,
    jb_n: V3<R>,
    /// `I_a⁻¹ (r_a × n)`, `I_b⁻¹ (r_b × n)` with the substep's inertia.
    ia_n: V3<R>,
    ib_n: V3<R>,
    /// The normal row of the pass (see [`PairRows::solve_normals`]): `−normal_mass ·
    /// mass_scale`, the bias velocity and the impulse scale, from the separation at the
    /// last [`ContactLanes::refresh`] ([`ContactLanes::weigh_normals`]).
    mass: R,
    bias: R,
    impulse_scale: R,
    /// `1 / normal_mass` (zero for an empty slot): the row velocity an impulse changes.
    normal_stiffness: R,
    /// The row's normal velocity when the block solve last reached it.
    block_velocity: R,
    normal_impulse: R,
    /// `r_a × t_k`, `r_b × t_k`.
    ja_t: [V3<R>; 2],
    jb_t: [V3<R>; 2],
    /// `I_a⁻¹ (r_a × t_k)`, `I_b⁻¹ (r_b × t_k)`, likewise.
    ia_t: [V3<R>; 2],
    ib_t: [V3<R>; 2],
    tangent_mass: [R; 2],
    tangent_impulse: [R; 2],
    max_normal_impulse: R,
}

/// The anchors in the bodies' frames and the separation at build time less
/// `n·(p_b − p_a)`, for the separation now, the separation and the normal row's
/// effective mass: per point, what only [`ContactLanes::refresh`] and
/// [`ContactLanes::weigh_normals`] read, kept out of the rows the passes stream through.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PointAnchors<R> {
    local_a: V3<R>,
    local_b: V3<R>,
    base_separation: R,
    /// Separation at the last [`ContactLanes::refresh`].
    separation: R,
    normal_mass: R,
}

/// `R::WIDTH` pairs (one, or four of one colour) solved side by side.
#[derive(Clone, Copy, Debug)]
pub(super) struct PairRows<R> {
    /// Each lane's pair (its index among the step's pairs), first point among the step's
    /// points, and number of points (0 for an empty lane).
    pair: [usize; LANES],
    start: [usize; LANES],
    count: [usize; LANES],
    /// Each lane's bodies (an empty lane repeats lane 0's and writes nothing).
    a: [usize; LANES],
    b: [usize; LANES],
    /// The group's point rows: `ContactLanes::rows[rows..rows + slots]`; slot `j` holds
    /// each lane's point `j`, zero masses and impulses where a lane has fewer.
    rows: usize,
    slots: usize,
    normal: V3<R>,
    tangents: [V3<R>; 2],
    inv_mass_a: R,
    inv_mass_b: R,
    friction: R,
    /// `ρ r` (see [`crate::scene::ROLLING_RESISTANCE`]); zero where the pair does not
    /// roll or both bodies are held.
    rolling_arm: R,
    /// Accumulated rolling-resistance angular impulse on b.
    rolling_impulse: V3<R>,
    /// `(I_a⁻¹ + I_b⁻¹)⁻¹` and the inverse inertias of the substep (rolling pairs only).
    rolling_mass: M3<R>,
    inv_inertia_a: M3<R>,
    inv_inertia_b: M3<R>,
}

/// The groups of one lane width and their point rows.
#[derive(Debug, Default)]
pub(super) struct ContactLanes<R> {
    groups: Vec<PairRows<R>>,
    rows: Vec<PointRows<R>>,
    /// Each row's anchors, at the row's index.
    anchors: Vec<PointAnchors<R>>,
    /// The pass whose normal rows the rows hold (`use_bias`), `None` after a
    /// [`ContactLanes::refresh`] ([`ContactLanes::weigh_normals`]).
    weighed_for: Option<bool>,
}

/// The velocities `v_a, ω_a, v_b, ω_b` of each lane's bodies.
type Velocities<R> = [V3<R>; 4];

impl<R: Real> ContactLanes<R> {
    /// Whether there is no group.
    pub(super) fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }

    /// Appends a group of 1 to `R::WIDTH` pairs (`lanes`, with their indices `index`
    /// among the step's pairs), each with at most [`SLOTS`] points when `R::WIDTH > 1`.
    pub(super) fn load(
        &mut self,
        index: &[usize],
        lanes: &[&PairConstraint],
        points: &[PointConstraint],
    ) {
        debug_assert!(!lanes.is_empty() && lanes.len() <= R::WIDTH);
        let lane = |k: usize| lanes.get(k).copied();
        let first = lanes[0];
        let or_zero = |k: usize, f: fn(&PairConstraint) -> f32| lane(k).map_or(0.0, f);
        let slots = lanes.iter().map(|p| p.count).max().unwrap_or(0);
        let group = PairRows {
            pair: std::array::from_fn(|k| index.get(k).copied().unwrap_or(0)),
            start: std::array::from_fn(|k| lane(k).map_or(0, |p| p.start)),
            count: std::array::from_fn(|k| lane(k).map_or(0, |p| p.count)),
            a: std::array::from_fn(|k| lane(k).unwrap_or(first).a),
            b: std::array::from_fn(|k| lane(k).unwrap_or(first).b),
            rows: self.rows.len(),
            slots,
            normal: V3::from_fn(|k| lane(k).map_or(Vec3::ZERO, |p| p.normal)),
            tangents: [0, 1]
                .map(|t| V3::from_fn(|k| lane(k).map_or(Vec3::ZERO, |p| p.tangents[t]))),
            inv_mass_a: R::from_fn(|k| or_zero(k, |p| p.inv_mass_a)),
            inv_mass_b: R::from_fn(|k| or_zero(k, |p| p.inv_mass_b)),
            friction: R::from_fn(|k| or_zero(k, |p| p.friction)),
            rolling_arm: R::from_fn(|k| or_zero(k, |p| p.rolling_arm)),
            rolling_impulse: V3::from_fn(|k| lane(k).map_or(Vec3::ZERO, |p| p.rolling_impulse)),
            rolling_mass: M3::default(),
            inv_inertia_a: M3::default(),
            inv_inertia_b: M3::default(),
        };
        let empty = PointConstraint::default();
        for j in 0..slots {
            let l: [&PointConstraint; LANES] = std::array::from_fn(|k| match lane(k) {
                Some(p) if j < p.count => &points[p.start + j],
                _ => &empty,
            });
            let v3 = |f: fn(&PointConstraint) -> Vec3| V3::from_fn(|k| f(l[k]));
            let s = |f: fn(&PointConstraint) -> f32| R::from_fn(|k| f(l[k]));
            self.rows.push(PointRows {
                ja_n: v3(|p| p.ja_n),
                jb_n: v3(|p| p.jb_n),
                ja_t: [v3(|p| p.ja_t[0]), v3(|p| p.ja_t[1])],
                jb_t: [v3(|p| p.jb_t[0]), v3(|p| p.jb_t[1])],
                normal_stiffness: s(|p| {
                    if p.normal_mass > 0.0 {
                        1.0 / p.normal_mass
                    } else {
                        0.0
                    }
                }),
                tangent_mass: [s(|p| p.tangent_mass[0]), s(|p| p.tangent_mass[1])],
                normal_impulse: s(|p| p.normal_impulse),
                tangent_impulse: [s(|p| p.tangent_impulse[0]), s(|p| p.tangent_impulse[1])],
                ..PointRows::default()
            });
            self.anchors.push(PointAnchors {
                local_a: v3(|p| p.local_a),
                local_b: v3(|p| p.local_b),
                base_separation: s(|p| p.base_separation),
                normal_mass: s(|p| p.normal_mass),
                ..PointAnchors::default()
            });
        }
        self.groups.push(group);
    }

    /// Forms each point's separation on the bodies' poses now and, with `inertia`, what
    /// changes every substep with the inertia: `I⁻¹ J` of every row and the rolling
    /// mass. Called at each substep's preparation, and before the relax pass
    /// (separations only: between the velocity and the position integration the bodies
    /// do not move).
    pub(super) fn refresh(&mut self, s: &BodyStates, inertia: bool) {
        self.weighed_for = None;
        for g in &mut self.groups {
            let (com_a, com_b) = (
                V3::<R>::from_fn(|k| s.com[g.a[k]]),
                V3::<R>::from_fn(|k| s.com[g.b[k]]),
            );
            let (rot_a, rot_b) = (
                Q::<R>::from_fn(|k| s.rot[g.a[k]]),
                Q::<R>::from_fn(|k| s.rot[g.b[k]]),
            );
            for c in &mut self.anchors[g.rows..g.rows + g.slots] {
                let pa = com_a + rot_a.rotate(c.local_a);
                let pb = com_b + rot_b.rotate(c.local_b);
                c.separation = c.base_separation + g.normal.dot(pb - pa);
            }
            let rows = &mut self.rows[g.rows..g.rows + g.slots];
            if !inertia {
                continue;
            }
            let ia = M3::<R>::from_fn(|k| Mat3::from(s.inv_inertia[g.a[k]]));
            let ib = M3::<R>::from_fn(|k| Mat3::from(s.inv_inertia[g.b[k]]));
            for w in rows.iter_mut() {
                w.ia_n = ia * w.ja_n;
                w.ib_n = ib * w.jb_n;
                w.ia_t = w.ja_t.map(|j| ia * j);
                w.ib_t = w.jb_t.map(|j| ib * j);
            }
            if R::any(g.rolling_arm.gt(R::ZERO)) {
                // Lanes that roll have a body that moves, so `I_a⁻¹ + I_b⁻¹` is
                // invertible but for a degenerate inertia; then the lane does not roll.
                let k = |l: usize| Mat3::from(s.inv_inertia[g.a[l]] + s.inv_inertia[g.b[l]]);
                let det = R::from_fn(|l| k(l).determinant().abs());
                g.rolling_arm = R::select(det.gt(R::splat(1e-20)), g.rolling_arm, R::ZERO);
                g.rolling_mass = M3::from_fn(|l| {
                    if g.rolling_arm.lane(l) > 0.0 {
                        k(l).inverse()
                    } else {
                        Mat3::ZERO
                    }
                });
                g.inv_inertia_a = ia;
                g.inv_inertia_b = ib;
            }
        }
    }

    /// Re-applies the accumulated impulses.
    pub(super) fn warm_start(&self, s: &mut BodyStates) {
        for g in &self.groups {
            let [mut va, mut wa, mut vb, mut wb] = g.gather(s);
            let [t0, t1] = g.tangents;
            for p in &self.rows[g.rows..g.rows + g.slots] {
                let [l0, l1] = p.tangent_impulse;
                let linear = g.normal * p.normal_impulse + t0 * l0 + t1 * l1;
                va -= linear * g.inv_mass_a;
                vb += linear * g.inv_mass_b;
                wa -= p.ia_n * p.normal_impulse + p.ia_t[0] * l0 + p.ia_t[1] * l1;
                wb += p.ib_n * p.normal_impulse + p.ib_t[0] * l0 + p.ib_t[1] * l1;
            }
            if R::any(g.rolling_arm.gt(R::ZERO)) {
                wa -= g.inv_inertia_a * g.rolling_impulse;
                wb += g.inv_inertia_b * g.rolling_impulse;
            }
            g.scatter(s, [va, wa, vb, wb]);
        }
    }

    /// Each point's normal row for the passes of `use_bias` until the next
    /// [`ContactLanes::refresh`], from its separation: speculative (the gap may close
    /// this substep, no further) or soft; its bias velocity, its mass `−normal_mass ·
    /// mass_scale` and its impulse scale. The biased iterations of a substep share one
    /// separation and so one row, formed once for them all.
    fn weigh_normals(&mut self, ctx: &StepContext, use_bias: bool) {
        let zero = R::ZERO;
        let one = R::ONE;
        let inv_h = R::splat(ctx.inv_h);
        let (bias_rate, push_out, soft_mass, soft_impulse) = if use_bias {
            (
                R::splat(ctx.contact.bias_rate),
                R::splat(-ctx.max_push_out),
                R::splat(ctx.contact.mass_scale),
                R::splat(ctx.contact.impulse_scale),
            )
        } else {
            (zero, zero, one, zero)
        };
        for (w, c) in self.rows.iter_mut().zip(&self.anchors) {
            let sep = c.separation;
            let speculative = sep.gt(zero);
            let soft_bias = (bias_rate * sep).max(push_out);
            w.bias = R::select(speculative, sep * inv_h, soft_bias);
            w.mass = -c.normal_mass * R::select(speculative, one, soft_mass);
            w.impulse_scale = R::select(speculative, zero, soft_impulse);
        }
        self.weighed_for = Some(use_bias);
    }

    /// One Gauss–Seidel pass over every group: the pair's soft non-penetration rows as
    /// one block ([`PairRows::solve_normals`]), then each point's friction capped by the
    /// normal impulse just computed (Box2D v3's order; friction first would cap it with
    /// a normal impulse the relax pass is about to raise, and slide too easily), then the
    /// pair's rolling resistance. The separations are those of the last
    /// [`ContactLanes::refresh`].
    pub(super) fn solve(&mut self, s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        if self.weighed_for != Some(use_bias) {
            self.weigh_normals(ctx, use_bias);
        }
        let zero = R::ZERO;
        let one = R::ONE;
        for g in &mut self.groups {
            let [mut va, mut wa, mut vb, mut wb] = g.gather(s);
            let rows = &mut self.rows[g.rows..g.rows + g.slots];
            g.solve_normals(rows, [&mut va, &mut wa, &mut vb, &mut wb]);
            let (ma, mb) = (g.inv_mass_a, g.inv_mass_b);
            let [t0, t1] = g.tangents;
            let mut total_normal = zero;
            for p in rows.iter_mut() {
                p.max_normal_impulse = p.max_normal_impulse.max(p.normal_impulse);
                total_normal += p.normal_impulse;
                // Coulomb friction: both tangent rows from the same velocity, the
                // impulse clamped to the disk of radius μλₙ.
                let dv = vb - va;
                let v0 = t0.dot(dv) + p.jb_t[0].dot(wb) - p.ja_t[0].dot(wa);
                let v1 = t1.dot(dv) + p.jb_t[1].dot(wb) - p.ja_t[1].dot(wa);
                let [o0, o1] = p.tangent_impulse;
                let n0 = o0 - p.tangent_mass[0] * v0;
                let n1 = o1 - p.tangent_mass[1] * v1;
                let cap = g.friction * p.normal_impulse;
                let len2 = n0 * n0 + n1 * n1;
                // Lanes within the cap keep their impulse (their 0/0 is never picked).
                let scale = R::select(len2.gt(cap * cap), cap / len2.sqrt(), one);
                let (n0, n1) = (n0 * scale, n1 * scale);
                p.tangent_impulse = [n0, n1];
                let (d0, d1) = (n0 - o0, n1 - o1);
                let linear = t0 * d0 + t1 * d1;
                va -= linear * ma;
                vb += linear * mb;
                wa -= p.ia_t[0] * d0 + p.ia_t[1] * d1;
                wb += p.ib_t[0] * d0 + p.ib_t[1] * d1;
            }
            // Rolling resistance: drive the relative angular velocity to zero with at
            // most ρ r Σλₙ of angular impulse (Box2D v3's rolling resistance, in 3D).
            if R::any(g.rolling_arm.gt(zero)) {
                let cap = g.rolling_arm * total_normal;
                let old = g.rolling_impulse;
                let free = old - g.rolling_mass * (wb - wa);
                let len2 = free.length_squared();
                let scale = R::select(len2.gt(cap * cap), cap / len2.sqrt(), one);
                let new = free * scale;
                g.rolling_impulse = new;
                wa -= g.inv_inertia_a * (new - old);
                wb += g.inv_inertia_b * (new - old);
            }
            g.scatter(s, [va, wa, vb, wb]);
        }
    }

    /// Writes the accumulated impulses back to the step's points and pairs, and empties
    /// the groups.
    pub(super) fn write_back(
        &mut self,
        points: &mut [PointConstraint],
        pairs: &mut [PairConstraint],
    ) {
        for g in &self.groups {
            for k in (0..R::WIDTH).filter(|&k| g.count[k] != 0) {
                let rows = &self.rows[g.rows..g.rows + g.count[k]];
                for (j, w) in rows.iter().enumerate() {
                    let p = &mut points[g.start[k] + j];
                    p.normal_impulse = w.normal_impulse.lane(k);
                    p.tangent_impulse = w.tangent_impulse.map(|t| t.lane(k));
                    p.max_normal_impulse = w.max_normal_impulse.lane(k);
                }
                pairs[g.pair[k]].rolling_impulse = g.rolling_impulse.lane(k);
            }
        }
        self.groups.clear();
        self.rows.clear();
        self.anchors.clear();
        self.weighed_for = None;
    }
}

impl<R: Real> PairRows<R> {
    /// The pair's normal rows solved as one block: the linear complementarity problem
    /// of its `k` points,
    ///
    /// `w = (K + Γ) λ + v_free + b`, `λ ≥ 0`, `w ≥ 0`, `λᵢ wᵢ = 0`,
    ///
    /// with `K = J M⁻¹ Jᵀ` the points' coupling through the two bodies, `b` each row's
    /// bias (a speculative row's `s/h`, a soft row's push-out), `Γ` the soft rows'
    /// compliance (`γᵢ = impulse_scale / (mass_scale · normal_massᵢ)`: a soft row's
    /// update `−mᵢ·mass_scale·(vᵢ + bᵢ) − impulse_scale·λᵢ` is the Gauss–Seidel step of
    /// this row, `−(vᵢ + bᵢ + γᵢλᵢ) / (Kᵢᵢ + γᵢ)`; a speculative or relax row has
    /// `γᵢ = 0`), `v_free` the row velocities without the pair's normal impulses. Solved
    /// by projected Gauss–Seidel on the pair alone, each point's accumulated impulse
    /// clamped at zero, sweep after sweep until no row's velocity moves by more than
    /// [`BLOCK_TOLERANCE`] over a sweep ([`BLOCK_SWEEPS`] at most). The sweeps apply each
    /// update to the pair's two bodies at once, so `K λ` is read off the velocities and
    /// never formed; each lane stops at its own tolerance (a pair gets the same bits
    /// alone as in a lane).
    ///
    /// One row at a time and once per iteration, Gauss–Seidel over a face's points
    /// converges slowly, and what it has not converged is an uneven spread of the
    /// impulse: a torque the contact does not exert. A cube hitting a wall face-on at
    /// 50 m/s came away spinning at 2.0 rad/s and sliding sideways at 0.45 m/s. Solved
    /// as a block, a face pressed evenly stops without turning. The solution is the
    /// complementarity problem's, the one the row-by-row solve converges to over its
    /// iterations: a hovering speculative point whose bias lets the bodies approach
    /// takes no impulse, so resting contacts carry the loads they carried before.
    /// (`K` of four coplanar points is singular: impulses that sum to no force and no
    /// torque move nothing, and the sweeps leave that part of `λ` where it is.)
    #[inline]
    fn solve_normals(&self, rows: &mut [PointRows<R>], [va, wa, vb, wb]: [&mut V3<R>; 4]) {
        let zero = R::ZERO;
        let tolerance = R::splat(BLOCK_TOLERANCE);
        let (ma, mb, n) = (self.inv_mass_a, self.inv_mass_b, self.normal);
        // Lanes still sweeping: `None` for all of them, in the first sweep (an empty
        // slot's row changes nothing).
        let mut open: Option<R::Mask> = None;
        for _ in 0..BLOCK_SWEEPS {
            // The largest row velocity change: over the last sweep as each row reads
            // it; in the first sweep, each row's own update.
            let mut change = zero;
            for p in rows.iter_mut() {
                let vn = n.dot(*vb - *va) + p.jb_n.dot(*wb) - p.ja_n.dot(*wa);
                let l = p.mass * (vn + p.bias) - p.impulse_scale * p.normal_impulse;
                let new = (p.normal_impulse + l).max(zero);
                let d = new - p.normal_impulse;
                match open {
                    None => {
                        change = change.max(d.abs() * p.normal_stiffness);
                        p.block_velocity = vn;
                        p.normal_impulse = new;
                        *va -= n * (d * ma);
                        *vb += n * (d * mb);
                        *wa -= p.ia_n * d;
                        *wb += p.ib_n * d;
                    }
                    // Lanes already solved keep their bits: each velocity is moved by
                    // subtracting a step that is +0 in those lanes (`x − (+0) = x` for
                    // every x, −0 included), so one mask per term replaces a blend of
                    // old and new velocity. An added step `x + y` is written
                    // `x − (−y)`, the same operation in IEEE 754.
                    Some(m) => {
                        change = change.max((vn - p.block_velocity).abs());
                        p.block_velocity = R::select(m, vn, p.block_velocity);
                        p.normal_impulse = R::select(m, new, p.normal_impulse);
                        let open = |step: V3<R>| V3::select(m, step, V3::default());
                        *va -= open(n * (d * ma));
                        *vb -= open(-(n * (d * mb)));
                        *wa -= open(p.ia_n * d);
                        *wb -= open(-(p.ib_n * d));
                    }
                }
            }
            let more = change.gt(tolerance);
            let still = open.map_or(more, |m| m & more);
            if !R::any(still) {
                break;
            }
            open = Some(still);
        }
    }

    /// The lanes' body velocities.
    #[inline]
    fn gather(&self, s: &BodyStates) -> Velocities<R> {
        let lanes = |v: &[Vec3A], body: &[usize; LANES]| {
            R::v3_from_lanes(std::array::from_fn(|k| {
                if k < R::WIDTH {
                    v[body[k]]
                } else {
                    Vec3A::ZERO
                }
            }))
        };
        [
            lanes(&s.lin_vel, &self.a),
            lanes(&s.ang_vel, &self.a),
            lanes(&s.lin_vel, &self.b),
            lanes(&s.ang_vel, &self.b),
        ]
    }

    /// Writes the lanes' velocities back to their moving bodies (in one group no moving
    /// body is in two lanes; static and sleeping bodies are not written).
    #[inline]
    fn scatter(&self, s: &mut BodyStates, [va, wa, vb, wb]: Velocities<R>) {
        let [va, wa, vb, wb] = [va, wa, vb, wb].map(R::v3_to_lanes);
        for k in (0..R::WIDTH).filter(|&k| self.count[k] != 0) {
            if self.inv_mass_a.lane(k) > 0.0 {
                s.lin_vel[self.a[k]] = va[k];
                s.ang_vel[self.a[k]] = wa[k];
            }
            if self.inv_mass_b.lane(k) > 0.0 {
                s.lin_vel[self.b[k]] = vb[k];
                s.ang_vel[self.b[k]] = wb[k];
            }
        }
    }
}

/// Deals `pairs` (their moving bodies: `None` for a body the solve does not write) into
/// colours, greedily in array order; a pair `wide_ok` rejects, or that no colour can
/// take, goes to the returned one-by-one list. Returns the colours' pairs and that list.
pub fn color(
    bodies: usize,
    pairs: impl Iterator<Item = (Option<usize>, Option<usize>, bool)>,
) -> (Vec<Vec<u32>>, Vec<u32>) {
    let words = bodies.div_ceil(64);
    let mut used = vec![0u64; COLORS * words];
    let mut colors: Vec<Vec<u32>> = vec![Vec::new(); COLORS];
    let mut single = Vec::new();
    let taken = |used: &[u64], c: usize, i: Option<usize>| {
        i.is_some_and(|i| used[c * words + i / 64] & (1 << (i % 64)) != 0)
    };
    for (index, (a, b, wide_ok)) in pairs.enumerate() {
        let free = wide_ok
            .then(|| (0..COLORS).find(|&c| !taken(&used, c, a) && !taken(&used, c, b)))
            .flatten();
        match free {
            Some(c) => {
                for i in [a, b].into_iter().flatten() {
                    used[c * words + i / 64] |= 1 << (i % 64);
                }
                colors[c].push(index as u32);
            }
            None => single.push(index as u32),
        }
    }
    (colors, single)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rigid::soft::Softness;
    use glam::{Mat3A, Quat};
    use wide::f32x4;

    /// Four boxes, each touching the static anchor (body 4) at 1 to 4 points with made-up
    /// but fixed rows, and a step context.
    fn four_pairs() -> (
        BodyStates,
        Vec<PairConstraint>,
        Vec<PointConstraint>,
        StepContext,
    ) {
        let mut s = BodyStates::with_capacity(5);
        for i in 0..4 {
            let f = i as f32;
            s.push(
                Vec3::new(f, 0.1 + 0.01 * f, 0.0),
                Quat::from_rotation_y(0.3 * f),
                Vec3::new(0.2, -1.0 - f, 0.1 * f),
                Vec3::new(0.5, -0.3 * f, 0.2),
            );
            s.inv_mass[i] = 1.0 / (1.0 + f);
            s.inv_inertia[i] = Mat3A::from_diagonal(Vec3::new(150.0, 120.0 + f, 90.0));
        }
        s.push(Vec3::ZERO, Quat::IDENTITY, Vec3::ZERO, Vec3::ZERO);
        let (mut pairs, mut points) = (Vec::new(), Vec::new());
        for i in 0..4 {
            let n = Vec3::new(0.1 * i as f32, -1.0, 0.05).normalize();
            let (t0, t1) = n.any_orthonormal_pair();
            let start = points.len();
            for j in 0..=i {
                let r = Vec3::new(0.1 - 0.2 * (j % 2) as f32, -0.1, 0.1 - 0.2 * (j / 2) as f32);
                points.push(PointConstraint {
                    local_a: r,
                    ja_n: r.cross(n),
                    ja_t: [r.cross(t0), r.cross(t1)],
                    normal_mass: 0.25 + 0.01 * j as f32,
                    tangent_mass: [0.3, 0.35],
                    normal_impulse: 0.02 * j as f32,
                    base_separation: 0.004 - 0.003 * j as f32,
                    ..PointConstraint::default()
                });
            }
            pairs.push(PairConstraint {
                a: i,
                b: 4,
                start,
                count: i + 1,
                normal: n,
                tangents: [t0, t1],
                inv_mass_a: s.inv_mass[i],
                friction: 0.6,
                ..PairConstraint::default()
            });
        }
        let h = 1.0 / 240.0;
        let ctx = StepContext {
            h,
            inv_h: 1.0 / h,
            joint: Softness::new(60.0, 10.0, h),
            contact: Softness::new(60.0, 10.0, h),
            max_push_out: 3.0,
        };
        (s, pairs, points, ctx)
    }

    /// Loads the four pairs as `R`-wide groups, runs a substep's passes and returns the
    /// velocities and impulses.
    fn run<R: Real>(groups: &[&[usize]]) -> (Vec<[u32; 6]>, Vec<u32>) {
        let (mut s, mut pairs, mut points, ctx) = four_pairs();
        let mut lanes = ContactLanes::<R>::default();
        for g in groups {
            let l: Vec<&PairConstraint> = g.iter().map(|&i| &pairs[i]).collect();
            lanes.load(g, &l, &points);
        }
        lanes.refresh(&s, true);
        lanes.warm_start(&mut s);
        for _ in 0..3 {
            lanes.solve(&mut s, &ctx, true);
        }
        lanes.refresh(&s, false);
        lanes.solve(&mut s, &ctx, false);
        lanes.write_back(&mut points, &mut pairs);
        let v = (0..4)
            .map(|i| {
                let (v, w) = (s.lin_vel[i], s.ang_vel[i]);
                [v.x, v.y, v.z, w.x, w.y, w.z].map(f32::to_bits)
            })
            .collect();
        let impulses = points
            .iter()
            .flat_map(|p| [p.normal_impulse, p.tangent_impulse[0], p.tangent_impulse[1]])
            .map(f32::to_bits)
            .collect();
        (v, impulses)
    }

    /// The determinism across thread counts rests on this: an island solve colours its
    /// own pairs, so a pair solved alone on one thread may share a group on another.
    #[test]
    fn a_pair_gets_the_same_bits_alone_as_in_a_lane() {
        let alone = run::<f32>(&[&[0], &[1], &[2], &[3]]);
        assert_eq!(alone, run::<f32x4>(&[&[0, 1, 2, 3]]));
        assert_eq!(alone, run::<f32x4>(&[&[3, 1], &[2, 0]]));
    }

    /// The block solve's answer is the pair's complementarity problem's: after a relax
    /// pass (rigid rows, no friction) every point's impulse is non-negative, its row's
    /// residual `w = v + b` (`b = s/h` for a speculative point, else 0) is too, and it is
    /// zero where the impulse is positive, to the order of [`BLOCK_TOLERANCE`]: the
    /// sweeps stop once a sweep moved no row's velocity by more than it, and the rows
    /// solved after a point in that last sweep leave it a residual of the same order
    /// (1.4e-4 m/s on the third pair), hence twice the tolerance. The pairs of
    /// [`four_pairs`] approach their anchor with points overlapping and one hovering, so
    /// both sides of the complementarity are met.
    #[test]
    fn a_pairs_normal_impulses_solve_its_complementarity_problem() {
        let (mut s, mut pairs, mut points, ctx) = four_pairs();
        for p in &mut pairs {
            p.friction = 0.0;
        }
        // The first box's point 4 mm from the anchor (at the origin), approached at about
        // 0.5 m/s: 2 mm of it close this substep, so the point hovers and takes no impulse.
        let (n, anchor) = (pairs[0].normal, s.com[0] + s.rot[0] * points[0].local_a);
        points[0].base_separation = 0.004 + n.dot(anchor);
        s.lin_vel[0].y = -0.5;
        let mut lanes = ContactLanes::<f32x4>::default();
        let all: Vec<&PairConstraint> = pairs.iter().collect();
        lanes.load(&[0, 1, 2, 3], &all, &points);
        lanes.refresh(&s, true);
        lanes.warm_start(&mut s);
        lanes.solve(&mut s, &ctx, true);
        lanes.refresh(&s, false);
        lanes.solve(&mut s, &ctx, false);
        let g = &lanes.groups[0];
        let [va, wa, vb, wb] = g.gather(&s);
        let (mut pressed, mut free) = (0, 0);
        for k in 0..4 {
            let anchors = &lanes.anchors[g.rows..g.rows + g.count[k]];
            for (p, c) in lanes.rows[g.rows..g.rows + g.count[k]].iter().zip(anchors) {
                let n = g.normal.lane(k);
                let v = n.dot(vb.lane(k) - va.lane(k)) + p.jb_n.lane(k).dot(wb.lane(k))
                    - p.ja_n.lane(k).dot(wa.lane(k));
                let sep = c.separation.lane(k);
                let w = v + if sep > 0.0 { sep * ctx.inv_h } else { 0.0 };
                let lambda = p.normal_impulse.lane(k);
                assert!(lambda >= 0.0, "pair {k}: impulse {lambda}");
                let tolerance = 2.0 * BLOCK_TOLERANCE;
                assert!(w >= -tolerance, "pair {k}: residual {w} m/s");
                if lambda > 0.0 {
                    assert!(w.abs() <= tolerance, "pair {k}: λ {lambda}, w {w} m/s");
                    pressed += 1;
                } else {
                    free += 1;
                }
            }
        }
        assert!(pressed > 0 && free > 0, "{pressed} pressed, {free} free");
    }

    #[test]
    fn a_colour_never_holds_a_moving_body_twice_but_shares_static_ones() {
        // A chain of moving bodies 0-1-2-3, each also on the ground (static: None).
        let pairs = [
            (Some(0), Some(1), true),
            (Some(1), Some(2), true),
            (Some(2), Some(3), true),
            (Some(0), None, true),
            (Some(1), None, true),
            (Some(2), None, true),
            (Some(3), None, true),
            (Some(3), Some(0), false),
        ];
        let (colors, single) = color(4, pairs.iter().copied());
        assert_eq!(
            single,
            vec![7],
            "a pair the caller keeps scalar stays scalar"
        );
        let mut seen = 0;
        for c in &colors {
            let mut bodies: Vec<usize> = c
                .iter()
                .flat_map(|&i| [pairs[i as usize].0, pairs[i as usize].1])
                .flatten()
                .collect();
            seen += c.len();
            let n = bodies.len();
            bodies.sort_unstable();
            bodies.dedup();
            assert_eq!(bodies.len(), n, "a moving body twice in colour {c:?}");
        }
        assert_eq!(seen, 7);
        // Greedy in array order: the chain's first and third links share the first colour.
        assert_eq!(colors[0], vec![0, 2]);
    }

    #[test]
    fn a_body_in_more_pairs_than_colours_overflows_to_the_scalar_solve() {
        let pairs = (1..=COLORS + 3).map(|i| (Some(0), Some(i), true));
        let (colors, single) = color(COLORS + 4, pairs);
        assert!(colors.iter().all(|c| c.len() == 1));
        assert_eq!(single, vec![16, 17, 18]);
    }
}
