//! All joints of a world, in one array per joint type (Box2D/Jolt style: no pointers,
//! no virtual calls in the inner loops), built from the scene's constraints.

use super::ball::{BallJoint, BallRows};
use super::body::{BodyInfo, BodyStates, Motions};
use super::fixed::FixedJoint;
use super::hinge::{HingeJoint, HingeRows};
use super::joint::{
    AlignPart, AngularLock3, FreeTurns, FrictionMotor, JointFrame, JointSolve, PointPart, RowKind,
    RowState,
};
use super::joint_rows::PointRows;
use super::joint_wide::JointLanes;
use super::limits::{AngleLimit, Swing};
use super::project::{PairPose, keep_pair_momentum};
use super::slider::SliderJoint;
use super::soft::StepContext;
use super::spring::SpringJoint;
use super::universal::{UniversalJoint, UniversalRows};
use crate::scene::{BodyRef, ConstraintDesc, JointKind, LimitStyle};
use crate::snapshot::{JointInstance, LimitShape};

/// Every joint, by type.
#[derive(Clone, Debug, Default)]
pub struct JointSet {
    /// Ball-and-socket joints.
    pub ball: Vec<BallJoint>,
    /// Hinges.
    pub hinge: Vec<HingeJoint>,
    /// Universal joints.
    pub universal: Vec<UniversalJoint>,
    /// Fixed joints.
    pub fixed: Vec<FixedJoint>,
    /// Sliders.
    pub slider: Vec<SliderJoint>,
    /// Springs.
    pub spring: Vec<SpringJoint>,
    /// The rows the solve of these arrays prepares for their joints, by type
    /// ([`JointSolve::Rows`]): one entry per joint the solve moves (touching an awake
    /// body), in the joints' order, sized by [`JointSet::prepare`] and read only within
    /// a solve; a type solved in lanes has one per joint (the lanes address them by
    /// joint). The world's arrays fill theirs only when solved in place; solved in
    /// batches ([`super::parallel`]), each batch's gathered arrays hold the rows of its
    /// own joints, and the world's stay empty.
    pub(crate) rows: JointRows,
    /// The ball joints and hinges in SIMD lanes ([`super::joint_wide`]), planned by the
    /// first solve of the whole set that would use them ([`JointSet::prepare`]); `None`
    /// (and in the arrays gathered for one island) solves each joint alone.
    pub lanes: Option<JointLanes>,
    /// The static anchor's index while the lanes are still to be planned. A world whose
    /// trees hold most point rows (a pile of humans, whose necks join light heads to
    /// heavy chests) never solves in lanes, and the bundles cost about as many bytes as
    /// the joints themselves; the lanes hold no state between steps (they take the
    /// joints' impulses at each `prepare`), so planned late they are planned the same.
    pub lanes_to_plan: Option<usize>,
    /// Some point rows are solved by [`super::joint_tree`] this solve: the lanes leave
    /// those rows to the trees (set by `JointTrees::build` before the substeps).
    pub direct: bool,
    /// How many joints' point rows the trees of this solve hold (set with `direct`).
    pub tree_points: usize,
    /// How many ball joints, hinges and universal joints touch a moving body this solve
    /// (set with `direct`).
    pub live_points: usize,
}

/// The rows a solve prepares for its joints ([`JointSolve::Rows`]), one array per joint
/// type. A type solved one by one has an entry for each joint that touches an awake
/// body, in joint order: the solve walks those joints and their rows side by side, and
/// a world whose bodies mostly sleep holds rows for the few that move. A type solved in
/// lanes ([`JointSet::lanes`]) has an entry for each joint, at the joint's index.
#[derive(Clone, Debug, Default)]
pub(crate) struct JointRows {
    pub ball: Vec<BallRows>,
    pub hinge: Vec<HingeRows>,
    pub universal: Vec<UniversalRows>,
    pub fixed: Vec<PointRows<f32>>,
    pub slider: Vec<()>,
    pub spring: Vec<()>,
    /// Per ball joint, hinge and universal joint (in that order of the arrays), the
    /// index of its rows in its type's array, [`NO_ROWS`] for a joint without: the
    /// joint trees read a joint's point rows by joint ([`super::joint_tree`]). Filled
    /// only while a solve has trees.
    pub slots: [Vec<u32>; 3],
}

