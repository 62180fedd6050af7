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
//! Storage and work per node: a body keeps `D⁻¹` as three 3×3 blocks (it is symmetric)
//! and `D⁻¹ Gᵀ` to its parent joint, a joint its 3×3 `D⁻¹` and the arm of `G` on its
//! parent body; `G` and `Gᵀ` are applied as cross products, and the pass up applies
//! each node's `D⁻¹` as soon as its children are in, so the diagonal solve costs no
//! pass of its own. A leaf body's `D⁻¹` is its inverse mass and inertia as they are.
//!
//! Determinism: a tree's nodes are ordered by its own joints' and bodies' relative order
//! only, so a tree solved alone (an island on another thread) gets the bits it gets in
//! the whole world.

use super::body::BodyStates;
use super::joint::PointPart;
use super::joint_rows::PointRows;
use super::joint_set::JointSet;
use super::soft::{Softness, StepContext};
use glam::{Mat3A, Vec3, Vec3A};

/// A joint whose point rows are in a tree: its type's array and index.
#[derive(Clone, Copy, Debug, PartialEq)]
enum JointRef {
    Ball(usize),
    Hinge(usize),
    Universal(usize),
}

/// A node in elimination order: an index into [`JointTrees::bodies`] or
/// [`JointTrees::joints`].
#[derive(Clone, Copy, Debug)]
enum NodeRef {
    Body(usize),
    Joint(usize),
}

/// A body of a tree and its blocks of the factorisation.
///
/// Its block of the parent joint's rows is `G = σ [1, X]` with `X = −r̂` (see [`arm`]),
/// so `G u = σ (u_lin + u_ang × r)` (the anchor's velocity in the motion `u`) and
/// `Gᵀ p = σ (p, r × p)` (the impulse `p` at the anchor): the solve applies them as
/// cross products.
#[derive(Clone, Copy, Debug)]
struct BodyNode {
    /// Index into the states.
    body: usize,
    /// The parent joint (index into [`JointTrees::joints`]), [`NO_PARENT`] at a root.
    parent: usize,
    /// Whether joints of the tree hang below it; a body without is a leaf, whose `D`
    /// is its mass matrix, inverted by its inverse mass and inertia as they are.
    inner: bool,
    /// The parent joint's anchor offset from the body's centre of mass, and `σ`.
    r: Vec3A,
    sign: f32,
    /// `D⁻¹ = [P Q; Qᵀ S]` by 3×3 blocks (`D` is symmetric). While factoring, `D =
    /// [A B; Bᵀ E]` itself is summed here first.
    p: Mat3A,
    q: Mat3A,
    s: Mat3A,
    /// `D⁻¹ Gᵀ` to the parent joint, σ included: its linear and angular 3×3 blocks.
    up_lin: Mat3A,
    up_ang: Mat3A,
}

impl BodyNode {
    fn new(body: usize, parent: usize, inner: bool) -> BodyNode {
        BodyNode {
            body,
            parent,
            inner,
            r: Vec3A::ZERO,
            sign: 0.0,
            p: Mat3A::ZERO,
            q: Mat3A::ZERO,
            s: Mat3A::ZERO,
            up_lin: Mat3A::ZERO,
            up_ang: Mat3A::ZERO,
        }
    }
}

/// A joint's point rows in a tree and their block of the factorisation.
#[derive(Clone, Copy, Debug)]
struct JointNode {
    joint: JointRef,
    /// The joint's bodies (its frame's `a` and `b`, indices into the states).
    a: usize,
    b: usize,
    /// The parent body (index into [`JointTrees::bodies`]), [`NO_PARENT`] at a root.
    parent: usize,
    /// The anchor's offset from the parent body's centre of mass, and `σ` on it.
    r: Vec3A,
    sign: f32,
    /// `D⁻¹` (3×3, symmetric); while factoring, `D` itself is summed here first.
    d_inv: Mat3A,
    /// The rows' anchor offsets from a's and b's centres of mass and their gap
    /// `p_b − p_a`, as the factorisation read them: the solve's `Ċ` and `C` are those
    /// of the `G` it factorised.
    ra: Vec3A,
    rb: Vec3A,
    c: Vec3A,
}

