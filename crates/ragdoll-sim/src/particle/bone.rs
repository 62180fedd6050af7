//! A bone: a tetrahedron of four particles and six sticks, and the frame it carries.
//!
//! The paper (section 3.1.2) computes a local frame from the particles and stores the box
//! in it. We keep two frame constructions:
//! - `paper`: origin at particle 0, X towards particle 1, Y from particle 2 by
//!   Gram–Schmidt — exactly what a tetrahedron that may deform gives you;
//! - `improved`: the best-fit rigid frame of the deformed tetrahedron (shape matching,
//!   Müller et al. 2005), whose origin is the centre of mass and whose axes are the
//!   principal axes of inertia, because the particles were placed to reproduce them.
//!
//! The improved solver also moves a bone *rigidly*: a correction impulse `p` at world
//! point `r` translates the centre of mass by `p/M` and rotates by `I⁻¹ (r − c) × p`,
//! then rewrites the four particles from the frame. For particles that reproduce M, c
//! and I exactly this is the limit of infinitely stiff sticks, reached in one step.

use crate::scene::{BodyCollider, Pose};
use glam::{Mat3, Quat, Vec3, Vec3A};

/// The six edges of a tetrahedron, as pairs of corner indices.
pub(crate) const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// One bone's cold and hot data.
#[derive(Clone)]
pub(crate) struct Bone {
    /// Index of the scene body.
    pub body: usize,
    /// The four particles of the tetrahedron.
    pub particles: [u32; 4],
    /// Particle positions in the bone frame at rest.
    pub rest: [Vec3; 4],
    /// Rest lengths of the six sticks (`EDGES`).
    pub stick_rest: [f32; 6],
    /// Bone frame: origin (the centre of mass in improved mode) at the start of the
    /// substep; the frame's origin is `com + dcom`.
    pub com: Vec3A,
    /// Displacement of the origin during the current substep. Kept apart from `com` so
    /// that velocities, `dcom / h`, come from small numbers: differences of f32
    /// positions 50 m from the origin would round to a biased 1e-3 m/s per substep.
    pub dcom: Vec3A,
    /// Bone frame: orientation.
    pub rot: Quat,
    /// Orientation at the start of the current substep (a contact's slip over the substep,
    /// `Bone::displacement`; its origin's motion is `dcom`).
    pub prev_rot: Quat,
    /// The shape frame expressed in the bone frame.
    pub shape_in_bone: Pose,
    /// Collision shape, in the shape frame.
    pub shape: BodyCollider,
    /// Centre of mass in the shape frame.
    pub shape_com: Vec3,
    /// Total mass (kg).
    pub mass: f32,
    /// Inverse inertia in the bone frame (diagonal: the frame is principal).
    pub inv_inertia_local: Vec3A,
    /// Fixed bones never move.
    pub fixed: bool,
    /// Asleep bones are frozen until something wakes their island.
    pub asleep: bool,
    /// Seconds this bone has been below the sleep speeds.
    pub sleep_time: f32,
    /// Where the bone was when it last moved more than the no-move bounds.
    pub still_anchor: (Vec3, Quat),
    /// Seconds the bone has stayed within the no-move bounds of `still_anchor`.
    pub still_time: f32,
    /// Linear velocity of the frame origin (m/s), from the particles.
    pub lin_vel: Vec3A,
    /// Angular velocity (rad/s, world), from the particles.
    pub ang_vel: Vec3A,
    /// Contact friction μ and restitution of the body.
    pub friction: f32,
    /// Restitution.
    pub restitution: f32,
    /// Air friction per second (linear, angular).
    pub air: (f32, f32),
    /// Connected component of the joint graph ("figure").
    pub figure: u32,
    /// Collides with bones of its own figure.
    pub self_collision: bool,
}

impl Bone {
    /// True when the bone takes no correction (fixed, or asleep).
    pub fn is_static(&self) -> bool {
        self.fixed || self.asleep
    }

    /// Wakes the bone with both rest timers restarted (and its no-move box around where
    /// it is now), or its island's longest-resting bone would put it straight back to
    /// sleep.
    pub fn wake(&mut self) {
        self.asleep = false;
        self.sleep_time = 0.0;
        self.still_time = 0.0;
        self.still_anchor = (Vec3::from(self.center()), self.rot);
    }

