//! Checks that a `SceneDesc` can be simulated, so methods can trust it.

use super::desc::*;
use super::{SceneError, mass_props};
use glam::Vec3;
use std::collections::HashSet;

fn finite3(v: Vec3) -> bool {
    v.is_finite()
}

fn unit(v: Vec3) -> bool {
    v.is_finite() && (v.length() - 1.0).abs() < 1e-3
}

/// Validates a scene: finite numbers, positive sizes and masses, unit axes, known
/// bodies, unique names, sane settings. Both methods call this before building.
pub fn validate(scene: &SceneDesc) -> Result<(), SceneError> {
    let mut names = HashSet::new();
    for b in &scene.bodies {
        if b.name == "world" {
            return Err(body_error(b, "\"world\" is reserved for the static world"));
        }
        if !names.insert(b.name.as_str()) {
            return Err(body_error(b, "another body has the same name"));
        }
        validate_body(b)?;
    }
    let mut cnames = HashSet::new();
    for c in &scene.constraints {
        if !cnames.insert(c.name.as_str()) {
            return Err(constraint_error(c, "another constraint has the same name"));
        }
        validate_constraint(c, scene.bodies.len())?;
    }
    validate_settings(&scene.settings)
}

fn body_error(b: &BodyDesc, what: impl Into<String>) -> SceneError {
    SceneError::Degenerate {
        body: b.name.clone(),
        what: what.into(),
    }
}

fn constraint_error(c: &ConstraintDesc, what: impl Into<String>) -> SceneError {
    SceneError::BadConstraint {
        constraint: c.name.clone(),
        what: what.into(),
    }
}

/// One body on its own: a finite unit pose, a shape of positive finite size, friction,
/// restitution and velocities in range, mass properties that exist.
fn validate_body(b: &BodyDesc) -> Result<(), SceneError> {
    let bad = |what: &str| Err(body_error(b, what));
    if !finite3(b.pose.position) || !b.pose.rotation.is_finite() {
        return bad("its pose is not finite");
    }
    if (b.pose.rotation.length() - 1.0).abs() > 1e-3 {
        return bad("its rotation is not a unit quaternion");
    }
    if !shape_size_ok(&b.shape) {
        return Err(body_error(
            b,
            format!(
                "its {} has a non-positive or non-finite size",
                b.shape.kind_name()
            ),
        ));
    }
    if !(b.friction.contact.is_finite() && b.friction.contact >= 0.0) {
        return bad("its contact friction is negative or not finite");
    }
    if !(b.restitution.is_finite() && (0.0..=1.0).contains(&b.restitution)) {
        return bad("its restitution is outside [0, 1]");
    }
    if !finite3(b.linear_velocity) || !finite3(b.angular_velocity) {
        return bad("its initial velocity is not finite");
    }
    mass_props(b)?;
    Ok(())
}

/// Whether every size of `shape` is finite and positive (a capsule's half height may
/// be zero: a sphere) and a hull has at least four finite points.
fn shape_size_ok(shape: &Shape) -> bool {
    match shape {
        Shape::Box { half_extents } => half_extents.is_finite() && half_extents.min_element() > 0.0,
        Shape::Capsule {
            half_height,
            radius,
        } => half_height.is_finite() && *half_height >= 0.0 && radius.is_finite() && *radius > 0.0,
        Shape::Cylinder {
            half_height,
            radius,
            ..
        }
        | Shape::Cone {
            half_height,
            radius,
            ..
        } => half_height.is_finite() && *half_height > 0.0 && radius.is_finite() && *radius > 0.0,
        Shape::ConvexHull { points } => points.len() >= 4 && points.iter().all(|p| p.is_finite()),
    }
}

/// One constraint on its own, in a scene of `bodies` bodies: bodies that exist and
/// differ, friction in range, its joint's numbers sound ([`joint_ok`]).
fn validate_constraint(c: &ConstraintDesc, bodies: usize) -> Result<(), SceneError> {
    let bad = |what: &str| Err(constraint_error(c, what));
    if c.body1.index() >= bodies {
        return bad("body1 does not exist");
    }
    if let BodyRef::Body(b2) = c.body2 {
        if b2.index() >= bodies {
            return bad("body2 does not exist");
        }
        if b2 == c.body1 {
            return bad("body1 and body2 are the same body");
        }
    }
    if !(c.friction.is_finite() && c.friction >= 0.0) {
        return bad("its friction is negative or not finite");
    }
    if !joint_ok(&c.kind) {
        return bad(
            "an anchor is not finite, an axis is not a unit vector, or a limit range is empty",
        );
    }
    Ok(())
}

