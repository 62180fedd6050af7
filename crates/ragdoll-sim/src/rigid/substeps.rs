//! The velocity solve of one step over a set of bodies, joints and contacts — the whole
//! world on one thread, or one island ([`super::parallel`]): the substeps, the
//! restitution pass and the position projection, as [`super::solver`] describes them.

use super::body::{BodyStates, Motions};
use super::contact::ContactPair;
use super::contact_solver::{ContactConstraints, PushOutBudget};
use super::integrate::{integrate_positions, integrate_velocities, update_inertia};
use super::joint_set::JointSet;
use super::joint_tree::JointTrees;
use super::project;
use super::soft::StepContext;
use crate::scene::SleepSettings;
use glam::Vec3;

/// What every island's solve needs besides its bodies and constraints: the same for all
/// islands of a step.
#[derive(Clone, Copy, Debug)]
pub struct SolveParams<'a> {
    /// Substep length and softness.
    pub ctx: StepContext,
    /// Substeps per step.
    pub substeps: u32,
    /// Biased velocity iterations per substep.
    pub iterations: u32,
    /// Joint passes of each substep's relax step ([`crate::scene::Settings::relax_passes`]).
    pub relax_passes: u32,
    /// Gravity (m/s²).
    pub gravity: Vec3,
    /// Approach speed below which contacts do not bounce (m/s).
    pub restitution_threshold: f32,
    /// Sleep speeds: bodies below them take no part in the position projection.
    pub sleep: &'a SleepSettings,
}

/// The constraint arrays a solve fills anew every step, kept from one step to the next
/// so that, once they have grown to the world's size, a step allocates nothing (a fresh
/// array per step cost its growth and its page faults: a tenth of a busy pile's step).
#[derive(Default)]
pub struct SolveBuffers {
    contacts: ContactConstraints,
    trees: JointTrees,
    /// Per body, what the position half adds to `R I Rᵀ ω` to read its angular
    /// momentum (see [`integrate_velocities`]).
    spin_offset: Vec<Vec3>,
    /// Per body, whether its figure touches anything this solve (see
    /// [`project::project_positions`]).
    touching: Vec<bool>,
    /// Per body, whether it has a contact this solve (see [`integrate_positions`]).
    in_contact: Vec<bool>,
}

impl SolveBuffers {
    /// Drops the buffers by owner (see `Method::drop_by_owner`): the contact
    /// constraints, the joint trees, the per-body arrays.
    pub(crate) fn drop_by_owner(self, dropped: &mut dyn FnMut(&'static str)) {
        let SolveBuffers {
            contacts,
            trees,
            spin_offset,
            touching,
            in_contact,
        } = self;
        drop(contacts);
        dropped("contact constraints");
        drop(trees);
        dropped("joint trees");
        drop((spin_offset, touching, in_contact));
        dropped("solve per-body arrays");
    }

    /// The joint trees, for a caller that keeps them apart between solves.
    pub fn trees_mut(&mut self) -> &mut JointTrees {
        &mut self.trees
    }
}

/// The velocity solve of one step over the bodies, joints and contact pairs given (the
/// whole world, or one island gathered by [`parallel`]): the substeps, the restitution
/// pass and the position projection. Reads contacts prepared by [`Contacts::update`].
pub fn solve(
    s: &mut BodyStates,
    motion: Motions<'_>,
    joints: &mut JointSet,
    pairs: &mut [ContactPair],
    awake: &[bool],
    buffers: &mut SolveBuffers,
    p: &SolveParams,
) {
    let SolveBuffers {
        contacts,
        trees,
        spin_offset,
        touching,
        in_contact,
    } = buffers;
    spin_offset.clear();
    spin_offset.resize(motion.bodies.len(), Vec3::ZERO);
    contacts.rebuild(pairs, s, awake);
    in_contact.clear();
    in_contact.resize(motion.bodies.len(), false);
    contacts.mark_touching(in_contact);
    trees.rebuild(joints, s, awake);
    for sub in 0..p.substeps {
        integrate_velocities(s, motion, awake, p.gravity, p.ctx.h, spin_offset);
        if sub == 0 {
            joints.prepare(s, awake);
        } else {
            // The pose is the one the joints were prepared on for the relax passes.
            update_inertia(s, motion, awake);
            joints.prepare_after_relax(s, awake);
        }
        trees.factor(joints, s);
        joints.warm_start(s, awake);
        contacts.prepare_substep(s);
        contacts.warm_start(s);
        for _ in 0..p.iterations {
            joints.solve(s, awake, &p.ctx, true);
            trees.solve(joints, s, &p.ctx, true);
            contacts.solve(s, &p.ctx, true);
        }
        integrate_positions(s, motion, awake, p.ctx.h, spin_offset, in_contact);
        // The relax passes solve on the moved pose, prepared once: a preparation reads
        // the pose, inertias and masses, which the velocity passes leave as they are.
        // Every relax row, joint and contact, turns a body with one world inertia, the
        // substep start pose's: the biased iterations solved with it, and the joints'
        // limit rows and the contact rows hold it from the substep's preparation. Rows
        // acting on one body with two inverse inertias (point rows with the moved pose's,
        // limit and contact rows with the start pose's) are each met by their own update,
        // but their Gauss–Seidel sweep is no projection in one kinetic-energy metric, the
        // kind of velocity correction that can only give energy up. The two inertias
        // differ by a turn of `h |ω|` (0.016 rad a substep for a fist whipping at 15
        // rad/s, h = 1/960 s); with them mixed so, the box human's arm keeps whipping at
        // its stops after the landing, and the figure comes to rest about 90 J lower
        // (110–140 J) in 40 of 72 ensemble starts (180–230 J in all 72 with one inertia)
        // and sleeps in 59.
        // With every relax row on the moved pose's inertias the next substep could keep
        // these rows and this factorisation (three of eight factorisations a frame). The
        // resting piles forbid it, through the limit rows: relaxed on limit rows measured
        // again on the moved pose instead of the ones the biased iterations solved, a
        // light limb end lying on the floor beyond a straight limb pressed on its stop
        // (the pile's bottom-layer fists) goes on sliding at 7–8 mm/s and turning at
        // 0.11–0.14 rad/s, just over the sleep speed, for seconds. That creep is this
        // schedule's too; what ends it here is the position projection, which moves no
        // body under the sleep speeds (`project::project_positions`), and on the
        // iterations' own limit rows the fists fall under them within a second of the
        // landing (docs/benchmarks.md, What is left). The capsule human's
        // free obstacle is another matter: flung by the landing, it rolls out under the
        // rolling resistance alone, `a = ρ g / (1 + I / (m r²))` (`scene::rolling_arm`),
        // on either inertias.
        joints.prepare_moved(s, awake);
        for pass in 0..p.relax_passes {
            joints.solve(s, awake, &p.ctx, false);
            if pass == 0 && !trees.is_empty() {
                trees.factor(joints, s);
            }
            trees.solve(joints, s, &p.ctx, false);
        }
        contacts.solve(s, &p.ctx, false);
    }
    joints.end_substeps();
    contacts.end_substeps();
    contacts.restitution(s, p.restitution_threshold);
    let push = PushOutBudget {
        max_speed: p.ctx.max_push_out,
        bias_rate: p.ctx.contact.bias_rate,
        dt: p.ctx.h * p.substeps as f32,
    };
    project::project_positions(s, motion, joints, contacts, awake, p.sleep, &push, touching);
    contacts.store_impulses(pairs);
}
