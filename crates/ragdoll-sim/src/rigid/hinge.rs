//! Hinge: the anchor is shared and the hinge axis fixed in both bodies stays aligned,
//! leaving one rotation, optionally limited to a range (Doom 3's V-shaped limit, ODE's
//! hinge stops).

use super::body::BodyStates;
use super::joint::{AlignPart, FreeTurns, FrictionMotor, JointFrame, JointSolve, PointPart};
use super::joint_rows::{AlignRows, PointRows};
use super::limits::{AngleLimit, RangeRows};
use super::soft::StepContext;
use glam::Vec3A;

/// A hinge joint.
#[derive(Clone, Debug)]
pub struct HingeJoint {
    /// Bodies and anchor.
    pub frame: JointFrame,
    /// The shared point.
    pub point: PointPart,
    /// The axis, kept aligned in both bodies.
    pub align: AlignPart,
    /// The range, if limited (its gauge measures the hinge angle).
    pub limit: Option<AngleLimit>,
    /// Joint friction.
    pub friction: FrictionMotor,
}

/// The rows a step prepares for a hinge ([`JointSolve::Rows`]): its point's, its
/// alignment's and its range's.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HingeRows {
    pub point: PointRows<f32>,
    pub align: AlignRows<f32>,
    pub limit: RangeRows,
}

impl HingeJoint {
    /// The one turn a hinge leaves free: about its axis (world, as body a carries it).
    pub(crate) fn free_turns(&self, s: &BodyStates) -> FreeTurns {
        FreeTurns::Axis(Vec3A::from(s.rot[self.frame.a] * self.align.local_a).normalize())
    }

    /// The range rows on the current pose and inertias.
    fn update_limit(&mut self, rows: &mut RangeRows, s: &BodyStates) {
        if let Some(l) = &mut self.limit {
            l.update(rows, &self.frame, s);
        }
    }
}

impl JointSolve for HingeJoint {
    type Rows = HingeRows;

    fn frame(&self) -> &JointFrame {
        &self.frame
    }

    fn prepare(&mut self, rows: &mut HingeRows, s: &BodyStates) {
        self.point.prepare(&mut rows.point, &self.frame, s);
        self.align.prepare(&mut rows.align, &self.frame, s);
        self.update_limit(&mut rows.limit, s);
    }

    fn prepare_after_relax(&mut self, rows: &mut HingeRows, s: &BodyStates) {
        self.point.weigh(&mut rows.point, &self.frame, s);
        AlignPart::weigh(&mut rows.align, &self.frame, s);
        self.update_limit(&mut rows.limit, s);
    }

    fn prepare_moved(&mut self, rows: &mut HingeRows, s: &BodyStates) {
        self.align.prepare(&mut rows.align, &self.frame, s);
        self.point.prepare_moved(&mut rows.point, &self.frame, s);
    }

    fn warm_start(&self, rows: &HingeRows, s: &mut BodyStates) {
        self.friction.warm_start(&self.frame, s);
        if let Some(l) = &self.limit {
            l.warm_start(&rows.limit, &self.frame, s);
        }
        self.align.warm_start(&rows.align, &self.frame, s);
        self.point.warm_start(&rows.point, &self.frame, s);
    }

    fn solve(&mut self, rows: &HingeRows, s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        if let Some(l) = &mut self.limit {
            l.solve(&rows.limit, &self.frame, s, ctx, use_bias);
        }
        self.align.solve(&rows.align, &self.frame, s, ctx, use_bias);
        self.point.solve(&rows.point, &self.frame, s, ctx, use_bias);
    }

    fn project(&self, s: &mut BodyStates) {
        if let Some(l) = &self.limit {
            l.project(&self.frame, s);
        }
        self.align.project(&self.frame, s);
        self.project_point(s);
    }

    fn project_point(&self, s: &mut BodyStates) {
        self.point.project(
            &self.frame,
            s,
            self.friction.max_torque > 0.0 && self.friction.holding,
        );
    }

    fn limit_violation(&self, s: &BodyStates) -> f32 {
        self.limit
            .as_ref()
            .map_or(0.0, |l| l.violation(&self.frame, s))
    }
}
