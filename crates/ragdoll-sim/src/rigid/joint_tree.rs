//! The point rows of the joints solved exactly, a tree of bodies at a time: Baraff's
//! linear-time factorisation of the constrained system ("Linear-Time Dynamics using
//! Lagrange Multipliers", SIGGRAPH 1996).
//!
//! Gauss–Seidel solves one joint after the other, and a joint's row between a light body
//! and a heavy one barely moves the heavy one: a 50 kg box hanging from five 0.5 kg
//! links needs hundreds of passes to be held, so at a few passes per substep the soft
//! joints sag as springs whose stiffness is the light link's mass times ω² (the chain
//! opened 39 mm gaps and stretched by 8 %). Solving all point rows of a tree together
//! makes the solve independent of the mass ratio.
//!
//! The system of one solve: body velocity changes `Δv` (6 per body: linear, angular) and
//! point impulses `λ` (3 per joint), with `G` the joints' Jacobian,
//!
//! ```text
//! [ M  Gᵀ ] [ Δv ]   [  0 ]
//! [ G  0  ] [ −λ ] = [ −r ]        r = Ċ + bias (the soft step's right-hand side)
//! ```
//!
//! i.e. `Δv = M⁻¹ Gᵀ λ` with `G Δv = −r`. Its graph (a node per body and per joint, an
//! edge where a joint acts on a body) is a tree when the joints form no loop, and
//! eliminating its nodes leaves first creates no fill-in: the factorisation is a 6×6 or
//! 3×3 block per node and one block per edge, and each solve one pass up the tree and
//! one down. Per joint, `G` is `[1, −r̂_b]` on body2 and `−[1, −r̂_a]` on body1 (the
//! anchor's velocity `v + ω × r`), so `Gᵀ p` is `(p, r × p)`, the impulse `p` at the anchor.
//!
//! The tree's leaves must be bodies (a joint's pivot `−G D⁻¹ Gᵀ` needs a child body), so
//! a tree whose joint holds it to a static body is rooted at that joint; a second such
//! joint, or a joint closing a loop, stays with Gauss–Seidel. Static, fixed and sleeping
//! bodies (zero inverse mass) are not nodes: a joint to them has one body.
//!
//! The rows are rigid: the biased pass asks `G Δv = −(Ċ + β C / h)` (see
//! [`TREE_BIAS`]), the relax pass `G Δv = −Ċ`. (The general update
//! `λ += −s_m K⁻¹ r − s_i λ_acc` of a soft row is kept in [`JointTrees::solve`]; with
//! soft rows a frictionless pendulum's bob hangs on a spring and loses the energy of its
//! sag.) Only trees with a joint across a large mass ratio ([`MASS_RATIO`]) or to a
//! static body are solved this way; the others stay with the soft Gauss–Seidel rows.
//!
//! Determinism: a tree's nodes are ordered by its own joints' and bodies' relative order
//! only, so a tree solved alone (an island on another thread) gets the bits it gets in
//! the whole world.

use super::body::BodyStates;
use super::joint::PointPart;
use super::joint_set::JointSet;
use super::soft::{Softness, StepContext};
use glam::{Mat3, Vec3, Vec3A};

type Matrix6 = Mat<6, 6>;
type Matrix3 = Mat<3, 3>;
type Matrix6x3 = Mat<6, 3>;
type Matrix3x6 = Mat<3, 6>;
type Vector6 = Mat<6, 1>;
type Vector3 = Mat<3, 1>;

/// A joint whose point rows are in a tree: its type's array and index.
#[derive(Clone, Copy, Debug, PartialEq)]
enum JointRef {
    Ball(usize),
    Hinge(usize),
    Universal(usize),
}

/// A node of a tree: a body or a joint, with the block to its parent.
#[derive(Clone, Copy, Debug)]
enum Node {
    /// A moving body (index into the states).
    Body {
        body: usize,
        /// `D⁻¹`, 6×6.
        d_inv: Matrix6,
        /// `D⁻¹ H_{self,parent}` to the parent joint (6×3); unused at the root.
        up: Matrix6x3,
    },
    /// A joint's point rows.
    Joint {
        joint: JointRef,
        /// `D⁻¹`, 3×3.
        d_inv: Matrix3,
        /// `D⁻¹ H_{self,parent}` to the parent body (3×6); unused at the root.
        up: Matrix3x6,
    },
}

