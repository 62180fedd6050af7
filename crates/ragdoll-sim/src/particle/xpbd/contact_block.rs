//! The normal pushes of one contact manifold (the points a pair's detection found
//! together) solved as one block, each pass.
//!
//! **Why a block.** Point by point, the first corner of a face that meets a wall takes
//! the whole push and turns the body; the next corners then push less, and what the
//! order leaves is a spin the passes only slowly take back (a cube hitting a wall at
//! 50 m/s face-on left it turning, and a stack of ten boxes drifted sideways). The
//! points of a manifold share one pair of bodies, so their rows are solved together:
//! the move that meets every active point at once, for a face the translation alone.
//!
//! **Rows.** Point `i` with normal `n_i` and levers `r_a`, `r_b` (from each body's
//! centre at the substep's start, as the joints' points: `joints::pull_rigid`) has
//! `C_i = (p_b − p_a) · n_i − floor_i` and Jacobian `J_a = (−n_i, −r_a × n_i)`,
//! `J_b = (n_i, r_b × n_i)` on each body's translation and turn. With `M⁻¹ = (1/m, I⁻¹)`
//! the block solves `(J M⁻¹ Jᵀ + ε) Δλ = −C` on its active rows and moves each body by
//! `M⁻¹ Jᵀ Δλ` (`joints::move_linear`). The points of a face are dependent (four rows,
//! three motions along the normal), and their depths, measured on a turning body, are
//! not quite those of a rigid move: `ε`, a hundredth of the largest diagonal, shares the
//! push between them as evenly as the geometry allows (each point's friction cone
//! `μ λ_i` as wide as its share) and keeps that inconsistency from growing into large
//! opposite pushes; it leaves a hundredth of the error to the next pass. With 1e-6 a
//! hinged chain on 20 iterations gained 70 % of its energy scale.
//!
//! **Inequalities.** A row is active where the points overlap or where it already
//! pushed this substep (`λ_i > 0`, which it may take back); a row whose total would
//! pull (`λ_i + Δλ_i < 0`) is set to release its push exactly and the rest solved
//! again, at most once a row (an active-set iteration).

// Small dense factorisations read as the formulas with row and column indices.
#![allow(clippy::needless_range_loop)]

use super::super::bone::Bone;
use super::super::contacts::{give_back_room, reserve_kept};
use super::contacts::{Contact, Work};
use super::joints::{Anchor, move_linear};
use super::particles::XParticles;
use glam::{DMat3, DVec3};

/// Most points of a block; a longer manifold is solved in blocks of this many.
pub(crate) const MAX_POINTS: usize = 8;

/// Relative regularisation of the block's diagonal (module doc).
const SHARE: f64 = 1e-2;

/// One body of a block: its bone (if it takes corrections), inverse mass and world
/// inverse inertia at the substep's start, and its centre then.
struct Body {
    bone: Option<usize>,
    inv_mass: f64,
    inv_inertia: DMat3,
    centre: DVec3,
}

impl Body {
    fn of(p: &XParticles, bones: &[Bone], e: &Anchor) -> Body {
        match *e {
            Anchor::Bone(i, _) if p.moves(i as usize) => {
                let i = i as usize;
                let b = &bones[i];
                Body {
                    bone: Some(i),
                    inv_mass: 1.0 / b.mass as f64,
                    inv_inertia: *p.inv_inertia_prev(i),
                    centre: p.centre_prev(i),
                }
            }
            _ => Body {
                bone: None,
                inv_mass: 0.0,
                inv_inertia: DMat3::ZERO,
                centre: DVec3::ZERO,
            },
        }
    }
}

/// The body a contact's side is on (`u32::MAX` for the world).
#[inline]
fn body_of(e: &Anchor) -> u32 {
    match *e {
        Anchor::Bone(i, _) => i,
        Anchor::World(_) => u32::MAX,
    }
}

