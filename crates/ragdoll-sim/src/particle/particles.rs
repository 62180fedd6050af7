//! The paper solver's particle storage and its integrator (section 2.5 of the paper).
//!
//! Hot state in dense arrays addressed by particle index: position, previous position,
//! mass. The paper's solver integrates with position Verlet,
//! `x(t+Δt) = 2x(t) − x(t−Δt) + a Δt²` (eq. 41), keeping only positions. The improved
//! solver uses the same scheme in its velocity form (`v += g h; x += v h`, algebraically
//! identical) on particles that are the corners of its rigid bone frames, so it keeps
//! them in the frames (`Bone::corner`) and needs none of this.

use glam::Vec3;

/// Every particle of the world, structure of arrays.
#[derive(Clone, Debug, Default)]
pub(crate) struct Particles {
    /// Current positions.
    pub x: Vec<Vec3>,
    /// Positions one (sub)step ago: Verlet's implicit velocity.
    pub x_prev: Vec<Vec3>,
    /// Positions at the start of the current frame, for E(t)'s `(x(t) − x(t−dt))/dt`.
    pub frame_start: Vec<Vec3>,
    /// Mass carried by each particle (kg; 0 for particles of fixed bones).
    pub mass: Vec<f32>,
    /// Inverse mass (0 = does not move).
    pub inv_mass: Vec<f32>,
    /// The particles `0..joints` are the joints' points, shared by the bones they join
    /// (drawn green in the paper's figure 31): the paper's build makes them first.
    pub joints: u32,
    /// Each bone's four particles (the tetrahedron's corners `0..4`), by bone index.
    pub of_bone: Vec<[u32; 4]>,
}

impl Particles {
    /// Appends a particle with velocity `v` at time 0 and returns its index.
    ///
    /// Verlet's velocity lives half a step back: `(x₀ − x₋₁)/Δt = v(−Δt/2)`. Starting it
    /// there, `x₋₁ = x₀ − v Δt + ½ g Δt²`, makes free fall exact (eq. 41 is exact for a
    /// parabola).
    pub fn push(
        &mut self,
        x: Vec3,
        v: Vec3,
        gravity: Vec3,
        dt: f32,
        mass: f32,
        movable: bool,
    ) -> u32 {
        let i = self.x.len() as u32;
        let (v, g) = if movable {
            (v, gravity)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        self.x.push(x);
        let prev = x - v * dt + g * (0.5 * dt * dt);
        self.x_prev.push(prev);
        self.frame_start.push(prev);
        self.mass.push(mass);
        self.inv_mass.push(if movable { 1.0 } else { 0.0 });
        i
    }

    /// Gives back the room the arrays grew beyond their length.
    pub fn shrink_to_fit(&mut self) {
        self.x.shrink_to_fit();
        self.x_prev.shrink_to_fit();
        self.frame_start.shrink_to_fit();
        self.mass.shrink_to_fit();
        self.inv_mass.shrink_to_fit();
        self.of_bone.shrink_to_fit();
    }

    /// True when particle `i` is a joint's point.
    pub fn is_joint(&self, i: usize) -> bool {
        i < self.joints as usize
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// One position-Verlet step of the paper (eq. 41) for every movable particle:
    /// `x' = x + (x − x_old) + g Δt²`.
    pub fn verlet(&mut self, gravity: Vec3, dt: f32) {
        let a = gravity * dt * dt;
        for i in 0..self.x.len() {
            if self.inv_mass[i] == 0.0 {
                continue;
            }
            let x = self.x[i];
            self.x[i] = x + (x - self.x_prev[i]) + a;
            self.x_prev[i] = x;
        }
    }

    /// Rescales Verlet's implicit velocities after a timestep change, so that
    /// `(x − x_old)/Δt` keeps its value.
    pub fn rescale_verlet(&mut self, old_dt: f32, new_dt: f32) {
        let s = new_dt / old_dt;
        for i in 0..self.x.len() {
            self.x_prev[i] = self.x[i] - (self.x[i] - self.x_prev[i]) * s;
        }
    }
}
