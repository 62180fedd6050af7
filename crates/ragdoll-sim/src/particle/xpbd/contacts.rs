//! Contacts on particles: detection on the frames the particles imply, response on the
//! particles with barycentric weights (the paper's section 3.4; Jakobsen 2001).
//!
//! **Detection** (a few times a frame): the broad phase of `crate::broadphase` over the
//! bones' shapes posed at their read frames, each box loosened by how far the bone can
//! travel before the next detection, its trees built once a frame (`Reused`, which
//! gives the pairs new trees would); parry3d's contact manifolds within the distance a
//! pair can close (speculative contacts). Each contact point becomes a point fixed in
//! each bone, attached to its particles by barycentric weights, with the normal fixed
//! until the next detection.
//!
//! **Response** (every substep): the non-penetration constraint
//! `C = (p_b − p_a) · n ≥ 0` (or, for a penetration the substep starts with, no deeper
//! than it less the push-out speed, `begin_substep`) on the attached points, a point
//! correction on their barycentric weights with the substep's total push clamped,
//! `λ_n ≥ 0` (a push that later corrections made too large is taken back, so a contact
//! meets its bound instead of passing it: a box started 25 cm in the ground rose at
//! 3.5 m/s against a push-out speed of 3); then Coulomb friction in position form
//! (Müller et al. 2020, section 3.5, applied as a cone on the substep's totals,
//! `|λ_t| ≤ μ λ_n`): the points' relative tangential motion over the substep is undone
//! as far as the cone allows, which holds a static contact and slides a moving one at
//! the kinetic rate `μ g cos θ` on a slope.

use super::super::bone::{Bone, rolled_point};
use super::super::bone_kinds::BoneKinds;
use super::super::contacts::{
    Filter, broad_phase_on, give_back_room, ground_pair, ground_plane, reaches_ground,
    reserve_kept, shape_pair,
};
use super::super::rolling;
use super::contact_block::{block_len, block_len_back, normals};
use super::frame::{combine, weights};
use super::joints::Anchor;
use super::particles::{PER_BONE, XParticles};
use crate::broadphase::{Reused, speculative_margin};
use crate::scene::{Settings, rolling_arm};
use glam::{DMat3, DVec3, Mat3, Vec3, Vec3A};
use parry3d::query::ContactManifold;

/// One contact point between bone `a` and bone `b` or the ground.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Contact {
    /// The point on body1, on its particles.
    pub a: Anchor,
    /// The point on body2 (or the ground).
    pub b: Anchor,
    /// Unit normal from `a` to `b`.
    pub n: Vec3,
    /// Coulomb coefficient, `√(μ_a μ_b)`.
    pub mu: f32,
    /// Restitution, the larger of the two.
    pub restitution: f32,
    /// `ρ r` of its rolling resistance (m, `crate::scene::rolling_arm`): 0 when
    /// neither side rolls.
    pub roll: f32,
    /// Relative normal velocity `(v_b − v_a) · n` before the substep (< 0: closing).
    pub vn_before: f32,
    /// Its normal push so far this substep, `λ_n ≥ 0` (m·kg); the contact is active
    /// ([`Contact::active`]) while it is positive.
    pub lambda: f32,
    /// Its friction so far this substep, a tangential `λ_t` with `|λ_t| ≤ μ λ_n`.
    pub lambda_t: Vec3,
    /// The least separation the substep must reach (m, ≤ 0): 0, or for a contact
    /// that started the substep in penetration its depth less `max_push_out_speed · h`.
    pub floor: f32,
    /// Its points' barycentric inverse mass, `Σ_a β² w + Σ_b β² w` (friction), fixed
    /// through the substep.
    pub inv_mass: f32,
}

