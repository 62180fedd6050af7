//! The pipeline set-up every draw of the renderer shares, written once: a bind group
//! layout of one uniform buffer, the depth–stencil state, and a render pipeline from a
//! shader's vertex and fragment entry points into one colour target of the frame's
//! format and sample count (the scene's meshes, lines, ground and shadows in
//! `Renderer::new`, the skinned mesh in `skin`).

use super::DEPTH_FORMAT;

/// A bind group layout of one uniform buffer at binding 0, read by the vertex and
/// fragment stages (the camera, a skin's joints and tint).
pub(crate) fn uniform_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    })
}

/// Depth testing with `compare`, writing depth if `write`; no stencil.
pub(crate) fn depth(write: bool, compare: wgpu::CompareFunction) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    }
}

/// What the frame's colour target is: its format and MSAA sample count.
#[derive(Clone, Copy)]
pub(crate) struct Target {
    pub format: wgpu::TextureFormat,
    pub samples: u32,
}

/// One pipeline: entry points `vs` and `fs` of `shader` over `buffers`.
pub(crate) struct Stage<'a> {
    pub label: &'a str,
    pub shader: &'a wgpu::ShaderModule,
    pub vs: &'a str,
    pub fs: &'a str,
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub topology: wgpu::PrimitiveTopology,
    /// Cull back faces.
    pub cull: bool,
    pub depth_stencil: wgpu::DepthStencilState,
    pub blend: Option<wgpu::BlendState>,
}

/// The render pipeline of `stage` with bind groups `layout`, drawing into `target`.
pub(crate) fn render_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    target: Target,
    stage: Stage,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(stage.label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: stage.shader,
            entry_point: Some(stage.vs),
            compilation_options: Default::default(),
            buffers: stage.buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: stage.topology,
            cull_mode: stage.cull.then_some(wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(stage.depth_stencil),
        multisample: wgpu::MultisampleState {
            count: target.samples,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module: stage.shader,
            entry_point: Some(stage.fs),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: target.format,
                blend: stage.blend,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}