impl JointNode {
    fn new(joint: JointRef, a: usize, b: usize, parent: usize) -> JointNode {
        JointNode {
            joint,
            a,
            b,
            parent,
            r: Vec3A::ZERO,
            sign: 0.0,
            d_inv: Mat3A::ZERO,
            ra: Vec3A::ZERO,
            rb: Vec3A::ZERO,
            c: Vec3A::ZERO,
        }
    }
}

/// The trees of one solve (the whole world, or one island's batch).
#[derive(Clone, Debug, Default)]
pub struct JointTrees {
    /// Every tree's nodes in elimination order: leaves first, each tree's root last,
    /// trees one after another.
    order: Vec<NodeRef>,
    bodies: Vec<BodyNode>,
    joints: Vec<JointNode>,
    /// Whether the last factorisation was usable (finite); otherwise the joints of the
    /// trees fall back to Gauss–Seidel for the substep.
    ok: bool,
    /// How many ball joints, hinges and universal joints touch a moving body (see
    /// `JointSet::live_points`).
    live_points: usize,
    /// What the trees were built from: per body, its inverse mass when it moves, zero
    /// otherwise; then, per ball joint, hinge and universal joint in that order, its two
    /// bodies. The trees depend on nothing else, so while this is unchanged (every
    /// step of a world whose sleep states and joints do not change) they are kept.
    built_from: Vec<f32>,
    built_joints: Vec<(usize, usize)>,
    /// Scratch of `solve`, kept between calls so the substeps allocate nothing: each
    /// body node's linear and angular value, each joint node's. Between solves the
    /// bodies' values are zero (a solve zeroes them as it applies them).
    x_lin: Vec<Vec3A>,
    x_ang: Vec<Vec3A>,
    x_joint: Vec<Vec3A>,
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
            for node in &self.joints {
                let point = point_of_mut(joints, node.joint);
                point.direct = true;
                point.in_tree = true;
            }
            joints.direct = !self.joints.is_empty();
            joints.tree_points = self.joints.len();
            joints.live_points = self.live_points;
            self.ok = true;
            return;
        }
        let built = JointTrees::build(joints, s, awake);
        self.order = built.order;
        self.bodies = built.bodies;
        self.joints = built.joints;
        self.ok = built.ok;
        self.live_points = built.live_points;
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
        let mut live_points = 0;
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
            live_points += usize::from(ma || mb);
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
            live_points,
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
        joints.live_points = live_points;
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
            // This tree, reversed: children before parents. First each node's index
            // among the nodes of its kind, then the nodes with their parents'.
            let mut slot_of = Vec::with_capacity(order.len() - start);
            let (mut bodies, mut joints_seen) = (trees.bodies.len(), trees.joints.len());
            for slot in (start..order.len()).rev() {
                let counter = if order[slot].0 {
                    &mut bodies
                } else {
                    &mut joints_seen
                };
                slot_of.push(*counter);
                *counter += 1;
            }
            // `slot_of` runs backwards over `order[start..]`.
            let index_of = |slot: usize| slot_of[order.len() - 1 - slot];
            let mut inner = vec![false; order.len() - start];
            for &(node_is_body, _, parent) in &order[start..] {
                if !node_is_body && parent != NO_PARENT {
                    inner[parent - start] = true;
                }
            }
            for slot in (start..order.len()).rev() {
                let (node_is_body, i, parent) = order[slot];
                let parent = if parent == NO_PARENT {
                    NO_PARENT
                } else {
                    index_of(parent)
                };
                if node_is_body {
                    trees.order.push(NodeRef::Body(trees.bodies.len()));
                    trees
                        .bodies
                        .push(BodyNode::new(i, parent, inner[slot - start]));
                } else {
                    let joint = chosen[i].0;
                    let (a, b) = frame_bodies(joints, joint);
                    trees.order.push(NodeRef::Joint(trees.joints.len()));
                    trees.joints.push(JointNode::new(joint, a, b, parent));
                }
            }
        }
        trees
    }
    /// Whether there is anything to solve.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Factorises the trees on the current pose and inertias and the anchors of the
    /// joints' last `prepare`, eliminating the nodes in order: a body's
    /// `D⁻¹` (by its Schur complement, [`invert_blocks`]) goes into its parent joint as
    /// `D_j −= G D_b⁻¹ Gᵀ`, a joint's into its parent body as `D_b −= Gᵀ D_j⁻¹ G`. A
    /// tree that does not factorise (a degenerate inertia) hands its joints back to
    /// Gauss–Seidel.
    pub fn factor(&mut self, joints: &mut JointSet, s: &BodyStates) {
        let JointTrees {
            order,
            bodies,
            joints: nodes,
            ..
        } = self;
        for node in nodes.iter_mut() {
            [node.ra, node.rb, node.c] = PointPart::anchors_of(rows_of(joints, node.joint));
            node.d_inv = Mat3A::ZERO;
        }
        for node in bodies.iter_mut() {
            let i = node.body;
            if node.inner {
                // D = M = diag(m 1, I), I the world inertia now; children subtract.
                node.p = Mat3A::from_diagonal(Vec3::splat(1.0 / s.inv_mass[i]));
                node.q = Mat3A::ZERO;
                node.s = s.inv_inertia[i].inverse();
            } else {
                node.p = Mat3A::from_diagonal(Vec3::splat(s.inv_mass[i]));
                node.q = Mat3A::ZERO;
                node.s = s.inv_inertia[i];
            }
        }
        let mut ok = true;
        for &node in order.iter() {
            match node {
                NodeRef::Body(k) => {
                    let body = &mut bodies[k];
                    if body.inner {
                        let Some((p, q, s)) = invert_blocks(body.p, body.q, body.s) else {
                            ok = false;
                            break;
                        };
                        (body.p, body.q, body.s) = (p, q, s);
                    }
                    if body.parent == NO_PARENT {
                        continue;
                    }
                    // Into the parent joint: with X = −r̂, G D⁻¹ Gᵀ = top + X bottom,
                    // top = P + Q Xᵀ, bottom = Qᵀ + S Xᵀ, and D⁻¹ Gᵀ = σ [top; bottom].
                    let joint = &mut nodes[body.parent];
                    let (r, sign) = arm(joint, body.body);
                    let x = minus_cross_matrix(r);
                    let xt = x.transpose();
                    let top = body.p + body.q * xt;
                    let bottom = body.q.transpose() + body.s * xt;
                    joint.d_inv -= top + x * bottom;
                    (body.r, body.sign) = (r, sign);
                    (body.up_lin, body.up_ang) = (top * sign, bottom * sign);
                    ok &= body.up_lin.is_finite() && body.up_ang.is_finite();
                }
                NodeRef::Joint(k) => {
                    let joint = &mut nodes[k];
                    let Some(d_inv) = invert(joint.d_inv) else {
                        ok = false;
                        break;
                    };
                    joint.d_inv = d_inv;
                    if joint.parent == NO_PARENT {
                        continue;
                    }
                    // Into the parent body: Gᵀ D⁻¹ G = [D⁻¹, D⁻¹ X; Xᵀ D⁻¹, Xᵀ D⁻¹ X].
                    let body = &mut bodies[joint.parent];
                    let (r, sign) = arm(joint, body.body);
                    let x = minus_cross_matrix(r);
                    let d_x = d_inv * x;
                    body.p -= d_inv;
                    body.q -= d_x;
                    body.s -= x.transpose() * d_x;
                    (joint.r, joint.sign) = (r, sign);
                }
            }
        }
        self.ok = ok;
        for node in &self.joints {
            point_of_mut(joints, node.joint).direct = ok;
        }
        if !ok {
            // Handed back to Gauss–Seidel, whose rows also read `K⁻¹`, which a joint of
            // a tree leaves unweighed (`PointPart::weigh`): weighed now, on the pose,
            // inertias and masses its rows were prepared on (no velocity pass moves them).
            for node in &self.joints {
                let f = frame_of(joints, node.joint);
                PointPart::weigh_all(rows_of_mut(joints, node.joint), &f, s);
            }
        }
    }

    /// One block update of every tree's point rows: the exact `λ' = K⁻¹(−r)` with
    /// `r = Ċ + bias_rate · C`, then the soft step's `λ += s_m λ' − s_i λ_acc`. The relax
    /// pass (`use_bias` false) solves rigidly with `r = Ċ`.
    ///
    /// The pass up the tree applies each node's `D⁻¹` as soon as its children are in
    /// (`x_parent −= Hᵀ D⁻¹ x = Hᵀ u` with `u = D⁻¹ x`, the node's value after the
    /// diagonal solve), the pass down `x_child −= D⁻¹ H x_parent`.
    pub fn solve(
        &mut self,
        joints: &mut JointSet,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        if !self.ok || self.order.is_empty() {
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
        let JointTrees {
            order,
            bodies,
            joints: nodes,
            x_lin,
            x_ang,
            x_joint,
            ..
        } = self;
        // Right-hand sides: zero for bodies (the apply below leaves them zero for the
        // next solve), −r for joints.
        if x_lin.len() != bodies.len() || x_ang.len() != bodies.len() {
            x_lin.clear();
            x_lin.resize(bodies.len(), Vec3A::ZERO);
            x_ang.clear();
            x_ang.resize(bodies.len(), Vec3A::ZERO);
        }
        x_joint.clear();
        x_joint.extend(nodes.iter().map(|node| {
            let cdot = s.point_velocity(node.b, node.rb) - s.point_velocity(node.a, node.ra);
            -(cdot + soft.bias_rate * node.c)
        }));
        // Up the tree, each node's D⁻¹ applied on the way.
        for &node in order.iter() {
            match node {
                NodeRef::Body(k) => {
                    let body = &bodies[k];
                    if !body.inner {
                        // A leaf's right-hand side is +0 (no joint below it writes it),
                        // and so is `u = D⁻¹ x` (its D⁻¹ is its inverse mass and inertia,
                        // finite once factored, with a non-negative diagonal: each row's
                        // sum of products with +0 is +0) and `u_lin + u_ang × r`. The
                        // push up `x_parent −= σ (+0)` then leaves x_parent as it is, but
                        // for σ = −1, where `x − (−0)` turns a −0 into +0: that subtraction
                        // alone is made.
                        if body.parent != NO_PARENT && body.sign < 0.0 {
                            x_joint[body.parent] -= Vec3A::splat(-0.0);
                        }
                        continue;
                    }
                    let (v, w) = (x_lin[k], x_ang[k]);
                    let u_lin = body.p * v + body.q * w;
                    let u_ang = transpose_mul(&body.q, v) + body.s * w;
                    (x_lin[k], x_ang[k]) = (u_lin, u_ang);
                    if body.parent != NO_PARENT {
                        x_joint[body.parent] -= (u_lin + u_ang.cross(body.r)) * body.sign;
                    }
                }
                NodeRef::Joint(k) => {
                    let joint = &nodes[k];
                    let u = joint.d_inv * x_joint[k];
                    x_joint[k] = u;
                    if joint.parent != NO_PARENT {
                        x_lin[joint.parent] -= u * joint.sign;
                        x_ang[joint.parent] -= joint.r.cross(u) * joint.sign;
                    }
                }
            }
        }
        // Down the tree.
        for &node in order.iter().rev() {
            match node {
                NodeRef::Body(k) => {
                    let body = &bodies[k];
                    if body.parent != NO_PARENT {
                        let p = x_joint[body.parent];
                        x_lin[k] -= body.up_lin * p;
                        x_ang[k] -= body.up_ang * p;
                    }
                }
                NodeRef::Joint(k) => {
                    let joint = &nodes[k];
                    if joint.parent != NO_PARENT {
                        let (v, w) = (x_lin[joint.parent], x_ang[joint.parent]);
                        x_joint[k] -= joint.d_inv * (v + w.cross(joint.r)) * joint.sign;
                    }
                }
            }
        }
        // Apply: bodies get s_m Δv', each joint's accumulated impulse decays by s_i.
        // Each body's values are zeroed as they are read: the next solve's right-hand
        // side.
        for ((body, lin), ang) in bodies.iter().zip(x_lin.iter_mut()).zip(x_ang.iter_mut()) {
            let b = body.body;
            s.lin_vel[b] += std::mem::take(lin) * soft.mass_scale;
            s.ang_vel[b] += std::mem::take(ang) * soft.mass_scale;
        }
        for (node, &y) in nodes.iter().zip(x_joint.iter()) {
            let lambda = -y;
            let decay = -soft.impulse_scale * Vec3A::from(point_of(joints, node.joint).impulse);
            if soft.impulse_scale != 0.0 {
                let f = frame_of(joints, node.joint);
                PointPart::apply(rows_of(joints, node.joint), &f, s, decay);
            }
            let point = point_of_mut(joints, node.joint);
            point.impulse =
                Vec3::from(Vec3A::from(point.impulse) + (soft.mass_scale * lambda + decay));
        }
    }
}

