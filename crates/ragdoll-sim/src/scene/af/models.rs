//! Doom 3 collision models as our shapes.
//!
//! Doom 3 builds its trace models (`idTraceModel::Setup*`) from a bounding box or two
//! bone ends; we build the same solids in the body's shape frame, already in metres and
//! our axes. Round models run along the shape frame's local Y, which is the file's up
//! axis (Doom 3's Z) after the axis mapping.

use crate::scene::Shape;
use glam::{Mat3, Quat, Vec3};
use std::f32::consts::TAU;
use std::sync::Arc;

/// A box-bounded model's size: half extents in the shape frame (metres, our axes).
pub fn boxed(half: Vec3) -> Shape {
    Shape::Box { half_extents: half }
}

/// Doom 3 `octahedron( min, max )`: the six face centres of the bounding box.
pub fn octahedron(half: Vec3) -> Shape {
    let pts = [
        Vec3::new(half.x, 0.0, 0.0),
        Vec3::new(-half.x, 0.0, 0.0),
        Vec3::new(0.0, half.y, 0.0),
        Vec3::new(0.0, -half.y, 0.0),
        Vec3::new(0.0, 0.0, half.z),
        Vec3::new(0.0, 0.0, -half.z),
    ];
    hull(&pts)
}

/// Doom 3 `dodecahedron( min, max )`: a regular dodecahedron scaled to fill the box.
pub fn dodecahedron(half: Vec3) -> Shape {
    // The 20 vertices of a regular dodecahedron: (±1, ±1, ±1), (0, ±1/φ, ±φ),
    // (±1/φ, ±φ, 0), (±φ, 0, ±1/φ); dividing by φ makes the extent 1 on every axis.
    let phi = (1.0 + 5f32.sqrt()) * 0.5;
    let a = 1.0 / phi;
    let mut pts = Vec::with_capacity(20);
    for sx in [-1.0f32, 1.0] {
        for sy in [-1.0f32, 1.0] {
            for sz in [-1.0f32, 1.0] {
                pts.push(Vec3::new(sx, sy, sz));
            }
            pts.push(Vec3::new(0.0, sx * a, sy * phi));
            pts.push(Vec3::new(sx * a, sy * phi, 0.0));
            pts.push(Vec3::new(sx * phi, 0.0, sy * a));
        }
    }
    let pts: Vec<Vec3> = pts.into_iter().map(|p| p / phi * half).collect();
    hull(&pts)
}

/// Doom 3 `cylinder( min, max, numSides )` along local Y. A circular cross-section
/// becomes our round cylinder (`sides` kept for drawing); an elliptic one a prism.
pub fn cylinder(half: Vec3, sides: u32) -> Shape {
    if round(half) {
        Shape::Cylinder {
            half_height: half.y,
            radius: half.x,
            sides,
        }
    } else {
        let ring = ellipse(half, sides);
        let mut pts: Vec<Vec3> = ring.iter().map(|p| *p - Vec3::Y * half.y).collect();
        pts.extend(ring.iter().map(|p| *p + Vec3::Y * half.y));
        hull(&pts)
    }
}

/// Doom 3 `cone( min, max, numSides )`: base at min along local Y, apex at max.
pub fn cone(half: Vec3, sides: u32) -> Shape {
    if round(half) {
        Shape::Cone {
            half_height: half.y,
            radius: half.x,
            sides,
        }
    } else {
        let mut pts: Vec<Vec3> = ellipse(half, sides)
            .iter()
            .map(|p| *p - Vec3::Y * half.y)
            .collect();
        pts.push(Vec3::Y * half.y);
        hull(&pts)
    }
}

/// Doom 3 `bone( start, end, width )` (`idTraceModel::SetupBone`): a triangular
/// bipyramid, its tips at the two ends and a triangle across its middle with one corner
/// `width / 2` to one side and two `width` apart `width / 4` to the other. In the shape
/// frame of [`bone_frame`] (local Y along the bone; local X and Z are Doom's bone axes x
/// and −y) the corners are (0, 0, w/2) and (±w/2, 0, −w/4). The triangle's centroid is
/// on the axis, so the centre of mass is the middle; the volume is w²·L/8.
pub fn bone(half_length: f32, width: f32) -> Shape {
    let w = width * 0.5;
    let pts = [
        Vec3::new(0.0, half_length, 0.0),
        Vec3::new(0.0, -half_length, 0.0),
        Vec3::new(0.0, 0.0, w),
        Vec3::new(w, 0.0, -0.5 * w),
        Vec3::new(-w, 0.0, -0.5 * w),
    ];
    hull(&pts)
}

