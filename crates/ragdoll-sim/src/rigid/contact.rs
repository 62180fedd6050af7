//! Contacts: parry3d manifolds between bodies and against the ground plane, cached per
//! body pair with persistent point ids for warm starting, solved as soft non-penetration
//! constraints with Coulomb friction and a restitution pass (Box2D v3's contact solver,
//! in 3D).
//!
//! Per step: the broad phase proposes pairs, the cache keeps each pair's parry workspace
//! and last impulses (a sorted array keyed by the pair, merged with the new pair list),
//! the narrow phase refreshes the manifolds, and `prepare` fixes anchors, normal and
//! effective masses for the step. Separation is then tracked through the substeps from
//! the bodies' motion (`s = s₀ + n·(Δp_b − Δp_a)`), as Box2D does.

// Several per-body arrays are walked together by index.
#![allow(clippy::needless_range_loop)]

use super::body::{BodyInfo, BodyStates, SolverBody};
use super::project::{CONTACT_CORRECTION, MAX_LINEAR_CORRECTION};
use super::soft::StepContext;
use crate::scene::Collider;
use crate::scene::Shape;
use glam::{Quat, Vec3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::Pose as PPose;
use parry3d::query::{
    ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher, TrackedContact,
};
use parry3d::shape::{Shape as ParryShape, SharedShape};
use rayon::prelude::*;

/// Distance within which contacts are created before touching (speculative margin, m).
pub const SPECULATIVE_DISTANCE: f32 = 0.02;
/// Penetration allowed at rest (m): keeps resting contacts from jittering in and out.
pub const LINEAR_SLOP: f32 = 0.0005;
/// Rolling resistance coefficient (Box2D v3's `rollingResistance`): a contact of a round
/// body (capsule, cylinder, cone) resists the relative rotation of its bodies with at
/// most `ρ r λₙ` of angular impulse, r the round body's rolling radius (its smallest half
/// extent) and λₙ the pair's normal impulse. It stands for the deformation of real
/// contacts, which a rigid round body lacks: without it a capsule on a level floor never
/// stops rolling and its island never sleeps. 0.005 is between a steel wheel on rail
/// (0.001) and a tyre on concrete (0.01–0.02): it stops scene 9's rolling head and
/// obstacle within seconds; larger values (0.01–0.03, measured) let the limbs land
/// differently enough that a hard limit is pushed past 2°.
pub const ROLLING_RESISTANCE: f32 = 0.005;

/// One contact point's solver state. It rides in the `data` slot of parry's tracked
/// contact, next to the point's geometry (anchors in the shape frames, separation,
/// feature ids): one array per pair holds both, and what parry already stores (the
/// persistent id, the separation at prepare time) is not repeated here. parry copies
/// `data` around when it refreshes a manifold, but [`prepare_pair`] rewrites it whole
/// for every point, with impulses carried over by id as before.
#[derive(Clone, Copy, Debug, Default)]
pub struct ContactPoint {
    /// Normal from a to b (world), the same for every point of a pair.
    pub normal: Vec3,
    /// Anchor on a relative to its centre of mass (world, fixed for the step).
    pub ra: Vec3,
    /// Anchor on b.
    pub rb: Vec3,
    /// Anchor in a's body space, to follow a through the substeps.
    pub local_a: Vec3,
    /// Anchor in b's body space.
    pub local_b: Vec3,
    /// World anchor on a at prepare time.
    pub pa0: Vec3,
    /// World anchor on b at prepare time.
    pub pb0: Vec3,
    /// Separation at the start of the current substep's iterations
    /// ([`prepare_substep`]): the positions hold still until they are integrated.
    pub separation: f32,
    /// 1 / (n·K·n).
    pub normal_mass: f32,
    /// Effective masses of the two tangent rows.
    pub tangent_mass: [f32; 2],
    /// Accumulated normal impulse.
    pub normal_impulse: f32,
    /// Accumulated friction impulse (world vector, survives basis changes).
    pub tangent_impulse: Vec3,
    /// Largest normal impulse applied this step (restitution only bounces real contacts).
    pub max_normal_impulse: f32,
    /// Normal velocity at prepare time (negative = approaching).
    pub relative_velocity: f32,
}

/// A cached body pair.
#[derive(Debug, Default)]
pub struct ContactPair {
    /// Body a.
    pub a: u32,
    /// Body b, or the static anchor for the ground.
    pub b: u32,
    /// Combined Coulomb coefficient.
    pub friction: f32,
    /// Combined restitution.
    pub restitution: f32,
    /// `ρ r`: rolling resistance times rolling radius (m).
    pub rolling_arm: f32,
    /// Accumulated rolling-resistance angular impulse on b.
    pub rolling_impulse: Vec3,
    /// Whether the points carry solver state: the manifold has points and a normal.
    touching: bool,
    /// The points of parry's persistent manifold of the pair, each with its solver state
    /// ([`ContactPoint`]). The manifold is kept between steps because parry reads it
    /// back (it keeps the points while the relative pose barely changed, and starts GJK
    /// from the last normal). Every shape is convex, so a pair has exactly one manifold;
    /// only the parts parry's convex–convex generators read and write are stored (see
    /// [`ContactPair::collide`]), not a `Vec` of whole manifolds and a composite-shape
    /// workspace, which cost ~290 bytes per pair, touching or not.
    points: Vec<TrackedContact<ContactPoint>>,
    /// The manifold's normal in a's shape frame.
    manifold_n1: Vec3,
    /// The manifold's normal in b's shape frame.
    manifold_n2: Vec3,
}

impl ContactPair {
    /// Whether any point is within the speculative margin.
    pub fn touching(&self) -> bool {
        self.touching
    }

    /// The solver points (none unless touching).
    pub fn points(&self) -> impl Iterator<Item = &ContactPoint> {
        let n = if self.touching { self.points.len() } else { 0 };
        self.points[..n].iter().map(|c| &c.data)
    }

    /// The tangent basis of the pair's points. It is a function of the normal, which all
    /// points share, so it is computed where it is used rather than stored per point
    /// (the same two vectors, bit for bit, as when they were stored).
    #[inline]
    fn tangents(&self) -> [Vec3; 2] {
        let (t0, t1) = self
            .points
            .first()
            .map_or(Vec3::ZERO, |c| c.data.normal)
            .any_orthonormal_pair();
        [t0, t1]
    }

    /// The impulses of the points now, by persistent id, for warm starting once the
    /// manifold is refreshed: read before [`ContactPair::collide`] rewrites the points
    /// (none unless touching). A manifold holds a handful of points; the first 8 are
    /// kept, as many as are looked up.
    fn old_impulses(&self) -> ([(u64, f32, Vec3); 8], usize) {
        let mut old: [(u64, f32, Vec3); 8] = [(u64::MAX, 0.0, Vec3::ZERO); 8];
        let n_old = if self.touching {
            self.points.len().min(8)
        } else {
            0
        };
        for (slot, c) in old.iter_mut().zip(&self.points[..n_old]) {
            *slot = (point_id(c), c.data.normal_impulse, c.data.tangent_impulse);
        }
        (old, n_old)
    }

    /// Runs parry's narrow phase on the pair's manifold. The manifold is put together
    /// from the stored parts for the call (moving the point vector, no allocation):
    /// parry's convex–convex generators never set the sub-shape fields, so they are
    /// always the `ContactManifold::new()` values, as they were when a `Vec` of
    /// manifolds was kept. This is the branch `contact_manifolds` takes for two
    /// non-composite shapes, called directly.
    fn collide(
        &mut self,
        pos12: &PPose,
        shape_a: &dyn ParryShape,
        shape_b: &dyn ParryShape,
        prediction: f32,
    ) {
        let mut manifold = ContactManifold::<(), ContactPoint>::new();
        manifold.points = std::mem::take(&mut self.points);
        manifold.local_n1 = self.manifold_n1;
        manifold.local_n2 = self.manifold_n2;
        let ok = DefaultQueryDispatcher.contact_manifold_convex_convex(
            pos12,
            shape_a,
            shape_b,
            None,
            None,
            prediction,
            &mut manifold,
        );
        if ok.is_err() {
            // What dropping the manifold did: the next call starts from a fresh one.
            manifold.points.clear();
            manifold.local_n1 = Vec3::ZERO;
            manifold.local_n2 = Vec3::ZERO;
        }
        self.points = manifold.points;
        self.manifold_n1 = manifold.local_n1;
        self.manifold_n2 = manifold.local_n2;
    }
}

/// The ground as a collider.
#[derive(Clone, Debug)]
pub struct GroundCollider {
    /// A parry half-space.
    pub shape: SharedShape,
    /// Its pose (the tilt, the height).
    pub pose: PPose,
    /// Outward normal.
    pub normal: Vec3,
    /// A point on the plane.
    pub origin: Vec3,
    /// Coulomb coefficient.
    pub friction: f32,
    /// Restitution.
    pub restitution: f32,
}

/// All contact state of a world.
#[derive(Default)]
pub struct Contacts {
    /// Active pairs, sorted by `(a, b)`.
    pub pairs: Vec<ContactPair>,
    candidates: Vec<(u32, u32)>,
    aabbs: Vec<Aabb>,
    /// Pairs that never collide (jointed, overlapping at rest, self-collision off), sorted.
    pub excluded: Vec<(u32, u32)>,
    /// The ground, if any.
    pub ground: Option<GroundCollider>,
    /// The parry colliders of the convex-hull bodies (see [`BodyInfo::collider`]).
    pub hulls: Vec<SharedShape>,
}

/// Upper bound of the speed of any point of body `i`.
#[inline]
fn point_speed(s: &BodyStates, info: &[BodyInfo], i: usize) -> f32 {
    s.lin_vel[i].length() + s.ang_vel[i].length() * info[i].bound_radius
}

/// parry pose of body `i`'s shape frame.
#[inline]
pub fn shape_pose(s: &BodyStates, info: &[BodyInfo], i: usize) -> PPose {
    let q = s.rot[i];
    PPose::from_parts(s.com[i] - q * info[i].local_com, q)
}

/// Whether two bodies may collide at all (not counting the exclusion list).
pub fn may_collide(info: &[BodyInfo], a: usize, b: usize) -> bool {
    let (ia, ib) = (&info[a], &info[b]);
    if ia.fixed && ib.fixed {
        return false;
    }
    ia.figure != ib.figure || (ia.self_collision && ib.self_collision)
}

impl Contacts {
    /// Runs broad and narrow phase for the current pose and prepares the solver data.
    /// `awake[i]` tells which bodies move; pairs between resting bodies keep their
    /// cached state untouched. `dt` widens the margins for fast bodies.
    pub fn update(&mut self, s: &BodyStates, info: &[BodyInfo], awake: &[bool], dt: f32) {
        let n = info.len();
        let anchor = n as u32;
        // Broad phase on AABBs loosened by the speculative margin and this step's motion.
        self.aabbs.clear();
        for i in 0..n {
            let motion = point_speed(s, info, i) * dt;
            let aabb = info[i]
                .collider(&self.hulls)
                .shape()
                .compute_aabb(&shape_pose(s, info, i));
            self.aabbs
                .push(aabb.loosened(SPECULATIVE_DISTANCE + motion));
        }
        self.candidates.clear();
        crate::broadphase::overlapping_pairs(&self.aabbs, &mut self.candidates);
        let excluded = &self.excluded;
        self.candidates.retain(|&(a, b)| {
            (awake[a as usize] || awake[b as usize])
                && may_collide(info, a as usize, b as usize)
                && excluded.binary_search(&(a, b)).is_err()
        });
        // Bodies near the ground plane (the plane comes last: the anchor has the largest index).
        if let Some(g) = &self.ground {
            for i in 0..n {
                if info[i].fixed {
                    continue;
                }
                let aabb = &self.aabbs[i];
                let c = aabb.center();
                let e = aabb.half_extents();
                let reach = g.normal.abs().dot(e);
                if g.normal.dot(c - g.origin) - reach < 0.0 {
                    self.candidates.push((i as u32, anchor));
                }
            }
            self.candidates.sort_unstable();
        }
        // Sleeping pairs stay in the cache as they are (islands need them).
        for p in &self.pairs {
            if !awake[p.a as usize] && !awake[p.b as usize] {
                self.candidates.push((p.a, p.b));
            }
        }
        self.candidates.sort_unstable();
        self.candidates.dedup();

        // Merge the sorted candidate list into the sorted cache in place (no second pair
        // array kept for the swap): surviving pairs keep their manifold and impulses, new
        // ones start empty. First the pairs that are no longer candidates are dropped,
        // keeping the order, so the cache is a subsequence of the candidates ...
        let candidates = &self.candidates;
        let mut c = 0;
        self.pairs.retain(|p| {
            while c < candidates.len() && candidates[c] < (p.a, p.b) {
                c += 1;
            }
            c < candidates.len() && candidates[c] == (p.a, p.b)
        });
        // ... then the array grows to the candidates' length and is filled from the back:
        // the `kept` cached pairs not yet placed stay at `0..kept`, and since each of
        // them matches a distinct candidate at or before slot `i`, `kept <= i + 1`, so
        // moving one up to `i` or writing a new pair at `i` never overwrites one.
        let new_pair = |a: u32, b: u32| {
            let (fa, ra) = (info[a as usize].friction, info[a as usize].restitution);
            let (fb, rb) = match (&self.ground, b == anchor) {
                (Some(g), true) => (g.friction, g.restitution),
                _ => (info[b as usize].friction, info[b as usize].restitution),
            };
            // Only round bodies roll; a box's rotation is already resisted by its
            // contact points' friction.
            let rolling = |i: usize| match info[i].shape {
                Shape::Capsule { .. } | Shape::Cylinder { .. } | Shape::Cone { .. } => {
                    info[i].min_half_extent()
                }
                _ => 0.0,
            };
            let radius = if b == anchor {
                rolling(a as usize)
            } else {
                rolling(a as usize).max(rolling(b as usize))
            };
            ContactPair {
                a,
                b,
                rolling_arm: ROLLING_RESISTANCE * radius,
                friction: (fa * fb).sqrt(),
                restitution: ra.max(rb),
                ..Default::default()
            }
        };
        let mut kept = self.pairs.len();
        // Grown to the size needed, not doubled: the array is kept for reuse at its
        // largest size, so doubling would hold up to twice the pairs for good (measured
        // 7680 slots for 4096 pairs in the memory bench), and a new largest size, which
        // costs one copy of the array, comes rarely once a scene has settled.
        self.pairs
            .reserve_exact(self.candidates.len().saturating_sub(kept));
        self.pairs
            .resize_with(self.candidates.len(), ContactPair::default);
        for i in (0..self.candidates.len()).rev() {
            let (a, b) = self.candidates[i];
            if kept > 0 && (self.pairs[kept - 1].a, self.pairs[kept - 1].b) == (a, b) {
                kept -= 1;
                self.pairs.swap(kept, i);
            } else {
                self.pairs[i] = new_pair(a, b);
            }
        }

        // Narrow phase: every pair on its own, so on all cores; each pair writes only its
        // own slot, the result does not depend on the thread count.
        let ground = &self.ground;
        let hulls = &self.hulls;
        self.pairs.par_iter_mut().with_min_len(64).for_each(|pair| {
            let (a, b) = (pair.a as usize, pair.b as usize);
            if !awake[a] && !awake[b] {
                return;
            }
            let pose_a = shape_pose(s, info, a);
            let collider_a = info[a].collider(hulls);
            let (pose_b, collider_b) = if b == n {
                let g = ground
                    .as_ref()
                    .expect("ground pairs exist only with a ground");
                (g.pose, Collider::Shared(&g.shape))
            } else {
                (shape_pose(s, info, b), info[b].collider(hulls))
            };
            // A point of a approaches a point of b at most |v_a − v_b| + |ω_a| r_a +
            // |ω_b| r_b: contacts that may close this step are created now, so the
            // speculative branch stops them on time even for a limb swinging fast about
            // its joint, and bodies falling side by side make none.
            let spin = |i: usize| s.ang_vel[i].length() * info[i].bound_radius;
            let approach = if b == n {
                point_speed(s, info, a)
            } else {
                (s.lin_vel[a] - s.lin_vel[b]).length() + spin(a) + spin(b)
            };
            let prediction = SPECULATIVE_DISTANCE + approach * dt;
            let pos12 = pose_a.inv_mul(&pose_b);
            let (old, n_old) = pair.old_impulses();
            pair.collide(&pos12, collider_a.shape(), collider_b.shape(), prediction);
            prepare_pair(pair, s, &pose_a, &pose_b, &old[..n_old]);
        });
    }
}

/// Pairs with points where at least one body is awake.
fn active<'a>(
    pairs: &'a mut [ContactPair],
    awake: &'a [bool],
) -> impl Iterator<Item = &'a mut ContactPair> {
    pairs
        .iter_mut()
        .filter(move |p| p.touching() && (awake[p.a as usize] || awake[p.b as usize]))
}

