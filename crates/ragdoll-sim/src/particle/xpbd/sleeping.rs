//! Sleeping: islands of bones linked by joints or by contacts between moving bodies
//! fall asleep together once each of their bones has rested for `sleep.time` seconds,
//! and wake together when any of them moves (an awake bone touching a sleeping one
//! joins its island, so a hit wakes it).
//!
//! A bone rests when every one of its particles is slower than the sleep speed, or when
//! its centre has stayed within `sleep.translation` of where it was for `sleep.time`
//! (Doom 3's `noMoveTime` test, which also catches a limb trembling in place against a
//! hard limit) and has not turned by more than `sleep.rotation`. A sleeping bone's particles are frozen: inverse mass 0, velocity 0.

use super::super::bone::Bone;
use super::super::joints::Link;
use super::contacts::Contact;
use super::joints::Anchor;
use super::particles::{PER_BONE, XParticles};
use crate::scene::SleepSettings;
use crate::union_find::UnionFind;
use glam::{Quat, Vec3};

/// Each bone's rest timers.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Rest {
    /// Seconds below the sleep speed.
    pub slow: f32,
    /// Seconds within the no-move box.
    pub still: f32,
    /// Where the no-move box is centred.
    pub anchor: Vec3,
    /// The orientation the no-move turn is measured from.
    pub turn: Quat,
}

/// Updates the timers over a frame of `dt` ending at `time` and puts islands to sleep
/// or wakes them (module doc). `held` is the grabbed bone, which never rests.
#[allow(clippy::too_many_arguments)]
pub(crate) fn update(
    p: &mut XParticles,
    bones: &mut [Bone],
    rest: &mut [Rest],
    links: &[Link],
    contacts: &[Contact],
    held: Option<usize>,
    s: &SleepSettings,
    dt: f32,
    time: f64,
) {
    let n = bones.len();
    for i in 0..n {
        if bones[i].fixed {
            continue;
        }
        let f = PER_BONE * i;
        let slow =
            bones[i].asleep || (f..f + PER_BONE).all(|k| p.v[k].length() < s.linear_velocity);
        let r = &mut rest[i];
        r.slow = if slow && held != Some(i) {
            r.slow + dt
        } else {
            0.0
        };
        let c = Vec3::from(bones[i].center());
        let turned = (bones[i].rot * r.turn.inverse()).to_axis_angle().1;
        let turned = turned.min(std::f32::consts::TAU - turned);
        let still = (c - r.anchor).length() <= s.translation && turned <= s.rotation;
        if bones[i].asleep || still && held != Some(i) {
            r.still += dt;
        } else {
            r.anchor = c;
            r.turn = bones[i].rot;
            r.still = 0.0;
        }
    }
    let mut sets = UnionFind::new(n);
    let dynamic = |bones: &[Bone], i: usize| !bones[i].fixed;
    for l in links {
        if let (Some(a), Some(b)) = l.sides()
            && dynamic(bones, a)
            && dynamic(bones, b)
        {
            sets.union(a, b);
        }
    }
    for c in contacts {
        if let (Anchor::Bone(a, _), Anchor::Bone(b, _)) = (c.a, c.b)
            && dynamic(bones, a as usize)
            && dynamic(bones, b as usize)
        {
            sets.union(a as usize, b as usize);
        }
    }
    // An island rests as long as its least rested bone.
    let mut island_rest = vec![f32::INFINITY; n];
    for i in 0..n {
        if bones[i].fixed {
            continue;
        }
        let root = sets.find(i);
        let r = rest[i].slow.max(rest[i].still);
        island_rest[root] = island_rest[root].min(r);
    }
    let forced = s.max_move_time > 0.0 && time >= s.max_move_time as f64;
    let allowed = time >= s.min_move_time as f64;
    for i in 0..n {
        if bones[i].fixed {
            continue;
        }
        let root = sets.find(i);
        let asleep = allowed && (forced || island_rest[root] >= s.time);
        if asleep != bones[i].asleep {
            bones[i].asleep = asleep;
            p.set_asleep(i, asleep);
            if !asleep {
                rest[i] = Rest {
                    anchor: Vec3::from(bones[i].center()),
                    turn: bones[i].rot,
                    ..Rest::default()
                };
            }
        }
    }
}