/// What a contact point holds through one part of a substep, beside the [`Contact`]:
/// the position passes and the velocity step each need their own, never both at once,
/// so one array serves both (`Scratch::work`, a slot per contact), set for the
/// position passes by `contact_block::begin_substep` and for the velocity step by
/// [`solve_velocities`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum Work {
    /// Through the position passes: its normal row's angular Jacobians `r × n` on `a`
    /// and `b` at the substep's start; 0 on a side that takes no correction. Their
    /// `I⁻¹ (r × n)` are not kept: the block forms them from its bodies' `I⁻¹` at the
    /// substep's start, which it holds anyway (`contact_block::normals`), the same
    /// product in the same bits, and a slot is 56 bytes, not 104.
    Position { turn: [DVec3; 2] },
    /// Through the velocity step: its two sides' arms ([`Lever::arm`]; the bones are
    /// the contact's), and its friction and normal impulses so far.
    Velocity {
        arms: [Vec3; 2],
        friction: Vec3,
        normal: f32,
    },
}

impl Work {
    /// The position passes' angular Jacobians (zero outside them).
    #[inline(always)]
    pub fn turns(&self) -> [DVec3; 2] {
        match *self {
            Work::Position { turn } => turn,
            Work::Velocity { .. } => [DVec3::ZERO; 2],
        }
    }

    /// The velocity step's arms and its friction and normal impulses so far (zero
    /// outside it).
    #[inline(always)]
    fn velocity(&self) -> ([Vec3; 2], Vec3, f32) {
        match *self {
            Work::Velocity {
                arms,
                friction,
                normal,
            } => (arms, friction, normal),
            Work::Position { .. } => ([Vec3::ZERO; 2], Vec3::ZERO, 0.0),
        }
    }
}

impl Contact {
    /// Whether it pushes this substep, `λ_n > 0`.
    #[inline]
    pub fn active(&self) -> bool {
        self.lambda > 0.0
    }

    /// Its two points at the substep's start, `prev_point64` of `a` and `b`: the
    /// levers of its block and the origin of its friction's slip. Formed from the
    /// particles' `x_prev` wherever needed, with the same arithmetic as the points now.
    #[inline]
    pub fn start(&self, p: &XParticles) -> [DVec3; 2] {
        [self.a.prev_point64(p), self.b.prev_point64(p)]
    }
}

/// What a detection reuses from the last (candidate pairs and parry's manifolds), and
/// what the contacts' substep works in.
#[derive(Default)]
pub(crate) struct Scratch {
    pairs: Vec<(usize, usize)>,
    manifolds: Vec<ContactManifold<(), ()>>,
    margins: Vec<f32>,
    speeds: Vec<f32>,
    /// Per contact, what the part of the substep under way keeps ([`Work`]).
    pub work: Vec<Work>,
    /// Per bone, its rigid body for the velocity step, taken at the first contact that
    /// needs it (`Rigid::of`); `taken` says which are.
    rigid: Vec<Rigid>,
    taken: Vec<bool>,
}

/// A point given in world coordinates, attached to bone `i`'s particles.
fn attach(bones: &[Bone], kinds: &BoneKinds, i: usize, world: Vec3) -> Anchor {
    let b = &bones[i];
    let local = b.rot.inverse() * (world - Vec3::from(b.center()));
    Anchor::Bone(i as u32, weights(&kinds.placement(b).rest, local))
}