/// Effective masses with the current inverse inertias (call after `update_inertia`).
pub fn prepare_masses(pairs: &mut [ContactPair], s: &BodyStates, awake: &[bool]) {
    for pair in active(pairs, awake) {
        let (a, b) = (pair.a as usize, pair.b as usize);
        let tangents = pair.tangents();
        for p in pair.points.iter_mut().map(|c| &mut c.data) {
            let k = |d: Vec3| {
                let (ja, jb) = (p.ra.cross(d), p.rb.cross(d));
                s.inv_mass[a]
                    + s.inv_mass[b]
                    + ja.dot(s.inv_inertia[a] * ja)
                    + jb.dot(s.inv_inertia[b] * jb)
            };
            let inv = |x: f32| if x > 1e-20 { 1.0 / x } else { 0.0 };
            p.normal_mass = inv(k(p.normal));
            p.tangent_mass = [inv(k(tangents[0])), inv(k(tangents[1]))];
            p.max_normal_impulse = 0.0;
            p.relative_velocity = p
                .normal
                .dot(s.point_velocity(b, p.rb) - s.point_velocity(a, p.ra));
        }
    }
}

/// Re-applies the impulses cached from the last step.
pub fn warm_start(pairs: &mut [ContactPair], s: &mut BodyStates, awake: &[bool]) {
    for pair in active(pairs, awake) {
        let (a, b) = (pair.a as usize, pair.b as usize);
        for p in pair.points.iter().map(|c| &c.data) {
            let imp = p.normal * p.normal_impulse + p.tangent_impulse;
            s.apply_impulse(a, p.ra, -imp);
            s.apply_impulse(b, p.rb, imp);
        }
        s.apply_angular_impulse(a, -pair.rolling_impulse);
        s.apply_angular_impulse(b, pair.rolling_impulse);
    }
}

