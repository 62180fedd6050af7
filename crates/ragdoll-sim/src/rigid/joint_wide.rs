//! Ball joints and hinges four at a time in SIMD lanes, as the contacts are in
//! [`super::contact_rows`]: a world of many figures has the same joints many times, and
//! four figures' joints share an instruction.
//!
//! A joint's solve reads the velocities of its two bodies and writes them, so
//! Gauss–Seidel order matters only between joints that share a body. `schedule` deals
//! a joint type's joints, in their solve order, into bundles of up to four (`LANES`) in
//! which no body appears twice, each joint in a later bundle than every earlier joint
//! on its bodies: every body meets its joints in the same order as one by one, and a
//! bundle's joints touch disjoint bodies, so solving its lanes at once is solving them
//! in any order. The rows are [`super::joint_rows`]'s, the same code the joints run
//! one by one, instantiated with `f32x4`; a lane whose update one by one would do
//! nothing (a row far from its bound, a singular effective mass, a joint between
//! sleeping bodies) keeps its old values by a select. So a world solved in lanes has the
//! one-by-one solve's bits by construction, on every target: the test
//! `joints_in_lanes_give_the_bits_of_joints_one_by_one` (`rigid::world`) compares them
//! frame by frame.
//!
//! The rows live in the lanes for a whole solve: prepared there from the bodies' poses
//! and inertias, warm-started, iterated, prepared again and relaxed there. Only the limit
//! angles are measured one joint at a time (an arctangent or arccosine and the unwrapping
//! memory) and their rows copied in. The accumulated impulses are taken from the joints
//! when a solve starts and handed back when its substeps end, so a step solved island by
//! island on other threads (one by one) continues from them. Rows are prepared in the
//! lanes, not prepared one by one and loaded: loading them at every substep would cost
//! more than the lanes save.
//!
//! Only the common shapes are bundled: hinges with a hard range and no friction, ball
//! joints with a hard cone, no twist limit and no friction (a pile's humans). A type
//! with any other joint is solved one by one, as are the other joint types.

use super::ball::{BallJoint, BallRows};
use super::body::BodyStates;
use super::hinge::{HingeJoint, HingeRows};
use super::joint::{AxisRow, JointFrame, PointPart, RowKind, RowState};
use super::joint_rows::{self, AlignRows, AngularRow, PointRows, Pose};
use super::limits::{MARGIN, Swing};
use super::soft::StepContext;
use crate::lanes::{LANES, Mat3x4, Quatx4, Vec3x4, f4};
use glam::Vec3;
use wide::f32x4;

/// No joint in this lane.
const EMPTY: u32 = u32::MAX;

/// Deals joints, given by their two bodies in solve order, into bundles of up to
/// [`LANES`] with no body twice, each joint placed in the first bundle with room after
/// the bundles of the earlier joints on its bodies (list scheduling). `anchor` (the
/// world) is never written and orders nothing. Returns each bundle's joint indices,
/// [`EMPTY`] for an unused lane, in the order to solve them.
fn schedule(
    joints: impl Iterator<Item = [usize; 2]>,
    bodies: usize,
    anchor: usize,
) -> Vec<[u32; LANES]> {
    // `after[i]`: the first bundle a joint on body i may join.
    let mut after = vec![0usize; bodies.max(anchor + 1)];
    let mut bundles: Vec<[u32; LANES]> = Vec::new();
    let mut filled: Vec<usize> = Vec::new();
    // Bundles before this one are full.
    let mut first_open = 0;
    for (j, pair) in joints.enumerate() {
        let moving = pair.iter().filter(|&&i| i != anchor);
        let needs = moving.clone().map(|&i| after[i]).max().unwrap_or(0);
        let mut at = needs.max(first_open);
        while at < bundles.len() && filled[at] == LANES {
            at += 1;
        }
        if at == bundles.len() {
            bundles.push([EMPTY; LANES]);
            filled.push(0);
        }
        bundles[at][filled[at]] = j as u32;
        filled[at] += 1;
        for &i in moving {
            after[i] = at + 1;
        }
        while first_open < bundles.len() && filled[first_open] == LANES {
            first_open += 1;
        }
    }
    bundles
}

/// A lane mask from a per-lane condition (all bits set where true).
fn mask(f: impl Fn(usize) -> bool) -> f32x4 {
    f32x4::new(std::array::from_fn(|k| {
        if f(k) { f32::from_bits(u32::MAX) } else { 0.0 }
    }))
}

/// Whether lane `k` of a mask is set.
#[inline]
fn is_set(m: f32x4, k: usize) -> bool {
    m.as_array()[k].to_bits() != 0
}