/// Finds the contacts of the next `span` seconds into `out` (module doc). `tree` is
/// the frame's broad phase, reused by its later detections (`Reused`: the same pairs
/// as new trees give).
#[allow(clippy::too_many_arguments)]
pub(crate) fn detect(
    tree: &mut Reused,
    p: &XParticles,
    (bones, kinds): (&[Bone], &BoneKinds),
    filter: &Filter,
    settings: &Settings,
    span: f32,
    scratch: &mut Scratch,
    out: &mut Vec<Contact>,
) {
    // The contacts are kept between detections, grown by an eighth at a time, not
    // doubled (`reserve_kept`), and their room is given back once they fill less than
    // half of it (`give_back_room`, at the end): a pile's landing would otherwise hold
    // its peak count for good.
    out.clear();
    let reach = speculative_margin(settings.gravity.length(), span);
    // A bone's points move no faster than its fastest particle plus its turn; the
    // particles sit inside the shape, so bound the points by the fastest particle
    // scaled by how far the shape reaches beyond them.
    scratch.speeds.clear();
    scratch.margins.clear();
    reserve_kept(&mut scratch.speeds, bones.len());
    reserve_kept(&mut scratch.margins, bones.len());
    for (i, b) in bones.iter().enumerate() {
        let f = 4 * i;
        let c = (p.v[f] + p.v[f + 1] + p.v[f + 2] + p.v[f + 3]) * 0.25;
        let spin = (0..4)
            .map(|k| (p.v[f + k] - c).length())
            .fold(0.0, f32::max);
        let (kind, placement) = (kinds.of(b), kinds.placement(b));
        let inner = placement
            .rest
            .iter()
            .map(|r| r.length())
            .fold(1e-6, f32::max);
        let outer = kind
            .shape
            .get()
            .shape()
            .compute_local_aabb()
            .half_extents()
            .length()
            + placement.shape_in_bone.position.length();
        let speed = c.length() + spin * (outer / inner).max(1.0);
        scratch.speeds.push(speed);
        scratch.margins.push(speed * span + reach);
    }
    let boxes = broad_phase_on(
        tree,
        (bones, kinds),
        &scratch.margins,
        filter,
        &mut scratch.pairs,
    );
    for &(i, j) in &scratch.pairs {
        let prediction = (scratch.speeds[i] + scratch.speeds[j]) * span + 2.0 * reach;
        let (mi, mj) = (kinds.material(&bones[i]), kinds.material(&bones[j]));
        let mu = (mi.friction * mj.friction).sqrt();
        let restitution = mi.restitution.max(mj.restitution);
        let roll = rolling_arm(
            kinds.of(&bones[i]).shape.rolling_radius(),
            kinds.of(&bones[j]).shape.rolling_radius(),
        );
        shape_pair(
            (bones, kinds),
            i,
            j,
            prediction,
            &mut scratch.manifolds,
            |pa, pb, n, _| {
                reserve_kept(out, 1);
                out.push(Contact {
                    a: attach(bones, kinds, i, pa),
                    b: attach(bones, kinds, j, pb),
                    n,
                    mu,
                    restitution,
                    roll,
                    vn_before: 0.0,
                    lambda: 0.0,
                    lambda_t: Vec3::ZERO,
                    floor: 0.0,
                    inv_mass: 0.0,
                });
            },
        );
    }
    if let Some(ground) = &settings.ground {
        let plane = ground_plane(ground);
        for i in 0..bones.len() {
            if bones[i].is_static() || !reaches_ground(plane, &boxes[i]) {
                continue;
            }
            let material = kinds.material(&bones[i]);
            let mu = (material.friction * ground.friction).sqrt();
            let restitution = material.restitution.max(ground.restitution);
            let roll = rolling_arm(kinds.of(&bones[i]).shape.rolling_radius(), 0.0);
            ground_pair(
                (bones, kinds),
                i,
                ground,
                scratch.margins[i],
                &mut scratch.manifolds,
                |pa, pb, n, _| {
                    reserve_kept(out, 1);
                    out.push(Contact {
                        a: attach(bones, kinds, i, pa),
                        b: Anchor::World(pb),
                        n,
                        mu,
                        restitution,
                        roll,
                        vn_before: 0.0,
                        lambda: 0.0,
                        lambda_t: Vec3::ZERO,
                        floor: 0.0,
                        inv_mass: 0.0,
                    });
                },
            );
        }
    }
    give_back_room(out);
    give_back_room(&mut scratch.pairs);
}

/// Relative normal velocity of a contact's points, `(v_b − v_a) · n`.
fn normal_velocity(c: &Contact, p: &XParticles) -> f32 {
    (c.b.velocity(p) - c.a.velocity(p)).dot(c.n)
}

