//! Fixed joint: no relative motion (PyODE's spine). The anchor is body1's centre of mass.

use super::body::BodyStates;
use super::joint::{AngularLock3, JointFrame, JointSolve, PointPart};
use super::joint_rows::PointRows;
use super::soft::StepContext;

/// A fixed joint.
#[derive(Clone, Debug)]
pub struct FixedJoint {
    /// Bodies and anchor.
    pub frame: JointFrame,
    /// The shared point.
    pub point: PointPart,
    /// The relative orientation lock.
    pub lock: AngularLock3,
}

impl JointSolve for FixedJoint {
    type Rows = PointRows<f32>;

    fn frame(&self) -> &JointFrame {
        &self.frame
    }

    fn prepare(&mut self, rows: &mut PointRows<f32>, s: &BodyStates) {
        self.point.prepare(rows, &self.frame, s);
    }

    fn prepare_after_relax(&mut self, rows: &mut PointRows<f32>, s: &BodyStates) {
        self.point.weigh(rows, &self.frame, s);
    }

    fn prepare_moved(&mut self, rows: &mut PointRows<f32>, s: &BodyStates) {
        self.point.prepare_moved(rows, &self.frame, s);
    }

    fn warm_start(&self, rows: &PointRows<f32>, s: &mut BodyStates) {
        self.lock.warm_start(&self.frame, s);
        self.point.warm_start(rows, &self.frame, s);
    }

    fn solve(
        &mut self,
        rows: &PointRows<f32>,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        self.lock.solve(&self.frame, s, ctx, use_bias);
        self.point.solve(rows, &self.frame, s, ctx, use_bias);
    }

    fn project(&self, s: &mut BodyStates) {
        self.lock.project(&self.frame, s);
        self.project_point(s);
    }

    fn project_point(&self, s: &mut BodyStates) {
        self.point.project(&self.frame, s, false);
    }

    fn limit_violation(&self, _: &BodyStates) -> f32 {
        0.0
    }
}