/// `Mᵀ v`.
#[inline]
fn transpose_mul(m: &Mat3A, v: Vec3A) -> Vec3A {
    Vec3A::new(m.x_axis.dot(v), m.y_axis.dot(v), m.z_axis.dot(v))
}

/// `−r̂`, the matrix of `u ↦ u × r`: by columns `(0, −r_z, r_y)`, `(r_z, 0, −r_x)`,
/// `(−r_y, r_x, 0)`.
fn minus_cross_matrix(r: Vec3A) -> Mat3A {
    Mat3A::from_cols(
        Vec3A::new(0.0, -r.z, r.y),
        Vec3A::new(r.z, 0.0, -r.x),
        Vec3A::new(-r.y, r.x, 0.0),
    )
}

/// The block of a joint's point rows on `body` as `G = σ [1, X]`, `X = −r̂`: the anchor's
/// offset `r` from that body and the sign `σ` (+1 on body2, −1 on body1;
/// `Ċ = v_b + ω_b × r_b − v_a − ω_a × r_a`, and `−r̂ ω = ω × r`).
fn arm(joint: &JointNode, body: usize) -> (Vec3A, f32) {
    if body == joint.b {
        (joint.rb, 1.0)
    } else {
        debug_assert_eq!(body, joint.a);
        (joint.ra, -1.0)
    }
}