/// Before a substep of `h`: each contact's approach, and how deep it may still be at
/// the end of the substep. A penetration the substep starts with (an overlapping start,
/// a deep hit) is pushed out at `push_speed` at most (the scene's
/// `max_push_out_speed`, Box2D's contact push speed): pushed out at once, the
/// particles' displacement would become their velocity (a box started 25 cm in the
/// ground left it at 175 m/s).
///
/// Runs at the substep's start, before the prediction: the points now are the points
/// at the start (`x_prev = x`, `Contact::start`). A capsule's ground points
/// are first rolled to its bottom ([`roll_ground_points`]; `bones` hold the frames
/// read from the particles now).
pub(crate) fn begin_substep(
    contacts: &mut [Contact],
    p: &XParticles,
    (bones, kinds): (&[Bone], &BoneKinds),
    push_speed: f32,
    h: f32,
) {
    roll_ground_points(contacts, bones, kinds);
    for c in contacts.iter_mut() {
        c.vn_before = normal_velocity(c, p);
        c.lambda = 0.0;
        c.lambda_t = Vec3::ZERO;
        let depth = (c.b.point64(p) - c.a.point64(p)).as_vec3().dot(c.n);
        c.floor = (depth + push_speed * h).min(0.0);
        c.inv_mass = c.a.inv_mass(p) + c.b.inv_mass(p);
    }
}

/// Moves each ground contact's point on a capsule to where its surface faces the
/// ground now (`bone::rolled_point`: the point of its core segment nearest the old one,
/// out by the radius along the normal), its barycentric weights taken again. A point
/// fixed in the bone from the detection has rolled off the bottom by `ω h` a substep
/// when the passes push at it, up behind the centre on the way the capsule rolls, and
/// the push spins it on: the closed forms' capsule rolling at 0.3 m/s on flat ground
/// sped up at 0.027 m/s² (0.57 m/s after 12 s), where rolling resistance should stop it
/// in 9 s. The rigid-frames solver rolls its ground points the same way
/// (`rigid_frames::roll_contact`). Ground contacts only: between two bones the normal
/// is no one side's.
fn roll_ground_points(contacts: &mut [Contact], bones: &[Bone], kinds: &BoneKinds) {
    for c in contacts.iter_mut() {
        let (Anchor::Bone(i, w), Anchor::World(_)) = (c.a, c.b) else {
            continue;
        };
        let b = &bones[i as usize];
        let rest = &kinds.placement(b).rest;
        let local = combine(rest, &w);
        if let Some(rolled) = rolled_point(b, kinds, local, Vec3A::from(c.n)) {
            c.a = Anchor::Bone(i, weights(rest, rolled));
        }
    }
}

/// A bone at the velocity level: the rigid body the sticks make of its particles
/// (`shape_match::project_velocities`). Positions stay put through the velocity
/// passes, so it is taken once a bone and shared by its contacts.
#[derive(Clone, Copy, Debug, Default)]
struct Rigid {
    /// The bone's `1/M`; 0 for a bone that takes no correction.
    inv_total: f32,
    /// `I⁻¹` (world) of the particles about their centre.
    inv_inertia: Mat3,
    /// The particles about their centre, `r_k = x_k − c`.
    arms: [Vec3; 4],
}

