//! The split-screen renderer: instanced lit shapes, planar shadows, a ground grid,
//! particles as small spheres and sticks, contacts and joint limits as lines, with 4× MSAA.
//!
//! It reads only [`RenderSnapshot`]s: no physics here. The window and offscreen capture
//! both call [`Renderer::render`], then draw the egui overlay on top of the same target.

pub mod camera;
pub mod gpu;
pub mod mesh;
pub mod palette;
mod pipeline;
pub mod skin;

use bytemuck::{Pod, Zeroable};
use camera::OrbitCamera;
use glam::{Mat4, Quat, Vec3};
use mesh::{MeshData, MeshVertex};
use ragdoll_sim::MethodKind;
use ragdoll_sim::scene::{Ground, Shape};
use ragdoll_sim::snapshot::{LimitShape, RenderSnapshot};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// Depth and stencil (the stencil draws each pixel's shadow once).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth24PlusStencil8;

/// Direction the sunlight travels: down, from the front left.
const LIGHT_DIR: Vec3 = Vec3::new(0.35, -1.0, -0.45);

/// A viewport rectangle in physical pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Left edge.
    pub x: f32,
    /// Top edge.
    pub y: f32,
    /// Width.
    pub width: f32,
    /// Height.
    pub height: f32,
}

impl Viewport {
    /// Width / height.
    pub fn aspect(&self) -> f32 {
        self.width / self.height.max(1.0)
    }

    /// Whether `p` (physical pixels) lies inside.
    pub fn contains(&self, p: glam::Vec2) -> bool {
        p.x >= self.x && p.y >= self.y && p.x < self.x + self.width && p.y < self.y + self.height
    }

    /// `p` in normalised device coordinates of this viewport (y up).
    pub fn ndc(&self, p: glam::Vec2) -> glam::Vec2 {
        glam::Vec2::new(
            (p.x - self.x) / self.width * 2.0 - 1.0,
            1.0 - (p.y - self.y) / self.height * 2.0,
        )
    }

    /// The pixel a world point projects to, if it is in front of the camera.
    pub fn project(&self, camera: &OrbitCamera, world: Vec3) -> Option<glam::Vec2> {
        let clip = camera.view_proj(self.aspect()) * world.extend(1.0);
        if clip.w <= 1e-4 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some(glam::Vec2::new(
            self.x + (ndc.x + 1.0) * 0.5 * self.width,
            self.y + (1.0 - ndc.y) * 0.5 * self.height,
        ))
    }
}

/// The two viewports of a split view filling `area` side by side.
pub fn split(area: Viewport) -> [Viewport; 2] {
    let half = (area.width * 0.5).floor();
    [
        Viewport {
            width: half,
            ..area
        },
        Viewport {
            x: area.x + half,
            width: area.width - half,
            ..area
        },
    ]
}

/// What to draw besides the bodies (the Doom 3 seed's `af_show*` set).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShowOptions {
    /// Particles as small spheres (particle method).
    pub particles: bool,
    /// Sticks as lines (particle method).
    pub sticks: bool,
    /// Contact points and normals.
    pub contacts: bool,
    /// Joint limits (cones and arcs) and joint gaps.
    pub limits: bool,
    /// Body names (drawn by the overlay, not here).
    pub names: bool,
    /// The bodies' collision shapes.
    pub bodies: bool,
    /// The skinned mesh, when the figure has one.
    pub mesh: bool,
}

impl Default for ShowOptions {
    fn default() -> Self {
        ShowOptions {
            particles: true,
            sticks: true,
            contacts: false,
            limits: false,
            names: false,
            bodies: true,
            mesh: true,
        }
    }
}

/// One half of the split view.
#[derive(Clone, Copy, Debug)]
pub struct SideView<'a> {
    /// Which method, for the colours.
    pub kind: MethodKind,
    /// What it shows now.
    pub snapshot: &'a RenderSnapshot,
    /// Where on the target.
    pub viewport: Viewport,
}

