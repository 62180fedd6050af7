//! What every joint is made of: a frame on each body, a point constraint, angular locks,
//! one-dimensional angular rows (limits, soft limits, motors) and joint friction.
//!
//! Conventions: body `a` is the scene's body1, body `b` its body2 or the static anchor
//! (the world). Offsets are stored in body space relative to the centre of mass and turned
//! into world space from the current orientations at every substep, so position errors
//! are measured on the current state (Box2D v3 measures them from delta positions; in 3D
//! with substeps this is the same quantity).

// `!(k > ε)` on purpose: it is also true for NaN, which must skip the row too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::body::BodyStates;
use super::joint_rows::{
    AlignRows, AngularRow, PointRows, Pose, Soft, Velocities, inertia, invert_symmetric,
    orthonormal_pair, point_response,
};
use super::project::{ANGULAR_SLOP, JOINT_SLOP, MAX_ANGULAR_CORRECTION, MAX_LINEAR_CORRECTION};
use super::soft::{Softness, Spring, StepContext};
use crate::lanes::V3;
use glam::{Mat3A, Quat, Vec3, Vec3A};

/// The two bodies of a joint and the joint anchor fixed in each.
#[derive(Clone, Copy, Debug)]
pub struct JointFrame {
    /// Body1.
    pub a: usize,
    /// Body2 or the static anchor.
    pub b: usize,
    /// Anchor in body a's space, relative to its centre of mass.
    pub local_a: Vec3,
    /// Anchor in body b's space (world space for the static anchor).
    pub local_b: Vec3,
}

impl JointFrame {
    /// A frame for a world-space `anchor` at the rest pose.
    pub fn new(s: &BodyStates, a: usize, b: usize, anchor: Vec3) -> JointFrame {
        JointFrame {
            a,
            b,
            local_a: s.rot[a].inverse() * (anchor - s.com[a]),
            local_b: s.rot[b].inverse() * (anchor - s.com[b]),
        }
    }

    /// World offsets of the anchor from each centre of mass, now.
    #[inline]
    pub fn offsets(&self, s: &BodyStates) -> (Vec3, Vec3) {
        (s.rot[self.a] * self.local_a, s.rot[self.b] * self.local_b)
    }

    /// World anchor as seen from a and from b; their distance is the joint gap.
    pub fn anchors(&self, s: &BodyStates) -> (Vec3, Vec3) {
        let (ra, rb) = self.offsets(s);
        (s.com[self.a] + ra, s.com[self.b] + rb)
    }

    /// A body-a direction given in world space at rest, stored in a's space.
    pub fn dir_in_a(&self, s: &BodyStates, v: Vec3) -> Vec3 {
        s.rot[self.a].inverse() * v
    }

    /// A body-b direction given in world space at rest, stored in b's space.
    pub fn dir_in_b(&self, s: &BodyStates, v: Vec3) -> Vec3 {
        s.rot[self.b].inverse() * v
    }

    /// Sum of the two world inverse inertias (the angular effective-mass matrix).
    #[inline]
    pub fn inv_inertia_sum(&self, s: &BodyStates) -> Mat3A {
        s.inv_inertia[self.a] + s.inv_inertia[self.b]
    }

    /// Relative angular velocity `ω_a − ω_b`.
    #[inline]
    pub fn rel_ang_vel(&self, s: &BodyStates) -> Vec3A {
        s.ang_vel[self.a] - s.ang_vel[self.b]
    }

    /// Applies the angular impulse `l` to a and `−l` to b.
    #[inline]
    pub fn apply_angular(&self, s: &mut BodyStates, l: Vec3A) {
        s.apply_angular_impulse(self.a, l);
        s.apply_angular_impulse(self.b, -l);
    }

    /// Rotates a by the angular position impulse `l` and b by `−l` (projection pass).
    #[inline]
    pub fn rotate_apart(&self, s: &mut BodyStates, l: Vec3) {
        s.apply_angular_position_impulse(self.a, l);
        s.apply_angular_position_impulse(self.b, -l);
    }
}