impl Rigid {
    /// Bone `i`, with `I = Σ m_k (|r_k|² 1 − r_k r_kᵀ)` the particles' own inertia
    /// about their centre (in f64, as their projection takes it).
    fn of(i: usize, p: &XParticles) -> Rigid {
        if !p.moves(i) {
            return Rigid::default();
        }
        let f = PER_BONE * i;
        let c = p.centre(i);
        let mut inertia = DMat3::ZERO;
        for k in f..f + PER_BONE {
            let r = p.x[k] - c;
            inertia += (DMat3::from_diagonal(DVec3::splat(r.length_squared()))
                - DMat3::from_cols(r * r.x, r * r.y, r * r.z))
                * p.mass[k] as f64;
        }
        let det = inertia.determinant();
        let inv_inertia = if det.is_finite() && det.abs() > 1e-300 {
            inertia.inverse().as_mat3()
        } else {
            Mat3::ZERO
        };
        Rigid {
            inv_total: 1.0 / p.mass[f..f + PER_BONE].iter().sum::<f32>(),
            inv_inertia,
            arms: std::array::from_fn(|k| (p.x[f + k] - c).as_vec3()),
        }
    }
}

/// One side of a contact at the velocity level: its bone's [`Rigid`] body seen from
/// the contact point. The body's `1/M` and `I⁻¹` are read from its [`Rigid`], shared
/// by the bone's contacts, not copied into each lever; only the arm is kept a contact
/// through the passes (`Scratch::arms`), the bone being the contact's side
/// ([`Lever::on`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lever {
    /// The bone ([`Lever::WORLD`] for the world).
    bone: u32,
    /// The point about the particles' centre, `r`; zero for the world or a bone that
    /// takes no correction.
    arm: Vec3,
}

impl Lever {
    /// The `bone` of the world's side.
    const WORLD: u32 = u32::MAX;

    /// The lever of `side` with the arm `arm` kept for it.
    #[inline(always)]
    fn on(side: &Anchor, arm: Vec3) -> Lever {
        let bone = match *side {
            Anchor::Bone(i, _) => i,
            Anchor::World(_) => Lever::WORLD,
        };
        Lever { bone, arm }
    }

    /// The lever of `side`, its bone's rigid body taken into `rigid` if not yet
    /// (`taken`).
    fn of(side: &Anchor, p: &XParticles, rigid: &mut [Rigid], taken: &mut [bool]) -> Lever {
        let Anchor::Bone(i, _) = *side else {
            return Lever {
                bone: Lever::WORLD,
                arm: Vec3::ZERO,
            };
        };
        let b = i as usize;
        if !taken[b] {
            rigid[b] = Rigid::of(b, p);
            taken[b] = true;
        }
        let r = &rigid[b];
        if r.inv_total == 0.0 {
            return Lever {
                bone: i,
                arm: Vec3::ZERO,
            };
        }
        // The centre `c` of `Rigid::of`, formed again: positions stay put through
        // the velocity step.
        Lever {
            bone: i,
            arm: (side.point64(p) - p.centre(b)).as_vec3(),
        }
    }