/// Where a node's value lives during a solve: 6 entries for a body, 3 for a joint.
#[derive(Clone, Copy, Debug)]
enum Value {
    Body(Vector6),
    Joint(Vector3),
}

/// The trees of one solve (the whole world, or one island's batch).
#[derive(Clone, Debug, Default)]
pub struct JointTrees {
    /// Every tree's nodes, leaves first, each tree's root last; trees one after another.
    nodes: Vec<Node>,
    /// Parent of each node (index into `nodes`), `usize::MAX` at a root.
    parent: Vec<usize>,
    /// Whether the last factorisation was usable (finite); otherwise the joints of the
    /// trees fall back to Gauss–Seidel for the substep.
    ok: bool,
    /// What the trees were built from: per body, its inverse mass when it moves, zero
    /// otherwise; then, per ball joint, hinge and universal joint in that order, its two
    /// bodies. The trees depend on nothing else, so while this is unchanged (every
    /// step of a world whose sleep states and joints do not change) they are kept.
    built_from: Vec<f32>,
    built_joints: Vec<(usize, usize)>,
    /// Scratch of `factor`, kept between calls so the substeps allocate nothing: `D` of
    /// every joint node and of every body node (indexed by node).
    d_joint: Vec<Matrix3>,
    d_body: Vec<Matrix6>,
    /// Scratch of `solve`: every node's value.
    x: Vec<Value>,
}

const NO_PARENT: usize = usize::MAX;

/// Mass ratio across a joint above which its tree is solved directly; a joint to a
/// static body counts as an infinite ratio (a frictionless pendulum on the soft row
/// hangs on a spring: it lost 2.6 % of its swing energy in 10 s at 5°, 9.9 % at 60°,
/// 0.7 % on the rigid row). Gauss–Seidel
/// converges at a rate set by the mass ratios it couples: at a few to one (the spiders,
/// the capsule human, 3:1 at most) its soft joints hold within a millimetre, and there
/// the soft rows are kept; the exact rigid rows then made the soft contacts the weakest
/// link (a capsule foot landing on the obstacle went 17 mm in, as every iteration's
/// exact joint solve pulled the foot back down with the whole body's momentum, against
/// a contact row that weighs the foot alone). At 27:1 (the human's neck against its
/// head) and 100:1 (a heavy box on light links) Gauss–Seidel leaves the joints sagging.
const MASS_RATIO: f32 = 10.0;

/// Fraction of a tree joint's gap closed per substep by the biased pass (Baumgarte's
/// β). At 1 the rows of a resting human's feet and the soft contacts under them kept
/// trading the same millimetre and it never slept; at 0.3 it sleeps at 2.5 s, and a
/// frictionless pendulum loses 0.7 % of its energy in 10 s (0.2: 0.8 %).
const TREE_BIAS: f32 = 0.3;

/// Union–find over bodies, each set knowing whether a joint holds it to a static body.
struct Sets {
    up: Vec<usize>,
    anchored: Vec<bool>,
}

impl Sets {
    fn find(&mut self, mut i: usize) -> usize {
        while self.up[i] != i {
            self.up[i] = self.up[self.up[i]];
            i = self.up[i];
        }
        i
    }
}

impl JointTrees {
    /// [`JointTrees::build`] into `self`, unless the bodies' motion and the joints are
    /// those of the last build: then the trees are kept and only the joints' flags are
    /// set again (an island solved elsewhere in between may have changed them).
    pub fn rebuild(&mut self, joints: &mut JointSet, s: &BodyStates, awake: &[bool]) {
        let n = s.len();
        let moving = |i: usize| i < awake.len() && awake[i] && s.inv_mass[i] > 0.0;
        let masses = (0..n).map(|i| if moving(i) { s.inv_mass[i] } else { 0.0 });
        let pairs = |joints: &JointSet| {
            all_refs(joints)
                .map(|r| frame_bodies(joints, r))
                .collect::<Vec<_>>()
        };
        // Bitwise, so that any change of a mass rebuilds.
        let same = self.built_from.len() == n
            && (self.built_from.iter().zip(masses.clone()))
                .all(|(a, b)| a.to_bits() == b.to_bits())
            && self.built_joints.len() == all_refs(joints).count()
            && (self.built_joints.iter().zip(all_refs(joints)))
                .all(|(&p, r)| p == frame_bodies(joints, r));
        if same {
            for r in all_refs(joints) {
                let point = point_of_mut(joints, r);
                point.direct = false;
                point.in_tree = false;
            }
            let mut count = 0;
            for node in &self.nodes {
                if let Node::Joint { joint, .. } = *node {
                    let point = point_of_mut(joints, joint);
                    point.direct = true;
                    point.in_tree = true;
                    count += 1;
                }
            }
            joints.direct = count > 0;
            joints.tree_points = count;
            self.ok = true;
            return;
        }
        let built = JointTrees::build(joints, s, awake);
        self.nodes = built.nodes;
        self.parent = built.parent;
        self.ok = built.ok;
        self.built_from.clear();
        self.built_from.extend(masses);
        self.built_joints = pairs(joints);
    }