/// Evaluates each point's current separation for a substep's biased iterations: between
/// the velocity and the position integration the bodies do not move, so the iterations
/// share one value (the relax pass, after the positions moved, evaluates its own).
pub fn prepare_substep(pairs: &mut [ContactPair], s: &BodyStates, awake: &[bool]) {
    for pair in active(pairs, awake) {
        let (a, b) = (pair.a as usize, pair.b as usize);
        let (qa, qb) = (s.rot[a], s.rot[b]);
        let (ca, cb) = (s.com[a], s.com[b]);
        for c in &mut pair.points {
            c.data.separation = current_separation(c, ca, qa, cb, qb);
        }
    }
}

/// One Gauss–Seidel pass: soft non-penetration, then friction capped by the normal
/// impulse just computed (Box2D v3's order; friction first would cap it with a
/// normal impulse the relax pass is about to raise, and slide too easily). The biased
/// pass reads the separations of [`prepare_substep`].
pub fn solve(
    pairs: &mut [ContactPair],
    s: &mut BodyStates,
    awake: &[bool],
    ctx: &StepContext,
    use_bias: bool,
) {
    for pair in active(pairs, awake) {
        let (a, b) = (pair.a as usize, pair.b as usize);
        let (qa, qb) = (s.rot[a], s.rot[b]);
        let (ca, cb) = (s.com[a], s.com[b]);
        // The pair's two (distinct) bodies as solver bodies while its points are solved.
        let (mut ba, mut bb) = (SolverBody::load(s, a), SolverBody::load(s, b));
        let tangents = pair.tangents();
        for c in &mut pair.points {
            // Non-penetration at the current separation.
            let sep = if use_bias {
                c.data.separation
            } else {
                current_separation(c, ca, qa, cb, qb)
            };
            let p = &mut c.data;
            let (bias, mass_scale, impulse_scale) = if sep > 0.0 {
                // Speculative: the gap may close this substep, no further.
                (sep * ctx.inv_h, 1.0, 0.0)
            } else if use_bias {
                let c = (sep + LINEAR_SLOP).min(0.0);
                (
                    (ctx.contact.bias_rate * c).max(-ctx.max_push_out),
                    ctx.contact.mass_scale,
                    ctx.contact.impulse_scale,
                )
            } else {
                (0.0, 1.0, 0.0)
            };
            let vn = p
                .normal
                .dot(bb.point_velocity(p.rb) - ba.point_velocity(p.ra));
            let l = -p.normal_mass * mass_scale * (vn + bias) - impulse_scale * p.normal_impulse;
            let new = (p.normal_impulse + l).max(0.0);
            let d = new - p.normal_impulse;
            p.normal_impulse = new;
            p.max_normal_impulse = p.max_normal_impulse.max(new);
            ba.apply_impulse(p.ra, -p.normal * d);
            bb.apply_impulse(p.rb, p.normal * d);

            // Coulomb friction, the tangent impulse clamped to the disk of radius μλₙ.
            let dv = bb.point_velocity(p.rb) - ba.point_velocity(p.ra);
            let old = p.tangent_impulse;
            let mut new = old;
            for (t, m) in tangents.iter().zip(p.tangent_mass) {
                new -= *t * (m * t.dot(dv));
            }
            let cap = pair.friction * p.normal_impulse;
            if new.length_squared() > cap * cap {
                new = new.normalize_or_zero() * cap;
            }
            p.tangent_impulse = new;
            let d = new - old;
            ba.apply_impulse(p.ra, -d);
            bb.apply_impulse(p.rb, d);
        }
        // Rolling resistance: drive the relative angular velocity to zero with at most
        // ρ r Σλₙ of angular impulse (Box2D v3's rolling resistance, in 3D).
        if pair.rolling_arm > 0.0 {
            let cap = pair.rolling_arm
                * pair
                    .points
                    .iter()
                    .map(|c| c.data.normal_impulse)
                    .sum::<f32>();
            let k = ba.inv_inertia + bb.inv_inertia;
            if k.determinant().abs() > 1e-20 {
                let w = bb.w - ba.w;
                let old = pair.rolling_impulse;
                let new = (old - k.inverse() * w).clamp_length_max(cap);
                pair.rolling_impulse = new;
                ba.apply_angular_impulse(-(new - old));
                bb.apply_angular_impulse(new - old);
            }
        }
        ba.store(s, a);
        bb.store(s, b);
    }
}