/// The length of the run of points between the same two bodies that `points` starts
/// with, at most [`MAX_POINTS`].
fn same_pair_run<'a>(mut points: impl Iterator<Item = &'a Contact>) -> usize {
    let Some(first) = points.next() else {
        return 0;
    };
    let pair = |c: &Contact| (body_of(&c.a), body_of(&c.b));
    let key = pair(first);
    1 + points
        .take(MAX_POINTS - 1)
        .take_while(|c| pair(c) == key)
        .count()
}

/// How many contacts from the start of `contacts` form one block: the run of points
/// between the same two bodies, at most [`MAX_POINTS`].
pub(crate) fn block_len(contacts: &[Contact]) -> usize {
    same_pair_run(contacts.iter())
}

/// How many contacts from the end of `contacts` form one block (as [`block_len`]).
pub(crate) fn block_len_back(contacts: &[Contact]) -> usize {
    same_pair_run(contacts.iter().rev())
}

/// Each contact's angular Jacobians at the substep's start into its slot of `work`
/// ([`Work::Position`]), with the arithmetic the passes use: the levers from the
/// bodies' centres then (`joints::pull_rigid`), fixed through the substep. Once
/// `contacts::begin_substep` and `XParticles::fix_start` ran. The slots are kept
/// between substeps, grown by an eighth, not doubled, and their room is given back
/// once the contacts fill less than half of it (`contacts::give_back_room`): a pile's
/// landing would otherwise hold its peak for good.
pub(crate) fn begin_substep(
    contacts: &[Contact],
    work: &mut Vec<Work>,
    p: &XParticles,
    bones: &[Bone],
) {
    work.clear();
    reserve_kept(work, contacts.len());
    work.extend(contacts.iter().map(|ct| {
        let a = Body::of(p, bones, &ct.a);
        let b = Body::of(p, bones, &ct.b);
        let n = ct.n.as_dvec3();
        let start = ct.start(p);
        let mut turn = [DVec3::ZERO; 2];
        if a.bone.is_some() {
            turn[0] = (start[0] - a.centre).cross(n);
        }
        if b.bone.is_some() {
            turn[1] = (start[1] - b.centre).cross(n);
        }
        Work::Position { turn }
    }));
    give_back_room(work);
}