/// A joint without rows in this solve ([`JointRows::slots`]).
pub(crate) const NO_ROWS: u32 = u32::MAX;

/// The rows a projection pass over the joints moves ([`JointSet::project`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProjectedRows {
    /// Every rigid row: limits, alignments, locks, then the point.
    All,
    /// The point rows alone.
    Points,
}

/// Runs `$body` with `$j` bound to every joint, mutably (fields, not the solve trait).
macro_rules! for_each_joint_mut {
    ($set:expr, $j:ident => $body:expr) => {{
        $set.ball.iter_mut().for_each(|$j| $body);
        $set.hinge.iter_mut().for_each(|$j| $body);
        $set.universal.iter_mut().for_each(|$j| $body);
        $set.fixed.iter_mut().for_each(|$j| $body);
        $set.slider.iter_mut().for_each(|$j| $body);
        $set.spring.iter_mut().for_each(|$j| $body);
    }};
}

/// Runs `$body` with `$list` bound to each type's array and `$rows` to its rows (an
/// entry per joint touching an awake body, see [`JointRows`]), ball joints and hinges
/// only when `$balls` / `$hinges` (solved in lanes) are false.
macro_rules! for_each_type {
    ($set:expr, $balls:expr, $hinges:expr, ($list:ident, $rows:ident) => $body:expr) => {{
        if !$balls {
            let ($list, $rows) = (&mut $set.ball, &mut $set.rows.ball);
            $body
        }
        if !$hinges {
            let ($list, $rows) = (&mut $set.hinge, &mut $set.rows.hinge);
            $body
        }
        let ($list, $rows) = (&mut $set.universal, &mut $set.rows.universal);
        $body
        let ($list, $rows) = (&mut $set.fixed, &mut $set.rows.fixed);
        $body
        let ($list, $rows) = (&mut $set.slider, &mut $set.rows.slider);
        $body
        let ($list, $rows) = (&mut $set.spring, &mut $set.rows.spring);
        $body
    }};
}

/// Runs `$body` with `$j` bound to every joint, read-only.
macro_rules! for_each_joint_ref {
    ($set:expr, $j:ident => $body:expr) => {{
        for $j in $set.ball.iter() {
            $body
        }
        for $j in $set.hinge.iter() {
            $body
        }
        for $j in $set.universal.iter() {
            $body
        }
        for $j in $set.fixed.iter() {
            $body
        }
        for $j in $set.slider.iter() {
            $body
        }
        for $j in $set.spring.iter() {
            $body
        }
    }};
}

