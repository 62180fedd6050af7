//! The skinned md5 mesh of a Doom 3 figure, drawn on each side with the joints that
//! side's bodies give it (see `ragdoll_sim::scene::rig`), tinted like that side's
//! bodies. Skinning runs in the vertex shader (`shaders/skin.wgsl`): joint matrices in
//! a uniform buffer per side, up to four weights per vertex as vertex attributes, taken
//! from the same [`SkinnedMesh`] records the CPU skins and casts shots against (so a
//! vertex keeps its four largest biases on both).
//!
//! A mesh with more joints than [`MAX_JOINTS`] is not drawn.

use bytemuck::{Pod, Zeroable};
use glam::Mat4;
use ragdoll_sim::scene::BodyDesc;
use ragdoll_sim::scene::Pose;
use ragdoll_sim::scene::md5mesh::Md5Mesh;
use ragdoll_sim::scene::rig::Rig;
use ragdoll_sim::scene::skin::SkinnedMesh;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// Joints the shader's uniform array holds (192 × 64 bytes + the colour fits the
/// 16 KiB every adapter offers).
pub const MAX_JOINTS: usize = 192;

/// A figure's mesh and how its bodies drive it.
#[derive(Clone, Debug)]
pub struct SkinModel {
    /// The joints from the bodies.
    pub rig: Rig,
    /// The mesh (file units and axes).
    pub mesh: Md5Mesh,
    /// The mesh's weights in our units, its triangles, and the body containing each
    /// joint: what the GPU draws and shots are cast against.
    pub skinned: SkinnedMesh,
}

impl SkinModel {
    /// The model of `mesh` driven by `rig`, its joints contained by `bodies` (the
    /// scene's bodies, whose `contained_joints` say which).
    pub fn new(rig: Rig, mesh: Md5Mesh, bodies: &[BodyDesc]) -> SkinModel {
        let skinned = SkinnedMesh::new(&mesh, &rig, bodies);
        SkinModel { rig, mesh, skinned }
    }

    /// Every joint's world pose for one side's body poses (shape frames, scene order).
    pub fn joint_poses(&self, bodies: &[Pose]) -> Vec<Pose> {
        self.rig.joint_poses(bodies)
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SkinVertex {
    weights: [[f32; 4]; 4],
    joints: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SkinUniform {
    color: [f32; 4],
    joints: [[[f32; 4]; 4]; MAX_JOINTS],
}

struct GpuSkin {
    /// Which model this is (the `Arc`'s address).
    key: usize,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
    sides: [(wgpu::Buffer, wgpu::BindGroup); 2],
    posed: [bool; 2],
}

/// The pipeline and the current model's buffers.
pub(crate) struct SkinRenderer {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    model: Option<GpuSkin>,
}

impl SkinRenderer {
    pub(crate) fn new(
        device: &wgpu::Device,
        target: super::pipeline::Target,
        camera_layout: &wgpu::BindGroupLayout,
    ) -> SkinRenderer {
        use super::pipeline::{Stage, depth, render_pipeline, uniform_layout};
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("skin"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/skin.wgsl").into()),
        });
        let layout = uniform_layout(device, "skin");
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("skin"),
            bind_group_layouts: &[Some(camera_layout), Some(&layout)],
            immediate_size: 0,
        });
        let attrs = wgpu::vertex_attr_array![
            0 => Float32x4, 1 => Float32x4, 2 => Float32x4, 3 => Float32x4, 4 => Uint32x4
        ];
        let pipeline = render_pipeline(
            device,
            &pipeline_layout,
            target,
            Stage {
                label: "skin",
                shader: &shader,
                vs: "vs_skin",
                fs: "fs_skin",
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<SkinVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attrs,
                })],
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull: false,
                depth_stencil: depth(true, wgpu::CompareFunction::Less),
                blend: None,
            },
        );
        SkinRenderer {
            pipeline,
            layout,
            model: None,
        }
    }

    /// Uploads `model` if it is not the one already on the GPU (or drops it for `None`),
    /// then each side's joint matrices and tint.
    pub(crate) fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        model: Option<&Arc<SkinModel>>,
        poses: [&[Pose]; 2],
        colors: [[f32; 4]; 2],
    ) {
        let Some(model) = model.filter(|m| m.rig.joints.len() <= MAX_JOINTS) else {
            self.model = None;
            return;
        };
        let key = Arc::as_ptr(model) as usize;
        if self.model.as_ref().is_none_or(|m| m.key != key) {
            self.model = Some(self.upload(device, model, key));
        }
        let gpu = self.model.as_mut().expect("uploaded above");
        for side in 0..2 {
            gpu.posed[side] = poses[side].len() == model.rig.joints.len();
            if !gpu.posed[side] {
                continue;
            }
            let mut u = SkinUniform::zeroed();
            u.color = colors[side];
            for (slot, p) in u.joints.iter_mut().zip(poses[side]) {
                *slot = Mat4::from_rotation_translation(p.rotation, p.position).to_cols_array_2d();
            }
            queue.write_buffer(&gpu.sides[side].0, 0, bytemuck::bytes_of(&u));
        }
    }

    fn upload(&self, device: &wgpu::Device, model: &SkinModel, key: usize) -> GpuSkin {
        let vertices: Vec<SkinVertex> = model
            .skinned
            .vertices
            .iter()
            .map(|v| {
                let mut out = SkinVertex::zeroed();
                for k in 0..v.joints.len() {
                    let o = v.offsets[k];
                    out.weights[k] = [o.x, o.y, o.z, v.biases[k]];
                    out.joints[k] = v.joints[k];
                }
                out
            })
            .collect();
        let indices: Vec<u32> = model.skinned.triangles.iter().flatten().copied().collect();
        let vertices_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("skin vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("skin indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let side = || {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("skin joints"),
                size: std::mem::size_of::<SkinUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("skin joints"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            });
            (buffer, group)
        };
        GpuSkin {
            key,
            vertices: vertices_buf,
            indices: indices_buf,
            count: indices.len() as u32,
            sides: [side(), side()],
            posed: [false; 2],
        }
    }

    /// Whether a model is on the GPU.
    pub(crate) fn has_model(&self) -> bool {
        self.model.is_some()
    }

    /// Draws side `side`'s mesh (the camera group is already bound).
    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>, side: usize) {
        let Some(gpu) = &self.model else { return };
        if side >= 2 || !gpu.posed[side] || gpu.count == 0 {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(1, &gpu.sides[side].1, &[]);
        pass.set_vertex_buffer(0, gpu.vertices.slice(..));
        pass.set_index_buffer(gpu.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..gpu.count, 0, 0..1);
    }
}
