//! The scale table: the pile scene (scene 10) with 1, 10, 100, 270 and 1000 humans of
//! 16 bones, 600 frames at 1/60 s, milliseconds per frame for each method, on one
//! thread and on all cores.
//!
//! Each measurement builds the method, steps it 600 frames and times every frame; the
//! table shows the mean (the cost of the whole run), the median frame and the busy-phase
//! figures ([`super::busy`]): the 95th-percentile and slowest frame, the time spent in
//! the first and second simulated seconds (while the pile falls and lands; it is asleep
//! within two to three) and µs per awake body per step. A row with
//! more threads than one is measured only for a method that really runs in parallel
//! ([`runs_in_parallel`]); otherwise its figure is `null` rather than a repeat of the
//! single-threaded one.

use super::busy::Busy;
use super::table::{Table, opt};
use super::{Flavor, Report, RowFilter, Size, on_threads, progress, time_method};
use crate::cli::SceneArgs;
use crate::{AppError, scenes};
use serde_json::json;

/// Humans in the pile, per row.
pub const HUMANS: [u32; 5] = [1, 10, 100, 270, 1000];
/// Frames per measurement.
pub const FRAMES: usize = 600;
/// Frame length (s).
pub const FRAME_DT: f32 = 1.0 / 60.0;

/// Whether `flavor` spreads one simulation's step over several threads: both methods
/// step their islands on the rayon pool they are stepped in (`rigid::parallel`,
/// `particle::islands`); the paper's and the XPBD particle solvers stay serial.
pub fn runs_in_parallel(flavor: Flavor) -> bool {
    matches!(flavor, Flavor::Multibody | Flavor::ParticleRigidFrames)
}

/// The thread counts to measure: one, and all cores when there is more than one.
pub fn thread_counts() -> Vec<usize> {
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    if all > 1 { vec![1, all] } else { vec![1] }
}

/// The pile of `humans` humans, stepped at [`FRAME_DT`].
pub fn pile(humans: u32) -> Result<ragdoll_sim::SceneDesc, AppError> {
    let loaded = scenes::load(&SceneArgs {
        scene: Some("pile".into()),
        count: Some(humans),
        ..SceneArgs::default()
    })?;
    let mut desc = loaded.desc;
    desc.settings.timestep = FRAME_DT;
    Ok(desc)
}

/// Mean, median and busy-phase ms per frame of one method on one pile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameCost {
    /// Mean ms per frame over the run: the stepping thread's CPU time on one thread
    /// (robust to a shared machine), wall-clock time on several (the other threads'
    /// work is not on the stepping thread's clock).
    pub mean_ms: f64,
    /// Mean wall-clock ms per frame over the run.
    pub wall_ms: f64,
    /// Median frame (ms).
    pub median_ms: f64,
    /// Slowest frame (ms).
    pub max_ms: f64,
    /// Still finite at the end.
    pub finite: bool,
    /// Mean height of the bodies' centres of mass at the end (m): a sanity check that
    /// two engines simulated the same thing (the pile fell and came to rest).
    pub final_mean_height: f64,
    /// Every body is asleep at the end.
    pub asleep_at_end: bool,
    /// The busy-phase figures, frames timed as `mean_ms` is.
    pub busy: Busy,
}

/// Builds `flavor` on `scene` and times `frames` frames, stepped on a pool of `threads`
/// threads (the methods share their work out over the pool they are stepped in).
pub fn measure_on(
    threads: usize,
    flavor: Flavor,
    scene: &ragdoll_sim::SceneDesc,
    frames: usize,
) -> Result<FrameCost, AppError> {
    let mut cost = on_threads(threads, || measure(flavor, scene, frames))?;
    if threads > 1 {
        cost.mean_ms = cost.wall_ms;
    }
    Ok(cost)
}

/// Builds `flavor` on `scene` and times `frames` frames on the calling thread's pool.
pub fn measure(
    flavor: Flavor,
    scene: &ragdoll_sim::SceneDesc,
    frames: usize,
) -> Result<FrameCost, AppError> {
    let mut method = flavor.build(scene)?;
    let t = time_method(method.as_mut(), frames);
    let mut states = Vec::new();
    method.body_states(&mut states);
    let final_mean_height =
        states.iter().map(|b| b.com.y as f64).sum::<f64>() / states.len().max(1) as f64;
    Ok(FrameCost {
        final_mean_height,
        asleep_at_end: method.sample().all_asleep,
        mean_ms: t.mean_step_ms(),
        wall_ms: 1e3 * t.t_wall / t.steps as f64,
        median_ms: t.median_step_ms,
        max_ms: t.max_step_ms,
        finite: t.finite,
        busy: t.busy,
    })
}

