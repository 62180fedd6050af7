//! The `replicate` grid of copies of the built figure (the `transform` block moves it
//! with [`SceneDesc::transform`]).

use super::build::Grid;
use crate::scene::{BodyId, BodyRef, Pose, SceneDesc};
use glam::{Quat, Vec3};

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
            b.transform(&t);
            desc.bodies.push(b);
        }
        for c in &constraints {
            let mut c = c.clone();
            c.name = suffix(&c.name);
            c.body1 = BodyId(base.0 + c.body1.0);
            if let BodyRef::Body(b2) = c.body2 {
                c.body2 = BodyRef::Body(BodyId(base.0 + b2.0));
            }
            c.kind.transform(&t);
            desc.constraints.push(c);
        }
    }
}