/// Everything one frame draws.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// The shared camera.
    pub camera: &'a OrbitCamera,
    /// The ground plane, if the scene has one.
    pub ground: Option<Ground>,
    /// The halves (at most two).
    pub sides: &'a [SideView<'a>],
    /// Overlays.
    pub show: ShowOptions,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CameraUniform {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
    ground: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Instance {
    model: [[f32; 4]; 4],
    params: [f32; 4],
    color: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LineVertex {
    position: [f32; 3],
    color: [f32; 4],
}

/// Which unit mesh an instance uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum MeshKey {
    Cube,
    Capsule,
    Sphere,
    Cylinder,
    Cone,
    /// A convex hull, keyed by the address of its shared point list.
    Hull(usize),
}

struct GpuMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

impl GpuMesh {
    fn new(device: &wgpu::Device, data: &MeshData, label: &str) -> GpuMesh {
        GpuMesh {
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(&data.vertices),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(&data.indices),
                usage: wgpu::BufferUsages::INDEX,
            }),
            count: data.indices.len() as u32,
        }
    }
}

/// A vertex buffer that grows as needed and is rewritten each frame.
struct GrowBuffer {
    buffer: wgpu::Buffer,
    label: &'static str,
}

impl GrowBuffer {
    fn new(device: &wgpu::Device, label: &'static str) -> GrowBuffer {
        GrowBuffer {
            buffer: Self::create(device, label, 4096),
            label,
        }
    }

    fn create(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, bytes: &[u8]) {
        if bytes.len() as u64 > self.buffer.size() {
            let size = (bytes.len() as u64).next_power_of_two();
            self.buffer = Self::create(device, self.label, size);
        }
        if !bytes.is_empty() {
            queue.write_buffer(&self.buffer, 0, bytes);
        }
    }
}

/// Draw ranges of one half.
#[derive(Default)]
struct SideDraws {
    viewport: Option<Viewport>,
    bodies: Vec<(MeshKey, Range<u32>)>,
    particles: Range<u32>,
    lines: Range<u32>,
}

/// The renderer's GPU state. Build once per device and target format.
pub struct Renderer {
    samples: u32,
    mesh_pipeline: wgpu::RenderPipeline,
    overlay_pipeline: wgpu::RenderPipeline,
    shadow_pipeline: wgpu::RenderPipeline,
    ground_pipeline: wgpu::RenderPipeline,
    line_pipeline: wgpu::RenderPipeline,
    cameras: Vec<(wgpu::Buffer, wgpu::BindGroup)>,
    meshes: HashMap<MeshKey, GpuMesh>,
    hulls: HashMap<usize, Arc<[Vec3]>>,
    instances: GrowBuffer,
    lines: GrowBuffer,
    ground: GrowBuffer,
    has_ground: bool,
    draws: Vec<SideDraws>,
    targets: Option<(u32, u32, Option<wgpu::TextureView>, wgpu::TextureView)>,
    format: wgpu::TextureFormat,
    skin: skin::SkinRenderer,
    show_bodies: bool,
    show_mesh: bool,
}