    /// Takes `from`'s motion: all that the improved solver's substeps write of a bone
    /// (its frame, the substep's start and displacement, its velocities), a quarter of
    /// its bytes. A batch of islands returns its bones to the world through this
    /// (`islands`); `particle_threads` checks the result is the serial one bit for bit.
    pub fn take_motion(&mut self, from: &Bone) {
        self.com = from.com;
        self.dcom = from.dcom;
        self.rot = from.rot;
        self.prev_rot = from.prev_rot;
        self.lin_vel = from.lin_vel;
        self.ang_vel = from.ang_vel;
    }

    /// Inverse mass seen by the solver.
    pub fn inv_mass(&self) -> f32 {
        if self.is_static() {
            0.0
        } else {
            1.0 / self.mass
        }
    }

    /// The frame origin now.
    pub fn center(&self) -> Vec3A {
        self.com + self.dcom
    }

    /// Motion of a bone-frame point during the current substep.
    pub fn displacement(&self, local: Vec3) -> Vec3A {
        let local = Vec3A::from(local);
        self.dcom + (self.rot * local - self.prev_rot * local)
    }

    /// World pose of the shape frame.
    pub fn shape_pose(&self) -> Pose {
        Pose {
            position: Vec3::from(self.center()),
            rotation: self.rot,
        }
        .mul_pose(&self.shape_in_bone)
    }

    /// The shape pose in parry's type.
    pub fn parry_pose(&self) -> parry3d::math::Pose {
        let p = self.shape_pose();
        parry3d::math::Pose::from_parts(p.position, p.rotation)
    }

    /// World position of a point given in the bone frame.
    pub fn world(&self, local: Vec3) -> Vec3A {
        self.com + (self.dcom + self.rot * Vec3A::from(local))
    }

    /// Improved mode: particle `k`, rigidly placed in the frame. Between substeps this is
    /// where the solver's particle is; the improved world stores no particle arrays.
    pub fn corner(&self, k: usize) -> Vec3 {
        Vec3::from(self.world(self.rest[k]))
    }

    /// Improved mode: the velocity of particle `k` as the next substep starts from it,
    /// the frame's rigid motion `v + ω × (R rest_k)`.
    pub fn corner_velocity(&self, k: usize) -> Vec3 {
        Vec3::from(self.lin_vel + self.ang_vel.cross(self.rot * Vec3A::from(self.rest[k])))
    }

    /// Largest relative stick-length error of the bone whose particles are `corners`.
    pub fn stretch(&self, corners: &[Vec3; 4]) -> f32 {
        let mut worst = 0.0f32;
        for (k, &(i, j)) in EDGES.iter().enumerate() {
            let l = corners[i].distance(corners[j]);
            let r = self.stick_rest[k];
            if r > 0.0 {
                worst = worst.max((l - r).abs() / r);
            }
        }
        worst
    }

    /// Improved mode, substep steps 1–2: advances every particle by its velocity,
    /// `x_k ← x_k + (v + ω × a_k + g h) h` with `a_k = R rest_k`, and shape-matches the
    /// bone to them (Müller et al. 2005), in closed form; the frame's displacement goes
    /// to `dcom`.
    ///
    /// Equal particle masses put the matched origin at the mean, moved by `(v + g h) h`.
    /// The matched rotation is the rotational part of `A = Σ (x_k − c) rest_kᵀ =
    /// (1 + h ω̂) R D`, `D = Σ rest_k rest_kᵀ` (diagonal in the principal bone frame), as
    /// Müller et al. 2016's iteration ("A robust method to extract the rotational part of
    /// deformations") finds it from the warm start `R`: linearised about `R`, the turn
    /// still to make, `e` in the bone frame, starts at `h ω` and shrinks as `e ← M e`
    /// with `M = D / tr D` while each iteration turns the frame by `(1 − M) e`; the
    /// iteration stops once a turn is below [`EXTRACT_TOLERANCE`], or after 20. So the
    /// bone turns by `(1 − M^N) h ω` (in its frame), not `h ω`. About an axis of small
    /// inertia the share `m_k = 1 − 2 I_k / tr I` is near 1 (0.73 about a capsule
    /// human's limb, 0.90 about a box human's) and the turn lags: a twist of a long bone
    /// is damped, most when slow (few iterations run), which is the damping the resting
    /// figures rely on (at 20 substeps a frame a box limb keeps about a tenth of a twist
    /// from frame to frame). To second order the
    /// iteration also turns by `½ (1 − M)⁻¹ (ê × M ê)`, `ê = h ω` in the bone frame,
    /// which keeps a tumbling bone's angular momentum, and which is added here. Running
    /// the iteration itself cost 5–7 rotation matrices, cross products and sines per bone
    /// per substep; this is the same turn to second order in `h |ω|` on the axes it
    /// converges on (within 0.03 % of the turn at `h |ω|` = 0.03 on a chest box, 0.1 %
    /// on a limb's capped twist: the unit test below), from three products per
    /// iteration, with the frame turned once, `q ← q + ½ q [θ, 0]` normalised (the
    /// turn `R (1 − M^N) Rᵀ h ω` plus that term).
    pub fn advance(&mut self, h: f32, gravity: Vec3) {
        self.dcom = (self.lin_vel + Vec3A::from(gravity) * h) * h;
        self.rot = matched_turn(self.rot, Vec3::from(self.ang_vel * h), turn_lag(&self.rest));
    }

