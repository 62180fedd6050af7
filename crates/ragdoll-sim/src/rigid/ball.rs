//! Ball-and-socket joint: the anchor is shared, rotation is free up to an optional swing
//! limit (Doom 3 cone or pyramid) and twist limit, hard or soft (PyODE's flex and twist).

use super::body::BodyStates;
use super::joint::{FrictionMotor, JointFrame, JointSolve, PointPart};
use super::joint_rows::PointRows;
use super::limits::{AngleLimit, RangeRows, Swing, SwingRows};
use super::soft::StepContext;

/// A ball-and-socket joint.
#[derive(Clone, Debug)]
pub struct BallJoint {
    /// Bodies and anchor.
    pub frame: JointFrame,
    /// The shared point.
    pub point: PointPart,
    /// Swing limit on body1's shaft relative to body2's axis.
    pub swing: Option<Swing>,
    /// Twist limit about body1's twist axis.
    pub twist: Option<AngleLimit>,
    /// Joint friction.
    pub friction: FrictionMotor,
}

/// The rows a step prepares for a ball joint ([`JointSolve::Rows`]): its point's, its
/// swing limit's and its twist limit's.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct BallRows {
    pub point: PointRows<f32>,
    pub swing: SwingRows,
    pub twist: RangeRows,
}

impl BallJoint {
    /// The swing and twist rows on the current pose and inertias.
    fn update_limits(&mut self, rows: &mut BallRows, s: &BodyStates) {
        if let Some(sw) = &mut self.swing {
            sw.update(&mut rows.swing, &self.frame, s);
        }
        if let Some(t) = &mut self.twist {
            t.update(&mut rows.twist, &self.frame, s);
        }
    }
}

impl JointSolve for BallJoint {
    type Rows = BallRows;

    fn frame(&self) -> &JointFrame {
        &self.frame
    }

    fn prepare(&mut self, rows: &mut BallRows, s: &BodyStates) {
        self.point.prepare(&mut rows.point, &self.frame, s);
        self.update_limits(rows, s);
    }

    fn prepare_after_relax(&mut self, rows: &mut BallRows, s: &BodyStates) {
        self.point.weigh(&mut rows.point, &self.frame, s);
        self.update_limits(rows, s);
    }

    fn prepare_moved(&mut self, rows: &mut BallRows, s: &BodyStates) {
        if let Some(sw) = &self.swing {
            sw.prepare_moved(&mut rows.swing, &self.frame, s);
        }
        self.point.prepare_moved(&mut rows.point, &self.frame, s);
    }

    fn warm_start(&self, rows: &BallRows, s: &mut BodyStates) {
        self.friction.warm_start(&self.frame, s);
        if let Some(sw) = &self.swing {
            sw.warm_start(&rows.swing, &self.frame, s);
        }
        if let Some(t) = &self.twist {
            t.warm_start(&rows.twist, &self.frame, s);
        }
        self.point.warm_start(&rows.point, &self.frame, s);
    }

    fn solve(&mut self, rows: &BallRows, s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        if let Some(sw) = &mut self.swing {
            sw.solve(&rows.swing, &self.frame, s, ctx, use_bias);
        }
        if let Some(t) = &mut self.twist {
            t.solve(&rows.twist, &self.frame, s, ctx, use_bias);
        }
        self.point.solve(&rows.point, &self.frame, s, ctx, use_bias);
    }

    fn project(&self, s: &mut BodyStates) {
        if let Some(sw) = &self.swing {
            sw.project(&self.frame, s);
        }
        if let Some(t) = &self.twist {
            t.project(&self.frame, s);
        }
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
        // Hard limits only: the soft flex/twist limits of the PyODE tutorial push back
        // with a torque proportional to the excess and are exceeded by design (seed
        // pyode-ragdoll-tutorial.txt: "the reactive torque will not stop the joint from
        // at least temporarily exceeding the angle limits, but this is actually
        // desirable"), so they do not count as violations.
        let sw = self
            .swing
            .as_ref()
            .filter(|l| l.is_hard())
            .map_or(0.0, |l| l.violation(&self.frame, s));
        let tw = self
            .twist
            .as_ref()
            .filter(|l| l.is_hard())
            .map_or(0.0, |l| l.violation(&self.frame, s));
        sw.max(tw)
    }
}
