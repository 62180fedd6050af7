//! The improved solver loop: substepped XPBD over particulated, rigidly projected bones
//! (Macklin et al. 2019, "Small steps in physics simulation"; Müller et al. 2020).
//!
//! Per frame: one collision detection with a speculative margin. Per substep `h`
//! ([`substeps`]: the scene's substeps × iterations):
//! 1. integrate every particle (`v += g h`, `x += v h`: Verlet in velocity form);
//! 2. shape-match each bone to the rigid frame that best fits its particles — the
//!    six sticks held exactly, with linear and angular momentum kept;
//! 3. one Gauss–Seidel pass over contacts, joints and limits, each a rigid correction
//!    of the bone frames weighted by generalised inverse mass (contacts first, so a
//!    joint is what holds last);
//! 4. rewrite the particles from the frames and derive `v = (x − x_prev)/h`;
//! 5. the velocity pass: restitution, air friction.
//!
//! Energy: every step is a projection or a dissipative velocity change; the only source
//! (push-out from a penetration) is cancelled by the velocity pass.

use super::contacts::{Contact, broad_phase, ground_pair, shape_pair};
use super::friction::{point_velocity, solve_friction, solve_normal, solve_velocity};
use super::{ParticleWorld, sleeping};
use crate::scene::Ground;
use glam::Vec3;

/// Collision detection for the frame, with each bone's margin from its speed.
fn detect(w: &mut ParticleWorld, dt: f32) {
    let g = w.scene.settings.gravity.length();
    let margins: Vec<f32> = w
        .bones
        .iter()
        .map(|b| {
            let ext = b.shape.compute_local_aabb().half_extents().length();
            (b.lin_vel.length() + b.ang_vel.length() * ext) * dt + g * dt * dt + 0.005
        })
        .collect();
    let mut pairs = std::mem::take(&mut w.pairs);
    broad_phase(&w.bones, &margins, &w.filter, &mut pairs);
    let mut contacts = std::mem::take(&mut w.contacts);
    contacts.clear();
    let bones = &w.bones;
    let mut group_count = 0u32;
    let mu_of = |i: usize| bones[i].friction;
    for &(i, j) in &pairs {
        let prediction = margins[i] + margins[j];
        let mu = (mu_of(i) * mu_of(j)).sqrt();
        let e = bones[i].restitution.max(bones[j].restitution);
        let group = group_count;
        group_count += 1;
        shape_pair(bones, i, j, prediction, &mut w.manifolds, |pa, pb, n, _| {
            contacts.push(Contact {
                a: i,
                b: Some(j),
                ra: bones[i].rot.inverse() * (pa - bones[i].center()),
                rb: bones[j].rot.inverse() * (pb - bones[j].center()),
                n,
                mu,
                e,
                lambda_n: 0.0,
                group,
                lambda_t: 0.0,
                vn_before: 0.0,
            });
        });
    }
    if let Some(ground) = w.scene.settings.ground {
        for (i, b) in bones.iter().enumerate() {
            if b.is_static() {
                continue;
            }
            let mu = (b.friction * ground.friction).sqrt();
            let e = b.restitution.max(ground.restitution);
            let g: &Ground = &ground;
            let group = group_count;
            group_count += 1;
            ground_pair(bones, i, g, margins[i], &mut w.manifolds, |pa, pb, n, _| {
                contacts.push(Contact {
                    a: i,
                    b: None,
                    ra: b.rot.inverse() * (pa - b.center()),
                    rb: pb,
                    n,
                    mu,
                    e,
                    lambda_n: 0.0,
                    group,
                    lambda_t: 0.0,
                    vn_before: 0.0,
                });
            });
        }
    }
    w.contacts = contacts;
    w.pairs = pairs;
}

/// Contacts, manifold by manifold (consecutive contacts of one group): each point's
/// normal correction, then its friction against the manifold's Coulomb cone so far.
fn contact_pass(bones: &mut [super::bone::Bone], contacts: &mut [Contact]) {
    let mut start = 0;
    while start < contacts.len() {
        let g = contacts[start].group;
        let end = contacts[start..]
            .iter()
            .position(|c| c.group != g)
            .map_or(contacts.len(), |k| start + k);
        let group = &mut contacts[start..end];
        let mut spent: f32 = group.iter().map(|c| c.lambda_t).sum();
        for k in 0..group.len() {
            solve_normal(bones, &mut group[k]);
            let normal: f32 = group.iter().map(|c| c.lambda_n).sum();
            spent += solve_friction(bones, &mut group[k], normal, spent);
        }
        start = end;
    }
}

/// Derives each bone's velocity from its particles: `v = Σ m v_i / M` and
/// `ω = I⁻¹ Σ m r_i × v_i` (angular momentum over inertia).
fn bone_velocities(w: &mut ParticleWorld) {
    let v = &w.particles.v;
    for b in w.bones.iter_mut() {
        if b.is_static() {
            b.lin_vel = Vec3::ZERO;
            b.ang_vel = Vec3::ZERO;
            continue;
        }
        let vi = b.particles.map(|p| v[p as usize]);
        let vc = (vi[0] + vi[1] + vi[2] + vi[3]) * 0.25;
        let m = b.mass * 0.25;
        let mut l = Vec3::ZERO;
        for (r, v) in b.rest.iter().zip(&vi) {
            l += (b.rot * *r).cross(*v - vc) * m;
        }
        b.lin_vel = vc;
        b.ang_vel = b.inv_inertia_mul(l);
    }
}

