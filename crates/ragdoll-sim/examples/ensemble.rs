//! A scene's particle method (rigid frames or XPBD), or its multibody method, from 72
//! nearby starts:
//! every body and joint anchor shifted by 0–23 mm along x, y and z in turn, 10 simulated
//! seconds each.
//!
//! ```text
//! cargo run --release -p ragdoll-sim --example ensemble -- hinge-chain 3 [--each] [--from MM] [--multibody | --xpbd [--schedule SxP]]
//! ```
//!
//! The name `lab-human` runs our Doom 3-style mod's humanoid (assets/doom3, entity
//! `monster_lab_human`, from its `af_pose` frame, as `tests/doom3_mod.rs` does).
//!
//! One start's figures are a matter of rounding in a chaotic scene (the human's sleep
//! time moves by seconds with one operation's rounding), so a solver change is judged
//! over the ensemble: the largest rise of the state's own energy
//! (`ParticleWorld::state_energy`) and of the `energy_gain` metric's frame-difference
//! measure (docs/metrics.md), both as fractions of the energy scale, how many starts
//! fall asleep and the largest joint gap, limit excess and penetration, with the medians
//! over the starts. `--each` prints every start too; `--from MM` shifts by
//! MM … MM + 23 mm instead, another 72 starts; `--multibody` runs the multibody method
//! instead, whose state energy is the sample's (its velocities are the state's own);
//! `--xpbd` the particle method's XPBD solver instead of its rigid frames; `--schedule SxP`
//! runs it at S substeps of P passes (`Settings::xpbd_substeps`, `Settings::xpbd_passes`).

use ragdoll_sim::glam::Vec3;
use ragdoll_sim::metrics::{EnergyRise, MethodStats, MetricsRecorder};
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::Pose;
use ragdoll_sim::scene::af::{AfOptions, load};
use ragdoll_sim::{Method, SceneDesc};
use std::path::PathBuf;
use std::process::ExitCode;

mod common;

/// Frames simulated per start (10 s at 1/60 s).
const FRAMES: usize = 600;

/// The scene `name` from `assets/scenes`, with `variant` applied, or the mod humanoid.
fn scene(name: &str, variant: u32) -> Result<SceneDesc, String> {
    if name == "lab-human" {
        return common::lab_human();
    }
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/scenes")
        .join(format!("{name}.af"));
    let opts = AfOptions {
        variant,
        ..Default::default()
    };
    load(&path, &opts)
        .map(|s| s.desc)
        .map_err(|e| e.to_string())
}

/// The metrics of one start (docs/metrics.md), and the largest rise of the state's own
/// energy above its running minimum as a fraction of the energy scale.
fn run(
    s: &SceneDesc,
    multibody: bool,
    solver: ParticleSolver,
) -> Result<(MethodStats, f64), String> {
    if multibody {
        // Its sample's energy is the state's: the velocities are the bodies' own.
        let w = MultibodyWorld::new(s).map_err(|e| e.to_string())?;
        measure(w, s, |w| w.sample().energy)
    } else {
        let w = ParticleWorld::new(s, solver).map_err(|e| e.to_string())?;
        measure(w, s, ParticleWorld::state_energy)
    }
}

