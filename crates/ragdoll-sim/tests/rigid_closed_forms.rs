//! The multibody method against closed forms: free fall, friction on a slope, a hinge
//! pendulum's period, a spinning box's angular momentum, a restitution bounce.

use ragdoll_sim::glam::{Quat, Vec3};
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::*;
use ragdoll_sim::{BodyState, Method};

fn cube(name: &str, half: f32, pos: Vec3, mass: f32) -> BodyDesc {
    BodyDesc::new(
        name,
        Shape::Box {
            half_extents: Vec3::splat(half),
        },
        Pose::from_position(pos),
        MassSpec::Mass(mass),
    )
}

fn scene(bodies: Vec<BodyDesc>, ground: Option<Ground>) -> SceneDesc {
    SceneDesc {
        name: "test".into(),
        bodies,
        settings: Settings {
            ground,
            ..Settings::default()
        },
        ..SceneDesc::default()
    }
}

fn state(w: &MultibodyWorld, i: usize) -> BodyState {
    let mut out = Vec::new();
    w.body_states(&mut out);
    out[i]
}

#[test]
fn free_fall_matches_closed_form() {
    // Semi-implicit Euler with substep h: y(t) = y0 − g t²/2 − g h t/2 exactly.
    let sc = scene(vec![cube("b", 0.1, Vec3::new(0.0, 10.0, 0.0), 1.0)], None);
    let mut w = MultibodyWorld::new(&sc).unwrap();
    let steps = 60;
    for _ in 0..steps {
        w.step();
    }
    let t = steps as f32 / 60.0;
    let h = sc.settings.timestep / sc.settings.substeps as f32;
    let y = 10.0 - 0.5 * 9.81 * t * t - 0.5 * 9.81 * h * t;
    let s = state(&w, 0);
    assert!((s.com.y - y).abs() < 1e-3, "y {} expected {}", s.com.y, y);
    assert!((s.linear_velocity.y + 9.81 * t).abs() < 1e-3);
}

/// A box resting on a slope of angle θ with μ: returns its acceleration along the slope
/// measured between t = 0.5 s and 1.5 s.
fn slope_acceleration(theta: f32, mu: f32) -> f32 {
    let ground = Ground {
        tilt: theta,
        friction: mu,
        ..Ground::default()
    };
    let n = ground.normal();
    let half = 0.1;
    let mut b = cube("b", half, n * (half + 1e-4), 1.0);
    b.pose.rotation = Quat::from_rotation_z(theta);
    b.friction.contact = mu;
    let mut sc = scene(vec![b], Some(ground));
    sc.settings.sleep.time = 1e9; // keep it awake: we measure a slide
    let mut w = MultibodyWorld::new(&sc).unwrap();
    let down = Vec3::new(-theta.cos(), -theta.sin(), 0.0); // along the slope, downhill
    for _ in 0..30 {
        w.step();
    }
    let v0 = state(&w, 0).linear_velocity.dot(down);
    for _ in 0..60 {
        w.step();
    }
    let v1 = state(&w, 0).linear_velocity.dot(down);
    v1 - v0
}

#[test]
fn box_on_slope_holds_below_friction_angle() {
    let mu = 0.6f32; // friction angle 31°
    let a = slope_acceleration(20f32.to_radians(), mu);
    assert!(a.abs() < 0.01, "box slid with a = {a}");
}

#[test]
fn box_on_slope_slides_above_friction_angle() {
    let mu = 0.3f32; // friction angle 16.7°
    let theta = 30f32.to_radians();
    let a = slope_acceleration(theta, mu);
    let expected = 9.81 * (theta.sin() - mu * theta.cos());
    assert!(
        (a - expected).abs() < 0.05 * expected,
        "a = {a}, expected {expected}"
    );
}

