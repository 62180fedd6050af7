//! One frame of the XPBD particle solver.
//!
//! Per frame, [`DETECTIONS_PER_FRAME`] collision detections or one per
//! [`DETECTION_SPAN`], whichever is more (`contacts::detect`); per
//! substep `h` ([`substep_count`] a frame: Macklin et al. 2019):
//! 1. predict every awake particle: `x_prev = x`, `v += g h`, `x += v h`;
//! 2. read each bone's frame from its particles (`frame::read`);
//! 3. [`Settings::xpbd_passes`] passes (by default [`PASSES`]) of: each contact
//!    manifold's normal pushes as one block (`contact_block`), then its friction on barycentric weights (`contacts::solve`);
//!    each joint's point, angular parts and violated limits as one block, moving each
//!    bone's particles along the gradients at the substep's start (`joint_block`; a
//!    slider's and a spring's parts one by one, `joints::solve_angular`,
//!    `joints::solve_point`); and, last, each bone's six sticks, solved exactly by
//!    their SHAKE projection (`shape_match`), momentum kept. The joints come after
//!    the contacts ([`PASSES`] says why);
//! 4. the grab, a soft point, and the projection again if it pulled;
//! 5. velocities from the displacements, `v = (x − x_prev)/h`, projected onto the
//!    rigid ones (the sticks at the velocity level, RATTLE), the scene's air friction
//!    (linear on the bone's mean velocity, angular on the rest), and the joints'
//!    friction, a capped angular impulse keeping linear momentum (`friction`);
//! 6. [`VELOCITY_PASSES`] passes of the contacts' velocity step (restitution, no
//!    push-out kept as velocity, and the friction the position step's cone left
//!    unused), impulses on the bones' rigid velocities (`contacts::solve_velocities`),
//!    then each manifold's rolling resistance.
//!
//! Each substep ends by reading the frames from the particles (drawing, metrics, the
//! next detection, the next substep's start); the frame ends by updating the sleep
//! islands. Every step is a projection or a dissipative velocity change;
//! the only source, the push-out of a penetration, is cancelled by step 6.

use super::super::ParticleWorld;
use super::super::bone::Bone;
use super::super::joints::in_figures;
use super::super::rigid_frames::substeps;
use super::joints::{Anchor, pull, solve_angular, solve_point};
use super::particles::PER_BONE;
use super::{
    XpbdState, contact_block, contacts, frame, friction, joint_block, shape_match, sleeping,
};
use crate::broadphase::Reused;
use crate::method::Grab;
use crate::scene::Settings;

/// Gauss–Seidel passes per substep over the joints, the contacts and the sticks'
/// projection by default ([`Settings::xpbd_passes`]). Each joint's point, angular parts and violated limits are one block
/// (`joint_block`), each manifold's normal pushes one block (`contact_block`), both
/// moving the bones as rigid bodies would, which the projection then keeps; what the
/// passes still resolve is the coupling between joints and manifolds. Solved part by
/// part, a joint's angle turned its bone about its centre and its point turned it back
/// (a pendulum kept only `(1/m) / (1/m + r²/I)` of each correction, 1/600 for the
/// closed forms' pendulum), and the first corner of a face took a manifold's whole push:
/// 16 passes were needed, with 8 a door started 10° outside its limit gained 73 % of
/// its energy scale coming back and a cube hitting a wall at 50 m/s spun at 2.8 rad/s.
/// With the blocks and 8 passes: the door 0.000 %, the cube 0.000 rad/s, the
/// pendulums lose 0.13 %, every scene within its thresholds (human: penetration
/// 0.5 mm, joint gap 3.7 mm, asleep at 2.6 s); with 6 the capsule human gains 2.7 %
/// of its energy scale (bound 2 %).
///
/// The same budget spent as more substeps of fewer passes (Macklin et al. 2019) pays
/// a substep's own work (the prediction, the frame reads, the velocities and their
/// [`VELOCITY_PASSES`]) more often and loses quality first: 40 substeps of two or of
/// three passes, or 20 of four, leave the capsule human gaining 3.6 %, 3.0 % and 3.5 %
/// of its energy scale; 60 substeps of one pass hold scenes 1–9 and the closed forms,
/// but the lab humanoid gains 1.0 % from every start (with these eight passes 0.03 %
/// at the median of 72) and the human falls asleep at 8.6 s instead of 3.4 s. The
/// sticks' projection in the last pass alone leaves the capsule human awake at 10 s.
/// `docs/benchmarks.md` gives what each costs.
///
/// The lab humanoid's gain at one pass comes from its landing: with one pass the
/// joints, solved after the contacts, press the bone that lands first back into the
/// ground in every substep, so each substep starts with that contact about 4 mm deep
/// and pushes it out by `max_push_out_speed · h`, a normal impulse of 2.4 kg·m/s a
/// substep where eight passes need 0.03. The joints carry most of that push into the
/// rest of the figure; step 6 takes the push-out back only from the contact's own bone,
/// as a free rigid body, so the rest keeps it: up to 1.8 J a substep from the positions'
/// velocities, 0.9 J taken back: 18 J over 28 substeps, 6.6 J (1.0 % of its energy
/// scale) between the frames the metric samples (`examples/energy_trace.rs` prints
/// them).
///
/// In each pass the contacts come first and the joints after them, so that what the
/// passes leave unresolved of a joint loaded against the ground stays in the contacts.
/// There it is an overlap, pushed out at no more than the push-out speed, and step 6
/// takes back the velocity of that push. Left in a joint or a limit instead, the excess
/// at the substep's end is closed by the next substep at once, at `excess / h`, and
/// becomes velocity: landing from some heights, the lab humanoid's waist, hip and knee
/// held their limits 0.2°–0.55° open for twenty substeps, a spring that gave back
/// 55 J (8.4 % of its energy scale) when it let go.
pub(crate) const PASSES: u32 = 8;

