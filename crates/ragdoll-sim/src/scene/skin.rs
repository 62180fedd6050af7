//! The skinned md5 mesh on the CPU: vertex positions from the joints the bodies drive
//! (see [`super::rig`]), segments cast against its triangles, and which body a hit
//! pushes (Doom 3's `containedJoints`).
//!
//! Skinning is the md5 rule, p = Σₖ biasₖ (tₖ + Rₖ oₖ), with (Rₖ, tₖ) the world pose of
//! weight k's joint and oₖ the weight's offset in that joint's frame. A vertex keeps its
//! [`MAX_WEIGHTS`] largest biases (Doom 3's own meshes rarely have more), not
//! renormalised, as Doom 3 does not renormalise; the offsets are converted once to our
//! units and axes. The GPU pass draws from these same [`SkinVertex`] records, so what
//! is hit here is what is drawn.
//!
//! A hit on the mesh is handed to a body as MrElusive's articulated-figure document says
//! under `containedjoints`: the joint nearest to the hit point, then the body that
//! contains that joint.

use super::md5mesh::Md5Mesh;
use super::rig::Rig;
use super::{BodyDesc, BodyId, Pose};
use glam::Vec3;
use parry3d::bounding_volume::Aabb;
use parry3d::query::{Ray, RayCast};
use parry3d::shape::TriMesh;
use std::cell::OnceCell;

/// Weights kept per vertex.
pub const MAX_WEIGHTS: usize = 4;

/// One vertex's weights, our units and axes. Unused slots have bias 0 and joint 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkinVertex {
    /// The weights' joints (skeleton indices).
    pub joints: [u32; MAX_WEIGHTS],
    /// The weights' biases, largest first.
    pub biases: [f32; MAX_WEIGHTS],
    /// The weights' offsets in their joints' frames (m, our axes).
    pub offsets: [Vec3; MAX_WEIGHTS],
}

/// Where a segment first meets the mesh, and the body the hit pushes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshHit {
    /// The hit point (world, m).
    pub point: Vec3,
    /// Fraction of the segment travelled to the hit, in [0, 1].
    pub fraction: f32,
    /// The triangle hit (index into [`SkinnedMesh::triangles`]).
    pub triangle: u32,
    /// The skeleton joint nearest to the point.
    pub joint: usize,
    /// The body containing that joint, `None` when no body contains it.
    pub body: Option<BodyId>,
}

/// A figure's mesh ready to skin on the CPU or upload to the GPU.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinnedMesh {
    /// Every vertex of every `mesh { }` block, in file order.
    pub vertices: Vec<SkinVertex>,
    /// Triangles as indices into `vertices`, in the file's winding.
    pub triangles: Vec<[u32; 3]>,
    /// For every skeleton joint, the body that contains it (`containedJoints`).
    pub joint_body: Vec<Option<BodyId>>,
}

impl SkinnedMesh {
    /// The mesh of `mesh` (file units and axes) for the skeleton of `rig`, each joint
    /// given to the body of `bodies` whose `contained_joints` lists it.
    pub fn new(mesh: &Md5Mesh, rig: &Rig, bodies: &[BodyDesc]) -> SkinnedMesh {
        let (axes, scale) = (rig.file_axes, rig.file_scale);
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for sub in &mesh.meshes {
            let base = vertices.len() as u32;
            for v in &sub.vertices {
                let first = v.first_weight as usize;
                let end = (first + v.weight_count as usize).min(sub.weights.len());
                let mut ws = sub.weights[first.min(end)..end].to_vec();
                // Stable, so equal biases keep the file's order.
                ws.sort_by(|a, b| b.bias.total_cmp(&a.bias));
                let mut out = SkinVertex {
                    joints: [0; MAX_WEIGHTS],
                    biases: [0.0; MAX_WEIGHTS],
                    offsets: [Vec3::ZERO; MAX_WEIGHTS],
                };
                for (k, w) in ws.iter().take(MAX_WEIGHTS).enumerate() {
                    out.joints[k] = w.joint;
                    out.biases[k] = w.bias;
                    out.offsets[k] = axes * w.offset * scale;
                }
                vertices.push(out);
            }
            triangles.extend(sub.triangles.iter().map(|t| t.map(|i| base + i)));
        }
        let mut joint_body = vec![None; rig.joints.len()];
        for (b, body) in bodies.iter().enumerate() {
            for &j in &body.contained_joints {
                if let Some(slot) = joint_body.get_mut(j as usize) {
                    *slot = Some(BodyId(b as u32));
                }
            }
        }
        SkinnedMesh {
            vertices,
            triangles,
            joint_body,
        }
    }

