//! Contact pairs solved four at a time: graph colouring and SIMD lanes (Box2D v3's
//! `constraint_graph.c` and the wide half of `contact_solver.c`, in 3D).
//!
//! Gauss–Seidel solves one constraint after another because each reads the velocities
//! the previous ones wrote. Two pairs that share no moving body do not read each other's
//! writes, so they can be solved at once. [`color`] deals the step's pairs into colours
//! in which no moving body appears twice (static and sleeping bodies are never written,
//! so they may appear in every pair of a colour: the ground does), and each colour is
//! cut into `Bundle`s of [`LANES`] pairs, one per lane of an `f32x4`. A bundle is then
//! solved with exactly the scalar solver's arithmetic per lane — the same rows, the same
//! soft coefficients, the same friction disk — four lanes to an instruction.
//!
//! What changes is only the order: the pairs no colour could take (a body in more than
//! [`COLORS`] pairs), the rolling pairs and the pairs with more than [`SLOTS`] points are
//! solved one by one first, then the colours in turn. Every order is deterministic: the
//! colouring is a greedy pass over the pairs in their array order.
//!
//! During the substeps a bundle holds its pairs' accumulated impulses; they are written
//! back to the scalar constraints once the substeps are done (`Bundle::write_back`).

use super::body::BodyStates;
use super::contact_solver::{PairConstraint, PointConstraint};
use super::soft::StepContext;
use crate::lanes::{Quatx4, Vec3x4, f4};
use glam::Vec3;
use wide::f32x4;

/// Pairs per bundle: the lanes of an `f32x4`.
pub const LANES: usize = crate::lanes::LANES;
/// Points per pair a bundle has room for (a box face on a face or on the ground has 4).
pub const SLOTS: usize = 4;
/// Colours tried before a pair is left to the one-by-one solve. A body of a pile touches
/// up to about a dozen others.
pub const COLORS: usize = 16;

/// One point slot of a bundle: the rows of each lane's point at that slot (see
/// [`PointConstraint`] for each field's meaning).
#[derive(Clone, Copy, Debug, Default)]
struct WidePoint {
    ja_n: Vec3x4,
    jb_n: Vec3x4,
    ja_t: [Vec3x4; 2],
    jb_t: [Vec3x4; 2],
    ia_n: Vec3x4,
    ib_n: Vec3x4,
    ia_t: [Vec3x4; 2],
    ib_t: [Vec3x4; 2],
    normal_mass: f32x4,
    tangent_mass: [f32x4; 2],
    normal_impulse: f32x4,
    tangent_impulse: [f32x4; 2],
    max_normal_impulse: f32x4,
    separation: f32x4,
    /// The anchors in the bodies' frames and the separation at build time less
    /// `n·(p_b − p_a)` (see [`PointConstraint`]), for the separation now.
    local_a: Vec3x4,
    local_b: Vec3x4,
    base_separation: f32x4,
}

/// Up to [`LANES`] pairs of one colour, solved side by side.
#[derive(Clone, Debug)]
pub(super) struct Bundle {
    /// Each lane's first point among the scalar points, and its number of points (0 for
    /// an empty lane).
    start: [usize; LANES],
    count: [usize; LANES],
    /// Each lane's bodies (an empty lane repeats lane 0's and writes nothing).
    a: [usize; LANES],
    b: [usize; LANES],
    /// How many point slots any lane uses.
    slots: usize,
    normal: Vec3x4,
    tangents: [Vec3x4; 2],
    inv_mass_a: f32x4,
    inv_mass_b: f32x4,
    friction: f32x4,
    points: [WidePoint; SLOTS],
}