/// Box2D's restitution pass, after the substeps: points that were approaching faster
/// than `threshold` and carried load get the normal velocity `−e · v_before`.
pub fn restitution(pairs: &mut [ContactPair], s: &mut BodyStates, awake: &[bool], threshold: f32) {
    // Block-free Gauss–Seidel over a face's points: one pass under-shoots, so
    // the pass is run a few times (the clamp keeps it from over-shooting).
    for _ in 0..4 {
        restitution_pass(pairs, s, awake, threshold);
    }
}

fn restitution_pass(pairs: &mut [ContactPair], s: &mut BodyStates, awake: &[bool], threshold: f32) {
    for pair in active(pairs, awake) {
        if pair.restitution == 0.0 {
            continue;
        }
        let (a, b) = (pair.a as usize, pair.b as usize);
        for p in pair.points.iter_mut().map(|c| &mut c.data) {
            if p.relative_velocity > -threshold || p.max_normal_impulse == 0.0 {
                continue;
            }
            let vn = p
                .normal
                .dot(s.point_velocity(b, p.rb) - s.point_velocity(a, p.ra));
            let l = -p.normal_mass * (vn + pair.restitution * p.relative_velocity);
            let new = (p.normal_impulse + l).max(0.0);
            let d = new - p.normal_impulse;
            p.normal_impulse = new;
            s.apply_impulse(a, p.ra, -p.normal * d);
            s.apply_impulse(b, p.rb, p.normal * d);
        }
    }
}
/// One position-projection pass (see [`super::project`]): each point deeper than
/// [`LINEAR_SLOP`] is pushed apart along its normal by a fraction of its depth,
/// `P = −K⁻¹ C` with `C = β (s + slop)` clamped to `[−MAX_LINEAR_CORRECTION, 0]`
/// (Box2D v2.4's `b2ContactSolver::SolvePositionConstraints`).
pub fn project(pairs: &mut [ContactPair], s: &mut BodyStates, awake: &[bool]) {
    for pair in active(pairs, awake) {
        let (a, b) = (pair.a as usize, pair.b as usize);
        for c in &pair.points {
            let sep = current_separation(c, s.com[a], s.rot[a], s.com[b], s.rot[b]);
            let p = &c.data;
            let c = (CONTACT_CORRECTION * (sep + LINEAR_SLOP)).clamp(-MAX_LINEAR_CORRECTION, 0.0);
            if c == 0.0 {
                continue;
            }
            let (ra, rb) = (s.rot[a] * p.local_a, s.rot[b] * p.local_b);
            let (ja, jb) = (ra.cross(p.normal), rb.cross(p.normal));
            let k = s.inv_mass[a]
                + s.inv_mass[b]
                + ja.dot(s.inv_inertia[a] * ja)
                + jb.dot(s.inv_inertia[b] * jb);
            if k <= 1e-20 {
                continue;
            }
            let impulse = p.normal * (-c / k);
            s.apply_position_impulse(a, ra, -impulse);
            s.apply_position_impulse(b, rb, impulse);
        }
    }
}

