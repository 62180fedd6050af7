//! The rain: humans dropped in groups at a steady rate onto the ground, so that several
//! hundred move at every moment, and what one moving body costs a step — in the manner
//! of Box3D's rain benchmark, whose figure is µs per body per step while its bodies move.
//!
//! Box3D spawns a row of groups of three humans every few dozen steps, each from 20 m
//! above its own cell of the floor, and destroys the oldest row once ten are out (about
//! 56 humans a second, 300 alive, each landing about 20 m/s). Our methods are built whole
//! from a scene and have no way to add a jointed figure later, so here every group is in
//! the scene from the start, in its own cell, stacked up a vertical stream: the groups
//! fall at their terminal speed `v = g / c` under a linear air drag `c` (the scene's
//! `friction.linear`, which all three engines apply as `dv/dt = −c v`), started at that
//! speed so that the stream keeps its spacing, and group `k`, started
//! `v (t₀ + k Δ)` above its landing height, lands at `t₀ + k Δ`: one group every
//! [`DROP_EVERY`] frames, each at [`FALL_SPEED`] (Box3D's 20 m drop). The drag is
//! 0.5 s⁻¹, weak beside the contacts once a human lands. The particle method and Rapier
//! read `friction.linear` as that rate `c`; the multibody method reads it as Doom 3's
//! fraction of the velocity lost per second, `f = 1 − e^{−c}` for the same drag, which
//! [`scene_for`] writes for it, so that the rain falls alike in all three.
//!
//! The difference that remains: Box3D's humans exist only from their drop, ours fall
//! from the start. A human in the air is cheap (joints, no contacts) and counts as
//! moving, so the cost per moving body is reported two ways that bracket a Box3D-like
//! mix: over every awake body (airborne ones included, a low bound), and over the awake
//! bodies that have landed, below [`LANDED_HEIGHT`] (the whole frame's time charged to
//! them, a high bound). With sleeping on (as in Box3D), landed humans that come to rest
//! sleep and drop out of both.

use super::busy::{Busy, FrameLog};
use super::scale::{FRAME_DT, pile, runs_in_parallel, thread_counts};
use super::table::{Table, opt};
use super::{Flavor, Report, Size, on_threads, progress, thread_cpu_seconds};
use crate::AppError;
use glam::{Quat, Vec3};
use ragdoll_sim::SceneDesc;
use ragdoll_sim::method::BodyState;
use ragdoll_sim::scene::{BodyId, BodyRef, Pose};
use serde_json::{Value, json};
use std::time::Instant;

/// Humans per group (Box3D's).
pub const GROUP_SIZE: usize = 3;
/// Frames between two groups' landings: 60 humans a second at 1/60 s (Box3D about 56).
pub const DROP_EVERY: usize = 3;
/// Landing speed of every group (m/s): the terminal speed `g / c`, Box3D's 20 m drop.
pub const FALL_SPEED: f32 = 19.62;
/// When the first group lands (s): it starts about 20 m up, as Box3D's do.
pub const FIRST_LANDING: f32 = 1.0;
/// Frames of a run: 10 simulated seconds.
pub const FRAMES: usize = 600;
/// Side of a group's cell of the floor (m): a human's arm span is 1.87 m.
pub const CELL: f32 = 4.0;
/// Vertical distance between the humans of a group (m), every other one turned 90°
/// about the vertical, as the pile's layers: they land crosswise on each other.
pub const GROUP_LAYER: f32 = 0.5;
/// A body whose centre of mass is below this height (m) has landed; above it, it falls
/// (a human lying on others is under 1.5 m).
pub const LANDED_HEIGHT: f32 = 3.0;

/// Groups in a run of `frames` frames: one every [`DROP_EVERY`] frames from
/// [`FIRST_LANDING`] to the end.
pub fn group_count(frames: usize) -> usize {
    let first = (FIRST_LANDING / FRAME_DT).round() as usize;
    frames.saturating_sub(first) / DROP_EVERY + 1
}