impl Bundle {
    /// A bundle of 1 to [`LANES`] pairs, each with at most [`SLOTS`] points. A slot a lane
    /// does not use keeps zero masses and impulses, so it applies nothing.
    pub(super) fn load(lanes: &[&PairConstraint], points: &[PointConstraint]) -> Bundle {
        let lane = |k: usize| lanes.get(k).copied();
        let first = lanes[0];
        let or_zero = |k: usize, f: fn(&PairConstraint) -> f32| lane(k).map_or(0.0, f);
        let mut bundle = Bundle {
            start: std::array::from_fn(|k| lane(k).map_or(0, |p| p.start)),
            count: std::array::from_fn(|k| lane(k).map_or(0, |p| p.count)),
            a: std::array::from_fn(|k| lane(k).unwrap_or(first).a),
            b: std::array::from_fn(|k| lane(k).unwrap_or(first).b),
            slots: lanes.iter().map(|p| p.count).max().unwrap_or(0),
            normal: Vec3x4::from_fn(|k| lane(k).map_or(Vec3::ZERO, |p| p.normal)),
            tangents: [0, 1]
                .map(|t| Vec3x4::from_fn(|k| lane(k).map_or(Vec3::ZERO, |p| p.tangents[t]))),
            inv_mass_a: f4(|k| or_zero(k, |p| p.inv_mass_a)),
            inv_mass_b: f4(|k| or_zero(k, |p| p.inv_mass_b)),
            friction: f4(|k| or_zero(k, |p| p.friction)),
            points: [WidePoint::default(); SLOTS],
        };
        let empty = PointConstraint::default();
        for j in 0..bundle.slots {
            let l: [&PointConstraint; LANES] =
                std::array::from_fn(|k| bundle.point(points, k, j).unwrap_or(&empty));
            let v3 = |f: fn(&PointConstraint) -> Vec3| Vec3x4::from_fn(|k| f(l[k]));
            let s4 = |f: fn(&PointConstraint) -> f32| f4(|k| f(l[k]));
            bundle.points[j] = WidePoint {
                ja_n: v3(|p| p.ja_n),
                jb_n: v3(|p| p.jb_n),
                ja_t: [v3(|p| p.ja_t[0]), v3(|p| p.ja_t[1])],
                jb_t: [v3(|p| p.jb_t[0]), v3(|p| p.jb_t[1])],
                normal_mass: s4(|p| p.normal_mass),
                tangent_mass: [s4(|p| p.tangent_mass[0]), s4(|p| p.tangent_mass[1])],
                normal_impulse: s4(|p| p.normal_impulse),
                tangent_impulse: [s4(|p| p.tangent_impulse[0]), s4(|p| p.tangent_impulse[1])],
                local_a: v3(|p| p.local_a),
                local_b: v3(|p| p.local_b),
                base_separation: s4(|p| p.base_separation),
                ..WidePoint::default()
            };
        }
        bundle
    }