/// The soft coefficients of a pass in lanes.
type Soft = joint_rows::Soft<f32x4>;
/// The velocities of a bundle's bodies.
type Velocities = joint_rows::Velocities<f32x4>;
/// The poses and world inverse inertias of a bundle's bodies.
type Bodies = Pose<f32x4>;

/// The world inverse inertias of a bundle's bodies.
#[derive(Clone, Copy, Debug, Default)]
struct Inertias {
    ia: Mat3x4,
    ib: Mat3x4,
}

/// A bundle's joints and bodies, and what holds for a whole solve.
#[derive(Clone, Copy, Debug)]
struct Lanes {
    /// The joint in each lane, [`EMPTY`] for none.
    joints: [u32; LANES],
    /// Body a and b of each lane (an unused lane repeats lane 0's and writes nothing).
    a: [usize; LANES],
    b: [usize; LANES],
    /// Set in the lanes whose joint the scalar solve would solve this step: a joint
    /// there, touching an awake body.
    live: f32x4,
    inv_mass_a: f32x4,
    inv_mass_b: f32x4,
    /// The bodies' world inverse inertias as the substep's preparation read them: they
    /// hold until the next substep refreshes them, so the relax pass, which prepares
    /// the rows again after the positions moved, reads them here.
    inertia: Inertias,
}

impl Lanes {
    fn new(joints: [u32; LANES], frame: impl Fn(usize) -> [usize; 2]) -> Lanes {
        let body = |k: usize| frame(joints[if joints[k] == EMPTY { 0 } else { k }] as usize);
        Lanes {
            joints,
            a: std::array::from_fn(|k| body(k)[0]),
            b: std::array::from_fn(|k| body(k)[1]),
            live: f32x4::ZERO,
            inv_mass_a: f32x4::ZERO,
            inv_mass_b: f32x4::ZERO,
            inertia: Inertias::default(),
        }
    }

    /// Whether every used lane's bodies are its joint's (`frame(j)`): the lanes were
    /// dealt from these joints and followed every change of their bodies' indices.
    fn names(&self, frame: impl Fn(usize) -> [usize; 2]) -> bool {
        (0..LANES)
            .filter(|&k| self.used(k))
            .all(|k| frame(self.joint(k)) == [self.a[k], self.b[k]])
    }

    /// Whether any lane's joint is solved this step.
    fn is_live(&self) -> bool {
        self.live.any()
    }

    /// Gathers the lanes' body velocities, lets `f` update them, writes them back.
    #[inline]
    fn update_velocities(&self, s: &mut BodyStates, f: impl FnOnce(&mut Velocities)) {
        let mut v = self.gather(s);
        f(&mut v);
        self.scatter(s, &v);
    }

    /// Whether lane `k` holds a joint.
    fn used(&self, k: usize) -> bool {
        self.joints[k] != EMPTY
    }

    /// The joint of lane `k`, lane 0's for an unused lane (whose results are masked).
    fn joint(&self, k: usize) -> usize {
        self.joints[if self.used(k) { k } else { 0 }] as usize
    }

    /// The sleep state and inverse masses of this step, and for a bundle with a live
    /// lane the inertias and poses its first preparation reads; `None` for a bundle
    /// without one (its figures asleep), which every pass skips until the next step's
    /// `begin`. `frame` names each joint's bodies, checked against the lanes' in debug
    /// builds.
    fn begin(
        &mut self,
        s: &BodyStates,
        awake: &[bool],
        frame: impl Fn(usize) -> [usize; 2],
    ) -> Option<Bodies> {
        debug_assert!(self.names(frame));
        let (a, b) = (self.a, self.b);
        self.live = mask(|k| self.used(k) && (awake[a[k]] || awake[b[k]]));
        self.inv_mass_a = f4(|k| s.inv_mass[a[k]]);
        self.inv_mass_b = f4(|k| s.inv_mass[b[k]]);
        if !self.is_live() {
            return None;
        }
        self.refresh_inertia(s);
        Some(self.bodies(s))
    }

    /// The poses now, with the inertias of the last [`Lanes::refresh_inertia`].
    fn bodies(&self, s: &BodyStates) -> Bodies {
        let (a, b) = (self.a, self.b);
        let Inertias { ia, ib } = self.inertia;
        Bodies {
            rot_a: Quatx4::from_fn(|k| s.rot[a[k]]),
            rot_b: Quatx4::from_fn(|k| s.rot[b[k]]),
            com_a: Vec3x4::from_fn(|k| s.com[a[k]]),
            com_b: Vec3x4::from_fn(|k| s.com[b[k]]),
            ia,
            ib,
        }
    }

    /// Reads the bodies' world inverse inertias (refreshed at each substep).
    fn refresh_inertia(&mut self, s: &BodyStates) {
        self.inertia = Inertias {
            ia: s.inv_inertia_x4(self.a),
            ib: s.inv_inertia_x4(self.b),
        };
    }