/// Steps `w` for [`FRAMES`] frames, recording the metrics and `state_energy`.
fn measure<M: Method>(
    mut w: M,
    s: &SceneDesc,
    state_energy: impl Fn(&M) -> f64,
) -> Result<(MethodStats, f64), String> {
    let mut rec = MetricsRecorder::new(s).map_err(|e| e.to_string())?;
    let mut state = EnergyRise::default();
    rec.record(0.0, &w.sample());
    state.record(state_energy(&w));
    for _ in 0..FRAMES {
        w.step();
        rec.record(w.time(), &w.sample());
        state.record(state_energy(&w));
    }
    let stats = rec.stats();
    let state_gain = state.rise() / stats.energy_scale_j;
    Ok((stats, state_gain))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let each = args.iter().any(|a| a == "--each");
    let multibody = args.iter().any(|a| a == "--multibody");
    let solver = if args.iter().any(|a| a == "--xpbd") {
        ParticleSolver::Xpbd
    } else {
        ParticleSolver::RigidFrames
    };
    let from = match args
        .iter()
        .position(|a| a == "--from")
        .map(|i| args.get(i + 1))
    {
        None => 0,
        Some(Some(v)) if v.parse::<u32>().is_ok() => v.parse::<u32>().unwrap_or(0),
        Some(_) => {
            eprintln!("error: --from takes a whole number of millimetres");
            return ExitCode::FAILURE;
        }
    };
    let schedule = match common::xpbd_schedule(&args) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut plain = args
        .iter()
        .enumerate()
        .filter(|&(i, a)| {
            !a.starts_with("--")
                && (i == 0 || !["--from", "--schedule"].contains(&args[i - 1].as_str()))
        })
        .map(|(_, a)| a);
    let name = plain.next().map_or("hinge-chain", String::as_str);
    let variant = match plain.next().map(|v| v.parse::<u32>()) {
        None => 1,
        Some(Ok(v)) => v,
        Some(Err(e)) => {
            eprintln!("error: variant: {e}");
            return ExitCode::FAILURE;
        }
    };
    let base = match scene(name, variant) {
        Ok(mut s) => {
            common::set_xpbd_schedule(&mut s, schedule);
            s
        }
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut worst_state = (0.0f64, String::new());
    let (mut worst_frame, mut gap, mut limit, mut pen) = (0.0f64, 0.0f32, 0.0f32, 0.0f32);
    // Every start's frame-measure gain, joint gap, limit excess and penetration, for medians.
    let mut all: [Vec<f64>; 4] = Default::default();
    let (mut asleep, mut asleep_sum) = (0, 0.0);
    for (axis, label) in ["x", "y", "z"].iter().enumerate() {
        for mm in from..from + 24 {
            let mut d = Vec3::ZERO;
            d[axis] = mm as f32 * 1e-3;
            let mut start = base.clone();
            start.transform(&Pose::from_position(d));
            let (st, state_gain) = match run(&start, multibody, solver) {
                Ok(r) => r,
                Err(e) => {
                    eprintln!("error: {label} {mm} mm: {e}");
                    return ExitCode::FAILURE;
                }
            };
            if each {
                println!(
                    "{label} {mm:2} mm: state {state_gain:.4} frame {:.4} asleep {:?}",
                    st.energy_gain, st.asleep_at_s
                );
            }
            if state_gain > worst_state.0 {
                worst_state = (state_gain, format!("{label} {mm} mm"));
            }
            worst_frame = worst_frame.max(st.energy_gain);
            gap = gap.max(st.max_joint_gap_m);
            limit = limit.max(st.max_limit_violation_deg);
            pen = pen.max(st.max_penetration_m);
            for (v, x) in all.iter_mut().zip([
                st.energy_gain,
                f64::from(st.max_joint_gap_m),
                f64::from(st.max_limit_violation_deg),
                f64::from(st.max_penetration_m),
            ]) {
                v.push(x);
            }
            if let Some(t) = st.asleep_at_s {
                asleep += 1;
                asleep_sum += t;
            }
        }
    }
    println!(
        "{name} v{variant} ({}), 72 starts: energy rise (state) {:.4} at {}, (frame measure) {worst_frame:.4}; \
         asleep in {asleep}/72 (mean {:.2} s); joint gap {gap:.4} m, limit {limit:.2} deg, penetration {pen:.4} m",
        if multibody { "multibody" } else { "particle" },
        worst_state.0,
        worst_state.1,
        asleep_sum / f64::from(asleep.max(1)),
    );
    let [g, j, l, p] = all.map(|mut v| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    });
    println!(
        "  medians: energy gain (frame measure) {g:.4}, joint gap {j:.4} m, limit {l:.2} deg, penetration {p:.4} m"
    );
    ExitCode::SUCCESS
}
