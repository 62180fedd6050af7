//! The improved solver loop: substepped XPBD over particulated, rigidly projected bones
//! (Macklin et al. 2019, "Small steps in physics simulation"; Müller et al. 2020).
//!
//! Per frame: collision detection with a speculative margin, [`DETECTIONS_PER_FRAME`]
//! times. Per substep `h` ([`substeps`]: the scene's substeps × iterations):
//! 1. integrate every particle (`v += g h`, `x += v h`: Verlet in velocity form);
//! 2. move each bone's frame as its particles move with the six sticks held exactly:
//!    momentum and angular momentum kept, the turn by the implicit midpoint rule
//!    (steps 1–2 in closed form, [`Bone::advance`]);
//! 3. [`PASSES`] Gauss–Seidel passes over contacts, joints and limits, each a rigid
//!    correction of the bone frames weighted by generalised inverse mass (contacts
//!    first, a manifold's points as one block, so a joint is what holds last; the joints of four figures side by side in
//!    SIMD lanes, `joint_lanes`);
//! 4. derive the velocities from the frames' motion over the substep, `v = Δc/h` and
//!    the turn's angular momentum carried to the substep's end
//!    ([`Bone::substep_velocity`]);
//! 5. the velocity pass: restitution, rolling resistance (`rolling`), joint friction,
//!    air friction.
//!
//! Energy: a free bone keeps its energy and angular momentum (no damping of its own);
//! every other step is a constraint correction or a dissipative velocity change. A
//! joint's anchor is corrected in one 3×3 solve aimed from the substep's start in the
//! first pass and projected from its end in the later ones (`bone::Aim`): a frictionless hinge
//! pendulum keeps its exact period and loses 0.1–0.2 % of its swing energy in 10 s at
//! 20 substeps a frame, where a projection alone loses 8.6 %. The only source of energy
//! (push-out from a penetration) is cancelled by the velocity pass.

use super::bone::{Aim, Bone, advance_moving};
use super::bone_kinds::BoneKinds;
use super::contacts::{
    BONES_PER_TASK, ContactPoint, ContactSet, Manifold, broad_phase_on, give_back_room,
    ground_pair, ground_plane, point_runs, range, ranges, reaches_ground, shape_pair,
};
use super::friction::{
    BLOCK, PushOut, point_velocity, solve_friction, solve_normal, solve_normals, solve_velocities,
};
use super::islands::{self, Part};
use super::joint_lanes::Lockstep;
use super::joints::{Joint, JointSet, in_figures};
use super::{ParticleWorld, sleeping};
use crate::broadphase::{Reused, speculative_margin};
use crate::scene::{Ground, Settings, rolling_arm};
use crate::timings::{PhaseClock, PhaseTimes};
use glam::{Quat, Vec3, Vec3A};
use parry3d::bounding_volume::Aabb;
use parry3d::query::ContactManifold;
use rayon::prelude::*;
use std::ops::Range;

/// Collision detection for the rest of the frame, `dt`.
///
/// Each bone's box is loosened by how far any of its points may travel, `(|v| + |ω| r)
/// dt + g dt²`, so the broad phase finds every pair that may meet. A pair's contacts are
/// then created within the distance it may close: its points approach at most
/// `|v_a − v_b| + |ω_a| r_a + |ω_b| r_b`, so limbs falling side by side make none
/// (a falling stack made a speculative point for every box it held).
///
/// `tree` is the broad phase of the frame's detections: the trees and candidate pairs
/// of its first detection, which the later ones reuse ([`Reused`]).
fn detect(w: &mut ParticleWorld, tree: &mut Reused, dt: f32) {
    let g = w.settings.gravity.length();
    let reach = speculative_margin(g, dt);
    // Per bone, on all threads (as its box, `broad_phase_on`).
    let (spins, margins): (Vec<f32>, Vec<f32>) = w
        .bones
        .par_iter()
        .with_min_len(BONES_PER_TASK)
        .map(|b| {
            let radius = w
                .kinds
                .of(b)
                .shape
                .get()
                .shape()
                .compute_local_aabb()
                .half_extents()
                .length();
            let spin = b.ang_vel.length() * radius;
            (spin, (b.lin_vel.length() + spin) * dt + reach)
        })
        .unzip();
    let mut pairs = std::mem::take(&mut w.pairs);
    let mut contacts = std::mem::take(&mut w.contacts);
    contacts.clear();
    let (bones, kinds) = (&w.bones[..], &w.kinds);
    let boxes = broad_phase_on(tree, (bones, kinds), &margins, &w.filter, &mut pairs);
    narrow_phase(
        &pairs,
        &mut w.manifolds,
        &mut contacts,
        |&(i, j), scratch, set| {
            let approach = (bones[i].lin_vel - bones[j].lin_vel).length() + spins[i] + spins[j];
            let prediction = approach * dt + 2.0 * reach;
            let (mi, mj) = (kinds.material(&bones[i]), kinds.material(&bones[j]));
            let mu = (mi.friction * mj.friction).sqrt();
            let e = mi.restitution.max(mj.restitution);
            let roll = rolling_arm(
                kinds.of(&bones[i]).shape.rolling_radius(),
                kinds.of(&bones[j]).shape.rolling_radius(),
            );
            let first = set.manifolds.len();
            shape_pair((bones, kinds), i, j, prediction, scratch, |pa, pb, n, _| {
                let point = ContactPoint::new(
                    bones[i].rot.inverse() * (pa - Vec3::from(bones[i].center())),
                    bones[j].rot.inverse() * (pb - Vec3::from(bones[j].center())),
                );
                set.push(first, (i, Some(j)), n, (mu, e, roll), point);
            });
        },
    );
    // The ground needs no broad phase: the bones whose boxes reach it, after the pairs.
    if let Some(ground) = &w.settings.ground {
        ground_contacts((bones, kinds), ground, &margins, &boxes, &mut contacts);
    }
    contacts.give_back_room();
    give_back_room(&mut pairs);
    w.contacts = contacts;
    w.pairs = pairs;
}