    /// The inverse masses of the lanes' bodies a and b.
    #[inline]
    fn inv_mass(&self) -> [f32x4; 2] {
        [self.inv_mass_a, self.inv_mass_b]
    }

    fn gather(&self, s: &BodyStates) -> Velocities {
        let [va, wa, vb, wb] = s.velocities_x4(self.a, self.b);
        Velocities { va, wa, vb, wb }
    }

    /// Writes the live lanes' moving bodies back (no body is in two lanes).
    fn scatter(&self, s: &mut BodyStates, v: &Velocities) {
        let masses = [self.inv_mass_a, self.inv_mass_b];
        let v = [v.va, v.wa, v.vb, v.wb];
        s.set_velocities_x4([self.a, self.b], masses, &v, |k| is_set(self.live, k));
    }
}

/// Four [`super::joint::PointPart`]s: their anchors, rows and impulses.
#[derive(Clone, Copy, Debug, Default)]
struct PointX4 {
    /// The anchor in each body's space (the joints' frames).
    local_a: Vec3x4,
    local_b: Vec3x4,
    impulse: Vec3x4,
    rows: PointRows<f32x4>,
    /// Live lanes whose joint's point rows a joint tree solves ([`super::joint_tree`]):
    /// the lanes prepare and warm-start them but leave their solve to the tree, which
    /// owns their impulse (in the joint) meanwhile.
    direct: f32x4,
    /// Live lanes whose joint is in a tree of this solve (a superset of `direct`: a
    /// tree whose factorisation failed hands its rows back to the lanes until it
    /// succeeds again).
    in_tree: f32x4,
}

impl PointX4 {
    /// The point constraints of the lanes' joint frames, before any preparation.
    fn at<'a>(frame: impl Fn(usize) -> &'a JointFrame) -> PointX4 {
        PointX4 {
            local_a: Vec3x4::from_fn(|k| frame(k).local_a),
            local_b: Vec3x4::from_fn(|k| frame(k).local_b),
            ..PointX4::default()
        }
    }

    fn prepare(&mut self, l: &Lanes, p: &Bodies) {
        let local = [self.local_a, self.local_b];
        self.rows.prepare(local, p, l.inv_mass(), l.live);
    }

    fn weigh(&mut self, l: &Lanes, ia: Mat3x4, ib: Mat3x4) {
        self.rows.weigh([ia, ib], l.inv_mass(), l.live);
    }

    fn warm_start(&self, v: &mut Velocities, l: &Lanes) {
        self.rows.apply(v, l.inv_mass(), self.impulse, l.live);
    }

    #[inline]
    fn solve(&mut self, v: &mut Velocities, l: &Lanes, soft: &Soft) {
        let on = self.rows.on & !self.direct;
        self.rows
            .solve(v, l.inv_mass(), &mut self.impulse, soft, on);
    }

    /// Follows the joints' `direct` flags (set when the trees are built and factored):
    /// a lane leaving a tree takes its impulse back from the joint, a lane joining one
    /// hands it over, so the impulse is where it is solved.
    fn sync_direct<J: Pointed>(&mut self, l: &Lanes, joints: &mut [J]) {
        let now = mask(|k| is_set(l.live, k) && joints[l.joint(k)].point().direct);
        if now.to_bitmask() == self.direct.to_bitmask() {
            return;
        }
        let mut impulse: [Vec3; LANES] = std::array::from_fn(|k| self.impulse.lane(k));
        for k in (0..LANES).filter(|&k| is_set(l.live, k)) {
            let point = joints[l.joint(k)].point_mut();
            match (is_set(self.direct, k), is_set(now, k)) {
                (true, false) => impulse[k] = point.impulse,
                (false, true) => point.impulse = impulse[k],
                _ => {}
            }
        }
        self.impulse = Vec3x4::from_fn(|k| impulse[k]);
        self.direct = now;
    }

    /// Takes the tree-solved lanes' impulses from their joints (for the warm start).
    fn take_direct<J: Pointed>(&mut self, l: &Lanes, joints: &[J]) {
        if self.direct.any() {
            let from = Vec3x4::from_fn(|k| joints[l.joint(k)].point().impulse);
            self.impulse = Vec3x4::select(self.direct, from, self.impulse);
        }
    }

    /// Copies the rows of the lanes in a tree to their joints' rows (`rows`, by joint):
    /// the tree reads them there, and they are the rows the one-by-one code prepares
    /// (the same code).
    fn hand_rows_to_trees<R: WithPoint>(&self, l: &Lanes, rows: &mut [R]) {
        if self.in_tree.any() {
            for k in (0..LANES).filter(|&k| is_set(self.in_tree, k)) {
                *rows[l.joint(k)].point_mut() = self.rows.lane(k);
            }
        }
    }
}