    /// Vertex positions (world, m) for the joints' world poses (`Rig::joint_poses`).
    pub fn positions(&self, joints: &[Pose], out: &mut Vec<Vec3>) {
        out.clear();
        out.extend(self.vertices.iter().map(|v| {
            (0..MAX_WEIGHTS)
                .filter(|&k| v.biases[k] != 0.0)
                .map(|k| {
                    let j = &joints[v.joints[k] as usize];
                    (j.position + j.rotation * v.offsets[k]) * v.biases[k]
                })
                .sum::<Vec3>()
        }));
    }

    /// The mesh skinned on `joints` (from `Rig::joint_poses`), ready for casts.
    pub fn posed<'a>(&'a self, joints: &'a [Pose]) -> PosedMesh<'a> {
        let mut positions = Vec::new();
        self.positions(joints, &mut positions);
        let bounds = (!positions.is_empty()).then(|| Aabb::from_points(positions.iter().copied()));
        PosedMesh {
            skin: self,
            joints,
            positions,
            bounds,
            mesh: OnceCell::new(),
        }
    }
}

/// A [`SkinnedMesh`] in one pose of its joints.
pub struct PosedMesh<'a> {
    skin: &'a SkinnedMesh,
    joints: &'a [Pose],
    positions: Vec<Vec3>,
    /// The box around every vertex: a segment missing it misses the mesh.
    bounds: Option<Aabb>,
    /// A BVH over the posed triangles, built at the first segment that reaches
    /// `bounds` (the mesh moves every step, so it is built per pose).
    mesh: OnceCell<Option<TriMesh>>,
}

impl PosedMesh<'_> {
    /// The skinned vertex positions (world, m).
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The first place the segment `from` → `to` meets a triangle, from either side,
    /// and the body the hit pushes. `None` for a miss, a zero-length segment, or a mesh
    /// without triangles.
    pub fn cast_segment(&self, from: Vec3, to: Vec3) -> Option<MeshHit> {
        if from == to || self.skin.triangles.is_empty() {
            return None;
        }
        let ray = Ray::new(from, to - from);
        self.bounds?.cast_local_ray(&ray, 1.0, true)?;
        let mesh = self
            .mesh
            .get_or_init(|| TriMesh::new(self.positions.clone(), self.skin.triangles.clone()).ok())
            .as_ref()?;
        let ray = Ray::new(from, to - from);
        let hit = mesh.cast_local_ray_and_get_normal(&ray, 1.0, false)?;
        let point = ray.point_at(hit.time_of_impact);
        let joint = nearest_joint(self.joints, point)?;
        Some(MeshHit {
            point,
            fraction: hit.time_of_impact,
            triangle: hit.subshape,
            joint,
            body: self.skin.joint_body.get(joint).copied().flatten(),
        })
    }
}