/// Whether a joint's anchors are finite, its axes unit vectors, its limit ranges not
/// empty and its spring's numbers finite and non-negative.
fn joint_ok(kind: &JointKind) -> bool {
    match kind {
        JointKind::BallAndSocket {
            anchor,
            swing,
            twist,
            ..
        } => {
            finite3(*anchor)
                && swing.is_none_or(|s| swing_ok(&s))
                && twist.is_none_or(|t| unit(t.axis) && t.min <= t.max)
        }
        JointKind::Universal {
            anchor,
            shaft1,
            shaft2,
            swing,
            ..
        } => {
            finite3(*anchor) && unit(*shaft1) && unit(*shaft2) && swing.is_none_or(|s| swing_ok(&s))
        }
        JointKind::Hinge {
            anchor,
            axis,
            limit,
        } => {
            finite3(*anchor)
                && unit(*axis)
                && limit.is_none_or(|l| l.min.is_finite() && l.max.is_finite() && l.min <= l.max)
        }
        JointKind::Slider { axis } => unit(*axis),
        JointKind::Fixed => true,
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
            finite3(*anchor1)
                && finite3(*anchor2)
                && [
                    *stretch,
                    *compress,
                    *damping,
                    *rest_length,
                    *min_length,
                    *max_length,
                ]
                .iter()
                .all(|v| v.is_finite() && *v >= 0.0)
        }
    }
}

/// The solver settings: timestep in (0, 1] s, iteration and substep counts in
/// 1..=1000, gravity finite.
fn validate_settings(s: &Settings) -> Result<(), SceneError> {
    if !(s.timestep.is_finite() && s.timestep > 0.0 && s.timestep <= 1.0) {
        return Err(SceneError::BadSetting {
            setting: "timestep",
            what: format!("{} s is not in (0, 1]", s.timestep),
        });
    }
    if s.iterations == 0 || s.iterations > 1000 {
        return Err(SceneError::BadSetting {
            setting: "iterations",
            what: format!("{} is not in 1..=1000", s.iterations),
        });
    }
    if s.substeps == 0 || s.substeps > 1000 {
        return Err(SceneError::BadSetting {
            setting: "substeps",
            what: format!("{} is not in 1..=1000", s.substeps),
        });
    }
    if let Some(n) = s.multibody_substeps
        && (n == 0 || n > 1000)
    {
        return Err(SceneError::BadSetting {
            setting: "multibodySubsteps",
            what: format!("{n} is not in 1..=1000"),
        });
    }
    if let Some(n) = s.multibody_iterations
        && (n == 0 || n > 1000)
    {
        return Err(SceneError::BadSetting {
            setting: "multibodyIterations",
            what: format!("{n} is not in 1..=1000"),
        });
    }
    if s.relax_passes == 0 || s.relax_passes > 1000 {
        return Err(SceneError::BadSetting {
            setting: "relaxPasses",
            what: format!("{} is not in 1..=1000", s.relax_passes),
        });
    }
    if let Some(n) = s.xpbd_substeps
        && (n == 0 || n > 1000)
    {
        return Err(SceneError::BadSetting {
            setting: "xpbdSubsteps",
            what: format!("{n} is not in 1..=1000"),
        });
    }
    if s.xpbd_passes == 0 || s.xpbd_passes > 1000 {
        return Err(SceneError::BadSetting {
            setting: "xpbdPasses",
            what: format!("{} is not in 1..=1000", s.xpbd_passes),
        });
    }
    if !s.gravity.is_finite() {
        return Err(SceneError::BadSetting {
            setting: "gravity",
            what: "not finite".into(),
        });
    }
    Ok(())
}

fn swing_ok(s: &SwingLimit) -> bool {
    match s {
        SwingLimit::Cone {
            axis,
            half_angle,
            shaft,
        } => unit(*axis) && unit(*shaft) && half_angle.is_finite() && *half_angle >= 0.0,
        SwingLimit::Pyramid {
            axis,
            half_angle1,
            half_angle2,
            roll,
            shaft,
        } => {
            unit(*axis)
                && unit(*shaft)
                && half_angle1.is_finite()
                && *half_angle1 >= 0.0
                && half_angle2.is_finite()
                && *half_angle2 >= 0.0
                && roll.is_finite()
        }
    }
}