/// The rows of a joint type the lanes bundle: they hold its point rows.
trait WithPoint {
    fn point_mut(&mut self) -> &mut PointRows<f32>;
}

impl WithPoint for BallRows {
    fn point_mut(&mut self) -> &mut PointRows<f32> {
        &mut self.point
    }
}

impl WithPoint for HingeRows {
    fn point_mut(&mut self) -> &mut PointRows<f32> {
        &mut self.point
    }
}

/// A joint type the lanes bundle: it has a point constraint.
trait Pointed {
    fn point(&self) -> &PointPart;
    fn point_mut(&mut self) -> &mut PointPart;
}

impl Pointed for BallJoint {
    fn point(&self) -> &PointPart {
        &self.point
    }
    fn point_mut(&mut self) -> &mut PointPart {
        &mut self.point
    }
}

impl Pointed for HingeJoint {
    fn point(&self) -> &PointPart {
        &self.point
    }
    fn point_mut(&mut self) -> &mut PointPart {
        &mut self.point
    }
}

/// Four [`super::joint::AlignPart`]s: their directions, rows and impulses.
#[derive(Clone, Copy, Debug, Default)]
struct AlignX4 {
    /// The direction in each body's space.
    local_a: Vec3x4,
    local_b: Vec3x4,
    impulse: [f32x4; 2],
    rows: AlignRows<f32x4>,
}

impl AlignX4 {
    fn prepare(&mut self, l: &Lanes, p: &Bodies) {
        self.rows.prepare([self.local_a, self.local_b], p, l.live);
    }

    fn weigh(&mut self, l: &Lanes, ia: Mat3x4, ib: Mat3x4) {
        self.rows.weigh([ia, ib], l.live);
    }

    fn warm_start(&self, v: &mut Velocities, l: &Lanes) {
        self.rows.apply(v, self.impulse, l.live);
    }

    #[inline]
    fn solve(&mut self, v: &mut Velocities, soft: &Soft) {
        self.rows.solve(v, &mut self.impulse, soft);
    }
}

/// Four hard-limit [`AxisRow`]s, set one by one (the angle is measured there) and
/// copied in.
#[derive(Clone, Copy, Debug, Default)]
struct RowX4 {
    impulse: f32x4,
    row: AngularRow<f32x4>,
}

impl RowX4 {
    /// Copies the rows just set one by one in the live lanes; a row set inactive has
    /// dropped its impulse.
    fn copy(&mut self, l: &Lanes, row: impl Fn(usize) -> AxisRow) {
        let live = (0..LANES).filter(|&k| is_set(l.live, k));
        if live.clone().all(|k| !row(k).active) {
            // Most rows are far from their bounds: nothing to solve or warm-start, and
            // the unused lanes' axes and turns are never read.
            self.impulse = l.live.select(f32x4::ZERO, self.impulse);
            self.row.active = f32x4::ZERO;
            self.row.on = f32x4::ZERO;
            return;
        }
        let mut impulse = *self.impulse.as_array();
        let (mut axis, mut c, mut m) = ([Vec3::ZERO; LANES], [0.0; LANES], [0.0; LANES]);
        let mut turn = [[Vec3::ZERO; LANES]; 2];
        let (mut active, mut on) = ([false; LANES], [false; LANES]);
        for k in live {
            let r = row(k);
            axis[k] = r.axis;
            c[k] = r.c;
            active[k] = r.active;
            if r.active {
                m[k] = 1.0 / r.k;
                turn[0][k] = Vec3::from(r.turn[0]);
                turn[1][k] = Vec3::from(r.turn[1]);
                on[k] = r.k > 1e-20;
            } else {
                impulse[k] = 0.0;
            }
        }
        self.impulse = f32x4::new(impulse);
        self.row = AngularRow {
            axis: Vec3x4::from_fn(|k| axis[k]),
            c: f32x4::new(c),
            m: f32x4::new(m),
            turn: turn.map(|t| Vec3x4::from_fn(|k| t[k])),
            active: mask(|k| active[k]),
            on: mask(|k| on[k]),
        };
    }

    fn warm_start(&self, v: &mut Velocities) {
        self.row.warm_start(v, self.impulse);
    }

    /// A [`RowKind::Limit`] row's update.
    #[inline]
    fn solve(&mut self, v: &mut Velocities, soft: &Soft) {
        self.row.solve(v, &mut self.impulse, soft, true);
    }
}

/// Four hinges: range rows, axis alignment, point, in [`HingeJoint`]'s order.
#[derive(Clone, Debug)]
struct HingeX4 {
    lanes: Lanes,
    limit: [RowX4; 2],
    align: AlignX4,
    point: PointX4,
}