    /// Improved mode, substep step 4: the bone's velocity from its particles'
    /// displacements over the substep, `v_k = (Δc + (R − P) r_k) / h` (`R`, `P` the frame
    /// now and at the substep's start, `r_k = rest_k`, `Δc = dcom`): the mean velocity
    /// and the angular momentum `L = (M/4) Σ R r_k × (v_k − v)` over the inertia.
    ///
    /// In closed form, with no particle evaluated: the rest positions sum to zero and
    /// `D = Σ r_k r_kᵀ` is diagonal (`placement`: corners `(±1, ±1, ±1)` scaled per
    /// axis), so `v = Δc / h` and, as `R r × R r = 0`, `L = −(M / 4h) R Σ r_k × Q r_k`
    /// with `Q = Rᵀ P`. For `Q = (w, u)`, `Q r = r + 2w u × r + 2 u × (u × r)`, and
    /// summing `r × (u × r) = |r|² u − (r·u) r` and `r × (u × (u × r)) = (u·r)(r × u)`
    /// over the corners gives `Σ r_k × Q r_k = 2w (tr D − D) u + 2 (D u) × u`. Then
    /// `ω = R I⁻¹ Rᵀ L = −(M / 2h) R I⁻¹ (w (tr D − D) u + (D u) × u)`: one quaternion
    /// product and one rotation, where the particles' form took ten rotations. (A turn
    /// `θ` over the substep gives `u ≈ −θ_local / 2`, `ω = I⁻¹ (M/4)(tr D − D) θ / h`:
    /// the turn rate, as the particles' inertia `(M/4)(tr D − D)` is the bone's — except
    /// for a needle, whose particles keep a floor of volume (`placement`), as the
    /// particles' form had it too.)
    pub fn substep_velocity(&self, h: f32) -> (Vec3A, Vec3A) {
        let q = self.rot.inverse() * self.prev_rot;
        let (u, w) = (Vec3A::new(q.x, q.y, q.z), q.w);
        let d = Vec3A::from(second_moments(&self.rest));
        let tr = d.x + d.y + d.z;
        let sum = (Vec3A::splat(tr) - d) * u * w + (d * u).cross(u);
        let local = self.inv_inertia_local * sum * (-0.5 * self.mass / h);
        (self.dcom / h, self.rot * local)
    }

    /// The paper's frame (section 3.1.2): origin at particle 0, X towards particle 1,
    /// Y towards particle 2 orthogonalised, Z = X × Y.
    pub fn paper_frame(&mut self, x: &[Vec3]) {
        let p0 = x[self.particles[0] as usize];
        let (r, ok) = gram_schmidt(
            x[self.particles[1] as usize] - p0,
            x[self.particles[2] as usize] - p0,
        );
        if ok {
            self.rot = r;
        }
        self.com = Vec3A::from(p0);
    }
}

/// Rotation with X along `e1` and Y in the plane of `e1`, `e2`. Returns false when the
/// three points are (nearly) collinear.
pub(crate) fn gram_schmidt(e1: Vec3, e2: Vec3) -> (Quat, bool) {
    let x = e1.normalize_or_zero();
    let y = (e2 - x * x.dot(e2)).normalize_or_zero();
    if x == Vec3::ZERO || y == Vec3::ZERO {
        return (Quat::IDENTITY, false);
    }
    let z = x.cross(y);
    (Quat::from_mat3(&Mat3::from_cols(x, y, z)).normalize(), true)
}

