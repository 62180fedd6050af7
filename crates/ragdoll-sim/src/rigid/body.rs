//! Rigid bodies as structure-of-arrays: the hot state the solver touches every substep
//! ([`BodyStates`]) apart from the cold description it reads once per step or less
//! ([`BodyInfo`]).
//!
//! The solver addresses bodies by index. Index `len()` of the hot arrays is the
//! *static anchor*: a body with zero inverse mass and zero velocity that stands for the
//! world (`body2 "world"`) and the ground, so constraint code never branches on it.

use crate::lanes::{LANES, Mat3x4, Vec3x4};
use crate::scene::{BodyDesc, Collider, MassProps, Shape};
use glam::{Mat3, Mat3A, Quat, Vec3, Vec3A};
use parry3d::shape::SharedShape;
use wide::f32x4;

/// Hot per-body state, one entry per body plus the trailing static anchor.
#[derive(Clone, Debug, Default)]
pub struct BodyStates {
    /// Centre of mass (world).
    pub com: Vec<Vec3>,
    /// Orientation of the body (= of its shape frame).
    pub rot: Vec<Quat>,
    /// Linear velocity of the centre of mass.
    pub lin_vel: Vec<Vec3A>,
    /// Angular velocity (world).
    pub ang_vel: Vec<Vec3A>,
    /// Inverse mass; 0 for fixed, sleeping and the static anchor.
    pub inv_mass: Vec<f32>,
    /// World-space inverse inertia `R I⁻¹ Rᵀ`, refreshed every substep. Stored with
    /// 16-byte columns (`Mat3A`): every product with it is done in SIMD lanes, and a
    /// `Mat3` of 12-byte columns is widened column by column at each product (the same
    /// lanes, the same bits). 12 bytes a body.
    pub inv_inertia: Vec<Mat3A>,
}

/// The velocities of four pairs of bodies in SIMD lanes: linear and angular of each
/// lane's body a, then of its body b (the contact bundles' and joint lanes' working set).
pub(crate) type VelocitiesX4 = [Vec3x4; 4];

impl BodyStates {
    /// The linear and angular velocities of bodies `a[k]` and `b[k]` in lane `k`.
    #[inline(always)]
    pub(crate) fn velocities_x4(&self, a: [usize; LANES], b: [usize; LANES]) -> VelocitiesX4 {
        [
            Vec3x4::from_fn(|k| Vec3::from(self.lin_vel[a[k]])),
            Vec3x4::from_fn(|k| Vec3::from(self.ang_vel[a[k]])),
            Vec3x4::from_fn(|k| Vec3::from(self.lin_vel[b[k]])),
            Vec3x4::from_fn(|k| Vec3::from(self.ang_vel[b[k]])),
        ]
    }

    /// Writes [`BodyStates::velocities_x4`] back for the lanes `used(k)`, each body only
    /// if its solver inverse mass (`inv_mass_a`, `inv_mass_b`) is positive: static and
    /// sleeping bodies keep theirs, as a one-by-one solve leaves them. No moving body
    /// may be in two lanes.
    #[inline(always)]
    pub(crate) fn set_velocities_x4(
        &mut self,
        [a, b]: [[usize; LANES]; 2],
        [inv_mass_a, inv_mass_b]: [f32x4; 2],
        [va, wa, vb, wb]: &VelocitiesX4,
        used: impl Fn(usize) -> bool,
    ) {
        for k in (0..LANES).filter(|&k| used(k)) {
            if inv_mass_a.as_array()[k] > 0.0 {
                self.lin_vel[a[k]] = Vec3A::from(va.lane(k));
                self.ang_vel[a[k]] = Vec3A::from(wa.lane(k));
            }
            if inv_mass_b.as_array()[k] > 0.0 {
                self.lin_vel[b[k]] = Vec3A::from(vb.lane(k));
                self.ang_vel[b[k]] = Vec3A::from(wb.lane(k));
            }
        }
    }

    /// The world inverse inertias of bodies `i[k]` in lane `k`.
    #[inline(always)]
    pub(crate) fn inv_inertia_x4(&self, i: [usize; LANES]) -> Mat3x4 {
        Mat3x4::from_fn(|k| Mat3::from(self.inv_inertia[i[k]]))
    }

