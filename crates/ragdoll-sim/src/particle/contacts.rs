//! Collision detection: which pairs may collide, a broad phase (`crate::broadphase`) over parry
//! AABBs, and parry3d contact manifolds between the shapes posed by the bone frames and
//! against the ground half-space.
//!
//! Filtering (paper section 3.4, and the Doom 3 seed's advice on jumpy figures): no
//! contacts between jointed bones, none between bones that overlap in the rest pose, none
//! inside a figure when either bone has `self_collision` off, none between two static
//! bones.

use super::bone::{Bone, Side};
use super::bone_kinds::BoneKinds;
use crate::broadphase::{Reused, box_height_above_plane};
use crate::scene::Ground;
use glam::{Vec3, Vec3A, Vec4};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::query::{ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher};
use parry3d::shape::HalfSpace;
use rayon::prelude::*;
use std::ops::Range;

/// A contact manifold: where two sides touch, and what its points share. Its points
/// are those of the same [`ContactSet`] from its `start` up to the next manifold's
/// (the last one's up to the set's end, [`ranges`]).
///
/// Split from the points (Box2D's manifold/point split) because a box face brings
/// four points with one normal and one pair of materials: kept once per manifold the
/// set is less than half the bytes, and the passes over the points stream less. Its
/// sides are packed in 4 bytes each ([`Manifold::a`], [`Manifold::b`]), its normal in
/// three floats followed by its Coulomb coefficient, so that one unaligned load gives
/// the normal's SIMD lanes ([`Manifold::n`]), and its points' end is the next
/// manifold's start, not kept: 36 bytes, four-byte aligned (a normal held in lanes,
/// 16 bytes and 16-aligned, and an end made it 48).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Manifold {
    /// The first bone.
    a: u32,
    /// The second bone, or the ground ([`GROUND`]).
    b: u32,
    /// The unit normal from `a` towards `b` (world, fixed for the frame), then the
    /// combined Coulomb coefficient ([`Manifold::n`], [`Manifold::mu`]).
    n_mu: [f32; 4],
    /// Combined restitution.
    pub e: f32,
    /// `ρ r` of its rolling resistance (m, `crate::scene::rolling_arm`): 0 when
    /// neither side rolls.
    pub roll: f32,
    /// First point; the manifold's points run up to the next manifold's first.
    pub start: u32,
}

/// A [`Manifold`]'s ground side.
const GROUND: u32 = u32::MAX;

// The sizes the docs of `Manifold` and `ContactPoint` give, which the memory bench's
// figures are made of.
const _: () = assert!(size_of::<Manifold>() == 36 && size_of::<ContactPoint>() == 56);

impl Manifold {
    /// The first bone.
    #[inline]
    pub fn a(&self) -> usize {
        self.a as usize
    }

    /// The second bone, or the ground (`None`).
    #[inline]
    pub fn b(&self) -> Side {
        (self.b != GROUND).then_some(self.b as usize)
    }

    /// Unit normal from `a` towards `b` (world), fixed for the frame, in SIMD lanes as
    /// the solver uses it: the four floats of `n_mu` in one load, the normal's bits in
    /// `x`, `y`, `z` and the Coulomb coefficient in the lane a `Vec3A` leaves unread.
    #[inline]
    pub fn n(&self) -> Vec3A {
        Vec3A::from_vec4(Vec4::from_array(self.n_mu))
    }

    /// Combined Coulomb coefficient, `√(μ_a μ_b)`.
    #[inline]
    pub fn mu(&self) -> f32 {
        self.n_mu[3]
    }

    /// The manifold between sides `a` and `b` (bones below `u32::MAX`) whose points
    /// start at `start`: its copy in a batch, bones and points renumbered.
    pub fn renumbered(self, (a, b): (usize, Side), start: u32) -> Manifold {
        Manifold {
            a: a as u32,
            b: b.map_or(GROUND, |j| j as u32),
            start,
            ..self
        }
    }
}

/// Manifold `k`'s points' range in its set, whose points end at `end`: from its start
/// up to the next manifold's, the last one's up to `end`.
pub(crate) fn range(manifolds: &[Manifold], k: usize, end: usize) -> Range<usize> {
    let next = manifolds.get(k + 1).map_or(end, |m| m.start as usize);
    debug_assert!(
        manifolds[k].start as usize <= next,
        "manifolds' points in order"
    );
    manifolds[k].start as usize..next
}

