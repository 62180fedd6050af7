//! `ragdoll-lab bench ...`: the paper's performance tests 9-12 (section 5.2, tables 1-4)
//! and the scale table of the pile of humans.
//!
//! Every table prints the paper's own figures in a column beside ours, for the particle
//! method in both solver modes and for the multibody method. t_real is the CPU time of
//! the stepping thread ([`thread_cpu_seconds`]): this machine is shared, and wall-clock
//! time would also count the time spent waiting for a core (the JSON has both). The
//! benches are run by hand in a release build and their output is committed to
//! `docs/benchmarks.md` with the command that produced it. Nothing here asserts a time.
//!
//! - [`memory`]: test 9, bytes per simulation, measured by a counting global allocator.
//! - [`timestep`]: test 10, t_real/t_sim against the timestep.
//! - [`bones`]: test 11, t_real/t_sim against the number of bones.
//! - [`iterations`]: test 12, t_real/t_sim against the iterations.
//! - [`scale`]: the pile of humans, milliseconds per frame.
//! - [`rain`]: humans dropped in groups at a steady rate, µs per moving body per step
//!   (Box3D's rain benchmark).
//! - [`busy`]: the busy-phase figures every run reports beside its mean (slowest and
//!   95th-percentile frame, time per simulated second, µs per awake body per step).
//! - [`scenes`]: the benches' scenes, built as `SceneDesc` in code.

pub mod bones;
pub mod busy;
pub mod iterations;
pub mod memory;
pub mod rain;
pub mod scale;
pub mod scenes;
mod table;
pub mod timestep;

use crate::AppError;
use crate::cli::{BenchArgs, BenchKind, ParticleSolverArg};
use crate::methods;
use busy::{Busy, FrameLog};
use ragdoll_sim::{Method, SceneDesc};
use serde_json::{Value, json};
use std::time::Instant;

/// One configuration the benches compare: a method, and for the particle method its
/// solver mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flavor {
    /// The particle method as the paper wrote it (section 3).
    ParticlePaper,
    /// Our particle method (the default solver).
    ParticleRigidFrames,
    /// The particle method's XPBD solver on particles (`--particle-solver xpbd`).
    ParticleXpbd,
    /// The impulse-based multibody method.
    Multibody,
}

impl Flavor {
    /// All three, in table order.
    pub const ALL: [Flavor; 3] = [
        Flavor::ParticlePaper,
        Flavor::ParticleRigidFrames,
        Flavor::Multibody,
    ];

    /// The key used in JSON and table headers.
    pub fn key(self) -> &'static str {
        match self {
            Flavor::ParticlePaper => "particle_paper",
            Flavor::ParticleRigidFrames => "particle_rigid_frames",
            Flavor::ParticleXpbd => "particle_xpbd",
            Flavor::Multibody => "multibody",
        }
    }

    /// Builds this method for `scene`.
    pub fn build(self, scene: &SceneDesc) -> Result<Box<dyn Method>, AppError> {
        match self {
            Flavor::ParticlePaper => methods::build_particle(scene, ParticleSolverArg::Paper),
            Flavor::ParticleRigidFrames => {
                methods::build_particle(scene, ParticleSolverArg::RigidFrames)
            }
            Flavor::ParticleXpbd => methods::build_particle(scene, ParticleSolverArg::Xpbd),
            Flavor::Multibody => methods::build_multibody(scene),
        }
    }

    /// The particle flavour of a `--particle-solver` choice.
    pub fn particle(solver: ParticleSolverArg) -> Flavor {
        match solver {
            ParticleSolverArg::Paper => Flavor::ParticlePaper,
            ParticleSolverArg::RigidFrames => Flavor::ParticleRigidFrames,
            ParticleSolverArg::Xpbd => Flavor::ParticleXpbd,
        }
    }
}

/// How much work a bench does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// The full table, as in the paper (minutes).
    Full,
    /// A smoke test: the smallest rows and a few frames (seconds). The figures mean nothing.
    Quick,
}

/// Which rows of a table to run: all, or those whose key (first column) is listed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RowFilter(Vec<f64>);

impl RowFilter {
    /// Keeps only the rows whose key is in `keys`; every row when `keys` is empty.
    pub fn new(keys: Vec<f64>) -> RowFilter {
        RowFilter(keys)
    }