/// Runs the scale table: the particle solver `particle` and the multibody method;
/// `no_sleep` turns sleeping off in both.
pub fn run(
    size: Size,
    only: &RowFilter,
    no_sleep: bool,
    particle: Flavor,
) -> Result<Report, AppError> {
    let flavors = [particle, Flavor::Multibody];
    let (humans, frames): (&[u32], usize) = match size {
        Size::Full => (&HUMANS, FRAMES),
        Size::Quick => (&[1, 2], 5),
    };
    let mut table = Table::new(
        format!(
            "Scale: pile of humans, {frames} frames at 1/60 s, sleeping {}, ms per frame (CPU \
             time on one thread, wall-clock on several); 1st s / 2nd s = ms spent in that simulated \
             second; us/bone = mean frame per bone; us/awake = microseconds per awake body \
             per step",
            if no_sleep { "off" } else { "on" }
        ),
        &[
            "Humans", "Bones", "Threads", "Method", "mean", "median", "p95", "max", "1st s",
            "2nd s", "us/bone", "us/awake",
        ],
    );
    let mut rows = Vec::new();
    for &n in humans {
        if !only.keeps(n as f64) {
            continue;
        }
        let mut scene = pile(n)?;
        if no_sleep {
            scene.settings.sleep.disable();
        }
        let bones = scene.dynamic_body_count();
        for threads in thread_counts() {
            let mut costs = [None; 2];
            for (slot, flavor) in costs.iter_mut().zip(flavors) {
                if threads > 1 && !runs_in_parallel(flavor) {
                    continue;
                }
                progress(&format!(
                    "scale: {n} humans, {threads} thread(s), {}",
                    flavor.key()
                ));
                *slot = Some(measure_on(threads, flavor, &scene, frames)?);
            }
            for (cost, flavor) in costs.iter().zip(flavors) {
                let ms = |x: f64| format!("{x:.2}");
                let Some(c) = cost else {
                    let mut cells = vec![n.to_string(), bones.to_string(), threads.to_string()];
                    cells.push(flavor.key().into());
                    cells.push("one thread".into());
                    cells.extend(std::iter::repeat_n("-".to_string(), 7));
                    table.row(cells);
                    continue;
                };
                let mean = if c.finite {
                    ms(c.mean_ms)
                } else {
                    format!("{} (NaN)", ms(c.mean_ms))
                };
                let [s1, s2, _] = c.busy.first_seconds_ms;
                table.row(vec![
                    n.to_string(),
                    bones.to_string(),
                    threads.to_string(),
                    flavor.key().into(),
                    mean,
                    ms(c.median_ms),
                    ms(c.busy.p95_ms),
                    ms(c.max_ms),
                    opt(s1, |x| format!("{x:.0}")),
                    opt(s2, |x| format!("{x:.0}")),
                    format!("{:.2}", 1e3 * c.mean_ms / bones as f64),
                    opt(c.busy.us_per_awake_body_step, |x| format!("{x:.2}")),
                ]);
            }
            let ms = |c: Option<FrameCost>| c.map(|c| c.mean_ms);
            let median = |c: Option<FrameCost>| c.map(|c| c.median_ms);
            let max = |c: Option<FrameCost>| c.map(|c| c.max_ms);
            let wall = |c: Option<FrameCost>| c.map(|c| c.wall_ms);
            let busy = |c: Option<FrameCost>| c.map(|c| c.busy.to_json());
            rows.push(json!({
                "humans": n,
                "bones": bones,
                "threads": threads,
                "particle_ms_per_frame": ms(costs[0]),
                "multibody_ms_per_frame": ms(costs[1]),
                "particle_median_ms": median(costs[0]),
                "multibody_median_ms": median(costs[1]),
                "particle_wall_ms_per_frame": wall(costs[0]),
                "multibody_wall_ms_per_frame": wall(costs[1]),
                "particle_max_ms": max(costs[0]),
                "multibody_max_ms": max(costs[1]),
                "particle_busy": busy(costs[0]),
                "multibody_busy": busy(costs[1]),
            }));
        }
    }
    if flavors.iter().any(|&f| !runs_in_parallel(f)) {
        table.note("\"one thread\": the method does not run a step on several threads, so there is no separate figure.");
    }
    table.note(
        "Goals at 1000 humans on two threads: slowest frame under 16.6 ms (multibody) and \
         33 ms (particle); two threads at least 1.8x faster than one from 100 humans up.",
    );
    Ok(Report {
        json: json!({
            "bench": "scale",
            "frames": frames,
            "frame_dt": FRAME_DT,
            "sleep": !no_sleep,
            "particle_solver": particle.key(),
            "rows": rows,
        }),
        text: table.render(),
    })
}