/// Symmetric Gauss–Seidel passes of the contacts' velocity step (6). The corners of a
/// face share their bone; with four, two cubes pushed out of each other at 3 m/s move
/// apart at 0.013 m/s while they overlap, and stop once they are out.
pub(crate) const VELOCITY_PASSES: u32 = 4;

/// Collision detections per frame at least: each covers the substeps until the next.
pub(crate) const DETECTIONS_PER_FRAME: u32 = 4;

/// The longest time one detection covers (s): more detections a frame where the
/// timestep is longer than [`DETECTIONS_PER_FRAME`] of these. A contact's points stay
/// fixed in their bones and its normal in the world until the next detection, so two
/// bones turning against each other drift from the pair parry found: their points'
/// separation along the old normal is no longer the shapes' distance, and the
/// contact pushes at a penetration that is not there. Over 25 ms (4 detections of a
/// 1/10 s frame) the human's thighs, held together at the hip, were pushed apart
/// against their joints and the figure gained 1500 J landing, a foot at 17.9 m/s; with
/// spans of 1/240 s, the default frame's, it lands without gain, at most 5.9 m/s.
pub(crate) const DETECTION_SPAN: f32 = 1.0 / 240.0;

/// How much the first detection of a frame loosens the bones' boxes for the broad
/// phase of all of the frame's detections (m, see `Reused`): each box is already
/// loosened by how far its bone can move until the next detection; a later detection
/// looks up again only the bones that left their loosened box. The pairs are the
/// same whatever it is.
const DETECTION_FAT: f32 = 0.01;

/// Most position-only passes that move a figure onto its narrowed limits
/// ([`close_start_slack`]); they stop earlier once every joint of the figures
/// with slack has its anchors within [`SLACK_GAP`].
const SLACK_PASSES: u32 = 64;

/// Joint gap (m) at which [`close_start_slack`]'s passes stop.
const SLACK_GAP: f64 = 1e-6;

/// A pose that starts outside a joint's limits (an id figure's `af_pose`, a knee a
/// few degrees past its range) has its limits widened by the excess (`Joint::slack`);
/// each frame narrows them by what `max_push_out_speed` allows
/// (`Joint::close_slack`: body1's centre turning about the anchor at that speed,
/// `Δslack = v_push Δt / max(r, 5 cm)`), and moves the figure onto the narrowed
/// limits by position only: the particles start each pass rigid at `x_prev = x`,
/// so the joint blocks' levers are the current ones, and the passes of joint blocks
/// and stick projections move `x` without touching `v`. The next substep takes its
/// `x_prev` from there, so no velocity comes of it, as in the rigid-frames solver
/// (`rigid_frames::close_start_slack`). Held at once instead, the lab humanoid's
/// left knee, 4° past its range, came back in the first substep (`Δθ/h` ≈ 300
/// rad/s): after one frame the lower leg moved at 4.5 m/s and 24 rad/s and the
/// figure had gained 88 J, 13 % of its energy scale.
/// What stays fixed through a substep, once `x_prev` and the bones' `prev_rot` are its
/// start: each moving bone's start ([`fix_start`](super::particles::Particles::fix_start)) and the joint blocks'
/// levers and factored rows ([`joint_block::begin_substep`]).
fn begin_substep(w: &ParticleWorld, st: &mut XpbdState) {
    let p = &mut st.particles;
    p.fix_start(&w.bones);
    joint_block::begin_substep(
        p,
        &w.bones,
        (&w.joints, &w.joint_kinds),
        &st.anchors,
        &mut st.joint_start,
        &mut st.limit_lambda,
    );
}