/// Per bone axis, the share of a turn that shape matching leaves to its next iteration
/// (see [`Bone::advance`]): `m_k = D_kk / tr D`, `D = Σ rest_j rest_jᵀ` (zero for a bone
/// without extent). Evaluated where it is used rather than stored: 12 bytes a bone
/// against a few products per substep.
pub(crate) fn turn_lag(rest: &[Vec3; 4]) -> Vec3 {
    let d = second_moments(rest);
    let tr = d.x + d.y + d.z;
    if tr > 0.0 { d / tr } else { Vec3::ZERO }
}

/// The diagonal of `D = Σ rest_k rest_kᵀ`, the particles' second moments about the
/// frame origin (per unit particle mass): diagonal in the principal bone frame.
fn second_moments(rest: &[Vec3; 4]) -> Vec3 {
    rest.iter().fold(Vec3::ZERO, |acc, r| acc + *r * *r)
}

/// The frame `q` turned as shape matching turns it when its particles turn by the world
/// rotation vector `turn` (see [`Bone::advance`]), `m` the bone's [`turn_lag`].
fn matched_turn(q: Quat, turn: Vec3, m: Vec3) -> Quat {
    let full = q.inverse() * turn;
    // In SIMD lanes: the products are glam's `Vec3` ones, lane by lane, and the squared
    // length adds them in `Vec3::length_squared`'s order, so the bits are the same.
    let (m, keep) = (Vec3A::from(m), Vec3A::ONE - Vec3A::from(m));
    let mut e = Vec3A::from(full);
    for _ in 0..EXTRACT_ITERATIONS {
        let step = keep * e;
        e *= m;
        let sq = step * step;
        if sq.x + sq.y + sq.z < EXTRACT_TOLERANCE * EXTRACT_TOLERANCE {
            break;
        }
    }
    // Second order: the extraction also turns the frame by `½ (1 − M)⁻¹ (ê × M ê)`,
    // `ê = h ω` in the bone frame, the gyroscopic turn that keeps a tumbling bone's
    // angular momentum; first order alone lets it drift (a chest box tumbling at 10 rad/s:
    // 0.08 rad in a second, against 8e-4 rad with this term, as the iteration kept it).
    // Each component is at most `½ |ê_j ê_k|`, `1 − m_i = m_j + m_k ≥ |m_k − m_j|`.
    let (m, keep) = (Vec3::from(m), Vec3::from(keep));
    let gyro = full.cross(m * full);
    let second = Vec3::select(keep.cmpgt(Vec3::ZERO), 0.5 * gyro / keep, Vec3::ZERO);
    rotate_local(q, Vec3A::from(full - Vec3::from(e) + second))
}

/// Turn (rad) below which Müller et al.'s extraction has converged and stops: a few f32
/// ulps of a unit quaternion component (ε ≈ 1.2e-7). It sets how strongly
/// [`Bone::advance`] damps a slow twist.
const EXTRACT_TOLERANCE: f32 = 1e-6;
/// Most iterations of the extraction per substep.
const EXTRACT_ITERATIONS: usize = 20;

/// A static-or-moving side of a two-body constraint: a bone, or the world/ground.
pub(crate) type Side = Option<usize>;

/// World point and frame origin of a point given in a side's local frame (world: as is).
#[inline]
pub(crate) fn side_world(bones: &[Bone], s: Side, local: Vec3) -> Vec3A {
    match s {
        Some(i) => bones[i].world(local),
        None => Vec3A::from(local),
    }
}

/// One moving side of a correction along a unit direction: the bone, and `I⁻¹ (r × n)`
/// in its frame. Computed once for the generalised inverse mass, `1/M + (r × n)ᵀ I⁻¹
/// (r × n)`, and reused for the rotation the correction applies, `R I⁻¹ (r × n) λ`,
/// instead of forming `r × n` and rotating it into the bone frame a second time.
#[derive(Clone, Copy)]
struct Lever {
    bone: usize,
    /// `I⁻¹ (r × n)` (or `I⁻¹ n` for a pure rotation) in the bone frame.
    turn: Vec3A,
}

