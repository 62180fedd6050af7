//! Wall-clock time spent in each phase of one step, for the window's panel.
//!
//! Plain data filled by a method's top-level step with a few `Instant::now` calls around
//! the phases it already runs; nothing in a step reads it back, so results do not depend
//! on it. A phase's name is what that solver really does there (a solver whose joints,
//! contacts and integration interleave within each substep reports them as one phase).

use std::time::Instant;

/// Most phases one step reports.
pub const MAX_PHASES: usize = 8;

/// Seconds spent in each named phase of the last step, in the order first entered, and
/// the step's whole wall time. Invariant: the phases' sum is at most `total`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    names: [&'static str; MAX_PHASES],
    seconds: [f64; MAX_PHASES],
    len: usize,
    /// Wall time of the whole step (s), phases and whatever lies between them.
    pub total: f64,
}

impl PhaseTimes {
    /// The phases, in order, as (name, seconds).
    pub fn phases(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        self.names[..self.len]
            .iter()
            .copied()
            .zip(self.seconds[..self.len].iter().copied())
    }

    /// Sum of the phases' times (s).
    pub fn phase_sum(&self) -> f64 {
        self.seconds[..self.len].iter().sum()
    }

    /// Adds `seconds` to phase `name` (a phase entered again, e.g. once per substep,
    /// accumulates); a phase beyond `MAX_PHASES` is dropped.
    pub(crate) fn add(&mut self, name: &'static str, seconds: f64) {
        if let Some(i) = self.names[..self.len].iter().position(|&n| n == name) {
            self.seconds[i] += seconds;
        } else if self.len < MAX_PHASES {
            self.names[self.len] = name;
            self.seconds[self.len] = seconds;
            self.len += 1;
        }
    }
}

/// A stopwatch over consecutive phases: each `lap` charges the time since the previous
/// lap (or the start) to the phase named.
pub(crate) struct PhaseClock {
    start: Instant,
    last: Instant,
}

impl PhaseClock {
    pub(crate) fn start() -> Self {
        let now = Instant::now();
        PhaseClock {
            start: now,
            last: now,
        }
    }

    /// Charges the time since the last lap to `name`.
    pub(crate) fn lap(&mut self, times: &mut PhaseTimes, name: &'static str) {
        let now = Instant::now();
        times.add(name, (now - self.last).as_secs_f64());
        self.last = now;
    }

    /// Starts the next phase without charging the time since the last lap to any phase.
    pub(crate) fn skip(&mut self) {
        self.last = Instant::now();
    }

    /// Sets `times.total` to the time since the start; the last call of a step.
    pub(crate) fn finish(&self, times: &mut PhaseTimes) {
        times.total = self.start.elapsed().as_secs_f64();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_accumulate_by_name_in_order() {
        let mut t = PhaseTimes::default();
        t.add("a", 1.0);
        t.add("b", 2.0);
        t.add("a", 0.5);
        let got: Vec<_> = t.phases().collect();
        assert_eq!(got, vec![("a", 1.5), ("b", 2.0)]);
        assert_eq!(t.phase_sum(), 3.5);
    }

    /// One step of each solver on a falling human fills its phases: a nonzero total no
    /// longer than the step's wall time seen from outside, and phases summing to no more
    /// than the total (the xpbd solver reports the total only).
    #[test]
    fn a_step_fills_the_phases() {
        use crate::scene::af::{AfOptions, parse};
        use crate::world::Solver;
        let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/scenes/human.af");
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
        let scene = parse(&text, &path, &AfOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
            .desc;
        for solver in [
            Solver::Paper,
            Solver::RigidFrames,
            Solver::Xpbd,
            Solver::Multibody,
        ] {
            let mut m = solver.build(&scene).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(m.phase_times(), PhaseTimes::default());
            let start = Instant::now();
            m.step();
            let wall = start.elapsed().as_secs_f64();
            let t = m.phase_times();
            let name = solver.name();
            assert!(
                t.total > 0.0 && t.total <= wall,
                "{name}: {t:?}, wall {wall}"
            );
            assert!(t.phase_sum() <= t.total, "{name}: {t:?}");
            if solver != Solver::Xpbd {
                assert!(t.phases().count() >= 2, "{name}: {t:?}");
                assert!(t.phase_sum() > 0.0, "{name}: {t:?}");
            }
        }
    }
}
