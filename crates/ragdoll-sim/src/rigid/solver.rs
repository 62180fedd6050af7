//! The step: Box2D v3's soft step (Catto, "Solver2D", 2024) in 3D.
//!
//! Once per step: collide (broad + narrow phase, contact anchors and masses fixed for
//! the step), find islands, wake what was touched. When touching bodies turn fast, the
//! substeps are split into windows, each starting with a detection of its own
//! ([`MAX_TURN_PER_DETECTION`]). Then per substep of `h = dt/substeps`:
//!
//! 1. integrate velocities (the gyroscopic term by an implicit midpoint rule, gravity,
//!    air friction);
//! 2. warm start joints and contacts with last substep's impulses;
//! 3. solve with bias (soft constraints push errors out at `contact_hertz` /
//!    `joint_hertz`, damped by `damping_ratio`), `iterations` times; the point rows of
//!    joint trees across a large mass ratio are solved exactly, after the other joint
//!    rows of each iteration ([`super::joint_tree`]);
//! 4. integrate positions, each body without a contact turned with its angular
//!    momentum held;
//! 5. relax: solve again without bias, removing the velocity the position feedback
//!    added, so pushing out does not become bouncing (joints in `relax_passes` passes).
//!
//! After the substeps, the restitution pass, the position projection ([`super::project`]:
//! what the soft constraints let give way is put back, positions only); then sleeping.
//!
//! The substeps, restitution and projection ([`substeps::solve`]) touch only an island's own
//! bodies, so islands are solved in batches of their own ([`super::parallel`]), on as
//! many threads as the rayon pool has, with the same bits as the whole world solved at
//! once.

use super::body::{BodyInfo, BodyStates, Motions};
use super::contact::Contacts;
use super::integrate::update_inertia;
use super::island::Islands;
use super::joint_set::JointSet;
use super::parallel::{self, IslandTasks};
use super::soft::{Softness, StepContext};
use super::substeps::{SolveBuffers, SolveParams};
use crate::broadphase::Reused;
use crate::scene::Settings;
use crate::timings::{PhaseClock, PhaseTimes};

