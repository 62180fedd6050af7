//! Universal joint: a ball-and-socket that also keeps body1's shaft at its rest angle
//! (normally 90°) to body2's shaft, so neither body twists about the shafts. Optional
//! Doom 3 swing limit on shaft1 and PyODE lo/hi stops about each shaft.

use super::body::BodyStates;
use super::joint::{
    AxisRow, FreeTurns, FrictionMotor, JointFrame, JointSolve, PointPart, RowState,
};
use super::joint_rows::PointRows;
use super::limits::{AngleLimit, RangeRows, Swing, SwingRows};
use super::soft::StepContext;
use glam::Vec3;

/// A universal joint.
#[derive(Clone, Debug)]
pub struct UniversalJoint {
    /// Bodies and anchor.
    pub frame: JointFrame,
    /// The shared point.
    pub point: PointPart,
    /// Shaft 1 in a.
    pub shaft_a: Vec3,
    /// Shaft 2 in b.
    pub shaft_b: Vec3,
    /// `shaft1 · shaft2` at rest.
    pub rest_dot: f32,
    /// The state of the row keeping `shaft1 · shaft2` at rest:
    /// `Ċ = (ω_a − ω_b)·(s₁ × s₂)`.
    pub cross_row: RowState,
    /// Swing limit on shaft 1.
    pub swing: Option<Swing>,
    /// Stops about shaft 1 and shaft 2.
    pub ranges: Option<[AngleLimit; 2]>,
    /// Joint friction.
    pub friction: FrictionMotor,
}

/// The rows a step prepares for a universal joint ([`JointSolve::Rows`]): its point's,
/// its cross row, its swing limit's and its stops'.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct UniversalRows {
    pub point: PointRows<f32>,
    pub cross: AxisRow,
    pub swing: SwingRows,
    pub ranges: [RangeRows; 2],
}

impl UniversalJoint {
    /// The turns a universal joint leaves free: about either shaft, the plane normal to
    /// `shaft₁ × shaft₂` (all three if the shafts were ever parallel, where the cross
    /// row has no axis either).
    pub(crate) fn free_turns(&self, s: &BodyStates) -> FreeTurns {
        let f = &self.frame;
        let n = (s.rot[f.a] * self.shaft_a).cross(s.rot[f.b] * self.shaft_b);
        match n.try_normalize() {
            Some(n) => FreeTurns::Plane(n.into()),
            None => FreeTurns::All,
        }
    }

    /// The cross row measured on the current pose (an equality: always active, its
    /// impulse kept).
    fn cross_row_now(&self, s: &BodyStates) -> AxisRow {
        let f = &self.frame;
        let s1 = s.rot[f.a] * self.shaft_a;
        let s2 = s.rot[f.b] * self.shaft_b;
        let mut impulse = self.cross_row.impulse;
        let mut row = AxisRow::default();
        let value = (s1.cross(s2), s1.dot(s2) - self.rest_dot);
        row.set(
            (self.cross_row.kind, &mut impulse),
            f,
            s,
            value,
            f32::INFINITY,
        );
        row
    }

    /// The cross row, the swing and the axis ranges on the current pose and inertias.
    fn set_angular_rows(&mut self, rows: &mut UniversalRows, s: &BodyStates) {
        let f = self.frame;
        rows.cross = self.cross_row_now(s);
        if let Some(sw) = &mut self.swing {
            sw.update(&mut rows.swing, &f, s);
        }
        if let Some(r) = &mut self.ranges {
            (r.iter_mut().zip(&mut rows.ranges)).for_each(|(l, set)| l.update(set, &f, s));
        }
    }
}

impl JointSolve for UniversalJoint {
    type Rows = UniversalRows;

    fn frame(&self) -> &JointFrame {
        &self.frame
    }

    fn prepare(&mut self, rows: &mut UniversalRows, s: &BodyStates) {
        self.point.prepare(&mut rows.point, &self.frame, s);
        self.set_angular_rows(rows, s);
    }

    fn prepare_after_relax(&mut self, rows: &mut UniversalRows, s: &BodyStates) {
        self.point.weigh(&mut rows.point, &self.frame, s);
        self.set_angular_rows(rows, s);
    }

    fn prepare_moved(&mut self, rows: &mut UniversalRows, s: &BodyStates) {
        if let Some(sw) = &self.swing {
            sw.prepare_moved(&mut rows.swing, &self.frame, s);
        }
        self.point.prepare_moved(&mut rows.point, &self.frame, s);
    }

    fn warm_start(&self, rows: &UniversalRows, s: &mut BodyStates) {
        let f = &self.frame;
        self.friction.warm_start(f, s);
        if let Some(sw) = &self.swing {
            sw.warm_start(&rows.swing, f, s);
        }
        if let Some(r) = &self.ranges {
            (r.iter().zip(&rows.ranges)).for_each(|(l, set)| l.warm_start(set, f, s));
        }
        rows.cross.warm_start(self.cross_row.impulse, f, s);
        self.point.warm_start(&rows.point, f, s);
    }

    fn solve(
        &mut self,
        rows: &UniversalRows,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        let f = &self.frame;
        if let Some(sw) = &mut self.swing {
            sw.solve(&rows.swing, f, s, ctx, use_bias);
        }
        if let Some(r) = &mut self.ranges {
            (r.iter_mut().zip(&rows.ranges)).for_each(|(l, set)| l.solve(set, f, s, ctx, use_bias));
        }
        rows.cross
            .solve(&mut self.cross_row.impulse, f, s, ctx, use_bias);
        self.point.solve(&rows.point, f, s, ctx, use_bias);
    }

    fn project(&self, s: &mut BodyStates) {
        let f = &self.frame;
        if let Some(sw) = &self.swing {
            sw.project(f, s);
        }
        if let Some(r) = &self.ranges {
            r.iter().for_each(|l| l.project(f, s));
        }
        self.cross_row_now(s).project(f, s);
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
        let f = &self.frame;
        let sw = self.swing.as_ref().map_or(0.0, |l| l.violation(f, s));
        let r = self
            .ranges
            .as_ref()
            .map_or(0.0, |r| r[0].violation(f, s).max(r[1].violation(f, s)));
        sw.max(r)
    }
}