/// Each manifold's points' range in turn ([`range`]), in a set whose points end at
/// `end`. Consecutive manifolds' points are consecutive: `ContactSet::push` and
/// `append`, and `Batch::gather`, keep them so.
pub(crate) fn ranges(manifolds: &[Manifold], end: usize) -> impl Iterator<Item = Range<usize>> {
    let next = (manifolds.iter().skip(1).map(|m| m.start as usize)).chain(std::iter::once(end));
    manifolds.iter().zip(next).map(|(m, next)| {
        debug_assert!(m.start as usize <= next, "manifolds' points in order");
        m.start as usize..next
    })
}

/// The points of consecutive manifolds, cut into each one's run in order: `points`
/// holds exactly their points, from the first manifold's first point on ([`ranges`]).
pub(crate) fn point_runs<'a>(
    manifolds: &'a [Manifold],
    mut points: &'a mut [ContactPoint],
) -> impl Iterator<Item = &'a mut [ContactPoint]> + 'a {
    let end = manifolds.first().map_or(0, |m| m.start as usize) + points.len();
    ranges(manifolds, end).map(move |r| {
        let (run, after) = std::mem::take(&mut points).split_at_mut(r.len());
        points = after;
        run
    })
}

/// One contact point, kept in the bones' frames so it can be re-evaluated every substep.
///
/// 56 bytes: its two material points and six numbers of the solve. What is the same
/// for every point of the set is not kept here: how far the frame so far allows an old
/// overlap to be pushed out is one product a substep (`friction::PushOut`), and a
/// point not yet pressed is told by a sentinel offset ([`UNTOUCHED`]), not an
/// `Option`'s tag. The friction multiplier of the position passes and the normal
/// impulse of the velocity pass share one number ([`ContactPoint::lambda_tv`]): a
/// substep is done with the first before it starts the second. The relative normal
/// velocity before a substep's solve, which only restitution reads, is the substep
/// loop's, measured only on manifolds that bounce (`rigid_frames::run_substeps`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ContactPoint {
    /// Contact point on `a`, bone frame.
    pub ra: Vec3,
    /// Contact point on `b`, bone frame (world for the ground).
    pub rb: Vec3,
    /// Normal multiplier of the current substep (0 when not touching).
    pub lambda_n: f32,
    /// Through the current substep's position passes, `λ_t`: the tangential (friction)
    /// multiplier they have spent, read by the manifold's Coulomb cone
    /// (`friction::solve_friction`). From its velocity pass on, `λ_v`: the normal
    /// impulse (N s) that pass has applied, `> 0` pushing, which with the position
    /// passes' `lambda_n / h` sums to the substep's whole normal impulse, never a pull
    /// (`friction::solve_velocities`), and which rolling resistance reads. Zero at the
    /// start of each (`rigid_frames::run_substeps`).
    pub lambda_tv: f32,
    /// Tangential offset `pa − pb` of the two points when they last came into touch (at
    /// the start of the first substep of an unbroken run of touching ones): what they
    /// drift from it since is slip static friction may take back
    /// (`friction::ANCHOR_PULL`); their approach before touching is not. [`UNTOUCHED`]
    /// until the point is first pressed in such a run ([`ContactPoint::touched_at`]):
    /// it is measured then (`friction::normal_target`), not for every speculative point
    /// at every substep's start.
    touched_at: Vec3,
    /// Overlap (m) the point's last normal solve left to push out later, at most
    /// `max_push_out_speed` × h a substep (`friction::normal_target`); `∞` before its
    /// first solve.
    pub left: f32,
    /// [`ContactPoint::left`] as the current substep started: the only overlap the
    /// substep's solves push out slowly. Anything deeper was pushed in after the last
    /// solve (by a joint) and is taken back in full.
    pub left_before: f32,
    /// Overlap (m) of the point's two material points where the bones stood as the
    /// frame began (≤ 0: apart), set at detection; `−∞` until then.
    pub frame_overlap: f32,
}

