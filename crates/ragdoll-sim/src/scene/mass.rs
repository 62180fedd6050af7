//! Mass properties of a body from its shape, via parry3d.
//!
//! Both methods take their masses from here so they simulate the same bodies: the
//! multibody method uses mass, centre of mass and inertia directly; the particle
//! method's improved mode places its particles to reproduce the same three.

use super::SceneError;
use super::desc::{BodyDesc, MassSpec, SceneDesc, Shape};
use glam::{DMat3, DVec3, Mat3, Vec3};
use parry3d::mass_properties::MassProperties;
use parry3d::shape::SharedShape;

/// The parry3d collider of a body's shape, shared by both methods so they collide the
/// same geometry. Round shapes in parry3d are Y-aligned like ours; a cone's base is at
/// −half_height and its apex at +half_height in both. Fails for a convex hull parry
/// cannot build (flat or fewer than four points), naming the body.
pub fn collider(body: &BodyDesc) -> Result<SharedShape, SceneError> {
    Ok(match &body.shape {
        Shape::Box { half_extents } => {
            SharedShape::cuboid(half_extents.x, half_extents.y, half_extents.z)
        }
        Shape::Capsule {
            half_height,
            radius,
        } => SharedShape::capsule_y(*half_height, *radius),
        Shape::Cylinder {
            half_height,
            radius,
            ..
        } => SharedShape::cylinder(*half_height, *radius),
        Shape::Cone {
            half_height,
            radius,
            ..
        } => SharedShape::cone(*half_height, *radius),
        Shape::ConvexHull { points } => {
            SharedShape::convex_hull(points).ok_or_else(|| SceneError::Degenerate {
                body: body.name.clone(),
                what: "its convex hull cannot be built".into(),
            })?
        }
    })
}

/// Mass, centre of mass and inertia of one body, in its shape frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassProps {
    /// Mass (kg).
    pub mass: f32,
    /// Centre of mass in the shape frame (m).
    pub local_com: Vec3,
    /// Inertia tensor about the centre of mass, in the shape frame's axes (kg·m²),
    /// with the body's `inertiaScale` applied.
    pub inertia: Mat3,
}

impl MassProps {
    /// Inverse inertia tensor (zero for a body with zero mass).
    pub fn inverse_inertia(&self) -> Mat3 {
        if self.mass <= 0.0 {
            Mat3::ZERO
        } else {
            self.inertia.inverse()
        }
    }
}

/// Unit-density mass properties of a shape: volume (m³), centre of mass and inertia
/// about it (shape frame).
struct UnitMass {
    volume: f32,
    local_com: Vec3,
    inertia: Mat3,
}

/// Volume (m³) and unit-density mass properties of a shape. The round shapes and the box
/// take parry3d's, whose principal frame is the shape's own; a convex hull's are
/// integrated here ([`hull_mass`]): parry3d 0.31 returns a hull's principal moments with
/// a wrong principal frame (Doom 3's `bone`, a bipyramid along Y, came back with its
/// smallest moment about X, its long axis's moment on a transverse axis; see also
/// dimforge/parry#252 on its polyhedral tensors). The tests below pin both paths to
/// closed forms.
fn unit_density(shape: &Shape) -> Option<UnitMass> {
    let mp = match shape {
        Shape::Box { half_extents } => MassProperties::from_cuboid(1.0, *half_extents),
        Shape::Capsule {
            half_height,
            radius,
        } => MassProperties::from_capsule(
            1.0,
            Vec3::new(0.0, -half_height, 0.0),
            Vec3::new(0.0, *half_height, 0.0),
            *radius,
        ),
        Shape::Cylinder {
            half_height,
            radius,
            ..
        } => MassProperties::from_cylinder(1.0, *half_height, *radius),
        Shape::Cone {
            half_height,
            radius,
            ..
        } => MassProperties::from_cone(1.0, *half_height, *radius),
        Shape::ConvexHull { points } => return hull_mass(points),
    };
    Some(UnitMass {
        volume: mp.mass(),
        local_com: mp.local_com,
        inertia: mp.reconstruct_inertia_matrix(),
    })
}

