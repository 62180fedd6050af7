//! The step: Box2D v3's soft step (Catto, "Solver2D", 2024) in 3D.
//!
//! Once per step: collide (broad + narrow phase, contact anchors and masses fixed for
//! the step), find islands, wake what was touched. Then per substep of `h = dt/substeps`:
//!
//! 1. integrate velocities (gravity, air friction, gyroscopic term);
//! 2. warm start joints and contacts with last substep's impulses;
//! 3. solve with bias (soft constraints push errors out at `contact_hertz` /
//!    `joint_hertz`, damped by `damping_ratio`), `iterations` times; the point rows of
//!    joint trees across a large mass ratio are solved exactly, after the other joint
//!    rows of each iteration ([`super::joint_tree`]);
//! 4. integrate positions;
//! 5. relax: solve again without bias, removing the velocity the position feedback
//!    added, so pushing out does not become bouncing (joints in
//!    `substeps::RELAX_JOINT_PASSES` passes).
//!
//! After the substeps, the restitution pass, the position projection ([`super::project`]:
//! what the soft constraints let give way is put back, positions only); then sleeping.
//!
//! The substeps, restitution and projection ([`substeps::solve`]) touch only an island's own
//! bodies, so on a rayon pool of several threads each island is solved on its own
//! ([`super::parallel`]), with the same bits as on one.

use super::body::{BodyInfo, BodyStates, Motions};
use super::contact::Contacts;
use super::integrate::update_inertia;
use super::island::Islands;
use super::joint_set::JointSet;
use super::parallel;
use super::soft::{Softness, StepContext};
use super::substeps::{self, SolveParams};
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
    times: &mut PhaseTimes,
) {
    // Phases as this solver runs them: collision (broad and narrow phase), islands (links
    // and wakes), substeps (joints, contacts and integration interleave in each), sleep.
    let mut clock = PhaseClock::start();
    *times = PhaseTimes::default();
    let n = info.len();
    let dt = settings.timestep;
    let g = settings.gravity.length();
    refresh_awake(s, info, islands, awake, dynamic);
    // A world at rest has nothing to do: nothing awake can touch a sleeping island to
    // wake it (a grab or a new body wakes what it needs before the step), every solver
    // pass skips sleeping bodies and the sleep update skips bodies already asleep. The
    // island links, the solver's passes over every joint and pair and the sleep update
    // would cost a few ms a frame for nothing on a resting pile of 1000 humans.
    if !awake.contains(&true) {
        clock.finish(times);
        return;
    }
    update_inertia(s, motion, awake);
    clock.skip();
    contacts.update(s, info, awake, dt, g);
    clock.lap(times, "collision");

    // Islands from joints and touching contacts between dynamic bodies; a link from an
    // awake body to a sleeping one wakes the sleeping island.
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
    for p in &contacts.pairs {
        let (a, b) = (p.a as usize, p.b as usize);
        if p.touching() && b < n && (awake[a] != awake[b]) && dynamic[a] && dynamic[b] {
            islands.request_wake(if awake[a] { b } else { a });
        }
    }
    if islands.apply_wakes() {
        refresh_awake(s, info, islands, awake, dynamic);
        update_inertia(s, motion, awake);
        clock.lap(times, "islands");
        contacts.update(s, info, awake, dt, g);
        clock.lap(times, "collision");
    }
    clock.lap(times, "islands");

    let substeps = settings.multibody_substep_count().max(1);
    let h = dt / substeps as f32;
    // Box2D caps contact stiffness at a quarter of the substep rate: stiffer is not
    // resolved by the integrator and only adds energy.
    let contact_hz = settings.contact_hertz.min(0.25 / h);
    let joint_hz = settings.joint_hertz.min(0.25 / h);
    let params = SolveParams {
        ctx: StepContext {
            h,
            inv_h: 1.0 / h,
            joint: Softness::new(joint_hz, settings.damping_ratio, h),
            contact: Softness::new(contact_hz, settings.damping_ratio, h),
            max_push_out: settings.max_push_out_speed,
        },
        substeps,
        iterations: settings.iterations.max(1),
        gravity: settings.gravity,
        restitution_threshold: settings.restitution_threshold,
        sleep: &settings.sleep,
    };
    // Islands share no moving body, so they can be solved in any order, or at once; on
    // one thread the whole world is solved in place, which gives the same bits.
    if rayon::current_num_threads() > 1 {
        parallel::solve_islands(
            s,
            motion,
            joints,
            &mut contacts.pairs,
            islands,
            awake,
            &params,
        );
    } else {
        substeps::solve(s, motion, joints, &mut contacts.pairs, awake, &params);
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
