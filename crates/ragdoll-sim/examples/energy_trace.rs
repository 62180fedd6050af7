//! The energy of our Doom 3-style mod's humanoid (assets/doom3, entity
//! `monster_lab_human`, from its `af_pose` frame, as `tests/xpbd_lab_human_shifts.rs`
//! drops it) under the XPBD particle solver, frame by frame: where the `energy_gain`
//! metric's rise (docs/metrics.md) happens.
//!
//! ```text
//! cargo run --release -p ragdoll-sim --example energy_trace -- [SHIFT_X_MM] [FRAMES] [--schedule SxP]
//! ```
//!
//! Prints per frame the time, the sampled energy `E` (J), the state's own energy
//! (`ParticleWorld::state_energy`) and the rise of `E` above its running minimum, then
//! the largest rise, its frame and its fraction of the energy scale. `--schedule SxP`
//! runs S substeps of P passes (`Settings::xpbd_substeps`, `Settings::xpbd_passes`).

use ragdoll_sim::Method;
use ragdoll_sim::glam::Vec3;
use ragdoll_sim::metrics::MetricsRecorder;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::{Pose, SceneDesc};
use std::process::ExitCode;

mod common;

/// The humanoid, shifted by `shift` along x.
fn figure(shift: f32) -> Result<SceneDesc, String> {
    let mut sc = common::lab_human()?;
    sc.transform(&Pose::from_position(Vec3::new(shift, 0.0, 0.0)));
    Ok(sc)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let schedule_at = args.iter().position(|a| a == "--schedule");
    let schedule = match common::xpbd_schedule(&args) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let plain: Vec<&String> = args
        .iter()
        .enumerate()
        .filter(|&(i, a)| !a.starts_with("--") && schedule_at.is_none_or(|s| i != s + 1))
        .map(|(_, a)| a)
        .collect();
    let (Ok(shift_mm), Ok(frames)) = (
        plain.first().map_or(Ok(0.0), |a| a.parse::<f32>()),
        plain.get(1).map_or(Ok(600), |a| a.parse::<usize>()),
    ) else {
        eprintln!("error: energy_trace [SHIFT_X_MM] [FRAMES] [--schedule SxP]");
        return ExitCode::FAILURE;
    };
    let mut sc = match figure(shift_mm * 1e-3) {
        Ok(sc) => sc,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    common::set_xpbd_schedule(&mut sc, schedule);
    let (mut w, mut rec) = match (
        ParticleWorld::new(&sc, ParticleSolver::Xpbd),
        MetricsRecorder::new(&sc),
    ) {
        (Ok(w), Ok(rec)) => (w, rec),
        (Err(e), _) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
        (_, Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    println!("# {}", w.solver_label());
    println!("frame t E state_E rise");
    let first = w.sample();
    rec.record(w.time(), &first);
    let (mut low, mut worst) = (first.energy, (0.0f64, 0usize));
    for f in 1..=frames {
        w.step();
        let s = w.sample();
        rec.record(w.time(), &s);
        low = low.min(s.energy);
        let rise = s.energy - low;
        if rise > worst.0 {
            worst = (rise, f);
        }
        println!(
            "{f} {:.4} {:.5} {:.5} {:.5}",
            w.time(),
            s.energy,
            w.state_energy(),
            rise
        );
    }
    let stats = rec.stats();
    println!(
        "# largest rise {:.4} J at frame {}: {:.3} % of the energy scale {:.1} J (energy_gain {:.3} %)",
        worst.0,
        worst.1,
        100.0 * worst.0 / stats.energy_scale_j,
        stats.energy_scale_j,
        100.0 * stats.energy_gain
    );
    ExitCode::SUCCESS
}
