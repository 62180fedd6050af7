//! A joint's point, its angular parts and its violated limits solved together: one
//! small block a joint, each pass.
//!
//! **Why a block.** Solved one after the other, a joint's parts fight: a hinge's
//! angular part turns the bone about its centre, which moves the joint's point by the
//! turn times the lever `r`; the point part closes that gap mostly by turning the bone
//! back, since its generalised inverse mass `1/m + |r|²/I` is mostly turn. A pass then
//! removes only `(1/m) / (1/m + |r|²/I)` of the error: a quarter for a rod jointed at
//! its end, 1/600 for the closed forms' pendulum (a 10 cm cube a metre below its
//! hinge), whose spin then rattled by ±0.2 rad/s with eight passes. Together the rows
//! find the move that meets all of them at once: the bone translates.
//!
//! **Rows.** Every row is a constraint `C` on the two sides' displacements
//! `(Δx, Δθ)`, linear to first order with Jacobian `J = (J_lin, J_ang)` per side:
//! - the point, along each world axis `e`: `C = e · (p_b − p_a)`,
//!   `J_a = (−e, −r_a × e)`, `J_b = (e, r_b × e)`;
//! - an angle about a world direction `u` (hinge axes, a universal's shafts, a fixed
//!   joint's orientation, a limit past its bound), `C = −u · φ` with `φ` the turn of
//!   body1 relative to body2 that meets it: `J_a = (0, u)`, `J_b = (0, −u)`.
//!
//! With `M⁻¹ = (1/m, I⁻¹)` per side, the XPBD update (Macklin et al. 2016, eq. 18,
//! one iteration from `λ = 0` per pass as the scalar rows) solves
//! `(J M⁻¹ Jᵀ + α̃) Δλ = −C` and moves each side by `M⁻¹ Jᵀ Δλ`: a translation and a
//! linear turn of its particles about their centre (`joints::move_linear`). The levers
//! `r` and inertias `I` are those at the substep's start, where the particles are
//! rigid (`joints::pull_rigid` says why); the errors are measured now. Rows that
//! depend on others (a zero pivot) are left out of that pass.
//!
//! **Limits are one-sided.** A limit row `C = s (φ − bound) ≥ 0` breached (`s` the
//! side) pushes with a multiplier `λ ≥ 0` summed over the substep's passes, the
//! usual XPBD treatment of an inequality (projected Gauss–Seidel on it): the row
//! enters in the first pass that finds it breached and stays in while its total
//! `λ > 0`, inside its range too, where it pulls back to the bound what other rows
//! pushed past it, up to what it pushed; a `Δλ` that would make the total pull is set
//! to release the push exactly and the rest of the block solved again, at most once a
//! row. Taken afresh each pass from whether it was breached, a row held at its bound
//! under load switched in and out from pass to pass (breached by rounding, then in
//! range by what the point rows moved back), and a figure resting on its limits
//! settled late: scene 8's human fell asleep at 5.1 s, at 3.4 s with the multipliers.

// Small dense factorisations read as the formulas with row and column indices.
#![allow(clippy::needless_range_loop)]

use super::super::bone::{Bone, Side};
use super::super::joint_kinds::{JointKind, JointKinds};
use super::super::joints::{Joint, JointType, hinge_turn_ratio};
use super::super::limits::{Swing, SwingLimit, perpendicular};
use super::joints::{Anchor, move_linear, rot};
use super::particles::XParticles;
use glam::{DMat3, DVec3, Quat, Vec3};

/// Most rows of a block: a point (3), a fixed joint's orientation (3), a swing limit
/// (two at a pyramid's corner) and its twist and axis limits.
const MAX_ROWS: usize = 10;

/// Rows of the point, first in every block.
const POINT_ROWS: usize = 3;

/// Most multipliers of a block's limit rows kept through a substep: the swing limit's
/// (one for a cone, two for a pyramid's faces), then the angle limits'.
const LIMIT_SLOTS: usize = MAX_ROWS - POINT_ROWS;