/// The rain of `groups` groups: the pile's human (lying face down) repeated, group `k`
/// in cell `k` of a square grid (row by row), falling at [`FALL_SPEED`] from the height
/// at which it lands at `FIRST_LANDING + k · DROP_EVERY` frames.
pub fn scene(groups: usize) -> Result<SceneDesc, AppError> {
    let human = pile(1)?;
    let g = human.settings.gravity.length();
    let drag = g / FALL_SPEED;
    let side = (groups as f64).sqrt().ceil() as usize;
    let mut rain = SceneDesc {
        name: format!("rain-{groups}"),
        bodies: Vec::with_capacity(groups * GROUP_SIZE * human.bodies.len()),
        constraints: Vec::with_capacity(groups * GROUP_SIZE * human.constraints.len()),
        ..human.clone()
    };
    let half = 0.5 * CELL * (side as f32 - 1.0);
    for k in 0..groups {
        let landing = FIRST_LANDING + (k * DROP_EVERY) as f32 * FRAME_DT;
        let (column, row) = (k % side, k / side);
        let at = Vec3::new(
            column as f32 * CELL - half,
            FALL_SPEED * landing,
            row as f32 * CELL - half,
        );
        for m in 0..GROUP_SIZE {
            let place = Pose {
                position: at + Vec3::Y * (m as f32 * GROUP_LAYER),
                rotation: Quat::from_rotation_y(m as f32 * std::f32::consts::FRAC_PI_2),
            };
            let first = rain.bodies.len() as u32;
            let tag = format!("#{k}.{m}");
            for b in &human.bodies {
                let mut b = b.clone();
                b.transform(&place);
                b.name.push_str(&tag);
                b.linear_velocity = Vec3::new(0.0, -FALL_SPEED, 0.0);
                b.friction.linear = drag;
                rain.bodies.push(b);
            }
            for c in &human.constraints {
                let mut c = c.clone();
                c.kind.transform(&place);
                c.name.push_str(&tag);
                c.body1 = BodyId(c.body1.0 + first);
                if let BodyRef::Body(b) = c.body2 {
                    c.body2 = BodyRef::Body(BodyId(b.0 + first));
                }
                rain.constraints.push(c);
            }
        }
    }
    Ok(rain)
}

/// The rain of `groups` groups as `flavor` reads it: the multibody method takes air
/// friction as the fraction of the velocity lost per second (`v ← v (1 − f)^h`), the
/// others as a rate (`v ← v (1 − c h)`); `f = 1 − e^{−c}` is the same drag.
pub fn scene_for(flavor: Flavor, groups: usize) -> Result<SceneDesc, AppError> {
    let mut rain = scene(groups)?;
    if flavor == Flavor::Multibody {
        for b in &mut rain.bodies {
            b.friction.linear = 1.0 - (-b.friction.linear).exp();
        }
    }
    Ok(rain)
}

/// Bodies whose centre of mass is above [`LANDED_HEIGHT`]: still falling.
pub fn airborne(states: &[BodyState]) -> usize {
    states.iter().filter(|s| s.com.y > LANDED_HEIGHT).count()
}

/// One engine's run of the rain: its frames and, per frame, the bodies in the air.
#[derive(Clone, Debug)]
pub struct RainRun {
    /// Frame times and awake bodies.
    pub log: FrameLog,
    /// Bodies above [`LANDED_HEIGHT`] when each frame's step began.
    pub airborne: Vec<usize>,
    /// Mean frame (ms), timed as the log's frames.
    pub mean_ms: f64,
    /// Every body's state was finite at the end.
    pub finite: bool,
}

/// What a run of the rain measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RainCost {
    /// Mean frame (ms).
    pub mean_ms: f64,
    /// Frames, seconds and cost per awake body (all of them, the airborne included).
    pub busy: Busy,
    /// Mean bodies in the air at the start of a step.
    pub mean_airborne: f64,
    /// Fewest bodies awake at the start of a step after the first landing.
    pub fewest_moving: usize,
    /// The run's time over the sum over its steps of awake bodies that have landed (µs).
    pub us_per_landed_moving_body_step: Option<f64>,
    /// Every body's state was finite at the end.
    pub finite: bool,
}

