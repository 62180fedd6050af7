//! Shots that hit the skinned mesh (Doom 3's `containedJoints`): a box shot with B is
//! also a projectile against the visual mesh of a figure that has one.
//!
//! Before every step, on each side separately, each shot's path over the step is cast
//! against that side's mesh skinned on its bodies' current poses (the pose that is
//! drawn). The path is the one its leading face sweeps along its centre line: from
//! c + v̂ s to c + v̂ s + v Δt, with c the box's centre, v its velocity and s its extent
//! ahead of the centre, s = a Σᵢ |v̂ · eᵢ| for half edge a and the box's axes eᵢ (so a
//! box meets the mesh when its front does, not when its centre does, and before its
//! front reaches a collision shape just inside the mesh). Gravity bends the path by
//! g Δt²/2, a fraction of a millimetre, which is left out.
//!
//! At the first triangle crossed, the joint nearest to the hit point is found and the
//! body containing it ([`ragdoll_sim::scene::BodyDesc::contained_joints`]) receives the
//! shot's momentum J = m v as an impulse at the hit point; the shot receives −J at its
//! centre of mass, so it stops where it is and falls: a perfectly inelastic hit that
//! keeps the pair's momentum. The shot then no longer hits the mesh on that side (a
//! stopped shot delivers nothing more; the collision shapes still collide with it).
//! When no body contains the nearest joint, nothing is pushed and the shot flies on,
//! also no longer hitting the mesh on that side.
//!
//! A shot is cast before the physics moves it, so it reaches the mesh before it
//! reaches any collision shape lying inside the mesh: where the mesh stands outside the
//! collision shapes (a forearm's tube around its thinner bone) only the mesh is hit.

use crate::render::skin::SkinModel;
use glam::Vec3;
use ragdoll_sim::scene::{BodyId, Pose};
use ragdoll_sim::{BodyState, Method, RenderSnapshot};

/// One shot's hit on one side's mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshImpact {
    /// The side: 0 particle (left), 1 multibody (right).
    pub side: usize,
    /// The shot (its body in that side's method).
    pub shot: BodyId,
    /// The hit point on the mesh (world, m).
    pub point: Vec3,
    /// The skeleton joint nearest to it.
    pub joint: usize,
    /// The body that took the shot's momentum; `None` if no body contains the joint.
    pub body: Option<BodyId>,
    /// The impulse the body took (N·s); zero when `body` is `None`.
    pub impulse: Vec3,
}

/// A shot in flight: its body on each side, its mass and half edge, and whether it may
/// still hit each side's mesh.
#[derive(Clone, Copy, Debug)]
struct Shot {
    body: [BodyId; 2],
    mass: f32,
    half_edge: f32,
    live: [bool; 2],
}

/// The shots that may still hit the mesh, and scratch space for casting them.
#[derive(Default)]
pub(crate) struct MeshTargets {
    shots: Vec<Shot>,
    states: Vec<BodyState>,
    snapshot: RenderSnapshot,
    poses: Vec<Pose>,
}

impl MeshTargets {
    /// Records a box shot added to both methods (`body` on each side) of mass `mass`
    /// (kg) and half edge `half_edge` (m).
    pub(crate) fn add_shot(&mut self, body: [BodyId; 2], mass: f32, half_edge: f32) {
        self.shots.push(Shot {
            body,
            mass,
            half_edge,
            live: [true; 2],
        });
    }

    /// Casts every live shot's path over the next step of `dt` seconds against each
    /// side's mesh and applies the impulses of the hits (see the module docs). Returns
    /// the hits. `scene_bodies` is the number of the scene's own bodies (the rig's).
    pub(crate) fn before_step(
        &mut self,
        skin: &SkinModel,
        methods: &mut [Box<dyn Method>; 2],
        scene_bodies: usize,
        dt: f32,
    ) -> Vec<MeshImpact> {
        let mut impacts = Vec::new();
        for (side, method) in methods.iter_mut().enumerate() {
            if !self.shots.iter().any(|s| s.live[side]) {
                continue;
            }
            method.body_states(&mut self.states);
            // Only a moving shot can cross the mesh; skip posing it otherwise.
            let moving = |s: &Shot| {
                s.live[side]
                    && self
                        .states
                        .get(s.body[side].index())
                        .is_some_and(|st| st.linear_velocity != Vec3::ZERO)
            };
            if !self.shots.iter().any(moving) {
                continue;
            }
            method.snapshot(&mut self.snapshot);
            self.poses.clear();
            self.poses.resize(scene_bodies, Pose::IDENTITY);
            for b in &self.snapshot.bodies {
                if let Some(p) = self.poses.get_mut(b.body.index()) {
                    *p = b.pose;
                }
            }
            let joints = skin.joint_poses(&self.poses);
            let posed = skin.skinned.posed(&joints);
            for shot in self.shots.iter_mut().filter(|s| s.live[side]) {
                let Some(st) = self.states.get(shot.body[side].index()).copied() else {
                    shot.live[side] = false;
                    continue;
                };
                let ahead = st.linear_velocity.normalize_or_zero();
                let reach = [Vec3::X, Vec3::Y, Vec3::Z]
                    .iter()
                    .map(|e| ahead.dot(st.orientation * *e).abs())
                    .sum::<f32>()
                    * shot.half_edge;
                let from = st.com + ahead * reach;
                let Some(hit) = posed.cast_segment(from, from + st.linear_velocity * dt) else {
                    continue;
                };
                shot.live[side] = false;
                let momentum = st.linear_velocity * shot.mass;
                let impulse = match hit.body {
                    Some(body) => {
                        method.apply_impulse(body, momentum, hit.point);
                        method.apply_impulse(shot.body[side], -momentum, st.com);
                        momentum
                    }
                    None => Vec3::ZERO,
                };
                impacts.push(MeshImpact {
                    side,
                    shot: shot.body[side],
                    point: hit.point,
                    joint: hit.joint,
                    body: hit.body,
                    impulse,
                });
            }
        }
        self.shots.retain(|s| s.live.iter().any(|l| *l));
        impacts
    }
}