/// Slots held for a swing limit's rows in the count of [`LIMIT_SLOTS`]: an angle
/// limit past `LIMIT_SLOTS − SWING_SLOTS` takes no row.
const SWING_SLOTS: usize = 2;

/// The limit slots of a joint of kind `kind`, the multipliers its block keeps through
/// a substep: its swing limit's rows (none, one for a cone, two for a pyramid), then
/// one for each of its angle limits that takes a row ([`SWING_SLOTS`]).
#[inline]
fn limit_slots(kind: &JointKind) -> (usize, usize) {
    let swing = match &kind.swing {
        None => 0,
        Some(s) => match s.kind {
            Swing::Cone { .. } => 1,
            Swing::Pyramid { .. } => 2,
        },
    };
    (
        swing,
        kind.angle_limits.len().min(LIMIT_SLOTS - SWING_SLOTS),
    )
}

/// One side of a block: its bone (if it takes corrections) and inverse mass. Both
/// stay the same through a substep (a bone's sleep changes between frames), so the
/// passes take them again from the joint's side rather than keep them; its world
/// inverse inertia at the substep's start is the particles' own
/// (`XParticles::inv_inertia_prev`).
#[derive(Clone, Copy)]
struct Body {
    bone: Option<u32>,
    inv_mass: f64,
}

impl Body {
    /// The side `s` of a joint.
    #[inline(always)]
    fn of(p: &XParticles, bones: &[Bone], s: Side) -> Body {
        match s {
            Some(i) if p.moves(i) => Body {
                bone: Some(i as u32),
                inv_mass: 1.0 / bones[i].mass as f64,
            },
            _ => Body {
                bone: None,
                inv_mass: 0.0,
            },
        }
    }

    /// Its lever: from its centre to its point `end`, both at the substep's start
    /// (zero on a side that takes no correction).
    fn lever(&self, p: &XParticles, end: &Anchor) -> DVec3 {
        match self.bone {
            Some(i) => end.prev_point64(p) - p.centre_prev(i as usize),
            None => DVec3::ZERO,
        }
    }

    /// Its world inverse inertia at the substep's start; zero for a side that takes no
    /// correction.
    #[inline(always)]
    fn inv_inertia(&self, p: &XParticles) -> DMat3 {
        match self.bone {
            Some(i) => *p.inv_inertia_prev(i as usize),
            None => DMat3::ZERO,
        }
    }
}

/// One row (module doc): body2's linear part (body1's is its negative), each side's
/// angular part, the error and the compliance `α̃`.
#[derive(Clone, Copy, Default)]
struct Row {
    lin: DVec3,
    ang_a: DVec3,
    ang_b: DVec3,
    c: f64,
    alpha: f64,
    /// `1 +` the limit slot of a limit row, 0 for the others.
    slot: u8,
}

/// Index of entry `(i, m)`, `m ≤ i`, of a lower triangle packed row by row.
const fn tri(i: usize, m: usize) -> usize {
    i * (i + 1) / 2 + m
}

/// What a joint's block keeps through a substep: its point rows depend only on the
/// substep's start (the levers, the inverse inertias), so their `M⁻¹ Jᵀ` and the
/// first [`POINT_ROWS`] rows of the Cholesky factor of `K` (which depend on nothing
/// after them) are taken once a substep ([`begin_substep`]), with the arithmetic the
/// passes use. What the passes form again with that same arithmetic is not kept: a
/// point row's linear part is its world axis `e` and its angular parts `−r_a × e` and
/// `r_b × e` come from the two levers, its error is measured in the pass, its
/// compliance is 0, and each side's bone, inverse mass and inverse inertia are its
/// joint's ([`Body::of`], [`Body::inv_inertia`]).
#[derive(Clone, Copy)]
pub(crate) struct Start {
    /// The levers `r_a` and `r_b` ([`Body::lever`]).
    lever: [DVec3; 2],
    /// `I_a⁻¹ J_a` and `I_b⁻¹ J_b` of the point rows.
    ia: [DVec3; POINT_ROWS],
    ib: [DVec3; POINT_ROWS],
    /// The point rows of the in-place factor (`solve_rows`), its lower triangle packed
    /// ([`tri`]; the rest is zero), and whether each row is live.
    factor: [f64; tri(POINT_ROWS, 0)],
    live: [bool; POINT_ROWS],
    /// Where its limit slots' multipliers start in the substep's multipliers
    /// ([`begin_substep`]'s `lambda`; as many as [`limit_slots`]).
    first: u32,
}