/// Each moving bone's contacts with the ground, `margins[i]` ahead, into `set`: the
/// bones whose loosened boxes `boxes` reach it (`reaches_ground`).
fn ground_contacts(
    (bones, kinds): (&[Bone], &BoneKinds),
    ground: &Ground,
    margins: &[f32],
    boxes: &[Aabb],
    set: &mut ContactSet,
) {
    let plane = ground_plane(ground);
    // On the pool, in bone order (rayon's collect keeps it): a test of every bone, four
    // times a frame, would otherwise be a serial part of a large pile's frame.
    let near: Vec<usize> = (0..bones.len())
        .into_par_iter()
        .with_min_len(BONES_PER_TASK)
        .filter(|&i| !bones[i].is_static() && reaches_ground(plane, &boxes[i]))
        .collect();
    narrow_phase(&near, &mut Vec::new(), set, |&i, scratch, set| {
        let b = &bones[i];
        let material = kinds.material(b);
        let mu = (material.friction * ground.friction).sqrt();
        let e = material.restitution.max(ground.restitution);
        let roll = rolling_arm(kinds.of(b).shape.rolling_radius(), 0.0);
        let first = set.manifolds.len();
        ground_pair(
            (bones, kinds),
            i,
            ground,
            margins[i],
            scratch,
            |pa, pb, n, _| {
                let point = ContactPoint::new(b.rot.inverse() * (pa - Vec3::from(b.center())), pb);
                set.push(first, (i, None), n, (mu, e, roll), point);
            },
        );
    });
}

/// The fewest pairs (or bones, for the ground) in a run of the parallel narrow phase,
/// and half the fewest for which it runs on the pool at all: a run must outweigh waking
/// a thread.
const NARROW_PHASE_MIN_RUN: usize = 64;

/// Room for a pair's or a bone's contacts that the serial narrow phase makes before
/// each, so that the kept set grows by an eighth at a time, not by doubling
/// ([`ContactSet::reserve_kept`]); a convex pair makes one manifold of a few points.
const KEPT_ROOM: usize = 16;

/// Runs of the parallel narrow phase per thread: a few, so that work stealing evens out
/// runs of unequal cost (as `islands`' batches), but not many: each run fills a contact
/// set of its own from empty, so a run costs more than its items, and hundreds of small
/// runs cost more than the second thread saves.
const NARROW_PHASE_RUNS_PER_THREAD: usize = 4;