#[test]
fn hinge_pendulum_small_angle_period() {
    // A small cube on a hinge 1 m above its centre: physical pendulum,
    // T = 2π sqrt(I_pivot / (m g L)), I_pivot = m (L² + a²/6) for a cube of edge a.
    let (l, half) = (1.0f32, 0.05f32);
    let theta0 = 0.05f32;
    let pivot = Vec3::new(0.0, 2.0, 0.0);
    let mut b = cube(
        "bob",
        half,
        pivot + Vec3::new(theta0.sin(), -theta0.cos(), 0.0) * l,
        1.0,
    );
    b.pose.rotation = Quat::from_rotation_z(theta0);
    let mut sc = scene(vec![b], None);
    sc.constraints.push(ConstraintDesc {
        name: "hinge".into(),
        body1: BodyId(0),
        body2: BodyRef::World,
        kind: JointKind::Hinge {
            anchor: pivot,
            axis: Vec3::Z,
            limit: None,
        },
        friction: 0.0,
    });
    sc.settings.sleep.time = 1e9;
    let a = 2.0 * half;
    let period = 2.0 * std::f32::consts::PI * ((l * l + a * a / 6.0) / (9.81 * l)).sqrt();
    let mut w = MultibodyWorld::new(&sc).unwrap();
    // Time the downward zero crossings of x by linear interpolation.
    let dt = sc.settings.timestep as f64;
    let mut crossings = Vec::new();
    let mut prev = state(&w, 0).com.x;
    for k in 1..=(10.0 / dt) as usize {
        w.step();
        let x = state(&w, 0).com.x;
        if prev > 0.0 && x <= 0.0 {
            crossings.push((k as f64 - 1.0 + prev as f64 / (prev - x) as f64) * dt);
        }
        prev = x;
    }
    assert!(crossings.len() >= 4);
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let err = (measured - period as f64).abs() / period as f64;
    assert!(err < 0.01, "period {measured} s, theory {period} s");
}

#[test]
fn spinning_box_keeps_angular_momentum() {
    // A box spinning about an axis off its principal axes (near the major one, so the
    // motion is a stable precession), no gravity: L = R I Rᵀ ω is conserved exactly;
    // the turn with L held should keep it within 1 % for 10 s.
    let mut b = BodyDesc::new(
        "spinner",
        Shape::Box {
            half_extents: Vec3::new(0.1, 0.3, 0.5),
        },
        Pose::from_position(Vec3::ZERO),
        MassSpec::Mass(2.0),
    );
    b.angular_velocity = Vec3::new(3.0, 0.3, 0.2);
    let mut sc = scene(vec![b.clone()], None);
    sc.settings.gravity = Vec3::ZERO;
    sc.settings.sleep.time = 1e9;
    let mp = mass_props(&b).unwrap();
    let momentum = |s: &BodyState| {
        let r = ragdoll_sim::glam::Mat3::from_quat(s.orientation);
        (r * mp.inertia * r.transpose()) * s.angular_velocity
    };
    let mut w = MultibodyWorld::new(&sc).unwrap();
    let l0 = momentum(&state(&w, 0));
    for _ in 0..600 {
        w.step();
        let l = momentum(&state(&w, 0));
        assert!(
            (l - l0).length() < 0.01 * l0.length(),
            "L drifted from {l0} to {l}"
        );
    }
}

#[test]
fn restitution_bounce_height() {
    // Dropped from h with restitution e the box rebounds to e² h (±10 %).
    let (h0, e, half) = (1.0f32, 0.7f32, 0.1f32);
    let mut b = cube("ball", half, Vec3::new(0.0, half + h0, 0.0), 1.0);
    b.restitution = e;
    let sc = scene(vec![b], Some(Ground::default()));
    let mut w = MultibodyWorld::new(&sc).unwrap();
    let mut bounced = false;
    let mut apex = 0.0f32;
    for _ in 0..150 {
        w.step();
        let s = state(&w, 0);
        if s.linear_velocity.y > 0.5 {
            bounced = true;
        }
        if bounced {
            apex = apex.max(s.com.y - half);
        }
    }
    let expected = e * e * h0;
    assert!(bounced);
    assert!(
        (apex - expected).abs() < 0.1 * expected,
        "apex {apex}, expected {expected}"
    );
}

fn joint(kind: JointKind, body2: BodyRef) -> ConstraintDesc {
    ConstraintDesc {
        name: "j".into(),
        body1: BodyId(0),
        body2,
        kind,
        friction: 0.0,
    }
}

