//! Moving the built figure: the `transform` block and the `replicate` grid of copies.

use super::build::Grid;
use crate::scene::{BodyDesc, BodyId, BodyRef, JointKind, Pose, SceneDesc, SwingLimit};
use glam::{Quat, Vec3};

/// Moves a body by a rigid transform of the world.
pub(super) fn place_body(b: &mut BodyDesc, t: &Pose) {
    b.pose = t.mul_pose(&b.pose);
    b.linear_velocity = t.rotation * b.linear_velocity;
    b.angular_velocity = t.rotation * b.angular_velocity;
}

/// Moves a joint's world-space anchors and axes by a rigid transform.
pub(super) fn place_joint(k: &mut JointKind, t: &Pose) {
    let r = t.rotation;
    let swing = |s: &mut SwingLimit| match s {
        SwingLimit::Cone { axis, shaft, .. } | SwingLimit::Pyramid { axis, shaft, .. } => {
            *axis = r * *axis;
            *shaft = r * *shaft;
        }
    };
    match k {
        JointKind::BallAndSocket {
            anchor,
            swing: s,
            twist,
            ..
        } => {
            *anchor = t.transform_point(*anchor);
            if let Some(s) = s {
                swing(s);
            }
            if let Some(tw) = twist {
                tw.axis = r * tw.axis;
            }
        }
        JointKind::Universal {
            anchor,
            shaft1,
            shaft2,
            swing: s,
            ..
        } => {
            *anchor = t.transform_point(*anchor);
            *shaft1 = r * *shaft1;
            *shaft2 = r * *shaft2;
            if let Some(s) = s {
                swing(s);
            }
        }
        JointKind::Hinge { anchor, axis, .. } => {
            *anchor = t.transform_point(*anchor);
            *axis = r * *axis;
        }
        JointKind::Slider { axis } => *axis = r * *axis,
        JointKind::Fixed => {}
        JointKind::Spring {
            anchor1, anchor2, ..
        } => {
            *anchor1 = t.transform_point(*anchor1);
            *anchor2 = t.transform_point(*anchor2);
        }
    }
}

/// Replaces the figure by `count` copies in a grid: columns along X, rows along Z,
/// layers up Y, centred on the figure's place in X and Z; copy `i` names its bodies and
/// constraints `name.i` (copy 0 keeps the original names). Layer `k` is turned by
/// `k · layerYaw` about the vertical through the figure's centre.
pub(super) fn replicate_figure(desc: &mut SceneDesc, g: &Grid, count: u32) {
    let n = desc.bodies.len();
    let centre = desc.bodies.iter().map(|b| b.pose.position).sum::<Vec3>() / n.max(1) as f32;
    let reach = desc
        .bodies
        .iter()
        .map(|b| {
            ((b.pose.position - centre) * Vec3::new(1.0, 0.0, 1.0)).length()
                + b.shape.local_half_extents().length()
        })
        .fold(0.0f32, f32::max);
    let height = desc
        .bodies
        .iter()
        .map(|b| b.shape.local_half_extents().length() * 2.0)
        .fold(0.0f32, f32::max);
    let spacing = g.spacing.unwrap_or(Vec3::new(
        2.0 * reach + 0.3,
        height + 0.2,
        2.0 * reach + 0.3,
    ));
    let layers = g.layers.max(1);
    let (mut cols, mut rows) = (g.columns, g.rows);
    if cols == 0
        || rows == 0
        || u64::from(count) > u64::from(cols) * u64::from(rows) * u64::from(layers)
    {
        // Grow the floor grid, keeping it square, until the copies fit in `layers`.
        let per_layer = count.div_ceil(layers);
        let side = (per_layer as f64).sqrt().ceil() as u32;
        cols = cols.max(side);
        rows = rows.max(per_layer.div_ceil(cols));
    }
    let bodies = std::mem::take(&mut desc.bodies);
    let constraints = std::mem::take(&mut desc.constraints);
    desc.bodies.reserve(n * count as usize);
    desc.constraints.reserve(constraints.len() * count as usize);
    for i in 0..count {
        let (c, r, l) = (i % cols, (i / cols) % rows, i / cols / rows);
        let offset = Vec3::new(
            (c as f32 - (cols - 1) as f32 * 0.5) * spacing.x,
            l as f32 * spacing.y,
            (r as f32 - (rows - 1) as f32 * 0.5) * spacing.z,
        );
        // Turn about the figure's centre, then move: p' = R (p - c) + c + offset.
        let rot = Quat::from_rotation_y(l as f32 * g.layer_yaw);
        let t = Pose {
            position: centre + offset - rot * centre,
            rotation: rot,
        };
        let suffix = |s: &str| {
            if i == 0 {
                s.to_string()
            } else {
                format!("{s}.{i}")
            }
        };
        let base = BodyId(i * n as u32);
        for b in &bodies {
            let mut b = b.clone();
            b.name = suffix(&b.name);
            place_body(&mut b, &t);
            desc.bodies.push(b);
        }
        for c in &constraints {
            let mut c = c.clone();
            c.name = suffix(&c.name);
            c.body1 = BodyId(base.0 + c.body1.0);
            if let BodyRef::Body(b2) = c.body2 {
                c.body2 = BodyRef::Body(BodyId(base.0 + b2.0));
            }
            place_joint(&mut c.kind, &t);
            desc.constraints.push(c);
        }
    }
}