    /// Picks the ball joints and hinges whose point rows form trees over the moving
    /// bodies (inverse mass > 0, awake), marks them `direct` (their own solve then skips
    /// the point rows) and orders each tree leaves first. Joints that would close a loop
    /// stay with Gauss–Seidel.
    pub fn build(joints: &mut JointSet, s: &BodyStates, awake: &[bool]) -> JointTrees {
        let n = s.len();
        let moving = |i: usize| i < awake.len() && awake[i] && s.inv_mass[i] > 0.0;
        let mut sets = Sets {
            up: (0..n).collect(),
            anchored: vec![false; n],
        };
        // Tree joints and, per moving body, the tree joints acting on it (in order).
        let mut chosen: Vec<(JointRef, usize, usize)> = Vec::new();
        for r in all_refs(joints) {
            let (f, point) = match r {
                JointRef::Ball(i) => (joints.ball[i].frame, &mut joints.ball[i].point),
                JointRef::Hinge(i) => (joints.hinge[i].frame, &mut joints.hinge[i].point),
                JointRef::Universal(i) => {
                    (joints.universal[i].frame, &mut joints.universal[i].point)
                }
            };
            point.direct = false;
            point.in_tree = false;
            let (ma, mb) = (moving(f.a), moving(f.b));
            let accept = match (ma, mb) {
                (true, true) => {
                    let (ra, rb) = (sets.find(f.a), sets.find(f.b));
                    if ra == rb || (sets.anchored[ra] && sets.anchored[rb]) {
                        false
                    } else {
                        let anchored = sets.anchored[ra] || sets.anchored[rb];
                        sets.up[ra] = rb;
                        sets.anchored[rb] = anchored;
                        true
                    }
                }
                (true, false) | (false, true) => {
                    let root = sets.find(if ma { f.a } else { f.b });
                    if sets.anchored[root] {
                        false
                    } else {
                        sets.anchored[root] = true;
                        true
                    }
                }
                (false, false) => false,
            };
            if accept {
                point.direct = true;
                chosen.push((
                    r,
                    if ma { f.a } else { NO_PARENT },
                    if mb { f.b } else { NO_PARENT },
                ));
            }
        }
        let mut trees = JointTrees {
            ok: true,
            ..JointTrees::default()
        };
        // Only trees with a large mass ratio across a joint are solved directly.
        let mut lopsided = vec![false; n];
        for &(_, a, b) in &chosen {
            if a != NO_PARENT && b != NO_PARENT {
                let (ia, ib) = (s.inv_mass[a], s.inv_mass[b]);
                if ia.max(ib) > MASS_RATIO * ia.min(ib) {
                    let root = sets.find(a);
                    lopsided[root] = true;
                }
            } else {
                // A joint to a static body: an infinite mass ratio.
                let root = sets.find(if a != NO_PARENT { a } else { b });
                lopsided[root] = true;
            }
        }
        chosen.retain(|&(r, a, b)| {
            let root = sets.find(if a != NO_PARENT { a } else { b });
            let keep = lopsided[root];
            let point = point_of_mut(joints, r);
            point.direct = keep;
            point.in_tree = keep;
            keep
        });
        joints.direct = !chosen.is_empty();
        joints.tree_points = chosen.len();
        if chosen.is_empty() {
            return trees;
        }
        // Adjacency: body → its tree joints, in joint order.
        let mut body_joints: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (k, &(_, a, b)) in chosen.iter().enumerate() {
            for body in [a, b] {
                if body != NO_PARENT {
                    body_joints[body].push(k);
                }
            }
        }
        // One tree per set, rooted at its anchoring joint or at its first body; breadth
        // first from the root, then reversed so every node comes after its children.
        let mut seen_joint = vec![false; chosen.len()];
        let mut seen_body = vec![false; n];
        let mut order: Vec<(bool, usize, usize)> = Vec::new(); // (is_body, index, parent slot)
        let roots: Vec<(bool, usize)> = {
            let mut r = Vec::new();
            // Anchoring joints first, in joint order, then the first body of each set
            // without one, in body order.
            for (k, &(_, a, b)) in chosen.iter().enumerate() {
                if a == NO_PARENT || b == NO_PARENT {
                    r.push((false, k));
                }
            }
            for (body, list) in body_joints.iter().enumerate() {
                if !list.is_empty() {
                    r.push((true, body));
                }
            }
            r
        };
        for (is_body, index) in roots {
            if (is_body && seen_body[index]) || (!is_body && seen_joint[index]) {
                continue;
            }
            let start = order.len();
            order.push((is_body, index, NO_PARENT));
            if is_body {
                seen_body[index] = true;
            } else {
                seen_joint[index] = true;
            }
            let mut next = start;
            while next < order.len() {
                let (node_is_body, i, _) = order[next];
                if node_is_body {
                    for &k in &body_joints[i] {
                        if !seen_joint[k] {
                            seen_joint[k] = true;
                            order.push((false, k, next));
                        }
                    }
                } else {
                    let (_, a, b) = chosen[i];
                    for body in [a, b] {
                        if body != NO_PARENT && !seen_body[body] {
                            seen_body[body] = true;
                            order.push((true, body, next));
                        }
                    }
                }
                next += 1;
            }
            // This tree, reversed: children before parents.
            let len = order.len() - start;
            let base = trees.nodes.len();
            for slot in (start..order.len()).rev() {
                let (node_is_body, i, parent) = order[slot];
                trees.nodes.push(if node_is_body {
                    Node::Body {
                        body: i,
                        d_inv: Matrix6::ZERO,
                        up: Matrix6x3::ZERO,
                    }
                } else {
                    Node::Joint {
                        joint: chosen[i].0,
                        d_inv: Matrix3::ZERO,
                        up: Matrix3x6::ZERO,
                    }
                });
                // Slot `slot` of `order` lands at `base + (order.len() - 1 - slot)`.
                trees.parent.push(if parent == NO_PARENT {
                    NO_PARENT
                } else {
                    base + (start + len - 1 - parent)
                });
            }
        }
        trees
    }