/// What the solver asks of every joint type.
///
/// A joint keeps what must last from one step to the next (bodies, anchors, limits,
/// accumulated impulses, friction state); what a step prepares anew on the pose and
/// inertias of each substep (offsets, errors, turns, effective masses: a joint's
/// [`JointSolve::Rows`]) lives in an array beside the joints, in the arrays being solved
/// ([`super::joint_set::JointSet::rows`]): the world's own when it is solved in place,
/// a batch's when it is solved in batches ([`super::parallel`]), so a world solved in
/// batches keeps one batch's worth of rows per thread rather than one per joint.
pub(crate) trait JointSolve {
    /// The rows a step prepares for the joint and its solve reads; nothing in them
    /// outlives the step.
    type Rows: Copy + Default;
    /// Bodies and anchor.
    fn frame(&self) -> &JointFrame;
    /// Evaluates the rows (anchors, errors, effective masses, limit rows) on the current
    /// pose and inertias, at a step's first substep (later substeps call
    /// [`JointSolve::prepare_after_relax`]).
    fn prepare(&mut self, rows: &mut Self::Rows, s: &BodyStates);
    /// [`JointSolve::prepare`] on the pose the last relax pass solved on (no position
    /// has moved since, only the inertias were refreshed): the point and alignment rows,
    /// prepared on this pose for the relax passes ([`JointSolve::prepare_moved`]), only
    /// re-weigh their turns and effective masses with the new inertias (the same bits as
    /// preparing them anew, for less).
    fn prepare_after_relax(&mut self, rows: &mut Self::Rows, s: &BodyStates) {
        self.prepare(rows, s);
    }
    /// The rows the relax pass solves on the pose the substep moved to: the point and
    /// alignment rows prepared on it (the limit rows keep the substep's). A function of
    /// the pose, inertias and masses alone, none of which a velocity pass changes, so
    /// every relax pass of a substep solves on this one preparation.
    fn prepare_moved(&mut self, _rows: &mut Self::Rows, _s: &BodyStates) {}
    /// Re-applies the accumulated impulses.
    fn warm_start(&self, rows: &Self::Rows, s: &mut BodyStates);
    /// One Gauss–Seidel update; `use_bias` false in the relax pass, which solves on the
    /// rows of [`JointSolve::prepare_moved`].
    fn solve(&mut self, rows: &Self::Rows, s: &mut BodyStates, ctx: &StepContext, use_bias: bool);
    /// One position-projection update (see [`super::project`]); joints without a
    /// rigid part (springs) keep the default, which does nothing.
    fn project(&self, _s: &mut BodyStates) {}
    /// The position projection of the point row alone, as [`JointSolve::project`]
    /// ends with it; joints without a point row keep the default, which does nothing.
    fn project_point(&self, _s: &mut BodyStates) {}
    /// Distance between the anchor as seen from each body (m).
    fn gap(&self, s: &BodyStates) -> f32 {
        let (pa, pb) = self.frame().anchors(s);
        pa.distance(pb)
    }
    /// Excess of a limited angle beyond its hard limit (rad); soft limits do not count.
    fn limit_violation(&self, s: &BodyStates) -> f32;
}

/// Soft coefficients for a bilateral row: the joint softness while solving, rigid
/// without feedback in the relax pass.
#[inline]
fn bilateral(ctx: &StepContext, use_bias: bool) -> Softness {
    if use_bias { ctx.joint } else { Softness::RIGID }
}

/// The ball-and-socket point constraint `p_b − p_a = 0`: one joint's accumulated
/// impulse and how it is solved; its [`PointRows`] (the rows, written once for one joint
/// and for lanes of four) are the joint's [`JointSolve::Rows`], passed in.
///
/// `K⁻¹` is prepared once per substep and shared by the biased iterations; the relax
/// passes come after the positions moved and share a second preparation
/// ([`JointSolve::prepare_moved`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct PointPart {
    /// Accumulated impulse on b (world). Kept as a `Vec3` (12 bytes) and widened where
    /// it is used: a `Vec3A`'s 16-byte alignment would make the part 32 bytes, not 16,
    /// in every joint; widening changes no bit of the products and sums.
    pub impulse: Vec3,
    /// Solved with its tree's other point rows by [`super::joint_tree`], not here.
    pub direct: bool,
    /// In a tree of this solve (`direct` unless the tree's factorisation failed): the
    /// tree reads the joint's rows.
    pub(super) in_tree: bool,
}

