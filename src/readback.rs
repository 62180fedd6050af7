//! Reading a rendered texture back into an [`Image`]: the window's screenshots and
//! recordings (P, Shift+P). The surface must have been configured with `COPY_SRC`.

use crate::AppError;
use crate::capture::Image;

/// Copies `texture` (8-bit RGBA or BGRA) into an RGBA image, waiting for the GPU.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Image, AppError> {
    use wgpu::TextureFormat as F;
    let bgra = match texture.format() {
        F::Rgba8Unorm | F::Rgba8UnormSrgb => false,
        F::Bgra8Unorm | F::Bgra8UnormSrgb => true,
        other => {
            return Err(AppError::Gpu(format!(
                "cannot save a frame in the window's format {other:?}; use `ragdoll-lab capture`"
            )));
        }
    };
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return Err(AppError::Gpu(
            "this window's surface cannot be read back; use `ragdoll-lab capture`".into(),
        ));
    }
    let (width, height) = (texture.width(), texture.height());
    let padded_row = (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("window readback"),
        size: (padded_row * height) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("window readback"),
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| drop(tx.send(r)));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| AppError::Gpu(format!("waiting for the frame: {e}")))?;
    rx.recv()
        .map_err(|e| AppError::Gpu(format!("reading the frame back: {e}")))?
        .map_err(|e| AppError::Gpu(format!("reading the frame back: {e}")))?;
    let mut rgba = Vec::with_capacity((width * height * 4) as usize);
    {
        let data = buffer
            .get_mapped_range(..)
            .map_err(|e| AppError::Gpu(format!("reading the frame back: {e}")))?;
        for row in data.chunks(padded_row as usize) {
            rgba.extend_from_slice(&row[..(width * 4) as usize]);
        }
    }
    if bgra {
        for px in rgba.chunks_exact_mut(4) {
            px.swap(0, 2);
        }
    }
    // The window's alpha is not an image's: write the pixels opaque.
    for px in rgba.chunks_exact_mut(4) {
        px[3] = 255;
    }
    Ok(Image {
        width,
        height,
        rgba,
    })
}