/// The narrow phase: `collide(item, scratch, set)` appends each item's manifolds to a
/// contact set, item after item. On a pool of several threads, with enough items, runs
/// of consecutive items ([`NARROW_PHASE_RUNS_PER_THREAD`] per thread) are collided on
/// all threads into sets of their own, then appended to `out` in item order: each
/// pair's manifolds and points land where the serial loop puts them, so the contacts are
/// the same bits on any number of threads and whatever the runs (the points of a set
/// are renumbered by where it lands, `ContactSet::append`). Parry's manifold query is
/// stateless here (`scratch` only holds its output), so runs share nothing. Collision
/// detection runs four times a frame and was the largest serial part of a frame on two
/// threads.
fn narrow_phase<T: Sync>(
    items: &[T],
    scratch: &mut Vec<ContactManifold<(), ()>>,
    out: &mut ContactSet,
    collide: impl Fn(&T, &mut Vec<ContactManifold<(), ()>>, &mut ContactSet) + Sync,
) {
    let threads = rayon::current_num_threads();
    if threads == 1 || items.len() < 2 * NARROW_PHASE_MIN_RUN {
        for item in items {
            out.reserve_kept(KEPT_ROOM);
            collide(item, scratch, out);
        }
        return;
    }
    let run = items
        .len()
        .div_ceil(threads * NARROW_PHASE_RUNS_PER_THREAD)
        .max(NARROW_PHASE_MIN_RUN);
    let sets: Vec<ContactSet> = items
        .par_chunks(run)
        .map(|run| {
            let mut set = ContactSet::default();
            let mut scratch = Vec::new();
            for item in run {
                collide(item, &mut scratch, &mut set);
            }
            set
        })
        .collect();
    // Grown to the size needed, not doubled: the set is kept for reuse at its largest
    // size (a pile's landing), so doubling would hold up to twice its points for good.
    out.manifolds
        .reserve_exact(sets.iter().map(|s| s.manifolds.len()).sum());
    out.points
        .reserve_exact(sets.iter().map(|s| s.points.len()).sum());
    for set in &sets {
        out.append(set);
    }
}

/// Each bone's frame (origin, orientation) at the start of the frame, by bone: what
/// the frame's detections measure an old overlap's push-out allowance from
/// ([`overlaps_at_frame_start`]). Read only within the frame, so the step holds it
/// and a world between steps does not (32 B a bone).
fn frame_starts(w: &ParticleWorld) -> Vec<(Vec3, Quat)> {
    w.bones
        .par_iter()
        .with_min_len(BONES_PER_TASK)
        .map(|b| (Vec3::from(b.com), b.rot))
        .collect()
}

/// Each contact point's overlap where its bones stood as the frame began
/// (`ContactPoint::frame_overlap`, from the frame's `starts`, [`frame_starts`]): the
/// push-out allowance of an overlap is measured from there (`friction::normal_target`,
/// with the frame's substeps so far, [`PushOut`]).
fn overlaps_at_frame_start(w: &mut ParticleWorld, starts: &[(Vec3, Quat)]) {
    let at_start = |i: usize, local: Vec3| {
        let (com, rot) = starts[i];
        Vec3A::from(com) + rot * Vec3A::from(local)
    };
    let (manifolds, points) = (&w.contacts.manifolds, &mut w.contacts.points);
    for (m, run) in manifolds.iter().zip(ranges(manifolds, points.len())) {
        for c in &mut points[run] {
            let pb = match m.b() {
                Some(j) => at_start(j, c.rb),
                None => Vec3A::from(c.rb),
            };
            c.frame_overlap = (at_start(m.a(), c.ra) - pb).dot(m.n());
        }
    }
}

/// Wakes every sleeping figure a moving bone touches, before the substeps that would
/// otherwise meet it as a static wall: a shot hitting a resting box would stop dead
/// against it and the box, woken only at the end of the frame, would never feel the
/// hit. (The end of the frame would wake it anyway: contacts join sleep islands.)
/// Returns whether any bone woke.
fn wake_touched(w: &mut ParticleWorld) -> bool {
    // On all threads: each manifold reads two bones from anywhere in the array, which
    // is memory-bound on a large pile.
    let bones = &w.bones;
    let mut figures: Vec<u32> = w
        .contacts
        .manifolds
        .par_iter()
        .with_min_len(BONES_PER_TASK)
        .filter_map(|m| {
            let (a, b) = (&bones[m.a()], &bones[m.b()?]);
            if a.fixed || b.fixed || a.asleep == b.asleep {
                return None;
            }
            Some(if a.asleep { a.figure } else { b.figure })
        })
        .collect();
    if figures.is_empty() {
        return false;
    }
    figures.sort_unstable();
    figures.dedup();
    for b in w.bones.iter_mut() {
        if b.asleep && figures.binary_search(&b.figure).is_ok() {
            b.wake();
        }
    }
    true
}