/// The `x` of [`ContactPoint::touched_at`] while the point has no touch offset: a NaN
/// with a payload of its own. An offset the solver measures is finite, or, in a world
/// gone to NaN, a NaN arithmetic made: the processor's default NaN or one of its
/// operands' payloads, and this value is never an operand. Compared by its bits, it
/// tells "none" from every offset, as the `Option`'s tag would, in 4 bytes fewer.
const UNTOUCHED: f32 = f32::from_bits(0x7fc0_7a11);

impl ContactPoint {
    /// A point at `ra` on `a` and `rb` on `b`, not yet solved.
    pub fn new(ra: Vec3, rb: Vec3) -> ContactPoint {
        ContactPoint {
            ra,
            rb,
            lambda_n: 0.0,
            lambda_tv: 0.0,
            touched_at: Vec3::splat(UNTOUCHED),
            left: f32::INFINITY,
            left_before: f32::INFINITY,
            frame_overlap: f32::NEG_INFINITY,
        }
    }

    /// The tangential offset of its two points when they came into touch in the
    /// current run of touching substeps (field `touched_at`); `None` before it is first
    /// pressed in the run.
    #[inline]
    pub fn touched_at(&self) -> Option<Vec3> {
        (self.touched_at.x.to_bits() != UNTOUCHED.to_bits()).then_some(self.touched_at)
    }

    /// Sets the offset of [`ContactPoint::touched_at`]; `None` starts a new run.
    #[inline]
    pub fn set_touched_at(&mut self, offset: Option<Vec3>) {
        self.touched_at = offset.unwrap_or(Vec3::splat(UNTOUCHED));
    }
}

/// The contacts of one collision detection: manifolds and their points.
#[derive(Clone, Debug, Default)]
pub(crate) struct ContactSet {
    /// Manifolds in detection order.
    pub manifolds: Vec<Manifold>,
    /// Every manifold's points, manifold by manifold.
    pub points: Vec<ContactPoint>,
}

impl ContactSet {
    /// Empties the set, keeping its storage.
    pub fn clear(&mut self) {
        self.manifolds.clear();
        self.points.clear();
    }

    /// Adds a point between sides `(a, b)` with normal `n` and materials `(μ, e, ρ r)`
    /// ([`Manifold`]): to the last manifold if it was opened for this pair (index
    /// `first` or later) with the same normal, else to a new one. Parry reports a pair's
    /// points manifold by manifold, so a pair of convex shapes makes one manifold and a
    /// pair with no points makes none. The last manifold's points run to the set's end,
    /// so a point added to it needs no change to it.
    pub fn push(
        &mut self,
        first: usize,
        (a, b): (usize, Side),
        n: Vec3,
        (mu, e, roll): (f32, f32, f32),
        point: ContactPoint,
    ) {
        let open = self.manifolds.len() > first;
        if !(self.manifolds.last()).is_some_and(|m| open && Vec3::from_slice(&m.n_mu) == n) {
            self.manifolds.push(Manifold {
                a: a as u32,
                b: b.map_or(GROUND, |j| j as u32),
                n_mu: [n.x, n.y, n.z, mu],
                e,
                roll,
                start: self.points.len() as u32,
            });
        }
        self.points.push(point);
    }

    /// Makes room for `extra` more manifolds and points in a set kept between
    /// detections, growing a full array by an eighth (at least `extra`) rather than
    /// doubling it: the set keeps its largest size (a pile's landing), so doubling
    /// would hold up to twice its points for good; growing by an eighth costs a few
    /// dozen copies of the set over a run, as its room is never given back.
    pub fn reserve_kept(&mut self, extra: usize) {
        reserve_kept(&mut self.manifolds, extra);
        reserve_kept(&mut self.points, extra);
    }

    /// [`give_back_room`] of both arrays, once a detection has filled them.
    pub fn give_back_room(&mut self) {
        give_back_room(&mut self.manifolds);
        give_back_room(&mut self.points);
    }

    /// Appends another set's manifolds and points after this one's, its points'
    /// ranges moved by where they land: the same set as pushing them here in turn.
    pub fn append(&mut self, other: &ContactSet) {
        let offset = self.points.len() as u32;
        self.manifolds
            .extend(other.manifolds.iter().map(|m| Manifold {
                start: m.start + offset,
                ..*m
            }));
        self.points.extend_from_slice(&other.points);
    }
}

