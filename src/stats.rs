//! `ragdoll-lab stats`: run a scene headless and print the metrics (`docs/metrics.md`)
//! as one JSON object; `--trace FILE` also writes every frame as JSON lines
//! (`docs/cli.md`).

use crate::cli::{MethodArg, ParticleSolverArg, StatsArgs};
use crate::{AppError, methods, scenes};
use ragdoll_sim::metrics::{MethodStats, MetricsRecorder};
use ragdoll_sim::scene::scene_mass_props;
use ragdoll_sim::{BodyState, Method, Sample, SceneDesc};
use serde_json::{Value, json};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug)]
pub struct StatsOptions {
    /// Simulated seconds.
    pub seconds: f64,
    /// Which methods.
    pub method: MethodArg,
    /// The particle method's solver.
    pub particle_solver: ParticleSolverArg,
}

/// One method's result.
#[derive(Clone, Debug)]
pub struct MethodReport {
    /// The method's own description of its solver.
    pub solver: String,
    /// Bodies simulated.
    pub bodies: usize,
    /// Particles simulated (0 for multibody).
    pub particles: usize,
    /// The metrics.
    pub stats: MethodStats,
    /// Mean wall-clock time of one step (ms).
    pub step_ms_mean: f64,
}

/// The whole `stats` result.
#[derive(Clone, Debug)]
pub struct StatsReport {
    /// Scene name.
    pub scene: String,
    /// Variant run.
    pub variant: u32,
    /// Simulated seconds.
    pub seconds: f64,
    /// Frame (step) length (s).
    pub frame_dt: f64,
    /// Particle method result, if run.
    pub particle: Option<MethodReport>,
    /// Multibody method result, if run.
    pub multibody: Option<MethodReport>,
}

impl MethodReport {
    fn to_json(&self) -> Value {
        let s = &self.stats;
        json!({
            "solver": self.solver,
            "bodies": self.bodies,
            "particles": self.particles,
            "energy_scale_j": s.energy_scale_j,
            "energy_gain": s.energy_gain,
            "energy_loss": s.energy_loss,
            "max_body_speed_mps": s.max_body_speed_mps,
            "final_kinetic": s.final_kinetic,
            "max_penetration_m": s.max_penetration_m,
            "max_joint_gap_m": s.max_joint_gap_m,
            "max_limit_violation_deg": s.max_limit_violation_deg,
            "max_bone_stretch": s.max_bone_stretch,
            "asleep_at_s": s.asleep_at_s,
            "step_ms_mean": self.step_ms_mean,
            "finite": s.finite,
        })
    }
}

impl StatsReport {
    /// The JSON object `stats` prints.
    pub fn to_json(&self) -> Value {
        let mut methods = serde_json::Map::new();
        if let Some(p) = &self.particle {
            methods.insert("particle".into(), p.to_json());
        }
        if let Some(m) = &self.multibody {
            methods.insert("multibody".into(), m.to_json());
        }
        json!({
            "scene": self.scene,
            "variant": self.variant,
            "seconds": self.seconds,
            "frame_dt": self.frame_dt,
            "methods": methods,
        })
    }
}