impl RainRun {
    /// The run's figures.
    pub fn cost(&self, frames_before_landing: usize) -> RainCost {
        let busy = self.log.summary();
        let total_ms: f64 = self.log.frame_ms().iter().sum();
        let awake = self.log.awake();
        let landed: usize = awake
            .iter()
            .zip(&self.airborne)
            .map(|(&a, &f)| a.saturating_sub(f))
            .sum();
        RainCost {
            mean_ms: self.mean_ms,
            busy,
            mean_airborne: self.airborne.iter().sum::<usize>() as f64
                / self.airborne.len().max(1) as f64,
            fewest_moving: awake
                .iter()
                .skip(frames_before_landing)
                .copied()
                .min()
                .unwrap_or(0),
            us_per_landed_moving_body_step: (landed > 0).then(|| 1e3 * total_ms / landed as f64),
            finite: self.finite,
        }
    }
}

impl RainCost {
    /// The JSON fields of these figures.
    pub fn to_json(&self) -> Value {
        json!({
            "mean_ms_per_frame": self.mean_ms,
            "busy": self.busy.to_json(),
            "us_per_moving_body_step": self.busy.us_per_awake_body_step,
            "us_per_landed_moving_body_step": self.us_per_landed_moving_body_step,
            "mean_moving_bodies": self.busy.mean_awake,
            "fewest_moving_bodies": self.fewest_moving,
            "mean_airborne_bodies": self.mean_airborne,
            "finite": self.finite,
        })
    }
}

/// Frames before the first group lands.
pub fn frames_before_landing() -> usize {
    (FIRST_LANDING / FRAME_DT).round() as usize
}

/// Builds `flavor` on `scene` and runs `frames` frames of the rain on the calling
/// thread's pool (frames timed by CPU time on one thread, wall-clock on several).
pub fn run_ours(flavor: Flavor, scene: &SceneDesc, frames: usize) -> Result<RainRun, AppError> {
    let mut m = flavor.build(scene)?;
    let on_cpu_clock = rayon::current_num_threads() == 1;
    let mut log = FrameLog::new(FRAME_DT as f64, frames);
    let mut airborne_per_frame = Vec::with_capacity(frames);
    let mut states = Vec::new();
    let mut total = 0.0;
    for _ in 0..frames {
        m.body_states(&mut states);
        airborne_per_frame.push(airborne(&states));
        let awake = m.awake_body_count();
        let cpu0 = thread_cpu_seconds();
        let t0 = Instant::now();
        m.step();
        let wall = t0.elapsed().as_secs_f64();
        let ms = 1e3
            * if on_cpu_clock {
                thread_cpu_seconds() - cpu0
            } else {
                wall
            };
        total += ms;
        log.push(ms, awake);
    }
    m.body_states(&mut states);
    let finite = states
        .iter()
        .all(|s| s.com.is_finite() && s.linear_velocity.is_finite());
    Ok(RainRun {
        log,
        airborne: airborne_per_frame,
        mean_ms: total / frames.max(1) as f64,
        finite,
    })
}