/// Makes room for `extra` more items in an array kept between uses at its largest
/// size, growing it by an eighth (at least `extra`) rather than doubling it: doubling
/// would hold up to twice the largest size for good. Into an emptied array, `extra` is
/// its size, and the room is exactly that.
pub(crate) fn reserve_kept<T>(v: &mut Vec<T>, extra: usize) {
    if v.capacity() - v.len() < extra {
        v.reserve_exact(extra.max(v.len() / 8));
    }
}

/// Gives back the room of an array kept between uses ([`reserve_kept`]) once it fills
/// less than half of it, keeping an eighth over its length: a pile's landing leaves its
/// contact arrays at two to three times what the landed pile fills, held for good
/// otherwise. Regrowing costs one copy per eighth of growth ([`reserve_kept`]), and
/// the room only changes where the items live, never their values.
pub(crate) fn give_back_room<T>(v: &mut Vec<T>) {
    if v.capacity() > 2 * v.len() {
        v.shrink_to(v.len() + v.len() / 8);
    }
}

/// Pairs that never collide, precomputed from the scene: jointed bones and bones that
/// overlap at rest.
///
/// Stored by bone (compressed rows): the broad phase asks it of every overlapping pair,
/// most of them a figure's jointed neighbours, and a binary search of one sorted list
/// of all the pairs (15 000 for a pile of 1000 humans) cost as much as finding them.
#[derive(Clone, Debug, Default)]
pub(crate) struct Filter {
    /// Bone `i`'s excluded partners of higher index are `partners[first[i]..first[i +
    /// 1]]`, ascending. Bones past its end (the last with a partner, a projectile)
    /// have none.
    first: Vec<u32>,
    partners: Vec<u32>,
}

/// What the filter reads of a bone, eight bytes, gathered with the bones' boxes: the
/// broad phase asks it of every overlapping pair, in no order, and a bone itself spans
/// several cache lines.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FilterKey {
    figure: u32,
    fixed: bool,
    at_rest: bool,
    self_collision: bool,
}

impl FilterKey {
    /// The bone's key.
    pub fn of(b: &Bone) -> FilterKey {
        FilterKey {
            figure: b.figure,
            fixed: b.fixed,
            at_rest: b.is_static(),
            self_collision: b.self_collision,
        }
    }
}

impl Filter {
    /// A filter excluding `pairs` (each in either order, repeats allowed) among `bones`.
    pub fn new(bones: usize, pairs: &[(usize, usize)]) -> Filter {
        let mut sorted: Vec<(u32, u32)> = pairs
            .iter()
            .map(|&(i, j)| (i.min(j) as u32, i.max(j) as u32))
            .collect();
        sorted.sort_unstable();
        sorted.dedup();
        // Rows up to the last bone with a partner: a scene without joints holds none.
        debug_assert!(
            sorted.iter().all(|&(_, hi)| (hi as usize) < bones),
            "an excluded pair names a bone past the world's {bones}"
        );
        let rows = sorted.last().map_or(0, |&(lo, _)| lo as usize + 1);
        let mut first = vec![0u32; if rows > 0 { rows + 1 } else { 0 }];
        for &(lo, _) in &sorted {
            first[lo as usize + 1] += 1;
        }
        for i in 0..rows {
            first[i + 1] += first[i];
        }
        let partners = sorted.iter().map(|&(_, hi)| hi).collect();
        Filter { first, partners }
    }

    /// Whether bones `i` and `j`, with their keys, may collide.
    pub fn collides(&self, (i, ki): (u32, FilterKey), (j, kj): (u32, FilterKey)) -> bool {
        if ki.fixed && kj.fixed {
            return false;
        }
        if ki.figure == kj.figure && !(ki.self_collision && kj.self_collision) {
            return false;
        }
        !self.excludes(i.min(j), i.max(j))
    }

    /// Whether the pair `lo < hi` is excluded.
    fn excludes(&self, lo: u32, hi: u32) -> bool {
        let lo = lo as usize;
        match (self.first.get(lo), self.first.get(lo + 1)) {
            (Some(&start), Some(&end)) => self.partners[start as usize..end as usize].contains(&hi),
            _ => false,
        }
    }
}

