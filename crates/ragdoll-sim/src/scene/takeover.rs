//! The ragdoll taking over from an animation: a Doom 3 figure placed on an `.md5anim`
//! at any time, with every body's velocity taken from the animation (the paper's "start
//! position", section 5.4; Doom 3's death).
//!
//! Placement is the engine's (`idAF::SetupPose`), the inverse of the rule the figure's
//! build keeps in its [`Rig`]: each body on the joint it modifies,
//! R_b = R_j R_rel, p_b = p_j + R_j o ([`Rig::body_poses`]). The joints are the
//! animation's at time t in model space, with the root joint carrying the animation's
//! root motion from its first frame, Δ(t) = t₀(t) − t₀(0) (Doom 3 moves the entity by
//! that delta; the figure's build poses the skeleton with the root at the origin).
//!
//! Velocities are central differences over one frame, h = 1/frameRate:
//!
//! ```text
//! v = (c(t+h) − c(t−h)) / 2h           c: the body's centre of mass
//! ω = axis·angle(q(t+h) q(t−h)⁻¹) / 2h  world frame, the shorter way round
//! ```
//!
//! one-sided (over h) where t ± h leaves the animation's [0, (F−1)/R]. Doom 3 gives a
//! dying figure the animation's linear velocity only when its entity sets
//! `velocityTime`; here every take-over gets both velocities.
//!
//! Joints keep their meaning from the build pose: [`SceneDesc::repose`] moves them with
//! the bodies and shifts ranges measured from the rest pose.

use super::md5anim::Md5Anim;
use super::md5mesh::Md5Skeleton;
use super::rig::Rig;
use super::{Pose, SceneDesc, mass_props};
use glam::{Quat, Vec3};
use thiserror::Error;

/// Why a figure cannot take over from an animation.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TakeoverError {
    /// The figure was not built on a skeleton (no mesh, or copies of it).
    #[error(
        "figure \"{figure}\" has no skeleton to animate: it must be built on an .md5mesh, as one copy where its file puts it"
    )]
    NoSkeleton {
        /// The figure's name.
        figure: String,
    },
    /// The animation's joints are not the mesh's (Doom 3's `CheckModelHierarchy`).
    #[error("the animation {anim} does not fit the mesh: {why}")]
    Hierarchy {
        /// The animation as named to the user.
        anim: String,
        /// What differs.
        why: String,
    },
    /// A frame number past the animation's last.
    #[error("frame {frame} is out of range: the animation {anim} has frames 0 to {last}")]
    FrameOutOfRange {
        /// The animation as named to the user.
        anim: String,
        /// The frame asked for.
        frame: u32,
        /// Its last frame.
        last: u32,
    },
    /// The figure's masses cannot be computed.
    #[error("{0}")]
    Scene(#[from] super::SceneError),
}

/// A figure, the skeleton it was built on, and an animation of that skeleton.
#[derive(Clone, Debug)]
pub struct Takeover {
    figure: SceneDesc,
    rig: Rig,
    anim: Md5Anim,
    name: String,
    /// Each body's centre of mass in its shape frame.
    local_com: Vec<Vec3>,
}

