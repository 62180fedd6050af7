use ragdoll_sim::glam::{Quat, Vec3};
use ragdoll_sim::metrics::MetricsRecorder;
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::*;
use ragdoll_sim::Method;

fn boxed(name: &str, half: Vec3, pos: Vec3, mass: f32) -> BodyDesc {
    BodyDesc::new(name, Shape::Box { half_extents: half }, Pose::from_position(pos), MassSpec::Density(mass))
}
fn spider() -> SceneDesc {
    let mut bodies = vec![boxed("body", Vec3::splat(0.2), Vec3::new(0.0, 1.5, 0.0), 500.0)];
    let mut cs = vec![];
    for (k, dir) in [Vec3::X, Vec3::Z, -Vec3::X, -Vec3::Z].iter().enumerate() {
        let rot = Quat::from_rotation_arc(Vec3::X, *dir);
        let up = bodies.len();
        let mut u = boxed(&format!("upper{k}"), Vec3::new(0.3, 0.05, 0.05), Vec3::new(0.0, 1.5, 0.0) + *dir * 0.5, 500.0);
        u.pose.rotation = rot;
        bodies.push(u);
        let mut l = boxed(&format!("lower{k}"), Vec3::new(0.05, 0.3, 0.05), Vec3::new(0.0, 1.5 - 0.35, 0.0) + *dir * 0.75, 500.0);
        l.pose.rotation = rot;
        bodies.push(l);
        cs.push(ConstraintDesc { name: format!("hip{k}"), body1: BodyId(up as u32), body2: BodyRef::Body(BodyId(0)),
            kind: JointKind::BallAndSocket { anchor: Vec3::new(0.0, 1.5, 0.0) + *dir * 0.2, swing: None, twist: None, limit_style: LimitStyle::Hard }, friction: 0.0 });
        cs.push(ConstraintDesc { name: format!("knee{k}"), body1: BodyId(up as u32 + 1), body2: BodyRef::Body(BodyId(up as u32)),
            kind: JointKind::Hinge { anchor: Vec3::new(0.0, 1.5 - 0.05, 0.0) + *dir * 0.75, axis: dir.cross(Vec3::Y), limit: None }, friction: 0.0 });
    }
    let mut s = SceneDesc { name: "spider".into(), bodies, constraints: cs, ..Default::default() };
    s.settings.ground = Some(Ground::default());
    s
}
#[test]
fn dbg() {
    for solver in [ParticleSolver::Improved, ParticleSolver::Paper] {
        let s = spider();
        let mut w = ParticleWorld::new(&s, solver).unwrap();
        let mut rec = MetricsRecorder::new(&s).unwrap();
        rec.record(0.0, &w.sample());
        let t0 = std::time::Instant::now();
        for i in 0..600 { w.step(); let sm = w.sample(); rec.record(w.time(), &sm); if i % 60 == 0 { println!("{i} E {:.2} K {:.3} pen {:.4} gap {:.4} lim {:.1} st {:?} asleep {}", sm.energy, sm.kinetic, sm.max_penetration, sm.max_joint_gap, sm.max_limit_violation_deg, sm.max_bone_stretch, sm.all_asleep); } }
        println!("{solver:?} {:?} {:?}", rec.stats(), t0.elapsed());
    }
}