/// Runs the rain table; `no_sleep` turns sleeping off in both methods.
pub fn run(size: Size, no_sleep: bool, particle: Flavor) -> Result<Report, AppError> {
    let frames = match size {
        Size::Full => FRAMES,
        Size::Quick => frames_before_landing() + 2 * DROP_EVERY,
    };
    let groups = group_count(frames);
    let scene_of = |flavor: Flavor| {
        let mut scene = scene_for(flavor, groups)?;
        if no_sleep {
            scene.settings.sleep.disable();
        }
        Ok::<_, AppError>(scene)
    };
    let bodies = scene_of(Flavor::Multibody)?.dynamic_body_count();
    let humans = groups * GROUP_SIZE;
    let mut table = Table::new(
        format!(
            "Rain: {humans} humans ({bodies} bones) in groups of {GROUP_SIZE}, one group \
             landing every {DROP_EVERY} frames at {FALL_SPEED} m/s from {FIRST_LANDING} s, \
             {frames} frames at 1/60 s, sleeping {}; ms per frame (CPU time on one thread, \
             wall-clock on several); us/moving = microseconds per awake body per step, \
             us/landed = the same over awake bodies below {LANDED_HEIGHT} m",
            if no_sleep { "off" } else { "on" }
        ),
        &[
            "Threads",
            "Method",
            "mean",
            "p95",
            "max",
            "moving",
            "fewest",
            "airborne",
            "us/moving",
            "us/landed",
        ],
    );
    let mut rows = Vec::new();
    for threads in thread_counts() {
        for flavor in [particle, Flavor::Multibody] {
            if threads > 1 && !runs_in_parallel(flavor) {
                continue;
            }
            progress(&format!("rain: {threads} thread(s), {}", flavor.key()));
            let scene = scene_of(flavor)?;
            let run = on_threads(threads, || run_ours(flavor, &scene, frames))?;
            let c = run.cost(frames_before_landing());
            let mean = if c.finite {
                format!("{:.2}", c.mean_ms)
            } else {
                format!("{:.2} (NaN)", c.mean_ms)
            };
            table.row(vec![
                threads.to_string(),
                flavor.key().into(),
                mean,
                format!("{:.2}", c.busy.p95_ms),
                format!("{:.2}", c.busy.max_ms),
                format!("{:.0}", c.busy.mean_awake),
                c.fewest_moving.to_string(),
                format!("{:.0}", c.mean_airborne),
                opt(c.busy.us_per_awake_body_step, |x| format!("{x:.2}")),
                opt(c.us_per_landed_moving_body_step, |x| format!("{x:.2}")),
            ]);
            let mut row = c.to_json();
            row["threads"] = json!(threads);
            row["method"] = json!(flavor.key());
            rows.push(row);
        }
    }
    table.note(
        "Box3D's figure for its rain: about 2.9 us per body per step. Bodies in the air count \
         as moving in us/moving (a low bound) and not in us/landed (a high bound).",
    );
    Ok(Report {
        json: json!({
            "bench": "rain",
            "sleep": !no_sleep,
            "humans": humans,
            "bodies": bodies,
            "groups": groups,
            "frames": frames,
            "frame_dt": FRAME_DT,
            "rows": rows,
        }),
        text: table.render(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_group_lands_at_its_turn_at_the_fall_speed() {
        let groups = 5;
        let rain = scene(groups).unwrap();
        let per_group = GROUP_SIZE * 16;
        assert_eq!(rain.bodies.len(), groups * per_group);
        assert_eq!(rain.constraints.len(), groups * GROUP_SIZE * 15);
        let human = pile(1).unwrap();
        let low = |k: usize| {
            rain.bodies[k * per_group..k * per_group + 16]
                .iter()
                .map(|b| b.pose.position.y)
                .fold(f32::MAX, f32::min)
        };
        let rest = human
            .bodies
            .iter()
            .map(|b| b.pose.position.y)
            .fold(f32::MAX, f32::min);
        for k in 0..groups {
            // The lowest bone of the group's first human reaches its rest height (the
            // pile's, just above the floor) at the group's turn.
            let t = (low(k) - rest) / FALL_SPEED;
            let turn = FIRST_LANDING + (k * DROP_EVERY) as f32 * FRAME_DT;
            assert!(
                (t - turn).abs() < 1e-4,
                "group {k}: lands at {t} s, not {turn}"
            );
        }
        let g = rain.settings.gravity.length();
        for b in &rain.bodies {
            assert_eq!(b.linear_velocity, Vec3::new(0.0, -FALL_SPEED, 0.0));
            // Terminal speed: drag balances gravity.
            assert!((b.friction.linear * FALL_SPEED - g).abs() < 1e-4);
        }
        // Joints refer to their own human's bodies.
        for (i, c) in rain.constraints.iter().enumerate() {
            let human = i / 15;
            let own = (human * 16) as u32..(human * 16 + 16) as u32;
            assert!(own.contains(&c.body1.0), "{}", c.name);
            if let BodyRef::Body(b) = c.body2 {
                assert!(own.contains(&b.0), "{}", c.name);
            }
        }
        assert!(ragdoll_sim::scene::validate(&rain).is_ok());
    }

    #[test]
    fn a_full_run_drops_a_group_every_few_frames_to_the_end() {
        assert_eq!(group_count(FRAMES), (FRAMES - 60) / DROP_EVERY + 1);
        assert_eq!(group_count(60), 1);
    }
}