/// The point rows of a block with levers `lever` (module doc): along each world axis
/// `e`, `J_a = (−e, −r_a × e)`, `J_b = (e, r_b × e)`.
#[inline(always)]
fn point_rows(lever: &[DVec3; 2]) -> [Row; POINT_ROWS] {
    std::array::from_fn(|i| {
        let e = [DVec3::X, DVec3::Y, DVec3::Z][i];
        Row {
            lin: e,
            ang_a: -lever[0].cross(e),
            ang_b: lever[1].cross(e),
            c: 0.0,
            alpha: 0.0,
            slot: 0,
        }
    })
}

/// Each block joint's [`Start`] (its kind in `kinds`) into `out` (a slot per joint; the others' stay unset
/// and unread), once `x_prev`, the bones' `prev_rot` and the particles' own start
/// (`XParticles::fix_start`) are the substep's; into `lambda`, each such joint's
/// limit multipliers (each limit slot's `λ` summed over the substep's passes so far,
/// `≥ 0`), at 0: as many as its limits take ([`limit_slots`]), none for the others.
pub(crate) fn begin_substep(
    p: &XParticles,
    bones: &[Bone],
    (joints, kinds): (&[Joint], &JointKinds),
    anchors: &[[Anchor; 2]],
    out: &mut Vec<Option<Start>>,
    lambda: &mut Vec<f64>,
) {
    out.clear();
    lambda.clear();
    out.extend(joints.iter().zip(anchors).map(|(j, [ea, eb])| {
        let kind = kinds.of(j);
        if !blocks(kind) {
            return None;
        }
        let (a, b) = (Body::of(p, bones, j.a()), Body::of(p, bones, j.b()));
        if a.bone.is_none() && b.bone.is_none() {
            return None;
        }
        let lever = [a.lever(p, ea), b.lever(p, eb)];
        let point = point_rows(&lever);
        let (inv_a, inv_b) = (a.inv_inertia(p), b.inv_inertia(p));
        let ia = point.map(|r| inv_a * r.ang_a);
        let ib = point.map(|r| inv_b * r.ang_b);
        let w = a.inv_mass + b.inv_mass;
        let mut k = [[0.0f64; MAX_ROWS]; MAX_ROWS];
        let mut live = [false; MAX_ROWS];
        fill_and_factor(&mut k, &mut live, &point, &ia, &ib, w, 0);
        let mut factor = [0.0; tri(POINT_ROWS, 0)];
        for i in 0..POINT_ROWS {
            for m in 0..=i {
                factor[tri(i, m)] = k[i][m];
            }
        }
        let first = lambda.len() as u32;
        let (swing, angles) = limit_slots(kind);
        lambda.resize(lambda.len() + swing + angles, 0.0);
        Some(Start {
            lever,
            ia,
            ib,
            factor,
            live: std::array::from_fn(|i| live[i]),
            first,
        })
    }));
}

/// The rows of one block.
struct Rows {
    rows: [Row; MAX_ROWS],
    n: usize,
}

impl Rows {
    fn push(&mut self, row: Row) {
        if self.n < MAX_ROWS {
            self.rows[self.n] = row;
            self.n += 1;
        }
    }

    /// An angle row: body1 to turn by `value` about the unit `u` relative to body2.
    fn angle(&mut self, u: Vec3, value: f32, alpha: f32) {
        let u = u.as_dvec3();
        self.push(Row {
            lin: DVec3::ZERO,
            ang_a: u,
            ang_b: -u,
            c: -(value as f64),
            alpha: alpha as f64,
            slot: 0,
        });
    }