/// Separation now, from the motion of both anchors since prepare.
#[inline]
fn current_separation(
    c: &TrackedContact<ContactPoint>,
    ca: Vec3,
    qa: Quat,
    cb: Vec3,
    qb: Quat,
) -> f32 {
    let p = &c.data;
    let da = ca + qa * p.local_a - p.pa0;
    let db = cb + qb * p.local_b - p.pb0;
    c.dist + p.normal.dot(db - da)
}

/// Persistent id of a manifold point: parry's feature ids of both shapes.
#[inline]
fn point_id<D>(c: &TrackedContact<D>) -> u64 {
    ((c.fid1.0 as u64) << 32) | c.fid2.0 as u64
}

/// Turns parry's manifold into solver points, carrying impulses over by feature id from
/// `old` ([`ContactPair::old_impulses`]); a linear search is cheapest for a handful.
fn prepare_pair(
    pair: &mut ContactPair,
    s: &BodyStates,
    pose_a: &PPose,
    pose_b: &PPose,
    old: &[(u64, f32, Vec3)],
) {
    let (a, b) = (pair.a as usize, pair.b as usize);
    pair.touching = false;
    // An empty manifold makes no points whatever its normal.
    if pair.points.is_empty() {
        return;
    }
    let normal = (pose_a.rotation * pair.manifold_n1).normalize_or_zero();
    if normal == Vec3::ZERO {
        return;
    }
    for c in &mut pair.points {
        let pa = pose_a.transform_point(c.local_p1);
        let pb = pose_b.transform_point(c.local_p2);
        let id = point_id(c);
        let (ni, ti) = old
            .iter()
            .find(|o| o.0 == id)
            .map_or((0.0, Vec3::ZERO), |o| (o.1, o.2 - normal * normal.dot(o.2)));
        let ra = pa - s.com[a];
        let rb = pb - s.com[b];
        c.data = ContactPoint {
            normal,
            ra,
            rb,
            local_a: s.rot[a].inverse() * ra,
            local_b: s.rot[b].inverse() * rb,
            pa0: pa,
            pb0: pb,
            normal_impulse: ni,
            tangent_impulse: ti,
            ..Default::default()
        };
    }
    pair.touching = true;
}