fn close_start_slack(w: &mut ParticleWorld, st: &mut XpbdState, h: f32) {
    let figures = w.close_slack_of_figures();
    if figures.is_empty() {
        return;
    }
    let in_figure = |bones: &[Bone], i: Option<usize>| in_figures(&figures, bones, i);
    for _ in 0..SLACK_PASSES {
        let p = &mut st.particles;
        p.x_prev.copy_from_slice(&p.x);
        for b in w.bones.iter_mut() {
            b.prev_rot = b.rot;
        }
        begin_substep(w, st);
        for ((j, ends), start) in w.joints.iter().zip(&st.anchors).zip(&st.joint_start) {
            if !in_figure(&w.bones, j.a().or(j.b())) {
                continue;
            }
            let joint = (j, w.joint_kinds.of(j));
            if joint_block::blocks(joint.1) {
                let (p, lambda) = (&mut st.particles, &mut st.limit_lambda);
                joint_block::solve(p, &mut w.bones, joint, ends, start, lambda, h);
            } else {
                solve_angular(&mut st.particles, &mut w.bones, joint, h);
                solve_point(&mut st.particles, &mut w.bones, joint, ends, h);
            }
        }
        shape_match::project(&mut st.particles, &mut w.bones);
        read_frames(w, st);
        let gap = w
            .joints
            .iter()
            .zip(&st.anchors)
            .filter(|(j, _)| in_figure(&w.bones, j.a().or(j.b())))
            .map(|(_, [a, b])| a.point64(&st.particles).distance(b.point64(&st.particles)))
            .fold(0.0, f64::max);
        if gap <= SLACK_GAP {
            break;
        }
    }
}

/// Substeps per frame: [`Settings::xpbd_substeps`], or the scene's substeps ×
/// iterations.
pub(crate) fn substep_count(s: &Settings) -> u32 {
    s.xpbd_substeps.unwrap_or_else(|| substeps(s))
}

/// Reads every moving bone's frame from its particles.
fn read_frames(w: &mut ParticleWorld, st: &XpbdState) {
    for (i, b) in w.bones.iter_mut().enumerate() {
        if st.particles.moves(i) {
            frame::read(b, &w.kinds.placement(b).rest, &st.particles.bone64(i));
        }
    }
}

/// The grab: a soft point between the grabbed point and the target, a 5 Hz spring on
/// the bone's own mass (`k = m ω²`, compliance `1/k`), as the other particle solvers.
fn grab(w: &ParticleWorld, st: &mut XpbdState, g: Grab, h: f32) {
    let Some(i) = w
        .bones
        .iter()
        .position(|b| b.body as usize == g.body.index())
    else {
        return;
    };
    let b = &w.bones[i];
    let placement = w.kinds.placement(b);
    let local = placement.shape_in_bone.transform_point(g.local_point);
    let a = Anchor::Bone(i as u32, frame::weights(&placement.rest, local));
    let omega = std::f32::consts::TAU * 5.0;
    let compliance = 1.0 / (b.mass.max(1e-3) * omega * omega);
    let d = (g.target.as_dvec3() - a.point64(&st.particles)).as_vec3();
    pull(
        &mut st.particles,
        &a,
        &Anchor::World(g.target),
        d,
        compliance / (h * h),
    );
}