    /// A limit row in `slot`: the angle `φ` with gradient `grad` (per unit turn of
    /// body1) within `[lo, hi]`, if it is breached or its multiplier `lambda` still
    /// pushes (module doc). On side `s` (+1 past `hi`, −1 past `lo`; while inside,
    /// the nearer bound) `C = s (φ − bound) / |g|` along `−s g / |g|`: a turn of `C`
    /// about it restores the bound to first order, and a push is `Δλ > 0`.
    #[allow(clippy::too_many_arguments)]
    fn limit(
        &mut self,
        slot: usize,
        grad: Vec3,
        phi: f32,
        lo: f32,
        hi: f32,
        alpha: f32,
        lambda: f64,
    ) {
        let g = grad.length();
        if !(g > 1e-6 && g.is_finite()) {
            return;
        }
        let upper = if phi > hi {
            true
        } else if phi < lo {
            false
        } else if lambda > 0.0 {
            phi - lo > hi - phi
        } else {
            return;
        };
        let (side, bound) = if upper { (1.0, hi) } else { (-1.0, lo) };
        let u = (grad * (-side / g)).as_dvec3();
        self.push(Row {
            lin: DVec3::ZERO,
            ang_a: u,
            ang_b: -u,
            c: -((side * (phi - bound) / g) as f64),
            alpha: alpha as f64,
            slot: slot as u8 + 1,
        });
    }
}

/// Whether a joint of kind `kind` is solved as a block (the others: a slider's and a
/// spring's points are not a ball's, `joints::solve_angular` and `joints::solve_point`).
pub(crate) fn blocks(kind: &JointKind) -> bool {
    matches!(
        kind.joint_type,
        JointType::Ball | JointType::Hinge { .. } | JointType::Universal { .. } | JointType::Fixed
    )
}

