//! The checks the particle solvers share, written once and run per solver: the closed
//! forms of `particle_closed_forms.rs` (rigid-frames, paper) and `xpbd_closed_forms.rs`,
//! and the scene thresholds of `particle_scenes.rs` and `xpbd_scenes.rs`.

use super::shipped_variant;
use ragdoll_sim::glam::{Quat, Vec3};
use ragdoll_sim::metrics::{EnergyRise, MethodStats, MetricsRecorder};
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::*;
use ragdoll_sim::{BodyState, Method};

/// A dynamic box of half extents `half` centred at `pos`.
pub fn boxed(name: &str, half: Vec3, pos: Vec3, mass: f32) -> BodyDesc {
    super::boxed(name, half, pos, mass)
}

/// A scene of `bodies` and `constraints` with default settings and the given ground.
pub fn scene(
    bodies: Vec<BodyDesc>,
    constraints: Vec<ConstraintDesc>,
    ground: Option<Ground>,
) -> SceneDesc {
    let mut s = SceneDesc {
        name: "test".into(),
        bodies,
        constraints,
        ..Default::default()
    };
    s.settings.ground = ground;
    s
}

/// Body `i`'s state now.
pub fn state(w: &ParticleWorld, i: usize) -> BodyState {
    let mut out = Vec::new();
    w.body_states(&mut out);
    out[i]
}

/// A thrown box (turning at `spin` rad/s) follows the parabola: its centre of mass
/// within 0.1 % of the distance travelled after two seconds.
pub fn free_fall_matches_parabola(solver: ParticleSolver, spin: Vec3) {
    let mut b = boxed(
        "b",
        Vec3::new(0.2, 0.1, 0.3),
        Vec3::new(0.0, 50.0, 0.0),
        2.0,
    );
    b.linear_velocity = Vec3::new(1.0, 3.0, -0.5);
    b.angular_velocity = spin;
    b.pose.rotation = Quat::from_rotation_x(0.3);
    let s = scene(vec![b.clone()], vec![], None);
    let mut w = ParticleWorld::new(&s, solver).unwrap();
    let x0 = state(&w, 0).com;
    for _ in 0..120 {
        w.step();
    }
    let t = w.time() as f32;
    let expected = x0 + b.linear_velocity * t + s.settings.gravity * (0.5 * t * t);
    let err = (state(&w, 0).com - expected).length();
    let travelled = (expected - x0).length();
    assert!(
        err <= 1e-3 * travelled,
        "{solver:?}: error {err} m over {travelled} m"
    );
}

/// A box on a ground tilted by `deg`, μ = 0.5 (friction angle 26.57°): the distance it
/// moved down the slope in `seconds`.
pub fn slide(solver: ParticleSolver, deg: f32, seconds: f32) -> f32 {
    let tilt = deg.to_radians();
    let ground = Ground {
        tilt,
        friction: 0.5,
        ..Default::default()
    };
    let n = ground.normal();
    let half = Vec3::new(0.2, 0.1, 0.2);
    let mut b = boxed("b", half, n * (half.y + 0.001), 1.0);
    b.pose.rotation = Quat::from_rotation_z(tilt);
    b.friction.contact = 0.5;
    let s = scene(vec![b], vec![], Some(ground));
    let mut w = ParticleWorld::new(&s, solver).unwrap();
    let x0 = state(&w, 0).com;
    let frames = (seconds / s.settings.timestep).round() as usize;
    for _ in 0..frames {
        w.step();
    }
    let down = Vec3::new(-tilt.cos(), -tilt.sin(), 0.0);
    (state(&w, 0).com - x0).dot(down)
}

/// Coulomb: the box stays below the friction angle (under 1 cm in 2 s at 20°) and
/// slides above it at `a = g (sin θ − μ cos θ)`, compared through the friction
/// coefficient the slide implies, `μ_eff = (sin θ − 2 d / (g t²)) / cos θ`, within 5 %
/// of μ: the distance itself amplifies a friction error by (μ cos θ)/(sin θ − μ cos θ)
/// (3.5× at 35°), so a 3 % friction error reads as a 10 % distance error.
pub fn box_on_slope_sticks_below_friction_angle_and_slides_above(solver: ParticleSolver) {
    let still = slide(solver, 20.0, 2.0);
    assert!(
        still.abs() < 0.01,
        "{solver:?}: moved {still} m at 20° (below 26.6°)"
    );
    let (deg, t) = (35.0f32, 1.0f32);
    let th = deg.to_radians();
    let moved = slide(solver, deg, t);
    let expected = 0.5 * 9.81 * (th.sin() - 0.5 * th.cos()) * t * t;
    let mu_eff = (th.sin() - 2.0 * moved / (9.81 * t * t)) / th.cos();
    println!("{solver:?} 35°: slid {moved} m (closed form {expected} m), μ_eff {mu_eff}");
    assert!(
        moved > 0.5 * expected,
        "{solver:?}: did not slide: {moved} m"
    );
    assert!(
        (mu_eff - 0.5).abs() < 0.05 * 0.5,
        "{solver:?}: μ_eff {mu_eff} (slid {moved} m, closed form {expected} m)"
    );
}