/// Contacts, manifold by manifold: the normal corrections of its points as one block
/// ([`solve_normals`]), then each point's friction against the manifold's Coulomb cone
/// so far.
///
/// Up to [`SIDE_BY_SIDE`] consecutive manifolds with no bone in common are solved side
/// by side, friction point by point: none reads what another writes (the ground and other static
/// sides are never written), so each gets the same bits as in turn, but the processor
/// has independent chains of corrections to overlap (within a manifold every correction
/// waits for the last one's turn of the same bone). A pass is bound by its work more
/// than by that wait, so this gains little, but detection order already deals most
/// points into such groups, the layout for solving a group in SIMD lanes.
///
/// `push` is how far an old overlap may be pushed out in the substep and in the frame
/// so far ([`solve_normals`]).
///
/// Every pass reads every manifold, also one an earlier pass found apart: a resting
/// contact left a fraction of a millimetre apart is pressed again once a later pass's
/// joints have moved its bones.
fn contact_pass(
    bones: &mut [Bone],
    manifolds: &[Manifold],
    points: &mut [ContactPoint],
    push: PushOut,
) {
    let mut k = 0;
    while k < manifolds.len() {
        let mut end = k + 1;
        while end < manifolds.len()
            && end - k < SIDE_BY_SIDE
            && manifolds[k..end]
                .iter()
                .all(|m| share_no_bone(m, &manifolds[end]))
        {
            end += 1;
        }
        let group = &manifolds[k..end];
        let mut solves: [Option<ManifoldSolve>; SIDE_BY_SIDE] = Default::default();
        let group_points = group[0].start as usize..range(manifolds, end - 1, points.len()).end;
        let runs = point_runs(group, &mut points[group_points]);
        for ((slot, m), run) in solves.iter_mut().zip(group).zip(runs) {
            *slot = Some(ManifoldSolve::new(m, run));
        }
        for s in solves.iter_mut().flatten() {
            s.normals(bones, push);
        }
        let longest = (solves.iter().flatten())
            .map(|s| s.points.len())
            .max()
            .unwrap_or(0);
        for i in 0..longest {
            for s in solves.iter_mut().flatten() {
                s.friction(bones, i, push);
            }
        }
        k = end;
    }
}

/// Most manifolds [`contact_pass`] solves side by side.
const SIDE_BY_SIDE: usize = 4;

/// Whether two manifolds touch different bones (they may share the ground).
fn share_no_bone(m: &Manifold, n: &Manifold) -> bool {
    let bone = |s: Option<usize>, t: Option<usize>| s.is_some() && s == t;
    let (ma, na) = (Some(m.a()), Some(n.a()));
    !(ma == na || bone(ma, n.b()) || bone(m.b(), na) || bone(m.b(), n.b()))
}

/// One manifold's points in a contact pass, and the friction its cone has spent.
struct ManifoldSolve<'a> {
    m: &'a Manifold,
    points: &'a mut [ContactPoint],
    spent: f32,
    /// Each point's normal multiplier of this pass, when its normals were solved as a
    /// block ([`solve_normals`]); `None` for a manifold of more than [`BLOCK`] points,
    /// whose normals are solved in turn, each before its friction.
    ///
    /// After a block each point after the first is still topped up before its friction
    /// ([`solve_normal`]: nothing, unless it is deeper than the block left it). The
    /// earlier points' friction acts below the bone's centre, tilts it and presses the
    /// later points back in; topped up, the cone of each point's friction holds the
    /// normal load that actually carries the bone. Without it the block's friction
    /// spent half of what the points solved one at a time spent on the resting human
    /// (scene 8), and piles of humans crept for seconds: piles of 4, 8, 14 and 26 asleep
    /// at a mean of 5.30 s without, 2.60 s with. The first point has had no friction
    /// before it; topping it up too pushed a one-point manifold twice at its material
    /// point, which on a rolling ball has turned off the bottom between detections, and
    /// spun the capsule human's ball up without end (20 rad/s after 15 s).
    pushed: Option<[f32; BLOCK]>,
    /// The part of `pushed` the points after the next one to take friction took.
    later: f32,
    /// Whether the block moved nothing (no point pressed) and nothing has moved the
    /// manifold's bones since: then a point's top-up would read the depths the block
    /// read, none of which asked for a push, and is skipped as the no-op it is (the
    /// manifolds solved beside it share none of its bones). Most of a pile's manifolds
    /// are speculative ones no pass presses.
    still: bool,
}

impl<'a> ManifoldSolve<'a> {
    fn new(m: &'a Manifold, points: &'a mut [ContactPoint]) -> Self {
        let spent = points.iter().map(|c| c.lambda_tv).sum();
        ManifoldSolve {
            m,
            points,
            spent,
            pushed: None,
            later: 0.0,
            still: false,
        }
    }

