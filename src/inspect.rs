//! What the inspector shows about a clicked body: its mass and velocities, and the angle
//! of each of its joints against that joint's limit, read from the bodies' orientations
//! (the same reading for both methods, whatever each solves internally).
//!
//! With `R_i = q_i(t) q_i(0)⁻¹` each body's rotation since the rest pose, a hinge's angle
//! is the twist of `D = R₂⁻¹ R₁` about the hinge axis, `2 atan2(a · D_xyz, D_w)` (body1
//! relative to body2, right-handed, zero at rest: the convention of `AngleRange`), and a
//! cone's swing is the angle between the shaft carried by body1, `R₁ s`, and the cone
//! axis carried by body2, `R₂ a`.

use glam::Quat;
use ragdoll_sim::BodyState;
use ragdoll_sim::scene::{BodyId, BodyRef, JointKind, SceneDesc, SwingLimit};

/// One joint of the inspected body, read now.
#[derive(Clone, Debug, PartialEq)]
pub struct JointReading {
    /// The constraint's name.
    pub name: String,
    /// "hinge", "ball", ...
    pub kind: &'static str,
    /// What is measured: the hinge angle, the cone swing, or the turn since rest (deg).
    pub angle_deg: f32,
    /// The limit the angle is held to (deg), if the joint has one of this form.
    pub limit_deg: Option<(f32, f32)>,
}

impl JointReading {
    /// Degrees beyond the limit (0 inside it).
    pub fn excess_deg(&self) -> f32 {
        match self.limit_deg {
            Some((lo, hi)) => (lo - self.angle_deg).max(self.angle_deg - hi).max(0.0),
            None => 0.0,
        }
    }
}

/// Each body's rotation since its rest pose, `q(t) q(0)⁻¹`; the world's is the identity.
fn since_rest(desc: &SceneDesc, states: &[BodyState], body: BodyRef) -> Quat {
    match body {
        BodyRef::World => Quat::IDENTITY,
        BodyRef::Body(id) => {
            let i = id.index();
            match (states.get(i), desc.bodies.get(i)) {
                (Some(s), Some(d)) => (s.orientation * d.pose.rotation.inverse()).normalize(),
                _ => Quat::IDENTITY,
            }
        }
    }
}

/// The readings of every joint `body` takes part in.
pub fn joint_readings(desc: &SceneDesc, states: &[BodyState], body: BodyId) -> Vec<JointReading> {
    desc.constraints
        .iter()
        .filter(|c| c.body1 == body || c.body2 == BodyRef::Body(body))
        .map(|c| {
            let r1 = since_rest(desc, states, BodyRef::Body(c.body1));
            let r2 = since_rest(desc, states, c.body2);
            let d = r2.inverse() * r1;
            let turn = || d.angle_between(Quat::IDENTITY).to_degrees();
            let (kind, angle_deg, limit_deg) = match &c.kind {
                JointKind::Hinge { axis, limit, .. } => {
                    let twist = 2.0 * axis.dot(d.xyz()).atan2(d.w);
                    let twist = wrap_pi(twist);
                    (
                        "hinge",
                        twist.to_degrees(),
                        limit.map(|l| (l.min.to_degrees(), l.max.to_degrees())),
                    )
                }
                JointKind::BallAndSocket { swing, .. } | JointKind::Universal { swing, .. } => {
                    let kind = if matches!(c.kind, JointKind::Universal { .. }) {
                        "universal"
                    } else {
                        "ball"
                    };
                    match swing {
                        Some(SwingLimit::Cone {
                            axis,
                            half_angle,
                            shaft,
                        }) => {
                            let swing = (r1 * *shaft).angle_between(r2 * *axis);
                            (
                                kind,
                                swing.to_degrees(),
                                Some((0.0, half_angle.to_degrees())),
                            )
                        }
                        _ => (kind, turn(), None),
                    }
                }
                _ => ("other", turn(), None),
            };
            JointReading {
                name: c.name.clone(),
                kind,
                angle_deg,
                limit_deg,
            }
        })
        .collect()
}