    /// Its bone's rigid body, if it takes corrections (`None` for the world or a bone
    /// with `1/M = 0`).
    #[inline(always)]
    fn body<'r>(&self, rigid: &'r [Rigid]) -> Option<&'r Rigid> {
        if self.bone == Lever::WORLD {
            return None;
        }
        let r = &rigid[self.bone as usize];
        (r.inv_total != 0.0).then_some(r)
    }

    /// The point's generalised inverse mass along the unit `d`,
    /// `1/M + (r × d)ᵀ I⁻¹ (r × d)`; 0 for a side that takes no correction.
    fn inv_mass(&self, rigid: &[Rigid], d: Vec3) -> f32 {
        let Some(r) = self.body(rigid) else {
            return 0.0;
        };
        let rd = self.arm.cross(d);
        r.inv_total + rd.dot(r.inv_inertia * rd)
    }

    /// The bone's angular velocity, `ω = I⁻¹ Σ m_k r_k × v_k` of its particles about
    /// their centre (their velocities are rigid here); zero for the world or a bone
    /// that takes no correction.
    fn spin(&self, rigid: &[Rigid], p: &XParticles) -> Vec3 {
        let Some(r) = self.body(rigid) else {
            return Vec3::ZERO;
        };
        let f = PER_BONE * self.bone as usize;
        let momentum: Vec3 = (0..PER_BONE)
            .map(|k| r.arms[k].cross(p.v[f + k]) * p.mass[f + k])
            .sum();
        r.inv_inertia * momentum
    }

    /// The bone's `I⁻¹` (world), zero for the world or a bone that takes no
    /// correction.
    fn inv_inertia(&self, rigid: &[Rigid]) -> Mat3 {
        self.body(rigid).map_or(Mat3::ZERO, |r| r.inv_inertia)
    }

    /// Changes the bone's velocities by the angular impulse `l`: particle `k` by
    /// `(I⁻¹ l) × r_k`, a turn that keeps the linear momentum.
    fn twist(&self, rigid: &[Rigid], p: &mut XParticles, l: Vec3) {
        let Some(r) = self.body(rigid) else {
            return;
        };
        let f = PER_BONE * self.bone as usize;
        let dw = r.inv_inertia * l;
        for (v, arm) in p.v[f..f + PER_BONE].iter_mut().zip(&r.arms) {
            *v += dw.cross(*arm);
        }
    }

    /// Changes the bone's velocities by the impulse `j` at the point: particle `k` by
    /// `j / M + (I⁻¹ (r × j)) × r_k`, a rigid velocity change.
    fn kick(&self, rigid: &[Rigid], p: &mut XParticles, j: Vec3) {
        let Some(r) = self.body(rigid) else {
            return;
        };
        let f = PER_BONE * self.bone as usize;
        let (dv, dw) = (j * r.inv_total, r.inv_inertia * self.arm.cross(j));
        for (v, arm) in p.v[f..f + PER_BONE].iter_mut().zip(&r.arms) {
            *v += dv + dw.cross(*arm);
        }
    }
}