/// A rod hinged to the world at its top end, 5° from the vertical, swings with the
/// rigid pendulum's period `T = 2π √(I_pivot / (m g d))`, within 2 % (zero crossings of
/// its horizontal offset, interpolated, over ten seconds). Its energy over the ten
/// seconds prints, against the swing's own, `m g d (1 − cos 5°)`.
pub fn hinge_pendulum_period_matches_rigid_pendulum(solver: ParticleSolver) {
    let half = Vec3::new(0.05, 0.5, 0.05);
    let m = 1.0;
    let amp = 5f32.to_radians();
    let pivot = Vec3::new(0.0, 3.0, 0.0);
    let rot = Quat::from_rotation_z(amp);
    let mut b = boxed("rod", half, pivot + rot * Vec3::new(0.0, -half.y, 0.0), m);
    b.pose.rotation = rot;
    let c = super::hinge("hinge", 0, None, pivot, Vec3::Z, None);
    let s = scene(vec![b], vec![c], None);
    let mut w = ParticleWorld::new(&s, solver).unwrap();
    let d = half.y;
    let i_cm = m / 12.0 * ((2.0 * half.x).powi(2) + (2.0 * half.y).powi(2));
    let expected = 2.0 * std::f32::consts::PI * ((i_cm + m * d * d) / (m * 9.81 * d)).sqrt();
    let mut crossings = Vec::new();
    let mut prev = state(&w, 0).com.x;
    let dt = s.settings.timestep;
    let e0 = w.sample().energy;
    let swing = e0 - (m as f64) * 9.81 * (pivot.y - d) as f64;
    let (mut e_min, mut e_max) = (e0, e0);
    for k in 1..=600 {
        w.step();
        let x = state(&w, 0).com.x;
        if prev > 0.0 && x <= 0.0 || prev < 0.0 && x >= 0.0 {
            crossings.push((k as f32 - 1.0 + prev / (prev - x)) * dt);
        }
        prev = x;
        let e = w.sample().energy;
        e_min = e_min.min(e);
        e_max = e_max.max(e);
    }
    assert!(
        crossings.len() >= 5,
        "{solver:?}: only {} crossings",
        crossings.len()
    );
    let n = crossings.len() - 1;
    let period = 2.0 * (crossings[n] - crossings[0]) / n as f32;
    println!(
        "{solver:?}: period {period} s, rigid {expected} s; energy of the swing {swing} J, range {} .. {} J",
        e_min - e0,
        e_max - e0
    );
    assert!(
        (period - expected).abs() < 0.02 * expected,
        "{solver:?}: period {period} s, rigid {expected} s"
    );
}

/// Three boxes on ball joints hanging from a fixed box, raised sideways, and a fourth
/// dropped on them: joints, contacts and the ground all at work.
pub fn chain_scene() -> SceneDesc {
    let half = Vec3::new(0.1, 0.25, 0.1);
    let mut top = boxed("top", half, Vec3::new(0.0, 3.0, 0.0), 1.0);
    top.motion = Motion::Fixed;
    let mut bodies = vec![top];
    let mut constraints = vec![];
    for i in 1..4 {
        let (x, y) = (0.5 * i as f32, 3.0 - 0.25);
        bodies.push(boxed(
            &format!("link{i}"),
            Vec3::new(0.25, 0.1, 0.1),
            Vec3::new(x - 0.15, y, 0.0),
            1.0,
        ));
        constraints.push(ConstraintDesc {
            name: format!("j{i}"),
            body1: BodyId(i),
            body2: BodyRef::Body(BodyId(i - 1)),
            kind: JointKind::BallAndSocket {
                anchor: Vec3::new(x - 0.4, y, 0.0),
                swing: None,
                twist: None,
                limit_style: LimitStyle::Hard,
            },
            friction: 0.0,
        });
    }
    bodies.push(boxed(
        "dropped",
        Vec3::splat(0.1),
        Vec3::new(1.0, 4.0, 0.05),
        1.0,
    ));
    scene(bodies, constraints, Some(Ground::default()))
}

/// Every particle's bits after `frames` frames of `s`, stepped in a pool of `threads`
/// threads, or (`None`) in rayon's global pool.
pub fn particle_bits(
    s: &SceneDesc,
    solver: ParticleSolver,
    frames: usize,
    threads: Option<usize>,
) -> Vec<u32> {
    let run = || {
        let mut w = ParticleWorld::new(s, solver).unwrap();
        for _ in 0..frames {
            w.step();
        }
        let mut p = Vec::new();
        w.particle_positions(&mut p);
        p.iter()
            .flat_map(|v| v.to_array())
            .map(f32::to_bits)
            .collect()
    };
    match threads {
        Some(threads) => rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(run),
        None => run(),
    }
}