    /// The normal corrections of all its points, as one block.
    #[inline(always)]
    fn normals(&mut self, bones: &mut [Bone], push: PushOut) {
        if self.points.len() <= BLOCK {
            let (pushed, moved) = solve_normals(bones, self.m, self.points, push);
            self.later = pushed.iter().sum();
            self.pushed = Some(pushed);
            self.still = !moved;
        }
    }

    /// Point `i`'s normal (solved, or topped up after the block) and its friction
    /// against the manifold's cone so far: the normal multipliers of the earlier passes
    /// and of this pass's points up to `i`. Shared so, a sliding
    /// face's kinetic friction is spread over its points as their normal loads are,
    /// where each point against the whole cone would leave it all to the first and
    /// turn the face about its normal (58° down a 35° slope in 2 s).
    #[inline(always)]
    fn friction(&mut self, bones: &mut [Bone], i: usize, push: PushOut) {
        if i >= self.points.len() {
            return;
        }
        // The point's material points when the top-up read them and moved nothing.
        let at = match &self.pushed {
            // After a block, a top-up of the points after the first: only what the
            // earlier points' friction pressed this point back in since (see
            // `ManifoldSolve::pushed`). The first has had no friction before it.
            Some(pushed) => {
                self.later -= pushed[i];
                if i > 0 && !self.still {
                    solve_normal(bones, self.m, &mut self.points[i], push)
                } else {
                    None
                }
            }
            None => solve_normal(bones, self.m, &mut self.points[i], push),
        };
        let normal: f32 = self.points.iter().map(|c| c.lambda_n).sum::<f32>() - self.later;
        if let Some(spent) =
            solve_friction(bones, self.m, &mut self.points[i], normal, self.spent, at)
        {
            self.spent += spent;
            self.still = false;
        }
    }
}

/// Collision detection runs this many times per frame (every few substeps): a limb
/// that turns within a frame brings a corner the frame-start manifold did not have.
const DETECTIONS_PER_FRAME: u32 = 4;

/// How much the first detection of a frame loosens the bones' boxes for the broad phase
/// of all of the frame's detections (m; see [`Reused`]): each later detection then only
/// looks up the few bones that moved out of their loosened box. Each box is already
/// loosened by how far the bone can move in the rest of the frame at its velocity; this
/// covers the velocity joints and contacts give it meanwhile. Measured on the
/// 1000-human pile (16 000 bones), on average over the later detections of its busiest
/// second: 955 boxes had left their box with no extra loosening, 417 with 5 mm, 189 with
/// 1 cm and 68 with 2 cm.
const DETECTION_FAT: f32 = 0.01;

/// Gauss–Seidel passes (contacts, then joints) per substep. An impact pushes a limb one
/// way and its joint pulls it back; a second pass halves the gap an impact leaves
/// (human, scene 8: 4.0 → 1.9 mm), and lets friction correct the slip the joints
/// brought, without which a resting figure creeps.
///
/// A figure that lands on a limb needs more: a shin on the ground with the knee at its
/// stop carries the torso, and each pass the ground's contact (its friction pinning the
/// foot, its normal lifting the shin) moves the light shin, and the knee, the hip and
/// the heavy torso behind them pull it back by nearly as much. What the passes leave of
/// that fight is a penetration the next substep pushes out as a velocity, or a turn of
/// the limb read as spin (a forearm under the chest spun up to 200 rad/s in one frame
/// with two passes). On the lab humanoid (`tests/doom3_mod.rs`), median (worst) over
/// the 72 starts of `examples/ensemble.rs` with 2 / 4 / 5 / 6 passes: energy gain 5.1
/// (32) / 1.2 (8.6) / 0.7 (7.0) / 1.5 (12) % of the energy scale, joint gap 8.3 (19) /
/// 5.5 (9.7) / 3.1 (7.2) / 3.8 (13) mm, penetration 13.7 (43) / 3.4 (12) / 2.7 (4.5) /
/// 2.3 (20) mm; the next 72 starts (`--from 24`) agree (2 passes 4.5 %, 8.6 mm,
/// 12.7 mm; 5 passes 0.95 %, 3.6 mm, 2.7 mm). Only the first pass aims the joints from
/// the substep's start (`Aim::of_pass`).
const PASSES: u32 = 5;

/// Passes of the contact velocity solve: one pass over a manifold leaves part of the
/// push-out velocity of the points solved first.
const VELOCITY_PASSES: u32 = 2;