/// `v` as a one-lane vector.
#[inline]
pub(super) fn one(v: impl Into<Vec3>) -> V3<f32> {
    let v = v.into();
    V3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// The inverse masses of `f`'s bodies.
#[inline]
fn masses(f: &JointFrame, s: &BodyStates) -> [f32; 2] {
    [s.inv_mass[f.a], s.inv_mass[f.b]]
}

impl PointPart {
    /// Evaluates the offsets, the error and what the solve reads of the weights on the
    /// current positions ([`PointPart::weigh`]).
    pub(crate) fn prepare(&self, rows: &mut PointRows<f32>, f: &JointFrame, s: &BodyStates) {
        let local = [one(f.local_a), one(f.local_b)];
        let pose = Pose::of(s, f.a, f.b);
        rows.place(local, &pose);
        self.weigh(rows, f, s);
    }

    /// The turns and `K⁻¹` for the offsets of the last [`PointPart::prepare`] and the
    /// inertias now: all that changes when only the inertias were refreshed since. A
    /// joint whose tree solves its point rows (`direct`) reads only the turns, in its
    /// warm start; its tree weighs `K⁻¹` if it hands the joint back to Gauss–Seidel
    /// ([`PointPart::weigh_all`]).
    pub(crate) fn weigh(&self, rows: &mut PointRows<f32>, f: &JointFrame, s: &BodyStates) {
        if self.direct {
            rows.turn([inertia(s, f.a), inertia(s, f.b)]);
        } else {
            PointPart::weigh_all(rows, f, s);
        }
    }

    /// The turns and `K⁻¹` whether or not a tree solves the joint.
    pub(super) fn weigh_all(rows: &mut PointRows<f32>, f: &JointFrame, s: &BodyStates) {
        let inertias = [inertia(s, f.a), inertia(s, f.b)];
        rows.weigh(inertias, masses(f, s), true);
    }

    /// The relax passes' rows on the pose the substep moved to
    /// ([`JointSolve::prepare_moved`]): a joint whose tree solves its point rows reads
    /// only the offsets and the error there (the relax passes start no warm start), and
    /// its tree weighs the rest if it hands the joint back to Gauss–Seidel.
    pub(crate) fn prepare_moved(&self, rows: &mut PointRows<f32>, f: &JointFrame, s: &BodyStates) {
        if self.direct {
            let local = [one(f.local_a), one(f.local_b)];
            rows.place(local, &Pose::of(s, f.a, f.b));
        } else {
            self.prepare(rows, f, s);
        }
    }

    /// The world offsets of the anchor from a's and from b's centre of mass and
    /// `p_b − p_a`, at the `prepare` of `rows`.
    #[inline]
    pub(super) fn anchors_of(rows: &PointRows<f32>) -> [Vec3A; 3] {
        [rows.ra, rows.rb, rows.c].map(|v| v.lane(0).into())
    }

    /// Applies the impulse `p` on b and `−p` on a.
    #[inline]
    pub(super) fn apply(rows: &PointRows<f32>, f: &JointFrame, s: &mut BodyStates, p: Vec3A) {
        let mut v = Velocities::of(s, f.a, f.b);
        rows.apply(&mut v, masses(f, s), one(p), true);
        v.store(s, f.a, f.b);
    }

    /// Re-applies last substep's impulse (after [`PointPart::prepare`]).
    pub(crate) fn warm_start(&self, rows: &PointRows<f32>, f: &JointFrame, s: &mut BodyStates) {
        PointPart::apply(rows, f, s, Vec3A::from(self.impulse));
    }

    /// One soft Gauss–Seidel update (the relax pass, `use_bias` false, on the rows
    /// prepared on the moved pose).
    pub(crate) fn solve(
        &mut self,
        rows: &PointRows<f32>,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        if self.direct || !rows.on {
            return;
        }
        let mut v = Velocities::of(s, f.a, f.b);
        let mut impulse = one(self.impulse);
        let soft = Soft::new(ctx, use_bias);
        rows.solve(&mut v, masses(f, s), &mut impulse, &soft, true);
        v.store(s, f.a, f.b);
        self.impulse = impulse.lane(0);
    }

    /// Position projection: moves both bodies by `P = −K⁻¹ C` so the anchors meet, the
    /// error clamped to [`MAX_LINEAR_CORRECTION`].
    ///
    /// Gaps below [`JOINT_SLOP`] are left to the velocity solver: a resting figure's
    /// joints sag that much under load, and closing it every step would make the figure
    /// creep. With `translate_only` (a joint held by its friction) the bodies are only
    /// translated, so the correction does not turn the joint past what friction holds.
    pub fn project(&self, f: &JointFrame, s: &mut BodyStates, translate_only: bool) {
        let (ra, rb) = f.offsets(s);
        let c = (s.com[f.b] + rb) - (s.com[f.a] + ra);
        if c.length_squared() <= JOINT_SLOP * JOINT_SLOP {
            return;
        }
        let c = c.clamp_length_max(MAX_LINEAR_CORRECTION);
        if translate_only {
            let m = s.inv_mass[f.a] + s.inv_mass[f.b];
            if m > 0.0 {
                let p = -c / m;
                s.com[f.a] -= p * s.inv_mass[f.a];
                s.com[f.b] += p * s.inv_mass[f.b];
            }
            return;
        }
        let (_, ka) = point_response(inertia(s, f.a), s.inv_mass[f.a], one(ra));
        let (_, kb) = point_response(inertia(s, f.b), s.inv_mass[f.b], one(rb));
        let (k_inv, ok) = invert_symmetric(std::array::from_fn(|j| ka[j] + kb[j]));
        if !ok {
            return;
        }
        let p = -(k_inv * one(c)).lane(0);
        s.apply_position_impulse(f.a, ra, -p);
        s.apply_position_impulse(f.b, rb, p);
    }
}

/// Inverse of a 3×3 effective-mass matrix, `None` when singular (both bodies static).
#[inline]
pub fn invert(k: Mat3A) -> Option<Mat3A> {
    let det = k.determinant();
    (det.is_finite() && det.abs() > 1e-20).then(|| k.inverse())
}

/// Locks all three relative rotations to the rest pose: `C = 2 vec(q_b q_rel q_a⁻¹)` with
/// `q_rel` the rest orientation of a seen from b... written so that `Ċ ≈ ω_a − ω_b`.
#[derive(Clone, Copy, Debug, Default)]
pub struct AngularLock3 {
    /// `q_b⁻¹ q_a` at rest.
    pub rest: Quat,
    /// Accumulated angular impulse on a.
    pub impulse: Vec3A,
}

impl AngularLock3 {
    /// The lock for the rest pose of `f`.
    pub fn new(f: &JointFrame, s: &BodyStates) -> AngularLock3 {
        AngularLock3 {
            rest: s.rot[f.b].inverse() * s.rot[f.a],
            impulse: Vec3A::ZERO,
        }
    }

    /// Rotation vector (small-angle) of a away from where the rest pose puts it.
    pub fn error(&self, f: &JointFrame, s: &BodyStates) -> Vec3 {
        let target = s.rot[f.b] * self.rest;
        let mut e = s.rot[f.a] * target.inverse();
        if e.w < 0.0 {
            e = -e;
        }
        2.0 * Vec3::new(e.x, e.y, e.z)
    }

    /// Re-applies the accumulated impulse.
    pub fn warm_start(&self, f: &JointFrame, s: &mut BodyStates) {
        f.apply_angular(s, self.impulse);
    }

    /// One soft block update.
    pub fn solve(&mut self, f: &JointFrame, s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        let c = Vec3A::from(self.error(f, s));
        let cdot = f.rel_ang_vel(s);
        let soft = bilateral(ctx, use_bias);
        let Some(k_inv) = invert(f.inv_inertia_sum(s)) else {
            return;
        };
        let l = -soft.mass_scale * (k_inv * (cdot + soft.bias_rate * c))
            - soft.impulse_scale * self.impulse;
        self.impulse += l;
        f.apply_angular(s, l);
    }

    /// Position projection: rotates the bodies back towards the rest orientation.
    pub fn project(&self, f: &JointFrame, s: &mut BodyStates) {
        let c = self.error(f, s).clamp_length_max(MAX_ANGULAR_CORRECTION);
        let Some(k_inv) = invert(f.inv_inertia_sum(s)) else {
            return;
        };
        f.rotate_apart(s, -(k_inv * c));
    }
}

/// Keeps a direction fixed in a aligned with one fixed in b (the hinge's rotational
/// part; a 0° cone): its directions and accumulated impulse. Its [`AlignRows`] are
/// passed in (the hinge's [`JointSolve::Rows`], the 0° cone's own); like [`PointPart`]'s,
/// the rows and their 2×2 effective mass are prepared once per substep and shared by the
/// biased iterations.
#[derive(Clone, Copy, Debug, Default)]
pub struct AlignPart {
    /// Direction in a's space.
    pub local_a: Vec3,
    /// Direction in b's space.
    pub local_b: Vec3,
    /// Accumulated impulse (two components along the current perpendiculars).
    pub impulse: [f32; 2],
}

impl AlignPart {
    /// Alignment of the world direction `d` (at rest) in both bodies.
    pub fn new(f: &JointFrame, s: &BodyStates, d: Vec3) -> AlignPart {
        AlignPart {
            local_a: f.dir_in_a(s, d),
            local_b: f.dir_in_b(s, d),
            ..AlignPart::default()
        }
    }

    fn basis(&self, f: &JointFrame, s: &BodyStates) -> (Vec3, Vec3, Vec3, Vec3) {
        let da = s.rot[f.a] * self.local_a;
        let db = s.rot[f.b] * self.local_b;
        let (u, v) = orthonormal_pair(one(da));
        (da, db, u.lane(0), v.lane(0))
    }

    /// Evaluates the rows, the error and the effective mass on the current positions.
    pub(crate) fn prepare(&self, rows: &mut AlignRows<f32>, f: &JointFrame, s: &BodyStates) {
        let local = [one(self.local_a), one(self.local_b)];
        rows.prepare(local, &Pose::of(s, f.a, f.b), true);
    }

    /// The turns and the effective mass for the rows of the last [`AlignPart::prepare`]
    /// and the inertias now: all that changes when only the inertias were refreshed
    /// since.
    pub(crate) fn weigh(rows: &mut AlignRows<f32>, f: &JointFrame, s: &BodyStates) {
        rows.weigh([inertia(s, f.a), inertia(s, f.b)], true);
    }

    /// Re-applies the accumulated impulse along the rows (after [`AlignPart::prepare`]).
    pub(crate) fn warm_start(&self, rows: &AlignRows<f32>, f: &JointFrame, s: &mut BodyStates) {
        let mut v = Velocities::of(s, f.a, f.b);
        rows.apply(&mut v, self.impulse, true);
        v.store(s, f.a, f.b);
    }

    /// One soft 2×2 block update (the relax pass, `use_bias` false, on the rows
    /// prepared on the moved pose).
    pub(crate) fn solve(
        &mut self,
        rows: &AlignRows<f32>,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        if !rows.on {
            return;
        }
        let mut v = Velocities::of(s, f.a, f.b);
        rows.solve(&mut v, &mut self.impulse, &Soft::new(ctx, use_bias));
        v.store(s, f.a, f.b);
    }

    /// Position projection: rotates the bodies so the two directions align again.
    pub fn project(&self, f: &JointFrame, s: &mut BodyStates) {
        let (da, db, u, v) = self.basis(f, s);
        let e = db.cross(da).clamp_length_max(MAX_ANGULAR_CORRECTION);
        let m = f.inv_inertia_sum(s);
        let (k11, k12, k22) = (u.dot(m * u), u.dot(m * v), v.dot(m * v));
        let det = k11 * k22 - k12 * k12;
        if !(det.abs() > 1e-20) {
            return;
        }
        let r = [u.dot(e), v.dot(e)];
        let l0 = -(k22 * r[0] - k12 * r[1]) / det;
        let l1 = -(k11 * r[1] - k12 * r[0]) / det;
        f.rotate_apart(s, u * l0 + v * l1);
    }
}

/// How a one-dimensional row reacts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowKind {
    /// `C ≥ 0`, impulse ≥ 0: a hard limit (soft in the Box2D sense, speculative when
    /// `C > 0` so it never pulls).
    Limit,
    /// `C ≥ 0` enforced by a one-sided spring of stiffness `k` (N·m per unit of C):
    /// the PyODE tutorial's restoring torque, implicitly integrated, with a little
    /// damping as the tutorial's counter-torque adds.
    SoftLimit {
        /// Stiffness.
        k: f32,
    },
    /// `C = 0`, both signs.
    Equality,
}