    /// Lane `k`'s point in slot `j`, if it has one.
    #[inline]
    fn point<'a>(
        &self,
        points: &'a [PointConstraint],
        k: usize,
        j: usize,
    ) -> Option<&'a PointConstraint> {
        (j < self.count[k]).then(|| &points[self.start[k] + j])
    }

    /// Forms each point's separation on the bodies' poses now (the scalar
    /// `current_separation`, the anchors rotated with glam's operations:
    /// `Quatx4::rotate_as_glam`) and, with `inertia`, what changes every substep with the
    /// inertia, `I⁻¹ J` of every row, in the lanes: at each substep's preparation, and
    /// before the relax pass (separations only). Each lane's product is glam's `Mat3 *
    /// Vec3`, column by column in the same order, so the lanes hold the scalar solver's
    /// bits.
    pub(super) fn refresh(&mut self, s: &BodyStates, inertia: bool) {
        let (com_a, com_b) = (
            Vec3x4::from_fn(|k| s.com[self.a[k]]),
            Vec3x4::from_fn(|k| s.com[self.b[k]]),
        );
        let (rot_a, rot_b) = (
            Quatx4::from_fn(|k| s.rot[self.a[k]]),
            Quatx4::from_fn(|k| s.rot[self.b[k]]),
        );
        for w in &mut self.points[..self.slots] {
            let pa = com_a + rot_a.rotate_as_glam(w.local_a);
            let pb = com_b + rot_b.rotate_as_glam(w.local_b);
            w.separation = w.base_separation + self.normal.dot(pb - pa);
        }
        if !inertia {
            return;
        }
        let (ia, ib) = (s.inv_inertia_x4(self.a), s.inv_inertia_x4(self.b));
        for w in &mut self.points[..self.slots] {
            w.ia_n = ia * w.ja_n;
            w.ib_n = ib * w.jb_n;
            w.ia_t = w.ja_t.map(|j| ia * j);
            w.ib_t = w.jb_t.map(|j| ib * j);
        }
    }

    /// The lanes' body velocities.
    #[inline]
    fn gather(&self, s: &BodyStates) -> [Vec3x4; 4] {
        s.velocities_x4(self.a, self.b)
    }

    /// Writes the lanes' velocities back to their moving bodies (in one colour no moving
    /// body is in two lanes; static and sleeping bodies are not written).
    #[inline]
    fn scatter(&self, s: &mut BodyStates, v: [Vec3x4; 4]) {
        let masses = [self.inv_mass_a, self.inv_mass_b];
        s.set_velocities_x4([self.a, self.b], masses, &v, |k| self.count[k] != 0);
    }

    /// Re-applies the accumulated impulses.
    pub(super) fn warm_start(&self, s: &mut BodyStates) {
        let [mut va, mut wa, mut vb, mut wb] = self.gather(s);
        let [t0, t1] = self.tangents;
        for p in &self.points[..self.slots] {
            let [l0, l1] = p.tangent_impulse;
            let linear = self.normal * p.normal_impulse + t0 * l0 + t1 * l1;
            va -= linear * self.inv_mass_a;
            vb += linear * self.inv_mass_b;
            wa -= p.ia_n * p.normal_impulse + p.ia_t[0] * l0 + p.ia_t[1] * l1;
            wb += p.ib_n * p.normal_impulse + p.ib_t[0] * l0 + p.ib_t[1] * l1;
        }
        self.scatter(s, [va, wa, vb, wb]);
    }

    /// One Gauss–Seidel pass over the bundle's points: the scalar
    /// `ContactConstraints::solve`, lane by lane, with the separations of the last
    /// [`Bundle::refresh`].
    pub(super) fn solve(&mut self, s: &mut BodyStates, ctx: &StepContext, use_bias: bool) {
        let [mut va, mut wa, mut vb, mut wb] = self.gather(s);
        let (ma, mb) = (self.inv_mass_a, self.inv_mass_b);
        let n = self.normal;
        let [t0, t1] = self.tangents;
        let zero = f32x4::ZERO;
        let one = f32x4::ONE;
        let inv_h = f32x4::splat(ctx.inv_h);
        let (bias_rate, push_out, soft_mass, soft_impulse) = if use_bias {
            (
                f32x4::splat(ctx.contact.bias_rate),
                f32x4::splat(-ctx.max_push_out),
                f32x4::splat(ctx.contact.mass_scale),
                f32x4::splat(ctx.contact.impulse_scale),
            )
        } else {
            (zero, zero, one, zero)
        };
        for p in &mut self.points[..self.slots] {
            // Speculative (the gap may close this substep, no further) or soft.
            let sep = p.separation;
            let speculative = sep.simd_gt(zero);
            let soft_bias = (bias_rate * sep).fast_max(push_out);
            let bias = speculative.select(sep * inv_h, soft_bias);
            let mass_scale = speculative.select(one, soft_mass);
            let impulse_scale = speculative.select(zero, soft_impulse);

            let vn = n.dot(vb - va) + p.jb_n.dot(wb) - p.ja_n.dot(wa);
            let l = -p.normal_mass * mass_scale * (vn + bias) - impulse_scale * p.normal_impulse;
            let new = (p.normal_impulse + l).fast_max(zero);
            let d = new - p.normal_impulse;
            p.normal_impulse = new;
            p.max_normal_impulse = p.max_normal_impulse.fast_max(new);
            va -= n * (d * ma);
            vb += n * (d * mb);
            wa -= p.ia_n * d;
            wb += p.ib_n * d;

            // Coulomb friction on the disk of radius μλₙ.
            let dv = vb - va;
            let v0 = t0.dot(dv) + p.jb_t[0].dot(wb) - p.ja_t[0].dot(wa);
            let v1 = t1.dot(dv) + p.jb_t[1].dot(wb) - p.ja_t[1].dot(wa);
            let [o0, o1] = p.tangent_impulse;
            let n0 = o0 - p.tangent_mass[0] * v0;
            let n1 = o1 - p.tangent_mass[1] * v1;
            let cap = self.friction * p.normal_impulse;
            let len2 = n0 * n0 + n1 * n1;
            let over = len2.simd_gt(cap * cap);
            // Lanes not over the cap keep their impulse (their 0/0 is never picked).
            let scale = over.select(cap / len2.sqrt(), one);
            let (n0, n1) = (n0 * scale, n1 * scale);
            p.tangent_impulse = [n0, n1];
            let (d0, d1) = (n0 - o0, n1 - o1);
            let linear = t0 * d0 + t1 * d1;
            va -= linear * ma;
            vb += linear * mb;
            wa -= p.ia_t[0] * d0 + p.ia_t[1] * d1;
            wb += p.ib_t[0] * d0 + p.ib_t[1] * d1;
        }
        self.scatter(s, [va, wa, vb, wb]);
    }

    /// Writes the lanes' accumulated impulses back to the scalar points.
    pub(super) fn write_back(&self, points: &mut [PointConstraint]) {
        for k in 0..LANES {
            for (j, w) in self.points[..self.count[k]].iter().enumerate() {
                let p = &mut points[self.start[k] + j];
                p.normal_impulse = w.normal_impulse.as_array()[k];
                p.tangent_impulse = w.tangent_impulse.map(|t| t.as_array()[k]);
                p.max_normal_impulse = w.max_normal_impulse.as_array()[k];
            }
        }
    }
}

