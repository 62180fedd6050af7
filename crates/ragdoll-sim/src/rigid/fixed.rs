//! Fixed joint: no relative motion (PyODE's spine). The anchor is body1's centre of mass.

use super::body::BodyStates;
use super::joint::{AngularLock3, JointFrame, JointSolve, PointPart};
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
    fn frame(&self) -> &JointFrame {
        &self.frame
    }

    fn prepare(&mut self, s: &BodyStates) {
        self.point.prepare(&self.frame, s);
    }

    fn prepare_after_relax(&mut self, s: &BodyStates) {
        self.point.weigh(&self.frame, s);
    }

    fn warm_start(&self, s: &mut BodyStates) {
        self.lock.warm_start(&self.frame, s);
        self.point.warm_start(&self.frame, s);
    }

    fn solve(&mut self, s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        self.lock.solve(&self.frame, s, ctx, use_bias);
        self.point.solve(&self.frame, s, ctx, use_bias);
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