/// Four ball joints: cone row, point, in [`BallJoint`]'s order.
#[derive(Clone, Debug)]
struct BallX4 {
    lanes: Lanes,
    cone: RowX4,
    point: PointX4,
    /// The cones' axes in b and shafts in a.
    axis_b: Vec3x4,
    shaft_a: Vec3x4,
    /// A shaft whose cosine with the axis exceeds this is far inside its cone
    /// (see [`JointLanes::update_limits`]).
    cos_far: f32x4,
}

/// Margin (rad) by which a shaft must be inside the angle at which its cone's row wakes
/// for the measurement to be skipped: far more than the arccosine's rounding, even at a
/// cosine near 1, where the angle is least well conditioned (about 3e-4 rad per ulp).
const FAR_SLACK: f32 = 0.01;

/// A hinge the lanes solve: a hard range, no friction.
fn hinge_fits(j: &HingeJoint) -> bool {
    j.friction.max_torque <= 0.0 && j.limit.is_some_and(|l| l.kind == RowKind::Limit)
}

/// A ball joint the lanes solve: a hard cone, no twist limit, no friction.
fn ball_fits(j: &BallJoint) -> bool {
    j.friction.max_torque <= 0.0
        && j.twist.is_none()
        && matches!(j.swing, Some(Swing::Cone { row, .. }) if row.kind == RowKind::Limit)
}

/// The cone row's state of a ball joint that [`ball_fits`].
fn cone_state(j: &BallJoint) -> RowState {
    match &j.swing {
        Some(Swing::Cone { row, .. }) => *row,
        _ => unreachable!("ball_fits checked the cone"),
    }
}

fn cone_state_mut(j: &mut BallJoint) -> &mut RowState {
    match &mut j.swing {
        Some(Swing::Cone { row, .. }) => row,
        _ => unreachable!("ball_fits checked the cone"),
    }
}

/// The world's ball joints and hinges in bundles of four, and their rows while a solve
/// runs.
#[derive(Clone, Debug, Default)]
pub struct JointLanes {
    /// The ball joints' bundles, empty when they are solved one by one.
    balls: Vec<BallX4>,
    /// The hinges' bundles, likewise.
    hinges: Vec<HingeX4>,
    /// How many joints of each type the bundles were dealt from.
    planned: [usize; 2],
}

impl JointLanes {
    /// Bundles for the types whose every joint the lanes can solve; `None` when neither
    /// type has enough joints to fill two bundles.
    pub fn plan(
        balls: &[BallJoint],
        hinges: &[HingeJoint],
        bodies: usize,
        anchor: usize,
    ) -> Option<JointLanes> {
        let worth = |n: usize| n >= 2 * LANES;
        let mut lanes = JointLanes {
            planned: [balls.len(), hinges.len()],
            ..JointLanes::default()
        };
        if worth(balls.len()) && balls.iter().all(ball_fits) {
            let frame = |j: usize| [balls[j].frame.a, balls[j].frame.b];
            for joints in schedule((0..balls.len()).map(frame), bodies, anchor) {
                let l = Lanes::new(joints, frame);
                let j = |k: usize| &balls[l.joint(k)];
                let point = PointX4::at(|k| &j(k).frame);
                let cone = |k: usize| match j(k).swing {
                    Some(Swing::Cone {
                        axis_b,
                        shaft_a,
                        half_angle,
                        ..
                    }) => (axis_b, shaft_a, half_angle),
                    _ => unreachable!("ball_fits checked the cone"),
                };
                // The row wakes at `C = half − φ < MARGIN`; far inside is
                // `φ < half − MARGIN − FAR_SLACK`, a cosine above that angle's.
                let far = |k: usize| {
                    let angle = cone(k).2 - MARGIN - FAR_SLACK;
                    if angle > 0.0 {
                        angle.cos()
                    } else {
                        f32::INFINITY
                    }
                };
                lanes.balls.push(BallX4 {
                    lanes: l,
                    cone: RowX4::default(),
                    point,
                    axis_b: Vec3x4::from_fn(|k| cone(k).0),
                    shaft_a: Vec3x4::from_fn(|k| cone(k).1),
                    cos_far: f4(far),
                });
            }
        }
        if worth(hinges.len()) && hinges.iter().all(hinge_fits) {
            let frame = |j: usize| [hinges[j].frame.a, hinges[j].frame.b];
            for joints in schedule((0..hinges.len()).map(frame), bodies, anchor) {
                let l = Lanes::new(joints, frame);
                let j = |k: usize| &hinges[l.joint(k)];
                let point = PointX4::at(|k| &j(k).frame);
                let align = AlignX4 {
                    local_a: Vec3x4::from_fn(|k| j(k).align.local_a),
                    local_b: Vec3x4::from_fn(|k| j(k).align.local_b),
                    ..AlignX4::default()
                };
                lanes.hinges.push(HingeX4 {
                    lanes: l,
                    limit: [RowX4::default(); 2],
                    align,
                    point,
                });
            }
        }
        (!lanes.balls.is_empty() || !lanes.hinges.is_empty()).then_some(lanes)
    }