    /// Whether the row with this key runs.
    pub fn keeps(&self, key: f64) -> bool {
        self.0.is_empty()
            || self
                .0
                .iter()
                .any(|k| (k - key).abs() <= 1e-9 * key.abs().max(1.0))
    }
}

/// CPU time this thread has used (s). On a shared machine this is the robust measure of
/// what a single-threaded step costs: wall-clock time also counts the time the thread
/// waited for a core. Falls back to wall-clock time where it is not available.
pub fn thread_cpu_seconds() -> f64 {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable timespec; the clock id is a constant.
        if unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) } == 0 {
            return ts.tv_sec as f64 + 1e-9 * ts.tv_nsec as f64;
        }
    }
    use std::sync::OnceLock;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// Cost of running a method for some simulated time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunTiming {
    /// Steps taken.
    pub steps: usize,
    /// Simulated seconds.
    pub t_sim: f64,
    /// Seconds of this thread's CPU time spent in `step` (building the method is not
    /// counted): the tables' t_real. The same as wall-clock time on an idle machine.
    pub t_real: f64,
    /// Wall-clock seconds spent in `step`.
    pub t_wall: f64,
    /// Median step (ms): CPU time on a one-thread pool, wall-clock on several.
    pub median_step_ms: f64,
    /// Slowest step (ms), timed as the median.
    pub max_step_ms: f64,
    /// The state was still finite at the end (a blown-up run is fast for the wrong reason).
    pub finite: bool,
    /// The busy-phase figures (steps timed as the median).
    pub busy: Busy,
}

impl RunTiming {
    /// The paper's measure: 100 % · t_real / t_sim (below 100 % is faster than real time).
    pub fn percent_of_realtime(&self) -> f64 {
        100.0 * self.t_real / self.t_sim
    }

    /// Mean CPU time of one step (ms).
    pub fn mean_step_ms(&self) -> f64 {
        1e3 * self.t_real / self.steps as f64
    }

    /// The paper's t_sim column: seconds simulated in 10 s of wall-clock time.
    pub fn t_sim_per_10s(&self) -> f64 {
        10.0 * self.t_sim / self.t_real
    }

    /// The JSON object the realtime benches print per method.
    pub fn to_json(&self) -> Value {
        json!({
            "steps": self.steps,
            "t_sim": self.t_sim,
            "t_real": self.t_real,
            "t_wall": self.t_wall,
            "percent_of_realtime": self.percent_of_realtime(),
            "mean_step_ms": self.mean_step_ms(),
            "median_step_ms": self.median_step_ms,
            "max_step_ms": self.max_step_ms,
            "finite": self.finite,
            "busy": self.busy.to_json(),
        })
    }
}

/// Runs `f` on a rayon pool of `threads` threads: both methods share their islands out
/// over the pool they are stepped in.
pub fn on_threads<T: Send>(
    threads: usize,
    f: impl FnOnce() -> Result<T, AppError> + Send,
) -> Result<T, AppError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| AppError::Other(format!("cannot start {threads} threads: {e}")))?
        .install(f)
}

/// Builds `flavor` for `scene` and times `steps` steps of `scene.settings.timestep`, on
/// one thread as the paper measured (t_real is the stepping thread's CPU time, which
/// would not see work done on other threads).
pub fn time_steps(flavor: Flavor, scene: &SceneDesc, steps: usize) -> Result<RunTiming, AppError> {
    on_threads(1, || {
        let mut method = flavor.build(scene)?;
        Ok(time_method(method.as_mut(), steps))
    })
}

/// Times `steps` steps of an already built method, each one measured on its own: on a
/// one-thread pool by the stepping thread's CPU time, on several by the wall clock (the
/// other threads' work is not on the stepping thread's clock). The bodies awake at each
/// step's start are counted outside the timed span.
pub fn time_method(method: &mut dyn Method, steps: usize) -> RunTiming {
    time_method_logged(method, steps).0
}

