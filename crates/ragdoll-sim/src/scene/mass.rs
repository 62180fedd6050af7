//! Mass properties of a body from its shape, via parry3d.
//!
//! Both methods take their masses from here so they simulate the same bodies: the
//! multibody method uses mass, centre of mass and inertia directly; the particle
//! method's improved mode places its particles to reproduce the same three.

use super::SceneError;
use super::desc::{BodyDesc, MassSpec, SceneDesc, Shape};
use glam::{Mat3, Vec3};
use parry3d::mass_properties::MassProperties;
use parry3d::shape::{ConvexPolyhedron, Shape as _, SharedShape};

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

/// Volume (m³) and unit-density mass properties of a shape.
fn unit_density(shape: &Shape) -> Option<MassProperties> {
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
        Shape::ConvexHull { points } => {
            ConvexPolyhedron::from_convex_hull(points)?.mass_properties(1.0)
        }
    };
    Some(mp)
}

/// Volume of a shape (m³); `None` for a degenerate hull.
pub fn volume(shape: &Shape) -> Option<f32> {
    unit_density(shape).map(|mp| mp.mass())
}

/// Mass properties of a body. With [`MassSpec::Mass`] the inertia is that of the shape at
/// the uniform density that gives this mass.
pub fn mass_props(body: &BodyDesc) -> Result<MassProps, SceneError> {
    let unit = unit_density(&body.shape).ok_or_else(|| SceneError::Degenerate {
        body: body.name.clone(),
        what: "its convex hull has no volume".into(),
    })?;
    let volume = unit.mass();
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
    let mut inertia = unit.reconstruct_inertia_matrix() * (mass / volume);
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
