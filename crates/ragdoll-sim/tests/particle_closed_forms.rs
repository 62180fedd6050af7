//! The particle method against closed forms (improved mode unless said otherwise):
//! free fall, a box on a slope below and above the friction angle, a hinge pendulum's
//! period, a restitution bounce; plus determinism, robustness and bad input. Scenes are
//! built in code.

mod common;

use common::particle::{self as shared, assert_sane, boxed, chain_scene, particle_bits, scene};
use ragdoll_sim::Method;
use ragdoll_sim::glam::{Quat, Vec3};
use ragdoll_sim::particle::{ParticleSolver, ParticleWorld};
use ragdoll_sim::scene::*;

/// A thrown box follows the parabola: its centre of mass within 0.1 % of the distance
/// travelled after two seconds.
#[test]
fn free_fall_matches_parabola() {
    for solver in [ParticleSolver::RigidFrames, ParticleSolver::Paper] {
        shared::free_fall_matches_parabola(solver, Vec3::ZERO);
    }
}

/// Dropped from `h` with restitution `e` a box rebounds to `e² h` (±10 %); with `e = 0`
/// it does not bounce at all. The velocity pass sets a pressed point's normal velocity to
/// `−e v_n`, `v_n` the approach before the substep's solve, which is only evaluated on
/// manifolds that bounce.
#[test]
fn restitution_bounce_height() {
    let (h0, half) = (1.0f32, 0.1f32);
    for e in [0.7f32, 0.0] {
        let mut b = boxed("b", Vec3::splat(half), Vec3::new(0.0, half + h0, 0.0), 1.0);
        b.restitution = e;
        let s = scene(vec![b], vec![], Some(Ground::default()));
        let mut w = ParticleWorld::new(&s, ParticleSolver::RigidFrames).unwrap();
        let (mut bounced, mut apex, mut up) = (false, 0.0f32, f32::MIN);
        for _ in 0..150 {
            w.step();
            let mut out = Vec::new();
            w.body_states(&mut out);
            let (y, vy) = (out[0].com.y - half, out[0].linear_velocity.y);
            up = up.max(vy);
            bounced |= vy > 0.5;
            if bounced {
                apex = apex.max(y);
            }
        }
        if e > 0.0 {
            let expected = e * e * h0;
            assert!(bounced, "e = {e}: never bounced");
            assert!(
                (apex - expected).abs() <= 0.1 * expected,
                "e = {e}: apex {apex}, expected {expected}"
            );
        } else {
            assert!(up < 0.05, "e = 0 bounced at {up} m/s");
        }
    }
}

/// Coulomb: a box (μ = 0.5) stays on a slope below its friction angle and slides above
/// it at `a = g (sin θ − μ cos θ)`, its implied μ within 5 %.
#[test]
fn box_on_slope_sticks_below_friction_angle_and_slides_above() {
    shared::box_on_slope_sticks_below_friction_angle_and_slides_above(ParticleSolver::RigidFrames);
}

/// A rod hinged to the world at its top end swings with the rigid pendulum's period
/// `T = 2π √(I_pivot / (m g d))`, within 2 %.
#[test]
fn hinge_pendulum_period_matches_rigid_pendulum() {
    shared::hinge_pendulum_period_matches_rigid_pendulum(ParticleSolver::RigidFrames);
}

/// The same scene (a chain hit by a box) gives the same particles bit for bit, run twice.
#[test]
fn same_scene_twice_gives_identical_bits() {
    for solver in [ParticleSolver::RigidFrames, ParticleSolver::Paper] {
        let run = || particle_bits(&chain_scene(), solver, 180, None);
        assert_eq!(run(), run(), "{solver:?}");
    }
}

#[test]
fn robust_across_timesteps_and_iterations() {
    for solver in [ParticleSolver::RigidFrames, ParticleSolver::Paper] {
        for dt in [1.0 / 1000.0, 1.0 / 60.0, 1.0 / 10.0] {
            let mut s = chain_scene();
            s.settings.timestep = dt;
            // Nothing here falls more than ~4 m: free-fall speed √(2 g h) ≈ 9 m/s.
            assert_sane(s, solver, 1.5, 20.0, &format!("dt {dt}"));
        }
        for it in [1, 2, 40] {
            let mut s = chain_scene();
            s.settings.iterations = it;
            s.settings.substeps = it.min(8);
            assert_sane(s, solver, 3.0, 20.0, &format!("{it} iterations"));
        }
    }
}