/// One frame (module doc).
pub(crate) fn step(w: &mut ParticleWorld, st: &mut XpbdState) {
    let dt = w.settings.timestep;
    let held = w.grab.and_then(|g| {
        w.bones
            .iter()
            .position(|b| b.body as usize == g.body.index())
    });
    if held.is_none() && w.bones.iter().all(|b| b.is_static()) {
        // Nothing moves: the timers only grow, every island stays asleep.
        return;
    }
    // Bones woken from outside (a grab) take corrections again.
    for (i, b) in w.bones.iter().enumerate() {
        if !b.is_static() && !st.particles.moves(i) {
            st.particles.set_asleep(i, false);
        }
    }
    let n = substep_count(&w.settings);
    let h = dt / n as f32;
    let g = w.settings.gravity;
    close_start_slack(w, st, h);
    // Less a thousandth: 1/60 s is 4 spans of 1/240 s, not 4.0000002 in f32.
    let detections = DETECTIONS_PER_FRAME.max((dt / DETECTION_SPAN - 1e-3).ceil() as u32);
    let every = n.div_ceil(detections);
    // The broad phase's trees from the first detection's boxes loosened by
    // `DETECTION_FAT`, for all of the frame's detections.
    let mut tree = Reused::fattened(DETECTION_FAT);
    for sub in 0..n {
        if sub % every == 0 {
            read_frames(w, st);
            let span = h * every.min(n - sub) as f32;
            contacts::detect(
                &mut tree,
                &st.particles,
                (&w.bones, &w.kinds),
                &w.filter,
                &w.settings,
                span,
                &mut st.scratch,
                &mut st.contacts,
            );
        }
        contacts::begin_substep(
            &mut st.contacts,
            &st.particles,
            (&w.bones, &w.kinds),
            w.settings.max_push_out_speed,
            h,
        );
        // The frames at the substep's start, where the particles are rigid: the
        // gradients of the joints' points are taken there (`joints::pull_rigid`).
        for b in w.bones.iter_mut() {
            b.prev_rot = b.rot;
        }
        let p = &mut st.particles;
        for k in 0..p.len() {
            p.x_prev[k] = p.x[k];
            if p.w[k] > 0.0 {
                p.v[k] += g * h;
                p.x[k] += p.v[k].as_dvec3() * h as f64;
            }
        }
        begin_substep(w, st);
        contact_block::begin_substep(&st.contacts, &mut st.scratch.work, &st.particles, &w.bones);
        read_frames(w, st);
        for pass in 0..w.settings.xpbd_passes {
            contacts::solve(
                &mut st.contacts,
                &st.scratch.work,
                &mut st.particles,
                &mut w.bones,
                pass % 2 == 1,
            );
            for ((j, ends), start) in w.joints.iter().zip(&st.anchors).zip(&st.joint_start) {
                let joint = (j, w.joint_kinds.of(j));
                if joint_block::blocks(joint.1) {
                    let (p, lambda) = (&mut st.particles, &mut st.limit_lambda);
                    joint_block::solve(p, &mut w.bones, joint, ends, start, lambda, h);
                } else {
                    solve_angular(&mut st.particles, &mut w.bones, joint, h);
                    solve_point(&mut st.particles, &mut w.bones, joint, ends, h);
                }
            }
            shape_match::project(&mut st.particles, &mut w.bones);
        }
        if let Some(gr) = w.grab {
            grab(w, st, gr, h);
        }
        if w.grab.is_some() {
            shape_match::project(&mut st.particles, &mut w.bones);
        }
        // The frames the projection composed, read once from the particles: the next
        // substep's start (`prev_rot`) is then the particles' own frame.
        read_frames(w, st);
        update_velocities(w, st, h);
        contacts::solve_velocities(
            &st.contacts,
            &mut st.particles,
            &mut st.scratch,
            w.settings.restitution_threshold,
            h,
            VELOCITY_PASSES,
        );
    }
    sleeping::update(
        &mut st.particles,
        &mut w.bones,
        &mut st.rest,
        &w.links,
        &st.contacts,
        held,
        &w.settings.sleep,
        dt,
        w.time + dt as f64,
    );
}

/// Step 5: `v = (x − x_prev)/h` (as below), then air friction, then joint friction.
fn update_velocities(w: &ParticleWorld, st: &mut XpbdState, h: f32) {
    let p = &mut st.particles;
    let inv_h = 1.0 / h as f64;
    for (i, b) in w.bones.iter().enumerate() {
        let f = PER_BONE * i;
        if p.w[f] == 0.0 {
            continue;
        }
        // `v = (x − x_prev)/h` in f64: free motion, `x = x_prev + v h`, gives back its
        // velocity to f32's last bit.
        for k in f..f + PER_BONE {
            p.v[k] = ((p.x[k] - p.x_prev[k]) * inv_h).as_vec3();
        }
        shape_match::project_velocities(p, i);
        let (lin, ang) = w.kinds.material(b).air;
        if lin > 0.0 || ang > 0.0 {
            let c = (p.v[f] + p.v[f + 1] + p.v[f + 2] + p.v[f + 3]) * 0.25;
            let (sl, sa) = ((1.0 - lin * h).max(0.0), (1.0 - ang * h).max(0.0));
            for k in f..f + PER_BONE {
                p.v[k] = c * sl + (p.v[k] - c) * sa;
            }
        }
    }
    friction::solve(p, &w.joints, &w.joint_kinds, h);
}