impl Renderer {
    /// Builds pipelines and unit meshes for targets of `format`, `samples` MSAA samples.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat, samples: u32) -> Renderer {
        let camera_layout = pipeline::uniform_layout(device, "camera");
        let target = pipeline::Target { format, samples };
        let pipelines = ScenePipelines::new(device, &camera_layout, target);
        Renderer {
            samples,
            mesh_pipeline: pipelines.mesh,
            overlay_pipeline: pipelines.overlay,
            shadow_pipeline: pipelines.shadow,
            ground_pipeline: pipelines.ground,
            line_pipeline: pipelines.line,
            cameras: camera_buffers(device, &camera_layout),
            meshes: unit_meshes(device),
            hulls: HashMap::new(),
            instances: GrowBuffer::new(device, "instances"),
            lines: GrowBuffer::new(device, "lines"),
            ground: GrowBuffer::new(device, "ground"),
            has_ground: false,
            draws: Vec::new(),
            targets: None,
            format,
            skin: skin::SkinRenderer::new(device, target, &camera_layout),
            show_bodies: true,
            show_mesh: true,
        }
    }

    /// Sets the skinned mesh to draw (uploaded once per model) and each side's joint
    /// poses; `None` draws none.
    pub fn set_skin(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        model: Option<&Arc<skin::SkinModel>>,
        poses: [&[ragdoll_sim::scene::Pose]; 2],
    ) {
        let tint = |kind| palette::body(kind, ragdoll_sim::snapshot::BodyRole::Dynamic, 0);
        let colors = [tint(MethodKind::Particle), tint(MethodKind::Multibody)];
        self.skin.update(device, queue, model, poses, colors);
    }

    /// MSAA sample count of the 3D pass.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Draws `frame` into `target` (a `width × height` view of the renderer's format),
    /// clearing it first. The caller submits `encoder`.
    pub fn render(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        size: (u32, u32),
        frame: &Frame,
    ) {
        self.prepare(device, queue, frame, size);
        let (msaa, depth) = self.attachments(device, size);
        let sky = palette::linear(palette::SKY);
        let (view, resolve) = match msaa {
            Some(m) => (m, Some(target)),
            None => (target, None),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: sky[0] as f64,
                        g: sky[1] as f64,
                        b: sky[2] as f64,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Discard,
                }),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.draw(&mut pass, size);
    }

    /// Reuses or (re)creates the MSAA colour and depth targets for `size`.
    fn attachments(
        &mut self,
        device: &wgpu::Device,
        size: (u32, u32),
    ) -> (Option<&wgpu::TextureView>, &wgpu::TextureView) {
        let stale = !matches!(&self.targets, Some((w, h, _, _)) if (*w, *h) == size);
        if stale {
            let texture = |format, label| {
                device
                    .create_texture(&wgpu::TextureDescriptor {
                        label: Some(label),
                        size: wgpu::Extent3d {
                            width: size.0,
                            height: size.1,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: self.samples,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                        view_formats: &[],
                    })
                    .create_view(&Default::default())
            };
            let msaa = (self.samples > 1).then(|| texture(self.format, "msaa"));
            let depth = texture(DEPTH_FORMAT, "depth");
            self.targets = Some((size.0, size.1, msaa, depth));
        }
        let (_, _, msaa, depth) = self.targets.as_ref().expect("targets were just made");
        (msaa.as_ref(), depth)
    }

    /// Fills the instance, line, ground and camera buffers for `frame`.
    fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &Frame,
        size: (u32, u32),
    ) {
        let mut instances: Vec<Instance> = Vec::new();
        let mut lines: Vec<LineVertex> = Vec::new();
        self.draws.clear();
        self.show_mesh = frame.show.mesh;
        // Without a mesh to show, the bodies are shown whatever the toggle says.
        self.show_bodies = frame.show.bodies || !(self.show_mesh && self.skin.has_model());
        let ground = frame.ground;
        let light = LIGHT_DIR.normalize();
        let (normal, offset) = match ground {
            Some(g) => (g.normal(), g.normal().dot(Vec3::new(0.0, g.height, 0.0))),
            // No ground: a plane far below keeps the shadow shader's division finite.
            None => (Vec3::Y, -1.0e4),
        };
        for (i, side) in frame.sides.iter().take(2).enumerate() {
            let vp = clip_viewport(side.viewport, size);
            let mut draws = SideDraws {
                viewport: vp,
                ..Default::default()
            };
            if let Some(vp) = vp {
                let uniform = CameraUniform {
                    view_proj: frame.camera.view_proj(vp.aspect()).to_cols_array_2d(),
                    eye: frame.camera.eye().extend(1.0).to_array(),
                    light: light.extend(0.0).to_array(),
                    ground: normal.extend(offset).to_array(),
                };
                queue.write_buffer(&self.cameras[i].0, 0, bytemuck::bytes_of(&uniform));
                self.side_instances(device, side, frame.show, &mut instances, &mut draws);
                let start = lines.len() as u32;
                side_lines(side, frame.show, &mut lines);
                draws.lines = start..lines.len() as u32;
            }
            self.draws.push(draws);
        }
        self.instances
            .write(device, queue, bytemuck::cast_slice(&instances));
        self.lines
            .write(device, queue, bytemuck::cast_slice(&lines));
        self.has_ground = ground.is_some();
        if let Some(g) = ground {
            let quad = ground_quad(&g, frame.camera.target);
            self.ground
                .write(device, queue, bytemuck::cast_slice(&quad));
        }
    }

    /// Appends `side`'s body and particle instances, sorted by mesh, and records the ranges.
    fn side_instances(
        &mut self,
        device: &wgpu::Device,
        side: &SideView,
        show: ShowOptions,
        out: &mut Vec<Instance>,
        draws: &mut SideDraws,
    ) {
        let snap = side.snapshot;
        let mut keyed: Vec<(MeshKey, Instance)> = Vec::with_capacity(snap.bodies.len());
        for (index, body) in snap.bodies.iter().enumerate() {
            let (key, params) = match &body.shape {
                Shape::Box { half_extents } => (MeshKey::Cube, half_extents.extend(0.0)),
                Shape::Capsule {
                    half_height,
                    radius,
                } => (MeshKey::Capsule, Vec3::splat(*radius).extend(*half_height)),
                Shape::Cylinder {
                    half_height,
                    radius,
                    ..
                } => (
                    MeshKey::Cylinder,
                    Vec3::new(*radius, *half_height, *radius).extend(0.0),
                ),
                Shape::Cone {
                    half_height,
                    radius,
                    ..
                } => (
                    MeshKey::Cone,
                    Vec3::new(*radius, *half_height, *radius).extend(0.0),
                ),
                Shape::ConvexHull { points } => {
                    let key = Arc::as_ptr(points) as *const Vec3 as usize;
                    if let std::collections::hash_map::Entry::Vacant(e) =
                        self.meshes.entry(MeshKey::Hull(key))
                    {
                        e.insert(GpuMesh::new(device, &mesh::convex_hull(points), "hull"));
                        // Keep the points alive so the address cannot be reused by another hull.
                        self.hulls.insert(key, points.clone());
                    }
                    (MeshKey::Hull(key), Vec3::ONE.extend(0.0))
                }
            };
            keyed.push((
                key,
                Instance {
                    model: Mat4::from_rotation_translation(body.pose.rotation, body.pose.position)
                        .to_cols_array_2d(),
                    params: params.to_array(),
                    color: palette::body(side.kind, body.role, index),
                },
            ));
        }
        keyed.sort_by_key(|(k, _)| *k);
        for (key, inst) in keyed {
            let at = out.len() as u32;
            match draws.bodies.last_mut() {
                Some((k, range)) if *k == key => range.end = at + 1,
                _ => draws.bodies.push((key, at..at + 1)),
            }
            out.push(inst);
        }
        let start = out.len() as u32;
        if show.particles {
            let r = particle_radius(snap);
            for p in &snap.particles {
                out.push(Instance {
                    model: Mat4::from_rotation_translation(Quat::IDENTITY, p.position)
                        .to_cols_array_2d(),
                    params: [r, r, r, 0.0],
                    color: palette::particle(p.role),
                });
            }
        }
        draws.particles = start..out.len() as u32;
    }

    fn draw(&self, pass: &mut wgpu::RenderPass<'_>, size: (u32, u32)) {
        pass.set_vertex_buffer(1, self.instances.buffer.slice(..));
        for (i, side) in self.draws.iter().enumerate() {
            let Some(vp) = side.viewport else { continue };
            pass.set_viewport(vp.x, vp.y, vp.width, vp.height, 0.0, 1.0);
            pass.set_scissor_rect(vp.x as u32, vp.y as u32, vp.width as u32, vp.height as u32);
            pass.set_bind_group(0, &self.cameras[i].1, &[]);
            if self.has_ground {
                pass.set_pipeline(&self.ground_pipeline);
                pass.set_vertex_buffer(0, self.ground.buffer.slice(..));
                pass.draw(0..6, 0..1);
                pass.set_pipeline(&self.shadow_pipeline);
                pass.set_stencil_reference(0);
                pass.set_vertex_buffer(1, self.instances.buffer.slice(..));
                self.draw_meshes(pass, &side.bodies);
            }
            if self.show_bodies {
                pass.set_pipeline(&self.mesh_pipeline);
                pass.set_vertex_buffer(1, self.instances.buffer.slice(..));
                self.draw_meshes(pass, &side.bodies);
            }
            if self.show_mesh {
                self.skin.draw(pass, i);
            }
            if !side.lines.is_empty() {
                pass.set_pipeline(&self.line_pipeline);
                pass.set_vertex_buffer(0, self.lines.buffer.slice(..));
                pass.draw(side.lines.clone(), 0..1);
            }
            if !side.particles.is_empty() {
                pass.set_pipeline(&self.overlay_pipeline);
                pass.set_vertex_buffer(1, self.instances.buffer.slice(..));
                self.draw_meshes(pass, &[(MeshKey::Sphere, side.particles.clone())]);
            }
        }
        // GL resolves MSAA with a blit the scissor test still clips: open it to the whole
        // target, or only the last half would be resolved.
        pass.set_scissor_rect(0, 0, size.0, size.1);
    }

    fn draw_meshes(&self, pass: &mut wgpu::RenderPass<'_>, draws: &[(MeshKey, Range<u32>)]) {
        for (key, range) in draws {
            let Some(mesh) = self.meshes.get(key) else {
                continue;
            };
            if mesh.count == 0 {
                continue;
            }
            pass.set_vertex_buffer(0, mesh.vertices.slice(..));
            pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.count, 0, range.clone());
        }
    }
}