/// Advances the world by `settings.timestep`.
#[allow(clippy::too_many_arguments)]
pub fn step(
    s: &mut BodyStates,
    info: &[BodyInfo],
    motion: Motions<'_>,
    joints: &mut JointSet,
    contacts: &mut Contacts,
    islands: &mut Islands,
    awake: &mut [bool],
    dynamic: &[bool],
    settings: &Settings,
    time: f32,
    buffers: &mut SolveBuffers,
    tasks: &mut IslandTasks,
    times: &mut PhaseTimes,
) {
    // Phases as this solver runs them: collision (broad and narrow phase), islands (links
    // and wakes), substeps (joints, contacts and integration interleave in each), sleep.
    let mut clock = PhaseClock::start();
    *times = PhaseTimes::default();
    let dt = settings.timestep;
    let g = settings.gravity.length();
    refresh_awake(s, info, islands, awake, dynamic);
    // A world at rest has nothing to do: nothing awake can touch a sleeping island to
    // wake it (a grab or a new body wakes what it needs before the step), every solver
    // pass skips sleeping bodies and the sleep update skips bodies already asleep. The
    // island links, the solver's passes over every joint and pair and the sleep update
    // would cost a few ms a frame for nothing on a resting pile of 1000 humans.
    if !awake.contains(&true) {
        // The solve's arrays are kept between busy steps; a world at rest gives them
        // back (a step waking it pays for growing them once).
        *buffers = SolveBuffers::default();
        *tasks = IslandTasks::default();
        joints.release_rows();
        contacts.release_trees();
        clock.finish(times);
        return;
    }
    update_inertia(s, motion, awake);
    clock.skip();
    let substeps = settings.multibody_substep_count().max(1);
    // The windows this step's speeds ask of the touching pairs the last step left: a
    // guess made before the detection, which only decides whether the broad phase keeps
    // its trees for a later window ([`DETECTION_FAT`]); no result depends on it.
    let guess = detection_windows(s, contacts, awake, info.len(), dt, substeps);
    let mut tree = if guess > 1 {
        Reused::fattened(DETECTION_FAT)
    } else {
        Reused::default()
    };
    contacts.update(s, info, awake, dt, g, &mut tree);
    clock.lap(times, "collision");
    link_islands(
        s, info, motion, joints, contacts, islands, awake, dynamic, dt, g, times, &mut clock,
        &mut tree,
    );

    let h = dt / substeps as f32;
    // Box2D caps contact stiffness at a quarter of the substep rate: stiffer is not
    // resolved by the integrator and only adds energy.
    let contact_hz = settings.contact_hertz.min(0.25 / h);
    let joint_hz = settings.joint_hertz.min(0.25 / h);
    let windows = detection_windows(s, contacts, awake, info.len(), dt, substeps);
    let params = SolveParams {
        ctx: StepContext {
            h,
            inv_h: 1.0 / h,
            joint: Softness::new(joint_hz, settings.damping_ratio, h),
            contact: Softness::new(contact_hz, settings.damping_ratio, h),
            max_push_out: settings.max_push_out_speed,
        },
        substeps: substeps / windows,
        iterations: settings.multibody_iteration_count().max(1),
        relax_passes: settings.relax_passes.max(1),
        gravity: settings.gravity,
        restitution_threshold: settings.restitution_threshold,
        sleep: &settings.sleep,
    };
    let window_dt = dt / windows as f32;
    for window in 0..windows {
        if window > 0 {
            // A fresh detection on the poses the last window reached, for the features
            // that have turned towards each other since.
            update_inertia(s, motion, awake);
            clock.lap(times, "substeps");
            contacts.update(s, info, awake, window_dt, g, &mut tree);
            clock.lap(times, "collision");
            link_islands(
                s, info, motion, joints, contacts, islands, awake, dynamic, window_dt, g, times,
                &mut clock, &mut tree,
            );
        }
        // Islands share no moving body, so they can be solved in any order, or at once:
        // in batches of their own, or a small world in place, with the same bits
        // ([`parallel`]).
        parallel::solve_islands(
            s,
            motion,
            joints,
            &mut contacts.pairs,
            islands,
            awake,
            buffers,
            tasks,
            &params,
        );
    }
    clock.lap(times, "substeps");

    if islands.update_sleep(s, dynamic, &settings.sleep, dt, time + dt) {
        refresh_awake(s, info, islands, awake, dynamic);
    }
    clock.lap(times, "sleep");
    clock.finish(times);
}

/// `awake` and the solver inverse masses from the sleep flags: sleeping bodies act as
/// static until woken.
pub fn refresh_awake(
    s: &mut BodyStates,
    info: &[BodyInfo],
    islands: &Islands,
    awake: &mut [bool],
    dynamic: &[bool],
) {
    for i in 0..info.len() {
        awake[i] = dynamic[i] && !islands.asleep[i];
        s.inv_mass[i] = if awake[i] { info[i].inv_mass() } else { 0.0 };
    }
}

/// Largest turn (rad) two touching bodies may make relative to each other between two
/// detections. A contact's points, normal and anchors are those of the detection; a
/// pair that turns fast brings other features together (a spinning fist's edges, pivoting
/// about the corner its contact holds, pass the anchors and enter the head), which the
/// rows cannot see. Jolt and Box2D detect once per step and rely on the turn per step
/// being small; a ragdoll's hand whipping at 30–40 rad/s turns half a radian in a 60 Hz
/// frame.
///
/// Measured on scene 8 (the human), whose right fist whips to 24–40 rad/s at the end of
/// its arm while the head turns at 22 rad/s: with one detection per frame the pair's
/// only close point (an edge–edge one) held while the fist pivoted about it, and its
/// faces went 20 mm into the head by the frame's end (its tracked separation stayed at
/// +0.3 mm); split into 4 windows the deepest overlap in the scene is 4.4 mm (3.0 mm at 0.1
/// rad; at 0.2 rad the landing took another path, with one frame of a 2.4 mm joint gap,
/// the landing being chaotic).
const MAX_TURN_PER_DETECTION: f32 = 0.3;

