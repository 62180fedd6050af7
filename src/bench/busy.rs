//! Busy-phase figures of a run: what a player feels while a scene moves, which a run's
//! mean hides when most of its frames have nothing awake.
//!
//! A run is logged frame by frame ([`FrameLog`]): the frame's time and the number of
//! dynamic bodies awake when its step began (`Method::awake_body_count`). The frame
//! time is the stepping thread's CPU time on a one-thread pool (robust to a shared
//! machine) and wall-clock time on several (the other threads' work is not on the
//! stepping thread's clock). From the log ([`Busy`]):
//!
//! - the slowest frame and the 95th-percentile frame (nearest rank: the smallest frame
//!   time that at least 95 % of the frames do not exceed);
//! - the time spent in each of the first simulated seconds, the frames of that second
//!   summed: a pile falls, lands and comes to rest within two to three seconds, so these
//!   are its busy seconds;
//! - µs per awake body per step: the run's time divided by the sum over its steps of the
//!   bodies awake — the cost of one moving body for one step, the measure Box3D gives
//!   for its rain benchmark. Steps with nothing awake cost next to nothing and add
//!   nothing to the sum, so this does not fall as a run's resting tail grows.

use serde_json::{Value, json};

/// Simulated seconds whose frame times [`Busy`] sums one by one.
pub const BUSY_SECONDS: usize = 3;

/// Frame times and awake-body counts of one run, frame by frame.
#[derive(Clone, Debug, Default)]
pub struct FrameLog {
    /// Frames per simulated second (rounded): 60 at 1/60 s.
    frames_per_second: usize,
    /// Each frame's time (ms).
    ms: Vec<f64>,
    /// Dynamic bodies awake when each frame's step began.
    awake: Vec<usize>,
}

impl FrameLog {
    /// An empty log of frames of `frame_dt` seconds, with room for `frames` of them.
    pub fn new(frame_dt: f64, frames: usize) -> FrameLog {
        FrameLog {
            frames_per_second: ((1.0 / frame_dt).round() as usize).max(1),
            ms: Vec::with_capacity(frames),
            awake: Vec::with_capacity(frames),
        }
    }

    /// Logs a frame of `ms` milliseconds whose step began with `awake` bodies awake.
    pub fn push(&mut self, ms: f64, awake: usize) {
        self.ms.push(ms);
        self.awake.push(awake);
    }

    /// The frames' times (ms), in order.
    pub fn frame_ms(&self) -> &[f64] {
        &self.ms
    }

    /// The bodies awake when each frame's step began, in order.
    pub fn awake(&self) -> &[usize] {
        &self.awake
    }

    /// The figures of the run.
    pub fn summary(&self) -> Busy {
        let mut sorted = self.ms.clone();
        sorted.sort_by(f64::total_cmp);
        let total_ms: f64 = self.ms.iter().sum();
        let awake_steps: usize = self.awake.iter().sum();
        let fps = self.frames_per_second.max(1);
        let first_seconds_ms = std::array::from_fn(|k| {
            // Only a second the run covered whole.
            (self.ms.len() >= (k + 1) * fps).then(|| self.ms[k * fps..(k + 1) * fps].iter().sum())
        });
        Busy {
            max_ms: sorted.last().copied().unwrap_or(0.0),
            p95_ms: percentile(&sorted, 0.95),
            median_ms: percentile(&sorted, 0.5),
            first_seconds_ms,
            us_per_awake_body_step: (awake_steps > 0).then(|| 1e3 * total_ms / awake_steps as f64),
            mean_awake: awake_steps as f64 / self.awake.len().max(1) as f64,
            peak_awake: self.awake.iter().copied().max().unwrap_or(0),
        }
    }
}

/// The nearest-rank percentile `p` (0–1] of ascending `sorted`; 0 when empty.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (p * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// The busy-phase figures of one run (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Busy {
    /// Slowest frame (ms).
    pub max_ms: f64,
    /// 95th-percentile frame (ms).
    pub p95_ms: f64,
    /// Median frame (ms, nearest rank).
    pub median_ms: f64,
    /// Time spent in each of the first [`BUSY_SECONDS`] simulated seconds (ms per
    /// simulated second); `None` for a second the run did not cover whole.
    pub first_seconds_ms: [Option<f64>; BUSY_SECONDS],
    /// The run's time over the sum of awake bodies over its steps (µs); `None` when
    /// nothing was ever awake.
    pub us_per_awake_body_step: Option<f64>,
    /// Mean number of bodies awake at the start of a step.
    pub mean_awake: f64,
    /// Most bodies awake at the start of a step.
    pub peak_awake: usize,
}

impl Busy {
    /// The JSON fields of these figures.
    pub fn to_json(&self) -> Value {
        json!({
            "max_frame_ms": self.max_ms,
            "p95_frame_ms": self.p95_ms,
            "first_seconds_ms": self.first_seconds_ms,
            "us_per_awake_body_step": self.us_per_awake_body_step,
            "mean_awake_bodies": self.mean_awake,
            "peak_awake_bodies": self.peak_awake,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_nearest_rank() {
        let xs: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(percentile(&xs, 0.95), 19.0);
        assert_eq!(percentile(&xs, 1.0), 20.0);
        assert_eq!(percentile(&xs, 0.5), 10.0);
        assert_eq!(percentile(&[7.0], 0.95), 7.0);
        assert_eq!(percentile(&[], 0.95), 0.0);
    }

    #[test]
    fn a_log_sums_its_seconds_and_divides_by_awake_body_steps() {
        // Ten frames of 1/4 s: two whole seconds, the third cut short.
        let mut log = FrameLog::new(0.25, 10);
        for k in 0..10 {
            // 2 ms a frame with 4 bodies awake, then nothing awake costs 0.5 ms.
            if k < 6 {
                log.push(2.0, 4);
            } else {
                log.push(0.5, 0);
            }
        }
        let b = log.summary();
        assert_eq!(b.first_seconds_ms, [Some(8.0), Some(5.0), None]);
        assert_eq!(b.max_ms, 2.0);
        assert_eq!(b.p95_ms, 2.0);
        // Four frames of 0.5 ms and six of 2: the fifth smallest is 2.
        assert_eq!(b.median_ms, 2.0);
        // 14 ms over 6 steps of 4 awake bodies: 14e3 / 24 µs.
        assert!((b.us_per_awake_body_step.unwrap() - 14e3 / 24.0).abs() < 1e-9);
        assert_eq!(b.mean_awake, 2.4);
        assert_eq!(b.peak_awake, 4);
    }

    #[test]
    fn nothing_awake_has_no_cost_per_awake_body() {
        let mut log = FrameLog::new(1.0 / 60.0, 2);
        log.push(0.1, 0);
        log.push(0.1, 0);
        assert_eq!(log.summary().us_per_awake_body_step, None);
    }
}
