//! Sleeping (improved solver): islands of bones linked by joints or touching contacts
//! go to sleep together once every bone has rested for `sleep.time` seconds, and wake
//! together
//! when any bone of the island moves — which includes an awake bone touching them, since
//! contacts join islands.
//!
//! A bone rests when it is below the sleep speeds (Doom 3's `suspendSpeed`) or when it
//! has not left a small box around where it was — `noMoveTranslation` and
//! `noMoveRotation` over `noMoveTime`, Doom 3's second test. The second catches a foot
//! trembling in place between a hard joint limit and the floor, whose speed alone never
//! settles under the threshold.

use super::bone::Bone;
use super::contacts::{BONES_PER_TASK, Manifold};
use super::joints::Link;
use crate::scene::SleepSettings;
use crate::union_find::UnionFind;
use glam::Vec3;
use rayon::prelude::*;

/// [`update`] for a world in which every bone is fixed or asleep and nothing is held:
/// every sleeping bone counts as slow and still, so its timers grow by `dt`, and its
/// island, unchanged since the last detection (none runs while everything sleeps) and
/// asleep with timers that only grow, stays asleep. The same bits as [`update`],
/// without its island search over every joint and contact, so a world at rest costs
/// a pass over its bones a frame.
pub(crate) fn advance_at_rest(bones: &mut [Bone], dt: f32) {
    for b in bones.iter_mut().filter(|b| !b.fixed) {
        b.sleep_time += dt;
        b.still_time += dt;
    }
}

/// Updates sleep timers and puts islands to sleep or wakes them. Returns the bones that
/// just fell asleep so the caller can zero their velocities. A `held` bone
/// (the mouse grab) never rests: the user is moving it, however slowly, so its island
/// stays awake until it is let go.
#[allow(clippy::too_many_arguments)]
pub(crate) fn update(
    bones: &mut [Bone],
    held: Option<usize>,
    links: &[Link],
    manifolds: &[Manifold],
    s: &SleepSettings,
    dt: f32,
    time: f64,
    newly_asleep: &mut Vec<usize>,
) {
    newly_asleep.clear();
    let n = bones.len();
    // Each bone's rest timers, on all threads (a turn angle each, for every bone: too
    // much to leave serial on a large pile).
    bones
        .par_iter_mut()
        .with_min_len(BONES_PER_TASK)
        .for_each(|b| {
            if b.fixed {
                return;
            }
            let slow = b.asleep
                || (b.lin_vel.length() < s.linear_velocity
                    && b.ang_vel.length() < s.angular_velocity);
            b.sleep_time = if slow { b.sleep_time + dt } else { 0.0 };
            let (p, q) = (b.still_at, b.still_turn);
            let turned = (b.rot * q.inverse()).to_axis_angle().1;
            let turned = turned.min(std::f32::consts::TAU - turned);
            if b.asleep
                || ((Vec3::from(b.center()) - p).length() <= s.translation && turned <= s.rotation)
            {
                b.still_time += dt;
            } else {
                b.still_at = Vec3::from(b.center());
                b.still_turn = b.rot;
                b.still_time = 0.0;
            }
        });
    if let Some(b) = held.and_then(|i| bones.get_mut(i)) {
        b.wake();
    }
    let mut sets = UnionFind::new(n);
    // Dense, for the links below, which ask it of bones all over the array.
    let is_dynamic: Vec<bool> = bones.iter().map(|b| !b.fixed).collect();
    let dynamic = |i: usize| is_dynamic[i];
    for l in links {
        if let (Some(a), Some(b)) = l.sides()
            && dynamic(a)
            && dynamic(b)
        {
            sets.union(a, b);
        }
    }
    for c in manifolds {
        if let Some(b) = c.b()
            && dynamic(c.a())
            && dynamic(b)
        {
            sets.union(c.a(), b);
        }
    }
    let mut min_time = vec![f32::INFINITY; n];
    for (i, b) in bones.iter().enumerate() {
        if !b.fixed {
            let r = sets.find(i);
            min_time[r] = min_time[r].min(b.sleep_time.max(b.still_time));
        }
    }
    let forced = s.max_move_time > 0.0 && time >= s.max_move_time as f64;
    let allowed = time >= s.min_move_time as f64;
    for (i, b) in bones.iter_mut().enumerate() {
        if b.fixed {
            continue;
        }
        let r = sets.find(i);
        let sleep = forced || (allowed && min_time[r] >= s.time);
        if sleep && !b.asleep {
            newly_asleep.push(i);
        }
        b.asleep = sleep;
        if !sleep {
            // A woken island starts its count again.
            if min_time[r] < s.time {
                b.sleep_time = b.sleep_time.min(min_time[r]);
                b.still_time = b.still_time.min(min_time[r]);
            }
        }
    }
}