/// Runs `seconds` of `s`: every particle finite, no body faster than `vmax` m/s and the
/// energy finite, every frame.
pub fn assert_sane(mut s: SceneDesc, solver: ParticleSolver, seconds: f32, vmax: f32, what: &str) {
    let frames = (seconds / s.settings.timestep).ceil() as usize;
    s.name = what.into();
    let mut w = ParticleWorld::new(&s, solver).unwrap();
    let (mut p, mut states) = (Vec::new(), Vec::new());
    for f in 0..frames {
        w.step();
        w.particle_positions(&mut p);
        assert!(
            p.iter().all(|x| x.is_finite()),
            "{what} ({solver:?}): not finite at frame {f}"
        );
        w.body_states(&mut states);
        let v = states
            .iter()
            .map(|b| b.linear_velocity.length())
            .fold(0.0, f32::max);
        assert!(v <= vmax, "{what} ({solver:?}): {v} m/s at frame {f}");
        assert!(
            w.sample().energy.is_finite(),
            "{what} ({solver:?}): energy not finite"
        );
    }
}

/// The scene table, in the README's order (scene N is `SCENES[N - 1]`).
pub const SCENES: [&str; 10] = [
    "collision",
    "ball-chain",
    "hinge-chain",
    "box-masses",
    "ball-limits",
    "hinge-limits",
    "spider",
    "human",
    "capsule-human",
    "pile",
];

/// What `ragdoll-lab stats --method particle --particle-solver S --seconds T`
/// measures, plus the largest rise of the state's own energy (see
/// `ParticleWorld::state_energy`) over the scene's energy scale, and the world at the end.
pub fn run_scene(
    s: &SceneDesc,
    solver: ParticleSolver,
    seconds: f64,
) -> (MethodStats, f64, ParticleWorld) {
    let mut w = ParticleWorld::new(s, solver).unwrap_or_else(|e| panic!("{}: {e}", s.name));
    let mut rec = MetricsRecorder::new(s).unwrap();
    let mut state = EnergyRise::default();
    rec.record(0.0, &w.sample());
    state.record(w.state_energy());
    let frames = (seconds / s.settings.timestep as f64).round() as usize;
    for _ in 0..frames {
        w.step();
        rec.record(w.time(), &w.sample());
        state.record(w.state_energy());
    }
    let stats = rec.stats();
    let state_gain = state.rise() / stats.energy_scale_j;
    (stats, state_gain, w)
}

/// Scene `n` (1-based) run for 10 s by `solver` against the scene thresholds (energy
/// gain ≤ 2 %, penetration ≤ 1 cm, joint gap ≤ 5 mm, limit excess ≤ 3°, bone stretch
/// ≤ 1 %; the spider, the human and the capsule human (with the obstacle it kicks
/// away, which rolling resistance stops) asleep with no kinetic energy left; with
/// `bound_state_energy` also the state's own energy gain ≤ 2 %), on variants
/// `variants` (`None`: every one): the failures.
pub fn scene_failures(
    solver: ParticleSolver,
    n: usize,
    variants: Option<&[u32]>,
    bound_state_energy: bool,
) -> Vec<String> {
    let name = SCENES[n - 1];
    let mut failures = Vec::new();
    let all: Vec<u32> = (1..=shipped_variant(name, 1).variants.len().max(1) as u32).collect();
    for &v in variants.unwrap_or(&all) {
        let (st, state_gain, _) = run_scene(&shipped_variant(name, v), solver, 10.0);
        println!(
            "{solver:?} scene {n} {name} v{v}: energy_gain {:.4} (state {:.4}) final_kinetic {:.2e} penetration {:.4} m joint_gap {:.4} m limit {:.2}° stretch {:.1e} asleep_at {:?}",
            st.energy_gain,
            state_gain,
            st.final_kinetic,
            st.max_penetration_m,
            st.max_joint_gap_m,
            st.max_limit_violation_deg,
            st.max_bone_stretch.unwrap_or(0.0),
            st.asleep_at_s
        );
        let mut check = |ok: bool, what: String| {
            if !ok {
                failures.push(format!("scene {n} {name} v{v}: {what}"));
            }
        };
        check(st.finite, "not finite".into());
        check(
            st.energy_gain <= 0.02,
            format!("energy_gain {}", st.energy_gain),
        );
        if bound_state_energy {
            check(
                state_gain <= 0.02,
                format!("state energy gain {state_gain}"),
            );
        }
        check(
            st.max_penetration_m <= 0.01,
            format!("max_penetration_m {}", st.max_penetration_m),
        );
        check(
            st.max_joint_gap_m <= 0.005,
            format!("max_joint_gap_m {}", st.max_joint_gap_m),
        );
        check(
            st.max_limit_violation_deg <= 3.0,
            format!("max_limit_violation_deg {}", st.max_limit_violation_deg),
        );
        check(
            st.max_bone_stretch.is_some_and(|s| s <= 0.01),
            format!("max_bone_stretch {:?}", st.max_bone_stretch),
        );
        if (7..=9).contains(&n) {
            check(
                st.final_kinetic <= 1e-3,
                format!("final_kinetic {}", st.final_kinetic),
            );
            check(st.asleep_at_s.is_some(), "never asleep".into());
        }
    }
    failures
}