impl Lever {
    /// The lever of side `s` for a correction along `n` at world point `p` (`None` for
    /// a pure rotation about `n`), with its generalised inverse mass; no lever for a
    /// static side. `n` need not be a unit vector: `n2` is `|n|²`, and the inverse mass
    /// returned is `|n|²` times the unit direction's (every term is quadratic in `n`).
    #[inline]
    fn of(bones: &[Bone], s: Side, p: Option<Vec3A>, n: Vec3A, n2: f32) -> (Option<Lever>, f32) {
        let Some(i) = s else {
            return (None, 0.0);
        };
        let b = &bones[i];
        if b.is_static() {
            return (None, 0.0);
        }
        let (axis, linear) = match p {
            Some(p) => ((p - b.center()).cross(n), b.inv_mass() * n2),
            None => (n, 0.0),
        };
        let local = b.rot.inverse() * axis;
        let turn = b.inv_inertia_local * local;
        (Some(Lever { bone: i, turn }), linear + local.dot(turn))
    }

    /// Applies the velocity impulse `λ` along the lever's direction: the centre's
    /// velocity changes by `n λ / M` (`linear`) and the angular one by `R turn λ`.
    #[inline]
    fn apply_velocity(self, bones: &mut [Bone], linear: Vec3A, lambda: f32) {
        let b = &mut bones[self.bone];
        b.lin_vel += linear * b.inv_mass();
        b.ang_vel += b.rot * (self.turn * lambda);
    }

    /// Applies the correction `λ` along the lever's direction: the centre moves by
    /// `n λ / M` (`linear`, zero for a pure rotation) and the frame turns by `R turn λ`.
    #[inline]
    fn apply(self, bones: &mut [Bone], linear: Vec3A, lambda: f32) {
        let b = &mut bones[self.bone];
        b.dcom += linear * b.inv_mass();
        b.rot = rotate_local(b.rot, self.turn * lambda);
    }
}

/// `q + ½ [θ, 0] q`, normalised: the XPBD orientation update for a small rotation θ
/// (world), given in the body frame as `θ_local = q⁻¹ θ q`. Since `[θ, 0] q = q [θ_local,
/// 0]`, this is `q + ½ q [θ_local, 0]`: no rotation of θ into the world first, which
/// every correction of the solver would otherwise pay.
///
/// The sum `r` has `|r|² = 1 + d` with `d` of order `|θ|²/4`: it is scaled by
/// `(1 + d)^(−1/2) ≈ 1 − d/2 + 3d²/8` (error about `5|d|³/16`, 2e-8 at `|d| = 4e-3`)
/// rather than divided by a square root, which sat on the chain of every correction of
/// the bone; a larger turn is normalised exactly.
pub(crate) fn rotate_local(q: Quat, theta_local: Vec3A) -> Quat {
    let dq = q * Quat::from_xyzw(theta_local.x, theta_local.y, theta_local.z, 0.0);
    let r = q + dq * 0.5;
    let d = r.length_squared() - 1.0;
    if d.abs() < 4e-3 {
        r * (1.0 - d * (0.5 - 0.375 * d))
    } else {
        r.normalize()
    }
}

/// A correction between two sides along a unit direction (or a turn about it), its
/// levers computed once: `w` is the generalised inverse mass along it (Müller et al. 2020,
/// eq. 2–3), [`Correction::apply`] moves the points by `λ` along it.
pub(crate) struct Correction {
    a: Option<Lever>,
    b: Option<Lever>,
    n: Vec3A,
    /// Generalised inverse mass of the two sides along `n`.
    pub w: f32,
}

impl Correction {
    /// Moving point `pa` of side `a` along unit `n` and `pb` of `b` against it.
    #[inline]
    pub fn along(bones: &[Bone], pa: (Side, Vec3A), pb: (Side, Vec3A), n: Vec3A) -> Self {
        Correction::along_scaled(bones, pa, pb, n, 1.0)
    }

    /// [`Correction::along`] a direction `d` of squared length `d2`, not normalised: `w`
    /// is `d2` times the unit direction's and [`Correction::apply`]'s `λ` is per unit of
    /// `d`. A correction of length `c` along `d / |d|` is then `λ = c / (|d| w_unit)`,
    /// and a caller that knows `c / |d|` (a constraint whose error is `d` itself) never
    /// waits for a square root and a division to normalise `d` before the levers.
    #[inline]
    pub fn along_scaled(
        bones: &[Bone],
        (a, pa): (Side, Vec3A),
        (b, pb): (Side, Vec3A),
        d: Vec3A,
        d2: f32,
    ) -> Self {
        let (a, wa) = Lever::of(bones, a, Some(pa), d, d2);
        let (b, wb) = Lever::of(bones, b, Some(pb), d, d2);
        Correction {
            a,
            b,
            n: d,
            w: wa + wb,
        }
    }