    /// Whether there is anything to solve.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Factorises the trees on the current pose and inertias and the anchors of the
    /// joints' last `prepare`. A tree that does not factorise (a degenerate inertia)
    /// hands its joints back to Gauss–Seidel.
    pub fn factor(&mut self, joints: &mut JointSet, s: &BodyStates) {
        // `D` of every node, children subtracted as they are eliminated.
        let mut d_joint = std::mem::take(&mut self.d_joint);
        let mut d_body = std::mem::take(&mut self.d_body);
        d_joint.clear();
        d_joint.resize(self.nodes.len(), Matrix3::ZERO);
        d_body.clear();
        d_body.resize(self.nodes.len(), Matrix6::ZERO);
        for (k, node) in self.nodes.iter().enumerate() {
            if let Node::Body { body, .. } = *node {
                d_body[k] = body_mass(s, body);
            }
        }
        let mut ok = true;
        for k in 0..self.nodes.len() {
            let parent = self.parent[k];
            match self.nodes[k] {
                Node::Body { body, .. } => {
                    let Some(d_inv) = d_body[k].try_inverse_blocks() else {
                        ok = false;
                        break;
                    };
                    let up = if parent == NO_PARENT {
                        Matrix6x3::ZERO
                    } else {
                        let Node::Joint { joint, .. } = self.nodes[parent] else {
                            unreachable!("a body's parent is a joint")
                        };
                        let (sign, x) =
                            arm(point_of(joints, joint), frame_bodies(joints, joint), body);
                        // Parent joint: D_j −= G D_b⁻¹ Gᵀ; up = D_b⁻¹ Gᵀ.
                        let (g_d_gt, d_gt) = body_through_joint(&d_inv, sign, x);
                        d_joint[parent].sub_mat3(g_d_gt);
                        d_gt
                    };
                    self.nodes[k] = Node::Body { body, d_inv, up };
                }
                Node::Joint { joint, .. } => {
                    let Some(d_inv) = d_joint[k].try_inverse() else {
                        ok = false;
                        break;
                    };
                    let up = if parent == NO_PARENT {
                        Matrix3x6::ZERO
                    } else {
                        let Node::Body { body, .. } = self.nodes[parent] else {
                            unreachable!("a joint's parent is a body")
                        };
                        let (sign, x) =
                            arm(point_of(joints, joint), frame_bodies(joints, joint), body);
                        // Parent body: D_b −= Gᵀ D_j⁻¹ G; up = D_j⁻¹ G.
                        let (gt_d_g, d_g) = joint_through_body(&d_inv, sign, x);
                        d_body[parent] -= gt_d_g;
                        d_g
                    };
                    self.nodes[k] = Node::Joint { joint, d_inv, up };
                }
            }
        }
        ok &= self.nodes.iter().all(|node| match node {
            Node::Body { d_inv, up, .. } => d_inv.is_finite() && up.is_finite(),
            Node::Joint { d_inv, up, .. } => d_inv.is_finite() && up.is_finite(),
        });
        self.ok = ok;
        self.d_joint = d_joint;
        self.d_body = d_body;
        for node in &self.nodes {
            if let Node::Joint { joint, .. } = *node {
                point_of_mut(joints, joint).direct = ok;
            }
        }
    }