/// Substeps per frame: the scene's substeps times its iterations, one constraint pass
/// each. Macklin et al. 2019 show that spending a fixed budget on substeps rather than
/// iterations converges faster and damps less; on the human (scene 8), 20 substeps × 1
/// pass leave a third of the joint gap and penetration of 4 substeps × 5 passes.
pub(crate) fn substeps(s: &crate::scene::Settings) -> u32 {
    (s.substeps.max(1) * s.iterations.max(1)).min(1000)
}

/// Runs the frame's substeps `subs` (counted from 0) of length `h` on a part.
pub(super) fn run_substeps(p: &mut Part, subs: Range<u32>, h: f32, s: &Settings) {
    // Each point's relative normal velocity before a substep's solve (m/s, > 0
    // approaching), by point, for restitution: measured on the manifolds that bounce at
    // all, and only held when some does. With `e = 0` the velocity pass's target is zero
    // whatever the approach (every shipped scene), and evaluating it (four rotations
    // and two cross products a point, most of a moving pile's points speculative ones
    // never pressed) would be wasted.
    let mut approach = if p.manifolds.iter().any(|m| m.e > 0.0) {
        vec![0.0; p.points.len()]
    } else {
        Vec::new()
    };
    substeps_with(p, subs, h, s, &mut approach);
}

/// [`run_substeps`] with its points' approach speeds held in `approach` (by point, or
/// empty when no manifold bounces). Out of line, the substeps' loop owns no array: with
/// the array a local of the loop's function, LLVM keeps the joint lanes' gather
/// (`SideLanes::gather`) and a block's levers (`BlockSide::new`) as calls that copy
/// their results out, 0.2 % more instructions in `pile_frames 30 1 60 --no-sleep --solver
/// rigid-frames` (callgrind).
#[inline(never)]
fn substeps_with(p: &mut Part, subs: Range<u32>, h: f32, s: &Settings, approach: &mut [f32]) {
    // How far an old overlap may be pushed out in a substep (`friction::solve_normals`).
    let push_out = s.max_push_out_speed * h;
    for sub in subs {
        // ... and in the frame up to and including this substep.
        let push = PushOut::at(push_out, sub + 1);
        // 1–2. integrate the particles (relative to the frame origin, see `Bone::dcom`)
        // and shape-match each moving bone to its rigid frame, in closed form.
        for b in p.bones.iter_mut() {
            b.prev_rot = b.rot;
            b.dturn = Quat::IDENTITY;
            b.dcom = Vec3A::ZERO;
        }
        advance_moving(p.bones, h, s.gravity);
        // A new substep for every contact point, and the approach of those that bounce.
        for (m, run) in p.manifolds.iter().zip(ranges(p.manifolds, p.points.len())) {
            for (i, c) in run.clone().zip(&mut p.points[run]) {
                if c.lambda_n == 0.0 {
                    // Not pressed in the last substep: a new run of touching ones may
                    // start here (`ContactPoint::touched_at`).
                    c.set_touched_at(None);
                }
                roll_contact(p.bones, p.kinds, m, c);
                c.lambda_n = 0.0;
                c.lambda_tv = 0.0;
                c.left_before = c.left;
                if m.e > 0.0 {
                    let pa = p.bones[m.a()].world(c.ra);
                    let pb = super::bone::side_world(p.bones, m.b(), c.rb);
                    let v = point_velocity(p.bones, Some(m.a()), pa)
                        - point_velocity(p.bones, m.b(), pb);
                    approach[i] = v.dot(m.n());
                }
            }
        }
        // 3. constraints: contacts then joints, `PASSES` times (the joints' anchors aimed
        // from the substep's start, then from its end: `Aim`)
        for pass in 0..PASSES {
            contact_pass(p.bones, p.manifolds, p.points, push);
            p.lockstep
                .solve(p.joints, p.bones, h, Aim::of_pass(pass, PASSES));
            if let Some(g) = p.grab {
                super::grab_improved(p.bones, p.kinds, g, h);
            }
        }
        // 4. velocities from the particles' displacements; the frame origin moves on
        for b in p.bones.iter_mut() {
            if b.is_static() {
                b.lin_vel = Vec3A::ZERO;
                b.ang_vel = Vec3A::ZERO;
                continue;
            }
            (b.lin_vel, b.ang_vel) = b.substep_velocity(h);
            b.com += b.dcom;
            b.dcom = Vec3A::ZERO;
        }
        // 5. velocity pass (contact points are relative to the updated frames), whose
        // normal impulses `λ_v` start from zero where the passes' friction `λ_t` was
        // (`ContactPoint::lambda_tv`)
        for c in p.points.iter_mut() {
            c.lambda_tv = 0.0;
        }
        for _ in 0..VELOCITY_PASSES {
            for (m, run) in p.manifolds.iter().zip(ranges(p.manifolds, p.points.len())) {
                let points = &mut p.points[run.clone()];
                let approach = approach.get(run).unwrap_or(&[]);
                solve_velocities(p.bones, m, points, approach, h, s.restitution_threshold);
            }
        }
        // Rolling resistance, on the substep's net normal impulses (`rolling`).
        super::rolling::solve(p.bones, p.manifolds, p.points, h);
        // Joint friction, the file's `friction` of each joint that has one.
        for &(_, k, a, b) in p.joints {
            if k.friction_torque > 0.0 {
                Joint::solve_friction(k, p.bones, a, b, h);
            }
        }
        for b in p.bones.iter_mut() {
            if b.is_static() {
                continue;
            }
            let air = p.kinds.material(b).air;
            b.lin_vel *= (1.0 - air.0 * h).max(0.0);
            b.ang_vel *= (1.0 - air.1 * h).max(0.0);
        }
    }
}