impl JointSet {
    /// Builds the joints of `constraints` on bodies at their rest pose. `anchor` is the
    /// index of the static anchor (the world).
    pub fn build(
        constraints: &[ConstraintDesc],
        s: &BodyStates,
        info: &[BodyInfo],
        anchor: usize,
        g: f32,
    ) -> JointSet {
        let mut set = JointSet::default();
        // Each array holds exactly its joints: they are never added to after the build,
        // and a hinge or ball joint keeps its rows (several hundred bytes), so an array
        // doubled while pushing would hold up to as many again for good.
        let count = |is: fn(&JointKind) -> bool| constraints.iter().filter(|c| is(&c.kind)).count();
        set.ball
            .reserve_exact(count(|k| matches!(k, JointKind::BallAndSocket { .. })));
        set.hinge
            .reserve_exact(count(|k| matches!(k, JointKind::Hinge { .. })));
        set.universal
            .reserve_exact(count(|k| matches!(k, JointKind::Universal { .. })));
        set.fixed
            .reserve_exact(count(|k| matches!(k, JointKind::Fixed)));
        set.slider
            .reserve_exact(count(|k| matches!(k, JointKind::Slider { .. })));
        set.spring
            .reserve_exact(count(|k| matches!(k, JointKind::Spring { .. })));
        for c in constraints {
            let a = c.body1.index();
            let b = match c.body2 {
                BodyRef::Body(id) => id.index(),
                BodyRef::World => anchor,
            };
            let friction = |frame: &JointFrame| {
                FrictionMotor::new(c.friction, info[a].mass, frame.local_a.length(), g)
            };
            match &c.kind {
                JointKind::BallAndSocket {
                    anchor: p,
                    swing,
                    twist,
                    limit_style,
                } => {
                    let frame = JointFrame::new(s, a, b, *p);
                    set.ball.push(BallJoint {
                        frame,
                        point: PointPart::default(),
                        swing: swing.map(|l| Swing::new(&frame, s, &l, *limit_style)),
                        twist: twist.map(|t| AngleLimit::twist(&frame, s, &t, *limit_style)),
                        friction: friction(&frame),
                    });
                }
                JointKind::Hinge {
                    anchor: p,
                    axis,
                    limit,
                } => {
                    let frame = JointFrame::new(s, a, b, *p);
                    set.hinge.push(HingeJoint {
                        frame,
                        point: PointPart::default(),
                        align: AlignPart::new(&frame, s, *axis),
                        limit: limit
                            .map(|r| AngleLimit::new(&frame, s, *axis, r, LimitStyle::Hard)),
                        friction: friction(&frame),
                    });
                }
                JointKind::Universal {
                    anchor: p,
                    shaft1,
                    shaft2,
                    swing,
                    axis_ranges,
                } => {
                    let frame = JointFrame::new(s, a, b, *p);
                    set.universal.push(UniversalJoint {
                        frame,
                        point: PointPart::default(),
                        shaft_a: frame.dir_in_a(s, *shaft1),
                        shaft_b: frame.dir_in_b(s, *shaft2),
                        rest_dot: shaft1.dot(*shaft2),
                        cross_row: RowState::new(RowKind::Equality),
                        swing: swing.map(|l| Swing::new(&frame, s, &l, LimitStyle::Hard)),
                        ranges: axis_ranges.map(|r| {
                            [
                                AngleLimit::new(&frame, s, *shaft1, r[0], LimitStyle::Hard),
                                AngleLimit::new(&frame, s, *shaft2, r[1], LimitStyle::Hard)
                                    .about_body2(),
                            ]
                        }),
                        friction: friction(&frame),
                    });
                }
                JointKind::Fixed => {
                    let frame = JointFrame::new(s, a, b, s.com[a]);
                    set.fixed.push(FixedJoint {
                        frame,
                        point: PointPart::default(),
                        lock: AngularLock3::new(&frame, s),
                    });
                }
                JointKind::Slider { axis } => {
                    let frame = JointFrame::new(s, a, b, s.com[a]);
                    set.slider.push(SliderJoint {
                        frame,
                        axis_b: frame.dir_in_b(s, *axis),
                        impulse: [0.0; 2],
                        lock: AngularLock3::new(&frame, s),
                    });
                }
                JointKind::Spring {
                    anchor1,
                    anchor2,
                    stretch,
                    compress,
                    damping,
                    rest_length,
                    min_length,
                    max_length,
                } => {
                    let mut frame = JointFrame::new(s, a, b, *anchor1);
                    frame.local_b = s.rot[b].inverse() * (*anchor2 - s.com[b]);
                    set.spring.push(SpringJoint {
                        frame,
                        stretch: *stretch,
                        compress: *compress,
                        damping: *damping,
                        rest_length: *rest_length,
                        min_length: *min_length,
                        max_length: *max_length,
                        impulse: [0.0; 3],
                    });
                }
            }
        }
        set.lanes_to_plan = Some(anchor);
        set
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.ball.len()
            + self.hinge.len()
            + self.universal.len()
            + self.fixed.len()
            + self.slider.len()
            + self.spring.len()
    }

    /// Calls `f(a, b)` for the two bodies of every joint.
    pub fn for_each_pair(&self, mut f: impl FnMut(usize, usize)) {
        for_each_joint_ref!(self, j => { let fr = j.frame(); f(fr.a, fr.b) });
    }