    /// Empty arrays with room for `n` entries: the world knows its body count when it is
    /// built, and pushing one by one would leave up to twice the room it needs.
    pub fn with_capacity(n: usize) -> BodyStates {
        BodyStates {
            com: Vec::with_capacity(n),
            rot: Vec::with_capacity(n),
            lin_vel: Vec::with_capacity(n),
            ang_vel: Vec::with_capacity(n),
            inv_mass: Vec::with_capacity(n),
            inv_inertia: Vec::with_capacity(n),
        }
    }

    /// Removes every entry, keeping the arrays' capacity.
    pub fn clear(&mut self) {
        self.com.clear();
        self.rot.clear();
        self.lin_vel.clear();
        self.ang_vel.clear();
        self.inv_mass.clear();
        self.inv_inertia.clear();
    }

    /// Number of entries including the static anchor.
    pub fn len(&self) -> usize {
        self.com.len()
    }

    /// Appends one body.
    pub fn push(&mut self, com: Vec3, rot: Quat, v: Vec3, w: Vec3) {
        self.com.push(com);
        self.rot.push(rot);
        self.lin_vel.push(Vec3A::from(v));
        self.ang_vel.push(Vec3A::from(w));
        self.inv_mass.push(0.0);
        self.inv_inertia.push(Mat3A::ZERO);
    }

    /// Appends a copy of body `i` of `from` (state, inverse mass and inertia).
    pub fn push_copy(&mut self, from: &BodyStates, i: usize) {
        self.com.push(from.com[i]);
        self.rot.push(from.rot[i]);
        self.lin_vel.push(from.lin_vel[i]);
        self.ang_vel.push(from.ang_vel[i]);
        self.inv_mass.push(from.inv_mass[i]);
        self.inv_inertia.push(from.inv_inertia[i]);
    }

    /// Overwrites body `i` with body `j` of `from`.
    pub fn copy_from(&mut self, i: usize, from: &BodyStates, j: usize) {
        self.com[i] = from.com[j];
        self.rot[i] = from.rot[j];
        self.lin_vel[i] = from.lin_vel[j];
        self.ang_vel[i] = from.ang_vel[j];
        self.inv_mass[i] = from.inv_mass[j];
        self.inv_inertia[i] = from.inv_inertia[j];
    }

    /// Whether an impulse can move body `i`: some inverse mass or inertia (zero for the
    /// static anchor, fixed and sleeping bodies, and bodies the projection pass holds).
    #[inline]
    pub fn is_mobile(&self, i: usize) -> bool {
        self.inv_mass[i] != 0.0 || self.inv_inertia[i] != Mat3A::ZERO
    }

    /// Velocity of the material point at world offset `r` from body `i`'s centre of mass.
    #[inline]
    pub fn point_velocity(&self, i: usize, r: Vec3A) -> Vec3A {
        self.lin_vel[i] + self.ang_vel[i].cross(r)
    }

    /// Applies the impulse `p` at offset `r` to body `i` (Newton: Δv = p/m, Δω = I⁻¹ r×p).
    #[inline]
    pub fn apply_impulse(&mut self, i: usize, r: Vec3A, p: Vec3A) {
        self.lin_vel[i] += p * self.inv_mass[i];
        self.ang_vel[i] += self.inv_inertia[i] * r.cross(p);
    }

    /// Applies the angular impulse `l` to body `i`.
    #[inline]
    pub fn apply_angular_impulse(&mut self, i: usize, l: Vec3A) {
        self.ang_vel[i] += self.inv_inertia[i] * l;
    }

    /// Moves body `i` as the *position* impulse `p` at offset `r` would (the projection
    /// pass): `Δx = p/m`, rotation by `Δθ = I⁻¹ (r × p)`. Velocities are untouched.
    #[inline]
    pub fn apply_position_impulse(&mut self, i: usize, r: Vec3, p: Vec3) {
        self.com[i] += p * self.inv_mass[i];
        self.rotate(i, self.inv_inertia[i] * r.cross(p));
    }

    /// Rotates body `i` by the angular position impulse `l`: `Δθ = I⁻¹ l`.
    #[inline]
    pub fn apply_angular_position_impulse(&mut self, i: usize, l: Vec3) {
        self.rotate(i, self.inv_inertia[i] * l);
    }

    /// `q += ½ (Δθ, 0) q`, renormalised: the first-order rotation by the small vector `Δθ`.
    #[inline]
    fn rotate(&mut self, i: usize, dtheta: Vec3) {
        if dtheta == Vec3::ZERO {
            return;
        }
        let q = self.rot[i];
        let dq = Quat::from_xyzw(dtheta.x, dtheta.y, dtheta.z, 0.0) * q;
        self.rot[i] = (q + dq * 0.5).normalize();
    }
}