/// How far the broad phase's trees are loosened (m) in a step that detects in several
/// windows, so that the later windows' detections reuse the first one's trees and
/// candidate pairs ([`Reused`], with the same pairs as new trees).
///
/// The first detection loosens each box by how far the body may move over the whole
/// step, a later window's by how far it may move over that window from the pose the
/// earlier windows reached: a later box lies inside the first one unless the solve
/// sped its body up, so a little fat keeps all but a few boxes inside their fat boxes
/// and a later window's broad phase is a filter of the candidates and a few queries
/// instead of new trees. A step with one window builds its trees without fat, which
/// would only add candidates.
const DETECTION_FAT: f32 = 0.01;

/// Into how many windows the step's substeps are split, each starting with its own
/// detection: enough that every touching pair with an awake body turns, at the step's
/// start speeds, at most [`MAX_TURN_PER_DETECTION`] relative to its partner per window
/// (`(|ω_a| + |ω_b|) dt / windows`); a divisor of `substeps`, so every window has the
/// same substeps and the same substep length. One when nothing turns fast.
fn detection_windows(
    s: &BodyStates,
    contacts: &Contacts,
    awake: &[bool],
    n: usize,
    dt: f32,
    substeps: u32,
) -> u32 {
    let spin = |i: usize| if i < n { s.ang_vel[i].length() } else { 0.0 };
    let turn = contacts
        .pairs
        .iter()
        .filter(|p| p.touching() && (awake[p.a as usize] || awake[p.b as usize]))
        .map(|p| (spin(p.a as usize) + spin(p.b as usize)) * dt)
        .fold(0.0f32, f32::max);
    let needed = (turn / MAX_TURN_PER_DETECTION).ceil().max(1.0) as u32;
    (needed..=substeps)
        .find(|w| substeps.is_multiple_of(*w))
        .unwrap_or(substeps)
}

/// Islands from joints and touching contacts between dynamic bodies; a link from an
/// awake body to a sleeping one wakes the sleeping island (and the contacts are detected
/// again for the bodies woken).
#[allow(clippy::too_many_arguments)]
fn link_islands(
    s: &mut BodyStates,
    info: &[BodyInfo],
    motion: Motions<'_>,
    joints: &JointSet,
    contacts: &mut Contacts,
    islands: &mut Islands,
    awake: &mut [bool],
    dynamic: &[bool],
    dt: f32,
    g: f32,
    times: &mut PhaseTimes,
    clock: &mut PhaseClock,
    tree: &mut Reused,
) {
    let n = info.len();
    islands.reset_links();
    let link = |a: usize, b: usize, islands: &mut Islands| {
        if a < n && b < n && dynamic[a] && dynamic[b] {
            islands.link(a, b);
        }
    };
    joints.for_each_pair(|a, b| link(a, b, islands));
    for p in &contacts.pairs {
        if p.touching() {
            link(p.a as usize, p.b as usize, islands);
        }
    }
    // Only a dynamic body at rest can be woken: when there is none, as in a pile's busy
    // frames, the pairs are not walked again.
    if (0..n).any(|i| dynamic[i] && !awake[i]) {
        for p in &contacts.pairs {
            let (a, b) = (p.a as usize, p.b as usize);
            if p.touching() && b < n && (awake[a] != awake[b]) && dynamic[a] && dynamic[b] {
                islands.request_wake(if awake[a] { b } else { a });
            }
        }
    }
    if islands.apply_wakes() {
        refresh_awake(s, info, islands, awake, dynamic);
        update_inertia(s, motion, awake);
        clock.lap(times, "islands");
        tree.forget();
        contacts.update(s, info, awake, dt, g, tree);
        clock.lap(times, "collision");
    }
    clock.lap(times, "islands");
}
