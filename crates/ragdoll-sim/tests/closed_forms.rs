//! The closed-form suite: every solver offered as an improvement, against properties
//! whose answer is known without running a solver (an exact pendulum period, Coulomb's
//! slide, free fall, conserved momentum, Euler's torque-free rotation, a roll stopped by
//! rolling resistance) and against scenes written from a description (stacks, a 100:1
//! chain, a 50 m/s impact, bodies that start overlapping or outside a joint limit).
//!
//! Each property is one function taking the solver's constructor; [`suite!`] turns the
//! list of properties into one `#[test]` per property and solver, named
//! `<solver>::<property>`. A new solver is one more `suite!` block. A property a solver
//! does not meet yet is marked `#[ignore]` with the figure it measured, never passed
//! with a looser bound.

mod common;

use common::*;
use ragdoll_sim::glam::{Mat3, Quat, Vec3};
use ragdoll_sim::metrics::MetricsRecorder;
use ragdoll_sim::scene::*;
use std::f32::consts::PI;

// ---------------------------------------------------------------------------------
// Pendulum: a 10 cm cube whose centre hangs d = 1 m below a frictionless world hinge.
// ---------------------------------------------------------------------------------

/// The arithmetic–geometric mean of `a` and `b`.
fn agm(mut a: f64, mut b: f64) -> f64 {
    while (a - b).abs() > 1e-15 * a {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    a
}

/// The complete elliptic integral of the first kind, `K(k) = π / (2 AGM(1, √(1 − k²)))`.
fn elliptic_k(k: f64) -> f64 {
    std::f64::consts::PI / (2.0 * agm(1.0, (1.0 - k * k).sqrt()))
}

/// Period and swing-energy loss of a physical pendulum released at `theta0`.
///
/// Exact period: `T = 4 K(sin(θ₀/2)) / ω₀` with `ω₀ = √(m g d / I_pivot)`,
/// `I_pivot = I_cm + m d²`, `I_cm = m (a² + a²)/12` for a cube of edge a about its face
/// normal. The period is timed between upward zero crossings of the angle over 10 s;
/// the energy lost is the largest fall of E = ½mv² + ½ωᵀIω + m g y below its start, over
/// the swing energy m g d (1 − cos θ₀).
fn pendulum(make: Make, theta0_deg: f32) {
    let theta0 = theta0_deg.to_radians();
    let (d, half, m, g) = (1.0f32, 0.05f32, 1.0f32, 9.81f32);
    let pivot = Vec3::new(0.0, 3.0, 0.0);
    let mut bob = cube(
        "bob",
        half,
        pivot + d * Vec3::new(theta0.sin(), -theta0.cos(), 0.0),
        m,
    );
    bob.pose.rotation = Quat::from_rotation_z(theta0);
    let mut sc = scene(vec![bob], None);
    sc.constraints
        .push(hinge("pivot", 0, None, pivot, Vec3::Z, None));
    let i_pivot = m * (2.0 * half * 2.0 * half) / 6.0 + m * d * d;
    let omega0 = ((m * g * d) as f64 / i_pivot as f64).sqrt();
    let exact = 4.0 * elliptic_k((theta0 as f64 / 2.0).sin()) / omega0;
    let swing = (m * g * d * (1.0 - theta0.cos())) as f64;

    let mut w = make(&sc);
    let dt = sc.settings.timestep as f64;
    let inertia = inertias(&sc);
    let e0 = energy(&w.body_states_vec(), &sc, &inertia);
    let angle = |s: &ragdoll_sim::BodyState| (s.com.x - pivot.x).atan2(pivot.y - s.com.y);
    let mut prev = angle(&w.body_states_vec()[0]);
    let mut crossings = Vec::new();
    let mut lost = 0.0f64;
    for k in 1..=(10.0 / dt).round() as usize {
        w.step();
        let st = w.body_states_vec();
        lost = lost.max(e0 - energy(&st, &sc, &inertia));
        let a = angle(&st[0]);
        if prev < 0.0 && a >= 0.0 {
            crossings.push((k as f64 - 1.0 + (-prev / (a - prev)) as f64) * dt);
        }
        prev = a;
    }
    assert!(
        crossings.len() >= 3,
        "{} zero crossings in 10 s",
        crossings.len()
    );
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let err = (measured - exact).abs() / exact;
    eprintln!(
        "pendulum {theta0_deg}°: period {measured:.5} s (exact {exact:.5}), lost {:.3} %",
        100.0 * lost / swing
    );
    assert!(
        err <= 0.005,
        "period {measured:.5} s, exact {exact:.5} s ({:.2} % off)",
        100.0 * err
    );
    assert!(
        lost <= 0.01 * swing,
        "lost {:.2} % of the swing energy in 10 s",
        100.0 * lost / swing
    );
}

fn pendulum_at_5_degrees_keeps_its_exact_period_and_energy(make: Make) {
    pendulum(make, 5.0);
}

fn pendulum_at_60_degrees_keeps_its_exact_period_and_energy(make: Make) {
    pendulum(make, 60.0);
}

// ---------------------------------------------------------------------------------
// Torque-free rotation of a box with three distinct moments, no gravity.
// ---------------------------------------------------------------------------------

/// Half extents (0.05, 0.1, 0.2) m, 1 kg: I = m/3 (b² + c²) per axis, so
/// I_x = 0.0167 (major), I_y = 0.0142 (intermediate), I_z = 0.0042 kg·m² (minor).
const SPINNER_HALF: Vec3 = Vec3::new(0.05, 0.1, 0.2);

/// Spins the box at body-frame angular velocity `omega` for 10 s. |L| (L = R I Rᵀ ω,
/// conserved exactly without torque) within 1 % and kinetic energy ½ωᵀIω within 2 % at
/// every frame. Returns the smallest cosine between the body's Y axis and the initial L
/// direction (−1: the intermediate axis turned over).
fn torque_free(make: Make, omega: Vec3) -> f32 {
    let mut b = boxed("spinner", SPINNER_HALF, Vec3::new(0.0, 1.0, 0.0), 1.0);
    b.angular_velocity = omega;
    let mut sc = scene(vec![b], None);
    sc.settings.gravity = Vec3::ZERO;
    let inertia = inertias(&sc)[0];
    let momentum = |s: &ragdoll_sim::BodyState| {
        let r = Mat3::from_quat(s.orientation);
        (r * inertia * r.transpose()) * s.angular_velocity
    };
    let mut w = make(&sc);
    let s0 = w.body_states_vec()[0];
    let l0 = momentum(&s0);
    let k0 = 0.5 * s0.angular_velocity.dot(momentum(&s0));
    let (mut worst_l, mut worst_k, mut min_cos) = (0.0f32, 0.0f32, 1.0f32);
    for _ in 0..600 {
        w.step();
        let s = w.body_states_vec()[0];
        let l = momentum(&s);
        worst_l = worst_l.max((l.length() - l0.length()).abs() / l0.length());
        worst_k = worst_k.max((0.5 * s.angular_velocity.dot(l) - k0).abs() / k0);
        min_cos = min_cos.min((s.orientation * Vec3::Y).dot(l0.normalize()));
    }
    eprintln!(
        "torque-free {omega}: |L| {:.3} %, KE {:.3} %, min cos {min_cos:.3}",
        100.0 * worst_l,
        100.0 * worst_k
    );
    assert!(worst_l <= 0.01, "|L| off by {:.2} %", 100.0 * worst_l);
    assert!(
        worst_k <= 0.02,
        "kinetic energy off by {:.2} %",
        100.0 * worst_k
    );
    min_cos
}

fn torque_free_rotation_about_a_general_axis_keeps_l_and_energy(make: Make) {
    torque_free(make, Vec3::new(2.0, 3.0, 4.0));
}

fn torque_free_rotation_near_the_major_axis_keeps_l_and_energy(make: Make) {
    torque_free(make, Vec3::new(5.0, 0.05, 0.05));
}

fn torque_free_rotation_near_the_minor_axis_keeps_l_and_energy(make: Make) {
    torque_free(make, Vec3::new(0.05, 0.05, 5.0));
}

/// Near the intermediate axis the spin is unstable (Dzhanibekov): a perturbation grows
/// as e^{λt}, λ = Ω √((I_y − I_z)(I_x − I_y) / (I_x I_z)) = 0.6 Ω here, so from 1 % at
/// Ω = 3 rad/s the body turns over in about 2.6 s and back again.
fn torque_free_rotation_near_the_intermediate_axis_flips_and_keeps_l_and_energy(make: Make) {
    let min_cos = torque_free(make, Vec3::new(0.03, 3.0, 0.03));
    assert!(min_cos < -0.9, "no flip: cos(Y, L) stayed ≥ {min_cos:.3}");
}

// ---------------------------------------------------------------------------------
// Free fall, Coulomb friction.
// ---------------------------------------------------------------------------------

/// A box dropped from 10 m without ground falls ½ g t² in t = 1 s, within 1 %.
fn free_fall_drops_half_g_t_squared(make: Make) {
    let sc = scene(vec![cube("b", 0.1, Vec3::new(0.0, 10.0, 0.0), 1.0)], None);
    let mut w = make(&sc);
    for _ in 0..60 {
        w.step();
    }
    let t = 60.0 * sc.settings.timestep;
    let exact = 0.5 * 9.81 * t * t;
    let s = w.body_states_vec()[0];
    let drop = 10.0 - s.com.y;
    assert!(
        (drop - exact).abs() <= 0.01 * exact,
        "fell {drop} m, ½gt² = {exact} m"
    );
    let v = -s.linear_velocity.y;
    assert!(
        (v - 9.81 * t).abs() <= 0.01 * 9.81 * t,
        "speed {v}, gt = {}",
        9.81 * t
    );
}

/// The angle (degrees) the body turned about `n` from `q0` to `q` (swing–twist split).
fn turn_about(q0: Quat, q: Quat, n: Vec3) -> f32 {
    let r = q * q0.inverse();
    let twist = 2.0 * Vec3::new(r.x, r.y, r.z).dot(n).atan2(r.w);
    let twist = if twist > PI { twist - 2.0 * PI } else { twist };
    twist.abs().to_degrees()
}

/// A 20 cm cube on ground tilted by `theta_deg` with μ = `mu` (body and ground), started
/// at rest touching it (or at `v0` m/s along the slope). Returns (distance along the
/// slope, largest turn about the normal in degrees) after `seconds`.
fn slide(make: Make, theta_deg: f32, mu: f32, v0: f32, seconds: f32) -> (f32, f32) {
    let theta = theta_deg.to_radians();
    let ground = Ground {
        tilt: theta,
        friction: mu,
        ..Ground::default()
    };
    let n = ground.normal();
    let down = Vec3::new(-theta.cos(), -theta.sin(), 0.0);
    let half = 0.1;
    let mut b = cube("b", half, n * half, 1.0);
    b.pose.rotation = Quat::from_rotation_z(theta);
    b.friction.contact = mu;
    b.linear_velocity = down * v0;
    let sc = scene(vec![b], Some(ground));
    let mut w = make(&sc);
    let s0 = w.body_states_vec()[0];
    let mut turn = 0.0f32;
    for _ in 0..(seconds / sc.settings.timestep).round() as usize {
        w.step();
        let s = w.body_states_vec()[0];
        turn = turn.max(turn_about(s0.orientation, s.orientation, n));
    }
    let s = w.body_states_vec()[0];
    ((s.com - s0.com).dot(down), turn)
}

/// Coulomb's slide from rest: d = ½ g (sin θ − μ cos θ) t², within 2 %; no turn.
fn slope_slide(make: Make, theta_deg: f32) {
    let (mu, t) = (0.5f32, 2.0f32);
    let theta = theta_deg.to_radians();
    let exact = 0.5 * 9.81 * (theta.sin() - mu * theta.cos()) * t * t;
    let (d, turn) = slide(make, theta_deg, mu, 0.0, t);
    eprintln!("slope {theta_deg}°: {d:.4} m (Coulomb {exact:.4}), turn {turn:.3}°");
    assert!(
        (d - exact).abs() <= 0.02 * exact,
        "slid {d:.4} m, Coulomb {exact:.4} m ({:+.2} %)",
        100.0 * (d - exact) / exact
    );
    assert!(turn < 0.5, "turned {turn:.2}° about the normal");
}

fn box_slides_down_35_degrees_as_coulomb_says_without_turning(make: Make) {
    slope_slide(make, 35.0);
}

fn box_slides_down_45_degrees_as_coulomb_says_without_turning(make: Make) {
    slope_slide(make, 45.0);
}

/// Launched at v₀ = 5 m/s on flat ground with μ = 0.5, the box stops after
/// v₀² / (2 μ g) = 2.55 m (within 2 %), without turning.
fn box_sliding_on_flat_ground_stops_where_coulomb_says(make: Make) {
    let (mu, v0) = (0.5f32, 5.0f32);
    let exact = v0 * v0 / (2.0 * mu * 9.81);
    let (d, turn) = slide(make, 0.0, mu, v0, 2.0);
    assert!(
        (d - exact).abs() <= 0.02 * exact,
        "slid {d:.4} m, Coulomb {exact:.4} m"
    );
    assert!(turn < 0.5, "turned {turn:.2}° about the normal");
}

/// A capsule (radius r = 10 cm, core 20 cm, 1 kg) lying on flat ground, rolling at
/// v₀ = 0.3 m/s about its axis without slipping. Rolling resistance (`scene::rolling`)
/// resists with a torque ρ r m g: `m a = −f`, `I α = f r − ρ r m g`, `a = α r` give a
/// uniform deceleration a = ρ g / (1 + I / (m r²)), I about the capsule's axis, so it
/// stops after v₀² / (2a) (1.3 m, in 8.8 s). Sleep is off, so the stop is the
/// solver's. The speed at 1 s and 5 s gives the deceleration within 3 %, the stop
/// distance is within 3 %, it rolls (|ω| r within 2 % of v at 3 s), and it is at rest
/// by 12 s.
fn capsule_rolling_on_flat_ground_stops_where_rolling_resistance_says(make: Make) {
    let (r, half_height, m, v0, g) = (0.1f32, 0.1f32, 1.0f32, 0.3f32, 9.81f32);
    // The capsule's axis (its local Y) along world Z; it rolls along +X, spinning
    // about −Z: the contact point at the bottom is still, v + ω × (−r ŷ) = 0.
    let mut b = BodyDesc::new(
        "roller",
        Shape::Capsule {
            half_height,
            radius: r,
        },
        Pose {
            position: Vec3::new(0.0, r, 0.0),
            rotation: Quat::from_rotation_x(0.5 * PI),
        },
        MassSpec::Mass(m),
    );
    b.linear_velocity = Vec3::new(v0, 0.0, 0.0);
    b.angular_velocity = Vec3::new(0.0, 0.0, -v0 / r);
    let mut sc = scene(vec![b], Some(Ground::default()));
    sc.settings.sleep.disable();
    let axis_inertia = inertias(&sc)[0].y_axis.y;
    let a = ROLLING_RESISTANCE * g / (1.0 + axis_inertia / (m * r * r));
    let exact = v0 * v0 / (2.0 * a);
    let mut w = make(&sc);
    let x0 = w.body_states_vec()[0].com.x;
    let dt = sc.settings.timestep;
    let (mut v1, mut v5, mut roll3) = (0.0f32, 0.0f32, (0.0f32, 0.0f32));
    for k in 1..=(12.0 / dt).round() as usize {
        w.step();
        let s = w.body_states_vec()[0];
        let t = k as f32 * dt;
        if (t - 1.0).abs() < 0.5 * dt {
            v1 = s.linear_velocity.x;
        }
        if (t - 3.0).abs() < 0.5 * dt {
            roll3 = (s.linear_velocity.x, s.angular_velocity.length() * r);
        }
        if (t - 5.0).abs() < 0.5 * dt {
            v5 = s.linear_velocity.x;
        }
    }
    let s = w.body_states_vec()[0];
    let d = s.com.x - x0;
    let measured = (v1 - v5) / 4.0;
    eprintln!(
        "rolling capsule: deceleration {measured:.5} m/s² (exact {a:.5}), stopped after \
         {d:.4} m (exact {exact:.4}), v {:.4} and ωr {:.4} m/s at 3 s, at 12 s {:.2e} m/s",
        roll3.0,
        roll3.1,
        s.linear_velocity.length()
    );
    assert!(
        (measured - a).abs() <= 0.03 * a,
        "decelerated at {measured:.5} m/s², rolling resistance says {a:.5} ({:+.1} %)",
        100.0 * (measured - a) / a
    );
    assert!(
        (d - exact).abs() <= 0.03 * exact,
        "stopped after {d:.4} m, rolling resistance says {exact:.4} m ({:+.1} %)",
        100.0 * (d - exact) / exact
    );
    assert!(
        (roll3.1 - roll3.0).abs() <= 0.02 * roll3.0,
        "at 3 s v = {:.4} m/s but ω r = {:.4} m/s: not rolling",
        roll3.0,
        roll3.1
    );
    assert!(
        s.linear_velocity.length() < 1e-3 && s.angular_velocity.length() * r < 1e-3,
        "still moving at 12 s: {:.4} m/s, {:.4} rad/s",
        s.linear_velocity.length(),
        s.angular_velocity.length()
    );
}

/// tan 20° = 0.36 < μ = 0.5: static friction holds; the box creeps < 1 mm in 2 s.
fn box_on_20_degrees_with_mu_half_holds(make: Make) {
    let (d, _) = slide(make, 20.0, 0.5, 0.0, 2.0);
    assert!(d.abs() < 1e-3, "crept {:.2} mm", 1e3 * d.abs());
}

// ---------------------------------------------------------------------------------
// Resting contact, stacks.
// ---------------------------------------------------------------------------------

/// Runs `sc` for `seconds`, returning the deepest penetration sampled and the largest
/// sink and sideways drift of body `watch` from its start.
fn rest(make: Make, sc: &SceneDesc, watch: usize, seconds: f32) -> (f32, f32, f32) {
    let mut w = make(sc);
    let p0 = w.body_states_vec()[watch].com;
    let (mut pen, mut sink, mut drift) = (0.0f32, 0.0f32, 0.0f32);
    for _ in 0..(seconds / sc.settings.timestep).round() as usize {
        w.step();
        pen = pen.max(w.sample().max_penetration);
        let p = w.body_states_vec()[watch].com;
        sink = sink.max(p0.y - p.y);
        drift = drift.max(Vec3::new(p.x - p0.x, 0.0, p.z - p0.z).length());
    }
    (pen, sink, drift)
}

/// A 20 cm cube placed on the ground: over 10 s, penetration ≤ 1 mm, drift ≤ 1 mm.
fn box_at_rest_stays_put(make: Make) {
    let sc = scene(
        vec![cube("b", 0.1, Vec3::new(0.0, 0.1, 0.0), 1.0)],
        Some(Ground::default()),
    );
    let (pen, sink, drift) = rest(make, &sc, 0, 10.0);
    assert!(pen <= 1e-3, "penetration {:.2} mm", 1e3 * pen);
    let moved = sink.max(drift);
    assert!(moved <= 1e-3, "drifted {:.2} mm", 1e3 * moved);
}

fn stack(make: Make, n: usize) {
    let bodies = (0..n)
        .map(|i| {
            cube(
                &format!("b{i}"),
                0.1,
                Vec3::new(0.0, 0.1 + 0.2 * i as f32, 0.0),
                1.0,
            )
        })
        .collect();
    let sc = scene(bodies, Some(Ground::default()));
    let (_, sink, drift) = rest(make, &sc, n - 1, 10.0);
    eprintln!(
        "stack {n}: sink {:.2} mm, drift {:.2} mm",
        1e3 * sink,
        1e3 * drift
    );
    assert!(sink < 0.01, "top box sank {:.2} mm", 1e3 * sink);
    assert!(drift < 0.005, "top box drifted {:.2} mm", 1e3 * drift);
}

fn stack_of_5_boxes_stands(make: Make) {
    stack(make, 5);
}

fn stack_of_10_boxes_stands(make: Make) {
    stack(make, 10);
}

// ---------------------------------------------------------------------------------
// The 100:1 chain: a 50 kg box hanging from five 0.5 kg links.
// ---------------------------------------------------------------------------------

/// Five 20 cm links (0.5 kg) and a 20 cm cube (50 kg) on ball joints from a world
/// anchor at (0, 3, 0), the whole chain turned by `tilt` about Z around the anchor.
/// Nominal length from the anchor to the cube's centre: 1.1 m.
fn heavy_chain(tilt: f32) -> SceneDesc {
    let top = Vec3::new(0.0, 3.0, 0.0);
    let rot = Quat::from_rotation_z(tilt);
    let at = |depth: f32| top + rot * Vec3::new(0.0, -depth, 0.0);
    let mut bodies = Vec::new();
    let mut constraints = Vec::new();
    for i in 0..5 {
        let mut l = boxed(
            &format!("link{i}"),
            Vec3::new(0.02, 0.1, 0.02),
            at(0.1 + 0.2 * i as f32),
            0.5,
        );
        l.pose.rotation = rot;
        bodies.push(l);
    }
    let mut heavy = cube("heavy", 0.1, at(1.1), 50.0);
    heavy.pose.rotation = rot;
    bodies.push(heavy);
    for b in &mut bodies {
        b.self_collision = false;
    }
    for i in 0..6 {
        let parent = if i == 0 { None } else { Some(i - 1) };
        constraints.push(ball(&format!("j{i}"), i, parent, at(0.2 * i as f32)));
    }
    let mut sc = scene(bodies, None);
    sc.constraints = constraints;
    sc
}

/// Largest joint gap and largest relative change of the anchor–cube distance in 5 s.
fn chain_run(make: Make, tilt: f32) {
    let sc = heavy_chain(tilt);
    let top = Vec3::new(0.0, 3.0, 0.0);
    let mut w = make(&sc);
    let (mut gap, mut stretch) = (0.0f32, 0.0f32);
    for _ in 0..300 {
        w.step();
        gap = gap.max(w.sample().max_joint_gap);
        let len = (w.body_states_vec()[5].com - top).length();
        stretch = stretch.max((len - 1.1).abs() / 1.1);
    }
    eprintln!(
        "chain tilt {tilt}: gap {:.2} mm, length {:.3} %",
        1e3 * gap,
        100.0 * stretch
    );
    assert!(gap <= 0.002, "joint gap {:.2} mm", 1e3 * gap);
    assert!(stretch <= 0.005, "length off by {:.2} %", 100.0 * stretch);
}

fn chain_of_mass_ratio_100_hangs_without_gaps(make: Make) {
    chain_run(make, 0.0);
}

fn chain_of_mass_ratio_100_swings_without_gaps(make: Make) {
    chain_run(make, 40f32.to_radians());
}

// ---------------------------------------------------------------------------------
// Impacts and momentum.
// ---------------------------------------------------------------------------------

/// A 20 cm cube hits a fixed wall face-on at 50 m/s (no gravity): it never passes the
/// wall's face, and comes away with spin < 0.5 rad/s and sideways speed < 0.1 m/s.
fn box_hitting_a_wall_at_50_m_s_stays_face_on(make: Make) {
    let mut wall = boxed(
        "wall",
        Vec3::new(0.1, 2.0, 2.0),
        Vec3::new(0.0, 1.0, 0.0),
        100.0,
    );
    wall.motion = Motion::Fixed;
    let mut b = cube("b", 0.1, Vec3::new(-2.0, 1.0, 0.0), 1.0);
    b.linear_velocity = Vec3::new(50.0, 0.0, 0.0);
    let mut sc = scene(vec![b, wall], None);
    sc.settings.gravity = Vec3::ZERO;
    let mut w = make(&sc);
    let (mut spin, mut side, mut furthest) = (0.0f32, 0.0f32, f32::MIN);
    for _ in 0..60 {
        w.step();
        let s = w.body_states_vec()[0];
        furthest = furthest.max(s.com.x);
        spin = spin.max(s.angular_velocity.length());
        side = side.max(Vec3::new(0.0, s.linear_velocity.y, s.linear_velocity.z).length());
    }
    // Centre at most the wall's half thickness + the box's half size in front of x = 0,
    // less a centimetre of contact give.
    assert!(
        furthest <= -0.2 + 0.01,
        "centre reached x = {furthest:.3} m (tunnelled)"
    );
    eprintln!("wall: furthest {furthest:.3} m, spin {spin:.3} rad/s, sideways {side:.3} m/s");
    assert!(spin < 0.5, "spin {spin:.3} rad/s");
    assert!(side < 0.1, "sideways {side:.3} m/s");
}

/// A 1 kg cube at 10 m/s hits a free 5 kg plate off centre (no gravity): linear and
/// angular momentum (about the origin) stay within 1 % of their start.
fn free_plate_hit_off_centre_keeps_momentum(make: Make) {
    let plate = boxed("plate", Vec3::new(0.5, 0.025, 0.5), Vec3::ZERO, 5.0);
    let mut b = cube("b", 0.1, Vec3::new(0.3, 0.6, 0.2), 1.0);
    b.linear_velocity = Vec3::new(0.0, -10.0, 0.0);
    let mut sc = scene(vec![plate, b], None);
    sc.settings.gravity = Vec3::ZERO;
    let inertia = inertias(&sc);
    let masses = [5.0f32, 1.0];
    let momenta = |st: &[ragdoll_sim::BodyState]| {
        let mut p = Vec3::ZERO;
        let mut l = Vec3::ZERO;
        for (i, s) in st.iter().enumerate() {
            let r = Mat3::from_quat(s.orientation);
            p += masses[i] * s.linear_velocity;
            l += s.com.cross(masses[i] * s.linear_velocity)
                + (r * inertia[i] * r.transpose()) * s.angular_velocity;
        }
        (p, l)
    };
    let mut w = make(&sc);
    let (p0, l0) = momenta(&w.body_states_vec());
    let mut hit = false;
    for _ in 0..60 {
        w.step();
        let st = w.body_states_vec();
        hit |= st[0].linear_velocity.length() > 0.1;
        let (p, l) = momenta(&st);
        assert!((p - p0).length() <= 0.01 * p0.length(), "P {p0} → {p}");
        assert!((l - l0).length() <= 0.01 * l0.length(), "L {l0} → {l}");
    }
    assert!(hit, "the cube never reached the plate");
}

// ---------------------------------------------------------------------------------
// Starting overlaps and joints outside their limits.
// ---------------------------------------------------------------------------------

/// Spacing of f32 numbers at `x`: the finest step a position stored or reported in f32
/// can take there.
fn f32_spacing(x: f32) -> f64 {
    let a = x.abs();
    (f32::from_bits(a.to_bits() + 1) - a) as f64
}

/// Runs `sc` 3 s, returning the largest rate at which `gap(states)` grew over a frame
/// (m/s) beyond what its reading can resolve, the largest body speed and the largest
/// distance any body got from its start.
///
/// `gap` returns the gap (m) from the f32 positions of the bodies, in f64 — the
/// difference of two f32 numbers is exact there, where in f32 it rounds again — and the
/// sum of the f32 spacings of the positions it read (m). A solver keeps or reports a
/// body's position in f32, so a frame's motion lands on that grid: rounded to the
/// nearest f32, the position is within half a spacing of where the solver aimed it,
/// and the overlap the solver aimed from (measured on the f32 position the frame began
/// at) carries one more such rounding. A frame's growth of the gap is therefore read
/// against `limit × dt` to within one spacing of each position read: the returned rate
/// is the largest `(growth − spacing) / dt`, at most `limit` for a solver that holds
/// its setting to the f32 grid. This is the reading's resolution at the positions read
/// (2.98e-8 m at 0.4 m, 1.8e-6 m/s at 1/60 s), not a margin: a solver whose allowance
/// chains from substep to substep keeps the roundings that lift a body out and
/// corrects the others, and moves many spacings a frame more than the setting (12
/// spacings, 3.7e-7 m, measured on rigid frames chained so) and fails.
fn push_out(
    make: Make,
    sc: &SceneDesc,
    gap: impl Fn(&[ragdoll_sim::BodyState]) -> (f64, f64),
) -> (f64, f32, f32) {
    let mut w = make(sc);
    let dt = sc.settings.timestep as f64;
    let s0 = w.body_states_vec();
    let (mut prev, _) = gap(&s0);
    let (mut rate, mut speed, mut travel) = (0.0f64, 0.0f32, 0.0f32);
    for _ in 0..180 {
        w.step();
        let st = w.body_states_vec();
        let (g, spacing) = gap(&st);
        rate = rate.max((g - prev - spacing) / dt);
        prev = g;
        for (s, s0) in st.iter().zip(&s0) {
            speed = speed.max(s.linear_velocity.length());
            travel = travel.max((s.com - s0.com).length());
        }
    }
    (rate, speed, travel)
}

/// A 1 m cube whose bottom starts 25 cm under the ground rises out no faster than
/// `max_push_out_speed` and ends < 0.5 m from its start (Doom 3's own `default.af`
/// starts bodies this deep). The rise of a frame is read from the f32 height of the
/// centre against the setting × dt to within that height's f32 spacing ([`push_out`]).
fn box_starting_25_cm_in_the_ground_is_pushed_out_gently(make: Make) {
    let sc = scene(
        vec![cube("b", 0.5, Vec3::new(0.0, 0.25, 0.0), 10.0)],
        Some(Ground::default()),
    );
    let limit = sc.settings.max_push_out_speed;
    let (rate, speed, travel) = push_out(make, &sc, |st| {
        (st[0].com.y as f64, f32_spacing(st[0].com.y))
    });
    eprintln!("ground overlap: rose at {rate:.3} m/s, speed {speed:.3}, travel {travel:.3} m");
    assert!(
        rate <= limit as f64,
        "rose at {rate:.7} m/s, setting {limit} m/s"
    );
    assert!(
        speed <= limit,
        "moved at {speed:.2} m/s, setting {limit} m/s"
    );
    assert!(travel < 0.5, "travelled {travel:.3} m");
}

/// Two 1 m cubes that start 25 cm inside each other (no gravity) are pushed apart
/// (their centres end at least 1 m − 1 mm apart), no faster than `max_push_out_speed`,
/// and end < 0.5 m from their starts. The separation of a frame is read from the two
/// centres' f32 positions to within their f32 spacings ([`push_out`]).
fn boxes_starting_25_cm_inside_each_other_are_pushed_apart_gently(make: Make) {
    let a = cube("a", 0.5, Vec3::new(-0.375, 1.0, 0.0), 10.0);
    let b = cube("b", 0.5, Vec3::new(0.375, 1.0, 0.0), 10.0);
    let mut sc = scene(vec![a, b], None);
    sc.settings.gravity = Vec3::ZERO;
    let limit = sc.settings.max_push_out_speed;
    let (rate, _, travel) = push_out(make, &sc, |st| {
        let (xa, xb) = (st[0].com.x, st[1].com.x);
        (xb as f64 - xa as f64, f32_spacing(xa) + f32_spacing(xb))
    });
    eprintln!("body overlap: separated at {rate:.3} m/s, travel {travel:.3} m");
    assert!(
        rate <= limit as f64,
        "separated at {rate:.7} m/s, setting {limit} m/s"
    );
    assert!(travel < 0.5, "travelled {travel:.3} m");
    let mut w = make(&sc);
    for _ in 0..180 {
        w.step();
    }
    let st = w.body_states_vec();
    let apart = (st[1].com - st[0].com).length();
    assert!(
        apart >= 0.999,
        "centres {apart:.4} m apart: still overlapping"
    );
}

/// A door on a vertical world hinge whose range [10°, 60°] leaves its rest pose 10°
/// outside: it comes back into range within 2 s, gaining ≤ 2 % of the energy scale
/// (gravity does no work about a vertical axis, so any gain is the pop).
fn joint_starting_10_degrees_outside_its_limit_returns_gently(make: Make) {
    let anchor = Vec3::new(0.0, 1.0, 0.0);
    let door = boxed(
        "door",
        Vec3::new(0.3, 0.2, 0.02),
        anchor + Vec3::new(0.3, 0.0, 0.0),
        5.0,
    );
    let mut sc = scene(vec![door], None);
    let range = AngleRange {
        min: 10f32.to_radians(),
        max: 60f32.to_radians(),
    };
    sc.constraints
        .push(hinge("door", 0, None, anchor, Vec3::Y, Some(range)));
    let mut w = make(&sc);
    let mut rec = MetricsRecorder::new(&sc).unwrap();
    rec.record(0.0, &w.sample());
    for f in 0..120 {
        w.step();
        rec.record((f + 1) as f64 * sc.settings.timestep as f64, &w.sample());
    }
    let gain = rec.stats().energy_gain;
    eprintln!(
        "limit pop: gain {:.3} %, excess at 2 s {:.3}°",
        100.0 * gain,
        w.sample().max_limit_violation_deg
    );
    assert!(
        gain <= 0.02,
        "gained {:.2} % of the energy scale",
        100.0 * gain
    );
    let excess = w.sample().max_limit_violation_deg;
    assert!(
        excess <= 0.5,
        "still {excess:.2}° outside the limit after 2 s"
    );
}

// ---------------------------------------------------------------------------------
// Joint friction: the limited arms of scenes 5 and 6.
// ---------------------------------------------------------------------------------

/// Runs a shipped scene 10 s; every body must then be at rest: asleep, or below the
/// scene's own sleep speeds (`suspendSpeed`).
fn comes_to_rest(make: Make, name: &str) {
    let sc = shipped_scene(name);
    let mut w = make(&sc);
    for _ in 0..(10.0 / sc.settings.timestep).round() as usize {
        w.step();
    }
    if w.sample().all_asleep {
        return;
    }
    let sleep = sc.settings.sleep;
    for (i, s) in w.body_states_vec().iter().enumerate() {
        let (v, om) = (s.linear_velocity.length(), s.angular_velocity.length());
        assert!(
            v <= sleep.linear_velocity && om <= sleep.angular_velocity,
            "{name}: body {} still moving at 10 s: {v:.3} m/s, {om:.3} rad/s",
            sc.bodies[i].name
        );
    }
}

fn ball_limited_arms_come_to_rest_by_joint_friction(make: Make) {
    comes_to_rest(make, "ball-limits");
}

fn hinge_limited_arms_come_to_rest_by_joint_friction(make: Make) {
    comes_to_rest(make, "hinge-limits");
}

// ---------------------------------------------------------------------------------
// The solvers.
// ---------------------------------------------------------------------------------

/// One `#[test]` per listed property for the solver `$solver` (a `Make` of that name);
/// `property = "why"` marks the test ignored with the figure it measured.
macro_rules! suite {
    ($solver:ident: $($property:ident $(= $why:literal)?),* $(,)?) => {
        mod $solver {
            $(
                #[test]
                $(#[ignore = $why])?
                fn $property() {
                    super::$property(super::$solver);
                }
            )*
        }
    };
}

suite!(multibody:
    pendulum_at_5_degrees_keeps_its_exact_period_and_energy,
    pendulum_at_60_degrees_keeps_its_exact_period_and_energy,
    torque_free_rotation_about_a_general_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_major_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_minor_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_intermediate_axis_flips_and_keeps_l_and_energy,
    free_fall_drops_half_g_t_squared,
    box_sliding_on_flat_ground_stops_where_coulomb_says,
    box_slides_down_35_degrees_as_coulomb_says_without_turning,
    box_slides_down_45_degrees_as_coulomb_says_without_turning,
    box_on_20_degrees_with_mu_half_holds,
    capsule_rolling_on_flat_ground_stops_where_rolling_resistance_says,
    box_at_rest_stays_put,
    stack_of_5_boxes_stands,
    stack_of_10_boxes_stands,
    chain_of_mass_ratio_100_hangs_without_gaps,
    chain_of_mass_ratio_100_swings_without_gaps,
    box_hitting_a_wall_at_50_m_s_stays_face_on,
    free_plate_hit_off_centre_keeps_momentum,
    box_starting_25_cm_in_the_ground_is_pushed_out_gently,
    boxes_starting_25_cm_inside_each_other_are_pushed_apart_gently,
    joint_starting_10_degrees_outside_its_limit_returns_gently,
    ball_limited_arms_come_to_rest_by_joint_friction,
    hinge_limited_arms_come_to_rest_by_joint_friction,
);

suite!(rigid_frames:
    pendulum_at_5_degrees_keeps_its_exact_period_and_energy,
    pendulum_at_60_degrees_keeps_its_exact_period_and_energy,
    torque_free_rotation_about_a_general_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_major_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_minor_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_intermediate_axis_flips_and_keeps_l_and_energy,
    free_fall_drops_half_g_t_squared,
    box_sliding_on_flat_ground_stops_where_coulomb_says,
    box_slides_down_35_degrees_as_coulomb_says_without_turning,
    box_slides_down_45_degrees_as_coulomb_says_without_turning,
    box_on_20_degrees_with_mu_half_holds,
    capsule_rolling_on_flat_ground_stops_where_rolling_resistance_says,
    box_at_rest_stays_put,
    stack_of_5_boxes_stands,
    stack_of_10_boxes_stands,
    chain_of_mass_ratio_100_hangs_without_gaps,
    chain_of_mass_ratio_100_swings_without_gaps,
    box_hitting_a_wall_at_50_m_s_stays_face_on,
    free_plate_hit_off_centre_keeps_momentum,
    box_starting_25_cm_in_the_ground_is_pushed_out_gently,
    boxes_starting_25_cm_inside_each_other_are_pushed_apart_gently,
    joint_starting_10_degrees_outside_its_limit_returns_gently,
    ball_limited_arms_come_to_rest_by_joint_friction,
    hinge_limited_arms_come_to_rest_by_joint_friction,
);

suite!(xpbd:
    pendulum_at_5_degrees_keeps_its_exact_period_and_energy,
    pendulum_at_60_degrees_keeps_its_exact_period_and_energy,
    torque_free_rotation_about_a_general_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_major_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_minor_axis_keeps_l_and_energy,
    torque_free_rotation_near_the_intermediate_axis_flips_and_keeps_l_and_energy,
    free_fall_drops_half_g_t_squared,
    box_sliding_on_flat_ground_stops_where_coulomb_says,
    box_slides_down_35_degrees_as_coulomb_says_without_turning,
    box_slides_down_45_degrees_as_coulomb_says_without_turning,
    box_on_20_degrees_with_mu_half_holds,
    capsule_rolling_on_flat_ground_stops_where_rolling_resistance_says,
    box_at_rest_stays_put,
    stack_of_5_boxes_stands,
    stack_of_10_boxes_stands,
    chain_of_mass_ratio_100_hangs_without_gaps,
    chain_of_mass_ratio_100_swings_without_gaps,
    box_hitting_a_wall_at_50_m_s_stays_face_on,
    free_plate_hit_off_centre_keeps_momentum,
    box_starting_25_cm_in_the_ground_is_pushed_out_gently,
    boxes_starting_25_cm_inside_each_other_are_pushed_apart_gently,
    joint_starting_10_degrees_outside_its_limit_returns_gently,
    ball_limited_arms_come_to_rest_by_joint_friction,
    hinge_limited_arms_come_to_rest_by_joint_friction,
);