    /// One block update of every tree's point rows: the exact `λ' = K⁻¹(−r)` with
    /// `r = Ċ + bias_rate · C`, then the soft step's `λ += s_m λ' − s_i λ_acc`. The relax
    /// pass (`use_bias` false) solves rigidly with `r = Ċ`.
    pub fn solve(
        &mut self,
        joints: &mut JointSet,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        if !self.ok || self.nodes.is_empty() {
            return;
        }
        // Rigid rows; the biased pass closes the fraction `TREE_BIAS` of the gap over
        // the substep (`bias = β C / h`), and the relax pass takes that velocity back.
        let soft = if use_bias {
            Softness {
                bias_rate: TREE_BIAS * ctx.inv_h,
                ..Softness::RIGID
            }
        } else {
            Softness::RIGID
        };
        // Right-hand sides: zero for bodies, −r for joints.
        let mut x = std::mem::take(&mut self.x);
        x.clear();
        x.extend(self.nodes.iter().map(|node| match *node {
            Node::Body { .. } => Value::Body(Vector6::ZERO),
            Node::Joint { joint, .. } => {
                let (a, b) = frame_bodies(joints, joint);
                let p = point_of(joints, joint);
                let cdot = s.point_velocity(b, p.rb()) - s.point_velocity(a, p.ra());
                let r = cdot + soft.bias_rate * p.c();
                Value::Joint(Mat([[-r.x], [-r.y], [-r.z]]))
            }
        }));
        // Up the tree: x_parent −= upᵀ x_child.
        for k in 0..self.nodes.len() {
            let parent = self.parent[k];
            if parent == NO_PARENT {
                continue;
            }
            match (self.nodes[k], x[k]) {
                (Node::Body { up, .. }, Value::Body(v)) => {
                    if let Value::Joint(ref mut xp) = x[parent] {
                        *xp -= up.t() * v;
                    }
                }
                (Node::Joint { up, .. }, Value::Joint(v)) => {
                    if let Value::Body(ref mut xp) = x[parent] {
                        *xp -= up.t() * v;
                    }
                }
                _ => unreachable!("node and value kinds match"),
            }
        }
        for (node, v) in self.nodes.iter().zip(x.iter_mut()) {
            match (node, v) {
                (Node::Body { d_inv, .. }, Value::Body(v)) => *v = *d_inv * *v,
                (Node::Joint { d_inv, .. }, Value::Joint(v)) => *v = *d_inv * *v,
                _ => unreachable!("node and value kinds match"),
            }
        }
        // Down the tree: x_child −= up x_parent.
        for k in (0..self.nodes.len()).rev() {
            let parent = self.parent[k];
            if parent == NO_PARENT {
                continue;
            }
            let xp = x[parent];
            match (self.nodes[k], &mut x[k], xp) {
                (Node::Body { up, .. }, Value::Body(v), Value::Joint(p)) => *v -= up * p,
                (Node::Joint { up, .. }, Value::Joint(v), Value::Body(p)) => *v -= up * p,
                _ => unreachable!("a tree alternates bodies and joints"),
            }
        }
        // Apply: bodies get s_m Δv', each joint's accumulated impulse decays by s_i.
        for (node, v) in self.nodes.iter().zip(&x) {
            match (node, v) {
                (Node::Body { body, .. }, Value::Body(dv)) => {
                    let b = *body;
                    let dv = dv.0;
                    s.lin_vel[b] += Vec3A::new(dv[0][0], dv[1][0], dv[2][0]) * soft.mass_scale;
                    s.ang_vel[b] += Vec3A::new(dv[3][0], dv[4][0], dv[5][0]) * soft.mass_scale;
                }
                (Node::Joint { joint, .. }, Value::Joint(y)) => {
                    let y = y.0;
                    let lambda = -Vec3A::new(y[0][0], y[1][0], y[2][0]);
                    let f = frame_of(joints, *joint);
                    let p = point_of_mut(joints, *joint);
                    let decay = -soft.impulse_scale * p.impulse;
                    if soft.impulse_scale != 0.0 {
                        p.apply(&f, s, decay);
                    }
                    p.impulse += soft.mass_scale * lambda + decay;
                }
                _ => unreachable!("node and value kinds match"),
            }
        }
        self.x = x;
    }
}

