use ragdoll_sim::metrics::MetricsRecorder;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::af::{load, AfOptions};
use ragdoll_sim::Method;
use std::path::PathBuf;

#[test]
fn dbg() {
    let names = ["collision", "ball-chain", "hinge-chain", "box-masses", "ball-limits", "hinge-limits", "spider", "human", "capsule-human"];
    let only: Option<String> = std::env::var("ONLY").ok();
    for (k, name) in names.iter().enumerate() {
        if only.as_ref().is_some_and(|o| o != name) { continue; }
        for variant in 1..=3u32 {
            let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes").join(format!("{name}.af"));
            let Ok(sc) = load(&path, &AfOptions { variant, ..Default::default() }) else { break };
            let mut s = sc.desc;
            if let Ok(n) = std::env::var("SUB") { s.settings.substeps = n.parse().unwrap(); }
            if let Ok(n) = std::env::var("IT") { s.settings.iterations = n.parse().unwrap(); }
            if variant > 1 && (s.variants.len() as u32) < variant { break; }
            for solver in [ParticleSolver::Improved] {
                let mut w = ParticleWorld::new(&s, solver).unwrap();
                let mut rec = MetricsRecorder::new(&s).unwrap();
                rec.record(0.0, &w.sample());
                let t0 = std::time::Instant::now();
                let frames = (10.0 / s.settings.timestep).round() as usize;
                let mut bs = Vec::new();
                for f in 0..frames { w.step(); rec.record(w.time(), &w.sample());
                    if std::env::var("VDBG").is_ok() && f % 60 == 59 { w.body_states(&mut bs); let (mut vl, mut va, mut il, mut ia) = (0.0f32, 0.0f32, 0, 0); for (i, b) in bs.iter().enumerate() { if b.linear_velocity.length() > vl { vl = b.linear_velocity.length(); il = i; } if b.angular_velocity.length() > va { va = b.angular_velocity.length(); ia = i; } } println!("b15 {} {} {}", bs[15].com, bs[15].orientation, bs[15].linear_velocity); println!("f {f} vmax {vl:.4} ({il}) wmax {va:.4} ({ia}) asleep {}", w.sample().all_asleep); }
                }
                let st = rec.stats();
                println!("{} {name} v{variant} {:?}: gain {:.4} fk {:.5} pen {:.4} gap {:.4} lim {:.2} str {:.5} asleep {:?} finite {} ({} bodies, {:?})", k+1, solver, st.energy_gain, st.final_kinetic, st.max_penetration_m, st.max_joint_gap_m, st.max_limit_violation_deg, st.max_bone_stretch.unwrap_or(0.0), st.asleep_at_s, st.finite, w.body_count(), t0.elapsed());
            }
        }
    }
}
