//! Contacts: parry3d manifolds between bodies and against the ground plane, cached per
//! body pair with persistent point ids for warm starting. They are solved as soft
//! non-penetration constraints with Coulomb friction and a restitution pass by
//! [`super::contact_solver`] (Box2D v3's contact solver, in 3D).
//!
//! Per step: the broad phase proposes pairs, the cache keeps each pair's parry workspace
//! and last impulses (a sorted array keyed by the pair, merged with the new pair list),
//! and the narrow phase refreshes the manifolds and anchors each point in both bodies'
//! frames. The solver then fixes normal, Jacobians and effective masses for the step and
//! tracks each separation through the substeps from the bodies' motion
//! (`s = s₀ + n·(Δp_b − Δp_a)`), as Box2D does.

// Several per-body arrays are walked together by index.
#![allow(clippy::needless_range_loop)]

use super::body::{BodyInfo, BodyStates};
use crate::broadphase::{KeptTrees, Reused, box_height_above_plane, speculative_margin};
use crate::scene::Collider;
use crate::scene::rolling_arm;
use glam::{Quat, Vec3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::Pose as PPose;
use parry3d::query::{
    ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher, TrackedContact,
};
use parry3d::shape::{Shape as ParryShape, SharedShape};
use rayon::prelude::*;

/// Penetration the position projection leaves alone (m): keeps resting contacts from
/// being pushed in and out every step ([`super::project`]). The soft velocity rows
/// have no slop (Box2D v3's): they push a resting contact towards zero separation and
/// it settles where the spring carries the load, `F / (m_eff ω²)`. A slop there would
/// add to that at every contact of a stack, half a millimetre per box.
pub const LINEAR_SLOP: f32 = 0.0005;

/// What a contact point keeps between steps. It rides in the `data` slot of parry's
/// tracked contact, next to the point's geometry (anchors in the shape frames,
/// separation, feature ids): one array per pair holds both, and what parry already
/// stores is not repeated here. Everything the solver derives from it for one step (the
/// Jacobians, effective masses, separations) lives in
/// [`super::contact_solver::ContactConstraints`] for that step only.
#[derive(Clone, Copy, Debug, Default)]
pub struct ContactPoint {
    /// Anchor in a's body space, relative to its centre of mass.
    pub local_a: Vec3,
    /// Anchor in b's body space.
    pub local_b: Vec3,
    /// Accumulated normal impulse, for the next step's warm start.
    pub normal_impulse: f32,
    /// Accumulated friction impulse (world vector, survives basis changes).
    pub tangent_impulse: Vec3,
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
    /// `ρ r`: rolling resistance times rolling radius (m, [`crate::scene::rolling_arm`]).
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

    /// How many of the stored points are live: all of them when touching, else none
    /// (the manifold is kept for parry, the points carry no solver state).
    fn live(&self) -> usize {
        if self.touching { self.points.len() } else { 0 }
    }

    /// The solver points (none unless touching).
    pub fn points(&self) -> impl Iterator<Item = &ContactPoint> {
        self.points[..self.live()].iter().map(|c| &c.data)
    }

    /// The points with their separation at the last narrow phase (none unless
    /// touching).
    pub(super) fn contact_points(&self) -> impl Iterator<Item = (&ContactPoint, f32)> {
        self.points[..self.live()].iter().map(|c| (&c.data, c.dist))
    }

    /// The points, to write their impulses (none unless touching).
    pub(super) fn contact_points_mut(&mut self) -> impl Iterator<Item = &mut ContactPoint> {
        let n = self.live();
        self.points[..n].iter_mut().map(|c| &mut c.data)
    }

    /// The pair's normal from a to b (world) when a's orientation is `rot_a`: parry's
    /// manifold normal, kept in a's shape frame, rotated out (zero if there is none).
    pub fn normal(&self, rot_a: Quat) -> Vec3 {
        (rot_a * self.manifold_n1).normalize_or_zero()
    }

    /// The impulses of the points now, by persistent id, for warm starting once the
    /// manifold is refreshed: read before [`ContactPair::collide`] rewrites the points
    /// (none unless touching). A manifold holds a handful of points; the first 8 are
    /// kept, as many as are looked up.
    fn old_impulses(&self) -> ([(u64, f32, Vec3); 8], usize) {
        let mut old: [(u64, f32, Vec3); 8] = [(u64::MAX, 0.0, Vec3::ZERO); 8];
        let n_old = self.live().min(8);
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
        // A pair keeps room for the points it has, no more (76 bytes each): a `Vec`
        // grows to at least four and then doubles, so a resting pair of one or two
        // points would hold four, and one that once had five would hold eight. A pair
        // that parted keeps none: most cached pairs of a landed pile are neighbours
        // whose loosened boxes overlap while their shapes do not. Parry reads back
        // the points and normals, never the spare room, so the result is the same; a
        // manifold of stable size is refilled in place (parry clears it and pushes as
        // many points as before), and shrinking a block is done where it lies.
        self.points.shrink_to_fit();
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
    /// The broad phase's trees of a step that detects once, refitted by the next.
    trees: KeptTrees,
    /// Pairs that never collide (jointed, overlapping at rest, self-collision off), sorted.
    pub excluded: Vec<(u32, u32)>,
    /// The ground, if any.
    pub ground: Option<GroundCollider>,
    /// The parry colliders of the convex-hull bodies (see [`BodyInfo::collider`]).
    pub hulls: Vec<SharedShape>,
}

impl Contacts {
    /// Gives back the broad phase's kept trees (a world at rest needs none).
    pub fn release_trees(&mut self) {
        self.trees.release();
    }

    /// Drops the contact state by owner (see `Method::drop_by_owner`): the pairs'
    /// manifold points, the pair cache, the broad phase's boxes and candidates, the
    /// excluded pairs, the ground and hull colliders.
    pub(crate) fn drop_by_owner(self, dropped: &mut dyn FnMut(&'static str)) {
        let Contacts {
            mut pairs,
            candidates,
            aabbs,
            trees,
            excluded,
            ground,
            hulls,
        } = self;
        pairs.iter_mut().for_each(|p| p.points = Vec::new());
        dropped("contact points");
        drop(pairs);
        dropped("contact pairs");
        drop((candidates, aabbs, trees));
        dropped("broad phase");
        drop(excluded);
        dropped("excluded pairs");
        drop((ground, hulls));
        dropped("ground, hulls");
    }
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
    /// cached state untouched. `dt` widens the margins for fast bodies, `g` (the
    /// gravity's magnitude, m/s²) for falling ones ([`speculative_margin`]).
    pub fn update(
        &mut self,
        s: &BodyStates,
        info: &[BodyInfo],
        awake: &[bool],
        dt: f32,
        g: f32,
        tree: &mut Reused,
    ) {
        let margin = speculative_margin(g, dt);
        let n = info.len();
        let anchor = n as u32;
        // Broad phase on AABBs loosened by the speculative margin and this step's motion,
        // each body's on its own (on all cores, in body order).
        self.aabbs.clear();
        let hulls = &self.hulls;
        self.aabbs
            .par_extend((0..n).into_par_iter().with_min_len(1024).map(|i| {
                let motion = point_speed(s, info, i) * dt;
                let aabb = info[i]
                    .collider(hulls)
                    .shape()
                    .compute_aabb(&shape_pose(s, info, i));
                aabb.loosened(margin + motion)
            }));
        self.candidates.clear();
        // Bodies near the ground plane (the plane comes last: the anchor has the largest
        // index). Listed first, as the broad phase reserves its pairs' room once, after
        // them; the list is sorted at the end.
        if let Some(g) = &self.ground {
            for i in 0..n {
                if info[i].fixed {
                    continue;
                }
                if box_height_above_plane(&self.aabbs[i], g.normal, g.origin) < 0.0 {
                    self.candidates.push((i as u32, anchor));
                }
            }
        }
        // Pairs judged as the traversal finds them, not sorted first and filtered after:
        // most overlaps are a figure's jointed neighbours. Pairs of two resting bodies
        // are not looked for at all (`moving_pairs_where`).
        let excluded = &self.excluded;
        let resting = |a: u32| !awake[a as usize];
        let keep = |a: u32, b: u32| {
            may_collide(info, a as usize, b as usize) && excluded.binary_search(&(a, b)).is_err()
        };
        // A step that detects in several windows shares its trees among them (`Reused`);
        // one that detects once refits the last step's.
        if tree.is_fattened() {
            tree.moving_pairs_where(&self.aabbs, resting, keep, &mut self.candidates);
        } else {
            self.trees
                .moving_pairs_where(&self.aabbs, resting, keep, &mut self.candidates);
        }
        // Sleeping pairs stay in the cache as they are (islands need them). Every pair
        // has a body of its own as `a`; when all of them move, as in a pile's busy
        // frames, no pair is between two resting bodies and the cache is not walked.
        if awake[..n].contains(&false) {
            for p in &self.pairs {
                if !awake[p.a as usize] && !awake[p.b as usize] {
                    self.candidates.push((p.a, p.b));
                }
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
            // Only round bodies roll (`crate::scene::rolling`); the ground does not.
            let radius = |i: usize| info[i].shape.rolling_radius();
            let rolling_arm = if b == anchor {
                rolling_arm(radius(a as usize), 0.0)
            } else {
                rolling_arm(radius(a as usize), radius(b as usize))
            };
            ContactPair {
                a,
                b,
                rolling_arm,
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
            let prediction = margin + approach * dt;
            let pos12 = pose_a.inv_mul(&pose_b);
            let (old, n_old) = pair.old_impulses();
            pair.collide(&pos12, collider_a.shape(), collider_b.shape(), prediction);
            prepare_pair(pair, s, &pose_a, &pose_b, &old[..n_old]);
        });
    }
}

/// Persistent id of a manifold point: parry's feature ids of both shapes.
#[inline]
fn point_id<D>(c: &TrackedContact<D>) -> u64 {
    ((c.fid1.0 as u64) << 32) | c.fid2.0 as u64
}

/// Keeps parry's refreshed manifold as the pair's points: each point's anchors in the
/// bodies' frames, and its impulses carried over by feature id from `old`
/// ([`ContactPair::old_impulses`]; a linear search is cheapest for a handful).
fn prepare_pair(
    pair: &mut ContactPair,
    s: &BodyStates,
    pose_a: &PPose,
    pose_b: &PPose,
    old: &[(u64, f32, Vec3)],
) {
    let (a, b) = (pair.a as usize, pair.b as usize);
    // An empty manifold makes no points whatever its normal.
    pair.touching = !pair.points.is_empty() && pair.normal(pose_a.rotation) != Vec3::ZERO;
    if !pair.touching {
        return;
    }
    let (inv_qa, inv_qb) = (s.rot[a].inverse(), s.rot[b].inverse());
    for c in &mut pair.points {
        let pa = pose_a.transform_point(c.local_p1);
        let pb = pose_b.transform_point(c.local_p2);
        let id = point_id(c);
        let (normal_impulse, tangent_impulse) = old
            .iter()
            .find(|o| o.0 == id)
            .map_or((0.0, Vec3::ZERO), |o| (o.1, o.2));
        c.data = ContactPoint {
            local_a: inv_qa * (pa - s.com[a]),
            local_b: inv_qb * (pb - s.com[b]),
            normal_impulse,
            tangent_impulse,
        };
    }
}