fn v3(v: glam::Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

fn trace_header(scene: &SceneDesc) -> Result<Value, AppError> {
    let props = scene_mass_props(scene)?;
    let bodies: Vec<Value> = scene
        .bodies
        .iter()
        .zip(&props)
        .map(|(b, mp)| {
            let i = mp.inertia;
            json!({
                "name": b.name,
                "mass": mp.mass,
                "fixed": b.is_fixed(),
                "inertia": [i.row(0).to_array(), i.row(1).to_array(), i.row(2).to_array()],
            })
        })
        .collect();
    Ok(json!({"type": "header", "scene": scene.name, "variant": scene.variant, "bodies": bodies}))
}

fn trace_frame(
    method: &dyn Method,
    sample: &Sample,
    states: &mut Vec<BodyState>,
    particles: &mut Vec<glam::Vec3>,
) -> Value {
    method.body_states(states);
    method.particle_positions(particles);
    let bodies: Vec<Value> = states
        .iter()
        .map(|s| {
            json!({
                "com": v3(s.com),
                "orientation": [s.orientation.x, s.orientation.y, s.orientation.z, s.orientation.w],
                "linear_velocity": v3(s.linear_velocity),
                "angular_velocity": v3(s.angular_velocity),
            })
        })
        .collect();
    let mut frame = json!({
        "type": "frame",
        "method": method.kind().name(),
        "t": method.time(),
        "energy": sample.energy,
        "kinetic": sample.kinetic,
        "bodies": bodies,
    });
    if !particles.is_empty() {
        frame["particles"] = Value::Array(particles.iter().map(|p| v3(*p)).collect());
    }
    frame
}

/// Runs the scene for `opts.seconds` and measures; writes the trace if asked.
pub fn measure(
    scene: &SceneDesc,
    opts: &StatsOptions,
    trace: Option<&Path>,
) -> Result<StatsReport, AppError> {
    let dt = scene.settings.timestep as f64;
    let frames = (opts.seconds / dt).round().max(0.0) as usize;
    let mut runs: Vec<(Box<dyn Method>, MetricsRecorder, f64)> = Vec::new();
    if matches!(opts.method, MethodArg::Particle | MethodArg::Both) {
        let m = methods::build_particle(scene, opts.particle_solver)?;
        runs.push((m, MetricsRecorder::new(scene)?, 0.0));
    }
    if matches!(opts.method, MethodArg::Multibody | MethodArg::Both) {
        let m = methods::build_multibody(scene)?;
        runs.push((m, MetricsRecorder::new(scene)?, 0.0));
    }
    let mut trace_out = match trace {
        Some(path) => {
            let f = File::create(path).map_err(|source| AppError::Io {
                path: path.display().to_string(),
                source,
            })?;
            let mut w = BufWriter::new(f);
            writeln!(w, "{}", trace_header(scene)?).map_err(|source| AppError::Io {
                path: path.display().to_string(),
                source,
            })?;
            Some((w, path))
        }
        None => None,
    };
    let mut states = Vec::new();
    let mut particles = Vec::new();
    for (m, rec, _) in runs.iter_mut() {
        rec.record(m.time(), &m.sample());
        m.body_states(&mut states);
        rec.record_speeds(&states);
    }
    for _ in 0..frames {
        for (m, rec, ms) in runs.iter_mut() {
            let t0 = Instant::now();
            m.step();
            *ms += t0.elapsed().as_secs_f64() * 1e3;
            let sample = m.sample();
            rec.record(m.time(), &sample);
            m.body_states(&mut states);
            rec.record_speeds(&states);
            if let Some((w, path)) = trace_out.as_mut() {
                writeln!(
                    w,
                    "{}",
                    trace_frame(m.as_ref(), &sample, &mut states, &mut particles)
                )
                .map_err(|source| AppError::Io {
                    path: path.display().to_string(),
                    source,
                })?;
            }
        }
    }
    if let Some((mut w, path)) = trace_out {
        w.flush().map_err(|source| AppError::Io {
            path: path.display().to_string(),
            source,
        })?;
    }
    let mut report = StatsReport {
        scene: scene.name.clone(),
        variant: scene.variant,
        seconds: frames as f64 * dt,
        frame_dt: dt,
        particle: None,
        multibody: None,
    };
    for (m, rec, ms) in runs {
        let r = MethodReport {
            solver: m.solver_label(),
            bodies: m.body_count(),
            particles: m.particle_count(),
            stats: rec.stats(),
            step_ms_mean: if frames > 0 { ms / frames as f64 } else { 0.0 },
        };
        match m.kind() {
            ragdoll_sim::MethodKind::Particle => report.particle = Some(r),
            ragdoll_sim::MethodKind::Multibody => report.multibody = Some(r),
        }
    }
    Ok(report)
}

/// `ragdoll-lab stats`.
pub fn run(args: StatsArgs) -> Result<(), AppError> {
    if !(args.seconds.is_finite() && args.seconds >= 0.0) {
        return Err(AppError::Usage(format!(
            "--seconds must be a non-negative number, got {}",
            args.seconds
        )));
    }
    // With --anim, the ragdoll takes over from its --at frame.
    let mut loaded = scenes::load(&args.scene)?.taken_over();
    let s = &mut loaded.desc.settings;
    if let Some(dt) = args.timestep {
        s.timestep = dt;
    }
    if let Some(it) = args.iterations {
        // An override is for both methods, whatever the scene gave the multibody one.
        s.iterations = it;
        s.multibody_iterations = None;
    }
    if let Some(n) = args.substeps {
        // An override is for both methods, whatever the scene gave the multibody one.
        s.substeps = n;
        s.multibody_substeps = None;
    }
    ragdoll_sim::scene::validate(&loaded.desc)?;
    let opts = StatsOptions {
        seconds: args.seconds,
        method: args.method,
        particle_solver: args.particle_solver,
    };
    let report = measure(&loaded.desc, &opts, args.trace.as_deref())?;
    println!("{}", report.to_json());
    Ok(())
}