    /// Whether the ball joints are solved in lanes.
    pub fn has_balls(&self) -> bool {
        !self.balls.is_empty()
    }

    /// Whether the hinges are solved in lanes.
    pub fn has_hinges(&self) -> bool {
        !self.hinges.is_empty()
    }

    /// Moves the lanes' references to the static anchor from index `old` to `new`.
    pub fn retarget_anchor(&mut self, old: usize, new: usize) {
        let lanes = self.balls.iter_mut().map(|b| &mut b.lanes);
        for l in lanes.chain(self.hinges.iter_mut().map(|h| &mut h.lanes)) {
            for b in &mut l.b {
                if *b == old {
                    *b = new;
                }
            }
        }
    }

    /// Whether these bundles were dealt from joint arrays of these lengths.
    pub fn fits(&self, balls: &[BallJoint], hinges: &[HingeJoint]) -> bool {
        self.planned == [balls.len(), hinges.len()]
    }

    /// The first substep's preparation: the step's sleep states and inverse masses, the
    /// joints' accumulated impulses, the rows on the poses and inertias now.
    pub fn prepare(
        &mut self,
        balls: &mut [BallJoint],
        hinges: &mut [HingeJoint],
        (ball_rows, hinge_rows): (&mut [BallRows], &mut [HingeRows]),
        s: &BodyStates,
        awake: &[bool],
    ) {
        for b in &mut self.balls {
            let frame = |j: usize| [balls[j].frame.a, balls[j].frame.b];
            let Some(p) = b.lanes.begin(s, awake, frame) else {
                continue;
            };
            let j = |k: usize| &balls[b.lanes.joint(k)];
            b.point.impulse = Vec3x4::from_fn(|k| j(k).point.impulse);
            b.cone.impulse = f4(|k| cone_state(j(k)).impulse);
            b.point.direct = mask(|k| is_set(b.lanes.live, k) && j(k).point.direct);
            b.point.in_tree = mask(|k| is_set(b.lanes.live, k) && j(k).point.in_tree);
            b.point.prepare(&b.lanes, &p);
            b.point.hand_rows_to_trees(&b.lanes, ball_rows);
        }
        for h in &mut self.hinges {
            let frame = |j: usize| [hinges[j].frame.a, hinges[j].frame.b];
            let Some(p) = h.lanes.begin(s, awake, frame) else {
                continue;
            };
            let j = |k: usize| &hinges[h.lanes.joint(k)];
            h.point.impulse = Vec3x4::from_fn(|k| j(k).point.impulse);
            h.align.impulse = [0, 1].map(|r| f4(|k| j(k).align.impulse[r]));
            for (r, row) in h.limit.iter_mut().enumerate() {
                row.impulse = f4(|k| limit_impulses(j(k))[r]);
            }
            h.point.direct = mask(|k| is_set(h.lanes.live, k) && j(k).point.direct);
            h.point.in_tree = mask(|k| is_set(h.lanes.live, k) && j(k).point.in_tree);
            h.point.prepare(&h.lanes, &p);
            h.point.hand_rows_to_trees(&h.lanes, hinge_rows);
            h.align.prepare(&h.lanes, &p);
        }
        self.update_limits(balls, hinges, (ball_rows, hinge_rows), s);
    }

    /// A later substep's preparation, on the pose the relax passes' rows were prepared on:
    /// the turns and effective masses with the inertias now, and the limit rows.
    pub fn prepare_after_relax(
        &mut self,
        balls: &mut [BallJoint],
        hinges: &mut [HingeJoint],
        (ball_rows, hinge_rows): (&mut [BallRows], &mut [HingeRows]),
        s: &BodyStates,
    ) {
        for b in self.balls.iter_mut().filter(|x| x.lanes.is_live()) {
            b.lanes.refresh_inertia(s);
            let Inertias { ia, ib } = b.lanes.inertia;
            b.point.weigh(&b.lanes, ia, ib);
            b.point.hand_rows_to_trees(&b.lanes, ball_rows);
        }
        for h in self.hinges.iter_mut().filter(|x| x.lanes.is_live()) {
            h.lanes.refresh_inertia(s);
            let Inertias { ia, ib } = h.lanes.inertia;
            h.point.weigh(&h.lanes, ia, ib);
            h.point.hand_rows_to_trees(&h.lanes, hinge_rows);
            h.align.weigh(&h.lanes, ia, ib);
        }
        self.update_limits(balls, hinges, (ball_rows, hinge_rows), s);
    }