/// The part of `vp` inside a `size` target, in whole pixels; `None` if empty.
/// One camera uniform buffer and its bind group per side.
fn camera_buffers(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
) -> Vec<(wgpu::Buffer, wgpu::BindGroup)> {
    (0..2)
        .map(|_| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("camera"),
                size: std::mem::size_of::<CameraUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("camera"),
                layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            });
            (buffer, group)
        })
        .collect()
}

/// The unit meshes instances of every shape but hulls are drawn with.
fn unit_meshes(device: &wgpu::Device) -> HashMap<MeshKey, GpuMesh> {
    HashMap::from([
        (
            MeshKey::Cube,
            GpuMesh::new(device, &mesh::unit_cube(), "cube"),
        ),
        (
            MeshKey::Capsule,
            GpuMesh::new(device, &mesh::unit_capsule(24, 16), "capsule"),
        ),
        (
            MeshKey::Sphere,
            GpuMesh::new(device, &mesh::unit_sphere(12, 8), "sphere"),
        ),
        (
            MeshKey::Cylinder,
            GpuMesh::new(device, &mesh::unit_round(24, 1.0), "cylinder"),
        ),
        (
            MeshKey::Cone,
            GpuMesh::new(device, &mesh::unit_round(24, 0.0), "cone"),
        ),
    ])
}

