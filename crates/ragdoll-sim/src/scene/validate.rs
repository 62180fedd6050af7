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
        let bad = |what: String| SceneError::Degenerate {
            body: b.name.clone(),
            what,
        };
        if b.name == "world" {
            return Err(bad("\"world\" is reserved for the static world".into()));
        }
        if !names.insert(b.name.as_str()) {
            return Err(bad("another body has the same name".into()));
        }
        if !finite3(b.pose.position) || !b.pose.rotation.is_finite() {
            return Err(bad("its pose is not finite".into()));
        }
        if (b.pose.rotation.length() - 1.0).abs() > 1e-3 {
            return Err(bad("its rotation is not a unit quaternion".into()));
        }
        let sizes_ok = match &b.shape {
            Shape::Box { half_extents } => {
                half_extents.is_finite() && half_extents.min_element() > 0.0
            }
            Shape::Capsule {
                half_height,
                radius,
            } => {
                half_height.is_finite()
                    && *half_height >= 0.0
                    && radius.is_finite()
                    && *radius > 0.0
            }
            Shape::Cylinder {
                half_height,
                radius,
                ..
            }
            | Shape::Cone {
                half_height,
                radius,
                ..
            } => {
                half_height.is_finite() && *half_height > 0.0 && radius.is_finite() && *radius > 0.0
            }
            Shape::ConvexHull { points } => {
                points.len() >= 4 && points.iter().all(|p| p.is_finite())
            }
        };
        if !sizes_ok {
            return Err(bad(format!(
                "its {} has a non-positive or non-finite size",
                b.shape.kind_name()
            )));
        }
        if !(b.friction.contact.is_finite() && b.friction.contact >= 0.0) {
            return Err(bad("its contact friction is negative or not finite".into()));
        }
        if !(b.restitution.is_finite() && (0.0..=1.0).contains(&b.restitution)) {
            return Err(bad("its restitution is outside [0, 1]".into()));
        }
        if !finite3(b.linear_velocity) || !finite3(b.angular_velocity) {
            return Err(bad("its initial velocity is not finite".into()));
        }
        mass_props(b)?;
    }
    let mut cnames = HashSet::new();
    for c in &scene.constraints {
        let bad = |what: String| SceneError::BadConstraint {
            constraint: c.name.clone(),
            what,
        };
        if !cnames.insert(c.name.as_str()) {
            return Err(bad("another constraint has the same name".into()));
        }
        if c.body1.index() >= scene.bodies.len() {
            return Err(bad("body1 does not exist".into()));
        }
        if let BodyRef::Body(b2) = c.body2 {
            if b2.index() >= scene.bodies.len() {
                return Err(bad("body2 does not exist".into()));
            }
            if b2 == c.body1 {
                return Err(bad("body1 and body2 are the same body".into()));
            }
        }
        if !(c.friction.is_finite() && c.friction >= 0.0) {
            return Err(bad("its friction is negative or not finite".into()));
        }
        let axes_ok = match &c.kind {
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
                finite3(*anchor)
                    && unit(*shaft1)
                    && unit(*shaft2)
                    && swing.is_none_or(|s| swing_ok(&s))
            }
            JointKind::Hinge {
                anchor,
                axis,
                limit,
            } => {
                finite3(*anchor)
                    && unit(*axis)
                    && limit
                        .is_none_or(|l| l.min.is_finite() && l.max.is_finite() && l.min <= l.max)
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
        };
        if !axes_ok {
            return Err(bad(
                "an anchor is not finite, an axis is not a unit vector, or a limit range is empty"
                    .into(),
            ));
        }
    }
    let s = &scene.settings;
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