/// After the velocities are derived: the velocity pass of Müller et al. 2020
/// (section 3.6), `passes` symmetric Gauss–Seidel passes (forwards, then backwards,
/// ...) over the contacts that pushed during the substep `h`.
///
/// **Normal** (their eq. 34): the contact leaves with the normal velocity Newton's law
/// of restitution gives, `v_n = max(−e ṽ_n, 0)` with `ṽ_n` its approach before the
/// substep (`e = 0` below `threshold`). Without it the push-out of a position
/// correction would stay in the velocities as energy the contact never had.
///
/// **Tangential**: the part of the Coulomb cone the position step left unused (its
/// friction `|λ_t| ≤ μ λ_n`, module doc) stops the points' relative tangential
/// velocity, an impulse of at most `μ (λ_n / h + j_n) − |λ_t| / h` over the passes,
/// `j_n` the normal impulse of this step so far: the cone is on the substep's net
/// normal impulse, the push less what the normal step takes back, so the total
/// friction of the substep stays within it. A contact sliding at the kinetic rate
/// (`|λ_t| = μ λ_n`) is left alone, and one that holds leaves without the slip the
/// position step's corrections left in its velocity (a 20 cm cube hitting a wall at
/// 50 m/s came away rolling along it at 0.12 m/s, 0.79 rad/s). On the push alone
/// (`(μ λ_n − |λ_t|) / h`), a resting contact's push-out, taken back as velocity by
/// the normal step, still widened the cone: friction no normal impulse carried kept
/// the human's hands and forearms trembling at 0.1 m/s, and it never fell asleep.
///
/// **Rolling**: after the passes, each manifold's rolling resistance, a capped couple
/// on its bones' relative spin ([`roll`]).
///
/// The velocities enter rigid (`shape_match::project_velocities`), so each change is
/// an impulse `j` at the point on the rigid velocities, with the point's rigid
/// generalised inverse mass `1/M + (r × d)ᵀ I⁻¹ (r × d)` along `d` ([`Lever`]): the
/// change a kick on the barycentric weights followed by the velocity projection gives
/// (its linear part `Σ β_k j / M`, its turn `I⁻¹ Σ β_k r_k × j`, `Σ β_k r_k = r`),
/// sized for it. Sized by the barycentric inverse mass `Σ β_k² w_k` instead — 10/M at a
/// 1 m cube's corner against the rigid 4/M — each kick met only 40 % of its target,
/// and two cubes pushed out of each other at 3 m/s kept drifting apart at 0.54 m/s.
pub(crate) fn solve_velocities(
    contacts: &[Contact],
    p: &mut XParticles,
    scratch: &mut Scratch,
    threshold: f32,
    h: f32,
    passes: u32,
) {
    // Positions stay put through the passes: each bone's rigid body and each side's
    // lever are taken once.
    let bones = p.len() / PER_BONE;
    scratch.taken.clear();
    scratch.taken.resize(bones, false);
    scratch.rigid.resize(bones, Rigid::default());
    // Each contact's slot from the position passes (`contact_block::begin_substep`).
    debug_assert_eq!(scratch.work.len(), contacts.len());
    for (c, work) in contacts.iter().zip(&mut scratch.work) {
        let arms = if c.active() {
            let (rigid, taken) = (&mut scratch.rigid, &mut scratch.taken);
            [
                Lever::of(&c.a, p, rigid, taken).arm,
                Lever::of(&c.b, p, rigid, taken).arm,
            ]
        } else {
            [Vec3::ZERO; 2]
        };
        *work = Work::Velocity {
            arms,
            friction: Vec3::ZERO,
            normal: 0.0,
        };
    }
    let rigid = &scratch.rigid;
    let n = contacts.len();
    for pass in 0..passes {
        let backwards = pass % 2 == 1;
        for k in 0..n {
            let k = if backwards { n - 1 - k } else { k };
            let c = &contacts[k];
            if !c.active() {
                continue;
            }
            let ([ra, rb], mut friction, mut normal) = scratch.work[k].velocity();
            let (la, lb) = (Lever::on(&c.a, ra), Lever::on(&c.b, rb));
            let e = if -c.vn_before > threshold {
                c.restitution
            } else {
                0.0
            };
            let target = (-e * c.vn_before).max(0.0);
            let dv = target - normal_velocity(c, p);
            let w = la.inv_mass(rigid, c.n) + lb.inv_mass(rigid, c.n);
            if w <= 0.0 {
                continue;
            }
            if dv.abs() >= 1e-9 {
                normal += dv / w;
                let j = c.n * (dv / w);
                la.kick(rigid, p, -j);
                lb.kick(rigid, p, j);
            }
            // The substep's net normal impulse is the position step's push `λ_n / h`
            // plus this step's so far (negative where it takes back a push-out): the
            // cone is on that, not on the push alone.
            let cap = (c.mu * (c.lambda / h + normal) - c.lambda_t.length() / h).max(0.0);
            let old = friction;
            if cap == 0.0 && old == Vec3::ZERO {
                scratch.work[k] = Work::Velocity {
                    arms: [ra, rb],
                    friction,
                    normal,
                };
                continue;
            }
            let rel = c.b.velocity(p) - c.a.velocity(p);
            let slip = rel - c.n * c.n.dot(rel);
            let speed = slip.length();
            let mut total = old;
            if speed >= 1e-9 {
                let d = slip / speed;
                let w = la.inv_mass(rigid, d) + lb.inv_mass(rigid, d);
                if w > 0.0 {
                    total -= d * (speed / w);
                }
            }
            // A cone narrowed since an earlier pass (more push-out taken back) takes
            // back the friction beyond it.
            if total.length_squared() > cap * cap {
                total = if cap > 0.0 {
                    total * (cap / total.length())
                } else {
                    Vec3::ZERO
                };
            }
            friction = total;
            scratch.work[k] = Work::Velocity {
                arms: [ra, rb],
                friction,
                normal,
            };
            la.kick(rigid, p, old - total);
            lb.kick(rigid, p, total - old);
        }
    }
    roll(contacts, p, scratch, h);
}