/// What a one-dimensional angular row ([`AxisRow`]) keeps from step to step: how it
/// reacts and its accumulated impulse. The joint holds it; the row itself is set anew
/// at every substep and lives with the joint's other rows ([`JointSolve::Rows`]). A
/// limit of several rows that react alike (a range's two, a pyramid's four) keeps the
/// kind once and an impulse per row instead.
#[derive(Clone, Copy, Debug)]
pub struct RowState {
    /// Reaction.
    pub kind: RowKind,
    /// Accumulated impulse.
    pub impulse: f32,
}

impl RowState {
    /// No impulse yet.
    pub const fn new(kind: RowKind) -> RowState {
        RowState { kind, impulse: 0.0 }
    }
}

/// One angular constraint row `Ċ = axis · (ω_a − ω_b)`, as set on a substep's pose;
/// its accumulated impulse is its [`RowState`]'s, passed in.
#[derive(Clone, Copy, Debug)]
pub struct AxisRow {
    /// World axis, recomputed every substep.
    pub axis: Vec3,
    /// Position value (rad or a dimensionless sine, positive = inside the limit).
    pub c: f32,
    /// Reaction (the state's, copied by [`AxisRow::set`]).
    pub kind: RowKind,
    /// Whether the row is near enough to its bound to be solved this substep.
    pub active: bool,
    /// How a unit impulse along the axis turns each body, `I_a⁻¹ axis` and `I_b⁻¹ axis`,
    /// and the row's `k = axisᵀ (I_a⁻¹ + I_b⁻¹) axis`: fixed from [`AxisRow::set`] to
    /// the end of the substep, as the inertias are.
    pub(super) turn: [Vec3A; 2],
    pub(super) k: f32,
}