/// Deals `pairs` (their moving bodies: `None` for a body the solve does not write) into
/// colours, greedily in array order; a pair `wide_ok` rejects, or that no colour can
/// take, goes to the returned one-by-one list. Returns the colours' pairs and that list.
pub fn color(
    bodies: usize,
    pairs: impl Iterator<Item = (Option<usize>, Option<usize>, bool)>,
) -> (Vec<Vec<u32>>, Vec<u32>) {
    let words = bodies.div_ceil(64);
    let mut used = vec![0u64; COLORS * words];
    let mut colors: Vec<Vec<u32>> = vec![Vec::new(); COLORS];
    let mut single = Vec::new();
    let taken = |used: &[u64], c: usize, i: Option<usize>| {
        i.is_some_and(|i| used[c * words + i / 64] & (1 << (i % 64)) != 0)
    };
    for (index, (a, b, wide_ok)) in pairs.enumerate() {
        let free = wide_ok
            .then(|| (0..COLORS).find(|&c| !taken(&used, c, a) && !taken(&used, c, b)))
            .flatten();
        match free {
            Some(c) => {
                for i in [a, b].into_iter().flatten() {
                    used[c * words + i / 64] |= 1 << (i % 64);
                }
                colors[c].push(index as u32);
            }
            None => single.push(index as u32),
        }
    }
    (colors, single)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_colour_never_holds_a_moving_body_twice_but_shares_static_ones() {
        // A chain of moving bodies 0-1-2-3, each also on the ground (static: None).
        let pairs = [
            (Some(0), Some(1), true),
            (Some(1), Some(2), true),
            (Some(2), Some(3), true),
            (Some(0), None, true),
            (Some(1), None, true),
            (Some(2), None, true),
            (Some(3), None, true),
            (Some(3), Some(0), false),
        ];
        let (colors, single) = color(4, pairs.iter().copied());
        assert_eq!(
            single,
            vec![7],
            "a pair the caller keeps scalar stays scalar"
        );
        let mut seen = 0;
        for c in &colors {
            let mut bodies: Vec<usize> = c
                .iter()
                .flat_map(|&i| [pairs[i as usize].0, pairs[i as usize].1])
                .flatten()
                .collect();
            seen += c.len();
            let n = bodies.len();
            bodies.sort_unstable();
            bodies.dedup();
            assert_eq!(bodies.len(), n, "a moving body twice in colour {c:?}");
        }
        assert_eq!(seen, 7);
        // Greedy in array order: the chain's first and third links share the first colour.
        assert_eq!(colors[0], vec![0, 2]);
    }

    #[test]
    fn a_body_in_more_pairs_than_colours_overflows_to_the_scalar_solve() {
        let pairs = (1..=COLORS + 3).map(|i| (Some(0), Some(i), true));
        let (colors, single) = color(COLORS + 4, pairs);
        assert!(colors.iter().all(|c| c.len() == 1));
        assert_eq!(single, vec![16, 17, 18]);
    }

    #[test]
    fn lanes_round_trip() {
        let v = Vec3x4::from_fn(|k| Vec3::new(k as f32, 10.0 + k as f32, -(k as f32)));
        for k in 0..LANES {
            assert_eq!(v.lane(k), Vec3::new(k as f32, 10.0 + k as f32, -(k as f32)));
        }
        let d = v.dot(v).to_array();
        assert_eq!(d[2], 4.0 + 144.0 + 4.0);
    }
}