#[test]
fn robust_drop_interpenetration_and_coincident_anchors() {
    for solver in [ParticleSolver::RigidFrames, ParticleSolver::Paper] {
        // A bone dropped from 100 m: at most √(2 g 100) ≈ 44 m/s, then it must stop.
        let s = scene(
            vec![boxed(
                "b",
                Vec3::new(0.3, 0.1, 0.2),
                Vec3::new(0.0, 100.0, 0.0),
                3.0,
            )],
            vec![],
            Some(Ground::default()),
        );
        assert_sane(s.clone(), solver, 6.0, 46.0, "drop from 100 m");
        if solver == ParticleSolver::RigidFrames {
            // It lands after 4.5 s and must then lie still on the ground, its centre
            // between its half-thickness (0.1 m, flat) and half-length (0.3 m, on end).
            let mut w = ParticleWorld::new(&s, solver).unwrap();
            for _ in 0..(8.0 / s.settings.timestep) as usize {
                w.step();
            }
            let mut b = Vec::new();
            w.body_states(&mut b);
            let (y, v) = (b[0].com.y, b[0].linear_velocity.length());
            assert!(
                (0.09..=0.31).contains(&y),
                "dropped bone ends at height {y}"
            );
            assert!(v < 0.05, "dropped bone still moves at {v} m/s after 8 s");
        }
        // Two bones started half inside each other, and on the ground.
        let s = scene(
            vec![
                boxed("a", Vec3::splat(0.2), Vec3::new(0.0, 0.2, 0.0), 1.0),
                boxed("b", Vec3::splat(0.2), Vec3::new(0.15, 0.3, 0.05), 1.0),
            ],
            vec![],
            Some(Ground::default()),
        );
        assert_sane(s, solver, 3.0, 10.0, "interpenetrating start");
        // A joint whose anchor is both centres: the two bones coincide.
        let s = scene(
            vec![
                boxed("a", Vec3::splat(0.2), Vec3::new(0.0, 1.0, 0.0), 1.0),
                boxed("b", Vec3::splat(0.2), Vec3::new(0.0, 1.0, 0.0), 1.0),
            ],
            vec![ConstraintDesc {
                name: "j".into(),
                body1: BodyId(1),
                body2: BodyRef::Body(BodyId(0)),
                kind: JointKind::BallAndSocket {
                    anchor: Vec3::new(0.0, 1.0, 0.0),
                    swing: None,
                    twist: None,
                    limit_style: LimitStyle::Hard,
                },
                friction: 0.0,
            }],
            Some(Ground::default()),
        );
        assert_sane(s, solver, 3.0, 10.0, "coincident anchors");
    }
}

#[test]
fn undescribable_scenes_are_clear_errors() {
    let flat = BodyDesc::new(
        "flat",
        Shape::ConvexHull {
            points: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)].into(),
        },
        Pose::IDENTITY,
        MassSpec::Density(1.0),
    );
    let err = ParticleWorld::new(
        &scene(vec![flat], vec![], None),
        ParticleSolver::RigidFrames,
    )
    .err()
    .expect("flat hull");
    assert!(err.to_string().contains("flat"), "{err}");
    let s = scene(
        vec![boxed("a", Vec3::splat(0.1), Vec3::ZERO, 1.0)],
        vec![ConstraintDesc {
            name: "self".into(),
            body1: BodyId(0),
            body2: BodyRef::Body(BodyId(0)),
            kind: JointKind::Fixed,
            friction: 0.0,
        }],
        None,
    );
    let err = ParticleWorld::new(&s, ParticleSolver::Paper)
        .err()
        .expect("self joint");
    assert!(err.to_string().contains("self"), "{err}");
}

#[test]
fn projectile_wakes_a_resting_box() {
    // A box at rest on the ground falls asleep; a world where every bone sleeps skips
    // its collision work, so the shot must still be seen and wake it.
    let s = scene(
        vec![boxed(
            "box",
            Vec3::splat(0.25),
            Vec3::new(0.0, 0.25, 0.0),
            2.0,
        )],
        vec![],
        Some(Ground::default()),
    );
    let mut w = ParticleWorld::new(&s, ParticleSolver::RigidFrames).unwrap();
    for _ in 0..180 {
        w.step();
    }
    assert!(w.sample().all_asleep, "the box should sleep within 3 s");
    let mut shot = boxed("shot", Vec3::splat(0.1), Vec3::new(-2.0, 0.3, 0.0), 5.0);
    shot.linear_velocity = Vec3::new(12.0, 0.0, 0.0);
    w.add_body(&shot);
    let mut woke = false;
    let mut states = Vec::new();
    for _ in 0..60 {
        w.step();
        w.body_states(&mut states);
        woke |= states[0].linear_velocity.length() > 0.1;
    }
    assert!(woke, "the resting box was never woken by the hit");
    assert!(states.iter().all(|b| b.com.is_finite()));
}