    /// The first substep's preparation of joints touching an awake body (the lanes also
    /// take the joints' impulses, see [`JointSet::end_substeps`]), with the rows sized
    /// to the joints.
    pub fn prepare(&mut self, s: &BodyStates, awake: &[bool]) {
        if self.live_points > 0
            && !self.trees_own_most()
            && let Some(anchor) = self.lanes_to_plan.take()
        {
            self.lanes = JointLanes::plan(&self.ball, &self.hinge, s.len(), anchor);
        }
        let (balls, hinges) = self.in_lanes();
        self.fit_rows(awake, balls, hinges);
        if let Some(lanes) = self.lanes.as_mut().filter(|_| balls || hinges) {
            let rows = (&mut self.rows.ball[..], &mut self.rows.hinge[..]);
            lanes.prepare(&mut self.ball, &mut self.hinge, rows, s, awake);
        }
        for_each_type!(self, balls, hinges, (list, rows) => {
            let mut k = 0;
            for j in list.iter_mut() {
                if touches_awake(j.frame(), awake) {
                    j.prepare(&mut rows[k], s);
                    k += 1;
                }
            }
        });
    }

    /// Gives back the rows of an in-place solve: a world at rest, or one now solved in
    /// batches (whose own arrays hold the rows), keeps none.
    pub fn release_rows(&mut self) {
        let r = &self.rows;
        if r.ball.capacity() + r.hinge.capacity() > 0
            || r.universal.capacity() + r.fixed.capacity() > 0
            || r.slots.iter().any(|v| v.capacity() > 0)
        {
            self.rows = JointRows::default();
        }
    }