/// An inactive row, never read before [`AxisRow::set`].
impl Default for AxisRow {
    fn default() -> AxisRow {
        AxisRow {
            axis: Vec3::ZERO,
            c: 0.0,
            kind: RowKind::Equality,
            active: false,
            turn: [Vec3A::ZERO; 2],
            k: 0.0,
        }
    }
}

impl AxisRow {
    /// Sets the row of reaction `kind` with axis and value on the current pose and
    /// inertias of `f`'s bodies; rows far from their bound (more than `margin`) sleep,
    /// and their accumulated `impulse` is dropped.
    pub fn set(
        &mut self,
        (kind, impulse): (RowKind, &mut f32),
        f: &JointFrame,
        s: &BodyStates,
        (axis, c): (Vec3, f32),
        margin: f32,
    ) {
        self.axis = axis;
        self.c = c;
        self.kind = kind;
        let active = self.kind == RowKind::Equality || c < margin;
        if !active {
            *impulse = 0.0;
        } else {
            let axis = Vec3A::from(axis);
            self.turn = [s.inv_inertia[f.a] * axis, s.inv_inertia[f.b] * axis];
            self.k = axis.dot(self.turn[0] + self.turn[1]);
        }
        self.active = active;
    }

    /// The row in one lane, for [`AngularRow`]'s updates.
    #[inline]
    fn one_lane(&self) -> AngularRow<f32> {
        AngularRow {
            axis: one(self.axis),
            c: self.c,
            m: 1.0 / self.k,
            turn: self.turn.map(one),
            active: self.active,
            on: self.active && self.k > 1e-20,
        }
    }