    /// The relax passes' point and axis rows, prepared on the pose the substep moved to
    /// (see `JointSolve::prepare_moved`), and the point rows of the lanes in a tree
    /// handed to their joints' rows, for the tree's factorisation.
    pub fn prepare_moved(
        &mut self,
        (ball_rows, hinge_rows): (&mut [BallRows], &mut [HingeRows]),
        s: &BodyStates,
    ) {
        for b in self.balls.iter_mut().filter(|x| x.lanes.is_live()) {
            b.point.prepare(&b.lanes, &b.lanes.bodies(s));
            b.point.hand_rows_to_trees(&b.lanes, ball_rows);
        }
        for h in self.hinges.iter_mut().filter(|x| x.lanes.is_live()) {
            let p = h.lanes.bodies(s);
            h.align.prepare(&h.lanes, &p);
            h.point.prepare(&h.lanes, &p);
            h.point.hand_rows_to_trees(&h.lanes, hinge_rows);
        }
    }

    /// Measures the live joints' limits one by one and copies their rows in.
    ///
    /// A cone's row is measured with an arccosine, a normalisation and the row's turns,
    /// but most shafts are far inside their cones, where the row only sleeps: the cosine
    /// of the shaft with the axis, formed in the lanes (glam's rotations and dot
    /// product, the scalar measurement's own cosine), tells those apart and they are set
    /// asleep as the measurement would (the angle and axis of a sleeping row are never
    /// read).
    fn update_limits(
        &mut self,
        balls: &mut [BallJoint],
        hinges: &mut [HingeJoint],
        (ball_rows, hinge_rows): (&mut [BallRows], &mut [HingeRows]),
        s: &BodyStates,
    ) {
        for b in self.balls.iter_mut().filter(|x| x.lanes.is_live()) {
            let (a, bb) = (b.lanes.a, b.lanes.b);
            let axis = Quatx4::from_fn(|k| s.rot[bb[k]]).rotate_as_glam(b.axis_b);
            let shaft = Quatx4::from_fn(|k| s.rot[a[k]]).rotate_as_glam(b.shaft_a);
            let far = axis.dot(shaft).simd_gt(b.cos_far);
            for k in (0..LANES).filter(|&k| is_set(b.lanes.live, k)) {
                let i = b.lanes.joints[k] as usize;
                let (j, rows) = (&mut balls[i], &mut ball_rows[i]);
                if is_set(far, k) {
                    rows.swing.axis_mut()[0].active = false;
                    cone_state_mut(j).impulse = 0.0;
                } else if let Some(sw) = &mut j.swing {
                    sw.update(&mut rows.swing, &j.frame, s);
                }
            }
            let rows = |k: usize| &ball_rows[b.lanes.joints[k] as usize];
            b.cone.copy(&b.lanes, |k| rows(k).swing.first());
        }
        for h in self.hinges.iter_mut().filter(|x| x.lanes.is_live()) {
            for k in (0..LANES).filter(|&k| is_set(h.lanes.live, k)) {
                let i = h.lanes.joints[k] as usize;
                let j = &mut hinges[i];
                if let Some(l) = &mut j.limit {
                    l.update(&mut hinge_rows[i].limit, &j.frame, s);
                }
            }
            let rows = |k: usize| &hinge_rows[h.lanes.joints[k] as usize];
            for (r, row) in h.limit.iter_mut().enumerate() {
                row.copy(&h.lanes, |k| rows(k).limit[r]);
            }
        }
    }

    /// Re-applies the accumulated impulses of the ball joints, in their scalar order
    /// (`trees`: some joints' point rows are solved by a tree, see
    /// [`PointX4::sync_direct`]).
    pub fn warm_start_balls(&mut self, s: &mut BodyStates, balls: &mut [BallJoint], trees: bool) {
        for b in self.balls.iter_mut().filter(|x| x.lanes.is_live()) {
            if trees {
                b.point.sync_direct(&b.lanes, balls);
                b.point.take_direct(&b.lanes, balls);
            }
            b.lanes.update_velocities(s, |v| {
                b.cone.warm_start(v);
                b.point.warm_start(v, &b.lanes);
            });
        }
    }

    /// Re-applies the accumulated impulses of the hinges, in their scalar order.
    pub fn warm_start_hinges(
        &mut self,
        s: &mut BodyStates,
        hinges: &mut [HingeJoint],
        trees: bool,
    ) {
        for h in self.hinges.iter_mut().filter(|x| x.lanes.is_live()) {
            if trees {
                h.point.sync_direct(&h.lanes, hinges);
                h.point.take_direct(&h.lanes, hinges);
            }
            h.lanes.update_velocities(s, |v| {
                h.limit[0].warm_start(v);
                h.limit[1].warm_start(v);
                h.align.warm_start(v, &h.lanes);
                h.point.warm_start(v, &h.lanes);
            });
        }
    }