/// Joint `j` of kind `kind` (a [`blocks`] one) between its anchors `ends`, `h` the substep: its
/// point, angular parts and violated limits as one block (module doc); `start` its
/// [`begin_substep`] (`None`: neither side takes corrections), `lambda` the substep's
/// limit multipliers of every joint ([`begin_substep`]). Inlined into both of
/// its callers, the substep's passes and the start's slack passes: the passes' hot loop
/// is built around it.
#[inline(always)]
pub(crate) fn solve(
    p: &mut XParticles,
    bones: &mut [Bone],
    (j, kind): (&Joint, &JointKind),
    ends: &[Anchor; 2],
    start: &Option<Start>,
    lambda: &mut [f64],
    h: f32,
) {
    let [ea, eb] = ends;
    let Some(start) = start else {
        return;
    };
    let (swing, angles) = limit_slots(kind);
    let first = start.first as usize;
    let lambda = &mut lambda[first..first + swing + angles];
    let mut rows = Rows {
        rows: [Row::default(); MAX_ROWS],
        n: 0,
    };
    let delta = eb.point64(p) - ea.point64(p);
    for mut row in point_rows(&start.lever) {
        row.c = row.lin.dot(delta);
        rows.push(row);
    }
    let (qa, qb) = (rot(bones, j.a()), rot(bones, j.b()));
    match kind.joint_type {
        JointType::Hinge { axis_a, axis_b } => {
            // Turn body1's axis onto body2's, by `asin(s)` about `c / s`,
            // `c = t_a × t_b`; the rows span the plane across the mean axis, the turn
            // about the axis stays free.
            let (ta, tb) = (qa * axis_a, qb * axis_b);
            let c = ta.cross(tb);
            let dphi = c * hinge_turn_ratio(c.length_squared());
            let m = (ta + tb).normalize_or(tb);
            let u1 = perpendicular(m);
            let u2 = m.cross(u1);
            rows.angle(u1, u1.dot(dphi), 0.0);
            rows.angle(u2, u2.dot(dphi), 0.0);
        }
        JointType::Universal { shaft_a, shaft_b } => {
            // Keep the shafts perpendicular: turn by `asin(s₁ · s₂)` about `s₂ × s₁`.
            let (s1, s2) = (qa * shaft_a, qb * shaft_b);
            let n = s2.cross(s1);
            let l = n.length();
            if l > 1e-9 {
                rows.angle(n / l, s1.dot(s2).clamp(-1.0, 1.0).asin(), 0.0);
            }
        }
        JointType::Fixed => {
            // Body1's rotation onto its rest orientation relative to body2:
            // `e = q_b q_rest q_a⁻¹`, turned by its rotation vector.
            let mut e = qb * kind.rest_rel * qa.inverse();
            if e.w < 0.0 {
                e = -e;
            }
            let dphi = Vec3::new(e.x, e.y, e.z) * 2.0;
            for u in [Vec3::X, Vec3::Y, Vec3::Z] {
                rows.angle(u, u.dot(dphi), 0.0);
            }
        }
        _ => {}
    }
    let alpha = kind.limit_compliance / (h * h);
    if let Some(s) = &kind.swing {
        swing_rows(&mut rows, s, qa, qb, j.slack, alpha, lambda);
    }
    for (i, l) in kind.angle_limits.iter().take(angles).enumerate() {
        // The range widened by the joint's slack (`step::close_start_slack`).
        let (phi, grad) = l.angle(bones, j.a(), j.b());
        let (lo, hi) = (l.min - j.slack, l.max + j.slack);
        let slot = swing + i;
        rows.limit(slot, grad, phi, lo, hi, alpha, lambda[slot]);
    }
    let (a, b) = (Body::of(p, bones, j.a()), Body::of(p, bones, j.b()));
    let (inv_a, inv_b) = (a.inv_inertia(p), b.inv_inertia(p));
    let w = a.inv_mass + b.inv_mass;
    let dl = solve_one_sided(&rows, start, lambda, inv_a, inv_b, w);
    for (r, l) in rows.rows[..rows.n].iter().zip(&dl) {
        if r.slot > 0 {
            lambda[r.slot as usize - 1] += *l;
        }
    }
    let (mut lin, mut ang_a, mut ang_b) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for (r, l) in rows.rows[..rows.n].iter().zip(&dl) {
        lin += r.lin * *l;
        ang_a += r.ang_a * *l;
        ang_b += r.ang_b * *l;
    }
    if let Some(i) = a.bone {
        let shift = (-lin * a.inv_mass).as_vec3();
        move_linear(p, bones, i as usize, shift, (inv_a * ang_a).as_vec3());
    }
    if let Some(i) = b.bone {
        let shift = (lin * b.inv_mass).as_vec3();
        move_linear(p, bones, i as usize, shift, (inv_b * ang_b).as_vec3());
    }
}