/// A convex hull's unit-density mass properties from its boundary triangles: each
/// triangle `(a, b, c)` (outward) spans with the origin a tetrahedron of signed volume
/// `d / 6`, `d = det[a b c]`, first moment `d (a + b + c) / 24` and second moment
/// `∫ x xᵀ = d A C₀ Aᵀ`, `A = [a b c]`, `C₀ = (1 + δ_ij) / 120` (Tonon 2004). Summed,
/// they give the hull's volume `V`, centroid `c` and covariance `C` about the origin;
/// about the centroid `C_c = C − V c cᵀ`, and the inertia is `tr(C_c) 1 − C_c`.
/// `None` for a hull parry3d cannot build or without volume.
fn hull_mass(points: &[Vec3]) -> Option<UnitMass> {
    let (vertices, triangles) = parry3d::transformation::try_convex_hull(points).ok()?;
    let v: Vec<DVec3> = vertices.iter().map(|p| p.as_dvec3()).collect();
    let (mut volume, mut moment, mut cov) = (0.0f64, DVec3::ZERO, DMat3::ZERO);
    for t in &triangles {
        let a = DMat3::from_cols(v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]);
        let d = a.determinant();
        volume += d / 6.0;
        moment += (a.x_axis + a.y_axis + a.z_axis) * (d / 24.0);
        let c0 = DMat3::from_cols_array(&[2.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 2.0]) / 120.0;
        cov += a * c0 * a.transpose() * d;
    }
    if !(volume.is_finite() && volume > 0.0) {
        return None;
    }
    let com = moment / volume;
    let about = cov - DMat3::from_cols(com * com.x, com * com.y, com * com.z) * volume;
    let trace = about.x_axis.x + about.y_axis.y + about.z_axis.z;
    let inertia = DMat3::from_diagonal(DVec3::splat(trace)) - about;
    Some(UnitMass {
        volume: volume as f32,
        local_com: com.as_vec3(),
        inertia: inertia.as_mat3(),
    })
}

/// Volume of a shape (m³); `None` for a degenerate hull.
pub fn volume(shape: &Shape) -> Option<f32> {
    unit_density(shape).map(|mp| mp.volume)
}

/// Mass properties of a body. With [`MassSpec::Mass`] the inertia is that of the shape at
/// the uniform density that gives this mass.
pub fn mass_props(body: &BodyDesc) -> Result<MassProps, SceneError> {
    let unit = unit_density(&body.shape).ok_or_else(|| SceneError::Degenerate {
        body: body.name.clone(),
        what: "its convex hull has no volume".into(),
    })?;
    let volume = unit.volume;
    if !(volume.is_finite() && volume > 0.0) {
        return Err(SceneError::Degenerate {
            body: body.name.clone(),
            what: format!("its shape has volume {volume}"),
        });
    }
    let mass = match body.mass {
        MassSpec::Density(d) => d * volume,
        MassSpec::Mass(m) => m,
    };
    if !(mass.is_finite() && mass > 0.0) {
        return Err(SceneError::Degenerate {
            body: body.name.clone(),
            what: format!("its mass is {mass} kg"),
        });
    }
    // Inertia scales linearly with density at fixed shape.
    let mut inertia = unit.inertia * (mass / volume);
    if let Some(s) = body.inertia_scale {
        // Doom 3 post-multiplies the tensor by the scale matrix (`I *= S`). For the usual
        // diagonal S and a tensor in principal axes that is symmetric; otherwise we keep
        // the symmetric part so the tensor stays a valid inertia.
        let scale = Mat3::from_cols_array_2d(&s).transpose();
        let scaled = inertia * scale;
        inertia = (scaled + scaled.transpose()) * 0.5;
    }
    Ok(MassProps {
        mass,
        local_com: unit.local_com,
        inertia,
    })
}

/// Mass properties of every body of a scene, indexed like `scene.bodies`. Fixed bodies
/// get their shape's mass too (a method treats them as infinite).
pub fn scene_mass_props(scene: &SceneDesc) -> Result<Vec<MassProps>, SceneError> {
    scene.bodies.iter().map(mass_props).collect()
}

