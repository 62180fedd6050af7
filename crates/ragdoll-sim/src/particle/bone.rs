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
//! The rigid-frames solver also moves a bone *rigidly*: a correction impulse `p` at
//! world point `r` translates the centre of mass by `p/M` and rotates by `I⁻¹ (r − c) ×
//! p`, then rewrites the four particles from the frame. For particles that reproduce M,
//! c and I exactly this is the limit of infinitely stiff sticks, reached in one step; a
//! free bone moves as that limit does, keeping its momentum and angular momentum
//! ([`Bone::advance`]).

use super::bone_kinds::BoneKinds;
use crate::scene::{BodyCollider, Pose};
use glam::{Mat3, Quat, Vec3, Vec3A};

/// The six edges of a tetrahedron, as pairs of corner indices.
pub(crate) const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// One bone's own state: its motion (read and written every substep), its mass
/// properties (read by every correction), its sleep state, and the indices of what it
/// shares with bones of its kind ([`BoneKinds`]): 192 bytes.
#[derive(Clone)]
pub(crate) struct Bone {
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
    /// The turn since the substep's start, in the frame at its start (`rot ≈ prev_rot
    /// dturn`): every turn of the frame is also made here. Kept apart for the same
    /// reason as `dcom`: read from `prev_rot⁻¹ rot`, the turn carries the rounding of
    /// the frame (an ulp, 6e-8), an angular velocity error of `ulp / h` a substep that
    /// adds up as a random walk (the spider at 1/1000 s and 200 substeps gained a third
    /// of its energy scale); near the identity the turn keeps its relative precision.
    pub dturn: Quat,
    /// Linear velocity of the frame origin (m/s), from the particles.
    pub lin_vel: Vec3A,
    /// Angular velocity (rad/s, world), from the particles.
    pub ang_vel: Vec3A,
    /// Inverse inertia in the bone frame (diagonal: the frame is principal).
    pub inv_inertia_local: Vec3A,
    /// Total mass (kg).
    pub mass: f32,
    /// Index of the scene body.
    pub body: u32,
    /// Connected component of the joint graph ("figure").
    pub figure: u32,
    /// Its shape: [`BoneKinds::of`].
    pub kind: u32,
    /// Its rest corners and shape frame: [`BoneKinds::placement`].
    pub placement: u32,
    /// Its contact and air materials: [`BoneKinds::material`].
    pub material: u32,
    /// Seconds this bone has been below the sleep speeds.
    pub sleep_time: f32,
    /// Where the bone's frame origin was when it last moved more than the no-move
    /// bounds (its orientation then is `still_turn`; two fields, not a `(Vec3, Quat)`,
    /// so the 12-byte position packs with the bone's 4-byte fields instead of padding
    /// to 16).
    pub still_at: Vec3,
    /// The bone's orientation when it last moved more than the no-move bounds.
    pub still_turn: Quat,
    /// Seconds the bone has stayed within the no-move bounds of `still_at` and
    /// `still_turn`.
    pub still_time: f32,
    /// Fixed bones never move.
    pub fixed: bool,
    /// Asleep bones are frozen until something wakes their island.
    pub asleep: bool,
    /// Collides with bones of its own figure.
    pub self_collision: bool,
}