/// The rows of swing limit `s` past its cone or pyramid widened by `slack` (rad,
/// `Joint::slack`), for body1 at `qa` and body2 at `qb`: each a one-sided angle
/// `C = φ − bound` along its own gradient `g = ∂φ/∂ω` (per unit turn `ω` of body1),
/// a turn of `(bound − φ) / |g|` about `g / |g|` restoring it to first order.
/// - Cone: `φ = atan2(|a × s|, a · s)` between the shaft `s` and the axis `a`,
///   `g = (a × s) / sin φ` (unit).
/// - Pyramid: a row per face, `φ = atan2(s · e, s · a)` for `e` each of its directions
///   `u` (bound `h1`) and `v` (`h2`): with `d = s · e`, `z = s · a`,
///   `g = s × (z e − d a) / (d² + z²)`, `|g| = 1 / √(d² + z²)`.
///
/// The angles come from `atan2`, exact to rounding at any size; through `acos` of the
/// shaft's cosine to its nearest allowed direction, as the one-by-one solve
/// (`joints::swing_correction`) measures, f32 resolves a breach only in steps of
/// 3.4e-4 rad. A pyramid's face is corrected along its own gradient: a turn onto the
/// nearest allowed direction by clamped angles is not, once the shaft is off the other
/// face's plane, and its part along the face then works on the bone.
#[inline(always)]
fn swing_rows(
    rows: &mut Rows,
    s: &SwingLimit,
    qa: Quat,
    qb: Quat,
    slack: f32,
    alpha: f32,
    lambda: &[f64],
) {
    let shaft = qa * s.shaft_a;
    let axis = qb * s.axis_b;
    match s.kind {
        Swing::Cone { half_angle, .. } => {
            let n = axis.cross(shaft);
            let sin = n.length();
            let phi = sin.atan2(shaft.dot(axis));
            let g = if sin > 1e-6 {
                n / sin
            } else {
                perpendicular(axis)
            };
            rows.limit(
                0,
                g,
                phi,
                f32::NEG_INFINITY,
                half_angle + slack,
                alpha,
                lambda[0],
            );
        }
        Swing::Pyramid { h1, h2, u, v } => {
            for (slot, (e, h)) in [(qb * u, h1), (qb * v, h2)].into_iter().enumerate() {
                let bound = h + slack;
                let (d, z) = (shaft.dot(e), shaft.dot(axis));
                let r2 = d * d + z * z;
                if r2 > 1e-12 {
                    let g = shaft.cross(e * z - axis * d) / r2;
                    rows.limit(slot, g, d.atan2(z), -bound, bound, alpha, lambda[slot]);
                }
            }
        }
    }
}

/// `Δλ` of the block (module doc) with its limit rows one-sided: a row whose total
/// multiplier would pull (`λ + Δλ < 0`) is fixed at `Δλ = −λ`, releasing its push
/// exactly, and the others solved again with the move of the fixed rows
/// (`M⁻¹ Jₖᵀ Δλₖ`) in their errors, `Cᵢ + Σₖ Jᵢ M⁻¹ Jₖᵀ Δλₖ`; at most once a row.
#[inline(always)]
fn solve_one_sided(
    rows: &Rows,
    start: &Start,
    lambda: &[f64],
    inv_a: DMat3,
    inv_b: DMat3,
    w: f64,
) -> [f64; MAX_ROWS] {
    let mut dl = solve_rows(rows, start, inv_a, inv_b, w);
    if rows.rows[..rows.n].iter().all(|r| r.slot == 0) {
        return dl;
    }
    let mut fixed: [Option<f64>; MAX_ROWS] = [None; MAX_ROWS];
    for _ in 0..LIMIT_SLOTS {
        let pulls = (0..rows.n).find(|&k| {
            let r = &rows.rows[k];
            r.slot > 0 && fixed[k].is_none() && lambda[r.slot as usize - 1] + dl[k] < 0.0
        });
        let Some(k) = pulls else {
            break;
        };
        fixed[k] = Some(-lambda[rows.rows[k].slot as usize - 1]);
        // The rows not fixed, their errors moved by the fixed rows' pushes.
        let mut free = Rows {
            rows: [Row::default(); MAX_ROWS],
            n: 0,
        };
        let mut index = [0usize; MAX_ROWS];
        for (i, r) in rows.rows[..rows.n].iter().enumerate() {
            if fixed[i].is_some() {
                continue;
            }
            let mut r = *r;
            for (f, l) in rows.rows[..rows.n].iter().zip(&fixed) {
                if let Some(l) = l {
                    let kif = r.lin.dot(f.lin) * w
                        + r.ang_a.dot(inv_a * f.ang_a)
                        + r.ang_b.dot(inv_b * f.ang_b);
                    r.c += kif * l;
                }
            }
            index[free.n] = i;
            free.push(r);
        }
        let sub = solve_rows(&free, start, inv_a, inv_b, w);
        for (m, &i) in index[..free.n].iter().enumerate() {
            dl[i] = sub[m];
        }
        for (i, l) in fixed.iter().enumerate() {
            if let Some(l) = l {
                dl[i] = *l;
            }
        }
    }
    dl
}