    /// Re-applies the accumulated impulse `impulse`.
    pub fn warm_start(&self, impulse: f32, f: &JointFrame, s: &mut BodyStates) {
        if self.active {
            let mut v = Velocities::of(s, f.a, f.b);
            self.one_lane().warm_start(&mut v, impulse);
            v.store(s, f.a, f.b);
        }
    }

    /// One update of the row. Inlined so that a row far from its bound (most limit rows:
    /// a range has two, at most one of them near) costs the test, not a call.
    #[inline]
    pub fn solve(
        &self,
        impulse: &mut f32,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        if self.active {
            self.solve_active(impulse, f, s, ctx, use_bias);
        }
    }

    /// [`AxisRow::solve`] of an active row: a hard limit or an equality by
    /// [`AngularRow::solve`], a soft limit here.
    fn solve_active(
        &self,
        impulse: &mut f32,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        let k = self.k;
        if !(k > 1e-20) {
            return;
        }
        let limit = match self.kind {
            RowKind::Limit => true,
            RowKind::Equality => false,
            RowKind::SoftLimit { k: stiffness } => {
                return self.solve_soft(impulse, f, s, ctx, stiffness);
            }
        };
        let mut v = Velocities::of(s, f.a, f.b);
        let soft = Soft::new(ctx, use_bias);
        self.one_lane().solve(&mut v, impulse, &soft, limit);
        v.store(s, f.a, f.b);
    }

    /// Applies the angular impulse `axis λ` to a and its opposite to b.
    #[inline]
    fn apply(&self, f: &JointFrame, s: &mut BodyStates, lambda: f32) {
        s.ang_vel[f.a] += self.turn[0] * lambda;
        s.ang_vel[f.b] -= self.turn[1] * lambda;
    }

    /// The update of an active soft limit of `stiffness`.
    fn solve_soft(
        &self,
        impulse: &mut f32,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        stiffness: f32,
    ) {
        let k = self.k;
        let cdot = Vec3A::from(self.axis).dot(f.rel_ang_vel(s));
        let old = *impulse;
        let new = if self.c >= 0.0 {
            0.0
        } else {
            // Damping 1 % of the stiffness, as the tutorial's `-0.01 * force`.
            let Some(sp) = Spring::new(stiffness, 0.01 * stiffness, ctx.h) else {
                return;
            };
            let l = -(cdot + sp.bias_rate * self.c + sp.gamma * old) / (k + sp.gamma);
            (old + l).max(0.0)
        };
        *impulse = new;
        self.apply(f, s, new - old);
    }

    /// Position projection of a hard limit or an equality with the axis and value last
    /// set: `Δθ = −C/k` along the axis, a limit only when violated by more than
    /// [`ANGULAR_SLOP`] (soft limits are springs by design and are left alone).
    pub fn project(&self, f: &JointFrame, s: &mut BodyStates) {
        let c = match self.kind {
            RowKind::Limit if self.active => (self.c + ANGULAR_SLOP).min(0.0),
            RowKind::Equality => self.c,
            _ => return,
        };
        if c == 0.0 {
            return;
        }
        let k = self.axis.dot(f.inv_inertia_sum(s) * self.axis);
        if !(k > 1e-20) {
            return;
        }
        let c = c.clamp(-MAX_ANGULAR_CORRECTION, MAX_ANGULAR_CORRECTION);
        f.rotate_apart(s, self.axis * (-c / k));
    }
}

/// The relative rotations a joint leaves free, the only ones its friction acts on: the
/// others are held by the joint's own rows (a hinge's alignment, a universal joint's
/// cross row), and a couple along them would only take over part of those rows' load,
/// spending the friction's cap on it (see [`FrictionMotor`]).
#[derive(Clone, Copy, Debug)]
pub enum FreeTurns {
    /// All three (a ball-and-socket joint).
    All,
    /// About one world axis, a unit vector (a hinge).
    Axis(Vec3A),
    /// In the plane normal to a world unit vector (a universal joint, whose cross row
    /// holds the turn about `shaft₁ × shaft₂`).
    Plane(Vec3A),
}