/// `M = diag(m 1, I)` of body `i`, with `I` the world inertia now.
fn body_mass(s: &BodyStates, i: usize) -> Matrix6 {
    let m = 1.0 / s.inv_mass[i];
    let inertia = Mat3::from(s.inv_inertia[i]).inverse();
    let mut out = Matrix6::ZERO;
    for r in 0..3 {
        out.0[r][r] = m;
        for c in 0..3 {
            out.0[3 + r][3 + c] = inertia.col(c)[r];
        }
    }
    out
}

/// The 3×6 block of a joint's point rows on `body` as `G = σ [1, X]`: the sign `σ` (+1
/// on body2, −1 on body1) and `X = −r̂` with `r` the anchor's offset from that body
/// (`Ċ = v_b + ω_b × r_b − v_a − ω_a × r_a`, and `−r̂ ω = ω × r`).
fn arm(p: &PointPart, (a, b): (usize, usize), body: usize) -> (f32, Mat3) {
    let (r, sign) = if body == b {
        (Vec3::from(p.rb()), 1.0)
    } else {
        debug_assert_eq!(body, a);
        (Vec3::from(p.ra()), -1.0)
    };
    // −r̂ by columns: (0, −r_z, r_y), (r_z, 0, −r_x), (−r_y, r_x, 0).
    let x = Mat3::from_cols(
        Vec3::new(0.0, -r.z, r.y),
        Vec3::new(r.z, 0.0, -r.x),
        Vec3::new(-r.y, r.x, 0.0),
    );
    (sign, x)
}

/// A body's elimination into its parent joint, by 3×3 blocks: with `D⁻¹ = [P Q; R S]`
/// and `G = σ [1, X]`, `G D⁻¹ Gᵀ = P + Q Xᵀ + X (R + S Xᵀ)` (σ² = 1) and
/// `D⁻¹ Gᵀ = σ [P + Q Xᵀ; R + S Xᵀ]` — a few 3×3 products for the dense 3×6·6×6·6×3.
fn body_through_joint(d_inv: &Matrix6, sign: f32, x: Mat3) -> (Mat3, Matrix6x3) {
    let (p, q) = (d_inv.block(0, 0), d_inv.block(0, 3));
    let (r, s) = (d_inv.block(3, 0), d_inv.block(3, 3));
    let xt = x.transpose();
    let top = p + q * xt;
    let bottom = r + s * xt;
    let g_d_gt = top + x * bottom;
    let mut d_gt = Matrix6x3::ZERO;
    for c in 0..3 {
        let (t, b) = (top.col(c) * sign, bottom.col(c) * sign);
        for k in 0..3 {
            d_gt.0[k][c] = t[k];
            d_gt.0[3 + k][c] = b[k];
        }
    }
    (g_d_gt, d_gt)
}