    /// Drops the joints by owner (see `Method::drop_by_owner`): the joints, the rows
    /// of an in-place solve, the SIMD lanes.
    pub(crate) fn drop_by_owner(mut self, dropped: &mut dyn FnMut(&'static str)) {
        drop(std::mem::take(&mut self.rows));
        dropped("joint rows");
        drop(self.lanes.take());
        dropped("joint lanes");
        drop(self);
        dropped("joints");
    }

    /// Sizes each type's rows to the joints this solve moves (those touching an awake
    /// body; every joint of a type in lanes, `balls` / `hinges`) and, when the solve has
    /// trees, numbers the rows of the joints they read ([`JointRows::slots`]). Entries
    /// are overwritten by the preparation of their joint before any read, so kept or
    /// fresh they give the same solve. The arrays keep their capacity from step to step
    /// (a batch's, from batch to batch), so a step allocates nothing once they have
    /// grown; an array holding more than twice the room it needs gives the rest back (a
    /// pile falling asleep), which reallocates only as often as the moving joints halve.
    fn fit_rows(&mut self, awake: &[bool], balls: bool, hinges: bool) {
        let r = &mut self.rows;
        fit(&mut r.ball, rows_needed(&self.ball, balls, awake));
        fit(&mut r.hinge, rows_needed(&self.hinge, hinges, awake));
        fit(&mut r.universal, rows_needed(&self.universal, false, awake));
        fit(&mut r.fixed, rows_needed(&self.fixed, false, awake));
        fit(&mut r.slider, rows_needed(&self.slider, false, awake));
        fit(&mut r.spring, rows_needed(&self.spring, false, awake));
        if self.direct {
            let [ball, hinge, universal] = &mut r.slots;
            number_rows(ball, &self.ball, balls, awake);
            number_rows(hinge, &self.hinge, hinges, awake);
            number_rows(universal, &self.universal, false, awake);
        } else {
            r.slots.iter_mut().for_each(Vec::clear);
        }
    }

    /// [`JointSolve::prepare_after_relax`] of joints touching an awake body.
    pub fn prepare_after_relax(&mut self, s: &BodyStates, awake: &[bool]) {
        let (balls, hinges) = self.in_lanes();
        if let Some(lanes) = self.lanes.as_mut().filter(|_| balls || hinges) {
            let rows = (&mut self.rows.ball[..], &mut self.rows.hinge[..]);
            lanes.prepare_after_relax(&mut self.ball, &mut self.hinge, rows, s);
        }
        for_each_type!(self, balls, hinges, (list, rows) => {
            let mut k = 0;
            for j in list.iter_mut() {
                if touches_awake(j.frame(), awake) {
                    j.prepare_after_relax(&mut rows[k], s);
                    k += 1;
                }
            }
        });
    }

    /// [`JointSolve::prepare_moved`] of joints touching an awake body: the rows of the
    /// relax passes, once on the pose the substep moved to.
    pub fn prepare_moved(&mut self, s: &BodyStates, awake: &[bool]) {
        let (balls, hinges) = self.in_lanes();
        if let Some(lanes) = self.lanes.as_mut().filter(|_| balls || hinges) {
            let rows = (&mut self.rows.ball[..], &mut self.rows.hinge[..]);
            lanes.prepare_moved(rows, s);
        }
        for_each_type!(self, balls, hinges, (list, rows) => {
            let mut k = 0;
            for j in list.iter_mut() {
                if touches_awake(j.frame(), awake) {
                    j.prepare_moved(&mut rows[k], s);
                    k += 1;
                }
            }
        });
    }

    /// Warm start of joints touching an awake body, type by type in the solve order.
    pub fn warm_start(&mut self, s: &mut BodyStates, awake: &[bool]) {
        let (balls, hinges) = self.in_lanes();
        let trees = self.direct;
        let rows = &self.rows;
        match self.lanes.as_mut().filter(|_| balls) {
            Some(l) => l.warm_start_balls(s, &mut self.ball, trees),
            None => warm_start_each(&self.ball, &rows.ball, s, awake),
        }
        match self.lanes.as_mut().filter(|_| hinges) {
            Some(l) => l.warm_start_hinges(s, &mut self.hinge, trees),
            None => warm_start_each(&self.hinge, &rows.hinge, s, awake),
        }
        warm_start_each(&self.universal, &rows.universal, s, awake);
        warm_start_each(&self.fixed, &rows.fixed, s, awake);
        warm_start_each(&self.slider, &rows.slider, s, awake);
        warm_start_each(&self.spring, &rows.spring, s, awake);
    }

    /// One iteration over joints touching an awake body: every joint's friction first,
    /// then the rows type by type (see [`FrictionMotor`] for why in this order).
    pub fn solve(&mut self, s: &mut BodyStates, awake: &[bool], ctx: &StepContext, use_bias: bool) {
        self.solve_friction(s, awake, ctx);
        let (balls, hinges) = self.in_lanes();
        let trees = self.direct;
        let rows = &self.rows;
        match self.lanes.as_mut().filter(|_| balls) {
            Some(l) => l.solve_balls(s, &mut self.ball, trees, ctx, use_bias),
            None => solve_each(&mut self.ball, &rows.ball, s, awake, ctx, use_bias),
        }
        match self.lanes.as_mut().filter(|_| hinges) {
            Some(l) => l.solve_hinges(s, &mut self.hinge, trees, ctx, use_bias),
            None => solve_each(&mut self.hinge, &rows.hinge, s, awake, ctx, use_bias),
        }
        solve_each(
            &mut self.universal,
            &rows.universal,
            s,
            awake,
            ctx,
            use_bias,
        );
        solve_each(&mut self.fixed, &rows.fixed, s, awake, ctx, use_bias);
        solve_each(&mut self.slider, &rows.slider, s, awake, ctx, use_bias);
        solve_each(&mut self.spring, &rows.spring, s, awake, ctx, use_bias);
    }

    /// One update of every joint friction touching an awake body, in the turns its
    /// joint leaves free. Most joints have none (the test on the cap comes first).
    fn solve_friction(&mut self, s: &mut BodyStates, awake: &[bool], ctx: &StepContext) {
        for j in &mut self.ball {
            if j.friction.max_torque > 0.0 && touches_awake(&j.frame, awake) {
                j.friction.solve(&j.frame, s, ctx, &j.point, FreeTurns::All);
            }
        }
        for j in &mut self.hinge {
            if j.friction.max_torque > 0.0 && touches_awake(&j.frame, awake) {
                let free = j.free_turns(s);
                j.friction.solve(&j.frame, s, ctx, &j.point, free);
            }
        }
        for j in &mut self.universal {
            if j.friction.max_torque > 0.0 && touches_awake(&j.frame, awake) {
                let free = j.free_turns(s);
                j.friction.solve(&j.frame, s, ctx, &j.point, free);
            }
        }
    }

    /// After a solve's substeps: the lanes hand their accumulated impulses back to the
    /// joints, for the next step's warm start (which may solve them one island at a
    /// time, one by one).
    pub fn end_substeps(&mut self) {
        if let Some(lanes) = self
            .lanes
            .as_ref()
            .filter(|l| l.fits(&self.ball, &self.hinge) && !self.trees_own_most())
        {
            lanes.finish(&mut self.ball, &mut self.hinge);
        }
    }

    /// Whether the trees of this solve hold the point rows of most ball joints and
    /// hinges that move (a pile of figures each with a heavy limb, some of them
    /// asleep): the lanes then stand aside, since the rows left to them (limits,
    /// alignments) do not pay for gathering and scattering their bundles' bodies
    /// (measured on the pile of humans: 270 figures ran about a quarter slower with the
    /// lanes around their trees).
    pub(super) fn trees_own_most(&self) -> bool {
        2 * self.tree_points > self.live_points
    }

    /// Whether the ball joints and the hinges are solved in lanes: when there are lanes
    /// and they were dealt from these arrays (an island's gathered arrays have none).
    fn in_lanes(&self) -> (bool, bool) {
        self.lanes
            .as_ref()
            .filter(|l| l.fits(&self.ball, &self.hinge) && !self.trees_own_most())
            .map_or((false, false), |l| (l.has_balls(), l.has_hinges()))
    }

    /// Moves references to the static anchor from index `old` to `new` (a body was
    /// inserted before it), in the joints and in their lanes.
    pub fn retarget_anchor(&mut self, old: usize, new: usize) {
        let fix = |b: &mut usize| {
            if *b == old {
                *b = new;
            }
        };
        for_each_joint_mut!(self, j => fix(&mut j.frame.b));
        if let Some(anchor) = &mut self.lanes_to_plan {
            fix(anchor);
        }
        if let Some(lanes) = &mut self.lanes {
            lanes.retarget_anchor(old, new);
        }
    }

    /// One position-projection pass over joints that can move: touching an awake body
    /// that the pass has not made immobile ([`super::project`] holds resting bodies as
    /// static). A joint between two immobile bodies would measure its errors and build
    /// its effective masses only to find them singular; once a pile starts to settle
    /// that is most of them. `rows` says whether each joint projects all its rows or
    /// its point row alone. The update of a joint of a figure that touches nothing
    /// (`touching` unset, per body) keeps its pair's angular momentum
    /// ([`keep_pair_momentum`]).
    pub fn project(
        &self,
        s: &mut BodyStates,
        motion: Motions<'_>,
        awake: &[bool],
        touching: &[bool],
        rows: ProjectedRows,
    ) {
        for_each_joint_ref!(self, j => {
            let f = j.frame();
            if touches_awake(f, awake) && (s.is_mobile(f.a) || s.is_mobile(f.b)) {
                let free = !touching[f.a] && !touching[f.b];
                let before = PairPose::of(s, f.a, f.b);
                match rows {
                    ProjectedRows::All => j.project(s),
                    ProjectedRows::Points => j.project_point(s),
                }
                if free {
                    keep_pair_momentum(s, motion, f.a, f.b, &before);
                }
            }
        });
    }

    /// Largest joint gap now (m).
    pub fn max_gap(&self, s: &BodyStates) -> f32 {
        let mut m = 0.0f32;
        for_each_joint_ref!(self, j => m = m.max(j.gap(s)));
        m
    }

    /// Largest hard-limit violation now (rad).
    pub fn max_limit_violation(&self, s: &BodyStates) -> f32 {
        let mut m = 0.0f32;
        for_each_joint_ref!(self, j => m = m.max(j.limit_violation(s)));
        m
    }

    /// Appends what to draw for every joint.
    pub fn draw(&self, s: &BodyStates, out: &mut Vec<JointInstance>) {
        for j in &self.ball {
            let (anchor, anchor2) = j.frame.anchors(s);
            let limit = j.swing.as_ref().map_or(LimitShape::None, |sw| {
                let (axis, half_angle) = sw.draw_cone(&j.frame, s);
                LimitShape::Cone { axis, half_angle }
            });
            out.push(JointInstance {
                anchor,
                anchor2,
                limit,
            });
        }
        for j in &self.hinge {
            let (anchor, anchor2) = j.frame.anchors(s);
            let limit = j
                .limit
                .as_ref()
                .map_or(LimitShape::None, |l| LimitShape::Arc {
                    axis: s.rot[j.frame.b] * l.gauge.axis_b,
                    reference: s.rot[j.frame.b] * l.gauge.ref_b,
                    min: l.range.min,
                    max: l.range.max,
                });
            out.push(JointInstance {
                anchor,
                anchor2,
                limit,
            });
        }
        for j in &self.universal {
            let (anchor, anchor2) = j.frame.anchors(s);
            let limit = j.swing.as_ref().map_or(LimitShape::None, |sw| {
                let (axis, half_angle) = sw.draw_cone(&j.frame, s);
                LimitShape::Cone { axis, half_angle }
            });
            out.push(JointInstance {
                anchor,
                anchor2,
                limit,
            });
        }
        for j in &self.fixed {
            let (anchor, anchor2) = j.frame.anchors(s);
            out.push(JointInstance {
                anchor,
                anchor2,
                limit: LimitShape::None,
            });
        }
        for j in &self.spring {
            let (anchor, anchor2) = j.frame.anchors(s);
            out.push(JointInstance {
                anchor,
                anchor2,
                limit: LimitShape::None,
            });
        }
    }
}

/// Warm start of `joints` touching an awake body, one by one, each with its rows.
fn warm_start_each<J: JointSolve>(
    joints: &[J],
    rows: &[J::Rows],
    s: &mut BodyStates,
    awake: &[bool],
) {
    let mut k = 0;
    for j in joints {
        if touches_awake(j.frame(), awake) {
            j.warm_start(&rows[k], s);
            k += 1;
        }
    }
}

/// One iteration over `joints` touching an awake body, one by one, each with its rows.
fn solve_each<J: JointSolve>(
    joints: &mut [J],
    rows: &[J::Rows],
    s: &mut BodyStates,
    awake: &[bool],
    ctx: &StepContext,
    use_bias: bool,
) {
    let mut k = 0;
    for j in joints {
        if touches_awake(j.frame(), awake) {
            j.solve(&rows[k], s, ctx, use_bias);
            k += 1;
        }
    }
}

/// How many of `joints` have rows ([`JointRows`]): all of them (`all`: solved in
/// lanes), otherwise those touching an awake body.
fn rows_needed<J: JointSolve>(joints: &[J], all: bool, awake: &[bool]) -> usize {
    if all {
        joints.len()
    } else {
        let moved = joints.iter().filter(|j| touches_awake(j.frame(), awake));
        moved.count()
    }
}

/// Numbers the rows of `joints` in `slots` ([`JointRows::slots`]): each joint with
/// rows (see [`rows_needed`]) the next index, in joint order, the others [`NO_ROWS`].
fn number_rows<J: JointSolve>(slots: &mut Vec<u32>, joints: &[J], all: bool, awake: &[bool]) {
    slots.clear();
    let mut next = 0u32;
    slots.extend(joints.iter().map(|j| {
        if all || touches_awake(j.frame(), awake) {
            next += 1;
            next - 1
        } else {
            NO_ROWS
        }
    }));
}

/// Sizes `rows` to `len` entries, giving back the room beyond `len` when it is more
/// than as much again (see [`JointSet::fit_rows`]).
fn fit<R: Copy + Default>(rows: &mut Vec<R>, len: usize) {
    rows.resize(len, R::default());
    if rows.capacity() > 2 * len {
        rows.shrink_to(len);
    }
}

#[inline]
fn touches_awake(f: &JointFrame, awake: &[bool]) -> bool {
    awake[f.a] || awake[f.b]
}