/// Joint friction as a capped motor (Doom 3 `friction`): drives the relative angular
/// velocity of the turns the joint leaves free ([`FreeTurns`]) to zero with at most
/// `max_torque · h` angular impulse per substep, so the joint holds still under small
/// loads and slips under large ones.
///
/// Coulomb's law for a joint: the impulse `λ` makes the free turns' relative angular
/// velocity zero (static friction) when that takes `|λ| ≤ max_torque · h`, and is
/// `λ = −max_torque · h · ŵ` along the slip otherwise; clamping the accumulated impulse
/// to that ball is the projected Gauss–Seidel step of this complementarity problem. The
/// cap is a constant ([`FrictionMotor::new`]), not the joint's load of the last
/// iteration, so it does not move with the friction's own answer.
///
/// Every joint's friction is solved before the joints' hard rows (limits, alignments,
/// points) in each iteration ([`super::joint_set::JointSet::solve`]), as Box2D orders a
/// joint's motor before its limit and point: the hard rows have the last word, and the
/// friction holds only what they leave free. Solved after them, a hinge's friction took
/// back up to its cap of the push its own stop had just given (both act about the hinge
/// axis), and on a resting limb answered each iteration's leftover of the rows before
/// it, landing on one end of its cap and then on the other from substep to substep (the
/// lab humanoid's forearm, whose spin then changed faster than `suspendSpeed` allows, so
/// the figure never slept).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrictionMotor {
    /// Largest friction torque (N·m); 0 disables the motor.
    pub max_torque: f32,
    /// Accumulated angular impulse on a (in the free turns of the last update); a
    /// `Vec3` widened where used, as [`PointPart::impulse`].
    pub impulse: Vec3,
    /// Whether the last update held the joint (impulse below the cap: sticking).
    pub holding: bool,
}

impl FrictionMotor {
    /// Doom 3 gives joint friction as a number in [0, 1] without units; we read it as the
    /// fraction of the torque gravity exerts on body1 held horizontally at its arm
    /// (the anchor's distance from body1's centre of mass): `f · m₁ g r`.
    pub fn new(friction: f32, mass_a: f32, arm: f32, g: f32) -> FrictionMotor {
        FrictionMotor {
            max_torque: friction * mass_a * g * arm.max(0.05),
            impulse: Vec3::ZERO,
            holding: false,
        }
    }

    /// Re-applies the accumulated impulse.
    #[inline]
    pub fn warm_start(&self, f: &JointFrame, s: &mut BodyStates) {
        if self.max_torque > 0.0 {
            f.apply_angular(s, Vec3A::from(self.impulse));
        }
    }

    /// One update of the turns `free`; friction is solved without bias, the same in
    /// both passes.
    #[inline]
    pub fn solve(
        &mut self,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        point: &PointPart,
        free: FreeTurns,
    ) {
        if self.max_torque > 0.0 {
            self.hold(f, s, ctx, point, free);
        }
    }

    /// [`FrictionMotor::solve`] of a motor with a positive cap. The impulse is a couple,
    /// `l` on a and `−l` on b; a joint whose point rows are solved by Gauss–Seidel gets
    /// it about the centres of mass, with the inverse effective mass `I_a⁻¹ + I_b⁻¹`.
    fn hold(
        &mut self,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        point: &PointPart,
        free: FreeTurns,
    ) {
        if point.direct {
            self.hold_with_point(f, s, ctx, free);
            return;
        }
        let Some(dl) = self.update(f.inv_inertia_sum(s), f.rel_ang_vel(s), ctx, free) else {
            return;
        };
        f.apply_angular(s, dl);
    }

    /// The new impulse for the relative spin `w` of the free turns, given the couple's
    /// inverse effective mass `k` (3×3, over all turns); returns the change to apply,
    /// `None` when the free turns do not move (both bodies static).
    ///
    /// Over the free turns' orthonormal basis `B` (3×d) the row is `Bᵀ w` with inverse
    /// effective mass `Bᵀ k B` (d×d), and `λ = −(Bᵀ k B)⁻¹ Bᵀ w`: for a hinge's axis `a`
    /// that is `−(a·w) / (aᵀ k a)`, for a plane a 2×2 solve. The accumulated impulse
    /// is taken in the free turns (a hinge's axis turns with its bodies; what lay
    /// outside them is let go).
    fn update(&mut self, k: Mat3A, w: Vec3A, ctx: &StepContext, free: FreeTurns) -> Option<Vec3A> {
        let old = Vec3A::from(self.impulse);
        let (kept, delta) = match free {
            FreeTurns::All => (old, -(invert(k)? * w)),
            FreeTurns::Axis(a) => {
                let kaa = a.dot(k * a);
                if !(kaa > 1e-20) {
                    return None;
                }
                (a * a.dot(old), a * (-a.dot(w) / kaa))
            }
            FreeTurns::Plane(n) => {
                let (u, v) = orthonormal_pair(one(n));
                let (u, v) = (Vec3A::from(u.lane(0)), Vec3A::from(v.lane(0)));
                let (ku, kv) = (k * u, k * v);
                let (k11, k12, k22) = (u.dot(ku), u.dot(kv), v.dot(kv));
                let det = k11 * k22 - k12 * k12;
                if !(det.abs() > 1e-20) {
                    return None;
                }
                let (ru, rv) = (u.dot(w), v.dot(w));
                let lu = -(k22 * ru - k12 * rv) / det;
                let lv = -(k11 * rv - k12 * ru) / det;
                (u * u.dot(old) + v * v.dot(old), u * lu + v * lv)
            }
        };
        let new = self.clamped(kept + delta, ctx);
        self.impulse = Vec3::from(new);
        Some(new - old)
    }