    /// Turning side `a` about `n` and `b` against it; no point moves along `n`. For a
    /// unit `n`, `w` is the inverse inertia about it; otherwise `|n|²` times that.
    #[inline]
    pub fn turning(bones: &[Bone], a: Side, b: Side, n: Vec3A) -> Self {
        let (a, wa) = Lever::of(bones, a, None, n, 1.0);
        let (b, wb) = Lever::of(bones, b, None, n, 1.0);
        Correction {
            a,
            b,
            n: Vec3A::ZERO,
            w: wa + wb,
        }
    }

    /// Applies the multiplier `λ`: `pa − pb` changes by `n λ w`.
    #[inline]
    pub fn apply(self, bones: &mut [Bone], lambda: f32) {
        if let Some(l) = self.a {
            l.apply(bones, self.n * lambda, lambda);
        }
        if let Some(l) = self.b {
            l.apply(bones, -self.n * lambda, -lambda);
        }
    }

    /// Applies the velocity impulse `λ`: the velocity of `pa` relative to `pb` changes
    /// by `n λ w`.
    #[inline]
    pub fn apply_velocity(self, bones: &mut [Bone], lambda: f32) {
        if let Some(l) = self.a {
            l.apply_velocity(bones, self.n * lambda, lambda);
        }
        if let Some(l) = self.b {
            l.apply_velocity(bones, -self.n * lambda, -lambda);
        }
    }
}

/// XPBD positional constraint between two sides (Müller et al. 2020, eq. 2–5): moves
/// the points so that `pa − pb` changes by `delta`, splitting by generalised inverse
/// mass; `alpha_tilde` = compliance / h². Returns the Lagrange multiplier λ (≥ 0).
///
/// With `c = |delta|`, `λ = c / (w + α̃)` along `delta / c`, which is `μ = λ / c =
/// c² / (W + α̃ c²)` along `delta` itself, `W = c² w` ([`Correction::along_scaled`]):
/// the levers start from `delta` at once instead of after a square root and a
/// division, which sat on the dependency chain of every contact and joint (each
/// correction waits for the last one's turn of the same bone).
pub(crate) fn positional(
    bones: &mut [Bone],
    a: Side,
    b: Side,
    pa: Vec3A,
    pb: Vec3A,
    delta: Vec3A,
    alpha_tilde: f32,
) -> f32 {
    let c2 = delta.length_squared();
    if c2 < 1e-18 {
        return 0.0;
    }
    let corr = Correction::along_scaled(bones, (a, pa), (b, pb), delta, c2);
    let den = corr.w + alpha_tilde * c2;
    if den <= 0.0 {
        return 0.0;
    }
    let mu = c2 / den;
    corr.apply(bones, mu);
    mu * c2.sqrt()
}

/// [`positional`] along a known unit direction `n` by `c > 0`: `pa − pb` changes by
/// `n c`. Returns λ.
pub(crate) fn positional_along(
    bones: &mut [Bone],
    (a, pa): (Side, Vec3A),
    (b, pb): (Side, Vec3A),
    n: Vec3A,
    c: f32,
) -> f32 {
    if c < 1e-9 {
        return 0.0;
    }
    let corr = Correction::along(bones, (a, pa), (b, pb), n);
    if corr.w <= 0.0 {
        return 0.0;
    }
    let lambda = c / corr.w;
    corr.apply(bones, lambda);
    lambda
}

/// XPBD angular constraint: rotates side `a` relative to `b` by the rotation vector
/// `dphi` (split by generalised inverse inertia). As in [`positional`], the turn is
/// `μ = φ² / (W + α̃ φ²)` about `dphi` itself, `W = φ² w` the inverse inertia about it
/// unnormalised, rather than `φ / (w + α̃)` about `dphi / φ`.
pub(crate) fn angular(bones: &mut [Bone], a: Side, b: Side, dphi: Vec3A, alpha_tilde: f32) {
    let angle2 = dphi.length_squared();
    if angle2 < 1e-18 {
        return;
    }
    let corr = Correction::turning(bones, a, b, dphi);
    let den = corr.w + alpha_tilde * angle2;
    if den <= 0.0 {
        return;
    }
    corr.apply(bones, angle2 / den);
}