impl Takeover {
    /// Checks that `anim` (named `name` in messages) fits `mesh`, the skeleton `rig` was
    /// built from; `figure` is the scene the build gave (its bodies in `rig`'s order).
    pub fn new(
        figure: &SceneDesc,
        rig: Option<&Rig>,
        mesh: &Md5Skeleton,
        anim: Md5Anim,
        name: &str,
    ) -> Result<Takeover, TakeoverError> {
        let rig = rig
            .filter(|r| r.body_rest.len() == figure.bodies.len())
            .ok_or_else(|| TakeoverError::NoSkeleton {
                figure: figure.name.clone(),
            })?;
        let hierarchy = |why: String| TakeoverError::Hierarchy {
            anim: name.to_string(),
            why,
        };
        anim.check_hierarchy(mesh).map_err(hierarchy)?;
        if rig.joints.len() != anim.joints.len() {
            return Err(hierarchy(format!(
                "the figure's skeleton has {} joints, the animation {}",
                rig.joints.len(),
                anim.joints.len()
            )));
        }
        let local_com = figure
            .bodies
            .iter()
            .map(|b| mass_props(b).map(|m| m.local_com))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Takeover {
            figure: figure.clone(),
            rig: rig.clone(),
            anim,
            name: name.to_string(),
            local_com,
        })
    }

    /// The animation.
    pub fn anim(&self) -> &Md5Anim {
        &self.anim
    }

    /// The figure as built (the rest pose its joints are defined in).
    pub fn figure(&self) -> &SceneDesc {
        &self.figure
    }

    /// The rig the figure drives its skeleton with.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// The time of frame `frame` (s), or an error past the last frame.
    pub fn frame_time(&self, frame: u32) -> Result<f32, TakeoverError> {
        let last = self.anim.frame_count() as u32 - 1;
        if frame > last {
            return Err(TakeoverError::FrameOutOfRange {
                anim: self.name.clone(),
                frame,
                last,
            });
        }
        Ok(frame as f32 / self.anim.frame_rate as f32)
    }

    /// Every joint's pose at `time` (s, clamped to the animation), in the figure's
    /// frame and units, the root moved by the root motion since frame 0.
    pub fn joint_poses(&self, time: f32) -> Vec<Pose> {
        let mut locals = self.anim.local_poses_within(time);
        locals[0].position -= self.anim.local_poses(0)[0].position;
        self.anim
            .compose(&locals)
            .iter()
            .map(|p| self.rig.from_file(p))
            .collect()
    }

    /// Every body's pose (shape frame) at `time`.
    pub fn body_poses(&self, time: f32) -> Vec<Pose> {
        self.rig.body_poses(&self.joint_poses(time))
    }

    /// Every body's (linear velocity of the centre of mass, angular velocity) at `time`,
    /// by the differences in the module docs.
    pub fn velocities(&self, time: f32) -> Vec<(Vec3, Vec3)> {
        let h = 1.0 / self.anim.frame_rate as f32;
        let end = self.anim.duration();
        let time = time.clamp(0.0, end);
        // A tolerance of a thousandth of a frame keeps frame 1 central when k/R − 1/R
        // rounds below zero.
        let slack = 1e-3 * h;
        let lo = if time - h < -slack { time } else { time - h };
        let hi = if time + h > end + slack {
            time
        } else {
            time + h
        };
        let span = hi - lo;
        if span <= 0.0 {
            return vec![(Vec3::ZERO, Vec3::ZERO); self.figure.bodies.len()];
        }
        let (a, b) = (self.body_poses(lo), self.body_poses(hi));
        a.iter()
            .zip(&b)
            .zip(&self.local_com)
            .map(|((a, b), c)| {
                let v = (b.transform_point(*c) - a.transform_point(*c)) / span;
                let mut turn = b.rotation * a.rotation.inverse();
                if turn.w < 0.0 {
                    turn = -turn;
                }
                let (axis, angle) = turn.normalize().to_axis_angle();
                let w = if angle.is_finite() && angle > 0.0 {
                    axis * (angle / span)
                } else {
                    Vec3::ZERO
                };
                (v, w)
            })
            .collect()
    }

    /// The figure at `time`: every dynamic body where the animation puts it with its
    /// velocities, the joints re-expressed for the new pose ([`SceneDesc::repose`]).
    pub fn scene_at(&self, time: f32) -> SceneDesc {
        let mut scene = self.figure.clone();
        let mut poses = self.body_poses(time);
        let velocities = self.velocities(time);
        for (i, b) in scene.bodies.iter().enumerate() {
            if b.is_fixed() {
                poses[i] = b.pose;
            }
        }
        scene.repose(&poses);
        for (b, (v, w)) in scene.bodies.iter_mut().zip(velocities) {
            if !b.is_fixed() {
                b.linear_velocity = v;
                b.angular_velocity = w;
            }
        }
        scene
    }

    /// The direction the animation's root moves over its length (unit, the figure's
    /// frame), when it moves at all: where a walk goes.
    pub fn root_motion(&self) -> Option<Vec3> {
        let first = self.anim.local_poses(0)[0].position;
        let last = self.anim.local_poses(self.anim.frame_count() - 1)[0].position;
        let d = self.rig.from_file(&Pose {
            position: last - first,
            rotation: Quat::IDENTITY,
        });
        d.position.try_normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::md5anim::{AnimJoint, BaseJoint};
    use crate::scene::md5mesh::Md5Joint;
    use crate::scene::rig::JointMod;
    use crate::scene::{BodyDesc, MassSpec, Shape};

    /// A two-joint skeleton (origin, and "bone" 1 unit up) with one box body driving
    /// "bone" by `mode`, offset from the joint; an animation of `frames` whose frame k
    /// gives (root translation, bone's parent-relative rotation).
    fn setup(frames: &[(Vec3, Quat)], rate: u32) -> Takeover {
        let mesh = Md5Skeleton {
            joints: vec![
                Md5Joint {
                    name: "origin".into(),
                    parent: None,
                    position: Vec3::ZERO,
                    orientation: Quat::IDENTITY,
                },
                Md5Joint {
                    name: "bone".into(),
                    parent: Some(0),
                    position: Vec3::Y,
                    orientation: Quat::IDENTITY,
                },
            ],
        };
        let body_pose = Pose {
            position: Vec3::new(0.3, 1.5, -0.2),
            rotation: Quat::from_rotation_x(0.3),
        };
        let mut figure = SceneDesc {
            name: "test".into(),
            ..Default::default()
        };
        figure.bodies.push(BodyDesc::new(
            "b",
            Shape::Box {
                half_extents: Vec3::new(0.1, 0.4, 0.1),
            },
            body_pose,
            MassSpec::Mass(2.0),
        ));
        let joints: Vec<(String, Option<usize>, Pose)> = mesh
            .joints
            .iter()
            .map(|j| (j.name.clone(), j.parent, j.pose()))
            .collect();
        let rig = Rig::new(&joints, &[(0, 1, JointMod::Both)], &[body_pose], None);
        // The file's x, y, z for a rotation q: `file_quat` gives (x, y, z, −w) with
        // w ≥ 0, which is q itself when q.w ≤ 0 (else −q, the same rotation).
        let file = |q: Quat| {
            let q = if q.w <= 0.0 { q } else { -q };
            Vec3::new(q.x, q.y, q.z)
        };
        let anim = Md5Anim {
            joints: vec![
                AnimJoint {
                    name: "origin".into(),
                    parent: None,
                    flags: 7,
                    start_index: 0,
                },
                AnimJoint {
                    name: "bone".into(),
                    parent: Some(0),
                    flags: 56,
                    start_index: 3,
                },
            ],
            frame_rate: rate,
            num_animated_components: 6,
            bounds: vec![[Vec3::ZERO, Vec3::ONE]; frames.len()],
            base: vec![
                BaseJoint {
                    position: Vec3::ZERO,
                    orientation: Vec3::ZERO,
                },
                BaseJoint {
                    position: Vec3::Y,
                    orientation: Vec3::ZERO,
                },
            ],
            frames: frames
                .iter()
                .map(|(t, q)| {
                    let x = file(*q);
                    vec![t.x, t.y, t.z, x.x, x.y, x.z]
                })
                .collect(),
        };
        Takeover::new(&figure, Some(&rig), &mesh, anim, "test").unwrap()
    }

    #[test]
    fn the_file_quaternion_helper_round_trips() {
        let q = Quat::from_rotation_z(0.7);
        let t = setup(&[(Vec3::ZERO, q), (Vec3::ZERO, q)], 10);
        let l = t.anim().local_poses(0);
        assert!(
            l[1].rotation.dot(q).abs() > 1.0 - 1e-6,
            "{:?}",
            l[1].rotation
        );
    }

    #[test]
    fn the_first_frame_of_the_build_pose_gives_the_figure_back() {
        let t = setup(&[(Vec3::ZERO, Quat::IDENTITY); 3], 24);
        let p = t.body_poses(0.0);
        let b = t.figure().bodies[0].pose;
        assert!(p[0].position.distance(b.position) < 1e-6);
        assert!(p[0].rotation.angle_between(b.rotation) < 1e-6);
    }

    #[test]
    fn a_body_translating_at_constant_speed_gets_exactly_that_velocity() {
        let v = Vec3::new(1.5, -0.25, 0.75);
        let rate = 24;
        let frames: Vec<(Vec3, Quat)> = (0..10)
            .map(|k| (v * (k as f32 / rate as f32), Quat::IDENTITY))
            .collect();
        let t = setup(&frames, rate);
        // Central in the middle, one-sided at both ends, and between frames.
        for time in [0.0, 1.0 / 24.0, 4.0 / 24.0, 0.123, 9.0 / 24.0] {
            let (lin, ang) = t.velocities(time)[0];
            assert!((lin - v).length() < 1e-4, "at {time}: {lin} vs {v}");
            assert!(ang.length() < 1e-5, "at {time}: {ang}");
        }
        let scene = t.scene_at(4.0 / 24.0);
        assert!((scene.bodies[0].linear_velocity - v).length() < 1e-4);
        let moved = scene.bodies[0].pose.position - t.figure().bodies[0].pose.position;
        assert!((moved - v * (4.0 / 24.0)).length() < 1e-5, "{moved}");
        assert!((t.root_motion().unwrap() - v.normalize()).length() < 1e-5);
    }

    #[test]
    fn a_body_rotating_at_constant_rate_gets_that_angular_velocity() {
        let axis = Vec3::new(0.3, 0.8, -0.5).normalize();
        let rate = 30;
        let speed = 2.5; // rad/s
        let frames: Vec<(Vec3, Quat)> = (0..12)
            .map(|k| {
                let a = speed * k as f32 / rate as f32;
                (Vec3::ZERO, Quat::from_axis_angle(axis, a))
            })
            .collect();
        let t = setup(&frames, rate);
        for time in [0.0, 5.0 / 30.0, 0.21, 11.0 / 30.0] {
            let (_, w) = t.velocities(time)[0];
            assert!((w - axis * speed).length() < 1e-3, "at {time}: {w}");
        }
    }

    #[test]
    fn frames_past_the_last_are_an_error() {
        let t = setup(&[(Vec3::ZERO, Quat::IDENTITY); 5], 24);
        assert!(t.frame_time(4).is_ok());
        let e = t.frame_time(5).unwrap_err();
        assert!(e.to_string().contains("frames 0 to 4"), "{e}");
    }
}