/// Rolling resistance (`particle::rolling`), once the velocity passes have finished the
/// substep's normal impulses: per run of points between the same two bodies (a
/// manifold, `contact_block`), one angular impulse capped at `ρ r` times the run's net
/// normal impulse, `Σ (λ_n / h + j_n)`, on the bones' rigid velocities.
fn roll(contacts: &[Contact], p: &mut XParticles, scratch: &Scratch, h: f32) {
    let mut start = 0;
    while start < contacts.len() {
        let run = start..start + block_len(&contacts[start..]);
        start = run.end;
        // Levers are taken for the active points only; a run with none pushed nothing.
        let Some(first) = run.clone().find(|&k| contacts[k].active()) else {
            continue;
        };
        let arm = contacts[first].roll;
        if arm <= 0.0 {
            continue;
        }
        let normal: f32 = run
            .filter(|&k| contacts[k].active())
            .map(|k| contacts[k].lambda / h + scratch.work[k].velocity().2)
            .sum();
        let ([ra, rb], ..) = scratch.work[first].velocity();
        let c = &contacts[first];
        let (la, lb) = (Lever::on(&c.a, ra), Lever::on(&c.b, rb));
        let rigid = &scratch.rigid;
        let spin = lb.spin(rigid, p) - la.spin(rigid, p);
        let (inv_a, inv_b) = (la.inv_inertia(rigid), lb.inv_inertia(rigid));
        if let Some(l) = rolling::impulse(spin, inv_a, inv_b, arm * normal) {
            la.twist(rigid, p, -l);
            lb.twist(rigid, p, l);
        }
    }
}

/// One pass over the contacts (module doc), in order or, every other pass, backwards:
/// symmetric Gauss–Seidel over the manifolds. The normal pushes of one manifold are
/// solved together (`contact_block`): point by point, the first corner of a face takes
/// the whole push and the others what is left, a turn the next pass does not take back
/// (a box hitting a wall at 50 m/s left it spinning). Then each point's friction.
pub(crate) fn solve(
    contacts: &mut [Contact],
    work: &[Work],
    p: &mut XParticles,
    bones: &mut [Bone],
    backwards: bool,
) {
    let n = contacts.len();
    let mut done = 0;
    while done < n {
        let range = if backwards {
            let end = n - done;
            end - block_len_back(&contacts[..end])..end
        } else {
            done..done + block_len(&contacts[done..])
        };
        done += range.len();
        let turns = &work[range.clone()];
        let group = &mut contacts[range];
        normals(group, turns, p, bones);
        let m = group.len();
        for k in 0..m {
            friction(&mut group[if backwards { m - 1 - k } else { k }], p);
        }
    }
}

/// Coulomb friction of one contact after its normal push (module doc), on barycentric
/// weights.
fn friction(c: &mut Contact, p: &mut XParticles) {
    let total = c.lambda;
    if c.mu <= 0.0 || (total <= 0.0 && c.lambda_t == Vec3::ZERO) {
        return;
    }
    let w = c.inv_mass;
    if w <= 0.0 {
        return;
    }
    // Relative motion of the points over the substep, its tangential part.
    let start = c.start(p);
    let moved = ((c.a.point64(p) - start[0]) - (c.b.point64(p) - start[1])).as_vec3();
    let slip = moved - c.n * c.n.dot(moved);
    // Undo the slip (`Δλ_t = −slip / w`, moving `a` back along it) as far as the cone `|λ_t| ≤ μ λ_n` allows,
    // on the substep's totals: where the normal push is taken back, so is the
    // friction it carried.
    let mut t = c.lambda_t - slip / w;
    let cap = c.mu * total;
    if t.length_squared() > cap * cap {
        t *= cap / t.length();
    }
    let dt = t - c.lambda_t;
    c.lambda_t = t;
    c.a.shift(p, dt);
    c.b.shift(p, -dt);
}