/// Orientation of a side (identity for the world).
pub(crate) fn side_rot(bones: &[Bone], s: Side) -> Quat {
    s.map_or(Quat::IDENTITY, |i| bones[i].rot)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Shape matching itself: the rotational part of `A = Σ (x_k − c) rest_kᵀ` by Müller
    /// et al. 2016's iteration `q ← exp(ω) q`, `ω = Σ r_k × a_k / |Σ r_k · a_k|`,
    /// warm-started from `q`, with the tolerance and cap of [`matched_turn`].
    fn extract(a: Mat3, mut q: Quat) -> Quat {
        for _ in 0..EXTRACT_ITERATIONS {
            let r = Mat3::from_quat(q);
            let num =
                r.x_axis.cross(a.x_axis) + r.y_axis.cross(a.y_axis) + r.z_axis.cross(a.z_axis);
            let den =
                (r.x_axis.dot(a.x_axis) + r.y_axis.dot(a.y_axis) + r.z_axis.dot(a.z_axis)).abs();
            let omega = num / den;
            let w = omega.length();
            if w == 0.0 || !w.is_finite() {
                break;
            }
            q = (Quat::from_axis_angle(omega / w, w) * q).normalize();
            if w < EXTRACT_TOLERANCE {
                break;
            }
        }
        q
    }

    /// `matched_turn` against the particles advanced and shape-matched one by one, for a
    /// long bone (0.4 × 0.08 × 0.08 m: where the extraction lags, about its own axis) and
    /// a chest box (0.196 × 0.125 × 0.2045 m: three different axes, where the turn
    /// converges and its second-order, gyroscopic part shows), turning slowly and fast.
    /// Returns the worst error relative to the substep's turn above 1 rad/s, per shape.
    fn worst_errors(f: impl Fn(Quat, Vec3, Vec3) -> Quat) -> [f32; 2] {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
        let h = 1.0 / 1200.0;
        let mut worst = [0.0f32; 2];
        for (s, size) in [Vec3::new(0.4, 0.08, 0.08), Vec3::new(0.196, 0.125, 0.2045)]
            .into_iter()
            .enumerate()
        {
            let rest = [
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(-1.0, 1.0, -1.0),
                Vec3::new(-1.0, -1.0, 1.0),
            ]
            .map(|c| c * size * 0.5 / 3f32.sqrt());
            let m = turn_lag(&rest);
            let (x, y, z) = (q * Vec3::X, q * Vec3::Y, q * Vec3::Z);
            for w in [
                x * 0.01,
                x * 2.0,
                x * 40.0,
                y * 0.01,
                y * 40.0,
                (x + y * 0.5) * 25.0,
                (x * 0.3 + y + z * 0.7) * 30.0,
            ] {
                let a = rest.iter().fold(Mat3::ZERO, |acc, r| {
                    let arm = q * *r;
                    let p = arm + w.cross(arm) * h;
                    acc + Mat3::from_cols(p * r.x, p * r.y, p * r.z)
                });
                let reference = extract(a, q);
                let ours = f(q, w * h, m);
                let diff = 2.0 * (ours * reference.inverse()).xyz().length();
                let turn = w.length() * h;
                assert!(
                    diff <= 0.01 * turn + 2e-6,
                    "ω {w}: off by {diff:e} of {turn:e}"
                );
                if w.length() > 1.0 {
                    worst[s] = worst[s].max(diff / turn);
                }
                if s == 0 && w == x * 0.01 {
                    // The slow twist of a long bone lags: the extraction stops after
                    // one iteration, which turns it by a tenth.
                    let turned = 2.0 * (ours * q.inverse()).xyz().length();
                    assert!(turned < 0.5 * turn, "no lag: {turned:e} of {turn:e}");
                }
            }
        }
        worst
    }

    /// The closed-form velocity is the particles' own, `v = Σ v_k / 4` and `ω = I⁻¹
    /// Σ (M/4) r_k × (v_k − v)` with `v_k = (Δc + (R − P) rest_k) / h`, to rounding: the
    /// human's 16 bones (long limbs, the chest), each turned by up to 0.05 rad about
    /// random axes in a substep from random frames.
    #[test]
    fn substep_velocity_is_the_particles_momentum() {
        use super::super::{scene_world, uniform};
        let w = scene_world("human.af", None);
        let mut next = uniform(0x5eed_1234);
        let h = 1.0 / 1200.0;
        for case in 0..800 {
            let mut random = || Vec3::new(next(), next(), next()) * 2.0 - Vec3::ONE;
            let mut b = w.bones[case % w.bones.len()].clone();
            let turn = random().normalize_or_zero() * 0.05 * (case as f32 / 800.0);
            b.prev_rot = Quat::from_scaled_axis(random() * 3.0);
            b.rot = (Quat::from_scaled_axis(turn) * b.prev_rot).normalize();
            b.dcom = Vec3A::from(random() * 0.01);
            let arms = b.rest.map(|r| b.rot * Vec3A::from(r));
            let vk: Vec<Vec3A> = (0..4)
                .map(|k| (b.dcom + (arms[k] - b.prev_rot * Vec3A::from(b.rest[k]))) / h)
                .collect();
            let v = (vk[0] + vk[1] + vk[2] + vk[3]) * 0.25;
            let l = (0..4).fold(Vec3A::ZERO, |l, k| {
                l + arms[k].cross(vk[k] - v) * (b.mass * 0.25)
            });
            let omega = b.rot * (b.inv_inertia_local * (b.rot.inverse() * l));
            let (ours_v, ours_w) = b.substep_velocity(h);
            assert!(
                (ours_v - v).length() < 1e-4,
                "case {case}: {ours_v} against {v}"
            );
            // Measured: within 1e-5 of the rate plus 1e-4 rad/s (the particles' form
            // takes differences of rotated points); without the `(D u) × u` term the
            // test fails.
            let tol = 1e-4 * omega.length() + 1e-3;
            assert!(
                (ours_w - omega).length() < tol,
                "case {case}: {ours_w} against {omega}"
            );
        }
    }

    /// The renormalisation's series against the exact one: unit length and the same
    /// rotation to f32 rounding, for turns from a micro-radian to half a radian (where
    /// the exact branch takes over).
    #[test]
    fn rotate_local_stays_unit_and_matches_exact_normalisation() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.7, -0.4, 2.1);
        for angle in [1e-6f32, 1e-4, 1e-3, 1e-2, 0.05, 0.1, 0.125, 0.13, 0.2, 0.5] {
            for axis in [Vec3A::X, Vec3A::new(0.3, -0.5, 0.8).normalize()] {
                let theta = axis * angle;
                let ours = rotate_local(q, theta);
                let dq = q * Quat::from_xyzw(theta.x, theta.y, theta.z, 0.0);
                let exact = (q + dq * 0.5).normalize();
                assert!(
                    (ours.length() - 1.0).abs() < 3e-7,
                    "{angle}: |q| = {}",
                    ours.length()
                );
                let off = (ours - exact).length();
                assert!(off < 3e-7, "{angle}: {off:e} from the exact normalisation");
            }
        }
    }

    /// The closed form is the shape matching it replaces: within 1 % of the substep's
    /// turn everywhere (the long bone's capped twist), and within 0.1 % on the chest box,
    /// where the first-order turn alone is off by more.
    #[test]
    fn matched_turn_is_shape_matching_in_closed_form() {
        let [limb, chest] = worst_errors(matched_turn);
        assert!(limb < 0.01, "long bone: {limb}");
        assert!(chest < 1e-3, "chest: {chest}");
        // Without the second-order term the chest box is off by more: the test sees it.
        let first_order = |q: Quat, turn: Vec3, m: Vec3| {
            let full = q.inverse() * turn;
            let mut e = full;
            for _ in 0..EXTRACT_ITERATIONS {
                let step = (Vec3::ONE - m) * e;
                e *= m;
                if step.length_squared() < EXTRACT_TOLERANCE * EXTRACT_TOLERANCE {
                    break;
                }
            }
            let t = full - e;
            (q + q * Quat::from_xyzw(t.x, t.y, t.z, 0.0) * 0.5).normalize()
        };
        let [_, chest_first] = worst_errors(first_order);
        assert!(chest_first > 2.0 * chest, "{chest_first} against {chest}");
    }
}
