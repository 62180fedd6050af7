//! Where a bone's four particles go.
//!
//! **Improved** (automatic particulation, paper section 2.3, eqs. 28–31): four equal
//! masses `M/4` at alternate corners `(±a', ±b', ±c')` of a box aligned with the body's
//! principal axes reproduce mass, centre of mass and the whole inertia tensor when
//! `a'² = (I₂ + I₃ − I₁) / (2M)` (and cyclically): the second moments `Σ m x²` of the
//! four points are `M a'²`, their products `Σ m x y` cancel on alternate corners, and
//! `I₁ = M (b'² + c'²)`. For a box of half extents (a, b, c) this is `(±a, ±b, ±c)/√3`.
//! The same formula works for any shape whose inertia parry3d computes (capsule,
//! cylinder, cone, hull): ten equations, twelve unknowns, and this closed-form solution.
//!
//! **Paper** (appendix A.2): joint particles are shared between bones; the others are
//! put "inside their respective body part, as far away from each other as possible".

use crate::scene::{MassProps, Pose, Shape};
use glam::{Mat3, Quat, Vec3};

/// The improved placement: bone frame (in the shape frame), particle positions in the
/// bone frame, and the diagonal inertia they reproduce.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Particulation {
    /// The bone (principal, centre-of-mass) frame expressed in the shape frame.
    pub bone_in_shape: Pose,
    /// Particle positions in the bone frame.
    pub rest: [Vec3; 4],
    /// Principal moments of inertia (kg·m²).
    pub principal_inertia: Vec3,
}

/// Signs of the four alternate corners of a cube: a regular tetrahedron.
const CORNERS: [Vec3; 4] = [
    Vec3::new(1.0, 1.0, 1.0),
    Vec3::new(1.0, -1.0, -1.0),
    Vec3::new(-1.0, 1.0, -1.0),
    Vec3::new(-1.0, -1.0, 1.0),
];

/// Particulates a body from its mass properties (see the module doc).
pub(crate) fn particulate(mp: &MassProps) -> Particulation {
    let i = mp.inertia;
    let off = i.x_axis.y.abs() + i.x_axis.z.abs() + i.y_axis.z.abs();
    let diag = Vec3::new(i.x_axis.x, i.y_axis.y, i.z_axis.z);
    let (axes, moments) = if off <= 1e-6 * diag.max_element().max(1e-12) {
        (Mat3::IDENTITY, diag)
    } else {
        let e = parry3d::math::SymmetricEigen3::new(i);
        let mut m = e.eigenvectors;
        if m.determinant() < 0.0 {
            m.z_axis = -m.z_axis;
        }
        (m, e.eigenvalues)
    };
    let m = mp.mass;
    // Second moments C_k = Σ m x_k² = (I_j + I_l − I_k)/2; a degenerate (needle) body
    // could give 0, so keep a small floor to leave the tetrahedron a volume.
    let sum = moments.x + moments.y + moments.z;
    let c = Vec3::splat(sum * 0.5) - moments;
    let floor = (sum * 1e-4).max(1e-12);
    let half = (c.max(Vec3::splat(floor)) / m).map(f32::sqrt);
    let rest = CORNERS.map(|s| s * half);
    let rot = Quat::from_mat3(&axes).normalize();
    Particulation {
        bone_in_shape: Pose {
            position: mp.local_com,
            rotation: rot,
        },
        rest,
        principal_inertia: moments,
    }
}

/// Mass, centre of mass and inertia (about the centre of mass, in the frame of `rest`)
/// of equal point masses — what a particulation actually reproduces.
#[cfg(test)]
pub(crate) fn point_mass_props(mass: f32, rest: &[Vec3; 4]) -> (Vec3, Mat3) {
    let m = mass / 4.0;
    let com = rest.iter().copied().sum::<Vec3>() / 4.0;
    let mut inertia = Mat3::ZERO;
    for p in rest {
        let r = *p - com;
        inertia +=
            (Mat3::IDENTITY * r.length_squared() - Mat3::from_cols(r * r.x, r * r.y, r * r.z)) * m;
    }
    (com, inertia)
}