impl SceneDesc {
    /// Turns every body's mass into kilograms ([`MassSpec::Mass`]) and applies Doom 3's
    /// `totalMass`: dynamic bodies are scaled by one factor so that they sum to it;
    /// fixed bodies keep their shape's mass. The `.af` reader calls this.
    pub fn resolve_masses(&mut self) -> Result<(), SceneError> {
        for b in &mut self.bodies {
            b.mass = MassSpec::Mass(mass_props(b)?.mass);
        }
        let kg = |m: MassSpec| match m {
            MassSpec::Mass(m) | MassSpec::Density(m) => m,
        };
        if let Some(total) = self.settings.total_mass {
            let sum: f32 = self
                .bodies
                .iter()
                .filter(|b| !b.is_fixed())
                .map(|b| kg(b.mass))
                .sum();
            if sum > 0.0 {
                let k = total / sum;
                for b in self.bodies.iter_mut().filter(|b| !b.is_fixed()) {
                    b.mass = MassSpec::Mass(kg(b.mass) * k);
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::desc::Pose;

    #[test]
    fn box_mass_and_inertia_match_closed_form() {
        let half = Vec3::new(0.5, 1.0, 1.5);
        let b = BodyDesc::new(
            "b",
            Shape::Box { half_extents: half },
            Pose::IDENTITY,
            MassSpec::Density(2.0),
        );
        let mp = mass_props(&b).unwrap();
        let (x, y, z) = (2.0 * half.x, 2.0 * half.y, 2.0 * half.z);
        let m = 2.0 * x * y * z;
        assert!((mp.mass - m).abs() < 1e-4);
        let ixx = m / 12.0 * (y * y + z * z);
        assert!((mp.inertia.col(0).x - ixx).abs() < 1e-3 * ixx);
        assert!(mp.local_com.length() < 1e-6);
    }

    #[test]
    fn given_mass_overrides_density() {
        let b = BodyDesc::new(
            "b",
            Shape::Capsule {
                half_height: 0.2,
                radius: 0.1,
            },
            Pose::IDENTITY,
            MassSpec::Mass(3.0),
        );
        assert!((mass_props(&b).unwrap().mass - 3.0).abs() < 1e-6);
    }

    /// The largest difference between two tensors' entries, relative to `a`'s largest.
    fn off(a: Mat3, b: Mat3) -> f32 {
        let scale = a.to_cols_array().iter().fold(0.0f32, |m, x| m.max(x.abs()));
        let d = (a - b).to_cols_array();
        d.iter().fold(0.0f32, |m, x| m.max(x.abs())) / scale
    }

    #[test]
    fn hull_of_a_turned_box_has_the_turned_box_inertia() {
        // A 0.2 × 0.6 × 1.0 m box given as its eight corners, turned and moved: its
        // tensor is `R diag(I) Rᵀ` about its centre, off-diagonal in the shape frame.
        let half = Vec3::new(0.1, 0.3, 0.5);
        let rot = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 1.1);
        let centre = Vec3::new(0.3, -0.2, 0.1);
        let pts: Vec<Vec3> = (0..8)
            .map(|k| {
                let s = Vec3::new(
                    if k & 1 == 0 { -1.0 } else { 1.0 },
                    if k & 2 == 0 { -1.0 } else { 1.0 },
                    if k & 4 == 0 { -1.0 } else { 1.0 },
                );
                centre + rot * (s * half)
            })
            .collect();
        let hull = BodyDesc::new(
            "hull",
            Shape::ConvexHull { points: pts.into() },
            Pose::IDENTITY,
            MassSpec::Density(3.0),
        );
        let mp = mass_props(&hull).unwrap();
        let (x, y, z) = (2.0 * half.x, 2.0 * half.y, 2.0 * half.z);
        let m = 3.0 * x * y * z;
        assert!((mp.mass - m).abs() < 1e-5 * m, "{} vs {m}", mp.mass);
        assert!(mp.local_com.distance(centre) < 1e-5, "{}", mp.local_com);
        let principal = Vec3::new(y * y + z * z, x * x + z * z, x * x + y * y) * (m / 12.0);
        let r = Mat3::from_quat(rot);
        let want = r * Mat3::from_diagonal(principal) * r.transpose();
        assert!(off(want, mp.inertia) < 1e-4, "{:?} vs {want:?}", mp.inertia);
    }

    #[test]
    fn doom_3_bone_turns_least_about_its_own_axis() {
        // Doom 3's `bone` is two pyramids over the triangle (0, w), (±w, −w/2) in x, z
        // with their tips at y = ±L (w half its width, L half its length). Over each
        // pyramid the cross-section at height t is the triangle scaled by 1 − t/L, so
        // with the triangle's area A = 1.5 w² and second moments ∫x² dA = A/12 · 2w²,
        // ∫z² dA = A/12 · 1.5w², ∫xz dA = 0: ∫x² dV = 2 · L/5 · A w²/6 = 0.1 L w⁴,
        // ∫z² dV = 0.075 L w⁴, ∫y² dV = 2 A ∫₀ᴸ t² (1 − t/L)² dt = 0.1 w² L³, V = w² L.
        let (w, l) = (0.0508f32, 0.1524f32);
        let b = BodyDesc::new(
            "bone",
            crate::scene::af::models::bone(l, 2.0 * w),
            Pose::IDENTITY,
            MassSpec::Density(1.0),
        );
        let mp = mass_props(&b).unwrap();
        let (xx, zz, yy) = (
            0.1 * l * w.powi(4),
            0.075 * l * w.powi(4),
            0.1 * w * w * l.powi(3),
        );
        assert!((mp.mass - w * w * l).abs() < 1e-5 * mp.mass);
        let want = Mat3::from_diagonal(Vec3::new(yy + zz, xx + zz, xx + yy));
        assert!(off(want, mp.inertia) < 1e-4, "{:?} vs {want:?}", mp.inertia);
        assert!(mp.local_com.length() < 1e-6);
    }

    #[test]
    fn flat_hull_is_rejected() {
        let pts: Vec<Vec3> = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
        let b = BodyDesc::new(
            "flat",
            Shape::ConvexHull { points: pts.into() },
            Pose::IDENTITY,
            MassSpec::Density(1.0),
        );
        assert!(mass_props(&b).is_err());
    }
}
