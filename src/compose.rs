//! One frame, window or offscreen: run the egui pass (it decides the 3D area), draw the
//! two halves with the scene renderer, then the egui layer on top.

use crate::app_state::{Action, AppState};
use crate::render::{Frame, Renderer, SideView, Viewport};
use crate::session::Session;
use crate::ui::{self, UiModel};
use ragdoll_sim::MethodKind;

/// What one frame's UI pass produced besides pixels.
pub struct FrameOutput {
    /// Actions the user took.
    pub actions: Vec<Action>,
    /// egui's platform output (cursor, clipboard).
    pub platform: egui::PlatformOutput,
    /// egui wants another frame within this long (an animation, a hover); `Duration::MAX`
    /// when nothing in the UI changes by itself.
    pub repaint_after: std::time::Duration,
    /// Where the UI put its parts (points), for layout tests.
    pub layout: ui::UiLayout,
}

/// The scene renderer and the egui context and renderer for one target format.
pub struct Compositor {
    /// The egui context (kept across frames: panel sizes, plot state).
    pub ctx: egui::Context,
    /// The two halves of the last frame (physical pixels), for picking and panning.
    pub viewports: [Viewport; 2],
    egui: egui_wgpu::Renderer,
    scene: Renderer,
}

impl Compositor {
    /// Builds both renderers: the 3D pass draws into views of `format` with `samples` MSAA,
    /// egui into views of `ui_format` (egui blends in gamma space, so it wants the
    /// non-sRGB view of an sRGB target where the platform offers one).
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        ui_format: wgpu::TextureFormat,
        samples: u32,
    ) -> Compositor {
        Compositor {
            ctx: egui::Context::default(),
            egui: egui_wgpu::Renderer::new(
                device,
                ui_format,
                egui_wgpu::RendererOptions {
                    msaa_samples: 1,
                    depth_stencil_format: None,
                    dithering: false,
                    predictable_texture_filtering: false,
                },
            ),
            scene: Renderer::new(device, format, samples),
            viewports: [Viewport {
                x: 0.0,
                y: 0.0,
                width: 1.0,
                height: 1.0,
            }; 2],
        }
    }

    /// Runs the UI on `raw` and draws the frame into `target` (`size` physical pixels), the
    /// egui layer through `ui_target` (a view of the same texture in the UI format).
    /// Returns the actions the UI produced, egui's platform output and the layout.
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        target: &wgpu::TextureView,
        ui_target: &wgpu::TextureView,
        size: (u32, u32),
        pixels_per_point: f32,
        raw: egui::RawInput,
        state: &AppState,
        session: &Session,
    ) -> FrameOutput {
        let mut actions = Vec::new();
        let mut layout = ui::UiLayout::default();
        let full = self.ctx.run_ui(raw, |ui| {
            let mut model = UiModel {
                state,
                session,
                pixels_per_point,
                actions: &mut actions,
                layout: &mut layout,
            };
            ui::build(ui, &mut model);
        });
        let area = layout.view;
        let viewports = ui::viewports(area, pixels_per_point, state.layout);
        self.viewports = viewports;
        let all = [
            SideView {
                kind: MethodKind::Particle,
                snapshot: &session.snapshots[0],
                viewport: viewports[0],
            },
            SideView {
                kind: MethodKind::Multibody,
                snapshot: &session.snapshots[1],
                viewport: viewports[1],
            },
        ];
        // A side the layout hides has no pixels and is not drawn.
        let sides: Vec<SideView> = all
            .into_iter()
            .filter(|s| s.viewport.width >= 1.0)
            .collect();
        let frame = Frame {
            camera: &state.camera,
            ground: session.settings().ground,
            sides: &sides,
            // A selected body shows its own joints' limits (the session kept only those)
            // even with the limits overlay off.
            show: crate::render::ShowOptions {
                limits: state.show.limits || state.selected.is_some(),
                ..state.show
            },
        };

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
        self.scene.set_skin(
            device,
            queue,
            session.loaded.skin.as_ref(),
            [&session.joint_poses[0], &session.joint_poses[1]],
        );
        self.scene
            .render(device, queue, &mut encoder, target, size, &frame);

        for (id, deltas) in &full.textures_delta.set {
            for delta in deltas {
                self.egui.update_texture(device, queue, *id, delta);
            }
        }
        let primitives = self.ctx.tessellate(full.shapes, full.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.0, size.1],
            pixels_per_point: full.pixels_per_point,
        };
        let extra = self
            .egui
            .update_buffers(device, queue, &mut encoder, &primitives, &screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: ui_target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.egui.render(&mut pass, &primitives, &screen);
        }
        queue.submit(extra.into_iter().chain([encoder.finish()]));
        for id in &full.textures_delta.free {
            self.egui.free_texture(id);
        }
        let repaint_after = full
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map_or(std::time::Duration::MAX, |v| v.repaint_delay);
        FrameOutput {
            actions,
            platform: full.platform_output,
            repaint_after,
            layout,
        }
    }
}