/// The pipelines of `shaders/scene.wgsl`, all with the camera as their one bind group.
struct ScenePipelines {
    /// Instanced shapes, depth-tested.
    mesh: wgpu::RenderPipeline,
    /// Particles and sticks sit inside the bodies they drive; they are drawn over them
    /// (an x-ray, like Doom 3's af_show* overlays) without touching the depth buffer.
    overlay: wgpu::RenderPipeline,
    /// Shapes flattened onto the ground; each shadow pixel is darkened once: the
    /// stencil passes only where it is still 0.
    shadow: wgpu::RenderPipeline,
    ground: wgpu::RenderPipeline,
    /// Joint axes, limits and the grab, over everything.
    line: wgpu::RenderPipeline,
}

impl ScenePipelines {
    fn new(
        device: &wgpu::Device,
        camera_layout: &wgpu::BindGroupLayout,
        target: pipeline::Target,
    ) -> ScenePipelines {
        use pipeline::{Stage, depth, render_pipeline};
        use wgpu::CompareFunction as C;
        use wgpu::PrimitiveTopology as T;
        let shader = device.create_shader_module(wgpu::include_wgsl!("../../shaders/scene.wgsl"));
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(camera_layout)],
            immediate_size: 0,
        });
        let mesh_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32];
        let inst_attrs = wgpu::vertex_attr_array![
            3 => Float32x4, 4 => Float32x4, 5 => Float32x4, 6 => Float32x4,
            7 => Float32x4, 8 => Float32x4
        ];
        let mesh_buffers = [
            Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<MeshVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &mesh_attrs,
            }),
            Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Instance>() as u64,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &inst_attrs,
            }),
        ];
        let ground_attrs = wgpu::vertex_attr_array![0 => Float32x3];
        let ground_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &ground_attrs,
        })];
        let line_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4];
        let line_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<LineVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &line_attrs,
        })];
        let build = |stage: Stage| render_pipeline(device, &layout, target, stage);
        let stencil_face = wgpu::StencilFaceState {
            compare: C::Equal,
            fail_op: wgpu::StencilOperation::Keep,
            depth_fail_op: wgpu::StencilOperation::Keep,
            pass_op: wgpu::StencilOperation::IncrementClamp,
        };
        ScenePipelines {
            mesh: build(Stage {
                label: "mesh",
                shader: &shader,
                vs: "vs_mesh",
                fs: "fs_mesh",
                buffers: &mesh_buffers,
                topology: T::TriangleList,
                cull: true,
                depth_stencil: depth(true, C::Less),
                blend: None,
            }),
            overlay: build(Stage {
                label: "overlay",
                shader: &shader,
                vs: "vs_mesh",
                fs: "fs_mesh",
                buffers: &mesh_buffers,
                topology: T::TriangleList,
                cull: true,
                depth_stencil: depth(false, C::Always),
                blend: None,
            }),
            line: build(Stage {
                label: "lines",
                shader: &shader,
                vs: "vs_line",
                fs: "fs_line",
                buffers: &line_buffers,
                topology: T::LineList,
                cull: false,
                depth_stencil: depth(false, C::Always),
                blend: None,
            }),
            ground: build(Stage {
                label: "ground",
                shader: &shader,
                vs: "vs_ground",
                fs: "fs_ground",
                buffers: &ground_buffers,
                topology: T::TriangleList,
                cull: false,
                depth_stencil: depth(true, C::Less),
                blend: None,
            }),
            shadow: build(Stage {
                label: "shadow",
                shader: &shader,
                vs: "vs_shadow",
                fs: "fs_shadow",
                buffers: &mesh_buffers,
                topology: T::TriangleList,
                cull: false,
                depth_stencil: wgpu::DepthStencilState {
                    stencil: wgpu::StencilState {
                        front: stencil_face,
                        back: stencil_face,
                        read_mask: 0xff,
                        write_mask: 0xff,
                    },
                    ..depth(false, C::LessEqual)
                },
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
            }),
        }
    }
}