const _: () = assert!(std::mem::size_of::<Bone>() == 192);

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
        self.still_at = Vec3::from(self.center());
        self.still_turn = self.rot;
    }

    /// Takes `from`'s motion: all that the rigid-frames solver's substeps write of a bone
    /// (its frame, the substep's start and displacement, its velocities), about a
    /// third of its bytes. A batch of islands returns its bones to the world through this
    /// (`islands`); `particle_threads` checks the result is the serial one bit for bit.
    pub fn take_motion(&mut self, from: &Bone) {
        self.com = from.com;
        self.dcom = from.dcom;
        self.rot = from.rot;
        self.prev_rot = from.prev_rot;
        self.dturn = from.dturn;
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

    /// World inverse inertia `R I⁻¹ Rᵀ` at the bone's orientation now.
    pub fn inv_inertia_world(&self) -> Mat3 {
        let r = Mat3::from_quat(self.rot);
        r * Mat3::from_diagonal(Vec3::from(self.inv_inertia_local)) * r.transpose()
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

    /// World pose of the shape frame (its placement in `kinds`).
    pub fn shape_pose(&self, kinds: &BoneKinds) -> Pose {
        Pose {
            position: Vec3::from(self.center()),
            rotation: self.rot,
        }
        .mul_pose(&kinds.placement(self).shape_in_bone)
    }

    /// The shape pose in parry's type.
    pub fn parry_pose(&self, kinds: &BoneKinds) -> parry3d::math::Pose {
        let p = self.shape_pose(kinds);
        parry3d::math::Pose::from_parts(p.position, p.rotation)
    }

    /// World position of a point given in the bone frame.
    pub fn world(&self, local: Vec3) -> Vec3A {
        self.com + (self.dcom + self.rot * Vec3A::from(local))
    }

    /// Improved mode: particle `k`, rigidly placed in the frame. Between substeps this is
    /// where the solver's particle is; the improved world stores no particle arrays.
    pub fn corner(&self, kinds: &BoneKinds, k: usize) -> Vec3 {
        Vec3::from(self.world(kinds.placement(self).rest[k]))
    }

    /// Improved mode: the velocity of particle `k` as the next substep starts from it,
    /// the frame's rigid motion `v + ω × (R rest_k)`.
    pub fn corner_velocity(&self, kinds: &BoneKinds, k: usize) -> Vec3 {
        let rest = kinds.placement(self).rest[k];
        Vec3::from(self.lin_vel + self.ang_vel.cross(self.rot * Vec3A::from(rest)))
    }

    /// The rest lengths of the six sticks (`EDGES`) between the rest particles: the
    /// rigid-frames and XPBD solvers' sticks, made from these same points (the paper
    /// solver measures its sticks from the world positions it placed, `paper::add_bone`,
    /// and keeps them in its own stick list).
    pub fn rest_stick_lengths(&self, kinds: &BoneKinds) -> [f32; 6] {
        let rest = &kinds.placement(self).rest;
        EDGES.map(|(a, b)| rest[a].distance(rest[b]))
    }

    /// Largest relative stick-length error of the bone whose particles are `corners`,
    /// sticks of rest lengths `stick_rest` (`EDGES`).
    pub fn stretch(corners: &[Vec3; 4], stick_rest: &[f32; 6]) -> f32 {
        let mut worst = 0.0f32;
        for (k, &(i, j)) in EDGES.iter().enumerate() {
            let l = corners[i].distance(corners[j]);
            let r = stick_rest[k];
            if r > 0.0 {
                worst = worst.max((l - r).abs() / r);
            }
        }
        worst
    }

    /// Rigid-frames mode, substep steps 1–2: advances the frame by its velocity, as the
    /// four particles of an infinitely stiff tetrahedron move: the centre of mass by
    /// `(v + g h) h` (to `dcom`), the orientation by the turn `θ` that keeps the angular
    /// momentum `L = R I Rᵀ ω` of a free body.
    ///
    /// The turn is the implicit midpoint rule on the rotation group: `θ = h R_m I⁻¹ R_mᵀ
    /// L`, `R_m` the frame half-way through the turn, `R_m = R m(θ)`. With `Π = Rᵀ L`
    /// (the momentum in the frame at the substep's start) and every turn in that frame,
    /// `θ = h m I⁻¹ m⁻¹ Π`, solved by fixed-point iteration from `θ = h Rᵀ ω`; each
    /// iteration contracts the error by about `h |ω|` times the inertia's anisotropy, and
    /// [`TURN_ITERATIONS`] leave it at f32 rounding at the substep rates used. The frame
    /// turns by the Cayley rotation `cay(θ) = (1, θ/2)/|·|` ([`rotate_local`]) and `m` is
    /// its half, `(1 + cay(θ))/|·|`; [`Bone::substep_velocity`] inverts exactly this map,
    /// so that with no correction in between, the momentum carried to the next substep is
    /// `L` itself: `|L|` and the direction of `L` are kept to rounding and the kinetic
    /// energy `½ ω·L` is kept without drift (it wobbles by `O(h²)` on a tumbling body).
    /// Gyroscopic motion — precession, the flip about the intermediate axis — is the
    /// turn of `ω` under a fixed `L`, and comes from this with no torque term.
    pub fn advance(&mut self, h: f32, gravity: Vec3) {
        advance_group([self], h, gravity);
    }

    /// Rigid-frames mode, substep step 4: the bone's velocity at the end of the substep
    /// from its motion over the substep, the frame's whole turn (its own and every
    /// correction's) and the displacement of its centre.
    ///
    /// `v = Δc / h`. The turn from the start frame `P` to the frame now `R = P d` is read
    /// back through the inverse Cayley map, `θ = 2 d_v / d_w` (in `P`'s frame), the map
    /// [`Bone::advance`] turns by, so a free substep gives back its own turn to rounding.
    /// `θ / h` is the angular velocity half-way through the substep, at the frame
    /// `R_m = P m`, `m = (1 + d)/|·|`; its momentum `L = P m I θ / h` (`m` turns about `θ`,
    /// so `m⁻¹ θ = θ`) is carried to the end, `ω = R I⁻¹ Rᵀ L = R I⁻¹ m⁻¹ I θ / h`
    /// (`d⁻¹ m = m⁻¹`). Taking `θ / h` as the end velocity instead would turn `L` by half
    /// the substep's turn at every substep.
    pub fn substep_velocity(&self, h: f32) -> (Vec3A, Vec3A) {
        let mut d = self.dturn;
        if d.w < 0.0 {
            d = -d;
        }
        // A frame turned by more than about 170° in a substep (never at the rates a
        // scene runs) reads as that much, not as an unbounded rate.
        let turn = Vec3A::new(d.x, d.y, d.z) * (2.0 / d.w.max(MIN_TURN_COSINE));
        let m = half_turn(d);
        let inertia = inertia_of(self.inv_inertia_local);
        let local = self.inv_inertia_local * (m.inverse() * (inertia * turn));
        (self.dcom / h, self.rot * local * (1.0 / h))
    }

    /// The paper's frame (section 3.1.2) of the bone whose particles are `ids`: origin
    /// at particle 0, X towards particle 1, Y towards particle 2 orthogonalised, Z = X ×
    /// Y.
    pub fn paper_frame(&mut self, ids: [u32; 4], x: &[Vec3]) {
        let p0 = x[ids[0] as usize];
        let (r, ok) = gram_schmidt(x[ids[1] as usize] - p0, x[ids[2] as usize] - p0);
        if ok {
            self.rot = r;
        }
        self.com = Vec3A::from(p0);
    }
}

/// [`Bone::advance`] of every moving bone of `bones`, four at a time
/// ([`advance_group`]).
pub(crate) fn advance_moving(bones: &mut [Bone], h: f32, gravity: Vec3) {
    let mut moving = bones.iter_mut().filter(|b| !b.is_static());
    while let Some(first) = moving.next() {
        match (moving.next(), moving.next(), moving.next()) {
            (Some(b), Some(c), Some(d)) => advance_group([first, b, c, d], h, gravity),
            (b, c, d) => {
                for bone in [Some(first), b, c, d].into_iter().flatten() {
                    bone.advance(h, gravity);
                }
            }
        }
    }
}

/// [`Bone::advance`] of `N` bones side by side: each bone's turn is a chain of square
/// roots and divisions (two normalisations per fixed-point iteration), and one bone's
/// chain leaves the processor waiting; the chains of `N` bones, step by step in one
/// loop, overlap. Each bone gets the same operations in the same order as alone, so the
/// same bits.
#[inline(always)]
fn advance_group<const N: usize>(mut bones: [&mut Bone; N], h: f32, gravity: Vec3) {
    let mut momentum = [Vec3A::ZERO; N];
    let mut turn = [Vec3A::ZERO; N];
    for (k, b) in bones.iter_mut().enumerate() {
        b.dcom = (b.lin_vel + Vec3A::from(gravity) * h) * h;
        let inertia = inertia_of(b.inv_inertia_local);
        let w = b.rot.inverse() * b.ang_vel;
        momentum[k] = inertia * w;
        turn[k] = w * h;
    }
    for _ in 0..TURN_ITERATIONS {
        for (k, b) in bones.iter().enumerate() {
            let m = half_turn(cayley(turn[k]));
            turn[k] = m * (b.inv_inertia_local * (m.inverse() * momentum[k])) * h;
        }
    }
    for (b, turn) in bones.iter_mut().zip(turn) {
        b.rot = rotate_local(b.rot, turn);
        b.dturn = rotate_local(b.dturn, turn);
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

/// Fixed-point iterations of the implicit turn ([`Bone::advance`]).
const TURN_ITERATIONS: usize = 3;

/// Smallest `w` of a substep's relative turn that [`Bone::substep_velocity`] divides by
/// (`cos 85°`, a turn of 170°).
const MIN_TURN_COSINE: f32 = 0.087;

/// The inertia from the inverse inertia, per principal axis (zero where the inverse is
/// zero: an axis that takes no turn).
fn inertia_of(inv: Vec3A) -> Vec3A {
    Vec3A::select(inv.cmpgt(Vec3A::ZERO), inv.recip(), Vec3A::ZERO)
}

/// The Cayley rotation of the rotation vector `θ`, `(1, θ/2)` normalised: the turn
/// [`rotate_local`] makes (by the angle `2 atan(|θ|/2)` about `θ`).
fn cayley(turn: Vec3A) -> Quat {
    Quat::from_xyzw(0.5 * turn.x, 0.5 * turn.y, 0.5 * turn.z, 1.0).normalize()
}

/// The half of a unit rotation `q` with `w ≥ 0`: `(1 + q)/|1 + q|`.
fn half_turn(q: Quat) -> Quat {
    Quat::from_xyzw(q.x, q.y, q.z, q.w + 1.0).normalize()
}

/// A static-or-moving side of a two-body constraint: a bone, or the world/ground.
pub(crate) type Side = Option<usize>;

/// Where a capsule's surface faces `dir` (world, unit) nearest bone-frame point `local`,
/// in the bone frame as it stands now: the point of its core
/// segment nearest `local`, moved out by the radius along `dir`. `None` for a shape
/// that is not round all over (a box, cylinder, cone or hull keeps its material
/// points: they do not roll).
pub(crate) fn rolled_point(b: &Bone, kinds: &BoneKinds, local: Vec3, dir: Vec3A) -> Option<Vec3> {
    let BodyCollider::Capsule {
        half_height,
        radius,
    } = kinds.of(b).shape
    else {
        return None;
    };
    let s = kinds.placement(b).shape_in_bone;
    let along = s
        .inverse_transform_point(local)
        .y
        .clamp(-half_height, half_height);
    let facing = s.inverse_transform_vector(Vec3::from(b.rot.inverse() * dir));
    Some(s.transform_point(Vec3::new(0.0, along, 0.0) + facing * radius))
}

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
        b.dturn = rotate_local(b.dturn, self.turn * lambda);
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
#[derive(Clone, Copy)]
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

/// Which frame a joint's point correction (`bone_lanes::point`) takes its arms from.
///
/// A projection at the substep's end — arms from the frame now, as position-based
/// dynamics projects — turns part of every correction across the motion: gravity
/// stretches a hanging joint along the arm the substep has already turned, and the
/// correction along it takes some of the swing. A frictionless pendulum then loses
/// energy at `ω₀² h` a second, 8.6 % in 10 s at 5° amplitude and 1/1200 s substeps.
/// Aimed from the substep's start (the constraint force's direction at the start of
/// the step, as SHAKE/RATTLE take it; Andersen 1983), what is left is of second order.
/// A correction aimed from the start is not a projection, though, and on a chain the
/// Gauss–Seidel passes leave part of each joint's correction undone, which then may
/// add energy as well as take it (a freely swinging chain of five links gained 3.7 %
/// of its energy scale with every pass aimed from the start). So the first pass aims
/// from the start and the later ones project from the end: the residual the first
/// leaves is taken out by projections, which can only take energy, and on a single
/// joint the first pass has already closed the gap, so the projections have nothing
/// left to turn. (With five passes on the lab humanoid, all but the last aimed from the
/// start gained 1.2 % of its energy scale in the median over 72 starts, only the first
/// 0.7 %.)
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Aim {
    /// Arms from the frame at the substep's start, `R₀ p = R d⁻¹ p` (`Bone::dturn`).
    Start,
    /// Arms from the frame now, `R p`: a projection.
    End,
}

impl Aim {
    /// The aim of pass `pass` of `passes`: the first from the start, the later ones
    /// from the end (a single pass from the end).
    pub fn of_pass(pass: u32, passes: u32) -> Aim {
        if pass == 0 && passes > 1 {
            Aim::Start
        } else {
            Aim::End
        }
    }
}

/// Orientation of a side (identity for the world).
pub(crate) fn side_rot(bones: &[Bone], s: Side) -> Quat {
    s.map_or(Quat::IDENTITY, |i| bones[i].rot)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bones advanced four at a time (`advance_moving`) get the bits each gets advanced
    /// alone, and the static ones stay put: two humans of the pile, every bone spun and
    /// moving at random, every third one asleep (so the groups of four skip bones and
    /// the last group is short).
    #[test]
    fn bones_advanced_together_get_the_bits_of_each_alone() {
        use super::super::{scene_world, uniform};
        let h = 1.0 / 1200.0;
        let gravity = Vec3::new(0.0, -9.81, 0.0);
        let mut w = scene_world("pile.af", Some(2));
        let mut next = uniform(0x5eed_1234);
        let mut spin = || Vec3A::new(next(), next(), next()) * 40.0 - Vec3A::splat(20.0);
        for (i, b) in w.bones.iter_mut().enumerate() {
            b.ang_vel = spin();
            b.lin_vel = spin() * 0.1;
            b.asleep = i % 3 == 1;
        }
        let mut together = w.bones.clone();
        advance_moving(&mut together, h, gravity);
        let mut alone = w.bones.clone();
        for b in alone.iter_mut().filter(|b| !b.is_static()) {
            b.advance(h, gravity);
        }
        let state = |b: &Bone| (b.rot, b.dturn, b.dcom);
        for (i, (t, a)) in together.iter().zip(&alone).enumerate() {
            assert!(state(t) == state(a), "bone {i}: advanced together differs");
            if w.bones[i].asleep {
                assert!(state(t) == state(&w.bones[i]), "sleeping bone {i} moved");
            } else {
                assert!(t.rot != w.bones[i].rot, "bone {i} did not turn");
            }
        }
    }

    /// A free bone tumbling about a general axis, substep after substep with nothing in
    /// between (`advance`, then `substep_velocity`, as the solver runs them): the world
    /// angular momentum stays put to rounding and the kinetic energy does not drift. The
    /// human's chest (three different inertias) and a forearm (two nearly equal, one
    /// small), at the solver's substep of 1/1200 s and at a coarse 1/60 s, for 10 s.
    #[test]
    fn free_turn_keeps_angular_momentum_and_energy() {
        use super::super::scene_world;
        let w = scene_world("human.af", None);
        for (i, h) in [(2usize, 1.0 / 1200.0), (2, 1.0 / 60.0), (5, 1.0 / 1200.0)] {
            let h: f32 = h;
            let mut b = w.bones[i].clone();
            b.rot = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
            b.ang_vel = Vec3A::new(3.0, -7.0, 5.0);
            let inertia = inertia_of(b.inv_inertia_local);
            let state = |b: &Bone| {
                let l = b.rot * (inertia * (b.rot.inverse() * b.ang_vel));
                (l, 0.5 * b.ang_vel.dot(l))
            };
            let (l0, e0) = state(&b);
            let (mut worst_l, mut worst_e) = (0.0f32, 0.0f32);
            for _ in 0..(10.0 / h) as usize {
                b.prev_rot = b.rot;
                b.dturn = Quat::IDENTITY;
                b.advance(h, Vec3::ZERO);
                (b.lin_vel, b.ang_vel) = b.substep_velocity(h);
                let (l, e) = state(&b);
                worst_l = worst_l.max((l - l0).length() / l0.length());
                worst_e = worst_e.max((e - e0).abs() / e0);
            }
            println!("bone {i}, h {h}: L within {worst_l}, energy within {worst_e}");
            // The bounds of a torque-free body over 10 s: |L| within 1 %, energy within
            // 2 %.
            assert!(worst_l < 0.01, "bone {i}, h {h}: L off by {worst_l}");
            assert!(worst_e < 0.02, "bone {i}, h {h}: energy off by {worst_e}");
        }
    }

    /// A turn made by [`rotate_local`] reads back as itself: the velocity of a bone turned
    /// by `θ` about a principal axis in a substep is `θ / h` about it, to the rounding of
    /// the turn (a few ulps of its size over `h`).
    #[test]
    fn substep_velocity_reads_back_the_turn() {
        use super::super::scene_world;
        let w = scene_world("human.af", None);
        let h = 1.0 / 1200.0;
        let mut b = w.bones[5].clone();
        for axis in [Vec3A::X, Vec3A::Y, Vec3A::Z] {
            for angle in [1e-4f32, 0.01, 0.3] {
                b.prev_rot = Quat::from_euler(glam::EulerRot::XYZ, 0.7, -0.4, 2.1);
                b.rot = rotate_local(b.prev_rot, axis * angle);
                b.dturn = rotate_local(Quat::IDENTITY, axis * angle);
                let (_, omega) = b.substep_velocity(h);
                let expected = b.prev_rot * axis * (angle / h);
                assert!(
                    (omega - expected).length() <= 1e-5 * expected.length(),
                    "{axis} by {angle}: {omega} against {expected}"
                );
            }
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
}
