//! Sticks: distance constraints `C = |x_a − x_b| − l` between two particles (the
//! paper's section 3.1, eq. 44; Jakobsen 2001), hard (zero compliance). A bone's six
//! sticks are the edges of its tetrahedron; they are what keeps it a rigid body.

use super::particles::XParticles;

/// A stick between particles `a` and `b` of rest length `rest` (m).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stick {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length (m).
    pub rest: f32,
}

/// One Gauss–Seidel pass over `sticks`: each moves its two particles along the stick by
/// their inverse masses, `Δx_a = −w_a / (w_a + w_b) C n`.
pub(crate) fn solve(sticks: &[Stick], p: &mut XParticles) {
    for s in sticks {
        let (a, b) = (s.a as usize, s.b as usize);
        let (wa, wb) = (p.w[a], p.w[b]);
        let sum = wa + wb;
        if sum == 0.0 {
            continue;
        }
        let d = p.x[b] - p.x[a];
        let len = d.length();
        if len < 1e-9 {
            continue;
        }
        let corr = d * ((len - s.rest) / (len * sum));
        p.x[a] += corr * wa;
        p.x[b] -= corr * wb;
    }
}