/// The joint whose world position is nearest to `point` (the first of equals).
pub fn nearest_joint(joints: &[Pose], point: Vec3) -> Option<usize> {
    joints
        .iter()
        .enumerate()
        .min_by(|a, b| {
            a.1.position
                .distance_squared(point)
                .total_cmp(&b.1.position.distance_squared(point))
        })
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::md5mesh::{Md5Joint, Md5Skeleton, Md5SubMesh, Md5Vertex, Md5Weight};
    use crate::scene::rig::JointMod;
    use crate::scene::{MassSpec, Shape};
    use glam::{Quat, Vec2};

    /// One triangle in the plane x = 1 (file units = metres, Y up), weighted to joint 1.
    fn one_triangle() -> (Md5Mesh, Rig, Vec<BodyDesc>) {
        let joint = |name: &str, parent, x| Md5Joint {
            name: name.into(),
            parent,
            position: Vec3::new(x, 0.0, 0.0),
            orientation: Quat::IDENTITY,
        };
        let skeleton = Md5Skeleton {
            joints: vec![joint("root", None, 0.0), joint("tip", Some(0), 1.0)],
        };
        let w = |o: Vec3| Md5Weight {
            joint: 1,
            bias: 1.0,
            offset: o,
        };
        let vertex = |i| Md5Vertex {
            uv: Vec2::ZERO,
            first_weight: i,
            weight_count: 1,
        };
        let sub = Md5SubMesh {
            vertices: (0..3).map(vertex).collect(),
            triangles: vec![[0, 1, 2]],
            weights: vec![
                w(Vec3::new(0.0, -1.0, -1.0)),
                w(Vec3::new(0.0, 1.0, -1.0)),
                w(Vec3::new(0.0, 0.0, 1.0)),
            ],
            ..Default::default()
        };
        let body = |name: &str, x: f32, joints: Vec<u32>| {
            let mut b = BodyDesc::new(
                name,
                Shape::Box {
                    half_extents: Vec3::splat(0.1),
                },
                Pose {
                    position: Vec3::new(x, 0.0, 0.0),
                    rotation: Quat::IDENTITY,
                },
                MassSpec::Mass(1.0),
            );
            b.contained_joints = joints;
            b
        };
        let bodies = vec![body("base", 0.0, vec![0]), body("end", 1.0, vec![1])];
        let joints: Vec<(String, Option<usize>, Pose)> = skeleton
            .joints
            .iter()
            .map(|j| (j.name.clone(), j.parent, j.pose()))
            .collect();
        let rest: Vec<Pose> = bodies.iter().map(|b| b.pose).collect();
        let rig = Rig::new(&joints, &[(1, 1, JointMod::Both)], &rest, Some(0));
        (
            Md5Mesh {
                skeleton,
                meshes: vec![sub],
            },
            rig,
            bodies,
        )
    }

    #[test]
    fn a_segment_through_the_triangle_hits_it_and_pushes_the_containing_body() {
        let (mesh, rig, bodies) = one_triangle();
        let skin = SkinnedMesh::new(&mesh, &rig, &bodies);
        let poses: Vec<Pose> = bodies.iter().map(|b| b.pose).collect();
        let joints = rig.joint_poses(&poses);
        let posed = skin.posed(&joints);
        assert_eq!(posed.positions()[2], Vec3::new(1.0, 0.0, 1.0));
        let from = Vec3::new(3.0, 0.0, 0.0);
        let hit = posed
            .cast_segment(from, Vec3::new(-1.0, 0.0, 0.0))
            .expect("crosses x = 1");
        assert!((hit.point - Vec3::X).length() < 1e-5, "{hit:?}");
        assert!((hit.fraction - 0.5).abs() < 1e-5);
        assert_eq!((hit.joint, hit.body), (1, Some(BodyId(1))));
        // Stopping short of the plane, or passing beside the triangle, misses.
        assert!(posed.cast_segment(from, Vec3::new(1.1, 0.0, 0.0)).is_none());
        let beside = Vec3::new(0.0, 3.0, 0.0);
        assert!(
            posed
                .cast_segment(from + beside, -Vec3::X + beside)
                .is_none()
        );
        // A joint no body contains: the hit is found, and pushes no body.
        let mut loose = bodies.clone();
        loose[1].contained_joints.clear();
        let skin = SkinnedMesh::new(&mesh, &rig, &loose);
        let hit = skin
            .posed(&joints)
            .cast_segment(from, -Vec3::X)
            .expect("the same triangle");
        assert_eq!((hit.joint, hit.body), (1, None));
    }
}