/// Moves a ground contact's point on a capsule to where its surface faces the ground
/// now, after the substep's advance: the point of its core segment nearest the old
/// point, out by the radius along the normal. A material point kept from the detection
/// has rolled off the bottom by `ω h` per substep by the time the passes push at it;
/// pushed up behind the centre, it spins the capsule on the way it rolls. Scene 9's
/// free obstacle rolled 11 % faster every second without end (0.71 to 1.51 m/s from 3 s
/// to 10 s); rolled to the bottom, it keeps its speed to 1e-4 over 5 s. The tangential jump is no
/// slip, so the touch offset moves with it (`friction::ANCHOR_PULL`). Ground contacts
/// only: between two bones the frame's normal is no one side's, and rolling both
/// points threw the capsule human at 19 m/s (1/20 s frames of 1000 substeps).
fn roll_contact(bones: &[Bone], kinds: &BoneKinds, m: &Manifold, c: &mut ContactPoint) {
    let start = |b: &Bone, local: Vec3| b.rot * Vec3A::from(local);
    let (n, mut jump) = (m.n(), Vec3A::ZERO);
    if m.b().is_none()
        && let Some(ra) = super::bone::rolled_point(&bones[m.a()], kinds, c.ra, n)
    {
        jump += start(&bones[m.a()], ra) - start(&bones[m.a()], c.ra);
        c.ra = ra;
    }
    if let Some(t) = c.touched_at() {
        c.set_touched_at(Some(t + Vec3::from(jump - n * jump.dot(n))));
    }
}

/// Most position passes over the joints of figures whose limits are still widened
/// ([`close_start_slack`]): a limit turns a bone about its centre and the anchor turns
/// it back, so the two meet by alternating passes (the door of the closed-form suite
/// takes a few dozen), and a gap left here would be closed by the substeps as a
/// velocity.
const SLACK_PASSES: u32 = 64;

/// The joint gap (m) at which [`close_start_slack`] stops passing over a figure.
const SLACK_GAP: f32 = 1e-6;

/// Brings the joints that started outside their limits a frame's step closer to them,
/// by position only.
///
/// Such a joint's limits are widened to the pose it started in (`Joint::slack`); each
/// frame narrows them at a bounded speed (`Joint::close_slack`) and moves its figure
/// onto the narrowed limits with [`SLACK_PASSES`] passes over the figure's joints
/// (anchors, axes and limits) until their anchors meet, folded into the frames as where
/// the bones are, not as a motion of a substep: no velocity comes of it. Held in one
/// substep instead, a door hinge 10° outside its range turned at 200 rad/s and gained
/// four times the scene's energy scale. It runs before the frame's start is recorded, so the energy metric's
/// velocities do not see it either. The joint pass holds the widened limits meanwhile.
fn close_start_slack(w: &mut ParticleWorld, h: f32) {
    let figures = w.close_slack_of_figures();
    if figures.is_empty() {
        return;
    }
    let in_figure = |bones: &[Bone], i: Option<usize>| in_figures(&figures, bones, i);
    for _ in 0..SLACK_PASSES {
        let mut gap = 0.0f32;
        for j in &w.joints {
            if in_figure(&w.bones, j.a().or(j.b())) {
                let k = w.joint_kinds.of(j);
                j.solve_between(k, &mut w.bones, j.a(), j.b(), h, Aim::End);
                gap = gap.max(j.gap(k, &w.bones));
            }
        }
        if gap <= SLACK_GAP {
            break;
        }
    }
    for b in &mut w.bones {
        b.com += b.dcom;
        b.dcom = Vec3A::ZERO;
        b.dturn = Quat::IDENTITY;
        b.prev_rot = b.rot;
    }
}