fn clip_viewport(vp: Viewport, size: (u32, u32)) -> Option<Viewport> {
    let x0 = vp.x.max(0.0).floor();
    let y0 = vp.y.max(0.0).floor();
    let x1 = (vp.x + vp.width).min(size.0 as f32).floor();
    let y1 = (vp.y + vp.height).min(size.1 as f32).floor();
    (x1 - x0 >= 1.0 && y1 - y0 >= 1.0).then_some(Viewport {
        x: x0,
        y: y0,
        width: x1 - x0,
        height: y1 - y0,
    })
}

/// A typical body size of a snapshot (m): the mean of the bodies' smallest half extents.
fn body_scale(snap: &RenderSnapshot) -> f32 {
    if snap.bodies.is_empty() {
        return 0.1;
    }
    let sum: f32 = snap
        .bodies
        .iter()
        .map(|b| b.shape.local_half_extents().min_element())
        .sum();
    sum / snap.bodies.len() as f32
}

/// Particles are drawn at a quarter of a typical body's half thickness, within 5–40 mm.
fn particle_radius(snap: &RenderSnapshot) -> f32 {
    (body_scale(snap) * 0.25).clamp(0.005, 0.04)
}

/// Sticks, contacts and limits of one side as line segments.
fn side_lines(side: &SideView, show: ShowOptions, out: &mut Vec<LineVertex>) {
    let snap = side.snapshot;
    let mut seg = |a: Vec3, b: Vec3, color: [f32; 4]| {
        out.push(LineVertex {
            position: a.to_array(),
            color,
        });
        out.push(LineVertex {
            position: b.to_array(),
            color,
        });
    };
    if show.sticks {
        for s in &snap.sticks {
            seg(s.a, s.b, palette::stick(s.role));
        }
    }
    let scale = body_scale(snap).max(0.02);
    if show.contacts {
        let c = palette::linear(palette::CONTACT);
        for contact in &snap.contacts {
            let p = contact.point;
            // The normal's axis, drawn on its upper side so it is not buried in the ground
            // (a normal from a body into the ground points down).
            let n = if contact.normal.y < 0.0 {
                -contact.normal
            } else {
                contact.normal
            };
            seg(p, p + n * scale * 2.0, c);
            let s = scale * 0.5;
            seg(p - Vec3::X * s, p + Vec3::X * s, c);
            seg(p - Vec3::Z * s, p + Vec3::Z * s, c);
        }
    }
    if show.limits {
        let c = palette::linear(palette::LIMIT);
        let len = scale * 6.0;
        for joint in &snap.joints {
            seg(
                joint.anchor,
                joint.anchor2,
                palette::linear([1.0, 0.2, 0.2]),
            );
            match joint.limit {
                LimitShape::None => {}
                LimitShape::Cone { axis, half_angle } => {
                    let axis = axis.normalize_or_zero();
                    let (u, v) = axis.any_orthonormal_pair();
                    let ring = |t: f32| {
                        joint.anchor
                            + len
                                * (axis * half_angle.cos()
                                    + half_angle.sin() * (u * t.cos() + v * t.sin()))
                    };
                    const N: usize = 24;
                    for k in 0..N {
                        let t0 = k as f32 / N as f32 * std::f32::consts::TAU;
                        let t1 = (k + 1) as f32 / N as f32 * std::f32::consts::TAU;
                        seg(ring(t0), ring(t1), c);
                        if k % 6 == 0 {
                            seg(joint.anchor, ring(t0), c);
                        }
                    }
                }
                LimitShape::Arc {
                    axis,
                    reference,
                    min,
                    max,
                } => {
                    let at = |a: f32| {
                        joint.anchor
                            + Quat::from_axis_angle(axis.normalize_or_zero(), a) * reference * len
                    };
                    const N: usize = 16;
                    for k in 0..N {
                        let a0 = min + (max - min) * k as f32 / N as f32;
                        let a1 = min + (max - min) * (k + 1) as f32 / N as f32;
                        seg(at(a0), at(a1), c);
                    }
                    seg(joint.anchor, at(min), c);
                    seg(joint.anchor, at(max), c);
                }
            }
        }
    }
}

/// A square of the ground plane, 200 m across, centred below the camera's target.
fn ground_quad(ground: &Ground, centre: Vec3) -> [[f32; 3]; 6] {
    let n = ground.normal();
    let tangent = Vec3::new(n.y, -n.x, 0.0).normalize();
    let origin = Vec3::new(0.0, ground.height, 0.0);
    let c = centre - n * n.dot(centre - origin);
    let (a, b) = (tangent * 100.0, Vec3::Z * 100.0);
    let p = [c - a - b, c + a - b, c + a + b, c - a + b];
    [p[0], p[2], p[1], p[0], p[3], p[2]].map(|v| v.to_array())
}
