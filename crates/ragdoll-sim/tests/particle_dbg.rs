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
            for solver in [ParticleSolver::Improved, ParticleSolver::Paper] {
                let mut w = ParticleWorld::new(&s, solver).unwrap();
                let mut rec = MetricsRecorder::new(&s).unwrap();
                rec.record(0.0, &w.sample());
                let t0 = std::time::Instant::now();
                let frames = (10.0 / s.settings.timestep).round() as usize;
                let mut bs = Vec::new();
                let mut smin = f64::INFINITY; let mut sgain = 0.0f64; let mut emin = f64::INFINITY; let mut prevgain = 0.0; for f in 0..frames { w.step(); let sm = w.sample(); rec.record(w.time(), &sm); emin = emin.min(sm.energy); let se = w.state_energy(); smin = smin.min(se); if std::env::var("PENDBG").is_ok() && sm.max_penetration > 0.01 { println!("p f {f} pen {:.4}", sm.max_penetration); }
                    if std::env::var("SDBG").is_ok() && (se - smin > sgain + 1.0 || (22..=30).contains(&f)) { println!("s f {f} Es {se:.2} rise {:.2} K {:.2} pen {:.4} gap {:.4}", se - smin, sm.kinetic, sm.max_penetration, sm.max_joint_gap); } sgain = sgain.max(se - smin); if std::env::var("EDBG").is_ok() && (sm.energy - emin > prevgain + 0.5 || (f >= 18 && f <= 32)) { prevgain = sm.energy - emin; println!("e f {f} E {:.3} K {:.3} rise {:.3} pen {:.4}", sm.energy, sm.kinetic, prevgain, sm.max_penetration); }
                    if std::env::var("VDBG").is_ok() && f % 60 == 59 { w.body_states(&mut bs); let (mut vl, mut va, mut il, mut ia) = (0.0f32, 0.0f32, 0, 0); for (i, b) in bs.iter().enumerate() { if b.linear_velocity.length() > vl { vl = b.linear_velocity.length(); il = i; } if b.angular_velocity.length() > va { va = b.angular_velocity.length(); ia = i; } } println!("b15 {} {} {}", bs[1].com, bs[1].orientation, bs[1].linear_velocity); println!("f {f} vmax {vl:.4} ({il}) wmax {va:.4} ({ia}) asleep {}", w.sample().all_asleep); }
                }
                let st = rec.stats();
                println!("{} {name} v{variant} {:?}: sgain {:.4} gain {:.4} fk {:.5} pen {:.4} gap {:.4} lim {:.2} str {:.5} asleep {:?} finite {} ({} bodies, {:?})", k+1, solver, sgain / st.energy_scale_j, st.energy_gain, st.final_kinetic, st.max_penetration_m, st.max_joint_gap_m, st.max_limit_violation_deg, st.max_bone_stretch.unwrap_or(0.0), st.asleep_at_s, st.finite, w.body_count(), t0.elapsed());
            }
        }
    }
}