/// Candidate interior points for the paper's placement, in the shape frame: the corners
/// of the shape's box shrunk to lie inside it (boxes: the corners themselves, as the
/// paper's figure 31 shows; round shapes: corners of the inscribed box).
pub(crate) fn paper_candidates(shape: &Shape) -> [Vec3; 8] {
    let h = shape.local_half_extents();
    let s = match shape {
        Shape::Box { .. } => Vec3::ONE,
        Shape::Capsule {
            half_height,
            radius,
        } => Vec3::new(0.7, half_height / (half_height + radius), 0.7),
        _ => Vec3::new(0.6, 0.6, 0.6),
    };
    std::array::from_fn(|k| {
        let sign = Vec3::new(
            if k & 1 == 0 { 1.0 } else { -1.0 },
            if k & 2 == 0 { 1.0 } else { -1.0 },
            if k & 4 == 0 { 1.0 } else { -1.0 },
        );
        h * s * sign
    })
}

/// Whether `p` can join the points already chosen without making them degenerate
/// (coincident, collinear or coplanar), relative to the bone's size.
pub(crate) fn independent(chosen: &[Vec3], p: Vec3, size: f32) -> bool {
    let eps = 0.05 * size;
    match chosen.len() {
        0 => true,
        1 => chosen[0].distance(p) > eps,
        2 => (chosen[1] - chosen[0]).cross(p - chosen[0]).length() > eps * size,
        3 => {
            let v = (chosen[1] - chosen[0])
                .cross(chosen[2] - chosen[0])
                .dot(p - chosen[0])
                .abs();
            v > eps * size * size
        }
        _ => false,
    }
}

/// Greedy farthest-point fill: adds candidates until there are four points, each time
/// the candidate whose smallest distance to the chosen ones is largest.
pub(crate) fn fill_far_apart(chosen: &mut Vec<Vec3>, candidates: &[Vec3], size: f32) {
    while chosen.len() < 4 {
        let mut best: Option<(f32, Vec3)> = None;
        for &c in candidates {
            if !independent(chosen, c, size) {
                continue;
            }
            let d = chosen
                .iter()
                .map(|q| q.distance(c))
                .fold(f32::INFINITY, f32::min);
            if best.is_none_or(|(bd, _)| d > bd) {
                best = Some((d, c));
            }
        }
        match best {
            Some((_, c)) => chosen.push(c),
            None => break,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{BodyDesc, MassSpec, mass_props};

    fn check_reproduces(shape: Shape) {
        let b = BodyDesc::new("b", shape, Pose::IDENTITY, MassSpec::Mass(3.0));
        let mp = mass_props(&b).unwrap();
        let p = particulate(&mp);
        // Map the particles to the shape frame and compare there.
        let rest = p.rest.map(|r| p.bone_in_shape.transform_point(r));
        let (com, inertia) = point_mass_props(mp.mass, &rest);
        assert!(
            (com - mp.local_com).length() < 1e-5,
            "com {com} vs {}",
            mp.local_com
        );
        let scale = mp
            .inertia
            .x_axis
            .x
            .max(mp.inertia.y_axis.y)
            .max(mp.inertia.z_axis.z);
        for c in 0..3 {
            let d = (inertia.col(c) - mp.inertia.col(c)).abs().max_element();
            assert!(
                d < 1e-4 * scale,
                "inertia column {c}: {} vs {}",
                inertia.col(c),
                mp.inertia.col(c)
            );
        }
    }

    #[test]
    fn box_particles_are_alternate_corners_over_sqrt3() {
        let half = Vec3::new(0.3, 0.1, 0.2);
        let b = BodyDesc::new(
            "b",
            Shape::Box { half_extents: half },
            Pose::IDENTITY,
            MassSpec::Mass(2.0),
        );
        let p = particulate(&mass_props(&b).unwrap());
        for (r, s) in p.rest.iter().zip(CORNERS) {
            assert!((*r - s * half / 3f32.sqrt()).length() < 1e-5, "{r}");
        }
        check_reproduces(Shape::Box { half_extents: half });
    }

    #[test]
    fn round_shapes_and_hulls_reproduce_mass_com_inertia() {
        check_reproduces(Shape::Capsule {
            half_height: 0.2,
            radius: 0.05,
        });
        check_reproduces(Shape::Cylinder {
            half_height: 0.1,
            radius: 0.3,
            sides: 0,
        });
        check_reproduces(Shape::Cone {
            half_height: 0.2,
            radius: 0.1,
            sides: 0,
        });
        let pts: Vec<Vec3> = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.4, 0.1, 0.0),
            Vec3::new(0.1, 0.3, 0.05),
            Vec3::new(0.05, 0.1, 0.25),
            Vec3::new(0.3, 0.3, 0.3),
        ];
        check_reproduces(Shape::ConvexHull { points: pts.into() });
    }
}