/// Candidate pairs, sorted: bones whose AABBs loosened by `margin[i]` overlap
/// ([`crate::broadphase`]), not both static, and allowed to collide by `filter`; the
/// bones' shapes are their kinds' in `kinds`.
pub(crate) fn broad_phase(
    bones: (&[Bone], &BoneKinds),
    margin: &[f32],
    filter: &Filter,
    out: &mut Vec<(usize, usize)>,
) {
    broad_phase_on(&mut Reused::default(), bones, margin, filter, out);
}

/// [`broad_phase`] on a tree kept from the step's earlier detections ([`Reused`]).
/// Returns the bones' loosened boxes, which also tell which bones may reach the ground
/// ([`reaches_ground`]).
pub(crate) fn broad_phase_on(
    tree: &mut Reused,
    (bones, kinds): (&[Bone], &BoneKinds),
    margin: &[f32],
    filter: &Filter,
    out: &mut Vec<(usize, usize)>,
) -> Vec<Aabb> {
    out.clear();
    // A box per bone, on all threads: 16 000 bones' poses and boxes were a tenth of a
    // detection run on one thread while the other waited.
    let (aabbs, keys): (Vec<_>, Vec<_>) = bones
        .par_iter()
        .with_min_len(BONES_PER_TASK)
        .zip(margin)
        .map(|(b, m)| {
            let aabb = kinds
                .of(b)
                .shape
                .get()
                .shape()
                .compute_aabb(&b.parry_pose(kinds))
                .loosened(*m);
            (aabb, FilterKey::of(b))
        })
        .unzip();
    let mut pairs = Vec::new();
    // Pairs of two bones at rest are not looked for (`Reused::moving_pairs_where`).
    tree.moving_pairs_where(
        &aabbs,
        |i| keys[i as usize].at_rest,
        |i, j| filter.collides((i, keys[i as usize]), (j, keys[j as usize])),
        &mut pairs,
    );
    // Kept between detections at the most pairs, not doubled past it.
    reserve_kept(out, pairs.len());
    out.extend(pairs.into_iter().map(|(i, j)| (i as usize, j as usize)));
    aabbs
}

/// Bones per task when a detection's per-bone work (margins, boxes) runs on the pool.
pub(super) const BONES_PER_TASK: usize = 512;

/// Contacts between two bones with `prediction` (m) of speculative distance. Calls
/// `emit(point_on_a_world, point_on_b_world, normal_a_to_b, distance)`.
pub(crate) fn shape_pair(
    (bones, kinds): (&[Bone], &BoneKinds),
    i: usize,
    j: usize,
    prediction: f32,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
    mut emit: impl FnMut(Vec3, Vec3, Vec3, f32),
) {
    let (ki, kj) = (kinds.of(&bones[i]), kinds.of(&bones[j]));
    let (pi, pj) = (bones[i].parry_pose(kinds), bones[j].parry_pose(kinds));
    let pos12 = pi.inv_mul(&pj);
    manifolds.clear();
    let mut ws = None;
    if DefaultQueryDispatcher
        .contact_manifolds(
            &pos12,
            ki.shape.get().shape(),
            kj.shape.get().shape(),
            prediction,
            manifolds,
            &mut ws,
        )
        .is_err()
    {
        return;
    }
    for m in manifolds.iter() {
        let n = pi.rotation * m.local_n1;
        for c in &m.points {
            emit(pi * c.local_p1, pj * c.local_p2, n, c.dist);
        }
    }
}

/// How far above the ground (m) a box must lie for [`reaches_ground`] to rule out
/// contacts: well past the rounding of parry's distances (about 1e-6 m at tens of
/// metres), well below any contact's size.
const GROUND_SLACK: f32 = 1e-4;

