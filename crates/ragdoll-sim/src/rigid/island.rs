//! Islands and sleeping.
//!
//! An island is a set of dynamic bodies connected by joints or touching contacts
//! (fixed bodies and the ground do not connect islands). Islands are found each step by
//! union–find over reusable arrays. A body is *still* when Doom 3's `suspendSpeed`
//! thresholds (speeds and accelerations) hold and it has not moved more than
//! `noMoveTranslation` / `noMoveRotation` from where it was when it became still; an
//! island whose bodies have all been still for `noMoveTime` falls asleep as a whole,
//! and wakes as a whole when an awake body touches it. `minMoveTime` delays sleep,
//! `maxMoveTime` forces it.

// Several per-body arrays are walked together by index.
#![allow(clippy::needless_range_loop)]

use super::body::BodyStates;
use crate::scene::SleepSettings;
use crate::union_find::UnionFind;
use glam::{Quat, Vec3, Vec3A};

/// Sleep bookkeeping per body plus the union–find of this step's links.
#[derive(Clone, Debug, Default)]
pub struct Islands {
    links: UnionFind,
    /// Per body: asleep.
    pub asleep: Vec<bool>,
    /// Per body: seconds it has been still.
    pub still_time: Vec<f32>,
    rest_com: Vec<Vec3>,
    rest_rot: Vec<Quat>,
    prev_lin: Vec<Vec3>,
    prev_ang: Vec<Vec3>,
    island_min_still: Vec<f32>,
    island_wake: Vec<bool>,
}

impl Islands {
    /// Sleep state for `n` bodies, all awake.
    pub fn new(s: &BodyStates, n: usize) -> Islands {
        Islands {
            links: UnionFind::new(n),
            asleep: vec![false; n],
            still_time: vec![0.0; n],
            rest_com: s.com[..n].to_vec(),
            rest_rot: s.rot[..n].to_vec(),
            prev_lin: s.lin_vel[..n].iter().map(|&v| Vec3::from(v)).collect(),
            prev_ang: s.ang_vel[..n].iter().map(|&w| Vec3::from(w)).collect(),
            island_min_still: vec![0.0; n],
            island_wake: vec![false; n],
        }
    }

    /// Adds a body (a projectile), awake.
    pub fn push(&mut self, s: &BodyStates, i: usize) {
        debug_assert_eq!(i, self.links.len(), "bodies are pushed in order");
        self.links.push();
        self.asleep.push(false);
        self.still_time.push(0.0);
        self.rest_com.push(s.com[i]);
        self.rest_rot.push(s.rot[i]);
        self.prev_lin.push(Vec3::from(s.lin_vel[i]));
        self.prev_ang.push(Vec3::from(s.ang_vel[i]));
        self.island_min_still.push(0.0);
        self.island_wake.push(false);
    }

    /// The representative of `i`'s island (valid until the next link).
    pub fn root(&mut self, i: usize) -> usize {
        self.links.find(i)
    }

    /// Starts a new union–find round.
    pub fn reset_links(&mut self) {
        self.links.reset();
    }

    /// Joins the islands of `a` and `b` (both dynamic).
    pub fn link(&mut self, a: usize, b: usize) {
        // Smaller root wins: the result does not depend on link order's history.
        self.links.union(a, b);
    }

    /// Marks `i`'s island to be woken by [`Islands::apply_wakes`].
    pub fn request_wake(&mut self, i: usize) {
        let r = self.links.find(i);
        self.island_wake[r] = true;
    }

    /// Wakes every island marked by [`Islands::request_wake`]; returns whether any woke.
    pub fn apply_wakes(&mut self) -> bool {
        let mut any = false;
        for i in 0..self.links.len() {
            let r = self.links.find(i);
            if self.island_wake[r] && self.asleep[i] {
                self.asleep[i] = false;
                self.still_time[i] = 0.0;
                any = true;
            }
        }
        self.island_wake.iter_mut().for_each(|w| *w = false);
        any
    }

    /// Updates stillness after a step of `dt` at time `t` and puts islands to sleep.
    /// `dynamic[i]` is false for fixed bodies. Returns whether any island fell asleep.
    pub fn update_sleep(
        &mut self,
        s: &mut BodyStates,
        dynamic: &[bool],
        cfg: &SleepSettings,
        dt: f32,
        t: f32,
    ) -> bool {
        let n = self.links.len();
        for i in 0..n {
            if !dynamic[i] || self.asleep[i] {
                continue;
            }
            let (v, w) = (Vec3::from(s.lin_vel[i]), Vec3::from(s.ang_vel[i]));
            let lin_acc = (v - self.prev_lin[i]).length() / dt;
            let ang_acc = (w - self.prev_ang[i]).length() / dt;
            self.prev_lin[i] = v;
            self.prev_ang[i] = w;
            let moved = s.com[i].distance(self.rest_com[i]);
            let turned = (s.rot[i] * self.rest_rot[i].inverse())
                .normalize()
                .to_axis_angle()
                .1;
            let turned = if turned > std::f32::consts::PI {
                std::f32::consts::TAU - turned
            } else {
                turned
            };
            let still = v.length() <= cfg.linear_velocity
                && w.length() <= cfg.angular_velocity
                && lin_acc <= cfg.linear_acceleration
                && ang_acc <= cfg.angular_acceleration
                && moved <= cfg.translation
                && turned <= cfg.rotation;
            if still {
                self.still_time[i] += dt;
            } else {
                self.still_time[i] = 0.0;
                self.rest_com[i] = s.com[i];
                self.rest_rot[i] = s.rot[i];
            }
        }
        if t < cfg.min_move_time {
            return false;
        }
        let forced = cfg.max_move_time > 0.0 && t >= cfg.max_move_time;
        // Island minimum of still time (fixed bodies do not take part).
        self.island_min_still
            .iter_mut()
            .for_each(|m| *m = f32::INFINITY);
        for i in 0..n {
            if dynamic[i] && !self.asleep[i] {
                let r = self.links.find(i);
                self.island_min_still[r] = self.island_min_still[r].min(self.still_time[i]);
            }
        }
        let mut any = false;
        for i in 0..n {
            if !dynamic[i] || self.asleep[i] {
                continue;
            }
            let r = self.links.find(i);
            if forced || self.island_min_still[r] >= cfg.time {
                self.asleep[i] = true;
                s.lin_vel[i] = Vec3A::ZERO;
                s.ang_vel[i] = Vec3A::ZERO;
                self.prev_lin[i] = Vec3::ZERO;
                self.prev_ang[i] = Vec3::ZERO;
                any = true;
            }
        }
        any
    }
}
