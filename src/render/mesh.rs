//! Unit meshes the instanced shape pipeline scales per instance.
//!
//! Every vertex carries a `cap` sign: the vertex shader computes
//! `local = position · params.xyz + (0, cap · params.w, 0)`, so one unit sphere split at
//! its equator serves every capsule (`params = (r, r, r, half_height)`), a unit cube every
//! box (`params = half extents`) and unit cylinders and cones every cylinder and cone.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// One mesh vertex.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MeshVertex {
    /// Position on the unit shape.
    pub position: [f32; 3],
    /// Outward normal on the unit shape.
    pub normal: [f32; 3],
    /// −1, 0 or +1: which end of a capsule the vertex moves with.
    pub cap: f32,
}

/// Triangle list geometry.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Vertices.
    pub vertices: Vec<MeshVertex>,
    /// Counter-clockwise triangles seen from outside.
    pub indices: Vec<u32>,
}

impl MeshData {
    fn push(&mut self, p: Vec3, n: Vec3, cap: f32) -> u32 {
        self.vertices.push(MeshVertex {
            position: p.to_array(),
            normal: n.to_array(),
            cap,
        });
        (self.vertices.len() - 1) as u32
    }
}

/// The cube [-1, 1]³ with flat faces.
pub fn unit_cube() -> MeshData {
    let mut m = MeshData::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            // Two tangents with u × v = n, so the quad winds counter-clockwise seen from outside.
            let u = match axis {
                0 => Vec3::Y,
                1 => Vec3::Z,
                _ => Vec3::X,
            };
            let v = n.cross(u);
            let base = m.vertices.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                m.push(n + u * a + v * b, n, 0.0);
            }
            m.indices
                .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    m
}

/// A UV sphere of radius 1 split at the equator: upper-half vertices have `cap = +1`, lower
/// `cap = −1`, and the equator ring is doubled so a capsule's cylinder wall joins them.
pub fn unit_capsule(segments: u32, rings: u32) -> MeshData {
    let mut m = MeshData::default();
    let half_rings = rings.max(2) / 2;
    let mut ring_rows: Vec<(f32, f32)> = Vec::new(); // (polar angle, cap)
    for i in 0..=half_rings {
        ring_rows.push((PI * 0.5 * i as f32 / half_rings as f32, 1.0));
    }
    for i in 0..=half_rings {
        ring_rows.push((PI * 0.5 + PI * 0.5 * i as f32 / half_rings as f32, -1.0));
    }
    let cols = segments + 1;
    for &(theta, cap) in &ring_rows {
        for j in 0..cols {
            let phi = TAU * j as f32 / segments as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            m.push(n, n, cap);
        }
    }
    for r in 0..ring_rows.len() as u32 - 1 {
        for j in 0..segments {
            let a = r * cols + j;
            let b = a + cols;
            m.indices.extend_from_slice(&[a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    m
}

/// The sphere of radius 1 (a capsule of zero length).
pub fn unit_sphere(segments: u32, rings: u32) -> MeshData {
    let mut m = unit_capsule(segments, rings);
    for v in &mut m.vertices {
        v.cap = 0.0;
    }
    m
}

/// A cylinder (`apex_radius = 1`) or cone (`apex_radius = 0`) of radius 1 from y = −1 to
/// y = +1, with its base cap and, for the cylinder, its top cap.
pub fn unit_round(segments: u32, apex_radius: f32) -> MeshData {
    let mut m = MeshData::default();
    // The side's normal tilts up by the slope of the wall: (2, 1 − apex) in (radial, y).
    let slope = Vec3::new(2.0, 1.0 - apex_radius, 0.0).normalize();
    for j in 0..=segments {
        let phi = TAU * j as f32 / segments as f32;
        let radial = Vec3::new(phi.cos(), 0.0, -phi.sin());
        let n = radial * slope.x + Vec3::Y * slope.y;
        m.push(radial - Vec3::Y, n, 0.0);
        m.push(radial * apex_radius + Vec3::Y, n, 0.0);
    }
    for j in 0..segments {
        let a = 2 * j;
        m.indices
            .extend_from_slice(&[a, a + 2, a + 1, a + 1, a + 2, a + 3]);
    }
    let mut disc = |y: f32, r: f32, up: bool| {
        if r <= 0.0 {
            return;
        }
        let n = if up { Vec3::Y } else { -Vec3::Y };
        let centre = m.push(Vec3::new(0.0, y, 0.0), n, 0.0);
        let first = m.vertices.len() as u32;
        for j in 0..=segments {
            let phi = TAU * j as f32 / segments as f32;
            m.push(Vec3::new(phi.cos() * r, y, -phi.sin() * r), n, 0.0);
        }
        for j in 0..segments {
            let (a, b) = (first + j, first + j + 1);
            if up {
                m.indices.extend_from_slice(&[centre, a, b]);
            } else {
                m.indices.extend_from_slice(&[centre, b, a]);
            }
        }
    };
    disc(-1.0, 1.0, false);
    disc(1.0, apex_radius, true);
    m
}

/// Flat-shaded convex hull of `points` (parry3d computes the hull).
pub fn convex_hull(points: &[Vec3]) -> MeshData {
    let mut m = MeshData::default();
    let Ok((verts, tris)) = parry3d::transformation::try_convex_hull(points) else {
        return m;
    };
    for t in tris {
        let [a, b, c] = t.map(|i| verts[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let i = m.push(a, n, 0.0);
        m.push(b, n, 0.0);
        m.push(c, n, 0.0);
        m.indices.extend_from_slice(&[i, i + 1, i + 2]);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Outward winding: for every triangle the geometric normal agrees with the stored one.
    fn assert_outward(m: &MeshData) {
        for t in m.indices.chunks(3) {
            let p = |i: u32| Vec3::from(m.vertices[i as usize].position);
            let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
            if n.length() < 1e-6 {
                continue; // degenerate pole triangle
            }
            let stored = Vec3::from(m.vertices[t[0] as usize].normal);
            assert!(n.dot(stored) > 0.0, "inward triangle {t:?}");
        }
    }

    #[test]
    fn meshes_wind_outward() {
        assert_outward(&unit_cube());
        assert_outward(&unit_capsule(12, 8));
        assert_outward(&unit_round(12, 1.0));
        assert_outward(&unit_round(12, 0.0));
        let octa = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let hull = convex_hull(&octa);
        assert_eq!(hull.indices.len(), 8 * 3);
        assert_outward(&hull);
    }
}