/// A box (0.6 × 0.4 × 0.2 m: three different inertias) spinning free of gravity and
/// air friction about `axis` (its own frame) at 6 rad/s for 10 s. Returns the worst
/// relative error of |L| and of the kinetic energy, and the largest angle between the
/// box's axis `watch` (its own frame) and where it started (rad).
fn free_spin(axis: Vec3, watch: Vec3) -> (f32, f32, f32) {
    let half = Vec3::new(0.3, 0.2, 0.1);
    let m = 2.0;
    let tilt = Quat::from_euler(ragdoll_sim::glam::EulerRot::XYZ, 0.4, -0.9, 0.2);
    let mut b = boxed("b", half, Vec3::new(0.0, 5.0, 0.0), m);
    b.pose.rotation = tilt;
    b.angular_velocity = tilt * axis.normalize() * 6.0;
    b.friction.linear = 0.0;
    b.friction.angular = 0.0;
    let mut s = scene(vec![b], vec![], None);
    s.settings.gravity = Vec3::ZERO;
    s.settings.sleep.linear_velocity = 0.0;
    s.settings.sleep.angular_velocity = 0.0;
    s.settings.sleep.translation = 0.0;
    s.settings.sleep.rotation = 0.0;
    let mut w = ParticleWorld::new(&s, ParticleSolver::RigidFrames).unwrap();
    let size = half * 2.0;
    let inertia = Vec3::new(
        size.y * size.y + size.z * size.z,
        size.x * size.x + size.z * size.z,
        size.x * size.x + size.y * size.y,
    ) * (m / 12.0);
    let state = |w: &ParticleWorld| {
        let mut out = Vec::new();
        w.body_states(&mut out);
        let local = out[0].orientation.inverse() * out[0].angular_velocity;
        let l = out[0].orientation * (inertia * local);
        (
            l,
            0.5 * local.dot(inertia * local),
            out[0].orientation * watch,
        )
    };
    let (l0, e0, a0) = state(&w);
    let (mut worst_l, mut worst_e, mut turned) = (0.0f32, 0.0f32, 0.0f32);
    for _ in 0..600 {
        w.step();
        let (l, e, a) = state(&w);
        worst_l = worst_l.max((l.length() - l0.length()).abs() / l0.length());
        worst_e = worst_e.max((e - e0).abs() / e0);
        turned = turned.max(a.angle_between(a0));
    }
    (worst_l, worst_e, turned)
}

/// Torque-free rotation: about a general axis and near each principal axis, |L| stays
/// within 1 % and the kinetic energy within 2 % over 10 s; near the major and minor axes
/// the spin stays put (the axis wobbles by less than 15°), near the intermediate axis it
/// flips (Dzhanibekov: the axis turns over, past 150°).
#[test]
fn torque_free_rotation_keeps_momentum_and_energy_and_flips_about_the_middle_axis() {
    let near = |a: Vec3| a + Vec3::new(0.02, 0.03, 0.025);
    let cases = [
        ("general", Vec3::new(1.0, 2.0, -1.5), None),
        ("near minor-inertia axis x", near(Vec3::X), Some(false)),
        ("near intermediate axis y", near(Vec3::Y), Some(true)),
        ("near major-inertia axis z", near(Vec3::Z), Some(false)),
    ];
    for (what, axis, flips) in cases {
        let watch = if axis.x.abs() > 0.9 {
            Vec3::X
        } else if axis.y.abs() > 0.9 {
            Vec3::Y
        } else {
            Vec3::Z
        };
        let (l, e, turned) = free_spin(axis, watch);
        println!(
            "{what}: |L| within {:.4} %, energy within {:.4} %, axis turned up to {:.1}°",
            l * 100.0,
            e * 100.0,
            turned.to_degrees()
        );
        assert!(l <= 0.01, "{what}: |L| off by {:.3} %", l * 100.0);
        assert!(
            e <= 0.02,
            "{what}: kinetic energy off by {:.3} %",
            e * 100.0
        );
        match flips {
            Some(true) => assert!(
                turned > 150f32.to_radians(),
                "{what}: never flipped ({:.1}°)",
                turned.to_degrees()
            ),
            Some(false) => assert!(
                turned < 15f32.to_radians(),
                "{what}: the axis wandered {:.1}°",
                turned.to_degrees()
            ),
            None => {}
        }
    }
}
