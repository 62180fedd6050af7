//! The step: Box2D v3's soft step (Catto, "Solver2D", 2024) in 3D.
//!
//! Once per step: collide (broad + narrow phase, contact anchors and masses fixed for
//! the step), find islands, wake what was touched. Then per substep of `h = dt/substeps`:
//!
//! 1. integrate velocities (gravity, air friction, gyroscopic term);
//! 2. warm start joints and contacts with last substep's impulses;
//! 3. solve with bias (soft constraints push errors out at `contact_hertz` /
//!    `joint_hertz`, damped by `damping_ratio`), `iterations` times;
//! 4. integrate positions;
//! 5. relax: solve again without bias, removing the velocity the position feedback
//!    added, so pushing out does not become bouncing.
//!
//! After the substeps, the restitution pass, the position projection ([`super::project`]:
//! what the soft constraints let give way is put back, positions only); then sleeping.

use super::body::{BodyInfo, BodyStates};
use super::contact::Contacts;
use super::integrate::{integrate_positions, integrate_velocities, update_inertia};
use super::island::Islands;
use super::joint_set::JointSet;
use super::project;
use super::soft::{Softness, StepContext};
use crate::scene::Settings;

/// Advances the world by `settings.timestep`.
#[allow(clippy::too_many_arguments)]
pub fn step(
    s: &mut BodyStates,
    info: &[BodyInfo],
    joints: &mut JointSet,
    contacts: &mut Contacts,
    islands: &mut Islands,
    awake: &mut [bool],
    dynamic: &[bool],
    settings: &Settings,
    time: f32,
) {
    let n = info.len();
    let dt = settings.timestep;
    refresh_awake(s, info, islands, awake, dynamic);
    update_inertia(s, info, awake);
    contacts.update(s, info, awake, dt);

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
        update_inertia(s, info, awake);
        contacts.update(s, info, awake, dt);
    }

    let substeps = settings.multibody_substep_count().max(1);
    let h = dt / substeps as f32;
    // Box2D caps contact stiffness at a quarter of the substep rate: stiffer is not
    // resolved by the integrator and only adds energy.
    let contact_hz = settings.contact_hertz.min(0.25 / h);
    let joint_hz = settings.joint_hertz.min(0.25 / h);
    let ctx = StepContext {
        h,
        inv_h: 1.0 / h,
        joint: Softness::new(joint_hz, settings.damping_ratio, h),
        contact: Softness::new(contact_hz, settings.damping_ratio, h),
        max_push_out: settings.max_push_out_speed,
    };
    contacts.prepare_masses(s, awake);
    let iterations = settings.iterations.max(1);
    for sub in 0..substeps {
        if sub > 0 {
            update_inertia(s, info, awake);
        }
        integrate_velocities(s, info, awake, settings.gravity, h);
        joints.prepare(s, awake);
        joints.warm_start(s, awake);
        contacts.warm_start(s, awake);
        for _ in 0..iterations {
            joints.solve(s, awake, &ctx, true);
            contacts.solve(s, awake, &ctx, true);
        }
        integrate_positions(s, info, awake, h);
        joints.solve(s, awake, &ctx, false);
        contacts.solve(s, awake, &ctx, false);
    }
    contacts.restitution(s, awake, settings.restitution_threshold);
    project::project_positions(s, joints, contacts, awake, &settings.sleep);

    if islands.update_sleep(s, dynamic, &settings.sleep, dt, time + dt) {
        refresh_awake(s, info, islands, awake, dynamic);
    }
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
        s.inv_mass[i] = if awake[i] { info[i].inv_mass } else { 0.0 };
    }
}