#[test]
fn spring_oscillates_with_its_natural_period() {
    // A mass hanging on a vertical spring from the world: T = 2π sqrt(m / k).
    let (m, k) = (2.0f32, 200.0f32);
    let top = Vec3::new(0.0, 5.0, 0.0);
    let rest = 1.0;
    let stretch0 = m * 9.81 / k + 0.05; // 5 cm below equilibrium
    let b = cube("bob", 0.05, top - Vec3::Y * (rest + stretch0), m);
    let mut sc = scene(vec![b], None);
    sc.settings.sleep.time = 1e9;
    sc.constraints.push(joint(
        JointKind::Spring {
            anchor1: top - Vec3::Y * (rest + stretch0),
            anchor2: top,
            stretch: k,
            compress: k,
            damping: 0.0,
            rest_length: rest,
            min_length: 0.0,
            max_length: 0.0,
        },
        BodyRef::World,
    ));
    let period = 2.0 * std::f64::consts::PI * (m as f64 / k as f64).sqrt();
    let eq = top.y - rest - m * 9.81 / k;
    let mut w = MultibodyWorld::new(&sc).unwrap();
    let dt = sc.settings.timestep as f64;
    let mut up = Vec::new();
    let mut prev = state(&w, 0).com.y - eq;
    for step in 1..=300 {
        w.step();
        let y = state(&w, 0).com.y - eq;
        if prev < 0.0 && y >= 0.0 {
            up.push((step as f64 - 1.0 + (-prev / (y - prev)) as f64) * dt);
        }
        prev = y;
    }
    assert!(up.len() >= 3);
    let measured = (up[up.len() - 1] - up[0]) / (up.len() - 1) as f64;
    assert!(
        (measured - period).abs() < 0.02 * period,
        "period {measured}, theory {period}"
    );
}

#[test]
fn slider_moves_only_along_its_axis() {
    // On a frictionless 30° rail (a slider to the world) a box accelerates at g sin θ.
    let theta = 30f32.to_radians();
    let axis = Vec3::new(theta.cos(), -theta.sin(), 0.0);
    let b = cube("carriage", 0.1, Vec3::new(0.0, 3.0, 0.0), 1.0);
    let mut sc = scene(vec![b], None);
    sc.constraints
        .push(joint(JointKind::Slider { axis }, BodyRef::World));
    let mut w = MultibodyWorld::new(&sc).unwrap();
    for _ in 0..60 {
        w.step();
    }
    let s = state(&w, 0);
    let v_along = s.linear_velocity.dot(axis);
    let expected = 9.81 * theta.sin();
    assert!(
        (v_along - expected).abs() < 0.02 * expected,
        "v {v_along}, expected {expected}"
    );
    let off = s.com - Vec3::new(0.0, 3.0, 0.0);
    assert!(
        (off - axis * off.dot(axis)).length() < 2e-3,
        "left the rail by {}",
        (off - axis * off.dot(axis)).length()
    );
    assert!(s.angular_velocity.length() < 1e-2);
}

#[test]
fn universal_joint_transmits_twist() {
    // Body1 hangs from a fixed body2 on a universal joint; spinning body1 about the
    // vertical shaft must drag nothing (body2 is fixed) and be stopped: no twist allowed.
    let mut post = cube("post", 0.1, Vec3::new(0.0, 3.0, 0.0), 1.0);
    post.motion = Motion::Fixed;
    let mut arm = cube("arm", 0.1, Vec3::new(0.0, 2.7, 0.0), 1.0);
    arm.angular_velocity = Vec3::new(0.0, 5.0, 0.0);
    let mut sc = scene(vec![arm, post], None);
    sc.constraints.push(joint(
        JointKind::Universal {
            anchor: Vec3::new(0.0, 2.85, 0.0),
            shaft1: Vec3::X,
            shaft2: Vec3::Z,
            swing: None,
            axis_ranges: None,
        },
        BodyRef::Body(BodyId(1)),
    ));
    let mut w = MultibodyWorld::new(&sc).unwrap();
    for _ in 0..60 {
        w.step();
        let s = state(&w, 0);
        assert!(
            s.angular_velocity.y.abs() < 0.1,
            "twisting at {}",
            s.angular_velocity.y
        );
    }
    assert!(w.sample().max_joint_gap < 2e-3);
}