/// The shape frame of a bone running along `dir` (the file's axes, not normalised),
/// as columns in the file's axes: Doom 3 (`idDeclAF_Body` with `idVec3::NormalVectors`)
/// takes z = dir/|dir|, x = (−z_y, z_x, 0)/|…| (or (1, 0, 0) for a bone along the
/// file's up axis), y = z × x; our frame is (x, z, −y), so that local Y runs along the
/// bone and the frame stays right-handed.
pub fn bone_frame(dir: Vec3) -> Mat3 {
    let z = dir.normalize();
    let d = z.x * z.x + z.y * z.y;
    let x = if d > 1e-12 {
        Vec3::new(-z.y, z.x, 0.0) / d.sqrt()
    } else {
        Vec3::X
    };
    let y = z.cross(x);
    Mat3::from_cols(x, z, -y)
}

/// The rotation taking local +Y to the unit direction `d` (shortest arc).
pub fn rotation_from_y(d: Vec3) -> Quat {
    Quat::from_rotation_arc(Vec3::Y, d)
}

fn round(half: Vec3) -> bool {
    (half.x - half.z).abs() <= 1e-5 * half.x.abs().max(half.z.abs())
}

/// `sides` points on the ellipse of half axes `half.x`, `half.z` (at least 8 when the
/// file asks for a smooth one with 0 sides).
fn ellipse(half: Vec3, sides: u32) -> Vec<Vec3> {
    let n = if sides >= 3 { sides.min(64) } else { 16 };
    (0..n)
        .map(|i| {
            let a = TAU * i as f32 / n as f32;
            Vec3::new(half.x * a.cos(), 0.0, half.z * a.sin())
        })
        .collect()
}

fn hull(points: &[Vec3]) -> Shape {
    Shape::ConvexHull {
        points: Arc::from(points),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mass::volume;

    #[test]
    fn dodecahedron_fills_its_box_and_has_the_regular_volume() {
        let s = dodecahedron(Vec3::ONE);
        assert!((s.local_half_extents() - Vec3::ONE).abs().max_element() < 1e-5);
        // Edge of the scaled dodecahedron: 2/φ² ... its volume is (15+7√5)/4 · a³ with
        // edge a = 2/φ / φ = 2/φ²  (vertices (±1,±1,±1)/φ).
        let phi = (1.0 + 5f32.sqrt()) * 0.5;
        let a = 2.0 / (phi * phi);
        let v = (15.0 + 7.0 * 5f32.sqrt()) / 4.0 * a * a * a;
        assert!((volume(&s).unwrap() - v).abs() < 1e-3 * v);
    }

    #[test]
    fn octahedron_volume_is_a_third_of_the_box_times_four_thirds() {
        // Octahedron with half diagonals a, b, c: V = 4abc/3.
        let s = octahedron(Vec3::new(1.0, 2.0, 3.0));
        assert!((volume(&s).unwrap() - 8.0).abs() < 1e-3);
    }

    #[test]
    fn bone_is_doom_3_s_triangular_bipyramid() {
        // idTraceModel::SetupBone(length 2, width 1): volume = triangle area · L / 3 =
        // (1 · 3/4 / 2) · 2 / 3 = 1/4 = w² L / 8; centroid on the axis.
        let s = bone(1.0, 1.0);
        assert!((volume(&s).unwrap() - 0.25).abs() < 1e-5);
        let h = s.local_half_extents();
        assert!(
            (h - Vec3::new(0.5, 1.0, 0.5)).abs().max_element() < 1e-6,
            "{h}"
        );
    }

    #[test]
    fn bone_frame_follows_doom_3_s_normal_vectors() {
        // A bone along the file's +X: z = X, x = (0, 1, 0), y = z × x = Z; ours (x, z, −y).
        let m = bone_frame(Vec3::new(3.0, 0.0, 0.0));
        assert!((m.x_axis - Vec3::Y).length() < 1e-6);
        assert!((m.y_axis - Vec3::X).length() < 1e-6);
        assert!((m.z_axis + Vec3::Z).length() < 1e-6);
        assert!((m.determinant() - 1.0).abs() < 1e-6);
        // Along the up axis: x = (1, 0, 0).
        let m = bone_frame(Vec3::new(0.0, 0.0, -2.0));
        assert!((m.x_axis - Vec3::X).length() < 1e-6);
        assert!((m.y_axis + Vec3::Z).length() < 1e-6);
        assert!((m.determinant() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn elliptic_cylinder_is_a_prism() {
        assert!(matches!(
            cylinder(Vec3::new(1.0, 1.0, 1.0), 8),
            Shape::Cylinder { .. }
        ));
        assert!(matches!(
            cylinder(Vec3::new(1.0, 1.0, 2.0), 8),
            Shape::ConvexHull { .. }
        ));
    }
}