/// What the integrator reads of a body every substep, constant over its life: kept
/// apart from the cold [`BodyInfo`] so an island can carry a compact copy of it to
/// another thread (see [`super::parallel`]).
///
/// The body-space inertia and its inverse are diagonal for every primitive (a box,
/// capsule, cylinder or cone is symmetric about its shape frame's axes), so they are kept
/// as their diagonals, 24 bytes instead of two `Mat3` (72). A tensor that is not exactly
/// diagonal (a convex hull, a skewed `inertiaScale`) is kept whole in the world's
/// [`FullInertia`] table and referred to by index. Either way the solver gets back the
/// very `Mat3` it was given, bit for bit (see [`BodyMotion::new`]).
#[derive(Clone, Copy, Debug)]
pub struct BodyMotion {
    /// Diagonal of the body-space inertia about the centre of mass, if `full` is `NONE`.
    inertia_diagonal: Vec3,
    /// Diagonal of the body-space inverse inertia (zero for fixed bodies), likewise.
    inv_inertia_diagonal: Vec3,
    /// Index of the body's tensors in the [`FullInertia`] table, or `NONE`.
    full: u32,
    /// Doom 3 air friction on translation, fraction of velocity lost per second.
    pub linear_damping: f32,
    /// Doom 3 air friction on rotation, fraction lost per second.
    pub angular_damping: f32,
}

/// No index: `BodyMotion::full` of a body whose tensors are diagonal, `BodyInfo::hull`
/// of a primitive.
const NONE: u32 = u32::MAX;

/// The inertia tensors of a body that are not diagonal in its shape frame.
#[derive(Clone, Copy, Debug)]
pub struct FullInertia {
    /// Body-space inertia about the centre of mass.
    pub inertia: Mat3,
    /// Body-space inverse inertia (zero for fixed bodies).
    pub inv_inertia_local: Mat3,
}

/// The motion data of some bodies and the table of full tensors their indices refer to.
#[derive(Clone, Copy, Debug)]
pub struct Motions<'a> {
    /// Per body.
    pub bodies: &'a [BodyMotion],
    /// The world's full tensors.
    pub full: &'a [FullInertia],
}

impl BodyMotion {
    /// Motion data of one body from its description and mass properties; a tensor that
    /// is not exactly diagonal goes to `full`. "Exactly" is to the bit (a `-0.0` off the
    /// diagonal counts as not diagonal), so `Mat3::from_diagonal` rebuilds the same
    /// matrix and every product with it is unchanged.
    pub fn new(desc: &BodyDesc, mp: &MassProps, full: &mut Vec<FullInertia>) -> BodyMotion {
        let inertia = mp.inertia;
        let inv_inertia_local = if desc.is_fixed() {
            Mat3::ZERO
        } else {
            mp.inverse_inertia()
        };
        let diagonal = |m: &Mat3| Vec3::new(m.x_axis.x, m.y_axis.y, m.z_axis.z);
        let is_diagonal = |m: &Mat3| {
            Mat3::from_diagonal(diagonal(m))
                .to_cols_array()
                .map(f32::to_bits)
                == m.to_cols_array().map(f32::to_bits)
        };
        let index = if is_diagonal(&inertia) && is_diagonal(&inv_inertia_local) {
            NONE
        } else {
            full.push(FullInertia {
                inertia,
                inv_inertia_local,
            });
            (full.len() - 1) as u32
        };
        BodyMotion {
            inertia_diagonal: diagonal(&inertia),
            inv_inertia_diagonal: diagonal(&inv_inertia_local),
            full: index,
            linear_damping: desc.friction.linear,
            angular_damping: desc.friction.angular,
        }
    }

    /// Body-space inertia about the centre of mass.
    #[inline]
    pub fn inertia(&self, full: &[FullInertia]) -> Mat3 {
        match full.get(self.full as usize) {
            Some(f) => f.inertia,
            None => Mat3::from_diagonal(self.inertia_diagonal),
        }
    }

    /// Body-space inverse inertia (zero for fixed bodies).
    #[inline]
    pub fn inv_inertia_local(&self, full: &[FullInertia]) -> Mat3 {
        match full.get(self.full as usize) {
            Some(f) => f.inv_inertia_local,
            None => Mat3::from_diagonal(self.inv_inertia_diagonal),
        }
    }
}