/// Collision detection runs this many times per frame (every few substeps): a limb
/// that turns within a frame brings a corner the frame-start manifold did not have.
const DETECTIONS_PER_FRAME: u32 = 4;

/// Gauss–Seidel passes (contacts, then joints) per substep. An impact pushes a limb one
/// way and its joint pulls it back; a second pass halves the gap an impact leaves
/// (human, scene 8: 4.0 → 1.9 mm), and lets friction correct the slip the joints
/// brought, without which a resting figure creeps.
const PASSES: u32 = 2;

/// Passes of the contact velocity solve: one pass over a manifold leaves part of the
/// push-out velocity of the points solved first.
const VELOCITY_PASSES: u32 = 2;

/// Substeps per frame: the scene's substeps times its iterations, one constraint pass
/// each. Macklin et al. 2019 show that spending a fixed budget on substeps rather than
/// iterations converges faster and damps less; measured on the human (scene 8),
/// 20 substeps × 1 pass halves the joint gap and penetration of 4 substeps × 5 passes.
pub(crate) fn substeps(s: &crate::scene::Settings) -> u32 {
    (s.substeps.max(1) * s.iterations.max(1)).min(1000)
}

/// One frame of the improved solver.
pub(crate) fn step(w: &mut ParticleWorld) {
    let s = w.scene.settings.clone();
    let dt = s.timestep;
    let n_sub = substeps(&s);
    let h = dt / n_sub as f32;
    w.particles.frame_start.clone_from(&w.particles.x);
    let every = n_sub.div_ceil(DETECTIONS_PER_FRAME);
    for sub in 0..n_sub {
        if sub % every == 0 {
            detect(w, dt * (n_sub - sub) as f32 / n_sub as f32);
        }
        // 1–2. integrate the particles (relative to the frame origin, see `Bone::dcom`)
        // and shape-match each moving bone to its rigid frame.
        for b in w.bones.iter_mut() {
            b.prev_com = b.com;
            b.prev_rot = b.rot;
            b.dcom = Vec3::ZERO;
            if b.is_static() {
                continue;
            }
            let mut u = [Vec3::ZERO; 4];
            for (k, uk) in u.iter_mut().enumerate() {
                let p = b.particles[k] as usize;
                w.particles.v[p] += s.gravity * h;
                *uk = b.rot * b.rest[k] + w.particles.v[p] * h;
            }
            b.shape_match(&u);
        }
        // relative normal velocity before the solve, for restitution
        for c in w.contacts.iter_mut() {
            c.lambda_n = 0.0;
            c.lambda_t = 0.0;
            let pa = w.bones[c.a].world(c.ra);
            let pb = super::bone::side_world(&w.bones, c.b, c.rb);
            c.vn_before = (point_velocity(&w.bones, Some(c.a), pa)
                - point_velocity(&w.bones, c.b, pb))
            .dot(c.n);
        }
        // 3. constraints: contacts then joints, twice
        for _ in 0..PASSES {
            contact_pass(&mut w.bones, &mut w.contacts);
            for j in &w.joints {
                j.solve(&mut w.bones, h);
            }
            if let Some(g) = w.grab {
                super::grab_improved(&mut w.bones, g, h);
            }
        }
        // 4. velocities from the particles' displacements, particles from the frames
        for b in w.bones.iter_mut() {
            if b.is_static() {
                continue;
            }
            for k in 0..4 {
                let p = b.particles[k] as usize;
                w.particles.v[p] = b.displacement(b.rest[k]) / h;
            }
            b.com += b.dcom;
            b.dcom = Vec3::ZERO;
            for k in 0..4 {
                let p = b.particles[k] as usize;
                w.particles.x_prev[p] = b.prev_com + b.prev_rot * b.rest[k];
            }
            b.write_particles(&mut w.particles.x);
        }
        bone_velocities(w);
        // 5. velocity pass (contact points are relative to the updated frames)
        for _ in 0..VELOCITY_PASSES {
            for c in &w.contacts {
                solve_velocity(&mut w.bones, c, h, s.restitution_threshold);
            }
        }
        for b in w.bones.iter_mut() {
            if b.is_static() {
                continue;
            }
            b.lin_vel *= (1.0 - b.air.0 * h).max(0.0);
            b.ang_vel *= (1.0 - b.air.1 * h).max(0.0);
            for k in 0..4 {
                let p = b.particles[k] as usize;
                w.particles.v[p] = b.lin_vel + b.ang_vel.cross(b.rot * b.rest[k]);
            }
        }
    }
    let mut newly = Vec::new();
    let held = w
        .grab
        .and_then(|g| w.bones.iter().position(|b| b.body == g.body.index()));
    sleeping::update(
        &mut w.bones,
        held,
        &w.joints,
        &w.contacts,
        &s.sleep,
        dt,
        w.time + dt as f64,
        &mut newly,
    );
    for &i in &newly {
        let b = &mut w.bones[i];
        b.lin_vel = Vec3::ZERO;
        b.ang_vel = Vec3::ZERO;
        for &p in &b.particles {
            w.particles.v[p as usize] = Vec3::ZERO;
            w.particles.x_prev[p as usize] = w.particles.x[p as usize];
        }
    }
}