    /// One iteration over the ball joints (the relax pass, `use_bias` false, on the rows
    /// of [`JointLanes::prepare_moved`]).
    pub fn solve_balls(
        &mut self,
        s: &mut BodyStates,
        balls: &mut [BallJoint],
        trees: bool,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        let soft = Soft::new(ctx, use_bias);
        for b in self.balls.iter_mut().filter(|x| x.lanes.is_live()) {
            // The trees are factored (and `direct` may change) only before the warm
            // start and between the relax passes.
            if trees && !use_bias {
                b.point.sync_direct(&b.lanes, balls);
            }
            b.lanes.update_velocities(s, |v| {
                b.cone.solve(v, &soft);
                b.point.solve(v, &b.lanes, &soft);
            });
        }
    }

    /// One iteration over the hinges (the relax pass on the rows of
    /// [`JointLanes::prepare_moved`]).
    pub fn solve_hinges(
        &mut self,
        s: &mut BodyStates,
        hinges: &mut [HingeJoint],
        trees: bool,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        let soft = Soft::new(ctx, use_bias);
        for h in self.hinges.iter_mut().filter(|x| x.lanes.is_live()) {
            if trees && !use_bias {
                h.point.sync_direct(&h.lanes, hinges);
            }
            h.lanes.update_velocities(s, |v| {
                h.limit[0].solve(v, &soft);
                h.limit[1].solve(v, &soft);
                h.align.solve(v, &soft);
                h.point.solve(v, &h.lanes, &soft);
            });
        }
    }

    /// Hands the accumulated impulses back to the joints (after a solve's substeps), for
    /// the next step's warm start wherever it is solved.
    pub fn finish(&self, balls: &mut [BallJoint], hinges: &mut [HingeJoint]) {
        for b in self.balls.iter().filter(|x| x.lanes.is_live()) {
            for k in (0..LANES).filter(|&k| is_set(b.lanes.live, k)) {
                let j = &mut balls[b.lanes.joints[k] as usize];
                if !is_set(b.point.direct, k) {
                    j.point.impulse = b.point.impulse.lane(k);
                }
                cone_state_mut(j).impulse = b.cone.impulse.as_array()[k];
            }
        }
        for h in self.hinges.iter().filter(|x| x.lanes.is_live()) {
            for k in (0..LANES).filter(|&k| is_set(h.lanes.live, k)) {
                let j = &mut hinges[h.lanes.joints[k] as usize];
                if !is_set(h.point.direct, k) {
                    j.point.impulse = h.point.impulse.lane(k);
                }
                j.align.impulse = h.align.impulse.map(|i| i.as_array()[k]);
                let limit = j.limit.as_mut().expect("hinge_fits checked the range");
                for (impulse, lanes) in limit.impulse.iter_mut().zip(&h.limit) {
                    *impulse = lanes.impulse.as_array()[k];
                }
            }
        }
    }
}

/// The range rows' accumulated impulses of a hinge that [`hinge_fits`].
fn limit_impulses(j: &HingeJoint) -> [f32; 2] {
    j.limit
        .as_ref()
        .expect("hinge_fits checked the range")
        .impulse
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every joint is dealt once, no bundle holds a moving body twice, and each body
    /// meets its joints in their order.
    #[test]
    fn schedule_keeps_each_bodys_order() {
        let anchor = 9;
        let joints: Vec<[usize; 2]> = vec![
            [0, 1],
            [1, 2],
            [3, 4],
            [5, 6],
            [7, 8],
            [2, 3],
            [0, anchor],
            [4, anchor],
            [6, 7],
            [1, 5],
        ];
        let bundles = schedule(joints.iter().copied(), 9, anchor);
        let mut seen = vec![false; joints.len()];
        let mut order: Vec<Vec<usize>> = vec![Vec::new(); 10];
        for bundle in &bundles {
            let mut bodies = Vec::new();
            for &j in bundle.iter().filter(|&&j| j != EMPTY) {
                assert!(!seen[j as usize], "joint {j} dealt twice");
                seen[j as usize] = true;
                for &i in joints[j as usize].iter().filter(|&&i| i != anchor) {
                    assert!(!bodies.contains(&i), "body {i} twice in one bundle");
                    bodies.push(i);
                    order[i].push(j as usize);
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "a joint was not dealt");
        for (i, js) in order.iter().enumerate() {
            assert!(js.windows(2).all(|w| w[0] < w[1]), "body {i} meets {js:?}");
        }
    }
}
