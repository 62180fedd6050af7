//! The XPBD particle solver: a ragdoll made of particles (Macklin et al. 2019, "Small
//! steps in physics simulation", on the particles of the paper's section 3).
//!
//! Each particle has its own position and velocity (`particles`). A bone is four
//! particles placed by exact particulation (`placement`, the paper's future work of
//! section 5.4: they reproduce the bone's mass, centre of mass and inertia tensor), held
//! by the six sticks of their tetrahedron, solved together and exactly in each pass by
//! SHAKE, forces along the sticks as they were at the substep's start (`shape_match`).
//! Joints couple points that are fixed affine combinations of their bones' particles,
//! and hinge axes and limits are angles of the frames the particles imply, corrected by
//! moving the particles along those constraints' gradients (`joints`). Contacts come from
//! a broad phase and parry3d's narrow phase on those frames and push particles with
//! barycentric weights (`contacts`). The bone frame is read from the particles by shape
//! matching (`frame`) — for drawing, collision shapes, limits and metrics — and never
//! moved as a rigid body. Joint friction is a capped angular impulse on the particles'
//! velocities (`friction`). The loop is in `step`; islands sleep in `sleeping`; the
//! metrics read the particles' own velocities (`measure`).

pub(crate) mod contact_block;
pub(crate) mod contacts;
pub(crate) mod frame;
pub(crate) mod friction;
pub(crate) mod joint_block;
pub(crate) mod joints;
pub(crate) mod measure;
pub(crate) mod particles;
pub(crate) mod shape_match;
pub(crate) mod sleeping;
pub(crate) mod step;

use super::bone::Bone;
use super::bone_kinds::BoneKinds;
use super::joints::Joint;
use glam::Vec3;
use joints::Anchor;
use particles::XParticles;

/// The solver's own state, beside the world's bones (whose frames it writes) and joints.
#[derive(Default)]
pub(crate) struct XpbdState {
    /// Every particle; bone `i` owns `4i .. 4i + 4`.
    pub particles: XParticles,
    /// Per joint, its point on each side.
    pub anchors: Vec<[Anchor; 2]>,
    /// Per joint, what its block keeps through the current substep.
    pub joint_start: Vec<Option<joint_block::Start>>,
    /// The block joints' limit multipliers through the current substep, as many as
    /// each joint's limits take (`joint_block::begin_substep`).
    pub limit_lambda: Vec<f64>,
    /// The contacts of the current detection.
    pub contacts: Vec<contacts::Contact>,
    /// What detections reuse.
    pub scratch: contacts::Scratch,
    /// Per bone, its rest timers.
    pub rest: Vec<sleeping::Rest>,
}

impl XpbdState {
    /// Adds bone `i`'s particles, at rest positions in its frame moving with its initial
    /// velocities.
    pub fn add_bone(&mut self, i: usize, b: &Bone, kinds: &BoneKinds) {
        debug_assert_eq!(self.rest.len(), i);
        let rest = &kinds.placement(b).rest;
        let x = std::array::from_fn(|k| Vec3::from(b.world(rest[k])));
        let (v, om) = (glam::Vec3::from(b.lin_vel), glam::Vec3::from(b.ang_vel));
        let c = Vec3::from(b.center());
        let vel = x.map(|xk: Vec3| v + om.cross(xk - c));
        self.particles.push_bone(x, vel, b.mass * 0.25, !b.fixed);
        self.rest.push(sleeping::Rest {
            anchor: c,
            ..Default::default()
        });
    }

    /// The state for `bones` (particulated, at their rest frames) and `joints`.
    pub fn new(bones: &mut [Bone], kinds: &BoneKinds, joints: &[Joint]) -> XpbdState {
        let mut st = XpbdState::default();
        for (i, b) in bones.iter_mut().enumerate() {
            st.add_bone(i, b, kinds);
        }
        st.anchors = joints
            .iter()
            .map(|j| {
                let side = |s: Option<usize>, local: Vec3| match s {
                    Some(i) => Anchor::Bone(
                        i as u32,
                        frame::weights(&kinds.placement(&bones[i]).rest, local),
                    ),
                    None => Anchor::World(local),
                };
                [side(j.a(), j.anchor_a), side(j.b(), j.anchor_b)]
            })
            .collect();
        st.particles.shrink_to_fit();
        st.rest.shrink_to_fit();
        st
    }
}