/// One frame of the improved solver.
///
/// Between two detections the contact set is fixed, so islands — bones linked by joints
/// and contacts, static bones only read — cannot touch each other and their substeps
/// run on all of rayon's threads (`islands`). A single thread steps the world in place.
pub(crate) fn step(w: &mut ParticleWorld) {
    // Phases as this solver runs them: detection (broad and narrow phase, a few times a
    // frame), substeps (joints, contacts, friction and integration interleave in each),
    // sleep.
    let mut times = PhaseTimes::default();
    let mut clock = PhaseClock::start();
    // A world at rest (every bone fixed or asleep; a grab wakes its bone when it is set)
    // has nothing to detect or solve: its substeps would leave every bone where it is.
    if w.grab.is_none() && w.bones.iter().all(|b| b.is_static()) {
        sleeping::advance_at_rest(&mut w.bones, w.settings.timestep);
        clock.lap(&mut times, "sleep");
        clock.finish(&mut times);
        w.phase_times = times;
        return;
    }
    let s = w.settings.clone();
    let dt = s.timestep;
    let n_sub = substeps(&s);
    let h = dt / n_sub as f32;
    close_start_slack(w, h);
    let starts = frame_starts(w);
    let every = n_sub.div_ceil(DETECTIONS_PER_FRAME);
    let threads = rayon::current_num_threads();
    // The broad phase's trees and candidate pairs, from the first detection's boxes
    // loosened by `DETECTION_FAT`, for all of the frame's detections.
    let mut tree = Reused::fattened(DETECTION_FAT);
    // The joint passes of the frame's last detection chunk, kept for the next one: the
    // world's, or each batch's with the batch itself (its islands seldom change within
    // a frame, and building a pass costs a walk over every joint).
    let (mut whole, mut kept) = (None, Vec::new());
    let mut sub = 0;
    while sub < n_sub {
        let rest_of_frame = dt * (n_sub - sub) as f32 / n_sub as f32;
        clock.skip();
        detect(w, &mut tree, rest_of_frame);
        if wake_touched(w) {
            // The woken figures' own contacts (with the ground, with each other) were
            // skipped while they slept, and so were their pairs in the broad phase.
            tree.forget();
            detect(w, &mut tree, rest_of_frame);
        }
        overlaps_at_frame_start(w, &starts);
        clock.lap(&mut times, "detection");
        let count = every.min(n_sub - sub);
        match islands::Plan::new(w, threads) {
            Some(plan) => {
                islands::run_substeps(w, &plan, sub..sub + count, h, &s, &mut kept, run_substeps)
            }
            None => {
                // The kept batches' copies of the bones stepped here are stale now.
                kept.clear();
                let joints = JointSet::All(&w.joints, &w.joint_kinds).entries();
                let lockstep = whole.get_or_insert_with(|| Lockstep::new(&joints, &w.bones));
                let mut part = Part {
                    bones: &mut w.bones,
                    kinds: &w.kinds,
                    manifolds: &w.contacts.manifolds,
                    points: &mut w.contacts.points,
                    joints: &joints,
                    lockstep,
                    grab: w.grab,
                };
                run_substeps(&mut part, sub..sub + count, h, &s);
            }
        }
        clock.lap(&mut times, "substeps");
        sub += count;
    }
    // The batches' copies of their bones, freed on all threads: one by one on the
    // stepping thread this would be a serial part of a large pile's frame.
    kept.into_par_iter().for_each(drop);
    let mut newly = Vec::new();
    let held = w.grab.and_then(|g| {
        w.bones
            .iter()
            .position(|b| b.body as usize == g.body.index())
    });
    sleeping::update(
        &mut w.bones,
        held,
        &w.links,
        &w.contacts.manifolds,
        &s.sleep,
        dt,
        w.time + dt as f64,
        &mut newly,
    );
    for &i in &newly {
        let b = &mut w.bones[i];
        b.lin_vel = Vec3A::ZERO;
        b.ang_vel = Vec3A::ZERO;
    }
    clock.lap(&mut times, "sleep");
    clock.finish(&mut times);
    w.phase_times = times;
}
