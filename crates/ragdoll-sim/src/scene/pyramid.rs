//! The frame of a pyramid swing limit, defined once for both methods as Doom 3 defines
//! it (dhewm3 `idAFConstraint_BallAndSocketJoint::SetPyramidLimit`, `AF.cpp`).
//!
//! Doom turns the limit's axis A into angles, `yaw = atan2(A_y, A_x)`,
//! `pitch = −atan2(A_z, √(A_x² + A_y²))`, takes the file's roll, and reads the rows of
//! `idAngles(pitch, yaw, roll).ToMat3()`:
//!
//! `M₀ = (cp cy, cp sy, −sp)`, `M₁ = (sr sp cy − cr sy, sr sp sy + cr cy, sr cp)`.
//!
//! The pyramid's axis is `B₂ = n(M₀)` (A itself), its first base axis
//! `B₀ = n(M₁ − B₂ (M₁·B₂))`, the second `B₁ = B₀ × B₂`. A shaft s is inside when its
//! angle from B₂ in the plane of B₂ and B₀ is at most the first half-angle and in the
//! plane of B₂ and B₁ at most the second. This is computed in Doom's Z-up frame, where
//! yaw and pitch mean what they say, and the result turned into our Y-up frame; the
//! turn `(x, y, z) ↦ (x, z, −y)` is a rotation, so `B₁ = B₀ × B₂` holds in both.

use glam::Vec3;

/// Our Y-up frame to Doom's Z-up one (the inverse of the `.af` reader's axes).
fn to_doom(v: Vec3) -> Vec3 {
    Vec3::new(v.x, -v.z, v.y)
}

/// Doom's Z-up frame to our Y-up one (the `.af` reader's axes).
fn from_doom(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.z, -v.y)
}

/// The base axes `(B₀, B₁)` of a pyramid limit around the unit `axis` (our frame),
/// rolled by `roll` radians: `half_angle1` bounds the shaft in the plane of the axis
/// and `B₀`, `half_angle2` in the plane of the axis and `B₁`. Both unit, perpendicular
/// to the axis and to each other.
pub fn pyramid_sides(axis: Vec3, roll: f32) -> (Vec3, Vec3) {
    let a = to_doom(axis);
    let yaw = a.y.atan2(a.x);
    let pitch = -a.z.atan2((a.x * a.x + a.y * a.y).sqrt());
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    let (sr, cr) = roll.sin_cos();
    let m0 = Vec3::new(cp * cy, cp * sy, -sp);
    let m1 = Vec3::new(sr * sp * cy - cr * sy, sr * sp * sy + cr * cy, sr * cp);
    let b2 = m0.normalize();
    let b0 = (m1 - b2 * m1.dot(b2)).normalize();
    let b1 = b0.cross(b2);
    (from_doom(b0), from_doom(b1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_are_an_orthonormal_frame_with_the_axis() {
        for axis in [
            Vec3::X,
            Vec3::Y,
            -Vec3::Y,
            Vec3::Z,
            Vec3::new(0.3, -0.8, 0.5),
        ] {
            let axis = axis.normalize();
            for roll in [0.0f32, 0.4, -1.3] {
                let (b0, b1) = pyramid_sides(axis, roll);
                assert!((b0.length() - 1.0).abs() < 1e-5 && (b1.length() - 1.0).abs() < 1e-5);
                assert!(b0.dot(axis).abs() < 1e-5 && b1.dot(axis).abs() < 1e-5);
                assert!(b0.dot(b1).abs() < 1e-5);
                // B₁ = B₀ × B₂ in our frame too.
                assert!((b0.cross(axis) - b1).length() < 1e-5);
            }
        }
    }

    #[test]
    fn doom_axis_along_x_gives_doom_y_then_rolls_towards_doom_z() {
        // Doom A = +X: yaw = pitch = 0, M₁ = (0, cr, sr): B₀ is Doom +Y at roll 0 and
        // turns towards Doom +Z with the roll.
        let (b0, _) = pyramid_sides(Vec3::X, 0.0);
        assert!((b0 - from_doom(Vec3::Y)).length() < 1e-6);
        let r = 0.5f32;
        let (b0, _) = pyramid_sides(Vec3::X, r);
        let expected = from_doom(Vec3::new(0.0, r.cos(), r.sin()));
        assert!((b0 - expected).length() < 1e-6);
    }
}
