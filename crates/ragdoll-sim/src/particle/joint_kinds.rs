//! What joints of one kind share, kept once: the joint's type and axes, its limits, its
//! rest relative orientation, compliance and friction (a [`JointKind`]).
//!
//! A joint's own data are its sides, its anchors and its slack ([`Joint`]); the rest is
//! its constant description, the same for the joints built from one constraint of
//! figures placed alike. A pile of humans, every other layer turned, has twenty kinds
//! for the fifteen joints of a human in its two orientations, however many humans, each
//! joint naming its kind by index, instead of a copy per joint.
//!
//! Kinds are equal when their fields are bit for bit equal, so sharing one changes no
//! number a solver reads. Every field of a kind is in the bones' frames, computed from
//! their orientations at rest alone (`q_b⁻¹ q_a`, `q⁻¹ d`): figures placed at different
//! positions with the same orientation get the same bits. The anchors are computed from
//! the placed world positions too (`q⁻¹ (p − o)`), which rounds differently at each
//! place: they stay with the joint. The paper solver's bone frames are measured from
//! the particles it placed, which round differently too: its joints share a kind only
//! where the bits agree.

use super::joints::{Joint, JointType};
use super::limits::{AngleLimit, Swing, SwingLimit};
use glam::Quat;
use std::collections::HashMap;

/// What every joint of one kind holds alike: read by each joint's solve, at the
/// building of a run's lanes (`joint_lanes::Lockstep::new`) and by measurement and
/// drawing.
#[derive(Clone, Debug)]
pub(crate) struct JointKind {
    /// Orientation of body1 relative to body2 at rest, `q_b⁻¹ q_a`.
    pub rest_rel: Quat,
    /// Type-specific data.
    pub joint_type: JointType,
    /// Hinge range, universal axis ranges, or twist limit.
    pub angle_limits: Box<[AngleLimit]>,
    /// Swing limit.
    pub swing: Option<SwingLimit>,
    /// Compliance of the limits (m/N-like; 0 = hard), from the PyODE soft limit.
    pub limit_compliance: f32,
    /// Whether this joint is drawn and measured by its anchor.
    pub has_anchor: bool,
    /// Largest joint friction torque (N·m, 0 for none): `Joint::new`.
    pub friction_torque: f32,
}

/// The kinds of a world's joints, each kept once ([`Joint::kind`] indexes them).
#[derive(Default)]
pub(crate) struct JointKinds {
    kinds: Vec<JointKind>,
    /// While the world is built: each kind's bits to its index, so that equal ones are
    /// kept once. Dropped by [`JointKinds::seal`].
    index: Option<HashMap<Vec<u32>, u32>>,
}

impl JointKinds {
    /// An empty table that shares equal kinds until [`JointKinds::seal`].
    pub fn building() -> JointKinds {
        JointKinds {
            kinds: Vec::new(),
            index: Some(HashMap::new()),
        }
    }

    /// Stops sharing (drops the index) and gives back the room the array does not use.
    pub fn seal(&mut self) {
        self.index = None;
        self.kinds.shrink_to_fit();
    }

    /// The kind of joint `j`.
    #[inline]
    pub fn of(&self, j: &Joint) -> &JointKind {
        &self.kinds[j.kind as usize]
    }

    /// How many kinds the table keeps.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.kinds.len()
    }

    /// The index of `kind`: an equal one's while building, else a new one.
    pub fn kind(&mut self, kind: JointKind) -> u32 {
        let next = self.kinds.len() as u32;
        let index = match &mut self.index {
            Some(ix) => *ix.entry(kind_bits(&kind)).or_insert(next),
            None => next,
        };
        if index == next {
            self.kinds.push(kind);
        }
        index
    }
}

/// Every bit of a kind that tells it from another: a tag for each variant and the
/// floats of every field, in order.
fn kind_bits(k: &JointKind) -> Vec<u32> {
    let mut bits: Vec<u32> = Vec::with_capacity(64);
    let mut floats = |tag: u32, v: &[f32]| {
        bits.push(tag);
        bits.extend(v.iter().map(|x| x.to_bits()));
    };
    floats(0, &k.rest_rel.to_array());
    match k.joint_type {
        JointType::Ball => floats(1, &[]),
        JointType::Hinge { axis_a, axis_b } => {
            floats(2, &[axis_a.to_array(), axis_b.to_array()].concat())
        }
        JointType::Universal { shaft_a, shaft_b } => {
            floats(3, &[shaft_a.to_array(), shaft_b.to_array()].concat())
        }
        JointType::Fixed => floats(4, &[]),
        JointType::Slider { axis_b } => floats(5, &axis_b.to_array()),
        JointType::Spring {
            stretch,
            compress,
            rest,
            min,
            max,
        } => floats(6, &[stretch, compress, rest, min, max]),
    }
    for l in &k.angle_limits {
        let v = [
            l.axis_a.to_array().as_slice(),
            &l.ref_b.to_array(),
            &l.rest_rel.to_array(),
            &[l.min, l.max],
            &l.inside,
        ]
        .concat();
        floats(7, &v);
    }
    match &k.swing {
        None => floats(8, &[]),
        Some(s) => {
            let dirs = [s.shaft_a.to_array(), s.axis_b.to_array()].concat();
            floats(9, &dirs);
            match s.kind {
                Swing::Cone {
                    half_angle,
                    cos_inside,
                } => floats(10, &[half_angle, cos_inside]),
                Swing::Pyramid { h1, h2, u, v } => floats(
                    11,
                    &[[h1, h2].as_slice(), &u.to_array(), &v.to_array()].concat(),
                ),
            }
        }
    }
    floats(
        12,
        &[
            k.limit_compliance,
            f32::from(u8::from(k.has_anchor)),
            k.friction_torque,
        ],
    );
    bits
}

#[cfg(test)]
mod tests {
    use super::super::scene_world;
    use std::collections::HashSet;

    /// The humans of a pile laid alike share their joints' kinds: the pile of four
    /// (two layers, the second turned) keeps at most one kind per joint of a human and
    /// layer, and the two humans of the first layer name the same kinds, joint by joint.
    #[test]
    fn humans_of_a_pile_share_joint_kinds() {
        let w = scene_world("pile.af", Some(4));
        let per_human = w.joints.len() / 4;
        assert_eq!(w.joints.len(), 4 * per_human);
        let human = |h: usize| &w.joints[h * per_human..(h + 1) * per_human];
        for (i, (a, b)) in human(0).iter().zip(human(1)).enumerate() {
            assert_eq!(a.kind, b.kind, "joint {i}: a kind of its own");
        }
        let kinds: HashSet<u32> = w.joints.iter().map(|j| j.kind).collect();
        assert_eq!(kinds.len(), w.joint_kinds.len(), "a kind no joint names");
        assert!(w.joint_kinds.len() <= 2 * per_human);
        assert!(
            w.joint_kinds.index.is_none(),
            "the index outlives the build"
        );
    }
}
