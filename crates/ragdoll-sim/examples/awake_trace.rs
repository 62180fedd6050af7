//! Which bodies keep a scene awake, frame by frame: the figure's energy and, for every
//! body over one of the scene's sleep thresholds, its speeds and which thresholds it is
//! over.
//!
//! ```text
//! cargo run --release -p ragdoll-sim --example awake_trace -- human [multibody|rigid-frames|xpbd|paper] [--every N] [--from SECONDS] [--shift AXIS MM]
//! ```
//!
//! The scene is `assets/scenes/NAME.af`; `--shift` moves it by MM millimetres along
//! axis 0, 1 or 2 (x, y, z), as the `ensemble` example's starts are moved. Every N-th
//! frame (default 6) from `--from` seconds on (default 0) prints a line
//!
//! ```text
//! t 3.400 E 216.596 J K 0.026 J  right_upper_arm v 0.051 w 0.26 [v w aa]  ...
//! ```
//!
//! with `E` the sampled total energy, `K` its kinetic part, and per body over a
//! threshold its linear and angular speed (m/s, rad/s) and the tests it fails: `v`, `w`
//! (speeds), `la`, `aa` (linear and angular acceleration from one frame to the next).
//! These are the speed and acceleration tests of `docs/metrics.md`'s sleep (Doom 3's
//! `suspendSpeed`/`suspendAcceleration`); the methods also require the body to stay
//! within `noMoveTranslation`/`noMoveRotation` of where it became still, which this
//! trace does not follow. The run ends when every body is asleep, or after 10 s.

use ragdoll_sim::scene::Pose;
use ragdoll_sim::scene::af::{AfOptions, load};
use ragdoll_sim::{BodyState, Solver};
use std::path::PathBuf;
use std::process::ExitCode;

/// Frames simulated at most (10 s at 1/60 s).
const FRAMES: usize = 600;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The value after the flag `name`, parsed.
fn flag<T: std::str::FromStr>(args: &[String], name: &str) -> Result<Option<T>, String> {
    match args.iter().position(|a| a == name) {
        None => Ok(None),
        Some(i) => args
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .map(Some)
            .ok_or_else(|| format!("{name} takes a number")),
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let every: usize = flag(&args, "--every")?.unwrap_or(6).max(1);
    let from: f64 = flag(&args, "--from")?.unwrap_or(0.0);
    let shift = match args.iter().position(|a| a == "--shift") {
        None => None,
        Some(i) => {
            let axis: usize = args
                .get(i + 1)
                .and_then(|v| v.parse().ok())
                .filter(|&a| a < 3)
                .ok_or("--shift takes an axis 0, 1 or 2 and millimetres")?;
            let mm: f32 = args
                .get(i + 2)
                .and_then(|v| v.parse().ok())
                .ok_or("--shift takes an axis 0, 1 or 2 and millimetres")?;
            Some((axis, mm))
        }
    };
    // Positional arguments: those that are neither flags nor a flag's values.
    let mut skip = 0;
    let mut plain = Vec::new();
    for a in &args {
        if skip > 0 {
            skip -= 1;
        } else if a == "--shift" {
            skip = 2;
        } else if a.starts_with("--") {
            skip = 1;
        } else {
            plain.push(a.as_str());
        }
    }
    let name = plain.first().copied().unwrap_or("human");
    let solver_name = plain.get(1).copied().unwrap_or("multibody");
    let solver = Solver::ALL
        .into_iter()
        .find(|s| s.name() == solver_name)
        .ok_or_else(|| format!("unknown solver {solver_name}"))?;
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/scenes")
        .join(format!("{name}.af"));
    let mut scene = load(&path, &AfOptions::default())
        .map_err(|e| e.to_string())?
        .desc;
    if let Some((axis, mm)) = shift {
        let mut d = ragdoll_sim::glam::Vec3::ZERO;
        d[axis] = mm * 1e-3;
        scene.transform(&Pose::from_position(d));
    }
    let names: Vec<String> = scene.bodies.iter().map(|b| b.name.clone()).collect();
    let mut world = solver.build(&scene).map_err(|e| e.to_string())?;
    let sleep = world.settings().sleep;
    let dt = f64::from(world.settings().timestep);
    let mut before: Vec<BodyState> = Vec::new();
    let mut now: Vec<BodyState> = Vec::new();
    world.body_states(&mut before);
    for frame in 1..=FRAMES {
        world.step();
        world.body_states(&mut now);
        let sample = world.sample();
        if world.time() + 0.5 * dt >= from && frame % every == 0 {
            let mut line = format!(
                "t {:.3} E {:.3} J K {:.3} J ",
                world.time(),
                sample.energy,
                sample.kinetic
            );
            for (i, (b, p)) in now.iter().zip(&before).enumerate() {
                let (v, w) = (b.linear_velocity.length(), b.angular_velocity.length());
                let la = f64::from((b.linear_velocity - p.linear_velocity).length()) / dt;
                let aa = f64::from((b.angular_velocity - p.angular_velocity).length()) / dt;
                let over: Vec<&str> = [
                    (v > sleep.linear_velocity, "v"),
                    (w > sleep.angular_velocity, "w"),
                    (la > f64::from(sleep.linear_acceleration), "la"),
                    (aa > f64::from(sleep.angular_acceleration), "aa"),
                ]
                .into_iter()
                .filter_map(|(over, tag)| over.then_some(tag))
                .collect();
                if !over.is_empty() {
                    line += &format!(" {} v {v:.3} w {w:.2} [{}]", names[i], over.join(" "));
                }
            }
            println!("{line}");
        }
        if sample.all_asleep {
            println!("all asleep at {:.3} s", world.time());
            return Ok(());
        }
        std::mem::swap(&mut before, &mut now);
    }
    println!("awake after {:.3} s", world.time());
    Ok(())
}