/// Cold per-body data: what the scene said, and what the solver derives from it once.
#[derive(Clone, Debug)]
pub struct BodyInfo {
    /// The scene shape: drawn in snapshots, and the collision shape itself for the
    /// primitives (see [`BodyInfo::collider`]).
    pub shape: Shape,
    /// Index of the body's parry collider in the world's hull table if it is a convex
    /// hull, built once (its faces and adjacency are worth keeping); `NONE` for the
    /// primitives, whose parry shapes are a few floats made on the spot instead of a
    /// shared allocation per body.
    hull: u32,
    /// Centre of mass in the shape frame.
    pub local_com: Vec3,
    /// Mass (kg), also for fixed bodies (they are treated as infinite).
    pub mass: f32,
    /// Fixed bodies never move.
    pub fixed: bool,
    /// Coulomb coefficient.
    pub friction: f32,
    /// Restitution.
    pub restitution: f32,
    /// Collides with bodies of its own figure.
    pub self_collision: bool,
    /// Figure (connected component of the joint graph) this body belongs to.
    pub figure: u32,
    /// Largest distance from the centre of mass to the shape's bounding box: with it,
    /// `|v| + |ω| r` bounds the speed of every point of the body.
    pub bound_radius: f32,
    /// Shot from the camera.
    pub projectile: bool,
}

impl BodyInfo {
    /// Cold data of one body from its description, mass properties and parry collider
    /// (`crate::scene::collider`, kept in `hulls` only for a convex hull).
    pub fn new(
        desc: &BodyDesc,
        mp: &MassProps,
        collider: SharedShape,
        figure: u32,
        hulls: &mut Vec<SharedShape>,
    ) -> BodyInfo {
        let fixed = desc.is_fixed();
        let hull = if matches!(desc.shape, Shape::ConvexHull { .. }) {
            hulls.push(collider);
            (hulls.len() - 1) as u32
        } else {
            NONE
        };
        BodyInfo {
            shape: desc.shape.clone(),
            hull,
            local_com: mp.local_com,
            mass: mp.mass,
            fixed,
            friction: desc.friction.contact,
            restitution: desc.restitution,
            self_collision: desc.self_collision,
            figure,
            bound_radius: (desc.shape.local_half_extents() + mp.local_com.abs()).length(),
            projectile: false,
        }
    }
}

impl BodyInfo {
    /// The collision shape, in the shape frame: for a primitive, the same parry shape
    /// `crate::scene::collider` builds (same constructor, same floats), made on the
    /// spot; for a convex hull, the one built with the body.
    pub fn collider<'a>(&self, hulls: &'a [SharedShape]) -> Collider<'a> {
        match hulls.get(self.hull as usize) {
            Some(hull) => Collider::Shared(hull),
            None => Collider::primitive(&self.shape)
                .expect("BodyInfo::new keeps the collider of every convex hull"),
        }
    }

    /// Inverse mass as built (zero for fixed bodies); `BodyStates::inv_mass` is zeroed
    /// while the body sleeps and restored from here. Computed, not stored: one division
    /// per body and step, the same one that was stored.
    #[inline]
    pub fn inv_mass(&self) -> f32 {
        if self.fixed { 0.0 } else { 1.0 / self.mass }
    }
}

/// Every body's scene name in one string (what a `String` per body would hold, without
/// its 24-byte header and separate allocation): names are read only for diagnostics.
#[derive(Clone, Debug, Default)]
pub struct BodyNames {
    text: String,
    /// End of each body's name in `text`; a name starts where the previous one ends.
    ends: Vec<u32>,
}

impl BodyNames {
    /// Room for `n` names of `bytes` bytes in all.
    pub fn with_capacity(n: usize, bytes: usize) -> BodyNames {
        BodyNames {
            text: String::with_capacity(bytes),
            ends: Vec::with_capacity(n),
        }
    }

    /// Appends the next body's name.
    pub fn push(&mut self, name: &str) {
        self.text.push_str(name);
        self.ends.push(self.text.len() as u32);
    }

    /// Body `i`'s name, `None` past the last body.
    pub fn get(&self, i: usize) -> Option<&str> {
        let end = *self.ends.get(i)? as usize;
        let start = if i == 0 { 0 } else { self.ends[i - 1] as usize };
        self.text.get(start..end)
    }
}