/// A joint's elimination into its parent body, by 3×3 blocks: with `G = σ [1, X]`,
/// `Gᵀ D⁻¹ G = [D⁻¹, D⁻¹ X; Xᵀ D⁻¹, Xᵀ D⁻¹ X]` and `D⁻¹ G = σ [D⁻¹, D⁻¹ X]`.
fn joint_through_body(d_inv: &Matrix3, sign: f32, x: Mat3) -> (Matrix6, Matrix3x6) {
    let m = &d_inv.0;
    let d = Mat3::from_cols(
        Vec3::new(m[0][0], m[1][0], m[2][0]),
        Vec3::new(m[0][1], m[1][1], m[2][1]),
        Vec3::new(m[0][2], m[1][2], m[2][2]),
    );
    let d_x = d * x;
    let xt_d = x.transpose() * d;
    let xt_d_x = xt_d * x;
    let mut gt_d_g = Matrix6::ZERO;
    gt_d_g.set_block(0, 0, d);
    gt_d_g.set_block(0, 3, d_x);
    gt_d_g.set_block(3, 0, xt_d);
    gt_d_g.set_block(3, 3, xt_d_x);
    let mut d_g = Matrix3x6::ZERO;
    for c in 0..3 {
        let (l, r) = (d.col(c) * sign, d_x.col(c) * sign);
        for k in 0..3 {
            d_g.0[k][c] = l[k];
            d_g.0[k][3 + c] = r[k];
        }
    }
    (gt_d_g, d_g)
}

/// Every ball joint, hinge and universal joint, in that order.
fn all_refs(joints: &JointSet) -> impl Iterator<Item = JointRef> + use<> {
    (0..joints.ball.len())
        .map(JointRef::Ball)
        .chain((0..joints.hinge.len()).map(JointRef::Hinge))
        .chain((0..joints.universal.len()).map(JointRef::Universal))
}

fn point_of(joints: &JointSet, j: JointRef) -> &PointPart {
    match j {
        JointRef::Ball(i) => &joints.ball[i].point,
        JointRef::Hinge(i) => &joints.hinge[i].point,
        JointRef::Universal(i) => &joints.universal[i].point,
    }
}

fn point_of_mut(joints: &mut JointSet, j: JointRef) -> &mut PointPart {
    match j {
        JointRef::Ball(i) => &mut joints.ball[i].point,
        JointRef::Hinge(i) => &mut joints.hinge[i].point,
        JointRef::Universal(i) => &mut joints.universal[i].point,
    }
}

fn frame_of(joints: &JointSet, j: JointRef) -> super::joint::JointFrame {
    match j {
        JointRef::Ball(i) => joints.ball[i].frame,
        JointRef::Hinge(i) => joints.hinge[i].frame,
        JointRef::Universal(i) => joints.universal[i].frame,
    }
}

fn frame_bodies(joints: &JointSet, j: JointRef) -> (usize, usize) {
    let f = frame_of(joints, j);
    (f.a, f.b)
}

/// A small dense matrix, row-major: the blocks of the factorisation.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Mat<const R: usize, const C: usize>([[f32; C]; R]);

impl<const R: usize, const C: usize> Mat<R, C> {
    const ZERO: Self = Mat([[0.0; C]; R]);

    /// The transpose.
    fn t(&self) -> Mat<C, R> {
        let mut out = Mat::<C, R>::ZERO;
        for r in 0..R {
            for c in 0..C {
                out.0[c][r] = self.0[r][c];
            }
        }
        out
    }

    fn is_finite(&self) -> bool {
        self.0.iter().flatten().all(|x| x.is_finite())
    }
}

impl Matrix6 {
    /// The 3×3 block at row `r0`, column `c0`.
    fn block(&self, r0: usize, c0: usize) -> Mat3 {
        let m = &self.0;
        let col = |c: usize| Vec3::new(m[r0][c0 + c], m[r0 + 1][c0 + c], m[r0 + 2][c0 + c]);
        Mat3::from_cols(col(0), col(1), col(2))
    }