    /// `new` within the cap `max_torque · h`; whether it was already is `holding`.
    fn clamped(&mut self, new: Vec3A, ctx: &StepContext) -> Vec3A {
        let cap = self.max_torque * ctx.h;
        self.holding = new.length_squared() <= cap * cap;
        if self.holding {
            new
        } else {
            // `v · (1/|v|)`, as `Vec3::normalize` rounds it (`Vec3A::normalize` divides
            // each lane by `|v|`, which rounds differently).
            new * new.length_recip() * cap
        }
    }

    /// The friction of a joint whose point rows are solved exactly
    /// ([`super::joint_tree`]): the couple and the impulse `p` at the anchor that keeps
    /// the anchors' relative velocity where it was, solved together, so the couple turns
    /// the two bodies about their anchor as the exact point rows will have them turn.
    ///
    /// With `K = (m_a⁻¹ + m_b⁻¹) 1 − r̂_a I_a⁻¹ r̂_a − r̂_b I_b⁻¹ r̂_b` (the anchor's
    /// response to `p`) and `C = r̂_b I_b⁻¹ + r̂_a I_a⁻¹` (its response to `l`), `p =
    /// −K⁻¹ C l`, and the friction row's inverse effective mass is the Schur complement,
    /// `I_a⁻¹ + I_b⁻¹ − Cᵀ K⁻¹ C`. For a joint to a static body that is the inverse of
    /// the body's inertia about the anchor, `I + m (|r|² 1 − r rᵀ)` (parallel axes): a
    /// bob on a frictional hinge (`I_cm ≪ m r²`) is held in one update, where the
    /// inertias about the centres of mass took a few hundred alternations of couple and
    /// point rows.
    ///
    /// A couple alone, weighed with the inertias about the anchor, would turn each body
    /// about its centre of mass until the tree solve: the limit rows and the other
    /// joints' friction of the same iteration would read a relative spin up to
    /// `m r² / I_cm` times the one meant (a thin limb's roll) and answer it.
    fn hold_with_point(
        &mut self,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        free: FreeTurns,
    ) {
        // The offsets now, measured here: the friction is solved without the point's
        // rows (prepared on this same pose, in the relax passes too).
        let (ra, rb) = f.offsets(s);
        let (ra, rb) = (Vec3A::from(ra), Vec3A::from(rb));
        let (ia, ib) = (s.inv_inertia[f.a], s.inv_inertia[f.b]);
        let (sa, sb) = (skew(ra), skew(rb));
        // K = (m_a⁻¹ + m_b⁻¹) 1 − r̂_a I_a⁻¹ r̂_a − r̂_b I_b⁻¹ r̂_b: the anchor's response.
        let k = Mat3A::from_diagonal(glam::Vec3::splat(s.inv_mass[f.a] + s.inv_mass[f.b]))
            - sa * ia * sa
            - sb * ib * sb;
        let Some(k_inv) = invert(k) else {
            return;
        };
        // C: the anchor's response to the couple; its transpose, the couple row's
        // response to an impulse at the anchor.
        let c = sb * ib + sa * ia;
        let schur = ia + ib - c.transpose() * k_inv * c;
        let Some(dl) = self.update(schur, f.rel_ang_vel(s), ctx, free) else {
            return;
        };
        let p = -(k_inv * (c * dl));
        f.apply_angular(s, dl);
        s.apply_impulse(f.b, rb, p);
        s.apply_impulse(f.a, ra, -p);
    }
}

/// The cross-product matrix `r̂`, `r̂ x = r × x`.
fn skew(r: Vec3A) -> Mat3A {
    Mat3A::from_cols(
        Vec3A::new(0.0, r.z, -r.y),
        Vec3A::new(-r.z, 0.0, r.x),
        Vec3A::new(r.y, -r.x, 0.0),
    )
}

/// Wraps an angle into (−π, π].
#[inline]
pub fn wrap_angle(a: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    let mut a = a % TAU;
    if a > PI {
        a -= TAU;
    } else if a <= -PI {
        a += TAU;
    }
    a
}

/// Follows an angle continuously past ±π: the new raw angle is taken as the nearest
/// multiple of 2π to the previous unwrapped value.
#[inline]
pub fn unwrap_angle(previous: f32, raw: f32) -> f32 {
    previous + wrap_angle(raw - previous)
}