/// Whether a bone whose box loosened by a margin is `aabb` may have contacts with the
/// ground within that margin ([`ground_pair`]'s `prediction`): whether the box reaches
/// the plane (`box_height_above_plane`, within [`GROUND_SLACK`]). With `x` in the shape
/// and within the margin of the plane, `x − margin n` is in the loosened box and on or
/// below the plane. Most bones of a pile are above it, and parry's manifold query (a
/// support feature, clipping) finds nothing there at about the cost of finding
/// something. `plane` is the ground's normal and a point of it ([`ground_plane`]).
pub(crate) fn reaches_ground((normal, origin): (Vec3, Vec3), aabb: &Aabb) -> bool {
    box_height_above_plane(aabb, normal, origin) <= GROUND_SLACK
}

/// The ground plane's unit normal and a point of it, as `reaches_ground` takes them.
pub(crate) fn ground_plane(ground: &Ground) -> (Vec3, Vec3) {
    (ground.normal(), Vec3::new(0.0, ground.height, 0.0))
}

/// Contacts of a bone with the ground plane. Same `emit` convention, `a` the bone.
pub(crate) fn ground_pair(
    (bones, kinds): (&[Bone], &BoneKinds),
    i: usize,
    ground: &Ground,
    prediction: f32,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
    mut emit: impl FnMut(Vec3, Vec3, Vec3, f32),
) {
    let plane = HalfSpace::new(ground.normal());
    let pg = parry3d::math::Pose::from_translation(Vec3::new(0.0, ground.height, 0.0));
    let kind = kinds.of(&bones[i]);
    let pb = bones[i].parry_pose(kinds);
    let pos12 = pg.inv_mul(&pb);
    manifolds.clear();
    let mut ws = None;
    if DefaultQueryDispatcher
        .contact_manifolds(
            &pos12,
            &plane,
            kind.shape.get().shape(),
            prediction,
            manifolds,
            &mut ws,
        )
        .is_err()
    {
        return;
    }
    for m in manifolds.iter() {
        let n = pg.rotation * m.local_n1;
        for c in &m.points {
            emit(pb * c.local_p2, pg * c.local_p1, -n, c.dist);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `reaches_ground` never rules out a bone parry finds ground contacts for, and
    /// rules out the bones well above the plane: the human's boxes and the capsule
    /// human's capsules at 3000 random poses within 50 cm of a ground tilted 0–20°, with
    /// margins up to 5 cm.
    #[test]
    fn ground_test_keeps_every_bone_that_touches() {
        use super::super::{scene_world, uniform};
        use glam::Quat;
        for (file, seed) in [
            ("human.af", 0x2545_f491_u32),
            ("capsule-human.af", 0x9e37_79b9),
        ] {
            let mut w = scene_world(file, None);
            let mut next = uniform(seed);
            let (mut touching, mut ruled_out) = (0, 0);
            for case in 0..3000 {
                let ground = Ground {
                    height: next() - 0.5,
                    tilt: next() * 0.35,
                    ..Ground::default()
                };
                let i = case % w.bones.len();
                let b = &mut w.bones[i];
                let turn = Vec3::new(next(), next(), next()) * 6.0 - Vec3::splat(3.0);
                b.rot = Quat::from_scaled_axis(turn);
                b.dcom = Vec3A::ZERO;
                let above = next() * 0.6 - 0.1;
                let plane_point = Vec3::new(next() * 4.0 - 2.0, ground.height, 0.0);
                b.com = Vec3A::from(plane_point + ground.normal() * above);
                let margin = next() * 0.05;
                let kind = w.kinds.of(b);
                let aabb = kind
                    .shape
                    .get()
                    .shape()
                    .compute_aabb(&b.parry_pose(&w.kinds));
                let reaches = reaches_ground(ground_plane(&ground), &aabb.loosened(margin));
                let mut found = false;
                ground_pair(
                    (&w.bones, &w.kinds),
                    i,
                    &ground,
                    margin,
                    &mut Vec::new(),
                    |_, _, _, _| {
                        found = true;
                    },
                );
                assert!(reaches || !found, "{file}, case {case}: bone {i} touches");
                touching += usize::from(found);
                ruled_out += usize::from(!reaches);
            }
            assert!(touching > 500 && ruled_out > 500, "{touching} {ruled_out}");
        }
    }

    fn point(x: f32) -> ContactPoint {
        ContactPoint::new(Vec3::splat(x), Vec3::ZERO)
    }

    /// The filter's rows answer for each pair in either order, for repeated pairs, and
    /// for a bone past the rows (a projectile added later); the keys' rules come first.
    #[test]
    fn filter_excludes_its_pairs_and_nothing_else() {
        let filter = Filter::new(6, &[(1, 0), (0, 1), (3, 1), (2, 5), (0, 4)]);
        let key = |figure| FilterKey {
            figure,
            fixed: false,
            at_rest: false,
            self_collision: true,
        };
        let excluded = [(0, 1), (1, 3), (2, 5), (0, 4)];
        for i in 0..8u32 {
            for j in 0..8u32 {
                if i == j {
                    continue;
                }
                let listed = excluded.contains(&(i.min(j), i.max(j)));
                assert_eq!(
                    filter.collides((i, key(0)), (j, key(0))),
                    !listed,
                    "({i}, {j})"
                );
            }
        }
        let fixed = FilterKey {
            fixed: true,
            ..key(1)
        };
        assert!(!filter.collides((2, fixed), (3, fixed)), "two fixed bones");
        let alone = FilterKey {
            self_collision: false,
            ..key(1)
        };
        assert!(
            !filter.collides((2, alone), (3, key(1))),
            "one figure, no self-collision"
        );
        assert!(filter.collides((2, alone), (3, key(2))), "two figures");
        let none = Filter::new(5, &[]);
        assert!(none.first.is_empty() && none.partners.is_empty());
        assert!(none.collides((0, key(0)), (4, key(0))));
    }

    /// A pair's points with one normal share a manifold; a second pair, or a second
    /// normal within a pair, opens another; a pair without points opens none.
    #[test]
    fn points_group_into_manifolds_by_pair_and_normal() {
        let mut set = ContactSet::default();
        let (up, side) = (Vec3::Y, Vec3::X);
        let first = set.manifolds.len();
        set.push(first, (0, Some(1)), up, (0.5, 0.0, 0.0), point(0.0));
        set.push(first, (0, Some(1)), up, (0.5, 0.0, 0.0), point(1.0));
        set.push(first, (0, Some(1)), side, (0.5, 0.0, 0.0), point(2.0));
        // Pair (1, 2) brings no point; pair (2, None) one, with the same normal as the
        // last manifold, which must not absorb it.
        let first = set.manifolds.len();
        set.push(first, (2, None), side, (0.3, 0.1, 0.0), point(3.0));
        let runs: Vec<_> = ranges(&set.manifolds, set.points.len()).collect();
        assert_eq!(runs, vec![0..2, 2..3, 3..4]);
        assert_eq!((set.manifolds[2].a(), set.manifolds[2].b()), (2, None));
        assert_eq!(set.manifolds[2].mu(), 0.3);
    }

    /// Sets filled apart and appended in order are the set filled in one go: the
    /// parallel narrow phase relies on it.
    #[test]
    fn appended_sets_are_the_set_pushed_in_turn() {
        let pairs = [(0, Some(1)), (1, Some(2)), (2, None), (3, None)];
        let push = |set: &mut ContactSet, k: usize| {
            let first = set.manifolds.len();
            for p in 0..k + 1 {
                let n = if p == 2 { Vec3::X } else { Vec3::Y };
                set.push(
                    first,
                    pairs[k],
                    n,
                    (0.5, 0.1, 0.0),
                    point(p as f32 + 10.0 * k as f32),
                );
            }
        };
        let mut whole = ContactSet::default();
        (0..4).for_each(|k| push(&mut whole, k));
        let (mut left, mut right) = (ContactSet::default(), ContactSet::default());
        (0..2).for_each(|k| push(&mut left, k));
        (2..4).for_each(|k| push(&mut right, k));
        let mut joined = ContactSet::default();
        joined.append(&left);
        joined.append(&right);
        let key = |s: &ContactSet| {
            let m: Vec<_> = (s.manifolds.iter())
                .zip(ranges(&s.manifolds, s.points.len()))
                .map(|(m, r)| (m.a(), m.b(), m.n(), r))
                .collect();
            let p: Vec<_> = s.points.iter().map(|c| c.ra).collect();
            (m, p)
        };
        assert_eq!(key(&joined), key(&whole));
        assert_eq!(whole.manifolds.len(), 7);
    }
}
