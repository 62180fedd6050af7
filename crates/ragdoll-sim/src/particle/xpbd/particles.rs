//! The particle state of the XPBD solver: dense arrays addressed by particle index.
//!
//! Bone `i` owns particles `4i .. 4i + 4` (its particulation, `placement`), so a bone's
//! particles are found without a lookup and lie side by side in memory. Each particle
//! has its own position and velocity; nothing about a bone's motion is stored elsewhere.
//!
//! Positions are f64: a substep of `h` moves a particle by `v h`, 0.4 mm at 0.5 m/s and
//! 1200 substeps a second, and f32's grid is 1.2e-7 m at 1 m from the origin and 4e-6 m
//! at 50 m, a rounding of 3e-4 to 1e-2 of each move. The velocities `(x − x_prev)/h`
//! took that rounding every substep, biased enough to drain 4 % of a spinning box's
//! angular momentum in 10 s. Velocities and the corrections, differences of positions,
//! stay f32.

use super::super::bone::Bone;
use glam::{DMat3, DVec3, Vec3};

/// Particles per bone.
pub(crate) const PER_BONE: usize = 4;

/// Every particle of the world, structure of arrays.
#[derive(Clone, Debug, Default)]
pub(crate) struct XParticles {
    /// Positions now.
    pub x: Vec<DVec3>,
    /// Positions at the start of the current substep (velocity update, friction, the
    /// arms of the sticks' projection).
    pub x_prev: Vec<DVec3>,
    /// Velocities. Integration is `v += g h; x += v h` (symplectic Euler), then
    /// `v = (x − x_prev)/h` after the constraints (Macklin et al. 2019, algorithm 1).
    pub v: Vec<Vec3>,
    /// Mass (kg); a quarter of the bone's.
    pub mass: Vec<f32>,
    /// Inverse mass the solver sees: `1 / mass` (0 for a fixed bone's particles, whose
    /// `mass` is 0), or 0 while the bone sleeps.
    pub w: Vec<f32>,
    /// What stays fixed through a substep's passes, set by [`XParticles::fix_start`].
    pub start: Start,
}

/// Each moving bone at the substep's start, where its particles are rigid: what the
/// passes move it about (`joints::move_linear`, `shape_match::project`, the joint and
/// contact blocks), the same all through the substep and so taken once. The particles'
/// arms about the centre, `x_prev_k − c`, are one subtraction from `x_prev` and the
/// centre, the same arithmetic wherever they are formed, and are not kept.
#[derive(Clone, Debug, Default)]
pub(crate) struct Start {
    /// Per bone, the centre of its particles, `¼ Σ x_prev_k`.
    pub centre: Vec<DVec3>,
    /// Per bone, its world inverse inertia `R I⁻¹ Rᵀ` at `prev_rot`
    /// (`frame::inv_inertia_prev`).
    pub inv_inertia: Vec<DMat3>,
}

impl XParticles {
    /// Appends one bone's particles at `x` with velocities `v`, each `mass`; a fixed
    /// bone's particles (`movable` false) never move.
    pub fn push_bone(&mut self, x: [Vec3; 4], v: [Vec3; 4], mass: f32, movable: bool) {
        let inv = if movable && mass > 0.0 {
            1.0 / mass
        } else {
            0.0
        };
        for k in 0..PER_BONE {
            self.x.push(x[k].as_dvec3());
            self.x_prev.push(x[k].as_dvec3());
            self.v.push(if movable { v[k] } else { Vec3::ZERO });
            self.mass.push(if movable { mass } else { 0.0 });
            self.w.push(inv);
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Bone `i`'s four positions, rounded to f32 (drawing).
    #[inline]
    pub fn bone(&self, i: usize) -> [Vec3; 4] {
        self.bone64(i).map(|x| x.as_vec3())
    }

    /// Bone `i`'s four positions.
    #[inline]
    pub fn bone64(&self, i: usize) -> [DVec3; 4] {
        let f = PER_BONE * i;
        [self.x[f], self.x[f + 1], self.x[f + 2], self.x[f + 3]]
    }

    /// Bone `i`'s four positions at the start of the substep.
    #[inline]
    pub fn bone_prev(&self, i: usize) -> [DVec3; 4] {
        let f = PER_BONE * i;
        [
            self.x_prev[f],
            self.x_prev[f + 1],
            self.x_prev[f + 2],
            self.x_prev[f + 3],
        ]
    }

    /// The centre of bone `i`'s particles at the start of the substep (kept by
    /// [`XParticles::fix_start`]).
    #[inline]
    pub fn centre_prev(&self, i: usize) -> DVec3 {
        self.start.centre[i]
    }

    /// Bone `i`'s particles about their centre at the start of the substep,
    /// `x_prev_k − c`.
    #[inline(always)]
    pub fn arms_prev(&self, i: usize) -> [DVec3; 4] {
        let c = self.start.centre[i];
        let x = &self.x_prev[PER_BONE * i..PER_BONE * i + PER_BONE];
        [x[0] - c, x[1] - c, x[2] - c, x[3] - c]
    }

    /// Bone `i`'s world inverse inertia at the start of the substep.
    #[inline]
    pub fn inv_inertia_prev(&self, i: usize) -> &DMat3 {
        &self.start.inv_inertia[i]
    }

    /// Keeps what stays fixed through the substep ([`Start`]) for every moving bone,
    /// once `x_prev` and the bones' `prev_rot` are the substep's start. A bone that
    /// takes no correction keeps stale values, which nothing reads.
    pub fn fix_start(&mut self, bones: &[Bone]) {
        let n = bones.len();
        let s = &mut self.start;
        s.centre.resize(n, DVec3::ZERO);
        s.inv_inertia.resize(n, DMat3::ZERO);
        for (i, b) in bones.iter().enumerate() {
            let f = PER_BONE * i;
            if self.w[f] <= 0.0 {
                continue;
            }
            let x = &self.x_prev[f..f + PER_BONE];
            s.centre[i] = (x[0] + x[1] + x[2] + x[3]) * 0.25;
            s.inv_inertia[i] = super::frame::inv_inertia_prev(b);
        }
    }

    /// The centre of bone `i`'s particles (equal masses).
    #[inline]
    pub fn centre(&self, i: usize) -> DVec3 {
        let x = self.bone64(i);
        (x[0] + x[1] + x[2] + x[3]) * 0.25
    }

    /// Whether bone `i` takes corrections (movable and awake).
    #[inline]
    pub fn moves(&self, i: usize) -> bool {
        self.w[PER_BONE * i] > 0.0
    }

    /// Puts bone `i` to sleep (frozen, no velocity) or wakes it. Only a bone that is not
    /// fixed is woken (a kinematic bone is fixed while it is): its particles take their
    /// inverse masses `1 / mass` again.
    pub fn set_asleep(&mut self, i: usize, asleep: bool) {
        for k in PER_BONE * i..PER_BONE * (i + 1) {
            if asleep {
                self.v[k] = Vec3::ZERO;
                self.x_prev[k] = self.x[k];
                self.w[k] = 0.0;
            } else {
                // As `push_bone` took it: a movable particle's `mass` is its own and
                // positive or 0 (then `w` is 0), a fixed one's 0.
                let m = self.mass[k];
                self.w[k] = if m > 0.0 { 1.0 / m } else { 0.0 };
            }
        }
    }

    /// Gives back the room the arrays grew beyond their length.
    pub fn shrink_to_fit(&mut self) {
        self.x.shrink_to_fit();
        self.x_prev.shrink_to_fit();
        self.v.shrink_to_fit();
        self.mass.shrink_to_fit();
        self.w.shrink_to_fit();
    }
}