/// [`time_method`], also returning the frame-by-frame log.
pub fn time_method_logged(method: &mut dyn Method, steps: usize) -> (RunTiming, FrameLog) {
    let dt = method.settings().timestep as f64;
    let on_cpu_clock = rayon::current_num_threads() == 1;
    let mut log = FrameLog::new(dt, steps);
    let mut t_wall = 0.0;
    let mut t_real = 0.0;
    for _ in 0..steps {
        let awake = method.awake_body_count();
        let cpu0 = thread_cpu_seconds();
        let t0 = Instant::now();
        method.step();
        let wall = t0.elapsed().as_secs_f64();
        let cpu = thread_cpu_seconds() - cpu0;
        t_wall += wall;
        t_real += cpu;
        log.push(1e3 * if on_cpu_clock { cpu } else { wall }, awake);
    }
    let busy = log.summary();
    let timing = RunTiming {
        steps,
        t_sim: steps as f64 * dt,
        t_real,
        t_wall,
        median_step_ms: busy.median_ms,
        max_step_ms: busy.max_ms,
        finite: method.sample().energy.is_finite(),
        busy,
    };
    (timing, log)
}

/// Times each flavor in turn on `scene` for `seconds` of simulated time.
pub fn time_flavors(
    scene: &SceneDesc,
    seconds: f64,
    flavors: &[Flavor],
) -> Result<Vec<(Flavor, RunTiming)>, AppError> {
    let steps = steps_for(seconds, scene.settings.timestep);
    flavors
        .iter()
        .map(|&f| Ok((f, time_steps(f, scene, steps)?)))
        .collect()
}

/// The realtime percentage of a run, marked when the run blew up.
fn pct_cell(t: &RunTiming) -> String {
    let cell = table::pct(t.percent_of_realtime());
    if t.finite {
        cell
    } else {
        format!("{cell} (NaN)")
    }
}

/// The median of `xs` (reorders them); 0 for an empty slice.
pub fn median(xs: &mut [f64]) -> f64 {
    if xs.is_empty() {
        return 0.0;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

/// Number of steps that simulate `seconds` at `dt`, at least one.
pub fn steps_for(seconds: f64, dt: f32) -> usize {
    ((seconds / dt as f64).round() as usize).max(1)
}

/// A bench's result: the JSON for machines and the text table for people.
pub struct Report {
    /// What `--json` prints.
    pub json: Value,
    /// What is printed without `--json`.
    pub text: String,
}

/// `ragdoll-lab bench ...`.
pub fn run(args: BenchArgs) -> Result<(), AppError> {
    let particle = Flavor::particle(args.particle_solver);
    let size = if args.quick { Size::Quick } else { Size::Full };
    let only = RowFilter::new(args.only);
    let report = match args.kind {
        BenchKind::Memory => memory::run(size, &only)?,
        BenchKind::Timestep => timestep::run(size, &only)?,
        BenchKind::Bones => bones::run(size, &only)?,
        BenchKind::Iterations => iterations::run(size, &only)?,
        BenchKind::Scale => scale::run(size, &only, args.no_sleep, particle)?,
        BenchKind::Rain => rain::run(size, args.no_sleep, particle)?,
    };
    if args.json {
        println!("{}", report.json);
    } else {
        print!("{}", report.text);
    }
    Ok(())
}

/// Prints progress to stderr so a long table shows it is alive; stdout stays clean.
fn progress(msg: &str) {
    eprintln!("bench: {msg}");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut []), 0.0);
    }

    #[test]
    fn realtime_percent_is_the_papers_measure() {
        // The paper's table 2, first particle row: 10 s of wall time simulated 3.3 s.
        let t = RunTiming {
            steps: 3300,
            t_sim: 3.3,
            t_real: 10.0,
            t_wall: 10.0,
            median_step_ms: 0.0,
            max_step_ms: 0.0,
            finite: true,
            busy: FrameLog::default().summary(),
        };
        assert_eq!(t.percent_of_realtime().round(), 303.0);
        assert!((t.t_sim_per_10s() - 3.3).abs() < 1e-12);
    }

    #[test]
    fn thread_cpu_time_advances_with_work() {
        let t0 = thread_cpu_seconds();
        let mut x = 0u64;
        for i in 0..20_000_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
        }
        std::hint::black_box(x);
        assert!(thread_cpu_seconds() > t0);
    }
}