/// The normal pushes of the block `group` (one pair of bodies; module doc), `work`
/// their slots ([`begin_substep`]); each contact is active where its total push is
/// positive.
pub(crate) fn normals(
    group: &mut [Contact],
    work: &[Work],
    p: &mut XParticles,
    bones: &mut [Bone],
) {
    let m = group.len().min(MAX_POINTS);
    let group = &mut group[..m];
    let a = Body::of(p, bones, &group[0].a);
    let b = Body::of(p, bones, &group[0].b);
    if a.bone.is_none() && b.bone.is_none() {
        return;
    }
    // Each point's error and angular Jacobians (`r × n`, kept from the substep's
    // start) with their `I⁻¹ (r × n)`, and which rows take part.
    let mut c = [0.0f64; MAX_POINTS];
    let mut ja = [DVec3::ZERO; MAX_POINTS];
    let mut jb = [DVec3::ZERO; MAX_POINTS];
    let mut ia = [DVec3::ZERO; MAX_POINTS];
    let mut ib = [DVec3::ZERO; MAX_POINTS];
    let mut n = [DVec3::ZERO; MAX_POINTS];
    let mut active = [false; MAX_POINTS];
    let mut any = false;
    for (i, ct) in group.iter().enumerate() {
        let d = (ct.b.point64(p) - ct.a.point64(p)).as_vec3().dot(ct.n) - ct.floor;
        c[i] = d as f64;
        active[i] = d < 0.0 || ct.lambda > 0.0;
        any |= active[i];
        n[i] = ct.n.as_dvec3();
        [ja[i], jb[i]] = work[i].turns();
        // `I⁻¹ (r × n)`, as the slot's Jacobians: every point of the block is on its
        // two bodies (`block_len`), whose `I⁻¹` at the substep's start `a` and `b` hold.
        (ia[i], ib[i]) = (a.inv_inertia * ja[i], b.inv_inertia * jb[i]);
    }
    if !any {
        return;
    }
    let w = a.inv_mass + b.inv_mass;
    let mut k = [[0.0f64; MAX_POINTS]; MAX_POINTS];
    for i in 0..m {
        for j in 0..m {
            k[i][j] = w * n[i].dot(n[j]) + ja[i].dot(ia[j]) + jb[i].dot(ib[j]);
        }
    }
    // `fixed[i]`: the row releases its push exactly, `Δλ_i = −λ_i`.
    let mut fixed = [false; MAX_POINTS];
    let mut dl = [0.0f64; MAX_POINTS];
    for _ in 0..=m {
        // Right-hand side of the free rows, less what the fixed rows already do.
        let free: [bool; MAX_POINTS] = std::array::from_fn(|i| i < m && active[i] && !fixed[i]);
        for i in 0..m {
            dl[i] = if fixed[i] {
                -(group[i].lambda as f64)
            } else {
                0.0
            };
        }
        let mut rhs = [0.0f64; MAX_POINTS];
        for i in 0..m {
            if free[i] {
                rhs[i] = -c[i] - (0..m).map(|j| k[i][j] * dl[j]).sum::<f64>();
            }
        }
        let x = solve_spd(&k, &free, &rhs, m);
        let mut pulled = false;
        for i in 0..m {
            if free[i] {
                dl[i] = x[i];
                if group[i].lambda as f64 + x[i] < 0.0 {
                    fixed[i] = true;
                    pulled = true;
                }
            }
        }
        if !pulled {
            break;
        }
    }
    let (mut fa, mut ta, mut tb) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for i in 0..m {
        if !active[i] || dl[i] == 0.0 {
            continue;
        }
        // Body2 takes `+n Δλ`, body1 `−n Δλ`.
        fa += n[i] * dl[i];
        ta += ja[i] * dl[i];
        tb += jb[i] * dl[i];
        let ct = &mut group[i];
        ct.lambda = (ct.lambda as f64 + dl[i]).max(0.0) as f32;
    }
    if let Some(i) = a.bone {
        move_linear(
            p,
            bones,
            i,
            (-fa * a.inv_mass).as_vec3(),
            (-(a.inv_inertia * ta)).as_vec3(),
        );
    }
    if let Some(i) = b.bone {
        move_linear(
            p,
            bones,
            i,
            (fa * b.inv_mass).as_vec3(),
            (b.inv_inertia * tb).as_vec3(),
        );
    }
}

/// `x` with `(K + ε) x = rhs` on the rows marked `free` (the others 0), by Cholesky's
/// factorisation; `ε` a relative [`SHARE`] of the largest diagonal (module doc).
fn solve_spd(
    k: &[[f64; MAX_POINTS]; MAX_POINTS],
    free: &[bool; MAX_POINTS],
    rhs: &[f64; MAX_POINTS],
    m: usize,
) -> [f64; MAX_POINTS] {
    let mut rows = [0usize; MAX_POINTS];
    let mut r = 0;
    for i in 0..m {
        if free[i] {
            rows[r] = i;
            r += 1;
        }
    }
    let eps = SHARE * (0..r).map(|i| k[rows[i]][rows[i]]).fold(0.0, f64::max);
    let mut l = [[0.0f64; MAX_POINTS]; MAX_POINTS];
    for i in 0..r {
        for j in 0..=i {
            let mut s = k[rows[i]][rows[j]] + if i == j { eps } else { 0.0 };
            for q in 0..j {
                s -= l[i][q] * l[j][q];
            }
            if i == j {
                l[i][i] = s.max(1e-300).sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = [0.0f64; MAX_POINTS];
    for i in 0..r {
        let mut s = rhs[rows[i]];
        for q in 0..i {
            s -= l[i][q] * y[q];
        }
        y[i] = s / l[i][i];
    }
    for i in (0..r).rev() {
        let mut s = y[i];
        for q in i + 1..r {
            s -= l[q][i] * y[q];
        }
        y[i] = s / l[i][i];
    }
    let mut x = [0.0f64; MAX_POINTS];
    for i in 0..r {
        x[rows[i]] = y[i];
    }
    x
}