/// Rows `from..n` of `K = J M⁻¹ Jᵀ + α̃` (lower triangle; `ia`, `ib` the rows'
/// `I⁻¹ J` per side, `w` the sides' summed inverse masses), then of its Cholesky
/// factor in place, rows `..from` already factored; a row whose pivot vanishes
/// against its diagonal depends on the rows before it and is marked not `live`.
#[inline]
fn fill_and_factor(
    k: &mut [[f64; MAX_ROWS]; MAX_ROWS],
    live: &mut [bool; MAX_ROWS],
    r: &[Row],
    ia: &[DVec3],
    ib: &[DVec3],
    w: f64,
    from: usize,
) {
    let n = r.len();
    for i in from..n {
        for jj in 0..=i {
            k[i][jj] =
                r[i].lin.dot(r[jj].lin) * w + r[i].ang_a.dot(ia[jj]) + r[i].ang_b.dot(ib[jj]);
        }
        k[i][i] += r[i].alpha;
    }
    for i in from..n {
        let diag = k[i][i];
        for jj in 0..i {
            let mut s = k[i][jj];
            for m in 0..jj {
                s -= k[i][m] * k[jj][m];
            }
            k[i][jj] = if live[jj] { s / k[jj][jj] } else { 0.0 };
        }
        let mut d = k[i][i];
        for m in 0..i {
            d -= k[i][m] * k[i][m];
        }
        live[i] = d > 1e-9 * diag && d > 0.0;
        k[i][i] = if live[i] { d.sqrt() } else { 1.0 };
        if !live[i] {
            for m in 0..i {
                k[i][m] = 0.0;
            }
        }
    }
}

/// `Δλ` of `(J M⁻¹ Jᵀ + α̃) Δλ = −C` by Cholesky's factorisation (the matrix is
/// symmetric positive semi-definite); a row whose pivot vanishes against its diagonal
/// depends on the rows before it and takes no `Δλ`. The point rows come factored
/// from `start`; `inv_a`, `inv_b` are its sides' inverse inertias, `w` their summed
/// inverse masses.
#[inline(always)]
fn solve_rows(rows: &Rows, start: &Start, inv_a: DMat3, inv_b: DMat3, w: f64) -> [f64; MAX_ROWS] {
    let n = rows.n;
    let r = &rows.rows[..n];
    // `I⁻¹ Jᵀ` of one side: the point rows' from `start`, the others' formed here.
    let side = |fixed: &[DVec3; POINT_ROWS], inv_inertia: DMat3, ang: fn(&Row) -> DVec3| {
        std::array::from_fn::<DVec3, MAX_ROWS, _>(|i| {
            if i < POINT_ROWS {
                fixed[i]
            } else if i < n {
                inv_inertia * ang(&r[i])
            } else {
                DVec3::ZERO
            }
        })
    };
    let ia = side(&start.ia, inv_a, |row| row.ang_a);
    let ib = side(&start.ib, inv_b, |row| row.ang_b);
    let mut k = [[0.0f64; MAX_ROWS]; MAX_ROWS];
    let mut live = [false; MAX_ROWS];
    for i in 0..POINT_ROWS {
        for m in 0..=i {
            k[i][m] = start.factor[tri(i, m)];
        }
        live[i] = start.live[i];
    }
    fill_and_factor(&mut k, &mut live, r, &ia[..n], &ib[..n], w, POINT_ROWS);
    // L y = −C, then Lᵀ Δλ = y.
    let mut y = [0.0f64; MAX_ROWS];
    for i in 0..n {
        if !live[i] {
            continue;
        }
        let mut s = -r[i].c;
        for m in 0..i {
            s -= k[i][m] * y[m];
        }
        y[i] = s / k[i][i];
    }
    for i in (0..n).rev() {
        if !live[i] {
            y[i] = 0.0;
            continue;
        }
        let mut s = y[i];
        for m in i + 1..n {
            s -= k[m][i] * y[m];
        }
        y[i] = s / k[i][i];
    }
    y
}