    fn set_block(&mut self, r0: usize, c0: usize, b: Mat3) {
        for c in 0..3 {
            let v = b.col(c);
            for r in 0..3 {
                self.0[r0 + r][c0 + c] = v[r];
            }
        }
    }

    /// The inverse of a body's `D = [A B; C E]` (3×3 blocks) by its Schur complement
    /// `S = E − C A⁻¹ B`:
    ///
    /// ```text
    /// D⁻¹ = [ A⁻¹ + A⁻¹B S⁻¹ C A⁻¹   −A⁻¹B S⁻¹ ]
    ///       [ −S⁻¹ C A⁻¹              S⁻¹       ]
    /// ```
    ///
    /// A body's `D` is its mass matrix plus the positive semidefinite terms of its
    /// eliminated children, so `A` (mass times the identity plus those terms) and `S` are
    /// positive definite and need no pivoting. `None` when a block's determinant vanishes
    /// or is not finite.
    fn try_inverse_blocks(&self) -> Option<Self> {
        let usable = |m: &Mat3| {
            let det = m.determinant();
            det.is_finite() && det.abs() > 1e-30
        };
        let a = self.block(0, 0);
        let b = self.block(0, 3);
        let c = self.block(3, 0);
        let e = self.block(3, 3);
        if !usable(&a) {
            return None;
        }
        let a_inv = a.inverse();
        let a_inv_b = a_inv * b;
        let c_a_inv = c * a_inv;
        let schur = e - c * a_inv_b;
        if !usable(&schur) {
            return None;
        }
        let s_inv = schur.inverse();
        let top_right = -(a_inv_b * s_inv);
        let mut out = Matrix6::ZERO;
        out.set_block(0, 0, a_inv - top_right * c_a_inv);
        out.set_block(0, 3, top_right);
        out.set_block(3, 0, -(s_inv * c_a_inv));
        out.set_block(3, 3, s_inv);
        Some(out)
    }
}

impl Matrix3 {
    /// `self −= m`.
    fn sub_mat3(&mut self, m: Mat3) {
        for c in 0..3 {
            let v = m.col(c);
            for r in 0..3 {
                self.0[r][c] -= v[r];
            }
        }
    }
}

impl<const N: usize> Mat<N, N> {
    /// The inverse by Gauss–Jordan elimination with partial pivoting, `None` when a
    /// pivot vanishes.
    fn try_inverse(&self) -> Option<Self> {
        let mut a = self.0;
        let mut inv = [[0.0f32; N]; N];
        for (i, row) in inv.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        for col in 0..N {
            let pivot = (col..N).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
            // Also true for NaN, which must stop the factorisation too.
            if a[pivot][col].abs().partial_cmp(&1e-30) != Some(std::cmp::Ordering::Greater) {
                return None;
            }
            a.swap(col, pivot);
            inv.swap(col, pivot);
            let scale = 1.0 / a[col][col];
            for k in 0..N {
                a[col][k] *= scale;
                inv[col][k] *= scale;
            }
            for r in 0..N {
                if r != col {
                    let f = a[r][col];
                    if f != 0.0 {
                        for k in 0..N {
                            a[r][k] -= f * a[col][k];
                            inv[r][k] -= f * inv[col][k];
                        }
                    }
                }
            }
        }
        Some(Mat(inv))
    }
}

/// The product, every term summed without skipping zero factors: a branch per entry
/// keeps the compiler from vectorising the row updates, and the blocks are finite
/// (`factor` checks), so a zero factor adds a zero.
impl<const R: usize, const K: usize, const C: usize> std::ops::Mul<Mat<K, C>> for Mat<R, K> {
    type Output = Mat<R, C>;

    fn mul(self, o: Mat<K, C>) -> Mat<R, C> {
        let mut out = Mat::<R, C>::ZERO;
        for r in 0..R {
            for k in 0..K {
                let x = self.0[r][k];
                for c in 0..C {
                    out.0[r][c] += x * o.0[k][c];
                }
            }
        }
        out
    }
}

impl<const R: usize, const C: usize> std::ops::SubAssign for Mat<R, C> {
    fn sub_assign(&mut self, o: Self) {
        for r in 0..R {
            for c in 0..C {
                self.0[r][c] -= o.0[r][c];
            }
        }
    }
}