/// `a` in (−π, π].
fn wrap_pi(a: f32) -> f32 {
    let tau = std::f32::consts::TAU;
    let a = a.rem_euclid(tau);
    if a > std::f32::consts::PI { a - tau } else { a }
}

/// The speed of a body's centre (m/s) and its spin (rad/s).
pub fn speeds(state: &BodyState) -> (f32, f32) {
    (
        state.linear_velocity.length(),
        state.angular_velocity.length(),
    )
}

/// Height of a body's centre above the ground's top (m), or above y = 0 without one.
pub fn height(desc: &SceneDesc, state: &BodyState) -> f32 {
    state.com.y - desc.settings.ground.map_or(0.0, |g| g.height)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use ragdoll_sim::scene::{AngleRange, BodyDesc, ConstraintDesc, MassSpec, Pose, Shape};

    fn scene(kind: JointKind) -> SceneDesc {
        let body = |name: &str, x: f32| {
            BodyDesc::new(
                name.to_string(),
                Shape::Box {
                    half_extents: Vec3::splat(0.1),
                },
                Pose {
                    position: Vec3::new(x, 1.0, 0.0),
                    rotation: Quat::from_rotation_y(0.3),
                },
                MassSpec::Mass(1.0),
            )
        };
        SceneDesc {
            bodies: vec![body("a", 0.0), body("b", 0.3)],
            constraints: vec![ConstraintDesc {
                name: "j".into(),
                body1: BodyId(0),
                body2: BodyRef::Body(BodyId(1)),
                kind,
                friction: 0.0,
            }],
            ..Default::default()
        }
    }

    fn states(desc: &SceneDesc, turn1: Quat, turn2: Quat) -> Vec<BodyState> {
        [turn1, turn2]
            .iter()
            .zip(&desc.bodies)
            .map(|(t, b)| BodyState {
                com: b.pose.position,
                orientation: *t * b.pose.rotation,
                linear_velocity: Vec3::ZERO,
                angular_velocity: Vec3::ZERO,
            })
            .collect()
    }

    #[test]
    fn a_hinge_reads_body1s_turn_relative_to_body2_about_its_axis() {
        let axis = Vec3::Z;
        let desc = scene(JointKind::Hinge {
            anchor: Vec3::new(0.15, 1.0, 0.0),
            axis,
            limit: Some(AngleRange {
                min: -0.5,
                max: 0.5,
            }),
        });
        // Both turned alike about another axis, then body1 a further 40° about the hinge.
        let common = Quat::from_rotation_x(0.7);
        let s = states(
            &desc,
            Quat::from_axis_angle(common * axis, 40f32.to_radians()) * common,
            common,
        );
        // The hinge axis is carried by body2: compare in body2's frame.
        let r = &joint_readings(&desc, &s, BodyId(0))[0];
        assert_eq!(r.kind, "hinge");
        assert!((r.angle_deg - 40.0).abs() < 0.05, "{r:?}");
        let limit = 0.5f32.to_degrees();
        assert!((r.excess_deg() - (40.0 - limit)).abs() < 0.05, "{r:?}");
        assert_eq!(
            joint_readings(&desc, &s, BodyId(1)).len(),
            1,
            "seen from body2 too"
        );
    }

    #[test]
    fn a_cone_reads_the_swing_between_shaft_and_axis() {
        let desc = scene(JointKind::BallAndSocket {
            anchor: Vec3::new(0.15, 1.0, 0.0),
            swing: Some(SwingLimit::Cone {
                axis: Vec3::X,
                half_angle: 0.25,
                shaft: Vec3::X,
            }),
            twist: None,
            limit_style: Default::default(),
        });
        let s = states(&desc, Quat::from_rotation_z(0.4), Quat::IDENTITY);
        let r = &joint_readings(&desc, &s, BodyId(0))[0];
        assert!((r.angle_deg - 0.4f32.to_degrees()).abs() < 0.05, "{r:?}");
        assert!((r.excess_deg() - (0.4f32 - 0.25).to_degrees()).abs() < 0.05);
    }
}
