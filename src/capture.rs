//! `ragdoll-lab capture`: simulate offscreen and write PNGs through the same renderer as
//! the window, with no window and no winit. On a machine without a GPU this runs on the
//! software rasteriser (Mesa llvmpipe through wgpu's GL backend).

use crate::app_state::{AppState, SCENES};
use crate::cli::CaptureArgs;
use crate::compose::Compositor;
use crate::picking;
use crate::render::camera::OrbitCamera;
use crate::render::{Frame, Renderer, gpu};
use crate::session::Session;
use crate::ui::UiLayout;
use crate::{AppError, scenes};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The target format: 8-bit sRGB, so the PNG holds what a screen would show.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// The same bytes seen without sRGB encoding, for egui (it blends in gamma space).
const UI_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// An RGBA8 image, rows top to bottom.
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height · 4` bytes.
    pub rgba: Vec<u8>,
}

impl Image {
    /// The pixel at (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// Writes a PNG.
    pub fn write_png(&self, path: &Path) -> Result<(), AppError> {
        let io = |source: std::io::Error| AppError::Io {
            path: path.display().to_string(),
            source,
        };
        let file = File::create(path).map_err(io)?;
        let mut encoder = png::Encoder::new(BufWriter::new(file), self.width, self.height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::High);
        let png_err = |e: png::EncodingError| AppError::Other(format!("{}: {e}", path.display()));
        let mut writer = encoder.write_header().map_err(png_err)?;
        writer.write_image_data(&self.rgba).map_err(png_err)?;
        writer.finish().map_err(png_err)
    }
}

/// An offscreen render target with its readback buffer.
pub struct Offscreen {
    gpu: gpu::Gpu,
    width: u32,
    height: u32,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    ui_view: wgpu::TextureView,
    ui_format: wgpu::TextureFormat,
    readback: wgpu::Buffer,
    padded_row: u32,
    compositor: Option<Compositor>,
    scene_only: Option<Renderer>,
    errors: Arc<Mutex<Vec<String>>>,
    layout: Option<UiLayout>,
}

impl Offscreen {
    /// Opens the best adapter (see [`gpu::offscreen`]) and a `width × height` target.
    pub fn new(width: u32, height: u32) -> Result<Offscreen, AppError> {
        if width == 0 || height == 0 || width > 8192 || height > 8192 {
            return Err(AppError::Usage(format!(
                "image size {width}x{height} out of range (1..8192 each)"
            )));
        }
        let gpu = gpu::offscreen()?;
        // Validation errors become values: collected here and returned after each frame.
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        gpu.device
            .on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                if let Ok(mut v) = sink.lock() {
                    v.push(e.to_string());
                }
            }));
        // GL (llvmpipe) cannot view one texture in two formats; egui then draws through
        // the sRGB view (its colours a little lighter), as it says in a warning.
        let view_formats_ok = gpu
            .adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::VIEW_FORMATS);
        let ui_format = if view_formats_ok { UI_FORMAT } else { FORMAT };
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("capture"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: if view_formats_ok { &[UI_FORMAT] } else { &[] },
        });
        let view = texture.create_view(&Default::default());
        let ui_view = texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(ui_format),
            ..Default::default()
        });
        let padded_row = (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: (padded_row * height) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Ok(Offscreen {
            gpu,
            width,
            height,
            texture,
            view,
            ui_view,
            ui_format,
            readback,
            padded_row,
            compositor: None,
            scene_only: None,
            errors,
            layout: None,
        })
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The adapter's name ("llvmpipe (LLVM ...)" on the software path).
    pub fn adapter_name(&self) -> String {
        self.gpu.adapter.get_info().name
    }

    fn samples(&self) -> u32 {
        gpu::msaa_samples(&self.gpu.adapter, FORMAT)
    }

    fn raw_input(&self) -> egui::RawInput {
        egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(self.width as f32, self.height as f32),
            )),
            ..Default::default()
        }
    }

    /// Renders the full frame (both halves, labels, and the panel if `state.panel`).
    pub fn render(&mut self, state: &AppState, session: &Session) -> Result<Image, AppError> {
        let samples = self.samples();
        let compositor = self.compositor.get_or_insert_with(|| {
            Compositor::new(&self.gpu.device, FORMAT, self.ui_format, samples)
        });
        if compositor.ctx.cumulative_pass_nr() == 0 {
            // egui lays out auto-sized areas in a first, invisible pass; run it once so
            // the captured frame shows the settled layout.
            let _ = compositor.frame(
                &self.gpu.device,
                &self.gpu.queue,
                &self.view,
                &self.ui_view,
                (self.width, self.height),
                1.0,
                egui::RawInput {
                    screen_rect: Some(egui::Rect::from_min_size(
                        egui::Pos2::ZERO,
                        egui::vec2(self.width as f32, self.height as f32),
                    )),
                    ..Default::default()
                },
                state,
                session,
            );
        }
        let raw = self.raw_input();
        let compositor = self.compositor.as_mut().expect("made above");
        let out = compositor.frame(
            &self.gpu.device,
            &self.gpu.queue,
            &self.view,
            &self.ui_view,
            (self.width, self.height),
            1.0,
            raw,
            state,
            session,
        );
        self.layout = Some(out.layout);
        self.read()
    }

    /// Where the last [`Offscreen::render`] put the panel and the view's texts.
    pub fn last_layout(&self) -> Option<&UiLayout> {
        self.layout.as_ref()
    }

    /// Renders only the 3D halves of `frame`, no egui (for renderer tests).
    pub fn render_scene(&mut self, frame: &Frame) -> Result<Image, AppError> {
        let samples = self.samples();
        let renderer = self
            .scene_only
            .get_or_insert_with(|| Renderer::new(&self.gpu.device, FORMAT, samples));
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("scene"),
            });
        renderer.render(
            &self.gpu.device,
            &self.gpu.queue,
            &mut encoder,
            &self.view,
            (self.width, self.height),
            frame,
        );
        self.gpu.queue.submit([encoder.finish()]);
        self.read()
    }

    /// Copies the target to the readback buffer and waits for it.
    fn read(&mut self) -> Result<Image, AppError> {
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("read"),
        });
        encoder.copy_texture_to_buffer(
            self.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        self.readback
            .map_async(wgpu::MapMode::Read, .., move |r| drop(tx.send(r)));
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| AppError::Gpu(format!("waiting for the frame: {e}")))?;
        rx.recv()
            .map_err(|e| AppError::Gpu(format!("reading the frame back: {e}")))?
            .map_err(|e| AppError::Gpu(format!("reading the frame back: {e}")))?;
        let mut rgba = Vec::with_capacity((self.width * self.height * 4) as usize);
        {
            let data = self
                .readback
                .get_mapped_range(..)
                .map_err(|e| AppError::Gpu(format!("reading the frame back: {e}")))?;
            for row in data.chunks(self.padded_row as usize) {
                rgba.extend_from_slice(&row[..(self.width * 4) as usize]);
            }
        }
        self.readback.unmap();
        if let Ok(mut errors) = self.errors.lock()
            && !errors.is_empty()
        {
            return Err(AppError::Gpu(
                errors.drain(..).collect::<Vec<_>>().join("; "),
            ));
        }
        Ok(Image {
            width: self.width,
            height: self.height,
            rgba,
        })
    }
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), AppError> {
    let bad = || AppError::Usage(format!("--size {s}: expected WxH, e.g. 1280x720"));
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    Ok((
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    ))
}

/// Fails early, before any simulating, if `path` cannot be written.
fn check_writable(path: &Path) -> Result<(), AppError> {
    let existed = path.exists();
    File::options()
        .append(true)
        .create(true)
        .open(path)
        .map_err(|source| AppError::Io {
            path: path.display().to_string(),
            source,
        })?;
    if !existed {
        let _ = std::fs::remove_file(path);
    }
    Ok(())
}

/// Simulates and renders offscreen, writing PNGs.
pub fn run(args: CaptureArgs) -> Result<(), AppError> {
    let (width, height) = parse_size(&args.size)?;
    // Where the frames go: one file, or frame_NNNNN.png every K frames in a directory.
    let (every, out_dir): (u32, Option<PathBuf>) = match (&args.out, &args.out_dir) {
        (_, Some(dir)) => {
            std::fs::create_dir_all(dir).map_err(|source| AppError::Io {
                path: dir.display().to_string(),
                source,
            })?;
            check_writable(&dir.join(".ragdoll-lab-write-test"))?;
            (args.every.unwrap_or(1).max(1), Some(dir.clone()))
        }
        (Some(out), None) => {
            check_writable(out)?;
            (0, None)
        }
        (None, None) => return Err(AppError::Usage("give --out FILE or --out-dir DIR".into())),
    };

    // With --anim, the ragdoll takes over from its --at frame.
    let loaded = scenes::load(&args.scene)?.taken_over();
    let scene_index = args
        .scene
        .scene
        .as_deref()
        .and_then(|s| index_of_scene(s, &loaded.desc.name));
    let mut state = AppState::new(
        scene_index,
        loaded.desc.variant,
        OrbitCamera::from_desc(&loaded.desc.settings.camera),
    );
    state.panel = args.ui;
    state.particle_solver = args.particle_solver;
    let mut session = Session::new(loaded, args.particle_solver)?;
    state.camera = picking::scene_camera(
        state.camera,
        &session.snapshots,
        half_aspect(width, height, args.ui),
    );
    let mut target = Offscreen::new(width, height)?;
    log::info!("capturing on {}", target.adapter_name());

    for frame in 0..=args.frames {
        if let Some(dir) = &out_dir
            && frame % every == 0
        {
            session.refresh();
            let image = target.render(&state, &session)?;
            image.write_png(&dir.join(format!("frame_{frame:05}.png")))?;
        }
        if frame < args.frames {
            session.step();
        }
    }
    if let Some(out) = &args.out {
        session.refresh();
        target.render(&state, &session)?.write_png(out)?;
    }
    Ok(())
}

/// Width / height of one half of a `width × height` image, with or without the panel.
pub fn half_aspect(width: u32, height: u32, panel: bool) -> f32 {
    let w = width as f32;
    let view = if panel {
        w - crate::ui::panel_width(w)
    } else {
        w
    };
    (view * 0.5) / (height.max(1) as f32)
}

/// The built-in scene index of a `--scene` argument (number or name).
fn index_of_scene(arg: &str, name: &str) -> Option<usize> {
    if let Ok(n) = arg.parse::<usize>() {
        return (1..=SCENES.len()).contains(&n).then(|| n - 1);
    }
    SCENES.iter().position(|s| *s == arg || *s == name)
}