/// Whether a 3×3 block can be inverted: a finite determinant away from zero.
fn invertible(m: &Mat3A) -> bool {
    let det = m.determinant();
    det.is_finite() && det.abs() > 1e-30
}

/// The inverse of a 3×3 block, `None` when it does not exist.
fn invert(m: Mat3A) -> Option<Mat3A> {
    invertible(&m).then(|| m.inverse())
}

/// The inverse of a body's `D = [A B; Bᵀ E]` (3×3 blocks, symmetric) by its Schur
/// complement `S = E − Bᵀ A⁻¹ B`:
///
/// ```text
/// D⁻¹ = [ A⁻¹ + A⁻¹B S⁻¹ Bᵀ A⁻¹   −A⁻¹B S⁻¹ ]
///       [ −S⁻¹ Bᵀ A⁻¹               S⁻¹       ]
/// ```
///
/// returned as its blocks `(P, Q, S⁻¹)`, the lower left being `Qᵀ`. A body's `D` is its
/// mass matrix plus the positive semidefinite terms of its eliminated children, so `A`
/// (mass times the identity plus those terms) and `S` are positive definite and need no
/// pivoting. `None` when a block's determinant vanishes or is not finite.
fn invert_blocks(a: Mat3A, b: Mat3A, e: Mat3A) -> Option<(Mat3A, Mat3A, Mat3A)> {
    let a_inv = invert(a)?;
    let a_inv_b = a_inv * b;
    let s_inv = invert(e - b.transpose() * a_inv_b)?;
    let q = -(a_inv_b * s_inv);
    let p = a_inv - q * a_inv_b.transpose();
    (p.is_finite() && q.is_finite() && s_inv.is_finite()).then_some((p, q, s_inv))
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

/// The point rows the solve prepared for joint `j` (a tree's joints touch moving
/// bodies, so the solve holds rows for them, numbered in [`JointRows::slots`]).
///
/// [`JointRows::slots`]: super::joint_set::JointRows::slots
#[inline(always)]
fn rows_of(joints: &JointSet, j: JointRef) -> &PointRows<f32> {
    let [ball, hinge, universal] = &joints.rows.slots;
    let slot = |slots: &[u32], i: usize| slots[i] as usize;
    match j {
        JointRef::Ball(i) => &joints.rows.ball[slot(ball, i)].point,
        JointRef::Hinge(i) => &joints.rows.hinge[slot(hinge, i)].point,
        JointRef::Universal(i) => &joints.rows.universal[slot(universal, i)].point,
    }
}

/// [`rows_of`], to be written.
fn rows_of_mut(joints: &mut JointSet, j: JointRef) -> &mut PointRows<f32> {
    let [ball, hinge, universal] = &joints.rows.slots;
    let slot = |slots: &[u32], i: usize| slots[i] as usize;
    match j {
        JointRef::Ball(i) => &mut joints.rows.ball[slot(ball, i)].point,
        JointRef::Hinge(i) => &mut joints.rows.hinge[slot(hinge, i)].point,
        JointRef::Universal(i) => &mut joints.rows.universal[slot(universal, i)].point,
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
